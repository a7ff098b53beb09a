/*
 * fem_mesh.c - the O-grid hexahedral mesh of the hemispherical phantom.
 *
 * A half-cube core [-a, a]^2 x [0, a] is meshed as a regular lattice of
 * (2n) x (2n) x n cells. Every lattice point c/n on the cube's curved-side
 * surface (top and four sides, not the base) is joined to the sphere by a radial
 * column of nodes: through the gel from the cube point to radius R - t along the
 * direction d(c) = normalize(tan(pi c / 4)) (equi-angular, so the surface cells
 * keep nearly equal size), then through the membrane at constant direction in
 * membrane_layers steps to R. The direction formula is the same for every face,
 * so columns on cube edges are shared without any merging. Points with c_z = 0
 * map to directions with d_z = 0, so the whole base lies in z = 0 and is clamped.
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fem_internal.h"

palp_fem_mesh_def palp_fem_mesh_default_def(void) {
  palp_fem_mesh_def d = {.radius = 0.04, .membrane_thickness = 0.002, .core_fraction = 0.5, .level = 2,
                         .membrane_layers = 0};
  return d;
}

void palp_fem_mesh_destroy(palp_fem_mesh *m) {
  if (!m) return;
  free(m->x);
  free(m->hex);
  free(m->region);
  free(m->fixed);
  for (int s = 0; s < m->set_count; ++s) free(m->sets[s].items);
  free(m->sets);
  memset(m, 0, sizeof *m);
}

const palp_fem_set *palp_fem_mesh_find_set(const palp_fem_mesh *m, const char *name, int is_element) {
  for (int s = 0; s < m->set_count; ++s) {
    if (m->sets[s].is_element != is_element) continue;
    const char *a = m->sets[s].name, *b = name;
    while (*a && *b && toupper((unsigned char)*a) == toupper((unsigned char)*b)) ++a, ++b;
    if (!*a && !*b) return &m->sets[s];
  }
  return NULL;
}

/* Appends a set (takes ownership of items). */
int palp_fem_mesh_add_set(palp_fem_mesh *m, const char *name, int is_element, int *items, int count) {
  palp_fem_set *s = realloc(m->sets, (size_t)(m->set_count + 1) * sizeof *s);
  if (!s) return PALP_ENOMEM;
  m->sets = s;
  palp_fem_set *n = &s[m->set_count++];
  memset(n, 0, sizeof *n);
  snprintf(n->name, sizeof n->name, "%s", name);
  for (char *c = n->name; *c; ++c) *c = (char)toupper((unsigned char)*c);
  n->is_element = is_element;
  n->items = items;
  n->count = count;
  return PALP_OK;
}

/* Makes the reference volume of every element positive by mirroring its node
 * order (swap faces 1-4 and 5-8) where it is negative. */
void palp_fem_mesh_orient(palp_fem_mesh *m) {
  for (int e = 0; e < m->element_count; ++e) {
    if (palp_fem_element_volume(m, e) >= 0.0) continue;
    int h[8];
    memcpy(h, m->hex[e], sizeof h);
    for (int a = 0; a < 4; ++a) {
      m->hex[e][a] = h[a + 4];
      m->hex[e][a + 4] = h[a];
    }
  }
}

/* Derives the standard sets BASE (fixed nodes), TOP, MEMBRANE, GEL when missing. */
int palp_fem_mesh_standard_sets(palp_fem_mesh *m) {
  if (!palp_fem_mesh_find_set(m, "BASE", 0)) {
    int n = 0, *it = malloc(sizeof(int) * (size_t)(m->node_count + 1));
    if (!it) return PALP_ENOMEM;
    for (int i = 0; i < m->node_count; ++i)
      if (m->fixed[i]) it[n++] = i;
    if (palp_fem_mesh_add_set(m, "BASE", 0, it, n)) return PALP_ENOMEM;
  }
  if (!palp_fem_mesh_find_set(m, "TOP", 0)) {
    int *it = malloc(sizeof(int));
    if (!it) return PALP_ENOMEM;
    it[0] = m->top_node;
    if (palp_fem_mesh_add_set(m, "TOP", 0, it, 1)) return PALP_ENOMEM;
  }
  for (int r = 0; r < 2; ++r) {
    const char *name = r == PALP_FEM_MEMBRANE ? "MEMBRANE" : "GEL";
    if (palp_fem_mesh_find_set(m, name, 1)) continue;
    int n = 0, *it = malloc(sizeof(int) * (size_t)(m->element_count + 1));
    if (!it) return PALP_ENOMEM;
    for (int e = 0; e < m->element_count; ++e)
      if (m->region[e] == r) it[n++] = e;
    if (palp_fem_mesh_add_set(m, name, 1, it, n)) return PALP_ENOMEM;
  }
  return PALP_OK;
}

/* The lattice coordinate s in [lo, hi] mapped about s0 (palp_fem_mesh_def.grading):
 * g(s) = s0 + (s - s0) (alpha + (1 - alpha) u^2), u = |s - s0| / |end - s0|; g(lo) = lo,
 * g(s0) = s0, g(hi) = hi, g' = alpha + 3 (1 - alpha) u^2 > 0. */
static double grade(double s, double s0, double lo, double hi, double alpha) {
  const double span = s >= s0 ? hi - s0 : s0 - lo;
  if (!(span > 0.0)) return s;
  const double u = fabs(s - s0) / span;
  return s0 + (s - s0) * (alpha + (1.0 - alpha) * u * u);
}

int palp_fem_mesh_create(const palp_fem_mesh_def *def, palp_fem_mesh *out) {
  memset(out, 0, sizeof *out);
  const int L = def->level;
  if (L < 1 || L > 16 || !(def->radius > 0.0) || !(def->membrane_thickness > 0.0) ||
      !(def->membrane_thickness < 0.5 * def->radius) || !(def->core_fraction > 0.05) ||
      !(def->core_fraction < 0.9) || def->membrane_layers < 0 || def->membrane_layers > 32 ||
      !(def->grading >= 0.0 && def->grading <= 1.0) ||
      !(def->grading_polar_deg >= 0.0 && def->grading_polar_deg <= 90.0))
    return PALP_EINVAL;
  const int n = 2 * L, Lg = 2 * L;
  const int Lm = def->membrane_layers ? def->membrane_layers : (L - 1 > 2 ? L - 1 : 2);
  if (Lm < 2) return PALP_EINVAL;
  const int Ls = Lg + Lm;
  const double R = def->radius, t = def->membrane_thickness;
  const double a = def->core_fraction * (R - t);
  const int W = 2 * n + 1, H = n + 1; /* lattice extents in x/y and z */
#define LAT(i, j, k) ((((i) + n) * W + ((j) + n)) * H + (k))
  const size_t lat = (size_t)W * W * H;
  int *id = malloc(sizeof(int) * lat * (size_t)(Ls + 1));
  if (!id) return PALP_ENOMEM;
  for (size_t q = 0; q < lat * (size_t)(Ls + 1); ++q) id[q] = -1;
  /* count nodes: every core lattice point, plus Ls per surface lattice point */
  int nsurf = 0;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = 0; k <= n; ++k)
        if (abs(i) == n || abs(j) == n || k == n) ++nsurf;
  const int nn = (int)lat + nsurf * Ls;
  const int ne = 4 * n * n * n + 12 * n * n * Ls;
  out->x = malloc(sizeof *out->x * (size_t)nn);
  out->hex = malloc(sizeof *out->hex * (size_t)ne);
  out->region = calloc((size_t)ne, 1);
  out->fixed = calloc((size_t)nn, 1);
  if (!out->x || !out->hex || !out->region || !out->fixed) {
    free(id);
    palp_fem_mesh_destroy(out);
    return PALP_ENOMEM;
  }
  const double alpha = def->grading, th = def->grading_polar_deg / 45.0; /* th in [0, 2] */
  const int graded = alpha > 0.0 && alpha < 1.0, side = th >= 1.0;
  /* the spot's lattice coordinates: on the top face dir = (tan(pi/4 s), 0, 1), polar
   * angle pi/4 s; on the x side dir = (1, 0, tan(pi/4 s)), polar angle pi/2 - pi/4 s */
  const double c0[3] = {side ? 1.0 : th, 0.0, side ? 2.0 - th : 1.0};
  int node = 0;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = 0; k <= n; ++k) {
        double c[3] = {(double)i / n, (double)j / n, (double)k / n};
        if (graded) {
          c[0] = grade(c[0], c0[0], -1.0, 1.0, alpha);
          c[1] = grade(c[1], c0[1], -1.0, 1.0, alpha);
          if (side) c[2] = grade(c[2], c0[2], 0.0, 1.0, alpha);
        }
        id[LAT(i, j, k) * (size_t)(Ls + 1)] = node;
        for (int d = 0; d < 3; ++d) out->x[node][d] = a * c[d];
        ++node;
        if (!(abs(i) == n || abs(j) == n || k == n)) continue;
        double dir[3], len = 0.0;
        for (int d = 0; d < 3; ++d) {
          dir[d] = tan(0.25 * PALP_FEM_PI * c[d]);
          len += dir[d] * dir[d];
        }
        len = sqrt(len);
        for (int d = 0; d < 3; ++d) dir[d] /= len;
        for (int l = 1; l <= Ls; ++l) {
          double r;
          if (l <= Lg) {
            const double s = (double)l / Lg;
            for (int d = 0; d < 3; ++d) out->x[node][d] = (1.0 - s) * a * c[d] + s * (R - t) * dir[d];
          } else {
            r = R - t + t * (double)(l - Lg) / Lm;
            for (int d = 0; d < 3; ++d) out->x[node][d] = r * dir[d];
          }
          if (k == 0) out->x[node][2] = 0.0; /* exactly on the base plane */
          id[LAT(i, j, k) * (size_t)(Ls + 1) + (size_t)l] = node;
          ++node;
        }
      }
#define NODE(i, j, k, l) id[LAT(i, j, k) * (size_t)(Ls + 1) + (size_t)(l)]
  int e = 0;
  for (int i = -n; i < n; ++i)
    for (int j = -n; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        int *h = out->hex[e];
        h[0] = NODE(i, j, k, 0);
        h[1] = NODE(i + 1, j, k, 0);
        h[2] = NODE(i + 1, j + 1, k, 0);
        h[3] = NODE(i, j + 1, k, 0);
        h[4] = NODE(i, j, k + 1, 0);
        h[5] = NODE(i + 1, j, k + 1, 0);
        h[6] = NODE(i + 1, j + 1, k + 1, 0);
        h[7] = NODE(i, j + 1, k + 1, 0);
        out->region[e++] = PALP_FEM_GEL;
      }
  /* surface quads of the cube: top, then the four sides; q[4] lattice corners */
  for (int face = 0; face < 5; ++face) {
    const int nu = 2 * n, nv = face == 0 ? 2 * n : n;
    for (int p = 0; p < nu; ++p)
      for (int q = 0; q < nv; ++q) {
        int c[4][3];
        for (int corner = 0; corner < 4; ++corner) {
          const int du = (corner == 1 || corner == 2), dv = (corner >= 2);
          const int s = -n + p + du; /* along the face, -n..n */
          const int r = face == 0 ? -n + q + dv : q + dv;
          switch (face) {
          case 0: c[corner][0] = s, c[corner][1] = r, c[corner][2] = n; break;
          case 1: c[corner][0] = n, c[corner][1] = s, c[corner][2] = r; break;
          case 2: c[corner][0] = -n, c[corner][1] = s, c[corner][2] = r; break;
          case 3: c[corner][0] = s, c[corner][1] = n, c[corner][2] = r; break;
          default: c[corner][0] = s, c[corner][1] = -n, c[corner][2] = r; break;
          }
        }
        for (int l = 0; l < Ls; ++l) {
          int *h = out->hex[e];
          for (int corner = 0; corner < 4; ++corner) {
            h[corner] = NODE(c[corner][0], c[corner][1], c[corner][2], l);
            h[corner + 4] = NODE(c[corner][0], c[corner][1], c[corner][2], l + 1);
          }
          out->region[e++] = l >= Lg ? PALP_FEM_MEMBRANE : PALP_FEM_GEL;
        }
      }
  }
  out->node_count = nn;
  out->element_count = e;
  palp_fem_mesh_orient(out);
  int *surf = malloc(sizeof(int) * (size_t)nsurf);
  if (!surf) {
    free(id);
    palp_fem_mesh_destroy(out);
    return PALP_ENOMEM;
  }
  int ns = 0;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = 0; k <= n; ++k)
        if (abs(i) == n || abs(j) == n || k == n) surf[ns++] = NODE(i, j, k, Ls);
  out->top_node = NODE(0, 0, n, Ls);
#undef NODE
#undef LAT
  free(id);
  for (int v = 0; v < nn; ++v) out->fixed[v] = out->x[v][2] <= 1e-12 * R;
  int rc = palp_fem_mesh_add_set(out, "SURFACE", 0, surf, ns);
  if (!rc) rc = palp_fem_mesh_standard_sets(out);
  if (rc) palp_fem_mesh_destroy(out);
  return rc;
}
