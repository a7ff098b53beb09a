/* palp-recorder: a session's exercise and its end as the server meant them (a review of 2026-12-07),
 * over real DDS on loopback (domain 200, of its own). The test plays two participants: run A, the
 * server whose states open the sessions, and B, another participant writing session exercises.
 * usage: test_db_recorder_ends TMPDIR PALP_RECORDER DDS_CONFIG EXERCISE_JSON
 *
 * The exercises are the shipped teaching.json with its name changed ("easy", "hard", "stale",
 * "fresh"), so that which one was logged tells whose it was. Checked in the file (exact names):
 *  - session 50: B writes "easy" for it, then A "hard", then A's OPEN: "hard" logged (before: "easy",
 *    the first waiting entry, and A's own dropped as "re-delivered");
 *  - session 55: B writes "easy", then A's OPEN, then A's "hard" (the order reproduced by the review):
 *    "hard" logged, and the recorder says B's was not (before: "easy", "hard" dropped);
 *  - session 51: A's "stale" 10.5 s before A's OPEN (the wait is 10 s): none logged, said;
 *  - session 52: A's "stale", and 10.5 s later A's "fresh" then OPEN: "fresh" logged (before: "stale",
 *    the fresh one dropped as "re-delivered" before the expiry was looked at);
 *  - session 53: CLOSED with "model step failed: state became non-finite": ended `error`, as the
 *    server's own log ends it (before: `normal`);
 *  - session 54, an exercise session: CLOSED with "exercise time limit reached" and no debrief, the
 *    recorder stopped 0.3 s later, within its 1 s wait for the debrief: ended `normal` with that reason,
 *    the server's 3 rejected samples in a `reject` event (before: `error`, "palp-recorder stopped while
 *    the session ran", no counts).
 * The test takes ~12 s: the 10 s wait is the recorder's. */
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

#define DOMAIN 200
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

/* The exercise text with its name replaced (`"name": "teaching"` -> `"name": "NAME"`); NULL if absent. */
static char *renamed(const char *json, const char *name) {
  static const char key[] = "\"name\": \"teaching\"";
  const char *at = strstr(json, key);
  if (!at) return NULL;
  const size_t n = strlen(json) + strlen(name) + 16;
  char *out = malloc(n);
  if (out) snprintf(out, n, "%.*s\"name\": \"%s\"%s", (int)(at - json), json, name, at + strlen(key));
  return out;
}

static void state(dds_entity_t w, uint32_t id, int closed, const char *reason, uint64_t rejected) {
  palp_SessionState ss;
  memset(&ss, 0, sizeof ss);
  ss.session_id = id;
  ss.phantom_id = PHANTOM;
  ss.phase = closed ? palp_PHASE_CLOSED : palp_PHASE_OPEN;
  palp_dds_session_partition(id, ss.partition, sizeof ss.partition);
  snprintf(ss.trainee_station, sizeof ss.trainee_station, "host/1/s%u", id);
  snprintf(ss.trainee_name, sizeof ss.trainee_name, "s%u", id);
  ss.tick_rate_hz = 250;
  ss.duration = closed ? 1.0 : 0.0;
  ss.ticks = closed ? 250 : 0;
  if (reason) snprintf(ss.reason, sizeof ss.reason, "%s", reason);
  ss.rejected_samples = rejected;
  dds_write(w, &ss);
}

static void exercise(dds_entity_t w, uint32_t id, const char *name, const char *json) {
  palp_SessionExercise *m = calloc(1, sizeof *m);
  m->session_id = id;
  m->phantom_id = PHANTOM;
  snprintf(m->name, sizeof m->name, "%s", name);
  snprintf(m->json, sizeof m->json, "%s", json);
  dds_write(w, m);
  free(m);
}

static double mono_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The exercise logged for session `id` (its trainee is "sID"), "" for none; the count of them in *n. */
static void logged_exercise(sqlite3 *h, uint32_t id, char *name, size_t len, int64_t *n) {
  char q[256];
  snprintf(q, sizeof q, "SELECT group_concat(exercise_name) FROM session_exercise WHERE session_id IN (SELECT id "
                        "FROM session WHERE trainee = 's%u')", id);
  db_text(h, q, name, len);
  snprintf(q, sizeof q, "SELECT count(*) FROM session_exercise WHERE session_id IN (SELECT id FROM session WHERE "
                        "trainee = 's%u')", id);
  *n = db_scalar(h, q);
}

static int log_says(const char *path, const char *a, const char *b) {
  FILE *f = fopen(path, "r");
  char line[2048];
  int found = 0;
  while (f && !found && fgets(line, sizeof line, f)) found = strstr(line, a) && strstr(line, b);
  if (f) fclose(f);
  return found;
}

int main(int argc, char **argv) {
  if (argc < 5) {
    fprintf(stderr, "usage: %s TMPDIR PALP_RECORDER DDS_CONFIG EXERCISE_JSON\n", argv[0]);
    return 2;
  }
  char db[600], logf[600];
  db_fresh_path(db, sizeof db, argv[1], "recorder_ends.db");
  db_fresh_path(logf, sizeof logf, argv[1], "recorder_ends.log");
  REQUIRE(palp_dds_use_config(argv[3]) == 0, "DDS config %s", argv[3]);
  char *json = read_file(argv[4]);
  REQUIRE(json != NULL, "read %s", argv[4]);
  char *easy = renamed(json, "easy"), *hard = renamed(json, "hard"), *stale = renamed(json, "stale"),
       *fresh = renamed(json, "fresh");
  REQUIRE(easy && hard && stale && fresh, "%s names its exercise \"teaching\"", argv[4]);

  const pid_t pid = start_recorder(argv[2], db, DOMAIN, logf, NULL);
  REQUIRE(pid >= 0, "fork");
  /* run A: the server of every session here */
  dds_entity_t pa = dds_create_participant(DOMAIN, NULL, NULL);
  REQUIRE(pa > 0, "participant A: %s", dds_strretcode(pa));
  dds_entity_t t[PALP_TOPIC_COUNT];
  for (int k = 0; k < PALP_TOPIC_COUNT; k++) t[k] = palp_dds_create_topic(pa, (palp_dds_topic_kind)k);
  dds_entity_t w_cat = palp_dds_create_writer(pa, t[PALP_TOPIC_CATALOGUE], PALP_TOPIC_CATALOGUE);
  dds_entity_t w_state = palp_dds_create_writer(pa, t[PALP_TOPIC_SESSION_STATE], PALP_TOPIC_SESSION_STATE);
  dds_entity_t w_ex = palp_dds_create_writer(pa, t[PALP_TOPIC_SESSION_EXERCISE], PALP_TOPIC_SESSION_EXERCISE);
  /* B: another participant that writes session exercises */
  dds_entity_t pb = dds_create_participant(DOMAIN, NULL, NULL);
  REQUIRE(pb > 0, "participant B: %s", dds_strretcode(pb));
  dds_entity_t w_ex_b = palp_dds_create_writer(pb, palp_dds_create_topic(pb, PALP_TOPIC_SESSION_EXERCISE),
                                               PALP_TOPIC_SESSION_EXERCISE);
  const dds_entity_t all[] = {w_cat, w_state, w_ex, w_ex_b};
  for (size_t k = 0; k < sizeof all / sizeof all[0]; k++)
    REQUIRE(wait_matched(all[k], 1, 20) == 0, "writer %zu never matched the recorder", k);

  palp_mesh_def md = palp_mesh_default_def();
  palp_mesh mesh;
  REQUIRE(palp_mesh_create(&md, &mesh) == 0, "mesh");
  palp_Vec3 *rest = calloc((size_t)mesh.vertex_count, sizeof *rest);
  palp_Phantom ph = test_phantom(PHANTOM, "Teaching", &md, &mesh, rest, 250);
  REQUIRE(dds_write(w_cat, &ph) == 0, "catalogue");
  sleep_ms(300);

  /* sessions 51 and 52: run A's exercises that wait 10.5 s */
  exercise(w_ex, 51, "stale", stale);
  exercise(w_ex, 52, "stale", stale);
  const double t_stale = mono_s();
  /* session 50: B's, then A's, then A's OPEN */
  exercise(w_ex_b, 50, "easy", easy);
  sleep_ms(200);
  exercise(w_ex, 50, "hard", hard);
  sleep_ms(200);
  state(w_state, 50, 0, NULL, 0);
  /* session 55: B's, then A's OPEN, then A's exercise */
  exercise(w_ex_b, 55, "easy", easy);
  sleep_ms(200);
  state(w_state, 55, 0, NULL, 0);
  sleep_ms(200);
  exercise(w_ex, 55, "hard", hard);
  /* session 53: its model failed */
  state(w_state, 53, 0, NULL, 0);
  sleep_ms(200);
  state(w_state, 53, 1, "model step failed: state became non-finite", 0);

  /* 10.5 s after the stale ones were written (the recorder's wait is 10 s) */
  const double wait = 10.5 - (mono_s() - t_stale);
  if (wait > 0) sleep_ms((int)(wait * 1e3));
  state(w_state, 51, 0, NULL, 0);
  sleep_ms(200);
  exercise(w_ex, 52, "fresh", fresh);
  sleep_ms(200);
  state(w_state, 52, 0, NULL, 0);
  /* session 54: an exercise session closed by its time limit; its debrief never comes, and the recorder
   * stops 0.3 s into its 1 s wait for it */
  exercise(w_ex, 54, "hard", hard);
  sleep_ms(200);
  state(w_state, 54, 0, NULL, 0);
  sleep_ms(200);
  state(w_state, 54, 1, "exercise time limit reached", 3);
  /* stopped once the recorder has taken the CLOSED state (its log says so), so well within its 1 s wait
   * for the debrief: a loaded run's recorder had not yet taken session 54's states 0.3 s after the
   * CLOSED one was written, and logged no session 54 at all (session 81) */
  for (int i = 0; i < 150 && !log_says(logf, "session 54 closed", "exercise time limit reached"); i++) sleep_ms(20);
  sleep_ms(100);

  int status;
  CHECK(stop_recorder(pid, &status), "the recorder exits 0 (status %d)", status);
  dds_delete(pb);
  dds_delete(pa);

  sqlite3 *h;
  REQUIRE(sqlite3_open(db, &h) == SQLITE_OK, "open %s", db);
  char name[256];
  int64_t n;
  logged_exercise(h, 50, name, sizeof name, &n);
  printf("session 50: exercise logged \"%s\" (%lld rows)\n", name, (long long)n);
  CHECK(n == 1 && !strcmp(name, "hard"), "session 50: the exercise of its own run (\"hard\") logged, not another "
        "participant's that came first (got \"%s\", %lld rows)", name, (long long)n);
  logged_exercise(h, 55, name, sizeof name, &n);
  printf("session 55: exercise logged \"%s\" (%lld rows)\n", name, (long long)n);
  CHECK(n == 1 && !strcmp(name, "hard"), "session 55: its run's exercise after its OPEN (\"hard\") logged, not "
        "another participant's that waited (got \"%s\", %lld rows)", name, (long long)n);
  CHECK(log_says(logf, "session 55: exercise \"easy\" not logged", "another participant"),
        "session 55: the recorder says another participant's exercise was not logged");
  logged_exercise(h, 51, name, sizeof name, &n);
  printf("session 51: exercise logged \"%s\" (%lld rows)\n", name, (long long)n);
  CHECK(n == 0, "session 51: an exercise that waited 10.5 s (over the 10 s wait) not logged (got \"%s\")", name);
  CHECK(log_says(logf, "session 51: exercise \"stale\" not logged", "before the session opened"),
        "session 51: the recorder says why its stale exercise was not logged");
  logged_exercise(h, 52, name, sizeof name, &n);
  printf("session 52: exercise logged \"%s\" (%lld rows)\n", name, (long long)n);
  CHECK(n == 1 && !strcmp(name, "fresh"), "session 52: the exercise that came just before its OPEN (\"fresh\") "
        "logged, not the one 10.5 s old (got \"%s\", %lld rows)", name, (long long)n);
  char reason[64], detail[256];
  db_text(h, "SELECT end_reason FROM session WHERE trainee = 's53'", reason, sizeof reason);
  db_text(h, "SELECT end_detail FROM session WHERE trainee = 's53'", detail, sizeof detail);
  printf("session 53: ended %s (%s)\n", reason, detail);
  CHECK(!strcmp(reason, "error") && !strcmp(detail, "model step failed: state became non-finite"),
        "session 53, closed as its model failed: ended error, the server's reason its detail (got %s, \"%s\")", reason,
        detail);
  db_text(h, "SELECT end_reason FROM session WHERE trainee = 's54'", reason, sizeof reason);
  db_text(h, "SELECT end_detail FROM session WHERE trainee = 's54'", detail, sizeof detail);
  const int64_t rejected = db_scalar(h, "SELECT coalesce(sum(count), 0) FROM event WHERE kind = 'reject' AND session_id "
                                        "IN (SELECT id FROM session WHERE trainee = 's54')");
  printf("session 54: ended %s (%s), %lld rejected samples in its events\n", reason, detail, (long long)rejected);
  CHECK(!strcmp(reason, "normal") && !strcmp(detail, "exercise time limit reached") && rejected == 3,
        "session 54, closed by its time limit, the recorder stopped within its wait for the debrief: ended normal "
        "with the server's reason and its 3 rejected samples (got %s, \"%s\", %lld)", reason, detail,
        (long long)rejected);
  CHECK(db_scalar(h, "SELECT count(*) FROM session WHERE end_unix_s IS NULL") == 0, "every session ended");
  sqlite3_close(h);
  free(easy), free(hard), free(stale), free(fresh), free(json), free(rest);
  palp_mesh_destroy(&mesh);
  CHECK_DONE();
}
