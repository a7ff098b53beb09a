/* test_disposed.c - another identity's dispose of a station's request key does not hide that
 * station's loss (secured classroom, real DDS Security plugins, domain 141).
 *
 * Trainee alice joins phantom 1. Trainee bob, authenticated and writing in his own request
 * partition (his permissions allow it), disposes alice's request key: the server refuses it (not
 * alice's writer), and her session goes on. Then alice's process is killed (SIGKILL): no goodbye,
 * her participant's lease (1 s in the loopback config) lapses. Her instance is already disposed, so
 * Cyclone has no new not-alive state to report; the server must notice her station's loss from her
 * request writer going away. Until 2026-12-06 it never did: her slot and session stayed held for as
 * long as bob's writer lived.
 *
 * Properties: the server says alice's station left her session (member_changed, her station id,
 * joined 0) within 5 s of the SIGKILL (five participant leases; measured ~1.1 s) and its log says
 * "trainee station lost"; her session, held station_grace (1 s) for her to come back, closes; and the
 * freed slot takes a new session: with max_sessions 1, bob's join to phantom 1 is accepted (refused
 * "server full" while hers is held).
 *
 * As in test_classroom.c, each identity runs in a process of its own (Cyclone 0.10.2 shares the first
 * secured participant's permissions within a process): this program is the server and re-executes
 * itself as "child alice" / "child bob".
 *
 * usage: test_security_disposed PKI_DIR   (made by make_pki.sh) */
#define _POSIX_C_SOURCE 200809L
#include <signal.h>
#include <spawn.h>
#include <stdatomic.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../tmpdir.h"
#include "../open_session.h"
#include "harness.h"
#include "palp_log.h"

#define DOMAIN 141
#define LOSS_BOUND_S 5.0 /* five participant leases of the loopback config */

extern char **environ;

static const char *pki;

static void open_secure(palp_cli_station *st, const char *identity, const char *label) {
  palp_dds_security sec;
  char err[512];
  if (palp_dds_security_init(&sec, pki, identity, err, sizeof err) < 0) {
    fprintf(stderr, "%s: %s\n", identity, err);
    exit(1);
  }
  if (palp_cli_station_open_secure(st, DOMAIN, label, &sec, err, sizeof err) < 0) {
    fprintf(stderr, "%s: %s\n", identity, err);
    exit(1);
  }
}

static int join(palp_cli_station *st, uint32_t phantom, double timeout, char *err, size_t errlen) {
  palp_cli_join j = {.role = palp_ROLE_TRAINEE, .phantom_id = phantom, .want_feedback = 1, .timeout = timeout};
  return palp_cli_station_join(st, &j, err, errlen);
}

/* Waits for the open session of trainee `name` in the public session states (0, or -1). */
static int find_session(palp_cli_station *st, const char *name, double timeout, palp_SessionState *out) {
  return palp_test_open_session(st->pp, name, timeout, out) ? 0 : -1;
}

/* One line from the parent on stdin ("go" or "quit"); 0 at end of file. */
static int order(char *buf, size_t len) {
  size_t n = 0;
  char c;
  while (n + 1 < len && read(0, &c, 1) == 1) {
    if (c == '\n') break;
    buf[n++] = c;
  }
  buf[n] = 0;
  return (int)n;
}

/* ---- alice: joins, then waits to be killed (no goodbye) ---- */
static int child_alice(void) {
  palp_cli_station alice;
  char err[512];
  open_secure(&alice, "trainee/alice", "t");
  REQUIRE(join(&alice, 1, 15, err, sizeof err) == 0, "alice joins phantom 1 (%s)", err);
  printf("%s\n", alice.station_id);
  fflush(stdout);
  /* Pressing keeps her session busy as a real one is; the parent kills her (at most 60 s). */
  const int64_t end = palp_dds_now_ns() + 60000000000LL;
  uint64_t seq = 0;
  while (palp_dds_now_ns() < end) {
    test_send_force(&alice, 0, 2, 30, 40, 2.0, ++seq);
    test_sleep(0.02);
  }
  return 1; /* never killed */
}

/* ---- bob: disposes alice's request key through his own, permitted writer; later joins phantom 1 ---- */
static int child_bob(void) {
  palp_cli_station bob;
  char err[512], line[64];
  open_secure(&bob, "trainee/bob", "t");
  palp_SessionState a;
  REQUIRE(find_session(&bob, "alice", 15, &a) == 0, "bob sees alice's session %u (station %s)", a.session_id,
          a.trainee_station);
  /* His request writer matched with the server's reader, so the dispose goes to it. */
  const int64_t until = palp_dds_now_ns() + 10000000000LL;
  dds_publication_matched_status_t pm = {0};
  while (dds_get_publication_matched_status(bob.request_w, &pm) == 0 && pm.current_count < 1 &&
         palp_dds_now_ns() < until)
    test_sleep(0.05);
  REQUIRE(pm.current_count >= 1, "bob's request writer is matched (%u readers)", pm.current_count);
  palp_SessionRequest key;
  memset(&key, 0, sizeof key);
  snprintf(key.station_id, sizeof key.station_id, "%s", a.trainee_station);
  REQUIRE(dds_dispose(bob.request_w, &key) == 0, "bob disposes alice's request key %s", a.trainee_station);
  /* Stays (his writer alive: it keeps the disposed instance registered) until told to join. */
  REQUIRE(order(line, sizeof line) > 0 && !strcmp(line, "go"), "bob told to join (\"%s\")", line);
  const int rc = join(&bob, 1, 10, err, sizeof err);
  printf("%s\n", rc == 0 ? "accepted" : err);
  fflush(stdout);
  order(line, sizeof line); /* until the parent is done */
  if (rc == 0) palp_cli_station_leave(&bob);
  palp_cli_station_close(&bob);
  return 0;
}

/* ---- the server (parent) ---- */

static struct {
  pthread_mutex_t mu;
  char alice[64];
  int64_t left_ns; /* when alice's station left its session (0: not yet) */
} seen = {.mu = PTHREAD_MUTEX_INITIALIZER};

/* [server thread] */
static void on_member(void *ctx, uint32_t session_id, const char *station, int role, int joined) {
  (void)ctx, (void)session_id, (void)role;
  pthread_mutex_lock(&seen.mu);
  if (!joined && seen.alice[0] && !strcmp(station, seen.alice) && !seen.left_ns) seen.left_ns = palp_dds_now_ns();
  pthread_mutex_unlock(&seen.mu);
}
static const palp_srv_events events = {.member_changed = on_member};

static int64_t alice_left_ns(void) {
  pthread_mutex_lock(&seen.mu);
  const int64_t t = seen.left_ns;
  pthread_mutex_unlock(&seen.mu);
  return t;
}

typedef struct child {
  pid_t pid;
  FILE *out; /* its stdout */
  int in;    /* its stdin */
} child;

/* A test that stops early (REQUIRE) leaves no pressing alice behind: she is killed at exit. */
static pid_t alice_pid;
static void kill_alice(void) {
  if (alice_pid > 0) kill(alice_pid, SIGKILL), waitpid(alice_pid, NULL, 0);
}

static child spawn(const char *self, const char *role) {
  int out[2], in[2];
  REQUIRE(pipe(out) == 0 && pipe(in) == 0, "pipes for %s", role);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_adddup2(&fa, out[1], 1);
  posix_spawn_file_actions_adddup2(&fa, in[0], 0);
  posix_spawn_file_actions_addclose(&fa, out[0]);
  posix_spawn_file_actions_addclose(&fa, in[1]);
  char *argv[] = {(char *)self, (char *)pki, "child", (char *)role, NULL};
  child c = {0};
  REQUIRE(posix_spawn(&c.pid, self, &fa, NULL, argv, environ) == 0, "started %s %s", self, role);
  posix_spawn_file_actions_destroy(&fa);
  close(out[1]);
  close(in[0]);
  c.out = fdopen(out[0], "r");
  c.in = in[1];
  return c;
}

static void tell(const child *c, const char *what) {
  const size_t n = strlen(what);
  if (write(c->in, what, n) != (ssize_t)n || write(c->in, "\n", 1) != 1) fprintf(stderr, "cannot tell the child\n");
}

static int log_count(const char *path, const char *a, const char *b) {
  FILE *f = fopen(path, "r");
  char buf[4096];
  int n = 0;
  while (f && fgets(buf, sizeof buf, f)) n += strstr(buf, a) != NULL && (!b || strstr(buf, b) != NULL);
  if (f) fclose(f);
  return n;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s PKI_DIR\n", argv[0]);
    return 2;
  }
  pki = argv[1];
  test_init();
  if (argc >= 4 && !strcmp(argv[2], "child")) {
    int rc = 2;
    if (!strcmp(argv[3], "alice")) rc = child_alice();
    else if (!strcmp(argv[3], "bob")) rc = child_bob();
    return palp_test_failures ? 1 : rc;
  }
  signal(SIGPIPE, SIG_IGN); /* a child that failed early closed its stdin */
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  snprintf(cfg.security_pki, sizeof cfg.security_pki, "%s", pki);
  cfg.max_sessions = 1; /* so that the freed slot is seen: bob's session needs alice's gone */
  cfg.max_viewers = 0;
  cfg.station_grace = 1.0;
  cfg.log_interval = 0.0; /* every refusal on its own line */
  char log_path[512];
  palp_test_tmp(log_path, sizeof log_path, "palp-disposed-XXXXXX");
  const int log_fd = mkstemp(log_path);
  palp_log plog;
  REQUIRE(log_fd >= 0 && palp_log_init(&plog, "palp-server", PALP_LOG_INFO, log_path) == 0, "server log %s", log_path);
  close(log_fd);
  const palp_srv_def def = {.cfg = cfg, .verbose = 1, .log = &plog, .events = &events};
  test_server ts = {0};
  test_server_start_def(&ts, &def);

  child alice = spawn(argv[0], "alice");
  alice_pid = alice.pid;
  atexit(kill_alice);
  char station[64] = "";
  if (fgets(station, sizeof station, alice.out) && strchr(station, '\n')) *strchr(station, '\n') = 0;
  REQUIRE(station[0], "alice joined: station %s", station);
  pthread_mutex_lock(&seen.mu);
  snprintf(seen.alice, sizeof seen.alice, "%s", station);
  pthread_mutex_unlock(&seen.mu);
  REQUIRE(palp_srv_open_sessions(ts.srv) == 1, "alice's session is open");

  /* bob's dispose of her key: refused (counted), her session goes on. */
  const uint64_t refused0 = palp_srv_refused_requests(ts.srv);
  child bob = spawn(argv[0], "bob");
  for (const int64_t until = palp_dds_now_ns() + 20000000000LL;
       palp_srv_refused_requests(ts.srv) == refused0 && palp_dds_now_ns() < until;)
    test_sleep(0.05);
  REQUIRE(palp_srv_refused_requests(ts.srv) == refused0 + 1, "the server refused bob's dispose of alice's key (%llu refused)",
          (unsigned long long)(palp_srv_refused_requests(ts.srv) - refused0));
  test_sleep(0.5); /* a pass or two of the main loop: the dispose changed nothing */
  CHECK(palp_srv_open_sessions(ts.srv) == 1 && alice_left_ns() == 0, "alice's session still open after bob's dispose");

  /* alice's process vanishes. */
  const int64_t k0 = palp_dds_now_ns();
  kill(alice.pid, SIGKILL);
  int status = 0;
  waitpid(alice.pid, &status, 0);
  alice_pid = 0;
  fclose(alice.out);
  close(alice.in);
  CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL, "alice's process was killed (SIGKILL)");
  while (!alice_left_ns() && palp_dds_now_ns() - k0 < (int64_t)((LOSS_BOUND_S + 5.0) * 1e9)) test_sleep(0.02);
  const int64_t left = alice_left_ns();
  const double lost_s = left ? (double)(left - k0) * 1e-9 : -1;
  if (left)
    CHECK(lost_s <= LOSS_BOUND_S, "the server notices alice's station gone %.2f s after the SIGKILL (want <= %.0f s)",
          lost_s, LOSS_BOUND_S);
  else
    CHECK(0, "the server never noticed alice's station gone (waited %.0f s after the SIGKILL; want <= %.0f s)",
          LOSS_BOUND_S + 5.0, LOSS_BOUND_S);
  CHECK(log_count(log_path, "trainee station lost", "held 1 s for it to come back") == 1,
        "its log says her trainee station was lost, her session held 1 s (station_grace)");
  /* Not back within station_grace: the session closes, and its slot takes bob's. */
  for (const int64_t until = palp_dds_now_ns() + 5000000000LL;
       palp_srv_open_sessions(ts.srv) > 0 && palp_dds_now_ns() < until;)
    test_sleep(0.02);
  const double closed_s = (double)(palp_dds_now_ns() - k0) * 1e-9;
  CHECK(palp_srv_open_sessions(ts.srv) == 0 && log_count(log_path, "not back within 1 s", NULL) == 1,
        "alice's session closed %.2f s after the SIGKILL, \"not back within 1 s\"", closed_s);
  tell(&bob, "go");
  char answer[600] = "";
  const int got = fgets(answer, sizeof answer, bob.out) != NULL;
  CHECK(got && !strncmp(answer, "accepted", 8), "bob's join to phantom 1 (max_sessions 1) is accepted: %s",
        got ? answer : "(bob said nothing)");
  tell(&bob, "quit");
  waitpid(bob.pid, &status, 0);
  fclose(bob.out);
  close(bob.in);
  CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0, "bob's process passed its checks (exit status %d)",
        WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  test_server_stop(&ts);
  palp_log_close(&plog);
  if (!palp_test_failures) unlink(log_path);
  else fprintf(stderr, "server log kept: %s\n", log_path);
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
