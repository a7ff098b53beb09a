/*
 * test_validated.c - where a parameter set was validated against the FE with a fingertip
 * (palp_world_def.validated_*, docs/model.md "Valid range"), and the world's count of
 * steps that press deeper (health.beyond_validated_steps, LM_BEYOND_VALIDATED on the wire).
 *
 * - palp_world_validated_depth: the table's values at its angles, linear in between, the
 *   end values beyond, +inf without a table (expected values by hand from the table).
 * - The shipped breast-tissue set (config/phantoms/dome.json) carries its table (pole 12 mm,
 *   45 deg 12, 60 deg 14, 70 deg 12 mm: the comparison with the FE refined where the finger
 *   presses, 2026-11-30, which eval_finger_refined checks against the stored curves; 14 mm at
 *   every site against uniform level 4 before), and a logged scene
 *   (palp_scene_to_json) gives it back bit for bit.
 * - Bad tables are refused with a message naming the field.
 * - A fingertip pressed at the pole to ~9 mm is never counted; pressed on to ~22 mm it is,
 *   and the largest excess equals the test's own largest R + r - |proxy| less the table's
 *   depth at the proxy's polar angle (1e-12 m; after each step, in contact); at 70
 *   deg, ~15 mm is counted (12 mm there); a set without a table counts nothing.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "palp.h"

#ifndef PALP_CONFIG_DIR
#define PALP_CONFIG_DIR "config"
#endif

static const double PI = 3.14159265358979323846;

static void test_interpolation(void) {
  palp_world_def d = palp_world_default_def();
  CHECK(isinf(palp_world_validated_depth(&d, 0.3)), "no table: no limit");
  d.validated_count = 3;
  d.validated_polar[0] = 0.0, d.validated_depth[0] = 0.0143;
  d.validated_polar[1] = 45.0 * PI / 180.0, d.validated_depth[1] = 0.0091;
  d.validated_polar[2] = 70.0 * PI / 180.0, d.validated_depth[2] = 0.0021;
  CHECK_NEAR(palp_world_validated_depth(&d, 0.0), 0.0143, 1e-15, "at the pole");
  CHECK_NEAR(palp_world_validated_depth(&d, 22.5 * PI / 180.0), 0.0117, 1e-12, "half way to 45 deg: (14.3 + 9.1) / 2 mm");
  CHECK_NEAR(palp_world_validated_depth(&d, 60.0 * PI / 180.0), 0.0049, 1e-12, "60 deg: 9.1 - 7.0 * 15 / 25 mm");
  CHECK_NEAR(palp_world_validated_depth(&d, 85.0 * PI / 180.0), 0.0021, 1e-15, "beyond the last angle: its depth");
  int e = 0;
  palp_world *w = palp_world_create(&d, &e);
  CHECK(w != NULL, "a valid table is accepted (%s)", palp_strerror(e));
  palp_world_destroy(w);
  d.validated_polar[2] = d.validated_polar[1];
  w = palp_world_create(&d, &e);
  CHECK(w == NULL && e == PALP_EINVAL, "polar angles not increasing: refused");
  palp_world_destroy(w);
}

static void test_scene(void) {
  palp_scene sc, back;
  char err[256];
  const char *path = PALP_CONFIG_DIR "/phantoms/dome.json";
  if (palp_scene_load(path, &sc, err, sizeof err)) {
    CHECK(0, "%s: %s", path, err);
    return;
  }
  CHECK(sc.world.validated_count == 4, "the breast-tissue set states 4 sites (%d)", sc.world.validated_count);
  CHECK_NEAR(sc.world.validated_depth[0], 0.012, 1e-15, "pole 12 mm");
  CHECK_NEAR(sc.world.validated_polar[1], 45.0 * PI / 180.0, 1e-15, "second site at 45 deg");
  CHECK_NEAR(sc.world.validated_depth[1], 0.012, 1e-15, "45 deg 12 mm");
  CHECK_NEAR(sc.world.validated_depth[2], 0.014, 1e-15, "60 deg 14 mm");
  CHECK_NEAR(sc.world.validated_depth[3], 0.012, 1e-15, "70 deg 12 mm");
  char *js = palp_scene_to_json(&sc);
  CHECK(js && palp_scene_parse(js, &back, err, sizeof err) == 0, "the logged scene parses again: %s", err);
  if (js) {
    CHECK(back.world.validated_count == sc.world.validated_count &&
              !memcmp(back.world.validated_polar, sc.world.validated_polar, sizeof sc.world.validated_polar) &&
              !memcmp(back.world.validated_depth, sc.world.validated_depth, sizeof sc.world.validated_depth),
          "the logged scene keeps the table bit for bit");
    free(js);
  }
  /* Bad tables: each refused, naming the field. */
  const char *base = "{\"name\":\"v\",\"mesh\":{\"radius_m\":0.04,\"vertex_count\":338},"
                     "\"membrane\":{\"thickness_m\":0.002,\"density_kg_m3\":950,\"E1_Pa\":1e6,\"eta1_Pa_s\":1e9,"
                     "\"E2_Pa\":1e5,\"eta2_Pa_s\":1e5},\"gel\":{\"law\":\"polytropic\",\"pressure_Pa\":101325,\"a1\":10,"
                     "\"a2_Pa_s_m3\":1e6},\"time\":{\"dt_s\":0.004,\"frames\":1},\"effects\":[],\"contacts\":[],";
  const struct {
    const char *v, *want;
  } bad[] = {
      {"\"validated\":{\"finger\":[{\"polar_deg\":45,\"depth_m\":0.01},{\"polar_deg\":10,\"depth_m\":0.01}]}}",
       "validated.finger[1].polar_deg: the polar angles must increase"},
      {"\"validated\":{\"finger\":[{\"polar_deg\":0,\"depth_m\":-0.01}]}}", "validated.finger[0].depth_m"},
      {"\"validated\":{\"finger\":[{\"polar_deg\":95,\"depth_m\":0.01}]}}", "within [0, 90] degrees"},
      {"\"validated\":{\"finger\":[]}}", "validated.finger: expected an array of 1 to 8"},
      {"\"validated\":[1,2]}", "validated: expected an object"},
      {"\"validated\":{\"finger\":[{\"polar_deg\":0,\"depth_m\":0.01}],\"hinge_error_rad\":1.5}}",
       "validated.hinge_error_rad: 1.5 rad is not a hinge's miss"},
      {"\"validated\":{\"finger\":[{\"polar_deg\":0,\"depth_m\":0.01}],\"hinge_error_rad\":0}}",
       "validated.hinge_error_rad: must be > 0"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
    char js2[2048];
    snprintf(js2, sizeof js2, "%s%s", base, bad[i].v);
    err[0] = 0;
    const int rc = palp_scene_parse(js2, &back, err, sizeof err);
    CHECK(rc != 0 && strstr(err, bad[i].want), "bad table %zu refused with \"%s\" (got %d: %s)", i, bad[i].want, rc, err);
  }
  char ok[2048];
  snprintf(ok, sizeof ok, "%s%s", base, "\"validated\":{\"finger\":[{\"polar_deg\":0,\"depth_m\":0.01}]}}");
  CHECK(palp_scene_parse(ok, &back, err, sizeof err) == 0 && back.world.validated_count == 1, "a one-site table: %s", err);
}

/* Presses a fingertip along the inward normal at polar angle th to the device depth
 * dev_mm over 1 s and holds 0.5 s; returns the proxy's indentation R + r - |proxy| [m]
 * at the end, and in *dmax the largest excess over the validated depth at the proxy's
 * own polar angle (it strays from the press's axis by a little), after any step in contact. */
static double proxy_depth(const palp_world *w, int f, double R, double r, int *contact, double *polar) {
  palp_local_model lm;
  palp_world_finger_local_model(w, f, &lm);
  const palp_vec3 p = lm.proxy;
  *contact = lm.contact;
  *polar = atan2(sqrt(p.x * p.x + p.y * p.y), p.z);
  return R + r - sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
}

static double press(palp_world *w, int f, double th, double R, double r, double from_mm, double dev_mm, double *dmax) {
  const palp_vec3 n = {sin(th), 0.0, cos(th)};
  const double dt = palp_world_get_def(w)->dt;
  const int ramp = (int)lround(1.0 / dt), hold = (int)lround(0.5 / dt);
  for (int k = 1; k <= ramp + hold; ++k) {
    const double d = 1e-3 * (from_mm + (dev_mm - from_mm) * fmin(1.0, (double)k / ramp));
    const double c = R + r - d;
    palp_world_set_finger_device(w, f, (palp_vec3){c * n.x, c * n.y, c * n.z});
    palp_world_step(w);
    int on = 0;
    double polar = 0.0;
    const double dp = proxy_depth(w, f, R, r, &on, &polar);
    const double over = dp - palp_world_validated_depth(palp_world_get_def(w), polar);
    if (on && over > *dmax) *dmax = over;
  }
  int on = 0;
  double polar = 0.0;
  return proxy_depth(w, f, R, r, &on, &polar);
}

/* The exercises' breast-tissue dome; nonzero (a failed check) when it does not load. */
static int load_dome(palp_scene *sc) {
  char err[256] = "";
  const int rc = palp_scene_load(PALP_CONFIG_DIR "/phantoms/dome.json", sc, err, sizeof err);
  CHECK(rc == 0, "%s", err);
  return rc;
}

static void test_counted(void) {
  palp_scene sc;
  if (load_dome(&sc)) return;
  const double R = sc.world.mesh.radius, r = 0.008;
  for (int site = 0; site < 3; ++site) {
    palp_world_def d = sc.world;
    if (site == 2) d.validated_count = 0, d.validated_hinge_error = 0.0; /* the same press, a set without a table */
    const double th = site == 1 ? 70.0 * PI / 180.0 : 0.0;
    int e = 0;
    palp_world *w = palp_world_create(&d, &e);
    CHECK(w != NULL, "world: %s", palp_strerror(e));
    if (!w) return;
    const int f = palp_world_add_finger(w, (palp_vec3){(R + r + 0.001) * sin(th), 0, (R + r + 0.001) * cos(th)}, r);
    palp_world_health h;
    /* the coupling spring stretches by F / k, so device 11 mm is ~9 mm of indentation */
    double dmax = -INFINITY;
    const double d12 = press(w, f, th, R, r, -1.0, site == 1 ? 22.0 : 11.0, &dmax); /* 70 deg: past its 12 mm */
    palp_world_get_health(w, &h);
    const double lim = palp_world_validated_depth(&d, th);
    if (site == 0) {
      CHECK(d12 > 0.008 && d12 < 0.010, "pole: the press reaches 8-10 mm (%.2f mm)", 1e3 * d12);
      CHECK(h.beyond_validated_steps == 0, "pole, %.2f mm (validated to %.1f): no step counted (%lld)", 1e3 * d12,
            1e3 * lim, (long long)h.beyond_validated_steps);
      CHECK(dmax < 0.0, "pole: never deeper than validated on the way (%.2f mm short at the closest)", -1e3 * dmax);
      const double d17 = press(w, f, th, R, r, 11.0, 30.0, &dmax);
      palp_world_get_health(w, &h);
      CHECK(d17 > 0.021, "pole: pressed on to beyond 21 mm (%.2f mm)", 1e3 * d17);
      CHECK(h.beyond_validated_steps > 0, "pole, %.2f mm: steps counted (%lld)", 1e3 * d17,
            (long long)h.beyond_validated_steps);
      CHECK_NEAR(h.max_beyond_validated, dmax, 1e-12, "pole: largest excess over the validated depth [m]");
      printf("pole: %.2f mm of indentation: 0 steps beyond the validated %.1f mm; %.2f mm: %lld steps, by up to %.2f mm\n",
             1e3 * d12, 1e3 * lim, 1e3 * d17, (long long)h.beyond_validated_steps, 1e3 * h.max_beyond_validated);
    } else if (site == 1) {
      CHECK(d12 > lim + 0.001, "70 deg: the press passes the validated %.1f mm by 1 mm (%.2f mm)", 1e3 * lim, 1e3 * d12);
      CHECK(h.beyond_validated_steps > 0, "70 deg, %.2f mm (validated to %.1f): steps counted (%lld)", 1e3 * d12,
            1e3 * lim, (long long)h.beyond_validated_steps);
      printf("70 deg: %.2f mm of indentation, validated to %.1f mm: %lld steps counted, by up to %.2f mm\n", 1e3 * d12,
             1e3 * lim, (long long)h.beyond_validated_steps, 1e3 * h.max_beyond_validated);
    } else {
      CHECK(h.beyond_validated_steps == 0 && h.max_beyond_validated == 0.0,
            "no table: nothing counted at %.2f mm (%lld)", 1e3 * d12, (long long)h.beyond_validated_steps);
    }
    palp_world_destroy(w);
  }
}

/* Presses at each site of the set's table to its validated depth, as the FE comparison
 * does (1 ms steps, the device at 5 mm/s until the proxy is there, then held 1 s with the
 * device moved so that the proxy stays there); returns the largest hinge miss the world
 * saw (health.max_bend_error) and, in *counted, the steps it counted beyond the hinges'
 * range over the four presses. */
static double validated_presses(palp_world_def d, int64_t *counted, double *depth_max) {
  d.dt = 0.001;
  const double R = d.mesh.radius, r = 0.008;
  double worst = 0.0;
  *counted = 0, *depth_max = 0.0;
  for (int s = 0; s < d.validated_count; ++s) {
    int e = 0;
    palp_world *w = palp_world_create(&d, &e);
    CHECK(w != NULL, "world: %s", palp_strerror(e));
    if (!w) return NAN;
    const double th = d.validated_polar[s], target = d.validated_depth[s];
    const palp_vec3 n = {sin(th), 0.0, cos(th)};
    const int f = palp_world_add_finger(w, (palp_vec3){(R + r + 0.001) * n.x, 0, (R + r + 0.001) * n.z}, r);
    double dev = -0.001, dp = -1.0, polar = 0.0;
    int on = 0, k = 0;
    for (; dp < target && k < 20000; ++k) {
      dev += 0.005 * d.dt;
      const double c = R + r - dev;
      palp_world_set_finger_device(w, f, (palp_vec3){c * n.x, c * n.y, c * n.z});
      palp_world_step(w);
      dp = proxy_depth(w, f, R, r, &on, &polar);
    }
    for (int t = 0; t < 1000; ++t) {
      dev += 0.3 * (target - dp); /* the coupling moves the proxy by ~0.5-0.9 of the device's move */
      const double c = R + r - dev;
      palp_world_set_finger_device(w, f, (palp_vec3){c * n.x, c * n.y, c * n.z});
      palp_world_step(w);
      dp = proxy_depth(w, f, R, r, &on, &polar);
    }
    palp_world_health h;
    palp_world_get_health(w, &h);
    printf("  %4.1f deg, held at %.3f mm (validated %.1f mm, %d steps to get there): largest hinge miss %.4f rad, "
           "%lld steps counted beyond the hinges' range\n",
           th * 180.0 / PI, 1e3 * dp, 1e3 * target, k, h.max_bend_error, (long long)h.large_bend_steps);
    CHECK(on && fabs(dp - target) < 2e-5, "%.0f deg: held in contact within 0.02 mm of %.1f mm (%.4f mm)",
          th * 180.0 / PI, 1e3 * target, 1e3 * dp);
    worst = fmax(worst, h.max_bend_error);
    *counted += h.large_bend_steps;
    *depth_max = fmax(*depth_max, dp);
    palp_world_destroy(w);
  }
  return worst;
}

/* A set's validated presses count no step beyond the hinges' range, and its stated miss rests on
 * them: at least their largest, at most 0.01 rad above. Returns that largest miss [rad]. */
static double stated_miss_rests_on_presses(const palp_scene *sc, const char *label) {
  const double stated = sc->world.validated_hinge_error;
  printf("%s, stated hinge miss %.3f rad; its validated presses at 1 ms:\n", label, stated);
  int64_t counted = 0;
  double deepest = 0.0;
  const double worst = validated_presses(sc->world, &counted, &deepest);
  CHECK(counted == 0, "%s: inside the validated depths no step is counted beyond the hinges' range (%lld)", label,
        (long long)counted);
  CHECK(stated >= worst && stated <= worst + 0.01,
        "%s: the stated miss %.3f rad rests on the validation: at least its presses' largest %.4f rad, at most 0.01 rad "
        "above", label, stated, worst);
  return worst;
}

/* The hinges' valid range of a set validated with a fingertip (palp_world_def.
 * validated_hinge_error): the breast-tissue set states the largest miss its validated
 * presses reach, and those presses count no step beyond the hinges' range; with the
 * former fixed 0.1 rad they did, inside the depths where the force agrees with the FE. */
static void test_hinge_range(void) {
  palp_scene sc;
  char err[256];
  if (load_dome(&sc)) return;
  const double stated = sc.world.validated_hinge_error;
  const double worst = stated_miss_rests_on_presses(&sc, "breast-tissue set");
  palp_world_def d = sc.world;
  d.validated_hinge_error = 0.0; /* the fixed 0.1 rad */
  int64_t counted0 = 0;
  double deepest = 0.0;
  const double worst0 = validated_presses(d, &counted0, &deepest);
  printf("with the fixed 0.1 rad: %lld steps counted in the same presses (largest miss %.4f rad)\n", (long long)counted0,
         worst0);
  CHECK(worst0 == worst && counted0 > 0, "the fixed 0.1 rad counts steps inside the validated depths (%lld)",
        (long long)counted0);
  /* a scene states it only beside its table: refused alone, and kept bit for bit in a log */
  d = sc.world;
  d.validated_count = 0;
  int e = 0;
  palp_world *w = palp_world_create(&d, &e);
  CHECK(!w && e == PALP_EINVAL, "a hinge miss without a validation table is refused (%d)", e);
  palp_world_destroy(w);
  palp_scene back;
  char *js = palp_scene_to_json(&sc);
  CHECK(js && palp_scene_parse(js, &back, err, sizeof err) == 0 &&
            !memcmp(&back.world.validated_hinge_error, &stated, sizeof stated),
        "the logged scene keeps the stated miss bit for bit: %s", err);
  free(js);
}

/* The same set on a 1,300-vertex net (config/phantoms/dome_fine.json, its own table and stated
 * miss): its validated presses count no step beyond the hinges' range, and the stated miss rests
 * on them (at least their largest, at most 0.01 rad above). */
static void test_hinge_range_fine(void) {
  palp_scene sc;
  char err[256] = "";
  const int rc = palp_scene_load(PALP_CONFIG_DIR "/phantoms/dome_fine.json", &sc, err, sizeof err);
  CHECK(rc == 0, "%s", err);
  if (rc) return;
  stated_miss_rests_on_presses(&sc, "breast-tissue set on 1,300 vertices");
}

int main(void) {
  test_interpolation();
  test_scene();
  test_counted();
  test_hinge_range();
  test_hinge_range_fine();
  CHECK_DONE();
}
