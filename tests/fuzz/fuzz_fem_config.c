/* fuzz_fem_config.c - palp_fem_config_parse and _validate on arbitrary text. */
#include "fuzz_util.h"
#include "palp_fem.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *json = fuzz_cstr(data, size);
  palp_fem_config cfg = palp_fem_default_config();
  char err[512];
  if (palp_fem_config_parse(json, &cfg, err, sizeof err) == 0) palp_fem_config_validate(&cfg, err, sizeof err);
  free(json);
  return 0;
}
