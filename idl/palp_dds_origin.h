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
 * writers, emptied when three quarters full: a writer still matched is simply looked up again).
 */
#ifndef PALP_DDS_ORIGIN_H
#define PALP_DDS_ORIGIN_H

#include <stdint.h>

#include "dds/dds.h"

#define PALP_DDS_ORIGIN_WRITERS 1024
#define PALP_DDS_ORIGIN_PARTITION 64 /* SessionState.partition: string<63> */

typedef struct palp_dds_origin_writer {
  dds_instance_handle_t pub;                /* 0: a free entry */
  dds_instance_handle_t participant;        /* its participant's instance handle (discovery's) */
  char partition[PALP_DDS_ORIGIN_PARTITION]; /* its one partition; "" when several, none or too long */
} palp_dds_origin_writer;

typedef struct palp_dds_origin {
  palp_dds_origin_writer w[PALP_DDS_ORIGIN_WRITERS];
  int used;
  uint64_t lookups; /* writers looked up in DDS (a cache miss each) */
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

#endif
