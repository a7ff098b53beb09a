/*
 * timer_floor.c - a thread that only sleeps to periodic deadlines and counts how
 * late it woke (palp_timer_floor.h).
 */
#include "palp_timer_floor.h"

#include <errno.h>
#include <string.h>
#include <time.h>

#include "palp_rt_thread.h"

static int64_t now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void *floor_main(void *arg) {
  palp_timer_floor *f = arg;
  int64_t next = f->first_ns;
  double late_max = 0;
  while (!atomic_load_explicit(&f->stop, memory_order_relaxed)) {
    next += f->period_ns;
    const struct timespec ts = {.tv_sec = (time_t)(next / 1000000000), .tv_nsec = (long)(next % 1000000000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
    const int64_t late = now_ns() - next;
    atomic_fetch_add_explicit(&f->ticks, 1, memory_order_relaxed);
    if (late > PALP_TIMER_FLOOR_STALL_NS) { /* the process was not run at all: not the timer */
      atomic_fetch_add_explicit(&f->stalls, 1, memory_order_relaxed);
    } else {
      if (late > f->late_ns) atomic_fetch_add_explicit(&f->late_ticks, 1, memory_order_relaxed);
      if ((double)late * 1e-9 > late_max) late_max = (double)late * 1e-9;
    }
    if (late > f->period_ns) {
      next += (late / f->period_ns) * f->period_ns;
      atomic_fetch_add_explicit(&f->missed, (uint_fast64_t)(late / f->period_ns), memory_order_relaxed);
    }
  }
  f->late_max = late_max;
  return NULL;
}

int palp_timer_floor_start(palp_timer_floor *f, int64_t period_ns, int64_t late_ns, int64_t first_ns, int priority) {
  memset(f, 0, sizeof *f);
  if (period_ns <= 0) return -1;
  f->period_ns = period_ns, f->late_ns = late_ns, f->first_ns = first_ns;
  if (palp_rt_thread_start(&f->thread, priority, floor_main, f, &f->rt_ok) < 0) return -1;
  f->started = 1;
  return 0;
}

void palp_timer_floor_request_stop(palp_timer_floor *f) { atomic_store(&f->stop, 1); }

void palp_timer_floor_stop(palp_timer_floor *f) {
  if (!f->started) return;
  atomic_store(&f->stop, 1);
  pthread_join(f->thread, NULL);
  f->started = 0;
}
