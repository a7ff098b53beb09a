/*
 * events.h - the seam between the server and whatever records sessions.
 *
 * The server calls these hooks; the database layer (db/) implements them. Hooks
 * marked [tick thread] run inside a 1 ms tick: they must only copy into a queue
 * and return (Redis bio.c style: a worker thread does the slow, durable write).
 * Every hook may be NULL. The ctx pointer is the implementer's.
 */
#ifndef PALP_SRV_EVENTS_H
#define PALP_SRV_EVENTS_H

#include <stdint.h>

#include "palp.h"
#include "validate.h"

typedef struct palp_srv_session_info {
  uint32_t session_id;
  uint32_t phantom_id;
  const char *phantom_name;
  const char *trainee_station; /* DDS station id of the trainee */
  const char *trainee_name;
  const char *partition;
  double tick_rate_hz;
  int64_t opened_ns;           /* CLOCK_MONOTONIC */
} palp_srv_session_info;

typedef struct palp_srv_session_summary {
  palp_srv_session_info info;
  double duration;             /* [s] wall time open */
  uint64_t ticks, overruns, awake_ticks;
  uint64_t contact_samples;    /* accepted or clamped */
  uint64_t rejected[PALP_SRV_REJ_COUNT];
  double peak_force;           /* [N] */
  double peak_displacement;    /* [m] */
  const char *close_reason;
} palp_srv_session_summary;

typedef struct palp_srv_events {
  void *ctx;
  /* [main thread] a trainee's session opened. */
  void (*session_opened)(void *ctx, const palp_srv_session_info *info);
  /* [main thread] a session closed; the summary is final. */
  void (*session_closed)(void *ctx, const palp_srv_session_summary *summary);
  /* [main thread] a visual station or observer joined or left a session. */
  void (*member_changed)(void *ctx, uint32_t session_id, const char *station, int role, int joined);
  /* [tick thread] a validated contact was applied at simulated time t [s]. */
  void (*contact_applied)(void *ctx, uint32_t session_id, const palp_srv_contact *c, double t);
  /* [tick thread] a sample was rejected (reason) or clamped. */
  void (*contact_rejected)(void *ctx, uint32_t session_id, palp_srv_reject_reason reason, int clamped);
  /* [tick thread] after a step that had contacts or motion: frame, simulated
   * time [s], pole displacement [m] and per-finger feedback force [N]. */
  void (*frame)(void *ctx, uint32_t session_id, int64_t frame, double t, double top_displacement,
                const palp_vec3 *finger_force, const uint8_t *finger_active, int fingers);
} palp_srv_events;

#endif
