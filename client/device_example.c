/*
 * device_example.c - a haptic device driver for palp-client, as a shared object.
 *
 * A template for a real device (Phantom Omni, Novint Falcon, a force sensor ...):
 * palp-client --input device:libpalp_device_example.so[:ARG] loads it and calls
 * palp_cli_device_driver(ARG, &ops) once. A driver implements the device
 * interface of client/input.h, position in and force out at 1 kHz:
 *   read_position(ctx, t, &x)  the fingertip centre [m] in the phantom's frame
 *                              (1: finger on, 0: lifted, PALP_CLI_INPUT_END, or a
 *                              negative PALP_E* code with error() saying why)
 *   write_force(ctx, f, flags) the force to render [N]; PALP_CLI_FORCE_LIMITED when
 *                              the station limited it to its safe force
 *   error(ctx)                 a clear message for the last error
 * Both run on palp-client's haptic thread every millisecond and must not block:
 * a real driver reads its encoders and commands its motors here. palp-client
 * renders the force from the server's local contact model, so the device gets
 * a new force every tick whatever the network does.
 *
 * This one emulates a spring-loaded probe: an 8 mm fingertip that dips 6 mm
 * into the pole and back at ARG Hz (default 0.5 Hz), and reports the force it
 * was told to render on stderr once a second. The older force-mode entry points
 * (poll/feedback) are kept so the driver also works where no haptic thread runs.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "input.h"

typedef struct probe {
  double R, freq, depth, radius;
  double last_report;
  palp_vec3 force; /* last force to render [N] */
  unsigned flags;
  double t;
  char err[128];
} probe;

static int p_open(void *ctx, double R) {
  probe *p = ctx;
  if (!(R > 0.005 && R < 1.0)) {
    snprintf(p->err, sizeof p->err, "example probe: phantom radius %g m is outside its reach", R);
    return PALP_EINVAL;
  }
  p->R = R;
  return 0;
}

/* depth(t) = D (1 - cos(2 pi f t)) / 2: from 0 to D and back, smoothly */
static double depth_at(const probe *p, double t) { return p->depth * 0.5 * (1 - cos(2 * 3.14159265358979 * p->freq * t)); }

static int p_read(void *ctx, double t, palp_vec3 *x) {
  probe *p = ctx;
  p->t = t;
  if (t - p->last_report >= 1.0) {
    fprintf(stderr, "device: t=%.1f s  rendering (%.2f, %.2f, %.2f) N%s%s\n", t, p->force.x, p->force.y, p->force.z,
            (p->flags & PALP_CLI_FORCE_LIMITED) ? " (limited)" : "",
            (p->flags & PALP_CLI_FORCE_OUT_OF_RANGE) ? " (outside the model's valid range)" : "");
    p->last_report = t;
  }
  const double d = depth_at(p, t);
  *x = (palp_vec3){0, 0, p->R + p->radius - d};
  return d > 1e-5 ? 1 : 0;
}

static void p_write(void *ctx, palp_vec3 f, unsigned flags) {
  probe *p = ctx;
  p->force = f; /* a real driver commands its motors here */
  p->flags = flags;
}

static const char *p_error(void *ctx) {
  probe *p = ctx;
  return p->err[0] ? p->err : NULL;
}

static int p_poll(void *ctx, double t, palp_cli_cmd *cmd, int cap) {
  probe *p = ctx;
  palp_vec3 x;
  const int on = p_read(ctx, t, &x);
  if (cap < 1) return 0;
  cmd[0] = (palp_cli_cmd){.finger = 0, .mode = on ? 2 : 0, .radius = p->radius, .center = x};
  return 1;
}

static void p_feedback(void *ctx, int finger, palp_vec3 force) {
  if (finger == 0) ((probe *)ctx)->force = force;
}

static void p_close(void *ctx) { free(ctx); }

int palp_cli_device_driver(const char *arg, palp_cli_input *out) {
  probe *p = calloc(1, sizeof *p);
  if (!p) return PALP_ENOMEM;
  p->freq = arg && *arg ? atof(arg) : 0.5;
  if (!(p->freq > 0 && p->freq < 100)) {
    free(p);
    return PALP_EINVAL;
  }
  p->depth = 0.006;
  p->radius = 0.008;
  *out = (palp_cli_input){.name = "example probe", .ctx = p, .open = p_open, .poll = p_poll,
                          .feedback = p_feedback, .close = p_close, .read_position = p_read,
                          .write_force = p_write, .error = p_error, .finger_radius = p->radius};
  return 0;
}
