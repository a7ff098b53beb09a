/* burgers.c - exact step coefficients of the Burgers element (see burgers.h). */
#include "burgers.h"

#include <math.h>

#include "palp.h"

/* phi0(z) = (e^z - 1) / z and phi1(z) = (e^z - 1 - z) / z^2, without cancellation. */
static double phi0(double z) { return fabs(z) < 1e-8 ? 1.0 + 0.5 * z : expm1(z) / z; }
static double phi1(double z) {
  if (fabs(z) < 1e-4) return 0.5 + z / 6.0 + z * z / 24.0;
  return (expm1(z) - z) / (z * z);
}

int palp_burgers_init(palp_burgers *b, double E1, double eta1, double E2, double eta2, double h) {
  if (!(E1 > 0.0 && eta1 > 0.0 && E2 > 0.0 && eta2 > 0.0 && h > 0.0)) return PALP_EINVAL;
  if (!(isfinite(E1) && isfinite(eta1) && isfinite(E2) && isfinite(eta2) && isfinite(h))) return PALP_EINVAL;
  b->E1 = E1, b->eta1 = eta1, b->E2 = E2, b->eta2 = eta2, b->h = h;
  const double a = E1 / eta1, e = E1 / eta2, c = (E1 + E2) / eta2; /* [1/s] */
  const double A[2][2] = {{-a, -a}, {-e, -c}};
  const double bv[2] = {a, e};
  /* Eigenvalues of A: real, negative and distinct, since the discriminant is
   * (a - c)^2 / 4 + a e > 0 for positive parameters. */
  const double mean = -(a + c) / 2.0, disc = sqrt((a - c) * (a - c) / 4.0 + a * e);
  const double l1 = mean + disc, l2 = mean - disc;
  /* Spectral projectors P1 = (A - l2 I)/(l1 - l2), P2 = (A - l1 I)/(l2 - l1);
   * f(A) = f(l1) P1 + f(l2) P2 for any analytic f. */
  double P1[2][2], P2[2][2];
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      const double d = (i == j) ? 1.0 : 0.0;
      P1[i][j] = (A[i][j] - l2 * d) / (l1 - l2);
      P2[i][j] = (A[i][j] - l1 * d) / (l2 - l1);
    }
  /* Phi = e^{Ah}; Psi0 = int_0^h e^{A s} ds = h phi0(Ah);
   * Psi1 = int_0^h e^{A (h - s)} s/h ds = h phi1(Ah) (substitute tau = h - s and
   * integrate tau e^{A tau} by parts). Then
   * x_{n+1} = Phi x_n + (Psi0 - Psi1) b eps_n + Psi1 b eps_{n+1}. */
  const double e1 = exp(l1 * h), e2 = exp(l2 * h);
  const double q0_1 = h * phi0(l1 * h), q0_2 = h * phi0(l2 * h);
  const double q1_1 = h * phi1(l1 * h), q1_2 = h * phi1(l2 * h);
  for (int i = 0; i < 2; ++i) {
    b->g0[i] = 0.0;
    b->g1[i] = 0.0;
    for (int j = 0; j < 2; ++j) {
      b->phi[i][j] = e1 * P1[i][j] + e2 * P2[i][j];
      const double psi0 = q0_1 * P1[i][j] + q0_2 * P2[i][j];
      const double psi1 = q1_1 * P1[i][j] + q1_2 * P2[i][j];
      b->g0[i] += (psi0 - psi1) * bv[j];
      b->g1[i] += psi1 * bv[j];
    }
  }
  b->tangent = E1 * (1.0 - b->g1[0] - b->g1[1]);
  return PALP_OK;
}

double palp_burgers_creep(double E1, double eta1, double E2, double eta2, double s0, double t1, double t) {
  /* eps(t) = s0/E1 + s0 t/eta1 + s0/E2 (1 - e^{-t E2/eta2})                  (loading)
   * eps(t) = s0 t1/eta1 + s0/E2 (1 - e^{-t1 E2/eta2}) e^{-(t - t1) E2/eta2}   (after removal) */
  const double r = E2 / eta2;
  if (t < 0.0) return 0.0;
  if (t1 <= 0.0 || t <= t1) return s0 / E1 + s0 * t / eta1 + s0 / E2 * (-expm1(-r * t));
  return s0 * t1 / eta1 + s0 / E2 * (-expm1(-r * t1)) * exp(-r * (t - t1));
}
