/* test_flood.c - a hostile participant floods the contact topic: 20,000 distinct
 * keys, 5,000 disposes of unknown keys, 2,000 samples with an out-of-range enum.
 * Properties: another session sharing the tick thread keeps its ticks on time (at most
 * 0.5% of its frame-to-frame gaps + 3 longer than 2 periods, none longer than 10); the
 * server's memory stays bounded; the flood is counted;
 * Cyclone's per-sample warnings are rate-limited; and a finger whose instance is
 * disposed is still lifted (the key is read from the invalid sample).
 * Then a second one disposes 40,000 made-up keys of the finding topic in the same
 * partition while it lives (session 73): each was an instance of the session's finding
 * reader (~1 kB) until its writer went; the server's memory stays bounded while it
 * floods, and the session's next mark is still answered. And a third disposes 2,000 made-up
 * session-request keys: those the server cannot bound (docs/robustness.md), so it counts them and
 * says in its log who writes them.
 *
 * The flooder is a child process (fork before any DDS call) with a participant of
 * its own, as a real attacker would be; the server and the good station run here. */
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../tmpdir.h"
#include "harness.h"
#include "palp_log.h"
#include "validate.h"

#define DOMAIN 170
#define RATE 100.0
#define KEYS 20000
#define DISPOSES 5000
#define BAD_ENUMS 2000
#define FINDING_DISPOSES 40000
#define REQUEST_DISPOSES 2000

/* ---- the flooder (child) ------------------------------------------------------ */

static int flooder(int go_fd, int done_fd) {
  test_init();
  dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  if (pp < 0) return 2;
  /* Session 2's partition: the victim shares session 1's tick thread. Cyclone
   * 0.10 does not check an enum on write, only on receipt: mode = 7 goes out and
   * the server's deserialiser refuses it, with a warning line per sample. */
  dds_entity_t topic = palp_dds_create_topic(pp, PALP_TOPIC_CONTACT);
  char part[64];
  palp_dds_session_partition(2, part, sizeof part);
  dds_entity_t pub = palp_dds_session_publisher(pp, part);
  dds_entity_t w = palp_dds_create_writer(pub, topic, PALP_TOPIC_CONTACT);
  dds_entity_t w2 = w;
  if (w < 0) return 4;
  char c;
  if (read(go_fd, &c, 1) != 1) return 5;
  int64_t t0 = palp_dds_now_ns();
  palp_Contact s;
  memset(&s, 0, sizeof s);
  s.mode = palp_CONTACT_FORCE;
  s.distribution = 2;
  s.vertex = -1;
  s.center = (palp_Vec3){0, 0, 0.04};
  s.force = (palp_Vec3){0, 0, -1};
  for (int i = 0; i < KEYS; i++) { /* distinct keys: (1000 + i, i % 4) */
    s.session_id = 1000u + (uint32_t)i;
    s.finger = (uint8_t)(i % 4);
    s.seq = (uint64_t)i;
    dds_write(w, &s);
    if (i % 200 == 199) test_sleep(0.01); /* ~20,000 keys/s */
  }
  for (int i = 0; i < DISPOSES; i++) { /* a dispose carries only a key: Cyclone does not filter it */
    s.session_id = 500000u + (uint32_t)i;
    s.finger = 0;
    dds_dispose(w, &s);
    if (i % 200 == 199) test_sleep(0.01);
  }
  s.session_id = 2;
  for (int i = 0; i < BAD_ENUMS; i++) {
    s.finger = (uint8_t)(i % 4);
    s.mode = (palp_ContactMode)7;
    dds_write(w2, &s);
    if (i % 200 == 199) test_sleep(0.01);
  }
  fprintf(stderr, "flooder: %d keys, %d disposes, %d bad enums in %.2f s\n", KEYS, DISPOSES, BAD_ENUMS,
          (double)(palp_dds_now_ns() - t0) * 1e-9);
  test_sleep(0.3);
  dds_delete(pp); /* gone: every instance it registered turns not-alive at the server */
  if (write(done_fd, "d", 1) != 1) return 6;
  return 0;
}

/* The second flooder (child): disposes of made-up finding keys into session 2's partition, then
 * stays (its instances are kept while its writer lives) until told to go. */
static int finding_flooder(int go_fd, int done_fd) {
  test_init();
  dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  if (pp < 0) return 2;
  char part[64];
  palp_dds_session_partition(2, part, sizeof part);
  dds_entity_t w = palp_dds_create_writer(palp_dds_session_publisher(pp, part),
                                          palp_dds_create_topic(pp, PALP_TOPIC_FINDING), PALP_TOPIC_FINDING);
  if (w < 0) return 4;
  char c;
  if (read(go_fd, &c, 1) != 1) return 5;
  const int64_t t0 = palp_dds_now_ns();
  palp_Finding f;
  memset(&f, 0, sizeof f);
  int ok = 0;
  for (int i = 0; i < FINDING_DISPOSES; i++) {
    f.session_id = 700000u + (uint32_t)i;
    ok += dds_dispose(w, &f) == 0;
    if (i % 200 == 199) test_sleep(0.01);
  }
  fprintf(stderr, "finding flooder: %d of %d disposes in %.2f s\n", ok, FINDING_DISPOSES,
          (double)(palp_dds_now_ns() - t0) * 1e-9);
  test_sleep(0.5); /* delivered */
  if (write(done_fd, "f", 1) != 1) return 6;
  if (read(go_fd, &c, 1) != 1) return 7; /* alive until the server's memory is read */
  dds_delete(pp);
  return ok == FINDING_DISPOSES ? 0 : 8;
}

/* The third flooder (child): disposes of made-up session-request keys, then stays until told to go. */
static int request_flooder(int go_fd, int done_fd) {
  test_init();
  dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  if (pp < 0) return 2;
  dds_entity_t w = palp_dds_create_writer(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REQUEST),
                                          PALP_TOPIC_SESSION_REQUEST);
  if (w < 0) return 4;
  char c;
  if (read(go_fd, &c, 1) != 1) return 5;
  palp_SessionRequest r;
  memset(&r, 0, sizeof r);
  int ok = 0;
  for (int i = 0; i < REQUEST_DISPOSES; i++) {
    snprintf(r.station_id, sizeof r.station_id, "flood/%d", i);
    ok += dds_dispose(w, &r) == 0;
    if (i % 200 == 199) test_sleep(0.01);
  }
  test_sleep(0.5); /* delivered */
  if (write(done_fd, "r", 1) != 1) return 6;
  if (read(go_fd, &c, 1) != 1) return 7;
  dds_delete(pp);
  return ok == REQUEST_DISPOSES ? 0 : 8;
}

/* ---- the server side (parent) --------------------------------------------------- */

/* [tick threads] The session log's view of what the filters dropped: events and samples. */
static atomic_ullong filtered_events, filtered_samples;
static void on_rejected(void *ctx, uint32_t session_id, palp_srv_reject_reason r, int clamped, uint64_t count) {
  (void)ctx, (void)session_id, (void)clamped;
  if (r != PALP_SRV_REJ_UNKNOWN_SESSION && r != PALP_SRV_REJ_BAD_FINGER) return;
  atomic_fetch_add(&filtered_events, 1);
  atomic_fetch_add(&filtered_samples, count);
}
static const palp_srv_events count_events = {.contact_rejected = on_rejected};

static int log_has(const char *path, const char *needle) {
  FILE *f = fopen(path, "r");
  char buf[2048];
  int found = 0;
  while (f && !found && fgets(buf, sizeof buf, f)) found = strstr(buf, needle) != NULL;
  if (f) fclose(f);
  return found;
}

typedef struct tick_trace {
  uint64_t frames;
  int64_t max_gap_ns, over;     /* largest gap between consecutive frames; gaps > 2 periods */
  uint64_t pairs;
  uint64_t last_frame;
  int64_t last_ns;
} tick_trace;

static void trace_feedback(palp_cli_station *st, tick_trace *t, double seconds, uint64_t *seq) {
  int64_t end = palp_dds_now_ns() + (int64_t)(seconds * 1e9);
  int64_t next_press = 0;
  while (palp_dds_now_ns() < end) {
    if (palp_dds_now_ns() >= next_press) { /* keep pressing 2 N: the world stays awake, feedback every tick */
      test_send_force(st, 0, 2, 25, 90, 2.0, ++*seq);
      next_press = palp_dds_now_ns() + 10000000;
    }
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(st->feedback_r, ptr, &info, 1, 1) > 0) {
      const palp_Feedback *fb = ptr[0];
      if (info.valid_data) {
        t->frames++;
        if (t->last_ns && fb->frame == t->last_frame + 1) {
          int64_t gap = fb->server_time_ns - t->last_ns;
          if (gap > t->max_gap_ns) t->max_gap_ns = gap;
          if (gap > (int64_t)(2e9 / RATE)) t->over++;
          t->pairs++;
        }
        t->last_frame = fb->frame;
        t->last_ns = fb->server_time_ns;
      }
      dds_return_loan(st->feedback_r, ptr, 1);
    }
    test_sleep(0.001);
  }
}

int main(void) {
  int go[2], done[2], fgo[2], fdone[2], rgo[2], rdone[2];
  if (pipe(go) || pipe(done) || pipe(fgo) || pipe(fdone) || pipe(rgo) || pipe(rdone)) return 1;
  pid_t child = fork();
  if (child == 0) {
    close(go[1]);
    close(done[0]);
    _exit(flooder(go[0], done[1]));
  }
  pid_t child2 = fork();
  if (child2 == 0) {
    close(fgo[1]);
    close(fdone[0]);
    _exit(finding_flooder(fgo[0], fdone[1]));
  }
  pid_t child3 = fork();
  if (child3 == 0) {
    close(rgo[1]);
    close(rdone[0]);
    _exit(request_flooder(rgo[0], rdone[1]));
  }
  close(go[0]);
  close(done[1]);
  close(fgo[0]);
  close(fdone[1]);
  close(rgo[0]);
  close(rdone[1]);

  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, RATE);
  cfg.tick_threads = 1; /* both sessions on one tick thread: the flood must not delay the other */
  /* SCHED_FIFO where allowed (root, CAP_SYS_NICE), as a lab server runs (docs/server.md): the
   * gaps then measure the server's own work, not other processes on a shared machine. When
   * refused the server says so and the test runs at normal priority. */
  cfg.tick_priority = 20;
  cfg.dds_log_lines = 5;
  cfg.dds_log_window = 60;
  /* the server's log in a file, for its words about the request flood */
  char log_path[512];
  palp_test_tmp(log_path, sizeof log_path, "palp-flood-XXXXXX");
  const int log_fd = mkstemp(log_path);
  palp_log plog;
  REQUIRE(log_fd >= 0 && palp_log_init(&plog, "palp-server", PALP_LOG_INFO, log_path) == 0, "server log %s", log_path);
  close(log_fd);
  const palp_srv_def def = {.cfg = cfg, .verbose = 1, .log = &plog, .events = &count_events};
  test_server ts = {0};
  test_server_start_def(&ts, &def);
  palp_cli_station good, bad;
  test_station_join(&good, DOMAIN, "good", palp_ROLE_TRAINEE, 1, 0, 1, 0);
  test_station_join(&bad, DOMAIN, "bad", palp_ROLE_TRAINEE, 2, 0, 1, 0);
  REQUIRE(good.session_id == 1 && bad.session_id == 2, "sessions 1 (good) and 2 (victim of the flood) open");
  dds_entity_t guard_r = palp_dds_create_reader(good.pp, good.topic[PALP_TOPIC_SERVER_GUARD], PALP_TOPIC_SERVER_GUARD);

  uint64_t seq = 0;
  tick_trace warm = {0}, flood = {0};
  trace_feedback(&good, &warm, 1.5, &seq); /* settle; also lets the flooder discover us */
  long rss0 = test_rss_kb();
  if (write(go[1], "g", 1) != 1) return 1;
  int64_t t0 = palp_dds_now_ns();
  /* Trace until the flooder is done and gone, and one more second. */
  char c;
  for (;;) {
    trace_feedback(&good, &flood, 0.25, &seq);
    fd_set fds;
    FD_ZERO(&fds);
    FD_SET(done[0], &fds);
    struct timeval tv = {0, 0};
    if (select(done[0] + 1, &fds, NULL, NULL, &tv) > 0) break;
    if (palp_dds_now_ns() - t0 > 30000000000LL) break;
  }
  if (read(done[0], &c, 1) != 1) {
    int st = 0;
    waitpid(child, &st, 0);
    REQUIRE(0, "the flooder finished (exit status %d, signal %d)", WIFEXITED(st) ? WEXITSTATUS(st) : -1,
            WIFSIGNALED(st) ? WTERMSIG(st) : 0);
  }
  trace_feedback(&good, &flood, 1.5, &seq); /* the flooder's participant is gone: its instances go not-alive */
  double secs = (double)(palp_dds_now_ns() - t0) * 1e-9;
  long rss1 = test_rss_kb();
  int status = 0;
  waitpid(child, &status, 0);
  CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0, "flooder exit status %d", WEXITSTATUS(status));

  const double period_ms = 1e3 / RATE;
  CHECK(flood.frames >= 0.8 * secs * RATE, "good session: %llu feedback frames in %.1f s (want >= 80%% of %.0f Hz)",
        (unsigned long long)flood.frames, secs, RATE);
  /* The property: no tick of the other session is delayed by more than one period
   * (its frame-to-frame gap stays <= 2 periods). Before the fix a 39,000-key flood
   * froze the server for 17.7 s. A loaded 2-core machine can stall a thread on its
   * own now and then (the warm-up before the flood saw 26 ms gaps in a full-suite
   * run): up to 0.5 % of gaps plus 3 may exceed 2 periods, none 10. */
  CHECK(flood.pairs > 0 && (uint64_t)flood.over <= flood.pairs / 200 + 3 &&
            flood.max_gap_ns <= (int64_t)(10 * period_ms * 1e6),
        "good session during the flood: largest tick gap %.2f ms (period %.0f ms), %lld of %llu gaps > 2 periods "
        "(want <= 0.5%% + 3, none > 10 periods); before the flood: largest %.2f ms",
        (double)flood.max_gap_ns * 1e-6, period_ms, (long long)flood.over, (unsigned long long)flood.pairs,
        (double)warm.max_gap_ns * 1e-6);
  /* 20,000 keys at ~760 B each (the unfiltered reader's cost) would be ~15 MB. Measured +304..+456 kB.
   * Under AddressSanitizer its allocator and shadow grow by ~4 MB more whatever the code (+4084..+4132 kB,
   * session 51's code and 52's alike, its quarantine off), so scripts/sanitize.sh raises the bound there
   * (PALP_TEST_FLOOD_RSS_KB), still half the unbounded growth. */
  const char *bound_env = getenv("PALP_TEST_FLOOD_RSS_KB");
  const long bound_kb = bound_env && atol(bound_env) > 0 ? atol(bound_env) : 4096;
  CHECK(rss1 - rss0 < bound_kb,
        "server process memory grew by %ld kB over the flood (want < %ld kB; unbounded: ~15,000 kB)", rss1 - rss0,
        bound_kb);

  palp_ServerGuard g;
  memset(&g, 0, sizeof g);
  test_sleep(1.1);
  REQUIRE(test_latest_guard(guard_r, 3.0, &g), "palp_server_guard received");
  CHECK(g.contacts_filtered >= KEYS / 2 && g.contacts_filtered <= KEYS,
        "contacts of other sessions dropped by the filter and counted: %llu of %d sent (best-effort: >= half)",
        (unsigned long long)g.contacts_filtered, KEYS);
  /* Folded in once per tick (session 75), not one call per sample on the tick thread. */
  const uint64_t fe = atomic_load(&filtered_events), fsamp = atomic_load(&filtered_samples);
  CHECK(fsamp == g.contacts_filtered && fe * 10 <= fsamp,
        "the filter's drops reach the session log as %llu events for %llu samples (want the guard's %llu, and at "
        "least 10 samples an event: one per tick, not one per sample)",
        (unsigned long long)fe, (unsigned long long)fsamp, (unsigned long long)g.contacts_filtered);
  CHECK(g.dds_log_printed <= 5 && g.dds_log_suppressed >= BAD_ENUMS / 2,
        "Cyclone warnings: %llu printed (want <= 5 per window), %llu suppressed of %d bad-enum samples sent",
        (unsigned long long)g.dds_log_printed, (unsigned long long)g.dds_log_suppressed, BAD_ENUMS);

  /* Both sessions are alive and the good one still feels its 2 N. */
  int n = 0;
  double f = 0;
  for (int i = 0; i < 10; i++) {
    test_send_force(&good, 0, 2, 25, 90, 2.0, ++seq);
    f = test_last_feedback(&good, 0.02, &n);
  }
  CHECK(fabs(f - 2.0) < 0.2, "good session's feedback %.3f N while pressing 2 N (tolerance 0.2 N)", f);
  /* Disposing the finger's instance lifts it: the server reads the key from the
   * invalid sample (no dds_instance_get_key). */
  palp_Contact key;
  memset(&key, 0, sizeof key);
  key.session_id = good.session_id;
  key.finger = 0;
  dds_dispose(good.contact_w, &key);
  int64_t lift_t0 = palp_dds_now_ns();
  double fl = 1e9;
  uint64_t seen = 0;
  while (palp_dds_now_ns() - lift_t0 < 2000000000LL) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(good.feedback_r, ptr, &info, 1, 1) > 0) {
      const palp_Feedback *fb = ptr[0];
      if (info.valid_data && fb->fingers._length > 0 && fb->fingers._buffer[0].finger == 0) {
        fl = fb->fingers._buffer[0].active ? 1e9 : 0;
        seen++;
      }
      dds_return_loan(good.feedback_r, ptr, 1);
    }
    if (fl == 0) break;
    test_sleep(0.005);
  }
  CHECK(fl == 0, "disposed finger lifted within %.0f ms (feedback says inactive; %llu samples seen)",
        (double)(palp_dds_now_ns() - lift_t0) * 1e-6, (unsigned long long)seen);

  /* The finding disposes: measured while their writer lives (it keeps their instances). Before the
   * server made a flooded finding reader anew (server/server.c, renew_finding_reader), each was an
   * instance of session 2's reader: these 40,000 grew this process by 23,108 kB (2026-12-06, the
   * renewal disabled; 100,000 grew a palp-server by 98 MB); now at most a quarter second of the flood
   * (+4,296..+4,568 kB measured). Under AddressSanitizer (quarantine off) ~4 MB more. */
  const long rss_f0 = test_rss_kb();
  if (write(fgo[1], "g", 1) != 1) return 1;
  const int got_f = read(fdone[0], &c, 1) == 1;
  test_sleep(0.5); /* the main loop takes what arrived last */
  const long rss_f1 = test_rss_kb();
  if (write(fgo[1], "x", 1) != 1) return 1;
  int status2 = 0;
  waitpid(child2, &status2, 0);
  CHECK(got_f && WIFEXITED(status2) && WEXITSTATUS(status2) == 0, "finding flooder exit status %d",
        WEXITSTATUS(status2));
  CHECK(rss_f1 - rss_f0 < 12288,
        "server process memory grew by %ld kB over %d disposes of made-up finding keys, their writer alive (want < 12,288 "
        "kB; unbounded: ~23,000 kB)", rss_f1 - rss_f0, FINDING_DISPOSES);
  /* ... and session 2's reader, made anew, still answers its station's mark (a session without an
   * exercise: refused, with the reason, which is an answer) */
  palp_FindingStatus fst;
  while (palp_cli_station_finding_status(&bad, &fst) == 1) {
  }
  const int mark = palp_cli_station_mark(&bad, (palp_vec3){0, 0, 0.04}, 1.0);
  int answered = 0;
  for (int i = 0; i < 300 && !answered; i++) {
    answered = palp_cli_station_finding_status(&bad, &fst) == 1 && fst.last_mark_id == (uint32_t)mark;
    if (!answered) test_sleep(0.01);
  }
  CHECK(mark > 0 && answered, "session 2's mark %d after the finding flood is answered within 3 s (%s)", mark,
        !answered ? "no answer" : fst.last_accepted ? "accepted" : fst.reason);

  /* The request disposes: counted, and the server's log says who writes them and what to do. */
  if (write(rgo[1], "g", 1) != 1) return 1;
  const int got_r = read(rdone[0], &c, 1) == 1;
  const uint64_t strays = palp_srv_request_strays(ts.srv);
  const int said = log_has(log_path, "a participant without an identity (DDS Security is off) disposed 256 "
                                     "session-request keys that no admitted request holds");
  if (write(rgo[1], "x", 1) != 1) return 1;
  int status3 = 0;
  waitpid(child3, &status3, 0);
  CHECK(got_r && WIFEXITED(status3) && WEXITSTATUS(status3) == 0, "request flooder exit status %d", WEXITSTATUS(status3));
  CHECK(strays == REQUEST_DISPOSES, "%llu of %d disposes of made-up request keys counted (reliable: all)",
        (unsigned long long)strays, REQUEST_DISPOSES);
  CHECK(said, "the server's log names the flood's writer and what to do (%s)", log_path);

  palp_cli_station_leave(&bad);
  palp_cli_station_leave(&good);
  test_sleep(0.2);
  palp_cli_station_close(&bad);
  palp_cli_station_close(&good);
  test_server_stop(&ts);
  palp_log_close(&plog);
  if (!palp_test_failures) unlink(log_path); /* kept for a failed run */
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
