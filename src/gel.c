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

double palp_gel_literal_step(const palp_gel_params *g, double p, double p_prev, double V, double V_prev, double h,
                             int damping) {
  /* F_i = F_{i-1} - F_{i-1} a1 (V_i - V_{i-1}) / V_{i-1} - a2 V/dt + a3 Fdot/dt with
   * "V" read as the frame's volume change and Fdot = (F_{i-1} - F_{i-2}) / dt. */
  const double dV = V - V_prev;
  double pn = p - p * g->a1 * dV / V_prev;
  if (damping) pn -= g->a2 * dV / h;
  pn += g->a3 * (p - p_prev) / (h * h);
  return pn;
}
