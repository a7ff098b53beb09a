/* test_killed.c - a trainee station killed with SIGKILL (no goodbye) is noticed
 * through DDS liveliness within 2 s; its session is held for station_grace (it
 * might have been a stall, test_stalled.c) and then closed, saying why.
 * While it is held, another participant (the watcher's) writes a JOIN as an observer and a LEAVE
 * under the lost station's id (plain DDS: anyone may write requests): neither ends the held session
 * before its grace (until session 80, 2026-12-07, the LEAVE closed it at once as "trainee station
 * left", and the JOIN under its id made its own JOIN miss the resume). */
#include <signal.h>
#include <spawn.h>
#include <string.h>
#include <sys/wait.h>

#include "harness.h"

#define DOMAIN 104

extern char **environ;

/* Newest state of a session named by trainee (or id): returns 1 when found. */
static int poll_state(palp_cli_station *st, const char *trainee, uint32_t id, palp_SessionState *out) {
  palp_SessionState buf[8];
  void *ptr[8];
  dds_sample_info_t info[8];
  for (int i = 0; i < 8; i++) ptr[i] = &buf[i];
  int n, found = 0;
  while ((n = dds_take(st->state_r, ptr, info, 8, 8)) > 0)
    for (int i = 0; i < n; i++)
      if (info[i].valid_data && (id ? buf[i].session_id == id : trainee && strcmp(buf[i].trainee_name, trainee) == 0)) {
        *out = buf[i];
        found = 1;
      }
  return found;
}

int main(void) {
  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  test_server ts = {0};
  test_server_start(&ts, &cfg);
  palp_cli_station watch;
  char err[256];
  REQUIRE(palp_cli_station_open(&watch, DOMAIN, "watch", err, sizeof err) == 0, "watcher %s", err);

  /* A real palp-client process, pressing the paper's profile for up to a minute. */
  char *argv[] = {PALP_CLIENT_PATH, "--role", "trainee", "--domain", "104", "--phantom", "1", "--name", "victim",
                  "--profile", "sine", "--magnitude", "1", "--duration", "60", "--quiet", NULL};
  pid_t pid;
  REQUIRE(posix_spawn(&pid, PALP_CLIENT_PATH, NULL, NULL, argv, environ) == 0, "spawned %s", PALP_CLIENT_PATH);
  palp_SessionState s;
  memset(&s, 0, sizeof s);
  int64_t end = palp_dds_now_ns() + 10000000000LL;
  int open = 0;
  while (!open && palp_dds_now_ns() < end) {
    if (poll_state(&watch, "victim", 0, &s) && s.phase == palp_PHASE_OPEN) open = 1;
    test_sleep(0.02);
  }
  if (!open) kill(pid, SIGKILL);
  REQUIRE(open, "the client's session %u opened", s.session_id);
  uint32_t sid = s.session_id;
  test_sleep(1.0); /* let it press for a while */
  int64_t t_kill = palp_dds_now_ns();
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL, "client killed by SIGKILL");
  /* A lapsed lease cannot tell a crash from a stall: the session is first held for the
   * station to come back (station_grace, 5 s by default), and says so to its viewers. */
  const double grace = cfg.station_grace;
  int held = 0, closed = 0, forged = 0;
  double t_held = -1;
  char victim_id[sizeof s.trainee_station];
  snprintf(victim_id, sizeof victim_id, "%s", s.trainee_station);
  const dds_entity_t fw = palp_dds_create_writer(watch.pp, palp_dds_create_topic(watch.pp, PALP_TOPIC_SESSION_REQUEST),
                                                 PALP_TOPIC_SESSION_REQUEST);
  REQUIRE(fw > 0 && victim_id[0], "the forger's request writer; the victim's station id \"%s\"", victim_id);
  end = t_kill + (int64_t)((grace + 4.0) * 1e9);
  while (!closed && palp_dds_now_ns() < end) {
    if (poll_state(&watch, NULL, sid, &s)) {
      if (s.phase == palp_PHASE_CLOSED) closed = 1;
      else if (!held && strstr(s.reason, "held") != NULL) {
        held = 1;
        t_held = (double)(palp_dds_now_ns() - t_kill) * 1e-9;
        fprintf(stderr, "held: \"%s\"\n", s.reason);
      }
    }
    if (held && !forged && (double)(palp_dds_now_ns() - t_kill) * 1e-9 >= t_held + 0.5) {
      forged = 1; /* 0.5 s into the hold: a LEAVE, then a JOIN as an observer, under the victim's id */
      palp_SessionRequest rq;
      memset(&rq, 0, sizeof rq);
      snprintf(rq.station_id, sizeof rq.station_id, "%s", victim_id);
      snprintf(rq.user_name, sizeof rq.user_name, "victim");
      rq.request_seq = 77, rq.op = palp_OP_LEAVE, rq.role = palp_ROLE_TRAINEE, rq.session_id = sid;
      dds_write(fw, &rq);
      test_sleep(0.6); /* past log_interval: its refusal is said too */
      rq.request_seq = 78, rq.op = palp_OP_JOIN, rq.role = palp_ROLE_OBSERVER;
      dds_write(fw, &rq);
    }
    if (!closed) test_sleep(0.01);
  }
  CHECK(forged, "another participant's JOIN and LEAVE under the held station's id were written");
  double dt = (double)(palp_dds_now_ns() - t_kill) * 1e-9;
  /* Budget: writer liveliness lease 0.5 s, participant lease 1 s, plus the server's
   * 100 ms loop and delivery: 2 s to notice; then the grace, plus 1 s. */
  CHECK(held && t_held <= 2.0, "session %u held %.2f s after SIGKILL (want <= 2 s), its state saying so", sid, t_held);
  CHECK(closed && dt >= grace && dt <= grace + 3.0, "session %u closed %.2f s after SIGKILL (want %.0f-%.0f s: the "
        "grace after the lease): \"%s\"", sid, dt, grace, grace + 3.0, closed ? s.reason : "(not closed)");
  CHECK(closed && t_held >= 0 && dt - t_held >= grace - 0.25, "closed %.2f s after it was held (want >= %.2f s)",
        dt - t_held, grace - 0.25);
  CHECK(closed && strstr(s.reason, "lost") != NULL && strstr(s.reason, "not back within") != NULL,
        "the reason says the station was lost and did not come back: \"%s\"", s.reason);
  palp_cli_station_close(&watch);
  test_server_stop(&ts);
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
