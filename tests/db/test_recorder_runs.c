/* palp-recorder across a server's restart: every sample in the session of the run that produced it
 * (domain 149, of its own).
 * usage: test_db_recorder_runs TMPDIR PALP_RECORDER DDS_CONFIG
 *
 * A restarted server hands out its session ids again, and its first samples can reach the recorder
 * before its OPEN state does: palp-server answers a trainee's JOIN before it writes the state
 * (server/server.c), so the trainee's first contacts race it, and the run's finding status and
 * exercise are written before either. Until the recorder has that state, the id names the old run's
 * session, still open in the recorder (kept 5 s for a lost server to come back); the new run's
 * early samples were logged into it. The test plays two server runs and their stations (each run
 * and each station a participant of its own, as the real ones are) with every rate under the
 * sessions' 100 Hz, so that the recorder keeps every sample that reaches it:
 *  - session 41: run 1 (trainee old41, its station writer W1) sends 20 feedback frames and 20
 *    contacts, then dies (its participant deleted); once the recorder says the state lapsed, run 2's
 *    station (trainee new41, writer W2) sends 30 contacts and run 2 10 feedback frames, all before
 *    run 2's OPEN state; after it 10 more contacts and frames. Run 1's station, not knowing, sends
 *    5 more contacts after run 2's OPEN. Expected: old41 20 contacts and 20 frames, ended `error`
 *    (server restarted); new41 30 + 10 = 40 contacts and 10 + 10 = 20 frames, ended `normal`; W1's
 *    5 late contacts in neither, counted in the recorder's stop line;
 *  - session 42: run 1's server is not yet seen dead (its lease not run out: a lab's 3 s lease is
 *    longer than a restart): run 1's station (W3) sends 10 contacts; run 2's station (W4) 15 before
 *    run 2's OPEN, 5 after. Expected: old42 10 contacts, new42 20;
 *  - session 43: its server's state writer is the one of 42's first run; a participant that never
 *    writes a state of 43 (no run of its server) sends 5 feedback frames for it: held, never logged
 *    in session 43 (0 frames), dropped at the stop, the only held samples dropped (the stop line: 5);
 *  - session 43 again (2026-12-06): its station's writer W6 sends 4 contacts, then a second writer W7 of
 *    it 4 more, held (a station that joined again); no state of 43 comes for seconds (a server at
 *    status_rate_hz 0.1): they are logged 1.5 s after they came (the log says so within 3 s), not at
 *    the next state (at 6 s they were dropped): 8 contacts in s43;
 *  - session 41 again (2026-12-06): while its server has lapsed, run 1's station makes a second contact
 *    writer (W1b) and sends 3 contacts, held; 500 ms later run 2 begins (its states' durations count from
 *    then). W1b's contacts came before run 2's session began: an earlier session's, dropped (counted with
 *    W1's 5 late ones: 8), not logged in new41, and W1b not taken as its station's;
 *  - session 44 (2026-12-06): its first run is 42's (not seen dead) and sends 10 frames; run 2 opens 44
 *    anew; then 3 late frames of run 1's feedback writer come, then run 2's station (W5, a writer new to
 *    44) sends 5 contacts. Expected: old44 10 frames; new44 none of the late 3 (dropped, counted as an
 *    earlier run's: they were held for a state that never comes), and W5's 5 contacts (they were held
 *    behind the late frames, then dropped with them);
 *  - the recorder exits 0.
 * The counts are exact: loopback, best effort but at 12 ms intervals (a lost sample would show as
 * one fewer, never as one in the wrong session). */
#include <math.h>
#include <signal.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "dds_util.h"
#include "sqlite_util.h"
#include "palp.h"
#include "palp_dds.h"

#define DOMAIN 149

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void state(dds_entity_t w, uint32_t id, const char *trainee, int closed, double duration, uint64_t ticks) {
  palp_SessionState ss;
  memset(&ss, 0, sizeof ss);
  ss.session_id = id;
  ss.phantom_id = 1;
  ss.phase = closed ? palp_PHASE_CLOSED : palp_PHASE_OPEN;
  palp_dds_session_partition(id, ss.partition, sizeof ss.partition);
  snprintf(ss.trainee_station, sizeof ss.trainee_station, "host/1/%s", trainee);
  snprintf(ss.trainee_name, sizeof ss.trainee_name, "%s", trainee);
  ss.tick_rate_hz = 100;
  ss.duration = duration;
  ss.ticks = ticks;
  if (closed) snprintf(ss.reason, sizeof ss.reason, "trainee station left");
  dds_write(w, &ss);
}

static void feedback(dds_entity_t w, uint32_t id, uint64_t frame) {
  palp_Feedback fb;
  memset(&fb, 0, sizeof fb);
  palp_FingerFeedback ff = {.finger = 0, .active = true, .force = {0, 0, 0.5}};
  fb.session_id = id;
  fb.frame = frame;
  fb.sim_time = 0.01 * (double)frame;
  fb.fingers._length = fb.fingers._maximum = 1;
  fb.fingers._buffer = &ff;
  dds_write(w, &fb);
}

static void contact(dds_entity_t w, uint32_t id, int k) {
  palp_Contact c;
  memset(&c, 0, sizeof c);
  c.session_id = id;
  c.seq = (uint64_t)k + 1;
  c.mode = palp_CONTACT_FINGER;
  c.center = (palp_Vec3){0, 0, 0.047 - 1e-5 * k};
  c.radius = 0.008;
  dds_write(w, &c);
}

/* A server run: a participant with a state writer and the feedback writer of session 41. */
typedef struct run {
  dds_entity_t pp, state, fb41;
} run;

static run run_start(void) {
  run u;
  u.pp = dds_create_participant(DOMAIN, NULL, NULL);
  char part[64];
  palp_dds_session_partition(41, part, sizeof part);
  u.state = palp_dds_create_writer(u.pp, palp_dds_create_topic(u.pp, PALP_TOPIC_SESSION_STATE), PALP_TOPIC_SESSION_STATE);
  u.fb41 = palp_dds_create_writer(palp_dds_session_publisher(u.pp, part), palp_dds_create_topic(u.pp, PALP_TOPIC_FEEDBACK),
                                  PALP_TOPIC_FEEDBACK);
  return u;
}

/* A server writer of `kind` in session id's partition. */
static dds_entity_t server_writer(dds_entity_t pp, uint32_t id, palp_dds_topic_kind kind) {
  char part[64];
  palp_dds_session_partition(id, part, sizeof part);
  return palp_dds_create_writer(palp_dds_session_publisher(pp, part), palp_dds_create_topic(pp, kind), kind);
}

/* A station: a participant with a contact writer in session id's partition. */
static dds_entity_t station(dds_entity_t *pp, uint32_t id) {
  if (!*pp) *pp = dds_create_participant(DOMAIN, NULL, NULL);
  char part[64];
  palp_dds_session_partition(id, part, sizeof part);
  return palp_dds_create_writer(palp_dds_session_publisher(*pp, part), palp_dds_create_topic(*pp, PALP_TOPIC_CONTACT),
                                PALP_TOPIC_CONTACT);
}

/* 0 once the file holds a line with `what`, -1 after timeout_s. */
static int wait_log(const char *path, const char *what, double timeout_s) {
  for (int i = 0; i < (int)(timeout_s * 100); i++) {
    FILE *f = fopen(path, "r");
    char line[2048];
    int found = 0;
    while (f && !found && fgets(line, sizeof line, f)) found = strstr(line, what) != NULL;
    if (f) fclose(f);
    if (found) return 0;
    sleep_ms(10);
  }
  return -1;
}

/* The number after `key` on the recorder's stop line (-1: no such line). */
static long long stop_count(const char *path, const char *key) {
  FILE *f = fopen(path, "r");
  char line[4096];
  long long v = -1;
  while (f && fgets(line, sizeof line, f)) {
    if (!strstr(line, "stopped;")) continue;
    const char *k = strstr(line, key);
    if (!k) continue;
    /* the count is the number just before the key: "..., N key ..." */
    const char *p = k;
    while (p > line && p[-1] == ' ') p--;
    while (p > line && p[-1] >= '0' && p[-1] <= '9') p--;
    v = strtoll(p, NULL, 10);
  }
  if (f) fclose(f);
  return v;
}

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: %s TMPDIR PALP_RECORDER DDS_CONFIG\n", argv[0]);
    return 2;
  }
  char db[600], logf[600];
  db_fresh_path(db, sizeof db, argv[1], "recorder_runs.db");
  db_fresh_path(logf, sizeof logf, argv[1], "recorder_runs.log");
  REQUIRE(palp_dds_use_config(argv[3]) == 0, "DDS config %s", argv[3]);
  const pid_t pid = start_recorder(argv[2], db, DOMAIN, logf, NULL);
  REQUIRE(pid >= 0, "fork");
  dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  REQUIRE(pp > 0, "participant: %s", dds_strretcode(pp));
  dds_entity_t w_cat = palp_dds_create_writer(pp, palp_dds_create_topic(pp, PALP_TOPIC_CATALOGUE), PALP_TOPIC_CATALOGUE);
  /* run 1 of session 41 (r1), run 1 of session 42 (a participant of its own, a1, never deleted: not
   * yet seen dead), run 1's stations (s1: W1 in 41, W3 in 42) */
  run r1 = run_start();
  dds_entity_t a1 = dds_create_participant(DOMAIN, NULL, NULL);
  dds_entity_t a1_state =
      palp_dds_create_writer(a1, palp_dds_create_topic(a1, PALP_TOPIC_SESSION_STATE), PALP_TOPIC_SESSION_STATE);
  dds_entity_t a1_fb44 = server_writer(a1, 44, PALP_TOPIC_FEEDBACK);
  dds_entity_t s1 = 0, s2 = 0;
  dds_entity_t w1 = station(&s1, 41), w3 = station(&s1, 42), w1b = station(&s1, 41);
  dds_entity_t w6 = station(&s1, 43), w7 = station(&s1, 43);
  const dds_entity_t first[] = {w_cat, r1.state, r1.fb41, a1_state, a1_fb44, w1, w3, w1b, w6, w7};
  for (size_t k = 0; k < sizeof first / sizeof first[0]; k++)
    REQUIRE(wait_matched(first[k], 1, 20) == 0, "writer %zu never matched the recorder", k);

  palp_mesh_def md = palp_mesh_default_def();
  palp_mesh mesh;
  REQUIRE(palp_mesh_create(&md, &mesh) == 0, "mesh");
  palp_Vec3 *rest = calloc((size_t)mesh.vertex_count, sizeof *rest);
  palp_Phantom ph = test_phantom(1, "dome", &md, &mesh, rest, 100);
  dds_write(w_cat, &ph);
  sleep_ms(300);

  /* ---- run 1 ---- */
  state(r1.state, 41, "old41", 0, 0, 0);
  state(a1_state, 42, "old42", 0, 0, 0);
  state(a1_state, 43, "s43", 0, 0, 0);
  state(a1_state, 44, "old44", 0, 0, 0);
  sleep_ms(300);
  for (int k = 0; k < 20; k++) {
    feedback(r1.fb41, 41, (uint64_t)k + 1);
    if (k < 10) feedback(a1_fb44, 44, (uint64_t)k + 1);
    if (k < 4) contact(w6, 43, k);
    contact(w1, 41, k);
    if (k < 10) contact(w3, 42, k);
    sleep_ms(12);
  }
  state(r1.state, 41, "old41", 0, 0.5, 50); /* its 1 Hz refresh */
  state(a1_state, 42, "old42", 0, 0.5, 50);
  state(a1_state, 44, "old44", 0, 0.5, 50);
  sleep_ms(300);
  for (int k = 0; k < 4; k++) contact(w7, 43, 10 + k), sleep_ms(12); /* a second writer: held */
  CHECK(wait_log(logf, "session 43: 4 held samples logged", 3) == 0,
          "session 43's second writer's 4 contacts not released within 3 s, with no state of 43");
  dds_delete(r1.pp); /* session 41's server dies */
  REQUIRE(wait_log(logf, "session 41: its server's state lapsed", 10) == 0,
          "the recorder never said session 41's state lapsed");
  for (int k = 0; k < 3; k++) contact(w1b, 41, 50 + k), sleep_ms(12); /* held: its server lapsed */
  sleep_ms(500);
  const double run2_began = now_s(); /* run 2's sessions' durations count from here */

  /* ---- run 2: its stations' contacts and its frames before its OPEN state ---- */
  run r2 = run_start();
  dds_entity_t w2 = station(&s2, 41), w4 = station(&s2, 42), w5 = station(&s2, 44);
  const dds_entity_t second[] = {r2.state, r2.fb41, w2, w4, w5};
  for (size_t k = 0; k < sizeof second / sizeof second[0]; k++)
    REQUIRE(wait_matched(second[k], 1, 20) == 0, "run 2's writer %zu never matched the recorder", k);
  /* The writers see the recorder's readers before those see them, and a reader drops what a writer it
   * does not know yet sends (measured: the first contact and frame lost without this wait). */
  sleep_ms(500);
  for (int k = 0; k < 30; k++) {
    contact(w2, 41, 100 + k);
    if (k < 10) feedback(r2.fb41, 41, (uint64_t)k + 1);
    if (k < 15) contact(w4, 42, 100 + k);
    sleep_ms(12);
  }
  sleep_ms(300); /* all taken by the recorder before the state is written */
  state(r2.state, 41, "new41", 0, now_s() - run2_began, 40);
  state(r2.state, 42, "new42", 0, now_s() - run2_began, 40);
  state(r2.state, 44, "new44", 0, now_s() - run2_began, 40);
  sleep_ms(300);
  /* run 1's late frames of 44, after run 2's OPEN of it; then run 2's station's first contacts */
  for (int k = 0; k < 3; k++) feedback(a1_fb44, 44, (uint64_t)k + 11), sleep_ms(12);
  sleep_ms(300);
  for (int k = 0; k < 5; k++) contact(w5, 44, k), sleep_ms(12);
  for (int k = 0; k < 10; k++) {
    contact(w2, 41, 130 + k);
    feedback(r2.fb41, 41, (uint64_t)k + 11);
    if (k < 5) contact(w4, 42, 115 + k);
    if (k < 5) contact(w1, 41, 20 + k); /* run 1's station, still writing */
    sleep_ms(12);
  }
  /* a participant that is no run of session 43's server sends frames of it */
  dds_entity_t x = dds_create_participant(DOMAIN, NULL, NULL);
  char p43[64];
  palp_dds_session_partition(43, p43, sizeof p43);
  dds_entity_t x_fb = palp_dds_create_writer(palp_dds_session_publisher(x, p43), palp_dds_create_topic(x, PALP_TOPIC_FEEDBACK),
                                             PALP_TOPIC_FEEDBACK);
  REQUIRE(wait_matched(x_fb, 1, 20) == 0, "the stray feedback writer never matched the recorder");
  sleep_ms(500);
  for (int k = 0; k < 5; k++) feedback(x_fb, 43, (uint64_t)k + 1), sleep_ms(12);
  /* session 45 (session 77): a server stalled past its lease and rediscovered: its state writer is new
   * to the recorder (a new handle) and re-delivers the last state it wrote before the stall (transient-
   * local), the same ticks and duration, before its clock runs on. The same run: one session, ended
   * normal (server_paused's full runs took it for a restart now and then: "server restarted: session 1's
   * state began again (3.945 s, 316 ticks after 3.945 s, 316 ticks)"). */
  dds_entity_t pa = dds_create_participant(DOMAIN, NULL, NULL);
  dds_entity_t pa_state = palp_dds_create_writer(pa, palp_dds_create_topic(pa, PALP_TOPIC_SESSION_STATE),
                                                 PALP_TOPIC_SESSION_STATE);
  REQUIRE(wait_matched(pa_state, 1, 20) == 0, "session 45's first state writer never matched the recorder");
  const double s45_began = now_s() - 0.5;
  state(pa_state, 45, "sid45", 0, 0.5, 50);
  REQUIRE(wait_log(logf, "recording session 45", 5) == 0, "session 45 never recorded");
  dds_delete(pa);
  sleep_ms(1500);
  dds_entity_t pb = dds_create_participant(DOMAIN, NULL, NULL);
  dds_entity_t pb_state = palp_dds_create_writer(pb, palp_dds_create_topic(pb, PALP_TOPIC_SESSION_STATE),
                                                 PALP_TOPIC_SESSION_STATE);
  REQUIRE(wait_matched(pb_state, 1, 20) == 0, "session 45's second state writer never matched the recorder");
  state(pb_state, 45, "sid45", 0, 0.5, 50); /* the last state again */
  sleep_ms(100);
  state(pb_state, 45, "sid45", 0, now_s() - s45_began, 300);
  sleep_ms(300);
  state(r2.state, 41, "new41", 1, now_s() - run2_began, 100);
  state(r2.state, 42, "new42", 1, now_s() - run2_began, 100);
  state(a1_state, 43, "s43", 1, 1.0, 100);
  state(r2.state, 44, "new44", 1, now_s() - run2_began, 100);
  state(pb_state, 45, "sid45", 1, now_s() - s45_began, 400);
  sleep_ms(600);
  int status;
  const int exited_0 = stop_recorder(pid, &status);
  dds_delete(r2.pp);
  dds_delete(a1);
  dds_delete(x);
  dds_delete(pb);
  dds_delete(s1);
  dds_delete(s2);
  dds_delete(pp);
  CHECK(exited_0, "the recorder exits 0 (status %d)", status);

  sqlite3 *h;
  REQUIRE(sqlite3_open(db, &h) == SQLITE_OK, "open");
#define OF(name) " session_id IN (SELECT id FROM session WHERE trainee = '" name "')"
#define CONTACTS(name) "SELECT count(*) FROM contact_input WHERE op IN ('add', 'update') AND" OF(name)
#define FRAMES(name) "SELECT count(*) FROM frame WHERE" OF(name)
  const int64_t c_old41 = db_scalar(h, CONTACTS("old41")), c_new41 = db_scalar(h, CONTACTS("new41"));
  const int64_t f_old41 = db_scalar(h, FRAMES("old41")), f_new41 = db_scalar(h, FRAMES("new41"));
  const int64_t c_old42 = db_scalar(h, CONTACTS("old42")), c_new42 = db_scalar(h, CONTACTS("new42"));
  printf("session 41: run 1 %lld contacts, %lld frames; run 2 %lld contacts, %lld frames; session 42: run 1 %lld "
         "contacts, run 2 %lld\n",
         (long long)c_old41, (long long)f_old41, (long long)c_new41, (long long)f_new41, (long long)c_old42,
         (long long)c_new42);
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'old41' AND end_reason = 'error' AND end_detail "
                     "LIKE 'server restarted%'") == 1 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'new41' AND end_reason = 'normal'") == 1 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'old42' AND end_reason = 'error'") == 1 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'new42' AND end_reason = 'normal'") == 1,
        "each session id logged as two sessions, the first ended error (server restarted), the second normal");
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'sid45'") == 1 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'sid45' AND end_reason = 'normal'") == 1,
        "session 45: its last state re-delivered by a rediscovered writer is the same run: one session, ended normal "
        "(%lld sessions, %lld normal)", (long long)db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'sid45'"),
        (long long)db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'sid45' AND end_reason = 'normal'"));
  CHECK(c_old41 == 20 && f_old41 == 20,
        "session 41's first run keeps its own 20 contacts and 20 frames, none of the new run's (%lld, %lld)",
        (long long)c_old41, (long long)f_old41);
  CHECK(c_new41 == 40 && f_new41 == 20,
        "session 41's new run has its 30 + 10 contacts and 10 + 10 frames, those before its state included "
        "(%lld, %lld)", (long long)c_new41, (long long)f_new41);
  CHECK(c_old42 == 10 && c_new42 == 20,
        "session 42 (its first run not yet seen dead): 10 contacts in the first run's session, 15 + 5 in the "
        "new run's (%lld, %lld)", (long long)c_old42, (long long)c_new42);
  CHECK(db_scalar(h, CONTACTS("s43")) == 8, "session 43: its station's 4 + 4 contacts (%lld)",
        (long long)db_scalar(h, CONTACTS("s43")));
  CHECK(db_scalar(h, FRAMES("s43")) == 0 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 's43' AND end_reason = 'normal'") == 1,
        "session 43: none of the 5 frames from a participant that is none of its server's runs (%lld), ended normal",
        (long long)db_scalar(h, FRAMES("s43")));
  CHECK(db_scalar(h, FRAMES("old44")) == 10 && db_scalar(h, FRAMES("new44")) == 0 &&
            db_scalar(h, CONTACTS("new44")) == 5 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'new44' AND end_reason = 'normal'") == 1,
        "session 44: run 1's 10 frames in its session (%lld), none of its 3 late ones in run 2's (%lld), and run 2's "
        "station's 5 contacts, not held behind them (%lld)",
        (long long)db_scalar(h, FRAMES("old44")), (long long)db_scalar(h, FRAMES("new44")),
        (long long)db_scalar(h, CONTACTS("new44")));
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE end_unix_s IS NULL") == 0, "every session ended");
  sqlite3_close(h);
  const long long ended = stop_count(logf, "samples from a station writer of a session that had ended"),
                  dropped = stop_count(logf, "held samples dropped");
  /* Each server writer's run is looked up once per session it writes in (its session's record then
   * knows it): run 1's feedback writer in old41, run 2's in old41 (its 10 early frames, held) and in
   * new41, the stray writer in 43; run 1's in old44 and (late) in new44; every one of their 78 frames
   * asked the origin cache until 2026-12-06. */
  const long long consults = stop_count(logf, "server samples' writers looked up in the origin cache");
  CHECK(consults == 6, "server writers' runs looked up once per writer and session: 6 (%lld)", consults);
  const long long earlier = stop_count(logf, "samples from an earlier run of their session's server");
  CHECK(earlier == 3, "session 44's 3 late frames of its ended run dropped, counted (%lld)", earlier);
  CHECK(ended == 8 && dropped == 5,
        "run 1's station's 5 contacts after its session ended and W1b's 3 held since before run 2 began are "
        "counted, not logged (%lld); the 5 stray frames "
        "of session 43 counted as held samples dropped, and no other (%lld)", ended, dropped);
  free(rest);
  palp_mesh_destroy(&mesh);
  CHECK_DONE();
}
