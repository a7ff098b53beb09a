/*
 * palp_dds_origin.c - which partition a sample's writer wrote it in (palp_dds_origin.h).
 */
#include "palp_dds_origin.h"

#include <string.h>

_Static_assert((PALP_DDS_ORIGIN_SETS & (PALP_DDS_ORIGIN_SETS - 1)) == 0, "a power of two");
_Static_assert(PALP_DDS_ORIGIN_SETS * PALP_DDS_ORIGIN_WAYS == PALP_DDS_ORIGIN_WRITERS, "whole sets");

void palp_dds_origin_init(palp_dds_origin *o) { memset(o, 0, sizeof *o); }

/* Fibonacci hashing of the 64-bit handle onto the sets (handles are counters with a random base:
 * their high bits say little). */
static palp_dds_origin_writer *set_of(palp_dds_origin *o, dds_instance_handle_t pub, size_t *set) {
  *set = (size_t)((pub * 0x9E3779B97F4A7C15ull) >> 40) & (PALP_DDS_ORIGIN_SETS - 1);
  return &o->w[*set * PALP_DDS_ORIGIN_WAYS];
}

const palp_dds_origin_writer *palp_dds_origin_find(palp_dds_origin *o, dds_instance_handle_t pub) {
  if (pub == 0) return NULL;
  size_t k;
  palp_dds_origin_writer *e = set_of(o, pub, &k);
  for (int i = 0; i < PALP_DDS_ORIGIN_WAYS; i++)
    if (e[i].pub == pub) {
      e[i].used = 1;
      return &e[i];
    }
  return NULL;
}

const palp_dds_origin_writer *palp_dds_origin_put(palp_dds_origin *o, dds_instance_handle_t pub,
                                                  dds_instance_handle_t participant, const char *partition) {
  if (pub == 0) return NULL;
  size_t k;
  palp_dds_origin_writer *e = set_of(o, pub, &k), *slot = NULL;
  for (int i = 0; i < PALP_DDS_ORIGIN_WAYS && !slot; i++)
    if (e[i].pub == 0 || e[i].pub == pub) slot = &e[i];
  /* Full: the first the hand finds not used since it last passed (it clears those it passes), so a
   * writer whose samples keep coming stays and one seen once goes; at most two turns. */
  while (!slot) {
    palp_dds_origin_writer *c = &e[o->hand[k]];
    o->hand[k] = (uint8_t)((o->hand[k] + 1) % PALP_DDS_ORIGIN_WAYS);
    if (c->used) c->used = 0;
    else {
      slot = c;
      o->evictions++;
    }
  }
  slot->pub = pub;
  slot->participant = participant;
  slot->partition[0] = '\0';
  if (partition && strlen(partition) < PALP_DDS_ORIGIN_PARTITION) memcpy(slot->partition, partition, strlen(partition) + 1);
  slot->used = 0; /* new: it earns its keep by being found again */
  return slot;
}

/* The writer's one partition as discovery announced it: a publisher in several partitions (or a
 * pattern) is not a session's writer; "" then. */
static void partition_of(const dds_builtintopic_endpoint_t *ep, char *out) {
  out[0] = '\0';
  uint32_t n = 0;
  char **ps = NULL;
  if (!ep->qos || !dds_qget_partition(ep->qos, &n, &ps)) return;
  if (n == 1 && ps[0] && strlen(ps[0]) < PALP_DDS_ORIGIN_PARTITION && !strpbrk(ps[0], "*?"))
    memcpy(out, ps[0], strlen(ps[0]) + 1);
  for (uint32_t i = 0; i < n; i++) dds_free(ps[i]);
  dds_free(ps);
}

static const palp_dds_origin_writer *lookup(palp_dds_origin *o, dds_entity_t reader, dds_instance_handle_t pub) {
  if (pub == 0) return NULL;
  const palp_dds_origin_writer *w = palp_dds_origin_find(o, pub);
  if (w) return w;
  /* Not cached: ask the reader, which knows its matched writers (a writer already gone is
   * unknown: its samples are not vouched for). */
  dds_builtintopic_endpoint_t *ep = dds_get_matched_publication_data(reader, pub);
  o->lookups++;
  if (!ep) return NULL;
  char partition[PALP_DDS_ORIGIN_PARTITION];
  partition_of(ep, partition);
  w = palp_dds_origin_put(o, pub, ep->participant_instance_handle, partition);
  dds_builtintopic_free_endpoint(ep);
  return w;
}

palp_dds_origin_verdict palp_dds_origin_check(palp_dds_origin *o, dds_entity_t reader, const dds_sample_info_t *info,
                                              const char *partition) {
  const palp_dds_origin_writer *w = lookup(o, reader, info->publication_handle);
  if (!w) return PALP_DDS_ORIGIN_UNKNOWN;
  return w->partition[0] && partition && !strcmp(w->partition, partition) ? PALP_DDS_ORIGIN_SAME : PALP_DDS_ORIGIN_OTHER;
}

const char *palp_dds_origin_partition(palp_dds_origin *o, dds_entity_t reader, const dds_sample_info_t *info) {
  const palp_dds_origin_writer *w = lookup(o, reader, info->publication_handle);
  return w ? w->partition : NULL;
}

dds_instance_handle_t palp_dds_origin_participant(palp_dds_origin *o, dds_entity_t reader, const dds_sample_info_t *info) {
  const palp_dds_origin_writer *w = lookup(o, reader, info->publication_handle);
  return w ? w->participant : 0;
}
