/*
 * test_cli.c - palp-stats end to end: good CSV gives the right numbers (JSON parsed
 * with cJSON), bad CSV gives a clear message naming file, line and column, and a
 * non-zero exit status.
 *
 * usage: test_cli PATH/TO/palp-stats WORKDIR
 */
#define _XOPEN_SOURCE 700 /* realpath */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "harness.h"

static const char *tool;
static const char *dir;

static void check_rel(const char *what, double got, double want, double rtol) {
  ++checks;
  if (!(fabs(got - want) <= rtol * fabs(want))) {
    ++failures;
    fprintf(stderr, "FAIL %s: got %.17g want %.17g (rtol %.1g)\n", what, got, want, rtol);
  }
}

static void write_file(const char *name, const char *text) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "w");
  if (!f) {
    perror(path);
    exit(2);
  }
  fputs(text, f);
  fclose(f);
}

typedef struct result {
  int status;
  char *out, *err;
} result;

/* Runs palp-stats with args (already shell-quoted) inside dir. */
/* stdout to out.txt, read back; or to stdout_path (e.g. /dev/full), not read. */
static result run_to(const char *args, const char *stdout_path) {
  char cmd[4096];
  snprintf(cmd, sizeof cmd, "cd '%s' && '%s' %s >'%s' 2>err.txt", dir, tool, args,
           stdout_path ? stdout_path : "out.txt");
  int st = system(cmd);
  result r;
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  char path[1024];
  snprintf(path, sizeof path, "%s/out.txt", dir);
  r.out = stdout_path ? strdup("") : slurp(path);
  snprintf(path, sizeof path, "%s/err.txt", dir);
  r.err = slurp(path);
  return r;
}

static result run(const char *args) { return run_to(args, NULL); }

static void result_free(result *r) {
  free(r->out);
  free(r->err);
}

static double num(const cJSON *o, const char *path) {
  /* "a.b" walks nested objects */
  char buf[128];
  snprintf(buf, sizeof buf, "%s", path);
  const cJSON *cur = o;
  for (char *tok = strtok(buf, "."); tok && cur; tok = strtok(NULL, "."))
    cur = cJSON_GetObjectItemCaseSensitive(cur, tok);
  if (!cJSON_IsNumber(cur)) {
    fprintf(stderr, "  (no number at %s)\n", path);
    return NAN;
  }
  return cur->valuedouble;
}

static int smls_digit(int i) { return i == 1 ? 2 : (i % 2 == 0 ? 1 : 3); }

/* NIST StRD SmLs07 written as its decimal text (13 constant leading digits), with a
 * quoted header field containing a comma. Certified: SS between 1.68 (df 8),
 * SS within 1.80 (df 180), F 21. The CLI subtracts an origin in exact decimal
 * arithmetic, so it must reproduce them to 9 digits, which binary64 input
 * conversion alone cannot (it gives F = 21.0008). */
static void test_smls07(void) {
  size_t cap = 64 * 200, len = 0;
  char *csv = malloc(cap);
  len += (size_t)snprintf(csv + len, cap - len, "treatment,\"value, as read\"\r\n");
  for (int t = 1; t <= 9; ++t)
    for (int r = 1; r <= 21; ++r)
      len += (size_t)snprintf(csv + len, cap - len, "T%d,1000000000000.%d\r\n", t,
                              smls_digit(t) + smls_digit(r));
  write_file("smls07.csv", csv);
  free(csv);
  result r = run("anova smls07.csv --group treatment --value 'value, as read' --json");
  check("SmLs07 exit 0", r.status == 0);
  cJSON *j = cJSON_Parse(r.out);
  check("SmLs07 JSON parses", j != NULL);
  if (j) {
    check_rel("SmLs07 F = 21 (9 digits)", num(j, "anova.f"), 21.0, 1e-9);
    check_rel("SmLs07 SS between 1.68", num(j, "anova.between.ss"), 1.68, 1e-9);
    check_rel("SmLs07 SS within 1.80", num(j, "anova.within.ss"), 1.80, 1e-9);
    check("SmLs07 df 8 / 180",
          num(j, "anova.between.df") == 8.0 && num(j, "anova.within.df") == 180.0);
    const cJSON *g = cJSON_GetObjectItemCaseSensitive(j, "groups");
    check("SmLs07 9 groups", cJSON_GetArraySize(g) == 9);
    /* Group 1 mean is 1000000000000.4 to within one binary64 spacing (1.2e-4). */
    const cJSON *g0 = cJSON_GetArrayItem(g, 0);
    check("SmLs07 group T1 mean", g0 && fabs(num(g0, "mean") - 1000000000000.4) <= 1.3e-4);
    check_rel("SmLs07 group T1 SD 0.1", num(g0, "sd"), 0.1, 1e-9);
    cJSON_Delete(j);
  }
  result_free(&r);
}

/* Three groups by hand (see test_stats.c): SS 26 and 6, F = 13 on (2, 6) df,
 * p = (1 + 2F/6)^-3 = 27/4096. Rows interleaved, a BOM, a blank line, a quoted and a
 * space-padded label and trailing ",," rows (as spreadsheets export) exercise the
 * reader. */
static void test_anova_hand(void) {
  write_file("three.csv",
             "\xEF\xBB\xBFid,group,length_mm\n"
             "1,\"low\",1\n2,mid,2\n3,high,5\n\n"
             "4,low,2\n5,mid,3\n6,high,6\n"
             "7,low,3\n8,mid,4\n9, high ,7\n,,\n,,\n");
  result r = run("anova three.csv --group group --value length_mm --json");
  check("hand anova exit 0", r.status == 0);
  cJSON *j = cJSON_Parse(r.out);
  check("hand anova JSON", j != NULL);
  if (j) {
    check_rel("hand F 13", num(j, "anova.f"), 13.0, 1e-12);
    check_rel("hand p 27/4096", num(j, "anova.p"), 27.0 / 4096.0, 1e-9);
    check_rel("hand SS between 26", num(j, "anova.between.ss"), 26.0, 1e-12);
    check_rel("hand SS within 6", num(j, "anova.within.ss"), 6.0, 1e-12);
    check("hand 3 groups", cJSON_GetArraySize(cJSON_GetObjectItem(j, "groups")) == 3);
    cJSON_Delete(j);
  }
  result_free(&r);
  /* The readable table says the same. */
  r = run("anova three.csv --group group --value length_mm");
  check("hand table exit 0", r.status == 0);
  check("hand table shows F 13 and the verdict",
        strstr(r.out, " 13 ") != NULL && strstr(r.out, "differ significantly") != NULL);
  result_free(&r);
}

/* The hand-worked Bland-Altman example of test_stats.c as a CSV file:
 * bias 0.1, SD sqrt(0.84/9), 9 of 10 within 2 SD (90 %), RMSE sqrt(0.94/10);
 * ANOVA a vs b: means 1.45 and 1.35, SS_between = 2*10*0.05^2 = 0.05,
 * SS_within = 1.945 + 1.225 = 3.17, F = 0.05 / (3.17/18). */
static void test_bland_altman(void) {
  write_file("ba.csv",
             "frame,realtime_cm,fem_cm\n"
             "0,1.3,1.2\n1,1.4,1.5\n2,1.0,0.8\n3,2.0,2.0\n4,0.9,1.1\n"
             "5,1.0,0.9\n6,1.7,1.7\n7,1.2,1.3\n8,1.7,1.6\n9,2.3,1.4\n");
  result r = run("bland-altman ba.csv --a realtime_cm --b fem_cm --json --svg ba.svg");
  check("BA exit 0", r.status == 0);
  cJSON *j = cJSON_Parse(r.out);
  check("BA JSON", j != NULL);
  if (j) {
    check_rel("BA bias", num(j, "bias"), 0.1, 1e-12);
    check_rel("BA sd", num(j, "sd"), sqrt(0.84 / 9.0), 1e-12);
    check_rel("BA loa upper", num(j, "loa_upper"), 0.1 + 1.96 * sqrt(0.84 / 9.0), 1e-12);
    check("BA within band 9", num(j, "within_band") == 9.0);
    check_rel("BA agreement 90%", num(j, "agreement_percent"), 90.0, 1e-12);
    check_rel("BA rmse", num(j, "rmse"), sqrt(0.094), 1e-12);
    check_rel("BA anova F", num(j, "anova_a_vs_b.f"), 0.05 / (3.17 / 18.0), 1e-10);
    check_rel("BA mean a", num(j, "mean_a"), 1.45, 1e-12);
    const cJSON *m = cJSON_GetObjectItem(j, "meets_paper_criteria");
    check("BA 90% does not meet the paper's criteria", cJSON_IsFalse(m));
    cJSON_Delete(j);
  }
  char path[1024];
  snprintf(path, sizeof path, "%s/ba.svg", dir);
  struct stat sb;
  check("BA --svg wrote the plot", stat(path, &sb) == 0 && sb.st_size > 500);
  result_free(&r);

  /* rmse with columns given by number; the table names the columns. */
  r = run("rmse ba.csv --a 2 --b 3 --json");
  check("rmse exit 0", r.status == 0);
  j = cJSON_Parse(r.out);
  if (j) {
    check_rel("rmse by column number", num(j, "rmse"), sqrt(0.094), 1e-12);
    cJSON_Delete(j);
  } else {
    check("rmse JSON", 0);
  }
  result_free(&r);
  r = run("bland-altman ba.csv --a realtime_cm --b fem_cm");
  check("BA table exit 0", r.status == 0);
  check("BA table verdict", strstr(r.out, "NOT met") != NULL && strstr(r.out, "90.0 %") != NULL);
  result_free(&r);
}

/* Data at very different levels: the command subtracts in decimal per group (ANOVA)
 * and per pair (differences), so nothing is lost to a common 1e12 offset.
 * Groups: big = 1e12 + {.3 .4 .5}, small = {1.1 1.2 1.3}: SS_within = 0.02 + 0.02,
 * group SDs 0.1, SS_between = 3 * 2 * ((1e12 - 0.8)/2)^2 = 1.5 (1e12 - 0.8)^2.
 * Pairs: d = 0.2 0.3 0.1 0.2: bias 0.2, SD sqrt(0.02/3), RMSE sqrt(0.18/4). */
static void test_far_apart(void) {
  write_file("far.csv", "group,value\nbig,1000000000000.3\nbig,1000000000000.4\n"
                        "big,1000000000000.5\nsmall,1.1\nsmall,1.2\nsmall,1.3\n");
  result r = run("anova far.csv --group group --value value --json");
  check("far groups exit 0", r.status == 0);
  cJSON *j = cJSON_Parse(r.out);
  if (j) {
    check_rel("far groups SS within 0.04", num(j, "anova.within.ss"), 0.04, 1e-9);
    check_rel("far groups SS between", num(j, "anova.between.ss"),
              1.5 * (1e12 - 0.8) * (1e12 - 0.8), 1e-9);
    const cJSON *g = cJSON_GetObjectItem(j, "groups");
    check_rel("far groups: big SD 0.1", num(cJSON_GetArrayItem(g, 0), "sd"), 0.1, 1e-9);
    check_rel("far groups: small SD 0.1", num(cJSON_GetArrayItem(g, 1), "sd"), 0.1, 1e-9);
    cJSON_Delete(j);
  } else {
    check("far groups JSON", 0);
  }
  result_free(&r);

  write_file("farpairs.csv", "a,b\n1000000000000.3,1000000000000.1\n1.5,1.2\n"
                             "1000000000000.4,1000000000000.3\n2.0,1.8\n");
  r = run("bland-altman farpairs.csv --a a --b b --json");
  check("far pairs exit 0", r.status == 0);
  j = cJSON_Parse(r.out);
  if (j) {
    check_rel("far pairs bias 0.2", num(j, "bias"), 0.2, 1e-9);
    check_rel("far pairs SD", num(j, "sd"), sqrt(0.02 / 3.0), 1e-9);
    check_rel("far pairs RMSE", num(j, "rmse"), sqrt(0.18 / 4.0), 1e-9);
    cJSON_Delete(j);
  } else {
    check("far pairs JSON", 0);
  }
  result_free(&r);
}

/* Values near 1e300 (session 81 review): the sums of squares are beyond the largest
 * double. Before, the unscaled squares turned NaN and the command printed F 0, p 1,
 * "every value is identical", exit 0. By hand (test_stats.c, test_scaled_sums):
 * F(1, 2) = 1681, p = 1 - 41/sqrt(1683) = 5.943536929e-4, the same as for the data
 * divided by 1e300; group A's SD 0.05 sqrt(2) 1e300. Bland-Altman of a = (1, 1.1)e300,
 * b = (-1, -1)e300: SD 0.1e300/sqrt(2) = 7.0710678e298, 2 of 2 inside. */
static void test_huge(void) {
  write_file("huge.csv", "g,v\nA,1e300\nA,1.1e300\nB,-1e300\nB,-1e300\n");
  result r = run("anova huge.csv --group g --value v --json");
  check("huge anova exit 0", r.status == 0);
  cJSON *j = cJSON_Parse(r.out);
  if (j) {
    check_rel("huge anova F 1681", num(j, "anova.f"), 1681.0, 1e-12);
    check_rel("huge anova p", num(j, "anova.p"), 5.943536929214899e-4, 1e-9);
    check("huge anova not all_equal",
          cJSON_IsFalse(cJSON_GetObjectItem(cJSON_GetObjectItem(j, "anova"), "all_equal")));
    check("huge anova ss_note", cJSON_GetObjectItem(cJSON_GetObjectItem(j, "anova"), "ss_note") != NULL);
    check_rel("huge group A SD", num(cJSON_GetArrayItem(cJSON_GetObjectItem(j, "groups"), 0), "sd"),
              0.07071067811865475e300, 1e-12);
    cJSON_Delete(j);
  } else {
    check("huge anova JSON", 0);
  }
  result_free(&r);
  r = run("anova huge.csv --group g --value v");
  check("huge anova table: no false 'identical' note", strstr(r.out, "identical") == NULL &&
                                                          strstr(r.out, "1681") != NULL);
  result_free(&r);
  write_file("hugepairs.csv", "a,b\n1e300,-1e300\n1.1e300,-1e300\n");
  r = run("bland-altman hugepairs.csv --a a --b b --json");
  check("huge BA exit 0", r.status == 0);
  j = cJSON_Parse(r.out);
  if (j) {
    check_rel("huge BA SD", num(j, "sd"), 0.07071067811865475e300, 1e-12);
    cJSON_Delete(j);
  } else {
    check("huge BA JSON", 0);
  }
  result_free(&r);
}

/* Bad input: exit 1, nothing on stdout, and a message with the file, the line and
 * the column or group at fault. */
static void expect_error(const char *what, const char *args, int status, const char **needles) {
  int before = failures;
  result r = run(args);
  char buf[256];
  snprintf(buf, sizeof buf, "%s: exit status %d", what, status);
  check(buf, r.status == status);
  snprintf(buf, sizeof buf, "%s: no output on stdout", what);
  check(buf, r.out[0] == '\0');
  for (const char **n = needles; *n; ++n) {
    snprintf(buf, sizeof buf, "%s: message contains \"%s\"", what, *n);
    check(buf, strstr(r.err, *n) != NULL);
  }
  if (failures > before) fprintf(stderr, "  stderr was: %s", r.err);
  result_free(&r);
}

static void test_errors(void) {
  write_file("groups.csv", "group,value\nA,1.0\nA,1.2\nB,2.0\nb,2.1\nB,2.2\n");
  write_file("nonnum.csv", "group,value\nA,1.0\nA,\"1,2\"\nB,2.0\nB,abc\n");
  write_file("single.csv", "group,value\nA,1.0\nA,1.2\nA,2.0\n");
  write_file("empty.csv", "");
  write_file("headonly.csv", "group,value\n");
  write_file("ragged.csv", "group,value\nA,1\nA,2,3\n");
  write_file("quote.csv", "group,value\nA,\"1\nA,2\n");
  write_file("semi.csv", "group;value\nA;1\nA;2\nB;3\nB;4\n");

  const char *missing[] = {"groups.csv:1", "no column \"grp\"", "--group", "did you mean \"group\"",
                           NULL};
  expect_error("missing column", "anova groups.csv --group grp --value value", 1, missing);

  const char *nonnum[] = {"nonnum.csv:3", "column \"value\" (column 2)", "\"1,2\" is not a number",
                          "decimal separator", NULL};
  expect_error("non-numeric cell", "anova nonnum.csv --group group --value value", 1, nonnum);

  const char *one[] = {"groups.csv:5", "group \"b\" has only one value", "at least 2 values",
                       "a group \"B\" exists", NULL};
  expect_error("group with one value", "anova groups.csv --group group --value value", 1, one);

  const char *single[] = {"single.csv", "single group (\"A\", 3 values)", "at least 2 groups",
                          NULL};
  /* --group and --value swapped: every value its own group. */
  write_file("trials.csv", "trial,depth_mm\n1,1.25\n1,1.31\n2,1.40\n2,1.38\n");
  const char *swapped[] = {"trials.csv:2", "group \"1.25\" has only one value",
                           "--group and --value swapped?", NULL};
  expect_error("swapped columns", "anova trials.csv --group depth_mm --value trial", 1, swapped);
  /* Two options naming one column (by its case, or by number) would compare it with itself
   * (Bland-Altman SD 0, "criteria: MET"): a wrong command line, exit 2, nothing printed. */
  const char *same_ab[] = {"--a \"value\" and --b \"VALUE\" name the same column of groups.csv", NULL};
  expect_error("usage: --a and --b one column", "bland-altman groups.csv --a value --b VALUE", 2, same_ab);
  const char *same_num[] = {"--a \"2\" and --b \"value\" name the same column", "(\"value\", column 2)", NULL};
  expect_error("usage: --a by number, --b by name", "rmse groups.csv --a 2 --b value", 2, same_num);
  const char *same_gv[] = {"--group \"group\" and --value \"1\" name the same column", NULL};
  expect_error("usage: --group and --value one column", "anova groups.csv --group group --value 1", 2, same_gv);
  const char *label[] = {"groups.csv:2", "\"A\" is not a number", "looks like a label", NULL};
  expect_error("label as value", "anova groups.csv --group value --value group", 1, label);
  expect_error("fewer than 2 groups", "anova single.csv --group group --value value", 1, single);

  const char *empty[] = {"empty.csv", "the file is empty", "header row", NULL};
  expect_error("empty file", "anova empty.csv --group group --value value", 1, empty);

  const char *head[] = {"headonly.csv:1", "no data rows", NULL};
  expect_error("header only", "bland-altman headonly.csv --a group --b value", 1, head);

  const char *ragged[] = {"ragged.csv:3", "3 comma-separated fields", "header (line 1) has 2",
                          NULL};
  expect_error("ragged row", "anova ragged.csv --group group --value value", 1, ragged);

  const char *quote[] = {"quote.csv:2", "never closed", NULL};
  expect_error("unterminated quote", "anova quote.csv --group group --value value", 1, quote);

  const char *semi[] = {"semi.csv:1", "--sep ';'", NULL};
  expect_error("semicolon file", "anova semi.csv --group group --value value", 1, semi);

  const char *nofile[] = {"nosuch.csv", "cannot open", NULL};
  expect_error("missing file", "rmse nosuch.csv --a x --b y", 1, nofile);

  const char *usage[] = {"needs --a COL and --b COL", NULL};
  expect_error("usage: missing --b", "bland-altman groups.csv --a value", 2, usage);
  const char *unknown[] = {"unknown command \"anvoa\"", NULL};
  expect_error("usage: unknown command", "anvoa groups.csv", 2, unknown);

  /* Failures that say why: a - b or a shift beyond the largest double names its row (it said
   * "could not be computed (error -1)"), a directory or a log file that cannot be opened says
   * the system's reason (it said "read error", "cannot open it"). */
  write_file("pairs.csv", "a,b\n1,1.1\n2,2.3\n3,2.9\n");
  write_file("big.csv", "a,b\n1,2\n1e308,-1e308\n3,4\n");
  const char *big_ab[] = {"big.csv:3", "too large to analyse", "a - b exceeds the largest double", NULL};
  expect_error("a - b beyond the largest double", "bland-altman big.csv --a a --b b", 1, big_ab);
  expect_error("a - b beyond the largest double (rmse)", "rmse big.csv --a a --b b", 1, big_ab);
  write_file("bigg.csv", "g,v\nA,1e308\nA,-1e308\nB,1\nB,2\n");
  const char *big_g[] = {"bigg.csv:3", "too large to analyse", "difference from line 2's value", NULL};
  expect_error("a group spread beyond the largest double", "anova bigg.csv --group g --value v", 1, big_g);
  const char *isdir[] = {"cannot read it: Is a directory", NULL};
  expect_error("a directory as the CSV", "rmse . --a a --b b", 1, isdir);
  const char *nolog[] = {"--log-file", "cannot open it: No such file or directory", NULL};
  expect_error("a log file in a missing directory", "rmse pairs.csv --a a --b b --log-file no/such/dir.log", 2, nolog);
  char longlog[1200 + 64];
  snprintf(longlog, sizeof longlog, "rmse pairs.csv --a a --b b --log-file %01200d", 0);
  const char *toolong[] = {"cannot open it: File name too long", NULL};
  expect_error("a log file name of 1200 characters", longlog, 2, toolong);

  /* Results that cannot be written (stdout on a full disk) are no success: exit 1, and why. */
  const char *full[] = {"rmse pairs.csv --a a --b b --json", "bland-altman pairs.csv --a a --b b", "--help"};
  for (int k = 0; k < 3; ++k) {
    result f = run_to(full[k], "/dev/full");
    char buf[256];
    snprintf(buf, sizeof buf, "palp-stats %s >/dev/full: exit 1 (got %d) and \"cannot write the results to stdout: "
             "No space left on device\"", full[k], f.status);
    check(buf, f.status == 1 && strstr(f.err, "cannot write the results to stdout: No space left on device"));
    result_free(&f);
  }

  /* The semicolon file works once told. */
  result r = run("anova semi.csv --group group --value value --sep ';' --json");
  check("--sep ';' exit 0", r.status == 0);
  cJSON *j = cJSON_Parse(r.out);
  /* groups {1,2} and {3,4}: SS_between = 4 (means 1.5, 3.5, grand 2.5), SS_within = 1, F = 8 */
  if (j) {
    check_rel("--sep ';' F = 8", num(j, "anova.f"), 8.0, 1e-12);
    cJSON_Delete(j);
  } else {
    check("--sep ';' JSON", 0);
  }
  result_free(&r);
}

/* A file over the 16 MiB bound (PALP_CSV_MAX_BYTES; session 81 review: there was no
 * bound, and the reader took 40-70 times the file size) is refused before it is read:
 * a sparse file of 16 MiB + 1 byte (no disk, no time), exit 1 and the bound named. */
static void test_too_big(void) {
  char path[1024];
  snprintf(path, sizeof path, "%s/big.csv", dir);
  FILE *f = fopen(path, "w");
  if (!f || fputs("a,b\n", f) < 0 || fclose(f) != 0 || truncate(path, (16L << 20) + 1) != 0) {
    check("big.csv made", 0);
    return;
  }
  const char *needles[] = {"big.csv", "more than the 16 MiB", NULL};
  expect_error("file over 16 MiB", "rmse big.csv --a a --b b", 1, needles);
  remove(path);
}

int main(int argc, char **argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: %s PALP_STATS WORKDIR\n", argv[0]);
    return 2;
  }
  /* Commands run inside dir, so the tool path must not be relative. */
  static char tool_abs[4096];
  if (!realpath(argv[1], tool_abs)) {
    perror(argv[1]);
    return 2;
  }
  tool = tool_abs;
  dir = argv[2];
  mkdir(dir, 0755);
  test_smls07();
  test_anova_hand();
  test_bland_altman();
  test_far_apart();
  test_huge();
  test_errors();
  test_too_big();
  printf("%d checks, %d failures\n", checks, failures);
  return failures ? 1 : 0;
}
