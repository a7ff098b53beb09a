/* palp-review trainee NAME [--since DATE] [--until DATE] [--csv FILE] [--out FILE.html]: one
 * trainee's record, for the instructor's talk with her: every session of hers, oldest first
 * (exercise, lumps found, marks near no lump, coverage, pattern, score, whether the attempt was
 * blind, the instructor's grade), then each exercise's scores in order, then what to work on: the
 * metrics her latest session of each exercise did not pass, the most often missed first, in the
 * words her station and page use (palp_metric_to_work_on). The class report (class.c) is the same
 * sessions seen by exercise. --out writes the same as one self-contained HTML page (no script,
 * nothing fetched), each exercise's scores also as a small chart, to print for the talk. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "assess_svg.h"
#include "palp_app.h"
#include "review.h"
#include "session_row.h"

/* What the terminal and the page both say, worked out once from the rows (oldest first). */
typedef struct record {
  int *exercise_first; /* [rows] the row of each exercise's first session, in the order she met them */
  int exercises;
  int missed[PALP_METRIC_COUNT]; /* over the latest session of each exercise whose passes are kept */
  int judged, pruned_latest;
} record;

static int same_exercise(const review_row *a, const review_row *b) {
  return a->a.has_exercise && b->a.has_exercise && !strcmp(a->a.exercise_name, b->a.exercise_name);
}

/* 0, or -1 when memory ran out; record_free after either. */
static int record_of(const review_row *rows, int nr, record *rec) {
  memset(rec, 0, sizeof *rec);
  rec->exercise_first = malloc(sizeof *rec->exercise_first * (size_t)(nr > 0 ? nr : 1));
  if (!rec->exercise_first) return -1;
  for (int i = 0; i < nr; i++) {
    if (!rows[i].a.has_exercise) continue;
    int seen = 0;
    for (int j = 0; j < i && !seen; j++) seen = same_exercise(&rows[j], &rows[i]);
    if (seen) continue;
    rec->exercise_first[rec->exercises++] = i;
    int latest = i;
    for (int j = i; j < nr; j++)
      if (same_exercise(&rows[j], &rows[i])) latest = j;
    /* what her latest attempt at it did not pass (a pruned session keeps no per-metric pass) */
    if (!rows[latest].computed) {
      rec->pruned_latest++;
      continue;
    }
    rec->judged++;
    for (int mt = 0; mt < PALP_METRIC_COUNT; mt++) rec->missed[mt] += !rows[latest].a.r.pass_metric[mt];
  }
  return 0;
}

static void record_free(record *rec) { free(rec->exercise_first); }

/* The metrics to work on into order[], the most often missed first (ties in the metrics' order); how many. */
static int work_on_order(const record *rec, int order[PALP_METRIC_COUNT]) {
  int n = 0;
  for (int times = rec->judged; times >= 1; times--)
    for (int mt = 0; mt < PALP_METRIC_COUNT; mt++)
      if (rec->missed[mt] == times) order[n++] = mt;
  return n;
}

/* The scores of exercise e's sessions, oldest first, into sc; how many; *passed, *latest (a row). */
static int exercise_scores(const review_row *rows, int nr, int first, double *sc, int *passed, int *latest) {
  int k = 0;
  *passed = 0, *latest = first;
  for (int j = first; j < nr; j++) {
    if (!same_exercise(&rows[j], &rows[first])) continue;
    sc[k++] = rows[j].a.r.score;
    *passed += rows[j].a.r.pass;
    *latest = j;
  }
  return k;
}

static int write_page(const char *path, const char *name, const review_row *rows, int nr, const record *rec,
                      const char *summary) {
  FILE *f = palp_app_fopen_private(path);
  if (!f) return -1;
  review_html_head(f, "palp trainee record: ", "Trainee record: ", "trainee", name, ".muted{color:#777}");
  fputs("<p id=\"summary\">", f);
  html_str(f, summary);
  fputs(". Definitions: docs/assessment.md. The automatic score informs the grade; the grade is the "
        "instructor's.</p>\n<h2>Sessions, oldest first</h2>\n<table id=\"record\"><tr><th>session</th><th>started</th>"
        "<th>exercise</th><th>lesions found</th><th>false positives</th><th>coverage light</th><th>medium</th>"
        "<th>deep</th><th>search pattern</th><th>time [s]</th><th>score</th><th>rubric</th><th>blind</th>"
        "<th>grade</th></tr>\n", f);
  for (int i = 0; i < nr; i++) {
    const review_row *r = &rows[i];
    const palp_assess_result *m = &r->a.r;
    const int ex = r->a.has_exercise;
    fputs("<tr class=\"record-row\"><td class=\"t nw session\">", f);
    html_str(f, r->s.uid);
    fputs("</td>", f);
    review_html_started_cell(f, r->s.start_unix_s);
    fputs("<td class=\"t exercise\">", f);
    html_str(f, ex ? r->a.exercise_name : "(practice)");
    if (ex) fprintf(f, "</td><td>%d of %d", m->found, m->lesion_count);
    else fputs("</td><td class=\"muted\">-", f);
    fprintf(f, "</td><td>%d</td><td>%.1f%%</td><td>%.1f%%</td><td>%.1f%%</td><td class=\"t\">%s</td><td>%.1f</td>",
            m->false_positives, 100 * m->coverage[0], 100 * m->coverage[1], 100 * m->coverage[2],
            palp_pattern_name(m->pattern), m->duration);
    if (ex)
      fprintf(f, "<td class=\"score\">%.1f</td><td%s>%s</td>", m->score, m->pass ? "" : " class=\"fail\"",
              m->pass ? "pass" : "fail");
    else fputs("<td class=\"score muted\">-</td><td class=\"muted\">-</td>", f);
    fprintf(f, "<td class=\"blind%s\">%s</td><td class=\"t grade\">", ex && r->computed && r->told[0] ? " fail" : "",
            ex && r->computed ? (r->told[0] ? "no" : "yes") : "-");
    html_str(f, r->grade[0] ? r->grade : "-");
    fputs("</td></tr>\n", f);
  }
  fputs("</table>\n", f);
  review_html_not_blind(f, rows, nr);
  if (rec->exercises) {
    fputs("<h2>By exercise</h2>\n<table id=\"by-exercise\"><tr><th>exercise</th><th>sessions</th>"
          "<th>scores, oldest first</th><th>passed</th><th>latest</th><th>chart</th></tr>\n", f);
    double *sc = malloc(sizeof *sc * (size_t)nr);
    for (int e = 0; sc && e < rec->exercises; e++) {
      int passed, latest;
      const int k = exercise_scores(rows, nr, rec->exercise_first[e], sc, &passed, &latest);
      fputs("<tr class=\"exercise-row\"><td class=\"t\">", f);
      html_str(f, rows[rec->exercise_first[e]].a.exercise_name);
      fprintf(f, "</td><td>%d</td><td class=\"t scores\">", k);
      for (int j = 0; j < k; j++) fprintf(f, "%s%.1f", j ? ", " : "", sc[j]);
      fprintf(f, "</td><td>%d of %d</td><td%s>%.1f %s</td><td>", passed, k, rows[latest].a.r.pass ? "" : " class=\"fail\"",
              rows[latest].a.r.score, rows[latest].a.r.pass ? "pass" : "fail");
      char id[32];
      snprintf(id, sizeof id, "scores-%d", e + 1);
      review_svg_scores(f, sc, k, 160, 40, id);
      fputs("</td></tr>\n", f);
    }
    free(sc);
    fputs("</table>\n", f);
  }
  if (rec->judged) {
    fputs("<h2>To work on</h2>\n<p>What the latest session of each exercise did not pass, the most often first, in "
          "the words her station and page use.</p>\n<ul id=\"work-on\">\n", f);
    int order[PALP_METRIC_COUNT];
    const int n = work_on_order(rec, order);
    for (int k = 0; k < n; k++)
      fprintf(f, "<li data-metric=\"%s\">%s (%d of %d exercise%s)</li>\n", palp_metric_name(order[k]),
              palp_metric_to_work_on(order[k]), rec->missed[order[k]], rec->judged, rec->judged == 1 ? "" : "s");
    if (!n) fputs("<li>nothing: every metric passed</li>\n", f);
    fputs("</ul>\n", f);
  }
  fputs("<p style=\"font-size:11px;color:#777\">Generated by palp-review from the session log.</p>\n</body></html>\n", f);
  return fclose(f) ? -1 : 0;
}

int review_trainee(palp_log *log, palp_db *db, int argc, char **argv) {
  const char *name = NULL, *csv = NULL, *out = NULL;
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
    else if (!strcmp(argv[i], "--out")) out = argv[++i];
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
  int practice = 0;
  for (int i = 0; i < nr; i++) practice += !rows[i].a.has_exercise;
  char first[64], last[64];
  review_fmt_time(rows[0].s.start_unix_s, first, sizeof first);
  review_fmt_time(rows[nr - 1].s.start_unix_s, last, sizeof last);
  first[10] = last[10] = '\0'; /* the dates */
  char summary[256];
  int used = snprintf(summary, sizeof summary, "trainee %s: %d session%s assessed, %s to %s: %d of exercises, %d of free practice",
                      name, nr, nr == 1 ? "" : "s", first, last, nr - practice, practice);
  if (forced && used > 0 && (size_t)used < sizeof summary)
    snprintf(summary + used, sizeof summary - (size_t)used, "; %d of force contacts only (nothing to assess)", forced);
  printf("%s\n", summary);
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
  record rec;
  double *sc = malloc(sizeof *sc * (size_t)nr);
  if (record_of(rows, nr, &rec) != 0 || !sc) {
    free(sc);
    record_free(&rec);
    for (int i = 0; i < nr; i++) review_row_free(&rows[i]);
    free(rows);
    return REVIEW_ERROR;
  }
  if (rec.exercises) printf("by exercise, oldest first:\n");
  for (int e = 0; e < rec.exercises; e++) {
    int passed, latest;
    const int k = exercise_scores(rows, nr, rec.exercise_first[e], sc, &passed, &latest);
    printf("  %-16s scores ", rows[rec.exercise_first[e]].a.exercise_name);
    for (int j = 0; j < k; j++) printf("%s%.1f", j ? ", " : "", sc[j]);
    printf("; passed %d of %d; latest %.1f %s\n", passed, k, rows[latest].a.r.score, rows[latest].a.r.pass ? "pass" : "fail");
  }
  free(sc);
  if (rec.judged) {
    printf("to work on (what the latest session of each exercise did not pass, the most often first):\n");
    int order[PALP_METRIC_COUNT];
    const int n = work_on_order(&rec, order);
    for (int k = 0; k < n; k++)
      printf("  %s (%d of %d exercise%s)\n", palp_metric_to_work_on(order[k]), rec.missed[order[k]], rec.judged,
             rec.judged == 1 ? "" : "s");
    if (!n) printf("  nothing: every metric passed\n");
  }
  if (rec.pruned_latest)
    printf("(%d exercise%s' latest session pruned: its metrics' passes are not kept)\n", rec.pruned_latest,
           rec.pruned_latest == 1 ? "" : "s");
  for (int i = 0; i < nr; i++)
    if (rows[i].told[0]) printf("not blind: %s: %s\n", rows[i].s.uid, rows[i].told);
  int rc = REVIEW_OK;
  if (csv && review_rows_csv(log, "trainee", db, csv, rows, nr) != 0) rc = REVIEW_ERROR;
  if (out) {
    if (write_page(out, name, rows, nr, &rec, summary) != 0) {
      palp_log_error(log, "trainee: %s: %s", out, strerror(errno));
      rc = REVIEW_ERROR;
    } else printf("trainee: wrote %s\n", out);
  }
  record_free(&rec);
  for (int i = 0; i < nr; i++) review_row_free(&rows[i]);
  free(rows);
  return rc;
}
