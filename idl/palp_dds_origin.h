/*
 * palp_dds_origin.h - which partition a sample's writer wrote it in.
 *
 * DDS Security's permissions say who may write in which partition (a trainee: contacts and findings
 * in her own "palp/s/NAME/..." partitions), never which session id the sample names. palp-web and palp-recorder
 * read every session's partition through one subscriber ("palp/s/" "*"), and the session gate
 * (palp_dds_gate.h) passes a sample by the session id it names: so trainee bob, writing in his own
 * "palp/s/bob/9", could name alice's session 7 and have his contacts and marks shown on the
 * dashboard and recorded as hers. The server is not fooled (it reads each session in its own
 * partition); its classroom-wide readers now check that a sample naming session S was written in
 * S's partition ("palp/s/alice/7"), from the writer's publisher partition as discovery announced it
 * (dds_get_matched_publication_data), cached per writer.
 *
 * The owner's thread alone uses an origin (no lock); the cache is bounded (PALP_DDS_ORIGIN_WRITERS
 * writers) and, full, forgets one writer at a time: each writer has a set of PALP_DDS_ORIGIN_WAYS
 * entries (by its handle's hash) and a new one takes the place of one in its set not used since the
 * hand last passed it (a clock). Until 2026-12-06 it emptied itself whole at three quarters full: past
 * ~770 writers (~100 sessions of a recorder's) nearly every sample missed, and a miss walks the
 * reader's matched writers and copies a QoS (dds_get_matched_publication_data). A writer still matched
 * that was forgotten is simply looked up again.
 */
#ifndef PALP_DDS_ORIGIN_H
#define PALP_DDS_ORIGIN_H

#include <stdint.h>

#include "dds/dds.h"

#define PALP_DDS_ORIGIN_WRITERS 1024
#define PALP_DDS_ORIGIN_WAYS 4 /* entries a writer may take (its set): a lookup compares at most these */
#define PALP_DDS_ORIGIN_SETS (PALP_DDS_ORIGIN_WRITERS / PALP_DDS_ORIGIN_WAYS)
#define PALP_DDS_ORIGIN_PARTITION 64 /* SessionState.partition: string<63> */

typedef struct palp_dds_origin_writer {
  dds_instance_handle_t pub;                /* 0: a free entry */
  dds_instance_handle_t participant;        /* its participant's instance handle (discovery's) */
  char partition[PALP_DDS_ORIGIN_PARTITION]; /* its one partition; "" when several, none or too long */
  uint8_t used;                             /* found since the clock's hand last passed it */
} palp_dds_origin_writer;

typedef struct palp_dds_origin {
  palp_dds_origin_writer w[PALP_DDS_ORIGIN_WRITERS]; /* set k: w[k * WAYS .. k * WAYS + WAYS - 1] */
  uint8_t hand[PALP_DDS_ORIGIN_SETS];                /* each set's clock hand */
  uint64_t lookups;                                  /* writers looked up in DDS (a cache miss each) */
  uint64_t evictions;                                /* writers forgotten to make room for another */
} palp_dds_origin;

/* What a sample's writer is, against a partition (palp_dds_origin_check). */
typedef enum palp_dds_origin_verdict {
  PALP_DDS_ORIGIN_SAME = 1,    /* written in exactly that partition */
  PALP_DDS_ORIGIN_OTHER = 0,   /* in another partition, in several, or in none */
  PALP_DDS_ORIGIN_UNKNOWN = -1 /* its writer is no longer matched and was not seen while it was */
} palp_dds_origin_verdict;

void palp_dds_origin_init(palp_dds_origin *o);
/* Whether the sample `info` describes (taken from `reader`) was written in `partition`. */
palp_dds_origin_verdict palp_dds_origin_check(palp_dds_origin *o, dds_entity_t reader, const dds_sample_info_t *info,
                                              const char *partition);
/* The partition the writer of `info`'s sample writes in, as the cache knows it ("" when several or
 * none; NULL when unknown): for messages. */
const char *palp_dds_origin_partition(palp_dds_origin *o, dds_entity_t reader, const dds_sample_info_t *info);
/* The participant of the writer of `info`'s sample (its instance handle, the same from every reader),
 * 0 when unknown: palp-recorder tells a server's runs apart by it (db/recorder/recorder.c). */
dds_instance_handle_t palp_dds_origin_participant(palp_dds_origin *o, dds_entity_t reader, const dds_sample_info_t *info);

/* The cache itself (the calls above use it; exposed for its test, tests/db/test_recorder_origin.c):
 * the entry of writer `pub` (marked used), NULL when not cached; and `pub` entered (partition ""
 * when NULL), one of its set forgotten when the set is full. pub 0 is no writer: NULL. */
const palp_dds_origin_writer *palp_dds_origin_find(palp_dds_origin *o, dds_instance_handle_t pub);
const palp_dds_origin_writer *palp_dds_origin_put(palp_dds_origin *o, dds_instance_handle_t pub,
                                                  dds_instance_handle_t participant, const char *partition);

#endif
