/*
 * recorder.h - the scripted trainees of client/trainee.c (the same code a station runs
 * over DDS: --input sim:expert / sim:novice) driving a fingertip in an in-process
 * palp_world, and the recorder that turns each step into a palp_assess_sample (the
 * fields the server logs: time, device, proxy, force, contact point, footprint area,
 * touched triangles). Shared by the assessment tests; header-only, static functions.
 *
 * Trainees know where their own hand is (the device point) and what they feel (the
 * force), never where the lesions are.
 */
#ifndef PALP_TEST_RECORDER_H
#define PALP_TEST_RECORDER_H
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h"
#include "palp_assess.h"
#include "trainee.h" /* client/ */

#define TR_PI 3.14159265358979323846

typedef struct recorder {
  palp_world *w;
  int finger;
  double R, r; /* dome and fingertip radii [m] */
  palp_assess_sample *s;
  size_t *tri_at; /* offset of each sample's triangles in tri */
  int n, cap;
  int *tri;
  size_t ntri, tricap;
  palp_vec3 device;
  int failed;
} recorder;

static inline int rec_init(recorder *rc, palp_world *w, double R, double r, palp_vec3 start) {
  memset(rc, 0, sizeof *rc);
  rc->w = w, rc->R = R, rc->r = r, rc->device = start;
  palp_finger_def fd = palp_finger_default_def();
  fd.radius = r;
  rc->finger = palp_world_add_finger_def(w, &fd, start);
  return rc->finger;
}

/* One physics step with the device at `dev`, recorded. */
static inline void rec_step(recorder *rc, palp_vec3 dev) {
  if (rc->failed) return;
  rc->device = dev;
  if (palp_world_set_finger_device(rc->w, rc->finger, dev) || palp_world_step(rc->w)) {
    rc->failed = 1;
    return;
  }
  if (rc->n == rc->cap) {
    rc->cap = rc->cap ? 2 * rc->cap : 4096;
    rc->s = realloc(rc->s, sizeof *rc->s * (size_t)rc->cap);
    rc->tri_at = realloc(rc->tri_at, sizeof *rc->tri_at * (size_t)rc->cap);
    if (!rc->s || !rc->tri_at) {
      rc->failed = 1;
      return;
    }
  }
  palp_local_model lm;
  palp_world_finger_local_model(rc->w, rc->finger, &lm);
  int tri[128];
  double tf[128];
  int nt = palp_world_finger_contacts(rc->w, rc->finger, tri, tf, 128);
  if (nt < 0) nt = 0;
  if (rc->ntri + (size_t)nt > rc->tricap) {
    rc->tricap = rc->tricap ? 2 * rc->tricap + (size_t)nt : 65536;
    rc->tri = realloc(rc->tri, sizeof *rc->tri * rc->tricap);
    if (!rc->tri) {
      rc->failed = 1;
      return;
    }
  }
  if (nt > 0) memcpy(rc->tri + rc->ntri, tri, sizeof(int) * (size_t)nt); /* rc->tri is NULL until a contact */
  palp_assess_sample *s = &rc->s[rc->n];
  *s = (palp_assess_sample){.t = palp_world_time(rc->w), .device = dev, .proxy = lm.proxy, .force = lm.force,
                            .contact = lm.contact, .point = lm.point, .area = lm.area, .triangle_count = nt};
  rc->tri_at[rc->n] = rc->ntri;
  rc->ntri += (size_t)nt;
  rc->n++;
}

/* Pointers into the triangle pool, once recording is over (it may have moved). */
static inline void rec_finish(recorder *rc) {
  for (int i = 0; i < rc->n; ++i) rc->s[i].triangles = rc->s[i].triangle_count ? rc->tri + rc->tri_at[i] : NULL;
}

static inline void rec_free(recorder *rc) {
  free(rc->s), free(rc->tri_at), free(rc->tri);
  memset(rc, 0, sizeof *rc);
}

/* ---- the client's trainees on the recorder ------------------------------------------ */
static inline int rec_hand_step(void *ctx, palp_vec3 dev, palp_vec3 *force, double *t) {
  recorder *rc = ctx;
  rec_step(rc, dev);
  if (rc->failed) return -1;
  *force = rc->s[rc->n - 1].force;
  *t = rc->s[rc->n - 1].t;
  return 0;
}

static inline void rec_hand(recorder *rc, palp_cli_hand *h) {
  palp_cli_hand_init(h, rc, rec_hand_step, palp_world_get_def(rc->w)->dt, rc->R, rc->r, rc->device);
}

typedef palp_cli_expert_spot expert_spot;
typedef palp_cli_expert_cfg expert_cfg;
static inline expert_cfg expert_default(void) { return palp_cli_expert_default(); }

static inline expert_spot *expert_exam(recorder *rc, const expert_cfg *cfg, int *count) {
  palp_cli_hand h;
  rec_hand(rc, &h);
  return palp_cli_expert_exam(&h, cfg, count);
}

/* Marks a lump at the strongest spot of each cluster of spots rising more than
 * `threshold` above their surroundings (clusters: spots within `cluster`). */
static inline int expert_findings(const recorder *rc, const expert_spot *sp, int n, double threshold, double cluster,
                                  palp_finding *out, int cap, double *max_rise_out) {
  palp_cli_hand h;
  rec_hand((recorder *)rc, &h);
  expert_cfg cfg = expert_default();
  cfg.threshold = threshold, cfg.cluster = cluster;
  palp_vec3 p[64];
  double t[64];
  const int nf = palp_cli_expert_lumps(&h, sp, n, &cfg, p, t, cap < 64 ? cap : 64, max_rise_out);
  for (int i = 0; i < nf; ++i) out[i] = (palp_finding){.t = t[i], .point = p[i], .withdrawn = 0};
  return nf;
}

static inline void novice_exam(recorder *rc, int presses, double depth, unsigned seed, palp_vec3 *last_press) {
  palp_cli_hand h;
  rec_hand(rc, &h);
  palp_cli_novice_exam(&h, presses, depth, seed, last_press, NULL, NULL);
}
#endif
