/* fuzz_replay.c - the contact CSV of palp-client --input replay:FILE, read and then played
 * through at 1 kHz steps of its own time axis (every poll must return within bounds). */
#include "fuzz_util.h"
#include "input.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_file(data, size, ".csv");
  palp_cli_input in;
  char err[512];
  if (palp_cli_replay_input(path, &in, err, sizeof err) != 0) return 0;
  if (in.open) in.open(in.ctx, 0.04);
  palp_cli_cmd cmds[PALP_CLI_MAX_FINGERS];
  /* A bounded walk: at most 20,000 polls, up to the end of the file's time axis. */
  for (int k = 0; k < 20000; k++) {
    int n = in.poll(in.ctx, k * 1e-3 * (1 + k / 1000), cmds, PALP_CLI_MAX_FINGERS);
    if (n == PALP_CLI_INPUT_END || n < 0) break;
    if (n > PALP_CLI_MAX_FINGERS) abort();
    for (int i = 0; i < n; i++) {
      if (cmds[i].finger < 0 || cmds[i].finger >= PALP_CLI_MAX_FINGERS) abort();
      /* nothing the server refuses on every sample: a force row's distribution 1-4, a finger's radius */
      if (cmds[i].mode == 1 && (cmds[i].distribution < 1 || cmds[i].distribution > 4)) abort();
      if (cmds[i].mode == 2 && !(cmds[i].radius > 0)) abort();
    }
  }
  in.close(in.ctx);
  return 0;
}
