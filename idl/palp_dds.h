/*
 * palp_dds.h - topic names, QoS and small helpers shared by every palp DDS
 * process (server, stations, tests, benchmarks).
 *
 * The topic names and QoS here are the public wire contract (docs/server.md).
 */
#ifndef PALP_DDS_H
#define PALP_DDS_H

#include <stddef.h>
#include <stdio.h>
#include <stdint.h>

#include <dds/dds.h>

#include "palp_types.h" /* generated from idl/palp_types.idl: palp_Contact, ... */

#ifdef __cplusplus
extern "C" {
#endif

typedef enum palp_dds_topic_kind {
  PALP_TOPIC_CATALOGUE = 0,
  PALP_TOPIC_SESSION_REQUEST,
  PALP_TOPIC_SESSION_REPLY,
  PALP_TOPIC_SESSION_STATE,
  PALP_TOPIC_CONTACT,
  PALP_TOPIC_FEEDBACK,
  PALP_TOPIC_DEFORMATION,
  PALP_TOPIC_SERVER_STATUS,
  PALP_TOPIC_LOCAL_MODEL, /* added with issue 11: local contact models for the station's haptic loop */
  PALP_TOPIC_SERVER_GUARD,
  PALP_TOPIC_SERVER_IDENTITY, /* added: several servers on one domain */
  PALP_TOPIC_STATION_REQUEST, /* added: a request keyed by 8 bytes, disposable by any vendor */
  PALP_TOPIC_EXERCISE,        /* added with issue 13: what a trainee may know of an exercise */
  PALP_TOPIC_FINDING,         /* added with issue 13: "lump here" marks, trainee -> server */
  PALP_TOPIC_FINDING_STATUS,  /* added with issue 13: the server's answer to the findings */
  PALP_TOPIC_DEBRIEF,         /* added 2026-12-05: what the trainee found, told at the session's end */
  PALP_TOPIC_SESSION_EXERCISE, /* added 2026-12-05: a session's exercise with its lesions, for instructors */
  PALP_TOPIC_SESSION_SCORE,   /* added 2026-12-05 (session 63): a closed session's automatic score, for instructors */
  PALP_TOPIC_DEBRIEF_SCORE,   /* added 2026-12-05 (session 64): that score, told to the trainee of a practice exercise */
  PALP_TOPIC_SESSION_LOG,     /* added 2026-12-06 (session 69): the records of a session its server's log lost */
  PALP_TOPIC_SESSION_CLOSED,  /* added 2026-12-06 (session 69): who a closed session was, for instructors */
  PALP_TOPIC_FINGER_SAMPLE,   /* added 2026-12-06 (session 71): the assessment's finger samples, touched triangles named */
  PALP_TOPIC_COUNT
} palp_dds_topic_kind;

/* Liveliness lease of every station writer [s]: automatic, so the DDS stack
 * asserts it; a station that vanishes is seen as not alive after ~this long. */
#define PALP_DDS_STATION_LEASE_S 0.5
/* The server's participant lease [s] as the shipped Cyclone configs set it (LeaseDuration: 1 s in
 * config/cyclonedds-loopback.xml, 3 s in cyclonedds-lab.xml.example): the shortest, so a station that
 * asks whether a stall of its own can have outlasted it never answers no when it could (a longer lease
 * only makes more stalls look like the cause: the station then waits longer for the server, as before;
 * client/station.h, PALP_CLI_STALL_LAPSE_FRACTION). */
#define PALP_DDS_SERVER_LEASE_S 1.0

/* Phantom and session ids are qualified by the server that hands them out:
 * server_number * 2^20 + the server's local id (palp_server_identity). */
#define PALP_DDS_ID_LOCAL_BITS 20
#define PALP_DDS_MAX_SERVER_NUMBER 4095u
#define PALP_DDS_ID(server_number, local) (((uint32_t)(server_number) << PALP_DDS_ID_LOCAL_BITS) | (uint32_t)(local))
#define PALP_DDS_ID_SERVER(id) ((uint32_t)(id) >> PALP_DDS_ID_LOCAL_BITS)
#define PALP_DDS_ID_LOCAL(id) ((uint32_t)(id) & ((1u << PALP_DDS_ID_LOCAL_BITS) - 1u))

/* The LocalModel.flags bits that put the model outside its valid range (docs/station.md): the
 * station, the bridge and the server's counts all read them with this one mask. */
#define PALP_DDS_LM_OUTSIDE (palp_LM_OUT_OF_RANGE | palp_LM_BEYOND_VALIDATED | palp_LM_GEL_LAW_RANGE)

/* A session's mark ids are its writers' own (a station and a palp-web trainee page each number from 1),
 * and the server refuses an id already made in the session: each writer's next mark takes an id above
 * any other writer's it has seen, but only one below this, so that a forged 2^32 - 1 cannot wrap the
 * next id to 0 (which the server refuses for good). */
#define PALP_DDS_MARK_ID_FOLLOW_MAX 65536u

/* Partition of a session's contact/feedback/deformation traffic. */
#define PALP_DDS_SESSION_PARTITION_FMT "palp/session/%u"
/* palp_finger_sample: its triangles are a sequence<long, 256> (idl/palp_types.idl), the session
 * log's PALP_DB_MAX_SAMPLE_TRIANGLES. */
#define PALP_FINGER_SAMPLE_TRIANGLES_MAX 256
/* palp_session_exercise: its json is a string<32767> (idl/palp_types.idl). */
#define PALP_SESSION_EXERCISE_JSON_MAX 32767

const char *palp_dds_topic_name(palp_dds_topic_kind kind);
/* 1 if the topic is written and read in a session's partition (PALP_DDS_SESSION_PARTITION_FMT),
 * its samples' first member the session_id; 0 for the default partition's topics. One list for
 * every tool that must know (palp-netem relays the session topics partition by partition). */
int palp_dds_topic_in_session(palp_dds_topic_kind kind);
const dds_topic_descriptor_t *palp_dds_topic_descriptor(palp_dds_topic_kind kind);

/* QoS for the topic and for both its readers and writers (caller deletes). */
dds_qos_t *palp_dds_qos(palp_dds_topic_kind kind);

/* Creates (or finds) the topic on participant pp with its QoS. */
dds_entity_t palp_dds_create_topic(dds_entity_t pp, palp_dds_topic_kind kind);

/* A reader's QoS for a topic: the topic's, except that a reader of findings bounds only the samples
 * per session (PALP_DDS_FINDING_READER_DEPTH), not the sessions. Cyclone 0.10 retries a reliable
 * sample a reader refuses for its limits on the delivery path: a peer writing findings under 64+
 * made-up session ids filled the 64 instances for as long as its writer lived, and every topic's
 * delivery to that process stalled (session 72: another session's trainee got 38 of 203 contacts to
 * the server in 5 s). The server's reader also drops other sessions' findings by a filter
 * (server/session.c). The writers keep their bound: a flood blocks at its own writer. Caller deletes
 * the QoS. */
#define PALP_DDS_FINDING_READER_DEPTH 256
dds_qos_t *palp_dds_reader_qos(palp_dds_topic_kind kind);

/* A reader/writer on `parent` (participant, subscriber or publisher) for a topic
 * made by palp_dds_create_topic, with the topic's QoS (a reader's: palp_dds_reader_qos). */
dds_entity_t palp_dds_create_reader(dds_entity_t parent, dds_entity_t topic, palp_dds_topic_kind kind);
dds_entity_t palp_dds_create_writer(dds_entity_t parent, dds_entity_t topic, palp_dds_topic_kind kind);

/* A display's palp_deformation reader: best-effort, newest sample only. The writer stays reliable
 * (the wire contract, and the recorder, which must see every frame, are unchanged); a display wants
 * the newest shape, and a reliable reader holds newer frames back behind a missing one until it is
 * repaired. In CI a page once received no frame through a whole 14 s press while the best-effort
 * contacts of the same session kept arriving (web_trainee_stiff; docs/server.md, docs/web.md). A lost resting
 * frame is repaired by the server, which sends a sleeping world's shape again every second while a
 * display watches (server/session.c). */
dds_entity_t palp_dds_create_display_reader(dds_entity_t parent, dds_entity_t topic);

/* Publisher / subscriber confined to one session's partition. */
dds_entity_t palp_dds_session_publisher(dds_entity_t pp, const char *partition);
dds_entity_t palp_dds_session_subscriber(dds_entity_t pp, const char *partition);
void palp_dds_session_partition(uint32_t session_id, char *buf, size_t len);

/* A peer refused by DDS Security, read off the warning Cyclone 0.10 logs for it
 * (its only trace: the refused peer gets no answer, the server no event). Measured
 * forms (docs/security.md, "Why a station was refused"):
 *   Process handshake failed: Certificate not valid: error: certificate revoked;
 *     subject: /O=palp/OU=trainee/CN=fd(code: 200)
 *   (also "Validate remote identity", "Begin handshake request" / "reply failed")
 *   Could not get remote participant GUID permissions from plugin: ... Verify error:
 *     self-signed certificate\n(code: 127)
 * The subject and the reason come from the peer's certificate, so from the network:
 * they are cut to size and anything unprintable becomes '?'. */
typedef enum palp_dds_refusal_kind {
  PALP_DDS_REFUSED_HANDSHAKE = 1,   /* authentication: its identity certificate */
  PALP_DDS_REFUSED_PERMISSIONS = 2, /* access control: its permissions document */
  PALP_DDS_REFUSED_UNAUTHENTICATED = 3, /* no identity at all: a plain DDS participant on a secured
                                           domain (palp_dds_strangers.h; no Cyclone line says it) */
} palp_dds_refusal_kind;
/* "at the handshake", "for its permissions", "without an identity": how palp's lines say it. */
const char *palp_dds_refusal_kind_words(palp_dds_refusal_kind kind);
/* "handshake", "permissions", "unauthenticated": the word the session log's events and
 * palp-web's dashboard carry. */
const char *palp_dds_refusal_kind_name(palp_dds_refusal_kind kind);
#define PALP_DDS_REFUSAL_WHO 96
/* How `who` begins when a certificate the handshake refused before its chain to the classroom CA
 * verified names a classroom identity: "an unverified certificate claiming trainee/alice". */
#define PALP_DDS_UNVERIFIED_CLAIM "an unverified certificate claiming "
#define PALP_DDS_REFUSAL_WHY 160
typedef struct palp_dds_refusal {
  palp_dds_refusal_kind kind;
  /* "trainee/dave" for palp's subject /O=palp/OU=trainee/CN=dave (the name
   * palp_dds_security uses) when the certificate's chain to the classroom CA verified (revoked,
   * expired, not yet valid), "an unverified certificate claiming trainee/dave" when not, another
   * subject as written, or "participant GUID". */
  char who[PALP_DDS_REFUSAL_WHO];
  /* "certificate revoked", "certificate has expired", "permissions not signed by
   * the classroom (self-signed certificate)", or Cyclone's text, shortened. */
  char why[PALP_DDS_REFUSAL_WHY];
} palp_dds_refusal;
/* 1 and *out filled when msg[0..len) is such a line; 0 for any other line. */
int palp_dds_refusal_parse(const char *msg, size_t len, palp_dds_refusal *out);
/* 1 when msg[0..len) is Cyclone 0.10.2's "Remote secure participant GUID not allowed". Cyclone says it
 * when no local participant matches a secured peer's announcement (ddsi_proxy_participant_has_pp_match):
 * either none exists yet (the domain's receive threads run while the participant and its security
 * plugins are still being made, ~0.1 s at start; the peer's next announcement matches), or one differs
 * in its governance's attributes, which Cyclone says first in a line of its own ("match
 * remote_participant ... security_attributes mismatch: ...") that stays printed. Pure. */
int palp_dds_startup_race(const char *msg, size_t len);
/* src[0..n) into dst (size cap, always terminated when cap > 0), each unprintable byte as '?':
 * text from the network (a certificate, a peer's announcement) kept to one log line. */
void palp_dds_copy_printable(char *dst, size_t cap, const char *src, size_t n);
/* A certificate's subject s[0..n) as palp names the peer: palp's /O=palp/OU=KIND/CN=NAME
 * (make-classroom-pki.sh) as "KIND/NAME", any other subject as written (printable). */
void palp_dds_subject_name(char *who, size_t cap, const char *s, size_t n);

/* Cyclone prints a warning line per malformed sample (e.g. an out-of-range enum
 * fails deserialisation): a hostile peer could fill a disk with them. This sink
 * passes at most `lines` per `window_ns` to `out` and counts the rest; it reports
 * the count suppressed when the next window opens. Cyclone's log sink is
 * process-wide: install one limiter per process and remove it before freeing. */
typedef struct palp_dds_log_limit {
  void *lock;          /* pthread_mutex_t, allocated by install */
  FILE *out;
  int lines;
  int64_t window_ns;
  int64_t window_start_ns;
  int printed_in_window;
  uint64_t suppressed_in_window;
  uint64_t printed, suppressed; /* totals since install */
  uint64_t races;               /* palp_dds_startup_race lines, not printed (totals since install) */
  /* Refusals by DDS Security (below) go here instead of `out` once set. */
  void (*on_refusal)(void *arg, const struct palp_dds_refusal *r);
  void *refusal_arg;
} palp_dds_log_limit;
int palp_dds_log_limit_install(palp_dds_log_limit *l, FILE *out, int lines, double window_s);
/* After install: hands each refusal line (palp_dds_refusal_parse) to fn instead of
 * printing it. Cyclone logs one a second for as long as a refused peer retries, so
 * the owner throttles them per peer and reason (server/refusals.c). */
void palp_dds_log_limit_on_refusal(palp_dds_log_limit *l,
                                   void (*fn)(void *arg, const struct palp_dds_refusal *r), void *arg);
void palp_dds_log_limit_remove(palp_dds_log_limit *l);
void palp_dds_log_limit_counts(palp_dds_log_limit *l, uint64_t *printed, uint64_t *suppressed);

/* Points CYCLONEDDS_URI at the config file path unless the environment already
 * sets it. Programs use palp_app_use_dds_config (app/palp_app.h), which adds
 * --dds-config and the installed default; tests pass PALP_DDS_DEFAULT_CONFIG.
 * Returns 0 or a negative PALP_E* code (path NULL, or the file does not exist). */
int palp_dds_use_config(const char *path);

/* CLOCK_MONOTONIC in ns; shared by every process on the host, so a contact's
 * source time and its feedback's receive time compare directly. */
int64_t palp_dds_now_ns(void);

/* An Exercise's pressure bands as the assessment reads them (palp_band, src/palp_assess.h; out:
 * PALP_BAND_COUNT of them, filled either way). 1 when every band has a bound and every bound is
 * finite, >= 0 and ordered; 0 when not, and a reader keeps its own bands (palp-web its force
 * gauge's, the station no band name). */
struct palp_band;
int palp_dds_exercise_bands(const palp_Exercise *ex, struct palp_band *out);

/* A debrief (palp_debrief) as a reader may use it: a known level; at most PALP_MAX_LESIONS
 * lesions, listed only at DEBRIEF_LESIONS and then all of them, each place, depth and size
 * finite and >= 0; found <= lesions and, listed, the count of found_by. found_by is not checked
 * against a station's own numbering: a mark made from palp-web's page has the bridge's number.
 * 1 when it holds, 0 when not (the station and palp-web both check with it). */
int palp_dds_debrief_ok(const palp_Debrief *d);

/* A palp_finger_sample (session 71) as its readers may use it: a finger 0..3, finite time, radius > 0,
 * finite device, proxy, force and contact point, area >= 0, at most PALP_FINGER_SAMPLE_TRIANGLES_MAX
 * ids; with mesh_triangles >= 0, every id a triangle of that mesh (the recorder logs the ids as they
 * are; the station and palp-web skip those that are not dome triangles). 1 when it holds, 0 when not
 * (the station, palp-web and palp-recorder all check with it). */
int palp_dds_finger_sample_ok(const palp_FingerSample *m, int mesh_triangles);

/* A catalogue entry (palp_catalogue) as its readers may use it: vertex and triangle counts within
 * bounds (no triangles at all only with triangles_optional: a reader that logs the rest mesh and
 * marks no coverage without them), every triangle index a vertex, the dome triangle count and top
 * vertex in range, radius and rest positions finite. Returns 0, or PALP_EINVAL with the reason in err
 * (the stations check with it as palp_cli_phantom_check, palp-recorder before it keeps an entry). */
int palp_dds_phantom_check(const palp_Phantom *ph, int triangles_optional, char *err, size_t errlen);
/* Who wrote a sample taken from `reader`, for a log line: its writer's participant GUID as
 * "participant xxxxxxxx:xxxxxxxx:xxxxxxxx" (38 characters), or "a writer already gone" when the
 * writer (pub, 0: none) is no longer matched. Returns out. */
char *palp_dds_writer_participant_text(dds_entity_t reader, dds_instance_handle_t pub, char *out, size_t len);
/* The participant of writer `pub` (a sample's publication_handle) matched to `reader`: 0 and its GUID
 * (discovery's participant_key) in *out; PALP_EINVAL when pub is 0 or no longer matched (a writer already
 * gone is nobody's). One dds_get_matched_publication_data: a caller that asks per sample caches the
 * answer by pub (Cyclone never reuses a handle in a process). */
int palp_dds_writer_participant(dds_entity_t reader, dds_instance_handle_t pub, dds_guid_t *out);
/* A participant's GUID as palp's lines name it: "participant xxxxxxxx:xxxxxxxx:xxxxxxxx" (its prefix,
 * 38 characters). Returns out. */
char *palp_dds_participant_text(const dds_guid_t *g, char *out, size_t len);

/* A session score (palp_session_score) as a reader may use it: a known status; GRADED: score in
 * [0, 100], each component in [0, 1], each coverage in [0, 1], found <= lesions, duration and
 * peak force finite and >= 0, a known pattern name. 1 when it holds, 0 when not (palp-web checks). */
int palp_dds_session_score_ok(const palp_SessionScore *m);

/* A Finding as src/palp_finding_answers.h pairs it with the server's answer (palp-recorder, palp-web).
 * The point is copied as sent; a reader that uses it checks it. */
struct palp_finding_sent;
void palp_dds_finding_sent(const palp_Finding *m, struct palp_finding_sent *out);

#ifdef __cplusplus
}
#endif
#endif
