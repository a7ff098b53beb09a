/* palp-recorder: logs classroom sessions from DDS into the session log, as its own process, so a
 * logging machine can serve several servers.
 *
 *   palp-recorder --db FILE [--domain N] [--dds-config FILE] [--duration S]
 *
 * It subscribes to the catalogue and session state (default partition) and, through a subscriber
 * on the partition pattern "palp/session/" + "*", to every session's contact, feedback and
 * deformation topics, and writes them through the same palp_db writer the server uses.
 *
 * What it can and cannot know: contact samples are logged as the recorder received them, stamped
 * with the newest frame it has seen from that session's feedback; the server's own log records the
 * frame each input was applied at. Frame summaries come from the deformation topic (30 Hz by
 * default) and carry no state hash. So a recorded session supports show, export and report but
 * not an exact replay; its params_json says "recorded_by": "palp-recorder" and replay refuses it.
 * Best-effort topics (contact, feedback) may lose samples; readers keep 256 samples per instance
 * so a busy recorder does not overwrite them itself.
 *
 * Exercise sessions (session 60): the exercise with its lesions (palp_session_exercise, which
 * only an instructor's permissions read), the trainee's findings with the server's answer to
 * each (palp_finding, palp_finding_status), the fingertip's samples from the local models the
 * server streams to the station (palp_local_model, at the assessment's rate), and the debrief
 * (palp_debrief): what the review needs to assess the session as it assesses the server's log. */
#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cjson/cJSON.h>
#include <dds/dds.h>

#include "palp_app.h"
#include "palp_assess.h"
#include "palp_coverage.h"
#include "palp_db.h"
#include "palp_dds.h"
#include "palp_dds_gate.h"
#include "palp_dds_origin.h"
#include "palp_dds_strays.h"
#include "palp_dds_refusals.h"
#include "palp_dds_security.h"
#include "palp_finding_answers.h"
#include "validate.h" /* palp_srv_validate_contact: what the server applies is what is logged (server/) */

#define MAX_PHANTOMS 64
/* A closed exercise session waits this long for its debrief (written just before the CLOSED
 * state, on another topic: the two can arrive in either order). */
#define DEBRIEF_WAIT DDS_SECS(1)
#define MAX_SESSIONS 1024
#define FINGERS 4
#define TAKE 64
/* A session's counts of what was not logged one by one (contacts refused or over its rate, findings
 * unanswered, refusals past FOLD_REFUSALS) become one event each this often: a trainee flooding her
 * own session (allowed, even secured) costs the shared queue a few records a second, not one per
 * sample, so other sessions keep theirs (as palp-server folds its counts, server/db_log.c). */
#define FOLD_NS 1000000000LL
#define FOLD_REFUSALS 8
/* A finger's contacts are logged at most one per tick of its session's rate, as the server applies
 * at most one per tick (server/session.c, play_out); a burst of this many ticks' worth passes (a
 * station's samples come in bunches), the newest over it is kept and logged at the next token. */
#define CONTACT_BURST 16.0
/* A new run of a server hands out its session ids again (server/server.c: from
 * PALP_DDS_ID(server_number, 1)): an OPEN state of a session already recorded is that session's only
 * if its run goes on: ticks and duration never fall within a run (the server's monotonic clock), and
 * a state from another writer whose session began more than this much later is another session. */
#define RESTART_GAP_NS 1000000000LL
/* A session's samples go to the session of the run that produced them (a server restarts). A server's
 * samples (feedback, deformation, local models, finger samples, finding status, debrief, exercise) are
 * that run's by their writer's participant, the participant of the run's state writer. A station's
 * (contacts, findings) by their writer: a station makes its writers as it joins a session, so a writer
 * taken as a session's station's stays that session's, and one of an ended session never becomes
 * another's (RETIRED_WRITERS). A sample whose run the recorder does not know yet is held, at most
 * HELD_WAIT_NS: a new run's, which can come before its OPEN state (palp-server answers the JOIN, then
 * writes the state; the trainee's first contacts race it, the run's finding status and exercise come
 * before both), until that state; a station writer's while the session's server has lapsed, or a second
 * station writer of the same topic (a station that joined again: the same run or a new one), until the
 * session's next state tells (the server writes one each second). Then it is logged in that state's
 * session, in the order the samples came, contacts at the rate they came (their arrival times). */
#define STATION_WRITERS 8
#define SERVER_WRITERS 16 /* a run writes a session's 8 server topics; a new run's 8 more before its state */
#define RETIRED_WRITERS 256
/* Runs of a session id that have ended, with their writers (ended_run): a late sample of one is dropped,
 * not held for a state that never comes. Up to 17 entries a session end (its run, its run's writers). */
#define ENDED_RUNS 2048
#define MAX_HELD 4096
#define HELD_BYTES_MAX (16 << 20) /* a deformation is a whole mesh: ~60 kB for the default dome */
#define HELD_WAIT_NS (RECORDER_SERVER_GRACE + DDS_SECS(1)) /* the old run's grace, and its new run's state */
/* A station sample held for a session id that came this much before the session opening for it began
 * (its OPEN state's duration back) is an earlier session's: a station joins a session after its server
 * made it. The margin: the state's own latency makes that start a little late. */
#define HELD_BEFORE_START_NS 250000000LL
/* A second station writer's samples held while nothing else says another run began (its session's server
 * not lapsed, no other run's samples held) are released this long after they came, not at the session's
 * next state: that comes at the server's status_rate_hz, which its config allows down to 0.1 Hz (below
 * ~0.17 Hz they expired at HELD_WAIT_NS and were dropped; below ~0.5 Hz a held finding was logged as
 * unanswered, PALP_FINDING_ANSWER_WAIT_S). A new run's OPEN state follows its station's JOIN within
 * milliseconds, and its own samples held would keep these held. */
#define SECOND_WRITER_WAIT_NS 1500000000LL

/* The readers, in the order a pass takes them: catalogue and state first, so that a session's samples
 * find it open; its exercise before its findings; the debrief last. The finger samples before the
 * local models: a session whose server sends them is logged from them from the first one on
 * (on_finger_sample). Those from RD_CONTACT on are the sessions' own, under the partition subscriber. */
enum { RD_CATALOGUE, RD_EXERCISE, RD_STATE, RD_SESSION_EXERCISE, RD_CONTACT, RD_FEEDBACK, RD_DEFORMATION,
       RD_FINGER_SAMPLE, RD_LOCAL_MODEL, RD_FINDING, RD_FINDING_STATUS, RD_DEBRIEF, RD_COUNT };

typedef struct phantom {
  uint32_t id;
  int used;
  char name[64];
  double tick_hz, max_force;
  int top_vertex;
  int n;
  palp_vec3 *rest;
  char *scene_json;
  /* its dome, for the footprint of a local model (palp_coverage_patch): the touched triangles are
   * not in a local model, how many there are is */
  palp_coverage *cov;
  int tri_count; /* the mesh's triangles, the ids a finger sample may name (with cov) */
  double radius;  /* the dome's [m], for the contact check's reach */
  int gone;       /* its catalogue instance was disposed or lost its writer: the slot is freed once no open
                     session holds it (at once, or when a new entry needs the slot) */
} phantom;

typedef struct rsession {
  uint32_t id;
  int open;
  palp_db_session h;
  uint32_t phantom_id;
  const phantom *ph; /* NULL while its catalogue entry has not come (on_phantom completes it) */
  char partition[64];
  double recorded_from; /* the session's age when the recorder first saw it [s] */
  int exercise_named;   /* its params name the exercise its phantom runs */
  int64_t frame;   /* newest frame seen from the server (feedback or deformation) */
  double t;        /* its simulated time [s] */
  uint8_t live[FINGERS];
  uint8_t kind[FINGERS];
  palp_vec3 force[FINGERS];
  uint8_t active[FINGERS];
  double volume, pressure, max_disp; /* from the newest deformation sample, 0 until one arrives */
  uint64_t mesh_hash; /* FNV-1a of the newest logged mesh's positions (0: none yet) */
  int held;           /* its open state says why it waits: its trainee station lost, the session held */
  /* Exercise sessions (session 60). */
  int exercise;       /* its exercise (with lesions) is logged */
  int debriefed;      /* its debrief is logged */
  double radius[FINGERS];       /* position-driven fingertips' radii [m], from their contact samples */
  int sample_every;             /* physics steps between finger samples (palp_assess_sample_every) */
  /* The server's own finger samples (palp_finger_sample, session 71), touched triangles named: once
   * one has come the session's samples are logged from them and no longer from the local models
   * (its params then say "footprint": "touched"). Frames logged so far per finger, either way. */
  int touched;
  int64_t sample_frame[FINGERS];
  palp_finding_answers marks; /* findings awaiting the server's answer, and answers their finding */
  int64_t findings_unanswered;
  int closing;                  /* CLOSED seen; ended when its debrief arrives or DEBRIEF_WAIT passes */
  int64_t closing_since;        /* palp_dds_now_ns() */
  palp_SessionState close_state;
  int64_t lost_since; /* its state's writer lapsed then (palp_dds_now_ns(); 0: alive); ended as lost RECORDER_SERVER_GRACE later */
  int64_t foreign; /* contacts and findings naming it from a writer outside its partition: not recorded */
  /* Its contacts' rate (CONTACT_BURST): a token bucket per finger at its tick rate; the newest contact
   * over it kept (pending) until a token comes. */
  double tick_hz;
  double tokens[FINGERS];
  int64_t tokens_ns[FINGERS];
  int has_pending[FINGERS];
  palp_srv_contact pending[FINGERS];
  /* Folded into one event each per FOLD_NS (fold_counts). */
  int64_t invalid[PALP_SRV_REJ_COUNT]; /* contacts the server's check refuses, by its reason */
  int64_t coalesced;                   /* contacts over the rate, replaced by a newer one before logged */
  int64_t unanswered;                  /* findings whose answer this recorder did not see, past FOLD_REFUSALS */
  int64_t refused_more;                /* refused findings past FOLD_REFUSALS */
  int refused_logged;                  /* refused and unanswered findings logged by name this interval */
  int64_t folded_ns;
  /* Its run, as its states tell it (RESTART_GAP_NS): a new run's OPEN state ends it. */
  double last_duration;
  uint64_t last_ticks;
  int64_t start_ns;                 /* palp_dds_now_ns() - its duration, at its first state */
  dds_instance_handle_t state_writer; /* of its states (0: not known) */
  dds_instance_handle_t run;          /* its state writer's participant: its server run (0: not known) */
  /* The server writers its samples came from, with each one's participant (its run): a known writer's
   * samples (local models up to 1 kHz) consult no cache (server_run_of); the oldest forgotten when full. */
  dds_instance_handle_t server_writer[SERVER_WRITERS], server_run[SERVER_WRITERS];
  int server_writers, server_next;
  /* Its station's contact and finding writers (RD_CONTACT, RD_FINDING), as taken (route_sample). */
  dds_instance_handle_t station_writer[STATION_WRITERS];
  uint8_t station_kind[STATION_WRITERS];
  int station_writers;
} rsession;

/* How long a session whose state's writer lapsed is kept open for its server to come back
 * [ns]: a server its machine stopped for a second or two lapses as a dead one does and
 * goes on with its sessions (docs/station.md, "A stalled server"); ended earlier, the
 * session was logged as ended `error` and its continuation as a second session. Longer
 * than the stations' 1 s wait: a recorder has no hand to answer. */
#define RECORDER_SERVER_GRACE DDS_SECS(5)

/* A session that opened before its phantom's catalogue entry arrived (the two topics race). */
typedef struct pending_open {
  int used;
  palp_SessionState state;
  dds_instance_handle_t writer, run; /* its state writer and that writer's participant */
  int64_t since;   /* palp_dds_now_ns() */
  int64_t seen_ns; /* palp_dds_now_ns() as its state was taken: its duration was its age then */
} pending_open;
#define MAX_PENDING 64
#define PENDING_WAIT DDS_SECS(2)

/* A session's exercise that arrived before the session's OPEN state (the two topics race), with the
 * server run that sent it and when: logged when that run opens the session within
 * PENDING_EXERCISE_WAIT, else dropped (on_session_exercise, open_session). */
typedef struct pending_exercise {
  uint32_t session_id;
  char name[64];
  char *json; /* checked: it parses as an exercise */
  int64_t since; /* palp_dds_now_ns() as it was taken */
  dds_instance_handle_t run; /* its writer's participant (server_run_of; 0: not known) */
} pending_exercise;
#define MAX_PENDING_EXERCISES 64
#define PENDING_EXERCISE_WAIT DDS_SECS(10)

/* What palp_exercise says a phantom runs (its public part: the name): a session on it whose
 * lesions never arrive is logged as that exercise's, without them (params_json "exercise_name"). */
typedef struct public_exercise {
  uint32_t phantom_id;
  char name[64];
} public_exercise;

/* A session sample whose run is not known yet (route_sample), a deep copy of it. */
typedef struct held_sample {
  int kind;                         /* RD_* */
  uint32_t session_id;
  dds_instance_handle_t writer;     /* its writer */
  dds_instance_handle_t run;        /* a server's sample: its writer's participant; 0 for a station's */
  int64_t arrival_ns;               /* palp_dds_now_ns() as it was taken */
  int historical;                   /* a finding status written before the readers were made */
  int from_known;                   /* a station's: its writer's partition is known, */
  char from[PALP_DDS_ORIGIN_PARTITION]; /* and is this (checked against the session it is logged in) */
  size_t bytes;
  void *sample;                     /* one block (held_copy) */
} held_sample;

/* A session's run that ended (set_open): its server's participant, and one of its writers (0: the run). */
typedef struct ended_run {
  uint32_t session_id;
  dds_instance_handle_t run, writer;
} ended_run;

typedef struct recorder {
  palp_db_writer *w;
  public_exercise pex[MAX_PHANTOMS];
  pending_exercise pending_ex[MAX_PENDING_EXERCISES];
  int64_t exercises_refused;
  pending_open pending[MAX_PENDING];
  phantom ph[MAX_PHANTOMS];
  rsession s[MAX_SESSIONS];
  int64_t unknown_session_samples, refused;
  uint64_t begins_refused; /* sessions not recorded: no slot, or the log refused their start (said) */
  int64_t phantoms_refused, phantoms_unkept; /* catalogue entries that failed phantom_ok; found no slot */
  palp_log *log;
  /* The sessions the stream readers' topic filters pass: those open here (slot = index in s[]) and
   * those heard open lately; a flood of made-up keys becomes no reader instance (idl/palp_dds_gate.h). */
  palp_dds_gate gate;
  /* Which partition each contact's and finding's writer writes in: a sample naming a session must
   * come from that session's partition (a trainee may write only in her own; idl/palp_dds_origin.h). */
  palp_dds_origin origin;
  int64_t foreign_samples;
  /* Disposes of finding keys of sessions never heard open: each an instance the findings reader keeps
   * while its writer lives (a dispose passes no filter); past a bound the reader is made anew. */
  int64_t finding_strays, finding_strays_total, finding_renewals;
  int64_t finding_renewed_ns, finding_renewal_said_ns;
  /* The same for the stream readers (RD_CONTACT .. RD_LOCAL_MODEL; is_stream), which also bound their
   * instances (reader_deep): disposes of keys the gate would not pass, and samples refused at the bound,
   * since each was made. With the bound alone a flood of disposes filled it while the disposing writer
   * lived, and every later session's contacts, feedback and finger data were refused (the session 81
   * review: 4,700 disposes, 0 of 100 contacts logged). Per reader, as each fills on its own. */
  int64_t stream_strays[RD_COUNT], stream_renewed_ns[RD_COUNT];
  uint32_t stream_refused_seen[RD_COUNT];
  int64_t stream_strays_total, stream_renewals, stream_renewal_said_ns;
  /* Samples held until their run is known (route_sample), in the order they came. */
  held_sample held[MAX_HELD];
  int nheld, releasing;
  size_t held_bytes;
  int64_t held_total, held_dropped;
  /* Station writers of ended sessions: what they still write is no session's (counted). */
  dds_instance_handle_t retired[RETIRED_WRITERS];
  int retired_next;
  int64_t ended_writer_samples;
  /* Runs (and their server writers) of sessions that ended here: a late sample of one is no session's. */
  ended_run ended[ENDED_RUNS];
  int ended_next;
  int64_t earlier_run_samples;
  /* Server samples whose writer's run was looked up in the origin cache (server_run_of): each writer's
   * first in its session, not each sample. */
  int64_t origin_consults;
  /* DDS's clock (the writers' source timestamps) as the readers were made: a finding status written
   * before it is the historical copy a reader is handed as it joins a running session, which answers
   * no finding this recorder saw (palp_finding_answers.h). */
  dds_time_t readers_since;
} recorder;

/* A session opens or ends in this log: its streams pass the gate as long as it is open here. Ended,
 * its station's writers are retired: a station writes a session's contacts and findings through
 * writers of that session, so what they write after its end is no session's. */
static void retire(recorder *r, dds_instance_handle_t w);

static void set_open(recorder *r, rsession *s, int open) {
  s->open = open;
  palp_dds_gate_set(&r->gate, (int)(s - r->s), open ? s->id : 0);
  if (open) return;
  /* Its run's writers by handle too: a late sample of a writer no longer matched has no known
   * participant (palp_dds_origin_participant: 0), and would otherwise be logged in the id's next session. */
  for (int i = -1; i < s->server_writers && s->run; i++) {
    if (i >= 0 && s->server_run[i] != s->run) continue; /* a new run's, held while this one ran */
    r->ended[r->ended_next] = (ended_run){.session_id = s->id, .run = s->run, .writer = i < 0 ? 0 : s->server_writer[i]};
    r->ended_next = (r->ended_next + 1) % ENDED_RUNS;
  }
  for (int i = 0; i < s->station_writers; i++) retire(r, s->station_writer[i]);
  s->station_writers = 0;
}

static atomic_int stop_flag, hup_flag; /* atomic: a signal may land on any thread (client/main.c) */
static void on_signal(int sig) {
  if (sig == SIGHUP) hup_flag = 1; /* log rotation: re-open --log-file in the main loop */
  else stop_flag = 1;
}

static double now_unix(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void count(recorder *r, int rc) {
  if (rc == PALP_EFULL) r->refused++;
}

/* A session's end into the log. The writer keeps a slot for each session's end (db/writer.c,
 * END_DETAIL_MAX): never refused for a full queue, as it was until session 81 (then kept here and
 * retried each pass). */
static void log_end(recorder *r, const rsession *s, palp_db_end_reason reason, const char *detail) {
  const int rc = palp_db_log_session_end(r->w, s->h, reason, detail, now_unix());
  count(r, rc);
  if (rc < 0) palp_log_error(r->log, "session %u: its end not logged: %s", s->id, palp_db_strerror(rc));
}

static int phantom_in_use(const recorder *r, const phantom *ph) {
  for (int i = 0; i < MAX_SESSIONS; i++)
    if (r->s[i].open && r->s[i].ph == ph) return 1;
  return 0;
}

static void phantom_free(phantom *ph) {
  free(ph->rest);
  free(ph->scene_json);
  palp_coverage_destroy(ph->cov);
  memset(ph, 0, sizeof *ph);
}

static phantom *find_phantom(recorder *r, uint32_t id, int create) {
  for (int i = 0; i < MAX_PHANTOMS; i++)
    if (r->ph[i].used && r->ph[i].id == id) return &r->ph[i];
  if (!create) return NULL;
  for (int i = 0; i < MAX_PHANTOMS; i++)
    if (!r->ph[i].used) {
      r->ph[i].used = 1;
      r->ph[i].id = id;
      return &r->ph[i];
    }
  /* all held: a gone phantom's slot that no open session holds any more */
  for (int i = 0; i < MAX_PHANTOMS; i++)
    if (r->ph[i].gone && !phantom_in_use(r, &r->ph[i])) {
      phantom_free(&r->ph[i]);
      r->ph[i].used = 1;
      r->ph[i].id = id;
      return &r->ph[i];
    }
  return NULL;
}

/* Its catalogue instance disposed (the phantom withdrawn) or without writers (its server gone): its
 * slot freed now if no open session holds it, else kept for them and taken when a slot is needed. A
 * server that comes back publishes its entry again. */
static void on_phantom_gone(recorder *r, uint32_t id) {
  phantom *ph = find_phantom(r, id, 0);
  if (!ph) return;
  if (phantom_in_use(r, ph)) ph->gone = 1;
  else phantom_free(ph);
}

static rsession *find_session(recorder *r, uint32_t id, int create) {
  rsession *free_slot = NULL;
  for (int i = 0; i < MAX_SESSIONS; i++) {
    if (r->s[i].open && r->s[i].id == id) return &r->s[i];
    if (!r->s[i].open && !free_slot) free_slot = &r->s[i];
  }
  return create ? free_slot : NULL;
}

/* The scene as far as the catalogue describes it: geometry, material, gel, effects, rate. */
static char *scene_from_catalogue(const palp_Phantom *p) {
  palp_scene sc;
  memset(&sc, 0, sizeof sc);
  snprintf(sc.name, sizeof sc.name, "%s", p->scene_name[0] ? p->scene_name : p->name);
  sc.world = palp_world_default_def();
  sc.world.mesh.radius = p->radius;
  sc.world.mesh.vertex_count = (int)p->rest._length;
  sc.world.membrane.thickness = p->membrane.thickness;
  sc.world.membrane.density = p->membrane.density;
  sc.world.membrane.E1 = p->membrane.E1;
  sc.world.membrane.eta1 = p->membrane.eta1;
  sc.world.membrane.E2 = p->membrane.E2;
  sc.world.membrane.eta2 = p->membrane.eta2;
  sc.world.gel.law = (palp_gel_law)p->gel.law;
  sc.world.gel.pressure = p->gel.pressure;
  sc.world.gel.a1 = p->gel.a1;
  sc.world.gel.a2 = p->gel.a2;
  sc.world.gel.a3 = p->gel.a3;
  sc.world.effects = p->effects;
  if (p->tick_rate_hz > 0) sc.world.dt = 1.0 / p->tick_rate_hz;
  sc.frames = 1;
  sc.frame_period = sc.world.dt;
  return palp_scene_to_json(&sc);
}

static const char *public_exercise_of(const recorder *r, uint32_t phantom_id);

/* The session's params as the log keeps them, from what the recorder knows now of its phantom (its
 * force limit) and of the exercise the phantom runs (its name); rewritten when either comes late. */
/* Built with cJSON, not by hand: the partition comes from the network (a quote in it made keys of
 * its own, "footprint" among them), and a number that is not finite is no JSON (left out). */
#define PARAMS_FALLBACK "{\"recorded_by\": \"palp-recorder\", \"replayable\": false}"
static char *session_params(const recorder *r, const rsession *s) {
  const char *pex = public_exercise_of(r, s->phantom_id);
  cJSON *o = cJSON_CreateObject();
  int ok = o && cJSON_AddStringToObject(o, "recorded_by", "palp-recorder") && cJSON_AddFalseToObject(o, "replayable") &&
           cJSON_AddStringToObject(o, "partition", s->partition);
  /* the limit only once its catalogue entry is here (it said 0 N before: a limit nobody set) */
  if (ok && s->ph && isfinite(s->ph->max_force)) ok = cJSON_AddNumberToObject(o, "max_force_n", s->ph->max_force) != NULL;
  if (ok) ok = cJSON_AddStringToObject(o, "footprint", s->touched ? "touched" : "patch") != NULL;
  if (ok && pex) ok = cJSON_AddStringToObject(o, "exercise_name", pex) != NULL;
  /* Started (or restarted) after the session opened: what came before is not in this log, and
   * the review says so (its marks, its coverage are this log's part of the session). A session
   * seen within a second of its opening counts as seen from its start. */
  if (ok && s->recorded_from > 1.0 && isfinite(s->recorded_from))
    ok = cJSON_AddNumberToObject(o, "recorded_from_s", round(s->recorded_from * 1e3) / 1e3) != NULL;
  char *json = ok ? cJSON_PrintUnformatted(o) : NULL;
  cJSON_Delete(o);
  return json;
}

static void log_params(recorder *r, rsession *s) {
  s->exercise_named = public_exercise_of(r, s->phantom_id) != NULL;
  char *params = session_params(r, s);
  count(r, palp_db_log_session_params(r->w, s->h, params ? params : PARAMS_FALLBACK));
  cJSON_free(params);
}

/* Sessions opened before their phantom's catalogue entry came (their samples forced the open: a
 * contact is not to be lost waiting): the entry, now here, gives their phantom's name and scene
 * to the log, which the review's metrics and replay read. */
static void complete_sessions(recorder *r, const phantom *ph, uint32_t phantom_id) {
  for (int i = 0; i < MAX_SESSIONS; i++) {
    rsession *s = &r->s[i];
    if (!s->open || s->ph || s->phantom_id != phantom_id || !ph->scene_json) continue;
    s->ph = ph;
    const int rc = palp_db_log_session_scene(r->w, s->h, ph->name, ph->scene_json);
    count(r, rc);
    log_params(r, s); /* its force limit, known now */
    palp_log_info(r->log, "session %u: phantom %u's catalogue entry came after the session: its scene logged now%s",
                  s->id, phantom_id, rc == 0 ? "" : " (refused: the log's queue is full)");
  }
}

/* A catalogue entry as the recorder may keep it: the stations' check (palp_dds_phantom_check: counts,
 * indices, finite rest positions and radius), and the numbers the session's params and scene carry
 * finite and in a server's range (tick rate 10..10,000 Hz as server/config.c allows; force limit >= 0). */
static int phantom_ok(const palp_Phantom *p, char *why, size_t len) {
  if (palp_dds_phantom_check(p, 1, why, len) < 0) return 0;
  const double nums[] = {p->tick_rate_hz, p->max_force, p->membrane.thickness, p->membrane.density, p->membrane.E1,
                         p->membrane.eta1, p->membrane.E2, p->membrane.eta2, p->gel.pressure, p->gel.a1, p->gel.a2,
                         p->gel.a3};
  for (size_t i = 0; i < sizeof nums / sizeof nums[0]; i++)
    if (!isfinite(nums[i])) {
      snprintf(why, len, "phantom %u: a number of its model is not finite", p->phantom_id);
      return 0;
    }
  if (!(p->tick_rate_hz >= 1.0 / PALP_WORLD_MAX_DT && p->tick_rate_hz <= 10000) || !(p->max_force >= 0)) {
    snprintf(why, len, "phantom %u: tick rate %g Hz, force limit %g N (want 10..10000 Hz, >= 0 N)", p->phantom_id,
             p->tick_rate_hz, p->max_force);
    return 0;
  }
  return 1;
}

static void on_phantom(recorder *r, const palp_Phantom *p) {
  char why[160];
  if (!phantom_ok(p, why, sizeof why)) {
    /* one it already keeps for that id stays (a session on it goes on with it) */
    r->phantoms_refused++;
    if (r->phantoms_refused <= 8 || r->phantoms_refused % 100 == 0) { /* a flood of them: a line every 100 */
      char name[4 * sizeof p->name];
      palp_log_warn(r->log, "catalogue entry \"%s\" refused (%lld so far): %s", palp_log_printable(p->name, name, sizeof name),
                    (long long)r->phantoms_refused, why);
    }
    return;
  }
  phantom *ph = find_phantom(r, p->phantom_id, 1);
  if (!ph) {
    if (r->phantoms_unkept++ == 0)
      palp_log_warn(r->log, "phantom %u's catalogue entry not kept: %d phantoms are held already (its sessions are "
                            "logged without their scene)", p->phantom_id, MAX_PHANTOMS);
    return;
  }
  ph->gone = 0;
  ph->radius = p->radius;
  snprintf(ph->name, sizeof ph->name, "%s", p->name);
  ph->tick_hz = p->tick_rate_hz;
  ph->max_force = p->max_force;
  ph->top_vertex = p->top_vertex;
  palp_vec3 *rest = realloc(ph->rest, sizeof *rest * (p->rest._length ? p->rest._length : 1));
  if (rest) {
    ph->rest = rest;
    ph->n = (int)p->rest._length;
    for (uint32_t i = 0; i < p->rest._length; i++)
      ph->rest[i] = (palp_vec3){p->rest._buffer[i].x, p->rest._buffer[i].y, p->rest._buffer[i].z};
  }
  free(ph->scene_json);
  ph->scene_json = scene_from_catalogue(p);
  /* Checked as it is built (indices in range, the dome's triangles first): a catalogue it refuses
   * leaves the footprint a disc of the contact's area. */
  palp_coverage_destroy(ph->cov);
  ph->cov = NULL;
  double *xyz = malloc(sizeof *xyz * 3 * (p->rest._length ? p->rest._length : 1));
  if (xyz && p->rest._length && p->triangles._length % 3 == 0) {
    for (uint32_t i = 0; i < p->rest._length; i++)
      xyz[3 * i] = p->rest._buffer[i].x, xyz[3 * i + 1] = p->rest._buffer[i].y, xyz[3 * i + 2] = p->rest._buffer[i].z;
    int rc;
    ph->cov = palp_coverage_create(xyz, (int)p->rest._length, p->triangles._buffer, (int)(p->triangles._length / 3),
                                   p->dome_triangle_count, &rc);
    ph->tri_count = (int)(p->triangles._length / 3);
  }
  free(xyz);
  complete_sessions(r, ph, p->phantom_id);
}

static void log_exercise(recorder *r, rsession *s, const char *name, const char *json) {
  if (s->exercise) return; /* transient-local re-delivery */
  const int rc = palp_db_log_exercise(r->w, s->h, name, json);
  count(r, rc);
  if (rc == 0) s->exercise = 1;
  else palp_log_error(r->log, "session %u: its exercise not logged: %s", s->id, palp_db_strerror(rc));
}

/* An exercise session's exercise, lesions included: checked as an exercise file is (it comes
 * from the network), then logged with its session, or kept until the session opens. run: its
 * writer's participant (0: not known). */
static void on_session_exercise(recorder *r, const palp_SessionExercise *m, dds_instance_handle_t run) {
  char name[64], err[256];
  snprintf(name, sizeof name, "%s", m->name);
  palp_exercise *ex = malloc(sizeof *ex);
  snprintf(err, sizeof err, "out of memory");
  const int rc = ex ? palp_exercise_parse(m->json, NULL, ex, err, sizeof err) : PALP_ENOMEM;
  const int named = ex && rc == 0 && strcmp(ex->name, name) == 0;
  free(ex);
  if (rc < 0 || !named) {
    r->exercises_refused++;
    palp_log_warn(r->log, "session %u: its exercise \"%s\" refused: %s", m->session_id, PALP_PRINTABLE(name),
                  rc < 0 ? PALP_PRINTABLE_LONG(err) : "its name is not the exercise's own");
    return;
  }
  rsession *s = find_session(r, m->session_id, 0);
  if (s) {
    log_exercise(r, s, name, m->json);
    return;
  }
  /* Until 2026-12-07 the first waiting entry of a session id won whatever its age and sender: another
   * participant's exercise for id 7, or one left 12 s from an earlier run, was logged when the session
   * opened, and the session's own, coming next, dropped as "re-delivered". Now the expired go first,
   * the same run's again is a re-delivery, and another run's replaces it (the newest run's is the one
   * whose session is about to open; open_session checks the run again). */
  const int64_t now = palp_dds_now_ns();
  pending_exercise *slot = NULL;
  for (int i = 0; i < MAX_PENDING_EXERCISES; i++) {
    pending_exercise *pe = &r->pending_ex[i];
    if (pe->json && now - pe->since > PENDING_EXERCISE_WAIT) { /* its session never opened here */
      free(pe->json);
      memset(pe, 0, sizeof *pe);
    }
    if (pe->json && pe->session_id == m->session_id) {
      if (pe->run == run) return; /* re-delivered (transient-local) */
      palp_log_warn(r->log, "session %u: exercise \"%s\" from another participant replaces \"%s\", which waited for "
                            "the session to open", m->session_id, PALP_PRINTABLE(name), PALP_PRINTABLE(pe->name));
      free(pe->json);
      memset(pe, 0, sizeof *pe);
    }
    if (!pe->json && !slot) slot = pe;
  }
  char *json = slot ? strdup(m->json) : NULL;
  if (!json) {
    palp_log_warn(r->log, "session %u: its exercise arrived before the session and could not be kept", m->session_id);
    return;
  }
  *slot = (pending_exercise){.session_id = m->session_id, .json = json, .since = now, .run = run};
  snprintf(slot->name, sizeof slot->name, "%s", name);
}

/* The exercise a catalogue phantom runs, by name. Only names of letters, digits and "-_." are
 * kept: the name goes into params_json as it is. */
static void on_public_exercise(recorder *r, const palp_Exercise *m) {
  const size_t n = strnlen(m->name, sizeof m->name);
  if (n == 0 || n >= sizeof m->name || strspn(m->name, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_.") != n)
    return;
  public_exercise *slot = NULL;
  for (int i = 0; i < MAX_PHANTOMS; i++) {
    if (r->pex[i].name[0] && r->pex[i].phantom_id == m->phantom_id) {
      slot = &r->pex[i];
      break;
    }
    if (!r->pex[i].name[0] && !slot) slot = &r->pex[i];
  }
  if (!slot) return;
  slot->phantom_id = m->phantom_id;
  snprintf(slot->name, sizeof slot->name, "%s", m->name);
  /* A session on this phantom opened before this came, and without its lesions (they stay on the
   * server): its params name the exercise now, so that its review says which it was. */
  for (int i = 0; i < MAX_SESSIONS; i++) {
    rsession *s = &r->s[i];
    if (!s->open || s->exercise || s->exercise_named || s->phantom_id != m->phantom_id) continue;
    log_params(r, s);
    palp_log_info(r->log, "session %u: the exercise its phantom runs (%s) came after the session: named now", s->id,
                  slot->name);
  }
}

static const char *public_exercise_of(const recorder *r, uint32_t phantom_id) {
  for (int i = 0; i < MAX_PHANTOMS; i++)
    if (r->pex[i].name[0] && r->pex[i].phantom_id == phantom_id) return r->pex[i].name;
  return NULL;
}

static int64_t held_since(const recorder *r, uint32_t session_id);
static void release_held(recorder *r, uint32_t session_id, const char *why);

/* writer: its state's writer, run: that writer's participant (0: not known). */
static int station_topic(int kind);

/* A session the recorder cannot record, said (the first 8, then every 100th) and counted for the stop
 * line: until session 90 it went unrecorded without a word, its samples filtered out as of no open
 * session (found by review). */
static void not_recorded(recorder *r, const palp_SessionState *m, const char *why) {
  r->begins_refused++;
  if (r->begins_refused <= 8 || r->begins_refused % 100 == 0)
    palp_log_warn(r->log, "session %u (trainee \"%s\", phantom %u): not recorded: %s (%llu sessions not recorded "
                  "so far)", m->session_id, PALP_PRINTABLE(m->trainee_name), m->phantom_id, why,
                  (unsigned long long)r->begins_refused);
}

/* seen_ns: palp_dds_now_ns() as the state was taken. */
static void open_session(recorder *r, const palp_SessionState *m, dds_instance_handle_t writer,
                         dds_instance_handle_t run, int64_t seen_ns) {
  rsession *s = find_session(r, m->session_id, 1);
  {
    if (!s) { /* every slot holds an open session */
      char why[64];
      snprintf(why, sizeof why, "all %d session slots are open", MAX_SESSIONS);
      not_recorded(r, m, why);
      return;
    }
    if (s->open) return; /* already recording (transient-local re-delivery) */
    const phantom *ph = find_phantom(r, m->phantom_id, 0);
    /* a duration that is no wall time (not finite, negative, absurd) counts as 0 */
    const double age = isfinite(m->duration) && m->duration >= 0 && m->duration < 1e9 ? m->duration : 0;
    const double start = now_unix() - age;
    char uid[128], pid[32];
    /* Session ids restart with each server run: the start time makes the uid unique. */
    snprintf(uid, sizeof uid, "dds-%u-%u-%.0f", m->phantom_id, m->session_id, start * 1e3);
    snprintf(pid, sizeof pid, "%u", m->phantom_id);
    memset(s, 0, sizeof *s);
    s->phantom_id = m->phantom_id;
    s->ph = ph;
    snprintf(s->partition, sizeof s->partition, "%s", m->partition);
    s->recorded_from = age;
    s->exercise_named = public_exercise_of(r, m->phantom_id) != NULL;
    /* its rate as the server's config allows it (10..10,000 Hz), else the haptic 1 kHz */
    const double hz = m->tick_rate_hz >= 1 && m->tick_rate_hz <= 10000 ? m->tick_rate_hz : 1000;
    char *params = session_params(r, s);
    palp_db_session_def d = {.uid = uid, .trainee = m->trainee_name, .station = m->trainee_station,
                             .phantom_id = pid, .phantom_name = ph ? ph->name : "",
                             .scene_json = ph && ph->scene_json ? ph->scene_json : "{}",
                             .params_json = params ? params : PARAMS_FALLBACK, .tick_hz = hz, .dt_s = 1.0 / hz,
                             .start_unix_s = start};
    const int begun = palp_db_log_session_begin(r->w, &d, &s->h);
    cJSON_free(params);
    if (begun != 0) {
      char why[96];
      snprintf(why, sizeof why, "the session log refused its start (%s)", palp_strerror(begun));
      not_recorded(r, m, why);
      return;
    }
    s->id = m->session_id;
    s->tick_hz = hz;
    s->last_duration = m->duration;
    s->last_ticks = m->ticks;
    s->start_ns = seen_ns - (int64_t)(age * 1e9);
  /* A station writer whose samples were held for this id (its server lapsed) since before this session
   * began is an earlier session's station's (a writer it made while its server was gone, or its second):
   * taken as this one's, its samples were logged here and the station's later ones too. Retired, its held
   * samples are dropped at the release (counted) as an ended session's. */
  for (int i = 0; i < r->nheld; i++) {
    const held_sample *h = &r->held[i];
    if (h->session_id == m->session_id && station_topic(h->kind) && h->arrival_ns < s->start_ns - HELD_BEFORE_START_NS)
      retire(r, h->writer);
  }
    s->state_writer = writer;
    s->run = run;
    s->folded_ns = palp_dds_now_ns();
    /* Its contacts held before this state are logged at the times they came (release_held): the
     * buckets start from the first of them, as they would have, had the state come first. */
    const int64_t first = held_since(r, m->session_id);
    for (int f = 0; f < FINGERS; f++)
      s->tokens[f] = CONTACT_BURST, s->tokens_ns[f] = first < s->folded_ns ? first : s->folded_ns;
    set_open(r, s, 1);
    if (!ph)
      palp_log_warn(r->log, "session %u: recording before phantom %u's catalogue entry came (its samples would "
                            "otherwise be lost); its scene is logged when the entry comes",
                    m->session_id, m->phantom_id);
    s->sample_every = palp_assess_sample_every(d.tick_hz, PALP_ASSESS_SAMPLE_HZ);
    char detail[160];
    snprintf(detail, sizeof detail, "%s joined as trainee from %s", m->trainee_name, m->trainee_station);
    count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_JOIN, -1, detail, 1));
    palp_log_info(r->log, "recording session %u as %s", m->session_id, uid);
    /* The exercise that waited for it, if it came within PENDING_EXERCISE_WAIT of the state and from
     * the run whose state opens it (a run not known on either side: the age alone decides). */
    for (int i = 0; i < MAX_PENDING_EXERCISES; i++) {
      pending_exercise *pe = &r->pending_ex[i];
      if (!pe->json || pe->session_id != m->session_id) continue;
      const int64_t waited = seen_ns - pe->since;
      if (waited > PENDING_EXERCISE_WAIT)
        palp_log_warn(r->log, "session %u: exercise \"%s\" not logged: it came %.1f s before the session opened (an "
                              "earlier session's; the wait is %.0f s)", m->session_id, PALP_PRINTABLE(pe->name),
                      (double)waited * 1e-9, (double)PENDING_EXERCISE_WAIT * 1e-9);
      else if (pe->run && run && pe->run != run)
        palp_log_warn(r->log, "session %u: exercise \"%s\" not logged: it came from another participant than the "
                              "server run that opened the session", m->session_id, PALP_PRINTABLE(pe->name));
      else log_exercise(r, s, pe->name, pe->json);
      free(pe->json);
      memset(pe, 0, sizeof *pe);
    }
  }
}

/* Opens pending sessions whose phantom is now known, that waited long enough, or (force) whose
 * samples are arriving. */
static void resolve_pending(recorder *r, uint32_t session_id, int force) {
  const int64_t now = palp_dds_now_ns();
  for (int i = 0; i < MAX_PENDING; i++) {
    pending_open *p = &r->pending[i];
    if (!p->used) continue;
    if (find_phantom(r, p->state.phantom_id, 0) || now - p->since > PENDING_WAIT ||
        (force && p->state.session_id == session_id)) {
      p->used = 0;
      open_session(r, &p->state, p->writer, p->run, p->seen_ns);
      release_held(r, p->state.session_id, "its state came");
    }
  }
}

static void settle_findings(recorder *r, rsession *s, int all);
static void close_session(recorder *r, rsession *s, const palp_SessionState *m);

/* An open session's state carries a reason only while the server holds it for its lost
 * trainee station (station_grace, docs/server.md): logged as that station's leave, and
 * its return as a join, as the server's own log has them. */
static void note_held(recorder *r, rsession *s, const palp_SessionState *m) {
  const int held = m->reason[0] != 0;
  if (!s->open || held == s->held) return;
  s->held = held;
  char detail[192];
  snprintf(detail, sizeof detail, "%.80s%s", m->trainee_station,
           held ? PALP_DB_DETAIL_TRAINEE_HELD : PALP_DB_DETAIL_TRAINEE_BACK);
  count(r, palp_db_log_event(r->w, s->h, held ? PALP_DB_EVENT_LEAVE : PALP_DB_EVENT_JOIN, s->frame, detail, 1));
}

static void fold_counts(recorder *r, rsession *s, int64_t now_ns, int all);
static void flush_contacts(recorder *r, rsession *s, int64_t now_ns, int all);

/* What a session still holds back, written before it ends: its unanswered findings, its pending
 * contacts and its folded counts. */
static void settle_all(recorder *r, rsession *s) {
  settle_findings(r, s, 1);
  flush_contacts(r, s, 0, 1);
  fold_counts(r, s, palp_dds_now_ns(), 1);
}

/* Ends a session in this log as cut short (why: its detail), its counts first. */
/* The samples forged into the session (someone else's writer naming it), as one event before its end:
 * the review then says this copy was written into by someone else. At every end, not only a CLOSED
 * state's: until session 90 a session the recorder's stop, a lost server or a restart ended kept no
 * sign of them (found by review). */
static void log_foreign(recorder *r, rsession *s) {
  if (s->foreign)
    count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_REJECT, s->frame,
                               "contacts and findings naming this session from a writer outside its partition, "
                               "not recorded (someone forged its session id)",
                               s->foreign));
}

static void end_cut(recorder *r, rsession *s, const char *why) {
  settle_all(r, s);
  log_foreign(r, s);
  count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_LEAVE, s->frame, why, 1));
  log_end(r, s, PALP_DB_END_ERROR, why);
  set_open(r, s, 0);
  s->lost_since = 0;
}

/* Whether an open session's state comes from a new run of its server, which hands out the same ids
 * again (RESTART_GAP_NS): its ticks or its duration fell, or another writer's session began more than
 * RESTART_GAP_NS after this one. A server stalled and back (the same run) passes: its clock ran on. */
static int new_run(const rsession *s, const palp_SessionState *m, dds_instance_handle_t writer, int64_t now_ns) {
  if (m->ticks < s->last_ticks || m->duration < s->last_duration) return 1;
  /* The state last seen, again: a server stalled past its lease and rediscovered (its writer a new
   * handle here) re-delivers its last state before its clock runs on; a new run's first state is
   * never the old run's to the tick and the nanosecond once that one has stepped (session 77:
   * server_paused, now and then; at tick 0 both runs' first states may read 0 s, 0 ticks). */
  if (s->last_ticks > 0 && m->ticks == s->last_ticks && m->duration == s->last_duration) return 0;
  if (!writer || !s->state_writer || writer == s->state_writer || !isfinite(m->duration)) return 0;
  return now_ns - (int64_t)(m->duration * 1e9) - s->start_ns > RESTART_GAP_NS;
}

/* A state of a session recorded here: a new run of its server ends it (error, saying so), and the
 * state is then a new session's; else its run's newest figures are kept. 1: ended. */
static int check_run(recorder *r, rsession *s, const palp_SessionState *m, dds_instance_handle_t writer,
                     dds_instance_handle_t run) {
  const int64_t now_ns = palp_dds_now_ns();
  if (new_run(s, m, writer, now_ns)) {
    char why[200];
    snprintf(why, sizeof why,
             "server restarted: session %u's state began again (%.3f s, %llu ticks after %.3f s, %llu ticks); "
             "the new run's session %u is logged as another session",
             s->id, m->duration, (unsigned long long)m->ticks, s->last_duration, (unsigned long long)s->last_ticks,
             m->session_id);
    palp_log_warn(r->log, "session %u: %s", s->id, why);
    end_cut(r, s, why);
    return 1;
  }
  if (writer) s->state_writer = writer;
  if (run) s->run = run;
  if (isfinite(m->duration)) s->last_duration = m->duration;
  s->last_ticks = m->ticks;
  return 0;
}

/* writer: the state's writer, run: that writer's participant (0: not known). What was held for the
 * session is logged in the session this state leaves open (release_held, here before a close, and
 * after each state in the main loop). */
static void on_state(recorder *r, const palp_SessionState *m, dds_instance_handle_t writer, dds_instance_handle_t run) {
  const int64_t seen_ns = palp_dds_now_ns();
  rsession *was = find_session(r, m->session_id, 0);
  if (was && check_run(r, was, m, writer, run)) {
    if (m->phase != palp_PHASE_OPEN) /* the new run's session opened and closed before its state was seen open */
      open_session(r, m, writer, run, seen_ns);
  }
  if (m->phase == palp_PHASE_OPEN) {
    rsession *known = find_session(r, m->session_id, 0);
    if (known) {
      if (known->lost_since) {
        known->lost_since = 0;
        palp_log_info(r->log, "session %u: its server is back; recording goes on", m->session_id);
      }
      note_held(r, known, m);
      return;
    }
    if (!find_phantom(r, m->phantom_id, 0)) { /* wait (briefly) for its catalogue entry */
      for (int i = 0; i < MAX_PENDING; i++) {
        if (r->pending[i].used && r->pending[i].state.session_id == m->session_id) return;
      }
      for (int i = 0; i < MAX_PENDING; i++)
        if (!r->pending[i].used) {
          r->pending[i].used = 1;
          r->pending[i].state = *m; /* fixed-size strings: a plain copy */
          r->pending[i].writer = writer;
          r->pending[i].run = run;
          r->pending[i].since = seen_ns;
          r->pending[i].seen_ns = seen_ns;
          return;
        }
    }
    open_session(r, m, writer, run, seen_ns);
    return;
  }
  resolve_pending(r, m->session_id, 1); /* opened and closed before its catalogue arrived */
  rsession *s = find_session(r, m->session_id, 0);
  if (!s || !s->open || s->closing) return;
  release_held(r, m->session_id, "its state came"); /* this run's, before it ends */
  if (s->exercise && !s->debriefed) { /* its debrief may still be on its way (DEBRIEF_WAIT) */
    s->closing = 1;
    s->closing_since = palp_dds_now_ns();
    s->close_state = *m;
    return;
  }
  close_session(r, s, m);
}

static void close_session(recorder *r, rsession *s, const palp_SessionState *m) {
  settle_all(r, s);
  if (m->rejected_samples)
    count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_REJECT, s->frame, "samples rejected by the server",
                               (int64_t)m->rejected_samples));
  if (m->overruns)
    count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_OVERRUN, s->frame, "tick overruns reported by the server",
                               (int64_t)m->overruns));
  log_foreign(r, s);
  count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_LEAVE, s->frame, m->reason, 1));
  log_end(r, s, palp_db_end_reason_of(m->reason), m->reason);
  palp_log_info(r->log, "session %u closed (%s)", m->session_id, PALP_PRINTABLE_LONG(m->reason));
  set_open(r, s, 0);
}

/* Closed exercise sessions whose debrief arrived, or did not within DEBRIEF_WAIT. */
static void end_closing_sessions(recorder *r, int64_t now) {
  for (int i = 0; i < MAX_SESSIONS; i++) {
    rsession *s = &r->s[i];
    if (s->open && s->closing && (s->debriefed || now - s->closing_since >= DEBRIEF_WAIT))
      close_session(r, s, &s->close_state);
  }
}

/* A session state whose writer is gone: its server died (several servers on one
 * domain: the others go on). The server can no longer close it, so the recorder
 * does, rather than leaving it "(running)" for ever. */
static void on_state_lost(recorder *r, const palp_SessionState *key) {
  /* The key comes from the invalid sample itself (Cyclone fills its key fields):
   * once that sample is taken the not-alive instance may be gone, and
   * dds_instance_get_key with it (a dead server's session then stayed "running"). */
  rsession *s = find_session(r, key->session_id, 0);
  if (!s || !s->open || s->lost_since) return;
  s->lost_since = palp_dds_now_ns();
  palp_log_warn(r->log, "session %u: its server's state lapsed; kept open %.0f s for the server to come back",
                key->session_id, (double)RECORDER_SERVER_GRACE * 1e-9);
}

/* Sessions whose server did not come back within RECORDER_SERVER_GRACE: ended as lost. */
static void end_lost_sessions(recorder *r, int64_t now) {
  for (int i = 0; i < MAX_SESSIONS; i++) {
    rsession *s = &r->s[i];
    if (!s->open || !s->lost_since || now - s->lost_since < RECORDER_SERVER_GRACE) continue;
    const char *why = "server lost (its session state's writer is gone)";
    palp_log_warn(r->log, "session %u: %s", s->id, why);
    end_cut(r, s, why);
  }
}

/* ---- findings: a mark counts as the server answered it --------------------------------
 * Paired as src/palp_finding_answers.h says: a finding is logged when its answer is seen, accepted
 * as a finding record, refused as a `reject` event, as the server's own log has them; one whose
 * answer was replaced (keep-last 1) or not seen within PALP_FINDING_ANSWER_WAIT_S is logged as an
 * unanswered event and not counted. */
typedef struct verdict_ctx {
  recorder *r;
  rsession *s;
} verdict_ctx;

static void log_verdict(void *ctx, const palp_finding_sent *f, int verdict, const char *reason) {
  recorder *r = ((verdict_ctx *)ctx)->r;
  rsession *s = ((verdict_ctx *)ctx)->s;
  char detail[200];
  if (verdict == PALP_VERDICT_ACCEPTED) {
    const palp_db_finding rec = {.mark_id = f->mark_id,
                                 .op = f->withdraw ? PALP_DB_FINDING_WITHDRAW : PALP_DB_FINDING_MARK,
                                 .frame = s->frame,
                                 .sim_time_s = s->t,
                                 .point_m = f->withdraw ? (palp_vec3){0, 0, 0} : f->point};
    count(r, palp_db_log_finding(r->w, s->h, &rec));
    return;
  }
  if (verdict != PALP_VERDICT_REFUSED) s->findings_unanswered++;
  /* As palp-server logs refusals: the first FOLD_REFUSALS an interval by name, the rest counted (a
   * flood of findings evicts one unanswered finding per finding past PALP_FINDING_ANSWERS_PENDING). */
  if (s->refused_logged >= FOLD_REFUSALS) {
    if (verdict == PALP_VERDICT_REFUSED) s->refused_more++;
    else s->unanswered++;
    return;
  }
  s->refused_logged++;
  if (verdict == PALP_VERDICT_REFUSED)
    snprintf(detail, sizeof detail, "finding %u refused: %s", f->mark_id, reason);
  else
    snprintf(detail, sizeof detail, "finding %u (%s) not logged: the recorder did not see the server's answer",
             f->mark_id, f->withdraw ? "withdrawal" : "mark");
  count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_REJECT, s->frame, detail, 1));
}

/* Findings and answers older than the wait (all: the session ends) are given up. */
static void settle_findings(recorder *r, rsession *s, int all) {
  verdict_ctx v = {r, s};
  palp_finding_answers_settle(&s->marks, (double)palp_dds_now_ns() * 1e-9, PALP_FINDING_ANSWER_WAIT_S, all, log_verdict, &v);
}

static void on_finding(recorder *r, const palp_Finding *m) {
  rsession *s = find_session(r, m->session_id, 0);
  if (!s) {
    r->unknown_session_samples++;
    return;
  }
  palp_finding_sent f;
  palp_dds_finding_sent(m, &f);
  verdict_ctx v = {r, s};
  palp_finding_answers_finding(&s->marks, &f, (double)palp_dds_now_ns() * 1e-9, log_verdict, &v);
}

static void on_finding_status(recorder *r, const palp_FindingStatus *m, int historical) {
  rsession *s = find_session(r, m->session_id, 0);
  if (!s) return;
  verdict_ctx v = {r, s};
  palp_finding_answers_answer(&s->marks, m->last_mark_id, m->last_accepted, m->reason, m->marks, historical,
                              (double)palp_dds_now_ns() * 1e-9, log_verdict, &v);
}

/* What the trainee was told as the session closed, logged as the server logs it (db/debrief.c);
 * one that contradicts itself is refused. */
static void on_debrief(recorder *r, const palp_Debrief *m) {
  rsession *s = find_session(r, m->session_id, 0);
  if (!s || s->debriefed) return;
  settle_findings(r, s, 0); /* the marks before what was told of them */
  palp_db_debrief d = {.sent = 1,
                       .level = (palp_db_debrief_level)m->level,
                       .lesions = (int)m->lesions,
                       .found = (int)m->found,
                       .marks = (int)m->marks,
                       .false_marks = (int)m->false_marks,
                       .duplicates = (int)m->duplicates};
  if (m->level == palp_DEBRIEF_LESIONS)
    for (uint32_t i = 0; i < m->lesion._length && i < PALP_DB_DEBRIEF_MAX_LESIONS; i++)
      d.found_by[d.listed++] = m->lesion._buffer[i].found_by;
  char detail[400];
  if ((unsigned)m->level > palp_DEBRIEF_LESIONS || palp_db_debrief_format(&d, detail, sizeof detail) < 0) {
    palp_log_warn(r->log, "session %u: its debrief contradicts itself; not logged", s->id);
    return;
  }
  count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_DEBRIEF, s->frame, detail, 1));
  s->debriefed = 1;
}

/* A finger sample into the log, from a local model or the server's own finger sample: its numbers
 * checked finite first (a sample the server cannot have meant is not logged), then logged for finger
 * f at frame, frames only rising per finger. v: device, proxy, force, contact point. 1 if logged. */
static int log_finger_sample(recorder *r, rsession *s, int f, int64_t frame, double time, double radius,
                              const palp_Vec3 v[4], double area, int in_contact, int tri_n, const int32_t *tri) {
  if (!isfinite(time) || !isfinite(radius) || !isfinite(area)) return 0;
  for (int k = 0; k < 4; k++)
    if (!isfinite(v[k].x) || !isfinite(v[k].y) || !isfinite(v[k].z)) return 0;
  if (frame <= s->sample_frame[f]) return 0;
  s->sample_frame[f] = frame;
  const palp_db_finger_sample fs = {.frame = frame,
                                    .sim_time_s = time,
                                    .slot = f,
                                    .radius_m = radius,
                                    .device_m = {v[0].x, v[0].y, v[0].z},
                                    .proxy_m = {v[1].x, v[1].y, v[1].z},
                                    .force_n = {v[2].x, v[2].y, v[2].z},
                                    .in_contact = in_contact,
                                    .point_m = {v[3].x, v[3].y, v[3].z},
                                    .area_m2 = area > 0 ? area : 0,
                                    .triangle_count = tri_n,
                                    .triangles = tri_n > 0 ? tri : NULL};
  count(r, palp_db_log_finger_sample(r->w, s->h, &fs));
  return 1;
}

/* The local models the server streams to the station are the fingertip's state each physics
 * step: logged as finger samples at the assessment's rate, as the server logs them, where the server
 * sends no finger samples of its own (a server older than session 71: on_finger_sample below). The
 * touched triangles are not in a local model, how many there are is: the sample's triangles are that
 * many under the fingertip (palp_coverage_patch, the rule palp-web's and the stations' coverage marked
 * by before session 71; the session's params say "footprint": "patch", and the review says so).
 * Without a count or the phantom's mesh, none: the review then takes a disc of the contact's area
 * (palp_assess). */
static void on_local_model(recorder *r, const palp_LocalModel *m) {
  rsession *s = find_session(r, m->session_id, 0);
  if (!s || m->finger >= FINGERS) {
    r->unknown_session_samples++;
    return;
  }
  const int f = m->finger;
  const int64_t frame = (int64_t)m->frame;
  /* the server's rule (server/db_log.c): every sample_every-th frame of the world */
  const int every = s->sample_every > 0 ? s->sample_every : 1;
  if (s->touched || frame % every != 0 || !(s->radius[f] > 0) || s->kind[f] != PALP_DB_KIND_FINGER) return;
  const palp_Vec3 v[4] = {m->device, m->proxy, m->force, m->point};
  int32_t patch[PALP_COVERAGE_TRIANGLES_MAX];
  int n = 0;
  if (m->in_contact && m->triangles > 0 && s->ph && s->ph->cov) {
    const double proxy[3] = {m->proxy.x, m->proxy.y, m->proxy.z};
    n = palp_coverage_patch(s->ph->cov, proxy, m->triangles, patch);
  }
  (void)log_finger_sample(r, s, f, frame, m->time, s->radius[f], v, m->area, m->in_contact != 0, n, patch);
}

/* The server's finger samples (palp_finger_sample, session 71): what its own log keeps, the touched
 * triangles named, so that this log's coverage is the server log's. Checked: finger, finite numbers,
 * a frame after the last logged for that finger, every id a triangle of the phantom's mesh (a sample
 * naming one that is not is refused whole). The first one turns the session's footprint to
 * "touched": its local models are no longer logged. */
static void on_finger_sample(recorder *r, const palp_FingerSample *m) {
  rsession *s = find_session(r, m->session_id, 0);
  if (!s || m->finger >= FINGERS) {
    r->unknown_session_samples++;
    return;
  }
  const int f = m->finger;
  if (!palp_dds_finger_sample_ok(m, s->ph && s->ph->cov ? s->ph->tri_count : INT32_MAX)) return;
  const palp_Vec3 v[4] = {m->device, m->proxy, m->force, m->point};
  if (log_finger_sample(r, s, f, (int64_t)m->frame, m->time, m->radius, v, m->area, m->in_contact != 0,
                        (int)m->triangles._length, m->triangles._buffer) &&
      !s->touched) {
    s->touched = 1;
    log_params(r, s); /* "footprint": "touched" */
  }
}

/* Whether a contact or finding naming an open session came from a writer in that session's partition
 * (v: palp_dds_origin_check against it; from: the writer's partition, NULL when unknown): a trainee's
 * permissions let her write in her own partitions only, so one naming another trainee's session there
 * forges it (not recorded, said once per session). A sample of a session not open here passes on, for
 * its handler to count. */
static int from_its_partition(recorder *r, uint32_t sid, palp_dds_origin_verdict v, const char *from, const char *what) {
  rsession *s = find_session(r, sid, 0);
  if (!s || !s->partition[0]) return 1;
  if (v == PALP_DDS_ORIGIN_SAME) return 1;
  r->foreign_samples++;
  if (s->foreign++ == 0) {
    if (v == PALP_DDS_ORIGIN_UNKNOWN) from = NULL;
    char where[320];
    if (!from) snprintf(where, sizeof where, "no longer matched (its partition unknown)");
    else if (!from[0]) snprintf(where, sizeof where, "in several or no partitions");
    else snprintf(where, sizeof where, "in partition %s", PALP_PRINTABLE(from)); /* a writer's: anyone's */
    palp_log_warn(r->log,
                  "session %u: a %s naming it came from a writer %s, not its partition %s: not recorded, nor any "
                  "such sample of it (counted at its end; someone forges its session id)",
                  sid, what, where, PALP_PRINTABLE(s->partition));
  }
  return 0;
}

/* A checked contact into the log, as the server's log has it: a switch of mode removes the finger's
 * contact first (the server replaces it), a release removes it. */
static void log_contact(recorder *r, rsession *s, const palp_srv_contact *v) {
  const int f = v->finger;
  palp_db_contact c;
  memset(&c, 0, sizeof c);
  c.frame = s->frame;
  c.sim_time_s = s->t;
  c.slot = f;
  if (v->mode == palp_CONTACT_RELEASE) {
    if (!s->live[f]) return;
    c.op = PALP_DB_OP_REMOVE;
    c.kind = s->kind[f];
    s->live[f] = 0;
    count(r, palp_db_log_contact(r->w, s->h, &c));
    return;
  }
  const int kind = v->mode == palp_CONTACT_FORCE ? PALP_DB_KIND_FORCE : PALP_DB_KIND_FINGER;
  if (s->live[f] && s->kind[f] != kind) { /* switched mode: the server replaces the contact */
    palp_db_contact rm = c;
    rm.op = PALP_DB_OP_REMOVE;
    rm.kind = s->kind[f];
    count(r, palp_db_log_contact(r->w, s->h, &rm));
    s->live[f] = 0;
  }
  c.op = s->live[f] ? PALP_DB_OP_UPDATE : PALP_DB_OP_ADD;
  c.kind = kind;
  if (kind == PALP_DB_KIND_FORCE) {
    c.def.distribution = v->distribution;
    c.def.center = v->center; /* on its vertex when it named one, as the server puts it */
    c.def.patch_area = v->patch_area > 0 ? v->patch_area : 5.2e-4;
    c.def.sigma_fraction = 0.5;
    c.def.offset_fraction = 0.5;
    c.def.offset_dir = v->offset_dir;
    c.force_n = v->force; /* clamped to the phantom's limit */
  } else {
    c.center_m = v->center;
    c.radius_m = v->radius;
    s->radius[f] = v->radius;
  }
  s->live[f] = 1;
  s->kind[f] = (uint8_t)kind;
  count(r, palp_db_log_contact(r->w, s->h, &c));
}

/* A token of finger f's bucket (CONTACT_BURST deep, filled at the session's tick rate), if one is there. */
static int take_token(rsession *s, int f, int64_t now_ns) {
  /* now_ns may lie before the bucket's time: a held contact, logged at the time it came (release_held) */
  const int64_t dt = now_ns > s->tokens_ns[f] ? now_ns - s->tokens_ns[f] : 0;
  double t = s->tokens[f] + (double)dt * 1e-9 * s->tick_hz;
  s->tokens_ns[f] += dt;
  s->tokens[f] = t < CONTACT_BURST ? t : CONTACT_BURST;
  if (s->tokens[f] < 1) return 0;
  s->tokens[f] -= 1;
  return 1;
}

/* Contacts kept over the rate, logged as their finger's next token comes (all: the session ends). */
static void flush_contacts(recorder *r, rsession *s, int64_t now_ns, int all) {
  for (int f = 0; f < FINGERS; f++)
    if (s->has_pending[f] && (all || take_token(s, f, now_ns))) {
      s->has_pending[f] = 0;
      log_contact(r, s, &s->pending[f]);
    }
}

/* A contact is checked as the server checks it (palp_srv_validate_contact) against the widest limits a
 * server's config may set, the phantom's own from its catalogue entry (force limit, radius, rest
 * vertices): one the server refuses is not logged, counted by reason; a force over the limit is logged
 * clamped, as the server applies it under its default policy. Then at most one per finger per tick
 * (take_token): a release always (it only follows a logged contact), the newest of the rest kept.
 * now_ns: when it came (palp_dds_now_ns()). */
static void on_contact(recorder *r, const palp_Contact *m, int64_t now_ns) {
  rsession *s = find_session(r, m->session_id, 0);
  if (!s || m->finger >= FINGERS) {
    r->unknown_session_samples++;
    return;
  }
  const phantom *ph = s->ph;
  /* Without its catalogue entry yet: no vertex to name, a reach of the largest dome a station accepts. */
  const palp_srv_limits lim = {.session_id = s->id,
                               .max_force = ph ? ph->max_force : PALP_SRV_CFG_MAX_FORCE_MAX,
                               .absurd_force = PALP_SRV_CFG_ABSURD_FORCE_MAX,
                               .force_policy = PALP_SRV_FORCE_CLAMP,
                               .finger_radius_min = PALP_SRV_CFG_FINGER_RADIUS_MIN,
                               .finger_radius_max = PALP_SRV_CFG_FINGER_RADIUS_MAX,
                               .phantom_radius = ph ? ph->radius : 10.0,
                               .vertex_count = ph ? ph->n : 0,
                               .rest = ph ? ph->rest : NULL};
  palp_srv_contact v;
  palp_srv_reject_reason why = PALP_SRV_REJ_COUNT;
  if (palp_srv_validate_contact(m, &lim, &v, &why) == PALP_SRV_REJECT) {
    s->invalid[(unsigned)why < PALP_SRV_REJ_COUNT ? why : PALP_SRV_REJ_MODEL]++;
    return;
  }
  const int f = v.finger;
  if (v.mode == palp_CONTACT_RELEASE) {
    s->has_pending[f] = 0; /* lifted: what was kept is no longer the finger's */
    log_contact(r, s, &v);
    return;
  }
  if (!s->has_pending[f] && take_token(s, f, now_ns)) {
    log_contact(r, s, &v);
    return;
  }
  s->coalesced += s->has_pending[f];
  s->pending[f] = v;
  s->has_pending[f] = 1;
}

/* The session's counts of what was not logged one by one, as one event each, once per FOLD_NS (all:
 * now, the session ends). */
static void fold_counts(recorder *r, rsession *s, int64_t now_ns, int all) {
  if (!all && now_ns - s->folded_ns < FOLD_NS) return;
  s->folded_ns = now_ns;
  s->refused_logged = 0;
  int64_t invalid = 0;
  char detail[400];
  size_t at = 0;
  for (int k = 0; k < PALP_SRV_REJ_COUNT; k++) {
    if (!s->invalid[k]) continue;
    invalid += s->invalid[k];
    const int n = snprintf(detail + at, sizeof detail - at, "%s%s %lld", at ? ", " : "", palp_srv_reject_name(k),
                           (long long)s->invalid[k]);
    if (n > 0 && (size_t)n < sizeof detail - at) at += (size_t)n;
    s->invalid[k] = 0;
  }
  if (invalid) {
    char line[480];
    snprintf(line, sizeof line, "contacts not recorded: the server refuses them (%s)", detail);
    count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_REJECT, s->frame, line, invalid));
  }
  if (s->coalesced) {
    count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_INFO, s->frame,
                               "contacts not recorded: more than one per finger per tick (the newest kept)",
                               s->coalesced));
    s->coalesced = 0;
  }
  if (s->unanswered) {
    count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_REJECT, s->frame,
                               "findings not logged: the recorder did not see the server's answer (more, not "
                               "logged one by one)",
                               s->unanswered));
    s->unanswered = 0;
  }
  if (s->refused_more) {
    count(r, palp_db_log_event(r->w, s->h, PALP_DB_EVENT_REJECT, s->frame,
                               "finding refused (more, not logged one by one)", s->refused_more));
    s->refused_more = 0;
  }
}

static void on_feedback(recorder *r, const palp_Feedback *m) {
  rsession *s = find_session(r, m->session_id, 0);
  if (!s) {
    r->unknown_session_samples++;
    return;
  }
  if ((int64_t)m->frame > s->frame) s->frame = (int64_t)m->frame, s->t = m->sim_time;
  for (uint32_t i = 0; i < m->fingers._length; i++) {
    const palp_FingerFeedback *ff = &m->fingers._buffer[i];
    if (ff->finger >= FINGERS) continue;
    s->active[ff->finger] = ff->active;
    s->force[ff->finger] = (palp_vec3){ff->force.x, ff->force.y, ff->force.z};
    if (ff->active) count(r, palp_db_log_feedback(r->w, s->h, (int64_t)m->frame, ff->finger, s->force[ff->finger]));
  }
  /* One frame row per feedback sample (every tick while a haptic station listens): the force is
   * exact; the pole's displacement is its depth along -z only (the feedback's top_displacement,
   * server/session.c), where the server's own frame row has the length of the pole's 3-D
   * displacement (db/summary.c): equal for a press straight down, shorter by the pole's sideways
   * drift otherwise. The 3-D value needs the pole's position at this frame, which no feedback sample
   * carries (a deformation does, at 30 Hz and only while a display watches). Volume, pressure and the
   * largest displacement come from the newest deformation sample. (Called exact until 2026-12-07.) */
  palp_vec3 sum = {0, 0, 0};
  for (int k = 0; k < FINGERS; k++)
    if (s->active[k]) sum.x += s->force[k].x, sum.y += s->force[k].y, sum.z += s->force[k].z;
  palp_db_frame f = {.frame = (int64_t)m->frame, .sim_time_s = m->sim_time, .top_disp_m = fabs(m->top_displacement),
                     .volume_m3 = s->volume, .pressure_pa = s->pressure,
                     .contact_force_n = sqrt(sum.x * sum.x + sum.y * sum.y + sum.z * sum.z)};
  f.max_disp_m = s->max_disp > f.top_disp_m ? s->max_disp : f.top_disp_m;
  count(r, palp_db_log_frame(r->w, s->h, &f));
}

/* FNV-1a over the positions' bytes, never 0 (0 means no mesh logged yet). */
static uint64_t mesh_fnv1a(const palp_vec3 *pos, int n) {
  const unsigned char *b = (const unsigned char *)pos;
  uint64_t h = 1469598103934665603ULL;
  for (size_t i = 0; i < sizeof *pos * (size_t)n; i++) h = (h ^ b[i]) * 1099511628211ULL;
  return h ? h : 1;
}

static void on_deformation(recorder *r, const palp_Deformation *m) {
  rsession *s = find_session(r, m->session_id, 0);
  if (!s) {
    r->unknown_session_samples++;
    return;
  }
  if ((int64_t)m->frame > s->frame) s->frame = (int64_t)m->frame, s->t = m->sim_time;
  const int n = (int)m->positions._length;
  palp_vec3 *pos = malloc(sizeof *pos * (size_t)(n ? n : 1));
  if (!pos) return;
  for (int i = 0; i < n; i++) pos[i] = (palp_vec3){m->positions._buffer[i].x, m->positions._buffer[i].y, m->positions._buffer[i].z};
  /* Kept for the frame rows the feedback writes: volume, pressure and the largest |x - X|. */
  s->volume = m->volume;
  s->pressure = m->pressure;
  const phantom *ph = s->ph;
  if (ph && ph->n == n) {
    double max2 = 0;
    for (int i = 0; i < n; i++) {
      const double dx = pos[i].x - ph->rest[i].x, dy = pos[i].y - ph->rest[i].y, dz = pos[i].z - ph->rest[i].z;
      const double d2 = dx * dx + dy * dy + dz * dz;
      if (d2 > max2) max2 = d2;
    }
    s->max_disp = sqrt(max2);
  }
  /* A sleeping world's shape is repeated once a second for the displays (server/session.c): a
   * sample marked asleep whose positions are those of the newest logged mesh adds no row. Compared,
   * not trusted: a writer that leaves `awake` unset still has every changed shape logged. */
  const uint64_t hash = n > 0 ? mesh_fnv1a(pos, n) : 0;
  if (n > 0 && !(!m->awake && hash == s->mesh_hash)) {
    count(r, palp_db_log_mesh(r->w, s->h, (int64_t)m->frame, pos, n));
    s->mesh_hash = hash;
  }
  free(pos);
}

/* ---- runs: the session a session sample goes to (STATION_WRITERS, above) ---------------------- */

static int station_topic(int kind) { return kind == RD_CONTACT || kind == RD_FINDING; }

static int station_writer_of(const rsession *s, dds_instance_handle_t w) {
  for (int i = 0; i < s->station_writers; i++)
    if (s->station_writer[i] == w) return 1;
  return 0;
}

static int has_station_writer(const rsession *s, int kind) {
  for (int i = 0; i < s->station_writers; i++)
    if (s->station_kind[i] == kind) return 1;
  return 0;
}

/* Taken as the session's station's (its oldest forgotten when STATION_WRITERS are: a station that
 * joined again that often). */
static void take_station_writer(rsession *s, dds_instance_handle_t w, int kind) {
  if (s->station_writers == STATION_WRITERS) {
    memmove(s->station_writer, s->station_writer + 1, sizeof s->station_writer[0] * (STATION_WRITERS - 1));
    memmove(s->station_kind, s->station_kind + 1, sizeof s->station_kind[0] * (STATION_WRITERS - 1));
    s->station_writers--;
  }
  s->station_writer[s->station_writers] = w;
  s->station_kind[s->station_writers++] = (uint8_t)kind;
}

static int retired(const recorder *r, dds_instance_handle_t w) {
  for (int i = 0; i < RETIRED_WRITERS; i++)
    if (r->retired[i] == w) return 1;
  return 0;
}

static void retire(recorder *r, dds_instance_handle_t w) {
  if (!w || retired(r, w)) return;
  r->retired[r->retired_next] = w;
  r->retired_next = (r->retired_next + 1) % RETIRED_WRITERS;
}

/* Whether a server sample of s's id (its writer's participant `run`, 0: not known) comes from a run of
 * s's id that ended here before s: a dead run's sample that came late. */
static int earlier_run(const recorder *r, const rsession *s, dds_instance_handle_t run, dds_instance_handle_t writer) {
  if (run && run == s->run) return 0;
  for (int i = 0; i < ENDED_RUNS; i++) {
    const ended_run *e = &r->ended[i];
    if (e->session_id == s->id && e->run != s->run && ((run && e->run == run) || (!run && writer && e->writer == writer)))
      return 1;
  }
  return 0;
}

/* A server's samples held for s's id from a run other than s's and none that ended before it: a new run
 * of its server has begun. */
static int other_run_held(const recorder *r, const rsession *s) {
  /* A run's held samples share its participant: earlier_run (a scan of ENDED_RUNS) once per run met in
   * a row, not once per sample (4,096 held x 2,048 ended was 8 million compares a call). */
  dds_instance_handle_t seen_run = 0, seen_writer = 0;
  for (int i = 0; i < r->nheld; i++) {
    const held_sample *h = &r->held[i];
    if (h->session_id != s->id || !h->run || !s->run || h->run == s->run) continue;
    if (h->run == seen_run && h->writer == seen_writer) continue; /* an earlier run's, as just found */
    if (!earlier_run(r, s, h->run, h->writer)) return 1;
    seen_run = h->run, seen_writer = h->writer;
  }
  return 0;
}

static int writer_held(const recorder *r, dds_instance_handle_t w) {
  for (int i = 0; i < r->nheld; i++)
    if (r->held[i].writer == w) return 1;
  return 0;
}

/* When the first contact held for the session came (INT64_MAX: none). */
static int64_t held_since(const recorder *r, uint32_t session_id) {
  int64_t t = INT64_MAX;
  for (int i = 0; i < r->nheld; i++)
    if (r->held[i].session_id == session_id && r->held[i].kind == RD_CONTACT && r->held[i].arrival_ns < t)
      t = r->held[i].arrival_ns;
  return t;
}

/* palp_dds_origin_check's verdict from the writer's partition (from: NULL when unknown). */
static palp_dds_origin_verdict origin_of(const char *from, const char *partition) {
  if (!from) return PALP_DDS_ORIGIN_UNKNOWN;
  return from[0] && !strcmp(from, partition) ? PALP_DDS_ORIGIN_SAME : PALP_DDS_ORIGIN_OTHER;
}

typedef enum route { ROUTE_LOG, ROUTE_HOLD, ROUTE_DROP, ROUTE_EARLIER } route;

/* Where a sample of session sid goes (writer: its writer, run: a server sample's writer's participant,
 * v: a station sample's writer's partition against the open session's): logged now (in the session open
 * for sid, or, none open, its handler counts it as before), held until its run is known, or dropped (a
 * writer of an ended session). */
static route route_sample(recorder *r, int kind, uint32_t sid, dds_instance_handle_t writer, dds_instance_handle_t run,
                          palp_dds_origin_verdict v) {
  rsession *s = find_session(r, sid, 0);
  if (!s) return ROUTE_LOG;
  if (!station_topic(kind)) {
    if (run && run == s->run) return ROUTE_LOG;
    /* a dead run's, late: held, it waited for a state that never comes, and meanwhile held every new
     * station writer's samples (other_run_held); its participant unknown, it was logged in this session */
    if (earlier_run(r, s, run, writer)) return ROUTE_EARLIER;
    return !run || !s->run ? ROUTE_LOG : ROUTE_HOLD;
  }
  if (!writer || station_writer_of(s, writer)) return ROUTE_LOG;
  if (retired(r, writer)) return ROUTE_DROP;
  /* its server lapsed (back, or a new run, the next state tells), a new run began, or this writer's
   * earlier samples wait: the state decides */
  if (s->lost_since || other_run_held(r, s) || writer_held(r, writer)) return ROUTE_HOLD;
  if (v != PALP_DDS_ORIGIN_SAME) return ROUTE_LOG; /* another partition's: counted as forged, never its station's */
  if (has_station_writer(s, kind)) return ROUTE_HOLD; /* a station joined again: this run or a new one */
  take_station_writer(s, writer, kind);
  return ROUTE_LOG;
}

/* run: a server sample's writer's participant (0: a station's, or not known); historical: a finding
 * status written before the readers were made. */
static void dispatch(recorder *r, int kind, const void *m, int64_t now_ns, palp_dds_origin_verdict v, const char *from,
                     dds_instance_handle_t run, int historical) {
  const uint32_t sid = *(const uint32_t *)m; /* every session topic's first key (idl/palp_dds_gate.c) */
  switch (kind) {
  case RD_SESSION_EXERCISE: on_session_exercise(r, m, run); break;
  case RD_CONTACT:
    if (from_its_partition(r, sid, v, from, "contact")) on_contact(r, m, now_ns);
    break;
  case RD_FEEDBACK: on_feedback(r, m); break;
  case RD_DEFORMATION: on_deformation(r, m); break;
  case RD_FINGER_SAMPLE: on_finger_sample(r, m); break;
  case RD_LOCAL_MODEL: on_local_model(r, m); break;
  case RD_FINDING:
    if (from_its_partition(r, sid, v, from, "finding")) on_finding(r, m);
    break;
  case RD_FINDING_STATUS: on_finding_status(r, m, historical); break;
  default: on_debrief(r, m); break;
  }
}

/* A copy of sample m of type T in one block, its one sequence `field` after it (elements of at most 8-byte
 * alignment, T's own: the block's second T is aligned for them). */
#define COPY_WITH_SEQ(T, field)                                                                          \
  do {                                                                                                   \
    const T *src_ = m;                                                                                   \
    const size_t n_ = src_->field._length, size_ = sizeof(T) + n_ * sizeof *src_->field._buffer;        \
    T *d_ = malloc(size_);                                                                               \
    if (!d_) return NULL;                                                                                \
    *d_ = *src_;                                                                                         \
    d_->field._buffer = n_ ? (void *)(d_ + 1) : NULL;                                                    \
    if (n_) memcpy(d_->field._buffer, src_->field._buffer, n_ * sizeof *src_->field._buffer);           \
    d_->field._maximum = (uint32_t)n_;                                                                   \
    d_->field._release = false;                                                                          \
    *bytes = size_;                                                                                      \
    return d_;                                                                                           \
  } while (0)

static void *copy_flat(const void *m, size_t size, size_t *bytes) {
  void *d = malloc(size);
  if (d) memcpy(d, m, size);
  *bytes = size;
  return d;
}

/* A deep copy of a session sample, freed with free(). */
static void *held_copy(int kind, const void *m, size_t *bytes) {
  switch (kind) {
  case RD_SESSION_EXERCISE: return copy_flat(m, sizeof(palp_SessionExercise), bytes);
  case RD_CONTACT: return copy_flat(m, sizeof(palp_Contact), bytes);
  case RD_LOCAL_MODEL: return copy_flat(m, sizeof(palp_LocalModel), bytes);
  case RD_FINDING: return copy_flat(m, sizeof(palp_Finding), bytes);
  case RD_FINDING_STATUS: return copy_flat(m, sizeof(palp_FindingStatus), bytes);
  case RD_FEEDBACK: COPY_WITH_SEQ(palp_Feedback, fingers);
  case RD_DEFORMATION: COPY_WITH_SEQ(palp_Deformation, positions);
  case RD_FINGER_SAMPLE: COPY_WITH_SEQ(palp_FingerSample, triangles);
  case RD_DEBRIEF: COPY_WITH_SEQ(palp_Debrief, lesion);
  default: *bytes = 0; return NULL; /* not a session's stream */
  }
}

static const char *topic_word(int kind) {
  static const char *const w[RD_COUNT] = {[RD_SESSION_EXERCISE] = "exercise", [RD_CONTACT] = "contact",
                                          [RD_FEEDBACK] = "feedback",         [RD_DEFORMATION] = "deformation",
                                          [RD_FINGER_SAMPLE] = "finger sample", [RD_LOCAL_MODEL] = "local model",
                                          [RD_FINDING] = "finding",           [RD_FINDING_STATUS] = "finding status",
                                          [RD_DEBRIEF] = "debrief"};
  return kind >= 0 && kind < RD_COUNT && w[kind] ? w[kind] : "sample";
}

static void hold(recorder *r, int kind, const void *m, dds_instance_handle_t writer, dds_instance_handle_t run,
                 const char *from, int historical) {
  const uint32_t sid = *(const uint32_t *)m;
  size_t bytes = 0;
  void *copy = r->nheld < MAX_HELD ? held_copy(kind, m, &bytes) : NULL;
  if (!copy || r->held_bytes + bytes > HELD_BYTES_MAX) {
    free(copy);
    if (r->held_dropped++ % 1000 == 0)
      palp_log_warn(r->log, "session %u: a %s held for its run's state not kept (%d samples, %zu bytes held already); "
                            "%lld so far", sid, topic_word(kind), r->nheld, r->held_bytes, (long long)r->held_dropped);
    return;
  }
  int first = 1;
  for (int i = 0; i < r->nheld && first; i++) first = r->held[i].session_id != sid;
  held_sample *h = &r->held[r->nheld++];
  *h = (held_sample){.kind = kind, .session_id = sid, .writer = writer, .run = run, .arrival_ns = palp_dds_now_ns(),
                     .historical = historical, .from_known = from != NULL, .bytes = bytes, .sample = copy};
  snprintf(h->from, sizeof h->from, "%s", from ? from : "");
  r->held_bytes += bytes;
  r->held_total++;
  if (first)
    palp_log_info(r->log, "session %u: %s %s held until a state tells its run (%s)", sid,
                  station_topic(kind) ? "a station's" : "a server's", topic_word(kind),
                  station_topic(kind) ? "its server lapsed, another run began, or a second writer of its station"
                                      : "another participant than its session's server: a new run");
}

/* What was held for session sid whose run is now known, logged in the session open for it, in the order
 * it came: a server's samples of that session's run, and (no other run's waiting, its server not
 * lapsed) its stations' (a writer taken as its station's then). Called after each state of sid. */
static void release_held(recorder *r, uint32_t sid, const char *why) {
  if (r->releasing || r->nheld == 0) return;
  rsession *s = find_session(r, sid, 0);
  if (!s || s->lost_since) return;
  r->releasing = 1; /* the handlers open and close no session, and hold nothing */
  const int other = other_run_held(r, s);
  int kept = 0, logged = 0, dropped = 0;
  for (int i = 0; i < r->nheld; i++) {
    held_sample *h = &r->held[i];
    int keep = h->session_id != sid;
    if (!keep) keep = station_topic(h->kind) ? other : h->run && s->run && h->run != s->run;
    if (keep) {
      r->held[kept++] = *h;
      continue;
    }
    if (station_topic(h->kind) && retired(r, h->writer)) {
      r->ended_writer_samples++;
      dropped++;
    } else if (!station_topic(h->kind) && earlier_run(r, s, h->run, h->writer)) {
      r->earlier_run_samples++;
      dropped++;
    } else {
      const char *from = h->from_known ? h->from : NULL;
      const palp_dds_origin_verdict v = s->partition[0] ? origin_of(from, s->partition) : PALP_DDS_ORIGIN_SAME;
      if (station_topic(h->kind) && v == PALP_DDS_ORIGIN_SAME && !station_writer_of(s, h->writer))
        take_station_writer(s, h->writer, h->kind);
      dispatch(r, h->kind, h->sample, h->arrival_ns, v, from, h->run, h->historical);
      logged++;
    }
    r->held_bytes -= h->bytes;
    free(h->sample);
  }
  r->nheld = kept;
  r->releasing = 0;
  if (logged || dropped)
    palp_log_info(r->log, "session %u: %d held samples logged in its session (%s)%s", sid, logged, why,
                  dropped ? "; some of an ended session's writers dropped" : "");
}

/* A second station writer's samples held SECOND_WRITER_WAIT_NS while no other run's are, its session's
 * server not lapsed: released into its session (release_held leaves none of that session's held). */
static void release_due(recorder *r, int64_t now_ns) {
  /* A session found blocked is not asked again for its next held sample in a row (other_run_held
   * scans every held sample: once per sample was quadratic in MAX_HELD a pass). */
  uint32_t blocked = 0;
  int have_blocked = 0;
  for (int i = 0; i < r->nheld; i++) {
    const held_sample *h = &r->held[i];
    if (!station_topic(h->kind) || now_ns - h->arrival_ns < SECOND_WRITER_WAIT_NS) continue;
    if (have_blocked && h->session_id == blocked) continue;
    const rsession *s = find_session(r, h->session_id, 0);
    if (!s || s->lost_since || other_run_held(r, s)) {
      blocked = h->session_id, have_blocked = 1;
      continue;
    }
    const int before = r->nheld;
    release_held(r, h->session_id, "no other run's samples came within 1.5 s");
    if (r->nheld < before) i = -1; /* the array was compacted: from its start again */
  }
}

/* Held samples whose run's state did not come within HELD_WAIT_NS: dropped, said once per session a pass. */
static void expire_held(recorder *r, int64_t now_ns) {
  int kept = 0, nsaid = 0;
  /* The sessions said this pass (up to 16; past them one line for the rest): remembering only the last
   * said one a line each time interleaved sessions' samples took turns, up to MAX_HELD lines a pass. */
  uint32_t said[16];
  int64_t unsaid = 0;
  for (int i = 0; i < r->nheld; i++) {
    held_sample *h = &r->held[i];
    if (now_ns - h->arrival_ns <= HELD_WAIT_NS) {
      r->held[kept++] = *h;
      continue;
    }
    int known = 0;
    for (int j = 0; j < nsaid && !known; j++) known = said[j] == h->session_id;
    if (!known && nsaid < (int)(sizeof said / sizeof said[0])) {
      said[nsaid++] = h->session_id;
      palp_log_warn(r->log, "session %u: a %s held for the state of its run dropped: no state told its run within "
                            "%.0f s (%lld held samples dropped so far)", h->session_id, topic_word(h->kind),
                    (double)HELD_WAIT_NS * 1e-9, (long long)r->held_dropped + 1);
    } else if (!known)
      unsaid++;
    r->held_dropped++;
    r->held_bytes -= h->bytes;
    free(h->sample);
  }
  r->nheld = kept;
  if (unsaid)
    palp_log_warn(r->log, "%lld more held samples of other sessions dropped as well: no state told their run within %.0f s",
                  (long long)unsaid, (double)HELD_WAIT_NS * 1e-9);
}

/* The run (participant) of a server sample's writer: from its session's record when the writer wrote
 * there before, else from the origin cache, then remembered there. Every server sample asked the cache
 * until 2026-12-06: ~8 writers a session overflowed it past ~100 sessions, nearly every sample then
 * missed and asked DDS (dds_get_matched_publication_data), and the recorder fell behind its
 * best-effort topics. A writer's participant never changes, so what the record says stays true. */
static dds_instance_handle_t server_run_of(recorder *r, rsession *s, dds_entity_t reader,
                                           const dds_sample_info_t *info) {
  const dds_instance_handle_t w = info->publication_handle;
  if (s && w)
    for (int i = 0; i < s->server_writers; i++)
      if (s->server_writer[i] == w) return s->server_run[i];
  r->origin_consults++;
  const dds_instance_handle_t run = palp_dds_origin_participant(&r->origin, reader, info);
  if (s && w && run) { /* unknown (0): asked again next time, as it may be known then */
    const int i = s->server_writers < SERVER_WRITERS ? s->server_writers++ : s->server_next;
    if (s->server_writers == SERVER_WRITERS) s->server_next = (i + 1) % SERVER_WRITERS;
    s->server_writer[i] = w;
    s->server_run[i] = run;
  }
  return run;
}

/* A sample of a session's stream, as taken from `reader`: routed (route_sample), then logged, held or
 * dropped. */
static void on_session_sample(recorder *r, int kind, dds_entity_t reader, const void *m,
                              const dds_sample_info_t *info) {
  const uint32_t sid = *(const uint32_t *)m;
  /* A session waiting for its catalogue entry opens as its inputs or frames come (not to lose them). */
  if (kind == RD_CONTACT || kind == RD_FINDING || kind == RD_FEEDBACK || kind == RD_DEFORMATION)
    resolve_pending(r, sid, 1);
  const int station = station_topic(kind);
  rsession *s = find_session(r, sid, 0);
  const dds_instance_handle_t run = station ? 0 : server_run_of(r, s, reader, info);
  /* a station writer taken as the session's was taken for writing in its partition (route_sample) */
  const char *from = !station                                          ? NULL
                     : s && station_writer_of(s, info->publication_handle) ? s->partition
                                                                          : palp_dds_origin_partition(&r->origin, reader, info);
  const palp_dds_origin_verdict v =
      station && s && s->partition[0] ? origin_of(from, s->partition) : PALP_DDS_ORIGIN_SAME;
  const int historical = kind == RD_FINDING_STATUS && info->source_timestamp < r->readers_since;
  switch (route_sample(r, kind, sid, info->publication_handle, run, v)) {
  case ROUTE_LOG: dispatch(r, kind, m, palp_dds_now_ns(), v, from, run, historical); break;
  case ROUTE_HOLD: hold(r, kind, m, info->publication_handle, run, from, historical); break;
  case ROUTE_EARLIER:
    if (r->earlier_run_samples++ == 0)
      palp_log_warn(r->log, "session %u: a %s from a run of its server that had ended (it came late): not recorded, "
                            "nor any such sample (counted at the stop)", sid, topic_word(kind));
    break;
  default:
    if (r->ended_writer_samples++ == 0)
      palp_log_warn(r->log, "session %u: a %s from a station writer of a session that had ended (its station not yet "
                            "told its server restarted): not recorded, nor any such sample (counted at the stop)",
                    sid, topic_word(kind));
    break;
  }
}

/* The readers of a session's streams, whose strays are counted and which are made anew (recorder.stream_*). */
static int is_stream(int k) { return k >= RD_CONTACT && k <= RD_LOCAL_MODEL; }
static int64_t stream_strays_left(const recorder *r) {
  int64_t n = 0;
  for (int k = RD_CONTACT; k <= RD_LOCAL_MODEL; k++) n += r->stream_strays[k];
  return n;
}

static dds_entity_t reader_deep(const recorder *r, dds_entity_t parent, dds_entity_t topic, palp_dds_topic_kind kind) {
  /* The topic's QoS, but a deeper reader history: the recorder, not a display, must see every
   * sample that arrives, and history depth is not part of the writer/reader match. */
  dds_qos_t *q = palp_dds_reader_qos(kind);
  if (kind == PALP_TOPIC_CONTACT || kind == PALP_TOPIC_FEEDBACK || kind == PALP_TOPIC_DEFORMATION ||
      kind == PALP_TOPIC_LOCAL_MODEL || kind == PALP_TOPIC_FINDING_STATUS || kind == PALP_TOPIC_FINGER_SAMPLE)
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 256);
  /* The best-effort streams hold at most the keys the gate passes (a dispose passes no filter);
   * deformations are reliable, and a reliable sample refused for resource limits is retried on
   * the delivery path (docs/robustness.md): filtered only. */
  if (kind == PALP_TOPIC_CONTACT || kind == PALP_TOPIC_FEEDBACK || kind == PALP_TOPIC_LOCAL_MODEL ||
      kind == PALP_TOPIC_FINGER_SAMPLE)
    palp_dds_gate_limit(&r->gate, q, kind);
  dds_entity_t rd = dds_create_reader(parent, topic, q, NULL);
  dds_delete_qos(q);
  return rd;
}

/* A flood of disposes of made-up stream keys: each stream reader made anew when idl/palp_dds_strays.h
 * says so (at once when full), its strays counted as it is taken (main's pass) and its samples
 * refused at the instance bound added here. The streams are volatile, so the new reader is handed
 * none of the flood again, and the sessions' keys become instances again with their next samples.
 * The new reader is made before the old goes, so that a remote writer always has a reader of this
 * participant matched and sends on; a sample in the old reader not yet taken in that instant is lost
 * (the pass just took them all). */
static void renew_streams(recorder *r, palp_log *plog, dds_entity_t sub, const dds_entity_t *t,
                          const palp_dds_topic_kind *kind, dds_entity_t *rd, dds_entity_t ws, int64_t now) {
  int renewed = 0;
  int64_t strays = 0;
  for (int k = RD_CONTACT; k <= RD_LOCAL_MODEL; k++) {
    r->stream_strays[k] += palp_dds_gate_refused_since(rd[k], &r->stream_refused_seen[k]);
    /* the deformations' reader is reliable and unbounded (reader_deep): never refuses, never full */
    if (!palp_dds_strays_renew_due((uint64_t)r->stream_strays[k], now, r->stream_renewed_ns[k]) &&
        !palp_dds_strays_full_due((uint64_t)r->stream_strays[k], r->stream_refused_seen[k],
                                  palp_dds_gate_instances(&r->gate, kind[k])))
      continue;
    const dds_entity_t fresh = reader_deep(r, sub, t[kind[k]], kind[k]);
    r->stream_renewed_ns[k] = now;
    if (fresh <= 0) {
      /* retried PALP_DDS_RENEW_NS later, not every pass however many come; said at most every 10 s */
      if (r->stream_strays[k] >= PALP_DDS_STRAYS_HARD) r->stream_strays[k] = PALP_DDS_STRAYS_HARD - 1;
      if (now - r->stream_renewal_said_ns < 10000000000LL && r->stream_renewal_said_ns) continue;
      r->stream_renewal_said_ns = now;
      palp_log_error(plog, "the %s reader, flooded with disposes of made-up keys, could not be made anew (%s): it "
                           "may refuse new sessions' samples until the flood's writer goes (tried again in %.2f s)",
                     topic_word(k), dds_strretcode(fresh), PALP_DDS_RENEW_NS * 1e-9);
      continue;
    }
    dds_waitset_detach(ws, rd[k]);
    dds_delete(rd[k]);
    rd[k] = fresh;
    dds_set_status_mask(rd[k], DDS_DATA_AVAILABLE_STATUS);
    dds_waitset_attach(ws, rd[k], k);
    r->stream_refused_seen[k] = 0;
    r->stream_strays_total += r->stream_strays[k];
    strays += r->stream_strays[k];
    r->stream_strays[k] = 0;
    r->stream_renewals++;
    renewed++;
  }
  if (renewed && (r->stream_renewals == renewed || now - r->stream_renewal_said_ns >= 10000000000LL)) {
    palp_log_warn(plog, "%lld disposes of stream keys of sessions never heard open, or samples refused at the stream "
                        "readers' bound (%lld in all; each kept while its writer lives: a flood); %d stream reader(s) "
                        "made anew to drop them, as each will be whenever %d more come (at most every %.2f s, unless "
                        "%d do)",
                  (long long)strays, (long long)r->stream_strays_total, renewed, PALP_DDS_STRAYS_MIN,
                  PALP_DDS_RENEW_NS * 1e-9, PALP_DDS_STRAYS_HARD);
    r->stream_renewal_said_ns = now;
  }
}

#define RECORDER_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_LOG | PALP_APP_OPT_VERBOSE | PALP_APP_OPT_DDS)

static void usage(FILE *f) {
  fputs("usage: palp-recorder --db FILE [--domain N] [--dds-config FILE] [--duration S] [--max-mb MB]\n"
        "                     [--pki DIR --identity instructor/NAME]   (DDS Security; or PALP_PKI, PALP_IDENTITY)\n"
        "--db FILE (also --database, as palp-server names it): the session log (SQLite).\n"
        "Records every classroom session seen on DDS into the session log until SIGINT/SIGTERM\n"
        "(or for S seconds). SIGHUP re-opens --log-file. --max-mb caps the log's file (0: no cap, or\n"
        ">= 1; at the cap it is full, as on a full disk: records lost are counted and said as they happen).\n",
        f);
  palp_app_common_usage(f, RECORDER_OPTS);
}

int main(int argc, char **argv) {
  const char *db = NULL, *pki = NULL, *identity = NULL;
  dds_domainid_t domain = DDS_DOMAIN_DEFAULT;
  double duration = 0, max_mb = 0;
  palp_app_opts ao;
  palp_app_opts_init(&ao, "palp-recorder");
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
      usage(stdout);
      return 0;
    }
    int common = palp_app_common_opt(&ao, RECORDER_OPTS, argc, argv, &i);
    if (common < 0) return 2;
    if (common) continue;
    if (i + 1 >= argc) {
      fprintf(stderr, "palp-recorder: %s needs a value\n", a);
      return 2;
    }
    if (!strcmp(a, "--db") || !strcmp(a, "--database")) db = argv[++i]; /* palp-server's name (docs/naming.md) */
    else if (!strcmp(a, "--pki")) pki = argv[++i];
    else if (!strcmp(a, "--identity")) identity = argv[++i];
    else if (!strcmp(a, "--domain")) {
      char *end;
      long v = strtol(argv[++i], &end, 10);
      if (*end || v < 0 || v > 232) {
        fprintf(stderr, "palp-recorder: --domain: expected 0..232, got '%s'\n", argv[i]);
        return 2;
      }
      domain = (dds_domainid_t)v;
    } else if (!strcmp(a, "--max-mb")) {
      char *end;
      max_mb = strtod(argv[++i], &end);
      if (*end || !(max_mb == 0 || (max_mb >= 1 && max_mb <= 1e7))) {
        fprintf(stderr, "palp-recorder: --max-mb: expected 0 (no cap) or 1..10000000 MB, got '%s'\n", argv[i]);
        return 2;
      }
    } else if (!strcmp(a, "--duration")) {
      /* Read whole and bounded as palp-server reads its own (server/main.c, parse_num: 0..1e7 s; 0 is no
       * duration here, so refused). atof took "10abc" for 10 s and "inf" for ever, and 1e10 s overflowed
       * the wait's nanoseconds: the recorder stopped after 0.1 s (until 2026-12-07). */
      char *end;
      errno = 0;
      duration = strtod(argv[++i], &end);
      if (end == argv[i] || *end || errno || !isfinite(duration) || !(duration > 0 && duration <= 1e7)) {
        fprintf(stderr, "palp-recorder: --duration: expected seconds in (0, 10000000], got '%s'\n", argv[i]);
        return 2;
      }
    } else {
      fprintf(stderr, "palp-recorder: unknown option %s\n", a);
      usage(stderr);
      return 2;
    }
  }
  if (ao.version) {
    palp_app_print_version(stdout, "palp-recorder");
    return 0;
  }
  if (!db) {
    usage(stderr);
    return 2;
  }
  char err[512], dds_chosen[1100];
  if (palp_app_use_dds_config(ao.dds_config, NULL, dds_chosen, sizeof dds_chosen, err, sizeof err) != 0) {
    fprintf(stderr, "palp-recorder: %s\n", err);
    return 2;
  }
  static palp_log plog; /* static: Cyclone's threads may log through it until the process ends */
  if (palp_log_init(&plog, "palp-recorder", ao.log_level, ao.log_file) < 0) {
    fprintf(stderr, "palp-recorder: --log-file %s: cannot open it: %s\n", ao.log_file, strerror(errno));
    return 2;
  }
  /* Secured, the recorder needs an identity that reads every session: an
   * instructor's (docs/security.md). */
  palp_dds_security sec;
  int src = pki || identity ? palp_dds_security_init(&sec, pki, identity, err, sizeof err)
                            : palp_dds_security_from_env(&sec, err, sizeof err);
  if (src == 0 && (pki || identity) && sec.kind == PALP_DDS_ID_NONE) {
    snprintf(err, sizeof err, "--pki and --identity go together");
    src = -1;
  }
  if (src == 0 && sec.kind != PALP_DDS_ID_NONE && sec.kind != PALP_DDS_ID_INSTRUCTOR) {
    /* refused here, not by a reader later: its permissions are sound, and re-issuing them mends nothing */
    snprintf(err, sizeof err,
             "--identity: the recorder needs an instructor identity (instructor/NAME), not %s/%s: it reads every "
             "session's every topic, as only an instructor's permissions allow (docs/security.md)",
             palp_dds_id_kind_name(sec.kind), sec.name);
    src = -1;
  }
  if (src < 0) {
    fprintf(stderr, "palp-recorder: %s\n", err);
    return 2;
  }
  if (sec.warning[0]) palp_log_warn(&plog, "DDS Security: %s", sec.warning);
  recorder *r = calloc(1, sizeof *r);
  if (r) r->log = &plog;
  palp_db_writer_opts wo = palp_db_writer_default_opts();
  wo.max_db_bytes = (int64_t)(max_mb * 1e6);
  if (!r || palp_db_writer_open(db, &wo, &r->w, err, sizeof err) != 0) {
    palp_log_error(&plog, "%s", r ? err : "out of memory");
    free(r);
    return 1;
  }
  /* the fill against the cap as it opens, then its losses as they happen (db/loss_watch.c, as palp-server) */
  palp_db_loss_watch watch = {.max_bytes = wo.max_db_bytes, .cap_name = "--max-mb"};
  int64_t next_watch_ns = palp_dds_now_ns() + 1000000000;
  {
    char line[320];
    const int full = palp_db_cap_describe(db, wo.max_db_bytes, "--max-mb", line, sizeof line);
    if (line[0]) palp_logf(&plog, full ? PALP_LOG_WARN : PALP_LOG_INFO, "%s", line);
  }
  /* Cyclone's warnings bounded, a refused peer said once (client/main.c does the same). */
  static palp_dds_log_limit dds_sink;
  static palp_dds_refusals refusals;
  palp_dds_refusals_init(&refusals, palp_log_warn_line, &plog, PALP_DDS_REFUSAL_WINDOW_S);
  palp_dds_refusals_install(&dds_sink, &refusals, 10, 10.0);
  /* a peer refused for its permissions named by its identity, not its GUID */
  if (palp_dds_security_name_peers(&sec, &refusals) < 0) palp_log_warn(&plog, "out of memory naming the classroom's identities");
  dds_entity_t pp = palp_dds_create_participant(domain, &sec);
  if (pp < 0) {
    palp_log_error(&plog, "cannot create a DDS participant: %s\n", dds_strretcode(pp));
    palp_db_writer_close(r->w);
    free(r);
    return 1;
  }
  dds_entity_t t[PALP_TOPIC_COUNT];
  for (int k = 0; k < PALP_TOPIC_COUNT; k++) t[k] = palp_dds_create_topic(pp, (palp_dds_topic_kind)k);
  /* The gate's filters, before the readers so that no sample of theirs passes unfiltered: the streams'
   * and the findings, their answers and the debriefs, which it logs only for a session it records
   * (find_session): reliable, so filtered only, never bounded (docs/robustness.md). */
  palp_dds_gate_init(&r->gate, MAX_SESSIONS);
  palp_dds_origin_init(&r->origin);
  static const palp_dds_topic_kind logged[] = {PALP_TOPIC_FINDING, PALP_TOPIC_FINDING_STATUS, PALP_TOPIC_DEBRIEF};
  const int filters = palp_dds_gate_filter_topics(&r->gate, t, logged, sizeof logged / sizeof logged[0]);
  char wildcard[64];
  snprintf(wildcard, sizeof wildcard, PALP_DDS_SESSION_PARTITION_FMT, 0u);
  char *z = strrchr(wildcard, '/');
  if (z) snprintf(z + 1, sizeof wildcard - (size_t)(z + 1 - wildcard), "*");
  /* secured sessions live in palp/s/TRAINEE/ID */
  if (sec.kind != PALP_DDS_ID_NONE) snprintf(wildcard, sizeof wildcard, "palp/s/*");
  dds_entity_t sub = palp_dds_session_subscriber(pp, wildcard);
  /* Each reader's topic (RD_*, in the order a pass takes them); those from RD_CONTACT on are the
   * sessions' own, under the partition subscriber. */
  static const palp_dds_topic_kind kind[RD_COUNT] = {
      PALP_TOPIC_CATALOGUE, PALP_TOPIC_EXERCISE,      PALP_TOPIC_SESSION_STATE,  PALP_TOPIC_SESSION_EXERCISE,
      PALP_TOPIC_CONTACT,   PALP_TOPIC_FEEDBACK,      PALP_TOPIC_DEFORMATION,    PALP_TOPIC_FINGER_SAMPLE,
      PALP_TOPIC_LOCAL_MODEL, PALP_TOPIC_FINDING,     PALP_TOPIC_FINDING_STATUS, PALP_TOPIC_DEBRIEF};
  dds_entity_t rd[RD_COUNT];
  r->readers_since = dds_time();
  for (int k = 0; k < RD_COUNT; k++) rd[k] = reader_deep(r, k < RD_CONTACT ? pp : sub, t[kind[k]], kind[k]);
  dds_entity_t ws = dds_create_waitset(pp);
  for (int k = 0; k < RD_COUNT; k++) {
    if (rd[k] < 0 || filters < 0) {
      char hint[PALP_DDS_HINT_MAX];
      palp_log_error(&plog, "cannot create a reader%s: %s%s\n", filters < 0 ? "'s topic filter" : "",
                     dds_strretcode(rd[k] < 0 ? rd[k] : filters),
                     palp_dds_refused_hint(&sec, NULL, hint, sizeof hint));
      dds_delete(pp);
      palp_db_writer_close(r->w);
      free(r);
      return 1;
    }
    dds_set_status_mask(rd[k], DDS_DATA_AVAILABLE_STATUS);
    dds_waitset_attach(ws, rd[k], k);
  }
  palp_app_on_signals(on_signal); /* by sigaction: signal()'s handler lasted one SIGHUP (palp_app.h) */
  /* A log on a pipe whose reader went (`... 2>&1 | tee x`, tee stopped): the next line's write fails
   * rather than killing the recorder with its sessions unended and its queue unwritten, as the
   * stations and palp-web have it (session 90's review) */
  struct sigaction pipe_sa;
  memset(&pipe_sa, 0, sizeof pipe_sa);
  pipe_sa.sa_handler = SIG_IGN;
  sigaction(SIGPIPE, &pipe_sa, NULL);
  char security[96];
  /* Without --domain, the DDS config's default domain: named by its number, as the server and stations
   * name theirs (it said "domain -1", DDS_DOMAIN_DEFAULT, until 2026-12-06). */
  dds_domainid_t joined;
  if (dds_get_domainid(pp, &joined) < 0) joined = domain;
  palp_log_info(&plog, "%s recording domain %u%s into %s (sessions on partition %s), DDS config %s; DDS Security %s",
                palp_app_version(), (unsigned)joined, domain == DDS_DOMAIN_DEFAULT ? " (the DDS config's default)" : "",
                db, wildcard, dds_chosen,
                palp_dds_security_state(&sec, security, sizeof security));
  /* Its waits on the monotonic clock, as its held samples' (palp_dds_now_ns): on the wall clock, which
   * NTP steps, a step back held a closed session, a lost server's or a pending state for as long as the
   * step, and one forward ended them at once (until 2026-12-07). Times written into the log stay wall
   * clock (now_unix, the writer's). */
  const int64_t t_end = duration > 0 ? palp_dds_now_ns() + (int64_t)(duration * 1e9) : 0;
  /* No phantom 10 s after the start while other participants are on the domain: say once what may
   * be wrong (a secured classroom and a recorder without an identity records nothing). */
  const int64_t t_hint = palp_dds_now_ns() + DDS_SECS(10);
  int hinted = 0;
  while (!stop_flag && (!t_end || palp_dds_now_ns() < t_end)) {
    if (!hinted && palp_dds_now_ns() >= t_hint) {
      hinted = 1;
      int any = 0;
      for (int i = 0; i < MAX_PHANTOMS && !any; i++) any = r->ph[i].used;
      char hint[PALP_DDS_HINT_MAX];
      if (!any) palp_dds_unanswered_hint(pp, &sec, hint, sizeof hint);
      if (!any && hint[0]) palp_log_warn(&plog, "no phantom from any palp-server in 10 s%s", hint);
    }
    dds_waitset_wait(ws, NULL, 0, DDS_MSECS(100));
    if (hup_flag) {
      hup_flag = 0;
      if (palp_log_reopen(&plog) < 0) palp_log_error(&plog, "SIGHUP: cannot re-open %s", plog.path);
      else palp_log_info(&plog, "SIGHUP: log re-opened; recording goes on");
    }
    /* Catalogue and session state first, so a session's samples find it open. */
    for (int k = 0; k < RD_COUNT; k++) {
      void *samples[TAKE] = {NULL};
      dds_sample_info_t info[TAKE];
      int n;
      while ((n = dds_take(rd[k], samples, info, TAKE, TAKE)) > 0) {
        for (int i = 0; i < n; i++) {
          if (!info[i].valid_data) {
            if (k == RD_STATE && info[i].instance_state != DDS_IST_ALIVE) on_state_lost(r, samples[i]);
            if (k == RD_CATALOGUE && info[i].instance_state != DDS_IST_ALIVE)
              on_phantom_gone(r, ((const palp_Phantom *)samples[i])->phantom_id);
            /* a dispose of a key whose session the gate would not pass (never heard open, so not a
             * station that leaves a session that just closed); Cyclone fills an invalid sample's key */
            if (k == RD_FINDING && info[i].instance_state == DDS_IST_NOT_ALIVE_DISPOSED &&
                !palp_dds_gate_passes(&r->gate, *(const uint32_t *)samples[i]))
              r->finding_strays++;
            /* a stream's: a key its filter would not pass (a made-up session, or finger past 3) */
            if (is_stream(k) && info[i].instance_state == DDS_IST_NOT_ALIVE_DISPOSED &&
                !palp_dds_gate_key_passes(&r->gate, kind[k], samples[i]))
              r->stream_strays[k]++;
            continue;
          }
          switch (k) {
          case RD_CATALOGUE: on_phantom(r, samples[i]); break;
          case RD_EXERCISE: on_public_exercise(r, samples[i]); break;
          case RD_STATE:
            /* its run: the participant of its writer (route_sample); then what waited for it */
            on_state(r, samples[i], info[i].publication_handle,
                     palp_dds_origin_participant(&r->origin, rd[k], &info[i]));
            release_held(r, ((const palp_SessionState *)samples[i])->session_id, "its state came");
            break;
          default: on_session_sample(r, k, rd[k], samples[i], &info[i]); break;
          }
        }
        dds_return_loan(rd[k], samples, n);
        if (n < TAKE) break;
      }
      if (k == RD_CATALOGUE) resolve_pending(r, 0, 0);
    }
    resolve_pending(r, 0, 0);
    const int64_t renew_ns = palp_dds_now_ns();
    renew_streams(r, &plog, sub, t, kind, rd, ws, renew_ns);
    if (palp_dds_strays_renew_due((uint64_t)r->finding_strays, renew_ns, r->finding_renewed_ns)) {
      /* As palp-server does with a session's (renew_finding_reader): the findings are volatile, so the new
       * reader is handed none of the flood again; a finding in flight in that instant is lost, and its
       * answer is then logged as one whose finding this recorder did not see. */
      dds_waitset_detach(ws, rd[RD_FINDING]);
      dds_delete(rd[RD_FINDING]);
      rd[RD_FINDING] = reader_deep(r, sub, t[kind[RD_FINDING]], kind[RD_FINDING]);
      if (rd[RD_FINDING] > 0) {
        dds_set_status_mask(rd[RD_FINDING], DDS_DATA_AVAILABLE_STATUS);
        dds_waitset_attach(ws, rd[RD_FINDING], RD_FINDING);
      }
      r->finding_strays_total += r->finding_strays;
      r->finding_renewals++;
      r->finding_renewed_ns = renew_ns;
      if (rd[RD_FINDING] <= 0)
        palp_log_error(&plog, "the findings reader could not be made anew (%s): findings are no longer recorded",
                       dds_strretcode(rd[RD_FINDING]));
      else if (r->finding_renewals == 1 || renew_ns - r->finding_renewal_said_ns >= 10000000000LL) {
        palp_log_warn(&plog, "%lld disposes of finding keys of sessions never heard open (%lld in all; each kept "
                             "while its writer lives: a flood); the findings reader was made anew to drop them, as "
                             "it will be whenever %d more come (at most every %.2f s, unless %d do)",
                      (long long)r->finding_strays, (long long)r->finding_strays_total, PALP_DDS_STRAYS_MIN,
                      PALP_DDS_RENEW_NS * 1e-9, PALP_DDS_STRAYS_HARD);
        r->finding_renewal_said_ns = renew_ns;
      }
      r->finding_strays = 0;
    }
    const int64_t pass_ns = palp_dds_now_ns();
    for (int i = 0; i < MAX_SESSIONS; i++)
      if (r->s[i].open) {
        settle_findings(r, &r->s[i], 0);
        flush_contacts(r, &r->s[i], pass_ns, 0);
        fold_counts(r, &r->s[i], pass_ns, 0);
      }
    end_closing_sessions(r, pass_ns);
    end_lost_sessions(r, pass_ns);
    release_due(r, pass_ns);
    expire_held(r, pass_ns);
    /* a service runs for days: a refused peer's repeats are said a window after its last line,
     * not only at stop (idl/palp_dds_refusals.h) */
    palp_dds_refusals_tick(&refusals, palp_dds_now_ns());
    const int64_t now_ns = palp_dds_now_ns();
    if (now_ns >= next_watch_ns) {
      next_watch_ns = now_ns + 1000000000;
      palp_db_writer_stats ws_;
      palp_db_writer_stats_get(r->w, &ws_);
      char line[640];
      const int said = palp_db_loss_watch_look(&watch, &ws_, now_ns, line, sizeof line);
      if (said == 1) palp_log_warn(&plog, "%s; recording goes on", line);
      else if (said == 2) palp_log_info(&plog, "%s", line);
    }
  }
  /* Sessions still running end here in this log, saying so: left "(running)", a restarted
   * recorder's copy of their rest (a new uid) looked like a second session beside an unended one. */
  int cut = 0;
  for (int i = 0; i < MAX_SESSIONS; i++) {
    rsession *s = &r->s[i];
    if (!s->open) continue;
    /* One whose CLOSED state came, waiting for its debrief (DEBRIEF_WAIT), ended as the server ended it:
     * until 2026-12-07 it was cut short here, its close reason and the server's counts lost. */
    if (s->closing) {
      close_session(r, s, &s->close_state);
      continue;
    }
    end_cut(r, s, "palp-recorder stopped while the session ran (the server's own log has the rest)");
    cut++;
  }
  if (cut) palp_log_warn(&plog, "stopping: %d session(s) still running end here in this log, cut short", cut);
  dds_delete(pp);
  palp_db_writer_stats st;
  palp_db_writer_flush(r->w, 10);
  palp_db_writer_stats_get(r->w, &st);
  palp_db_writer_close(r->w);
  palp_log_info(&plog,
          "stopped; %lld records written, %lld shed, %lld failed, %lld samples of unknown sessions, "
          "%lld of a writer outside their session's partition, %lld samples from a station writer of a session "
          "that had ended, %lld samples from an earlier run of their session's server, %lld held for the state of their run (%lld held samples dropped: it did not come), %lld "
          "server samples' writers looked up in the origin cache (%lld writers asked of DDS, %lld forgotten), %lld "
          "disposes of finding keys of sessions never heard open (the findings reader made anew %lld times), %lld "
          "disposes of stream keys never heard open or samples refused at the streams' bound (stream readers made "
          "anew %lld times), %lld exercises refused, %lld catalogue entries refused, %llu sessions not recorded "
          "(no slot, or their start refused)%s%s\n",
          (long long)st.written, (long long)st.shed, (long long)st.failed, (long long)r->unknown_session_samples,
          (long long)r->foreign_samples, (long long)r->ended_writer_samples, (long long)r->earlier_run_samples,
          (long long)r->held_total,
          (long long)(r->held_dropped + r->nheld), (long long)r->origin_consults, (long long)r->origin.lookups,
          (long long)r->origin.evictions, (long long)(r->finding_strays_total + r->finding_strays),
          (long long)r->finding_renewals, (long long)(r->stream_strays_total + stream_strays_left(r)),
          (long long)r->stream_renewals, (long long)r->exercises_refused, (long long)r->phantoms_refused,
          (unsigned long long)r->begins_refused, st.last_error[0] ? "; last error: " : "",
          st.last_error);
  for (int i = 0; i < MAX_PHANTOMS; i++) phantom_free(&r->ph[i]);
  for (int i = 0; i < MAX_PENDING_EXERCISES; i++) free(r->pending_ex[i].json);
  for (int i = 0; i < r->nheld; i++) free(r->held[i].sample);
  free(r);
  palp_dds_log_limit_remove(&dds_sink); /* before the log closes; then the repeats not yet said */
  palp_dds_refusals_flush(&refusals);
  palp_log_close(&plog);
  return st.shed + st.failed ? 1 : 0;
}
