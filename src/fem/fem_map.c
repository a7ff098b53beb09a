/*
 * fem_map.c - where each real-time vertex sits on the FE outer surface.
 *
 * The outer surface is every hexahedron face that belongs to one element only and
 * does not lie on the clamped base. A real-time vertex p is projected radially
 * from the base centre: the ray s p / |p| meets a bilinear face
 *   X(xi, eta) = sum_a N_a(xi, eta) X_a
 * where the component of X orthogonal to the ray vanishes, (I - u u^T) X = 0,
 * solved by Gauss-Newton from the face centre. The face with a solution inside
 * [-1, 1]^2 (small tolerance) farthest along the ray wins; the vertex then carries
 * the face's four bilinear weights N_a(xi, eta). Loads are spread and
 * displacements gathered with the same weights, so both models talk about the
 * same material points.
 *
 * The patch map (palp_fem_map_create_patch) spreads a vertex over its hat function
 * instead: every FE surface quadrature point is carried radially onto the
 * real-time dome, and the triangle it lands in shares its area among its three
 * vertices by barycentric weight. A vertex's weights are
 *   w_va = int N_a phi_v dA / int phi_v dA,
 * so a force F_v becomes the traction F_v phi_v / int phi_v dA (resultant F_v) and
 * the gathered displacement is phi_v's weighted average of the FE surface. Rim
 * (clamped) vertices map to no node.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fem_internal.h"

/* Local faces of a C3D8 element, ordered so the normal points out of the element. */
static const int hex_face[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                   {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};

typedef struct face_key {
  int s[4]; /* sorted nodes */
  int e, f;
} face_key;

static int cmp_face(const void *a, const void *b) {
  const face_key *x = a, *y = b;
  for (int i = 0; i < 4; ++i)
    if (x->s[i] != y->s[i]) return x->s[i] < y->s[i] ? -1 : 1;
  return 0;
}

static int cmp_int4(const void *a, const void *b) {
  const int x = *(const int *)a, y = *(const int *)b;
  return (x > y) - (x < y);
}

int palp_fem_surface_faces(const palp_fem_mesh *mesh, int (**faces)[4], int *count) {
  const int E = mesh->element_count;
  face_key *k = malloc(sizeof *k * (size_t)E * 6);
  if (!k) return PALP_ENOMEM;
  for (int e = 0; e < E; ++e)
    for (int f = 0; f < 6; ++f) {
      face_key *q = &k[e * 6 + f];
      for (int i = 0; i < 4; ++i) q->s[i] = mesh->hex[e][hex_face[f][i]];
      qsort(q->s, 4, sizeof(int), cmp_int4);
      q->e = e, q->f = f;
    }
  qsort(k, (size_t)E * 6, sizeof *k, cmp_face);
  int (*out)[4] = malloc(sizeof *out * (size_t)E * 6);
  if (!out) {
    free(k);
    return PALP_ENOMEM;
  }
  int n = 0;
  for (int i = 0; i < E * 6;) {
    int j = i + 1;
    while (j < E * 6 && cmp_face(&k[i], &k[j]) == 0) ++j;
    if (j == i + 1) {
      int base = 1;
      for (int c = 0; c < 4; ++c) {
        const int node = mesh->hex[k[i].e][hex_face[k[i].f][c]];
        out[n][c] = node;
        base &= mesh->fixed[node];
      }
      if (!base) ++n;
    }
    i = j;
  }
  free(k);
  *faces = out;
  *count = n;
  return PALP_OK;
}

static void bilinear(double xi, double eta, double N[4], double dxi[4], double deta[4]) {
  static const double s[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (int a = 0; a < 4; ++a) {
    N[a] = 0.25 * (1 + s[a][0] * xi) * (1 + s[a][1] * eta);
    dxi[a] = 0.25 * s[a][0] * (1 + s[a][1] * eta);
    deta[a] = 0.25 * s[a][1] * (1 + s[a][0] * xi);
  }
}

/* The bilinear face f at (xi, eta): shape functions N, the point X and its tangents
 * Xa = dX/dxi, Xb = dX/deta [m]. */
static void face_point(const palp_fem_mesh *mesh, const int f[4], double xi, double eta, double N[4], double X[3],
                       double Xa[3], double Xb[3]) {
  double dx[4], de[4];
  bilinear(xi, eta, N, dx, de);
  for (int d = 0; d < 3; ++d) X[d] = Xa[d] = Xb[d] = 0.0;
  for (int c = 0; c < 4; ++c)
    for (int d = 0; d < 3; ++d) {
      X[d] += N[c] * mesh->x[f[c]][d];
      Xa[d] += dx[c] * mesh->x[f[c]][d];
      Xb[d] += de[c] * mesh->x[f[c]][d];
    }
}

/* Gauss-Newton for (I - u u^T) X(xi, eta) = 0; returns the residual distance [m]. */
static double ray_face(const palp_fem_mesh *mesh, const int f[4], const double u[3], double *xi, double *eta,
                       double *along) {
  double a = 0.0, b = 0.0, r2 = 0.0;
  for (int it = 0; it < 20; ++it) {
    double N[4], X[3], Xa[3], Xb[3];
    face_point(mesh, f, a, b, N, X, Xa, Xb);
    const double xu = X[0] * u[0] + X[1] * u[1] + X[2] * u[2];
    const double au = Xa[0] * u[0] + Xa[1] * u[1] + Xa[2] * u[2];
    const double bu = Xb[0] * u[0] + Xb[1] * u[1] + Xb[2] * u[2];
    double r[3], ja[3], jb[3];
    for (int d = 0; d < 3; ++d) {
      r[d] = X[d] - xu * u[d];
      ja[d] = Xa[d] - au * u[d];
      jb[d] = Xb[d] - bu * u[d];
    }
    r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    *along = xu;
    const double A = ja[0] * ja[0] + ja[1] * ja[1] + ja[2] * ja[2];
    const double B = ja[0] * jb[0] + ja[1] * jb[1] + ja[2] * jb[2];
    const double C = jb[0] * jb[0] + jb[1] * jb[1] + jb[2] * jb[2];
    const double ga = ja[0] * r[0] + ja[1] * r[1] + ja[2] * r[2];
    const double gb = jb[0] * r[0] + jb[1] * r[1] + jb[2] * r[2];
    const double det = A * C - B * B;
    if (!(det > 0.0)) break;
    const double da = -(C * ga - B * gb) / det, db = -(A * gb - B * ga) / det;
    a += da, b += db;
    if (fabs(a) > 3 || fabs(b) > 3) break; /* far outside: not this face */
    if (fabs(da) + fabs(db) < 1e-14) break;
  }
  *xi = a, *eta = b;
  return sqrt(r2);
}

int palp_fem_map_create(const palp_fem_mesh *mesh, const palp_vec3 *points, int count, palp_fem_map *out) {
  memset(out, 0, sizeof *out);
  int (*faces)[4] = NULL, nf = 0;
  int rc = palp_fem_surface_faces(mesh, &faces, &nf);
  if (rc) return rc;
  /* angular extent of each face around its centre direction, for a quick cull */
  double (*cdir)[4] = malloc(sizeof *cdir * (size_t)(nf ? nf : 1));
  out->start = malloc(sizeof *out->start * (size_t)(count + 1));
  out->node = malloc(sizeof *out->node * (size_t)(4 * count + 1));
  out->w = malloc(sizeof *out->w * (size_t)(4 * count + 1));
  if (!cdir || !out->start || !out->node || !out->w) {
    free(faces), free(cdir);
    palp_fem_map_destroy(out);
    return PALP_ENOMEM;
  }
  double scale = 0.0;
  for (int f = 0; f < nf; ++f) {
    double c[3] = {0};
    for (int k = 0; k < 4; ++k)
      for (int d = 0; d < 3; ++d) c[d] += 0.25 * mesh->x[faces[f][k]][d];
    const double l = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    scale = fmax(scale, l);
    double mincos = 1.0;
    for (int k = 0; k < 4; ++k) {
      const double *x = mesh->x[faces[f][k]];
      const double lx = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
      const double cs = lx > 0 && l > 0 ? (x[0] * c[0] + x[1] * c[1] + x[2] * c[2]) / (lx * l) : -1.0;
      mincos = fmin(mincos, cs);
    }
    for (int d = 0; d < 3; ++d) cdir[f][d] = l > 0 ? c[d] / l : 0.0;
    cdir[f][3] = acos(fmax(-1.0, fmin(1.0, mincos)));
  }
  for (int v = 0; v < count; ++v) {
    double u[3] = {points[v].x, points[v].y, points[v].z};
    const double lu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(lu > 0.0)) {
      rc = PALP_EINVAL;
      break;
    }
    for (int d = 0; d < 3; ++d) u[d] /= lu;
    int best = -1;
    double best_along = -INFINITY, bxi = 0, beta_ = 0;
    for (int f = 0; f < nf; ++f) {
      const double cs = u[0] * cdir[f][0] + u[1] * cdir[f][1] + u[2] * cdir[f][2];
      if (acos(fmax(-1.0, fmin(1.0, cs))) > cdir[f][3] * 1.5 + 1e-6) continue;
      double xi, eta, along;
      const double r = ray_face(mesh, faces[f], u, &xi, &eta, &along);
      const double tol = 1e-6;
      if (r > 1e-9 * scale || fabs(xi) > 1 + tol || fabs(eta) > 1 + tol || along <= 0.0) continue;
      if (along > best_along) {
        best_along = along, best = f, bxi = xi, beta_ = eta;
      }
    }
    if (best < 0) {
      rc = PALP_ERANGE; /* the ray misses the FE surface: geometries do not match */
      break;
    }
    double N[4], dx[4], de[4];
    bilinear(fmax(-1.0, fmin(1.0, bxi)), fmax(-1.0, fmin(1.0, beta_)), N, dx, de);
    out->start[v] = 4 * v;
    for (int k = 0; k < 4; ++k) {
      out->node[4 * v + k] = faces[best][k];
      out->w[4 * v + k] = N[k];
    }
  }
  out->start[count] = 4 * count;
  out->count = count;
  free(faces);
  free(cdir);
  if (rc) palp_fem_map_destroy(out);
  return rc;
}

/* Ray from the base centre along unit u against triangle (a, b, c): 1 and the
 * barycentric weights of the hit when the ray passes within tol (barycentric) of it
 * (Moller-Trumbore with the origin at 0). */
static int ray_triangle(const double u[3], const palp_vec3 *a, const palp_vec3 *b, const palp_vec3 *c, double tol,
                        double bary[3]) {
  const double e1[3] = {b->x - a->x, b->y - a->y, b->z - a->z}, e2[3] = {c->x - a->x, c->y - a->y, c->z - a->z};
  const double p[3] = {u[1] * e2[2] - u[2] * e2[1], u[2] * e2[0] - u[0] * e2[2], u[0] * e2[1] - u[1] * e2[0]};
  const double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
  if (fabs(det) < 1e-300) return 0;
  const double s[3] = {-a->x, -a->y, -a->z};
  const double b1 = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
  const double q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
  const double b2 = (u[0] * q[0] + u[1] * q[1] + u[2] * q[2]) / det;
  const double t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
  if (!(t > 0.0) || b1 < -tol || b2 < -tol || b1 + b2 > 1.0 + tol) return 0;
  bary[1] = fmax(0.0, b1), bary[2] = fmax(0.0, b2);
  bary[0] = fmax(0.0, 1.0 - bary[1] - bary[2]);
  const double sum = bary[0] + bary[1] + bary[2];
  for (int k = 0; k < 3; ++k) bary[k] /= sum;
  return 1;
}

typedef struct map_entry {
  int v, node;
  double w;
} map_entry;

static int cmp_entry(const void *a, const void *b) {
  const map_entry *x = a, *y = b;
  if (x->v != y->v) return x->v < y->v ? -1 : 1;
  return (x->node > y->node) - (x->node < y->node);
}

int palp_fem_map_create_patch(const palp_fem_mesh *mesh, const palp_mesh *rt, palp_fem_map *out) {
  memset(out, 0, sizeof *out);
  /* 4 x 4 Gauss points a face: the hat functions are linear inside a real-time
   * triangle and kink along its edges, which cut the FE faces, so the rule is exact
   * only on faces no edge crosses; the error is confined to those faces and shrinks
   * with them as the level rises. */
  enum { G = 4 };
  static const double gp[G] = {-0.86113631159405257522, -0.33998104358485626480, 0.33998104358485626480,
                                0.86113631159405257522};
  static const double gw[G] = {0.34785484513745385737, 0.65214515486254614263, 0.65214515486254614263,
                               0.34785484513745385737};
  const int V = rt->vertex_count, T = rt->dome_triangle_count;
  int (*faces)[4] = NULL, nf = 0;
  int rc = palp_fem_surface_faces(mesh, &faces, &nf);
  if (rc) return rc;
  /* each real-time triangle's centre direction and angular radius, for a quick cull */
  double (*tdir)[4] = malloc(sizeof *tdir * (size_t)(T ? T : 1));
  double *norm = calloc((size_t)V + 1, sizeof *norm);
  const size_t cap = (size_t)nf * G * G * 12 + 1;
  map_entry *e = malloc(sizeof *e * cap);
  out->start = calloc((size_t)V + 1, sizeof *out->start);
  if (!tdir || !norm || !e || !out->start) {
    rc = PALP_ENOMEM;
    goto done;
  }
  for (int t = 0; t < T; ++t) {
    double c[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k) {
      const palp_vec3 *x = &rt->rest[rt->tri[t][k]];
      c[0] += x->x, c[1] += x->y, c[2] += x->z;
    }
    const double l = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    double mincos = 1.0;
    for (int k = 0; k < 3; ++k) {
      const palp_vec3 *x = &rt->rest[rt->tri[t][k]];
      const double lx = sqrt(x->x * x->x + x->y * x->y + x->z * x->z);
      mincos = fmin(mincos, lx > 0 && l > 0 ? (x->x * c[0] + x->y * c[1] + x->z * c[2]) / (lx * l) : -1.0);
    }
    for (int d = 0; d < 3; ++d) tdir[t][d] = l > 0 ? c[d] / l : 0.0;
    tdir[t][3] = mincos; /* cos of the angular radius */
  }
  size_t n = 0;
  for (int f = 0; f < nf && !rc; ++f)
    for (int i = 0; i < G && !rc; ++i)
      for (int j = 0; j < G && !rc; ++j) {
        double N[4], X[3], Xa[3], Xb[3];
        face_point(mesh, faces[f], gp[i], gp[j], N, X, Xa, Xb);
        const double cr[3] = {Xa[1] * Xb[2] - Xa[2] * Xb[1], Xa[2] * Xb[0] - Xa[0] * Xb[2], Xa[0] * Xb[1] - Xa[1] * Xb[0]};
        const double dA = gw[i] * gw[j] * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]); /* [m^2] */
        const double lX = sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2]);
        if (!(lX > 0.0)) continue;
        const double u[3] = {X[0] / lX, X[1] / lX, X[2] / lX};
        int hit = -1;
        double bary[3] = {0, 0, 0};
        for (int t = 0; t < T && hit < 0; ++t) {
          const double cs = u[0] * tdir[t][0] + u[1] * tdir[t][1] + u[2] * tdir[t][2];
          if (cs < tdir[t][3] - 1e-9) continue;
          if (ray_triangle(u, &rt->rest[rt->tri[t][0]], &rt->rest[rt->tri[t][1]], &rt->rest[rt->tri[t][2]], 1e-9, bary))
            hit = t;
        }
        if (hit < 0) {
          rc = PALP_ERANGE; /* the dome is star-shaped from the base centre: every ray up hits it */
          continue;
        }
        for (int k = 0; k < 3; ++k) {
          const int v = rt->tri[hit][k];
          /* a rim vertex is clamped in the real-time model: it maps to nothing, so
           * its displacement is 0 there too, and its share of the ring stays unused */
          if (!(bary[k] > 0.0) || rt->fixed[v]) continue;
          norm[v] += bary[k] * dA;
          for (int a = 0; a < 4; ++a) e[n++] = (map_entry){v, faces[f][a], bary[k] * N[a] * dA};
        }
      }
  if (rc) goto done;
  qsort(e, n, sizeof *e, cmp_entry);
  size_t m = 0; /* merge equal (v, node) */
  for (size_t k = 0; k < n; ++k) {
    if (m > 0 && e[m - 1].v == e[k].v && e[m - 1].node == e[k].node)
      e[m - 1].w += e[k].w;
    else
      e[m++] = e[k];
  }
  out->node = malloc(sizeof *out->node * (m + 1));
  out->w = malloc(sizeof *out->w * (m + 1));
  if (!out->node || !out->w) {
    rc = PALP_ENOMEM;
    goto done;
  }
  for (size_t k = 0; k < m; ++k) {
    out->node[k] = e[k].node;
    out->w[k] = e[k].w / norm[e[k].v]; /* the hat-weighted average: weights sum to 1 */
    out->start[e[k].v + 1]++;
  }
  for (int v = 0; v < V; ++v) {
    if (!(norm[v] > 0.0) && !rt->fixed[v]) rc = PALP_ERANGE; /* a free vertex with no patch */
    out->start[v + 1] += out->start[v];
  }
  out->count = V;
done:
  free(faces);
  free(tdir);
  free(norm);
  free(e);
  if (rc) palp_fem_map_destroy(out);
  return rc;
}

void palp_fem_map_destroy(palp_fem_map *map) {
  if (!map) return;
  free(map->start);
  free(map->node);
  free(map->w);
  memset(map, 0, sizeof *map);
}

int palp_fem_cap_traction(const palp_fem_mesh *mesh, double F, double area, int gauss, double *f) {
  /* Gauss-Legendre points and weights on [-1, 1]. 6 points integrate the exact cap (whose
   * edge cuts faces) to <1% of its area on a level-1 face; 2 keep bench_profiles' figures. */
  static const double p2[2] = {-0.57735026918962576451, 0.57735026918962576451}, w2[2] = {1.0, 1.0};
  static const double p6[6] = {-0.93246951420315202781, -0.66120938646626451366, -0.23861918608319690863,
                               0.23861918608319690863,  0.66120938646626451366,  0.93246951420315202781};
  static const double w6[6] = {0.17132449237917034504, 0.36076157304813860757, 0.46791393457269104739,
                               0.46791393457269104739, 0.36076157304813860757, 0.17132449237917034504};
  if ((gauss != 2 && gauss != 6) || !(F >= 0.0) || !(area > 0.0)) return PALP_EINVAL;
  const double *gp = gauss == 2 ? p2 : p6, *gw = gauss == 2 ? w2 : w6;
  int (*faces)[4], nf;
  const int rc = palp_fem_surface_faces(mesh, &faces, &nf);
  if (rc) return rc;
  memset(f, 0, sizeof(double) * 3 * (size_t)mesh->node_count);
  const double s2 = area / PALP_FEM_PI;
  double total = 0.0;
  for (int k = 0; k < nf; ++k)
    for (int i = 0; i < gauss; ++i)
      for (int j = 0; j < gauss; ++j) {
        double N[4], X[3], Xa[3], Xb[3];
        face_point(mesh, faces[k], gp[i], gp[j], N, X, Xa, Xb);
        if (X[2] <= 0.0 || X[0] * X[0] + X[1] * X[1] > s2) continue;
        const double n[3] = {Xa[1] * Xb[2] - Xa[2] * Xb[1], Xa[2] * Xb[0] - Xa[0] * Xb[2],
                             Xa[0] * Xb[1] - Xa[1] * Xb[0]};
        const double dA = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) * gw[i] * gw[j]; /* [m^2] */
        for (int a = 0; a < 4; ++a) f[3 * faces[k][a] + 2] -= N[a] * dA;
        total += dA;
      }
  free(faces);
  if (!(total > 0.0)) return PALP_EINVAL;
  for (int i = 0; i < 3 * mesh->node_count; ++i) f[i] *= F / total;
  return 0;
}
