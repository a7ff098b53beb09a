/*
 * palp-stats - the paper's agreement statistics on your own CSV data.
 *
 *   palp-stats anova FILE.csv --group COL --value COL [--json]
 *   palp-stats bland-altman FILE.csv --a COL --b COL [--json] [--svg PLOT.svg]
 *   palp-stats rmse FILE.csv --a COL --b COL [--json]
 *
 * Exit status: 0 results printed, 1 the data or file cannot be used (the message
 * says where and why), 2 the command line is wrong.
 *
 * Every numeric cell is read as an exact decimal and one data value is subtracted
 * from all of them before conversion to binary64 (see decimal.h), so data with
 * many constant leading digits lose nothing.
 */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <cjson/cJSON.h>

#include "csv.h"
#include "decimal.h"
#include "stats.h"
#include "svg_plot.h"
#include "palp_app.h"
#include "cli.h"
#include "label_index.h"

#define STATS_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_LOG | PALP_APP_OPT_VERBOSE)

static void usage(FILE *to) {
  fputs(
      "usage:\n"
      "  palp-stats anova FILE.csv --group COL --value COL [options]\n"
      "  palp-stats bland-altman FILE.csv --a COL --b COL [options]\n"
      "  palp-stats rmse FILE.csv --a COL --b COL [options]\n"
      "  palp-stats neff FILE.csv (--value COL | --a COL --b COL) [options]\n"
      "  palp-stats bootstrap FILE.csv (--value COL | --a COL --b COL) [--block B]\n"
      "             [--resamples N] [--seed S] [--level L] [options]\n"
      "  palp-stats tost FILE.csv (--value COL | --a COL --b COL)\n"
      "             (--margin M | --lower L --upper U) [--alpha A] [--serial | --unit COL]\n"
      "  palp-stats ba-rm FILE.csv --subject COL (--value COL | --a COL --b COL)\n"
      "\n"
      "anova         one-way ANOVA of the value column across the groups named in\n"
      "              the group column (at least 2 groups, 2 values per group)\n"
      "bland-altman  agreement of two paired columns (a - b): bias, SD, limits of\n"
      "              agreement, share within bias +- 2 SD, RMSE and the ANOVA of a\n"
      "              against b: one row of the paper's Tables V/VI and its verdict\n"
      "rmse          root-mean-square difference of two paired columns\n"
      "neff          lag-1 autocorrelation of a series (rows in file order), its AR(1)\n"
      "              effective sample size n (1 - r1)/(1 + r1) and the SE of its mean\n"
      "bootstrap     moving-block bootstrap of the mean of a series: SE and percentile\n"
      "              interval (block from the AR(1) rule unless --block; seeded, so\n"
      "              reproducible; default 10000 resamples, level 0.90, seed 1)\n"
      "tost          two one-sided tests (Schuirmann): is the mean inside the margins?\n"
      "              values independent (default), --serial (SE from n_eff), or\n"
      "              --unit COL (the units' means are the observations, e.g. runs);\n"
      "              alpha 0.05 per side\n"
      "ba-rm         Bland-Altman limits with several pairs per subject, the true value\n"
      "              varying within a subject (Bland & Altman 2007)\n"
      "\n"
      "FILE.csv      header row required; fields separated by commas; fields may be\n"
      "              quoted (\"...\", with \"\" for a quote); numbers use a dot\n"
      "COL           a header name (exact, else case-insensitive) or a 1-based\n"
      "              column number\n"
      "options:\n"
      "  --json          print JSON instead of a table\n"
      "  --sep CHAR      field separator: ',' (default), ';' or 'tab'\n"
      "  --skip-empty    skip rows whose used cells are empty instead of failing\n"
      "  --svg FILE      bland-altman only: also write a Bland-Altman plot (SVG)\n",
      to);
  palp_app_common_usage(to, STATS_OPTS);
  fputs("exit status: 0 ok, 1 unusable data (the message names file, line and column)\n"
        "or results that cannot be written to stdout, 2 wrong command line\n",
        to);
}

static int usage_error(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fputs("palp-stats: ", stderr);
  vfprintf(stderr, fmt, ap);
  fputs("\n(run 'palp-stats --help' for usage)\n", stderr);
  va_end(ap);
  return EXIT_USAGE;
}

/* A data error, then hints: each one timestamped ERROR line, so a --log-file
 * holds the error with its hints and --log-level filters them together. */
static void vlog_error(palp_log *log, const char *fmt, va_list ap) {
  char msg[1024];
  vsnprintf(msg, sizeof msg, fmt, ap);
  palp_log_error(log, "%s", msg);
}

void data_error(palp_log *log, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vlog_error(log, fmt, ap);
  va_end(ap);
}

/* A hint after a data error: indented, at the error's level. */
__attribute__((format(printf, 2, 3))) static void hint(palp_log *log, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vlog_error(log, fmt, ap);
  va_end(ap);
}

/* ---- columns ------------------------------------------------------------------ */

static size_t edit_distance(const char *s, const char *t) {
  size_t n = strlen(s), m = strlen(t);
  if (n > 64 || m > 64) return 99;
  size_t d[65][65];
  for (size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (size_t i = 1; i <= n; ++i)
    for (size_t j = 1; j <= m; ++j) {
      size_t sub = d[i - 1][j - 1] + (tolower((unsigned char)s[i - 1]) != tolower((unsigned char)t[j - 1]));
      size_t del = d[i - 1][j] + 1, ins = d[i][j - 1] + 1;
      d[i][j] = sub < del ? (sub < ins ? sub : ins) : (del < ins ? del : ins);
    }
  return d[n][m];
}

static void list_columns(palp_log *log, const palp_csv *csv) {
  char line[1024];
  size_t n = (size_t)snprintf(line, sizeof line, "  the header has: ");
  for (int i = 0; i < csv->ncols && n < sizeof line; ++i)
    n += (size_t)snprintf(line + n, sizeof line - n, "%s%d:\"%s\"", i ? ", " : "", i + 1, csv->header[i]);
  hint(log, "%s", line);
}

/* Resolves a column by exact name, then case-insensitive name, then 1-based number. */
int find_column(const palp_csv *csv, const options *o, const char *want, const char *flag,
                       int *col) {
  int hit = -1, hits = 0;
  for (int i = 0; i < csv->ncols; ++i)
    if (strcmp(csv->header[i], want) == 0) hit = i, hits++;
  if (hits == 0)
    for (int i = 0; i < csv->ncols; ++i)
      if (strcasecmp(csv->header[i], want) == 0) hit = i, hits++;
  if (hits > 1) {
    data_error(o->log, "%s:%zu: column \"%s\" (%s) appears %d times in the header; rename the "
               "duplicates or give the column number instead",
               o->file, csv->header_line, want, flag, hits);
    list_columns(o->log, csv);
    return -1;
  }
  if (hits == 1) {
    *col = hit;
    return 0;
  }
  char *end;
  long k = strtol(want, &end, 10);
  if (*want && *end == '\0' && k >= 1 && k <= csv->ncols) {
    *col = (int)k - 1;
    return 0;
  }
  data_error(o->log, "%s:%zu: no column \"%s\" (given as %s) in the header", o->file, csv->header_line,
             want, flag);
  list_columns(o->log, csv);
  int best = -1;
  size_t bd = 99;
  for (int i = 0; i < csv->ncols; ++i) {
    size_t d = edit_distance(want, csv->header[i]);
    if (d < bd) bd = d, best = i;
  }
  if (best >= 0 && bd <= 3 && bd < strlen(want)) hint(o->log, "  did you mean \"%s\"?", csv->header[best]);
  if (csv->ncols == 1) {
    const char *h = csv->header[0];
    if (strchr(h, ';'))
      hint(o->log, "  the header is a single field containing ';': for a semicolon-separated file "
            "add --sep ';'");
    else if (strchr(h, '\t'))
      hint(o->log, "  the header is a single field containing tabs: for a tab-separated file add "
            "--sep tab");
  }
  return -1;
}

/* ---- cells -------------------------------------------------------------------------- */

/* Two options naming one column (by name, by its case or by number) would compare the column
 * with itself: SD 0, p = 1, the paper's criteria met, EQUIVALENT. A wrong command line, so
 * usage's exit status (the names are read against the header, hence after the file). */
int same_column(const options *o, const palp_csv *csv, int c1, const char *f1, const char *w1, int c2,
                const char *f2, const char *w2, const char *want) {
  if (c1 != c2) return 0;
  usage_error("%s \"%s\" and %s \"%s\" name the same column of %s (\"%s\", column %d); %s", f1, w1, f2, w2,
              o->file, csv->header[c1], c1 + 1, want);
  return 1;
}

int cell_is_empty(const palp_csv *csv, size_t row, int col) {
  return palp_csv_cell(csv, row, col)[0] == '\0';
}

/* Parses one numeric cell; on failure prints where and why, with a hint. */
int cell_number(const palp_csv *csv, const options *o, size_t row, int col,
                       palp_dec *out) {
  const char *text = palp_csv_cell(csv, row, col);
  int rc = palp_dec_parse(text, out);
  if (rc == 0) return 0;
  const char *name = csv->header[col];
  size_t line = csv->line[row];
  if (text[0] == '\0') {
    data_error(o->log, "%s:%zu: column \"%s\" (column %d) is empty; fill in the measurement, delete "
               "the row, or pass --skip-empty to ignore such rows",
               o->file, line, name, col + 1);
    return -1;
  }
  if (rc == -2) {
    data_error(o->log, "%s:%zu: column \"%s\" (column %d): \"%s\" is too large for a double", o->file,
               line, name, col + 1, text);
    return -1;
  }
  data_error(o->log, "%s:%zu: column \"%s\" (column %d): \"%s\" is not a number", o->file, line, name,
             col + 1, text);
  char low[16] = {0};
  for (int i = 0; i < 15 && text[i]; ++i) low[i] = (char)tolower((unsigned char)text[i]);
  palp_dec tmp;
  char fixed[256];
  snprintf(fixed, sizeof fixed, "%s", text);
  for (char *c = fixed; *c; ++c)
    if (*c == ',') *c = '.';
  if (strchr(text, ',') && palp_dec_parse(fixed, &tmp) == 0)
    hint(o->log, "  numbers must use a dot as the decimal separator (1.25, not 1,25)");
  else if (strstr(low, "nan") || strstr(low, "inf") || strcmp(low, "na") == 0 ||
           strcmp(low, "n/a") == 0)
    hint(o->log, "  missing or non-finite values are not accepted; remove the row or pass "
          "--skip-empty with an empty cell");
  else if (strpbrk(text, "0123456789") == NULL)
    hint(o->log, "  this looks like a label, not a measurement: does the option name the column "
          "holding the numbers (--value, --a, --b)?");
  else if (isdigit((unsigned char)text[0]) || text[0] == '-' || text[0] == '.')
    hint(o->log, "  write plain numbers without units or thousands separators (e.g. 0.0125, "
          "1.2e-3); put the unit in the column name");
  return -1;
}

/* ---- output helpers ------------------------------------------------------------------ */

void print_json(cJSON *root) {
  char *s = cJSON_Print(root);
  if (!s) { /* no result is not a result: never an empty stdout and exit 0 */
    fputs("palp-stats: out of memory: the JSON result could not be printed\n", stderr);
    exit(EXIT_DATA);
  }
  puts(s); /* a failed write is caught at exit (main) */
  free(s);
}

static cJSON *anova_json(const palp_stats_anova *a) {
  cJSON *j = cJSON_CreateObject();
  cJSON_AddNumberToObject(j, "n", (double)a->n);
  cJSON_AddNumberToObject(j, "grand_mean", a->grand_mean);
  cJSON *b = cJSON_AddObjectToObject(j, "between");
  cJSON_AddNumberToObject(b, "df", a->df_between);
  cJSON_AddNumberToObject(b, "ss", a->ss_between);
  cJSON_AddNumberToObject(b, "ms", a->ms_between);
  cJSON *w = cJSON_AddObjectToObject(j, "within");
  cJSON_AddNumberToObject(w, "df", (double)a->df_within);
  cJSON_AddNumberToObject(w, "ss", a->ss_within);
  cJSON_AddNumberToObject(w, "ms", a->ms_within);
  cJSON *t = cJSON_AddObjectToObject(j, "total");
  cJSON_AddNumberToObject(t, "df", (double)(a->n - 1));
  cJSON_AddNumberToObject(t, "ss", a->ss_total);
  if (isinf(a->f)) {
    cJSON_AddNullToObject(j, "f");
    cJSON_AddStringToObject(j, "f_note", "infinite: every group is constant but the means differ");
  } else {
    cJSON_AddNumberToObject(j, "f", a->f);
  }
  cJSON_AddNumberToObject(j, "p", a->p);
  cJSON_AddNumberToObject(j, "r_squared", a->r_squared);
  cJSON_AddBoolToObject(j, "zero_within", (a->flags & PALP_STATS_ZERO_WITHIN) != 0);
  cJSON_AddBoolToObject(j, "all_equal", (a->flags & PALP_STATS_ALL_EQUAL) != 0);
  if (a->flags & PALP_STATS_SS_OVERFLOW)
    cJSON_AddStringToObject(j, "ss_note", "a sum of squares is beyond the largest double (1.8e308) and "
                            "printed as null; F, p and R^2 are computed from scaled sums and are exact");
  cJSON_AddBoolToObject(j, "p_above_0_05", a->p > PALP_STATS_PAPER_ALPHA);
  return j;
}

static void print_anova_table(const palp_stats_anova *a) {
  printf("  %-9s %8s %16s %16s %12s %10s\n", "source", "df", "sum of squares", "mean square", "F",
         "p");
  char fbuf[32];
  if (isinf(a->f)) snprintf(fbuf, sizeof fbuf, "inf");
  else snprintf(fbuf, sizeof fbuf, "%.6g", a->f);
  printf("  %-9s %8d %16.9g %16.9g %12s %10.4g\n", "between", a->df_between, a->ss_between,
         a->ms_between, fbuf, a->p);
  printf("  %-9s %8ld %16.9g %16.9g\n", "within", a->df_within, a->ss_within, a->ms_within);
  printf("  %-9s %8zu %16.9g\n", "total", a->n - 1, a->ss_total);
  if (a->flags & PALP_STATS_ALL_EQUAL)
    printf("  note: every value is identical; F is reported as 0 and p as 1\n");
  else if (a->flags & PALP_STATS_ZERO_WITHIN)
    printf("  note: every group is constant but the group means differ; F is infinite, p = 0\n");
  if (a->flags & PALP_STATS_SS_OVERFLOW)
    printf("  note: a sum of squares is beyond the largest double (1.8e308), printed as inf; F, p and "
           "R^2 are computed from scaled sums and are exact\n");
}

/* ---- anova --------------------------------------------------------------------------- */

typedef struct group {
  char *name;
  size_t n, first_line, first_row;
} group;

static int run_anova(const options *o, const palp_csv *csv) {
  int gc, vc;
  if (find_column(csv, o, o->group, "--group", &gc) < 0) return EXIT_DATA;
  if (find_column(csv, o, o->value, "--value", &vc) < 0) return EXIT_DATA;
  if (same_column(o, csv, gc, "--group", o->group, vc, "--value", o->value,
                  "--group names the column of labels, --value the measurement")) return EXIT_USAGE;
  if (csv->nrows == 0) {
    data_error(o->log, "%s:%zu: no data rows after the header", o->file, csv->header_line);
    return EXIT_DATA;
  }
  size_t nr = csv->nrows;
  int *gid = malloc(nr * sizeof *gid);
  palp_dec *dv = malloc(nr * sizeof *dv);
  group *groups = calloc(nr, sizeof *groups);
  double *values = malloc(nr * sizeof *values);
  size_t *start = NULL, *fill = NULL;
  double *offset = NULL;
  int ng = 0, rc = EXIT_DATA;
  size_t used = 0, skipped = 0;
  label_index index = {0};
  if (!gid || !dv || !groups || !values || label_index_init(&index, 64) < 0) {
    data_error(o->log, "out of memory");
    goto done;
  }
  for (size_t r = 0; r < nr; ++r) {
    gid[r] = -1;
    if (o->skip_empty && (cell_is_empty(csv, r, gc) || cell_is_empty(csv, r, vc))) {
      skipped++;
      continue;
    }
    const char *label = palp_csv_cell(csv, r, gc);
    if (label[0] == '\0') {
      data_error(o->log, "%s:%zu: column \"%s\" (column %d, the group) is empty; every row needs a group "
                 "label (or pass --skip-empty)",
                 o->file, csv->line[r], csv->header[gc], gc + 1);
      goto done;
    }
    if (cell_number(csv, o, r, vc, &dv[r]) < 0) goto done;
    int added, g = label_index_get(&index, label, &added); /* O(1) expected, not a scan */
    if (g < 0) {
      data_error(o->log, "out of memory");
      goto done;
    }
    if (added) {
      groups[ng].name = (char *)label;
      groups[ng].first_line = csv->line[r];
      groups[ng].first_row = r;
      ng++;
    }
    groups[g].n++;
    gid[r] = g;
    used++;
  }
  if (used == 0) {
    data_error(o->log, "%s: every data row was skipped as empty; nothing to analyse", o->file);
    goto done;
  }
  if (ng < 2) {
    data_error(o->log, "%s: column \"%s\" holds a single group (\"%s\", %zu values); one-way ANOVA "
               "compares at least 2 groups: check that --group names the column that "
               "identifies the groups",
               o->file, csv->header[gc], groups[0].name, groups[0].n);
    goto done;
  }
  for (int g = 0; g < ng; ++g)
    if (groups[g].n < 2) {
      data_error(o->log, "%s:%zu: group \"%s\" has only one value; one-way ANOVA needs at least 2 values "
                 "per group to estimate the spread within it. Check the spelling of the label "
                 "(labels are compared exactly, case included) or add measurements",
                 o->file, groups[g].first_line, groups[g].name);
      for (int h = 0; h < ng; ++h)
        if (h != g && (strcasecmp(groups[h].name, groups[g].name) == 0 ||
                       edit_distance(groups[h].name, groups[g].name) == 1))
          hint(o->log, "  a group \"%s\" exists (first on line %zu): the same group mistyped?",
                  groups[h].name, groups[h].first_line);
      if ((size_t)ng * 2 > used)
        hint(o->log, "  %d different labels in %zu rows: does --group name the column that "
                     "identifies the groups (--group and --value swapped?)",
                ng, used);
      goto done;
    }

  /* Exact decimal shifts: each value relative to its group's first value (keeps
   * the spread inside the group), each group's first value relative to the first
   * value of the file (keeps the differences between groups); then a
   * group-contiguous layout. */
  const palp_dec *origin = &dv[groups[0].first_row];
  start = malloc((size_t)(ng + 1) * sizeof *start);
  fill = malloc((size_t)ng * sizeof *fill);
  offset = malloc((size_t)ng * sizeof *offset);
  if (!start || !fill || !offset) {
    data_error(o->log, "out of memory");
    goto done;
  }
  start[0] = 0;
  for (int g = 0; g < ng; ++g) start[g + 1] = start[g] + groups[g].n;
  for (int g = 0; g < ng; ++g) {
    fill[g] = start[g];
    offset[g] = palp_dec_sub(&dv[groups[g].first_row], origin);
  }
  for (size_t r = 0; r < nr; ++r)
    if (gid[r] >= 0) values[fill[gid[r]]++] = palp_dec_sub(&dv[r], &dv[groups[gid[r]].first_row]);
  /* 1e308 and -1e308: each finite, their difference not (the ANOVA refused it, saying only "error -1") */
  for (size_t r = 0; r < nr; ++r) {
    if (gid[r] < 0) continue;
    const size_t f = groups[gid[r]].first_row;
    if (!isfinite(palp_dec_sub(&dv[r], &dv[f])) || !isfinite(offset[gid[r]])) {
      const size_t from = isfinite(offset[gid[r]]) ? f : groups[0].first_row;
      data_error(o->log, "%s:%zu: the value is too large to analyse: its difference from line %zu's value exceeds "
                 "the largest double (1.8e308)",
                 o->file, csv->line[isfinite(offset[gid[r]]) ? r : f], csv->line[from]);
      goto done;
    }
  }

  palp_stats_anova a;
  int err = palp_stats_anova_offset(values, start, ng, offset, &a);
  if (err < 0) {
    data_error(o->log, "%s: the ANOVA could not be computed: a value or a sum is beyond the largest double "
               "(error %d)", o->file, err);
    goto done;
  }
  a.grand_mean += origin->value;
  if (skipped) palp_log_info(o->log, "note: %zu rows with empty cells skipped", skipped);

  if (o->json) {
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "command", "anova");
    cJSON_AddStringToObject(root, "file", o->file);
    cJSON_AddStringToObject(root, "group_column", csv->header[gc]);
    cJSON_AddStringToObject(root, "value_column", csv->header[vc]);
    cJSON_AddNumberToObject(root, "rows_skipped", (double)skipped);
    cJSON *garr = cJSON_AddArrayToObject(root, "groups");
    for (int g = 0; g < ng; ++g) {
      double m, sd;
      palp_stats_mean_sd(values + start[g], groups[g].n, &m, &sd);
      cJSON *gj = cJSON_CreateObject();
      cJSON_AddStringToObject(gj, "name", groups[g].name);
      cJSON_AddNumberToObject(gj, "n", (double)groups[g].n);
      cJSON_AddNumberToObject(gj, "mean", dv[groups[g].first_row].value + m);
      cJSON_AddNumberToObject(gj, "sd", sd);
      cJSON_AddItemToArray(garr, gj);
    }
    cJSON *aj = anova_json(&a);
    cJSON_AddItemToObject(root, "anova", aj);
    print_json(root);
    cJSON_Delete(root);
  } else {
    printf("One-way ANOVA of \"%s\" grouped by \"%s\" (%s, %zu values, %d groups)\n\n",
           csv->header[vc], csv->header[gc], o->file, a.n, ng);
    printf("  %-20s %8s %22s %14s\n", "group", "n", "mean", "SD");
    for (int g = 0; g < ng; ++g) {
      double m, sd;
      palp_stats_mean_sd(values + start[g], groups[g].n, &m, &sd);
      printf("  %-20.20s %8zu %22.15g %14.6g\n", groups[g].name, groups[g].n,
             dv[groups[g].first_row].value + m, sd);
    }
    printf("\n");
    print_anova_table(&a);
    printf("\n  R^2 = %.6g\n", a.r_squared);
    printf("  %s\n", a.p > PALP_STATS_PAPER_ALPHA
                         ? "p > 0.05: no significant difference between the groups (the paper's "
                           "ANOVA criterion holds)"
                         : "p <= 0.05: the group means differ significantly (the paper's ANOVA "
                           "criterion fails)");
  }
  rc = 0;
done:
  label_index_free(&index);
  free(gid);
  free(dv);
  free(groups);
  free(values);
  free(start);
  free(fill);
  free(offset);
  return rc;
}

/* ---- paired columns ---------------------------------------------------------------------- */

/* Paired columns, each subtraction done exactly in decimal and rounded once:
 *   d[i]      = a_i - b_i           (Bland-Altman, RMSE: exact per pair)
 *   ab[i]     = a_i - a_0,  ab[n+i] = b_i - b_0   (ANOVA groups, spread kept)
 *   off[1]    = b_0 - a_0           (ANOVA between-group difference kept) */
typedef struct paired {
  int ca, cb;
  size_t n, skipped;
  double *d, *zero, *ab;
  double a0, b0, off[2];
} paired;

static void paired_free(paired *p) {
  free(p->d);
  free(p->zero);
  free(p->ab);
}

static int read_paired(const options *o, const palp_csv *csv, size_t min_n, const char *why,
                       paired *p) {
  memset(p, 0, sizeof *p);
  if (find_column(csv, o, o->a, "--a", &p->ca) < 0) return -1;
  if (find_column(csv, o, o->b, "--b", &p->cb) < 0) return -1;
  if (same_column(o, csv, p->ca, "--a", o->a, p->cb, "--b", o->b, "give the two paired columns")) return -2;
  if (csv->nrows == 0) {
    data_error(o->log, "%s:%zu: no data rows after the header", o->file, csv->header_line);
    return -1;
  }
  size_t nr = csv->nrows;
  palp_dec *da = malloc(nr * sizeof *da), *db = malloc(nr * sizeof *db);
  unsigned char *use = calloc(nr, 1);
  p->d = malloc(nr * sizeof *p->d);
  p->zero = calloc(nr, sizeof *p->zero);
  p->ab = malloc(2 * nr * sizeof *p->ab);
  int rc = -1;
  if (!da || !db || !use || !p->d || !p->zero || !p->ab) {
    data_error(o->log, "out of memory");
    goto done;
  }
  size_t first = nr;
  for (size_t r = 0; r < nr; ++r) {
    if (o->skip_empty && (cell_is_empty(csv, r, p->ca) || cell_is_empty(csv, r, p->cb))) {
      p->skipped++;
      continue;
    }
    if (cell_number(csv, o, r, p->ca, &da[r]) < 0) goto done;
    if (cell_number(csv, o, r, p->cb, &db[r]) < 0) goto done;
    use[r] = 1;
    if (first == nr) first = r;
  }
  if (first == nr) {
    data_error(o->log, "%s: every data row was skipped as empty; nothing to analyse", o->file);
    goto done;
  }
  size_t used = 0;
  for (size_t r = 0; r < nr; ++r) used += use[r];
  for (size_t r = 0, i = 0; r < nr; ++r)
    if (use[r]) {
      p->d[i] = palp_dec_sub(&da[r], &db[r]);
      p->ab[i] = palp_dec_sub(&da[r], &da[first]);
      p->ab[used + i] = palp_dec_sub(&db[r], &db[first]);
      /* 1e308 and -1e308: each finite, a - b not (the statistics refused it, saying only "error -1") */
      if (!isfinite(p->d[i]) || !isfinite(p->ab[i]) || !isfinite(p->ab[used + i])) {
        data_error(o->log, "%s:%zu: the values are too large to analyse: %s exceeds the largest double (1.8e308)",
                   o->file, csv->line[r],
                   !isfinite(p->d[i]) ? "a - b" : "their difference from the first row's");
        goto done;
      }
      ++i;
    }
  p->n = used;
  p->a0 = da[first].value;
  p->b0 = db[first].value;
  p->off[0] = 0.0;
  p->off[1] = palp_dec_sub(&db[first], &da[first]);
  if (p->n < min_n) {
    data_error(o->log, "%s: %zu data row%s; %s needs at least %zu pairs", o->file, p->n,
               p->n == 1 ? "" : "s", why, min_n);
    goto done;
  }
  if (p->skipped) palp_log_info(o->log, "note: %zu rows with empty cells skipped", p->skipped);
  rc = 0;
done:
  free(da);
  free(db);
  free(use);
  if (rc < 0) paired_free(p);
  return rc;
}

static int run_rmse(const options *o, const palp_csv *csv) {
  paired p;
  const int rd = read_paired(o, csv, 1, "RMSE", &p);
  if (rd < 0) return read_exit(rd);
  double r;
  int err = palp_stats_rmse(p.d, p.zero, p.n, &r);
  if (err < 0) {
    data_error(o->log, "%s: RMSE could not be computed: a value or a sum is beyond the largest double (error %d)",
               o->file, err);
    paired_free(&p);
    return EXIT_DATA;
  }
  if (o->json) {
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "command", "rmse");
    cJSON_AddStringToObject(root, "file", o->file);
    cJSON_AddStringToObject(root, "a_column", csv->header[p.ca]);
    cJSON_AddStringToObject(root, "b_column", csv->header[p.cb]);
    cJSON_AddNumberToObject(root, "n", (double)p.n);
    cJSON_AddNumberToObject(root, "rows_skipped", (double)p.skipped);
    cJSON_AddNumberToObject(root, "rmse", r);
    print_json(root);
    cJSON_Delete(root);
  } else {
    printf("RMSE of \"%s\" - \"%s\" (%s, %zu pairs)\n\n", csv->header[p.ca], csv->header[p.cb],
           o->file, p.n);
    printf("  RMSE = %.9g  (in the columns' unit)\n", r);
  }
  paired_free(&p);
  return 0;
}

static int run_bland_altman(const options *o, const palp_csv *csv) {
  paired p;
  const int rd = read_paired(o, csv, 2, "Bland-Altman (an SD of the differences)", &p);
  if (rd < 0) return read_exit(rd);
  palp_stats_ba ba;
  palp_stats_anova an;
  double rmse;
  size_t start[3] = {0, p.n, 2 * p.n};
  int err = palp_stats_bland_altman(p.d, p.zero, p.n, &ba);
  if (err == 0) err = palp_stats_anova_offset(p.ab, start, 2, p.off, &an);
  if (err == 0) err = palp_stats_rmse(p.d, p.zero, p.n, &rmse);
  if (err < 0) {
    data_error(o->log, "%s: the statistics could not be computed: a value or a sum is beyond the largest double "
               "(error %d)", o->file, err);
    paired_free(&p);
    return EXIT_DATA;
  }
  /* The means of the columns themselves (ba was computed from d and 0). */
  double ssd;
  palp_stats_mean_ssd(p.ab, p.n, &ba.mean_a, &ssd);
  palp_stats_mean_ssd(p.ab + p.n, p.n, &ba.mean_b, &ssd);
  ba.mean_a += p.a0;
  ba.mean_b += p.b0;
  an.grand_mean += p.a0;
  int meets = palp_stats_meets_paper_criteria(&an, &ba);

  if (o->svg) {
    const char *na = csv->header[p.ca], *nb = csv->header[p.cb];
    char title[512];
    snprintf(title, sizeof title, "Bland-Altman: %s vs %s", na, nb);
    double *ma = malloc(p.n * sizeof *ma), *mb = malloc(p.n * sizeof *mb);
    if (!ma || !mb) {
      free(ma);
      free(mb);
      data_error(o->log, "out of memory");
      paired_free(&p);
      return EXIT_DATA;
    }
    for (size_t i = 0; i < p.n; ++i) ma[i] = p.a0 + p.ab[i], mb[i] = p.b0 + p.ab[p.n + i];
    palp_svg_bland_altman_def def = palp_svg_bland_altman_default_def();
    def.title = title;
    def.a = ma;
    def.b = mb;
    def.n = p.n;
    def.bias = ba.bias;
    def.sd = ba.sd;
    def.label_a = na;
    def.label_b = nb;
    char perr[256];
    int sr = palp_svg_bland_altman_file(o->svg, &def, perr, sizeof perr);
    free(ma);
    free(mb);
    if (sr < 0) {
      data_error(o->log, "%s", perr);
      paired_free(&p);
      return EXIT_DATA;
    }
  }

  if (o->json) {
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "command", "bland-altman");
    cJSON_AddStringToObject(root, "file", o->file);
    cJSON_AddStringToObject(root, "a_column", csv->header[p.ca]);
    cJSON_AddStringToObject(root, "b_column", csv->header[p.cb]);
    cJSON_AddNumberToObject(root, "n", (double)ba.n);
    cJSON_AddNumberToObject(root, "rows_skipped", (double)p.skipped);
    cJSON_AddNumberToObject(root, "mean_a", ba.mean_a);
    cJSON_AddNumberToObject(root, "mean_b", ba.mean_b);
    cJSON_AddNumberToObject(root, "bias", ba.bias);
    cJSON_AddNumberToObject(root, "sd", ba.sd);
    cJSON_AddNumberToObject(root, "loa_lower", ba.loa_lower);
    cJSON_AddNumberToObject(root, "loa_upper", ba.loa_upper);
    cJSON_AddNumberToObject(root, "within_loa", (double)ba.within_loa);
    cJSON_AddNumberToObject(root, "band_lower", ba.band_lower);
    cJSON_AddNumberToObject(root, "band_upper", ba.band_upper);
    cJSON_AddNumberToObject(root, "within_band", (double)ba.within_band);
    cJSON_AddNumberToObject(root, "agreement", ba.agreement);
    cJSON_AddNumberToObject(root, "agreement_percent", 100.0 * ba.agreement);
    cJSON_AddNumberToObject(root, "rmse", rmse);
    cJSON_AddItemToObject(root, "anova_a_vs_b", anova_json(&an));
    cJSON_AddBoolToObject(root, "meets_paper_criteria", meets);
    if (o->svg) cJSON_AddStringToObject(root, "svg", o->svg);
    print_json(root);
    cJSON_Delete(root);
  } else {
    printf("Bland-Altman agreement of a = \"%s\" and b = \"%s\" (%s, %zu pairs)\n\n",
           csv->header[p.ca], csv->header[p.cb], o->file, ba.n);
    printf("  %-28s %.9g\n", "mean of a", ba.mean_a);
    printf("  %-28s %.9g\n", "mean of b", ba.mean_b);
    printf("  %-28s %.9g\n", "bias (mean of a - b)", ba.bias);
    printf("  %-28s %.9g\n", "SD of a - b", ba.sd);
    printf("  %-28s [%.6g, %.6g]  (%zu of %zu inside)\n", "limits bias -+ 1.96 SD",
           ba.loa_lower, ba.loa_upper, ba.within_loa, ba.n);
    printf("  %-28s [%.6g, %.6g]  (%zu of %zu inside)\n", "paper band bias -+ 2 SD",
           ba.band_lower, ba.band_upper, ba.within_band, ba.n);
    printf("  %-28s %.1f %%\n", "agreement (within -+ 2 SD)", 100.0 * ba.agreement);
    printf("  %-28s %.9g\n", "RMSE", rmse);
    if (isinf(an.f))
      printf("  %-28s F(1, %ld) = inf, p = 0\n", "one-way ANOVA a vs b", an.df_within);
    else
      printf("  %-28s F(1, %ld) = %.4g, p = %.4g\n", "one-way ANOVA a vs b", an.df_within, an.f,
             an.p);
    printf("\n  paper's criteria (ANOVA p > 0.05 and more than 95 %% within bias -+ 2 SD): %s\n",
           meets ? "MET" : "NOT met");
    if (!meets) {
      if (!(an.p > PALP_STATS_PAPER_ALPHA))
        printf("    - p = %.4g is not above 0.05: the means of a and b differ significantly\n",
               an.p);
      if (!(ba.agreement > PALP_STATS_PAPER_AGREEMENT))
        printf("    - only %.1f %% of the differences lie within bias -+ 2 SD\n",
               100.0 * ba.agreement);
    }
    if (o->svg) printf("\n  plot written to %s\n", o->svg);
  }
  paired_free(&p);
  return 0;
}

/* Numeric options of the serial-data commands: 1 taken, 0 not one of them, -1 error. */
static int number_opt(options *o, int argc, char **argv, int *i) {
  const char *s = argv[*i];
  double *dst = NULL;
  long *ldst = NULL;
  double lo = -INFINITY, hi = INFINITY;
  int *flag = NULL;
  if (!strcmp(s, "--margin")) dst = &o->margin, flag = &o->have_margin, lo = 0;
  else if (!strcmp(s, "--lower")) dst = &o->lower, flag = &o->have_lower;
  else if (!strcmp(s, "--upper")) dst = &o->upper, flag = &o->have_upper;
  else if (!strcmp(s, "--alpha")) dst = &o->alpha, lo = 0, hi = 0.5;
  else if (!strcmp(s, "--level")) dst = &o->level, lo = 0, hi = 1;
  else if (!strcmp(s, "--block")) ldst = &o->block, lo = 1, hi = 1e9;
  else if (!strcmp(s, "--resamples")) ldst = &o->resamples, lo = 2, hi = 1e7;
  else if (!strcmp(s, "--seed")) flag = &o->have_seed;
  else return 0;
  if (*i + 1 >= argc) {
    usage_error("%s needs a number", s);
    return -1;
  }
  const char *v = argv[++*i];
  char *end = NULL;
  if (!strcmp(s, "--seed")) {
    errno = 0;
    unsigned long long x = strtoull(v, &end, 10);
    /* digits only: strtoull skips blanks and negates a '-' (" -5" was 2^64 - 5), and
     * saturates beyond 2^64 - 1 (ERANGE: every larger seed was the same one) */
    if (!isdigit((unsigned char)v[0]) || *end || errno == ERANGE) {
      usage_error("--seed expects a whole number from 0 to %llu, got \"%s\"", ULLONG_MAX, v);
      return -1;
    }
    o->seed = x;
    *flag = 1;
    return 1;
  }
  const double x = strtod(v, &end);
  if (!*v || isspace((unsigned char)v[0]) || *end || !isfinite(x) || (ldst && x != floor(x)) || x < lo || x > hi ||
      ((dst == &o->alpha || dst == &o->level) && (x <= lo || x >= hi)) || (dst == &o->margin && !(x > 0))) {
    usage_error("%s expects %s, got \"%s\"", s,
                dst == &o->alpha  ? "a number in (0, 0.5)"
                : dst == &o->level ? "a number in (0, 1)"
                : ldst             ? "a positive integer"
                : dst == &o->margin ? "a number > 0"
                                    : "a number",
                v);
    return -1;
  }
  if (dst) *dst = x;
  else *ldst = (long)x;
  if (flag) *flag = 1;
  return 1;
}

/* ---- main ------------------------------------------------------------------------------ */

/* Results on a full disk or a closed pipe were written to nothing: not a success (rc 0 -> 1). */
static int stdout_done(int rc) {
  errno = 0;
  if (fflush(stdout) != 0 || ferror(stdout)) {
    fprintf(stderr, "palp-stats: cannot write the results to stdout: %s\n", strerror(errno ? errno : EIO));
    if (!rc) rc = EXIT_DATA;
  }
  return rc;
}

int main(int argc, char **argv) {
  if (palp_app_handle_version(argc, argv, "palp-stats")) return 0;
  palp_app_opts ao;
  palp_app_opts_init(&ao, "palp-stats");
  options o = {0};
  o.sep = ',';
  if (argc < 2) {
    usage(stderr);
    return EXIT_USAGE;
  }
  if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "help") == 0) {
    usage(stdout);
    return stdout_done(0);
  }
  o.command = argv[1];
  int is_anova = strcmp(o.command, "anova") == 0;
  int is_ba = strcmp(o.command, "bland-altman") == 0;
  int is_rmse = strcmp(o.command, "rmse") == 0;
  int is_neff = strcmp(o.command, "neff") == 0, is_boot = strcmp(o.command, "bootstrap") == 0;
  int is_tost = strcmp(o.command, "tost") == 0, is_barm = strcmp(o.command, "ba-rm") == 0;
  int is_serial = is_neff || is_boot || is_tost || is_barm;
  if (!is_anova && !is_ba && !is_rmse && !is_serial)
    return usage_error("unknown command \"%s\"; expected anova, bland-altman, rmse, neff, bootstrap, tost or ba-rm",
                       o.command);
  o.seed = 1;

  for (int i = 2; i < argc; ++i) {
    const char *s = argv[i];
    const char **slot = NULL;
    const int common = palp_app_common_opt(&ao, STATS_OPTS, argc, argv, &i);
    if (common < 0) return EXIT_USAGE;
    if (common) continue;
    if (strcmp(s, "--json") == 0) {
      o.json = 1;
      continue;
    }
    if (strcmp(s, "--skip-empty") == 0) {
      o.skip_empty = 1;
      continue;
    }
    if (strcmp(s, "--serial") == 0) {
      o.serial = 1;
      continue;
    }
    {
      const int num = number_opt(&o, argc, argv, &i);
      if (num < 0) return EXIT_USAGE;
      if (num) continue;
    }
    if (strcmp(s, "--help") == 0 || strcmp(s, "-h") == 0) {
      usage(stdout);
      return stdout_done(0);
    }
    if (strcmp(s, "--sep") == 0) {
      if (i + 1 >= argc) return usage_error("--sep needs a value: ',', ';' or 'tab'");
      const char *v = argv[++i];
      if (strcmp(v, "tab") == 0 || strcmp(v, "\\t") == 0 || strcmp(v, "\t") == 0) o.sep = '\t';
      else if (strlen(v) == 1 && v[0] != '"' && v[0] != '\n' && v[0] != '\r') o.sep = v[0];
      else return usage_error("--sep takes a single character or 'tab', not \"%s\"", v);
      continue;
    }
    if (strcmp(s, "--group") == 0) slot = &o.group;
    else if (strcmp(s, "--value") == 0) slot = &o.value;
    else if (strcmp(s, "--a") == 0) slot = &o.a;
    else if (strcmp(s, "--b") == 0) slot = &o.b;
    else if (strcmp(s, "--svg") == 0) slot = &o.svg;
    else if (strcmp(s, "--unit") == 0) slot = &o.unit;
    else if (strcmp(s, "--subject") == 0) slot = &o.subject;
    if (slot) {
      if (i + 1 >= argc) return usage_error("%s needs a column name", s);
      *slot = argv[++i];
      continue;
    }
    if (s[0] == '-' && s[1] == '-')
      return usage_error("unknown option \"%s\"", s);
    if (o.file) return usage_error("more than one input file given (\"%s\" and \"%s\")", o.file, s);
    o.file = s;
  }
  if (ao.version) { /* after the command word: read by the loop above, never as another option's value */
    palp_app_print_version(stdout, "palp-stats");
    return stdout_done(0);
  }
  if (!o.file) return usage_error("%s: no input CSV file given", o.command);
  /* An option of another command is refused, naming that command: it was dropped unread, and
   * bland-altman --subject s gave plain Bland-Altman where the repeated-measures one was meant. */
  const struct {
    int given;
    const char *opt, *owner;
    int ours;
  } foreign[] = {
      {o.subject != NULL, "--subject", "ba-rm (repeated-measures Bland-Altman)", is_barm},
      {o.serial, "--serial", "tost", is_tost},
      {o.unit != NULL, "--unit", "tost", is_tost},
      {o.have_margin, "--margin", "tost", is_tost},
      {o.have_lower, "--lower", "tost", is_tost},
      {o.have_upper, "--upper", "tost", is_tost},
      {o.alpha != 0, "--alpha", "tost", is_tost},
      {o.block != 0, "--block", "bootstrap", is_boot},
      {o.resamples != 0, "--resamples", "bootstrap", is_boot},
      {o.level != 0, "--level", "bootstrap", is_boot},
      {o.have_seed, "--seed", "bootstrap", is_boot},
  };
  for (size_t k = 0; k < sizeof foreign / sizeof foreign[0]; ++k)
    if (foreign[k].given && !foreign[k].ours)
      return usage_error("%s does not take %s; it belongs to %s", o.command, foreign[k].opt, foreign[k].owner);
  if (is_serial) {
    if (o.group || o.svg) return usage_error("%s takes --value or --a/--b, not --group/--svg", o.command);
    if (o.value && (o.a || o.b)) return usage_error("%s: give --value COL or --a COL --b COL, not both", o.command);
    if (!o.value && (!o.a || !o.b))
      return usage_error("%s needs --value COL (a series, e.g. differences) or --a COL --b COL (their difference)",
                         o.command);
    if (is_barm && !o.subject) return usage_error("ba-rm needs --subject COL (the column naming each row's subject)");
    if (is_tost) {
      if (o.have_margin == (o.have_lower || o.have_upper))
        return usage_error("tost needs either --margin M (the interval -M..M) or both --lower L and --upper U");
      if (!o.have_margin && !(o.have_lower && o.have_upper)) return usage_error("tost needs both --lower and --upper");
      if (o.have_margin && !(o.margin > 0)) return usage_error("--margin must be > 0");
      if (!o.have_margin && !(o.lower < o.upper)) return usage_error("--lower must be below --upper");
      if (o.serial && o.unit) return usage_error("--serial and --unit are alternatives; give one");
    }
  } else if (is_anova) {
    if (!o.group || !o.value)
      return usage_error("anova needs --group COL (the column naming each row's group) and "
                         "--value COL (the measurement)");
    if (o.a || o.b || o.svg) return usage_error("anova takes --group and --value, not --a/--b/--svg");
  } else {
    if (!o.a || !o.b)
      return usage_error("%s needs --a COL and --b COL (the two paired measurement columns)",
                         o.command);
    if (o.group || o.value) return usage_error("%s takes --a and --b, not --group/--value", o.command);
    if (o.svg && !is_ba) return usage_error("--svg is available for bland-altman only");
  }

  palp_log log;
  if (palp_log_init(&log, "palp-stats", ao.log_level, ao.log_file) < 0)
    return usage_error("--log-file %s: cannot open it: %s", ao.log_file, strerror(errno));
  o.log = &log; /* every line is flushed as written */
  palp_csv csv;
  char err[1024];
  if (palp_csv_read(o.file, o.sep, &csv, err, sizeof err) < 0) {
    data_error(o.log, "%s", err);
    return EXIT_DATA;
  }
  int rc = is_anova  ? run_anova(&o, &csv)
           : is_ba   ? run_bland_altman(&o, &csv)
           : is_rmse ? run_rmse(&o, &csv)
           : is_neff ? run_neff(&o, &csv)
           : is_boot ? run_bootstrap(&o, &csv)
           : is_tost ? run_tost(&o, &csv)
                     : run_ba_rm(&o, &csv);
  palp_csv_free(&csv);
  return stdout_done(rc);
}
