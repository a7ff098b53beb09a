/* fuzz_stats_csv.c - palp-stats' CSV reader (palp_csv_parse); the first byte picks the delimiter. */
#include "csv.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static const char delims[] = {',', ';', '\t', '|'};
  const char delim = size ? delims[data[0] % 4] : ',';
  char *text = fuzz_cstr(size ? data + 1 : data, size ? size - 1 : 0);
  palp_csv csv;
  char err[512];
  if (palp_csv_parse(text, size ? size - 1 : 0, "fuzz.csv", delim, &csv, err, sizeof err) == 0) {
    for (size_t r = 0; r < csv.nrows; r++)
      for (int c = 0; c < csv.ncols; c++)
        if (!palp_csv_cell(&csv, r, c)) abort(); /* every cell of an accepted table exists */
    palp_csv_free(&csv);
  }
  free(text);
  return 0;
}
