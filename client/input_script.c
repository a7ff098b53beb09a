/* input_script.c - scripted palpation: a profile applied at a point of the dome. */
#include <math.h>
#include <stdlib.h>

#include "input.h"

palp_vec3 palp_cli_dome_point(double R, double polar_deg, double azimuth_deg, palp_vec3 *normal) {
  const double deg = 3.14159265358979323846 / 180.0;
  double th = polar_deg * deg, ph = azimuth_deg * deg;
  palp_vec3 n = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)};
  if (normal) *normal = n;
  return (palp_vec3){R * n.x, R * n.y, R * n.z};
}

const char *palp_cli_dist_name(int d) {
  static const char *const n[] = {"?", "I single", "II uniform", "III gaussian", "IV gaussian_offset"};
  return d >= 1 && d <= 4 ? n[d] : n[0];
}

typedef struct script {
  palp_cli_script_def def;
  double R;
} script;

static int s_open(void *ctx, double R) {
  ((script *)ctx)->R = R;
  return 0;
}

static int s_poll(void *ctx, double t, palp_cli_cmd *cmd, int cap) {
  script *s = ctx;
  if (t >= s->def.end_time) return PALP_CLI_INPUT_END;
  if (cap < 1) return 0;
  palp_vec3 n;
  palp_vec3 p = palp_cli_dome_point(s->R, s->def.polar_deg, s->def.azimuth_deg, &n);
  double v = palp_profile_eval(&s->def.profile, t);
  cmd[0] = (palp_cli_cmd){.finger = 0, .distribution = s->def.distribution, .patch_area = s->def.patch_area};
  if (!s->def.finger_mode) {
    /* Force along the inward normal; a zero force lifts the finger. */
    if (fabs(v) < 1e-9) return 1;
    cmd[0].mode = 1;
    cmd[0].center = p;
    cmd[0].force = (palp_vec3){-v * n.x, -v * n.y, -v * n.z};
  } else {
    /* Tip centre at depth v below the rest surface, along the normal. */
    if (v <= 0) return 1;
    double r = s->def.radius, d = s->R + r - v;
    cmd[0].mode = 2;
    cmd[0].radius = r;
    cmd[0].center = (palp_vec3){d * n.x, d * n.y, d * n.z};
  }
  return 1;
}

static void s_close(void *ctx) { free(ctx); }

int palp_cli_script_input(const palp_cli_script_def *def, palp_cli_input *out) {
  script *s = calloc(1, sizeof *s);
  if (!s) return PALP_ENOMEM;
  s->def = *def;
  *out = (palp_cli_input){.name = "script", .ctx = s, .open = s_open, .poll = s_poll, .close = s_close};
  return 0;
}
