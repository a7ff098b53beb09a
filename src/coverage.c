/* coverage.c - where on the dome a trainee has pressed, and how hard (palp_coverage.h). */
#include "palp_coverage.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h" /* PALP_E* codes */
#include "vec3.h" /* PALP_PI */

struct palp_coverage {
  int n;
  double *rest;    /* 3n [m] */
  double *area;    /* per vertex: a third of its dome triangles' area [m^2]; 0 off the dome */
  uint8_t *band;   /* per vertex: deepest band pressed, 1 light .. 3 deep, 0 none */
  uint8_t *bits;   /* per vertex: the bands pressed, 1 << (1 light .. 3 deep) */
  double dome_area;
  double radius;      /* the largest |rest| [m]: the dome's, at its pole */
  int dome_tris;
  int32_t *tri;       /* 3 per dome triangle */
  double *centroid;   /* 3 per dome triangle, on the rest mesh [m] */
  double at_least[4]; /* area pressed at band >= k, kept current by press */
  double in_band[4];  /* area pressed in band k itself, kept current by press */
};

palp_coverage *palp_coverage_create(const double *rest, int n, const int32_t *tri, int tri_count, int dome_tris,
                                    int *rc) {
  *rc = PALP_EINVAL;
  if (!rest || !tri || n <= 0 || tri_count <= 0 || dome_tris <= 0 || dome_tris > tri_count) return NULL;
  for (int i = 0; i < 3 * tri_count; i++)
    if (tri[i] < 0 || tri[i] >= n) return NULL;
  for (int i = 0; i < 3 * n; i++)
    if (!isfinite(rest[i])) return NULL;
  *rc = PALP_ENOMEM;
  palp_coverage *c = calloc(1, sizeof *c);
  if (!c) return NULL;
  c->n = n;
  c->rest = malloc(sizeof *c->rest * 3 * (size_t)n);
  c->area = calloc((size_t)n, sizeof *c->area);
  c->band = calloc((size_t)n, 1);
  c->bits = calloc((size_t)n, 1);
  c->dome_tris = dome_tris;
  c->tri = malloc(sizeof *c->tri * 3 * (size_t)dome_tris);
  c->centroid = malloc(sizeof *c->centroid * 3 * (size_t)dome_tris);
  if (!c->rest || !c->area || !c->band || !c->bits || !c->tri || !c->centroid) {
    palp_coverage_destroy(c);
    return NULL;
  }
  memcpy(c->rest, rest, sizeof *c->rest * 3 * (size_t)n);
  memcpy(c->tri, tri, sizeof *c->tri * 3 * (size_t)dome_tris);
  for (int i = 0; i < n; i++) {
    const double *p = rest + 3 * i;
    c->radius = fmax(c->radius, sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
  }
  for (int t = 0; t < dome_tris; t++) {
    const double *a = rest + 3 * tri[3 * t], *b = rest + 3 * tri[3 * t + 1], *d = rest + 3 * tri[3 * t + 2];
    for (int k = 0; k < 3; k++) c->centroid[3 * t + k] = (a[k] + b[k] + d[k]) / 3.0;
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    const double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2], z = u[0] * v[1] - u[1] * v[0];
    const double area = 0.5 * sqrt(x * x + y * y + z * z);
    for (int k = 0; k < 3; k++) c->area[tri[3 * t + k]] += area / 3.0;
    c->dome_area += area;
  }
  *rc = 0;
  return c;
}

void palp_coverage_destroy(palp_coverage *c) {
  if (!c) return;
  free(c->rest);
  free(c->area);
  free(c->band);
  free(c->bits);
  free(c->tri);
  free(c->centroid);
  free(c);
}

void palp_coverage_reset(palp_coverage *c) {
  memset(c->band, 0, (size_t)c->n);
  memset(c->bits, 0, (size_t)c->n);
  memset(c->at_least, 0, sizeof c->at_least);
  memset(c->in_band, 0, sizeof c->in_band);
}

/* Vertex i pressed in `band` (1 light .. 3 deep here: 0 is "none" in c->band): 1 when its deepest
 * band rose or it had not been pressed in this band. */
static int mark(palp_coverage *c, int i, int band) {
  const uint8_t bit = (uint8_t)(1u << band);
  if (c->area[i] <= 0 || (c->band[i] >= band && (c->bits[i] & bit))) return 0;
  if (!(c->bits[i] & bit)) c->bits[i] |= bit, c->in_band[band] += c->area[i];
  for (int k = c->band[i] + 1; k <= band; k++) c->at_least[k] += c->area[i];
  if (c->band[i] < band) c->band[i] = (uint8_t)band;
  return 1;
}

int palp_coverage_press(palp_coverage *c, const double center[3], double radius, int band) {
  if (!c || band < PALP_BAND_LIGHT || band > PALP_BAND_DEEP || !(radius > 0) || !isfinite(radius) ||
      !isfinite(center[0]) || !isfinite(center[1]) || !isfinite(center[2]))
    return 0;
  /* A finger tip's centre lies above or inside the surface, not on it: measure from the dome vertex
   * nearest to it, so a deep press marks the same skin as a light one at the same place. */
  int near = -1;
  double best = INFINITY;
  for (int i = 0; i < c->n; i++) {
    if (c->area[i] <= 0) continue;
    const double *p = c->rest + 3 * i;
    const double d2 = (p[0] - center[0]) * (p[0] - center[0]) + (p[1] - center[1]) * (p[1] - center[1]) +
                      (p[2] - center[2]) * (p[2] - center[2]);
    if (d2 < best) best = d2, near = i;
  }
  if (near < 0) return 0;
  const double *q = c->rest + 3 * near, r2 = radius * radius;
  int raised = 0;
  for (int i = 0; i < c->n; i++) {
    const double *p = c->rest + 3 * i;
    const double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
    if (d2 <= r2) raised += mark(c, i, band + 1);
  }
  return raised;
}

int palp_coverage_patch(const palp_coverage *c, const double point[3], int count, int32_t *out) {
  if (!c || count <= 0 || !out || !isfinite(point[0]) || !isfinite(point[1]) || !isfinite(point[2])) return 0;
  const double len = sqrt(point[0] * point[0] + point[1] * point[1] + point[2] * point[2]);
  if (!(len > 0)) return 0;
  if (count > PALP_COVERAGE_TRIANGLES_MAX) count = PALP_COVERAGE_TRIANGLES_MAX;
  if (count > c->dome_tris) count = c->dome_tris;
  /* The point projected onto the dome (a fingertip's centre lies outside it, a contact point
   * pressed in inside), then the `count` centroids nearest it, by insertion into a sorted list. */
  const double q[3] = {point[0] * c->radius / len, point[1] * c->radius / len, point[2] * c->radius / len};
  int best[PALP_COVERAGE_TRIANGLES_MAX];
  double bd[PALP_COVERAGE_TRIANGLES_MAX];
  int have = 0;
  for (int t = 0; t < c->dome_tris; t++) {
    const double *g = c->centroid + 3 * t;
    const double d2 = (g[0] - q[0]) * (g[0] - q[0]) + (g[1] - q[1]) * (g[1] - q[1]) + (g[2] - q[2]) * (g[2] - q[2]);
    if (have == count && !(d2 < bd[have - 1])) continue;
    int j = have < count ? have++ : have - 1;
    while (j > 0 && bd[j - 1] > d2) bd[j] = bd[j - 1], best[j] = best[j - 1], j--;
    bd[j] = d2, best[j] = t;
  }
  for (int k = 0; k < have; k++) out[k] = best[k];
  return have;
}

int palp_coverage_press_triangles(palp_coverage *c, const double point[3], int count, int band) {
  if (!c || band < PALP_BAND_LIGHT || band > PALP_BAND_DEEP) return 0;
  int32_t patch[PALP_COVERAGE_TRIANGLES_MAX];
  const int have = palp_coverage_patch(c, point, count, patch);
  int raised = 0;
  for (int k = 0; k < have; k++)
    for (int v = 0; v < 3; v++) raised += mark(c, c->tri[3 * patch[k] + v], band + 1);
  return raised;
}

int palp_coverage_press_touched(palp_coverage *c, const int32_t *tri, int count, int band) {
  if (!c || !tri || count <= 0 || band < PALP_BAND_LIGHT || band > PALP_BAND_DEEP) return 0;
  int raised = 0;
  for (int k = 0; k < count; k++) {
    const int32_t t = tri[k];
    if (t < 0 || t >= c->dome_tris) continue; /* base triangles are not palpable */
    for (int v = 0; v < 3; v++) raised += mark(c, c->tri[3 * t + v], band + 1);
  }
  return raised;
}

int palp_coverage_press_contact(palp_coverage *c, const double point[3], const double proxy[3], int triangles,
                                double area, double tip_radius, int band) {
  if (triangles > 0) return palp_coverage_press_triangles(c, proxy, triangles, band);
  const double r = area > 0 && isfinite(area) ? sqrt(area / PALP_PI) : tip_radius;
  return palp_coverage_press(c, point, r, band);
}

int palp_coverage_vertex_bands(const palp_coverage *c, uint8_t *out, int n) {
  if (!c || !out || n != c->n) return 0;
  for (int i = 0; i < n; i++) out[i] = (uint8_t)(c->bits[i] >> 1); /* bits 1 << (1 light .. 3 deep) */
  return n;
}

void palp_coverage_fractions(const palp_coverage *c, double out[3]) {
  for (int k = 0; k < 3; k++) {
    double f = c && c->dome_area > 0 ? c->at_least[k + 1] / c->dome_area : 0;
    out[k] = f < 0 ? 0 : f > 1 ? 1 : f;
  }
}

void palp_coverage_band_fractions(const palp_coverage *c, double out[3]) {
  for (int k = 0; k < 3; k++) {
    double f = c && c->dome_area > 0 ? c->in_band[k + 1] / c->dome_area : 0;
    out[k] = f < 0 ? 0 : f > 1 ? 1 : f;
  }
}

double palp_coverage_dome_area(const palp_coverage *c) { return c ? c->dome_area : 0; }
