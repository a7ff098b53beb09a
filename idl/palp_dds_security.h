/*
 * palp_dds_security.h - DDS Security (Cyclone's built-in authentication, access
 * control and cryptography plugins) for every palp DDS process, and the naming
 * rules that let the access control plugin carry palp's own rules.
 *
 * A process is secured by an identity out of a directory made by
 * scripts/make-classroom-pki.sh: "KIND/NAME" with KIND trainee, instructor or
 * server. The participant is created with the dds.sec.* QoS properties naming
 * the classroom CA, the identity's certificate, key and signed permissions, the
 * signed governance and the CRL (docs/security.md).
 *
 * Cyclone DDS 0.10 does not expose a remote participant's certificate subject
 * through its C API (the identity token stays inside DDSI), so who a sample
 * comes from is read from what the permissions allow instead: each identity may
 * publish requests only in its own partition "palp/KIND/NAME", and a matched
 * publication's partition is checked by the access control plugin against the
 * remote's signed permissions before the reader ever matches it.
 */
#ifndef PALP_DDS_SECURITY_H
#define PALP_DDS_SECURITY_H

#include <stddef.h>
#include <stdint.h>

#include <dds/dds.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PALP_DDS_PKI_PATH_MAX 512
#define PALP_DDS_NAME_MAX 32 /* identity names: 1..31 of [a-z0-9_-] */

typedef enum palp_dds_id_kind {
  PALP_DDS_ID_NONE = 0, /* not secured */
  PALP_DDS_ID_SERVER,
  PALP_DDS_ID_TRAINEE,
  PALP_DDS_ID_INSTRUCTOR
} palp_dds_id_kind;

/* Days before an expiry palp warns of it (docs/security.md, "Keep in mind"). */
#define PALP_DDS_EXPIRY_WARN_DAYS 30

/* The permissions version this build's topics need: scripts/make-classroom-pki.sh's PERMISSIONS_VERSION,
 * which it writes into each identity's permissions ("palp permissions, version N"); test security_cli
 * checks the two agree. An identity whose permissions are older is warned of at start
 * (palp_dds_security.warning): the topics added since are refused to it. */
#define PALP_DDS_PERMISSIONS_VERSION 8

typedef struct palp_dds_security {
  palp_dds_id_kind kind;              /* PALP_DDS_ID_NONE: plain DDS */
  char name[PALP_DDS_NAME_MAX];
  char pki[PALP_DDS_PKI_PATH_MAX];    /* absolute directory of the classroom PKI */
  /* Set by palp_dds_security_init when the identity's certificate or the classroom CRL expires
   * within PALP_DDS_EXPIRY_WARN_DAYS or has expired (an expired CRL fails every handshake), or its
   * permissions are older than PALP_DDS_PERMISSIONS_VERSION: what and what to do, for the program
   * to log at its start. Empty otherwise. */
  char warning[1024];
} palp_dds_security;

/* "trainee", "instructor", "server" (NULL for NONE). */
const char *palp_dds_id_kind_name(palp_dds_id_kind kind);

/* Parses "KIND/NAME" ("server" alone means server/server). Returns 0 or
 * PALP_EINVAL with a message. */
int palp_dds_identity_parse(const char *identity, palp_dds_id_kind *kind, char *name, size_t namelen, char *err,
                            size_t errlen);

/* Fills sec for identity in the PKI directory pki and checks that every file the
 * plugins will read exists, the classroom CRL (crl.pem) included and read as a CRL: without it
 * revocation would be off (every role: each participant decides alone whom it admits).
 * pki NULL or identity NULL: sec is plain (returns 0). */
int palp_dds_security_init(palp_dds_security *sec, const char *pki, const char *identity, char *err, size_t errlen);

/* As palp_dds_security_init from the environment: PALP_PKI and PALP_IDENTITY
 * (both or neither). Returns 0 (plain when unset) or a negative code. */
int palp_dds_security_from_env(palp_dds_security *sec, char *err, size_t errlen);

/* Adds the dds.sec.* properties (plugins, CA, identity, permissions, governance,
 * CRL) to qos. Nothing when sec is NULL or plain. */
void palp_dds_security_qos(const palp_dds_security *sec, dds_qos_t *qos);

/* dds_create_participant with sec's properties (sec NULL or plain: none). */
dds_entity_t palp_dds_create_participant(dds_domainid_t domain, const palp_dds_security *sec);

/* The partition an identity publishes its session requests in: "palp/KIND/NAME". */
void palp_dds_request_partition(const palp_dds_security *sec, char *buf, size_t len);

/* The identity behind a request partition ("palp/trainee/alice"); 0 or PALP_EINVAL. */
int palp_dds_identity_from_partition(const char *partition, palp_dds_id_kind *kind, char *name, size_t namelen);

/* The session partition of a trainee identity's session: "palp/s/NAME/ID", which
 * that trainee's permissions allow (palp/s/NAME/ followed by anything) and no other trainee's do. */
void palp_dds_secure_session_partition(const char *name, uint32_t session_id, char *buf, size_t len);

/* Other DDS participants pp has discovered on its domain (alive, not pp itself), or a negative
 * code. Plain and secured participants see each other's announcements, nothing more. */
int palp_dds_peer_participants(dds_entity_t pp);

/* When nothing answered pp: "" if no other participant is on the domain (nothing is running);
 * else "; N other DDS participants ..." with what to check, for a plain participant (the
 * classroom may be secured: --pki/--identity) or a secured one (the same PKI, a valid
 * certificate). For the end of a "no answer" message; a buffer of PALP_DDS_HINT_MAX holds the
 * longest (a secured one is ~480 characters: 320 cut it before its last question, 2026-12-05),
 * and a message that ends with it wants PALP_DDS_HINT_MAX + 256. */
#define PALP_DDS_HINT_MAX 768
void palp_dds_unanswered_hint(dds_entity_t pp, const palp_dds_security *sec, char *buf, size_t len);

/* "on (identity KIND/NAME)" or "off", into buf (returned): how every palp program's log says whether
 * it runs secured. */
const char *palp_dds_security_state(const palp_dds_security *sec, char *buf, size_t len);

/* For the end of a "cannot create topic T" (or reader) message: "" on plain DDS; secured, that the
 * identity's permissions may not allow T (topic NULL: the process's topics) and how they are re-issued
 * (make-classroom-pki.sh DIR init). buf of PALP_DDS_HINT_MAX holds it. Returns buf. */
const char *palp_dds_refused_hint(const palp_dds_security *sec, const char *topic, char *buf, size_t len);

struct palp_dds_refusals;
/* Gives t the classroom's identities found under sec's PKI directory (KIND/NAME.cert.pem for the
 * trainees, instructors and the server; not the revoked ones), so that a peer refused for its
 * permissions is named by its identity (trainee/bob) instead of its GUID (palp_dds_refusals_set_names).
 * Returns how many were read (0 for a plain sec), or PALP_ENOMEM. */
int palp_dds_security_name_peers(const palp_dds_security *sec, struct palp_dds_refusals *t);

#ifdef __cplusplus
}
#endif
#endif
