/* identity.c - the authenticated identity behind a session request (DDS Security). */
#include "identity.h"

#include <stdio.h>
#include <string.h>

#include "palp.h"

int palp_srv_requester_of(dds_entity_t reader, dds_instance_handle_t publication, palp_srv_requester *out) {
  if (!publication) return PALP_EINVAL;
  dds_builtintopic_endpoint_t *ep = dds_get_matched_publication_data(reader, publication);
  if (!ep) return PALP_EINVAL;
  uint32_t n = 0;
  char **parts = NULL;
  int rc = PALP_EINVAL;
  /* Exactly one partition: a writer in two would be allowed only if both were
   * its own, and the server must not have to choose. */
  if (ep->qos && dds_qget_partition(ep->qos, &n, &parts) && n == 1 &&
      palp_dds_identity_from_partition(parts[0], &out->kind, out->name, sizeof out->name) == 0)
    rc = 0;
  for (uint32_t i = 0; i < n; i++) dds_free(parts[i]);
  dds_free(parts);
  dds_builtintopic_free_endpoint(ep);
  return rc;
}

int palp_srv_station_owned_by(const char *station_id, const palp_srv_requester *who) {
  char prefix[64];
  int n = snprintf(prefix, sizeof prefix, "%s/%s/", palp_dds_id_kind_name(who->kind), who->name);
  return n > 0 && (size_t)n < sizeof prefix && strncmp(station_id, prefix, (size_t)n) == 0;
}
