/* Effects: the step runs only the stages a scene declares, an effect that is off
 * allocates nothing, and each effect does what its physics says when removed. */
#include <malloc.h>

#include "common.h"

static size_t heap_in_use(void) { return mallinfo2().uordblks; }

/* Pushes the pole with 3 N for `hold` s and returns the pole's inward displacement [m]
 * at 0.5 s and at the end, and the largest relative volume change. */
static void press(uint32_t effects, double hold, double *d_early, double *d_end, double *dv) {
  palp_world_def d = handset_def();
  d.effects = effects;
  int e;
  palp_world *w = palp_world_create(&d, &e);
  palp_contact_def c = palp_contact_default_def(PALP_DIST_UNIFORM, (palp_vec3){0, 0, 0.04});
  const int id = palp_world_add_contact(w, &c);
  palp_world_set_contact_force(w, id, (palp_vec3){0, 0, -3.0});
  *dv = 0;
  const long n = lround(hold / d.dt);
  for (long k = 0; k < n; ++k) {
    palp_world_step(w);
    const double dz = 0.04 - palp_world_positions(w)[0].z;
    if (k == lround(0.5 / d.dt) - 1) *d_early = dz;
    *dv = fmax(*dv, fabs(palp_world_volume(w) / palp_world_rest_volume(w) - 1));
  }
  *d_end = 0.04 - palp_world_positions(w)[0].z;
  palp_world_destroy(w);
}

int main(void) {
  const uint32_t all = PALP_EFFECT_ALL & ~(uint32_t)PALP_EFFECT_GRAVITY;
  int e;
  /* Stages follow the effects. */
  palp_world_def d = handset_def();
  d.effects = PALP_EFFECT_MEMBRANE_ELASTICITY;
  palp_world *w = palp_world_create(&d, &e);
  CHECK(w && !has_stage(w, "gel_forces") && !has_stage(w, "gel_state") && !has_stage(w, "feedback") &&
            !has_stage(w, "gel_support") && has_stage(w, "membrane_forces"),
        "elasticity-only world runs no gel, support or feedback stage");
  palp_world_destroy(w);

  /* Memory: a world without viscosity holds no Burgers states (2 doubles per link),
   * one without the gel no gradient and Sherman-Morrison vectors. */
  d = handset_def();
  size_t h0 = heap_in_use();
  w = palp_world_create(&d, &e);
  const size_t full = heap_in_use() - h0;
  const int links = palp_world_mesh(w)->link_count, nv = palp_world_mesh(w)->vertex_count;
  palp_world_destroy(w);
  d.effects = all & ~(uint32_t)(PALP_EFFECT_MEMBRANE_VISCOSITY);
  h0 = heap_in_use();
  w = palp_world_create(&d, &e);
  const size_t noviscous = heap_in_use() - h0;
  palp_world_destroy(w);
  printf("world heap: all effects %zu B, without viscosity %zu B (%d links)\n", full, noviscous, links);
  /* full >= other + need, not full - other >= need: size_t would wrap if the other took more */
  CHECK(full >= noviscous + (size_t)links * 2 * sizeof(double), "viscosity off frees its 16 B per link");
  d.effects = all & ~(uint32_t)(PALP_EFFECT_GEL_PRESSURE | PALP_EFFECT_GEL_DAMPING);
  h0 = heap_in_use();
  w = palp_world_create(&d, &e);
  const size_t nogel = heap_in_use() - h0;
  palp_world_destroy(w);
  CHECK(full >= nogel + (size_t)nv * 3 * sizeof(double), "gel off frees its per-vertex gradient (%lld B less)",
        (long long)full - (long long)nogel);

  /* Without any viscosity (membrane and gel damping off) there is no creep: once the
   * elastic transient of the implicit step has passed (~0.3 s at 10 ms), the pole's
   * displacement at 0.5 s equals the one at 2 s within 1%. With viscosity it creeps:
   * the end value is at least 10% larger. */
  double d1, d2, dv;
  press(all & ~(uint32_t)(PALP_EFFECT_MEMBRANE_VISCOSITY | PALP_EFFECT_GEL_DAMPING), 2.0, &d1, &d2, &dv);
  printf("elastic: %.4f mm at 0.5 s, %.4f mm at 2 s\n", 1e3 * d1, 1e3 * d2);
  CHECK(fabs(d2 - d1) <= 0.01 * d2, "no creep without viscosity (%.4f vs %.4f mm)", 1e3 * d1, 1e3 * d2);
  press(all, 2.0, &d1, &d2, &dv);
  printf("viscoelastic: %.4f mm at 0.5 s, %.4f mm at 2 s\n", 1e3 * d1, 1e3 * d2);
  CHECK(d2 > 1.1 * d1, "creep with viscosity (%.4f -> %.4f mm)", 1e3 * d1, 1e3 * d2);

  /* Without the gel pressure the volume is not kept: >= 5x the change with it. */
  double dv_gel, dv_none;
  press(all, 1.0, &d1, &d2, &dv_gel);
  press(all & ~(uint32_t)(PALP_EFFECT_GEL_PRESSURE), 1.0, &d1, &d2, &dv_none);
  printf("volume change under 3 N: %.4f%% with gel pressure, %.4f%% without\n", 100 * dv_gel, 100 * dv_none);
  CHECK(dv_none > 5.0 * dv_gel, "gel pressure keeps the volume (%.4f%% vs %.4f%%)", 100 * dv_gel, 100 * dv_none);

  /* Gravity: without it the unloaded rest shape stays exactly at rest; with it the
   * pole sags (membrane weight 0.19 N pulls it down by a measurable amount). */
  d = handset_def();
  w = palp_world_create(&d, &e);
  for (int k = 0; k < 100; ++k) palp_world_step(w);
  CHECK(palp_world_positions(w)[0].z == 0.04, "no gravity: the pole does not move (z = %.17g)",
        palp_world_positions(w)[0].z);
  palp_world_destroy(w);
  d.effects = all | PALP_EFFECT_GRAVITY;
  w = palp_world_create(&d, &e);
  for (int k = 0; k < 100; ++k) palp_world_step(w);
  const double sag = 0.04 - palp_world_positions(w)[0].z;
  printf("gravity sag of the pole after 1 s: %.4f um\n", 1e6 * sag);
  CHECK(sag > 1e-7, "gravity makes the pole sag (%.3g m)", sag);
  palp_world_destroy(w);

  /* Invalid combinations are refused. */
  d = handset_def();
  d.effects = PALP_EFFECT_MEMBRANE_VISCOSITY;
  CHECK(palp_world_create(&d, &e) == NULL && e == PALP_EINVAL, "viscosity without elasticity refused");
  CHECK_DONE();
}
