/* retire.c - a bounded ring of DDS instances to release after a retention time. */
#include "retire.h"

#include <stdlib.h>
#include <string.h>

int palp_srv_retire_init(palp_srv_retire *r, int capacity, double retention_s) {
  memset(r, 0, sizeof *r);
  r->ring = calloc((size_t)capacity, sizeof *r->ring);
  if (!r->ring) return -1;
  r->cap = capacity;
  r->retention_ns = (int64_t)(retention_s * 1e9);
  return 0;
}

void palp_srv_retire_free(palp_srv_retire *r) {
  free(r->ring);
  r->ring = NULL;
}

static void pop(palp_srv_retire *r, void (*release)(void *, const palp_srv_retire_entry *), void *ctx) {
  palp_srv_retire_entry e = r->ring[r->head];
  r->head = (r->head + 1) % r->cap;
  r->count--;
  release(ctx, &e);
  r->released++;
}

void palp_srv_retire_add(palp_srv_retire *r, const palp_srv_retire_entry *e, int64_t now_ns,
                         void (*release)(void *, const palp_srv_retire_entry *), void *ctx) {
  if (r->count == r->cap) pop(r, release, ctx);
  palp_srv_retire_entry *slot = &r->ring[(r->head + r->count) % r->cap];
  *slot = *e;
  slot->due_ns = now_ns + r->retention_ns;
  r->count++;
}

void palp_srv_retire_due(palp_srv_retire *r, int64_t now_ns,
                         void (*release)(void *, const palp_srv_retire_entry *), void *ctx) {
  /* Entries are added with one retention, so due times are in ring order. */
  while (r->count > 0 && r->ring[r->head].due_ns <= now_ns) pop(r, release, ctx);
}
