/*
 * bench_model_effects - what each effect costs per step, and that a scene without
 * an effect does not pay for it: the median step time with every effect on, then
 * with each effect removed in turn (and its dependants), at 338 vertices and 10 ms,
 * under the paper's 3 N uniform load. Also the cost of a sleeping world's step.
 *
 *   bench_model_effects [--steps N]
 */
#define _GNU_SOURCE
#include <math.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "palp.h"

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
static int cmpd(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* A world that refuses a step or the load measures nothing (a broken world "steps" in well
 * under a microsecond): stop and say which case, which step and why. */
static void check(int rc, uint32_t effects, const char *what, long step) {
  if (rc >= 0) return;
  fprintf(stderr, "bench_model_effects: effects 0x%x: %s", (unsigned)effects, what);
  if (step >= 0) fprintf(stderr, ", step %ld", step);
  fprintf(stderr, ": %s\n", palp_strerror(rc));
  exit(1);
}

static double median_step(uint32_t effects, int steps, int load, char *stages, size_t len) {
  palp_world_def d = palp_world_default_def();
  d.effects = effects;
  int e;
  palp_world *w = palp_world_create(&d, &e);
  if (!w) check(e, effects, "cannot create the world", -1);
  const palp_vec3 c = {0.04 * sin(0.5236) * cos(0.698), 0.04 * sin(0.5236) * sin(0.698), 0.04 * cos(0.5236)};
  palp_contact_def cd = palp_contact_default_def(PALP_DIST_UNIFORM, c);
  const int id = palp_world_add_contact(w, &cd);
  check(id, effects, "the 3 N load", -1);
  long k = 0;
  if (load)
    check(palp_world_set_contact_force(w, id, (palp_vec3){-3 * c.x / 0.04, -3 * c.y / 0.04, -3 * c.z / 0.04}),
          effects, "the 3 N load", -1);
  else
    for (int i = 0; i < 200; ++i, ++k) check(palp_world_step(w), effects, "falling asleep", k);
  for (int i = 0; i < 20; ++i, ++k) check(palp_world_step(w), effects, "warming up", k);
  double *t = malloc(sizeof(double) * (size_t)steps);
  if (!t) check(PALP_ENOMEM, effects, "the step times", -1);
  for (int i = 0; i < steps; ++i, ++k) {
    const double s = now_s();
    const int rc = palp_world_step(w);
    t[i] = now_s() - s;
    check(rc, effects, "timed", k);
  }
  qsort(t, (size_t)steps, sizeof *t, cmpd);
  const double med = t[steps / 2];
  free(t);
  palp_stage_timings tm;
  palp_world_timings(w, &tm);
  size_t o = 0;
  stages[0] = 0;
  for (int s = 0; s < PALP_STAGE_COUNT && tm.name[s]; ++s)
    o += (size_t)snprintf(stages + o, o < len ? len - o : 0, "%s%s", s ? "," : "", tm.name[s]);
  palp_world_destroy(w);
  return med;
}

int main(int argc, char **argv) {
  int steps = 2000;
  for (int i = 1; i + 1 < argc; ++i)
    if (!strcmp(argv[i], "--steps")) {
      char *end;
      const long v = strtol(argv[i + 1], &end, 10);
      /* the median is of these steps: none (0 read t[0] of an empty sample) is no run */
      if (*end || end == argv[i + 1] || v < 1 || v > 100000000) {
        fprintf(stderr, "bench_model_effects: --steps must be a whole number from 1 to 100000000 (got \"%s\")\n",
                argv[i + 1]);
        return 2;
      }
      steps = (int)v;
    }
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(0, &set);
  sched_setaffinity(0, sizeof set, &set);
  const uint32_t all = PALP_EFFECT_ALL;
  char stages[512];
  const double base = median_step(all, steps, 1, stages, sizeof stages);
  printf("palp effect costs: 338 vertices, 10 ms, 3 N uniform load, median of %d steps\n", steps);
  printf("%-34s %10s %10s %s\n", "scene", "median_us", "vs_all", "stages run");
  printf("%-34s %10.1f %10.2f %s\n", "all effects", 1e6 * base, 1.0, stages);
  struct {
    const char *name;
    uint32_t off;
  } cases[] = {
      {"without gravity", PALP_EFFECT_GRAVITY},
      {"without force_feedback", PALP_EFFECT_FORCE_FEEDBACK},
      {"without membrane_viscosity", PALP_EFFECT_MEMBRANE_VISCOSITY},
      {"without gel_damping", PALP_EFFECT_GEL_DAMPING},
      {"without gel_support", PALP_EFFECT_GEL_SUPPORT},
      {"without gel_pressure (+damping)", PALP_EFFECT_GEL_PRESSURE},
      {"membrane elasticity only", all & ~(uint32_t)PALP_EFFECT_MEMBRANE_ELASTICITY},
  };
  for (size_t k = 0; k < sizeof cases / sizeof *cases; ++k) {
    uint32_t fx = all & ~cases[k].off;
    if (!(fx & PALP_EFFECT_GEL_PRESSURE) && !(fx & PALP_EFFECT_GEL_SUPPORT)) fx &= ~(uint32_t)PALP_EFFECT_GEL_DAMPING;
    if (!strcmp(cases[k].name, "membrane elasticity only")) fx = PALP_EFFECT_MEMBRANE_ELASTICITY;
    const double m = median_step(fx, steps, 1, stages, sizeof stages);
    printf("%-34s %10.1f %10.2f %s\n", cases[k].name, 1e6 * m, m / base, stages);
  }
  const double sleeping = median_step(all, steps, 0, stages, sizeof stages);
  printf("%-34s %10.3f %10.4f (no load: the world sleeps)\n", "all effects, asleep", 1e6 * sleeping, sleeping / base);
  return 0;
}
