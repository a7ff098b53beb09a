/* label_index.c - see label_index.h. */
#include "label_index.h"

#include <limits.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* FNV-1a, 64 bit: a short, well-mixed hash for short text keys. */
static uint64_t hash(const char *s) {
  uint64_t h = 1469598103934665603ull;
  for (; *s; ++s) h = (h ^ (unsigned char)*s) * 1099511628211ull;
  return h;
}

static int alloc_slots(label_index *t, size_t cap) {
  t->key = calloc(cap, sizeof *t->key);
  t->id = malloc(cap * sizeof *t->id);
  if (!t->key || !t->id) {
    free(t->key);
    free(t->id);
    t->key = NULL;
    t->id = NULL;
    return -1;
  }
  t->cap = cap;
  return 0;
}

/* Linear probing; cap is a power of two and never more than half full. */
static size_t slot_of(const label_index *t, const char *key) {
  size_t i = (size_t)hash(key) & (t->cap - 1);
  while (t->key[i] && strcmp(t->key[i], key) != 0) i = (i + 1) & (t->cap - 1);
  return i;
}

int label_index_init(label_index *t, size_t expected) {
  size_t cap = 16;
  while (cap < 2 * expected && cap < ((size_t)1 << 40)) cap *= 2;
  t->count = 0;
  return alloc_slots(t, cap);
}

static int grow(label_index *t) {
  label_index n = *t;
  if (alloc_slots(&n, t->cap * 2) < 0) return -1;
  for (size_t i = 0; i < t->cap; ++i)
    if (t->key[i]) {
      size_t j = slot_of(&n, t->key[i]);
      n.key[j] = t->key[i];
      n.id[j] = t->id[i];
    }
  free(t->key);
  free(t->id);
  *t = n;
  return 0;
}

int label_index_get(label_index *t, const char *key, int *added) {
  *added = 0;
  size_t i = slot_of(t, key);
  if (t->key[i]) return t->id[i];
  if (t->count >= (size_t)INT_MAX) return -1;
  if (2 * (t->count + 1) > t->cap) {
    if (grow(t) < 0) return -1;
    i = slot_of(t, key);
  }
  t->key[i] = key;
  t->id[i] = (int)t->count++;
  *added = 1;
  return t->id[i];
}

void label_index_free(label_index *t) {
  free(t->key);
  free(t->id);
  t->key = NULL;
  t->id = NULL;
  t->cap = t->count = 0;
}
