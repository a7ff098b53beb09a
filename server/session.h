/*
 * session.h - one trainee's session: its own palp_world, its partition's DDS
 * endpoints, and the per-tick pipeline (take contacts -> validate -> apply ->
 * step -> publish feedback / deformation).
 *
 * A session is created and destroyed by the server's main thread and ticked by
 * exactly one tick thread; fields marked [main] are written by the main thread
 * only (atomics), the rest belong to the tick thread and are read by the main
 * thread under the tick group's lock.
 */
#ifndef PALP_SRV_SESSION_H
#define PALP_SRV_SESSION_H

#include <stdatomic.h>
#include <stdint.h>

#include <dds/dds.h>

#include "config.h"
#include "events.h"
#include "factor_pool.h"
#include "palp_log.h"
#include "palp.h"
#include "palp_assess.h"
#include "palp_dds.h" /* PALP_FINGER_SAMPLE_TRIANGLES_MAX */
#include "palp_dds_reaper.h"
#include "palp_types.h"
#include "playout.h"
#include "findings.h"
#include "validate.h"

/* A hosted phantom: its scene (contacts stripped, dt set to the tick period) and
 * a template world whose mesh feeds the catalogue and the validation limits. */
typedef struct palp_srv_phantom {
  palp_srv_phantom_cfg cfg;
  palp_scene scene;
  palp_world *template_world;
  const palp_mesh *mesh;
  /* issue 13: an exercise (NULL for a plain phantom). The scene above then has the
   * exercise's lesions hidden in it: it stays on the server (and in its log). */
  palp_exercise *exercise;
  char *exercise_json; /* the exercise file's text, for the log */
} palp_srv_phantom;

typedef struct palp_srv_session_stats {
  /* ticks: steps taken; overruns: steps late, those that ended after their deadline and the
   * slots its group skipped behind schedule; skipped: those slots alone (session 82), so that
   * overruns <= ticks + skipped */
  uint64_t ticks, overruns, skipped, awake_ticks;
  uint64_t contact_samples;                 /* applied (accepted or clamped) */
  uint64_t entries;                         /* fingers placed below the surface, brought in from it */
  uint64_t rejected[PALP_SRV_REJ_COUNT];    /* per reason; force_limit counts clamps too */
  double peak_force;                        /* [N] */
  double peak_displacement;                 /* [m] */
  double step_us_max;                       /* longest tick of this session in the status period [us] */
  uint64_t local_models;                    /* palp_local_model samples published */
  uint64_t force_limited_steps;             /* finger-steps whose force exceeded max_force (reported, not clamped) */
  uint64_t out_of_range_steps;              /* steps with a model-validity flag (PALP_DDS_LM_OUTSIDE) */
  uint64_t factor_jobs;                     /* lagged-tangent rebuilds handed to the helper */
  uint64_t factor_waits;                    /* ... that were due before the helper had finished */
  int64_t factor_wait_ns;                   /* time ticks spent waiting for them [ns] */
  int64_t last_frame;
  double sim_time;                          /* [s] */
} palp_srv_session_stats;

/* When a device sample arrived, stamped on the receive thread (palp_srv_session). */
typedef struct palp_srv_arrival {
  atomic_uint_fast64_t seq;
  atomic_int_fast64_t recv_ns;
} palp_srv_arrival;

typedef struct palp_srv_finger_state {
  int world_contact;      /* model contact id, -1 when lifted */
  int mode;               /* palp_ContactMode of the applied command */
  palp_srv_contact cmd;   /* last applied command */
  /* The writer of the last applied command (its publication handle; 0: none yet): its own dispose
   * or going lifts the finger without a lookup, which a writer already gone could not answer. */
  dds_instance_handle_t writer;
  palp_vec3 feedback;     /* [N] after the last step */
  /* A position-driven finger's device samples, played out at a steady delay so a
   * jittery network does not push the phantom in bunches (playout.h). */
  palp_srv_playout playout;
} palp_srv_finger_state;

/* A writer the session has looked up on one of its readers (contacts, findings): of the participant
 * that joined it, of another, or gone before it was looked up. Cyclone never gives a publication handle
 * twice (a writer found again gets a new one), and a writer has the one handle on every reader of the
 * server's participant, a reader made anew included (seen on Cyclone 0.10.2, 2026-12-06), so a verdict
 * holds for as long as the entry is kept. */
#define PALP_SRV_WRITERS_KEPT 8
typedef struct palp_srv_writer_entry {
  dds_instance_handle_t pub; /* 0: a free entry */
  int own;                   /* 1: the session's participant's; 0: another's; -1: gone before it was looked up */
  dds_guid_t participant;    /* own 0: that participant */
  int named;                 /* refused once already: the log named it, or counted it among the unnamed */
} palp_srv_writer_entry;

/* The writers one reader of a session has looked up, and what the log said of those it refused. One
 * per reader, each used by one thread only (contacts: the tick; findings: the main thread). */
typedef struct palp_srv_writer_check {
  /* As the log names a refused writer: what the reader takes ("contacts"), who alone writes them ("the
   * session is palpated only from", then the participant), what becomes of its samples, and who another
   * participant writing them is likely to be. */
  const char *what, *rule, *counted, *suspects;
  palp_srv_writer_entry e[PALP_SRV_WRITERS_KEPT];
  unsigned hand;
  uint64_t foreign_writers;  /* writers refused: another participant's, or gone */
  uint64_t foreign_unnamed;  /* refused writers not named in the log since the last one named */
  int64_t foreign_said_ns;   /* when the log last named one (at most one a log_interval) */
} palp_srv_writer_check;

/* Whether a writer that is not of the session's participant may write here all the same (findings:
 * a visual station the server admitted to the session, in an unsecured classroom). */
typedef int (*palp_srv_participant_ok_fn)(void *ctx, const dds_guid_t *participant);

typedef struct palp_srv_session_def {
  uint32_t id;
  /* The participant whose request writer JOINed the session (participant_key of that writer): only
   * its writers' contacts reach the world (take_contacts). Required: a session never runs unbound. */
  dds_guid_t trainee_participant;
  palp_srv_phantom *phantom;
  const palp_srv_config *cfg;
  const char *trainee_station;
  const char *trainee_name;
  dds_entity_t participant;
  dds_entity_t contact_topic, feedback_topic, deformation_topic;
  dds_entity_t local_model_topic; /* 0: no local models (older callers) */
  dds_entity_t finding_topic, finding_status_topic; /* 0: no findings (older callers) */
  dds_entity_t debrief_topic; /* 0: no debrief (older callers, or permissions that predate it) */
  dds_entity_t session_log_topic; /* 0: no palp_session_log (older callers, permissions that predate it) */
  dds_entity_t finger_sample_topic; /* 0: no palp_finger_sample (older callers, permissions that predate it) */
  const palp_srv_events *events; /* may be NULL */
  const char *partition;         /* NULL: "palp/session/<id>"; secured: "palp/s/<trainee>/<id>" */
  palp_log *log;                 /* may be NULL (stderr) */
  /* The server's (may be NULL): the session's publisher, whose writers wait for the stations'
   * acknowledgements as they are deleted, is deleted on its thread, not the caller's (palp_dds_reaper.h) */
  palp_dds_reaper *reaper;
  uint32_t placement_seed;       /* a random exercise's draw for this session (palp_exercise_draw) */
  char *refusal;                 /* NULL, or where palp_srv_session_create says why it failed, in */
  size_t refusal_len;            /* the trainee's words, when it can say more than its error code */
} palp_srv_session_def;

typedef struct palp_srv_session {
  uint32_t id;
  palp_srv_phantom *phantom;
  /* The exercise this session runs (NULL: none), the scene its world was built from and the
   * exercise's text for the log: the phantom's, or for a random exercise this session's own draw
   * (docs/assessment.md, "Lesions drawn for each session"), which the findings, the debrief and
   * the log then use. */
  const palp_exercise *exercise;
  const palp_scene *scene;
  const char *exercise_json;
  palp_exercise *own_exercise;   /* owned: a draw's (NULL otherwise) */
  palp_scene *own_scene;
  char *own_exercise_json;
  palp_world *world;
  char partition[64];
  char trainee_station[64];
  char trainee_name[64];
  int64_t opened_ns;
  dds_entity_t sub, pub, contact_reader, feedback_writer, deformation_writer, local_model_writer;
  palp_dds_reaper *reaper; /* def.reaper */
  dds_entity_t contact_topic; /* this session's own topic entity: it carries the filter below */
  /* issue 13: "lump here" marks, read and answered by the main thread (findings.h) */
  dds_entity_t finding_reader, finding_status_writer, finding_rc;
  dds_entity_t finding_topic; /* this session's own topic entity for its finding reader: its filter's */
  /* [DDS receive thread] findings the filter dropped for naming another session (session 72: made-up
   * keys would each become an instance), and the last such session id; [main] the count logged. */
  atomic_uint_fast64_t filtered_findings;
  _Atomic uint32_t filtered_finding_session;
  uint64_t filtered_findings_said;
  /* [main] disposes of other sessions' finding keys its reader took (each an instance it keeps while
   * their writer lives): past a bound the reader is made anew (server/server.c, renew_finding_reader) */
  uint64_t finding_strays, finding_strays_total, finding_reader_renewals;
  int64_t finding_reader_renewed_ns, finding_renewal_said_ns;
  palp_srv_findings findings;
  /* [main] the writers of its findings (server/server.c, offer_finding): only the participant that
   * joined the session marks its findings (unsecured, also its visual stations': palp-web writes a
   * trainee page's marks); the rest are refused unanswered, never offered (2026-12-06). */
  palp_srv_writer_check finding_writers;
  uint64_t findings_foreign;   /* findings (marks, withdrawals) refused so */
  dds_entity_t debrief_writer; /* palp_debrief, written once as an exercise session closes; 0: none */
  /* palp_session_log (session 69): this session's records the log lost, as last written; 0: none */
  dds_entity_t session_log_writer;
  int session_log_sent;
  uint64_t session_log_shed, session_log_failed;
  palp_srv_limits limits;
  const palp_srv_events *events;
  palp_log *log;
  double log_interval;        /* [s] */
  double deformation_period;  /* [s] */
  double assess_sample_hz;    /* finger samples logged per second (issue 13) */
  int64_t findings_status_ns; /* [main] last palp_finding_status written */

  /* [DDS receive thread] samples the contact filter dropped before they reached
   * the reader cache: another session's id, or a finger past the last. */
  atomic_uint_fast64_t filtered_session, filtered_finger;
  /* When each finger's recent samples arrived (server clock), stamped by the filter
   * on the receive thread: the tick takes them up to a period later, and the
   * playout's jitter estimate must see the network, not the tick (playout.h).
   * A slot is (seq, time), written time first; read back if its seq still matches. */
  palp_srv_arrival arrival[PALP_SRV_MAX_FINGERS][16];

  /* Set at create, never changed (a station found again after a stall keeps its participant GUID;
   * another participant's JOIN under its station id is refused since session 80, and took its station
   * slot, never its fingers, before): read by the tick thread without a lock. */
  dds_guid_t trainee_participant;

  /* [main] */
  uint32_t trainee_request_seq; /* the JOIN that opened it: the same request again resumes it */
  /* Its trainee station lost (a lease expired): the session stays open, its fingers lifted
   * (their writer is gone too), for station_grace after held_since_ns, for the station to
   * come back from a stall with the same request (docs/server.md). 0: not held. */
  int64_t held_since_ns;
  char held_reason[160];
  atomic_int want_feedback;   /* haptic trainee present */
  atomic_int deform_members;  /* members that asked for palp_deformation */
  atomic_int failed;          /* set by the tick thread: the model refused to step */

  /* tick thread */
  palp_srv_finger_state finger[PALP_SRV_MAX_FINGERS];
  palp_srv_session_stats stats;
  int64_t next_deformation_ns;
  int64_t last_feedback_ns;
  int64_t rest_refresh_ns;     /* when a sleeping world's shape is sent (again); 0 while awake */
  int deform_members_seen;     /* deform_members at the last tick: a rise is a display that just joined */
  uint32_t deform_matched_seen; /* the deformation writer's total matched readers at the last look */
  uint64_t deformations_sent;  /* palp_deformation samples written */
  uint64_t filtered_seen_session, filtered_seen_finger; /* folded into stats.rejected so far */
  /* The writers of its contacts, looked up once each while kept (take_contacts); a refused one is
   * the first to make room, so a flood of new writers never pushes out the trainee's own. */
  palp_srv_writer_check contact_writers;
  int64_t last_log_ns[PALP_SRV_REJ_COUNT];
  uint64_t log_suppressed[PALP_SRV_REJ_COUNT];
  palp_Feedback fb;
  palp_FingerFeedback fb_fingers[PALP_SRV_MAX_FINGERS];
  palp_Deformation deformation;
  palp_world_health health;   /* after the previous step: per-step flags are deltas */
  palp_LocalModel lm;
  /* palp_finger_sample (session 71): the assessment's samples, touched triangles named, written on
   * the steps the log samples (every sample_every-th); 0: none */
  dds_entity_t finger_sample_writer;
  int sample_every;
  palp_FingerSample fs;
  int32_t fs_tri[PALP_FINGER_SAMPLE_TRIANGLES_MAX];
  int64_t last_limit_log_ns;
  /* The literal gel law's frames without their momentum term (health.gel_momentum_dropped):
   * said in the server's log at the first, then at most every log_interval with the frames
   * since; the rest in the total said at close. */
  int64_t gel_said_ns;
  int64_t gel_unsaid;
  /* Set by the ticker that holds the session: rebuilds go to its helper (NULL: the
   * world computes them itself at their due frame). */
  palp_srv_factor_pool *factor_pool;
  palp_srv_factor_slot factor;
  /* The ticker's group that steps it, + 1; 0 while in none (the ticker's add and remove set it,
   * on the thread that owns the session). palp_srv_ticker_with locks that group alone. */
  int tick_group;
} palp_srv_session;

/* Hands an in-flight rebuild back to the world (waiting for the helper): before the
 * session leaves its ticker. */
void palp_srv_session_factor_settle(palp_srv_session *s);

palp_srv_session *palp_srv_session_create(const palp_srv_session_def *def, int *err);
void palp_srv_session_destroy(palp_srv_session *s);

/* Whether the writer of a sample taken from `reader` (its publication handle `pub`, from the sample's
 * info) may write in session s: 1 when it is of the participant whose request JOINed the session, or
 * `also` (NULL: none) says its participant may; 0 when not, or when it was gone before it could be
 * looked up (a forger could otherwise write and vanish). The writer is looked up once while wc keeps
 * it (a miss costs one dds_get_matched_publication_data); a refused one is named in the server's log
 * with the session and station once (the first at once, then at most one a log_interval, the rest
 * counted). wc: the reader's own (palp_srv_writer_check); one thread per wc. */
int palp_srv_session_writer_ok(palp_srv_session *s, palp_srv_writer_check *wc, dds_entity_t reader,
                               dds_instance_handle_t pub, int64_t now_ns, palp_srv_participant_ok_fn also, void *ctx);

/* 0 when this session's next tick would wait for a tangent rebuild a helper has not
 * finished (it is due at the world's frame); 1 otherwise. The ticker steps such a
 * session after the rest of its group, so that one session's wait delays no other
 * and the helper gets the group's work time to finish. */
int palp_srv_session_tick_ready(palp_srv_session *s);

/* One tick at CLOCK_MONOTONIC time now_ns. Returns the time spent [ns]. */
int64_t palp_srv_session_tick(palp_srv_session *s, int64_t now_ns);

/* Fills a summary (strings point into s; valid while s lives). */
void palp_srv_session_summary_fill(const palp_srv_session *s, const char *reason, int64_t now_ns,
                                   palp_srv_session_summary *out);
void palp_srv_session_info_fill(const palp_srv_session *s, palp_srv_session_info *out);

#endif
