/*
 * ccx_crosscheck - the FEM reference against an independent FE code (issue 12): CalculiX
 * (Debian's calculix-ccx) on the project's own hemisphere mesh made quadratic.
 *
 *   ccx_crosscheck [--levels 1,2,3] [--profile paper_long_term] [--force 3] [--dir DIR] [--ccx PATH]
 *                  [--ccx-only | --palp-only] [--ccx-inc FRACTION] [--ccx-timeout SECONDS] [--ccx-quarter]
 *                  [--palp-inc K]
 *
 * For each level: the project's relaxed static pole displacement under distribution II (a
 * uniform vertical traction of total F over the 5.2 cm^2 cap around the pole, as
 * bench_profiles), then the same problem in CalculiX: every hexahedron becomes a 20-node
 * C3D20R (CalculiX has no hybrid elements; quadratic reduced-integration bricks are its answer
 * to near incompressibility) whose edge midpoints lie on the true sphere wherever both ends of
 * the edge lie on one sphere about the centre (the outer surface and the membrane's inner
 * face), the relaxed moduli as *HYPERELASTIC, NEO HOOKE (CalculiX has no Prony series for
 * hyperelasticity: relaxed states are compared), the base clamped, NLGEOM, and the traction
 * integrated over the curved 8-node faces (6 x 6 Gauss points, the same point-in-cap rule and
 * quadrature as the project's load here)
 * into *CLOAD dead loads scaled to exactly F. The pole's uz is read from ccx's .dat file.
 * Built, not run by CTest (level 3 takes minutes in ccx); the test fem_ccx runs levels 1 and 2.
 *
 * --cap-area loads a smaller cap (a fingertip's contact: 0.5 cm^2 is a 4 mm radius) and --grading
 * refines the mesh of both codes at the pole (palp_fem_mesh_def.grading): how far a fingertip's
 * response is from converged on each code's elements (docs/fem.md, "The fingertip's mesh").
 *
 * --palp-only skips CalculiX (the project's side alone reaches levels 5-7, where a quadratic ccx
 * deck would be 3-7 times larger than the largest it has solved). --ccx-inc sets ccx's initial
 * and largest load increment (default 0.25): at level 4 its Newton diverged in the third of
 * four increments. --ccx-timeout stops ccx after that many seconds (coreutils timeout), so a
 * run that diverges and keeps cutting back cannot hold the shared machine. --ccx-quarter gives
 * ccx only the quarter x >= 0, y >= 0 with symmetry conditions (ux = 0 on x = 0, uy = 0 on
 * y = 0): the O-grid, the clamp and the cap load are symmetric about both planes (the planes
 * are mesh planes, x = 0 and y = 0 exactly), so the solution is the full model's, at a quarter of
 * the unknowns and ~1/16 of SPOOLES's factorisation (its only direct solver in Debian's build);
 * the full level 4 deck took >26 min without finishing. Peak resident memory
 * is printed per side: palp's is this process's peak so far (run one level per process for a
 * per-level figure), ccx's the largest child's. --palp-inc sets palp's load increments (default
 * 4): breast_tissue's 4.5 mm response inverts an element within the third of four from level 3 on.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "fem_internal.h"

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* 6-point Gauss-Legendre for the quadratic faces: the cap's edge cuts faces, and both codes
 * must see the same cap (palp_fem_cap_traction with 6 points on the project's side). With
 * 2 x 2 against 3 x 3 points the loaded area changed differently with the level in each code
 * and the pole's displacement was not monotone in the level. */
static const double GP[6] = {-0.93246951420315202781, -0.66120938646626451366, -0.23861918608319690863,
                             0.23861918608319690863,  0.66120938646626451366,  0.93246951420315202781};
static const double GW[6] = {0.17132449237917034504, 0.36076157304813860757, 0.46791393457269104739,
                             0.46791393457269104739, 0.36076157304813860757, 0.17132449237917034504};

/* ---- the quadratic mesh ------------------------------------------------------------------ */
typedef struct quad_mesh {
  int n;          /* nodes: the hexahedra's corners first (same indices), then edge midpoints */
  double (*x)[3];
  int (*el)[20];  /* C3D20 node order */
  int ne;
  /* edge -> midpoint, open addressing on the sorted corner pair */
  int *ka, *kb, *kv, cap;
} quad_mesh;

static double norm3d(const double *v) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

static int midpoint(quad_mesh *q, const palp_fem_mesh *m, int a, int b) {
  if (a > b) {
    const int t = a;
    a = b, b = t;
  }
  unsigned h = ((unsigned)a * 2654435761u ^ (unsigned)b * 40503u) & (unsigned)(q->cap - 1);
  while (q->kv[h] >= 0) {
    if (q->ka[h] == a && q->kb[h] == b) return q->kv[h];
    h = (h + 1) & (unsigned)(q->cap - 1);
  }
  double *x = q->x[q->n];
  for (int d = 0; d < 3; ++d) x[d] = 0.5 * (m->x[a][d] + m->x[b][d]);
  /* Both ends on one sphere about the centre (within 1e-9 relative): the midpoint goes onto it,
   * so the surface is the true sphere to the quadratic's order, not the hexahedra's facets. */
  const double ra = norm3d(m->x[a]), rb = norm3d(m->x[b]), r = norm3d(x);
  if (ra > 0 && fabs(ra - rb) <= 1e-9 * ra && r > 0 && x[2] > 1e-12)
    for (int d = 0; d < 3; ++d) x[d] *= ra / r;
  q->ka[h] = a, q->kb[h] = b, q->kv[h] = q->n;
  return q->n++;
}

static int quad_create(const palp_fem_mesh *m, quad_mesh *q) {
  memset(q, 0, sizeof *q);
  q->cap = 1;
  while (q->cap < 8 * m->element_count + 64) q->cap <<= 1;
  const int maxn = m->node_count + 12 * m->element_count;
  q->x = malloc(sizeof *q->x * (size_t)maxn);
  q->el = malloc(sizeof *q->el * (size_t)m->element_count);
  q->ka = malloc(sizeof(int) * (size_t)q->cap), q->kb = malloc(sizeof(int) * (size_t)q->cap);
  q->kv = malloc(sizeof(int) * (size_t)q->cap);
  if (!q->x || !q->el || !q->ka || !q->kb || !q->kv) return PALP_ENOMEM;
  for (int i = 0; i < q->cap; ++i) q->kv[i] = -1;
  memcpy(q->x, m->x, sizeof *q->x * (size_t)m->node_count);
  q->n = m->node_count;
  static const int edge[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                  {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  for (int e = 0; e < m->element_count; ++e) {
    for (int k = 0; k < 8; ++k) q->el[e][k] = m->hex[e][k];
    for (int k = 0; k < 12; ++k) q->el[e][8 + k] = midpoint(q, m, m->hex[e][edge[k][0]], m->hex[e][edge[k][1]]);
  }
  q->ne = m->element_count;
  return 0;
}

static void quad_destroy(quad_mesh *q) {
  free(q->x), free(q->el), free(q->ka), free(q->kb), free(q->kv);
}

/* Serendipity 8-node quad: corners (-1,-1),(1,-1),(1,1),(-1,1), then mids of edges 01,12,23,30. */
static void shape8(double xi, double eta, double N[8], double dxi[8], double deta[8]) {
  static const double c[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (int a = 0; a < 4; ++a) {
    const double s = c[a][0], t = c[a][1];
    N[a] = 0.25 * (1 + s * xi) * (1 + t * eta) * (s * xi + t * eta - 1);
    dxi[a] = 0.25 * s * (1 + t * eta) * (2 * s * xi + t * eta);
    deta[a] = 0.25 * t * (1 + s * xi) * (s * xi + 2 * t * eta);
  }
  N[4] = 0.5 * (1 - xi * xi) * (1 - eta), dxi[4] = -xi * (1 - eta), deta[4] = -0.5 * (1 - xi * xi);
  N[5] = 0.5 * (1 + xi) * (1 - eta * eta), dxi[5] = 0.5 * (1 - eta * eta), deta[5] = -eta * (1 + xi);
  N[6] = 0.5 * (1 - xi * xi) * (1 + eta), dxi[6] = -xi * (1 + eta), deta[6] = 0.5 * (1 - xi * xi);
  N[7] = 0.5 * (1 - xi) * (1 - eta * eta), dxi[7] = -0.5 * (1 - eta * eta), deta[7] = -eta * (1 - xi);
}

/* The traction on the curved faces: nodal z loads [N] (length q->n), total exactly F. */
static int quad_load(const palp_fem_mesh *m, quad_mesh *q, double F, double area, int quarter, double *fz) {
  int (*faces)[4], nf;
  if (palp_fem_surface_faces(m, &faces, &nf)) return PALP_ENOMEM;
  memset(fz, 0, sizeof(double) * (size_t)q->n);
  const double s2 = area / PALP_FEM_PI;
  double total = 0.0;
  for (int k = 0; k < nf; ++k) {
    int nd[8];
    for (int a = 0; a < 4; ++a) nd[a] = faces[k][a];
    for (int a = 0; a < 4; ++a) nd[4 + a] = midpoint(q, m, faces[k][a], faces[k][(a + 1) % 4]); /* existing */
    /* quarter model: only faces in x > 0, y > 0 load nodes (so nodes on a symmetry plane get
     * their half, the pole its quarter), but every face counts in the area, so the loads are
     * the full model's restricted to the quarter (total F / 4) */
    double cx = 0.0, cy = 0.0;
    for (int a = 0; a < 4; ++a) cx += m->x[nd[a]][0], cy += m->x[nd[a]][1];
    const int loads = !quarter || (cx > 0.0 && cy > 0.0);
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) {
        double N[8], dxi[8], deta[8], X[3] = {0}, Xa[3] = {0}, Xb[3] = {0};
        shape8(GP[i], GP[j], N, dxi, deta);
        for (int a = 0; a < 8; ++a)
          for (int d = 0; d < 3; ++d) {
            X[d] += N[a] * q->x[nd[a]][d];
            Xa[d] += dxi[a] * q->x[nd[a]][d];
            Xb[d] += deta[a] * q->x[nd[a]][d];
          }
        if (X[2] <= 0.0 || X[0] * X[0] + X[1] * X[1] > s2) continue;
        const double n[3] = {Xa[1] * Xb[2] - Xa[2] * Xb[1], Xa[2] * Xb[0] - Xa[0] * Xb[2],
                             Xa[0] * Xb[1] - Xa[1] * Xb[0]};
        const double dA = norm3d(n) * GW[i] * GW[j];
        if (loads)
          for (int a = 0; a < 8; ++a) fz[nd[a]] -= N[a] * dA;
        total += dA;
      }
  }
  free(faces);
  if (!(total > 0)) return PALP_EINVAL;
  for (int i = 0; i < q->n; ++i) fz[i] *= F / total;
  return 0;
}

static double relaxed_c10(const palp_fem_config *cfg, const palp_fem_material *mt) {
  if (cfg->c10_reading == PALP_FEM_C10_LONG_TERM) return mt->c10;
  double ginf = 1.0;
  for (int k = 0; k < mt->prony_count; ++k) ginf -= mt->g[k];
  return ginf * mt->c10;
}

/* Element e belongs to the quarter x > 0, y > 0 (no element straddles x = 0 or y = 0: they
 * are lattice planes of the O-grid). */
static int in_quarter(const palp_fem_mesh *m, int e) {
  double cx = 0.0, cy = 0.0;
  for (int k = 0; k < 8; ++k) cx += m->x[m->hex[e][k]][0], cy += m->x[m->hex[e][k]][1];
  return cx > 0.0 && cy > 0.0;
}

/* Writes the deck; *written = nodes in it. */
static int write_inp(const char *path, const palp_fem_mesh *m, const quad_mesh *q, const double *fz,
                     const palp_fem_config *cfg, const char *profile, int level, double inc, int quarter,
                     int *written) {
  uint8_t *used = calloc((size_t)q->n, 1);
  FILE *f = used ? fopen(path, "w") : NULL;
  if (!f) {
    free(used);
    return PALP_EIO;
  }
  for (int e = 0; e < q->ne; ++e)
    if (!quarter || in_quarter(m, e))
      for (int k = 0; k < 20; ++k) used[q->el[e][k]] = 1;
  fprintf(f, "*HEADING\npalp ccx cross-check: level %d, profile %s, relaxed moduli, C3D20R%s\n*NODE, NSET=NALL\n",
          level, profile, quarter ? ", quarter x >= 0, y >= 0 with symmetry planes" : "");
  /* 14 digits: CalculiX reads at most ~20 characters per field (a 22-character %.17g failed). */
  *written = 0;
  for (int i = 0; i < q->n; ++i)
    if (used[i]) {
      fprintf(f, "%d, %.14g, %.14g, %.14g\n", i + 1, q->x[i][0], q->x[i][1], q->x[i][2]);
      ++*written;
    }
  static const char *const set[2] = {"GEL", "MEMBRANE"};
  for (int r = 0; r < 2; ++r) {
    fprintf(f, "*ELEMENT, TYPE=C3D20R, ELSET=%s\n", set[r]);
    for (int e = 0; e < q->ne; ++e) {
      if (m->region[e] != (r == 0 ? PALP_FEM_GEL : PALP_FEM_MEMBRANE) || (quarter && !in_quarter(m, e))) continue;
      fprintf(f, "%d", e + 1);
      for (int k = 0; k < 20; ++k) fprintf(f, ",%s%d", k == 15 ? "\n" : " ", q->el[e][k] + 1);
      fputc('\n', f);
    }
  }
  /* the clamp, and with a quarter the symmetry planes: 1e-12 m against R = 0.04 m (the planes'
   * nodes are exactly 0, the nearest others >= ~0.5 mm away even at level 7) */
  static const char *const nset[3] = {"BASE", "XSYM", "YSYM"};
  for (int s = 0; s < (quarter ? 3 : 1); ++s) {
    fprintf(f, "*NSET, NSET=%s\n", nset[s]);
    int c = 0;
    for (int i = 0; i < q->n; ++i) {
      const int on = s == 0 ? q->x[i][2] <= 1e-9 : fabs(q->x[i][s - 1]) <= 1e-12;
      if (used[i] && on) fprintf(f, "%d,%s", i + 1, ++c % 12 ? "" : "\n");
    }
    fputc('\n', f);
  }
  fprintf(f, "*NSET, NSET=TOP\n%d\n", m->top_node + 1);
  const palp_fem_material *mt[2] = {&cfg->gel, &cfg->membrane};
  for (int r = 0; r < 2; ++r)
    fprintf(f, "*MATERIAL, NAME=M%s\n*HYPERELASTIC, NEO HOOKE\n%.10g, %.10g\n*SOLID SECTION, ELSET=%s, MATERIAL=M%s\n",
            set[r], relaxed_c10(cfg, mt[r]), mt[r]->d1, set[r], set[r]);
  fputs(quarter ? "*BOUNDARY\nBASE, 1, 3\nXSYM, 1, 1\nYSYM, 2, 2\n" : "*BOUNDARY\nBASE, 1, 3\n", f);
  /* initial = largest increment: ccx may cut back below it, never grow past it */
  fprintf(f, "*STEP, NLGEOM, INC=1000\n*STATIC\n%.6g, 1.0, 1e-5, %.6g\n*CLOAD\n", inc, inc);
  for (int i = 0; i < q->n; ++i)
    if (fz[i] != 0.0 && used[i]) fprintf(f, "%d, 3, %.14g\n", i + 1, fz[i]);
  fputs("*NODE PRINT, NSET=TOP\nU\n*END STEP\n", f);
  free(used);
  return fclose(f) ? PALP_EIO : 0;
}

/* The last "displacements ... for set TOP and time T" block of ccx's .dat: uz of its node, and T.
 * NODE PRINT writes every converged increment, so T < 1 means ccx stopped before the full load. */
static int read_top_uz(const char *dat, double *uz, double *time) {
  FILE *f = fopen(dat, "r");
  if (!f) return PALP_EIO;
  char line[512];
  int in = 0, got = 0;
  double t = NAN;
  while (fgets(line, sizeof line, f)) {
    if (strstr(line, "displacements") && strstr(line, "TOP")) {
      const char *tt = strstr(line, "time");
      t = tt ? atof(tt + 4) : NAN;
      in = 1;
      continue;
    }
    int node;
    double a, b, z;
    if (in && sscanf(line, "%d %lf %lf %lf", &node, &a, &b, &z) == 4) {
      *uz = z, *time = t, got = 1, in = 0;
    }
  }
  fclose(f);
  return got ? 0 : PALP_EPARSE;
}

int main(int argc, char **argv) {
  const char *levels = "1,2", *profile = "paper_long_term", *dir = "out/ccx", *ccx = "ccx";
  double force = 3.0, inc = 0.25, timeout = 0.0, area = 5.2e-4, grading = 1.0;
  int no_project = 0, no_ccx = 0, quarter = 0, palp_inc = 4, ccx_threads = 2;
  for (int i = 1; i < argc; ++i) {
    if (i + 1 < argc && !strcmp(argv[i], "--levels")) levels = argv[++i];
    else if (i + 1 < argc && !strcmp(argv[i], "--profile")) profile = argv[++i];
    else if (i + 1 < argc && !strcmp(argv[i], "--force")) force = atof(argv[++i]);
    else if (i + 1 < argc && !strcmp(argv[i], "--dir")) dir = argv[++i];
    else if (i + 1 < argc && !strcmp(argv[i], "--ccx")) ccx = argv[++i];
    else if (i + 1 < argc && !strcmp(argv[i], "--ccx-inc")) inc = atof(argv[++i]);
    else if (i + 1 < argc && !strcmp(argv[i], "--ccx-timeout")) timeout = atof(argv[++i]);
    else if (!strcmp(argv[i], "--ccx-only")) no_project = 1;
    else if (!strcmp(argv[i], "--palp-only")) no_ccx = 1;
    else if (!strcmp(argv[i], "--ccx-quarter")) quarter = 1;
    else if (i + 1 < argc && !strcmp(argv[i], "--palp-inc")) palp_inc = atoi(argv[++i]);
    else if (i + 1 < argc && !strcmp(argv[i], "--cap-area")) area = atof(argv[++i]);
    else if (i + 1 < argc && !strcmp(argv[i], "--grading")) grading = atof(argv[++i]);
    else if (i + 1 < argc && !strcmp(argv[i], "--ccx-threads")) ccx_threads = atoi(argv[++i]);
    else {
      fprintf(stderr, "usage: ccx_crosscheck [--levels 1,2,3] [--profile NAME] [--force N] [--dir DIR] [--ccx PATH] "
                      "[--ccx-only | --palp-only] [--ccx-inc FRACTION] [--ccx-timeout SECONDS] [--ccx-quarter] [--palp-inc K] "
                      "[--cap-area M2] [--grading ALPHA] [--ccx-threads N]\n");
      return 2;
    }
  }
  if (no_project && no_ccx) {
    fprintf(stderr, "ccx_crosscheck: --ccx-only and --palp-only exclude each other\n");
    return 2;
  }
  if (!(inc > 0.0) || inc > 1.0 || timeout < 0.0 || timeout != timeout || palp_inc < 1 || palp_inc > 1000 ||
      ccx_threads < 1 || ccx_threads > 64) {
    fprintf(stderr, "ccx_crosscheck: --ccx-inc must be in (0, 1], --ccx-timeout >= 0 s, --palp-inc in 1..1000, --ccx-threads in 1..64\n");
    return 2;
  }
  if (!(area >= 1e-6 && area <= 5.2e-4) || !(grading > 0.0 && grading <= 1.0)) {
    fprintf(stderr, "ccx_crosscheck: --cap-area must be in [1e-6, 5.2e-4] m^2, --grading in (0, 1]\n");
    return 2;
  }
  if (!(force > 0.0) || force > 100.0) {
    fprintf(stderr, "ccx_crosscheck: --force must be in (0, 100] N\n");
    return 2;
  }
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "mkdir -p '%s'", dir);
  if (system(cmd) != 0) return 1;
  char err[200];
  palp_fem_config cfg = palp_fem_default_config();
  if (palp_fem_config_set_material(&cfg, profile, err, sizeof err)) {
    fprintf(stderr, "ccx_crosscheck: %s\n", err);
    return 2;
  }
  printf("a cap at the pole (5.2 cm^2: distribution II), %.3g N over %.3g cm^2, mesh grading %.2g at the pole, "
         "relaxed, profile %s (gel C10 %.4g Pa, D1 %.3g 1/Pa; membrane C10 %.4g Pa)\n",
         force, 1e4 * area, grading, profile, relaxed_c10(&cfg, &cfg.gel), cfg.gel.d1, relaxed_c10(&cfg, &cfg.membrane));
  /* the first eight columns are what tests/fem/test_ccx.sh reads */
  printf("%5s %8s %14s %8s %8s %14s %8s %9s %8s %8s %7s\n", "level", "hexa", "palp uz [mm]", "wall s", "nodes20",
         "ccx uz [mm]", "wall s", "ccx/palp", "palp MiB", "ccx MiB", "newton");
  int fail = 0;
  for (const char *l = levels; *l;) {
    const int L = (int)strtol(l, (char **)&l, 10);
    if (*l == ',') ++l;
    /* palp's level 8 (87,040 hexahedra) peaks at 5 GB; level 9 would take ~8-9 GB of a shared
     * 23 GB machine. ccx's quadratic deck is far larger still (its level 5 quarter: 1.5 GB). */
    if (L < 1 || L > 8) {
      fprintf(stderr, "ccx_crosscheck: level %d out of 1..8\n", L);
      return 2;
    }
    cfg.mesh.level = L;
    cfg.mesh.grading = grading;
    palp_fem_mesh mesh;
    if (palp_fem_mesh_create(&cfg.mesh, &mesh)) return 1;
    double uz_p = NAN, tp = 0, mb_p = NAN, mb_c = NAN;
    int newton = 0;
    if (!no_project) {
      palp_fem_model m;
      if (palp_fem_model_create(&m, &mesh, &cfg) || palp_fem_model_finalize(&m)) return 1;
      m.max_newton = 40;
      double *f = calloc((size_t)m.ndof, sizeof(double));
      palp_fem_cap_traction(&mesh, force, area, 6, f);
      const double t0 = now_s();
      if (palp_fem_solve_static(&m, f, palp_inc, INFINITY) == 0) uz_p = m.u[3 * mesh.top_node + 2];
      else {
        fprintf(stderr, "ccx_crosscheck: palp level %d: %s\n", L, m.err);
        fail = 1; /* a palp solve that fails is a failed run, as a ccx one is (exit 0 until session 82) */
      }
      tp = now_s() - t0;
      newton = m.newton_iterations;
      struct rusage ru;
      if (getrusage(RUSAGE_SELF, &ru) == 0) mb_p = (double)ru.ru_maxrss / 1024.0; /* Linux: kB */
      free(f);
      palp_fem_model_destroy(&m);
    }
    double uz_c = NAN, tc = 0;
    int nq = 0;
    if (!no_ccx) {
      quad_mesh q;
      if (quad_create(&mesh, &q)) return 1;
      double *fz = malloc(sizeof(double) * (size_t)(q.n + 64));
      if (!fz || quad_load(&mesh, &q, force, area, quarter, fz)) return 1;
      char job[1024], path[1100], lim[64] = "";
      snprintf(job, sizeof job, "%s/level%d_%s", dir, L, profile);
      snprintf(path, sizeof path, "%s.inp", job);
      if (write_inp(path, &mesh, &q, fz, &cfg, profile, L, inc, quarter, &nq)) {
        fprintf(stderr, "ccx_crosscheck: cannot write %s\n", path);
        return 1;
      }
      if (timeout > 0.0) snprintf(lim, sizeof lim, "timeout %.0f ", timeout);
      /* SPOOLES is the only direct solver in Debian's build; CCX_NPROC_EQUATION_SOLVER lets it use
       * both cores (OMP_NUM_THREADS alone leaves it on one). The test runs it on one thread
       * (--ccx-threads 1): two threads beside other work spin and took 4x as long. */
      snprintf(cmd, sizeof cmd,
               "cd '%s' && OMP_NUM_THREADS=%d CCX_NPROC_EQUATION_SOLVER=%d %s'%s' -i 'level%d_%s' > 'level%d_%s.log' 2>&1",
               dir, ccx_threads, ccx_threads, lim, ccx, L, profile, L, profile);
      const double t1 = now_s();
      const int st = system(cmd);
      tc = now_s() - t1;
      struct rusage ru;
      if (getrusage(RUSAGE_CHILDREN, &ru) == 0) mb_c = (double)ru.ru_maxrss / 1024.0;
      snprintf(path, sizeof path, "%s.dat", job);
      double tdone = NAN;
      if (st != 0 || read_top_uz(path, &uz_c, &tdone) || !(fabs(tdone - 1.0) <= 1e-6)) {
        fprintf(stderr, "ccx_crosscheck: ccx failed at level %d (exit %d%s): see %s.log\n", L, st,
                WIFEXITED(st) && WEXITSTATUS(st) == 124 ? ", timed out" : "", job);
        uz_c = NAN; /* a .dat from an unfinished run holds an intermediate increment, not the answer */
        fail = 1;
      }
      free(fz);
      quad_destroy(&q);
    }
    printf("%5d %8d %14.4f %8.1f %8d %14.4f %8.1f %9.4f %8.0f %8.0f %7d\n", L, mesh.element_count, 1e3 * uz_p, tp, nq,
           1e3 * uz_c, tc, uz_c / uz_p, mb_p, mb_c, newton);
    fflush(stdout);
    palp_fem_mesh_destroy(&mesh);
  }
  return fail;
}
