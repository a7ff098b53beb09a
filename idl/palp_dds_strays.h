/*
 * palp_dds_strays.h - when a reader flooded with disposes of made-up keys is made anew.
 *
 * A dispose carries no data, so no topic filter sees it (Cyclone 0.10), and a dispose of a key the
 * reader never had makes an instance that it keeps while the disposing writer lives (~0.6-1 kB). A
 * reliable reader cannot bound its instances (one refused for a resource limit stalls delivery on
 * Cyclone's delivery path: docs/robustness.md), so the readers of the volatile findings (palp-server's
 * per session, palp-recorder's and palp-web's) count such disposes and are made anew past
 * PALP_DDS_STRAYS_MIN of them, at most once per PALP_DDS_RENEW_NS unless PALP_DDS_STRAYS_HARD come:
 * the instances go with the old reader, and a volatile topic hands the new one none of them again.
 * The best-effort stream readers of palp-web and palp-recorder bound their instances as well
 * (palp_dds_gate_limit) and are made anew the same way, and at once when full (palp_dds_strays_full_due).
 */
#ifndef PALP_DDS_STRAYS_H
#define PALP_DDS_STRAYS_H

#include <stdint.h>

#define PALP_DDS_STRAYS_MIN 256
#define PALP_DDS_STRAYS_HARD 4096       /* made anew at once however soon: a fast flood's bound */
#define PALP_DDS_RENEW_NS 250000000LL  /* [ns] */

/* Whether a reader that has taken `strays` such disposes since it was made (at last_ns, 0: never
 * made anew) is to be made anew at now_ns. */
static inline int palp_dds_strays_renew_due(uint64_t strays, int64_t now_ns, int64_t last_ns) {
  return strays >= PALP_DDS_STRAYS_MIN && (now_ns - last_ns >= PALP_DDS_RENEW_NS || strays >= PALP_DDS_STRAYS_HARD);
}

/* Whether a reader bounded to `bound` instances that has refused `refused` samples for that bound
 * since it was made is to be made anew at once, not PALP_DDS_RENEW_NS after the last time: while it
 * is full every new key is refused, a new session's too (the stream readers of palp-web and
 * palp-recorder; the session 81 review). Only when strays (disposes taken and samples refused) reach
 * half its bound, or PALP_DDS_STRAYS_MIN if fewer: a flood filled it, not its own sessions. */
static inline int palp_dds_strays_full_due(uint64_t strays, uint64_t refused, int64_t bound) {
  const uint64_t half = bound > 1 ? (uint64_t)bound / 2 : 1;
  return refused > 0 && strays >= (half < PALP_DDS_STRAYS_MIN ? half : PALP_DDS_STRAYS_MIN);
}

#endif
