/*
 * burgers.h - the Burgers element of Eq. 1 (internal to the model).
 *
 * A Maxwell arm (spring E1 [Pa], dashpot eta1 [Pa s]) in series with a Kelvin arm
 * (spring E2 || dashpot eta2). With total strain eps, Maxwell dashpot strain x1 and
 * Kelvin strain x2, the stress is sigma = E1 (eps - x1 - x2) and
 *   dx1/dt = sigma / eta1,
 *   dx2/dt = (sigma - E2 x2) / eta2,
 * i.e. dx/dt = A x + b eps with A = [[-E1/eta1, -E1/eta1], [-E1/eta2, -(E1+E2)/eta2]],
 * b = [E1/eta1, E1/eta2]. Eliminating x gives Eq. 1:
 *   sigma + (eta1/E1 + eta1/E2 + eta2/E2) dsigma/dt + eta1 eta2/(E1 E2) d2sigma/dt2
 *       = eta1 deps/dt + eta1 eta2 / E2 d2eps/dt2.
 * The step integrates this exactly for a strain that is linear over the step:
 *   x_{n+1} = Phi x_n + G0 eps_n + G1 eps_{n+1},
 * with Phi = exp(A h) and G0, G1 from the spectral form using expm1, so it stays
 * exact and stable when the time constants are far shorter than the step.
 */
#ifndef PALP_BURGERS_H
#define PALP_BURGERS_H

typedef struct palp_burgers {
  double E1, eta1, E2, eta2; /* [Pa], [Pa s] */
  double h;                  /* step [s] the coefficients were built for */
  double phi[2][2];          /* exp(A h) */
  double g0[2], g1[2];       /* weights of eps_n and eps_{n+1} */
  double tangent;            /* d sigma_{n+1} / d eps_{n+1} [Pa] */
} palp_burgers;

/* Builds the step coefficients; returns 0 or PALP_EINVAL. */
int palp_burgers_init(palp_burgers *b, double E1, double eta1, double E2, double eta2, double h);

/* Advances the internal strains x[2] from eps_n to eps_{n+1}; returns sigma_{n+1} [Pa]. */
static inline double palp_burgers_advance(const palp_burgers *b, double x[2], double eps_n, double eps_np1) {
  const double x1 = b->phi[0][0] * x[0] + b->phi[0][1] * x[1] + b->g0[0] * eps_n + b->g1[0] * eps_np1;
  const double x2 = b->phi[1][0] * x[0] + b->phi[1][1] * x[1] + b->g0[1] * eps_n + b->g1[1] * eps_np1;
  x[0] = x1;
  x[1] = x2;
  return b->E1 * (eps_np1 - x1 - x2);
}

/* Stress at the end of the step if the strain stays at eps_n: sigma_pred [Pa]. */
static inline double palp_burgers_predict(const palp_burgers *b, const double x[2], double eps_n) {
  const double x1 = b->phi[0][0] * x[0] + b->phi[0][1] * x[1] + (b->g0[0] + b->g1[0]) * eps_n;
  const double x2 = b->phi[1][0] * x[0] + b->phi[1][1] * x[1] + (b->g0[1] + b->g1[1]) * eps_n;
  return b->E1 * (eps_n - x1 - x2);
}

/* Closed-form creep strain under a stress step sigma0 [Pa] applied at t = 0 and removed
 * just after t1 [s] (t1 <= 0: never removed), Findley, Lai & Onaran (1976) Ch. 5. */
double palp_burgers_creep(double E1, double eta1, double E2, double eta2, double sigma0, double t1, double t);

#endif
