/*
 * bench_model_rebuilds - what a haptic session's tangent rebuilds cost when the model is
 * stepped as the server steps it: physics at --rate (250 Hz), the rebuild lag and blend
 * the server gives that rate (palp_world_refactor_lag_for / _blend_for), each rebuild
 * job claimed after the step that asks for it and run at once in this thread (the
 * server's helper), installed at its due frame. One fingertip moves as the exercises'
 * scripted expert does (vertical strips at 3 / 9 / 16 mm with small circles, as
 * bench_server --motion strip: bench/bench_motion.h, for a dome of radius 4 cm) or
 * presses 0-10 mm at 0.7 Hz (--motion press).
 *
 * Printed per scene: rebuild jobs per simulated second, a job's median / p99, the
 * step's median / p99 / mean (the compliance columns of vertices the fingertip reaches
 * are solved in the step), and the share of a core the session takes (steps plus jobs
 * over simulated time). The baseline, in the same process, is the exercises' 338-vertex
 * dome (config/phantoms/dome.json); --scene FILE is the dome compared with it (default
 * config/phantoms/dome_fine.json, 1,300 vertices). One core's view: pin it with taskset.
 *
 *   bench_model_rebuilds [--scene FILE] [--rate HZ] [--seconds S] [--motion strip|press]
 */
#define _GNU_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../bench_motion.h"
#include "../bench_util.h"
#include "palp.h"

#ifndef PALP_CONFIG_DIR
#define PALP_CONFIG_DIR "config"
#endif

static double now_s(void) { return palp_bench_clock_s(CLOCK_MONOTONIC); }
/* 0-10 mm at 0.7 Hz near the pole */
static palp_vec3 press_device(double t, double R) {
  const double r = 0.008, depth = 0.005 * (1 - cos(2 * 3.14159265358979 * 0.7 * t));
  const double h = R + r - depth + 0.001;
  return (palp_vec3){0.2 * h, 0, sqrt(1 - 0.04) * h};
}

/* 1 (said on stderr) when a world call failed: a world that refuses its finger or a job would
 * still "step", in under a microsecond, and be printed as the session's cost (unchecked until
 * session 82). */
static int failed(int rc, const char *path, const char *what, int step) {
  if (rc >= 0) return 0;
  fprintf(stderr, "%s: %s", path, what);
  if (step >= 0) fprintf(stderr, ", step %d", step);
  fprintf(stderr, ": %s\n", palp_strerror(rc));
  return 1;
}

static int run(const char *path, double rate, double seconds, int strip, double *share) {
  palp_scene sc;
  char err[256];
  if (palp_scene_load(path, &sc, err, sizeof err) < 0) {
    fprintf(stderr, "%s\n", err);
    return 1;
  }
  sc.world.dt = 1.0 / rate;
  sc.world.refactor_lag = palp_world_refactor_lag_for(sc.world.dt);
  sc.world.refactor_blend = palp_world_refactor_blend_for(sc.world.dt);
  int rc = 0;
  palp_world *w = palp_scene_create_world(&sc, &rc);
  if (!w) {
    fprintf(stderr, "%s: cannot create the world: %s\n", path, palp_strerror(rc));
    return 1;
  }
  for (int k = 0; k < sc.contact_count; ++k) palp_world_remove_contact(w, k);
  const double R = sc.world.mesh.radius;
  const int f = palp_world_add_finger(w, strip ? palp_bench_strip_device(0, 0) : press_device(0, R), 0.008);
  if (failed(f, path, "the finger", -1)) return 1;
  const int steps = (int)(seconds * rate + 0.5);
  if (steps < 1) {
    fprintf(stderr, "%s: %g s at %g Hz is no step\n", path, seconds, rate);
    return 1;
  }
  double *ts = malloc(sizeof(double) * (size_t)steps), *tj = malloc(sizeof(double) * (size_t)steps);
  if (!ts || !tj) return 1;
  int jobs = 0;
  double step_sum = 0.0, job_sum = 0.0;
  palp_factor_job *pending = NULL;
  for (int k = 0; k < steps; ++k) {
    const double t = k / rate;
    if (failed(palp_world_set_finger(w, f, strip ? palp_bench_strip_device(0, t) : press_device(t, R), 0.008), path,
               "the finger's device", k))
      return 1;
    if (pending && palp_world_factor_due(w) <= palp_world_frame(w)) {
      if (failed(palp_world_factor_done(w, pending), path, "installing a rebuild", k)) return 1;
      pending = NULL;
    }
    const double a = now_s();
    rc = palp_world_step(w);
    ts[k] = now_s() - a;
    step_sum += ts[k];
    if (rc < 0) {
      fprintf(stderr, "%s: step failed: %s\n", path, palp_strerror(rc));
      return 1;
    }
    palp_factor_job *j = palp_world_factor_claim(w);
    if (j) {
      const double b = now_s();
      const int jr = palp_factor_job_run(j);
      tj[jobs] = now_s() - b;
      if (failed(jr, path, "a rebuild job", k)) return 1;
      job_sum += tj[jobs++];
      pending = j;
    }
  }
  palp_world_health hl;
  palp_world_get_health(w, &hl);
  qsort(ts, (size_t)steps, sizeof *ts, palp_bench_cmp);
  qsort(tj, (size_t)(jobs ? jobs : 1), sizeof *tj, palp_bench_cmp);
  const double sim = steps / rate;
  printf("%-34s %5d %8.1f %9.2f %9.2f %8.1f %8.1f %8.1f %7.1f%%\n", sc.name, sc.world.mesh.vertex_count, jobs / sim,
         jobs ? 1e3 * tj[jobs / 2] : 0.0, jobs ? 1e3 * tj[(int)(0.99 * (jobs - 1))] : 0.0, 1e6 * ts[steps / 2],
         1e6 * ts[(int)(0.99 * (steps - 1))], 1e6 * step_sum / steps, 100.0 * (step_sum + job_sum) / sim);
  *share = (step_sum + job_sum) / sim;
  if (hl.margin_rebuilds > 0) printf("    (%lld rebuilds made at once on the step: the factor reached its margin)\n",
                                     (long long)hl.margin_rebuilds);
  free(ts), free(tj);
  palp_world_destroy(w);
  return 0;
}

int main(int argc, char **argv) {
  const char *scene = PALP_CONFIG_DIR "/phantoms/dome_fine.json";
  double rate = 250.0, seconds = 10.0;
  int strip = 1;
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--scene") && i + 1 < argc) scene = argv[++i];
    else if (!strcmp(argv[i], "--rate") && i + 1 < argc) rate = atof(argv[++i]);
    else if (!strcmp(argv[i], "--seconds") && i + 1 < argc) seconds = atof(argv[++i]);
    else if (!strcmp(argv[i], "--motion") && i + 1 < argc && (!strcmp(argv[i + 1], "strip") || !strcmp(argv[i + 1], "press")))
      strip = !strcmp(argv[++i], "strip");
    else {
      fprintf(stderr, "usage: bench_model_rebuilds [--scene FILE] [--rate HZ] [--seconds S] [--motion strip|press]\n");
      return 2;
    }
  }
  if (!(rate >= 10.0 && rate <= 10000.0) || !(seconds > 0.0 && seconds <= 3600.0)) {
    fprintf(stderr, "--rate must be 10-10000 Hz and --seconds 0-3600\n");
    return 2;
  }
  printf("one haptic session stepped as the server steps it: %.0f Hz physics, lag %d / blend %d frames, rebuild jobs run "
         "on this thread when claimed; fingertip %s, %.0f s simulated\n", rate, palp_world_refactor_lag_for(1.0 / rate),
         palp_world_refactor_blend_for(1.0 / rate), strip ? "searching in vertical strips at 3 / 9 / 16 mm" :
         "pressing 0-10 mm at 0.7 Hz", seconds);
  printf("%-34s %5s %8s %9s %9s %8s %8s %8s %8s\n", "scene", "verts", "jobs/s", "job_ms", "p99_ms", "step_us", "p99_us",
         "mean_us", "of_core");
  double base = 0.0, share = 0.0;
  if (run(PALP_CONFIG_DIR "/phantoms/dome.json", rate, seconds, strip, &base)) return 1;
  if (run(scene, rate, seconds, strip, &share)) return 1;
  printf("a session's share of a core, --scene / the 338-vertex baseline: %.2f\n", base > 0.0 ? share / base : 0.0);
  return 0;
}
