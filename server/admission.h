/*
 * admission.h - who may hold what on the request topic.
 *
 * A station process has one request writer and one station id. A peer that
 * writes thousands of station ids would make Cyclone keep an instance per id in
 * the server's request reader (memory) and fill the server's station slots. The
 * request topic's filter (receive thread) therefore admits a new request
 * instance only while its writer holds fewer than `per_writer` of them, and only
 * while the table of admitted instances has room; the main thread releases an
 * instance when it sees it go not-alive. Bounded: `capacity` instances in all.
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
/* [main thread] The instance went not-alive: its writer may use the slot again. Whether the
 * table held it (a dispose of a key never written passes no filter, so was never admitted). */
bool palp_srv_admission_release(palp_srv_admission *a, uint64_t iid);
/* Instances refused by the filter since creation. */
uint64_t palp_srv_admission_refused(palp_srv_admission *a);
/* Instances admitted now. */
int palp_srv_admission_count(palp_srv_admission *a);

/* [main thread] Takes a join token at CLOCK_MONOTONIC now_ns; false: over the rate. */
bool palp_srv_admission_join_token(palp_srv_admission *a, int64_t now_ns);

#endif
