#include "sim.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define DEG (3.14159265358979323846 / 180.0)

static palp_vec3 on_sphere(double r, double polar_deg, double az_deg) {
  palp_vec3 p = {r * sin(polar_deg * DEG) * cos(az_deg * DEG), r * sin(polar_deg * DEG) * sin(az_deg * DEG),
                 r * cos(polar_deg * DEG)};
  return p;
}

static void keep_contact(sim_result *r, const palp_db_contact *c) {
  palp_db_contact *n = realloc(r->contacts, (size_t)(r->ncontacts + 1) * sizeof *n);
  if (!n) return;
  r->contacts = n;
  r->contacts[r->ncontacts++] = *c;
}

static void count(sim_result *r, int rc) {
  if (rc == PALP_EFULL) r->records_refused++;
  else if (rc) r->log_errors++;
}

int sim_run(const sim_opts *o, sim_result *r) {
  memset(r, 0, sizeof *r);
  palp_scene sc;
  char err[512];
  int rc = palp_scene_load(o->scene_path, &sc, err, sizeof err);
  if (rc) {
    fprintf(stderr, "sim: %s: %s\n", o->scene_path, err);
    return rc;
  }
  const double dt = 1.0 / o->tick_hz;
  sc.world.dt = dt;
  char *scene_json = palp_scene_to_json(&sc); /* self-contained: parameters inlined */
  if (!scene_json) return PALP_ENOMEM;
  palp_world *w = palp_db_world_from_scene(scene_json, dt, &rc, err, sizeof err);
  if (!w) {
    fprintf(stderr, "sim: %s\n", err);
    free(scene_json);
    return rc;
  }
  palp_db_writer_opts wo = palp_db_writer_default_opts();
  wo.max_db_bytes = o->max_db_bytes;
  if (o->max_db_bytes) {
    wo.retry_backoff_s = 0.01;
    wo.retry_limit = 2;
  }
  palp_db_writer *lw;
  if ((rc = palp_db_writer_open(o->db, &wo, &lw, err, sizeof err))) {
    fprintf(stderr, "sim: %s\n", err);
    palp_world_destroy(w);
    free(scene_json);
    return rc;
  }
  palp_db_session_def sd = {.uid = o->uid, .trainee = "trainee-07", .station = "haptic-station-2",
                            .phantom_id = "phantom-a", .phantom_name = sc.name, .scene_json = scene_json,
                            .params_json = "{\"force_limit_n\": 20}", .tick_hz = o->tick_hz, .dt_s = dt};
  palp_db_session s;
  if ((rc = palp_db_log_session_begin(lw, &sd, &s))) {
    fprintf(stderr, "sim: session_begin: %d\n", rc);
    palp_db_writer_close(lw);
    palp_world_destroy(w);
    free(scene_json);
    return rc;
  }
  free(scene_json);
  const double R = sc.world.mesh.radius;
  const int64_t nframes = (int64_t)llround(o->seconds * o->tick_hz);
  /* The script, in seconds: a Gaussian press ramped 0 -> 3 N over [0.05, 0.45] s, held, released
   * at 0.9 s; a finger (8 mm) pressing 1.5 mm into the far side from 0.3 s, sliding 30 degrees of
   * azimuth until it lifts at 1.3 s. Repeats every 1.5 s for longer sessions. */
  const int64_t period = (int64_t)llround(1.5 * o->tick_hz);
  int force_id = -1, finger_id = -1;
  palp_vec3 press_n = {0, 0, 0};
  count(r, palp_db_log_event(lw, s, PALP_DB_EVENT_JOIN, 0, "trainee-07 joined as trainee", 1));
  r->events++;
  struct timespec next;
  clock_gettime(CLOCK_MONOTONIC, &next);
  palp_vec3 fb_buf;
  for (int64_t i = 0; i < nframes; i++) {
    const int64_t f = palp_world_frame(w);
    const double t = palp_world_time(w);
    const int64_t ph = f % period;
    const double tp = (double)ph / o->tick_hz;
    /* Every contact change goes through the logged world calls (db/world_log.c), as the server's
     * should; the test keeps its own copy of what it asked for, to compare with the export. */
    palp_db_contact c;
    if (ph == (int64_t)llround(0.05 * o->tick_hz)) {
      palp_vec3 ctr = on_sphere(R, 20.0 + 5.0 * (double)(f / period), 40.0);
      press_n = (palp_vec3){-ctr.x / R, -ctr.y / R, -ctr.z / R}; /* inward normal */
      c = (palp_db_contact){.frame = f, .sim_time_s = t, .op = PALP_DB_OP_ADD, .kind = PALP_DB_KIND_FORCE,
                            .def = palp_contact_default_def(PALP_DIST_GAUSSIAN, ctr)};
      force_id = palp_db_world_add_contact(lw, s, w, &c.def, c.force_n);
      c.slot = force_id;
      c.center_m = ctr;
      if (o->keep) keep_contact(r, &c);
    } else if (force_id >= 0 && ph % 10 == 0 && tp <= 0.46) { /* ramp at 100 Hz, as a slower station would */
      const double mag = 3.0 * fmin(1.0, (tp - 0.05) / 0.4);
      c = (palp_db_contact){.frame = f, .sim_time_s = t, .slot = force_id, .op = PALP_DB_OP_UPDATE,
                            .kind = PALP_DB_KIND_FORCE,
                            .force_n = {mag * press_n.x, mag * press_n.y, mag * press_n.z}};
      palp_db_world_set_contact_force(lw, s, w, force_id, c.force_n);
      if (o->keep) keep_contact(r, &c);
    } else if (force_id >= 0 && ph == (int64_t)llround(0.9 * o->tick_hz)) {
      c = (palp_db_contact){.frame = f, .sim_time_s = t, .slot = force_id, .op = PALP_DB_OP_REMOVE,
                            .kind = PALP_DB_KIND_FORCE};
      palp_db_world_remove_contact(lw, s, w, force_id, PALP_DB_KIND_FORCE);
      force_id = -1;
      if (o->keep) keep_contact(r, &c);
    }
    if (ph >= (int64_t)llround(0.3 * o->tick_hz) && ph < (int64_t)llround(1.3 * o->tick_hz)) {
      const double u = (tp - 0.3) / 1.0; /* 0..1 over the slide */
      palp_vec3 ctr = on_sphere(R + 0.008 - 0.0015, 35.0, 200.0 + 30.0 * u);
      c = (palp_db_contact){.frame = f, .sim_time_s = t, .kind = PALP_DB_KIND_FINGER, .center_m = ctr,
                            .radius_m = 0.008};
      if (finger_id < 0) {
        c.op = PALP_DB_OP_ADD;
        finger_id = palp_db_world_add_finger(lw, s, w, ctr, 0.008);
      } else {
        c.op = PALP_DB_OP_UPDATE;
        palp_db_world_set_finger(lw, s, w, finger_id, ctr, 0.008);
      }
      c.slot = finger_id;
      if (o->keep) keep_contact(r, &c);
    } else if (finger_id >= 0) {
      c = (palp_db_contact){.frame = f, .sim_time_s = t, .slot = finger_id, .op = PALP_DB_OP_REMOVE,
                            .kind = PALP_DB_KIND_FINGER};
      palp_db_world_remove_contact(lw, s, w, finger_id, PALP_DB_KIND_FINGER);
      finger_id = -1;
      if (o->keep) keep_contact(r, &c);
    }
    if (ph == (int64_t)llround(1.0 * o->tick_hz)) { /* a station sent a NaN force: rejected, not applied */
      count(r, palp_db_log_event(lw, s, PALP_DB_EVENT_REJECT, f, "force sample with NaN component", 1));
      r->events++;
    }

    palp_db_frame fr;
    if (palp_db_world_step(lw, s, w, &fr) != 0) { /* steps and logs the frame summary */
      fprintf(stderr, "sim: the world refused to step at frame %lld\n", (long long)f);
      break;
    }
    r->frames_stepped++;
    if (o->keep) {
      palp_db_frame *n = realloc(r->frames, (size_t)(r->nframes + 1) * sizeof *n);
      if (n) (r->frames = n)[r->nframes++] = fr;
    }
    const int ids[2] = {force_id, finger_id};
    for (int k = 0; k < 2; k++) {
      if (ids[k] < 0 || palp_world_contact_feedback(w, ids[k], &fb_buf) != 0) continue;
      count(r, palp_db_log_feedback(lw, s, fr.frame, ids[k], fb_buf));
      if (o->keep) {
        sim_sent_fb *n = realloc(r->fb, (size_t)(r->nfb + 1) * sizeof *n);
        if (n) (r->fb = n)[r->nfb++] = (sim_sent_fb){fr.frame, ids[k], fb_buf};
      }
    }
    if (fr.frame % 33 == 0) { /* ~30 Hz at 1 kHz */
      const palp_mesh *m = palp_world_mesh(w);
      count(r, palp_db_log_mesh(lw, s, fr.frame, palp_world_positions(w), m->vertex_count));
      r->meshes++;
    }
    if (o->progress && fr.frame % 10 == 0) {
      /* Frames the writer accepted: stepped minus the frame records it shed. */
      palp_db_writer_stats_get(lw, &r->st);
      printf("frames %lld\n", (long long)(r->frames_stepped - r->st.shed_by_kind[PALP_DB_REC_FRAME]));
      fflush(stdout);
    }
    if (o->realtime) {
      next.tv_nsec += (long)(1e9 / o->tick_hz);
      while (next.tv_nsec >= 1000000000L) next.tv_nsec -= 1000000000L, next.tv_sec++;
      while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL) == EINTR) {
      }
    }
  }
  count(r, palp_db_log_event(lw, s, PALP_DB_EVENT_LEAVE, palp_world_frame(w), "trainee-07 left", 1));
  r->events++;
  count(r, palp_db_log_session_end(lw, s, PALP_DB_END_NORMAL, "station closed the session", 0));
  palp_db_writer_flush(lw, 30);
  palp_db_writer_stats_get(lw, &r->st);
  r->frames_logged = r->frames_stepped - r->st.shed_by_kind[PALP_DB_REC_FRAME];
  palp_db_writer_close(lw);
  palp_world_destroy(w);
  return 0;
}

void sim_result_free(sim_result *r) {
  free(r->frames);
  free(r->contacts);
  free(r->fb);
  memset(r, 0, sizeof *r);
}
