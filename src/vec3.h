/* vec3.h - small inline vector helpers shared by the model's modules (internal). */
#ifndef PALP_VEC3_H
#define PALP_VEC3_H

#include <math.h>

#include "palp.h"

#define PALP_PI 3.14159265358979323846

static inline palp_vec3 v3(double x, double y, double z) { return (palp_vec3){x, y, z}; }
static inline palp_vec3 v3_add(palp_vec3 a, palp_vec3 b) { return (palp_vec3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static inline palp_vec3 v3_sub(palp_vec3 a, palp_vec3 b) { return (palp_vec3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static inline palp_vec3 v3_scale(palp_vec3 a, double s) { return (palp_vec3){a.x * s, a.y * s, a.z * s}; }
static inline double v3_dot(palp_vec3 a, palp_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline double v3_len(palp_vec3 a) { return sqrt(v3_dot(a, a)); }
static inline palp_vec3 v3_cross(palp_vec3 a, palp_vec3 b) {
  return (palp_vec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline int v3_isfinite(palp_vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }

#endif
