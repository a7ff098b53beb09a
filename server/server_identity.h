/*
* server_identity.h - a server's identity on its DDS domain, so that several servers can
 * share one (docs/deploy.md, "Several servers on one domain").
 *
 * Each server announces {server_name, server_number, instance, start time, hosted
 * phantoms} on palp_server_identity (reliable, transient-local, keyed by name).
 * Every phantom and session id it hands out carries its number in the high bits
 * (PALP_DDS_ID), so ids never collide while numbers differ. At start a server
 * listens for wait_s for the identities already alive on the domain and refuses
 * to start if its name or number is taken; afterwards it keeps watching, and of
 * two servers that started at the same moment the younger stops (the older one
 * re-announces itself). Peers that appear or vanish are logged; a vanished
 * server's stations learn it from their session state (palp-client --rejoin).
 *
 * Start-up window: the younger gives way only within 5 s of its announcement (a
 * server started at the same moment is found by then; the sessions it may have
 * opened meanwhile from stations' durable requests close as it stops, as before).
 * Later, a claim of its name or number by an older
 * server is anomalous (on plain DDS one forged sample {its name, number 0,
 * started_unix_ns 0} used to stop the server and close every session): it is
 * warned about, naming the claimant, at most once per log_interval_s, and ignored;
 * the server announces itself again (at most once a second).
 */
#ifndef PALP_SRV_SERVER_IDENTITY_H
#define PALP_SRV_SERVER_IDENTITY_H

#include <stddef.h>
#include <stdint.h>

#include <dds/dds.h>

#include "palp_log.h"

typedef struct palp_srv_identity palp_srv_identity;

typedef struct palp_srv_identity_def {
  dds_entity_t participant;
  dds_entity_t topic;          /* PALP_TOPIC_SERVER_IDENTITY */
  const char *name;            /* server_name */
  uint32_t number;             /* server_number */
  const char *instance;        /* "host/pid" */
  int phantom_count;
  const uint32_t *phantom_id;  /* qualified ids */
  const char *const *phantom_name;
  double wait_s;               /* how long to listen for existing identities before announcing */
  double log_interval_s;       /* least time between two warnings of a late claim (0: 1 s) */
  int secured;                 /* DDS Security on: only server certificates may write identities */
  palp_log *log;               /* may be NULL */
} palp_srv_identity_def;

/* Listens, checks, announces. Returns NULL with a message in err (e.g. the name is
 * held by another live server) and *rc < 0. */
palp_srv_identity *palp_srv_identity_create(const palp_srv_identity_def *def, int *rc, char *err, size_t errlen);
/* Reads what changed (at most 64 samples): returns 0, or PALP_EINVAL with a message in err
 * when a conflicting server that started before this one appeared within the start-up
 * window (this one must stop). */
int palp_srv_identity_poll(palp_srv_identity *id, char *err, size_t errlen);
/* Other servers alive on the domain, as last polled (poll first for the newest). */
int palp_srv_identity_peers(const palp_srv_identity *id);
void palp_srv_identity_destroy(palp_srv_identity *id);

#endif
