/* test_malformed.c - a station flooding malformed contacts gets every sample
 * rejected (or clamped) and counted by reason, while another session keeps its
 * tick rate and its feedback. */
#include <math.h>
#include <string.h>

#include "harness.h"
#include "validate.h"

#define DOMAIN 105
#define RATE 100.0

static int latest_status(palp_cli_station *st, dds_entity_t reader, double wait, palp_ServerStatus *out,
                         palp_SessionLoad *loads, int cap, int *nloads) {
  (void)st;
  int64_t end = palp_dds_now_ns() + (int64_t)(wait * 1e9);
  int got = 0;
  while (palp_dds_now_ns() < end && !got) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(reader, ptr, &info, 1, 1) > 0) {
      if (info.valid_data) {
        const palp_ServerStatus *s = ptr[0];
        *out = *s;
        *nloads = 0;
        for (uint32_t i = 0; i < s->sessions._length && *nloads < cap; i++) loads[(*nloads)++] = s->sessions._buffer[i];
        out->sessions._buffer = NULL;
        got = 1;
      }
      dds_return_loan(reader, ptr, 1);
    }
    test_sleep(0.02);
  }
  return got;
}

static int session_state(palp_cli_station *st, uint32_t id, double wait, palp_SessionState *out) {
  int64_t end = palp_dds_now_ns() + (int64_t)(wait * 1e9);
  int got = 0;
  while (palp_dds_now_ns() < end && !got) {
    palp_SessionState buf[8];
    void *ptr[8];
    dds_sample_info_t info[8];
    for (int i = 0; i < 8; i++) ptr[i] = &buf[i];
    int n;
    while ((n = dds_take(st->state_r, ptr, info, 8, 8)) > 0)
      for (int i = 0; i < n; i++)
        if (info[i].valid_data && buf[i].session_id == id) *out = buf[i], got = 1;
    if (!got) test_sleep(0.02);
  }
  return got;
}

int main(void) {
  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, RATE);
  test_server ts = {0};
  test_server_start(&ts, &cfg);
  palp_cli_station good, bad;
  test_station_join(&good, DOMAIN, "good", palp_ROLE_TRAINEE, 1, 0, 1, 0);
  test_station_join(&bad, DOMAIN, "bad", palp_ROLE_TRAINEE, 2, 0, 1, 0);
  dds_entity_t status_r = palp_dds_create_reader(good.pp, good.topic[PALP_TOPIC_SERVER_STATUS], PALP_TOPIC_SERVER_STATUS);

  /* The good session presses 2 N throughout, so its world is awake and stepping. */
  uint64_t seq = 0;
  for (int i = 0; i < 50; i++) {
    test_send_force(&good, 0, 2, 25, 90, 2.0, ++seq);
    test_sleep(0.01);
  }
  palp_SessionState s0, s1;
  REQUIRE(session_state(&good, good.session_id, 2.5, &s0), "good session state before the flood");

  /* 3 s of flood from the bad station at ~2 kHz, cycling through every kind of bad sample. */
  enum { KINDS = 8 };
  int sent[KINDS] = {0};
  int64_t end = palp_dds_now_ns() + 3000000000LL;
  uint64_t bseq = 0;
  int k = 0;
  while (palp_dds_now_ns() < end) {
    palp_Contact c;
    memset(&c, 0, sizeof c);
    c.session_id = bad.session_id;
    c.finger = (uint8_t)(k % 4);
    c.seq = ++bseq;
    c.mode = palp_CONTACT_FORCE;
    c.distribution = 2;
    c.vertex = -1;
    c.center = (palp_Vec3){0, 0, 0.04};
    c.force = (palp_Vec3){0, 0, -1};
    switch (k) {
    case 0: c.center.x = NAN; break;                 /* nonfinite */
    case 1: c.force.z = -INFINITY; break;            /* nonfinite */
    case 2: c.distribution = 9; break;               /* bad_distribution */
    case 3: c.vertex = 100000; break;                /* bad_vertex */
    case 4: c.force.z = -100; break;                 /* force_limit (clamped to 20 N; 1e6 N is absurd_force) */
    case 5: c.mode = palp_CONTACT_FINGER; c.radius = 2.0; break; /* bad_radius */
    case 6: c.session_id = 999999; break;            /* unknown_session */
    case 7: c.finger = 17; break;                    /* bad_finger */
    }
    test_send_raw(&bad, &c);
    sent[k]++;
    k = (k + 1) % KINDS;
    /* keep the good station pressing at its 100 Hz too */
    if (bseq % 20 == 0) test_send_force(&good, 0, 2, 25, 90, 2.0, ++seq);
    test_sleep(0.0005);
  }
  for (int i = 0; i < 20; i++) {
    test_send_force(&good, 0, 2, 25, 90, 2.0, ++seq);
    test_sleep(0.01);
  }
  REQUIRE(session_state(&good, good.session_id, 2.5, &s1), "good session state after the flood");
  double dt = s1.duration - s0.duration;
  double rate = (double)(s1.ticks - s0.ticks) / dt;
  /* A correctness property, not a benchmark: the good session keeps >= 90 % of
   * its nominal tick rate while the other is flooded (measured between two
   * 1 Hz session states at least 2.5 s apart, spanning the 3 s flood). */
  CHECK(dt >= 2.5 && rate >= 0.9 * RATE, "good session ticked at %.1f Hz over %.1f s during the flood (want >= %.0f Hz)",
        rate, dt, 0.9 * RATE);
  CHECK(s1.rejected_samples == 0, "good session: %llu rejected samples (want 0)", (unsigned long long)s1.rejected_samples);
  int n = 0;
  double f = test_last_feedback(&good, 0.1, &n);
  CHECK(fabs(f - 2.0) < 0.2, "good session's feedback %.3f N while pressing 2 N (tolerance 0.2 N)", f);

  palp_ServerStatus st;
  palp_SessionLoad loads[8];
  int nl = 0;
  test_sleep(1.1); /* a status period after the flood */
  REQUIRE(latest_status(&good, status_r, 3.0, &st, loads, 8, &nl), "server status received");
  const palp_SessionLoad *lb = NULL, *lg = NULL;
  for (int i = 0; i < nl; i++) {
    if (loads[i].session_id == bad.session_id) lb = &loads[i];
    if (loads[i].session_id == good.session_id) lg = &loads[i];
  }
  REQUIRE(lb && lg, "both sessions listed in palp_server_status (%d listed)", nl);
  const struct {
    palp_srv_reject_reason r;
    int sent;
  } want[] = {{PALP_SRV_REJ_NONFINITE, sent[0] + sent[1]}, {PALP_SRV_REJ_BAD_DISTRIBUTION, sent[2]},
              {PALP_SRV_REJ_BAD_VERTEX, sent[3]},          {PALP_SRV_REJ_FORCE_LIMIT, sent[4]},
              {PALP_SRV_REJ_BAD_RADIUS, sent[5]},          {PALP_SRV_REJ_UNKNOWN_SESSION, sent[6]},
              {PALP_SRV_REJ_BAD_FINGER, sent[7]}};
  for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
    /* Best-effort keep-last 1 per (session, finger) instance: samples may be
     * overwritten before the 100 Hz tick takes them, so the count is > 0 and
     * <= sent, never more. */
    uint64_t got = lb->rejected[want[i].r];
    CHECK(got > 0 && got <= (uint64_t)want[i].sent && st.rejected[want[i].r] >= got,
          "reason %-16s counted %llu of %d sent (server total %llu)", palp_srv_reject_name(want[i].r),
          (unsigned long long)got, want[i].sent, (unsigned long long)st.rejected[want[i].r]);
  }
  uint64_t good_rej = 0;
  for (int r = 0; r < PALP_SRV_REJ_WIRE; r++) good_rej += lg->rejected[r];
  CHECK(good_rej == 0, "good session's rejected counters are all 0 (sum %llu)", (unsigned long long)good_rej);
  palp_SessionState sb;
  CHECK(session_state(&bad, bad.session_id, 2.5, &sb) && sb.phase == palp_PHASE_OPEN,
        "the flooded session itself stays open (phase %d)", (int)sb.phase);

  palp_cli_station_leave(&good);
  palp_cli_station_leave(&bad);
  test_sleep(0.2);
  palp_cli_station_close(&good);
  palp_cli_station_close(&bad);
  test_server_stop(&ts);
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
