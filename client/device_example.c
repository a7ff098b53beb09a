/*
 * device_example.c - a haptic device driver for palp-client, as a shared object.
 *
 * A template for a real device (Phantom Omni, Novint Falcon, a force sensor ...):
 * palp-client --input device:libpalp_device_example.so[:ARG] loads it, calls
 * palp_cli_device_driver(ARG, &ops) once, then poll() every tick and feedback()
 * with every force the server returns. This one emulates a spring-loaded probe:
 * a position-driven finger of 8 mm radius that dips into the pole and back at
 * ARG Hz (default 0.5 Hz, 6 mm deep), and reports the rendered force on stderr
 * once a second, where a real driver would command its motors.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "input.h"

typedef struct probe {
  double R, freq, depth, radius;
  double last_report;
  palp_vec3 force; /* last force to render [N] */
  double t;
} probe;

static int p_open(void *ctx, double R) {
  ((probe *)ctx)->R = R;
  return 0;
}

static int p_poll(void *ctx, double t, palp_cli_cmd *cmd, int cap) {
  probe *p = ctx;
  p->t = t;
  if (t - p->last_report >= 1.0) {
    fprintf(stderr, "device: t=%.1f s  rendering (%.2f, %.2f, %.2f) N\n", t, p->force.x, p->force.y, p->force.z);
    p->last_report = t;
  }
  if (cap < 1) return 0;
  /* depth(t) = D (1 - cos(2 pi f t)) / 2: from 0 to D and back, smoothly */
  double d = p->depth * 0.5 * (1 - cos(2 * 3.14159265358979 * p->freq * t));
  cmd[0] = (palp_cli_cmd){.finger = 0, .mode = d > 1e-5 ? 2 : 0, .radius = p->radius,
                          .center = {0, 0, p->R + p->radius - d}};
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
                          .feedback = p_feedback, .close = p_close};
  return 0;
}
