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

static inline double vdist(palp_vec3 a, palp_vec3 b) {
  return sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
}
static inline palp_vec3 v3_scaled(palp_vec3 a, double s) { return (palp_vec3){a.x * s, a.y * s, a.z * s}; }
#endif
