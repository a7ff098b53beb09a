/*
 * admission.h - who may hold what on the request topic.
 *
 * A station process has one request writer and one station id. A peer that
 * writes thousands of station ids would make Cyclone keep an instance per id in
 * the server's request reader (memory) and fill the server's station slots. The
 * request topic's filter (receive thread) therefore admits a new request
 * instance only while its writer holds fewer than `per_writer` of them, and only
 * while the table of admitted instances has room. A writer's instances are released
 * only when the writer itself is gone (the main thread's sweep, when the reader's
 * matched writers fall), not when an instance goes not-alive: a writer that lives
 * keeps its disposed instances registered in the reader (Cyclone drops them only
 * with their last writer), so releasing on a dispose let one writer cycle
 * write-then-dispose over fresh keys without bound; and a dispose taken together
 * with the request before it (a station's LEAVE and dispose) shows no not-alive
 * sample of its own, so its instance, later dropped silently with its writer, was
 * never released: the table filled with departed stations until it refused every
 * new one (both until 2026-12-06). Bounded: `capacity` instances in all.
 *
 * The join rate limit (a token bucket) lives here too: it is the main thread's.
 */
#ifndef PALP_SRV_ADMISSION_H
#define PALP_SRV_ADMISSION_H

#include <stdbool.h>
#include <stdint.h>

typedef struct palp_srv_admission palp_srv_admission;

palp_srv_admission *palp_srv_admission_create(int per_writer, int capacity, double rate_per_s, int burst);
void palp_srv_admission_destroy(palp_srv_admission *a);

/* [receive thread, via the topic filter] May instance `iid`, written by writer
 * `writer`, enter the reader cache? Known instances always may. */
bool palp_srv_admission_admit(palp_srv_admission *a, uint64_t iid, uint64_t writer);
/* [main thread] Whether the table holds instance `iid` (a dispose of a key never written, or
 * whose writes the filter refused, passes no filter, so was never admitted). */
bool palp_srv_admission_holds(palp_srv_admission *a, uint64_t iid);
/* [main thread] Releases the instances of every writer in the table for which `matched`
 * returns 0 (that writer is gone: it can admit nothing more). `matched` is called without the
 * table's lock held (it may take DDS's locks, which the receive thread holds while it calls the
 * filter), once per writer, all after the table's writers were copied: one that reads the matched
 * writers at its first call (the server's, into a sorted set) sees every one that lives. The
 * instances are erased in one pass over the table. Returns the instances released. */
int palp_srv_admission_sweep(palp_srv_admission *a, int (*matched)(uint64_t writer, void *arg), void *arg);
/* Instances refused by the filter since creation. */
uint64_t palp_srv_admission_refused(palp_srv_admission *a);
/* Instances admitted now. */
int palp_srv_admission_count(palp_srv_admission *a);

/* [main thread] Takes a join token at CLOCK_MONOTONIC now_ns; false: over the rate. */
bool palp_srv_admission_join_token(palp_srv_admission *a, int64_t now_ns);

#endif
