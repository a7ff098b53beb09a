/* session_row.c - one logged session as the review's tables show it (session_row.h). */
#include "session_row.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "grades.h"
#include "palp_app.h"
#include "review.h"
#include "review_util.h"

int review_row_fill(palp_log *log, const char *cmd, palp_db *db, const palp_db_session_info *s, review_row *r) {
  memset(r, 0, sizeof *r);
  r->s = *s;
  char err[512] = "";
  int rc = review_assess(db, s, &r->a, err, sizeof err);
  if (rc == 0) r->computed = 1;
  else {
    const int stored = review_stored_metrics(db, s->id, &r->a);
    if (stored != 0) {
      /* no samples, and the metrics a prune kept cannot be read: that is why, not "force contacts only" */
      if (stored != PALP_DB_ENOTFOUND && rc == PALP_DB_ENOTFOUND) {
        snprintf(err, sizeof err, "the session_metrics table could not be read: %s", palp_db_errmsg(db));
        rc = stored;
      }
      if (log) palp_log_warn(log, "%s: %s left out: %s", cmd, s->uid, err);
      return rc < 0 ? rc : PALP_DB_ENOTFOUND;
    }
  }
  review_latest_grade(db, s->id, r->grade, sizeof r->grade);
  r->outside_s = review_valid_range_seconds(db, s);
  if (r->outside_s >= 0) snprintf(r->outside, sizeof r->outside, "%.2f", r->outside_s);
  else snprintf(r->outside, sizeof r->outside, "-");
  /* (a pruned session's stored metrics carry no lesions: it is not looked at) */
  review_told told;
  if (r->computed && review_told_before(db, s, &r->a, &told) == 1) review_told_text(s, &told, r->told, sizeof r->told);
  return 0;
}

int review_row_unreadable(int rc) { return rc <= PALP_DB_ENEWER && rc >= PALP_DB_ECOPY && rc != PALP_DB_ENOTFOUND; }

void review_row_free(review_row *r) { review_assessment_free(&r->a); }

void review_html_head(FILE *f, const char *title, const char *heading, const char *id, const char *name,
                      const char *extra_css) {
  fputs("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>", f);
  html_str(f, title);
  html_str(f, name);
  fputs("</title>\n<style>body{font-family:sans-serif;margin:24px;color:#222;max-width:1200px}"
        "table{border-collapse:collapse;margin:8px 0 20px}td,th{border:1px solid #ccc;padding:3px 5px;"
        "text-align:right;font-size:13px}th{background:#f4f4f4}td.t{text-align:left}.nw{white-space:nowrap}"
        ".fail{color:#a00}",
        f);
  fputs(extra_css, f);
  fputs("</style>\n</head><body>\n<h1>", f);
  html_str(f, heading);
  fprintf(f, "<span id=\"%s\">", id);
  html_str(f, name);
  fputs("</span></h1>\n", f);
}

void review_html_started_cell(FILE *f, double unix_s) {
  char t[64];
  review_fmt_time(unix_s, t, sizeof t);
  char *sp = strchr(t, ' ');
  if (sp) *sp = '\0';
  fprintf(f, "<td class=\"t\"><span class=\"nw\">%s</span>%s<span class=\"nw\">%s</span></td>", t, sp ? " " : "",
          sp ? sp + 1 : "");
}

void review_html_not_blind(FILE *f, const review_row *rows, int n) {
  for (int i = 0; i < n; i++)
    if (rows[i].told[0]) {
      fputs("<p class=\"fail told-before\">Not blind: ", f);
      html_str(f, rows[i].s.uid);
      fputs(": ", f);
      html_str(f, rows[i].told);
      fputs(".</p>\n", f);
    }
}

int review_rows_csv(palp_log *log, const char *cmd, palp_db *db, const char *path, const review_row *rows, int n) {
  FILE *c = strcmp(path, "-") ? review_fopen_out(log, path) : stdout;
  if (!c) {
    palp_log_error(log, "%s: %s: %s", cmd, path, strerror(errno));
    return -1;
  }
  review_metrics_csv_header(c);
  for (int i = 0; i < n; i++) review_metrics_csv_row(c, db, &rows[i].s, &rows[i].a, rows[i].outside_s);
  if (review_close_out(c) == 0) return 0;
  palp_log_error(log, "%s: %s: %s (%s)", cmd, c == stdout ? "standard output" : path, strerror(errno),
                 c == stdout ? "the CSV is incomplete" : "not written; a file already there is kept");
  return -1;
}
