/* The finger's compliance by etree paths (docs/haptics.md, "The compliance by etree
 * paths"): on a nested-dissection factor (a net of 600 vertices and more) a finger's
 * local block of A^{-1} is assembled from its vertices' forward passes, z = L^{-1} P e on
 * their etree paths (W = z^T D^{-1} z), and the surface's correction is one more solve,
 * where the reference takes full columns of A^{-1} (def.finger_columns = 1). The two are
 * the same quantities to rounding (the columns are kept in single precision, ~6e-8).
 * Checked on the long-term dome's 1,300-vertex net at 250 Hz with the server's lag, its
 * deferred jobs run when claimed (they make the paths of the new factor too), a fingertip
 * pressing 4.5 mm at the pole and sliding 20 mm with a 1 mm, 3 Hz wobble:
 * - the local model's force within 1e-6 of its magnitude + 1 uN, and its stiffness within
 *   1e-6 of its norm + 0.1 N/m, at every frame (measured: see the printout);
 * - both worlds rebuild the same number of times;
 * - the paths served (health finger_paths > 0) and not in the reference (0), nor on the
 *   338-vertex dome, whose factor keeps AMD's order. */
#include "check.h"
#include "palp.h"

static palp_vec3 device_at(int f) {
  const double t = 0.004 * f, pi = 3.14159265358979323846;
  const double depth = t < 0.4 ? -0.001 + 0.0055 * t / 0.4 : 0.0045 + 0.001 * sin(2 * pi * 3.0 * (t - 0.4));
  const double x = t < 0.4 ? 0.0 : 0.020 * (t - 0.4) / 1.6;
  return (palp_vec3){x, 0.0, 0.048 - depth};
}

static double norm3(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

/* One step of a lagged world as a server steps it: a due job handed back first, a new
 * one claimed after the step and run at once. Returns the jobs run. */
static int step(palp_world *w, palp_factor_job **held) {
  int jobs = 0;
  if (*held && palp_world_factor_due(w) == palp_world_frame(w)) {
    CHECK(palp_world_factor_done(w, *held) == PALP_OK, "hand back");
    *held = NULL;
  }
  CHECK(palp_world_step(w) == PALP_OK, "step at frame %lld", (long long)palp_world_frame(w));
  palp_factor_job *j = palp_world_factor_claim(w);
  if (j) {
    palp_factor_job_run(j);
    *held = j;
    jobs++;
  }
  return jobs;
}

int main(void) {
  palp_scene sc;
  char err[256];
  CHECK(palp_scene_load(PALP_CONFIG_DIR "/paper_step_long_term_fine.json", &sc, err, sizeof err) == 0, "scene: %s", err);
  palp_world_def d = sc.world;
  d.dt = 0.004;
  d.refactor_lag = palp_world_refactor_lag_for(d.dt);
  d.refactor_blend = palp_world_refactor_blend_for(d.dt);
  palp_world_def dc = d;
  dc.finger_columns = 1;
  int e;
  palp_world *wp = palp_world_create(&d, &e), *wc = palp_world_create(&dc, &e);
  CHECK(wp && wc, "worlds: %s", palp_strerror(e));
  if (!wp || !wc) CHECK_DONE();
  const palp_finger_def fd = palp_finger_default_def();
  const int fp = palp_world_add_finger_def(wp, &fd, device_at(0)), fc = palp_world_add_finger_def(wc, &fd, device_at(0));
  palp_factor_job *hp = NULL, *hc = NULL;
  int jobs_p = 0, jobs_c = 0, frames_in_contact = 0;
  double worst_f = 0.0, worst_k = 0.0, peak = 0.0;
  for (int f = 0; f < 500; ++f) {
    palp_world_set_finger_device(wp, fp, device_at(f));
    palp_world_set_finger_device(wc, fc, device_at(f));
    jobs_p += step(wp, &hp);
    jobs_c += step(wc, &hc);
    palp_local_model mp, mc;
    palp_world_finger_local_model(wp, fp, &mp);
    palp_world_finger_local_model(wc, fc, &mc);
    const double F = norm3(mc.force), dF = norm3((palp_vec3){mp.force.x - mc.force.x, mp.force.y - mc.force.y,
                                                             mp.force.z - mc.force.z});
    double kn = 0.0, dk = 0.0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const double kc = mc.stiffness[i][j], dkij = mp.stiffness[i][j] - kc;
        kn += kc * kc, dk += dkij * dkij;
      }
    kn = sqrt(kn), dk = sqrt(dk);
    frames_in_contact += mc.contact;
    if (F > peak) peak = F;
    if (F > 0.01 && dF / F > worst_f) worst_f = dF / F;
    if (kn > 1.0 && dk / kn > worst_k) worst_k = dk / kn;
    CHECK(dF <= 1e-6 * F + 1e-6, "frame %d: force %.6f N by paths against %.6f N by columns", f, norm3(mp.force), F);
    CHECK(dk <= 1e-6 * kn + 0.1, "frame %d: stiffness differs by %.3g N/m of %.3g", f, dk, kn);
  }
  palp_world_health hp_, hc_;
  palp_world_get_health(wp, &hp_);
  palp_world_get_health(wc, &hc_);
  printf("1,300-vertex long-term dome, 250 Hz, 500 frames (%d in contact, peak %.2f N): paths against columns, force within "
         "%.2e of it (1e-6), stiffness within %.2e of its norm (1e-6); jobs %d / %d; vertices made by paths %lld (on the "
         "tick and by jobs), by the reference %lld\n", frames_in_contact, peak, worst_f, worst_k, jobs_p, jobs_c,
         (long long)hp_.finger_paths, (long long)hc_.finger_paths);
  CHECK(frames_in_contact > 400 && peak > 1.0, "the fingertip pressed: %d frames in contact, peak %.2f N", frames_in_contact, peak);
  CHECK(jobs_p == jobs_c && jobs_p >= 3, "rebuilds: %d by paths, %d by columns (the same, 3 or more)", jobs_p, jobs_c);
  CHECK(hp_.finger_paths > 0 && hc_.finger_paths == 0, "paths served: %lld, in the reference %lld",
        (long long)hp_.finger_paths, (long long)hc_.finger_paths);
  if (hp) palp_world_factor_done(wp, hp);
  if (hc) palp_world_factor_done(wc, hc);
  palp_world_destroy(wp), palp_world_destroy(wc);
  /* the 338-vertex dome keeps AMD's order, and full columns */
  CHECK(palp_scene_load(PALP_CONFIG_DIR "/paper_step_long_term.json", &sc, err, sizeof err) == 0, "scene: %s", err);
  palp_world *w = palp_world_create(&sc.world, &e);
  CHECK(w != NULL, "338-vertex world");
  if (w) {
    const int f0 = palp_world_add_finger_def(w, &fd, (palp_vec3){0, 0, 0.046});
    for (int f = 0; f < 20; ++f) palp_world_step(w);
    palp_local_model m;
    palp_world_finger_local_model(w, f0, &m);
    palp_world_health h;
    palp_world_get_health(w, &h);
    CHECK(m.contact && h.finger_paths == 0, "338 vertices: in contact %d, vertices made by paths %lld (0)", m.contact,
          (long long)h.finger_paths);
    palp_world_destroy(w);
  }
  CHECK_DONE();
}
