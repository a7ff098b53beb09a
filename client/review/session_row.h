/* One logged session as the review's tables show it (class.c, trainee.c): its assessment (from
 * the samples, or the metrics kept when it was pruned), the instructor's latest grade, the time
 * outside the model's valid range and whether the attempt was blind. */
#ifndef PALP_REVIEW_SESSION_ROW_H
#define PALP_REVIEW_SESSION_ROW_H

#include <stdio.h>

#include "assess_log.h"
#include "palp_db.h"
#include "palp_log.h"

typedef struct review_row {
  palp_db_session_info s;
  review_assessment a;
  int computed;      /* 1: from the samples (has maps); 0: stored metrics */
  char grade[160];
  double outside_s;  /* seconds outside the model's valid range, -1 where the log does not say */
  char outside[24];  /* the same as text, "-" where the log does not say */
  char told[512];    /* an attempt after a debrief on the same lesions: review_told_text; "" */
} review_row;

/* Fills *r for session s: 0, or a negative code (logged as a warning naming `cmd`, unless log is
 * NULL) when the session has neither samples nor stored metrics to assess (it is then left out of
 * the table: PALP_DB_ENOTFOUND for one without finger samples, force contacts only; PALP_DB_ESQL for one
 * without, whose stored metrics cannot be read). */
int review_row_fill(palp_log *log, const char *cmd, palp_db *db, const palp_db_session_info *s, review_row *r);
/* 1 when review_row_fill's (or a read's) code says the log itself could not be read (SQLite failed: a
 * damaged page, say), 0 when the session holds nothing to assess or what it logged does not parse. The
 * tables exit 2 for the first, as show does for the same reads; show exits 0 for the second. */
int review_row_unreadable(int rc);
void review_row_free(review_row *r);

/* The HTML both tables' pages share (class.c, trainee.c): the page's head up to and including
 * `<h1>HEADING<span id=ID>NAME</span></h1>` (the shared style plus extra_css), a start time as a
 * cell (the date on one line, the time and its offset on a second, never broken at a hyphen), and
 * the "Not blind" paragraphs of the rows that were not. */
void review_html_head(FILE *f, const char *title, const char *heading, const char *id, const char *name,
                      const char *extra_css);
void review_html_started_cell(FILE *f, double unix_s);
void review_html_not_blind(FILE *f, const review_row *rows, int n);
/* The rows' metrics as CSV (review_metrics_csv_header and _row) into path ("-": stdout), created
 * private; 0, or -1 logged as `cmd: path: why` (not opened, or a write or the close failed). */
int review_rows_csv(palp_log *log, const char *cmd, palp_db *db, const char *path, const review_row *rows, int n);

#endif
