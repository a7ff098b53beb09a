/*
 * palp_coverage.h - where on the dome a trainee has pressed, and how hard.
 *
 * Pure geometry on the phantom's rest mesh (as the catalogue sends it): every dome vertex owns a
 * third of the area of its dome triangles; a press marks vertices with the pressure band reached
 * (PALP_BAND_LIGHT / _MEDIUM / _DEEP, palp_assess.h). Coverage is the share of the dome's area
 * marked, so it does not depend on how the mesh is refined. What palp-web's pages and a station's
 * terminal show live; the grade's thoroughness is palp_assess's, from the session log, whose
 * footprint palp_coverage_press_triangles follows (docs/web.md, "Measured against the grade").
 */
#ifndef PALP_COVERAGE_H
#define PALP_COVERAGE_H

#include <stdint.h>

#include "palp_assess.h" /* PALP_BAND_* */

#ifdef __cplusplus
extern "C" {
#endif

typedef struct palp_coverage palp_coverage;

/* rest: n vertices (x, y, z) [m]; tri: 3 indices per triangle, the first dome_tris of them the
 * dome. Every index is checked. Returns NULL and *rc (PALP_EINVAL, PALP_ENOMEM) on failure. */
palp_coverage *palp_coverage_create(const double *rest, int n, const int32_t *tri, int tri_count, int dome_tris,
                                    int *rc);
void palp_coverage_destroy(palp_coverage *c);
void palp_coverage_reset(palp_coverage *c);

/* Marks every dome vertex within `radius` [m] of `center` (its projection onto the rest surface:
 * the vertex nearest to it and its neighbours in that radius) as pressed in `band` (PALP_BAND_LIGHT,
 * _MEDIUM or _DEEP; anything else marks nothing). Returns the number of vertices whose deepest band
 * rose or that had not been pressed in this band. */
int palp_coverage_press(palp_coverage *c, const double center[3], double radius, int band);

/* The assessment's footprint (src/assess.c: every vertex of the dome triangles the fingertip
 * touches) as near as a local model lets a reader of it come (palp-web, a station): it gives how
 * many triangles are in contact and where the fingertip is, not which triangles. The touched patch
 * is taken as the `count` dome triangles whose rest centroids lie nearest `point` projected onto
 * the dome (at most PALP_COVERAGE_TRIANGLES_MAX), `point` the fingertip's centre (the proxy): the
 * patch under it. Their vertices are marked in `band`. Returns as palp_coverage_press. */
#define PALP_COVERAGE_TRIANGLES_MAX 64
int palp_coverage_press_triangles(palp_coverage *c, const double point[3], int count, int band);
/* That patch itself: the `count` dome triangles (indices into tri, which are the mesh's, the dome's
 * first) whose rest centroids lie nearest `point` projected onto the dome, nearest first, into out
 * (room for min(count, PALP_COVERAGE_TRIANGLES_MAX)). Returns how many (0 for bad input). palp-recorder
 * logs a local model's footprint by it (docs/assessment.md, "Recorded over DDS"). */
int palp_coverage_patch(const palp_coverage *c, const double point[3], int count, int32_t *out);

/* The assessment's footprint itself (src/assess.c), where the touched triangles are known (the
 * server's palp_finger_sample, session 71): every vertex of the `count` triangles in tri (indices
 * into the mesh's triangles) that are dome triangles is marked in `band`; base triangles and
 * indices out of range are skipped, as the assessment skips them. Returns as palp_coverage_press. */
int palp_coverage_press_touched(palp_coverage *c, const int32_t *tri, int count, int band);

/* A fingertip's contact as a local model gives it (palp_local_model: its contact point, its centre
 * the proxy, how many triangles it touches, its footprint area), pressed in `band`: the `triangles`
 * triangles under the proxy; without a count, the disc of the footprint's area around the contact
 * point (radius sqrt(area / pi); tip_radius [m] when the area is 0). The one rule palp-web's pages
 * and a station's terminal mark by (docs/web.md, "Measured against the grade"). Returns as
 * palp_coverage_press. */
int palp_coverage_press_contact(palp_coverage *c, const double point[3], const double proxy[3], int triangles,
                                double area, double tip_radius, int band);

/* Each vertex's bands pressed, as bits: 1 light, 2 medium, 4 deep (0: not pressed; off the dome
 * never), into out[n], n the mesh's vertex count. Returns n, or 0 when n is not the mesh's. */
int palp_coverage_vertex_bands(const palp_coverage *c, uint8_t *out, int n);

/* Area fractions of the dome pressed at least light / medium / deep, each in [0, 1]. */
void palp_coverage_fractions(const palp_coverage *c, double out[3]);
/* Area fractions pressed in the light / medium / deep band itself, as the assessment counts an
 * exercise's thoroughness (a place pressed only deep counts for deep alone), each in [0, 1]. */
void palp_coverage_band_fractions(const palp_coverage *c, double out[3]);
double palp_coverage_dome_area(const palp_coverage *c);

#ifdef __cplusplus
}
#endif

#endif
