/*
 * bench_fem_finger - the FE fingertip curve (palp_fem_finger_curve) by inexact
 * Newton on reused, shifted-where-indefinite factors, each depth started from the
 * secant prediction (static_reuse and predict, the default) against full Newton (a
 * factorisation per iteration, each depth from the last state; the baseline),
 * alternated in one process (docs/fem.md, "Inexact static Newton with shifted
 * factors" and "The secant start").
 *
 *   bench_fem_finger [--level 2] [--runs 3] [--site-deg 45] [--depth-mm 6] [--material breast_tissue]
 *
 * Prints each run's wall and process CPU seconds, the medians, the ratio of the
 * medians, and the largest relative difference between the two curves' forces.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../bench_util.h"
#include "fem_finger.h"

int main(int argc, char **argv) {
  int level = 2, runs = 3;
  double site_deg = 45.0, depth_mm = 6.0;
  const char *material = "breast_tissue";
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--level") && i + 1 < argc) level = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--runs") && i + 1 < argc) runs = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--site-deg") && i + 1 < argc) site_deg = atof(argv[++i]);
    else if (!strcmp(argv[i], "--depth-mm") && i + 1 < argc) depth_mm = atof(argv[++i]);
    else if (!strcmp(argv[i], "--material") && i + 1 < argc) material = argv[++i];
    else {
      fprintf(stderr, "usage: bench_fem_finger [--level 1..4] [--runs N] [--site-deg 0..70] [--depth-mm 0.25..30] "
                      "[--material NAME]\n");
      return 2;
    }
  }
  if (level < 1 || level > 4 || runs < 1 || runs > 20 || !(site_deg >= 0 && site_deg <= 70) ||
      !(depth_mm >= 0.25 && depth_mm <= 30)) {
    fprintf(stderr, "bench_fem_finger: level 1..4, runs 1..20, site 0..70 deg, depth 0.25..30 mm\n");
    return 2;
  }
  palp_fem_config cfg = palp_fem_default_config();
  char err[256];
  if (palp_fem_config_set_material(&cfg, material, err, sizeof err)) {
    fprintf(stderr, "bench_fem_finger: %s\n", err);
    return 2;
  }
  cfg.mesh.level = level;
  cfg.max_newton = 25; /* as palp-fem finger */
  palp_fem_mesh mesh;
  if (palp_fem_mesh_create(&cfg.mesh, &mesh)) {
    fprintf(stderr, "bench_fem_finger: mesh\n");
    return 1;
  }
  /* palp-fem finger's depth sequence, up to depth_mm */
  static const double seq[] = {0.25, 0.5, 0.75, 1,  1.5, 2,  2.5, 3,  4,  5,  6,  7,
                               8,    10,  12,   14, 16,  18, 20,  22, 24, 26, 28, 30};
  double depth[24];
  int nd = 0;
  for (int k = 0; k < 24 && seq[k] <= depth_mm + 1e-9; ++k) depth[nd++] = 1e-3 * seq[k];
  const double th = site_deg * PALP_FEM_PI / 180.0, n[3] = {sin(th), 0.0, cos(th)};
  printf("FE finger curve, level %d (%d hexahedra), %s, %.0f deg, %d depths to %.2f mm, %d runs of each mode\n",
         level, mesh.element_count, material, site_deg, nd, 1e3 * depth[nd - 1], runs);
  double wall[2][20], cpu[2][20], F[2][24], maxdiff = 0.0;
  long newton[2] = {0, 0};
  int rc = 0;
  for (int r = 0; r < runs && !rc; ++r)
    for (int mode = 0; mode < 2 && !rc; ++mode) { /* 0: full Newton (baseline), 1: static_reuse */
      palp_fem_config c = cfg;
      c.full_newton = mode == 0;
      const double w0 = palp_bench_clock_s(CLOCK_MONOTONIC), c0 = palp_bench_clock_s(CLOCK_PROCESS_CPUTIME_ID);
      const int done = palp_fem_finger_curve(&c, &mesh, NULL, 0, n, 0.008, depth, nd, INFINITY, F[mode], NULL,
                                             &newton[mode], NULL, NULL, err, sizeof err);
      wall[mode][r] = palp_bench_clock_s(CLOCK_MONOTONIC) - w0;
      cpu[mode][r] = palp_bench_clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0;
      if (done != nd) {
        fprintf(stderr, "bench_fem_finger: %s: %s\n", mode ? "static_reuse" : "full Newton", err);
        rc = 1;
        break;
      }
      printf("  run %d %-12s %7.2f s wall %7.2f s CPU, %ld Newton iterations, %.4f N at %.2f mm\n", r + 1,
             mode ? "static_reuse" : "full Newton", wall[mode][r], cpu[mode][r], newton[mode], F[mode][nd - 1],
             1e3 * depth[nd - 1]);
      if (mode == 1)
        for (int k = 0; k < nd; ++k) maxdiff = fmax(maxdiff, fabs(F[1][k] / F[0][k] - 1.0));
    }
  if (!rc) {
    const double wf = palp_bench_median(wall[0], runs), wr = palp_bench_median(wall[1], runs);
    const double cf = palp_bench_median(cpu[0], runs), cr = palp_bench_median(cpu[1], runs);
    printf("median wall: full Newton %.2f s, static_reuse %.2f s: ratio %.2f (x%.2f faster)\n", wf, wr, wr / wf,
           wf / wr);
    printf("median CPU:  full Newton %.2f s, static_reuse %.2f s: ratio %.2f\n", cf, cr, cr / cf);
    printf("largest force difference between the modes: %.2e (relative)\n", maxdiff);
  }
  palp_fem_mesh_destroy(&mesh);
  return rc;
}
