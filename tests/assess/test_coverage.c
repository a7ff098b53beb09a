/* test_coverage.c - where on the dome a trainee has pressed (src/coverage.c, palp_coverage.h): on a
 * flat square whose areas are exact, and on the model's own mesh (its lumped areas, a brute-force sort
 * of its triangles). What palp-web's pages and the stations show live (docs/web.md). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "palp.h"
#include "palp_coverage.h"

#define PI 3.14159265358979323846

/* A flat 1 m x 1 m square of 2 x 100 x 100 triangles on z = 0: areas are exact. */
static void test_coverage_square(void) {
  enum { N = 100 };
  const int nv = (N + 1) * (N + 1);
  double *rest = malloc(sizeof *rest * 3 * nv);
  int32_t *tri = malloc(sizeof *tri * 6 * N * N);
  for (int j = 0; j <= N; j++)
    for (int i = 0; i <= N; i++) {
      double *p = rest + 3 * (j * (N + 1) + i);
      p[0] = (double)i / N - 0.5, p[1] = (double)j / N - 0.5, p[2] = 0;
    }
  int t = 0;
  for (int j = 0; j < N; j++)
    for (int i = 0; i < N; i++) {
      const int a = j * (N + 1) + i, b = a + 1, c = a + N + 1, d = c + 1;
      int32_t q[6] = {a, b, d, a, d, c};
      memcpy(tri + 6 * t++, q, sizeof q);
    }
  int rc;
  palp_coverage *c = palp_coverage_create(rest, nv, tri, 2 * N * N, 2 * N * N, &rc);
  CHECK(c && rc == 0, "square mesh accepted");
  if (!c) return;
  CHECK(fabs(palp_coverage_dome_area(c) - 1.0) < 1e-12, "area of the unit square %.15g", palp_coverage_dome_area(c));
  double f[3];
  palp_coverage_fractions(c, f);
  CHECK(f[0] == 0 && f[1] == 0 && f[2] == 0, "nothing pressed yet");
  /* Light press of radius 0.1 m at the centre: pi r^2 = 0.0314 of the square, within the lumped
   * vertex areas' resolution (one ring of 0.01 m cells: 2 pi r h / A = 0.0063). */
  const double ctr[3] = {0, 0, 0.02}; /* 2 cm above the surface: measured from the nearest vertex */
  int raised = palp_coverage_press(c, ctr, 0.1, PALP_BAND_LIGHT);
  palp_coverage_fractions(c, f);
  CHECK(raised > 0 && fabs(f[0] - PI * 0.01) < 0.0063, "light disc %.5f vs pi r^2 %.5f", f[0], PI * 0.01);
  CHECK(f[1] == 0 && f[2] == 0, "no medium or deep yet (%g, %g)", f[1], f[2]);
  const double light = f[0];
  /* The same place again, lighter or equal: nothing changes. */
  CHECK(palp_coverage_press(c, ctr, 0.1, PALP_BAND_LIGHT) == 0, "re-press at the same band raises nothing");
  /* Deep at the same place: all three fractions equal the disc. */
  palp_coverage_press(c, ctr, 0.1, PALP_BAND_DEEP);
  palp_coverage_fractions(c, f);
  CHECK(f[0] == light && fabs(f[1] - light) < 1e-15 && fabs(f[2] - light) < 1e-15, "deep covers medium and light");
  /* ... but in each band itself (an exercise's thoroughness) it is light and deep, not medium */
  double g[3];
  palp_coverage_band_fractions(c, g);
  CHECK(g[0] == light && g[1] == 0 && fabs(g[2] - light) < 1e-15, "in band: light and deep, not medium (%g %g %g)",
        g[0], g[1], g[2]);
  /* Medium elsewhere (disjoint): light and medium grow by a disc, deep does not. */
  const double ctr2[3] = {0.3, 0.3, 0};
  palp_coverage_press(c, ctr2, 0.1, PALP_BAND_MEDIUM);
  palp_coverage_fractions(c, f);
  CHECK(fabs(f[0] - 2 * light) < 0.0063 && fabs(f[1] - f[0]) < 1e-15 && fabs(f[2] - light) < 1e-15,
        "medium elsewhere: %g %g %g", f[0], f[1], f[2]);
  /* in band: the medium disc alone (a place pressed medium only is not light); medium at the first
   * place too adds its medium, and changes no "at least" fraction */
  palp_coverage_band_fractions(c, g);
  CHECK(g[0] == light && fabs(g[1] - (f[0] - light)) < 1e-15 && fabs(g[2] - light) < 1e-15,
        "in band, medium elsewhere: %g %g %g", g[0], g[1], g[2]);
  CHECK(palp_coverage_press(c, ctr, 0.1, PALP_BAND_MEDIUM) > 0, "medium where it was deep: a band new there");
  palp_coverage_band_fractions(c, g);
  double f2[3];
  palp_coverage_fractions(c, f2);
  CHECK(fabs(g[1] - f[1]) < 1e-15 && f2[0] == f[0] && f2[1] == f[1] && f2[2] == f[2],
        "in band medium now both discs (%g); at least unchanged", g[1]);
  /* Each vertex's bands (palp-web's dashboard map): the centre vertex (50, 50) light, deep and now
   * medium, 1 | 2 | 4 = 7; the vertex at (0.3, 0.3), index 80 * 101 + 80, medium alone, 2; a corner
   * none. The wrong vertex count gives nothing. */
  uint8_t *vb = malloc((size_t)nv);
  CHECK(vb && palp_coverage_vertex_bands(c, vb, nv) == nv && vb[50 * 101 + 50] == 7 && vb[80 * 101 + 80] == 2 &&
            vb[0] == 0,
        "vertex bands: centre %d, (0.3, 0.3) %d, corner %d", vb ? vb[50 * 101 + 50] : -1, vb ? vb[80 * 101 + 80] : -1,
        vb ? vb[0] : -1);
  CHECK(vb && palp_coverage_vertex_bands(c, vb, nv - 1) == 0, "vertex bands: a wrong count refused");
  free(vb);
  /* Bad input changes nothing. */
  const double nan3[3] = {NAN, 0, 0};
  CHECK(palp_coverage_press(c, nan3, 0.1, PALP_BAND_DEEP) == 0 && palp_coverage_press(c, ctr, -1, PALP_BAND_DEEP) == 0 &&
            palp_coverage_press(c, ctr, 0.1, 7) == 0 && palp_coverage_press(c, ctr, 0.1, -1) == 0,
        "NaN centre, negative radius, unknown band ignored");
  palp_coverage_reset(c);
  palp_coverage_fractions(c, f);
  CHECK(f[0] == 0, "reset");
  palp_coverage_destroy(c);
  /* Malformed meshes are refused. */
  tri[5] = nv;
  CHECK(!palp_coverage_create(rest, nv, tri, 2 * N * N, 2 * N * N, &rc) && rc == PALP_EINVAL, "index out of range");
  tri[5] = 0;
  rest[4] = INFINITY;
  CHECK(!palp_coverage_create(rest, nv, tri, 2 * N * N, 2 * N * N, &rc) && rc == PALP_EINVAL, "non-finite vertex");
  CHECK(!palp_coverage_create(rest, nv, tri, 10, 11, &rc), "more dome triangles than triangles");
  free(rest);
  free(tri);
}

/* The server's phantom: the model's own mesh, its triangles as the catalogue sends them, and a
 * coverage map on it. */
typedef struct dome {
  palp_mesh_def d;
  palp_mesh m;
  double *rest;
  int32_t *tri;
  palp_coverage *c;
} dome;
static int dome_open(dome *o) {
  memset(o, 0, sizeof *o);
  o->d = palp_mesh_default_def();
  if (palp_mesh_create(&o->d, &o->m) != 0) return -1;
  const palp_mesh *m = &o->m;
  o->rest = malloc(sizeof *o->rest * 3 * (size_t)m->vertex_count);
  o->tri = malloc(sizeof *o->tri * 3 * (size_t)m->triangle_count);
  if (!o->rest || !o->tri) return -1;
  for (int i = 0; i < m->vertex_count; i++)
    o->rest[3 * i] = m->rest[i].x, o->rest[3 * i + 1] = m->rest[i].y, o->rest[3 * i + 2] = m->rest[i].z;
  for (int t = 0; t < m->triangle_count; t++)
    for (int k = 0; k < 3; k++) o->tri[3 * t + k] = m->tri[t][k];
  int rc;
  o->c = palp_coverage_create(o->rest, m->vertex_count, o->tri, m->triangle_count, m->dome_triangle_count, &rc);
  return o->c ? 0 : -1;
}
static void dome_close(dome *o) {
  palp_coverage_destroy(o->c);
  free(o->rest);
  free(o->tri);
  palp_mesh_destroy(&o->m);
}

static void test_coverage_dome(const dome *o) {
  const palp_mesh m = o->m;
  const palp_mesh_def d = o->d;
  palp_coverage *c = o->c;
  palp_coverage_reset(c);
  double model_area = 0;
  for (int i = 0; i < m.vertex_count; i++) model_area += m.vertex_area[i];
  const double A = palp_coverage_dome_area(c), R = d.radius, hemi = 2 * PI * R * R;
  /* The inscribed polyhedron is a little smaller than the sphere: within 2% at 338 vertices. */
  CHECK(fabs(A - hemi) / hemi < 0.02, "dome area %.6g m^2 vs 2 pi R^2 %.6g", A, hemi);
  CHECK(fabs(A - model_area) / model_area < 1e-9, "the model's lumped areas sum to the same %.9g vs %.9g", A, model_area);
  /* The paper's patch (5.2 cm^2, r = 12.9 mm) at the pole: a spherical cap of that chord radius
   * has area pi r^2 (Archimedes: 2 pi R h with h from the chord) = 5.2 cm^2 = 5.2e-4 / 1.005e-2 of
   * the dome; the vertices' lumped areas resolve it to about one ring (~20%). */
  const double pole[3] = {0, 0, R}, r = sqrt(5.2e-4 / PI);
  palp_coverage_press(c, pole, r, PALP_BAND_MEDIUM);
  double f[3];
  palp_coverage_fractions(c, f);
  CHECK(fabs(f[0] - 5.2e-4 / hemi) < 0.2 * 5.2e-4 / hemi, "patch at the pole: %.4f of the dome vs %.4f", f[0],
        5.2e-4 / hemi);
}

/* The assessment's footprint as the bridge takes it (palp_coverage_press_triangles): the
 * `count` dome triangles nearest the contact point. Expected here by brute force on the model's own
 * mesh (its triangles sorted by the distance of their centroids from the point projected onto the
 * dome, then the model's lumped areas of their vertices), for points on and 2-10 mm inside the skin,
 * in general position (at the pole a ring of centroids ties). */
typedef struct tri_dist {
  double d;
  int t;
} tri_dist;
static int by_dist(const void *a, const void *b) {
  const double x = ((const tri_dist *)a)->d, y = ((const tri_dist *)b)->d;
  return x < y ? -1 : x > y;
}
static void test_coverage_triangles(const dome *o) {
  const palp_mesh m = o->m;
  palp_coverage *c = o->c;
  const double R = o->d.radius, A = palp_coverage_dome_area(c);
  tri_dist *td = malloc(sizeof *td * (size_t)m.dome_triangle_count);
  uint8_t *hit = malloc((size_t)m.vertex_count);
  /* polar / azimuth [deg] and depth below the skin [m] */
  const double where[][3] = {{3, 10, 0}, {30, 40, 0.006}, {55, 200, 0.002}, {70, 300, 0.010}};
  const int counts[] = {1, 3, 7, 20};
  int right = 0, cases = 0;
  for (size_t w = 0; w < sizeof where / sizeof where[0]; w++)
    for (size_t k = 0; k < sizeof counts / sizeof counts[0]; k++) {
      const double th = where[w][0] * PI / 180, ph = where[w][1] * PI / 180, r = R - where[w][2];
      const double u[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)}, p[3] = {r * u[0], r * u[1], r * u[2]};
      for (int t = 0; t < m.dome_triangle_count; t++) {
        double g[3] = {0, 0, 0};
        for (int v = 0; v < 3; v++) g[0] += m.rest[m.tri[t][v]].x / 3, g[1] += m.rest[m.tri[t][v]].y / 3, g[2] += m.rest[m.tri[t][v]].z / 3;
        const double dx = g[0] - R * u[0], dy = g[1] - R * u[1], dz = g[2] - R * u[2];
        td[t] = (tri_dist){dx * dx + dy * dy + dz * dz, t};
      }
      qsort(td, (size_t)m.dome_triangle_count, sizeof *td, by_dist);
      memset(hit, 0, (size_t)m.vertex_count);
      double want = 0;
      for (int j = 0; j < counts[k]; j++)
        for (int v = 0; v < 3; v++) {
          const int i = m.tri[td[j].t][v];
          if (!hit[i]) hit[i] = 1, want += m.vertex_area[i];
        }
      want /= A;
      palp_coverage_reset(c);
      const int raised = palp_coverage_press_triangles(c, p, counts[k], PALP_BAND_MEDIUM);
      double f[3], g[3];
      palp_coverage_fractions(c, f);
      palp_coverage_band_fractions(c, g);
      const int ok = raised > 0 && fabs(f[1] - want) < 1e-12 && fabs(g[1] - want) < 1e-12 && g[0] == 0 && f[2] == 0;
      if (!ok)
        fprintf(stderr, "  %g deg, %g deg, %g mm, %d triangles: %.6f of the dome, want %.6f (raised %d)\n", where[w][0],
                where[w][1], where[w][2] * 1e3, counts[k], g[1], want, raised);
      right += ok, cases++;
    }
  CHECK(right == cases, "%d of %d presses mark the vertices of the nearest triangles (1e-12 of the dome's area)", right,
        cases);
  /* at a triangle's own centroid, one triangle: its three vertices, nothing else */
  const int t0 = m.dome_triangle_count / 2;
  double g0[3] = {0, 0, 0};
  for (int v = 0; v < 3; v++) g0[0] += m.rest[m.tri[t0][v]].x / 3, g0[1] += m.rest[m.tri[t0][v]].y / 3, g0[2] += m.rest[m.tri[t0][v]].z / 3;
  palp_coverage_reset(c);
  const int three = palp_coverage_press_triangles(c, g0, 1, PALP_BAND_LIGHT);
  double f[3];
  palp_coverage_fractions(c, f);
  const double a3 = (m.vertex_area[m.tri[t0][0]] + m.vertex_area[m.tri[t0][1]] + m.vertex_area[m.tri[t0][2]]) / A;
  CHECK(three == 3 && fabs(f[0] - a3) < 1e-12, "one triangle at its centroid: its 3 vertices (%d), %.6f of the dome", three,
        f[0]);
  const double nan3[3] = {NAN, 0, 0};
  palp_coverage_reset(c);
  CHECK(palp_coverage_press_triangles(c, g0, 0, PALP_BAND_MEDIUM) == 0 &&
            palp_coverage_press_triangles(c, nan3, 3, PALP_BAND_MEDIUM) == 0 &&
            palp_coverage_press_triangles(c, g0, 3, -1) == 0 && palp_coverage_press_triangles(c, g0, 3, 3) == 0 &&
            palp_coverage_press_triangles(NULL, g0, 3, PALP_BAND_MEDIUM) == 0,
        "no triangles, a NaN point, no band, no map: nothing marked");
  /* a count beyond the cap (a hostile or corrupt model) marks the cap's triangles, no more */
  palp_coverage_press_triangles(c, g0, 1000000, PALP_BAND_DEEP);
  palp_coverage_fractions(c, f);
  CHECK(f[2] > 0 && f[2] < 0.25, "a million triangles asked: %d at most, %.3f of the dome", PALP_COVERAGE_TRIANGLES_MAX,
        f[2]);
  free(hit);
  free(td);
}

/* The assessment's own footprint where the touched triangles are named (palp_finger_sample, session
 * 71; palp_coverage_press_touched): every vertex of the dome triangles given, base triangles and ids
 * out of range skipped, as src/assess.c's footprint. Expected: the model's lumped areas of those
 * vertices, gathered here from the mesh's own triangle list. */
static void test_coverage_touched(const dome *o) {
  const palp_mesh *m = &o->m;
  palp_coverage *c = o->c;
  palp_coverage_reset(c);
  const int nd = m->dome_triangle_count;
  CHECK(m->triangle_count > nd, "the model's mesh has base triangles after the dome's (%d of %d)", nd,
        m->triangle_count);
  /* three dome triangles apart, one next to the first, the first twice, a base triangle, two bad ids */
  const int32_t ids[] = {0, nd / 3, nd - 1, 1, 0, nd, -1, m->triangle_count + 5};
  const int n = (int)(sizeof ids / sizeof ids[0]);
  char *seen = calloc((size_t)m->vertex_count, 1);
  double want = 0, dome_area = 0;
  for (int k = 0; k < n; k++) {
    if (ids[k] < 0 || ids[k] >= nd) continue;
    for (int j = 0; j < 3; j++) {
      const int v = m->tri[ids[k]][j];
      if (!seen[v]) seen[v] = 1, want += m->vertex_area[v];
    }
  }
  for (int i = 0; i < m->vertex_count; i++) dome_area += m->vertex_area[i];
  const int raised = palp_coverage_press_touched(c, ids, n, PALP_BAND_MEDIUM);
  int marked = 0;
  for (int i = 0; i < m->vertex_count; i++) marked += seen[i];
  double f[3];
  palp_coverage_band_fractions(c, f);
  CHECK(raised == marked && fabs(f[1] - want / dome_area) < 1e-12 && f[0] == 0 && f[2] == 0,
        "touched: the %d vertices of the 4 dome triangles named marked medium, %.6f of the dome (want %.6f, 1e-12); "
        "the base triangle and the ids out of range skipped", raised, f[1], want / dome_area);
  CHECK(palp_coverage_press_touched(c, ids, n, PALP_BAND_MEDIUM) == 0, "touched again at the same band: nothing raised");
  CHECK(palp_coverage_press_touched(c, ids + 5, 3, PALP_BAND_DEEP) == 0 && palp_coverage_press_touched(c, NULL, 3, 1) == 0 &&
            palp_coverage_press_touched(c, ids, n, 7) == 0,
        "only a base triangle and bad ids, no list, or no band: nothing marked");
  free(seen);
}

int main(void) {
  test_coverage_square();
  dome o;
  CHECK(dome_open(&o) == 0, "the model's mesh, accepted as a dome");
  test_coverage_dome(&o);
  test_coverage_triangles(&o);
  test_coverage_touched(&o);
  dome_close(&o);
  CHECK_DONE();
}
