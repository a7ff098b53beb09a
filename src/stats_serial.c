/*
 * stats_serial.c - statistics for serially correlated differences and for several
 * observations per unit of analysis: lag-1 autocorrelation, the AR(1) effective
 * sample size, the moving-block bootstrap of a mean, Schuirmann's TOST and
 * Bland & Altman's (2007) repeated-measures limits of agreement.
 * Formulas and choices: stats.h and docs/statistics.md ("Sound statistics").
 *
 * Why: the evaluation's vertex-frames come from one deterministic run; their
 * per-frame differences have a lag-1 autocorrelation near 0.996, so treating
 * 118,400 of them as independent makes any p-value a measure of sample size.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include <gsl/gsl_cdf.h>

#include "stats.h"

int palp_stats_autocorr1(const double *x, size_t n, double *r1) {
  if (!x || !r1 || n < 3) return PALP_EINVAL;
  for (size_t i = 0; i < n; ++i)
    if (!isfinite(x[i])) return PALP_EINVAL;
  double m, ssd;
  palp_stats_mean_ssd(x, n, &m, &ssd);
  if (!(ssd > 0.0)) return PALP_EINVAL; /* constant: no correlation defined */
  palp_stats_sum c = {0.0, 0.0};
  for (size_t t = 0; t + 1 < n; ++t) palp_stats_sum_add(&c, (x[t] - m) * (x[t + 1] - m));
  *r1 = palp_stats_sum_value(&c) / ssd;
  return PALP_OK;
}

/* For AR(1), corr(x_t, x_{t+k}) = r^|k|, so var(mean) = (sigma^2 / n) sum_k r^|k|
 * -> (sigma^2 / n) (1 + r) / (1 - r) for n >> 1/(1 - r). */
double palp_stats_neff_ar1(size_t n, double r1) {
  if (n == 0 || !isfinite(r1)) return NAN;
  if (r1 >= 1.0) return 1.0;
  if (r1 <= -1.0) return (double)n;
  double ne = (double)n * (1.0 - r1) / (1.0 + r1);
  if (ne > (double)n) ne = (double)n;
  if (ne < 1.0) ne = 1.0;
  return ne;
}

/* AR(1) of unit variance: R(k) = r^|k|; G = sum_k |k| R(k) = 2 r / (1 - r)^2;
 * g = sum_k R(k) = (1 + r) / (1 - r); D_MBB = (4/3) g^2. Then
 * 2 G^2 / D = 6 r^2 / (1 - r^2)^2. */
size_t palp_stats_block_length_ar1(size_t n, double r1) {
  if (n == 0) return 0;
  if (!(r1 > 0.0)) return 1;
  if (r1 >= 1.0) return n;
  double b = cbrt(6.0) * pow(r1 / (1.0 - r1 * r1), 2.0 / 3.0) * cbrt((double)n);
  if (!(b < (double)n)) return n;
  size_t bi = (size_t)ceil(b);
  return bi < 1 ? 1 : (bi > n ? n : bi);
}

/* SplitMix64 (Steele, Lea & Flood 2014): a tiny, well-mixed, reproducible stream;
 * its state is the caller's seed, so no generator object is allocated. */
static uint64_t splitmix64(uint64_t *state) {
  uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/* Uniform integer in [0, m), m >= 1, without modulo bias (rejection). */
static uint64_t uniform_below(uint64_t *state, uint64_t m) {
  const uint64_t limit = UINT64_MAX - UINT64_MAX % m;
  uint64_t r;
  do r = splitmix64(state);
  while (r >= limit);
  return r % m;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

double palp_stats_quantile_sorted(const double *s, size_t n, double q) {
  double h = q * (double)(n - 1);
  size_t lo = (size_t)floor(h);
  if (lo + 1 >= n) return s[n - 1];
  return s[lo] + (h - (double)lo) * (s[lo + 1] - s[lo]);
}

int palp_stats_block_bootstrap_mean(const double *x, size_t n, size_t block, size_t resamples,
                                    unsigned long long seed, double level, double *work,
                                    palp_stats_boot *out) {
  if (!x || !work || !out || n < 2 || block == 0 || block > n || resamples < 2) return PALP_EINVAL;
  if (!(level > 0.0 && level < 1.0)) return PALP_EINVAL;
  for (size_t i = 0; i < n; ++i)
    if (!isfinite(x[i])) return PALP_EINVAL;
  const size_t starts = n - block + 1, nblocks = (n + block - 1) / block;
  uint64_t state = (uint64_t)seed;
  for (size_t r = 0; r < resamples; ++r) {
    palp_stats_sum s = {0.0, 0.0};
    size_t taken = 0;
    for (size_t k = 0; k < nblocks; ++k) {
      size_t s0 = (size_t)uniform_below(&state, (uint64_t)starts);
      for (size_t j = 0; j < block && taken < n; ++j, ++taken) palp_stats_sum_add(&s, x[s0 + j]);
    }
    work[r] = palp_stats_sum_value(&s) / (double)n;
  }
  palp_stats_boot o;
  double m, ssd;
  palp_stats_mean_ssd(x, n, &o.mean, &ssd);
  palp_stats_mean_ssd(work, resamples, &m, &ssd);
  o.se = sqrt(ssd / (double)(resamples - 1));
  qsort(work, resamples, sizeof *work, cmp_double);
  o.ci_lower = palp_stats_quantile_sorted(work, resamples, 0.5 * (1.0 - level));
  o.ci_upper = palp_stats_quantile_sorted(work, resamples, 0.5 * (1.0 + level));
  o.level = level;
  o.block = block;
  o.blocks = nblocks;
  o.resamples = resamples;
  *out = o;
  return PALP_OK;
}

/*
 * H0: estimate <= lower or estimate >= upper, rejected at level alpha when both
 *   t_lower = (estimate - lower) / se  and  t_upper = (upper - estimate) / se
 * exceed t_{1-alpha, df}; equivalently p = max(Q_t(t_lower), Q_t(t_upper)) < alpha,
 * or the (1 - 2 alpha) interval estimate -+ t_{1-alpha, df} se inside the margins.
 */
int palp_stats_tost_t(double estimate, double se, double df, double lower, double upper, double alpha,
                      palp_stats_tost *out) {
  if (!out || !isfinite(estimate) || !isfinite(se) || !isfinite(df) || !isfinite(lower) || !isfinite(upper))
    return PALP_EINVAL;
  if (se < 0.0 || !(df > 0.0) || !(lower < upper) || !(alpha > 0.0 && alpha < 0.5)) return PALP_EINVAL;
  palp_stats_tost o;
  o.estimate = estimate;
  o.se = se;
  o.df = df;
  o.lower = lower;
  o.upper = upper;
  o.alpha = alpha;
  if (se == 0.0) {
    /* No uncertainty: equivalent exactly when the estimate lies inside. */
    int in = estimate > lower && estimate < upper;
    o.t_lower = estimate > lower ? INFINITY : -INFINITY;
    o.t_upper = estimate < upper ? INFINITY : -INFINITY;
    o.p = in ? 0.0 : 1.0;
    o.ci_lower = o.ci_upper = estimate;
  } else {
    o.t_lower = (estimate - lower) / se;
    o.t_upper = (upper - estimate) / se;
    o.p = fmax(gsl_cdf_tdist_Q(o.t_lower, df), gsl_cdf_tdist_Q(o.t_upper, df));
    const double tq = gsl_cdf_tdist_Qinv(alpha, df);
    o.ci_lower = estimate - tq * se;
    o.ci_upper = estimate + tq * se;
  }
  o.equivalent = o.p < alpha;
  *out = o;
  return PALP_OK;
}

/*
 * Bland & Altman (2007), Sec. 5 (the true value varies within a subject): with k
 * subjects, m_i differences each, N = sum m_i, a one-way ANOVA of the differences
 * by subject gives MS_between and MS_within;
 *   var_within  = MS_within,
 *   var_between = (MS_between - MS_within) / m0,  m0 = (N^2 - sum m_i^2) / ((k - 1) N),
 *   SD_total    = sqrt(var_between + var_within),  LoA = bias -+ 1.96 SD_total,
 * bias = the mean of all N differences. A negative var_between (sampling noise
 * when subjects do not differ) is set to 0.
 */
int palp_stats_bland_altman_rm(const double *d, const size_t *start, int subjects,
                               palp_stats_ba_rm *out) {
  if (!out) return PALP_EINVAL;
  palp_stats_anova a;
  int rc = palp_stats_anova_oneway(d, start, subjects, &a);
  if (rc) return rc;
  const double N = (double)a.n;
  palp_stats_sum sm2 = {0.0, 0.0};
  for (int g = 0; g < subjects; ++g) {
    double m = (double)(start[g + 1] - start[g]);
    palp_stats_sum_add(&sm2, m * m);
  }
  palp_stats_ba_rm o;
  o.subjects = subjects;
  o.n = a.n;
  o.bias = a.grand_mean;
  o.ms_between = a.ms_between;
  o.ms_within = a.ms_within;
  o.divisor = (N * N - palp_stats_sum_value(&sm2)) / ((double)(subjects - 1) * N);
  o.var_within = a.ms_within;
  o.var_between = fmax(0.0, (a.ms_between - a.ms_within) / o.divisor);
  o.sd_total = sqrt(o.var_between + o.var_within);
  o.loa_lower = o.bias - PALP_STATS_LOA_SD * o.sd_total;
  o.loa_upper = o.bias + PALP_STATS_LOA_SD * o.sd_total;
  *out = o;
  return PALP_OK;
}
