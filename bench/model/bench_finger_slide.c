/*
 * bench_finger_slide.c - what a fingertip sliding at constant depth feels
 * (docs/haptics.md, "The facets are felt at light touch").
 *
 * A scene's world (its force contacts removed), 1 kHz, one default fingertip (8 mm,
 * 2000 N/m coupling, 5000 N/m pad). The device is pressed at 1 mm/s to `depth` below
 * the dome's sphere (its centre at radius R + r - depth from the base centre), along
 * the sphere's normal at polar angle `polar` and azimuth 0, held 0.3 s, then slid at
 * `speed` along that latitude for `arc` degrees of azimuth. Reported over the slide
 * after its first 2 mm: the force's mean, min, max and (max - min) / mean, its
 * tick-to-tick step off the linear trend |F_k - 2 F_(k-1) + F_(k-2)| (worst), the
 * facet sag under the device's ray (the real-time dome is inscribed in the sphere) at
 * the worst and best ticks, and the finger stage's mean cost per step.
 *
 *   bench_finger_slide [--scene FILE] [--surface smooth|facets] [--polar DEG]
 *                      [--depth MM] [--speed MM_S] [--arc DEG] [--trace]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h"

#define PI 3.14159265358979323846

static palp_vec3 at(double rho, double polar, double az) {
  return (palp_vec3){rho * sin(polar) * cos(az), rho * sin(polar) * sin(az), rho * cos(polar)};
}

int main(int argc, char **argv) {
  const char *scene = PALP_CONFIG_DIR "/paper_step_long_term.json";
  const char *surface = NULL;
  double polar_deg = 30.0, depth_mm = 0.5, speed = 5.0, arc_deg = 60.0;
  int trace = 0;
  double pad = -1.0;
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--scene") && i + 1 < argc) scene = argv[++i];
    else if (!strcmp(argv[i], "--surface") && i + 1 < argc) surface = argv[++i];
    else if (!strcmp(argv[i], "--polar") && i + 1 < argc) polar_deg = atof(argv[++i]);
    else if (!strcmp(argv[i], "--depth") && i + 1 < argc) depth_mm = atof(argv[++i]);
    else if (!strcmp(argv[i], "--speed") && i + 1 < argc) speed = atof(argv[++i]);
    else if (!strcmp(argv[i], "--arc") && i + 1 < argc) arc_deg = atof(argv[++i]);
    else if (!strcmp(argv[i], "--trace")) trace = 1;
    else if (!strcmp(argv[i], "--pad") && i + 1 < argc) pad = atof(argv[++i]);
    else {
      fprintf(stderr, "usage: %s [--scene FILE] [--surface smooth|facets] [--polar DEG] [--depth MM] [--speed MM_S] "
                      "[--arc DEG] [--pad N_M] [--trace]\n", argv[0]);
      return 2;
    }
  }
  palp_scene sc;
  char err[256];
  if (palp_scene_load(scene, &sc, err, sizeof err)) {
    fprintf(stderr, "%s\n", err);
    return 1;
  }
  sc.world.dt = 0.001;
  if (surface && palp_finger_surface_from_name(surface, &sc.world.finger_surface)) {
    fprintf(stderr, "--surface: smooth or facets\n");
    return 2;
  }
  int e = 0;
  palp_world *w = palp_scene_create_world(&sc, &e);
  if (!w) {
    fprintf(stderr, "world: %s\n", palp_strerror(e));
    return 1;
  }
  for (int c = 0; c < sc.contact_count; ++c) palp_world_remove_contact(w, c);
  const double R = sc.world.mesh.radius, r = 0.008, depth = depth_mm * 1e-3, polar = polar_deg * PI / 180.0;
  palp_finger_def fd = palp_finger_default_def();
  if (pad >= 0.0) fd.pad_stiffness = pad;
  const int f = palp_world_add_finger_def(w, &fd, at(R + r + 1e-3, polar, 0.0));
  if (f < 0) {
    fprintf(stderr, "finger: %s\n", palp_strerror(f));
    return 1;
  }
  /* press at 1 mm/s from 1 mm above the sphere, hold 0.3 s */
  const int npress = (int)lround((1e-3 + depth) / 1e-6);
  for (int k = 1; k <= npress + 300; ++k) {
    const double rho = R + r + 1e-3 - 1e-6 * (k < npress ? k : npress);
    palp_world_set_finger_device(w, f, at(rho, polar, 0.0));
    if (palp_world_step(w)) return 1;
  }
  const double rho = R + r - depth, lat = rho * sin(polar); /* [m] latitude radius of the device */
  const double daz = speed * 1e-3 * 1e-3 / lat;                /* [rad per tick] */
  const int nslide = (int)(arc_deg * PI / 180.0 / daz), skip = (int)(2e-3 / (speed * 1e-3) * 1e3);
  const palp_mesh *m = palp_world_mesh(w);
  double sum = 0.0, fmin_ = INFINITY, fmax_ = 0.0, worst_step = 0.0, ftime = 0.0;
  double sag_min = 0.0, sag_max = 0.0;
  int n = 0, lost = 0;
  double F1 = 0.0, F2 = 0.0;
  palp_stage_timings tm;
  for (int k = 1; k <= nslide; ++k) {
    const double az = daz * k;
    palp_world_set_finger_device(w, f, at(rho, polar, az));
    if (palp_world_step(w)) return 1;
    palp_world_timings(w, &tm);
    for (int s = 0; s < PALP_STAGE_COUNT; ++s)
      if (tm.name[s] && !strcmp(tm.name[s], "fingers")) ftime += tm.last[s];
    palp_local_model lm;
    palp_world_finger_local_model(w, f, &lm);
    const double F = sqrt(lm.force.x * lm.force.x + lm.force.y * lm.force.y + lm.force.z * lm.force.z);
    if (!lm.contact) lost++;
    if (trace) printf("T %d %.3f %.6f %d\n", k, az * 180.0 / PI, F, lm.triangles);
    if (k > skip) {
      /* the sag of the rest dome under the device's ray: R minus the distance to the
       * facet it crosses (a ray from the base centre) */
      const palp_vec3 u = at(1.0, polar, az);
      double sag = 0.0;
      for (int t = 0; t < m->dome_triangle_count; ++t) {
        const palp_vec3 a = m->rest[m->tri[t][0]], b = m->rest[m->tri[t][1]], c = m->rest[m->tri[t][2]];
        const palp_vec3 e1 = {b.x - a.x, b.y - a.y, b.z - a.z}, e2 = {c.x - a.x, c.y - a.y, c.z - a.z};
        const palp_vec3 nn = {e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x};
        const double den = nn.x * u.x + nn.y * u.y + nn.z * u.z;
        if (!(den > 0.0)) continue;
        const double s = (nn.x * a.x + nn.y * a.y + nn.z * a.z) / den; /* ray length to the plane */
        const palp_vec3 x = {s * u.x - a.x, s * u.y - a.y, s * u.z - a.z};
        /* inside the triangle: barycentric by areas */
        const palp_vec3 c1 = {e1.y * x.z - e1.z * x.y, e1.z * x.x - e1.x * x.z, e1.x * x.y - e1.y * x.x};
        const palp_vec3 c2 = {x.y * e2.z - x.z * e2.y, x.z * e2.x - x.x * e2.z, x.x * e2.y - x.y * e2.x};
        const double w2 = (c1.x * nn.x + c1.y * nn.y + c1.z * nn.z) / (nn.x * nn.x + nn.y * nn.y + nn.z * nn.z);
        const double w1 = (c2.x * nn.x + c2.y * nn.y + c2.z * nn.z) / (nn.x * nn.x + nn.y * nn.y + nn.z * nn.z);
        if (w1 < -1e-12 || w2 < -1e-12 || w1 + w2 > 1 + 1e-12) continue;
        sag = R - s;
        break;
      }
      if (F < fmin_) fmin_ = F, sag_min = sag;
      if (F > fmax_) fmax_ = F, sag_max = sag;
      sum += F;
      n++;
      const double st = fabs(F - 2 * F1 + F2);
      if (st > worst_step) worst_step = st;
    }
    F2 = F1, F1 = F;
  }
  const double mean = sum / n;
  printf("surface %s, polar %.0f deg, %.2f mm below the sphere, %.1f mm/s over %.0f deg (%d ticks measured): force "
         "mean %.4f N, min %.4f (sag under the device %.3f mm), max %.4f (sag %.3f mm), (max - min) / mean %.1f%%; "
         "worst tick step off the trend %.5f N; ticks out of contact %d; finger stage %.2f us per step\n",
         palp_finger_surface_name(sc.world.finger_surface), polar_deg, depth_mm, speed, arc_deg, n, mean, fmin_,
         sag_min * 1e3, fmax_, sag_max * 1e3, 100.0 * (fmax_ - fmin_) / mean, worst_step, lost, 1e6 * ftime / nslide);
  palp_world_destroy(w);
  return 0;
}
