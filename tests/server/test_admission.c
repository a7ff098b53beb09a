/* test_admission.c - station slots, join limits and released instances.
 *
 * - one writer asking for 300 station ids gets 2 (stations_per_writer) into the
 *   server's reader cache, the rest are dropped by the filter and counted, and real
 *   stations still join afterwards;
 * - a session takes at most max_viewers viewers;
 * - joins beyond join_rate/join_burst are refused "server busy" and counted;
 * - after 20 sessions opened and closed, a new participant is sent only the open
 *   sessions' states and the live stations' replies (closed_retention 0.3 s). */
#include <string.h>

#include "harness.h"

#define DOMAIN 171

static dds_entity_t request_writer(dds_entity_t pp) {
  dds_entity_t t = palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REQUEST);
  return palp_dds_create_writer(pp, t, PALP_TOPIC_SESSION_REQUEST);
}

static void send_join(dds_entity_t w, const char *station, int role, uint32_t phantom, uint32_t session, uint32_t seq,
                      int op) {
  palp_SessionRequest rq;
  memset(&rq, 0, sizeof rq);
  snprintf(rq.station_id, sizeof rq.station_id, "%s", station);
  rq.request_seq = seq;
  rq.op = op;
  rq.role = role;
  rq.phantom_id = phantom;
  rq.session_id = session;
  snprintf(rq.user_name, sizeof rq.user_name, "%s", station);
  dds_write(w, &rq);
}

/* Waits for the reply to (station, seq): 1 accepted, 0 refused (reason copied), -1 none. */
static int await_reply(dds_entity_t r, const char *station, uint32_t seq, double wait, char *reason, size_t len) {
  int64_t end = palp_dds_now_ns() + (int64_t)(wait * 1e9);
  while (palp_dds_now_ns() < end) {
    palp_SessionReply b[8];
    void *ptr[8];
    dds_sample_info_t info[8];
    for (int i = 0; i < 8; i++) ptr[i] = &b[i];
    int n = dds_take(r, ptr, info, 8, 8);
    for (int i = 0; i < n; i++)
      if (info[i].valid_data && !strcmp(b[i].station_id, station) && b[i].request_seq == seq) {
        if (reason) snprintf(reason, len, "%s", b[i].reason);
        return b[i].status == palp_REPLY_ACCEPTED;
      }
    test_sleep(0.005);
  }
  return -1;
}

/* Takes replies for `seconds`; counts those whose station id starts with prefix. */
static void collect_replies(dds_entity_t r, const char *prefix, double seconds, int want, int *answered, int *busy) {
  int64_t end = palp_dds_now_ns() + (int64_t)(seconds * 1e9);
  *answered = *busy = 0;
  while (palp_dds_now_ns() < end && *answered < want) {
    palp_SessionReply b[8];
    void *ptr[8];
    dds_sample_info_t info[8];
    for (int i = 0; i < 8; i++) ptr[i] = &b[i];
    int n = dds_take(r, ptr, info, 8, 8);
    for (int i = 0; i < n; i++)
      if (info[i].valid_data && !strncmp(b[i].station_id, prefix, strlen(prefix))) {
        ++*answered;
        *busy += b[i].status == palp_REPLY_REJECTED && strstr(b[i].reason, "server busy") != NULL;
      }
    test_sleep(0.005);
  }
}

static void wait_guard_after(dds_entity_t r, palp_ServerGuard *g) {
  palp_ServerGuard tmp;
  while (test_latest_guard(r, 0.01, &tmp)) {
  } /* drop what is queued */
  REQUIRE(test_latest_guard(r, 3.0, g), "palp_server_guard received");
}

int main(void) {
  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  cfg.max_sessions = 6;
  cfg.max_viewers = 2;
  cfg.stations_per_writer = 2;
  cfg.join_rate = 20;
  cfg.join_burst = 10;
  cfg.closed_retention = 0.3;
  cfg.status_rate_hz = 5;
  test_server ts = {0};
  test_server_start(&ts, &cfg);

  dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  REQUIRE(pp > 0, "test participant");
  dds_entity_t reply_t = palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REPLY);
  dds_entity_t reply_r = palp_dds_create_reader(pp, reply_t, PALP_TOPIC_SESSION_REPLY);
  dds_entity_t guard_t = palp_dds_create_topic(pp, PALP_TOPIC_SERVER_GUARD);
  dds_entity_t guard_r = palp_dds_create_reader(pp, guard_t, PALP_TOPIC_SERVER_GUARD);

  /* 1. One writer, 300 station ids (the issue: 300 bogus joins filled 256 slots). */
  dds_entity_t evil = request_writer(pp);
  test_sleep(0.5);
  char id[64];
  for (int i = 0; i < 300; i++) {
    snprintf(id, sizeof id, "evil/%d", i);
    send_join(evil, id, palp_ROLE_TRAINEE, 1, 0, 1, palp_OP_JOIN);
  }
  char why[128] = "";
  int first = await_reply(reply_r, "evil/0", 1, 3.0, why, sizeof why);
  int third = await_reply(reply_r, "evil/2", 1, 0.5, NULL, 0);
  CHECK(first == 1, "the writer's first station id is served (%s)", first == 1 ? "accepted" : why);
  CHECK(third == -1, "its third station id never reaches the server (no reply within 0.5 s)");
  palp_ServerGuard g;
  test_sleep(0.3);
  wait_guard_after(guard_r, &g);
  CHECK(g.request_keys_filtered >= 298 && g.request_keys_filtered <= 300,
        "request instances refused by the per-writer filter: %llu (want 298 of 300)",
        (unsigned long long)g.request_keys_filtered);
  CHECK(g.stations <= 2 && g.station_slots == 6 * (1 + 2), "station slots in use %u of %u (want <= 2 of 18)", g.stations,
        g.station_slots);

  /* 2. Real stations still get in: two trainees, and viewers up to max_viewers. */
  palp_cli_station a, b, v[3];
  test_station_join(&a, DOMAIN, "real-a", palp_ROLE_TRAINEE, 1, 0, 1, 0);
  test_station_join(&b, DOMAIN, "real-b", palp_ROLE_TRAINEE, 2, 0, 1, 0);
  CHECK(a.session_id > 0 && b.session_id > 0, "real trainees joined after the flood: sessions %u and %u", a.session_id,
        b.session_id);
  test_station_join(&v[0], DOMAIN, "viewer-0", palp_ROLE_OBSERVER, 0, a.session_id, 1, 0);
  test_station_join(&v[1], DOMAIN, "viewer-1", palp_ROLE_VISUAL, 0, a.session_id, 0, 1);
  char err[256] = "";
  palp_cli_station_open(&v[2], DOMAIN, "viewer-2", err, sizeof err);
  palp_cli_join j = {.role = palp_ROLE_OBSERVER, .session_id = a.session_id, .user_name = "viewer-2", .timeout = 3};
  int rc = palp_cli_station_join(&v[2], &j, err, sizeof err);
  CHECK(rc < 0 && strstr(err, "max_viewers"), "a third viewer is refused: \"%s\"", err);

  /* 3. Join rate: 40 joins from 40 writers at once, burst 10, 20/s. */
  dds_entity_t burst_w[40];
  for (int i = 0; i < 40; i++) burst_w[i] = request_writer(pp);
  test_sleep(0.5);
  palp_ServerGuard g0;
  wait_guard_after(guard_r, &g0);
  int64_t t0 = palp_dds_now_ns();
  for (int i = 0; i < 40; i++) {
    snprintf(id, sizeof id, "burst/%d", i);
    send_join(burst_w[i], id, palp_ROLE_TRAINEE, 99, 0, 1, palp_OP_JOIN); /* unknown phantom: refused anyway */
  }
  double dt = (double)(palp_dds_now_ns() - t0) * 1e-9; /* sending time: tokens refill meanwhile */
  int busy = 0, answered = 0;
  collect_replies(reply_r, "burst/", 5.0, 40, &answered, &busy);
  test_sleep(0.3);
  wait_guard_after(guard_r, &g);
  /* At most burst + rate x elapsed joins get a token. */
  int allowed = 10 + (int)(20 * dt) + 1;
  CHECK(answered == 40 && busy >= 40 - allowed && g.joins_refused_rate - g0.joins_refused_rate == (uint64_t)busy,
        "40 joins in %.2f s: %d refused \"server busy\" (want >= %d), counted %llu", dt, busy, 40 - allowed,
        (unsigned long long)(g.joins_refused_rate - g0.joins_refused_rate));
  test_sleep(1.0); /* tokens refill */

  /* 4. 20 sessions opened and closed by one station; then a newcomer's view. */
  dds_entity_t cyc = request_writer(pp);
  test_sleep(0.3);
  int cycled = 0;
  for (uint32_t k = 1; k <= 20; k++) {
    send_join(cyc, "cycler", palp_ROLE_TRAINEE, 1, 0, 2 * k, palp_OP_JOIN);
    if (await_reply(reply_r, "cycler", 2 * k, 3.0, why, sizeof why) == 1) cycled++;
    send_join(cyc, "cycler", palp_ROLE_TRAINEE, 0, 0, 2 * k + 1, palp_OP_LEAVE);
    await_reply(reply_r, "cycler", 2 * k + 1, 3.0, NULL, 0);
    test_sleep(0.06); /* under join_rate */
  }
  CHECK(cycled == 20, "20 sessions opened and closed by one station (%d accepted)", cycled);
  palp_cli_station_leave(&v[1]);
  palp_cli_station_leave(&v[0]);
  test_sleep(1.0); /* > closed_retention */
  wait_guard_after(guard_r, &g);
  dds_entity_t late = dds_create_participant(DOMAIN, NULL, NULL);
  dds_entity_t st_t = palp_dds_create_topic(late, PALP_TOPIC_SESSION_STATE);
  dds_entity_t st_r = palp_dds_create_reader(late, st_t, PALP_TOPIC_SESSION_STATE);
  dds_entity_t rp_t = palp_dds_create_topic(late, PALP_TOPIC_SESSION_REPLY);
  dds_entity_t rp_r = palp_dds_create_reader(late, rp_t, PALP_TOPIC_SESSION_REPLY);
  test_sleep(1.5);
  int states = 0, replies = 0, open_states = 0;
  {
    void *ptr[64] = {NULL};
    dds_sample_info_t info[64];
    int n = dds_take(st_r, ptr, info, 64, 64);
    for (int i = 0; i < n; i++)
      if (info[i].valid_data) states++, open_states += ((palp_SessionState *)ptr[i])->phase == palp_PHASE_OPEN;
    if (n > 0) dds_return_loan(st_r, ptr, n);
    n = dds_take(rp_r, ptr, info, 64, 64);
    for (int i = 0; i < n; i++) replies += info[i].valid_data;
    if (n > 0) dds_return_loan(rp_r, ptr, n);
  }
  /* Open now: the two admitted evil ids' sessions and real-a's and real-b's. Live
   * replies: theirs (refused and closed ones are released). */
  CHECK(states == 4 && open_states == 4, "a newcomer is sent %d session states, %d open (want 4 and 4; never released it would be 24)",
        states, open_states);
  CHECK(replies <= (int)g.stations && replies >= 2, "a newcomer is sent %d replies for %u stations in slots (want 2..%u; "
        "never released: one per station id ever answered, 48 here)", replies, g.stations, g.stations);
  CHECK(g.instances_released >= 20, "instances released: %llu (want >= 20 closed states)",
        (unsigned long long)g.instances_released);

  dds_delete(late);
  palp_cli_station_close(&v[0]);
  palp_cli_station_close(&v[1]);
  palp_cli_station_close(&v[2]);
  palp_cli_station_leave(&a);
  palp_cli_station_leave(&b);
  test_sleep(0.2);
  palp_cli_station_close(&a);
  palp_cli_station_close(&b);
  dds_delete(pp);
  test_server_stop(&ts);
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
