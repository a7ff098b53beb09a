/*
 * retire.h - releasing the DDS instances of what is over.
 *
 * A closed session's state and the reply to a station that left (or was
 * refused) are transient-local: the server's writers keep them for every late
 * joiner until they are unregistered. Left alone, after 180 sessions every new
 * station was sent 180 old states and 360 old replies. Each is scheduled here
 * when it stops mattering and unregistered `retention` seconds later, so a
 * station that is about to read it still does. The queue is a bounded ring: when
 * full, the oldest entry is released at once.
 */
#ifndef PALP_SRV_RETIRE_H
#define PALP_SRV_RETIRE_H

#include <stdint.h>

#include <dds/dds.h>

typedef enum palp_srv_retire_kind { PALP_SRV_RETIRE_STATE, PALP_SRV_RETIRE_REPLY } palp_srv_retire_kind;

typedef struct palp_srv_retire_entry {
  palp_srv_retire_kind kind;
  uint32_t session_id;   /* STATE */
  char station_id[64];   /* REPLY */
  int64_t due_ns;
} palp_srv_retire_entry;

typedef struct palp_srv_retire {
  palp_srv_retire_entry *ring;
  int cap, head, count;
  int64_t retention_ns;
  uint64_t released;
} palp_srv_retire;

int palp_srv_retire_init(palp_srv_retire *r, int capacity, double retention_s);
void palp_srv_retire_free(palp_srv_retire *r);
/* Schedules a release; when the ring is full the oldest entry is released first
 * through `release`. */
void palp_srv_retire_add(palp_srv_retire *r, const palp_srv_retire_entry *e, int64_t now_ns,
                         void (*release)(void *ctx, const palp_srv_retire_entry *e), void *ctx);
/* Releases every entry due at now_ns. */
void palp_srv_retire_due(palp_srv_retire *r, int64_t now_ns,
                         void (*release)(void *ctx, const palp_srv_retire_entry *e), void *ctx);

#endif
