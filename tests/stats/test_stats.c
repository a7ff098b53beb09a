/*
 * test_stats.c - every statistic of src/stats.c against independently known values:
 * NIST StRD one-way ANOVA certified values, exact rational results derived by hand
 * in the comments, and closed forms of the F distribution.
 *
 * Tolerances are relative and stated at each check; "9 significant digits" means
 * |got - want| <= 1e-9 |want|.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "stats.h"

static int failures = 0;
static int checks = 0;

static void check_rel(const char *what, double got, double want, double rtol) {
  ++checks;
  double err = fabs(got - want);
  double lim = rtol * fabs(want);
  if (!(err <= lim)) {
    ++failures;
    fprintf(stderr, "FAIL %s: got %.17g want %.17g (rel err %.3g > %.3g)\n", what, got, want,
            want != 0.0 ? err / fabs(want) : err, rtol);
  }
}

static void check_abs(const char *what, double got, double want, double atol) {
  ++checks;
  if (!(fabs(got - want) <= atol)) {
    ++failures;
    fprintf(stderr, "FAIL %s: got %.17g want %.17g (abs tol %.3g)\n", what, got, want, atol);
  }
}

static void check_true(const char *what, int cond) {
  ++checks;
  if (!cond) {
    ++failures;
    fprintf(stderr, "FAIL %s\n", what);
  }
}

/* ---- NIST StRD one-way ANOVA ---------------------------------------------------
 * Data and certified values from https://www.itl.nist.gov/div898/strd/anova/
 * (the .dat files: "Certified Values" block, lines 41-47). */

/* SiRstv: silicon resistivity, 5 instruments x 5 replicates, lower difficulty.
 * Certified: Between Instrument df 4, SS 5.11462616000000E-02, MS 1.27865654000000E-02,
 * F 1.18046237440255E+00; Within Instrument df 20, SS 2.16636560000000E-01,
 * MS 1.08318280000000E-02; R^2 1.90999039051129E-01. */
static const double sirstv[25] = {
    196.3052, 196.1240, 196.1890, 196.2569, 196.3403, /* instrument 1 */
    196.3042, 196.3825, 196.1669, 196.3257, 196.0422, /* instrument 2 */
    196.1303, 196.2005, 196.2889, 196.0343, 196.1811, /* instrument 3 */
    196.2795, 196.1748, 196.1494, 196.1485, 195.9885, /* instrument 4 */
    196.2119, 196.1051, 196.1850, 196.0052, 196.2090, /* instrument 5 */
};

/* AtmWtAg: atomic weight of silver, 2 instruments x 24 replicates, 7 constant
 * leading digits, average difficulty. Certified: Between Instrument df 1,
 * SS 3.63834187500000E-09, F 1.59467335677930E+01; Within Instrument df 46,
 * SS 1.04951729166667E-08, MS 2.28155932971014E-10; R^2 2.57426544538321E-01. */
static const double atmwtag[48] = {
    107.8681568, 107.8681465, 107.8681572, 107.8681785, 107.8681446, 107.8681903,
    107.8681526, 107.8681494, 107.8681616, 107.8681587, 107.8681519, 107.8681486,
    107.8681419, 107.8681569, 107.8681508, 107.8681672, 107.8681385, 107.8681518,
    107.8681662, 107.8681424, 107.8681360, 107.8681333, 107.8681610, 107.8681477,
    107.8681079, 107.8681344, 107.8681513, 107.8681197, 107.8681604, 107.8681385,
    107.8681642, 107.8681365, 107.8681151, 107.8681082, 107.8681517, 107.8681448,
    107.8681198, 107.8681482, 107.8681334, 107.8681609, 107.8681101, 107.8681512,
    107.8681469, 107.8681360, 107.8681254, 107.8681261, 107.8681450, 107.8681368,
};

/* SmLs01..09: 9 treatments x R replicates (R = 21, 201, 2001), constant part
 * "1", "1000000" or "1000000000000" (1, 7 or 13 constant leading digits). Value of
 * treatment t, replicate r: offset + b(t) + b(r) with b(1) = 0.2, b(even) = 0.1,
 * b(odd >= 3) = 0.3, i.e. the fraction digits of SmLs01.dat:
 *   t1: 1.4 1.3 1.5 1.3 1.5 ...  t2: 1.3 1.2 1.4 1.2 ...  t3: 1.5 1.4 1.6 1.4 ...
 * Certified (NIST): SmLs01/04/07: between df 8, SS 1.68, MS 0.21, F 21; within
 * df 180, SS 1.80, MS 0.01. SmLs02/05/08: F 201 (SS 16.08 and 18.0, df 8 and 1800).
 * SmLs03/06/09: F 2001 (SS 160.08 and 180.0, df 8 and 18000). By hand: every group
 * has one value at its mean and (R-1)/2 at +-0.1, so SS_within = 9 0.01;
 * group means are 1.4 (t1), 1.3 (even t), 1.5 (odd t), grand mean 1.4, so
 * SS_between = R (4 0.01 + 4 0.01) = 0.08 R. */
static int smls_digit(int idx) { return idx == 1 ? 2 : (idx % 2 == 0 ? 1 : 3); }

/* Values are parsed from their decimal text as a reader of the .dat file would. */
static double *smls_values(const char *offset, int reps, size_t *start) {
  double *v = malloc(sizeof(double) * 9 * (size_t)reps);
  if (!v) abort();
  size_t k = 0;
  for (int t = 1; t <= 9; ++t) {
    start[t - 1] = k;
    for (int r = 1; r <= reps; ++r) {
      char buf[64];
      int d = smls_digit(t) + smls_digit(r);
      if (strcmp(offset, "1") == 0)
        snprintf(buf, sizeof buf, "1.%d", d);
      else
        snprintf(buf, sizeof buf, "%s.%d", offset, d);
      v[k++] = strtod(buf, NULL);
    }
  }
  start[9] = k;
  return v;
}

static void test_sirstv(void) {
  size_t start[6] = {0, 5, 10, 15, 20, 25};
  palp_stats_anova a;
  check_true("SiRstv returns ok", palp_stats_anova_oneway(sirstv, start, 5, &a) == PALP_OK);
  /* 9 significant digits against NIST's 15 certified ones. */
  check_true("SiRstv df", a.df_between == 4 && a.df_within == 20);
  check_rel("SiRstv SS between", a.ss_between, 5.11462616000000E-02, 1e-9);
  check_rel("SiRstv SS within", a.ss_within, 2.16636560000000E-01, 1e-9);
  check_rel("SiRstv MS between", a.ms_between, 1.27865654000000E-02, 1e-9);
  check_rel("SiRstv MS within", a.ms_within, 1.08318280000000E-02, 1e-9);
  check_rel("SiRstv F", a.f, 1.18046237440255E+00, 1e-9);
  check_rel("SiRstv R^2", a.r_squared, 1.90999039051129E-01, 1e-9);
}

static void test_atmwtag(void) {
  size_t start[3] = {0, 24, 48};
  palp_stats_anova a;
  check_true("AtmWtAg returns ok", palp_stats_anova_oneway(atmwtag, start, 2, &a) == PALP_OK);
  check_true("AtmWtAg df", a.df_between == 1 && a.df_within == 46);
  /* 9 digits: the binary64 rounding of the 10-digit inputs moves F by ~7e-11. */
  check_rel("AtmWtAg SS between", a.ss_between, 3.63834187500000E-09, 1e-9);
  check_rel("AtmWtAg SS within", a.ss_within, 1.04951729166667E-08, 1e-9);
  check_rel("AtmWtAg MS within", a.ms_within, 2.28155932971014E-10, 1e-9);
  check_rel("AtmWtAg F", a.f, 1.59467335677930E+01, 1e-9);
  check_rel("AtmWtAg R^2", a.r_squared, 2.57426544538321E-01, 1e-9);
  /* The two-array entry point must agree to the last few ulps. */
  palp_stats_anova b;
  check_true("AtmWtAg two-array ok", palp_stats_anova_two(atmwtag, atmwtag + 24, 24, &b) == PALP_OK);
  check_rel("AtmWtAg two-array F", b.f, a.f, 1e-13);
}

/* SmLs01-06: certified values to 9 digits. */
static void test_smls_certified(const char *name, const char *offset, int reps) {
  size_t start[10];
  double *v = smls_values(offset, reps, start);
  palp_stats_anova a;
  char what[96];
  snprintf(what, sizeof what, "%s returns ok", name);
  check_true(what, palp_stats_anova_oneway(v, start, 9, &a) == PALP_OK);
  double R = reps;
  snprintf(what, sizeof what, "%s df", name);
  check_true(what, a.df_between == 8 && a.df_within == 9 * (reps - 1));
  snprintf(what, sizeof what, "%s SS between", name);
  check_rel(what, a.ss_between, 0.08 * R, 1e-9);
  snprintf(what, sizeof what, "%s SS within", name);
  check_rel(what, a.ss_within, 0.09 * (R - 1), 1e-9);
  snprintf(what, sizeof what, "%s MS between", name);
  check_rel(what, a.ms_between, 0.01 * R, 1e-9);
  snprintf(what, sizeof what, "%s MS within", name);
  check_rel(what, a.ms_within, 0.01, 1e-9);
  snprintf(what, sizeof what, "%s F", name);
  check_rel(what, a.f, R, 1e-9); /* certified F = 21, 201, 2001 */
  free(v);
}

/*
 * SmLs07-09 (13 constant leading digits). "1000000000000.d" cannot be held in
 * binary64: the spacing of doubles at 1e12 is u = 2^-13, so the parsed values are
 * 1e12 + q u with q = round(0.d / u) = 1638 (0.2), 2458 (0.3), 3277 (0.4),
 * 4096 (0.5), 4915 (0.6). No arithmetic can recover the certified F = 21 from
 * these inputs (it recovers 21.0008...); the CLI does, by subtracting a common
 * origin in exact decimal arithmetic before conversion (tests/stats/test_cli.c).
 * What the library must deliver is the exact answer for the values it is given;
 * by hand, in units of u, with R = 2m + 1 replicates:
 *   t1:      one 3277, m x 2458, m x 4096      sum 3277 R        (mean 3277)
 *   t even:  one 2458, m x 1638, m x 3277      sum 2458 + 4915 m
 *   t odd:   one 4096, m x 3277, m x 4915      sum 4096 R        (mean 4096)
 * and with S_g the group sums, Q_g the sums of squares, T = sum S_g:
 *   R SS_within    = sum_g (R Q_g - S_g^2)
 *   9R SS_between  = 9 sum_g S_g^2 - T^2
 * all integers below 2^63 for m <= 1000, so exact in int64. For SmLs07 this gives
 * SS_between = 21310388552/189 u^2, SS_within = 2536852940/21 u^2 and
 * F = 21.000811887818..., matching the 80-digit binary64-input value 21.00081188781877
 * published by an independent NIST-conformance harness (201.01300409594845 for
 * SmLs08, 2001.1349262209505 for SmLs09).
 */
static void test_smls_ill_conditioned(const char *name, int reps, double published_f) {
  size_t start[10];
  double *v = smls_values("1000000000000", reps, start);
  int64_t m = (reps - 1) / 2, R = reps;
  int64_t S1 = 3277 * R, Se = 2458 + 4915 * m, So = 4096 * R;
  int64_t Q1 = 3277 * 3277 + m * (2458 * 2458 + 4096 * 4096);
  int64_t Qe = 2458 * 2458 + m * (1638 * 1638 + 3277 * 3277);
  int64_t Qo = 4096 * 4096 + m * (3277 * 3277 + 4915 * 4915);
  int64_t T = S1 + 4 * Se + 4 * So;
  int64_t w = (R * Q1 - S1 * S1) + 4 * (R * Qe - Se * Se) + 4 * (R * Qo - So * So);
  int64_t b = 9 * (S1 * S1 + 4 * Se * Se + 4 * So * So) - T * T;
  const double u2 = ldexp(1.0, -26);
  double ssw = (double)w / (double)R * u2;
  double ssb = (double)b / (double)(9 * R) * u2;
  double f = (ssb / 8.0) / (ssw / (double)(9 * (R - 1)));

  char what[96];
  snprintf(what, sizeof what, "%s hand-derived F vs published binary64 F", name);
  check_rel(what, f, published_f, 1e-12); /* the derivation itself, to 12 digits */

  palp_stats_anova a;
  snprintf(what, sizeof what, "%s returns ok", name);
  check_true(what, palp_stats_anova_oneway(v, start, 9, &a) == PALP_OK);
  /* 9 significant digits of the exact result for these binary64 inputs. */
  snprintf(what, sizeof what, "%s SS between", name);
  check_rel(what, a.ss_between, ssb, 1e-9);
  snprintf(what, sizeof what, "%s SS within", name);
  check_rel(what, a.ss_within, ssw, 1e-9);
  snprintf(what, sizeof what, "%s F", name);
  check_rel(what, a.f, f, 1e-9);
  /* And the certified value to the 3-4 digits the inputs still carry. */
  snprintf(what, sizeof what, "%s F vs certified (input-limited, 1e-3)", name);
  check_rel(what, a.f, (double)R, 1e-3);
  free(v);
}

/* ---- hand-computed ANOVA and p-values ---------------------------------------------- */
static void test_anova_hand(void) {
  /* Groups {1,2,3}, {2,3,4}, {5,6,7}: means 2, 3, 6, grand mean 11/3.
   * SS_between = 3 [(2-11/3)^2 + (3-11/3)^2 + (6-11/3)^2] = 3 (25 + 4 + 49)/9 = 26,
   * SS_within = 2 + 2 + 2 = 6, df 2 and 6, MS 13 and 1, F = 13.
   * For df1 = 2 the F survival function is closed-form:
   *   Q(F; 2, d2) = (1 + 2F/d2)^(-d2/2) = (1 + 26/6)^(-3) = (3/16)^3 = 27/4096. */
  const double v[9] = {1, 2, 3, 2, 3, 4, 5, 6, 7};
  const size_t start[4] = {0, 3, 6, 9};
  palp_stats_anova a;
  check_true("hand 3 groups ok", palp_stats_anova_oneway(v, start, 3, &a) == PALP_OK);
  check_rel("hand SS between", a.ss_between, 26.0, 1e-14);
  check_rel("hand SS within", a.ss_within, 6.0, 1e-14);
  check_rel("hand SS total", a.ss_total, 32.0, 1e-14);
  check_rel("hand grand mean", a.grand_mean, 11.0 / 3.0, 1e-15);
  check_rel("hand F", a.f, 13.0, 1e-14);
  check_rel("hand p (closed form 27/4096)", a.p, 27.0 / 4096.0, 1e-10);
  check_true("hand flags clear", a.flags == 0);

  /* Two groups {1,2,3}, {4,5,6}: means 2 and 5, grand 3.5, SS_between = 2*3*1.5^2 = 13.5,
   * SS_within = 4, df 1 and 4, F = 13.5. With one numerator df, F = t^2 and
   * p = 2 (1 - T_4(t)), where Student's t with 4 df has the closed form
   *   T_4(t) = 1/2 + (3/8) (t / s) (1 - t^2 / (12 s^2)),  s = sqrt(1 + t^2/4). */
  const double g1[3] = {1, 2, 3}, g2[3] = {4, 5, 6};
  check_true("hand 2 groups ok", palp_stats_anova_two(g1, g2, 3, &a) == PALP_OK);
  double t = sqrt(13.5), s = sqrt(1.0 + 13.5 / 4.0);
  double p = 2.0 * (1.0 - (0.5 + 0.375 * (t / s) * (1.0 - 13.5 / (12.0 * s * s))));
  check_rel("hand 2-group F", a.f, 13.5, 1e-14);
  check_rel("hand 2-group p (Student t, 4 df)", a.p, p, 1e-10);

  /* Shifting the same data by 1e12 (exact for these small integers) must not move
   * F or the sums of squares (9 digits). */
  double v12[9];
  for (int i = 0; i < 9; ++i) v12[i] = v[i] + 1e12;
  check_true("shifted ok", palp_stats_anova_oneway(v12, start, 3, &a) == PALP_OK);
  check_rel("shifted 1e12 SS between", a.ss_between, 26.0, 1e-9);
  check_rel("shifted 1e12 SS within", a.ss_within, 6.0, 1e-9);
  check_rel("shifted 1e12 F", a.f, 13.0, 1e-9);
}

/* Groups far apart: B near 1e12 first (exact in binary64: 1e12 + 0.25 k), A near 1.
 * SS_within = 0.125 (B: deviations -0.25 0 0.25) + 0.02 (A: 1.1 1.2 1.3) = 0.145.
 * Differencing A against a 1e12 shift would round its values to 1.2e-4 and its SS
 * by ~1e-3; each group's spread must survive the gap (1e-12). */
static void test_anova_far_groups(void) {
  const double v[6] = {1e12 + 0.25, 1e12 + 0.5, 1e12 + 0.75, 1.1, 1.2, 1.3};
  const size_t start[3] = {0, 3, 6};
  palp_stats_anova a;
  check_true("far groups ok", palp_stats_anova_oneway(v, start, 2, &a) == PALP_OK);
  check_rel("far groups SS within", a.ss_within, 0.145, 1e-12);
  /* means 1e12 + 0.5 and 1.2: SS_between = 3 * 2 * ((1e12 - 0.7)/2)^2 = 1.5 (1e12 - 0.7)^2 */
  check_rel("far groups SS between", a.ss_between, 1.5 * (1e12 - 0.7) * (1e12 - 0.7), 1e-12);
  check_true("far groups two-array ok", palp_stats_anova_two_n(v, 3, v + 3, 3, &a) == PALP_OK);
  check_rel("far groups two-array SS within", a.ss_within, 0.145, 1e-12);
}

/* palp_stats_anova_offset: SmLs07 as an exact-subtracting caller hands it over.
 * True value = 1e12 + 0.4 (origin) + offset[t] + y: offset = first value of the
 * treatment minus the origin = b(t) + 0.2 - 0.4, y = b(r) - 0.2 (b as above). The
 * certified values (SS 1.68 and 1.80, F 21) must come back to 9 digits. */
static void test_anova_offset(void) {
  double y[9 * 21], off[9];
  size_t start[10];
  for (int t = 1; t <= 9; ++t) {
    start[t - 1] = (size_t)(t - 1) * 21;
    off[t - 1] = 0.1 * smls_digit(t) - 0.2;
    for (int r = 1; r <= 21; ++r) y[(t - 1) * 21 + (r - 1)] = 0.1 * smls_digit(r) - 0.2;
  }
  start[9] = 9 * 21;
  palp_stats_anova a;
  check_true("offset ok", palp_stats_anova_offset(y, start, 9, off, &a) == PALP_OK);
  check_rel("offset SmLs07 SS between", a.ss_between, 1.68, 1e-9);
  check_rel("offset SmLs07 SS within", a.ss_within, 1.80, 1e-9);
  check_rel("offset SmLs07 F", a.f, 21.0, 1e-9);
  check_abs("offset SmLs07 grand mean relative to the origin", a.grand_mean, 0.0, 1e-15);
  check_true("offset NULL -> EINVAL", palp_stats_anova_offset(y, start, 9, NULL, &a) == PALP_EINVAL);
  off[3] = NAN;
  check_true("offset NaN -> EINVAL", palp_stats_anova_offset(y, start, 9, off, &a) == PALP_EINVAL);
}

static void test_anova_edges(void) {
  palp_stats_anova a;
  memset(&a, 0, sizeof a);
  const double v[6] = {1, 2, 3, 4, 5, 6};
  size_t one_group[2] = {0, 6};
  check_true("one group -> EINVAL", palp_stats_anova_oneway(v, one_group, 1, &a) == PALP_EINVAL);
  size_t singleton[3] = {0, 1, 6};
  check_true("group with one value -> EINVAL",
             palp_stats_anova_oneway(v, singleton, 2, &a) == PALP_EINVAL);
  size_t empty[3] = {0, 0, 6};
  check_true("empty group -> EINVAL", palp_stats_anova_oneway(v, empty, 2, &a) == PALP_EINVAL);
  check_true("NULL values -> EINVAL", palp_stats_anova_oneway(NULL, one_group, 2, &a) == PALP_EINVAL);
  const double bad[4] = {1, NAN, 3, 4};
  size_t two[3] = {0, 2, 4};
  check_true("NaN -> EINVAL", palp_stats_anova_oneway(bad, two, 2, &a) == PALP_EINVAL);
  const double inf[4] = {1, 2, INFINITY, 4};
  check_true("inf -> EINVAL", palp_stats_anova_oneway(inf, two, 2, &a) == PALP_EINVAL);
  check_true("two: n = 1 -> EINVAL", palp_stats_anova_two(v, v + 1, 1, &a) == PALP_EINVAL);
  check_true("two: n = 0 -> EINVAL", palp_stats_anova_two(v, v, 0, &a) == PALP_EINVAL);

  /* Constant groups with different levels: SS_within = 0 exactly (the refined mean
   * of 0.1, 0.1, 0.1 is 0.1), F = +inf, p = 0 by definition. */
  const double cw[6] = {0.1, 0.1, 0.1, 0.7, 0.7, 0.7};
  size_t s3[3] = {0, 3, 6};
  check_true("zero within ok", palp_stats_anova_oneway(cw, s3, 2, &a) == PALP_OK);
  check_true("zero within: SS_within exactly 0", a.ss_within == 0.0);
  check_true("zero within: F = +inf, p = 0", isinf(a.f) && a.f > 0 && a.p == 0.0);
  check_true("zero within: flag", a.flags == PALP_STATS_ZERO_WITHIN);
  check_rel("zero within: SS between = 6 * 0.3^2", a.ss_between, 0.54, 1e-14);

  /* Every value equal: F = 0, p = 1 by definition (no evidence of a difference). */
  const double eq[4] = {3.3, 3.3, 3.3, 3.3};
  check_true("all equal ok", palp_stats_anova_oneway(eq, two, 2, &a) == PALP_OK);
  check_true("all equal: F = 0, p = 1", a.f == 0.0 && a.p == 1.0);
  check_true("all equal: flags", a.flags == (PALP_STATS_ZERO_WITHIN | PALP_STATS_ALL_EQUAL));
  check_true("all equal: R^2 = 0", a.r_squared == 0.0);
}

/* ---- RMSE -------------------------------------------------------------------------- */
static void test_rmse(void) {
  /* d = (-0.5, 0, 1, -0.5): sum d^2 = 1.5, RMSE = sqrt(1.5/4) = sqrt(0.375). */
  const double a[4] = {1, 2, 3, 4}, b[4] = {1.5, 2, 2, 4.5};
  double r = -1;
  check_true("rmse ok", palp_stats_rmse(a, b, 4, &r) == PALP_OK);
  check_rel("rmse hand", r, sqrt(0.375), 1e-15);
  check_true("rmse identical = 0", palp_stats_rmse(a, a, 4, &r) == PALP_OK && r == 0.0);
  /* Differences of +-2e300: squares overflow naively; RMSE = 2e300 exactly. */
  const double big_a[2] = {1e300, -1e300}, big_b[2] = {-1e300, 1e300};
  check_true("rmse huge ok", palp_stats_rmse(big_a, big_b, 2, &r) == PALP_OK);
  check_rel("rmse huge", r, 2e300, 1e-15);
  /* a - b = 2e308 overflows binary64; the halves path must still give the
   * representable RMSE = sqrt((2e308)^2 / 4) = 1e308. */
  const double max_a[4] = {1e308, 0, 0, 0}, max_b[4] = {-1e308, 0, 0, 0};
  check_true("rmse overflowing difference ok", palp_stats_rmse(max_a, max_b, 4, &r) == PALP_OK);
  check_rel("rmse overflowing difference", r, 1e308, 1e-15);
  /* Tiny: d = 3e-300 and 4e-300, RMSE = sqrt((9 + 16)/2) 1e-300 = sqrt(12.5) 1e-300. */
  const double t_a[2] = {3e-300, 4e-300}, t_b[2] = {0, 0};
  check_true("rmse tiny ok", palp_stats_rmse(t_a, t_b, 2, &r) == PALP_OK);
  check_rel("rmse tiny", r, sqrt(12.5) * 1e-300, 1e-14);
  check_true("rmse n = 0 -> EINVAL", palp_stats_rmse(a, b, 0, &r) == PALP_EINVAL);
  const double nan_b[4] = {1, NAN, 2, 3};
  check_true("rmse NaN -> EINVAL", palp_stats_rmse(a, nan_b, 4, &r) == PALP_EINVAL);
}

/* ---- Bland-Altman ---------------------------------------------------------------------- */
static void test_bland_altman(void) {
  /*
   * Worked example by hand, n = 10 (think cm of displacement):
   *   b = 1.2 1.5 0.8 2.0 1.1 0.9 1.7 1.3 1.6 1.4          mean 13.5/10 = 1.35
   *   d = 0.1 -0.1 0.2 0.0 -0.2 0.1 0.0 -0.1 0.1 0.9       sum 1.0, bias = 0.1
   *   a = b + d                                            mean 1.45
   *   d - bias = 0 -0.2 0.1 -0.1 -0.3 0 -0.1 -0.2 0 0.8
   *   squares  = 0 .04 .01 .01 .09 0 .01 .04 0 .64         sum 0.84
   *   SD = sqrt(0.84 / 9) = 0.30550504633...
   *   LoA = 0.1 -+ 1.96 SD = [-0.49879, 0.69879]
   *   band = 0.1 -+ 2 SD = [-0.51101, 0.71101]
   *   |d - bias| <= 2 SD = 0.61101 for all but the last (0.8): 9 of 10 -> 90 %,
   *   also 9 of 10 inside 1.96 SD = 0.59879.
   */
  const double b[10] = {1.2, 1.5, 0.8, 2.0, 1.1, 0.9, 1.7, 1.3, 1.6, 1.4};
  const double d[10] = {0.1, -0.1, 0.2, 0.0, -0.2, 0.1, 0.0, -0.1, 0.1, 0.9};
  double a[10];
  for (int i = 0; i < 10; ++i) a[i] = b[i] + d[i];
  palp_stats_ba ba;
  check_true("BA ok", palp_stats_bland_altman(a, b, 10, &ba) == PALP_OK);
  double sd = sqrt(0.84 / 9.0);
  /* 1e-12: a = b + d is rounded once per element (about 1e-16 of 2.0). */
  check_rel("BA bias", ba.bias, 0.1, 1e-12);
  check_rel("BA SD", ba.sd, sd, 1e-12);
  check_rel("BA mean a", ba.mean_a, 1.45, 1e-14);
  check_rel("BA mean b", ba.mean_b, 1.35, 1e-14);
  check_rel("BA LoA lower", ba.loa_lower, 0.1 - 1.96 * sd, 1e-12);
  check_rel("BA LoA upper", ba.loa_upper, 0.1 + 1.96 * sd, 1e-12);
  check_rel("BA band lower", ba.band_lower, 0.1 - 2.0 * sd, 1e-12);
  check_rel("BA band upper", ba.band_upper, 0.1 + 2.0 * sd, 1e-12);
  check_true("BA 9 of 10 within 2 SD", ba.within_band == 9);
  check_true("BA 9 of 10 within LoA", ba.within_loa == 9);
  check_abs("BA agreement 0.9", ba.agreement, 0.9, 1e-15);

  /* Without the outlier (first 9 pairs): d = 0.1 -0.1 0.2 0 -0.2 0.1 0 -0.1 0.1,
   * sum 0.1, bias = 0.1/9; every |d - bias| <= 0.2111 while SD = sqrt((0.13 - 0.01/9)/8)
   * = 0.1269..., 2 SD = 0.2539: all 9 inside -> 100 %. */
  check_true("BA 9 ok", palp_stats_bland_altman(a, b, 9, &ba) == PALP_OK);
  check_rel("BA 9 bias", ba.bias, 0.1 / 9.0, 1e-11);
  check_rel("BA 9 SD", ba.sd, sqrt((0.13 - 0.01 / 9.0) / 8.0), 1e-11);
  check_true("BA 9 all inside", ba.within_band == 9 && ba.agreement == 1.0);

  /* Ill-conditioned: both series near 1e12 (exact doubles: multiples of 2^-13 = 1.220703125e-4 after 1e12).
   * d = (1, -1, 1, -1) 2^-10 => bias 0, SD = sqrt(4/3) 2^-10. */
  const double q = ldexp(1.0, -10);
  const double ia[4] = {1e12 + q, 1e12, 1e12 + q, 1e12};
  const double ib[4] = {1e12, 1e12 + q, 1e12, 1e12 + q};
  check_true("BA 1e12 ok", palp_stats_bland_altman(ia, ib, 4, &ba) == PALP_OK);
  check_abs("BA 1e12 bias", ba.bias, 0.0, 1e-25);
  check_rel("BA 1e12 SD", ba.sd, sqrt(4.0 / 3.0) * q, 1e-14);

  /* Constant difference: SD = 0, every pair on the bias, agreement 100 %. */
  const double ca[3] = {1.0, 2.0, 3.0}, cb[3] = {0.5, 1.5, 2.5};
  check_true("BA constant ok", palp_stats_bland_altman(ca, cb, 3, &ba) == PALP_OK);
  check_true("BA constant: SD 0, agreement 1", ba.sd == 0.0 && ba.agreement == 1.0);
  check_abs("BA constant bias", ba.bias, 0.5, 0.0);

  check_true("BA n = 1 -> EINVAL", palp_stats_bland_altman(a, b, 1, &ba) == PALP_EINVAL);
  check_true("BA n = 0 -> EINVAL", palp_stats_bland_altman(a, b, 0, &ba) == PALP_EINVAL);
  const double nan_a[3] = {1.0, NAN, 3.0};
  check_true("BA NaN -> EINVAL", palp_stats_bland_altman(nan_a, cb, 3, &ba) == PALP_EINVAL);
}

static void test_paper_criteria(void) {
  palp_stats_anova a;
  palp_stats_ba ba;
  memset(&a, 0, sizeof a);
  memset(&ba, 0, sizeof ba);
  /* Table V, Distr. I: p = 0.12, agreement 95.2 % -> meets. */
  a.p = 0.12;
  ba.agreement = 0.952;
  check_true("paper: p .12, 95.2% meets", palp_stats_meets_paper_criteria(&a, &ba) == 1);
  /* "more than 95 %": exactly 95 % (19 of 20) fails. */
  ba.agreement = 19.0 / 20.0;
  check_true("paper: exactly 95% fails", palp_stats_meets_paper_criteria(&a, &ba) == 0);
  /* "p-value of more than 0.05": p = 0.05 fails, p = 0.04 fails. */
  ba.agreement = 0.99;
  a.p = 0.05;
  check_true("paper: p = 0.05 fails", palp_stats_meets_paper_criteria(&a, &ba) == 0);
  a.p = 0.04;
  check_true("paper: p = 0.04 fails", palp_stats_meets_paper_criteria(&a, &ba) == 0);
  check_true("paper: NULL -> 0", palp_stats_meets_paper_criteria(NULL, &ba) == 0);
}

static void test_mean_ssd(void) {
  /* NIST StRD univariate NumAcc4 pattern: 1e7 + 0.2 once, 0.1 and 0.3 500 times each.
   * Certified mean 10000000.2, SD 0.1 -> SSD = 1000 * 0.01 = 10 (input rounding at
   * 1e7 is 1e-9 of the spread: 1e-6 relative is plenty and still catches the
   * one-pass formula, which loses every digit here). */
  static double x[1001];
  x[0] = 10000000.2;
  for (int i = 1; i <= 1000; ++i) x[i] = i % 2 ? 10000000.1 : 10000000.3;
  double m, ssd;
  palp_stats_mean_ssd(x, 1001, &m, &ssd);
  check_rel("NumAcc4 mean", m, 10000000.2, 1e-15);
  check_rel("NumAcc4 SSD", ssd, 10.0, 1e-6);
}

/* ---- sums of squares at the ends of the double range (session 81 review) ----------
 * Deviations above ~1.3e154 square to inf (the compensated sum then made it NaN and the
 * ANOVA reported "every value identical", F 0, p 1); below ~1.5e-154 they square to 0.
 * By hand, groups {1, 1.1} and {-1, -1} (any common unit u):
 *   means 1.05, -1; grand mean 0.025; SS_b = 2 (1.025^2 + 1.025^2) = 4.2025 u^2,
 *   SS_w = 2 (0.05^2) = 0.005 u^2, F(1, 2) = (4.2025 / 1) / (0.005 / 2) = 1681.
 *   With 2 denominator df, F(1, 2) = t^2 and P(|t_2| > t) = 1 - t / sqrt(t^2 + 2):
 *   p = 1 - 41 / sqrt(1683) = 5.943536929e-4 (python: 1 - 41/math.sqrt(1683)).
 *   R^2 = 4.2025 / 4.2075 = 1681 / 1683. The same F, p, R^2 for u = 1e300 and 1e-300.
 * Tolerance 1e-12: 1.1e300 and 1.1e-300 carry one rounding (1.1e-16 relative), which
 * the 0.1 spread inside group A amplifies 11 times. */
static void test_scaled_sums(void) {
  const double want_p = 5.943536929214899e-4;
  const double units[3] = {1.0, 1e300, 1e-300};
  size_t two[3] = {0, 2, 4};
  for (int k = 0; k < 3; ++k) {
    const double u = units[k];
    const double v[4] = {1.0 * u, 1.1 * u, -1.0 * u, -1.0 * u};
    char what[96];
    palp_stats_anova a;
    snprintf(what, sizeof what, "scaled anova u=%g ok", u);
    check_true(what, palp_stats_anova_oneway(v, two, 2, &a) == PALP_OK);
    snprintf(what, sizeof what, "scaled anova u=%g F = 1681", u);
    check_rel(what, a.f, 1681.0, 1e-12);
    snprintf(what, sizeof what, "scaled anova u=%g p = 1 - 41/sqrt(1683)", u);
    check_rel(what, a.p, want_p, 1e-9);
    snprintf(what, sizeof what, "scaled anova u=%g R^2 = 1681/1683", u);
    check_rel(what, a.r_squared, 1681.0 / 1683.0, 1e-12);
    snprintf(what, sizeof what, "scaled anova u=%g: no zero-within/all-equal flag", u);
    check_true(what, (a.flags & (PALP_STATS_ZERO_WITHIN | PALP_STATS_ALL_EQUAL)) == 0);
    snprintf(what, sizeof what, "scaled anova_two_n u=%g F = 1681", u);
    check_true(what, palp_stats_anova_two_n(v, 2, v + 2, 2, &a) == PALP_OK);
    check_rel(what, a.f, 1681.0, 1e-12);
    double m, sd;
    palp_stats_mean_sd(v, 2, &m, &sd);
    /* SD of {1, 1.1} u = 0.05 sqrt(2) u = 0.0707106781186548 u */
    snprintf(what, sizeof what, "mean_sd u=%g SD = 0.05 sqrt(2) u", u);
    check_rel(what, sd, 0.07071067811865475 * u, 1e-12);
  }
  palp_stats_anova a;
  const double v[4] = {1e300, 1.1e300, -1e300, -1e300};
  check_true("scaled anova 1e300 ok", palp_stats_anova_oneway(v, two, 2, &a) == PALP_OK);
  check_true("scaled anova 1e300: SS 4.2e600 flagged beyond DBL_MAX",
             isinf(a.ss_between) && (a.flags & PALP_STATS_SS_OVERFLOW));
  check_rel("scaled anova 1: SS_b = 4.2025", (palp_stats_anova_oneway((double[]){1, 1.1, -1, -1}, two, 2, &a),
            a.ss_between), 4.2025, 1e-12);
  check_true("scaled anova 1: not flagged", a.flags == 0);
  /* A group {1e308, -1e308}: its deviations exceed DBL_MAX. An error, never "all equal". */
  const double wide[4] = {1e308, -1e308, 0.0, 1.0};
  check_true("deviation beyond DBL_MAX -> EINVAL",
             palp_stats_anova_oneway(wide, two, 2, &a) == PALP_EINVAL);

  /* Bland-Altman: a = (1, 1.1) u, b = (-1, -1) u: d = (2, 2.1) u, bias 2.05 u,
   * SD = 0.05 sqrt(2) u = 0.1 u / sqrt(2); both pairs 0.05 u from the bias, inside 2 SD. */
  for (int k = 0; k < 3; ++k) {
    const double u = units[k];
    const double ba_a[2] = {1.0 * u, 1.1 * u}, ba_b[2] = {-1.0 * u, -1.0 * u};
    palp_stats_ba ba;
    char what[96];
    snprintf(what, sizeof what, "scaled BA u=%g ok", u);
    check_true(what, palp_stats_bland_altman(ba_a, ba_b, 2, &ba) == PALP_OK);
    snprintf(what, sizeof what, "scaled BA u=%g SD = 0.1 u / sqrt(2)", u);
    check_rel(what, ba.sd, 0.07071067811865475 * u, 1e-12);
    snprintf(what, sizeof what, "scaled BA u=%g: 2 of 2 inside, agreement 1", u);
    check_true(what, ba.within_band == 2 && ba.agreement == 1.0);
  }
  /* The reviewer's tiny case: a = (1e-300, 2e-300), b = 0: d - bias = -+0.5e-300,
   * SD = 0.5e-300 sqrt(2) = 7.0710678e-301, both inside. */
  const double ta[2] = {1e-300, 2e-300}, tb[2] = {0.0, 0.0};
  palp_stats_ba ba;
  check_true("tiny BA ok", palp_stats_bland_altman(ta, tb, 2, &ba) == PALP_OK);
  check_rel("tiny BA SD", ba.sd, 0.7071067811865476e-300, 1e-12);
  check_true("tiny BA 100 %", ba.within_band == 2 && ba.agreement == 1.0);
}

int main(void) {
  test_sirstv();
  test_atmwtag();
  test_smls_certified("SmLs01", "1", 21);
  test_smls_certified("SmLs02", "1", 201);
  test_smls_certified("SmLs03", "1", 2001);
  test_smls_certified("SmLs04", "1000000", 21);
  test_smls_certified("SmLs05", "1000000", 201);
  test_smls_certified("SmLs06", "1000000", 2001);
  test_smls_ill_conditioned("SmLs07", 21, 21.00081188781877);
  test_smls_ill_conditioned("SmLs08", 201, 201.01300409594845);
  test_smls_ill_conditioned("SmLs09", 2001, 2001.1349262209505);
  test_anova_hand();
  test_anova_far_groups();
  test_anova_offset();
  test_anova_edges();
  test_rmse();
  test_bland_altman();
  test_paper_criteria();
  test_mean_ssd();
  test_scaled_sums();
  printf("%d checks, %d failures\n", checks, failures);
  return failures ? 1 : 0;
}
