/*
 * eval_calibrate.c - fitting the real-time parameters to a reference with GSL's
 * nonlinear least squares.
 *
 * Unknowns x_j = ln(p_j / p_start_j) for the fitted parameters (optionally
 * bounded, ln(p_j / p_start_j) = B tanh(x_j / B), B = ln(bound_factor)): the parameters
 * stay positive whatever step the solver takes, and one finite-difference step
 * h_df in x is the same relative change (h_df = 3e-3: 0.3%) for a modulus of
 * 1e6 Pa and an exponent of 10. The step has to be that large because the model
 * makes discrete choices (a lagged-tangent rebuild when a link has turned by
 * 30 degrees, a Sherman-Morrison refresh when the volume gradient has turned by
 * 2%), so its output is only piecewise smooth: measured on the synthetic test,
 * 1e-3 steps sent the first trust-region step into the wrong valley (a stiff
 * Kelvin arm, eta2 -> 0) and 1e-2 steps stalled 2% short; 3e-3 converges.
 *
 * Residual vector r(x), all in cm-equivalents so one scale fits all:
 *   data:     100 (u_rt - u_ref) per component [cm], every vertex_stride-th free
 *             vertex at every frame_stride-th frame, for every reference;
 *   force:    force_weight (f_rt - f_ref) per component [N] at the paired contact
 *             vertices (optional);
 *   bias:     lambda_b (mean |u_rt| - mean |u_ref|) [cm] per reference over the
 *             same vertices and frames, lambda_b = bias_weight sqrt(N_data). The
 *             paper's one-way ANOVA compares exactly these means, and with some
 *             10^5 values per group it flags a mean difference of a few
 *             micrometres: least squares on components alone leaves a bias
 *             of that size without caring;
 *   prior:    lambda_p x_j, lambda_p = prior_weight sqrt(N_data): a factor e on one
 *             parameter costs as much as an RMS error of prior_weight cm over all
 *             data residuals. It only decides directions the data do not (eta1's
 *             slow flow, a2's volume damping when the gel is incompressible);
 *   peak:     lambda_k 100 (peak_rt - peak_ref) [cm] per reference, peak = the largest
 *             |u| over every vertex and frame, lambda_k = peak_weight sqrt(N_data): the
 *             issue's "peak within 10%". Least squares over all frames weighs the
 *             long hold and the recovery as much as the peak, and a model whose shape
 *             cannot follow the reference settles below it (the long-term fit of
 *             2026-11-26 had peaks 7.5-14% low; docs/materials.md);
 *   recovery: lambda_r (|t_recover - target| - band)+ / tol (signed), lambda_r =
 *             recovery_weight sqrt(N_data): the paper's "about 1 s" recovery as a
 *             soft constraint that is free inside target +- band.
 * Minimised: 0.5 |r|^2 by the trust-region method (Levenberg-Marquardt steps,
 * More's scaling), QR on the Jacobian, forward differences for the Jacobian.
 * A trial whose model blows up gets residuals of 1 m per entry, which the trust
 * region rejects like any worse step.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cjson/cJSON.h>
#include <gsl/gsl_blas.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_vector.h>

#include "eval.h"

const char *const palp_eval_param_name[PALP_EVAL_P_COUNT] = {
    "E1", "eta1", "E2", "eta2", "a1", "a2", "support_modulus", "support_viscosity", "added_mass",
    "support_bulk_fraction", "bending_stiffness", "support_relax_modulus", "support_relax_time"};
const char *const palp_eval_param_unit[PALP_EVAL_P_COUNT] = {"Pa", "Pa s", "Pa", "Pa s", "-", "Pa s/m^3", "Pa/m",
                                                              "Pa s/m", "-", "-", "N m", "Pa/m", "s"};

void palp_eval_params_get(const palp_world_def *w, double p[PALP_EVAL_P_COUNT]) {
  p[PALP_EVAL_P_E1] = w->membrane.E1;
  p[PALP_EVAL_P_ETA1] = w->membrane.eta1;
  p[PALP_EVAL_P_E2] = w->membrane.E2;
  p[PALP_EVAL_P_ETA2] = w->membrane.eta2;
  p[PALP_EVAL_P_A1] = w->gel.a1;
  p[PALP_EVAL_P_A2] = w->gel.a2;
  p[PALP_EVAL_P_SUPPORT_K] = w->gel.support_modulus;
  p[PALP_EVAL_P_SUPPORT_C] = w->gel.support_viscosity;
  p[PALP_EVAL_P_ADDED_MASS] = w->gel.added_mass_fraction;
  p[PALP_EVAL_P_BULK_FRACTION] = w->gel.support_bulk_fraction;
  p[PALP_EVAL_P_BENDING] = w->membrane.bending_stiffness;
  p[PALP_EVAL_P_RELAX_K] = w->gel.support_relax_modulus;
  p[PALP_EVAL_P_RELAX_TAU] = w->gel.support_relax_time;
}

void palp_eval_params_set(palp_world_def *w, const double p[PALP_EVAL_P_COUNT]) {
  w->membrane.E1 = p[PALP_EVAL_P_E1];
  w->membrane.eta1 = p[PALP_EVAL_P_ETA1];
  w->membrane.E2 = p[PALP_EVAL_P_E2];
  w->membrane.eta2 = p[PALP_EVAL_P_ETA2];
  w->gel.a1 = p[PALP_EVAL_P_A1];
  w->gel.a2 = p[PALP_EVAL_P_A2];
  w->gel.support_modulus = p[PALP_EVAL_P_SUPPORT_K];
  w->gel.support_viscosity = p[PALP_EVAL_P_SUPPORT_C];
  w->gel.added_mass_fraction = p[PALP_EVAL_P_ADDED_MASS];
  w->gel.support_bulk_fraction = p[PALP_EVAL_P_BULK_FRACTION];
  w->membrane.bending_stiffness = p[PALP_EVAL_P_BENDING];
  /* the skin's share of D is not fitted, but never above D (a world refuses it) */
  w->membrane.skin_bending_stiffness = fmin(w->membrane.skin_bending_stiffness, w->membrane.bending_stiffness);
  w->gel.support_relax_modulus = p[PALP_EVAL_P_RELAX_K];
  w->gel.support_relax_time = p[PALP_EVAL_P_RELAX_TAU];
}

int palp_eval_params_parse_mask(const char *list, unsigned *mask, char *err, size_t errlen) {
  if (!list || !*list) {
    snprintf(err, errlen, "--fit: empty parameter list");
    return PALP_EINVAL;
  }
  if (!strcmp(list, "all")) {
    *mask = (1u << PALP_EVAL_P_COUNT) - 1u;
    return PALP_OK;
  }
  unsigned m = 0;
  const char *s = list;
  while (*s) {
    const char *e = strchr(s, ',');
    size_t len = e ? (size_t)(e - s) : strlen(s);
    int found = -1;
    for (int j = 0; j < PALP_EVAL_P_COUNT; ++j)
      if (strlen(palp_eval_param_name[j]) == len && !strncmp(palp_eval_param_name[j], s, len)) found = j;
    if (found < 0) {
      snprintf(err, errlen,
               "--fit: unknown parameter \"%.*s\" (E1, eta1, E2, eta2, a1, a2, support_modulus, "
               "support_viscosity, added_mass, support_bulk_fraction, bending_stiffness, support_relax_modulus, "
               "support_relax_time, or all)",
               (int)len, s);
      return PALP_EINVAL;
    }
    m |= 1u << found;
    s = e ? e + 1 : s + len;
  }
  *mask = m;
  return PALP_OK;
}

/* ---- recovery ---------------------------------------------------------------- */

int palp_eval_recovery_measure(const palp_scene *base, palp_eval_recovery *out, char *err, size_t errlen) {
  palp_scene s = *base;
  const double R = s.world.mesh.radius;
  palp_profile prof = palp_profile_paper_step();
  if (s.contact_count > 0 && s.contact[0].profile.kind == PALP_PROFILE_STEP) prof = s.contact[0].profile;
  s.contact_count = 1;
  memset(&s.contact[0], 0, sizeof s.contact[0]);
  s.contact[0].def = palp_contact_default_def(PALP_DIST_UNIFORM, (palp_vec3){0, 0, R});
  s.contact[0].profile = prof;
  /* 2.5 s after release: enough to see the 5% crossing of a model that is
   * 2.5 times slower than the paper's, without wasting a calibration's time. */
  const double t_release = prof.t_off, t_end = t_release + 2.5;
  s.frames = (int)ceil(t_end / s.frame_period - 1e-9);
  s.world.effects &= ~(uint32_t)PALP_EFFECT_FORCE_FEEDBACK;
  palp_eval_record r;
  int rc = palp_eval_run_rt(&s, &r, err, errlen);
  if (rc) return rc;
  const int top = r.top_vertex, nv = r.vertex_count;
  double peak = 0.0;
  int last_loaded = -1;
  for (int f = 0; f < r.frames; ++f) {
    const palp_vec3 d = r.disp[(size_t)f * (size_t)nv + (size_t)top];
    const double u = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if (r.time[f] <= t_release + 1e-9) {
      peak = fmax(peak, u);
      last_loaded = f;
    }
  }
  palp_eval_recovery res = {.peak = peak, .t_recover = NAN, .residual_1s = NAN, .reached = 0};
  const double level = 0.05 * peak;
  double prev_u = peak, prev_t = t_release;
  if (last_loaded >= 0) {
    const palp_vec3 d = r.disp[(size_t)last_loaded * (size_t)nv + (size_t)top];
    prev_u = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    prev_t = r.time[last_loaded];
  }
  double u_last = prev_u, t_last = prev_t, u_before = prev_u, t_before = prev_t;
  for (int f = last_loaded + 1; f < r.frames; ++f) {
    const palp_vec3 d = r.disp[(size_t)f * (size_t)nv + (size_t)top];
    const double u = sqrt(d.x * d.x + d.y * d.y + d.z * d.z), t = r.time[f];
    if (isnan(res.residual_1s) && t >= t_release + 1.0 - 1e-9) {
      /* linear interpolation to exactly 1 s after release */
      const double w = (t - prev_t) > 0 ? (t_release + 1.0 - prev_t) / (t - prev_t) : 1.0;
      res.residual_1s = peak > 0 ? (prev_u + w * (u - prev_u)) / peak : 0.0;
    }
    if (!res.reached && u <= level && prev_u > level) {
      res.t_recover = prev_t + (t - prev_t) * (prev_u - level) / (prev_u - u) - t_release;
      res.reached = 1;
    }
    u_before = u_last, t_before = t_last;
    u_last = u, t_last = t;
    prev_u = u, prev_t = t;
  }
  if (!res.reached && peak > 0) {
    /* Not back within the run: extrapolate the last frames' exponential decay
     * (continuous in the parameters, so the fit's penalty still has a slope). */
    double rate = (u_before > u_last && u_last > 0 && t_last > t_before) ? log(u_before / u_last) / (t_last - t_before)
                                                                           : 0.0;
    res.t_recover = rate > 0 ? (t_last - t_release) + log(u_last / level) / rate : 10.0 * (t_end - t_release);
  }
  res.t_recover = fmin(res.t_recover, 10.0 * (t_end - t_release));
  palp_eval_record_destroy(&r);
  *out = res;
  return PALP_OK;
}

/* ---- calibration ----------------------------------------------------------------- */

typedef struct fit_ws {
  const palp_scene *scenes;
  const palp_eval_record *refs;
  int count;
  const palp_eval_calib_def *def;
  double start[PALP_EVAL_P_COUNT];
  int idx[PALP_EVAL_P_COUNT]; /* fitted parameter of each unknown */
  int np;
  int *sel_vertex; /* selected free vertices */
  int nsel;

  size_t n_data;     /* data and force residuals */
  size_t n_finger;   /* finger residuals (sites x depths) */
  double lambda_finger;
  size_t n_force_expected;
  double lambda_prior, lambda_rec, lambda_bias, lambda_peak;
  double ref_peak[4]; /* record_peak of each reference, once [m] */
  int with_recovery;
  int evaluations;
  int verbose;
  char err[256];
} fit_ws;

/* ln(p / p_start) of the solver's unknown j: the identity, or a tanh that is the
 * identity's tangent at the start and never leaves [lo, hi]: lo = -B, hi = B with
 * B = ln(bound_factor), except that hi is ln(p_max / p_start) for a parameter with
 * a physical ceiling (the added gel mass cannot exceed the whole gel, fraction 1).
 *   y(x) = m + r tanh((x + x0) / r),  m = (hi + lo) / 2, r = (hi - lo) / 2,
 *   x0 = r atanh(-m / r), so that y(0) = 0. */
static const double param_max[PALP_EVAL_P_COUNT] = {0, 0, 0, 0, 0, 0, 0, 0, 1.0, 1.0, 0}; /* 0: none */

static double log_ratio(const fit_ws *ws, int j, double x) {
  const double b = ws->def->bound_factor;
  const double B = b > 1.0 ? log(b) : INFINITY;
  const double lo = -B, hi = param_max[j] > 0 ? fmin(B, log(param_max[j] / ws->start[j])) : B;
  if (!isfinite(lo) && !isfinite(hi)) return x;
  if (!isfinite(lo)) return hi - log1p(exp(log(expm1(hi)) - x)); /* softplus ceiling, y(0) = 0 */
  const double m = 0.5 * (hi + lo), r = 0.5 * (hi - lo);
  return m + r * tanh((x + r * atanh(-m / r)) / r);
}

static void params_of_x(const fit_ws *ws, const gsl_vector *x, double p[PALP_EVAL_P_COUNT]) {
  memcpy(p, ws->start, sizeof ws->start);
  for (int j = 0; j < ws->np; ++j)
    p[ws->idx[j]] = ws->start[ws->idx[j]] * exp(log_ratio(ws, ws->idx[j], gsl_vector_get(x, (size_t)j)));
}

static size_t force_pairs(const palp_eval_record *ref, const palp_scene *s) {
  (void)s;
  return (size_t)ref->contact_vertex_count;
}

/* The largest displacement magnitude of a record over every vertex and frame [m]. */
static double record_peak(const palp_eval_record *r) {
  double m2 = 0.0;
  const size_t n = (size_t)r->frames * (size_t)r->vertex_count;
  for (size_t i = 0; i < n; ++i) {
    const palp_vec3 u = r->disp[i];
    const double d2 = u.x * u.x + u.y * u.y + u.z * u.z;
    if (d2 > m2) m2 = d2;
  }
  return sqrt(m2);
}

/* Fills the data and force residuals of one reference; returns 0 or an error. */
static int residuals_one(fit_ws *ws, int i, const double p[PALP_EVAL_P_COUNT], double *r, size_t *k) {
  palp_scene s = ws->scenes[i];
  palp_eval_params_set(&s.world, p);
  const palp_eval_record *ref = &ws->refs[i];
  palp_eval_record rt;
  int rc = palp_eval_run_rt(&s, &rt, ws->err, sizeof ws->err);
  if (rc) return rc;
  if (rt.frames != ref->frames || rt.vertex_count != ref->vertex_count) {
    palp_eval_record_destroy(&rt);
    snprintf(ws->err, sizeof ws->err, "reference %d has %d frames x %d vertices, the model %d x %d", i,
             ref->frames, ref->vertex_count, rt.frames, rt.vertex_count);
    return PALP_EINVAL;
  }
  const int nv = rt.vertex_count, stride = ws->def->frame_stride;
  palp_stats_sum sum_a = {0, 0}, sum_b = {0, 0};
  size_t count = 0;
  for (int f = stride - 1; f < rt.frames; f += stride) {
    const palp_vec3 *a = rt.disp + (size_t)f * (size_t)nv, *b = ref->disp + (size_t)f * (size_t)nv;
    for (int q = 0; q < ws->nsel; ++q) {
      const int v = ws->sel_vertex[q];
      r[(*k)++] = 100.0 * (a[v].x - b[v].x);
      r[(*k)++] = 100.0 * (a[v].y - b[v].y);
      r[(*k)++] = 100.0 * (a[v].z - b[v].z);
      palp_stats_sum_add(&sum_a, sqrt(a[v].x * a[v].x + a[v].y * a[v].y + a[v].z * a[v].z));
      palp_stats_sum_add(&sum_b, sqrt(b[v].x * b[v].x + b[v].y * b[v].y + b[v].z * b[v].z));
      ++count;
    }
  }
  if (ws->lambda_bias > 0)
    r[(*k)++] = ws->lambda_bias * 100.0 *
                (palp_stats_sum_value(&sum_a) - palp_stats_sum_value(&sum_b)) / (double)(count ? count : 1);
  if (ws->lambda_peak > 0) r[(*k)++] = ws->lambda_peak * 100.0 * (record_peak(&rt) - ws->ref_peak[i]);
  if (ws->def->force_weight > 0) {
    const double wgt = ws->def->force_weight;
    for (int f = stride - 1; f < rt.frames; f += stride)
      for (int j = 0; j < ref->contact_vertex_count; ++j) {
        int m = -1;
        for (int q = 0; q < rt.contact_vertex_count; ++q)
          if (rt.contact_vertex[q] == ref->contact_vertex[j] && rt.contact_of[q] == ref->contact_of[j]) m = q;
        const palp_vec3 fr = ref->feedback[(size_t)f * (size_t)ref->contact_vertex_count + (size_t)j];
        const palp_vec3 fa = m >= 0 ? rt.feedback[(size_t)f * (size_t)rt.contact_vertex_count + (size_t)m]
                                    : (palp_vec3){0, 0, 0};
        r[(*k)++] = wgt * (fa.x - fr.x);
        r[(*k)++] = wgt * (fa.y - fr.y);
        r[(*k)++] = wgt * (fa.z - fr.z);
      }
  }
  palp_eval_record_destroy(&rt);
  return PALP_OK;
}

static int fit_f(const gsl_vector *x, void *ud, gsl_vector *fvec) {
  fit_ws *ws = ud;
  double p[PALP_EVAL_P_COUNT];
  params_of_x(ws, x, p);
  ws->evaluations++;
  const size_t n = fvec->size;
  double *r = malloc(sizeof(double) * n);
  if (!r) return GSL_ENOMEM;
  size_t k = 0;
  int rc = 0;
  for (int i = 0; !rc && i < ws->count; ++i) rc = residuals_one(ws, i, p, r, &k);
  if (!rc && ws->with_recovery) {
    palp_eval_recovery rec;
    palp_scene s = ws->scenes[0];
    palp_eval_params_set(&s.world, p);
    rc = palp_eval_recovery_measure(&s, &rec, ws->err, sizeof ws->err);
    if (!rc) {
      const double dev = rec.t_recover - ws->def->recovery_target, out = fabs(dev) - ws->def->recovery_band;
      r[k++] = out > 0 ? ws->lambda_rec * copysign(out, dev) / ws->def->recovery_tol : 0.0;
    }
  }
  if (!rc && ws->n_finger) {
    /* the fingertip at each site and depth, relative force error */
    palp_world_def wd = ws->scenes[0].world;
    palp_eval_params_set(&wd, p);
    for (int i = 0; !rc && i < ws->def->finger_count; ++i) {
      const palp_eval_finger_ref *f = &ws->def->finger[i];
      double F[PALP_EVAL_FINGER_MAX_DEPTHS], D[PALP_EVAL_FINGER_MAX_DEPTHS];
      if (palp_eval_finger_rt(&wd, f->lesion, f->lesion_count, f->n, f->radius, f->depth, f->count,
                              ws->def->finger_hold_s, F, D, ws->err, sizeof ws->err) < 0)
        rc = PALP_EUNSTABLE;
      else
        for (int d = 0; d < f->count; ++d)
          r[k++] = ws->lambda_finger * (F[d] / palp_eval_finger_ref_at(f, D[d]) - 1.0);
    }
  }
  if (rc == PALP_EUNSTABLE || rc == PALP_ESOLVER || rc == PALP_EINVAL) {
    /* A trial the model cannot run: a residual of 1 m everywhere, worse than any
     * real fit, so the trust region shrinks and tries a shorter step. */
    if (ws->verbose) fprintf(stderr, "calibrate: trial rejected (%s)\n", ws->err);
    for (size_t i = 0; i < n; ++i) gsl_vector_set(fvec, i, 100.0);
    free(r);
    return GSL_SUCCESS;
  }
  if (rc) {
    free(r);
    return GSL_EFAILED;
  }
  for (int j = 0; j < ws->np; ++j) r[k++] = ws->lambda_prior * gsl_vector_get(x, (size_t)j);
  if (k != n) {
    snprintf(ws->err, sizeof ws->err, "internal: %zu residuals filled, %zu expected", k, n);
    free(r);
    return GSL_EBADLEN;
  }
  for (size_t i = 0; i < n; ++i) gsl_vector_set(fvec, i, r[i]);
  free(r);
  return GSL_SUCCESS;
}

static void fit_callback(const size_t iter, void *ud, const gsl_multifit_nlinear_workspace *w) {
  fit_ws *ws = ud;
  if (!ws->verbose) return;
  const gsl_vector *f = gsl_multifit_nlinear_residual(w), *x = gsl_multifit_nlinear_position(w);
  double chi = gsl_blas_dnrm2(f);
  fprintf(stderr, "calibrate: iteration %2zu  |r| %.6g  (evaluations %d)  ", iter, chi, ws->evaluations);
  for (int j = 0; j < ws->np; ++j)
    fprintf(stderr, " %s=%.4g", palp_eval_param_name[ws->idx[j]],
            ws->start[ws->idx[j]] * exp(log_ratio(ws, ws->idx[j], gsl_vector_get(x, (size_t)j))));
  fprintf(stderr, "\n");
}

palp_eval_calib_def palp_eval_calib_default_def(void) {
  palp_eval_calib_def d;
  memset(&d, 0, sizeof d);
  /* a1 is held: it sets the gel's bulk modulus a1 P, the FEM gel is nearly
   * incompressible (K = 2 GPa), and a1 P = 1 MPa already keeps the volume within
   * 0.15%; freed, the fit traded volume conservation for RMSE (a1 -> 0.37,
   * 2.7% volume loss under 3 N). "--fit all" frees it. */
  d.mask = ((1u << PALP_EVAL_P_COUNT) - 1u) & ~(1u << PALP_EVAL_P_A1);
  d.frame_stride = 2;
  d.vertex_stride = 1;
  d.force_weight = 0.0;
  d.bias_weight = 0.0;
  d.peak_weight = 0.0;
  d.prior_weight = 1e-3;
  d.recovery_weight = 0.0;
  d.recovery_target = 1.0;
  d.recovery_tol = 0.1;
  d.recovery_band = 0.2;
  d.bound_factor = 100.0;
  d.max_iter = 40;
  d.h_df = 3e-3;
  d.finger_weight = 0.0;
  d.finger_hold_s = 0.3;
  return d;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* RMSE of the displacement magnitude (Table V's data set) of each reference. */
static int rmse_all(const palp_scene *scenes, const palp_eval_record *refs, int count, const double *p, double *rmse,
                    double *peak, char *err, size_t errlen) {
  for (int i = 0; i < count; ++i) {
    palp_scene s = scenes[i];
    palp_eval_params_set(&s.world, p);
    palp_eval_record rt;
    int rc = palp_eval_run_rt(&s, &rt, err, errlen);
    if (rc) return rc;
    palp_eval_pairs pr;
    rc = palp_eval_pairs_build(&rt, &refs[i], &pr, err, errlen);
    if (!rc) rc = palp_stats_rmse(pr.disp_rt, pr.disp_ref, pr.n_disp, &rmse[i]);
    peak[i] = record_peak(&rt);
    palp_eval_pairs_destroy(&pr);
    palp_eval_record_destroy(&rt);
    if (rc) return rc;
  }
  return PALP_OK;
}

int palp_eval_calibrate(const palp_scene *scenes, const palp_eval_record *refs, int count,
                        const palp_eval_calib_def *def, palp_eval_calib_result *out, char *err, size_t errlen) {
  const double t0 = now_s();
  if (count < 1 || count > 4) {
    snprintf(err, errlen, "calibrate: 1 to 4 references expected, got %d", count);
    return PALP_EINVAL;
  }
  if (def->frame_stride < 1 || def->vertex_stride < 1 || !(def->h_df > 0) || def->max_iter < 1 ||
      !(def->prior_weight >= 0) || !(def->bias_weight >= 0) || !(def->force_weight >= 0) || !(def->recovery_weight >= 0) ||
      !(def->peak_weight >= 0) ||
      !(def->recovery_tol > 0) || !(def->recovery_band >= 0)) {
    snprintf(err, errlen, "calibrate: strides and iterations must be >= 1, h_df and recovery_tol > 0, weights >= 0");
    return PALP_EINVAL;
  }
  fit_ws ws;
  memset(&ws, 0, sizeof ws);
  ws.scenes = scenes;
  ws.refs = refs;
  ws.count = count;
  ws.def = def;
  ws.verbose = def->verbose;
  palp_eval_params_get(&scenes[0].world, ws.start);
  /* A model without added gel mass (fraction 0) cannot be left in log space, and
   * one at the ceiling (the whole gel, 1) has no room inside it: the fit starts
   * such a mass from half the gel's. */
  if ((def->mask & (1u << PALP_EVAL_P_ADDED_MASS)) &&
      !(ws.start[PALP_EVAL_P_ADDED_MASS] > 0.0 && ws.start[PALP_EVAL_P_ADDED_MASS] < 0.99))
    ws.start[PALP_EVAL_P_ADDED_MASS] = 0.5;
  /* The support's bulk fraction likewise lives in (0, 1]. */
  if ((def->mask & (1u << PALP_EVAL_P_BULK_FRACTION)) &&
      !(ws.start[PALP_EVAL_P_BULK_FRACTION] > 0.0 && ws.start[PALP_EVAL_P_BULK_FRACTION] < 0.99))
    ws.start[PALP_EVAL_P_BULK_FRACTION] = 0.5;
  /* A membrane without bending (the paper's) stays without: bending is fitted only
   * from a start > 0, i.e. when the scene's parameters have it. */
  unsigned mask = def->mask;
  if (!(ws.start[PALP_EVAL_P_BENDING] > 0.0)) mask &= ~(1u << PALP_EVAL_P_BENDING);
  if (!(ws.start[PALP_EVAL_P_RELAX_K] > 0.0)) mask &= ~((1u << PALP_EVAL_P_RELAX_K) | (1u << PALP_EVAL_P_RELAX_TAU));
  for (int j = 0; j < PALP_EVAL_P_COUNT; ++j) {
    if (!(mask & (1u << j))) continue; /* held parameters may be 0 */
    if (!(ws.start[j] > 0) || !isfinite(ws.start[j])) {
      snprintf(err, errlen, "calibrate: start value of %s is %g; parameters must be positive to fit in log space",
               palp_eval_param_name[j], ws.start[j]);
      return PALP_EINVAL;
    }
    ws.idx[ws.np++] = j;
  }
  if (ws.np == 0) {
    snprintf(err, errlen, "calibrate: no parameter to fit");
    return PALP_EINVAL;
  }
  const palp_eval_record *r0 = &refs[0];
  for (int i = 0; i < count; ++i)
    if (refs[i].vertex_count != r0->vertex_count || refs[i].frames != scenes[i].frames) {
      snprintf(err, errlen, "calibrate: reference %d does not match its scene (%d frames, scene %d)", i,
               refs[i].frames, scenes[i].frames);
      return PALP_EINVAL;
    }
  ws.sel_vertex = malloc(sizeof(int) * (size_t)r0->vertex_count);
  if (!ws.sel_vertex) return PALP_ENOMEM;
  for (int v = 0, q = 0; v < r0->vertex_count; ++v)
    if (!r0->fixed[v] && (q++ % def->vertex_stride) == 0) ws.sel_vertex[ws.nsel++] = v;
  size_t n_data = 0;
  for (int i = 0; i < count; ++i) {
    const size_t frames_used = (size_t)(refs[i].frames / def->frame_stride);
    n_data += frames_used * (size_t)ws.nsel * 3;
    if (def->force_weight > 0) n_data += frames_used * force_pairs(&refs[i], &scenes[i]) * 3;
  }
  ws.n_data = n_data;
  ws.lambda_prior = def->prior_weight * sqrt((double)n_data);
  ws.lambda_rec = def->recovery_weight * sqrt((double)n_data);
  ws.lambda_bias = def->bias_weight * sqrt((double)n_data);
  ws.lambda_peak = def->peak_weight * sqrt((double)n_data);
  ws.with_recovery = def->recovery_weight > 0;
  if (def->finger_weight > 0 && def->finger_count > 0) {
    for (int i = 0; i < def->finger_count; ++i) {
      const palp_eval_finger_ref *f = &def->finger[i];
      int ok = f->count >= 1 && f->count <= PALP_EVAL_FINGER_MAX_DEPTHS && f->radius > 0;
      for (int d = 0; ok && d < f->count; ++d) ok = f->force[d] > 0 && f->depth[d] > 0;
      if (!ok) {
        snprintf(err, errlen, "calibrate: finger reference %d (%s) needs 1-%d depths > 0 with forces > 0", i,
                 f->name ? f->name : "?", PALP_EVAL_FINGER_MAX_DEPTHS);
        free(ws.sel_vertex);
        return PALP_EINVAL;
      }
      ws.n_finger += (size_t)f->count;
    }
    if (!(def->finger_hold_s > 0)) {
      snprintf(err, errlen, "calibrate: finger_hold_s must be > 0");
      free(ws.sel_vertex);
      return PALP_EINVAL;
    }
    ws.lambda_finger = def->finger_weight * sqrt((double)n_data / (double)ws.n_finger);
  }
  const size_t n = n_data + (ws.lambda_bias > 0 ? (size_t)count : 0) + (ws.lambda_peak > 0 ? (size_t)count : 0) +
                   (size_t)ws.with_recovery + ws.n_finger +
                   (size_t)ws.np,
               np = (size_t)ws.np;

  palp_eval_calib_result res;
  memset(&res, 0, sizeof res);
  memcpy(res.start, ws.start, sizeof ws.start);
  for (int i = 0; i < count; ++i) res.peak_ref[i] = ws.ref_peak[i] = record_peak(&refs[i]);
  int rc = rmse_all(scenes, refs, count, ws.start, res.rmse_before, res.peak_before, err, errlen);
  if (!rc) rc = palp_eval_recovery_measure(&scenes[0], &res.recovery_before, err, errlen);
  res.finger_rms_before = res.finger_rms_after = NAN;
  if (!rc && ws.n_finger) {
    res.finger_rms_before =
        palp_eval_finger_rms(&scenes[0].world, def->finger, def->finger_count, def->finger_hold_s, NULL, err, errlen);
    if (isnan(res.finger_rms_before)) rc = PALP_EINVAL;
  }
  if (rc) {
    free(ws.sel_vertex);
    return rc;
  }

  gsl_multifit_nlinear_fdf fdf;
  memset(&fdf, 0, sizeof fdf);
  fdf.f = fit_f;
  fdf.df = NULL; /* forward differences */
  fdf.fvv = NULL;
  fdf.n = n;
  fdf.p = np;
  fdf.params = &ws;
  gsl_multifit_nlinear_parameters fp = gsl_multifit_nlinear_default_parameters();
  fp.trs = gsl_multifit_nlinear_trs_lm;
  fp.scale = gsl_multifit_nlinear_scale_more;
  fp.solver = gsl_multifit_nlinear_solver_qr;
  fp.fdtype = GSL_MULTIFIT_NLINEAR_FWDIFF;
  fp.h_df = def->h_df;
  gsl_multifit_nlinear_workspace *w = gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &fp, n, np);
  gsl_vector *x = gsl_vector_calloc(np);
  if (!w || !x) {
    if (w) gsl_multifit_nlinear_free(w);
    gsl_vector_free(x);
    free(ws.sel_vertex);
    snprintf(err, errlen, "calibrate: cannot allocate the solver for %zu residuals x %zu unknowns", n, np);
    return PALP_ENOMEM;
  }
  int gs = gsl_multifit_nlinear_init(x, &fdf, w);
  if (gs) {
    snprintf(err, errlen, "calibrate: initial evaluation failed: %s%s%s", gsl_strerror(gs), ws.err[0] ? ": " : "",
             ws.err);
    gsl_multifit_nlinear_free(w);
    gsl_vector_free(x);
    free(ws.sel_vertex);
    return PALP_EINVAL;
  }
  {
    const gsl_vector *f = gsl_multifit_nlinear_residual(w);
    double c = gsl_blas_dnrm2(f);
    res.cost_before = 0.5 * c * c;
  }
  /* gsl_multifit_nlinear_driver's loop, plus a wall-clock budget: a model run
   * gets slower as the fit softens the phantom, and a calibration should end
   * when its user said it should. */
  int info = 0;
  gs = GSL_EMAXITER;
  for (int it = 0; it < def->max_iter; ++it) {
    int st = gsl_multifit_nlinear_iterate(w);
    fit_callback((size_t)(it + 1), &ws, w);
    if (st == GSL_ENOPROG) {
      gs = GSL_ENOPROG; /* no step lowers the cost: a (local) minimum at the model's smoothness */
      break;
    }
    if (st) {
      gs = st;
      break;
    }
    if (gsl_multifit_nlinear_test(1e-5, 1e-8, 1e-10, &info, w) == GSL_SUCCESS) {
      gs = GSL_SUCCESS;
      break;
    }
    if (def->max_seconds > 0 && now_s() - t0 > def->max_seconds) {
      gs = PALP_EVAL_FIT_TIMEOUT;
      info = 0;
      break;
    }
  }
  res.status = gs;
  res.reason = info;
  res.iterations = (int)gsl_multifit_nlinear_niter(w);
  if (gs && gs != GSL_EMAXITER && gs != GSL_ENOPROG && gs != PALP_EVAL_FIT_TIMEOUT) {
    snprintf(err, errlen, "calibrate: the solver stopped: %s%s%s", gsl_strerror(gs), ws.err[0] ? ": " : "",
             ws.err);
    gsl_multifit_nlinear_free(w);
    gsl_vector_free(x);
    free(ws.sel_vertex);
    return PALP_EINVAL;
  }
  {
    const gsl_vector *f = gsl_multifit_nlinear_residual(w);
    double c = gsl_blas_dnrm2(f);
    res.cost_after = 0.5 * c * c;
  }
  params_of_x(&ws, gsl_multifit_nlinear_position(w), res.fitted);
  res.evaluations = ws.evaluations;
  res.recovery_penalised = ws.with_recovery;
  gsl_multifit_nlinear_free(w);
  gsl_vector_free(x);
  free(ws.sel_vertex);
  rc = rmse_all(scenes, refs, count, res.fitted, res.rmse_after, res.peak_after, err, errlen);
  if (!rc) {
    palp_scene s = scenes[0];
    palp_eval_params_set(&s.world, res.fitted);
    rc = palp_eval_recovery_measure(&s, &res.recovery_after, err, errlen);
    if (!rc && ws.n_finger) {
      res.finger_rms_after =
          palp_eval_finger_rms(&s.world, def->finger, def->finger_count, def->finger_hold_s, NULL, err, errlen);
      if (isnan(res.finger_rms_after)) rc = PALP_EINVAL;
    }
  }
  if (rc) return rc;
  res.seconds = now_s() - t0;
  *out = res;
  return PALP_OK;
}

const char *palp_eval_fit_status_text(int status) {
  switch (status) {
  case GSL_SUCCESS: return "converged (step, gradient or cost change below tolerance)";
  case GSL_EMAXITER: return "iteration limit reached";
  case GSL_ENOPROG: return "no further step lowers the cost";
  case PALP_EVAL_FIT_TIMEOUT: return "time budget ran out (best point so far kept)";
  default: return gsl_strerror(status);
  }
}

/* ---- parameter file ---------------------------------------------------------------- */

int palp_eval_params_write(const char *path, const palp_world_def *w, const char *material, const char *comment,
                           char *err, size_t errlen) {
  char tmp[1100];
  snprintf(tmp, sizeof tmp, "%s.tmp", path);
  FILE *f = fopen(tmp, "w");
  if (!f) {
    snprintf(err, errlen, "cannot write %s", tmp);
    return PALP_EIO;
  }
  /* The comment goes through cJSON so any text is a valid JSON string. */
  cJSON *c = cJSON_CreateString(comment ? comment : "");
  char *cs = c ? cJSON_PrintUnformatted(c) : NULL;
  const palp_membrane_params *m = &w->membrane;
  const palp_gel_params *g = &w->gel;
  fprintf(f, "{\n  \"comment\": %s,\n", cs ? cs : "\"\"");
  /* names come from palp_fem_material_names(): identifiers, no escaping needed */
  if (material && material[0]) fprintf(f, "  \"material\": \"%s\",\n", material);
  fprintf(f,
          "  \"membrane\": { \"thickness_m\": %.9g, \"density_kg_m3\": %.9g,\n"
          "                \"E1_Pa\": %.9g, \"eta1_Pa_s\": %.9g, \"E2_Pa\": %.9g, \"eta2_Pa_s\": %.9g",
          m->thickness, m->density, m->E1, m->eta1, m->E2, m->eta2);
  if (m->bending_stiffness > 0.0) fprintf(f, ",\n                \"bending_stiffness_N_m\": %.9g", m->bending_stiffness);
  if (m->rim_hinge_release > 0.0) fprintf(f, ",\n                \"rim_hinge_release\": %.9g", m->rim_hinge_release);
  /* Carried over, not fitted: the skin's own plate stiffness comes from its material (a
   * fit that took D below it has D_skin = D: every hinge the skin's, none seeing a lesion). */
  if (m->skin_bending_stiffness > 0.0)
    fprintf(f, ",\n                \"skin_bending_stiffness_N_m\": %.9g", m->skin_bending_stiffness);
  fprintf(f, " },\n");
  fprintf(f,
          "  \"gel\": { \"law\": \"%s\", \"pressure_Pa\": %.9g, \"a1\": %.9g, \"a2_Pa_s_m3\": %.9g, \"a3_s2\": %.9g,\n"
          "           \"support_modulus_Pa_m\": %.9g, \"support_viscosity_Pa_s_m\": %.9g,\n"
          "           \"support_bulk_fraction\": %.9g,\n",
          g->law == PALP_GEL_PAPER_LITERAL ? "paper_literal" : "polytropic", g->pressure, g->a1, g->a2, g->a3,
          g->support_modulus, g->support_viscosity, g->support_bulk_fraction);
  if (g->support_relax_modulus > 0.0)
    fprintf(f, "           \"support_relax_modulus_Pa_m\": %.9g, \"support_relax_time_s\": %.9g,\n",
            g->support_relax_modulus, g->support_relax_time);
  /* Not fitted, carried over: the stiffening support is the model's form (a set without it
   * is another model). The "validated" table is not: a new fit has not been validated. */
  if (g->support_stiffening > 0.0)
    fprintf(f, "           \"support_stiffening\": %.9g, \"support_stiffening_power\": %.9g,\n",
            g->support_stiffening, g->support_stiffening_power);
  if (g->support_base_reach > 0.0) /* the same: the base's cut of the column is the model's form */
    fprintf(f, "           \"support_base_reach\": %.9g,\n", g->support_base_reach);
  fprintf(f, "           \"density_kg_m3\": %.9g, \"added_mass_fraction\": %.9g }\n}\n", g->density,
          g->added_mass_fraction);
  free(cs);
  cJSON_Delete(c);
  int bad = ferror(f);
  bad |= fclose(f) != 0;
  if (bad || rename(tmp, path) != 0) {
    remove(tmp);
    snprintf(err, errlen, "cannot write %s", path);
    return PALP_EIO;
  }
  return PALP_OK;
}
