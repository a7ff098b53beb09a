/* What a SESSION argument names (docs/naming.md): an exact uid, else the number a station showed
 * ("session 3": a whole number of at most 9 digits, the uid's tail), else, where the command allows,
 * a unique prefix of a uid.
 *
 * The station's number is tried before a prefix (session 81, found by review): the prefix was tried
 * first, so with uids 3f9c1e-7 and a41d0b-3 "show 3" showed session 7, and with real uids
 * (1795482287-28255-N) "show 1" was an ambiguous prefix and "session 1" could not be named by its
 * number. A command that destroys (delete) takes no prefix at all: "delete run7-1" run twice deleted
 * run7-1 and then run7-10, printing "deleted run7-1" both times. */
#include <stdio.h>
#include <string.h>

#include "palp_db.h"
#include "retention.h"
#include "review_util.h"

/* as `list` sizes it: the longest name, at most 40 */
static int name_width(const palp_db_session_info *v, int n) {
  int pw = 7;
  for (int i = 0; i < n; i++) {
    const int len = (int)strnlen(v[i].phantom_name, 40);
    if (len > pw) pw = len;
  }
  return pw;
}

static void list_candidates(const palp_db_session_info *c, int total, int shown) {
  const int pw = name_width(c, shown);
  for (int i = 0; i < shown; i++) {
    char t0[64];
    review_fmt_time(c[i].start_unix_s, t0, sizeof t0);
    fprintf(stderr, "  %-36s %-14.14s %-*.*s %s\n", c[i].uid, c[i].trainee, pw, pw, c[i].phantom_name, t0);
  }
  if (total > shown) fprintf(stderr, "  ... and %d more (palp-review list)\n", total - shown);
}

int review_find_session(palp_log *log, palp_db *db, const char *cmd, const char *arg, int allow_prefix,
                        palp_db_session_info *s) {
  enum { SHOW = 10 };
  palp_db_session_info c[SHOW];
  int total = 0;
  int rc = palp_db_find_session_uid(db, arg, s);
  if (rc != PALP_DB_ENOTFOUND) goto sql;
  /* the station's number; candidates answers 0 for anything but 1-9 digits */
  if ((rc = palp_db_session_candidates(db, arg, 1, c, SHOW, &total))) goto sql;
  if (total == 1) {
    palp_log_info(log, "%s: \"session %s\" on the stations is %s (%s, %s)", cmd, arg, c[0].uid, c[0].trainee,
                  c[0].phantom_name);
    *s = c[0];
    return 0;
  }
  if (total > 1) {
    palp_log_error(log, "%s: session '%s' could be any of %d sessions (\"session %s\" on the stations of several "
                   "server runs); name one by its uid:", cmd, arg, total, arg);
    list_candidates(c, total, total < SHOW ? total : SHOW);
    return REVIEW_ERROR;
  }
  if ((rc = palp_db_session_candidates(db, arg, 0, c, SHOW, &total))) goto sql;
  if (total == 1 && allow_prefix) {
    *s = c[0];
    return 0;
  }
  if (total == 0) {
    palp_log_error(log, "%s: session '%s': %s (palp-review list shows the sessions; a station's \"session N\" is "
                   "the uid's last number)", cmd, arg, palp_db_strerror(PALP_DB_ENOTFOUND));
    return REVIEW_ERROR;
  }
  if (!allow_prefix)
    palp_log_error(log, "%s: no session has the uid '%s' nor the station number %s; %s takes a whole uid or a "
                   "station's \"session N\", never the start of a uid (it could name another session); the uid%s "
                   "starting with it:", cmd, arg, arg, cmd, total == 1 ? "" : "s");
  else
    palp_log_error(log, "%s: session '%s' could be any of %d sessions (their uids start with it); name one by its uid:",
                   cmd, arg, total);
  list_candidates(c, total, total < SHOW ? total : SHOW);
  return REVIEW_ERROR;
sql:
  if (rc == 0) return 0;
  palp_log_error(log, "%s: session '%s': %s", cmd, arg, rc == PALP_DB_ESQL ? palp_db_errmsg(db) : palp_db_strerror(rc));
  return REVIEW_ERROR;
}
