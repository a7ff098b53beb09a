/* The session-log writer: a bounded queue in front of a worker thread that owns the SQLite
 * connection (the Redis bio.c pattern: slow I/O off the real-time thread).
 *
 * Queue: a ring of fixed-size records. Producers (the server's tick loops) take the mutex, copy a
 * record into the slot at head and leave; the worker reads the slots [tail, tail + n) without the
 * lock, because producers only ever write at head and head never reaches a slot the worker still
 * holds (count <= capacity). The worker gives slots back after their batch is committed or
 * dropped. Producers signal the worker only when a batch's worth of records is waiting, so the
 * common enqueue is a lock, a memcpy and an unlock with no system call.
 *
 * Control records (session begin/end, events) may use a reserve above the data capacity, in records
 * and in bytes, so a queue flooded with frames or meshes still records who was in a session and how it
 * ended.
 *
 * Disk errors: a failed batch is rolled back and retried after a doubling back-off
 * (retry_backoff_s, capped at 1 s) up to retry_limit times, then dropped and counted per kind and
 * per session. While the worker waits, producers keep going; if the queue fills they shed and
 * count. Either way the tick loop never sees the disk. */
#include <errno.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "db_internal.h"
#include "palp_db.h"

#define CONTROL_RESERVE 1024 /* slots above queue_capacity for begin/end/event records */
/* Bytes above queue_max_bytes that only control records may hold. Until 2026-12-07 the reserve was in
 * slots only: a queue holding queue_max_bytes of meshes (a stalled disk) refused a session's end like a
 * mesh, and palp-recorder left that session "(running)". The bound is the slot reserve at 4 kB a record
 * (measured 2026-12-07: a session begin with its scene 0.8-1.8 kB, an event's or an end's detail under
 * 0.5 kB, a shipped exercise 2-4 kB): room for every reserved slot as they are used, while a flood of
 * large control records (a 32 kB exercise each) still leaves the queue's memory bounded. */
#define CONTROL_RESERVE_BYTES ((size_t)4 << 20)
/* A session's end is never refused (session 81): each begin taken keeps one ring slot for its end, and
 * the end's detail is cut to this many bytes, held outside the byte caps (so at most this much per open
 * session). Until then an end met a queue whose control reserve a stalled disk and a flood of events had
 * spent: refused, counted as shed in the session's own row, and the server's log left it "(running)"
 * (palp-recorder kept it and retried). */
#define END_DETAIL_MAX 512
#define MAX_TXN_RECORDS 16384 /* records per transaction: bounds one commit's latency */
#define SHED_LOG_INTERVAL_S 1.0
#define DROP_SAY_INTERVAL_S 10.0 /* stderr lines for dropped batches: a full disk fails one every ~0.4 s */

#include "palp_version.h" /* PALP_VERSION_STRING, written at each build (cmake/PalpVersion.cmake) */

typedef struct rec {
  uint8_t kind; /* palp_db_record_kind */
  palp_db_session s;
  size_t bytes; /* heap bytes owned by the record (accounted in queue_bytes) */
  union {
    struct {
      char *blob; /* the def's strings, packed */
      palp_db_session_def def;
    } begin;
    struct {
      palp_db_end_reason reason;
      double end_unix_s;
      char *detail;
    } end;
    palp_db_contact contact;
    struct {
      int64_t frame;
      int slot;
      palp_vec3 f;
    } fb;
    palp_db_frame frame;
    struct {
      int64_t frame;
      int n;
      double *xyz; /* little-endian doubles, 3 n */
    } mesh;
    struct {
      palp_db_event_kind kind;
      int64_t frame;
      int64_t count;
      double wall;
      char *detail;
    } ev;
    struct {
      char *name; /* name and JSON, packed in one allocation */
      char *json;
    } ex;
    struct {
      palp_db_finger_sample s; /* s.triangles points into tri */
      int32_t *tri;            /* little-endian int32, NULL when none */
    } fs;
    palp_db_finding fd;
  } u;
} rec;

/* Producer-side view of a session: guarded by the mutex. */
typedef struct psess {
  int64_t shed;
  int64_t failed; /* counted by the worker (count_failed), read by any thread (palp_db_writer_session_losses) */
  uint8_t open;
  uint8_t end_kept; /* its begin keeps a ring slot for its end (ends_kept) */
} psess;

/* Worker-side view of a session: touched by the worker only. */
typedef struct wsess {
  int64_t rowid; /* 0 until the session row exists */
  char *blob;    /* the begin record's strings, kept until the row is durable and ended */
  palp_db_session_def def;
  int64_t shed_synced; /* records_shed last written */
  int64_t failed_synced;
  int ended;
  int dup; /* its uid's row in the file is another session's (session 82): its records are refused */
} wsess;

enum { ST_BEGIN, ST_SEL_SESSION, ST_END, ST_CONTACT, ST_FEEDBACK, ST_FRAME, ST_MESH, ST_EVENT,
       ST_COUNTS, ST_EXERCISE, ST_FINGER_SAMPLE, ST_FINDING, ST_SCENE, ST_PARAMS, ST_COUNT };

static const char *const stmt_sql[ST_COUNT] = {
    [ST_BEGIN] = "INSERT INTO session(uid, trainee, station, phantom_id, phantom_name, scene_json, "
                 "params_json, tick_hz, dt_s, start_unix_s) VALUES(?1,?2,?3,?4,?5,?6,?7,?8,?9,?10) "
                 "ON CONFLICT(uid) DO NOTHING",
    [ST_SEL_SESSION] = "SELECT id, trainee, station, phantom_id FROM session WHERE uid = ?1",
    [ST_END] = "UPDATE session SET end_unix_s = ?2, end_reason = ?3, end_detail = ?4, "
               "records_shed = ?5, records_failed = ?6 WHERE id = ?1",
    [ST_CONTACT] = "INSERT INTO contact_input(session_id, frame, sim_time_s, slot, op, kind, "
                   "distribution, center_x_m, center_y_m, center_z_m, force_x_n, force_y_n, force_z_n, "
                   "radius_m, patch_area_m2, sigma_fraction, offset_fraction, offset_dir_x, "
                   "offset_dir_y, offset_dir_z) "
                   "VALUES(?1,?2,?3,?4,?5,?6,?7,?8,?9,?10,?11,?12,?13,?14,?15,?16,?17,?18,?19,?20)",
    [ST_FEEDBACK] = "INSERT INTO feedback(session_id, frame, slot, force_x_n, force_y_n, force_z_n) "
                    "VALUES(?1,?2,?3,?4,?5,?6)",
    [ST_FRAME] = "INSERT INTO frame(session_id, frame, sim_time_s, top_disp_m, max_disp_m, volume_m3, "
                 "pressure_pa, contact_force_n, state_hash) VALUES(?1,?2,?3,?4,?5,?6,?7,?8,?9)",
    [ST_MESH] = "INSERT INTO mesh(session_id, frame, vertex_count, positions_m) VALUES(?1,?2,?3,?4)",
    [ST_EVENT] = "INSERT INTO event(session_id, wall_unix_s, frame, kind, detail, count) "
                 "VALUES(?1,?2,?3,?4,?5,?6)",
    [ST_COUNTS] = "UPDATE session SET records_shed = ?2, records_failed = ?3 WHERE id = ?1",
    [ST_EXERCISE] = "INSERT INTO session_exercise(session_id, exercise_name, exercise_json) VALUES(?1,?2,?3)",
    [ST_SCENE] = "UPDATE session SET phantom_name = ?2, scene_json = ?3 WHERE id = ?1 AND scene_json = '{}'",
    [ST_PARAMS] = "UPDATE session SET params_json = ?2 WHERE id = ?1",
    [ST_FINGER_SAMPLE] = "INSERT INTO finger_sample(session_id, frame, slot, sim_time_s, radius_m, device_x_m, "
                         "device_y_m, device_z_m, proxy_x_m, proxy_y_m, proxy_z_m, force_x_n, force_y_n, "
                         "force_z_n, in_contact, point_x_m, point_y_m, point_z_m, area_m2, triangles) "
                         "VALUES(?1,?2,?3,?4,?5,?6,?7,?8,?9,?10,?11,?12,?13,?14,?15,?16,?17,?18,?19,?20)",
    [ST_FINDING] = "INSERT INTO finding(session_id, mark_id, op, frame, sim_time_s, wall_unix_s, point_x_m, "
                   "point_y_m, point_z_m) VALUES(?1,?2,?3,?4,?5,?6,?7,?8,?9)",
};

struct palp_db_writer {
  palp_db_writer_opts opts;
  char path[1024];
  sqlite3 *db;
  sqlite3_stmt *st[ST_COUNT];
  int64_t run_id;
  pthread_t thread;

  pthread_mutex_t mu;
  pthread_cond_t wake; /* worker: records waiting, flush or stop */
  pthread_cond_t done; /* flushers: records retired */
  rec *ring;
  int cap;       /* ring slots = data capacity + control reserve */
  int data_cap;  /* data records are refused beyond this */
  int head, tail, count;
  int ends_kept; /* ring slots kept for the ends of the sessions begun (END_DETAIL_MAX) */
  size_t queue_bytes;
  int stop;
  int flush_waiters;
  int64_t enq_seq, done_seq; /* records accepted / retired (written or dropped) */
  psess *ps;
  int ps_cap;
  palp_db_session next_session;
  palp_db_writer_stats st_;

  /* worker-only state */
  wsess *ws;
  int ws_cap;
  int64_t shed_logged;
  double shed_logged_at;
  int64_t failed_logged;
  int64_t counts_shed, counts_failed; /* the writer's totals when the sessions' counts were last synced */
  int counts_resync;                  /* a sync rolled back: every session's row goes again */
  int64_t drop_unsaid;                /* records in dropped batches not yet said on stderr */
  int drop_unsaid_batches, drop_said; /* ... in so many batches; a line was printed already */
  double drop_said_at, shed_said_at;  /* when the last such line was printed [s, monotonic] */
  /* The worker's per-batch marks, here rather than malloc'd at the thread's start (session 82: that
   * malloc was unchecked, and a failure became a NULL write in the worker at its first batch). */
  uint8_t refused[MAX_TXN_RECORDS]; /* attempt_batch: the records a constraint refused */
  uint8_t pick[MAX_TXN_RECORDS];    /* rescue_control: the records it tries */
  uint8_t scratch[MAX_TXN_RECORDS]; /* rescue_control: the records a constraint refused */
  palp_db_session *touched; /* sessions whose row was inserted in the current attempt */
  int touched_n, touched_cap;
};

palp_db_writer_opts palp_db_writer_default_opts(void) {
  palp_db_writer_opts o = {0};
  o.queue_capacity = 131072;
  o.queue_max_bytes = (size_t)64 << 20;
  o.batch_records = 4096;
  o.commit_interval_s = 0.1;
  o.retry_backoff_s = 0.05;
  o.retry_limit = 3;
  o.max_db_bytes = 0;
  o.app_version = NULL;
  return o;
}

const char *palp_db_record_kind_name(palp_db_record_kind k) {
  static const char *const n[PALP_DB_REC_KIND_COUNT] = {"session_begin", "session_end", "contact",
                                                        "feedback", "frame", "mesh", "event",
                                                        "exercise", "finger_sample", "finding",
                                                        "session_scene", "session_params"};
  return (unsigned)k < PALP_DB_REC_KIND_COUNT ? n[k] : "?";
}

const char *palp_db_end_reason_name(palp_db_end_reason r) {
  switch (r) {
  case PALP_DB_END_NORMAL: return "normal";
  case PALP_DB_END_STATION_VANISHED: return "station_vanished";
  case PALP_DB_END_SERVER_SHUTDOWN: return "server_shutdown";
  case PALP_DB_END_ERROR: return "error";
  }
  return NULL;
}

palp_db_end_reason palp_db_end_reason_of(const char *reason) {
  if (!reason) return PALP_DB_END_NORMAL;
  /* a failure first: whatever else a reason says, a fault ended the session */
  if (strstr(reason, "failed") || strstr(reason, "full") || strstr(reason, "error") || strstr(reason, "conflict"))
    return PALP_DB_END_ERROR;
  if (strstr(reason, "lost") || strstr(reason, "vanish") || strstr(reason, "liveliness"))
    return PALP_DB_END_STATION_VANISHED;
  if (strstr(reason, "shutdown")) return PALP_DB_END_SERVER_SHUTDOWN;
  return PALP_DB_END_NORMAL;
}

const char *palp_db_event_kind_name(palp_db_event_kind k) {
  static const char *const n[PALP_DB_EVENT_KIND_COUNT] = {
      NULL, "join", "leave", "reject", "clamp", "overrun", "shed", "disk_error", "info", "valid_range",
      "security_refused", "debrief"};
  return (k > 0 && k < PALP_DB_EVENT_KIND_COUNT) ? n[k] : NULL;
}

static void rec_free(rec *r) {
  switch (r->kind) {
  case PALP_DB_REC_SESSION_BEGIN: free(r->u.begin.blob); break;
  case PALP_DB_REC_SESSION_END: free(r->u.end.detail); break;
  case PALP_DB_REC_MESH: free(r->u.mesh.xyz); break;
  case PALP_DB_REC_EVENT: free(r->u.ev.detail); break;
  case PALP_DB_REC_EXERCISE:
  case PALP_DB_REC_SESSION_SCENE:
  case PALP_DB_REC_SESSION_PARAMS: free(r->u.ex.name); break;
  case PALP_DB_REC_FINGER_SAMPLE: free(r->u.fs.tri); break;
  default: break;
  }
}

static void sleep_s(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
  while (nanosleep(&ts, &ts) == -1 && errno == EINTR) {
  }
}

static void abs_deadline(struct timespec *ts, double s) {
  clock_gettime(CLOCK_MONOTONIC, ts);
  double ns = (double)ts->tv_nsec + s * 1e9;
  ts->tv_sec += (time_t)(ns / 1e9);
  ts->tv_nsec = (long)(ns - (double)(time_t)(ns / 1e9) * 1e9);
}

static double mono_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- producer side ------------------------------------------------------------ */

/* Claims a slot for a record of `kind` holding `bytes` heap bytes; returns NULL (and counts the
 * shed record) when the queue is full. Called with the mutex held. */
static rec *claim(palp_db_writer *w, palp_db_record_kind kind, palp_db_session s, size_t bytes) {
  /* An exercise and a trainee's findings are as rare and as needed as who was in a session. */
  const int control = kind == PALP_DB_REC_SESSION_BEGIN || kind == PALP_DB_REC_SESSION_END ||
                      kind == PALP_DB_REC_EVENT || kind == PALP_DB_REC_EXERCISE || kind == PALP_DB_REC_FINDING ||
                      kind == PALP_DB_REC_SESSION_SCENE || kind == PALP_DB_REC_SESSION_PARAMS;
  const int limit = control ? w->cap : w->data_cap;
  const size_t max_bytes = w->opts.queue_max_bytes, reserve = control ? CONTROL_RESERVE_BYTES : 0;
  const size_t byte_limit = max_bytes > SIZE_MAX - reserve ? SIZE_MAX : max_bytes + reserve;
  /* its end's slot kept by its begin: taken whatever the queue holds (count + ends_kept <= cap) */
  const int kept = kind == PALP_DB_REC_SESSION_END && s > 0 && s < w->ps_cap && w->ps[s].end_kept;
  const int slots = kind == PALP_DB_REC_SESSION_BEGIN ? 2 : 1; /* a begin keeps one for its end */
  if (kept) {
    w->ps[s].end_kept = 0;
    w->ends_kept--;
  } else if (w->count >= limit || w->count + w->ends_kept + slots > w->cap ||
             (bytes > 0 && (bytes > byte_limit || w->queue_bytes > byte_limit - bytes))) {
    w->st_.shed++;
    w->st_.shed_by_kind[kind]++;
    if (s > 0 && s < w->ps_cap) w->ps[s].shed++;
    return NULL;
  }
  rec *r = &w->ring[w->head];
  w->head = (w->head + 1) % w->cap;
  w->count++;
  if (w->count > w->st_.queue_high_water) w->st_.queue_high_water = w->count;
  w->queue_bytes += bytes;
  w->enq_seq++;
  w->st_.enqueued++;
  memset(r, 0, sizeof *r);
  r->kind = (uint8_t)kind;
  r->s = s;
  r->bytes = bytes;
  return r;
}

/* Wakes the worker only when a batch is ready: no syscall on the common path. */
static void publish(palp_db_writer *w) {
  if (w->count == w->opts.batch_records) pthread_cond_signal(&w->wake);
  pthread_mutex_unlock(&w->mu);
}

static int session_ok(const palp_db_writer *w, palp_db_session s) {
  return s > 0 && s < w->next_session && s < w->ps_cap && w->ps[s].open;
}

/* Takes the queue lock for a record of session s (0 allowed only where none_ok).
 * On an unknown or closed session it unlocks, frees the caller's copied payload
 * (may be NULL) and fails, so every enqueue function checks the same way. */
static int lock_session(palp_db_writer *w, palp_db_session s, int none_ok, void *owned) {
  pthread_mutex_lock(&w->mu);
  if ((none_ok && s == 0) || session_ok(w, s)) return 0;
  pthread_mutex_unlock(&w->mu);
  free(owned);
  return PALP_EINVAL;
}

static size_t str_size(const char *s) { return (s ? strlen(s) : 0) + 1; }
static char *pack(char **p, const char *s) {
  char *d = *p;
  size_t n = str_size(s);
  if (s) memcpy(d, s, n); else d[0] = '\0';
  *p += n;
  return d;
}

int palp_db_log_session_begin(palp_db_writer *w, const palp_db_session_def *def, palp_db_session *out) {
  if (!w || !def || !out || !def->uid || !*def->uid || !(def->tick_hz > 0) || !(def->dt_s > 0))
    return PALP_EINVAL;
  const char *str[7] = {def->uid, def->trainee, def->station, def->phantom_id, def->phantom_name,
                        def->scene_json, def->params_json ? def->params_json : "{}"};
  size_t bytes = 0;
  for (int i = 0; i < 7; i++) bytes += str_size(str[i]);
  char *blob = malloc(bytes); /* outside the lock: the copy is the caller's cost, not the queue's */
  if (!blob) return PALP_ENOMEM;
  char *p = blob;
  palp_db_session_def d = *def;
  d.uid = pack(&p, str[0]);
  d.trainee = pack(&p, str[1]);
  d.station = pack(&p, str[2]);
  d.phantom_id = pack(&p, str[3]);
  d.phantom_name = pack(&p, str[4]);
  d.scene_json = pack(&p, str[5]);
  d.params_json = pack(&p, str[6]);
  if (d.start_unix_s <= 0) d.start_unix_s = palp_db__now();

  pthread_mutex_lock(&w->mu);
  palp_db_session s = w->next_session;
  if (s >= w->ps_cap) {
    int ncap = w->ps_cap ? 2 * w->ps_cap : 64;
    psess *n = realloc(w->ps, (size_t)ncap * sizeof *n);
    if (!n) {
      pthread_mutex_unlock(&w->mu);
      free(blob);
      return PALP_ENOMEM;
    }
    memset(n + w->ps_cap, 0, (size_t)(ncap - w->ps_cap) * sizeof *n);
    w->ps = n;
    w->ps_cap = ncap;
  }
  rec *r = claim(w, PALP_DB_REC_SESSION_BEGIN, 0, bytes);
  if (!r) {
    pthread_mutex_unlock(&w->mu);
    free(blob);
    return PALP_EFULL;
  }
  w->next_session++;
  w->ps[s].open = 1;
  w->ps[s].end_kept = 1; /* claim counted its slot */
  w->ends_kept++;
  w->ps[s].shed = w->ps[s].failed = 0;
  r->s = s;
  r->u.begin.blob = blob;
  r->u.begin.def = d;
  publish(w);
  *out = s;
  return 0;
}

int palp_db_log_contact(palp_db_writer *w, palp_db_session s, const palp_db_contact *c) {
  if (!w || !c || c->op < PALP_DB_OP_ADD || c->op > PALP_DB_OP_REMOVE || c->kind < PALP_DB_KIND_FORCE ||
      c->kind > PALP_DB_KIND_FINGER)
    return PALP_EINVAL;
  if (lock_session(w, s, 0, NULL)) return PALP_EINVAL;
  rec *r = claim(w, PALP_DB_REC_CONTACT, s, 0);
  if (r) r->u.contact = *c;
  publish(w);
  return r ? 0 : PALP_EFULL;
}

int palp_db_log_feedback(palp_db_writer *w, palp_db_session s, int64_t frame, int slot, palp_vec3 force_n) {
  if (!w) return PALP_EINVAL;
  if (lock_session(w, s, 0, NULL)) return PALP_EINVAL;
  rec *r = claim(w, PALP_DB_REC_FEEDBACK, s, 0);
  if (r) {
    r->u.fb.frame = frame;
    r->u.fb.slot = slot;
    r->u.fb.f = force_n;
  }
  publish(w);
  return r ? 0 : PALP_EFULL;
}

int palp_db_log_frame(palp_db_writer *w, palp_db_session s, const palp_db_frame *f) {
  if (!w || !f) return PALP_EINVAL;
  if (lock_session(w, s, 0, NULL)) return PALP_EINVAL;
  rec *r = claim(w, PALP_DB_REC_FRAME, s, 0);
  if (r) r->u.frame = *f;
  publish(w);
  return r ? 0 : PALP_EFULL;
}

/* Stores doubles little-endian whatever the host order, so files move between machines. */
static void put_le_doubles(double *dst, const palp_vec3 *pos, int n) {
  unsigned char *out = (unsigned char *)dst;
  for (int i = 0; i < n; i++) {
    const double v[3] = {pos[i].x, pos[i].y, pos[i].z};
    for (int k = 0; k < 3; k++) {
      uint64_t u;
      memcpy(&u, &v[k], 8);
      for (int b = 0; b < 8; b++) *out++ = (unsigned char)(u >> (8 * b));
    }
  }
}

int palp_db_log_mesh(palp_db_writer *w, palp_db_session s, int64_t frame, const palp_vec3 *pos,
                     int vertex_count) {
  /* A blob of at most INT_MAX bytes (session 82): the worker's length was an int, which overflowed
   * past 89,478,485 vertices (possible with a queue_max_bytes over 2 GiB); refused before the copy. */
  if (!w || !pos || vertex_count <= 0 || vertex_count > PALP_DB_MESH_MAX_VERTICES) return PALP_EINVAL;
  size_t bytes = (size_t)vertex_count * 3 * sizeof(double);
  double *xyz = malloc(bytes);
  if (!xyz) return PALP_ENOMEM;
  put_le_doubles(xyz, pos, vertex_count);
  if (lock_session(w, s, 0, xyz)) return PALP_EINVAL;
  rec *r = claim(w, PALP_DB_REC_MESH, s, bytes);
  if (r) {
    r->u.mesh.frame = frame;
    r->u.mesh.n = vertex_count;
    r->u.mesh.xyz = xyz;
  }
  publish(w);
  if (!r) free(xyz);
  return r ? 0 : PALP_EFULL;
}

/* A caller's text copied for the queue (the caller's buffer may not outlive the
 * call); NULL stays NULL. *bytes counts the terminator, for the queue's accounting. */
static int copy_text(const char *src, char **out, size_t *bytes) {
  *out = NULL;
  *bytes = 0;
  if (!src) return 0;
  *bytes = strlen(src) + 1;
  if (!(*out = malloc(*bytes))) return -1;
  memcpy(*out, src, *bytes);
  return 0;
}

int palp_db_log_event(palp_db_writer *w, palp_db_session s, palp_db_event_kind kind, int64_t frame,
                      const char *detail, int64_t count) {
  if (!w || !palp_db_event_kind_name(kind)) return PALP_EINVAL;
  char *d = NULL;
  size_t bytes = 0;
  if (copy_text(detail, &d, &bytes)) return PALP_ENOMEM;
  if (lock_session(w, s, 1, d)) return PALP_EINVAL;
  rec *r = claim(w, PALP_DB_REC_EVENT, s, bytes);
  if (r) {
    r->u.ev.kind = kind;
    r->u.ev.frame = frame;
    r->u.ev.count = count > 0 ? count : 1;
    r->u.ev.wall = palp_db__now();
    r->u.ev.detail = d;
  }
  publish(w);
  if (!r) free(d);
  return r ? 0 : PALP_EFULL;
}

int palp_db_log_session_end(palp_db_writer *w, palp_db_session s, palp_db_end_reason reason,
                            const char *detail, double end_unix_s) {
  if (!w || !palp_db_end_reason_name(reason)) return PALP_EINVAL;
  char *d = NULL;
  size_t bytes = 0;
  if (copy_text(detail, &d, &bytes)) return PALP_ENOMEM;
  if (d && bytes > END_DETAIL_MAX) { /* cut at a UTF-8 character's start */
    size_t n = END_DETAIL_MAX - 1;
    while (n > 0 && ((unsigned char)d[n] & 0xC0) == 0x80) n--;
    d[n] = '\0';
    bytes = n + 1;
  }
  if (lock_session(w, s, 0, d)) return PALP_EINVAL;
  rec *r = claim(w, PALP_DB_REC_SESSION_END, s, bytes);
  if (r) {
    w->ps[s].open = 0;
    r->u.end.reason = reason;
    r->u.end.end_unix_s = end_unix_s > 0 ? end_unix_s : palp_db__now();
    r->u.end.detail = d;
  }
  publish(w);
  if (!r) free(d);
  return r ? 0 : PALP_EFULL;
}

/* A record of a name and a JSON text, packed in one allocation (the exercise, the session's scene). */
static int log_named_json(palp_db_writer *w, palp_db_session s, palp_db_record_kind kind, const char *name,
                          const char *json) {
  const size_t nn = strlen(name) + 1, nj = strlen(json) + 1;
  char *blob = malloc(nn + nj);
  if (!blob) return PALP_ENOMEM;
  memcpy(blob, name, nn);
  memcpy(blob + nn, json, nj);
  if (lock_session(w, s, 0, blob)) return PALP_EINVAL;
  rec *r = claim(w, kind, s, nn + nj);
  if (r) {
    r->u.ex.name = blob;
    r->u.ex.json = blob + nn;
  }
  publish(w);
  if (!r) free(blob);
  return r ? 0 : PALP_EFULL;
}

int palp_db_log_exercise(palp_db_writer *w, palp_db_session s, const char *exercise_name,
                         const char *exercise_json) {
  if (!w || !exercise_name || !*exercise_name || !exercise_json) return PALP_EINVAL;
  return log_named_json(w, s, PALP_DB_REC_EXERCISE, exercise_name, exercise_json);
}

int palp_db_log_session_scene(palp_db_writer *w, palp_db_session s, const char *phantom_name,
                              const char *scene_json) {
  if (!w || !phantom_name || !scene_json || !*scene_json) return PALP_EINVAL;
  return log_named_json(w, s, PALP_DB_REC_SESSION_SCENE, phantom_name, scene_json);
}

int palp_db_log_session_params(palp_db_writer *w, palp_db_session s, const char *params_json) {
  if (!w || !params_json || !*params_json) return PALP_EINVAL;
  return log_named_json(w, s, PALP_DB_REC_SESSION_PARAMS, "", params_json);
}

int palp_db_log_finger_sample(palp_db_writer *w, palp_db_session s, const palp_db_finger_sample *fs) {
  if (!w || !fs || fs->triangle_count < 0 || fs->triangle_count > PALP_DB_MAX_SAMPLE_TRIANGLES ||
      (fs->triangle_count > 0 && !fs->triangles))
    return PALP_EINVAL;
  int32_t *tri = NULL;
  const size_t bytes = (size_t)fs->triangle_count * 4;
  if (bytes) {
    if (!(tri = malloc(bytes))) return PALP_ENOMEM;
    unsigned char *o = (unsigned char *)tri; /* little-endian whatever the host order */
    for (int i = 0; i < fs->triangle_count; i++) {
      const uint32_t v = (uint32_t)fs->triangles[i];
      for (int b = 0; b < 4; b++) *o++ = (unsigned char)(v >> (8 * b));
    }
  }
  if (lock_session(w, s, 0, tri)) return PALP_EINVAL;
  rec *r = claim(w, PALP_DB_REC_FINGER_SAMPLE, s, bytes);
  if (r) {
    r->u.fs.s = *fs;
    r->u.fs.s.triangles = NULL;
    r->u.fs.tri = tri;
  }
  publish(w);
  if (!r) free(tri);
  return r ? 0 : PALP_EFULL;
}

int palp_db_log_finding(palp_db_writer *w, palp_db_session s, const palp_db_finding *f) {
  if (!w || !f || (f->op != PALP_DB_FINDING_MARK && f->op != PALP_DB_FINDING_WITHDRAW)) return PALP_EINVAL;
  if (lock_session(w, s, 0, NULL)) return PALP_EINVAL;
  rec *r = claim(w, PALP_DB_REC_FINDING, s, 0);
  if (r) {
    r->u.fd = *f;
    if (r->u.fd.wall_unix_s <= 0) r->u.fd.wall_unix_s = palp_db__now();
  }
  publish(w);
  return r ? 0 : PALP_EFULL;
}

static int losses_of(palp_db_writer *w, palp_db_session s, int64_t *shed, int64_t *failed);

int palp_db_writer_session_losses(palp_db_writer *w, palp_db_session s, int64_t *shed, int64_t *failed) {
  *shed = *failed = 0;
  return w && losses_of(w, s, shed, failed) ? 0 : PALP_EINVAL;
}

void palp_db_writer_stats_get(palp_db_writer *w, palp_db_writer_stats *out) {
  pthread_mutex_lock(&w->mu);
  *out = w->st_;
  out->queued = w->count;
  out->queue_capacity = w->data_cap;
  pthread_mutex_unlock(&w->mu);
}

int64_t palp_db_writer_mark(palp_db_writer *w) {
  if (!w) return 0;
  pthread_mutex_lock(&w->mu);
  const int64_t m = w->enq_seq;
  pthread_mutex_unlock(&w->mu);
  return m;
}

int palp_db_writer_flush(palp_db_writer *w, double timeout_s) {
  return palp_db_writer_wait(w, palp_db_writer_mark(w), timeout_s);
}

int palp_db_writer_wait(palp_db_writer *w, int64_t target, double timeout_s) {
  if (!w) return PALP_EINVAL;
  struct timespec dl;
  abs_deadline(&dl, timeout_s);
  int rc = 0;
  pthread_mutex_lock(&w->mu);
  w->flush_waiters++;
  pthread_cond_signal(&w->wake);
  while (w->done_seq < target) {
    if (pthread_cond_timedwait(&w->done, &w->mu, &dl) == ETIMEDOUT) {
      rc = PALP_EIO;
      break;
    }
  }
  w->flush_waiters--;
  pthread_mutex_unlock(&w->mu);
  return rc;
}

/* ---- worker side --------------------------------------------------------------- */

static int is_disk_error(int rc) {
  switch (rc & 0xff) {
  case SQLITE_FULL:
  case SQLITE_IOERR:
  case SQLITE_BUSY:
  case SQLITE_LOCKED:
  case SQLITE_CANTOPEN:
  case SQLITE_READONLY:
  case SQLITE_CORRUPT:
  case SQLITE_NOMEM:
  case SQLITE_NOTADB:
  case SQLITE_PROTOCOL: return 1;
  default: return 0;
  }
}

static void set_error(palp_db_writer *w, int rc, const char *what) {
  pthread_mutex_lock(&w->mu);
  w->st_.in_error = 1;
  w->st_.disk_errors++;
  w->st_.last_error_code = rc;
  const char *msg = sqlite3_errmsg(w->db), *gen = sqlite3_errstr(rc);
  /* a rollback after the failure succeeded: errmsg then says "not an error", which tells nothing */
  if (strcmp(msg, gen) == 0 || sqlite3_errcode(w->db) == SQLITE_OK)
    palp_db__fmt(w->st_.last_error, sizeof w->st_.last_error, "%s: %s", what, gen);
  else palp_db__fmt(w->st_.last_error, sizeof w->st_.last_error, "%s: %s (%s)", what, msg, gen);
  pthread_mutex_unlock(&w->mu);
}

static wsess *wsess_get(palp_db_writer *w, palp_db_session s) {
  if (s >= w->ws_cap) {
    int ncap = w->ws_cap ? 2 * w->ws_cap : 64;
    while (ncap <= s) ncap *= 2;
    wsess *n = realloc(w->ws, (size_t)ncap * sizeof *n);
    if (!n) return NULL;
    memset(n + w->ws_cap, 0, (size_t)(ncap - w->ws_cap) * sizeof *n);
    w->ws = n;
    w->ws_cap = ncap;
  }
  return &w->ws[s];
}

static int step_reset(sqlite3_stmt *st) {
  int rc = sqlite3_step(st);
  sqlite3_reset(st);
  sqlite3_clear_bindings(st);
  return rc == SQLITE_ROW ? SQLITE_DONE : rc;
}

static void bind_text(sqlite3_stmt *st, int i, const char *s) {
  sqlite3_bind_text(st, i, s ? s : "", -1, SQLITE_STATIC);
}

/* Makes sure the session's row exists (it may have been rolled back with a failed batch). */
static int session_rowid(palp_db_writer *w, palp_db_session s, int64_t *rowid) {
  wsess *ws = wsess_get(w, s);
  if (!ws) return SQLITE_NOMEM;
  if (ws->rowid) {
    *rowid = ws->rowid;
    return SQLITE_OK;
  }
  if (ws->dup) return SQLITE_CONSTRAINT_UNIQUE; /* refused at its begin: every record counted failed */
  if (!ws->blob) return SQLITE_MISUSE; /* begin never seen: cannot happen with a FIFO queue */
  const palp_db_session_def *d = &ws->def;
  sqlite3_stmt *st = w->st[ST_BEGIN];
  bind_text(st, 1, d->uid);
  bind_text(st, 2, d->trainee);
  bind_text(st, 3, d->station);
  bind_text(st, 4, d->phantom_id);
  bind_text(st, 5, d->phantom_name);
  bind_text(st, 6, d->scene_json);
  bind_text(st, 7, d->params_json);
  sqlite3_bind_double(st, 8, d->tick_hz);
  sqlite3_bind_double(st, 9, d->dt_s);
  sqlite3_bind_double(st, 10, d->start_unix_s);
  int rc = step_reset(st);
  if (rc != SQLITE_DONE) return rc;
  /* No row inserted: the uid is in the file already (a rolled-back row is not, so this is never this
   * writer's own). The same trainee, station and phantom: the same session begun again (palp-recorder
   * restarted within the millisecond its uid is built from), which goes on in that row as before
   * session 82. Anything else is another session under a uid already taken (another writer's, a
   * server run whose id repeated, a forgery): refused, so that its records never join the old
   * session's or overwrite its end. */
  const int inserted = sqlite3_changes(w->db) > 0;
  st = w->st[ST_SEL_SESSION];
  bind_text(st, 1, d->uid);
  rc = sqlite3_step(st);
  int same = 1;
  if (rc == SQLITE_ROW && !inserted) {
    const char *have[3] = {(const char *)sqlite3_column_text(st, 1), (const char *)sqlite3_column_text(st, 2),
                           (const char *)sqlite3_column_text(st, 3)};
    const char *want[3] = {d->trainee, d->station, d->phantom_id};
    for (int i = 0; i < 3; i++) same &= !strcmp(have[i] ? have[i] : "", want[i] ? want[i] : "");
  }
  if (rc == SQLITE_ROW && same) ws->rowid = sqlite3_column_int64(st, 0);
  sqlite3_reset(st);
  sqlite3_clear_bindings(st);
  if (rc == SQLITE_ROW && !same) {
    ws->dup = 1;
    char msg[256];
    palp_db__fmt(msg, sizeof msg, "session uid \"%.100s\" refused: the file holds another session under it "
                 "(another trainee, station or phantom); its records are not logged", d->uid);
    fprintf(stderr, "palp_db: %s: %s\n", w->path, msg);
    pthread_mutex_lock(&w->mu);
    palp_db__fmt(w->st_.last_error, sizeof w->st_.last_error, "%s", msg);
    w->st_.last_error_code = SQLITE_CONSTRAINT_UNIQUE;
    pthread_mutex_unlock(&w->mu);
    return SQLITE_CONSTRAINT_UNIQUE;
  }
  if (rc != SQLITE_ROW) return rc == SQLITE_DONE ? SQLITE_ERROR : rc;
  /* The new row counts no loss; records this session lost before it existed go in at the next pass. */
  ws->shed_synced = ws->failed_synced = 0;
  w->counts_resync = 1;
  if (w->touched_n == w->touched_cap) {
    int ncap = w->touched_cap ? 2 * w->touched_cap : 16;
    palp_db_session *n = realloc(w->touched, (size_t)ncap * sizeof *n);
    if (!n) return SQLITE_NOMEM;
    w->touched = n;
    w->touched_cap = ncap;
  }
  w->touched[w->touched_n++] = s;
  *rowid = ws->rowid;
  return SQLITE_OK;
}

static void bind_vec(sqlite3_stmt *st, int i, palp_vec3 v) {
  sqlite3_bind_double(st, i, v.x);
  sqlite3_bind_double(st, i + 1, v.y);
  sqlite3_bind_double(st, i + 2, v.z);
}

/* A session's losses so far (the producer's sheds, the worker's failures), under the mutex: 1, or 0
 * (both 0) for a handle this writer never gave. */
static int losses_of(palp_db_writer *w, palp_db_session s, int64_t *shed, int64_t *failed) {
  pthread_mutex_lock(&w->mu);
  const int ok = s > 0 && s < w->next_session && s < w->ps_cap;
  *shed = ok ? w->ps[s].shed : 0;
  *failed = ok ? w->ps[s].failed : 0;
  pthread_mutex_unlock(&w->mu);
  return ok;
}

/* A session-begin record's strings, taken over by its session: they outlive the record's slot for
 * lazy re-inserts of the session's row (session_rowid). Returns the session's state, NULL without
 * memory. */
static wsess *take_begin(palp_db_writer *w, rec *r) {
  wsess *ws = wsess_get(w, r->s);
  if (ws && !ws->blob && r->u.begin.blob) {
    ws->blob = r->u.begin.blob;
    ws->def = r->u.begin.def;
    r->u.begin.blob = NULL;
  }
  return ws;
}

/* Writes one record inside the open transaction. Returns an SQLite code. */
static int write_rec(palp_db_writer *w, rec *r) {
  if (r->kind == PALP_DB_REC_SESSION_BEGIN) {
    wsess *ws = take_begin(w, r);
    if (!ws) return SQLITE_NOMEM;
    int64_t id;
    const int rc = session_rowid(w, r->s, &id);
    if (!ws->dup) return rc;
    /* refused (a uid already in the file): a session-less event says so, in this transaction */
    char detail[256];
    palp_db__fmt(detail, sizeof detail, "session begin refused: uid \"%.100s\" is another session's in this file "
                 "(trainee \"%.40s\"); its records are not logged", ws->def.uid, ws->def.trainee ? ws->def.trainee : "");
    sqlite3_stmt *st = w->st[ST_EVENT];
    sqlite3_bind_double(st, 2, palp_db__now());
    bind_text(st, 4, palp_db_event_kind_name(PALP_DB_EVENT_REJECT));
    bind_text(st, 5, detail);
    sqlite3_bind_int64(st, 6, 1);
    const int erc = step_reset(st);
    return is_disk_error(erc) ? erc : rc;
  }
  int64_t sid = 0;
  if (r->s > 0) {
    int rc = session_rowid(w, r->s, &sid);
    if (rc != SQLITE_OK) return rc;
  }
  sqlite3_stmt *st;
  switch (r->kind) {
  case PALP_DB_REC_SESSION_END: {
    wsess *ws = &w->ws[r->s];
    st = w->st[ST_END];
    sqlite3_bind_int64(st, 1, sid);
    sqlite3_bind_double(st, 2, r->u.end.end_unix_s);
    bind_text(st, 3, palp_db_end_reason_name(r->u.end.reason));
    if (r->u.end.detail) bind_text(st, 4, r->u.end.detail);
    int64_t shed, failed;
    losses_of(w, r->s, &shed, &failed);
    sqlite3_bind_int64(st, 5, shed);
    sqlite3_bind_int64(st, 6, failed);
    ws->ended = 1;
    return step_reset(st);
  }
  case PALP_DB_REC_CONTACT: {
    const palp_db_contact *c = &r->u.contact;
    st = w->st[ST_CONTACT];
    sqlite3_bind_int64(st, 1, sid);
    sqlite3_bind_int64(st, 2, c->frame);
    sqlite3_bind_double(st, 3, c->sim_time_s);
    sqlite3_bind_int(st, 4, c->slot);
    bind_text(st, 5, c->op == PALP_DB_OP_ADD ? "add" : c->op == PALP_DB_OP_UPDATE ? "update" : "remove");
    bind_text(st, 6, c->kind == PALP_DB_KIND_FORCE ? "force" : "finger");
    if (c->op != PALP_DB_OP_REMOVE) {
      if (c->kind == PALP_DB_KIND_FORCE) {
        bind_vec(st, 11, c->force_n);
        if (c->def.distribution != 0) {
          sqlite3_bind_int(st, 7, (int)c->def.distribution);
          bind_vec(st, 8, c->def.center);
          sqlite3_bind_double(st, 15, c->def.patch_area);
          sqlite3_bind_double(st, 16, c->def.sigma_fraction);
          sqlite3_bind_double(st, 17, c->def.offset_fraction);
          bind_vec(st, 18, c->def.offset_dir);
        }
      } else {
        bind_vec(st, 8, c->center_m);
        sqlite3_bind_double(st, 14, c->radius_m);
      }
    }
    return step_reset(st);
  }
  case PALP_DB_REC_FEEDBACK:
    st = w->st[ST_FEEDBACK];
    sqlite3_bind_int64(st, 1, sid);
    sqlite3_bind_int64(st, 2, r->u.fb.frame);
    sqlite3_bind_int(st, 3, r->u.fb.slot);
    bind_vec(st, 4, r->u.fb.f);
    return step_reset(st);
  case PALP_DB_REC_FRAME: {
    const palp_db_frame *f = &r->u.frame;
    st = w->st[ST_FRAME];
    sqlite3_bind_int64(st, 1, sid);
    sqlite3_bind_int64(st, 2, f->frame);
    sqlite3_bind_double(st, 3, f->sim_time_s);
    sqlite3_bind_double(st, 4, f->top_disp_m);
    sqlite3_bind_double(st, 5, f->max_disp_m);
    sqlite3_bind_double(st, 6, f->volume_m3);
    sqlite3_bind_double(st, 7, f->pressure_pa);
    sqlite3_bind_double(st, 8, f->contact_force_n);
    int64_t h;
    memcpy(&h, &f->state_hash, sizeof h); /* the uint64 bits, stored as SQLite's int64 */
    sqlite3_bind_int64(st, 9, h);
    return step_reset(st);
  }
  case PALP_DB_REC_MESH:
    st = w->st[ST_MESH];
    sqlite3_bind_int64(st, 1, sid);
    sqlite3_bind_int64(st, 2, r->u.mesh.frame);
    sqlite3_bind_int(st, 3, r->u.mesh.n);
  {
    /* in 64 bits; a blob over SQLite's own length limit (SQLITE_TOOBIG) refuses this record only */
    const int brc = sqlite3_bind_blob64(st, 4, r->u.mesh.xyz, (sqlite3_uint64)r->u.mesh.n * 3 * sizeof(double),
                                        SQLITE_STATIC);
    if (brc != SQLITE_OK) {
      sqlite3_reset(st);
      sqlite3_clear_bindings(st);
      return brc;
    }
    return step_reset(st);
  }
  case PALP_DB_REC_EVENT:
    st = w->st[ST_EVENT];
    if (sid) sqlite3_bind_int64(st, 1, sid);
    sqlite3_bind_double(st, 2, r->u.ev.wall);
    if (r->u.ev.frame >= 0) sqlite3_bind_int64(st, 3, r->u.ev.frame);
    bind_text(st, 4, palp_db_event_kind_name(r->u.ev.kind));
    bind_text(st, 5, r->u.ev.detail);
    sqlite3_bind_int64(st, 6, r->u.ev.count);
    return step_reset(st);
  case PALP_DB_REC_EXERCISE:
  case PALP_DB_REC_SESSION_SCENE:
    st = w->st[r->kind == PALP_DB_REC_EXERCISE ? ST_EXERCISE : ST_SCENE];
    sqlite3_bind_int64(st, 1, sid);
    bind_text(st, 2, r->u.ex.name);
    bind_text(st, 3, r->u.ex.json);
    return step_reset(st);
  case PALP_DB_REC_SESSION_PARAMS:
    st = w->st[ST_PARAMS];
    sqlite3_bind_int64(st, 1, sid);
    bind_text(st, 2, r->u.ex.json);
    return step_reset(st);
  case PALP_DB_REC_FINGER_SAMPLE: {
    const palp_db_finger_sample *fs = &r->u.fs.s;
    st = w->st[ST_FINGER_SAMPLE];
    sqlite3_bind_int64(st, 1, sid);
    sqlite3_bind_int64(st, 2, fs->frame);
    sqlite3_bind_int(st, 3, fs->slot);
    sqlite3_bind_double(st, 4, fs->sim_time_s);
    sqlite3_bind_double(st, 5, fs->radius_m);
    bind_vec(st, 6, fs->device_m);
    bind_vec(st, 9, fs->proxy_m);
    bind_vec(st, 12, fs->force_n);
    sqlite3_bind_int(st, 15, fs->in_contact ? 1 : 0);
    bind_vec(st, 16, fs->point_m);
    sqlite3_bind_double(st, 19, fs->area_m2);
    if (r->u.fs.tri) sqlite3_bind_blob(st, 20, r->u.fs.tri, fs->triangle_count * 4, SQLITE_STATIC);
    return step_reset(st);
  }
  case PALP_DB_REC_FINDING: {
    const palp_db_finding *f = &r->u.fd;
    st = w->st[ST_FINDING];
    sqlite3_bind_int64(st, 1, sid);
    sqlite3_bind_int64(st, 2, f->mark_id);
    bind_text(st, 3, f->op == PALP_DB_FINDING_MARK ? "mark" : "withdraw");
    sqlite3_bind_int64(st, 4, f->frame);
    sqlite3_bind_double(st, 5, f->sim_time_s);
    sqlite3_bind_double(st, 6, f->wall_unix_s);
    if (f->op == PALP_DB_FINDING_MARK) bind_vec(st, 7, f->point_m);
    return step_reset(st);
  }
  default: return SQLITE_MISUSE;
  }
}

/* One attempt at committing slots [tail, tail + n) (those `only` marks, when not NULL). On a disk error everything is rolled back
 * and *rc holds the error. Records refused by a constraint (a duplicate frame) are counted as
 * failed and skipped without failing the batch. Returns the number of records refused. */
static int attempt_batch(palp_db_writer *w, int tail, int n, int *rc_out, uint8_t *refused, const uint8_t *only) {
  w->touched_n = 0;
  int rc = sqlite3_exec(w->db, "BEGIN", NULL, NULL, NULL);
  int bad = 0;
  for (int i = 0; rc == SQLITE_OK && i < n; i++) {
    rec *r = &w->ring[(tail + i) % w->cap];
    refused[i] = 0;
    if (only && !only[i]) continue;
    int rr = write_rec(w, r);
    if (rr == SQLITE_DONE || rr == SQLITE_OK) continue;
    if (is_disk_error(rr)) {
      rc = rr;
      break;
    }
    refused[i] = 1; /* constraint or misuse: this record only */
    bad++;
  }
  if (rc == SQLITE_OK) rc = sqlite3_exec(w->db, "COMMIT", NULL, NULL, NULL);
  if (rc != SQLITE_OK) {
    int ec = sqlite3_extended_errcode(w->db);
    if (!sqlite3_get_autocommit(w->db)) sqlite3_exec(w->db, "ROLLBACK", NULL, NULL, NULL);
    for (int i = 0; i < w->touched_n; i++) w->ws[w->touched[i]].rowid = 0; /* rolled back */
    *rc_out = ec ? ec : rc;
    return 0;
  }
  *rc_out = SQLITE_OK;
  return bad;
}

/* The library's line on stderr for batches dropped after their retries: the first at once, then at
 * most one per DROP_SAY_INTERVAL_S with what was dropped since, and the rest as the writer closes. A
 * full disk fails a batch every ~0.4 s for as long as it stays full: a line each filled the journal
 * (~9,000 lines an hour); the server's own log says the loss at most once a minute (db/loss_watch.c). */
static void say_dropped(palp_db_writer *w, int n, int force) {
  w->drop_unsaid += n;
  w->drop_unsaid_batches += n > 0;
  const double now = mono_now();
  if (!w->drop_unsaid || (!force && w->drop_said && now - w->drop_said_at < DROP_SAY_INTERVAL_S)) return;
  char last[256];
  pthread_mutex_lock(&w->mu);
  memcpy(last, w->st_.last_error, sizeof last);
  pthread_mutex_unlock(&w->mu);
  if (w->drop_unsaid_batches == 1)
    fprintf(stderr, "palp_db: %s: dropped %lld records after %d attempts: %s\n", w->path, (long long)w->drop_unsaid,
            w->opts.retry_limit + 1, last);
  else
    fprintf(stderr, "palp_db: %s: dropped %lld records in %d batches, each after %d attempts, over %.0f s: %s\n",
            w->path, (long long)w->drop_unsaid, w->drop_unsaid_batches, w->opts.retry_limit + 1,
            w->drop_said ? now - w->drop_said_at : 0.0, last);
  w->drop_unsaid = 0;
  w->drop_unsaid_batches = 0;
  w->drop_said = 1;
  w->drop_said_at = now;
}

/* Per-session loss counts, so `palp-review show` and the grader can say a log is incomplete. Their own
 * transaction, every pass: an UPDATE in place still fits a full file (its cap, or a full disk) where
 * the loss event below, a new row, does not; tied to that event they went stale as the file filled,
 * and a score told the trainee fewer lost records than the review later showed. */
static void write_session_counts(palp_db_writer *w) {
  pthread_mutex_lock(&w->mu);
  const int64_t shed = w->st_.shed, failed = w->st_.failed;
  pthread_mutex_unlock(&w->mu);
  if (!w->counts_resync && shed == w->counts_shed && failed == w->counts_failed) return; /* the common pass */
  int rc = SQLITE_DONE, open = 0; /* the transaction begins at the first row that needs it */
  for (int s = 1; rc == SQLITE_DONE && s < w->ws_cap; s++) {
    wsess *ws = &w->ws[s];
    int64_t sh = 0, fl = 0;
    if (ws->rowid) losses_of(w, s, &sh, &fl);
    if (!ws->rowid || (sh == ws->shed_synced && fl == ws->failed_synced)) continue;
    if (!open) {
      if (sqlite3_exec(w->db, "BEGIN", NULL, NULL, NULL) != SQLITE_OK) {
        rc = SQLITE_ERROR;
        break;
      }
      open = 1;
    }
    sqlite3_stmt *st = w->st[ST_COUNTS];
    sqlite3_bind_int64(st, 1, ws->rowid);
    sqlite3_bind_int64(st, 2, sh);
    sqlite3_bind_int64(st, 3, fl);
    rc = step_reset(st);
    ws->shed_synced = sh; /* taken back below if the transaction does not commit */
    ws->failed_synced = fl;
  }
  if (rc == SQLITE_DONE && (!open || sqlite3_exec(w->db, "COMMIT", NULL, NULL, NULL) == SQLITE_OK)) {
    w->counts_shed = shed;
    w->counts_failed = failed;
    w->counts_resync = 0;
    return;
  }
  if (!sqlite3_get_autocommit(w->db)) sqlite3_exec(w->db, "ROLLBACK", NULL, NULL, NULL);
  for (int s = 1; s < w->ws_cap; s++) w->ws[s].shed_synced = -1; /* no count is -1: all go again next pass */
  w->counts_resync = 1;
}

/* Writes the writer's own events (shed, disk errors) and the sessions' loss counts. */
static void write_accounting(palp_db_writer *w, int force) {
  write_session_counts(w);
  pthread_mutex_lock(&w->mu);
  int64_t shed = w->st_.shed, failed = w->st_.failed;
  int64_t sk[PALP_DB_REC_KIND_COUNT];
  memcpy(sk, w->st_.shed_by_kind, sizeof sk);
  pthread_mutex_unlock(&w->mu);
  double now = mono_now();
  int shed_due = shed > w->shed_logged && (force || now - w->shed_logged_at >= SHED_LOG_INTERVAL_S);
  int failed_due = failed > w->failed_logged;
  if (!shed_due && !failed_due) return;
  if (sqlite3_exec(w->db, "BEGIN", NULL, NULL, NULL) != SQLITE_OK) return;
  char detail[256];
  sqlite3_stmt *st = w->st[ST_EVENT];
  int rc = SQLITE_DONE;
  if (shed_due) {
    int64_t d = shed - w->shed_logged;
    palp_db__fmt(detail, sizeof detail,
                 "log queue full: shed %lld records (total %lld: frame %lld, feedback %lld, contact %lld, "
                 "mesh %lld)",
                 (long long)d, (long long)shed, (long long)sk[PALP_DB_REC_FRAME],
                 (long long)sk[PALP_DB_REC_FEEDBACK], (long long)sk[PALP_DB_REC_CONTACT],
                 (long long)sk[PALP_DB_REC_MESH]);
    /* the line once per interval even while a full file refuses the event (which is retried each pass) */
    if (force || now - w->shed_said_at >= SHED_LOG_INTERVAL_S) {
      fprintf(stderr, "palp_db: %s: %s\n", w->path, detail);
      w->shed_said_at = now;
    }
    sqlite3_bind_double(st, 2, palp_db__now());
    bind_text(st, 4, "shed");
    bind_text(st, 5, detail);
    sqlite3_bind_int64(st, 6, d);
    rc = step_reset(st);
  }
  if (rc == SQLITE_DONE && failed_due) {
    int64_t d = failed - w->failed_logged;
    char last[256];
    pthread_mutex_lock(&w->mu);
    memcpy(last, w->st_.last_error, sizeof last);
    pthread_mutex_unlock(&w->mu);
    palp_db__fmt(detail, sizeof detail, "lost %lld records to disk errors (total %lld); last error: %s",
                 (long long)d, (long long)failed, last);
    sqlite3_bind_double(st, 2, palp_db__now());
    bind_text(st, 4, "disk_error");
    bind_text(st, 5, detail);
    sqlite3_bind_int64(st, 6, d);
    rc = step_reset(st);
  }
  if (rc == SQLITE_DONE && sqlite3_exec(w->db, "COMMIT", NULL, NULL, NULL) == SQLITE_OK) {
    if (shed_due) {
      w->shed_logged = shed;
      w->shed_logged_at = now;
    }
    if (failed_due) w->failed_logged = failed;
  } else if (!sqlite3_get_autocommit(w->db)) {
    sqlite3_exec(w->db, "ROLLBACK", NULL, NULL, NULL);
  }
}

static void retire(palp_db_writer *w, int n, int64_t written, int committed,
                   const int64_t *failed_by_kind) {
  size_t bytes = 0;
  for (int i = 0; i < n; i++) {
    rec *r = &w->ring[(w->tail + i) % w->cap];
    bytes += r->bytes;
    /* A batch dropped on a disk error before it reached a session's begin: keep the strings, or
     * every later record of that session is refused (session_rowid) even once space is back, and
     * the session never gets its row. Its row is then made by the session's next record written; the
     * begin record is still counted failed, with the batch. */
    if (r->kind == PALP_DB_REC_SESSION_BEGIN) (void)take_begin(w, r);
    rec_free(r);
  }
  pthread_mutex_lock(&w->mu);
  w->tail = (w->tail + n) % w->cap;
  w->count -= n;
  w->queue_bytes -= bytes;
  w->st_.written += written;
  for (int k = 0; k < PALP_DB_REC_KIND_COUNT; k++) {
    w->st_.failed_by_kind[k] += failed_by_kind[k];
    w->st_.failed += failed_by_kind[k];
  }
  w->st_.commits += committed;
  pthread_mutex_unlock(&w->mu);
}

/* The batch's failed records (every one, or those refused[i] marks) counted per kind (by_kind, for
 * retire) and per session, where any thread may read them (palp_db_writer_session_losses) and the
 * session's row gets them (write_session_counts). */
static void count_failed(palp_db_writer *w, int tail, int n, const uint8_t *refused, int64_t *by_kind) {
  pthread_mutex_lock(&w->mu);
  for (int i = 0; i < n; i++) {
    const rec *r = &w->ring[(tail + i) % w->cap];
    if (refused && !refused[i]) continue;
    by_kind[r->kind]++;
    if (r->s > 0 && r->s < w->ps_cap) w->ps[r->s].failed++;
  }
  pthread_mutex_unlock(&w->mu);
}

/* A batch dropped after its retries: its session ends, and the begins, events and findings that go
 * with them, get a transaction of their own (session 82). An end is an UPDATE in place, which still
 * fits a full file (its cap, or a full disk) where the batch's frames and meshes did not: dropped with
 * them, a session kept end_reason NULL for good and the reason it ended was lost. First the control
 * records together, in the batch's order; if they do not fit either, the ends alone (a begin's row
 * that is not in the file is still inserted first, by session_rowid). On return lost[i] marks the
 * batch's records not written; returns how many were written. */
static int64_t rescue_control(palp_db_writer *w, int tail, int n, uint8_t *lost) {
  uint8_t *pick = w->pick, *refused = w->scratch;
  int64_t saved = 0;
  for (int pass = 0; pass < 2; pass++) {
    int any = 0;
    for (int i = 0; i < n; i++) {
      const int k = w->ring[(tail + i) % w->cap].kind;
      pick[i] = k == PALP_DB_REC_SESSION_END || (pass == 0 && (k == PALP_DB_REC_SESSION_BEGIN ||
                                                                 k == PALP_DB_REC_EVENT || k == PALP_DB_REC_FINDING));
      any |= pick[i];
    }
    if (!any) break;
    int rc;
    (void)attempt_batch(w, tail, n, &rc, refused, pick);
    if (rc != SQLITE_OK) continue;
    for (int i = 0; i < n; i++)
      if (pick[i] && !refused[i]) {
        lost[i] = 0;
        saved++;
      }
    break;
  }
  return saved;
}

static void *worker(void *arg) {
  palp_db_writer *w = arg;
  uint8_t *refused = w->refused;
  pthread_mutex_lock(&w->mu);
  for (;;) {
    if (w->count == 0 && !w->stop) {
      struct timespec dl;
      abs_deadline(&dl, w->opts.commit_interval_s);
      pthread_cond_timedwait(&w->wake, &w->mu, &dl);
    } else if (w->count < w->opts.batch_records && !w->stop && !w->flush_waiters) {
      /* Records wait but not a batch's worth: give them one commit interval to gather. */
      struct timespec dl;
      abs_deadline(&dl, w->opts.commit_interval_s);
      pthread_cond_timedwait(&w->wake, &w->mu, &dl);
    }
    const int n = w->count < MAX_TXN_RECORDS ? w->count : MAX_TXN_RECORDS;
    int tail = w->tail;
    int stop = w->stop;
    pthread_mutex_unlock(&w->mu);

    if (n > 0) {
      int rc = SQLITE_OK, bad = 0;
      double backoff = w->opts.retry_backoff_s;
      for (int attempt = 0;; attempt++) {
        bad = attempt_batch(w, tail, n, &rc, refused, NULL);
        if (rc == SQLITE_OK) break;
        set_error(w, rc, "writing the session log");
        if (attempt >= w->opts.retry_limit) break;
        sleep_s(backoff);
        backoff = backoff * 2 < 1.0 ? backoff * 2 : 1.0;
      }
      int64_t failed_by_kind[PALP_DB_REC_KIND_COUNT] = {0};
      int64_t written = n;
      if (rc != SQLITE_OK) { /* dropped after retries: count every record, per kind and session */
        memset(refused, 1, (size_t)n); /* now: the records lost */
        written = rescue_control(w, tail, n, refused);
        count_failed(w, tail, n, refused, failed_by_kind);
        say_dropped(w, n - (int)written, 0);
      } else {
        written = n - bad;
        if (bad) count_failed(w, tail, n, refused, failed_by_kind);
        pthread_mutex_lock(&w->mu);
        w->st_.in_error = 0;
        pthread_mutex_unlock(&w->mu);
      }
      retire(w, n, written, rc == SQLITE_OK, failed_by_kind);
    }
    write_accounting(w, stop);
    /* Ended sessions no longer need their strings for lazy re-inserts, nor does a session refused at
     * its begin (dup: its reject event is in, every later record of it refused before its strings are
     * read); until session 90 a refused session's strings were kept until the writer closed, its end
     * never marked (found by review). Its def's pointers go with them. */
    for (int s = 1; s < w->ws_cap; s++) {
      wsess *ws = &w->ws[s];
      if (ws->blob && ((ws->ended && ws->rowid) || ws->dup)) {
        free(ws->blob);
        ws->blob = NULL;
        memset(&ws->def, 0, sizeof ws->def);
      }
    }

    struct timespec cpu;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu);
    pthread_mutex_lock(&w->mu);
    w->st_.worker_cpu_s = (double)cpu.tv_sec + 1e-9 * (double)cpu.tv_nsec;
    /* A waiter (the grader, palp_db_writer_flush) wakes only once the batch's losses are in its
     * sessions' rows too: woken at retire, a grader read a count the next pass then raised. */
    if (n > 0) {
      w->done_seq += n;
      pthread_cond_broadcast(&w->done);
    }
    if (w->stop && w->count == 0) break;
  }
  pthread_mutex_unlock(&w->mu);
  say_dropped(w, 0, 1);
  /* The last pass may have read stop = 0 and skipped the rate-limited shed event; a closing
   * writer always accounts for every record it shed. */
  write_accounting(w, 1);
  return NULL;
}

/* ---- open / close ---------------------------------------------------------------- */

int palp_db_writer_open(const char *path, const palp_db_writer_opts *opts, palp_db_writer **out,
                        char *err, size_t errlen) {
  if (!out) return PALP_EINVAL;
  *out = NULL;
  palp_db_writer_opts o = opts ? *opts : palp_db_writer_default_opts();
  if (o.queue_capacity <= 0 || o.batch_records <= 0 || !(o.commit_interval_s > 0) ||
      o.retry_limit < 0 || !(o.retry_backoff_s >= 0) || o.queue_max_bytes == 0) {
    palp_db__fmt(err, errlen, "palp_db_writer_open: invalid options");
    return PALP_EINVAL;
  }
  if (o.batch_records > o.queue_capacity) o.batch_records = o.queue_capacity;
  palp_db_writer *w = calloc(1, sizeof *w);
  if (!w) return PALP_ENOMEM;
  w->opts = o;
  palp_db__fmt(w->path, sizeof w->path, "%s", path ? path : "");
  w->data_cap = o.queue_capacity;
  w->cap = o.queue_capacity + CONTROL_RESERVE;
  w->ring = calloc((size_t)w->cap, sizeof *w->ring);
  w->next_session = 1;
  if (!w->ring) {
    free(w);
    return PALP_ENOMEM;
  }
  int rc = palp_db__connect(path, 1, o.app_version, &w->db, err, errlen);
  if (rc) {
    free(w->ring);
    free(w);
    return rc;
  }
  if (o.max_db_bytes > 0) {
    /* Cap the file so a runaway log cannot fill the lab machine's disk; the cap shows up as
     * SQLITE_FULL, handled like any full disk. */
    long long page = 4096;
    sqlite3_stmt *ps;
    if (sqlite3_prepare_v2(w->db, "PRAGMA page_size", -1, &ps, NULL) == SQLITE_OK) {
      if (sqlite3_step(ps) == SQLITE_ROW) page = sqlite3_column_int64(ps, 0);
      sqlite3_finalize(ps);
    }
    char sql[96];
    snprintf(sql, sizeof sql, "PRAGMA max_page_count = %lld", (o.max_db_bytes + page - 1) / page);
    sqlite3_exec(w->db, sql, NULL, NULL, NULL);
  }
  /* The worker inserts a session's row before any of its records (session_rowid), so the
   * per-row parent lookups of foreign-key enforcement buy nothing here and cost ~10% of the
   * insert rate; readers and annotate keep them on. */
  sqlite3_exec(w->db, "PRAGMA foreign_keys=OFF", NULL, NULL, NULL);
  for (int i = 0; i < ST_COUNT; i++) {
    if (sqlite3_prepare_v3(w->db, stmt_sql[i], -1, SQLITE_PREPARE_PERSISTENT, &w->st[i], NULL) != SQLITE_OK) {
      palp_db__fmt(err, errlen, "%s: preparing statements: %s", path, sqlite3_errmsg(w->db));
      for (int k = 0; k < i; k++) sqlite3_finalize(w->st[k]);
      sqlite3_close(w->db);
      free(w->ring);
      free(w);
      return PALP_DB_ESQL;
    }
  }
  sqlite3_stmt *st;
  if (sqlite3_prepare_v2(w->db, "INSERT INTO writer_run(app_version, pid, opened_unix_s) VALUES(?1,?2,?3)",
                         -1, &st, NULL) == SQLITE_OK) {
    bind_text(st, 1, o.app_version ? o.app_version : PALP_VERSION_STRING);
    sqlite3_bind_int64(st, 2, (int64_t)getpid());
    sqlite3_bind_double(st, 3, palp_db__now());
    if (sqlite3_step(st) == SQLITE_DONE) w->run_id = sqlite3_last_insert_rowid(w->db);
    sqlite3_finalize(st);
  }
  pthread_mutex_init(&w->mu, NULL);
  pthread_condattr_t ca;
  pthread_condattr_init(&ca);
  pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
  pthread_cond_init(&w->wake, &ca);
  pthread_cond_init(&w->done, &ca);
  pthread_condattr_destroy(&ca);
  if (pthread_create(&w->thread, NULL, worker, w) != 0) {
    palp_db__fmt(err, errlen, "%s: cannot start the writer thread", path);
    for (int k = 0; k < ST_COUNT; k++) sqlite3_finalize(w->st[k]);
    sqlite3_close(w->db);
    free(w->ring);
    free(w);
    return PALP_ENOMEM;
  }
  *out = w;
  return 0;
}

void palp_db_writer_close(palp_db_writer *w) {
  if (!w) return;
  pthread_mutex_lock(&w->mu);
  w->stop = 1;
  pthread_cond_signal(&w->wake);
  pthread_mutex_unlock(&w->mu);
  pthread_join(w->thread, NULL);
  /* The run's final counts, for whoever wonders later whether this log is complete. */
  if (w->run_id) {
    sqlite3_stmt *st;
    if (sqlite3_prepare_v2(w->db,
                           "UPDATE writer_run SET closed_unix_s = ?2, records_written = ?3, "
                           "records_shed = ?4, records_failed = ?5, last_error = ?6 WHERE id = ?1",
                           -1, &st, NULL) == SQLITE_OK) {
      sqlite3_bind_int64(st, 1, w->run_id);
      sqlite3_bind_double(st, 2, palp_db__now());
      sqlite3_bind_int64(st, 3, w->st_.written);
      sqlite3_bind_int64(st, 4, w->st_.shed);
      sqlite3_bind_int64(st, 5, w->st_.failed);
      if (w->st_.last_error[0]) bind_text(st, 6, w->st_.last_error);
      sqlite3_step(st);
      sqlite3_finalize(st);
    }
  }
  for (int k = 0; k < ST_COUNT; k++) sqlite3_finalize(w->st[k]);
  /* A clean close checkpoints and removes the -wal file, leaving one self-contained file. */
  sqlite3_close(w->db);
  for (int s = 0; s < w->ws_cap; s++) free(w->ws[s].blob);
  free(w->ws);
  free(w->ps);
  free(w->touched);
  free(w->ring);
  pthread_mutex_destroy(&w->mu);
  pthread_cond_destroy(&w->wake);
  pthread_cond_destroy(&w->done);
  free(w);
}
