/*
 * palp_place.h - a place on the phantom, named for reading by hand (docs/naming.md, "position on
 * the phantom"): the clock position seen from above (12 o'clock = +y, 3 o'clock = +x) and the arc
 * from the pole along the surface. Every tool that names a place names it by these.
 */
#ifndef PALP_PLACE_H
#define PALP_PLACE_H

#include "palp.h"

/* The clock position of p seen from above, in hours (0, 12]: 12 at +y, 3 at +x. */
double palp_place_clock_hours(palp_vec3 p);
/* The arc from the pole to p along the sphere through p centred at the base's centre [m]:
 * |p| x (angle of p from +z). */
double palp_place_arc(palp_vec3 p);

#endif
