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

#endif
