/* place.c - the clock position and the arc from the pole of a place on the phantom. */
#include "palp_place.h"

#include <math.h>
#include <stdio.h>

#include "vec3.h" /* PALP_PI */

double palp_place_clock_hours(palp_vec3 p) {
  /* Angle clockwise from +y seen from above (+z towards the viewer), in hours of a clock face. */
  const double a = atan2(p.x, p.y); /* 0 at +y, +pi/2 at +x [rad] */
  double h = a / (2.0 * PALP_PI) * 12.0;
  if (h <= 0.0) h += 12.0;
  return h;
}

double palp_place_clock_shown(palp_vec3 p) {
  /* whole steps, so the value printed with one decimal (or sent) is exactly the one rounded here */
  long n = lround(palp_place_clock_hours(p) / PALP_PLACE_CLOCK_STEP);
  if (n <= 0) n = lround(12.0 / PALP_PLACE_CLOCK_STEP); /* 12 o'clock is 12.0, never 0.0 */
  return (double)n * PALP_PLACE_CLOCK_STEP;
}

double palp_place_mm_shown(double metres) {
  const double mm = metres * 1e3;
  /* nearbyint: the current rounding mode (to nearest, ties to even), as printf's "%.0f" of the same double */
  return isfinite(mm) ? nearbyint(mm) : 0.0;
}

double palp_place_arc(palp_vec3 p) {
  /* the great-circle distance from the pole of the sphere through p: r x (angle from +z) [m] */
  const double r = sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
  return r > 0 ? r * acos(fmax(-1.0, fmin(1.0, p.z / r))) : 0.0;
}

int palp_place_at_pole(palp_vec3 p) { return palp_place_arc(p) < PALP_PLACE_POLE_ARC; }

char *palp_place_words(palp_vec3 p, char *buf, size_t len) {
  if (!buf || len == 0) return buf;
  if (palp_place_at_pole(p)) snprintf(buf, len, "at the pole");
  else
    snprintf(buf, len, "at %.1f o'clock, %.0f mm from the pole", palp_place_clock_shown(p),
             palp_place_mm_shown(palp_place_arc(p)));
  return buf;
}
