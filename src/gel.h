/*
 * gel.h - the inside gel: volume by the divergence theorem and the pressure law
 * (Eqs. 2-3 of the paper; the reading is argued in docs/model.md). Internal.
 */
#ifndef PALP_GEL_H
#define PALP_GEL_H

#include "palp.h"

/* V = sum_t x_a . (x_b x x_c) / 6 [m^3] over the dome triangles, and its gradient
 * g_i = dV/dx_i = sum_{t (i,j,k) ccw} (x_j x x_k) / 6 [m^2] at every vertex. */
double palp_gel_volume_gradient(const palp_mesh *m, const palp_vec3 *pos, palp_vec3 *grad);

/* Polytropic state: gauge pressure p = P [(V0/V)^a1 - 1] [Pa] and dp/dV [Pa/m^3]. */
double palp_gel_polytropic(const palp_gel_params *g, double V0, double V, double *dp_dV);

/* Literal Eq. 3, one frame: absolute pressures [Pa] p (frame i-1), p_prev (i-2),
 * volumes [m^3] V (frame i) and V_prev (i-1), this frame's step h [s] and the last
 * one's h_prev [s] (the momentum term is a3 (p - p_prev) / (h h_prev)). Returns p_i.
 * *dropped is 1 outside palp_gel_literal_valid (palp.h), where the momentum term would
 * amplify every change of pressure and is left out (docs/model.md), else 0. */
double palp_gel_literal_step(const palp_gel_params *g, double p, double p_prev, double V, double V_prev,
                             double h, double h_prev, int damping, int *dropped);

#endif
