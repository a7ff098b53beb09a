/* test_rewritten.c - a station's JOIN again from a new request writer keeps the station (plain DDS, domain 164).
 *
 * When a station's participant is lost and found again, Cyclone gives its request writer a new publication
 * handle and re-delivers the station's JOIN (transient-local) from it; the new valid sample wipes the pending
 * not-alive one, so the server sees only the same JOIN again and answers it without redoing it. Until
 * 2026-12-06 that path kept the station's old writer handle: the old writer's unmatch then scheduled the
 * writers sweep (sweep_gone_writers), which found the station's writer unmatched and declared a live station
 * lost (a palp-web viewer silently dropped, a trainee's session held).
 *
 * Here one participant plays it out with writers that do not dispose on deletion (as a lost participant's
 * writers are only unregistered): a trainee (W0) and an observer (W1) join; each JOIN is written again,
 * unchanged, from a new writer (W2, W3) and answered; then W0 and W1 are deleted, so the matched count falls
 * and the sweep runs. Neither station may leave. Then W2 is deleted too, the observer's last writer: it is
 * lost (the check above can see a loss). */
#include <stdatomic.h>
#include <string.h>
#include <unistd.h>

#include "../tmpdir.h"
#include "harness.h"
#include "palp_log.h"

#define DOMAIN 164

static atomic_int left_trainee, left_viewer;

static void on_member(void *ctx, uint32_t session_id, const char *station, int role, int joined) {
  (void)ctx, (void)session_id, (void)role;
  if (joined) return;
  if (!strcmp(station, "trainee")) atomic_fetch_add(&left_trainee, 1);
  if (!strcmp(station, "viewer")) atomic_fetch_add(&left_viewer, 1);
}

/* A request writer that only unregisters its instances when deleted, as a lost participant's writer is. */
static dds_entity_t quiet_writer(dds_entity_t pp, dds_entity_t topic) {
  dds_qos_t *q = palp_dds_qos(PALP_TOPIC_SESSION_REQUEST);
  dds_qset_writer_data_lifecycle(q, false);
  const dds_entity_t w = dds_create_writer(pp, topic, q, NULL);
  dds_delete_qos(q);
  return w;
}

static void join(dds_entity_t w, const char *id, int role, uint32_t session) {
  palp_SessionRequest r;
  memset(&r, 0, sizeof r);
  snprintf(r.station_id, sizeof r.station_id, "%s", id);
  snprintf(r.user_name, sizeof r.user_name, "%s", id);
  r.request_seq = 7;
  r.op = palp_OP_JOIN;
  r.role = role;
  r.phantom_id = 1;
  r.session_id = session;
  dds_write(w, &r);
}

/* The next reply to station id within wait [s]: 1 accepted (*session set), 0 refused, -1 none. */
static int await_reply(dds_entity_t r, const char *id, double wait, uint32_t *session) {
  const int64_t end = palp_dds_now_ns() + (int64_t)(wait * 1e9);
  while (palp_dds_now_ns() < end) {
    palp_SessionReply b[8];
    void *ptr[8];
    dds_sample_info_t info[8];
    for (int i = 0; i < 8; i++) ptr[i] = &b[i];
    const int n = dds_take(r, ptr, info, 8, 8);
    for (int i = 0; i < n; i++)
      if (info[i].valid_data && !strcmp(b[i].station_id, id)) {
        if (session) *session = b[i].session_id;
        return b[i].status == palp_REPLY_ACCEPTED;
      }
    if (n <= 0) test_sleep(0.005);
  }
  return -1;
}

static int log_count(const char *path, const char *a, const char *b) {
  FILE *f = fopen(path, "r");
  char buf[4096];
  int n = 0;
  while (f && fgets(buf, sizeof buf, f)) n += strstr(buf, a) != NULL && (!b || strstr(buf, b) != NULL);
  if (f) fclose(f);
  return n;
}

int main(void) {
  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  char log_path[512];
  palp_test_tmp(log_path, sizeof log_path, "palp-rewritten-XXXXXX");
  const int log_fd = mkstemp(log_path);
  palp_log plog;
  REQUIRE(log_fd >= 0 && palp_log_init(&plog, "palp-server", PALP_LOG_INFO, log_path) == 0, "server log %s", log_path);
  close(log_fd);
  const palp_srv_events ev = {.member_changed = on_member};
  const palp_srv_def def = {.cfg = cfg, .verbose = 1, .log = &plog, .events = &ev};
  test_server ts = {0};
  test_server_start_def(&ts, &def);

  const dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  const dds_entity_t topic = palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REQUEST);
  const dds_entity_t rr = palp_dds_create_reader(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REPLY),
                                                 PALP_TOPIC_SESSION_REPLY);
  const dds_entity_t w0 = quiet_writer(pp, topic), w1 = quiet_writer(pp, topic);
  REQUIRE(pp > 0 && topic > 0 && rr > 0 && w0 > 0 && w1 > 0, "test participant, reply reader, writers");
  test_sleep(1.0); /* matched */

  uint32_t sid = 0, again_sid = 0;
  join(w0, "trainee", palp_ROLE_TRAINEE, 0);
  REQUIRE(await_reply(rr, "trainee", 3.0, &sid) == 1, "the trainee joins (session %u)", sid);
  join(w1, "viewer", palp_ROLE_OBSERVER, sid);
  REQUIRE(await_reply(rr, "viewer", 3.0, NULL) == 1, "the observer joins session %u", sid);

  /* The same JOINs from new writers (the participant found again). */
  const dds_entity_t w2 = quiet_writer(pp, topic), w3 = quiet_writer(pp, topic);
  REQUIRE(w2 > 0 && w3 > 0, "new writers");
  test_sleep(0.5); /* matched */
  join(w2, "viewer", palp_ROLE_OBSERVER, sid);
  CHECK(await_reply(rr, "viewer", 3.0, &again_sid) == 1 && again_sid == sid,
        "the observer's JOIN again from a new writer is answered: session %u", again_sid);
  join(w3, "trainee", palp_ROLE_TRAINEE, 0);
  CHECK(await_reply(rr, "trainee", 3.0, &again_sid) == 1 && again_sid == sid,
        "the trainee's JOIN again from a new writer is answered: session %u", again_sid);

  /* The old writers go: the matched count falls and the sweep looks at every station's writer. */
  dds_delete(w0);
  dds_delete(w1);
  test_sleep(1.0); /* GONE_GRACE_NS (50 ms) and a pass that drains the reader, many times over */
  CHECK(atomic_load(&left_viewer) == 0 && log_count(log_path, "station viewer", "left session") == 0,
        "the observer, answered from its new writer, is not lost when its old writer goes (%d leave(s))",
        atomic_load(&left_viewer));
  CHECK(atomic_load(&left_trainee) == 0 && log_count(log_path, "trainee station trainee", NULL) == 0 &&
            palp_srv_open_sessions(ts.srv) == 1,
        "the trainee, answered from its new writer, is not lost when its old writer goes (%d leave(s), %d "
        "session(s) open)", atomic_load(&left_trainee), palp_srv_open_sessions(ts.srv));

  /* Its last writer gone, the observer is lost: the checks above can see a loss. */
  dds_delete(w2);
  const int64_t end = palp_dds_now_ns() + 3000000000LL;
  /* both the event and the log line awaited (the server logs first since 2026-12-07) */
  while ((atomic_load(&left_viewer) == 0 || log_count(log_path, "station viewer", "lost") == 0) &&
         palp_dds_now_ns() < end)
    test_sleep(0.01);
  CHECK(atomic_load(&left_viewer) == 1 && log_count(log_path, "station viewer", "lost") == 1,
        "the observer's last writer gone, it is lost (%d leave(s))", atomic_load(&left_viewer));

  dds_delete(pp);
  test_server_stop(&ts);
  palp_log_close(&plog);
  if (!palp_test_failures) unlink(log_path);
  else fprintf(stderr, "server log kept: %s\n", log_path);
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
