/*
 * fem_material.c - Abaqus compressible Neo-Hookean with a deviatoric Prony series.
 *
 * The strain energy splits into an isochoric part C10 (I1bar - 3) and a
 * volumetric part (J - 1)^2 / D1. Only the isochoric part relaxes (the Prony
 * series of Eq. 4 acts on the shear modulus; the bulk response is elastic), which
 * is how Abaqus and FEBio treat a deviatoric Prony series. The volumetric part is
 * evaluated per element from the mean dilatation (fem_model.c), so here it is a
 * one-line pressure.
 */
#include <math.h>
#include <string.h>

#include "fem_internal.h"

double palp_fem_ginf(const palp_fem_material *m) {
  double g = 1.0;
  for (int k = 0; k < m->prony_count; ++k) g -= m->g[k];
  return g;
}

double palp_fem_c10_instant(const palp_fem_material *m, palp_fem_c10_reading r) {
  if (r == PALP_FEM_C10_INSTANTANEOUS) return m->c10;
  return m->c10 / palp_fem_ginf(m);
}

/* Inverse and determinant of a symmetric 3x3 in Voigt form. */
static double sym_inverse(const double C[6], double Ci[6]) {
  const double c11 = C[0], c22 = C[1], c33 = C[2], c12 = C[3], c23 = C[4], c13 = C[5];
  const double a11 = c22 * c33 - c23 * c23;
  const double a22 = c11 * c33 - c13 * c13;
  const double a33 = c11 * c22 - c12 * c12;
  const double a12 = c13 * c23 - c12 * c33;
  const double a23 = c12 * c13 - c11 * c23;
  const double a13 = c12 * c23 - c13 * c22;
  const double det = c11 * a11 + c12 * a12 + c13 * a13;
  Ci[0] = a11 / det;
  Ci[1] = a22 / det;
  Ci[2] = a33 / det;
  Ci[3] = a12 / det;
  Ci[4] = a23 / det;
  Ci[5] = a13 / det;
  return det;
}

/* Voigt index pairs. */
static const int vi[6] = {0, 1, 2, 0, 1, 0};
static const int vj[6] = {0, 1, 2, 1, 2, 2};

void palp_fem_nh_iso(double c10, const double C[6], double S[6], double D[6][6]) {
  double Ci[6];
  const double detC = sym_inverse(C, Ci);
  const double I1 = C[0] + C[1] + C[2];
  const double Jm23 = pow(detC, -1.0 / 3.0); /* J^(-2/3) = det(C)^(-1/3) */
  const double mu = 2.0 * c10;
  static const double Iv[6] = {1, 1, 1, 0, 0, 0};
  for (int p = 0; p < 6; ++p) S[p] = mu * Jm23 * (Iv[p] - I1 / 3.0 * Ci[p]);
  if (!D) return;
  /* full 3x3 of C^-1 for the (.) product */
  double M[3][3] = {{Ci[0], Ci[3], Ci[5]}, {Ci[3], Ci[1], Ci[4]}, {Ci[5], Ci[4], Ci[2]}};
  const double f = 2.0 / 3.0 * mu * Jm23;
  for (int p = 0; p < 6; ++p) {
    const int i = vi[p], j = vj[p];
    for (int q = 0; q < 6; ++q) {
      const int k = vi[q], l = vj[q];
      /* (C^-1 (.) C^-1)_ijkl = (Ci_ik Ci_jl + Ci_il Ci_jk) / 2 */
      const double odot = 0.5 * (M[i][k] * M[j][l] + M[i][l] * M[j][k]);
      D[p][q] = f * (I1 * odot + I1 / 3.0 * Ci[p] * Ci[q] - Iv[p] * Ci[q] - Ci[p] * Iv[q]);
    }
  }
}

double palp_fem_prony_update(const palp_fem_material *m, double dt, const double S0new[6],
                             const double S0old[6], const double *Hold, double *Hnew,
                             double S[6]) {
  const double ginf = palp_fem_ginf(m);
  double gamma = ginf;
  for (int p = 0; p < 6; ++p) S[p] = ginf * S0new[p];
  for (int k = 0; k < m->prony_count; ++k) {
    double decay, beta; /* exp(-x), g (1 - exp(-x)) / x */
    if (dt <= 0.0) {
      decay = 1.0;
      beta = m->g[k];
    } else if (isinf(dt)) {
      decay = 0.0;
      beta = 0.0;
    } else {
      const double x = dt / m->tau[k];
      decay = exp(-x);
      beta = x < 1e-8 ? m->g[k] * (1.0 - 0.5 * x) : m->g[k] * (-expm1(-x)) / x;
    }
    gamma += beta;
    for (int p = 0; p < 6; ++p) {
      Hnew[6 * k + p] = decay * Hold[6 * k + p] + beta * (S0new[p] - S0old[p]);
      S[p] += Hnew[6 * k + p];
    }
  }
  return gamma;
}
