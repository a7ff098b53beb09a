/* Health counters and stage timings per frame (session 81 review): a step the world splits
 * into halves is still one step for the counters the server log and the replay summary
 * print, and for the timings a benchmark divides by. */
#include "common.h"

/* Largest |engineering strain| of any link [-], from the positions alone (rest lengths from
 * the mesh's rest positions): the test's own measure, not the world's. */
static double end_strain(const palp_world *w) {
  const palp_mesh *m = palp_world_mesh(w);
  const palp_vec3 *x = palp_world_positions(w);
  double mx = 0.0;
  for (int l = 0; l < m->link_count; ++l) {
    const int a = m->link[l][0], b = m->link[l][1];
    const double e = fabs(vdist(x[a], x[b]) / vdist(m->rest[a], m->rest[b]) - 1.0);
    if (e > mx) mx = e;
  }
  return mx;
}

/* The reviewer's case: the default world, 30 N on the pole vertex alone for 100 frames of
 * 10 ms. The steps are split (health.substeps > 0) and the links strain past 50%. */
static void test_large_strain_per_frame(void) {
  palp_world_def d = palp_world_default_def();
  int e;
  palp_world *w = palp_world_create(&d, &e);
  CHECK(w, "default world: %d", e);
  if (!w) return;
  const palp_mesh *m = palp_world_mesh(w);
  palp_contact_def c = palp_contact_default_def(PALP_DIST_SINGLE, m->rest[m->top_vertex]);
  const int id = palp_world_add_contact(w, &c);
  CHECK(id >= 0 && palp_world_set_contact_force(w, id, (palp_vec3){0, 0, -30.0}) == PALP_OK, "the 30 N load");
  const int frames = 100;
  int64_t prev = 0;
  int bad_increment = 0, missed = 0, strained_frames = 0;
  for (int f = 0; f < frames; ++f) {
    CHECK(palp_world_step(w) == PALP_OK, "frame %d", f);
    palp_world_health h;
    palp_world_get_health(w, &h);
    const int64_t inc = h.large_strain_steps - prev;
    prev = h.large_strain_steps;
    /* counted at most once a frame; always when the frame ends with a link beyond 50%
     * (1e-9 above it, so that rounding in the two strain formulas cannot decide) */
    if (inc < 0 || inc > 1) bad_increment++;
    if (end_strain(w) > 0.5 + 1e-9) {
      strained_frames++;
      if (inc != 1) missed++;
    }
  }
  palp_world_health h;
  palp_world_get_health(w, &h);
  printf("30 N on the pole vertex, %d frames of 10 ms: %lld split steps, large_strain_steps %lld (frames ending "
         "beyond 50%%: %d), max strain %.2f, frame %lld\n",
         frames, (long long)h.substeps, (long long)h.large_strain_steps, strained_frames, h.max_strain,
         (long long)palp_world_frame(w));
  CHECK(h.substeps > 0, "the load splits steps (%lld), or the case tests nothing", (long long)h.substeps);
  CHECK(strained_frames > 0, "frames end beyond 50%% strain (%d)", strained_frames);
  CHECK(h.large_strain_steps <= palp_world_frame(w), "large_strain_steps %lld <= frames %lld",
        (long long)h.large_strain_steps, (long long)palp_world_frame(w));
  CHECK(bad_increment == 0, "large_strain_steps rose by 0 or 1 each frame (%d frames rose otherwise)", bad_increment);
  CHECK(missed == 0, "every frame ending with a link beyond 50%% counted (%d missed)", missed);
  palp_world_destroy(w);
}

int main(void) {
  test_large_strain_per_frame();
  CHECK_DONE();
}
