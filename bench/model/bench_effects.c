/*
 * bench_model_effects - what each effect costs per step, and that a scene without
 * an effect does not pay for it: the median step time with every effect on, then
 * with each effect removed in turn (and its dependants), at 338 vertices and 10 ms,
 * under the paper's 3 N uniform load (--load for another). Also the cost of a sleeping
 * world's step (no gravity, no load: it exits 1 if those steps were not asleep). Each row
 * prints the refactorisations, split steps and base contacts of its timed steps: a reduced
 * model whose dome collapses onto its base under the load is marked so, since its time is
 * then the collapse's, not what its effects cost (session 82).
 *
 *   bench_model_effects [--steps N] [--load NEWTONS]
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

/* One case's timed steps, and what the world had to do in them: a case whose dome collapses
 * onto its base (base contacts) or refactorises every step measures that, not its effects. */
typedef struct {
  double med, p99;          /* [s] of one step */
  int64_t awake;            /* timed steps stepped awake (palp_stage_timings.steps) */
  int64_t refactors;        /* factorisations in the timed steps */
  int64_t substeps;         /* steps split in halves in the timed steps */
  int64_t base_contacts;    /* vertex-steps held at the base plane in the timed steps */
} effect_run;

/* load_n: the uniform load [N]; 0 means none, the world is stepped until it sleeps (at most
 * 5000 steps, 50 s simulated) and its timed steps must all be asleep: the case exits 1 if not. */
static effect_run run_case(uint32_t effects, int steps, double load_n, char *stages, size_t len) {
  palp_world_def d = palp_world_default_def();
  d.effects = effects;
  int e;
  palp_world *w = palp_world_create(&d, &e);
  if (!w) check(e, effects, "cannot create the world", -1);
  const palp_vec3 c = {0.04 * sin(0.5236) * cos(0.698), 0.04 * sin(0.5236) * sin(0.698), 0.04 * cos(0.5236)};
  palp_contact_def cd = palp_contact_default_def(PALP_DIST_UNIFORM, c);
  const int id = palp_world_add_contact(w, &cd);
  check(id, effects, "the load", -1);
  long k = 0;
  if (load_n > 0)
    check(palp_world_set_contact_force(
              w, id, (palp_vec3){-load_n * c.x / 0.04, -load_n * c.y / 0.04, -load_n * c.z / 0.04}),
          effects, "the load", -1);
  else {
    while (palp_world_is_awake(w) && k < 5000) check(palp_world_step(w), effects, "falling asleep", k++);
    if (palp_world_is_awake(w)) {
      fprintf(stderr, "bench_model_effects: effects 0x%x, no load: still awake after %ld steps\n",
              (unsigned)effects, k);
      exit(1);
    }
  }
  for (int i = 0; i < 20; ++i, ++k) check(palp_world_step(w), effects, "warming up", k);
  palp_stage_timings t0, t1;
  palp_world_health h0, h1;
  palp_world_timings(w, &t0);
  palp_world_get_health(w, &h0);
  double *t = malloc(sizeof(double) * (size_t)steps);
  if (!t) check(PALP_ENOMEM, effects, "the step times", -1);
  for (int i = 0; i < steps; ++i, ++k) {
    const double s = now_s();
    const int rc = palp_world_step(w);
    t[i] = now_s() - s;
    check(rc, effects, "timed", k);
  }
  qsort(t, (size_t)steps, sizeof *t, cmpd);
  effect_run r = {.med = t[steps / 2], .p99 = t[(int)floor(0.99 * (steps - 1))]};
  free(t);
  palp_world_timings(w, &t1);
  palp_world_get_health(w, &h1);
  r.awake = t1.steps - t0.steps;
  r.refactors = t1.refactors - t0.refactors;
  r.substeps = h1.substeps - h0.substeps;
  r.base_contacts = h1.base_contacts - h0.base_contacts;
  size_t o = 0;
  stages[0] = 0;
  for (int s = 0; s < PALP_STAGE_COUNT && t1.name[s]; ++s)
    o += (size_t)snprintf(stages + o, o < len ? len - o : 0, "%s%s", s ? "," : "", t1.name[s]);
  palp_world_destroy(w);
  return r;
}

static void row(const char *name, const effect_run *r, const effect_run *base, const char *stages) {
  printf("%-34s %9.1f %8.1f %7.2f %7.2f %6lld %6lld %9lld %s%s\n", name, 1e6 * r->med, 1e6 * r->p99, r->med / base->med,
         r->p99 / base->p99, (long long)r->refactors, (long long)r->substeps, (long long)r->base_contacts,
         r->base_contacts ? "COLLAPSED onto the base: not the effects' cost; " : "", stages);
}

int main(int argc, char **argv) {
  int steps = 2000;
  double load = 3.0;
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
    } else if (!strcmp(argv[i], "--load")) {
      char *end;
      const double v = strtod(argv[i + 1], &end);
      if (*end || end == argv[i + 1] || !(v > 0 && v <= 30)) {
        fprintf(stderr, "bench_model_effects: --load must be a force in N above 0, at most 30 (got \"%s\")\n",
                argv[i + 1]);
        return 2;
      }
      load = v;
    }
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(0, &set);
  sched_setaffinity(0, sizeof set, &set);
  const uint32_t all = PALP_EFFECT_ALL;
  char stages[512];
  const effect_run base = run_case(all, steps, load, stages, sizeof stages);
  printf("palp effect costs: 338 vertices, 10 ms, %.3g N uniform load, %d timed steps a case; ratios to "
         "\"all effects\" (this run)\n",
         load, steps);
  printf("%-34s %9s %8s %7s %7s %6s %6s %9s %s\n", "scene", "median_us", "p99_us", "med/all", "p99/all", "refact",
         "split", "base_vtx", "stages run");
  row("all effects", &base, &base, stages);
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
    const effect_run r = run_case(fx, steps, load, stages, sizeof stages);
    row(cases[k].name, &r, &base, stages);
  }
  /* Since session 81 a world under gravity never sleeps (docs/model.md), so the sleeping case
   * has every effect but gravity, and no load; run_case checks that its timed steps slept. */
  const effect_run sleeping = run_case(all & ~(uint32_t)PALP_EFFECT_GRAVITY, steps, 0, stages, sizeof stages);
  printf("%-34s %9.3f %8.3f %7.4f %7.4f (no gravity, no load: %lld of %d timed steps awake)\n",
         "all but gravity, asleep", 1e6 * sleeping.med, 1e6 * sleeping.p99, sleeping.med / base.med,
         sleeping.p99 / base.p99, (long long)sleeping.awake, steps);
  if (sleeping.awake) {
    fprintf(stderr, "bench_model_effects: the sleeping case stepped %lld of its timed steps awake\n",
            (long long)sleeping.awake);
    return 1;
  }
  return 0;
}
