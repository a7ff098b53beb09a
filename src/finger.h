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

/* The eigen-decomposition of a symmetric 3x3 K (cyclic Jacobi, to round-off): K = V diag(lambda)
 * V^T, lambda[e] the eigenvalue of column e of V (orthonormal), in no particular order. Pure. */
void palp_sym3_eig(const double K[3][3], double lambda[3], double V[3][3]);

/* K^+ r for a symmetric positive semi-definite 3x3 K (cyclic Jacobi; eigenvalues at or
 * below rel_tol of the largest are taken as zero, so r's part outside K's range is
 * dropped): the motion that K turns into the force r, where K can turn any into it. */
palp_vec3 palp_sym3_pinv_apply(const double K[3][3], palp_vec3 r, double rel_tol);

/* The drift of the local contact model (palp.h, docs/haptics.md "The drift observer").
 * A model says F(x, t) = F_m - K (x - x_m - d (t - t_m)); d is the surface's own motion
 * at the contact. The step's surface velocity v there overstates it on a phantom that
 * yields to the finger within a step: v is mostly the dent the device's own motion
 * made, which K already counts, so a model extrapolated by v lost to a held force
 * (rendered at 1 kHz from 250 Hz, RMS 4.7% of the peak on breast tissue against 3.6%
 * held). So d = v + c, with c an observer's correction from how well the last model
 * predicted this step's force F at this step's device point x:
 *   e = F - (F' - K' (x - x' - d' h)),   c <- c + g K^+ e / h   [m/s],
 * primes for the last model, h the step [s], g = PALP_DRIFT_GAIN. c starts at 0 at
 * first touch, when there is no last model. K^+ inverts every direction above 1e-6 of
 * K's largest stiffness, so an error along a direction K barely resists (a fingertip
 * deep in the exercise dome: ~0.002 N/m against ~1,000 N/m) could drive c to ~100 m/s,
 * which is no surface's motion (the world caps its vertices at def.max_speed) and which
 * the station refuses as a corrupt model (|d| > 100 m/s; 12-74 of a 123 s strip
 * search's 30,700 models were). So |d| is capped at max_speed [m/s]: along that
 * direction K is so soft that the cap moves the model's force by < 1e-3 N. Returns d
 * and updates *c. */
#define PALP_DRIFT_GAIN 0.2
palp_vec3 palp_drift_observe(const palp_local_model *last, const palp_local_model *now, palp_vec3 v, double h,
                             double max_speed, palp_vec3 *c);

/* ---- the smooth contact surface (docs/haptics.md, "The smooth contact surface") ----
 * The dome's triangles are chords of the tissue's surface: between vertices a flat facet
 * lies up to 0.13-0.27 mm inside its sphere (338 vertices). The fingertip may instead
 * meet a Phong tessellation of each triangle (Boubekeur & Alexa 2008) built from per-
 * vertex normals N_i:
 *   S(b) = sum_i b_i x_i + o(b),   o(b) = -alpha sum_i b_i ((P(b) - X_i) . N_i) N_i
 *        = -alpha sum_ij b_i b_j d_ij N_i,   d_ij = (X_j - X_i) . N_i [m],
 * x the current and X the rest positions, P(b) = sum_j b_j X_j, b the barycentric
 * weights. On a sphere of radius R with its own normals, sum_i b_i ((P - X_i) . N_i) N_i
 * ~ -(R^2 - |P|^2) / R N ~ -2 s N to leading order (s the chord's sag), so alpha = 1/2
 * puts the patch on the sphere (the paper's visual 3/4 would bulge by half the sag): at
 * 338 vertices within 2.7 um of it, its normal within 0.12 deg of the sphere's
 * (tests/model/test_finger_surface.c). The offset is exact at rest and carried with the
 * deformation: the d_ij are the rest ones, and each vertex's normal turns with its ring
 * of triangles (palp_normal_carry), one normal per vertex, so along an edge S depends on
 * that edge's two vertices only and neighbouring patches meet, deformed or not; their
 * tangent planes agree to the normals' error, not to the facets' tilt (~5 deg). */
#define PALP_PHONG_ALPHA 0.5

typedef struct palp_smooth_patch {
  double d[3][3]; /* d_ij = (X_j - X_i) . N_i at rest [m], d_ii = 0 */
} palp_smooth_patch;

/* Rest normals of a mesh's vertices (unit): the sphere's own, X / |X|, when every rest
 * vertex lies on one sphere about the base centre (the hemispheres palp_mesh_create
 * builds); otherwise the angle-weighted normals of the dome triangles (Thuermer &
 * Wuethrich 1998). */
void palp_rest_normals(const palp_mesh *mesh, palp_vec3 *normals);

/* The patch of triangle (X0, X1, X2) with rest normals N0..N2. 0, or -1 if degenerate. */
int palp_smooth_patch_init(palp_smooth_patch *sp, const palp_vec3 X[3], const palp_vec3 N[3]);

/* A bound on |o(b)| over the patch for any unit normals [m] (pruning). */
double palp_smooth_patch_max_offset(const palp_smooth_patch *sp, const palp_vec3 X[3], const palp_vec3 N[3]);

/* A vertex's rest normal n_rest turned by the rotation that takes its ring's rest normal
 * m_rest to its current one m_now (both unit): the least rotation, about m_rest x m_now. */
palp_vec3 palp_normal_carry(palp_vec3 n_rest, palp_vec3 m_rest, palp_vec3 m_now);

/* The patch point S(b) over the current triangle (a, b, c) with the vertices' current
 * normals N, and its tangents dS/db_1, dS/db_2 (b_0 = 1 - b_1 - b_2) [m]. */
palp_vec3 palp_smooth_point(const palp_smooth_patch *sp, palp_vec3 a, palp_vec3 b, palp_vec3 c, const palp_vec3 N[3],
                            const double bary[3], palp_vec3 *t1, palp_vec3 *t2);

/* Closest point to p of the patch over the current triangle (a, b, c), with its
 * barycentric weights (exact zeros on an edge or at a vertex, as palp_tri_closest) and
 * the patch's outward unit normal there. On entry bary holds the flat facet's closest
 * point's weights, as palp_tri_closest(p, a, b, c, bary) gives them (the caller has
 * them already: its pruning needs the facet's point). Two Gauss-Newton steps from that
 * point, each the closest point of the patch's tangent-plane triangle at the
 * current weights (so the weights stay in the triangle); each step cuts the error of
 * the point by about |p - S| / (radius of curvature), ~0.2 for an 8 mm tip on a 40 mm
 * dome, and the distance's error is second order in it: from <= 0.7 mm on the facet,
 * 0.03 mm of point after two steps, ~1e-7 m of distance. */
palp_vec3 palp_smooth_closest(palp_vec3 p, palp_vec3 a, palp_vec3 b, palp_vec3 c, const palp_vec3 N[3],
                              const palp_smooth_patch *sp, double bary[3], palp_vec3 *normal);

#endif
