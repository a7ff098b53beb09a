/*
 * palp_dds_reaper.c - DDS entities deleted on a thread of their own (palp_dds_reaper.h).
 */
#include "palp_dds_reaper.h"

#include <pthread.h>
#include <stdlib.h>
#include <time.h>

#include "palp.h"

_Static_assert(PALP_DDS_REAPER_FULL == PALP_EFULL, "the reaper's refusal is PALP_EFULL");

struct palp_dds_reaper {
  pthread_mutex_t mu;
  pthread_cond_t cv;
  pthread_t thread;
  dds_entity_t *ring; /* capacity entries, head .. head + count - 1 (mod capacity) waiting */
  int capacity, head, count;
  int busy;           /* the thread is deleting one it took off the ring */
  int stopping;
  palp_dds_reaper_stats st;
};

static int64_t mono_ns(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (int64_t)t.tv_sec * 1000000000LL + t.tv_nsec;
}

static void *reap(void *arg) {
  palp_dds_reaper *r = arg;
  pthread_mutex_lock(&r->mu);
  for (;;) {
    while (r->count == 0 && !r->stopping) pthread_cond_wait(&r->cv, &r->mu);
    if (r->count == 0) break; /* stopping, and nothing left */
    const dds_entity_t e = r->ring[r->head];
    r->head = (r->head + 1) % r->capacity;
    r->count--;
    r->busy = 1;
    pthread_mutex_unlock(&r->mu);
    const int64_t t0 = mono_ns();
    dds_delete(e); /* the slow part: waits for the readers' acknowledgements (the linger) */
    const int64_t took = mono_ns() - t0;
    pthread_mutex_lock(&r->mu);
    r->busy = 0;
    r->st.deleted++;
    r->st.total_ns += took;
    if (took > r->st.longest_ns) r->st.longest_ns = took;
  }
  pthread_mutex_unlock(&r->mu);
  return NULL;
}

palp_dds_reaper *palp_dds_reaper_create(int capacity) {
  if (capacity < 1) return NULL;
  palp_dds_reaper *r = calloc(1, sizeof *r);
  if (!r) return NULL;
  r->ring = calloc((size_t)capacity, sizeof *r->ring);
  r->capacity = capacity;
  if (!r->ring || pthread_mutex_init(&r->mu, NULL) != 0) {
    free(r->ring);
    free(r);
    return NULL;
  }
  if (pthread_cond_init(&r->cv, NULL) != 0) {
    pthread_mutex_destroy(&r->mu);
    free(r->ring);
    free(r);
    return NULL;
  }
  if (pthread_create(&r->thread, NULL, reap, r) != 0) {
    pthread_cond_destroy(&r->cv);
    pthread_mutex_destroy(&r->mu);
    free(r->ring);
    free(r);
    return NULL;
  }
  return r;
}

int palp_dds_reaper_put(palp_dds_reaper *r, dds_entity_t e) {
  if (e <= 0) return -1;
  pthread_mutex_lock(&r->mu);
  if (r->count == r->capacity || r->stopping) {
    r->st.refused++;
    pthread_mutex_unlock(&r->mu);
    return PALP_DDS_REAPER_FULL;
  }
  r->ring[(r->head + r->count) % r->capacity] = e;
  r->count++;
  r->st.handed++;
  pthread_cond_signal(&r->cv);
  pthread_mutex_unlock(&r->mu);
  return 0;
}

void palp_dds_reaper_stats_get(palp_dds_reaper *r, palp_dds_reaper_stats *out) {
  pthread_mutex_lock(&r->mu);
  *out = r->st;
  out->pending = r->count + r->busy;
  pthread_mutex_unlock(&r->mu);
}

void palp_dds_reaper_destroy(palp_dds_reaper *r) {
  if (!r) return;
  pthread_mutex_lock(&r->mu);
  r->stopping = 1;
  pthread_cond_signal(&r->cv);
  pthread_mutex_unlock(&r->mu);
  pthread_join(r->thread, NULL); /* after the last one waiting is deleted */
  pthread_cond_destroy(&r->cv);
  pthread_mutex_destroy(&r->mu);
  free(r->ring);
  free(r);
}
