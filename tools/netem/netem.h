/*
 * netem.h - a user-space network emulator for palp: a DDS-level relay between
 * two DDS domains on loopback (docs/station.md, "Network emulation").
 *
 * Stations run on domain A, the server on domain B; the relay subscribes to every
 * palp topic on both sides and republishes each sample on the other side after a
 * delay drawn from a seeded RNG (mean delay, uniform +- jitter; each instance's samples
 * kept in order, as DDS orders them, other instances' delayed independently), losing a
 * fraction of the samples:
 * best-effort topics drop them (a lost sample's instance end, and a dispose or
 * unregister, still cross: never lost, never delayed extra), reliable topics
 * deliver them one extra round trip later (what the reliability protocol's
 * retransmission costs).
 * Keys, partitions (palp/session/N, from the sample's session_id) and QoS
 * (palp_dds_qos) are preserved; disposals and unregistrations are forwarded.
 *
 * Why not netem or namespaces: this kernel has no sch_netem, and a relay on
 * loopback needs no privileges, runs anywhere the tests run, and delays exactly
 * the palp samples; what it does not emulate is IP-level fragmentation and the
 * interaction of loss with Cyclone's own retransmission timers.
 */
#ifndef PALP_NETEM_H
#define PALP_NETEM_H

#include <stddef.h>
#include <stdint.h>

typedef struct palp_netem_def {
  uint32_t domain_a, domain_b; /* stations' and server's domains (different) */
  double delay;                /* one-way mean delay [s] */
  double jitter;               /* uniform +- [s], < delay */
  double loss;                 /* probability a sample is lost, [0, 0.5] */
  uint64_t seed;               /* RNG seed: the same seed, the same draws */
  size_t queue_bytes;          /* memory the samples in flight may hold; 0: PALP_NETEM_QUEUE_BYTES */
} palp_netem_def;

/* Default bound of the samples in flight [bytes]: what the relay holds is rate x delay, and a
 * 100k-vertex deformation is 2.4 MB; past it samples are dropped (counted in over_budget). */
#define PALP_NETEM_QUEUE_BYTES ((size_t)256 << 20)

typedef struct palp_netem_stats {
  uint64_t forwarded, dropped, retransmitted, disposals;
  uint64_t over_budget;        /* of the dropped: the queue held its byte budget (queue_bytes) */
  uint64_t ends_kept;          /* best-effort disposes and unregisters whose loss draw lost them, sent
                                * anyway at their own delay (a lost write's end crosses too, counted
                                * in dropped): each draw that hits is in one of dropped, retransmitted
                                * and ends_kept */
  uint64_t sessions_reclaimed; /* session slots given to a new session (closed or idle ones') */
  double delay_min, delay_max; /* applied one-way delays [s] */
} palp_netem_stats;

typedef struct palp_netem palp_netem;

/* Starts the relay (its threads); NULL and a message in err on failure. CYCLONEDDS_URI
 * must point at the loopback config. */
palp_netem *palp_netem_start(const palp_netem_def *def, char *err, size_t errlen);
void palp_netem_get_stats(palp_netem *n, palp_netem_stats *out);
void palp_netem_stop(palp_netem *n);

#endif
