/*
 * test_finger_step.c - a held fingertip's force against the physics step
 * (palp_world_def.finger_linearise; docs/haptics.md, "The held force depends on
 * the physics step").
 *
 * The 8 mm fingertip's device is lowered at 50 mm/s to 3 mm below the pole's surface
 * and held 3 s (the support's relaxation, 0.35 s, long done: the force at +3 s and +6 s
 * agreed to 1e-4 N), at 4, 1 and 0.25 ms steps. Asserted:
 *  - with the contact linearised at the current positions ("current"), the held force
 *    is the same at every step within 0.1% (measured: equal to 4 digits, 0.7558 N on
 *    the breast-tissue dome, 2.8934 N on the long-term dome), which is what a static
 *    equilibrium must be;
 *    (the breast-tissue figure is the set as it was before its refit with "current" on
 *    2026-11-29; the refitted set holds 0.7319 N there, and 0.6197 N since its refit against
 *    the refined fingertip FE, 2026-11-30);
 *  - the other reading ("free", the step's free positions, with which the long-term set
 *    was fitted and the breast-tissue set was until 2026-11-29) tends to it as the step
 *    shrinks: within 2% at 0.25 ms (measured 1.2% on breast tissue). Its value at 4 ms is
 *    printed: 12.4% low on breast tissue.
 *  - a scene says which ("finger_linearise"): absent = "free" (the long-term dome's
 *    scene), the exercises' dome says "current", the logged scene keeps it, and a bad
 *    value is refused naming the field.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "palp.h"

/* The held force [N] at step dt with the contact linearised at `where`. */
static double held(const char *scene, double dt, int where) {
  palp_scene sc;
  char err[256];
  if (palp_scene_load(scene, &sc, err, sizeof err)) {
    CHECK(0, "%s: %s", scene, err);
    return NAN;
  }
  sc.world.dt = dt;
  sc.world.finger_linearise = where;
  int e = 0;
  palp_world *w = palp_world_create(&sc.world, &e);
  CHECK(w != NULL, "%s: world: %s", scene, palp_strerror(e));
  if (!w) return NAN;
  const double R = sc.world.mesh.radius, r = 0.008;
  double z = R + r + 0.001;
  const double zend = R + r - 0.003;
  const int f = palp_world_add_finger(w, (palp_vec3){0, 0, z}, r);
  double F = NAN, t_end = -1.0;
  for (long k = 0;; ++k) {
    const double t = (double)(k + 1) * dt;
    if (z > zend) z = fmax(zend, z - 0.05 * dt);
    else if (t_end < 0.0) t_end = t;
    palp_world_set_finger_device(w, f, (palp_vec3){0, 0, z});
    if (palp_world_step(w) < 0) {
      CHECK(0, "%s at %.2f ms: step failed", scene, dt * 1e3);
      break;
    }
    if (t_end >= 0.0 && t >= t_end + 3.0) {
      palp_local_model m;
      palp_world_finger_local_model(w, f, &m);
      F = sqrt(m.force.x * m.force.x + m.force.y * m.force.y + m.force.z * m.force.z);
      break;
    }
  }
  palp_world_destroy(w);
  return F;
}

static void test_dome(const char *scene, const char *name, double free_small_tol) {
  static const double dts[3] = {0.004, 0.001, 0.00025};
  double cur[3], fr[3];
  for (int i = 0; i < 3; ++i) {
    cur[i] = held(scene, dts[i], PALP_FINGER_LINEARISE_CURRENT);
    fr[i] = held(scene, dts[i], PALP_FINGER_LINEARISE_FREE);
  }
  printf("%s, device 3 mm, held 3 s: linearised at the current positions %.4f / %.4f / %.4f N, at the free "
         "positions (the default) %.4f / %.4f / %.4f N at 4 / 1 / 0.25 ms (4 ms: %+.1f%%)\n",
         name, cur[0], cur[1], cur[2], fr[0], fr[1], fr[2], 100.0 * (fr[0] / cur[0] - 1.0));
  const double lo = fmin(cur[0], fmin(cur[1], cur[2])), hi = fmax(cur[0], fmax(cur[1], cur[2]));
  CHECK(lo > 0.1 && hi <= lo * 1.001, "%s: linearised at the current positions, the held force is the same at every "
        "step within 0.1%% (%.5f..%.5f N)", name, lo, hi);
  CHECK(fabs(fr[2] / cur[2] - 1.0) <= free_small_tol, "%s: the default reading tends to it as the step shrinks: "
        "%.4f against %.4f N at 0.25 ms (within %.0f%%)", name, fr[2], cur[2], 100.0 * free_small_tol);
}

static void test_scene_key(void) {
  palp_scene sc, back;
  char err[256];
  /* the long-term dome's scene has no key (its set was fitted with "free"); the exercises'
   * breast-tissue dome says "current" (refitted with it, 2026-11-29) */
  const char *path = PALP_CONFIG_DIR "/paper_step_long_term.json";
  if (palp_scene_load(path, &sc, err, sizeof err)) {
    CHECK(0, "%s: %s", path, err);
    return;
  }
  CHECK(sc.world.finger_linearise == PALP_FINGER_LINEARISE_FREE, "a scene without the key: \"free\" (%d)",
        sc.world.finger_linearise);
  char *js = palp_scene_to_json(&sc);
  CHECK(js && strstr(js, "\"finger_linearise\"") == NULL, "a \"free\" scene logs no key (earlier logs print as they did)");
  free(js);
  path = PALP_CONFIG_DIR "/phantoms/dome.json";
  if (palp_scene_load(path, &sc, err, sizeof err)) {
    CHECK(0, "%s: %s", path, err);
    return;
  }
  CHECK(sc.world.finger_linearise == PALP_FINGER_LINEARISE_CURRENT, "the exercises' dome says \"current\" (%d)",
        sc.world.finger_linearise);
  js = palp_scene_to_json(&sc);
  CHECK(js && strstr(js, "\"finger_linearise\"") != NULL && strstr(js, "\"current\"") != NULL,
        "the logged scene says \"finger_linearise\": \"current\"");
  CHECK(js && palp_scene_parse(js, &back, err, sizeof err) == 0 &&
            back.world.finger_linearise == PALP_FINGER_LINEARISE_CURRENT,
        "and parses back to it: %s", err);
  if (js) {
    const char *k = strstr(js, "\"current\"");
    if (k) memcpy((char *)k, "\"nearby\" ", 9);
    err[0] = 0;
    CHECK(palp_scene_parse(js, &back, err, sizeof err) != 0 && strstr(err, "finger_linearise") != NULL,
          "a bad value is refused, naming the field (%s)", err);
  }
  free(js);
}

int main(void) {
  test_scene_key();
  test_dome(PALP_CONFIG_DIR "/phantoms/dome.json", "breast tissue", 0.02);
  test_dome(PALP_CONFIG_DIR "/paper_step_long_term.json", "long-term dome", 0.02);
  CHECK_DONE();
}
