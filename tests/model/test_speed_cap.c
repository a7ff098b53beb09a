/*
 * test_speed_cap.c - the last halving's speed cap (stage_solve, docs/model.md "Failures are
 * caught before they land") and its counter, health.clamped_steps (session 83 review).
 *
 * White box, as test_state_hash.c: world.c is compiled into this test, so that one sub-step at
 * the last halving (try_step with last_resort) can be taken from a known state. Three worlds of
 * the default phantom are driven alike (3 N on the pole vertex for 3 frames of 10 ms: the same
 * bits, model_determinism), then each takes one such sub-step of 10 ms, differing only in
 * def.max_speed. World A's is 1e9 m/s (nothing capped); from its solved velocities the test
 * reads the fastest vertex speed s and the largest component c (c >= s / sqrt 3). Asserted:
 *  - with max_speed midway between s and sqrt 3 c, the step's per-component test trips
 *    (c > max_speed / sqrt 3) while no vertex is above max_speed: nothing is capped, the world
 *    is A's bit for bit (state hash), and clamped_steps does not count it (it did until the
 *    review: 7 of 1,008 counted steps in the reviewer's run capped nothing);
 *  - with max_speed s / 2 the fastest vertices are capped: clamped_steps counts one, and no
 *    vertex is faster than max_speed (1e-12 relative).
 */
#include "world.c"

#include "check.h"

static palp_world *pressed(void) {
  palp_world_def d = palp_world_default_def();
  int e = 0;
  palp_world *w = palp_world_create(&d, &e);
  if (!w) {
    fprintf(stderr, "world: %s\n", palp_strerror(e));
    exit(2);
  }
  const palp_contact_def c = palp_contact_default_def(PALP_DIST_SINGLE, w->mesh.rest[w->mesh.top_vertex]);
  const int id = palp_world_add_contact(w, &c);
  if (id < 0 || palp_world_set_contact_force(w, id, (palp_vec3){0, 0, -3.0}) != PALP_OK) exit(2);
  for (int f = 0; f < 3; ++f)
    if (palp_world_step(w) != PALP_OK) exit(2);
  return w;
}

/* The fastest free vertex's speed and the largest |component| of any [m/s]. */
static void fastest(const palp_world *w, double *s, double *c) {
  *s = *c = 0.0;
  for (int r = 0; r < w->nfree; ++r) {
    const palp_vec3 v = w->vel[w->vertex_of[r]];
    *s = fmax(*s, sqrt(v.x * v.x + v.y * v.y + v.z * v.z));
    *c = fmax(*c, fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z))));
  }
}

int main(void) {
  palp_world *a = pressed(), *b = pressed(), *c = pressed();
  CHECK(palp_world_state_hash(a) == palp_world_state_hash(b) && palp_world_state_hash(a) == palp_world_state_hash(c),
        "three worlds driven alike are the same bits");
  const double h = a->def.dt;
  a->def.max_speed = 1e9;
  CHECK(try_step(a, h, 1) == PALP_OK && a->clamped_steps == 0, "A: the sub-step at 1e9 m/s, nothing capped");
  double s, cmax;
  fastest(a, &s, &cmax);
  const double mid = 0.5 * (s + sqrt(3.0) * cmax);
  printf("A: fastest vertex %.6g m/s, largest component %.6g m/s; B's max_speed %.6g m/s (component test at %.6g)\n", s,
         cmax, mid, mid / sqrt(3.0));
  CHECK(s > 0.0 && cmax > mid / sqrt(3.0) && s < mid, "the case: c %.6g > max_speed / sqrt 3 %.6g, s %.6g < max_speed %.6g",
        cmax, mid / sqrt(3.0), s, mid);

  b->def.max_speed = mid;
  const int64_t b0 = b->clamped_steps;
  CHECK(try_step(b, h, 1) == PALP_OK, "B: the sub-step");
  printf("B: clamped_steps %lld -> %lld\n", (long long)b0, (long long)b->clamped_steps);
  CHECK(palp_world_state_hash(b) == palp_world_state_hash(a), "B: nothing capped, the world is A's bit for bit");
  CHECK(b->clamped_steps == b0, "B: a sub-step that capped no vertex is not counted (%lld -> %lld)", (long long)b0,
        (long long)b->clamped_steps);

  c->def.max_speed = 0.5 * s;
  const int64_t c0 = c->clamped_steps;
  CHECK(try_step(c, h, 1) == PALP_OK, "C: the sub-step");
  double sc, cc;
  fastest(c, &sc, &cc);
  printf("C: max_speed %.6g m/s: fastest vertex after the sub-step %.6g m/s; clamped_steps %lld -> %lld\n", 0.5 * s, sc,
         (long long)c0, (long long)c->clamped_steps);
  CHECK(c->clamped_steps == c0 + 1, "C: the capping sub-step is counted once");
  CHECK(sc <= 0.5 * s * (1.0 + 1e-12), "C: no vertex faster than max_speed (%.9g <= %.9g)", sc, 0.5 * s);
  palp_world_destroy(a), palp_world_destroy(b), palp_world_destroy(c);
  CHECK_DONE();
}
