/* The phantom surface: exact vertex counts, closed and consistently oriented,
 * Euler characteristic 2, and a volume that matches the analytic hemisphere within
 * 1% at the paper's 338 vertices and converges as the mesh refines. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "palp.h"

static int cmp2(const void *a, const void *b) {
  const int *x = a, *y = b;
  if (x[0] != y[0]) return x[0] - y[0];
  return x[1] - y[1];
}

/* Every directed edge (a, b) must appear once and its reverse (b, a) once: the
 * surface is closed and every pair of neighbouring triangles agrees on orientation. */
static int closed_and_oriented(const palp_mesh *m) {
  const int ne = 3 * m->triangle_count;
  int(*e)[2] = malloc(sizeof *e * (size_t)ne);
  for (int t = 0; t < m->triangle_count; ++t)
    for (int q = 0; q < 3; ++q) e[3 * t + q][0] = m->tri[t][q], e[3 * t + q][1] = m->tri[t][(q + 1) % 3];
  qsort(e, (size_t)ne, sizeof *e, cmp2);
  int ok = 1;
  for (int i = 0; i < ne && ok; ++i) {
    if (i > 0 && e[i][0] == e[i - 1][0] && e[i][1] == e[i - 1][1]) ok = 0; /* duplicated directed edge */
    int rev[2] = {e[i][1], e[i][0]};
    if (!bsearch(rev, e, (size_t)ne, sizeof *e, cmp2)) ok = 0; /* open edge */
  }
  free(e);
  return ok;
}

int main(void) {
  const double R = 0.04, Vexact = 2.0 / 3.0 * 3.14159265358979323846 * R * R * R; /* [m^3] */
  const int counts[] = {100, 338, 1300, 5000};
  double err[4];
  for (int k = 0; k < 4; ++k) {
    palp_mesh_def d = {.radius = R, .vertex_count = counts[k]};
    palp_mesh m;
    CHECK(palp_mesh_create(&d, &m) == PALP_OK, "mesh %d", counts[k]);
    CHECK(m.vertex_count == counts[k], "exact vertex count %d vs %d", m.vertex_count, counts[k]);
    CHECK(closed_and_oriented(&m), "mesh of %d vertices is closed and consistently oriented", counts[k]);
    /* Euler characteristic of a sphere-like closed surface: V - E + F = 2, with
     * E = 3F/2 for a closed triangle mesh. */
    CHECK(m.vertex_count - 3 * m.triangle_count / 2 + m.triangle_count == 2, "Euler characteristic");
    /* Outward orientation: every dome triangle's normal points away from the origin. */
    int outward = 1;
    for (int t = 0; t < m.dome_triangle_count; ++t) {
      const palp_vec3 a = m.rest[m.tri[t][0]], b = m.rest[m.tri[t][1]], c = m.rest[m.tri[t][2]];
      const palp_vec3 u = {b.x - a.x, b.y - a.y, b.z - a.z}, v = {c.x - a.x, c.y - a.y, c.z - a.z};
      const palp_vec3 n = {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
      if (n.x * (a.x + b.x + c.x) + n.y * (a.y + b.y + c.y) + n.z * (a.z + b.z + c.z) <= 0) outward = 0;
    }
    CHECK(outward, "dome normals point outward at %d vertices", counts[k]);
    /* The rim is fixed and lies on the base plane; the pole is the top vertex. */
    int rim_ok = 1;
    for (int i = 0; i < m.vertex_count; ++i)
      if (m.fixed[i] && fabs(m.rest[i].z) > 1e-15) rim_ok = 0;
    CHECK(rim_ok, "fixed vertices lie on z = 0");
    CHECK(fabs(m.rest[m.top_vertex].z - R) < 1e-15, "top vertex at the pole");
    err[k] = fabs(palp_mesh_volume(&m, m.rest) - Vexact) / Vexact;
    printf("%5d vertices: %5d triangles, %5d links, volume error %.4f%%\n", counts[k], m.triangle_count,
           m.link_count, 100 * err[k]);
    palp_mesh_destroy(&m);
  }
  CHECK(err[1] < 0.01, "volume at 338 vertices within 1%% of 2/3 pi R^3 (error %.4f%%)", 100 * err[1]);
  /* An inscribed polyhedron's volume error falls as h^2 ~ 1/N: each fourfold
   * refinement must cut it at least threefold. */
  for (int k = 1; k < 4; ++k)
    CHECK(err[k] < err[k - 1] / 3.0, "volume error falls with refinement: %.3g -> %.3g", err[k - 1], err[k]);
  palp_mesh_def bad = {.radius = -1.0, .vertex_count = 338};
  palp_mesh m;
  CHECK(palp_mesh_create(&bad, &m) == PALP_EINVAL, "negative radius is rejected");
  bad = (palp_mesh_def){.radius = R, .vertex_count = 5};
  CHECK(palp_mesh_create(&bad, &m) == PALP_EINVAL, "too few vertices are rejected");
  CHECK_DONE();
}
