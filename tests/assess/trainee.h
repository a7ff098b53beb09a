/*
 * trainee.h - scripted trainees driving a fingertip in an in-process palp_world, and
 * the recorder that turns each step into a palp_assess_sample (the fields the server
 * will log: time, device, proxy, force, contact point, footprint area, touched
 * triangles). Shared by the assessment tests; header-only, static functions.
 *
 * Trainees know where their own hand is (the device point) and what they feel (the
 * force), never where the lesions are.
 */
#ifndef PALP_TEST_TRAINEE_H
#define PALP_TEST_TRAINEE_H
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h"
#include "palp_assess.h"

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
  memcpy(rc->tri + rc->ntri, tri, sizeof(int) * (size_t)nt);
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

static inline double rec_dt(const recorder *rc) { return palp_world_get_def(rc->w)->dt; }

/* Moves the device in a straight line at `speed` [m/s]. */
static inline void move_to(recorder *rc, palp_vec3 to, double speed) {
  const palp_vec3 a = rc->device;
  const double L = sqrt((to.x - a.x) * (to.x - a.x) + (to.y - a.y) * (to.y - a.y) + (to.z - a.z) * (to.z - a.z));
  const int k = (int)ceil(L / (speed * rec_dt(rc)));
  for (int i = 1; i <= k; ++i) {
    const double u = (double)i / k;
    rec_step(rc, (palp_vec3){a.x + u * (to.x - a.x), a.y + u * (to.y - a.y), a.z + u * (to.z - a.z)});
  }
}

static inline void hold(recorder *rc, double seconds) {
  const int k = (int)lround(seconds / rec_dt(rc));
  for (int i = 0; i < k; ++i) rec_step(rc, rc->device);
}

static inline double force_now(const recorder *rc) {
  const palp_vec3 f = rc->s[rc->n - 1].force;
  return sqrt(f.x * f.x + f.y * f.y + f.z * f.z);
}

/* The device `depth` [m] below the rest surface along the normal n, never below the
 * table the phantom stands on (a hand stops there: near the rim it presses sideways). */
static palp_vec3 device_at(const recorder *rc, palp_vec3 n, double depth) {
  const double q = rc->R + rc->r - depth;
  palp_vec3 d = {q * n.x, q * n.y, q * n.z};
  if (d.z < rc->r) d.z = rc->r;
  return d;
}

/* ---- the expert: vertical strips, three pressures at every spot ---------------- */
/* MammaCare's vertical strip: parallel strips (planes x = const, so straight lines seen
 * from above), spots along each strip 8 mm apart on the surface, strips 8 mm apart; at
 * every spot the fingertip presses light -> medium -> deep and back, and glides to the
 * next spot at the light depth without lifting. */
typedef struct expert_spot {
  palp_vec3 n;      /* unit normal (the spot's direction from the dome's centre) */
  double t;         /* when pressed [s] */
  double f_medium;  /* force held at the medium depth [N] */
  double f_deep;    /* force held at the deep depth [N] */
  int free;         /* the deep press went along the normal, clear of the table */
} expert_spot;

#define RISE_R_IN 0.012
#define RISE_R_OUT 0.028
typedef struct expert_cfg {
  double spacing;         /* [m] between spots and strips */
  double d_light, d_medium, d_deep; /* device depths [m] */
  double press_speed, glide_speed;  /* [m/s] */
  double hold;            /* [s] at each depth */
  double min_nz;          /* spots down to this normal z (rim margin) */
  double keep_force;      /* light touch kept while rising and gliding [N] */
  double patience;        /* longest wait for the dent to recover to the light depth [s] */
} expert_cfg;

static inline expert_cfg expert_default(void) {
  return (expert_cfg){.spacing = 0.008, .d_light = 0.003, .d_medium = 0.009, .d_deep = 0.016,
                      .press_speed = 0.05, .glide_speed = 0.05, .hold = 0.12, .min_nz = 0.06,
                      .keep_force = 0.05, .patience = 0.3};
}

/* Moves the hand to depth `d` [m] at spot normal `to`, gliding over the surface at
 * `speed` and pressing at `vz` [m/s]. Rising is allowed only while the finger still
 * feels at least `keep` [N]: an examiner keeps a light touch, so the finger follows the
 * dent as it recovers (the phantom's gel recovers in about a second, docs/model.md)
 * instead of leaving the surface. Gives up rising after `patience` [s]. */
typedef struct hand {
  palp_vec3 n; /* current spot normal */
  double d;    /* current depth [m] */
} hand;
static inline void travel(recorder *rc, hand *h, palp_vec3 to, double d, double speed, double vz, double keep,
                          double patience) {
  const double dt = rec_dt(rc);
  const palp_vec3 from = h->n;
  const double arc = rc->R * acos(fmax(-1.0, fmin(1.0, from.x * to.x + from.y * to.y + from.z * to.z)));
  const int k = arc > 0 ? (int)ceil(arc / (speed * dt)) : 0;
  const int limit = k + (int)ceil((fabs(d - h->d) / vz + patience) / dt);
  for (int i = 1; i <= limit; ++i) {
    if (i <= k) {
      const double u = (double)i / k;
      palp_vec3 n = {from.x + u * (to.x - from.x), from.y + u * (to.y - from.y), from.z + u * (to.z - from.z)};
      const double l = sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
      h->n = (palp_vec3){n.x / l, n.y / l, n.z / l};
    }
    if (h->d < d) h->d = fmin(d, h->d + vz * dt);
    else if (h->d > d && (rc->n == 0 || force_now(rc) >= keep)) h->d = fmax(d, h->d - vz * dt);
    rec_step(rc, device_at(rc, h->n, h->d));
    if (i >= k && fabs(h->d - d) < 1e-12) break;
  }
}

/* Runs the exam; returns the spots (malloc'd) and their count in *count. */
static expert_spot *expert_exam(recorder *rc, const expert_cfg *cfg, int *count) {
  const double R = rc->R;
  const double da = cfg->spacing / R;
  const int na = (int)floor((TR_PI / 2.0) / da);
  expert_spot *sp = NULL;
  int n = 0, cap = 0, strip = 0;
  hand h = {{0, 0, 1}, 0.0};
  for (int ia = -na; ia <= na; ++ia, ++strip) {
    const double a = ia * da, ca = cos(a);
    if (ca < cfg->min_nz) continue;
    /* b such that cos a cos b >= min_nz */
    const double bmax = acos(fmin(1.0, cfg->min_nz / ca));
    const double db = cfg->spacing / (R * ca);
    const int nb = (int)floor(bmax / db);
    for (int k = -nb; k <= nb; ++k) {
      const int kb = (strip % 2) ? -k : k; /* boustrophedon */
      const double b = kb * db;
      const palp_vec3 nrm = {sin(a), ca * sin(b), ca * cos(b)};
      if (n == cap) {
        cap = cap ? 2 * cap : 256;
        sp = realloc(sp, sizeof *sp * (size_t)cap);
        if (!sp) return NULL;
      }
      expert_spot *s = &sp[n++];
      s->n = nrm;
      if (n == 1) { /* first spot: come down onto it from where the hand is */
        move_to(rc, device_at(rc, nrm, 0.0), cfg->glide_speed);
        h.n = nrm, h.d = 0.0;
      }
      travel(rc, &h, nrm, cfg->d_light, cfg->glide_speed, cfg->press_speed, cfg->keep_force, cfg->patience);
      s->t = palp_world_time(rc->w);
      travel(rc, &h, nrm, cfg->d_medium, cfg->glide_speed, cfg->press_speed, cfg->keep_force, 0.0);
      hold(rc, cfg->hold);
      s->f_medium = force_now(rc);
      travel(rc, &h, nrm, cfg->d_deep, cfg->glide_speed, cfg->press_speed, cfg->keep_force, 0.0);
      hold(rc, cfg->hold);
      s->f_deep = force_now(rc);
      s->free = (R + rc->r - cfg->d_deep) * nrm.z >= rc->r;
    }
  }
  *count = n;
  return sp;
}

/* The rise of a free spot's force at the medium depth over its surroundings at the
 * same depth: a quadratic surface c0 + g . u + u^T H u (u: tangent-plane offset)
 * fitted by least squares to the free spots between r_in and r_out away, so that the
 * dome's own smooth change of stiffness across the surface (highest at the pole and
 * towards the fixed rim, lowest half-way) is not taken for a lump. Returns F / c0 - 1,
 * or NAN with fewer than 10 neighbours. */
static inline double expert_rise(const recorder *rc, const expert_spot *sp, int n, int i, double r_in, double r_out) {
  enum { P = 6 };
  double A[P][P + 1] = {{0}};
  int m = 0;
  const palp_vec3 pi = sp[i].n;
  /* a tangent basis at spot i */
  palp_vec3 e1 = fabs(pi.z) < 0.9 ? (palp_vec3){-pi.y, pi.x, 0} : (palp_vec3){1, 0, 0};
  const double ndote = pi.x * e1.x + pi.y * e1.y + pi.z * e1.z;
  e1 = (palp_vec3){e1.x - ndote * pi.x, e1.y - ndote * pi.y, e1.z - ndote * pi.z};
  const double l = sqrt(e1.x * e1.x + e1.y * e1.y + e1.z * e1.z);
  e1 = (palp_vec3){e1.x / l, e1.y / l, e1.z / l};
  const palp_vec3 e2 = {pi.y * e1.z - pi.z * e1.y, pi.z * e1.x - pi.x * e1.z, pi.x * e1.y - pi.y * e1.x};
  for (int j = 0; j < n; ++j) {
    if (j == i || !sp[j].free) continue;
    const palp_vec3 d = {rc->R * (sp[j].n.x - pi.x), rc->R * (sp[j].n.y - pi.y), rc->R * (sp[j].n.z - pi.z)};
    const double dist = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if (dist < r_in || dist > r_out) continue;
    const double x = (d.x * e1.x + d.y * e1.y + d.z * e1.z) / r_out, y = (d.x * e2.x + d.y * e2.y + d.z * e2.z) / r_out;
    const double u[P] = {1.0, x, y, x * x, x * y, y * y};
    for (int p = 0; p < P; ++p) {
      A[p][P] += u[p] * sp[j].f_medium;
      for (int q = 0; q < P; ++q) A[p][q] += u[p] * u[q];
    }
    m++;
  }
  if (m < 10) return NAN;
  /* Gaussian elimination with partial pivoting on the normal equations */
  for (int c = 0; c < P; ++c) {
    int piv = c;
    for (int r = c + 1; r < P; ++r)
      if (fabs(A[r][c]) > fabs(A[piv][c])) piv = r;
    if (fabs(A[piv][c]) < 1e-12) return NAN;
    for (int k = 0; k <= P; ++k) {
      const double t = A[c][k];
      A[c][k] = A[piv][k], A[piv][k] = t;
    }
    for (int r = 0; r < P; ++r) {
      if (r == c) continue;
      const double f = A[r][c] / A[c][c];
      for (int k = c; k <= P; ++k) A[r][k] -= f * A[c][k];
    }
  }
  const double c0 = A[0][P] / A[0][0];
  return c0 > 0 ? sp[i].f_medium / c0 - 1.0 : NAN;
}

/* Marks a lump at the strongest spot of each cluster of spots whose deep force rises
 * more than `threshold` above their surroundings (clusters: spots within `cluster`
 * of each other). Returns the number of findings written (<= cap). */
static inline int expert_findings(const recorder *rc, const expert_spot *sp, int n, double threshold, double cluster,
                           palp_finding *out, int cap, double *max_rise_out) {
  double *rise = malloc(sizeof(double) * (size_t)n);
  int *used = calloc((size_t)n, sizeof(int));
  int nf = 0;
  double maxr = -INFINITY;
  for (int i = 0; i < n; ++i) {
    rise[i] = sp[i].free ? expert_rise(rc, sp, n, i, RISE_R_IN, RISE_R_OUT) : NAN;
    if (rise[i] > maxr) maxr = rise[i];
  }
  if (max_rise_out) *max_rise_out = maxr;
  for (;;) {
    int best = -1;
    for (int i = 0; i < n; ++i)
      if (!used[i] && rise[i] > threshold && (best < 0 || rise[i] > rise[best])) best = i;
    if (best < 0 || nf >= cap) break;
    for (int i = 0; i < n; ++i) {
      const double dx = sp[i].n.x - sp[best].n.x, dy = sp[i].n.y - sp[best].n.y, dz = sp[i].n.z - sp[best].n.z;
      if (rc->R * sqrt(dx * dx + dy * dy + dz * dz) <= cluster) used[i] = 1;
    }
    const palp_vec3 p = {rc->R * sp[best].n.x, rc->R * sp[best].n.y, rc->R * sp[best].n.z};
    out[nf++] = (palp_finding){.t = sp[best].t, .point = p, .withdrawn = 0};
  }
  free(rise), free(used);
  return nf;
}

/* ---- the novice: a few light presses at random places ----------------------------- */
static inline unsigned tr_rand(unsigned *state) {
  *state = *state * 1664525u + 1013904223u;
  return *state >> 8;
}

static inline void novice_exam(recorder *rc, int presses, double depth, unsigned seed, palp_vec3 *last_press) {
  unsigned st = seed;
  for (int k = 0; k < presses; ++k) {
    const double polar = (tr_rand(&st) % 1000) / 1000.0 * 60.0 * TR_PI / 180.0;
    const double az = (tr_rand(&st) % 1000) / 1000.0 * 2.0 * TR_PI;
    const palp_vec3 n = {sin(polar) * cos(az), sin(polar) * sin(az), cos(polar)};
    /* travel in the air, 5 mm above the dome (not along the chord, which cuts through it) */
    const palp_vec3 from = rc->device;
    const double lf = sqrt(from.x * from.x + from.y * from.y + from.z * from.z);
    for (int i = 1; i <= 20; ++i) {
      const double u = i / 20.0;
      palp_vec3 m = {(1 - u) * from.x / lf + u * n.x, (1 - u) * from.y / lf + u * n.y, (1 - u) * from.z / lf + u * n.z};
      const double lm = sqrt(m.x * m.x + m.y * m.y + m.z * m.z);
      move_to(rc, device_at(rc, (palp_vec3){m.x / lm, m.y / lm, m.z / lm}, -0.005), 0.1);
    }
    move_to(rc, device_at(rc, n, depth), 0.03);
    hold(rc, 0.3);
    move_to(rc, device_at(rc, n, -0.005), 0.03);
    if (last_press) *last_press = (palp_vec3){rc->R * n.x, rc->R * n.y, rc->R * n.z};
  }
}
#endif
