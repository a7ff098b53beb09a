/* palp-review trainee NAME [--since DATE] [--until DATE] [--csv FILE]: one trainee's record, for the
 * instructor's talk with her: every session of hers, oldest first (exercise, lumps found, marks near
 * no lump, coverage, pattern, score, whether the attempt was blind, the instructor's grade), then each
 * exercise's scores in order, then what to work on: the metrics her latest session of each exercise
 * did not pass, the most often missed first, in the words her station and page use
 * (palp_metric_to_work_on). The class report (class.c) is the same sessions seen by exercise. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "palp_app.h"
#include "review.h"
#include "session_row.h"

int review_trainee(palp_log *log, palp_db *db, int argc, char **argv) {
  const char *name = NULL, *csv = NULL;
  palp_db_filter flt = {0};
  for (int i = 0; i < argc; i++) {
    if (argv[i][0] != '-') {
      if (name) {
        fprintf(stderr, "palp-review trainee: one trainee at a time ('%s' and '%s')\n", name, argv[i]);
        return REVIEW_ERROR;
      }
      name = argv[i];
      continue;
    }
    if (i + 1 >= argc) {
      fprintf(stderr, "palp-review trainee: %s needs a value\n", argv[i]);
      return REVIEW_ERROR;
    }
    if (!strcmp(argv[i], "--csv")) csv = argv[++i];
    else if (!strcmp(argv[i], "--since") || !strcmp(argv[i], "--until")) {
      double t;
      if (review_parse_date(argv[i + 1], &t)) {
        fprintf(stderr, "palp-review trainee: %s: expected YYYY-MM-DD[THH:MM[:SS]], got '%s'\n", argv[i], argv[i + 1]);
        return REVIEW_ERROR;
      }
      if (!strcmp(argv[i], "--since")) flt.since_unix_s = t;
      else flt.until_unix_s = t;
      i++;
    } else {
      fprintf(stderr, "palp-review trainee: unknown option %s\n", argv[i]);
      return REVIEW_ERROR;
    }
  }
  if (!name || !name[0]) {
    fprintf(stderr, "palp-review trainee: NAME is required (palp-review list gives the trainees' names)\n");
    return REVIEW_ERROR;
  }
  flt.trainee = name;
  palp_db_session_info *v;
  int n;
  if (palp_db_list_sessions(db, &flt, &v, &n)) {
    palp_log_error(log, "trainee: %s", palp_db_errmsg(db));
    return REVIEW_ERROR;
  }
  if (n == 0) {
    fprintf(stderr, "palp-review trainee: no session of trainee '%s'%s in this log (palp-review list gives the names)\n",
            name, flt.since_unix_s > 0 || flt.until_unix_s > 0 ? " in that time" : "");
    free(v);
    return REVIEW_ERROR;
  }
  review_row *rows = calloc((size_t)n, sizeof *rows);
  if (!rows) {
    free(v);
    return REVIEW_ERROR;
  }
  /* A session without a fingertip (force contacts only: the paper's experiment) has nothing to
   * assess: counted, not listed; one that fails otherwise is left out with a warning. */
  int nr = 0, forced = 0;
  for (int i = 0; i < n; i++) {
    const int rc = review_row_fill(NULL, "trainee", db, &v[i], &rows[nr]);
    if (rc == 0) nr++;
    else if (rc == PALP_DB_ENOTFOUND) forced++;
    else palp_log_warn(log, "trainee: %s left out: it could not be assessed (palp-review show says why)", v[i].uid);
  }
  free(v);
  if (nr == 0) {
    printf("trainee %s: %d session%s, none with a fingertip to assess (%d of force contacts only; palp-review list "
           "shows them)\n", name, n, n == 1 ? "" : "s", forced);
    free(rows);
    return REVIEW_OK;
  }
  int practice = 0, exercises = 0;
  for (int i = 0; i < nr; i++) practice += !rows[i].a.has_exercise;
  char first[64], last[64];
  review_fmt_time(rows[0].s.start_unix_s, first, sizeof first);
  review_fmt_time(rows[nr - 1].s.start_unix_s, last, sizeof last);
  first[10] = last[10] = '\0'; /* the dates */
  printf("trainee %s: %d session%s assessed, %s to %s: %d of exercises, %d of free practice", name, nr,
         nr == 1 ? "" : "s", first, last, nr - practice, practice);
  if (forced) printf("; %d of force contacts only (nothing to assess)", forced);
  printf("\n");
  /* BLIND: "no" when an earlier session of hers was debriefed on these very lesions (the review's
   * "not blind"), "-" for free practice and a pruned session (its lesions are not kept). */
  printf("%-30s %-10s %-16s %7s %5s %7s %7s %7s %-15s %6s %-6s %-5s %s\n", "SESSION", "DATE", "EXERCISE", "FOUND",
         "FALSE", "LIGHT", "MEDIUM", "DEEP", "PATTERN", "SCORE", "RUBRIC", "BLIND", "GRADE");
  for (int i = 0; i < nr; i++) {
    const review_row *r = &rows[i];
    const palp_assess_result *m = &r->a.r;
    const int ex = r->a.has_exercise;
    char t[64], found[16] = "-", score[16] = "-";
    review_fmt_time(r->s.start_unix_s, t, sizeof t);
    t[10] = '\0';
    if (ex) {
      snprintf(found, sizeof found, "%d/%d", m->found, m->lesion_count);
      snprintf(score, sizeof score, "%.1f", m->score);
    }
    printf("%-30.30s %-10s %-16.16s %7s %5d %6.1f%% %6.1f%% %6.1f%% %-15s %6s %-6s %-5s %s\n", r->s.uid, t,
           ex ? r->a.exercise_name : "(practice)", found, m->false_positives, 100 * m->coverage[0],
           100 * m->coverage[1], 100 * m->coverage[2], palp_pattern_name(m->pattern), score,
           ex ? (m->pass ? "pass" : "fail") : "-", ex && r->computed ? (r->told[0] ? "no" : "yes") : "-",
           r->grade[0] ? r->grade : "-");
  }
  /* By exercise, in the order she first met each: her scores in order, how many passed, the latest. */
  int missed[PALP_METRIC_COUNT] = {0}, judged = 0, pruned_latest = 0;
  for (int i = 0; i < nr; i++) {
    const review_row *r = &rows[i];
    if (!r->a.has_exercise) continue;
    int seen = 0;
    for (int j = 0; j < i && !seen; j++)
      seen = rows[j].a.has_exercise && !strcmp(rows[j].a.exercise_name, r->a.exercise_name);
    if (seen) continue;
    if (!exercises++) printf("by exercise, oldest first:\n");
    int k = 0, passed = 0, latest = i;
    printf("  %-16s scores ", r->a.exercise_name);
    for (int j = i; j < nr; j++) {
      if (!rows[j].a.has_exercise || strcmp(rows[j].a.exercise_name, r->a.exercise_name)) continue;
      printf("%s%.1f", k++ ? ", " : "", rows[j].a.r.score);
      passed += rows[j].a.r.pass;
      latest = j;
    }
    printf("; passed %d of %d; latest %.1f %s\n", passed, k, rows[latest].a.r.score,
           rows[latest].a.r.pass ? "pass" : "fail");
    /* what her latest attempt at it did not pass (a pruned session keeps no per-metric pass) */
    if (!rows[latest].computed) {
      pruned_latest++;
      continue;
    }
    judged++;
    for (int mt = 0; mt < PALP_METRIC_COUNT; mt++) missed[mt] += !rows[latest].a.r.pass_metric[mt];
  }
  if (judged) {
    printf("to work on (what the latest session of each exercise did not pass, the most often first):\n");
    int any = 0;
    for (int times = judged; times >= 1; times--)
      for (int mt = 0; mt < PALP_METRIC_COUNT; mt++)
        if (missed[mt] == times)
          any++, printf("  %s (%d of %d exercise%s)\n", palp_metric_to_work_on(mt), times, judged, judged == 1 ? "" : "s");
    if (!any) printf("  nothing: every metric passed\n");
  }
  if (pruned_latest)
    printf("(%d exercise%s' latest session pruned: its metrics' passes are not kept)\n", pruned_latest,
           pruned_latest == 1 ? "" : "s");
  for (int i = 0; i < nr; i++)
    if (rows[i].told[0]) printf("not blind: %s: %s\n", rows[i].s.uid, rows[i].told);
  int rc = REVIEW_OK;
  if (csv) {
    FILE *c = strcmp(csv, "-") ? palp_app_fopen_private(csv) : stdout;
    if (!c) {
      palp_log_error(log, "trainee: %s: %s", csv, strerror(errno));
      rc = REVIEW_ERROR;
    } else {
      review_metrics_csv_header(c);
      for (int i = 0; i < nr; i++) review_metrics_csv_row(c, db, &rows[i].s, &rows[i].a, rows[i].outside_s);
      if (c != stdout && fclose(c)) rc = REVIEW_ERROR;
    }
  }
  for (int i = 0; i < nr; i++) review_row_free(&rows[i]);
  free(rows);
  return rc;
}
