/*
 * mesh.c - the hemispherical phantom surface.
 *
 * Vertices sit on latitude rings at equal polar-angle spacing, so meridian and
 * circumferential edges have about the same length and the triangles stay near
 * equilateral at every resolution. The ring sizes are apportioned by the largest-
 * remainder method so that any requested vertex count is met exactly (338 is the
 * paper's count). The rim ring lies on z = 0 and is fixed; the flat base is closed
 * by triangles between rim vertices, which keeps the surface closed for the
 * divergence theorem without adding vertices (the base contributes nothing to the
 * volume because x . n = 0 on z = 0 with the origin at the base centre).
 */
#include "palp.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vec3.h"

palp_mesh_def palp_mesh_default_def(void) {
  palp_mesh_def d = {.radius = 0.04, .vertex_count = 338};
  return d;
}


/* Ring sizes n_k (k = 1..K) summing to total, proportional to sin(theta_k). */
static int ring_sizes(int total, int rings, int *n) {
  double w[rings], wsum = 0.0;
  for (int k = 1; k <= rings; ++k) {
    w[k - 1] = sin(0.5 * PALP_PI * k / rings);
    wsum += w[k - 1];
  }
  int assigned = 0;
  double rem[rings];
  for (int k = 0; k < rings; ++k) {
    double ideal = total * w[k] / wsum;
    n[k] = (int)floor(ideal);
    if (n[k] < 3) n[k] = 3;
    rem[k] = ideal - floor(ideal);
    assigned += n[k];
  }
  /* Largest remainder first; deterministic tie-break on ring index. */
  while (assigned < total) {
    int best = 0;
    for (int k = 1; k < rings; ++k)
      if (rem[k] > rem[best]) best = k;
    n[best]++;
    rem[best] = -1.0;
    assigned++;
  }
  while (assigned > total) { /* only when the minimum of 3 per ring overshot */
    int best = -1;
    for (int k = rings - 1; k >= 0; --k)
      if (n[k] > 3 && (best < 0 || n[k] > n[best])) best = k;
    if (best < 0) return PALP_EINVAL;
    n[best]--;
    assigned--;
  }
  return PALP_OK;
}

typedef struct edge_key {
  int a, b; /* a < b */
} edge_key;

static int edge_cmp(const void *pa, const void *pb) {
  const edge_key *x = pa, *y = pb;
  if (x->a != y->a) return x->a < y->a ? -1 : 1;
  return (x->b > y->b) - (x->b < y->b);
}

/* Appends triangle (a, b, c), flipped if needed so its normal points along `out`. */
static void add_tri(palp_mesh *m, int a, int b, int c, palp_vec3 out) {
  palp_vec3 n = v3_cross(v3_sub(m->rest[b], m->rest[a]), v3_sub(m->rest[c], m->rest[a]));
  int *t = m->tri[m->triangle_count++];
  if (v3_dot(n, out) >= 0.0) {
    t[0] = a, t[1] = b, t[2] = c;
  } else {
    t[0] = a, t[1] = c, t[2] = b;
  }
}

int palp_mesh_create(const palp_mesh_def *def, palp_mesh *out) {
  memset(out, 0, sizeof *out);
  if (!def || !(def->radius > 0.0) || !isfinite(def->radius) || def->vertex_count < 19 ||
      def->vertex_count > PALP_MESH_MAX_VERTICES)
    return PALP_EINVAL;
  const int nv = def->vertex_count;
  const double r = def->radius;
  /* N - 1 ~ sum_k 4K sin(theta_k) ~ 8 K^2 / pi for near-equilateral triangles. */
  int rings = (int)lround(sqrt(PALP_PI * (nv - 1) / 8.0));
  if (rings < 2) rings = 2;
  while (rings > 2 && 3 * rings > nv - 1) rings--;
  int *n = malloc(sizeof(int) * rings);
  if (!n) return PALP_ENOMEM;
  if (ring_sizes(nv - 1, rings, n) != PALP_OK) {
    free(n);
    return PALP_EINVAL;
  }

  out->vertex_count = nv;
  out->ring_count = rings;
  const int rim = n[rings - 1];
  /* Dome: fan of n1 at the pole + (n_{k} + n_{k+1}) per band; base: rim - 2. */
  int ntri = n[0];
  for (int k = 0; k + 1 < rings; ++k) ntri += n[k] + n[k + 1];
  ntri += rim - 2;
  out->rest = calloc((size_t)nv, sizeof *out->rest);
  out->fixed = calloc((size_t)nv, 1);
  out->vertex_area = calloc((size_t)nv, sizeof(double));
  out->ring_start = calloc((size_t)rings + 2, sizeof(int));
  out->tri = calloc((size_t)ntri, sizeof *out->tri);
  if (!out->rest || !out->fixed || !out->vertex_area || !out->ring_start || !out->tri) {
    free(n);
    palp_mesh_destroy(out);
    return PALP_ENOMEM;
  }

  /* Vertices: pole, then rings from the top down; odd rings are turned by half a
   * spacing so that the zipper between rings does not build slivers. */
  out->rest[0] = (palp_vec3){0.0, 0.0, r};
  out->top_vertex = 0;
  out->ring_start[0] = 0;
  int v = 1;
  for (int k = 1; k <= rings; ++k) {
    out->ring_start[k] = v;
    const double theta = 0.5 * PALP_PI * k / rings;
    const double st = (k == rings) ? 1.0 : sin(theta), ct = (k == rings) ? 0.0 : cos(theta);
    const int nk = n[k - 1];
    const double phase = (k % 2) ? PALP_PI / nk : 0.0;
    for (int i = 0; i < nk; ++i, ++v) {
      const double phi = phase + 2.0 * PALP_PI * i / nk;
      out->rest[v] = (palp_vec3){r * st * cos(phi), r * st * sin(phi), r * ct};
      out->fixed[v] = (k == rings);
    }
  }
  out->ring_start[rings + 1] = v;

  /* Pole fan. */
  for (int i = 0; i < n[0]; ++i) {
    int a = 1 + i, b = 1 + (i + 1) % n[0];
    palp_vec3 c = out->rest[a];
    add_tri(out, 0, a, b, (palp_vec3){c.x, c.y, c.z + r});
  }
  /* Zipper between ring k (inner) and k+1 (outer): always advance along the ring
   * whose next vertex comes first in azimuth, which yields a closed band. */
  for (int k = 1; k < rings; ++k) {
    const int s0 = out->ring_start[k], s1 = out->ring_start[k + 1];
    const int na = n[k - 1], nb = n[k];
    const double pa = (k % 2) ? PALP_PI / na : 0.0, pb = ((k + 1) % 2) ? PALP_PI / nb : 0.0;
    int i = 0, j = 0;
    while (i < na || j < nb) {
      const double next_a = pa + 2.0 * PALP_PI * (i + 1) / na;
      const double next_b = pb + 2.0 * PALP_PI * (j + 1) / nb;
      const int a0 = s0 + i % na, b0 = s1 + j % nb;
      palp_vec3 mid = out->rest[a0];
      if (j >= nb || (i < na && next_a <= next_b)) {
        add_tri(out, a0, b0, s0 + (i + 1) % na, mid);
        ++i;
      } else {
        add_tri(out, a0, b0, s1 + (j + 1) % nb, mid);
        ++j;
      }
    }
  }
  out->dome_triangle_count = out->triangle_count;
  /* Base: zig-zag strip across the rim polygon, normals along -z. */
  {
    const int s = out->ring_start[rings];
    int lo = 0, hi = rim - 1, turn = 0;
    while (hi - lo >= 2) {
      if (!turn) {
        add_tri(out, s + lo, s + lo + 1, s + hi, (palp_vec3){0, 0, -1});
        ++lo;
      } else {
        add_tri(out, s + lo, s + hi - 1, s + hi, (palp_vec3){0, 0, -1});
        --hi;
      }
      turn = !turn;
    }
  }
  free(n);

  /* Lumped areas: one third of each adjacent dome triangle. */
  for (int t = 0; t < out->dome_triangle_count; ++t) {
    const int *T = out->tri[t];
    palp_vec3 c = v3_cross(v3_sub(out->rest[T[1]], out->rest[T[0]]), v3_sub(out->rest[T[2]], out->rest[T[0]]));
    const double a = 0.5 * sqrt(v3_dot(c, c));
    for (int q = 0; q < 3; ++q) out->vertex_area[T[q]] += a / 3.0;
  }

  /* Links: unique edges with at least one free end. */
  edge_key *e = malloc(sizeof *e * 3 * (size_t)out->triangle_count);
  if (!e) {
    palp_mesh_destroy(out);
    return PALP_ENOMEM;
  }
  int ne = 0;
  for (int t = 0; t < out->triangle_count; ++t)
    for (int q = 0; q < 3; ++q) {
      int a = out->tri[t][q], b = out->tri[t][(q + 1) % 3];
      if (out->fixed[a] && out->fixed[b]) continue;
      e[ne++] = (edge_key){a < b ? a : b, a < b ? b : a};
    }
  qsort(e, (size_t)ne, sizeof *e, edge_cmp);
  out->link = malloc(sizeof *out->link * (size_t)(ne ? ne : 1));
  if (!out->link) {
    free(e);
    palp_mesh_destroy(out);
    return PALP_ENOMEM;
  }
  for (int i = 0; i < ne; ++i) {
    if (i > 0 && e[i].a == e[i - 1].a && e[i].b == e[i - 1].b) continue;
    out->link[out->link_count][0] = e[i].a;
    out->link[out->link_count][1] = e[i].b;
    out->link_count++;
  }
  free(e);
  return PALP_OK;
}

void palp_mesh_destroy(palp_mesh *m) {
  if (!m) return;
  free(m->rest);
  free(m->tri);
  free(m->link);
  free(m->fixed);
  free(m->ring_start);
  free(m->vertex_area);
  memset(m, 0, sizeof *m);
}

double palp_mesh_volume(const palp_mesh *m, const palp_vec3 *p) {
  /* V = (1/3) \oint x . n dA = sum_t x_a . (x_b x x_c) / 6 [m^3]; base triangles add 0. */
  double v = 0.0;
  for (int t = 0; t < m->triangle_count; ++t) {
    const int *T = m->tri[t];
    v += v3_dot(p[T[0]], v3_cross(p[T[1]], p[T[2]]));
  }
  return v / 6.0;
}

int palp_mesh_nearest_vertex(const palp_mesh *m, const palp_vec3 *pos, palp_vec3 p) {
  int best = -1;
  double bd = INFINITY;
  for (int i = 0; i < m->vertex_count; ++i) {
    palp_vec3 d = v3_sub(pos[i], p);
    double dd = v3_dot(d, d);
    if (dd < bd) bd = dd, best = i;
  }
  return best;
}
