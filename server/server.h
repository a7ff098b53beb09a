/*
 * server.h - the classroom server: hosts phantoms, answers session requests,
 * runs each trainee's session on the tick pool and publishes catalogue, session
 * states and server status over DDS.
 *
 * Threads: the caller's thread runs palp_srv_run (a waitset loop over session
 * requests, a guard condition for stop, and a timeout for the status period);
 * the tick pool (ticker.h) steps the sessions. palp_srv_request_stop may be
 * called from any thread, not from a signal handler: main.c's handler writes the
 * signal's number into a pipe that a signal thread reads and calls it from.
 */
#ifndef PALP_SRV_SERVER_H
#define PALP_SRV_SERVER_H

#include <stdint.h>
#include <stdio.h>

#include "config.h"
#include "events.h"
#include "palp.h"
#include "palp_log.h"
#include "palp_types.h" /* palp_Phantom */

typedef struct palp_srv palp_srv;

typedef struct palp_srv_def {
  palp_srv_config cfg;
  const palp_srv_events *events; /* may be NULL; must outlive the server */
  int verbose;                   /* log joins/leaves (also: log level debug) */
  palp_log *log;                 /* may be NULL (stderr); must outlive the server */
  double identity_wait_s;        /* listen this long for servers already on the domain before
                                    announcing (identity.h); 0: announce at once */
  uint32_t session_local_max;    /* local session ids run 1..this and wrap (0: 2^20 - 1, the wire's
                                    PALP_DDS_ID_LOCAL_BITS); smaller only for tests of the wrap */
} palp_srv_def;

/* Loads every phantom's scene, creates the DDS participant (CYCLONEDDS_URI must
 * be set by the caller, see palp_dds_use_config) and starts the tick pool.
 * On failure returns NULL, *rc < 0 and a message in err. */
palp_srv *palp_srv_create(const palp_srv_def *def, int *rc, char *err, size_t errlen);
/* Runs until palp_srv_request_stop or, when duration > 0, for duration [s];
 * then closes every session ("server shutdown"). Returns 0 or a negative code. */
int palp_srv_run(palp_srv *srv, double duration);
void palp_srv_request_stop(palp_srv *srv);
/* Per-session table of every session the server ran (open ones too). */
void palp_srv_print_summary(const palp_srv *srv, FILE *out);
/* Sessions open now; any thread. */
int palp_srv_open_sessions(const palp_srv *srv);
/* Secured: session requests refused because they were not the sender's own
 * (another identity's station id, user name or disposal); any thread. */
uint64_t palp_srv_refused_requests(palp_srv *srv);
/* Disposes of session-request keys no admitted request holds (never written, or refused past
 * stations_per_writer): a flood (each an instance the request reader
 * keeps while its writer lives; the server names the writer in its log); any thread. */
uint64_t palp_srv_request_strays(palp_srv *srv);
/* Secured: participants DDS Security refused (revoked, expired or foreign
 * certificate; permissions not the classroom's), counted from Cyclone's warnings
 * (idl/palp_dds_refusals.h); `who` gets "trainee/dave: certificate revoked (31x); ..."
 * when not NULL. Any thread. */
uint64_t palp_srv_security_refusals(palp_srv *srv, char *who, size_t len);
void palp_srv_destroy(palp_srv *srv);

/* What the start does to hosted phantom `index` of cfg (phantoms, then exercises) once its scene
 * is loaded, and what `palp-server --check` does too: the scene steps at the entry's physics rate
 * (pc->physics_rate_hz, 0: the server's tick_rate_hz; set to the rate used) with the rebuild lag
 * and blend of that step, must have force feedback and room for a station's fingers, and its
 * template world is built into *world (the caller destroys it). pc is the entry (its scene_path
 * the exercise's phantom for an exercise). On failure returns < 0 and a message that names the
 * entry and, when the rate is the cause, its key. */
int palp_srv_prepare_phantom(const palp_srv_config *cfg, int index, palp_srv_phantom_cfg *pc, palp_scene *scene,
                             palp_world **world, char *err, size_t errlen);

/* DDS Security as the start takes it, checked as --check checks it (before the session log is made):
 * none without a PKI directory (cfg->security_pki empty: 0, *sec zeroed); otherwise an identity
 * named, a domain in the governance's 0-PALP_SRV_SECURED_DOMAIN_MAX, the identity's files readable
 * (palp_dds_security_init) and of a server. < 0 with the reason in msg. */
#define PALP_SRV_SECURED_DOMAIN_MAX 230
struct palp_dds_security;
int palp_srv_security_prepare(const palp_srv_config *cfg, struct palp_dds_security *sec, char *msg, size_t msglen);

/* A catalogue entry's mesh (palp_catalogue) as the server publishes a phantom's: its rest
 * positions into rest (m->vertex_count) and triangles into tri (3 m->triangle_count, the dome's
 * first), buffers the caller owns and msg then points to; its top vertex and dome triangle count.
 * The stations and palp-recorder check it with palp_dds_phantom_check: test server_phantom_bound
 * passes the largest mesh a scene can ask for (PALP_MESH_MAX_VERTICES) through both. */
void palp_srv_catalogue_mesh(const palp_mesh *m, palp_Vec3 *rest, int32_t *tri, palp_Phantom *msg);

#endif
