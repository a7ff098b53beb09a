/* hub.c - palp-web's DDS thread and its latest-value store of browser messages. */
#include "hub.h"
#include "utf8.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>
#include <dds/dds.h>

#include "palp.h"
#include "palp_assess.h"
#include "palp_coverage.h"
#include "palp_dds.h"
#include "palp_dds_gate.h"
#include "palp_dds_origin.h"
#include "palp_dds_reaper.h"
#include "palp_dds_strays.h"
#include "palp_dds_log_view.h"
#include "palp_dds_strangers.h"
#include "palp_finding_answers.h"
#include "palp_place.h"

#define FINGERS 4
#define TAKE 32
#define MAX_CLIENTS_HARD 256
#define DEFAULT_PATCH_AREA 5.2e-4 /* [m^2], the server's default when a contact says 0 */
/* The live view's bounds on what a contact may say: 10 m from the phantom's origin, 1 MN (the server's
 * absurd_force may be set up to 1e6 N). Beyond them it is no palpation, and the numbers' width in the
 * live message stays bounded (%.6f of 10 m: 10 characters). */
#define LIVE_MAX_REACH_M 10.0
#define LIVE_MAX_FORCE_N 1.0e6
#define WAKE_PERIOD_NS 100000000LL
#define JOIN_PERIOD_NS 100000000LL
#define SESSIONS_PERIOD_NS 200000000LL /* the list's live figures (force, coverage) at 5 Hz */
#define COVER_PERIOD_NS 500000000LL    /* a session's pressed-skin map to its pages at most at 2 Hz */
#define REJOIN_AFTER_NS 5000000000LL
#define REASK_AFTER_NS 1000000000LL /* rejoin_if_dropped: not sooner after joining, nor more often */
/* A turn of the DDS thread this long after the last one: palp-web did not run (stopped, a loaded
 * machine), long enough for its request writer's 0.5 s liveliness to lapse at the server, which then
 * drops the bridge from the sessions it streams (rejoin_if_dropped). Its turns are 16.7 ms apart. */
#define STALL_NS 300000000LL
#define STALL_ASKS 2 /* JOINs sent again after a stall: at once, and REASK_AFTER_NS later */
/* Streams are polled at this period rather than woken per sample: 8 sessions at 30 Hz would wake
 * the thread 240 times a second, and on a virtual machine every wake-up costs more than the work
 * (bench/web). Adds at most 16.7 ms to a frame's way to the page. */
#define POLL_NS 16666667LL
/* Local models are read in full (not just the newest) so that consecutive frames can be compared
 * for late haptic updates: 64 per finger covers a 60 Hz poll at up to 3.8 kHz physics. */
#define LM_DEPTH 64
#define MAX_EXERCISES PALP_WEB_MAX_PHANTOMS
/* Finding requests from a trainee page: at most one per FINDING_GAP_NS, FINDING_MARKS_MAX marks
 * standing per session from the bridge, a contact point at most CONTACT_FRESH_NS old. */
#define FINDING_GAP_NS 500000000LL
#define FINDING_MARKS_MAX 64
#define CONTACT_FRESH_NS 250000000LL
/* An exercise session's exercise can come before its OPEN state (two topics): kept this long. */
#define SESSION_EXERCISE_WAIT_NS 10000000000LL
#define SESSION_EXERCISES_PENDING 16
#define ANSWER_MARKS 64 /* marks a session's answers list: the server's own bound (findings.c) */
/* Publishers of refused catalogue entries named in the log, each once; beyond them one line says more
 * came (a peer making writers in a loop must not fill the log). */
#define REFUSED_PUBLISHERS 16

/* One published message: bytes and the version they were built at (versions are unique across
 * the hub, so a cursor holding an old version of a reused slot is never mistaken as current). */
typedef struct item {
  uint64_t ver;
  unsigned char *buf;
  size_t len;
} item;

typedef struct finger {
  int mode;         /* palp_ContactMode; RELEASE = not pressing */
  double center[3]; /* [m] */
  double force[3];  /* force-driven: on the phantom [N] */
  double radius;    /* footprint for coverage [m] */
  double fb[3];     /* feedback: phantom on the finger [N] */
  int fb_active;
  /* newest haptic local model (palp_local_model) of a position-driven finger: its proxy is the
   * fingertip on the surface, device the point the station's device reached beneath it */
  int lm_valid, lm_contact;
  uint64_t lm_frame;
  double proxy[3], device[3]; /* [m] */
  double lm_force;            /* |force| of the model, not limited [N] */
  uint32_t lm_flags;          /* LM_* of the newest model */
  int64_t lm_server_ns;       /* its server_time_ns */
  double point[3], area;      /* its contact point [m] and footprint [m^2] */
  int lm_triangles;           /* triangles in contact (0 when not known) */
} finger;

/* What a trainee may know of an exercise (palp_exercise), per phantom. */
typedef struct exercise {
  int used;
  uint32_t phantom_id;
  char name[64], title[128], instructions[1024];
  double time_limit, max_force;
  /* Its pressure bands (light, medium, deep), by which the assessment grades; bands_ok when
   * every band has a bound and every bound is finite and ordered: then an in-contact
   * position-driven finger is banded by them, not by the gauge's force bands (docs/web.md). */
  palp_band band[PALP_BAND_COUNT];
  int bands_ok;
} exercise;

/* The server's answer on a session's findings (palp_finding_status). */
typedef struct finding_status {
  int valid;
  uint32_t marks, last_mark_id;
  int last_accepted;
  char reason[128];
  double time_left;
  int64_t at_ns;
} finding_status;

/* Per session slot, shared between the DDS thread (which owns the writer and the contact point)
 * and the web thread (which handles a trainee page's request), under the hub's mutex. */
typedef struct finding_slot {
  dds_entity_t pub, w;           /* palp_finding writer in the session's partition (exercise sessions) */
  int exercise;                  /* the session's phantom runs an exercise */
  int contact;                   /* a finger's newest local model is in contact */
  int contact_finger;
  double point[3], time;         /* its contact point [m] and world time [s] */
  int64_t at_ns;                 /* when the bridge took it */
  uint32_t next_mark, stack[FINDING_MARKS_MAX];
  int nstack;
  int64_t last_ns;
  int joined; /* the bridge's visual station is in the session: the server takes its findings only then */
} finding_slot;

/* An exercise session's answers, for an instructor's dashboard (docs/web.md, "The hidden lumps"):
 * the exercise as the server drew it for this session (palp_session_exercise) and the trainee's
 * marks the server accepted, paired with its answers as palp-recorder pairs them. */
typedef struct answers {
  palp_exercise *ex;             /* NULL until the session's exercise arrives */
  palp_finding_answers pairs;
  int n;                         /* marks accepted, in order; a withdrawal sets withdrawn */
  uint32_t id[ANSWER_MARKS];
  palp_finding mark[ANSWER_MARKS];
  int refused, unanswered;
  int dirty;
} answers;

typedef struct pending_exercise {
  uint32_t sid;
  palp_exercise *ex;
  int64_t at_ns;
} pending_exercise;

typedef struct phantom {
  int used;
  uint32_t id;
  int n, tri_count, dome_tris;
  double *rest;     /* 3n [m] */
  int32_t *tri;
  double radius;
  char name[64];
} phantom;

/* A stream reader's strays since it was made (renew_stream): disposes of keys the gate would not pass and
 * samples refused at its instance bound. The bound alone let a flood of disposes of made-up keys fill
 * the reader while the disposing writer lived, every later session's samples then refused (the
 * session 81 review: 800 disposes, 0 of 100 contacts received); past idl/palp_dds_strays.h's bound
 * the reader is made anew. */
typedef struct stray_watch {
  uint64_t strays;
  uint32_t refused_seen; /* its sample-rejected total when last asked (palp_dds_gate_refused_since) */
  int64_t renewed_ns;    /* when last made anew (0: never) */
} stray_watch;

typedef struct session {
  int used;
  uint32_t id;
  palp_SessionState st;
  /* The participant of its latest OPEN state's writer (palp_dds_origin_participant; 0: not known): its
   * server, from which alone its server topics are taken (from_its_server) */
  dds_instance_handle_t server_pp;
  const phantom *ph;
  palp_coverage *cov;
  /* From the server's finger samples (palp_finger_sample, session 71), touched triangles named:
   * the review's own footprint. Shown once one has come (samples > 0); cov, marked from the local
   * models' count, otherwise (a server that predates the topic). */
  palp_coverage *touched;
  uint64_t samples, samples_frame[FINGERS];
  finger f[FINGERS];
  double force;           /* magnitude of the summed finger forces [N] */
  int band;
  int exercise_bands;     /* band is by the exercise's bands (else the gauge's force bands) */
  double depth;           /* indentation of the deepest in-contact position finger [m]; NAN: none */
  double max_disp;        /* largest displacement in the newest frame [m] */
  double sim_time;
  uint64_t frame;
  int have_deform;
  int64_t fps_t0;
  int fps_count;
  double fps;
  uint32_t lm_flags_seen;  /* LM_* bits seen in this session's local models since it opened */
  double outside_s;        /* time the received local models were outside the model's valid range
                              (PALP_DDS_LM_OUTSIDE): a period per frame [s] */
  uint64_t outside_frame;  /* the last frame counted there (fingers of one frame count once) */
  int outside_counted;
  uint64_t late_haptic;    /* local models published > 2 periods after the previous frame's */
  uint64_t lost_haptic;    /* frames the bridge never received (while a finger stayed down) */
  finding_status fst;
  /* the server's session log as this session sees it, from its server's status (session 68): its
   * trainee's page says what her station says when it loses records */
  palp_dds_log_view log;
  answers *ans;           /* def.answers: its exercise's lumps and the marks (NULL: none yet) */
  int changed;            /* live data changed since the last live message */
  int cover_changed;      /* its coverage map changed since the last "cover" message */
  int64_t next_cover_ns;
  int64_t next_live_ns;
  /* feedback of this session's partition, read only while a position-driven finger presses (its
   * force comes from feedback alone; a force-driven contact carries its own) */
  dds_entity_t fb_sub, fb_r;
  stray_watch fb_strays;
  /* viewer membership, through a request writer of this session's own: the server admits at most
   * stations_per_writer (2) stations per writer (server/admission.c), as a station process has one */
  dds_entity_t req_w;
  int joined;
  int64_t unwanted_since, join_failed_ns;
  int64_t next_ask_ns; /* when its JOIN may be sent again (rejoin_if_dropped) */
  int asked_again;      /* JOINs sent again (the first said in the log) */
  int stall_asks;       /* JOINs still to send again after a stall of palp-web (STALL_ASKS) */
  uint32_t join_seq;    /* the request_seq of its last JOIN */
  char station[64];
} session;

typedef struct server_status {
  int used;
  palp_ServerStatus s; /* copy without the sessions sequence */
  uint32_t nsessions;
  palp_SessionLoad *loads;
  int64_t at_ns;
} server_status;

#define MAX_SERVERS 4

/* The newest debriefs (palp_debrief: what a trainee's marks found, at her exercise session's end),
 * kept for the pages that should see them: a class's sessions may close within the same second. */
#define DEBRIEFS 16
/* The names of the sessions that closed lately (palp_session_closed), as many as the server keeps. */
#define CLOSED_NAMES 64
/* What a session's debrief message says beside the server's debrief: its trainee, its phantom (the
 * exercise's name), what the bridge saw it cover (session_coverage; cov_rule 0: nothing tracked, 1
 * the force bands, 2 the exercise's), as the station's last lines say it, and how long it ran [s]
 * (the server's figure). Taken from the open session, or kept as it closes. */
typedef struct session_end {
  uint32_t sid, phantom;
  char trainee[64];
  double cov[3];
  int cov_rule;
  int cov_touched; /* from the server's finger samples (session 71): the review's footprint */
  double duration;
  dds_instance_handle_t server_pp; /* the participant that wrote its states (0: not known) */
} session_end;

typedef struct debrief_item {
  item msg;
  uint32_t sid;
  char trainee[64];
} debrief_item;

struct palp_web_hub {
  palp_web_hub_def def;
  char host[32];
  dds_entity_t pp, topic[PALP_TOPIC_COUNT];
  dds_entity_t catalogue_r, state_r, status_r, reply_r, sub, contact_r, deform_r, lm_r;
  dds_entity_t fsample_r; /* palp_finger_sample (session 71); 0: none */
  dds_entity_t exercise_r, fstatus_r, debrief_r;
  dds_entity_t debrief_score_r; /* palp_debrief_score (session 64): a practice session's score, for her page */
  dds_entity_t sexercise_r, finding_r, score_r; /* def.answers */
  dds_entity_t req_pub; /* secured: the publisher of the bridge's requests, in "palp/instructor/NAME" */
  palp_dds_strangers strangers; /* secured, with a refusal table: plain participants named (hub thread only) */
  int strangers_ready;
  int hinted;           /* hint_if_unanswered has looked */
  dds_entity_t ws, stop_gc;
  pthread_t thread;
  atomic_int running; /* written by palp_web_hub_stop, read by the hub's thread */
  palp_web_wake_fn wake;
  void *wake_ctx;
  uint32_t request_seq;
  /* A closed session's writers and their publishers and subscribers, deleted on a thread of their own: the
   * delete of a writer waits for its readers' acknowledgements (idl/palp_dds_reaper.h). */
  palp_dds_reaper *reaper;
  /* The sessions the stream readers' topic filters pass (contacts, feedback, deformations, local
   * models, finger samples): the hub's table, slot by slot, and the sessions heard open lately; a
   * flood of made-up keys in an unsecured classroom becomes no reader instance (idl/palp_dds_gate.h). */
  palp_dds_gate gate;

  /* DDS-thread state */
  palp_dds_origin origin; /* where each contact's and finding's writer writes (from_its_partition) */
  /* Disposes of finding keys of sessions never heard open: each an instance the findings reader keeps
   * while its writer lives (a dispose passes no filter); past a bound it is made anew (renew_findings). */
  dds_entity_t finding_topic_r; /* the findings reader's own, gated topic entity */
  uint64_t finding_strays, finding_renewals;
  int64_t finding_renewed_ns;
  /* the same for the stream readers, each on its own (renew_stream; each session's feedback reader
   * keeps its own in its session) */
  stray_watch contact_strays, deform_strays, lm_strays, fsample_strays;
  int stream_renewal_said;
  /* the writer of the sample drain() is handing its callback (on_phantom names a refused one's), and
   * the participant of that writer when drain() had it looked up (on_state), else 0 */
  dds_instance_handle_t sample_writer, sample_participant;
  /* and its source timestamp (DDS's clock); readers_since: that clock as the readers were made. A
   * finding status written before it is the historical copy a reader is handed as it joins a
   * running session: it answers no finding this bridge saw (palp_finding_answers.h) */
  dds_time_t sample_source, readers_since;
  /* a session whose server topics another participant wrote: said once per bridge (from_its_server) */
  int not_server_said;
  /* the publishers whose catalogue entries were refused and named in the log (refuse_phantom) */
  dds_instance_handle_t refused_pub[REFUSED_PUBLISHERS];
  int refused_pub_n, refused_pub_more;
  phantom ph[PALP_WEB_MAX_PHANTOMS];
  session s[PALP_WEB_MAX_SESSIONS];
  server_status srv[MAX_SERVERS];
  exercise ex[MAX_EXERCISES];
  int sessions_dirty, sessions_structure;
  /* sessions closed lately: a debrief may come after its session's CLOSED state */
  session_end closed[DEBRIEFS];
  int closed_next;
  pending_exercise pending_ex[SESSION_EXERCISES_PENDING];
  int64_t next_sessions_ns, next_join_ns, next_wake_ns, next_poll_ns;
  int64_t turn_ns; /* the DDS thread's last turn (STALL_NS) */

  /* shared with the web thread, under mu */
  pthread_mutex_t mu;
  uint64_t next_ver;
  item hello, phantom_msg[PALP_WEB_MAX_PHANTOMS], sessions_msg, status_msg, exercises_msg;
  finding_slot fs[PALP_WEB_MAX_SESSIONS];
  uint64_t bind_seq;
  item deform_msg[PALP_WEB_MAX_SESSIONS], live_msg[PALP_WEB_MAX_SESSIONS], answers_msg[PALP_WEB_MAX_SESSIONS],
      cover_msg[PALP_WEB_MAX_SESSIONS];
  uint32_t slot_sid[PALP_WEB_MAX_SESSIONS]; /* 0: free */
  char slot_trainee[PALP_WEB_MAX_SESSIONS][64]; /* its trainee's name, for scoped pages */
  debrief_item debrief[DEBRIEFS];
  int debrief_next;
  item ended_answers[DEBRIEFS]; /* the last answers of the exercise sessions that ended lately */
  int ended_answers_next;
  item scores[DEBRIEFS];        /* the scores of the exercise sessions the server graded lately */
  uint32_t scores_sid[DEBRIEFS];
  int scores_next;
  /* palp_session_closed (session 69): who the sessions that closed lately were, as the server said
   * it, so that a score of a session this bridge never saw open names its trainee */
  dds_entity_t closed_r; /* 0: none (a server or permissions from before it) */
  struct {
    uint32_t sid; /* 0: free */
    char trainee[64];
    dds_instance_handle_t server_pp; /* the participant that wrote it (0: not known) */
  } closed_names[CLOSED_NAMES];
  int closed_names_next;
  /* the session open/close lines of the last SESSION_LINES_WINDOW_NS (session_line_ok): a flood of made-up
   * session states (unsecured, anyone may write them) must not become a flood of log lines */
  int64_t lines_window_ns;
  unsigned lines_in_window, lines_skipped;
  /* the scores the server told trainees lately (palp_debrief_score, session 64: practice sessions
   * alone, the server decides), each for its session's bound page */
  item told_scores[DEBRIEFS];
  uint32_t told_scores_sid[DEBRIEFS];
  char told_scores_trainee[DEBRIEFS][64]; /* whose session it was, as trainee_of_session found it ("": not known) */
  int told_scores_next;
  /* palp_session_log (session 69): the newest own-loss counts per session, kept so that one read
   * before its session's state is applied once the session is known (on_status) */
  dds_entity_t session_log_r; /* 0: none (a bridge whose permissions predate the topic) */
  struct {
    uint32_t sid; /* 0: free */
    uint64_t shed, failed;
  } slog[2 * PALP_WEB_MAX_SESSIONS];
  int slog_next;
  palp_web_cursor *clients[MAX_CLIENTS_HARD];
  int nclients;
  int want[PALP_WEB_MAX_SESSIONS]; /* recomputed by the DDS thread from the cursors */
  /* Counted by the DDS thread alone, without the lock, except findings_written and findings_refused,
   * which the pages' requests count under mu. stats_pub is its copy under mu, made at the end of
   * every pass of the thread (at least every 100 ms), which palp_web_hub_stats_get reads: the counters
   * themselves were read under mu while the thread wrote them without it (ThreadSanitizer, session 75). */
  palp_web_hub_stats stats, stats_pub;
};

static int fail(char *err, size_t errlen, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err, errlen, fmt, ap);
  va_end(ap);
  return -1;
}

palp_web_hub_def palp_web_hub_default_def(void) {
  return (palp_web_hub_def){.domain = 0, .join = 1, .read_feedback = 1, .dashboard_hz = 10, .live_hz = 30,
                            .scale_mm = 30, .scale_min_mm = 0.5, .linger_s = 2, .bands = palp_web_bands_default(),
                            .answers = 1};
}

/* ---- publishing (DDS thread) --------------------------------------------------------------- */

/* Replaces an item's bytes (takes ownership of buf) with a new version. */
static void publish(palp_web_hub *h, item *it, unsigned char *buf, size_t len) {
  pthread_mutex_lock(&h->mu);
  unsigned char *old = it->buf;
  it->buf = buf;
  it->len = len;
  it->ver = buf ? ++h->next_ver : 0;
  pthread_mutex_unlock(&h->mu);
  free(old);
}

static void publish_json(palp_web_hub *h, item *it, cJSON *j) {
  char *s = j ? cJSON_PrintUnformatted(j) : NULL;
  cJSON_Delete(j);
  if (s) publish(h, it, (unsigned char *)s, strlen(s));
}

static cJSON *vec_json(const double *v, int n, double scale) {
  cJSON *a = cJSON_CreateArray();
  for (int i = 0; i < n; i++) cJSON_AddItemToArray(a, cJSON_CreateNumber(v[i] * scale));
  return a;
}

static void build_hello(palp_web_hub *h) {
  cJSON *j = cJSON_CreateObject();
  cJSON_AddStringToObject(j, "type", "hello");
  cJSON_AddStringToObject(j, "bridge", "palp-web");
  cJSON_AddNumberToObject(j, "domain", h->def.domain);
  cJSON_AddNumberToObject(j, "scale_mm", h->def.scale_mm);
  cJSON_AddNumberToObject(j, "scale_min_mm", h->def.scale_min_mm);
  cJSON *b = cJSON_AddObjectToObject(j, "bands");
  cJSON_AddNumberToObject(b, "touch_min", h->def.bands.touch_min);
  cJSON_AddNumberToObject(b, "light_max", h->def.bands.light_max);
  cJSON_AddNumberToObject(b, "medium_max", h->def.bands.medium_max);
  cJSON_AddNumberToObject(j, "dashboard_hz", h->def.dashboard_hz);
  cJSON_AddBoolToObject(j, "joins", h->def.join);
  /* A trainee page bound to an exercise session may mark findings (palp_finding). */
  cJSON_AddBoolToObject(j, "findings", h->def.sec.kind == PALP_DDS_ID_NONE);
  cJSON_AddNumberToObject(j, "finding_gap_s", FINDING_GAP_NS * 1e-9);
  cJSON_AddBoolToObject(j, "proxy", 1); /* palp_local_model: live fingers carry proxy and device */
  /* An instructor's dashboard is sent where exercise sessions' lumps are (docs/web.md). */
  cJSON_AddBoolToObject(j, "answers", h->def.answers);
  publish_json(h, &h->hello, j);
}

static void build_phantom(palp_web_hub *h, int slot) {
  const phantom *p = &h->ph[slot];
  cJSON *j = cJSON_CreateObject();
  cJSON_AddStringToObject(j, "type", "phantom");
  cJSON_AddNumberToObject(j, "id", p->id);
  cJSON_AddStringToObject(j, "name", p->name);
  cJSON_AddNumberToObject(j, "radius", p->radius);
  cJSON_AddNumberToObject(j, "dome_triangles", p->dome_tris);
  cJSON *rest = cJSON_AddArrayToObject(j, "rest");
  for (int i = 0; i < 3 * p->n; i++) cJSON_AddItemToArray(rest, cJSON_CreateNumber(round(p->rest[i] * 1e7) * 1e-7));
  cJSON *tri = cJSON_AddArrayToObject(j, "triangles");
  for (int i = 0; i < 3 * p->tri_count; i++) cJSON_AddItemToArray(tri, cJSON_CreateNumber(p->tri[i]));
  publish_json(h, &h->phantom_msg[slot], j);
}

/* A session's pressed-skin map for the dashboard and the pages following it (docs/web.md, "The pressed skin"):
 * {"type": "cover", "session", "phantom", "bands": one hex digit per rest vertex, the bands it was
 * pressed in as bits (1 light, 2 medium, 4 deep; 0 not pressed)}, by the rule its coverage figures
 * count by (palp_coverage): 338 characters for the shipped dome. */
/* The session's coverage map: the finger samples' once one has come, else the local models'. */
static const palp_coverage *session_map(const session *s) { return s->samples && s->touched ? s->touched : s->cov; }

static void build_cover(palp_web_hub *h, int slot) {
  const session *s = &h->s[slot];
  if (!s->cov || !s->ph) return;
  const int n = s->ph->n;
  char *text = malloc((size_t)n + 128);
  if (!text) return;
  const int k = snprintf(text, 128, "{\"type\":\"cover\",\"session\":%u,\"phantom\":%u,\"bands\":\"", s->id, s->ph->id);
  uint8_t *bits = (uint8_t *)text + k; /* the bits, then their digits in their place */
  if (palp_coverage_vertex_bands(session_map(s), bits, n) != n) {
    free(text);
    return;
  }
  for (int i = 0; i < n; i++) text[k + i] = "0123456789abcdef"[bits[i] & 15];
  memcpy(text + k + n, "\"}", 3);
  publish(h, &h->cover_msg[slot], (unsigned char *)text, (size_t)(k + n + 2));
}

/* Coverage as the session's band rule counts it: in an exercise the area pressed in each band
 * itself, as the assessment's thoroughness; else the area pressed at each band or deeper. */
static void session_coverage(const session *s, double cov[3]) {
  if (s->exercise_bands) palp_coverage_band_fractions(session_map(s), cov);
  else palp_coverage_fractions(session_map(s), cov);
}

static void build_sessions(palp_web_hub *h) {
  cJSON *j = cJSON_CreateObject();
  cJSON_AddStringToObject(j, "type", "sessions");
  cJSON *arr = cJSON_AddArrayToObject(j, "sessions");
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++) {
    const session *s = &h->s[i];
    if (!s->used) continue;
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "id", s->id);
    cJSON_AddNumberToObject(o, "phantom", s->st.phantom_id);
    cJSON_AddStringToObject(o, "phantom_name", s->ph ? s->ph->name : "");
    cJSON_AddStringToObject(o, "trainee", s->st.trainee_name);
    cJSON_AddStringToObject(o, "station", s->st.trainee_station);
    /* An open session's state says why it waits, when it does: its trainee station lost and
     * the session held for it to come back (station_grace, docs/server.md); "" otherwise. */
    cJSON_AddStringToObject(o, "status", s->st.reason);
    cJSON_AddNumberToObject(o, "visual", s->st.visual_count);
    cJSON_AddNumberToObject(o, "observer", s->st.observer_count);
    cJSON_AddNumberToObject(o, "tick_hz", s->st.tick_rate_hz);
    cJSON_AddNumberToObject(o, "duration", s->st.duration);
    cJSON_AddNumberToObject(o, "ticks", (double)s->st.ticks);
    cJSON_AddNumberToObject(o, "overruns", (double)s->st.overruns);
    cJSON_AddNumberToObject(o, "contact_samples", (double)s->st.contact_samples);
    cJSON_AddNumberToObject(o, "rejected", (double)s->st.rejected_samples);
    cJSON_AddNumberToObject(o, "peak_force", s->st.peak_force);
    cJSON_AddNumberToObject(o, "peak_disp_mm", s->st.peak_displacement * 1e3);
    cJSON_AddNumberToObject(o, "force", s->force);
    cJSON_AddStringToObject(o, "band", palp_web_band_name(s->band));
    cJSON_AddStringToObject(o, "band_rule", s->exercise_bands ? "exercise" : "force");
    double cov[3];
    session_coverage(s, cov);
    cJSON_AddItemToObject(o, "coverage", vec_json(cov, 3, 1));
    /* "touched": from the server's finger samples, the review's own footprint (session 71) */
    cJSON_AddStringToObject(o, "coverage_rule", s->samples && s->touched ? "touched" : "approximated");
    cJSON_AddNumberToObject(o, "fps", s->fps);
    cJSON_AddBoolToObject(o, "joined", s->joined);
    int pos = 0;
    for (int k = 0; k < FINGERS; k++) pos |= s->f[k].mode == palp_CONTACT_FINGER;
    cJSON_AddBoolToObject(o, "position_finger", pos);
    /* Model-validity bits seen since the session opened (LM_*), and the newest models' bits. */
    uint32_t now_flags = 0;
    for (int k = 0; k < FINGERS; k++)
      if (s->f[k].mode == palp_CONTACT_FINGER && s->f[k].lm_valid) now_flags |= s->f[k].lm_flags;
    cJSON_AddNumberToObject(o, "model_flags", now_flags);
    cJSON_AddNumberToObject(o, "model_flags_seen", s->lm_flags_seen);
    cJSON_AddNumberToObject(o, "outside_s", s->outside_s);
    /* Findings: the marks standing in the server's newest palp_finding_status (null before
     * one arrived). Late haptic updates: as the bridge sees the local models (docs/web.md). */
    const exercise *ex = NULL;
    for (int k = 0; k < MAX_EXERCISES && !ex; k++)
      if (h->ex[k].used && h->ex[k].phantom_id == s->st.phantom_id) ex = &h->ex[k];
    if (ex) cJSON_AddStringToObject(o, "exercise", ex->name);
    else cJSON_AddNullToObject(o, "exercise");
    if (s->fst.valid) cJSON_AddNumberToObject(o, "findings", s->fst.marks);
    else cJSON_AddNullToObject(o, "findings");
    /* Time left of the exercise's limit [s]: the server's newest figure (its finding status, 2 Hz)
     * less the time since it came; null without a status or a limit (the server's -1). */
    if (s->fst.valid && isfinite(s->fst.time_left) && s->fst.time_left >= 0) {
      const double age = (double)(palp_dds_now_ns() - s->fst.at_ns) * 1e-9;
      cJSON_AddNumberToObject(o, "time_left", round(fmax(0.0, s->fst.time_left - age) * 10) / 10);
    } else {
      cJSON_AddNullToObject(o, "time_left");
    }
    /* The records the session log lost while the session ran (session 69): its own where its server
     * says them (palp_session_log, log_own), else the whole server's since the bridge saw it listed;
     * the dashboard's card shows them, so the instructor knows which reviews will be incomplete. */
    cJSON_AddNumberToObject(o, "log_lost", (double)(s->log.shed + s->log.failed));
    cJSON_AddBoolToObject(o, "log_own", s->log.own);
    /* The session log's losses while it runs, in her station's words (palp_dds_log_view_words); "": none. */
    char log_words[320];
    const int log_state = palp_dds_log_view_words(&s->log, 1, log_words, sizeof log_words);
    cJSON_AddStringToObject(o, "log", log_words);
    /* ... and which of them, so that a page colours them without reading its words (session 71) */
    cJSON_AddStringToObject(o, "log_state", log_state == 1 ? "losing" : log_state == 2 ? "writing" : "");
    /* ... and in the words of an instructor's station following it (she is the one to act) */
    palp_dds_log_view_words(&s->log, 0, log_words, sizeof log_words);
    cJSON_AddStringToObject(o, "log_observer", log_words);
    /* ... and the loss in all, which a page shows once the session has ended (her station's last line) */
    palp_dds_log_view_summary(&s->log, log_words, sizeof log_words);
    cJSON_AddStringToObject(o, "log_summary", log_words);
    if (pos) {
      cJSON_AddNumberToObject(o, "late_haptic", (double)s->late_haptic);
      cJSON_AddNumberToObject(o, "lost_haptic", (double)s->lost_haptic);
    } else {
      cJSON_AddNullToObject(o, "late_haptic"); /* a force-driven session has no local models */
      cJSON_AddNullToObject(o, "lost_haptic");
    }
    cJSON_AddItemToArray(arr, o);
  }
  publish_json(h, &h->sessions_msg, j);
}

static void build_exercises(palp_web_hub *h) {
  cJSON *j = cJSON_CreateObject();
  cJSON_AddStringToObject(j, "type", "exercises");
  cJSON *arr = cJSON_AddArrayToObject(j, "exercises");
  for (int i = 0; i < MAX_EXERCISES; i++) {
    const exercise *e = &h->ex[i];
    if (!e->used) continue;
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "phantom", e->phantom_id);
    cJSON_AddStringToObject(o, "name", e->name);
    cJSON_AddStringToObject(o, "title", e->title);
    cJSON_AddStringToObject(o, "instructions", e->instructions);
    cJSON_AddNumberToObject(o, "time_limit", e->time_limit);
    cJSON_AddNumberToObject(o, "max_force", e->max_force);
    /* its bands, as the exercise file gives them (mm, N), when the bridge bands by them */
    if (e->bands_ok) {
      cJSON *bands = cJSON_AddObjectToObject(o, "bands");
      for (int b = 0; b < PALP_BAND_COUNT; b++) {
        cJSON *bo = cJSON_AddObjectToObject(bands, palp_band_name(b));
        if (e->band[b].has_depth) {
          const double d[2] = {round(e->band[b].depth_min * 1e6) / 1e3, round(e->band[b].depth_max * 1e6) / 1e3};
          cJSON_AddItemToObject(bo, "depth_mm", cJSON_CreateDoubleArray(d, 2));
        }
        if (e->band[b].has_force) {
          const double f[2] = {e->band[b].force_min, e->band[b].force_max};
          cJSON_AddItemToObject(bo, "force_N", cJSON_CreateDoubleArray(f, 2));
        }
      }
    }
    cJSON_AddItemToArray(arr, o);
  }
  publish_json(h, &h->exercises_msg, j);
}

/* Copies a wire string for a hand-built JSON message: printable ASCII only, no quote or backslash. */
static void json_safe(char *out, size_t outlen, const char *in) {
  size_t k = 0;
  for (; in && *in && k + 1 < outlen; in++) {
    const unsigned char c = (unsigned char)*in;
    out[k++] = (c >= 32 && c < 127 && c != '"' && c != '\\') ? (char)c : '?';
  }
  out[k] = 0;
}

static void build_status(palp_web_hub *h) {
  cJSON *j = cJSON_CreateObject();
  cJSON_AddStringToObject(j, "type", "status");
  cJSON *arr = cJSON_AddArrayToObject(j, "servers");
  for (int i = 0; i < MAX_SERVERS; i++) {
    const server_status *ss = &h->srv[i];
    if (!ss->used) continue;
    const palp_ServerStatus *s = &ss->s;
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "id", s->server_id);
    cJSON_AddNumberToObject(o, "uptime", s->uptime);
    cJSON_AddNumberToObject(o, "tick_hz", s->tick_rate_hz);
    cJSON_AddNumberToObject(o, "tick_threads", s->tick_threads);
    cJSON_AddNumberToObject(o, "sessions_open", s->sessions_open);
    cJSON_AddNumberToObject(o, "sessions_total", (double)s->sessions_total);
    cJSON_AddNumberToObject(o, "load", s->load);
    const double tick[3] = {s->tick_us_p50, s->tick_us_p99, s->tick_us_max};
    cJSON_AddItemToObject(o, "tick_us", vec_json(tick, 3, 1));
    cJSON_AddNumberToObject(o, "ticks", (double)s->ticks);
    cJSON_AddNumberToObject(o, "overruns", (double)s->overruns);
    double rej[10];
    for (int k = 0; k < 10; k++) rej[k] = (double)s->rejected[k];
    cJSON_AddItemToObject(o, "rejected", vec_json(rej, 10, 1));
    const double log[3] = {(double)s->log_written, (double)s->log_shed, (double)s->log_failed};
    cJSON_AddItemToObject(o, "log", vec_json(log, 3, 1));
    cJSON *ls = cJSON_AddArrayToObject(o, "sessions");
    for (uint32_t k = 0; k < ss->nsessions; k++) {
      const palp_SessionLoad *l = &ss->loads[k];
      cJSON *x = cJSON_CreateObject();
      cJSON_AddNumberToObject(x, "id", l->session_id);
      cJSON_AddNumberToObject(x, "ticks", (double)l->ticks);
      cJSON_AddNumberToObject(x, "overruns", (double)l->overruns);
      cJSON_AddNumberToObject(x, "awake_ticks", (double)l->awake_ticks);
      cJSON_AddNumberToObject(x, "step_us_max", l->step_us_max);
      cJSON_AddItemToArray(ls, x);
    }
    cJSON_AddItemToArray(arr, o);
  }
  /* Who DDS Security refused (a revoked or expired certificate, another CA's): this bridge
   * refuses them as the server does. The names come from certificates: made printable by
   * palp_dds_refusal_parse, escaped by cJSON, and the page sets them as text. */
  cJSON *ref = cJSON_AddArrayToObject(j, "refused");
  palp_dds_refusal_entry e[PALP_DDS_REFUSAL_SLOTS];
  const int ne = h->def.refusals ? palp_dds_refusals_list(h->def.refusals, e, PALP_DDS_REFUSAL_SLOTS) : 0;
  for (int k = 0; k < ne; k++) {
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "who", e[k].r.who);
    cJSON_AddStringToObject(o, "why", e[k].r.why);
    cJSON_AddStringToObject(o, "at", palp_dds_refusal_kind_name(e[k].r.kind));
    cJSON_AddNumberToObject(o, "count", (double)e[k].count);
    cJSON_AddItemToArray(ref, o);
  }
  publish_json(h, &h->status_msg, j);
}

/* Appends to a fixed buffer: once a text does not fit, *n passes cap and every later call writes
 * nothing, so the caller tests *n < cap once at the end. (snprintf returns the length it wanted: the
 * pattern n += snprintf(buf + n, sizeof buf - n, ...) handed a wrapped size to the next call once n
 * passed the buffer, and wrote past it; session 75, found by review with a contact of 1e308 m.) */
static void app(char *buf, size_t cap, size_t *n, const char *fmt, ...) {
  if (*n >= cap) return;
  va_list ap;
  va_start(ap, fmt);
  const int r = vsnprintf(buf + *n, cap - *n, fmt, ap);
  va_end(ap);
  *n = r < 0 ? cap : *n + (size_t)r;
}

/* A number for the live message: JSON has no inf or nan (the page's JSON.parse would throw and its
 * view freeze); every value here is checked where it arrives, so this is the last line only. */
static double jnum(double x) { return isfinite(x) ? x : 0.0; }

static void build_live(palp_web_hub *h, int slot) {
  const session *s = &h->s[slot];
  double cov[3];
  session_coverage(s, cov);
  /* four fingers at the bounds on what arrives (LIVE_MAX_*: ~400 characters each with a local model),
   * the findings' reason (128) and the head: ~2.2 kB at most */
  char buf[4096];
  size_t n = 0;
  app(buf, sizeof buf, &n,
      "{\"type\":\"live\",\"session\":%u,\"frame\":%.0f,\"sim_time\":%.4f,\"force\":%.4f,"
      "\"band\":\"%s\",\"band_rule\":\"%s\",\"max_disp_mm\":%.3f,\"fps\":%.1f,"
      "\"coverage\":[%.4f,%.4f,%.4f],",
      s->id, jnum((double)s->frame), jnum(s->sim_time), jnum(s->force), palp_web_band_name(s->band),
      s->exercise_bands ? "exercise" : "force", jnum(s->max_disp * 1e3), jnum(s->fps), jnum(cov[0]), jnum(cov[1]),
      jnum(cov[2]));
  /* the indentation the band was read from (exercise bands), [mm] */
  if (s->exercise_bands && isfinite(s->depth)) app(buf, sizeof buf, &n, "\"depth_mm\":%.3f,", s->depth * 1e3);
  app(buf, sizeof buf, &n, "\"fingers\":[");
  int first = 1;
  for (int k = 0; k < FINGERS; k++) {
    const finger *f = &s->f[k];
    if (f->mode == palp_CONTACT_RELEASE) continue;
    const double *fv = f->mode == palp_CONTACT_FORCE ? f->force : f->fb;
    app(buf, sizeof buf, &n,
        "%s{\"finger\":%d,\"mode\":\"%s\",\"center\":[%.6f,%.6f,%.6f],\"force\":[%.4f,%.4f,%.4f],"
        "\"radius\":%.5f}",
        first ? "" : ",", k, f->mode == palp_CONTACT_FORCE ? "force" : "finger", jnum(f->center[0]), jnum(f->center[1]),
        jnum(f->center[2]), jnum(fv[0]), jnum(fv[1]), jnum(fv[2]), jnum(f->radius));
    /* A position-driven finger's newest local model: the proxy (fingertip on the surface) and
     * the device point, so that the page draws the tip where the phantom stops it (written over the
     * finger's closing brace, and closing it again). */
    if (f->mode == palp_CONTACT_FINGER && f->lm_valid && n < sizeof buf) {
      n--;
      app(buf, sizeof buf, &n,
          ",\"proxy\":[%.6f,%.6f,%.6f],\"device\":[%.6f,%.6f,%.6f],\"in_contact\":%s,"
          "\"model_force\":%.4f,\"flags\":%u,\"force_limit\":%s,\"out_of_range\":%s}",
          jnum(f->proxy[0]), jnum(f->proxy[1]), jnum(f->proxy[2]), jnum(f->device[0]), jnum(f->device[1]),
          jnum(f->device[2]), f->lm_contact ? "true" : "false", jnum(f->lm_force), (unsigned)f->lm_flags,
          (f->lm_flags & palp_LM_FORCE_LIMIT) ? "true" : "false",
          (f->lm_flags & PALP_DDS_LM_OUTSIDE) ? "true" : "false");
    }
    first = 0;
  }
  app(buf, sizeof buf, &n, "]");
  if (s->fst.valid) {
    char reason[128];
    json_safe(reason, sizeof reason, s->fst.reason);
    app(buf, sizeof buf, &n,
        ",\"findings\":{\"marks\":%u,\"last_mark_id\":%u,\"last_accepted\":%s,\"reason\":\"%s\","
        "\"time_left\":%.3f,\"age\":%.3f}",
        s->fst.marks, s->fst.last_mark_id, s->fst.last_accepted ? "true" : "false", reason, jnum(s->fst.time_left),
        jnum((double)(palp_dds_now_ns() - s->fst.at_ns) * 1e-9));
  }
  app(buf, sizeof buf, &n, "}");
  if (n >= sizeof buf) {
    h->stats.dropped++; /* cannot be with the values checked as they arrive; counted, not sent */
    return;
  }
  unsigned char *m = malloc(n);
  if (!m) return;
  memcpy(m, buf, n);
  publish(h, &h->live_msg[slot], m, n);
}

/* ---- DDS samples ---------------------------------------------------------------------------- */

static int vec_finite(const palp_Vec3 *v) { return isfinite(v->x) && isfinite(v->y) && isfinite(v->z); }
/* finite and no longer than bound (the live message's bounds, LIVE_MAX_*) */
static int vec_within(const palp_Vec3 *v, double bound) {
  return vec_finite(v) && hypot(hypot(v->x, v->y), v->z) <= bound;
}

static phantom *find_phantom(palp_web_hub *h, uint32_t id, int create, int *slot) {
  for (int i = 0; i < PALP_WEB_MAX_PHANTOMS; i++)
    if (h->ph[i].used && h->ph[i].id == id) return *slot = i, &h->ph[i];
  if (!create) return NULL;
  for (int i = 0; i < PALP_WEB_MAX_PHANTOMS; i++)
    if (!h->ph[i].used) {
      memset(&h->ph[i], 0, sizeof h->ph[i]);
      h->ph[i].used = 1;
      h->ph[i].id = id;
      return *slot = i, &h->ph[i];
    }
  return NULL;
}

static session *find_session(palp_web_hub *h, uint32_t id, int *slot) {
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
    if (h->s[i].used && h->s[i].id == id) return *slot = i, &h->s[i];
  return NULL;
}

static void attach_coverage(session *s) {
  if (s->cov || !s->ph) return;
  int rc;
  s->cov = palp_coverage_create(s->ph->rest, s->ph->n, s->ph->tri, s->ph->tri_count, s->ph->dome_tris, &rc);
  if (s->cov)
    s->touched = palp_coverage_create(s->ph->rest, s->ph->n, s->ph->tri, s->ph->tri_count, s->ph->dome_tris, &rc);
  s->samples = 0;
}

/* Why a catalogue entry cannot be used, into why (0 when it can). Checked before use: a mesh the pages
 * could not draw is dropped, not half-shown; and one larger than any palp-server's is refused before
 * it is walked, copied or sent. At the old bound (1M vertices, 4M triangles) the bridge kept ~70 MB of
 * it, built ~100 MB of JSON through a cJSON tree of the order of 1 GB, and sent that to every page; at
 * this bound a mesh's message is ~14 MB (measured: a 200,000-vertex hemisphere). */
static int phantom_refusal(const palp_Phantom *p, char *why, size_t len) {
  const uint32_t n = p->rest._length, nt = p->triangles._length;
  if (n == 0 || n > PALP_WEB_PHANTOM_MAX_VERTICES || !p->rest._buffer)
    return snprintf(why, len, "%u rest vertices, beyond the %d of the largest mesh a palp-server publishes",
                    n, PALP_WEB_PHANTOM_MAX_VERTICES), 1;
  if (nt == 0 || nt % 3 != 0 || nt / 3 > PALP_WEB_PHANTOM_MAX_TRIANGLES || !p->triangles._buffer)
    return snprintf(why, len, "%u triangle indices (want a positive multiple of 3, at most %d triangles)", nt,
                    PALP_WEB_PHANTOM_MAX_TRIANGLES), 1;
  if (p->dome_triangle_count <= 0 || (uint32_t)p->dome_triangle_count > nt / 3)
    return snprintf(why, len, "dome_triangle_count %d of %u triangles", (int)p->dome_triangle_count, nt / 3), 1;
  if (!(isfinite(p->radius) && p->radius > 0)) return snprintf(why, len, "radius %g m", p->radius), 1;
  for (uint32_t i = 0; i < nt; i++)
    if (p->triangles._buffer[i] < 0 || (uint32_t)p->triangles._buffer[i] >= n)
      return snprintf(why, len, "triangle %u names vertex %d of %u", i / 3, (int)p->triangles._buffer[i], n), 1;
  for (uint32_t i = 0; i < n; i++)
    if (!vec_finite(&p->rest._buffer[i]))
      return snprintf(why, len, "rest vertex %u is not finite", i), 1;
  return 0;
}

/* Counts a refused catalogue entry and names its publisher in the log, once per publisher and for at
 * most REFUSED_PUBLISHERS of them: a broken or hostile peer republishing (the server does at every
 * session's open and close) must not fill the log; the stats line counts them all. */
static void refuse_phantom(palp_web_hub *h, const palp_Phantom *p, const char *why) {
  h->stats.dropped++;
  h->stats.catalogue_refused++;
  const dds_instance_handle_t w = h->sample_writer;
  for (int k = 0; k < h->refused_pub_n; k++)
    if (h->refused_pub[k] == w) return;
  if (h->refused_pub_n == REFUSED_PUBLISHERS) {
    if (!h->refused_pub_more)
      palp_log_warn(h->def.log, "catalogue: more than %d publishers of refused phantoms; the others are counted, not "
                                "named (--stats)", REFUSED_PUBLISHERS);
    h->refused_pub_more = 1;
    return;
  }
  h->refused_pub[h->refused_pub_n++] = w;
  /* named by its participant's GUID (plain DDS: any peer may publish a catalogue) */
  char who[64], name[64];
  palp_dds_writer_participant_text(h->catalogue_r, w, who, sizeof who);
  palp_log_warn(h->def.log, "catalogue: phantom %u \"%s\" from %s refused: %s; its publisher's further refusals are "
                            "counted, not logged (--stats)",
                p->phantom_id, palp_log_printable(p->name, name, sizeof name), who, why);
}

static void on_phantom(palp_web_hub *h, const palp_Phantom *p) {
  const uint32_t n = p->rest._length, nt = p->triangles._length;
  char why[160];
  if (phantom_refusal(p, why, sizeof why)) {
    refuse_phantom(h, p, why);
    return;
  }
  int slot;
  phantom *ph = find_phantom(h, p->phantom_id, 1, &slot);
  if (!ph) { /* more phantoms than PALP_WEB_MAX_PHANTOMS */
    h->stats.dropped++;
    return;
  }
  const int same = ph->n == (int)n && ph->tri_count == (int)(nt / 3);
  if (same && ph->dome_tris == p->dome_triangle_count && ph->radius == p->radius && !strcmp(ph->name, p->name) &&
      !memcmp(ph->tri, p->triangles._buffer, sizeof *ph->tri * nt)) {
    int moved = 0;
    for (uint32_t i = 0; i < n && !moved; i++)
      moved = ph->rest[3 * i] != p->rest._buffer[i].x || ph->rest[3 * i + 1] != p->rest._buffer[i].y ||
              ph->rest[3 * i + 2] != p->rest._buffer[i].z;
    /* The server republishes its catalogue whenever a session opens or closes (active_sessions):
     * the pages need the mesh once, not again with every session. */
    if (!moved) return;
  }
  if (!same) {
    double *rest = malloc(sizeof *rest * 3 * n);
    int32_t *tri = malloc(sizeof *tri * nt);
    if (!rest || !tri) {
      free(rest);
      free(tri);
      h->stats.dropped++;
      return;
    }
    /* Sessions of this phantom lose their coverage map (its vertex count changed). */
    for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
      if (h->s[i].used && h->s[i].ph == ph) {
        palp_coverage_destroy(h->s[i].cov);
        palp_coverage_destroy(h->s[i].touched);
        h->s[i].cov = h->s[i].touched = NULL;
        h->s[i].samples = 0;
      }
    free(ph->rest);
    free(ph->tri);
    ph->rest = rest;
    ph->tri = tri;
  }
  ph->n = (int)n;
  ph->tri_count = (int)(nt / 3);
  ph->dome_tris = p->dome_triangle_count;
  ph->radius = p->radius;
  snprintf(ph->name, sizeof ph->name, "%s", p->name);
  for (uint32_t i = 0; i < n; i++) {
    ph->rest[3 * i] = p->rest._buffer[i].x;
    ph->rest[3 * i + 1] = p->rest._buffer[i].y;
    ph->rest[3 * i + 2] = p->rest._buffer[i].z;
  }
  memcpy(ph->tri, p->triangles._buffer, sizeof *ph->tri * nt);
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
    if (h->s[i].used && h->s[i].st.phantom_id == ph->id) {
      h->s[i].ph = ph;
      attach_coverage(&h->s[i]);
    }
  build_phantom(h, slot);
  h->sessions_dirty = h->sessions_structure = 1; /* phantom names in the list */
}

/* seq 0: a new request (the next of the bridge's numbers); a JOIN's number is kept, so that the same JOIN
 * can be sent again (rejoin_if_dropped): the server answers a station it holds under that number again,
 * and takes one it dropped back (server/server.c, handle_join). */
static void send_request_seq(palp_web_hub *h, session *s, int op, uint32_t seq) {
  palp_SessionRequest rq;
  memset(&rq, 0, sizeof rq);
  snprintf(rq.station_id, sizeof rq.station_id, "%s", s->station);
  rq.request_seq = seq ? seq : ++h->request_seq;
  if (op == palp_OP_JOIN) s->join_seq = rq.request_seq;
  rq.op = op;
  rq.role = palp_ROLE_VISUAL;
  rq.phantom_id = s->st.phantom_id;
  rq.session_id = s->id;
  /* secured, the server accepts a join only under the authenticated identity's own name */
  snprintf(rq.user_name, sizeof rq.user_name, "%s", h->def.sec.kind != PALP_DDS_ID_NONE ? h->def.sec.name : "palp-web");
  rq.want_feedback = 0; /* the bridge reads feedback only when the trainee's station asks for it */
  rq.want_deformation = 1;
  if (s->req_w <= 0) /* secured: in the identity's own partition, which tells the server who asks */
    s->req_w = palp_dds_create_writer(h->req_pub > 0 ? h->req_pub : h->pp, h->topic[PALP_TOPIC_SESSION_REQUEST],
                                      PALP_TOPIC_SESSION_REQUEST);
  if (s->req_w > 0) dds_write(s->req_w, &rq);
}

static void send_request(palp_web_hub *h, session *s, int op) { send_request_seq(h, s, op, 0); }

/* Forgets the session's request instance (the server's station table is finite). */
static void dispose_request(session *s) {
  if (s->req_w <= 0) return;
  palp_SessionRequest key;
  memset(&key, 0, sizeof key);
  snprintf(key.station_id, sizeof key.station_id, "%s", s->station);
  dds_dispose(s->req_w, &key);
}

/* s->joined is the DDS thread's; its copy in the finding slot is what a page's mark is checked
 * against (finding_request, web thread, under h->mu). */
static void set_joined(palp_web_hub *h, session *s, int joined) {
  s->joined = joined;
  if (joined) s->next_ask_ns = palp_dds_now_ns() + REASK_AFTER_NS;
  pthread_mutex_lock(&h->mu);
  h->fs[s - h->s].joined = joined;
  pthread_mutex_unlock(&h->mu);
}

static void leave(palp_web_hub *h, session *s) {
  if (!s->joined) return;
  /* As a station says goodbye: OP_LEAVE so the server tells it from a crash, then the disposal
   * so that it forgets the station (its station table is finite). */
  send_request(h, s, palp_OP_LEAVE);
  dispose_request(s);
  set_joined(h, s, 0);
  h->stats.leaves++;
  h->sessions_dirty = 1;
}

static const exercise *find_exercise(const palp_web_hub *h, uint32_t phantom_id) {
  for (int k = 0; k < MAX_EXERCISES; k++)
    if (h->ex[k].used && h->ex[k].phantom_id == phantom_id) return &h->ex[k];
  return NULL;
}

/* An exercise session gets its palp_finding writer as soon as the bridge knows it, so that the
 * server's reader has matched it long before a trainee page's first mark (a reliable volatile
 * sample written before the match would be lost). */
static void update_finding_writer(palp_web_hub *h, int slot) {
  session *s = &h->s[slot];
  const int ex = find_exercise(h, s->st.phantom_id) != NULL;
  dds_entity_t pub = 0, w = 0;
  pthread_mutex_lock(&h->mu);
  finding_slot *fs = &h->fs[slot];
  fs->exercise = ex;
  /* Secured, the bridge is an instructor, whose permissions do not write into a trainee's
   * session (docs/security.md): the trainee marks findings from the station, not the page. */
  const int need = ex && fs->pub <= 0 && s->st.partition[0] && h->def.sec.kind == PALP_DDS_ID_NONE;
  pthread_mutex_unlock(&h->mu);
  if (!need) return;
  pub = palp_dds_session_publisher(h->pp, s->st.partition);
  if (pub > 0) w = palp_dds_create_writer(pub, h->topic[PALP_TOPIC_FINDING], PALP_TOPIC_FINDING);
  if (pub <= 0 || w <= 0) {
    palp_log_warn(h->def.log, "session %u: cannot create the findings writer", s->id);
    if (pub > 0) dds_delete(pub);
    return;
  }
  pthread_mutex_lock(&h->mu);
  fs->pub = pub;
  fs->w = w;
  pthread_mutex_unlock(&h->mu);
}

/* ---- the hidden lumps, for an instructor's dashboard (docs/web.md, "The hidden lumps") ---------
 * The server writes an exercise session's exercise, lesions included, on palp_session_exercise for
 * instructors' readers only; the bridge is one when secured. What the dashboard is sent is what the
 * debrief would say if the session ended now, matched by the same function (palp_assess_findings),
 * live: each lump's place and whether a standing mark found it, and each standing mark's lump. */

static answers *session_answers(palp_web_hub *h, session *s) {
  if (!h->def.answers) return NULL;
  if (!s->ans) s->ans = calloc(1, sizeof *s->ans);
  if (!s->ans) h->stats.dropped++;
  return s->ans;
}

/* The dome's radius as the assessment measures it: |rest pole|, the highest rest vertex [m]. */
static double dome_radius(const phantom *p) {
  int top = 0;
  for (int i = 1; i < p->n; i++)
    if (p->rest[3 * i + 2] > p->rest[3 * top + 2]) top = i;
  const double *v = p->rest + 3 * top;
  return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static cJSON *place_json(palp_vec3 p) {
  const double pt[3] = {round(p.x * 1e4) / 10, round(p.y * 1e4) / 10, round(p.z * 1e4) / 10};
  return cJSON_CreateDoubleArray(pt, 3);
}

/* {"type": "answers", "session", "exercise", "lesions", "found", "marks", "false_marks", "duplicates",
 *  "refused", "unanswered", "lumps": [{"found_by", "clock_h", "at_pole", "arc_mm", "across_mm", "deep_mm", "point_mm"}],
 *  "marks_at": [{"id", "point_mm", "lump"}]}: lump is the lump's number (from 1) a mark found, 0 near no
 * lump, -1 on a lump another mark found. Places as every tool names them (palp_place_*). */
static cJSON *answers_json(palp_web_hub *h, session *s) {
  answers *a = s->ans;
  a->dirty = 0;
  if (!a->ex || !s->ph) return NULL;
  const double R = dome_radius(s->ph);
  palp_assess_result r;
  int match[ANSWER_MARKS];
  if (palp_assess_findings(a->ex, R, a->mark, a->n, &r, match) < 0) {
    h->stats.dropped++;
    return NULL;
  }
  cJSON *j = cJSON_CreateObject();
  cJSON_AddStringToObject(j, "type", "answers");
  cJSON_AddNumberToObject(j, "session", s->id);
  cJSON_AddStringToObject(j, "exercise", a->ex->name);
  cJSON_AddNumberToObject(j, "lesions", r.lesion_count);
  cJSON_AddNumberToObject(j, "found", r.found);
  cJSON_AddNumberToObject(j, "marks", r.findings); /* standing: palp_assess counts the withdrawn apart */
  cJSON_AddNumberToObject(j, "false_marks", r.false_positives);
  cJSON_AddNumberToObject(j, "duplicates", r.duplicates);
  cJSON_AddNumberToObject(j, "refused", a->refused);
  cJSON_AddNumberToObject(j, "unanswered", a->unanswered);
  cJSON *lumps = cJSON_AddArrayToObject(j, "lumps");
  for (int l = 0; l < a->ex->lesion_count && l < PALP_MAX_LESIONS; l++) {
    const palp_exercise_lesion *L = &a->ex->lesion[l];
    const palp_vec3 p = palp_exercise_lesion_surface(L, R);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "found_by", r.lesion_found[l] >= 0 ? a->id[r.lesion_found[l]] : 0);
    cJSON_AddNumberToObject(o, "clock_h", palp_place_clock_shown(p)); /* as the page prints it: 12, never 0 */
    cJSON_AddBoolToObject(o, "at_pole", palp_place_at_pole(p)); /* no clock worth reading there */
    /* whole mm as the station and palp-review print them (palp_place_mm_shown; 0.1 mm before session 82) */
    cJSON_AddNumberToObject(o, "arc_mm", palp_place_mm_shown(palp_place_arc(p)));
    cJSON_AddNumberToObject(o, "across_mm", palp_place_mm_shown(L->diameter));
    cJSON_AddNumberToObject(o, "deep_mm", palp_place_mm_shown(L->depth));
    cJSON_AddItemToObject(o, "point_mm", place_json(p));
    cJSON_AddItemToArray(lumps, o);
  }
  cJSON *marks = cJSON_AddArrayToObject(j, "marks_at");
  for (int k = 0; k < a->n; k++) {
    if (a->mark[k].withdrawn) continue;
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "id", a->id[k]);
    cJSON_AddItemToObject(o, "point_mm", place_json(a->mark[k].point));
    cJSON_AddNumberToObject(o, "lump", match[k] >= 0 ? match[k] + 1 : match[k] == PALP_FINDING_DUPLICATE ? -1 : 0);
    cJSON_AddItemToArray(marks, o);
  }
  return j;
}

static void build_answers(palp_web_hub *h, int slot) {
  cJSON *j = answers_json(h, &h->s[slot]);
  if (j) publish_json(h, &h->answers_msg[slot], j);
}

/* A finding's verdict (palp_finding_answers): an accepted mark stands until its withdrawal. */
typedef struct verdict_ctx {
  palp_web_hub *h;
  answers *a;
} verdict_ctx;

static void on_verdict(void *ctx, const palp_finding_sent *f, int verdict, const char *reason) {
  (void)reason;
  verdict_ctx *v = ctx;
  answers *a = v->a;
  a->dirty = 1;
  if (verdict == PALP_VERDICT_REFUSED) {
    a->refused++;
  } else if (verdict == PALP_VERDICT_UNANSWERED) {
    a->unanswered++;
    v->h->stats.findings_unanswered++;
  } else if (f->withdraw) {
    for (int k = a->n - 1; k >= 0; k--)
      if (a->id[k] == f->mark_id && !a->mark[k].withdrawn) {
        a->mark[k].withdrawn = 1;
        break;
      }
  } else if (a->n < ANSWER_MARKS) { /* the server refuses mark 65 on: never reached */
    a->id[a->n] = f->mark_id;
    a->mark[a->n++] = (palp_finding){.t = f->t, .point = f->point, .withdrawn = 0};
  }
}

static void on_finding(palp_web_hub *h, const palp_Finding *m) {
  int slot;
  session *s = find_session(h, m->session_id, &slot);
  if (!s) {
    h->stats.no_session++;
    return;
  }
  answers *a = session_answers(h, s);
  if (!a) return;
  if (!isfinite(m->point.x) || !isfinite(m->point.y) || !isfinite(m->point.z) || !isfinite(m->time)) {
    h->stats.dropped++; /* the server refuses it too; its answer then finds no finding and expires */
    return;
  }
  palp_finding_sent f;
  palp_dds_finding_sent(m, &f);
  verdict_ctx v = {h, a};
  palp_finding_answers_finding(&a->pairs, &f, (double)palp_dds_now_ns() * 1e-9, on_verdict, &v);
}

static void attach_exercise(palp_web_hub *h, session *s, palp_exercise *ex) {
  answers *a = session_answers(h, s);
  if (!a) {
    free(ex);
    return;
  }
  free(a->ex);
  a->ex = ex;
  a->dirty = 1;
}

/* The session's exercise from the server, checked as an exercise file is: it comes from the
 * network. One whose name is not its JSON's is refused too. */
static void on_session_exercise(palp_web_hub *h, const palp_SessionExercise *m) {
  char err[256];
  palp_exercise *ex = malloc(sizeof *ex);
  const int rc = ex ? palp_exercise_parse(m->json, NULL, ex, err, sizeof err) : PALP_ENOMEM;
  if (rc == 0 && strcmp(ex->name, m->name) != 0) {
    snprintf(err, sizeof err, "it names exercise \"%.60s\", its JSON \"%.60s\"", m->name, ex->name);
    free(ex);
    ex = NULL;
  } else if (rc != 0) {
    if (rc == PALP_ENOMEM) snprintf(err, sizeof err, "out of memory");
    free(ex);
    ex = NULL;
  }
  if (!ex) {
    h->stats.dropped++;
    palp_log_warn(h->def.log, "session %u: its exercise from the server refused: %s", m->session_id,
                  PALP_PRINTABLE_LONG(err)); /* err quotes its names and its JSON: printable (2026-12-07) */
    return;
  }
  int slot;
  session *s = find_session(h, m->session_id, &slot);
  if (s) {
    attach_exercise(h, s, ex);
    return;
  }
  /* before its OPEN state: kept a while (the oldest given up) */
  pending_exercise *keep = &h->pending_ex[0];
  for (int k = 0; k < SESSION_EXERCISES_PENDING; k++) {
    pending_exercise *p = &h->pending_ex[k];
    if (!p->ex || p->sid == m->session_id) {
      keep = p;
      break;
    }
    if (p->at_ns < keep->at_ns) keep = p;
  }
  free(keep->ex);
  *keep = (pending_exercise){.sid = m->session_id, .ex = ex, .at_ns = palp_dds_now_ns()};
}

static void claim_session_exercise(palp_web_hub *h, session *s) {
  for (int k = 0; k < SESSION_EXERCISES_PENDING; k++) {
    pending_exercise *p = &h->pending_ex[k];
    if (p->ex && p->sid == s->id) {
      attach_exercise(h, s, p->ex);
      *p = (pending_exercise){0};
    }
  }
}

/* Each poll: findings whose answers did not come are given up, pending exercises of sessions that
 * never opened here dropped, and changed answers rebuilt. */
static void tend_answers(palp_web_hub *h, int64_t now) {
  for (int k = 0; k < SESSION_EXERCISES_PENDING; k++) {
    pending_exercise *p = &h->pending_ex[k];
    if (p->ex && now - p->at_ns > SESSION_EXERCISE_WAIT_NS) {
      free(p->ex);
      *p = (pending_exercise){0};
    }
  }
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++) {
    session *s = &h->s[i];
    if (!s->used || !s->ans) continue;
    verdict_ctx v = {h, s->ans};
    palp_finding_answers_settle(&s->ans->pairs, (double)now * 1e-9, PALP_FINDING_ANSWER_WAIT_S, 0, on_verdict, &v);
    if (s->ans->dirty) build_answers(h, i);
  }
}

typedef void (*sample_fn)(palp_web_hub *h, const void *sample);
/* An instance that turned not-alive; sample holds its key fields (an invalid sample's key is
 * filled in), since the instance itself may already be gone once its last sample is taken. */
typedef void (*lost_fn)(palp_web_hub *h, dds_instance_handle_t ih, const void *sample);
static int drain(palp_web_hub *h, dds_entity_t rd, sample_fn on, lost_fn lost, uint64_t *counter);
static dds_entity_t stream_reader(const palp_web_hub *h, dds_entity_t sub, dds_entity_t topic, palp_dds_topic_kind kind,
                                  int32_t depth);
static void on_finding_status(palp_web_hub *h, const palp_FindingStatus *m);

/* An exercise session that ended: what its marks found, kept for the dashboard's list of ended
 * sessions beside the server's debrief (docs/web.md, "The hidden lumps"). The debrief tells what
 * the exercise lets the trainee be told, nothing at all in an examination; the instructor is shown
 * the whole of it. Its last marks and their answers may still wait in the polled readers as the
 * CLOSED state wakes the thread: they are taken first, so that what is kept counts what the
 * server's debrief counted; a finding still without its answer then counts as unanswered. */
static void keep_ended_answers(palp_web_hub *h, int slot) {
  session *s = &h->s[slot];
  if (!s->ans || !s->ans->ex) return;
  drain(h, h->finding_r, (sample_fn)on_finding, NULL, &h->stats.findings_read);
  drain(h, h->fstatus_r, (sample_fn)on_finding_status, NULL, &h->stats.finding_statuses);
  verdict_ctx v = {h, s->ans};
  palp_finding_answers_settle(&s->ans->pairs, (double)palp_dds_now_ns() * 1e-9, PALP_FINDING_ANSWER_WAIT_S, 1,
                              on_verdict, &v);
  cJSON *j = answers_json(h, s);
  if (!j) return;
  cJSON_AddBoolToObject(j, "ended", 1);
  publish_json(h, &h->ended_answers[h->ended_answers_next], j); /* the oldest replaced */
  h->ended_answers_next = (h->ended_answers_next + 1) % DEBRIEFS; /* the DDS thread's alone */
}

/* The session's figures for its debrief (session_end); the trainee's name under h->mu. */
static void session_end_of(palp_web_hub *h, int slot, session_end *e) {
  const session *s = &h->s[slot];
  *e = (session_end){.sid = s->id, .phantom = s->st.phantom_id, .duration = s->st.duration, .server_pp = s->server_pp};
  if (s->cov) {
    e->cov_rule = s->exercise_bands ? 2 : 1;
    e->cov_touched = s->samples && s->touched;
    session_coverage(s, e->cov);
  }
  pthread_mutex_lock(&h->mu);
  memcpy(e->trainee, h->slot_trainee[slot], sizeof e->trainee);
  pthread_mutex_unlock(&h->mu);
}

/* An entity the DDS thread is done with, deleted by the reaper (or here when its queue is full). */
static void delete_later(palp_web_hub *h, dds_entity_t e) {
  if (e <= 0) return;
  if (!h->reaper || palp_dds_reaper_put(h->reaper, e) != 0) dds_delete(e);
}

static void free_session(palp_web_hub *h, int slot) {
  session *s = &h->s[slot];
  keep_ended_answers(h, slot);
  session_end end;
  session_end_of(h, slot, &end);
  const int64_t t0 = palp_dds_now_ns();
  leave(h, s);
  /* The request writer has just written the LEAVE and the dispose, whose acknowledgement its delete would
   * wait for: 0.1-0.2 s (the server's answer to its next heartbeat), 1 s against a stalled server, the
   * DDS thread sending no frames meanwhile, per session of a class closing at once (until 2026-12-07). */
  delete_later(h, s->req_w);
  pthread_mutex_lock(&h->mu);
  const dds_entity_t fpub = h->fs[slot].pub;
  memset(&h->fs[slot], 0, sizeof h->fs[slot]);
  pthread_mutex_unlock(&h->mu);
  delete_later(h, fpub); /* the findings writer's, as slow with a mark just written */
  delete_later(h, s->fb_sub);
  const double took = (double)(palp_dds_now_ns() - t0) * 1e-9;
  if (took > h->stats.free_longest_s) h->stats.free_longest_s = took;
  palp_coverage_destroy(s->cov);
  palp_coverage_destroy(s->touched);
  if (s->ans) free(s->ans->ex);
  free(s->ans);
  memset(s, 0, sizeof *s);
  publish(h, &h->deform_msg[slot], NULL, 0);
  publish(h, &h->live_msg[slot], NULL, 0);
  publish(h, &h->answers_msg[slot], NULL, 0);
  publish(h, &h->cover_msg[slot], NULL, 0);
  pthread_mutex_lock(&h->mu);
  h->closed[h->closed_next] = end;
  h->closed_next = (h->closed_next + 1) % DEBRIEFS;
  h->slot_sid[slot] = 0;
  h->slot_trainee[slot][0] = '\0';
  pthread_mutex_unlock(&h->mu);
  palp_dds_gate_set(&h->gate, slot, 0);
  h->sessions_dirty = h->sessions_structure = 1;
}

/* [DDS thread] Whether a session's open or close may be logged: at most SESSION_LINES_MAX lines in any
 * window of SESSION_LINES_WINDOW_NS (a class of 32 opening and closing at once is logged whole); those
 * beyond are counted and said in one line as the next window opens. */
#define SESSION_LINES_MAX 100
#define SESSION_LINES_WINDOW_NS 10000000000LL
static int session_line_ok(palp_web_hub *h) {
  const int64_t now = palp_dds_now_ns();
  if (!h->lines_window_ns || now - h->lines_window_ns >= SESSION_LINES_WINDOW_NS) {
    if (h->lines_skipped)
      palp_log_warn(h->def.log, "%u session opens and closes not logged in the last %.0f s (more than %d: a flood of "
                    "session states, or a class far larger than this bridge's sessions)", h->lines_skipped,
                    (double)(now - h->lines_window_ns) * 1e-9, SESSION_LINES_MAX);
    h->lines_window_ns = now, h->lines_in_window = 0, h->lines_skipped = 0;
  }
  if (h->lines_in_window < SESSION_LINES_MAX) return ++h->lines_in_window, 1;
  h->lines_skipped++;
  return 0;
}

static void on_state(palp_web_hub *h, const palp_SessionState *m) {
  int slot;
  session *s = find_session(h, m->session_id, &slot);
  if (m->phase != palp_PHASE_OPEN) {
    if (!s) return;
    if (isfinite(m->duration) && m->duration >= 0) s->st.duration = m->duration; /* its last: kept for the debrief */
    /* One line as the bridge takes the CLOSED state, before it lets go of the session: an operator reads
     * when the bridge knew, beside the server's own "closed" line (web_dashboard times the two legs,
     * server -> bridge and bridge -> page, from these lines) */
    if (session_line_ok(h))
      palp_log_info(h->def.log, "session %u closed by its server (%s)", m->session_id, PALP_PRINTABLE_LONG(m->reason));
    free_session(h, slot);
    return;
  }
  if (!s) {
    for (int i = 0; i < PALP_WEB_MAX_SESSIONS && !s; i++)
      if (!h->s[i].used) s = &h->s[i], slot = i;
    if (!s) {
      h->stats.dropped++;
      return;
    }
    memset(s, 0, sizeof *s);
    s->used = 1;
    s->id = m->session_id;
    s->depth = NAN;
    if (h->def.sec.kind != PALP_DDS_ID_NONE) /* secured: the server takes only "KIND/NAME/..." from KIND/NAME;
                                              * 11 + 31 + 7 + 11 characters fit the 63 */
      snprintf(s->station, sizeof s->station, "%s/%s/%ld/w%u", palp_dds_id_kind_name(h->def.sec.kind),
               h->def.sec.name, (long)getpid(), m->session_id);
    else
      snprintf(s->station, sizeof s->station, "%.24s/%ld/web-s%u", h->host, (long)getpid(), m->session_id);
    s->fps_t0 = palp_dds_now_ns();
    /* its id and its trainee under one lock: between the two, a page's scope was checked against the
     * slot's previous trainee, and alice's page could bind to bob's new session until the next rescope
     * (<= 100 ms; until session 90, found by review) */
    pthread_mutex_lock(&h->mu);
    h->slot_sid[slot] = s->id;
    snprintf(h->slot_trainee[slot], sizeof h->slot_trainee[slot], "%.*s", (int)sizeof h->slot_trainee[slot] - 1,
             m->trainee_name);
    pthread_mutex_unlock(&h->mu);
    palp_dds_gate_set(&h->gate, slot, s->id);
    h->sessions_structure = 1;
    /* as it closes below: one line for each session the bridge takes on, and one as it lets it go */
    if (session_line_ok(h))
      palp_log_info(h->def.log, "session %u opened: trainee \"%s\" on phantom %u", m->session_id,
                    PALP_PRINTABLE(m->trainee_name), m->phantom_id);
  }
  s->st = *m; /* bounded strings: a plain copy */
  /* Its server is whoever writes its state: a restarted server's new run takes over (its states
   * come from its new participant), and so would a forger's states, which the session list shows */
  if (h->sample_participant) s->server_pp = h->sample_participant;
  pthread_mutex_lock(&h->mu);
  snprintf(h->slot_trainee[slot], sizeof h->slot_trainee[slot], "%.*s", (int)sizeof h->slot_trainee[slot] - 1,
           s->st.trainee_name);
  pthread_mutex_unlock(&h->mu);
  int ps;
  phantom *ph = find_phantom(h, m->phantom_id, 0, &ps);
  if (ph != s->ph && (s->cov || s->touched)) {
    /* Its phantom changed (a restarted server's new run on another phantom under the same id, or a
     * forged state): the coverage of the old mesh goes with it. It was kept, read with the new
     * mesh's triangles, and with the phantom unknown a finger sample read its radius through NULL
     * (session 80's review, 2026-12-07). */
    palp_coverage_destroy(s->cov);
    palp_coverage_destroy(s->touched);
    s->cov = s->touched = NULL;
    publish(h, &h->cover_msg[slot], NULL, 0);
  }
  s->ph = ph;
  attach_coverage(s);
  update_finding_writer(h, slot);
  claim_session_exercise(h, s);
  h->sessions_dirty = 1;
}

static void copy_str(char *out, size_t outlen, const char *in) { snprintf(out, outlen, "%s", in ? in : ""); }

/* [DDS thread] Whose session sid was, for a score written by participant pp (0: not known): the open
 * session's trainee, or a closed one's as the bridge saw it close, or as its server said it
 * (palp_session_closed, session 69, for a session this bridge did not see close); NULL if none is
 * known. A session id is its server run's alone: a restarted server numbers its sessions from 1, so a
 * name is taken only from the same server participant as the score's where both are known. Until
 * session 90 the first name kept under the id was taken: a restarted run's session 5, which the bridge
 * did not see open, had its score named, and told to the page still bound to the old run's session 5,
 * as that one's trainee's (found by review). */
static int same_server(dds_instance_handle_t a, dds_instance_handle_t b) { return !a || !b || a == b; }
static const char *trainee_of_session(palp_web_hub *h, uint32_t sid, dds_instance_handle_t pp) {
  int slot;
  const session *s = find_session(h, sid, &slot);
  if (s && same_server(s->server_pp, pp)) return s->st.trainee_name;
  for (int k = 0; k < DEBRIEFS; k++)
    if (h->closed[k].sid == sid && same_server(h->closed[k].server_pp, pp)) return h->closed[k].trainee;
  for (int k = 0; k < CLOSED_NAMES; k++)
    if (h->closed_names[k].sid == sid && same_server(h->closed_names[k].server_pp, pp)) return h->closed_names[k].trainee;
  return NULL;
}

/* A closed exercise session's score as the pages get it ("score", docs/web.md): malloc'd JSON, or
 * NULL when m does not make sense (refused and counted) or memory ran out (counted). */
static char *score_json(palp_web_hub *h, const palp_SessionScore *m) {
  if (!palp_dds_session_score_ok(m)) {
    h->stats.dropped++;
    return NULL;
  }
  char text[128];
  cJSON *j = cJSON_CreateObject();
  cJSON_AddStringToObject(j, "type", "score");
  cJSON_AddNumberToObject(j, "session", m->session_id);
  const char *trainee = trainee_of_session(h, m->session_id, h->sample_participant);
  if (trainee) cJSON_AddStringToObject(j, "trainee", trainee);
  else cJSON_AddNullToObject(j, "trainee");
  copy_str(text, sizeof text, m->exercise_name);
  cJSON_AddStringToObject(j, "exercise", text);
  copy_str(text, sizeof text, m->log_uid);
  cJSON_AddStringToObject(j, "log_uid", text);
  const int graded = m->status == palp_SCORE_GRADED;
  cJSON_AddBoolToObject(j, "graded", graded);
  if (!graded) {
    copy_str(text, sizeof text, m->reason);
    cJSON_AddStringToObject(j, "reason", text);
  } else {
    /* as her station says it (palp_cli_score_text): not passed, floored to 0.1 so it never reads as a
     * pass mark it missed; failed on the score alone, that named what to work on (session 81 review) */
    int only_score = !m->pass;
    for (int i = 0; i < PALP_METRIC_COUNT && i < 6; i++) only_score = only_score && m->passed[i];
    cJSON_AddNumberToObject(j, "score", palp_shown_tenths(m->score, NAN, m->pass));
    cJSON_AddBoolToObject(j, "pass", m->pass);
    cJSON *cr = cJSON_AddObjectToObject(j, "credit"), *ps = cJSON_AddObjectToObject(j, "passed");
    cJSON *work = cJSON_AddArrayToObject(j, "work_on"); /* her words for what she did not pass (session 64) */
    for (int i = 0; i < PALP_METRIC_COUNT && i < 6; i++) {
      cJSON_AddNumberToObject(cr, palp_metric_name(i), round(m->credit[i] * 1000) / 1000);
      cJSON_AddBoolToObject(ps, palp_metric_name(i), m->passed[i]);
      if (!m->passed[i]) cJSON_AddItemToArray(work, cJSON_CreateString(palp_metric_to_work_on(i)));
    }
    if (only_score) cJSON_AddItemToArray(work, cJSON_CreateString(PALP_SCORE_TO_WORK_ON));
    cJSON_AddNumberToObject(j, "lesions", m->lesions);
    cJSON_AddNumberToObject(j, "found", m->found);
    cJSON_AddNumberToObject(j, "false_marks", m->false_marks);
    const double cov[3] = {m->coverage[0] * 100, m->coverage[1] * 100, m->coverage[2] * 100};
    cJSON *c = cJSON_AddArrayToObject(j, "coverage"); /* [%], 0.1 */
    for (int b = 0; b < 3; b++) cJSON_AddItemToArray(c, cJSON_CreateNumber(round(cov[b] * 10) / 10));
    cJSON_AddStringToObject(j, "pattern", m->pattern);
    cJSON_AddNumberToObject(j, "duration", round(m->duration * 10) / 10);
    cJSON_AddNumberToObject(j, "peak_force", round(m->peak_force * 100) / 100);
    cJSON_AddNumberToObject(j, "out_of_range", m->out_of_range);
    cJSON_AddNumberToObject(j, "samples", m->samples);
    cJSON_AddBoolToObject(j, "log_complete", m->log_complete);
    copy_str(text, sizeof text, m->log_health);
    cJSON_AddStringToObject(j, "log_health", text);
  }
  char *out = cJSON_PrintUnformatted(j);
  cJSON_Delete(j);
  if (!out) h->stats.dropped++;
  return out;
}

/* Keeps msg in ring[*next] (the oldest replaced; sid beside it when sids is not NULL, and its trainee
 * when names is not NULL) and wakes the web thread. */
static void keep_score(palp_web_hub *h, char *msg, item *ring, uint32_t *sids, char (*names)[64], int *next,
                       uint32_t sid, const char *trainee) {
  if (!msg) return;
  pthread_mutex_lock(&h->mu);
  const int k = *next;
  *next = (*next + 1) % DEBRIEFS;
  unsigned char *old = ring[k].buf;
  ring[k] = (item){.buf = (unsigned char *)msg, .len = strlen(msg), .ver = ++h->next_ver};
  if (sids) sids[k] = sid;
  if (names) copy_str(names[k], sizeof names[k], trainee);
  pthread_mutex_unlock(&h->mu);
  free(old);
  if (h->wake) h->wake(h->wake_ctx);
}

/* A closed exercise session's score, as the server graded it from its own log (palp_session_score,
 * session 63): kept beside the ended answers for the dashboard's list of ended sessions, where the
 * instructor reads it with the session's id in the log (palp-review show takes it). */
static void on_score(palp_web_hub *h, const palp_SessionScore *m) {
  keep_score(h, score_json(h, m), h->scores, h->scores_sid, NULL, &h->scores_next, m->session_id, NULL);
}

/* Who a closed session was (palp_session_closed, session 69): kept for the scores to come, and given
 * to a kept score that came first without a name (a bridge begun after the close reads both topics'
 * histories in no set order): that score's message is sent again, named. */
static void on_session_closed(palp_web_hub *h, const palp_SessionClosed *m) {
  if (!m->session_id) {
    h->stats.dropped++;
    return;
  }
  int k = -1;
  for (int i = 0; i < CLOSED_NAMES && k < 0; i++)
    if (h->closed_names[i].sid == m->session_id) k = i;
  if (k < 0) {
    k = h->closed_names_next;
    h->closed_names_next = (h->closed_names_next + 1) % CLOSED_NAMES;
  }
  h->closed_names[k].sid = m->session_id;
  h->closed_names[k].server_pp = h->sample_participant;
  copy_str(h->closed_names[k].trainee, sizeof h->closed_names[k].trainee, m->trainee_name);
  for (int i = 0; i < DEBRIEFS; i++) {
    if (h->scores_sid[i] != m->session_id || !h->scores[i].buf) continue;
    pthread_mutex_lock(&h->mu);
    cJSON *j = cJSON_ParseWithLength((const char *)h->scores[i].buf, h->scores[i].len);
    pthread_mutex_unlock(&h->mu);
    cJSON *t = j ? cJSON_GetObjectItemCaseSensitive(j, "trainee") : NULL;
    char *named = NULL;
    if (t && cJSON_IsNull(t)) {
      cJSON_ReplaceItemInObjectCaseSensitive(j, "trainee", cJSON_CreateString(h->closed_names[k].trainee));
      named = cJSON_PrintUnformatted(j);
    }
    cJSON_Delete(j);
    if (!named) continue;
    pthread_mutex_lock(&h->mu); /* in place, a new version: a page replaces the row it has */
    unsigned char *old = h->scores[i].buf;
    h->scores[i] = (item){.buf = (unsigned char *)named, .len = strlen(named), .ver = ++h->next_ver};
    pthread_mutex_unlock(&h->mu);
    free(old);
    if (h->wake) h->wake(h->wake_ctx);
  }
}

/* The same score as the server told it to the trainee (palp_debrief_score, session 64), which it does
 * only for a practice session, after a debrief that told her the lesions: for her bound page. The
 * server decides who is told, in either security mode; the bridge relays it to her session's page. */
static void on_debrief_score(palp_web_hub *h, const palp_SessionScore *m) {
  keep_score(h, score_json(h, m), h->told_scores, h->told_scores_sid, h->told_scores_trainee, &h->told_scores_next,
             m->session_id, trainee_of_session(h, m->session_id, h->sample_participant));
}

static void on_exercise(palp_web_hub *h, const palp_Exercise *m) {
  exercise *e = NULL;
  for (int k = 0; k < MAX_EXERCISES && !e; k++)
    if (h->ex[k].used && h->ex[k].phantom_id == m->phantom_id) e = &h->ex[k];
  for (int k = 0; k < MAX_EXERCISES && !e; k++)
    if (!h->ex[k].used) e = &h->ex[k];
  /* The strings are bounded by the type; the numbers must make sense to be shown. */
  if (!e || !isfinite(m->time_limit) || !isfinite(m->max_force)) {
    h->stats.dropped++;
    return;
  }
  e->used = 1;
  e->phantom_id = m->phantom_id;
  copy_str(e->name, sizeof e->name, m->name);
  copy_str(e->title, sizeof e->title, m->title);
  copy_str(e->instructions, sizeof e->instructions, m->instructions);
  e->time_limit = m->time_limit;
  e->max_force = m->max_force;
  /* The bands as sent, checked: a band with no bound, a bound not finite, negative or not
   * ordered, and the bridge keeps its force bands for this exercise (and says which). */
  e->bands_ok = palp_dds_exercise_bands(m, e->band);
  build_exercises(h);
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
    if (h->s[i].used && h->s[i].st.phantom_id == m->phantom_id) update_finding_writer(h, i);
  h->sessions_dirty = 1;
}

/* A session's debrief (docs/assessment.md, "Debrief"), checked as the station checks it
 * (palp_dds_debrief_ok), as a page
 * message: {"type": "debrief", "session", "trainee", "exercise", "level", "lesions", "found", "marks",
 * "false_marks", "duplicates", "reason", "lumps": [{"found_by", "clock_h", "at_pole", "arc_mm", "across_mm",
 * "deep_mm", "point_mm"}]}, the places named as every tool names them (palp_place_*). */
static void on_debrief(palp_web_hub *h, const palp_Debrief *m) {
  if (!palp_dds_debrief_ok(m)) {
    h->stats.dropped++;
    return;
  }
  const uint32_t n = m->lesion._length;
  session_end e;
  int slot, known = 0;
  if (find_session(h, m->session_id, &slot)) session_end_of(h, slot, &e), known = 1;
  /* a closed one's from the same server participant (trainee_of_session): a restarted run's debrief of
   * its own session under the id went to the page of the old run's trainee as hers until session 90 */
  for (int k = 0; k < DEBRIEFS && !known; k++)
    if (h->closed[k].sid == m->session_id && same_server(h->closed[k].server_pp, h->sample_participant))
      e = h->closed[k], known = 1;
  if (!known) {
    h->stats.no_session++;
    return;
  }
  static const char *const level[] = {"none", "count", "lesions"};
  cJSON *j = cJSON_CreateObject();
  cJSON_AddStringToObject(j, "type", "debrief");
  cJSON_AddNumberToObject(j, "session", m->session_id);
  cJSON_AddStringToObject(j, "trainee", e.trainee);
  /* the exercise's name, so that a page that did not see the session open still names it */
  const exercise *ex = find_exercise(h, e.phantom);
  if (ex) cJSON_AddStringToObject(j, "exercise", ex->name);
  else cJSON_AddNullToObject(j, "exercise");
  cJSON_AddStringToObject(j, "level", level[m->level]);
  cJSON_AddNumberToObject(j, "lesions", m->lesions);
  cJSON_AddNumberToObject(j, "found", m->found);
  cJSON_AddNumberToObject(j, "marks", m->marks);
  cJSON_AddNumberToObject(j, "false_marks", m->false_marks);
  cJSON_AddNumberToObject(j, "duplicates", m->duplicates);
  char reason[128];
  copy_str(reason, sizeof reason, m->reason);
  cJSON_AddStringToObject(j, "reason", reason);
  /* how long it ran [s], the server's session state's figure (its last; null if not a number) */
  if (isfinite(e.duration) && e.duration >= 0) cJSON_AddNumberToObject(j, "duration", round(e.duration * 10) / 10);
  else cJSON_AddNullToObject(j, "duration");
  /* The bridge's own figure, not the server's: the skin it saw pressed since it began following the
   * session (docs/web.md, "Measured against the grade"), as the station's last line says it */
  if (e.cov_rule) {
    cJSON_AddItemToObject(j, "coverage", vec_json(e.cov, 3, 1));
    cJSON_AddStringToObject(j, "band_rule", e.cov_rule == 2 ? "exercise" : "force");
    cJSON_AddStringToObject(j, "coverage_rule", e.cov_touched ? "touched" : "approximated");
  } else {
    cJSON_AddNullToObject(j, "coverage");
  }
  cJSON *arr = cJSON_AddArrayToObject(j, "lumps");
  for (uint32_t i = 0; i < n; i++) {
    const palp_DebriefLesion *l = &m->lesion._buffer[i];
    const palp_vec3 p = {l->point.x, l->point.y, l->point.z};
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "found_by", l->found_by);
    cJSON_AddNumberToObject(o, "clock_h", palp_place_clock_shown(p)); /* as the page prints it: 12, never 0 */
    cJSON_AddBoolToObject(o, "at_pole", palp_place_at_pole(p)); /* no clock worth reading there */
    /* whole mm as the station and palp-review print them (palp_place_mm_shown; 0.1 mm before session 82) */
    cJSON_AddNumberToObject(o, "arc_mm", palp_place_mm_shown(palp_place_arc(p)));
    cJSON_AddNumberToObject(o, "across_mm", palp_place_mm_shown(l->diameter));
    cJSON_AddNumberToObject(o, "deep_mm", palp_place_mm_shown(l->depth));
    const double pt[3] = {round(p.x * 1e4) / 10, round(p.y * 1e4) / 10, round(p.z * 1e4) / 10};
    cJSON_AddItemToObject(o, "point_mm", cJSON_CreateDoubleArray(pt, 3));
    cJSON_AddItemToArray(arr, o);
  }
  char *text = cJSON_PrintUnformatted(j);
  cJSON_Delete(j);
  if (!text) {
    h->stats.dropped++;
    return;
  }
  pthread_mutex_lock(&h->mu);
  debrief_item *d = &h->debrief[h->debrief_next];
  h->debrief_next = (h->debrief_next + 1) % DEBRIEFS;
  free(d->msg.buf);
  d->msg.buf = (unsigned char *)text;
  d->msg.len = strlen(text);
  d->msg.ver = ++h->next_ver;
  d->sid = m->session_id;
  memcpy(d->trainee, e.trainee, sizeof d->trainee);
  pthread_mutex_unlock(&h->mu);
  if (h->wake) h->wake(h->wake_ctx);
}

/* An exercise withdrawn (disposed) or its server gone: no longer offered. */
static void on_exercise_lost(palp_web_hub *h, dds_instance_handle_t ih, const void *sample) {
  (void)ih;
  const palp_Exercise key = *(const palp_Exercise *)sample;
  for (int k = 0; k < MAX_EXERCISES; k++)
    if (h->ex[k].used && h->ex[k].phantom_id == key.phantom_id) h->ex[k].used = 0;
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
    if (h->s[i].used && h->s[i].st.phantom_id == key.phantom_id) {
      pthread_mutex_lock(&h->mu);
      h->fs[i].exercise = 0;
      pthread_mutex_unlock(&h->mu);
    }
  build_exercises(h);
  h->sessions_dirty = 1;
}

static void on_finding_status(palp_web_hub *h, const palp_FindingStatus *m) {
  int slot;
  session *s = find_session(h, m->session_id, &slot);
  if (!s || !isfinite(m->time_left)) {
    if (s) h->stats.dropped++;
    else h->stats.no_session++;
    return;
  }
  s->fst.valid = 1;
  s->fst.marks = m->marks;
  s->fst.last_mark_id = m->last_mark_id;
  s->fst.last_accepted = m->last_accepted != 0;
  copy_str(s->fst.reason, sizeof s->fst.reason, m->reason);
  s->fst.time_left = m->time_left;
  s->fst.at_ns = palp_dds_now_ns();
  answers *a = session_answers(h, s);
  if (a) {
    verdict_ctx v = {h, a};
    palp_finding_answers_answer(&a->pairs, m->last_mark_id, m->last_accepted, m->reason, m->marks,
                                h->sample_source < h->readers_since, (double)palp_dds_now_ns() * 1e-9, on_verdict, &v);
  }
  /* A mark the server refused does not stand: "withdraw last" must not name it. */
  pthread_mutex_lock(&h->mu);
  finding_slot *fs = &h->fs[slot];
  if (!m->last_accepted && fs->nstack > 0 && fs->stack[fs->nstack - 1] == m->last_mark_id) fs->nstack--;
  /* A mark id the server answered, of any writer (the trainee's own station numbers hers from 1 too):
   * this bridge's next mark takes a higher one (until 2026-12-07 a page's first mark after her
   * station's mark 1 was mark 1 again, refused "already made"). The answers, not the findings read: a
   * writer the server refuses unanswered moves nothing. */
  if (m->last_mark_id < PALP_DDS_MARK_ID_FOLLOW_MAX && m->last_mark_id > fs->next_mark) fs->next_mark = m->last_mark_id;
  pthread_mutex_unlock(&h->mu);
  s->changed = 1;
  h->sessions_dirty = 1;
}

/* A state instance that turned not-alive: its server is gone, the session with it. */
static void on_state_lost(palp_web_hub *h, dds_instance_handle_t ih, const void *sample) {
  (void)ih;
  const uint32_t sid = ((const palp_SessionState *)sample)->session_id; /* the invalid sample's key */
  int slot;
  if (find_session(h, sid, &slot)) {
    if (session_line_ok(h))
      palp_log_info(h->def.log,
                    "session %u closed: its server's state is gone (its server stopped, was lost or let it go)", sid);
    set_joined(h, &h->s[slot], 0); /* its server cannot hear a goodbye; the instance is disposed below */
    dispose_request(&h->s[slot]);
    free_session(h, slot);
  }
}

/* A session's own losses (palp_session_log, session 69): kept, and told to its view at once where
 * the session is known (else at its server's next status, on_status). */
static void on_session_log(palp_web_hub *h, const palp_SessionLog *m) {
  int k = -1;
  for (int i = 0; i < 2 * PALP_WEB_MAX_SESSIONS && k < 0; i++)
    if (h->slog[i].sid == m->session_id) k = i;
  if (k < 0) { /* the oldest replaced: more than twice the sessions the bridge can follow */
    k = h->slog_next;
    h->slog_next = (h->slog_next + 1) % (2 * PALP_WEB_MAX_SESSIONS);
  }
  h->slog[k].sid = m->session_id;
  h->slog[k].shed = m->shed;
  h->slog[k].failed = m->failed;
  int slot;
  session *s = find_session(h, m->session_id, &slot);
  if (!s) return;
  const palp_dds_log_view was = s->log;
  palp_dds_log_view_session(&s->log, m->shed, m->failed, palp_dds_now_ns());
  if (s->log.losing != was.losing || s->log.shed + s->log.failed != was.shed + was.failed || s->log.own != was.own)
    h->sessions_dirty = 1;
}

static void on_status(palp_web_hub *h, const palp_ServerStatus *m) {
  server_status *ss = NULL;
  for (int i = 0; i < MAX_SERVERS && !ss; i++)
    if (h->srv[i].used && !strcmp(h->srv[i].s.server_id, m->server_id)) ss = &h->srv[i];
  for (int i = 0; i < MAX_SERVERS && !ss; i++)
    if (!h->srv[i].used) ss = &h->srv[i];
  if (!ss) { /* a fifth server: replace the stalest */
    ss = &h->srv[0];
    for (int i = 1; i < MAX_SERVERS; i++)
      if (h->srv[i].at_ns < ss->at_ns) ss = &h->srv[i];
  }
  uint32_t n = m->sessions._length > 4096 ? 4096 : m->sessions._length;
  palp_SessionLoad *loads = ss->loads;
  if (n > ss->nsessions || !loads) {
    loads = realloc(ss->loads, sizeof *loads * (n ? n : 1));
    if (!loads) {
      h->stats.dropped++;
      return;
    }
  }
  ss->loads = loads;
  ss->used = 1;
  ss->s = *m;
  ss->s.sessions._buffer = NULL;
  ss->s.sessions._length = ss->s.sessions._maximum = 0;
  ss->nsessions = n;
  if (n) memcpy(ss->loads, m->sessions._buffer, sizeof *loads * n); /* an empty sequence's buffer is NULL */
  ss->at_ns = palp_dds_now_ns();
  /* Each session this server lists: its log's losses since the bridge first saw it there. */
  for (uint32_t k = 0; k < n; k++) {
    int slot;
    session *s = find_session(h, ss->loads[k].session_id, &slot);
    if (!s) continue;
    const palp_dds_log_view was = s->log; /* its words change with these three alone */
    palp_dds_log_view_status(&s->log, m->log_written, m->log_shed, m->log_failed, ss->at_ns);
    for (int i = 0; i < 2 * PALP_WEB_MAX_SESSIONS && !s->log.own; i++) /* its own counts, read before it was known */
      if (h->slog[i].sid == s->id) palp_dds_log_view_session(&s->log, h->slog[i].shed, h->slog[i].failed, ss->at_ns);
    if (s->log.losing != was.losing || s->log.shed + s->log.failed != was.shed + was.failed || s->log.own != was.own)
      h->sessions_dirty = 1;
  }
  /* a refused peer that stopped retrying: its repeats logged within a window of the last line */
  if (h->def.refusals) palp_dds_refusals_tick(h->def.refusals, palp_dds_now_ns());
  if (h->strangers_ready) palp_dds_strangers_tick(&h->strangers, h->def.refusals, palp_dds_now_ns());
  build_status(h);
}

/* A position-driven finger's indentation [m] as the assessment measures it: the undeformed
 * dome's radius plus the fingertip's, less the proxy's distance from the dome's centre. */
static double finger_depth(const session *s, const finger *f) {
  return s->ph ? palp_fingertip_depth(s->ph->radius, f->radius, (palp_vec3){f->proxy[0], f->proxy[1], f->proxy[2]})
               : NAN;
}

/* The exercise whose bands band this session's fingers, or NULL (force bands). */
static const exercise *banding_exercise(const palp_web_hub *h, const session *s) {
  const exercise *ex = find_exercise(h, s->st.phantom_id);
  return ex && ex->bands_ok && s->ph ? ex : NULL;
}

/* The band of an in-contact position-driven finger with a local model, of force `force` [N]:
 * the exercise's `ex`, as palp_assess grades a sample (palp_band_of); without one the gauge's
 * force bands. */
/* The band of a fingertip `depth` [m] below the skin pushed back with `force` [N]: the exercise's, or
 * the gauge's force bands without one. */
static int band_at(const palp_web_hub *h, const exercise *ex, double depth, double force) {
  if (!ex) return palp_web_band(&h->def.bands, force);
  const int b = palp_band_of(ex->band, depth, force);
  return b < 0 ? PALP_WEB_BAND_NONE : b + 1; /* PALP_BAND_LIGHT = 0 is PALP_WEB_BAND_LIGHT = 1 */
}

static int finger_band(const palp_web_hub *h, const exercise *ex, const session *s, const finger *f, double force) {
  return band_at(h, ex, ex ? finger_depth(s, f) : NAN, force);
}

static void recompute_force(palp_web_hub *h, session *s) {
  double sum[3] = {0, 0, 0};
  for (int k = 0; k < FINGERS; k++) {
    const finger *f = &s->f[k];
    if (f->mode == palp_CONTACT_FORCE)
      for (int d = 0; d < 3; d++) sum[d] += f->force[d];
    else if (f->mode == palp_CONTACT_FINGER && f->fb_active)
      for (int d = 0; d < 3; d++) sum[d] += f->fb[d];
  }
  const double mag = sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
  int band = palp_web_band(&h->def.bands, mag);
  /* In an exercise the band is the exercise's, as the assessment will grade it: of the deepest
   * position-driven finger in contact (none while every such finger is in the air). */
  const exercise *ex = banding_exercise(h, s);
  const int xb = ex != NULL;
  double depth = NAN;
  if (xb) {
    band = PALP_WEB_BAND_NONE;
    for (int k = 0; k < FINGERS; k++) {
      const finger *f = &s->f[k];
      if (f->mode != palp_CONTACT_FINGER || !f->lm_valid || !f->lm_contact) continue;
      const double d = finger_depth(s, f);
      if (isnan(depth) || d > depth) depth = d;
      const int b = finger_band(h, ex, s, f, f->lm_force);
      if (b > band) band = b;
    }
  }
  if (mag != s->force || band != s->band || xb != s->exercise_bands) s->changed = 1, h->sessions_dirty = 1;
  if (!(depth == s->depth || (isnan(depth) && isnan(s->depth)))) s->changed = 1; /* live only */
  s->force = mag;
  s->band = band;
  s->exercise_bands = xb;
  s->depth = depth;
}

static void on_contact(palp_web_hub *h, const palp_Contact *m) {
  int slot;
  session *s = find_session(h, m->session_id, &slot);
  if (!s || m->finger >= FINGERS) {
    if (s) h->stats.dropped++;
    else h->stats.no_session++;
    return;
  }
  finger *f = &s->f[m->finger];
  /* finite, and of a size a phantom can have (the server refuses the same: a contact 10 m off or of
   * 10 kN is no palpation; 1e308 m printed 316 characters into the live message, session 75) */
  const int finite = vec_within(&m->center, LIVE_MAX_REACH_M) && vec_within(&m->force, LIVE_MAX_FORCE_N) &&
                     fabs(m->radius) <= LIVE_MAX_REACH_M && /* false for NaN and inf too */
                     fabs(m->patch_area) <= LIVE_MAX_REACH_M * LIVE_MAX_REACH_M;
  if (m->mode == palp_CONTACT_RELEASE || !finite ||
      (m->mode != palp_CONTACT_FORCE && m->mode != palp_CONTACT_FINGER)) {
    /* The server rejects what is not finite or of no known mode; so does the view. */
    if (!finite || m->mode != palp_CONTACT_RELEASE) h->stats.dropped++;
    f->mode = palp_CONTACT_RELEASE;
  } else {
    f->mode = (int)m->mode;
    f->center[0] = m->center.x, f->center[1] = m->center.y, f->center[2] = m->center.z;
    f->force[0] = m->force.x, f->force[1] = m->force.y, f->force[2] = m->force.z;
    if (m->mode == palp_CONTACT_FORCE) {
      const double area = m->patch_area > 0 ? m->patch_area : DEFAULT_PATCH_AREA;
      f->radius = sqrt(area / 3.14159265358979323846);
    } else {
      f->radius = m->radius > 0 ? m->radius : 0;
    }
  }
  if (f->mode != palp_CONTACT_FINGER) {
    f->lm_valid = 0;
    pthread_mutex_lock(&h->mu);
    if (h->fs[slot].contact_finger == m->finger) h->fs[slot].contact = 0;
    pthread_mutex_unlock(&h->mu);
  }
  if (f->mode == palp_CONTACT_FINGER && h->def.read_feedback && s->fb_sub <= 0 && s->st.partition[0]) {
    s->fb_sub = palp_dds_session_subscriber(h->pp, s->st.partition);
    s->fb_r = s->fb_sub > 0 ? stream_reader(h, s->fb_sub, h->topic[PALP_TOPIC_FEEDBACK], PALP_TOPIC_FEEDBACK, 1) : -1;
    memset(&s->fb_strays, 0, sizeof s->fb_strays);
    if (s->fb_r < 0) h->stats.dropped++;
  }
  s->changed = 1;
  recompute_force(h, s);
}

static void on_contact_lost(palp_web_hub *h, dds_instance_handle_t ih, const void *sample) {
  (void)sample;
  palp_Contact key;
  memset(&key, 0, sizeof key);
  int slot;
  if (dds_instance_get_key(h->contact_r, ih, &key) != 0 || key.finger >= FINGERS) return;
  session *s = find_session(h, key.session_id, &slot);
  if (!s) return;
  s->f[key.finger].mode = palp_CONTACT_RELEASE;
  s->changed = 1;
  recompute_force(h, s);
}

static void on_feedback(palp_web_hub *h, const palp_Feedback *m) {
  int slot;
  session *s = find_session(h, m->session_id, &slot);
  if (!s) {
    h->stats.no_session++;
    return;
  }
  for (uint32_t i = 0; i < m->fingers._length && i < FINGERS; i++) {
    const palp_FingerFeedback *ff = &m->fingers._buffer[i];
    if (ff->finger >= FINGERS || !vec_within(&ff->force, LIVE_MAX_FORCE_N)) continue;
    finger *f = &s->f[ff->finger];
    f->fb[0] = ff->force.x, f->fb[1] = ff->force.y, f->fb[2] = ff->force.z;
    f->fb_active = ff->active;
  }
  if (isfinite(m->sim_time) && m->sim_time > s->sim_time && !s->have_deform) s->sim_time = m->sim_time, s->frame = m->frame;
  recompute_force(h, s);
}


/* The server's local model of one finger (published while the trainee's station asks for
 * feedback): newest per finger kept, an older frame (reordered or replayed) ignored. */
static void on_local_model(palp_web_hub *h, const palp_LocalModel *m) {
  int slot;
  session *s = find_session(h, m->session_id, &slot);
  if (!s || m->finger >= FINGERS || !vec_within(&m->proxy, LIVE_MAX_REACH_M) ||
      !vec_within(&m->device, LIVE_MAX_REACH_M) || !vec_within(&m->force, LIVE_MAX_FORCE_N)) {
    if (s) h->stats.dropped++;
    else h->stats.no_session++;
    return;
  }
  finger *f = &s->f[m->finger];
  if (f->lm_valid && m->frame <= f->lm_frame) return;
  /* Late haptic updates, from what the bridge sees: the model of the frame after the previous
   * one, published (server clock, so no clock between hosts is compared) more than two of its
   * periods after it: the station's haptic loop had to extrapolate the old model that long.
   * Frames between the two that the bridge never received are counted apart (lost), not late:
   * the station may have had them. */
  if (f->lm_valid && isfinite(m->period) && m->period > 0) {
    const uint64_t gap = m->frame - f->lm_frame;
    if (gap == 1 && (double)(m->server_time_ns - f->lm_server_ns) > 2e9 * m->period) {
      s->late_haptic++;
      h->stats.late_haptic++;
      h->sessions_dirty = 1;
    } else if (gap > 1 && gap < 1000) {
      s->lost_haptic += gap - 1;
      h->stats.lost_haptic += gap - 1;
      h->sessions_dirty = 1;
    }
  }
  f->lm_server_ns = m->server_time_ns;
  f->lm_valid = 1;
  f->lm_frame = m->frame;
  f->lm_contact = m->in_contact != 0;
  f->proxy[0] = m->proxy.x, f->proxy[1] = m->proxy.y, f->proxy[2] = m->proxy.z;
  f->device[0] = m->device.x, f->device[1] = m->device.y, f->device[2] = m->device.z;
  f->lm_force = sqrt(m->force.x * m->force.x + m->force.y * m->force.y + m->force.z * m->force.z);
  const int point_ok = vec_finite(&m->point) && isfinite(m->area) && m->area >= 0 && isfinite(m->time);
  f->point[0] = m->point.x, f->point[1] = m->point.y, f->point[2] = m->point.z;
  f->area = point_ok ? m->area : 0;
  f->lm_triangles = point_ok && m->triangles > 0 ? (int)m->triangles : 0;
  /* The contact point a trainee page's "lump here" marks: the newest in-contact model of any
   * finger; a finger that lifts clears it if it set it. */
  pthread_mutex_lock(&h->mu);
  finding_slot *fs = &h->fs[slot];
  if (m->in_contact && point_ok) {
    fs->contact = 1;
    fs->contact_finger = m->finger;
    memcpy(fs->point, f->point, sizeof fs->point);
    fs->time = m->time;
    fs->at_ns = palp_dds_now_ns();
  } else if (fs->contact && fs->contact_finger == m->finger) {
    fs->contact = 0;
  }
  pthread_mutex_unlock(&h->mu);
  const uint32_t flags = (uint32_t)m->flags & (palp_LM_FORCE_LIMIT | PALP_DDS_LM_OUTSIDE);
  if (flags != f->lm_flags || (flags & ~s->lm_flags_seen)) h->sessions_dirty = 1;
  f->lm_flags = flags;
  s->lm_flags_seen |= flags;
  /* The time outside the valid range, as the station and the review count it (one physics period
   * per flagged frame; docs/db.md): frames the bridge never received are not counted. */
  if ((flags & PALP_DDS_LM_OUTSIDE) && isfinite(m->period) && m->period > 0 &&
      m->period < 1 && !(s->outside_counted && s->outside_frame == m->frame)) {
    s->outside_s += m->period;
    s->outside_frame = m->frame;
    s->outside_counted = 1;
    h->sessions_dirty = 1;
  }
  /* Coverage from the physics steps the assessment samples (palp_assess_sample_every on the model's
   * own period), marked as a station marks them (palp_coverage_press_contact): the models the review's
   * thoroughness is computed from. At the live rate (30 Hz), as until 2026-12-05, the page read up to
   * 0.9 points off the review, by which models a tick happened to see. */
  if (s->cov && f->lm_contact && isfinite(m->period) && m->period > 0 &&
      m->frame % (uint64_t)palp_assess_sample_every(1.0 / m->period, PALP_ASSESS_SAMPLE_HZ) == 0) {
    const int band = finger_band(h, banding_exercise(h, s), s, f, f->lm_force);
    if (band && palp_coverage_press_contact(s->cov, f->point, f->proxy, f->lm_triangles, f->area, f->radius, band - 1) > 0)
      s->cover_changed = 1;
  }
  if (banding_exercise(h, s)) recompute_force(h, s); /* the band follows the fingertip's depth */
  s->changed = 1;
}

/* A position-driven finger's sample on a step the session log samples (palp_finger_sample, session
 * 71), checked (its finger, finite numbers, a frame after the finger's last, triangle ids against the
 * mesh in palp_coverage_press_touched) and marked at the band its session counts by, from the sample's
 * own fingertip (the review's depth), on the triangles it names: the review's footprint. */
static void on_finger_sample(palp_web_hub *h, const palp_FingerSample *m) {
  int slot;
  session *s = find_session(h, m->session_id, &slot);
  if (!s) {
    h->stats.no_session++;
    return;
  }
  if (!palp_dds_finger_sample_ok(m, -1) || m->finger >= FINGERS || m->frame <= s->samples_frame[m->finger]) {
    h->stats.dropped++;
    return;
  }
  s->samples_frame[m->finger] = m->frame;
  if (!s->touched || !s->ph) return;
  if (++s->samples == 1) h->sessions_dirty = 1, s->cover_changed = 1; /* its coverage_rule is "touched" now */
  if (!m->in_contact) return;
  const double force = sqrt(m->force.x * m->force.x + m->force.y * m->force.y + m->force.z * m->force.z);
  const double depth = palp_fingertip_depth(s->ph->radius, m->radius, (palp_vec3){m->proxy.x, m->proxy.y, m->proxy.z});
  const int band = band_at(h, banding_exercise(h, s), depth, force);
  if (!band) return;
  int raised;
  if (m->triangles._length > 0) {
    raised = palp_coverage_press_touched(s->touched, m->triangles._buffer, (int)m->triangles._length, band - 1);
  } else { /* none named: the disc of the footprint's area, as the review */
    const double point[3] = {m->point.x, m->point.y, m->point.z}, proxy[3] = {m->proxy.x, m->proxy.y, m->proxy.z};
    raised = palp_coverage_press_contact(s->touched, point, proxy, 0, m->area, m->radius, band - 1);
  }
  if (raised > 0) s->cover_changed = s->changed = 1;
}

static void on_deformation(palp_web_hub *h, const palp_Deformation *m) {
  int slot;
  session *s = find_session(h, m->session_id, &slot);
  const uint32_t n = m->positions._length;
  /* a time the view can print (the live message's sim_time: JSON has no inf) */
  if (!s || !s->ph || (int)n != s->ph->n || !isfinite(m->sim_time)) {
    if (s) h->stats.dropped++;
    else h->stats.no_session++;
    return;
  }
  const size_t len = PALP_WEB_DEFORM_HEADER + (size_t)n * 3 * sizeof(float);
  unsigned char *buf = malloc(len);
  if (!buf) return;
  const uint32_t hdr[4] = {PALP_WEB_DEFORM_MAGIC, m->session_id, s->st.phantom_id, n};
  const double fr = (double)m->frame, t = m->sim_time;
  /* The pages read little-endian (DataView / Float32Array); x86-64 and arm64 are. */
  memcpy(buf, hdr, sizeof hdr);
  memcpy(buf + 16, &fr, 8);
  memcpy(buf + 24, &t, 8);
  float *d = (float *)(void *)(buf + PALP_WEB_DEFORM_HEADER);
  double max2 = 0;
  for (uint32_t i = 0; i < n; i++) {
    const palp_Vec3 *p = &m->positions._buffer[i];
    const double *r = s->ph->rest + 3 * i;
    double dx = p->x - r[0], dy = p->y - r[1], dz = p->z - r[2];
    /* drawn at rest, never NaN, nor beyond the visual station's 10 m bound (palp_cli_deformation_check),
     * whose float would be infinite and which the pages refuse (since session 82) */
    if (!(fabs(dx) <= 10.0) || !(fabs(dy) <= 10.0) || !(fabs(dz) <= 10.0)) dx = dy = dz = 0;
    d[3 * i] = (float)dx, d[3 * i + 1] = (float)dy, d[3 * i + 2] = (float)dz;
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 > max2) max2 = d2;
  }
  publish(h, &h->deform_msg[slot], buf, len);
  s->max_disp = sqrt(max2);
  s->sim_time = m->sim_time;
  s->frame = m->frame;
  s->have_deform = 1;
  s->fps_count++;
  s->changed = 1;
}

/* ---- the thread ------------------------------------------------------------------------------ */

/* Whether a contact or finding naming a session the bridge follows came from a writer in that
 * session's partition: a trainee may write only in her own partitions, so one naming another
 * trainee's session there forges it (idl/palp_dds_origin.h). A sample of a session the bridge does
 * not follow passes on, for its handler to count. A dispose is checked too (a forged one lifted
 * the finger on the dashboard until its next contact), but refused only when its writer is known
 * to write elsewhere: a station that leaves disposes its contacts and deletes its writer at once,
 * so its last dispose may name a writer no longer matched (PALP_DDS_ORIGIN_UNKNOWN). Cyclone fills
 * an invalid sample's key, the session id with it. */
static int is_fb_reader(const palp_web_hub *h, dds_entity_t rd) {
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
    if (h->s[i].used && h->s[i].fb_r == rd) return 1;
  return 0;
}

/* A sample of a session's server topic (reader rd) from the session's server: the participant of its
 * writer is that of the session's latest OPEN state. Until 2026-12-07 any participant in a session's
 * partition could put forces, a fingertip, marks' answers, a debrief or a score on the trainee's page
 * and the instructor's dashboard (the station takes them from its server alone since 2026-12-06). A
 * session the bridge has no state for, or a writer already gone (a closing session's last samples,
 * whose publisher the server deleted), passes: nothing to tell it by. Said once, with the session. */
static int from_its_server(palp_web_hub *h, dds_entity_t rd, const void *sample, const dds_sample_info_t *info) {
  int slot;
  const session *s = find_session(h, *(const uint32_t *)sample, &slot); /* the session id first (palp_dds_gate.c) */
  if (!s || !s->server_pp) return 1;
  const dds_instance_handle_t pp = palp_dds_origin_participant(&h->origin, rd, info);
  if (!pp || pp == s->server_pp) return 1;
  h->stats.not_server++;
  if (!h->not_server_said) {
    h->not_server_said = 1;
    palp_log_warn(h->def.log, "session %u: samples of its server's topics from another participant than its server "
                              "dropped (a peer writing into its partition: run the classroom with DDS Security); counted "
                              "in --stats, not said again", s->id);
  }
  return 0;
}

static int from_its_partition(palp_web_hub *h, dds_entity_t rd, const void *sample, const dds_sample_info_t *info) {
  int slot;
  const session *s = find_session(h, *(const uint32_t *)sample, &slot); /* the session id first (palp_dds_gate.c) */
  if (!s || !s->st.partition[0]) return 1;
  const palp_dds_origin_verdict v = palp_dds_origin_check(&h->origin, rd, info, s->st.partition);
  if (v == PALP_DDS_ORIGIN_SAME || (!info->valid_data && v == PALP_DDS_ORIGIN_UNKNOWN)) return 1;
  h->stats.foreign++;
  return 0;
}

/* A flood of disposes of made-up finding keys: the findings reader made anew when
 * idl/palp_dds_strays.h says so (as palp-server and palp-recorder do; docs/robustness.md).
 * The findings are volatile, so the new reader is handed none of the flood again; a finding in
 * flight in that instant is lost to the dashboard (its answer still comes). */
static dds_entity_t make_reader(dds_entity_t parent, dds_entity_t topic, palp_dds_topic_kind kind);
static void renew_findings(palp_web_hub *h, int64_t now) {
  if (h->finding_r <= 0 || !palp_dds_strays_renew_due(h->finding_strays, now, h->finding_renewed_ns)) return;
  /* Under mu: palp_web_hub_has_instance reads the handle from another thread and uses the reader
   * under mu, so it never sees the handle half-replaced nor a reader deleted under it (ThreadSanitizer
   * reported the handle read against this write). This thread alone writes it, so its own reads need
   * no lock. */
  pthread_mutex_lock(&h->mu);
  dds_delete(h->finding_r);
  h->finding_r = make_reader(h->sub, h->finding_topic_r, PALP_TOPIC_FINDING);
  pthread_mutex_unlock(&h->mu);
  h->finding_renewed_ns = now;
  h->finding_renewals++;
  h->finding_strays = 0;
  h->stats.finding_renewals = h->finding_renewals;
}

/* The stray count of stream reader rd and its topic; NULL for another reader. */
static stray_watch *strays_of(palp_web_hub *h, dds_entity_t rd, palp_dds_topic_kind *kind) {
  if (rd <= 0) return NULL;
  if (rd == h->contact_r) return *kind = PALP_TOPIC_CONTACT, &h->contact_strays;
  if (rd == h->deform_r) return *kind = PALP_TOPIC_DEFORMATION, &h->deform_strays;
  if (rd == h->lm_r) return *kind = PALP_TOPIC_LOCAL_MODEL, &h->lm_strays;
  if (rd == h->fsample_r) return *kind = PALP_TOPIC_FINGER_SAMPLE, &h->fsample_strays;
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
    if (h->s[i].used && h->s[i].fb_r == rd) return *kind = PALP_TOPIC_FEEDBACK, &h->s[i].fb_strays;
  return NULL;
}

/* A flood of disposes of made-up stream keys: the stream reader *rd (under sub, of `kind`, `depth`
 * deep) made anew when idl/palp_dds_strays.h says so (at once when full), its strays counted as
 * drain() takes them and the samples its bound refused added here. The streams are volatile, so the
 * new reader is handed none of the flood again, and a session's keys become instances again with its
 * next samples (10 ms to 16 ms at the rates servers and stations write). Made before the old goes,
 * so that a remote writer always has a reader of this participant matched; what the old one holds in
 * that instant, taken by drain() just before, is little. `shared`: the handle is read by other
 * threads (palp_web_hub_has_instance, under mu), so it is replaced under mu as renew_findings does;
 * the old reader is deleted after, when no other thread can have it. */
static void renew_stream(palp_web_hub *h, dds_entity_t *rd, stray_watch *sw, dds_entity_t sub, palp_dds_topic_kind kind,
                         int32_t depth, int shared, int64_t now) {
  if (*rd <= 0) return;
  const uint32_t refused = palp_dds_gate_refused_since(*rd, &sw->refused_seen);
  sw->strays += refused;
  h->stats.rejected += refused;
  if (!palp_dds_strays_renew_due(sw->strays, now, sw->renewed_ns) &&
      !palp_dds_strays_full_due(sw->strays, sw->refused_seen, palp_dds_gate_instances(&h->gate, kind)))
    return;
  sw->renewed_ns = now;
  const dds_entity_t fresh = stream_reader(h, sub, h->topic[kind], kind, depth);
  if (fresh <= 0) {
    /* tried again PALP_DDS_RENEW_NS later, not every pass however many come */
    if (sw->strays >= PALP_DDS_STRAYS_HARD) sw->strays = PALP_DDS_STRAYS_HARD - 1;
    h->stats.stream_renewals_failed++;
    return;
  }
  if (shared) pthread_mutex_lock(&h->mu);
  const dds_entity_t old = *rd;
  *rd = fresh;
  if (shared) pthread_mutex_unlock(&h->mu);
  dds_delete(old);
  sw->strays = 0;
  sw->refused_seen = 0;
  h->stats.stream_renewals++;
  if (!h->stream_renewal_said) { /* then counted in --stats (web/main.c) */
    h->stream_renewal_said = 1;
    palp_log_warn(h->def.log, "a flood of disposes of made-up stream keys (each kept by a reader while its writer "
                              "lives; unsecured, anyone may write them): the %s reader was made anew to drop them, "
                              "as each stream reader will be whenever %d more come (at most every %.2f s, unless %d "
                              "do); counted in --stats, not said again",
                  palp_dds_topic_name(kind), PALP_DDS_STRAYS_MIN, PALP_DDS_RENEW_NS * 1e-9, PALP_DDS_STRAYS_HARD);
  }
}

static void renew_streams(palp_web_hub *h, int64_t now) {
  renew_stream(h, &h->contact_r, &h->contact_strays, h->sub, PALP_TOPIC_CONTACT, 1, 1, now);
  renew_stream(h, &h->deform_r, &h->deform_strays, h->sub, PALP_TOPIC_DEFORMATION, 1, 1, now);
  renew_stream(h, &h->lm_r, &h->lm_strays, h->sub, PALP_TOPIC_LOCAL_MODEL, LM_DEPTH, 1, now);
  renew_stream(h, &h->fsample_r, &h->fsample_strays, h->sub, PALP_TOPIC_FINGER_SAMPLE, LM_DEPTH, 1, now);
  /* each session's feedback reader, this thread's alone */
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
    if (h->s[i].used && h->s[i].fb_r > 0)
      renew_stream(h, &h->s[i].fb_r, &h->s[i].fb_strays, h->s[i].fb_sub, PALP_TOPIC_FEEDBACK, 1, 0, now);
}

static int drain(palp_web_hub *h, dds_entity_t rd, sample_fn on, lost_fn lost, uint64_t *counter) {
  if (rd <= 0) return 0;
  int total = 0, n;
  void *ptr[TAKE] = {NULL};
  dds_sample_info_t info[TAKE];
  /* the topics a trainee may write (contacts, findings): checked for where they were written */
  const int check = rd == h->contact_r || rd == h->finding_r;
  /* a session's server topics: checked for who wrote them (its state's participant, on_state's) */
  const int server_topic = rd == h->lm_r || rd == h->fsample_r || rd == h->fstatus_r || rd == h->debrief_r ||
                           rd == h->debrief_score_r || rd == h->session_log_r || rd == h->deform_r || is_fb_reader(h, rd);
  palp_dds_topic_kind kind = PALP_TOPIC_CONTACT;
  stray_watch *sw = strays_of(h, rd, &kind);
  while ((n = dds_take(rd, ptr, info, TAKE, TAKE)) > 0) {
    for (int i = 0; i < n; i++) {
      /* a stream's dispose of a key its filter would not pass (a made-up session, or a finger past 3),
       * whoever wrote it: the instance is the reader's all the same (Cyclone fills an invalid sample's key) */
      if (sw && !info[i].valid_data && info[i].instance_state == DDS_IST_NOT_ALIVE_DISPOSED &&
          !palp_dds_gate_key_passes(&h->gate, kind, ptr[i]))
        sw->strays++, h->stats.stream_strays++;
      if (check && !from_its_partition(h, rd, ptr[i], &info[i])) continue; /* data and disposes alike */
      if (server_topic && info[i].valid_data && !from_its_server(h, rd, ptr[i], &info[i])) continue;
      /* the states' writer (on_state), and the closed sessions', scores' and debriefs' (trainee_of_session): rare
       * topics, one discovery lookup a sample */
      const int whose = rd == h->state_r || rd == h->closed_r || rd == h->score_r || rd == h->debrief_score_r ||
                        rd == h->debrief_r;
      h->sample_participant = whose && info[i].valid_data ? palp_dds_origin_participant(&h->origin, rd, &info[i]) : 0;
      /* a dispose of a key whose session the gate would not pass (never heard open, so not a station
       * that leaves a session that just closed); Cyclone fills an invalid sample's key */
      if (!info[i].valid_data && rd == h->finding_r && info[i].instance_state == DDS_IST_NOT_ALIVE_DISPOSED &&
          !palp_dds_gate_passes(&h->gate, *(const uint32_t *)ptr[i]))
        h->finding_strays++, h->stats.finding_strays++;
      if (info[i].valid_data) {
        h->sample_writer = info[i].publication_handle;
        h->sample_source = info[i].source_timestamp;
        on(h, ptr[i]);
        (*counter)++;
      } else if (lost && info[i].instance_state != DDS_IST_ALIVE) {
        lost(h, info[i].instance_handle, ptr[i]);
      }
    }
    dds_return_loan(rd, ptr, n);
    total += n;
    if (n < TAKE) break;
  }
  return total;
}

/* A session the bridge joined whose server counts no visual station: the server dropped the bridge (its
 * request writer's 0.5 s liveliness lapsed while palp-web did not run, a loaded machine) and streams the
 * session's deformation to nobody, while the bridge believed itself joined for good: the view stood still
 * until the session ended (web_disconnect in a fresh clone's run, 2026-12-07: joined, dropped 0.97 s later).
 * The JOIN is sent again, as a trainee station asks again after a stall; the server answers a station it
 * still holds again, harmlessly. Not in the first second after joining (the server's state may not count
 * the bridge yet), and at most once a second. A drop while another visual station is in the session leaves
 * the count above zero, and the bridge's own stall is what tells it then (2026-12-08): after a turn of its
 * DDS thread STALL_NS late the JOIN goes again at once and a second later, whatever the count (the
 * deformation still came, for the other station, but the server refused the trainee page's marks from a
 * bridge no longer its member). */
static void rejoin_if_dropped(palp_web_hub *h, session *s, int64_t now) {
  if (!s->joined || now < s->next_ask_ns) return;
  const int after_stall = s->stall_asks > 0;
  if (s->st.visual_count > 0 && !after_stall) return;
  send_request_seq(h, s, palp_OP_JOIN, s->join_seq); /* the same JOIN */
  s->next_ask_ns = now + REASK_AFTER_NS;
  h->stats.rejoins++;
  if (after_stall)
    s->stall_asks--; /* said once for all sessions (note_stall) */
  else if (s->asked_again++ == 0)
    palp_log_warn(h->def.log, "session %u: its server counts no visual station, so it dropped this bridge (did palp-web "
                              "not run for a while?): JOIN sent again", s->id);
}

static void manage_joins(palp_web_hub *h, int64_t now) {
  int want[PALP_WEB_MAX_SESSIONS];
  pthread_mutex_lock(&h->mu);
  memset(want, 0, sizeof want);
  for (int c = 0; c < h->nclients; c++) {
    const palp_web_cursor *cu = h->clients[c];
    for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
      if (h->slot_sid[i] && (cu->mode == PALP_WEB_FOLLOW_ALL ||
                             (cu->mode == PALP_WEB_FOLLOW_SESSION && cu->follow == h->slot_sid[i])))
        want[i] = 1;
  }
  memcpy(h->want, want, sizeof want);
  pthread_mutex_unlock(&h->mu);
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++) {
    session *s = &h->s[i];
    if (!s->used) continue;
    if (want[i]) {
      s->unwanted_since = 0;
      if (!s->joined && h->def.join && (!s->join_failed_ns || now - s->join_failed_ns > REJOIN_AFTER_NS)) {
        send_request(h, s, palp_OP_JOIN);
        set_joined(h, s, 1);
        s->join_failed_ns = 0;
        h->stats.joins++;
        h->sessions_dirty = 1;
      } else {
        rejoin_if_dropped(h, s, now);
      }
    } else if (s->joined) {
      if (!s->unwanted_since) s->unwanted_since = now;
      if ((double)(now - s->unwanted_since) * 1e-9 >= h->def.linger_s) leave(h, s);
    }
  }
}

/* The server's answers to the bridge's own requests: a rejected join is retried later. */
static void check_replies(palp_web_hub *h, int64_t now) {
  palp_SessionReply buf[8];
  void *ptr[8];
  dds_sample_info_t info[8];
  for (int i = 0; i < 8; i++) ptr[i] = &buf[i];
  int n;
  while ((n = dds_take(h->reply_r, ptr, info, 8, 8)) > 0) {
    for (int i = 0; i < n; i++) {
      if (!info[i].valid_data || buf[i].status != palp_REPLY_REJECTED) continue;
      for (int k = 0; k < PALP_WEB_MAX_SESSIONS; k++) {
        session *s = &h->s[k];
        if (s->used && s->joined && !strcmp(s->station, buf[i].station_id) && strcmp(buf[i].reason, "left") != 0) {
          /* from the session's server alone, as its streams (from_its_server): a peer that read the
           * bridge's station id wrote a refusal and the bridge left the session for 5 s, its page's
           * marks refused meanwhile (session 80's review, 2026-12-07) */
          const dds_instance_handle_t pp = palp_dds_origin_participant(&h->origin, h->reply_r, &info[i]);
          if (s->server_pp && pp && pp != s->server_pp) {
            h->stats.not_server++;
            continue;
          }
          /* the reason printable: it comes from the network, and a newline in it forged a log line */
          palp_log_warn(h->def.log, "the server refused to stream session %u: %s", s->id,
                        PALP_PRINTABLE_LONG(buf[i].reason));
          set_joined(h, s, 0);
          s->join_failed_ns = now;
          h->stats.join_rejected++;
          dispose_request(s); /* forget the request instance too */
        }
      }
    }
    if (n < 8) break;
  }
}

/* No phantom heard 10 s after the start, with other participants on the domain: say once what
 * may be wrong (most often a secured classroom and a bridge without an identity). */
#define QUIET_HINT_AFTER_NS (10 * 1000000000LL)

static void hint_if_unanswered(palp_web_hub *h, int64_t now, int64_t start) {
  if (h->hinted || now - start < QUIET_HINT_AFTER_NS) return;
  h->hinted = 1;
  for (int i = 0; i < PALP_WEB_MAX_PHANTOMS; i++)
    if (h->ph[i].used) return;
  char hint[PALP_DDS_HINT_MAX];
  palp_dds_unanswered_hint(h->pp, &h->def.sec, hint, sizeof hint);
  if (hint[0]) palp_log_warn(h->def.log, "no phantom from any palp-server in 10 s%s", hint);
}

/* The DDS thread's counters, copied under the lock for palp_web_hub_stats_get (stats_pub). */
static void publish_stats(palp_web_hub *h) {
  pthread_mutex_lock(&h->mu);
  h->stats_pub = h->stats;
  pthread_mutex_unlock(&h->mu);
}

/* A turn of the DDS thread STALL_NS or more after the last: every session the bridge joined sends its
 * JOIN again (rejoin_if_dropped), said once per stall. */
static void note_stall(palp_web_hub *h, int64_t now) {
  const int64_t gap = h->turn_ns ? now - h->turn_ns : 0;
  h->turn_ns = now;
  if (gap < STALL_NS) return;
  int joined = 0;
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++) {
    session *s = &h->s[i];
    if (!s->used || !s->joined) continue;
    s->stall_asks = STALL_ASKS;
    s->next_ask_ns = 0;
    joined++;
  }
  h->stats.stalls++;
  if (joined)
    palp_log_warn(h->def.log, "palp-web's DDS thread was away %.2f s (the process stopped or starved, or one long "
                              "turn): the server may have dropped it from the %d session(s) it streams; JOIN sent again "
                              "to each", 1e-9 * (double)gap, joined);
}

static void *hub_main(void *arg) {
  palp_web_hub *h = arg;
  const int64_t live_period = (int64_t)(1e9 / h->def.live_hz);
  const int64_t start = palp_dds_now_ns();
  while (h->running) {
    /* Wakes for state changes (catalogue, session states, status, replies) at once, else polls. */
    int64_t now = palp_dds_now_ns();
    if (h->next_poll_ns > now) dds_waitset_wait(h->ws, NULL, 0, h->next_poll_ns - now);
    if (!h->running) break;
    now = palp_dds_now_ns();
    note_stall(h, now);
    const int poll_due = now >= h->next_poll_ns;
    if (poll_due) h->next_poll_ns = now + POLL_NS;
    int news = 0;
    news += drain(h, h->catalogue_r, (sample_fn)on_phantom, NULL, &h->stats.catalogue);
    news += drain(h, h->state_r, (sample_fn)on_state, on_state_lost, &h->stats.states);
    news += drain(h, h->status_r, (sample_fn)on_status, NULL, &h->stats.statuses);
    news += drain(h, h->exercise_r, (sample_fn)on_exercise, on_exercise_lost, &h->stats.exercises);
    drain(h, h->sexercise_r, (sample_fn)on_session_exercise, NULL, &h->stats.session_exercises);
    /* Contacts and feedback arrive at the tick rate (up to 1 kHz): polled here, newest per key,
     * instead of waking the thread per sample. */
    if (poll_due) {
      drain(h, h->contact_r, (sample_fn)on_contact, on_contact_lost, &h->stats.contacts);
      for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
        if (h->s[i].used && h->s[i].fb_r > 0) drain(h, h->s[i].fb_r, (sample_fn)on_feedback, NULL, &h->stats.feedbacks);
      drain(h, h->lm_r, (sample_fn)on_local_model, NULL, &h->stats.local_models);
      drain(h, h->fsample_r, (sample_fn)on_finger_sample, NULL, &h->stats.finger_samples);
      drain(h, h->fstatus_r, (sample_fn)on_finding_status, NULL, &h->stats.finding_statuses);
      drain(h, h->debrief_r, (sample_fn)on_debrief, NULL, &h->stats.debriefs);
      drain(h, h->closed_r, (sample_fn)on_session_closed, NULL, &h->stats.closed_sessions); /* before the scores */
      if (h->score_r > 0) drain(h, h->score_r, (sample_fn)on_score, NULL, &h->stats.scores);
      drain(h, h->debrief_score_r, (sample_fn)on_debrief_score, NULL, &h->stats.told_scores); /* after the debriefs */
      drain(h, h->session_log_r, (sample_fn)on_session_log, NULL, &h->stats.session_logs);
      if (h->def.answers) {
        drain(h, h->finding_r, (sample_fn)on_finding, NULL, &h->stats.findings_read);
        renew_findings(h, now);
        tend_answers(h, now);
      }
      news += drain(h, h->deform_r, (sample_fn)on_deformation, NULL, &h->stats.deformations);
      renew_streams(h, now);
    }
    check_replies(h, now);
    for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++) {
      session *s = &h->s[i];
      if (!s->used) continue;
      if (now - s->fps_t0 >= 1000000000LL) {
        const double fps = s->fps_count / ((double)(now - s->fps_t0) * 1e-9);
        if (fps != s->fps) s->changed = 1;
        s->fps = fps;
        s->fps_count = 0;
        s->fps_t0 = now;
      }
      if (now >= s->next_live_ns) {
        /* Coverage: the footprint of every finger pressing at least lightly, at the live rate. */
        for (int k = 0; k < FINGERS; k++) {
          const finger *f = &s->f[k];
          if (f->mode == palp_CONTACT_RELEASE || !s->cov) continue;
          /* A position-driven finger with local models is marked as its models arrive
           * (on_local_model). Else the contact's centre and radius with the force it carries or
           * its feedback (docs/web.md). */
          if (f->mode == palp_CONTACT_FINGER && f->lm_valid) continue;
          const double *fv = f->mode == palp_CONTACT_FORCE ? f->force : f->fb;
          if (f->mode == palp_CONTACT_FINGER && !f->fb_active) continue;
          const int band = palp_web_band(&h->def.bands, sqrt(fv[0] * fv[0] + fv[1] * fv[1] + fv[2] * fv[2]));
          if (band && palp_coverage_press(s->cov, f->center, f->radius, band - 1) > 0) s->changed = s->cover_changed = 1;
          if (band && s->touched) palp_coverage_press(s->touched, f->center, f->radius, band - 1);
        }
        if (s->changed) {
          build_live(h, i);
          s->changed = 0;
          news++;
        }
        s->next_live_ns = now + live_period;
      }
      if (s->cover_changed && now >= s->next_cover_ns) {
        build_cover(h, i);
        s->cover_changed = 0;
        s->next_cover_ns = now + COVER_PERIOD_NS;
        news++;
      }
    }
    if (h->sessions_structure || (h->sessions_dirty && now >= h->next_sessions_ns)) {
      build_sessions(h);
      h->sessions_dirty = h->sessions_structure = 0;
      h->next_sessions_ns = now + SESSIONS_PERIOD_NS;
      news++;
    }
    if (now >= h->next_join_ns) {
      manage_joins(h, now);
      h->next_join_ns = now + JOIN_PERIOD_NS;
      hint_if_unanswered(h, now, start);
    }
    publish_stats(h);
    if ((news || now >= h->next_wake_ns) && h->wake) {
      h->wake(h->wake_ctx);
      h->next_wake_ns = now + WAKE_PERIOD_NS;
    }
  }
  publish_stats(h);
  return NULL;
}

/* ---- set-up ---------------------------------------------------------------------------------- */

static dds_entity_t make_reader(dds_entity_t parent, dds_entity_t topic, palp_dds_topic_kind kind) {
  return palp_dds_create_reader(parent, topic, kind);
}

/* A stream's reader (contacts, feedback, deformations, local models, finger samples), best-effort,
 * keeping `depth` samples per instance and at most as many instances as the gate can pass: a
 * dispose carries no sample for the filter to judge, so a flood of disposes of made-up keys would
 * otherwise grow the reader until its writer goes. Past the bound a new key's samples are rejected
 * (counted: palp_web_hub_stats.rejected); the instances the bridge already has go on. Best-effort,
 * so a rejected sample is dropped, never retried on the delivery path as a reliable one would be
 * (docs/robustness.md). */
static dds_entity_t stream_reader(const palp_web_hub *h, dds_entity_t sub, dds_entity_t topic, palp_dds_topic_kind kind,
                                  int32_t depth) {
  dds_qos_t *q = palp_dds_qos(kind);
  dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0); /* a reliable writer's too: never waits for a retransmit */
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
  palp_dds_gate_limit(&h->gate, q, kind);
  const dds_entity_t r = dds_create_reader(sub, topic, q, NULL);
  dds_delete_qos(q);
  return r;
}

palp_web_hub *palp_web_hub_create(const palp_web_hub_def *def, char *err, size_t errlen) {
  if (palp_web_bands_check(&def->bands) != 0) {
    fail(err, errlen, "bands: need 0 <= touch < light < medium");
    return NULL;
  }
  if (!(def->dashboard_hz > 0 && def->dashboard_hz <= 60) || !(def->live_hz > 0 && def->live_hz <= 120) ||
      !(def->scale_mm > 0 && def->scale_mm <= 1000) ||
      !(def->scale_min_mm > 0 && def->scale_min_mm <= def->scale_mm) || !(def->linger_s >= 0 && def->linger_s <= 3600)) {
    fail(err, errlen, "rates, scale or linger out of range");
    return NULL;
  }
  palp_web_hub *h = calloc(1, sizeof *h);
  if (!h) {
    fail(err, errlen, "out of memory");
    return NULL;
  }
  h->def = *def;
  pthread_mutex_init(&h->mu, NULL);
  gethostname(h->host, sizeof h->host - 1);
  const int secured = def->sec.kind != PALP_DDS_ID_NONE;
  if (secured && def->sec.kind != PALP_DDS_ID_INSTRUCTOR) {
    /* a trainee's permissions read only its own sessions and the server's are the server's */
    fail(err, errlen, "the bridge needs an instructor identity (instructor/NAME), not %s/%s: it shows every session",
         palp_dds_id_kind_name(def->sec.kind), def->sec.name);
    palp_web_hub_destroy(h);
    return NULL;
  }
  h->reaper = palp_dds_reaper_create(4 * PALP_WEB_MAX_SESSIONS); /* three entities a session, and room */
  if (!h->reaper) {
    fail(err, errlen, "cannot start the thread that deletes closed sessions' entities");
    palp_web_hub_destroy(h);
    return NULL;
  }
  h->pp = palp_dds_create_participant((dds_domainid_t)def->domain, &def->sec);
  if (h->pp < 0) {
    fail(err, errlen, "cannot create a DDS participant on domain %u: %s%s", def->domain, dds_strretcode(h->pp),
         secured ? " (DDS Security refused the identity: see the messages above; is the certificate revoked or "
                   "expired, the domain above 230?)"
                 : "");
    palp_web_hub_destroy(h);
    return NULL;
  }
  if (secured && def->refusals &&
      palp_dds_strangers_init(&h->strangers, h->pp, PALP_DDS_STRANGER_GRACE_S) == 0)
    h->strangers_ready = 1; /* the dashboard lists a station started without an identity too */
  for (int k = 0; k < PALP_TOPIC_COUNT; k++) h->topic[k] = palp_dds_create_topic(h->pp, (palp_dds_topic_kind)k);
  /* The gate's filters, before the readers so that no sample of theirs passes unfiltered: the streams'
   * and the session's reliable topics it only reads (the findings on a topic entity of their own,
   * below: it writes its pages' on this one, and a filter applies to writes too); a debrief, a told
   * score or the log's losses of a session that just closed still pass, by the ring of sessions heard
   * open. */
  palp_dds_gate_init(&h->gate, PALP_WEB_MAX_SESSIONS);
  static const palp_dds_topic_kind read_only[] = {PALP_TOPIC_FINDING_STATUS, PALP_TOPIC_DEBRIEF,
                                                  PALP_TOPIC_DEBRIEF_SCORE, PALP_TOPIC_SESSION_LOG};
  const int filters = palp_dds_gate_filter_topics(&h->gate, h->topic, read_only, sizeof read_only / sizeof read_only[0]);
  h->catalogue_r = make_reader(h->pp, h->topic[PALP_TOPIC_CATALOGUE], PALP_TOPIC_CATALOGUE);
  h->state_r = make_reader(h->pp, h->topic[PALP_TOPIC_SESSION_STATE], PALP_TOPIC_SESSION_STATE);
  h->status_r = make_reader(h->pp, h->topic[PALP_TOPIC_SERVER_STATUS], PALP_TOPIC_SERVER_STATUS);
  h->reply_r = make_reader(h->pp, h->topic[PALP_TOPIC_SESSION_REPLY], PALP_TOPIC_SESSION_REPLY);
  /* Every session's partition, as palp-recorder reads them: "palp/session/" + "*". */
  char wildcard[64];
  snprintf(wildcard, sizeof wildcard, PALP_DDS_SESSION_PARTITION_FMT, 0u);
  char *z = strrchr(wildcard, '/');
  if (z) snprintf(z + 1, sizeof wildcard - (size_t)(z + 1 - wildcard), "*");
  if (secured) { /* secured sessions live in palp/s/TRAINEE/ID (as palp-recorder reads them) */
    snprintf(wildcard, sizeof wildcard, "palp/s/*");
    char part[64];
    palp_dds_request_partition(&def->sec, part, sizeof part);
    h->req_pub = palp_dds_session_publisher(h->pp, part);
  }
  h->sub = palp_dds_session_subscriber(h->pp, wildcard);
  h->readers_since = dds_time();
  h->contact_r = stream_reader(h, h->sub, h->topic[PALP_TOPIC_CONTACT], PALP_TOPIC_CONTACT, 1);
  h->deform_r = stream_reader(h, h->sub, h->topic[PALP_TOPIC_DEFORMATION], PALP_TOPIC_DEFORMATION, 1);
  /* local models in full (not just the newest), every frame, for late updates */
  h->lm_r = stream_reader(h, h->sub, h->topic[PALP_TOPIC_LOCAL_MODEL], PALP_TOPIC_LOCAL_MODEL, LM_DEPTH);
  /* ... and the finger samples, 100 Hz per finger: 64 hold 0.64 s between polls */
  if (h->topic[PALP_TOPIC_FINGER_SAMPLE] > 0)
    h->fsample_r = stream_reader(h, h->sub, h->topic[PALP_TOPIC_FINGER_SAMPLE], PALP_TOPIC_FINGER_SAMPLE, LM_DEPTH);
  h->fstatus_r = make_reader(h->sub, h->topic[PALP_TOPIC_FINDING_STATUS], PALP_TOPIC_FINDING_STATUS);
  /* an instructor's permissions read every topic: no older permissions to allow for here */
  h->debrief_r = make_reader(h->sub, h->topic[PALP_TOPIC_DEBRIEF], PALP_TOPIC_DEBRIEF);
  h->debrief_score_r = make_reader(h->sub, h->topic[PALP_TOPIC_DEBRIEF_SCORE], PALP_TOPIC_DEBRIEF_SCORE);
  /* session 69: a bridge on permissions from before it counts the server's losses, as a station does */
  h->session_log_r = h->topic[PALP_TOPIC_SESSION_LOG] > 0
                         ? make_reader(h->sub, h->topic[PALP_TOPIC_SESSION_LOG], PALP_TOPIC_SESSION_LOG)
                         : 0;
  if (h->session_log_r < 0) h->session_log_r = 0;
  /* session 69: a bridge whose permissions predate it shows the ended sessions it did not see unnamed */
  h->closed_r = h->topic[PALP_TOPIC_SESSION_CLOSED] > 0
                    ? make_reader(h->pp, h->topic[PALP_TOPIC_SESSION_CLOSED], PALP_TOPIC_SESSION_CLOSED)
                    : 0;
  if (h->closed_r < 0) h->closed_r = 0;
  h->exercise_r = make_reader(h->pp, h->topic[PALP_TOPIC_EXERCISE], PALP_TOPIC_EXERCISE);
  if (def->answers) {
    /* the answers (instructors only: a trainee's permissions cannot even create the topic) */
    h->sexercise_r = make_reader(h->pp, h->topic[PALP_TOPIC_SESSION_EXERCISE], PALP_TOPIC_SESSION_EXERCISE);
    /* The findings are read through a topic entity of their own, gated as the answers are: the pages'
     * findings are written on h->topic[PALP_TOPIC_FINDING], which must stay unfiltered (a filter applies
     * to its topic entity's writers too), so made-up sessions' findings become no instance here. */
    dds_entity_t only[PALP_TOPIC_COUNT] = {0};
    static const palp_dds_topic_kind finding[] = {PALP_TOPIC_FINDING};
    only[PALP_TOPIC_FINDING] = palp_dds_create_topic(h->pp, PALP_TOPIC_FINDING);
    h->finding_r = h->finding_topic_r = only[PALP_TOPIC_FINDING];
    if (h->finding_r > 0) {
      const int rc = palp_dds_gate_filter_topics(&h->gate, only, finding, 1);
      h->finding_r = rc < 0 ? rc : make_reader(h->sub, only[PALP_TOPIC_FINDING], PALP_TOPIC_FINDING);
    }
    h->score_r = make_reader(h->pp, h->topic[PALP_TOPIC_SESSION_SCORE], PALP_TOPIC_SESSION_SCORE);
  }
  h->ws = dds_create_waitset(h->pp);
  h->stop_gc = dds_create_guardcondition(h->pp);
  const dds_entity_t wake_on[] = {h->catalogue_r, h->state_r, h->status_r, h->reply_r, h->exercise_r};
  int bad = filters < 0 || h->sexercise_r < 0 || h->finding_r < 0 || h->score_r < 0 || h->req_pub < 0 || h->fstatus_r < 0 || h->debrief_r < 0 || h->debrief_score_r < 0 || h->sub < 0 || h->contact_r < 0 || h->deform_r < 0 || h->lm_r < 0 || h->fsample_r < 0 || h->ws < 0 || h->stop_gc < 0;
  for (size_t k = 0; k < sizeof wake_on / sizeof wake_on[0]; k++) {
    bad |= wake_on[k] < 0;
    if (wake_on[k] > 0) {
      dds_set_status_mask(wake_on[k], DDS_DATA_AVAILABLE_STATUS);
      dds_waitset_attach(h->ws, wake_on[k], (dds_attach_t)k);
    }
  }
  if (!bad) bad = dds_waitset_attach(h->ws, h->stop_gc, -1) < 0;
  if (bad) {
    char hint[PALP_DDS_HINT_MAX];
    fail(err, errlen, "cannot create the bridge's DDS readers%s", palp_dds_refused_hint(&def->sec, NULL, hint, sizeof hint));
    palp_web_hub_destroy(h);
    return NULL;
  }
  build_hello(h);
  build_exercises(h);
  return h;
}

int palp_web_hub_start(palp_web_hub *h, palp_web_wake_fn wake, void *ctx) {
  h->wake = wake;
  h->wake_ctx = ctx;
  h->running = 1;
  if (pthread_create(&h->thread, NULL, hub_main, h) != 0) {
    h->running = 0;
    return PALP_ENOMEM;
  }
  return 0;
}

void palp_web_hub_stop(palp_web_hub *h) {
  if (!h || !h->running) return;
  h->running = 0;
  dds_set_guardcondition(h->stop_gc, true);
  pthread_join(h->thread, NULL);
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
    if (h->s[i].used) leave(h, &h->s[i]);
}

void palp_web_hub_destroy(palp_web_hub *h) {
  if (!h) return;
  palp_web_hub_stop(h);
  palp_dds_reaper_destroy(h->reaper); /* what it still holds deleted before their participant */
  if (h->strangers_ready) palp_dds_strangers_destroy(&h->strangers);
  if (h->pp > 0) dds_delete(h->pp);
  for (int i = 0; i < PALP_WEB_MAX_PHANTOMS; i++) {
    free(h->ph[i].rest);
    free(h->ph[i].tri);
    free(h->phantom_msg[i].buf);
  }
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++) {
    palp_coverage_destroy(h->s[i].cov);
    palp_coverage_destroy(h->s[i].touched); /* as free_session does (a leak at exit until 2026-12-07) */
    free(h->deform_msg[i].buf);
    free(h->live_msg[i].buf);
    free(h->answers_msg[i].buf);
    free(h->cover_msg[i].buf);
    if (h->s[i].ans) free(h->s[i].ans->ex);
    free(h->s[i].ans);
  }
  for (int k = 0; k < SESSION_EXERCISES_PENDING; k++) free(h->pending_ex[k].ex);
  for (int i = 0; i < MAX_SERVERS; i++) free(h->srv[i].loads);
  free(h->hello.buf);
  for (int k = 0; k < DEBRIEFS; k++) free(h->debrief[k].msg.buf), free(h->ended_answers[k].buf), free(h->scores[k].buf), free(h->told_scores[k].buf);
  free(h->sessions_msg.buf);
  free(h->status_msg.buf);
  free(h->exercises_msg.buf);
  pthread_mutex_destroy(&h->mu);
  free(h);
}

int palp_web_hub_has_instance(palp_web_hub *h, int topic, uint32_t session_id, unsigned finger) {
  union { /* every stream's key is (session id[, finger]) first (idl/palp_dds_gate.c) */
    palp_Contact c;
    palp_Deformation d;
    palp_LocalModel l;
    palp_FingerSample f;
    palp_FindingStatus fs;
    palp_Debrief db;
    palp_SessionScore sc;
    palp_SessionLog sl;
    palp_Finding fi;
  } key;
  memset(&key, 0, sizeof key);
  key.c.session_id = session_id;
  dds_entity_t rd;
  /* mu: the findings and stream readers may be made anew meanwhile by the DDS thread (renew_findings,
   * renew_stream); held until the read is done so that the reader is not deleted under it. The other
   * readers live as long as the hub. */
  pthread_mutex_lock(&h->mu);
  switch (topic) {
  case PALP_TOPIC_CONTACT: rd = h->contact_r, key.c.finger = (uint8_t)finger; break;
  case PALP_TOPIC_DEFORMATION: rd = h->deform_r; break;
  case PALP_TOPIC_LOCAL_MODEL: rd = h->lm_r, key.l.finger = (uint8_t)finger; break;
  case PALP_TOPIC_FINGER_SAMPLE: rd = h->fsample_r, key.f.finger = (uint8_t)finger; break;
  case PALP_TOPIC_FINDING_STATUS: rd = h->fstatus_r; break;
  case PALP_TOPIC_DEBRIEF: rd = h->debrief_r; break;
  case PALP_TOPIC_DEBRIEF_SCORE: rd = h->debrief_score_r; break;
  case PALP_TOPIC_SESSION_LOG: rd = h->session_log_r; break;
  case PALP_TOPIC_FINDING: rd = h->finding_r; break;
  default: pthread_mutex_unlock(&h->mu); return PALP_EINVAL;
  }
  int held = 0;
  if (rd > 0) {
    /* dds_lookup_instance answers from the domain's key map, which any entity of this process that
     * keeps the key (a reliable writer's history) fills too: a read of the instance asks this reader
     * (Cyclone: "precondition not met" for a handle it holds no instance of). */
    const dds_instance_handle_t ih = dds_lookup_instance(rd, &key);
    if (ih != 0) {
      void *ptr[1] = {NULL};
      dds_sample_info_t info[1];
      const dds_return_t n = dds_read_instance(rd, ptr, info, 1, 1, ih);
      if (n > 0) dds_return_loan(rd, ptr, n);
      held = n >= 0;
    }
  }
  pthread_mutex_unlock(&h->mu);
  return held;
}

void palp_web_hub_stats_get(palp_web_hub *h, palp_web_hub_stats *out) {
  /* the samples the stream readers refused are counted by the DDS thread (renew_stream), which makes
   * those readers anew: read here from the readers, they were counted afresh with each new one */
  pthread_mutex_lock(&h->mu);
  /* the DDS thread's counters as of its last pass; the pages' finding requests count under mu */
  *out = h->stats_pub;
  out->findings_written = h->stats.findings_written;
  out->findings_refused = h->stats.findings_refused;
  out->clients = h->nclients;
  palp_dds_reaper_stats rs = {0};
  if (h->reaper) palp_dds_reaper_stats_get(h->reaper, &rs);
  out->reaped = rs.deleted;
  out->reap_pending = rs.pending;
  out->reap_longest_s = (double)rs.longest_ns * 1e-9;
  out->sessions_open = 0;
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++) out->sessions_open += h->slot_sid[i] != 0;
  pthread_mutex_unlock(&h->mu);
}

/* ---- browser side (web thread) ------------------------------------------------------------------ */

int palp_web_hub_attach(palp_web_hub *h, palp_web_cursor *c, int max_clients) {
  memset(c, 0, sizeof *c);
  if (max_clients > MAX_CLIENTS_HARD) max_clients = MAX_CLIENTS_HARD;
  pthread_mutex_lock(&h->mu);
  int rc = PALP_EFULL;
  if (h->nclients < max_clients) {
    h->clients[h->nclients++] = c;
    c->debrief_from = h->next_ver; /* a page is sent the debriefs that come after it (and a dashboard more) */
    rc = 0;
  }
  pthread_mutex_unlock(&h->mu);
  return rc;
}

void palp_web_hub_scope(palp_web_hub *h, palp_web_cursor *c, const char *trainee) {
  pthread_mutex_lock(&h->mu);
  snprintf(c->scope, sizeof c->scope, "%s", trainee);
  pthread_mutex_unlock(&h->mu);
}

void palp_web_hub_detach(palp_web_hub *h, palp_web_cursor *c) {
  pthread_mutex_lock(&h->mu);
  for (int i = 0; i < h->nclients; i++)
    if (h->clients[i] == c) {
      h->clients[i] = h->clients[--h->nclients];
      break;
    }
  pthread_mutex_unlock(&h->mu);
}

/* Sets this page's answer to its finding request (under mu); sent before anything else. */
static void set_reply(palp_web_cursor *c, const char *op, int ok, uint32_t mark_id, const char *reason) {
  char safe[200];
  json_safe(safe, sizeof safe, reason);
  const int n = snprintf(c->reply, sizeof c->reply,
                         "{\"type\":\"finding_reply\",\"op\":\"%s\",\"ok\":%s,\"mark_id\":%u,\"reason\":\"%s\"}", op,
                         ok ? "true" : "false", mark_id, safe);
  c->reply_len = n > 0 && (size_t)n < sizeof c->reply ? (size_t)n : 0;
}

/* A control refused for the page's token, told to the page: {"type": "refused", "message": ...}. */
static void set_refused(palp_web_cursor *c, const char *why) {
  const int n = snprintf(c->reply, sizeof c->reply, "{\"type\":\"refused\",\"message\":\"%s\"}", why);
  c->reply_len = n > 0 && (size_t)n < sizeof c->reply ? (size_t)n : 0;
}

/* {"finding": "mark" | "withdraw"} from a page (web thread). Every check is made here, under the
 * mutex, against what the DDS thread holds; the write itself happens outside it. */
static int scope_allows(const palp_web_hub *h, const palp_web_cursor *c, uint32_t id);

static int finding_request(palp_web_hub *h, palp_web_cursor *c, int mark) {
  const char *op = mark ? "mark" : "withdraw";
  const char *why = NULL;
  palp_Finding f;
  memset(&f, 0, sizeof f);
  dds_entity_t w = 0;
  int slot = -1;
  const int64_t now = palp_dds_now_ns();
  pthread_mutex_lock(&h->mu);
  if (!c->trainee) {
    why = "only the trainee page of a session may mark findings; this page is a viewer";
  } else if (c->scope[0] && !scope_allows(h, c, c->trainee)) {
    why = "the session this page was bound to is no longer this trainee's";
  } else {
    for (int i = 0; i < PALP_WEB_MAX_SESSIONS && slot < 0; i++)
      if (h->slot_sid[i] == c->trainee) slot = i;
    for (int k = 0; k < h->nclients && !why; k++)
      if (h->clients[k] != c && h->clients[k]->trainee == c->trainee && h->clients[k]->bind_seq > c->bind_seq)
        why = "another trainee page took this session";
  }
  finding_slot *fs = slot >= 0 ? &h->fs[slot] : NULL;
  if (why) {
  } else if (!fs) {
    why = "the session is not open";
  } else if (!fs->exercise) {
    why = "no exercise is running in this session";
  } else if (fs->w <= 0) {
    why = h->def.sec.kind != PALP_DDS_ID_NONE
              ? "in a secured classroom findings are marked from the trainee's own station, not from this page"
              : "the bridge cannot write findings for this session";
  } else if (!fs->joined) {
    /* The server takes a session's findings only from the participant that joined it or one with a
     * visual station in it (docs/server.md); from this bridge it would refuse them unanswered. */
    why = h->def.join ? "the bridge is not in this session: the server refused its join (it asks again every 5 s); "
                        "mark from the trainee's station"
                      : "this bridge runs with --no-join, so the server does not take its marks: mark from the "
                        "trainee's station";
  } else if (fs->last_ns && now - fs->last_ns < FINDING_GAP_NS) {
    why = "too fast: one finding request per 0.5 s";
  } else if (mark && (!fs->contact || now - fs->at_ns > CONTACT_FRESH_NS)) {
    why = "not touching the phantom: press where you feel the lump, then mark it";
  } else if (mark && fs->nstack >= FINDING_MARKS_MAX) {
    why = "too many marks standing";
  } else if (!mark && fs->nstack == 0) {
    why = "no mark of this page to withdraw";
  } else {
    dds_publication_matched_status_t ms;
    if (dds_get_publication_matched_status(fs->w, &ms) != 0 || ms.current_count == 0)
      why = "no server takes findings for this session";
  }
  if (!why) {
    f.session_id = c->trainee;
    f.op = mark ? palp_FINDING_MARK : palp_FINDING_WITHDRAW;
    f.mark_id = mark ? fs->next_mark + 1 : fs->stack[fs->nstack - 1];
    if (mark) f.point = (palp_Vec3){fs->point[0], fs->point[1], fs->point[2]}, f.time = fs->time;
    w = fs->w;
    fs->last_ns = now; /* the rate counts attempts that reach DDS */
  } else {
    h->stats.findings_refused++;
    set_reply(c, op, 0, 0, why);
  }
  pthread_mutex_unlock(&h->mu);
  if (why) return 1;
  /* Reliable keep-all; at this rate the writer's history never fills, so this does not block. */
  const dds_return_t rc = dds_write(w, &f);
  pthread_mutex_lock(&h->mu);
  if (rc != 0) {
    h->stats.findings_refused++;
    set_reply(c, op, 0, 0, "the finding could not be written to the session");
  } else {
    if (h->slot_sid[slot] == f.session_id) { /* still the same session */
      /* The server's answer may have come while the lock was let go for the write (on_finding_status
       * pops a refused top mark): pop the mark withdrawn only if it is still on top, push within the
       * stack's bound (a plain nstack-- could pop another mark, or go to -1 and the next mark write
       * stack[-1]; session 75, found by review). */
      if (mark) {
        if (fs->nstack < FINDING_MARKS_MAX) fs->stack[fs->nstack++] = f.mark_id;
        if (f.mark_id > fs->next_mark) fs->next_mark = f.mark_id; /* an answer may have raised it meanwhile */
      } else if (fs->nstack > 0 && fs->stack[fs->nstack - 1] == f.mark_id) {
        fs->nstack--;
      }
    }
    h->stats.findings_written++;
    set_reply(c, op, 1, f.mark_id, "");
  }
  pthread_mutex_unlock(&h->mu);
  return rc != 0;
}

/* Under h->mu: session id is open and its trainee is the cursor's scope. */
static int scope_allows(const palp_web_hub *h, const palp_web_cursor *c, uint32_t id) {
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++)
    if (h->slot_sid[i] == id) return strcmp(h->slot_trainee[i], c->scope) == 0;
  return 0;
}

/* The session list as a scoped page may see it: the shared message with the other trainees'
 * sessions taken out (built at most at the list's 5 Hz, per scoped page). */
static int take_scoped_sessions(const item *it, const char *scope, size_t pre, unsigned char **buf, size_t *len) {
  cJSON *j = cJSON_ParseWithLength((const char *)it->buf, it->len);
  cJSON *arr = j ? cJSON_GetObjectItemCaseSensitive(j, "sessions") : NULL;
  if (!cJSON_IsArray(arr)) {
    cJSON_Delete(j);
    return PALP_ENOMEM; /* our own message: only memory can have failed */
  }
  for (int k = cJSON_GetArraySize(arr) - 1; k >= 0; k--) {
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(arr, k), "trainee");
    if (!cJSON_IsString(t) || strcmp(t->valuestring, scope) != 0) cJSON_DeleteItemFromArray(arr, k);
  }
  char *text = cJSON_PrintUnformatted(j);
  cJSON_Delete(j);
  if (!text) return PALP_ENOMEM;
  const size_t n = strlen(text);
  unsigned char *b = malloc(pre + n);
  if (b) memcpy(b + pre, text, n);
  free(text);
  if (!b) return PALP_ENOMEM;
  *buf = b;
  *len = n;
  return 1;
}

int palp_web_hub_control(palp_web_hub *h, palp_web_cursor *c, const char *msg, size_t len) {
  if (!msg || len == 0 || len > 256) return PALP_EINVAL;
  cJSON *j = cJSON_ParseWithLength(msg, len);
  if (!j) return PALP_EINVAL;
  const cJSON *f = cJSON_GetObjectItemCaseSensitive(j, "follow");
  const cJSON *t = cJSON_GetObjectItemCaseSensitive(j, "trainee");
  const cJSON *fi = cJSON_GetObjectItemCaseSensitive(j, "finding");
  int mode = -1, bind = 0, finding = -1;
  uint32_t id = 0;
  if (cJSON_IsObject(j) && cJSON_GetArraySize(j) == 1 && f) {
    if (cJSON_IsNull(f)) mode = PALP_WEB_FOLLOW_NONE;
    else if (cJSON_IsString(f) && !strcmp(f->valuestring, "all")) mode = PALP_WEB_FOLLOW_ALL;
    else if (cJSON_IsNumber(f) && f->valuedouble >= 1 && f->valuedouble <= 4294967295.0 &&
             f->valuedouble == floor(f->valuedouble))
      mode = PALP_WEB_FOLLOW_SESSION, id = (uint32_t)f->valuedouble;
  } else if (cJSON_IsObject(j) && cJSON_GetArraySize(j) == 1 && t) {
    if (cJSON_IsNumber(t) && t->valuedouble >= 1 && t->valuedouble <= 4294967295.0 &&
        t->valuedouble == floor(t->valuedouble))
      mode = PALP_WEB_FOLLOW_SESSION, id = (uint32_t)t->valuedouble, bind = 1;
  } else if (cJSON_IsObject(j) && cJSON_GetArraySize(j) == 1 && fi && cJSON_IsString(fi)) {
    if (!strcmp(fi->valuestring, "mark")) finding = 1;
    else if (!strcmp(fi->valuestring, "withdraw")) finding = 0;
  }
  cJSON_Delete(j);
  if (finding >= 0) return finding_request(h, c, finding);
  if (mode < 0) return PALP_EINVAL;
  pthread_mutex_lock(&h->mu);
  /* A scoped page (a trainee's token) sees that trainee's sessions only: no dashboard, and a session
   * it follows must be known to be that trainee's. */
  if (c->scope[0] && (mode == PALP_WEB_FOLLOW_ALL || (mode == PALP_WEB_FOLLOW_SESSION && !scope_allows(h, c, id)))) {
    /* refused, and told why (since session 82: the dashboard opened with a trainee's token said "live"
     * and waited for ever); still an error for the counters */
    set_refused(c, mode == PALP_WEB_FOLLOW_ALL ? "this link's token is a trainee's: the dashboard is for instructors"
                                               : "this link's token is a trainee's: that session is not hers");
    pthread_mutex_unlock(&h->mu);
    return PALP_EINVAL;
  }
  /* A trainee page stays with its session: it may rebind to another one (the session it followed
   * closed) or follow nothing, but not turn into a viewer of other sessions. */
  if (c->trainee && !bind && mode != PALP_WEB_FOLLOW_NONE && !(mode == PALP_WEB_FOLLOW_SESSION && id == c->trainee)) {
    pthread_mutex_unlock(&h->mu);
    return PALP_EINVAL;
  }
  if (bind) {
    c->trainee = id;
    c->bind_seq = ++h->bind_seq; /* the newest binding of a session wins */
  }
  if (c->mode == PALP_WEB_FOLLOW_SESSION && !(mode == PALP_WEB_FOLLOW_SESSION && id == c->follow))
    c->followed = c->follow;
  c->mode = mode;
  c->follow = id;
  /* A new follow starts from the newest frame, not from whatever was skipped. */
  memset(c->deform_ver, 0, sizeof c->deform_ver);
  memset(c->live_ver, 0, sizeof c->live_ver);
  memset(c->answers_ver, 0, sizeof c->answers_ver);
  memset(c->cover_ver, 0, sizeof c->cover_ver);
  pthread_mutex_unlock(&h->mu);
  return 0;
}

static int take(const item *it, size_t pre, unsigned char **buf, size_t *len) {
  unsigned char *b = malloc(pre + it->len);
  if (!b) return PALP_ENOMEM;
  memcpy(b + pre, it->buf, it->len);
  *buf = b;
  *len = it->len;
  return 1;
}

/* The oldest message of a ring that is newer than ver (a page's cursor into it), or NULL. */
static const item *oldest_after(const item *ring, int n, uint64_t ver) {
  const item *pick = NULL;
  for (int k = 0; k < n; k++)
    if (ring[k].buf && ring[k].ver > ver && (!pick || ring[k].ver < pick->ver))
      pick = &ring[k];
  return pick;
}

/* Under h->mu: a trainee's page (scoped) lets go of a session id that is open for someone else. The
 * scope was checked as the page bound or followed it, never again, and a restarted server numbers its
 * sessions from 1: alice's page bound to session 77 was sent bob's live data, and his told score as
 * hers, once a new run opened 77 for him (session 80's review, 2026-12-07). Checked at each of the
 * page's wake-ups (<= 100 ms), before anything is picked for it. */
static void rescope(const palp_web_hub *h, palp_web_cursor *c) {
  if (!c->scope[0]) return;
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++) {
    if (!h->slot_sid[i] || !strcmp(h->slot_trainee[i], c->scope)) continue;
    if (c->trainee == h->slot_sid[i]) c->trainee = 0;
    if (c->mode == PALP_WEB_FOLLOW_SESSION && c->follow == h->slot_sid[i]) c->mode = PALP_WEB_FOLLOW_NONE;
    if (c->followed == h->slot_sid[i]) c->followed = 0;
  }
}

int palp_web_hub_next(palp_web_hub *h, palp_web_cursor *c, size_t pre, unsigned char **buf, size_t *len,
                      int *binary) {
  int rc = 0;
  *binary = 0;
  const int64_t now = palp_dds_now_ns();
  pthread_mutex_lock(&h->mu);
  rescope(h, c);
  if (!c->hello_sent && h->hello.buf) {
    rc = take(&h->hello, pre, buf, len);
    if (rc > 0) c->hello_sent = 1;
    goto out;
  }
  if (c->reply_len) {
    const item r = {.ver = 0, .buf = (unsigned char *)c->reply, .len = c->reply_len};
    rc = take(&r, pre, buf, len);
    if (rc > 0) c->reply_len = 0;
    goto out;
  }
  if (h->exercises_msg.buf && c->exercises_ver != h->exercises_msg.ver) {
    rc = take(&h->exercises_msg, pre, buf, len);
    if (rc > 0) c->exercises_ver = h->exercises_msg.ver;
    goto out;
  }
  for (int i = 0; i < PALP_WEB_MAX_PHANTOMS; i++)
    if (h->phantom_msg[i].buf && c->phantom_ver[i] != h->phantom_msg[i].ver) {
      rc = take(&h->phantom_msg[i], pre, buf, len);
      if (rc > 0) c->phantom_ver[i] = h->phantom_msg[i].ver;
      goto out;
    }
  if (h->sessions_msg.buf && c->sessions_ver != h->sessions_msg.ver) {
    rc = c->scope[0] ? take_scoped_sessions(&h->sessions_msg, c->scope, pre, buf, len)
                     : take(&h->sessions_msg, pre, buf, len);
    if (rc > 0) c->sessions_ver = h->sessions_msg.ver;
    goto out;
  }
  if (c->scope[0]) c->status_ver = h->status_msg.ver; /* the server status names every session: not for a scoped page */
  if (h->status_msg.buf && c->status_ver != h->status_msg.ver) {
    rc = take(&h->status_msg, pre, buf, len);
    if (rc > 0) c->status_ver = h->status_msg.ver;
    goto out;
  }
  {
    /* the oldest debrief not yet sent that is this page's: its own trainee session's (it may have
     * followed nothing since the session closed), or an instructor's page's sessions. Those that came
     * before the page attached go only to an instructor's page following every session, the class
     * dashboard: an instructor who opens or reloads it then sees the sessions that ended lately (up to
     * DEBRIEFS). The rule is checked here, as each debrief is picked, so the order of the page's
     * follow messages does not matter: whatever it followed before, once it follows every session the
     * older ones it was not sent come, oldest first; as debrief_ver only grows, none is sent twice
     * (one older than a debrief the page was already sent is skipped). A trainee's page (scoped, or
     * bound to its session) and a page following one session keep the rule of before: only what came
     * after they attached. An instructor's page is also sent the debrief of the session it followed
     * last (c->followed): the page lets go of a session as the session list drops it, and the server's
     * debrief, written before its CLOSED state, can reach the bridge after it (polled, not woken). */
    const int replay = !c->scope[0] && !c->trainee && c->mode == PALP_WEB_FOLLOW_ALL;
    const debrief_item *pick = NULL;
    for (int k = 0; k < DEBRIEFS; k++) {
      const debrief_item *d = &h->debrief[k];
      if (!d->msg.buf || d->msg.ver <= c->debrief_ver || (pick && d->msg.ver >= pick->msg.ver)) continue;
      if (d->msg.ver <= c->debrief_from && !replay) continue;
      if (c->scope[0] && strcmp(c->scope, d->trainee) != 0) continue;
      const int follows = c->mode == PALP_WEB_FOLLOW_ALL || (c->mode == PALP_WEB_FOLLOW_SESSION && c->follow == d->sid);
      if (c->trainee == d->sid || (!c->scope[0] && (follows || c->followed == d->sid))) pick = d;
    }
    if (pick) {
      rc = take(&pick->msg, pre, buf, len);
      if (rc > 0) c->debrief_ver = pick->msg.ver;
      goto out;
    }
    /* a page's own trainee session's score, where the server told her it (on_debrief_score); to a
     * trainee's page (scoped) only when it was hers, as its debrief (her page may still be bound to
     * a closed session whose id a restarted server gave another trainee: trainee_of_session) */
    const item *mine = NULL;
    for (int k = 0; k < DEBRIEFS && c->trainee; k++) {
      const item *it = &h->told_scores[k];
      if (!it->buf || it->ver <= c->scores_ver || h->told_scores_sid[k] != c->trainee || (mine && it->ver >= mine->ver))
        continue;
      if (c->scope[0] && strcmp(c->scope, h->told_scores_trainee[k]) != 0) continue;
      mine = it;
    }
    if (mine) {
      rc = take(mine, pre, buf, len);
      if (rc > 0) c->scores_ver = mine->ver;
      goto out;
    }
    /* the ended sessions' answers, then the closed sessions' scores (session 63), oldest first, to the
     * dashboard alone (as the live answers below: they tell what the marks found), those from before it
     * attached too: a reloaded dashboard still shows what an examination found and how it scored */
    struct {
      const item *ring;
      uint64_t *ver;
    } const kept[] = {{h->ended_answers, &c->ended_answers_ver}, {h->scores, &c->scores_ver}};
    for (size_t r = 0; r < sizeof kept / sizeof kept[0] && replay && h->def.answers; r++) {
      const item *next = oldest_after(kept[r].ring, DEBRIEFS, *kept[r].ver);
      if (!next) continue;
      rc = take(next, pre, buf, len);
      if (rc > 0) *kept[r].ver = next->ver;
      goto out;
    }
  }
  if (c->mode == PALP_WEB_FOLLOW_NONE) goto out;
  const int64_t min_gap = c->mode == PALP_WEB_FOLLOW_ALL ? (int64_t)(1e9 / h->def.dashboard_hz) : 0;
  /* The hidden lumps go to an instructor's page following every session, the dashboard, alone:
   * never to a trainee's token, never to a page bound as a trainee page (whoever opened it), never
   * to a page following one session (the dashboard's click opens one in front of the trainee). */
  const int answers_ok = !c->scope[0] && !c->trainee && c->mode == PALP_WEB_FOLLOW_ALL;
  for (int i = 0; i < PALP_WEB_MAX_SESSIONS; i++) {
    if (!h->slot_sid[i] || (c->mode == PALP_WEB_FOLLOW_SESSION && h->slot_sid[i] != c->follow)) continue;
    const item *d = &h->deform_msg[i], *l = &h->live_msg[i], *a = &h->answers_msg[i], *cv = &h->cover_msg[i];
    if (answers_ok && a->buf && c->answers_ver[i] != a->ver) {
      rc = take(a, pre, buf, len);
      if (rc > 0) c->answers_ver[i] = a->ver;
      goto out;
    }
    if (cv->buf && c->cover_ver[i] != cv->ver) { /* to the dashboard, and to a page following this session */
      rc = take(cv, pre, buf, len);
      if (rc > 0) c->cover_ver[i] = cv->ver;
      goto out;
    }
    /* 1 ms of slack: frames that arrive at exactly the dashboard rate are not pushed to the next one. */
    if (d->buf && c->deform_ver[i] != d->ver && now - c->deform_sent_ns[i] >= min_gap - 1000000) {
      rc = take(d, pre, buf, len);
      if (rc > 0) c->deform_ver[i] = d->ver, c->deform_sent_ns[i] = now, *binary = 1;
      goto out;
    }
    if (c->mode == PALP_WEB_FOLLOW_SESSION && l->buf && c->live_ver[i] != l->ver) {
      rc = take(l, pre, buf, len);
      if (rc > 0) c->live_ver[i] = l->ver;
      goto out;
    }
  }
out:
  pthread_mutex_unlock(&h->mu);
  /* Every text frame a page is sent is valid UTF-8, cleaned here, in the page's own copy, whatever
   * message it is and whoever wrote its strings (utf8.h). */
  if (rc > 0 && !*binary) palp_web_utf8_clean(*buf + pre, *len);
  return rc;
}
