/*
 * gen.h - logs a scripted trainee's exercise session into a real SQLite file through the
 * writer, the way the server logs one (palp_db_log_session_begin, palp_db_log_exercise, one
 * palp_db_log_finger_sample per physics step, palp_db_log_finding per mark), and assesses the
 * same samples in process with palp_assess: the reference the review's metrics must equal.
 *
 * The trainees are tests/assess/recorder.h (client/trainee.c) expert (vertical strips, three pressures, marks
 * where the medium-depth force rises > 12% over its surroundings) and novice (a few light
 * random presses and a guess), on tests/assess/exercise_expert.json.
 */
#ifndef PALP_TEST_REVIEW_GEN_H
#define PALP_TEST_REVIEW_GEN_H
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp_assess.h"
#include "palp_db.h"
#include "recorder.h"

static char *gen_slurp(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *b = n >= 0 ? malloc((size_t)n + 1) : NULL;
  if (b && fread(b, 1, (size_t)n, f) != (size_t)n) free(b), b = NULL;
  if (b) b[n] = 0;
  fclose(f);
  return b;
}

typedef enum { GEN_EXPERT = 0, GEN_NOVICE = 1, GEN_FREE = 2 } gen_kind;

/* Logs one session; *ref receives the in-process assessment. 0 or a message on stderr and -1.
 * debrief: NULL, a log as a server before session 59 wrote it (no debriefs logged, no
 * "debrief_events" key); "", a server that logs debriefs and logged none; else the debrief
 * event's detail, as the server would have logged it (a fixture: the review reads it back). */
/* inline: test_review_assess includes this header for gen_slurp alone (it reads review_gen's class) */
static inline int gen_session(palp_db_writer *w, const char *test_dir, const char *uid, const char *trainee, gen_kind kind,
                       unsigned seed, double start_unix_s, palp_assess_result *ref, const char *debrief) {
  char ex_path[1024], sc_path[1024], err[512] = "";
  snprintf(ex_path, sizeof ex_path, "%s/exercise_expert.json", test_dir);
  snprintf(sc_path, sizeof sc_path, "%s/phantom_stiff.json", test_dir);
  palp_exercise ex;
  palp_scene *sc = malloc(sizeof *sc);
  if (!sc || palp_exercise_load(ex_path, &ex, err, sizeof err) || palp_exercise_scene(&ex, sc, err, sizeof err)) {
    fprintf(stderr, "gen: %s: %s\n", ex_path, err);
    free(sc);
    return -1;
  }
  int e = 0;
  palp_world *world = palp_world_create(&sc->world, &e);
  char *ex_json = gen_slurp(ex_path), *sc_json = gen_slurp(sc_path);
  if (!world || !ex_json || !sc_json) {
    fprintf(stderr, "gen: world %s, files %p %p\n", palp_strerror(e), (void *)ex_json, (void *)sc_json);
    return -1;
  }
  const double R = sc->world.mesh.radius, r = 0.008;
  recorder rc;
  rec_init(&rc, world, R, r, (palp_vec3){0, 0, R + r + 0.005});
  palp_finding f[16];
  int nf = 0;
  if (kind == GEN_EXPERT) {
    expert_cfg cfg = expert_default();
    int nspots = 0;
    expert_spot *sp = expert_exam(&rc, &cfg, &nspots);
    double max_rise;
    nf = expert_findings(&rc, sp, nspots, 0.12, 0.015, f, 16, &max_rise);
    free(sp);
  } else {
    palp_vec3 guess = {0, 0, 0};
    novice_exam(&rc, 5, 0.003, seed, &guess);
    /* a mark the novice withdraws, then the guess at the last press */
    f[nf++] = (palp_finding){.t = palp_world_time(world) - 0.5, .point = {0, 0, R}, .withdrawn = 1};
    f[nf++] = (palp_finding){.t = palp_world_time(world), .point = guess, .withdrawn = 0};
  }
  rec_finish(&rc);
  if (rc.failed) {
    fprintf(stderr, "gen: the exam failed after %d samples\n", rc.n);
    return -1;
  }
  /* a server that logs valid-range events says so (server/db_log.c); the novice's log is as an
   * earlier server wrote it, without the key; so for debriefs */
  char params[128];
  snprintf(params, sizeof params, "{%s%s%s}", kind == GEN_NOVICE ? "" : "\"valid_range_events\": true",
           kind != GEN_NOVICE && debrief ? ", " : "", debrief ? "\"debrief_events\": true" : "");
  palp_db_session_def d = {.uid = uid, .trainee = trainee, .station = "gen", .phantom_id = "stiff",
                           .phantom_name = sc->name[0] ? sc->name : "phantom_stiff", .scene_json = sc_json,
                           .params_json = params, .tick_hz = 1.0 / sc->world.dt, .dt_s = sc->world.dt,
                           .start_unix_s = start_unix_s};
  palp_db_session s;
  int rc_ = palp_db_log_session_begin(w, &d, &s);
  if (!rc_ && kind != GEN_FREE) rc_ = palp_db_log_exercise(w, s, ex.name, ex_json);
  for (int i = 0; i < rc.n && !rc_; i++) {
    const palp_assess_sample *a = &rc.s[i];
    palp_db_finger_sample fs = {.frame = i + 1, .sim_time_s = a->t, .slot = rc.finger, .radius_m = r,
                                .device_m = a->device, .proxy_m = a->proxy, .force_n = a->force,
                                .in_contact = a->contact, .point_m = a->point, .area_m2 = a->area,
                                .triangle_count = a->triangle_count, .triangles = (const int32_t *)a->triangles};
    /* the queue is bounded: wait for the disk now and then rather than shed */
    while ((rc_ = palp_db_log_finger_sample(w, s, &fs)) == PALP_EFULL) palp_db_writer_flush(w, 10.0);
    if (i % 20000 == 19999) palp_db_writer_flush(w, 30.0);
  }
  for (int k = 0; k < nf && !rc_; k++) {
    palp_db_finding m = {.mark_id = k + 1, .op = PALP_DB_FINDING_MARK, .frame = k + 1, .sim_time_s = f[k].t,
                         .wall_unix_s = start_unix_s + f[k].t, .point_m = f[k].point};
    rc_ = palp_db_log_finding(w, s, &m);
    if (!rc_ && f[k].withdrawn) {
      m.op = PALP_DB_FINDING_WITHDRAW;
      m.sim_time_s += 0.1;
      rc_ = palp_db_log_finding(w, s, &m);
    }
  }
  if (kind == GEN_EXPERT && !rc_) {
    /* Valid-range events as the server writes them (test_review_cli.sh expects their sums:
     * 355 steps, 310 deeper than validated by up to 2.4 mm, 50 skin, none at the limits, one
     * event unreadable), after the samples: the assessment does not read them. */
    const palp_db_valid_range e[2] = {{.steps = 250, .depth_steps = 250, .deepest_m = 0.0012},
                                      {.steps = 100, .depth_steps = 60, .skin_steps = 50, .deepest_m = 0.0024}};
    char detail[200];
    for (int k = 0; k < 2 && !rc_; k++) {
      palp_db_valid_range_format(&e[k], detail, sizeof detail);
      rc_ = palp_db_log_event(w, s, PALP_DB_EVENT_VALID_RANGE, 1000 * (k + 1), detail, e[k].steps);
    }
    if (!rc_) rc_ = palp_db_log_event(w, s, PALP_DB_EVENT_VALID_RANGE, 3000, "outside at many steps", 5);
  }
  if (!rc_ && debrief && debrief[0])
    rc_ = palp_db_log_event(w, s, PALP_DB_EVENT_DEBRIEF, rc.n, debrief, 1);
  if (!rc_) rc_ = palp_db_log_session_end(w, s, PALP_DB_END_NORMAL, NULL, start_unix_s + palp_world_time(world));
  if (!rc_) rc_ = palp_db_writer_flush(w, 60.0);
  if (rc_) fprintf(stderr, "gen: logging failed: %s\n", palp_strerror(rc_));
  palp_exercise free_ex;
  const palp_exercise *use = &ex;
  if (kind == GEN_FREE) { /* the review's free-practice bands are the shipped ones: no lesions */
    free_ex = ex;
    free_ex.lesion_count = 0;
    use = &free_ex;
  }
  if (!rc_ && ref) rc_ = palp_assess(use, palp_world_mesh(world), r, rc.s, rc.n, f, nf, ref, NULL, NULL);
  rec_free(&rc);
  palp_world_destroy(world);
  free(ex_json), free(sc_json), free(sc);
  return rc_ ? -1 : 0;
}
#endif
