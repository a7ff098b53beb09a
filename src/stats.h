/*
 * stats.h - the paper's agreement statistics (Widmer & Hu 2011, Sec. II-D):
 * RMSE, one-way ANOVA and Bland-Altman agreement, as small pure functions over
 * caller-provided arrays. No allocation, no globals, no I/O.
 *
 * Every function returns PALP_OK (0) or a negative PALP_E* code from palp.h and
 * leaves *out untouched on error. Units are whatever the caller's data carry
 * (the evaluation passes metres and newtons); results share them, squared for
 * sums of squares and mean squares.
 *
 * Numerics: every sum is taken about a data value (an exact subtraction for data
 * that share leading digits), in two passes (means first, then deviations) with
 * Neumaier-compensated accumulation. Data that share 13 leading digits, such as
 * NIST StRD SmLs07-09, keep F and the sums of squares to 9+ significant digits of
 * the exact result for the binary64 values given. See docs/statistics.md.
 */
#ifndef PALP_STATS_H
#define PALP_STATS_H

#include <stddef.h>

#include "palp.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The paper's success criteria (Sec. II-D): ANOVA p above this ... */
#define PALP_STATS_PAPER_ALPHA 0.05
/* ... and more than this share of the differences within bias +- 2 SD. */
#define PALP_STATS_PAPER_AGREEMENT 0.95
/* Half-width of the paper's agreement band, in SDs of the differences. */
#define PALP_STATS_PAPER_BAND_SD 2.0
/* Bland & Altman (1986) limits of agreement: bias +- 1.96 SD. */
#define PALP_STATS_LOA_SD 1.96

/* ---- RMSE ------------------------------------------------------------------ */
/* RMSE = sqrt( sum_i (a_i - b_i)^2 / n ). n >= 1, all values finite.
 * Scaled like BLAS dnrm2, so it neither overflows nor underflows. */
int palp_stats_rmse(const double *a, const double *b, size_t n, double *out);

/* ---- one-way ANOVA ------------------------------------------------------------ */
/* Flags describing degenerate but well-defined results. */
enum {
  /* Every group is constant inside (SS_within = 0) but the group means differ:
   * F = +inf, p = 0 (the groups certainly differ). */
  PALP_STATS_ZERO_WITHIN = 1u << 0,
  /* Every value is the same (SS_within = SS_between = 0): F = 0, p = 1 (no
   * evidence of any difference; the paper's criterion p > 0.05 holds). */
  PALP_STATS_ALL_EQUAL = 1u << 1,
  /* A sum of squares, their total or a mean square is beyond DBL_MAX (data above
   * ~1e154): that field is +inf. F, p and R^2 are formed from the scaled sums and
   * stay exact. (Sums below DBL_MIN likewise read 0 or subnormal without this flag;
   * the flags above are judged on the scaled sums, exactly.) */
  PALP_STATS_SS_OVERFLOW = 1u << 2
};

typedef struct palp_stats_anova {
  int group_count;    /* k >= 2 */
  size_t n;           /* total observations N */
  double grand_mean;  /* sum of all values / N */
  double ss_between;  /* sum_g n_g (mean_g - grand_mean)^2 */
  double ss_within;   /* sum_g sum_i (x_gi - mean_g)^2 */
  double ss_total;    /* ss_between + ss_within */
  int df_between;     /* k - 1 */
  long df_within;     /* N - k */
  double ms_between;  /* ss_between / df_between */
  double ms_within;   /* ss_within / df_within */
  double f;           /* ms_between / ms_within (see flags) */
  double p;           /* P(F(df_between, df_within) > f) = gsl_cdf_fdist_Q */
  double r_squared;   /* ss_between / ss_total (0 when ss_total = 0) */
  unsigned flags;     /* PALP_STATS_ZERO_WITHIN, PALP_STATS_ALL_EQUAL */
} palp_stats_anova;

/* Groups are stored back to back: group g holds values[start[g] .. start[g+1]),
 * so start has group_count + 1 entries, start[0] = 0 and start ascending.
 * Errors (PALP_EINVAL): group_count < 2, a group with fewer than 2 values (one
 * value carries no within-group spread and usually means a mistyped group label),
 * a non-finite value, start not ascending, a deviation beyond DBL_MAX (values
 * of opposite sign near DBL_MAX): never a made-up "all equal". */
int palp_stats_anova_oneway(const double *values, const size_t *start, int group_count,
                            palp_stats_anova *out);

/* As palp_stats_anova_oneway for values given relative to a per-group offset:
 * group g holds the values offset[g] + values[i]. For callers that can subtract
 * exactly (palp-stats subtracts decimal text): values relative to their group keep
 * their spread, and offsets relative to one common origin keep the between-group
 * differences; grand_mean is then relative to that origin. */
int palp_stats_anova_offset(const double *values, const size_t *start, int group_count,
                            const double *offset, palp_stats_anova *out);

/* The paper's use: two groups of n values each (real-time model vs FEM). */
int palp_stats_anova_two(const double *a, const double *b, size_t n, palp_stats_anova *out);

/* Two groups of different sizes. */
int palp_stats_anova_two_n(const double *a, size_t na, const double *b, size_t nb,
                           palp_stats_anova *out);

/* ---- Bland-Altman agreement ---------------------------------------------------- */
typedef struct palp_stats_ba {
  size_t n;            /* pairs, >= 2 */
  double mean_a, mean_b;
  double bias;         /* mean of d_i = a_i - b_i */
  double sd;           /* SD of d_i with n - 1 in the denominator */
  double loa_lower;    /* bias - 1.96 sd */
  double loa_upper;    /* bias + 1.96 sd */
  double band_lower;   /* bias - 2 sd: the paper's agreement band */
  double band_upper;   /* bias + 2 sd */
  size_t within_band;  /* pairs with band_lower <= d_i <= band_upper */
  double agreement;    /* within_band / n, a share in [0, 1] (the paper prints %) */
  size_t within_loa;   /* pairs with loa_lower <= d_i <= loa_upper */
} palp_stats_ba;

/* Errors (PALP_EINVAL): n < 2, a non-finite value. With sd = 0 every pair lies
 * on the bias, so agreement = 1. */
int palp_stats_bland_altman(const double *a, const double *b, size_t n,
                            palp_stats_ba *out);

/* The paper's verdict for one distribution: ANOVA p > 0.05 and more than 95% of
 * the differences within bias +- 2 SD. Returns 1 when both hold, else 0. */
int palp_stats_meets_paper_criteria(const palp_stats_anova *anova,
                                    const palp_stats_ba *ba);

/* ---- building blocks ----------------------------------------------------------- */
/* Neumaier (improved Kahan-Babuska) compensated sum: the running sum plus the
 * rounding errors lost so far. */
typedef struct palp_stats_sum {
  double s, c;
} palp_stats_sum;

static inline void palp_stats_sum_add(palp_stats_sum *acc, double x) {
  double t = acc->s + x;
  /* The branch picks the operand whose low bits were rounded away. */
  if ((acc->s >= 0 ? acc->s : -acc->s) >= (x >= 0 ? x : -x))
    acc->c += (acc->s - t) + x;
  else
    acc->c += (x - t) + acc->s;
  acc->s = t;
}

static inline double palp_stats_sum_value(const palp_stats_sum *acc) { return acc->s + acc->c; }

/* Mean and sum of squared deviations of x[0..n) in two compensated passes about
 * the shift x[0]: mean = x0 + sum(x - x0)/n, refined once by the mean residual,
 * then ssd = sum (x - mean)^2. n >= 1; ssd = 0 for n = 1. */
void palp_stats_mean_ssd(const double *x, size_t n, double *mean, double *ssd);

/* As palp_stats_mean_ssd, but the sample SD sqrt(ssd / (n - 1)) in x's unit,
 * formed from a sum scaled by max |x - mean| so it neither overflows (data above
 * ~1e154, where ssd is +inf) nor vanishes (below ~1e-154). n >= 2, else sd = NaN. */
void palp_stats_mean_sd(const double *x, size_t n, double *mean, double *sd);

/* Quantile q in [0, 1] of s[0..n), n >= 1, sorted ascending: linear interpolation
 * between order statistics (Hyndman & Fan's type 7, the default of R and NumPy; the
 * bootstrap's percentile interval). Nondecreasing in q: a median never above a p99. */
double palp_stats_quantile_sorted(const double *s, size_t n, double q);

/* ---- serially correlated data: effective size, block bootstrap, TOST, ------- */
/* ---- repeated-measures agreement (src/stats_serial.c) ------------------------ */
/* The paper's statistics treat every vertex-frame as an independent observation;
 * the differences of two smooth models over a run are instead strongly
 * autocorrelated in time (lag-1 r ~ 0.99). These functions give the statistics a
 * sound unit of analysis (docs/statistics.md, "Sound statistics"). */

/* Lag-1 autocorrelation (Box & Jenkins' estimator):
 *   r1 = sum_{t<n-1} (x_t - m)(x_{t+1} - m) / sum_t (x_t - m)^2.
 * n >= 3 and the series not constant (else PALP_EINVAL). */
int palp_stats_autocorr1(const double *x, size_t n, double *r1);

/* Effective sample size of the mean of an AR(1) series with lag-1 autocorrelation
 * r1: var(mean) = sigma^2 / n_eff with n_eff = n (1 - r1) / (1 + r1) (Bayley &
 * Hammersley 1946), clamped to [1, n] (a negative r1 is not credited with more
 * than n observations; a series holds at least one observation of its mean). */
double palp_stats_neff_ar1(size_t n, double r1);

/* Block length for the moving-block bootstrap of a mean: Politis & White's (2004)
 * optimal b = (2 G^2 / D)^(1/3) n^(1/3) with G, D evaluated for an AR(1) process
 * of lag-1 autocorrelation r1, which gives b = 6^(1/3) (r1 / (1 - r1^2))^(2/3)
 * n^(1/3), rounded up; 1 for r1 <= 0; at most n. */
size_t palp_stats_block_length_ar1(size_t n, double r1);

typedef struct palp_stats_boot {
  double mean;        /* the statistic on the data: mean of x */
  double se;          /* SD of the resampled means (B - 1 in the denominator) */
  double ci_lower;    /* percentile interval of the resampled means at `level` */
  double ci_upper;
  double level;       /* e.g. 0.90 for TOST at alpha = 0.05 */
  size_t block;       /* block length b */
  size_t blocks;      /* blocks per resample, ceil(n / b) */
  size_t resamples;   /* B */
} palp_stats_boot;

/* Moving-block bootstrap (Kuensch 1989) of the mean of x[0..n): each resample
 * joins ceil(n / b) blocks x[s .. s+b) with s uniform on 0..n-b, cut to n values.
 * Deterministic: the draws come from a SplitMix64 stream started at `seed`.
 * work holds `resamples` doubles (the resampled means, left sorted). Errors
 * (PALP_EINVAL): n < 2, block 0 or > n, resamples < 2, level outside (0, 1), a
 * non-finite value, NULL pointers. */
int palp_stats_block_bootstrap_mean(const double *x, size_t n, size_t block, size_t resamples,
                                    unsigned long long seed, double level, double *work,
                                    palp_stats_boot *out);

typedef struct palp_stats_tost {
  double estimate;     /* e.g. the bias */
  double se;           /* its standard error */
  double df;           /* degrees of freedom of the t reference (may be fractional) */
  double lower, upper; /* equivalence margins, lower < upper */
  double alpha;        /* each one-sided test's level, 0.05 */
  double t_lower;      /* (estimate - lower) / se: tests H0 estimate <= lower */
  double t_upper;      /* (upper - estimate) / se: tests H0 estimate >= upper */
  double p;            /* max of the two one-sided p-values Q_t(t; df) */
  double ci_lower;     /* estimate -+ t_{1-alpha, df} se: the (1 - 2 alpha) interval */
  double ci_upper;
  int equivalent;      /* 1 when p < alpha, i.e. the interval lies inside (lower, upper) */
} palp_stats_tost;

/* Schuirmann's (1987) two one-sided tests. se = 0 gives p = 0 when the estimate
 * lies strictly inside the margins, else 1. Errors (PALP_EINVAL): se < 0, df <= 0,
 * lower >= upper, alpha outside (0, 0.5), non-finite input. */
int palp_stats_tost_t(double estimate, double se, double df, double lower, double upper, double alpha,
                      palp_stats_tost *out);

typedef struct palp_stats_ba_rm {
  int subjects;         /* units of analysis (here: runs), >= 2 */
  size_t n;             /* observations in all */
  double bias;          /* mean of all differences */
  double ms_between;    /* one-way ANOVA of the differences by subject */
  double ms_within;
  double divisor;       /* m0 = (N^2 - sum m_i^2) / ((k - 1) N) */
  double var_between;   /* (MS_b - MS_w) / m0, 0 when negative */
  double var_within;    /* MS_w */
  double sd_total;      /* sqrt(var_between + var_within) */
  double loa_lower;     /* bias - 1.96 sd_total */
  double loa_upper;     /* bias + 1.96 sd_total */
} palp_stats_ba_rm;

/* Bland & Altman (2007), "true value varies": limits of agreement for several
 * differences per subject. Subject g holds d[start[g] .. start[g+1]) (at least 2
 * each; see palp_stats_anova_oneway for the layout and errors). */
int palp_stats_bland_altman_rm(const double *d, const size_t *start, int subjects,
                               palp_stats_ba_rm *out);

#ifdef __cplusplus
}
#endif

#endif /* PALP_STATS_H */
