/* fuzz_valid_range.c - the session log's valid_range event detail (palp_db_valid_range_parse),
 * which palp-review reads from a file anyone may have edited. The input is the detail; its
 * count is the number the detail itself states (or 1), so the fuzzer reaches the checks past
 * the format. An accepted detail obeys the invariants and comes back the same when rewritten. */
#include <inttypes.h>
#include <math.h>

#include "fuzz_util.h"
#include "palp_db.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = fuzz_cstr(data, size);
  int64_t count = 1;
  if (sscanf(text, "outside at %" SCNd64, &count) != 1) count = 1;
  palp_db_valid_range r;
  if (palp_db_valid_range_parse(text, count, &r) == 0) {
    if (r.steps < 1 || r.steps != count || r.depth_steps < 0 || r.skin_steps < 0 || r.limit_steps < 0 ||
        r.depth_steps > r.steps || r.skin_steps > r.steps || r.limit_steps > r.steps || !isfinite(r.deepest_m) ||
        r.deepest_m < 0 || r.deepest_m > 1.0 || r.gel_steps < 0 || r.gel_steps > r.steps ||
        (r.gel_steps == 0) != (r.gel_frames == 0) || r.gel_frames < r.gel_steps ||
        r.depth_steps + r.skin_steps + r.limit_steps + r.gel_steps < r.steps)
      abort();
    char again[256];
    palp_db_valid_range_format(&r, again, sizeof again);
    palp_db_valid_range b;
    if (palp_db_valid_range_parse(again, count, &b) != 0 || b.steps != r.steps || b.depth_steps != r.depth_steps ||
        b.skin_steps != r.skin_steps || b.limit_steps != r.limit_steps || b.gel_steps != r.gel_steps ||
        b.gel_frames != r.gel_frames || fabs(b.deepest_m - r.deepest_m) > 6e-6)
      abort(); /* rewritten to 0.01 mm: within half of it */
  }
  free(text);
  return 0;
}
