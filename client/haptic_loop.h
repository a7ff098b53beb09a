/*
 * haptic_loop.h - the station's 1 kHz haptic thread (issue 11, docs/station.md).
 *
 * The server steps the phantom at its physics rate (e.g. 250 Hz) and publishes a
 * local contact model per finger after every step (topic palp_local_model). The
 * station's DDS thread converts each one (checked) and drops it into a mailbox;
 * the haptic thread wakes on absolute CLOCK_MONOTONIC deadlines (clock_nanosleep
 * TIMER_ABSTIME, optionally SCHED_FIFO), reads the device position, renders the
 * force with palp_haptic from the newest model, writes it to the device, and
 * every rate/physics_rate ticks queues the device position for the server as a
 * CONTACT_FINGER sample (a sender thread writes it: the haptic thread never
 * calls DDS). It never waits for the network: a late or lost model is
 * extrapolated, then held, then faded out by the renderer.
 *
 * The mailbox is a mutex held for one struct copy; the haptic thread only
 * try-locks it, so a DDS thread holding it costs the haptic tick nothing but
 * one tick's delay in seeing the model.
 */
#ifndef PALP_CLI_HAPTIC_LOOP_H
#define PALP_CLI_HAPTIC_LOOP_H

#include <pthread.h>
#include <semaphore.h>
#include <stdatomic.h>
#include <stdint.h>

#include <dds/dds.h>

#include "input.h"
#include "palp.h"
#include "palp_haptic.h"
#include "palp_timer_floor.h"
#include "palp_types.h"
#include "station.h"

/* ---- mailbox: DDS thread -> haptic thread ----------------------------------------- */
typedef struct palp_cli_mailbox {
  pthread_mutex_t lock;
  palp_local_model model;
  uint32_t server_flags; /* palp_LM_* of the model */
  double max_force;      /* the phantom's limit, from the model [N] */
  double age;            /* the model's age on arrival [s]: now - its contact sample's source time; < 0 unknown */
  uint64_t seq;          /* models put so far */
  uint64_t taken;        /* seq of the last model taken */
  uint64_t superseded;   /* models not put: older than the one waiting untaken */
} palp_cli_mailbox;

int palp_cli_mailbox_init(palp_cli_mailbox *mb);
void palp_cli_mailbox_destroy(palp_cli_mailbox *mb);
/* Puts m in the box, unless the model waiting there untaken is newer (by time): that one
 * stays (counted in superseded). */
void palp_cli_mailbox_put(palp_cli_mailbox *mb, const palp_local_model *m, uint32_t server_flags, double max_force,
                          double age);
/* Non-blocking: 1 and a copy when a model newer than *seq is there (updates *seq);
 * 0 when none or the lock is busy. */
int palp_cli_mailbox_take(palp_cli_mailbox *mb, uint64_t *seq, palp_local_model *m, uint32_t *server_flags,
                          double *max_force, double *age);

/* A model's period: a step at those rates, or a retried step's 1/16 [s]. */
#define PALP_CLI_MODEL_PERIOD_MIN (1.0 / (16.0 * PALP_CLI_PHYSICS_RATE_MAX))
#define PALP_CLI_MODEL_PERIOD_MAX (1.0 / PALP_CLI_PHYSICS_RATE_MIN)

/* Checks a wire sample before it reaches the renderer: finite fields; a period in
 * [PALP_CLI_MODEL_PERIOD_MIN, PALP_CLI_MODEL_PERIOD_MAX]; a unit normal (out of contact:
 * unit or 0); a stiffness of at most 1e6 N/m per entry, symmetric within 1e-6 of its
 * largest entry, with a diagonal >= 0; a force of magnitude at most 1e4 N; a device
 * point within 10 m and a drift below 100 m/s. Returns 0 or PALP_EINVAL (the sample
 * is dropped and counted). */
int palp_cli_local_model_from_wire(const palp_LocalModel *in, palp_local_model *out);
/* 1 if m's period is a step of the session's physics rate [Hz]: within 1% of 1/rate, or
 * of a retried step's half down to 1/16 of it; else 0 (the feed drops the sample). */
int palp_cli_local_model_fits_rate(const palp_local_model *m, double physics_rate_hz);
/* Haptic ticks per contact sample sent to the server: rate / physics rate rounded, at
 * least 1, at most 1e6, 1 for a physics rate at or above the haptic rate or not a number. */
long palp_cli_contact_every(double rate_hz, double physics_rate_hz);

/* ---- the per-tick logic, pure: the haptic thread runs it, tests drive it --------------- */
typedef struct palp_cli_haptic_core {
  palp_haptic renderer;
  int compensate;         /* latency compensation on */
  double hold_after;      /* [s] horizon of a model's stiffness and drift */
  double max_latency;     /* [s] ages beyond are not trusted */
  double x_arrival_t, model_age;
  palp_vec3 offset;       /* device motion made while the force was held [m] */
  palp_vec3 x_prev;       /* the last good device reading [m] */
  int have_x;             /* a finite reading was seen */
  uint64_t bad_x_ticks;   /* ticks whose reading was not finite (the last good one stood in) */
  int was_on, holding;
  /* passivity observer/controller (time-domain, Hannaford & Ryu 2002) */
  int passivity;          /* on by default */
  double max_damping;     /* the controller's damping limit [N s/m] */
  double energy;          /* work done on the device in this contact episode [J]; > 0: energy generated */
  palp_vec3 f_prev;       /* force rendered at the previous tick [N] */
  palp_vec3 x_prev_pc;    /* device point at the previous tick [m] */
  double t_prev;
  double dissipated;      /* by the controller, total [J] */
  uint64_t pc_ticks;      /* ticks the controller acted (damped, lessened a push, or both) */
} palp_cli_haptic_core;

/* hold_after 0: max(2 physics periods, 8 ms). The passivity controller is on
 * with a 20 N s/m damping limit; set core.passivity = 0 to switch it off. */
int palp_cli_haptic_core_init(palp_cli_haptic_core *c, const palp_haptic_def *render, double physics_rate_hz,
                              int latency_compensation, double hold_after, double max_latency);
/* One tick at station time t [s] with the device at x (on: finger on; a reading that
 * is not finite is replaced by the last good one, or, before any, counts as lifted).
 * m: a model that arrived since the last tick (NULL if none; re-anchored in place
 * whatever its age when compensating and on), age: its age on arrival [s] (< 0 unknown). Fills the force to render and (xr) the
 * renderer's device point; returns palp_haptic_update's result for m (1 taken). */
int palp_cli_haptic_core_tick(palp_cli_haptic_core *c, int on, palp_vec3 x, double t, palp_local_model *m,
                              double age, palp_haptic_out *out, palp_vec3 *xr);

/* ---- the haptic thread --------------------------------------------------------------- */
typedef struct palp_cli_haptic_sample {
  double t;          /* station time since the loop started [s] */
  double late;       /* wake-up lateness [s] */
  palp_vec3 x;       /* device point [m] */
  palp_vec3 f;       /* force written to the device [N] */
  double requested;  /* |force| before the limit [N] */
  unsigned flags;    /* PALP_CLI_FORCE_* */
  int on;            /* finger on (1) or lifted (0) */
} palp_cli_haptic_sample;

typedef struct palp_cli_haptic_def {
  double rate_hz;          /* haptic rate, default 1000 */
  double physics_rate_hz;  /* the server's physics rate: contact samples are sent at it */
  double late_threshold;   /* a tick waking later than this is counted late [s], default 0.5e-3 */
  int rt_priority;         /* 0: normal scheduling; 1..99 SCHED_FIFO (refused: runs normal, says so) */
  int finger;              /* finger index on the wire, default 0 */
  double radius;           /* fingertip [m]; 0 = the input's, else 8 mm */
  palp_haptic_def render;  /* renderer parameters (max_force: the station's safe force limit) */
  double phantom_max_force; /* the phantom's limit from the catalogue (Phantom.max_force) [N]: the
                               safe force is the smaller; 0 = unknown (the station's alone) */
  int latency_compensation; /* re-anchor each model at the device's position on arrival (default 1) */
  double max_latency;       /* ages beyond this [s] are not compensated, default 0.2 */
  double hold_after;        /* the model's stiffness is used for this horizon [s] from the state it describes
                               (its age on arrival included), then the force is held until the next model;
                               0 = max(2 physics periods, 8 ms) */
  palp_cli_input *in;      /* must have read_position */
  dds_entity_t contact_w;  /* palp_contact writer in the session partition; 0: send nothing */
  uint32_t session_id;
  double duration;         /* [s]; 0 = until the input ends or stop is requested */
  palp_cli_haptic_sample *trace; /* optional: every tick recorded here */
  size_t trace_cap;
  int timer_floor;         /* 1: measure this machine's timer floor beside the loop (stats.floor_*) */
  /* optional: each valid local model palp_cli_haptic_feed takes, with its world frame, on its
   * caller's thread (the station's live coverage of an exercise) */
  void (*on_model)(void *ctx, const palp_local_model *m, uint64_t frame);
  void *on_model_ctx;
} palp_cli_haptic_def;

palp_cli_haptic_def palp_cli_haptic_default_def(void);

typedef struct palp_cli_haptic_stats {
  uint64_t ticks, late_ticks;   /* late: woke > late_threshold after the deadline; stalls excluded */
  double late_max;              /* [s]; stalls excluded */
  /* Ticks that woke more than PALP_TIMER_FLOOR_STALL_NS (0.4 s) late: the station's whole
   * process was not run (stopped, swapped out), which its timing does not describe; one
   * such tick per stall (the missed deadlines are not made up). */
  uint64_t stalls;
  double stall_max, stall_total; /* [s] */
  /* Deadlines skipped after a wake-up more than a period late (stalls included): ticks +
   * missed is the span the loop ran, in periods, however loaded the machine was. */
  uint64_t missed;
  uint64_t models;              /* models taken from the mailbox */
  uint64_t contacts_sent, contacts_dropped; /* dropped: the sender's ring was full */
  uint64_t contacts_failed;                 /* the sender's writes DDS refused */
  uint64_t bad_x_ticks;                     /* ticks whose device reading was not finite (core.bad_x_ticks) */
  uint64_t limited_ticks, stale_ticks, contact_ticks;
  uint64_t held_ticks; /* ticks rendered with the force held (model late) */
  uint64_t passivity_ticks;  /* ticks the passivity controller acted (damped or lessened a push) */
  double passivity_dissipated; /* energy it took out [J] */
  uint64_t server_limited_models; /* models the server flagged LM_FORCE_LIMIT */
  uint64_t stiffness_limited_models; /* models whose K the renderer limited (above render.max_stiffness, or
                                        indefinite: palp_haptic_limit_stiffness); their ticks in contact count
                                        in limited_ticks */
  uint64_t out_of_range_models;   /* models with any model-validity flag */
  uint64_t out_of_range_ticks;    /* ticks rendered from such a model (PALP_CLI_FORCE_OUT_OF_RANGE); here and in
                                     limited_ticks and the four below, the deadlines a late tick skipped count
                                     with the tick before (the device held its force): periods rendered */
  uint64_t beyond_validated_ticks; /* of those, from a model flagged LM_BEYOND_VALIDATED: the fingertip
                                      deeper than the phantom's forces were checked against the FE there */
  uint64_t strained_ticks;         /* of those, from a model flagged LM_LARGE_STRAIN: a link or the skin's
                                      bending beyond the model's own linear range */
  uint64_t limit_ticks;            /* of those, flagged LM_BASE_CONTACT, LM_CLAMPED_STEP or LM_UNSOLVED: pressed
                                      onto the base or beyond what the step can follow (a tick may be in several) */
  uint64_t gel_ticks;              /* of those, flagged LM_GEL_LAW_RANGE: the gel's literal pressure law
                                      stepped outside its stable range (since 2026-12-06) */
  double peak_force, peak_requested; /* [N] rendered / before the limit */
  double max_force;             /* the limit in force [N] */
  size_t trace_len;
  /* The timer floor (def.timer_floor, app/palp_timer_floor.h): a thread with the haptic
   * thread's scheduling that sleeps to the same deadlines, half a period later, and does
   * nothing else; late past late_threshold. The loop's own late_ticks are read against
   * it. Filled at join. */
  uint64_t floor_ticks, floor_late_ticks;
  uint64_t floor_missed;        /* its deadlines skipped, as missed: floor_ticks + floor_missed is its span */
  double floor_late_max;        /* [s] */
  int rt_ok;                    /* SCHED_FIFO granted */
  int ended;                    /* the input finished */
  int failed;                   /* the input reported an error (message in error) */
  char error[160];
} palp_cli_haptic_stats;

/* What the screen shows, refreshed every tick (mutex; readers copy). */
typedef struct palp_cli_haptic_view {
  double t;
  palp_vec3 x, proxy, force;
  palp_vec3 xr;  /* the renderer's device point: x minus the motion made while the force was held */
  /* issue 13: the server's newest local model, for a "lump here" mark at its contact point */
  palp_vec3 point;      /* LocalModel.point [m] */
  int model_contact;    /* a mark may be taken at point (palp_cli_haptic_can_mark) */
  double model_time;    /* LocalModel.time: world time of the step [s] */
  double requested, depth;
  unsigned flags;
  int on;
  uint64_t out_of_range_ticks; /* the stats' count so far: a reader sampling the view misses no episode */
  uint64_t beyond_validated_ticks, strained_ticks, limit_ticks, gel_ticks; /* the stats' counts by flag: which limit */
} palp_cli_haptic_view;

/* Contact samples queued from the haptic thread to its sender thread, and how many releases
 * a lift sends (best-effort: one lost must not leave the finger down). */
#define PALP_CLI_OUTBOX 64
#define PALP_CLI_RELEASE_SAMPLES 3
/* 1 if a sample may be queued with `queued` samples already waiting: a release while the ring
 * has room, a position sample only while room for a whole lift stays after it. */
int palp_cli_outbox_admits(unsigned queued, int release);
/* Whether a "lump here" mark may be taken at the renderer's current model, given the tick's flags
 * (palp_haptic_out): in contact and pushing (PALP_HAPTIC_CONTACT), and the model fresh. A model past
 * stale_time (a server gone quiet) still fades on the hand for fade_time, its contact point where the
 * finger was; until session 90 a mark was sent there, with its time, and graded where she no longer was
 * (found by review). A new press (palp_haptic_forget) has no model until the server's first. */
int palp_cli_haptic_can_mark(unsigned flags);

typedef struct palp_cli_haptic_loop {
  palp_cli_haptic_def def;
  palp_cli_mailbox mailbox;
  palp_cli_haptic_core core;
  pthread_t thread;
  int started;
  atomic_int stop, done;
  pthread_mutex_t view_lock;
  palp_cli_haptic_view view;
  palp_cli_haptic_stats stats; /* written by the haptic thread; read after join, or approximately */
  uint64_t seq;                /* contact samples */
  /* contact samples, haptic thread -> sender thread (single producer, single consumer) */
  palp_Contact outbox[PALP_CLI_OUTBOX];
  atomic_uint out_head, out_tail;
  sem_t out_sem;
  pthread_t sender;
  int sender_started;
  _Atomic uint64_t sent; /* by the sender thread; the station's main thread reads it (report_rejected) */
  uint64_t write_failed; /* by the sender thread alone, read after it is joined */
  palp_timer_floor floor; /* def.timer_floor; copied into stats at join */
  int64_t t0_ns;          /* the haptic thread's first deadline [ns], set before either thread starts */
} palp_cli_haptic_loop;

/* Starts the thread. The loop's mailbox takes models from the caller's DDS thread. */
int palp_cli_haptic_start(palp_cli_haptic_loop *l, const palp_cli_haptic_def *def, char *err, size_t errlen);
void palp_cli_haptic_request_stop(palp_cli_haptic_loop *l);
int palp_cli_haptic_done(palp_cli_haptic_loop *l);
/* Stops (if not done), joins, and fills *out; the loop can then be discarded. */
void palp_cli_haptic_join(palp_cli_haptic_loop *l, palp_cli_haptic_stats *out);
void palp_cli_haptic_get_view(palp_cli_haptic_loop *l, palp_cli_haptic_view *out);

/* The DDS side: takes every palp_local_model sample of finger def.finger from the
 * station's reader (st->local_model_r), checks it and puts it into the loop's mailbox.
 * Only the session's server's samples count (palp_cli_station_from_server: another
 * participant's are dropped and counted in st->bind, not in *bad). Returns the samples
 * taken; *bad counts dropped ones; *latency_us (if not NULL) gets the newest
 * sample's contact -> local model latency [us] (NAN if none), echoing the stamp
 * of the contact sample its step used. */
int palp_cli_haptic_feed(palp_cli_haptic_loop *l, palp_cli_station *st, uint64_t *bad, double *latency_us);

#endif
