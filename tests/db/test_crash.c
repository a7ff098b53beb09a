/* SIGKILL mid-session: the file stays intact and holds all but at most the last second.
 * usage: test_db_crash TMPDIR SIM_SESSION SCENE PALP_REVIEW
 *
 * The scripted session runs as its own process, paced at 1 kHz on the wall clock, and reports
 * "frames N" (frames accepted by palp_db_log_frame) every 10 frames. While it runs, palp-review
 * reads the same file (WAL reader beside the writer). Right after the child reports >= 2000
 * frames it gets SIGKILL. Then:
 *   - PRAGMA integrity_check says ok;
 *   - the frames in the file >= N - 1000 (one second at 1 kHz, the brief's bound) where N is
 *     the last count the child reported before it died (read to the pipe's end), and <= N + 10 + 1
 *     (the child can only have enqueued the frames of one more report interval);
 *   - the session has no end (it never ended), and replay reproduces the frames that are there.
 */
#include <signal.h>
#include <stdint.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "sqlite_util.h"

int main(int argc, char **argv) {
  if (argc < 5) {
    fprintf(stderr, "usage: %s TMPDIR SIM_SESSION SCENE PALP_REVIEW\n", argv[0]);
    return 2;
  }
  char db[600];
  db_fresh_path(db, sizeof db, argv[1], "crash.db");
  const char *uid = "crash-run-9b2d-0001";
  int fds[2];
  REQUIRE(pipe(fds) == 0, "pipe");
  pid_t pid = fork();
  REQUIRE(pid >= 0, "fork");
  if (pid == 0) {
    dup2(fds[1], 1);
    close(fds[0]);
    close(fds[1]);
    execl(argv[2], argv[2], db, uid, argv[3], "20", "--realtime", "--progress", (char *)NULL);
    _exit(127);
  }
  close(fds[1]);
  FILE *in = fdopen(fds[0], "r");
  char line[256];
  long long n = -1;
  int read_live = 0;
  while (fgets(line, sizeof line, in)) {
    long long v;
    if (sscanf(line, "frames %lld", &v) != 1) continue;
    n = v;
    if (n >= 2000) {
      kill(pid, SIGKILL);
      break;
    }
    if (n >= 1000 && !read_live) {
      /* A reader on the live file: the server is writing it right now. */
      char cmd[1400];
      snprintf(cmd, sizeof cmd, "'%s' --db '%s' show %s > /dev/null", argv[4], db, uid);
      int st = system(cmd);
      CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 0, "palp-review show on the live file failed (%d)", st);
      read_live = 1;
    }
  }
  /* The child's reports up to its death are still in the pipe: a parent behind on reading them (a
   * loaded machine) killed it 206 frames after the count it acted on (session 82's fresh clone), so N
   * is the last count the child reported, not the first >= 2000 read. */
  while (n >= 2000 && fgets(line, sizeof line, in)) {
    long long v;
    if (sscanf(line, "frames %lld", &v) == 1 && v > n) n = v;
  }
  int status;
  waitpid(pid, &status, 0);
  fclose(in);
  REQUIRE(n >= 2000, "the session process stopped early at %lld frames", n);
  CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL, "child killed by SIGKILL");

  sqlite3 *h;
  REQUIRE(sqlite3_open(db, &h) == SQLITE_OK, "open after the crash");
  sqlite3_stmt *st;
  sqlite3_prepare_v2(h, "PRAGMA integrity_check", -1, &st, NULL);
  CHECK(sqlite3_step(st) == SQLITE_ROW && !strcmp((const char *)sqlite3_column_text(st, 0), "ok"),
        "integrity_check after SIGKILL");
  sqlite3_finalize(st);
  int64_t frames = db_scalar(h, "SELECT count(*) FROM frame f JOIN session s ON s.id = f.session_id "
                          "WHERE s.uid = 'crash-run-9b2d-0001'");
  int64_t contiguous = db_scalar(h, "SELECT max(frame) - min(frame) + 1 FROM frame");
  printf("reported %lld frames before SIGKILL; the file holds %lld (lost %lld = %.3f s at 1 kHz)\n", n,
         (long long)frames, n - (long long)frames, (double)(n - frames) / 1000.0);
  CHECK(frames >= n - 1000, "the file holds %lld frames, fewer than %lld - 1000 (more than 1 s lost)",
        (long long)frames, n);
  CHECK(frames <= n + 11, "the file holds %lld frames, more than were enqueued (%lld + 11)", (long long)frames, n);
  CHECK(contiguous == frames, "frames are a gap-free prefix (%lld span, %lld rows)", (long long)contiguous,
        (long long)frames);
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE end_unix_s IS NULL AND end_reason IS NULL") == 1,
        "the killed session has no end");
  CHECK(db_scalar(h, "SELECT count(*) FROM writer_run WHERE closed_unix_s IS NULL") == 1, "the writer run never closed");
  sqlite3_close(h);

  char cmd[1400];
  snprintf(cmd, sizeof cmd, "'%s' --db '%s' replay %s", argv[4], db, uid);
  int rs = system(cmd);
  CHECK(WIFEXITED(rs) && WEXITSTATUS(rs) == 0, "replay of the surviving frames (%d)", rs);
  CHECK_DONE();
}
