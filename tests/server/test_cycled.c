/* test_cycled.c - a request writer's admission lasts as long as the writer (plain DDS, domain 148).
 *
 * The request topic's filter admits a new instance only while its writer holds fewer than
 * stations_per_writer (2) of them (server/admission.h). Until 2026-12-06 the server gave a writer its
 * place back whenever it took a not-alive sample of one of its instances, and only then:
 * - a writer that writes a fresh station key, waits for the answer and then disposes it (the dispose
 *   then comes as a sample of its own) was never refused: 600 of 600 answered (A), and cycling trainee
 *   JOINs it held all 4 sessions (each held station_grace, 5 s, as a lost station's), a real trainee
 *   refused "server full" (B);
 * - a station that leaves as palp-client and palp-web do, LEAVE and dispose at once, has its dispose
 *   taken with the LEAVE (one valid sample whose instance is disposed): no not-alive sample of its own,
 *   so its place was never given back, and Cyclone drops the disposed instance silently with its
 *   writer. The table filled with departed stations: after 80 (2 x 8 slots + 64) the filter refused
 *   every new station, and a new trainee got no answer at all (D).
 * A writer's instances are now released when the writer is gone (no longer matched), not before.
 *
 * - C (a station's own life, which must keep working): one writer, one station id, joins a session,
 *   leaves (LEAVE, answered, then dispose) and joins again, 4 times: every join accepted;
 * - A: LEAVEs for fresh station ids, each answered and then disposed, until 3 go unanswered, then 300
 *   more written and disposed at once: 2 reach the server, the rest are refused by the filter and
 *   counted, their disposes counted as strays and said in the log as keys no admitted request holds;
 * - B: trainee JOINs for 6 fresh station ids on phantom 1 from a new writer, each disposed once
 *   answered: 2 sessions, and a real trainee still gets one (max_sessions 4);
 * - D: three rounds of 40 stations (a writer each) leaving with LEAVE and dispose at once, their
 *   writers deleted after: all 120 answered, and a new trainee still gets a session.
 *
 * The cycler is a child process (fork before any DDS call), so the server's memory is its own; its
 * growth over A is printed, not asserted: each disposed key stays an instance of the server's request
 * reader while the writer lives whether or not its write was admitted (a dispose passes no filter;
 * docs/robustness.md). */
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../tmpdir.h"
#include "harness.h"
#include "palp_log.h"

#define DOMAIN 148
#define CYCLES 600
#define JOINS 6
#define BURST 300

static int log_count(const char *path, const char *a, const char *b) {
  FILE *f = fopen(path, "r");
  char buf[4096];
  int n = 0;
  while (f && fgets(buf, sizeof buf, f)) n += strstr(buf, a) != NULL && (!b || strstr(buf, b) != NULL);
  if (f) fclose(f);
  return n;
}

static void request(dds_entity_t w, const char *id, int op, int role, uint32_t phantom, uint32_t seq) {
  palp_SessionRequest r;
  memset(&r, 0, sizeof r);
  snprintf(r.station_id, sizeof r.station_id, "%s", id);
  snprintf(r.user_name, sizeof r.user_name, "%s", id);
  r.request_seq = seq;
  r.op = op;
  r.role = role;
  r.phantom_id = phantom;
  dds_write(w, &r);
}

static void dispose(dds_entity_t w, const char *id) {
  palp_SessionRequest k;
  memset(&k, 0, sizeof k);
  snprintf(k.station_id, sizeof k.station_id, "%s", id);
  dds_dispose(w, &k);
}

/* The reply to (id, seq) within wait [s]: 1 accepted, 0 refused (reason copied), -1 none. */
static int await_reply(dds_entity_t r, const char *id, uint32_t seq, double wait, char *reason, size_t len) {
  const int64_t end = palp_dds_now_ns() + (int64_t)(wait * 1e9);
  while (palp_dds_now_ns() < end) {
    palp_SessionReply b[16];
    void *ptr[16];
    dds_sample_info_t info[16];
    for (int i = 0; i < 16; i++) ptr[i] = &b[i];
    const int n = dds_take(r, ptr, info, 16, 16);
    for (int i = 0; i < n; i++)
      if (info[i].valid_data && !strcmp(b[i].station_id, id) && b[i].request_seq == seq) {
        if (reason) snprintf(reason, len, "%s", b[i].reason);
        return b[i].status == palp_REPLY_ACCEPTED;
      }
    if (n <= 0) test_sleep(0.005);
  }
  return -1;
}

/* Takes replies for up to `seconds` until `want` came; counts those whose station id starts with prefix. */
static int count_replies(dds_entity_t r, const char *prefix, int want, double seconds) {
  const int64_t end = palp_dds_now_ns() + (int64_t)(seconds * 1e9);
  int got = 0;
  while (got < want && palp_dds_now_ns() < end) {
    palp_SessionReply b[16];
    void *ptr[16];
    dds_sample_info_t info[16];
    for (int i = 0; i < 16; i++) ptr[i] = &b[i];
    const int n = dds_take(r, ptr, info, 16, 16);
    for (int i = 0; i < n; i++) got += info[i].valid_data && !strncmp(b[i].station_id, prefix, strlen(prefix));
    if (n <= 0) test_sleep(0.005);
  }
  return got;
}

/* ---- the cycler (child): one participant, one request writer, told what to do on a pipe ---- */

static int cycler(int cmd_fd, int done_fd) {
  test_init();
  const dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  if (pp < 0) return 2;
  const dds_entity_t topic = palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REQUEST);
  const dds_entity_t rr = palp_dds_create_reader(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REPLY),
                                                 PALP_TOPIC_SESSION_REPLY);
  if (topic < 0 || rr < 0) return 3;
  char c, id[64], why[256];
  int result = 0;
  while (read(cmd_fd, &c, 1) == 1 && c != 'x') {
    /* A writer of its own for each command, kept to the end (it keeps what it was admitted). */
    const dds_entity_t w = palp_dds_create_writer(pp, topic, PALP_TOPIC_SESSION_REQUEST);
    if (w < 0) return 3;
    test_sleep(0.5); /* matched */
    int answered = 0;
    if (c == 'C') { /* one station id: join, leave (LEAVE + dispose, as a station does), join again */
      for (uint32_t k = 1; k <= 4; k++) {
        request(w, "same", palp_OP_JOIN, palp_ROLE_TRAINEE, 2, 2 * k);
        answered += await_reply(rr, "same", 2 * k, 3.0, why, sizeof why) == 1;
        request(w, "same", palp_OP_LEAVE, palp_ROLE_TRAINEE, 0, 2 * k + 1);
        await_reply(rr, "same", 2 * k + 1, 3.0, NULL, 0);
        dispose(w, "same");
        test_sleep(0.1); /* under join_rate */
      }
    } else if (c == 'A') { /* fresh ids: LEAVE, its answer awaited, then the dispose; until 3 go unanswered */
      int missed = 0;
      for (int i = 0; i < CYCLES && missed < 3; i++) {
        snprintf(id, sizeof id, "cyc/%d", i);
        request(w, id, palp_OP_LEAVE, palp_ROLE_OBSERVER, 0, 1);
        const int a = await_reply(rr, id, 1, 0.5, NULL, 0) >= 0;
        answered += a;
        missed += !a;
        dispose(w, id);
      }
      /* then fresh ids written and disposed at once, as a flood would (all beyond the writer's 2) */
      for (int i = 0; i < BURST; i++) {
        snprintf(id, sizeof id, "burst/%d", i);
        request(w, id, palp_OP_LEAVE, palp_ROLE_OBSERVER, 0, 1);
        dispose(w, id);
        if (i % 50 == 49) test_sleep(0.01);
      }
      answered += count_replies(rr, "burst/", BURST, 0.5);
      test_sleep(0.3); /* the last dispose taken */
    } else if (c == 'B') { /* fresh trainee ids on phantom 1: JOIN, and dispose once answered */
      for (int i = 0; i < JOINS; i++) {
        snprintf(id, sizeof id, "sess/%d", i);
        request(w, id, palp_OP_JOIN, palp_ROLE_TRAINEE, 1, 1);
        const int a = await_reply(rr, id, 1, 0.6, why, sizeof why);
        answered += a == 1;
        fprintf(stderr, "cycler: %s %s\n", id, a == 1 ? "accepted" : a == 0 ? why : "not answered");
        dispose(w, id);
        test_sleep(0.2); /* the dispose taken: its session held */
      }
    }
    char out[16];
    const int len = snprintf(out, sizeof out, "%d\n", answered);
    if (write(done_fd, out, (size_t)len) != len) result = 4;
  }
  dds_delete(pp);
  return result;
}

/* The cycler's answer to command c: how many of its requests were accepted or answered. */
static int run(int cmd_fd, FILE *done, char c) {
  if (write(cmd_fd, &c, 1) != 1) return -1;
  int n = -1;
  if (fscanf(done, "%d", &n) != 1) return -1;
  return n;
}

static void wait_guard_after(dds_entity_t r, palp_ServerGuard *g) {
  palp_ServerGuard tmp;
  while (test_latest_guard(r, 0.01, &tmp)) {
  }
  REQUIRE(test_latest_guard(r, 3.0, g), "palp_server_guard received");
}

int main(void) {
  int cmd[2], done[2];
  if (pipe(cmd) || pipe(done)) return 1;
  const pid_t child = fork();
  if (child == 0) {
    close(cmd[1]);
    close(done[0]);
    _exit(cycler(cmd[0], done[1]));
  }
  close(cmd[0]);
  close(done[1]);
  FILE *done_f = fdopen(done[0], "r");

  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  cfg.max_sessions = 4;
  cfg.max_viewers = 1;
  cfg.stations_per_writer = 2;
  cfg.join_rate = 100;
  cfg.join_burst = 100;
  cfg.status_rate_hz = 5;
  cfg.log_interval = 0.5;
  char log_path[512];
  palp_test_tmp(log_path, sizeof log_path, "palp-cycled-XXXXXX");
  const int log_fd = mkstemp(log_path);
  palp_log plog;
  REQUIRE(log_fd >= 0 && palp_log_init(&plog, "palp-server", PALP_LOG_INFO, log_path) == 0, "server log %s", log_path);
  close(log_fd);
  const palp_srv_def def = {.cfg = cfg, .verbose = 1, .log = &plog};
  test_server ts = {0};
  test_server_start_def(&ts, &def);
  const dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  const dds_entity_t guard_r = palp_dds_create_reader(pp, palp_dds_create_topic(pp, PALP_TOPIC_SERVER_GUARD),
                                                      PALP_TOPIC_SERVER_GUARD);
  REQUIRE(pp > 0 && guard_r > 0, "test participant and guard reader");
  test_sleep(1.0); /* the cycler matched */

  /* C. A station's own life on one writer: join, leave, join again. */
  const int rejoined = run(cmd[1], done_f, 'C');
  CHECK(rejoined == 4, "one station id joins, leaves (LEAVE + dispose) and joins again on one writer: %d of 4 joins "
        "accepted", rejoined);

  /* A. Fresh ids, each written, answered, then disposed. */
  palp_ServerGuard g0, g;
  wait_guard_after(guard_r, &g0);
  const uint64_t strays0 = palp_srv_request_strays(ts.srv);
  const long rss0 = test_rss_kb();
  const int answered = run(cmd[1], done_f, 'A');
  const long rss1 = test_rss_kb();
  test_sleep(0.3);
  wait_guard_after(guard_r, &g);
  const uint64_t filtered = g.request_keys_filtered - g0.request_keys_filtered;
  const uint64_t strays = palp_srv_request_strays(ts.srv) - strays0;
  fprintf(stderr, "A: %d answered, %llu filtered, %llu disposes counted as strays, server RSS %+ld kB\n", answered,
          (unsigned long long)filtered, (unsigned long long)strays, rss1 - rss0);
  CHECK(answered == 2 && filtered == 3 + BURST && strays == filtered,
        "fresh station ids written, answered and disposed by one writer, then %d written and disposed at once: %d reach "
        "the server (want 2, stations_per_writer; the cycle stops at 3 unanswered), %llu refused by the filter (want "
        "%d), their disposes counted as strays (%llu)", BURST, answered, (unsigned long long)filtered, 3 + BURST,
        (unsigned long long)strays);
  test_sleep(0.6); /* > log_interval */
  CHECK(log_count(log_path, "new request keys refused", NULL) >= 1 &&
            log_count(log_path, "a participant without an identity (DDS Security is off) disposed 256 session-request "
                                "keys that no admitted request holds (never written, or written past "
                                "stations_per_writer and refused",
                      NULL) == 1,
        "the refusals and the disposes are said in the server's log, as what they are");

  /* B. Fresh trainee ids on phantom 1, each disposed once answered. */
  const int sessions = run(cmd[1], done_f, 'B');
  const int open = palp_srv_open_sessions(ts.srv);
  CHECK(sessions == 2 && open <= 2,
        "a writer cycling %d trainee ids opens %d sessions (want 2, stations_per_writer), %d still open (held 5 s "
        "each; want <= 2)", JOINS, sessions, open);
  palp_cli_station real;
  char err[256] = "";
  palp_cli_station_open(&real, DOMAIN, "real", err, sizeof err);
  palp_cli_join j = {.role = palp_ROLE_TRAINEE, .phantom_id = 1, .user_name = "real", .timeout = 3};
  int rc = palp_cli_station_join(&real, &j, err, sizeof err);
  CHECK(rc == 0, "a real trainee still gets a session (max_sessions %d): %s", cfg.max_sessions,
        rc == 0 ? "accepted" : err);
  if (rc == 0) palp_cli_station_leave(&real);
  palp_cli_station_close(&real);

  /* D. Stations leaving as palp-client and palp-web do (LEAVE and dispose at once), their writers then
   * gone: three rounds of 40, more in all than the admission table holds (2 x 8 slots + 64 = 80). */
  {
    enum { ROUNDS = 3, LEAVERS = 40 };
    const dds_entity_t rq_t = palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REQUEST);
    const dds_entity_t reply_r = palp_dds_create_reader(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REPLY),
                                                        PALP_TOPIC_SESSION_REPLY);
    char id[64], prefix[32];
    int left[ROUNDS];
    for (int r = 0; r < ROUNDS; r++) {
      dds_entity_t lw[LEAVERS];
      for (int i = 0; i < LEAVERS; i++) lw[i] = palp_dds_create_writer(pp, rq_t, PALP_TOPIC_SESSION_REQUEST);
      test_sleep(0.5); /* matched */
      for (int i = 0; i < LEAVERS; i++) {
        snprintf(id, sizeof id, "leaver/%d/%d", r, i);
        request(lw[i], id, palp_OP_LEAVE, palp_ROLE_OBSERVER, 0, 1);
        dispose(lw[i], id);
      }
      snprintf(prefix, sizeof prefix, "leaver/%d/", r);
      left[r] = count_replies(reply_r, prefix, LEAVERS, 2.0);
      for (int i = 0; i < LEAVERS; i++) dds_delete(lw[i]);
      test_sleep(0.5); /* their writers unmatched */
    }
    palp_cli_station_open(&real, DOMAIN, "after", err, sizeof err);
    palp_cli_join ja = {.role = palp_ROLE_TRAINEE, .phantom_id = 1, .user_name = "after", .timeout = 3};
    rc = palp_cli_station_join(&real, &ja, err, sizeof err);
    CHECK(left[0] == LEAVERS && left[1] == LEAVERS && left[2] == LEAVERS && rc == 0,
          "%d rounds of %d stations leave (LEAVE and dispose at once), their writers then gone: %d, %d and %d answered "
          "(want all), and a new trainee still gets a session: %s", ROUNDS, LEAVERS, left[0], left[1], left[2],
          rc == 0 ? "accepted" : err);
    if (rc == 0) palp_cli_station_leave(&real);
    palp_cli_station_close(&real);
  }

  if (write(cmd[1], "x", 1) != 1) fprintf(stderr, "cannot stop the cycler\n");
  int status = 0;
  waitpid(child, &status, 0);
  fclose(done_f);
  CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0, "cycler exit status %d", WEXITSTATUS(status));
  dds_delete(pp);
  test_server_stop(&ts);
  palp_log_close(&plog);
  if (!palp_test_failures) unlink(log_path);
  else fprintf(stderr, "server log kept: %s\n", log_path);
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
