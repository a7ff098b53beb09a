/* test_isolation.c - two trainees on the same phantom get two sessions in two
 * partitions: one pressing leaves the other's world, feedback and contact
 * stream untouched. And (2026-12-07) a station restarted with the same station
 * id joins again after its first session closed. Domain 103. */
#include <math.h>
#include <string.h>

#include "harness.h"
#include "view.h"

#define DOMAIN 103

typedef struct seen {
  int feedback, foreign_feedback, contacts, deformations, foreign_deformations;
  double max_fb, max_disp;
} seen;

static void drain(palp_cli_station *st, const palp_Phantom *ph, seen *s) {
  void *ptr[1] = {NULL};
  dds_sample_info_t info;
  while (st->feedback_r > 0 && dds_take(st->feedback_r, ptr, &info, 1, 1) > 0) {
    const palp_Feedback *fb = ptr[0];
    if (info.valid_data) {
      s->feedback++;
      s->foreign_feedback += fb->session_id != st->session_id;
      for (uint32_t k = 0; k < fb->fingers._length; k++) {
        palp_Vec3 f = fb->fingers._buffer[k].force;
        double m = sqrt(f.x * f.x + f.y * f.y + f.z * f.z);
        if (m > s->max_fb) s->max_fb = m;
      }
    }
    dds_return_loan(st->feedback_r, ptr, 1);
  }
  while (st->contact_r > 0 && dds_take(st->contact_r, ptr, &info, 1, 1) > 0) {
    s->contacts += info.valid_data;
    dds_return_loan(st->contact_r, ptr, 1);
  }
  while (st->deformation_r > 0 && dds_take(st->deformation_r, ptr, &info, 1, 1) > 0) {
    if (info.valid_data) {
      const palp_Deformation *d = ptr[0];
      s->deformations++;
      s->foreign_deformations += d->session_id != st->session_id;
      double m = palp_cli_max_displacement(ph, d, NULL);
      if (m > s->max_disp) s->max_disp = m;
    }
    dds_return_loan(st->deformation_r, ptr, 1);
  }
}

/* The instances reader r holds: its samples not read yet, a page at a time (keep-last 1: one an
 * instance; the stations take, never read, these readers' samples). */
static int instances_held(dds_entity_t r) {
  int held = 0, n;
  do {
    void *ptr[64] = {NULL};
    dds_sample_info_t info[64];
    n = r > 0 ? dds_read_mask(r, ptr, info, 64, 64, DDS_NOT_READ_SAMPLE_STATE) : 0;
    if (n > 0) dds_return_loan(r, ptr, n);
    held += n > 0 ? n : 0;
  } while (n > 0);
  return held;
}

int main(void) {
  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  test_server ts = {0};
  test_server_start(&ts, &cfg);
  palp_cli_station a, b, obs_a, obs_b;
  test_station_join(&a, DOMAIN, "trainee-a", palp_ROLE_TRAINEE, 1, 0, 1, 0);
  test_station_join(&b, DOMAIN, "trainee-b", palp_ROLE_TRAINEE, 1, 0, 1, 0);
  REQUIRE(a.session_id != b.session_id && strcmp(a.partition, b.partition) != 0,
          "same phantom, two sessions: %u in %s and %u in %s", a.session_id, a.partition, b.session_id, b.partition);
  test_station_join(&obs_a, DOMAIN, "observer-a", palp_ROLE_OBSERVER, 0, a.session_id, 1, 1);
  test_station_join(&obs_b, DOMAIN, "observer-b", palp_ROLE_OBSERVER, 0, b.session_id, 1, 1);
  char err[256];
  palp_Phantom ph;
  REQUIRE(palp_cli_station_catalogue(&a, 1, 5, &ph, err, sizeof err) == 0, "catalogue %s", err);
  seen sa = {0}, sb = {0}, soa = {0}, sob = {0};
  /* A presses 4 N for 1.5 s; B does nothing. */
  uint64_t seq = 0;
  int64_t end = palp_dds_now_ns() + 1500000000;
  while (palp_dds_now_ns() < end) {
    test_send_force(&a, 0, 3, 20, 0, 4.0, ++seq);
    test_sleep(0.01);
    drain(&a, &ph, &sa);
    drain(&b, &ph, &sb);
    drain(&obs_a, &ph, &soa);
    drain(&obs_b, &ph, &sob);
  }
  test_sleep(0.2);
  drain(&a, &ph, &sa);
  drain(&b, &ph, &sb);
  drain(&obs_a, &ph, &soa);
  drain(&obs_b, &ph, &sob);

  CHECK(sa.max_fb > 3.0, "A's feedback reaches %.2f N (pressing 4 N; want > 3 N)", sa.max_fb);
  CHECK(soa.contacts > 50 && soa.max_disp > 1e-3, "A's observer sees %d of A's contacts and %.2f mm displacement",
        soa.contacts, soa.max_disp * 1e3);
  /* the idle session is sent feedback too (its finger inactive): samples received, all at 0 N */
  CHECK(sb.feedback > 0 && sb.max_fb == 0.0, "B's feedback stays exactly 0 N (max %.3g N over %d samples; want > 0 "
                                              "samples)", sb.max_fb, sb.feedback);
  CHECK(sob.contacts == 0, "B's observer sees %d contact samples (want 0: A's are in another partition)", sob.contacts);
  /* B's world never received a load: its only motion is settling under gravity,
   * far below A's millimetres. 0.1 mm tolerance. */
  CHECK(sob.max_disp < 1e-4, "B's displacement stays below 0.1 mm (max %.4f mm over %d frames)", sob.max_disp * 1e3,
        sob.deformations);
  /* A positive control for the zeros above: B's observer does receive B's world (a sleeping world's
   * shape is sent again once a second, test_contact.c), so its readers are matched in B's partition. */
  CHECK(sob.deformations > 0, "B's observer received B's world: %d frames in 1.7 s (want > 0: its reader is matched)",
        sob.deformations);
  CHECK(sa.foreign_feedback == 0 && sb.foreign_feedback == 0 && soa.foreign_deformations == 0 &&
            sob.foreign_deformations == 0,
        "no station received a sample of the other session (%d, %d, %d, %d)", sa.foreign_feedback, sb.foreign_feedback,
        soa.foreign_deformations, sob.foreign_deformations);
  /* An idle phantom sleeps: B, never touched, is ticked but not stepped. Two
   * server statuses about a second apart: B keeps ticking (~100 at 100 Hz),
   * its awake ticks not at all. */
  dds_entity_t status_r = palp_dds_create_reader(b.pp, b.topic[PALP_TOPIC_SERVER_STATUS], PALP_TOPIC_SERVER_STATUS);
  uint64_t ticks[2] = {0, 0}, awake[2] = {0, 0};
  for (int k = 0; k < 2; k++) {
    int got = 0;
    int64_t until = palp_dds_now_ns() + 3000000000LL;
    while (!got && palp_dds_now_ns() < until) {
      void *ptr[1] = {NULL};
      dds_sample_info_t info;
      while (dds_take(status_r, ptr, &info, 1, 1) > 0) {
        const palp_ServerStatus *st = ptr[0];
        if (info.valid_data)
          for (uint32_t i = 0; i < st->sessions._length; i++)
            if (st->sessions._buffer[i].session_id == b.session_id) {
              ticks[k] = st->sessions._buffer[i].ticks;
              awake[k] = st->sessions._buffer[i].awake_ticks;
              got = 1;
            }
        dds_return_loan(status_r, ptr, 1);
      }
      test_sleep(0.02);
    }
    if (k == 0) test_sleep(1.0);
  }
  CHECK(ticks[1] - ticks[0] >= 50 && awake[1] == awake[0],
        "idle B: %llu ticks, %llu of them awake, between two statuses (want >= 50: ticking, and 0: asleep)",
        (unsigned long long)(ticks[1] - ticks[0]), (unsigned long long)(awake[1] - awake[0]));
  /* The other positive control: B presses 0.5 s (4 N, as A did); B's feedback and B's observer's contacts
   * arrive (the readers that saw nothing above do receive their own session), A's observer sees none of
   * B's contacts (A is not pressing now), and no station a sample of the other session. */
  {
    seen sb2 = {0}, sob2 = {0}, sa2 = {0}, soa2 = {0};
    uint64_t bseq = 0;
    for (const int64_t until = palp_dds_now_ns() + 500000000; palp_dds_now_ns() < until; test_sleep(0.01)) {
      test_send_force(&b, 0, 3, 20, 0, 4.0, ++bseq);
      drain(&b, &ph, &sb2);
      drain(&obs_b, &ph, &sob2);
      drain(&a, &ph, &sa2);
      drain(&obs_a, &ph, &soa2);
    }
    test_sleep(0.2);
    drain(&b, &ph, &sb2);
    drain(&obs_b, &ph, &sob2);
    drain(&a, &ph, &sa2);
    drain(&obs_a, &ph, &soa2);
    CHECK(sb2.feedback > 0 && sb2.max_fb > 1.0 && sob2.contacts > 0,
          "B pressing 4 N for 0.5 s: B's feedback %d samples up to %.2f N (want > 1 N), B's observer %d contacts "
          "(want > 0)", sb2.feedback, sb2.max_fb, sob2.contacts);
    CHECK(soa2.contacts == 0 && sa2.foreign_feedback == 0 && soa2.foreign_deformations == 0 &&
              sb2.foreign_feedback == 0 && sob2.foreign_deformations == 0,
          "while B presses, A's observer sees %d contacts; samples of the other session: %d, %d, %d, %d (want 0 each)",
          soa2.contacts, sa2.foreign_feedback, soa2.foreign_deformations, sb2.foreign_feedback,
          sob2.foreign_deformations);
  }
  /* (2026-12-07) A peer writes made-up keys of the global topics the stations read while they are in
   * their sessions: 20,000 OPEN states and 20,000 replies of distinct ids, 2,000 exercises and 2,000
   * server statuses. Each became an instance of every station's reader, held while its writer lived
   * (a reviewer's observer: 12.8 MB -> 138 MB RSS for 200,000 states). Filtered, a station holds its own
   * session's state, its own reply, its phantom's exercise and its server's status; and A's session
   * goes on. Written in this process: delivered to the stations' readers within each write. */
  {
    enum { FLOOD = 20000, FEW = 2000 };
    const dds_entity_t fp = dds_create_participant(DOMAIN, NULL, NULL);
    static const palp_dds_topic_kind kind[] = {PALP_TOPIC_SESSION_STATE, PALP_TOPIC_SESSION_REPLY, PALP_TOPIC_EXERCISE,
                                               PALP_TOPIC_SERVER_STATUS};
    dds_entity_t fw[4];
    for (int k = 0; k < 4; k++) fw[k] = palp_dds_create_writer(fp, palp_dds_create_topic(fp, kind[k]), kind[k]);
    REQUIRE(fp > 0 && fw[0] > 0 && fw[1] > 0 && fw[2] > 0 && fw[3] > 0, "a peer writes states, replies, exercises and statuses");
    const long rss0 = test_rss_kb();
    const int64_t t0 = palp_dds_now_ns();
    for (uint32_t k = 1; k <= FLOOD; k++) {
      palp_SessionState m;
      memset(&m, 0, sizeof m);
      m.session_id = 0x7f000000u + k; /* another server number than the harness server's (0) */
      m.phase = palp_PHASE_OPEN;
      snprintf(m.trainee_name, sizeof m.trainee_name, "flood");
      snprintf(m.trainee_station, sizeof m.trainee_station, "flood/%u", k);
      dds_write(fw[0], &m);
      palp_SessionReply r;
      memset(&r, 0, sizeof r);
      snprintf(r.station_id, sizeof r.station_id, "flood/%u", k);
      r.request_seq = k;
      dds_write(fw[1], &r);
      if (k > FEW) continue;
      palp_Exercise e;
      memset(&e, 0, sizeof e);
      e.phantom_id = 5000 + k;
      snprintf(e.name, sizeof e.name, "flood");
      dds_write(fw[2], &e);
      palp_ServerStatus ss;
      memset(&ss, 0, sizeof ss);
      snprintf(ss.server_id, sizeof ss.server_id, "flood/%u", k);
      dds_write(fw[3], &ss);
    }
    const double flood_s = (double)(palp_dds_now_ns() - t0) * 1e-9;
    const long rss1 = test_rss_kb();
    const int hs = instances_held(a.state_r), hr = instances_held(a.reply_r), he = instances_held(a.exercise_r),
              hst = instances_held(a.status_r), ho = instances_held(obs_a.state_r), hor = instances_held(obs_a.reply_r);
    fprintf(stderr, "flood written in %.2f s; RSS %ld -> %ld kB (the peer's writers and 4 stations)\n", flood_s, rss0, rss1);
    CHECK(hs <= 1 && hr <= 1 && he <= 1 && hst <= 2 && ho <= 1 && hor <= 1,
          "after %d made-up states and replies and %d exercises and statuses, trainee A's readers hold %d states, %d "
          "replies, %d exercises, %d statuses, her observer's %d states and %d replies (want <= 1 each, 2 statuses)",
          FLOOD, FEW, hs, hr, he, hst, ho, hor);
    uint64_t fseq = 1000000;
    seen sf = {0};
    for (const int64_t until = palp_dds_now_ns() + 500000000; palp_dds_now_ns() < until; test_sleep(0.01)) {
      test_send_force(&a, 0, 3, 20, 0, 4.0, ++fseq);
      drain(&a, &ph, &sf);
    }
    char why[256] = "";
    const int closed = palp_cli_station_session_closed(&a, why, sizeof why);
    CHECK(!closed && sf.max_fb > 3.0, "A's session goes on through the flood: %s, feedback %.2f N (pressing 4 N; want > 3 N)",
          closed ? why : "open", sf.max_fb);
    dds_delete(fp);
  }
  /* (2026-12-07) A station restarted with the same id (host, pid and label: a container's pid 1 and
   * fixed hostname, a pid reused; here two stations of one process with one label) is accepted: both
   * numbered their requests from 1, and the second's JOIN was the closed session's (station id,
   * request_seq) pair, refused "session N closed: trainee station left". */
  palp_cli_station first, second;
  test_station_join(&first, DOMAIN, "restarted", palp_ROLE_TRAINEE, 2, 0, 0, 0);
  palp_cli_station_leave(&first);
  char why[256] = "";
  int left = 0;
  for (int64_t until = palp_dds_now_ns() + 3000000000LL; !left && palp_dds_now_ns() < until; test_sleep(0.02))
    left = palp_cli_station_session_closed(&first, why, sizeof why);
  palp_cli_station_close(&first);
  REQUIRE(left, "the first station's session %u closed: %s", first.session_id, why);
  err[0] = 0;
  REQUIRE(palp_cli_station_open(&second, DOMAIN, "restarted", err, sizeof err) == 0, "the second station opens %s", err);
  const palp_cli_join j = {.role = palp_ROLE_TRAINEE, .phantom_id = 2, .user_name = "restarted", .timeout = 5};
  const int rc = palp_cli_station_join(&second, &j, err, sizeof err);
  CHECK(rc == 0 && strcmp(second.station_id, first.station_id) == 0 && second.session_id != first.session_id,
        "a second station with the first's id %s joins after the first's session %u closed: %s", second.station_id,
        first.session_id, rc ? err : "a new session");
  if (rc == 0) palp_cli_station_leave(&second);
  palp_cli_station_close(&second);
  palp_cli_phantom_free(&ph);
  palp_cli_station *all[] = {&obs_a, &obs_b, &a, &b};
  for (int i = 0; i < 4; i++) palp_cli_station_leave(all[i]);
  test_sleep(0.2);
  for (int i = 0; i < 4; i++) palp_cli_station_close(all[i]);
  test_server_stop(&ts);
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
