/* Runs the scripted session as its own process (for the SIGKILL test and by hand).
 * usage: sim_session DB UID SCENE SECONDS [--realtime] [--progress] [--tick-hz HZ] */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim.h"

int main(int argc, char **argv) {
  if (argc < 5) {
    fprintf(stderr, "usage: %s DB UID SCENE SECONDS [--realtime] [--progress] [--tick-hz HZ]\n", argv[0]);
    return 2;
  }
  sim_opts o = {.db = argv[1], .uid = argv[2], .scene_path = argv[3], .seconds = atof(argv[4]), .tick_hz = 1000};
  for (int i = 5; i < argc; i++) {
    if (!strcmp(argv[i], "--realtime")) o.realtime = 1;
    else if (!strcmp(argv[i], "--progress")) o.progress = 1;
    else if (!strcmp(argv[i], "--tick-hz") && i + 1 < argc) o.tick_hz = atof(argv[++i]);
    else {
      fprintf(stderr, "sim_session: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  if (!(o.seconds > 0) || !(o.tick_hz > 0)) {
    fprintf(stderr, "sim_session: SECONDS and --tick-hz must be positive\n");
    return 2;
  }
  sim_result r;
  int rc = sim_run(&o, &r);
  if (rc) return 1;
  printf("done frames %lld logged %lld refused %lld written %lld shed %lld failed %lld\n",
         (long long)r.frames_stepped, (long long)r.frames_logged, (long long)r.records_refused,
         (long long)r.st.written, (long long)r.st.shed, (long long)r.st.failed);
  sim_result_free(&r);
  return 0;
}
