/* A single Burgers link (Eq. 1): under a step stress the model's exponential update
 * reproduces the closed-form creep and recovery of Findley, Lai & Onaran (1976) and
 * converges at second order in the step; under imposed strain (as in the world) it
 * is exact for piecewise-linear strain even when a time constant is 100x shorter
 * than the step. */
#include "burgers.h"
#include "check.h"
#include "palp.h"

/* The closed form of Findley, Lai & Onaran (1976) for a Burgers body (Maxwell E1, eta1 in series
 * with Kelvin E2, eta2) under a stress step s0 held to t1, written here and not taken from the
 * library (src/burgers.c's palp_burgers_creep is code under test, compared with this below):
 *   eps(t) = s0/E1 + s0 t/eta1 + s0/E2 (1 - e^{-t E2/eta2})                   t <= t1 (creep)
 *   eps(t) = s0 t1/eta1 + s0/E2 (1 - e^{-t1 E2/eta2}) e^{-(t - t1) E2/eta2}   t > t1 (recovery:
 *            the elastic s0/E1 back at once, the dashpot's flow kept, the Kelvin strain decaying) */
static double findley(double E1, double eta1, double E2, double eta2, double s0, double t1, double t) {
  const double tau = eta2 / E2; /* [s] the Kelvin element's retardation time */
  if (t <= t1) return s0 / E1 + s0 * t / eta1 + s0 / E2 * (1.0 - exp(-t / tau));
  return s0 * t1 / eta1 + s0 / E2 * (1.0 - exp(-t1 / tau)) * exp(-(t - t1) / tau);
}

/* Runs stress sigma(t) = s0 for t < t1, 0 after, and returns the largest strain
 * error against the closed form over [0, T], relative to the peak strain. */
static double creep_error(double E1, double eta1, double E2, double eta2, double h, double t1, double T) {
  palp_burgers b;
  if (palp_burgers_init(&b, E1, eta1, E2, eta2, h)) return INFINITY;
  const double s0 = 1.0e4; /* [Pa] */
  double x[2] = {0.0, 0.0}, eps = 0.0, worst = 0.0, peak = 0.0;
  const long n = lround(T / h);
  /* The step of stress at t = 0 is elastic: eps(0+) = s0 / E1, no flow yet. */
  eps = s0 / E1;
  for (long k = 0; k < n; ++k) {
    const double t = (k + 1) * h;
    const double s = (t <= t1 + 1e-12) ? s0 : 0.0;
    /* At removal the stress drops at once: impose the elastic jump first. */
    if (fabs(t - h - t1) < 1e-12) eps -= s0 / E1;
    /* sigma_{n+1} = E1 (eps' - x1' - x2'), x' = Phi x + g0 eps + g1 eps'  =>  solve for eps'. */
    const double px = (b.phi[0][0] + b.phi[1][0]) * x[0] + (b.phi[0][1] + b.phi[1][1]) * x[1];
    const double epsn = (s / E1 + px + (b.g0[0] + b.g0[1]) * eps) / (1.0 - b.g1[0] - b.g1[1]);
    const double sig = palp_burgers_advance(&b, x, eps, epsn);
    eps = epsn;
    if (fabs(sig - s) > 1e-9 * s0) return INFINITY; /* the update must return the imposed stress */
    const double ref = findley(E1, eta1, E2, eta2, s0, t1, t);
    if (fabs(ref) > peak) peak = fabs(ref);
    if (fabs(eps - ref) > worst) worst = fabs(eps - ref);
  }
  return worst / peak;
}

static double ramp(double t) { return 1e-3 * fmin(t / 0.02, 1.0); } /* imposed strain [-] */

static double strain_driven_error(double E1, double eta1, double E2, double eta2, double h) {
  palp_burgers b;
  if (palp_burgers_init(&b, E1, eta1, E2, eta2, h)) return INFINITY;
  const double a = E1 / eta1, e = E1 / eta2, c = (E1 + E2) / eta2; /* [1/s] */
  double x[2] = {0, 0}, y[2] = {0, 0}, worst = 0.0, peak = 0.0;
  const int sub = (int)lround(h / 5e-7);
  const double hh = h / sub;
  for (int k = 0; k < 20; ++k) {
    const double t0 = k * h;
    const double sig = palp_burgers_advance(&b, x, ramp(t0), ramp(t0 + h));
    for (int j = 0; j < sub; ++j) {
      const double t = t0 + j * hh;
#define RHS(yy, tt, out) \
  (out)[0] = -a * (yy)[0] - a * (yy)[1] + a * ramp(tt), (out)[1] = -e * (yy)[0] - c * (yy)[1] + e * ramp(tt)
      double k1[2], k2[2], k3[2], k4[2], yt[2];
      RHS(y, t, k1);
      yt[0] = y[0] + 0.5 * hh * k1[0], yt[1] = y[1] + 0.5 * hh * k1[1];
      RHS(yt, t + 0.5 * hh, k2);
      yt[0] = y[0] + 0.5 * hh * k2[0], yt[1] = y[1] + 0.5 * hh * k2[1];
      RHS(yt, t + 0.5 * hh, k3);
      yt[0] = y[0] + hh * k3[0], yt[1] = y[1] + hh * k3[1];
      RHS(yt, t + hh, k4);
#undef RHS
      y[0] += hh / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]);
      y[1] += hh / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]);
    }
    const double ref = E1 * (ramp(t0 + h) - y[0] - y[1]);
    peak = fmax(peak, fabs(ref));
    worst = fmax(worst, fabs(sig - ref));
  }
  return worst / peak;
}

int main(void) {
  /* Default membrane parameters: E1 = 4.2 MPa, eta1 = 2e8 Pa s, E2 = 8 MPa,
   * eta2 = 8e5 Pa s (Kelvin retardation 0.1 s); load 2 s, then 2 s free. */
  const double E1 = 4.2e6, eta1 = 2e8, E2 = 8e6, eta2 = 8e5;
  const double e10 = creep_error(E1, eta1, E2, eta2, 0.01, 2.0, 4.0);
  const double e5 = creep_error(E1, eta1, E2, eta2, 0.005, 2.0, 4.0);
  const double e1 = creep_error(E1, eta1, E2, eta2, 0.001, 2.0, 4.0);
  printf("creep-recovery error vs closed form: %.3e (10 ms), %.3e (5 ms), %.3e (1 ms)\n", e10, e5, e1);
  CHECK(e10 < 1e-2, "10 ms step within 1%% of the peak strain (%.3e)", e10);
  CHECK(e1 < 1e-4, "1 ms step within 0.01%% of the peak strain (%.3e)", e1);
  /* Linear-in-step strain makes the update second order: halving h cuts the error ~4x. */
  CHECK(e5 < e10 / 3.0, "second-order convergence: %.3e -> %.3e", e10, e5);

  /* Fast time constants, driven as the world drives them (strain imposed, stress
   * out): a strain ramp to 1e-3 over 20 ms (two steps), then held, at a 10 ms step. The
   * reference integrates dx/dt = A x + b eps(t) with classical RK4 at 0.5 us steps
   * (an independent implementation). The update must match to 1e-6 of the peak
   * stress even when a time constant is 100x shorter than the step, where explicit
   * Euler would diverge. */
  const double cases[3][4] = {{E1, eta1, E2, eta2}, {E1, eta1, E2, 8e2 /* Kelvin 0.1 ms */},
                              {E1, 4.2e3 /* Maxwell 1 ms */, E2, eta2}};
  for (int c = 0; c < 3; ++c) {
    const double e = strain_driven_error(cases[c][0], cases[c][1], cases[c][2], cases[c][3], 0.01);
    printf("strain-driven ramp and hold, case %d: max stress error %.3e of peak\n", c, e);
    CHECK(e < 1e-6, "case %d: exact for piecewise-linear strain at a 10 ms step (%.3e)", c, e);
  }

  /* Eq. 1 itself: strain rate after the elastic jump, deps/dt(0+) = s0/eta1 + s0/eta2,
   * from the closed form by a forward difference. */
  const double s0 = 1e4, dt = 1e-7;
  const double rate = (findley(E1, eta1, E2, eta2, s0, 10.0, 2 * dt) - findley(E1, eta1, E2, eta2, s0, 10.0, dt)) / dt;
  CHECK_NEAR(rate, s0 / eta1 + s0 / eta2, 1e-3 * (s0 / eta2), "initial creep rate s0/eta1 + s0/eta2 [1/s]");
  /* The library's closed form (used by tools and docs) is the same curve: creep and recovery, 1 ms
   * to 4 s, within 1e-12 of the peak strain. */
  double lib_worst = 0.0, lib_peak = 0.0;
  for (int k = 1; k <= 4000; ++k) {
    const double t = 1e-3 * k, ref = findley(E1, eta1, E2, eta2, s0, 2.0, t);
    lib_peak = fmax(lib_peak, fabs(ref));
    lib_worst = fmax(lib_worst, fabs(palp_burgers_creep(E1, eta1, E2, eta2, s0, 2.0, t) - ref));
  }
  CHECK(lib_worst <= 1e-12 * lib_peak, "palp_burgers_creep is the Findley closed form (worst %.3e of peak %.3e)",
        lib_worst, lib_peak);

  palp_burgers b;
  CHECK(palp_burgers_init(&b, -1, eta1, E2, eta2, 0.01) == PALP_EINVAL, "negative modulus rejected");
  CHECK(palp_burgers_init(&b, E1, eta1, E2, eta2, 0.0) == PALP_EINVAL, "zero step rejected");
  CHECK_DONE();
}
