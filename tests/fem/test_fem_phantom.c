/*
 * test_fem_phantom.c - the FE reference on the phantom itself: mesh sanity, the
 * surface map, Newton's quadratic convergence, and convergence under time-step
 * halving and mesh refinement. Usage: test_fem_phantom <case>.
 */
#include <time.h>

#include "fem_test.h"

/* Nodal forces [N] of a vertical traction t(x) = -q0 exp(-r^2 / s^2) e_z on the
 * outer surface (r: distance from the axis), integrated with 2x2 Gauss points on
 * every surface face; q0 = F / (pi s^2) makes the total about F for s << R. */
static void cap_load(const palp_fem_mesh *mesh, double F, double s, double *f) {
  int (*faces)[4], nf;
  palp_fem_surface_faces(mesh, &faces, &nf);
  memset(f, 0, sizeof(double) * 3 * (size_t)mesh->node_count);
  const double q0 = F / (PALP_FEM_PI * s * s), g = 0.57735026918962576451;
  static const double sg[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (int k = 0; k < nf; ++k)
    for (int q = 0; q < 4; ++q) {
      const double xi = g * sg[q][0], eta = g * sg[q][1];
      double N[4], X[3] = {0}, Xa[3] = {0}, Xb[3] = {0};
      for (int a = 0; a < 4; ++a) {
        N[a] = 0.25 * (1 + sg[a][0] * xi) * (1 + sg[a][1] * eta);
        const double da = 0.25 * sg[a][0] * (1 + sg[a][1] * eta), db = 0.25 * sg[a][1] * (1 + sg[a][0] * xi);
        for (int d = 0; d < 3; ++d) {
          X[d] += N[a] * mesh->x[faces[k][a]][d];
          Xa[d] += da * mesh->x[faces[k][a]][d];
          Xb[d] += db * mesh->x[faces[k][a]][d];
        }
      }
      const double n[3] = {Xa[1] * Xb[2] - Xa[2] * Xb[1], Xa[2] * Xb[0] - Xa[0] * Xb[2], Xa[0] * Xb[1] - Xa[1] * Xb[0]};
      const double dA = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      const double t = -q0 * exp(-(X[0] * X[0] + X[1] * X[1]) / (s * s));
      for (int a = 0; a < 4; ++a) f[3 * faces[k][a] + 2] += N[a] * t * dA;
    }
  free(faces);
}

/* The level-L mesh and the 3 N cap load (s = 1 cm) on it, the setup of the factor
 * reuse and background cases; the caller frees the load and destroys the mesh. */
static double *capped_mesh(int level, palp_fem_mesh *mesh) {
  palp_fem_mesh_def d = palp_fem_mesh_default_def();
  d.level = level;
  CHECK(palp_fem_mesh_create(&d, mesh) == 0, "mesh, level %d", level);
  double *f = calloc(3 * (size_t)mesh->node_count, sizeof(double));
  CHECK(f != NULL, "load vector");
  cap_load(mesh, 3.0, 0.01, f);
  return f;
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Level 1..4 element counts are 224, 1408, 4320, 10496 (2n x 2n x n core cells
 * plus 12 n^2 columns of 2n + L_m layers, n = 2 level); every element has positive
 * volume; the mesh volume is the hemisphere's 2/3 pi R^3, and the membrane's
 * 2/3 pi (R^3 - (R - t)^3), within the faceting error of flat faces, which falls as
 * h^2: tolerance 7% / level^2; the base is z = 0. */
static void test_mesh(void) {
  const int expect[4] = {224, 1408, 4320, 10496};
  for (int L = 1; L <= 4; ++L) {
    palp_fem_mesh_def d = palp_fem_mesh_default_def();
    d.level = L;
    palp_fem_mesh m;
    CHECK(palp_fem_mesh_create(&d, &m) == 0, "mesh level %d", L);
    CHECK(m.element_count == expect[L - 1], "level %d: %d elements, expected %d", L, m.element_count, expect[L - 1]);
    double vol = 0.0, vm = 0.0, vmin = INFINITY;
    for (int e = 0; e < m.element_count; ++e) {
      const double v = palp_fem_element_volume(&m, e);
      vol += v;
      vmin = fmin(vmin, v);
      if (m.region[e] == PALP_FEM_MEMBRANE) vm += v;
    }
    const double R = d.radius, t = d.membrane_thickness;
    const double vex = 2.0 / 3.0 * PALP_FEM_PI * R * R * R;
    const double vmex = 2.0 / 3.0 * PALP_FEM_PI * (R * R * R - (R - t) * (R - t) * (R - t));
    CHECK(vmin > 0.0, "level %d: smallest element volume %.3g m^3", L, vmin);
    const double tol = 0.07 / (L * L);
    CHECK(fabs(vol - vex) <= tol * vex, "level %d: volume %.6g m^3 vs %.6g (tolerance %.2g)", L, vol, vex, tol);
    CHECK(fabs(vm - vmex) <= tol * vmex, "level %d: membrane %.6g m^3 vs %.6g (tolerance %.2g)", L, vm, vmex, tol);
    CHECK(fabs(m.x[m.top_node][2] - R) < 1e-12, "level %d: top node at z = %.9g", L, m.x[m.top_node][2]);
    int nbase = 0;
    for (int n = 0; n < m.node_count; ++n) {
      nbase += m.fixed[n];
      if (m.fixed[n]) CHECK(fabs(m.x[n][2]) < 1e-15, "base node off z = 0");
    }
    printf("level %d: %d nodes, %d elements, volume %.4f%% off, membrane %.3f%% off, %d base nodes\n", L,
           m.node_count, m.element_count, 100 * (vol - vex) / vex, 100 * (vm - vmex) / vmex, nbase);
    palp_fem_mesh_destroy(&m);
  }
  /* The pole grading (mesh.grading): 1 gives the uniform lattice bit for bit; 0.5
   * puts the top's first surface node at the polar angle (pi/4) g(1/n), g(s) = s (a +
   * (1 - a) s^2), n = 2 level (the cube-to-sphere map sends lattice s to tan(pi/4 s)),
   * half the uniform cell's angle; the volume stays within 1% (the uniform lattice is
   * 0.42% under at level 4; the cube's edge cells, grown 3 - 2a = 2x in angle, facet
   * more: 0.60% measured). */
  palp_fem_mesh_def d = palp_fem_mesh_default_def();
  d.level = 4;
  palp_fem_mesh u, g1, g;
  CHECK(palp_fem_mesh_create(&d, &u) == 0, "uniform level 4");
  d.grading = 1.0;
  CHECK(palp_fem_mesh_create(&d, &g1) == 0, "grading 1");
  CHECK(u.node_count == g1.node_count && memcmp(u.x, g1.x, sizeof *u.x * (size_t)u.node_count) == 0,
        "grading 1: not the uniform lattice bit for bit");
  d.grading = 0.5;
  CHECK(palp_fem_mesh_create(&d, &g) == 0, "grading 0.5");
  d.grading = 1.5;
  palp_fem_mesh bad;
  CHECK(palp_fem_mesh_create(&d, &bad) == PALP_EINVAL, "grading 1.5 accepted");
  const int n = 8;
  const double s1 = 1.0 / n, want = 0.25 * PALP_FEM_PI * s1 * (0.5 + 0.5 * s1 * s1);
  double got = INFINITY, vol = 0.0, vmin = INFINITY;
  for (int k = 0; k < g.node_count; ++k) { /* the surface node nearest the top in the y = 0 plane, x > 0 */
    const double *x = g.x[k], r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    if (fabs(x[1]) > 1e-12 || x[0] <= 1e-9 || fabs(r - d.radius) > 1e-9) continue;
    got = fmin(got, atan2(x[0], x[2]));
  }
  for (int e = 0; e < g.element_count; ++e) {
    const double v = palp_fem_element_volume(&g, e);
    vol += v, vmin = fmin(vmin, v);
  }
  const double vex = 2.0 / 3.0 * PALP_FEM_PI * d.radius * d.radius * d.radius;
  CHECK(fabs(got - want) < 1e-9, "grading 0.5: first node at %.6f deg, expected %.6f", got * 180 / PALP_FEM_PI,
        want * 180 / PALP_FEM_PI);
  CHECK(vmin > 0.0 && fabs(vol - vex) <= 0.01 * vex, "grading 0.5: volume %.4f%% off, smallest element %.3g m^3",
        100 * (vol - vex) / vex, vmin);
  printf("grading 0.5, level 4: first cell %.3f deg (uniform %.3f), volume %.4f%% off\n", got * 180 / PALP_FEM_PI,
         45.0 * s1, 100 * (vol - vex) / vex);
  palp_fem_mesh_destroy(&u), palp_fem_mesh_destroy(&g1), palp_fem_mesh_destroy(&g);
  /* The fingertip's other sites: the spot at 45 / 60 / 70 deg in the x-z plane. Along the
   * meridian y = 0 the surface nodes within 4 deg of the spot are 0.4-0.7 of the uniform
   * cell apart (alpha 0.5 at the spot, which need not be a lattice point; at 70 deg the
   * base is 20 deg away, so g' grows fastest there: 0.64 measured); valid elements, the
   * volume within 1%. */
  const double sites[3] = {45.0, 60.0, 70.0};
  for (int q = 0; q < 3; ++q) {
    d.grading = 0.5, d.grading_polar_deg = sites[q];
    CHECK(palp_fem_mesh_create(&d, &g) == 0, "grading at %.0f deg", sites[q]);
    double th[256];
    int nth = 0;
    for (int k = 0; k < g.node_count && nth < 256; ++k) {
      const double *x = g.x[k], r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
      if (fabs(x[1]) > 1e-12 || x[0] < 0.0 || fabs(r - d.radius) > 1e-9) continue;
      th[nth++] = atan2(x[0], x[2]) * 180.0 / PALP_FEM_PI;
    }
    for (int a = 1; a < nth; ++a) /* insertion sort: ~33 angles */
      for (int b = a; b > 0 && th[b - 1] > th[b]; --b) {
        const double tmp = th[b];
        th[b] = th[b - 1], th[b - 1] = tmp;
      }
    double gmin = INFINITY, gmax = 0.0;
    for (int a = 1; a < nth; ++a) {
      const double mid = 0.5 * (th[a] + th[a - 1]);
      if (fabs(mid - sites[q]) > 4.0) continue;
      gmin = fmin(gmin, th[a] - th[a - 1]), gmax = fmax(gmax, th[a] - th[a - 1]);
    }
    vol = 0.0, vmin = INFINITY;
    for (int e = 0; e < g.element_count; ++e) {
      const double v = palp_fem_element_volume(&g, e);
      vol += v, vmin = fmin(vmin, v);
    }
    CHECK(gmin >= 0.4 * 45.0 * s1 && gmax <= 0.7 * 45.0 * s1, "grading at %.0f deg: meridian cells %.3f-%.3f deg near it "
          "(uniform %.3f)", sites[q], gmin, gmax, 45.0 * s1);
    CHECK(vmin > 0.0 && fabs(vol - vex) <= 0.01 * vex, "grading at %.0f deg: volume %.4f%% off, smallest %.3g m^3",
          sites[q], 100 * (vol - vex) / vex, vmin);
    printf("grading 0.5 at %.0f deg: meridian cells %.3f-%.3f deg within 4 deg of it, volume %.4f%% off\n", sites[q], gmin,
           gmax, 100 * (vol - vex) / vex);
    palp_fem_mesh_destroy(&g);
  }
}

/* The surface map: points on the R = 4 cm sphere (a spiral of 400 directions over
 * the dome, rim included) map onto a face with weights summing to 1, and the mapped
 * point lies on the ray through the point (1e-9 m) within the faceting sagitta
 * (0.5 mm at level 2, R (1 - cos(half a face's angle))) of the sphere. */
static void test_map(void) {
  palp_fem_mesh_def d = palp_fem_mesh_default_def();
  d.level = 2;
  palp_fem_mesh m;
  CHECK(palp_fem_mesh_create(&d, &m) == 0, "mesh");
  enum { NP = 400 };
  palp_vec3 p[NP];
  for (int i = 0; i < NP; ++i) {
    const double z = (double)i / (NP - 1), rho = sqrt(1 - z * z), ph = 2.399963229728653 * i;
    p[i] = (palp_vec3){0.04 * rho * cos(ph), 0.04 * rho * sin(ph), 0.04 * z};
  }
  palp_fem_map map;
  CHECK(palp_fem_map_create(&m, p, NP, &map) == 0, "map");
  double worst_ray = 0.0, worst_rad = 0.0, worst_w = 0.0;
  for (int i = 0; i < NP && map.count == NP; ++i) {
    double X[3] = {0}, ws = 0.0;
    for (int k = 0; k < 4; ++k) {
      ws += map.w[map.start[i] + k];
      for (int dd = 0; dd < 3; ++dd) X[dd] += map.w[map.start[i] + k] * m.x[map.node[map.start[i] + k]][dd];
      CHECK(map.w[map.start[i] + k] >= -1e-12, "negative weight");
    }
    const double u[3] = {p[i].x / 0.04, p[i].y / 0.04, p[i].z / 0.04};
    const double c[3] = {X[1] * u[2] - X[2] * u[1], X[2] * u[0] - X[0] * u[2], X[0] * u[1] - X[1] * u[0]};
    worst_ray = fmax(worst_ray, sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]));
    worst_rad = fmax(worst_rad, fabs(sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2]) - 0.04));
    worst_w = fmax(worst_w, fabs(ws - 1.0));
  }
  CHECK(worst_w <= 1e-12, "map: weights sum off 1 by %.3g", worst_w);
  CHECK(worst_ray <= 1e-9, "map: mapped points off the ray by %.3g m (tolerance 1e-9 m)", worst_ray);
  CHECK(worst_rad <= 5e-4, "map: mapped points %.3g m inside the sphere (tolerance 0.5 mm)", worst_rad);
  printf("map: %d points, off-ray %.2g m, sagitta %.3g mm\n", NP, worst_ray, 1e3 * worst_rad);
  palp_fem_map_destroy(&map);
  palp_fem_mesh_destroy(&m);
}

/* The patch map (the default load map): every free vertex of the shipped 338-vertex
 * dome spreads over FE nodes with non-negative weights summing to 1 (1e-12), so a
 * vertex load keeps its resultant; rim vertices, clamped in the real-time model, map
 * to nothing; the weights' centroid sits on the vertex (its hat function is centred
 * there, up to the FE faces' size): within 0.3 of the vertex's shortest edge
 * (measured 0.21 at level 2, whose faces are about a real-time edge across); and the
 * patch stays in the vertex's one-ring widened by one FE face: no weighted node
 * farther from the vertex than its longest edge plus the largest surface face
 * diagonal (measured up to 2.4 longest edges). And the configurations: the patch by
 * default and for paper_long_term and breast_tissue (since it integrates with HHT), the
 * point for paper_instantaneous and its c10_reading alias, an explicit "load_map" over
 * both, a bad value an error. */
static void test_map_patch(void) {
  palp_fem_mesh_def d = palp_fem_mesh_default_def();
  d.level = 2;
  palp_fem_mesh m;
  CHECK(palp_fem_mesh_create(&d, &m) == 0, "mesh");
  palp_mesh_def rd = palp_mesh_default_def();
  palp_mesh rt;
  CHECK(palp_mesh_create(&rd, &rt) == 0, "real-time mesh");
  palp_fem_map map;
  CHECK(palp_fem_map_create_patch(&m, &rt, &map) == 0, "patch map");
  double *emin = malloc(sizeof(double) * (size_t)rt.vertex_count), *emax = malloc(sizeof(double) * (size_t)rt.vertex_count);
  for (int v = 0; v < rt.vertex_count; ++v) emin[v] = INFINITY, emax[v] = 0.0;
  for (int l = 0; l < rt.link_count; ++l) {
    const palp_vec3 a = rt.rest[rt.link[l][0]], b = rt.rest[rt.link[l][1]];
    const double len = sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
    for (int k = 0; k < 2; ++k) {
      emin[rt.link[l][k]] = fmin(emin[rt.link[l][k]], len);
      emax[rt.link[l][k]] = fmax(emax[rt.link[l][k]], len);
    }
  }
  int (*faces)[4] = NULL, nf = 0;
  CHECK(palp_fem_surface_faces(&m, &faces, &nf) == 0, "surface faces");
  double diag = 0.0; /* the largest surface face diagonal [m] */
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 2; ++k) {
      const double *a = m.x[faces[f][k]], *b = m.x[faces[f][k + 2]];
      diag = fmax(diag, sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2])));
    }
  free(faces);
  double worst_w = 0.0, worst_c = 0.0, worst_r = 0.0, worst_reach = 0.0, min_w = 0.0;
  int rim_mapped = 0, free_empty = 0, nodes = 0;
  for (int v = 0; v < rt.vertex_count && map.count == rt.vertex_count; ++v) {
    const int n = map.start[v + 1] - map.start[v];
    if (rt.fixed[v]) {
      rim_mapped += n > 0;
      continue;
    }
    free_empty += n == 0;
    nodes = n > nodes ? n : nodes;
    double ws = 0.0, c[3] = {0, 0, 0};
    const double p[3] = {rt.rest[v].x, rt.rest[v].y, rt.rest[v].z};
    for (int k = map.start[v]; k < map.start[v + 1]; ++k) {
      ws += map.w[k];
      min_w = fmin(min_w, map.w[k]);
      const double *x = m.x[map.node[k]];
      for (int dd = 0; dd < 3; ++dd) c[dd] += map.w[k] * x[dd];
      if (map.w[k] > 0.0) {
        const double r = sqrt((x[0] - p[0]) * (x[0] - p[0]) + (x[1] - p[1]) * (x[1] - p[1]) + (x[2] - p[2]) * (x[2] - p[2]));
        worst_r = fmax(worst_r, r / emax[v]);
        worst_reach = fmax(worst_reach, r / (emax[v] + diag));
      }
    }
    worst_w = fmax(worst_w, fabs(ws - 1.0));
    /* the centroid's offset across the ray through the vertex (it lies inside the
     * sphere by the patch's sagitta, which is not an offset) */
    const double lp = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    const double u[3] = {p[0] / lp, p[1] / lp, p[2] / lp};
    const double cu = c[0] * u[0] + c[1] * u[1] + c[2] * u[2];
    const double off[3] = {c[0] - cu * u[0], c[1] - cu * u[1], c[2] - cu * u[2]};
    worst_c = fmax(worst_c, sqrt(off[0] * off[0] + off[1] * off[1] + off[2] * off[2]) / emin[v]);
  }
  CHECK(map.count == rt.vertex_count, "patch map: %d vertices mapped of %d", map.count, rt.vertex_count);
  CHECK(rim_mapped == 0, "patch map: %d rim vertices map to FE nodes (expected none)", rim_mapped);
  CHECK(free_empty == 0, "patch map: %d free vertices without a patch", free_empty);
  CHECK(worst_w <= 1e-12, "patch map: weights sum off 1 by %.3g", worst_w);
  CHECK(min_w >= 0.0, "patch map: negative weight %.3g", min_w);
  CHECK(worst_c <= 0.3, "patch map: a patch's centroid %.3f of the shortest edge off its vertex (bound 0.3)", worst_c);
  CHECK(worst_reach <= 1.0, "patch map: a weighted node %.2f x (longest edge + face diagonal %.1f mm) from its vertex",
        worst_reach, 1e3 * diag);
  printf("patch map: up to %d nodes a vertex, centroid offset <= %.3f shortest edge, reach <= %.2f longest edge "
         "(%.2f of the bound)\n", nodes, worst_c, worst_r, worst_reach);
  free(emin);
  free(emax);
  palp_fem_map_destroy(&map);
  palp_mesh_destroy(&rt);
  palp_fem_mesh_destroy(&m);
  /* which map a configuration reads: the patch by default and for the sound profiles,
   * the point for the paper's literal reproduction, an explicit key over either */
  static const struct {
    const char *json;
    int want; /* palp_fem_load_map, or -1 for a parse error naming load_map */
  } cases[] = {{"{}", PALP_FEM_LOAD_PATCH},
               {"{\"material\":\"paper_instantaneous\"}", PALP_FEM_LOAD_POINT},
               {"{\"c10_reading\":\"instantaneous\"}", PALP_FEM_LOAD_POINT},
               {"{\"material\":\"breast_tissue\"}", PALP_FEM_LOAD_PATCH},
               {"{\"material\":\"paper_instantaneous\",\"load_map\":\"patch\"}", PALP_FEM_LOAD_PATCH},
               {"{\"load_map\":\"point\"}", PALP_FEM_LOAD_POINT},
               {"{\"load_map\":\"nodes\"}", -1},
               {"{\"load_map\":1}", -1}};
  for (size_t i = 0; i < sizeof cases / sizeof *cases; ++i) {
    palp_fem_config cfg = palp_fem_default_config();
    char err[256] = "";
    const int rc = palp_fem_config_parse(cases[i].json, &cfg, err, sizeof err);
    if (cases[i].want < 0)
      CHECK(rc != 0 && strstr(err, "load_map"), "config %s: expected an error naming load_map, got %d '%s'", cases[i].json,
            rc, err);
    else
      CHECK(rc == 0 && (int)cfg.load_map == cases[i].want, "config %s: load_map %d, expected %d (%s)", cases[i].json,
            (int)cfg.load_map, cases[i].want, err);
  }
}

/* Newton's convergence order q = log(r_k+1 / r_k) / log(r_k / r_k-1), away from the
 * round-off floor (1e-10 r0), with the tangent factored every iteration:
 * (a) a distorted, compressible 3x3x3 block stretched to 1.15 in one increment
 *     (strongly nonlinear): q must reach 1.8 (quadratic: 2);
 * (b) a 10 ms implicit step of the level-1 phantom (paper materials) under a 3 N
 *     top load: r must fall below 1e-8 r0 within 4 iterations (its round-off floor
 *     is ~2e-9 r0: K = 2 GPa against forces of newtons). */
static double best_order(const palp_fem_model *m) {
  double best = 0.0;
  printf("  residuals [N]:");
  for (int k = 0; k < m->trace_count; ++k) printf(" %.3e", m->trace[k]);
  printf("\n");
  for (int k = 1; k + 1 < m->trace_count; ++k) {
    if (m->trace[k + 1] < 1e-10 * m->trace[0]) break;
    const double q = log(m->trace[k + 1] / m->trace[k]) / log(m->trace[k] / m->trace[k - 1]);
    printf("  order at iteration %d: %.2f\n", k + 1, q);
    if (m->trace[k] < m->trace[k - 1]) best = fmax(best, q);
  }
  return best;
}

static void test_newton(void) {
  palp_fem_mesh block;
  block_mesh(&block, 3, 3, 3, 0.2);
  palp_fem_config cfg = elastic_config(1e5, 4e-6);
  cfg.full_newton = 1;
  palp_fem_model m;
  CHECK(palp_fem_model_create(&m, &block, &cfg) == 0, "model");
  for (int n = 0; n < block.node_count; ++n) {
    if (block.x[n][0] < 1e-12) palp_fem_model_prescribe(&m, n, 0, 0.0);
    if (block.x[n][0] > 1 - 1e-12) palp_fem_model_prescribe(&m, n, 0, 0.15);
    if (block.x[n][1] < 1e-12) palp_fem_model_prescribe(&m, n, 1, 0.0);
    if (block.x[n][2] < 1e-12) palp_fem_model_prescribe(&m, n, 2, 0.0);
  }
  CHECK(palp_fem_model_finalize(&m) == 0, "finalize");
  m.rtol = 1e-14;
  m.atol = 0.0;
  m.max_newton = 20;
  palp_fem_solve_static(&m, NULL, 1, INFINITY); /* stops at the round-off floor; the trace counts */
  printf("block stretched to 1.15:\n");
  const double qa = best_order(&m);
  CHECK(qa >= 1.8, "newton (block): best order %.2f (need >= 1.8)", qa);
  palp_fem_model_destroy(&m);
  free_block(&block);

  palp_fem_mesh_def d = palp_fem_mesh_default_def();
  d.level = 1;
  palp_fem_mesh mesh;
  CHECK(palp_fem_mesh_create(&d, &mesh) == 0, "mesh");
  cfg = palp_fem_default_config();
  cfg.c10_reading = PALP_FEM_C10_LONG_TERM;
  cfg.full_newton = 1;
  CHECK(palp_fem_model_create(&m, &mesh, &cfg) == 0, "model");
  CHECK(palp_fem_model_finalize(&m) == 0, "finalize");
  double *f = calloc((size_t)m.ndof, sizeof(double));
  f[3 * mesh.top_node + 2] = -3.0;
  m.rtol = 3e-9;
  m.atol = 0.0;
  m.max_cutbacks = 0;
  m.max_newton = 4;
  const int rc = palp_fem_step(&m, f, 0.01);
  printf("phantom, 10 ms step:\n");
  best_order(&m);
  CHECK(rc == 0, "newton (phantom): step failed: %s", m.err);
  CHECK(m.trace[m.trace_count - 1] <= 1e-8 * m.trace[0], "newton (phantom): final residual %.3g of %.3g",
        m.trace[m.trace_count - 1], m.trace[0]);
  free(f);
  palp_fem_model_destroy(&m);
  palp_fem_mesh_destroy(&mesh);
}

/* (Phantom tests use the long-term reading of C10, whose sub-millimetre response
 * keeps them fast; the verification is of the discretisation, not the reading.)
 * Top-node displacement at t = 40 ms of the level-1 phantom under a 3 N cap load
 * ramped over 30 ms, with dt = 4, 2, 1 ms: the differences between successive
 * halvings must shrink by at least a factor 2.5 (second order gives 4). */
static double run_dt(double dt, const palp_fem_mesh *mesh, const double *f3) {
  palp_fem_config cfg = palp_fem_default_config();
  cfg.c10_reading = PALP_FEM_C10_LONG_TERM;
  palp_fem_model m;
  palp_fem_model_create(&m, mesh, &cfg);
  palp_fem_model_finalize(&m);
  double *f = calloc((size_t)m.ndof, sizeof(double));
  const int steps = (int)lround(0.04 / dt);
  for (int s = 1; s <= steps; ++s) {
    const double t = s * dt, lam = t < 0.03 ? t / 0.03 : 1.0;
    for (int k = 0; k < m.ndof; ++k) f[k] = lam * f3[k];
    CHECK(palp_fem_step(&m, f, dt) == 0, "step: %s", m.err);
  }
  const double uz = m.u[3 * mesh->top_node + 2];
  free(f);
  palp_fem_model_destroy(&m);
  return uz;
}

static void test_dt(void) {
  palp_fem_mesh_def d = palp_fem_mesh_default_def();
  d.level = 1;
  palp_fem_mesh mesh;
  CHECK(palp_fem_mesh_create(&d, &mesh) == 0, "mesh");
  double *f3 = calloc((size_t)mesh.node_count * 3, sizeof(double));
  cap_load(&mesh, 3.0, 0.01, f3);
  const double u4 = run_dt(0.004, &mesh, f3), u2 = run_dt(0.002, &mesh, f3), u1 = run_dt(0.001, &mesh, f3);
  const double e1 = fabs(u4 - u2), e2 = fabs(u2 - u1);
  printf("dt: top uz at 40 ms = %.6f / %.6f / %.6f mm for dt = 4 / 2 / 1 ms; differences %.3g, %.3g mm (ratio %.2f)\n",
         1e3 * u4, 1e3 * u2, 1e3 * u1, 1e3 * e1, 1e3 * e2, e1 / e2);
  CHECK(e2 * 2.5 <= e1, "dt halving: differences %.3g then %.3g m (need a ratio >= 2.5)", e1, e2);
  free(f3);
  palp_fem_mesh_destroy(&mesh);
}

/* Relaxed static top displacement under the 3 N cap load at levels 1, 2, 3: the
 * change from each refinement to the next must shrink (ratio <= 0.7), and the
 * finest two agree within 15% (the membrane, two linear hex layers, stiffens coarse
 * meshes in bending, so the sequence converges from below). */
static void test_refine(void) {
  double u[3];
  for (int L = 1; L <= 3; ++L) {
    palp_fem_mesh_def d = palp_fem_mesh_default_def();
    d.level = L;
    palp_fem_mesh mesh;
    CHECK(palp_fem_mesh_create(&d, &mesh) == 0, "mesh");
    palp_fem_config cfg = palp_fem_default_config();
    cfg.c10_reading = PALP_FEM_C10_LONG_TERM;
    palp_fem_model m;
    palp_fem_model_create(&m, &mesh, &cfg);
    palp_fem_model_finalize(&m);
    double *f = calloc((size_t)m.ndof, sizeof(double));
    cap_load(&mesh, 3.0, 0.01, f);
    const double t0 = now();
    CHECK(palp_fem_solve_static(&m, f, 1, INFINITY) == 0, "level %d: %s", L, m.err);
    u[L - 1] = m.u[3 * mesh.top_node + 2];
    printf("refine: level %d (%d elements): top uz %.5f mm, %d Newton residuals, %.2f s\n", L, mesh.element_count,
           1e3 * u[L - 1], m.trace_count, now() - t0);
    free(f);
    palp_fem_model_destroy(&m);
    palp_fem_mesh_destroy(&mesh);
  }
  const double e1 = fabs(u[1] - u[0]), e2 = fabs(u[2] - u[1]);
  CHECK(e2 <= 0.7 * e1, "refinement: changes %.3g then %.3g m (need ratio <= 0.7)", e1, e2);
  CHECK(e2 <= 0.15 * fabs(u[2]), "refinement: levels 2 and 3 differ by %.3g of %.3g m (tolerance 15%%)", e2, u[2]);
}

/* Reusing the factor (automatic renewal, and the force-only assembly of an iterate
 * predicted to converge) changes only the Newton path, not the answer: the level-2
 * phantom under an unramped 3 N cap load (long-term reading), 40 steps of 10 ms,
 * against full Newton (a fresh factorisation at every iteration, no reuse) and
 * against a factor that is never renewed (pcg_refactor 1000). Every node's
 * displacement history agrees within 1e-4 of the largest displacement (the Newton
 * tolerance is rtol = 1e-4 of the force scale, and the response is linear in the
 * load to a few per cent); the automatic run both reuses and renews the factor, and
 * skips the tangent of converged iterates. */
typedef struct reuse_run {
  double *u;      /* [steps * ndof] displacement after every step [m] */
  long factorizations, newton, assemblies, tangents;
} reuse_run;

static int run_reuse(const palp_fem_mesh *mesh, const double *f, int full_newton, int pcg_refactor, int steps,
                     reuse_run *out) {
  palp_fem_config cfg = palp_fem_default_config();
  cfg.c10_reading = PALP_FEM_C10_LONG_TERM;
  cfg.full_newton = full_newton;
  cfg.pcg_refactor = pcg_refactor;
  palp_fem_model m;
  if (palp_fem_model_create(&m, mesh, &cfg) || palp_fem_model_finalize(&m)) return -1;
  out->u = malloc(sizeof(double) * (size_t)steps * (size_t)m.ndof);
  int rc = 0;
  for (int k = 0; k < steps && !rc; ++k) {
    rc = palp_fem_step(&m, f, 0.01);
    memcpy(out->u + (size_t)k * (size_t)m.ndof, m.u, sizeof(double) * (size_t)m.ndof);
  }
  out->factorizations = m.factorizations, out->newton = m.newton_iterations;
  out->assemblies = m.assemblies, out->tangents = m.tangent_assemblies;
  printf("reuse: full_newton %d, pcg_refactor %4d: %ld steps, %ld Newton iterations, %ld factorisations, %ld CG "
         "iterations, %ld assemblies (%ld with tangent)%s%s\n",
         full_newton, pcg_refactor, m.steps, m.newton_iterations, m.factorizations, m.pcg_iterations, m.assemblies,
         m.tangent_assemblies, rc ? ": " : "", rc ? m.err : "");
  palp_fem_model_destroy(&m);
  return rc;
}

static void test_reuse(void) {
  palp_fem_mesh mesh;
  double *f = capped_mesh(2, &mesh);
  const int steps = 40, nd = 3 * mesh.node_count;
  reuse_run a = {0}, b = {0}, c = {0};
  CHECK(run_reuse(&mesh, f, 0, 0, steps, &a) == 0, "automatic reuse run");
  CHECK(run_reuse(&mesh, f, 1, 0, steps, &b) == 0, "full Newton run");
  CHECK(run_reuse(&mesh, f, 0, 1000, steps, &c) == 0, "never-renewed run");
  double umax = 0.0, dab = 0.0, dcb = 0.0;
  for (size_t k = 0; k < (size_t)steps * (size_t)nd; ++k) {
    umax = fmax(umax, fabs(b.u[k]));
    dab = fmax(dab, fabs(a.u[k] - b.u[k]));
    dcb = fmax(dcb, fabs(c.u[k] - b.u[k]));
  }
  printf("reuse: largest displacement %.4f mm; automatic vs full Newton %.2e of it, never renewed vs full Newton "
         "%.2e\n", 1e3 * umax, dab / umax, dcb / umax);
  CHECK(umax > 0.0 && dab <= 1e-4 * umax, "automatic reuse vs full Newton: %.3g of the largest displacement "
        "(tolerance 1e-4)", dab / umax);
  CHECK(umax > 0.0 && dcb <= 1e-4 * umax, "never-renewed factor vs full Newton: %.3g of the largest displacement "
        "(tolerance 1e-4)", dcb / umax);
  CHECK(a.factorizations >= 2 && a.factorizations < steps, "automatic: the factor is renewed and reused (%ld "
        "factorisations in %d steps)", a.factorizations, steps);
  CHECK(b.factorizations == b.newton, "full Newton: a factorisation per iteration (%ld, %ld)", b.factorizations,
        b.newton);
  CHECK(a.assemblies > a.tangents && a.tangents >= a.newton, "automatic: converged iterates assembled without the "
        "tangent (%ld assemblies, %ld with tangent, %ld Newton iterations)", a.assemblies, a.tangents, a.newton);
  free(a.u), free(b.u), free(c.u);
  free(f);
  palp_fem_mesh_destroy(&mesh);
}

/* Background renewal of the factor (factor_lag) and the factor made in setup
 * (palp_fem_model_prefactor), level 2 under the 3 N cap load for 24 steps:
 * - the results do not depend on the thread's timing: a run whose background
 *   factorisations are made at once (the fastest thread), one where they are made
 *   only when installed (the slowest) and one with a real thread agree bit for bit;
 * - the background factor is installed (at least one renewal in 24 steps) and the
 *   run agrees with the foreground renewal (factor_lag 0) within 1e-4 of the
 *   largest displacement, the Newton tolerance (rtol 1e-4 of the force scale);
 * - a run whose first factorisation was made in setup is bit-identical to one
 *   that made it in its first step;
 * - a hard run (level 1, instantaneous reading, 5 steps: cut-backs) renews in the
 *   foreground: bit-identical with the default factor_lag and 0.
 * All with the default config's factor_lag (3 until 2026-12-02, 8 until 2026-12-03, 5 since). */
typedef struct bg_run {
  double *u; /* [steps * ndof] [m] */
  long factorizations, background, cutbacks;
} bg_run;

static int run_bg_reading(const palp_fem_mesh *mesh, const double *f, int lag, int mode, int prefactor, int steps,
                          palp_fem_c10_reading reading, bg_run *out) {
  palp_fem_config cfg = palp_fem_default_config();
  cfg.c10_reading = reading;
  cfg.factor_lag = lag;
  palp_fem_model m;
  if (palp_fem_model_create(&m, mesh, &cfg) || palp_fem_model_finalize(&m)) return -1;
  palp_fem_solver_set_background_mode(m.solver, mode);
  int rc = prefactor ? palp_fem_model_prefactor(&m, 0.01) : 0;
  out->u = malloc(sizeof(double) * (size_t)steps * (size_t)m.ndof);
  for (int k = 0; k < steps && !rc; ++k) {
    rc = palp_fem_step(&m, f, 0.01);
    memcpy(out->u + (size_t)k * (size_t)m.ndof, m.u, sizeof(double) * (size_t)m.ndof);
  }
  out->factorizations = m.factorizations, out->background = m.bg_factorizations, out->cutbacks = m.cutbacks;
  printf("background: factor_lag %d, mode %d, prefactor %d, %s: %ld Newton iterations, %ld CG iterations, %ld "
         "factorisations (%ld in the background), %ld cut-backs%s%s\n",
         lag, mode, prefactor, reading == PALP_FEM_C10_LONG_TERM ? "long-term" : "instantaneous", m.newton_iterations,
         m.pcg_iterations, m.factorizations, m.bg_factorizations, m.cutbacks, rc ? ": " : "", rc ? m.err : "");
  palp_fem_model_destroy(&m);
  return rc;
}

static int run_bg(const palp_fem_mesh *mesh, const double *f, int lag, int mode, int prefactor, int steps, bg_run *out) {
  return run_bg_reading(mesh, f, lag, mode, prefactor, steps, PALP_FEM_C10_LONG_TERM, out);
}

static void test_background(void) {
  palp_fem_mesh mesh;
  double *f = capped_mesh(2, &mesh);
  const int steps = 24, nd = 3 * mesh.node_count;
  const size_t bytes = sizeof(double) * (size_t)steps * (size_t)nd;
  bg_run fg = {0}, fast = {0}, slow = {0}, thr = {0}, pre = {0};
  /* the shipped lag (5 since 2026-12-03, docs/fem.md "The lag again"), whatever it is */
  const int lag = palp_fem_default_config().factor_lag;
  CHECK(lag > 0, "the default config renews on a background thread (factor_lag %d)", lag);
  CHECK(run_bg(&mesh, f, 0, 0, 0, steps, &fg) == 0, "foreground run");
  CHECK(run_bg(&mesh, f, 0, 0, 1, steps, &pre) == 0, "foreground run, factor made in setup");
  CHECK(run_bg(&mesh, f, lag, 1, 1, steps, &fast) == 0, "background run, at once");
  CHECK(run_bg(&mesh, f, lag, 2, 1, steps, &slow) == 0, "background run, when installed");
  CHECK(run_bg(&mesh, f, lag, 0, 1, steps, &thr) == 0, "background run, thread");
  if (fg.u && pre.u && fast.u && slow.u && thr.u) {
    CHECK(!memcmp(fg.u, pre.u, bytes), "the factor made in setup changed the results (tolerance: bit-identical)");
    CHECK(!memcmp(fast.u, slow.u, bytes) && !memcmp(fast.u, thr.u, bytes),
          "background renewal: the results depend on when the factorisation finished (tolerance: bit-identical)");
    double umax = 0.0, diff = 0.0;
    for (size_t k = 0; k < (size_t)steps * (size_t)nd; ++k) {
      umax = fmax(umax, fabs(fg.u[k]));
      diff = fmax(diff, fabs(thr.u[k] - fg.u[k]));
    }
    printf("background: largest displacement %.4f mm; background vs foreground renewal %.2e of it\n", 1e3 * umax,
           diff / umax);
    CHECK(umax > 0.0 && diff <= 1e-4 * umax, "background vs foreground renewal: %.3g of the largest displacement "
          "(tolerance 1e-4)", diff / umax);
  }
  CHECK(thr.background >= 1 && thr.background == fast.background && thr.background == slow.background,
        "background factorisations installed: %ld, %ld, %ld (need >= 1, the same in every mode)", thr.background,
        fast.background, slow.background);
  CHECK(fg.background == 0, "factor_lag 0 made %ld background factorisations", fg.background);
  free(fg.u), free(pre.u), free(fast.u), free(slow.u), free(thr.u);
  free(f);
  palp_fem_mesh_destroy(&mesh);

  /* a hard run (instantaneous reading, level 1: cut-backs, indefinite tangents)
   * renews in the foreground as before fem-frames: the same bits with the default
   * factor_lag as with 0 */
  f = capped_mesh(1, &mesh);
  const int hs = 5, hn = 3 * mesh.node_count;
  bg_run h0 = {0}, h3 = {0};
  CHECK(run_bg_reading(&mesh, f, 0, 0, 1, hs, PALP_FEM_C10_INSTANTANEOUS, &h0) == 0, "instantaneous, factor_lag 0");
  CHECK(run_bg_reading(&mesh, f, lag, 0, 1, hs, PALP_FEM_C10_INSTANTANEOUS, &h3) == 0, "instantaneous, default factor_lag");
  CHECK(h3.cutbacks > 0, "the instantaneous run was not hard (no cut-back): it tests nothing");
  CHECK(h0.u && h3.u && !memcmp(h0.u, h3.u, sizeof(double) * (size_t)hs * (size_t)hn) && h3.background == 0,
        "a run with cut-backs used background renewals (%ld) or changed (tolerance: bit-identical)", h3.background);
  free(h0.u), free(h3.u);
  free(f);
  palp_fem_mesh_destroy(&mesh);
}

/* The Krylov preconditioner's single-precision solve (palp_fem_solver_precond), on the
 * level-2 factor of K_eff at dt = 10 ms (the factor made in setup), against the double
 * solve with the same factor (CHOLMOD's), for three right-hand sides (the cap load, a
 * unit load on one free equation, a pseudo-random vector):
 * - it solves the same system: ||x_f - x|| <= 1e-5 ||x|| (measured 1.9-2.2e-7; L rounded to 2^-24 of itself
 *   perturbs the solution by about cond(L) 2^-24; the Krylov iteration needs it only
 *   as an SPD preconditioner, fem_solver.c);
 * - the AVX2 and the portable kernels give the same bits (bit-identical), so a run's
 *   results do not depend on the CPU's vector unit;
 * - it is not the double solve itself (some difference > 0), or the test would not see
 *   which path ran. */
static void test_precond(void) {
  palp_fem_mesh mesh;
  double *f = capped_mesh(2, &mesh);
  palp_fem_config cfg = palp_fem_default_config();
  cfg.cache_dir[0] = 0;
  palp_fem_model m;
  CHECK(palp_fem_model_create(&m, &mesh, &cfg) == 0 && palp_fem_model_finalize(&m) == 0, "model");
  CHECK(palp_fem_model_prefactor(&m, 0.01) == 0, "the factor of K_eff");
  const int n = m.nfree;
  double *b = malloc(sizeof(double) * 3 * (size_t)n), *x = b + n, *xf = x + n;
  double *xs = malloc(sizeof(double) * (size_t)n);
  CHECK(b && xs, "vectors");
  for (int rhs = 0; rhs < 3 && b && xs; ++rhs) {
    unsigned long long r = 0x9E3779B97F4A7C15ull;
    for (int i = 0; i < n; ++i) {
      r = r * 6364136223846793005ull + 1442695040888963407ull;
      b[i] = rhs == 0 ? 0.0 : rhs == 1 ? (i == n / 2) : (double)(r >> 11) / 9007199254740992.0 - 0.5;
    }
    if (rhs == 0)
      for (int d = 0; d < m.ndof; ++d)
        if (m.eq[d] >= 0) b[m.eq[d]] = f[d];
    CHECK(palp_fem_solver_solve(m.solver, b, x) == 0, "double solve");
    palp_fem_solver_set_precond_simd(m.solver, 1);
    CHECK(palp_fem_solver_precond(m.solver, b, xf) == 0, "single-precision solve");
    palp_fem_solver_set_precond_simd(m.solver, 0);
    CHECK(palp_fem_solver_precond(m.solver, b, xs) == 0, "single-precision solve, portable");
    double xn = 0.0, dn = 0.0;
    for (int i = 0; i < n; ++i) xn += x[i] * x[i], dn += (xf[i] - x[i]) * (xf[i] - x[i]);
    xn = sqrt(xn), dn = sqrt(dn);
    printf("precond: right-hand side %d: ||x_f - x|| / ||x|| = %.3e\n", rhs, dn / xn);
    CHECK(xn > 0.0 && dn <= 1e-5 * xn, "rhs %d: the single-precision solve is %.3g of ||x|| off (tolerance 1e-5)",
          rhs, dn / xn);
    CHECK(dn > 0.0, "rhs %d: the single-precision solve equals the double one bit for bit: not the float path", rhs);
    CHECK(!memcmp(xf, xs, sizeof(double) * (size_t)n), "rhs %d: AVX2 and portable kernels differ (tolerance: bit-identical)",
          rhs);
  }
  free(b), free(xs);
  palp_fem_model_destroy(&m);
  free(f);
  palp_fem_mesh_destroy(&mesh);
}

int main(int argc, char **argv) {
  const char *c = argc > 1 ? argv[1] : "all";
  const int all = strcmp(c, "all") == 0;
  if (all || !strcmp(c, "mesh")) test_mesh();
  if (all || !strcmp(c, "map")) test_map();
  if (all || !strcmp(c, "map_patch")) test_map_patch();
  if (all || !strcmp(c, "newton")) test_newton();
  if (all || !strcmp(c, "dt")) test_dt();
  if (all || !strcmp(c, "refine")) test_refine();
  if (all || !strcmp(c, "reuse")) test_reuse();
  if (all || !strcmp(c, "background")) test_background();
  if (all || !strcmp(c, "precond")) test_precond();
  if (fem_failures) fprintf(stderr, "%d check(s) failed\n", fem_failures);
  return fem_failures ? 1 : 0;
}
