/*
 * identity.h - who sent a session request, when the classroom runs DDS Security.
 *
 * Cyclone DDS 0.10 keeps a remote participant's certificate subject inside DDSI
 * (no C API reaches it), so the server reads the sender's identity from what its
 * signed permissions allow: a station may publish requests only in its own
 * partition "palp/KIND/NAME", the access control plugin checks every remote
 * writer's partitions against the remote's permissions before the reader matches
 * it, and the matched publication's partition is what this module reads back
 * (dds_get_matched_publication_data on the sample's publication handle).
 */
#ifndef PALP_SRV_IDENTITY_H
#define PALP_SRV_IDENTITY_H

#include <dds/dds.h>

#include "palp_dds_security.h"

typedef struct palp_srv_requester {
  palp_dds_id_kind kind; /* trainee or instructor */
  char name[PALP_DDS_NAME_MAX];
} palp_srv_requester;

/* The identity behind the writer `publication` matched by `reader`: 0, or
 * PALP_EINVAL when the writer is unknown (gone) or its partitions are not exactly
 * one identity partition. */
int palp_srv_requester_of(dds_entity_t reader, dds_instance_handle_t publication, palp_srv_requester *out);

/* 1 when station_id belongs to the identity: it starts with "KIND/NAME/". */
int palp_srv_station_owned_by(const char *station_id, const palp_srv_requester *who);

#endif
