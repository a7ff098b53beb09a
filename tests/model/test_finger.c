/*
 * test_finger.c - the fingertip against the deforming surface (issue 11,
 * docs/haptics.md): no slip-through at any depth, force monotone in depth at rest,
 * smooth force while sliding, the table stops the tip, the local contact model
 * predicts the next step, and the drift it carries stays a surface's speed.
 *
 * The phantom is the shipped default (calibrated, soft: ~2.9 N at 30 mm at the pole),
 * stepped at 1 kHz; the fingertip is the default 8 mm sphere with a 2000 N/m coupling.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "finger.h"
#include "palp.h"
#include "palp_haptic.h"

#define PALP_TEST_PI 3.14159265358979323846
static const double R = 0.04, r = 0.008;

static palp_vec3 add(palp_vec3 a, palp_vec3 b) { return (palp_vec3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static palp_vec3 sc(palp_vec3 a, double s) { return (palp_vec3){a.x * s, a.y * s, a.z * s}; }
static double dot(palp_vec3 a, palp_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static double len(palp_vec3 a) { return sqrt(dot(a, a)); }

static palp_world *make_surface_lag(double dt, int surface, int lag, int blend) {
  palp_world_def d = palp_world_default_def();
  d.dt = dt;
  d.finger_surface = surface;
  d.refactor_lag = lag;
  d.refactor_blend = blend;
  int err = 0;
  palp_world *w = palp_world_create(&d, &err);
  if (!w) {
    fprintf(stderr, "world: %s\n", palp_strerror(err));
    exit(2);
  }
  return w;
}

static palp_world *make_surface(double dt, int surface) { return make_surface_lag(dt, surface, 0, 0); }

/* The library's default surface (smooth since 2026-11-27). */
static palp_world *make(double dt) { return make_surface(dt, palp_world_default_def().finger_surface); }

/* A shipped scene's world for a finger alone (palp_world_create adds none of the
 * scene's scripted contacts), stepped at dt (the scene's own when dt is 0), on the
 * given contact surface (the scene's when surface < 0), with the given rebuild lag and
 * blend (def.refactor_lag, refactor_blend; 0 and 0 rebuild at once, the library's
 * default). NULL, with a failed check, if the scene does not load. */
static palp_world *scene_world(const char *path, double dt, int surface, double *dt_out, int lag, int blend) {
  palp_scene sc_;
  char err[256];
  if (palp_scene_load(path, &sc_, err, sizeof err)) {
    CHECK(0, "%s: %s", path, err);
    return NULL;
  }
  if (dt > 0.0) sc_.world.dt = dt;
  if (surface >= 0) sc_.world.finger_surface = surface;
  sc_.world.refactor_lag = lag;
  sc_.world.refactor_blend = blend;
  int e = 0;
  palp_world *w = palp_world_create(&sc_.world, &e);
  CHECK(w != NULL, "%s: world: %s", path, palp_strerror(e));
  if (!w) return NULL;
  if (dt_out) *dt_out = sc_.world.dt;
  return w;
}

/* Deepest penetration of the proxy sphere into any dome triangle [m] (0 if none),
 * and whether the proxy centre lies on the inner side of the triangle it is closest
 * to (a slip-through). */
static double penetration(const palp_world *w, palp_vec3 p, int *inside) {
  const palp_mesh *m = palp_world_mesh(w);
  const palp_vec3 *x = palp_world_positions(w);
  double best = INFINITY, pen = 0.0;
  *inside = 0;
  for (int t = 0; t < m->dome_triangle_count; ++t) {
    const int *T = m->tri[t];
    double bary[3];
    const palp_vec3 q = palp_tri_closest(p, x[T[0]], x[T[1]], x[T[2]], bary);
    const palp_vec3 d = add(p, sc(q, -1.0));
    const double dist = len(d);
    if (r - dist > pen) pen = r - dist;
    if (dist < best) {
      best = dist;
      const palp_vec3 e1 = add(x[T[1]], sc(x[T[0]], -1)), e2 = add(x[T[2]], sc(x[T[0]], -1));
      const palp_vec3 nf = {e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x};
      *inside = dot(d, nf) < -1e-12;
    }
  }
  return pen;
}

/* Presses the device from just above the surface along dir (unit, into the phantom)
 * from start, in 2 mm increments (10 mm/s) to 2 * nlevel mm, each level 0.5 s of
 * travel and hold, in the world w (destroyed here) at its own step dt; checks contact
 * and the proxy at every tick and returns the settled force along -dir at each depth. */
static void press_world(const char *what, palp_world *w, double dt, int nlevel, double pen_max, palp_vec3 start,
                        palp_vec3 dir, double *settled, int *levels) {
  const int f = palp_world_add_finger(w, start, r);
  const int ticks = (int)lround(0.5 / dt);
  double depth = 0.0, max_pen = 0.0;
  int lost = 0, slipped = 0, n = 0, touched = 0;
  for (int level = 1; level <= nlevel; ++level) {
    const double target = 0.002 * level;
    for (int k = 0; k < ticks; ++k) {
      if (depth < target) depth = fmin(target, depth + 0.01 * dt); /* 10 mm/s */
      palp_world_set_finger_device(w, f, add(start, sc(dir, depth)));
      CHECK(palp_world_step(w) == 0, "%s: step at depth %.1f mm", what, depth * 1e3);
      palp_local_model lm;
      palp_world_finger_local_model(w, f, &lm);
      int inside = 0;
      const double pen = penetration(w, lm.proxy, &inside);
      if (pen > max_pen) max_pen = pen;
      slipped += inside;
      if (lm.contact) touched = 1;
      else if (touched) lost++;
      if (k == ticks - 1) settled[n++] = -dot(lm.force, dir);
    }
  }
  *levels = n;
  printf("%s: settled force at 2..%d mm:", what, 2 * nlevel);
  for (int i = 0; i < n; ++i) printf(" %.3f", settled[i]);
  printf(" N; proxy penetration max %.3f mm, ticks out of contact after touching %d, behind the surface %d\n",
         max_pen * 1e3, lost, slipped);
  CHECK(touched, "%s: the fingertip touched the surface", what);
  CHECK(lost == 0, "%s: contact kept all the way (%d ticks lost)", what, lost);
  CHECK(slipped == 0, "%s: the proxy never passed behind the surface (%d ticks)", what, slipped);
  /* The proxy rests on the surface: penetration only from the linearisation. */
  CHECK(max_pen < pen_max, "%s: proxy penetration %.3f mm < %.1f mm", what, max_pen * 1e3, pen_max * 1e3);
  for (int i = 1; i < n; ++i)
    CHECK(settled[i] > settled[i - 1] * 1.001, "%s: settled force rises with depth: %.4f N at %d mm after %.4f N",
          what, settled[i], 2 * (i + 1), settled[i - 1]);
  palp_world_health hh;
  palp_world_get_health(w, &hh);
  CHECK(hh.finger_unsolved == 0, "%s: every contact solve converged (%lld did not)", what,
        (long long)hh.finger_unsolved);
  palp_world_destroy(w);
}

/* press_world on the library's default phantom at 1 kHz, to 30 mm. */
static void press(const char *what, palp_vec3 start, palp_vec3 dir, double *settled, int *levels) {
  press_world(what, make(0.001), 0.001, 15, 0.5e-3, start, dir, settled, levels);
}

static void test_presses(void) {
  double F[16];
  int n = 0;
  /* At the pole, straight down. */
  press("pole", (palp_vec3){0, 0, R + r + 0.001}, (palp_vec3){0, 0, -1}, F, &n);
  CHECK(n == 15 && F[14] > 1.0, "pole: 30 mm deep holds more than 1 N (%.3f N)", F[14]);
  /* At 60 degrees from the pole, along the inward normal. */
  const double a = 60.0 * PALP_TEST_PI / 180.0;
  const palp_vec3 n60 = {sin(a), 0, cos(a)};
  press("60 deg", sc(n60, R + r + 0.001), sc(n60, -1.0), F, &n);
  /* 5 degrees above the rim: an 8 mm tip there rests on the table (its centre cannot
   * go below z = r), so it presses horizontally towards the axis at the height of
   * the dome point 5 degrees above the rim plus the table's clearance. */
  const double b = 85.0 * PALP_TEST_PI / 180.0;
  const double zc = r;                                /* tip on the table */
  const double x0 = sqrt(R * R - 0.0) * sin(b) + r + 0.001; /* outside the rim region */
  press("5 deg above the rim", (palp_vec3){x0, 0, zc}, (palp_vec3){-1, 0, 0}, F, &n);
}

/* A shipped dome pressed deep in 2 mm levels at its scene's own step. The breast-tissue
 * phantom the exercises and the demo's dome D use (250 Hz): at the pole and 45 deg to 34 mm of device
 * travel (~25 mm of indentation, ~17 N), at 70 deg to 30 mm (the tip meets the table).
 * A parameter set whose skin creeps without bound (a Burgers membrane with its Kelvin
 * spring at 0.08% of E1 and 0.4% added mass: the breast-tissue refit of 2026-11-27,
 * withdrawn) went through the surface here at the pole from 28 mm (after 8.1 N; its
 * links strained by up to 179%; docs/materials.md). The proxy sinks into the surface by
 * the contact's linearisation, more on this softer phantom at 25 mm and 16 N than on
 * the default one: measured 1.51-1.64 mm, bound 2 mm; deepest levels 18.0 / 19.2 /
 * 19.1 N (2026-11-28, the set whose support relaxes as its FEM's gel does; 0.83-1.48 mm
 * and 15.9 / 14.7 / 13.3 N with the 2026-11-26 set). The shipped long-term dome (its scene's 10 ms step) the same way: 35.7 / 34.9 /
 * 30.8 N at the deepest levels, far beyond the server's 20 N limit, the proxy at most
 * 1.18 mm into the surface. */
static void test_deep_press(const char *scene, const char *name) {
  const double polar[3] = {0, 45, 70};
  const int nlevel[3] = {17, 17, 15};
  for (int i = 0; i < 3; ++i) {
    double dt = 0.0;
    palp_world *w = scene_world(scene, 0.0, -1, &dt, 0, 0);
    if (!w) return;
    const double a = polar[i] * PALP_TEST_PI / 180.0;
    const palp_vec3 n = {sin(a), 0, cos(a)};
    char what[96];
    snprintf(what, sizeof what, "%s, %g deg", name, polar[i]);
    double F[20];
    int m = 0;
    press_world(what, w, dt, nlevel[i], 2.0e-3, sc(n, R + r + 0.001), sc(n, -1.0), F, &m);
    CHECK(m == nlevel[i] && F[m - 1] > 8.0, "%s: the deepest level holds more than 8 N (%.3f N)", what,
          m ? F[m - 1] : 0.0);
  }
}

/* Sliding at 50 mm/s across the pole at 10 mm depth, 1 kHz: no tick-to-tick force
 * step beyond what the motion explains. The device moves at a constant speed along a
 * smooth path, so the force it meets changes smoothly too (the surface's curvature,
 * the dent it drags along); what is left after the local linear trend,
 *   s_k = |F_k - 2 F_{k-1} + F_{k-2}|,
 * is a step the hand would feel as texture that is not there (a vertex entering
 * contact, a contact switching feature). Measured after the first 50 ticks, where the
 * device's speed itself steps from 0 to 50 mm/s.
 * The target is max(2% of the force, 0.01 N). With a rigid pad (pad_stiffness 0)
 * the contact moving onto another facet stepped the force by up to 0.022 N; the
 * default compliant pad spreads the load over the facets it touches (docs/haptics.md).
 * Both contact surfaces are held to it: the smooth one (the default) and the facets. */
static void test_slide_in(const char *sn, palp_world *w, int max_over);

static void test_slide(int surface) {
  test_slide_in(palp_finger_surface_name(surface), make_surface(0.001, surface), 0);
}

/* The same slide on the shipped domes, at 1 kHz physics, stepped as the server steps
 * them: rebuilt tangents deferred by 16 frames and blended in over 8
 * (palp_world_refactor_lag_for / _blend_for), and with the blend alone. Before the blend
 * the breast-tissue dome of the exercises stepped at its tangent rebuilds (12 of 1,062
 * ticks over, max 4.2% of the force, 0.149 N; 14 with the lag); before the lag's safety
 * trigger the long-term dome rang at the Nyquist rate while a deferred rebuild waited
 * (85 ticks over, 30%). With both, one tick over was left on the long-term dome (2.07%
 * of the force, 0.0076 N beyond the bound): the dome ringing while a turned stiff link
 * outgrew what its vertex held, which the turn rule now rebuilds before (docs/haptics.md,
 * "A turned stiff link rings"). */
static void test_slide_shipped(void) {
  const char *scene[2] = {PALP_CONFIG_DIR "/paper_step_long_term.json", PALP_CONFIG_DIR "/phantoms/dome.json"};
  const char *name[2][2] = {{"long-term dome, as served", "breast-tissue dome, as served"},
                            {"long-term dome, blend alone", "breast-tissue dome, blend alone"}};
  const int max_over[2][2] = {{0, 0}, {0, 0}};
  for (int lag = 1; lag >= 0; --lag)
    for (int i = 0; i < 2; ++i) {
      palp_world *w = scene_world(scene[i], 0.001, -1, NULL, lag ? palp_world_refactor_lag_for(0.001) : 0,
                                  palp_world_refactor_blend_for(0.001));
      if (w) test_slide_in(name[!lag][i], w, max_over[!lag][i]);
    }
}

/* What a slide measured (slide). */
typedef struct slide_stats {
  int ticks, over, lost;     /* ticks slid; over max(2%, 0.01 N) beyond the trend; out of contact */
  double worst, worst_raw;   /* largest step beyond the trend, and tick-to-tick change, / force */
  double worst_n, margin;    /* the largest such step [N]; the least margin to max(2%, 0.01 N) [N] */
  double fmin;               /* the least force [N] */
  long long rebuilds, at_once; /* tangent rebuilds, and those made at once (health.margin_rebuilds) */
} slide_stats;

/* The device's path: a circle of radius R + r - depth in the plane through the pole at
 * azimuth az, from polar -40 to +40 degrees at speed v, entered by a 10 mm/s press at
 * -40 degrees and 0.3 s of settling. Measured after the first 50 ticks, where the
 * device's speed itself steps from 0 to v. */
static slide_stats slide(palp_world *w, double depth, double v, double az) {
  const double rho = R + r - depth, a0 = -40.0 * PALP_TEST_PI / 180.0, ca = cos(az), sa = sin(az);
#define SLIDE_AT(rad, ph) ((palp_vec3){(rad) * sin(ph) * ca, (rad) * sin(ph) * sa, (rad) * cos(ph)})
  const int f = palp_world_add_finger(w, SLIDE_AT(R + r + 0.001, a0), r);
  for (int k = 0; k <= 1100; ++k) {
    const double s = fmin(1.0, k / 1100.0), rr = (R + r + 0.001) * (1 - s) + rho * s;
    palp_world_set_finger_device(w, f, SLIDE_AT(rr, a0));
    palp_world_step(w);
  }
  for (int k = 0; k < 300; ++k) palp_world_step(w); /* settle */
  slide_stats st = {.margin = INFINITY, .fmin = INFINITY};
  palp_world_health h0, h1;
  palp_world_get_health(w, &h0);
  palp_vec3 F1 = {0, 0, 0}, F2 = {0, 0, 0};
  for (double phi = a0; phi < -a0; phi += v * 0.001 / rho, ++st.ticks) {
    palp_world_set_finger_device(w, f, SLIDE_AT(rho, phi));
    palp_world_step(w);
    palp_local_model lm;
    palp_world_finger_local_model(w, f, &lm);
    st.lost += !lm.contact;
    const double Fm = len(lm.force);
    if (st.ticks >= 50) {
      const double step = len(add(add(lm.force, sc(F1, -2.0)), F2)), raw = len(add(lm.force, sc(F1, -1.0)));
      st.over += step > fmax(0.02 * Fm, 0.01);
      st.worst_n = fmax(st.worst_n, step);
      st.margin = fmin(st.margin, fmax(0.02 * Fm, 0.01) - step);
      if (step / Fm > st.worst) st.worst = step / Fm;
      if (raw / Fm > st.worst_raw) st.worst_raw = raw / Fm;
      st.fmin = fmin(st.fmin, Fm);
    }
    if (getenv("SLIDE_TRACE"))
      printf("T %d %.5f %.5f %.5f %.5f %d\n", st.ticks, lm.force.x, lm.force.y, lm.force.z, Fm, lm.triangles);
    F2 = F1, F1 = lm.force;
  }
#undef SLIDE_AT
  palp_world_get_health(w, &h1);
  st.rebuilds = (long long)(h1.refactors - h0.refactors);
  st.at_once = (long long)(h1.margin_rebuilds - h0.margin_rebuilds);
  return st;
}

/* The slide of test_slide_shipped at two depths, two speeds and in two planes on both
 * shipped domes, as served at 1 kHz. Before the turn rule (world.c, PALP_TURN_STALE)
 * 6 of the 8 long-term slides had ticks over (27 ticks, worst 4.2% of the force: the
 * dome rang at the Nyquist rate for ~10 ticks while a stiff skin link turned into a
 * vertex's soft direction) and 1 of the 8 breast-tissue ones (10 ticks, 5.3%: a rebuild
 * made at once, unblended; docs/haptics.md, "A turned stiff link rings"). */
static long long slide_grid_on(int nscene, const char *const *scene, const char *const *dome, int *slides_out);

static void test_slide_grid(void) {
  const char *scene[2] = {PALP_CONFIG_DIR "/paper_step_long_term.json", PALP_CONFIG_DIR "/phantoms/dome.json"};
  const char *dome[2] = {"long-term", "breast-tissue"};
  int slides = 0;
  const long long at_once_all = slide_grid_on(2, scene, dome, &slides);
  /* the rebuilds made at once (the turn rule's, blended) are exercised */
  CHECK(at_once_all >= 1, "slide grid: rebuilds made at once over the %d slides (%lld)", slides, at_once_all);
}

/* The grid's slides on each scene; the rebuilds made at once over them. */
static long long slide_grid_on(int nscene, const char *const *scene, const char *const *dome, int *slides_out) {
  long long at_once_all = 0;
  int slides = 0;
  for (int i = 0; i < nscene; ++i)
    for (int d = 0; d < 2; ++d)
      for (int s = 0; s < 2; ++s)
        for (int a = 0; a < 2; ++a) {
          const double depth = d ? 0.012 : 0.008, v = s ? 0.100 : 0.020, az = a ? PALP_TEST_PI / 4 : 0.0;
          palp_world *w = scene_world(scene[i], 0.001, -1, NULL, palp_world_refactor_lag_for(0.001),
                                      palp_world_refactor_blend_for(0.001));
          if (!w) return at_once_all;
          const slide_stats st = slide(w, depth, v, az);
          printf("slide grid (%s dome, as served): %.0f mm deep, %.0f mm/s, azimuth %.0f deg: %d ticks over max(2%%, "
                 "0.01 N), worst %.2f%% of the force, %d ticks out of contact, %lld rebuilds at once\n",
                 dome[i], 1e3 * depth, 1e3 * v, az * 180 / PALP_TEST_PI, st.over, 100 * st.worst, st.lost, st.at_once);
          CHECK(st.over == 0, "slide grid (%s dome), %.0f mm, %.0f mm/s, %.0f deg: no tick-to-tick step beyond max(2%% "
                              "of the force, 0.01 N) off the trend (%d ticks)", dome[i], 1e3 * depth, 1e3 * v,
                az * 180 / PALP_TEST_PI, st.over);
          CHECK(st.lost == 0, "slide grid (%s dome): contact kept all the way (%d ticks lost)", dome[i], st.lost);
          at_once_all += st.at_once, slides++;
          palp_world_destroy(w);
        }
  *slides_out = slides;
  return at_once_all;
}

/* A blend's store of the replaced factor's columns grows while a finger slides onto
 * new vertices; growing it may move it (realloc). Pointers into it kept across that
 * growth read freed memory: the long-term dome slid at 100 mm/s, 10 mm deep, as served
 * at 1 kHz, then went differently from run to run of the same inputs (in 5 of 6 runs
 * it lost contact for ~260 ticks and made thousands of rebuilds; valgrind: invalid reads
 * in stage_fingers). The same slide six times in one process must give the same
 * world, bit for bit, every tick in contact, and the finger pressing all the way. That
 * caught the fault in 5 of 8 processes (the heap decides whether the store moves), so
 * the test model_finger_memcheck also runs it once under valgrind, which reports any
 * read of freed memory whatever the heap does.
 * Since 2026-12-07 the slide is 12 mm deep: with today's world the 10 mm slide no longer
 * grows the store while pointers into it are held (the fault put back into stage_fingers,
 * that slide ran clean under valgrind), so neither test could see the fault come back.
 * The 12 mm slide grows it at t = 1.624 s with 11 columns' pointers held, and valgrind
 * reports the invalid reads (measured with the fault put back; clean without it). It is
 * also the slide grid's long-term 12 mm, 100 mm/s, azimuth 0 slide. */
static void test_slide_repeatable(int runs) {
  uint64_t first = 0;
  for (int run = 0; run < runs; ++run) {
    palp_world *w = scene_world(PALP_CONFIG_DIR "/paper_step_long_term.json", 0.001, -1, NULL,
                                palp_world_refactor_lag_for(0.001), palp_world_refactor_blend_for(0.001));
    if (!w) return;
    const slide_stats st = slide(w, 0.012, 0.100, 0.0);
    const uint64_t hsh = palp_world_hash(w);
    if (run == 0) first = hsh;
    printf("slide repeated (long-term dome, as served, 100 mm/s, 12 mm deep), run %d: %d ticks, %d out of contact, "
           "force >= %.3f N, state hash %016llx\n", run + 1, st.ticks, st.lost, st.fmin, (unsigned long long)hsh);
    CHECK(st.lost == 0, "slide repeated, run %d: contact kept all the way (%d ticks lost)", run + 1, st.lost);
    CHECK(st.fmin > 1.0, "slide repeated, run %d: the finger presses all the way (%.3f N)", run + 1, st.fmin);
    CHECK(hsh == first, "slide repeated, run %d: the same world as run 1, bit for bit (%016llx against %016llx)", run + 1,
          (unsigned long long)hsh, (unsigned long long)first);
    palp_world_destroy(w);
  }
}

/* The slide (50 mm/s, 10 mm deep, in the x-z plane), checked: contact all the
 * way, the finger pressing, at most max_over ticks over. */
static void test_slide_in(const char *sn, palp_world *w, int max_over) {
  const slide_stats st = slide(w, 0.010, 0.050, 0.0);
  printf("slide (%s): %d ticks at 50 mm/s, 10 mm deep, force >= %.3f N: tick-to-tick step beyond the linear trend at "
         "most %.2f%% of the force (raw tick-to-tick change at most %.2f%%), at most %.4f N, smallest margin to "
         "max(2%%, 0.01 N) %.4f N; %d ticks over it; %lld rebuilds, %lld of them at once at the margin\n",
         sn, st.ticks, st.fmin, 100 * st.worst, 100 * st.worst_raw, st.worst_n, st.margin, st.over, st.rebuilds,
         st.at_once);
  CHECK(st.lost == 0, "slide (%s): contact kept all the way (%d ticks lost)", sn, st.lost);
  CHECK(st.fmin > 0.1, "slide (%s): the finger presses all the way (%.3f N)", sn, st.fmin);
  CHECK(st.over <= max_over, "slide (%s): at most %d tick-to-tick force steps beyond max(2%% of the force, 0.01 N) "
                             "off the motion's trend (%d ticks)", sn, max_over, st.over);
  palp_world_destroy(w);
}

static void test_local_model_in(const char *what, palp_world *w, double bound);

/* The local model predicts the next 250 Hz step's force: pressed to 20 mm at 5 mm/s
 * with a 2 mm, 0.7 Hz wobble, each step's force against the last model evaluated at
 * this step's device point and time, within 5% wherever the force exceeds 0.1 N. On
 * the library's default phantom (the paper's literal reading) and on the breast-tissue
 * dome of the exercises, where the surface's own velocity as the drift missed by up to
 * 10.4% (a finger touching down: the dent the device's motion makes, which the
 * stiffness already counts) and the drift observer misses by 3.7% (default phantom:
 * 2.9% before, 4.9% now: its gel flows, the surface's velocity is its drift). */
static void test_local_model(void) {
  palp_world *w = make(0.004);
  test_local_model_in("default phantom", w, 0.05);
  w = scene_world(PALP_CONFIG_DIR "/phantoms/dome.json", 0.004, -1, NULL, 0, 0);
  if (w) test_local_model_in("breast-tissue dome", w, 0.05);
  /* As the server steps them (rebuilds deferred 4 frames; at 250 Hz neither the blend nor
   * the margin test, docs/haptics.md, "Rebuilds blended in"). The default phantom (the
   * paper's flowing reading) then misses its next step by up to 21.3% in a 4-step burst at
   * 0.15-0.18 N while a factor past its margin waits for its due frame (5.9% with the
   * margin test, which cost the demo's exercise sessions late ticks): a known shortfall,
   * held at 25% so that it cannot grow unnoticed, not the target. The breast-tissue dome of
   * the exercises keeps 5%. */
  w = make_surface_lag(0.004, palp_world_default_def().finger_surface, palp_world_refactor_lag_for(0.004),
                       palp_world_refactor_blend_for(0.004));
  test_local_model_in("default phantom, as served", w, 0.25);
  w = scene_world(PALP_CONFIG_DIR "/phantoms/dome.json", 0.004, -1, NULL, palp_world_refactor_lag_for(0.004),
                  palp_world_refactor_blend_for(0.004));
  if (w) test_local_model_in("breast-tissue dome, as served", w, 0.05);
}

static void test_local_model_in(const char *what, palp_world *w, double bound) {
  palp_vec3 start = {0.0, 0.0, R + r + 0.001};
  const int f = palp_world_add_finger(w, start, r);
  palp_local_model prev;
  palp_world_finger_local_model(w, f, &prev);
  double worst = 0.0;
  int compared = 0;
  for (int k = 0; k < 1000; ++k) {
    const double t = k * 0.004;
    const double depth = fmin(0.02, 0.005 * t) + 0.002 * sin(2 * PALP_TEST_PI * 0.7 * t); /* press + wobble */
    const palp_vec3 x = {0, 0, R + r + 0.001 - depth};
    palp_world_set_finger_device(w, f, x);
    palp_world_step(w);
    palp_local_model lm;
    palp_world_finger_local_model(w, f, &lm);
    if (prev.contact && lm.contact && len(lm.force) > 0.1) {
      const palp_vec3 pred = palp_local_model_force(&prev, x, lm.time - prev.time);
      const double e = len(add(pred, sc(lm.force, -1))) / len(lm.force);
      if (e > worst) worst = e;
      compared++;
    }
    /* K is symmetric, positive semi-definite and bounded by the coupling */
    for (int i = 0; i < 3; ++i) {
      CHECK(lm.stiffness[i][i] >= -1e-9 && lm.stiffness[i][i] <= 2000.0 * 1.001, "K_%d%d = %g in [0, k_c]", i, i,
            lm.stiffness[i][i]);
      for (int j = 0; j < 3; ++j) CHECK(fabs(lm.stiffness[i][j] - lm.stiffness[j][i]) < 1e-6, "K symmetric");
    }
    prev = lm;
  }
  printf("local model at 250 Hz, %s: next-step force predicted within %.2f%% (worst of %d steps)\n", what,
         100 * worst, compared);
  CHECK(compared > 500, "%s: compared %d steps in contact", what, compared);
  CHECK(worst < bound, "%s: next-step force predicted within %.0f%% (worst %.2f%%)", what, 100 * bound, 100 * worst);
  palp_world_destroy(w);
}

/* The renderer: continuous at a model's arrival, limited and flagged above
 * max_force, faded out when the models stop. */
static void test_renderer(void) {
  palp_haptic h;
  palp_haptic_def def = palp_haptic_default_def();
  def.max_force = 2.0;
  def.damping = 0.0; /* the spring part first; the damper below */
  CHECK(palp_haptic_init(&h, &def) == 0, "init");
  palp_local_model m = {.time = 1.0, .period = 0.004, .contact = 1, .device = {0, 0, 0.03},
                        .normal = {0, 0, 1}, .force = {0, 0, 1.0}};
  m.stiffness[2][2] = 500.0;
  palp_haptic_out o;
  {
    /* A loop already rendering when its first model comes (the device pressed in before the
     * server answered: 0.8 s in the demo) gets the force over fade_time, not in one tick. */
    palp_haptic h0;
    CHECK(palp_haptic_init(&h0, &def) == 0, "init");
    palp_haptic_render(&h0, m.device, -0.010, &o);
    CHECK(o.flags & PALP_HAPTIC_NO_MODEL, "no model: flagged");
    CHECK(len(o.force) == 0.0, "no model: no force");
    /* The server's models come every period (4 ms) through the onset, as on a station: each
     * one leaves the onset running (session 82: the second finished it within 4 ticks). */
    double prev = 0.0, worst = 0.0, at_half = 0.0;
    int taken = 0;
    for (int k = 0; k <= 150; ++k) {
      if (k % 4 == 0) {
        palp_local_model mk = m;
        mk.time = 1.0 + 0.001 * k;
        taken += palp_haptic_update(&h0, &mk, 0.001 * k) == 1;
      }
      palp_haptic_render(&h0, m.device, 0.001 * k, &o);
      worst = fmax(worst, fabs(o.force.z - prev));
      prev = o.force.z;
      if (k == 50) at_half = o.force.z;
    }
    /* linear over fade_time (0.1 s): 1 N in 100 ticks, 0.01 N a tick */
    CHECK(taken == 38, "onset: %d of the 38 models taken", taken);
    CHECK(worst <= 0.0101, "onset, a model every 4 ms: largest tick-to-tick step %.4f N (bound 0.0101 N: 1 N over "
          "100 ticks)", worst);
    CHECK(fabs(at_half - 0.5) < 1e-9, "onset: half the force half way (%.4f N)", at_half);
    CHECK(fabs(prev - 1.0) < 1e-12, "onset: the model's force once faded in (%.6f N)", prev);
  }
  palp_haptic_update(&h, &m, 0.0);
  palp_haptic_render(&h, m.device, 0.0, &o);
  CHECK(fabs(o.force.z - 1.0) < 1e-12, "at the model's device point: its force (%.6f N)", o.force.z);
  palp_haptic_render(&h, (palp_vec3){0, 0, 0.029}, 0.001, &o);
  CHECK(fabs(o.force.z - 1.5) < 0.02 + 2.0 * 0.001, "1 mm deeper: + K dx = 1.5 N, damper aside (%.4f N)", o.force.z);
  /* A new model that disagrees by 0.3 N arrives: no step at its arrival. */
  palp_local_model m2 = m;
  m2.time = 1.004;
  m2.device = (palp_vec3){0, 0, 0.029};
  m2.force = (palp_vec3){0, 0, 1.8};
  const double before = o.force.z;
  palp_haptic_update(&h, &m2, 0.001);
  palp_haptic_render(&h, (palp_vec3){0, 0, 0.029}, 0.001, &o);
  CHECK(fabs(o.force.z - before) < 0.01, "continuous at the arrival: %.4f N then %.4f N", before, o.force.z);
  palp_haptic_render(&h, (palp_vec3){0, 0, 0.029}, 0.006, &o);
  CHECK(fabs(o.force.z - 1.8) < 1e-9, "the new model's force one period later (%.4f N)", o.force.z);
  /* The damper: moving in at 0.1 m/s adds b v = 0.2 N along the normal. */
  palp_haptic hd;
  palp_haptic_def dd = palp_haptic_default_def();
  palp_haptic_init(&hd, &dd);
  palp_haptic_update(&hd, &m, 0.0);
  palp_haptic_out od;
  palp_haptic_render(&hd, m.device, 0.0, &od);
  palp_haptic_render(&hd, (palp_vec3){0, 0, 0.0299}, 0.001, &od);
  CHECK(fabs(od.force.z - (1.0 + 500 * 1e-4 + 2.0 * 0.1)) < 1e-9, "damper: 1.25 N expected (%.6f N)", od.force.z);
  /* Deep: limited and flagged. */
  palp_haptic_render(&h, (palp_vec3){0, 0, 0.026}, 0.007, &o);
  CHECK((o.flags & PALP_HAPTIC_LIMITED) && fabs(len(o.force) - 2.0) < 1e-9 && o.requested > 2.0,
        "limited to 2 N and flagged (requested %.3f N)", o.requested);
  /* Silent server: faded out. */
  palp_haptic_render(&h, (palp_vec3){0, 0, 0.029}, 0.4, &o);
  CHECK((o.flags & PALP_HAPTIC_STALE) && len(o.force) == 0.0, "stale models fade to 0 N (%.4f N)", len(o.force));
  /* Older models are ignored; non-finite ones refused. */
  palp_local_model old = m;
  CHECK(palp_haptic_update(&h, &old, 0.41) == 0, "an older model is ignored");
  palp_local_model bad = m2;
  bad.time = 2.0;
  bad.force.x = NAN;
  CHECK(palp_haptic_update(&h, &bad, 0.41) < 0, "a non-finite model is refused");
  /* The server comes back: its model's 1.3 N blends in from the faded-out 0 N over fade_time. */
  palp_local_model m3 = m2;
  m3.time = 1.5;
  m3.force = (palp_vec3){0, 0, 1.3};
  palp_haptic_render(&h, (palp_vec3){0, 0, 0.029}, 0.409, &o);
  const double faded = o.force.z;
  CHECK(palp_haptic_update(&h, &m3, 0.41) == 1, "a newer model after the silence is taken");
  double prev = faded, worst = 0.0;
  int resumed = 1;
  for (int k = 0; k <= 120; ++k) {
    if (k > 0 && k % 4 == 0) { /* the resumed server's stream, every 4 ms */
      palp_local_model mk = m3;
      mk.time = 1.5 + 0.001 * k;
      resumed += palp_haptic_update(&h, &mk, 0.41 + 0.001 * k) == 1;
    }
    palp_haptic_render(&h, (palp_vec3){0, 0, 0.029}, 0.41 + 0.001 * k, &o);
    worst = fmax(worst, fabs(o.force.z - prev));
    prev = o.force.z;
  }
  CHECK(resumed == 31 && faded == 0.0 && worst <= 0.0131, "resumed, a model every 4 ms (%d of 31 taken): from %.4f N, "
        "largest tick step %.4f N (bound 0.0131: 1.3 N over 100 ticks)", resumed, faded, worst);
  CHECK(fabs(prev - 1.3) < 1e-9, "resumed: the new model's force after fade_time (%.4f N)", prev);
}

/* The stiff default dome (config/paper_step_long_term.json, ~2.3 N/mm under the tip):
 * pressed slowly by position (1 mm/s of device travel, 1 kHz) to 6 mm at polar 30, 45 and
 * 60 deg, no tick-to-tick force step beyond the motion's linear trend larger than
 * max(2% of the force, 0.01 N). With a pad spring per feature, a vertex's neighbours
 * joined the contact at 45 deg already ~1 mm into the pad and the force stepped by
 * 0.82 N (15%) in one tick, 1.27 N (24%) in three (docs/haptics.md). Both contact
 * surfaces, whatever the scene says. */
static void test_stiff_press(int surface) {
  const char *sn = palp_finger_surface_name(surface);
  const double polar[3] = {30, 45, 60};
  for (int ia = 0; ia < 3; ++ia) {
    palp_world *w = scene_world(PALP_CONFIG_DIR "/paper_step_long_term.json", 0.001, surface, NULL, 0, 0);
    if (!w) return;
    const double a = polar[ia] * PALP_TEST_PI / 180.0;
    const palp_vec3 n = {sin(a), 0, cos(a)};
    const int f = palp_world_add_finger(w, sc(n, R + r + 0.001), r);
    double worst = 0.0, fmax_ = 0.0, F1 = 0.0, F2 = 0.0;
    int over = 0, k = 0;
    for (double dd = -0.001; dd <= 0.006; dd += 1e-6, ++k) {
      palp_world_set_finger_device(w, f, sc(n, R + r - dd));
      palp_world_step(w);
      palp_local_model lm;
      palp_world_finger_local_model(w, f, &lm);
      const double F = dot(lm.force, n);
      if (k >= 2 && F > 0.0) {
        const double step = fabs(F - 2.0 * F1 + F2);
        if (step > fmax(0.02 * F, 0.01)) over++;
        if (step > worst) worst = step;
      }
      if (F > fmax_) fmax_ = F;
      F2 = F1, F1 = F;
    }
    printf("stiff dome (%s), %g deg: pressed to 6 mm at 1 mm/s, force up to %.2f N, largest tick step off the trend "
           "%.4f N\n", sn, polar[ia], fmax_, worst);
    CHECK(fmax_ > 5.0, "%s, %g deg: the press reaches 5 N (%.2f N)", sn, polar[ia], fmax_);
    CHECK(over == 0, "%s, %g deg: no tick step off the trend beyond max(2%%, 0.01 N) (%d ticks; largest %.4f N)", sn,
          polar[ia], over, worst);
    palp_world_destroy(w);
  }
}

/* palp_sym3_pinv_apply against a pseudo-inverse built by hand: K = Q diag(4, 1, 0) Q^T
 * with Q a rotation by 30 deg about z then 50 deg about x, so K^+ r = Q diag(1/4, 1, 0)
 * Q^T r; within 1e-12 m/N per N. */
static void test_pinv(void) {
  const double a = 30.0 * PALP_TEST_PI / 180.0, b = 50.0 * PALP_TEST_PI / 180.0;
  const double Rz[3][3] = {{cos(a), -sin(a), 0}, {sin(a), cos(a), 0}, {0, 0, 1}};
  const double Rx[3][3] = {{1, 0, 0}, {0, cos(b), -sin(b)}, {0, sin(b), cos(b)}};
  double Q[3][3] = {{0}}, K[3][3] = {{0}}, P[3][3] = {{0}};
  const double ev[3] = {4.0, 1.0, 0.0}, iv[3] = {0.25, 1.0, 0.0};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) Q[i][j] += Rx[i][k] * Rz[k][j];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) K[i][j] += Q[i][k] * ev[k] * Q[j][k], P[i][j] += Q[i][k] * iv[k] * Q[j][k];
  const palp_vec3 r = {0.3, -1.2, 0.7};
  const palp_vec3 got = palp_sym3_pinv_apply((const double(*)[3])K, r, 1e-6);
  const double want[3] = {P[0][0] * r.x + P[0][1] * r.y + P[0][2] * r.z, P[1][0] * r.x + P[1][1] * r.y + P[1][2] * r.z,
                          P[2][0] * r.x + P[2][1] * r.y + P[2][2] * r.z};
  const double err = fmax(fmax(fabs(got.x - want[0]), fabs(got.y - want[1])), fabs(got.z - want[2]));
  printf("pseudo-inverse of a rank-2 3x3 stiffness: largest error %.2e\n", err);
  CHECK(err < 1e-12, "K^+ r within 1e-12 (%.2e)", err);
  const double Z[3][3] = {{0}};
  const palp_vec3 z = palp_sym3_pinv_apply(Z, r, 1e-6);
  CHECK(z.x == 0.0 && z.y == 0.0 && z.z == 0.0, "a zero stiffness turns nothing into force: K^+ r = 0");
}

/* The drift a served model carries stays a surface's speed: the exercise dome (the
 * breast-tissue scene) at 250 Hz with the server's lag, jobs factored as a helper does,
 * a fingertip searching in a vertical strip as the exercises' expert does (spots 8 mm
 * apart along a meridian, each felt at 3 / 9 / 16 mm with circles of 2.5 mm at 2 Hz;
 * bench_server's strip_device), 8 s. Before the observer was capped, the 16 mm
 * circles drove the drift to 106 m/s at 6.4 s along a direction the model's K barely
 * resists, and the station refused those models as corrupt (|d| > 100 m/s). Bound:
 * def.max_speed (20 m/s) at every step, and K and F finite. */
static double ease01(double x) { return x <= 0 ? 0 : x >= 1 ? 1 : 0.5 - 0.5 * cos(PALP_TEST_PI * x); }

static palp_vec3 strip_point(double t) {
  const double spot = 1.5, half = 50.0 * PALP_TEST_PI / 180.0 * R;
  const double k = floor(t / spot), x = t - k * spot;
  const double depth = 0.003 + 0.006 * ease01((x - 0.3) / 0.15) + 0.007 * ease01((x - 0.65) / 0.15) -
                       0.013 * ease01((x - 1.0) / 0.2);
  const double span = 2 * half, pos = fmod((k + ease01((x - 1.2) / 0.3)) * 0.008, 2 * span);
  const double th = ((pos < span ? pos : 2 * span - pos) - half) / R;
  const palp_vec3 n = {sin(th), 0, cos(th)}, eu = {cos(th), 0, -sin(th)}, ev = {0, 1, 0};
  const double w = 2 * PALP_TEST_PI * 2.0 * t, rho = 0.0025, hgt = R + r - depth;
  return add(sc(n, hgt), add(sc(eu, rho * cos(w)), sc(ev, rho * sin(w))));
}

static void test_drift_bounded(void) {
  const char *path = PALP_CONFIG_DIR "/phantoms/dome.json";
  palp_scene sc_;
  char err[256];
  if (palp_scene_load(path, &sc_, err, sizeof err)) {
    CHECK(0, "%s: %s", path, err);
    return;
  }
  double dt = sc_.world.dt; /* the scene's step, which the server's lag depends on */
  palp_world *w = scene_world(path, 0.0, -1, &dt, palp_world_refactor_lag_for(dt), 0);
  if (!w) return;
  const double vmax = palp_world_get_def(w)->max_speed;
  const int f = palp_world_add_finger(w, strip_point(0.0), r);
  const int steps = (int)lround(8.0 / dt);
  double worst = 0.0, worst_t = 0.0;
  int bad = 0, jobs = 0;
  for (int k = 0; k < steps; ++k) {
    palp_world_set_finger_device(w, f, strip_point(k * dt));
    CHECK(palp_world_step(w) == 0, "strip search: step %d", k);
    palp_factor_job *j = palp_world_factor_claim(w);
    if (j) {
      jobs++;
      CHECK(palp_factor_job_run(j) == 0 && palp_world_factor_done(w, j) == 0, "strip search: job at step %d", k);
    }
    palp_local_model m;
    if (palp_world_finger_local_model(w, f, &m) < 0 || !m.contact) continue;
    const double d = len(m.drift);
    if (d > worst) worst = d, worst_t = k * dt;
    int finite = isfinite(d) && isfinite(len(m.force));
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) finite &= isfinite(m.stiffness[a][b]);
    bad += !finite;
  }
  printf("strip search on the exercise dome, 8 s at %.0f Hz, %d rebuilds as a helper makes them: largest drift %.3f m/s "
         "at %.2f s (bound: max_speed %.0f m/s), %d models not finite\n", 1.0 / dt, jobs, worst, worst_t, vmax, bad);
  CHECK(worst <= vmax * (1.0 + 1e-12), "the served drift stays within max_speed (%.3f m/s, bound %.0f m/s)", worst, vmax);
  CHECK(bad == 0, "every served model finite (%d not)", bad);
  palp_world_destroy(w);
}

int main(int argc, char **argv) {
  /* test_model_finger SCENE: only the deep presses, on another breast-tissue scene
   * (e.g. a parameter set under trial). */
  if (argc > 1 && !strcmp(argv[1], "--slide-repeatable")) { /* model_finger_memcheck: once, under valgrind */
    test_slide_repeatable(1);
    CHECK_DONE();
  }
  /* test_model_finger --served SCENE NAME [--grid]: another shipped dome (the long-term dome's
   * 1,300-vertex net, model_finger_fine) held to the slide as served at 1 kHz and the deep
   * presses; with --grid also the slide grid's eight slides (~20 s more at 1,300 vertices; by hand:
   * measured 2026-12-02, 0 ticks over in all eight, worst 0.70% of the force). */
  if (argc > 3 && !strcmp(argv[1], "--served")) {
    const char *sc1[1] = {argv[2]}, *nm1[1] = {argv[3]};
    palp_world *w = scene_world(argv[2], 0.001, -1, NULL, palp_world_refactor_lag_for(0.001),
                                palp_world_refactor_blend_for(0.001));
    if (w) test_slide_in(argv[3], w, 0);
    if (argc > 4 && !strcmp(argv[4], "--grid")) {
      int slides = 0;
      slide_grid_on(1, sc1, nm1, &slides);
      CHECK(slides == 8, "slide grid on %s: %d of 8 slides", argv[3], slides);
    }
    test_deep_press(argv[2], argv[3]);
    CHECK_DONE();
  }
  if (argc > 1) {
    test_deep_press(argv[1], argv[1]);
    CHECK_DONE();
  }
  test_pinv();
  test_renderer();
  test_presses();
  test_slide(PALP_FINGER_SURFACE_SMOOTH);
  test_slide(PALP_FINGER_SURFACE_FACETS);
  test_slide_shipped();
  test_slide_grid();
  test_slide_repeatable(6);
  test_stiff_press(PALP_FINGER_SURFACE_SMOOTH);
  test_stiff_press(PALP_FINGER_SURFACE_FACETS);
  test_local_model();
  test_drift_bounded();
  test_deep_press(PALP_CONFIG_DIR "/phantoms/dome.json", "breast tissue");
  test_deep_press(PALP_CONFIG_DIR "/paper_step_long_term.json", "long-term dome");
  CHECK_DONE();
}
