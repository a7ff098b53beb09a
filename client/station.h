/*
 * station.h - the DDS side of a palp station: participant, catalogue, joining a
 * session (request -> reply), and the session partition's endpoints.
 *
 * Used by palp-client and, in-process, by the server tests and the benchmark.
 * Functions return 0 or a negative PALP_E* code; messages go to the err buffer.
 */
#ifndef PALP_CLI_STATION_H
#define PALP_CLI_STATION_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include <dds/dds.h>

#include "palp.h"
#include "palp_dds.h"
#include "palp_dds_log_view.h"
#include "palp_dds_security.h"

/* The session log's news said to the station's user (palp_cli_station_log_news). */
typedef struct palp_cli_log_news {
  uint64_t said_lost;             /* the loss the last line said [records] */
  int64_t said_ns;                /* when the last "losing" line was said; 0: none */
  int said_losing;                /* a "losing" line said, no "writing again" since */
} palp_cli_log_news;

/* The local models (and finger samples) a trainee's station holds between two takes of its main
 * thread: 128 ms of physics steps at 250 Hz, 32 ms at 1 kHz (station.c). */
#define PALP_CLI_MODEL_DEPTH 32
/* ... and at most this many instances (those and its other best-effort streams: contacts, feedback,
 * deformations): its 4 fingers, and room for a few disposes of made-up keys (a dispose passes no
 * topic filter); past it a new key's samples are dropped. */
#define PALP_CLI_STREAM_INSTANCES 32

/* The session's server (2026-12-06): the participant whose writer answered the station's accepted JOIN.
 * Every reader of the server's topics in a session drops the samples of any other participant (in an
 * unsecured classroom anyone may write into a session's partition: a forged local model changed what the
 * trainee felt, a forged state closed her session, a forged score told her a false grade; in a secured
 * one a second or a restarted server may). A writer's verdict is found once (the server's writers from
 * discovery's announcements, DCPSPublication; another's by palp_dds_writer_participant) and kept by its
 * publication handle, which Cyclone never reuses in a process: the local models come at up to 1 kHz. */
#define PALP_CLI_SERVER_WRITERS 24 /* the server's writers kept (~12 a station reads; full, the oldest goes) */
#define PALP_CLI_OTHER_WRITERS 8   /* others' writers kept, the oldest replaced first */
typedef struct palp_cli_server_bind {
  int bound;                /* a JOIN was accepted: `server` is its replier's participant */
  dds_guid_t server;
  dds_instance_handle_t mine[PALP_CLI_SERVER_WRITERS];
  int n_mine;
  unsigned mine_next;       /* full, the next to replace */
  dds_instance_handle_t other[PALP_CLI_OTHER_WRITERS];
  dds_guid_t other_pp[PALP_CLI_OTHER_WRITERS];
  unsigned other_next;
  uint64_t ignored;         /* samples dropped: another participant's, or a writer gone before it was known */
  dds_guid_t first_other;   /* the first such participant, named to the user and in the log */
  int have_other;           /* ... known (0: only writers already gone) */
  int told;                 /* palp_cli_station_foreign_news said it */
  int64_t first_ignored_ns; /* when the first was dropped (palp_dds_now_ns): heard_ns past it, the server is
                             * there while another participant writes */
  int left;                 /* palp_cli_station_leave ran: nothing more comes, what there is is said */
  int64_t heard_ns;         /* the last sample of the server's, any topic (palp_dds_now_ns) */
  /* A state of this session from another participant that claims the server restarted (another
   * trainee's session under this id, or its ticks fallen back): a restarted server's, or a forgery.
   * Taken for a restart only when the server itself is silent (palp_cli_station_session_closed). */
  int64_t suspect_ns;       /* since then; 0: none */
  char suspect_reason[128];
  int64_t asked_ns;         /* the accepted JOIN sent again, for the server to answer if it is there */
  /* The session ended as its server restarted (either sign, from the bound server's own states or from
   * another participant's confirmed): the samples ignored were likely the restarted server's, and
   * palp_cli_station_foreign_news says so rather than an intrusion (review s83 #5). */
  int restarted;
  /* The session's server refused the accepted JOIN, sent again: it no longer holds the session (closed
   * while this station did not run, review s83 #3); refused_reason is its word for why. */
  int refused;
  char refused_reason[128];
} palp_cli_server_bind;

/* A reader of a global topic the session's server writes for all its stations, the catalogue or an exercise,
 * that takes only the server's writers' samples (review s83 #1). Read after the JOIN bound the server, from
 * any participant as before, another's entry or exercise replaced the server's in a keep-last-1 reader
 * (a forger writing every 5 ms gave the trainee its phantom's radius and max_force, a mesh her frames did
 * not fit, a title, instructions and pressure bands); a deeper history does not stop a fast forger. The
 * filter runs on Cyclone's receive thread: its writer set is fixed while the reader lives (the server's
 * writers of the topic as a reader made before matched them), and what it drops is counted (atomics) and
 * added to palp_cli_server_bind.ignored on the main thread. */
#define PALP_CLI_SERVER_ONLY_WRITERS 8
typedef struct palp_cli_server_only {
  dds_entity_t topic, reader; /* 0: none */
  int n;
  dds_instance_handle_t pub[PALP_CLI_SERVER_ONLY_WRITERS]; /* the server's writers when the reader was made */
  uint32_t phantom;          /* the one phantom whose samples are read (others pass uncounted) */
  atomic_ullong refused;     /* [receive thread] samples of that phantom from other writers, dropped */
  atomic_ullong first_refused; /* ... the first one's publication handle; 0: none */
  uint64_t counted;          /* refused already added to bind.ignored */
  int64_t looked_ns;         /* the server's writers last looked for (palp_dds_now_ns) */
} palp_cli_server_only;

/* A wait given up because the caller's stop flag was set (palp_cli_station.stop): the user asked
 * the station to end (Ctrl-C), not a failure. */
#define PALP_CLI_ESTOPPED (-100)

typedef struct palp_cli_station {
  char station_id[64];
  /* The caller's stop flag (palp-client's SIGINT/SIGTERM/SIGHUP flag), or NULL: never. Set, every wait
   * below (join, catalogue, phantom, server, exercise, debrief, score) returns PALP_CLI_ESTOPPED within
   * its poll period (<= 100 ms): a Ctrl-C with no server waited out --timeout twice (up to 2 h).
   * palp_cli_station_leave does not look at it: the goodbye is what a stop sends. Set after open. */
  const atomic_int *stop;
  dds_entity_t pp;
  dds_entity_t topic[PALP_TOPIC_COUNT];
  /* reply_r holds this station's replies only, through reply_topic, which carries that filter
   * (2026-12-07); state_r: below, state_topic */
  dds_entity_t catalogue_r, request_w, reply_r, state_r, reply_topic;
  /* session endpoints, valid after a successful join */
  uint32_t session_id;
  /* A copy of session_id for own_status, the filter of a reader that lives from open on: it runs on
   * Cyclone's receive thread while the main thread joins and ends sessions (a data race on the plain
   * field, review s83 #13). The other filters' readers exist only while session_id stays put. */
  atomic_uint status_session_id;
  uint32_t phantom_id;
  char partition[64];
  double tick_rate_hz;
  int64_t join_asked_ns; /* when the accepted JOIN was sent (palp_dds_now_ns): the session opened after it */
  /* The session's trainee station as its state names it: a trainee's own station id; a viewer's, the
   * first state's. A state of this session id naming another is a restarted server's session of another
   * trainee (it numbers them from 1 again), not this one (palp_cli_station_session_closed). */
  char session_trainee[64];
  /* SessionState.ticks last seen for this session: a server steps on, never back; fewer ticks are
   * a new session under the same id (a restarted server that took this station's JOIN again) */
  uint64_t session_ticks;
  /* SessionState.rejected_samples last seen from its server, and the count the trainee was last told
   * of and when (palp-client's report_rejected): a station whose samples the server refuses (a finger
   * radius outside its range, say) pressed on a dome that never moved, told nothing (session 81) */
  uint64_t rejected_samples, rejected_said;
  int64_t rejected_said_ns;
  dds_entity_t pub, sub;
  dds_entity_t contact_w, contact_r, feedback_r, deformation_r;
  dds_entity_t local_model_r; /* trainee with feedback: the server's local contact models (issue 11) */
  dds_entity_t finger_sample_r; /* ... and its finger samples, touched triangles named (session 71); 0: none */
  dds_entity_t finger_sample_topic; /* the reader's own topic entity, which carries its session filter */
  dds_entity_t contact_topic;       /* a viewer's contact reader's, likewise (session 72) */
  /* palp_exercise (issue 13): what the trainee may know of an exercise. Only the joined phantom's
   * (exercise_phantom), through a topic entity of its own that carries that filter (2026-12-07): made
   * by the join, deleted with the session; 0: none. */
  dds_entity_t exercise_r, exercise_topic;
  uint32_t exercise_phantom;
  /* ... and in a session, where exercise_r only finds the server's writers, the exercise read: the
   * server's alone (palp_cli_server_only); made by palp_cli_station_exercise, deleted with the session */
  palp_cli_server_only exercise_srv;
  /* In a session state_r reads its state only, through a topic entity of its own that carries the
   * filter (2026-12-07); 0 outside one, where state_r reads every state (--trainee looks there). */
  dds_entity_t state_topic;
  dds_entity_t finding_w, finding_status_r; /* trainee: "lump here" marks and the server's answers */
  dds_entity_t debrief_r;     /* trainee: palp_debrief, what its marks found, at its session's end; 0: none
                               * (a secured identity whose permissions predate the topic) */
  int debrief_topic_refused;  /* ... and that is why: said once at the end of an exercise */
  dds_entity_t debrief_score_r; /* trainee: palp_debrief_score, a practice session's score after its
                                 * debrief (session 64); 0: none (permissions that predate the topic) */
  int debrief_score_topic_refused; /* ... and that is why */
  int in_exercise;            /* palp_cli_station_exercise found the joined phantom's exercise */
  uint32_t next_mark_id;      /* the station numbers its marks from 1 */
  /* The last request's number. From a random 31-bit start (2026-12-07, first_request_seq in station.c):
   * a station restarted with the same host, pid and label has the same station id, and the server
   * refuses the (station id, request_seq) pair that opened a session it closed. */
  uint32_t request_seq;
  palp_dds_security sec;    /* identity; kind PALP_DDS_ID_NONE: plain DDS */
  dds_entity_t request_pub; /* secured: the publisher in the identity's request partition */
  /* A station its machine stalled (swap, a core taken) for longer than its lease: the
   * server holds its session (station_grace) for the same request again, and the
   * station's own view of the server's lease may have lapsed too (docs/station.md,
   * "A stalled station"). Kept by palp_cli_station_session_closed. */
  palp_SessionRequest last_join; /* the accepted JOIN, sent again while the server holds its session */
  int has_last_join;
  int64_t last_check_ns;  /* the previous palp_cli_station_session_closed */
  int64_t stall_end_ns;   /* when the last stall ended; 0: none */
  double stall_s;         /* [s] its length */
  unsigned stalls;        /* stalls seen */
  int64_t doubt_until_ns; /* the server's lease lapsed: its state may come back until then */
  int doubt_after_stall;  /* ... and it lapsed right after a stall of this station's own */
  unsigned server_returns; /* lapses of the server's lease it came back from */
  int64_t next_held_ask_ns;  /* the server holds our session for us: the JOIN again, not before this */
  unsigned held_asks;        /* JOINs sent again because the server held our session (the station says so) */
  /* A viewer (visual station, observer) the server dropped (its writers' 0.5 s liveliness lapsed while it,
   * or the server, did not run) is not held: the JOIN again, naming its session, after a stall of its
   * own or when the session's state counts no viewer of its role (viewer_ask in client/station.c). */
  int64_t next_viewer_ask_ns; /* not before this (1 s after the join, then at most once a second) */
  unsigned viewer_asks;       /* JOINs sent again as a viewer */
  unsigned viewer_stalls;     /* the stalls already answered with one */
  int viewer_stall_asks;      /* JOINs still to send after the last stall (two: at once, a second later) */
  int closed_seen;        /* palp_cli_station_session_closed said closed: nothing left to leave gently */
  /* The server's session log as this station's session sees it (session 68): read from
   * palp_server_status by palp_cli_station_session_closed, said by palp_cli_station_log_news. */
  dds_entity_t status_r;  /* 0: none (permissions that refuse it; nothing is said then) */
  dds_entity_t status_topic; /* status_r's, filtered to the statuses that list this session (2026-12-07) */
  dds_entity_t publications_r; /* DCPSPublication: the domain's writers as announced (palp_cli_server_bind); 0: none */
  dds_entity_t session_log_r; /* palp_session_log (session 69), in the session: its own losses; 0: none */
  palp_dds_log_view log;
  palp_cli_log_news log_said;
  int goodbye_unanswered; /* palp_cli_station_leave, after a stall: the server did not answer its JOIN
                           * (within PALP_CLI_LEAVE_WAIT_S) or then its LEAVE: the goodbye may be lost */
  palp_cli_server_bind bind; /* the session's server (palp_cli_station_from_server) */
} palp_cli_station;

/* A gap between two palp_cli_station_session_closed calls longer than this was a stall
 * that may have outlasted the station's lease (PALP_DDS_STATION_LEASE_S, 0.5 s); the
 * callers check every 100 ms. */
#define PALP_CLI_STALL_S 0.4
/* After a stall, how long the server's state may stay lapsed before the server is
 * taken for lost: its participant must be found again (SPDP every ~0.1 s on the
 * loopback config) and its state re-delivered. */
#define PALP_CLI_SERVER_WAIT_S 5.0
/* Which lapses a stall of this station's own explains (review s83 #2): the station's view of the server's
 * participant lease (PALP_DDS_SERVER_LEASE_S) lapses while it is stopped only if the stop lasted about that
 * long. The server renews it with every message (SPDP every ~0.1 s on the loopback config, its samples
 * more often), so a stop of 0.8 of the lease can outlast it; a shorter one cannot. And the lapse a stall
 * causes is there as the station runs again, seen by the first check after it (100 ms on): one seen later
 * than PALP_CLI_STALL_LAPSE_SEEN_S after the stall's end is the server's own (the server's traffic renewed
 * the lease since). Before, any stall over PALP_CLI_STALL_S within 2 s bought a dead server 5 s (a 0.5 s
 * hiccup and a SIGKILL 0.2 s later: "not back within 5 s of this station's 0.6 s stall"). */
#define PALP_CLI_STALL_LAPSE_FRACTION 0.8
#define PALP_CLI_STALL_LAPSE_SEEN_S 0.5
/* That wait over, the station asks the server before it says "server lost" (review s83 #3): its accepted
 * JOIN again, the answer awaited this long [s] (an alive server answers in milliseconds). A station
 * stopped past station_grace + closed_retention (>= 15 s by default) finds its session's state retired,
 * never re-delivered, and the server alive: it answers "session N closed: trainee station lost ..." (it
 * remembers its last 1,024 closed requests), and that reason is the session's. */
#define PALP_CLI_LOST_ASK_S 0.3
/* A lapse of the server's lease with no stall of this station's before it: the server
 * crashed, or its machine did not run it for a while (a starved or stopped process lets
 * its lease lapse just as a dead one does). Its session state may come back until then:
 * the server, running again, is found again and republishes its states every status
 * period (1 s by default). Past it the server is taken for lost. */
#define PALP_CLI_SERVER_GRACE_S 1.0
/* A state of this session from another participant that claims a restart (palp_cli_server_bind.suspect_ns)
 * ends the session only when the session's server has sent nothing for this long [s] (from this
 * station's last stall, if later): a pressing trainee's server sends a local model or feedback every
 * physics step, an idle one's its state each status period (1 s by default). A forger cannot silence
 * the server; a restarted server's old self is silent (server_lost.sh) ... */
#define PALP_CLI_SERVER_QUIET_S 0.5
/* ... and then did not answer its accepted JOIN, sent again, within this long [s] (it answers at once:
 * its main thread waits on requests). palp_cli_station_session_closed waits for that answer. */
#define PALP_CLI_SERVER_ASK_S 0.1
/* A trainee that leaves within this long of a stall (or right out of one) first asks the
 * server to find it again: its accepted JOIN once more, waiting up to this long for the
 * answer. A stall past the participant's 1 s lease makes the server forget the station's
 * participant, and a LEAVE sent before it is found again is lost with the participant;
 * the session would then wait out station_grace and close as "not back" (docs/station.md,
 * "A stalled station"). */
#define PALP_CLI_LEAVE_WAIT_S 3.0

typedef struct palp_cli_join {
  int role;                 /* palp_Role */
  uint32_t phantom_id;
  uint32_t session_id;      /* viewers: 0 = newest session on the phantom */
  const char *user_name;
  int want_feedback;
  /* A position-driven trainee renders from the local models alone: no reader of the
   * Feedback summary is created, so the server's per-step summary is not sent to
   * this station (at 1 kHz physics, a second sample per step it only threw away). */
  int local_models_only;
  int want_deformation;
  double timeout;           /* [s] to wait for the reply (and, for viewers, for a session) */
} palp_cli_join;

/* Creates the participant on `domain` (CYCLONEDDS_URI must be set) and the
 * global endpoints. label goes into the station id ("host/pid/label"). */
int palp_cli_station_open(palp_cli_station *st, uint32_t domain, const char *label, char *err, size_t errlen);
/* As palp_cli_station_open, secured by sec (NULL or plain: not secured). A
 * secured station's id starts with its identity ("trainee/alice/host/pid/label")
 * and its requests go out in the identity's partition ("palp/trainee/alice"),
 * the only one its permissions allow; the server checks both. */
int palp_cli_station_open_secure(palp_cli_station *st, uint32_t domain, const char *label,
                                 const palp_dds_security *sec, char *err, size_t errlen);
void palp_cli_station_close(palp_cli_station *st);

/* Waits up to timeout [s] for phantom_id in the catalogue (0: any; the first
 * seen). On success *out is a copy the caller frees with palp_cli_phantom_free. In a session (a JOIN
 * bound its server) only the server's entry is taken, 0 meaning the session's phantom: other
 * participants' entries are dropped and counted (bind.ignored), and when only those came the error
 * names their participant (review s83 #1). */
int palp_cli_station_catalogue(palp_cli_station *st, uint32_t phantom_id, double timeout, palp_Phantom *out,
                               char *err, size_t errlen);

void palp_cli_phantom_free(palp_Phantom *p);

/* Sends a join and waits for the reply; on acceptance creates the session's
 * publisher/subscriber in its partition and the role's readers/writers. */
int palp_cli_station_join(palp_cli_station *st, const palp_cli_join *j, char *err, size_t errlen);
/* Disposes the request instance: the server closes/leaves the session now. Right after a
 * stall of this process a trainee first waits (up to PALP_CLI_LEAVE_WAIT_S) until the
 * server answers its JOIN again, so that the goodbye reaches a server that knows it, and
 * then until it answers the LEAVE (at least 1 s), before the disposal; when it does not
 * answer, st->goodbye_unanswered is set (the caller tells the user: the server may log the
 * session as "not back" after its station_grace) and the goodbye goes anyway. */
int palp_cli_station_leave(palp_cli_station *st);
/* This station's own work runs now (its haptic thread joined, its trace written): the time since its
 * last check is work, not a stall, for the leave that follows. A stall before it is noted as one. */
void palp_cli_station_alive(palp_cli_station *st);

/* Several servers on one domain (docs/deploy.md). The alive phantom called name
 * with the fewest active sessions, on server server_number (-1: any) and not on
 * exclude_server (-1: none); waits up to timeout [s], then 0.3 s more after the
 * first match for other servers' entries. */
int palp_cli_station_find_phantom(palp_cli_station *st, const char *name, int64_t server_number,
                                  int64_t exclude_server, double timeout, uint32_t *out_id, char *err, size_t errlen);
/* The number of the live server called server_name (palp_server_identity). */
int palp_cli_station_server_number(palp_cli_station *st, const char *server_name, double timeout, uint32_t *out,
                                   char *err, size_t errlen);
/* Drops the session's endpoints (after its server was lost), ready for another join. */
void palp_cli_station_end_session(palp_cli_station *st);

/* issue 13. The exercise the phantom runs (title, instructions, limits): 1 and *out
 * when there is one within timeout [s], 0 when not (a plain phantom, or since 2026-12-07 a phantom
 * other than the one joined: only its exercise is read), PALP_CLI_ESTOPPED when stopped. In a session
 * only the server's exercise is taken; other participants' are dropped and counted (review s83 #1). */
int palp_cli_station_exercise(palp_cli_station *st, uint32_t phantom_id, double timeout, palp_Exercise *out);
/* Sends a "lump here" mark at point [m] (the fingertip's contact point, world time t)
 * and returns its mark id (> 0), or withdraws mark_id (op palp_FINDING_WITHDRAW);
 * a negative code on failure. */
int palp_cli_station_mark(palp_cli_station *st, palp_vec3 point, double t);
int palp_cli_station_withdraw(palp_cli_station *st, uint32_t mark_id);
/* Non-blocking: 1 and the newest palp_finding_status when one came since the last call. */
int palp_cli_station_finding_status(palp_cli_station *st, palp_FindingStatus *out);
/* The session's debrief (palp_debrief), which the server writes once as an exercise session
 * closes: 1 and *out when it came within timeout [s], its lesions copied into lesions
 * [PALP_DEBRIEF_MAX_LESIONS] (out->lesion points there; checked by palp_dds_debrief_ok), 0 when
 * none came, a negative code when what came is malformed (err says why), PALP_CLI_ESTOPPED when the
 * wait was stopped (palp_cli_station.stop). */
#define PALP_DEBRIEF_MAX_LESIONS PALP_MAX_LESIONS
int palp_cli_station_debrief(palp_cli_station *st, double timeout, palp_Debrief *out, palp_DebriefLesion *lesions,
                             char *err, size_t errlen);
/* The session's score (palp_debrief_score), which the server writes after a debrief that told the
 * lesions, once it has graded the session from its log: 1 and *out when it came within timeout [s]
 * (checked by palp_dds_session_score_ok), 0 when none came, a negative code when what came is
 * malformed (err says why), PALP_CLI_ESTOPPED when stopped. */
int palp_cli_station_debrief_score(palp_cli_station *st, double timeout, palp_SessionScore *out, char *err,
                                   size_t errlen);
/* What the trainee is told of a score (the station's line after "[trainee NAME] "; her web page says
 * the same, web/www/js/trainee.js): "score: S of 100, passed|not passed (...). To work on: ... ." and,
 * from a log that lost records, " The session's log is incomplete: the score may be low."; or "no
 * score: REASON" when it was not graded. Returns buf. */
const char *palp_cli_score_text(const palp_SessionScore *m, char *buf, size_t len);

/* Non-blocking, but for a wait of up to PALP_CLI_SERVER_ASK_S for a silent server's answer when another
 * participant says it restarted: 1 and the reason when the session's state from its server changed to
 * closed, or when that other participant's word was not refuted by the server (palp_cli_server_bind; a
 * forged close is ignored). Call it about every 100 ms: a longer gap is taken for a stall of this process, after which
 * the station's JOIN is sent again (the server resumes a session it held for it; to a
 * station it never lost it only answers again) and a lapse of the server's lease that such a
 * stall explains (PALP_CLI_STALL_LAPSE_FRACTION) waits up to PALP_CLI_SERVER_WAIT_S for the server
 * to be found again; then a trainee asks the server (PALP_CLI_LOST_ASK_S, waited for here) and
 * takes its word for why the session closed, and only an unanswered question closes it as "server
 * lost". st->stalls counts the stalls. */
int palp_cli_station_session_closed(palp_cli_station *st, char *reason, size_t len);

/* 1 when the sample `info` describes, taken from `reader` (a reader of the session's server's topics),
 * was written by the session's server (palp_cli_server_bind), or when no JOIN bound a server yet; 0 when
 * by another participant or by a writer gone before the station knew it: the caller drops it, and it is
 * counted (st->bind.ignored) for palp_cli_station_foreign_news. */
int palp_cli_station_from_server(palp_cli_station *st, dds_entity_t reader, const dds_sample_info_t *info);
/* The samples other participants wrote into this session, for the station's user (2026-12-06): 1 the
 * first time some were dropped, with the line (after "[trainee NAME] ") in line and the participant as
 * palp_dds_participant_text names it in who (for the log); 0 otherwise: said once a session. Until the
 * session is over (closed, or left) it is held while the server has not been heard since the first was
 * dropped or another participant's claim that it restarted is unresolved (bind.suspect_ns): a restarted
 * server's reply, status or state comes before its restart shows (review s83 #5). Then it is said as an
 * intrusion when the server spoke since (it is there while another writes), as the restarted server's
 * samples when the session ended so, and plainly otherwise. */
int palp_cli_station_foreign_news(palp_cli_station *st, char *line, size_t len, char *who, size_t wholen);

/* A session whose server's log goes on losing records is said again at most this often [s]. */
#define PALP_CLI_LOG_SAY_S 60.0
/* The session log's news for the station's user (session 68), from what palp_cli_station_session_closed
 * read of the server's status (palp_dds_log_view): 1 and the line (after "[trainee NAME] ") when the
 * server's log lost records since this session was first listed in its status, at once and then at most
 * every PALP_CLI_LOG_SAY_S while the losses go on, or when it writes again after one was said; the words
 * are palp_dds_log_view_words' (palp-web's trainee page shows the same). 0 and "" otherwise: a server
 * that logs nothing, or lost nothing, says nothing. */
int palp_cli_station_log_news(palp_cli_station *st, char *line, size_t len);

#endif
