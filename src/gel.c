/* gel.c - see gel.h and docs/model.md (section "The gel's state equation"). */
#include "gel.h"

#include <math.h>
#include <string.h>

#include "vec3.h"

/* restrict: g is written while p is read, and without it the compiler reloads the
 * positions after every store to g (the same operations, the same bits). An AVX2 clone
 * (its three-operand instructions: ~15% fewer per triangle), static so that the public
 * function stays a plain symbol; no fused multiply-add, so both give the same bits. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
__attribute__((target_clones("avx2", "default")))
#endif
static double volume_gradient(int nv, int nt, const int (*restrict tri)[3], const palp_vec3 *restrict p,
                              palp_vec3 *restrict g) {
  memset(g, 0, sizeof *g * (size_t)nv);
  double v6 = 0.0;
  for (int t = 0; t < nt; ++t) {
    const int a = tri[t][0], b = tri[t][1], c = tri[t][2];
    const palp_vec3 bc = v3_cross(p[b], p[c]);
    v6 += v3_dot(p[a], bc);
    /* d/dx_a [x_a . (x_b x x_c)] = x_b x x_c, and cyclically. */
    g[a] = v3_add(g[a], bc);
    g[b] = v3_add(g[b], v3_cross(p[c], p[a]));
    g[c] = v3_add(g[c], v3_cross(p[a], p[b]));
  }
  for (int i = 0; i < nv; ++i) g[i] = v3_scale(g[i], 1.0 / 6.0);
  return v6 / 6.0;
}

double palp_gel_volume_gradient(const palp_mesh *m, const palp_vec3 *p, palp_vec3 *g) {
  return volume_gradient(m->vertex_count, m->dome_triangle_count, (const int(*)[3])m->tri, p, g);
}

double palp_gel_polytropic(const palp_gel_params *g, double V0, double V, double *dp_dV) {
  /* Eq. 3's a1 term, dp = -a1 p dV / V, integrated exactly: p_abs = P (V0/V)^a1.
   * The outside pressure P balances it at rest, so the gauge pressure is
   * P [(V0/V)^a1 - 1] and the bulk modulus at rest is a1 P. */
  const double r = pow(V0 / V, g->a1);
  if (dp_dV) *dp_dV = -g->a1 * g->pressure * r / V;
  return g->pressure * (r - 1.0);
}

int palp_gel_literal_valid(double a3, double h, double h_prev) {
  /* The momentum term passes c = a3 / (h h_prev) of the last change of pressure on [-].
   * Where the step's implicit solve removes a share s in [0, 1] of the pressure's excess
   * e over its equilibrium (1 where the gel's stiffness dominates the volume mode, 0 where
   * the volume does not respond), e_i = (1 - s + c) e_{i-1} - c e_{i-2}, whose roots lie
   * inside the unit circle (Jury) iff c < 1 and c > s/2 - 1: for every s, -1/2 < c < 1.
   * Outside, the changes grow frame by frame; a halved step (h/2 after h) already doubles
   * c, h/16 makes it 128x. */
  const double hh = h * h_prev; /* [s^2] */
  return a3 < hh && a3 > -0.5 * hh;
}

double palp_gel_literal_min_step(double a3) {
  /* the bound above at h = h_prev: h^2 > a3 for a3 > 0, h^2 > -2 a3 for a3 < 0 [s] */
  return a3 > 0.0 ? sqrt(a3) : sqrt(-2.0 * a3);
}

double palp_gel_literal_step(const palp_gel_params *g, double p, double p_prev, double V, double V_prev, double h,
                             double h_prev, int damping, int *dropped) {
  /* F_i = F_{i-1} - F_{i-1} a1 (V_i - V_{i-1}) / V_{i-1} - a2 V/dt + a3 Fdot/dt with
   * "V" read as the frame's volume change and Fdot = (F_{i-1} - F_{i-2}) / h_prev [Pa/s],
   * the rate over the frame that made that change; "/dt" is this frame's h. At a fixed
   * step this is the printed a3 (F_{i-1} - F_{i-2}) / dt^2, and the same bits. */
  const double dV = V - V_prev;
  double pn = p - p * g->a1 * dV / V_prev;
  if (damping) pn -= g->a2 * dV / h;
  /* outside its stable range the momentum term is left out, and the caller told */
  *dropped = !palp_gel_literal_valid(g->a3, h, h_prev);
  if (!*dropped) pn += g->a3 * (p - p_prev) / (h * h_prev);
  return pn;
}
