/*
 * bench_profiles - the relaxed (long-term) pole displacement of each material
 * profile under distribution II (docs/materials.md): a uniform vertical pressure
 * over the 5.2 cm^2 cap around the pole, total F, solved statically with the
 * relaxed moduli (dt = infinity) at each refinement level.
 *
 *   bench_profiles [--levels 1,2,3] [--force N] [--increments K] [--profiles a,b]
 *
 * Prints per profile and level: elements, pole uz [mm], lowest node z [mm] (the
 * base plane is z = 0), Newton residual count and wall time. Built, not run by
 * CTest (level 3 and beyond take tens of seconds to minutes on the shared VM).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fem_internal.h"

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv) {
  const char *levels = "1,2,3", *profiles = "paper_long_term,breast_tissue,paper_instantaneous";
  double force = 3.0;
  int increments = 0;
  for (int i = 1; i < argc; ++i) {
    if (i + 1 < argc && strcmp(argv[i], "--levels") == 0) levels = argv[++i];
    else if (i + 1 < argc && strcmp(argv[i], "--force") == 0) force = atof(argv[++i]);
    else if (i + 1 < argc && strcmp(argv[i], "--increments") == 0) increments = atoi(argv[++i]);
    else if (i + 1 < argc && strcmp(argv[i], "--profiles") == 0) profiles = argv[++i];
    else {
      fprintf(stderr, "usage: bench_profiles [--levels 1,2,3] [--force N] [--increments K] [--profiles a,b]\n");
      return 2;
    }
  }
  if (!(force > 0.0) || force > 100.0) {
    fprintf(stderr, "bench_profiles: --force must be in (0, 100] N\n");
    return 2;
  }
  printf("distribution II at the pole, %.3g N over 5.2 cm^2, relaxed (static, dt = inf)\n", force);
  printf("%-20s %5s %8s %12s %14s %7s %8s\n", "profile", "level", "hexa", "pole uz mm", "lowest z mm", "newton", "wall s");
  char plist[256];
  snprintf(plist, sizeof plist, "%s", profiles);
  for (char *ps = strtok(plist, ","); ps; ps = strtok(NULL, ",")) {
    char err[200];
    palp_fem_config cfg = palp_fem_default_config();
    if (palp_fem_config_set_material(&cfg, ps, err, sizeof err)) {
      fprintf(stderr, "bench_profiles: %s\n", err);
      return 2;
    }
    for (const char *l = levels; *l;) {
      const int L = (int)strtol(l, (char **)&l, 10);
      if (*l == ',') ++l;
      if (L < 1 || L > 8) {
        fprintf(stderr, "bench_profiles: level %d out of 1..8\n", L);
        return 2;
      }
      cfg.mesh.level = L;
      palp_fem_mesh mesh;
      if (palp_fem_mesh_create(&cfg.mesh, &mesh)) return 1;
      palp_fem_model m;
      if (palp_fem_model_create(&m, &mesh, &cfg) || palp_fem_model_finalize(&m)) return 1;
      m.max_newton = 40;
      double *f = calloc((size_t)m.ndof, sizeof(double));
      palp_fem_cap_traction(&mesh, force, 5.2e-4, 2, f); /* 2 x 2 points: the figures in docs/materials.md */
      /* the soft profiles deform far: more load increments keep Newton in reach */
      const int inc = increments > 0 ? increments : (strcmp(ps, "paper_instantaneous") == 0 ? 20 : 4);
      const double t0 = now_s();
      const int rc = palp_fem_solve_static(&m, f, inc, INFINITY);
      double zmin = INFINITY;
      for (int n = 0; n < mesh.node_count; ++n) zmin = fmin(zmin, mesh.x[n][2] + m.u[3 * n + 2]);
      if (rc) printf("%-20s %5d %8d failed: %s\n", ps, L, mesh.element_count, m.err);
      else
        printf("%-20s %5d %8d %12.4f %14.4f %7d %8.2f\n", ps, L, mesh.element_count, 1e3 * m.u[3 * mesh.top_node + 2],
               1e3 * zmin, (int)m.newton_iterations, now_s() - t0);
      fflush(stdout);
      free(f);
      palp_fem_model_destroy(&m);
      palp_fem_mesh_destroy(&mesh);
    }
  }
  return 0;
}
