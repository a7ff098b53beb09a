/*
 * refusals.h - the peers DDS Security refused, in the server's own log.
 *
 * A station refused at the handshake (revoked, expired, signed by another CA) or
 * for its permissions gets no answer, and the server has no event for it: the
 * only trace is a Cyclone warning, repeated every second while the station
 * retries (palp_dds_refusal_parse). Here each refusal is counted per peer and
 * reason, the first one is logged at once as a palp warning naming the peer as
 * palp names it (trainee/dave), and the repeats are summed into one line per
 * peer and reason per `window` (one a minute by default). The table is bounded:
 * past PALP_SRV_REFUSAL_SLOTS peers, the one seen longest ago gives up its slot
 * (its unreported repeats are logged first). Thread-safe: Cyclone's threads call in.
 */
#ifndef PALP_SRV_REFUSALS_H
#define PALP_SRV_REFUSALS_H

#include <pthread.h>
#include <stdint.h>
#include <stdio.h>

#include "palp_dds.h"
#include "palp_log.h"

#define PALP_SRV_REFUSAL_SLOTS 16
#define PALP_SRV_REFUSAL_WINDOW_S 60.0 /* [s] between two lines about one peer and reason */

typedef struct palp_srv_refusal_slot {
  palp_dds_refusal r;
  uint64_t count;      /* since first seen */
  uint64_t unreported; /* since the last line about it */
  int64_t reported_ns, seen_ns;
  int used;
} palp_srv_refusal_slot;

typedef struct palp_srv_refusals {
  pthread_mutex_t mu;
  palp_log *log; /* NULL: stderr */
  int64_t window_ns;
  uint64_t total, lines;
  palp_srv_refusal_slot slot[PALP_SRV_REFUSAL_SLOTS];
} palp_srv_refusals;

void palp_srv_refusals_init(palp_srv_refusals *t, palp_log *log, double window_s);
void palp_srv_refusals_destroy(palp_srv_refusals *t);
/* One refusal seen at now_ns (monotonic): logs the first of its peer and reason,
 * or the repeats once `window` has passed since the last line about them. */
void palp_srv_refusals_note(palp_srv_refusals *t, const palp_dds_refusal *r, int64_t now_ns);
/* Logs every repeat not yet reported (at shutdown). */
void palp_srv_refusals_flush(palp_srv_refusals *t);
/* Totals: refusals seen, log lines written. */
void palp_srv_refusals_counts(palp_srv_refusals *t, uint64_t *total, uint64_t *lines);
/* "trainee/dave: certificate revoked (31x); ..." for the peers still in the table,
 * most refused first; returns the number listed. */
int palp_srv_refusals_describe(palp_srv_refusals *t, char *buf, size_t len);

#endif
