/* test_loss_watch.c - a session log's losses said as they happen, and its fill against its cap
 * (db/loss_watch.c, session 66): the words and the pacing, from counters written here by hand and
 * a file of a known size; every expected line is written out in full. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <sqlite3.h>

#include "check.h"
#include "palp_db.h"

#define S 1000000000LL /* ns */

static palp_db_writer_stats stats(int64_t written, int64_t shed, int64_t failed, int in_error, const char *error) {
  palp_db_writer_stats st;
  memset(&st, 0, sizeof st);
  st.written = written, st.shed = shed, st.failed = failed, st.in_error = in_error;
  snprintf(st.last_error, sizeof st.last_error, "%s", error);
  st.last_error_code = strstr(error, "database or disk is full") ? SQLITE_FULL : 0; /* as the writer sets both */
  return st;
}

static void look(palp_db_loss_watch *w, palp_db_writer_stats st, int64_t t, int want, const char *line) {
  char got[640];
  const int said = palp_db_loss_watch_look(w, &st, t, got, sizeof got);
  CHECK(said == want && strcmp(got, line) == 0, "at %.0f s: said %d \"%s\", wanted %d \"%s\"", (double)t / S, said, got,
        want, line);
}

int main(int argc, char **argv) {
  const char *full = "writing the session log: database or disk is full";
  palp_db_loss_watch w = {.max_bytes = 208896, .cap_name = "session_log_max_mb"};
  look(&w, stats(100, 0, 0, 0, ""), 0, 0, "");
  look(&w, stats(120, 0, 49, 1, full), 1 * S, 1,
       "session log: 49 records lost so far (0 shed: the queue was full; 49 failed: writing the session log: database "
       "or disk is full); the file reached its cap of 0.21 MB (session_log_max_mb) or its disk is full: prune old "
       "sessions (palp-review prune), move the log away or raise the cap");
  /* losing on: not again within the minute */
  look(&w, stats(120, 0, 300, 1, full), 2 * S, 0, "");
  look(&w, stats(120, 0, 900, 1, full), 60 * S, 0, "");
  look(&w, stats(120, 0, 950, 1, full), 61 * S, 1,
       "session log: 950 records lost so far (0 shed: the queue was full; 950 failed: writing the session log: "
       "database or disk is full); the file reached its cap of 0.21 MB (session_log_max_mb) or its disk is full: prune "
       "old sessions (palp-review prune), move the log away or raise the cap");
  /* no new loss, but its last attempt failed: not recovered; then one succeeded (what it wrote may
   * have come in the period of the last loss: nothing more written since is still a recovery) */
  look(&w, stats(120, 0, 950, 1, full), 62 * S, 0, "");
  look(&w, stats(120, 0, 950, 0, full), 63 * S, 2, "session log: writing again (950 records lost in all)");
  look(&w, stats(240, 0, 950, 0, full), 64 * S, 0, "");
  /* a new loss after a recovery is said at once */
  look(&w, stats(240, 0, 951, 1, full), 65 * S, 1,
       "session log: 951 records lost so far (0 shed: the queue was full; 951 failed: writing the session log: "
       "database or disk is full); the file reached its cap of 0.21 MB (session_log_max_mb) or its disk is full: prune "
       "old sessions (palp-review prune), move the log away or raise the cap");
  /* a new loss in the period of a look is not a recovery, whatever was written beside it */
  look(&w, stats(300, 0, 960, 0, full), 66 * S, 0, "");
  look(&w, stats(300, 0, 960, 0, full), 67 * S, 2, "session log: writing again (960 records lost in all)");
  /* no cap: the disk; a shed queue without an error; a cap of 16 GB in whole MB */
  palp_db_loss_watch d = {0};
  look(&d, stats(10, 0, 7, 1, full), 0, 1,
       "session log: 7 records lost so far (0 shed: the queue was full; 7 failed: writing the session log: database or "
       "disk is full); its disk is full: prune old sessions (palp-review prune), free space or move the log away");
  palp_db_loss_watch q = {.max_bytes = 16384000000LL, .cap_name = "--max-mb"};
  look(&q, stats(10, 5, 0, 0, ""), 0, 1, "session log: 5 records lost so far (5 shed: the queue was full; 0 failed)");
  look(&q, stats(40, 7, 0, 0, ""), 1 * S, 0, "");
  /* sheds alone: recovered only by a period with records written and none shed */
  look(&q, stats(40, 7, 0, 0, ""), 2 * S, 0, "");
  look(&q, stats(90, 7, 0, 0, ""), 3 * S, 2, "session log: writing again (7 records lost in all)");
  palp_db_loss_watch c = {.max_bytes = 16384000000LL, .cap_name = "--max-mb"};
  look(&c, stats(10, 0, 3, 1, full), 0, 1,
       "session log: 3 records lost so far (0 shed: the queue was full; 3 failed: writing the session log: database or "
       "disk is full); the file reached its cap of 16384 MB (--max-mb) or its disk is full: prune old sessions "
       "(palp-review prune), move the log away or raise the cap");

  /* The fill against the cap, from a SQLite file written here in rollback-journal mode, whose size on
   * disk is then its pages (the cap counts pages); the caps are set around that size. */
  char path[512], line[320], want[320];
  snprintf(path, sizeof path, "%s/loss_watch.db", argc > 1 ? argv[1] : ".");
  unlink(path);
  sqlite3 *h = NULL;
  REQUIRE(sqlite3_open(path, &h) == SQLITE_OK, "%s", path);
  REQUIRE(sqlite3_exec(h, "PRAGMA journal_mode=DELETE; CREATE TABLE pad(x BLOB); INSERT INTO pad VALUES(zeroblob(940000));",
                       NULL, NULL, NULL) == SQLITE_OK,
          "pad: %s", sqlite3_errmsg(h));
  sqlite3_close(h);
  struct stat sb;
  REQUIRE(stat(path, &sb) == 0 && sb.st_size > 940000 && sb.st_size < 960000, "the file: %lld bytes",
          (long long)sb.st_size);
  const double size = (double)sb.st_size;
  int lv = palp_db_cap_describe(path, 0, "session_log_max_mb", line, sizeof line);
  CHECK(lv == 0 && line[0] == 0, "no cap: nothing to say (%d \"%s\")", lv, line);
  lv = palp_db_cap_describe(path, 20000000, "session_log_max_mb", line, sizeof line);
  snprintf(want, sizeof want, "session log: %.2f MB of its cap of 20 MB (session_log_max_mb)", size * 1e-6);
  CHECK(lv == 0 && strcmp(line, want) == 0, "%d \"%s\"", lv, line);
  lv = palp_db_cap_describe(path, (int64_t)(size / 0.95), "--max-mb", line, sizeof line);
  snprintf(want, sizeof want,
           "session log: %.2f MB of its cap of %.2f MB (--max-mb): nearly full; prune old sessions (palp-review prune), "
           "move the log away or raise the cap",
           size * 1e-6, (double)(int64_t)(size / 0.95) * 1e-6);
  CHECK(lv == 1 && strcmp(line, want) == 0, "at 95%%: %d \"%s\"", lv, line);
  lv = palp_db_cap_describe(path, (int64_t)size - 4096, "--max-mb", line, sizeof line);
  snprintf(want, sizeof want,
           "session log: %.2f MB of its cap of %.2f MB (--max-mb): FULL, new sessions will not be logged; prune old "
           "sessions (palp-review prune), move the log away or raise the cap",
           size * 1e-6, (size - 4096) * 1e-6);
  CHECK(lv == 2 && strcmp(line, want) == 0, "a page over: %d \"%s\"", lv, line);
  unlink(path);
  lv = palp_db_cap_describe(path, 1000000, "--max-mb", line, sizeof line);
  CHECK(lv == 0 && strcmp(line, "session log: 0.00 MB of its cap of 1.00 MB (--max-mb)") == 0,
        "a log not made yet: %d \"%s\"", lv, line);
  unlink(path);
  CHECK_DONE();
}
