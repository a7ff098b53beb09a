/*
 * factor_pool.h - the server's refactorisation helper (docs/server.md, "Rebuilds off
 * the tick path"). A world asks for a lagged-tangent rebuild now and then (a pressing
 * finger: ~9 per 1,000 steps); computing it on the tick thread costs 2-10 ms and
 * stalls every session of that tick group. The world defers the install by
 * def.refactor_lag frames instead, and this helper thread computes the job meanwhile,
 * below the ticks' priority, so that it only uses time the ticks leave.
 */
#ifndef PALP_SRV_FACTOR_POOL_H
#define PALP_SRV_FACTOR_POOL_H

#include <stdint.h>

#include "palp.h"

typedef struct palp_srv_factor_pool palp_srv_factor_pool;

/* One session's job in flight; owned by the session, done under the pool's lock. */
typedef struct palp_srv_factor_slot {
  palp_factor_job *job; /* NULL: none in flight */
  int state;            /* PALP_SRV_FACTOR_QUEUED, _RUNNING or _DONE */
} palp_srv_factor_slot;
enum { PALP_SRV_FACTOR_QUEUED = 0, PALP_SRV_FACTOR_RUNNING = 1, PALP_SRV_FACTOR_DONE = 2 };

/* priority > 0: SCHED_FIFO at that priority (below the ticks', above ordinary
 * processes: on a shared machine a helper at ordinary priority waited behind other
 * programs for up to 14 ms and stalled the ticks that needed its factor); falls
 * back to ordinary scheduling when the real-time class is not granted. */
palp_srv_factor_pool *palp_srv_factor_pool_create(int priority, int *err);
/* Runs every job still queued, then stops the thread. */
void palp_srv_factor_pool_destroy(palp_srv_factor_pool *p);
/* Queues slot->job (set by the caller); never blocks on the helper. Returns 0 or
 * PALP_EFULL (the caller then runs the job itself). */
int palp_srv_factor_submit(palp_srv_factor_pool *p, palp_srv_factor_slot *slot);
/* Makes sure slot's job has run: a job no helper has started yet is taken back and
 * run on the calling thread (a hand-off to a helper costs a scheduling latency, tens
 * of ms on an overloaded machine); one a helper is running is waited for. Returns
 * the time spent [ns] (0 when a helper had finished it already). */
int64_t palp_srv_factor_wait(palp_srv_factor_pool *p, palp_srv_factor_slot *slot);
/* 1 when slot's job has run (a helper finished it), 0 when it is queued or running.
 * Never blocks on the helper. */
int palp_srv_factor_done(palp_srv_factor_pool *p, const palp_srv_factor_slot *slot);

#endif
