/* test_stalled.c - a trainee station its machine stalls (SIGSTOP, then SIGCONT) for
 * longer than its liveliness lease keeps its session: the server holds the session
 * for station_grace (5 s), the station sends its JOIN again, and the same session goes
 * on; a stall longer than the grace ends the session, saying why, and the station's
 * JOIN coming again then opens no second session. Five real palp-client processes
 * at once: "sam" stalls 1.5 s (past the writer's 0.5 s lease and the participant's
 * 1 s: DDS re-delivers its JOIN when it is found again), "uma" 0.8 s (past the
 * writer's lease only: nothing is re-delivered, the station must send its JOIN again),
 * "tess" 7.5 s, and "vic" 0.8 s, interrupted by its user as it runs again (its LEAVE
 * closes the held session at once), and "wes" 1.5 s, interrupted likewise: past the
 * participant's lease the server has forgotten its participant, so the station first asks
 * to be found again (its JOIN, answered) and then says goodbye; before, it exited before
 * the server found it and the session waited out the grace as "not back"). */
#include <signal.h>
#include <spawn.h>
#include <string.h>
#include <sys/wait.h>

#include "harness.h"

#define DOMAIN 118

extern char **environ;

typedef struct watched {
  const char *name;
  uint32_t sid;             /* its first session */
  int open, held, resumed, closed, other_sessions;
  double t_held, t_resumed, t_closed; /* [s] after its SIGSTOP (t_resumed: after its SIGCONT) */
  uint64_t samples_at_resume, samples_last;
  palp_SessionState last;
} watched;

/* Takes every state sample and files it under the trainee it names. */
static void poll_states(palp_cli_station *st, watched *w, int nw, const int64_t *t_stop, const int64_t *t_cont) {
  palp_SessionState buf[8];
  void *ptr[8];
  dds_sample_info_t info[8];
  for (int i = 0; i < 8; i++) ptr[i] = &buf[i];
  int n;
  const int64_t now = palp_dds_now_ns();
  while ((n = dds_take(st->state_r, ptr, info, 8, 8)) > 0)
    for (int i = 0; i < n; i++) {
      if (!info[i].valid_data) continue;
      for (int k = 0; k < nw; k++) {
        watched *x = &w[k];
        if (strcmp(buf[i].trainee_name, x->name) != 0) continue;
        if (!x->sid && buf[i].phase == palp_PHASE_OPEN) x->sid = buf[i].session_id, x->open = 1;
        if (buf[i].session_id != x->sid) {
          x->other_sessions++;
          fprintf(stderr, "%s: another session %u (%s)\n", x->name, buf[i].session_id,
                  buf[i].phase == palp_PHASE_CLOSED ? "closed" : "open");
          continue;
        }
        x->last = buf[i];
        x->samples_last = buf[i].contact_samples;
        if (buf[i].phase == palp_PHASE_CLOSED) {
          if (!x->closed) x->t_closed = (double)(now - t_stop[k]) * 1e-9;
          x->closed = 1;
        } else if (strstr(buf[i].reason, "held")) {
          if (!x->held) {
            x->t_held = (double)(now - t_stop[k]) * 1e-9;
            fprintf(stderr, "%s: held %.2f s after SIGSTOP: \"%s\"\n", x->name, x->t_held, buf[i].reason);
          }
          x->held = 1;
        } else if (x->held && !x->resumed && buf[i].reason[0] == 0) {
          x->resumed = 1;
          x->t_resumed = (double)(now - t_cont[k]) * 1e-9;
          x->samples_at_resume = buf[i].contact_samples;
        }
      }
    }
}

static pid_t spawn_client(const char *name, const char *duration) {
  char *argv[] = {PALP_CLIENT_PATH, "--role", "trainee", "--domain", "118", "--phantom", "1", "--name", (char *)name,
                  "--profile", "sine", "--magnitude", "1", "--t-on", "0", "--t-off", "60", "--duration", (char *)duration,
                  "--print-period", "0",
                  NULL};
  pid_t pid;
  if (posix_spawn(&pid, PALP_CLIENT_PATH, NULL, NULL, argv, environ) != 0) return -1;
  return pid;
}

int main(void) {
  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  const double grace = cfg.station_grace;
  REQUIRE(grace == 5.0, "the default station_grace is 5 s (%.1f)", grace);
  test_server ts = {0};
  test_server_start(&ts, &cfg);
  palp_cli_station watch;
  char err[256];
  REQUIRE(palp_cli_station_open(&watch, DOMAIN, "watch", err, sizeof err) == 0, "watcher %s", err);

  enum { NW = 5 };
  watched w[NW] = {{.name = "sam"}, {.name = "tess"}, {.name = "uma"}, {.name = "vic"}, {.name = "wes"}};
  const double stall[NW] = {1.5, grace + 2.5, 0.8, 0.8, 1.5};
  const int interrupted[NW] = {0, 0, 0, 1, 1}; /* its user stops it (SIGINT), handled once it runs again */
  int64_t t_stop[NW], t_cont[NW];
  pid_t pid[NW];
  int all_open = 1, spawned = 1;
  for (int k = 0; k < NW; k++) {
    t_stop[k] = 0, t_cont[k] = INT64_MAX;
    pid[k] = spawn_client(w[k].name, k == 0 || k == 2 ? "12" : "30");
    spawned &= pid[k] > 0;
  }
  REQUIRE(spawned, "spawned five clients");
  int64_t end = palp_dds_now_ns() + 10000000000LL;
  do {
    poll_states(&watch, w, NW, t_stop, t_cont);
    all_open = 1;
    for (int k = 0; k < NW; k++) all_open &= w[k].open;
    if (!all_open) test_sleep(0.02);
  } while (!all_open && palp_dds_now_ns() < end);
  if (!all_open)
    for (int k = 0; k < NW; k++) kill(pid[k], SIGKILL);
  REQUIRE(all_open, "five sessions opened (%u, %u, %u, %u, %u)", w[0].sid, w[1].sid, w[2].sid, w[3].sid, w[4].sid);
  test_sleep(1.0); /* pressing */

  /* All stopped at once; each continued after its own stall. */
  const int64_t t0 = palp_dds_now_ns();
  int stopped[NW], status[NW], exited[NW];
  for (int k = 0; k < NW; k++) t_stop[k] = t0, stopped[k] = 1, status[k] = 0, exited[k] = 0;
  for (int k = 0; k < NW; k++) kill(pid[k], SIGSTOP);
  end = t_stop[0] + (int64_t)((stall[1] + 15.0) * 1e9);
  int all_exited = 0;
  while (palp_dds_now_ns() < end && !all_exited) {
    const int64_t now = palp_dds_now_ns();
    all_exited = 1;
    for (int k = 0; k < NW; k++) {
      if (stopped[k] && now - t_stop[k] >= (int64_t)(stall[k] * 1e9)) {
        if (interrupted[k]) kill(pid[k], SIGINT); /* its user stops it: handled once it runs again */
        kill(pid[k], SIGCONT);
        t_cont[k] = palp_dds_now_ns();
        stopped[k] = 0;
      }
      if (!exited[k] && waitpid(pid[k], &status[k], WNOHANG) == pid[k]) exited[k] = 1;
      all_exited &= exited[k];
    }
    poll_states(&watch, w, NW, t_stop, t_cont);
    test_sleep(0.01);
  }
  for (int k = 0; k < NW; k++)
    if (!exited[k]) kill(pid[k], SIGCONT), kill(pid[k], SIGKILL), waitpid(pid[k], &status[k], 0);
  test_sleep(0.5);
  poll_states(&watch, w, NW, t_stop, t_cont);

  /* sam (1.5 s) and uma (0.8 s): within the grace. */
  for (int k = 0; k <= 2; k += 2) {
    const watched *x = &w[k];
    CHECK(x->held && x->t_held <= 1.5, "%s's session %u held %.2f s into its %.1f s stall (want <= 1.5 s: the 0.5 s "
          "lease, then the server's loop)", x->name, x->sid, x->t_held, stall[k]);
    CHECK(x->resumed && x->t_resumed <= 2.0, "%s's session %u went on %.2f s after SIGCONT (want <= 2 s)", x->name,
          x->sid, x->t_resumed);
    CHECK(x->samples_last >= x->samples_at_resume + 200, "%s's contacts kept coming after it (%llu, then %llu: "
          "want >= 200 more, 100 Hz for the rest of its 12 s)", x->name, (unsigned long long)x->samples_at_resume,
          (unsigned long long)x->samples_last);
    CHECK(exited[k] && WIFEXITED(status[k]) && WEXITSTATUS(status[k]) == 0, "%s's client ran its 12 s and exited 0 "
          "(status %d)", x->name, status[k]);
    CHECK(x->closed && strcmp(x->last.reason, "trainee station left") == 0, "%s's session %u ended as it left: "
          "\"%s\"", x->name, x->sid, x->last.reason);
    CHECK(x->other_sessions == 0, "%s has no other session (%d states of others)", x->name, x->other_sessions);
  }

  /* vic (0.8 s) and wes (1.5 s, past the participant's lease), each interrupted by its
   * user (SIGINT) as it ran again: the goodbye closes the held session at once, not at the
   * grace's end (5.5 s after SIGSTOP, as "not back within 5 s"). wes's server has forgotten
   * its participant, so wes first asks to be found again (its JOIN, answered), which takes
   * up to half a second more. */
  for (int k = 3; k <= 4; k++) {
    const watched *x = &w[k];
    const double within = stall[k] + (k == 3 ? 2.0 : 2.5);
    CHECK(x->held && x->closed && strcmp(x->last.reason, "trainee station left") == 0 && x->t_closed <= within,
          "%s's held session %u closed as it left, %.2f s after SIGSTOP (want <= %.1f s, before the grace's %.1f): "
          "\"%s\"", x->name, x->sid, x->t_closed, within, grace + 0.5, x->last.reason);
    CHECK(exited[k] && WIFEXITED(status[k]), "%s's client exited (status %d)", x->name, status[k]);
    CHECK(x->other_sessions == 0, "%s has no other session (%d)", x->name, x->other_sessions);
  }

  /* tess: 7.5 s, past the grace. */
  CHECK(w[1].held && w[1].t_held <= 1.5, "tess's session %u held %.2f s into its stall", w[1].sid, w[1].t_held);
  CHECK(w[1].closed && !w[1].resumed && strstr(w[1].last.reason, "not back within 5 s") != NULL,
        "tess's session %u closed while it was stopped: \"%s\"", w[1].sid, w[1].last.reason);
  const double closed_after_stop = w[1].t_closed;
  CHECK(w[1].closed && closed_after_stop >= grace + 0.4 && closed_after_stop <= grace + 2.5, "tess's session closed "
        "%.2f s after its SIGSTOP (want %.1f-%.1f s: lease, then the grace)", closed_after_stop, grace + 0.4,
        grace + 2.5);
  CHECK(exited[1] && WIFEXITED(status[1]) && WEXITSTATUS(status[1]) == 3, "tess's client, continued, learnt its "
        "session had closed and exited 3 (status %d)", status[1]);
  CHECK(w[1].other_sessions == 0, "tess's JOIN, coming again after its session closed, opened no other session (%d)",
        w[1].other_sessions);
  palp_cli_station_close(&watch);
  test_server_stop(&ts);
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
