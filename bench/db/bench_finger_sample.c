/* Cost of logging finger samples on the tick (issue 13): what the server's frame hook adds
 * to a physics step when it logs a position-driven fingertip (palp_world_finger_local_model,
 * palp_world_finger_contacts and palp_db_log_finger_sample's enqueue into a real writer).
 *
 * usage: bench_finger_sample SCENE.json [DB_PATH] [STEPS=5000] (DB_PATH: by default in a scratch
 * directory under TMPDIR, removed at exit)
 *
 * A fingertip (8 mm) pressed 9 mm into the dome at polar 30 deg, stepped STEPS times per
 * variant, alternating blocks of 250 steps so that both variants see the same machine load:
 * step only; step + sample every step (the worst case: physics at or below assess_sample_hz).
 * Prints the median, p90 and p99 per-step cost of each, the differences and the ratios to
 * "step only", the baseline of the same run (p99 and ratios since session 82). Every world
 * call is checked: a world that refuses to step would be timed at under a microsecond. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "palp.h"
#include "../bench_tmp.h"
#include "palp_db.h"

static double now_us(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec * 1e6 + 1e-3 * (double)ts.tv_nsec;
}

static int cmp(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* A world or log call that failed: say which and stop (exit 1). */
static void check(int rc, const char *what, int step) {
  if (rc >= 0) return;
  fprintf(stderr, "bench_finger_sample: %s", what);
  if (step >= 0) fprintf(stderr, ", step %d", step);
  fprintf(stderr, ": %s\n", palp_strerror(rc));
  exit(1);
}

static int g_part; /* 0: all; 1: local model only; 2: + contacts (no enqueue) */
static void sample(palp_world *w, int f, palp_db_writer *wr, palp_db_session s) {
  palp_local_model m;
  if (palp_world_finger_local_model(w, f, &m) < 0) return;
  if (g_part == 1) return;
  int tri[PALP_DB_MAX_SAMPLE_TRIANGLES];
  double tf[PALP_DB_MAX_SAMPLE_TRIANGLES];
  int nt = palp_world_finger_contacts(w, f, tri, tf, PALP_DB_MAX_SAMPLE_TRIANGLES);
  if (nt < 0) nt = 0;
  if (g_part == 2) return;
  const palp_db_finger_sample fs = {.frame = palp_world_frame(w), .sim_time_s = palp_world_time(w), .slot = f,
                                    .radius_m = 0.008, .device_m = m.device, .proxy_m = m.proxy, .force_n = m.force,
                                    .in_contact = m.contact, .point_m = m.point, .area_m2 = m.area,
                                    .triangle_count = nt, .triangles = nt ? (const int32_t *)tri : NULL};
  palp_db_log_finger_sample(wr, s, &fs);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s SCENE.json [DB_PATH] [STEPS]\n", argv[0]);
    return 2;
  }
  char scratch[600];
  const char *db = argc > 2 ? argv[2] : bench_tmp_path("palp-bench-finger-sample", "bench.db", scratch, sizeof scratch);
  if (!db) return 1;
  int steps = 5000;
  if (argc > 3) {
    char *end;
    const long v = strtol(argv[3], &end, 10);
    /* the median is of these steps: none (0 read t0[0] of malloc(0)) is no run */
    if (*end || end == argv[3] || v < 1 || v > 10000000) {
      fprintf(stderr, "bench_finger_sample: STEPS must be a whole number from 1 to 10000000 (got \"%s\")\n", argv[3]);
      return 2;
    }
    steps = (int)v;
  }
  g_part = argc > 4 ? atoi(argv[4]) : 0;
  palp_scene sc;
  char err[256];
  if (palp_scene_load(argv[1], &sc, err, sizeof err) < 0) {
    fprintf(stderr, "%s: %s\n", argv[1], err);
    return 1;
  }
  sc.world.dt = 1.0 / 250;
  int e = 0;
  palp_world *w = palp_world_create(&sc.world, &e);
  if (!w) check(e, "cannot create the world", -1);
  const double R = sc.world.mesh.radius, r = 0.008, p = 30 * 3.14159265358979 / 180;
  const int f = palp_world_add_finger(w, (palp_vec3){0, 0, R + r + 0.003}, r);
  check(f, "the finger", -1);
  unlink(db);
  palp_db_writer *wr = NULL;
  palp_db_writer_opts o = palp_db_writer_default_opts();
  if (palp_db_writer_open(db, &o, &wr, err, sizeof err) < 0) {
    fprintf(stderr, "%s: %s\n", db, err);
    return 1;
  }
  palp_db_session_def d = {.uid = "bench", .trainee = "bench", .station = "bench", .phantom_id = "1",
                           .phantom_name = "bench", .scene_json = "{}", .params_json = "{}", .tick_hz = 250,
                           .dt_s = 1.0 / 250};
  palp_db_session s = 0;
  check(palp_db_log_session_begin(wr, &d, &s), "the log's session", -1);
  /* press 9 mm in along the normal over 0.5 s, then hold */
  for (int k = 0; k < 250; k++) {
    const double depth = 0.009 * fmin(1.0, k / 125.0), q = R + r - depth;
    check(palp_world_set_finger(w, f, (palp_vec3){q * sin(p), 0, q * cos(p)}, r), "the press", k);
    check(palp_world_step(w), "the press", k);
  }
  double *t0 = malloc(sizeof(double) * (size_t)steps), *t1 = malloc(sizeof(double) * (size_t)steps);
  if (!t0 || !t1) check(PALP_ENOMEM, "the step times", -1);
  int n0 = 0, n1 = 0, tris = 0;
  for (int block = 0; n0 < steps || n1 < steps; block++) {
    const int with = block % 2;
    for (int k = 0; k < 250; k++) {
      palp_world_wake(w); /* a held finger keeps the world awake anyway; be sure */
      const double a = now_us();
      const int rc = palp_world_step(w);
      if (with) sample(w, f, wr, s);
      const double b = now_us();
      check(rc, with ? "step + sample" : "step only", block * 250 + k);
      if (with && n1 < steps) t1[n1++] = b - a;
      if (!with && n0 < steps) t0[n0++] = b - a;
    }
  }
  {
    int tri[PALP_DB_MAX_SAMPLE_TRIANGLES];
    double tf[PALP_DB_MAX_SAMPLE_TRIANGLES];
    tris = palp_world_finger_contacts(w, f, tri, tf, PALP_DB_MAX_SAMPLE_TRIANGLES);
  }
  qsort(t0, (size_t)n0, sizeof *t0, cmp);
  qsort(t1, (size_t)n1, sizeof *t1, cmp);
  palp_db_log_session_end(wr, s, PALP_DB_END_NORMAL, "bench", 0);
  palp_db_writer_flush(wr, 10);
  palp_db_writer_stats st;
  palp_db_writer_stats_get(wr, &st);
  palp_db_writer_close(wr);
  printf("finger 9 mm in at polar 30 deg, %d triangles touched; %d steps per variant\n", tris, steps);
  /* p99 as the other benchmarks take it: sorted[floor(0.99 (n-1))] */
  const double m0 = t0[n0 / 2], m1 = t1[n1 / 2], q0 = t0[n0 * 9 / 10], q1 = t1[n1 * 9 / 10];
  const double r0 = t0[(int)floor(0.99 * (n0 - 1))], r1 = t1[(int)floor(0.99 * (n1 - 1))];
  printf("step only:            median %.1f us, p90 %.1f us, p99 %.1f us\n", m0, q0, r0);
  printf("step + finger sample: median %.1f us, p90 %.1f us, p99 %.1f us\n", m1, q1, r1);
  printf("added by the sample: %.1f us (median), %.1f us (p90), %.1f us (p99); log: %lld records written, %lld shed\n",
         m1 - m0, q1 - q0, r1 - r0, (long long)st.written, (long long)st.shed);
  printf("step + sample / step only (same run): median %.3f, p99 %.3f\n", m1 / m0, r1 / r0);
  free(t0), free(t1);
  palp_world_destroy(w);
  return 0;
}
