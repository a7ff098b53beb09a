/* test_contact.c - a force contact deforms the phantom near where it presses and
 * the feedback force balances it; lifting the finger lets it recover. */
#include <math.h>
#include <string.h>

#include "harness.h"
#include "input.h"
#include "view.h"

#define DOMAIN 102

/* Latest deformation: max displacement [m] and where. */
static int latest_deformation(palp_cli_station *st, const palp_Phantom *ph, double wait, double *maxd, palp_Vec3 *at) {
  int64_t end = palp_dds_now_ns() + (int64_t)(wait * 1e9);
  int got = 0;
  while (palp_dds_now_ns() < end) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(st->deformation_r, ptr, &info, 1, 1) > 0) {
      if (info.valid_data) {
        const palp_Deformation *d = ptr[0];
        int v = -1;
        *maxd = palp_cli_max_displacement(ph, d, &v);
        if (v >= 0) *at = ph->rest._buffer[v];
        got = 1;
      }
      dds_return_loan(st->deformation_r, ptr, 1);
    }
    test_sleep(0.01);
  }
  return got;
}

/* Frames a display takes over `wait` seconds: all of them, and those of a sleeping world. */
static void count_frames(palp_cli_station *st, double wait, int *all, int *asleep) {
  *all = *asleep = 0;
  const int64_t end = palp_dds_now_ns() + (int64_t)(wait * 1e9);
  while (palp_dds_now_ns() < end) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(st->deformation_r, ptr, &info, 1, 1) > 0) {
      if (info.valid_data) {
        (*all)++;
        *asleep += !((const palp_Deformation *)ptr[0])->awake;
      }
      dds_return_loan(st->deformation_r, ptr, 1);
    }
    test_sleep(0.01);
  }
}

int main(void) {
  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  test_server ts = {0};
  test_server_start(&ts, &cfg);
  palp_cli_station tr, vis;
  test_station_join(&tr, DOMAIN, "trainee", palp_ROLE_TRAINEE, 1, 0, 1, 0);

  /* The full mesh is sent only while a member asked for it: a deformation reader
   * in the trainee's partition sees nothing while the trainee (who did not ask)
   * presses alone, then the display rate (30 Hz) once a visual station joins. */
  dds_entity_t spy = palp_dds_create_reader(tr.sub, tr.topic[PALP_TOPIC_DEFORMATION], PALP_TOPIC_DEFORMATION);
  uint64_t seq = 0;
  int spied = 0;
  for (int i = 0; i < 60; i++) { /* 0.6 s of pressing, world awake */
    test_send_force(&tr, 0, 2, 30, 40, 1.0, ++seq);
    test_sleep(0.01);
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(spy, ptr, &info, 1, 1) > 0) {
      spied += info.valid_data;
      dds_return_loan(spy, ptr, 1);
    }
  }
  CHECK(spied == 0, "no deformation sample while no member asked for one (%d seen in 0.6 s)", spied);
  test_station_join(&vis, DOMAIN, "visual", palp_ROLE_VISUAL, 1, 0, 0, 1);
  spied = 0;
  int64_t t_spy = palp_dds_now_ns();
  while (palp_dds_now_ns() - t_spy < 1000000000) { /* 1 s, still pressing */
    test_send_force(&tr, 0, 2, 30, 40, 1.0, ++seq);
    test_sleep(0.005);
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(spy, ptr, &info, 1, 1) > 0) {
      spied += info.valid_data;
      dds_return_loan(spy, ptr, 1);
    }
  }
  /* 30 Hz for 1 s: 30 frames; +4 for the window edges and the 5 ms polling: never above the stream's
   * 30 Hz cap. Below, 18: a server starved among the first tests of a fresh clone's run sent 22
   * (session 84; 26 had been the bound); 18 still fails a stream at half its rate (15 Hz). */
  CHECK(spied >= 18 && spied <= 34, "%d deformation frames in 1 s with a visual station (want 30, 18-34: the 30 Hz "
        "cap, and at least 60%% of it on a loaded machine)", spied);
  dds_delete(spy);
  for (int i = 0; i < 3; i++) { /* lift and let it recover before the measured press */
    test_send_force(&tr, 0, 2, 30, 40, 0.0, ++seq);
    test_sleep(0.01);
  }
  test_sleep(1.5);
  CHECK(vis.session_id == tr.session_id, "the visual station follows the trainee's session %u (got %u)", tr.session_id,
        vis.session_id);
  char err[256];
  palp_Phantom ph;
  REQUIRE(palp_cli_station_catalogue(&vis, 1, 5, &ph, err, sizeof err) == 0, "catalogue %s", err);

  double d0 = 0;
  palp_Vec3 at0 = {0, 0, 0};
  latest_deformation(&vis, &ph, 0.3, &d0, &at0); /* the shape before the measured press */

  /* 3 N (the paper's force) along the inward normal, distribution II, at polar
   * 30 deg, azimuth 40 deg, resent at 100 Hz for 1.5 s. */
  int64_t end = palp_dds_now_ns() + 1500000000;
  while (palp_dds_now_ns() < end) {
    test_send_force(&tr, 0, 2, 30, 40, 3.0, ++seq);
    test_sleep(0.01);
  }
  int n = 0;
  double f = test_last_feedback(&tr, 0.1, &n);
  /* Quasi-static after 1.5 s (the model relaxes within ~1 s): the phantom pushes
   * back with the applied force, Newton's third law; 10 % covers the residual creep. */
  CHECK(n > 0 && fabs(f - 3.0) < 0.3, "feedback |F| = %.3f N while pressing with 3 N (tolerance 0.3 N), %d samples", f, n);
  double d1 = 0;
  palp_Vec3 at1 = {0, 0, 0};
  int got = latest_deformation(&vis, &ph, 0.2, &d1, &at1);
  palp_vec3 p = palp_cli_dome_point(0.04, 30, 40, NULL);
  double dist = sqrt((at1.x - p.x) * (at1.x - p.x) + (at1.y - p.y) * (at1.y - p.y) + (at1.z - p.z) * (at1.z - p.z));
  CHECK(got && d1 > 1e-3, "pressing displaces the surface by %.2f mm (want > 1 mm; rest frame showed %.3f mm)", d1 * 1e3,
        d0 * 1e3);
  /* The patch of 5.2 cm^2 has a radius of 1.3 cm; the largest displacement is inside it. */
  CHECK(got && dist < 0.013, "largest displacement %.1f mm from the contact centre (want < 13 mm, the patch radius)",
        dist * 1e3);

  /* Lift: the finger's feedback goes to zero and the dome recovers (paper: ~1 s). */
  for (int i = 0; i < 3; i++) {
    test_send_force(&tr, 0, 2, 30, 40, 0.0, ++seq);
    test_sleep(0.01);
  }
  test_sleep(2.0);
  f = test_last_feedback(&tr, 0.3, &n);
  /* n > 0: no feedback at all would read 0 N too (test_last_feedback's default) */
  CHECK(n > 0 && f < 1e-9, "feedback after lifting: %.3g N in the last of %d samples (want 0: no contact, from "
                           "samples received)", f, n);
  double d2 = 1;
  latest_deformation(&vis, &ph, 0.3, &d2, &at1);
  CHECK(d2 < 0.3 * d1, "2 s after lifting the displacement fell from %.2f to %.2f mm (want < 30 %%)", d1 * 1e3, d2 * 1e3);

  /* The displays read palp_deformation best-effort (a reliable reader holds newer frames behind a
   * lost one), so a sleeping world's shape is sent again once a second: a lost last frame is
   * repaired within a second, and a display that joins a sleeping session sees its shape at once. */
  dds_qos_t *rq = dds_create_qos();
  dds_reliability_kind_t rk = DDS_RELIABILITY_RELIABLE;
  REQUIRE(dds_get_qos(vis.deformation_r, rq) == 0 && dds_qget_reliability(rq, &rk, NULL), "the display reader's QoS");
  dds_delete_qos(rq);
  CHECK(rk == DDS_RELIABILITY_BEST_EFFORT, "the station's deformation reader is best-effort (got reliability kind %d)",
        (int)rk);
  int all = 0, asleep = 0;
  for (int i = 0; i < 20 && asleep == 0; i++) count_frames(&vis, 0.5, &all, &asleep); /* until it sleeps */
  REQUIRE(asleep > 0, "the released dome falls asleep within 10 s");
  count_frames(&vis, 3.5, &all, &asleep);
  /* 1 Hz over 3.5 s: 3 or 4 frames; 2 and 5 for the window's edges on a loaded machine. */
  CHECK(all >= 2 && all <= 5 && asleep == all,
        "a sleeping world's shape is sent again once a second: %d frames in 3.5 s, %d asleep (want 2-5, all asleep)",
        all, asleep);
  /* Joined right after a repeat (the other display just took one), so the next repeat is ~1 s away:
   * a first frame well before it can only be the one sent at the join. */
  all = 0;
  for (int i = 0; i < 30 && all == 0; i++) count_frames(&vis, 0.05, &all, &asleep);
  REQUIRE(all > 0, "a repeat within 1.5 s");
  palp_cli_station late;
  const int64_t t_join = palp_dds_now_ns();
  test_station_join(&late, DOMAIN, "late visual", palp_ROLE_VISUAL, 1, tr.session_id, 0, 1);
  int late_frames = 0;
  double late_s = -1;
  while (palp_dds_now_ns() - t_join < 3000000000LL && late_frames == 0) {
    int a = 0, z = 0;
    count_frames(&late, 0.02, &a, &z);
    late_frames += a;
    if (a) late_s = (double)(palp_dds_now_ns() - t_join) * 1e-9;
  }
  /* Before: nothing until the trainee touched again; sent only with the repeats, ~1 s after the one
   * just taken. The join itself (a new participant, discovery, the reply) took 0.02 s on this machine. */
  CHECK(late_frames > 0 && late_s < 0.7,
        "a display joining the sleeping session sees its shape %.2f s after it asked, a repeat having just "
        "passed (want < 0.7 s: before the next repeat)", late_s);
  palp_cli_station_leave(&late);
  palp_cli_station_close(&late);

  palp_cli_phantom_free(&ph);
  palp_cli_station_leave(&vis);
  palp_cli_station_leave(&tr);
  test_sleep(0.2);
  palp_cli_station_close(&vis);
  palp_cli_station_close(&tr);
  test_server_stop(&ts);
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
