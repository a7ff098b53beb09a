/* session_row.c - one logged session as the review's tables show it (session_row.h). */
#include "session_row.h"

#include <stdio.h>
#include <string.h>

#include "grades.h"
#include "review_util.h"

int review_row_fill(palp_log *log, const char *cmd, palp_db *db, const palp_db_session_info *s, review_row *r) {
  memset(r, 0, sizeof *r);
  r->s = *s;
  char err[512] = "";
  const int rc = review_assess(db, s, &r->a, err, sizeof err);
  if (rc == 0) r->computed = 1;
  else if (review_stored_metrics(db, s->id, &r->a) != 0) {
    if (log) palp_log_warn(log, "%s: %s left out: %s", cmd, s->uid, err);
    return rc < 0 ? rc : PALP_DB_ENOTFOUND;
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

void review_row_free(review_row *r) { review_assessment_free(&r->a); }
