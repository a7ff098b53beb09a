/*
 * validate.h - checks on every incoming contact sample.
 *
 * A pure function of the sample, the session it arrived in and the limits: the
 * tick thread calls it before anything reaches the model, so a malformed or
 * hostile sample can cost one session nothing but a counted rejection.
 */
#ifndef PALP_SRV_VALIDATE_H
#define PALP_SRV_VALIDATE_H

#include <stdint.h>

#include "config.h"
#include "palp.h"
#include "palp_types.h"

#define PALP_SRV_MAX_FINGERS 4

/* Reasons are indices into the rejected[] counters of palp_server_status; their
 * order is part of the wire contract (docs/server.md). */
typedef enum palp_srv_reject_reason {
  PALP_SRV_REJ_NONFINITE = 0,    /* NaN or infinity in a used field */
  PALP_SRV_REJ_UNKNOWN_SESSION,  /* session_id is not the session of this partition */
  PALP_SRV_REJ_BAD_FINGER,       /* finger index >= PALP_SRV_MAX_FINGERS */
  PALP_SRV_REJ_BAD_MODE,         /* contact mode not release/force/finger */
  PALP_SRV_REJ_BAD_DISTRIBUTION, /* distribution not 1..4, or patch area out of range */
  PALP_SRV_REJ_BAD_VERTEX,       /* vertex index >= vertex count */
  PALP_SRV_REJ_OUT_OF_REACH,     /* contact centre absurdly far from the phantom */
  PALP_SRV_REJ_FORCE_LIMIT,      /* |force| > max_force: clamped or rejected by policy */
  PALP_SRV_REJ_BAD_RADIUS,       /* finger radius outside [finger_radius_min, _max] */
  PALP_SRV_REJ_MODEL,            /* the model refused the contact (e.g. no free slot) */
  /* Reasons past the wire's rejected[10] arrays; published in palp_server_guard. */
  PALP_SRV_REJ_ABSURD_FORCE,     /* |force| > absurd_force: no hand presses that hard; never clamped */
  /* Neither on the wire by reason (the @final ServerGuard has no field for it; counted in
   * SessionState.rejected_samples with the rest) nor checked here: the session checks a sample's
   * writer (server/session.c, take_contacts). In the server's log, its summary and the session log. */
  PALP_SRV_REJ_FOREIGN_PARTICIPANT, /* written (or disposed) by a participant other than the one whose
                                       request writer JOINed the session, or by a writer already gone */
  PALP_SRV_REJ_COUNT
} palp_srv_reject_reason;

/* Reasons carried by the rejected[10] arrays of palp_server_status (wire contract). */
#define PALP_SRV_REJ_WIRE 10

const char *palp_srv_reject_name(palp_srv_reject_reason r);

typedef struct palp_srv_limits {
  uint32_t session_id;
  double max_force;                  /* [N] */
  double absurd_force;               /* [N] above this a sample is rejected, whatever the policy */
  palp_srv_force_policy force_policy;
  double finger_radius_min;          /* [m] */
  double finger_radius_max;          /* [m] */
  double phantom_radius;             /* [m] */
  int vertex_count;
  const palp_vec3 *rest;             /* [vertex_count] rest positions [m] */
} palp_srv_limits;


/* A validated contact, in model terms. */
/* A fingertip's device point farther than this many phantom radii from the centre is
 * a unit error (mm sent as m), refused (PALP_SRV_REJ_OUT_OF_REACH). */
#define PALP_SRV_FINGER_REACH_RADII 10.0

typedef struct palp_srv_contact {
  int finger;
  int mode;                 /* palp_CONTACT_RELEASE / _FORCE / _FINGER */
  palp_distribution distribution;
  palp_vec3 center;         /* [m] */
  palp_vec3 force;          /* [N], after clamping */
  double radius;            /* [m] */
  double patch_area;        /* [m^2] */
  palp_vec3 offset_dir;
  uint64_t seq;
  int64_t source_time_ns;
} palp_srv_contact;

enum {
  PALP_SRV_ACCEPT = 0,  /* apply out */
  PALP_SRV_CLAMPED = 1, /* apply out; *reason says what was corrected */
  PALP_SRV_REJECT = -1  /* drop; *reason says why */
};

int palp_srv_validate_contact(const palp_Contact *in, const palp_srv_limits *lim, palp_srv_contact *out,
                              palp_srv_reject_reason *reason);

#endif
