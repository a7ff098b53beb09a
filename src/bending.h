/* bending.h - the skin's bending stiffness as linearised hinges (internal; docs/model.md).
 *
 * A thin plate of bending stiffness D = E t^3 / (12 (1 - nu^2)) [N m] resists the
 * change of the dihedral angle at each edge shared by two triangles (a hinge):
 *   E_b = sum_e k_e dtheta_e^2 / 2,   k_e = D |e|^2 / A_e   [N m],
 * A_e the two triangles' area. On an equilateral lattice this is the plate's energy
 * D kappa^2 / 2 per unit area for cylindrical bending in any direction, and
 * D (1 + nu) kappa^2 with nu = -1/3 for spherical bending (tests/model/test_bending.c):
 * the plate equation's D laplacian^2 w = p is D's alone, the Poisson ratio only
 * weighs the Gaussian curvature, which matters at free edges (the dome has none).
 * The angle is linearised about the rest shape, dtheta_e = sum_k g_k . u_k with the
 * rest gradients g_k and u the displacement, so the stiffness matrix
 * K_b = sum_e k_e g g^T is constant: it enters the implicit factor once, and the rest
 * shape (the dome's own curvature) carries no bending stress. Valid while the
 * linear angle stays close to the true one (PALP_HINGE_LINEAR_ERR_MAX); a world
 * counts the steps beyond it. */
#ifndef PALP_BENDING_H
#define PALP_BENDING_H

#include "palp.h"

/* The linearised angle's valid range, by its own error: a step counts as beyond it
 * when a hinge's linear turn sum_k g_k . u_k misses the true turn (palp_hinge_angle
 * now minus at rest) by more than this [rad]. The hinge's turn alone is no guide:
 * the error comes mostly from the hinge's rigid rotation (the flanks of a dent tilt),
 * so it is 0.05 rad at a 0.52 rad turn 70 deg from the pole but 0.11 rad at a 0.55
 * rad turn at the pole; and hinges turned by under 0.2 rad were seen off by 0.5 rad
 * near the rim (docs/model.md, "Valid range"). At 0.1 rad on the shipped domes the
 * bending energy is 10-13% below the true angle's, and the fingertip force moves by
 * 0.18-0.27% per % of D, so the force is off by about 3%: a fifth of the 15-22%
 * compliance a hand can discriminate. A parameter set whose fingertip was validated
 * against the FE deeper may state the larger miss those presses reached
 * (palp_world_def.validated_hinge_error, breast tissue 0.344 rad); the world then counts
 * from that. */
#define PALP_HINGE_LINEAR_ERR_MAX 0.1

/* The true angles cost an atan2 each, ~1,000 hinges at 338 vertices, so each step
 * checks its share of the hinges in turn, all of them once per this much simulated
 * time [s]: ~5,000 angles per simulated second whatever the physics rate (+0.6 us on
 * a 250 Hz step of ~46 us), and a step counts beyond the range while any hinge's
 * latest check found it so: flagged and cleared within 0.2 s. */
#define PALP_HINGE_CHECK_PERIOD 0.2

/* The dihedral angle [rad] at edge (a, b) between triangle (a, b, c) and triangle
 * (b, a, d), signed, zero when flat: atan2((n2 x n1) . e^, n1 . n2). */
double palp_hinge_angle(palp_vec3 a, palp_vec3 b, palp_vec3 c, palp_vec3 d);

/* Its gradient [1/m] with respect to a, b, c, d, in g[0..3] (Bridson et al. 2003:
 * the wings move along their triangles' normals, the edge ends share the rest). The
 * four sum to zero (a translation turns no hinge). Returns -1 for a degenerate hinge
 * (a triangle of zero area or an edge of zero length), 0 otherwise. */
int palp_hinge_gradient(palp_vec3 a, palp_vec3 b, palp_vec3 c, palp_vec3 d, palp_vec3 g[4]);

/* k_e = D |e|^2 / A_e [N m] for bending stiffness D [N m], the edge's length
 * squared |e|^2 [m^2] and the two triangles' area A_e [m^2]. */
double palp_hinge_stiffness(double D, double edge_len2, double area_sum);

#endif
