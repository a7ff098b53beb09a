/* input_simdevice.c - a simulated position-driven haptic device: scripted
 * trajectories (press, slide, circles, press-release cycles, the MammaCare
 * vertical-strip search) for tests and demos (input.h).
 *
 * A trajectory is a list of waypoints (time, surface coordinates u = x, v = y of
 * the undeformed dome, depth below it, finger on or lifted) interpolated
 * linearly; the device point is the fingertip sphere's centre, radius - depth
 * above the surface point along its normal. Pure function of (def, R, t), so a
 * test can drive a model with exactly the trajectory the station plays. */
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input.h"

#define MAX_WP 1024
#define PI 3.14159265358979323846
/* The most of each count whose trajectory fits MAX_WP waypoints with its final lift (build: 8 + 48
 * per circle, 4 + 2 per cycle, 4 + 8 per strip). add() drops what does not fit, and circles=30
 * ended pressed 10 mm deep: the parser and palp_cli_simdevice_input refuse more. */
#define SIM_MAX_CIRCLES ((MAX_WP - 8) / 48) /* 21 */
#define SIM_MAX_CYCLES ((MAX_WP - 4) / 2)   /* 510 */
#define SIM_MAX_STRIPS ((MAX_WP - 4) / 8)   /* 127 */

typedef struct wp {
  double t, u, v, depth;
  int on;
} wp;

typedef struct path {
  wp w[MAX_WP];
  int n;
} path;

palp_cli_simdevice_def palp_cli_simdevice_default_def(palp_cli_sim_pattern pattern) {
  return (palp_cli_simdevice_def){.pattern = pattern,
                                  .polar_deg = 0,
                                  .azimuth_deg = 0,
                                  .depth = 0.010,
                                  .speed = 0.02,
                                  .hold = 0.5,
                                  .approach = 0.003,
                                  .slide_speed = 0.05,
                                  .slide_distance = 0.02,
                                  .circle_radius = 0.005,
                                  .circle_hz = 1.0,
                                  .circle_count = 2,
                                  .cycle_count = 5,
                                  .strip_count = 4,
                                  .strip_extent = 0,
                                  .radius = 0.008,
                                  .start = 0.2,
                                  .tail = 0.5};
}

static void add(path *p, double dt, double u, double v, double depth, int on) {
  if (p->n >= MAX_WP) return;
  const double t = p->n ? p->w[p->n - 1].t + dt : dt;
  p->w[p->n++] = (wp){t, u, v, depth, on};
}

static const wp *last(const path *p) { return &p->w[p->n - 1]; }

/* Move to (u, v, depth) at a speed [m/s] over the larger of the depth change and the surface distance. */
static void move(path *p, double u, double v, double depth, double speed, int on) {
  const wp *l = last(p);
  const double d = fmax(fabs(depth - l->depth), hypot(u - l->u, v - l->v));
  add(p, speed > 0 ? d / speed : 0, u, v, depth, on);
}

static void build(const palp_cli_simdevice_def *d, double R, path *p) {
  p->n = 0;
  palp_vec3 n;
  const palp_vec3 s = palp_cli_dome_point(R, d->polar_deg, d->azimuth_deg, &n);
  const double up = -d->approach;
  double u0 = s.x, v0 = s.y;
  if (d->pattern == PALP_CLI_SIM_STRIPS) {
    const double E = d->strip_extent > 0 ? d->strip_extent : 0.6 * R;
    /* counts held to what fits (palp_cli_simdevice_at and _duration take a def as it is) */
    const int ns = d->strip_count > 1 ? (d->strip_count < SIM_MAX_STRIPS ? d->strip_count : SIM_MAX_STRIPS) : 1;
    add(p, 0, -E, -E, up, 0);
    add(p, d->start, -E, -E, up, 1);
    const double depths[3] = {d->depth / 3, 2 * d->depth / 3, d->depth};
    for (int k = 0; k < ns; k++) {
      const double x = ns > 1 ? -E + 2 * E * k / (ns - 1) : 0;
      move(p, x, -E, up, d->slide_speed, 1);
      double y = -E;
      for (int j = 0; j < 3; j++) {
        move(p, x, y, depths[j], d->speed, 1);
        y = -y;
        move(p, x, y, depths[j], d->slide_speed, 1);
      }
      move(p, x, y, up, d->speed, 1);
    }
    add(p, 1e-3, last(p)->u, last(p)->v, up, 0);
    add(p, d->tail, last(p)->u, last(p)->v, up, 0);
    return;
  }
  add(p, 0, u0, v0, up, 0);
  add(p, d->start, u0, v0, up, 1);
  switch (d->pattern) {
  case PALP_CLI_SIM_CYCLES:
    for (int c = 0; c < (d->cycle_count > 0 ? (d->cycle_count < SIM_MAX_CYCLES ? d->cycle_count : SIM_MAX_CYCLES) : 1);
         c++) {
      move(p, u0, v0, d->depth, d->speed, 1);
      move(p, u0, v0, up, d->speed, 1);
    }
    break;
  case PALP_CLI_SIM_SLIDE: {
    move(p, u0, v0, d->depth, d->speed, 1);
    add(p, d->hold, u0, v0, d->depth, 1);
    /* Tangent direction: azimuth + 90 deg, in the horizontal plane. */
    const double a = (d->azimuth_deg + 90) * PI / 180;
    const double u1 = u0 + d->slide_distance * cos(a), v1 = v0 + d->slide_distance * sin(a);
    move(p, u1, v1, d->depth, d->slide_speed, 1);
    add(p, d->hold, u1, v1, d->depth, 1);
    move(p, u1, v1, up, d->speed, 1);
    break;
  }
  case PALP_CLI_SIM_CIRCLES: {
    const double r = d->circle_radius, hz = d->circle_hz > 0 ? d->circle_hz : 1;
    move(p, u0 + r, v0, up, d->speed, 1);
    move(p, u0 + r, v0, d->depth, d->speed, 1);
    add(p, d->hold, u0 + r, v0, d->depth, 1);
    const int steps =
        48 * (d->circle_count > 0 ? (d->circle_count < SIM_MAX_CIRCLES ? d->circle_count : SIM_MAX_CIRCLES) : 1);
    for (int i = 1; i <= steps; i++) {
      const double ph = 2 * PI * i / 48.0;
      add(p, 1.0 / (48 * hz), u0 + r * cos(ph), v0 + r * sin(ph), d->depth, 1);
    }
    move(p, last(p)->u, last(p)->v, up, d->speed, 1);
    break;
  }
  case PALP_CLI_SIM_PRESS:
  default:
    move(p, u0, v0, d->depth, d->speed, 1);
    add(p, d->hold, u0, v0, d->depth, 1);
    move(p, u0, v0, up, d->speed, 1);
    break;
  }
  add(p, 1e-3, last(p)->u, last(p)->v, up, 0);
  add(p, d->tail, last(p)->u, last(p)->v, up, 0);
}

static palp_vec3 device_point(double R, double radius, double u, double v, double depth) {
  double r2 = u * u + v * v;
  if (r2 > R * R) { /* off the dome: project onto its rim */
    const double s = R / sqrt(r2);
    u *= s;
    v *= s;
    r2 = R * R;
  }
  const palp_vec3 p = {u, v, sqrt(R * R - r2)};
  const double h = radius - depth;
  return (palp_vec3){p.x + p.x / R * h, p.y + p.y / R * h, p.z + p.z / R * h};
}

static int eval(const path *p, const palp_cli_simdevice_def *d, double R, double t, palp_vec3 *x) {
  if (p->n == 0) return PALP_EINVAL;
  if (t >= p->w[p->n - 1].t) {
    const wp *l = last(p);
    *x = device_point(R, d->radius, l->u, l->v, l->depth);
    return PALP_CLI_INPUT_END;
  }
  int k = 0;
  while (k + 1 < p->n && p->w[k + 1].t <= t) k++;
  const wp *a = &p->w[k], *b = &p->w[k + 1 < p->n ? k + 1 : k];
  const double span = b->t - a->t;
  const double s = span > 0 ? (t - a->t) / span : 1;
  const double sc = s < 0 ? 0 : (s > 1 ? 1 : s);
  *x = device_point(R, d->radius, a->u + (b->u - a->u) * sc, a->v + (b->v - a->v) * sc,
                    a->depth + (b->depth - a->depth) * sc);
  return a->on;
}

int palp_cli_simdevice_at(const palp_cli_simdevice_def *def, double R, double t, palp_vec3 *x) {
  path *p = malloc(sizeof *p);
  if (!p) return PALP_ENOMEM;
  build(def, R, p);
  int rc = eval(p, def, R, t, x);
  free(p);
  return rc;
}

double palp_cli_simdevice_duration(const palp_cli_simdevice_def *def, double R) {
  path *p = malloc(sizeof *p);
  if (!p) return 0;
  build(def, R, p);
  double t = p->w[p->n - 1].t;
  free(p);
  return t;
}

/* ---- as an input source -------------------------------------------------------- */

typedef struct simdev {
  palp_cli_simdevice_def def;
  double R;
  path p;
  palp_vec3 force; /* last force written [N] */
  unsigned flags;
  char err[128];
  int marked, withdrawn;  /* haptic thread: the scripted button presses done */
  atomic_int button;      /* haptic thread -> main thread */
} simdev;

static int sd_open(void *ctx, double R) {
  simdev *s = ctx;
  if (!(R > 0)) return PALP_EINVAL;
  s->R = R;
  build(&s->def, R, &s->p);
  return 0;
}

static int sd_read(void *ctx, double t, palp_vec3 *x) {
  simdev *s = ctx;
  if (!(s->R > 0)) {
    snprintf(s->err, sizeof s->err, "simulated device: read before open");
    return PALP_EINVAL;
  }
  if (s->def.mark_at > 0 && !s->marked && t >= s->def.mark_at) {
    s->marked = 1;
    atomic_store(&s->button, PALP_CLI_BUTTON_MARK);
  }
  if (s->def.withdraw_at > 0 && !s->withdrawn && t >= s->def.withdraw_at) {
    s->withdrawn = 1;
    atomic_store(&s->button, PALP_CLI_BUTTON_WITHDRAW);
  }
  return eval(&s->p, &s->def, s->R, t, x);
}

static int sd_button(void *ctx) {
  simdev *s = ctx;
  return atomic_exchange(&s->button, 0);
}

static void sd_write(void *ctx, palp_vec3 f, unsigned flags) {
  simdev *s = ctx;
  s->force = f; /* a real device would command its motors here */
  s->flags = flags;
}

static const char *sd_error(void *ctx) {
  simdev *s = ctx;
  return s->err[0] ? s->err : NULL;
}

/* poll() for callers that drive the device the old way (10-1000 Hz, no haptic thread). */
static int sd_poll(void *ctx, double t, palp_cli_cmd *cmd, int cap) {
  simdev *s = ctx;
  palp_vec3 x;
  int on = sd_read(ctx, t, &x);
  if (on < 0 || on == PALP_CLI_INPUT_END) return on;
  if (cap < 1) return 0;
  cmd[0] = (palp_cli_cmd){.finger = 0, .mode = on ? 2 : 0, .center = x, .radius = s->def.radius};
  return 1;
}

static void sd_close(void *ctx) { free(ctx); }

int palp_cli_simdevice_input(const palp_cli_simdevice_def *def, palp_cli_input *out) {
  if (!def || !out || !(def->depth >= 0 && def->depth < 0.1) || !(def->speed > 0) || !(def->radius > 0) ||
      !(def->slide_speed > 0) || !(def->hold >= 0) || !(def->approach >= 0) || def->circle_count > SIM_MAX_CIRCLES ||
      def->cycle_count > SIM_MAX_CYCLES || def->strip_count > SIM_MAX_STRIPS)
    return PALP_EINVAL;
  simdev *s = calloc(1, sizeof *s);
  if (!s) return PALP_ENOMEM;
  s->def = *def;
  *out = (palp_cli_input){.name = "simulated device",
                          .ctx = s,
                          .open = sd_open,
                          .poll = sd_poll,
                          .close = sd_close,
                          .read_position = sd_read,
                          .write_force = sd_write,
                          .error = sd_error,
                          .finger_radius = def->radius,
                          .button = sd_button};
  return 0;
}

int palp_cli_simdevice_parse(const char *spec, palp_cli_simdevice_def *out, char *err, size_t errlen) {
  static const char *const names[] = {"press", "slide", "circles", "cycles", "strips"};
  char buf[256];
  if (!spec || strlen(spec) >= sizeof buf) {
    snprintf(err, errlen, "simulated device: empty or too long a trajectory");
    return PALP_EINVAL;
  }
  snprintf(buf, sizeof buf, "%s", spec);
  char *save = NULL, *tok = strtok_r(buf, ",", &save);
  int pat = -1;
  for (int i = 0; tok && i < 5; i++)
    if (!strcmp(tok, names[i])) pat = i;
  if (pat < 0) {
    snprintf(err, errlen, "simulated device: trajectory \"%s\": expected press, slide, circles, cycles or strips",
             tok ? tok : "");
    return PALP_EINVAL;
  }
  palp_cli_simdevice_def d = palp_cli_simdevice_default_def((palp_cli_sim_pattern)pat);
  while ((tok = strtok_r(NULL, ",", &save))) {
    char *eq = strchr(tok, '=');
    char *end = NULL;
    double v = eq ? strtod(eq + 1, &end) : NAN;
    /* azimuth may be negative, as --azimuth may (-360..360 deg); every other value is >= 0 */
    const int signed_ok = eq && (size_t)(eq - tok) == strlen("azimuth") && !strncmp(tok, "azimuth", 7);
    if (!eq || end == eq + 1 || *end || !isfinite(v) || v < (signed_ok ? -360 : 0) || v > 1e4) {
      snprintf(err, errlen, "simulated device: \"%s\": expected key=value with a number in [%s, 1e4]", tok,
               signed_ok ? "-360" : "0");
      return PALP_EINVAL;
    }
    *eq = 0;
    /* counts are whole: circles=2.5 was cut to 2 without a word (session 81) */
    if ((!strcmp(tok, "circles") || !strcmp(tok, "cycles") || !strcmp(tok, "strips")) && v != floor(v)) {
      snprintf(err, errlen, "simulated device: \"%s=%s\": a count, expected a whole number", tok, eq + 1);
      return PALP_EINVAL;
    }
    if (!strcmp(tok, "depth_mm")) d.depth = v * 1e-3;
    else if (!strcmp(tok, "speed_mm_s")) d.speed = v * 1e-3;
    else if (!strcmp(tok, "hold_s")) d.hold = v;
    else if (!strcmp(tok, "slide_mm_s")) d.slide_speed = v * 1e-3;
    else if (!strcmp(tok, "slide_mm")) d.slide_distance = v * 1e-3;
    else if (!strcmp(tok, "circle_mm")) d.circle_radius = v * 1e-3;
    else if (!strcmp(tok, "circle_hz")) d.circle_hz = v;
    else if (!strcmp(tok, "circles")) d.circle_count = (int)v;
    else if (!strcmp(tok, "cycles")) d.cycle_count = (int)v;
    else if (!strcmp(tok, "strips")) d.strip_count = (int)v;
    else if (!strcmp(tok, "polar")) d.polar_deg = v;
    else if (!strcmp(tok, "azimuth")) d.azimuth_deg = v;
    else if (!strcmp(tok, "radius_mm")) d.radius = v * 1e-3;
    else if (!strcmp(tok, "mark_s")) d.mark_at = v;
    else if (!strcmp(tok, "withdraw_s")) d.withdraw_at = v;
    else {
      snprintf(err, errlen, "simulated device: unknown key \"%s\" (depth_mm, speed_mm_s, hold_s, slide_mm_s, "
                            "slide_mm, circle_mm, circle_hz, circles, cycles, strips, polar, azimuth, radius_mm, mark_s, "
                            "withdraw_s)", tok);
      return PALP_EINVAL;
    }
  }
  if (!(d.depth < 0.1) || !(d.speed > 0) || !(d.slide_speed > 0) || !(d.radius > 0) || d.polar_deg > 90) {
    snprintf(err, errlen, "simulated device: depth must be < 100 mm, speeds and radius > 0, polar <= 90 deg");
    return PALP_EINVAL;
  }
  if (d.circle_count > SIM_MAX_CIRCLES || d.cycle_count > SIM_MAX_CYCLES || d.strip_count > SIM_MAX_STRIPS) {
    snprintf(err, errlen, "simulated device: at most %d circles, %d cycles and %d strips (a trajectory is %d "
             "waypoints, and a longer one would be cut short while pressing)", SIM_MAX_CIRCLES, SIM_MAX_CYCLES,
             SIM_MAX_STRIPS, MAX_WP);
    return PALP_EINVAL;
  }
  *out = d;
  return 0;
}
