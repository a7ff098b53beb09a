/*
 * eval_finger.c - the real-time model's fingertip force-depth curve, the side of
 * `palp-fem finger` and of calibrate's finger residuals that needs no FEM.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "eval.h"

/* The point s [m] along the unit normal n from the dome's centre. */
static palp_vec3 along(palp_vec3 n, double s) { return (palp_vec3){s * n.x, s * n.y, s * n.z}; }

double palp_eval_deep_press(const palp_world_def *wd0, palp_vec3 n, double max_depth, double *force, double *strain,
                            char *err, size_t errlen) {
  palp_world_def wd = *wd0;
  wd.dt = 0.004;
  int e = 0;
  palp_world *w = palp_world_create(&wd, &e);
  if (!w) {
    snprintf(err, errlen, "deep press: world: %s", palp_strerror(e));
    return -1;
  }
  const double R = wd.mesh.radius, r = 0.008;
  const int fid = palp_world_add_finger(w, along(n, R + r + 0.001), r);
  double lost = 0.0, depth = 0.0;
  palp_local_model lm = {0};
  int touched = 0;
  for (double level = 0.002; level <= max_depth + 1e-9 && lost == 0.0; level += 0.002)
    for (int k = 0; k < 125; ++k) { /* 0.5 s a level: the travel at 10 mm/s, then the hold */
      depth = fmin(level, depth + 4e-5);
      palp_world_set_finger_device(w, fid, along(n, R + r + 0.001 - depth));
      if (palp_world_step(w) < 0) {
        snprintf(err, errlen, "deep press: the step failed at %.1f mm", 1e3 * depth);
        palp_world_destroy(w);
        return -1;
      }
      palp_world_finger_local_model(w, fid, &lm);
      touched |= lm.contact;
      if (touched && !lm.contact && lost == 0.0) lost = level;
    }
  palp_world_health h;
  palp_world_get_health(w, &h);
  if (force) *force = lm.force.x * n.x + lm.force.y * n.y + lm.force.z * n.z;
  if (strain) *strain = h.max_strain;
  palp_world_destroy(w);
  return lost;
}

double palp_eval_finger_rt_step(const palp_world_def *wd) {
  return wd->finger_linearise == PALP_FINGER_LINEARISE_CURRENT ? 0.004 : 0.001;
}

int palp_eval_finger_rt(const palp_world_def *wd, const palp_lesion *les, int nles, palp_vec3 n, double radius,
                        const double *depth, int count, double hold_s, double *force, double *depth_real, char *err,
                        size_t errlen) {
  return palp_eval_finger_rt_at(wd, palp_eval_finger_rt_step(wd), les, nles, n, radius, depth, count, hold_s, force,
                                depth_real, err, errlen);
}

int palp_eval_finger_rt_at(const palp_world_def *wd0, double dt, const palp_lesion *les, int nles, palp_vec3 n,
                           double radius, const double *depth, int count, double hold_s, double *force,
                           double *depth_real, char *err, size_t errlen) {
  palp_world_def wd = *wd0;
  if (!(dt > 0.0 && dt <= 0.01)) {
    snprintf(err, errlen, "real-time finger: step %g s (want 0 < dt <= 10 ms)", dt);
    return -1;
  }
  wd.dt = dt;
  if (nles < 0 || nles > PALP_MAX_LESIONS) {
    snprintf(err, errlen, "real-time finger: %d lesions (0 to %d)", nles, PALP_MAX_LESIONS);
    return -1;
  }
  wd.lesion_count = nles;
  for (int i = 0; i < nles; ++i) wd.lesion[i] = les[i];
  int e = 0;
  palp_world *w = palp_world_create(&wd, &e);
  if (!w) {
    snprintf(err, errlen, "real-time world: %s", palp_strerror(e));
    return -1;
  }
  const double R = wd.mesh.radius, r = radius;
  const int fid = palp_world_add_finger(w, along(n, R + r + 0.001), r);
  if (fid < 0) {
    snprintf(err, errlen, "real-time finger: %s", palp_strerror(fid));
    palp_world_destroy(w);
    return -1;
  }
  double dd = -0.001; /* device depth [m] */
  for (int k = 0; k < count; ++k) {
    double target = depth[k] + (k ? force[k - 1] / 2000.0 : 0.0); /* proxy ~ F / k_c above the device */
    palp_local_model lm = {0};
    double prev_dev = NAN, prev_real = NAN;
    for (int pass = 0; pass < 6; ++pass) { /* the last pass measures, it does not move */
      /* ramp the device at 5 mm/s, then hold (hold_s, then hold_s / 2 for each
       * correction: the real-time model's creep settles in about a second at
       * hold_s = 1; the FE side is fully relaxed), and move the device so the proxy
       * sits at depth: by the secant of proxy depth over device depth once two
       * passes are known (a stiff phantom moves the proxy by only k_c / (k_c + k)
       * of the device's move, and plain error feedback then converged by ~20% a
       * pass); always six passes, so that the force is a continuous function of the
       * model's parameters (a calibration differentiates it) */
      const double travel = 5e-3 * dt; /* [m] a step at 5 mm/s */
      while (fabs(target - dd) > travel) {
        dd += target > dd ? travel : -travel;
        palp_world_set_finger_device(w, fid, along(n, R + r - dd));
        palp_world_step(w);
      }
      dd = target;
      palp_world_set_finger_device(w, fid, along(n, R + r - dd));
      const int hold = (int)lround((pass < 2 ? 1.0 : 0.5) * hold_s / dt);
      for (int s = 0; s < hold; ++s) palp_world_step(w);
      palp_world_finger_local_model(w, fid, &lm);
      const double pr = sqrt(lm.proxy.x * lm.proxy.x + lm.proxy.y * lm.proxy.y + lm.proxy.z * lm.proxy.z);
      depth_real[k] = R + r - pr;
      const double miss = depth[k] - depth_real[k];
      if (pass == 5) break;
      const double slope = pass ? (depth_real[k] - prev_real) / (dd - prev_dev) : NAN;
      prev_dev = dd, prev_real = depth_real[k];
      target += slope > 0.05 && slope <= 1.0 ? miss / slope : miss;
    }
    force[k] = lm.force.x * n.x + lm.force.y * n.y + lm.force.z * n.z;
    if (!isfinite(force[k])) {
      snprintf(err, errlen, "real-time finger: no finite force at %.2f mm", depth[k] * 1e3);
      palp_world_destroy(w);
      return -1;
    }
  }
  palp_world_destroy(w);
  return count;
}

double palp_eval_finger_ref_at(const palp_eval_finger_ref *f, double d) {
  double d0 = 0.0, f0 = 0.0; /* the curve starts at the undeformed surface */
  for (int k = 0; k < f->count; ++k) {
    if (d <= f->depth[k] || k == f->count - 1) {
      const double span = f->depth[k] - d0;
      return span > 0.0 ? f0 + (f->force[k] - f0) * (d - d0) / span : f->force[k];
    }
    d0 = f->depth[k], f0 = f->force[k];
  }
  return NAN;
}

double palp_eval_finger_rms(const palp_world_def *wd, const palp_eval_finger_ref *refs, int count, double hold_s,
                            double *forces, char *err, size_t errlen) {
  double ss = 0.0;
  int m = 0;
  for (int i = 0; i < count; ++i) {
    const palp_eval_finger_ref *f = &refs[i];
    double F[PALP_EVAL_FINGER_MAX_DEPTHS], D[PALP_EVAL_FINGER_MAX_DEPTHS];
    if (palp_eval_finger_rt(wd, f->lesion, f->lesion_count, f->n, f->radius, f->depth, f->count, hold_s, F, D, err,
                            errlen) < 0)
      return NAN;
    for (int k = 0; k < f->count; ++k) {
      const double e = F[k] / palp_eval_finger_ref_at(f, D[k]) - 1.0;
      ss += e * e;
      ++m;
      if (forces) forces[i * PALP_EVAL_FINGER_MAX_DEPTHS + k] = F[k];
    }
  }
  return m ? sqrt(ss / m) : NAN;
}

int palp_eval_finger_csv_read(const char *path, const char *site, int max, double *depth, double *force, double *gap,
                              char *err, size_t errlen) {
  FILE *f = fopen(path, "r");
  if (!f) {
    snprintf(err, errlen, "cannot read %s", path);
    return -1;
  }
  char line[4096], name[64];
  int n = 0, row = 0;
  do { /* '#' lines before the header: provenance (tests/data keeps the generating command there) */
    if (!fgets(line, sizeof line, f)) line[0] = 0;
  } while (line[0] == '#');
  if (strncmp(line, "site,depth_m,fem_N,", 19) != 0) {
    snprintf(err, errlen, "%s: not a CSV of palp-fem finger (header site,depth_m,fem_N,...)", path);
    fclose(f);
    return -1;
  }
  while (fgets(line, sizeof line, f)) {
    ++row;
    double d, fe, rt, rd, ratio, g;
    if (sscanf(line, "%63[^,],%lf,%lf,%lf,%lf,%lf,%lf", name, &d, &fe, &rt, &rd, &ratio, &g) != 7) {
      snprintf(err, errlen, "%s: row %d is not a site and six numbers", path, row);
      fclose(f);
      return -1;
    }
    if (strcmp(name, site) != 0) continue;
    /* sscanf takes "inf" and "nan": an infinite force passed the calibration's force > 0 (session 81) */
    if (!isfinite(d) || !isfinite(fe) || !isfinite(rt) || !isfinite(rd) || !isfinite(ratio) || !isfinite(g)) {
      snprintf(err, errlen, "%s: row %d (site %s): a number is not finite", path, row, name);
      fclose(f);
      return -1;
    }
    /* one row per (site, depth): a second one counted twice toward "every fitted depth" and the
     * caller then said, falsely, that a depth had no row */
    for (int j = 0; j < n; ++j)
      if (fabs(depth[j] - d) < 1e-12) {
        snprintf(err, errlen, "%s: row %d: site %s at depth %g m given twice", path, row, name, d);
        fclose(f);
        return -1;
      }
    if (n == max) continue;
    depth[n] = d, force[n] = fe;
    if (gap) gap[n] = g;
    ++n;
  }
  fclose(f);
  return n;
}
