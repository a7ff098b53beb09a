/* db_log.c - palp-server's session log through the db/ writer. */
#include "db_log.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "grader.h"
#include "palp_assess.h" /* palp_assess_sample_every */
#include "palp_db.h"
#include "palp_dds.h"

#define SLOT_FINGERS 16 /* model contact ids whose fingertip radius is tracked */
#define SLOTS 1024 /* open sessions are far fewer; a slot is found from id % SLOTS (find) */
#define FLUSH_NS 1000000000 /* reject/clamp/overrun counts are logged once a second per session */

typedef struct slot {
  palp_db_session h;
  int64_t next_mesh_frame;
  int64_t last_flush_ns;
  int64_t last_frame;
  uint64_t rejected[PALP_SRV_REJ_COUNT], clamped, overruns;
  /* issue 13 */
  int sample_every;            /* log a finger sample every this many frames */
  int frame_every, mesh_every; /* frames at ~100 Hz, meshes at ~2 Hz of this session's physics rate */
  /* Finding refusals: counted by the main thread (on_finding), flushed by the session's tick thread
   * (flush_counts, from on_frame), so atomic, and taken with an exchange (until session 82 plain
   * fields both threads wrote: a refusal could be lost or counted twice). */
  atomic_int_fast64_t findings_refused; /* refusals not logged one by one since the last flush */
  atomic_int refusals_logged;           /* logged one by one since the last flush */
  double finger_radius[SLOT_FINGERS]; /* per model contact id, from the world ops [m] */
  palp_db_valid_range range;          /* steps outside the model's valid range since the last flush */
  /* gaps in the device points caught up, fingers brought in from the surface, since the last flush
   * (server/playout.h, server/session.c): the longest gap [s], the deepest placement [m] */
  uint64_t gaps, entries;
  double gap_max, entry_max;
  /* session 63: an exercise session is scored from this log once it closes (grader.h) */
  char uid[96];
  char exercise[64];                  /* "" for none */
} slot;

struct palp_srv_db_log {
  palp_db_writer *w;
  palp_srv_events ev;
  char run_id[48];
  char numerics[24]; /* palp_numerics_fingerprint, hex: each session's params carry it (replay) */
  slot s[SLOTS];
  palp_log *log; /* may be NULL (stderr) */
  palp_srv_grader *grader; /* NULL: closed sessions are not scored live */
  palp_db_loss_watch watch; /* session 66: the log's losses said as they happen */
  /* The slots' ids as the tick threads probe them (find): a tick thread reads other sessions' ids
   * while the main thread opens and closes those sessions (on_opened, on_closed), so these are
   * atomic, apart from the slots themselves, which only their own session's threads touch between
   * its open and its close. ids[k] is slot k's session, 0 when free. */
  _Atomic uint32_t ids[SLOTS];
  /* The farthest a session's slot has been placed from id % SLOTS: find looks no further. Written
   * by the main thread before the session's first tick (on_opened), only ever grown. */
  _Atomic int max_probe;
};

/* Linear probing from id % SLOTS (until session 75 only that slot: a new session whose slot an
 * older session still held, ids 1,024 apart, was not logged at all). A freed slot is no end of
 * the probe (the id may lie past it), so find looks max_probe + 1 slots, not until a free one. */
static slot *find(palp_srv_db_log *l, uint32_t id) {
  const int probe = atomic_load_explicit(&l->max_probe, memory_order_relaxed);
  for (int k = 0; k <= probe; k++) {
    const uint32_t at = (id + (uint32_t)k) % SLOTS;
    /* acquire: the slot was filled before its id was published (on_opened) */
    if (atomic_load_explicit(&l->ids[at], memory_order_acquire) == id) return &l->s[at];
  }
  return NULL;
}

/* A free slot for a new session, nearest its home; NULL when all SLOTS are held. */
static slot *place(palp_srv_db_log *l, uint32_t id) {
  for (int k = 0; k < SLOTS; k++) {
    const uint32_t at = (id + (uint32_t)k) % SLOTS;
    if (atomic_load_explicit(&l->ids[at], memory_order_relaxed)) continue; /* only the main thread writes them */
    if (k > atomic_load_explicit(&l->max_probe, memory_order_relaxed))
      atomic_store_explicit(&l->max_probe, k, memory_order_relaxed);
    return &l->s[at];
  }
  return NULL;
}

static void flush_counts(palp_srv_db_log *l, slot *s, int64_t frame) {
  for (int r = 0; r < PALP_SRV_REJ_COUNT; r++)
    if (s->rejected[r]) {
      palp_db_log_event(l->w, s->h, PALP_DB_EVENT_REJECT, frame, palp_srv_reject_name((palp_srv_reject_reason)r),
                        (int64_t)s->rejected[r]);
      s->rejected[r] = 0;
    }
  if (s->clamped) {
    palp_db_log_event(l->w, s->h, PALP_DB_EVENT_CLAMP, frame, "force_limit", (int64_t)s->clamped);
    s->clamped = 0;
  }
  const int64_t refused = (int64_t)atomic_exchange(&s->findings_refused, 0);
  if (refused)
    palp_db_log_event(l->w, s->h, PALP_DB_EVENT_REJECT, frame, "finding refused (more, not logged one by one)",
                      refused);
  atomic_store(&s->refusals_logged, 0);
  if (s->range.steps) {
    char detail[256]; /* the longest detail, every number at its bound, is 212 characters */
    palp_db_valid_range_format(&s->range, detail, sizeof detail);
    palp_db_log_event(l->w, s->h, PALP_DB_EVENT_VALID_RANGE, frame, detail, s->range.steps);
    s->range.steps = s->range.depth_steps = s->range.skin_steps = s->range.limit_steps = 0; /* deepest: so far */
    s->range.gel_steps = s->range.gel_frames = 0;
  }
  if (s->gaps) {
    char detail[200];
    snprintf(detail, sizeof detail, "device points resumed after a gap (a stalled station or server), the longest "
             "%.2f s: the phantom was given the hand's path over it, not the jump (docs/station.md)", s->gap_max);
    palp_db_log_event(l->w, s->h, PALP_DB_EVENT_INFO, frame, detail, (int64_t)s->gaps);
    s->gaps = 0, s->gap_max = 0;
  }
  if (s->entries) {
    char detail[200];
    snprintf(detail, sizeof detail, "a finger placed below the surface (a station back from a stall, a device "
             "pressed in), the deepest %.1f mm: brought in from the surface at a pressing hand's speed",
             1e3 * s->entry_max);
    palp_db_log_event(l->w, s->h, PALP_DB_EVENT_INFO, frame, detail, (int64_t)s->entries);
    s->entries = 0, s->entry_max = 0;
  }
  if (s->overruns) {
    palp_db_log_event(l->w, s->h, PALP_DB_EVENT_OVERRUN, frame, "tick ended after the next tick's start",
                      (int64_t)s->overruns);
    s->overruns = 0;
  }
}

/* ---- main-thread hooks ----------------------------------------------------------- */

/* Frames between two logged records for a record rate of hz at a physics rate of rate_hz: the
 * assessment's sampling rule (palp_assess_sample_every), which the stations' coverage also follows. */
static int log_every(double rate_hz, double hz) { return palp_assess_sample_every(rate_hz, hz); }

/* A session's uid in the log (docs/naming.md): <server run>-<session id>. */
static void session_uid(const palp_srv_db_log *l, uint32_t session_id, char *buf, size_t len) {
  snprintf(buf, len, "%s-%u", l->run_id, session_id);
}

static void on_opened(void *ctx, const palp_srv_session_info *i) {
  palp_srv_db_log *l = ctx;
  slot *s = place(l, i->session_id);
  if (!s) { /* 1,024 sessions open at once: far beyond any max_sessions */
    palp_log_error(l->log, "session log: all %d slots busy; session %u not logged", SLOTS, i->session_id);
    return;
  }
  char uid[96], phantom[16];
  session_uid(l, i->session_id, uid, sizeof uid);
  snprintf(phantom, sizeof phantom, "%u", i->phantom_id);
  /* valid_range_events: this server logs the steps outside the model's valid range as events
   * (none then means none happened; a log without the key does not say); debrief_events: it logs
   * each exercise session's debrief, sent or not (none then means none was sent; since session 59).
   * Built with cJSON (escaped, as palp-recorder's since session 75), not by hand. */
  cJSON *pj = cJSON_CreateObject();
  cJSON_AddNumberToObject(pj, "max_force_n", i->max_force);
  cJSON_AddNumberToObject(pj, "tick_rate_hz", i->tick_rate_hz);
  cJSON_AddStringToObject(pj, "partition", i->partition);
  cJSON_AddBoolToObject(pj, "valid_range_events", 1);
  cJSON_AddBoolToObject(pj, "debrief_events", 1);
  /* this machine's math library (session 81): a replay elsewhere tells a library's last bit from a
   * damaged log */
  cJSON_AddStringToObject(pj, "numerics", l->numerics);
  char *params = cJSON_PrintUnformatted(pj);
  cJSON_Delete(pj);
  /* Self-contained (parameters inlined), so the log alone rebuilds the world. */
  char *scene = palp_scene_to_json(i->scene);
  palp_db_session_def d = {.uid = uid,
                           .trainee = i->trainee_name,
                           .station = i->trainee_station,
                           .phantom_id = phantom,
                           .phantom_name = i->phantom_name,
                           .scene_json = scene ? scene : "{}",
                           .params_json = params ? params : "{}",
                           .tick_hz = i->tick_rate_hz,
                           .dt_s = i->dt};
  palp_db_session h = 0;
  int rc = palp_db_log_session_begin(l->w, &d, &h);
  free(scene);
  cJSON_free(params);
  if (rc < 0) {
    palp_log_error(l->log, "session log: session %u not logged: %s", i->session_id, palp_db_strerror(rc));
    return;
  }
  memset(s, 0, sizeof *s);
  s->h = h;
  s->last_flush_ns = palp_dds_now_ns();
  snprintf(s->uid, sizeof s->uid, "%s", uid);
  if (i->exercise_name && i->exercise_json) snprintf(s->exercise, sizeof s->exercise, "%s", i->exercise_name);
  /* Every physics step when the physics is slower than assess_sample_hz. */
  const double hz = i->assess_sample_hz > 0 ? i->assess_sample_hz : PALP_ASSESS_SAMPLE_HZ;
  s->sample_every = log_every(i->tick_rate_hz, hz);
  /* From the session's own physics rate, not the server's tick rate: a 1 kHz phantom on a
   * 100 Hz server logged every frame and a mesh 20 times a second (10x and 10x the intent),
   * and summarising and hashing each frame cost its tick ~10 us (issue 11). */
  s->frame_every = log_every(i->tick_rate_hz, 100.0);
  s->mesh_every = log_every(i->tick_rate_hz, 2.0);
  atomic_store_explicit(&l->ids[s - l->s], i->session_id, memory_order_release); /* filled: find may return it */
  if (i->exercise_name && i->exercise_json) {
    rc = palp_db_log_exercise(l->w, h, i->exercise_name, i->exercise_json);
    if (rc < 0)
      palp_log_error(l->log, "session log: session %u: exercise not logged: %s", i->session_id, palp_db_strerror(rc));
  }
  palp_db_log_event(l->w, h, PALP_DB_EVENT_JOIN, 0, i->trainee_station, 1);
}

static void on_closed(void *ctx, const palp_srv_session_summary *sum) {
  palp_srv_db_log *l = ctx;
  slot *s = find(l, sum->info.session_id);
  const char *why = sum->close_reason ? sum->close_reason : "";
  const palp_db_end_reason r = palp_db_end_reason_of(why); /* as palp-recorder classes the CLOSED state's reason */
  if (!s) {
    /* Not in the log (its start refused: the writer's queue full, or no slot): an exercise session is
     * still handed to the grader, which finds it missing and answers why ("not in the session log,
     * which is losing records ...; tell your instructor"), so that her station and the dashboard are
     * told rather than wait for a score that never comes (until session 90; found by review). */
    if (l->grader && sum->info.exercise_name && sum->info.exercise_json && r != PALP_DB_END_SERVER_SHUTDOWN) {
      char uid[96];
      session_uid(l, sum->info.session_id, uid, sizeof uid);
      palp_srv_grader_submit(l->grader, sum->info.session_id, uid, sum->info.exercise_name);
    }
    return;
  }
  flush_counts(l, s, s->last_frame);
  palp_db_log_event(l->w, s->h, PALP_DB_EVENT_LEAVE, s->last_frame, sum->info.trainee_station, 1);
  palp_db_log_session_end(l->w, s->h, r, why, 0);
  /* An exercise session is scored for the instructors once its end is in the log; not one the
   * server's shutdown closed: nobody would be told. */
  if (l->grader && s->exercise[0] && r != PALP_DB_END_SERVER_SHUTDOWN)
    palp_srv_grader_submit(l->grader, sum->info.session_id, s->uid, s->exercise);
  atomic_store_explicit(&l->ids[s - l->s], 0, memory_order_relaxed); /* free before its contents go */
  memset(s, 0, sizeof *s);
}

static int take_score(void *ctx, palp_srv_score *out) {
  palp_srv_db_log *l = ctx;
  return palp_srv_grader_take(l->grader, out);
}

/* Accepted findings are records; refusals are events, one by one up to a few per
 * second and then counted (a flooding station cannot flood the log). */
#define REFUSALS_LOGGED_PER_FLUSH 16
static void on_finding(void *ctx, uint32_t session_id, const palp_srv_finding_event *ev) {
  palp_srv_db_log *l = ctx;
  slot *s = find(l, session_id);
  if (!s) return;
  if (ev->accepted) {
    const palp_db_finding f = {.mark_id = ev->mark_id,
                               .op = ev->withdraw ? PALP_DB_FINDING_WITHDRAW : PALP_DB_FINDING_MARK,
                               .frame = ev->frame,
                               .sim_time_s = ev->sim_time,
                               .wall_unix_s = 0,
                               .point_m = ev->withdraw ? (palp_vec3){0, 0, 0} : ev->point};
    palp_db_log_finding(l->w, s->h, &f);
    return;
  }
  /* One ticket each: a refusal past the flush's allowance is counted for the next flush. */
  if (atomic_fetch_add(&s->refusals_logged, 1) >= REFUSALS_LOGGED_PER_FLUSH) {
    atomic_fetch_add(&s->findings_refused, 1);
    return;
  }
  char detail[200];
  snprintf(detail, sizeof detail, "finding %u refused: %s", ev->mark_id, ev->reason ? ev->reason : "");
  palp_db_log_event(l->w, s->h, PALP_DB_EVENT_REJECT, ev->frame, detail, 1);
}

/* What the trainee was told as her exercise session closed (docs/assessment.md, "Debrief"): the
 * review's "not blind" and its debrief line read it back (palp_db_session_debrief). */
static void on_debrief(void *ctx, uint32_t session_id, const palp_srv_debrief_event *ev) {
  palp_srv_db_log *l = ctx;
  slot *s = find(l, session_id);
  if (!s) return;
  palp_db_debrief d = {.sent = ev->sent,
                       .level = (palp_db_debrief_level)ev->level,
                       .lesions = (int)ev->lesions,
                       .found = (int)ev->found,
                       .marks = (int)ev->marks,
                       .false_marks = (int)ev->false_marks,
                       .duplicates = (int)ev->duplicates};
  if (ev->sent && ev->level == PALP_DB_DEBRIEF_LESIONS)
    for (uint32_t i = 0; i < ev->listed && i < PALP_DB_DEBRIEF_MAX_LESIONS; i++) d.found_by[d.listed++] = ev->found_by[i];
  if (!ev->sent) snprintf(d.why, sizeof d.why, "%s", ev->why && ev->why[0] ? ev->why : "(no reason given)");
  char detail[400];
  if (palp_db_debrief_format(&d, detail, sizeof detail) < 0) {
    palp_log_error(l->log, "session log: session %u's debrief contradicts itself; not logged", session_id);
    return;
  }
  palp_db_log_event(l->w, s->h, PALP_DB_EVENT_DEBRIEF, s->last_frame, detail, 1);
}

static void on_member(void *ctx, uint32_t session_id, const char *station, int role, int joined) {
  palp_srv_db_log *l = ctx;
  slot *s = find(l, session_id);
  if (!s) return;
  char detail[128];
  /* A trainee leaves and joins its own session only when its station was lost and held
   * (station_grace) and, the second time, came back. */
  if (role == palp_ROLE_TRAINEE)
    snprintf(detail, sizeof detail, "%.80s%s", station, joined ? PALP_DB_DETAIL_TRAINEE_BACK : PALP_DB_DETAIL_TRAINEE_HELD);
  else
    snprintf(detail, sizeof detail, "%s (%s)", station, role == palp_ROLE_VISUAL ? "visual" : "observer");
  palp_db_log_event(l->w, s->h, joined ? PALP_DB_EVENT_JOIN : PALP_DB_EVENT_LEAVE, -1, detail, 1);
}

/* ---- tick-thread hooks: enqueue only ------------------------------------------------- */

static void on_world_op(void *ctx, uint32_t session_id, const palp_srv_world_op *op) {
  palp_srv_db_log *l = ctx;
  slot *s = find(l, session_id);
  if (!s) return;
  palp_db_contact c;
  memset(&c, 0, sizeof c);
  c.frame = op->frame;
  c.sim_time_s = op->sim_time;
  c.slot = op->slot;
  c.op = (palp_db_contact_op)op->op;
  c.kind = op->kind == 2 ? PALP_DB_KIND_FINGER : PALP_DB_KIND_FORCE;
  c.def = op->def;
  c.force_n = op->force;
  c.center_m = op->center;
  c.radius_m = op->radius;
  palp_db_log_contact(l->w, s->h, &c);
  if (op->kind == 2 && op->op != PALP_SRV_OP_REMOVE && op->slot >= 0 && op->slot < SLOT_FINGERS)
    s->finger_radius[op->slot] = op->radius;
}

static void on_rejected(void *ctx, uint32_t session_id, palp_srv_reject_reason r, int clamped, uint64_t count) {
  palp_srv_db_log *l = ctx;
  slot *s = find(l, session_id);
  if (!s) return;
  if (clamped) s->clamped += count;
  else if ((unsigned)r < PALP_SRV_REJ_COUNT) s->rejected[r] += count;
}

static void on_input_gap(void *ctx, uint32_t session_id, int64_t frame, int finger, double gap_s, double depth_m) {
  (void)frame, (void)finger;
  palp_srv_db_log *l = ctx;
  slot *s = find(l, session_id);
  if (!s) return;
  if (depth_m > 0) {
    s->entries++;
    if (depth_m > s->entry_max) s->entry_max = depth_m;
  } else {
    s->gaps++;
    if (gap_s > s->gap_max) s->gap_max = gap_s;
  }
}

static void on_overrun(void *ctx, uint32_t session_id, uint64_t n, int64_t late_ns) {
  (void)late_ns;
  palp_srv_db_log *l = ctx;
  slot *s = find(l, session_id);
  if (s) s->overruns += n;
}

/* The parts are the station's (client/haptic_loop.c): depth, skin, the model's limits and the
 * literal gel law outside its stable range (LM_GEL_LAW_RANGE), whose frames are counted too. */
static void on_valid_range(void *ctx, uint32_t session_id, uint32_t flags, int64_t gel_dropped, double deepest_m) {
  palp_srv_db_log *l = ctx;
  slot *s = find(l, session_id);
  if (!s) return;
  s->range.steps++;
  if (flags & palp_LM_BEYOND_VALIDATED) s->range.depth_steps++;
  if (flags & palp_LM_LARGE_STRAIN) s->range.skin_steps++;
  if (flags & (palp_LM_OUT_OF_RANGE & ~palp_LM_LARGE_STRAIN)) s->range.limit_steps++;
  if (gel_dropped > 0) s->range.gel_steps++, s->range.gel_frames += gel_dropped;
  if (deepest_m > s->range.deepest_m) s->range.deepest_m = deepest_m;
}

static void on_frame(void *ctx, uint32_t session_id, const palp_world *w, const int *finger_slot,
                     const palp_vec3 *finger_force, int fingers) {
  palp_srv_db_log *l = ctx;
  slot *s = find(l, session_id);
  if (!s) return;
  int64_t frame = palp_world_frame(w);
  s->last_frame = frame;
  if (frame % s->frame_every == 0) {
    palp_db_frame f;
    palp_db_frame_summarize(w, &f);
    palp_db_log_frame(l->w, s->h, &f);
    for (int i = 0; i < fingers; i++)
      if (finger_slot[i] >= 0) palp_db_log_feedback(l->w, s->h, frame, finger_slot[i], finger_force[i]);
  }
  /* issue 13: the position-driven fingertips, what palp_assess scores. A force-driven
   * contact has no local model (the call refuses it). Cheap: a local model and the
   * touched triangles, copied into the queue. */
  if (frame % s->sample_every == 0)
    for (int i = 0; i < fingers; i++) {
      if (finger_slot[i] < 0 || finger_slot[i] >= SLOT_FINGERS) continue;
      palp_local_model m;
      if (palp_world_finger_local_model(w, finger_slot[i], &m) < 0) continue;
      int tri[PALP_DB_MAX_SAMPLE_TRIANGLES];
      double tf[PALP_DB_MAX_SAMPLE_TRIANGLES];
      int nt = palp_world_finger_contacts(w, finger_slot[i], tri, tf, PALP_DB_MAX_SAMPLE_TRIANGLES);
      if (nt < 0) nt = 0;
      const palp_db_finger_sample fs = {.frame = frame,
                                        .sim_time_s = palp_world_time(w),
                                        .slot = finger_slot[i],
                                        .radius_m = s->finger_radius[finger_slot[i]],
                                        .device_m = m.device,
                                        .proxy_m = m.proxy,
                                        .force_n = m.force,
                                        .in_contact = m.contact != 0,
                                        .point_m = m.point,
                                        .area_m2 = m.area,
                                        .triangle_count = nt,
                                        .triangles = nt ? (const int32_t *)tri : NULL};
      palp_db_log_finger_sample(l->w, s->h, &fs);
    }
  if (palp_world_is_awake(w) && frame >= s->next_mesh_frame) {
    palp_db_log_mesh(l->w, s->h, frame, palp_world_positions(w), palp_world_mesh(w)->vertex_count);
    s->next_mesh_frame = frame + s->mesh_every;
  }
  int64_t now = palp_dds_now_ns();
  if (now - s->last_flush_ns >= FLUSH_NS) {
    flush_counts(l, s, frame);
    s->last_flush_ns = now;
  }
}

/* Server-wide: the instructor's review lists who could not join, and why (palp-review list). */
static void on_security_refused(void *ctx, const char *detail, uint64_t count) {
  palp_srv_db_log *l = ctx;
  palp_db_log_event(l->w, 0, PALP_DB_EVENT_SECURITY_REFUSED, -1, detail, (int64_t)count);
}

/* The log's losses said in the server's log while it runs, not only at its stop (palp_db_loss_watch):
 * sessions go on meanwhile; an exercise session that lost records is scored from what its log holds,
 * and its score says the log is incomplete (docs/server.md, "A full session log"). */
static void watch_health(palp_srv_db_log *l, const palp_db_writer_stats *st) {
  char line[640];
  const int said = palp_db_loss_watch_look(&l->watch, st, palp_dds_now_ns(), line, sizeof line);
  if (said == 1)
    palp_log_warn(l->log, "%s; sessions go on; an exercise session is scored from what its log holds, and its score "
                          "says when that is incomplete", line);
  else if (said == 2)
    palp_log_info(l->log, "%s", line);
}

static void on_log_counts(void *ctx, uint64_t *written, uint64_t *shed, uint64_t *failed) {
  palp_srv_db_log *l = ctx;
  palp_db_writer_stats st;
  palp_db_writer_stats_get(l->w, &st);
  watch_health(l, &st);
  *written = (uint64_t)st.written;
  *shed = (uint64_t)st.shed;
  *failed = (uint64_t)st.failed;
}

static int on_session_log_losses(void *ctx, uint32_t session_id, uint64_t *shed, uint64_t *failed) {
  palp_srv_db_log *l = ctx;
  const slot *s = find(l, session_id);
  int64_t sh = 0, f = 0;
  if (!s || palp_db_writer_session_losses(l->w, s->h, &sh, &f) != 0) return 0;
  *shed = (uint64_t)sh;
  *failed = (uint64_t)f;
  return 1;
}

int palp_srv_db_log_open(const char *path, int64_t max_bytes, palp_log *log, palp_srv_db_log **out, char *err,
                         size_t errlen) {
  palp_srv_db_log *l = calloc(1, sizeof *l);
  if (!l) return PALP_ENOMEM;
  l->log = log;
  l->watch = (palp_db_loss_watch){.max_bytes = max_bytes > 0 ? max_bytes : 0, .cap_name = "session_log_max_mb"};
  palp_db_writer_opts o = palp_db_writer_default_opts();
  o.max_db_bytes = l->watch.max_bytes; /* PRAGMA max_page_count: at the cap, SQLITE_FULL as on a full disk */
  int rc = palp_db_writer_open(path, &o, &l->w, err, errlen);
  if (rc < 0) {
    free(l);
    return rc;
  }
  /* Said at the start, so that a log near its cap is moved or its cap raised before a class, not
   * found full at the end of one. */
  char line[320];
  const int full = palp_db_cap_describe(path, l->watch.max_bytes, "session_log_max_mb", line, sizeof line);
  if (line[0]) palp_logf(log, full ? PALP_LOG_WARN : PALP_LOG_INFO, "%s", line);
  /* Without a grader the server runs on; its sessions are only scored by the review. */
  rc = palp_srv_grader_open(path, l->w, log, &l->grader);
  if (rc != 0) {
    palp_log_warn(log, "session log: closed sessions will not be scored live (no grader thread: %s); palp-review "
                       "show scores them from the log", palp_strerror(rc));
    l->grader = NULL;
  }
  /* uid = <start time>-<pid>-<session>: unique across server runs on one host. */
  snprintf(l->run_id, sizeof l->run_id, "%lld-%ld", (long long)time(NULL), (long)getpid());
  snprintf(l->numerics, sizeof l->numerics, "%016llx", (unsigned long long)palp_numerics_fingerprint());
  l->ev = (palp_srv_events){.ctx = l,
                            .session_opened = on_opened,
                            .session_closed = on_closed,
                            .member_changed = on_member,
                            .world_op = on_world_op,
                            .contact_rejected = on_rejected,
                            .frame = on_frame,
                            .overrun = on_overrun,
                            .input_gap = on_input_gap,
                            .valid_range = on_valid_range,
                            .finding = on_finding,
                            .debrief = on_debrief,
                            .security_refused = on_security_refused,
                            .log_counts = on_log_counts,
                            .session_log_losses = on_session_log_losses,
                            /* A server whose grader did not start tells her so at once rather than
                             * leave her station waiting for a score that will not come. */
                            .take_score = l->grader ? take_score : NULL,
                            .unscored = "this server's grader did not start (its log says why); the "
                                        "instructor's review scores the session from the session log"};
  *out = l;
  return 0;
}

const palp_srv_events *palp_srv_db_log_events(palp_srv_db_log *l) { return &l->ev; }

void palp_srv_db_log_close(palp_srv_db_log *l) {
  if (!l) return;
  palp_srv_grader_close(l->grader); /* it waits on the writer: stopped first */
  palp_db_writer_flush(l->w, 10.0);
  palp_db_writer_stats st;
  palp_db_writer_stats_get(l->w, &st);
  palp_logf(l->log, st.shed || st.failed ? PALP_LOG_WARN : PALP_LOG_INFO,
            "session log: %lld records written, %lld shed (queue full), %lld failed%s%s",
            (long long)st.written, (long long)st.shed, (long long)st.failed, st.last_error[0] ? ": " : "",
            st.last_error);
  palp_db_writer_close(l->w);
  free(l);
}
