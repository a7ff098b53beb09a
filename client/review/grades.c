/* Structured grades. Why validate here and in the schema's CHECK: the schema refuses what is
 * out of range, this module says why in words ("B+", "7/10", "" and 101 are refused with a
 * message naming what is accepted) before anything is written. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sqlite3.h>

#include "grades.h"
#include "review_util.h"

const char *const review_levels[4] = {"insufficient", "developing", "competent", "proficient"};

int review_parse_score(const char *s, double *out, char *msg, size_t len) {
  const char *p = s ? s : "";
  int digits = 0, dots = 0;
  for (const char *q = p; *q; q++) {
    if (*q >= '0' && *q <= '9') digits++;
    else if (*q == '.' && !dots) dots++;
    else {
      snprintf(msg, len, "score '%s': a number from 0 to 100 is required (e.g. 82 or 82.5; not a letter or a fraction)", p);
      return -1;
    }
  }
  if (!digits) {
    snprintf(msg, len, "score '%s': a number from 0 to 100 is required", p);
    return -1;
  }
  double v = strtod(p, NULL);
  if (!(v >= 0.0 && v <= 100.0)) {
    snprintf(msg, len, "score %s: out of range (0 to 100)", p);
    return -1;
  }
  *out = v;
  return 0;
}

int review_parse_level(const char *s, int *out, char *msg, size_t len) {
  for (int i = 0; i < 4; i++)
    if (s && !strcmp(s, review_levels[i])) {
      *out = i;
      return 0;
    }
  snprintf(msg, len, "level '%s': one of insufficient, developing, competent, proficient is required", s ? s : "");
  return -1;
}

int review_add_graded_note(palp_db *db, int64_t sid, const char *author, const char *text, double score,
                           const char *level) {
  sqlite3 *h = palp_db_handle(db);
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(h,
                         "INSERT INTO note(session_id, author, wall_unix_s, text, score, level) "
                         "VALUES(?1, ?2, (julianday('now') - 2440587.5) * 86400.0, ?3, ?4, ?5)",
                         -1, &st, NULL) != SQLITE_OK)
    return PALP_DB_ESQL;
  sqlite3_bind_int64(st, 1, sid);
  sqlite3_bind_text(st, 2, author, -1, SQLITE_STATIC);
  sqlite3_bind_text(st, 3, text, -1, SQLITE_STATIC);
  if (score >= 0) sqlite3_bind_double(st, 4, score);
  if (level) sqlite3_bind_text(st, 5, level, -1, SQLITE_STATIC);
  const int rc = sqlite3_step(st);
  sqlite3_finalize(st);
  return rc == SQLITE_DONE ? 0 : PALP_DB_ESQL;
}

void review_grade_text(int has_score, double score, const char *level, const char *free_text, char *buf, size_t len) {
  char sc[32] = "";
  if (has_score) snprintf(sc, sizeof sc, "%g", score);
  if (has_score || (level && *level))
    snprintf(buf, len, "%s%s%s", sc, has_score && level && *level ? " " : "", level ? level : "");
  else if (free_text && *free_text) snprintf(buf, len, "'%s' (free text)", free_text);
  else snprintf(buf, len, "-");
  review_tty(buf); /* a level or free-text grade from the file, printed by list and show */
}

/* The latest note that grades: its score (-1: none), level and free-text grade ("" when absent);
 * 1 when there is one, 0 when none, -1 when the notes could not be read (a damaged page: until session 90
 * that read as "no grade", and prune --keep-graded pruned a graded session; found by review). One query
 * for review_latest_grade and its parts. */
static int latest_grade(palp_db *db, int64_t sid, double *score, char level[32], char text[128]) {
  *score = -1, level[0] = text[0] = '\0';
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(palp_db_handle(db),
                         "SELECT score, level, grade FROM note WHERE session_id = ?1 AND "
                         "(score IS NOT NULL OR level IS NOT NULL OR (grade IS NOT NULL AND grade <> '')) "
                         "ORDER BY id DESC LIMIT 1",
                         -1, &st, NULL) != SQLITE_OK)
    return -1;
  sqlite3_bind_int64(st, 1, sid);
  const int step = sqlite3_step(st);
  const int found = step == SQLITE_ROW ? 1 : step == SQLITE_DONE ? 0 : -1;
  if (found > 0) {
    if (sqlite3_column_type(st, 0) != SQLITE_NULL) *score = sqlite3_column_double(st, 0);
    const char *l = (const char *)sqlite3_column_text(st, 1), *g = (const char *)sqlite3_column_text(st, 2);
    snprintf(level, 32, "%s", l ? l : "");
    snprintf(text, 128, "%s", g ? g : "");
  }
  sqlite3_finalize(st);
  return found;
}

int review_latest_grade(palp_db *db, int64_t sid, char *buf, size_t len) {
  double score;
  char level[32], text[128];
  const int rc = latest_grade(db, sid, &score, level, text);
  if (rc > 0) review_grade_text(score >= 0, score, level, text, buf, len);
  else snprintf(buf, len, rc < 0 ? "unreadable" : "-");
  return rc;
}

int review_latest_grade_parts(palp_db *db, int64_t sid, double *score, char *level, size_t len) {
  char l[32], text[128];
  if (latest_grade(db, sid, score, l, text) < 0) *score = -1, l[0] = '\0';
  if (len) snprintf(level, len, "%s", l);
  return *score >= 0 || l[0];
}

int review_each_note(palp_db *db, int64_t sid, review_note_fn fn, void *user) {
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(palp_db_handle(db),
                         "SELECT wall_unix_s, author, text, score, level, grade FROM note WHERE session_id = ?1 "
                         "ORDER BY id",
                         -1, &st, NULL) != SQLITE_OK)
    return PALP_DB_ESQL;
  sqlite3_bind_int64(st, 1, sid);
  int rc = 0, step;
  while (!rc && (step = sqlite3_step(st)) == SQLITE_ROW) {
    char g[160];
    review_grade_text(sqlite3_column_type(st, 3) != SQLITE_NULL, sqlite3_column_double(st, 3),
                      (const char *)sqlite3_column_text(st, 4), (const char *)sqlite3_column_text(st, 5), g, sizeof g);
    const char *a = (const char *)sqlite3_column_text(st, 1), *t = (const char *)sqlite3_column_text(st, 2);
    rc = fn(user, sqlite3_column_double(st, 0), a ? a : "", t ? t : "", strcmp(g, "-") ? g : NULL);
  }
  /* a step that fails (a damaged page) ends the notes early: an error, not their end */
  if (!rc && step != SQLITE_DONE) rc = PALP_DB_ESQL;
  sqlite3_finalize(st);
  return rc;
}
