/*
 * eval_record.c - a run of the real-time model as a per-frame record.
 *
 * The loop is palp-run's (tools/run/palp_run.c), palp-sweep's too: before step q of
 * frame f the scene's profiles are applied at palp_scene_step_time, f * frame_period
 * + q * dt, the FEM's expression (src/fem/fem_run.c), not at the world's clock. The
 * world sums its time step by step (t += dt), and 0.01 added ten times is
 * 0.09999999999999999, not 0.1: a step edge at t_off = 0.1 s (or 2.5, 3.0, 3.5 s,
 * about half of the 10 ms edges in a 4 s run) then loaded the real-time model one
 * step longer than the FEM, and the comparison booked that extra 10 ms of load as
 * model error (session 82 review). Both models on one clock compare the models.
 * After the frame's last sub-step the state is read back, so frame f holds the
 * state at t = (f + 1) * frame_period, the time stamp the FEM reference uses too.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "eval.h"

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void palp_eval_record_destroy(palp_eval_record *r) {
  if (!r) return;
  free(r->time);
  free(r->disp);
  free(r->fixed);
  free(r->contact_vertex);
  free(r->contact_of);
  free(r->feedback);
  memset(r, 0, sizeof *r);
}

/* Contact vertices of every contact, in contact order. Returns the count. */
static int gather_contact_vertices(const palp_world *w, int contacts, int *vert, int *of, palp_vec3 *fb, int cap) {
  int n = 0;
  for (int c = 0; c < contacts; ++c) {
    int k = palp_world_contact_vertices(w, c, vert ? vert + n : NULL, fb ? fb + n : NULL, cap - n);
    if (k < 0) return k;
    if (k > cap - n) k = cap - n;
    if (of)
      for (int i = 0; i < k; ++i) of[n + i] = c;
    n += k;
  }
  return n;
}

int palp_eval_run_rt(const palp_scene *s, palp_eval_record *out, char *err, size_t errlen) {
  const double t0 = now_s();
  memset(out, 0, sizeof *out);
  if (err && errlen) err[0] = 0;
  if (s->frames < 1 || !(s->frame_period > 0) || !(s->world.dt > 0)) {
    snprintf(err, errlen, "scene: frames and frame period must be positive");
    return PALP_EINVAL;
  }
  int rc;
  palp_world *w = palp_scene_create_world(s, &rc);
  if (!w) {
    snprintf(err, errlen, "cannot create the real-time world: %s", palp_strerror(rc));
    return rc ? rc : PALP_EINVAL;
  }
  const palp_mesh *m = palp_world_mesh(w);
  const int nv = m->vertex_count, sub = (int)lround(s->frame_period / s->world.dt);
  /* Every contact's vertex set is fixed at creation; size it once. */
  const int cap = nv;
  int *vbuf = malloc(sizeof(int) * (size_t)cap);
  palp_vec3 *fbuf = malloc(sizeof(palp_vec3) * (size_t)cap);
  out->frames = s->frames;
  out->vertex_count = nv;
  out->top_vertex = m->top_vertex;
  out->time = malloc(sizeof(double) * (size_t)s->frames);
  out->disp = malloc(sizeof(palp_vec3) * (size_t)s->frames * (size_t)nv);
  out->fixed = malloc((size_t)nv);
  rc = (vbuf && fbuf && out->time && out->disp && out->fixed) ? PALP_OK : PALP_ENOMEM;
  int nc = 0;
  if (!rc) {
    memcpy(out->fixed, m->fixed, (size_t)nv);
    const int with_feedback = (s->world.effects & PALP_EFFECT_FORCE_FEEDBACK) != 0;
    nc = with_feedback ? gather_contact_vertices(w, s->contact_count, vbuf, NULL, NULL, cap) : 0;
    if (nc < 0) rc = nc, nc = 0;
  }
  if (!rc && nc > 0) {
    out->contact_vertex_count = nc;
    out->contact_vertex = malloc(sizeof(int) * (size_t)nc);
    out->contact_of = malloc(sizeof(int) * (size_t)nc);
    out->feedback = malloc(sizeof(palp_vec3) * (size_t)nc * (size_t)s->frames);
    if (!out->contact_vertex || !out->contact_of || !out->feedback) rc = PALP_ENOMEM;
    else gather_contact_vertices(w, s->contact_count, out->contact_vertex, out->contact_of, NULL, nc);
  }
  for (int f = 0; !rc && f < s->frames; ++f) {
    for (int q = 0; !rc && q < sub; ++q) {
      /* the FEM's clock (see the top of the file), not palp_world_time(w) */
      rc = palp_scene_apply(s, w, palp_scene_step_time(s, f, q));
      if (!rc) rc = palp_world_step(w);
    }
    if (rc) {
      snprintf(err, errlen, "real-time model, frame %d: %s", f, palp_strerror(rc));
      break;
    }
    const palp_vec3 *p = palp_world_positions(w);
    palp_vec3 *d = out->disp + (size_t)f * (size_t)nv;
    int finite = 1;
    for (int i = 0; i < nv; ++i) {
      d[i] = (palp_vec3){p[i].x - m->rest[i].x, p[i].y - m->rest[i].y, p[i].z - m->rest[i].z};
      finite &= isfinite(d[i].x) && isfinite(d[i].y) && isfinite(d[i].z);
    }
    out->time[f] = palp_world_time(w);
    if (!finite) {
      rc = PALP_EUNSTABLE;
      snprintf(err, errlen, "real-time model, frame %d: non-finite displacement", f);
      break;
    }
    if (nc > 0) {
      int k = gather_contact_vertices(w, s->contact_count, vbuf, NULL, fbuf, cap);
      if (k != nc) {
        rc = k < 0 ? k : PALP_ERANGE;
        snprintf(err, errlen, "real-time model, frame %d: contact vertex set changed", f);
        break;
      }
      memcpy(out->feedback + (size_t)f * (size_t)nc, fbuf, sizeof(palp_vec3) * (size_t)nc);
    }
  }
  if (rc && err && !err[0]) snprintf(err, errlen, "real-time model: %s", palp_strerror(rc));
  free(vbuf);
  free(fbuf);
  palp_world_destroy(w);
  if (rc) {
    palp_eval_record_destroy(out);
    return rc;
  }
  out->wall_seconds = now_s() - t0;
  return PALP_OK;
}
