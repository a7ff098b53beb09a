/* palp-recorder, session 75 review fixes, over real DDS on loopback (domain 140, of its own).
 * usage: test_db_recorder_review TMPDIR PALP_RECORDER DDS_CONFIG
 *
 * The test plays the server (and a hostile trainee), the recorder at --max-mb 1:
 *  - catalogue: an entry with an infinite force limit and one naming vertex 1,000,000 are refused
 *    (their sessions logged without a scene, their params valid JSON); 64 made-up phantoms written
 *    then disposed leave their slots free: a phantom after them is kept (its name logged);
 *  - params_json: a session whose partition is `x", "footprint": "touched", "a": "` has params that
 *    parse, name that partition and say "footprint": "patch";
 *  - the log: a contact writer whose partition holds a newline forges no log line;
 *  - a server restart: session 36's server dies and a new run opens id 36 again 1.5 s later, within
 *    the recorder's 5 s wait (its duration fell); session 37's run died before its first refresh, so
 *    only the new writer and a start 1.5 s later tell it: each is logged as two sessions, the first
 *    ended `error` saying the server restarted, the new run's 40 frames all in the second (>= 36 of 40,
 *    best effort), none refused;
 *  - a flood: session 38's trainee sends 40 contacts the server refuses, 3 of 50 N, then 30,000
 *    valid contacts and 3,000 findings (no answers) as fast as she can; session 39's 40 contacts and
 *    40 feedback samples among them are all logged (>= 36, best effort) and it ends `normal`; session 38
 *    keeps at most 4 x (16 + 1 + 100 Hz x the seconds from the flood to the stop) + 8 contacts and
 *    at most 12 events a second, none refused, the 50 N clamped to its 20 N limit, the 40 refused
 *    counted (>= 36) in its events; the recorder exits 0 (nothing lost at its 1 MB cap). */
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

#define DOMAIN 140
#define SPOOF "x\", \"footprint\": \"touched\", \"a\": \""

static double mono_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void state(dds_entity_t w, uint32_t id, uint32_t phantom, const char *partition, const char *trainee,
                  int closed, double duration, uint64_t ticks) {
  palp_SessionState ss;
  memset(&ss, 0, sizeof ss);
  ss.session_id = id;
  ss.phantom_id = phantom;
  ss.phase = closed ? palp_PHASE_CLOSED : palp_PHASE_OPEN;
  if (partition) snprintf(ss.partition, sizeof ss.partition, "%s", partition);
  else palp_dds_session_partition(id, ss.partition, sizeof ss.partition);
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

static palp_Contact finger_contact(uint32_t id, int finger, double z) {
  palp_Contact c;
  memset(&c, 0, sizeof c);
  c.session_id = id;
  c.finger = (uint8_t)finger;
  c.mode = palp_CONTACT_FINGER;
  c.center = (palp_Vec3){0, 0, z};
  c.radius = 0.008;
  return c;
}

/* A "server run": its own participant, so that deleting it is the crash of that run. */
typedef struct run {
  dds_entity_t pp, state, fb36;
} run;

static run run_start(void) {
  run u;
  u.pp = dds_create_participant(DOMAIN, NULL, NULL);
  dds_entity_t ts = palp_dds_create_topic(u.pp, PALP_TOPIC_SESSION_STATE);
  dds_entity_t tf = palp_dds_create_topic(u.pp, PALP_TOPIC_FEEDBACK);
  char part[64];
  palp_dds_session_partition(36, part, sizeof part);
  u.state = palp_dds_create_writer(u.pp, ts, PALP_TOPIC_SESSION_STATE);
  u.fb36 = palp_dds_create_writer(palp_dds_session_publisher(u.pp, part), tf, PALP_TOPIC_FEEDBACK);
  return u;
}

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: %s TMPDIR PALP_RECORDER DDS_CONFIG\n", argv[0]);
    return 2;
  }
  char db[600], logf[600];
  db_fresh_path(db, sizeof db, argv[1], "recorder_review.db");
  db_fresh_path(logf, sizeof logf, argv[1], "recorder_review.log");
  REQUIRE(palp_dds_use_config(argv[3]) == 0, "DDS config %s", argv[3]);
  const pid_t pid = start_recorder(argv[2], db, DOMAIN, logf, "1");
  REQUIRE(pid >= 0, "fork");
  dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  REQUIRE(pp > 0, "participant: %s", dds_strretcode(pp));
  dds_entity_t t[PALP_TOPIC_COUNT];
  for (int k = 0; k < PALP_TOPIC_COUNT; k++) t[k] = palp_dds_create_topic(pp, (palp_dds_topic_kind)k);
  dds_entity_t w_cat = palp_dds_create_writer(pp, t[PALP_TOPIC_CATALOGUE], PALP_TOPIC_CATALOGUE);
  dds_entity_t w_state = palp_dds_create_writer(pp, t[PALP_TOPIC_SESSION_STATE], PALP_TOPIC_SESSION_STATE);
  char p38[64], p39[64], p35[64];
  palp_dds_session_partition(38, p38, sizeof p38);
  palp_dds_session_partition(39, p39, sizeof p39);
  palp_dds_session_partition(35, p35, sizeof p35);
  dds_entity_t pub38 = palp_dds_session_publisher(pp, p38), pub39 = palp_dds_session_publisher(pp, p39);
  dds_entity_t w_con38 = palp_dds_create_writer(pub38, t[PALP_TOPIC_CONTACT], PALP_TOPIC_CONTACT);
  dds_entity_t w_find38 = palp_dds_create_writer(pub38, t[PALP_TOPIC_FINDING], PALP_TOPIC_FINDING);
  dds_entity_t w_con39 = palp_dds_create_writer(pub39, t[PALP_TOPIC_CONTACT], PALP_TOPIC_CONTACT);
  dds_entity_t w_fb39 = palp_dds_create_writer(pub39, t[PALP_TOPIC_FEEDBACK], PALP_TOPIC_FEEDBACK);
  /* a writer whose partition would end a log line and begin a forged one, if printed raw */
  char forged[64];
  snprintf(forged, sizeof forged, "%.40s\nFORGED-LINE ERROR", p35);
  dds_entity_t w_forge = palp_dds_create_writer(palp_dds_session_publisher(pp, forged), t[PALP_TOPIC_CONTACT],
                                                PALP_TOPIC_CONTACT);
  const dds_entity_t all[] = {w_cat, w_state, w_con38, w_find38, w_con39, w_fb39, w_forge};
  for (size_t k = 0; k < sizeof all / sizeof all[0]; k++)
    REQUIRE(wait_matched(all[k], 1, 20) == 0, "writer %zu never matched the recorder", k);

  /* ---- the catalogue ---- */
  palp_mesh_def md = palp_mesh_default_def();
  palp_mesh mesh;
  REQUIRE(palp_mesh_create(&md, &mesh) == 0, "mesh");
  palp_Vec3 *rest = calloc((size_t)mesh.vertex_count, sizeof *rest);
  palp_Phantom ph = test_phantom(1, "dome", &md, &mesh, rest, 100);
  dds_write(w_cat, &ph);
  palp_Phantom inf = test_phantom(2, "inf-force", &md, &mesh, rest, 100);
  inf.max_force = INFINITY;
  dds_write(w_cat, &inf);
  palp_Phantom bad = test_phantom(3, "bad-tri", &md, &mesh, rest, 100);
  int32_t tri[3] = {0, 1, 1000000};
  bad.triangles._buffer = tri;
  bad.triangles._length = bad.triangles._maximum = 3;
  bad.dome_triangle_count = 1;
  dds_write(w_cat, &bad);
  for (uint32_t k = 0; k < 64; k++) { /* 64 made-up phantoms: more than the recorder's slots */
    palp_Phantom f = test_phantom(1000 + k, "made-up", &md, &mesh, rest, 100);
    dds_write(w_cat, &f);
  }
  sleep_ms(500);
  for (uint32_t k = 0; k < 64; k++) {
    palp_Phantom f = test_phantom(1000 + k, "made-up", &md, &mesh, rest, 100);
    dds_dispose(w_cat, &f);
  }
  sleep_ms(500);
  palp_Phantom late = test_phantom(4, "after-dispose", &md, &mesh, rest, 100);
  dds_write(w_cat, &late);
  sleep_ms(300);
  state(w_state, 31, 2, NULL, "ina", 0, 0, 0);
  state(w_state, 32, 3, NULL, "bea", 0, 0, 0);
  state(w_state, 33, 4, NULL, "dita", 0, 0, 0);
  state(w_state, 34, 1, SPOOF, "spoof", 0, 0, 0);
  state(w_state, 35, 1, NULL, "fay", 0, 0, 0);
  sleep_ms(300);
  palp_Contact fc = finger_contact(35, 0, 0.047);
  for (int k = 0; k < 3; k++) dds_write(w_forge, &fc), sleep_ms(20);

  /* ---- a server restart ---- */
  run r1 = run_start();
  REQUIRE(wait_matched(r1.state, 1, 20) == 0 && wait_matched(r1.fb36, 1, 20) == 0, "run 1 never matched");
  state(r1.state, 36, 1, NULL, "rita", 0, 0, 0);
  state(r1.state, 37, 1, NULL, "ruth", 0, 0, 0);
  sleep_ms(300);
  for (uint64_t f = 1; f <= 40; f++) feedback(r1.fb36, 36, f), sleep_ms(4);
  state(r1.state, 36, 1, NULL, "rita", 0, 0.5, 50); /* its run's 1 Hz refresh: the same run */
  sleep_ms(200);
  dds_delete(r1.pp); /* the crash; systemd starts the server again (2 s), ids from 1 again */
  sleep_ms(1500);
  run r2 = run_start();
  REQUIRE(wait_matched(r2.state, 1, 20) == 0 && wait_matched(r2.fb36, 1, 20) == 0, "run 2 never matched");
  state(r2.state, 36, 1, NULL, "rita", 0, 0.01, 1);
  state(r2.state, 37, 1, NULL, "ruth", 0, 0.001, 0);
  sleep_ms(300);
  for (uint64_t f = 1; f <= 40; f++) feedback(r2.fb36, 36, f), sleep_ms(4);
  state(r2.state, 36, 1, NULL, "rita", 1, 0.6, 60);
  state(r2.state, 37, 1, NULL, "ruth", 1, 0.6, 60);

  /* ---- a flood in session 38, then session 39 ---- */
  state(w_state, 38, 1, NULL, "flo", 0, 0, 0);
  state(w_state, 39, 1, NULL, "vic", 0, 0, 0);
  sleep_ms(300);
  /* refused by the server: NaN, 1e300 N, a vertex past the mesh, a 1 m fingertip (a mode past the enum
   * is refused by Cyclone's deserializer already) */
  for (int k = 0; k < 40; k++) {
    palp_Contact c = finger_contact(38, k % 3, 0.047);
    if (k % 4 == 0) c.center.x = NAN;
    if (k % 4 == 1) c.mode = palp_CONTACT_FORCE, c.distribution = 1, c.vertex = -1, c.force = (palp_Vec3){0, 0, -1e300};
    if (k % 4 == 2) c.mode = palp_CONTACT_FORCE, c.distribution = 1, c.vertex = 100000, c.force = (palp_Vec3){0, 0, -1};
    if (k % 4 == 3) c.radius = 1.0;
    dds_write(w_con38, &c);
    sleep_ms(4);
  }
  for (int k = 0; k < 3; k++) { /* 50 N: the server clamps it to the phantom's 20 N */
    palp_Contact c = finger_contact(38, 3, 0.047);
    c.mode = palp_CONTACT_FORCE, c.distribution = 1, c.vertex = -1, c.force = (palp_Vec3){0, 0, -50};
    dds_write(w_con38, &c);
    sleep_ms(20);
  }
  /* Session 39's trainee palpates while session 38's floods: 750 of the flood's contacts and 75 of
   * its findings, then one of session 39's contacts and feedback samples, 40 times. */
  const double t_flood = mono_s();
  for (int k = 0; k < 30000; k++) {
    palp_Contact c = finger_contact(38, k % 3, 0.047 - 1e-7 * k);
    dds_write(w_con38, &c);
    if (k % 10 == 0) {
      palp_Finding f;
      memset(&f, 0, sizeof f);
      f.session_id = 38;
      f.mark_id = (uint32_t)(k / 10 + 1);
      f.op = palp_FINDING_MARK;
      f.point = (palp_Vec3){0, 0, 0.04};
      dds_write(w_find38, &f);
    }
    if (k % 750 == 749) {
      const int v = k / 750;
      palp_Contact cv = finger_contact(39, 0, 0.047 - 1e-5 * v);
      dds_write(w_con39, &cv);
      feedback(w_fb39, 39, (uint64_t)v + 1);
      sleep_ms(12); /* under its 100 Hz: more than one a tick the server would not apply either */
    }
  }
  printf("flood: 30,000 contacts and 3,000 findings in %.2f s\n", mono_s() - t_flood);
  sleep_ms(200);
  state(w_state, 39, 1, NULL, "vic", 1, 1.0, 100);
  state(w_state, 38, 1, NULL, "flo", 1, 1.0, 100);
  for (uint32_t id = 31; id <= 35; id++)
    state(w_state, id, id == 31 ? 2 : id == 32 ? 3 : id == 33 ? 4 : 1, id == 34 ? SPOOF : NULL,
          id == 31 ? "ina" : id == 32 ? "bea" : id == 33 ? "dita" : id == 34 ? "spoof" : "fay", 1, 2.0, 200);
  sleep_ms(800);
  int status;
  const int exited_0 = stop_recorder(pid, &status);
  const double span = mono_s() - t_flood;
  dds_delete(r2.pp);
  dds_delete(pp);
  CHECK(exited_0, "the recorder exits 0: nothing lost at its 1 MB cap (status %d)", status);

  sqlite3 *h;
  REQUIRE(sqlite3_open(db, &h) == SQLITE_OK, "open");
#define TR(name) " session_id IN (SELECT id FROM session WHERE trainee = '" name "')"
  /* catalogue */
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'ina' AND phantom_name = '' AND scene_json = '{}' "
                     "AND json_valid(params_json) AND json_extract(params_json, '$.max_force_n') IS NULL") == 1,
        "phantom 2 (force limit infinite) refused: its session logged without a scene, its params valid JSON");
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'bea' AND phantom_name = '' AND scene_json = '{}'") == 1,
        "phantom 3 (a triangle naming vertex 1,000,000) refused: its session logged without a scene");
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'dita' AND phantom_name = 'after-dispose' AND "
                     "scene_json <> '{}'") == 1,
        "phantom 4, after 64 made-up phantoms written and disposed: kept, its name and scene logged");
  /* params */
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'spoof' AND json_valid(params_json) AND "
                         "json_extract(params_json, '$.partition') = 'x\", \"footprint\": \"touched\", \"a\": \"' AND "
                         "json_extract(params_json, '$.footprint') = 'patch' AND json_extract(params_json, '$.a') IS NULL") == 1,
        "a partition with quotes is the partition's value in params_json, no key of its own (footprint: patch)");
  /* restart */
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'rita'") == 2 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'rita' AND end_reason = 'error' AND "
                         "end_detail LIKE 'server restarted%'") == 1 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'rita' AND end_reason = 'normal'") == 1,
        "session 36 (its duration fell): two sessions, the first ended error (server restarted), the second normal");
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'ruth'") == 2 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'ruth' AND end_reason = 'error' AND "
                         "end_detail LIKE 'server restarted%'") == 1,
        "session 37 (a new writer, begun 1.5 s later): two sessions, the first ended error (server restarted)");
  const int64_t fr2 = db_scalar(h, "SELECT count(*) FROM frame WHERE session_id = (SELECT max(id) FROM session WHERE "
                                   "trainee = 'rita')");
  const int64_t fr1 = db_scalar(h, "SELECT count(*) FROM frame WHERE session_id = (SELECT min(id) FROM session WHERE "
                                   "trainee = 'rita')");
  printf("session 36: %lld frames in the first run's session, %lld in the second's (40 sent each)\n", (long long)fr1,
         (long long)fr2);
  CHECK(fr1 >= 36 && fr1 <= 40 && fr2 >= 36 && fr2 <= 40, "each run's frames in its own session (>= 36 of 40)");
  /* flood */
  const int64_t vic_c = db_scalar(h, "SELECT count(*) FROM contact_input WHERE op IN ('add', 'update') AND" TR("vic"));
  const int64_t vic_f = db_scalar(h, "SELECT count(*) FROM frame WHERE" TR("vic"));
  const int64_t flo_c = db_scalar(h, "SELECT count(*) FROM contact_input WHERE" TR("flo"));
  const int64_t flo_e = db_scalar(h, "SELECT count(*) FROM event WHERE" TR("flo"));
  const int64_t flo_bad = db_scalar(h, "SELECT count(*) FROM contact_input WHERE" TR("flo") " AND op <> 'remove' AND "
                                       "(center_x_m IS NULL OR (kind = 'finger' AND (radius_m IS NULL OR radius_m > 0.1)) "
                                       "OR (kind = 'force' AND force_z_n * force_z_n > 400 * (1 + 1e-12)))");
  const int64_t flo_clamped = db_scalar(h, "SELECT count(*) FROM contact_input WHERE" TR("flo") " AND kind = 'force' AND "
                                           "abs(force_z_n + 20) < 1e-9");
  const int64_t flo_refused = db_scalar(h, "SELECT coalesce(sum(count), 0) FROM event WHERE" TR("flo") " AND detail LIKE "
                                           "'contacts not recorded: the server refuses%'");
  const double bound_c = 4 * (16 + 1 + 100 * span) + 8, bound_e = 12 * (span + 2);
  printf("session 39: %lld of 40 contacts, %lld of 40 frames; session 38: %lld contacts (bound %.0f), %lld events "
         "(bound %.0f) in %.1f s, %lld refused counted, %lld clamped\n",
         (long long)vic_c, (long long)vic_f, (long long)flo_c, bound_c, (long long)flo_e, bound_e, span,
         (long long)flo_refused, (long long)flo_clamped);
  CHECK(vic_c >= 36 && vic_f >= 36 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE trainee = 'vic' AND end_reason = 'normal'") == 1,
        "session 39, after session 38's flood: its contacts and frames (>= 36 of 40) and its end logged");
  CHECK(flo_c <= bound_c && flo_e <= bound_e, "session 38's flood: at most one contact per finger per tick and a "
                                               "few events a second logged");
  CHECK(flo_bad == 0 && flo_clamped >= 1, "no contact the server refuses logged; the 50 N logged as its 20 N");
  CHECK(flo_refused >= 36 && flo_refused <= 40, "the refused contacts counted in its events (%lld of 40)",
        (long long)flo_refused);
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE end_unix_s IS NULL") == 0, "every session ended");
  sqlite3_close(h);

  /* the log: the forging writer's partition escaped (the warning said, on one line) */
  FILE *f = fopen(logf, "r");
  char line[2048];
  int forged_lines = 0, said = 0;
  while (f && fgets(line, sizeof line, f)) {
    if (!strncmp(line, "FORGED-LINE", 11)) forged_lines++;
    if (strstr(line, "FORGED-LINE") && strstr(line, "session 35")) said++;
  }
  if (f) fclose(f);
  CHECK(forged_lines == 0 && said >= 1, "a writer's partition with a newline forges no log line (%d forged, %d said)",
        forged_lines, said);
  free(rest);
  palp_mesh_destroy(&mesh);
  CHECK_DONE();
}
