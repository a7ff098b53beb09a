/* A full session through the writer, then palp-review on the file.
 * usage: test_db_session TMPDIR SCENE PALP_REVIEW
 *
 * 1. The scripted session (tests/db/sim.c: a real palp_world at 1 kHz, a ramped Gaussian press, a
 *    sliding finger updated every tick, feedback, meshes at ~30 Hz, events) lands in the file, and
 *    `export --format json|csv` gives back every frame, contact input and feedback sample that was
 *    sent, bit for bit (tolerance 0: %.17g round-trips doubles); `show` reports the peak force the
 *    test computes from what it sent, and the input count.
 * 2. `annotate` stores a note that `show` and `export` return.
 * 3. `replay` reproduces every logged frame bit-identically (exit 0); after one logged value is
 *    nudged by one ulp it names that frame and exits 1.
 * 4. A full disk (the writer's file capped with max_page_count) does not stop the stepping loop:
 *    it keeps its frame count, the enqueue calls only ever return 0 or PALP_EFULL, and the writer
 *    reports SQLITE_FULL and counts every lost record.
 * 5. A session that sleeps and is woken by a finger move replays bit-identically. */
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "check.h"
#include "sim.h"

static const char *review;

/* Runs palp-review with args and returns its stdout (malloc'd) and exit status. */
static char *run(int *status, const char *fmt, ...) {
  char args[2048], cmd[2600];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(args, sizeof args, fmt, ap);
  va_end(ap);
  snprintf(cmd, sizeof cmd, "'%s' %s", review, args);
  FILE *p = popen(cmd, "r");
  if (!p) return NULL;
  size_t cap = 1 << 16, n = 0;
  char *buf = malloc(cap);
  size_t k;
  while (buf && (k = fread(buf + n, 1, cap - n - 1, p)) > 0) {
    n += k;
    if (n + 1 == cap) {
      char *nb = realloc(buf, cap *= 2);
      if (!nb) break;
      buf = nb;
    }
  }
  if (buf) buf[n] = '\0';
  int st = pclose(p);
  *status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return buf;
}

static int same(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }
static double num(const cJSON *o, const char *k) { return cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(o, k)); }
static double at(const cJSON *o, const char *k, int i) {
  return cJSON_GetNumberValue(cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(o, k), i));
}
static const char *str(const cJSON *o, const char *k) {
  return cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(o, k));
}

static void check_export_json(const char *db, const char *uid, const sim_result *r) {
  int st;
  char *out = run(&st, "--db '%s' export %s --format json", db, uid);
  REQUIRE(out && st == 0, "export json exit %d", st);
  cJSON *j = cJSON_Parse(out);
  REQUIRE(j, "export is not valid JSON");
  const cJSON *s = cJSON_GetObjectItemCaseSensitive(j, "session");
  CHECK(!strcmp(str(s, "uid"), uid) && !strcmp(str(s, "trainee"), "trainee-07") &&
            !strcmp(str(s, "station"), "haptic-station-2") && !strcmp(str(s, "end_reason"), "normal"),
        "session fields");
  CHECK(num(s, "tick_hz") == 1000 && num(s, "dt_s") == 0.001, "tick/dt");
  CHECK(cJSON_IsObject(cJSON_GetObjectItemCaseSensitive(s, "scene")), "scene embedded as JSON");

  const cJSON *fr = cJSON_GetObjectItemCaseSensitive(j, "frames");
  CHECK(cJSON_GetArraySize(fr) == r->nframes, "frames: exported %d, sent %d", cJSON_GetArraySize(fr), r->nframes);
  int bad = 0, i = 0;
  const cJSON *e;
  cJSON_ArrayForEach(e, fr) {
    if (i >= r->nframes) break;
    const palp_db_frame *f = &r->frames[i++];
    char h[32];
    snprintf(h, sizeof h, "0x%016" PRIx64, f->state_hash);
    if (num(e, "frame") != (double)f->frame || !same(num(e, "sim_time_s"), f->sim_time_s) ||
        !same(num(e, "top_disp_m"), f->top_disp_m) || !same(num(e, "max_disp_m"), f->max_disp_m) ||
        !same(num(e, "volume_m3"), f->volume_m3) || !same(num(e, "pressure_pa"), f->pressure_pa) ||
        !same(num(e, "contact_force_n"), f->contact_force_n) || strcmp(str(e, "state_hash"), h))
      bad++;
  }
  CHECK(bad == 0, "%d exported frames differ from the sent ones (tolerance: 0 ulp)", bad);

  const cJSON *cs = cJSON_GetObjectItemCaseSensitive(j, "contacts");
  CHECK(cJSON_GetArraySize(cs) == r->ncontacts, "contacts: exported %d, sent %d", cJSON_GetArraySize(cs), r->ncontacts);
  bad = 0;
  i = 0;
  cJSON_ArrayForEach(e, cs) {
    if (i >= r->ncontacts) break;
    const palp_db_contact *c = &r->contacts[i++];
    const char *op = c->op == PALP_DB_OP_ADD ? "add" : c->op == PALP_DB_OP_UPDATE ? "update" : "remove";
    if (num(e, "frame") != (double)c->frame || !same(num(e, "sim_time_s"), c->sim_time_s) ||
        num(e, "slot") != c->slot || strcmp(str(e, "op"), op) ||
        strcmp(str(e, "kind"), c->kind == PALP_DB_KIND_FORCE ? "force" : "finger")) {
      bad++;
      continue;
    }
    if (c->op == PALP_DB_OP_REMOVE) continue;
    if (c->kind == PALP_DB_KIND_FINGER &&
        (!same(at(e, "center_m", 0), c->center_m.x) || !same(at(e, "center_m", 1), c->center_m.y) ||
         !same(at(e, "center_m", 2), c->center_m.z) || !same(num(e, "radius_m"), c->radius_m)))
      bad++;
    if (c->kind == PALP_DB_KIND_FORCE &&
        (!same(at(e, "force_n", 0), c->force_n.x) || !same(at(e, "force_n", 1), c->force_n.y) ||
         !same(at(e, "force_n", 2), c->force_n.z)))
      bad++;
    if (c->kind == PALP_DB_KIND_FORCE && c->op == PALP_DB_OP_ADD &&
        (num(e, "distribution") != c->def.distribution || !same(at(e, "center_m", 0), c->def.center.x) ||
         !same(at(e, "center_m", 2), c->def.center.z) || !same(num(e, "patch_area_m2"), c->def.patch_area) ||
         !same(num(e, "sigma_fraction"), c->def.sigma_fraction)))
      bad++;
  }
  CHECK(bad == 0, "%d exported contact inputs differ from the sent ones (tolerance: 0 ulp)", bad);

  const cJSON *fb = cJSON_GetObjectItemCaseSensitive(j, "feedback");
  CHECK(cJSON_GetArraySize(fb) == r->nfb, "feedback: exported %d, sent %d", cJSON_GetArraySize(fb), r->nfb);
  bad = 0;
  i = 0;
  /* Export orders feedback by (frame, slot); the sender sent slot 0 (force) before slot 1 (finger). */
  cJSON_ArrayForEach(e, fb) {
    if (i >= r->nfb) break;
    const sim_sent_fb *f = &r->fb[i++];
    if (num(e, "frame") != (double)f->frame || num(e, "slot") != f->slot || !same(at(e, "force_n", 0), f->f.x) ||
        !same(at(e, "force_n", 1), f->f.y) || !same(at(e, "force_n", 2), f->f.z))
      bad++;
  }
  CHECK(bad == 0, "%d exported feedback samples differ (tolerance: 0 ulp)", bad);
  CHECK(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(j, "events")) == r->events, "events: %d sent",
        r->events);
  cJSON_Delete(j);
  free(out);
}

static void check_csv_and_show(const char *db, const char *uid, const sim_result *r) {
  int st;
  char *out = run(&st, "--db '%s' export %s --format csv", db, uid);
  REQUIRE(out && st == 0, "export csv exit %d", st);
  int lines = 0;
  for (char *p = out; *p; p++) lines += *p == '\n';
  CHECK(lines == r->nframes + 1, "csv: %d lines for %d frames + header", lines, r->nframes);
  /* Row for frame 1234 (line 1235 after the header) against what was sent. */
  char *row = out;
  for (int k = 0; k < 1234 && row; k++) row = strchr(row, '\n') ? strchr(row, '\n') + 1 : NULL;
  REQUIRE(row, "csv row 1234");
  const palp_db_frame *f = &r->frames[1233];
  long long fr;
  double t, top, mx, vol, p, fc;
  CHECK(sscanf(row, "%lld,%lf,%lf,%lf,%lf,%lf,%lf", &fr, &t, &top, &mx, &vol, &p, &fc) == 7 && fr == f->frame &&
            same(t, f->sim_time_s) && same(top, f->top_disp_m) && same(mx, f->max_disp_m) &&
            same(vol, f->volume_m3) && same(p, f->pressure_pa) && same(fc, f->contact_force_n),
        "csv row for frame %lld differs from the sent frame", (long long)f->frame);
  free(out);

  out = run(&st, "--db '%s' export %s --format csv --table contacts", db, uid);
  lines = 0;
  for (char *q = out; q && *q; q++) lines += *q == '\n';
  CHECK(st == 0 && lines == r->ncontacts + 1, "contacts csv: %d lines for %d inputs", lines, r->ncontacts);
  free(out);

  /* show: the peak force and when, from the sent frames. */
  double peak = 0, peak_t = 0, peak_top = 0;
  for (int k = 0; k < r->nframes; k++) {
    if (r->frames[k].contact_force_n > peak) peak = r->frames[k].contact_force_n, peak_t = r->frames[k].sim_time_s;
    if (r->frames[k].top_disp_m > peak_top) peak_top = r->frames[k].top_disp_m;
  }
  out = run(&st, "--db '%s' show %s", db, uid);
  REQUIRE(out && st == 0, "show exit %d", st);
  char want[128];
  snprintf(want, sizeof want, "peak force           %.2f N at t = %.2f s", peak, peak_t);
  CHECK(strstr(out, want), "show lacks '%s':\n%s", want, out);
  snprintf(want, sizeof want, "top vertex %.2f mm", peak_top * 1e3);
  CHECK(strstr(out, want), "show lacks '%s'", want);
  snprintf(want, sizeof want, "contacts   %d inputs", r->ncontacts);
  CHECK(strstr(out, want), "show lacks '%s'", want);
  snprintf(want, sizeof want, "join 1, reject %d, leave 1", r->events - 2); /* the sim's events */
  CHECK(strstr(out, "trainee-07") && strstr(out, want) && strstr(out, "log        complete"),
        "show: trainee, '%s', completeness:\n%s", want, out);
  free(out);

  out = run(&st, "--db '%s' annotate %s --author 'Dr. Lee' --note 'Good systematic pattern; press deeper at 8 o'\"'\"'clock.' --grade B+ 2>/dev/null",
            db, uid);
  CHECK(st == 2, "a free-text grade 'B+' is refused with exit 2 (got %d)", st); /* issue 13: grades are structured */
  free(out);
  out = run(&st, "--db '%s' annotate %s --author 'Dr. Lee' --note 'Good systematic pattern; press deeper at 8 o'\"'\"'clock.' --score 82 --level competent",
            db, uid);
  CHECK(st == 0, "annotate exit %d", st);
  free(out);
  out = run(&st, "--db '%s' show %s", db, uid);
  CHECK(strstr(out, "Dr. Lee [grade 82 competent]: Good systematic pattern; press deeper at 8 o'clock."), "note in show:\n%s", out);
  free(out);
  out = run(&st, "--db '%s' list --trainee trainee-07", db);
  CHECK(st == 0 && strstr(out, uid) && strstr(out, "1 session"), "list --trainee:\n%s", out);
  free(out);
  out = run(&st, "--db '%s' list --trainee nobody", db);
  CHECK(st == 0 && !strstr(out, uid) && strstr(out, "0 sessions"), "list --trainee nobody");
  free(out);
  out = run(&st, "--db '%s' list --since 2000-01-01 --until 2999-01-01 --phantom phantom-a", db);
  CHECK(st == 0 && strstr(out, uid), "list with dates");
  free(out);
  out = run(&st, "--db '%s' list --since yesterday 2>/dev/null", db);
  CHECK(st == 2, "a bad date is an error with exit 2 (got %d)", st);
  free(out);
  out = run(&st, "--db '%s' show no-such-session 2>/dev/null", db);
  CHECK(st == 2, "unknown session: exit 2 (got %d)", st);
  free(out);
}

static void check_replay(const char *db, const char *uid) {
  int st;
  char *out = run(&st, "--db '%s' replay %s", db, uid);
  CHECK(out && st == 0 && strstr(out, "bit-identically"), "replay exit %d:\n%s", st, out ? out : "");
  free(out);
  /* Nudge one logged value by one ulp: replay must name that frame and fail. */
  sqlite3 *h;
  REQUIRE(sqlite3_open(db, &h) == SQLITE_OK, "open");
  sqlite3_stmt *q;
  sqlite3_prepare_v2(h, "SELECT pressure_pa FROM frame WHERE frame = 1234", -1, &q, NULL);
  REQUIRE(sqlite3_step(q) == SQLITE_ROW, "frame 1234 exists");
  double p = sqlite3_column_double(q, 0);
  sqlite3_finalize(q);
  sqlite3_prepare_v2(h, "UPDATE frame SET pressure_pa = ?1 WHERE frame = 1234", -1, &q, NULL);
  sqlite3_bind_double(q, 1, nextafter(p, INFINITY));
  CHECK(sqlite3_step(q) == SQLITE_DONE, "tamper");
  sqlite3_finalize(q);
  sqlite3_close(h);
  out = run(&st, "--db '%s' replay %s", db, uid);
  CHECK(st == 1 && out && strstr(out, "MISMATCH at frame 1234") && strstr(out, "pressure_pa"),
        "tampered replay: exit %d (want 1):\n%s", st, out ? out : "");
  free(out);
}

static void check_full_disk(const char *dir, const char *scene) {
  char db[600];
  snprintf(db, sizeof db, "%s/session_full.db", dir);
  unlink(db);
  sim_opts o = {.db = db, .uid = "full-disk-1", .scene_path = scene, .seconds = 2.0, .tick_hz = 1000,
                .max_db_bytes = 256 * 1024};
  sim_result r;
  REQUIRE(sim_run(&o, &r) == 0, "sim_run");
  CHECK(r.frames_stepped == 2000, "the stepping loop kept its frame count: %lld of 2000", (long long)r.frames_stepped);
  CHECK(r.log_errors == 0, "%lld log calls failed with something other than PALP_EFULL", (long long)r.log_errors);
  CHECK(r.st.failed > 0 && (r.st.last_error_code & 0xff) == SQLITE_FULL && strstr(r.st.last_error, "full"),
        "writer reports the full disk: failed %lld, last error '%s'", (long long)r.st.failed, r.st.last_error);
  CHECK(r.st.written + r.st.failed == r.st.enqueued,
        "every accepted record is written or counted lost (%lld + %lld vs %lld)", (long long)r.st.written,
        (long long)r.st.failed, (long long)r.st.enqueued);
  CHECK(r.st.shed >= r.records_refused, "every refused call is counted as shed (%lld >= %lld)",
        (long long)r.st.shed, (long long)r.records_refused);
  sqlite3 *h;
  sqlite3_open(db, &h);
  sqlite3_stmt *q;
  sqlite3_prepare_v2(h, "PRAGMA integrity_check", -1, &q, NULL);
  CHECK(sqlite3_step(q) == SQLITE_ROW && !strcmp((const char *)sqlite3_column_text(q, 0), "ok"), "integrity ok");
  sqlite3_finalize(q);
  sqlite3_close(h);
  printf("full disk: %lld frames stepped, %lld records written, %lld lost, last error: %s\n",
         (long long)r.frames_stepped, (long long)r.st.written, (long long)r.st.failed, r.st.last_error);
  sim_result_free(&r);
}

/* Sleep and wake across a replay. A finger presses 0.2 mm in for 0.35 s and lifts to hover 5 mm
 * above the pole, drifting every tick for 1.8 s while the membrane creeps back slower than the
 * sleep speed (1e-5 m/s). The wake after every input (contract item 3) keeps the world awake and creeping; a
 * twin world given the same finger moves without the wakes falls asleep (velocities zeroed), which
 * shows that the scenario depends on them. Then the finger rests, the world sleeps, and a final
 * press wakes it. Replay must follow the logged world bit for bit. */
static void check_sleep_wake(const char *dir, const char *scene_path) {
  char db[600], err[512];
  snprintf(db, sizeof db, "%s/session_sleep.db", dir);
  unlink(db);
  palp_scene sc;
  REQUIRE(palp_scene_load(scene_path, &sc, err, sizeof err) == 0, "scene: %s", err);
  sc.world.dt = 0.001;
  char *json = palp_scene_to_json(&sc);
  int rc;
  palp_world *w = palp_db_world_from_scene(json, 0.001, &rc, err, sizeof err);
  palp_world *twin = palp_db_world_from_scene(json, 0.001, &rc, err, sizeof err);
  REQUIRE(w && twin, "world: %s", err);
  palp_db_writer *lw;
  REQUIRE(palp_db_writer_open(db, NULL, &lw, err, sizeof err) == 0, "writer: %s", err);
  palp_db_session_def d = {.uid = "sleep-wake-1", .trainee = "t", .station = "s", .phantom_id = "p",
                           .phantom_name = "p", .scene_json = json, .tick_hz = 1000, .dt_s = 0.001};
  palp_db_session s;
  REQUIRE(palp_db_log_session_begin(lw, &d, &s) == 0, "begin");
  const double R = sc.world.mesh.radius, r = 0.008;
  const palp_mesh *m = palp_world_mesh(w);
  int finger = -1, tf = -1, awake_while_moving = 0, twin_slept = 0, asleep_after_rest = 0;
  double top_before = 0;
  for (int f = 0; f < 3200; f++) {
    const palp_vec3 press = {0, 0, R + r - 0.0002}, hover = {1e-6 * (f - 400), 0, R + r + 0.005};
    if (f == 50) {
      finger = palp_db_world_add_finger(lw, s, w, press, r);
      tf = palp_world_add_finger(twin, press, r);
    }
    if (f >= 400 && f < 2200) { /* lifted, hovering and drifting 1 um per tick */
      palp_db_world_set_finger(lw, s, w, finger, hover, r);
      palp_world_set_finger(twin, tf, hover, r); /* the same move, no wake */
    }
    if (f == 2199) {
      awake_while_moving = palp_world_is_awake(w);
      twin_slept = !palp_world_is_awake(twin);
    }
    if (f == 3000) {
      asleep_after_rest = !palp_world_is_awake(w);
      top_before = m->rest[m->top_vertex].z - palp_world_positions(w)[m->top_vertex].z;
      palp_db_world_set_finger(lw, s, w, finger, (palp_vec3){0, 0, R + r - 0.0015}, r);
    }
    REQUIRE(palp_db_world_step(lw, s, w, NULL) == 0, "step %d", f);
    if (f < 2200) palp_world_step(twin);
  }
  const double top_after = m->rest[m->top_vertex].z - palp_world_positions(w)[m->top_vertex].z;
  CHECK(awake_while_moving, "a finger moved every tick keeps the world awake");
  CHECK(twin_slept, "without the wakes the creeping world falls asleep (sleep_time 0.5 s): the scenario "
                    "must depend on the wakes");
  CHECK(asleep_after_rest, "0.7 s without input puts the world to sleep");
  CHECK(top_after - top_before > 1e-4, "the last press moved the pole in (%.3g m; want > 0.1 mm)",
        top_after - top_before);
  palp_db_log_session_end(lw, s, PALP_DB_END_NORMAL, NULL, 0);
  palp_db_writer_close(lw);
  palp_world_destroy(w);
  palp_world_destroy(twin);
  free(json);
  int st;
  char *out = run(&st, "--db '%s' replay sleep-wake-1", db);
  CHECK(st == 0 && out && strstr(out, "bit-identically"), "replay across sleep and wake: exit %d\n%s", st,
        out ? out : "");
  free(out);
}

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: %s TMPDIR SCENE PALP_REVIEW\n", argv[0]);
    return 2;
  }
  review = argv[3];
  char db[600];
  snprintf(db, sizeof db, "%s/session.db", argv[1]);
  unlink(db);
  sim_opts o = {.db = db, .uid = "run-5f3a-0001", .scene_path = argv[2], .seconds = 2.5, .tick_hz = 1000, .keep = 1};
  sim_result r;
  REQUIRE(sim_run(&o, &r) == 0, "sim_run");
  CHECK(r.frames_stepped == 2500 && r.nframes == 2500 && r.records_refused == 0 && r.log_errors == 0,
        "session ran clean: %lld frames, %lld refused", (long long)r.frames_stepped, (long long)r.records_refused);
  CHECK(r.st.written == r.st.enqueued && r.st.shed == 0 && r.st.failed == 0, "written %lld of %lld",
        (long long)r.st.written, (long long)r.st.enqueued);
  check_export_json(db, o.uid, &r);
  check_csv_and_show(db, o.uid, &r);
  check_replay(db, o.uid);
  sim_result_free(&r);
  check_full_disk(argv[1], argv[2]);
  check_sleep_wake(argv[1], argv[2]);
  CHECK_DONE();
}
