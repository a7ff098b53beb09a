/* fuzz_server_config.c - palp_srv_config_parse (config/server.json) on arbitrary text. */
#include "config.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *json = fuzz_cstr(data, size);
  palp_srv_config cfg;
  char err[512];
  if (palp_srv_config_parse(json, "/nonexistent-base", &cfg, err, sizeof err) == 0) {
    /* What it accepts is within its documented ranges. */
    if (cfg.phantom_count < 1 || cfg.phantom_count > PALP_SRV_MAX_PHANTOMS || cfg.max_sessions < 1 ||
        !(cfg.tick_rate_hz >= 1 && cfg.tick_rate_hz <= 10000) || !(cfg.absurd_force >= cfg.max_force))
      abort();
  }
  free(json);
  return 0;
}
