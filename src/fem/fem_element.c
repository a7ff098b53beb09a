/*
 * fem_element.c - the Q1/P0 (mean-dilatation) viscoelastic hexahedron.
 *
 * The element's stored energy is
 *   Pi_e = int_Ve0 W_iso(C) dV + Ve0 U(theta),   theta = ve / Ve0,
 * where ve is the element's current volume. The isochoric Neo-Hookean part is
 * integrated at the 2x2x2 Gauss points (total Lagrangian, with the Prony history
 * per Gauss point); the volumetric part sees only the element's mean dilatation
 * theta, i.e. one constant pressure per element (P0). A trilinear hex with a
 * pointwise J has 8 volumetric constraints per element against ~3 free DOFs, and
 * locks when the gel's K/mu ~ 1e5; the mean dilatation leaves one. Because the
 * Abaqus energy is split into I1bar (independent of J) and J, this is exactly the
 * Simo-Taylor-Pister mixed Q1/P0 element, and its tangent is symmetric:
 *   f_a   = int B_a^T S dV0 + p dve/dx_a,                       p = 2 (theta - 1) / D1
 *   K_ab  = int B_a^T (gamma CC0) B_b + (dN_a . S dN_b) I dV0
 *         + (2 / D1) / Ve0 (dve/dx_a)(dve/dx_b)^T + p d2ve/dx_a dx_b
 *   dve/dx_a          = int grad_x N_a dv
 *   d2ve/dx_ai dx_bj  = int (N_a,i N_b,j - N_a,j N_b,i) dv
 */
#include <math.h>
#include <string.h>

#include "fem_internal.h"

static double det3(double F[3][3]) {
  return F[0][0] * (F[1][1] * F[2][2] - F[1][2] * F[2][1]) - F[0][1] * (F[1][0] * F[2][2] - F[1][2] * F[2][0]) +
         F[0][2] * (F[1][0] * F[2][1] - F[1][1] * F[2][0]);
}

static void inv3(double F[3][3], double det, double Fi[3][3]) {
  Fi[0][0] = (F[1][1] * F[2][2] - F[1][2] * F[2][1]) / det;
  Fi[0][1] = (F[0][2] * F[2][1] - F[0][1] * F[2][2]) / det;
  Fi[0][2] = (F[0][1] * F[1][2] - F[0][2] * F[1][1]) / det;
  Fi[1][0] = (F[1][2] * F[2][0] - F[1][0] * F[2][2]) / det;
  Fi[1][1] = (F[0][0] * F[2][2] - F[0][2] * F[2][0]) / det;
  Fi[1][2] = (F[0][2] * F[1][0] - F[0][0] * F[1][2]) / det;
  Fi[2][0] = (F[1][0] * F[2][1] - F[1][1] * F[2][0]) / det;
  Fi[2][1] = (F[0][1] * F[2][0] - F[0][0] * F[2][1]) / det;
  Fi[2][2] = (F[0][0] * F[1][1] - F[0][1] * F[1][0]) / det;
}

/* Deformation gradient F = sum_a x_a (x) dN_a/dX at one Gauss point. */
static void deformation(const double *x, const double *dN, double F[3][3]) {
  memset(F, 0, 9 * sizeof(double));
  for (int a = 0; a < 8; ++a)
    for (int i = 0; i < 3; ++i)
      for (int J = 0; J < 3; ++J) F[i][J] += x[3 * a + i] * dN[3 * a + J];
}

/* Prony coefficients of one step of length dt [s] (the factors of
 * palp_fem_prony_update): decay_k = exp(-x_k), beta_k = g_k (1 - exp(-x_k)) / x_k,
 * x_k = dt / tau_k; returns gamma = g_inf + sum_k beta_k. They depend only on the
 * material and dt, so an element computes them once instead of at every Gauss point. */
static double prony_coeffs(const palp_fem_material *m, int np, double dt, double *decay, double *beta) {
  double gamma = palp_fem_ginf(m);
  for (int k = 0; k < np; ++k) {
    if (dt <= 0.0) {
      decay[k] = 1.0;
      beta[k] = m->g[k];
    } else if (isinf(dt)) {
      decay[k] = 0.0;
      beta[k] = 0.0;
    } else {
      const double x = dt / m->tau[k];
      decay[k] = exp(-x);
      beta[k] = x < 1e-8 ? m->g[k] * (1.0 - 0.5 * x) : m->g[k] * (-expm1(-x)) / x;
    }
    gamma += beta[k];
  }
  return gamma;
}

int palp_fem_element(const palp_fem_model *m, int e, const double *ue, double dt, double *fe,
                     double (*ke)[24], double *S0t, double *Ht) {
  const palp_fem_mesh *mesh = m->mesh;
  const palp_fem_material *mat = &m->mat[mesh->region[e]];
  palp_fem_material scaled; /* a lesion's element: the gel with its C10 scaled */
  if (m->c10_scale && m->c10_scale[e] != 1.0) {
    scaled = *mat;
    scaled.c10 *= m->c10_scale[e];
    mat = &scaled;
  }
  const int np = m->nprony;
  double x[8][3];
  for (int a = 0; a < 8; ++a)
    for (int i = 0; i < 3; ++i) x[a][i] = mesh->x[mesh->hex[e][a]][i] + ue[3 * a + i];
  double decay[PALP_FEM_MAX_PRONY], beta[PALP_FEM_MAX_PRONY];
  const double ginf = palp_fem_ginf(mat), gamma = prony_coeffs(mat, np, dt, decay, beta);
  const double mu = 2.0 * mat->c10; /* instantaneous shear modulus [Pa] */
  double g[24] = {0}, ve = 0.0;
  /* the geometric volume term p d2v/dx_a dx_b is antisymmetric in (i, k) for each
   * node pair: accumulate the cross products sum jw (grad_x N_a x grad_x N_b) [m^3 / m^2]
   * for a < b and expand them once p is known */
  double X[8][8][3];
  memset(fe, 0, 24 * sizeof(double));
  if (ke) {
    memset(ke, 0, 24 * 24 * sizeof(double));
    memset(X, 0, sizeof X);
  }
  for (int gp = 0; gp < 8; ++gp) {
    const size_t q = (size_t)e * 8 + (size_t)gp;
    const double(*dN)[3] = (const double(*)[3])(m->gp_dNdX + q * 24);
    const double w = m->gp_w[q];
    double F[3][3];
    deformation(&x[0][0], &dN[0][0], F);
    const double J = det3(F);
    if (!(J > 0.0)) return PALP_EUNSTABLE;
    double Fi[3][3];
    inv3(F, J, Fi);
    /* isochoric Neo-Hookean S0 = mu J^(-2/3) (I - I1/3 C^-1), C^-1 = F^-1 F^-T
     * (palp_fem_nh_iso, with the inverse from F) */
    const double Jm13 = 1.0 / cbrt(J), Jm23 = Jm13 * Jm13;
    const double C[6] = {F[0][0] * F[0][0] + F[1][0] * F[1][0] + F[2][0] * F[2][0],
                         F[0][1] * F[0][1] + F[1][1] * F[1][1] + F[2][1] * F[2][1],
                         F[0][2] * F[0][2] + F[1][2] * F[1][2] + F[2][2] * F[2][2],
                         F[0][0] * F[0][1] + F[1][0] * F[1][1] + F[2][0] * F[2][1],
                         F[0][1] * F[0][2] + F[1][1] * F[1][2] + F[2][1] * F[2][2],
                         F[0][0] * F[0][2] + F[1][0] * F[1][2] + F[2][0] * F[2][2]};
    const double Ci[6] = {Fi[0][0] * Fi[0][0] + Fi[0][1] * Fi[0][1] + Fi[0][2] * Fi[0][2],
                          Fi[1][0] * Fi[1][0] + Fi[1][1] * Fi[1][1] + Fi[1][2] * Fi[1][2],
                          Fi[2][0] * Fi[2][0] + Fi[2][1] * Fi[2][1] + Fi[2][2] * Fi[2][2],
                          Fi[0][0] * Fi[1][0] + Fi[0][1] * Fi[1][1] + Fi[0][2] * Fi[1][2],
                          Fi[1][0] * Fi[2][0] + Fi[1][1] * Fi[2][1] + Fi[1][2] * Fi[2][2],
                          Fi[0][0] * Fi[2][0] + Fi[0][1] * Fi[2][1] + Fi[0][2] * Fi[2][2]};
    const double trC = C[0] + C[1] + C[2], f0 = mu * Jm23, f1 = f0 * trC / 3.0;
    const double S0[6] = {f0 - f1 * Ci[0], f0 - f1 * Ci[1], f0 - f1 * Ci[2], -f1 * Ci[3], -f1 * Ci[4], -f1 * Ci[5]};
    /* Prony: H_k+ = decay_k H_k + beta_k (S0+ - S0), S = g_inf S0+ + sum_k H_k+ */
    const double *S0old = m->S0 ? m->S0 + q * 6 : S0;
    const double *Hold = m->H ? m->H + q * (size_t)np * 6 : NULL;
    double S[6];
    for (int c = 0; c < 6; ++c) S[c] = ginf * S0[c];
    for (int k = 0; k < np; ++k)
      for (int c = 0; c < 6; ++c) {
        const double h = (Hold ? decay[k] * Hold[6 * k + c] : 0.0) + beta[k] * (S0[c] - S0old[c]);
        if (Ht) Ht[((size_t)gp * (size_t)np + (size_t)k) * 6 + (size_t)c] = h;
        S[c] += h;
      }
    if (S0t) memcpy(S0t + gp * 6, S0, sizeof S0);
    /* internal force: f_a = w F S dN_a (the B^T S of the Voigt form, B = sym(F^T grad N)) */
    double FS[3][3];
    for (int i = 0; i < 3; ++i) {
      FS[i][0] = F[i][0] * S[0] + F[i][1] * S[3] + F[i][2] * S[5];
      FS[i][1] = F[i][0] * S[3] + F[i][1] * S[1] + F[i][2] * S[4];
      FS[i][2] = F[i][0] * S[5] + F[i][1] * S[4] + F[i][2] * S[2];
    }
    for (int a = 0; a < 8; ++a)
      for (int i = 0; i < 3; ++i) fe[3 * a + i] += w * (FS[i][0] * dN[a][0] + FS[i][1] * dN[a][1] + FS[i][2] * dN[a][2]);
    /* volumetric: current volume and its gradient */
    const double jw = J * w;
    double nx[8][3]; /* grad_x N_a = F^-T dN_a/dX */
    for (int a = 0; a < 8; ++a)
      for (int i = 0; i < 3; ++i) {
        nx[a][i] = dN[a][0] * Fi[0][i] + dN[a][1] * Fi[1][i] + dN[a][2] * Fi[2][i];
        g[3 * a + i] += nx[a][i] * jw;
      }
    ve += jw;
    if (!ke) continue;
    /* Material part in spatial form. The push-forward of gamma CC0 is gamma times
     * the Kirchhoff-based Neo-Hookean modulus (Holzapfel 6.170, mu = 2 C10_inst):
     *   J c = 2/3 mu tr(bb) [II - 1/3 I x I] - 2/3 mu [dev(bb) x I + I x dev(bb)],
     * bb = J^(-2/3) F F^T. Contracted with grad_x N_a (A) and grad_x N_b (B):
     *   K_ab,ik = w gamma [ al/2 (A.B) d_ik + al/2 B_i A_k - al/3 A_i B_k
     *                      - 2/3 mu ((dA)_i B_k + A_i (dB)_k) ],  al = 2/3 mu tr(bb),
     * d = dev(bb). Geometric part in reference form: (dN_a . S dN_b) I.
     * Grouped as three outer products per node pair,
     *   K_ab,ik = B_i P_a,k + U_a,i B_k + A_i V_b,k + d_ik (c_d A.B + G_ab),
     * P = c1 A, U = c2 A - c3 dA, V = -c3 dA (c1 = wg al/2, c2 = -wg al/3, c3 = wg 2/3 mu). */
    double bb[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) bb[i][j] = Jm23 * (F[i][0] * F[j][0] + F[i][1] * F[j][1] + F[i][2] * F[j][2]);
    const double trb = bb[0][0] + bb[1][1] + bb[2][2];
    for (int i = 0; i < 3; ++i) bb[i][i] -= trb / 3.0; /* now dev(bb) */
    const double wg = w * gamma, al = 2.0 / 3.0 * mu * trb;
    const double c1 = wg * 0.5 * al, c2 = -wg * al / 3.0, c3 = wg * 2.0 / 3.0 * mu;
    double P[8][3], U[8][3], V[8][3], SdN[8][3];
    for (int a = 0; a < 8; ++a) {
      for (int i = 0; i < 3; ++i) {
        const double dA = bb[i][0] * nx[a][0] + bb[i][1] * nx[a][1] + bb[i][2] * nx[a][2];
        P[a][i] = c1 * nx[a][i];
        U[a][i] = c2 * nx[a][i] - c3 * dA;
        V[a][i] = -c3 * dA;
      }
      SdN[a][0] = w * (S[0] * dN[a][0] + S[3] * dN[a][1] + S[5] * dN[a][2]);
      SdN[a][1] = w * (S[3] * dN[a][0] + S[1] * dN[a][1] + S[4] * dN[a][2]);
      SdN[a][2] = w * (S[5] * dN[a][0] + S[4] * dN[a][1] + S[2] * dN[a][2]);
    }
    for (int a = 0; a < 8; ++a)
      for (int b = a; b < 8; ++b) {
        const double *A = nx[a], *B = nx[b];
        const double d = c1 * (A[0] * B[0] + A[1] * B[1] + A[2] * B[2]) +
                         (dN[a][0] * SdN[b][0] + dN[a][1] * SdN[b][1] + dN[a][2] * SdN[b][2]);
        for (int i = 0; i < 3; ++i) {
          double *row = &ke[3 * a + i][3 * b];
          for (int k = 0; k < 3; ++k) row[k] += B[i] * P[a][k] + U[a][i] * B[k] + A[i] * V[b][k];
          row[i] += d;
        }
        if (b > a) {
          X[a][b][0] += jw * (A[1] * B[2] - A[2] * B[1]);
          X[a][b][1] += jw * (A[2] * B[0] - A[0] * B[2]);
          X[a][b][2] += jw * (A[0] * B[1] - A[1] * B[0]);
        }
      }
  }
  const double V0 = m->vol0[e];
  const double theta = ve / V0;
  if (!(theta > 0.0)) return PALP_EUNSTABLE;
  const double p = palp_fem_pressure(mat->d1, theta);
  for (int c = 0; c < 24; ++c) fe[c] += p * g[c];
  if (ke) {
    const double kv = 2.0 / mat->d1 / V0;
    /* p d2v/dx_ai dx_bk = p sum jw (A_i B_k - A_k B_i): the antisymmetric matrix of
     * X_ab, (0,1) = X_2, (1,2) = X_0, (2,0) = X_1 */
    for (int a = 0; a < 8; ++a)
      for (int b = a + 1; b < 8; ++b) {
        const double x0 = p * X[a][b][0], x1 = p * X[a][b][1], x2 = p * X[a][b][2];
        double(*K)[24] = ke + 3 * a;
        const int c = 3 * b;
        K[0][c + 1] += x2, K[1][c] -= x2;
        K[1][c + 2] += x0, K[2][c + 1] -= x0;
        K[2][c] += x1, K[0][c + 2] -= x1;
      }
    for (int r = 0; r < 24; ++r)
      for (int c = r; c < 24; ++c) ke[r][c] += kv * g[r] * g[c];
    /* node pairs a <= b hold the upper triangle; mirror it */
    for (int r = 0; r < 24; ++r)
      for (int c = 0; c < r; ++c) ke[r][c] = ke[c][r];
  }
  return PALP_OK;
}

int palp_fem_element_cauchy(const palp_fem_model *m, int e, int gp, const double *u, double dt, double sigma[6]) {
  const palp_fem_mesh *mesh = m->mesh;
  const palp_fem_material *mat = &m->mat[mesh->region[e]];
  palp_fem_material scaled; /* a lesion's element: the gel with its C10 scaled */
  if (m->c10_scale && m->c10_scale[e] != 1.0) {
    scaled = *mat;
    scaled.c10 *= m->c10_scale[e];
    mat = &scaled;
  }
  double x[8][3];
  double ve = 0.0, Fg[3][3] = {{0}}, Sg[6] = {0};
  for (int a = 0; a < 8; ++a)
    for (int i = 0; i < 3; ++i) x[a][i] = mesh->x[mesh->hex[e][a]][i] + u[3 * mesh->hex[e][a] + i];
  for (int q = 0; q < 8; ++q) {
    const size_t k = (size_t)e * 8 + (size_t)q;
    const double(*dN)[3] = (const double(*)[3])(m->gp_dNdX + k * 24);
    double F[3][3];
    deformation(&x[0][0], &dN[0][0], F);
    const double J = det3(F);
    if (!(J > 0.0)) return PALP_EUNSTABLE;
    ve += J * m->gp_w[k];
    if (q != gp) continue;
    memcpy(Fg, F, sizeof F);
    const double C[6] = {F[0][0] * F[0][0] + F[1][0] * F[1][0] + F[2][0] * F[2][0],
                         F[0][1] * F[0][1] + F[1][1] * F[1][1] + F[2][1] * F[2][1],
                         F[0][2] * F[0][2] + F[1][2] * F[1][2] + F[2][2] * F[2][2],
                         F[0][0] * F[0][1] + F[1][0] * F[1][1] + F[2][0] * F[2][1],
                         F[0][1] * F[0][2] + F[1][1] * F[1][2] + F[2][1] * F[2][2],
                         F[0][0] * F[0][2] + F[1][0] * F[1][2] + F[2][0] * F[2][2]};
    double S0[6], Hn[PALP_FEM_MAX_PRONY * 6];
    static const double zeroH[PALP_FEM_MAX_PRONY * 6] = {0};
    palp_fem_nh_iso(mat->c10, C, S0, NULL);
    const double *S0old = m->S0 ? m->S0 + k * 6 : S0;
    const double *Hold = m->H ? m->H + k * (size_t)m->nprony * 6 : zeroH;
    palp_fem_prony_update(mat, dt, S0, S0old, Hold, Hn, Sg);
  }
  const double J = det3(Fg);
  const double p = palp_fem_pressure(mat->d1, ve / m->vol0[e]);
  /* sigma = F S F^T / J + p I */
  const double S[3][3] = {{Sg[0], Sg[3], Sg[5]}, {Sg[3], Sg[1], Sg[4]}, {Sg[5], Sg[4], Sg[2]}};
  double T[3][3] = {{0}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) T[i][j] += Fg[i][k] * S[k][l] * Fg[j][l] / J;
  sigma[0] = T[0][0] + p;
  sigma[1] = T[1][1] + p;
  sigma[2] = T[2][2] + p;
  sigma[3] = T[0][1];
  sigma[4] = T[1][2];
  sigma[5] = T[0][2];
  return PALP_OK;
}
