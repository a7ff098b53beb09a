/* The phantom under the paper's experiment (3 N step for 2 s, then 2 s free):
 * the gel keeps the volume within 1% of rest, the feedback balances the load once
 * the phantom has settled, the phantom returns to within 5% of its peak displacement
 * about 1.0 s after release (the paper's recovery time), every run stays finite, at
 * the paper's 10 ms step and the haptic 1 ms step, and the two steps agree. The
 * shipped parameters are config/params/calibrated.json (fitted to the FEM). */
#include "common.h"

typedef struct outcome {
  double peak, recover_t, max_vol_err, fb_err;
  double trace[400]; /* probe displacement every 10 ms [m] */
  double fb_settle;  /* last time in the hold with |feedback| off the load by > 5% [s] */
  double fb_lag;     /* largest |feedback - load| over the hold [N] */
  double fb_lag_late; /* the same after the first 0.5 s of the hold [N] */
  int ok;
} outcome;

/* Runs the scene; `top` measures the top vertex, else the contact's centre vertex. */
static outcome run(palp_scene s, double dt, int top) {
  outcome o = {.recover_t = -1.0, .ok = 1};
  s.world.dt = dt;
  int e;
  palp_world *w = palp_scene_create_world(&s, &e);
  if (!w) return (outcome){.ok = 0};
  const palp_mesh *m = palp_world_mesh(w);
  const int probe = top ? m->top_vertex : palp_mesh_nearest_vertex(m, m->rest, s.contact[0].def.center);
  const long n = lround(4.0 / dt);
  for (long k = 0; k < n; ++k) {
    palp_scene_apply(&s, w, palp_world_time(w));
    if (palp_world_step(w)) {
      o.ok = 0;
      break;
    }
    const double t = palp_world_time(w);
    const double d = vdist(palp_world_positions(w)[probe], m->rest[probe]);
    if (!isfinite(d)) o.ok = 0;
    if (d > o.peak) o.peak = d;
    const long sample = lround(t / 0.01) - 1;
    if (fabs(t - 0.01 * (double)(sample + 1)) < 0.25 * dt && sample >= 0 && sample < 400) o.trace[sample] = d;
    const double ve = fabs(palp_world_volume(w) / palp_world_rest_volume(w) - 1.0);
    if (ve > o.max_vol_err) o.max_vol_err = ve;
    if (fabs(t - 2.0) < 0.5 * dt) {
      /* Settled at the end of the hold: the phantom pushes back with the applied
       * force, f_fb = -F (quasi-static balance; inertia of the membrane is ~1e-5 N). */
      palp_vec3 fb;
      palp_world_contact_feedback(w, 0, &fb);
      const int v = palp_mesh_nearest_vertex(m, m->rest, s.contact[0].def.center);
      const palp_vec3 n_in = {-m->rest[v].x / 0.04, -m->rest[v].y / 0.04, -m->rest[v].z / 0.04};
      const palp_vec3 F = {3.0 * n_in.x, 3.0 * n_in.y, 3.0 * n_in.z};
      o.fb_err = vdist(fb, (palp_vec3){-F.x, -F.y, -F.z}) / 3.0;
    }
    if (t > 2.0 && o.recover_t < 0 && d <= 0.05 * o.peak) o.recover_t = t - 2.0;
    if (t < 2.0 - 0.5 * dt) {
      palp_vec3 fb;
      palp_world_contact_feedback(w, 0, &fb);
      const double lag = fabs(3.0 - sqrt(fb.x * fb.x + fb.y * fb.y + fb.z * fb.z));
      o.fb_lag = fmax(o.fb_lag, lag);
      if (lag > 0.15) o.fb_settle = t;
      if (t >= 0.5) o.fb_lag_late = fmax(o.fb_lag_late, lag);
    }
  }
  palp_world_destroy(w);
  return o;
}

int main(void) {
  palp_scene s = paper_scene();
  CHECK(s.frames == 400 && fabs(s.world.dt - 0.01) < 1e-15, "the shipped scene is the paper's 400 frames of 10 ms");
  CHECK(s.contact_count == 1 && s.contact[0].profile.kind == PALP_PROFILE_STEP &&
            s.contact[0].profile.magnitude == 3.0 && s.contact[0].profile.t_off == 2.0,
        "the shipped scene holds the paper's 3 N step for 2 s");

  /* The paper tuned its recovery with the contact at the top: uniform patch at the pole. */
  palp_scene top = s;
  top.contact[0].def.center = (palp_vec3){0, 0, 0.04};
  top.contact[0].def.distribution = PALP_DIST_UNIFORM;
  const double dts[2] = {0.01, 0.001};
  outcome tops[2];
  for (int i = 0; i < 2; ++i) {
    outcome o = run(top, dts[i], 1);
    tops[i] = o;
    printf("top contact, dt %.3f s: peak %.3f mm, back within 5%% after %.2f s, max volume error %.3f%%, feedback "
           "error %.2f%%\n",
           dts[i], 1e3 * o.peak, o.recover_t, 100 * o.max_vol_err, 100 * o.fb_err);
    CHECK(o.ok, "finite and stable at dt %.3f", dts[i]);
    CHECK(o.max_vol_err < 0.01, "volume within 1%% of rest under 3 N (%.3f%%)", 100 * o.max_vol_err);
    /* "About 1.0 s": within +-40% of the paper's figure at the paper's 10 ms step, where
     * the parameters were calibrated. The 5% level is crossed in a slow tail where the
     * 10 ms and 1 ms traces differ by < 3% of the peak (checked below), so the crossing
     * moves with the step and with when the lagged tangent happens to be rebuilt
     * (measured 1.23 s at 10 ms, 1.13 s at 1 ms; 1.53 s at 1 ms before the mass-aware
     * rebuild trigger): bound 1.8 s at 1 ms. */
    CHECK(o.recover_t >= 0.6 && o.recover_t <= (dts[i] > 0.005 ? 1.4 : 1.8), "recovery to 5%% of peak (%.2f s)",
          o.recover_t);
    CHECK(o.fb_err < 0.02, "feedback balances the 3 N load within 2%% (%.2f%%)", 100 * o.fb_err);
    /* The feedback is the membrane and gel force on the contact vertices: while the
     * load first accelerates the vertices and the gel they carry, it is below the
     * load by the inertial force. It must be within 5% of the load 0.2 s into the
     * hold and within 1% after 0.5 s, at both steps. */
    printf("    feedback lag over the hold %.4f N, within 5%% from %.3f s, after 0.5 s %.4f N\n", o.fb_lag,
           o.fb_settle, o.fb_lag_late);
    CHECK(o.fb_settle < 0.2, "feedback within 5%% of the load from 0.2 s on (last miss at %.3f s)", o.fb_settle);
    CHECK(o.fb_lag_late < 0.03, "feedback within 1%% of the load after 0.5 s (lag %.4f N)", o.fb_lag_late);
    /* The calibrated phantom is as soft as the FEM reference (~3 cm under 3 N); the
     * bound is physical: the pole stays inside the dome. */
    CHECK(o.peak > 1e-4 && o.peak < 0.04, "peak displacement is physical: 0.1-40 mm (%.3f mm)", 1e3 * o.peak);
  }
  /* The step size changes the trajectory by little: outside the first 0.15 s after
   * each jump of the load, the 10 ms and 1 ms traces of the pole agree within 4% of
   * the peak (measured 2.7%, in the slow tail). Inside those windows the 10 ms step
   * lags by its first-order error, ~h / tau for the ~50 ms rise (measured 3.6 mm, 13%
   * of the peak, at the first frame): bound 20%. */
  double worst = 0.0, worst_jump = 0.0;
  for (int k = 0; k < 400; ++k) {
    const double t = 0.01 * (k + 1), e = fabs(tops[0].trace[k] - tops[1].trace[k]);
    if (t < 0.15 + 1e-9 || (t > 2.0 + 1e-9 && t < 2.15 + 1e-9)) worst_jump = fmax(worst_jump, e);
    else worst = fmax(worst, e);
  }
  printf("top contact: 10 ms vs 1 ms traces differ by at most %.3f mm (%.2f%% of the peak), %.3f mm (%.2f%%) in the "
         "0.15 s after a jump of the load\n",
         1e3 * worst, 100 * worst / tops[1].peak, 1e3 * worst_jump, 100 * worst_jump / tops[1].peak);
  CHECK(worst < 0.04 * tops[1].peak, "10 ms and 1 ms traces within 4%% of the peak (%.3f mm)", 1e3 * worst);
  CHECK(worst_jump < 0.20 * tops[1].peak, "10 ms lag after a jump within 20%% of the peak (%.3f mm)",
        1e3 * worst_jump);

  /* The four distributions at the off-centre contact, at both steps. */
  for (int d = 1; d <= 4; ++d)
    for (int i = 0; i < 2; ++i) {
      palp_scene sd = s;
      sd.contact[0].def.distribution = (palp_distribution)d;
      outcome o = run(sd, dts[i], 0);
      printf("distribution %d, dt %.3f s: peak %.3f mm at the contact, volume error %.3f%%, feedback error %.2f%%\n",
             d, dts[i], 1e3 * o.peak, 100 * o.max_vol_err, 100 * o.fb_err);
      CHECK(o.ok, "distribution %d finite at dt %.3f", d, dts[i]);
      CHECK(o.max_vol_err < 0.01, "distribution %d volume within 1%% (%.3f%%)", d, 100 * o.max_vol_err);
      CHECK(o.fb_err < 0.02, "distribution %d feedback balances the load within 2%% (%.2f%%)", d, 100 * o.fb_err);
    }
  CHECK_DONE();
}
