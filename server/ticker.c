/* ticker.c - the tick thread pool. */
#include "ticker.h"

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "palp.h"
#include "palp_dds.h"
#include "palp_rt_thread.h"

typedef struct tick_group {
  palp_srv_ticker *owner;
  pthread_t thread;
  pthread_mutex_t lock;
  palp_srv_session **sessions;
  int count;
  int64_t period_ns; /* this group's physics period: groups per rate (issue 11) */
  /* timing, under lock */
  double *work_us;   /* this status period's tick work times [us] */
  int work_n, work_cap;
  double work_us_max; /* the period's longest, kept past work_cap too [us] */
  int64_t busy_ns, period_start_ns;
  uint64_t ticks, overruns, period_ticks, period_overruns;
  uint64_t steps, late_steps; /* session steps taken, and those that ended late */
  uint64_t lost_slots;        /* tick slots dropped behind schedule (no session stepped) */
  uint64_t skipped_steps;     /* lost_slots x the group's sessions then: steps not taken */
  uint64_t deferred_total;    /* session steps put last to wait for a rebuild */
  palp_srv_session **deferred; /* [max_sessions] this tick's sessions waiting for a rebuild */
} tick_group;

struct palp_srv_ticker {
  int n;        /* groups = threads per rate x rates */
  int per_rate; /* threads per rate */
  int max_sessions;
  atomic_int stop;
  tick_group *g;
  palp_srv_factor_pool *factor; /* lagged-tangent rebuilds off the tick path */
  int started;
};

static struct timespec ts_of(int64_t ns) {
  return (struct timespec){.tv_sec = (time_t)(ns / 1000000000), .tv_nsec = (long)(ns % 1000000000)};
}

/* n late steps of session s, late_ns past their deadline: its counters and its log. A slot its
 * group skipped behind schedule is one (the step it was due came late: simulated time lags). */
static void session_late(palp_srv_session *s, uint64_t n, int64_t late_ns) {
  s->stats.overruns += n;
  if (s->events && s->events->overrun) s->events->overrun(s->events->ctx, s->id, n, late_ns);
}

/* One session's tick. Late when its own work ends after the next tick should have
 * started: counted for that session (its log and SessionLoad say so), not for the
 * group's others, whose steps may have ended in time. Returns 1 when late. */
static int tick_one(palp_srv_session *s, int64_t next, int64_t deadline) {
  palp_srv_session_tick(s, next);
  const int64_t end = palp_dds_now_ns();
  if (end <= deadline) return 0;
  session_late(s, 1, end - deadline);
  return 1;
}

static void *group_main(void *arg) {
  tick_group *g = arg;
  palp_srv_ticker *t = g->owner;
  const int64_t period_ns = g->period_ns;
  int64_t next = palp_dds_now_ns() + period_ns;
  while (!atomic_load(&t->stop)) {
    struct timespec ts = ts_of(next);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
    int64_t t0 = palp_dds_now_ns();
    const int64_t deadline = next + period_ns;
    pthread_mutex_lock(&g->lock);
    /* A session whose due rebuild a helper has not finished would wait for it on
     * this thread (2-10 ms): it goes last, so that its wait delays no other session
     * of the group and the helper has the group's work time to finish. Sessions are
     * independent worlds: the order changes no session's result. */
    int waiting = 0, late = 0;
    for (int i = 0; i < g->count; i++) {
      palp_srv_session *s = g->sessions[i];
      if (!palp_srv_session_tick_ready(s)) {
        g->deferred[waiting++] = s;
        continue;
      }
      late += tick_one(s, next, deadline);
    }
    for (int k = 0; k < waiting; k++) late += tick_one(g->deferred[k], next, deadline);
    int64_t t1 = palp_dds_now_ns();
    /* Overrun: this tick's work ended after the next tick should have started. */
    int overrun = t1 > deadline;
    g->ticks++;
    g->period_ticks++;
    g->overruns += (uint64_t)overrun;
    g->period_overruns += (uint64_t)overrun;
    g->deferred_total += (uint64_t)waiting;
    g->late_steps += (uint64_t)late;
    g->steps += (uint64_t)g->count;
    g->busy_ns += t1 - t0;
    const double work_us = (double)(t1 - t0) * 1e-3;
    if (g->work_n < g->work_cap) g->work_us[g->work_n++] = work_us;
    if (work_us > g->work_us_max) g->work_us_max = work_us;
    next += period_ns;
    if (next <= t1) {
      /* Behind schedule: drop the lost slots rather than burst. */
      int64_t lost = (t1 - next) / period_ns + 1;
      next += lost * period_ns;
      g->lost_slots += (uint64_t)lost;
      /* Every session of the group missed them: counted as late steps (its overruns, its log's
       * overrun events, the wire's as since 2026-12-02), so that a session's overruns never
       * flatter a group that fell behind, and as its skipped slots too: a share of late steps is
       * of the slots due, steps taken plus slots skipped, and stays <= 100% (until session 82
       * it was of the steps taken alone: "168 of 136 ticks overran" after a stall). */
      for (int i = 0; i < g->count; i++) {
        session_late(g->sessions[i], (uint64_t)lost, t1 - deadline);
        g->sessions[i]->stats.skipped += (uint64_t)lost;
      }
      g->late_steps += (uint64_t)lost * (uint64_t)g->count;
      g->skipped_steps += (uint64_t)lost * (uint64_t)g->count;
    }
    pthread_mutex_unlock(&g->lock);
  }
  return NULL;
}

palp_srv_ticker *palp_srv_ticker_create(int threads, double rate_hz, int max_sessions, int priority,
                                        double status_rate_hz, int *rt_ok, int *err) {
  return palp_srv_ticker_create_rates(threads, &rate_hz, 1, max_sessions, priority, status_rate_hz, rt_ok, err);
}

palp_srv_ticker *palp_srv_ticker_create_rates(int threads, const double *rates_hz, int rate_count, int max_sessions,
                                              int priority, double status_rate_hz, int *rt_ok, int *err) {
  *rt_ok = 0;
  if (threads <= 0) {
    long c = sysconf(_SC_NPROCESSORS_ONLN);
    threads = c > 0 ? (int)c : 1;
  }
  if (rate_count < 1 || rate_count > PALP_SRV_TICKER_MAX_RATES || max_sessions < 1 || !(status_rate_hz >= 0.01) ||
      !(status_rate_hz <= 1e3)) {
    *err = PALP_EINVAL;
    return NULL;
  }
  for (int r = 0; r < rate_count; r++)
    if (!(rates_hz[r] > 0) || !(rates_hz[r] <= 1e5)) {
      *err = PALP_EINVAL;
      return NULL;
    }
  palp_srv_ticker *t = calloc(1, sizeof *t);
  if (!t) goto nomem;
  t->per_rate = threads;
  t->n = threads * rate_count;
  t->max_sessions = max_sessions;
  t->g = calloc((size_t)t->n, sizeof *t->g);
  if (!t->g) goto nomem;
  for (int i = 0; i < t->n; i++) {
    tick_group *g = &t->g[i];
    const double rate_hz = rates_hz[i / threads];
    /* Every pass of a status period, and half a period more for a status that comes late (until
     * session 82, 4 s of passes: at the 0.1 Hz status the config allows, 60% of each period was
     * in no percentile); the max is kept past the cap too. 1 kHz, 0.1 Hz: 120 KB a group. */
    const int cap = (int)(rate_hz / status_rate_hz * 1.5) + 16;
    g->owner = t;
    g->period_ns = (int64_t)(1e9 / rate_hz + 0.5);
    /* Priority inheritance: the main thread (ordinary priority) takes a group's lock for a
     * snapshot; preempted while holding it, it would hold up the group's SCHED_FIFO tick for as
     * long as other ordinary work runs. With inheritance it runs at the tick's priority until it
     * lets go. Where the protocol is not supported the lock is an ordinary one. */
    pthread_mutexattr_t ma;
    pthread_mutexattr_init(&ma);
    if (pthread_mutexattr_setprotocol(&ma, PTHREAD_PRIO_INHERIT) != 0 || pthread_mutex_init(&g->lock, &ma) != 0)
      pthread_mutex_init(&g->lock, NULL);
    pthread_mutexattr_destroy(&ma);
    g->sessions = calloc((size_t)max_sessions, sizeof *g->sessions);
    g->deferred = calloc((size_t)max_sessions, sizeof *g->deferred);
    g->work_us = calloc((size_t)cap, sizeof *g->work_us);
    g->work_cap = cap;
    g->period_start_ns = palp_dds_now_ns();
    if (!g->sessions || !g->deferred || !g->work_us) goto nomem;
  }
  int ferr = 0;
  /* One below the ticks: it must not delay a tick, but must beat ordinary work. At tick priority 1,
   * the lowest SCHED_FIFO one, the ticks' own (docs/server.md says so). */
  t->factor = palp_srv_factor_pool_create(priority > 1 ? priority - 1 : priority, &ferr);
  if (!t->factor) goto nomem;
  threads = t->n;
  for (int i = 0; i < threads; i++) {
    /* A tick preempted by a compiler or a browser is a missed haptic deadline: a
     * real-time class keeps the tick threads ahead of ordinary work. */
    int rt = 0;
    const int rc = palp_rt_thread_start(&t->g[i].thread, priority, group_main, &t->g[i], &rt);
    if (rc == 0 && rt && i == 0) *rt_ok = 1;
    if (rc < 0) {
      atomic_store(&t->stop, 1);
      for (int j = 0; j < i; j++) pthread_join(t->g[j].thread, NULL);
      t->started = 0;
      palp_srv_ticker_destroy(t);
      *err = PALP_ENOMEM;
      return NULL;
    }
    t->started = i + 1;
  }
  *err = 0;
  return t;
nomem:
  palp_srv_ticker_destroy(t);
  *err = PALP_ENOMEM;
  return NULL;
}

void palp_srv_ticker_destroy(palp_srv_ticker *t) {
  if (!t) return;
  atomic_store(&t->stop, 1);
  for (int i = 0; i < t->started; i++) pthread_join(t->g[i].thread, NULL);
  /* The tick threads are gone: hand every job in flight back before the helper goes. */
  if (t->g)
    for (int i = 0; i < t->n; i++)
      for (int k = 0; k < t->g[i].count; k++) {
        palp_srv_session_factor_settle(t->g[i].sessions[k]);
        t->g[i].sessions[k]->factor_pool = NULL;
      }
  palp_srv_factor_pool_destroy(t->factor);
  if (t->g)
    for (int i = 0; i < t->n; i++) {
      pthread_mutex_destroy(&t->g[i].lock);
      free(t->g[i].sessions);
      free(t->g[i].deferred);
      free(t->g[i].work_us);
    }
  free(t->g);
  free(t);
}

int palp_srv_ticker_threads(const palp_srv_ticker *t) { return t->n; }

int palp_srv_ticker_add(palp_srv_ticker *t, palp_srv_session *s) {
  return palp_srv_ticker_add_rate(t, s, 1e9 / (double)t->g[0].period_ns);
}

int palp_srv_ticker_add_rate(palp_srv_ticker *t, palp_srv_session *s, double rate_hz) {
  if (!(rate_hz > 0)) return PALP_EINVAL;
  const int64_t period_ns = (int64_t)(1e9 / rate_hz + 0.5);
  int best = -1;
  for (int i = 0; i < t->n; i++)
    if (t->g[i].period_ns == period_ns && (best < 0 || t->g[i].count < t->g[best].count)) best = i;
  if (best < 0) return PALP_EINVAL; /* no group at this rate */
  tick_group *g = &t->g[best];
  pthread_mutex_lock(&g->lock);
  int rc = PALP_EFULL;
  if (g->count < t->max_sessions) {
    s->factor_pool = t->factor;
    s->tick_group = best + 1;
    g->sessions[g->count++] = s;
    rc = 0;
  }
  pthread_mutex_unlock(&g->lock);
  return rc;
}

void palp_srv_ticker_remove(palp_srv_ticker *t, palp_srv_session *s) {
  int found = 0;
  for (int i = 0; i < t->n && !found; i++) {
    tick_group *g = &t->g[i];
    pthread_mutex_lock(&g->lock);
    for (int k = 0; k < g->count; k++)
      if (g->sessions[k] == s) {
        g->sessions[k] = g->sessions[--g->count];
        found = 1;
        break;
      }
    pthread_mutex_unlock(&g->lock);
  }
  /* Its rebuild in flight is settled only now, after the group's lock (until session 82 under
   * it): the settle runs a queued job on this thread or waits for a helper's, 2-19 ms, and the
   * group's tick thread, real-time, would have waited on this ordinary thread all that time,
   * every other session of the group losing its slots. Out of the group no tick touches s,
   * and the settle needs only the pool's own lock. */
  if (found) {
    palp_srv_session_factor_settle(s);
    s->factor_pool = NULL;
  }
  s->tick_group = 0;
}

int palp_srv_ticker_with(palp_srv_ticker *t, palp_srv_session *s, void (*fn)(void *ctx, palp_srv_session *s),
                         void *ctx) {
  const int i = s->tick_group - 1;
  if (i < 0 || i >= t->n) return 0;
  tick_group *g = &t->g[i];
  int found = 0;
  pthread_mutex_lock(&g->lock);
  for (int k = 0; k < g->count && !found; k++)
    if (g->sessions[k] == s) found = 1;
  if (found) fn(ctx, s);
  pthread_mutex_unlock(&g->lock);
  return found;
}

void palp_srv_ticker_each(palp_srv_ticker *t, void (*fn)(void *ctx, palp_srv_session *s), void *ctx) {
  for (int i = 0; i < t->n; i++) {
    tick_group *g = &t->g[i];
    pthread_mutex_lock(&g->lock);
    for (int k = 0; k < g->count; k++) fn(ctx, g->sessions[k]);
    pthread_mutex_unlock(&g->lock);
  }
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

void palp_srv_ticker_stats(palp_srv_ticker *t, palp_srv_tick_stats *out) {
  memset(out, 0, sizeof *out);
  int total = 0;
  for (int i = 0; i < t->n; i++) total += t->g[i].work_cap;
  double *all = malloc((size_t)total * sizeof *all);
  int n = 0;
  int64_t now = palp_dds_now_ns();
  for (int i = 0; i < t->n; i++) {
    tick_group *g = &t->g[i];
    pthread_mutex_lock(&g->lock);
    if (all) memcpy(all + n, g->work_us, (size_t)g->work_n * sizeof *all);
    n += all ? g->work_n : 0;
    if (g->work_us_max > out->tick_us_max) out->tick_us_max = g->work_us_max;
    g->work_us_max = 0;
    double span = (double)(now - g->period_start_ns);
    double load = span > 0 ? (double)g->busy_ns / span : 0;
    if (load > out->load) out->load = load;
    out->ticks += g->ticks;
    out->overruns += g->overruns;
    out->period_ticks += g->period_ticks;
    out->period_overruns += g->period_overruns;
    out->steps += g->steps;
    out->late_steps += g->late_steps;
    out->lost_slots += g->lost_slots;
    out->skipped_steps += g->skipped_steps;
    out->deferred += g->deferred_total;
    g->work_n = 0;
    g->busy_ns = 0;
    g->period_ticks = g->period_overruns = 0;
    g->period_start_ns = now;
    pthread_mutex_unlock(&g->lock);
  }
  if (all && n > 0) {
    qsort(all, (size_t)n, sizeof *all, cmp_double);
    out->tick_us_p50 = all[(n - 1) / 2];
    out->tick_us_p99 = all[(int)((n - 1) * 0.99)];
    if (all[n - 1] > out->tick_us_max) out->tick_us_max = all[n - 1];
  }
  free(all);
}
