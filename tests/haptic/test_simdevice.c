/*
 * test_simdevice.c - the simulated haptic device's trajectories (pure, no DDS):
 * the device point is the fingertip centre, radius - depth above the undeformed
 * dome along its normal, so |x| = R + radius - depth wherever the finger is on
 * the dome. Checked per pattern against values computed here from the stated
 * parameters, and the parser's errors.
 */
#include <math.h>
#include <string.h>

#include "check.h"
#include "input.h"

static double len3(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

int main(void) {
  const double R = 0.04;
  /* press: 10 mm at 20 mm/s after a 3 mm approach, held 0.5 s */
  palp_cli_simdevice_def d = palp_cli_simdevice_default_def(PALP_CLI_SIM_PRESS);
  const double t_bottom = d.start + (d.depth + d.approach) / d.speed; /* 0.2 + 0.65 s */
  palp_vec3 x;
  int on = palp_cli_simdevice_at(&d, R, t_bottom + 0.25, &x);
  CHECK(on == 1 && fabs(len3(x) - (R + d.radius - d.depth)) < 1e-12 && fabs(x.z - len3(x)) < 1e-12,
        "press: held at 10 mm below the pole: |x| = %.6f m (expected %.6f)", len3(x), R + d.radius - d.depth);
  on = palp_cli_simdevice_at(&d, R, d.start + 0.5 * (d.depth + d.approach) / d.speed, &x);
  CHECK(on == 1 && fabs(len3(x) - (R + d.radius - 0.5 * (d.depth - d.approach))) < 1e-12,
        "press: half way down at 20 mm/s: |x| = %.6f m", len3(x));
  on = palp_cli_simdevice_at(&d, R, 0.1, &x);
  CHECK(on == 0, "press: lifted before its start");
  const double dur = palp_cli_simdevice_duration(&d, R);
  CHECK(fabs(dur - (t_bottom + d.hold + (d.depth + d.approach) / d.speed + 1e-3 + d.tail)) < 1e-12,
        "press: duration %.4f s", dur);
  CHECK(palp_cli_simdevice_at(&d, R, dur + 0.01, &x) == PALP_CLI_INPUT_END, "press: ends after its duration");

  /* slide: 20 mm at 50 mm/s towards azimuth + 90 deg (azimuth 0: +y) */
  d = palp_cli_simdevice_default_def(PALP_CLI_SIM_SLIDE);
  const double ts = d.start + (d.depth + d.approach) / d.speed + d.hold;
  palp_vec3 a, b;
  palp_cli_simdevice_at(&d, R, ts, &a);
  palp_cli_simdevice_at(&d, R, ts + d.slide_distance / d.slide_speed, &b);
  /* On the dome's surface (the device point projected back onto it): */
  const double ay = a.y / len3(a) * R, by = b.y / len3(b) * R;
  CHECK(fabs(by - ay - d.slide_distance) < 1e-12 && fabs(b.x - a.x) < 1e-12,
        "slide: 20 mm along +y on the surface in 0.4 s (moved %.4f mm)", (by - ay) * 1e3);
  CHECK(fabs(len3(b) - (R + d.radius - d.depth)) < 1e-12, "slide: stays 10 mm deep along the surface");

  /* circles: radius 5 mm around the press point, at depth */
  d = palp_cli_simdevice_default_def(PALP_CLI_SIM_CIRCLES);
  d.polar_deg = 20;
  double rmin = 1, rmax = 0;
  palp_vec3 c;
  palp_cli_dome_point(R, d.polar_deg, d.azimuth_deg, &c);
  const double t0 = d.start + (2 * d.circle_radius) / d.speed + (d.depth + d.approach) / d.speed + d.hold;
  for (double t = t0 + 0.01; t < t0 + d.circle_count / d.circle_hz - 0.01; t += 0.01) {
    palp_cli_simdevice_at(&d, R, t, &x);
    const double r = hypot(x.x / len3(x) * R - c.x * R, x.y / len3(x) * R - c.y * R);
    if (r < rmin) rmin = r;
    if (r > rmax) rmax = r;
  }
  CHECK(rmin > 0.0045 && rmax < 0.0052, "circles: %.2f..%.2f mm from the press point (5 mm, chords of 48 per turn)",
        rmin * 1e3, rmax * 1e3);

  /* strips: 4 strips, each swept at depth/3, 2 depth/3 and depth */
  d = palp_cli_simdevice_default_def(PALP_CLI_SIM_STRIPS);
  int seen[3] = {0, 0, 0};
  double xs[4] = {0};
  int nx = 0;
  const double sd = palp_cli_simdevice_duration(&d, R);
  for (double t = 0; t < sd; t += 0.002) {
    if (palp_cli_simdevice_at(&d, R, t, &x) != 1) continue;
    const double depth = R + d.radius - len3(x);
    for (int j = 0; j < 3; j++)
      if (fabs(depth - d.depth * (j + 1) / 3) < 1e-9) seen[j]++;
    if (fabs(depth - d.depth) < 1e-9) {
      const double u = x.x / len3(x) * R;
      int k = 0;
      while (k < nx && fabs(xs[k] - u) > 1e-6) k++;
      if (k == nx && nx < 4) xs[nx++] = u;
    }
  }
  CHECK(seen[0] > 100 && seen[1] > 100 && seen[2] > 100, "strips: time at light/medium/deep %d/%d/%d ticks", seen[0],
        seen[1], seen[2]);
  CHECK(nx == 4 && fabs(xs[0] + 0.6 * R) < 1e-6 && fabs(xs[3] - 0.6 * R) < 1e-6,
        "strips: 4 deep sweeps at x = %.1f .. %.1f mm (+-24 mm)", xs[0] * 1e3, xs[nx ? nx - 1 : 0] * 1e3);

  /* the parser */
  char err[256];
  palp_cli_simdevice_def p;
  CHECK(palp_cli_simdevice_parse("slide,depth_mm=15,slide_mm_s=20", &p, err, sizeof err) == 0 &&
            p.pattern == PALP_CLI_SIM_SLIDE && fabs(p.depth - 0.015) < 1e-15 && fabs(p.slide_speed - 0.02) < 1e-15,
        "parse: slide, 15 mm, 20 mm/s");
  CHECK(palp_cli_simdevice_parse("knead", &p, err, sizeof err) < 0 && strstr(err, "knead"), "parse: %s", err);
  CHECK(palp_cli_simdevice_parse("press,depth=5", &p, err, sizeof err) < 0 && strstr(err, "unknown key"), "parse: %s",
        err);
  CHECK(palp_cli_simdevice_parse("press,depth_mm=abc", &p, err, sizeof err) < 0, "parse: %s", err);
  CHECK(palp_cli_simdevice_parse("press,depth_mm=200", &p, err, sizeof err) < 0, "parse: %s", err);

  /* Counts a trajectory of 1024 waypoints holds with its final lift (8 + 48 per circle, 4 + 2 per
   * cycle, 4 + 8 per strip): one more is refused, naming the largest. The largest ends lifted:
   * over the tail, the finger off and the device point at least radius + approach (3 mm, within
   * 1 um) above the surface. Before, circles=30 ended pressed 10 mm deep and cycles=2000 and
   * strips=200 were cut short while pressing. */
  const struct {
    const char *over, *max, *largest;
  } counts[] = {{"circles,circles=22", "circles,circles=21", "21 circles"},
                {"cycles,cycles=511", "cycles,cycles=510", "510 cycles"},
                {"strips,strips=128", "strips,strips=127", "127 strips"}};
  for (int k = 0; k < 3; k++) {
    err[0] = '\0';
    CHECK(palp_cli_simdevice_parse(counts[k].over, &p, err, sizeof err) < 0 && strstr(err, counts[k].largest),
          "parse \"%s\" refused naming \"%s\": %s", counts[k].over, counts[k].largest, err);
    const int ok = palp_cli_simdevice_parse(counts[k].max, &p, err, sizeof err) == 0;
    const double T = ok ? palp_cli_simdevice_duration(&p, R) : 0;
    palp_vec3 x = {0, 0, 0};
    const int on = ok ? palp_cli_simdevice_at(&p, R, T - p.tail / 2, &x) : -1;
    const double above = len3(x) - R - p.radius; /* the fingertip's lowest point above the dome [m] */
    CHECK(ok && on == 0 && fabs(above - p.approach) < 1e-6,
          "\"%s\" (%.0f s) ends lifted: finger %s, %.3f mm above the surface (3 mm)", counts[k].max, T,
          on == 0 ? "off" : "on", above * 1e3);
  }
  palp_cli_input in;
  p = palp_cli_simdevice_default_def(PALP_CLI_SIM_CIRCLES), p.circle_count = 30;
  CHECK(palp_cli_simdevice_input(&p, &in) == PALP_EINVAL, "a def of 30 circles refused as an input");
  {
    const double T = palp_cli_simdevice_duration(&p, R);
    palp_vec3 x = {0, 0, 0};
    const int on = palp_cli_simdevice_at(&p, R, T - p.tail / 2, &x);
    const double above = len3(x) - R - p.radius;
    CHECK(on == 0 && fabs(above - p.approach) < 1e-6,
          "a def of 30 circles given as it is (palp_cli_simdevice_at) ends lifted: finger %s, %.3f mm above the surface",
          on == 0 ? "off" : "on", above * 1e3);
  }
  return check_exit();
}
