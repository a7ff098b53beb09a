/* session.c - one trainee's session: its world, its partition, its tick. */
#include "session.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp_dds.h"

#define TAKE_BATCH 8
/* While the world sleeps with no finger down, feedback (all zero, unchanged) is
 * repeated at 10 Hz instead of every tick: a station still sees the server alive,
 * and 32 idle sessions do not cost 32 000 writes per second. */
#define IDLE_FEEDBACK_PERIOD_NS 100000000
/* A sleeping world's shape is sent again once a second while a display watches. The displays read
 * palp_deformation best-effort (palp_dds_create_display_reader), so a lost last frame is repaired
 * within this period instead of leaving a page on a stale dent until the next touch (docs/server.md). */
#define PALP_SRV_REST_REFRESH_NS 1000000000
/* A force contact whose centre moves by more than this is re-snapped [m]. */
#define RESNAP_DISTANCE 1e-4

/* The contact reader holds at most this many instances: the 4 fingers of its
 * session and room for a few disposes of unknown keys (a dispose bypasses the
 * filter). Cyclone refuses (best-effort: drops) samples of instances beyond it,
 * so no peer can make the server's memory grow with keys. */
#define CONTACT_MAX_INSTANCES 32

static double norm3(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }
static double dist3(palp_vec3 a, palp_vec3 b) {
  return norm3((palp_vec3){a.x - b.x, a.y - b.y, a.z - b.z});
}

/* Runs on Cyclone's receive thread before a sample enters the reader cache: a
 * sample of another session, or of a finger past the last, never becomes an
 * instance, whatever its key. Counted here, folded into the session's rejection
 * counters by its tick. */
static bool contact_filter(const void *sample, void *arg) {
  const palp_Contact *c = sample;
  palp_srv_session *s = arg;
  if (c->session_id != s->id) {
    atomic_fetch_add_explicit(&s->filtered_session, 1, memory_order_relaxed);
    return false;
  }
  if (c->finger >= PALP_SRV_MAX_FINGERS) {
    atomic_fetch_add_explicit(&s->filtered_finger, 1, memory_order_relaxed);
    return false;
  }
  if (c->mode == palp_CONTACT_FINGER) {
    palp_srv_arrival *a = &s->arrival[c->finger][c->seq % 16];
    atomic_store_explicit(&a->seq, 0, memory_order_relaxed); /* no match while it is rewritten */
    atomic_thread_fence(memory_order_release);
    atomic_store_explicit(&a->recv_ns, palp_dds_now_ns(), memory_order_relaxed);
    atomic_store_explicit(&a->seq, c->seq, memory_order_release);
  }
  return true;
}

/* The finding reader's filter (DDS receive thread): this session's findings only. A finding naming
 * another session is a peer's in this partition (an unsecured classroom, or a trainee writing into
 * her own partition): each made-up session id would be an instance of the reader; dropped here and
 * counted, the main thread logs it (handle_findings). */
static bool finding_filter(const void *sample, void *arg) {
  const palp_Finding *f = sample;
  palp_srv_session *s = arg;
  if (f->session_id == s->id) return true;
  atomic_store_explicit(&s->filtered_finding_session, f->session_id, memory_order_relaxed);
  atomic_fetch_add_explicit(&s->filtered_findings, 1, memory_order_relaxed);
  return false;
}

/* When sample seq of finger arrived, if the filter stamped it (else the take's time). */
static int64_t arrival_ns(palp_srv_session *s, int finger, uint64_t seq, int64_t taken_ns) {
  palp_srv_arrival *a = &s->arrival[finger][seq % 16];
  if (seq == 0 || atomic_load_explicit(&a->seq, memory_order_acquire) != seq) return taken_ns;
  const int64_t t = atomic_load_explicit(&a->recv_ns, memory_order_relaxed);
  atomic_thread_fence(memory_order_acquire);
  if (atomic_load_explicit(&a->seq, memory_order_relaxed) != seq || t > taken_ns) return taken_ns;
  return t;
}

palp_srv_session *palp_srv_session_create(const palp_srv_session_def *def, int *err) {
  static const dds_guid_t unknown_guid; /* all zero: no participant has it */
  if (!memcmp(&def->trainee_participant, &unknown_guid, sizeof unknown_guid)) {
    *err = PALP_EINVAL; /* unbound, anyone in its partition would palpate it */
    return NULL;
  }
  palp_srv_session *s = calloc(1, sizeof *s);
  if (!s) {
    *err = PALP_ENOMEM;
    return NULL;
  }
  s->id = def->id;
  s->trainee_participant = def->trainee_participant;
  s->contact_writers = (palp_srv_writer_check){.what = "contacts",
                                               .rule = "the session is palpated only from",
                                               .counted = "its samples are counted as foreign_participant",
                                               .suspects = "another process in its partition: a stale station of "
                                                           "that name, or a second participant of the same identity"};
  s->finding_writers = (palp_srv_writer_check){.what = "findings",
                                               .rule = "the session's findings are marked only from",
                                               .counted = "its findings go unanswered, each a refusal in the "
                                                          "session log",
                                               .suspects = "another process in its partition: a stale station of "
                                                           "that name, a second participant of the same identity, or "
                                                           "a palp-web not joined to the session"};
  s->phantom = def->phantom;
  s->events = def->events;
  s->log = def->log;
  s->reaper = def->reaper;
  s->log_interval = def->cfg->log_interval;
  s->deformation_period = 1.0 / def->cfg->deformation_rate_hz;
  s->assess_sample_hz = def->cfg->assess_sample_hz;
  snprintf(s->trainee_station, sizeof s->trainee_station, "%s", def->trainee_station);
  snprintf(s->trainee_name, sizeof s->trainee_name, "%s", def->trainee_name);
  if (def->partition && def->partition[0])
    snprintf(s->partition, sizeof s->partition, "%s", def->partition);
  else
    palp_dds_session_partition(s->id, s->partition, sizeof s->partition);
  for (int i = 0; i < PALP_SRV_MAX_FINGERS; i++) s->finger[i].world_contact = -1;

  s->exercise = def->phantom->exercise;
  s->scene = &def->phantom->scene;
  s->exercise_json = def->phantom->exercise_json;
  if (s->exercise && s->exercise->placement.kind == PALP_PLACEMENT_RANDOM) {
    /* This session's own lesions: the phantom's scene with the exercise's lesions moved to a draw
     * of their own. The scene's lesions are all the exercise's (a phantom with lesions of its own
     * is refused, palp_exercise_scene), as many as count_max of them (session 83; all those listed
     * before), so the session's draw replaces them from index 0. */
    s->own_exercise = malloc(sizeof *s->own_exercise);
    s->own_scene = malloc(sizeof *s->own_scene);
    if (!s->own_exercise || !s->own_scene) {
      *err = PALP_ENOMEM;
      goto fail;
    }
    char msg[256] = "";
    const double R = def->phantom->scene.world.mesh.radius;
    *s->own_scene = def->phantom->scene;
    /* A file whose lesions fit its band only now and then (the server's start proved one draw of
     * each set a session may hide) must
     * not turn a trainee away: other seeds, derived from hers, before giving up. */
    int rc = PALP_EINVAL, tries = 0;
    for (; tries < 16 && rc != 0; tries++)
      rc = palp_exercise_draw(s->exercise, R, def->placement_seed + 0x9e3779b9u * (uint32_t)tries, s->own_exercise, msg,
                              sizeof msg);
    if (rc == 0 && tries > 1)
      palp_log_warn(def->log, "session %u: its lesions were placed at the %d-th seed (%s)", def->id, tries, msg);
    if (rc == 0) {
      /* this session's lesions in place of the exercise's (as many as its draw hides: maybe fewer) */
      rc = palp_exercise_lesions(s->own_exercise, R, s->own_scene->world.lesion, PALP_MAX_LESIONS, msg, sizeof msg);
      if (rc >= 0) s->own_scene->world.lesion_count = rc;
    }
    if (rc >= 0 && !(s->own_exercise_json = palp_exercise_drawn_json(def->phantom->exercise_json, s->own_exercise)))
      rc = PALP_ENOMEM;
    if (rc < 0) {
      palp_log_error(def->log, "session %u: its lesions could not be drawn: %s", def->id, msg[0] ? msg : palp_strerror(rc));
      if (def->refusal)
        snprintf(def->refusal, def->refusal_len,
                 "its lesions could not be placed (the exercise file asks too much; the server's log says why)");
      *err = rc;
      goto fail;
    }
    s->exercise = s->own_exercise;
    s->scene = s->own_scene;
    s->exercise_json = s->own_exercise_json;
  }
  /* Built the way a recorder replays it (db/palp_db.h): the scene with its own
   * contacts, then those contacts removed; stations drive the contacts. */
  s->world = palp_scene_create_world(s->scene, err);
  if (!s->world) goto fail;
  for (int i = 0; i < def->phantom->scene.contact_count; i++) palp_world_remove_contact(s->world, i);
  const palp_mesh *mesh = palp_world_mesh(s->world);
  s->limits = (palp_srv_limits){.session_id = s->id,
                                .max_force = def->cfg->max_force,
                                .absurd_force = def->cfg->absurd_force,
                                .force_policy = def->cfg->force_policy,
                                .finger_radius_min = def->cfg->finger_radius_min,
                                .finger_radius_max = def->cfg->finger_radius_max,
                                .phantom_radius = def->phantom->scene.world.mesh.radius,
                                .vertex_count = mesh->vertex_count,
                                .rest = mesh->rest};
  /* Within the validator's reach; a gap caught up at most PALP_SRV_PLAYOUT_CATCHUP world steps a step. */
  for (int i = 0; i < PALP_SRV_MAX_FINGERS; i++)
    palp_srv_playout_init(&s->finger[i].playout, PALP_SRV_FINGER_REACH_RADII * s->limits.phantom_radius,
                          palp_world_get_def(s->world)->dt);

  s->deformation.session_id = s->id;
  s->deformation.positions._buffer = calloc((size_t)mesh->vertex_count, sizeof(palp_Vec3));
  if (!s->deformation.positions._buffer) {
    *err = PALP_ENOMEM;
    goto fail;
  }
  s->deformation.positions._maximum = s->deformation.positions._length = (uint32_t)mesh->vertex_count;
  s->deformation.rest_volume = palp_world_rest_volume(s->world);
  s->fb.session_id = s->id;
  s->fb.fingers._buffer = s->fb_fingers;
  s->fb.fingers._maximum = PALP_SRV_MAX_FINGERS;

  s->sub = palp_dds_session_subscriber(def->participant, s->partition);
  s->pub = palp_dds_session_publisher(def->participant, s->partition);
  if (s->sub < 0 || s->pub < 0) goto dds_fail;
  /* A topic entity of its own (same name and type as everyone's) so that its
   * filter applies to this session's reader only. */
  (void)def->contact_topic;
  s->contact_topic = palp_dds_create_topic(def->participant, PALP_TOPIC_CONTACT);
  if (s->contact_topic < 0) goto dds_fail;
  {
    struct dds_topic_filter flt = {.mode = DDS_TOPIC_FILTER_SAMPLE_ARG, .f = {.sample_arg = contact_filter}, .arg = s};
    if (dds_set_topic_filter_extended(s->contact_topic, &flt) < 0) goto dds_fail;
    dds_qos_t *q = palp_dds_qos(PALP_TOPIC_CONTACT);
    dds_qset_resource_limits(q, CONTACT_MAX_INSTANCES, CONTACT_MAX_INSTANCES, 1);
    s->contact_reader = dds_create_reader(s->sub, s->contact_topic, q, NULL);
    dds_delete_qos(q);
  }
  s->feedback_writer = palp_dds_create_writer(s->pub, def->feedback_topic, PALP_TOPIC_FEEDBACK);
  s->deformation_writer = palp_dds_create_writer(s->pub, def->deformation_topic, PALP_TOPIC_DEFORMATION);
  if (def->local_model_topic > 0)
    s->local_model_writer = palp_dds_create_writer(s->pub, def->local_model_topic, PALP_TOPIC_LOCAL_MODEL);
  if (s->contact_reader < 0 || s->feedback_writer < 0 || s->deformation_writer < 0 || s->local_model_writer < 0)
    goto dds_fail;
  /* issue 13: findings (docs/assessment.md). Read and answered by the server's main
   * thread, not the tick: a mark is a rare event, and its log record needs no step. */
  if (def->finding_topic > 0 && def->finding_status_topic > 0) {
    s->finding_topic = palp_dds_create_topic(def->participant, PALP_TOPIC_FINDING);
    struct dds_topic_filter flt = {.mode = DDS_TOPIC_FILTER_SAMPLE_ARG, .f = {.sample_arg = finding_filter}, .arg = s};
    if (s->finding_topic < 0 || dds_set_topic_filter_extended(s->finding_topic, &flt) < 0) goto dds_fail;
    /* no bound on its instances (palp_dds_reader_qos): a reliable sample refused for one stalls delivery */
    s->finding_reader = palp_dds_create_reader(s->sub, s->finding_topic, PALP_TOPIC_FINDING);
    s->finding_status_writer = palp_dds_create_writer(s->pub, def->finding_status_topic, PALP_TOPIC_FINDING_STATUS);
    if (s->finding_reader < 0 || s->finding_status_writer < 0) goto dds_fail;
    s->finding_rc = dds_create_readcondition(s->finding_reader, DDS_ANY_STATE);
    if (s->finding_rc < 0) goto dds_fail;
    /* A mark is a contact point: on the skin, or pressed into it no deeper than the exercise's
     * deepest band (server/findings.h). */
    const palp_srv_findings_limits fl = {.session_id = s->id,
                                         .dome_radius = def->phantom->scene.world.mesh.radius,
                                         .depth_max = palp_srv_findings_depth_max(def->phantom->exercise),
                                         .height_max = PALP_SRV_MARK_HEIGHT,
                                         .rate = PALP_SRV_FINDING_RATE,
                                         .burst = PALP_SRV_FINDING_BURST,
                                         .time_limit = s->exercise ? s->exercise->time_limit : 0.0};
    palp_srv_findings_init(&s->findings, &fl);
  }
  /* Only an exercise's session is debriefed (docs/assessment.md, "Debrief"). */
  if (def->debrief_topic > 0 && def->phantom->exercise) {
    s->debrief_writer = palp_dds_create_writer(s->pub, def->debrief_topic, PALP_TOPIC_DEBRIEF);
    if (s->debrief_writer < 0) goto dds_fail;
  }
  /* The steps the log samples, from the session's own physics rate (server/db_log.c). */
  {
    const double hz = s->assess_sample_hz > 0 ? s->assess_sample_hz : PALP_ASSESS_SAMPLE_HZ;
    s->sample_every = palp_assess_sample_every(1.0 / def->phantom->scene.world.dt, hz);
  }
  if (def->finger_sample_topic > 0) {
    s->finger_sample_writer = palp_dds_create_writer(s->pub, def->finger_sample_topic, PALP_TOPIC_FINGER_SAMPLE);
    if (s->finger_sample_writer < 0) goto dds_fail;
  }
  /* Only where something logs the session: its station then hears its own losses, not the server's. */
  if (def->session_log_topic > 0 && def->events && def->events->session_log_losses) {
    s->session_log_writer = palp_dds_create_writer(s->pub, def->session_log_topic, PALP_TOPIC_SESSION_LOG);
    if (s->session_log_writer < 0) goto dds_fail;
  }
  palp_world_get_health(s->world, &s->health);
  s->opened_ns = palp_dds_now_ns();
  *err = 0;
  return s;
dds_fail:
  *err = PALP_EIO;
fail:
  palp_srv_session_destroy(s);
  return NULL;
}

void palp_srv_session_factor_settle(palp_srv_session *s) {
  if (!s->factor.job) return;
  palp_srv_factor_wait(s->factor_pool, &s->factor);
  palp_world_factor_done(s->world, s->factor.job);
  s->factor.job = NULL;
}

void palp_srv_session_destroy(palp_srv_session *s) {
  if (!s) return;
  palp_srv_session_factor_settle(s); /* the helper may still be writing into the world's job */
  /* Deleting the publisher/subscriber deletes their readers and writers. The subscriber here and now: its
   * readers' filters take s as their argument. The publisher's writers have just written the CLOSED
   * state's companions (the debrief, the answers, the last feedback), whose acknowledgement by the stations
   * their delete waits for: 5-100 ms a session in the demo, 1 s against a stalled station, the main loop
   * answering no request meanwhile (until 2026-12-07): the reaper's thread waits instead. */
  if (s->sub > 0) dds_delete(s->sub);
  if (s->pub > 0 && (!s->reaper || palp_dds_reaper_put(s->reaper, s->pub) != 0)) dds_delete(s->pub);
  /* After its reader: nothing calls the filter (whose argument is s) any more. */
  if (s->contact_topic > 0) dds_delete(s->contact_topic);
  if (s->finding_topic > 0) dds_delete(s->finding_topic);
  free(s->deformation.positions._buffer);
  palp_world_destroy(s->world);
  free(s->own_exercise);
  free(s->own_scene);
  free(s->own_exercise_json);
  free(s);
}

/* n samples rejected (or clamped) for one reason: counted, told to the events and the log once
 * (the filter's drops arrive as one count: until session 75 they were folded in one by one on
 * the tick thread, an event and a clock comparison per sample of a flood). */
static void count_rejects(palp_srv_session *s, palp_srv_reject_reason r, int clamped, uint64_t n, int64_t now_ns) {
  if (n == 0) return;
  s->stats.rejected[r] += n;
  if (s->events && s->events->contact_rejected) s->events->contact_rejected(s->events->ctx, s->id, r, clamped, n);
  /* Rate-limited: a station flooding NaN at 1 kHz yields one line per interval. */
  if (now_ns - s->last_log_ns[r] >= (int64_t)(s->log_interval * 1e9)) {
    palp_log_warn(s->log, "session %u: contact %s: %s (%llu more since last report)", s->id,
            clamped ? "clamped" : "rejected", palp_srv_reject_name(r),
            (unsigned long long)(s->log_suppressed[r] + n - 1));
    s->last_log_ns[r] = now_ns;
    s->log_suppressed[r] = 0;
  } else {
    s->log_suppressed[r] += n;
  }
}

static void count_reject(palp_srv_session *s, palp_srv_reject_reason r, int clamped, int64_t now_ns) {
  count_rejects(s, r, clamped, 1, now_ns);
}

static void emit_op(palp_srv_session *s, int finger, int slot, palp_srv_world_op_kind op, int kind,
                    const palp_contact_def *def, palp_vec3 force, palp_vec3 center, double radius) {
  /* Replay contract: every world operation, and nothing else, wakes the world. An
   * input that changes nothing (a release with nothing pressed) must not wake it,
   * or the live world would step where the replayed one sleeps. */
  palp_world_wake(s->world);
  if (!s->events || !s->events->world_op) return;
  palp_srv_world_op o;
  memset(&o, 0, sizeof o);
  o.frame = palp_world_frame(s->world);
  o.sim_time = palp_world_time(s->world);
  o.finger = finger;
  o.slot = slot;
  o.op = op;
  o.kind = kind;
  if (def) o.def = *def;
  o.force = force;
  o.center = center;
  o.radius = radius;
  s->events->world_op(s->events->ctx, s->id, &o);
}

static void lift(palp_srv_session *s, palp_srv_finger_state *f) {
  if (f->world_contact >= 0) {
    palp_world_remove_contact(s->world, f->world_contact);
    /* The log names what was lifted: 1 force-driven, 2 position-driven finger. */
    const int kind = f->mode == palp_CONTACT_FINGER ? 2 : 1;
    emit_op(s, (int)(f - s->finger), f->world_contact, PALP_SRV_OP_REMOVE, kind, NULL, (palp_vec3){0, 0, 0},
            (palp_vec3){0, 0, 0}, 0);
  }
  f->world_contact = -1;
  f->mode = palp_CONTACT_RELEASE;
  f->feedback = (palp_vec3){0, 0, 0};
  palp_srv_playout_clear(&f->playout);
}

/* Applies a validated command; returns 0 or a negative model error. */
static int apply(palp_srv_session *s, const palp_srv_contact *c) {
  palp_srv_finger_state *f = &s->finger[c->finger];
  int rc = 0;
  switch (c->mode) {
  case palp_CONTACT_RELEASE: lift(s, f); break;
  case palp_CONTACT_FORCE: {
    int resnap = f->mode != palp_CONTACT_FORCE || f->world_contact < 0 ||
                 f->cmd.distribution != c->distribution || dist3(f->cmd.center, c->center) > RESNAP_DISTANCE ||
                 f->cmd.patch_area != c->patch_area || dist3(f->cmd.offset_dir, c->offset_dir) > 1e-9;
    if (resnap) {
      lift(s, f);
      palp_contact_def d = palp_contact_default_def(c->distribution, c->center);
      if (c->patch_area > 0) d.patch_area = c->patch_area;
      if (norm3(c->offset_dir) > 0) d.offset_dir = c->offset_dir;
      int id = palp_world_add_contact(s->world, &d);
      if (id < 0) return id;
      rc = palp_world_set_contact_force(s->world, id, c->force);
      if (rc < 0) {
        /* Undo, so the world and the log agree that nothing happened. */
        palp_world_remove_contact(s->world, id);
        return rc;
      }
      f->world_contact = id;
      f->mode = palp_CONTACT_FORCE;
      emit_op(s, c->finger, id, PALP_SRV_OP_ADD, 1, &d, c->force, c->center, 0);
    } else {
      rc = palp_world_set_contact_force(s->world, f->world_contact, c->force);
      if (rc == 0) emit_op(s, c->finger, f->world_contact, PALP_SRV_OP_UPDATE, 1, NULL, c->force, c->center, 0);
    }
    double fm = norm3(c->force);
    if (fm > s->stats.peak_force) s->stats.peak_force = fm;
    break;
  }
  case palp_CONTACT_FINGER:
    if (f->mode != palp_CONTACT_FINGER || f->world_contact < 0) {
      lift(s, f);
      int id = palp_world_add_finger(s->world, c->center, c->radius);
      if (id < 0) return id;
      f->world_contact = id;
      f->mode = palp_CONTACT_FINGER;
      emit_op(s, c->finger, id, PALP_SRV_OP_ADD, 2, NULL, (palp_vec3){0, 0, 0}, c->center, c->radius);
    } else {
      rc = palp_world_set_finger(s->world, f->world_contact, c->center, c->radius);
      if (rc == 0)
        emit_op(s, c->finger, f->world_contact, PALP_SRV_OP_UPDATE, 2, NULL, (palp_vec3){0, 0, 0}, c->center,
                c->radius);
    }
    break;
  default: return PALP_EINVAL;
  }
  if (rc < 0) return rc;
  f->cmd = *c; /* the world was woken by emit_op if anything changed in it */
  return 0;
}

/* A refused writer, named in the server's log with the session and its station: the first at once,
 * then at most one a log_interval per reader (a flood of new writers writes no flood of lines), each
 * naming how many went unnamed since. e: its entry (own 0: another participant's; -1: gone already);
 * also: whether another participant could have been let in (the log says who may write). */
static void say_foreign_writer(palp_srv_session *s, palp_srv_writer_check *wc, const palp_srv_writer_entry *e,
                               int also, int64_t now_ns) {
  wc->foreign_writers++;
  if (wc->foreign_said_ns && now_ns - wc->foreign_said_ns < (int64_t)(s->log_interval * 1e9)) {
    wc->foreign_unnamed++;
    return;
  }
  char who[64], own[64], unnamed[96] = "";
  if (e->own == 0)
    palp_dds_participant_text(&e->participant, who, sizeof who);
  else
    snprintf(who, sizeof who, "a writer already gone");
  palp_dds_participant_text(&s->trainee_participant, own, sizeof own);
  if (wc->foreign_unnamed)
    snprintf(unnamed, sizeof unnamed, "; %llu other such writer%s since the last one named",
             (unsigned long long)wc->foreign_unnamed, wc->foreign_unnamed == 1 ? "" : "s");
  palp_log_warn(s->log, "session %u (trainee station %s): %s from %s%s refused: %s %s, whose request joined it%s "
                        "(%s); %s%s",
                s->id, PALP_PRINTABLE(s->trainee_station), wc->what, e->own == 0 ? "a writer of " : "", who, wc->rule,
                own, also ? ", or from a visual station it admitted" : "",
                e->own == 0 ? wc->suspects : "gone before it was looked up, it cannot be shown to be the trainee's",
                wc->counted, unnamed);
  wc->foreign_said_ns = now_ns;
  wc->foreign_unnamed = 0;
}

/* The entry of writer `pub`, looked up on `reader` when wc does not keep it. A miss asks the reader
 * (dds_get_matched_publication_data walks its matched writers and copies one's QoS), once for each
 * sample taken at most, so a flood of new writers costs a pass no more lookups than the take's bound.
 * A writer no longer matched when first looked up cannot be shown to be the trainee's (own -1: a
 * station's writer lives for its session and is looked up at its first sample). */
static palp_srv_writer_entry *writer_entry(palp_srv_session *s, palp_srv_writer_check *wc, dds_entity_t reader,
                                           dds_instance_handle_t pub) {
  for (int i = 0; i < PALP_SRV_WRITERS_KEPT; i++)
    if (wc->e[i].pub == pub) return &wc->e[i];
  palp_srv_writer_entry n = {.pub = pub, .own = -1};
  dds_builtintopic_endpoint_t *ep = dds_get_matched_publication_data(reader, pub);
  if (ep) {
    n.participant = ep->participant_key;
    n.own = !memcmp(ep->participant_key.v, s->trainee_participant.v, sizeof s->trainee_participant.v);
    dds_builtintopic_free_endpoint(ep);
  }
  /* A free entry, else the next refused one from the hand, else (all the trainee's own: a station
   * found again eight times) the hand's: a writer forgotten is looked up again. */
  palp_srv_writer_entry *slot = NULL;
  for (int i = 0; i < PALP_SRV_WRITERS_KEPT && !slot; i++)
    if (!wc->e[i].pub) slot = &wc->e[i];
  for (int k = 0; k < PALP_SRV_WRITERS_KEPT && !slot; k++) {
    const unsigned at = (wc->hand + (unsigned)k) % PALP_SRV_WRITERS_KEPT;
    if (wc->e[at].own != 1) slot = &wc->e[at], wc->hand = (at + 1) % PALP_SRV_WRITERS_KEPT;
  }
  if (!slot) {
    slot = &wc->e[wc->hand];
    wc->hand = (wc->hand + 1) % PALP_SRV_WRITERS_KEPT;
  }
  *slot = n;
  return slot;
}

int palp_srv_session_writer_ok(palp_srv_session *s, palp_srv_writer_check *wc, dds_entity_t reader,
                               dds_instance_handle_t pub, int64_t now_ns, palp_srv_participant_ok_fn also, void *ctx) {
  if (pub == 0) return 0;
  palp_srv_writer_entry *e = writer_entry(s, wc, reader, pub);
  if (e->own == 1) return 1;
  /* Asked each time, not kept: a visual station may join after its writer's first sample, or leave. */
  if (e->own == 0 && also && also(ctx, &e->participant)) return 1;
  if (!e->named) {
    e->named = 1;
    say_foreign_writer(s, wc, e, also != NULL, now_ns);
  }
  return 0;
}

/* Folds the filter's counts into the rejection counters (and the log). */
static void fold_filtered(palp_srv_session *s, int64_t now_ns) {
  uint64_t fs = atomic_load_explicit(&s->filtered_session, memory_order_relaxed);
  uint64_t ff = atomic_load_explicit(&s->filtered_finger, memory_order_relaxed);
  if (fs > s->filtered_seen_session)
    count_rejects(s, PALP_SRV_REJ_UNKNOWN_SESSION, 0, fs - s->filtered_seen_session, now_ns);
  if (ff > s->filtered_seen_finger) count_rejects(s, PALP_SRV_REJ_BAD_FINGER, 0, ff - s->filtered_seen_finger, now_ns);
  s->filtered_seen_session = fs;
  s->filtered_seen_finger = ff;
}

/* Moves each placed finger's device to its played-out point (playout.h): once per
 * tick, whatever number of samples came, and only when it is new (a new point, or a
 * newer station time for the same point, which the local model echoes for the
 * station's latency compensation), so a still device lets the world sleep. */
static void play_out(palp_srv_session *s, int64_t recv_ns, int64_t now_ns) {
  for (int i = 0; i < PALP_SRV_MAX_FINGERS; i++) {
    palp_srv_finger_state *f = &s->finger[i];
    if (f->mode != palp_CONTACT_FINGER || f->world_contact < 0) continue;
    palp_srv_contact c = f->cmd;
    const uint64_t gaps = f->playout.gaps;
    if (palp_srv_playout_at(&f->playout, recv_ns, &c.center, &c.source_time_ns, &c.seq) <= 0) continue;
    if (f->playout.gaps != gaps && s->events && s->events->input_gap)
      s->events->input_gap(s->events->ctx, s->id, palp_world_frame(s->world), i, f->playout.gap_last, 0);
    if (c.source_time_ns == f->cmd.source_time_ns && c.center.x == f->cmd.center.x &&
        c.center.y == f->cmd.center.y && c.center.z == f->cmd.center.z)
      continue;
    if (apply(s, &c) < 0) count_reject(s, PALP_SRV_REJ_MODEL, 0, now_ns);
  }
}

/* Where a finger placed below the phantom's surface is placed instead (docs/server.md, "A finger
 * placed below the surface"). A station that comes back from a stall longer than its lease (its
 * fingers lifted meanwhile: the server could not tell it from a station gone), or one that joins
 * with its device pressed in, places its finger millimetres deep in a phantom at rest, and the
 * world answered within one step with the phantom's viscous response to those millimetres in 4 ms
 * (measured, the paper's membrane, 12 mm deep in a slide whose peak is 0.36 N: 4.40 N after a
 * 0.6 s stop of the station). The finger is placed where its tip touches the undeformed dome, on
 * the dome's radius through the device point, standing for the station time the hand would have
 * been there pressing in at a palpation's speed (ENTRY_SPEED); the playout then brings it to the
 * device point as it catches a gap up (playout.h). 1 when *placed was moved. */
#define ENTRY_MIN 0.0005  /* [m] a first point this shallow is placed where it is */
#define ENTRY_SPEED 0.020 /* [m/s] a palpating hand's pressing speed (docs/station.md) */
#define ENTRY_LEAD_MAX 1.0 /* [s] */
static int entry_point(const palp_srv_session *s, const palp_srv_contact *c, palp_srv_contact *placed) {
  const double touch = s->limits.phantom_radius + c->radius; /* |x| where the tip meets the dome [m] */
  const double r = norm3(c->center), depth = touch - r;
  if (!(depth > ENTRY_MIN) || !(c->center.z > 0)) return 0; /* above it, or beside its base */
  /* at most 1 s before it (a 20 mm deep point: brought in at 20 mm/s or faster), which the playout
   * catches up rather than jumps (its CATCHUP_MAX) */
  const double lead_ns = fmin(depth / ENTRY_SPEED, ENTRY_LEAD_MAX) * 1e9;
  if ((double)c->source_time_ns - lead_ns <= -4.6e18) return 0; /* before any clock reading: as it is */
  placed->center = r > 1e-9 ? (palp_vec3){c->center.x * touch / r, c->center.y * touch / r, c->center.z * touch / r}
                            : (palp_vec3){0, 0, touch};
  placed->source_time_ns = c->source_time_ns - (int64_t)lead_ns;
  return 1;
}

static void take_contacts(palp_srv_session *s, int64_t now_ns) {
  fold_filtered(s, now_ns);
  /* Now: when the samples of this take had all arrived. Each one's own arrival is
   * the filter's stamp (arrival_ns); this is the playout's clock and the fallback. */
  const int64_t recv_ns = palp_dds_now_ns();
  palp_Contact buf[TAKE_BATCH];
  void *ptr[TAKE_BATCH];
  dds_sample_info_t info[TAKE_BATCH];
  for (int i = 0; i < TAKE_BATCH; i++) ptr[i] = &buf[i];
  /* At most what the reader can hold per tick: a peer writing faster than the tick
   * drains cannot keep it in this loop; the rest waits for the next tick. */
  for (int round = 0; round < CONTACT_MAX_INSTANCES / TAKE_BATCH; round++) {
    int n = dds_take(s->contact_reader, ptr, info, TAKE_BATCH, TAKE_BATCH);
    if (n <= 0) break;
    for (int i = 0; i < n; i++) {
      if (!info[i].valid_data) {
        /* The finger's writer is gone or disposed it: lift that finger so a
         * vanished station does not keep pressing until its session closes. */
        /* Cyclone fills an invalid sample's key fields, so the finger is read
         * from it: dds_instance_get_key scans every instance the participant
         * ever saw (quadratic under a flood of keys). */
        if (info[i].instance_state != DDS_IST_ALIVE && buf[i].session_id == s->id &&
            buf[i].finger < PALP_SRV_MAX_FINGERS) {
          /* Only the trainee's own writers lift its fingers: the writer that placed this one (known
           * without a lookup: it may be gone by now, and gone it could not be looked up), or another
           * of its participant. Another participant's dispose is refused like its contacts (until
           * 2026-12-06 anyone in the partition could lift the trainee's finger). */
          palp_srv_finger_state *f = &s->finger[buf[i].finger];
          if ((f->writer && info[i].publication_handle == f->writer) ||
              palp_srv_session_writer_ok(s, &s->contact_writers, s->contact_reader, info[i].publication_handle, now_ns,
                                         NULL, NULL))
            lift(s, f);
          else
            count_reject(s, PALP_SRV_REJ_FOREIGN_PARTICIPANT, 0, now_ns);
        }
        continue;
      }
      /* Only the participant that joined the session palpates it (until 2026-12-06 any writer in
       * its partition did: in an unsecured classroom anyone who knew the station's name, in a
       * secured one a second participant of the same identity). Before the checks: a foreign
       * sample is refused for being foreign, whatever else is wrong with it. */
      if (!palp_srv_session_writer_ok(s, &s->contact_writers, s->contact_reader, info[i].publication_handle, now_ns,
                                      NULL, NULL)) {
        count_reject(s, PALP_SRV_REJ_FOREIGN_PARTICIPANT, 0, now_ns);
        continue;
      }
      palp_srv_contact c;
      palp_srv_reject_reason why = PALP_SRV_REJ_COUNT;
      int v = palp_srv_validate_contact(&buf[i], &s->limits, &c, &why);
      if (v == PALP_SRV_REJECT) {
        count_reject(s, why, 0, now_ns);
        continue;
      }
      if (v == PALP_SRV_CLAMPED) count_reject(s, why, 1, now_ns);
      palp_srv_finger_state *f = &s->finger[c.finger];
      if (c.mode == palp_CONTACT_FINGER && f->mode == palp_CONTACT_FINGER && f->world_contact >= 0 &&
          c.radius == f->cmd.radius) {
        /* A placed finger's next device point: played out after the batch (play_out). */
        const int pushed = palp_srv_playout_push(&f->playout, c.source_time_ns,
                                                 arrival_ns(s, c.finger, c.seq, recv_ns), c.center, c.seq);
        if (pushed == 0) continue;
        if (pushed < 0) { /* a stamp that is no clock reading: applied as it comes */
          palp_srv_playout_clear(&f->playout);
          if (apply(s, &c) < 0) {
            count_reject(s, PALP_SRV_REJ_MODEL, 0, now_ns);
            continue;
          }
        }
      } else {
        /* A finger placed below the surface is placed on it and brought in; one already placed (a new
         * radius) stays where it is. */
        palp_srv_contact placed = c;
        const int placing = f->mode != palp_CONTACT_FINGER || f->world_contact < 0;
        const int entry = c.mode == palp_CONTACT_FINGER && placing && entry_point(s, &c, &placed);
        if (apply(s, &placed) < 0) {
          count_reject(s, PALP_SRV_REJ_MODEL, 0, now_ns);
          continue;
        }
        /* Its playout starts from this point (or from the one it is brought in from). */
        palp_srv_playout_clear(&f->playout);
        if (entry) {
          palp_srv_playout_start(&f->playout, placed.source_time_ns, placed.center, c.seq);
          s->stats.entries++;
          if (s->events && s->events->input_gap)
            s->events->input_gap(s->events->ctx, s->id, palp_world_frame(s->world), c.finger,
                                 1e-9 * (double)(c.source_time_ns - placed.source_time_ns),
                                 norm3((palp_vec3){c.center.x - placed.center.x, c.center.y - placed.center.y,
                                                   c.center.z - placed.center.z}));
        }
        if (c.mode == palp_CONTACT_FINGER)
          palp_srv_playout_push(&f->playout, c.source_time_ns, arrival_ns(s, c.finger, c.seq, recv_ns), c.center,
                                c.seq);
      }
      f->writer = info[i].publication_handle;
      s->stats.contact_samples++;
      if (s->events && s->events->contact_applied)
        s->events->contact_applied(s->events->ctx, s->id, &c, palp_world_time(s->world));
    }
    if (n < TAKE_BATCH) break;
  }
  play_out(s, recv_ns, now_ns);
}

static void publish_feedback(palp_srv_session *s, int64_t now_ns, double top_disp) {
  s->fb.frame = (uint64_t)palp_world_frame(s->world);
  s->fb.sim_time = palp_world_time(s->world);
  s->fb.top_displacement = top_disp;
  uint32_t n = 0;
  for (int i = 0; i < PALP_SRV_MAX_FINGERS; i++) {
    const palp_srv_finger_state *f = &s->finger[i];
    if (f->mode == palp_CONTACT_RELEASE && f->cmd.seq == 0) continue; /* never used */
    palp_FingerFeedback *o = &s->fb_fingers[n++];
    o->finger = (uint8_t)i;
    o->active = f->world_contact >= 0;
    o->force = (palp_Vec3){f->feedback.x, f->feedback.y, f->feedback.z};
    o->contact_seq = f->cmd.seq;
    o->contact_source_time_ns = f->cmd.source_time_ns;
  }
  s->fb.fingers._length = n;
  s->fb.server_time_ns = palp_dds_now_ns();
  dds_write(s->feedback_writer, &s->fb);
  s->last_feedback_ns = now_ns;
}

/* Model-validity flags of the step just taken: what the health counters gained; *gel_dropped:
 * the step's frames (it or its halves) the literal gel law took without its momentum term
 * (LM_GEL_LAW_RANGE on the wire since 2026-12-06: the stations are told, as the log is). */
static uint32_t step_flags(palp_srv_session *s, int64_t *gel_dropped) {
  palp_world_health h;
  palp_world_get_health(s->world, &h);
  *gel_dropped = h.gel_momentum_dropped - s->health.gel_momentum_dropped;
  uint32_t fl = 0;
  /* large deformation, by stretching or by bending (the wire has one bit for both) */
  if (h.large_strain_steps > s->health.large_strain_steps || h.large_bend_steps > s->health.large_bend_steps)
    fl |= palp_LM_LARGE_STRAIN;
  if (h.base_contacts > s->health.base_contacts) fl |= palp_LM_BASE_CONTACT;
  if (h.clamped_steps > s->health.clamped_steps) fl |= palp_LM_CLAMPED_STEP;
  if (h.finger_unsolved > s->health.finger_unsolved) fl |= palp_LM_UNSOLVED;
  if (h.substeps > s->health.substeps) fl |= palp_LM_SUBSTEPPED;
  if (h.beyond_validated_steps > s->health.beyond_validated_steps) fl |= palp_LM_BEYOND_VALIDATED;
  if (*gel_dropped > 0) fl |= palp_LM_GEL_LAW_RANGE;
  s->health = h;
  return fl;
}

/* Frames the literal gel law took without its momentum term (docs/model.md, "Steps of other
 * lengths, and where a3 is stable"): there the phantom is not the law its scene names, so the
 * server's log says so at the first, then at most every log_interval with the frames since (a
 * hard press halves step after step); close_session says the total. */
static void say_gel_dropped(palp_srv_session *s, int64_t n, int64_t now_ns) {
  s->gel_unsaid += n;
  if (s->gel_said_ns && now_ns - s->gel_said_ns < (int64_t)(s->log_interval * 1e9)) return;
  const double a3 = palp_world_get_def(s->world)->gel.a3;
  if (!s->gel_said_ns)
    palp_log_warn(s->log, "session %u: the literal gel law's momentum term left out at %lld frame%s: a halved step "
                          "(or the one after it) puts a3 / (h h_prev) outside (-1/2, 1) (a3 %.3g s^2), where the "
                          "term would amplify every change of pressure; the gel there is the law without a3",
                  s->id, (long long)s->gel_unsaid, s->gel_unsaid == 1 ? "" : "s", a3);
  else
    palp_log_warn(s->log, "session %u: the literal gel law's momentum term left out at %lld more frame%s since the "
                          "last report (%lld in all)",
                  s->id, (long long)s->gel_unsaid, s->gel_unsaid == 1 ? "" : "s",
                  (long long)s->health.gel_momentum_dropped);
  s->gel_said_ns = now_ns;
  s->gel_unsaid = 0;
}

/* A position-driven finger's sample on a step the session log samples, as the log keeps it
 * (server/db_log.c): the touched triangles are what a station's and palp-web's coverage needs to be
 * the review's (the local model only counts them). */
static void publish_finger_sample(palp_srv_session *s, int i, const palp_srv_finger_state *f, const palp_local_model *m,
                                  uint64_t frame, double time) {
  int tri[PALP_FINGER_SAMPLE_TRIANGLES_MAX];
  const int nt = palp_world_finger_contacts(s->world, f->world_contact, tri, NULL, PALP_FINGER_SAMPLE_TRIANGLES_MAX);
  palp_FingerSample *o = &s->fs;
  memset(o, 0, sizeof *o);
  o->session_id = s->id;
  o->finger = (uint8_t)i;
  o->frame = frame;
  o->time = time;
  o->radius = f->cmd.radius;
  o->in_contact = m->contact != 0;
  o->device = (palp_Vec3){m->device.x, m->device.y, m->device.z};
  o->proxy = (palp_Vec3){m->proxy.x, m->proxy.y, m->proxy.z};
  o->force = (palp_Vec3){m->force.x, m->force.y, m->force.z};
  o->point = (palp_Vec3){m->point.x, m->point.y, m->point.z};
  o->area = m->area;
  /* the count of all touched (it may pass cap: those named are the first cap, as the log keeps them) */
  const int n = nt < 0 ? 0 : nt > PALP_FINGER_SAMPLE_TRIANGLES_MAX ? PALP_FINGER_SAMPLE_TRIANGLES_MAX : nt;
  for (int k = 0; k < n; k++) s->fs_tri[k] = tri[k];
  o->triangles._buffer = s->fs_tri;
  o->triangles._length = o->triangles._maximum = (uint32_t)n;
  o->triangles._release = false;
  (void)dds_write(s->finger_sample_writer, o); /* best-effort: a lost one is the review's still */
}

/* The local contact model of every position-driven finger after the step
 * (issue 11): the station's 1 kHz loop renders from it between physics steps.
 * A force above max_force is reported (LM_FORCE_LIMIT), not clamped: with a
 * position-driven finger the force is the model's output, and the station's
 * renderer limits what reaches the hand and shows that it did. */
static void publish_local_models(palp_srv_session *s, int64_t now_ns, uint32_t flags) {
  const double period = palp_world_get_def(s->world)->dt;
  for (int i = 0; i < PALP_SRV_MAX_FINGERS; i++) {
    const palp_srv_finger_state *f = &s->finger[i];
    if (f->mode != palp_CONTACT_FINGER || f->world_contact < 0) continue;
    palp_local_model m;
    if (palp_world_finger_local_model(s->world, f->world_contact, &m) < 0) continue;
    palp_LocalModel *o = &s->lm;
    memset(o, 0, sizeof *o);
    o->session_id = s->id;
    o->finger = (uint8_t)i;
    o->frame = (uint64_t)palp_world_frame(s->world);
    o->time = m.time;
    o->period = m.period > 0 ? m.period : period;
    o->contact_seq = f->cmd.seq;
    o->contact_source_time_ns = f->cmd.source_time_ns;
    o->in_contact = m.contact != 0;
    o->triangles = m.triangles;
    o->device = (palp_Vec3){m.device.x, m.device.y, m.device.z};
    o->proxy = (palp_Vec3){m.proxy.x, m.proxy.y, m.proxy.z};
    o->normal = (palp_Vec3){m.normal.x, m.normal.y, m.normal.z};
    o->force = (palp_Vec3){m.force.x, m.force.y, m.force.z};
    for (int r = 0; r < 3; r++)
      for (int c = 0; c < 3; c++) o->stiffness[3 * r + c] = m.stiffness[r][c];
    o->drift = (palp_Vec3){m.drift.x, m.drift.y, m.drift.z};
    o->area = m.area;
    o->depth = m.depth;
    o->point = (palp_Vec3){m.point.x, m.point.y, m.point.z};
    o->max_force = s->limits.max_force;
    o->max_strain = s->health.max_strain;
    o->flags = flags;
    const double fm = norm3(m.force);
    if (fm > s->limits.max_force) {
      o->flags |= palp_LM_FORCE_LIMIT;
      s->stats.force_limited_steps++;
      if (now_ns - s->last_limit_log_ns >= (int64_t)(s->log_interval * 1e9)) {
        /* into the server's log, which --log-file keeps (stderr alone until 2026-12-07) */
        palp_log_warn(s->log, "session %u: finger %d pushes back with %.1f N, above max_force %.1f N: reported to the "
                              "station (which limits it), not clamped", s->id, i, fm, s->limits.max_force);
        s->last_limit_log_ns = now_ns;
      }
    }
    if (flags & PALP_DDS_LM_OUTSIDE) s->stats.out_of_range_steps++;
    o->server_time_ns = palp_dds_now_ns();
    if (dds_write(s->local_model_writer, o) == 0) s->stats.local_models++;
    if (s->finger_sample_writer > 0 && o->frame % (uint64_t)s->sample_every == 0)
      publish_finger_sample(s, i, f, &m, o->frame, o->time);
  }
}

static void publish_deformation(palp_srv_session *s) {
  const palp_vec3 *p = palp_world_positions(s->world);
  palp_Vec3 *o = s->deformation.positions._buffer;
  for (uint32_t i = 0; i < s->deformation.positions._length; i++) o[i] = (palp_Vec3){p[i].x, p[i].y, p[i].z};
  s->deformation.frame = (uint64_t)palp_world_frame(s->world);
  s->deformation.sim_time = palp_world_time(s->world);
  s->deformation.volume = palp_world_volume(s->world);
  s->deformation.pressure = palp_world_pressure(s->world);
  s->deformation.awake = palp_world_is_awake(s->world) != 0;
  dds_write(s->deformation_writer, &s->deformation);
}

int palp_srv_session_tick_ready(palp_srv_session *s) {
  if (!s->factor.job || !s->factor_pool) return 1;
  if (palp_world_factor_due(s->world) > palp_world_frame(s->world)) return 1;
  return palp_srv_factor_done(s->factor_pool, &s->factor);
}

int64_t palp_srv_session_tick(palp_srv_session *s, int64_t now_ns) {
  int64_t t0 = palp_dds_now_ns();
  s->stats.ticks++;
  if (atomic_load_explicit(&s->failed, memory_order_relaxed)) return 0;
  take_contacts(s, now_ns);

  int any_down = 0;
  for (int i = 0; i < PALP_SRV_MAX_FINGERS; i++) any_down |= s->finger[i].world_contact >= 0;
  int awake = palp_world_is_awake(s->world);
  double top_disp = 0;
  const palp_mesh *mesh = palp_world_mesh(s->world);
  /* A rebuild the helper computes is due: wait for it (rare: ~8 ms of frames). */
  if (s->factor.job && palp_world_factor_due(s->world) <= palp_world_frame(s->world)) {
    const int64_t waited = palp_srv_factor_wait(s->factor_pool, &s->factor);
    s->stats.factor_waits += waited > 0;
    s->stats.factor_wait_ns += waited;
    palp_world_factor_done(s->world, s->factor.job);
    s->factor.job = NULL;
  }
  /* Stepped every tick: a sleeping world returns at once but keeps its clock. */
  int rc = palp_world_step(s->world);
  if (rc == 0 && s->factor_pool) {
    palp_factor_job *j = palp_world_factor_claim(s->world);
    if (j) {
      s->factor.job = j;
      s->stats.factor_jobs++;
      if (palp_srv_factor_submit(s->factor_pool, &s->factor) != 0) {
        palp_factor_job_run(j); /* queue full: compute it here, as the world would */
        palp_world_factor_done(s->world, j);
        s->factor.job = NULL;
      }
    }
  }
  if (rc < 0) {
      palp_log_error(s->log, "session %u: model step failed: %s; closing the session", s->id,
              palp_strerror(rc));
    atomic_store(&s->failed, rc);
    return palp_dds_now_ns() - t0;
  }
  if (awake) {
    s->stats.awake_ticks++;
    s->rest_refresh_ns = 0; /* the shape it sleeps in next is sent when it falls asleep */
    /* Peak displacement over the dome: O(vertices), only while the world moves. */
    const palp_vec3 *pos = palp_world_positions(s->world);
    double peak2 = 0;
    for (int v = 0; v < mesh->vertex_count; v++) {
      double dx = pos[v].x - mesh->rest[v].x, dy = pos[v].y - mesh->rest[v].y, dz = pos[v].z - mesh->rest[v].z;
      double d2 = dx * dx + dy * dy + dz * dz;
      if (d2 > peak2) peak2 = d2;
    }
    double peak = sqrt(peak2);
    if (peak > s->stats.peak_displacement) s->stats.peak_displacement = peak;
    for (int i = 0; i < PALP_SRV_MAX_FINGERS; i++) {
      palp_srv_finger_state *f = &s->finger[i];
      if (f->world_contact < 0) continue;
      palp_vec3 fb = {0, 0, 0};
      if (palp_world_contact_feedback(s->world, f->world_contact, &fb) == 0) f->feedback = fb;
      double m = norm3(f->feedback);
      if (f->mode == palp_CONTACT_FINGER && m > s->stats.peak_force) s->stats.peak_force = m;
    }
  }
  top_disp = mesh->rest[mesh->top_vertex].z - palp_world_positions(s->world)[mesh->top_vertex].z;
  s->stats.last_frame = palp_world_frame(s->world);
  s->stats.sim_time = palp_world_time(s->world);

  if (s->events && s->events->frame) {
    palp_vec3 ff[PALP_SRV_MAX_FINGERS];
    int slot[PALP_SRV_MAX_FINGERS];
    for (int i = 0; i < PALP_SRV_MAX_FINGERS; i++) {
      ff[i] = s->finger[i].feedback;
      slot[i] = s->finger[i].world_contact;
    }
    s->events->frame(s->events->ctx, s->id, s->world, slot, ff, PALP_SRV_MAX_FINGERS);
  }

  int64_t gel_dropped = 0;
  const uint32_t flags = step_flags(s, &gel_dropped);
  /* the session log keeps what the stations were told, for the instructor's review, with the
   * literal gel law's frames outside its stable range counted */
  if ((flags & PALP_DDS_LM_OUTSIDE) && s->events && s->events->valid_range)
    s->events->valid_range(s->events->ctx, s->id, flags, gel_dropped, s->health.max_beyond_validated);
  if (gel_dropped > 0) say_gel_dropped(s, gel_dropped, now_ns);
  const int want_feedback = atomic_load_explicit(&s->want_feedback, memory_order_relaxed) != 0;
  if (want_feedback && s->local_model_writer > 0) publish_local_models(s, now_ns, flags);
  if (want_feedback && (awake || any_down || now_ns - s->last_feedback_ns >= IDLE_FEEDBACK_PERIOD_NS))
    publish_feedback(s, now_ns, top_disp);

  /* A display that joined since the last tick gets the shape now: the topic is volatile, so it has
   * seen nothing, and a sleeping world (held still, dented) would otherwise send nothing more. */
  const int members = atomic_load_explicit(&s->deform_members, memory_order_relaxed);
  int joined = members > s->deform_members_seen;
  s->deform_members_seen = members;
  /* The join is accepted before the display's reader exists, and a volatile frame sent
   * before the writer has matched that reader is lost: the display then waited for the
   * next once-a-second repeat of a sleeping shape (server_contact, under load). A new
   * match is the moment it can receive one; looked at only while a display is a member. */
  dds_publication_matched_status_t pm;
  if (members > 0 && dds_get_publication_matched_status(s->deformation_writer, &pm) == 0 &&
      pm.total_count != s->deform_matched_seen) {
    s->deform_matched_seen = pm.total_count;
    joined = 1;
  }
  if (members > 0 && (joined || (now_ns >= s->next_deformation_ns && (awake || now_ns >= s->rest_refresh_ns)))) {
    publish_deformation(s);
    s->deformations_sent++;
    if (!awake) s->rest_refresh_ns = now_ns + PALP_SRV_REST_REFRESH_NS;
    /* Advance by the period, not from now: at 100 Hz ticks a 30 Hz display then
     * gets 3- and 4-tick gaps averaging 30 Hz, not a steady 4 (25 Hz). After a
     * pause (sleep, no viewer) the schedule restarts from now. */
    const int64_t period = (int64_t)(s->deformation_period * 1e9);
    s->next_deformation_ns =
        now_ns - s->next_deformation_ns > period ? now_ns + period : s->next_deformation_ns + period;
  }
  int64_t dt = palp_dds_now_ns() - t0;
  double us = (double)dt * 1e-3;
  if (us > s->stats.step_us_max) s->stats.step_us_max = us;
  return dt;
}

void palp_srv_session_info_fill(const palp_srv_session *s, palp_srv_session_info *out) {
  out->session_id = s->id;
  out->phantom_id = s->phantom->cfg.id;
  out->phantom_name = s->phantom->cfg.name;
  out->trainee_station = s->trainee_station;
  out->trainee_name = s->trainee_name;
  out->partition = s->partition;
  out->tick_rate_hz = 1.0 / s->phantom->scene.world.dt;
  out->dt = s->phantom->scene.world.dt;
  out->scene_path = s->phantom->cfg.scene_path;
  out->scene = s->scene;
  out->max_force = s->limits.max_force;
  out->opened_ns = s->opened_ns;
  out->exercise_name = s->exercise ? s->exercise->name : NULL;
  out->exercise_json = s->exercise ? s->exercise_json : NULL;
  out->assess_sample_hz = s->assess_sample_hz;
}

void palp_srv_session_summary_fill(const palp_srv_session *s, const char *reason, int64_t now_ns,
                                   palp_srv_session_summary *out) {
  memset(out, 0, sizeof *out);
  palp_srv_session_info_fill(s, &out->info);
  out->duration = (double)(now_ns - s->opened_ns) * 1e-9;
  out->ticks = s->stats.ticks;
  out->overruns = s->stats.overruns;
  out->skipped = s->stats.skipped;
  out->awake_ticks = s->stats.awake_ticks;
  out->contact_samples = s->stats.contact_samples;
  memcpy(out->rejected, s->stats.rejected, sizeof out->rejected);
  out->peak_force = s->stats.peak_force;
  out->peak_displacement = s->stats.peak_displacement;
  out->close_reason = reason;
}
