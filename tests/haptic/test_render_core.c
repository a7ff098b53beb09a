/*
 * test_render_core.c - the station's renderer (src/haptic.c) and per-tick core
 * (client/haptic_loop.c) against the inputs session 75's review found them wrong on
 * (docs/haptics.md, "Session 75 review fixes"). Pure and in process: station times are
 * given (1 kHz ticks, exact), no DDS; the one loop run (the safe force) only counts
 * what its callbacks saw, never how fast.
 *
 * Expected values are worked by hand from each test's own model:
 *   F(x) = force - K (x - device), along the normal z, unilateral; limit L;
 *   stale fade: scale 1 - (age - stale_time) / fade_time, 0.25 s and 0.1 s (100 ticks).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "finger.h"
#include "haptic_loop.h"
#include "palp_haptic.h"

#define TICK 1e-3 /* [s] */

static double len(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

/* A model in contact along +z at device point (0, 0, z0) with force fz [N] and K_zz = k [N/m]. */
static palp_local_model contact_model(double time, double z0, double fz, double k) {
  palp_local_model m;
  memset(&m, 0, sizeof m);
  m.time = time, m.period = 0.004, m.contact = 1, m.triangles = 1;
  m.device = (palp_vec3){0, 0, z0}, m.proxy = (palp_vec3){0, 0, z0 + 0.001};
  m.normal = (palp_vec3){0, 0, 1}, m.force = (palp_vec3){0, 0, fz};
  m.stiffness[2][2] = k;
  return m;
}

/* 1. A model far above the limit, then silence: the rendered force goes from L to 0 over
 * fade_time in steps of at most L / 100 ticks (slack 1%); so does its onset under a pressed
 * device, and its return after the silence. Before the fix (limit after the fade) the fade
 * held L until the scale fell below L/R and then dropped R/100 a tick: 0.4 N at R = 40 N,
 * 10 N in one tick at R = 1e4 N. The models come as the server sends them, one every period
 * (4 ms) from t = 0 to 148 ms, then none (session 82: with one model only, the onset's
 * fade_time was never tested against the next model; each one restarted the ramp and the
 * onset took 4 ticks, 2.4 N a tick at L = 10 N). Expected, by hand: the onset gain t / 0.1 s,
 * L/2 at 50 ms, L from 100 ms; the last model (148 ms) stale from 398 ms, faded to 0 at
 * 498 ms, L/2 at 448 ms. */
static void test_fade_above_limit(double R) {
  palp_haptic_def def = palp_haptic_default_def(); /* L = 10 N, stale 0.25 s, fade 0.1 s */
  def.damping = 0;
  palp_haptic h;
  palp_haptic_init(&h, &def);
  const double L = def.max_force, bound = L / 100.0 * 1.01;
  const palp_vec3 x = {0, 0, 0.03};
  palp_haptic_out o;
  palp_haptic_render(&h, x, -TICK, &o); /* pressed before the first model: the hand feels 0 N */
  double prev = 0, worst_on = 0, worst_off = 0, at_half_on = -1, at_half_off = -1, at_full = -1, after = -1;
  int taken = 0;
  for (int k = 0; k <= 600; ++k) {
    const double t = k * TICK;
    if (k % 4 == 0 && k <= 148) {
      palp_local_model m = contact_model(1.0 + t, 0.03, R, 500);
      taken += palp_haptic_update(&h, &m, t) == 1;
    }
    palp_haptic_render(&h, x, t, &o);
    const double f = len(o.force);
    if (k <= 250) worst_on = fmax(worst_on, fabs(f - prev));
    else worst_off = fmax(worst_off, fabs(f - prev));
    if (k == 50) at_half_on = f;
    if (k == 200) at_full = f;
    if (k == 448) at_half_off = f; /* 50 ms into the 100 ms fade */
    if (k == 510) after = f;
    prev = f;
  }
  CHECK(taken == 38, "R = %g N: %d of the 38 models (every 4 ms to 148 ms) taken", R, taken);
  CHECK(worst_on <= bound && fabs(at_half_on - 0.5 * L) < 1e-9,
        "R = %g N, onset under a pressed device, a model every period: largest tick step %.4f N <= %.4f N (L / 100 "
        "ticks, +1%%), %.6f N half way (5 N)", R, worst_on, bound, at_half_on);
  CHECK(fabs(at_full - L) < 1e-9, "R = %g N: limited to %.6f N once in (10 N)", R, at_full);
  CHECK(worst_off <= bound && fabs(at_half_off - 0.5 * L) < 1e-9 && after == 0.0,
        "R = %g N, silent server: largest tick step %.4f N <= %.4f N, %.6f N half way through the fade (5 N), "
        "%.6f N after it (0)", R, worst_off, bound, at_half_off, after);
  /* The server comes back under the pressed device, a model every period again: the same ramp up. */
  prev = 0;
  double worst_back = 0, half_back = -1;
  int back = 0;
  for (int k = 0; k <= 150; ++k) {
    const double t = 0.601 + k * TICK;
    if (k % 4 == 0) {
      palp_local_model m2 = contact_model(1.4 + k * TICK, 0.03, R, 500);
      back += palp_haptic_update(&h, &m2, t) == 1;
    }
    palp_haptic_render(&h, x, t, &o);
    worst_back = fmax(worst_back, fabs(len(o.force) - prev));
    if (k == 50) half_back = len(o.force);
    prev = len(o.force);
  }
  CHECK(back == 38, "R = %g N: %d of the returning server's 38 models taken", R, back);
  CHECK(worst_back <= bound && fabs(half_back - 0.5 * L) < 1e-9 && fabs(prev - L) < 1e-9,
        "R = %g N, restart, a model every period: largest tick step %.4f N <= %.4f N, %.6f N half way (5 N), %.6f N "
        "at the end (10 N)", R, worst_back, bound, half_back, prev);
}

/* 1. A crossfade from a model asking 40 N to one asking 5 N (limit 10 N) over its 4 ms
 * period: from the 10 N rendered to 5 N in 4 ticks of 1.25 N. Before, from the unlimited
 * 40 N: 10 N held for three ticks, then 5 N in one. */
static void test_crossfade_above_limit(void) {
  palp_haptic_def def = palp_haptic_default_def();
  def.damping = 0;
  palp_haptic h;
  palp_haptic_init(&h, &def);
  const palp_vec3 x = {0, 0, 0.03};
  palp_local_model a = contact_model(1.0, 0.03, 40, 500), b = contact_model(1.004, 0.03, 5, 500);
  palp_haptic_out o;
  palp_haptic_update(&h, &a, 0.0);
  palp_haptic_render(&h, x, 0.0, &o);
  double prev = len(o.force), worst = 0;
  palp_haptic_update(&h, &b, 0.004);
  for (int k = 0; k <= 8; ++k) {
    palp_haptic_render(&h, x, 0.004 + k * TICK, &o);
    worst = fmax(worst, fabs(len(o.force) - prev));
    prev = len(o.force);
  }
  CHECK(worst <= 1.25 * 1.01 && fabs(prev - 5.0) < 1e-9,
        "crossfade 40 N -> 5 N asked, 10 N limit: largest tick step %.4f N <= 1.2625 N ((10 - 5) / 4 ticks, +1%%), "
        "%.6f N after (5 N)", worst, prev);
}

/* 8. A finite K that overflowed: K_zz = -1e308 N/m read 10 m off gave F = +inf; scaled by
 * L / inf it rendered NaN, then 0 N (session 75). Since session 82 the renderer projects K to
 * positive semi-definite within max_stiffness, so that K is 0 N/m: the model's own 1 N, flagged
 * limited (palp_haptic_limit_stiffness). The clamp's non-finite path is checked on its own. */
static void test_nonfinite(void) {
  unsigned fl = 0;
  palp_vec3 f = palp_haptic_clamp((palp_vec3){NAN, 0, 1}, 10, &fl);
  CHECK(f.x == 0 && f.y == 0 && f.z == 0 && (fl & PALP_HAPTIC_LIMITED), "clamp: NaN gives 0 N, flagged");
  fl = 0;
  f = palp_haptic_clamp((palp_vec3){0, INFINITY, 0}, 10, &fl);
  CHECK(len(f) == 0 && (fl & PALP_HAPTIC_LIMITED), "clamp: an infinite force gives 0 N, flagged");
  fl = 0;
  f = palp_haptic_clamp((palp_vec3){30, 40, 0}, 10, &fl);
  CHECK(fabs(f.x - 6) < 1e-12 && fabs(f.y - 8) < 1e-12 && (fl & PALP_HAPTIC_LIMITED), "clamp: (30, 40, 0) N to (6, 8, 0)");
  fl = 0;
  f = palp_haptic_clamp((palp_vec3){3, 4, 0}, 10, &fl);
  CHECK(f.x == 3 && f.y == 4 && !fl, "clamp: 5 N under 10 N unchanged, not flagged");
  palp_haptic_def def = palp_haptic_default_def();
  palp_haptic h;
  palp_haptic_init(&h, &def);
  palp_local_model m = contact_model(1.0, 0.0, 1.0, -1e308);
  CHECK(palp_haptic_update(&h, &m, 0.0) == 1, "an overflowing (finite) K is a model the renderer takes");
  palp_haptic_out o;
  palp_haptic_render(&h, (palp_vec3){0, 0, 10}, 0.001, &o);
  CHECK(isfinite(o.force.x) && isfinite(o.force.y) && isfinite(o.force.z) && fabs(o.force.z - 1.0) < 1e-12 &&
            (o.flags & PALP_HAPTIC_LIMITED),
        "K_zz = -1e308 N/m, 10 m off: rendered %g N (its K projected to 0: the model's 1 N, limited), requested %g",
        len(o.force), o.requested);
}

/* 5. One model stamped 1e300 s must not stop the models after it. */
static void test_time_jump(void) {
  palp_haptic_def def = palp_haptic_default_def();
  palp_haptic h;
  palp_haptic_init(&h, &def);
  palp_local_model m = contact_model(1.0, 0.03, 1.0, 500);
  palp_haptic_update(&h, &m, 0.0);
  palp_local_model far = contact_model(1e300, 0.03, 1.0, 500);
  CHECK(palp_haptic_update(&h, &far, 0.002) == 0, "a model 1e300 s ahead is ignored");
  palp_local_model ahead = contact_model(1.0 + 0.004 + 0.25 + 0.01, 0.03, 1.0, 500);
  CHECK(palp_haptic_update(&h, &ahead, 0.004) == 0, "nor one 0.26 s ahead after 4 ms (bound: 4 ms + stale_time)");
  int taken = 0, stale = 0;
  palp_haptic_out o;
  for (int k = 1; k <= 250; ++k) { /* 1 s of models at 250 Hz */
    palp_local_model n = contact_model(1.0 + 0.004 * k, 0.03, 1.0, 500);
    taken += palp_haptic_update(&h, &n, 0.004 * k) == 1;
    palp_haptic_render(&h, (palp_vec3){0, 0, 0.03}, 0.004 * k, &o);
    stale += (o.flags & PALP_HAPTIC_STALE) != 0;
  }
  CHECK(taken == 250 && stale == 0 && fabs(len(o.force) - 1.0) < 1e-9,
        "the models after it: %d of 250 taken, %d stale ticks, %.6f N at the end (1 N)", taken, stale, len(o.force));
  /* After a silence (the current model stale) a newer model is taken however far ahead. */
  palp_local_model later = contact_model(2.0 + 10.0, 0.03, 1.0, 500);
  CHECK(palp_haptic_update(&h, &later, 1.0 + 0.26) == 1, "after 0.26 s of silence a model 10 s ahead is taken");
}

/* A core as the station runs it, the pieces under test isolated: renderer damping off,
 * passivity controller as given. */
static void core_make(palp_cli_haptic_core *c, int passivity) {
  palp_haptic_def def = palp_haptic_default_def();
  def.damping = 0;
  palp_cli_haptic_core_init(c, &def, 250, 1, 0, 0.2); /* hold_after 8 ms, max_latency 0.2 s */
  c->passivity = passivity;
}

/* 2. The hand moves 5 mm out while the force is held (offset 4.75 mm); then a model comes
 * whose age is unknown (-1), beyond max_latency (0.5 s) or negative (-0.3 s), at the
 * server's device point x (its own frame), asking 2 N on 600 N/m. Expected: 2 N, the
 * model's own answer at its point, once blended (4 ms). Before, it was read at x - offset:
 * 2 + 600 x 0.00475 = 4.85 N. */
static void test_unanchored(double age2) {
  palp_cli_haptic_core c;
  core_make(&c, 0);
  palp_haptic_out o;
  palp_local_model m = contact_model(0.0, 0.0, 1.0, 600);
  double held_worst = 0;
  for (int k = 0; k <= 40; ++k) {
    const double t = k * TICK;
    const double z = k <= 10 ? 0.0 : (k >= 30 ? 0.005 : 0.005 * (k - 10) / 20.0); /* 0.25 m/s out */
    palp_local_model mk = m, m2 = contact_model(0.030, z, 2.0, 600);
    palp_local_model *mp = k == 0 ? &mk : (k == 30 ? &m2 : NULL);
    palp_cli_haptic_core_tick(&c, 1, (palp_vec3){0, 0, z}, t, mp, k == 0 ? 0.001 : age2, &o, NULL);
    if (k >= 10 && k < 30) held_worst = fmax(held_worst, fabs(o.force.z - 1.0));
  }
  CHECK(held_worst < 1e-9, "age %g: the force held at 1 N while the hand moved out (worst off %.2e N)", age2,
        held_worst);
  CHECK(fabs(o.force.z - 2.0) < 1e-6, "age %g s: a model at the server's device point renders its 2 N there "
                                      "(%.6f N; taken as is it was 4.85 N)", age2, o.force.z);
}

/* 5. Models the renderer refuses (older: repeats of the current one) must not restart the
 * horizon: the force stays held at 1 N while the hand goes 0.8 mm in at 20 mm/s. Before,
 * each refused copy released the hold for 7 ms and the force followed K: up to
 * 1 + 600 x 0.0008 = 1.48 N. */
static void test_refused_keep_hold(void) {
  palp_cli_haptic_core c;
  core_make(&c, 0);
  palp_haptic_out o;
  const palp_local_model m = contact_model(0.0, 0.0, 1.0, 600);
  double worst = 0;
  int refused = 0;
  for (int k = 0; k <= 50; ++k) {
    const double z = k <= 10 ? 0.0 : -0.02 * (k - 10) * TICK;
    palp_local_model mk = m;
    const int r = palp_cli_haptic_core_tick(&c, 1, (palp_vec3){0, 0, z}, k * TICK, k % 4 == 0 ? &mk : NULL, 0.001, &o,
                                            NULL);
    if (k > 0 && k % 4 == 0) refused += r == 0;
    if (k >= 10) worst = fmax(worst, fabs(o.force.z - 1.0));
  }
  CHECK(refused == 12 && worst < 1e-9, "%d repeated models refused; the force held at 1 N while the hand went in "
                                       "(worst off %.2e N)", refused, worst);
}

/* 4. The server falls silent while the finger moves in and out by 2 mm at 50 mm/s, with
 * the passivity observer holding energy (1 mJ, set every tick as late models leave it).
 * After the fade (0.35 s) the force is exactly 0 on every tick and nothing is "in contact";
 * before, the contact flag came from the unfaded force, the observer never reset, and its
 * damper pushed. */
static void test_silence_damper(void) {
  palp_cli_haptic_core c;
  core_make(&c, 1);
  palp_haptic_out o;
  palp_local_model m = contact_model(0.0, 0.0, 1.0, 500);
  double worst = 0;
  int contact = 0, ticks = 0;
  for (int k = 0; k <= 1000; ++k) {
    const double t = k * TICK;
    const double z = -0.002 * fabs(sin(2 * 3.14159265358979 * 6.25 * t)); /* ~50 mm/s peak, 2 mm deep */
    palp_local_model mk = m;
    if (k > 100) c.energy = 1e-3;
    palp_cli_haptic_core_tick(&c, 1, (palp_vec3){0, 0, z}, t, k == 0 ? &mk : NULL, 0.001, &o, NULL);
    if (t > 0.3505) {
      worst = fmax(worst, len(o.force));
      contact += (o.flags & PALP_HAPTIC_CONTACT) != 0;
      ticks++;
    }
  }
  CHECK(worst == 0.0 && contact == 0, "after the fade: largest force %.3e N over %d moving ticks (0 exactly), %d ticks "
                                      "in contact (0)", worst, ticks, contact);
}

/* 7. The device reads NaN once mid-press (held force, so the motion goes to the offset):
 * the force goes on from the last good reading; before, it was 0 until the finger lifted. */
static void test_nan_reading(void) {
  palp_cli_haptic_core c;
  core_make(&c, 1);
  palp_haptic_out o;
  palp_local_model m = contact_model(0.0, 0.0, 1.0, 500);
  double least = INFINITY;
  int finite = 1;
  for (int k = 0; k <= 100; ++k) {
    const double z = -0.01 * k * TICK; /* in at 10 mm/s */
    palp_local_model mk = m;
    palp_vec3 x = {0, 0, z};
    if (k == 20) x.z = NAN;
    palp_cli_haptic_core_tick(&c, 1, x, k * TICK, k == 0 ? &mk : NULL, 0.001, &o, NULL);
    finite &= isfinite(o.force.x) && isfinite(o.force.y) && isfinite(o.force.z);
    if (k >= 20) least = fmin(least, o.force.z);
  }
  CHECK(finite && least >= 1.0 - 1e-9 && isfinite(c.energy) && isfinite(c.offset.z) && c.bad_x_ticks == 1,
        "one NaN reading at 20 ms: the force stays >= 1 N after it (least %.6f N), energy %g J and offset %g m finite",
        least, c.energy, c.offset.z);
  palp_cli_haptic_core c2;
  core_make(&c2, 1);
  palp_local_model mk = m;
  palp_cli_haptic_core_tick(&c2, 1, (palp_vec3){NAN, 0, 0}, 0.0, &mk, 0.001, &o, NULL);
  CHECK(len(o.force) == 0.0, "a NaN first reading: no force (%g N)", len(o.force));
}

/* 6. Hostile samples at the wire check. */
static palp_LocalModel wire_ok(void) {
  palp_LocalModel w;
  memset(&w, 0, sizeof w);
  w.time = 1.0, w.period = 0.004, w.in_contact = 1, w.triangles = 1;
  w.normal = (palp_Vec3){0, 0, 1}, w.force = (palp_Vec3){0, 0, 1};
  w.stiffness[0] = w.stiffness[4] = 100, w.stiffness[8] = 600, w.stiffness[1] = w.stiffness[3] = 20;
  w.max_force = 20;
  return w;
}

static void test_from_wire(void) {
  palp_local_model m;
  palp_LocalModel w = wire_ok();
  CHECK(palp_cli_local_model_from_wire(&w, &m) == 0, "a sound sample passes");
  const double periods[4] = {0, 1e-6, 1.5, -0.004};
  for (int i = 0; i < 4; ++i) {
    w = wire_ok(), w.period = periods[i];
    CHECK(palp_cli_local_model_from_wire(&w, &m) < 0, "period %g s refused (%g..%g s)", periods[i],
          PALP_CLI_MODEL_PERIOD_MIN, PALP_CLI_MODEL_PERIOD_MAX);
  }
  w = wire_ok(), w.stiffness[1] = 100, w.stiffness[3] = -100;
  CHECK(palp_cli_local_model_from_wire(&w, &m) < 0, "an asymmetric K (K_xy = 100, K_yx = -100 N/m) refused");
  w = wire_ok(), w.stiffness[1] = 20 + 1e-5;
  CHECK(palp_cli_local_model_from_wire(&w, &m) == 0, "K_xy - K_yx = 1e-5 N/m (1.7e-8 of 600 N/m) passes");
  w = wire_ok(), w.stiffness[8] = -600;
  CHECK(palp_cli_local_model_from_wire(&w, &m) < 0, "a negative K_zz refused");
  w = wire_ok(), w.in_contact = 0, w.normal = (palp_Vec3){1e5, 0, 0};
  CHECK(palp_cli_local_model_from_wire(&w, &m) < 0, "out of contact, a normal of length 1e5 refused");
  w = wire_ok(), w.in_contact = 0, w.normal = (palp_Vec3){0, 0, 0};
  CHECK(palp_cli_local_model_from_wire(&w, &m) == 0, "out of contact, a zero normal passes");
  w = wire_ok(), w.force = (palp_Vec3){6000, 6000, 6000};
  CHECK(palp_cli_local_model_from_wire(&w, &m) < 0, "a force of 6000 N per axis (|F| = 10392 N > 1e4 N) refused");
  /* Positions are held to the device's 10 m: a finite proxy of 1e40 m once reached the finger
   * keyboard's fingertip depth (R + r - |proxy|) and its status line. */
  w = wire_ok(), w.proxy = (palp_Vec3){0, 0, 1e40};
  CHECK(palp_cli_local_model_from_wire(&w, &m) < 0, "a proxy 1e40 m out refused");
  w = wire_ok(), w.proxy = (palp_Vec3){0, 0, -11};
  CHECK(palp_cli_local_model_from_wire(&w, &m) < 0, "a proxy 11 m out refused (10 m, as the device)");
  w = wire_ok(), w.proxy = (palp_Vec3){0, 0, 0.058};
  CHECK(palp_cli_local_model_from_wire(&w, &m) == 0 && m.proxy.z == 0.058, "a proxy 58 mm out (a dome's pole) passes");
  w = wire_ok(), w.point = (palp_Vec3){1e40, 0, 0};
  CHECK(palp_cli_local_model_from_wire(&w, &m) < 0, "a contact point 1e40 m out refused");
  w = wire_ok(), w.depth = -1e40;
  CHECK(palp_cli_local_model_from_wire(&w, &m) < 0, "a depth of -1e40 m refused (20 m: device and proxy within 10 m)");
  w = wire_ok();
  palp_cli_local_model_from_wire(&w, &m);
  CHECK(palp_cli_local_model_fits_rate(&m, 250), "4 ms at 250 Hz fits");
  m.period = 0.004 / 16;
  CHECK(palp_cli_local_model_fits_rate(&m, 250), "0.25 ms (a retried step's 1/16) at 250 Hz fits");
  m.period = 0.008;
  CHECK(!palp_cli_local_model_fits_rate(&m, 250), "8 ms at 250 Hz does not");
  m.period = 1e-4;
  CHECK(!palp_cli_local_model_fits_rate(&m, 250), "0.1 ms at 250 Hz does not");
}

/* 3. The server's physics rate: the contact sample interval is bounded, and the loop
 * refuses a rate outside 1..10000 Hz (1e-300 Hz made it 0, and tick % 0 a SIGFPE). */
static int no_read(void *ctx, double t, palp_vec3 *x) { (void)ctx, (void)t, (void)x; return PALP_CLI_INPUT_END; }
static void no_write(void *ctx, palp_vec3 f, unsigned flags) { (void)ctx, (void)f, (void)flags; }

static void test_physics_rate(void) {
  CHECK(palp_cli_contact_every(1000, 250) == 4, "1 kHz over 250 Hz: every 4th tick");
  CHECK(palp_cli_contact_every(1000, 300) == 3, "1 kHz over 300 Hz: every 3rd (3.33 rounded)");
  CHECK(palp_cli_contact_every(1000, 2000) == 1, "physics above the haptic rate: every tick");
  CHECK(palp_cli_contact_every(1000, 1e-300) == 1000000, "1e-300 Hz: bounded at 1e6 ticks (was 0 after overflow)");
  CHECK(palp_cli_contact_every(1000, 0) == 1000000 && palp_cli_contact_every(1000, NAN) == 1,
        "0 Hz bounded, NaN: every tick");
  const double bad[4] = {1e-300, 0.5, 2e4, NAN};
  for (int i = 0; i < 4; ++i) {
    palp_cli_input in;
    memset(&in, 0, sizeof in);
    in.name = "test", in.read_position = no_read, in.write_force = no_write;
    palp_cli_haptic_def d = palp_cli_haptic_default_def();
    d.in = &in;
    d.physics_rate_hz = bad[i];
    static palp_cli_haptic_loop l;
    char err[256] = "";
    const int rc = palp_cli_haptic_start(&l, &d, err, sizeof err);
    CHECK(rc == PALP_EINVAL && strstr(err, "physics rate"), "physics rate %g Hz refused: \"%s\"", bad[i], err);
  }
}

/* 5. The safe force is the station's and the phantom's, not any model's: a loop with a
 * 10 N station limit on a 3 N phantom renders a 5 N model at 3 N although the model's
 * max_force says 1e-9 N (before: lowered to 1e-9 N for the rest of the session). The run
 * ends 0.3 s (station time) after the model was taken: the 0.1 s onset is over. */
typedef struct fake_dev {
  atomic_int model_seen;
  double t_model, peak;
} fake_dev;
static int fake_read(void *ctx, double t, palp_vec3 *x) {
  fake_dev *d = ctx;
  *x = (palp_vec3){0, 0, 0.03};
  if (atomic_load(&d->model_seen) == 1) d->t_model = t, atomic_store(&d->model_seen, 2);
  if (atomic_load(&d->model_seen) == 2 && t > d->t_model + 0.3) return PALP_CLI_INPUT_END;
  if (t > 5.0) return PALP_CLI_INPUT_END; /* no model came: fails below */
  return 1;
}
static void fake_write(void *ctx, palp_vec3 f, unsigned flags) {
  (void)flags;
  fake_dev *d = ctx;
  d->peak = fmax(d->peak, len(f));
}
static void fake_model(void *ctx, const palp_local_model *m) {
  (void)m;
  fake_dev *d = ctx;
  int z = 0;
  atomic_compare_exchange_strong(&d->model_seen, &z, 1);
}

static void test_safe_force(void) {
  static fake_dev dev;
  palp_cli_input in;
  memset(&in, 0, sizeof in);
  in.name = "fake", in.ctx = &dev, in.read_position = fake_read, in.write_force = fake_write, in.model = fake_model;
  palp_cli_haptic_def d = palp_cli_haptic_default_def();
  d.in = &in;
  d.phantom_max_force = 3.0;
  static palp_cli_haptic_loop l;
  char err[256] = "";
  CHECK(palp_cli_haptic_start(&l, &d, err, sizeof err) == 0, "loop started %s", err);
  palp_local_model m = contact_model(1.0, 0.03, 5.0, 500);
  palp_cli_mailbox_put(&l.mailbox, &m, 0, 1e-9, 0.001);
  while (!palp_cli_haptic_done(&l)) nanosleep(&(struct timespec){0, 10000000}, NULL);
  palp_cli_haptic_stats st;
  palp_cli_haptic_join(&l, &st);
  CHECK(atomic_load(&dev.model_seen) == 2 && st.models == 1, "the model was taken (%llu)",
        (unsigned long long)st.models);
  CHECK(fabs(st.max_force - 3.0) < 1e-12 && fabs(dev.peak - 3.0) < 1e-9,
        "safe force %.3g N (min of 10 N and the phantom's 3 N), peak written %.6f N (3 N)", st.max_force, dev.peak);
}

/* 6. The summary's seconds are periods the device rendered, not ticks run (2026-12-07): a device
 * whose read blocks the loop 20 ms every 0.1 s (a loaded machine's late wake-ups, made sure) while a
 * model flagged deeper than validated is rendered for 0.6 s. The deadlines a late tick skips held the
 * force of the tick before, flags and all: the flagged count is the flagged span in ms, within 5
 * ticks (the span's two ends), though ~100 of its deadlines were skipped.
 * Before: only the ticks run were counted, ~100 short. */
typedef struct block_dev {
  atomic_int model_seen;
  double t_model, t_end, next_block;
} block_dev;
static int block_read(void *ctx, double t, palp_vec3 *x) {
  block_dev *d = ctx;
  *x = (palp_vec3){0, 0, 0.03};
  if (atomic_load(&d->model_seen) == 1) d->t_model = t, d->next_block = t + 0.1, atomic_store(&d->model_seen, 2);
  if (atomic_load(&d->model_seen) == 2 && t >= d->t_model + 0.6) {
    d->t_end = t; /* the deadlines a late last wake-up skipped were flagged too: the span ends here */
    return PALP_CLI_INPUT_END;
  }
  if (t > 5.0) return PALP_CLI_INPUT_END; /* no model came: fails below */
  if (atomic_load(&d->model_seen) == 2 && t >= d->next_block) {
    d->next_block += 0.1;
    nanosleep(&(struct timespec){0, 20000000}, NULL);
  }
  return 1;
}
static void block_model(void *ctx, const palp_local_model *m) {
  (void)m;
  block_dev *d = ctx;
  int z = 0;
  atomic_compare_exchange_strong(&d->model_seen, &z, 1);
}

static void test_skipped_deadlines(void) {
  static block_dev dev;
  palp_cli_input in;
  memset(&in, 0, sizeof in);
  in.name = "blocking", in.ctx = &dev, in.read_position = block_read, in.write_force = no_write, in.model = block_model;
  palp_cli_haptic_def d = palp_cli_haptic_default_def();
  d.in = &in;
  static palp_cli_haptic_loop l;
  char err[256] = "";
  CHECK(palp_cli_haptic_start(&l, &d, err, sizeof err) == 0, "loop started %s", err);
  double t = 1.0;
  while (!palp_cli_haptic_done(&l)) { /* a fresh model every 4 ms, as the server's 250 Hz stream */
    const palp_local_model m = contact_model(t, 0.03, 2.0, 500);
    palp_cli_mailbox_put(&l.mailbox, &m, palp_LM_BEYOND_VALIDATED, 10.0, 0.001);
    t += 0.004;
    nanosleep(&(struct timespec){0, 4000000}, NULL);
  }
  palp_cli_haptic_stats st;
  palp_cli_haptic_join(&l, &st);
  /* to the read that ended it, not the last one rendered: under load the last wake-up came 5.7 ms
   * late and its skipped deadlines, flagged as they should be, fell outside a span that ended at
   * t_last (605 periods over 599.3 ms, session 82's full run) */
  const double span_ms = (dev.t_end - dev.t_model) * 1e3;
  CHECK(atomic_load(&dev.model_seen) == 2 && st.missed >= 50,
        "the device blocked the loop: %llu deadlines skipped (want >= 50: 5 blocks of 20 ms)",
        (unsigned long long)st.missed);
  CHECK(fabs((double)st.beyond_validated_ticks - span_ms) <= 5 && st.out_of_range_ticks == st.beyond_validated_ticks,
        "deeper than validated for %llu periods of 1 ms over a flagged span of %.1f ms (want within 5), out of range "
        "%llu (the same); %llu ticks run in all", (unsigned long long)st.beyond_validated_ticks, span_ms,
        (unsigned long long)st.out_of_range_ticks, (unsigned long long)st.ticks);
}

/* ---- session 80's review (2026-12-07) ---- */

/* A plane z = 0 of stiffness k [N/m] as the server answers a device at z: force k (-z) up while
 * z < 0, K_zz = k, the normal +z (out of contact: no force, no K, normal +z). */
static palp_local_model plane_model(double time, double z, double k) {
  palp_local_model m = contact_model(time, z, z < 0 ? -k * z : 0.0, z < 0 ? k : 0.0);
  m.contact = z < 0;
  m.proxy = (palp_vec3){0, 0, 0};
  return m;
}

/* 8. The passivity controller on a stiff plane (2000 N/m) with models 40 ms late (every 4 ms,
 * each of the device 40 ms before), 10 smooth press-release cycles 10 mm deep (78 mm/s at
 * most). A plane never pulls: the rendered normal force is >= 0 on every tick (to 1e-12 N).
 * Before the fix the controller's damper pulled while the hand came out: 1,084 ticks, down to
 * -0.32 N (a triangular 50 mm/s wave: 670 ticks, -2.9 N). The net work on the device (sum
 * F . dx) is within 1% of the work the hand put in: 0.00% since session 89, whose cut lessens
 * the push coming off (sessions 80-88: 1.9%, what the damper could not take out coming off
 * it took pressing in, and not all of it). */
static void test_passivity_no_pull(void) {
  palp_cli_haptic_core c;
  core_make(&c, 1);
  palp_haptic_out o;
  enum { LAG = 40, N = 10 * 440 + 100 };
  static double z_at[N + 1];
  double least = INFINITY, worst_step = 0, prev = 0, work = 0, pushed_in = 0, zprev = 0.001;
  int pulls = 0;
  for (int k = 0; k <= N; ++k) {
    const double t = k * TICK;
    /* 1 mm above, down to 10 mm below and back every 0.44 s (a hand's smooth reversal; 78 mm/s at most) */
    const double z = k >= 10 * 440 ? 0.001 : 0.001 - 0.011 * 0.5 * (1.0 - cos(2.0 * 3.14159265358979 * t / 0.44));
    z_at[k] = z;
    palp_local_model mk;
    const int model = k % 4 == 0;
    if (model) mk = plane_model(t - LAG * TICK, k >= LAG ? z_at[k - LAG] : 0.001, 2000);
    palp_cli_haptic_core_tick(&c, 1, (palp_vec3){0, 0, z}, t, model ? &mk : NULL, LAG * TICK, &o, NULL);
    const double dz = z - zprev;
    work += prev * dz;                 /* the force of the tick before acted over this tick's motion */
    if (dz < 0) pushed_in += -prev * dz;
    if (o.flags & PALP_HAPTIC_CONTACT) least = fmin(least, o.force.z);
    pulls += o.force.z < -1e-12;
    if (k > 0) worst_step = fmax(worst_step, fabs(o.force.z - prev));
    prev = o.force.z, zprev = z;
  }
  printf("stiff plane, 40 ms late models: least force in contact %.4f N, %d pulling ticks, largest step %.3f N, "
         "work on the device %.2f mJ of %.2f mJ put in, controller acted %llu ticks\n", least, pulls, worst_step,
         1e3 * work, 1e3 * pushed_in, (unsigned long long)c.pc_ticks);
  CHECK(pulls == 0, "the plane never pulls the finger in: %d ticks below 0 N (least in contact %.4f N)", pulls,
        least);
  CHECK(c.pc_ticks > 0 && work <= 0.01 * pushed_in, "passive: %.2f mJ given back net for %.2f mJ put in "
        "(<= 1%%), the controller acting on %llu ticks", 1e3 * work, 1e3 * pushed_in, (unsigned long long)c.pc_ticks);
}

/* 8b. The passivity controller never pulls either, coming off the surface (session 82's
 * review #3). A plane of 600 or 2000 N/m; a model every 4 ms of the device `lag` ms before
 * (4, 10 or 20 ms); the device moves 2 mm either side of z = -0.5 mm at 5 Hz (in contact
 * 0.25 of each cycle's 2.5 mm swing below 0, out for the rest), 4000 ticks, 20 cycles. A
 * surface pushes: F_z >= -1e-9 N on every tick, in contact or coming off. Before (session
 * 88's code) the controller's damper -a v acted along the hand's velocity as the hand left,
 * with the observer's excess still in it: 4-84 ticks pulled, down to -1.11 N. And, over 19
 * whole cycles (from the deepest point of the first to that of the 20th: each release with
 * the press after it), the work on the device (sum F_k . (z_{k+1} - z_k)) stays within 1% of
 * the work the hand put in: what the damper may not take coming off it takes at the next
 * press. Before: 2.6-26% given back over those cycles. */
static void test_leave_no_pull(double k_plane, int lag) {
  palp_cli_haptic_core c;
  core_make(&c, 1);
  palp_haptic_out o;
  enum { N = 4000 };
  static double z_at[N + 1];
  double least = 0, work = 0, pushed_in = 0, prev = 0, zprev = 0;
  int pulls = 0, at = -1;
  for (int k = 0; k <= N; ++k) {
    const double t = k * TICK;
    const double z = -0.0005 + 0.002 * sin(2.0 * 3.14159265358979 * 5.0 * t);
    z_at[k] = z;
    palp_local_model mk;
    const int model = k % 4 == 0;
    if (model) mk = plane_model(t - lag * TICK, k >= lag ? z_at[k - lag] : z_at[0], k_plane);
    palp_cli_haptic_core_tick(&c, 1, (palp_vec3){0, 0, z}, t, model ? &mk : NULL, lag * TICK, &o, NULL);
    if (k > 150 && k <= 3950) { /* the bottoms of the 1st and the 20th cycles: 19 whole cycles */
      const double dz = z - zprev;
      work += prev * dz;
      if (prev * dz < 0) pushed_in += -prev * dz;
    }
    if (o.force.z < least) least = o.force.z, at = k;
    pulls += o.force.z < -1e-9;
    prev = o.force.z, zprev = z;
  }
  printf("leaving a %.0f N/m plane, models %d ms late: %d pulling ticks, most negative F_z %.4f N (tick %d); work "
         "on the device %.4f mJ of %.4f mJ put in; controller acted %llu ticks, took out %.4f mJ, %.4f mJ left in the observer\n", k_plane, lag,
         pulls, least, at, 1e3 * work, 1e3 * pushed_in, (unsigned long long)c.pc_ticks, 1e3 * c.dissipated, 1e3 * c.energy);
  CHECK(pulls == 0, "leaving a %.0f N/m plane with models %d ms late never pulls: %d ticks below -1e-9 N (least "
        "%.4f N)", k_plane, lag, pulls, least);
  CHECK(work <= 0.01 * pushed_in, "and stays passive: %.4f mJ given back net for %.4f mJ put in (<= 1%%)", 1e3 * work,
        1e3 * pushed_in);
}

/* 9. A press after a lift (50 ms, longer than the 40 ms the server's last in-contact models
 * still come) at the same spot: models of 3 N on 600 N/m came while pressed and while lifted,
 * none after. The new press feels 0 N on every tick until a new model; the first one (3 N)
 * blends in from 0: at most 3 N x 1 ms / fade_time (0.1 s) on its first tick, slack 5%. Before:
 * 3.0 N on the press's first tick. The new models come every period (4 ms) from 200 ms, as the
 * server sends them: the whole onset rises by at most 3 N / 100 ticks a tick (+1e-9 N) and is
 * 3 N from 300 ms (session 82: the second model finished the ramp within 4 ticks, 0.7 N a tick). */
static void test_repress(double side) {
  palp_cli_haptic_core c;
  core_make(&c, 0);
  palp_haptic_out o;
  double worst_silent = 0, first_new = -1, worst_onset = 0, prev = 0, at_half = -1;
  for (int k = 0; k <= 320; ++k) {
    const double t = k * TICK;
    const int on = k < 100 || k >= 150;                 /* lifted 100..149 ms */
    const int model = k % 4 == 0 && (k < 140 || k >= 200); /* in-contact models until 140 ms; new ones from 200 ms */
    palp_local_model mk = contact_model(t, 0.0, 3.0, 600);
    const palp_vec3 x = {k >= 150 ? side : 0.0, 0, 0};
    palp_cli_haptic_core_tick(&c, on, x, t, model ? &mk : NULL, 0.001, &o, NULL);
    if (k >= 150 && k < 200) worst_silent = fmax(worst_silent, len(o.force));
    if (k == 200) first_new = len(o.force);
    if (k == 250) at_half = len(o.force);
    if (k >= 200) worst_onset = fmax(worst_onset, fabs(len(o.force) - prev));
    prev = len(o.force);
  }
  CHECK(worst_silent == 0.0, "pressed again %g mm aside after a 50 ms lift: 0 N until a new model (largest %.3f N; "
        "was 3 N at once)", 1e3 * side, worst_silent);
  CHECK(first_new >= 0 && first_new <= 3.0 * TICK / 0.1 * 1.05, "the first new model blends in from 0: %.4f N on its "
        "first tick (<= %.4f N)", first_new, 3.0 * TICK / 0.1 * 1.05);
  CHECK(worst_onset <= 0.03 + 1e-9 && fabs(at_half - 1.5) < 1e-9 && fabs(prev - 3.0) < 1e-9,
        "a model every 4 ms through the onset: largest tick step %.4f N (<= 0.03 N: 3 N over 100 ticks), %.6f N at "
        "50 ms (1.5 N), %.6f N at the end (3 N)", worst_onset, at_half, prev);
}

/* 10. A correction from a retried step's model (its period 0.25 ms, 1/16 of the 4 ms step at
 * 250 Hz) blends over the session's step, not its period: a 1 -> 3 N correction under a still
 * device moves at most 2 N / 4 ticks = 0.5 N a tick (slack 1e-9). Before: 2.0 N in one tick. */
static void test_retried_blend(void) {
  palp_cli_haptic_core c;
  core_make(&c, 0);
  palp_haptic_out o;
  double worst = 0, prev = 0;
  for (int k = 0; k <= 40; ++k) {
    palp_local_model m1 = contact_model(k * TICK, 0.0, 1.0, 600), m3 = contact_model(k * TICK, 0.0, 3.0, 600);
    m3.period = 0.004 / 16;
    palp_local_model *mp = k == 0 ? &m1 : (k == 20 ? &m3 : NULL);
    palp_cli_haptic_core_tick(&c, 1, (palp_vec3){0, 0, 0}, k * TICK, mp, 0.001, &o, NULL);
    if (k > 20) worst = fmax(worst, fabs(o.force.z - prev));
    prev = o.force.z;
  }
  CHECK(worst <= 0.5 + 1e-9 && fabs(o.force.z - 3.0) < 1e-9, "a retried step's correction: largest step %.3f N a "
        "tick (<= 0.5 N), %.4f N at the end (3 N)", worst, o.force.z);
}

/* 11. A model whose age is not trusted (unknown -1, beyond max_latency 0.5 s) is held at once:
 * with the hand going in at 20 mm/s its 1 N stays 1 N (to 1e-9 N) on every tick; one 1 ms old
 * follows K for its horizon (8 ms: up to 1 + 600 x 0.02 x 0.008 = 1.096 N, > 1.05 N). Before,
 * an untrusted age counted as 0 and followed K longest. */
static void test_untrusted_age(double age) {
  palp_cli_haptic_core c;
  core_make(&c, 0);
  palp_haptic_out o;
  double most = 0;
  for (int k = 0; k <= 20; ++k) {
    palp_local_model m = contact_model(0.0, 0.0, 1.0, 600);
    const double z = -0.02 * k * TICK;
    palp_cli_haptic_core_tick(&c, 1, (palp_vec3){0, 0, z}, k * TICK, k == 0 ? &m : NULL, age, &o, NULL);
    most = fmax(most, o.force.z);
  }
  if (age >= 0 && age <= 0.2)
    CHECK(most > 1.05, "a model %g s old follows K for its horizon (up to %.4f N)", age, most);
  else
    CHECK(fabs(most - 1.0) < 1e-9, "a model of untrusted age %g s is held at once (up to %.6f N, 1 N)", age, most);
}

/* 12. The mailbox keeps the newest model waiting: a model older than the untaken one is not put
 * (counted); once taken, any model goes in (the renderer judges it). */
static void test_mailbox_order(void) {
  palp_cli_mailbox mb;
  palp_cli_mailbox_init(&mb);
  palp_local_model m2 = contact_model(2.0, 0, 1, 0), m1 = contact_model(1.0, 0, 1, 0), got;
  uint32_t fl;
  double mf, age;
  uint64_t seq = 0;
  palp_cli_mailbox_put(&mb, &m2, 0, 10, 0.001);
  palp_cli_mailbox_put(&mb, &m1, 0, 10, 0.001); /* reordered in one batch */
  const int took = palp_cli_mailbox_take(&mb, &seq, &got, &fl, &mf, &age);
  CHECK(took == 1 && got.time == 2.0 && mb.superseded == 1, "an older model after a newer untaken one: the newer "
        "is taken (time %g s, 2 s), 1 superseded (%llu)", got.time, (unsigned long long)mb.superseded);
  palp_cli_mailbox_put(&mb, &m1, 0, 10, 0.001);
  CHECK(palp_cli_mailbox_take(&mb, &seq, &got, &fl, &mf, &age) == 1 && got.time == 1.0,
        "after a take an older model goes in (time %g s)", got.time);
  palp_cli_mailbox_destroy(&mb);
}

/* 13. The contact ring keeps room for a lift: position samples are refused with 3 slots left,
 * and a lift's 3 releases then all fit, a 4th not. */
static void test_outbox_lift(void) {
  unsigned q = 0;
  while (palp_cli_outbox_admits(q, 0)) q++;
  int releases = 0;
  while (palp_cli_outbox_admits(q + (unsigned)releases, 1)) releases++;
  CHECK(q == PALP_CLI_OUTBOX - PALP_CLI_RELEASE_SAMPLES && releases == PALP_CLI_RELEASE_SAMPLES,
        "a full ring of position samples (%u of %d) still takes a whole lift (%d releases, %d)", q, PALP_CLI_OUTBOX,
        releases, PALP_CLI_RELEASE_SAMPLES);
}

/* ---- session 82's review ---- */

/* 14. The onset through the station core as palp-client runs it (250 Hz, compensation and
 * passivity on, the default renderer with its damper): the finger held 2 mm into a 1000 N/m
 * surface, a 2 N model at t = 0 and then every 4 ms. Expected, by hand: the gain t / fade_time,
 * 2 N x 1 ms / 0.1 s = 0.02 N a tick (+1e-9 N), 1 N at 50 ms, 2 N from 100 ms. Before: the second
 * model finished the ramp over one period, 0.48 N a tick (24x the bound), 2 N at 8 ms. */
static void test_onset_stream(void) {
  palp_cli_haptic_core c;
  palp_haptic_def def = palp_haptic_default_def();
  palp_cli_haptic_core_init(&c, &def, 250, 1, 0, 0.2);
  palp_haptic_out o;
  const palp_vec3 x = {0, 0, -0.002};
  double prev = 0, worst = 0, half = -1;
  int taken = 0;
  for (int k = -5; k <= 150; ++k) {
    const double t = k * TICK;
    palp_local_model m = plane_model(1.0 + t, -0.002, 1000);
    taken += palp_cli_haptic_core_tick(&c, 1, x, t, k >= 0 && k % 4 == 0 ? &m : NULL, 0.001, &o, NULL) == 1;
    worst = fmax(worst, fabs(o.force.z - prev));
    if (k == 50) half = o.force.z;
    prev = o.force.z;
  }
  printf("onset through the core, a 2 N model every 4 ms: largest tick step %.4f N, %.4f N at 50 ms, %.4f N at 150 "
         "ms\n", worst, half, prev);
  CHECK(taken == 38 && worst <= 0.02 + 1e-9 && fabs(half - 1.0) < 1e-9 && fabs(prev - 2.0) < 1e-9,
        "onset with a model every period (%d taken, 38): largest tick step %.4f N (<= 0.02 N: F / 100 ticks), %.6f N "
        "at 50 ms (1 N), %.6f N at the end (2 N)", taken, worst, half, prev);
}

/* 15. A quick tap (the review's): 1 mm into 1000 N/m, the first model (1 N) at t = 0, then one
 * every 4 ms of the plane at the device point 1 ms before (or none for 40 ms after the first:
 * a late server); the hand lifts at 200 mm/s from 1 ms. A surface never pulls: F_z >= -1e-9 N on
 * every tick, passivity on or off. Before: the onset's offset (-F_new at the arrival) was left
 * alone as F_new fell to 0, down to -0.56 N (-0.94 N with the pause, held by the core's hold). */
static double tap_z(int i) { return -0.001 + (i > 1 ? 0.2 * (i * TICK - 0.001) : 0); }
static void test_tap(int passivity, double pause) {
  palp_cli_haptic_core c;
  palp_haptic_def def = palp_haptic_default_def();
  palp_cli_haptic_core_init(&c, &def, 250, 1, 0, 0.2);
  c.passivity = passivity;
  palp_haptic_out o;
  double least = 0, most = 0;
  int at = -1;
  for (int i = -5; i <= 80; ++i) {
    const double t = i * TICK, z = tap_z(i), zl = tap_z(i - 1);
    palp_local_model m = plane_model(1.0 + t, zl, 1000);
    const int model = i >= 0 && i % 4 == 0 && (i == 0 || t >= pause);
    palp_cli_haptic_core_tick(&c, 1, (palp_vec3){0, 0, z}, t, model ? &m : NULL, 0.001, &o, NULL);
    if (o.force.z < least) least = o.force.z, at = i;
    most = fmax(most, o.force.z);
  }
  CHECK(least >= -1e-9, "a quick tap, passivity %d, models paused %.0f ms after the first: most negative F_z %.3e N "
        "(at %d ms; >= -1e-9 N), largest %.4f N", passivity, 1e3 * pause, least, at, most);
}

/* 17. palp_sym3_eig on K = [[2,1,0],[1,2,0],[0,0,3]]: eigenvalues 1, 3, 3 by hand (2 -+ 1 on the
 * xy block, 3 on z); V orthonormal and V diag(l) V^T = K, to 1e-12. */
static void test_sym3_eig(void) {
  const double K[3][3] = {{2, 1, 0}, {1, 2, 0}, {0, 0, 3}};
  double l[3], V[3][3], worst_k = 0, worst_o = 0;
  palp_sym3_eig(K, l, V);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double r = 0, o = 0;
      for (int e = 0; e < 3; ++e) r += V[i][e] * l[e] * V[j][e], o += V[e][i] * V[e][j];
      worst_k = fmax(worst_k, fabs(r - K[i][j]));
      worst_o = fmax(worst_o, fabs(o - (i == j)));
    }
  const double lo = fmin(fmin(l[0], l[1]), l[2]), hi = fmax(fmax(l[0], l[1]), l[2]);
  CHECK(fabs(lo - 1) < 1e-12 && fabs(hi - 3) < 1e-12 && fabs(l[0] + l[1] + l[2] - 7) < 1e-12 && worst_k < 1e-12 &&
            worst_o < 1e-12,
        "palp_sym3_eig: eigenvalues %.15g %.15g %.15g (1, 3, 3), |V L V^T - K| %.1e, |V^T V - I| %.1e", l[0], l[1], l[2],
        worst_k, worst_o);
}

/* 18. The station's stiffness bound. (a) The review's indefinite K, [[0, 1000, 0], [1000, 0, 0],
 * [0, 0, 1000]] N/m: diagonal >= 0, so the wire check passes it, but its eigenvalue along
 * u = (1, -1, 0)/sqrt2 is -1000 N/m. Projected (by hand: 1000 (v v^T + z z^T), v = (1, 1, 0)/sqrt2,
 * which has no part along u), 1 mm along u renders the model's own 1 N along z, nothing along
 * the motion (to 1e-9 N), flagged limited. Before: (0.707, -0.707, 1) N, +1 N along the motion.
 * (b) K_zz = 1e6 N/m: 1 mm in renders 1 N + max_stiffness (4000 N/m) x 1 mm = 5 N (to 1e-9 N),
 * flagged. Before: 1001 N asked, 10 N (the force limit). (c) A positive definite K under the cap
 * is left bit for bit; a rank-1 K's round-off is projected but not flagged. */
static void test_stiffness_limit(void) {
  palp_LocalModel w = wire_ok();
  const double Kw[9] = {0, 1000, 0, 1000, 0, 0, 0, 0, 1000};
  memcpy(w.stiffness, Kw, sizeof Kw);
  palp_local_model m;
  CHECK(palp_cli_local_model_from_wire(&w, &m) == 0, "the indefinite K passes the wire check (diagonal >= 0)");
  palp_haptic_def def = palp_haptic_default_def();
  def.damping = 0;
  palp_haptic h;
  palp_haptic_init(&h, &def);
  CHECK(palp_haptic_update(&h, &m, 0.0) == 1, "the model with the indefinite K is taken");
  palp_haptic_out o;
  const double r = 0.001 / sqrt(2.0);
  palp_haptic_render(&h, (palp_vec3){r, -r, 0}, 0.0, &o);
  const double along = (o.force.x - o.force.y) / sqrt(2.0);
  CHECK(fabs(o.force.x) < 1e-9 && fabs(o.force.y) < 1e-9 && fabs(o.force.z - 1.0) < 1e-9 && along <= 1e-9 &&
            (o.flags & PALP_HAPTIC_LIMITED) && h.stiffness_limited == 1,
        "indefinite K, 1 mm along its negative direction: force (%.6f, %.6f, %.6f) N ((0, 0, 1)), %.2e N along the "
        "motion (<= 1e-9; was +1 N), limited flag %d, %llu model counted", o.force.x, o.force.y, o.force.z, along,
        (o.flags & PALP_HAPTIC_LIMITED) != 0, (unsigned long long)h.stiffness_limited);
  palp_haptic_init(&h, &def);
  palp_local_model stiff = contact_model(1.0, 0.0, 1.0, 1e6);
  palp_haptic_update(&h, &stiff, 0.0);
  palp_haptic_render(&h, (palp_vec3){0, 0, -0.001}, 0.0, &o);
  CHECK(fabs(o.force.z - (1.0 + def.max_stiffness * 0.001)) < 1e-9 && (o.flags & PALP_HAPTIC_LIMITED) &&
            h.stiffness_limited == 1,
        "K_zz = 1e6 N/m, 1 mm in: %.6f N (1 N + %.0f N/m x 1 mm = 5 N; was the 10 N limit), flagged limited",
        o.force.z, def.max_stiffness);
  /* through the station core, as palp-client renders it: flagged on the tick */
  palp_cli_haptic_core c;
  core_make(&c, 1);
  palp_local_model s2 = contact_model(1.0, 0.0, 1.0, 1e6);
  palp_cli_haptic_core_tick(&c, 1, (palp_vec3){0, 0, 0}, 0.0, &s2, 0.001, &o, NULL);
  palp_cli_haptic_core_tick(&c, 1, (palp_vec3){0, 0, -0.0001}, TICK, NULL, 0.001, &o, NULL);
  CHECK((o.flags & PALP_HAPTIC_LIMITED) && fabs(o.force.z - (1.0 + def.max_stiffness * 0.0001)) < 1e-9 &&
            c.renderer.stiffness_limited == 1,
        "through the core: K_zz = 1e6 N/m, 0.1 mm in, %.6f N (1.4 N), flagged limited", o.force.z);
  double K[3][3] = {{100, 20, 0}, {20, 100, 0}, {0, 0, 600}}, K0[3][3];
  memcpy(K0, K, sizeof K);
  CHECK(palp_haptic_limit_stiffness(K, 4000) == 0 && memcmp(K, K0, sizeof K) == 0,
        "a positive definite K under the cap: not limited, bit for bit");
  double R1[3][3] = {{360, 480, 0}, {480, 640, 0}, {0, 0, 0}}; /* 1000 n n^T, n = (0.6, 0.8, 0) */
  double dev = 0;
  const int r1 = palp_haptic_limit_stiffness(R1, 4000);
  const double R0[3][3] = {{360, 480, 0}, {480, 640, 0}, {0, 0, 0}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) dev = fmax(dev, fabs(R1[i][j] - R0[i][j]));
  CHECK(r1 == 0 && dev < 1e-9, "a rank-1 K: not flagged, changed by %.1e N/m at most (round-off)", dev);
}

/* 16. A refused model says nothing (session 90's review): the loop renders model A (time 1.0 s, no
 * flags); then B comes, older (0.9 s: a relay's reordering) and flagged outside the valid range. The
 * renderer refuses B, so the driver hears of A alone, no model is counted outside the range and no
 * tick is flagged (before: B was handed to the driver, counted, and its flag put on A's force until
 * the next model). */
typedef struct order_dev {
  atomic_int models, stop;
  double last_time;
} order_dev;
static int order_read(void *ctx, double t, palp_vec3 *x) {
  order_dev *d = ctx;
  *x = (palp_vec3){0, 0, 0.03};
  return atomic_load(&d->stop) || t > 5.0 ? PALP_CLI_INPUT_END : 1;
}
static void order_model(void *ctx, const palp_local_model *m) {
  order_dev *d = ctx;
  d->last_time = m->time;
  atomic_fetch_add(&d->models, 1);
}
static void test_refused_says_nothing(void) {
  static order_dev dev;
  palp_cli_input in;
  memset(&in, 0, sizeof in);
  in.name = "order", in.ctx = &dev, in.read_position = order_read, in.write_force = no_write, in.model = order_model;
  palp_cli_haptic_def d = palp_cli_haptic_default_def();
  d.in = &in;
  static palp_cli_haptic_loop l;
  char err[256] = "";
  CHECK(palp_cli_haptic_start(&l, &d, err, sizeof err) == 0, "refused model: loop started %s", err);
  palp_local_model a = contact_model(1.0, 0.03, 2.0, 500), b = contact_model(0.9, 0.03, 2.0, 500);
  palp_cli_mailbox_put(&l.mailbox, &a, 0, 10, 0.001);
  for (int i = 0; i < 500 && atomic_load(&dev.models) < 1; i++) nanosleep(&(struct timespec){0, 2000000}, NULL);
  palp_cli_mailbox_put(&l.mailbox, &b, palp_LM_BEYOND_VALIDATED, 10, 0.001);
  nanosleep(&(struct timespec){0, 100000000}, NULL); /* 100 ticks rendering A after B came */
  atomic_store(&dev.stop, 1);
  palp_cli_haptic_stats st;
  palp_cli_haptic_join(&l, &st);
  CHECK(atomic_load(&dev.models) == 1 && dev.last_time == 1.0 && st.models == 1,
        "  the driver told of model A alone (%d, last at %.1f s), 1 model rendered (%llu)", atomic_load(&dev.models),
        dev.last_time, (unsigned long long)st.models);
  CHECK(st.out_of_range_models == 0 && st.out_of_range_ticks == 0,
        "  the refused B flagged nothing: %llu models counted outside the range, %llu ticks (0, 0)",
        (unsigned long long)st.out_of_range_models, (unsigned long long)st.out_of_range_ticks);
}

/* 17. The loop's summary has the device's bad readings (session 90's review: counted in the core,
 * never copied out): a device whose reads 10-16 are NaN (7 of them) and which ends at read 50. */
typedef struct nan_dev {
  int reads;
} nan_dev;
static int nan_read(void *ctx, double t, palp_vec3 *x) {
  (void)t;
  nan_dev *d = ctx;
  const int k = d->reads++;
  *x = k >= 10 && k <= 16 ? (palp_vec3){NAN, 0, 0.03} : (palp_vec3){0, 0, 0.03};
  return k >= 50 ? PALP_CLI_INPUT_END : 1;
}
static void test_bad_readings_counted(void) {
  static nan_dev dev;
  palp_cli_input in;
  memset(&in, 0, sizeof in);
  in.name = "nan", in.ctx = &dev, in.read_position = nan_read, in.write_force = no_write;
  palp_cli_haptic_def d = palp_cli_haptic_default_def();
  d.in = &in;
  static palp_cli_haptic_loop l;
  char err[256] = "";
  CHECK(palp_cli_haptic_start(&l, &d, err, sizeof err) == 0, "bad readings: loop started %s", err);
  while (!palp_cli_haptic_done(&l)) nanosleep(&(struct timespec){0, 10000000}, NULL);
  palp_cli_haptic_stats st;
  palp_cli_haptic_join(&l, &st);
  CHECK(st.bad_x_ticks == 7 && st.contacts_failed == 0,
        "  7 readings not numbers reach the summary (%llu), no contact write failed (%llu)",
        (unsigned long long)st.bad_x_ticks, (unsigned long long)st.contacts_failed);
}

/* 18. The renderer's own guards (session 90's review of src/haptic.c):
 *  - the damper's velocity over at least 0.5 ms: a render 10 us after the last with the device 10 um
 *    further in adds at most damping x 10 um / 0.5 ms = 2 x 0.02 = 0.04 N (before: 2 x 1 m/s = 2 N);
 *  - a model's contact normal of length 3 is taken as its unit vector: the hand withdrawing at
 *    0.1 m/s from a 1 N press never feels a pull (before: -0.8 N, the damper's floor read against |n|^2);
 *  - an infinite stale or fade time is refused at init (a silent server's force would never fade). */
static void test_renderer_guards(void) {
  palp_haptic_def def = palp_haptic_default_def(); /* damping 2 N s/m */
  palp_haptic h;
  palp_haptic_init(&h, &def);
  palp_haptic_out o;
  palp_local_model m = contact_model(1.0, 0.03, 1.0, 0);
  palp_haptic_update(&h, &m, 0.0);
  for (int k = 0; k <= 200; ++k) palp_haptic_render(&h, (palp_vec3){0, 0, 0.03}, k * TICK, &o); /* onset over */
  const double f0 = o.force.z;
  palp_haptic_render(&h, (palp_vec3){0, 0, 0.03 - 10e-6}, 0.200 + 10e-6, &o);
  CHECK(fabs(f0 - 1.0) < 1e-9 && o.force.z - f0 <= 0.04 + 1e-9,
        "a render 10 us after the last, 10 um further in: the damper adds %.4f N (<= 0.04 N; before 2 N)", o.force.z - f0);

  palp_haptic h2;
  palp_haptic_init(&h2, &def);
  palp_local_model m3 = contact_model(1.0, 0.03, 1.0, 0);
  m3.normal = (palp_vec3){0, 0, 3};
  CHECK(palp_haptic_update(&h2, &m3, 0.0) == 1, "a model with a normal of length 3 is taken");
  double least = 1e9;
  for (int k = 0; k <= 200; ++k) palp_haptic_render(&h2, (palp_vec3){0, 0, 0.03}, k * TICK, &o);
  for (int k = 1; k <= 20; ++k) { /* withdrawing at 0.1 m/s: 0.1 mm a tick */
    palp_haptic_render(&h2, (palp_vec3){0, 0, 0.03 + k * 1e-4}, 0.200 + k * TICK, &o);
    least = fmin(least, o.force.z);
  }
  CHECK(least >= 0.0, "  withdrawing from it at 0.1 m/s: the least force along the normal %.4f N (never a pull; "
        "before -0.80 N)", least);
  m3.normal = (palp_vec3){0, 0, 0};
  m3.time = 2.0;
  CHECK(palp_haptic_update(&h2, &m3, 0.3) == PALP_EINVAL, "  one in contact along no direction (normal 0) refused");

  palp_haptic h3;
  palp_haptic_def inf = palp_haptic_default_def();
  inf.stale_time = INFINITY;
  const int r1 = palp_haptic_init(&h3, &inf);
  inf = palp_haptic_default_def();
  inf.fade_time = INFINITY;
  const int r2 = palp_haptic_init(&h3, &inf);
  CHECK(r1 == PALP_EINVAL && r2 == PALP_EINVAL, "an infinite stale_time (%d) or fade_time (%d) refused at init", r1, r2);
}

/* 15. Where a mark may be taken (session 90's review): a pressing model every 4 ms to 100 ms, then a
 * server gone quiet. By hand: stale from 100 + 250 = 350 ms, faded to 0 N at 450 ms. At 200 ms (fresh,
 * 2 N) a mark is allowed; at 400 ms the hand still feels half the force (1 N, contact) but its point is
 * 300 ms old: no mark (before: allowed, at the old point); at 460 ms, faded, no contact and no mark.
 * After a new press (palp_haptic_forget) there is no model, so no mark until the server's next. */
static void test_can_mark(void) {
  palp_haptic_def def = palp_haptic_default_def(); /* stale 0.25 s, fade 0.1 s */
  def.damping = 0;
  palp_haptic h;
  palp_haptic_init(&h, &def);
  const palp_vec3 x = {0, 0, 0.03};
  palp_haptic_out o;
  int at200 = -1, at400 = -1, at460 = -1;
  unsigned f400 = 0;
  double force400 = -1;
  for (int k = 0; k <= 460; ++k) {
    const double t = k * TICK;
    if (k % 4 == 0 && k <= 100) {
      palp_local_model m = contact_model(1.0 + t, 0.03, 2.0, 500);
      palp_haptic_update(&h, &m, t);
    }
    palp_haptic_render(&h, x, t, &o);
    if (k == 200) at200 = palp_cli_haptic_can_mark(o.flags);
    if (k == 400) at400 = palp_cli_haptic_can_mark(o.flags), f400 = o.flags, force400 = len(o.force);
    if (k == 460) at460 = palp_cli_haptic_can_mark(o.flags);
  }
  CHECK(at200 == 1, "marks: a fresh pressing model at 200 ms allows a mark (%d)", at200);
  CHECK((f400 & PALP_HAPTIC_CONTACT) && fabs(force400 - 1.0) < 1e-9 && at400 == 0,
        "  300 ms after its last model the hand still feels %.6f N (1 N: half faded), in contact, but no mark (%d)",
        force400, at400);
  CHECK(at460 == 0, "  faded out at 460 ms: no mark (%d)", at460);
  palp_local_model m = contact_model(2.0, 0.03, 2.0, 500);
  palp_haptic_update(&h, &m, 0.5);
  palp_haptic_render(&h, x, 0.501, &o);
  const int fresh = palp_cli_haptic_can_mark(o.flags);
  palp_haptic_forget(&h);
  palp_haptic_render(&h, x, 0.502, &o);
  CHECK(fresh == 1 && palp_cli_haptic_can_mark(o.flags) == 0,
        "  the server back: a mark allowed (%d); a new press before its first model: none (%d)", fresh,
        palp_cli_haptic_can_mark(o.flags));
}

int main(void) {
  test_fade_above_limit(40);
  test_fade_above_limit(1e4);
  test_crossfade_above_limit();
  test_nonfinite();
  test_time_jump();
  test_unanchored(-1);
  test_unanchored(0.5);
  test_unanchored(-0.3);
  test_refused_keep_hold();
  test_silence_damper();
  test_nan_reading();
  test_from_wire();
  test_physics_rate();
  test_safe_force();
  test_skipped_deadlines();
  test_passivity_no_pull();
  const int lags[] = {4, 10, 20};
  for (int i = 0; i < 3; ++i) {
    test_leave_no_pull(600, lags[i]);
    test_leave_no_pull(2000, lags[i]);
  }
  test_repress(0.0);
  test_repress(0.010);
  test_retried_blend();
  test_untrusted_age(0.001);
  test_untrusted_age(-1);
  test_untrusted_age(0.5);
  test_mailbox_order();
  test_outbox_lift();
  test_onset_stream();
  test_tap(1, 0.0);
  test_tap(0, 0.0);
  test_tap(1, 0.040);
  test_tap(0, 0.040);
  test_sym3_eig();
  test_stiffness_limit();
  test_can_mark();
  test_refused_says_nothing();
  test_bad_readings_counted();
  test_renderer_guards();
  return check_exit();
}
