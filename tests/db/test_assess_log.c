/* Schema 3: an exercise session's exercise, finger samples and findings round-trip through the
 * writer and the reader on a real SQLite file.
 * usage: test_db_assess_log TMPDIR
 * Values are compared exactly (tolerance 0): SQLite stores IEEE doubles and int64 bit for bit. */
#include <sqlite3.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "palp_db.h"
#include "sqlite_util.h"

enum { SAMPLES = 300 };

static palp_db_finger_sample sample_of(int i, int32_t *tri) {
  palp_db_finger_sample s = {0};
  s.frame = 4 * i + 4;
  s.sim_time_s = 0.004 * (double)(i + 1);
  s.slot = 0;
  s.radius_m = 0.008;
  s.device_m = (palp_vec3){1e-3 * i / 3.0, -2e-3, 0.05 - 1e-5 * i};
  s.proxy_m = (palp_vec3){1e-3 * i / 3.0, -2e-3, 0.052 - 5e-6 * i};
  s.force_n = (palp_vec3){0.01, -0.02, 0.003 * i};
  s.in_contact = i % 3 != 0;
  s.point_m = (palp_vec3){1e-3 * i / 3.0, -2e-3, 0.044};
  s.area_m2 = 1e-6 * i;
  s.triangle_count = i % 7; /* 0..6 triangles; 0 = the disc footprint */
  for (int k = 0; k < s.triangle_count; k++) tri[k] = (k == 5) ? INT32_MAX - i : 100 + i + k;
  s.triangles = s.triangle_count ? tri : NULL;
  return s;
}

typedef struct {
  int n, bad, tri_bad;
} sample_chk;
static int on_sample(void *u, const palp_db_finger_sample *s) {
  sample_chk *c = u;
  int32_t tri[8];
  palp_db_finger_sample e = sample_of(c->n++, tri);
  if (s->frame != e.frame || s->sim_time_s != e.sim_time_s || s->slot != e.slot || s->radius_m != e.radius_m ||
      s->device_m.x != e.device_m.x || s->device_m.z != e.device_m.z || s->proxy_m.z != e.proxy_m.z ||
      s->force_n.y != e.force_n.y || s->force_n.z != e.force_n.z || s->in_contact != e.in_contact ||
      s->point_m.x != e.point_m.x || s->area_m2 != e.area_m2)
    c->bad++;
  if (s->triangle_count != e.triangle_count || (e.triangle_count && memcmp(s->triangles, tri, 4u * (unsigned)e.triangle_count)))
    c->tri_bad++;
  return 0;
}

typedef struct {
  int n, marks, withdrawals, bad;
} finding_chk;
static int on_finding(void *u, const palp_db_finding *f) {
  finding_chk *c = u;
  c->n++;
  if (f->op == PALP_DB_FINDING_MARK) {
    c->marks++;
    if (f->mark_id == 2 && (f->point_m.x != 0.0125 || f->point_m.y != -0.003 || f->point_m.z != 0.0375)) c->bad++;
  } else {
    c->withdrawals++;
    if (f->mark_id != 1 || c->n != 3) c->bad++; /* the withdrawal of mark 1 comes third */
  }
  return 0;
}

int main(int argc, char **argv) {
  REQUIRE(argc == 2, "usage: test_db_assess_log TMPDIR");
  char path[1024];
  db_fresh_path(path, sizeof path, argv[1], "assess_log.sqlite");
  char err[256];
  palp_db_writer *w = NULL;
  REQUIRE(palp_db_writer_open(path, NULL, &w, err, sizeof err) == 0, "open writer: %s", err);
  CHECK(palp_db_schema_version() >= 3, "schema version %d (>= 3 has the assessment tables)", palp_db_schema_version());

  palp_db_session_def d = {.uid = "assess-1", .trainee = "alice", .station = "st", .phantom_id = "7",
                           .phantom_name = "easy exercise", .scene_json = "{}", .tick_hz = 250, .dt_s = 0.004};
  palp_db_session s;
  REQUIRE(palp_db_log_session_begin(w, &d, &s) == 0, "begin");
  const char *ex_json = "{\"name\": \"easy\", \"lesions\": [{\"depth_mm\": 10}]}";
  CHECK(palp_db_log_exercise(w, s, "easy", ex_json) == 0, "log exercise");
  CHECK(palp_db_log_exercise(w, s, "", ex_json) == PALP_EINVAL, "an exercise without a name is refused");

  for (int i = 0; i < SAMPLES; i++) {
    int32_t tri[8];
    palp_db_finger_sample fs = sample_of(i, tri);
    CHECK(palp_db_log_finger_sample(w, s, &fs) == 0, "sample %d", i);
  }
  int32_t many[PALP_DB_MAX_SAMPLE_TRIANGLES + 1] = {0};
  palp_db_finger_sample big = sample_of(0, many);
  big.frame = 999999;
  big.triangle_count = PALP_DB_MAX_SAMPLE_TRIANGLES + 1;
  big.triangles = many;
  CHECK(palp_db_log_finger_sample(w, s, &big) == PALP_EINVAL, "a sample with %d triangles is refused",
        PALP_DB_MAX_SAMPLE_TRIANGLES + 1);

  palp_db_finding m1 = {.mark_id = 1, .op = PALP_DB_FINDING_MARK, .frame = 10, .sim_time_s = 0.04,
                        .point_m = {0.001, 0.002, 0.039}};
  palp_db_finding m2 = {.mark_id = 2, .op = PALP_DB_FINDING_MARK, .frame = 20, .sim_time_s = 0.08,
                        .point_m = {0.0125, -0.003, 0.0375}};
  palp_db_finding w1 = {.mark_id = 1, .op = PALP_DB_FINDING_WITHDRAW, .frame = 30, .sim_time_s = 0.12};
  palp_db_finding bad = {.mark_id = 3, .op = (palp_db_finding_op)9};
  CHECK(palp_db_log_finding(w, s, &m1) == 0 && palp_db_log_finding(w, s, &m2) == 0 &&
            palp_db_log_finding(w, s, &w1) == 0,
        "log findings");
  CHECK(palp_db_log_finding(w, s, &bad) == PALP_EINVAL, "an unknown finding op is refused");
  CHECK(palp_db_log_session_end(w, s, PALP_DB_END_NORMAL, NULL, 0) == 0, "end");
  CHECK(palp_db_log_finding(w, s, &m1) == PALP_EINVAL, "a finding after the session's end is refused");
  palp_db_writer_close(w);

  palp_db *db = NULL;
  REQUIRE(palp_db_open(path, 0, &db, err, sizeof err) == 0, "open reader: %s", err);
  palp_db_session_info info;
  REQUIRE(palp_db_find_session(db, "assess-1", &info) == 0, "find session");
  char name[64];
  char *json = NULL;
  CHECK(palp_db_session_exercise(db, info.id, name, sizeof name, &json) == 0 && !strcmp(name, "easy") && json &&
            !strcmp(json, ex_json),
        "exercise round trip: name '%s', json %s", name, json ? json : "(null)");
  free(json);

  sample_chk sc = {0};
  CHECK(palp_db_each_finger_sample(db, info.id, on_sample, &sc) == 0, "each sample");
  CHECK(sc.n == SAMPLES && sc.bad == 0 && sc.tri_bad == 0, "%d of %d samples read back, %d differ, %d triangle lists differ",
        sc.n, SAMPLES, sc.bad, sc.tri_bad);

  finding_chk fc = {0};
  CHECK(palp_db_each_finding(db, info.id, on_finding, &fc) == 0, "each finding");
  CHECK(fc.n == 3 && fc.marks == 2 && fc.withdrawals == 1 && fc.bad == 0, "findings: %d (%d marks, %d withdrawals), %d bad",
        fc.n, fc.marks, fc.withdrawals, fc.bad);

  /* A damaged triangle blob (not a whole number of int32) reads as "no triangles", and the
   * walk goes on past it. */
  sqlite3 *h = palp_db_handle(db);
  CHECK(sqlite3_exec(h, "UPDATE finger_sample SET triangles = x'0102030405' WHERE frame = 8", NULL, NULL, NULL) ==
            SQLITE_OK,
        "damage one blob");
  sc = (sample_chk){0};
  palp_db_each_finger_sample(db, info.id, on_sample, &sc);
  CHECK(sc.n == SAMPLES && sc.tri_bad == 1 && sc.bad == 0, "after damage: %d samples, %d triangle lists differ (1 expected)",
        sc.n, sc.tri_bad);

  /* A session without an exercise says so. */
  CHECK(palp_db_session_exercise(db, info.id + 1000, name, sizeof name, NULL) == PALP_DB_ENOTFOUND,
        "no exercise: PALP_DB_ENOTFOUND");
  palp_db_close(db);
  CHECK_DONE();
}
