/*
 * bench_eval - where the time of one `palp-eval evaluate` goes: the real-time
 * model, the FEM reference cold (computed) and warm (read from its cache), and
 * the statistics of Tables V and VI.
 *
 *   bench_eval [--scene FILE] [--level N] [--frames N] [--repeats R]
 *
 * Defaults: config/paper_step.json, FEM level 1, 40 frames (the FEM cold run
 * dominates; 400 frames at level 1 take minutes), 5 repeats of everything but
 * the cold FEM run, which runs once per distribution. Prints per distribution
 * and in total: median [min, max] of the repeats, and the warm/cold ratio.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <time.h>
#include <unistd.h>

#include "../bench_util.h"
#include "eval.h"
#include "eval_fem.h"

#ifndef PALP_CONFIG_DIR
#define PALP_CONFIG_DIR "config"
#endif

static double now_s(void) { return palp_bench_clock_s(CLOCK_MONOTONIC); }

int main(int argc, char **argv) {
  const char *scene_path = PALP_CONFIG_DIR "/paper_step.json";
  int level = 1, frames = 40, repeats = 5;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!strcmp(argv[i], "--scene")) scene_path = argv[i + 1];
    else if (!strcmp(argv[i], "--level")) level = atoi(argv[i + 1]);
    else if (!strcmp(argv[i], "--frames")) frames = atoi(argv[i + 1]);
    else if (!strcmp(argv[i], "--repeats")) repeats = atoi(argv[i + 1]);
    else {
      fprintf(stderr, "usage: bench_eval [--scene FILE] [--level N] [--frames N] [--repeats R]\n");
      return 2;
    }
  }
  if (level < 1 || frames < 2 || repeats < 1 || repeats > 100) {
    fprintf(stderr, "bench_eval: --level >= 1, --frames >= 2, --repeats 1..100\n");
    return 2;
  }
  palp_scene scene;
  char err[512] = "";
  if (palp_scene_load(scene_path, &scene, err, sizeof err) || scene.contact_count < 1) {
    fprintf(stderr, "bench_eval: %s: %s\n", scene_path, err[0] ? err : "no contact");
    return 1;
  }
  scene.frames = frames;
  palp_fem_config cfg;
  if (palp_fem_config_for_scene(&scene, &cfg, err, sizeof err)) {
    fprintf(stderr, "bench_eval: %s: %s\n", scene_path, err);
    return 1;
  }
  cfg.mesh.level = level;
  char cache[] = "/tmp/palp_bench_eval_XXXXXX";
  if (!mkdtemp(cache)) {
    fprintf(stderr, "bench_eval: cannot create a cache directory\n");
    return 1;
  }
  snprintf(cfg.cache_dir, sizeof cfg.cache_dir, "%s", cache);
  printf("bench_eval: %s, %d frames, %d vertices, FEM level %d, %d repeats (cold FEM once)\n", scene_path, frames,
         scene.world.mesh.vertex_count, level, repeats);
  printf("%-8s %22s %12s %22s %22s %12s\n", "distr.", "real-time [ms]", "FEM cold [s]", "FEM warm [ms]",
         "statistics [ms]", "warm/cold");
  double tot_rt = 0, tot_cold = 0, tot_warm = 0, tot_stats = 0;
  for (int d = 1; d <= 4; ++d) {
    palp_scene sd = scene;
    sd.contact[0].def.distribution = (palp_distribution)d;
    /* medians sort these in place, so [0] and [repeats - 1] are then min and max */
    double t_rt[100], t_warm[100], t_stats[100], t_cold;
    palp_eval_record rt, ref;
    palp_fem_result fr;
    /* cold: computed and stored */
    double t0 = now_s();
    if (palp_fem_run(&cfg, &sd, &fr, NULL, NULL, err, sizeof err)) {
      fprintf(stderr, "bench_eval: FEM: %s\n", err);
      return 1;
    }
    t_cold = now_s() - t0;
    if (fr.from_cache) fprintf(stderr, "bench_eval: warning: the cold run came from a cache\n");
    palp_fem_result_destroy(&fr);
    for (int r = 0; r < repeats; ++r) {
      t0 = now_s();
      if (palp_eval_run_rt(&sd, &rt, err, sizeof err)) {
        fprintf(stderr, "bench_eval: real-time: %s\n", err);
        return 1;
      }
      t_rt[r] = now_s() - t0;
      t0 = now_s();
      if (palp_fem_run(&cfg, &sd, &fr, NULL, NULL, err, sizeof err) ||
          palp_eval_record_from_fem(&fr, &sd, &ref, err, sizeof err)) {
        fprintf(stderr, "bench_eval: FEM warm: %s\n", err);
        return 1;
      }
      t_warm[r] = now_s() - t0;
      if (!fr.from_cache) fprintf(stderr, "bench_eval: warning: the warm run was recomputed\n");
      palp_fem_result_destroy(&fr);
      t0 = now_s();
      palp_eval_pairs pr;
      palp_eval_row a, b;
      if (palp_eval_pairs_build(&rt, &ref, &pr, err, sizeof err) ||
          palp_eval_row_compute(pr.disp_rt, pr.disp_ref, pr.n_disp, &a) ||
          (pr.n_force >= 2 && palp_eval_row_compute(pr.force_rt, pr.force_ref, pr.n_force, &b))) {
        fprintf(stderr, "bench_eval: statistics failed\n");
        return 1;
      }
      t_stats[r] = now_s() - t0;
      palp_eval_pairs_destroy(&pr);
      palp_eval_record_destroy(&rt);
      palp_eval_record_destroy(&ref);
    }
    const double m_rt = palp_bench_median(t_rt, repeats), m_w = palp_bench_median(t_warm, repeats);
    const double m_s = palp_bench_median(t_stats, repeats);
    printf("%-8s %8.2f [%5.2f,%6.2f] %12.2f %8.3f [%5.3f,%6.3f] %8.3f [%5.3f,%6.3f] %12.2e\n", palp_eval_roman(d),
           1e3 * m_rt, 1e3 * t_rt[0], 1e3 * t_rt[repeats - 1], t_cold, 1e3 * m_w, 1e3 * t_warm[0],
           1e3 * t_warm[repeats - 1], 1e3 * m_s, 1e3 * t_stats[0], 1e3 * t_stats[repeats - 1], m_w / t_cold);
    tot_rt += m_rt, tot_cold += t_cold, tot_warm += m_w, tot_stats += m_s;
  }
  printf("%-8s %22.2f %12.2f %22.3f %22.3f %12.2e\n", "total", 1e3 * tot_rt, tot_cold, 1e3 * tot_warm,
         1e3 * tot_stats, tot_warm / tot_cold);
  printf("one evaluate run: %.2f s cold, %.3f s warm (real-time %.1f%%, FEM %.1f%%, statistics %.1f%% of warm)\n",
         tot_rt + tot_cold + tot_stats, tot_rt + tot_warm + tot_stats,
         100.0 * tot_rt / (tot_rt + tot_warm + tot_stats), 100.0 * tot_warm / (tot_rt + tot_warm + tot_stats),
         100.0 * tot_stats / (tot_rt + tot_warm + tot_stats));
  /* leave no cache behind: the cache holds flat files only */
  DIR *dir = opendir(cache);
  for (struct dirent *e; dir && (e = readdir(dir));) {
    if (e->d_name[0] == '.') continue;
    char path[700];
    snprintf(path, sizeof path, "%s/%s", cache, e->d_name);
    remove(path);
  }
  if (dir) closedir(dir);
  if (rmdir(cache)) fprintf(stderr, "bench_eval: could not remove %s\n", cache);
  return 0;
}
