/* The writer's worker thread under a malloc that fails (session 82 review, defect 3).
 * usage: test_db_writer_oom TMPDIR
 * Linked with -Wl,--wrap=malloc: every malloc the library calls from any thread but main's fails
 * (SQLite's own allocations are in its shared library and unaffected). Until session 82 the worker
 * malloc'd its batch marks at its start without a check and wrote through the NULL at its first batch
 * (SIGSEGV). Now: a session of 1,000 frames is written whole and the file reads back. */
#include <pthread.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>

#include "check.h"
#include "sqlite_util.h"
#include "palp_db.h"

void *__real_malloc(size_t n);
void *__wrap_malloc(size_t n);
static pthread_t main_thread;
static volatile int failing;
static volatile long refused_n;
void *__wrap_malloc(size_t n) {
  if (failing && !pthread_equal(pthread_self(), main_thread)) {
    refused_n++;
    return NULL;
  }
  return __real_malloc(n);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s TMPDIR\n", argv[0]);
    return 2;
  }
  main_thread = pthread_self();
  char p[600], err[256];
  db_fresh_path(p, sizeof p, argv[1], "oom.db");
  failing = 1;
  palp_db_writer *w;
  REQUIRE(palp_db_writer_open(p, NULL, &w, err, sizeof err) == 0, "open: %s", err);
  palp_db_session_def d = {.uid = "oom-1", .scene_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
  palp_db_session s;
  REQUIRE(palp_db_log_session_begin(w, &d, &s) == 0, "begin");
  for (int64_t i = 0; i < 1000; i++) {
    palp_db_frame f = {.frame = i, .sim_time_s = 0.001 * (double)i};
    CHECK(palp_db_log_frame(w, s, &f) == 0, "frame %lld", (long long)i);
  }
  CHECK(palp_db_log_session_end(w, s, PALP_DB_END_NORMAL, NULL, 0) == 0, "end");
  palp_db_writer_close(w);
  failing = 0;
  sqlite3 *h;
  REQUIRE(sqlite3_open_v2(p, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK, "reopen");
  CHECK(db_scalar(h, "SELECT count(*) FROM frame") == 1000, "the 1,000 frames in the file");
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE end_reason = 'normal'") == 1, "the session ended");
  sqlite3_close(h);
  printf("worker-thread mallocs refused: %ld\n", refused_n);
  CHECK_DONE();
}
