/*
 * bench_motion.h - the exercises' search as a device trajectory, shared by the
 * benchmarks that step haptic sessions (bench_server haptic --motion strip,
 * bench_model_rebuilds; header-only, bench/ only).
 */
#ifndef PALP_BENCH_MOTION_H
#define PALP_BENCH_MOTION_H

#include <math.h>

#include "palp.h"

/* Smooth step from 0 to 1 over [0, 1] (C1: the device never jumps). */
static inline double palp_bench_ease(double x) { return x <= 0 ? 0 : x >= 1 ? 1 : 0.5 - 0.5 * cos(3.14159265358979 * x); }

/* Device of session i at t for --motion strip: a MammaCare vertical-strip search as the
 * exercises' scripted expert does it (client/trainee.c: spots 8 mm apart, each felt at
 * 3 / 9 / 16 mm with small circles): along the meridian at azimuth 0.3 i through the
 * pole, 50 deg either side; per 1.5 s spot ~0.3 s at each depth (0.15 s ramps), a lift to
 * 3 mm (0.2 s) and a glide to the next spot (0.3 s); circles of 2.5 mm radius at 2 Hz
 * throughout; sessions phase-shifted. Device speeds up to ~100 mm/s. */
static inline palp_vec3 palp_bench_strip_device(int i, double t) {
  const double R = 0.04, r = 0.008, spot = 1.5, spacing = 0.008, half = 50.0 * 3.14159265358979 / 180.0 * R;
  const double ts = t + 0.37 * i;
  const double k = floor(ts / spot), x = ts - k * spot; /* spot index, time within it [s] */
  const double d1 = 0.003, d2 = 0.009, d3 = 0.016;     /* [m] */
  const double depth = d1 + (d2 - d1) * palp_bench_ease((x - 0.3) / 0.15) +
                       (d3 - d2) * palp_bench_ease((x - 0.65) / 0.15) - (d3 - d1) * palp_bench_ease((x - 1.0) / 0.2);
  /* arc coordinate: a triangle wave over [-half, half], one spacing per spot, glided in
   * the spot's last 0.3 s */
  const double u_steps = k + palp_bench_ease((x - 1.2) / 0.3);
  const double span = 2 * half, pos = fmod(u_steps * spacing, 2 * span);
  const double u = (pos < span ? pos : 2 * span - pos) - half;
  const double th = u / R, ph = 0.3 * i;
  const palp_vec3 n = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)};
  const palp_vec3 eu = {cos(th) * cos(ph), cos(th) * sin(ph), -sin(th)}, ev = {-sin(ph), cos(ph), 0};
  const double w = 2 * 3.14159265358979 * 2.0 * ts, rho = 0.0025;
  const double hgt = R + r - depth; /* depth: device travel past first touch at rest [m] */
  return (palp_vec3){n.x * hgt + rho * (cos(w) * eu.x + sin(w) * ev.x),
                     n.y * hgt + rho * (cos(w) * eu.y + sin(w) * ev.y),
                     n.z * hgt + rho * (cos(w) * eu.z + sin(w) * ev.z)};
}

#endif
