/*
 * ticker.h - the tick thread pool.
 *
 * A small fixed set of threads (default: one per core), each owning a group of
 * sessions. Each thread wakes on absolute CLOCK_MONOTONIC deadlines
 * (clock_nanosleep TIMER_ABSTIME), ticks every session of its group once, and
 * records the tick's work time. A tick whose work ends after the next tick's
 * start is an overrun; the thread then skips the lost slots instead of bursting
 * to catch up (simulated time lags wall time, the station sees it in sim_time).
 */
#ifndef PALP_SRV_TICKER_H
#define PALP_SRV_TICKER_H

#include <stdint.h>

#include "session.h"

typedef struct palp_srv_ticker palp_srv_ticker;

typedef struct palp_srv_tick_stats {
  /* work time per tick pass over the status period, all threads [us]: every pass of a period up to 1.5
   * status periods long (the max of any period) */
  double tick_us_p50, tick_us_p99, tick_us_max;
  double load;                                  /* worst thread's busy fraction over the period */
  uint64_t ticks, overruns;                     /* since start, all threads */
  uint64_t period_ticks, period_overruns;       /* since the previous call */
  /* since start, all threads: session steps taken and those late (each session's own
   * deadline, the next tick's start, and every step a dropped slot skipped); tick slots
   * dropped behind schedule, and the session steps they skipped (a slot of a group of n
   * sessions skips n; late_steps <= steps + skipped_steps); steps put last in their group
   * to wait for a rebuild */
  uint64_t steps, late_steps, lost_slots, skipped_steps, deferred;
} palp_srv_tick_stats;

/* threads <= 0: one per online core. max_sessions bounds every group.
 * priority 1..99 asks for SCHED_FIFO (needs CAP_SYS_NICE / rtprio limit); when
 * refused the threads run at normal priority and *rt_ok is 0. status_rate_hz
 * (0.01..1000): how often palp_srv_ticker_stats is called, which sizes the pass
 * times kept for its percentiles. */
palp_srv_ticker *palp_srv_ticker_create(int threads, double rate_hz, int max_sessions, int priority,
                                        double status_rate_hz, int *rt_ok, int *err);
/* Groups per rate (issue 11): `threads` threads for each of rate_count rates
 * (each phantom may step at its own physics rate); a session joins a group of its
 * phantom's rate. At most PALP_SRV_TICKER_MAX_RATES distinct rates. */
#define PALP_SRV_TICKER_MAX_RATES PALP_SRV_MAX_PHANTOMS
palp_srv_ticker *palp_srv_ticker_create_rates(int threads, const double *rates_hz, int rate_count, int max_sessions,
                                              int priority, double status_rate_hz, int *rt_ok, int *err);
/* Stops and joins the threads; sessions still attached are not destroyed. */
void palp_srv_ticker_destroy(palp_srv_ticker *t);
int palp_srv_ticker_threads(const palp_srv_ticker *t);
/* Attaches to the group with the fewest sessions (of the first rate). */
int palp_srv_ticker_add(palp_srv_ticker *t, palp_srv_session *s);
/* Attaches to the group at rate_hz with the fewest sessions; PALP_EINVAL if no group runs at it. */
int palp_srv_ticker_add_rate(palp_srv_ticker *t, palp_srv_session *s, double rate_hz);
/* Detaches; on return no tick thread touches s any more. */
void palp_srv_ticker_remove(palp_srv_ticker *t, palp_srv_session *s);
/* Calls fn for every attached session under its group's lock (short work only). */
void palp_srv_ticker_each(palp_srv_ticker *t, void (*fn)(void *ctx, palp_srv_session *s), void *ctx);
/* Calls fn for s alone under its own group's lock (short work only): no other group's tick waits
 * for it. Returns 1, or 0 (fn not called) if s is attached to no group of t. */
int palp_srv_ticker_with(palp_srv_ticker *t, palp_srv_session *s, void (*fn)(void *ctx, palp_srv_session *s),
                         void *ctx);
/* Snapshot of the timing since the previous call. */
void palp_srv_ticker_stats(palp_srv_ticker *t, palp_srv_tick_stats *out);

#endif
