/*
 * stats.c - RMSE, one-way ANOVA and Bland-Altman agreement (see stats.h and
 * docs/statistics.md for the formulas and the numerical method).
 *
 * Why the care: the evaluation compares vertex displacements of two models that
 * agree to a few micrometres on values of centimetres, and users feed in phantom
 * measurements with many constant leading digits. The textbook one-pass formula
 * SS = sum x^2 - (sum x)^2 / n then cancels catastrophically (NIST SmLs09 loses
 * every digit). Here every sum is
 *   1. taken about a shift c = one of the data values (the group's first one
 *      inside a group), so x - c is exact by
 *      Sterbenz' lemma whenever x and c are within a factor of two (the
 *      ill-conditioned case) and the magnitudes summed are the spreads, not the
 *      levels;
 *   2. split in two passes: means first (refined once by the mean residual),
 *      then squared deviations from them;
 *   3. accumulated with Neumaier compensation, so long sums (18009 values in
 *      SmLs09, 400 frames x 338 vertices in the evaluation) do not drift.
 */
#include "stats.h"

#include <math.h>

#include <gsl/gsl_cdf.h>

/* Mean of (x - c) over x[0..n), in two compensated passes. */
static double shifted_mean(const double *x, size_t n, double c) {
  palp_stats_sum s = {0.0, 0.0};
  for (size_t i = 0; i < n; ++i) palp_stats_sum_add(&s, x[i] - c);
  double m = palp_stats_sum_value(&s) / (double)n;
  /* One refinement: the mean of the residuals corrects the rounding of m itself
   * (a constant group then gets its mean exactly and a within-SS of exactly 0). */
  palp_stats_sum r = {0.0, 0.0};
  for (size_t i = 0; i < n; ++i) palp_stats_sum_add(&r, (x[i] - c) - m);
  return m + palp_stats_sum_value(&r) / (double)n;
}

/* A sum of squares held scaled, as LAPACK's dlassq does: value = scale^2 * ssq,
 * scale = the largest |term| (data units), ssq = sum (term / scale)^2 in [1, n]
 * (dimensionless; 0 with scale 0 when every term is 0). Squaring the terms
 * unscaled overflows to inf above ~1.3e154 (the compensated sum then turns it
 * into NaN) and vanishes below ~1.5e-154; scaled, the ratios F and R^2 stay exact
 * at any magnitude a double holds. */
typedef struct ssq {
  double scale, ssq;
} ssq;

/* Fold w * t^2 (w >= 0 a count, t a deviation in data units) into acc, given
 * acc->scale >= |t| already (the caller found the maximum first). */
static void ssq_add(ssq *acc, palp_stats_sum *sum, double w, double t) {
  if (acc->scale > 0.0) {
    double r = t / acc->scale;
    palp_stats_sum_add(sum, w * r * r);
  }
}

/* The value scale^2 * ssq; +inf when beyond DBL_MAX, 0 or subnormal below DBL_MIN. */
static double ssq_value(ssq q) { return q.scale * q.scale * q.ssq; }

/* Merge b into a: both rescaled to the larger scale (ssq_a (s_a/S)^2 + ssq_b (s_b/S)^2). */
static ssq ssq_merge(ssq a, ssq b) {
  double big = a.scale > b.scale ? a.scale : b.scale;
  if (big == 0.0) return (ssq){0.0, 0.0};
  double ra = a.scale / big, rb = b.scale / big;
  palp_stats_sum s = {0.0, 0.0};
  palp_stats_sum_add(&s, a.ssq * ra * ra);
  palp_stats_sum_add(&s, b.ssq * rb * rb);
  return (ssq){big, palp_stats_sum_value(&s)};
}

/* sum_i ((x_i - c) - m)^2, scaled and compensated; m is a mean of x - c. */
static ssq shifted_ssq(const double *x, size_t n, double c, double m) {
  ssq q = {0.0, 0.0};
  for (size_t i = 0; i < n; ++i) {
    double e = fabs((x[i] - c) - m);
    if (!(e <= q.scale)) q.scale = e; /* a NaN (x - c beyond DBL_MAX) propagates */
  }
  palp_stats_sum s = {0.0, 0.0};
  for (size_t i = 0; i < n; ++i) ssq_add(&q, &s, 1.0, (x[i] - c) - m);
  q.ssq = palp_stats_sum_value(&s);
  return q;
}

static int all_finite(const double *x, size_t n) {
  for (size_t i = 0; i < n; ++i)
    if (!isfinite(x[i])) return 0;
  return 1;
}

void palp_stats_mean_ssd(const double *x, size_t n, double *mean, double *ssd) {
  if (n == 0) {
    *mean = NAN;
    *ssd = NAN;
    return;
  }
  double c = x[0];
  double m = shifted_mean(x, n, c);
  *mean = c + m;
  *ssd = ssq_value(shifted_ssq(x, n, c, m));
}

void palp_stats_mean_sd(const double *x, size_t n, double *mean, double *sd) {
  if (n < 2) {
    palp_stats_mean_ssd(x, n, mean, sd);
    *sd = NAN;
    return;
  }
  double c = x[0];
  double m = shifted_mean(x, n, c);
  *mean = c + m;
  ssq q = shifted_ssq(x, n, c, m);
  *sd = q.scale * sqrt(q.ssq / (double)(n - 1)); /* data units; never squared unscaled */
}

/* ---- RMSE ------------------------------------------------------------------ */

/* RMSE = sqrt( sum (a_i - b_i)^2 / n ), evaluated as s sqrt( sum (d_i/s)^2 / n )
 * with s = max |d_i| so that squares of differences near 1e200 or 1e-200 neither
 * overflow nor vanish. When a - b itself overflows (opposite signs near DBL_MAX),
 * the halves a/2 - b/2 are used and the result doubled. */
int palp_stats_rmse(const double *a, const double *b, size_t n, double *out) {
  if (!a || !b || !out || n == 0) return PALP_EINVAL;
  if (!all_finite(a, n) || !all_finite(b, n)) return PALP_EINVAL;
  double half = 1.0;
  double scale = 0.0;
  for (size_t i = 0; i < n; ++i) {
    double d = fabs(a[i] - b[i]);
    if (isinf(d)) half = 0.5;
    if (d > scale) scale = d;
  }
  if (half != 1.0) {
    scale = 0.0;
    for (size_t i = 0; i < n; ++i) {
      double d = fabs(a[i] * half - b[i] * half);
      if (d > scale) scale = d;
    }
  }
  if (scale == 0.0) {
    *out = 0.0;
    return PALP_OK;
  }
  palp_stats_sum s = {0.0, 0.0};
  for (size_t i = 0; i < n; ++i) {
    double d = (a[i] * half - b[i] * half) / scale;
    palp_stats_sum_add(&s, d * d);
  }
  *out = scale * sqrt(palp_stats_sum_value(&s) / (double)n) / half;
  return PALP_OK;
}

/* ---- one-way ANOVA ------------------------------------------------------------ */

/* df, mean squares, F, p and the degenerate cases from the scaled sums of squares
 * (SS = scale^2 ssq, data units squared). F and R^2 are formed from the scaled
 * parts, so they are exact even when an SS itself is beyond DBL_MAX:
 *   F   = (SS_b / df_b) / (SS_w / df_w) = (s_b / s_w)^2 (ssq_b df_w) / (ssq_w df_b)
 *   R^2 = SS_b / (SS_b + SS_w)          = 1 / (1 + (s_w / s_b)^2 ssq_w / ssq_b)
 * Returns PALP_EINVAL when a sum is not finite (a deviation beyond DBL_MAX), never
 * a made-up "all equal". */
static int anova_finish(palp_stats_anova *r, ssq between, ssq within) {
  if (!isfinite(between.scale) || !isfinite(between.ssq) || !isfinite(within.scale) ||
      !isfinite(within.ssq))
    return PALP_EINVAL;
  r->df_between = r->group_count - 1;
  r->df_within = (long)(r->n - (size_t)r->group_count);
  const double dfb = (double)r->df_between, dfw = (double)r->df_within;
  r->ss_between = ssq_value(between);
  r->ss_within = ssq_value(within);
  r->ss_total = r->ss_between + r->ss_within;
  r->ms_between = between.scale * between.scale * (between.ssq / dfb);
  r->ms_within = within.scale * within.scale * (within.ssq / dfw);
  r->flags = 0;
  if (!isfinite(r->ss_total) || !isfinite(r->ms_between) || !isfinite(r->ms_within))
    r->flags |= PALP_STATS_SS_OVERFLOW;
  if (within.ssq > 0.0) {
    double ratio = between.scale / within.scale; /* inf only when F is beyond DBL_MAX */
    r->f = between.ssq > 0.0 ? ratio * ratio * ((between.ssq * dfw) / (within.ssq * dfb)) : 0.0;
    r->p = gsl_cdf_fdist_Q(r->f, dfb, dfw);
  } else if (between.ssq > 0.0) {
    /* No noise at all, yet the groups differ: the difference is certain. */
    r->flags |= PALP_STATS_ZERO_WITHIN;
    r->f = INFINITY;
    r->p = 0.0;
  } else {
    /* Both sums exactly 0, every value identical: nothing distinguishes the groups. */
    r->flags |= PALP_STATS_ZERO_WITHIN | PALP_STATS_ALL_EQUAL;
    r->f = 0.0;
    r->p = 1.0;
  }
  if (between.ssq > 0.0) {
    double ratio = within.scale / between.scale;
    r->r_squared = 1.0 / (1.0 + ratio * ratio * (within.ssq / between.ssq));
  } else {
    r->r_squared = 0.0;
  }
  return PALP_OK;
}

/*
 * With groups g = 1..k of sizes n_g, N = sum n_g, group means m_g and grand mean
 * G = sum_g n_g m_g / N:
 *   SS_between = sum_g n_g (m_g - G)^2          df_between = k - 1
 *   SS_within  = sum_g sum_i (x_gi - m_g)^2     df_within  = N - k
 *   MS = SS / df,  F = MS_between / MS_within,  p = Q_F(F; k - 1, N - k).
 * Within each group the sums are taken about the group's own first value x_g0, so
 * its SS is exact-differenced even when groups sit far apart. Group means are kept
 * relative to an origin c: M_g = m_g - c = (x_g0 - c) + (m_g - x_g0), an exact
 * difference plus a small accurate number, so M_g - G is a difference of small,
 * accurately known numbers. Without offsets c = values[0]; with offsets the true
 * values are offset[g] + x and M_g = offset[g] + x_g0 + (m_g - x_g0).
 * Both SS are held scaled (ssq above).
 */
static int anova_core(const double *values, const size_t *start, int group_count,
                      const double *offset, palp_stats_anova *out) {
  if (!values || !start || !out || group_count < 2) return PALP_EINVAL;
  if (start[0] != 0) return PALP_EINVAL;
  for (int g = 0; g < group_count; ++g)
    if (start[g + 1] < start[g] || start[g + 1] - start[g] < 2) return PALP_EINVAL;
  size_t n = start[group_count];
  if (!all_finite(values, n)) return PALP_EINVAL;
  if (offset && !all_finite(offset, (size_t)group_count)) return PALP_EINVAL;

  const double c = offset ? 0.0 : values[0];
  palp_stats_sum weighted = {0.0, 0.0}; /* sum n_g M_g */
  ssq within = {0.0, 0.0};
  for (int g = 0; g < group_count; ++g) {
    const double *x = values + start[g];
    size_t ng = start[g + 1] - start[g];
    double m = shifted_mean(x, ng, x[0]);
    double base = offset ? offset[g] + x[0] : x[0] - c;
    palp_stats_sum_add(&weighted, (double)ng * (base + m));
    within = ssq_merge(within, shifted_ssq(x, ng, x[0], m));
  }
  double gm = palp_stats_sum_value(&weighted) / (double)n; /* G - c */

  /* Between-group SS from the same means (recomputed: k small passes are cheaper
   * than a workspace and keep the function allocation-free); two passes, the
   * largest |M_g - G| first, then sum n_g ((M_g - G) / scale)^2. */
  ssq between = {0.0, 0.0};
  for (int pass = 0; pass < 2; ++pass) {
    palp_stats_sum s = {0.0, 0.0};
    for (int g = 0; g < group_count; ++g) {
      const double *x = values + start[g];
      size_t ng = start[g + 1] - start[g];
      double base = offset ? offset[g] + x[0] : x[0] - c;
      double e = (base + shifted_mean(x, ng, x[0])) - gm;
      if (pass == 0) {
        if (!(fabs(e) <= between.scale)) between.scale = fabs(e);
      } else {
        ssq_add(&between, &s, (double)ng, e);
      }
    }
    if (pass == 1) between.ssq = palp_stats_sum_value(&s);
  }

  palp_stats_anova r;
  r.group_count = group_count;
  r.n = n;
  r.grand_mean = c + gm;
  int err = anova_finish(&r, between, within);
  if (err < 0) return err;
  *out = r;
  return PALP_OK;
}

int palp_stats_anova_oneway(const double *values, const size_t *start, int group_count,
                            palp_stats_anova *out) {
  return anova_core(values, start, group_count, NULL, out);
}

int palp_stats_anova_offset(const double *values, const size_t *start, int group_count,
                            const double *offset, palp_stats_anova *out) {
  if (!offset) return PALP_EINVAL;
  return anova_core(values, start, group_count, offset, out);
}

int palp_stats_anova_two_n(const double *a, size_t na, const double *b, size_t nb,
                           palp_stats_anova *out) {
  if (!a || !b || !out || na < 2 || nb < 2) return PALP_EINVAL;
  if (!all_finite(a, na) || !all_finite(b, nb)) return PALP_EINVAL;
  /* Same algorithm as anova_core, for two separate arrays. */
  const double c = a[0];
  double la = shifted_mean(a, na, a[0]), lb = shifted_mean(b, nb, b[0]);
  double ma = la, mb = (b[0] - c) + lb; /* group means minus c */
  double n = (double)(na + nb);
  palp_stats_sum w = {0.0, 0.0};
  palp_stats_sum_add(&w, (double)na * ma);
  palp_stats_sum_add(&w, (double)nb * mb);
  double gm = palp_stats_sum_value(&w) / n;
  ssq within = ssq_merge(shifted_ssq(a, na, a[0], la), shifted_ssq(b, nb, b[0], lb));
  double ea = ma - gm, eb = mb - gm;
  ssq between = {fmax(fabs(ea), fabs(eb)), 0.0};
  if (!isfinite(ea) || !isfinite(eb)) between.scale = NAN; /* b0 - a0 beyond DBL_MAX */
  palp_stats_sum s = {0.0, 0.0};
  ssq_add(&between, &s, (double)na, ea);
  ssq_add(&between, &s, (double)nb, eb);
  between.ssq = palp_stats_sum_value(&s);

  palp_stats_anova r;
  r.group_count = 2;
  r.n = na + nb;
  r.grand_mean = c + gm;
  int err = anova_finish(&r, between, within);
  if (err < 0) return err;
  *out = r;
  return PALP_OK;
}

int palp_stats_anova_two(const double *a, const double *b, size_t n, palp_stats_anova *out) {
  return palp_stats_anova_two_n(a, n, b, n, out);
}

/* ---- Bland-Altman ---------------------------------------------------------------- */

/*
 * d_i = a_i - b_i (exact when a_i and b_i are within a factor of two),
 * bias = sum d_i / n, sd = sqrt( sum (d_i - bias)^2 / (n - 1) ),
 * limits of agreement bias +- 1.96 sd (Bland & Altman 1986), and the paper's
 * agreement: the share of d_i inside the closed band [bias - 2 sd, bias + 2 sd].
 */
int palp_stats_bland_altman(const double *a, const double *b, size_t n,
                            palp_stats_ba *out) {
  if (!a || !b || !out || n < 2) return PALP_EINVAL;
  if (!all_finite(a, n) || !all_finite(b, n)) return PALP_EINVAL;
  for (size_t i = 0; i < n; ++i)
    if (!isfinite(a[i] - b[i])) return PALP_EINVAL; /* differences beyond DBL_MAX */

  const double c = a[0] - b[0];
  palp_stats_sum s = {0.0, 0.0};
  for (size_t i = 0; i < n; ++i) palp_stats_sum_add(&s, (a[i] - b[i]) - c);
  double m = palp_stats_sum_value(&s) / (double)n;
  palp_stats_sum r = {0.0, 0.0};
  for (size_t i = 0; i < n; ++i) palp_stats_sum_add(&r, ((a[i] - b[i]) - c) - m);
  m += palp_stats_sum_value(&r) / (double)n;
  /* sum (d_i - bias)^2 scaled by the largest |d_i - bias| (see ssq), so SD is
   * neither inf/NaN for differences above ~1e154 nor 0 below ~1e-154. */
  ssq q = {0.0, 0.0};
  for (size_t i = 0; i < n; ++i) {
    double e = fabs(((a[i] - b[i]) - c) - m);
    if (e > q.scale) q.scale = e;
  }
  palp_stats_sum qs = {0.0, 0.0};
  for (size_t i = 0; i < n; ++i) ssq_add(&q, &qs, 1.0, ((a[i] - b[i]) - c) - m);
  q.ssq = palp_stats_sum_value(&qs);
  if (!isfinite(q.scale) || !isfinite(q.ssq)) return PALP_EINVAL; /* spread beyond DBL_MAX */

  palp_stats_ba o;
  o.n = n;
  o.mean_a = a[0] + shifted_mean(a, n, a[0]);
  o.mean_b = b[0] + shifted_mean(b, n, b[0]);
  o.bias = c + m;
  o.sd = q.scale * sqrt(q.ssq / (double)(n - 1)); /* data units */
  o.loa_lower = o.bias - PALP_STATS_LOA_SD * o.sd;
  o.loa_upper = o.bias + PALP_STATS_LOA_SD * o.sd;
  o.band_lower = o.bias - PALP_STATS_PAPER_BAND_SD * o.sd;
  o.band_upper = o.bias + PALP_STATS_PAPER_BAND_SD * o.sd;
  /* Count against the deviation from the bias, computed the same shifted way as
   * the SD, so a point exactly on the band is judged without extra rounding. */
  o.within_band = 0;
  o.within_loa = 0;
  for (size_t i = 0; i < n; ++i) {
    double e = fabs(((a[i] - b[i]) - c) - m);
    if (e <= PALP_STATS_PAPER_BAND_SD * o.sd) o.within_band++;
    if (e <= PALP_STATS_LOA_SD * o.sd) o.within_loa++;
  }
  o.agreement = (double)o.within_band / (double)n;
  *out = o;
  return PALP_OK;
}

int palp_stats_meets_paper_criteria(const palp_stats_anova *anova,
                                    const palp_stats_ba *ba) {
  if (!anova || !ba) return 0;
  return anova->p > PALP_STATS_PAPER_ALPHA && ba->agreement > PALP_STATS_PAPER_AGREEMENT;
}
