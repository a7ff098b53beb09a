/*
 * test_gel_literal.c - the paper's literal gel law (PALP_GEL_PAPER_LITERAL, docs/model.md,
 * "Steps of other lengths, and where a3 is stable") at steps other than def.dt.
 *
 * The momentum term is a3 (p_{i-1} - p_{i-2}) / (h_i h_{i-1}), stable for
 * -1/2 < a3 / (h_i h_{i-1}) < 1; a frame outside leaves it out and is counted
 * (health.gel_momentum_dropped). Asserted:
 *  - one frame of the law against hand-computed pressures (to 1e-9 Pa): at a fixed step,
 *    after a longer step (h_prev enters), outside the range (the term left out), and
 *    the a1 and a2 terms;
 *  - the range's edges (palp_gel_literal_valid, palp_gel_literal_min_step) and the
 *    world's refusal of a dt outside it: a3 = -0.51 dt^2 (accepted before, and it rang);
 *  - on the default phantom with this law: a3 = 0.2 dt^2 under 10 N and 1 N on one vertex
 *    (halved steps) stays within 1.5x the peak gauge pressure of a3 = 0 (the momentum
 *    adds at most c / (1 - c) = 25% to an excursion at c = 0.2; before: 2.07e8 Pa against
 *    3.6e3 Pa at 10 N), and counts the frames it left the range;
 *  - a3 = 0.9 dt^2 stepped at dt/2 (c = 3.6 every frame) is the law without a3, bit for
 *    bit (state hashes equal to a3 = 0 after every step), every frame counted (before: it
 *    failed within 16 steps);
 *  - h_prev is the last frame's own length: dt then dt/2 (c = 2 a3 / dt^2) keeps the term
 *    for a3 = 0.3 dt^2, the next dt/2 (c = 4 a3 / dt^2 = 1.2) leaves it out.
 */
#include <math.h>
#include <stdio.h>

#include "check.h"
#include "gel.h"
#include "palp.h"

static void test_frame(void) {
  palp_gel_params g = {0};
  g.a1 = 10.0, g.a2 = 5e6, g.a3 = 2e-5; /* a3 = 0.2 (10 ms)^2 */
  const double V = 1e-4; /* [m^3] */
  int dropped = -1;
  /* fixed 10 ms step, no volume change: p + a3 (p - p_prev) / h^2 = 102325 + 0.2 * 1000 */
  double p = palp_gel_literal_step(&g, 102325.0, 101325.0, V, V, 0.01, 0.01, 1, &dropped);
  CHECK_NEAR(p, 102525.0, 1e-9, "fixed step: the momentum term");
  CHECK(dropped == 0, "fixed step: kept");
  /* 5 ms after 10 ms: a3 / (h h_prev) = 2e-5 / 5e-5 = 0.4 (a3 / h^2 = 0.8 was used before) */
  p = palp_gel_literal_step(&g, 102325.0, 101325.0, V, V, 0.005, 0.01, 1, &dropped);
  CHECK_NEAR(p, 102725.0, 1e-9, "5 ms after 10 ms: the change over the last frame's own length");
  CHECK(dropped == 0, "5 ms after 10 ms: kept");
  /* 2.5 ms after 5 ms: 2e-5 / 1.25e-5 = 1.6, outside: the term is left out */
  p = palp_gel_literal_step(&g, 102325.0, 101325.0, V, V, 0.0025, 0.005, 1, &dropped);
  CHECK_NEAR(p, 102325.0, 1e-9, "2.5 ms after 5 ms: the momentum term left out");
  CHECK(dropped == 1, "2.5 ms after 5 ms: dropped (%d)", dropped);
  /* negative a3 = -0.6 (10 ms)^2 at 10 ms: c = -0.6 < -1/2, left out */
  g.a3 = -6e-5;
  p = palp_gel_literal_step(&g, 102325.0, 101325.0, V, V, 0.01, 0.01, 1, &dropped);
  CHECK(p == 102325.0 && dropped == 1, "a3 = -0.6 dt^2: left out (%.9g, %d)", p, dropped);
  /* the a1 and a2 terms: V shrinks by 1e-3 of V_prev over 10 ms, p = p_prev = 101325:
   * p - p a1 dV / V_prev - a2 dV / h = 101325 + 1013.25 + 50 */
  g.a3 = 0.0;
  const double Vn = V - 1e-7;
  p = palp_gel_literal_step(&g, 101325.0, 101325.0, Vn, V, 0.01, 0.01, 1, &dropped);
  CHECK_NEAR(p, 102388.25, 1e-9, "a1 and a2 terms");
  p = palp_gel_literal_step(&g, 101325.0, 101325.0, Vn, V, 0.01, 0.01, 0, &dropped);
  CHECK_NEAR(p, 102338.25, 1e-9, "a1 term, no damping");
  CHECK(dropped == 0, "a3 = 0 is always in range");
}

static void test_range(void) {
  const double h = 0.01, hh = h * h;
  CHECK(palp_gel_literal_valid(0.999 * hh, h, h) && !palp_gel_literal_valid(hh, h, h), "upper edge a3 < h^2");
  CHECK(palp_gel_literal_valid(-0.49 * hh, h, h) && !palp_gel_literal_valid(-0.5 * hh, h, h) &&
            !palp_gel_literal_valid(-0.51 * hh, h, h),
        "lower edge a3 > -h^2 / 2");
  CHECK(palp_gel_literal_valid(0.0, 1e-9, 1e-9) && !palp_gel_literal_valid(NAN, h, h), "a3 = 0 anywhere; NaN nowhere");
  CHECK(palp_gel_literal_valid(0.3 * hh, 0.5 * h, h) && !palp_gel_literal_valid(0.3 * hh, 0.5 * h, 0.5 * h),
        "h h_prev, not h^2: 0.3 h^2 at h/2 after h (0.6) but not after h/2 (1.2)");
  CHECK_NEAR(palp_gel_literal_min_step(1e-4), 0.01, 1e-15, "min step for a3 = 1e-4 s^2");
  CHECK_NEAR(palp_gel_literal_min_step(-2e-4), 0.02, 1e-15, "min step for a3 = -2e-4 s^2 (h^2 > 2 |a3|)");
  CHECK(palp_gel_literal_min_step(0.0) == 0.0, "min step for a3 = 0");
  /* the world refuses a dt outside, accepts one inside */
  const double fr[4] = {0.99, 1.0, -0.49, -0.51};
  const int ok[4] = {1, 0, 1, 0};
  for (int q = 0; q < 4; ++q) {
    palp_world_def d = palp_world_default_def();
    d.gel.law = PALP_GEL_PAPER_LITERAL;
    d.gel.a3 = fr[q] * d.dt * d.dt;
    int e = 0;
    palp_world *w = palp_world_create(&d, &e);
    CHECK((w != NULL) == ok[q] && (ok[q] || e == PALP_EINVAL), "a3 = %.2f dt^2: %s (err %d)", fr[q],
          ok[q] ? "accepted" : "refused", e);
    palp_world_destroy(w);
  }
}

/* The default phantom with the literal law and a3 = a3f dt^2, F [N] down on the pole
 * vertex, `steps` steps of hf dt each: the peak |gauge pressure| [Pa]; health to *hl; the
 * state hash after each step to hashes (when not NULL); the first error to *err. */
static double run(double a3f, double F, int steps, double hf, palp_world_health *hl, unsigned long long *hashes,
                  int *err) {
  palp_world_def d = palp_world_default_def();
  d.gel.law = PALP_GEL_PAPER_LITERAL;
  d.gel.a3 = a3f * d.dt * d.dt;
  int e = 0;
  palp_world *w = palp_world_create(&d, &e);
  *err = e;
  if (!w) return NAN;
  const palp_contact_def cd = palp_contact_default_def(PALP_DIST_SINGLE, (palp_vec3){0, 0, d.mesh.radius});
  const int c = palp_world_add_contact(w, &cd);
  palp_world_set_contact_force(w, c, (palp_vec3){0, 0, -F});
  double peak = 0.0;
  for (int k = 0; k < steps && !*err; ++k) {
    *err = palp_world_step_dt(w, hf * d.dt);
    const double p = fabs(palp_world_pressure(w));
    if (!(p <= peak)) peak = p; /* a NaN is kept */
    if (hashes) hashes[k] = (unsigned long long)palp_world_hash(w);
  }
  palp_world_get_health(w, hl);
  palp_world_destroy(w);
  return peak;
}

static void test_halved_steps(void) {
  const double Fs[2] = {10.0, 1.0};
  for (int q = 0; q < 2; ++q) {
    palp_world_health h0, h2;
    int e0 = 0, e2 = 0;
    const double p0 = run(0.0, Fs[q], 300, 1.0, &h0, NULL, &e0);
    const double p2 = run(0.2, Fs[q], 300, 1.0, &h2, NULL, &e2);
    printf("literal law, %.0f N on one vertex, 300 steps of 10 ms: peak gauge %.4g Pa with a3 = 0.2 dt^2 (%lld halved "
           "steps, %lld frames without the momentum term), %.4g Pa with a3 = 0\n",
           Fs[q], p2, (long long)h2.substeps, (long long)h2.gel_momentum_dropped, p0);
    CHECK(e0 == 0 && e2 == 0, "%.0f N: every step succeeds (%d, %d)", Fs[q], e0, e2);
    CHECK(h2.substeps > 0, "%.0f N: the load makes halved steps (%lld): the test measures something", Fs[q],
          (long long)h2.substeps);
    CHECK(p2 <= 1.5 * p0, "%.0f N: peak gauge pressure %.4g Pa within 1.5x that of a3 = 0 (%.4g Pa)", Fs[q], p2, p0);
    CHECK(h2.gel_momentum_dropped > 0, "%.0f N: frames outside the range counted (%lld)", Fs[q],
          (long long)h2.gel_momentum_dropped);
    CHECK(h0.gel_momentum_dropped == 0, "a3 = 0 never leaves the range");
  }
}

static void test_short_steps(void) {
  enum { N = 300 };
  static unsigned long long ha[N], hb[N];
  palp_world_health h0, h9;
  int e0 = 0, e9 = 0;
  const double p0 = run(0.0, 10.0, N, 0.5, &h0, ha, &e0);
  const double p9 = run(0.9, 10.0, N, 0.5, &h9, hb, &e9);
  int same = e0 == 0 && e9 == 0;
  for (int k = 0; k < N && same; ++k) same = ha[k] == hb[k];
  printf("literal law stepped at dt/2, a3 = 0.9 dt^2 (c = 3.6): %s, peak gauge %.4g Pa (a3 = 0: %.4g Pa); %lld frames "
         "without the momentum term of %d steps + %lld halvings\n",
         same ? "the a3 = 0 state bit for bit after every step" : "differs from a3 = 0", p9, p0,
         (long long)h9.gel_momentum_dropped, N, (long long)h9.substeps);
  CHECK(e0 == 0 && e9 == 0, "every step succeeds (%d, %d)", e0, e9);
  CHECK(same, "a3 = 0.9 dt^2 at dt/2 is the law without a3: equal state hashes after every step (tolerance 0)");
  CHECK(h9.gel_momentum_dropped == N + h9.substeps, "every frame counted: %lld of %lld",
        (long long)h9.gel_momentum_dropped, (long long)(N + h9.substeps));
}

static void test_prev_step(void) {
  palp_world_def d = palp_world_default_def();
  d.gel.law = PALP_GEL_PAPER_LITERAL;
  d.gel.a3 = 0.3 * d.dt * d.dt;
  int e = 0;
  palp_world *w = palp_world_create(&d, &e);
  CHECK(w != NULL, "world: %d", e);
  if (!w) return;
  const palp_contact_def cd = palp_contact_default_def(PALP_DIST_GAUSSIAN, (palp_vec3){0, 0, d.mesh.radius});
  const int c = palp_world_add_contact(w, &cd);
  palp_world_set_contact_force(w, c, (palp_vec3){0, 0, -0.05}); /* light: no halved step */
  const double h[3] = {d.dt, 0.5 * d.dt, 0.5 * d.dt};
  const long long want[3] = {0, 0, 1}; /* c = 0.3 (after the creation's dt), 0.6, 1.2 */
  for (int k = 0; k < 3; ++k) {
    CHECK(palp_world_step_dt(w, h[k]) == 0, "step %d", k);
    palp_world_health hl;
    palp_world_get_health(w, &hl);
    CHECK(hl.substeps == 0 && hl.gel_momentum_dropped == want[k],
          "after step %d (%.1f ms): %lld frames without the term, want %lld (halved steps %lld, want 0)", k,
          h[k] * 1e3, (long long)hl.gel_momentum_dropped, want[k], (long long)hl.substeps);
  }
  palp_world_destroy(w);
}

int main(void) {
  test_frame();
  test_range();
  test_halved_steps();
  test_short_steps();
  test_prev_step();
  CHECK_DONE();
}
