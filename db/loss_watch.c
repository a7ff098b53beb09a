/* loss_watch.c - a session log's losses said as they happen, and its fill against its cap (palp_db.h).
 * Shared by palp-server (server/db_log.c) and palp-recorder: one wording for one thing. */
#include <stdio.h>
#include <string.h>

#include <sqlite3.h>

#include "palp_db.h"

#define LOSS_SAY_NS 60000000000LL /* a log that goes on losing records is said again at most once a minute */
/* What to do, in one wording: pruning old sessions (their samples deleted, their metrics kept) frees
 * pages the writer reuses at once (docs/db.md, "Retention"). */
#define ADVICE_CAP "prune old sessions (palp-review prune), move the log away or raise the cap"
#define ADVICE_DISK "prune old sessions (palp-review prune), free space or move the log away"

/* A size in MB (10^6 bytes) as a lab reads it: "16384", or "0.26" below 10 MB. */
static const char *mb_text(double bytes, char *buf, size_t len) {
  snprintf(buf, len, "%.*f", bytes < 10e6 ? 2 : 0, bytes * 1e-6);
  return buf;
}

int palp_db_cap_describe(const char *path, int64_t max_bytes, const char *cap_name, char *line, size_t len) {
  if (len) line[0] = 0;
  if (max_bytes <= 0) return 0;
  /* The cap is on pages (PRAGMA max_page_count), so the pages are counted: in WAL mode the main file
   * lags what the log holds. SQLite keeps a cap below the log's size at its size: an old large log
   * is simply full. */
  double used = 0;
  sqlite3 *h = NULL;
  if (path && sqlite3_open_v2(path, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK) {
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(h, "SELECT page_count * page_size FROM pragma_page_count, pragma_page_size", -1, &q,
                           NULL) == SQLITE_OK &&
        sqlite3_step(q) == SQLITE_ROW)
      used = (double)sqlite3_column_int64(q, 0);
    sqlite3_finalize(q);
  }
  sqlite3_close(h);
  const double cap = (double)max_bytes;
  char u[32], c[32];
  const int level = used >= cap ? 2 : used >= 0.9 * cap ? 1 : 0;
  snprintf(line, len, "session log: %s MB of its cap of %s MB (%s)%s", mb_text(used, u, sizeof u),
           mb_text(cap, c, sizeof c), cap_name,
           level == 2   ? ": FULL, new sessions will not be logged; " ADVICE_CAP
           : level == 1 ? ": nearly full; " ADVICE_CAP
                        : "");
  return level;
}

int palp_db_loss_watch_look(palp_db_loss_watch *w, const palp_db_writer_stats *st, int64_t now_ns, char *line,
                            size_t len) {
  if (len) line[0] = 0;
  const int64_t lost = st->shed + st->failed;
  int said = 0;
  if (lost > w->lost_said && (!w->losing || now_ns - w->said_ns >= LOSS_SAY_NS)) {
    char hint[200] = "", mb[32];
    const int full = (st->last_error_code & 0xff) == SQLITE_FULL; /* the cap's error is the full disk's */
    if (full && w->max_bytes > 0)
      snprintf(hint, sizeof hint, "; the file reached its cap of %s MB (%s) or its disk is full: " ADVICE_CAP,
               mb_text((double)w->max_bytes, mb, sizeof mb), w->cap_name ? w->cap_name : "its cap");
    else if (full)
      snprintf(hint, sizeof hint, "; its disk is full: " ADVICE_DISK);
    snprintf(line, len, "session log: %lld records lost so far (%lld shed: the queue was full; %lld failed%s%s)%s",
             (long long)lost, (long long)st->shed, (long long)st->failed, st->last_error[0] ? ": " : "", st->last_error,
             hint);
    w->lost_said = lost, w->said_ns = now_ns, w->losing = 1;
    said = 1;
  } else if (w->losing && lost == w->lost_seen &&
             (st->failed > 0 ? !st->in_error : st->written > w->written_seen)) {
    /* A whole look's period without a new loss, and the writer writing: after disk errors, its last
     * attempt succeeded (in_error is cleared only by a success, which may have come in the period of
     * the last loss); after a full queue alone, records written in this period. */
    snprintf(line, len, "session log: writing again (%lld records lost in all)", (long long)lost);
    w->losing = 0, w->lost_said = lost;
    said = 2;
  }
  w->lost_seen = lost, w->written_seen = st->written;
  return said;
}
