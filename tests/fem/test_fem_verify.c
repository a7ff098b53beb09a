/*
 * test_fem_verify.c - verification of the FE reference against analytic solutions.
 * Usage: test_fem_verify <case>; each case is its own CTest test.
 */
#include "fem_test.h"

static const double C10 = 1.0e5;  /* [Pa] */
static const double D1 = 4.0e-6;  /* [1/Pa]: K = 2 / D1 = 5e5 Pa, K / mu = 2.5 (compressible) */

static double gp_sigma(const palp_fem_model *m, int e, int g, int i, int j) {
  double s[6];
  palp_fem_element_cauchy(m, e, g, m->u, INFINITY, s);
  const int v[3][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}};
  return s[v[i][j]];
}

/* Prescribes every node to x = F X (all three directions) where mask says so. */
static void prescribe_affine(palp_fem_model *m, const double F[3][3], int boundary_only) {
  const palp_fem_mesh *mesh = m->mesh;
  for (int n = 0; n < mesh->node_count; ++n) {
    const double *X = mesh->x[n];
    int on = 0;
    for (int d = 0; d < 3; ++d) on |= fabs(X[d]) < 1e-12 || fabs(X[d] - 1.0) < 1e-12;
    if (boundary_only && !on) continue;
    for (int i = 0; i < 3; ++i) {
      double xi = 0.0;
      for (int k = 0; k < 3; ++k) xi += F[i][k] * X[k];
      palp_fem_model_prescribe(m, n, i, xi - X[i]);
    }
  }
}

/* Uniaxial stretch lambda = 1.3 of a unit cube with symmetry planes, lateral faces
 * traction free. Analytic: the lateral stretch solves sigma_22(lambda, lt) = 0
 * (bisection on the closed form); sigma_11 from the closed form. Tolerances:
 * lateral stretch 1e-8, sigma_11 1e-7 relative, sigma_22 1e-6 C10. */
static void test_uniaxial(void) {
  palp_fem_mesh mesh;
  block_mesh(&mesh, 1, 1, 1, 0.0);
  palp_fem_config cfg = elastic_config(C10, D1);
  palp_fem_model m;
  CHECK(palp_fem_model_create(&m, &mesh, &cfg) == 0, "model");
  const double lam = 1.3;
  for (int n = 0; n < 8; ++n) {
    const double *X = mesh.x[n];
    if (X[0] < 0.5) palp_fem_model_prescribe(&m, n, 0, 0.0);
    else palp_fem_model_prescribe(&m, n, 0, lam - 1.0);
    if (X[1] < 0.5) palp_fem_model_prescribe(&m, n, 1, 0.0);
    if (X[2] < 0.5) palp_fem_model_prescribe(&m, n, 2, 0.0);
  }
  CHECK(palp_fem_model_finalize(&m) == 0, "finalize");
  m.rtol = 1e-12;
  CHECK(palp_fem_solve_static(&m, NULL, 5, INFINITY) == 0, "static solve: %s", m.err);
  double lo = 0.3, hi = 1.2;
  for (int it = 0; it < 200; ++it) {
    const double lt = 0.5 * (lo + hi), F[3][3] = {{lam, 0, 0}, {0, lt, 0}, {0, 0, lt}};
    double s[3][3];
    nh_cauchy(C10, D1, F, s);
    if (s[1][1] > 0.0) hi = lt;
    else lo = lt;
  }
  const double lt = 0.5 * (lo + hi), F[3][3] = {{lam, 0, 0}, {0, lt, 0}, {0, 0, lt}};
  double s[3][3];
  nh_cauchy(C10, D1, F, s);
  CHECK_NEAR(1.0 + m.u[3 * 6 + 1], lt, 1e-8, "uniaxial lateral stretch (node 7, y)");
  CHECK_NEAR(1.0 + m.u[3 * 6 + 2], lt, 1e-8, "uniaxial lateral stretch (node 7, z)");
  for (int g = 0; g < 8; ++g) {
    CHECK_NEAR(gp_sigma(&m, 0, g, 0, 0), s[0][0], 1e-7 * fabs(s[0][0]), "uniaxial sigma_11 [Pa]");
    CHECK_NEAR(gp_sigma(&m, 0, g, 1, 1), 0.0, 1e-6 * C10, "uniaxial sigma_22 [Pa]");
  }
  printf("uniaxial: lambda %.2f lateral %.9f sigma_11 %.6g Pa (analytic %.6g)\n", lam, 1.0 + m.u[19],
         gp_sigma(&m, 0, 0, 0, 0), s[0][0]);
  palp_fem_model_destroy(&m);
  free_block(&mesh);
}

/* Simple shear gamma = 0.5 of a distorted 2x2x2 block, every node prescribed:
 * sigma_12 = 2 C10 gamma, sigma_11 = 4/3 C10 gamma^2, sigma_22 = sigma_33 = -2/3
 * C10 gamma^2 at every Gauss point (J = 1). Tolerance 1e-9 C10. */
static void test_shear(void) {
  palp_fem_mesh mesh;
  block_mesh(&mesh, 2, 2, 2, 0.15);
  palp_fem_config cfg = elastic_config(C10, D1);
  palp_fem_model m;
  CHECK(palp_fem_model_create(&m, &mesh, &cfg) == 0, "model");
  const double gam = 0.5, F[3][3] = {{1, gam, 0}, {0, 1, 0}, {0, 0, 1}};
  prescribe_affine(&m, F, 0);
  CHECK(palp_fem_model_finalize(&m) == 0, "finalize");
  CHECK(palp_fem_solve_static(&m, NULL, 1, INFINITY) == 0, "solve: %s", m.err);
  for (int e = 0; e < mesh.element_count; ++e)
    for (int g = 0; g < 8; ++g) {
      CHECK_NEAR(gp_sigma(&m, e, g, 0, 1), 2 * C10 * gam, 1e-9 * C10, "shear sigma_12 [Pa]");
      CHECK_NEAR(gp_sigma(&m, e, g, 0, 0), 4.0 / 3.0 * C10 * gam * gam, 1e-9 * C10, "shear sigma_11 [Pa]");
      CHECK_NEAR(gp_sigma(&m, e, g, 1, 1), -2.0 / 3.0 * C10 * gam * gam, 1e-9 * C10, "shear sigma_22 [Pa]");
      CHECK_NEAR(gp_sigma(&m, e, g, 2, 2), -2.0 / 3.0 * C10 * gam * gam, 1e-9 * C10, "shear sigma_33 [Pa]");
      CHECK_NEAR(gp_sigma(&m, e, g, 1, 2), 0.0, 1e-9 * C10, "shear sigma_23 [Pa]");
    }
  /* the top face (y = 1, area 1 m^2 also after shear) carries sigma_12 in x */
  double fx = 0.0;
  for (int n = 0; n < mesh.node_count; ++n)
    if (mesh.x[n][1] > 1.0 - 1e-12) fx += m.fint[3 * n];
  CHECK_NEAR(fx, 2 * C10 * gam, 1e-9 * C10, "shear: nodal force on the y = 1 face [N]");
  printf("shear: gamma %.2f sigma_12 %.9g Pa (analytic %.9g), face force %.9g N\n", gam, gp_sigma(&m, 0, 0, 0, 1),
         2 * C10 * gam, fx);
  palp_fem_model_destroy(&m);
  free_block(&mesh);
}

/* Pure dilatation x = 1.1 X: sigma = 2 (J - 1) / D1 I with J = 1.331, no shear
 * stress, and the x = 1 face carries sigma * 1.21 m^2. Tolerance 1e-9 relative. */
static void test_dilatation(void) {
  palp_fem_mesh mesh;
  block_mesh(&mesh, 2, 2, 2, 0.15);
  palp_fem_config cfg = elastic_config(C10, D1);
  palp_fem_model m;
  CHECK(palp_fem_model_create(&m, &mesh, &cfg) == 0, "model");
  const double s = 1.1, F[3][3] = {{s, 0, 0}, {0, s, 0}, {0, 0, s}};
  prescribe_affine(&m, F, 0);
  CHECK(palp_fem_model_finalize(&m) == 0, "finalize");
  CHECK(palp_fem_solve_static(&m, NULL, 1, INFINITY) == 0, "solve");
  const double p = 2.0 * (s * s * s - 1.0) / D1;
  for (int e = 0; e < mesh.element_count; ++e)
    for (int g = 0; g < 8; ++g) {
      for (int i = 0; i < 3; ++i) CHECK_NEAR(gp_sigma(&m, e, g, i, i), p, 1e-9 * p, "dilatation sigma_ii [Pa]");
      CHECK_NEAR(gp_sigma(&m, e, g, 0, 1), 0.0, 1e-9 * p, "dilatation sigma_12 [Pa]");
    }
  double fx = 0.0;
  for (int n = 0; n < mesh.node_count; ++n)
    if (mesh.x[n][0] > 1.0 - 1e-12) fx += m.fint[3 * n];
  CHECK_NEAR(fx, p * s * s, 1e-9 * p, "dilatation: force on the x = 1 face [N]");
  printf("dilatation: J %.4f pressure %.9g Pa (analytic %.9g)\n", s * s * s, gp_sigma(&m, 0, 0, 0, 0), p);
  palp_fem_model_destroy(&m);
  free_block(&mesh);
}

/* Patch test: a 3x3x3 block with every interior node jittered by up to 20% of a
 * cell; the boundary follows x = F X for a general F (J = 1.04); the free interior
 * nodes must land on F X (1e-9 m) and the stress be the analytic one everywhere
 * (1e-7 relative to its largest component). Both a compressible and a nearly
 * incompressible (K / mu = 1e4) material. */
static void test_patch(double d1, const char *label) {
  palp_fem_mesh mesh;
  block_mesh(&mesh, 3, 3, 3, 0.2);
  palp_fem_config cfg = elastic_config(C10, d1);
  palp_fem_model m;
  CHECK(palp_fem_model_create(&m, &mesh, &cfg) == 0, "model");
  const double F[3][3] = {{1.1, 0.05, 0.02}, {-0.03, 0.95, 0.04}, {0.01, 0.06, 1.0}};
  prescribe_affine(&m, F, 1);
  CHECK(palp_fem_model_finalize(&m) == 0, "finalize");
  CHECK(m.nfree == 24, "patch: 8 free interior nodes expected, got %d equations", m.nfree);
  m.rtol = 1e-12;
  CHECK(palp_fem_solve_static(&m, NULL, 3, INFINITY) == 0, "patch solve: %s", m.err);
  double err = 0.0;
  for (int n = 0; n < mesh.node_count; ++n)
    for (int i = 0; i < 3; ++i) {
      double xi = 0.0;
      for (int k = 0; k < 3; ++k) xi += F[i][k] * mesh.x[n][k];
      err = fmax(err, fabs(mesh.x[n][i] + m.u[3 * n + i] - xi));
    }
  CHECK(err <= 1e-9, "patch (%s): interior nodes off the affine field by %.3g m (tolerance 1e-9 m)", label, err);
  double s[3][3];
  nh_cauchy(C10, d1, F, s);
  double smax = 0.0, serr = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) smax = fmax(smax, fabs(s[i][j]));
  for (int e = 0; e < mesh.element_count; ++e)
    for (int g = 0; g < 8; ++g)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) serr = fmax(serr, fabs(gp_sigma(&m, e, g, i, j) - s[i][j]));
  CHECK(serr <= 1e-7 * smax, "patch (%s): stress error %.3g Pa of %.3g Pa (tolerance 1e-7 relative)", label, serr, smax);
  printf("patch (%s): max node error %.3g m, max stress error %.3g Pa of %.3g Pa\n", label, err, serr, smax);
  palp_fem_model_destroy(&m);
  free_block(&mesh);
}

/* Rigid rotation (60 degrees about (1,2,3)) of a distorted element: zero internal
 * force and stress (1e-9 C10); rotating a stretched state rotates its stress,
 * sigma(R F) = R sigma(F) R^T (1e-9 relative). */
static void test_rotation(void) {
  palp_fem_mesh mesh;
  block_mesh(&mesh, 2, 2, 2, 0.2);
  palp_fem_config cfg = elastic_config(C10, D1);
  cfg.gel.prony_count = 2;
  cfg.gel.g[0] = 0.5, cfg.gel.tau[0] = 0.01, cfg.gel.g[1] = 0.3, cfg.gel.tau[1] = 0.1;
  const double n[3] = {1 / sqrt(14.0), 2 / sqrt(14.0), 3 / sqrt(14.0)}, th = PALP_FEM_PI / 3;
  double R[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double eps = (i == j) ? 0.0 : ((j == (i + 1) % 3) ? -n[3 - i - j] : n[3 - i - j]);
      R[i][j] = cos(th) * (i == j) + sin(th) * eps + (1 - cos(th)) * n[i] * n[j];
    }
  for (int pass = 0; pass < 2; ++pass) {
    palp_fem_model m;
    CHECK(palp_fem_model_create(&m, &mesh, &cfg) == 0, "model");
    const double U[3][3] = {{1.2, 0.1, 0}, {0.1, 0.9, 0.05}, {0, 0.05, 1.05}};
    double F[3][3] = {{0}};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) F[i][j] += R[i][k] * (pass ? U[k][j] : (k == j));
    prescribe_affine(&m, (const double(*)[3])F, 0);
    CHECK(palp_fem_model_finalize(&m) == 0, "finalize");
    CHECK(palp_fem_solve_static(&m, NULL, 1, 0.0) == 0, "solve");
    if (pass == 0) {
      double fmaxv = 0.0, smax = 0.0;
      for (int d = 0; d < m.ndof; ++d) fmaxv = fmax(fmaxv, fabs(m.fint[d]));
      for (int e = 0; e < mesh.element_count; ++e)
        for (int g = 0; g < 8; ++g)
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) smax = fmax(smax, fabs(gp_sigma(&m, e, g, i, j)));
      CHECK(fmaxv <= 1e-9 * C10, "rigid rotation: internal force %.3g N (tolerance 1e-9 C10 x 1 m^2)", fmaxv);
      CHECK(smax <= 1e-9 * C10, "rigid rotation: stress %.3g Pa (tolerance 1e-9 C10)", smax);
      printf("rotation: max |f_int| %.3g N, max |sigma| %.3g Pa\n", fmaxv, smax);
    } else {
      double s[3][3], sr[3][3] = {{0}};
      nh_cauchy(C10 / (1.0 - 0.8), D1, U, s); /* instantaneous response, C10 long-term */
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 3; ++l) sr[i][j] += R[i][k] * s[k][l] * R[j][l];
      double err = 0.0, smax = 0.0;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          err = fmax(err, fabs(gp_sigma(&m, 3, 5, i, j) - sr[i][j]));
          smax = fmax(smax, fabs(sr[i][j]));
        }
      /* gp_sigma evaluates with dt = INFINITY from the committed history; use dt = 0 */
      double sv[6];
      palp_fem_element_cauchy(&m, 3, 5, m.u, 0.0, sv);
      const int v[3][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}};
      err = 0.0;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) err = fmax(err, fabs(sv[v[i][j]] - sr[i][j]));
      CHECK(err <= 1e-9 * smax, "objectivity: sigma(RU) vs R sigma(U) R^T off by %.3g Pa (tolerance 1e-9 rel)", err);
      printf("objectivity: max error %.3g Pa of %.3g Pa\n", err, smax);
    }
    palp_fem_model_destroy(&m);
  }
  free_block(&mesh);
}

/* Step-strain relaxation with the paper's Prony series (g = 0.9, 0.09; tau = 2, 5 ms).
 * An isochoric stretch (lambda = 1.2, J = 1) is ramped in h = 1 us, then held with
 * steps of 1 ms and later 50 ms (>> tau). The recursive update is exact for a
 * ramp-and-hold history, so sigma_11 - sigma_22 must follow
 *   s0 [g_inf + sum g_k tau_k / h (1 - exp(-h / tau_k)) exp(-(t - h) / tau_k)]
 * to 1e-9 relative, and the step closed form s0 g(t) within h / (2 tau_1) = 2.5e-4. */
static void test_prony(void) {
  palp_fem_mesh mesh;
  block_mesh(&mesh, 1, 1, 1, 0.0);
  palp_fem_config cfg = palp_fem_default_config();
  cfg.gel.d1 = 4e-6;
  cfg.c10_reading = PALP_FEM_C10_INSTANTANEOUS;
  palp_fem_model m;
  CHECK(palp_fem_model_create(&m, &mesh, &cfg) == 0, "model");
  const double lam = 1.2, lt = 1.0 / sqrt(lam);
  const double F[3][3] = {{lam, 0, 0}, {0, lt, 0}, {0, 0, lt}};
  prescribe_affine(&m, F, 0);
  CHECK(palp_fem_model_finalize(&m) == 0, "finalize");
  const double c10 = cfg.gel.c10, h = 1e-6;
  const double s0 = 2.0 * c10 * (lam * lam - lt * lt); /* sigma_11 - sigma_22, instantaneous */
  CHECK(palp_fem_solve_static(&m, NULL, 1, h) == 0, "ramp");
  double t = h, worst = 0.0, worst_step = 0.0;
  for (int k = 0; k < 40; ++k) {
    const double dt = k < 30 ? 1e-3 : 50e-3;
    CHECK(palp_fem_solve_static(&m, NULL, 1, dt) == 0, "hold");
    t += dt;
    double sv[6];
    palp_fem_element_cauchy(&m, 0, 0, m.u, 0.0, sv); /* dt = 0: the committed stress */
    const double got = sv[0] - sv[1];
    double ramp = 1.0 - cfg.gel.g[0] - cfg.gel.g[1], step = ramp;
    for (int q = 0; q < 2; ++q) {
      const double tau = cfg.gel.tau[q], g = cfg.gel.g[q];
      ramp += g * tau / h * (1.0 - exp(-h / tau)) * exp(-(t - h) / tau);
      step += g * exp(-t / tau);
    }
    worst = fmax(worst, fabs(got - s0 * ramp) / s0);
    worst_step = fmax(worst_step, fabs(got - s0 * step) / s0);
    if (k == 0 || k == 4 || k == 29 || k == 39)
      printf("prony: t = %7.4f s  sigma/s0 = %.9f  closed form %.9f  step %.9f\n", t, got / s0, ramp, step);
  }
  CHECK(worst <= 1e-9, "prony: ramp-and-hold closed form off by %.3g (tolerance 1e-9 relative)", worst);
  CHECK(worst_step <= 2.5e-4, "prony: step closed form off by %.3g (tolerance 2.5e-4 relative)", worst_step);
  palp_fem_model_destroy(&m);
  free_block(&mesh);
}

/* Consistent tangent against central differences of the internal force, for a
 * distorted element in a general deformed state with viscoelastic history, both
 * compressible and with the paper's nearly incompressible gel. Step eps = 1e-7 m
 * on a 1 m element; tolerance 1e-6 of the largest entry. */
static void test_tangent(double d1, const char *label) {
  palp_fem_mesh mesh;
  block_mesh(&mesh, 2, 2, 2, 0.2);
  palp_fem_config cfg = palp_fem_default_config();
  cfg.gel.d1 = d1;
  palp_fem_model m;
  CHECK(palp_fem_model_create(&m, &mesh, &cfg) == 0, "model");
  /* history: one step of a different deformation */
  const double F1[3][3] = {{1.05, 0.02, 0}, {0, 0.97, 0.03}, {0.01, 0, 1.0}};
  prescribe_affine(&m, F1, 0);
  CHECK(palp_fem_model_finalize(&m) == 0, "finalize");
  CHECK(palp_fem_solve_static(&m, NULL, 1, 0.003) == 0, "history");
  const int e = 7; /* the element with the jittered centre node */
  double ue[24];
  unsigned s = 99u;
  for (int a = 0; a < 8; ++a)
    for (int i = 0; i < 3; ++i) {
      s = s * 1103515245u + 12345u;
      ue[3 * a + i] = m.u[3 * mesh.hex[e][a] + i] + 0.04 * (((s >> 8) & 0xffff) / 65535.0 - 0.5);
    }
  double fe[24], ke[24][24], fp[24], fm[24], S0t[48], Ht[8 * 2 * 6];
  CHECK(palp_fem_element(&m, e, ue, 0.004, fe, ke, S0t, Ht) == 0, "element");
  double kmax = 0.0, err = 0.0;
  for (int r = 0; r < 24; ++r)
    for (int c = 0; c < 24; ++c) kmax = fmax(kmax, fabs(ke[r][c]));
  const double eps = 1e-7;
  for (int c = 0; c < 24; ++c) {
    double up[24], um[24];
    memcpy(up, ue, sizeof up);
    memcpy(um, ue, sizeof um);
    up[c] += eps;
    um[c] -= eps;
    palp_fem_element(&m, e, up, 0.004, fp, NULL, S0t, Ht);
    palp_fem_element(&m, e, um, 0.004, fm, NULL, S0t, Ht);
    for (int r = 0; r < 24; ++r) err = fmax(err, fabs((fp[r] - fm[r]) / (2 * eps) - ke[r][c]));
  }
  double asym = 0.0;
  for (int r = 0; r < 24; ++r)
    for (int c = 0; c < 24; ++c) asym = fmax(asym, fabs(ke[r][c] - ke[c][r]));
  CHECK(err <= 1e-6 * kmax, "tangent (%s): FD mismatch %.3g of max %.3g (tolerance 1e-6 relative)", label, err, kmax);
  CHECK(asym <= 1e-12 * kmax, "tangent (%s): asymmetry %.3g", label, asym);
  printf("tangent (%s): max |K - K_fd| = %.3g of max |K| = %.3g (ratio %.2g)\n", label, err, kmax, err / kmax);
  palp_fem_model_destroy(&m);
  free_block(&mesh);
}

/* The material-level modulus of palp_fem_nh_iso (Voigt, engineering shear)
 * against central differences of S(C): D_pq = 2 dS_p/dC_q for normal q, dS_p/dC_q
 * for shear q (one Voigt entry stands for C_ij and C_ji). Tolerance 1e-7 of max |D|. */
static void test_material_modulus(void) {
  const double C[6] = {1.3, 0.9, 1.1, 0.12, -0.05, 0.08}, c10 = 1e5, eps = 1e-6;
  double S[6], D[6][6], Sp[6], Sm[6], dmax = 0.0, err = 0.0;
  palp_fem_nh_iso(c10, C, S, D);
  for (int q = 0; q < 6; ++q) {
    double Cp[6], Cm[6];
    memcpy(Cp, C, sizeof Cp);
    memcpy(Cm, C, sizeof Cm);
    Cp[q] += eps;
    Cm[q] -= eps;
    palp_fem_nh_iso(c10, Cp, Sp, NULL);
    palp_fem_nh_iso(c10, Cm, Sm, NULL);
    for (int p = 0; p < 6; ++p) {
      const double fd = (q < 3 ? 2.0 : 1.0) * (Sp[p] - Sm[p]) / (2 * eps);
      err = fmax(err, fabs(fd - D[p][q]));
      dmax = fmax(dmax, fabs(D[p][q]));
    }
  }
  CHECK(err <= 1e-7 * dmax, "material modulus: FD mismatch %.3g of %.3g (tolerance 1e-7 relative)", err, dmax);
  printf("material modulus: max |D - D_fd| = %.3g of %.3g\n", err, dmax);
}

/* One block's axial mode, dynamically: a unit cube with its base fixed and every
 * node held in x and y, so the four top nodes move together in z (uniaxial strain)
 * and the cube is one mass on one spring, linear at a 1 um stroke:
 *   k = (K + 4/3 mu) A / L = 2 / D1 + 8/3 C10 [N/m],  m = rho V / 2 (the top half of
 * the lumped mass) [kg],  omega = sqrt(k / m) [rad/s].
 * A step force F (k u_s with u_s = 1 um) is applied from t = 0. The same scheme is
 * run here on the scalar equation m a + k u = F (HHT-alpha: m a+ + (1 + alpha)(k u+ -
 * F+) - alpha (k u - F) = 0, Newmark's update with beta = (1 - alpha)^2 / 4 and gamma
 * = 1/2 - alpha), and the FE's top displacement must follow it within 2e-5 u_s
 * (measured 0.6-2.8e-6: the Neo-Hookean's quadratic terms at 1e-6 strain, K / M ~ 0.65
 * of them volumetric). Properties of the scheme, on the scalar trace the FE follows:
 *  - alpha = 0 (the trapezoidal rule) keeps the amplitude about u_s at Omega =
 *    omega dt = 10: within 1e-6 after 200 steps (no numerical dissipation);
 *  - alpha = -0.05 at Omega = 10 (a mode the step cannot resolve): after 50 steps the
 *    amplitude is below 2 (0.95 / 1.05)^50 = 1.4% of the start (HHT's spectral radius
 *    at infinite Omega is (1 + alpha) / (1 - alpha) = 0.905);
 *  - alpha = -0.05 at Omega = 0.1 (resolved, 63 steps a period): after one period the
 *    amplitude is above 0.999 of the start (second-order accurate: resolved modes keep
 *    their energy). */
static void hht_run(double alpha, double Omega, int steps, double *amp0, double *amp_end, double *worst) {
  const double c10 = C10, d1 = D1, rho = 950.0;
  const double k = 2.0 / d1 + 8.0 / 3.0 * c10, mass = 0.5 * rho, omega = sqrt(k / mass), dt = Omega / omega;
  const double us = 1e-6, F = k * us;
  palp_fem_mesh mesh;
  block_mesh(&mesh, 1, 1, 1, 0.0);
  palp_fem_config cfg = elastic_config(c10, d1);
  cfg.gel.density = cfg.membrane.density = rho;
  palp_fem_config_set_hht(&cfg, alpha);
  palp_fem_model m;
  CHECK(palp_fem_model_create(&m, &mesh, &cfg) == 0, "model");
  double fext[24] = {0};
  for (int n = 0; n < 8; ++n) {
    palp_fem_model_prescribe(&m, n, 0, 0.0);
    palp_fem_model_prescribe(&m, n, 1, 0.0);
    if (mesh.x[n][2] < 0.5) palp_fem_model_prescribe(&m, n, 2, 0.0);
    else fext[3 * n + 2] = 0.25 * F;
  }
  CHECK(palp_fem_model_finalize(&m) == 0, "finalize");
  m.rtol = 1e-8; /* J - 1 ~ 1e-6 loses ~1e-10 to cancellation: the residual's floor */
  m.atol = 1e-15;
  m.full_newton = 1; /* exact Newton steps */
  m.max_cutbacks = 0; /* a step that fails must fail the test, not be halved */
  const double beta = 0.25 * (1.0 - alpha) * (1.0 - alpha), gamma = 0.5 - alpha;
  const double c0 = 1.0 / (beta * dt * dt), c1 = 1.0 / (beta * dt), c2 = 1.0 / (2.0 * beta) - 1.0;
  double u = 0.0, v = 0.0, a = 0.0, Fprev = 0.0;
  *worst = 0.0;
  *amp0 = *amp_end = 0.0;
  for (int i = 0; i < steps; ++i) {
    /* m (c0 (u+ - u) - c1 v - c2 a) + (1 + alpha)(k u+ - F) - alpha (k u - Fprev) = 0 */
    const double u1 = (mass * (c0 * u + c1 * v + c2 * a) + (1.0 + alpha) * F - alpha * (Fprev - k * u)) /
                      (mass * c0 + (1.0 + alpha) * k);
    const double a1 = c0 * (u1 - u) - c1 * v - c2 * a;
    v += dt * ((1.0 - gamma) * a + gamma * a1);
    u = u1, a = a1, Fprev = F;
    const int rc = palp_fem_step(&m, fext, dt);
    CHECK(rc == 0, "HHT alpha %g Omega %g step %d: %s", alpha, Omega, i, m.err);
    if (rc) break;
    for (int n = 4; n < 8; ++n) *worst = fmax(*worst, fabs(m.u[3 * n + 2] - u) / us);
    /* the amplitude about the static displacement, from the scalar trace's energy */
    const double amp = sqrt((u - us) * (u - us) + v * v / (omega * omega)) / us;
    if (i == 0) *amp0 = amp;
    *amp_end = amp;
  }
  palp_fem_model_destroy(&m);
  free_block(&mesh);
}

static void test_hht(void) {
  double a0, a1, w;
  hht_run(0.0, 10.0, 200, &a0, &a1, &w);
  printf("hht: alpha 0, Omega 10: amplitude %.9f -> %.9f after 200 steps; FE off the scalar scheme by %.3g u_s\n",
         a0, a1, w);
  CHECK(fabs(a1 / a0 - 1.0) <= 1e-6, "trapezoidal rule lost amplitude: %.9f -> %.9f (tolerance 1e-6)", a0, a1);
  CHECK(w <= 2e-5, "FE off the scalar trapezoidal scheme by %.3g u_s (tolerance 2e-5)", w);
  hht_run(-0.05, 10.0, 50, &a0, &a1, &w);
  const double bound = 2.0 * pow(0.95 / 1.05, 50);
  printf("hht: alpha -0.05, Omega 10: amplitude %.6f -> %.6f after 50 steps (bound %.4f of the start); FE off by %.3g u_s\n",
         a0, a1, bound, w);
  CHECK(a1 <= bound * a0, "HHT did not damp the unresolved mode: %.6f -> %.6f (bound %.4f of the start)", a0, a1, bound);
  CHECK(w <= 2e-5, "FE off the scalar HHT scheme by %.3g u_s (tolerance 2e-5)", w);
  hht_run(-0.05, 0.1, 63, &a0, &a1, &w);
  printf("hht: alpha -0.05, Omega 0.1: amplitude %.6f -> %.6f after one period; FE off by %.3g u_s\n", a0, a1, w);
  CHECK(a1 >= 0.999 * a0, "HHT damped a resolved mode: %.6f -> %.6f (tolerance 0.1%% per period)", a0, a1);
  CHECK(w <= 2e-5, "FE off the scalar HHT scheme by %.3g u_s (tolerance 2e-5)", w);
  /* the configuration: hht_alpha sets beta and gamma; the breast-tissue profile
   * takes Abaqus's default, the paper's profiles the trapezoidal rule */
  palp_fem_config c = palp_fem_default_config();
  char err[256];
  CHECK(c.hht_alpha == 0.0 && c.newmark_beta == 0.25 && c.newmark_gamma == 0.5, "default is the trapezoidal rule");
  CHECK(palp_fem_config_parse("{\"hht_alpha\": -0.1}", &c, err, sizeof err) == 0, "hht_alpha -0.1: %s", err);
  CHECK_NEAR(c.newmark_beta, 0.3025, 1e-15, "beta = (1.1)^2 / 4");
  CHECK_NEAR(c.newmark_gamma, 0.6, 1e-15, "gamma = 0.6");
  c = palp_fem_default_config();
  CHECK(palp_fem_config_parse("{\"hht_alpha\": -0.1, \"newmark_gamma\": 0.6}", &c, err, sizeof err) != 0 &&
            strstr(err, "hht_alpha"), "hht_alpha beside newmark_gamma must be refused (got \"%s\")", err);
  c = palp_fem_default_config();
  CHECK(palp_fem_config_parse("{\"hht_alpha\": -0.5}", &c, err, sizeof err) != 0 && strstr(err, "hht_alpha"),
        "hht_alpha -0.5 (below -1/3) must be refused (got \"%s\")", err);
  c = palp_fem_default_config();
  CHECK(palp_fem_config_parse("{\"hht_alpha\": 0.1}", &c, err, sizeof err) != 0, "hht_alpha 0.1 must be refused");
  c = palp_fem_default_config();
  CHECK(palp_fem_config_parse("{\"material\": \"breast_tissue\"}", &c, err, sizeof err) == 0 &&
            c.hht_alpha == -0.05 && c.load_map == PALP_FEM_LOAD_PATCH,
        "breast_tissue: HHT -0.05 and the patch map (got %g, map %d)", c.hht_alpha, (int)c.load_map);
  CHECK(palp_fem_config_set_material(&c, "paper_long_term", err, sizeof err) == 0 && c.hht_alpha == 0.0 &&
            c.newmark_beta == 0.25 && c.newmark_gamma == 0.5,
        "paper_long_term after breast_tissue: back to the trapezoidal rule");
}

int main(int argc, char **argv) {
  const char *c = argc > 1 ? argv[1] : "all";
  const int all = strcmp(c, "all") == 0;
  if (all || !strcmp(c, "uniaxial")) test_uniaxial();
  if (all || !strcmp(c, "shear")) test_shear();
  if (all || !strcmp(c, "dilatation")) test_dilatation();
  if (all || !strcmp(c, "patch")) {
    test_patch(D1, "compressible");
    test_patch(2.0 / (1e4 * 2 * C10), "K/mu = 1e4");
  }
  if (all || !strcmp(c, "rotation")) test_rotation();
  if (all || !strcmp(c, "prony")) test_prony();
  if (all || !strcmp(c, "hht")) test_hht();
  if (all || !strcmp(c, "tangent")) {
    test_material_modulus();
    test_tangent(4e-6, "compressible gel");
    test_tangent(1e-9, "paper gel, D1 = 0.001 1/MPa");
  }
  if (fem_failures) fprintf(stderr, "%d check(s) failed\n", fem_failures);
  return fem_failures ? 1 : 0;
}
