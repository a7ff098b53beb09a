/*
 * test_serial.c - type-7 quantile, lag-1 autocorrelation, AR(1) effective sample size,
 * block length rule, moving-block bootstrap, TOST and repeated-measures Bland-Altman
 * (src/stats_serial.c). Every expected value is worked by hand in the comment
 * beside it (closed forms of Student's t for 1 and 2 degrees of freedom, Kuensch's
 * exact bootstrap variance), never taken from the code under test.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "harness.h"
#include "stats.h"

static const double PI = 3.14159265358979323846;

static void near(const char *what, double got, double want, double tol) {
  int ok = fabs(got - want) <= tol;
  if (!ok) fprintf(stderr, "  %s: got %.17g, want %.17g (tol %g)\n", what, got, want, tol);
  check(what, ok);
}

static void test_autocorr(void) {
  /* 1..5: mean 3, deviations -2 -1 0 1 2, sum of squares 10, lag-1 products
   * 2 + 0 + 0 + 2 = 4: r1 = 0.4. */
  const double ramp[5] = {1, 2, 3, 4, 5};
  double r = 0;
  check("autocorr ramp ok", palp_stats_autocorr1(ramp, 5, &r) == PALP_OK);
  near("autocorr ramp r1 = 0.4", r, 0.4, 1e-15);
  /* 1 -1 1 -1: mean 0, sum of squares 4, products -1 x 3: r1 = -0.75. */
  const double alt[4] = {1, -1, 1, -1};
  check("autocorr alternating ok", palp_stats_autocorr1(alt, 4, &r) == PALP_OK);
  near("autocorr alternating r1 = -0.75", r, -0.75, 1e-15);
  /* shifted by 1e9: the same r1 (the sums are taken about the mean) */
  const double ramp9[5] = {1e9 + 1, 1e9 + 2, 1e9 + 3, 1e9 + 4, 1e9 + 5};
  check("autocorr shifted ok", palp_stats_autocorr1(ramp9, 5, &r) == PALP_OK);
  near("autocorr shifted r1 = 0.4", r, 0.4, 1e-12);
  const double flat[4] = {2, 2, 2, 2};
  double keep = 7;
  check("autocorr constant -> EINVAL", palp_stats_autocorr1(flat, 4, &keep) == PALP_EINVAL && keep == 7);
  check("autocorr n = 2 -> EINVAL", palp_stats_autocorr1(ramp, 2, &keep) == PALP_EINVAL);
  const double bad[3] = {1, NAN, 2};
  check("autocorr NaN -> EINVAL", palp_stats_autocorr1(bad, 3, &keep) == PALP_EINVAL);

  /* n_eff = n (1 - r) / (1 + r): 5 x 0.6 / 1.4 = 15/7 */
  near("neff(5, 0.4) = 15/7", palp_stats_neff_ar1(5, 0.4), 15.0 / 7.0, 1e-14);
  near("neff(400, 0) = 400", palp_stats_neff_ar1(400, 0.0), 400.0, 0.0);
  /* 4 x 1.75 / 0.25 = 28 > n: clamped to 4 */
  near("neff(4, -0.75) clamped to 4", palp_stats_neff_ar1(4, -0.75), 4.0, 0.0);
  /* the traces: 400 x 0.004 / 1.996 = 0.80 < 1: clamped to 1 */
  near("neff(400, 0.996) clamped to 1", palp_stats_neff_ar1(400, 0.996), 1.0, 0.0);
  /* 400 x 0.1 / 1.9 = 21.0526 */
  near("neff(400, 0.9) = 21.05", palp_stats_neff_ar1(400, 0.9), 400.0 * 0.1 / 1.9, 1e-12);

  /* b = 6^(1/3) (r / (1 - r^2))^(2/3) n^(1/3): r = 0.4, n = 400:
   * 1.817121 x 0.476190^(2/3) = 1.817121 x 0.609778 = 1.108041; x 7.368063 = 8.1644 -> 9 */
  check("block length r 0.4, n 400 = 9", palp_stats_block_length_ar1(400, 0.4) == 9);
  check("block length r 0 = 1", palp_stats_block_length_ar1(400, 0.0) == 1);
  check("block length r < 0 = 1", palp_stats_block_length_ar1(400, -0.3) == 1);
  /* r = 0.996: 0.996 / 0.007984 = 124.75, ^(2/3) = 24.97; x 1.8171 x 7.3681 = 334.27 -> 335 */
  check("block length r 0.996, n 400 = 335", palp_stats_block_length_ar1(400, 0.996) == 335);
  check("block length capped at n", palp_stats_block_length_ar1(50, 0.999) == 50);
}

static void test_bootstrap(void) {
  const double x[6] = {1, 2, 3, 4, 5, 6};
  static double w[40000], w2[40000];
  palp_stats_boot b;
  /* Kuensch (1989): with k = n / b whole blocks, the bootstrap variance of the mean
   * is the variance of the n - b + 1 block means (divisor n - b + 1) over k.
   * b = 2: block means 1.5 2.5 3.5 4.5 5.5, mean 3.5, variance (4+1+0+1+4)/5 = 2;
   * var* = 2 / 3, SE* = 0.816497. With B = 40000 the SE's Monte Carlo error is
   * about SE / sqrt(2B) = 0.35%: tolerance 2%. */
  check("mbb b=2 ok", palp_stats_block_bootstrap_mean(x, 6, 2, 40000, 12345, 0.90, w, &b) == PALP_OK);
  near("mbb b=2 SE = sqrt(2/3)", b.se, sqrt(2.0 / 3.0), 0.02 * sqrt(2.0 / 3.0));
  near("mbb mean of data = 3.5", b.mean, 3.5, 1e-15);
  check("mbb b=2 blocks = 3", b.blocks == 3 && b.block == 2 && b.resamples == 40000);
  double m = 0;
  for (int i = 0; i < 40000; ++i) m += w[i];
  /* E*[mean*] = mean of block means = 3.5; MC error 0.8165 / 200 = 0.004 */
  near("mbb b=2 mean of resamples = 3.5", m / 40000, 3.5, 0.02);
  check("mbb CI brackets the mean", b.ci_lower < 3.5 && b.ci_upper > 3.5 && b.ci_lower >= 1.0 && b.ci_upper <= 6.0);
  check("mbb work sorted", w[0] <= w[19999] && w[19999] <= w[39999]);

  /* deterministic: same seed, same draws */
  palp_stats_boot b2;
  palp_stats_block_bootstrap_mean(x, 6, 2, 40000, 12345, 0.90, w2, &b2);
  check("mbb same seed -> identical", memcmp(w, w2, sizeof w) == 0 && b.se == b2.se);
  palp_stats_block_bootstrap_mean(x, 6, 2, 40000, 54321, 0.90, w2, &b2);
  check("mbb other seed -> other draws", memcmp(w, w2, sizeof w) != 0);

  /* b = 1 is the iid bootstrap: SE* = sqrt(sum (x - m)^2 / n) / sqrt(n)
   * = sqrt(17.5 / 36) = 0.697217 */
  check("mbb b=1 ok", palp_stats_block_bootstrap_mean(x, 6, 1, 40000, 7, 0.90, w, &b) == PALP_OK);
  near("mbb b=1 SE = iid bootstrap SE", b.se, sqrt(17.5 / 36.0), 0.02 * sqrt(17.5 / 36.0));

  /* b = n: one block, every resample is the data: SE 0, interval the mean */
  check("mbb b=n ok", palp_stats_block_bootstrap_mean(x, 6, 6, 100, 7, 0.90, w, &b) == PALP_OK);
  near("mbb b=n SE = 0", b.se, 0.0, 1e-15);
  near("mbb b=n CI lower = mean", b.ci_lower, 3.5, 1e-15);

  /* a non-divisible block: 7 values, b = 3 -> 3 blocks cut to 7 values */
  const double y[7] = {1, 2, 3, 4, 5, 6, 7};
  check("mbb n=7 b=3 ok", palp_stats_block_bootstrap_mean(y, 7, 3, 1000, 1, 0.9, w, &b) == PALP_OK && b.blocks == 3);

  palp_stats_boot keep = b;
  check("mbb block 0 -> EINVAL", palp_stats_block_bootstrap_mean(x, 6, 0, 100, 1, 0.9, w, &b) == PALP_EINVAL);
  check("mbb block > n -> EINVAL", palp_stats_block_bootstrap_mean(x, 6, 7, 100, 1, 0.9, w, &b) == PALP_EINVAL);
  check("mbb 1 resample -> EINVAL", palp_stats_block_bootstrap_mean(x, 6, 2, 1, 1, 0.9, w, &b) == PALP_EINVAL);
  check("mbb level 1 -> EINVAL", palp_stats_block_bootstrap_mean(x, 6, 2, 100, 1, 1.0, w, &b) == PALP_EINVAL);
  const double bad[3] = {1, INFINITY, 2};
  check("mbb inf -> EINVAL", palp_stats_block_bootstrap_mean(bad, 3, 1, 100, 1, 0.9, w, &b) == PALP_EINVAL);
  check("mbb out untouched on error", memcmp(&keep, &b, sizeof b) == 0);
}

static void test_tost(void) {
  palp_stats_tost t;
  /* df = 2: P(T > t) = 1/2 - t / (2 sqrt(2 + t^2)).
   * estimate 0.1, se 0.2, margins -+0.5: t_lower = 3, t_upper = 2;
   * Q(3) = 0.5 - 3 / (2 sqrt 11) = 0.047733, Q(2) = 0.5 - 2 / (2 sqrt 6) = 0.091752;
   * p = 0.091752 >= 0.05: not equivalent. t_{0.95,2}: t / sqrt(2 + t^2) = 0.9,
   * t^2 = 1.62 / 0.19, t = 2.919986; interval 0.1 -+ 0.583997. */
  check("tost df2 ok", palp_stats_tost_t(0.1, 0.2, 2.0, -0.5, 0.5, 0.05, &t) == PALP_OK);
  near("tost df2 t_lower = 3", t.t_lower, 3.0, 1e-14);
  near("tost df2 t_upper = 2", t.t_upper, 2.0, 1e-14);
  near("tost df2 p = Q(2;2)", t.p, 0.5 - 1.0 / sqrt(6.0), 1e-9);
  near("tost df2 CI lower", t.ci_lower, 0.1 - 0.2 * sqrt(1.62 / 0.19), 1e-8);
  near("tost df2 CI upper", t.ci_upper, 0.1 + 0.2 * sqrt(1.62 / 0.19), 1e-8);
  check("tost df2 not equivalent", t.equivalent == 0);
  /* df = 1 (Cauchy): P(T > t) = 1/2 - atan(t) / pi. estimate 0, se 0.05, margins
   * -+0.5: t = 10 both sides, p = 0.5 - atan(10)/pi = 0.031726 < 0.05: equivalent;
   * t_{0.95,1} = tan(0.45 pi) = 6.313752, interval -+0.315688. */
  check("tost df1 ok", palp_stats_tost_t(0.0, 0.05, 1.0, -0.5, 0.5, 0.05, &t) == PALP_OK);
  near("tost df1 p", t.p, 0.5 - atan(10.0) / PI, 1e-9);
  near("tost df1 CI upper", t.ci_upper, 0.05 * tan(0.45 * PI), 1e-8);
  check("tost df1 equivalent", t.equivalent == 1);
  /* asymmetric margins: the worse side decides. estimate 0.3 in (-1, 0.5), se 0.1,
   * df 2: t_lower = 13, t_upper = 2: p = Q(2;2) */
  palp_stats_tost_t(0.3, 0.1, 2.0, -1.0, 0.5, 0.05, &t);
  near("tost asymmetric p = Q(2;2)", t.p, 0.5 - 1.0 / sqrt(6.0), 1e-9);
  /* no uncertainty */
  palp_stats_tost_t(0.2, 0.0, 3.0, -0.5, 0.5, 0.05, &t);
  check("tost se 0 inside: p 0, equivalent", t.p == 0.0 && t.equivalent == 1);
  palp_stats_tost_t(0.5, 0.0, 3.0, -0.5, 0.5, 0.05, &t);
  check("tost se 0 on the margin: p 1, not equivalent", t.p == 1.0 && t.equivalent == 0);
  palp_stats_tost keep = t;
  check("tost se < 0 -> EINVAL", palp_stats_tost_t(0, -1, 3, -1, 1, 0.05, &t) == PALP_EINVAL);
  check("tost df 0 -> EINVAL", palp_stats_tost_t(0, 1, 0, -1, 1, 0.05, &t) == PALP_EINVAL);
  check("tost margins reversed -> EINVAL", palp_stats_tost_t(0, 1, 3, 1, -1, 0.05, &t) == PALP_EINVAL);
  check("tost alpha 0.5 -> EINVAL", palp_stats_tost_t(0, 1, 3, -1, 1, 0.5, &t) == PALP_EINVAL);
  check("tost NaN -> EINVAL", palp_stats_tost_t(NAN, 1, 3, -1, 1, 0.05, &t) == PALP_EINVAL);
  check("tost out untouched on error", memcmp(&keep, &t, sizeof t) == 0);
}

static void test_ba_rm(void) {
  palp_stats_ba_rm r;
  /* Unequal sizes: subject 1 {1, 3}, subject 2 {4, 6, 8}. N = 5, bias = 22/5 = 4.4;
   * means 2 and 6; SS_w = 2 + 8 = 10, df 3, MS_w = 10/3; SS_b = 2 (2.4)^2 + 3 (1.6)^2
   * = 19.2, df 1, MS_b = 19.2; m0 = (25 - 13) / (1 x 5) = 2.4;
   * var_b = (19.2 - 10/3) / 2.4 = 6.611111; SD = sqrt(6.611111 + 3.333333) = 3.153481;
   * LoA = 4.4 -+ 6.180823 = [-1.780823, 10.580823]. */
  const double d1[5] = {1, 3, 4, 6, 8};
  const size_t s1[3] = {0, 2, 5};
  check("ba_rm unequal ok", palp_stats_bland_altman_rm(d1, s1, 2, &r) == PALP_OK);
  near("ba_rm bias 4.4", r.bias, 4.4, 1e-14);
  near("ba_rm MS_w 10/3", r.ms_within, 10.0 / 3.0, 1e-13);
  near("ba_rm MS_b 19.2", r.ms_between, 19.2, 1e-12);
  near("ba_rm m0 2.4", r.divisor, 2.4, 1e-14);
  near("ba_rm var_b", r.var_between, (19.2 - 10.0 / 3.0) / 2.4, 1e-12);
  near("ba_rm LoA lower", r.loa_lower, -1.780823389952003, 1e-9);
  near("ba_rm LoA upper", r.loa_upper, 10.580823389952004, 1e-9);
  /* Equal sizes m = 2: {0,2} {4,6} {8,10}: bias 5, MS_b = 2 (16 + 0 + 16) / 2 = 32,
   * MS_w = 6 / 3 = 2, m0 = m = 2, var_b = 15, SD = sqrt(17), LoA 5 -+ 8.081287. */
  const double d2[6] = {0, 2, 4, 6, 8, 10};
  const size_t s2[4] = {0, 2, 4, 6};
  check("ba_rm equal ok", palp_stats_bland_altman_rm(d2, s2, 3, &r) == PALP_OK);
  near("ba_rm equal m0 = 2", r.divisor, 2.0, 1e-14);
  near("ba_rm equal SD = sqrt 17", r.sd_total, sqrt(17.0), 1e-12);
  near("ba_rm equal LoA upper", r.loa_upper, 5.0 + 1.96 * sqrt(17.0), 1e-12);
  /* Subjects alike: {1,3} {1,3}: MS_b = 0 < MS_w = 2: var_b clamped to 0, SD = sqrt 2,
   * LoA 2 -+ 2.771859 (the ordinary within-subject SD). */
  const double d3[4] = {1, 3, 1, 3};
  const size_t s3[3] = {0, 2, 4};
  check("ba_rm alike ok", palp_stats_bland_altman_rm(d3, s3, 2, &r) == PALP_OK);
  near("ba_rm alike var_b = 0", r.var_between, 0.0, 0.0);
  near("ba_rm alike LoA lower", r.loa_lower, 2.0 - 1.96 * sqrt(2.0), 1e-13);
  /* one observation per subject is refused (no within-subject spread) */
  const size_t s4[3] = {0, 1, 4};
  check("ba_rm subject with 1 value -> EINVAL", palp_stats_bland_altman_rm(d3, s4, 2, &r) == PALP_EINVAL);
  check("ba_rm 1 subject -> EINVAL", palp_stats_bland_altman_rm(d3, s3, 1, &r) == PALP_EINVAL);
}

/* Type 7: h = q (n - 1), x[floor h] + (h - floor h)(x[floor h + 1] - x[floor h]), by hand. */
static void test_quantile(void) {
  const double two[2] = {10.0, 20.0}, five[5] = {1.0, 2.0, 4.0, 8.0, 16.0}, one[1] = {3.0};
  near("quantile n 2, q 0.5 = 15", palp_stats_quantile_sorted(two, 2, 0.5), 15.0, 1e-12);
  near("quantile n 2, q 0.99 = 19.9", palp_stats_quantile_sorted(two, 2, 0.99), 19.9, 1e-12);
  near("quantile n 5, q 0.5 = x[2] = 4", palp_stats_quantile_sorted(five, 5, 0.5), 4.0, 0.0);
  near("quantile n 5, q 0.99: h 3.96, 8 + 0.96 * 8 = 15.68", palp_stats_quantile_sorted(five, 5, 0.99), 15.68, 1e-12);
  near("quantile q 0 = min", palp_stats_quantile_sorted(five, 5, 0.0), 1.0, 0.0);
  near("quantile q 1 = max", palp_stats_quantile_sorted(five, 5, 1.0), 16.0, 0.0);
  near("quantile n 1 = the value", palp_stats_quantile_sorted(one, 1, 0.99), 3.0, 0.0);
}

int main(void) {
  (void)slurp; /* harness.h also serves the tool tests */
  test_quantile();
  test_autocorr();
  test_bootstrap();
  test_tost();
  test_ba_rm();
  printf("%d checks, %d failures\n", checks, failures);
  return failures ? 1 : 0;
}
