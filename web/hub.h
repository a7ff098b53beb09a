/*
 * hub.h - the DDS side of palp-web (palp_web_hub): one viewer participant that reads the
 * catalogue, session states, server status and every session partition's contact, feedback and
 * deformation, and keeps, per item, the newest message for browsers ready to send.
 *
 * Latest value, not a queue: each item (a phantom, the session list, the status, a session's
 * deformation and live data) has a version; a browser's cursor remembers what it was sent, and
 * palp_web_hub_next returns the next item it has not seen. A slow browser skips frames, memory
 * stays bounded, and the DDS thread never waits for a socket.
 *
 * Writes to DDS: the bridge's own viewer requests (join a followed session as a visual station so
 * that the server streams its deformation, leave it when no page follows it), and one thing a
 * browser may ask for: a trainee page bound to an exercise session may mark a finding ("lump
 * here", at the fingertip's contact point the bridge holds) or withdraw its last one. Nothing else
 * a browser sends reaches DDS (docs/web.md).
 */
#ifndef PALP_WEB_HUB_H
#define PALP_WEB_HUB_H

#include <stddef.h>
#include <stdint.h>

#include "coverage.h"
#include "palp.h" /* PALP_MESH_MAX_VERTICES, a constant */
#include "palp_dds_refusals.h"
#include "palp_dds_security.h"
#include "palp_log.h"

#define PALP_WEB_MAX_PHANTOMS 16
#define PALP_WEB_MAX_SESSIONS 64
/* The largest catalogue mesh the bridge takes: the largest a palp-server can publish (a scene's
 * mesh.vertex_count, at most PALP_MESH_MAX_VERTICES by palp_mesh_create, the stations' and
 * palp-recorder's bound too since 2026-12-06; test_web_unit checks that the mesh is made) and the
 * triangles of a closed surface of that many vertices (2V - 4). The shipped phantoms have 338 and
 * 1300 vertices. A larger mesh is no server's: refused, its publisher named in the log once
 * (docs/web.md). */
#define PALP_WEB_PHANTOM_MAX_VERTICES PALP_MESH_MAX_VERTICES
#define PALP_WEB_PHANTOM_MAX_TRIANGLES (2 * PALP_WEB_PHANTOM_MAX_VERTICES)

typedef struct palp_web_hub_def {
  uint32_t domain;
  int join;              /* 1: join followed sessions as a visual station; 0: read only what is published */
  int read_feedback;     /* 1: read a session's feedback while a position-driven finger presses (its force) */
  double dashboard_hz;   /* deformation frames per second and session to a dashboard */
  double live_hz;        /* live (force, fingers, coverage) messages per second to a trainee page */
  double scale_mm;       /* the pages' largest colour scale: 0 .. scale_mm of displacement */
  double scale_min_mm;   /* their smallest: a page's scale starts here and grows with the session's
                          * deepest displacement (equal to scale_mm: one fixed scale) */
  double linger_s;       /* stay joined this long after the last page stopped following */
  palp_web_bands bands;
  palp_log *log;         /* main's (app/palp_log.h); NULL = stderr */
  /* DDS Security (docs/security.md, docs/web.md): kind PALP_DDS_ID_NONE (zeroed) joins plain DDS;
   * secured, the bridge needs an instructor identity, the one kind whose permissions read every
   * session (palp/s/TRAINEE/ID); it then joins sessions as that instructor's visual station. */
  palp_dds_security sec;
  /* The peers DDS Security refused (main's table, idl/palp_dds_refusals.h; NULL: none): listed
   * in the dashboard's status, so the instructor sees who cannot join and why. */
  palp_dds_refusals *refusals;
  /* 1 (default): read each exercise session's exercise, lesions included (palp_session_exercise:
   * the server writes it for instructors only), and its findings, and send an instructor's
   * dashboard where the hidden lumps are and which of them the trainee's marks found, live
   * (docs/web.md, "The hidden lumps"). 0 (--no-answers): a bridge whose dashboard must not show
   * them (one projected in the room) reads neither. */
  int answers;
} palp_web_hub_def;

palp_web_hub_def palp_web_hub_default_def(void);

typedef struct palp_web_hub palp_web_hub;
typedef void (*palp_web_wake_fn)(void *ctx);

enum { PALP_WEB_FOLLOW_NONE = 0, PALP_WEB_FOLLOW_SESSION = 1, PALP_WEB_FOLLOW_ALL = 2 };

/* What one browser connection has been sent. */
typedef struct palp_web_cursor {
  int mode;           /* PALP_WEB_FOLLOW_* */
  uint32_t follow;    /* session id (FOLLOW_SESSION) */
  int hello_sent;
  uint64_t phantom_ver[PALP_WEB_MAX_PHANTOMS];
  uint64_t sessions_ver, status_ver;
  uint64_t deform_ver[PALP_WEB_MAX_SESSIONS], live_ver[PALP_WEB_MAX_SESSIONS];
  int64_t deform_sent_ns[PALP_WEB_MAX_SESSIONS];
  uint64_t exercises_ver;
  /* an exercise session's hidden lumps and marks (palp_web_hub_next sends them only to an
   * instructor's page following every session: the dashboard) */
  uint64_t answers_ver[PALP_WEB_MAX_SESSIONS];
  /* the newest of the ended exercise sessions' last answers this page was sent (the dashboard only) */
  uint64_t ended_answers_ver;
  /* the newest of the closed exercise sessions' scores this page was sent: the dashboard all of them
   * (session 63), a trainee page its own session's where the server told her it (session 64) */
  uint64_t scores_ver;
  /* a session's pressed-skin map (palp_web_hub_next sends it to pages following every session) */
  uint64_t cover_ver[PALP_WEB_MAX_SESSIONS];
  /* {"trainee": ID}: this page is that session's trainee page (the newest binding wins); only a
   * bound page may send findings. 0: a viewer (dashboard, observer). */
  uint32_t trainee;
  uint64_t bind_seq;
  /* "" (an instructor's page, or no tokens): every session. A trainee's name (the page gave that
   * trainee's token, serve.c): only that trainee's sessions are listed and may be followed, no
   * dashboard, no server status; set after palp_web_hub_attach. */
  char scope[32];
  /* the newest debrief (palp_debrief) this page was sent: it is sent those of its own trainee session,
   * or, an instructor's page, of the sessions it follows, that come after it attached (debrief_from,
   * the hub's version then); an instructor's page following every session (the dashboard) is also
   * sent those the hub still holds from before (palp_web_hub_next) */
  uint64_t debrief_ver, debrief_from;
  /* the session this page followed before its last change of follow (0: none): an instructor's page
   * lets go of a session as its CLOSED state arrives, which may come before its debrief */
  uint32_t followed;
  /* the answer to this page's last finding request, sent before anything else */
  char reply[320];
  size_t reply_len;
} palp_web_cursor;

typedef struct palp_web_hub_stats {
  uint64_t catalogue, states, statuses, contacts, feedbacks, deformations, local_models; /* DDS samples taken */
  uint64_t finger_samples; /* palp_finger_sample samples taken (session 71) */
  uint64_t dropped;   /* samples refused: malformed, or no room (sessions, exercises, memory) */
  uint64_t catalogue_refused; /* of them, catalogue entries refused (malformed, or a mesh beyond
                               * PALP_WEB_PHANTOM_MAX_VERTICES); each publisher's first is logged */
  uint64_t no_session; /* samples of a session the bridge has no state for: benign when it has just
                        * opened (its first contacts can overtake its state) or just closed */
  uint64_t rejected;   /* stream samples of a new key refused at the readers' instance bound (a flood of
                        * disposes of made-up keys, unsecured; Cyclone's sample-rejected status) */
  uint64_t finding_strays, finding_renewals; /* disposes of finding keys of sessions it does not follow, and how
                                              * often the findings reader was made anew for them (a flood) */
  uint64_t stream_strays, stream_renewals; /* disposes of stream keys the gate would not pass, and how often a
                                            * stream reader was made anew for them or for samples refused at its
                                            * bound (a flood; web/hub.c, renew_stream) */
  uint64_t stream_renewals_failed;         /* a new stream reader that could not be made (tried again later) */
  uint64_t foreign;    /* contacts and findings (disposes too) naming a session from a writer outside its partition (a
                        * trainee forging another's session id, idl/palp_dds_origin.h): dropped */
  uint64_t not_server; /* samples of a session's server topics (feedback, deformation, local models, finger samples,
                        * finding answers, debriefs, told scores, log losses) from another participant than the one
                        * whose state opened it, the latest: dropped (2026-12-07) */
  uint64_t joins, leaves, join_rejected;
  uint64_t rejoins; /* JOINs sent again to a server whose state counted no visual station, or after a stall of the
                     * bridge's own (web/hub.c, rejoin_if_dropped) */
  uint64_t stalls;  /* turns of the DDS thread 0.3 s or more after the last (palp-web not run: STALL_NS) */
  uint64_t exercises, finding_statuses;            /* DDS samples taken */
  uint64_t debriefs;                               /* palp_debrief samples taken (2026-12-05) */
  uint64_t session_exercises, findings_read;       /* palp_session_exercise, palp_finding samples taken */
  uint64_t scores;                                 /* palp_session_score samples taken (session 63) */
  uint64_t told_scores;                            /* palp_debrief_score samples taken (session 64) */
  uint64_t session_logs;                           /* palp_session_log samples taken (session 69) */
  uint64_t closed_sessions;                        /* palp_session_closed samples taken (session 69) */
  uint64_t findings_unanswered;                    /* findings whose answer the bridge did not see */
  uint64_t findings_written, findings_refused;     /* browser finding requests */
  uint64_t late_haptic, lost_haptic;               /* local models late / missing, all sessions */
  /* A closed session let go of (2026-12-07): the longest the DDS thread spent on one [s]; its request and
   * findings writers and feedback reader, deleted by the reaper (idl/palp_dds_reaper.h): deleted, still
   * to delete, and the longest single delete [s] (a writer waits for its readers' acknowledgements) */
  double free_longest_s;
  uint64_t reaped;
  int reap_pending;
  double reap_longest_s;
  int sessions_open, clients;
} palp_web_hub_stats;

/* Creates the participant and endpoints (CYCLONEDDS_URI must be set). NULL and a message in err
 * on failure. */
palp_web_hub *palp_web_hub_create(const palp_web_hub_def *def, char *err, size_t errlen);
/* Starts the DDS thread; wake(ctx) is called from it whenever something new is ready (and at
 * least every 100 ms), from that thread. 0 or a negative PALP_E* code. */
int palp_web_hub_start(palp_web_hub *h, palp_web_wake_fn wake, void *ctx);
/* Stops the thread and leaves every joined session. */
void palp_web_hub_stop(palp_web_hub *h);
void palp_web_hub_destroy(palp_web_hub *h);
void palp_web_hub_stats_get(palp_web_hub *h, palp_web_hub_stats *out);
/* Whether the bridge's reader of a session topic (PALP_TOPIC_CONTACT, _DEFORMATION, _LOCAL_MODEL,
 * _FINGER_SAMPLE, _FINDING (with answers), _FINDING_STATUS, _DEBRIEF, _DEBRIEF_SCORE or _SESSION_LOG, as
 * palp_dds_topic_kind;
 * the finger where the key has one) holds an instance of (session, finger), itself (not
 * another entity of the process): 1 or 0, or PALP_EINVAL for another topic. For tests of its
 * filters and for diagnostics; safe from any thread while the hub runs (it takes the hub's lock, under
 * which the DDS thread makes the findings reader anew). */
int palp_web_hub_has_instance(palp_web_hub *h, int topic, uint32_t session_id, unsigned finger);

/* A browser connection: attach when it opens (PALP_EFULL at max_clients), detach when it closes. */
int palp_web_hub_attach(palp_web_hub *h, palp_web_cursor *c, int max_clients);
void palp_web_hub_detach(palp_web_hub *h, palp_web_cursor *c);
/* Scopes an attached cursor to one trainee's sessions (cursor.scope), under the hub's lock. */
void palp_web_hub_scope(palp_web_hub *h, palp_web_cursor *c, const char *trainee);

/* A control message from a browser (at most 256 bytes of JSON, one key): {"follow": ID} follows one
 * session, {"follow": "all"} every session (the dashboard), {"follow": null} none; {"trainee": ID}
 * binds this connection as that session's trainee page (and follows it; a bound page may follow
 * nothing else); {"finding": "mark"} / {"finding": "withdraw"} asks to mark a finding at the
 * fingertip's contact point or withdraw this session's last mark: checked (bound trainee page,
 * exercise running, touching, rate) and answered with a "finding_reply" message to this page
 * either way. 0; 1 for a finding refused (answered); PALP_EINVAL for anything malformed, and for a
 * scoped page (cursor.scope) asking for every session or another trainee's (the caller counts it;
 * no answer). */
int palp_web_hub_control(palp_web_hub *h, palp_web_cursor *c, const char *msg, size_t len);

/* The next message this cursor has not been sent: *buf is malloc'ed with `pre` spare bytes
 * before the payload (libwebsockets' LWS_PRE), *len the payload length, *binary 1 for a
 * deformation frame. Returns 1 with a message, 0 when the cursor is up to date, PALP_ENOMEM. */
int palp_web_hub_next(palp_web_hub *h, palp_web_cursor *c, size_t pre, unsigned char **buf, size_t *len,
                      int *binary);

/* Binary deformation frame (little-endian), as sent to the pages:
 *   uint32 magic 'PDEF' (0x46454450), uint32 session_id, uint32 phantom_id, uint32 vertex count n,
 *   float64 frame, float64 sim_time [s], then n x 3 float32 displacement from rest [m]. */
#define PALP_WEB_DEFORM_MAGIC 0x46454450u
#define PALP_WEB_DEFORM_HEADER 32

#endif
