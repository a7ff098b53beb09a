/*
 * test_eval_calibrate - the calibration recovers parameters it did not see.
 *
 * Synthetic problem: "reference" records come from the real-time model itself
 * run with known parameters p* (the hand-set defaults) under the four
 * distributions. The fit starts from p* perturbed by factors between 0.8 and 1.25
 * and must return the well-determined parameters (support stiffness and
 * damping, the membrane's static modulus) within 2% and the weakly determined
 * split of the membrane's springs within 25% (reasons at the check), and cut
 * the displacement RMSE by at least a factor of 50 in every distribution.
 * Also: the parameter file written by palp_eval_params_write loads back
 * through palp_scene_load with every value equal to 9 significant digits.
 *
 * finger: fingertip force-depth references enter the fit. The displacement
 * references come from support modulus k, the finger's (pole, 1 and 2 mm) from a
 * model with 2k; fitting k alone from 1.4k, the fit lands within 3% of k without
 * the finger residuals and within 3% of 2k with them at weight 10 cm (a 10% force
 * error costs 1 cm RMS of displacement, far above the fields' residuals), where
 * the finger's RMS relative force error is below 0.02 (from above 0.1 at the start).
 *
 * peak: the peak residual moves a fit that cannot follow the reference's shape onto
 * its peak. The reference (uniform distribution, II) comes from a model with a softer
 * support under a stiffer membrane (k 0.5x, E1 and E2 2x: another dent shape); the fit
 * may move the support modulus k only. Fields alone settle k where the whole record
 * fits best, leaving the largest displacement (peak) off by more than 5%; with peak
 * weight 3 the peak error falls to a third of that or less and below 2%, while the
 * RMSE rises but stays within 3x (the peak is bought with the rest of the record;
 * measured: peak -17.4% -> -0.03%, RMSE 0.14 -> 0.27 mm).
 *
 * deep_press: the check calibrate runs on what it fitted (palp_eval_deep_press). The
 * shipped breast-tissue set keeps the fingertip pressed to 34 mm at the pole (~16 N);
 * the refit of 2026-11-27 that was withdrawn (its values below: a Kelvin spring at 0.08%
 * of E1, 0.4% added mass) loses it on the way (at 28 mm), its links strained to 3.2 (the
 * shipped set: to 1.15 at 34 mm, already beyond the linear Burgers law's range, which the
 * station is told). Bounds: kept, above 8 N (15.9), strain below 1.5; lost, strain above 2.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>

#include "eval.h"
#include "../tmpdir.h"

static int failures = 0;
#define CHECK(cond, ...)                                                                                               \
  do {                                                                                                                 \
    if (!(cond)) {                                                                                                     \
      ++failures;                                                                                                      \
      fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);                                                             \
      fprintf(stderr, __VA_ARGS__);                                                                                    \
      fprintf(stderr, "\n");                                                                                           \
    }                                                                                                                  \
  } while (0)

/* A small phantom (150 vertices) and 2.6 s (2 s hold, 0.6 s of recovery) keep
 * each model run near 10 ms; the physics is the paper's scene. */
static const char *scene_json =
    "{ \"name\": \"calib_synthetic\", \"mesh\": {\"radius_m\": 0.04, \"vertex_count\": 150},"
    "  \"membrane\": {\"thickness_m\": 0.002, \"density_kg_m3\": 950, \"E1_Pa\": 4.2e6, \"eta1_Pa_s\": 2e8,"
    "                 \"E2_Pa\": 8e6, \"eta2_Pa_s\": 8e5},"
    "  \"gel\": {\"law\": \"polytropic\", \"pressure_Pa\": 101325, \"a1\": 10, \"a2_Pa_s_m3\": 5e6, \"a3_s2\": 0,"
    "            \"support_modulus_Pa_m\": 1.5e6, \"support_viscosity_Pa_s_m\": 6e5, \"added_mass_fraction\": 0},"
    "  \"time\": {\"dt_s\": 0.01, \"frames\": 260, \"frame_period_s\": 0.01},"
    "  \"effects\": [\"membrane_elasticity\", \"membrane_viscosity\", \"gel_pressure\", \"gel_damping\","
    "              \"gel_support\", \"force_feedback\"],"
    "  \"contacts\": [{\"distribution\": \"uniform\", \"center_deg\": {\"polar\": 30, \"azimuth\": 40},"
    "                 \"patch_area_m2\": 5.2e-4,"
    "                 \"profile\": {\"kind\": \"step\", \"magnitude_N\": 3, \"t_on_s\": 0, \"t_off_s\": 2}}] }";

/* The synthetic phantom and its four "reference" runs (one per distribution);
 * returns 0, or -1 after a failed check. */
static int synthetic_refs(palp_scene *base, palp_scene scenes[4], palp_eval_record refs[4]) {
  char err[512] = "";
  int rc = palp_scene_parse(scene_json, base, err, sizeof err);
  CHECK(rc == 0, "scene parse: %s", err);
  for (int d = 0; !rc && d < 4; ++d) {
    scenes[d] = *base;
    scenes[d].contact[0].def.distribution = (palp_distribution)(d + 1);
    rc = palp_eval_run_rt(&scenes[d], &refs[d], err, sizeof err);
    CHECK(rc == 0, "reference run %d: %s", d + 1, err);
  }
  return rc ? -1 : 0;
}

static void test_recovers_parameters(void) {
  palp_scene base;
  char err[512] = "";
  palp_scene scenes[4];
  palp_eval_record refs[4];
  if (synthetic_refs(&base, scenes, refs)) return;
  int rc;
  double truth[PALP_EVAL_P_COUNT];
  palp_eval_params_get(&base.world, truth);
  /* Perturbed start; the fitted set is the parameters the displacement data
   * determine (stiffnesses and the recovery's viscosities). eta1 (flow of 1.4%
   * over 2 s), a1 and a2 (the gel is nearly incompressible either way) stay at
   * the truth, as the prior would keep them in a real calibration. */
  const double factor[PALP_EVAL_P_COUNT] = {1.2, 1.0, 0.8, 1.25, 1.0, 1.0, 0.8, 1.2, 1.0, 1.0};
  const unsigned mask = (1u << PALP_EVAL_P_E1) | (1u << PALP_EVAL_P_E2) | (1u << PALP_EVAL_P_ETA2) |
                        (1u << PALP_EVAL_P_SUPPORT_K) | (1u << PALP_EVAL_P_SUPPORT_C);
  double start[PALP_EVAL_P_COUNT];
  for (int j = 0; j < PALP_EVAL_P_COUNT; ++j) start[j] = truth[j] * factor[j];
  for (int d = 0; d < 4; ++d) palp_eval_params_set(&scenes[d].world, start);
  palp_eval_calib_def def = palp_eval_calib_default_def();
  def.mask = mask;
  def.prior_weight = 0.0; /* no pull towards the (wrong) start */
  def.frame_stride = 2;
  def.max_iter = 30;
  def.verbose = getenv("PALP_TEST_VERBOSE") != NULL;
  palp_eval_calib_result res;
  rc = palp_eval_calibrate(scenes, refs, 4, &def, &res, err, sizeof err);
  CHECK(rc == 0, "calibrate: %s", err);
  if (rc == 0) {
    /* Well determined by the data: the support (stiffness and damping of every
     * vertex) and the membrane's static modulus, Maxwell and Kelvin springs in
     * series, E1 E2 / (E1 + E2): within 2%. The split between E1 and E2 and the
     * Kelvin time eta2 / E2 only shape the first ~0.1 s after each step, a few
     * frames, and the model is piecewise smooth in its parameters (lagged-tangent
     * rebuilds and Sherman-Morrison refreshes are discrete), so the fit ends
     * where no step lowers the cost: measured 5-14% off on each, with the series
     * modulus within 0.4%. Those three are held to 25%. */
    const double tol[PALP_EVAL_P_COUNT] = {0.25, 0, 0.25, 0.25, 0, 0, 0.02, 0.02};
    for (int j = 0; j < PALP_EVAL_P_COUNT; ++j) {
      const double rel = fabs(res.fitted[j] / truth[j] - 1.0);
      if (mask & (1u << j))
        CHECK(rel < tol[j], "%s: fitted %.6g, truth %.6g (start %.6g): relative error %.3g > %g",
              palp_eval_param_name[j], res.fitted[j], truth[j], start[j], rel, tol[j]);
      else
        CHECK(res.fitted[j] == start[j], "%s was not fitted but changed: %.9g -> %.9g", palp_eval_param_name[j],
              start[j], res.fitted[j]);
    }
    const double e1 = res.fitted[PALP_EVAL_P_E1], e2 = res.fitted[PALP_EVAL_P_E2];
    const double es = e1 * e2 / (e1 + e2), es_true = truth[PALP_EVAL_P_E1] * truth[PALP_EVAL_P_E2] /
                                                       (truth[PALP_EVAL_P_E1] + truth[PALP_EVAL_P_E2]);
    CHECK(fabs(es / es_true - 1.0) < 0.02, "static membrane modulus E1 E2/(E1 + E2): fitted %.6g, truth %.6g (> 2%%)",
          es, es_true);
    for (int d = 0; d < 4; ++d)
      CHECK(res.rmse_after[d] < 0.02 * res.rmse_before[d],
            "distribution %d: RMSE %.3g m -> %.3g m, not cut by 50x", d + 1, res.rmse_before[d], res.rmse_after[d]);
    CHECK(res.cost_after < res.cost_before, "cost did not fall: %.6g -> %.6g", res.cost_before, res.cost_after);
    printf("calibrate synthetic: %d iterations, %d evaluations, %.1f s; RMSE I %.3g -> %.3g m\n", res.iterations,
           res.evaluations, res.seconds, res.rmse_before[0], res.rmse_after[0]);
  }
  for (int d = 0; d < 4; ++d) palp_eval_record_destroy(&refs[d]);
}

static void test_finger_residuals(void) {
  palp_scene base;
  char err[512] = "";
  palp_scene scenes[4];
  palp_eval_record refs[4];
  if (synthetic_refs(&base, scenes, refs)) return;
  int rc;
  const double k = base.world.gel.support_modulus;
  palp_eval_finger_ref f;
  memset(&f, 0, sizeof f);
  f.name = "pole";
  f.n = (palp_vec3){0, 0, 1};
  f.radius = 0.008;
  f.count = 2;
  f.depth[0] = 1e-3, f.depth[1] = 2e-3;
  palp_world_def stiff = base.world;
  stiff.gel.support_modulus = 2.0 * k;
  double dreal[2];
  rc = palp_eval_finger_rt(&stiff, NULL, 0, f.n, f.radius, f.depth, f.count, 0.3, f.force, dreal, err, sizeof err);
  CHECK(rc == 2 && f.force[0] > 0 && f.force[1] > f.force[0], "finger reference: rc %d, %.4g / %.4g N: %s", rc,
        f.force[0], f.force[1], err);
  CHECK(fabs(dreal[0] - 1e-3) < 5e-5 && fabs(dreal[1] - 2e-3) < 5e-5,
        "the proxy ends at %.4f / %.4f mm, not within 0.05 mm of 1 / 2 mm", 1e3 * dreal[0], 1e3 * dreal[1]);
  if (rc != 2) return;
  for (int with = 0; with < 2; ++with) {
    for (int d = 0; d < 4; ++d) scenes[d].world.gel.support_modulus = 1.4 * k;
    palp_eval_calib_def def = palp_eval_calib_default_def();
    def.mask = 1u << PALP_EVAL_P_SUPPORT_K;
    def.prior_weight = 0.0;
    def.frame_stride = 4;
    def.max_iter = 30;
    def.finger = &f;
    def.finger_count = 1;
    def.finger_weight = with ? 10.0 : 0.0;
    def.verbose = getenv("PALP_TEST_VERBOSE") != NULL;
    palp_eval_calib_result res;
    rc = palp_eval_calibrate(scenes, refs, 4, &def, &res, err, sizeof err);
    CHECK(rc == 0, "calibrate (finger weight %g): %s", def.finger_weight, err);
    if (rc) break;
    const double fitted = res.fitted[PALP_EVAL_P_SUPPORT_K], want = with ? 2.0 * k : k;
    printf("finger weight %4.1f: support modulus %.6g Pa/m (fields' %.6g, finger's %.6g), finger RMS relative error "
           "%.4f -> %.4f\n",
           def.finger_weight, fitted, k, 2.0 * k, res.finger_rms_before, res.finger_rms_after);
    CHECK(fabs(fitted / want - 1.0) < 0.03, "finger weight %g: support modulus %.6g, expected %.6g within 3%%",
          def.finger_weight, fitted, want);
    if (with) {
      CHECK(res.finger_rms_before > 0.1 && res.finger_rms_after < 0.02,
            "finger RMS relative error %.4f -> %.4f (expected > 0.1 -> < 0.02)", res.finger_rms_before,
            res.finger_rms_after);
    } else {
      CHECK(isnan(res.finger_rms_before) && isnan(res.finger_rms_after), "finger RMS reported without the finger");
    }
  }
  for (int d = 0; d < 4; ++d) palp_eval_record_destroy(&refs[d]);
}

static void test_peak_residual(void) {
  palp_scene base;
  char err[512] = "";
  palp_eval_record ref;
  int rc = palp_scene_parse(scene_json, &base, err, sizeof err);
  CHECK(rc == 0, "scene parse: %s", err);
  if (rc) return;
  base.contact[0].def.distribution = PALP_DIST_UNIFORM;
  palp_scene other = base;
  other.world.gel.support_modulus *= 0.5;
  other.world.membrane.E1 *= 2.0;
  other.world.membrane.E2 *= 2.0;
  rc = palp_eval_run_rt(&other, &ref, err, sizeof err);
  CHECK(rc == 0, "reference run: %s", err);
  if (rc) return;
  double e[2] = {0, 0}, rmse[2] = {0, 0};
  for (int with = 0; with < 2; ++with) {
    palp_eval_calib_def def = palp_eval_calib_default_def();
    def.mask = 1u << PALP_EVAL_P_SUPPORT_K;
    def.prior_weight = 0.0;
    def.frame_stride = 4;
    def.max_iter = 30;
    def.peak_weight = with ? 3.0 : 0.0;
    def.verbose = getenv("PALP_TEST_VERBOSE") != NULL;
    palp_eval_calib_result res;
    rc = palp_eval_calibrate(&base, &ref, 1, &def, &res, err, sizeof err);
    CHECK(rc == 0, "calibrate (peak weight %g): %s", def.peak_weight, err);
    if (rc) break;
    CHECK(res.peak_ref[0] > 0 && res.peak_after[0] > 0, "peaks %.4g / %.4g m", res.peak_ref[0], res.peak_after[0]);
    e[with] = res.peak_after[0] / res.peak_ref[0] - 1.0;
    rmse[with] = res.rmse_after[0];
    printf("peak weight %g: support modulus %.6g Pa/m (reference model %.6g); peak %.4f mm against %.4f mm (%+.2f%%), "
           "RMSE %.4f mm\n",
           def.peak_weight, res.fitted[PALP_EVAL_P_SUPPORT_K], other.world.gel.support_modulus,
           1e3 * res.peak_after[0], 1e3 * res.peak_ref[0], 100 * e[with], 1e3 * res.rmse_after[0]);
  }
  CHECK(fabs(e[0]) > 0.05, "the mismatch should leave the fields-only fit's peak off by > 5%% (got %+.4f)", e[0]);
  CHECK(fabs(e[1]) <= fabs(e[0]) / 3.0 && fabs(e[1]) < 0.02,
        "peak error with the peak residual %+.4f (fields only %+.4f): want <= 1/3 of it and < 2%%", e[1], e[0]);
  CHECK(rmse[1] > rmse[0] && rmse[1] <= 3.0 * rmse[0],
        "RMSE %.4g -> %.4g mm: the peak should cost some of the rest of the record (a trade), not more than 3x",
        1e3 * rmse[0], 1e3 * rmse[1]);
  palp_eval_record_destroy(&ref);
}

static void test_param_file_roundtrip(void) {
  palp_scene s;
  char err[512] = "";
  int rc = palp_scene_parse(scene_json, &s, err, sizeof err);
  CHECK(rc == 0, "scene parse: %s", err);
  if (rc) return;
  /* Values with 9 significant digits that no default has. */
  const double p[PALP_EVAL_P_COUNT] = {3.14159265e6, 1.23456789e8, 7.65432101e6, 9.87654321e5,
                                       11.1111111,   4.44444444e6, 1.71828183e6, 5.55555556e5, 0.314159265,
                                       0.271828183,  2.71828183e-3, 8.31446262e5, 0.577215665};
  palp_eval_params_set(&s.world, p);
  s.world.gel.support_stiffening = 4.25, s.world.gel.support_stiffening_power = 2.5; /* carried over, not fitted */
  s.world.membrane.skin_bending_stiffness = 1.25e-3; /* carried over too (below the fitted D 2.72e-3) */
  char dir[160];
  palp_test_tmp(dir, sizeof dir, "palp_eval_paramsXXXXXX");
  CHECK(mkdtemp(dir) != NULL, "mkdtemp");
  char ppath[256], spath[256];
  snprintf(ppath, sizeof ppath, "%s/fitted.json", dir);
  snprintf(spath, sizeof spath, "%s/scene.json", dir);
  rc = palp_eval_params_write(ppath, &s.world, "breast_tissue", "test \"quoted\" comment", err, sizeof err);
  CHECK(rc == 0, "params write: %s", err);
  FILE *f = fopen(spath, "w");
  CHECK(f != NULL, "cannot write %s", spath);
  if (!f) return;
  fprintf(f, "{\"name\": \"rt\", \"mesh\": {\"radius_m\": 0.04, \"vertex_count\": 150}, \"parameters\": \"fitted.json\","
             " \"time\": {\"dt_s\": 0.01, \"frames\": 10, \"frame_period_s\": 0.01},"
             " \"effects\": [\"membrane_elasticity\"], \"contacts\": []}\n");
  fclose(f);
  palp_scene back;
  rc = palp_scene_load(spath, &back, err, sizeof err);
  CHECK(rc == 0, "scene with the written parameters does not load: %s", err);
  if (!rc) {
    double q[PALP_EVAL_P_COUNT];
    palp_eval_params_get(&back.world, q);
    for (int j = 0; j < PALP_EVAL_P_COUNT; ++j)
      CHECK(fabs(q[j] / p[j] - 1.0) < 1e-9, "%s: wrote %.9g, read %.9g", palp_eval_param_name[j], p[j], q[j]);
    CHECK(strcmp(back.material, "breast_tissue") == 0, "material: wrote breast_tissue, read \"%s\"", back.material);
    CHECK(back.world.membrane.thickness == 0.002 && back.world.membrane.density == 950.0 &&
              back.world.gel.pressure == 101325.0 && back.world.gel.law == PALP_GEL_POLYTROPIC,
          "fixed parameters not carried over");
    CHECK(back.world.gel.support_stiffening == 4.25 && back.world.gel.support_stiffening_power == 2.5,
          "the stiffening support not carried over: %g, %g", back.world.gel.support_stiffening,
          back.world.gel.support_stiffening_power);
    CHECK(back.world.membrane.skin_bending_stiffness == 1.25e-3, "the skin's share of D not carried over: %g",
          back.world.membrane.skin_bending_stiffness);
  }
  remove(ppath);
  remove(spath);
  rmdir(dir);
}

static void test_bad_mask(void) {
  unsigned m = 0;
  char err[256] = "";
  CHECK(palp_eval_params_parse_mask("E1,nope", &m, err, sizeof err) == PALP_EINVAL && strstr(err, "nope"),
        "unknown parameter name not rejected by name: \"%s\"", err);
  CHECK(palp_eval_params_parse_mask("E1,support_viscosity", &m, err, sizeof err) == 0 &&
            m == ((1u << PALP_EVAL_P_E1) | (1u << PALP_EVAL_P_SUPPORT_C)),
        "mask of E1,support_viscosity is %#x", m);
}

static void test_deep_press(void) {
  palp_scene sc;
  char err[512];
  if (palp_scene_load(PALP_CONFIG_DIR "/paper_step_breast_tissue.json", &sc, err, sizeof err)) {
    CHECK(0, "breast-tissue scene: %s", err);
    return;
  }
  const palp_vec3 pole = {0, 0, 1};
  double F = 0, strain = 0;
  const double kept = palp_eval_deep_press(&sc.world, pole, 0.034, &F, &strain, err, sizeof err);
  printf("deep press, shipped breast tissue: lost at %.0f mm (0: kept), %.2f N at the end, largest strain %.2f\n",
         1e3 * kept, F, strain);
  CHECK(kept == 0.0, "the shipped breast-tissue set keeps the fingertip to 34 mm (lost at %.0f mm)", 1e3 * kept);
  CHECK(F > 8.0, "it pushes back with more than 8 N at 34 mm (%.2f N)", F);
  CHECK(strain < 1.5, "its links strain by less than 150%% (%.2f)", strain);
  palp_world_def wd = sc.world; /* the withdrawn refit of 2026-11-27 */
  wd.membrane.E1 = 509346.028, wd.membrane.eta1 = 1.4012004e9, wd.membrane.E2 = 424.049785;
  wd.membrane.eta2 = 112231.22, wd.membrane.bending_stiffness = 0.00124996902;
  wd.gel.a2 = 7041700.6, wd.gel.support_modulus = 1452136.32, wd.gel.support_viscosity = 48.5276642;
  wd.gel.support_bulk_fraction = 0.86592857, wd.gel.support_relax_modulus = 187834.369;
  wd.gel.support_relax_time = 1.09727561, wd.gel.added_mass_fraction = 0.00401460967;
  wd.gel.support_stiffening = 0.0; /* a linear support, as the refit had (the stiffening holds even it, docs/model.md) */
  /* stepped as it was when withdrawn: its fingertip linearised at the free positions (with the
   * contact at the current positions, 2026-11-29, the same set keeps the fingertip to 34 mm,
   * largest strain 1.60: the check needs a set that loses it) */
  wd.finger_linearise = PALP_FINGER_LINEARISE_FREE;
  const double lost = palp_eval_deep_press(&wd, pole, 0.034, &F, &strain, err, sizeof err);
  printf("deep press, withdrawn refit: lost at %.0f mm, largest strain %.2f\n", 1e3 * lost, strain);
  CHECK(lost > 0.0, "the withdrawn refit loses the fingertip in the press (%.0f mm)", 1e3 * lost);
  CHECK(strain > 2.0, "and strains its links beyond 200%% (%.2f)", strain);
}

/* The fingertip curve's step (palp_eval_finger_rt_step): a scene whose contact is linearised
 * at the current positions is driven at 4 ms, and its curve there is the one at 1 ms within
 * 0.1% (the held force's step independence, model_finger_step's 0.1% at one depth, here over
 * the curve's ramps, holds and corrections); a "free" scene stays at 1 ms, where its sets were
 * fitted (its held force 45 deg off the pole at 3 mm falls 3.4% from 1 to 4 ms). */
static void test_finger_step(void) {
  palp_scene sc;
  char err[512] = "";
  if (palp_scene_load(PALP_CONFIG_DIR "/phantoms/dome.json", &sc, err, sizeof err)) {
    CHECK(0, "exercise dome: %s", err);
    return;
  }
  CHECK(sc.world.finger_linearise == PALP_FINGER_LINEARISE_CURRENT, "the exercise dome's contact is not \"current\"");
  CHECK(palp_eval_finger_rt_step(&sc.world) == 0.004, "its fingertip step %g s, not 4 ms",
        palp_eval_finger_rt_step(&sc.world));
  palp_world_def fr = sc.world;
  fr.finger_linearise = PALP_FINGER_LINEARISE_FREE;
  CHECK(palp_eval_finger_rt_step(&fr) == 0.001, "a free scene's fingertip step %g s, not 1 ms",
        palp_eval_finger_rt_step(&fr));
  const double th = 45.0 * 3.14159265358979323846 / 180.0;
  const palp_vec3 n = {sin(th), 0, cos(th)};
  const double depth[3] = {1e-3, 3e-3, 6e-3};
  double F4[3], F1[3], D4[3], D1[3];
  const int r4 = palp_eval_finger_rt(&sc.world, NULL, 0, n, 0.008, depth, 3, 1.0, F4, D4, err, sizeof err);
  CHECK(r4 == 3, "the curve at 4 ms: %s", err);
  const int r1 = palp_eval_finger_rt_at(&sc.world, 0.001, NULL, 0, n, 0.008, depth, 3, 1.0, F1, D1, err, sizeof err);
  CHECK(r1 == 3, "the curve at 1 ms: %s", err);
  if (r4 != 3 || r1 != 3) return;
  for (int k = 0; k < 3; ++k) {
    printf("exercise dome, 45 deg, %.0f mm: %.4f N at 4 ms, %.4f N at 1 ms (%+.3f%%)\n", 1e3 * depth[k], F4[k], F1[k],
           100.0 * (F4[k] / F1[k] - 1.0));
    CHECK(F1[k] > 0.0 && fabs(F4[k] / F1[k] - 1.0) < 1e-3, "%.0f mm: %.4f N at 4 ms against %.4f N at 1 ms (want 0.1%%)",
          1e3 * depth[k], F4[k], F1[k]);
    CHECK(fabs(D4[k] - depth[k]) < 5e-6 && fabs(D1[k] - depth[k]) < 5e-6, "%.0f mm: the proxy at %.4f / %.4f mm",
          1e3 * depth[k], 1e3 * D4[k], 1e3 * D1[k]);
  }
  err[0] = 0;
  CHECK(palp_eval_finger_rt_at(&sc.world, 0.0, NULL, 0, n, 0.008, depth, 1, 1.0, F4, D4, err, sizeof err) == -1 &&
            strstr(err, "step"),
        "a zero step is refused with a reason (\"%s\")", err);
}

int main(int argc, char **argv) {
  gsl_set_error_handler_off();
  const char *only = argc > 1 ? argv[1] : "all";
  if (!strcmp(only, "all") || !strcmp(only, "recover")) test_recovers_parameters();
  if (!strcmp(only, "all") || !strcmp(only, "params")) test_param_file_roundtrip();
  if (!strcmp(only, "all") || !strcmp(only, "mask")) test_bad_mask();
  if (!strcmp(only, "all") || !strcmp(only, "finger")) test_finger_residuals();
  if (!strcmp(only, "all") || !strcmp(only, "peak")) test_peak_residual();
  if (!strcmp(only, "all") || !strcmp(only, "deep_press")) test_deep_press();
  if (!strcmp(only, "all") || !strcmp(only, "finger_step")) test_finger_step();
  if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
  else printf("ok\n");
  return failures ? 1 : 0;
}
