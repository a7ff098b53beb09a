/* admission.c - per-writer instance limit for the request topic, and the join rate. */
#include "admission.h"

#include <pthread.h>
#include <stdlib.h>

/* Open addressing with linear probing and backward-shift deletion: no tombstones,
 * so a long-running server's table never degrades. Key 0 marks an empty slot
 * (Cyclone never hands out instance or writer handle 0). */
typedef struct entry {
  uint64_t key, val;
} entry;

typedef struct map {
  entry *e;
  uint32_t mask; /* size - 1, size a power of two */
} map;

static int map_init(map *m, int capacity) {
  uint32_t n = 16;
  while (n < (uint32_t)capacity * 2) n <<= 1; /* load factor <= 0.5 */
  m->e = calloc(n, sizeof *m->e);
  m->mask = n - 1;
  return m->e ? 0 : -1;
}

static uint32_t slot_of(const map *m, uint64_t k) {
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdULL;
  k ^= k >> 33;
  return (uint32_t)k & m->mask;
}

static entry *map_find(map *m, uint64_t k) {
  for (uint32_t i = slot_of(m, k);; i = (i + 1) & m->mask) {
    if (m->e[i].key == k) return &m->e[i];
    if (m->e[i].key == 0) return NULL;
  }
}

static entry *map_insert(map *m, uint64_t k) {
  uint32_t i = slot_of(m, k);
  while (m->e[i].key != 0 && m->e[i].key != k) i = (i + 1) & m->mask;
  if (m->e[i].key == 0) m->e[i] = (entry){k, 0};
  return &m->e[i];
}

static void map_erase(map *m, entry *at) {
  uint32_t i = (uint32_t)(at - m->e);
  for (uint32_t j = (i + 1) & m->mask; m->e[j].key != 0; j = (j + 1) & m->mask) {
    /* Move e[j] back into the hole at i if its home slot does not lie in (i, j]. */
    uint32_t home = slot_of(m, m->e[j].key);
    if (((j - home) & m->mask) >= ((j - i) & m->mask)) {
      m->e[i] = m->e[j];
      i = j;
    }
  }
  m->e[i] = (entry){0, 0};
}

struct palp_srv_admission {
  pthread_mutex_t lock;
  map instances; /* instance handle -> writer handle */
  map writers;   /* writer handle -> admitted instance count */
  uint64_t *swept; /* [main thread] the writers a sweep looks at, copied out of the lock; [capacity] */
  int count, capacity, per_writer;
  uint64_t refused;
  double rate, tokens;
  int burst;
  int64_t last_ns;
};

palp_srv_admission *palp_srv_admission_create(int per_writer, int capacity, double rate_per_s, int burst) {
  palp_srv_admission *a = calloc(1, sizeof *a);
  if (!a) return NULL;
  a->swept = calloc((size_t)capacity, sizeof *a->swept);
  if (!a->swept || map_init(&a->instances, capacity) || map_init(&a->writers, capacity)) {
    free(a->instances.e);
    free(a->writers.e);
    free(a->swept);
    free(a);
    return NULL;
  }
  pthread_mutex_init(&a->lock, NULL);
  a->capacity = capacity;
  a->per_writer = per_writer;
  a->rate = rate_per_s;
  a->burst = burst;
  a->tokens = burst;
  a->last_ns = -1;
  return a;
}

void palp_srv_admission_destroy(palp_srv_admission *a) {
  if (!a) return;
  pthread_mutex_destroy(&a->lock);
  free(a->instances.e);
  free(a->writers.e);
  free(a->swept);
  free(a);
}

bool palp_srv_admission_admit(palp_srv_admission *a, uint64_t iid, uint64_t writer) {
  if (iid == 0 || writer == 0) return true; /* not from a remote writer's data: nothing to count */
  bool ok = false;
  pthread_mutex_lock(&a->lock);
  if (map_find(&a->instances, iid)) {
    ok = true;
  } else if (a->count < a->capacity) {
    entry *w = map_find(&a->writers, writer);
    if (!w || w->val < (uint64_t)a->per_writer) {
      w = map_insert(&a->writers, writer);
      w->val++;
      map_insert(&a->instances, iid)->val = writer;
      a->count++;
      ok = true;
    }
  }
  if (!ok) a->refused++;
  pthread_mutex_unlock(&a->lock);
  return ok;
}

bool palp_srv_admission_holds(palp_srv_admission *a, uint64_t iid) {
  pthread_mutex_lock(&a->lock);
  const bool held = map_find(&a->instances, iid) != NULL;
  pthread_mutex_unlock(&a->lock);
  return held;
}

/* A writer's count with this bit set: the writer is gone, its instances are being erased. Set and
 * cleared under the lock, so the filter never sees it. */
#define GONE_BIT (1ULL << 63)

/* Erases the instances of the `n` writers gone[], and the writers; returns the instances erased.
 * One pass over the instance map, each entry's writer looked up by hash: until 2026-12-06 each
 * instance was found by a scan from slot 0, (instances x table size) probes, ~3.5e10 to empty the
 * largest config's table. The pass stays on a slot it erased: the backward shift may have moved an
 * entry not yet looked at into it. Entries only move back along their run, so one not yet looked at
 * lands on this slot or a later one; one that wraps from the table's start to its end was looked at
 * already (and kept). So one pass leaves none of a gone writer's. */
static int release_writers(palp_srv_admission *a, const uint64_t *gone, int n) {
  int marked = 0, released = 0;
  for (int k = 0; k < n; k++) {
    entry *w = map_find(&a->writers, gone[k]);
    if (w && !(w->val & GONE_BIT)) w->val |= GONE_BIT, marked++;
  }
  if (!marked) return 0;
  for (uint32_t i = 0; i <= a->instances.mask;) {
    const entry *e = &a->instances.e[i];
    const entry *w = e->key ? map_find(&a->writers, e->val) : NULL;
    if (w && (w->val & GONE_BIT)) {
      map_erase(&a->instances, &a->instances.e[i]);
      released++;
      continue; /* the same slot again */
    }
    i++;
  }
  for (int k = 0; k < n; k++) {
    entry *w = map_find(&a->writers, gone[k]);
    if (w) map_erase(&a->writers, w);
  }
  a->count -= released;
  return released;
}

int palp_srv_admission_sweep(palp_srv_admission *a, int (*matched)(uint64_t writer, void *arg), void *arg) {
  int n = 0, gone = 0;
  pthread_mutex_lock(&a->lock);
  for (uint32_t i = 0; i <= a->writers.mask && n < a->capacity; i++)
    if (a->writers.e[i].key != 0) a->swept[n++] = a->writers.e[i].key;
  pthread_mutex_unlock(&a->lock);
  /* Asked only now: every writer copied above was matched when it was admitted, so a `matched` that
   * looks at the matched writers once, at its first call, still sees every one of them that lives. */
  for (int k = 0; k < n; k++)
    /* Not matched now means gone for good (publication handles are never reused): it can send
     * nothing more, so no instance of it is let in twice. */
    if (!matched(a->swept[k], arg)) a->swept[gone++] = a->swept[k];
  if (!gone) return 0;
  pthread_mutex_lock(&a->lock);
  const int released = release_writers(a, a->swept, gone);
  pthread_mutex_unlock(&a->lock);
  return released;
}

uint64_t palp_srv_admission_refused(palp_srv_admission *a) {
  pthread_mutex_lock(&a->lock);
  uint64_t n = a->refused;
  pthread_mutex_unlock(&a->lock);
  return n;
}

int palp_srv_admission_count(palp_srv_admission *a) {
  pthread_mutex_lock(&a->lock);
  int n = a->count;
  pthread_mutex_unlock(&a->lock);
  return n;
}

bool palp_srv_admission_join_token(palp_srv_admission *a, int64_t now_ns) {
  if (a->last_ns >= 0) {
    a->tokens += (double)(now_ns - a->last_ns) * 1e-9 * a->rate;
    if (a->tokens > a->burst) a->tokens = a->burst;
  }
  a->last_ns = now_ns;
  if (a->tokens < 1) return false;
  a->tokens -= 1;
  return true;
}
