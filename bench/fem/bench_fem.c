/*
 * bench_fem - seconds per 10 ms frame of the FE reference at two mesh sizes, and
 * the time of one 400-frame distribution run, against the paper's 22.5 s per step.
 *
 *   bench_fem [SCENE.json] [--levels 2,4] [--frames N] [--reading long_term|instantaneous]
 *             [--distribution single|uniform|gaussian|gaussian_offset] [--load-map point|patch]
 *
 * Each level runs the scene's first N frames (default 20: the transient after
 * the 3 N step, the hardest part of the run) with the cache off. The run's setup
 * (mesh, map, model, symbolic analysis and, since fem-frames, the first numeric
 * factorisation) ends with the progress callback for frame 0 and is printed
 * apart; per-frame times are the gaps between progress callbacks. The 400-frame
 * figure is measured when N >= 400, otherwise extrapolated as the setup plus the
 * first frame plus 399 x the mean of the others, and says so.
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

static int cmp(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* CPU seconds of the calling thread or of the whole process: on a shared machine
 * the wall time of a frame also holds the time other processes had the cores, so
 * the CPU time is printed beside it. The calling thread's is what a frame costs
 * when the background factorisation and the second assembly thread have a core of
 * their own; the process's, when everything shares one core. */
static double cpu_s(clockid_t id) {
  struct timespec t;
  clock_gettime(id, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* One solve with the factor, timed: wall best and sum, and this thread's CPU sum [s]. */
static void timed_solve(palp_fem_solver *solver, const double *b, double *x, double *best, double *sum, double *cpu) {
  const double t1 = now_s(), c1 = cpu_s(CLOCK_THREAD_CPUTIME_ID);
  palp_fem_solver_solve(solver, b, x);
  const double d = now_s() - t1;
  *cpu += cpu_s(CLOCK_THREAD_CPUTIME_ID) - c1;
  *best = d < *best ? d : *best;
  *sum += d;
}

typedef struct stamps {
  double *t, *ct, *cp; /* wall, thread CPU, process CPU [s] at each callback */
  int n, cap;
} stamps;

static int on_frame(void *ud, int frame, int frames, double sim) {
  (void)frames, (void)sim;
  stamps *s = ud;
  if (frame <= s->cap) {
    s->t[frame] = now_s(), s->n = frame;
    s->ct[frame] = cpu_s(CLOCK_THREAD_CPUTIME_ID);
    s->cp[frame] = cpu_s(CLOCK_PROCESS_CPUTIME_ID);
  }
  return 0;
}

/* median, p90 and max of the per-frame differences of x[0..n] */
static void frame_stats(const double *x, int n, double *med, double *p90, double *mx) {
  double *d = malloc(sizeof(double) * (size_t)n);
  for (int i = 0; i < n; ++i) d[i] = x[i + 1] - x[i];
  qsort(d, (size_t)n, sizeof *d, cmp);
  *med = d[n / 2], *p90 = d[(int)(0.9 * (n - 1))], *mx = d[n - 1];
  free(d);
}


int main(int argc, char **argv) {
  const char *scene_path = "config/paper_step.json", *levels = "2,4", *reading = NULL, *dist = NULL, *load_map = NULL;
  int frames = 20, kernel = 0, lag = -1, threads = 0, per_frame = 0;
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--levels") && i + 1 < argc) levels = argv[++i];
    else if (!strcmp(argv[i], "--frames") && i + 1 < argc) frames = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--reading") && i + 1 < argc) reading = argv[++i];
    else if (!strcmp(argv[i], "--load-map") && i + 1 < argc) load_map = argv[++i];
    else if (!strcmp(argv[i], "--distribution") && i + 1 < argc) dist = argv[++i];
    else if (!strcmp(argv[i], "--kernel")) kernel = 1;
    else if (!strcmp(argv[i], "--factor-lag") && i + 1 < argc) lag = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--per-frame")) per_frame = 1;
    else if (argv[i][0] != '-') scene_path = argv[i];
    else {
      fprintf(stderr, "usage: bench_fem [SCENE.json] [--levels 2,4] [--frames N] [--reading R] [--distribution D] [--kernel] [--factor-lag N] [--threads N] [--load-map point|patch] [--per-frame]\n"
                      "  --kernel: time the assembly alone (tangent and residual, 1 and 2 threads) and one solve instead of frames\n"
                      "  --factor-lag N: the config's factor_lag (0: renew the factor in the foreground)\n"
                      "  --threads N: the config's assembly threads\n"
                      "  --per-frame: print every frame's wall and CPU seconds\n");
      return 2;
    }
  }
  if (frames < 2) frames = 2;
  palp_scene scene;
  char err[512];
  if (palp_scene_load(scene_path, &scene, err, sizeof err)) {
    fprintf(stderr, "bench_fem: %s: %s\n", scene_path, err);
    return 2;
  }
  static const char *names[] = {"single", "uniform", "gaussian", "gaussian_offset"};
  for (int d = 0; dist && d < 4; ++d)
    if (!strcmp(dist, names[d]))
      for (int c = 0; c < scene.contact_count; ++c) scene.contact[c].def.distribution = (palp_distribution)(d + 1);
  const int full = scene.frames;
  scene.frames = frames < full ? frames : full;
  printf("FE reference benchmark: scene %s, %d of %d frames of %.3f s, the paper's FEM: 22.5 s per step\n",
         scene.name, scene.frames, full, scene.frame_period);
  char buf[64];
  snprintf(buf, sizeof buf, "%s", levels);
  /* The same-run baseline (session 82): the first level of --levels; each later level's median
   * frame is printed as a ratio to it. */
  double base_med = 0, base_p99 = 0;
  int base_level = 0;
  for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
    palp_fem_config cfg = palp_fem_default_config();
    cfg.mesh.level = atoi(tok);
    cfg.cache_dir[0] = 0;
    if (lag >= 0) cfg.factor_lag = lag;
    if (threads > 0) cfg.threads = threads;
    if (reading) cfg.c10_reading = strcmp(reading, "long_term") ? PALP_FEM_C10_INSTANTANEOUS : PALP_FEM_C10_LONG_TERM;
    /* the default config's map (patch) unless asked: the point map is the paper's literal nodal load */
    if (load_map) cfg.load_map = strcmp(load_map, "point") ? PALP_FEM_LOAD_PATCH : PALP_FEM_LOAD_POINT;
    stamps st = {.t = calloc((size_t)scene.frames + 1, sizeof(double)),
                 .ct = calloc((size_t)scene.frames + 1, sizeof(double)),
                 .cp = calloc((size_t)scene.frames + 1, sizeof(double)),
                 .cap = scene.frames};
    palp_fem_result r;
    const double t0 = now_s();
    st.t[0] = t0;
    st.n = -1;
    /* setup = everything before the first step: time it with a zero-frame trick */
    palp_fem_mesh mesh;
    if (palp_fem_mesh_create(&cfg.mesh, &mesh)) {
      fprintf(stderr, "bench_fem: bad level %s\n", tok);
      return 2;
    }
    palp_fem_model m;
    const double ts = now_s();
    palp_fem_model_create(&m, &mesh, &cfg);
    palp_fem_model_finalize(&m);
    palp_fem_assemble(&m, m.u, scene.frame_period, 1);
    const double tfa = now_s();
    palp_fem_solver_factor(m.solver, m.kval);
    const double tf = now_s() - tfa, setup = tfa - ts;
    if (kernel) { /* assembly alone, at the rest state with the frame's viscous step */
      for (int th = 1; th <= 2; ++th) {
        m.threads = th; /* the model keeps private buffers for its configured count (2) */
        for (int tan = 1; tan >= 0; --tan) {
          double best = 1e30, sum = 0.0;
          for (int rep = 0; rep < 7; ++rep) {
            const double t1 = now_s();
            palp_fem_assemble(&m, m.u, scene.frame_period, tan);
            const double d = now_s() - t1;
            best = d < best ? d : best;
            sum += d;
          }
          printf("level %s: %d threads, %s: best %.1f ms, mean %.1f ms of 7\n", tok, th,
                 tan ? "force + tangent" : "force only", 1e3 * best, 1e3 * sum / 7);
        }
      }
      { /* one solve with the factor (a CG iteration's preconditioner) */
        double *b = malloc(sizeof(double) * (size_t)m.nfree), *x = malloc(sizeof(double) * (size_t)m.nfree);
        for (int i = 0; i < m.nfree; ++i) b[i] = 1.0 + 1e-3 * (i % 17);
        double best = 1e30, sum = 0.0, csum0 = 0.0;
        for (int rep = 0; rep < 10; ++rep) timed_solve(m.solver, b, x, &best, &sum, &csum0);
        printf("level %s: one solve with the factor: best %.1f ms, mean %.1f ms (CPU %.1f ms) of 10\n", tok, 1e3 * best,
               1e3 * sum / 10, 1e3 * csum0 / 10);
        /* the same while a factorisation runs on the background thread (factor_lag):
         * what the frames it overlaps pay for it */
        palp_fem_solver_factor_start(m.solver, m.kval); /* the first allocates the second factor: not timed */
        palp_fem_solver_factor_finish(m.solver, 0);
        const double tb = now_s();
        palp_fem_solver_factor_start(m.solver, m.kval);
        best = 1e30, sum = 0.0;
        double csum = 0.0; /* CPU of this thread: apart from the time the scheduler gave away */
        int reps = 0;
        double abest = 1e30, asum = 0.0;
        int areps = 0;
        for (; reps < 12; ++reps) { /* ~0.5 s of work, within the ~1.1 s factorisation */
          timed_solve(m.solver, b, x, &best, &sum, &csum);
          if (reps % 4 == 3) { /* and an assembly with tangent every 4 solves */
            const double t2 = now_s();
            palp_fem_assemble(&m, m.u, scene.frame_period, 1);
            const double d2 = now_s() - t2;
            abest = d2 < abest ? d2 : abest;
            asum += d2;
            ++areps;
          }
        }
        palp_fem_solver_factor_finish(m.solver, 0);
        const double tbg = now_s() - tb;
        printf("level %s: during a background factorisation (%.2f s until joined): one solve best %.1f ms, mean %.1f ms "
               "(CPU %.1f ms) of %d; assembly with tangent best %.1f ms, mean %.1f ms of %d\n",
               tok, tbg, 1e3 * best, 1e3 * sum / (reps ? reps : 1), 1e3 * csum / (reps ? reps : 1), reps, 1e3 * abest,
               1e3 * asum / (areps ? areps : 1), areps);
        free(b);
        free(x);
      }
      palp_fem_model_destroy(&m);
      palp_fem_mesh_destroy(&mesh);
      continue;
    }
    const double lnz = palp_fem_solver_factor_nnz(m.solver), fl = palp_fem_solver_factor_flops(m.solver);
    palp_fem_model_destroy(&m);
    const double run0 = now_s();
    st.t[0] = run0; /* overwritten by the callback for frame 0 (setup done) */
    const int rc = palp_fem_run(&cfg, &scene, &r, on_frame, &st, err, sizeof err);
    if (rc) {
      fprintf(stderr, "bench_fem: level %s: %s\n", tok, err);
      return 1;
    }
    const int n = st.n;
    double *dt = malloc(sizeof(double) * (size_t)n), mean = 0.0, rest = 0.0;
    for (int i = 0; i < n; ++i) {
      dt[i] = st.t[i + 1] - st.t[i];
      mean += dt[i] / n;
      if (i > 0) rest += dt[i] / (n - 1);
    }
    const double first = dt[0];
    for (int i = 0; per_frame && i < n; ++i)
      printf("  frame %3d: wall %.3f s, CPU this thread %.3f s, process %.3f s\n", i + 1, dt[i], st.ct[i + 1] - st.ct[i],
             st.cp[i + 1] - st.cp[i]);
    printf("\nlevel %s: frames over 0.5 s:", tok);
    int over = 0;
    for (int i = 0; i < n; ++i)
      if (dt[i] > 0.5) printf(" %d (%.2f s)", i + 1, dt[i]), ++over;
    printf("%s\n", over ? "" : " none");
    qsort(dt, (size_t)n, sizeof *dt, cmp);
    const double med = dt[n / 2], p90 = dt[(int)(0.9 * (n - 1))], p99 = dt[(int)floor(0.99 * (n - 1))], mx = dt[n - 1];
    const double total = st.t[n] - run0, run_setup = st.t[0] - run0;
    printf("level %s: %d nodes, %d hexahedra, %d free DOFs; nnz(L) %.3g, %.3g Gflop per factorisation\n", tok,
           mesh.node_count, mesh.element_count, r.dof_count, lnz, 1e-9 * fl);
    printf("  setup (model, sparsity, symbolic, 1 assembly) %.2f s; one numeric factorisation %.2f s\n", setup, tf);
    printf("  the run's setup before frame 1 (mesh, map, model, symbolic analysis, first numeric factorisation): "
           "%.2f s (not in the frame times below)\n", run_setup);
    printf("  per 10 ms frame: mean %.3f s, median %.3f s, p90 %.3f s, p99 %.3f s, max %.3f s (first frame %.3f s)\n",
           mean, med, p90, p99, mx, first);
    if (!base_level)
      base_med = med, base_p99 = p99, base_level = cfg.mesh.level;
    else
      printf("  vs level %d, this run's baseline (the first of --levels): median x%.2f, p99 x%.2f\n", base_level,
             med / base_med, p99 / base_p99);
    {
      double a, b, c, d, e, f;
      frame_stats(st.ct, n, &a, &b, &c);
      frame_stats(st.cp, n, &d, &e, &f);
      printf("  CPU per frame: this thread median %.3f s, p90 %.3f s, max %.3f s; the process (both assembly threads "
             "and the background factorisation) median %.3f s, p90 %.3f s, max %.3f s\n", a, b, c, d, e, f);
    }
    printf("  solver: %ld steps, %ld Newton iterations, %ld CG iterations, %ld factorisations (%ld of them on the "
           "background thread, factor_lag %d, %.2f s waited for them), %ld cut-backs\n",
           r.steps, r.newton_iterations, r.pcg_iterations, r.factorizations, r.background_factorizations,
           cfg.factor_lag, r.sec_factor_wait, r.cutbacks);
    printf("  time: assembly %.2f s (%ld, %ld with tangent), factorisation %.2f s, solves %.2f s (%ld), other Krylov "
           "%.2f s, rest %.2f s of %.2f s\n",
           r.sec_assemble, r.assemblies, r.tangent_assemblies, r.sec_factor, r.sec_solve, r.solves, r.sec_krylov,
           r.wall_seconds - r.sec_assemble - r.sec_factor - r.sec_solve - r.sec_krylov, r.wall_seconds);
    if (n >= 400)
      printf("  400-frame run: %.1f s measured\n", total);
    else
      printf("  400-frame run: ~%.0f s extrapolated (setup + first frame + 399 x the mean "
             "of the other %d; the transient frames after the step are the costliest)\n",
             run_setup + first + 399.0 * rest, n - 1);
    printf("  vs the paper's 22.5 s per step: %.0fx faster per frame (median); target <= 0.5 s/frame at >= 10k "
           "elements: %s\n",
           22.5 / med,
           mesh.element_count >= 10000 ? (mx <= 0.5 ? "met by every frame" : med <= 0.5 ? "met by the median, NOT by every frame" : "NOT met")
                                       : "n/a (smaller mesh)");
    free(dt);
    free(st.t);
    free(st.ct);
    free(st.cp);
    palp_fem_result_destroy(&r);
    palp_fem_mesh_destroy(&mesh);
  }
  return 0;
}
