/*
 * palp_dds_reaper.h - DDS entities deleted on a thread of their own, off a loop that must keep its pace.
 *
 * dds_delete of a reliable writer (or of the publisher that holds it) waits until every matched
 * reader has acknowledged what the writer wrote, up to Cyclone's WriterLingerDuration (1 s by
 * default). A session's last samples are written just before its entities are deleted (palp-web's
 * LEAVE and dispose of its request; the server's CLOSED state, debrief and answers), and their
 * acknowledgement comes with the reader's answer to the writer's next heartbeat: palp-web's DDS thread
 * stood 0.20 s in one such delete (web_dashboard, 2026-12-07), the server's main loop 0.10 s (the
 * demo), each sending nothing meanwhile, a class closing at once standing that long per session; and a
 * full second per session against a stalled reader. As Redis's bio.c takes slow closes off its event
 * loop, the owner hands such an entity to the reaper, whose thread deletes it, one at a time, in the
 * order handed.
 *
 * An entity handed over is the reaper's: its owner never touches the handle again. Bounded: at most
 * `capacity` wait; when they are that many palp_dds_reaper_put refuses (PALP_DDS_REAPER_FULL) and the
 * owner deletes the entity itself, as before (slow, never lost). Anything whose deletion must be over
 * before the owner goes on (a reader whose filter's argument the owner is about to free) is not handed
 * over.
 */
#ifndef PALP_DDS_REAPER_H
#define PALP_DDS_REAPER_H

#include <stdint.h>

#include "dds/dds.h"

#define PALP_DDS_REAPER_FULL (-7) /* PALP_EFULL */

typedef struct palp_dds_reaper palp_dds_reaper;

typedef struct palp_dds_reaper_stats {
  uint64_t handed;     /* entities taken (put returned 0) */
  uint64_t deleted;    /* of them, deleted */
  uint64_t refused;    /* put refused: the queue was full (the owner deleted them itself) */
  int pending;         /* taken, not yet deleted (the one being deleted among them) */
  int64_t longest_ns;  /* the longest single dds_delete on the reaper's thread */
  int64_t total_ns;    /* the reaper thread's time in dds_delete, all told */
} palp_dds_reaper_stats;

/* NULL on failure (no memory, no thread). */
palp_dds_reaper *palp_dds_reaper_create(int capacity);
/* [the owner's thread] 0: `e` is the reaper's; PALP_DDS_REAPER_FULL: it is still the caller's; -1 for
 * e <= 0. */
int palp_dds_reaper_put(palp_dds_reaper *r, dds_entity_t e);
void palp_dds_reaper_stats_get(palp_dds_reaper *r, palp_dds_reaper_stats *out);
/* Deletes what is still waiting (each as slowly as it takes), stops the thread, frees the reaper.
 * Call before deleting the participant that holds the entities. NULL is a no-op. */
void palp_dds_reaper_destroy(palp_dds_reaper *r);

#endif
