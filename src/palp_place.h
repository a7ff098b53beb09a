/*
 * palp_place.h - a place on the phantom, named for reading by hand (docs/naming.md, "position on
 * the phantom"): the clock position seen from above (12 o'clock = +y, 3 o'clock = +x) and the arc
 * from the pole along the surface. Every tool that names a place names it by these.
 */
#ifndef PALP_PLACE_H
#define PALP_PLACE_H

#include <stddef.h>

#include "palp.h"

/* The clock position of p seen from above, in hours (0, 12]: 12 at +y, 3 at +x. */
double palp_place_clock_hours(palp_vec3 p);
/* The clock position as every tool prints and sends it, in hours: palp_place_clock_hours rounded to
 * PALP_PLACE_CLOCK_STEP (what "%.1f" shows), a reading that rounds to 0 given as 12.0. Print and send
 * this, never the raw hours: azimuth 90 deg (12 o'clock) reads 6e-17 h (cos 90 deg is not 0 in
 * floating point), a hair past 0 and so not mapped to 12 by the raw function, and "%.1f" printed
 * "0.0 o'clock" (session 81 review); so did anything within 0.05 h clockwise of +y. */
#define PALP_PLACE_CLOCK_STEP 0.1 /* [h] */
double palp_place_clock_shown(palp_vec3 p);
/* The arc from the pole to p along the sphere through p centred at the base's centre [m]:
 * |p| x (angle of p from +z). */
double palp_place_arc(palp_vec3 p);

/* A length of a place or a lump [m] in the whole millimetres every tool prints it with ("%.0f" of
 * metres x 1e3, the station's debrief and palp-review), as a number to send: rounded as printf rounds
 * (to nearest, a tie to even, in the default rounding mode), so a page that prints it with no decimals
 * reads what the station does. Send this, not a value rounded to 0.1 mm: the page's toFixed(0) then
 * rounded it again, ties up, and 24.46 mm read "25" on the page and "24" on the station (session 82
 * review). Non-finite in, 0 out. */
double palp_place_mm_shown(double metres);

/* Nearer the pole than this along the surface [m], a place has no clock position worth reading, and
 * every tool says "the pole" instead of a clock. One clock hour there spans less than 2 pi s / 12 =
 * 0.52 mm of skin, less than the fingertip's own wander while it holds still (0.1-0.5 mm in the logs),
 * so the hour printed is noise (the demo's presses at the pole read 0.9 h, 6.8 h, 2.0 h before); a
 * lesion at polar 0 has no azimuth at all. Breast reports likewise name a place behind the nipple by
 * its region, not a clock face. */
#define PALP_PLACE_POLE_ARC 1.0e-3
/* 1 when p is within PALP_PLACE_POLE_ARC of the pole along the surface (palp_place_arc), else 0. */
int palp_place_at_pole(palp_vec3 p);

/* The place p in the one phrase every tool prints (docs/naming.md, "position on the phantom"):
 * "at the pole" within PALP_PLACE_POLE_ARC of it, else "at H.H o'clock, N mm from the pole", the
 * clock palp_place_clock_shown's and N the arc (palp_place_arc) in palp_place_mm_shown's whole mm.
 * Written into buf (cut to len - 1 bytes, always terminated when len > 0); returns buf. One function
 * since session 83: the station's debrief and palp-web's trainee page said "mm from the pole along the
 * skin", palp-review and the observer "mm from the pole" (web/www/js/common.js mirrors this). */
char *palp_place_words(palp_vec3 p, char *buf, size_t len);

#endif
