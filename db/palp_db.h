/*
 * palp_db.h - the session log: SQLite storage of palpation sessions for instructor review.
 *
 * Two sides share one file:
 *  - the writer (server side): palp_db_writer_open() starts a worker thread that owns the only
 *    writing connection. The palp_db_log_*() calls copy a record into a bounded in-memory queue
 *    and return at once; they never block on disk and never take longer than a mutex hand-off and
 *    a memcpy (plus one malloc for records that carry a mesh or strings). A full queue returns
 *    PALP_EFULL and the record is counted as shed, never silently lost. The worker batches
 *    records into transactions (WAL, synchronous=NORMAL, prepared statements) and commits at least
 *    every opts.commit_interval_s. A disk error never reaches the caller: the worker backs off,
 *    retries the batch, then drops it and counts it as failed; palp_db_writer_stats_get() reports it.
 *  - readers (palp-review, tests): palp_db_open() works on a file the server is writing at the
 *    same time (WAL readers never block the writer; busy_timeout covers checkpoints).
 *
 * Units are SI everywhere ([m], [N], [Pa], [m^3], [s]); wall times are Unix seconds (UTC).
 *
 * REPLAY CONTRACT (what the server must do so that `palp-review replay` reproduces a session
 * bit for bit):
 *  1. Build the world with palp_db_world_from_scene(scene_json, dt_s, ...) (or the same steps:
 *     palp_scene_parse, world.dt = dt_s, palp_scene_create_world, remove the scene's own contacts
 *     0..contact_count-1) and log that same scene_json and dt_s in palp_db_log_session_begin().
 *  2. Step only with palp_world_step() (fixed dt), never palp_world_step_dt().
 *  3. Every world call that changes a contact is logged, in the order made, with frame =
 *     palp_world_frame(w) at the time of the call (i.e. before the step from frame f to f + 1):
 *       palp_world_add_contact(def) + palp_world_set_contact_force(id, F)
 *                                      -> op ADD,    kind FORCE,  slot = id, def, force F
 *       palp_world_set_contact_force(id, F)   -> op UPDATE, kind FORCE,  slot = id, force F
 *       palp_world_add_finger(c, r)           -> op ADD,    kind FINGER, slot = id, center c, radius r
 *       palp_world_set_finger(id, c, r)       -> op UPDATE, kind FINGER, slot = id, center c, radius r
 *       palp_world_remove_contact(id)         -> op REMOVE, slot = id
 *     After each applied input the world is woken (palp_world_wake); replay does the same. Waking
 *     is idempotent: one wake after several inputs at the same frame is equivalent. Apart from
 *     these inputs and their wakes, nothing may change the world between steps.
 *     Inputs that the server rejected (never applied) are not contact inputs: log them as events.
 *  4. After each palp_world_step(), log the frame summary filled by palp_db_frame_summarize(w, ...)
 *     (frame = the new frame number, state_hash = palp_world_hash(w)). Frames may be logged at a
 *     reduced rate; replay checks those that are logged.
 *  5. Feedback (palp_db_log_feedback) and meshes (palp_db_log_mesh) carry the frame after the step
 *     they were computed from.
 * The palp_db_world_* wrappers below do 3 and 4 for the caller.
 */
#ifndef PALP_DB_H
#define PALP_DB_H

#include <stddef.h>
#include <stdint.h>

#include "palp.h" /* PALP_E* codes, palp_vec3, palp_contact_def; header only */

#ifdef __cplusplus
extern "C" {
#endif

/* The schema version this library writes (= number of embedded migrations). */
int palp_db_schema_version(void);
/* Error text for PALP_E* codes and the palp_db-specific ones below. */
const char *palp_db_strerror(int err);
enum {
  PALP_DB_ENEWER = -100, /* the file's schema is newer than this palp */
  PALP_DB_ENOTFOUND = -101, /* no such session */
  PALP_DB_ESQL = -102, /* SQLite reported an error; see the message */
  PALP_DB_EAMBIGUOUS = -103, /* a session prefix matches several sessions */
  PALP_DB_EOLDER = -104, /* the file's schema is older, and palp_db_open_readonly would not copy it */
  PALP_DB_ECOPY = -105   /* reading the file needs a copy in memory larger than palp_db_open_readonly may make */
};

/* ---- records --------------------------------------------------------------- */
typedef enum palp_db_end_reason {
  PALP_DB_END_NORMAL = 1,
  PALP_DB_END_STATION_VANISHED = 2,
  PALP_DB_END_SERVER_SHUTDOWN = 3,
  PALP_DB_END_ERROR = 4
} palp_db_end_reason;
const char *palp_db_end_reason_name(palp_db_end_reason r); /* "normal", ... ; NULL if unknown */
/* How a session ended, from the reason palp-server gives as it closes it (server/server.c,
 * close_session: the session log's detail and the CLOSED state's reason): a reason naming a failure
 * ("model step failed: ...", "tick pool full", "server identity conflict") is error; a lost station
 * ("trainee station lost (...)", and its "...; not back within N s") station_vanished; "server
 * shutdown" server_shutdown; the rest ("trainee station left", "exercise time limit reached", NULL)
 * normal. One function for palp-server's own log (server/db_log.c) and palp-recorder's (from the
 * CLOSED state), so the two logs of one session cannot disagree (they did until 2026-12-07: the
 * recorder logged a failed model step as normal). Pure. */
palp_db_end_reason palp_db_end_reason_of(const char *reason);

typedef enum palp_db_contact_op {
  PALP_DB_OP_ADD = 1,
  PALP_DB_OP_UPDATE = 2,
  PALP_DB_OP_REMOVE = 3
} palp_db_contact_op;

typedef enum palp_db_contact_kind {
  PALP_DB_KIND_FORCE = 1, /* force-driven contact (palp_world_add_contact) */
  PALP_DB_KIND_FINGER = 2 /* position-driven finger (palp_world_add_finger) */
} palp_db_contact_kind;

typedef enum palp_db_event_kind {
  PALP_DB_EVENT_JOIN = 1,
  PALP_DB_EVENT_LEAVE = 2,
  PALP_DB_EVENT_REJECT = 3,    /* a sample rejected; detail says why */
  PALP_DB_EVENT_CLAMP = 4,     /* a sample clamped to a limit */
  PALP_DB_EVENT_OVERRUN = 5,   /* a tick overran its period */
  PALP_DB_EVENT_SHED = 6,      /* the log queue shed records (written by the writer itself) */
  PALP_DB_EVENT_DISK_ERROR = 7, /* the log lost records to a disk error (written by the writer) */
  PALP_DB_EVENT_INFO = 8,
  /* the model left its valid range (docs/model.md, "Valid range"): count = the physics steps
   * flagged since the last such event; detail (server/db_log.c, read back by palp_db_valid_range_parse):
   * "outside at N steps: depth N, skin N, limit N; deepest X mm beyond the validated depth so far",
   * and where the literal gel law left its momentum term out (since 2026-12-06) "outside at N steps:
   * depth N, skin N, limit N, gel N; deepest X mm beyond the validated depth so far; gel momentum
   * left out at N frames" */
  PALP_DB_EVENT_VALID_RANGE = 9,
  /* server-wide (no session): a peer DDS Security refused (idl/palp_dds_refusals.h); detail
   * "WHO: WHY (handshake|permissions)", count = the refusals this row stands for (the first,
   * then the repeats summed once a minute, as the server's log says them) */
  PALP_DB_EVENT_SECURITY_REFUSED = 10,
  /* an exercise session's debrief as it closed (docs/assessment.md, "Debrief"): what its trainee
   * was told, or that the debrief was not sent and why; detail written and read by db/debrief.c
   * (palp_db_debrief_format / _parse); one per session, by palp-server (since 2026-12-05, session
   * 59; its params_json then says "debrief_events": true) and by palp-recorder as it hears it */
  PALP_DB_EVENT_DEBRIEF = 11
} palp_db_event_kind;

/* A trainee's own leave and join in its session: its station lost and the session held
 * for it (palp-server's station_grace), then its return. The event detail is the station
 * id followed by one of these, written alike by palp-server and palp-recorder. */
#define PALP_DB_DETAIL_TRAINEE_HELD " (trainee, lost; session held)"
#define PALP_DB_DETAIL_TRAINEE_BACK " (trainee, back from a stall)"

#define PALP_DB_EVENT_KIND_COUNT 12
const char *palp_db_event_kind_name(palp_db_event_kind k); /* "join", ... */

typedef struct palp_db_session_def {
  const char *uid;          /* unique across server runs, e.g. "<run uuid>-<n>"; required */
  const char *trainee;
  const char *station;
  const char *phantom_id;
  const char *phantom_name;
  const char *scene_json;   /* the scene the world was built from; required for replay */
  const char *params_json;  /* server-side parameters (limits, ...), "{}" if none */
  double tick_hz;           /* [Hz] */
  double dt_s;              /* [s] fixed step of the world */
  double start_unix_s;      /* wall time [s]; 0 = now */
} palp_db_session_def;

typedef struct palp_db_contact {
  int64_t frame;       /* world frame at which the input took effect (before stepping from it) */
  double sim_time_s;   /* palp_world_time at that moment [s] */
  int slot;            /* contact id in the world */
  palp_db_contact_op op;
  palp_db_contact_kind kind;
  palp_contact_def def; /* force contacts: the contact definition; def.center is the centre [m] */
  palp_vec3 force_n;    /* force contacts: force vector [N] */
  palp_vec3 center_m;   /* fingers: sphere centre [m]; readers fill it for force contacts too */
  double radius_m;      /* fingers: sphere radius [m] */
} palp_db_contact;

typedef struct palp_db_frame {
  int64_t frame;          /* palp_world_frame after the step */
  double sim_time_s;      /* [s] */
  double top_disp_m;      /* |x - X| of the top vertex [m] */
  double max_disp_m;      /* max |x - X| over vertices [m] */
  double volume_m3;       /* [m^3] */
  double pressure_pa;     /* gauge gel pressure [Pa] */
  double contact_force_n; /* |sum of the contacts' feedback| [N] */
  uint64_t state_hash;    /* palp_world_hash */
} palp_db_frame;

/* ---- writer (server side) ----------------------------------------------------- */
typedef struct palp_db_writer palp_db_writer;
typedef int32_t palp_db_session; /* a writer-local handle for a logged session, > 0 */

typedef struct palp_db_writer_opts {
  int queue_capacity;       /* records, default 131072 (about 1.3 s of 32 sessions at 1 kHz x 3) */
  size_t queue_max_bytes;   /* bytes held by meshes and strings in the queue, default 64 MiB */
  int batch_records;        /* wake the worker when this many records wait, default 4096 */
  double commit_interval_s; /* commit at least this often while records arrive [s], default 0.1 */
  double retry_backoff_s;   /* first back-off after a disk error [s], doubles, default 0.05 */
  int retry_limit;          /* retries of a failed batch before dropping it, default 3 */
  int64_t max_db_bytes;     /* cap on the file size (PRAGMA max_page_count); 0 = no cap */
  const char *app_version;  /* recorded in meta and writer_run; default the palp version */
} palp_db_writer_opts;
palp_db_writer_opts palp_db_writer_default_opts(void);

/* Opens (creating or upgrading) the database and starts the worker. On failure returns a
 * negative code and writes a message into err (if errlen > 0). */
int palp_db_writer_open(const char *path, const palp_db_writer_opts *opts, palp_db_writer **out,
                        char *err, size_t errlen);
/* Flushes everything queued, records the run's counts and stops the worker. NULL is a no-op. */
void palp_db_writer_close(palp_db_writer *w);
/* Blocks until every record enqueued before the call is committed or dropped, or timeout_s
 * passes. For tests and shutdown, never for the tick loop. Returns 0 or PALP_EIO on timeout. */
int palp_db_writer_flush(palp_db_writer *w, double timeout_s);
/* The same for the records enqueued up to a mark taken earlier (palp_db_writer_mark: every record
 * enqueued before it), so that a waiter in short slices waits for those alone, not for what the
 * sessions went on logging meanwhile (server/grader.c). */
int64_t palp_db_writer_mark(palp_db_writer *w);
int palp_db_writer_wait(palp_db_writer *w, int64_t mark, double timeout_s);

/* The enqueue calls: never block on disk. Return 0, PALP_EFULL (queue full: shed and counted),
 * PALP_EINVAL (bad argument or unknown session) or PALP_ENOMEM. */
int palp_db_log_session_begin(palp_db_writer *w, const palp_db_session_def *def, palp_db_session *out);
int palp_db_log_contact(palp_db_writer *w, palp_db_session s, const palp_db_contact *c);
int palp_db_log_feedback(palp_db_writer *w, palp_db_session s, int64_t frame, int slot, palp_vec3 force_n);
int palp_db_log_frame(palp_db_writer *w, palp_db_session s, const palp_db_frame *f);
/* The most vertices a mesh may have (since session 82): its blob stays under INT_MAX bytes. */
#define PALP_DB_MESH_MAX_VERTICES (2147483647 / 24)
/* Copies vertex_count positions [m]; PALP_EINVAL beyond PALP_DB_MESH_MAX_VERTICES. */
int palp_db_log_mesh(palp_db_writer *w, palp_db_session s, int64_t frame, const palp_vec3 *pos,
                     int vertex_count);
/* s = 0 for a server-wide event; frame < 0 if none; detail may be NULL. */
int palp_db_log_event(palp_db_writer *w, palp_db_session s, palp_db_event_kind kind, int64_t frame,
                      const char *detail, int64_t count);
/* end_unix_s = 0 means now. After this the handle is invalid. */
int palp_db_log_session_end(palp_db_writer *w, palp_db_session s, palp_db_end_reason reason,
                            const char *detail, double end_unix_s);

/* ---- assessment records (schema 3, docs/assessment.md) ----------------------------- */
/* The position-driven fingertip after a physics step (palp_local_model and
 * palp_world_finger_contacts), what palp_assess needs to score a session. */
#define PALP_DB_MAX_SAMPLE_TRIANGLES 256
typedef struct palp_db_finger_sample {
  int64_t frame;       /* world frame after the step */
  double sim_time_s;   /* [s] */
  int slot;            /* the finger's contact id */
  double radius_m;     /* fingertip radius [m] */
  palp_vec3 device_m;  /* device point the step used [m] */
  palp_vec3 proxy_m;   /* fingertip centre on the surface [m] */
  palp_vec3 force_n;   /* of the phantom on the finger [N] */
  int in_contact;      /* 0 or 1 */
  palp_vec3 point_m;   /* contact point [m] */
  double area_m2;      /* contact footprint [m^2] */
  int triangle_count;  /* 0..PALP_DB_MAX_SAMPLE_TRIANGLES (the writer refuses more) */
  const int32_t *triangles; /* touched triangles (mesh indices); NULL/0: a disc of area_m2 */
} palp_db_finger_sample;

typedef enum palp_db_finding_op {
  PALP_DB_FINDING_MARK = 1,
  PALP_DB_FINDING_WITHDRAW = 2
} palp_db_finding_op;

typedef struct palp_db_finding {
  int64_t mark_id;       /* the station's number for the mark; a withdrawal names it */
  palp_db_finding_op op;
  int64_t frame;         /* world frame when the server received it */
  double sim_time_s;     /* world time then [s] */
  double wall_unix_s;    /* 0 = now (writer) */
  palp_vec3 point_m;     /* marks: where the lump is felt [m] */
} palp_db_finding;

/* The exercise a session runs (its file's text, hidden lesions included): log it right after
 * palp_db_log_session_begin. */
int palp_db_log_exercise(palp_db_writer *w, palp_db_session s, const char *exercise_name,
                         const char *exercise_json);
/* A session begun before its phantom was known (palp-recorder: the session's samples came before
 * its phantom's catalogue entry, and were not to be lost): its phantom's name and scene, once known.
 * Only a session logged with the empty scene "{}" is changed (session 65). */
int palp_db_log_session_scene(palp_db_writer *w, palp_db_session s, const char *phantom_name,
                              const char *scene_json);
/* The same session's params, rewritten with what came late (its phantom's force limit, the name of
 * the exercise its phantom runs): replaces params_json (session 65). */
int palp_db_log_session_params(palp_db_writer *w, palp_db_session s, const char *params_json);
/* Copies the triangles. PALP_EINVAL for more than PALP_DB_MAX_SAMPLE_TRIANGLES. */
int palp_db_log_finger_sample(palp_db_writer *w, palp_db_session s, const palp_db_finger_sample *fs);
int palp_db_log_finding(palp_db_writer *w, palp_db_session s, const palp_db_finding *f);

typedef enum palp_db_record_kind {
  PALP_DB_REC_SESSION_BEGIN = 0,
  PALP_DB_REC_SESSION_END,
  PALP_DB_REC_CONTACT,
  PALP_DB_REC_FEEDBACK,
  PALP_DB_REC_FRAME,
  PALP_DB_REC_MESH,
  PALP_DB_REC_EVENT,
  PALP_DB_REC_EXERCISE,      /* schema 3 */
  PALP_DB_REC_FINGER_SAMPLE, /* schema 3 */
  PALP_DB_REC_FINDING,       /* schema 3 */
  PALP_DB_REC_SESSION_SCENE, /* session 65: palp_db_log_session_scene */
  PALP_DB_REC_SESSION_PARAMS, /* session 65: palp_db_log_session_params */
  PALP_DB_REC_KIND_COUNT
} palp_db_record_kind;
const char *palp_db_record_kind_name(palp_db_record_kind k);

typedef struct palp_db_writer_stats {
  int64_t enqueued;     /* accepted into the queue */
  int64_t written;      /* committed to the file */
  int64_t shed;         /* refused because the queue was full */
  int64_t failed;       /* dropped after a disk error (or rejected by a constraint) */
  int64_t shed_by_kind[PALP_DB_REC_KIND_COUNT];
  int64_t failed_by_kind[PALP_DB_REC_KIND_COUNT];
  int queued;           /* in the queue now */
  int queue_high_water; /* most records ever queued at once */
  int queue_capacity;
  int64_t commits;      /* transactions committed */
  double worker_cpu_s;  /* CPU time the writer thread has used [s]: its load on the machine */
  int64_t disk_errors;  /* failed batch attempts */
  int in_error;         /* 1 while the last attempt failed */
  int last_error_code;  /* SQLite extended result code of the last error, 0 if none */
  char last_error[256]; /* text of the last error, "" if none */
} palp_db_writer_stats;
void palp_db_writer_stats_get(palp_db_writer *w, palp_db_writer_stats *out);
/* One logged session's losses so far: its records shed (queue full) and failed (disk errors), the
 * counts its session row gets (records_shed, records_failed). Any thread. 0, or PALP_EINVAL for a
 * handle this writer never gave (session 69: the server tells each session its own loss). */
int palp_db_writer_session_losses(palp_db_writer *w, palp_db_session s, int64_t *shed, int64_t *failed);

/* ---- a log's losses said as they happen (session 66, db/loss_watch.c) ---------------------
 * A full disk, or the file's cap (max_db_bytes), loses every batch from then on; the tick loop goes
 * on, so the lab must hear it from the program's log when it happens, with what to do. */
typedef struct palp_db_loss_watch {
  int64_t max_bytes;    /* the writer's max_db_bytes, 0 none: named in the advice */
  const char *cap_name; /* what sets it, for the advice: "session_log_max_mb", "--max-mb" */
  int64_t lost_said, said_ns, lost_seen, written_seen;
  int losing;           /* a loss said and no recovery said since */
} palp_db_loss_watch;
/* Looks at the writer's counters (call it every second or so, now_ns a monotonic clock): 1 and a
 * warning in line when records were lost since the last one said (at once, then at most once a
 * minute while losses go on: "session log: 49 records lost so far (0 shed: the queue was full; 49
 * failed: ...database or disk is full); the file reached its cap of 0.21 MB (session_log_max_mb)
 * or its disk is full: prune old sessions (palp-review prune), move the log away or raise the cap"); 2 and "session log: writing again (N
 * records lost in all)" on the first look after a loss with no new loss since the look before and
 * the writer writing (its last attempt a success; after sheds alone, records written since the look
 * before); 0 and "" otherwise. */
int palp_db_loss_watch_look(palp_db_loss_watch *w, const palp_db_writer_stats *st, int64_t now_ns, char *line,
                            size_t len);
/* How full the log at path is against max_bytes (its pages, as the cap counts them; 0: no cap,
 * returns 0 and ""), for the program's log as it opens the writer: "session log: 29 MB of its cap of
 * 16384 MB (CAP_NAME)"; returns 1 with "...: nearly full; ..." from 90%, 2 with "...: FULL, new
 * sessions will not be logged; ..." at the cap, 0 otherwise. */
int palp_db_cap_describe(const char *path, int64_t max_bytes, const char *cap_name, char *line, size_t len);

/* ---- frame summary (needs the palp model library: link palp_db_sim) -------------- */
/* Fills f from the world's current state with the definitions above. Server and replay both
 * call this, so the logged and replayed summaries are computed by the same code. */
void palp_db_frame_summarize(const palp_world *w, palp_db_frame *f);
/* Builds the world the replay contract names. Returns NULL and sets *err (and msg) on failure. */
palp_world *palp_db_world_from_scene(const char *scene_json, double dt_s, int *err, char *msg,
                                     size_t msglen);

/* Logged world calls (palp_db_sim): each makes the palp_world call and, when it succeeds, logs
 * it as the replay contract says, so a server that changes contacts and steps only through these
 * is replayable by construction. w may be NULL (logging off): then they are the plain world calls.
 * They return what the world call returns; a full log queue is counted by the writer, never
 * reported here, so the simulation does not depend on the disk. */
int palp_db_world_add_contact(palp_db_writer *w, palp_db_session s, palp_world *world,
                              const palp_contact_def *def, palp_vec3 force_n);
int palp_db_world_set_contact_force(palp_db_writer *w, palp_db_session s, palp_world *world, int id,
                                    palp_vec3 force_n);
int palp_db_world_add_finger(palp_db_writer *w, palp_db_session s, palp_world *world, palp_vec3 center_m,
                             double radius_m);
int palp_db_world_set_finger(palp_db_writer *w, palp_db_session s, palp_world *world, int id,
                             palp_vec3 center_m, double radius_m);
/* kind: what the caller is removing (the world does not say); readers show it. */
int palp_db_world_remove_contact(palp_db_writer *w, palp_db_session s, palp_world *world, int id,
                                 palp_db_contact_kind kind);
/* palp_world_step, then the frame summary is logged; *out (may be NULL) receives it. */
int palp_db_world_step(palp_db_writer *w, palp_db_session s, palp_world *world, palp_db_frame *out);

/* ---- readers ---------------------------------------------------------------- */
typedef struct palp_db palp_db;

/* Opens read-write: for annotating and deleting, and for the server's own reads of its log
 * (palp_db_open_readonly reads without ever writing). A file with an older schema is upgraded in a
 * transaction;
 * one with a newer schema is refused (PALP_DB_ENEWER) with a message saying so. create = 0
 * refuses a missing file, and refuses an empty or foreign file (no palp schema) after
 * looking at it read-only, so it is left untouched. */
int palp_db_open(const char *path, int create, palp_db **out, char *err, size_t errlen);
/* Opens an existing log for reading only (palp-review's list, show, export, ...): the connection is
 * SQLITE_OPEN_READONLY, so reading never changes the file, whether it is a copy from an older palp,
 * on read-only media, or being written by a live server. A file with the current schema is read in
 * place. One with an older schema is copied into memory (the SQLite backup API) and the copy is
 * upgraded, when the file (with its -wal) is at most copy_max_bytes; a larger one is refused
 * (PALP_DB_EOLDER, the message naming `palp-review migrate`), as are newer, empty, foreign and
 * missing files. A WAL-mode log without a -wal file (or with an empty one) in a directory this user
 * cannot write (where SQLite cannot make the -wal and -shm it reads through), or that this user may
 * not write in a directory it may (where it could not remove them after), is opened immutable (with
 * no -wal, no writer has it open) and copied into memory at once (no lock keeps a writer that opens
 * it later from checkpointing into it under the reads), within copy_max_bytes too (else
 * PALP_DB_ECOPY); if the file changed while it was copied, PALP_EIO ("read it again"). The -wal and
 * -shm SQLite makes beside a log that had no -wal are removed after the read (palp_db_close), unless
 * another connection has the file open. Writing through the handle fails (SQLITE_READONLY; a copy is
 * query_only, as a write to it would be lost at close). */
int palp_db_open_readonly(const char *path, long long copy_max_bytes, palp_db **out, char *err, size_t errlen);
/* The file's schema version when db reads an upgraded in-memory copy of it (palp_db_open_readonly
 * on an older file), else 0. */
int palp_db_copied_from_version(palp_db *db);
/* 1 when db reads an in-memory copy of a file opened immutable (palp_db_open_readonly: no -wal and a
 * directory this user cannot write), else 0. */
int palp_db_copied_unlocked(palp_db *db);
/* The schema version of the log at path, looked at read-only (as palp_db_open_readonly checks it);
 * 0, or the codes palp_db_open_readonly returns for a file it refuses. */
int palp_db_peek_version(const char *path, int *version, char *err, size_t errlen);
/* The log's bytes on disk: the file and its -wal (0 for what does not exist). */
long long palp_db_file_bytes(const char *path);
void palp_db_close(palp_db *db);
/* The file's schema version (PRAGMA user_version). */
int palp_db_file_version(palp_db *db);
/* The underlying connection, for ad-hoc queries (palp-review, tests). */
struct sqlite3 *palp_db_handle(palp_db *db);
const char *palp_db_errmsg(palp_db *db);
/* SQLite's words for a result code, e.g. a writer's last_error_code: "database or disk is full". */
const char *palp_db_error_text(int code);

typedef struct palp_db_session_info {
  int64_t id;
  char uid[128];
  char trainee[128];
  char station[128];
  char phantom_id[128];
  char phantom_name[128];
  double tick_hz, dt_s;
  double start_unix_s;
  double end_unix_s;   /* 0 if not ended */
  char end_reason[32]; /* "" if not ended */
  char end_detail[256];
  int64_t records_shed, records_failed;
  int64_t frames, contact_inputs, meshes, events, notes;
  double sim_duration_s; /* last logged frame's sim time */
  /* When palp-review prune deleted its frames, inputs, meshes and finger samples (0: it has not). Read
   * since session 81: a pruned session looked like a complete session of 0 frames. */
  double pruned_unix_s;
} palp_db_session_info;

typedef struct palp_db_filter {
  const char *trainee;    /* exact match, NULL = any */
  const char *phantom;    /* matches phantom_id or phantom_name, NULL = any */
  double since_unix_s;    /* start >= since, when has_since */
  double until_unix_s;    /* start < until, when has_until */
  /* A bound applies when its flag is set, whatever its value (since session 81: a bound <= 0 meant
   * none, so "list --until 1970-01-01" listed every session and a prune cutoff before 1970, from
   * --older-than 30000, pruned every ended session). */
  int has_since, has_until;
} palp_db_filter;

/* What a log can be trusted for, from the data itself and not only the writer's counters
 * (a writer whose disk is full cannot record that it lost records):
 *  - cut short: no end was logged (the server was killed, or still writes); the data
 *    ends at last_frame / last_sim_time_s / last_event_unix_s;
 *  - damaged: records shed or failed by the writer's count, or frames missing from the
 *    sequence the writer logs (every frame_step-th frame, frame_step the commonest gap);
 *  - complete: neither. */
typedef struct palp_db_log_health {
  int ended;
  int64_t frames, first_frame, last_frame, frame_step, frames_expected, frames_missing;
  double last_sim_time_s;
  double last_event_unix_s; /* 0: no event */
  int64_t records_shed, records_failed;
  int cut_short, damaged, complete;
  int pruned; /* its frames deleted by a prune: never complete, what they held cannot be judged */
} palp_db_log_health;
int palp_db_log_health_get(palp_db *db, const palp_db_session_info *s, palp_db_log_health *out);
/* One line for people, e.g. "complete: ended normal; 184 of 184 frames, nothing shed or lost". */
void palp_db_log_health_describe(const palp_db_log_health *h, char *buf, size_t len);

/* Largest mesh a reader accepts from a file (the model's meshes: 338..5,000 vertices). */
#define PALP_DB_MAX_VERTICES 1000000
/* Replay refuses a jump of more than this much simulated time between two logged frames
 * (the writer logs a frame at least every 0.01 s): a frame number of 10^12 is damage,
 * not a session to step through for years. */
#define PALP_DB_MAX_FRAME_GAP_S 60.0
/* ... and of more than this many steps whatever the logged dt_s (session 81, found by review: the gap's
 * steps were 60 s / dt_s, so a dt_s of 1e-7 let one frame numbered 5e8 step for hours): 60 s at the
 * fastest rate a server steps (10 kHz, server/config.c). */
#define PALP_DB_MAX_FRAME_GAP_STEPS 600000
/* The step a server can have logged: 1 / (10 kHz) .. PALP_WORLD_MAX_DT; replay refuses another. */
#define PALP_DB_MIN_DT_S 1e-4

/* Lists matching sessions, oldest first; *out is malloc'd (free()). */
int palp_db_list_sessions(palp_db *db, const palp_db_filter *f, palp_db_session_info **out, int *count);

/* The peers DDS Security refused between f->since_unix_s and f->until_unix_s (each if its has_ flag),
 * from the server-wide security_refused events: one row per detail, refusals summed, most
 * first. Freed by the caller (free). */
typedef struct palp_db_refused {
  char detail[256];            /* "trainee/mallory: certificate revoked (handshake)" */
  int64_t count;
  double first_unix_s, last_unix_s;
} palp_db_refused;
int palp_db_list_refused(palp_db *db, const palp_db_filter *f, palp_db_refused **out, int *count);
/* Finds a session by its uid or a unique prefix of it. */
int palp_db_find_session(palp_db *db, const char *uid_or_prefix, palp_db_session_info *out);
/* Finds a session by exactly its uid, never a prefix ("run7-1" is not "run7-10"): 0, PALP_DB_ENOTFOUND,
 * PALP_EINVAL or PALP_DB_ESQL. */
int palp_db_find_session_uid(palp_db *db, const char *uid, palp_db_session_info *out);
/* What a SESSION argument that names no session exactly may mean, newest first, at most max in
 * out[] and the number of all of them in *total: the sessions whose uid starts with it, or, with
 * by_number and a whole number N, the sessions the stations called "session N" (uid "<run>-N",
 * docs/naming.md: one number per server run). 0, PALP_EINVAL or PALP_DB_ESQL. */
int palp_db_session_candidates(palp_db *db, const char *arg, int by_number, palp_db_session_info *out, int max,
                               int *total);
/* Session's scene and params JSON; malloc'd strings (free()). */
int palp_db_session_json(palp_db *db, int64_t session_id, char **scene_json, char **params_json);

/* Iterators in frame order (contacts in the order applied). A callback returning non-zero stops
 * the walk and its value is returned. */
typedef int (*palp_db_contact_fn)(void *user, const palp_db_contact *c);
typedef int (*palp_db_frame_fn)(void *user, const palp_db_frame *f);
typedef int (*palp_db_feedback_fn)(void *user, int64_t frame, int slot, palp_vec3 force_n);
typedef int (*palp_db_mesh_fn)(void *user, int64_t frame, const palp_vec3 *pos, int vertex_count);
typedef int (*palp_db_event_fn)(void *user, double wall_unix_s, int64_t frame, const char *kind,
                                const char *detail, int64_t count);
int palp_db_each_contact(palp_db *db, int64_t session_id, palp_db_contact_fn fn, void *user);
int palp_db_each_frame(palp_db *db, int64_t session_id, palp_db_frame_fn fn, void *user);
int palp_db_each_feedback(palp_db *db, int64_t session_id, palp_db_feedback_fn fn, void *user);
int palp_db_each_mesh(palp_db *db, int64_t session_id, palp_db_mesh_fn fn, void *user);
int palp_db_each_event(palp_db *db, int64_t session_id, palp_db_event_fn fn, void *user);
/* Notes are read by palp-review's review_each_note (client/review/grades.c), which gives each note's
 * grade with its score and level; palp_db_each_note, which gave only the free-text grade of before
 * schema 3, was removed on 2026-12-05 after the report and the JSON export had shown no structured
 * grade through it. */

/* ---- the model's valid range (PALP_DB_EVENT_VALID_RANGE, db/valid_range.c) -------------- */
/* What the phantom's model met outside its valid range over some physics steps (docs/model.md,
 * "Valid range"), split the three ways the station splits the time it rendered from flagged
 * local models (client/haptic_loop.c), so the station, the log and the review name the same
 * things. A step may count in several of the three; steps counts it once. */
typedef struct palp_db_valid_range {
  int64_t steps;       /* steps with any of the three */
  int64_t depth_steps; /* a fingertip deeper than the parameters were validated against the FE there
                          (LM_BEYOND_VALIDATED) */
  int64_t skin_steps;  /* a link strained past 50%, or a hinge beyond its linear range (LM_LARGE_STRAIN) */
  int64_t limit_steps; /* pressed onto the base, speeds capped, or the finger's solve unconverged
                          (LM_BASE_CONTACT, LM_CLAMPED_STEP, LM_UNSOLVED) */
  double deepest_m;    /* the largest excess of a fingertip's indentation over its validated depth,
                          over the session so far [m] */
  /* Since 2026-12-06 (session 76): the literal gel law outside its stable range, the server's own
   * (no wire bit: the stations are not told, so the review's time outside may exceed theirs) */
  int64_t gel_steps;   /* steps of which a frame (the step or a half) left the law's momentum term
                          out (palp_world_health.gel_momentum_dropped rose) */
  int64_t gel_frames;  /* those frames (>= gel_steps; 0 with it) */
} palp_db_valid_range;
/* The event's detail; returns what snprintf returns. Without gel steps it is the detail written
 * before 2026-12-06, word for word (an earlier palp-review reads it); with them, the head gains
 * ", gel N" and the tail "; gel momentum left out at N frames". */
int palp_db_valid_range_format(const palp_db_valid_range *r, char *buf, size_t len);
/* Reads a detail back; count is the event's count, which must equal its steps. PALP_EINVAL
 * for a detail this format did not write or whose numbers contradict each other. */
int palp_db_valid_range_parse(const char *detail, int64_t count, palp_db_valid_range *out);
/* The session's valid_range events summed (deepest: the largest); *events = how many, and
 * *unreadable = how many did not parse (their count is still added to steps). */
int palp_db_session_valid_range(palp_db *db, int64_t session_id, palp_db_valid_range *sum, int64_t *events,
                                int64_t *unreadable);

/* ---- an exercise session's debrief (PALP_DB_EVENT_DEBRIEF, db/debrief.c) ---------------- */
/* What the server told the trainee as her exercise session closed, as much as the exercise's
 * "debrief" key allowed (palp_debrief_level, src/palp_assess.h; the wire's palp_Debrief); the
 * lesions' places are not repeated: the session's exercise, logged with it, has them in order. */
#define PALP_DB_DEBRIEF_MAX_LESIONS 8 /* = PALP_MAX_LESIONS, the wire's sequence bound */
typedef enum palp_db_debrief_level {
  PALP_DB_DEBRIEF_NONE = 0,   /* nothing of the lesions, not even how many */
  PALP_DB_DEBRIEF_COUNT = 1,  /* how many were found, how many marks were near none */
  PALP_DB_DEBRIEF_LESIONS = 2 /* also each lesion, found (by which mark) or missed */
} palp_db_debrief_level;
typedef struct palp_db_debrief {
  int sent;                   /* 1: written to the trainee's station; 0: not (why says why) */
  palp_db_debrief_level level;
  int lesions, found;         /* count and lesions levels (0 at none) */
  int marks;                  /* marks standing */
  int false_marks, duplicates;/* count and lesions levels (0 at none) */
  int listed;                 /* lesions level: = lesions, else 0 */
  uint32_t found_by[PALP_DB_DEBRIEF_MAX_LESIONS]; /* per listed lesion, in the exercise's order:
                                                      the mark that found it, 0 missed */
  char why[160];              /* not sent: why ("" when sent) */
} palp_db_debrief;
/* "told at level none: marks standing M" |
 * "told at level count: found F of L lesions; marks standing M, near no lesion X, duplicates D" |
 * the same at level lesions followed by "; found by marks B1 B2 ..." (one per lesion, 0 missed) |
 * "not sent (level LEVEL): WHY". Returns what snprintf returns; PALP_EINVAL for a debrief that
 * contradicts itself (the checks of palp_db_debrief_parse). */
int palp_db_debrief_format(const palp_db_debrief *d, char *buf, size_t len);
/* Reads a detail back; PALP_EINVAL for one this format did not write or whose numbers contradict
 * each other (found above lesions, more found_by than lesions, found not the count of found_by). */
int palp_db_debrief_parse(const char *detail, palp_db_debrief *out);
/* The session's debrief event: 1 and *out, 0 when none is logged, PALP_EINVAL when its detail
 * does not parse (*out then zeroed), < 0 on a database error. The last one if several. */
int palp_db_session_debrief(palp_db *db, int64_t session_id, palp_db_debrief *out);
const char *palp_db_debrief_level_name(palp_db_debrief_level l); /* "none", "count", "lesions"; NULL */

/* Schema 3 (assessment). The session's exercise: name (up to namelen) and its JSON
 * (malloc'd, free()); PALP_DB_ENOTFOUND when the session ran none. */
int palp_db_session_exercise(palp_db *db, int64_t session_id, char *name, size_t namelen,
                             char **exercise_json);
/* Finger samples in (frame, slot) order; s->triangles is valid during the callback only. */
typedef int (*palp_db_finger_sample_fn)(void *user, const palp_db_finger_sample *s);
int palp_db_each_finger_sample(palp_db *db, int64_t session_id, palp_db_finger_sample_fn fn, void *user);
/* Findings in the order received. */
typedef int (*palp_db_finding_fn)(void *user, const palp_db_finding *f);
int palp_db_each_finding(palp_db *db, int64_t session_id, palp_db_finding_fn fn, void *user);

/* Adds an instructor note; grade may be NULL. */
int palp_db_add_note(palp_db *db, int64_t session_id, const char *author, const char *text,
                     const char *grade);

#ifdef __cplusplus
}
#endif
#endif
