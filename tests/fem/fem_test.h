/* fem_test.h - tiny helpers shared by the FEM tests. */
#ifndef FEM_TEST_H
#define FEM_TEST_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fem_internal.h"

static int fem_failures;

#define CHECK(cond, ...)                                                                                         \
  do {                                                                                                           \
    if (!(cond)) {                                                                                               \
      fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);                                                       \
      fprintf(stderr, __VA_ARGS__);                                                                              \
      fprintf(stderr, "\n");                                                                                     \
      fem_failures++;                                                                                            \
    }                                                                                                            \
  } while (0)

/* |a - b| <= tol, with a message naming the quantity and the tolerance. */
#define CHECK_NEAR(a, b, tol, what)                                                                              \
  CHECK(fabs((a) - (b)) <= (tol), "%s: got %.12g, expected %.12g (tolerance %.3g)", what, (double)(a),       \
        (double)(b), (double)(tol))

/* An nx x ny x nz block of hexes on [0,1]^3 [m]; interior nodes jittered by up to
 * `jitter` of a cell (deterministic). No node is fixed; region gel. */
static inline void block_mesh(palp_fem_mesh *m, int nx, int ny, int nz, double jitter) {
  memset(m, 0, sizeof *m);
  m->node_count = (nx + 1) * (ny + 1) * (nz + 1);
  m->element_count = nx * ny * nz;
  m->x = calloc((size_t)m->node_count, sizeof *m->x);
  m->hex = calloc((size_t)m->element_count, sizeof *m->hex);
  m->region = calloc((size_t)m->element_count, 1);
  m->fixed = calloc((size_t)m->node_count, 1);
  unsigned s = 12345u;
#define ID(i, j, k) (((k) * (ny + 1) + (j)) * (nx + 1) + (i))
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        double *x = m->x[ID(i, j, k)];
        x[0] = (double)i / nx, x[1] = (double)j / ny, x[2] = (double)k / nz;
        const int interior = i > 0 && i < nx && j > 0 && j < ny && k > 0 && k < nz;
        for (int d = 0; d < 3; ++d) {
          s = s * 1103515245u + 12345u;
          const double r = ((s >> 8) & 0xffff) / 65535.0 - 0.5;
          const double h = d == 0 ? 1.0 / nx : d == 1 ? 1.0 / ny : 1.0 / nz;
          if (interior) x[d] += 2.0 * jitter * h * r;
        }
      }
  int e = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i, ++e) {
        int *h = m->hex[e];
        h[0] = ID(i, j, k), h[1] = ID(i + 1, j, k), h[2] = ID(i + 1, j + 1, k), h[3] = ID(i, j + 1, k);
        h[4] = ID(i, j, k + 1), h[5] = ID(i + 1, j, k + 1), h[6] = ID(i + 1, j + 1, k + 1), h[7] = ID(i, j + 1, k + 1);
      }
#undef ID
  m->top_node = m->node_count - 1;
}

/* A config with one hyperelastic material everywhere: C10 [Pa], D1 [1/Pa], no Prony. */
static inline palp_fem_config elastic_config(double c10, double d1) {
  palp_fem_config c = palp_fem_default_config();
  c.gel.c10 = c.membrane.c10 = c10;
  c.gel.d1 = c.membrane.d1 = d1;
  c.gel.prony_count = c.membrane.prony_count = 0;
  c.c10_reading = PALP_FEM_C10_LONG_TERM; /* C10 is the relaxed modulus when Prony terms are added */
  c.cache_dir[0] = 0;
  return c;
}

/* Analytic Cauchy stress of the Abaqus Neo-Hookean for a deformation gradient F:
 *   sigma = 2 C10 / J (Bbar - tr(Bbar)/3 I) + 2 (J - 1) / D1 I,  Bbar = J^(-2/3) F F^T */
static inline void nh_cauchy(double c10, double d1, const double F[3][3], double s[3][3]) {
  const double J = F[0][0] * (F[1][1] * F[2][2] - F[1][2] * F[2][1]) - F[0][1] * (F[1][0] * F[2][2] - F[1][2] * F[2][0]) +
                   F[0][2] * (F[1][0] * F[2][1] - F[1][1] * F[2][0]);
  double B[3][3] = {{0}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) B[i][j] += F[i][k] * F[j][k] * pow(J, -2.0 / 3.0);
  const double tr = B[0][0] + B[1][1] + B[2][2];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s[i][j] = 2.0 * c10 / J * (B[i][j] - (i == j) * tr / 3.0) + (i == j) * 2.0 * (J - 1.0) / d1;
}

static inline void free_block(palp_fem_mesh *m) { palp_fem_mesh_destroy(m); }

#endif
