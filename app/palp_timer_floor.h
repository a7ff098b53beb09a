/*
 * palp_timer_floor.h - what this machine makes of a periodic deadline for a thread
 * that does no work.
 *
 * A thread at a given scheduling (SCHED_FIFO at `priority` when granted) sleeps to
 * absolute CLOCK_MONOTONIC deadlines one period apart and only counts how late it
 * woke. Beside a periodic loop (the station's 1 kHz haptic thread, the server's tick
 * threads in bench_server) it measures, over the same seconds, the lateness the VM,
 * the kernel and the other threads cause by themselves: the loop's own late ticks
 * are read against it. On the 2-core VM of session 34, idle, a bare 1 kHz timer at
 * SCHED_FIFO 20 woke > 0.5 ms late on 0.42-0.86% of its ticks (docs/station.md).
 * A wake-up more than a period late is not made up: the lost slots are dropped and
 * the phase kept, as the loops it stands beside do.
 */
#ifndef PALP_TIMER_FLOOR_H
#define PALP_TIMER_FLOOR_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>

typedef struct palp_timer_floor {
  int64_t period_ns, late_ns, first_ns; /* set by start */
  atomic_int stop;
  pthread_t thread;
  int started, rt_ok;
  /* written by its thread; read after palp_timer_floor_stop (or approximately before) */
  atomic_uint_fast64_t ticks, late_ticks; /* late: woke more than late_ns after the deadline */
  atomic_uint_fast64_t missed;            /* deadlines dropped while a wake-up was over a period late */
  double late_max;                        /* [s]; final after stop; stalls excluded */
  /* A wake-up more than PALP_TIMER_FLOOR_STALL_NS late is the whole process not run (a
   * stopped or swapped-out station: docs/station.md, "A stalled station"), not the timer:
   * counted here, not in late_ticks or late_max. */
  atomic_uint_fast64_t stalls;
} palp_timer_floor;

/* [ns] as PALP_CLI_STALL_S (client/station.h): a gap the station takes for a stall */
#define PALP_TIMER_FLOOR_STALL_NS 400000000

/* Starts the thread: deadlines first_ns + k period_ns [CLOCK_MONOTONIC ns], k = 1, 2, ...;
 * late past late_ns. priority > 0 asks for SCHED_FIFO (refused: normal, rt_ok 0).
 * Returns 0, or -1 when no thread could be started (the floor then stays empty). */
int palp_timer_floor_start(palp_timer_floor *f, int64_t period_ns, int64_t late_ns, int64_t first_ns, int priority);
/* Asks the thread to end after its next wake-up (any thread may call it). */
void palp_timer_floor_request_stop(palp_timer_floor *f);
/* Stops and joins; the counts are final after it. */
void palp_timer_floor_stop(palp_timer_floor *f);

#endif
