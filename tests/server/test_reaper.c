/* test_reaper.c - idl/palp_dds_reaper.h: a publisher whose reliable writer has just written, handed to the
 * reaper while its one reader (a process of its own, this program run again with --reader) is stopped
 * (SIGSTOP): the hand-over returns at once while the delete waits beside it for the acknowledgement, and
 * is done once the reader runs again. The bound: a reaper of 2 refuses a third entity, which stays the
 * caller's (alive), and its destroy deletes what it took. Domain 215; the server's closed sessions and
 * palp-web's take this path (server/session.c, web/hub.c; the hub's in web_unit's test_close_stalled). */
#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "../child_lines.h"
#include "check.h"
#include "palp_dds.h"
#include "palp_dds_reaper.h"
#include "palp_types.h"

#define DOMAIN 215

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* The child: a reliable reader of the session-state topic that prints "matched N" as its count of matched
 * writers changes, until killed. */
static int reader(void) {
  /* a stalled server, not a lost one: with the loopback config's 1 s lease, lapsed under a fresh clone's load,
   * no delete had anybody to wait for */
  palp_test_child_lease("30s");
  const dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  const dds_entity_t r =
      palp_dds_create_reader(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_STATE), PALP_TOPIC_SESSION_STATE);
  if (r <= 0) return 1;
  int32_t last = -1;
  for (;;) {
    dds_subscription_matched_status_t ms;
    if (dds_get_subscription_matched_status(r, &ms) == 0 && (int32_t)ms.current_count != last) {
      last = (int32_t)ms.current_count;
      printf("matched %d\n", (int)last);
      fflush(stdout);
    }
    dds_sleepfor(DDS_MSECS(5));
  }
}

/* Whether e is a live entity (its parent can be read). */
static int alive(dds_entity_t e) { return dds_get_parent(e) > 0; }

int main(int argc, char **argv) {
  if (argc == 2 && !strcmp(argv[1], "--reader")) return reader();
  int fd[2];
  if (pipe(fd) != 0) return 1;
  const pid_t child = fork();
  if (child == 0) {
    dup2(fd[1], 1);
    close(fd[0]);
    execl(argv[0], argv[0], "--reader", (char *)NULL);
    _exit(127);
  }
  close(fd[1]);
  const dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  const dds_entity_t topic = palp_dds_create_topic(pp, PALP_TOPIC_SESSION_STATE);
  const dds_entity_t pub = dds_create_publisher(pp, NULL, NULL);
  const dds_entity_t w = palp_dds_create_writer(pub, topic, PALP_TOPIC_SESSION_STATE);
  palp_dds_reaper *r = palp_dds_reaper_create(2);
  CHECK(child > 0 && pp > 0 && w > 0 && r, "a reader process, a writer and a reaper of 2");
  if (child > 0 && w > 0 && r) {
    /* matched both ways: a writer that has not yet matched the reader has nobody to wait for */
    dds_publication_matched_status_t pm = {0};
    for (int i = 0; i < 3000 && pm.current_count == 0; i++) {
      dds_get_publication_matched_status(w, &pm);
      if (pm.current_count == 0) dds_sleepfor(DDS_MSECS(10));
    }
    CHECK(palp_test_child_says(fd[0], "matched 1", 0, 30000) && pm.current_count == 1, "the reader and the writer matched");
    dds_sleepfor(DDS_MSECS(300));
    kill(child, SIGSTOP);
    /* stopped for certain before anything is written: a reader still running on the other core acked the
     * write in the moment the signal took (a fresh clone's run: no delete waited) */
    int wst = 0;
    CHECK(waitpid(child, &wst, WUNTRACED) == child && WIFSTOPPED(wst), "the stand-in reader stopped");
    palp_SessionState st;
    memset(&st, 0, sizeof st);
    st.session_id = 1, st.phase = palp_PHASE_CLOSED;
    CHECK(dds_write(w, &st) == 0, "a CLOSED state written as the reader stands stopped");
    const double t0 = now_s();
    const int put = palp_dds_reaper_put(r, pub);
    const double took = now_s() - t0;
    CHECK(put == 0 && took < 0.1, "the publisher handed over in %.4f s (< 0.1 s; put %d)", took, put);
    /* The bound, while the thread waits on that delete: two more taken, a third refused and the caller's. */
    dds_sleepfor(DDS_MSECS(100)); /* the thread has taken the publisher off the ring */
    const dds_entity_t a = dds_create_publisher(pp, NULL, NULL), b = dds_create_publisher(pp, NULL, NULL),
                       c = dds_create_publisher(pp, NULL, NULL);
    const int ra = palp_dds_reaper_put(r, a), rb = palp_dds_reaper_put(r, b), rc = palp_dds_reaper_put(r, c);
    CHECK(ra == 0 && rb == 0 && rc == PALP_DDS_REAPER_FULL && alive(c),
          "a reaper of 2 busy with one: two more taken (%d, %d), a third refused (%d) and still alive", ra, rb, rc);
    CHECK(palp_dds_reaper_put(r, 0) == -1 && palp_dds_reaper_put(r, -5) == -1, "no entity: -1");
    palp_dds_reaper_stats rs;
    dds_sleepfor(DDS_MSECS(300));
    palp_dds_reaper_stats_get(r, &rs);
    CHECK(rs.pending == 3 && rs.deleted == 0 && rs.refused == 1,
          "0.4 s on, the delete still waits for the stopped reader (%d pending, %llu deleted, %llu refused)",
          rs.pending, (unsigned long long)rs.deleted, (unsigned long long)rs.refused);
    dds_sleepfor(DDS_MSECS(300));
    kill(child, SIGCONT);
    for (int i = 0; i < 500 && rs.pending > 0; i++) {
      dds_sleepfor(DDS_MSECS(10));
      palp_dds_reaper_stats_get(r, &rs);
    }
    CHECK(rs.pending == 0 && rs.deleted == 3 && !alive(w) && !alive(a) && !alive(b) && rs.longest_ns >= 500000000LL,
          "continued, all three deleted, the writer with its publisher (%d pending, %llu deleted, writer %s); the "
          "first delete took %.3f s (>= 0.5 s)",
          rs.pending, (unsigned long long)rs.deleted, alive(w) ? "alive" : "gone", (double)rs.longest_ns * 1e-9);
    dds_delete(c);
    const dds_entity_t d = dds_create_publisher(pp, NULL, NULL);
    CHECK(palp_dds_reaper_put(r, d) == 0, "one more taken");
    palp_dds_reaper_destroy(r);
    r = NULL;
    CHECK(!alive(d), "destroyed at once, the reaper deleted what it held");
  }
  if (child > 0) {
    kill(child, SIGCONT);
    kill(child, SIGKILL);
    waitpid(child, NULL, 0);
  }
  close(fd[0]);
  if (r) palp_dds_reaper_destroy(r);
  if (pp > 0) dds_delete(pp);
  return failures != 0;
}
