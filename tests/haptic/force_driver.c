/*
 * force_driver.c - a force-mode device driver for the station's tests: poll() and feedback() only, no
 * read_position, so palp-client drives it from its force-driven loop (run_trainee), as it does an older
 * driver built before the 1 kHz haptic thread. ARG is comma-separated key=value:
 *   log=FILE   every feedback() call as "T FINGER FX FY FZ" (T: CLOCK_REALTIME [s], as `date +%s.%N`),
 *              and at close "close FX FY FZ", the force the device was last given
 *   depth=MM   a fingertip (8 mm) pressed this deep at the pole from 0.3 s on (default 4)
 *   fail=S     poll() fails from S seconds on (PALP_EIO), error() saying why
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "input.h"

typedef struct drv {
  FILE *log;
  double R, depth, fail_at;
  palp_vec3 last;
  char err[128];
} drv;

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int d_open(void *ctx, double R) {
  ((drv *)ctx)->R = R;
  return 0;
}

static int d_poll(void *ctx, double t, palp_cli_cmd *cmd, int cap) {
  drv *d = ctx;
  if (d->fail_at > 0 && t >= d->fail_at) {
    snprintf(d->err, sizeof d->err, "test driver: the device stopped answering at %.1f s (its USB link was lost)",
             d->fail_at);
    return PALP_EIO;
  }
  if (cap < 1) return 0;
  const double r = 0.008;
  const int on = t >= 0.3;
  cmd[0] = (palp_cli_cmd){.finger = 0, .mode = on ? 2 : 0, .radius = r, .center = {0, 0, d->R + r - d->depth}};
  return 1;
}

static void d_feedback(void *ctx, int finger, palp_vec3 f) {
  drv *d = ctx;
  if (finger == 0) d->last = f;
  if (d->log) fprintf(d->log, "%.6f %d %.6g %.6g %.6g\n", now_s(), finger, f.x, f.y, f.z);
}

static const char *d_error(void *ctx) {
  drv *d = ctx;
  return d->err[0] ? d->err : NULL;
}

static void d_close(void *ctx) {
  drv *d = ctx;
  if (d->log) {
    fprintf(d->log, "close %.6g %.6g %.6g\n", d->last.x, d->last.y, d->last.z);
    fclose(d->log);
  }
  free(d);
}

int palp_cli_device_driver(const char *arg, palp_cli_input *out) {
  drv *d = calloc(1, sizeof *d);
  if (!d) return PALP_ENOMEM;
  d->depth = 0.004;
  char buf[1024];
  snprintf(buf, sizeof buf, "%s", arg ? arg : "");
  for (char *save = NULL, *kv = strtok_r(buf, ",", &save); kv; kv = strtok_r(NULL, ",", &save)) {
    if (!strncmp(kv, "log=", 4)) {
      d->log = fopen(kv + 4, "w");
      if (d->log) setvbuf(d->log, NULL, _IOLBF, 0);
    } else if (!strncmp(kv, "depth=", 6)) {
      d->depth = atof(kv + 6) * 1e-3;
    } else if (!strncmp(kv, "fail=", 5)) {
      d->fail_at = atof(kv + 5);
    }
  }
  *out = (palp_cli_input){.name = "test force driver", .ctx = d, .open = d_open, .poll = d_poll,
                          .feedback = d_feedback, .close = d_close, .error = d_error};
  return 0;
}
