/*
 * serial_cmd.c - palp-stats commands for serially correlated or clustered data
 * (docs/statistics.md, "Sound statistics"): the AR(1) effective sample size, the
 * moving-block bootstrap of a mean, Schuirmann's TOST equivalence test, and
 * Bland & Altman's (2007) repeated-measures limits of agreement.
 *
 *   palp-stats neff FILE.csv --value COL | --a COL --b COL
 *   palp-stats bootstrap FILE.csv (--value COL | --a COL --b COL) [--block B] [--resamples N]
 *                                 [--seed S] [--level L]
 *   palp-stats tost FILE.csv (--value COL | --a COL --b COL) (--margin M | --lower L --upper U)
 *                            [--alpha A] [--serial | --unit COL]
 *   palp-stats ba-rm FILE.csv --subject COL (--value COL | --a COL --b COL)
 *
 * Rows are taken in file order (the order is the time axis for neff and bootstrap).
 * A single column's values are read as exact decimals and taken relative to the first
 * one before conversion, as the other commands do; a - b is subtracted exactly per row.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "label_index.h"
#include "stats.h"

typedef struct series {
  size_t n, skipped;
  double *x;      /* value - origin, or a - b */
  double origin;  /* added back for means and estimates */
  int *label;     /* [n] index of the row's label (unit or subject), when asked */
  int labels;     /* distinct labels, in order of first appearance */
  size_t *first_row; /* [labels] first data row of each label */
  int label_col;
} series;

static void series_free(series *s) {
  free(s->x), free(s->label), free(s->first_row);
  memset(s, 0, sizeof *s);
}

/* The measured column(s) and, when label_flag is set, the label column. */
static int read_series(const options *o, const palp_csv *csv, const char *label_col, const char *label_flag,
                       series *s) {
  memset(s, 0, sizeof *s);
  int ca = -1, cb = -1, cl = -1;
  if (o->value) {
    if (find_column(csv, o, o->value, "--value", &ca) < 0) return -1;
  } else {
    if (find_column(csv, o, o->a, "--a", &ca) < 0) return -1;
    if (find_column(csv, o, o->b, "--b", &cb) < 0) return -1;
    if (same_column(o, csv, ca, "--a", o->a, cb, "--b", o->b, "a - b needs two different columns")) return -2;
  }
  s->label_col = -1;
  if (label_col) {
    if (find_column(csv, o, label_col, label_flag, &cl) < 0) return -1;
    s->label_col = cl;
    const char *fa = o->value ? "--value" : "--a", *wa = o->value ? o->value : o->a;
    const char *labels = "it must name the column of labels, not a measured one";
    if (same_column(o, csv, cl, label_flag, label_col, ca, fa, wa, labels) ||
        (cb >= 0 && same_column(o, csv, cl, label_flag, label_col, cb, "--b", o->b, labels)))
      return -2;
  }
  if (csv->nrows == 0) {
    data_error(o->log, "%s:%zu: no data rows after the header", o->file, csv->header_line);
    return -1;
  }
  const size_t nr = csv->nrows;
  s->x = malloc(nr * sizeof *s->x);
  s->label = malloc(nr * sizeof *s->label);
  s->first_row = malloc(nr * sizeof *s->first_row);
  if (!s->x || !s->label || !s->first_row) {
    data_error(o->log, "out of memory");
    series_free(s);
    return -1;
  }
  label_index index = {0};
  if (cl >= 0 && label_index_init(&index, 64) < 0) {
    data_error(o->log, "out of memory");
    series_free(s);
    return -1;
  }
  palp_dec first;
  int have_first = 0;
  for (size_t r = 0; r < nr; ++r) {
    if (o->skip_empty && (cell_is_empty(csv, r, ca) || (cb >= 0 && cell_is_empty(csv, r, cb)) ||
                          (cl >= 0 && cell_is_empty(csv, r, cl)))) {
      s->skipped++;
      continue;
    }
    palp_dec a, b;
    if (cell_number(csv, o, r, ca, &a) < 0 || (cb >= 0 && cell_number(csv, o, r, cb, &b) < 0)) {
      label_index_free(&index);
      series_free(s);
      return -1;
    }
    if (cb >= 0) s->x[s->n] = palp_dec_sub(&a, &b);
    else {
      if (!have_first) first = a, have_first = 1, s->origin = a.value;
      s->x[s->n] = palp_dec_sub(&a, &first);
    }
    if (!isfinite(s->x[s->n])) {
      data_error(o->log, "%s:%zu: the value is too large to analyse", o->file, csv->line[r]);
      label_index_free(&index);
      series_free(s);
      return -1;
    }
    if (cl >= 0) {
      const char *lab = palp_csv_cell(csv, r, cl);
      if (!lab[0]) {
        data_error(o->log, "%s:%zu: column \"%s\" (column %d, %s) is empty; every row needs a label (or pass "
                   "--skip-empty)",
                   o->file, csv->line[r], csv->header[cl], cl + 1, label_flag);
        label_index_free(&index);
        series_free(s);
        return -1;
      }
      int added, g = label_index_get(&index, lab, &added); /* O(1) expected, not a scan */
      if (g < 0) {
        data_error(o->log, "out of memory");
        label_index_free(&index);
        series_free(s);
        return -1;
      }
      if (added) s->first_row[s->labels++] = r;
      s->label[s->n] = g;
    }
    s->n++;
  }
  label_index_free(&index);
  if (s->n == 0) {
    data_error(o->log, "%s: every data row was skipped as empty; nothing to analyse", o->file);
    series_free(s);
    return -1;
  }
  if (s->skipped) palp_log_info(o->log, "note: %zu rows with empty cells skipped", s->skipped);
  return 0;
}

static const char *what(const options *o) { return o->value ? o->value : "a - b"; }

/* ---- neff ----------------------------------------------------------------------------- */

int run_neff(const options *o, const palp_csv *csv) {
  series s;
  const int rd = read_series(o, csv, NULL, NULL, &s);
  if (rd < 0) return read_exit(rd);
  if (s.n < 3) {
    data_error(o->log, "%s: %zu values; the lag-1 autocorrelation needs at least 3", o->file, s.n);
    series_free(&s);
    return EXIT_DATA;
  }
  double mean, sd, r1;
  palp_stats_mean_sd(s.x, s.n, &mean, &sd);
  if (palp_stats_autocorr1(s.x, s.n, &r1) != 0) {
    data_error(o->log, "%s: every value is the same; a constant series has no autocorrelation", o->file);
    series_free(&s);
    return EXIT_DATA;
  }
  const double neff = palp_stats_neff_ar1(s.n, r1);
  const size_t block = palp_stats_block_length_ar1(s.n, r1);
  mean += s.origin;
  if (o->json) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "command", "neff");
    cJSON_AddStringToObject(j, "file", o->file);
    cJSON_AddNumberToObject(j, "n", (double)s.n);
    cJSON_AddNumberToObject(j, "mean", mean);
    cJSON_AddNumberToObject(j, "sd", sd);
    cJSON_AddNumberToObject(j, "r1", r1);
    cJSON_AddNumberToObject(j, "n_eff", neff);
    cJSON_AddNumberToObject(j, "se_iid", sd / sqrt((double)s.n));
    cJSON_AddNumberToObject(j, "se_ar1", sd / sqrt(neff));
    cJSON_AddNumberToObject(j, "block_length", (double)block);
    print_json(j);
    cJSON_Delete(j);
  } else {
    printf("Effective sample size of \"%s\" (%s, %zu values in file order)\n\n", what(o), o->file, s.n);
    printf("  %-40s %.9g\n", "mean", mean);
    printf("  %-40s %.9g\n", "SD", sd);
    printf("  %-40s %.9g\n", "lag-1 autocorrelation r1", r1);
    printf("  %-40s %.6g  (n (1 - r1) / (1 + r1), within [1, n])\n", "AR(1) effective sample size n_eff", neff);
    printf("  %-40s %.9g\n", "SE of the mean, independent (SD/sqrt n)", sd / sqrt((double)s.n));
    printf("  %-40s %.9g\n", "SE of the mean, AR(1) (SD/sqrt n_eff)", sd / sqrt(neff));
    printf("  %-40s %zu  (Politis & White, AR(1) plug-in)\n", "moving-block length", block);
  }
  series_free(&s);
  return 0;
}

/* ---- bootstrap -------------------------------------------------------------------------- */

int run_bootstrap(const options *o, const palp_csv *csv) {
  series s;
  const int rd = read_series(o, csv, NULL, NULL, &s);
  if (rd < 0) return read_exit(rd);
  if (s.n < 2) {
    data_error(o->log, "%s: %zu value; the bootstrap needs at least 2", o->file, s.n);
    series_free(&s);
    return EXIT_DATA;
  }
  size_t block = (size_t)o->block;
  double r1 = 0.0;
  if (!block) block = s.n >= 3 && palp_stats_autocorr1(s.x, s.n, &r1) == 0 ? palp_stats_block_length_ar1(s.n, r1) : 1;
  if (block > s.n) {
    data_error(o->log, "%s: --block %zu is longer than the series (%zu values)", o->file, block, s.n);
    series_free(&s);
    return EXIT_DATA;
  }
  const size_t B = o->resamples ? (size_t)o->resamples : 10000;
  double *work = malloc(B * sizeof *work);
  palp_stats_boot bt;
  int rc = work ? palp_stats_block_bootstrap_mean(s.x, s.n, block, B, o->seed, o->level ? o->level : 0.90, work, &bt)
                : -1;
  free(work);
  if (rc) {
    data_error(o->log, "%s: the bootstrap could not be computed (error %d)", o->file, rc);
    series_free(&s);
    return EXIT_DATA;
  }
  bt.mean += s.origin, bt.ci_lower += s.origin, bt.ci_upper += s.origin;
  if (o->json) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "command", "bootstrap");
    cJSON_AddStringToObject(j, "file", o->file);
    cJSON_AddNumberToObject(j, "n", (double)s.n);
    cJSON_AddNumberToObject(j, "mean", bt.mean);
    cJSON_AddNumberToObject(j, "se", bt.se);
    cJSON_AddNumberToObject(j, "ci_lower", bt.ci_lower);
    cJSON_AddNumberToObject(j, "ci_upper", bt.ci_upper);
    cJSON_AddNumberToObject(j, "level", bt.level);
    cJSON_AddNumberToObject(j, "block", (double)bt.block);
    cJSON_AddNumberToObject(j, "blocks", (double)bt.blocks);
    cJSON_AddNumberToObject(j, "resamples", (double)bt.resamples);
    cJSON_AddNumberToObject(j, "seed", (double)o->seed);
    print_json(j);
    cJSON_Delete(j);
  } else {
    printf("Moving-block bootstrap of the mean of \"%s\" (%s, %zu values in file order)\n\n", what(o), o->file, s.n);
    printf("  %-30s %.9g\n", "mean", bt.mean);
    printf("  %-30s %.9g\n", "bootstrap SE", bt.se);
    printf("  %-30s [%.9g, %.9g]\n", "percentile interval", bt.ci_lower, bt.ci_upper);
    printf("  %-30s %.3g\n", "level", bt.level);
    printf("  %-30s %zu%s, %zu blocks per resample\n", "block length", bt.block, o->block ? "" : " (AR(1) rule)",
           bt.blocks);
    printf("  %-30s %zu, seed %llu\n", "resamples", bt.resamples, o->seed);
    if (bt.blocks < 4)
      printf("  note: fewer than 4 blocks per resample: the resamples are near copies of the series and the SE is "
             "too small to trust\n");
  }
  series_free(&s);
  return 0;
}

/* ---- tost --------------------------------------------------------------------------------- */

int run_tost(const options *o, const palp_csv *csv) {
  series s;
  const int rd = read_series(o, csv, o->unit, "--unit", &s);
  if (rd < 0) return read_exit(rd);
  double lower = o->have_margin ? -o->margin : o->lower, upper = o->have_margin ? o->margin : o->upper;
  const double alpha = o->alpha ? o->alpha : 0.05;
  double est = 0, se = 0, df = 0, r1 = NAN, neff = NAN;
  size_t nobs = s.n;
  const char *mode = o->unit ? "units" : o->serial ? "ar1" : "iid";
  int rc = EXIT_DATA;
  double *m = NULL;
  if (o->unit) {
    /* one observation per unit: the unit's mean */
    m = calloc((size_t)s.labels, sizeof *m);
    size_t *cnt = calloc((size_t)s.labels, sizeof *cnt);
    if (!m || !cnt) {
      free(cnt);
      data_error(o->log, "out of memory");
      goto done;
    }
    for (size_t i = 0; i < s.n; ++i) m[s.label[i]] += s.x[i], cnt[s.label[i]]++;
    for (int g = 0; g < s.labels; ++g) m[g] /= (double)cnt[g];
    free(cnt);
    nobs = (size_t)s.labels;
    if (nobs < 2) {
      data_error(o->log, "%s: one unit in column \"%s\"; a t test over units needs at least 2", o->file, o->unit);
      goto done;
    }
    double sd;
    palp_stats_mean_sd(m, nobs, &est, &sd);
    se = sd / sqrt((double)nobs);
    df = (double)(nobs - 1);
  } else {
    if (s.n < (o->serial ? 3u : 2u)) {
      data_error(o->log, "%s: %zu values; too few for a t test", o->file, s.n);
      goto done;
    }
    double sd;
    palp_stats_mean_sd(s.x, s.n, &est, &sd);
    if (o->serial) {
      if (palp_stats_autocorr1(s.x, s.n, &r1) != 0) r1 = 0.0;
      neff = palp_stats_neff_ar1(s.n, r1);
      if (neff < 2.0) {
        data_error(o->log, "%s: the effective sample size is %.3g (r1 = %.4g): fewer than 2 independent values, so "
                   "no t reference exists; the series cannot be tested on its own",
                   o->file, neff, r1);
        goto done;
      }
      se = sd / sqrt(neff);
      df = neff - 1.0;
    } else {
      se = sd / sqrt((double)s.n);
      df = (double)(s.n - 1);
    }
  }
  est += s.origin;
  palp_stats_tost t;
  if (palp_stats_tost_t(est, se, df, lower, upper, alpha, &t) != 0) {
    data_error(o->log, "%s: TOST could not be computed (check the margins and --alpha)", o->file);
    goto done;
  }
  if (o->json) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "command", "tost");
    cJSON_AddStringToObject(j, "file", o->file);
    cJSON_AddStringToObject(j, "mode", mode);
    cJSON_AddNumberToObject(j, "n", (double)s.n);
    cJSON_AddNumberToObject(j, "observations", (double)nobs);
    if (o->serial) {
      cJSON_AddNumberToObject(j, "r1", r1);
      cJSON_AddNumberToObject(j, "n_eff", neff);
    }
    cJSON_AddNumberToObject(j, "estimate", t.estimate);
    cJSON_AddNumberToObject(j, "se", t.se);
    cJSON_AddNumberToObject(j, "df", t.df);
    cJSON_AddNumberToObject(j, "lower", t.lower);
    cJSON_AddNumberToObject(j, "upper", t.upper);
    cJSON_AddNumberToObject(j, "alpha", t.alpha);
    cJSON_AddNumberToObject(j, "t_lower", t.t_lower);
    cJSON_AddNumberToObject(j, "t_upper", t.t_upper);
    cJSON_AddNumberToObject(j, "p", t.p);
    cJSON_AddNumberToObject(j, "ci_lower", t.ci_lower);
    cJSON_AddNumberToObject(j, "ci_upper", t.ci_upper);
    cJSON_AddBoolToObject(j, "equivalent", t.equivalent);
    print_json(j);
    cJSON_Delete(j);
  } else {
    printf("TOST equivalence of the mean of \"%s\" within (%.6g, %.6g) (%s, %zu values)\n\n", what(o), lower, upper,
           o->file, s.n);
    if (o->unit) printf("  observations: the means of %zu units (column \"%s\")\n", nobs, o->unit);
    else if (o->serial) printf("  observations: %zu serial values, AR(1) r1 = %.4g, n_eff = %.4g\n", s.n, r1, neff);
    else printf("  observations: %zu values taken as independent\n", s.n);
    printf("  %-30s %.9g\n", "estimate (mean)", t.estimate);
    printf("  %-30s %.9g  (df %.4g)\n", "standard error", t.se, t.df);
    printf("  %-30s t_L = %.6g, t_U = %.6g\n", "one-sided statistics", t.t_lower, t.t_upper);
    printf("  %-30s %.6g\n", "p (larger one-sided p)", t.p);
    char lab[40];
    snprintf(lab, sizeof lab, "%.0f%% interval", 100.0 * (1.0 - 2.0 * alpha));
    printf("  %-30s [%.9g, %.9g]\n", lab, t.ci_lower, t.ci_upper);
    printf("\n  %s at alpha = %.3g per side: the %.0f%% interval %s inside the margins\n",
           t.equivalent ? "EQUIVALENT" : "NOT shown equivalent", alpha, 100.0 * (1.0 - 2.0 * alpha),
           t.equivalent ? "lies" : "does not lie");
  }
  rc = 0;
done:
  free(m);
  series_free(&s);
  return rc;
}

/* ---- ba-rm -------------------------------------------------------------------------------- */

int run_ba_rm(const options *o, const palp_csv *csv) {
  series s;
  const int rd = read_series(o, csv, o->subject, "--subject", &s);
  if (rd < 0) return read_exit(rd);
  int rc = EXIT_DATA;
  double *d = malloc(s.n * sizeof *d);
  size_t *start = calloc((size_t)s.labels + 1, sizeof *start), *fill = calloc((size_t)s.labels + 1, sizeof *fill);
  if (!d || !start || !fill) {
    data_error(o->log, "out of memory");
    goto done;
  }
  if (s.labels < 2) {
    data_error(o->log, "%s: one subject in column \"%s\"; repeated-measures limits need at least 2", o->file,
               o->subject);
    goto done;
  }
  /* group the rows by subject, keeping file order inside each */
  for (size_t i = 0; i < s.n; ++i) start[s.label[i] + 1]++;
  for (int g = 0; g < s.labels; ++g) {
    if (start[g + 1] < 2) {
      data_error(o->log, "%s:%zu: subject \"%s\" has one pair; each subject needs at least 2 to estimate the "
                 "within-subject spread (check the label's spelling)",
                 o->file, csv->line[s.first_row[g]], palp_csv_cell(csv, s.first_row[g], s.label_col));
      goto done;
    }
    start[g + 1] += start[g];
  }
  for (int g = 0; g < s.labels; ++g) fill[g] = start[g];
  for (size_t i = 0; i < s.n; ++i) d[fill[s.label[i]]++] = s.x[i];
  palp_stats_ba_rm ba;
  if (palp_stats_bland_altman_rm(d, start, s.labels, &ba) != 0) {
    data_error(o->log, "%s: the repeated-measures limits could not be computed", o->file);
    goto done;
  }
  ba.bias += s.origin, ba.loa_lower += s.origin, ba.loa_upper += s.origin;
  if (o->json) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "command", "ba-rm");
    cJSON_AddStringToObject(j, "file", o->file);
    cJSON_AddNumberToObject(j, "subjects", ba.subjects);
    cJSON_AddNumberToObject(j, "n", (double)ba.n);
    cJSON_AddNumberToObject(j, "bias", ba.bias);
    cJSON_AddNumberToObject(j, "ms_between", ba.ms_between);
    cJSON_AddNumberToObject(j, "ms_within", ba.ms_within);
    cJSON_AddNumberToObject(j, "divisor", ba.divisor);
    cJSON_AddNumberToObject(j, "var_between", ba.var_between);
    cJSON_AddNumberToObject(j, "var_within", ba.var_within);
    cJSON_AddNumberToObject(j, "sd_total", ba.sd_total);
    cJSON_AddNumberToObject(j, "loa_lower", ba.loa_lower);
    cJSON_AddNumberToObject(j, "loa_upper", ba.loa_upper);
    print_json(j);
    cJSON_Delete(j);
  } else {
    printf("Repeated-measures Bland-Altman of \"%s\" by \"%s\" (%s, %d subjects, %zu pairs)\n\n", what(o), o->subject,
           o->file, ba.subjects, ba.n);
    printf("  %-36s %.9g\n", "bias (mean of all differences)", ba.bias);
    printf("  %-36s %.9g\n", "MS between subjects", ba.ms_between);
    printf("  %-36s %.9g\n", "MS within subjects", ba.ms_within);
    printf("  %-36s %.9g\n", "divisor m0", ba.divisor);
    printf("  %-36s %.9g\n", "between-subject variance", ba.var_between);
    printf("  %-36s %.9g\n", "within-subject variance", ba.var_within);
    printf("  %-36s %.9g\n", "SD of a single difference", ba.sd_total);
    printf("  %-36s [%.9g, %.9g]\n", "limits bias -+ 1.96 SD", ba.loa_lower, ba.loa_upper);
  }
  rc = 0;
done:
  free(d), free(start), free(fill);
  series_free(&s);
  return rc;
}
