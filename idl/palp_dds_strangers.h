/*
 * palp_dds_strangers.h - plain DDS participants on a secured domain, found and named.
 *
 * A participant without a DDS Security identity (a station started without --pki and
 * --identity, another vendor's tool, a student's script) is ignored by every secured
 * participant: it sees nothing and is answered nothing. Unlike a refused certificate it
 * leaves no Cyclone warning, so until now the classroom's log had no trace of it and the
 * instructor no way to learn that a trainee's station was misconfigured.
 *
 * What a secured participant can see of it: its announcement (DCPSParticipant), which a
 * plain Cyclone participant fills with the properties __ProcessName, __Hostname and
 * __Pid, and which a secured Cyclone 0.10.2 participant sends without them (measured,
 * docs/security.md); and no endpoint of it ever (its discovery of endpoints is refused).
 * A peer is a stranger here when it carries those properties and, `grace` after it was
 * first seen, still shows no endpoint (a secured peer that carried them would show its
 * endpoints once authenticated, so it is not named). Each stranger is noted once into the
 * owner's refusal table (palp_dds_refusals.h, kind PALP_DDS_REFUSED_UNAUTHENTICATED), which
 * says it in the log, keeps it in the session log and counts a stranger that comes back
 * (a restarted station) as a repeat. Its name is what it says of itself ("palp-client on
 * host lab-07"): from the network, cut to size, unprintable bytes made '?'.
 *
 * A plain peer from another vendor that sends none of these properties is not named
 * (Fast DDS sends its own): a documented gap. Bounded: PALP_DDS_STRANGER_SLOTS peers
 * followed at once, builtin-topic samples of peers gone taken out each tick. Not
 * thread-safe: the owner's loop calls it.
 */
#ifndef PALP_DDS_STRANGERS_H
#define PALP_DDS_STRANGERS_H

#include <stdint.h>

#include "dds/dds.h"
#include "palp_dds_refusals.h"

#define PALP_DDS_STRANGER_SLOTS 32
#define PALP_DDS_STRANGER_GRACE_S 3.0 /* [s]: authentication on loopback takes ~0.1-1 s */
#define PALP_DDS_STRANGER_READ 4096   /* builtin samples read per topic per tick */

typedef struct palp_dds_stranger_slot {
  dds_guid_t key;
  int64_t first_ns;
  int used, said, seen;
} palp_dds_stranger_slot;

typedef struct palp_dds_strangers {
  dds_entity_t rd[3]; /* DCPSParticipant, DCPSPublication, DCPSSubscription readers (owned) */
  dds_guid_t me;
  int64_t grace_ns;
  uint64_t named;     /* strangers noted so far */
  void **ptr;         /* [PALP_DDS_STRANGER_READ] loans */
  dds_sample_info_t *info;
  palp_dds_stranger_slot slot[PALP_DDS_STRANGER_SLOTS];
} palp_dds_strangers;

/* Readers on pp's domain. 0, or PALP_EIO / PALP_ENOMEM (nothing to destroy then). */
int palp_dds_strangers_init(palp_dds_strangers *s, dds_entity_t pp, double grace_s);
/* Looks at the domain's participants now (call it about once a second) and notes each new
 * stranger into t. Returns how many it noted in this call (>= 0). */
int palp_dds_strangers_tick(palp_dds_strangers *s, palp_dds_refusals *t, int64_t now_ns);
void palp_dds_strangers_destroy(palp_dds_strangers *s);

/* The name a stranger gets from its announced properties (any may be NULL): "palp-client on
 * host lab-07", "a participant on host lab-07", "palp-client", each part cut to 40 bytes
 * and unprintable bytes made '?'; the process name loses its directories. Pure. */
void palp_dds_stranger_name(const char *process, const char *host, char *out, size_t len);

#endif
