/*
 * finger.h - the pure pieces of the fingertip contact (internal; docs/haptics.md):
 * sphere-triangle proximity, the contact LCP and the contact stiffness. world.c
 * owns the state and calls these from its "fingers" stage.
 */
#ifndef PALP_FINGER_H
#define PALP_FINGER_H

#include "palp.h"

/* Closest point of triangle (a, b, c) to p, with its barycentric weights
 * (Ericson, Real-Time Collision Detection, 5.1.5). */
palp_vec3 palp_tri_closest(palp_vec3 p, palp_vec3 a, palp_vec3 b, palp_vec3 c, double bary[3]);

/* Solves the linear complementarity problem
 *   g = b + W lambda >= 0,  lambda >= 0,  g_i lambda_i = 0
 * for a symmetric positive semi-definite m x m W (row-major) by projected
 * Gauss-Seidel from the given lambda (warm start). Stops when every residual
 * (min(g_i, lambda_i) scaled to a length by W_ii) is below tol [m] or after
 * max_iter sweeps. Returns the sweeps used, or -1 if it did not converge. */
int palp_lcp_pgs(int m, const double *W, const double *b, double *lambda, int max_iter, double tol);

/* The same LCP by an active-set method (Lawson-Hanson on the equivalent bound-
 * constrained quadratic program), exact up to round-off, warm-started from lambda.
 * work needs m*m + 3*m doubles. Returns the iterations used or -1. */
int palp_lcp_solve(int m, const double *W, const double *b, double *lambda, double *work);

/* K = N_A (W_AA + eps I)^{-1} N_A^T [N/m] over the active contacts (lambda > 0),
 * n[i] the unit normals, W [m/N] row-major m x m: the finger's stiffness with the
 * active set held. work needs m*m + 3*m doubles. Returns the active count. */
int palp_contact_stiffness(int m, const double *W, const palp_vec3 *n, const double *lambda, double K[3][3],
                           double *work);

#endif
