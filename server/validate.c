/* validate.c - checks on every incoming contact sample. */
#include "validate.h"

#include <math.h>

static const char *const reject_names[PALP_SRV_REJ_COUNT] = {
    "nonfinite",  "unknown_session", "bad_finger", "bad_mode",  "bad_distribution",
    "bad_vertex", "out_of_reach",    "force_limit", "bad_radius", "model_refused",
    "absurd_force", "foreign_participant"};

const char *palp_srv_reject_name(palp_srv_reject_reason r) {
  return (unsigned)r < PALP_SRV_REJ_COUNT ? reject_names[r] : "unknown";
}

static int finite3(palp_Vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }
static double norm3(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }
/* |v| without overflow: 1e300 N must come out as 1e300, not as infinity (whose
 * clamp factor max/|F| would be 0 and apply a 1e300 N press as 0 N). */
static double norm3_safe(palp_vec3 v) {
  double m = fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z)));
  if (!(m > 0) || !isfinite(m)) return m;
  palp_vec3 u = {v.x / m, v.y / m, v.z / m};
  return m * norm3(u);
}
static palp_vec3 vec(palp_Vec3 v) { return (palp_vec3){v.x, v.y, v.z}; }

/* Patch areas between 0.1 cm^2 and half the dome's surface (pi R^2 of 2 pi R^2). */
#define PATCH_AREA_MIN 1e-5

int palp_srv_validate_contact(const palp_Contact *in, const palp_srv_limits *lim, palp_srv_contact *out,
                              palp_srv_reject_reason *reason) {
#define REJECT(r)                                                                                       \
  do {                                                                                                  \
    *reason = (r);                                                                                      \
    return PALP_SRV_REJECT;                                                                             \
  } while (0)
  const double R = lim->phantom_radius;
  if (in->session_id != lim->session_id) REJECT(PALP_SRV_REJ_UNKNOWN_SESSION);
  if (in->finger >= PALP_SRV_MAX_FINGERS) REJECT(PALP_SRV_REJ_BAD_FINGER);
  out->finger = in->finger;
  out->mode = (int)in->mode;
  out->seq = in->seq;
  out->source_time_ns = in->source_time_ns;
  out->force = (palp_vec3){0, 0, 0};
  out->radius = 0;
  out->patch_area = 0;
  out->distribution = PALP_DIST_SINGLE;
  out->offset_dir = (palp_vec3){0, 0, 0};
  switch (in->mode) {
  case palp_CONTACT_RELEASE: return PALP_SRV_ACCEPT;
  case palp_CONTACT_FORCE: {
    if (!finite3(in->center) || !finite3(in->force) || !finite3(in->offset_dir) ||
        !isfinite(in->patch_area))
      REJECT(PALP_SRV_REJ_NONFINITE);
    if (in->distribution < 1 || in->distribution > 4) REJECT(PALP_SRV_REJ_BAD_DISTRIBUTION);
    const double pi = 3.14159265358979323846;
    double area_max = pi * R * R;
    if (in->patch_area != 0 && (in->patch_area < PATCH_AREA_MIN || in->patch_area > area_max))
      REJECT(PALP_SRV_REJ_BAD_DISTRIBUTION);
    if (in->vertex >= lim->vertex_count) REJECT(PALP_SRV_REJ_BAD_VERTEX);
    palp_vec3 c = in->vertex >= 0 ? lim->rest[in->vertex] : vec(in->center);
    /* The centre is snapped to the nearest dome vertex; a point more than a
     * radius off the surface is a unit or frame error, not a palpation. */
    if (norm3(c) > 2.0 * R) REJECT(PALP_SRV_REJ_OUT_OF_REACH);
    out->distribution = (palp_distribution)in->distribution;
    out->center = c;
    out->patch_area = in->patch_area;
    out->offset_dir = vec(in->offset_dir);
    out->force = vec(in->force);
    double f = norm3_safe(out->force);
    /* A force far beyond any hand is a unit error or an attack: scaling it down
     * would apply a press nobody made, so it is refused with its own reason. */
    if (!(f <= lim->absurd_force)) REJECT(PALP_SRV_REJ_ABSURD_FORCE);
    if (f > lim->max_force) {
      *reason = PALP_SRV_REJ_FORCE_LIMIT;
      if (lim->force_policy == PALP_SRV_FORCE_REJECT) return PALP_SRV_REJECT;
      double s = lim->max_force / f;
      out->force = (palp_vec3){out->force.x * s, out->force.y * s, out->force.z * s};
      return PALP_SRV_CLAMPED;
    }
    return PALP_SRV_ACCEPT;
  }
  case palp_CONTACT_FINGER: {
    if (!finite3(in->center) || !isfinite(in->radius)) REJECT(PALP_SRV_REJ_NONFINITE);
    if (in->radius < lim->finger_radius_min || in->radius > lim->finger_radius_max)
      REJECT(PALP_SRV_REJ_BAD_RADIUS);
    out->center = vec(in->center);
    /* A hovering finger is legitimate, but one ten radii away is a unit error
     * (mm sent as m) that must not reach the model. */
    if (norm3(out->center) > PALP_SRV_FINGER_REACH_RADII * R) REJECT(PALP_SRV_REJ_OUT_OF_REACH);
    out->radius = in->radius;
    return PALP_SRV_ACCEPT;
  }
  default: REJECT(PALP_SRV_REJ_BAD_MODE);
  }
#undef REJECT
}
