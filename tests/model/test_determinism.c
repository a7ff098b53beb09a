/* Bit-identical results: two worlds built from the same scene and driven the same
 * way reach the same state hash after every frame, also when stepped interleaved
 * (no hidden shared state), both the logged one (palp_world_hash) and the whole
 * state's (palp_world_state_hash); a change of the load in the 9th digit changes both. */
#include "common.h"

int main(void) {
  palp_scene s = paper_scene();
  s.contact[0].def.distribution = PALP_DIST_GAUSSIAN_OFFSET;
  int e;
  palp_world *a = palp_scene_create_world(&s, &e), *b = palp_scene_create_world(&s, &e);
  palp_scene s2 = s;
  s2.contact[0].profile.magnitude = 3.0 * (1.0 + 1e-9);
  palp_world *c = palp_scene_create_world(&s2, &e);
  CHECK(a && b && c, "worlds created");
  CHECK(palp_world_hash(a) == palp_world_hash(b), "equal at creation");
  CHECK(palp_world_state_hash(a) == palp_world_state_hash(b), "whole states equal at creation");
  /* A finger in both, so both contact paths run. */
  const int fa = palp_world_add_finger(a, (palp_vec3){0.0, -0.02, 0.04}, 0.008);
  const int fb = palp_world_add_finger(b, (palp_vec3){0.0, -0.02, 0.04}, 0.008);
  palp_world_add_finger(c, (palp_vec3){0.0, -0.02, 0.04}, 0.008);
  int same = 1, same_state = 1;
  uint64_t h_end = 0;
  for (int f = 0; f < 400; ++f) {
    const palp_vec3 tip = {0.0, -0.02, 0.04 - 0.004 * sin(0.01 * f)};
    palp_world_set_finger(a, fa, tip, 0.008);
    palp_world_set_finger(b, fb, tip, 0.008);
    palp_world_set_finger(c, fa, tip, 0.008);
    palp_scene_apply(&s, a, palp_world_time(a));
    palp_scene_apply(&s, b, palp_world_time(b));
    palp_scene_apply(&s2, c, palp_world_time(c));
    CHECK(palp_world_step(a) == PALP_OK && palp_world_step(b) == PALP_OK && palp_world_step(c) == PALP_OK,
          "step %d", f);
    if (palp_world_hash(a) != palp_world_hash(b)) same = 0;
    if (palp_world_state_hash(a) != palp_world_state_hash(b)) same_state = 0;
    h_end = palp_world_hash(a);
  }
  CHECK(same, "identical hashes after every one of 400 frames");
  CHECK(same_state, "identical whole-state hashes after every one of 400 frames");
  CHECK(palp_world_hash(c) != h_end, "a 1e-9 relative change of the load changes the hash");
  CHECK(palp_world_state_hash(c) != palp_world_state_hash(a), "and the whole state's");
  /* A third run after the others (allocator state differs) still agrees. */
  palp_world *d = palp_scene_create_world(&s, &e);
  const int fd = palp_world_add_finger(d, (palp_vec3){0.0, -0.02, 0.04}, 0.008);
  for (int f = 0; f < 400; ++f) {
    palp_world_set_finger(d, fd, (palp_vec3){0.0, -0.02, 0.04 - 0.004 * sin(0.01 * f)}, 0.008);
    palp_scene_apply(&s, d, palp_world_time(d));
    palp_world_step(d);
  }
  CHECK(palp_world_hash(d) == h_end, "a later run reproduces the final hash %016llx", (unsigned long long)h_end);
  CHECK(palp_world_state_hash(d) == palp_world_state_hash(a), "and the whole state's");
  printf("final state hash %016llx\n", (unsigned long long)h_end);
  palp_world_destroy(a), palp_world_destroy(b), palp_world_destroy(c), palp_world_destroy(d);
  CHECK_DONE();
}
