/* palp-review class --exercise NAME [--since DATE] --out FILE.html [--csv FILE]: every session of
 * one exercise side by side (a table of metrics and score, small multiples of the coverage maps)
 * and each trainee's progress (score per session, oldest first). Pruned sessions appear with
 * their stored metrics and no maps. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "assess_svg.h"
#include "palp_assess.h" /* palp_shown_tenths */
#include "grades.h"
#include "palp_app.h"
#include "review.h"
#include "session_row.h"

typedef review_row row;

/* "15, 1.00": the strips and their order where the review shows them, else "-". */
static void class_strips(const palp_assess_result *m, char *buf, size_t len) {
  if (review_strips_shown(m)) snprintf(buf, len, "%d, %.2f", m->evidence.strips, m->evidence.sweep_monotony);
  else snprintf(buf, len, "-");
}

/* Appends uid to the list in buf ("a, b"), ", ..." once it is full. */
static void uid_list_add(char *buf, size_t len, const char *uid) {
  const size_t used = strlen(buf);
  if (used + strlen(uid) + 8 < len) snprintf(buf + used, len - used, "%s%s", used ? ", " : "", uid);
  else if (used + 5 < len && !strstr(buf, "...")) snprintf(buf + used, len - used, ", ...");
}

int review_class(palp_log *log, palp_db *db, int argc, char **argv) {
  const char *exercise = NULL, *out = NULL, *csv = NULL;
  palp_db_filter flt = {0};
  static const char *const takes_value[] = {"--exercise", "--out", "--csv", "--since", NULL};
  for (int i = 0; i < argc; i++) {
    if (!review_option_known(argv[i], takes_value)) {
      fprintf(stderr, "palp-review class: unknown option %s\n", argv[i]);
      return REVIEW_ERROR;
    }
    if (i + 1 >= argc) {
      fprintf(stderr, "palp-review class: %s needs a value\n", argv[i]);
      return REVIEW_ERROR;
    }
    if (!strcmp(argv[i], "--exercise")) exercise = argv[++i];
    else if (!strcmp(argv[i], "--out")) out = argv[++i];
    else if (!strcmp(argv[i], "--csv")) csv = argv[++i];
    else { /* --since */
      flt.has_since = 1;
      if (review_parse_date(argv[++i], &flt.since_unix_s)) {
        fprintf(stderr, "palp-review class: --since: expected YYYY-MM-DD[THH:MM[:SS]], got '%s'\n", argv[i]);
        return REVIEW_ERROR;
      }
    }
  }
  if (!exercise || !out) {
    fprintf(stderr, "palp-review class: --exercise NAME and --out FILE.html are required\n");
    return REVIEW_ERROR;
  }
  /* --csv -: stdout carries the CSV alone, for a pipe; the table for the terminal goes to stderr */
  FILE *tty = csv && !strcmp(csv, "-") ? stderr : stdout;
  palp_db_session_info *v;
  int n;
  if (palp_db_list_sessions(db, &flt, &v, &n)) {
    palp_log_error(log, "class: %s", palp_db_errmsg(db));
    return REVIEW_ERROR;
  }
  row *rows = calloc((size_t)(n ? n : 1), sizeof *rows);
  if (!rows) {
    free(v);
    return REVIEW_ERROR;
  }
  /* A session left out is named: one whose log could not be read (its exercise, samples or stored
   * metrics: a damaged page, say) also makes the run a failure (exit 2), the report lacking it; one
   * whose logged exercise or scene does not parse is warned of, as show reports it and exits 0. A
   * session of force contacts only (ENOTFOUND) has nothing to assess: no error. */
  int nr = 0, left = 0, unread = 0;
  char left_uids[512] = "", unread_uids[512] = "";
  for (int i = 0; i < n; i++) {
    char name[64];
    int rc = palp_db_session_exercise(db, v[i].id, name, sizeof name, NULL);
    if (rc == PALP_DB_ENOTFOUND || (rc == 0 && strcmp(name, exercise))) continue;
    if (rc == 0 && (rc = review_row_fill(log, "class", db, &v[i], &rows[nr])) == 0) {
      nr++;
      continue;
    }
    if (rc == PALP_DB_ENOTFOUND) continue;
    if (!rows[nr].s.uid[0]) /* review_row_fill warned with the reason; the exercise's read did not */
      palp_log_warn(log, "class: %s left out: its exercise could not be read: %s", v[i].uid, palp_db_errmsg(db));
    memset(&rows[nr], 0, sizeof rows[nr]);
    left++;
    uid_list_add(left_uids, sizeof left_uids, v[i].uid);
    if (review_row_unreadable(rc)) unread++, uid_list_add(unread_uids, sizeof unread_uids, v[i].uid);
  }
  if (nr == 0 && left) {
    char why[96] = "";
    if (unread == left) snprintf(why, sizeof why, " because the log could not be read");
    else if (unread) snprintf(why, sizeof why, ", %d because the log could not be read", unread);
    fprintf(stderr, "palp-review class: exercise '%s': no session could be assessed: %d left out%s (%s; palp-review "
            "show SESSION says why)\n", exercise, left, why, left_uids);
    free(v), free(rows);
    return REVIEW_ERROR;
  }
  if (nr == 0) {
    /* Name what there is, so a typo is seen at once. */
    char known[512] = "";
    size_t used = 0;
    for (int i = 0; i < n && used + 70 < sizeof known; i++) {
      char name[64];
      if (palp_db_session_exercise(db, v[i].id, name, sizeof name, NULL) || strstr(known, name)) continue;
      used += (size_t)snprintf(known + used, sizeof known - used, "%s%s", used ? ", " : "", name);
    }
    fprintf(stderr, "palp-review class: no session of exercise '%s'%s in this log (exercises logged: %s)\n", exercise,
            flt.has_since ? " since that date" : "", used ? known : "none");
    free(v), free(rows);
    return REVIEW_ERROR;
  }
  free(v);
  int rc = unread ? REVIEW_ERROR : REVIEW_OK;
  /* The instructor at a terminal: the same table as the report's, as text. */
  fprintf(tty, "class report: exercise %s, %d session%s\n", exercise, nr, nr == 1 ? "" : "s");
  /* OUTSIDE[s]: how long the phantom's model was outside its valid range (review_valid_range;
   * "-" where the log does not say), beside the pressure levels that rest on its forces */
  /* STRIPS: how many, and the share of the steps between them that keep their direction
   * (docs/assessment.md, "Strips and their order"); class_strips */
  fprintf(tty, "%-12s %-30s %-10s %7s %5s %7s %7s %7s %-15s %-9s %7s %6s %-6s %10s %s\n", "TRAINEE", "SESSION", "DATE",
         "FOUND", "FALSE", "LIGHT", "MEDIUM", "DEEP", "PATTERN", "STRIPS", "TIME[s]", "SCORE", "RUBRIC", "OUTSIDE[s]",
         "GRADE");
  for (int i = 0; i < nr; i++) {
    const palp_assess_result *m = &rows[i].a.r;
    char t[64], found[16], strips[24];
    review_fmt_time(rows[i].s.start_unix_s, t, sizeof t);
    t[10] = '\0'; /* the date */
    snprintf(found, sizeof found, "%d/%d", m->found, m->lesion_count);
    class_strips(m, strips, sizeof strips);
    fprintf(tty, "%-12.12s %-30.30s %-10s %7s %5d %6.1f%% %6.1f%% %6.1f%% %-15s %-9s %7.1f %6.1f %-6s %10s %s\n",
           rows[i].s.trainee, rows[i].s.uid, t, found, m->false_positives, 100 * m->coverage[0],
           100 * m->coverage[1], 100 * m->coverage[2], palp_pattern_name(m->pattern), strips, m->duration,
           palp_shown_tenths(m->score, NAN, m->pass), m->pass ? "pass" : "fail", rows[i].outside,
           rows[i].grade[0] ? rows[i].grade : "-");
  }
  /* Attempts that were not blind (docs/assessment.md, "Debrief"), under the table they qualify. */
  for (int i = 0; i < nr; i++)
    if (rows[i].told[0]) fprintf(tty, "not blind: %s: %s\n", rows[i].s.uid, rows[i].told);
  if (csv && review_rows_csv(log, "class", db, csv, rows, nr) != 0) rc = REVIEW_ERROR;
  FILE *f = review_fopen_out(log, out);
  if (!f) {
    if (errno != EINVAL) palp_log_error(log, "class: %s: %s", out, strerror(errno)); /* EINVAL: said already */
    rc = REVIEW_ERROR;
  } else {
    review_html_head(f, "palp class report: ", "Class report: exercise ", "exercise", exercise,
                     ".multiples{display:flex;flex-wrap:wrap;gap:14px}.multiples figure{margin:0}"
                     "figcaption{font-size:12px}.key span{display:inline-block;width:12px;height:12px;margin:0 4px 0 12px}");
    fprintf(f, "<p>%d session%s. Definitions: docs/assessment.md; names: docs/naming.md.</p>\n", nr,
            nr == 1 ? "" : "s");
    fputs("<h2>Side by side</h2>\n<table id=\"class-table\"><tr><th>trainee</th><th>session</th><th>started</th>"
          "<th>lesions found</th><th>false positives</th><th>coverage light</th><th>medium</th><th>deep</th>"
          "<th>search pattern</th><th>strips, in order</th><th>time [s]</th><th>peak force [N]</th><th>score</th>"
          "<th>rubric</th><th>outside the model's valid range [s]</th><th>grade</th></tr>\n", f);
    for (int i = 0; i < nr; i++) {
      const row *r = &rows[i];
      const palp_assess_result *m = &r->a.r;
      fputs("<tr class=\"trainee-row\"><td class=\"t trainee\">", f);
      html_str(f, r->s.trainee);
      fputs("</td><td class=\"t nw\">", f);
      html_str(f, r->s.uid);
      /* The columns in the terminal table's order (the strips beside the pattern they qualify). */
      char strips[24];
      class_strips(m, strips, sizeof strips);
      fputs("</td>", f);
      review_html_started_cell(f, r->s.start_unix_s);
      fprintf(f,
              "<td>%d of %d</td><td>%d</td><td>%.1f%%</td><td>%.1f%%</td><td>%.1f%%</td>"
              "<td class=\"t\">%s</td><td class=\"strips nw\">%s</td><td>%.1f</td><td>%.2f</td>"
              "<td class=\"score\">%.1f</td><td%s>%s",
              m->found, m->lesion_count, m->false_positives,
              100 * m->coverage[0], 100 * m->coverage[1], 100 * m->coverage[2], palp_pattern_name(m->pattern), strips,
              m->duration, m->peak_force, palp_shown_tenths(m->score, NAN, m->pass), m->pass ? "" : " class=\"fail\"",
              m->pass ? "pass" : "fail");
      fprintf(f, "</td><td class=\"outside\">%s</td><td class=\"t\">", r->outside);
      html_str(f, r->grade);
      fputs("</td></tr>\n", f);
    }
    fputs("</table>\n", f);
    review_html_not_blind(f, rows, nr);
    fputs("<h2>Coverage maps</h2>\n<p class=\"key\">Seen from above (12 o'clock = +y). Palpated at "
          "<span style=\"background:#56b4e9\"></span>light <span style=\"background:#e69f00\"></span>medium "
          "<span style=\"background:#009e73\"></span>deep pressure; <span style=\"background:#e6e6e6\"></span>never.</p>\n"
          "<div class=\"multiples\">\n", f);
    for (int i = 0; i < nr; i++) {
      if (!rows[i].computed) continue;
      fputs("<figure class=\"small-multiple\"><figcaption>", f);
      html_str(f, rows[i].s.trainee);
      fprintf(f, " - %.1f</figcaption>\n", palp_shown_tenths(rows[i].a.r.score, NAN, rows[i].a.r.pass));
      for (int b = 0; b < 3; b++) {
        char id[64];
        snprintf(id, sizeof id, "cov-%d-%s", i + 1, palp_band_name(b));
        review_svg_coverage(f, &rows[i].a, b, 90, id);
      }
      fputs("</figure>\n", f);
    }
    fputs("</div>\n<h2>Progress</h2>\n<table id=\"progress\"><tr><th>trainee</th><th>sessions</th>"
          "<th>scores, oldest first</th><th>chart</th></tr>\n", f);
    int *done = calloc((size_t)(nr > 0 ? nr : 1), sizeof *done);
    double *sc = malloc(sizeof *sc * (size_t)(nr > 0 ? nr : 1));
    for (int i = 0; done && sc && i < nr; i++) {
      if (done[i]) continue;
      int k = 0;
      for (int j = i; j < nr; j++)
        if (!done[j] && !strcmp(rows[j].s.trainee, rows[i].s.trainee))
          done[j] = 1, sc[k++] = palp_shown_tenths(rows[j].a.r.score, NAN, rows[j].a.r.pass);
      fputs("<tr class=\"progress-row\" data-trainee=\"", f);
      html_str(f, rows[i].s.trainee);
      fputs("\"><td class=\"t\">", f);
      html_str(f, rows[i].s.trainee);
      fprintf(f, "</td><td class=\"sessions\">%d</td><td class=\"t\">", k);
      for (int j = 0; j < k; j++) fprintf(f, "%s%.1f", j ? ", " : "", sc[j]);
      fputs("</td><td>", f);
      char id[64];
      snprintf(id, sizeof id, "progress-%d", i + 1);
      review_svg_scores(f, sc, k, 160, 40, id);
      fputs("</td></tr>\n", f);
    }
    free(done), free(sc);
    fputs("</table>\n<p style=\"font-size:11px;color:#777\">Generated by palp-review from the session log.</p>\n"
          "</body></html>\n", f);
    if (review_close_out(f) != 0) {
      palp_log_error(log, "class: %s: %s (not written; a file already there is kept)", out, strerror(errno));
      rc = REVIEW_ERROR;
    } else fprintf(tty, "class: wrote %s (%d sessions)\n", out, nr);
  }
  if (unread)
    fprintf(stderr, "palp-review class: %d session%s left out because the log could not be read (%s; palp-review show "
            "SESSION says why)\n", unread, unread == 1 ? "" : "s", unread_uids);
  for (int i = 0; i < nr; i++) review_row_free(&rows[i]);
  free(rows);
  return rc;
}
