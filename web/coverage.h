/*
 * coverage.h - where on the dome a trainee has pressed, and how hard (palp_web_).
 *
 * Pure geometry on the catalogue's rest mesh (no DDS, no web): every dome vertex owns a third of
 * the area of its dome triangles; a press marks the vertices within the contact's radius of its
 * centre with the pressure band reached (light / medium / deep). Coverage is the share of the
 * dome's area marked at each band or deeper, so it does not depend on how the mesh is refined.
 */
#ifndef PALP_WEB_COVERAGE_H
#define PALP_WEB_COVERAGE_H

#include <stddef.h>
#include <stdint.h>

/* Pressure bands of the force gauge [N]: light below light_max, medium up to medium_max, deep
 * above; a force below touch_min is resting on the skin, not palpating (docs/web.md). */
typedef struct palp_web_bands {
  double touch_min;
  double light_max;
  double medium_max;
} palp_web_bands;

enum { PALP_WEB_BAND_NONE = 0, PALP_WEB_BAND_LIGHT = 1, PALP_WEB_BAND_MEDIUM = 2, PALP_WEB_BAND_DEEP = 3 };

palp_web_bands palp_web_bands_default(void);
/* 0 when touch_min >= 0 and touch_min < light_max < medium_max (all finite), else PALP_EINVAL. */
int palp_web_bands_check(const palp_web_bands *b);
/* The band of a force magnitude [N]. */
int palp_web_band(const palp_web_bands *b, double force);
const char *palp_web_band_name(int band);

typedef struct palp_web_coverage palp_web_coverage;

/* rest: n vertices (x, y, z) [m]; tri: 3 indices per triangle, the first dome_tris of them the
 * dome. Every index is checked. Returns NULL and *rc (PALP_EINVAL, PALP_ENOMEM) on failure. */
palp_web_coverage *palp_web_coverage_create(const double *rest, int n, const int32_t *tri, int tri_count,
                                            int dome_tris, int *rc);
void palp_web_coverage_destroy(palp_web_coverage *c);
void palp_web_coverage_reset(palp_web_coverage *c);

/* Marks every dome vertex within `radius` [m] of `center` (its projection onto the rest surface:
 * the vertex nearest to it and its neighbours in that radius) as pressed in `band`. Returns the
 * number of vertices whose deepest band rose or that had not been pressed in this band. */
int palp_web_coverage_press(palp_web_coverage *c, const double center[3], double radius, int band);

/* The assessment's footprint (src/assess.c: every vertex of the dome triangles the fingertip
 * touches) as near as the wire lets the bridge come: a local model gives how many triangles are in
 * contact and the contact point, not which. The touched patch is taken as the `count` dome
 * triangles whose rest centroids lie nearest `point` (at most PALP_WEB_COVERAGE_TRIANGLES_MAX);
 * their vertices are marked in `band`. Returns as palp_web_coverage_press. */
#define PALP_WEB_COVERAGE_TRIANGLES_MAX 64
int palp_web_coverage_press_triangles(palp_web_coverage *c, const double point[3], int count, int band);

/* Area fractions of the dome pressed at least light / medium / deep, each in [0, 1]. */
void palp_web_coverage_fractions(const palp_web_coverage *c, double out[3]);
/* Area fractions pressed in the light / medium / deep band itself, as the assessment counts an
 * exercise's thoroughness (a place pressed only deep counts for deep alone), each in [0, 1]. */
void palp_web_coverage_band_fractions(const palp_web_coverage *c, double out[3]);
double palp_web_coverage_dome_area(const palp_web_coverage *c);

#endif
