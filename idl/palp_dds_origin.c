/*
 * palp_dds_origin.c - which partition a sample's writer wrote it in (palp_dds_origin.h).
 */
#include "palp_dds_origin.h"

#include <string.h>

_Static_assert((PALP_DDS_ORIGIN_WRITERS & (PALP_DDS_ORIGIN_WRITERS - 1)) == 0, "a power of two");

void palp_dds_origin_init(palp_dds_origin *o) { memset(o, 0, sizeof *o); }

/* Fibonacci hashing of the 64-bit handle onto the table (handles are counters with a random base:
 * their high bits say little). */
static size_t slot_of(dds_instance_handle_t pub) {
  return (size_t)((pub * 0x9E3779B97F4A7C15ull) >> 40) & (PALP_DDS_ORIGIN_WRITERS - 1);
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
  size_t i = slot_of(pub);
  for (; o->w[i].pub != 0; i = (i + 1) & (PALP_DDS_ORIGIN_WRITERS - 1))
    if (o->w[i].pub == pub) return &o->w[i];
  /* Not cached: ask the reader, which knows its matched writers (a writer already gone is
   * unknown: its samples are not vouched for). */
  dds_builtintopic_endpoint_t *ep = dds_get_matched_publication_data(reader, pub);
  o->lookups++;
  if (!ep) return NULL;
  if (o->used >= PALP_DDS_ORIGIN_WRITERS / 4 * 3) { /* a flood of writers: start over */
    memset(o->w, 0, sizeof o->w);
    o->used = 0;
    i = slot_of(pub);
  }
  o->w[i].pub = pub;
  o->w[i].participant = ep->participant_instance_handle;
  partition_of(ep, o->w[i].partition);
  o->used++;
  dds_builtintopic_free_endpoint(ep);
  return &o->w[i];
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
