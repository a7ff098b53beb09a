/*
 * events.h - the seam between the server and whatever records sessions.
 *
 * The server calls these hooks; the database layer (db/) implements them. Hooks
 * marked [tick thread] run inside a 1 ms tick: they must only copy into a queue
 * and return (Redis bio.c style: a worker thread does the slow, durable write).
 * Every hook may be NULL. The ctx pointer is the implementer's.
 */
#ifndef PALP_SRV_EVENTS_H
#define PALP_SRV_EVENTS_H

#include <stdint.h>

#include "palp.h"
#include "validate.h"

/* A change the server made to a session's world contacts, in the order made.
 * Logging every one with its frame lets a recorder replay the session bit for
 * bit (db/palp_db.h, "replay contract"). */
typedef enum palp_srv_world_op_kind {
  PALP_SRV_OP_ADD = 1,    /* palp_world_add_contact (+ set force) or palp_world_add_finger */
  PALP_SRV_OP_UPDATE = 2, /* palp_world_set_contact_force or palp_world_set_finger */
  PALP_SRV_OP_REMOVE = 3  /* palp_world_remove_contact */
} palp_srv_world_op_kind;

typedef struct palp_srv_world_op {
  int64_t frame;          /* palp_world_frame when applied (before the next step) */
  double sim_time;        /* [s] */
  int finger;             /* station finger 0..3 */
  int slot;               /* model contact id */
  palp_srv_world_op_kind op;
  int kind;               /* 1 force-driven, 2 position-driven finger */
  palp_contact_def def;   /* force-driven ADD: the definition */
  palp_vec3 force;        /* force-driven: [N] */
  palp_vec3 center;       /* finger: sphere centre [m] */
  double radius;          /* finger: [m] */
} palp_srv_world_op;

typedef struct palp_srv_session_info {
  uint32_t session_id;
  uint32_t phantom_id;
  const char *phantom_name;
  const char *trainee_station; /* DDS station id of the trainee */
  const char *trainee_name;
  const char *partition;
  double tick_rate_hz;
  double dt;                   /* world step [s] = 1 / tick_rate_hz */
  const char *scene_path;      /* the scene file of the phantom */
  const palp_scene *scene;     /* the resolved scene the world was built from (world.dt = dt):
                                * palp_scene_create_world, then its own contacts 0..n-1 removed;
                                * palp_scene_to_json gives it self-contained for the log */
  double max_force;            /* [N] */
  int64_t opened_ns;           /* CLOCK_MONOTONIC */
  const char *exercise_name;   /* issue 13: the exercise the session runs, NULL for none; its */
  const char *exercise_json;   /* file's text (hidden lesions included: the log is the instructor's) */
  double assess_sample_hz;     /* finger samples to log per second (config assess_sample_hz) */
} palp_srv_session_info;

/* issue 13: a "lump here" finding the server received, and its verdict. */
typedef struct palp_srv_finding_event {
  int accepted;
  uint32_t mark_id;
  int withdraw;                /* 0 mark, 1 withdrawal */
  palp_vec3 point;             /* [m] (marks) */
  int64_t frame;               /* the world's frame and time when it was taken */
  double sim_time;             /* [s] */
  const char *reason;          /* why it was refused ("" when accepted) */
} palp_srv_finding_event;

/* An exercise session's debrief as it closed (docs/assessment.md, "Debrief"): what its trainee was
 * told, or that it was not sent and why. The numbers are the wire's (palp_Debrief). */
typedef struct palp_srv_debrief_event {
  int sent;                    /* 1 written to the trainee's station, 0 not (why) */
  int level;                   /* palp_debrief_level (src/palp_assess.h): 0 none, 1 count, 2 lesions */
  uint32_t lesions, found, marks, false_marks, duplicates;
  uint32_t listed;             /* lesions level: the lesions, in the exercise's order */
  const uint32_t *found_by;    /* listed of them: the mark that found each, 0 missed */
  const char *why;             /* not sent: why */
} palp_srv_debrief_event;

typedef struct palp_srv_session_summary {
  palp_srv_session_info info;
  double duration;             /* [s] wall time open */
  uint64_t ticks, overruns, awake_ticks; /* steps taken; late ones, skipped slots included */
  uint64_t skipped;            /* tick slots skipped behind schedule: no step taken (session 82) */
  uint64_t contact_samples;    /* accepted or clamped */
  uint64_t rejected[PALP_SRV_REJ_COUNT];
  double peak_force;           /* [N] */
  double peak_displacement;    /* [m] */
  const char *close_reason;
} palp_srv_session_summary;

/* A closed exercise session's automatic score (session 63): what palp-review gives the session's own
 * log, graded off the main thread once the log holds the session's end (server/grader.c). The numbers
 * are palp_assess_result's (src/palp_assess.h); the wire's palp_SessionScore carries them. */
typedef struct palp_srv_score {
  uint32_t session_id;
  int graded;                  /* 1: the fields below; 0: reason says why not */
  char log_uid[96];        /* the session's uid in the log (palp-review show takes it) */
  char exercise[64];
  double score;                /* [0, 100] */
  int pass;
  double credit[6];            /* palp_assess_result.component, PALP_METRIC_* order, each [0, 1] */
  int passed[6];               /* palp_assess_result.pass_metric */
  uint32_t lesions, found, false_marks;
  double coverage[3];          /* light, medium, deep [0, 1] */
  int pattern;                 /* palp_pattern */
  double duration;             /* [s] */
  double peak_force;           /* [N] */
  uint32_t out_of_range;
  uint32_t samples;
  char reason[128];
  int log_complete;            /* graded: palp_db_log_health's complete */
  char log_health[128];        /* graded: palp_db_log_health_describe's line */
} palp_srv_score;

typedef struct palp_srv_events {
  void *ctx;
  /* [main thread] a trainee's session opened. */
  void (*session_opened)(void *ctx, const palp_srv_session_info *info);
  /* [main thread] a session closed; the summary is final. */
  void (*session_closed)(void *ctx, const palp_srv_session_summary *summary);
  /* [main thread] a visual station or observer joined or left a session. */
  void (*member_changed)(void *ctx, uint32_t session_id, const char *station, int role, int joined);
  /* [tick thread] a validated contact was applied at simulated time t [s]. */
  void (*contact_applied)(void *ctx, uint32_t session_id, const palp_srv_contact *c, double t);
  /* [tick thread] every world contact change, in order (see palp_srv_world_op). */
  void (*world_op)(void *ctx, uint32_t session_id, const palp_srv_world_op *op);
  /* [tick thread] count samples were rejected (reason) or clamped: 1 for a sample the session
   * checked, any number for those the contact reader's filter dropped since the last tick. */
  void (*contact_rejected)(void *ctx, uint32_t session_id, palp_srv_reject_reason reason, int clamped, uint64_t count);
  /* [tick thread] after every palp_world_step (sleeping ones too): the world may
   * be read (palp_world_frame/_hash/_positions...) but not changed; per finger:
   * its model contact id (-1 when lifted) and feedback force [N]. */
  void (*frame)(void *ctx, uint32_t session_id, const palp_world *w, const int *finger_slot,
                const palp_vec3 *finger_force, int fingers);
  /* [main thread] the log's counters for palp_server_status: records written,
   * shed (queue full) and failed (disk errors). */
  void (*log_counts)(void *ctx, uint64_t *written, uint64_t *shed, uint64_t *failed);
  /* [main thread] an open session's own losses in that log (session 69, palp_session_log): 1 and the
   * counts of its records shed and failed so far; 0 when the log does not hold the session (its
   * opening was lost with the rest, or nothing logs): its station then counts the server's losses. */
  int (*session_log_losses)(void *ctx, uint32_t session_id, uint64_t *shed, uint64_t *failed);
  /* [main thread] a finding was accepted or refused (issue 13). */
  void (*finding)(void *ctx, uint32_t session_id, const palp_srv_finding_event *ev);
  /* [main thread] an exercise session's debrief, once, as it closes (before session_closed). */
  void (*debrief)(void *ctx, uint32_t session_id, const palp_srv_debrief_event *ev);
  /* [tick thread] at frame, finger's device points came after a gap of gap_s [s] (a stalled station
   * or server), caught up rather than jumped (server/playout.h); or, with depth_m > 0, the finger
   * was placed depth_m [m] below the surface and is brought in from it (server/session.c). */
  void (*input_gap)(void *ctx, uint32_t session_id, int64_t frame, int finger, double gap_s, double depth_m);
  /* [tick thread] n steps of this session late, the last ending late_ns after its deadline: a tick
   * (n = 1) or the slots its group skipped behind schedule, once for all of them (one call per slot
   * was 60,000 calls per session after a 60 s stop at 1 kHz, under the group's lock). */
  void (*overrun)(void *ctx, uint32_t session_id, uint64_t n, int64_t late_ns);
  /* [tick thread] after a step that left the model's valid range (issue 12; docs/model.md,
   * "Valid range"): the step's model-validity bits (PALP_DDS_LM_OUTSIDE, as the stations get
   * them), its frames (the step or its halves) whose literal gel law left its momentum term out
   * (palp_world_health.gel_momentum_dropped's gain, > 0 with palp_LM_GEL_LAW_RANGE), and the
   * largest excess of a fingertip over its validated depth so far [m]. */
  void (*valid_range)(void *ctx, uint32_t session_id, uint32_t flags, int64_t gel_dropped, double deepest_m);
  /* [a Cyclone thread] DDS Security refused a peer (no session): detail "WHO: WHY (handshake|
   * permissions)", count the refusals it stands for; as the server's log says them
   * (idl/palp_dds_refusals.h: the first at once, the repeats once a minute, the rest at stop). */
  void (*security_refused)(void *ctx, const char *detail, uint64_t count);
  /* [main thread] a closed exercise session's score, when one is ready: 1 and *out filled, 0 when
   * none is waiting. The server asks after every wake (<= 100 ms) and writes it on
   * palp_session_score for the instructors. NULL when nothing scores sessions live: its trainee is
   * then told at once (palp_debrief_score) why, in unscored's words or, without them, that the
   * server keeps no session log. */
  int (*take_score)(void *ctx, palp_srv_score *out);
  const char *unscored;
} palp_srv_events;

#endif
