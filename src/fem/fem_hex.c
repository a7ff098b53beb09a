/*
 * fem_hex.c - the trilinear 8-node hexahedron (Abaqus C3D8 node order).
 *
 * Natural coordinates of the nodes: 1 (-1,-1,-1), 2 (1,-1,-1), 3 (1,1,-1),
 * 4 (-1,1,-1), 5..8 the same at xi3 = +1. Integration is 2x2x2 Gauss, which is
 * exact for the reference and current volumes of a trilinear hex (det of the
 * Jacobian is at most quadratic in each natural coordinate).
 */
#include <math.h>

#include "fem_internal.h"

static const double node_xi[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                     {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

#define GP 0.57735026918962576451 /* 1 / sqrt(3) */
const double palp_fem_gauss[8][3] = {{-GP, -GP, -GP}, {GP, -GP, -GP}, {GP, GP, -GP}, {-GP, GP, -GP},
                                     {-GP, -GP, GP},  {GP, -GP, GP},  {GP, GP, GP},  {-GP, GP, GP}};

/* N_a = (1 + xi xi_a)(1 + eta eta_a)(1 + zeta zeta_a) / 8 */
void palp_fem_hex_dshape(const double xi[3], double dN[8][3]) {
  for (int a = 0; a < 8; ++a) {
    const double s0 = 1.0 + xi[0] * node_xi[a][0];
    const double s1 = 1.0 + xi[1] * node_xi[a][1];
    const double s2 = 1.0 + xi[2] * node_xi[a][2];
    dN[a][0] = 0.125 * node_xi[a][0] * s1 * s2;
    dN[a][1] = 0.125 * node_xi[a][1] * s0 * s2;
    dN[a][2] = 0.125 * node_xi[a][2] * s0 * s1;
  }
}

double palp_fem_hex_jacobian(const palp_fem_mesh *mesh, int e, int g, double dN[8][3], double J[3][3]) {
  palp_fem_hex_dshape(palp_fem_gauss[g], dN);
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) J[i][k] = 0.0;
  for (int a = 0; a < 8; ++a) {
    const double *x = mesh->x[mesh->hex[e][a]];
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) J[i][k] += x[i] * dN[a][k];
  }
  return J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) - J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
         J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
}

double palp_fem_element_volume(const palp_fem_mesh *mesh, int e) {
  double vol = 0.0;
  for (int g = 0; g < 8; ++g) {
    double dN[8][3], J[3][3];
    vol += palp_fem_hex_jacobian(mesh, e, g, dN, J); /* Gauss weights are 1 */
  }
  return vol;
}
