/* server.c - the classroom server's DDS front end and session bookkeeping. */
#include "server.h"
#include "identity.h"
#include "server_identity.h"

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>
#include <unistd.h>

#include <dds/dds.h>

#include "palp.h"
#include "palp_assess.h" /* palp_pattern_name */
#include "palp_input_file.h"
#include "palp_rng.h"
#include "identity.h"
#include "server_identity.h"
#include "palp_dds.h"
#include "admission.h"
#include "retire.h"
#include "palp_dds_reaper.h"
#include "palp_dds_refusals.h"
#include "palp_dds_strangers.h"
#include "palp_dds_security.h"
#include "palp_dds_strays.h"
#include "session.h"
#include "ticker.h"

/* Closed sessions kept for the summary table (palp_srv_print_summary); older ones
 * are counted (sessions_forgotten), so a server that runs for a term stays bounded. */
#define CLOSED_KEEP 1024

/* A station holds a slot only while it is in an open session: a refused join
 * takes none, and a session's close frees its members' slots. So the slots
 * (max_sessions x (1 + max_viewers)) cannot run out before the sessions do, and
 * no peer can lock real stations out by joining without finishing. */
typedef struct station {
  int in_use;
  char id[64];
  int role;            /* palp_Role */
  uint32_t session_id; /* the session it is in */
  uint64_t writer;     /* publication handle of its request writer; secured, only its
                          disappearance (not another identity disposing this station's
                          key) means the station is gone */
  int want_feedback, want_deformation;
  uint32_t request_seq; /* of the JOIN it was accepted with: the same request again is answered, not redone */
  int keyed;           /* last request came on palp_station_request */
  dds_instance_handle_t ih; /* its instance there (keyed by station_key) */
  /* Its keyed instance was disposed while its writer was matched: a goodbye, unless the writer's
   * liveliness turns out lapsed by gone_due_ns (decide_gone_stations); 0: nothing pending. */
  int64_t gone_due_ns;
  dds_instance_handle_t gone_writer;
  /* The participant of its request writer (a visual station's, looked up as it JOINed): unsecured, a
   * visual station's participant may write the session's findings (palp-web writes a bound trainee
   * page's marks so; docs/web.md). 0: not known (gone before it was looked up, or not asked). */
  int participant_known;
  dds_guid_t participant;
} station;

/* How long after a keyed station's dispose the server looks whether its writer's liveliness
 * lapsed: Cyclone calls the liveliness listener right after it unregisters (autodisposes) a
 * lapsed writer's instances. Decided on a later pass of the main loop, never slept on. */
#define GONE_GRACE_NS 50000000LL

/* Request samples taken per topic per pass of the main loop (as findings are): a flood cannot
 * hold the main thread; the rest wait in the reader, whose read condition wakes the next pass. */
#define REQUESTS_PER_PASS 64

/* How long past its first due time the writers sweep (sweep_gone_writers) waits for a pass that drains the
 * request reader: traffic of REQUESTS_PER_PASS or more a pass drains none, and until 2026-12-06 the
 * sweep then never ran (no loss found, no admission released for as long as the traffic lasted). Past
 * it a station whose LEAVE is still queued is said lost rather than left: the lesser harm. */
#define SWEEP_OVERDUE_NS 1000000000LL

#define SCORES_KEPT 64 /* palp_session_score instances kept for late dashboards */
#define TOLD_KEPT 16   /* palp_debrief_score: practice sessions awaiting their score, writers kept */

/* A practice session whose trainee is told her score when the grader has it (palp_debrief_score):
 * its partition outlives the session's publisher, which its close deleted. */
typedef struct score_to_tell {
  uint32_t session_id; /* 0: free */
  char partition[64];
} score_to_tell;

typedef struct guard_counts {
  uint64_t joins_refused_rate, joins_refused_writer, joins_refused_viewers, joins_refused_other;
} guard_counts;

typedef struct closed_session {
  palp_srv_session_summary sum;
  char phantom_name[64], station[64], name[64], partition[64], reason[128];
  int open; /* still open at print time (filled from a live session) */
  uint32_t request_seq; /* of the JOIN that opened it (trainee_request_seq) */
} closed_session;

struct palp_srv {
  palp_srv_config cfg;
  const palp_srv_events *events;
  int verbose;
  palp_log *log;
  palp_srv_identity *identity;
  char server_id[64];
  int64_t start_ns;

  palp_srv_phantom phantom[PALP_SRV_MAX_PHANTOMS];
  int phantom_count;

  dds_entity_t pp;
  /* Deletes a closed session's publisher (and a rotated score's) beside the main loop (palp_dds_reaper.h);
   * close_longest_s: the longest the main loop spent on one closing session's entities and world [s] */
  palp_dds_reaper *reaper;
  double close_longest_s;
  dds_entity_t topic[PALP_TOPIC_COUNT];
  dds_entity_t station_request_r, station_request_rc;
  /* palp_station_request writers whose liveliness lapsed (Cyclone's listener thread
   * -> main thread): tells a crash from a dispose, which Cyclone reports alike. */
  pthread_mutex_t lost_mu;
  dds_instance_handle_t lost[64];
  unsigned lost_n;
  dds_entity_t catalogue_w, request_r, reply_w, state_w, status_w, status_r, guard_w;
  dds_entity_t exercise_w; /* palp_exercise: what a trainee may know of each exercise */
  /* palp_session_exercise: each exercise session's exercise with its lesions, for instructors'
   * recorders (session 60); 0: not written (config "session_exercise", or permissions before it) */
  dds_entity_t session_exercise_w;
  /* palp_session_score (session 63): each closed exercise session's score, for the instructors;
   * written when palp_session_exercise is (it tells the answers); 0: not written. The newest
   * SCORES_KEPT instances are kept for a dashboard opened later, older ones unregistered. */
  dds_entity_t session_score_w;
  uint32_t scored[SCORES_KEPT];
  int scored_next;
  /* palp_session_closed (session 69): who each closed session was, for a dashboard begun after it
   * (every server, secured or not: the names are palp_session_state's); the newest SCORES_KEPT kept,
   * as the scores are. 0: not written (permissions that predate it). */
  dds_entity_t session_closed_w;
  uint32_t closed_sent[SCORES_KEPT];
  int closed_sent_next;
  /* palp_debrief_score (session 64): practice sessions (debrief DEBRIEF_LESIONS) waiting for their
   * score, and the publishers (one per session partition) that told the last TOLD_KEPT: the oldest
   * is deleted as a new one is made, so a station has had 16 scores' time to take hers. */
  score_to_tell to_tell[TOLD_KEPT];
  int to_tell_next;
  dds_entity_t told_pub[TOLD_KEPT];
  int told_next;
  int stopping; /* closing every session as the server stops: none of them will be scored live */
  dds_entity_t request_topic; /* the server's own entity: it carries the admission filter */
  /* Disposes of request keys no admitted request holds (never written, or written past
   * stations_per_writer and refused; each an instance the request reader keeps while its writer lives;
   * unbounded: docs/robustness.md): counted, and the writer named (note_request_stray). */
  atomic_ullong request_strays; /* read by any thread (palp_srv_request_strays) */
  uint64_t stray_writer_count;
  dds_instance_handle_t stray_writer;
  int64_t stray_said_ns;
  int warned_other_server;
  dds_entity_t request_rc, stop_gc, waitset;
  /* A palp_session_request writer went away (the reader's matched count fell): when to look which
   * stations' writers are gone (sweep_gone_writers); 0: nothing pending. */
  int64_t writers_sweep_ns;
  int64_t writers_sweep_first_ns; /* its due time as first set: later unmatches move it no further than
                                     SWEEP_OVERDUE_NS past this */
  /* [main thread] The matched writers a sweep reads once (matched_set); grown as needed, kept. */
  dds_instance_handle_t *matched;
  size_t matched_cap;

  palp_srv_ticker *ticker;
  palp_srv_session **sessions; /* open sessions, [cfg.max_sessions] */
  atomic_int session_count; /* changed by the server's thread; read by any (palp_srv_open_sessions) */
  uint32_t next_session_id;
  uint32_t session_local_max; /* local ids 1..this, then 1 again (def.session_local_max) */
  uint64_t placement_key; /* this run's secret for random exercises' draws (placement_seed) */
  uint64_t sessions_total;
  uint64_t rejected_closed[PALP_SRV_REJ_COUNT]; /* counters of sessions already closed */

  station *stations;
  int station_slots;
  palp_srv_admission *admission;
  /* palp_station_request's own (session 75): until then a plain peer could keep 10^6 station keys
   * there for as long as its writer lived. Its topic entity carries the filter. */
  palp_srv_admission *station_admission;
  dds_entity_t station_request_topic;
  uint64_t filtered_said; /* request keys refused by either filter, as last logged */
  int64_t filtered_said_ns;
  palp_srv_retire retire;
  guard_counts guard;
  palp_dds_log_limit dds_log;
  int dds_log_installed;
  palp_dds_refusals refusals; /* peers DDS Security refused (palp_dds_refusals.h) */
  int refusals_ready; /* initialised: a server that failed before it is destroyed without them */
  palp_dds_strangers strangers; /* plain participants on the secured domain (palp_dds_strangers.h) */
  int strangers_ready;

  closed_session *closed; /* ring of the last CLOSED_KEEP */
  int closed_count, closed_head;
  uint64_t sessions_forgotten;

  palp_SessionLoad *loads;
  atomic_int stop;

  /* DDS Security (docs/security.md); sec.kind PALP_DDS_ID_NONE: plain DDS */
  palp_dds_security sec;
  dds_entity_t request_sub;
  atomic_ullong refused_requests; /* not from the station's own identity, or not allowed */
  int64_t refused_log_ns;     /* last log line about them */
  uint64_t refused_unlogged;
};

static int secured(const palp_srv *srv) { return srv->sec.kind != PALP_DDS_ID_NONE; }

/* Cyclone's threads: a line about a refused peer was logged; the session log keeps it too. */
static void record_refusal(void *ctx, const palp_dds_refusal *r, uint64_t count) {
  const palp_srv *srv = ctx;
  if (!srv->events || !srv->events->security_refused) return;
  char detail[PALP_DDS_REFUSAL_WHO + PALP_DDS_REFUSAL_WHY + 32];
  snprintf(detail, sizeof detail, "%s: %s (%s)", r->who, r->why, palp_dds_refusal_kind_name(r->kind));
  srv->events->security_refused(srv->events->ctx, detail, count);
}

static int fail(char *err, size_t errlen, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err, errlen, fmt, ap);
  va_end(ap);
  return 0;
}

static void logf_(const palp_srv *srv, const char *fmt, ...) {
  if (!srv->verbose && !palp_log_enabled(srv->log, PALP_LOG_DEBUG)) return;
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  palp_logf(srv->log, srv->verbose ? PALP_LOG_INFO : PALP_LOG_DEBUG, "%s", msg);
}

/* A request refused for its identity: counted, and logged at most once per
 * log_interval with the number left unlogged (a peer may send thousands). */
static void refuse_identity(palp_srv *srv, const char *fmt, ...) {
  srv->refused_requests++;
  int64_t now = palp_dds_now_ns();
  if (srv->refused_log_ns && now - srv->refused_log_ns < (int64_t)(srv->cfg.log_interval * 1e9)) {
    srv->refused_unlogged++;
    return;
  }
  /* The server's log (it went to stderr alone until 2026-12-07, missing a --log-file) */
  char what[400];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(what, sizeof what, fmt, ap);
  va_end(ap);
  if (srv->refused_unlogged)
    palp_logf(srv->log, PALP_LOG_WARN, "refused request: %s (and %llu more since the last line)", what,
              (unsigned long long)srv->refused_unlogged);
  else
    palp_logf(srv->log, PALP_LOG_WARN, "refused request: %s", what);
  srv->refused_unlogged = 0;
  srv->refused_log_ns = now;
}

/* ---- phantoms and catalogue ------------------------------------------------ */

/* The exercise's file text, for the log; bounded (an exercise is a few kB). */
#define EXERCISE_FILE_MAX (256 * 1024)
static char *read_text(const char *path) {
  char *buf = NULL, why[160];
  return palp_input_file_read(path, EXERCISE_FILE_MAX, &buf, NULL, why, sizeof why) == 0 ? buf : NULL;
}

/* A random exercise's seed for one session: the stream of the run's key at the session id's place
 * (src/palp_rng.h), so that neighbouring sessions' draws share nothing. */
static uint32_t placement_seed(uint64_t key, uint32_t session_id) {
  uint64_t state = key + 0x9e3779b97f4a7c15ULL * (uint64_t)session_id;
  return (uint32_t)(palp_rng_next(&state) >> 32);
}

/* issue 13: an exercise is hosted as a phantom: the exercise's phantom scene with its
 * lesions hidden in it (palp_exercise_scene), named by the exercise's title. The scene
 * and the file's text stay on the server and in its log; what goes on the wire is the
 * catalogue's rest mesh (which lesions do not change) and the palp_exercise sample, and at a
 * session's end its debrief, as much as the exercise tells (publish_debrief). */
static int load_exercise(palp_srv *srv, palp_srv_phantom *ph, char *err, size_t errlen) {
  char msg[256] = "";
  const palp_srv_phantom_cfg *pc = &ph->cfg;
  ph->exercise = calloc(1, sizeof *ph->exercise);
  if (!ph->exercise) return PALP_ENOMEM;
  int rc = palp_exercise_load(pc->exercise_path, ph->exercise, msg, sizeof msg);
  /* "per": "run" (an examination): one draw now, for every session of this run; the phantom then
   * holds the drawn exercise, which the sessions do not draw again (docs/assessment.md) */
  palp_exercise drawn;
  const int per_run = rc == 0 && ph->exercise->placement.kind == PALP_PLACEMENT_RANDOM && ph->exercise->placement.per_run;
  if (per_run) {
    /* the dome's radius from its scene (loaded again, lesions and all, just below) */
    rc = palp_scene_load(ph->exercise->phantom_path, &ph->scene, msg, sizeof msg);
    /* the phantom's id in place of a session's: its own stream of the run's key */
    if (rc == 0)
      rc = palp_exercise_draw(ph->exercise, ph->scene.world.mesh.radius, placement_seed(srv->placement_key, ~pc->id),
                              &drawn, msg, sizeof msg);
  }
  if (rc == 0) rc = palp_exercise_scene(per_run ? &drawn : ph->exercise, &ph->scene, msg, sizeof msg);
  /* Its bands against this dome and this server (session 90's review): a depth band reaching the dome's
   * radius let a mark anywhere inside the dome be taken for a contact point (findings.h), and a force
   * band starting at or above the server's force limit can never be pressed into, so every trainee
   * failed its coverage. */
  if (rc == 0)
    rc = palp_srv_findings_check_exercise(ph->exercise, ph->scene.world.mesh.radius, srv->cfg.max_force, msg, sizeof msg);
  if (rc < 0) {
    fail(err, errlen, "exercises (id %u): %s: %s", pc->id, pc->exercise_path, msg[0] ? msg : palp_strerror(rc));
    return rc;
  }
  if (per_run && ph->exercise->debrief != PALP_DEBRIEF_NONE)
    palp_log_warn(srv->log, "exercise %s: drawn once for this run (\"per\": \"run\") and debriefed \"%s\": each "
                  "trainee's debrief tells of the lesions the later trainees of this run search (the review marks "
                  "their attempts not blind); an examination debriefs \"none\"", ph->exercise->name,
                  ph->exercise->debrief == PALP_DEBRIEF_LESIONS ? "lesions" : "count");
  ph->exercise_json = read_text(pc->exercise_path);
  if (ph->exercise_json && per_run) {
    char *text = palp_exercise_drawn_json(ph->exercise_json, &drawn);
    free(ph->exercise_json);
    ph->exercise_json = text;
    *ph->exercise = drawn;
    palp_log_info(srv->log, "exercise %s: its lesions drawn once for this run (seed %u): every session of the run "
                  "searches the same", drawn.name, (unsigned)drawn.placement.seed);
  }
  if (!ph->exercise_json) {
    fail(err, errlen, "exercises (id %u): %s: cannot read it again for the log", pc->id, pc->exercise_path);
    return PALP_EIO;
  }
  snprintf(ph->cfg.name, sizeof ph->cfg.name, "%.63s", ph->exercise->title);
  snprintf(ph->cfg.scene_path, sizeof ph->cfg.scene_path, "%s", ph->exercise->phantom_path);
  return 0;
}

/* What a trainee may know of an exercise: no lesion, nothing derived from one. */
static void publish_exercise(palp_srv *srv, const palp_srv_phantom *ph) {
  if (!ph->exercise || srv->exercise_w <= 0) return;
  const palp_exercise *ex = ph->exercise;
  palp_Exercise m;
  memset(&m, 0, sizeof m);
  m.phantom_id = ph->cfg.id;
  snprintf(m.name, sizeof m.name, "%s", ex->name);
  snprintf(m.title, sizeof m.title, "%s", ex->title);
  snprintf(m.instructions, sizeof m.instructions, "%s", ex->instructions);
  m.time_limit = ex->time_limit;
  m.max_force = ex->max_force;
  for (int b = 0; b < PALP_BAND_COUNT; b++) {
    const palp_band *in = &ex->band[b];
    palp_PressureBand *o = &m.bands[b];
    o->has_depth = in->has_depth != 0;
    o->has_force = in->has_force != 0;
    o->depth_min = in->depth_min, o->depth_max = in->depth_max;
    o->force_min = in->force_min, o->force_max = in->force_max;
  }
  dds_write(srv->exercise_w, &m);
}

/* What a server whose permissions predate a topic goes without (NULL: a topic it cannot serve
 * without). palp_debrief (2026-12-04): nobody is told what they found (the review still is);
 * palp_session_exercise (session 60): recorders get no exercise, their logs cannot assess them. */
static const char *optional_topic_loss(palp_dds_topic_kind k) {
  switch (k) {
  case PALP_TOPIC_DEBRIEF: return "no debriefs";
  case PALP_TOPIC_SESSION_EXERCISE: return "no exercises for recorders";
  case PALP_TOPIC_SESSION_SCORE: return "no live scores for the instructors";
  case PALP_TOPIC_DEBRIEF_SCORE: return "no scores told to the trainees of practice exercises";
  case PALP_TOPIC_SESSION_LOG:
    return "no session told its own records the session log lost (stations count the server's instead)";
  case PALP_TOPIC_SESSION_CLOSED: return "no names for the ended sessions of a dashboard begun after them";
  case PALP_TOPIC_FINGER_SAMPLE:
    return "no touched triangles for the stations' and pages' coverage (they approximate it from the local models)";
  default: return NULL;
  }
}

static void publish_session_log(palp_srv *srv, palp_srv_session *s);

/* An exercise session's exercise, its lesions included, for the instructors' recorders (only
 * their permissions read it): what the server's own log holds, so that a recorder's log of the
 * session is assessed as the server's is. Too long for the topic's bound, it is not sent, and
 * said why: the recorder's log then assesses the session without its lesions. */
static void publish_session_exercise(palp_srv *srv, const palp_srv_session *s, const char *name, const char *json) {
  if (srv->session_exercise_w <= 0 || !name || !json) return;
  const size_t n = strlen(json);
  if (n > PALP_SESSION_EXERCISE_JSON_MAX) {
    palp_log_warn(srv->log, "session %u: its exercise (%zu bytes) is longer than palp_session_exercise carries "
                            "(%d): a recorder cannot assess this session",
                  s->id, n, PALP_SESSION_EXERCISE_JSON_MAX);
    return;
  }
  palp_SessionExercise *m = calloc(1, sizeof *m); /* 32 KiB: not on the main loop's stack */
  if (!m) {
    palp_log_warn(srv->log, "session %u: its exercise was not sent to recorders: out of memory", s->id);
    return;
  }
  m->session_id = s->id;
  m->phantom_id = s->phantom->cfg.id;
  snprintf(m->name, sizeof m->name, "%s", name);
  memcpy(m->json, json, n + 1);
  const dds_return_t rc = dds_write(srv->session_exercise_w, m);
  free(m);
  if (rc < 0) palp_log_warn(srv->log, "session %u: its exercise was not sent to recorders: %s", s->id, dds_strretcode(rc));
}

/* Its instance goes with the session: a recorder has logged it, and a late one has no session to log. */
static void release_session_exercise(palp_srv *srv, const palp_srv_session *s) {
  if (srv->session_exercise_w <= 0 || !s->exercise) return;
  palp_SessionExercise *key = calloc(1, sizeof *key);
  if (!key) return;
  key->session_id = s->id;
  dds_unregister_instance(srv->session_exercise_w, key);
  free(key);
}

/* A writer of a topic for the instructors alone (palp_session_exercise and palp_session_score, which
 * tell the answers; palp_session_closed), in the default partition; 0 when the permissions predate the
 * topic (its loss was said as the topics were made) or the writer cannot be made (said here: what is
 * lost). */
static dds_entity_t answers_writer(palp_srv *srv, palp_dds_topic_kind k) {
  if (srv->topic[k] <= 0) return 0;
  const dds_entity_t w = palp_dds_create_writer(srv->pp, srv->topic[k], k);
  if (w >= 0) return w;
  palp_log_warn(srv->log, "%s: cannot write %s: %s", optional_topic_loss(k), palp_dds_topic_name(k),
                dds_strretcode(w));
  return 0;
}

/* Keeps a writer's newest SCORES_KEPT instances, keyed by session (palp_session_score,
 * palp_session_closed): id takes the oldest's place in ring, which is unregistered (bounded memory in
 * the writer). key: a zeroed sample of the writer's type, whose key field *key_id this sets. */
static void keep_newest(dds_entity_t w, uint32_t *ring, int *next, uint32_t id, const void *key, uint32_t *key_id) {
  uint32_t *slot = &ring[*next];
  if (*slot) {
    *key_id = *slot;
    dds_unregister_instance(w, key);
  }
  *slot = id;
  *next = (*next + 1) % SCORES_KEPT;
}

/* Who a closed session was, for a dashboard whose bridge began after it (palp_session_closed, session
 * 69): its score (palp_session_score) names no trainee. Keep-last 1 per session, transient-local: the
 * newest SCORES_KEPT kept, the oldest unregistered (bounded memory in the writer), as the scores. */
static void publish_session_closed(palp_srv *srv, const palp_srv_session *s, double duration, const char *reason) {
  if (srv->session_closed_w <= 0) return;
  palp_SessionClosed m;
  memset(&m, 0, sizeof m);
  m.session_id = s->id;
  m.phantom_id = s->phantom->cfg.id;
  snprintf(m.trainee_name, sizeof m.trainee_name, "%s", s->trainee_name);
  snprintf(m.trainee_station, sizeof m.trainee_station, "%s", s->trainee_station);
  m.duration = duration;
  snprintf(m.reason, sizeof m.reason, "%s", reason ? reason : "");
  if (dds_write(srv->session_closed_w, &m) < 0) return; /* the dashboard then shows it without a name */
  palp_SessionClosed key;
  memset(&key, 0, sizeof key);
  keep_newest(srv->session_closed_w, srv->closed_sent, &srv->closed_sent_next, s->id, &key, &key.session_id);
}

/* A closed exercise session's score, as the session log graded it (events.h take_score), as the wire
 * carries it (both palp_session_score and palp_debrief_score). */
static void score_message(const palp_srv_score *sc, palp_SessionScore *out) {
  palp_SessionScore m;
  memset(&m, 0, sizeof m);
  m.session_id = sc->session_id;
  m.status = sc->graded ? palp_SCORE_GRADED : palp_SCORE_NOT_GRADED;
  snprintf(m.log_uid, sizeof m.log_uid, "%s", sc->log_uid);
  snprintf(m.exercise_name, sizeof m.exercise_name, "%s", sc->exercise);
  snprintf(m.reason, sizeof m.reason, "%s", sc->reason);
  if (sc->graded) {
    m.score = sc->score;
    m.pass = sc->pass != 0;
    for (int i = 0; i < 6; i++) {
      m.credit[i] = sc->credit[i];
      m.passed[i] = sc->passed[i] != 0;
    }
    m.lesions = sc->lesions;
    m.found = sc->found;
    m.false_marks = sc->false_marks;
    for (int b = 0; b < 3; b++) m.coverage[b] = sc->coverage[b];
    snprintf(m.pattern, sizeof m.pattern, "%s", palp_pattern_name((palp_pattern)sc->pattern));
    m.duration = sc->duration;
    m.peak_force = sc->peak_force;
    m.out_of_range = sc->out_of_range;
    m.samples = sc->samples;
    m.log_complete = sc->log_complete != 0;
    snprintf(m.log_health, sizeof m.log_health, "%s", sc->log_health);
  }
  *out = m;
}

/* The trainee of a practice exercise is told her score in her session's partition (palp_debrief_score):
 * a publisher there of the server's own (the session's went with it), kept for TOLD_KEPT more. */
static void write_told_score(palp_srv *srv, const char *partition, const palp_SessionScore *m) {
  const dds_entity_t pub = palp_dds_session_publisher(srv->pp, partition);
  const dds_entity_t w =
      pub < 0 ? pub : palp_dds_create_writer(pub, srv->topic[PALP_TOPIC_DEBRIEF_SCORE], PALP_TOPIC_DEBRIEF_SCORE);
  const dds_return_t rc = w < 0 ? w : dds_write(w, m);
  if (rc < 0) {
    palp_log_warn(srv->log, "session %u: its trainee was not told her score: %s", m->session_id, dds_strretcode(rc));
    if (pub > 0) dds_delete(pub);
    return;
  }
  dds_entity_t *slot = &srv->told_pub[srv->told_next];
  /* its writer, and the sample it kept for a late reader; beside the main loop (a writer's delete waits) */
  if (*slot > 0 && (!srv->reaper || palp_dds_reaper_put(srv->reaper, *slot) != 0)) dds_delete(*slot);
  *slot = pub;
  srv->told_next = (srv->told_next + 1) % TOLD_KEPT;
}

/* A session whose debrief told its trainee the lesions (a practice exercise) is told its score as
 * well, when the grader has it; told at once that there will be none when nothing will grade it. */
static void expect_told_score(palp_srv *srv, const palp_srv_session *s) {
  if (srv->topic[PALP_TOPIC_DEBRIEF_SCORE] <= 0 || !s->exercise) return;
  const palp_srv_events *ev = srv->events;
  const char *none = !ev || !ev->take_score
                         ? (ev && ev->unscored ? ev->unscored
                                               : "this server keeps no session log to score it from; your instructor "
                                                 "grades the session")
                     : srv->stopping ? "the server stopped before it scored the session; the instructor's review "
                                       "scores it from the session log"
                                     : NULL;
  if (none) {
    palp_SessionScore m;
    memset(&m, 0, sizeof m);
    m.session_id = s->id;
    m.status = palp_SCORE_NOT_GRADED;
    snprintf(m.exercise_name, sizeof m.exercise_name, "%s", s->exercise->name);
    snprintf(m.reason, sizeof m.reason, "%s", none);
    write_told_score(srv, s->partition, &m);
    return;
  }
  /* The grader takes at most 32 waiting, so 16 slots are only outrun by a burst of closes; the
   * oldest then goes untold (its station says no score came). */
  score_to_tell *t = &srv->to_tell[srv->to_tell_next];
  t->session_id = s->id;
  snprintf(t->partition, sizeof t->partition, "%s", s->partition);
  srv->to_tell_next = (srv->to_tell_next + 1) % TOLD_KEPT;
}

static void tell_score(palp_srv *srv, const palp_SessionScore *m) {
  if (srv->topic[PALP_TOPIC_DEBRIEF_SCORE] <= 0) return;
  for (int i = 0; i < TOLD_KEPT; i++) {
    score_to_tell *t = &srv->to_tell[i];
    if (t->session_id != m->session_id) continue;
    write_told_score(srv, t->partition, m);
    t->session_id = 0;
    return;
  }
}

/* The score to its trainee when she is told it (tell_score), and to the instructors' dashboards.
 * Keep-last 1 per session and transient-local, so a dashboard opened later still gets it: the newest
 * 64 are kept, the oldest unregistered (bounded memory in the writer). */
static void publish_session_score(palp_srv *srv, const palp_srv_score *sc) {
  palp_SessionScore m;
  score_message(sc, &m);
  tell_score(srv, &m);
  if (srv->session_score_w <= 0) return;
  const dds_return_t rc = dds_write(srv->session_score_w, &m);
  if (rc < 0) {
    palp_log_warn(srv->log, "session %u: its score was not sent to the instructors: %s", sc->session_id,
                  dds_strretcode(rc));
    return;
  }
  palp_SessionScore key;
  memset(&key, 0, sizeof key);
  keep_newest(srv->session_score_w, srv->scored, &srv->scored_next, sc->session_id, &key, &key.session_id);
}

static void publish_scores(palp_srv *srv) {
  if (!srv->events || !srv->events->take_score) return;
  palp_srv_score sc;
  while (srv->events->take_score(srv->events->ctx, &sc)) publish_session_score(srv, &sc);
}

/* What the start does to a hosted phantom's loaded scene, shared with `palp-server --check`
 * (main.c) so that the check refuses what the start would. */
int palp_srv_prepare_phantom(const palp_srv_config *cfg, int index, palp_srv_phantom_cfg *pc, palp_scene *scene,
                             palp_world **world, char *err, size_t errlen) {
  *world = NULL;
  const int plain = cfg->phantom_count - cfg->exercise_count;
  /* the config key a message names: the entry's own rate, or the server's */
  char entry[48], rate_key[80];
  if (index >= plain) snprintf(entry, sizeof entry, "exercises[%d]", index - plain);
  else snprintf(entry, sizeof entry, "phantoms[%d]", index);
  if (pc->physics_rate_hz > 0) snprintf(rate_key, sizeof rate_key, "%s.physics_rate_hz", entry);
  else snprintf(rate_key, sizeof rate_key, "%s: tick_rate_hz (or --tick-rate)", entry);
  /* Every session steps at the server's tick rate. Stations drive the contacts:
   * each session removes the scene's scripted contacts after building its world
   * (session.c). The server needs contact feedback and a slot per finger besides
   * the scene's contacts; a scene without them is refused rather than altered,
   * so a recorded scene file always rebuilds the world the session ran. */
  /* Each phantom steps at its own physics rate (issue 11), by default the server's. */
  const double rate = pc->physics_rate_hz > 0 ? pc->physics_rate_hz : cfg->tick_rate_hz;
  pc->physics_rate_hz = rate;
  scene->world.dt = 1.0 / rate;
  /* The config refuses rates below 1 / PALP_WORLD_MAX_DT; said here too, naming the key, for a
   * config made in code (the world's own refusal names neither key nor bound). */
  if (!(scene->world.dt <= PALP_WORLD_MAX_DT)) {
    fail(err, errlen, "%s: %g Hz steps the world by %g s, above its %g s bound (at least %g Hz)", rate_key, rate,
         scene->world.dt, PALP_WORLD_MAX_DT, 1.0 / PALP_WORLD_MAX_DT);
    return PALP_EINVAL;
  }
  /* The literal gel law's momentum term is stable only for -dt^2/2 < a3 < dt^2
   * (palp_gel_literal_valid): a fast physics rate can break a scene that loads at its own dt_s. */
  const palp_gel_params *g = &scene->world.gel;
  if ((scene->world.effects & PALP_EFFECT_GEL_PRESSURE) && g->law == PALP_GEL_PAPER_LITERAL &&
      !palp_gel_literal_valid(g->a3, scene->world.dt, scene->world.dt)) {
    fail(err, errlen,
         "%s: %g Hz steps the world by %g s, too fine for the scene %s's paper_literal gel (a3_s2 %g needs "
         "-dt^2/2 < a3 < dt^2: at most %g Hz)",
         rate_key, rate, scene->world.dt, pc->scene_path, g->a3, 1.0 / palp_gel_literal_min_step(g->a3));
    return PALP_EINVAL;
  }
  /* Rebuilds are computed by the ticker's helper behind the ticks (docs/server.md);
   * the logged scene carries the lag (time.refactor_lag_steps), so replay defers the same. */
  scene->world.refactor_lag = palp_world_refactor_lag_for(scene->world.dt);
  /* A rebuilt tangent takes over across ~8 ms (time.refactor_blend_steps in the logged
   * scene, replayed the same): in one step, it stepped the finger's force (docs/haptics.md). */
  scene->world.refactor_blend = palp_world_refactor_blend_for(scene->world.dt);
  /* The recorded scene must stay loadable: its frame period a whole number of steps
   * (0.01 s at 250 Hz is 2.5 steps; it becomes 3). */
  {
    const double steps = round(scene->frame_period / scene->world.dt);
    scene->frame_period = scene->world.dt * (steps >= 1 ? steps : 1);
  }
  if (!(scene->world.effects & PALP_EFFECT_FORCE_FEEDBACK)) {
    fail(err, errlen, "%s (id %u): scene %s: effects must include \"force_feedback\" for stations", entry, pc->id,
         pc->scene_path);
    return PALP_EINVAL;
  }
  if (scene->world.max_contacts < PALP_SRV_MAX_FINGERS) {
    fail(err, errlen, "%s (id %u): scene %s: max_contacts %d is below the %d fingers of a station", entry, pc->id,
         pc->scene_path, scene->world.max_contacts, PALP_SRV_MAX_FINGERS);
    return PALP_EINVAL;
  }
  int rc = 0;
  *world = palp_scene_create_world(scene, &rc);
  if (!*world) {
    fail(err, errlen, "%s (id %u): scene %s: cannot build the world at %g Hz (%s): %s", entry, pc->id,
         pc->scene_path, rate, rate_key, palp_strerror(rc));
    return rc < 0 ? rc : PALP_EINVAL;
  }
  return 0;
}

static int load_phantom(palp_srv *srv, int index, const palp_srv_phantom_cfg *pc, palp_srv_phantom *ph, char *err,
                        size_t errlen) {
  char msg[256] = "";
  ph->cfg = *pc;
  int rc;
  if (pc->exercise_path[0]) {
    rc = load_exercise(srv, ph, err, errlen);
    if (rc < 0) return rc;
  } else
    rc = palp_scene_load(pc->scene_path, &ph->scene, msg, sizeof msg);
  if (rc < 0) {
    fail(err, errlen, "phantoms (id %u): scene %s: %s", pc->id, pc->scene_path, msg[0] ? msg : palp_strerror(rc));
    return rc;
  }
  rc = palp_srv_prepare_phantom(&srv->cfg, index, &ph->cfg, &ph->scene, &ph->template_world, err, errlen);
  if (rc < 0) return rc;
  ph->mesh = palp_world_mesh(ph->template_world);
  return 0;
}

static int phantom_sessions(const palp_srv *srv, uint32_t phantom_id) {
  int n = 0;
  for (int i = 0; i < srv->session_count; i++) n += srv->sessions[i]->phantom->cfg.id == phantom_id;
  return n;
}

void palp_srv_catalogue_mesh(const palp_mesh *m, palp_Vec3 *rest, int32_t *tri, palp_Phantom *msg) {
  msg->top_vertex = m->top_vertex;
  msg->dome_triangle_count = m->dome_triangle_count;
  for (int i = 0; i < m->vertex_count; i++) rest[i] = (palp_Vec3){m->rest[i].x, m->rest[i].y, m->rest[i].z};
  for (int i = 0; i < m->triangle_count; i++)
    for (int k = 0; k < 3; k++) tri[3 * i + k] = m->tri[i][k];
  msg->rest = (dds_sequence_palp_Vec3){(uint32_t)m->vertex_count, (uint32_t)m->vertex_count, rest, false};
  msg->triangles = (dds_sequence_long){(uint32_t)m->triangle_count * 3, (uint32_t)m->triangle_count * 3, tri, false};
}

static void publish_catalogue(palp_srv *srv, const palp_srv_phantom *ph) {
  const palp_mesh *m = ph->mesh;
  const palp_world_def *wd = &ph->scene.world;
  palp_Phantom msg;
  memset(&msg, 0, sizeof msg);
  msg.phantom_id = ph->cfg.id;
  snprintf(msg.name, sizeof msg.name, "%s", ph->cfg.name);
  snprintf(msg.scene_name, sizeof msg.scene_name, "%s", ph->scene.name);
  msg.radius = wd->mesh.radius;
  msg.tick_rate_hz = ph->cfg.physics_rate_hz;
  msg.max_force = srv->cfg.max_force;
  msg.effects = wd->effects;
  msg.membrane = (palp_MembraneParams){wd->membrane.thickness, wd->membrane.density, wd->membrane.E1,
                                       wd->membrane.eta1, wd->membrane.E2, wd->membrane.eta2};
  msg.gel = (palp_GelParams){(int32_t)wd->gel.law, wd->gel.pressure, wd->gel.a1, wd->gel.a2, wd->gel.a3};
  palp_Vec3 *rest = malloc((size_t)m->vertex_count * sizeof *rest);
  int32_t *tri = malloc((size_t)m->triangle_count * 3 * sizeof *tri);
  if (!rest || !tri) {
    free(rest);
    free(tri);
    return;
  }
  palp_srv_catalogue_mesh(m, rest, tri, &msg);
  msg.active_sessions = (uint32_t)phantom_sessions(srv, ph->cfg.id);
  dds_write(srv->catalogue_w, &msg);
  free(rest);
  free(tri);
}

static palp_srv_phantom *find_phantom(palp_srv *srv, uint32_t id) {
  for (int i = 0; i < srv->phantom_count; i++)
    if (srv->phantom[i].cfg.id == id) return &srv->phantom[i];
  return NULL;
}

/* ---- session state ----------------------------------------------------------- */

static void snap_one(void *ctx, palp_srv_session *s) { *(palp_srv_session_stats *)ctx = s->stats; }

/* Its own group's lock alone (until session 89 every group's, one after the other, for each batch of
 * findings: a flood of foreign findings in one session took the lock of every group's real-time tick). */
static palp_srv_session_stats session_stats(palp_srv *srv, palp_srv_session *s) {
  palp_srv_session_stats st;
  if (palp_srv_ticker_with(srv->ticker, s, snap_one, &st)) return st;
  return s->stats; /* detached: the tick thread no longer writes it */
}

static void member_counts(const palp_srv *srv, uint32_t sid, uint32_t *visual, uint32_t *observer) {
  *visual = *observer = 0;
  for (int i = 0; i < srv->station_slots; i++) {
    const station *st = &srv->stations[i];
    if (!st->in_use || st->session_id != sid) continue;
    if (st->role == palp_ROLE_VISUAL) ++*visual;
    if (st->role == palp_ROLE_OBSERVER) ++*observer;
  }
}

static void publish_state(palp_srv *srv, palp_srv_session *s, int closed, const char *reason,
                          const palp_srv_session_stats *stp) {
  palp_srv_session_stats st = stp ? *stp : session_stats(srv, s);
  palp_SessionState m;
  memset(&m, 0, sizeof m);
  m.session_id = s->id;
  m.phantom_id = s->phantom->cfg.id;
  m.phase = closed ? palp_PHASE_CLOSED : palp_PHASE_OPEN;
  snprintf(m.partition, sizeof m.partition, "%s", s->partition);
  snprintf(m.trainee_station, sizeof m.trainee_station, "%s", s->trainee_station);
  snprintf(m.trainee_name, sizeof m.trainee_name, "%s", s->trainee_name);
  member_counts(srv, s->id, &m.visual_count, &m.observer_count);
  m.tick_rate_hz = s->phantom->cfg.physics_rate_hz;
  m.duration = (double)(palp_dds_now_ns() - s->opened_ns) * 1e-9;
  m.ticks = st.ticks;
  m.overruns = st.overruns;
  m.contact_samples = st.contact_samples;
  for (int r = 0; r < PALP_SRV_REJ_COUNT; r++)
    if (r != PALP_SRV_REJ_FORCE_LIMIT || srv->cfg.force_policy == PALP_SRV_FORCE_REJECT)
      m.rejected_samples += st.rejected[r];
  m.peak_force = st.peak_force;
  m.peak_displacement = st.peak_displacement;
  if (reason)
    snprintf(m.reason, sizeof m.reason, "%s", reason);
  else if (s->held_since_ns) /* open, waiting for its trainee station: the viewers are told why nothing moves */
    snprintf(m.reason, sizeof m.reason, "%.96s; held %.0f s for it to come back", s->held_reason, srv->cfg.station_grace);
  dds_write(srv->state_w, &m);
}

static void reply(palp_srv *srv, const palp_SessionRequest *rq, palp_srv_session *s, const char *why) {
  palp_SessionReply r;
  memset(&r, 0, sizeof r);
  /* bounded copies: both fields hold IDL-bounded strings, terminated on receipt */
  snprintf(r.station_id, sizeof r.station_id, "%.*s", (int)sizeof r.station_id - 1, rq->station_id);
  r.request_seq = rq->request_seq;
  r.status = s ? palp_REPLY_ACCEPTED : palp_REPLY_REJECTED;
  r.tick_rate_hz = s ? s->phantom->cfg.physics_rate_hz : srv->cfg.tick_rate_hz;
  if (s) {
    r.session_id = s->id;
    r.phantom_id = s->phantom->cfg.id;
    snprintf(r.partition, sizeof r.partition, "%s", s->partition);
  } else {
    r.phantom_id = rq->phantom_id;
    snprintf(r.reason, sizeof r.reason, "%.*s", (int)sizeof r.reason - 1, why ? why : "rejected");
  }
  dds_write(srv->reply_w, &r);
}

static palp_srv_session *find_session(palp_srv *srv, uint32_t id) {
  for (int i = 0; i < srv->session_count; i++)
    if (srv->sessions[i]->id == id) return srv->sessions[i];
  return NULL;
}

/* The id the next session gets. Local ids wrap after session_local_max (2^20 - 1) sessions, keeping
 * the server's number, and skip any a session still open (or held for its station) has: until session
 * 89 a session open across the wrap shared its id with a new one (its partition, its feedback and
 * findings, its log), ~14.6 h of JOINs and LEAVEs at the default join_rate away. Fewer than 2^20
 * sessions are ever open, so a free id is always found. */
static void next_session_id(palp_srv *srv) {
  uint32_t tries = 0;
  do {
    srv->next_session_id++;
    if (PALP_DDS_ID_LOCAL(srv->next_session_id) == 0 ||
        PALP_DDS_ID_LOCAL(srv->next_session_id) > srv->session_local_max)
      srv->next_session_id = PALP_DDS_ID(srv->cfg.server_number, 1);
  } while (find_session(srv, srv->next_session_id) && ++tries < srv->session_local_max);
}

static station *find_station(palp_srv *srv, const char *id) {
  for (int i = 0; i < srv->station_slots; i++) {
    station *st = &srv->stations[i];
    if (st->in_use && strcmp(st->id, id) == 0) return st;
  }
  return NULL;
}

static station *new_station(palp_srv *srv, const char *id, uint64_t writer) {
  for (int i = 0; i < srv->station_slots; i++) {
    station *st = &srv->stations[i];
    if (st->in_use) continue;
    memset(st, 0, sizeof *st);
    st->in_use = 1;
    st->writer = writer;
    snprintf(st->id, sizeof st->id, "%s", id);
    return st;
  }
  return NULL;
}

static int stations_in_use(const palp_srv *srv) {
  int n = 0;
  for (int i = 0; i < srv->station_slots; i++) n += srv->stations[i].in_use;
  return n;
}

static int stations_of_writer(const palp_srv *srv, uint64_t writer) {
  int n = 0;
  for (int i = 0; i < srv->station_slots; i++) n += srv->stations[i].in_use && srv->stations[i].writer == writer;
  return n;
}

/* ---- releasing instances ------------------------------------------------------- */

static void release_instance(void *ctx, const palp_srv_retire_entry *e) {
  palp_srv *srv = ctx;
  if (e->kind == PALP_SRV_RETIRE_STATE) {
    palp_SessionState k;
    memset(&k, 0, sizeof k);
    k.session_id = e->session_id;
    dds_unregister_instance(srv->state_w, &k);
    return;
  }
  /* The station came back meanwhile: its reply is live again. */
  if (find_station(srv, e->station_id)) return;
  palp_SessionReply k;
  memset(&k, 0, sizeof k);
  snprintf(k.station_id, sizeof k.station_id, "%s", e->station_id);
  dds_unregister_instance(srv->reply_w, &k);
}

static void retire_reply(palp_srv *srv, const char *station_id) {
  palp_srv_retire_entry e = {.kind = PALP_SRV_RETIRE_REPLY};
  snprintf(e.station_id, sizeof e.station_id, "%.*s", (int)sizeof e.station_id - 1, station_id);
  palp_srv_retire_add(&srv->retire, &e, palp_dds_now_ns(), release_instance, srv);
}

static void retire_state(palp_srv *srv, uint32_t session_id) {
  palp_srv_retire_entry e = {.kind = PALP_SRV_RETIRE_STATE, .session_id = session_id};
  palp_srv_retire_add(&srv->retire, &e, palp_dds_now_ns(), release_instance, srv);
}

static void free_station(palp_srv *srv, station *st) {
  st->in_use = 0;
  retire_reply(srv, st->id);
}

static void remember_closed(palp_srv *srv, const palp_srv_session_summary *sum, int open, uint32_t request_seq) {
  if (!srv->closed) return;
  closed_session *c;
  if (srv->closed_count < CLOSED_KEEP) {
    c = &srv->closed[(srv->closed_head + srv->closed_count++) % CLOSED_KEEP];
  } else {
    c = &srv->closed[srv->closed_head];
    srv->closed_head = (srv->closed_head + 1) % CLOSED_KEEP;
    srv->sessions_forgotten++;
  }
  c->sum = *sum;
  c->open = open;
  c->request_seq = request_seq;
  snprintf(c->phantom_name, sizeof c->phantom_name, "%s", sum->info.phantom_name);
  snprintf(c->station, sizeof c->station, "%s", sum->info.trainee_station);
  snprintf(c->name, sizeof c->name, "%s", sum->info.trainee_name);
  snprintf(c->partition, sizeof c->partition, "%s", sum->info.partition);
  snprintf(c->reason, sizeof c->reason, "%s", sum->close_reason ? sum->close_reason : "");
  c->sum.info.phantom_name = c->phantom_name;
  c->sum.info.trainee_station = c->station;
  c->sum.info.trainee_name = c->name;
  c->sum.info.partition = c->partition;
  c->sum.close_reason = c->reason;
  /* Not copied, and the session's (its own scene and exercise for a drawn one) are freed with it:
   * none kept to dangle (until session 82 they were, unread). scene_path is its phantom's. */
  c->sum.info.scene = NULL;
  c->sum.info.exercise_name = NULL;
  c->sum.info.exercise_json = NULL;
}

/* The newest closed session this trainee station opened, if it was opened by request
 * request_seq: a JOIN that comes again after its session closed (DDS re-delivers it when
 * the station's participant is found again; a station back from a stall sends it once
 * more) must not open another. */
static const closed_session *closed_by_request(const palp_srv *srv, const char *station_id, uint32_t request_seq) {
  for (int i = srv->closed ? srv->closed_count - 1 : -1; i >= 0; i--) {
    const closed_session *c = &srv->closed[(srv->closed_head + i) % CLOSED_KEEP];
    if (strcmp(c->station, station_id) == 0) return c->request_seq == request_seq ? c : NULL;
  }
  return NULL;
}

/* ---- findings (issue 13) -------------------------------------------------------- */

#define FINDING_STATUS_PERIOD_NS 500000000 /* 2 Hz: a countdown on the station moves every second */

/* Seconds left of the session's exercise time limit, or -1 without one. */
static double time_left(const palp_srv_session *s, int64_t now_ns) {
  if (!s->exercise) return -1.0;
  const double left = s->exercise->time_limit - (double)(now_ns - s->opened_ns) * 1e-9;
  return left > 0 ? left : 0.0;
}

static void publish_finding_status(palp_srv_session *s) {
  if (s->finding_status_writer <= 0) return;
  const palp_srv_findings *f = &s->findings;
  palp_FindingStatus m;
  memset(&m, 0, sizeof m);
  m.session_id = s->id;
  m.marks = (uint32_t)f->marks;
  m.last_mark_id = f->last_mark_id;
  m.last_accepted = f->last_accepted != 0;
  snprintf(m.reason, sizeof m.reason, "%s", f->reason);
  const int64_t now = palp_dds_now_ns();
  m.time_left = time_left(s, now);
  dds_write(s->finding_status_writer, &m);
  s->findings_status_ns = now;
}

/* The debrief's record in the session log: what the trainee was told, or that nothing was sent
 * and why, so the review's "not blind" rests on what happened (docs/assessment.md, "Debrief"). */
static void log_debrief(palp_srv *srv, const palp_srv_session *s, const palp_Debrief *m, int level, const char *why) {
  if (!srv->events || !srv->events->debrief) return;
  uint32_t found_by[PALP_MAX_LESIONS] = {0};
  palp_srv_debrief_event ev = {.sent = why == NULL, .level = level, .why = why};
  if (m && !why) {
    ev.lesions = m->lesions, ev.found = m->found, ev.marks = m->marks, ev.false_marks = m->false_marks;
    ev.duplicates = m->duplicates;
    ev.listed = m->lesion._length <= PALP_MAX_LESIONS ? m->lesion._length : 0;
    for (uint32_t i = 0; i < ev.listed; i++) found_by[i] = m->lesion._buffer[i].found_by;
    ev.found_by = found_by;
  }
  srv->events->debrief(srv->events->ctx, s->id, &ev);
}

/* An exercise session's debrief, written once as it closes (docs/assessment.md, "Debrief"): what
 * its standing marks found, matched as the review matches them, told at the exercise's level. */
static int publish_debrief(palp_srv *srv, palp_srv_session *s, const char *reason) {
  const palp_exercise *ex = s->exercise;
  if (!ex) return -1;
  char why[160];
  if (s->debrief_writer <= 0) {
    /* palp_debrief came after the classroom PKIs of 2026-12-04 and before (server start warns) */
    log_debrief(srv, s, NULL, (int)ex->debrief,
                "the server's permissions do not allow topic palp_debrief (make-classroom-pki.sh re-issues them)");
    return -1;
  }
  const palp_mesh *mesh = palp_world_mesh(s->world);
  const palp_vec3 pole = mesh->rest[mesh->top_vertex];
  const double R = sqrt(pole.x * pole.x + pole.y * pole.y + pole.z * pole.z); /* as palp_assess's [m] */
  palp_Debrief m;
  palp_DebriefLesion lesions[PALP_MAX_LESIONS];
  const int rc = palp_srv_findings_debrief(&s->findings, ex, R, s->id, reason, &m, lesions);
  if (rc < 0) {
    palp_log_warn(srv->log, "session %u: no debrief: %s", s->id, palp_strerror(rc));
    snprintf(why, sizeof why, "the marks could not be matched: %s", palp_strerror(rc));
    log_debrief(srv, s, NULL, (int)ex->debrief, why);
    return -1;
  }
  const dds_return_t w = dds_write(s->debrief_writer, &m);
  if (w < 0) {
    palp_log_warn(srv->log, "session %u: the debrief was not sent: %s", s->id, dds_strretcode(w));
    snprintf(why, sizeof why, "DDS refused the write: %s", dds_strretcode(w));
    log_debrief(srv, s, NULL, (int)ex->debrief, why);
    return -1;
  }
  log_debrief(srv, s, &m, (int)m.level, NULL);
  if (m.level == palp_DEBRIEF_NONE)
    palp_log_info(srv->log, "session %u: debrief sent: the exercise tells nothing of its lesions (marks standing: %u)",
                  s->id, m.marks);
  else
    palp_log_info(srv->log, "session %u: debrief sent (%s): lesions found %u of %u; marks standing %u, near no lesion %u",
                  s->id, m.level == palp_DEBRIEF_LESIONS ? "with the lesions' places" : "the count only", m.found,
                  m.lesions, m.marks, m.false_marks);
  return (int)m.level;
}

/* At most this many findings per session per pass of the main loop: a flooding
 * station cannot hold the main thread; the rest wait in the (bounded) reader. */
#define FINDINGS_PER_PASS 64

/* A dispose of a made-up finding key passes the reader's filter and becomes an instance the reader
 * keeps while its writer lives: 100,000 in 5 s grew the server by 98 MB (2026-12-06, before this
 * bound). The session's finding reader is made anew when idl/palp_dds_strays.h says so: what it held
 * of the session's own findings is answered first. */

/* Whether `participant` has a visual station admitted to the session (ctx: a finding_writer_ctx):
 * unsecured, palp-web writes a bound trainee page's marks from its own participant, which joined the
 * session as a visual station (docs/web.md, "Findings"). Secured, the bridge is an instructor, whose
 * permissions write nothing in a trainee's partition: only the trainee's participant marks. */
typedef struct finding_writer_ctx {
  const palp_srv *srv;
  uint32_t session_id;
} finding_writer_ctx;

static int visual_of_session(void *ctx, const dds_guid_t *participant) {
  const finding_writer_ctx *c = ctx;
  for (int i = 0; i < c->srv->station_slots; i++) {
    const station *st = &c->srv->stations[i];
    if (st->in_use && st->session_id == c->session_id && st->role == palp_ROLE_VISUAL && st->participant_known &&
        !memcmp(st->participant.v, participant->v, sizeof participant->v))
      return 1;
  }
  return 0;
}

/* One finding of this session, taken from `reader` (written by `pub`): offered, logged and answered,
 * or refused for its writer. */
static void offer_finding(palp_srv *srv, palp_srv_session *s, dds_entity_t reader, dds_instance_handle_t pub,
                          const palp_Finding *f, palp_srv_session_stats *st, int *have_st) {
  const int64_t now = palp_dds_now_ns();
  /* Only the participant that joined the session marks its findings (until 2026-12-06 any writer in
   * its partition placed and withdrew marks, and so changed the trainee's debrief and grade). Before
   * the bucket and the checks, as another session's findings are: a foreign finding spends none of
   * the trainee's tokens. Refused unanswered: palp_finding_status is keep-last 1 per session, and an
   * answer to another's finding would replace the trainee's own latest. */
  const finding_writer_ctx wctx = {.srv = srv, .session_id = s->id};
  if (!palp_srv_session_writer_ok(s, &s->finding_writers, reader, pub, now, secured(srv) ? NULL : visual_of_session,
                                  (void *)&wctx)) {
    s->findings_foreign++;
    if (!*have_st) {
      *st = session_stats(srv, s);
      *have_st = 1;
    }
    if (srv->events && srv->events->finding) {
      char why[128];
      snprintf(why, sizeof why, "%s: its writer is not of the participant that joined the session",
               palp_srv_reject_name(PALP_SRV_REJ_FOREIGN_PARTICIPANT));
      const palp_srv_finding_event ev = {.accepted = 0,
                                         .mark_id = f->mark_id,
                                         .withdraw = f->op == palp_FINDING_WITHDRAW,
                                         .frame = st->last_frame,
                                         .sim_time = st->sim_time,
                                         .reason = why};
      srv->events->finding(srv->events->ctx, s->id, &ev);
    }
    return;
  }
  const int ok = palp_srv_findings_offer(&s->findings, f, now);
  if (!*have_st) { /* the world's frame and time, once per batch: a snapshot under the tick lock */
    *st = session_stats(srv, s);
    *have_st = 1;
  }
  if (srv->events && srv->events->finding) {
    const palp_srv_finding_event ev = {.accepted = ok,
                                       .mark_id = f->mark_id,
                                       .withdraw = f->op == palp_FINDING_WITHDRAW,
                                       .point = {f->point.x, f->point.y, f->point.z},
                                       .frame = st->last_frame,
                                       .sim_time = st->sim_time,
                                       .reason = s->findings.reason};
    srv->events->finding(srv->events->ctx, s->id, &ev);
  }
  /* The first few, then every 100th: a flood must not flood the server's log either. */
  if (!ok && (s->findings.refused <= 16 || s->findings.refused % 100 == 0))
    logf_(srv, "session %u: finding %u refused: %s (%llu refused so far)", s->id, f->mark_id, s->findings.reason,
          (unsigned long long)s->findings.refused);
  /* Every answer goes out (keep-last 1: a station reading slower sees the latest). */
  publish_finding_status(s);
}

/* The session's finding reader made anew (palp_dds_strays_renew_due): its own findings still held are
 * answered first; the strays' instances go with the old reader. */
static void renew_finding_reader(palp_srv *srv, palp_srv_session *s, int64_t now_ns) {
  palp_Finding key, buf[16];
  memset(&key, 0, sizeof key);
  key.session_id = s->id;
  const dds_instance_handle_t own = dds_lookup_instance(s->finding_reader, &key);
  void *ptr[16];
  dds_sample_info_t info[16];
  for (int i = 0; i < 16; i++) ptr[i] = &buf[i];
  palp_srv_session_stats st = {0};
  int have_st = 0, n;
  while (own != 0 && (n = dds_take_instance(s->finding_reader, ptr, info, 16, 16, own)) > 0)
    for (int i = 0; i < n; i++)
      if (info[i].valid_data)
        offer_finding(srv, s, s->finding_reader, info[i].publication_handle, &buf[i], &st, &have_st);
  dds_waitset_detach(srv->waitset, s->finding_rc);
  dds_delete(s->finding_reader); /* its read condition with it */
  s->finding_reader = palp_dds_create_reader(s->sub, s->finding_topic, PALP_TOPIC_FINDING);
  s->finding_rc = s->finding_reader > 0 ? dds_create_readcondition(s->finding_reader, DDS_ANY_STATE) : 0;
  if (s->finding_rc > 0) dds_waitset_attach(srv->waitset, s->finding_rc, 0);
  const uint64_t strays = s->finding_strays;
  s->finding_strays_total += strays;
  s->finding_strays = 0;
  s->finding_reader_renewed_ns = now_ns;
  s->finding_reader_renewals++;
  if (s->finding_reader <= 0 || s->finding_rc <= 0) {
    palp_logf(srv->log, PALP_LOG_ERROR, "session %u: its finding reader could not be made anew (%s): its findings "
              "go unanswered from now on",
              s->id, dds_strretcode(s->finding_reader <= 0 ? s->finding_reader : s->finding_rc));
    if (s->finding_reader > 0) dds_delete(s->finding_reader);
    s->finding_reader = s->finding_rc = 0;
    return;
  }
  /* said once a session at warning level (a peer writes here); the later ones in the debug log */
  if (s->finding_reader_renewals == 1)
    palp_logf(srv->log, PALP_LOG_WARN, "session %u: %llu disposes of other sessions' finding keys reached its "
              "reader (each kept while its writer lives: a flood%s%s%s); the reader was made anew to drop them, as "
              "it will be whenever %d more come (at most every %.2f s, unless %d do; a finding sent in that "
              "instant may go unanswered)",
              s->id, (unsigned long long)strays,
              /* secured, only the session's own trainee may write in its partition (docs/security.md) */
              secured(srv) ? ", written by trainee/" : "", secured(srv) ? s->trainee_name : "",
              secured(srv) ? ", the only identity that may write in this session's partition" : "",
              PALP_DDS_STRAYS_MIN, PALP_DDS_RENEW_NS * 1e-9, PALP_DDS_STRAYS_HARD);
  else if (now_ns - s->finding_renewal_said_ns >= (int64_t)(srv->cfg.log_interval * 1e9)) /* a flood goes on */
    logf_(srv, "session %u: finding reader made anew (%llu times), %llu stray disposes in all", s->id,
          (unsigned long long)s->finding_reader_renewals, (unsigned long long)s->finding_strays_total);
  else
    return;
  s->finding_renewal_said_ns = now_ns;
}

static void handle_findings(palp_srv *srv, palp_srv_session *s) {
  if (s->finding_reader <= 0) return;
  /* Findings naming another session, dropped by the reader's filter: logged as one refusal per pass
   * that saw any (not answered: the station that wrote them is not this session's). */
  const uint64_t stray = atomic_load_explicit(&s->filtered_findings, memory_order_relaxed);
  if (stray > s->filtered_findings_said) {
    const uint64_t n = stray - s->filtered_findings_said;
    s->filtered_findings_said = stray;
    char why[176];
    snprintf(why, sizeof why, "%llu finding(s) of another writer dropped unanswered at the reader; the last names "
             "session %u, not this partition's session %u", (unsigned long long)n,
             (unsigned)atomic_load_explicit(&s->filtered_finding_session, memory_order_relaxed), s->id);
    const palp_srv_session_stats st = session_stats(srv, s);
    if (srv->events && srv->events->finding) {
      const palp_srv_finding_event ev = {.accepted = 0, .frame = st.last_frame, .sim_time = st.sim_time, .reason = why};
      srv->events->finding(srv->events->ctx, s->id, &ev);
    }
    /* said once a session at warning level (a peer writes here); the later counts in the debug log */
    if (stray == n) palp_logf(srv->log, PALP_LOG_WARN, "session %u: %s", s->id, why);
    else logf_(srv, "session %u: %s", s->id, why);
  }
  palp_Finding buf[16];
  void *ptr[16];
  dds_sample_info_t info[16];
  for (int i = 0; i < 16; i++) ptr[i] = &buf[i];
  for (int done = 0; done < FINDINGS_PER_PASS;) {
    const int n = dds_take(s->finding_reader, ptr, info, 16, 16);
    if (n <= 0) break;
    done += n;
    palp_srv_session_stats st = {0};
    int have_st = 0;
    for (int i = 0; i < n; i++) {
      if (info[i].valid_data)
        offer_finding(srv, s, s->finding_reader, info[i].publication_handle, &buf[i], &st, &have_st);
      else if (info[i].instance_state == DDS_IST_NOT_ALIVE_DISPOSED && buf[i].session_id != s->id)
        s->finding_strays++; /* Cyclone fills an invalid sample's key */
    }
    if (n < 16) break;
  }
  const int64_t now = palp_dds_now_ns();
  if (palp_dds_strays_renew_due(s->finding_strays, now, s->finding_reader_renewed_ns)) renew_finding_reader(srv, s, now);
}

static void close_session(palp_srv *srv, palp_srv_session *s, const char *reason) {
  palp_srv_ticker_remove(srv->ticker, s);
  /* A mark the station sent just before it left still counts, in its log and its debrief. */
  handle_findings(srv, s);
  if (s->finding_rc > 0) dds_waitset_detach(srv->waitset, s->finding_rc);
  /* Before the CLOSED state, which a station waits on: the debrief is there when it looks. */
  if (publish_debrief(srv, s, reason) == (int)palp_DEBRIEF_LESIONS) expect_told_score(srv, s);
  release_session_exercise(srv, s);
  /* Detached: the stats are final and owned by this thread now. */
  palp_srv_session_summary sum;
  palp_srv_session_summary_fill(s, reason, palp_dds_now_ns(), &sum);
  publish_session_log(srv, s); /* its last count, before the CLOSED state its station ends on */
  publish_state(srv, s, 1, reason, &s->stats);
  publish_session_closed(srv, s, sum.duration, reason);
  remember_closed(srv, &sum, 0, s->trainee_request_seq);
  for (int r = 0; r < PALP_SRV_REJ_COUNT; r++) srv->rejected_closed[r] += s->stats.rejected[r];
  if (srv->events && srv->events->session_closed) srv->events->session_closed(srv->events->ctx, &sum);
  palp_log_info(srv->log, "session %u closed after %.1f s (%s)", s->id, sum.duration, reason);
  if (s->stats.rejected[PALP_SRV_REJ_FOREIGN_PARTICIPANT]) /* the writers were named as they came (session.c) */
    palp_log_warn(srv->log, "session %u: %llu contact samples refused in all from %llu writer%s not of the participant "
                            "that joined it (%s)",
                  s->id, (unsigned long long)s->stats.rejected[PALP_SRV_REJ_FOREIGN_PARTICIPANT],
                  (unsigned long long)s->contact_writers.foreign_writers,
                  s->contact_writers.foreign_writers == 1 ? "" : "s",
                  palp_srv_reject_name(PALP_SRV_REJ_FOREIGN_PARTICIPANT));
  if (s->findings_foreign)
    palp_log_warn(srv->log, "session %u: %llu findings refused unanswered in all from %llu writer%s not of the "
                            "participant that joined it (%s)",
                  s->id, (unsigned long long)s->findings_foreign,
                  (unsigned long long)s->finding_writers.foreign_writers,
                  s->finding_writers.foreign_writers == 1 ? "" : "s",
                  palp_srv_reject_name(PALP_SRV_REJ_FOREIGN_PARTICIPANT));
  if (s->session_log_shed + s->session_log_failed > 0) /* its own records (session 69); more may fail still queued */
    palp_log_warn(srv->log, "session %u: the session log lost %llu of its records while it ran (%llu shed, %llu failed): "
                            "its review will be incomplete",
                  s->id, (unsigned long long)(s->session_log_shed + s->session_log_failed),
                  (unsigned long long)s->session_log_shed, (unsigned long long)s->session_log_failed);
  if (s->deformations_sent > 0)
    palp_log_info(srv->log, "session %u: %llu deformation frames sent to its displays", s->id,
                  (unsigned long long)s->deformations_sent);
  palp_world_health h;
  palp_world_get_health(s->world, &h);
  /* Why ticks ran late, when they did: a tick that reached a rebuild's due frame before
   * the helper had finished it waited for it (docs/haptics.md), and how many rebuilds
   * were made on the tick because the factor reached its stability margin before its
   * due frame (palp_world_health.margin_rebuilds, ~0.5 ms each). */
  if (s->stats.overruns > 0 || s->stats.skipped > 0 || s->stats.factor_waits > 0)
    palp_log_info(srv->log, "session %u: %llu of %llu steps late (%llu of them slots skipped behind schedule); %llu "
                            "tangent rebuilds off the tick, %llu waited for (%.1f ms in all), %lld made on the tick "
                            "at the stability margin", s->id,
                  (unsigned long long)s->stats.overruns, (unsigned long long)(s->stats.ticks + s->stats.skipped),
                  (unsigned long long)s->stats.skipped,
                  (unsigned long long)s->stats.factor_jobs, (unsigned long long)s->stats.factor_waits,
                  (double)s->stats.factor_wait_ns * 1e-6, (long long)h.margin_rebuilds);
  /* What the network's jitter cost: the delay the device samples were played out at
   * (server/playout.h; none on a steady link). */
  uint64_t played = 0, late = 0, behind = 0, gaps = 0;
  double delay_max = 0, behind_max = 0;
  for (int i = 0; i < PALP_SRV_MAX_FINGERS; i++) {
    const palp_srv_playout *p = &s->finger[i].playout;
    played += p->samples, late += p->late, behind += p->behind_steps, gaps += p->gaps;
    if (p->delay_max > delay_max) delay_max = p->delay_max;
    if (p->behind_max > behind_max) behind_max = p->behind_max;
  }
  if (delay_max > 0)
    palp_log_info(srv->log, "session %u: the station's device points came with jitter and were played out up to "
                            "%.1f ms late; %llu of %llu came after their turn and were bridged", s->id,
                  delay_max * 1e3, (unsigned long long)late, (unsigned long long)played);
  /* What the gaps in them cost (a stalled station or server; playout.h, "A gap is caught up"), and
   * the fingers placed below the surface and brought in (session.c, entry_point). */
  /* Said when a gap of 50 ms or more was (a loaded link's sample a step late is caught up too). */
  if (gaps > 0 || s->stats.entries > 0)
    palp_log_info(srv->log, "session %u: %llu gap(s) in the station's device points (a stalled station or server) "
                            "caught up over %llu steps, up to %.0f ms behind, the finger never more than twice as fast "
                            "as the hand (lags over 0.5 s shrinking by e^-1 every 0.25 s); %llu finger(s) placed below "
                            "the surface brought in from it", s->id, (unsigned long long)gaps, (unsigned long long)behind,
                  behind_max * 1e3, (unsigned long long)s->stats.entries);
  /* Where the model's answers were extrapolations (the stations were told each step,
   * LM_LARGE_STRAIN; docs/model.md, "Valid range"). */
  if (h.large_strain_steps > 0 || h.large_bend_steps > 0)
    palp_log_info(srv->log, "session %u: beyond the model's valid range at %lld steps by a link's strain (largest "
                            "%.2f) and %lld by the skin's bending (largest hinge miss %.3f rad)", s->id,
                  (long long)h.large_strain_steps, h.max_strain, (long long)h.large_bend_steps, h.max_bend_error);
  /* and where a fingertip pressed deeper than the parameters were validated against the FE
   * (LM_BEYOND_VALIDATED) */
  if (h.beyond_validated_steps > 0)
    palp_log_info(srv->log, "session %u: a fingertip deeper than the phantom's parameters were validated against the FE "
                            "at %lld steps (by up to %.1f mm)", s->id, (long long)h.beyond_validated_steps,
                  1e3 * h.max_beyond_validated);
  /* and where the literal gel law met steps outside its stable range and left its momentum term
   * out (LM_GEL_LAW_RANGE; the session log's valid_range events count its frames) */
  if (h.gel_momentum_dropped > 0)
    palp_log_info(srv->log, "session %u: the literal gel law's momentum term left out at %lld frames in all (steps or "
                            "their halves with a3 / (h h_prev) outside (-1/2, 1))", s->id,
                  (long long)h.gel_momentum_dropped);
  /* Its members' slots are free again; its state instance is released after
   * the retention time, once every member has read the CLOSED state. */
  for (int i = 0; i < srv->station_slots; i++)
    if (srv->stations[i].in_use && srv->stations[i].session_id == s->id) free_station(srv, &srv->stations[i]);
  retire_state(srv, s->id);
  for (int i = 0; i < srv->session_count; i++)
    if (srv->sessions[i] == s) {
      srv->sessions[i] = srv->sessions[--srv->session_count];
      break;
    }
  palp_srv_phantom *ph = s->phantom;
  const int64_t t0 = palp_dds_now_ns();
  palp_srv_session_destroy(s);
  const double took = (double)(palp_dds_now_ns() - t0) * 1e-9;
  if (took > srv->close_longest_s) srv->close_longest_s = took;
  publish_catalogue(srv, ph);
}

/* A station accepted by request rq into s: what it asked for is counted in the session
 * (a viewer's join, a held trainee's return). */
static void attach_station(palp_srv_session *s, station *st, const palp_SessionRequest *rq) {
  st->role = (int)rq->role;
  st->session_id = s->id;
  st->request_seq = rq->request_seq;
  st->want_feedback = rq->want_feedback;
  st->want_deformation = rq->want_deformation;
  if (st->want_deformation) atomic_fetch_add(&s->deform_members, 1);
  if (st->want_feedback) atomic_fetch_add(&s->want_feedback, 1);
}

/* Its trainee station's lease lapsed: the station is forgotten (its slot freed), the
 * session kept open until station_grace has passed. Its fingers are lifted by the tick
 * thread, which sees their writer gone too (session.c, take_contacts). */
static void hold_session(palp_srv *srv, palp_srv_session *s, station *st, const char *why) {
  const int64_t now = palp_dds_now_ns();
  s->held_since_ns = now;
  snprintf(s->held_reason, sizeof s->held_reason, "%s", why);
  if (st->want_deformation) atomic_fetch_sub(&s->deform_members, 1);
  if (st->want_feedback) atomic_fetch_sub(&s->want_feedback, 1);
  palp_log_info(srv->log, "session %u: %s; held %.0f s for it to come back with its request", s->id, why,
                srv->cfg.station_grace);
  if (srv->events && srv->events->member_changed) /* after its log line, as station_leave */
    srv->events->member_changed(srv->events->ctx, s->id, st->id, palp_ROLE_TRAINEE, 0);
  free_station(srv, st);
  publish_state(srv, s, 0, NULL, NULL);
}

/* A held session's trainee station asked again with the request that opened it: it was
 * stalled, not gone, and the session goes on where it was. */
static void resume_session(palp_srv *srv, palp_srv_session *s, const palp_SessionRequest *rq, uint64_t writer) {
  station *st = new_station(srv, rq->station_id, writer);
  if (!st) { /* cannot happen: its slot was freed when it was held */
    close_session(srv, s, s->held_reason);
    return;
  }
  attach_station(s, st, rq);
  const double away = (double)(palp_dds_now_ns() - s->held_since_ns) * 1e-9;
  s->held_since_ns = 0;
  s->held_reason[0] = 0;
  reply(srv, rq, s, NULL);
  publish_state(srv, s, 0, NULL, NULL);
  palp_log_info(srv->log, "session %u: trainee station %s came back after %.1f s; the session goes on", s->id,
                PALP_PRINTABLE(st->id), away);
  if (srv->events && srv->events->member_changed) /* after its log line, as station_leave */
    srv->events->member_changed(srv->events->ctx, s->id, st->id, palp_ROLE_TRAINEE, 1);
}

/* The open session held for this trainee station, or NULL. */
static palp_srv_session *held_session_of(palp_srv *srv, const char *station_id) {
  for (int i = 0; i < srv->session_count; i++)
    if (srv->sessions[i]->held_since_ns && strcmp(srv->sessions[i]->trainee_station, station_id) == 0)
      return srv->sessions[i];
  return NULL;
}

/* A LEAVE from a station with no slot, whose session is held for it: it came back only to
 * say goodbye (stopped by its user right after a stall). 1 when there was one. */
/* Plain DDS: whether `writer` on `reader` is of participant p (its GUID into *sender, *sender_known,
 * when Cyclone still knows the writer; a writer already gone is of none). */
static int writer_of(dds_entity_t reader, uint64_t writer, const dds_guid_t *p, dds_guid_t *sender,
                     int *sender_known) {
  *sender_known = 0;
  dds_builtintopic_endpoint_t *ep = dds_get_matched_publication_data(reader, writer);
  if (!ep) return 0;
  *sender = ep->participant_key, *sender_known = 1;
  dds_builtintopic_free_endpoint(ep);
  return !memcmp(sender->v, p->v, sizeof p->v);
}

/* Says why a request for a station (or its held session) from another participant than the one that
 * joined it is refused, unanswered: a reply to this station id would land on the station itself. what:
 * what was done, before its sender ("LEAVE from", "disposed or unregistered by"). */
static void refuse_foreign_request(palp_srv *srv, const char *what, const char *station_id, uint32_t session_id,
                                   const dds_guid_t *sender, int sender_known) {
  char who[64] = "a writer already gone";
  if (sender_known) palp_dds_participant_text(sender, who, sizeof who);
  refuse_identity(srv, "station \"%s\" (session %u): %s %s, which did not join it; the station stays "
                       "(plain DDS: anyone may write requests; run the classroom with DDS Security)",
                  PALP_PRINTABLE(station_id), session_id, what, who);
}

/* A LEAVE for a station whose session is held: the held session closes. On plain DDS only from the
 * participant whose JOIN opened it (refused, said, otherwise: 1 as handled). */
static int leave_held(palp_srv *srv, const char *station_id, dds_entity_t reader, uint64_t writer) {
  palp_srv_session *h = held_session_of(srv, station_id);
  if (!h) return 0;
  dds_guid_t sender;
  int sender_known;
  if (!secured(srv) && !writer_of(reader, writer, &h->trainee_participant, &sender, &sender_known)) {
    refuse_foreign_request(srv, "LEAVE from", station_id, h->id, &sender, sender_known);
    return 1;
  }
  close_session(srv, h, "trainee station left");
  return 1;
}

/* The station leaves whatever it is in: a trainee's session closes (or, lost, is held),
 * a viewer only stops being counted. */
static void station_leave(palp_srv *srv, station *st, const char *reason) {
  palp_srv_session *s = st->session_id ? find_session(srv, st->session_id) : NULL;
  uint32_t sid = st->session_id;
  int role = st->role;
  if (!s) {
    free_station(srv, st);
    return;
  }
  if (role == palp_ROLE_TRAINEE && strcmp(s->trainee_station, st->id) == 0) {
    char why[160];
    snprintf(why, sizeof why, "trainee station %s", reason);
    /* A lapsed lease cannot tell a crash from a stall (a machine swapping, a core taken
     * for a second): the session waits station_grace for the same request again. */
    if (srv->cfg.station_grace > 0 && strncmp(reason, "lost", 4) == 0) {
      hold_session(srv, s, st, why);
      return;
    }
    close_session(srv, s, why); /* frees st with the session's other members */
    return;
  }
  if (st->want_deformation) atomic_fetch_sub(&s->deform_members, 1);
  if (st->want_feedback) atomic_fetch_sub(&s->want_feedback, 1);
  /* At the level of its join (who followed a session, and until when, is the instructor's to read).
   * Logged before the event is told, so that whoever reacts to the event finds the line written (until
   * 2026-12-07 the other way round: server_rewritten read the log between the two, once in a full run). */
  palp_log_info(srv->log, "station %s (%s) left session %u: %s", PALP_PRINTABLE(st->id),
                role == palp_ROLE_VISUAL ? "visual" : "observer", sid, reason);
  if (srv->events && srv->events->member_changed) srv->events->member_changed(srv->events->ctx, sid, st->id, role, 0);
  free_station(srv, st); /* after its last read */
  publish_state(srv, s, 0, NULL, NULL);
}

/* With other servers on the domain, a request for a phantom or session this server
 * does not hold is theirs: no reply (two replies to one station would race). Alone,
 * the server rejects it with a reason, as it always did. */
static int not_mine(const palp_srv *srv, const palp_SessionRequest *rq) {
  char ignored[256]; /* a conflict is acted on by palp_srv_run's next poll */
  palp_srv_identity_poll(srv->identity, ignored, sizeof ignored);
  if (!palp_srv_identity_peers(srv->identity)) return 0;
  if (rq->role != palp_ROLE_TRAINEE && rq->session_id)
    return PALP_DDS_ID_SERVER(rq->session_id) != srv->cfg.server_number;
  return find_phantom((palp_srv *)srv, rq->phantom_id) == NULL;
}

/* A reply (a refusal, a "left") to a station that holds no slot: its transient-local instance is
 * released after the retention time, since nothing else ever would (free_station does it for a
 * station that held one). Every such reply goes through here: until session 75 a LEAVE for an
 * unknown station on palp_station_request left its reply instance behind for good. */
static void reply_unslotted(palp_srv *srv, const palp_SessionRequest *rq, const char *why) {
  reply(srv, rq, NULL, why);
  if (!find_station(srv, rq->station_id)) retire_reply(srv, rq->station_id);
}

/* A refused join: answered, counted, and its reply released after the retention time. */
static void refuse(palp_srv *srv, const palp_SessionRequest *rq, uint64_t *counter, const char *why) {
  (*counter)++;
  reply_unslotted(srv, rq, why);
}

/* The participant that joined station st, if the server knows it: looked up at its JOIN on plain DDS
 * (learn_participant), or, for a trainee, its session's (the participant whose JOIN opened it). */
static int station_participant(palp_srv *srv, const station *st, dds_guid_t *out) {
  if (st->participant_known) return *out = st->participant, 1;
  const palp_srv_session *s = st->role == palp_ROLE_TRAINEE ? find_session(srv, st->session_id) : NULL;
  if (s) *out = s->trainee_participant;
  return s != NULL;
}

/* Plain DDS: whether a request (LEAVE, or JOIN again) for station st taken from `writer` on `reader`
 * is the station's own. Its own request writer's, or another writer of the participant that joined it
 * (found by Cyclone's discovery data); one from a writer already gone that is not the station's cannot
 * be told apart from a forgery, and is refused. Until 2026-12-07 anyone on the domain who knew a
 * station's id (the server's log, a session's viewers) ended its session with one LEAVE; and, LEAVEs
 * checked, until session 80 with one JOIN under its id (another request number: "re-joined"), or took
 * the station over with its own JOIN replayed (then its LEAVE counted, the station's own not). */
static int request_is_own(palp_srv *srv, const station *st, dds_entity_t reader, uint64_t writer,
                          dds_guid_t *sender, int *sender_known) {
  *sender_known = 0;
  if (writer == st->writer) return 1;
  dds_guid_t joined;
  if (!station_participant(srv, st, &joined)) return 1; /* nothing to check against: as before */
  return writer_of(reader, writer, &joined, sender, sender_known);
}

/* A LEAVE: the station leaves what it is in (its slot freed, which schedules its reply's release),
 * or the session held for it closes. Answered "left", and alone on the domain also when there was
 * nothing to leave (with other servers, that request may be theirs).
 * On plain DDS only the station's own participant's LEAVE counts (request_is_own). */
static void handle_leave(palp_srv *srv, const palp_SessionRequest *rq, dds_entity_t reader, uint64_t writer) {
  station *st = find_station(srv, rq->station_id);
  dds_guid_t sender;
  int sender_known;
  if (st && !secured(srv) && !request_is_own(srv, st, reader, writer, &sender, &sender_known)) {
    refuse_foreign_request(srv, "LEAVE from", rq->station_id, st->session_id, &sender, sender_known);
    return;
  }
  if (st) {
    station_leave(srv, st, "left"); /* frees its slot: free_station retired its reply */
    reply(srv, rq, NULL, "left");
  } else if (leave_held(srv, rq->station_id, reader, writer) || !palp_srv_identity_peers(srv->identity)) {
    reply_unslotted(srv, rq, "left");
  }
}

/* The participant of a visual station's request writer, for its session's findings (visual_of_session).
 * One lookup per admitted JOIN (join_rate bounds them). */
static void learn_participant(station *st, dds_entity_t reader, uint64_t writer) {
  dds_builtintopic_endpoint_t *ep = dds_get_matched_publication_data(reader, writer);
  st->participant_known = ep != NULL;
  if (ep) {
    st->participant = ep->participant_key;
    dds_builtintopic_free_endpoint(ep);
  }
}

/* who: the authenticated sender (secured), NULL on plain DDS; writer: its
 * publication handle on `reader` (palp_session_request's or palp_station_request's). */
static void handle_join(palp_srv *srv, const palp_SessionRequest *rq, const palp_srv_requester *who,
                        dds_entity_t reader, uint64_t writer) {
  char why[128];
  guard_counts *g = &srv->guard;
  if (rq->role > palp_ROLE_OBSERVER) {
    refuse(srv, rq, &g->joins_refused_other, "unknown role");
    return;
  }
  if (who && who->kind == PALP_DDS_ID_INSTRUCTOR && rq->role == palp_ROLE_TRAINEE) {
    refuse(srv, rq, &g->joins_refused_other,
           "an instructor identity follows sessions; palpating needs a trainee identity");
    return;
  }
  /* The same request again (a station back from a stall sends it once more, and DDS
   * re-delivers it when the station's participant is found again): answered again, not
   * redone, so it neither opens a second session nor takes a join token. */
  station *again = find_station(srv, rq->station_id);
  /* Plain DDS: a JOIN under a live station's id from another participant is not the station's: it
   * would have ended its session ("re-joined") or, replayed, taken the station over (session 80's
   * review, 2026-12-07). Secured, handle_requests checked the sender owns the id. */
  dds_guid_t sender;
  int sender_known;
  if (again && !secured(srv) && !request_is_own(srv, again, reader, writer, &sender, &sender_known)) {
    refuse_foreign_request(srv, "JOIN from", rq->station_id, again->session_id, &sender, sender_known);
    return;
  }
  palp_srv_session *cur = again && again->request_seq == rq->request_seq && again->role == (int)rq->role
                              ? find_session(srv, again->session_id)
                              : NULL;
  if (cur) {
    /* From another writer: the station's participant was lost and found again, and Cyclone, which gave
     * its writer a new handle, re-delivers the JOIN (its new sample wipes the pending not-alive one, so
     * this JOIN is all the server sees). The station is that writer's now: left at the old handle, the
     * old writer's unmatch made sweep_gone_writers declare a live station lost (until 2026-12-06).
     * Secured, the sender was checked to own this station id before any JOIN (handle_requests). A
     * writer already at stations_per_writer takes no more: that bound holds however a station came. */
    if (again->writer != writer && stations_of_writer(srv, writer) < srv->cfg.stations_per_writer) {
      again->writer = writer;
      if (!secured(srv)) learn_participant(again, reader, writer);
    }
    reply(srv, rq, cur, NULL);
    return;
  }
  /* A held session's station id is the held trainee's whatever the role asked: an observer's JOIN
   * under it made the trainee's own JOIN miss its resume. */
  palp_srv_session *held = !again ? held_session_of(srv, rq->station_id) : NULL;
  if (held && !secured(srv) && !writer_of(reader, writer, &held->trainee_participant, &sender, &sender_known)) {
    refuse_foreign_request(srv, "JOIN from", rq->station_id, held->id, &sender, sender_known);
    return;
  }
  if (held && rq->role != palp_ROLE_TRAINEE) held = NULL; /* as before: only a trainee's JOIN resumes or ends it */
  if (held && held->trainee_request_seq == rq->request_seq && held->phantom->cfg.id == rq->phantom_id) {
    resume_session(srv, held, rq, writer);
    return;
  }
  if (held) /* back with another request: the held session ends as it would have */
    close_session(srv, held, held->held_reason);
  const closed_session *done = rq->role == palp_ROLE_TRAINEE && !again && !held
                                   ? closed_by_request(srv, rq->station_id, rq->request_seq)
                                   : NULL;
  if (done) {
    snprintf(why, sizeof why, "session %u closed: %.80s", done->sum.info.session_id, done->reason);
    reply_unslotted(srv, rq, why);
    return;
  }
  if (!palp_srv_admission_join_token(srv->admission, palp_dds_now_ns())) {
    snprintf(why, sizeof why, "server busy: joins are limited to %g per second (join_rate); try again",
             srv->cfg.join_rate);
    refuse(srv, rq, &g->joins_refused_rate, why);
    return;
  }
  station *st = find_station(srv, rq->station_id);
  if (st) station_leave(srv, st, "re-joined"); /* frees its slot; taken again below if accepted */
  if (stations_of_writer(srv, writer) >= srv->cfg.stations_per_writer) {
    snprintf(why, sizeof why, "too many stations from one writer (stations_per_writer %d)",
             srv->cfg.stations_per_writer);
    refuse(srv, rq, &g->joins_refused_writer, why);
    return;
  }
  palp_srv_session *s = NULL;
  if (rq->role == palp_ROLE_TRAINEE) {
    palp_srv_phantom *ph = find_phantom(srv, rq->phantom_id);
    if (!ph && not_mine(srv, rq)) return;
    if (!ph) {
      snprintf(why, sizeof why, "unknown phantom %u", rq->phantom_id);
      refuse(srv, rq, &g->joins_refused_other, why);
      return;
    }
    if (srv->session_count >= srv->cfg.max_sessions) {
      snprintf(why, sizeof why, "server full: %d sessions open (max_sessions)", srv->session_count);
      refuse(srv, rq, &g->joins_refused_other, why);
      return;
    }
    /* The session is bound to the participant whose request writer JOINed it: only that participant's
     * contacts reach its world (server/session.c, take_contacts). A writer no longer matched has no
     * participant to bind to, and a session bound to none would refuse its station's every contact,
     * or (unbound) take anyone's: the JOIN is dropped unanswered, as a secured request whose writer's
     * identity is gone is (handle_requests). A station that lives was only lost for a moment: Cyclone
     * re-delivers its (transient-local) JOIN when it finds the station again, with a new handle, and
     * that one is answered. */
    dds_builtintopic_endpoint_t *joiner = dds_get_matched_publication_data(reader, writer);
    if (!joiner) {
      g->joins_refused_other++;
      palp_log_warn(srv->log, "station %s: JOIN not answered: its request writer is already gone, so the session "
                              "would have no participant to take contacts from",
                    PALP_PRINTABLE(rq->station_id));
      return;
    }
    const dds_guid_t trainee_participant = joiner->participant_key;
    dds_builtintopic_free_endpoint(joiner);
    /* Secured, the partition carries the trainee's identity, so that only its
     * permissions (palp/s/NAME/...) allow writing contacts into it. */
    char partition[64] = "";
    if (who) palp_dds_secure_session_partition(who->name, srv->next_session_id, partition, sizeof partition);
    palp_srv_session_def d = {.id = srv->next_session_id,
                              .trainee_participant = trainee_participant,
                              .phantom = ph,
                              .cfg = &srv->cfg,
                              .trainee_station = rq->station_id,
                              .trainee_name = rq->user_name,
                              .participant = srv->pp,
                              .contact_topic = srv->topic[PALP_TOPIC_CONTACT],
                              .feedback_topic = srv->topic[PALP_TOPIC_FEEDBACK],
                              .deformation_topic = srv->topic[PALP_TOPIC_DEFORMATION],
                              .local_model_topic = srv->topic[PALP_TOPIC_LOCAL_MODEL],
                              .finding_topic = srv->topic[PALP_TOPIC_FINDING],
                              .finding_status_topic = srv->topic[PALP_TOPIC_FINDING_STATUS],
                              .debrief_topic = srv->topic[PALP_TOPIC_DEBRIEF],
                              .session_log_topic = srv->topic[PALP_TOPIC_SESSION_LOG],
                              .finger_sample_topic = srv->topic[PALP_TOPIC_FINGER_SAMPLE],
                              .events = srv->events,
                              .partition = partition,
                              .log = srv->log,
                              .reaper = srv->reaper,
                              .placement_seed = placement_seed(srv->placement_key, srv->next_session_id)};
    int rc = 0;
    char refusal[200] = "";
    d.refusal = refusal, d.refusal_len = sizeof refusal;
    s = palp_srv_session_create(&d, &rc);
    if (!s) {
      snprintf(why, sizeof why, "cannot create the session: %s", refusal[0] ? refusal : palp_strerror(rc));
      refuse(srv, rq, &g->joins_refused_other, why);
      return;
    }
    st = new_station(srv, rq->station_id, writer);
    if (!st) { /* cannot happen while slots = max_sessions x (1 + max_viewers) */
      palp_srv_session_destroy(s);
      refuse(srv, rq, &g->joins_refused_other, "too many stations");
      return;
    }
    st->role = (int)rq->role;
    st->request_seq = rq->request_seq;
    s->trainee_request_seq = rq->request_seq;
    st->want_feedback = rq->want_feedback;
    st->want_deformation = rq->want_deformation;
    atomic_store(&s->want_feedback, rq->want_feedback ? 1 : 0);
    atomic_store(&s->deform_members, rq->want_deformation ? 1 : 0);
    /* The log learns of the session before its first tick can report on it. */
    palp_srv_session_info info;
    palp_srv_session_info_fill(s, &info);
    if (srv->events && srv->events->session_opened) srv->events->session_opened(srv->events->ctx, &info);
    if (palp_srv_ticker_add_rate(srv->ticker, s, ph->cfg.physics_rate_hz) < 0) {
      palp_srv_session_summary sum;
      palp_srv_session_summary_fill(s, "tick pool full", palp_dds_now_ns(), &sum);
      if (srv->events && srv->events->session_closed) srv->events->session_closed(srv->events->ctx, &sum);
      palp_srv_session_destroy(s);
      st->in_use = 0;
      refuse(srv, rq, &g->joins_refused_other, "tick pool full");
      return;
    }
    publish_session_exercise(srv, s, info.exercise_name, info.exercise_json);
    publish_session_log(srv, s);
    srv->sessions_total++;
    srv->sessions[srv->session_count++] = s;
    next_session_id(srv); /* past s's own id too */
    if (s->finding_rc > 0) dds_waitset_attach(srv->waitset, s->finding_rc, 0);
    publish_finding_status(s);
    st->session_id = s->id;
    reply(srv, rq, s, NULL);
    publish_state(srv, s, 0, NULL, NULL);
    publish_catalogue(srv, ph);
    palp_log_info(srv->log, "session %u opened: trainee \"%s\" (%s) on phantom %u \"%s\", partition %s",
            s->id, PALP_PRINTABLE(s->trainee_name), PALP_PRINTABLE(s->trainee_station), ph->cfg.id, ph->cfg.name,
            PALP_PRINTABLE(s->partition));
    return;
  }
  /* Visual station or observer: a given session, else the newest on the phantom.
   * Secured, a trainee identity may follow only its own sessions (its
   * permissions would not let it read another's anyway); an instructor any. */
  const char *only = who && who->kind == PALP_DDS_ID_TRAINEE ? who->name : NULL;
  if (rq->session_id) {
    s = find_session(srv, rq->session_id);
    if (s && only && strcmp(s->trainee_name, only) != 0) {
      snprintf(why, sizeof why, "session %u belongs to another trainee", rq->session_id);
      reply_unslotted(srv, rq, why);
      return;
    }
  } else {
    for (int i = 0; i < srv->session_count; i++) {
      palp_srv_session *c = srv->sessions[i];
      if (only && strcmp(c->trainee_name, only) != 0) continue;
      if ((rq->phantom_id == 0 || c->phantom->cfg.id == rq->phantom_id) && (!s || c->id > s->id)) s = c;
    }
  }
  if (!s && not_mine(srv, rq)) return;
  if (!s) {
    if (rq->session_id)
      snprintf(why, sizeof why, "no open session %u", rq->session_id);
    else
      snprintf(why, sizeof why, "no open session on phantom %u", rq->phantom_id);
    refuse(srv, rq, &g->joins_refused_other, why);
    return;
  }
  uint32_t visual, observer;
  member_counts(srv, s->id, &visual, &observer);
  if ((int)(visual + observer) >= srv->cfg.max_viewers) {
    snprintf(why, sizeof why, "session %u already has %u viewers (max_viewers)", s->id, visual + observer);
    refuse(srv, rq, &g->joins_refused_viewers, why);
    return;
  }
  st = new_station(srv, rq->station_id, writer);
  if (!st) {
    refuse(srv, rq, &g->joins_refused_other, "too many stations");
    return;
  }
  attach_station(s, st, rq);
  if (!secured(srv)) learn_participant(st, reader, writer);
  reply(srv, rq, s, NULL);
  publish_state(srv, s, 0, NULL, NULL);
  palp_log_info(srv->log, "station %s joined session %u as %s", PALP_PRINTABLE(st->id), s->id,
                rq->role == palp_ROLE_VISUAL ? "visual station" : "observer");
  if (srv->events && srv->events->member_changed) /* after its log line, as station_leave */
    srv->events->member_changed(srv->events->ctx, s->id, st->id, st->role, 1);
}

/* A request instance that turned not-alive while its writer is still matched was
 * disposed on purpose: a goodbye (dispose alone is enough, as for any DDS entity).
 * A writer that is gone (lease expired) means the station vanished. */
static void on_station_liveliness(dds_entity_t reader, const dds_liveliness_changed_status_t st, void *arg) {
  (void)reader;
  palp_srv *srv = arg;
  if ((st.not_alive_count_change > 0 || st.alive_count_change < 0) && st.last_publication_handle) {
    pthread_mutex_lock(&srv->lost_mu);
    srv->lost[srv->lost_n++ % 64] = st.last_publication_handle;
    pthread_mutex_unlock(&srv->lost_mu);
  }
}

static int station_writer_lost(palp_srv *srv, dds_instance_handle_t w) {
  int lost = 0;
  pthread_mutex_lock(&srv->lost_mu);
  for (unsigned i = 0; i < 64 && i < srv->lost_n; i++) lost |= srv->lost[i] == w;
  pthread_mutex_unlock(&srv->lost_mu);
  return lost;
}

/* Whether `writer` is matched with `reader` now, asked alone: Cyclone walks the reader's matched writers and
 * copies the one found's QoS. matched_has's way when it has no set. */
static int writer_matched(dds_entity_t reader, uint64_t writer) {
  dds_builtintopic_endpoint_t *w = dds_get_matched_publication_data(reader, writer);
  if (!w) return 0;
  dds_builtintopic_free_endpoint(w);
  return 1;
}

/* Cyclone 0.10 reports a dispose and a writer whose liveliness lapsed (autodispose)
 * alike, as a disposed instance, and unregisters the lapsed writer's instances just
 * before it calls the liveliness listener. So a disposed instance is a goodbye only
 * if its writer is still matched and, a moment later, has not lost its liveliness.
 * That moment is not slept on (until session 75 it was, 50 ms on the main thread per
 * dispose: a peer joining and disposing at join_rate stalled every session's requests,
 * findings and time limits): the station is marked, and decide_gone_stations judges
 * it GONE_GRACE_NS later. Returns whether it was marked; else it is lost now. */
static int station_gone_later(palp_srv *srv, station *st, const dds_sample_info_t *info) {
  if (info->instance_state != DDS_IST_NOT_ALIVE_DISPOSED || !info->publication_handle) return 0;
  if (!writer_matched(srv->station_request_r, info->publication_handle)) return 0;
  if (!st->gone_due_ns) st->gone_due_ns = palp_dds_now_ns() + GONE_GRACE_NS;
  st->gone_writer = info->publication_handle;
  return 1;
}

/* Judges one marked station now: lost if its writer's liveliness lapsed meanwhile, else it left. */
static void decide_gone(palp_srv *srv, station *st) {
  const int lost = station_writer_lost(srv, st->gone_writer);
  st->gone_due_ns = 0;
  station_leave(srv, st, lost ? "lost (liveliness lease expired)" : "left (request disposed)"); /* frees its slot */
}

/* The marked stations whose moment has passed (all of them when now_ns is INT64_MAX). */
static void decide_gone_stations(palp_srv *srv, int64_t now_ns) {
  for (int i = 0; i < srv->station_slots; i++) {
    station *st = &srv->stations[i];
    if (st->in_use && st->gone_due_ns && st->gone_due_ns <= now_ns) decide_gone(srv, st);
  }
}

/* The earliest moment a marked station is due (INT64_MAX: none), so the main loop wakes for it. */
static int64_t next_gone_due(const palp_srv *srv) {
  int64_t due = INT64_MAX;
  for (int i = 0; i < srv->station_slots; i++) {
    const station *st = &srv->stations[i];
    if (st->in_use && st->gone_due_ns && st->gone_due_ns < due) due = st->gone_due_ns;
  }
  return due;
}

/* A reader's matched writers as one sweep sees them: read at the first question (after the admission table's
 * writers were copied, and after every station it asks about joined, so every writer of theirs that lives is
 * in it), sorted, and each question a binary search. Until 2026-12-06 each table writer and each station was
 * asked alone (writer_matched), (table writers + stations) x matched writers steps a sweep. */
typedef struct matched_set {
  palp_srv *srv;
  dds_entity_t reader;
  int loaded, alone; /* alone: the set could not be had (an error, no memory): writers asked alone */
  size_t n;
} matched_set;

static int cmp_handle(const void *a, const void *b) {
  const dds_instance_handle_t x = *(const dds_instance_handle_t *)a, y = *(const dds_instance_handle_t *)b;
  return (x > y) - (x < y);
}

static void matched_load(matched_set *m) {
  palp_srv *srv = m->srv;
  m->loaded = 1;
  for (;;) {
    const dds_return_t n = dds_get_matched_publications(m->reader, srv->matched, srv->matched_cap);
    if (n < 0) {
      m->alone = 1;
      return;
    }
    if ((size_t)n <= srv->matched_cap) {
      m->n = (size_t)n;
      break;
    }
    /* More than last time: room with some to spare, and asked again (more may have matched meanwhile). */
    const size_t cap = (size_t)n + (size_t)n / 2 + 16;
    dds_instance_handle_t *h = realloc(srv->matched, cap * sizeof *h);
    if (!h) {
      m->alone = 1;
      return;
    }
    srv->matched = h, srv->matched_cap = cap;
  }
  qsort(srv->matched, m->n, sizeof *srv->matched, cmp_handle);
}

/* Whether `writer` is in the set *arg (palp_srv_admission_sweep's `matched`). */
static int matched_has(uint64_t writer, void *arg) {
  matched_set *m = arg;
  if (!m->loaded) matched_load(m);
  if (m->alone) return writer_matched(m->reader, writer);
  const dds_instance_handle_t key = writer;
  return bsearch(&key, m->srv->matched, m->n, sizeof key, cmp_handle) != NULL;
}

/* Whether the reader lost matched writers since the last call (its status' changes are read, and so
 * reset, only here): total_count_change counts new matches, current_count_change new matches less
 * lost ones. */
static int writers_unmatched(dds_entity_t reader) {
  dds_subscription_matched_status_t ms;
  return dds_get_subscription_matched_status(reader, &ms) == 0 &&
         (int64_t)ms.total_count_change - ms.current_count_change > 0;
}

static void handle_request_sample(palp_srv *srv, palp_SessionRequest *rq, dds_entity_t reader, uint64_t writer,
                                  station **out_st) {
  /* A station marked gone that asks again: its dispose is judged first, as it was before this
   * sample when the server slept on it. */
  station *marked = find_station(srv, rq->station_id);
  if (marked && marked->gone_due_ns) decide_gone(srv, marked);
  if (rq->op == palp_OP_JOIN) {
    handle_join(srv, rq, NULL, reader, writer); /* palp_station_request is not offered when secured */
    /* the station this writer's JOIN made or kept: one refused (another participant's) keeps its own
     * key instance, never the refused writer's */
    station *st = find_station(srv, rq->station_id);
    if (out_st) *out_st = st && st->writer == writer ? st : NULL;
    return;
  }
  handle_leave(srv, rq, reader, writer);
  if (out_st) *out_st = NULL;
}

/* palp_station_request: the same requests, keyed by 8 bytes (docs/interop.md). */
static void handle_station_requests(palp_srv *srv) {
  enum { N = 16 };
  palp_StationRequest buf[N];
  void *ptr[N];
  dds_sample_info_t info[N];
  for (int i = 0; i < N; i++) ptr[i] = &buf[i];
  int n, taken = 0;
  /* A writer gone: its request instances leave the table (admission.h), and only then. */
  if (srv->station_request_r > 0 && writers_unmatched(srv->station_request_r)) {
    matched_set m = {.srv = srv, .reader = srv->station_request_r};
    palp_srv_admission_sweep(srv->station_admission, matched_has, &m);
  }
  while (srv->station_request_r > 0 && taken < REQUESTS_PER_PASS &&
         (n = dds_take(srv->station_request_r, ptr, info, N, N)) > 0) {
    taken += n;
    for (int i = 0; i < n; i++) {
      if (info[i].valid_data) {
        const palp_StationRequest *s = &buf[i];
        palp_SessionRequest rq;
        memset(&rq, 0, sizeof rq);
        snprintf(rq.station_id, sizeof rq.station_id, "%s", s->station_id);
        rq.request_seq = s->request_seq;
        rq.op = s->op;
        rq.role = s->role;
        rq.phantom_id = s->phantom_id;
        rq.session_id = s->session_id;
        snprintf(rq.user_name, sizeof rq.user_name, "%s", s->user_name);
        rq.want_feedback = s->want_feedback;
        rq.want_deformation = s->want_deformation;
        station *st = NULL;
        handle_request_sample(srv, &rq, srv->station_request_r, info[i].publication_handle, &st);
        if (st) {
          st->keyed = 1;
          st->ih = info[i].instance_handle;
        }
        continue;
      }
      if (info[i].instance_state == DDS_IST_ALIVE) continue;
      /* The instance is gone, but not necessarily its writer, which keeps its admission until it
       * goes (admission.h). By instance handle: once its last sample is taken, a "no writers"
       * instance may be gone, and its key with it. */
      for (int k = 0; k < srv->station_slots; k++) {
        station *st = &srv->stations[k];
        if (!st->in_use || !st->keyed || st->ih != info[i].instance_handle) continue;
        if (!station_gone_later(srv, st, &info[i])) station_leave(srv, st, "lost (liveliness lease expired)");
      }
    }
    if (n < N) break;
  }
}

/* A dispose of a request key no admitted request holds (never written, or written by a writer past its
 * stations_per_writer, whose request the filter refused) passes the admission filter (it carries no data) and
 * is an instance of the request reader for as long as its writer lives (~0.6 kB: 40,000 grew a
 * server by 23 MB, 2026-12-06). Neither an instance bound (a reliable reader refusing one stalls
 * delivery) nor a new reader (requests are transient-local: the writer's history hands it every
 * disposed key again) can stop it, so the server says so and names the writer's identity, which
 * the instructor can revoke and whose machine she can stop: once when one writer's count reaches
 * PALP_DDS_STRAYS_MIN, then at most every log_interval while it goes on. */
static void note_request_stray(palp_srv *srv, dds_instance_handle_t writer) {
  atomic_fetch_add(&srv->request_strays, 1);
  if (writer != srv->stray_writer) srv->stray_writer = writer, srv->stray_writer_count = 0;
  if (++srv->stray_writer_count < PALP_DDS_STRAYS_MIN) return;
  const int64_t now = palp_dds_now_ns();
  if (srv->stray_said_ns && now - srv->stray_said_ns < (int64_t)(srv->cfg.log_interval * 1e9)) return;
  srv->stray_said_ns = now;
  palp_srv_requester who;
  char by[96];
  if (secured(srv) && palp_srv_requester_of(srv->request_r, writer, &who) == 0)
    snprintf(by, sizeof by, "%s/%s", palp_dds_id_kind_name(who.kind), who.name);
  else
    snprintf(by, sizeof by, "%s",
             secured(srv) ? "a writer already gone" : "a participant without an identity (DDS Security is off)");
  palp_logf(srv->log, PALP_LOG_WARN, "%s disposed %llu session-request keys that no admitted request holds (never "
            "written, or written past stations_per_writer and refused; %llu in all): a flood, each kept by the server "
            "while that writer lives (~0.6 kB); %s", by, (unsigned long long)srv->stray_writer_count,
            (unsigned long long)atomic_load(&srv->request_strays),
            secured(srv) ? "revoke that identity (make-classroom-pki.sh DIR revoke KIND/NAME) and stop its machine"
                         : "run the classroom with DDS Security, so that only its identities may write requests");
}

/* A station is gone when its own request writer is: its instance's state cannot say so once another
 * writer has touched it. Secured, a dispose of the station's key by another identity is refused
 * (handle_requests), but the instance stays disposed, so when the station's process later dies
 * Cyclone has no new not-alive state to report, and the station held its slot and session for as
 * long as that other writer lived (until 2026-12-06). So the server also watches the request
 * reader's matched writers: when one goes, every station joined through palp_session_request whose
 * writer is no longer matched is lost. Not slept on: the fall of the matched count is noted, and the
 * stations are looked at GONE_GRACE_NS later, once the reader has been drained in that pass, so that
 * a departing station's LEAVE and dispose (sent before its writer went) are taken first and it
 * leaves rather than being lost. Keyed stations (palp_station_request, plain DDS only) keep their own
 * rule (station_gone_later): there any writer's dispose ends the station. */
static void note_request_unmatches(palp_srv *srv, int64_t now_ns) {
  if (!writers_unmatched(srv->request_r)) return;
  /* Every writer that goes gets its GONE_GRACE_NS: a pending sweep is put off to give it (until
   * 2026-12-06 one that unmatched just before the due time got almost none, and a departing viewer was
   * said lost rather than left). A churn of writers puts it off no more than SWEEP_OVERDUE_NS past its
   * first due time (handle_requests). */
  const int64_t due = now_ns + GONE_GRACE_NS;
  if (!srv->writers_sweep_ns) srv->writers_sweep_first_ns = due;
  if (due > srv->writers_sweep_ns) srv->writers_sweep_ns = due;
}

static void sweep_gone_writers(palp_srv *srv) {
  srv->writers_sweep_ns = 0;
  /* Their request instances leave the admission table, and only then (admission.h). */
  matched_set m = {.srv = srv, .reader = srv->request_r}; /* one read of the matched writers for both */
  palp_srv_admission_sweep(srv->admission, matched_has, &m);
  for (int i = 0; i < srv->station_slots; i++) {
    station *st = &srv->stations[i];
    if (!st->in_use || st->keyed || !st->writer || matched_has(st->writer, &m)) continue;
    station_leave(srv, st, "lost (its request writer is gone)"); /* may free other slots: each is checked */
  }
}

static void handle_requests(palp_srv *srv) {
  enum { N = 16 };
  palp_SessionRequest buf[N];
  void *ptr[N];
  dds_sample_info_t info[N];
  for (int i = 0; i < N; i++) ptr[i] = &buf[i];
  int n, taken = 0;
  handle_station_requests(srv);
  decide_gone_stations(srv, palp_dds_now_ns());
  note_request_unmatches(srv, palp_dds_now_ns());
  n = 0;
  while (taken < REQUESTS_PER_PASS && (n = dds_take(srv->request_r, ptr, info, N, N)) > 0) {
    taken += n;
    for (int i = 0; i < n; i++) {
      if (info[i].valid_data) {
        /* Strings from the wire are bounded by the IDL, but a forged sample need
         * not be NUL-terminated where we expect: terminate before use. */
        buf[i].station_id[sizeof buf[i].station_id - 1] = '\0';
        buf[i].user_name[sizeof buf[i].user_name - 1] = '\0';
        palp_srv_requester who;
        if (secured(srv)) {
          /* The sender is the identity whose partition its writer is in (the
           * access control plugin matched it only because its permissions allow
           * it); a request for a station id that is not that identity's own is
           * dropped unanswered, so no reply can land on another's station. */
          if (palp_srv_requester_of(srv->request_r, info[i].publication_handle, &who) < 0) {
            /* A station's last LEAVE can be taken after its writer is gone (a
             * loaded server reads it once the process has exited), when Cyclone no
             * longer has the writer's data to name its identity. The writer that
             * joined this station was checked at its join: its LEAVE is its own. */
            if (buf[i].op == palp_OP_LEAVE) {
              station *own = find_station(srv, buf[i].station_id);
              if (own && own->writer == info[i].publication_handle) {
                station_leave(srv, own, "left"); /* frees its slot, whose reply free_station retired */
                continue;
              }
              /* Nothing to leave (its session closed first, as an observer's does
               * when the trainee goes): the request has no effect, so there is no
               * one to refuse. */
              if (!own) {
                logf_(srv, "station \"%s\": LEAVE from a writer already gone, for no open station",
                       PALP_PRINTABLE(buf[i].station_id));
                continue;
              }
            }
            refuse_identity(srv, "station \"%s\": the writer's identity is unknown", PALP_PRINTABLE(buf[i].station_id));
            continue;
          }
          if (!palp_srv_station_owned_by(buf[i].station_id, &who)) {
            refuse_identity(srv, "%s/%s sent a request for station \"%s\", which is not its own",
                            palp_dds_id_kind_name(who.kind), PALP_PRINTABLE(who.name), PALP_PRINTABLE(buf[i].station_id));
            continue;
          }
          if (buf[i].op == palp_OP_JOIN && strcmp(buf[i].user_name, who.name) != 0) {
            char why[160];
            snprintf(why, sizeof why, "user_name \"%.40s\" is not the authenticated identity %s/%s", buf[i].user_name,
                     palp_dds_id_kind_name(who.kind), who.name);
            refuse_identity(srv, "user_name \"%s\" is not the authenticated identity %s/%s", PALP_PRINTABLE(buf[i].user_name),
                            palp_dds_id_kind_name(who.kind), PALP_PRINTABLE(who.name));
            reply_unslotted(srv, &buf[i], why);
            continue;
          }
        }
        if (buf[i].op == palp_OP_JOIN)
          handle_join(srv, &buf[i], secured(srv) ? &who : NULL, srv->request_r, info[i].publication_handle);
        else
          handle_leave(srv, &buf[i], srv->request_r, info[i].publication_handle);
        continue;
      }
      if (info[i].instance_state == DDS_IST_ALIVE) continue;
      /* The instance is gone (disposed or no writers). Its writer keeps its admission
       * until it is gone too (admission.h). Cyclone fills an invalid sample's key fields,
       * so the station id is read from it: dds_instance_get_key scans every instance
       * ever seen. */
      const bool admitted = palp_srv_admission_holds(srv->admission, info[i].instance_handle);
      buf[i].station_id[sizeof buf[i].station_id - 1] = '\0';
      station *st = find_station(srv, buf[i].station_id);
      if (!st) {
        if (!admitted && info[i].instance_state == DDS_IST_NOT_ALIVE_DISPOSED)
          note_request_stray(srv, info[i].publication_handle);
        continue;
      }
      /* Secured: a dispose or unregister by any writer but the station's own
       * (another identity writing this key) says nothing about the station. Its own
       * writer's going is then seen by sweep_gone_writers: the instance, already
       * disposed, may turn not-alive no more. */
      if (secured(srv) && info[i].publication_handle != st->writer) {
        refuse_identity(srv, "station \"%s\": disposed or unregistered by a writer that is not its own",
                        PALP_PRINTABLE(buf[i].station_id));
        continue;
      }
      /* Plain DDS (2026-12-07): the same for a writer of another participant than the one that joined
       * (request_is_own); a writer gone before it was looked up, if not the station's, is refused too. */
      dds_guid_t sender;
      int sender_known;
      if (!secured(srv) && !request_is_own(srv, st, srv->request_r, info[i].publication_handle, &sender, &sender_known)) {
        refuse_foreign_request(srv, "disposed or unregistered by", buf[i].station_id, st->session_id, &sender,
                               sender_known);
        continue;
      }
      /* A station that says goodbye sends OP_LEAVE first (handled above, which
       * forgets it), so reaching here means it vanished: its writer's automatic
       * liveliness (0.5 s) or its participant's lease (1 s) expired, and
       * Cyclone unregistered (or, autodispose, disposed) its instance. Cyclone
       * reports a lapsed writer's instances as disposed, so a dispose alone cannot
       * be told from a crash on this topic: palp_station_request can. */
      station_leave(srv, st, "lost (liveliness lease expired)");
    }
    if (n < N) break;
  }
  /* Drained (the last take came short): whatever a gone writer sent before it went has been taken. Or
   * overdue: the reader not drained, or the sweep put off by writer after writer (SWEEP_OVERDUE_NS
   * past its first due time). */
  const int64_t now = palp_dds_now_ns();
  if (srv->writers_sweep_ns && ((n < N && now >= srv->writers_sweep_ns) ||
                                now - srv->writers_sweep_first_ns >= SWEEP_OVERDUE_NS))
    sweep_gone_writers(srv);
}

/* [receive thread] The request topics' filter: see admission.h. arg: that topic's admission
 * table (palp_session_request's, palp_station_request's). */
static bool request_filter_fn(const void *sample, const dds_sample_info_t *si, void *arg) {
  (void)sample;
  return palp_srv_admission_admit(arg, si->instance_handle, si->publication_handle);
}

/* Request keys refused by the filters since the start (palp_server_guard.request_keys_filtered). */
static uint64_t request_keys_filtered(palp_srv *srv) {
  return palp_srv_admission_refused(srv->admission) +
         (srv->station_admission ? palp_srv_admission_refused(srv->station_admission) : 0);
}

/* New refusals said in the log at most once per log_interval, with the limit that refused them:
 * an operator sees a flood of station keys, not only a counter in palp_server_guard. */
static void say_filtered(palp_srv *srv, int64_t now_ns) {
  const uint64_t n = request_keys_filtered(srv);
  if (n == srv->filtered_said) return;
  if (srv->filtered_said_ns && now_ns - srv->filtered_said_ns < (int64_t)(srv->cfg.log_interval * 1e9)) return;
  palp_logf(srv->log, PALP_LOG_WARN, "%llu new request keys refused (%llu in all; on palp_station_request %llu): a "
            "writer may hold %d station ids at a time (stations_per_writer), the server %d per request topic; %s",
            (unsigned long long)(n - srv->filtered_said), (unsigned long long)n,
            (unsigned long long)(srv->station_admission ? palp_srv_admission_refused(srv->station_admission) : 0),
            srv->cfg.stations_per_writer, 2 * srv->station_slots + 64,
            secured(srv) ? "a classroom identity writes them" : "some participant writes them (DDS Security is off)");
  srv->filtered_said = n;
  srv->filtered_said_ns = now_ns;
}

/* ---- status -------------------------------------------------------------------- */

typedef struct load_ctx {
  palp_srv *srv;
  uint32_t n;
  uint64_t rejected[PALP_SRV_REJ_COUNT];
} load_ctx;

static void load_one(void *ctx, palp_srv_session *s) {
  load_ctx *lc = ctx;
  if (lc->n >= (uint32_t)lc->srv->cfg.max_sessions) return;
  palp_SessionLoad *l = &lc->srv->loads[lc->n++];
  memset(l, 0, sizeof *l);
  l->session_id = s->id;
  l->phantom_id = s->phantom->cfg.id;
  l->ticks = s->stats.ticks;
  l->overruns = s->stats.overruns;
  l->awake_ticks = s->stats.awake_ticks;
  l->contact_samples = s->stats.contact_samples;
  for (int r = 0; r < PALP_SRV_REJ_COUNT; r++) {
    if (r < PALP_SRV_REJ_WIRE) l->rejected[r] = s->stats.rejected[r];
    lc->rejected[r] += s->stats.rejected[r];
  }
  l->step_us_max = s->stats.step_us_max;
  s->stats.step_us_max = 0;
}

static void check_other_servers(palp_srv *srv) {
  void *ptr[4] = {NULL};
  dds_sample_info_t info[4];
  int n;
  while ((n = dds_take(srv->status_r, ptr, info, 4, 4)) > 0) {
    for (int i = 0; i < n; i++) {
      const palp_ServerStatus *st = ptr[i];
      if (info[i].valid_data && strcmp(st->server_id, srv->server_id) != 0 && !srv->warned_other_server) {
        /* Harmless with distinct server numbers (identity.h), which refuse to start
         * otherwise; a server without identities (older palp) would answer every join. */
        palp_log_info(srv->log, "another server (%s) publishes status on domain %u", PALP_PRINTABLE(st->server_id),
                      srv->cfg.domain_id);
        srv->warned_other_server = 1;
      }
    }
    dds_return_loan(srv->status_r, ptr, n);
  }
}

/* A session's own losses in the session log (palp_session_log, session 69): written as it opens and
 * whenever they rose, so that its station says the records of her session the log lost, not the
 * whole server's. None for a session the log does not hold (its opening lost with the rest): its
 * station then counts the server's losses from palp_server_status. */
static void publish_session_log(palp_srv *srv, palp_srv_session *s) {
  if (s->session_log_writer <= 0) return;
  uint64_t shed = 0, failed = 0;
  if (!srv->events->session_log_losses(srv->events->ctx, s->id, &shed, &failed)) return;
  if (s->session_log_sent && shed == s->session_log_shed && failed == s->session_log_failed) return;
  const palp_SessionLog m = {.session_id = s->id, .shed = shed, .failed = failed};
  if (dds_write(s->session_log_writer, &m) < 0) return; /* tried again at the next status */
  s->session_log_sent = 1;
  s->session_log_shed = shed;
  s->session_log_failed = failed;
}

static void publish_status(palp_srv *srv) {
  check_other_servers(srv);
  palp_srv_tick_stats ts;
  palp_srv_ticker_stats(srv->ticker, &ts);
  load_ctx lc = {.srv = srv};
  palp_srv_ticker_each(srv->ticker, load_one, &lc);
  palp_ServerStatus m;
  memset(&m, 0, sizeof m);
  snprintf(m.server_id, sizeof m.server_id, "%s", srv->server_id);
  m.uptime = (double)(palp_dds_now_ns() - srv->start_ns) * 1e-9;
  m.tick_rate_hz = srv->cfg.tick_rate_hz;
  m.tick_threads = (uint32_t)palp_srv_ticker_threads(srv->ticker);
  m.sessions_open = (uint32_t)srv->session_count;
  m.sessions_total = srv->sessions_total;
  m.load = ts.load;
  m.tick_us_p50 = ts.tick_us_p50;
  m.tick_us_p99 = ts.tick_us_p99;
  m.tick_us_max = ts.tick_us_max;
  m.ticks = ts.ticks;
  m.overruns = ts.overruns;
  for (int r = 0; r < PALP_SRV_REJ_WIRE; r++) m.rejected[r] = lc.rejected[r] + srv->rejected_closed[r];
  if (srv->events && srv->events->log_counts) {
    uint64_t w = 0, sh = 0, f = 0;
    srv->events->log_counts(srv->events->ctx, &w, &sh, &f);
    m.log_written = w;
    m.log_shed = sh;
    m.log_failed = f;
  }
  m.sessions = (dds_sequence_palp_SessionLoad){lc.n, lc.n, srv->loads, false};
  dds_write(srv->status_w, &m);
  palp_ServerGuard gm;
  memset(&gm, 0, sizeof gm);
  snprintf(gm.server_id, sizeof gm.server_id, "%s", srv->server_id);
  gm.stations = (uint32_t)stations_in_use(srv);
  gm.station_slots = (uint32_t)srv->station_slots;
  gm.joins_refused_rate = srv->guard.joins_refused_rate;
  gm.joins_refused_writer = srv->guard.joins_refused_writer;
  gm.joins_refused_viewers = srv->guard.joins_refused_viewers;
  gm.joins_refused_other = srv->guard.joins_refused_other;
  gm.request_keys_filtered = request_keys_filtered(srv);
  gm.contacts_filtered = lc.rejected[PALP_SRV_REJ_UNKNOWN_SESSION] + srv->rejected_closed[PALP_SRV_REJ_UNKNOWN_SESSION] +
                         lc.rejected[PALP_SRV_REJ_BAD_FINGER] + srv->rejected_closed[PALP_SRV_REJ_BAD_FINGER];
  gm.contacts_absurd_force = lc.rejected[PALP_SRV_REJ_ABSURD_FORCE] + srv->rejected_closed[PALP_SRV_REJ_ABSURD_FORCE];
  gm.instances_released = srv->retire.released;
  uint64_t printed = 0, suppressed = 0;
  palp_dds_log_limit_counts(&srv->dds_log, &printed, &suppressed);
  gm.dds_log_printed = printed;
  gm.dds_log_suppressed = suppressed;
  gm.sessions_forgotten = srv->sessions_forgotten;
  dds_write(srv->guard_w, &gm);
  for (int i = 0; i < srv->session_count; i++) {
    publish_state(srv, srv->sessions[i], 0, NULL, NULL);
    publish_session_log(srv, srv->sessions[i]);
  }
}

/* The server's DDS Security as its start takes it, and as --check checks it (before the session log is
 * made): until session 81 --check read only the identity's files, so a trainee's identity, an empty
 * one (with a PKI directory: the classroom served without DDS Security, unsaid) or a domain above 230
 * passed it and failed (or, the empty one, went unsecured) at class time. */
int palp_srv_security_prepare(const palp_srv_config *cfg, palp_dds_security *sec, char *msg, size_t msglen) {
  memset(sec, 0, sizeof *sec);
  if (!cfg->security_pki[0]) return 0;
  if (!cfg->security_identity[0]) {
    snprintf(msg, msglen, "identity: empty: with a PKI directory (%s) the server needs its identity in it (the "
                          "default is \"server\"); without one it would serve the classroom without DDS Security",
             cfg->security_pki);
    return PALP_EINVAL;
  }
  if (cfg->domain_id > PALP_SRV_SECURED_DOMAIN_MAX) {
    snprintf(msg, msglen, "domain %u: a classroom's governance covers domains 0-%d (Cyclone's parser refuses ids "
                          "above it; docs/security.md)", cfg->domain_id, PALP_SRV_SECURED_DOMAIN_MAX);
    return PALP_EINVAL;
  }
  int rc = palp_dds_security_init(sec, cfg->security_pki, cfg->security_identity, msg, msglen);
  if (rc == 0 && sec->kind != PALP_DDS_ID_SERVER) {
    snprintf(msg, msglen, "identity \"%s\" is not the server's (a server/NAME identity of the classroom's PKI)",
             PALP_PRINTABLE(cfg->security_identity));
    rc = PALP_EINVAL;
  }
  return rc;
}

/* ---- lifecycle ------------------------------------------------------------------- */

palp_srv *palp_srv_create(const palp_srv_def *def, int *rc, char *err, size_t errlen) {
  palp_srv *srv = calloc(1, sizeof *srv);
  if (!srv) {
    *rc = PALP_ENOMEM;
    fail(err, errlen, "out of memory");
    return NULL;
  }
  /* Once per server: it guards the lost-station list that DDS listener threads write. */
  pthread_mutex_init(&srv->lost_mu, NULL);
  srv->cfg = def->cfg;
  srv->events = def->events;
  srv->verbose = def->verbose;
  srv->log = def->log;
  srv->next_session_id = PALP_DDS_ID(srv->cfg.server_number, 1);
  const uint32_t local_all = (1u << PALP_DDS_ID_LOCAL_BITS) - 1u;
  srv->session_local_max =
      def->session_local_max > 0 && def->session_local_max < local_all ? def->session_local_max : local_all;
  srv->start_ns = palp_dds_now_ns();
  /* Unpredictable, so that a trainee cannot work out a random exercise's lesions from her session
   * number; each draw's seed is logged with it (docs/assessment.md, "Lesions drawn for each session"). */
  if (getrandom(&srv->placement_key, sizeof srv->placement_key, 0) != (ssize_t)sizeof srv->placement_key)
    srv->placement_key = (uint64_t)time(NULL) * 0x9e3779b97f4a7c15ULL ^ (uint64_t)getpid() ^ (uint64_t)srv->start_ns;
  char host[32] = "host";
  gethostname(host, sizeof host - 1);
  snprintf(srv->server_id, sizeof srv->server_id, "palp-server/%s/%ld", host, (long)getpid());
  if (!srv->cfg.server_name[0]) snprintf(srv->cfg.server_name, sizeof srv->cfg.server_name, "%s", host);
  if (palp_srv_config_check_ids(&srv->cfg, err, errlen) < 0) {
    *rc = PALP_EINVAL;
    goto fail;
  }
  /* Every id this server hands out carries its number (idl/palp_dds.h). */
  for (int i = 0; i < srv->cfg.phantom_count; i++)
    srv->cfg.phantom[i].id = PALP_DDS_ID(srv->cfg.server_number, srv->cfg.phantom[i].id);
  srv->sessions = calloc((size_t)srv->cfg.max_sessions, sizeof *srv->sessions);
  srv->loads = calloc((size_t)srv->cfg.max_sessions, sizeof *srv->loads);
  srv->station_slots = srv->cfg.max_sessions * (1 + srv->cfg.max_viewers);
  srv->stations = calloc((size_t)srv->station_slots, sizeof *srv->stations);
  srv->closed = calloc(CLOSED_KEEP, sizeof *srv->closed);
  /* Request instances: each slot's, plus as many again for stations between
   * a refused join and their retry or exit. */
  srv->admission = palp_srv_admission_create(srv->cfg.stations_per_writer, 2 * srv->station_slots + 64,
                                             srv->cfg.join_rate, srv->cfg.join_burst);
  /* The same bound on palp_station_request (its join tokens unused: joins take srv->admission's). */
  srv->station_admission = palp_srv_admission_create(srv->cfg.stations_per_writer, 2 * srv->station_slots + 64,
                                                     srv->cfg.join_rate, srv->cfg.join_burst);
  if (!srv->sessions || !srv->loads || !srv->stations || !srv->closed || !srv->admission || !srv->station_admission ||
      palp_srv_retire_init(&srv->retire, 4 * srv->station_slots + 256, srv->cfg.closed_retention) < 0) {
    *rc = PALP_ENOMEM;
    fail(err, errlen, "out of memory");
    goto fail;
  }
  for (int i = 0; i < srv->cfg.phantom_count; i++) {
    *rc = load_phantom(srv, i, &srv->cfg.phantom[i], &srv->phantom[i], err, errlen);
    srv->phantom_count = i + (srv->phantom[i].template_world != NULL);
    if (*rc < 0) goto fail;
  }
  {
    /* One name for one phantom, the exercises' titles now known: a station picks a phantom by name. */
    const char *names[PALP_SRV_MAX_PHANTOMS];
    char msg[320] = "";
    for (int i = 0; i < srv->phantom_count; i++) names[i] = srv->phantom[i].cfg.name;
    if ((*rc = palp_srv_config_check_names(names, srv->phantom_count, srv->cfg.phantom_count - srv->cfg.exercise_count,
                                           msg, sizeof msg)) < 0) {
      fail(err, errlen, "%s", msg);
      goto fail;
    }
  }
  palp_dds_refusals_init(&srv->refusals, palp_log_warn_line, srv->log, PALP_DDS_REFUSAL_WINDOW_S);
  palp_dds_refusals_on_record(&srv->refusals, record_refusal, srv);
  srv->refusals_ready = 1;
  if (palp_dds_refusals_install(&srv->dds_log, &srv->refusals, srv->cfg.dds_log_lines, srv->cfg.dds_log_window) == 0)
    srv->dds_log_installed = 1;
  {
    char msg[400] = "";
    if ((*rc = palp_srv_security_prepare(&srv->cfg, &srv->sec, msg, sizeof msg)) < 0) {
      fail(err, errlen, "security: %s", msg);
      goto fail;
    }
  }
  if (srv->sec.warning[0]) palp_log_warn(srv->log, "DDS Security: %s", srv->sec.warning);
  /* a peer refused for its permissions named by its identity, not its GUID */
  if (palp_dds_security_name_peers(&srv->sec, &srv->refusals) < 0)
    palp_log_warn(srv->log, "out of memory naming the classroom's identities");
  srv->reaper = palp_dds_reaper_create(2 * srv->cfg.max_sessions + TOLD_KEPT); /* a class closing at once, and room */
  if (!srv->reaper) {
    *rc = PALP_ENOMEM;
    fail(err, errlen, "cannot start the thread that deletes closed sessions' publishers");
    goto fail;
  }
  srv->pp = palp_dds_create_participant((dds_domainid_t)srv->cfg.domain_id, &srv->sec);
  if (srv->pp < 0) {
    *rc = PALP_EIO;
    fail(err, errlen, "dds_config: cannot create a DDS participant on domain %u: %s (CYCLONEDDS_URI=%s)%s",
         srv->cfg.domain_id, dds_strretcode(srv->pp), getenv("CYCLONEDDS_URI") ? getenv("CYCLONEDDS_URI") : "",
         secured(srv) ? "; DDS Security refused the identity (see above: revoked, expired, domain > 230?)" : "");
    goto fail;
  }
  /* Secured, a participant without an identity is ignored by DDS Security without a word:
   * look for such strangers at each status, so the log names the misconfigured station. */
  if (secured(srv) && palp_dds_strangers_init(&srv->strangers, srv->pp, PALP_DDS_STRANGER_GRACE_S) == 0)
    srv->strangers_ready = 1;
  for (int k = 0; k < PALP_TOPIC_COUNT; k++) {
    /* Secured, palp_station_request is not offered (no identity to check; see below). */
    if (secured(srv) && k == PALP_TOPIC_STATION_REQUEST) continue;
    srv->topic[k] = palp_dds_create_topic(srv->pp, (palp_dds_topic_kind)k);
    /* Topics added after a classroom's PKI was made: with permissions that predate one, the
     * server serves on without it and says what is lost. make-classroom-pki.sh init re-issues them. */
    const char *lost = optional_topic_loss((palp_dds_topic_kind)k);
    if (srv->topic[k] < 0 && lost && secured(srv)) {
      palp_log_warn(srv->log, "%s: the server's permissions do not allow topic %s (%s); re-issue the classroom's "
                              "permissions with scripts/make-classroom-pki.sh DIR init (docs/security.md)",
                    lost, palp_dds_topic_name((palp_dds_topic_kind)k), dds_strretcode(srv->topic[k]));
      srv->topic[k] = 0;
      continue;
    }
    if (srv->topic[k] < 0) {
      *rc = PALP_EIO;
      char hint[PALP_DDS_HINT_MAX];
      const char *name = palp_dds_topic_name((palp_dds_topic_kind)k);
      fail(err, errlen, "cannot create topic %s: %s%s", name, dds_strretcode(srv->topic[k]),
           palp_dds_refused_hint(&srv->sec, name, hint, sizeof hint));
      goto fail;
    }
  }
  srv->catalogue_w = palp_dds_create_writer(srv->pp, srv->topic[PALP_TOPIC_CATALOGUE], PALP_TOPIC_CATALOGUE);
  /* The request reader sits on a topic entity of its own, which carries the
   * admission filter (a filter applies to every reader of its topic entity);
   * secured, under a subscriber in each identity's own partition (palp/KIND/NAME). */
  srv->request_topic = palp_dds_create_topic(srv->pp, PALP_TOPIC_SESSION_REQUEST);
  {
    struct dds_topic_filter flt = {.mode = DDS_TOPIC_FILTER_SAMPLE_SAMPLEINFO_ARG,
                                   .f = {.sample_sampleinfo_arg = request_filter_fn},
                                   .arg = srv->admission};
    if (srv->request_topic < 0 || dds_set_topic_filter_extended(srv->request_topic, &flt) < 0) {
      *rc = PALP_EIO;
      fail(err, errlen, "cannot create the session request topic");
      goto fail;
    }
  }
  dds_entity_t request_parent = srv->pp;
  if (secured(srv)) {
    dds_qos_t *q = dds_create_qos();
    dds_qset_partition(q, 2, (const char *[]){"palp/trainee/*", "palp/instructor/*"});
    srv->request_sub = request_parent = dds_create_subscriber(srv->pp, q, NULL);
    dds_delete_qos(q);
  }
  srv->request_r = request_parent < 0 ? request_parent
                                      : palp_dds_create_reader(request_parent, srv->request_topic, PALP_TOPIC_SESSION_REQUEST);
  srv->guard_w = palp_dds_create_writer(srv->pp, srv->topic[PALP_TOPIC_SERVER_GUARD], PALP_TOPIC_SERVER_GUARD);
  srv->reply_w = palp_dds_create_writer(srv->pp, srv->topic[PALP_TOPIC_SESSION_REPLY], PALP_TOPIC_SESSION_REPLY);
  srv->state_w = palp_dds_create_writer(srv->pp, srv->topic[PALP_TOPIC_SESSION_STATE], PALP_TOPIC_SESSION_STATE);
  srv->status_w = palp_dds_create_writer(srv->pp, srv->topic[PALP_TOPIC_SERVER_STATUS], PALP_TOPIC_SERVER_STATUS);
  srv->exercise_w = palp_dds_create_writer(srv->pp, srv->topic[PALP_TOPIC_EXERCISE], PALP_TOPIC_EXERCISE);
  /* The lesions go on the wire only where permissions keep them from trainees, unless the
   * config says otherwise (docs/server.md, "session_exercise"). */
  const int answers = srv->cfg.session_exercise == PALP_SRV_SESSION_EXERCISE_ALWAYS ||
                      (srv->cfg.session_exercise == PALP_SRV_SESSION_EXERCISE_SECURED && secured(srv));
  srv->session_exercise_w = answers ? answers_writer(srv, PALP_TOPIC_SESSION_EXERCISE) : 0;
  srv->session_score_w = answers ? answers_writer(srv, PALP_TOPIC_SESSION_SCORE) : 0; /* session 63 */
  srv->session_closed_w = answers_writer(srv, PALP_TOPIC_SESSION_CLOSED);             /* session 69 */
  if (srv->cfg.exercise_count > 0 && srv->session_exercise_w <= 0)
    palp_log_info(srv->log, "exercise sessions' lesions stay on this server (%s): a palp-recorder's log cannot "
                            "assess them; this server's own log can",
                  srv->cfg.session_exercise == PALP_SRV_SESSION_EXERCISE_OFF ? "session_exercise \"off\""
                  : !secured(srv) ? "no DDS Security: session_exercise \"always\" sends them anyway"
                  : srv->topic[PALP_TOPIC_SESSION_EXERCISE] <= 0 ? "the permissions predate palp_session_exercise"
                                                                 : "palp_session_exercise could not be written");
  /* Only to notice a second server on the domain: both would answer every join. */
  srv->status_r = palp_dds_create_reader(srv->pp, srv->topic[PALP_TOPIC_SERVER_STATUS], PALP_TOPIC_SERVER_STATUS);
  srv->waitset = dds_create_waitset(srv->pp);
  srv->stop_gc = dds_create_guardcondition(srv->pp);
  srv->request_rc = dds_create_readcondition(srv->request_r, DDS_ANY_STATE);
  /* palp_station_request (other vendors' stations, docs/interop.md) carries no
   * identity the server could check, so a secured classroom does not offer it. */
  if (!secured(srv)) {
    /* On a topic entity of its own, which carries its admission filter (as the session requests'). */
    srv->station_request_topic = palp_dds_create_topic(srv->pp, PALP_TOPIC_STATION_REQUEST);
    struct dds_topic_filter flt = {.mode = DDS_TOPIC_FILTER_SAMPLE_SAMPLEINFO_ARG,
                                   .f = {.sample_sampleinfo_arg = request_filter_fn},
                                   .arg = srv->station_admission};
    srv->station_request_r =
        srv->station_request_topic < 0 || dds_set_topic_filter_extended(srv->station_request_topic, &flt) < 0
            ? -1
            : palp_dds_create_reader(srv->pp, srv->station_request_topic, PALP_TOPIC_STATION_REQUEST);
    srv->station_request_rc = dds_create_readcondition(srv->station_request_r, DDS_ANY_STATE);
    if (srv->station_request_r > 0) {
      dds_listener_t *lv = dds_create_listener(NULL);
      dds_lset_liveliness_changed_arg(lv, on_station_liveliness, srv, true);
      dds_set_listener(srv->station_request_r, lv);
      dds_delete_listener(lv);
    }
    if (srv->station_request_r < 0 || srv->station_request_rc < 0 ||
        dds_waitset_attach(srv->waitset, srv->station_request_rc, 1) < 0) {
      *rc = PALP_EIO;
      fail(err, errlen, "cannot create the palp_station_request reader");
      goto fail;
    }
  }
  if (srv->catalogue_w < 0 || srv->request_r < 0 || srv->reply_w < 0 || srv->state_w < 0 || srv->status_w < 0 ||
      srv->status_r < 0 || srv->guard_w < 0 || srv->exercise_w < 0 ||
      srv->waitset < 0 || srv->stop_gc < 0 || srv->request_rc < 0 ||
      dds_waitset_attach(srv->waitset, srv->request_rc, 0) < 0 || dds_waitset_attach(srv->waitset, srv->stop_gc, 0) < 0) {
    *rc = PALP_EIO;
    fail(err, errlen, "cannot create the server's DDS readers and writers");
    goto fail;
  }
  int rt_ok = 0;
  /* One pool of tick threads per distinct physics rate. */
  double rates[PALP_SRV_MAX_PHANTOMS];
  int nrates = 0;
  for (int i = 0; i < srv->phantom_count; i++) {
    int seen = 0;
    for (int k = 0; k < nrates; k++) seen |= rates[k] == srv->phantom[i].cfg.physics_rate_hz;
    if (!seen) rates[nrates++] = srv->phantom[i].cfg.physics_rate_hz;
  }
  if (nrates == 0) rates[nrates++] = srv->cfg.tick_rate_hz;
  srv->ticker = palp_srv_ticker_create_rates(srv->cfg.tick_threads, rates, nrates, srv->cfg.max_sessions,
                                             srv->cfg.tick_priority, srv->cfg.status_rate_hz, &rt_ok, rc);
  if (!srv->ticker) {
    fail(err, errlen, "cannot start the tick threads: %s", palp_strerror(*rc));
    goto fail;
  }
  if (srv->cfg.tick_priority > 0 && !rt_ok)
    palp_log_warn(srv->log, "tick_priority %d: SCHED_FIFO refused (needs CAP_SYS_NICE or an rtprio limit); "
                    "tick threads run at normal priority\n", srv->cfg.tick_priority);
  {
    uint32_t ids[PALP_SRV_MAX_PHANTOMS];
    const char *names[PALP_SRV_MAX_PHANTOMS];
    for (int i = 0; i < srv->phantom_count; i++) {
      ids[i] = srv->phantom[i].cfg.id;
      names[i] = srv->phantom[i].cfg.name;
    }
    char instance[64];
    snprintf(instance, sizeof instance, "%.40s/%ld", host, (long)getpid());
    palp_srv_identity_def idd = {.participant = srv->pp,
                                 .topic = srv->topic[PALP_TOPIC_SERVER_IDENTITY],
                                 .name = srv->cfg.server_name,
                                 .number = srv->cfg.server_number,
                                 .instance = instance,
                                 .phantom_count = srv->phantom_count,
                                 .phantom_id = ids,
                                 .phantom_name = names,
                                 .wait_s = def->identity_wait_s,
                                 .log_interval_s = srv->cfg.log_interval,
                                 .secured = secured(srv),
                                 .log = srv->log};
    srv->identity = palp_srv_identity_create(&idd, rc, err, errlen);
    if (!srv->identity) goto fail;
  }
  for (int i = 0; i < srv->phantom_count; i++) {
    publish_catalogue(srv, &srv->phantom[i]);
    publish_exercise(srv, &srv->phantom[i]);
  }
  *rc = 0;
  return srv;
fail:
  palp_srv_destroy(srv);
  return NULL;
}

void palp_srv_request_stop(palp_srv *srv) {
  atomic_store(&srv->stop, 1);
  dds_set_guardcondition(srv->stop_gc, true);
}

int palp_srv_run(palp_srv *srv, double duration) {
  const int64_t status_period = (int64_t)(1e9 / srv->cfg.status_rate_hz);
  int64_t next_status = palp_dds_now_ns() + status_period;
  int64_t end = duration > 0 ? palp_dds_now_ns() + (int64_t)(duration * 1e9) : INT64_MAX;
  int result = 0;
  palp_log_info(srv->log, "%s: server \"%s\" number %u, domain %u, %d phantom(s), %.0f Hz on %d tick thread(s), max %d "
                "sessions", srv->server_id, srv->cfg.server_name, srv->cfg.server_number, srv->cfg.domain_id,
                srv->phantom_count, srv->cfg.tick_rate_hz, palp_srv_ticker_threads(srv->ticker), srv->cfg.max_sessions);
  /* Whether the classroom is secured is the first thing an administrator reading the log needs: until
   * 2026-12-04 the log said it only in the summary at exit. */
  if (secured(srv)) /* n_names: set before the participant existed, never again */
    palp_log_info(srv->log, "DDS Security on: identity %s/%s, classroom %s; refused peers are named from %d classroom "
                  "certificate(s)",
                  palp_dds_id_kind_name(srv->sec.kind), srv->sec.name, srv->sec.pki, srv->refusals.n_names);
  else
    palp_log_info(srv->log, "DDS Security off: every participant on domain %u is trusted (a classroom runs with "
                  "\"security\" in its config or --pki; docs/security.md)",
                  srv->cfg.domain_id);
  for (int i = 0; i < srv->phantom_count; i++)
    if (srv->phantom[i].cfg.physics_rate_hz != srv->cfg.tick_rate_hz)
      palp_log_info(srv->log, "phantom %u \"%s\" steps at %.0f Hz (physics_rate_hz)", srv->phantom[i].cfg.id,
                    srv->phantom[i].cfg.name, srv->phantom[i].cfg.physics_rate_hz);
  while (!atomic_load(&srv->stop)) {
    int64_t now = palp_dds_now_ns();
    if (now >= end) break;
    int64_t wake = next_status < end ? next_status : end;
    /* Wake at least every 100 ms to notice sessions whose model failed. */
    if (wake - now > 100000000) wake = now + 100000000;
    const int64_t gone_due = next_gone_due(srv); /* a disposed station's moment (station_gone_later) */
    if (gone_due < wake) wake = gone_due;
    if (srv->writers_sweep_ns && srv->writers_sweep_ns < wake) wake = srv->writers_sweep_ns; /* sweep_gone_writers */
    dds_waitset_wait(srv->waitset, NULL, 0, wake - now > 0 ? wake - now : 0);
    handle_requests(srv);
    publish_scores(srv);
    palp_srv_retire_due(&srv->retire, palp_dds_now_ns(), release_instance, srv);
    for (int i = 0; i < srv->session_count; i++) {
      palp_srv_session *s = srv->sessions[i];
      int f = atomic_load(&s->failed);
      if (f) {
        char why[128];
        snprintf(why, sizeof why, "model step failed: %s", palp_strerror(f));
        close_session(srv, s, why);
        i--;
        continue;
      }
      handle_findings(srv, s);
      const int64_t t = palp_dds_now_ns();
      if (s->held_since_ns && t - s->held_since_ns >= (int64_t)(srv->cfg.station_grace * 1e9)) {
        char why[224];
        snprintf(why, sizeof why, "%s; not back within %.0f s", s->held_reason, srv->cfg.station_grace);
        close_session(srv, s, why);
        i--;
        continue;
      }
      if (s->exercise && time_left(s, t) <= 0) {
        close_session(srv, s, "exercise time limit reached");
        i--;
        continue;
      }
      /* The time left and the marks, refreshed at least once a second. */
      if (t - s->findings_status_ns >= FINDING_STATUS_PERIOD_NS) publish_finding_status(s);
    }
    if (palp_dds_now_ns() >= next_status) {
      char why[256];
      /* Only within its start-up window (server_identity.h): later, a claim of its name is warned
       * about and ignored, so one sample cannot close every session. */
      if (palp_srv_identity_poll(srv->identity, why, sizeof why) < 0) {
        palp_log_error(srv->log, "stopping: %s", why);
        result = PALP_EINVAL;
        break;
      }
      publish_status(srv);
      say_filtered(srv, palp_dds_now_ns());
      /* a refused peer that stopped retrying: its repeats logged (and kept) within a window */
      palp_dds_refusals_tick(&srv->refusals, palp_dds_now_ns());
      if (srv->strangers_ready) palp_dds_strangers_tick(&srv->strangers, &srv->refusals, palp_dds_now_ns());
      next_status += status_period;
      if (next_status < palp_dds_now_ns()) next_status = palp_dds_now_ns() + status_period;
    }
  }
  dds_set_guardcondition(srv->stop_gc, false);
  srv->stopping = 1;
  while (srv->session_count > 0)
    close_session(srv, srv->sessions[srv->session_count - 1], result ? "server identity conflict" : "server shutdown");
  publish_status(srv);
  palp_dds_refusals_flush(&srv->refusals); /* the repeats not yet logged, before the summary */
  return result;
}

uint64_t palp_srv_security_refusals(palp_srv *srv, char *who, size_t len) {
  uint64_t total = 0;
  palp_dds_refusals_counts(&srv->refusals, &total, NULL);
  if (who && len) palp_dds_refusals_describe(&srv->refusals, who, len);
  return total;
}

int palp_srv_open_sessions(const palp_srv *srv) { return atomic_load(&srv->session_count); }

uint64_t palp_srv_refused_requests(palp_srv *srv) { return atomic_load(&srv->refused_requests); }

uint64_t palp_srv_request_strays(palp_srv *srv) { return atomic_load(&srv->request_strays); }

static void print_row(FILE *out, const palp_srv_session_summary *s, const char *state, int pw) {
  uint64_t rej = 0;
  for (int r = 0; r < PALP_SRV_REJ_COUNT; r++) rej += s->rejected[r];
  /* names printable: the table goes to the log file too, and a trainee's name from the network with a
   * newline in it began a forged line there (until 2026-12-07) */
  fprintf(out, "%-7u %-16.16s %-*.*s %8.2f %9llu %8.2f %9.2f %9llu %8llu %8llu %8llu  %s\n", s->info.session_id,
          PALP_PRINTABLE(s->info.trainee_name), pw, pw, PALP_PRINTABLE(s->info.phantom_name), s->duration, (unsigned long long)s->contact_samples,
          s->peak_force, s->peak_displacement * 1e3, (unsigned long long)s->ticks,
          (unsigned long long)s->overruns, (unsigned long long)s->skipped, (unsigned long long)rej, state);
}

/* A column width *w grown to fit name, at most 44 characters. */
static void widen_to(int *w, const char *name) {
  const int n = name ? (int)strnlen(name, 44) : 0;
  if (n > *w) *w = n;
}

void palp_srv_print_summary(const palp_srv *srv, FILE *out) {
  if (secured(srv)) {
    char state[96];
    fprintf(out, "DDS Security %s; requests refused for their identity: %llu\n",
            palp_dds_security_state(&srv->sec, state, sizeof state),
            (unsigned long long)atomic_load(&((palp_srv *)srv)->refused_requests));
    char who[600];
    const uint64_t total = palp_srv_security_refusals((palp_srv *)srv, who, sizeof who);
    if (total) fprintf(out, "DDS Security refused participants %llu time(s): %s\n", (unsigned long long)total, who);
  }
  /* The phantom column as wide as its longest name, at most 44 characters: cut at 26 the
   * demo's "dome C (long-term, haptic 250 Hz)" lost what set it apart from dome B. */
  int pw = 7;
  for (int i = 0; i < srv->closed_count; i++)
    widen_to(&pw, srv->closed[(srv->closed_head + i) % CLOSED_KEEP].sum.info.phantom_name);
  for (int i = 0; i < srv->session_count; i++) {
    palp_srv_session_info info;
    palp_srv_session_info_fill(srv->sessions[i], &info);
    widen_to(&pw, info.phantom_name);
  }
  /* "overruns": its late steps, skipped slots included; "skipped": the slots its group dropped behind
   * schedule, in which it took no step (session 82) */
  fprintf(out, "%-7s %-16s %-*s %8s %9s %8s %9s %9s %8s %8s %8s  %s\n", "session", "trainee", pw, "phantom", "dur[s]",
          "samples", "Fmax[N]", "dmax[mm]", "ticks", "overruns", "skipped", "rejected", "closed because");
  if (srv->sessions_forgotten)
    fprintf(out, "(%llu older closed sessions not kept)\n", (unsigned long long)srv->sessions_forgotten);
  for (int i = 0; i < srv->closed_count; i++) {
    const closed_session *c = &srv->closed[(srv->closed_head + i) % CLOSED_KEEP];
    print_row(out, &c->sum, c->reason, pw);
  }
  for (int i = 0; i < srv->session_count; i++) {
    palp_srv_session_summary sum;
    palp_srv_session_summary_fill(srv->sessions[i], "(open)", palp_dds_now_ns(), &sum);
    print_row(out, &sum, "(open)", pw);
  }
}

void palp_srv_destroy(palp_srv *srv) {
  if (!srv) return;
  if (srv->ticker) {
    palp_srv_tick_stats ts;
    palp_srv_ticker_stats(srv->ticker, &ts);
    if (ts.steps > 0)
      palp_log_info(srv->log, "ticks: %llu session steps due, %llu late (%.3f%%), %llu put last to wait for a rebuild; "
                    "%llu of %llu tick passes overran, %llu tick slots dropped behind schedule (%llu session steps "
                    "skipped, counted late)",
                    (unsigned long long)(ts.steps + ts.skipped_steps), (unsigned long long)ts.late_steps,
                    100.0 * (double)ts.late_steps / (double)(ts.steps + ts.skipped_steps),
                    (unsigned long long)ts.deferred, (unsigned long long)ts.overruns, (unsigned long long)ts.ticks,
                    (unsigned long long)ts.lost_slots, (unsigned long long)ts.skipped_steps);
  }
  palp_srv_ticker_destroy(srv->ticker);
  for (int i = 0; i < srv->session_count; i++) palp_srv_session_destroy(srv->sessions[i]);
  if (srv->reaper) {
    palp_dds_reaper_stats rs;
    palp_dds_reaper_stats_get(srv->reaper, &rs);
    if (rs.handed > 0)
      palp_log_info(srv->log, "closed sessions: the main loop let go of each in at most %.3f s; %llu publishers "
                    "deleted beside it (their writers waiting for the stations' acknowledgements), the longest in "
                    "%.3f s, %d still to delete", srv->close_longest_s, (unsigned long long)rs.handed,
                    (double)rs.longest_ns * 1e-9, rs.pending);
  }
  palp_dds_reaper_destroy(srv->reaper); /* what it still holds deleted before their participant */
  if (srv->strangers_ready) palp_dds_strangers_destroy(&srv->strangers); /* its readers, before their participant */
  if (srv->pp > 0) dds_delete(srv->pp);
  palp_srv_identity_destroy(srv->identity);
  /* After the participant: the request filter (which uses the admission table)
   * can no longer run. */
  palp_srv_admission_destroy(srv->admission);
  free(srv->matched);
  palp_srv_admission_destroy(srv->station_admission);
  palp_srv_retire_free(&srv->retire);
  if (srv->dds_log_installed) palp_dds_log_limit_remove(&srv->dds_log);
  if (srv->refusals_ready) { /* after the sink is gone: nothing notes a refusal any more */
    palp_dds_refusals_flush(&srv->refusals);
    palp_dds_refusals_destroy(&srv->refusals);
  }
  free(srv->stations);
  for (int i = 0; i < srv->phantom_count; i++) {
    palp_world_destroy(srv->phantom[i].template_world);
    free(srv->phantom[i].exercise);
    free(srv->phantom[i].exercise_json);
  }
  free(srv->sessions);
  free(srv->loads);
  free(srv->closed);
  pthread_mutex_destroy(&srv->lost_mu);
  free(srv);
}
