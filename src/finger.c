/*
 * finger.c - sphere-triangle proximity, the contact LCP and the contact stiffness
 * (finger.h). Small pure functions over plain arrays.
 */
#include <math.h>
#include <string.h>

#include "finger.h"
#include "vec3.h"

palp_vec3 palp_tri_closest(palp_vec3 p, palp_vec3 a, palp_vec3 b, palp_vec3 c, double bary[3]) {
  /* Voronoi regions of the vertices, then the edges, then the face. */
  const palp_vec3 ab = v3_sub(b, a), ac = v3_sub(c, a), ap = v3_sub(p, a);
  const double d1 = v3_dot(ab, ap), d2 = v3_dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    bary[0] = 1, bary[1] = 0, bary[2] = 0;
    return a;
  }
  const palp_vec3 bp = v3_sub(p, b);
  const double d3 = v3_dot(ab, bp), d4 = v3_dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) {
    bary[0] = 0, bary[1] = 1, bary[2] = 0;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    bary[0] = 1 - v, bary[1] = v, bary[2] = 0;
    return v3_add(a, v3_scale(ab, v));
  }
  const palp_vec3 cp = v3_sub(p, c);
  const double d5 = v3_dot(ab, cp), d6 = v3_dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) {
    bary[0] = 0, bary[1] = 0, bary[2] = 1;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double wv = d2 / (d2 - d6);
    bary[0] = 1 - wv, bary[1] = 0, bary[2] = wv;
    return v3_add(a, v3_scale(ac, wv));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double wv = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    bary[0] = 0, bary[1] = 1 - wv, bary[2] = wv;
    return v3_add(b, v3_scale(v3_sub(c, b), wv));
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, wv = vc * denom;
  bary[0] = 1 - v - wv, bary[1] = v, bary[2] = wv;
  return v3_add(a, v3_add(v3_scale(ab, v), v3_scale(ac, wv)));
}

int palp_lcp_pgs(int m, const double *W, const double *b, double *lambda, int max_iter, double tol) {
  for (int it = 1; it <= max_iter; ++it) {
    double worst = 0.0; /* [m] */
    for (int i = 0; i < m; ++i) {
      const double *Wi = W + (size_t)i * (size_t)m;
      double g = b[i];
      for (int j = 0; j < m; ++j) g += Wi[j] * lambda[j];
      /* Residual of complementarity as a length: a violated gap, or the gap that a
       * needlessly positive lambda holds open (lambda W_ii). */
      const double r = fmin(g, lambda[i] * Wi[i]);
      if (fabs(r) > worst) worst = fabs(r);
      const double li = lambda[i] - g / Wi[i];
      lambda[i] = li > 0.0 ? li : 0.0;
    }
    if (worst <= tol) return it;
  }
  return -1;
}

/* In-place Cholesky of an SPD n x n (row-major, lower used); 0 or -1. */
static int cholesky(double *A, int n) {
  for (int j = 0; j < n; ++j) {
    double d = A[j * n + j];
    for (int k = 0; k < j; ++k) d -= A[j * n + k] * A[j * n + k];
    if (!(d > 0.0)) return -1;
    d = sqrt(d);
    A[j * n + j] = d;
    for (int i = j + 1; i < n; ++i) {
      double s = A[i * n + j];
      for (int k = 0; k < j; ++k) s -= A[i * n + k] * A[j * n + k];
      A[i * n + j] = s / d;
    }
  }
  return 0;
}

static void chol_solve(const double *L, int n, double *x) {
  for (int i = 0; i < n; ++i) {
    double s = x[i];
    for (int k = 0; k < i; ++k) s -= L[i * n + k] * x[k];
    x[i] = s / L[i * n + i];
  }
  for (int i = n - 1; i >= 0; --i) {
    double s = x[i];
    for (int k = i + 1; k < n; ++k) s -= L[k * n + i] * x[k];
    x[i] = s / L[i * n + i];
  }
}

int palp_contact_stiffness(int m, const double *W, const palp_vec3 *n, const double *lambda, double K[3][3],
                           double *work) {
  memset(K, 0, sizeof(double) * 9);
  int na = 0;
  int *idx = (int *)(void *)(work + (size_t)m * (size_t)m + 2 * (size_t)m); /* m ints fit in m doubles */
  for (int i = 0; i < m; ++i)
    if (lambda[i] > 0.0) idx[na++] = i;
  if (!na) return 0;
  double *A = work, *x = work + (size_t)na * (size_t)na;
  /* Redundant contacts (neighbouring triangles at one point) make W_AA singular;
   * a relative regularisation of 1e-9 of its largest diagonal changes K by less. */
  double dmax = 0.0;
  for (int a = 0; a < na; ++a) dmax = fmax(dmax, W[(size_t)idx[a] * (size_t)m + (size_t)idx[a]]);
  for (int a = 0; a < na; ++a)
    for (int c = 0; c < na; ++c)
      A[a * na + c] = W[(size_t)idx[a] * (size_t)m + (size_t)idx[c]] + (a == c ? 1e-9 * dmax : 0.0);
  if (cholesky(A, na)) return -1;
  for (int col = 0; col < 3; ++col) {
    for (int a = 0; a < na; ++a) {
      const palp_vec3 q = n[idx[a]];
      x[a] = col == 0 ? q.x : (col == 1 ? q.y : q.z);
    }
    chol_solve(A, na, x);
    for (int a = 0; a < na; ++a) {
      const palp_vec3 q = n[idx[a]];
      K[0][col] += q.x * x[a];
      K[1][col] += q.y * x[a];
      K[2][col] += q.z * x[a];
    }
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < i; ++j) K[i][j] = K[j][i] = 0.5 * (K[i][j] + K[j][i]);
  return na;
}

int palp_lcp_solve(int m, const double *W, const double *b, double *lambda, double *work) {
  /* Lawson-Hanson active set for min 1/2 l^T W l + b^T l, l >= 0, whose optimality
   * conditions are the LCP; W_PP is regularised like palp_contact_stiffness so that
   * duplicate contacts (one point seen by two triangles) stay solvable. */
  double dmax = 0.0;
  for (int i = 0; i < m; ++i) dmax = fmax(dmax, W[(size_t)i * (size_t)m + (size_t)i]);
  const double eps = 1e-9 * dmax;
  double *A = work, *z = work + (size_t)m * (size_t)m, *g = z + m;
  int *P = (int *)(void *)(g + m); /* m ints in m doubles */
  for (int i = 0; i < m; ++i)
    if (!(lambda[i] > 0.0)) lambda[i] = 0.0;
  for (int it = 0; it < 4 * m + 8; ++it) {
    int np = 0;
    for (int i = 0; i < m; ++i)
      if (lambda[i] > 0.0) P[np++] = i;
    /* Complementarity: add the most violated inactive constraint, if any. */
    if (np == 0 || it > 0) {
      for (int i = 0; i < m; ++i) {
        g[i] = b[i];
        for (int j = 0; j < m; ++j) g[i] += W[(size_t)i * (size_t)m + (size_t)j] * lambda[j];
      }
      int worst = -1;
      for (int i = 0; i < m; ++i)
        if (!(lambda[i] > 0.0) && g[i] < -1e-12 && (worst < 0 || g[i] < g[worst])) worst = i;
      if (worst < 0) return it;
      P[np++] = worst;
    }
    /* Solve on P, stepping back to feasibility while some z_P <= 0. */
    for (;;) {
      for (int a = 0; a < np; ++a)
        for (int c = 0; c < np; ++c)
          A[a * np + c] = W[(size_t)P[a] * (size_t)m + (size_t)P[c]] + (a == c ? eps : 0.0);
      if (cholesky(A, np)) return -1;
      for (int a = 0; a < np; ++a) z[a] = -b[P[a]];
      chol_solve(A, np, z);
      double alpha = 1.0;
      int drop = -1;
      for (int a = 0; a < np; ++a)
        if (z[a] <= 0.0) {
          const double l = lambda[P[a]];
          const double t = l / (l - z[a]);
          if (t < alpha) alpha = t, drop = a;
        }
      for (int a = 0; a < np; ++a) lambda[P[a]] += alpha * (z[a] - lambda[P[a]]);
      if (drop < 0) break;
      lambda[P[drop]] = 0.0;
      int q = 0;
      for (int a = 0; a < np; ++a)
        if (lambda[P[a]] > 0.0) P[q++] = P[a];
      np = q;
      if (!np) break;
    }
  }
  return -1;
}

/* ---- the smooth contact surface (finger.h) ---- */

void palp_rest_normals(const palp_mesh *mesh, palp_vec3 *normals) {
  const int nv = mesh->vertex_count;
  double rmin = INFINITY, rmax = 0.0;
  for (int i = 0; i < nv; ++i) {
    const double l = v3_len(mesh->rest[i]);
    rmin = fmin(rmin, l), rmax = fmax(rmax, l);
  }
  if (nv > 0 && rmax - rmin <= 1e-9 * rmax && rmin > 0.0) {
    /* a sphere about the base centre (the rim's normals are horizontal, as the sphere's) */
    for (int i = 0; i < nv; ++i) normals[i] = v3_scale(mesh->rest[i], 1.0 / v3_len(mesh->rest[i]));
    return;
  }
  for (int i = 0; i < nv; ++i) normals[i] = v3(0, 0, 0);
  for (int t = 0; t < mesh->dome_triangle_count; ++t) {
    const int *T = mesh->tri[t];
    const palp_vec3 nf = v3_cross(v3_sub(mesh->rest[T[1]], mesh->rest[T[0]]), v3_sub(mesh->rest[T[2]], mesh->rest[T[0]]));
    const double fl = v3_len(nf);
    if (!(fl > 0.0)) continue;
    for (int e = 0; e < 3; ++e) {
      /* the triangle's angle at the vertex weighs its normal */
      const palp_vec3 u = v3_sub(mesh->rest[T[(e + 1) % 3]], mesh->rest[T[e]]);
      const palp_vec3 v = v3_sub(mesh->rest[T[(e + 2) % 3]], mesh->rest[T[e]]);
      const double ang = atan2(v3_len(v3_cross(u, v)), v3_dot(u, v));
      normals[T[e]] = v3_add(normals[T[e]], v3_scale(nf, ang / fl));
    }
  }
  for (int i = 0; i < nv; ++i) {
    const double l = v3_len(normals[i]);
    normals[i] = l > 0.0 ? v3_scale(normals[i], 1.0 / l) : v3(0, 0, 1);
  }
}

int palp_smooth_patch_init(palp_smooth_patch *sp, const palp_vec3 X[3], const palp_vec3 N[3]) {
  memset(sp, 0, sizeof *sp);
  const palp_vec3 f = v3_cross(v3_sub(X[1], X[0]), v3_sub(X[2], X[0]));
  if (!(v3_len(f) > 0.0)) return -1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) sp->d[i][j] = i == j ? 0.0 : v3_dot(v3_sub(X[j], X[i]), N[i]);
  return 0;
}

palp_vec3 palp_normal_carry(palp_vec3 n_rest, palp_vec3 m_rest, palp_vec3 m_now) {
  /* R v = v + w x v + w x (w x v) / (1 + c), w = m_rest x m_now, c = m_rest . m_now: the
   * rotation by the angle between them about w (Rodrigues, written without the angle) */
  const palp_vec3 w = v3_cross(m_rest, m_now);
  const double c = v3_dot(m_rest, m_now);
  if (!(c > -0.5)) return m_now; /* the ring turned over: its own normal is all that is left */
  const palp_vec3 wv = v3_cross(w, n_rest);
  return v3_add(n_rest, v3_add(wv, v3_scale(v3_cross(w, wv), 1.0 / (1.0 + c))));
}

palp_vec3 palp_smooth_point(const palp_smooth_patch *sp, palp_vec3 a, palp_vec3 b, palp_vec3 c, const palp_vec3 N[3],
                            const double bary[3], palp_vec3 *t1, palp_vec3 *t2) {
  const double al = PALP_PHONG_ALPHA;
  /* o = sum_i c_i N_i, c_i = -alpha b_i s_i, s_i = sum_j b_j d_ij [m]; along b_k with
   * b_0 = 1 - b_1 - b_2 its derivative is d/db_k - d/db_0 of the homogeneous form,
   * d c_i / d b_k = -alpha (delta_ik s_i + b_i d_ik) */
  double s[3];
  for (int i = 0; i < 3; ++i) s[i] = bary[0] * sp->d[i][0] + bary[1] * sp->d[i][1] + bary[2] * sp->d[i][2];
  palp_vec3 o = v3(0, 0, 0), o1 = v3(0, 0, 0), o2 = v3(0, 0, 0);
  for (int i = 0; i < 3; ++i) {
    const double ci = -al * bary[i] * s[i];
    const double d0 = -al * ((i == 0 ? s[i] : 0.0) + bary[i] * sp->d[i][0]);
    const double d1 = -al * ((i == 1 ? s[i] : 0.0) + bary[i] * sp->d[i][1]);
    const double d2 = -al * ((i == 2 ? s[i] : 0.0) + bary[i] * sp->d[i][2]);
    o = v3_add(o, v3_scale(N[i], ci));
    o1 = v3_add(o1, v3_scale(N[i], d1 - d0));
    o2 = v3_add(o2, v3_scale(N[i], d2 - d0));
  }
  const palp_vec3 e1 = v3_sub(b, a), e2 = v3_sub(c, a);
  *t1 = v3_add(e1, o1);
  *t2 = v3_add(e2, o2);
  return v3_add(v3_add(a, v3_add(v3_scale(e1, bary[1]), v3_scale(e2, bary[2]))), o);
}

double palp_smooth_patch_max_offset(const palp_smooth_patch *sp, const palp_vec3 X[3], const palp_vec3 N[3]) {
  /* |o| <= alpha sum_i b_i |s_i| (unit normals), a quadratic in b: sampled on a 1/8 grid,
   * plus 10%, it bounds the offset for any unit normals */
  double best = 0.0;
  (void)X, (void)N;
  for (int i = 0; i <= 8; ++i)
    for (int j = 0; i + j <= 8; ++j) {
      const double bb[3] = {(8 - i - j) / 8.0, i / 8.0, j / 8.0};
      double o = 0.0;
      for (int k = 0; k < 3; ++k) o += bb[k] * fabs(bb[0] * sp->d[k][0] + bb[1] * sp->d[k][1] + bb[2] * sp->d[k][2]);
      best = fmax(best, PALP_PHONG_ALPHA * o);
    }
  return 1.1 * best;
}

palp_vec3 palp_smooth_closest(palp_vec3 p, palp_vec3 a, palp_vec3 b, palp_vec3 c, const palp_vec3 N[3],
                              const palp_smooth_patch *sp, double bary[3], palp_vec3 *normal) {
  palp_vec3 S, t1, t2; /* from the facet's closest point, bary on entry */
  for (int it = 0; it < 2; ++it) {
    S = palp_smooth_point(sp, a, b, c, N, bary, &t1, &t2);
    /* the patch linearised at bary: S + t1 (b_1' - b_1) + t2 (b_2' - b_2) over the
     * triangle, whose closest point is the constrained Gauss-Newton step */
    const palp_vec3 v0 = v3_sub(S, v3_add(v3_scale(t1, bary[1]), v3_scale(t2, bary[2])));
    palp_tri_closest(p, v0, v3_add(v0, t1), v3_add(v0, t2), bary);
  }
  S = palp_smooth_point(sp, a, b, c, N, bary, &t1, &t2);
  const palp_vec3 n = v3_cross(t1, t2);
  const double nl = v3_len(n);
  *normal = nl > 0.0 ? v3_scale(n, 1.0 / nl) : v3(0, 0, 0);
  return S;
}

void palp_sym3_eig(const double K[3][3], double lambda[3], double V[3][3]) {
  double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  memcpy(a, K, sizeof a);
  /* a <- J^T a J until off-diagonal round-off: 3x3 converges in a few sweeps */
  for (int sweep = 0; sweep < 16; ++sweep) {
    const double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
    const double diag = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
    if (!(off > 1e-15 * diag)) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0.0) continue;
        const double th = 0.5 * atan2(2.0 * a[p][q], a[q][q] - a[p][p]);
        const double c = cos(th), s = sin(th);
        for (int k = 0; k < 3; ++k) {
          const double x = a[k][p], y = a[k][q];
          a[k][p] = c * x - s * y, a[k][q] = s * x + c * y;
        }
        for (int k = 0; k < 3; ++k) {
          const double x = a[p][k], y = a[q][k];
          a[p][k] = c * x - s * y, a[q][k] = s * x + c * y;
        }
        for (int k = 0; k < 3; ++k) {
          const double x = v[k][p], y = v[k][q];
          v[k][p] = c * x - s * y, v[k][q] = s * x + c * y;
        }
      }
  }
  for (int e = 0; e < 3; ++e) lambda[e] = a[e][e];
  memcpy(V, v, sizeof v);
}

palp_vec3 palp_sym3_pinv_apply(const double K[3][3], palp_vec3 r, double rel_tol) {
  double a[3][3] = {{0}}, v[3][3], l[3];
  palp_sym3_eig(K, l, v);
  for (int e = 0; e < 3; ++e) a[e][e] = l[e];
  const double lmax = fmax(fmax(a[0][0], a[1][1]), a[2][2]);
  const double rv[3] = {r.x, r.y, r.z};
  double out[3] = {0, 0, 0};
  for (int e = 0; e < 3; ++e) {
    if (!(a[e][e] > rel_tol * lmax)) continue; /* also NaN */
    const double pr = (v[0][e] * rv[0] + v[1][e] * rv[1] + v[2][e] * rv[2]) / a[e][e];
    for (int i = 0; i < 3; ++i) out[i] += v[i][e] * pr;
  }
  return v3(out[0], out[1], out[2]);
}

static palp_vec3 mat3_apply(const double K[3][3], palp_vec3 x) {
  return v3(K[0][0] * x.x + K[0][1] * x.y + K[0][2] * x.z, K[1][0] * x.x + K[1][1] * x.y + K[1][2] * x.z,
            K[2][0] * x.x + K[2][1] * x.y + K[2][2] * x.z);
}

palp_vec3 palp_drift_observe(const palp_local_model *last, const palp_local_model *now, palp_vec3 v, double h,
                             double max_speed, palp_vec3 *c) {
  if (!last->contact || !now->contact || !(h > 0.0)) {
    *c = v3(0, 0, 0);
    return v;
  }
  /* the last model's force at this step's device point, h later [N] */
  const palp_vec3 d = v3_sub(v3_sub(now->device, last->device), v3_scale(last->drift, h));
  const palp_vec3 e = v3_sub(now->force, v3_sub(last->force, mat3_apply(last->stiffness, d)));
  const palp_vec3 dc = v3_scale(palp_sym3_pinv_apply(now->stiffness, e, 1e-6), PALP_DRIFT_GAIN / h);
  /* a non-finite step (it cannot come from a solved step) leaves the correction as it was */
  if (isfinite(dc.x) && isfinite(dc.y) && isfinite(dc.z)) *c = v3_add(*c, dc);
  palp_vec3 drift = v3_add(v, *c);
  const double dl = v3_len(drift);
  if (dl > max_speed && max_speed > 0.0) { /* no surface moves faster: the correction is held there */
    drift = v3_scale(drift, max_speed / dl);
    *c = v3_sub(drift, v);
  }
  return drift;
}
