/*
 * fem_finger.c - a rigid spherical fingertip pressed by position into the FE
 * model (fem_finger.h, docs/fem.md "The finger").
 *
 * Why a penalty on a surface integral: the sphere is the master surface (smooth,
 * analytic) and the FE faces are the slave. At each face Gauss point x(xi, eta) =
 * sum N_a x_a the gap is g = |x - c| - R; where g < 0 the point carries the
 * pressure p = -eps g along n = (x - c) / |x - c|, integrated over the reference
 * area. A node-lumped penalty would put all force on 4-9 nodes when the contact
 * radius (sqrt(R d): 2-9 mm) spans one or two faces; a composite rule over the
 * face spreads it as the pressure does. Its contribution to the internal force and the tangent:
 *   f_a += N_a eps g dA n,   K_ab += N_a N_b eps dA [n n^T + g / |x - c| (I - n n^T)],
 * (exact linearisation; the second term is the rotation of n, small and
 * negative). A pure penalty lets the surface in by p / eps, and under the stiff
 * membrane the pressure concentrates (1.4 MPa at the pole node at level 2: 0.14 mm
 * at 1e10 N/m^3), so the penalty is augmented (Uzawa): p = max(0, lambda - eps g),
 * lambda <- p after each converged solve, until the penetration is below 1 um.
 * The tangent then uses p in place of -eps g in the rotation term.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fem_finger.h"

int palp_fem_finger_init(palp_fem_finger *f, const palp_fem_mesh *mesh, const int (*faces)[4], int face_count,
                         double radius, double penalty) {
  memset(f, 0, sizeof *f);
  f->radius = radius > 0.0 ? radius : 0.008;
  f->penalty = penalty > 0.0 ? penalty : 1e10;
  f->quad = 8;
  f->gap_tol = 1e-6;
  f->max_augment = 30;
  int rc = PALP_OK;
  if (faces) {
    f->face = malloc(sizeof *f->face * (size_t)(face_count > 0 ? face_count : 1));
    if (!f->face) return PALP_ENOMEM;
    memcpy(f->face, faces, sizeof *f->face * (size_t)face_count);
    f->face_count = face_count;
  } else
    rc = palp_fem_surface_faces(mesh, &f->face, &f->face_count);
  if (rc) return rc;
  const size_t np = (size_t)(f->face_count > 0 ? f->face_count : 1) * 17 * 17;
  f->lam = calloc(np, sizeof(double));
  f->last_p = calloc(np, sizeof(double));
  if (!f->lam || !f->last_p) {
    palp_fem_finger_destroy(f);
    return PALP_ENOMEM;
  }
  return PALP_OK;
}

void palp_fem_finger_destroy(palp_fem_finger *f) {
  if (!f) return;
  free(f->u_prev);
  free(f->u_save);
  free(f->face);
  free(f->lam);
  free(f->last_p);
  memset(f, 0, sizeof *f);
}

/* Position of (row, col) with row <= col in the upper-triangle pattern, or -1. */
static long kidx(const palp_fem_model *m, int r, int c) {
  if (r > c) {
    const int t = r;
    r = c, c = t;
  }
  int lo = m->colp[c], hi = m->colp[c + 1] - 1;
  while (lo <= hi) {
    const int mid = (lo + hi) / 2;
    if (m->rowi[mid] < r) lo = mid + 1;
    else if (m->rowi[mid] > r) hi = mid - 1;
    else return mid;
  }
  return -1;
}

/* Composite Simpson rule on [-1, 1] with n (even) intervals: n + 1 points that
 * include the face's nodes. Why not Gauss points: an 8 mm sphere on a coarse face
 * (8 mm at level 2) first touches near one node, and its contact zone (radius
 * sqrt(2 R |g|), ~1.3 mm at 0.1 mm of penetration) falls between Gauss points;
 * a 5-point Lobatto rule caught it only at the node, which then carried MPa and
 * sank 0.18 mm. Eight intervals sample every ~1 mm. */
static int simpson_1d(int n, double *x, double *w) {
  if (n < 2) n = 2;
  if (n > 16) n = 16;
  n &= ~1;
  const double h = 2.0 / n;
  for (int i = 0; i <= n; ++i) {
    x[i] = -1.0 + h * i;
    w[i] = h / 3.0 * (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0));
  }
  return n + 1;
}

static int contact_term(void *ud, palp_fem_model *m, const double *u, int want_tangent) {
  palp_fem_finger *f = ud;
  const palp_fem_mesh *mesh = m->mesh;
  const double *c = f->center, R = f->radius, eps = f->penalty;
  double gx[17], gw[17];
  const int nq = simpson_1d(f->quad, gx, gw);
  f->force[0] = f->force[1] = f->force[2] = 0.0;
  f->min_gap = INFINITY;
  f->max_pressure = 0.0;
  f->active = 0;
  static const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
  for (int k = 0; k < f->face_count; ++k) {
    const int *nd = f->face[k];
    double X[4][3], x[4][3];
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) {
        X[a][i] = mesh->x[nd[a]][i];
        x[a][i] = X[a][i] + u[3 * nd[a] + i];
      }
    /* cheap reject: the face's current bounding sphere against the finger */
    double mid[3] = {0, 0, 0}, rad = 0.0;
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) mid[i] += 0.25 * x[a][i];
    for (int a = 0; a < 4; ++a) {
      const double d0 = x[a][0] - mid[0], d1 = x[a][1] - mid[1], d2 = x[a][2] - mid[2];
      rad = fmax(rad, sqrt(d0 * d0 + d1 * d1 + d2 * d2));
    }
    const double dm = sqrt((mid[0] - c[0]) * (mid[0] - c[0]) + (mid[1] - c[1]) * (mid[1] - c[1]) +
                           (mid[2] - c[2]) * (mid[2] - c[2]));
    if (dm - rad > R + 0.002) {
      for (int q = 0; q < nq * 17; ++q) f->last_p[(size_t)k * 289 + (size_t)q] = 0.0;
      continue;
    }
    for (int a = 0; a < 4; ++a) { /* the nodes' own gaps, for the no-penetration check */
      const double d0 = x[a][0] - c[0], d1 = x[a][1] - c[1], d2 = x[a][2] - c[2];
      f->min_gap = fmin(f->min_gap, sqrt(d0 * d0 + d1 * d1 + d2 * d2) - R);
    }
    for (int qi = 0; qi < nq; ++qi)
      for (int qj = 0; qj < nq; ++qj) {
        const size_t pt = (size_t)k * 289 + (size_t)qi * 17 + (size_t)qj;
        f->last_p[pt] = 0.0;
        const double xi = gx[qi], et = gx[qj];
        double N[4], dXa[3] = {0}, dXb[3] = {0}, p[3] = {0}, dxa[3] = {0}, dxb[3] = {0};
        for (int a = 0; a < 4; ++a) {
          N[a] = 0.25 * (1 + sx[a] * xi) * (1 + sy[a] * et);
          const double na = 0.25 * sx[a] * (1 + sy[a] * et), nb = 0.25 * sy[a] * (1 + sx[a] * xi);
          for (int i = 0; i < 3; ++i) {
            p[i] += N[a] * x[a][i];
            dXa[i] += na * X[a][i];
            dXb[i] += nb * X[a][i];
            dxa[i] += na * x[a][i];
            dxb[i] += nb * x[a][i];
          }
        }
        double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
        const double r = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const double g = r - R;
        f->min_gap = fmin(f->min_gap, g);
        const double pr = f->lam[pt] - eps * g; /* augmented pressure */
        if (!(pr > 0.0) || !(r > 0.0)) continue;
        const double n[3] = {d[0] / r, d[1] / r, d[2] / r};
        /* only faces that face the sphere (never pull a back face) */
        const double nf[3] = {dxa[1] * dxb[2] - dxa[2] * dxb[1], dxa[2] * dxb[0] - dxa[0] * dxb[2],
                              dxa[0] * dxb[1] - dxa[1] * dxb[0]};
        if (nf[0] * n[0] + nf[1] * n[1] + nf[2] * n[2] >= 0.0) continue;
        const double cr[3] = {dXa[1] * dXb[2] - dXa[2] * dXb[1], dXa[2] * dXb[0] - dXa[0] * dXb[2],
                              dXa[0] * dXb[1] - dXa[1] * dXb[0]};
        const double dA = sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]) * gw[qi] * gw[qj];
        f->last_p[pt] = pr;
        f->active++;
        f->max_pressure = fmax(f->max_pressure, pr);
        for (int i = 0; i < 3; ++i) f->force[i] -= pr * dA * n[i];
        for (int a = 0; a < 4; ++a)
          for (int i = 0; i < 3; ++i) m->fint[3 * nd[a] + i] -= N[a] * pr * dA * n[i];
        if (!want_tangent) continue;
        double T[3][3];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            T[i][j] = dA * (eps * n[i] * n[j] - pr / r * ((i == j) - n[i] * n[j]));
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b)
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j) {
                const int ra = m->eq[3 * nd[a] + i], cb = m->eq[3 * nd[b] + j];
                if (ra < 0 || cb < 0 || ra > cb) continue; /* upper triangle once */
                const long q = kidx(m, ra, cb);
                if (q >= 0) m->kval[q] += N[a] * N[b] * T[i][j];
              }
      }
  }
  return PALP_OK;
}

void palp_fem_finger_attach(palp_fem_finger *f, palp_fem_model *m) {
  m->extra_fn = contact_term;
  m->extra_ud = f;
}

/* The secant predictor (palp_fem_finger.predict): m->u becomes u_k + a (u_k - u_prev)
 * on the free equations, a = |c_next - c_k| / |c_k - c_prev| (at most 4), u_k kept in
 * u_save. Why: started from u_k, the first Newton iterate meets the sphere overlapping
 * the surface by the whole depth step (0.25-2 mm; a penalty pressure of 1e10 x 1e-3 =
 * 10 MPa), and the solve spends its first iterations, and most of its indefinite
 * tangents, pulling the surface back out; the extrapolated state is near the new
 * equilibrium (the relaxed solid's path is smooth). The converged state does not
 * depend on the start (the same residual test). Returns 1 if m->u was extrapolated;
 * *saved tells whether u_save holds u_k (every press but the first). */
static int predict(palp_fem_model *m, palp_fem_finger *f, const double c_k[3], const double c_next[3], int *saved) {
  const size_t nd = (size_t)m->ndof;
  *saved = 0;
  if (!f->predict) return 0;
  if (!f->u_save && !(f->u_save = malloc(nd * sizeof(double)))) return 0;
  if (!f->u_prev) { /* the first press: nothing to extrapolate from yet */
    if (!(f->u_prev = malloc(nd * sizeof(double)))) return 0;
    memcpy(f->u_prev, m->u, nd * sizeof(double)); /* the state at c_k (0 for a curve's first contact) */
    for (int i = 0; i < 3; ++i) f->c_prev[i] = c_k[i];
    return 0;
  }
  double s0 = 0.0, s1 = 0.0;
  for (int i = 0; i < 3; ++i) {
    s0 += (c_k[i] - f->c_prev[i]) * (c_k[i] - f->c_prev[i]);
    s1 += (c_next[i] - c_k[i]) * (c_next[i] - c_k[i]);
  }
  memcpy(f->u_save, m->u, nd * sizeof(double)); /* u_k, the secant's next older end */
  *saved = 1;
  if (!(s0 > 0.0)) return 0;
  const double a = fmin(4.0, sqrt(s1 / s0));
  for (size_t d = 0; d < nd; ++d)
    if (m->eq[d] >= 0) m->u[d] += a * (f->u_save[d] - f->u_prev[d]);
  f->predictions++;
  return 1;
}

int palp_fem_finger_press(palp_fem_model *m, palp_fem_finger *f, const double (*centers)[3], int count,
                          double (*force)[3], double *min_gap) {
  double prev[3] = {f->center[0], f->center[1], f->center[2]};
  const size_t nd = (size_t)m->ndof;
  for (int k = 0; k < count; ++k) {
    const double c_k[3] = {prev[0], prev[1], prev[2]};
    int saved;
    int predicted = predict(m, f, c_k, centers[k], &saved);
    /* sub-steps from prev to centers[k]: 1, then 2, 4, ... on failure */
    int rc = PALP_OK;
    for (int level = 0; level <= 6; ++level) {
      if (level == 1 && predicted) { /* the prediction did not converge: from u_k, as without one */
        memcpy(m->u, f->u_save, nd * sizeof(double));
        predicted = 0;
        level = 0;
      }
      const int parts = 1 << level;
      double start[3] = {prev[0], prev[1], prev[2]};
      rc = PALP_OK;
      for (int s = 1; s <= parts && rc == PALP_OK; ++s) {
        for (int i = 0; i < 3; ++i) f->center[i] = start[i] + (centers[k][i] - start[i]) * s / parts;
        rc = palp_fem_solve_static(m, NULL, 1, INFINITY);
        if (rc == PALP_OK)
          for (int i = 0; i < 3; ++i) prev[i] = f->center[i];
      }
      if (rc == PALP_OK) break;
      if (rc == PALP_ENOMEM) return rc;
    }
    if (rc) {
      if (predicted) memcpy(m->u, f->u_save, nd * sizeof(double));
      return rc;
    }
    if (saved) { /* the secant's older end moves up to u_k (after the first press u_prev is u_k already) */
      memcpy(f->u_prev, f->u_save, nd * sizeof(double));
      for (int i = 0; i < 3; ++i) f->c_prev[i] = c_k[i];
    }
    /* Uzawa: the multipliers take the converged pressure until the penetration
     * is below gap_tol; the force then no longer depends on the penalty */
    for (int aug = 0; aug < f->max_augment && f->min_gap < -f->gap_tol; ++aug) {
      memcpy(f->lam, f->last_p, sizeof(double) * (size_t)f->face_count * 289);
      f->augmentations++;
      rc = palp_fem_solve_static(m, NULL, 1, INFINITY);
      if (rc) return rc;
    }
    /* f->force holds the last assembly, the converged one */
    if (force)
      for (int i = 0; i < 3; ++i) force[k][i] = f->force[i];
    if (min_gap) min_gap[k] = f->min_gap;
  }
  return PALP_OK;
}

int palp_fem_lesion_scale(const palp_fem_mesh *mesh, const palp_lesion *les, int count, double *scale) {
  int touched = 0;
  enum { S = 6 };
  for (int e = 0; e < mesh->element_count; ++e) {
    scale[e] = 1.0;
    if (mesh->region[e] != PALP_FEM_GEL || count <= 0) continue;
    const int *h = mesh->hex[e];
    static const double sg[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                    {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    /* bounding-sphere reject */
    double mid[3] = {0, 0, 0}, rad = 0.0;
    for (int a = 0; a < 8; ++a)
      for (int i = 0; i < 3; ++i) mid[i] += 0.125 * mesh->x[h[a]][i];
    for (int a = 0; a < 8; ++a) {
      double s2 = 0;
      for (int i = 0; i < 3; ++i) s2 += (mesh->x[h[a]][i] - mid[i]) * (mesh->x[h[a]][i] - mid[i]);
      rad = fmax(rad, sqrt(s2));
    }
    double add = 0.0;
    for (int l = 0; l < count; ++l) {
      const double dc = sqrt((mid[0] - les[l].center.x) * (mid[0] - les[l].center.x) +
                             (mid[1] - les[l].center.y) * (mid[1] - les[l].center.y) +
                             (mid[2] - les[l].center.z) * (mid[2] - les[l].center.z));
      if (dc > rad + les[l].radius) continue;
      /* volume fraction by the reference map's Jacobian-weighted midpoint rule */
      double vin = 0.0, vall = 0.0;
      for (int i = 0; i < S; ++i)
        for (int j = 0; j < S; ++j)
          for (int k = 0; k < S; ++k) {
            const double xi[3] = {-1 + (2 * i + 1.0) / S, -1 + (2 * j + 1.0) / S, -1 + (2 * k + 1.0) / S};
            double dN[8][3], J[3][3] = {{0}}, p[3] = {0};
            palp_fem_hex_dshape(xi, dN);
            for (int a = 0; a < 8; ++a) {
              const double Na = 0.125 * (1 + xi[0] * sg[a][0]) * (1 + xi[1] * sg[a][1]) * (1 + xi[2] * sg[a][2]);
              for (int r = 0; r < 3; ++r) {
                p[r] += Na * mesh->x[h[a]][r];
                for (int q = 0; q < 3; ++q) J[r][q] += mesh->x[h[a]][r] * dN[a][q];
              }
            }
            const double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
                               J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
                               J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
            const double q0 = p[0] - les[l].center.x, q1 = p[1] - les[l].center.y, q2 = p[2] - les[l].center.z;
            vall += det;
            if (q0 * q0 + q1 * q1 + q2 * q2 <= les[l].radius * les[l].radius) vin += det;
          }
      if (vin > 0.0) add += vin / vall * (les[l].stiffness_ratio - 1.0);
    }
    if (add != 0.0) {
      scale[e] = fmax(1.0 + add, 1e-6);
      ++touched;
    }
  }
  return touched;
}

int palp_fem_finger_curve(const palp_fem_config *cfg, const palp_fem_mesh *mesh, const palp_lesion *lesions,
                          int lesion_count, const double n[3], double radius, const double *depth, int count,
                          double fmax, double *force, double *min_gap, long *newton,
                          palp_fem_finger_progress_fn progress, void *ud, char *err, size_t errlen) {
  palp_fem_model m;
  int rc = palp_fem_model_create(&m, mesh, cfg);
  if (!rc) rc = palp_fem_model_finalize(&m);
  if (rc) {
    snprintf(err, errlen, "model: %s", m.err);
    return -1;
  }
  double *scale = malloc(sizeof(double) * (size_t)mesh->element_count);
  palp_fem_finger f;
  if (!scale || palp_fem_finger_init(&f, mesh, NULL, 0, radius, 0.0)) {
    free(scale);
    palp_fem_model_destroy(&m);
    snprintf(err, errlen, "out of memory");
    return -1;
  }
  palp_fem_lesion_scale(mesh, lesions, lesion_count, scale);
  m.c10_scale = scale;
  palp_fem_finger_attach(&f, &m);
  /* full_newton 0 (the default): inexact Newton on the consistent tangent with a
   * reused, shifted-where-indefinite factor (fem_model.c, solve_static), each depth
   * started from the secant prediction: the same curve within the Newton tolerance,
   * 13x faster at level 3 (docs/fem.md) */
  m.static_reuse = !cfg->full_newton;
  f.predict = !cfg->full_newton; /* the secant start (predict): 45 deg, level 3, 9 depths: 6 factorisations
                                  * and no LDL^T against 55 and 16 without it */
  const double R = cfg->mesh.radius, r = f.radius;
  for (int a = 0; a < 3; ++a) f.center[a] = (R + r) * n[a];
  int done = 0;
  double d_last = 0.0;
  for (int k = 0; k < count; ++k) {
    /* With the secant start, a step of the depth longer than 1 mm is pressed through
     * intermediate depths (not reported): past ~8 mm a 2 mm step's prediction missed
     * and its solve from the last state ran into the indefinite tangents the start
     * avoids (45 deg, level 4, 8 -> 10 mm: over 18 min of simplicial LDL^T). The
     * reported depth's equilibrium does not depend on the path (relaxed, frictionless). */
    const int parts = f.predict && depth[k] - d_last > 1e-3 ? (int)ceil((depth[k] - d_last) / 1e-3 - 1e-9) : 1;
    double f3[1][3], g = 0.0;
    int bad = 0;
    for (int p = 1; p <= parts && !bad; ++p) {
      const double dk = p == parts ? depth[k] : d_last + (depth[k] - d_last) * p / parts;
      const double c[1][3] = {{(R + r - dk) * n[0], (R + r - dk) * n[1], (R + r - dk) * n[2]}};
      bad = palp_fem_finger_press(&m, &f, c, 1, f3, &g) != 0;
    }
    if (bad) {
      snprintf(err, errlen, "FE press at %.2f mm: %s", depth[k] * 1e3, m.err);
      break;
    }
    d_last = depth[k];
    force[k] = f3[0][0] * n[0] + f3[0][1] * n[1] + f3[0][2] * n[2]; /* along the outward normal */
    if (min_gap) min_gap[k] = g;
    done = k + 1;
    if (progress) progress(ud, k, depth[k], force[k], g, m.newton_iterations);
    if (force[k] > fmax) break;
  }
  if (newton) *newton = m.newton_iterations;
  palp_fem_finger_destroy(&f);
  free(scale);
  palp_fem_model_destroy(&m);
  return done;
}
