/* Writer and schema tests on real SQLite files (no model library needed).
 * usage: test_db_writer TMPDIR MIGRATION_0001_SQL
 * Values are compared exactly (tolerance 0): SQLite stores IEEE doubles and int64 bit for bit. */
#include <math.h>
#include <sqlite3.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "sqlite_util.h"
#include "palp_db.h"

static char dir[512];

static void path_in(char *buf, size_t n, const char *name) { db_fresh_path(buf, n, dir, name); }

static palp_db_frame frame_of(int64_t i) {
  palp_db_frame f;
  f.frame = i;
  f.sim_time_s = 0.001 * (double)i;
  f.top_disp_m = 1e-3 / 3.0 * (double)i;
  f.max_disp_m = 2e-3 / 7.0 * (double)i;
  f.volume_m3 = 1.3404e-4 - 1e-9 * (double)i;
  f.pressure_pa = 101.25 + (double)i;
  f.contact_force_n = 3.0 / 11.0 * (double)i;
  f.state_hash = 0xF000000000000000ull ^ (uint64_t)i * 0x9E3779B97F4A7C15ull; /* high bit set */
  return f;
}

/* --- round trip ----------------------------------------------------------------------- */
typedef struct {
  int n, bad;
} frame_chk;
static int on_frame(void *u, const palp_db_frame *f) {
  frame_chk *c = u;
  palp_db_frame e = frame_of(c->n + 1);
  if (memcmp(&e, f, sizeof e) != 0) c->bad++;
  c->n++;
  return 0;
}
typedef struct {
  int n, bad;
  palp_db_contact sent[3];
} contact_chk;
static int on_contact(void *u, const palp_db_contact *c) {
  contact_chk *k = u;
  const palp_db_contact *e = &k->sent[k->n++];
  if (c->frame != e->frame || c->sim_time_s != e->sim_time_s || c->slot != e->slot || c->op != e->op ||
      c->kind != e->kind)
    k->bad++;
  if (e->kind == PALP_DB_KIND_FORCE && e->op == PALP_DB_OP_ADD &&
      (c->def.distribution != e->def.distribution || c->def.center.x != e->def.center.x ||
       c->def.center.z != e->def.center.z || c->force_n.z != e->force_n.z ||
       c->def.patch_area != e->def.patch_area || c->def.offset_dir.y != e->def.offset_dir.y))
    k->bad++;
  if (e->kind == PALP_DB_KIND_FINGER && (c->center_m.y != e->center_m.y || c->radius_m != e->radius_m))
    k->bad++;
  return 0;
}
static int on_mesh(void *u, int64_t frame, const palp_vec3 *pos, int n) {
  int *bad = u;
  if (frame != 10 || n != 4) (*bad)++;
  for (int i = 0; i < n; i++)
    if (pos[i].x != 0.1 * i || pos[i].y != -0.2 * i || pos[i].z != 1.0 / (i + 3)) (*bad)++;
  return 0;
}

static void test_round_trip(void) {
  char p[600];
  path_in(p, sizeof p, "roundtrip.db");
  char err[512];
  palp_db_writer *w;
  int rc = palp_db_writer_open(p, NULL, &w, err, sizeof err);
  REQUIRE(rc == 0, "writer_open: %s", err);
  /* A new session log (trainees' names, what they did, their grades) is its owner's alone, and
   * so is its write-ahead log, whatever the umask (this test's is the shell's, usually 022). */
  struct stat fst;
  char wal[640];
  snprintf(wal, sizeof wal, "%s-wal", p);
  CHECK(stat(p, &fst) == 0 && (fst.st_mode & 077) == 0, "a new session log is mode 0600 (got %04o)",
        (unsigned)(fst.st_mode & 07777));
  CHECK(stat(wal, &fst) == 0 && (fst.st_mode & 077) == 0, "its -wal file too (got %04o)",
        (unsigned)(fst.st_mode & 07777));
  palp_db_session_def d = {.uid = "run-abc-1", .trainee = "alice", .station = "haptic-1",
                           .phantom_id = "p1", .phantom_name = "soft dome",
                           .scene_json = "{\"name\":\"x\"}", .params_json = "{\"force_limit_n\":20}",
                           .tick_hz = 1000, .dt_s = 0.001, .start_unix_s = 1.7e9};
  palp_db_session s;
  REQUIRE(palp_db_log_session_begin(w, &d, &s) == 0, "session_begin");
  contact_chk cc = {0};
  palp_vec3 c0 = {0.001, 0.002, 0.04};
  cc.sent[0] = (palp_db_contact){.frame = 0, .sim_time_s = 0, .slot = 0, .op = PALP_DB_OP_ADD,
                                 .kind = PALP_DB_KIND_FORCE,
                                 .def = {.distribution = PALP_DIST_GAUSSIAN, .center = c0,
                                         .sigma_fraction = 0.5, .offset_fraction = 0.5}};
  cc.sent[0].def.patch_area = 5.2e-4;
  cc.sent[0].def.offset_dir = (palp_vec3){0, 1.0 / 3.0, 0};
  cc.sent[0].force_n = (palp_vec3){0, 0, -3.0};
  cc.sent[1] = (palp_db_contact){.frame = 5, .sim_time_s = 0.005, .slot = 1, .op = PALP_DB_OP_ADD,
                                 .kind = PALP_DB_KIND_FINGER, .center_m = {0.0, 0.01 / 3.0, 0.041},
                                 .radius_m = 0.008};
  cc.sent[2] = (palp_db_contact){.frame = 9, .sim_time_s = 0.009, .slot = 0, .op = PALP_DB_OP_REMOVE,
                                 .kind = PALP_DB_KIND_FORCE};
  for (int i = 0; i < 3; i++) CHECK(palp_db_log_contact(w, s, &cc.sent[i]) == 0, "log_contact %d", i);
  for (int64_t i = 1; i <= 2000; i++) {
    palp_db_frame f = frame_of(i);
    CHECK(palp_db_log_frame(w, s, &f) == 0, "log_frame");
    CHECK(palp_db_log_feedback(w, s, i, 0, (palp_vec3){0, 0, 0.5 * (double)i}) == 0, "log_feedback");
  }
  palp_vec3 mesh[4];
  for (int i = 0; i < 4; i++) mesh[i] = (palp_vec3){0.1 * i, -0.2 * i, 1.0 / (i + 3)};
  CHECK(palp_db_log_mesh(w, s, 10, mesh, 4) == 0, "log_mesh");
  CHECK(palp_db_log_event(w, s, PALP_DB_EVENT_REJECT, 7, "force 50 N beyond the 20 N limit", 1) == 0, "event");
  CHECK(palp_db_log_session_end(w, s, PALP_DB_END_STATION_VANISHED, "liveliness lost", 1.7e9 + 2) == 0, "end");
  /* After the end the handle is dead: a late record is refused, not written under another name. */
  palp_db_frame late = frame_of(9999);
  CHECK(palp_db_log_frame(w, s, &late) == PALP_EINVAL, "record after session end must be refused");
  CHECK(palp_db_writer_flush(w, 10) == 0, "flush");
  palp_db_writer_stats st;
  palp_db_writer_stats_get(w, &st);
  /* 1 begin + 3 contacts + 2000 frames + 2000 feedback + 1 mesh + 1 event + 1 end */
  CHECK(st.enqueued == 4007 && st.written == 4007, "enqueued %lld written %lld (expected 4007)",
        (long long)st.enqueued, (long long)st.written);
  CHECK(st.shed == 0 && st.failed == 0, "shed %lld failed %lld", (long long)st.shed, (long long)st.failed);
  palp_db_writer_close(w);

  palp_db *db;
  REQUIRE(palp_db_open(p, 0, &db, err, sizeof err) == 0, "open: %s", err);
  palp_db_session_info info;
  REQUIRE(palp_db_find_session(db, "run-abc", &info) == 0, "find by prefix");
  CHECK(!strcmp(info.uid, "run-abc-1") && !strcmp(info.trainee, "alice") && !strcmp(info.phantom_name, "soft dome"),
        "session strings");
  CHECK(info.frames == 2000 && info.contact_inputs == 3 && info.meshes == 1 && info.events == 1, "counts");
  CHECK(!strcmp(info.end_reason, "station_vanished") && info.end_unix_s == 1.7e9 + 2, "end %s", info.end_reason);
  CHECK(info.sim_duration_s == 2.0, "sim duration %.17g (expected 2.0, last frame 2000 x 1 ms)", info.sim_duration_s);
  frame_chk fc = {0};
  CHECK(palp_db_each_frame(db, info.id, on_frame, &fc) == 0 && fc.n == 2000 && fc.bad == 0,
        "frames n=%d bad=%d (exact)", fc.n, fc.bad);
  int nc = cc.n;
  cc.n = 0;
  (void)nc;
  CHECK(palp_db_each_contact(db, info.id, on_contact, &cc) == 0 && cc.n == 3 && cc.bad == 0,
        "contacts n=%d bad=%d", cc.n, cc.bad);
  int mbad = 0;
  CHECK(palp_db_each_mesh(db, info.id, on_mesh, &mbad) == 0 && mbad == 0, "mesh bad=%d", mbad);
  char *scene, *params;
  CHECK(palp_db_session_json(db, info.id, &scene, &params) == 0 && !strcmp(scene, "{\"name\":\"x\"}") &&
            !strcmp(params, "{\"force_limit_n\":20}"),
        "json");
  free(scene);
  free(params);
  CHECK(palp_db_add_note(db, info.id, "dr. b", "good pressure", "A") == 0, "note");
  palp_db_filter f = {.trainee = "alice"};
  palp_db_session_info *list;
  int n;
  CHECK(palp_db_list_sessions(db, &f, &list, &n) == 0 && n == 1, "list alice n=%d", n);
  free(list);
  f.trainee = "bob";
  CHECK(palp_db_list_sessions(db, &f, &list, &n) == 0 && n == 0, "list bob n=%d", n);
  free(list);
  f = (palp_db_filter){.since_unix_s = 1.7e9 + 1, .has_since = 1};
  CHECK(palp_db_list_sessions(db, &f, &list, &n) == 0 && n == 0, "list since n=%d", n);
  free(list);
  sqlite3 *h = palp_db_handle(db);
  CHECK(db_scalar(h, "SELECT count(*) FROM feedback WHERE force_z_n = 1000.0 AND frame = 2000") == 1, "feedback");
  CHECK(db_scalar(h, "SELECT records_written FROM writer_run") == 4007, "writer_run records");
  palp_db_close(db);
}

/* --- shedding: a tiny queue flooded faster than any disk must count every refused record ------ */
static void test_shed(void) {
  char p[600], err[512];
  path_in(p, sizeof p, "shed.db");
  palp_db_writer_opts o = palp_db_writer_default_opts();
  o.queue_capacity = 64;
  o.batch_records = 32;
  palp_db_writer *w;
  REQUIRE(palp_db_writer_open(p, &o, &w, err, sizeof err) == 0, "open: %s", err);
  palp_db_session_def d = {.uid = "shed-1", .scene_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
  palp_db_session s;
  REQUIRE(palp_db_log_session_begin(w, &d, &s) == 0, "begin");
  int ok = 0, full = 0;
  for (int64_t i = 1; i <= 200000; i++) {
    palp_db_frame f = frame_of(i);
    int rc = palp_db_log_frame(w, s, &f);
    if (rc == 0) ok++;
    else if (rc == PALP_EFULL) full++;
  }
  CHECK(ok + full == 200000, "every call returns 0 or PALP_EFULL (%d + %d)", ok, full);
  CHECK(full > 0, "a 64-record queue fed 200000 records in a tight loop must shed");
  CHECK(palp_db_log_session_end(w, s, PALP_DB_END_NORMAL, NULL, 0) == 0, "end fits in the control reserve");
  palp_db_writer_flush(w, 10);
  palp_db_writer_stats st;
  palp_db_writer_stats_get(w, &st);
  CHECK(st.shed == full && st.shed_by_kind[PALP_DB_REC_FRAME] == full, "shed %lld vs EFULL %d",
        (long long)st.shed, full);
  /* 64 data records plus the end record, which may use the control reserve. */
  CHECK(st.queue_high_water <= 65, "data records never exceed the capacity (hw %d)", st.queue_high_water);
  palp_db_writer_close(w);
  palp_db *db;
  REQUIRE(palp_db_open(p, 0, &db, err, sizeof err) == 0, "open: %s", err);
  sqlite3 *h = palp_db_handle(db);
  CHECK(db_scalar(h, "SELECT count(*) FROM frame") == ok, "frames written = accepted (%d)", ok);
  char q[128];
  snprintf(q, sizeof q, "SELECT count(*) FROM session WHERE records_shed = %d AND end_reason = 'normal'", full);
  CHECK(db_scalar(h, q) == 1, "session.records_shed = %d", full);
  snprintf(q, sizeof q, "SELECT sum(count) FROM event WHERE kind = 'shed'");
  CHECK(db_scalar(h, q) == full, "shed events account for all %d shed records (got %lld)", full,
        (long long)db_scalar(h, q));
  palp_db_close(db);
}

/* --- a duplicate frame is refused alone; the rest of its batch lands ----------------------- */
static void test_duplicate(void) {
  char p[600], err[512];
  path_in(p, sizeof p, "dup.db");
  palp_db_writer *w;
  REQUIRE(palp_db_writer_open(p, NULL, &w, err, sizeof err) == 0, "open: %s", err);
  palp_db_session_def d = {.uid = "dup-1", .scene_json = "{}", .tick_hz = 100, .dt_s = 0.01};
  palp_db_session s;
  REQUIRE(palp_db_log_session_begin(w, &d, &s) == 0, "begin");
  for (int64_t i = 1; i <= 10; i++) {
    palp_db_frame f = frame_of(i == 5 ? 4 : i);
    palp_db_log_frame(w, s, &f);
  }
  palp_db_writer_flush(w, 10);
  palp_db_writer_stats st;
  palp_db_writer_stats_get(w, &st);
  CHECK(st.written == 10 && st.failed == 1 && st.failed_by_kind[PALP_DB_REC_FRAME] == 1,
        "written %lld failed %lld (expected 10 incl. begin, 1)", (long long)st.written, (long long)st.failed);
  palp_db_writer_close(w);
}

/* --- migrations ------------------------------------------------------------------------ */
static char *slurp(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *b = malloc((size_t)n + 1);
  if (b && fread(b, 1, (size_t)n, f) != (size_t)n) n = 0;
  if (b) b[n] = '\0';
  fclose(f);
  return b;
}

static void test_migration(const char *v1_sql) {
  char p[600], err[512];
  path_in(p, sizeof p, "v1.db");
  /* A file as palp 0.1 with schema 1 left it, built from the original script. */
  sqlite3 *h;
  REQUIRE(sqlite3_open(p, &h) == SQLITE_OK, "sqlite3_open");
  char *sql = slurp(v1_sql);
  REQUIRE(sql, "cannot read %s", v1_sql);
  REQUIRE(sqlite3_exec(h, sql, NULL, NULL, NULL) == SQLITE_OK, "v1 script: %s", sqlite3_errmsg(h));
  free(sql);
  REQUIRE(sqlite3_exec(h,
                       "PRAGMA user_version = 1;"
                       "INSERT INTO meta VALUES('app_version', '0.0.9');"
                       "INSERT INTO session(uid, trainee, station, phantom_id, phantom_name, scene_json, "
                       "params_json, tick_hz, dt_s, start_unix_s) VALUES('old-1', 'carol', 's', 'p', 'n', "
                       "'{}', '{}', 100, 0.01, 1.6e9);"
                       "INSERT INTO frame VALUES(1, 1, 0.01, 1e-3, 2e-3, 1e-4, 5.0, 3.0, -42);",
                       NULL, NULL, NULL) == SQLITE_OK,
          "v1 rows: %s", sqlite3_errmsg(h));
  sqlite3_close(h);

  /* Read-only first: an upgraded copy in memory to read, the file left at version 1 (2026-12-06: the
   * readers upgraded it in place); too large to copy (0 bytes allowed) is refused, naming migrate. */
  palp_db *db;
  REQUIRE(palp_db_open_readonly(p, 1LL << 30, &db, err, sizeof err) == 0, "open v1 read-only: %s", err);
  palp_db_session_info info;
  CHECK(palp_db_copied_from_version(db) == 1 && palp_db_file_version(db) == palp_db_schema_version() &&
            palp_db_find_session(db, "old-1", &info) == 0 && !strcmp(info.trainee, "carol") && info.frames == 1,
        "v1 read through a copy upgraded to %d (copied from %d)", palp_db_file_version(db),
        palp_db_copied_from_version(db));
  CHECK(palp_db_add_note(db, info.id, "Lee", "x", NULL) != 0, "the read-only copy refuses a write");
  palp_db_close(db);
  REQUIRE(sqlite3_open_v2(p, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK, "peek");
  CHECK(db_scalar(h, "PRAGMA user_version") == 1 && db_scalar(h, "SELECT count(*) FROM note") == 0 &&
            db_scalar(h, "SELECT count(*) FROM sqlite_master WHERE name = 'writer_run'") == 0,
        "the file is still version 1, without the note or migration 2's table");
  sqlite3_close(h);
  int rc = palp_db_open_readonly(p, 0, &db, err, sizeof err);
  CHECK(rc == PALP_DB_EOLDER && strstr(err, "palp-review --db") && strstr(err, "migrate"),
        "too large to copy: refused (%d): %s", rc, err);

  REQUIRE(palp_db_open(p, 0, &db, err, sizeof err) == 0, "open v1: %s", err);
  CHECK(palp_db_file_version(db) == palp_db_schema_version() && palp_db_schema_version() == 5,
        "upgraded to %d (library %d, expected 5)", palp_db_file_version(db), palp_db_schema_version());
  CHECK(palp_db_find_session(db, "old-1", &info) == 0 && !strcmp(info.trainee, "carol") && info.frames == 1 &&
            info.records_shed == 0,
        "v1 data survives the upgrade with the new columns at their defaults");
  h = palp_db_handle(db);
  CHECK(db_scalar(h, "SELECT count(*) FROM writer_run") == 0, "writer_run created by migration 2");
  CHECK(db_scalar(h, "SELECT count(*) FROM meta WHERE key = 'upgraded_unix_s'") == 1, "meta.upgraded_unix_s");
  CHECK(db_scalar(h, "SELECT count(*) FROM frame WHERE state_hash = -42") == 1, "v1 frame intact");
  CHECK(db_scalar(h, "SELECT count(*) FROM pragma_table_info('session_metrics') WHERE name IN ('strips', "
                     "'strip_order')") == 2,
        "session_metrics has the strips and their order (migration 5)");
  palp_db_close(db);

  /* Opening again is a no-op. */
  REQUIRE(palp_db_open(p, 0, &db, err, sizeof err) == 0, "reopen: %s", err);
  palp_db_close(db);

  /* A fresh file starts at the current version with its creation time recorded. */
  path_in(p, sizeof p, "fresh.db");
  REQUIRE(palp_db_open(p, 1, &db, err, sizeof err) == 0, "create: %s", err);
  h = palp_db_handle(db);
  CHECK(palp_db_file_version(db) == 5, "fresh version");
  CHECK(db_scalar(h, "SELECT count(*) FROM meta WHERE key IN ('created_unix_s','app_version','schema_version')") == 3,
        "meta rows");
  CHECK(db_scalar(h, "PRAGMA journal_mode = WAL") >= -1, "wal");
  palp_db_close(db);

  /* Somebody else's SQLite file (tables, no palp version) is refused, not "upgraded". */
  path_in(p, sizeof p, "foreign.db");
  REQUIRE(sqlite3_open(p, &h) == SQLITE_OK, "open");
  REQUIRE(sqlite3_exec(h, "CREATE TABLE invoices(id INTEGER PRIMARY KEY, total REAL)", NULL, NULL, NULL) == SQLITE_OK,
          "foreign table");
  sqlite3_close(h);
  CHECK(palp_db_open(p, 1, &db, err, sizeof err) != 0 && strstr(err, "not a palp session log"),
        "foreign database refused: %s", err);
  REQUIRE(sqlite3_open(p, &h) == SQLITE_OK, "reopen");
  CHECK(db_scalar(h, "SELECT count(*) FROM sqlite_master") == 1, "foreign database untouched");
  sqlite3_close(h);

  /* A missing file is not created by a reader. */
  path_in(p, sizeof p, "missing.db");
  CHECK(palp_db_open(p, 0, &db, err, sizeof err) != 0 && access(p, F_OK) != 0, "reader must not create %s", p);
}

static void test_newer(void) {
  char p[600], err[512] = "";
  path_in(p, sizeof p, "newer.db");
  sqlite3 *h;
  REQUIRE(sqlite3_open(p, &h) == SQLITE_OK, "open");
  REQUIRE(sqlite3_exec(h, "CREATE TABLE future(x); PRAGMA user_version = 99;", NULL, NULL, NULL) == SQLITE_OK, "v99");
  sqlite3_close(h);
  palp_db *db;
  int rc = palp_db_open(p, 0, &db, err, sizeof err);
  CHECK(rc == PALP_DB_ENEWER, "newer file refused (rc %d)", rc);
  CHECK(strstr(err, "database schema version 99 is newer than this palp (5); upgrade palp") != NULL,
        "clear message, got: %s", err);
  palp_db_writer *w;
  err[0] = '\0';
  rc = palp_db_writer_open(p, NULL, &w, err, sizeof err);
  CHECK(rc == PALP_DB_ENEWER && strstr(err, "upgrade palp"), "writer refuses too: %s", err);
  /* ... and leaves the file untouched. */
  REQUIRE(sqlite3_open(p, &h) == SQLITE_OK, "open");
  CHECK(db_scalar(h, "PRAGMA user_version") == 99 && db_scalar(h, "SELECT count(*) FROM sqlite_master") == 1,
        "file untouched");
  sqlite3_close(h);
}

/* --- another program's database with a version number of its own: refused, untouched -----------
 * (session 75, found by review: a negative user_version ran every migration into it, and a version
 * 1..5 made its journal WAL for good before the migration found no palp table). Each file keeps its
 * version, its one table and its rollback journal (journal_mode 'delete'). */
static void test_foreign_versioned(void) {
  static const int versions[] = {-1, 3};
  for (int k = 0; k < 2; k++) {
    char p[600], err[512] = "", name[32];
    snprintf(name, sizeof name, "foreign%d.db", k);
    path_in(p, sizeof p, name);
    sqlite3 *h;
    REQUIRE(sqlite3_open(p, &h) == SQLITE_OK, "open");
    char sql[128];
    snprintf(sql, sizeof sql, "CREATE TABLE theirs(x); PRAGMA user_version = %d;", versions[k]);
    REQUIRE(sqlite3_exec(h, sql, NULL, NULL, NULL) == SQLITE_OK, "make version %d", versions[k]);
    sqlite3_close(h);
    palp_db_writer *w = NULL;
    const int rc = palp_db_writer_open(p, NULL, &w, err, sizeof err);
    CHECK(rc == PALP_EINVAL && strstr(err, "not a palp session log") && strstr(err, "left untouched"),
          "version %d: the writer refuses it (rc %d): %s", versions[k], rc, err);
    if (rc == 0) palp_db_writer_close(w);
    REQUIRE(sqlite3_open(p, &h) == SQLITE_OK, "open");
    CHECK(db_scalar(h, "PRAGMA user_version") == versions[k] && db_scalar(h, "SELECT count(*) FROM sqlite_master") == 1,
          "version %d: file untouched (version %lld, %lld objects)", versions[k],
          (long long)db_scalar(h, "PRAGMA user_version"), (long long)db_scalar(h, "SELECT count(*) FROM sqlite_master"));
    sqlite3_stmt *q;
    const char *mode = "?";
    if (sqlite3_prepare_v2(h, "PRAGMA journal_mode", -1, &q, NULL) == SQLITE_OK && sqlite3_step(q) == SQLITE_ROW)
      mode = (const char *)sqlite3_column_text(q, 0);
    CHECK(mode && !strcmp(mode, "delete"), "version %d: its journal mode stays 'delete' (got %s)", versions[k], mode);
    sqlite3_finalize(q);
    sqlite3_close(h);
  }
}

/* --- a full disk: the caller never fails except by EFULL, and the loss is reported ----------- */
static void test_full_disk(void) {
  char p[600], err[512];
  path_in(p, sizeof p, "full.db");
  palp_db_writer_opts o = palp_db_writer_default_opts();
  o.max_db_bytes = 160 * 1024; /* room for the schema and a few hundred rows */
  o.retry_backoff_s = 0.005;
  o.retry_limit = 1;
  palp_db_writer *w;
  REQUIRE(palp_db_writer_open(p, &o, &w, err, sizeof err) == 0, "open: %s", err);
  palp_db_session_def d = {.uid = "full-1", .scene_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
  palp_db_session s;
  REQUIRE(palp_db_log_session_begin(w, &d, &s) == 0, "begin");
  int bad = 0;
  for (int64_t i = 1; i <= 20000; i++) {
    palp_db_frame f = frame_of(i);
    int rc = palp_db_log_frame(w, s, &f);
    if (rc != 0 && rc != PALP_EFULL) bad++;
  }
  CHECK(bad == 0, "%d enqueue calls failed with something other than EFULL", bad);
  palp_db_writer_flush(w, 20);
  palp_db_writer_stats st;
  palp_db_writer_stats_get(w, &st);
  CHECK(st.failed > 0 && st.disk_errors > 0, "a full file must fail batches (failed %lld)", (long long)st.failed);
  CHECK((st.last_error_code & 0xff) == SQLITE_FULL && strstr(st.last_error, "full"), "last error: %s (%d)",
        st.last_error, st.last_error_code);
  CHECK(st.written + st.failed == st.enqueued, "every record is written or counted as failed (%lld + %lld vs %lld)",
        (long long)st.written, (long long)st.failed, (long long)st.enqueued);
  /* A flush returns once the losses are in the session's row as well: the grader reads that row's
   * count into a trainee's score right after its wait, and palp-review reads it later; they must agree.
   * Each round loses more records (the file stays full) and reads the row beside the writer. */
  sqlite3 *h;
  sqlite3_open_v2(p, &h, SQLITE_OPEN_READONLY, NULL);
  int stale = 0;
  long long row = -1;
  for (int round = 0; round < 8; round++) {
    for (int64_t i = 1; i <= 600; i++) {
      palp_db_frame f = frame_of(20000 + 600 * round + i);
      (void)palp_db_log_frame(w, s, &f);
    }
    palp_db_writer_flush(w, 20);
    palp_db_writer_stats_get(w, &st);
    row = db_scalar(h, "SELECT records_failed FROM session WHERE uid = 'full-1'");
    if (row != st.failed) stale++;
  }
  CHECK(stale == 0, "after each flush the session's row counts every lost record: %d of 8 rounds stale (last: row %lld, "
        "writer %lld)", stale, row, (long long)st.failed);
  sqlite3_close(h);
  palp_db_writer_close(w);
  sqlite3_open(p, &h);
  CHECK(db_scalar(h, "PRAGMA integrity_check") != -2, "integrity");
  sqlite3_stmt *q;
  sqlite3_prepare_v2(h, "PRAGMA integrity_check", -1, &q, NULL);
  CHECK(sqlite3_step(q) == SQLITE_ROW && !strcmp((const char *)sqlite3_column_text(q, 0), "ok"), "integrity ok");
  sqlite3_finalize(q);
  sqlite3_close(h);
}

/* --- a session's end lands even when its batch's frames do not (session 82 review, defect 1) ------
 * The file is filled to its cap (256 kB) with frames, 1,000 a batch; then 4,000 more frames and the session's end go
 * in one batch (a 30 s commit interval and a larger batch size: only the flush wakes the worker). The
 * frames cannot fit and the batch is dropped after its retries. Before session 82 the end went with
 * it: end_reason NULL for good. Now: the end as logged (reason, detail, time), none of the 4,000
 * frames in the file, and every frame either in the file or counted in the row (24,000 enqueued). */
static void test_end_survives_full(void) {
  char p[600], err[512];
  path_in(p, sizeof p, "end-full.db");
  palp_db_writer_opts o = palp_db_writer_default_opts();
  o.max_db_bytes = 256 * 1024;
  o.retry_backoff_s = 0.002;
  o.retry_limit = 1;
  o.commit_interval_s = 30;
  o.batch_records = 65536;
  palp_db_writer *w;
  REQUIRE(palp_db_writer_open(p, &o, &w, err, sizeof err) == 0, "open: %s", err);
  palp_db_session_def d = {.uid = "u-end", .trainee = "t", .scene_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
  palp_db_session s;
  REQUIRE(palp_db_log_session_begin(w, &d, &s) == 0, "begin");
  int bad = 0;
  for (int64_t i = 1; i <= 20000; i++) { /* in batches of 1,000: the file fills to its last pages */
    palp_db_frame f = frame_of(i);
    bad += palp_db_log_frame(w, s, &f) != 0;
    if (i % 1000 == 0) palp_db_writer_flush(w, 20);
  }
  palp_db_writer_stats st;
  palp_db_writer_stats_get(w, &st);
  REQUIRE(st.failed > 0, "the file must be full after 20,000 frames (failed %lld)", (long long)st.failed);
  for (int64_t i = 20001; i <= 24000; i++) {
    palp_db_frame f = frame_of(i);
    bad += palp_db_log_frame(w, s, &f) != 0;
  }
  CHECK(bad == 0, "every frame enqueued (%d refused)", bad);
  CHECK(palp_db_log_session_end(w, s, PALP_DB_END_NORMAL, "trainee left", 1765000000.25) == 0, "end enqueued");
  palp_db_writer_flush(w, 20);
  int64_t shed = -1, failed = -1;
  palp_db_writer_session_losses(w, s, &shed, &failed);
  palp_db_writer_close(w);
  sqlite3 *h;
  REQUIRE(sqlite3_open_v2(p, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK, "reopen");
  char reason[64], detail[64];
  db_text(h, "SELECT end_reason FROM session WHERE uid = 'u-end'", reason, sizeof reason);
  db_text(h, "SELECT end_detail FROM session WHERE uid = 'u-end'", detail, sizeof detail);
  CHECK(!strcmp(reason, "normal") && !strcmp(detail, "trainee left"), "the end as logged: reason '%s', detail '%s'",
        reason, detail);
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE uid = 'u-end' AND end_unix_s = 1765000000.25") == 1,
        "the end's time as logged");
  const long long late = db_scalar(h, "SELECT count(*) FROM frame WHERE frame > 20000");
  REQUIRE(late == 0, "the 4,000 frames after the fill did not fit (%lld in the file)", late);
  const long long in_file = db_scalar(h, "SELECT count(*) FROM frame");
  const long long row_failed = db_scalar(h, "SELECT records_failed FROM session WHERE uid = 'u-end'");
  CHECK(in_file + row_failed == 24000, "each of the 24,000 frames in the file or counted lost: %lld + %lld", in_file,
        row_failed);
  CHECK(row_failed == failed && shed == 0, "the row's count is the writer's (%lld vs %lld), none shed (%lld)",
        row_failed, (long long)failed, (long long)shed);
  sqlite3_close(h);
}

/* --- a begin whose uid is already in the file (session 82 review, defect 2) -------------------------
 * Three writers one after the other on one file, all with uid "run1-3". alice: frames 0-99, ended
 * normal. mallory (another trainee): frames 50-149, ended error "forged": before session 82 merged
 * into alice's row (her end and detail overwritten, 150 frames). Now refused: alice's row as she left
 * it, the 102 records of mallory's session (begin, 100 frames, end) counted failed, a reject event
 * and the writer's last error naming the uid. Then alice's session begun again by the same trainee,
 * station and phantom (palp-recorder restarted): frames 100-109 go on in her row. */
static int run_writer(const char *p, const char *trainee, int64_t f0, int64_t nf, palp_db_end_reason why,
                      const char *detail, palp_db_writer_stats *st, int64_t *failed) {
  char err[512];
  palp_db_writer *w;
  if (palp_db_writer_open(p, NULL, &w, err, sizeof err) != 0) return -1;
  palp_db_session_def d = {.uid = "run1-3", .trainee = trainee, .station = "st-1", .phantom_id = "7",
                           .scene_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
  palp_db_session s;
  int rc = palp_db_log_session_begin(w, &d, &s);
  for (int64_t i = f0; rc == 0 && i < f0 + nf; i++) {
    palp_db_frame f = frame_of(i);
    rc = palp_db_log_frame(w, s, &f);
  }
  if (rc == 0) rc = palp_db_log_session_end(w, s, why, detail, 1765000000.0 + (double)f0);
  palp_db_writer_flush(w, 20);
  palp_db_writer_stats_get(w, st);
  int64_t shed;
  palp_db_writer_session_losses(w, s, &shed, failed);
  palp_db_writer_close(w);
  return rc;
}

static void test_duplicate_uid(void) {
  char p[600];
  path_in(p, sizeof p, "dup-uid.db");
  palp_db_writer_stats st;
  int64_t failed;
  REQUIRE(run_writer(p, "alice", 0, 100, PALP_DB_END_NORMAL, "done", &st, &failed) == 0, "alice's writer");
  CHECK(st.written == 102 && failed == 0, "alice: 102 records written (%lld), none failed (%lld)", (long long)st.written,
        (long long)failed);
  REQUIRE(run_writer(p, "mallory", 50, 100, PALP_DB_END_ERROR, "forged", &st, &failed) == 0, "mallory's writer");
  CHECK(failed == 102 && st.failed == 102, "mallory: begin, 100 frames and end counted failed (session %lld, writer %lld)",
        (long long)failed, (long long)st.failed);
  CHECK(strstr(st.last_error, "run1-3") != NULL, "the writer's last error names the uid: \"%s\"", st.last_error);
  sqlite3 *h;
  REQUIRE(sqlite3_open_v2(p, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK, "reopen");
  char t[64], reason[64], detail[64];
  db_text(h, "SELECT trainee FROM session WHERE uid = 'run1-3'", t, sizeof t);
  db_text(h, "SELECT end_reason FROM session WHERE uid = 'run1-3'", reason, sizeof reason);
  db_text(h, "SELECT end_detail FROM session WHERE uid = 'run1-3'", detail, sizeof detail);
  CHECK(db_scalar(h, "SELECT count(*) FROM session") == 1 && !strcmp(t, "alice"), "one session row, alice's ('%s')", t);
  CHECK(!strcmp(reason, "normal") && !strcmp(detail, "done"), "alice's end kept: '%s' '%s'", reason, detail);
  CHECK(db_scalar(h, "SELECT records_failed FROM session") == 0, "alice's row counts none of mallory's losses");
  CHECK(db_scalar(h, "SELECT count(*) FROM frame") == 100 && db_scalar(h, "SELECT max(frame) FROM frame") == 99,
        "alice's 100 frames only, 0-99");
  CHECK(db_scalar(h, "SELECT count(*) FROM event WHERE kind = 'reject' AND session_id IS NULL AND "
                     "detail LIKE '%\"run1-3\"%mallory%'") == 1,
        "a session-less reject event names the uid and the refused trainee");
  sqlite3_close(h);
  REQUIRE(run_writer(p, "alice", 100, 10, PALP_DB_END_NORMAL, "again", &st, &failed) == 0, "alice's again");
  CHECK(failed == 0 && st.written == 12, "the same session begun again: nothing failed (%lld), 12 written (%lld)",
        (long long)failed, (long long)st.written);
  REQUIRE(sqlite3_open_v2(p, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK, "reopen");
  CHECK(db_scalar(h, "SELECT count(*) FROM session") == 1 && db_scalar(h, "SELECT count(*) FROM frame") == 110,
        "it goes on in alice's row: 1 session, 110 frames");
  sqlite3_close(h);
}

/* --- a mesh's byte length (session 82 review, defect 4) ----------------------------------------------
 * 2,147,483,647 / 24 = 89,478,485 vertices is the most whose blob (24 bytes a vertex) stays within an
 * int. One more is refused as PALP_EINVAL before anything is copied (the caller's array here holds one
 * vertex: before session 82 the call copied 2 GiB from it). A 1,000-vertex mesh still goes in whole:
 * 24,000 bytes. */
static void test_mesh_bound(void) {
  char p[600], err[512];
  path_in(p, sizeof p, "mesh-bound.db");
  palp_db_writer *w;
  REQUIRE(palp_db_writer_open(p, NULL, &w, err, sizeof err) == 0, "open: %s", err);
  palp_db_session_def d = {.uid = "mesh-1", .scene_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
  palp_db_session s;
  REQUIRE(palp_db_log_session_begin(w, &d, &s) == 0, "begin");
  static palp_vec3 one[1];
  CHECK(palp_db_log_mesh(w, s, 1, one, 89478486) == PALP_EINVAL, "89,478,486 vertices refused");
  static palp_vec3 pos[1000];
  for (int v = 0; v < 1000; v++) pos[v] = (palp_vec3){1e-3 * v, -2e-3 * v, 0.5};
  CHECK(palp_db_log_mesh(w, s, 2, pos, 1000) == 0, "1,000 vertices taken");
  palp_db_writer_close(w);
  sqlite3 *h;
  REQUIRE(sqlite3_open_v2(p, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK, "reopen");
  CHECK(db_scalar(h, "SELECT count(*) FROM mesh") == 1, "one mesh in the file");
  CHECK(db_scalar(h, "SELECT length(positions_m) FROM mesh WHERE vertex_count = 1000 AND frame = 2") == 24000,
        "its blob 24,000 bytes");
  sqlite3_close(h);
}

/* --- WAL confirmed at open (session 82 review, defect 5) ---------------------------------------------
 * SQLite answers a refused journal-mode change with the mode it kept, not an error. An in-memory
 * database (a URI with mode=memory; this SQLite is built with USE_URI) keeps "memory": the writer must
 * refuse it, naming that mode, where it used to run on without WAL. A file opens, and is in WAL. */
static void test_wal_confirmed(void) {
  char uri[700], err[512] = "";
  snprintf(uri, sizeof uri, "file:%s/wal-mem.db?mode=memory&cache=private", dir);
  palp_db_writer *w = NULL;
  const int rc = palp_db_writer_open(uri, NULL, &w, err, sizeof err);
  CHECK(rc != 0 && w == NULL, "a database that keeps journal mode \"memory\" is refused (rc %d)", rc);
  CHECK(strstr(err, "\"memory\"") && strstr(err, "WAL"), "the error names the mode kept: \"%s\"", err);
  if (w) palp_db_writer_close(w);
  char p[600];
  path_in(p, sizeof p, "wal-file.db");
  REQUIRE(palp_db_writer_open(p, NULL, &w, err, sizeof err) == 0, "a file opens: %s", err);
  sqlite3 *h;
  REQUIRE(sqlite3_open_v2(p, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK, "reopen");
  char mode[32];
  db_text(h, "PRAGMA journal_mode", mode, sizeof mode);
  CHECK(!strcmp(mode, "wal"), "the file is in WAL ('%s')", mode);
  sqlite3_close(h);
  palp_db_writer_close(w);
}

/* --- a session that begins while the file is full gets its row once space is back ------------
 * A batch that fails on a full file fails at its first record and is dropped after its retries. A
 * session's begin behind another session's mesh in such a batch was never reached: until session 75
 * its strings were freed with the batch, and every later record of that session was refused even
 * after the instructor freed space (here: another connection deletes the first session's meshes), so
 * the session never got its row. Five sessions begin behind a mesh of the first while the file is
 * full, then log 10 frames each and end once it has room: each must have its row, its 10 frames and
 * its end (exact counts). */
static void test_full_disk_new_session(void) {
  char p[600], err[512];
  path_in(p, sizeof p, "full-new.db");
  palp_db_writer_opts o = palp_db_writer_default_opts();
  o.max_db_bytes = 160 * 1024;
  o.retry_backoff_s = 0.02;
  o.retry_limit = 1;
  palp_db_writer *w;
  REQUIRE(palp_db_writer_open(p, &o, &w, err, sizeof err) == 0, "open: %s", err);
  palp_db_session_def d = {.uid = "fill-1", .scene_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
  palp_db_session a;
  REQUIRE(palp_db_log_session_begin(w, &d, &a) == 0, "begin");
  int64_t i = 1;
  palp_db_writer_stats st;
  /* fill the file with meshes (338 vertices: 8 kB each, overflow pages): once one fails, the file has
   * no room for another, so every batch that starts with a mesh fails at it */
  enum { NV = 338 };
  static palp_vec3 mesh[NV];
  for (int v = 0; v < NV; v++) mesh[v] = (palp_vec3){1e-3 * v, 2e-3 * v, 3e-3 * v};
  for (int round = 0; round < 100; round++) {
    for (int k = 0; k < 4; k++, i++) (void)palp_db_log_mesh(w, a, i, mesh, NV);
    palp_db_writer_flush(w, 20);
    palp_db_writer_stats_get(w, &st);
    if (st.disk_errors > 0) break;
  }
  REQUIRE(st.disk_errors > 0, "the file must fill (%lld disk errors)", (long long)st.disk_errors);
  enum { NEW = 5 };
  palp_db_session b[NEW];
  char uid[NEW][32];
  for (int k = 0; k < NEW; k++) { /* each begin behind a mesh of the first session, in one batch */
    (void)palp_db_log_mesh(w, a, i++, mesh, NV);
    snprintf(uid[k], sizeof uid[k], "late-%d", k);
    palp_db_session_def e = {.uid = uid[k], .trainee = "ida", .scene_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
    REQUIRE(palp_db_log_session_begin(w, &e, &b[k]) == 0, "begin %s", uid[k]);
    for (int64_t j = 1; j <= 3; j++) {
      palp_db_frame g = frame_of(j);
      (void)palp_db_log_frame(w, b[k], &g);
    }
  }
  palp_db_writer_flush(w, 20);
  palp_db_writer_stats_get(w, &st);
  const long long failed_full = (long long)st.failed;
  sqlite3 *h;
  REQUIRE(sqlite3_open(p, &h) == SQLITE_OK, "open a second connection");
  sqlite3_busy_timeout(h, 5000);
  /* Since session 82 a dropped batch's begins get a transaction of their own (a session row may fit where
   * a mesh does not), so the late sessions' rows may already be in; their frames are not. */
  CHECK(db_scalar(h, "SELECT count(*) FROM frame JOIN session ON session.id = frame.session_id "
                     "WHERE uid LIKE 'late-%'") == 0,
        "while the file is full no late session has a frame yet");
  CHECK(sqlite3_exec(h, "DELETE FROM mesh", NULL, NULL, NULL) == SQLITE_OK, "free space: %s", sqlite3_errmsg(h));
  for (int k = 0; k < NEW; k++) {
    for (int64_t j = 4; j <= 13; j++) {
      palp_db_frame g = frame_of(j);
      CHECK(palp_db_log_frame(w, b[k], &g) == 0, "frame %lld of %s", (long long)j, uid[k]);
    }
    CHECK(palp_db_log_session_end(w, b[k], PALP_DB_END_NORMAL, NULL, (double)time(NULL)) == 0, "end %s", uid[k]);
  }
  palp_db_writer_flush(w, 20);
  palp_db_writer_stats_get(w, &st);
  CHECK((long long)st.failed == failed_full, "nothing more is lost once there is room (%lld failed, %lld before)",
        (long long)st.failed, failed_full);
  for (int k = 0; k < NEW; k++) {
    char q[256];
    snprintf(q, sizeof q, "SELECT count(*) FROM session WHERE uid = '%s' AND trainee = 'ida' AND end_reason = 'normal'",
             uid[k]);
    CHECK(db_scalar(h, q) == 1, "%s has its row, its trainee and its end", uid[k]);
    snprintf(q, sizeof q, "SELECT count(*) FROM frame JOIN session ON session.id = frame.session_id WHERE uid = '%s'",
             uid[k]);
    const long long n = db_scalar(h, q);
    CHECK(n == 10, "%s has the 10 frames logged once there was room (%lld)", uid[k], n);
  }
  sqlite3_close(h);
  palp_db_writer_close(w);
}

/* The valid_range event's detail (db/valid_range.c): written and read back, and what a
 * damaged or forged row says refused rather than summed. */
static void test_valid_range_detail(void) {
  const palp_db_valid_range r = {.steps = 1234, .depth_steps = 1200, .skin_steps = 40, .limit_steps = 3,
                                 .deepest_m = 0.00241};
  char d[200];
  palp_db_valid_range_format(&r, d, sizeof d);
  CHECK(!strcmp(d, "outside at 1234 steps: depth 1200, skin 40, limit 3; deepest 2.41 mm beyond the validated "
                   "depth so far"),
        "the detail reads '%s'", d);
  palp_db_valid_range b;
  CHECK(palp_db_valid_range_parse(d, 1234, &b) == 0 && b.steps == 1234 && b.depth_steps == 1200 &&
            b.skin_steps == 40 && b.limit_steps == 3 && fabs(b.deepest_m - 0.00241) < 1e-12,
        "read back: %lld %lld %lld %lld %g", (long long)b.steps, (long long)b.depth_steps, (long long)b.skin_steps,
        (long long)b.limit_steps, b.deepest_m);
  static const struct { const char *detail; int64_t count; const char *why; } bad[] = {
      {"outside at 1234 steps: depth 1200, skin 40, limit 3; deepest 2.41 mm beyond the validated depth so far", 1233,
       "the row's count differs from its steps"},
      {"outside at 10 steps: depth 11, skin 0, limit 0; deepest 1.00 mm beyond the validated depth so far", 10,
       "more depth steps than steps"},
      {"outside at 10 steps: depth 2, skin 3, limit 4; deepest 1.00 mm beyond the validated depth so far", 10,
       "parts that do not cover the steps"},
      {"outside at 10 steps: depth -1, skin 10, limit 0; deepest 1.00 mm beyond the validated depth so far", 10,
       "a negative part"},
      {"outside at 10 steps: depth 10, skin 0, limit 0; deepest nan mm beyond the validated depth so far", 10,
       "a depth that is not a number"},
      {"outside at 10 steps: depth 10, skin 0, limit 0; deepest 5000 mm beyond the validated depth so far", 10,
       "an excess of 5 m on a 40 mm dome"},
      {"outside at 10 steps: depth 10, skin 0, limit 0; deepest 1.00 mm beyond the validated depth so far; DROP", 10,
       "trailing text"},
      {"outside at 0 steps: depth 0, skin 0, limit 0; deepest 0.00 mm beyond the validated depth so far", 0,
       "no steps"},
      {"outside at 2000000000000 steps: depth 2000000000000, skin 0, limit 0; deepest 1.00 mm beyond the validated "
       "depth so far", 2000000000000LL, "more steps than 31 years at 1 kHz"},
      {"outside at 99999999999999999999 steps: depth 1, skin 0, limit 0; deepest 1.00 mm beyond the validated "
       "depth so far", 1, "a number past int64"},
      {"outside at many steps", 5, "not this format"},
      {"", 1, "empty"},
      /* the literal gel law's part (2026-12-06) */
      {"outside at 10 steps: depth 0, skin 0, limit 0, gel 0; deepest 0.00 mm beyond the validated depth so far; "
       "gel momentum left out at 0 frames", 10, "gel 0 (written the old way): parts that do not cover the steps"},
      {"outside at 10 steps: depth 10, skin 0, limit 0, gel 0; deepest 0.00 mm beyond the validated depth so far; "
       "gel momentum left out at 0 frames", 10, "gel 0 with the gel tail (not what the writer writes)"},
      {"outside at 10 steps: depth 0, skin 0, limit 0, gel 11; deepest 0.00 mm beyond the validated depth so far; "
       "gel momentum left out at 20 frames", 10, "more gel steps than steps"},
      {"outside at 10 steps: depth 0, skin 0, limit 0, gel 10; deepest 0.00 mm beyond the validated depth so far; "
       "gel momentum left out at 9 frames", 10, "fewer gel frames than gel steps"},
      {"outside at 10 steps: depth 0, skin 0, limit 0, gel 10; deepest 0.00 mm beyond the validated depth so far; "
       "gel momentum left out at 2000000000000 frames", 10, "more gel frames than 31 years of steps"},
      {"outside at 10 steps: depth 0, skin 0, limit 0, gel 10; deepest 0.00 mm beyond the validated depth so far",
       10, "the gel part without its frames"},
      {"outside at 10 steps: depth 10, skin 0, limit 0; deepest 0.00 mm beyond the validated depth so far; gel "
       "momentum left out at 4 frames", 10, "gel frames without the gel part"},
      {"outside at 10 steps: depth 0, skin 0, limit 0, gel 10; deepest 0.00 mm beyond the validated depth so far; "
       "gel momentum left out at 12 frames; DROP", 10, "trailing text after the gel tail"}};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
    CHECK(palp_db_valid_range_parse(bad[i].detail, bad[i].count, &b) == PALP_EINVAL, "refused: %s", bad[i].why);
  CHECK(palp_db_valid_range_parse(NULL, 1, &b) == PALP_EINVAL, "refused: no detail");
  /* The literal gel law's steps outside its stable range (2026-12-06): a part of their own, the
   * frames in the tail; a detail without them is the old one word for word (above). */
  const palp_db_valid_range g = {.steps = 12, .depth_steps = 0, .skin_steps = 9, .limit_steps = 1, .deepest_m = 0,
                                 .gel_steps = 4, .gel_frames = 11};
  palp_db_valid_range_format(&g, d, sizeof d);
  CHECK(!strcmp(d, "outside at 12 steps: depth 0, skin 9, limit 1, gel 4; deepest 0.00 mm beyond the validated "
                   "depth so far; gel momentum left out at 11 frames"),
        "with gel: the detail reads '%s'", d);
  CHECK(palp_db_valid_range_parse(d, 12, &b) == 0 && b.steps == 12 && b.skin_steps == 9 && b.limit_steps == 1 &&
            b.depth_steps == 0 && b.gel_steps == 4 && b.gel_frames == 11 && b.deepest_m == 0,
        "with gel: read back: %lld steps, gel %lld steps %lld frames", (long long)b.steps, (long long)b.gel_steps,
        (long long)b.gel_frames);
  /* a step outside by the gel law alone is a step outside */
  const palp_db_valid_range only = {.steps = 3, .gel_steps = 3, .gel_frames = 7};
  palp_db_valid_range_format(&only, d, sizeof d);
  CHECK(palp_db_valid_range_parse(d, 3, &b) == 0 && b.steps == 3 && b.gel_steps == 3 && b.gel_frames == 7 &&
            b.depth_steps + b.skin_steps + b.limit_steps == 0,
        "gel only: '%s' read back", d);
  /* and the old detail reads with no gel part */
  CHECK(palp_db_valid_range_parse("outside at 100 steps: depth 60, skin 50, limit 3; deepest 2.41 mm beyond the "
                                  "validated depth so far", 100, &b) == 0 &&
            b.gel_steps == 0 && b.gel_frames == 0 && b.steps == 100,
        "the detail of before reads with no gel part");
}

/* The debrief event's detail (db/debrief.c): each level written as the docs say and read back,
 * and rows that contradict themselves or were not written by it refused. */
static void test_debrief_detail(void) {
  char d[400];
  palp_db_debrief b;
  const palp_db_debrief lesions = {.sent = 1, .level = PALP_DB_DEBRIEF_LESIONS, .lesions = 3, .found = 2, .marks = 4,
                                   .false_marks = 1, .duplicates = 1, .listed = 3, .found_by = {2, 0, 4000000000u}};
  CHECK(palp_db_debrief_format(&lesions, d, sizeof d) > 0 &&
            !strcmp(d, "told at level lesions: found 2 of 3 lesions; marks standing 4, near no lesion 1, duplicates 1; "
                       "found by marks 2 0 4000000000"),
        "lesions: '%s'", d);
  CHECK(palp_db_debrief_parse(d, &b) == 0 && b.sent && b.level == PALP_DB_DEBRIEF_LESIONS && b.lesions == 3 &&
            b.found == 2 && b.marks == 4 && b.false_marks == 1 && b.duplicates == 1 && b.listed == 3 &&
            b.found_by[0] == 2 && b.found_by[1] == 0 && b.found_by[2] == 4000000000u,
        "  read back");
  const palp_db_debrief count = {.sent = 1, .level = PALP_DB_DEBRIEF_COUNT, .lesions = 2, .found = 0, .marks = 1,
                                 .false_marks = 1};
  CHECK(palp_db_debrief_format(&count, d, sizeof d) > 0 &&
            !strcmp(d, "told at level count: found 0 of 2 lesions; marks standing 1, near no lesion 1, duplicates 0"),
        "count: '%s'", d);
  CHECK(palp_db_debrief_parse(d, &b) == 0 && b.level == PALP_DB_DEBRIEF_COUNT && b.lesions == 2 && b.listed == 0,
        "  read back");
  const palp_db_debrief none = {.sent = 1, .level = PALP_DB_DEBRIEF_NONE, .marks = 63};
  CHECK(palp_db_debrief_format(&none, d, sizeof d) > 0 && !strcmp(d, "told at level none: marks standing 63"),
        "none: '%s'", d);
  CHECK(palp_db_debrief_parse(d, &b) == 0 && b.sent && b.level == PALP_DB_DEBRIEF_NONE && b.marks == 63, "  read back");
  palp_db_debrief unsent = {.sent = 0, .level = PALP_DB_DEBRIEF_LESIONS};
  snprintf(unsent.why, sizeof unsent.why, "DDS refused the write: Error");
  CHECK(palp_db_debrief_format(&unsent, d, sizeof d) > 0 && !strcmp(d, "not sent (level lesions): DDS refused the write: Error"),
        "not sent: '%s'", d);
  CHECK(palp_db_debrief_parse(d, &b) == 0 && !b.sent && b.level == PALP_DB_DEBRIEF_LESIONS &&
            !strcmp(b.why, "DDS refused the write: Error"),
        "  read back");
  /* a debrief that contradicts itself is not written either */
  const palp_db_debrief liar = {.sent = 1, .level = PALP_DB_DEBRIEF_LESIONS, .lesions = 2, .found = 2, .marks = 1,
                                .listed = 2, .found_by = {1, 0}};
  CHECK(palp_db_debrief_format(&liar, d, sizeof d) == PALP_EINVAL, "format refuses found 2 with one lesion found by a mark");
  static const struct { const char *detail, *why; } bad[] = {
      {"told at level lesions: found 2 of 1 lesions; marks standing 4, near no lesion 1, duplicates 0; found by marks 1",
       "more found than lesions"},
      {"told at level lesions: found 1 of 2 lesions; marks standing 4, near no lesion 1, duplicates 0; found by marks 1",
       "fewer lesions listed than counted"},
      {"told at level lesions: found 2 of 2 lesions; marks standing 4, near no lesion 1, duplicates 0; found by marks 1 0",
       "found not the count of found_by"},
      {"told at level lesions: found 1 of 9 lesions; marks standing 4, near no lesion 1, duplicates 0; found by marks 1 0 0 "
       "0 0 0 0 0 0",
       "nine lesions (the wire carries eight)"},
      {"told at level count: found 1 of 2 lesions; marks standing 1, near no lesion 2, duplicates 0",
       "more marks near no lesion than marks"},
      {"told at level count: found 1 of 2 lesions; marks standing 1, near no lesion 0, duplicates 0; found by marks 1 0",
       "lesions listed at level count"},
      {"told at level count: found -1 of 2 lesions; marks standing 1, near no lesion 0, duplicates 0", "a sign"},
      {"told at level count: found 1 of 2 lesions; marks standing 99999999999, near no lesion 0, duplicates 0",
       "a number past int"},
      {"told at level count: found 01 of 2 lesions; marks standing 1, near no lesion 0, duplicates 0", "a leading zero"},
      {"told at level lesions: found 1 of 1 lesions; marks standing 1, near no lesion 0, duplicates 0; found by marks 4294967296",
       "a mark past uint32"},
      {"told at level lesions: found 1 of 1 lesions; marks standing 1, near no lesion 0, duplicates 0; found by marks  1",
       "two spaces"},
      {"told at level none: marks standing 3; found 1", "trailing text"},
      {"told at level all: marks standing 3", "an unknown level"},
      {"not sent (level lesions): ", "not sent without a reason"},
      {"not sent (level most): permissions", "not sent at an unknown level"},
      {"", "empty"}};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
    CHECK(palp_db_debrief_parse(bad[i].detail, &b) == PALP_EINVAL, "refused: %s", bad[i].why);
  CHECK(palp_db_debrief_parse(NULL, &b) == PALP_EINVAL, "refused: no detail");
}

/* --- peers DDS Security refused: server-wide events, summed per peer by the reader ---------- */
static void test_refused(void) {
  char p[600], err[512];
  path_in(p, sizeof p, "refused.db");
  palp_db_writer *w;
  palp_db_writer_opts o = palp_db_writer_default_opts();
  REQUIRE(palp_db_writer_open(p, &o, &w, err, sizeof err) == 0, "open: %s", err);
  /* As palp-server logs them: the first refusal, then the repeats summed (1 + 59 + 12), and
   * another peer once; none belongs to a session. */
  const char *mallory = "trainee/mallory: certificate revoked (handshake)";
  const char *other = "participant 1:2:3:4: permissions not signed by the classroom (self-signed certificate) "
                      "(permissions)";
  CHECK(palp_db_log_event(w, 0, PALP_DB_EVENT_SECURITY_REFUSED, -1, mallory, 1) == 0 &&
            palp_db_log_event(w, 0, PALP_DB_EVENT_SECURITY_REFUSED, -1, other, 1) == 0 &&
            palp_db_log_event(w, 0, PALP_DB_EVENT_SECURITY_REFUSED, -1, mallory, 59) == 0 &&
            palp_db_log_event(w, 0, PALP_DB_EVENT_SECURITY_REFUSED, -1, mallory, 12) == 0,
        "four server-wide refusal events enqueued");
  palp_db_writer_flush(w, 10);
  palp_db_writer_close(w);
  palp_db *db;
  REQUIRE(palp_db_open(p, 0, &db, err, sizeof err) == 0, "open: %s", err);
  palp_db_refused *v;
  int n;
  REQUIRE(palp_db_list_refused(db, NULL, &v, &n) == 0, "list refused");
  CHECK(n == 2 && !strcmp(v[0].detail, mallory) && v[0].count == 72 && !strcmp(v[1].detail, other) &&
            v[1].count == 1 && v[0].first_unix_s <= v[0].last_unix_s,
        "two peers, most refused first: %d rows, %s %lld", n, n ? v[0].detail : "-", n ? (long long)v[0].count : 0);
  free(v);
  palp_db_filter later = {.since_unix_s = 4102444800.0, .has_since = 1}; /* 2100-01-01: after every event */
  CHECK(palp_db_list_refused(db, &later, &v, &n) == 0 && n == 0, "none after their time (%d)", n);
  free(v);
  CHECK(db_scalar(palp_db_handle(db), "SELECT count(*) FROM event WHERE session_id IS NOT NULL") == 0,
        "none is tied to a session");
  palp_db_close(db);
}

/* The disk stalled as a reviewer stalled it (2026-12-07): another connection holds the file in BEGIN
 * EXCLUSIVE, so the writer's worker waits in its busy handler and retires nothing, until release_disk. */
static sqlite3 *stall_disk(const char *path) {
  sqlite3 *lock = NULL;
  REQUIRE(sqlite3_open(path, &lock) == SQLITE_OK && sqlite3_exec(lock, "BEGIN EXCLUSIVE", NULL, NULL, NULL) == SQLITE_OK,
          "another connection holds the file: %s", sqlite3_errmsg(lock));
  return lock;
}

static void release_disk(sqlite3 *lock) {
  sqlite3_exec(lock, "COMMIT", NULL, NULL, NULL);
  sqlite3_close(lock);
}

/* --- a session's end is taken while meshes fill the queue's bytes ----------------------------------
 * The disk stalled as the reviewer stalled it (2026-12-07): another connection holds BEGIN EXCLUSIVE,
 * so the worker waits in its busy handler (5 s) and retires nothing. Meshes of 1,000 vertices (24 kB),
 * then smaller ones, fill a 256 kB byte cap to within 24 bytes; then the session's event and its end must be taken
 * (before, the end was refused like a mesh and the session stayed "(running)"), a mesh still refused
 * (data never use the reserve), and 256 kB session-less events taken at most 16 times (the 4 MiB
 * reserve / 256 kB) before one is refused. Once the lock goes: the end and its detail in the row. */
static void test_control_bytes(void) {
  char p[600], err[512];
  path_in(p, sizeof p, "control-bytes.db");
  palp_db_writer_opts o = palp_db_writer_default_opts();
  o.queue_max_bytes = 256 * 1024;
  palp_db_writer *w;
  REQUIRE(palp_db_writer_open(p, &o, &w, err, sizeof err) == 0, "open: %s", err);
  palp_db_session_def d = {.uid = "control-bytes-1", .scene_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
  palp_db_session s;
  REQUIRE(palp_db_log_session_begin(w, &d, &s) == 0, "begin");
  REQUIRE(palp_db_writer_flush(w, 10) == 0, "flush the begin");
  sqlite3 *lock = stall_disk(p);
  enum { NV = 1000 };
  static palp_vec3 pos[NV];
  int meshes = 0, refused = 0, frame = 0;
  /* to the byte: meshes of 1,000 vertices, then 100, 10 and 1 (24 bytes) until each is refused */
  for (int n = NV; n >= 1; n /= 10) {
    int no = 0;
    while (!no && frame < 1000) {
      const int rc = palp_db_log_mesh(w, s, ++frame, pos, n);
      if (rc == 0) meshes += n == NV;
      else no = refused = rc == PALP_EFULL;
    }
  }
  CHECK(refused && meshes >= 1 && meshes <= 11, "meshes fill a 256 kB queue to within 24 bytes: %d of 24 kB taken, "
        "then refused (%d)", meshes, refused);
  const int ev = palp_db_log_event(w, s, PALP_DB_EVENT_LEAVE, frame, "trainee station lost (liveliness lease expired)", 1);
  const int end = palp_db_log_session_end(w, s, PALP_DB_END_NORMAL, "exercise time limit reached", 0);
  CHECK(ev == 0 && end == 0, "with the queue's bytes full of meshes, the session's leave event (%d) and end (%d) are "
        "taken (0), not refused (%d)", ev, end, PALP_EFULL);
  palp_db_session s2;
  palp_db_session_def d2 = d;
  d2.uid = "control-bytes-2";
  REQUIRE(palp_db_log_session_begin(w, &d2, &s2) == 0, "a second session begins (a control record)");
  CHECK(palp_db_log_mesh(w, s2, 1, pos, NV) == PALP_EFULL, "a mesh is still refused: data never use the reserve");
  static char big[256 * 1024];
  memset(big, 'x', sizeof big - 1);
  int big_taken = 0, big_refused = 0;
  for (int i = 0; i < 40 && !big_refused; i++) {
    const int rc = palp_db_log_event(w, 0, PALP_DB_EVENT_INFO, -1, big, 1);
    if (rc == 0) big_taken++;
    else big_refused = rc == PALP_EFULL;
  }
  printf("control bytes: %d meshes of 24 kB taken before one was refused; %d events of 256 kB over the cap\n", meshes,
         big_taken);
  CHECK(big_refused && big_taken >= 1 && big_taken <= 16, "256 kB events over the byte cap: %d taken, then refused "
        "(%d): the reserve is bounded (4 MiB)", big_taken, big_refused);
  release_disk(lock);
  palp_db_writer_flush(w, 20);
  palp_db_writer_close(w);
  sqlite3 *h;
  REQUIRE(sqlite3_open(p, &h) == SQLITE_OK, "open");
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE uid = 'control-bytes-1' AND end_reason = 'normal' AND "
                     "end_detail = 'exercise time limit reached'") == 1,
        "the session's end and its detail in its row");
  CHECK(db_scalar(h, "SELECT count(*) FROM event e JOIN session s ON s.id = e.session_id WHERE s.uid = "
                     "'control-bytes-1' AND e.kind = 'leave'") == 1,
        "its leave event in the log");
  sqlite3_close(h);
}

/* --- a session's end is never refused (session 81) -----------------------------------------------
 * The disk stalled as in test_control_bytes; three sessions begun, then session-less events fill every
 * ring slot (1,088: 64 + the 1,024 control slots) until one is refused. Each session's end must still
 * be taken, its 2 kB detail cut to 510 bytes, before a character the 511-byte cut would split (before:
 * refused as PALP_EFULL and counted as shed in the session's own row, which stayed "(running)"); a
 * fourth begin is refused (its end would have no slot). Once the lock goes: three ends in their rows,
 * records_shed 0 for each, the writer's shed count exactly the refused event and begin. */
static void test_end_kept(void) {
  char p[600], err[512];
  path_in(p, sizeof p, "end-kept.db");
  palp_db_writer_opts o = palp_db_writer_default_opts();
  o.queue_capacity = 64;
  o.queue_max_bytes = 64 * 1024;
  palp_db_writer *w;
  REQUIRE(palp_db_writer_open(p, &o, &w, err, sizeof err) == 0, "open: %s", err);
  palp_db_session s[3];
  char uid[3][32];
  for (int i = 0; i < 3; i++) {
    snprintf(uid[i], sizeof uid[i], "end-kept-%d", i + 1);
    palp_db_session_def d = {.uid = uid[i], .scene_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
    REQUIRE(palp_db_log_session_begin(w, &d, &s[i]) == 0, "begin %d", i + 1);
  }
  REQUIRE(palp_db_writer_flush(w, 10) == 0, "flush the begins");
  sqlite3 *lock = stall_disk(p);
  int small = 0, refused = 0;
  for (int i = 0; i < 5000 && !refused; i++) {
    const int rc = palp_db_log_event(w, 0, PALP_DB_EVENT_INFO, -1, "x", 1);
    if (rc == 0) small++;
    else refused = rc == PALP_EFULL;
  }
  /* 1,088 slots less the three kept for the ends */
  CHECK(refused && small == 64 + 1024 - 3, "session-less events fill the ring's slots: %d taken (want %d), then "
        "refused (%d)", small, 64 + 1024 - 3, refused);
  palp_db_session_def d4 = {.uid = "end-kept-4", .scene_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
  palp_db_session s4;
  CHECK(palp_db_log_session_begin(w, &d4, &s4) == PALP_EFULL, "a fourth session's begin is refused: no slot "
        "for its end");
  static char detail[2048];
  memset(detail, 'a', sizeof detail - 1);
  memcpy(detail + 510, "\xc3\xa9", 2); /* an e-acute across the 511-byte cut (bytes 510-511): cut before it */
  int ends_ok = 0;
  for (int i = 0; i < 3; i++) ends_ok += palp_db_log_session_end(w, s[i], PALP_DB_END_NORMAL, detail, 0) == 0;
  CHECK(ends_ok == 3, "with every slot taken, the three sessions' ends are taken: %d of 3", ends_ok);
  palp_db_writer_stats st;
  palp_db_writer_stats_get(w, &st);
  CHECK(st.shed == 2, "the writer shed exactly the refused event and the refused begin: %lld (want 2)",
        (long long)st.shed);
  release_disk(lock);
  palp_db_writer_flush(w, 20);
  palp_db_writer_close(w);
  sqlite3 *h;
  REQUIRE(sqlite3_open(p, &h) == SQLITE_OK, "open");
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE uid LIKE 'end-kept-%' AND end_reason = 'normal' AND "
                     "length(CAST(end_detail AS BLOB)) = 510 AND records_shed = 0") == 3,
        "three ends in their rows, each detail cut to 510 bytes (before the 2-byte character at 510), none shed");
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE uid = 'end-kept-4'") == 0, "no row for the refused begin");
  sqlite3_close(h);
}

/* --- how a session ended, from palp-server's close reason ---------------------------------------
 * Every reason server/server.c closes a session with (close_session's callers: station_leave's
 * "trainee station " + its reason, a held session's "...; not back within N s", the model's failure,
 * the time limit, the tick pool, the identity conflict, the shutdown), classed by hand. palp-server's
 * own log and palp-recorder's call the one function; until 2026-12-07 the recorder had its own, which
 * said normal for "model step failed: ..." and "tick pool full". */
static void test_end_reason_of(void) {
  static const struct {
    const char *reason;
    palp_db_end_reason want;
  } cases[] = {
      {"trainee station left", PALP_DB_END_NORMAL},
      {"trainee station re-joined", PALP_DB_END_NORMAL},
      {"trainee station left (request disposed)", PALP_DB_END_NORMAL},
      {"exercise time limit reached", PALP_DB_END_NORMAL},
      {"trainee station lost (liveliness lease expired)", PALP_DB_END_STATION_VANISHED},
      {"trainee station lost (its request writer is gone)", PALP_DB_END_STATION_VANISHED},
      {"trainee station lost (liveliness lease expired); not back within 10 s", PALP_DB_END_STATION_VANISHED},
      {"model step failed: state became non-finite", PALP_DB_END_ERROR},
      {"model step failed: sparse factorisation failed", PALP_DB_END_ERROR},
      {"tick pool full", PALP_DB_END_ERROR},
      {"server identity conflict", PALP_DB_END_ERROR},
      {"server shutdown", PALP_DB_END_SERVER_SHUTDOWN},
      {"", PALP_DB_END_NORMAL},
      {NULL, PALP_DB_END_NORMAL},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    const palp_db_end_reason got = palp_db_end_reason_of(cases[i].reason);
    CHECK(got == cases[i].want, "end reason of \"%s\": %s, want %s", cases[i].reason ? cases[i].reason : "(null)",
          palp_db_end_reason_name(got), palp_db_end_reason_name(cases[i].want));
  }
}

/* A session found by its exact uid is found through the uid index, not a scan of every uid: delete
 * resolves each name it is given this way, and 10,000 names on a 10,000-session log were 10^8 uid
 * comparisons (2026-12-06: 97 s for 5,000 names). SQLite's own counter of full-scan steps, read as
 * each statement ends (SQLITE_TRACE_PROFILE), must stay 0 for exact uids; a real prefix still scans
 * and is still found, and an ambiguous one still refused. */
static long long scan_steps;
static int on_profile(unsigned type, void *u, void *p, void *x) {
  (void)u, (void)x;
  if (type == SQLITE_TRACE_PROFILE) scan_steps += sqlite3_stmt_status((sqlite3_stmt *)p, SQLITE_STMTSTATUS_FULLSCAN_STEP, 0);
  return 0;
}

static void test_find_exact(void) {
  char p[600], err[512];
  path_in(p, sizeof p, "find.db");
  palp_db *db;
  REQUIRE(palp_db_open(p, 1, &db, err, sizeof err) == 0, "create: %s", err);
  sqlite3 *h = palp_db_handle(db);
  REQUIRE(sqlite3_exec(h,
                       "WITH RECURSIVE n(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM n WHERE i < 2999) "
                       "INSERT INTO session(uid, trainee, station, phantom_id, phantom_name, scene_json, params_json, "
                       "tick_hz, dt_s, start_unix_s) SELECT printf('run-%04d', i), 'ann', 's', '1', 'p', '{}', '{}', "
                       "100, 0.01, 1.6e9 + i FROM n",
                       NULL, NULL, NULL) == SQLITE_OK,
          "3000 sessions: %s", sqlite3_errmsg(h));
  sqlite3_trace_v2(h, SQLITE_TRACE_PROFILE, on_profile, NULL);
  palp_db_session_info s;
  scan_steps = 0;
  int found = 0;
  for (int i = 0; i < 3000; i += 100) {
    char uid[32];
    snprintf(uid, sizeof uid, "run-%04d", i);
    found += palp_db_find_session(db, uid, &s) == 0 && !strcmp(s.uid, uid);
  }
  CHECK(found == 30 && scan_steps == 0, "30 exact uids found (%d) with no full-scan step (%lld)", found, scan_steps);
  scan_steps = 0;
  CHECK(palp_db_find_session(db, "run-299", &s) == PALP_DB_EAMBIGUOUS, "an ambiguous prefix refused");
  CHECK(palp_db_find_session(db, "run-2999", &s) == 0 && !strcmp(s.uid, "run-2999"), "an exact uid that is also a prefix");
  REQUIRE(sqlite3_exec(h, "UPDATE session SET uid = 'solo-uid-1' WHERE uid = 'run-0007'", NULL, NULL, NULL) == SQLITE_OK,
          "rename");
  CHECK(palp_db_find_session(db, "solo", &s) == 0 && !strcmp(s.uid, "solo-uid-1"), "a unique prefix found");
  CHECK(palp_db_find_session(db, "nosuch", &s) == PALP_DB_ENOTFOUND, "no such uid");
  palp_db_close(db);
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: %s TMPDIR MIGRATION_0001_SQL\n", argv[0]);
    return 2;
  }
  snprintf(dir, sizeof dir, "%s", argv[1]);
  test_round_trip();
  test_shed();
  test_duplicate();
  test_migration(argv[2]);
  test_newer();
  test_foreign_versioned();
  test_full_disk();
  test_full_disk_new_session();
  test_end_survives_full();
  test_duplicate_uid();
  test_mesh_bound();
  test_wal_confirmed();
  test_valid_range_detail();
  test_debrief_detail();
  test_refused();
  test_find_exact();
  test_end_reason_of();
  test_control_bytes();
  test_end_kept();
  CHECK_DONE();
}
