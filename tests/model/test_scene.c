/* Scene files: the shipped scene loads; a missing or ill-typed field fails with a
 * message that names the field; the serialised scene rebuilds a bit-identical run. */
#include "common.h"

static const char *base =
    "{\"name\":\"t\",\"mesh\":{\"radius_m\":0.04,\"vertex_count\":120},"
    "\"membrane\":{\"thickness_m\":0.002,\"density_kg_m3\":950,\"E1_Pa\":4.2e6,\"eta1_Pa_s\":2e8,"
    "\"E2_Pa\":8e6,\"eta2_Pa_s\":8e5},"
    "\"gel\":{\"law\":\"polytropic\",\"pressure_Pa\":101325,\"a1\":10,\"a2_Pa_s_m3\":5e6,"
    "\"support_modulus_Pa_m\":1.5e6,\"support_viscosity_Pa_s_m\":6e5},"
    "\"time\":{\"dt_s\":0.01,\"frames\":50},"
    "\"effects\":[\"membrane_elasticity\",\"membrane_viscosity\",\"gel_pressure\",\"gel_damping\","
    "\"gel_support\",\"force_feedback\"],"
    "\"contacts\":[{\"distribution\":\"gaussian\",\"center_deg\":{\"polar\":20,\"azimuth\":10},"
    "\"profile\":{\"kind\":\"step\",\"magnitude_N\":3,\"t_on_s\":0,\"t_off_s\":0.3}}]}";

/* Replaces the first occurrence of `from` in base by `to` and expects a parse error
 * whose message contains `field`. */
static void expect_error(const char *from, const char *to, const char *field) {
  char buf[4096];
  const char *at = strstr(base, from);
  if (!at) {
    CHECK(0, "test setup: \"%s\" not in the base scene", from);
    return;
  }
  snprintf(buf, sizeof buf, "%.*s%s%s", (int)(at - base), base, to, at + strlen(from));
  palp_scene s;
  char err[256] = "";
  const int rc = palp_scene_parse(buf, &s, err, sizeof err);
  CHECK(rc < 0, "\"%s\" -> \"%s\" is rejected", from, to);
  CHECK(strstr(err, field) != NULL, "message names %s: \"%s\"", field, err);
  printf("rejected as expected: %s\n", err);
}

int main(void) {
  palp_scene s;
  char err[256];
  CHECK(palp_scene_parse(base, &s, err, sizeof err) == PALP_OK, "base scene parses: %s", err);
  CHECK(s.world.mesh.vertex_count == 120 && s.frames == 50 && s.contact_count == 1, "fields read");
  CHECK(s.contact[0].def.distribution == PALP_DIST_GAUSSIAN, "distribution read");
  {
    /* The library's defaults are the shipped calibrated parameters: the same decimal
     * strings, so the same doubles. Recalibrating means updating both. */
    const palp_scene paper = paper_scene();
    const palp_world_def d = palp_world_default_def();
    const palp_membrane_params *a = &paper.world.membrane, *b = &d.membrane;
    const palp_gel_params *g = &paper.world.gel, *h = &d.gel;
    CHECK(a->thickness == b->thickness && a->density == b->density && a->E1 == b->E1 && a->eta1 == b->eta1 &&
              a->E2 == b->E2 && a->eta2 == b->eta2,
          "palp_world_default_def's membrane equals config/params/calibrated.json");
    CHECK(g->law == h->law && g->pressure == h->pressure && g->a1 == h->a1 && g->a2 == h->a2 && g->a3 == h->a3 &&
              g->support_modulus == h->support_modulus && g->support_viscosity == h->support_viscosity &&
              g->density == h->density && g->added_mass_fraction == h->added_mass_fraction &&
              g->support_bulk_fraction == h->support_bulk_fraction,
          "palp_world_default_def's gel equals config/params/calibrated.json");
  }
  CHECK_NEAR(s.contact[0].def.center.z, 0.04 * cos(20 * 3.14159265358979323846 / 180), 1e-15, "centre from degrees [m]");

  expect_error("\"mesh\":{", "\"meshes\":{", "mesh");
  expect_error("\"E1_Pa\":4.2e6", "\"E1_Pa\":\"stiff\"", "membrane.E1_Pa");
  expect_error("\"E1_Pa\":4.2e6,", "", "membrane.E1_Pa");
  expect_error("\"eta2_Pa_s\":8e5", "\"eta2_Pa_s\":8e5,\"rim_hinge_release\":1.5", "membrane.rim_hinge_release: must be in [0, 1]");
  expect_error("\"eta2_Pa_s\":8e5", "\"eta2_Pa_s\":8e5,\"rim_hinge_release\":\"pinned\"", "membrane.rim_hinge_release");
  /* the skin's share of the hinges' D: none without bending, never more than D */
  expect_error("\"eta2_Pa_s\":8e5", "\"eta2_Pa_s\":8e5,\"skin_bending_stiffness_N_m\":1e-4",
               "membrane.skin_bending_stiffness_N_m: must be in [0, bending_stiffness_N_m]");
  expect_error("\"eta2_Pa_s\":8e5", "\"eta2_Pa_s\":8e5,\"bending_stiffness_N_m\":1e-3,\"skin_bending_stiffness_N_m\":2e-3",
               "membrane.skin_bending_stiffness_N_m: must be in [0, bending_stiffness_N_m]");
  expect_error("\"vertex_count\":120", "\"vertex_count\":12.5", "mesh.vertex_count");
  expect_error("\"law\":\"polytropic\"", "\"law\":\"ideal\"", "gel.law");
  expect_error("\"dt_s\":0.01", "\"dt_s\":-0.01", "time.dt_s");
  /* Fuzzing (issue 15): 1e-300 made any frame period a "whole multiple" of dt. */
  expect_error("\"dt_s\":0.01", "\"dt_s\":1e-300,\"frame_period_s\":0.01", "time.dt_s: 1e-300 s is below 1e-6 s");
  expect_error("\"dt_s\":0.01", "\"dt_s\":1e-6,\"frame_period_s\":1", "time.frame_period_s: 1000000 steps per frame");
  /* The deferred-rebuild lag a session was stepped with (replay needs it): 0..1000 steps. */
  expect_error("\"dt_s\":0.01", "\"dt_s\":0.01,\"refactor_lag_steps\":-1", "time.refactor_lag_steps");
  expect_error("\"dt_s\":0.01", "\"dt_s\":0.01,\"refactor_lag_steps\":1001", "time.refactor_lag_steps");
  expect_error("\"dt_s\":0.01", "\"dt_s\":0.01,\"refactor_blend_steps\":-1", "time.refactor_blend_steps");
  expect_error("\"dt_s\":0.01", "\"dt_s\":0.01,\"refactor_blend_steps\":1001", "time.refactor_blend_steps");
  /* The fingertip's contact surface (docs/haptics.md): "smooth" or "facets", nothing else. */
  expect_error("\"effects\":[", "\"finger_surface\":\"round\",\"effects\":[", "finger_surface");
  expect_error("\"effects\":[", "\"finger_surface\":1,\"effects\":[", "finger_surface");
  expect_error("\"t_off_s\":0.3", "\"t_of_s\":0.3", "contacts[0].profile.t_off_s");
  expect_error("\"kind\":\"step\"", "\"kind\":5", "contacts[0].profile.kind");
  expect_error("\"distribution\":\"gaussian\"", "\"distribution\":\"round\"", "contacts[0].distribution");
  expect_error("\"gel_support\"", "\"gel_suport\"", "effects[4]");
  expect_error("\"support_viscosity_Pa_s_m\":6e5", "\"support_viscosity_Pa_s_m\":6e5,\"added_mass_fraction\":-1",
               "gel.added_mass_fraction");
  expect_error("\"support_viscosity_Pa_s_m\":6e5", "\"support_viscosity_Pa_s_m\":6e5,\"support_bulk_fraction\":1.5",
               "gel.support_bulk_fraction");
  expect_error("\"effects\":[", "\"effects\":{\"a\":1},\"x\":[", "effects");
  expect_error("{\"name\":\"t\",", "{\"name\":\"t\",,", "invalid JSON");
  expect_error("\"mesh\":{", "\"parameters\":\"/nonexistent/p.json\",\"mesh\":{", "parameters");

  /* The FEM profile the parameters answer to ("material", docs/materials.md): an identifier,
   * from the scene or else its parameter file; none in the base scene. */
  CHECK(s.material[0] == 0, "no material declared: \"%s\"", s.material);
  expect_error("\"mesh\":{", "\"material\":7,\"mesh\":{", "material");
  expect_error("\"mesh\":{", "\"material\":\"\",\"mesh\":{", "material");
  expect_error("\"mesh\":{", "\"material\":\"Long term\",\"mesh\":{", "material");
  expect_error("\"mesh\":{", "\"material\":\"a_very_long_profile_name_of_32_ch\",\"mesh\":{", "material");

  /* The shipped scenes, through their parameter files: each names the profile it was fitted to. */
  palp_scene paper = paper_scene();
  CHECK(paper.world.membrane.E1 > 0 && paper.world.gel.support_modulus > 0, "parameters file applied");
  CHECK(strcmp(paper.material, "paper_instantaneous") == 0, "paper_step.json: material \"%s\"", paper.material);
  {
    static const char *const scene_material[][2] = {{"paper_step_long_term.json", "paper_long_term"},
                                                     {"paper_step_breast_tissue.json", "breast_tissue"}};
    for (int i = 0; i < 2; ++i) {
      char path[512];
      snprintf(path, sizeof path, "%s/%s", PALP_CONFIG_DIR, scene_material[i][0]);
      palp_scene sm;
      CHECK(palp_scene_load(path, &sm, err, sizeof err) == PALP_OK, "%s: %s", path, err);
      CHECK(strcmp(sm.material, scene_material[i][1]) == 0, "%s: material \"%s\", want %s", path, sm.material,
            scene_material[i][1]);
      /* the scene's own "material" wins over its parameter file's, and survives the log's JSON */
      char *mj = palp_scene_to_json(&sm);
      CHECK(mj && strstr(mj, scene_material[i][1]) != NULL, "%s: serialised scene keeps its material", path);
      palp_scene back;
      CHECK(mj && palp_scene_parse(mj, &back, err, sizeof err) == PALP_OK && strcmp(back.material, sm.material) == 0,
            "%s: material round trip: %s", path, err);
      free(mj);
    }
    char buf[4096];
    snprintf(buf, sizeof buf, "{\"material\":\"breast_tissue\",\"parameters\":\"%s/params/paper_long_term.json\",%s",
             PALP_CONFIG_DIR, base + 1);
    palp_scene ov;
    CHECK(palp_scene_parse(buf, &ov, err, sizeof err) == PALP_OK && strcmp(ov.material, "breast_tissue") == 0,
          "the scene's material overrides its parameter file's: \"%s\" %s", ov.material, err);
  }
  CHECK(palp_scene_load("/nonexistent/scene.json", &s, err, sizeof err) == PALP_EIO, "missing file: %s", err);

  /* Serialise, parse back, and run both: identical hashes after 50 frames. */
  palp_scene a;
  palp_scene_parse(base, &a, err, sizeof err);
  char *json = palp_scene_to_json(&a);
  palp_scene b;
  CHECK(json && palp_scene_parse(json, &b, err, sizeof err) == PALP_OK, "round trip parses: %s", err);
  free(json);
  /* Every number round-trips to the same double: cJSON's own printing gave 15 digits for
   * -0.018825206147913998 (a teaching lesion's x), which read back as ...914001, and the
   * replayed world diverged from the session's after 66 frames. */
  {
    palp_scene x = a;
    x.world.lesion_count = 1;
    x.world.lesion[0] = (palp_lesion){.center = {-0.018825206147913998, -0.013181551253121145, 0.01928362829059618},
                                      .radius = 0.005, .stiffness_ratio = 20};
    char *xj = palp_scene_to_json(&x);
    palp_scene xb;
    CHECK(xj && palp_scene_parse(xj, &xb, err, sizeof err) == PALP_OK && xb.world.lesion_count == 1 &&
              xb.world.lesion[0].center.x == x.world.lesion[0].center.x &&
              xb.world.lesion[0].center.y == x.world.lesion[0].center.y &&
              xb.world.lesion[0].center.z == x.world.lesion[0].center.z,
          "lesion centre round-trips bit for bit: %.17g -> %.17g (%s)", x.world.lesion[0].center.x,
          xj ? xb.world.lesion[0].center.x : 0.0, err);
    free(xj);
  }
  /* The finger surface: absent is the facets (how every scene and log before it was stepped),
   * and it survives the round trip; the facets print as earlier logs did (no key). */
  {
    CHECK(a.world.finger_surface == PALP_FINGER_SURFACE_FACETS, "no \"finger_surface\": the facets (%d)",
          a.world.finger_surface);
    char *fj = palp_scene_to_json(&a);
    CHECK(fj && !strstr(fj, "finger_surface"), "the facets are written as no key");
    free(fj);
    palp_scene sm = a;
    sm.world.finger_surface = PALP_FINGER_SURFACE_SMOOTH;
    char *sj = palp_scene_to_json(&sm);
    palp_scene sb;
    CHECK(sj && palp_scene_parse(sj, &sb, err, sizeof err) == PALP_OK &&
              sb.world.finger_surface == PALP_FINGER_SURFACE_SMOOTH,
          "finger_surface \"smooth\" round trip (%s)", err);
    free(sj);
    const palp_scene shipped = paper_scene();
    CHECK(shipped.world.finger_surface == PALP_FINGER_SURFACE_SMOOTH, "the shipped scene asks for the smooth surface");
  }
  /* The rebuild lag and blend survive the round trip (a server's logged scene carries them
   * to replay); a scene without them (every log before them) reads 0. */
  palp_scene lagged = a;
  lagged.world.refactor_lag = 4;
  lagged.world.refactor_blend = 2;
  char *lj = palp_scene_to_json(&lagged);
  palp_scene lb;
  CHECK(lj && palp_scene_parse(lj, &lb, err, sizeof err) == PALP_OK && lb.world.refactor_lag == 4 &&
            lb.world.refactor_blend == 2,
        "refactor_lag_steps / refactor_blend_steps round trip: %d / %d (expected 4 / 2)", lj ? lb.world.refactor_lag : -1,
        lj ? lb.world.refactor_blend : -1);
  free(lj);
  CHECK(a.world.refactor_blend == 0, "a scene without time.refactor_blend_steps blends nothing (%d)", a.world.refactor_blend);
  int e;
  palp_world *wa = palp_scene_create_world(&a, &e), *wb = palp_scene_create_world(&b, &e);
  for (int f = 0; f < a.frames; ++f) {
    palp_scene_apply(&a, wa, palp_world_time(wa));
    palp_scene_apply(&b, wb, palp_world_time(wb));
    palp_world_step(wa);
    palp_world_step(wb);
  }
  CHECK(palp_world_hash(wa) == palp_world_hash(wb), "serialised scene reproduces the run bit for bit");
  palp_world_destroy(wa), palp_world_destroy(wb);
  CHECK_DONE();
}
