/* replay: re-simulate a session from its logged scene and contact inputs and check that every
 * logged frame comes back bit for bit (state hash and every summary field, compared as bits).
 *
 * Follows the replay contract in db/palp_db.h: the world is built by palp_db_world_from_scene;
 * inputs logged at frame f are applied, in log order, before the step from f to f + 1; a logged
 * frame F is compared after the step that reaches F. */
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "review.h"

#define MAX_SLOTS 4096

typedef struct replay_ctx {
  palp_world *w;
  const review_contacts *in;
  int next; /* next input to apply */
  int map[MAX_SLOTS]; /* logged slot -> replayed contact id, -1 if none */
  int verbose;
  palp_log *log;
  int64_t checked;
  int mismatch;
  int apply_errors;
  int step_error;
  int damaged;
  double dt; /* [s] */
} replay_ctx;

static int bits_eq(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

static void apply(replay_ctx *r, const palp_db_contact *c) {
  int rc = 0;
  if (c->slot < 0 || c->slot >= MAX_SLOTS) {
    palp_log_error(r->log, "replay: frame %" PRId64 ": contact slot %d out of range", c->frame, c->slot);
    r->apply_errors++;
    return;
  }
  int *id = &r->map[c->slot];
  if (c->op == PALP_DB_OP_ADD) {
    if (c->kind == PALP_DB_KIND_FORCE) {
      rc = palp_world_add_contact(r->w, &c->def);
      if (rc >= 0) {
        *id = rc;
        rc = palp_world_set_contact_force(r->w, *id, c->force_n);
      }
    } else {
      rc = palp_world_add_finger(r->w, c->center_m, c->radius_m);
      if (rc >= 0) *id = rc, rc = 0;
    }
  } else if (*id < 0) {
    palp_log_error(r->log, "replay: frame %" PRId64 ": %s of slot %d that was never added", c->frame,
            c->op == PALP_DB_OP_UPDATE ? "update" : "removal", c->slot);
    r->apply_errors++;
    return;
  } else if (c->op == PALP_DB_OP_UPDATE) {
    rc = c->kind == PALP_DB_KIND_FORCE ? palp_world_set_contact_force(r->w, *id, c->force_n)
                                       : palp_world_set_finger(r->w, *id, c->center_m, c->radius_m);
  } else {
    rc = palp_world_remove_contact(r->w, *id);
    *id = -1;
  }
  if (rc < 0) {
    palp_log_error(r->log, "replay: frame %" PRId64 ": applying input to slot %d: %s", c->frame, c->slot,
            palp_strerror(rc));
    r->apply_errors++;
    return;
  }
  palp_world_wake(r->w); /* contract item 3: every applied input wakes the world */
}

static void print_diff(const palp_db_frame *log, const palp_db_frame *got) {
  printf("replay: MISMATCH at frame %" PRId64 " (t = %.6f s):\n", log->frame, log->sim_time_s);
#define DIFF(field, unit)                                                                          \
  if (!bits_eq(log->field, got->field))                                                            \
    printf("  %-16s logged %.17g %s, replayed %.17g %s (difference %.3g)\n", #field, log->field, unit,  \
           got->field, unit, got->field - log->field);
  DIFF(sim_time_s, "s")
  DIFF(top_disp_m, "m")
  DIFF(max_disp_m, "m")
  DIFF(volume_m3, "m^3")
  DIFF(pressure_pa, "Pa")
  DIFF(contact_force_n, "N")
#undef DIFF
  if (log->state_hash != got->state_hash)
    printf("  %-16s logged 0x%016" PRIx64 ", replayed 0x%016" PRIx64 "\n", "state_hash", log->state_hash,
           got->state_hash);
}

static int frame_cb(void *u, const palp_db_frame *logged) {
  replay_ctx *r = u;
  /* Checked before stepping to it: a damaged frame number (10^12) would step for years. */
  const int64_t at = palp_world_frame(r->w);
  const double g = PALP_DB_MAX_FRAME_GAP_S / r->dt;
  const int64_t max_gap = g < PALP_DB_MAX_FRAME_GAP_STEPS ? (int64_t)g + 1 : PALP_DB_MAX_FRAME_GAP_STEPS;
  if (logged->frame < at || logged->frame - at > max_gap) {
    printf("replay: DAMAGED LOG: logged frame %" PRId64 " follows frame %" PRId64 " (at most %" PRId64
           " frames = %.0f s of simulated time may lie between two logged frames); stopping\n",
           logged->frame, at, max_gap, PALP_DB_MAX_FRAME_GAP_S);
    r->damaged = 1;
    return 1;
  }
  while (palp_world_frame(r->w) < logged->frame) {
    const int64_t f = palp_world_frame(r->w);
    while (r->next < r->in->n && r->in->v[r->next].frame <= f) apply(r, &r->in->v[r->next++]);
    int rc = palp_world_step(r->w);
    if (rc) {
      printf("replay: the world refused to step at frame %" PRId64 ": %s\n", f, palp_strerror(rc));
      r->step_error = 1;
      return 1;
    }
  }
  palp_db_frame got;
  palp_db_frame_summarize(r->w, &got);
  int same = got.frame == logged->frame && got.state_hash == logged->state_hash &&
             bits_eq(got.sim_time_s, logged->sim_time_s) && bits_eq(got.top_disp_m, logged->top_disp_m) &&
             bits_eq(got.max_disp_m, logged->max_disp_m) && bits_eq(got.volume_m3, logged->volume_m3) &&
             bits_eq(got.pressure_pa, logged->pressure_pa) && bits_eq(got.contact_force_n, logged->contact_force_n);
  if (!same) {
    if (got.frame != logged->frame)
      printf("replay: MISMATCH: logged frame %" PRId64 " but the world is at %" PRId64 "\n", logged->frame, got.frame);
    else print_diff(logged, &got);
    r->mismatch = 1;
    return 1;
  }
  r->checked++;
  if (r->verbose && r->checked % 1000 == 0)
    printf("replay: %" PRId64 " frames identical (frame %" PRId64 ")\n", r->checked, logged->frame);
  return 0;
}

int review_replay(palp_log *log, palp_db *db, const palp_db_session_info *s, int verbose) {
  if (s->pruned_unix_s > 0) {
    char tp[64];
    review_fmt_time(s->pruned_unix_s, tp, sizeof tp);
    palp_log_error(log, "replay: session %s was PRUNED on %s: its frames and contact inputs were deleted, so there "
                   "is nothing to replay (its stored metrics: palp-review show)", s->uid, tp);
    return REVIEW_ERROR;
  }
  char *scene = NULL, *params = NULL;
  if (palp_db_session_json(db, s->id, &scene, &params)) {
    palp_log_error(log, "replay: %s", palp_db_errmsg(db));
    return REVIEW_ERROR;
  }
  const int recorded = params && strstr(params, "\"recorded_by\"") != NULL;
  /* The math library of the machine that ran the session (palp_numerics_fingerprint, "numerics" in
   * its params since session 81) against this one's: another one's last bits differ, and its replay
   * mismatches however sound the log (said before and after). */
  char logged_numerics[24] = "", here[24];
  snprintf(here, sizeof here, "%016llx", (unsigned long long)palp_numerics_fingerprint());
  {
    cJSON *pj = params ? cJSON_Parse(params) : NULL;
    const char *v = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(pj, "numerics"));
    if (v && strlen(v) == 16 && strspn(v, "0123456789abcdef") == 16)
      snprintf(logged_numerics, sizeof logged_numerics, "%s", v);
    cJSON_Delete(pj);
  }
  free(params);
  const int other_numerics = logged_numerics[0] && strcmp(logged_numerics, here) != 0;
  if (other_numerics)
    printf("replay: %s ran on a machine whose math library computes the model's exp, pow, atan2, sin and cos "
           "differently in the last bit (numerics %s there, %s here: glibc picks FMA/AVX2 or baseline code by the "
           "CPU); a bit-identical replay is not expected here\n",
           s->uid, logged_numerics, here);
  if (recorded) {
    /* palp-recorder logs inputs as received over DDS, not as the server applied them. */
    palp_log_error(log, "replay: session %s was recorded over DDS by palp-recorder: its contact inputs are stamped "
                    "with the frames the recorder saw, not the frames the server applied them at, and its frames "
                    "carry no state hash, so it cannot be replayed exactly; replay the server's own log instead",
            s->uid);
    free(scene);
    return REVIEW_ERROR;
  }
  /* A step no server steps at is a damaged or edited log: 1e-7 s would make each logged second ten
   * million steps (the gap guard below bounds one gap; this bounds the whole replay's pace). */
  if (s->dt_s > 0 && !(s->dt_s >= PALP_DB_MIN_DT_S * (1 - 1e-9) && s->dt_s <= PALP_WORLD_MAX_DT * (1 + 1e-9))) {
    palp_log_error(log, "replay: DAMAGED LOG: session %s logged a step of %g s; a server steps at %g .. %g s (10 Hz .. "
                   "10 kHz): not replayed", s->uid, s->dt_s, PALP_DB_MIN_DT_S, PALP_WORLD_MAX_DT);
    free(scene);
    return REVIEW_ERROR;
  }
  char msg[512];
  int err;
  palp_world *w = palp_db_world_from_scene(scene, s->dt_s, &err, msg, sizeof msg);
  free(scene);
  if (!w) {
    palp_log_error(log, "replay: session %s: cannot rebuild the world: %s", s->uid, msg);
    return REVIEW_ERROR;
  }
  review_contacts in;
  if (review_load_contacts(db, s->id, &in)) {
    palp_log_error(log, "replay: %s", palp_db_errmsg(db));
    palp_world_destroy(w);
    return REVIEW_ERROR;
  }
  if (s->records_shed || s->records_failed)
    palp_log_warn(log, "replay: the log of %s is incomplete (%lld shed, %lld lost); if contact inputs are "
                       "among them the replay will diverge",
            s->uid, (long long)s->records_shed, (long long)s->records_failed);
  replay_ctx *r = calloc(1, sizeof *r);
  if (!r) {
    free(in.v);
    palp_world_destroy(w);
    return REVIEW_ERROR;
  }
  r->w = w;
  r->in = &in;
  r->verbose = verbose;
  r->log = log;
  r->dt = s->dt_s > 0 ? s->dt_s : 1e-3;
  for (int i = 0; i < MAX_SLOTS; i++) r->map[i] = -1;
  int rc = palp_db_each_frame(db, s->id, frame_cb, r);
  int result;
  if (rc < 0) {
    palp_log_error(log, "replay: reading frames: %s", palp_db_errmsg(db));
    result = REVIEW_ERROR;
  } else if (r->damaged) {
    result = REVIEW_ERROR;
  } else if (r->step_error) {
    result = REVIEW_MISMATCH;
  } else if (r->mismatch) {
    printf("replay: %s diverges after %" PRId64 " identical frames%s\n", s->uid, r->checked,
           other_numerics ? ": expected on this machine, whose math library is not the logging machine's (above); "
                            "replay it on a machine of the logging kind"
           : logged_numerics[0] ? " (the same math library as the machine that ran it: the log or the model differs)"
                                : " (the log keeps no numerics fingerprint: logged before session 81 or by another "
                                  "tool; on a machine of another CPU kind the math library's last bits may be why)");
    result = REVIEW_MISMATCH;
  } else if (r->checked == 0) {
    palp_log_error(log, "replay: %s has no logged frames to compare", s->uid);
    result = REVIEW_ERROR;
  } else {
    palp_stage_timings ts;
    palp_world_timings(w, &ts);
    printf("replay: %s: %" PRId64 " logged frames reproduced bit-identically (state hash and summary), "
           "%d contact inputs applied, last frame %" PRId64 ", %lld factorisations (lagged-tangent rebuilds "
           "included)\n",
           s->uid, r->checked, r->next, palp_world_frame(w), (long long)ts.refactors);
    /* What the station was told frame by frame (LM_LARGE_STRAIN), summed for the
     * instructor: where the model's answer is an extrapolation (docs/model.md). */
    palp_world_health h;
    palp_world_get_health(w, &h);
    const double hinge_range = palp_world_hinge_range(palp_world_get_def(w));
    printf("replay: %s: beyond the model's valid range: %lld steps stretched a link past 50%% (largest strain "
           "%.2f), %lld bent a hinge past its linear range (a miss over %.3f rad; largest miss %.3f rad, largest turn "
           "%.3f rad)\n",
           s->uid, (long long)h.large_strain_steps, h.max_strain, (long long)h.large_bend_steps, hinge_range,
           h.max_bend_error, h.max_bend);
    /* and where a fingertip pressed deeper than the parameters were validated against the FE
     * (LM_BEYOND_VALIDATED; only for parameters that state it) */
    if (palp_world_get_def(w)->validated_count > 0)
      printf("replay: %s: a fingertip deeper than the parameters were validated against the FE: %lld steps (by up to "
             "%.1f mm)\n", s->uid, (long long)h.beyond_validated_steps, 1e3 * h.max_beyond_validated);
    /* and where the literal gel law stepped outside its stable range (only for that law; the server
     * logs it since 2026-12-06, and this recomputes it for earlier logs) */
    if (palp_world_get_def(w)->gel.law == PALP_GEL_PAPER_LITERAL)
      printf("replay: %s: the literal gel law's momentum term left out at %lld frames (a3 / (h h_prev) outside "
             "(-1/2, 1))\n", s->uid, (long long)h.gel_momentum_dropped);
    result = REVIEW_OK;
  }
  if (r->apply_errors) printf("replay: %d contact inputs could not be applied\n", r->apply_errors);
  free(r);
  free(in.v);
  palp_world_destroy(w);
  return result;
}
