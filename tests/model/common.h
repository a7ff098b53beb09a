/* common.h - scene helpers shared by the model tests. */
#ifndef PALP_TEST_COMMON_H
#define PALP_TEST_COMMON_H
#include <string.h>

#include "check.h"
#include "palp.h"

/* The shipped paper experiment (config/paper_step.json with its parameter file). */
static inline palp_scene paper_scene(void) {
  palp_scene s;
  char err[256];
  if (palp_scene_load(PALP_CONFIG_DIR "/paper_step.json", &s, err, sizeof err)) {
    fprintf(stderr, "cannot load the paper scene: %s\n", err);
    exit(2);
  }
  return s;
}

/* The library's defaults with the hand-set parameters of config/params/handset.json:
 * a phantom ~20x stiffer than the calibrated default, on which each effect is visible
 * at the paper's load and 30 N stays well inside the dome. */
static inline palp_world_def handset_def(void) {
  palp_scene s;
  char err[256];
  const char *json = "{\"name\": \"handset\", \"mesh\": {\"radius_m\": 0.04, \"vertex_count\": 338},"
                     " \"parameters\": \"" PALP_CONFIG_DIR "/params/handset.json\","
                     " \"time\": {\"dt_s\": 0.01, \"frames\": 1}, \"effects\": [], \"contacts\": []}";
  if (palp_scene_parse_in(json, NULL, &s, err, sizeof err)) { /* trusted text naming a parameter file */
    fprintf(stderr, "cannot load the hand-set parameters: %s\n", err);
    exit(2);
  }
  palp_world_def d = palp_world_default_def();
  d.membrane = s.world.membrane;
  d.gel = s.world.gel;
  return d;
}

/* A small scene whose gel line ends in %s, for the support's optional fields (printf
 * format: the caller adds ",\"field\":value" pairs, or ""). */
#define SUPPORT_SCENE_FMT                                                                                           \
  "{\"name\":\"r\",\"mesh\":{\"radius_m\":0.04,\"vertex_count\":120},"                                          \
  "\"membrane\":{\"thickness_m\":0.002,\"density_kg_m3\":950,\"E1_Pa\":4.2e6,\"eta1_Pa_s\":2e8,"                     \
  "\"E2_Pa\":8e6,\"eta2_Pa_s\":8e5},"                                                                                 \
  "\"gel\":{\"law\":\"polytropic\",\"pressure_Pa\":101325,\"a1\":10,\"a2_Pa_s_m3\":5e6,"                           \
  "\"support_modulus_Pa_m\":1.5e6,\"support_viscosity_Pa_s_m\":6e5%s},"                                             \
  "\"time\":{\"dt_s\":0.01,\"frames\":5},\"effects\":[\"gel_support\"],\"contacts\":[]}"

static inline double vdist(palp_vec3 a, palp_vec3 b) {
  return sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
}
static inline palp_vec3 v3_scaled(palp_vec3 a, double s) { return (palp_vec3){a.x * s, a.y * s, a.z * s}; }
/* 1 when the world's pipeline runs the stage of that name (palp_world_timings). */
static inline int has_stage(const palp_world *w, const char *name) {
  palp_stage_timings t;
  palp_world_timings(w, &t);
  for (int i = 0; i < PALP_STAGE_COUNT; ++i)
    if (t.name[i] && strcmp(t.name[i], name) == 0) return 1;
  return 0;
}
#endif
