/* palp-recorder logs an exercise session as the server's own log has it (session 60; docs/db.md,
 * "palp-recorder"), over real DDS on loopback (domain 183, of its own). The test plays the server.
 * usage: test_db_recorder_exercise TMPDIR PALP_RECORDER DDS_CONFIG EXERCISE_JSON PALP_REVIEW
 *
 * Session 8 (exercise "teaching", the shipped file's text): its palp_session_exercise sample comes
 * before its OPEN state (the two topics race), then the trainee's findings and the server's answers
 * in the orders the wire allows:
 *   mark 1 answered accepted; mark 2 answered refused ("too close to mark 1"); marks 3 and 4 with
 *   only 4's answer seen (keep-last 1 replaced 3's); 5's answer before its mark; the withdrawal of
 *   mark 1, accepted.
 * Local models of finger 0 (an 8 mm fingertip) at frames 1..60 of a 250 Hz world, frame 30's force
 * NaN; the debrief (level lesions, mark 4 found lesion 1, lesion 2 missed); the CLOSED state.
 * Session 9: its exercise is not JSON (refused, said and counted; the session is logged without one).
 * Session 10: its CLOSED state comes 0.3 s before its debrief (the recorder waits for it).
 * Session 11: open 12.5 s when the recorder first sees it, still open when the recorder is stopped.
 * Checked in the file, against values written here by hand:
 *  - session 8's exercise is the text sent, byte for byte; session 9 has none, and the recorder's
 *    stop line counts 1 exercise refused;
 *  - findings 1 (mark), 4 (mark), 5 (mark), 1 (withdraw), in that order, with the points sent (1e-12);
 *  - a reject event "finding 2 refused: too close to mark 1" and one "finding 3 (mark) not logged:
 *    the recorder did not see the server's answer";
 *  - finger samples every 3rd frame (round(250 / 100), the server's rule): frames 3, 6, ..., 60
 *    but 30 (NaN), 19 rows, radius 0.008 m, device and force as sent (1e-12), no triangles;
 *  - the debrief lines, "told at level lesions: found 1 of 2 lesions; marks standing 2, near no
 *    lesion 1, duplicates 0; found by marks 4 0" for session 8 and "told at level none: marks
 *    standing 0" for session 10, whose session ended normally after it;
 *  - session 11 ended `error`, "palp-recorder stopped while the session ran (...)", and said; its
 *    params say "recorded_from_s": 12.5 (session 8's nothing) and `palp-review show` says the
 *    recorder joined 12.5 s into it. */
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

#define DOMAIN 183
#define PHANTOM 14u

static char *read_file(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  char *buf = calloc(1, 65536);
  size_t n = buf ? fread(buf, 1, 65535, f) : 0;
  fclose(f);
  if (buf && n == 0) {
    free(buf);
    return NULL;
  }
  return buf;
}

/* A session's writers in its partition. */
typedef struct sess {
  uint32_t id;
  dds_entity_t pub, contact, local_model, finding, status, debrief, finger_sample;
} sess;

static void sess_open(dds_entity_t pp, const dds_entity_t *t, uint32_t id, sess *s) {
  char part[64];
  palp_dds_session_partition(id, part, sizeof part);
  s->id = id;
  s->pub = palp_dds_session_publisher(pp, part);
  s->contact = palp_dds_create_writer(s->pub, t[PALP_TOPIC_CONTACT], PALP_TOPIC_CONTACT);
  s->local_model = palp_dds_create_writer(s->pub, t[PALP_TOPIC_LOCAL_MODEL], PALP_TOPIC_LOCAL_MODEL);
  s->finding = palp_dds_create_writer(s->pub, t[PALP_TOPIC_FINDING], PALP_TOPIC_FINDING);
  s->status = palp_dds_create_writer(s->pub, t[PALP_TOPIC_FINDING_STATUS], PALP_TOPIC_FINDING_STATUS);
  s->debrief = palp_dds_create_writer(s->pub, t[PALP_TOPIC_DEBRIEF], PALP_TOPIC_DEBRIEF);
  s->finger_sample = palp_dds_create_writer(s->pub, t[PALP_TOPIC_FINGER_SAMPLE], PALP_TOPIC_FINGER_SAMPLE);
}

/* A finger sample of session s's finger 0 as a server writes it (session 71), in contact, touching
 * the n triangles in tri. */
static void finger_sample(const sess *s, uint64_t frame, double fz, const int32_t *tri, uint32_t n) {
  palp_FingerSample m;
  memset(&m, 0, sizeof m);
  m.session_id = s->id;
  m.finger = 0;
  m.frame = frame;
  m.time = 0.004 * (double)frame;
  m.radius = 0.008;
  m.in_contact = true;
  m.device = (palp_Vec3){0, 0, 0.045};
  m.proxy = (palp_Vec3){0, 0, 0.047};
  m.force = (palp_Vec3){0, 0, fz};
  m.point = (palp_Vec3){0, 0, 0.039};
  m.area = 1e-5;
  m.triangles._buffer = (int32_t *)tri;
  m.triangles._length = m.triangles._maximum = n;
  dds_write(s->finger_sample, &m);
}

static void state_at(dds_entity_t w, uint32_t id, int closed, double duration) {
  palp_SessionState ss;
  memset(&ss, 0, sizeof ss);
  ss.session_id = id;
  ss.phantom_id = PHANTOM;
  ss.phase = closed ? palp_PHASE_CLOSED : palp_PHASE_OPEN;
  palp_dds_session_partition(id, ss.partition, sizeof ss.partition);
  snprintf(ss.trainee_station, sizeof ss.trainee_station, "host/77/trainee:nina");
  snprintf(ss.trainee_name, sizeof ss.trainee_name, "nina");
  ss.tick_rate_hz = 250;
  ss.duration = duration;
  if (closed) snprintf(ss.reason, sizeof ss.reason, "trainee station left");
  dds_write(w, &ss);
}

static void state(dds_entity_t w, uint32_t id, int closed) { state_at(w, id, closed, 0.0); }

static void exercise(dds_entity_t w, uint32_t id, const char *name, const char *json) {
  palp_SessionExercise *m = calloc(1, sizeof *m);
  m->session_id = id;
  m->phantom_id = PHANTOM;
  snprintf(m->name, sizeof m->name, "%s", name);
  snprintf(m->json, sizeof m->json, "%s", json);
  dds_write(w, m);
  free(m);
}

static void finding(const sess *s, uint32_t mark, int withdraw, double x) {
  palp_Finding f = {.session_id = s->id,
                    .mark_id = mark,
                    .op = withdraw ? palp_FINDING_WITHDRAW : palp_FINDING_MARK,
                    .point = {x, 0.001, 0.039},
                    .time = 0.5};
  dds_write(s->finding, &f);
}

static void answer(const sess *s, uint32_t mark, int accepted, const char *reason, uint32_t marks) {
  palp_FindingStatus st;
  memset(&st, 0, sizeof st);
  st.session_id = s->id;
  st.marks = marks;
  st.last_mark_id = mark;
  st.last_accepted = accepted != 0;
  snprintf(st.reason, sizeof st.reason, "%s", reason);
  st.time_left = 100;
  dds_write(s->status, &st);
}

int main(int argc, char **argv) {
  if (argc < 6) {
    fprintf(stderr, "usage: %s TMPDIR PALP_RECORDER DDS_CONFIG EXERCISE_JSON PALP_REVIEW\n", argv[0]);
    return 2;
  }
  char db[600], log[600];
  db_fresh_path(db, sizeof db, argv[1], "recorder-exercise.db");
  snprintf(log, sizeof log, "%s/recorder-exercise.log", argv[1]);
  REQUIRE(palp_dds_use_config(argv[3]) == 0, "DDS config %s", argv[3]);
  char *json = read_file(argv[4]);
  REQUIRE(json != NULL, "read %s", argv[4]);

  const pid_t pid = start_recorder(argv[2], db, DOMAIN, log, NULL);
  REQUIRE(pid >= 0, "fork");

  dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  REQUIRE(pp > 0, "participant: %s", dds_strretcode(pp));
  dds_entity_t t[PALP_TOPIC_COUNT];
  for (int k = 0; k < PALP_TOPIC_COUNT; k++) t[k] = palp_dds_create_topic(pp, (palp_dds_topic_kind)k);
  dds_entity_t w_cat = palp_dds_create_writer(pp, t[PALP_TOPIC_CATALOGUE], PALP_TOPIC_CATALOGUE);
  dds_entity_t w_state = palp_dds_create_writer(pp, t[PALP_TOPIC_SESSION_STATE], PALP_TOPIC_SESSION_STATE);
  dds_entity_t w_ex = palp_dds_create_writer(pp, t[PALP_TOPIC_SESSION_EXERCISE], PALP_TOPIC_SESSION_EXERCISE);
  sess s8, s9, s10;
  sess_open(pp, t, 8, &s8);
  sess_open(pp, t, 9, &s9);
  sess_open(pp, t, 10, &s10);
  const dds_entity_t all[] = {w_cat, w_state, w_ex, s8.contact, s8.local_model, s8.finding, s8.status, s8.debrief,
                              s10.debrief, s10.contact, s10.local_model, s10.finger_sample};
  for (size_t k = 0; k < sizeof all / sizeof all[0]; k++)
    REQUIRE(wait_matched(all[k], 1, 20) == 0, "writer %zu never matched the recorder", k);

  palp_mesh_def md = palp_mesh_default_def();
  palp_mesh mesh;
  REQUIRE(palp_mesh_create(&md, &mesh) == 0, "mesh");
  palp_Vec3 *rest = calloc((size_t)mesh.vertex_count, sizeof *rest);
  palp_Phantom ph = test_phantom(PHANTOM, "Teaching", &md, &mesh, rest, 250);
  /* its triangles, as the server's catalogue sends them: the recorder's footprint patches need them */
  int32_t *tri = calloc((size_t)mesh.triangle_count * 3, sizeof *tri);
  REQUIRE(tri != NULL, "triangles");
  for (int t = 0; t < mesh.triangle_count; t++)
    for (int v = 0; v < 3; v++) tri[3 * t + v] = mesh.tri[t][v];
  ph.triangles._length = ph.triangles._maximum = (uint32_t)mesh.triangle_count * 3;
  ph.triangles._buffer = tri;
  REQUIRE(dds_write(w_cat, &ph) == 0, "catalogue");
  sleep_ms(200);

  /* session 8: its exercise first, then its OPEN state */
  exercise(w_ex, 8, "teaching", json);
  sleep_ms(200);
  state(w_state, 8, 0);
  /* session 9: an exercise that is not one */
  exercise(w_ex, 9, "teaching", "{\"name\": \"teaching\", \"lesions\": [");
  state(w_state, 9, 0);
  /* session 10: a well-formed exercise */
  exercise(w_ex, 10, "teaching", json);
  state(w_state, 10, 0);
  /* session 11: still running when the recorder stops, and open 12.5 s when the recorder first saw it */
  state_at(w_state, 11, 0, 12.5);
  sleep_ms(300);

  /* session 8's fingertip: a contact (its radius), then local models of frames 1..60 */
  palp_Contact c;
  memset(&c, 0, sizeof c);
  c.session_id = 8;
  c.finger = 0;
  c.seq = 1;
  c.mode = palp_CONTACT_FINGER;
  c.center = (palp_Vec3){0, 0, 0.045};
  c.radius = 0.008;
  dds_write(s8.contact, &c);
  sleep_ms(100);
  for (int k = 1; k <= 60; k++) {
    palp_LocalModel m;
    memset(&m, 0, sizeof m);
    m.session_id = 8;
    m.finger = 0;
    m.frame = (uint64_t)k;
    m.time = 0.004 * k;
    m.period = 0.004;
    m.in_contact = true;
    m.device = (palp_Vec3){0.0001 * k, 0, 0.045};
    m.proxy = (palp_Vec3){0.0001 * k, k > 30 ? 0.0013 : 0, 0.047}; /* off the mirror plane y = 0: no ties */
    m.force = (palp_Vec3){0, 0, k == 30 ? NAN : 0.01 * k};
    m.point = (palp_Vec3){0.0001 * k, 0, 0.039};
    m.area = 1e-5;
    m.triangles = k > 30 ? 6 : 0; /* from frame 31 on, 6 triangles touched: a patch of 6 logged */
    dds_write(s8.local_model, &m);
    sleep_ms(2);
  }
  sleep_ms(200);

  /* session 10's fingertip from a server that writes finger samples (session 71): a local model at
   * frame 3 (logged, as no finger sample has come yet), then finger samples: frames 6 and 9 logged
   * with their triangles; 12 with a NaN force, 15 naming a triangle past the mesh's and 9 again
   * (not after the last) refused; 18 logged; and a local model at frame 21, no longer logged */
  c.session_id = 10;
  dds_write(s10.contact, &c);
  sleep_ms(100);
  {
    palp_LocalModel m;
    memset(&m, 0, sizeof m);
    m.session_id = 10;
    m.frame = 3;
    m.time = 0.012;
    m.period = 0.004;
    m.in_contact = true;
    m.proxy = (palp_Vec3){0, 0, 0.047};
    m.device = m.point = m.proxy;
    m.area = 1e-5;
    dds_write(s10.local_model, &m);
    sleep_ms(50);
    const int32_t a[] = {0, 1, 2}, b[] = {5}, off[] = {4, mesh.triangle_count}, d[] = {7, 8};
    finger_sample(&s10, 6, 0.5, a, 3);
    finger_sample(&s10, 9, 0.6, b, 1);
    finger_sample(&s10, 12, NAN, b, 1);
    finger_sample(&s10, 15, 0.7, off, 2);
    finger_sample(&s10, 9, 0.6, d, 2);
    finger_sample(&s10, 18, 0.8, d, 2);
    sleep_ms(50);
    m.frame = 21;
    dds_write(s10.local_model, &m);
  }
  sleep_ms(200);

  /* session 8's findings and the server's answers */
  finding(&s8, 1, 0, 0.001);
  sleep_ms(50);
  answer(&s8, 1, 1, "", 1);
  sleep_ms(100);
  finding(&s8, 2, 0, 0.0012);
  sleep_ms(50);
  answer(&s8, 2, 0, "too close to mark 1", 1);
  sleep_ms(100);
  finding(&s8, 3, 0, 0.003);
  finding(&s8, 4, 0, 0.004);
  sleep_ms(50);
  answer(&s8, 4, 1, "", 3); /* 3's answer was replaced before it went out */
  sleep_ms(100);
  answer(&s8, 5, 1, "", 4); /* the answer first */
  sleep_ms(50);
  finding(&s8, 5, 0, 0.005);
  sleep_ms(100);
  finding(&s8, 1, 1, 0);
  sleep_ms(50);
  answer(&s8, 1, 1, "", 3);
  sleep_ms(200);

  /* session 8's debrief, then its CLOSED state (as the server writes them) */
  palp_DebriefLesion les[2] = {{.point = {0.01, 0, 0.038}, .depth = 0.01, .diameter = 0.015, .found_by = 4},
                               {.point = {-0.01, 0, 0.038}, .depth = 0.01, .diameter = 0.015, .found_by = 0}};
  palp_Debrief d;
  memset(&d, 0, sizeof d);
  d.session_id = 8;
  d.level = palp_DEBRIEF_LESIONS;
  d.lesions = 2;
  d.found = 1;
  d.marks = 2;
  d.false_marks = 1;
  d.lesion._length = d.lesion._maximum = 2;
  d.lesion._buffer = les;
  snprintf(d.reason, sizeof d.reason, "trainee station left");
  REQUIRE(dds_write(s8.debrief, &d) == 0, "debrief 8");
  state(w_state, 8, 1);
  state(w_state, 9, 1);
  /* session 10: its CLOSED state first, its debrief 0.3 s later */
  state(w_state, 10, 1);
  sleep_ms(300);
  palp_Debrief d10;
  memset(&d10, 0, sizeof d10);
  d10.session_id = 10;
  d10.level = palp_DEBRIEF_NONE;
  REQUIRE(dds_write(s10.debrief, &d10) == 0, "debrief 10");
  sleep_ms(1500);
  int status;
  CHECK(stop_recorder(pid, &status), "recorder exit status %d", status);
  dds_delete(pp);

  sqlite3 *h;
  REQUIRE(sqlite3_open(db, &h) == SQLITE_OK, "open");
  const char *uid8 = "(SELECT id FROM session WHERE uid LIKE 'dds-14-8-%')";
  char sql[1024];
  sqlite3_stmt *q;
  int same = 0;
  snprintf(sql, sizeof sql, "SELECT exercise_name, exercise_json FROM session_exercise WHERE session_id = %s", uid8);
  if (sqlite3_prepare_v2(h, sql, -1, &q, NULL) == SQLITE_OK && sqlite3_step(q) == SQLITE_ROW)
    same = !strcmp((const char *)sqlite3_column_text(q, 0), "teaching") &&
           !strcmp((const char *)sqlite3_column_text(q, 1), json);
  sqlite3_finalize(q);
  CHECK(same, "session 8's exercise, sent before its session opened, is logged byte for byte");
  CHECK(db_scalar(h, "SELECT count(*) FROM session_exercise e JOIN session s ON s.id = e.session_id "
                     "WHERE s.uid LIKE 'dds-14-9-%'") == 0 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE uid LIKE 'dds-14-9-%'") == 1,
        "session 9 is logged without its malformed exercise");
  static char text[65536];
  FILE *lf = fopen(log, "r");
  size_t n = lf ? fread(text, 1, sizeof text - 1, lf) : 0;
  if (lf) fclose(lf);
  text[n] = 0;
  CHECK(strstr(text, "session 9: its exercise \"teaching\" refused: ") != NULL &&
            strstr(text, ", 1 exercises refused") != NULL,
        "the recorder says why session 9's exercise was refused, and counts it");

  /* findings: 1, 4, 5 marked and 1 withdrawn, in that order, at the points sent */
  snprintf(sql, sizeof sql,
           "SELECT group_concat(mark_id || ':' || op, ' ') FROM (SELECT mark_id, op FROM finding WHERE session_id = %s "
           "ORDER BY id)",
           uid8);
  char got[256] = "";
  if (sqlite3_prepare_v2(h, sql, -1, &q, NULL) == SQLITE_OK && sqlite3_step(q) == SQLITE_ROW && sqlite3_column_text(q, 0))
    snprintf(got, sizeof got, "%s", (const char *)sqlite3_column_text(q, 0));
  sqlite3_finalize(q);
  CHECK(!strcmp(got, "1:mark 4:mark 5:mark 1:withdraw"), "findings as the server answered them: %s", got);
  snprintf(sql, sizeof sql,
           "SELECT count(*) FROM finding WHERE session_id = %s AND op = 'mark' AND abs(point_x_m - mark_id * 0.001) < 1e-12 "
           "AND abs(point_y_m - 0.001) < 1e-12 AND abs(point_z_m - 0.039) < 1e-12",
           uid8);
  CHECK(db_scalar(h, sql) == 3, "the marks' points as sent");
  snprintf(sql, sizeof sql,
           "SELECT count(*) FROM event WHERE session_id = %s AND kind = 'reject' AND detail IN "
           "('finding 2 refused: too close to mark 1', "
           "'finding 3 (mark) not logged: the recorder did not see the server''s answer')",
           uid8);
  CHECK(db_scalar(h, sql) == 2, "mark 2's refusal and mark 3's unseen answer are reject events");

  /* finger samples: every 3rd frame but the NaN one */
  snprintf(sql, sizeof sql,
           "SELECT count(*) FROM finger_sample WHERE session_id = %s AND frame %% 3 = 0 AND frame <> 30 AND "
           "radius_m = 0.008 AND abs(device_x_m - 0.0001 * frame) < 1e-12 AND abs(force_z_n - 0.01 * frame) < 1e-12 "
           "AND in_contact = 1 AND area_m2 = 1e-5 AND (triangles IS NULL) = (frame <= 30)",
           uid8);
  const int64_t good = db_scalar(h, sql);
  snprintf(sql, sizeof sql, "SELECT count(*) FROM finger_sample WHERE session_id = %s", uid8);
  const int64_t all_samples = db_scalar(h, sql);
  printf("finger samples: %lld as sent of %lld logged (want 19 of 19)\n", (long long)good, (long long)all_samples);
  CHECK(good == 19 && all_samples == 19, "finger samples every 3rd frame of 60 (250 Hz / 100 Hz), frame 30's NaN left out; "
        "triangles only from frame 31, where the local models count them");
  /* The patch: at frame 45 (proxy (4.5, 1.3, 47) mm) the 6 dome triangles whose rest centroids lie
   * nearest the proxy projected onto the dome, by a brute-force sort here */
  {
    const double px = 0.0045, py = 0.0013, pz = 0.047, len = sqrt(px * px + py * py + pz * pz), R = md.radius;
    const double q[3] = {px * R / len, py * R / len, pz * R / len};
    int order[6];
    double dist[6];
    for (int k = 0; k < 6; k++) order[k] = -1, dist[k] = INFINITY;
    for (int t = 0; t < mesh.dome_triangle_count; t++) {
      double g[3] = {0, 0, 0};
      for (int v = 0; v < 3; v++) {
        g[0] += mesh.rest[mesh.tri[t][v]].x / 3, g[1] += mesh.rest[mesh.tri[t][v]].y / 3;
        g[2] += mesh.rest[mesh.tri[t][v]].z / 3;
      }
      const double d = (g[0] - q[0]) * (g[0] - q[0]) + (g[1] - q[1]) * (g[1] - q[1]) + (g[2] - q[2]) * (g[2] - q[2]);
      for (int k = 0; k < 6; k++)
        if (d < dist[k]) {
          for (int j = 5; j > k; j--) dist[j] = dist[j - 1], order[j] = order[j - 1];
          dist[k] = d, order[k] = t;
          break;
        }
    }
    /* as sets (the order is nearest first, but near-equal distances may swap) */
    snprintf(sql, sizeof sql, "SELECT hex(triangles) FROM finger_sample WHERE session_id = %s AND frame = 45", uid8);
    char got_hex[64] = "";
    db_text(h, sql, got_hex, sizeof got_hex);
    int got[6], n = 0;
    for (; n < 6 && strlen(got_hex) >= (size_t)(8 * (n + 1)); n++) {
      unsigned b[4];
      sscanf(got_hex + 8 * n, "%2x%2x%2x%2x", &b[0], &b[1], &b[2], &b[3]);
      got[n] = (int)(b[0] | b[1] << 8 | b[2] << 16 | b[3] << 24);
    }
    int same = n == 6 && strlen(got_hex) == 48;
    for (int k = 0; k < 6 && same; k++) {
      int in = 0;
      for (int j = 0; j < 6; j++) in |= got[j] == order[k];
      same = in;
    }
    CHECK(same, "frame 45's footprint: the 6 dome triangles nearest the fingertip (%s; want %d %d %d %d %d %d)", got_hex,
          order[0], order[1], order[2], order[3], order[4], order[5]);
    snprintf(sql, sizeof sql,
             "SELECT count(*) FROM session WHERE id = %s AND json_extract(params_json, '$.footprint') = 'patch'", uid8);
    CHECK(db_scalar(h, sql) == 1, "the session's params say its footprints are patches");
  }

  /* session 10's samples from the server's finger samples: frame 3 from its local model (no
   * triangles), then 6, 9 and 18 with the triangles sent, the malformed, off-mesh and repeated
   * ones refused, the later local model not logged; its params say "touched" */
  {
    const char *uid10 = "(SELECT id FROM session WHERE uid LIKE 'dds-14-10-%')";
    snprintf(sql, sizeof sql,
             "SELECT group_concat(frame || ':' || CASE WHEN triangles IS NULL THEN '-' ELSE hex(triangles) END, ' ') FROM "
             "(SELECT frame, triangles FROM finger_sample WHERE session_id = %s ORDER BY frame)", uid10);
    char rows[256] = "";
    db_text(h, sql, rows, sizeof rows);
    const char *want = "3:- 6:000000000100000002000000 9:05000000 18:0700000008000000";
    CHECK(!strcmp(rows, want), "session 10's finger samples: %s (want %s)", rows, want);
    snprintf(sql, sizeof sql,
             "SELECT count(*) FROM session WHERE id = %s AND json_extract(params_json, '$.footprint') = 'touched'", uid10);
    CHECK(db_scalar(h, sql) == 1, "session 10's params say its footprints are the touched triangles");
  }

  /* the debriefs */
  snprintf(sql, sizeof sql,
           "SELECT count(*) FROM event WHERE session_id = %s AND kind = 'debrief' AND detail = 'told at level lesions: "
           "found 1 of 2 lesions; marks standing 2, near no lesion 1, duplicates 0; found by marks 4 0'",
           uid8);
  CHECK(db_scalar(h, sql) == 1, "session 8's debrief as the server logs it");
  CHECK(db_scalar(h, "SELECT count(*) FROM event e JOIN session s ON s.id = e.session_id WHERE s.uid LIKE 'dds-14-10-%' "
                     "AND e.kind = 'debrief' AND e.detail = 'told at level none: marks standing 0'") == 1 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE uid LIKE 'dds-14-10-%' AND end_reason = 'normal'") == 1,
        "session 10's debrief, 0.3 s after its CLOSED state, is logged, and the session ended normally");
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE uid LIKE 'dds-14-11-%' AND end_reason = 'error' AND "
                     "end_detail = 'palp-recorder stopped while the session ran (the server''s own log has the rest)'") == 1 &&
            strstr(text, "stopping: 1 session(s) still running end here in this log, cut short") != NULL,
        "session 11, still running at the recorder's stop, ends in its log saying why, and the recorder says so");
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE uid LIKE 'dds-14-11-%' AND "
                     "json_extract(params_json, '$.recorded_from_s') = 12.5") == 1 &&
            db_scalar(h, "SELECT count(*) FROM session WHERE uid LIKE 'dds-14-8-%' AND "
                         "json_extract(params_json, '$.recorded_from_s') IS NULL") == 1,
        "session 11's log says the recorder saw it 12.5 s after it opened; session 8's, seen at once, says nothing");
  sqlite3_close(h);
  char cmd[1600];
  snprintf(cmd, sizeof cmd, "'%s' --db '%s' show 11 2>/dev/null | grep -q '^           FROM 12.5 s INTO THE SESSION: the recorder joined late'",
           argv[5], db);
  const int st = system(cmd);
  CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 0, "palp-review show 11 says the recorder joined 12.5 s into the session");
  free(rest);
  free(tri);
  free(json);
  palp_mesh_destroy(&mesh);
  CHECK_DONE();
}
