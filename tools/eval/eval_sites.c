/*
 * eval_sites.c - the run as the unit of analysis: random contact sites and force
 * levels per load distribution, each run's figures, and each distribution's
 * statistics over its runs (docs/statistics.md, "Runs over random sites").
 *
 * Why: the paper's tables come from one deterministic run per distribution at one
 * site. Its vertex-frames are repeated measures of that run (per-frame differences
 * with lag-1 autocorrelation ~0.996), so one run holds about one independent
 * observation of its bias, and a single site says nothing about the next contact.
 * Runs at random sites and forces are the independent observations; a
 * distribution's equivalence test is a t test over them.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "eval.h"
#include "palp_rng.h" /* SplitMix64: a seed names the same sites everywhere */
#include "vec3.h"

int palp_eval_sites_draw(unsigned long long seed, int count, double polar_min_deg, double polar_max_deg,
                         palp_eval_site *out) {
  if (!out || count < 1 || !(polar_min_deg >= 0.0) || !(polar_max_deg <= 90.0) || !(polar_min_deg < polar_max_deg))
    return PALP_EINVAL;
  uint64_t st = (uint64_t)seed;
  /* The area element of a sphere is sin(theta) dtheta dphi, so cos(theta) is uniform
   * over the area between the two polar angles. */
  const double c_hi = cos(polar_min_deg * PALP_PI / 180.0), c_lo = cos(polar_max_deg * PALP_PI / 180.0);
  for (int i = 0; i < count; ++i) {
    const double c = c_hi - (c_hi - c_lo) * palp_rng_uniform(&st);
    out[i].polar_deg = acos(fmin(1.0, fmax(-1.0, c))) * 180.0 / PALP_PI;
    out[i].azimuth_deg = 360.0 * palp_rng_uniform(&st);
  }
  return PALP_OK;
}

static double norm3(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

int palp_eval_record_recovery(const palp_eval_record *r, int vertex, double t_off, double *t, int *reached) {
  if (!r || !t || !reached || vertex < 0 || vertex >= r->vertex_count || r->frames < 2) return PALP_EINVAL;
  const int nv = r->vertex_count;
  double peak = 0.0;
  for (int f = 0; f < r->frames; ++f) peak = fmax(peak, norm3(r->disp[(size_t)f * (size_t)nv + (size_t)vertex]));
  *t = NAN, *reached = 0;
  if (!(peak > 0.0)) return PALP_OK;
  const double level = PALP_EVAL_RECOVERY_LEVEL * peak;
  /* the first frame after release at or below the level; the frame before it (or
   * the release itself) above it */
  double tp = t_off, up = NAN;
  for (int f = 0; f < r->frames; ++f) {
    const double tf = r->time[f], u = norm3(r->disp[(size_t)f * (size_t)nv + (size_t)vertex]);
    if (tf <= t_off) {
      tp = tf, up = u;
      continue;
    }
    if (u <= level) {
      /* linear between the previous frame and this one */
      *t = (isfinite(up) && up > u) ? tp + (tf - tp) * (up - level) / (up - u) - t_off : tf - t_off;
      *t = fmax(*t, 0.0);
      *reached = 1;
      return PALP_OK;
    }
    tp = tf, up = u;
  }
  return PALP_OK;
}

int palp_eval_run_compute(const palp_eval_pairs *p, const palp_eval_record *rt, const palp_eval_record *ref,
                          double t_off, palp_eval_run *out) {
  if (!p || !rt || !ref || !out || p->n_disp < 2 || rt->frames < 3 || p->n_disp % (size_t)rt->frames)
    return PALP_EINVAL;
  palp_eval_run *o = out;
  o->frames = rt->frames;
  palp_stats_sum s = {0, 0};
  double mx = 0.0, prt = 0.0, pref = 0.0;
  for (size_t i = 0; i < p->n_disp; ++i) {
    const double d = p->disp_rt[i] - p->disp_ref[i];
    palp_stats_sum_add(&s, d);
    mx = fmax(mx, fabs(d));
    prt = fmax(prt, p->disp_rt[i]);
    pref = fmax(pref, p->disp_ref[i]);
  }
  o->disp_bias = palp_stats_sum_value(&s) / (double)p->n_disp;
  int rc = palp_stats_rmse(p->disp_rt, p->disp_ref, p->n_disp, &o->disp_rmse);
  if (rc) return rc;
  o->disp_max_abs = mx;
  o->disp_peak_rt = prt, o->disp_peak_ref = pref;
  o->peak_error = pref > 0.0 ? (prt - pref) / pref : NAN;
  o->disp_margin = palp_eval_disp_margin(pref);
  /* n_eff of the per-frame mean difference: how much one run knows about its bias */
  const size_t nf = (size_t)rt->frames, per = p->n_disp / nf;
  double *dbar = malloc(sizeof(double) * nf);
  if (!dbar) return PALP_ENOMEM;
  for (size_t f = 0; f < nf; ++f) {
    palp_stats_sum a = {0, 0};
    for (size_t i = 0; i < per; ++i) palp_stats_sum_add(&a, p->disp_rt[f * per + i] - p->disp_ref[f * per + i]);
    dbar[f] = palp_stats_sum_value(&a) / (double)per;
  }
  if (palp_stats_autocorr1(dbar, nf, &o->disp_r1) != PALP_OK) o->disp_r1 = 0.0;
  o->disp_n_eff = palp_stats_neff_ar1(nf, o->disp_r1);
  free(dbar);
  o->has_force = p->n_force >= 2;
  if (o->has_force) {
    palp_stats_sum fs = {0, 0};
    double fp = 0.0;
    for (size_t i = 0; i < p->n_force; ++i) {
      palp_stats_sum_add(&fs, p->force_rt[i] - p->force_ref[i]);
      fp = fmax(fp, p->force_ref[i]);
    }
    o->force_bias = palp_stats_sum_value(&fs) / (double)p->n_force;
    if ((rc = palp_stats_rmse(p->force_rt, p->force_ref, p->n_force, &o->force_rmse))) return rc;
    o->force_peak_ref = fp;
    o->force_margin = PALP_EVAL_MARGIN_FORCE_REL * fp;
    if (!(o->force_margin > 0.0)) o->has_force = 0;
  }
  /* recovery where the FEM is displaced most */
  const int nv = ref->vertex_count;
  double best = -1.0;
  o->peak_vertex = ref->top_vertex;
  for (int f = 0; f < ref->frames; ++f)
    for (int i = 0; i < nv; ++i) {
      const double u = norm3(ref->disp[(size_t)f * (size_t)nv + (size_t)i]);
      if (u > best) best = u, o->peak_vertex = i;
    }
  rc = palp_eval_record_recovery(rt, o->peak_vertex, t_off, &o->recovery_rt, &o->recovered_rt);
  if (!rc) rc = palp_eval_record_recovery(ref, o->peak_vertex, t_off, &o->recovery_ref, &o->recovered_ref);
  return rc;
}

int palp_eval_sites_summarise(const double *a, const double *b, const size_t *start, int runs, int frames,
                              const double *margin, unsigned long long seed, palp_eval_sites_summary *out) {
  if (!a || !b || !start || !margin || !out || runs < 2 || runs > PALP_EVAL_SITES_MAX_RUNS || frames < 3)
    return PALP_EINVAL;
  palp_eval_sites_summary o;
  memset(&o, 0, sizeof o);
  o.runs = runs;
  o.n = start[runs] - start[0];
  o.margin = margin[0];
  for (int g = 0; g < runs; ++g) {
    const size_t ng = start[g + 1] - start[g];
    if (start[g + 1] < start[g] || ng < (size_t)frames || ng % (size_t)frames || !(margin[g] > 0.0)) return PALP_EINVAL;
    o.margin = fmin(o.margin, margin[g]);
  }
  /* the paper's literal row over every pooled vertex-frame */
  int rc = palp_eval_row_compute(a + start[0], b + start[0], o.n, &o.paper);
  if (rc) return rc;
  /* runs as units: differences by run for the repeated-measures limits and the t test
   * over run biases */
  double *diff = malloc(sizeof(double) * o.n);
  const size_t nfr = (size_t)runs * (size_t)frames;
  double *dbar = malloc(sizeof(double) * nfr);
  double *work = malloc(sizeof(double) * PALP_EVAL_BOOT_RESAMPLES);
  size_t *st = malloc(sizeof(size_t) * (size_t)(runs + 1));
  if (!diff || !dbar || !work || !st) {
    free(diff), free(dbar), free(work), free(st);
    return PALP_ENOMEM;
  }
  for (int g = 0; g <= runs; ++g) st[g] = start[g] - start[0];
  for (size_t i = 0; i < o.n; ++i) diff[i] = a[start[0] + i] - b[start[0] + i];
  rc = palp_eval_sound_pool_compute(diff, st, runs, o.margin, &o.pool);
  /* The pooled frames: each run's per-frame mean differences, joined run after run,
   * block-bootstrapped with the AR(1) block rule. A block may straddle two runs;
   * the rule's blocks are far longer than one run's correlation would need only when
   * the within-run r1 is ~1, and then the join adds little extra dependence. */
  for (int g = 0; g < runs && !rc; ++g) {
    const size_t per = (st[g + 1] - st[g]) / (size_t)frames;
    for (size_t f = 0; f < (size_t)frames; ++f) {
      palp_stats_sum s = {0, 0};
      for (size_t i = 0; i < per; ++i) palp_stats_sum_add(&s, diff[st[g] + f * per + i]);
      dbar[(size_t)g * (size_t)frames + f] = palp_stats_sum_value(&s) / (double)per;
    }
  }
  if (!rc) {
    if (palp_stats_autocorr1(dbar, nfr, &o.frames_r1) != PALP_OK) o.frames_r1 = 0.0;
    rc = palp_stats_block_bootstrap_mean(dbar, nfr, palp_stats_block_length_ar1(nfr, o.frames_r1),
                                         PALP_EVAL_BOOT_RESAMPLES, seed, 1.0 - 2.0 * PALP_EVAL_TOST_ALPHA, work,
                                         &o.boot);
  }
  free(diff), free(dbar), free(work), free(st);
  if (rc) return rc;
  o.boot_reliable = o.boot.blocks >= PALP_EVAL_BOOT_MIN_BLOCKS;
  o.boot_equivalent = o.boot_reliable && o.boot.ci_lower > -o.margin && o.boot.ci_upper < o.margin;
  *out = o;
  return PALP_OK;
}
