/*
 * bench_model_step - step time of the real-time model (median, p99) at about 338,
 * 1,300 and 5,000 vertices, at 10 ms and 1 ms steps, with every effect on and the
 * paper's 3 N uniform load pressing off-centre, against the paper's 10 ms budget.
 * The baseline measured in the same run is the world's own "solve" stage: the sparse
 * triangular solves that bound the step from below. Then a pressing finger at 338
 * vertices: its tangent-rebuild steps on the stepping thread against deferred.
 *
 * With --bending D every world has the skin's bending stiffness D [N m] (hinges in
 * the factor; docs/model.md): run with and without to see what bending costs.
 *
 * Last, a server core's view: --worlds K copies of the shipped default dome
 * (config/paper_step_long_term.json) with a fingertip pressing 0-10 mm each, stepped in
 * turn at 250 Hz as one tick thread steps its sessions, against one such world stepped
 * alone in the same run: in turn, each step finds its factor and compliance columns
 * out of the caches, which is what the server's capacity pays (docs/model.md). --scene FILE
 * steps another dome there (e.g. config/paper_step_long_term_fine.json, 1,300 vertices).
 *
 * --surface smooth|facets sets the fingertip's contact surface of the finger cases (else
 * the library's default, and the scene's in the server core's view): run both in the same
 * hour to see what the smooth surface costs (docs/haptics.md).
 *
 * --hash also prints, per case of the server core's view, an FNV-1a fold of
 * palp_world_hash after every step (outside the timed calls): equal before and after a
 * change that claims to keep the bits (docs/model.md, "The stages around the solve").
 *
 *   bench_model_step [--steps N] [--quick] [--bending D] [--worlds K] [--core-only] [--cpu C]
 *                    [--surface smooth|facets] [--hash] [--scene FILE]
 */
#define _GNU_SOURCE
#include <math.h>
#include <sched.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "palp.h"

#ifndef PALP_CONFIG_DIR
#define PALP_CONFIG_DIR "config"
#endif

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
static int cmpd(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* A world that refuses a step, a force or a finger measures nothing (a broken world "steps"
 * in well under a microsecond): stop and say which case, which step and why. */
static void check(int rc, const char *what, long step) {
  if (rc >= 0) return;
  if (step >= 0) fprintf(stderr, "bench_model_step: %s, step %ld: %s\n", what, step, palp_strerror(rc));
  else fprintf(stderr, "bench_model_step: %s: %s\n", what, palp_strerror(rc));
  exit(1);
}
static void *check_alloc(void *p) {
  if (!p) {
    fprintf(stderr, "bench_model_step: out of memory\n");
    exit(1);
  }
  return p;
}

/* Device of world i at t: presses 0..10 mm near the pole at 0.7 Hz, phase-shifted. */
static palp_vec3 press_device(int i, double t) {
  const double R = 0.04, r = 0.008, pi = 3.14159265358979323846;
  const double depth = 0.005 * (1 - cos(2 * pi * 0.7 * t + i));
  const double a = 0.3 * i;
  const palp_vec3 n = {0.2 * cos(a), 0.2 * sin(a), sqrt(1 - 0.04)};
  const double h = R + r - depth + 0.001;
  return (palp_vec3){n.x * h, n.y * h, n.z * h};
}

/* K worlds stepped in turn (rounds of one step each) against one world alone, the same
 * trajectory per world; median / p99 of single steps, and the stages' means. */
static int server_core(int K, int rounds, int surface, int hash, const char *path) {
  palp_scene sc;
  char err[256];
  if (palp_scene_load(path, &sc, err, sizeof err) < 0) {
    fprintf(stderr, "%s\n", err);
    return 1;
  }
  sc.world.dt = 1.0 / 250.0;
  sc.world.refactor_lag = 0; /* rebuilds on the stepping thread here: the server defers them */
  if (surface >= 0) sc.world.finger_surface = surface;
  if (K < 1) K = 1;
  const int shipped = strcmp(path, PALP_CONFIG_DIR "/paper_step_long_term.json") == 0;
  printf("a server core's view: %s (%s, %d vertices), a fingertip pressing 0-10 mm at 0.7 Hz, 250 Hz, "
         "finger surface %s\n", shipped ? "the shipped default dome" : "the dome of --scene", sc.name,
         sc.world.mesh.vertex_count, palp_finger_surface_name(sc.world.finger_surface));
  printf("%8s %8s %11s %11s   stage means (us)\n", "worlds", "steps", "median_us", "p99_us");
  const int cases[2] = {1, K};
  double med[2] = {0, 0};
  for (int c = 0; c < 2; ++c) {
    const int n = cases[c];
    palp_world **w = check_alloc(calloc((size_t)n, sizeof *w));
    int *f = check_alloc(calloc((size_t)n, sizeof *f));
    const int total = rounds * n;
    double *t = check_alloc(malloc(sizeof(double) * (size_t)(rounds * n)));
    for (int i = 0; i < n; ++i) {
      int rc;
      w[i] = palp_scene_create_world(&sc, &rc);
      if (!w[i]) {
        fprintf(stderr, "cannot create the world: %s\n", palp_strerror(rc));
        return 1;
      }
      for (int k = 0; k < sc.contact_count; ++k) check(palp_world_remove_contact(w[i], k), "server core: a scene contact", -1);
      f[i] = palp_world_add_finger(w[i], press_device(i, 0), 0.008);
      check(f[i], "server core: the fingertip", -1);
    }
    int m = 0;
    uint64_t H = 14695981039346656037ull; /* FNV-1a over the worlds' state hashes, step by step */
    for (int k = 0; k < rounds; ++k)
      for (int i = 0; i < n; ++i) {
        check(palp_world_set_finger(w[i], f[i], press_device(i, k / 250.0), 0.008), "server core: the fingertip", k);
        const double s = now_s();
        const int rc = palp_world_step(w[i]);
        t[m++] = now_s() - s;
        check(rc, n > 1 ? "server core, worlds in turn" : "server core, one world", k);
        if (hash) H = (H ^ palp_world_hash(w[i])) * 1099511628211ull;
      }
    double stage[PALP_STAGE_COUNT] = {0};
    int64_t nsteps = 0;
    palp_stage_timings tm;
    for (int i = 0; i < n; ++i) {
      palp_world_timings(w[i], &tm);
      nsteps += tm.steps;
      for (int s = 0; s < PALP_STAGE_COUNT; ++s)
        if (tm.name[s]) stage[s] += tm.total[s];
    }
    qsort(t, (size_t)m, sizeof *t, cmpd);
    med[c] = t[m / 2];
    printf("%8d %8d %11.1f %11.1f  ", n, total, 1e6 * t[m / 2], 1e6 * t[(int)(0.99 * (m - 1))]);
    for (int s = 0; s < PALP_STAGE_COUNT; ++s)
      if (tm.name[s]) printf(" %s %.1f", tm.name[s], 1e6 * stage[s] / (double)(nsteps ? nsteps : 1));
    printf("\n");
    if (hash) printf("    state hash over every step of the %d world%s: %016llx\n", n, n > 1 ? "s" : "", (unsigned long long)H);
    for (int i = 0; i < n; ++i) palp_world_destroy(w[i]);
    free(w), free(f), free(t);
  }
  printf("in turn / alone (median): %.2f\n", med[1] / med[0]);
  return 0;
}

int main(int argc, char **argv) {
  int steps = 3000, quick = 0, worlds = 12, core_only = 0, cpu = 0, surface = -1, hash = 0;
  const char *scene = PALP_CONFIG_DIR "/paper_step_long_term.json"; /* --core-only's dome */
  double bending = 0.0; /* [N m] */
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--steps") && i + 1 < argc) {
      char *end;
      const long v = strtol(argv[++i], &end, 10);
      /* the median and p99 are of these steps: none (0 read t[0] of an empty sample) is no run */
      if (*end || end == argv[i] || v < 1 || v > 100000000) {
        fprintf(stderr, "bench_model_step: --steps must be a whole number from 1 to 100000000 (got \"%s\")\n", argv[i]);
        return 2;
      }
      steps = (int)v;
    }
    else if (!strcmp(argv[i], "--bending") && i + 1 < argc) bending = atof(argv[++i]);
    else if (!strcmp(argv[i], "--quick")) quick = 1;
    else if (!strcmp(argv[i], "--worlds") && i + 1 < argc) worlds = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--core-only")) core_only = 1;
    else if (!strcmp(argv[i], "--scene") && i + 1 < argc) scene = argv[++i];
    else if (!strcmp(argv[i], "--hash")) hash = 1;
    else if (!strcmp(argv[i], "--cpu") && i + 1 < argc) cpu = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--surface") && i + 1 < argc) {
      if (palp_finger_surface_from_name(argv[++i], &surface)) {
        fprintf(stderr, "--surface: smooth or facets\n");
        return 2;
      }
    }
  }
  if (quick) steps = 300;
  /* One core, as the target says: pin to CPU 0 (--cpu) when allowed. */
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  const int pinned = sched_setaffinity(0, sizeof set, &set) == 0;
  if (core_only) return server_core(worlds, quick ? 200 : 1000, surface, hash, scene);
  printf("palp model step benchmark: %d steps per case, all effects on, 3 N uniform load at polar 30 deg%s, "
         "bending stiffness %g N m\n", steps, pinned ? ", pinned to one CPU" : "", bending);
  /* step/solve is the median step over the median solve stage, each step's solve taken from
   * palp_stage_timings.last (until session 82 a median over the stage's mean, which takes in the
   * rare slow solves, refactorising steps among them, and swung with them); the mean stays as a
   * column of its own. */
  printf("%8s %7s %8s %11s %11s %11s %11s %11s %9s %10s %10s\n", "vertices", "dt_ms", "unknowns", "median_us",
         "p99_us", "solve_med", "solve_p99", "solve_mean", "step/solve", "of_10ms_%", "refactors");
  const int counts[3] = {338, 1300, 5000};
  const double dts[2] = {0.01, 0.001};
  double *t = check_alloc(malloc(sizeof(double) * (size_t)steps));
  double *ts = check_alloc(malloc(sizeof(double) * (size_t)steps)); /* each step's solve stage [s] */
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 2; ++k) {
      palp_world_def d = palp_world_default_def();
      d.mesh.vertex_count = counts[c];
      d.membrane.bending_stiffness = bending;
      d.dt = dts[k];
      d.effects = PALP_EFFECT_ALL;
      int ce;
      palp_world *w = palp_world_create(&d, &ce);
      if (!w) {
        fprintf(stderr, "cannot create a world of %d vertices: %s\n", counts[c], palp_strerror(ce));
        return 1;
      }
      const double th = 30.0 * 3.14159265358979323846 / 180.0, ph = 40.0 * 3.14159265358979323846 / 180.0;
      const palp_vec3 ctr = {0.04 * sin(th) * cos(ph), 0.04 * sin(th) * sin(ph), 0.04 * cos(th)};
      palp_contact_def cd = palp_contact_default_def(PALP_DIST_UNIFORM, ctr);
      const int id = palp_world_add_contact(w, &cd);
      check(id, "the 3 N load", -1);
      check(palp_world_set_contact_force(w, id, (palp_vec3){-3.0 * ctr.x / 0.04, -3.0 * ctr.y / 0.04, -3.0 * ctr.z / 0.04}),
            "the 3 N load", -1);
      char what[64];
      snprintf(what, sizeof what, "%d vertices, %g ms", counts[c], 1e3 * dts[k]);
      for (int i = 0; i < 20; ++i) check(palp_world_step(w), what, i); /* warm caches and the factor */
      palp_stage_timings t0, tl;
      palp_world_timings(w, &t0);
      int solve_at = -1;
      for (int s = 0; s < PALP_STAGE_COUNT; ++s)
        if (t0.name[s] && !strcmp(t0.name[s], "solve")) solve_at = s;
      if (solve_at < 0) {
        fprintf(stderr, "bench_model_step: %s: the world's timings name no solve stage\n", what);
        return 1;
      }
      for (int i = 0; i < steps; ++i) {
        const double s = now_s();
        const int rc = palp_world_step(w);
        t[i] = now_s() - s;
        check(rc, what, 20 + i);
        palp_world_timings(w, &tl); /* outside the timed call */
        ts[i] = tl.last[solve_at];
      }
      palp_stage_timings t1;
      palp_world_timings(w, &t1);
      const double solve_mean = (t1.total[solve_at] - t0.total[solve_at]) / (double)steps;
      qsort(t, (size_t)steps, sizeof *t, cmpd);
      qsort(ts, (size_t)steps, sizeof *ts, cmpd);
      const double med = t[steps / 2], p99 = t[(int)(0.99 * (steps - 1))];
      const double smed = ts[steps / 2], sp99 = ts[(int)(0.99 * (steps - 1))];
      printf("%8d %7.1f %8d %11.1f %11.1f %11.1f %11.1f %11.1f %9.2f %10.3f %10lld\n", counts[c], 1e3 * dts[k],
             t1.unknowns, 1e6 * med, 1e6 * p99, 1e6 * smed, 1e6 * sp99, 1e6 * solve_mean, med / smed,
             100.0 * med / 0.010, (long long)(t1.refactors - t0.refactors));
      if (c == 0 && k == 0) {
        printf("    stages at 338 vertices, 10 ms (mean us):");
        for (int s = 0; s < PALP_STAGE_COUNT; ++s)
          if (t1.name[s]) printf(" %s %.1f", t1.name[s], 1e6 * (t1.total[s] - t0.total[s]) / steps);
        printf("\n");
      }
      palp_world_destroy(w);
    }
  /* A finger pressing at 338 vertices (the haptic sessions' load): the steps that
   * rebuild the lagged tangent, on the stepping thread (refactor_lag 0, the library's
   * default) against deferred with the job computed off the timed path (the
   * server's helper threads; docs/haptics.md). */
  printf("finger pressing 2-18 mm at the pole with a 0.7 Hz wobble, 338 vertices, finger surface %s (median / p99 / "
         "max us):\n", palp_finger_surface_name(surface >= 0 ? surface : palp_world_default_def().finger_surface));
  printf("%7s %10s %8s %23s %23s %8s\n", "dt_ms", "lag/blend", "steps", "rebuild/request/install", "other steps",
         "at_once");
  for (int k = 0; k < 2; ++k)
    for (int deferred = 0; deferred < 2; ++deferred) {
      const double dt = k ? 0.001 : 0.004;
      palp_world_def d = palp_world_default_def();
      d.dt = dt;
      d.refactor_lag = deferred ? palp_world_refactor_lag_for(dt) : 0;
      d.refactor_blend = deferred ? palp_world_refactor_blend_for(dt) : 0; /* as the server */
      if (surface >= 0) d.finger_surface = surface;
      d.membrane.bending_stiffness = bending;
      int ce;
      palp_world *w = palp_world_create(&d, &ce);
      char what[64];
      snprintf(what, sizeof what, "finger, %g ms, %s", 1e3 * dt, deferred ? "deferred" : "on the stepping thread");
      if (!w) check(ce, what, -1);
      const palp_finger_def fd = palp_finger_default_def();
      const int id = palp_world_add_finger_def(w, &fd, (palp_vec3){0, 0, 0.06});
      check(id, what, -1);
      const int n = quick ? 500 : (k ? 4000 : 2000);
      double *tr = check_alloc(malloc(sizeof(double) * (size_t)n)), *tn = check_alloc(malloc(sizeof(double) * (size_t)n));
      int nr = 0, nn = 0;
      for (int i = 0; i < n; ++i) {
        const double tt = i * dt, pi = 3.14159265358979323846;
        const double depth = 0.010 + 0.008 * sin(2 * pi * 0.7 * tt);
        check(palp_world_set_finger_device(w, id, (palp_vec3){0.01 * sin(2 * pi * 0.3 * tt), 0, 0.056 - depth}), what, i);
        palp_stage_timings a, b;
        palp_world_timings(w, &a);
        const double s = now_s();
        const int rc = palp_world_step(w);
        const double e = now_s() - s;
        check(rc, what, i);
        palp_world_timings(w, &b);
        palp_factor_job *j = palp_world_factor_claim(w);
        if (j) { /* requested by this step: the server's helper would run it now */
          check(palp_factor_job_run(j), what, i);
          check(palp_world_factor_done(w, j), what, i);
          tr[nr++] = e;
        } else if (b.refactors > a.refactors) {
          tr[nr++] = e;
        } else {
          tn[nn++] = e;
        }
      }
      qsort(tr, (size_t)nr, sizeof *tr, cmpd);
      qsort(tn, (size_t)nn, sizeof *tn, cmpd);
      palp_world_health hl;
      palp_world_get_health(w, &hl);
      printf("%7.1f %7d/%-2d %8d %7.0f %7.0f %7.0f %7.1f %7.1f %7.0f %8lld\n", 1e3 * dt, d.refactor_lag,
             d.refactor_blend, nr,
             nr ? 1e6 * tr[nr / 2] : 0.0, nr ? 1e6 * tr[(int)(0.99 * (nr - 1))] : 0.0, nr ? 1e6 * tr[nr - 1] : 0.0,
             1e6 * tn[nn / 2], 1e6 * tn[(int)(0.99 * (nn - 1))], 1e6 * tn[nn - 1], (long long)hl.margin_rebuilds);
      free(tr), free(tn);
      palp_world_destroy(w);
    }
  free(t), free(ts);
  return server_core(worlds, quick ? 200 : 1000, surface, hash, scene);
}
