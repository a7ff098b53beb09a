/*
 * test_multirate.c - the station's 1 kHz rendering from a 250 Hz physics rate
 * (issue 11, in-process: no DDS, the same code path as the station's haptic
 * thread minus the network):
 *
 * (a) accuracy: a palp_world stepping at 250 Hz feeds its local contact model to
 *     palp_haptic, which renders at 1 kHz along a press-hold-slide device
 *     trajectory (the simulated device's); a second palp_world computes the same
 *     finger at 1 kHz itself. The rendered force agrees with the 1 kHz force
 *     within 5% of the peak force in RMS over the trajectory (the per-tick
 *     maximum is printed, not asserted: ~22% at the end of the slide, where the
 *     250 Hz physics itself differs from the 1 kHz world's; docs/station.md).
 * (b) passivity: over 100 press-release cycles rendered the same way, the device
 *     receives no more energy than it puts in: the work of the rendered force
 *     along the device path, sum F_k . (x_{k+1} - x_k), is <= 0 within 1% of
 *     the energy the device put in (and per cycle, no cycle returns more than
 *     1% of its input beyond what it took).
 * (c) the force limit: the same 100 cycles with the limit at 60% of the peak, models on
 *     time and late: no tick renders more than the limit (tolerance 1e-12 relative),
 *     the passivity controller's damper included; (d) that damper alone, pressing in
 *     with energy held from earlier, stays under a 0.15 N limit.
 * All run through the station's own per-tick logic (palp_cli_haptic_core), and
 * again with every model reaching the station 40 ms after the device sample its
 * step used: accuracy then no worse than holding the late force, and passivity
 * kept by the station's passivity controller (without it: 68.5 mJ given back
 * for 29.5 mJ put in).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "haptic_loop.h"
#include "input.h"
#include "palp.h"
#include "palp_haptic.h"

/* The phantom (argv[1], default the paper's scene) and the presses' depth scale
 * (argv[2], default 1: 12 mm and 8 mm; the long-term candidate, ~100x stiffer, is
 * pressed a quarter as deep, where a hand meets 2-7 N). */
static const char *scene_path = PALP_CONFIG_DIR "/paper_step.json";
static double depth_scale = 1.0;
/* Late models: the rendered RMS error may exceed the held force's by this factor
 * (argv[4], default 1.05). On a stiff phantom the passivity controller's damper,
 * which must absorb what a late force generates (~K tau), moves the force further
 * from the held one: measured 1.09 at 20 ms on the long-term candidate. */
static double late_rms_factor = 1.05;

static palp_world *make_world(double dt) {
  palp_scene s;
  char err[256];
  if (palp_scene_load(scene_path, &s, err, sizeof err)) {
    fprintf(stderr, "cannot load the scene %s: %s\n", scene_path, err);
    exit(2);
  }
  s.world.dt = dt;
  /* Rebuilds deferred and blended in as the server steps a phantom at this rate. */
  s.world.refactor_lag = palp_world_refactor_lag_for(dt);
  s.world.refactor_blend = palp_world_refactor_blend_for(dt);
  int rc = 0;
  palp_world *w = palp_scene_create_world(&s, &rc);
  if (!w) {
    fprintf(stderr, "cannot build the world: %s\n", palp_strerror(rc));
    exit(2);
  }
  /* As the server does: the scene's scripted contacts removed, the station drives. */
  for (int i = 0; i < s.contact_count; i++) palp_world_remove_contact(w, i);
  return w;
}

static int cmp_d(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}
static double len3(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }
static palp_vec3 sub3(palp_vec3 a, palp_vec3 b) { return (palp_vec3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static double dot3(palp_vec3 a, palp_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/* Finger force of a world after its step (the server's answer at that rate). */
static palp_vec3 world_force(palp_world *w, int f) {
  palp_local_model m;
  if (palp_world_finger_local_model(w, f, &m) < 0 || !m.contact) return (palp_vec3){0, 0, 0};
  return m.force;
}

#define HAPTIC_HZ 1000
#define PHYSICS_HZ 250

/* The server's side of a multi-rate run: the 250 Hz world stepped along the device
 * trajectory, once. The world sees the device point only, never the rendered force, so
 * the models it answers with are the same whatever the station does with them and
 * whenever they reach it: one physics run serves every replay below (models on time and
 * late, any force limit). Until 2026-12-07 each replay stepped its own world: the
 * accuracy trajectory's worlds twice (and its 1 kHz reference twice), the cycles' four
 * times (100 cycles on time and late, 20 for each limit run). */
typedef struct physics_run {
  int n;               /* 1 kHz ticks until the trajectory ends */
  palp_vec3 *x;        /* device point per tick */
  int *on;             /* the device's on flag per tick (palp_cli_simdevice_at) */
  palp_local_model *m; /* the model of the 250 Hz step taken at tick 4 j, at j */
} physics_run;

static void *xalloc(size_t n, size_t size) {
  void *p = calloc(n, size);
  if (!p) {
    fprintf(stderr, "out of memory\n");
    exit(2);
  }
  return p;
}

/* Steps the 250 Hz world along traj for up to cap 1 kHz ticks, each step with the device
 * point of its tick; its local models and the device samples kept in *run. */
static void run_physics(const palp_cli_simdevice_def *traj, int cap, physics_run *run) {
  const int every = HAPTIC_HZ / PHYSICS_HZ;
  palp_world *w = make_world(1.0 / PHYSICS_HZ);
  const double R = palp_world_get_def(w)->mesh.radius;
  run->x = xalloc((size_t)cap, sizeof *run->x);
  run->on = xalloc((size_t)cap, sizeof *run->on);
  run->m = xalloc((size_t)cap / every + 1, sizeof *run->m);
  int f = -1, n = 0;
  for (int k = 0; k < cap; k++) {
    const double t = (double)k / HAPTIC_HZ;
    palp_vec3 p;
    const int on = palp_cli_simdevice_at(traj, R, t, &p);
    if (on == PALP_CLI_INPUT_END) break;
    if (k % every == 0) {
      /* The server's physics step: the device point of this tick, one step ahead. */
      if (f < 0) f = palp_world_add_finger(w, p, traj->radius);
      palp_world_set_finger(w, f, p, traj->radius);
      if (palp_world_step(w) < 0) {
        fprintf(stderr, "250 Hz step failed at t=%.3f\n", t);
        exit(2);
      }
      palp_world_finger_local_model(w, f, &run->m[k / every]);
    }
    run->x[k] = p;
    run->on[k] = on;
    n = k + 1;
  }
  run->n = n;
  palp_world_destroy(w);
}

static void free_physics(physics_run *run) {
  free(run->x), free(run->on), free(run->m);
  memset(run, 0, sizeof *run);
}

/* One multi-rate run through the station's own per-tick logic
 * (palp_cli_haptic_core: re-anchoring, horizon, palp_haptic) on a physics run's
 * models, each reaching the station `latency` ticks after the device sample its step
 * used (0: in the same tick); fills force[k] (rendered) and held[k] (the step's force
 * held, the baseline) per 1 kHz tick. */
#define LAT_MAX 128
static int run_multirate(const physics_run *run, const palp_haptic_def *hd, int latency, palp_vec3 *force,
                         palp_vec3 *held, unsigned *flags_or) {
  palp_vec3 last = {0, 0, 0};
  const int every = HAPTIC_HZ / PHYSICS_HZ;
  palp_cli_haptic_core core;
  palp_cli_haptic_core_init(&core, hd, PHYSICS_HZ, 1, 0, 0.2);
  /* models in flight: (due tick, model, tick its device sample was taken) */
  static palp_local_model q[LAT_MAX];
  static int q_due[LAT_MAX], q_sent[LAT_MAX];
  int qh = 0, qt = 0;
  *flags_or = 0;
  for (int k = 0; k < run->n; k++) {
    const double t = (double)k / HAPTIC_HZ;
    const palp_vec3 p = run->x[k];
    if (k % every == 0) {
      q[qh % LAT_MAX] = run->m[k / every];
      q_due[qh % LAT_MAX] = k + latency;
      q_sent[qh % LAT_MAX] = k;
      qh++;
    }
    palp_local_model m, *mp = NULL;
    double age = -1;
    while (qt < qh && q_due[qt % LAT_MAX] <= k) { /* the newest due model wins, as in the mailbox */
      m = q[qt % LAT_MAX];
      age = (double)(k - q_sent[qt % LAT_MAX]) / HAPTIC_HZ;
      mp = &m;
      last = m.contact ? m.force : (palp_vec3){0, 0, 0};
      qt++;
    }
    palp_haptic_out o;
    palp_cli_haptic_core_tick(&core, run->on[k], p, t, mp, age, &o, NULL);
    *flags_or |= o.flags;
    force[k] = o.force;
    if (held) held[k] = last;
  }
  return run->n;
}

/* The accuracy trajectory's physics: the 250 Hz world's models and the reference, the
 * same finger computed at 1 kHz by the model itself (fref, its peak). Computed once for
 * the runs on time and late: neither world sees the station. */
enum { ACC_CAP = 8000 };
typedef struct accuracy_physics {
  palp_cli_simdevice_def traj;
  physics_run run;
  palp_vec3 *fref;
  double peak;
} accuracy_physics;

static void accuracy_physics_run(accuracy_physics *a) {
  palp_cli_simdevice_def traj = palp_cli_simdevice_default_def(PALP_CLI_SIM_SLIDE);
  traj.polar_deg = 15;
  traj.azimuth_deg = 30;
  traj.depth = 0.012 * depth_scale; /* 12 mm on the default phantom */
  traj.speed = 0.02;       /* 20 mm/s in and out */
  traj.hold = 0.3;
  traj.slide_speed = 0.05; /* 50 mm/s along the surface */
  traj.slide_distance = 0.02;
  a->traj = traj;
  run_physics(&traj, ACC_CAP, &a->run);
  const int n = a->run.n;
  const palp_vec3 *x = a->run.x;
  a->fref = xalloc((size_t)ACC_CAP, sizeof *a->fref);
  palp_world *w = make_world(1.0 / HAPTIC_HZ);
  int f = -1;
  double peak = 0;
  for (int k = 0; k < n; k++) {
    if (f < 0) f = palp_world_add_finger(w, x[k], traj.radius);
    palp_world_set_finger(w, f, x[k], traj.radius);
    if (palp_world_step(w) < 0) {
      fprintf(stderr, "1 kHz step failed\n");
      exit(2);
    }
    a->fref[k] = world_force(w, f);
    if (len3(a->fref[k]) > peak) peak = len3(a->fref[k]);
  }
  palp_world_destroy(w);
  a->peak = peak;
}

static void test_accuracy(const accuracy_physics *a, int latency) {
  enum { CAP = ACC_CAP };
  static palp_vec3 fr[CAP], fzoh[CAP];
  const palp_cli_simdevice_def traj = a->traj;
  const palp_vec3 *fref = a->fref;
  const double peak = a->peak;
  palp_haptic_def hd = palp_haptic_default_def();
  hd.max_force = 100; /* no limiting: the accuracy of the model is measured */
  hd.damping = 0;     /* the device-side damper is not part of the phantom's force */
  unsigned fl = 0;
  const int n = run_multirate(&a->run, &hd, latency, fr, fzoh, &fl);
  /* Errors against the 1 kHz model: the rendered force (local model), the
   * baseline that holds each physics step's force for its period (what a station
   * without a local model renders), and the 250 Hz physics itself at its own
   * steps (the floor no renderer can beat: a 4 ms step is a different
   * discretisation of the same phantom). */
  double emax = 0, e2 = 0, zmax = 0, z2 = 0, pmax = 0, p2 = 0;
  int kmax = 0, np = 0;
  for (int k = 0; k < n; k++) {
    const double e = len3(sub3(fr[k], fref[k])), z = len3(sub3(fzoh[k], fref[k]));
    e2 += e * e;
    z2 += z * z;
    if (z > zmax) zmax = z;
    if (e > emax) {
      emax = e;
      kmax = k;
    }
    if (k % 4 == 0) { /* the 250 Hz step at tick k used x[k], as the 1 kHz step at tick k */
      const double q = len3(sub3(fzoh[k], fref[k]));
      p2 += q * q;
      np++;
      if (q > pmax) pmax = q;
    }
  }
  const double rms = sqrt(e2 / n), zrms = sqrt(z2 / n), prms = sqrt(p2 / (np ? np : 1));
  /* Smoothness: the 99th percentile of the tick-to-tick force step [N]. */
  static double st_r[CAP], st_z[CAP], st_f[CAP];
  for (int k = 1; k < n; k++) {
    st_r[k - 1] = len3(sub3(fr[k], fr[k - 1]));
    st_z[k - 1] = len3(sub3(fzoh[k], fzoh[k - 1]));
    st_f[k - 1] = len3(sub3(fref[k], fref[k - 1]));
  }
  qsort(st_r, (size_t)(n - 1), sizeof(double), cmp_d);
  qsort(st_z, (size_t)(n - 1), sizeof(double), cmp_d);
  qsort(st_f, (size_t)(n - 1), sizeof(double), cmp_d);
  const int i99 = (int)((n - 2) * 0.99);
  printf("accuracy, models %d ms late: %d ticks (press %.1f mm at 20 mm/s, hold, slide 20 mm at 50 mm/s, hold, release), peak %.3f N "
         "(1 kHz model)\n"
         "  rendered at 1 kHz from 250 Hz local models: RMS %.4f N (%.2f%% of peak), max %.4f N (%.2f%%, t=%.3f s: "
         "%.3f vs %.3f N)\n"
         "  baseline, 250 Hz force held 4 ticks:        RMS %.4f N (%.2f%%), max %.4f N (%.2f%%)\n"
         "  250 Hz physics at its own steps (floor):    RMS %.4f N (%.2f%%), max %.4f N (%.2f%%)\n"
         "  tick-to-tick force step, p99: rendered %.4f N, held %.4f N, 1 kHz model %.4f N\n",
         latency, n, 1e3 * traj.depth, peak, rms, 100 * rms / peak, emax, 100 * emax / peak, kmax * 1e-3, len3(fr[kmax]), len3(fref[kmax]), zrms,
         100 * zrms / peak, zmax, 100 * zmax / peak, prms, 100 * prms / peak, pmax, 100 * pmax / peak, st_r[i99], st_z[i99],
         st_f[i99]);
  CHECK(peak > 0.3, "the press reaches a real force: peak %.3f N > 0.3 N", peak);
  CHECK(!(fl & PALP_HAPTIC_LIMITED), "no tick was force-limited (limit 100 N)");
  if (latency > 0) {
    /* A round trip the server cannot know about: reported against the held
     * force of the same late models (what a station without local models would
     * render); asserted: no worse than it, and no more tick-to-tick texture. */
    CHECK(rms <= zrms * late_rms_factor, "models %d ms late: rendered RMS %.4f N <= %.2f x held %.4f N", latency, rms,
          late_rms_factor, zrms);
    CHECK(st_r[i99] <= st_z[i99], "models %d ms late: p99 tick step %.4f <= held %.4f N", latency, st_r[i99], st_z[i99]);
    return;
  }
  CHECK(rms <= 0.05 * peak, "rendered force within 5%% of the peak of the 1 kHz model (RMS over the trajectory): "
                            "%.4f N <= %.4f N", rms, 0.05 * peak);
  CHECK(st_r[i99] < st_z[i99], "the rendered force moves in smaller tick-to-tick steps than the held 250 Hz force "
                                "(p99 %.4f < %.4f N)", st_r[i99], st_z[i99]);
  /* The local model's extrapolation is no worse than holding each step's force: with
   * the surface's own velocity as its drift it was (RMS 1.31-1.67x the held force's on
   * the paper's, the long-term and the breast-tissue phantoms); with the drift
   * observer 1.02-1.08x (palp_drift_observe, docs/haptics.md). Bound 1.10x. */
  CHECK(rms <= 1.10 * zrms, "the local model is as accurate as the held force within 10%% (RMS %.4f N <= 1.10 x "
                            "%.4f N)", rms, zrms);
}

/* count press-release cycles 10 deg off the pole */
static palp_cli_simdevice_def cycles_traj(int count) {
  palp_cli_simdevice_def traj = palp_cli_simdevice_default_def(PALP_CLI_SIM_CYCLES);
  traj.polar_deg = 10;
  traj.depth = 0.008 * depth_scale; /* 8 mm on the default phantom */
  traj.approach = 0.002;
  traj.speed = 0.05;    /* 50 mm/s: a cycle lasts 0.4 s */
  traj.cycle_count = count;
  traj.start = 0.05;
  traj.tail = 0.05;
  return traj;
}

enum { CYC_CAP = 45000 };

/* the 100 cycles of (b) and (c) stepped by the 250 Hz world (physics_run) */
static double test_passivity(const physics_run *run, int latency) {
  const palp_cli_simdevice_def traj = cycles_traj(100);
  enum { CAP = CYC_CAP };
  static palp_vec3 fr[CAP];
  const palp_vec3 *x = run->x;
  palp_haptic_def hd = palp_haptic_default_def(); /* as the station renders: damper on, 10 N limit */
  unsigned fl = 0;
  const int n = run_multirate(run, &hd, latency, fr, NULL, &fl);
  const double cyc = 2 * (traj.depth + traj.approach) / traj.speed; /* [s] */
  double in = 0, out = 0, worst_cycle = -INFINITY, peak = 0;
  double cin = 0, cnet = 0;
  int cycles = 0, cur = -1;
  for (int k = 0; k + 1 < n; k++) {
    /* Zero-order hold: the force of tick k acts while the device moves to x[k+1]. */
    const double dw = dot3(fr[k], sub3(x[k + 1], x[k])); /* [J] to the device */
    if (dw < 0) in -= dw; else out += dw;
    if (len3(fr[k]) > peak) peak = len3(fr[k]);
    const int c = (int)floor((k * 1e-3 - traj.start) / cyc);
    if (c != cur) {
      if (cur >= 0 && cin > 0) {
        const double rel = cnet / cin;
        if (rel > worst_cycle) worst_cycle = rel;
        cycles++;
      }
      cur = c;
      cin = cnet = 0;
    }
    cnet += dw;
    if (dw < 0) cin -= dw;
  }
  const double net = out - in;
  printf("passivity, models %d ms late: %d ticks, %d cycles (%.1f mm at 50 mm/s), peak %.3f N: energy put in by the "
         "device %.4f mJ, given back %.4f mJ, net to the device %.4f mJ (%.2f%% of the input); worst cycle net/in %.4f\n",
         latency, n, cycles, 1e3 * traj.depth, peak, in * 1e3, out * 1e3, net * 1e3, 100 * net / in, worst_cycle);
  CHECK(peak > 0.2, "the cycles press for real: peak %.3f N", peak);
  CHECK(cycles >= 99, "%d press-release cycles measured", cycles);
  CHECK(net <= 0.01 * in, "over 100 cycles the device gets no more energy than it puts in (net %.4f mJ <= 1%% of "
                          "%.4f mJ)", net * 1e3, in * 1e3);
  CHECK(worst_cycle <= 0.01, "no cycle returns more than 1%% of its input energy beyond it (worst %.4f)", worst_cycle);
  return peak;
}

/* (c) the safe force holds whatever adds to the force: the same cycles (all 100 of (b)'s
 * physics run since 2026-12-07, 20 of them before, each on a world of its own), the limit
 * at 60% of the peak the unlimited rendering reached. With late models the passivity
 * controller's damper acts on top of the renderer's (limited) force; once it took the
 * force 3.5x past a 0.15 N limit (test haptic_session, a loaded machine). */
static void test_limit(const physics_run *run, int latency, double peak) {
  enum { CAP = CYC_CAP };
  static palp_vec3 fr[CAP];
  palp_haptic_def hd = palp_haptic_default_def();
  hd.max_force = 0.6 * peak;
  unsigned fl = 0;
  const int n = run_multirate(run, &hd, latency, fr, NULL, &fl);
  double top = 0;
  int at_limit = 0;
  for (int k = 0; k < n; k++) {
    const double m = len3(fr[k]);
    if (m > top) top = m;
    at_limit += m >= hd.max_force * (1 - 1e-9);
  }
  printf("force limit %.4f N (0.6 x the peak), models %d ms late: %d ticks, %d at the limit, largest rendered %.6f N\n",
         hd.max_force, latency, n, at_limit, top);
  CHECK(fl & PALP_HAPTIC_LIMITED, "models %d ms late: some ticks were limited", latency);
  CHECK(top <= hd.max_force * (1 + 1e-12), "models %d ms late: no tick rendered more than the limit (%.6f N <= %.6f N)",
        latency, top, hd.max_force);
}

/* (d) the passivity controller's damper under the limit: a finger pressing in at
 * 0.1 m/s onto a model of 0.1 N while the observer holds energy from earlier (as late
 * or jittered models leave it; set here). Pressing in, the damper -a v adds to the
 * force (up to the 20 N s/m limit: 2 N); the device must still get at most the safe
 * force, 0.15 N (tolerance 1e-12 relative), and the tick is flagged limited. */
static void test_limit_controller(void) {
  palp_haptic_def hd = palp_haptic_default_def();
  hd.max_force = 0.15;
  hd.damping = 0; /* the renderer's own damper off: the controller's alone */
  palp_cli_haptic_core c;
  CHECK(palp_cli_haptic_core_init(&c, &hd, 250, 1, 0, 0.2) == 0, "core initialised");
  palp_local_model m;
  memset(&m, 0, sizeof m);
  m.period = 0.004, m.contact = 1, m.triangles = 1;
  m.normal = (palp_vec3){0, 0, 1}, m.force = (palp_vec3){0, 0, 0.1};
  double top = 0;
  unsigned fl = 0;
  int acted = 0;
  for (int k = 0; k < 20; k++) {
    const double t = 1e-3 * k;
    const palp_vec3 x = {0, 0, -1e-4 * k}; /* in at 0.1 m/s */
    m.device = x, m.proxy = (palp_vec3){0, 0, 0}, m.time = t;
    palp_local_model mk = m;
    if (k >= 2) c.energy = 1e-3; /* [J] held from earlier */
    const uint64_t before = c.pc_ticks;
    palp_haptic_out o;
    palp_cli_haptic_core_tick(&c, 1, x, t, k % 4 == 0 ? &mk : NULL, 0.0, &o, NULL);
    acted += c.pc_ticks > before;
    if (k >= 2) fl |= o.flags;
    if (len3(o.force) > top) top = len3(o.force);
  }
  printf("passivity controller under a 0.15 N limit: acted on %d ticks, largest rendered %.6f N, limited: %s\n", acted,
         top, fl & PALP_HAPTIC_LIMITED ? "yes" : "no");
  CHECK(acted > 10, "the controller acted (%d ticks)", acted);
  CHECK(top <= 0.15 * (1 + 1e-12), "the damper never took the force past the limit: %.6f N <= 0.15 N", top);
  CHECK(fl & PALP_HAPTIC_LIMITED, "the limited ticks are flagged (shown to the trainee)");
}

int main(int argc, char **argv) {
  if (argc > 1) scene_path = argv[1];
  if (argc > 2) depth_scale = atof(argv[2]);
  const int late_ms = argc > 3 ? atoi(argv[3]) : 40; /* the round trip of the second pass [ms] */
  if (argc > 4) late_rms_factor = atof(argv[4]);
  if (!(depth_scale > 0 && depth_scale <= 2)) {
    fprintf(stderr, "depth scale %s: expected (0, 2]\n", argv[2]);
    return 2;
  }
  printf("phantom %s, depths x%.2f\n", scene_path, depth_scale);
  accuracy_physics acc;
  accuracy_physics_run(&acc);
  physics_run cyc;
  const palp_cli_simdevice_def cycles = cycles_traj(100);
  run_physics(&cycles, CYC_CAP, &cyc);
  test_accuracy(&acc, 0);
  test_passivity(&cyc, 0);
  /* The same with every model reaching the station late_ms (40) after the device
   * sample its step used (a 40 ms round trip), through the same station logic. */
  test_accuracy(&acc, late_ms);
  const double peak = test_passivity(&cyc, late_ms);
  test_limit_controller();
  test_limit(&cyc, 0, peak);
  test_limit(&cyc, late_ms, peak);
  free_physics(&acc.run);
  free(acc.fref);
  free_physics(&cyc);
  return check_exit();
}
