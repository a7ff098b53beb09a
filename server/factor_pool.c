/* factor_pool.c - see factor_pool.h. */
#include "factor_pool.h"

#include <pthread.h>
#include <sched.h>
#include <stdlib.h>
#include <time.h>

#include "palp_dds.h"
#include "palp_rt_thread.h"

/* More than any server holds sessions: one job in flight per session. */
#define PALP_SRV_FACTOR_QUEUE 1024

/* Two helpers: jobs come in bursts (sessions pressing in step), and the machine the
 * server is sized for has 2 cores. */
#define PALP_SRV_FACTOR_THREADS 2

struct palp_srv_factor_pool {
  pthread_t thread[PALP_SRV_FACTOR_THREADS];
  int threads;
  pthread_mutex_t lock;
  pthread_cond_t work, finished;
  palp_srv_factor_slot *queue[PALP_SRV_FACTOR_QUEUE];
  int head, count;
  int stop;
};

static void *helper_main(void *arg) {
  palp_srv_factor_pool *p = arg;
  pthread_mutex_lock(&p->lock);
  for (;;) {
    while (!p->count && !p->stop) pthread_cond_wait(&p->work, &p->lock);
    if (!p->count) break; /* stopping, and the queue is drained */
    palp_srv_factor_slot *s = p->queue[p->head];
    p->head = (p->head + 1) % PALP_SRV_FACTOR_QUEUE;
    p->count--;
    if (s->state != PALP_SRV_FACTOR_QUEUED) continue; /* defensive: taken entries leave the queue */
    s->state = PALP_SRV_FACTOR_RUNNING;
    palp_factor_job *j = s->job;
    pthread_mutex_unlock(&p->lock);
    /* The job touches only its own memory: the session's world steps on meanwhile. */
    palp_factor_job_run(j);
    pthread_mutex_lock(&p->lock);
    s->state = PALP_SRV_FACTOR_DONE;
    pthread_cond_broadcast(&p->finished);
  }
  pthread_mutex_unlock(&p->lock);
  return NULL;
}

palp_srv_factor_pool *palp_srv_factor_pool_create(int priority, int *err) {
  palp_srv_factor_pool *p = calloc(1, sizeof *p);
  if (!p) {
    *err = PALP_ENOMEM;
    return NULL;
  }
  pthread_mutex_init(&p->lock, NULL);
  pthread_cond_init(&p->work, NULL);
  pthread_cond_init(&p->finished, NULL);
  for (int i = 0; i < PALP_SRV_FACTOR_THREADS; i++) {
    if (palp_rt_thread_start(&p->thread[i], priority, helper_main, p, NULL) < 0) break;
    p->threads++;
  }
  if (!p->threads) {
    pthread_mutex_destroy(&p->lock);
    pthread_cond_destroy(&p->work);
    pthread_cond_destroy(&p->finished);
    free(p);
    *err = PALP_ENOMEM;
    return NULL;
  }
  *err = 0;
  return p;
}

void palp_srv_factor_pool_destroy(palp_srv_factor_pool *p) {
  if (!p) return;
  pthread_mutex_lock(&p->lock);
  p->stop = 1;
  pthread_cond_broadcast(&p->work);
  pthread_mutex_unlock(&p->lock);
  for (int i = 0; i < p->threads; i++) pthread_join(p->thread[i], NULL);
  pthread_mutex_destroy(&p->lock);
  pthread_cond_destroy(&p->work);
  pthread_cond_destroy(&p->finished);
  free(p);
}

int palp_srv_factor_submit(palp_srv_factor_pool *p, palp_srv_factor_slot *slot) {
  pthread_mutex_lock(&p->lock);
  if (p->count >= PALP_SRV_FACTOR_QUEUE || p->stop) {
    pthread_mutex_unlock(&p->lock);
    return PALP_EFULL;
  }
  slot->state = PALP_SRV_FACTOR_QUEUED;
  p->queue[(p->head + p->count) % PALP_SRV_FACTOR_QUEUE] = slot;
  p->count++;
  pthread_cond_signal(&p->work);
  pthread_mutex_unlock(&p->lock);
  return 0;
}

int64_t palp_srv_factor_wait(palp_srv_factor_pool *p, palp_srv_factor_slot *slot) {
  int64_t waited = 0;
  pthread_mutex_lock(&p->lock);
  if (slot->state == PALP_SRV_FACTOR_QUEUED) {
    /* Not started: take its entry out of the queue (the session may be freed next)
     * and run it here. */
    for (int i = 0; i < p->count; i++)
      if (p->queue[(p->head + i) % PALP_SRV_FACTOR_QUEUE] == slot) {
        for (int k = i; k + 1 < p->count; k++)
          p->queue[(p->head + k) % PALP_SRV_FACTOR_QUEUE] = p->queue[(p->head + k + 1) % PALP_SRV_FACTOR_QUEUE];
        p->count--;
        break;
      }
    slot->state = PALP_SRV_FACTOR_RUNNING;
    pthread_mutex_unlock(&p->lock);
    const int64_t t0 = palp_dds_now_ns();
    palp_factor_job_run(slot->job);
    waited = palp_dds_now_ns() - t0;
    pthread_mutex_lock(&p->lock);
    slot->state = PALP_SRV_FACTOR_DONE;
  } else if (slot->state != PALP_SRV_FACTOR_DONE) {
    const int64_t t0 = palp_dds_now_ns();
    while (slot->state != PALP_SRV_FACTOR_DONE) pthread_cond_wait(&p->finished, &p->lock);
    waited = palp_dds_now_ns() - t0;
  }
  pthread_mutex_unlock(&p->lock);
  return waited;
}

int palp_srv_factor_done(palp_srv_factor_pool *p, const palp_srv_factor_slot *slot) {
  pthread_mutex_lock(&p->lock);
  const int done = slot->state == PALP_SRV_FACTOR_DONE;
  pthread_mutex_unlock(&p->lock);
  return done;
}
