/*
 * palp_dds_strangers.h - plain DDS participants on a secured domain, found and named.
 *
 * A participant without a DDS Security identity (a station started without --pki and
 * --identity, another vendor's tool, a student's script) is ignored by every secured
 * participant: it sees nothing and is answered nothing. Unlike a refused certificate it
 * leaves no Cyclone warning, so until now the classroom's log had no trace of it and the
 * instructor no way to learn that a trainee's station was misconfigured.
 *
 * What a secured participant can see of it: its announcement (DCPSParticipant) and its GUID,
 * and no endpoint of it ever (its discovery of endpoints is refused). The builtin
 * authentication (DDS Security 1.1, 9.3.3) derives a secured participant's GUID prefix from
 * its certificate's subject with the first bit set; a plain participant's prefix starts with
 * its vendor id (0x01 0x10 Cyclone DDS, 0x01 0x0f Fast DDS), first bit clear (measured on
 * loopback: plain Cyclone 0110..., plain Fast DDS 010f..., secured alice d34f..., revoked
 * dave 95d9...). A plain Cyclone participant also announces __ProcessName, __Hostname and
 * __Pid, which a secured Cyclone 0.10.2 one does not. A peer is a stranger here when its
 * prefix's first bit is clear or it carries those properties, and `grace` after it was first
 * seen it still shows no endpoint (a secured peer shows its endpoints once authenticated, so
 * it is not named; a revoked one, first bit set, is the refusal table's). Each stranger is noted once into the
 * owner's refusal table (palp_dds_refusals.h, kind PALP_DDS_REFUSED_UNAUTHENTICATED), which
 * says it in the log, keeps it in the session log and counts a stranger that comes back
 * (a restarted station) as a repeat. Its name is what it says of itself ("palp-client on
 * host lab-07"): from the network, cut to size, unprintable bytes made '?'.
 *
 * Not named: a plain peer whose vendor starts its GUID prefix with the first bit set (RTI
 * Connext, by default, puts the host's address there) and sends none of the properties.
 * Bounded: PALP_DDS_STRANGER_SLOTS peers
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
 * and unprintable bytes made '?'; the process name loses its directories. With neither, from
 * its 12-byte GUID prefix (may be NULL): "a Fast DDS participant, GUID prefix 010f1a2b3c4d".
 * Pure. */
void palp_dds_stranger_name(const char *process, const char *host, const uint8_t *prefix, char *out, size_t len);
/* Whether a GUID prefix cannot be a secured participant's (DDS Security 9.3.3: first bit set). */
int palp_dds_guid_plain(const uint8_t prefix[12]);

#endif
