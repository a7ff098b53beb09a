/*
 * test_grader.c - the server's grader (server/grader.c) at its bounds, against a real SQLite log whose
 * writer a second connection holds up: BEGIN IMMEDIATE takes SQLite's write lock, as another writer or
 * a slow disk would keep the writer from committing. No DDS; the grader's jobs name sessions that are
 * not in the log, so each is answered "not graded" (what is graded, and that it equals the review's
 * reading, is server_findings' and install_demo's).
 *
 *  1. 32 sessions wait while the writer is held; the 33rd is refused (PALP_EFULL), the log says it
 *     will not be scored live and it is answered at once as not graded, with why (since session 64:
 *     the dashboard and her station say so rather than wait); nothing else is answered while the
 *     writer is held; released, the 32 are answered in the order they closed, each "the session is
 *     not in the log".
 *  2. 32 answers not taken: the 33rd is graded but not kept (the log says so), and the 32 are.
 *  0. Sessions in the log that cannot be scored (session 67; their scene "{}" has no name): one whose
 *     row counts 7 records shed is told the loss, in the grader's words, as what lost records (an
 *     exercise, a scene, samples) cannot be scored from; one that lost nothing is told the assessment's
 *     own reason. (The row's count is set by the test's own connection: the loss of a full file is
 *     server_log_full's; this is the grader's choice of words, exactly.)
 *  3. Stopping while the grader already waits on a held writer (a wait that began before the stop,
 *     which would have held the server up to 30 s until session 64): close returns after the
 *     2 s the stop gives the writer, not 30, and the log names the sessions left.
 *
 * usage: test_server_grader TMPDIR
 */
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "grader.h"
#include "palp.h"

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void nap(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
  nanosleep(&ts, NULL);
}

/* Waits up to timeout_s for needle to occur at least n times in the log. */
static long wait_for_lines(const char *path, const char *needle, long n, double timeout_s) {
  const double end = now_s() + timeout_s;
  long got;
  while ((got = count_lines(path, needle)) < n && now_s() < end) nap(0.02);
  return got;
}

/* Holds the log's write lock (BEGIN IMMEDIATE) and queues one record behind it, so that the
 * grader's wait for the writer cannot end until release(). */
static sqlite3 *hold(const char *path, palp_db_writer *w) {
  sqlite3 *db = NULL;
  if (sqlite3_open(path, &db) != SQLITE_OK) return NULL;
  sqlite3_busy_timeout(db, 5000);
  if (sqlite3_exec(db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK) {
    sqlite3_close(db);
    return NULL;
  }
  if (palp_db_log_event(w, 0, PALP_DB_EVENT_REJECT, -1, "test_grader: the log is held", 0) != 0) {
    sqlite3_close(db);
    return NULL;
  }
  return db;
}

static void release(sqlite3 *db) {
  sqlite3_exec(db, "COMMIT", NULL, NULL, NULL);
  sqlite3_close(db);
}

static void uid_of(uint32_t id, char *buf, size_t len) { snprintf(buf, len, "test-grader-%u", id); }

/* Takes every answer that comes within timeout_s (stopping at max), into ids[]. */
static int take_all(palp_srv_grader *g, uint32_t *ids, int max, int want, double timeout_s, int *all_not_in_log) {
  const double end = now_s() + timeout_s;
  int n = 0;
  *all_not_in_log = 1;
  while (now_s() < end && n < want) {
    palp_srv_score s;
    while (n < max && palp_srv_grader_take(g, &s)) {
      ids[n++] = s.session_id;
      if (s.graded || strcmp(s.reason, "the session is not in the log") != 0) *all_not_in_log = 0;
    }
    if (n < want) nap(0.02);
  }
  return n;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s TMPDIR\n", argv[0]);
    return 2;
  }
  /* The log's health line fitted to the wire's 128 bytes (palp_srv_health_fit, session 66): a short
   * one whole; a damaged and cut-short one (211 characters; 143 without its explanations) and one with
   * larger counts, each without its explanations and cut after a whole phrase, " ..." at its end,
   * never inside a count. */
  {
    char out[128];
    palp_srv_health_fit("complete: an end was logged; 1504 of 1504 frames present, no records shed or lost", out,
                        sizeof out);
    CHECK(strcmp(out, "complete: an end was logged; 1504 of 1504 frames present, no records shed or lost") == 0,
          "health fit: a short line whole: \"%s\"", out);
    palp_srv_health_fit("CUT SHORT: no end was logged (the server was killed, or is still writing); the data ends at "
                        "frame 240, t = 0.960 s; DAMAGED: 0 records shed (queue full), 343 lost to disk errors, 0 of 80 "
                        "frames missing (0.0%)",
                        out, sizeof out);
    CHECK(strcmp(out, "CUT SHORT: no end was logged; the data ends at frame 240, t = 0.960 s; DAMAGED: 0 records shed, "
                      "343 lost to disk errors ...") == 0,
          "health fit: a long line without its explanations, cut after a whole phrase: \"%s\"", out);
    palp_srv_health_fit("CUT SHORT: no end was logged (the server was killed, or is still writing); the data ends at "
                        "frame 1234567, t = 12345.678 s; DAMAGED: 123456 records shed (queue full), 1234567 lost to "
                        "disk errors, 123456 of 1234567 frames missing (10.0%)",
                        out, sizeof out);
    CHECK(strcmp(out, "CUT SHORT: no end was logged; the data ends at frame 1234567, t = 12345.678 s; DAMAGED: 123456 "
                      "records shed ...") == 0,
          "health fit: still too long, cut after a whole phrase: \"%s\"", out);
  }
  char path[512], log_path[512];
  snprintf(path, sizeof path, "%s/grader-%ld.db", argv[1], (long)getpid());
  snprintf(log_path, sizeof log_path, "%s/grader-%ld.log", argv[1], (long)getpid());
  unlink(path), unlink(log_path);
  const palp_db_writer_opts opts = palp_db_writer_default_opts();
  palp_db_writer *w = NULL;
  char err[256] = "";
  if (palp_db_writer_open(path, &opts, &w, err, sizeof err) != 0) {
    fprintf(stderr, "FAIL the log's writer: %s\n", err);
    return 1;
  }
  palp_log log;
  if (palp_log_init(&log, "test_grader", PALP_LOG_INFO, log_path) != 0) {
    fprintf(stderr, "FAIL the test's log file %s\n", log_path);
    return 1;
  }
  palp_srv_grader *g = NULL;
  CHECK(palp_srv_grader_open(path, w, &log, &g) == 0 && g, "the grader thread started");
  if (!g) return 1;
  char uid[64];

  /* ---- 0. in the log, not scorable: lost records, or none ---- */
  {
    palp_db_session ls[2];
    for (int k = 0; k < 2; k++) {
      uid_of(301 + k, uid, sizeof uid);
      const palp_db_session_def d = {.uid = uid, .trainee = "ida", .scene_json = "{}", .tick_hz = 100, .dt_s = 0.01};
      CHECK(palp_db_log_session_begin(w, &d, &ls[k]) == 0, "session %d begun in the log", 301 + k);
    }
    CHECK(palp_db_writer_flush(w, 10) == 0, "their rows written");
    sqlite3 *c = NULL;
    CHECK(sqlite3_open(path, &c) == SQLITE_OK && sqlite3_busy_timeout(c, 5000) == SQLITE_OK &&
              sqlite3_exec(c, "UPDATE session SET records_shed = 7 WHERE uid = 'test-grader-301'", NULL, NULL, NULL) ==
                  SQLITE_OK && sqlite3_changes(c) == 1,
          "session 301's row counts 7 records shed");
    sqlite3_close(c);
    for (uint32_t id = 301; id <= 302; id++) {
      uid_of(id, uid, sizeof uid);
      CHECK(palp_srv_grader_submit(g, id, uid, "t") == 0, "session %u submitted", id);
    }
    palp_srv_score got[2];
    int n0 = 0;
    for (double end = now_s() + 15; n0 < 2 && now_s() < end;)
      if (!palp_srv_grader_take(g, &got[n0])) nap(0.02);
      else n0++;
    CHECK(n0 == 2 && got[0].session_id == 301 && !got[0].graded &&
              strcmp(got[0].reason, "the session log lost 7 of its records (its queue was full); tell your instructor") == 0,
          "in the log, not scorable, 7 records lost: told the loss: \"%s\"", n0 > 0 ? got[0].reason : "");
    CHECK(n0 == 2 && got[1].session_id == 302 && !got[1].graded &&
              strcmp(got[1].reason, "the logged scene does not parse: name: missing or not a string") == 0,
          "in the log, not scorable, nothing lost: the assessment's reason: \"%s\"", n0 > 1 ? got[1].reason : "");
    CHECK(count_lines(log_path, "session 301 (test-grader-301): the logged scene does not parse: name: missing or not a "
                                "string, after the session log lost 7 of its records") == 1,
          "  the server's log keeps what the assessment found too");
  }

  /* ---- 1. 32 waiting, the 33rd refused ---- */
  sqlite3 *h = hold(path, w);
  CHECK(h != NULL, "a second connection holds the log's write lock, a record queued behind it");
  if (!h) return 1;
  int accepted = 0, refused_rc = 0;
  for (uint32_t id = 1; id <= 33; id++) {
    uid_of(id, uid, sizeof uid);
    const int rc = palp_srv_grader_submit(g, id, uid, "t");
    if (id <= 32) accepted += rc == 0;
    else refused_rc = rc;
  }
  CHECK(accepted == 32 && refused_rc == PALP_EFULL, "32 sessions wait to be graded (%d accepted), the 33rd is refused: %s",
        accepted, palp_strerror(refused_rc));
  CHECK(count_lines(log_path, "session 33 (test-grader-33): not scored live: 32 sessions are waiting to be graded") == 1,
        "  the log says the 33rd will not be scored live (palp-review show grades it)");
  palp_srv_score s;
  const int told33 = palp_srv_grader_take(g, &s);
  CHECK(told33 && s.session_id == 33 && !s.graded &&
            strcmp(s.reason, "32 sessions were waiting to be graded as it closed; palp-review show grades it from the "
                             "log") == 0,
        "  and answered at once as not graded, with why: \"%s\"", told33 ? s.reason : "");
  nap(0.3);
  CHECK(!palp_srv_grader_take(g, &s), "nothing else is answered while the writer is held (0.3 s)");
  release(h);
  uint32_t ids[40];
  int not_in_log = 0;
  int n = take_all(g, ids, 40, 32, 15.0, &not_in_log);
  nap(0.3);
  while (n < 40 && palp_srv_grader_take(g, &s)) ids[n++] = s.session_id; /* anything more would be a fault */
  int in_order = n == 32;
  for (int i = 0; i < n && in_order; i++) in_order = ids[i] == (uint32_t)(i + 1);
  CHECK(in_order && not_in_log, "released, the 32 are answered in the order they closed (%d answers), each \"the "
                                "session is not in the log\" (%s); the 33rd not again", n, not_in_log ? "yes" : "no");

  /* ---- 2. 32 answers not taken: the 33rd is not kept ---- */
  accepted = 0;
  for (uint32_t id = 101; id <= 132; id++) {
    uid_of(id, uid, sizeof uid);
    accepted += palp_srv_grader_submit(g, id, uid, "t") == 0;
  }
  const long graded_lines = wait_for_lines(log_path, "): not scored: the session is not in the log", 64, 15.0);
  CHECK(accepted == 32 && graded_lines == 64, "32 more sessions graded, none taken (%d accepted, %ld graded in all)",
        accepted, graded_lines);
  uid_of(133, uid, sizeof uid);
  CHECK(palp_srv_grader_submit(g, 133, uid, "t") == 0, "a 33rd is accepted (the grader has room to grade it)");
  CHECK(wait_for_lines(log_path, "session 133: its score was not sent: 32 scores are waiting for the server", 1, 15.0) == 1,
        "  it is graded, not kept, and the log says so");
  n = take_all(g, ids, 40, 32, 5.0, &not_in_log);
  nap(0.3);
  while (n < 40 && palp_srv_grader_take(g, &s)) ids[n++] = s.session_id;
  in_order = n == 32;
  for (int i = 0; i < n && in_order; i++) in_order = ids[i] == (uint32_t)(101 + i);
  CHECK(in_order, "the 32 kept are taken, 101 to 132 in order, not the 33rd (%d answers)", n);

  /* ---- 3. stopping while the grader waits on a held writer ---- */
  h = hold(path, w);
  CHECK(h != NULL, "the log held again, a record queued behind it");
  if (!h) return 1;
  for (uint32_t id = 201; id <= 203; id++) {
    uid_of(id, uid, sizeof uid);
    palp_srv_grader_submit(g, id, uid, "t");
  }
  nap(0.5); /* the grader is waiting on the writer for 201, a wait begun before the stop */
  const double t0 = now_s();
  palp_srv_grader_close(g);
  const double stop_s = now_s() - t0;
  release(h);
  /* The stop gives the writer 2 s (STOPPING_WAIT_S), then leaves the rest; 6 s of margin for a
   * loaded machine's scheduling, against the 30 s a wait begun before the stop used to hold. */
  CHECK(stop_s >= 1.9 && stop_s < 8.0, "the grader stops %.2f s after it is asked, waiting on a held writer (2 s the "
                                       "stop gives it; tolerance 1.9-8 s, not 30)", stop_s);
  CHECK(count_lines(log_path, "session 201 (test-grader-201): not scored: the session log's writer did not catch up") == 1 &&
            count_lines(log_path, "session log: 2 closed session(s) not scored: the log's writer is behind as the server "
                               "stops") == 1,
        "  the log says 201 was not scored (the writer behind) and that the 2 after it were left");
  palp_db_writer_close(w);
  palp_log_close(&log);
  unlink(path), unlink(log_path);
  char side[600];
  snprintf(side, sizeof side, "%s-wal", path), unlink(side);
  snprintf(side, sizeof side, "%s-shm", path), unlink(side);
  fprintf(stderr, "%s\n", failures ? "FAILED" : "all checks passed");
  return failures != 0;
}
