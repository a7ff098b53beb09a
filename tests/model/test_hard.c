/* Hard cases for the real-time model (issue 7): each stays finite and bounded, keeps
 * its volume, and returns to rest; where the model is pushed beyond what it can
 * represent faithfully, the world says so through its health counters. */
#include "common.h"

static const double R = 0.04; /* [m] */

static double max_disp(const palp_world *w) {
  const palp_mesh *m = palp_world_mesh(w);
  double mx = 0.0;
  for (int i = 0; i < m->vertex_count; ++i) {
    const double d = vdist(palp_world_positions(w)[i], m->rest[i]);
    if (!(d <= mx)) mx = d; /* NaN propagates */
  }
  return mx;
}

static double vol_err(const palp_world *w) { return fabs(palp_world_volume(w) / palp_world_rest_volume(w) - 1.0); }

static palp_vec3 on_sphere(double polar_deg, double az_deg) {
  const double t = polar_deg * 3.14159265358979323846 / 180.0, p = az_deg * 3.14159265358979323846 / 180.0;
  return (palp_vec3){R * sin(t) * cos(p), R * sin(t) * sin(p), R * cos(t)};
}

typedef struct result {
  int err;
  double peak, final, max_dv;
  palp_world_health health;
} result;

/* Force `force(t)` [N] along the inward normal at `at` for 4 s of which the load is
 * on for the first 2; `jitter` draws each step from [0.5, 1.5] dt. */
static result press(palp_world_def d, palp_distribution dist, palp_vec3 at, double F, int impulses, int jitter) {
  result r = {0};
  int e;
  palp_world *w = palp_world_create(&d, &e);
  if (!w) return (result){.err = e};
  palp_contact_def c = palp_contact_default_def(dist, at);
  const int id = palp_world_add_contact(w, &c);
  unsigned seed = 12345u;
  while (palp_world_time(w) < 4.0 - 1e-9) {
    const double t = palp_world_time(w);
    double f = t < 2.0 ? F : 0.0;
    if (impulses) f = (t < 2.0 && (palp_world_frame(w) % 2 == 0)) ? F : 0.0; /* on-off every tick */
    palp_world_set_contact_force(w, id, (palp_vec3){-f * at.x / R, -f * at.y / R, -f * at.z / R});
    double h = d.dt;
    if (jitter) {
      seed = seed * 1103515245u + 12345u;
      h = d.dt * (0.5 + (double)(seed >> 8 & 0xffff) / 65535.0);
    }
    if ((r.err = palp_world_step_dt(w, h))) break;
    r.peak = fmax(r.peak, max_disp(w));
    r.max_dv = fmax(r.max_dv, vol_err(w));
  }
  r.final = max_disp(w);
  palp_world_get_health(w, &r.health);
  palp_world_destroy(w);
  return r;
}

static void report(const char *name, result r) {
  printf("%-40s peak %7.2f mm, final %6.3f mm, max volume change %.3f%%, substeps %lld, refactors %lld, max strain "
         "%.2f, large-strain steps %lld\n",
         name, 1e3 * r.peak, 1e3 * r.final, 100 * r.max_dv, (long long)r.health.substeps,
         (long long)r.health.refactors, r.health.max_strain, (long long)r.health.large_strain_steps);
}

/* The common bar: finite, bounded by the phantom's radius, volume within 2%, and
 * back within 10% of the peak 2 s after release. */
static void faithful(const char *name, result r) {
  report(name, r);
  CHECK(r.err == PALP_OK && isfinite(r.peak) && isfinite(r.final), "%s: finite (error %d)", name, r.err);
  CHECK(r.peak < R, "%s: peak displacement below the radius (%.2f mm)", name, 1e3 * r.peak);
  CHECK(r.max_dv < 0.02, "%s: volume within 2%% (%.3f%%)", name, 100 * r.max_dv);
  CHECK(r.final < 0.1 * r.peak, "%s: back within 10%% of the peak 2 s after release (%.3f of %.3f mm)", name,
        1e3 * r.final, 1e3 * r.peak);
}

/* On the calibrated default phantom (as soft as the FEM reference: a 3 N point load
 * settles 39 mm deep) the server's largest force, 20 N, and 30 N crush the dome
 * through its base plane, which the model does not represent (nor does the FEM's
 * instantaneous reading, docs/fem.md). The bar there: the world never fails, the
 * volume stays within 2%, the phantom comes back within 10% of its peak 2 s after
 * release, and the health counters say the strain was beyond the model. */
static void survives(const char *name, result r) {
  report(name, r);
  CHECK(r.err == PALP_OK && isfinite(r.peak) && isfinite(r.final), "%s: finite, world not failed (error %d)", name,
        r.err);
  CHECK(r.max_dv < 0.02, "%s: volume within 2%% (%.3f%%)", name, 100 * r.max_dv);
  CHECK(r.final < 0.1 * r.peak, "%s: back within 10%% of the peak 2 s after release (%.3f of %.3f mm)", name,
        1e3 * r.final, 1e3 * r.peak);
  CHECK(r.health.large_strain_steps > 0, "%s: reported as large strain (max %.2f)", name, r.health.max_strain);
}

int main(void) {
  /* The numerical hard cases run on the stiff hand-set phantom, where 30 N stays
   * inside the dome and the figures below are physical; the shipped phantom's
   * cases follow them. */
  const palp_world_def d10 = handset_def();
  palp_world_def d1 = d10;
  d1.dt = 0.001;
  const palp_vec3 off = on_sphere(30, 40), rim = on_sphere(86, 0);

  /* Ten times the paper's force, a step with no ramp, at both steps. */
  faithful("30 N uniform, no ramp, 10 ms", press(d10, PALP_DIST_UNIFORM, off, 30, 0, 0));
  faithful("30 N uniform, no ramp, 1 ms", press(d1, PALP_DIST_UNIFORM, off, 30, 0, 0));
  /* A point load: all 30 N on one vertex. */
  faithful("30 N single vertex, 10 ms", press(d10, PALP_DIST_SINGLE, off, 30, 0, 0));
  /* Impulses every tick at 1 kHz. */
  faithful("30 N on/off every tick, 1 kHz", press(d1, PALP_DIST_SINGLE, off, 30, 1, 0));
  /* Contact at the fixed base's rim (4 degrees above the base). */
  faithful("3 N gaussian at the rim, 10 ms", press(d10, PALP_DIST_GAUSSIAN, rim, 3, 0, 0));
  faithful("30 N uniform at the rim, 1 ms", press(d1, PALP_DIST_UNIFORM, rim, 30, 0, 0));
  /* Relaxation times far shorter than the step: Kelvin 0.1 ms, Maxwell 1 ms at 10 ms. */
  palp_world_def fast = d10;
  fast.membrane.eta2 = 8e2;
  fast.membrane.eta1 = 4.2e3;
  faithful("tau 0.1 ms and 1 ms at a 10 ms step", press(fast, PALP_DIST_UNIFORM, off, 3, 0, 0));
  /* A very stiff membrane (100x, time constants kept) on a very soft gel (1/100
   * support, a1 = 1). */
  palp_world_def stiff = d10;
  stiff.membrane.E1 *= 100, stiff.membrane.E2 *= 100, stiff.membrane.eta1 *= 100, stiff.membrane.eta2 *= 100;
  stiff.gel.support_modulus /= 100, stiff.gel.support_viscosity /= 100, stiff.gel.a1 = 1.0;
  faithful("stiff membrane on a soft gel, 10 ms", press(stiff, PALP_DIST_UNIFORM, off, 3, 0, 0));
  /* Jittering steps: each drawn from [0.5, 1.5] ms; the peak must agree with the
   * regular 1 ms run within 5% (the dynamics do not depend on the clock's noise). */
  const result jit = press(d1, PALP_DIST_GAUSSIAN, off, 3, 0, 1), reg = press(d1, PALP_DIST_GAUSSIAN, off, 3, 0, 0);
  faithful("3 N gaussian, jittering 0.5-1.5 ms steps", jit);
  CHECK(fabs(jit.peak - reg.peak) < 0.05 * reg.peak, "jittered peak %.3f mm vs regular %.3f mm (5%%)",
        1e3 * jit.peak, 1e3 * reg.peak);

  /* Far beyond the model: 300 N on one vertex strains links by >100%. It must stay
   * finite and say so: the large-strain counter is raised. */
  const result big = press(d10, PALP_DIST_SINGLE, off, 300, 0, 0);
  report("300 N single vertex (beyond the model)", big);
  CHECK(big.err == PALP_OK && isfinite(big.peak), "300 N stays finite");
  CHECK(big.health.large_strain_steps > 0 && big.health.max_strain > 0.5, "300 N is reported as large strain");
  const result small = press(d10, PALP_DIST_UNIFORM, off, 3, 0, 0);
  CHECK(small.health.large_strain_steps == 0, "the paper's 3 N is not reported as large strain (max %.3f)",
        small.health.max_strain);

  /* A point load on a soft, tensionless membrane (moduli ~20x below the hand-set
   * ones, a soft support, as a fit to a soft reference gives): at rest a link has no
   * stiffness across itself, so one linearised 10 ms step overshot to ~3x the
   * settled depth (116 vs 39 mm, feedback 232 N for a 3 N load). Steps that leave
   * their linearisation are retried in halves: the first frame must stay within the
   * settled depth and its feedback within 1.5x the load. */
  {
    palp_world_def soft = d10;
    soft.membrane.E1 = 2.2e5, soft.membrane.eta1 = 5e9, soft.membrane.E2 = 1.0e5, soft.membrane.eta2 = 1.4e4;
    soft.gel.support_modulus = 1.4e4, soft.gel.support_viscosity = 5e3;
    int e;
    palp_world *w = palp_world_create(&soft, &e);
    palp_contact_def c = palp_contact_default_def(PALP_DIST_SINGLE, off);
    const int id = palp_world_add_contact(w, &c);
    palp_world_set_contact_force(w, id, (palp_vec3){-3.0 * off.x / R, -3.0 * off.y / R, -3.0 * off.z / R});
    double first = 0.0, first_fb = 0.0, worst_fb = 0.0, dv = 0.0;
    for (int s = 0; s < 200; ++s) {
      CHECK(palp_world_step(w) == PALP_OK, "soft point load step %d", s);
      palp_vec3 fb;
      palp_world_contact_feedback(w, id, &fb);
      const double f = sqrt(fb.x * fb.x + fb.y * fb.y + fb.z * fb.z);
      if (s == 0) first = max_disp(w), first_fb = f;
      worst_fb = fmax(worst_fb, f);
      dv = fmax(dv, vol_err(w));
    }
    const double settled = max_disp(w);
    palp_world_health hl;
    palp_world_get_health(w, &hl);
    printf("soft point load, 3 N: first frame %.2f mm (feedback %.2f N), settled %.2f mm, worst feedback %.2f N, "
           "volume %.3f%%, max strain %.2f, substeps %lld\n",
           1e3 * first, first_fb, 1e3 * settled, worst_fb, 100 * dv, hl.max_strain, (long long)hl.substeps);
    CHECK(first <= settled, "soft point load: first frame %.2f mm beyond the settled %.2f mm", 1e3 * first,
          1e3 * settled);
    CHECK(worst_fb < 4.5, "soft point load: feedback %.2f N for a 3 N load (bound 4.5 N)", worst_fb);
    CHECK(hl.max_strain < 2.0, "soft point load: link strain %.2f (bound 2)", hl.max_strain);
    CHECK(dv < 0.01, "soft point load: volume within 1%% (%.3f%%)", 100 * dv);
    palp_world_destroy(w);
  }

  /* The shipped (calibrated) phantom: the paper's 3 N under every distribution at
   * both steps is faithful; 20 N (the server's max_force) and 30 N survive. */
  {
    const palp_world_def c10 = palp_world_default_def();
    palp_world_def c1 = c10;
    c1.dt = 0.001;
    faithful("calibrated: 3 N single vertex, 10 ms", press(c10, PALP_DIST_SINGLE, off, 3, 0, 0));
    faithful("calibrated: 3 N gaussian, 1 ms", press(c1, PALP_DIST_GAUSSIAN, off, 3, 0, 0));
    faithful("calibrated: 3 N uniform at the rim, 10 ms", press(c10, PALP_DIST_UNIFORM, rim, 3, 0, 0));
    survives("calibrated: 20 N single vertex, 1 ms", press(c1, PALP_DIST_SINGLE, off, 20, 0, 0));
    survives("calibrated: 30 N uniform, 10 ms", press(c10, PALP_DIST_UNIFORM, off, 30, 0, 0));
    survives("calibrated: 30 N on/off every tick, 1 kHz", press(c1, PALP_DIST_SINGLE, off, 30, 1, 0));

    /* A haptic station's typical load at 1 kHz: 1.5 +- 1 N at 0.7 Hz. Each rebuild of
     * the lagged tangent costs ~2 ms, two 1 kHz ticks, so rebuilds must be rare: the
     * mass term's share of the stability margin is counted before a link's growing
     * tension forces one. Measured 4 in 4,000 steps (88 before); bound 0.5%. The run
     * stays stable: volume within 1%, finite. */
    int e;
    palp_world *w = palp_world_create(&c1, &e);
    palp_contact_def c = palp_contact_default_def(PALP_DIST_GAUSSIAN, on_sphere(25, 60));
    const int id = palp_world_add_contact(w, &c);
    double dv = 0.0;
    int ok = 1;
    for (int s = 0; s < 4000 && ok; ++s) {
      const double f = 1.5 + sin(2 * 3.14159265358979323846 * 0.7 * palp_world_time(w));
      const palp_vec3 n = on_sphere(25, 60);
      palp_world_set_contact_force(w, id, (palp_vec3){-f * n.x / R, -f * n.y / R, -f * n.z / R});
      ok = palp_world_step(w) == PALP_OK;
      dv = fmax(dv, vol_err(w));
    }
    palp_world_health hl;
    palp_world_get_health(w, &hl);
    printf("calibrated: 0.7 Hz press at 1 kHz, 4 s: %lld refactorisations in 4000 steps, volume %.3f%%, peak now "
           "%.2f mm\n",
           (long long)hl.refactors, 100 * dv, 1e3 * max_disp(w));
    CHECK(ok && dv < 0.01, "0.7 Hz press: stable, volume within 1%% (%.3f%%)", 100 * dv);
    CHECK(hl.refactors < 20, "0.7 Hz press at 1 kHz: %lld tangent rebuilds in 4000 steps (bound 20)",
          (long long)hl.refactors);
    palp_world_destroy(w);
  }

  /* Several fingers at once (position-driven): three spheres pressed 5 mm into the
   * surface over 1 s, held 1 s and withdrawn; each feels a push back while
   * touching, all is finite, and the phantom returns within 2 s. */
  {
    int e;
    palp_world *w = palp_world_create(&d1, &e);
    const palp_vec3 at[3] = {on_sphere(20, 0), on_sphere(35, 120), on_sphere(50, 240)};
    const double rad = 0.007; /* fingertip radius [m] */
    int id[3];
    for (int k = 0; k < 3; ++k) id[k] = palp_world_add_finger(w, v3_scaled(at[k], (R + rad) / R), rad);
    double min_push[3] = {INFINITY, INFINITY, INFINITY}, peak = 0.0;
    for (int s = 0; s < 4000; ++s) {
      const double t = palp_world_time(w);
      const double depth = t < 1.0 ? 0.005 * t : (t < 2.0 ? 0.005 : 0.0); /* [m] */
      for (int k = 0; k < 3; ++k)
        palp_world_set_finger(w, id[k], v3_scaled(at[k], (R + rad - depth) / R), rad);
      CHECK(palp_world_step(w) == PALP_OK, "fingers step %d", s);
      if (t > 1.0 && t < 2.0)
        for (int k = 0; k < 3; ++k) {
          palp_vec3 fb;
          palp_world_contact_feedback(w, id[k], &fb);
          /* outward component of the push on the finger [N] */
          min_push[k] = fmin(min_push[k], (fb.x * at[k].x + fb.y * at[k].y + fb.z * at[k].z) / R);
        }
      peak = fmax(peak, max_disp(w));
    }
    printf("three fingers: peak %.2f mm, least push while pressed %.3f / %.3f / %.3f N, final %.3f mm\n", 1e3 * peak,
           min_push[0], min_push[1], min_push[2], 1e3 * max_disp(w));
    for (int k = 0; k < 3; ++k) CHECK(min_push[k] > 0.0, "finger %d is pushed back while pressing", k);
    CHECK(max_disp(w) < 0.1 * peak, "fingers: back within 10%% of the peak 2 s after withdrawal");
    palp_world_destroy(w);
  }

  /* An hour of simulated time: a 3 N press of 5 s every minute. The volume after the
   * last rest may differ from rest only by the Burgers fluid's permanent flow:
   * within 0.5%, and the world sleeps between presses (so the hour costs little). */
  {
    int e;
    palp_world *w = palp_world_create(&d10, &e);
    palp_contact_def c = palp_contact_default_def(PALP_DIST_GAUSSIAN, off);
    const int id = palp_world_add_contact(w, &c);
    int64_t awake_steps = 0;
    double dv_first = -1.0;
    while (palp_world_time(w) < 3600.0 - 1e-6) {
      const double t = palp_world_time(w), phase = fmod(t + 1e-9, 60.0);
      const double f = phase < 5.0 ? 3.0 : 0.0;
      palp_world_set_contact_force(w, id, (palp_vec3){-f * off.x / R, -f * off.y / R, -f * off.z / R});
      awake_steps += palp_world_is_awake(w);
      if (palp_world_step(w) != PALP_OK) {
        CHECK(0, "hour run failed at %.2f s", t);
        break;
      }
      if (dv_first < 0 && t > 59.0) dv_first = vol_err(w);
    }
    printf("one hour: volume change %.4f%% after the first minute, %.4f%% at the end; awake %.1f%% of steps\n",
           100 * dv_first, 100 * vol_err(w), 100.0 * (double)awake_steps / 360000.0);
    CHECK(vol_err(w) < 0.005, "no volume drift over an hour: %.4f%%", 100 * vol_err(w));
    CHECK(awake_steps < 360000 / 2, "the idle phantom sleeps between presses");
    palp_world_destroy(w);
  }
  CHECK_DONE();
}
