/* trainee.c - scripted trainees driving a hand (see trainee.h). */
#include "trainee.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TR_PI 3.14159265358979323846
#define RISE_R_IN 0.012  /* the surroundings a spot is compared with: 12-28 mm away */
#define RISE_R_OUT 0.028
#define SUSPECT 0.5 /* spots rising above this share of the threshold are left out of the others' fits */
#define MAX_RECHECKS 12 /* re-palpations of suspected lumps, at most (~3 s each) */

void palp_cli_hand_init(palp_cli_hand *h, void *ctx, int (*step)(void *, palp_vec3, palp_vec3 *, double *), double dt,
                        double R, double r, palp_vec3 start) {
  memset(h, 0, sizeof *h);
  h->ctx = ctx, h->step = step, h->dt = dt, h->R = R, h->r = r, h->device = start;
}

void palp_cli_hand_step(palp_cli_hand *h, palp_vec3 dev) {
  if (h->failed) return;
  h->device = dev;
  if (h->step(h->ctx, dev, &h->force, &h->t) < 0) {
    h->failed = 1;
    return;
  }
  h->steps++;
}

static double force_now(const palp_cli_hand *h) {
  return sqrt(h->force.x * h->force.x + h->force.y * h->force.y + h->force.z * h->force.z);
}

void palp_cli_hand_move_to(palp_cli_hand *h, palp_vec3 to, double speed) {
  const palp_vec3 a = h->device;
  const double L = sqrt((to.x - a.x) * (to.x - a.x) + (to.y - a.y) * (to.y - a.y) + (to.z - a.z) * (to.z - a.z));
  const int k = (int)ceil(L / (speed * h->dt));
  for (int i = 1; i <= k && !h->failed; ++i) {
    const double u = (double)i / k;
    palp_cli_hand_step(h, (palp_vec3){a.x + u * (to.x - a.x), a.y + u * (to.y - a.y), a.z + u * (to.z - a.z)});
  }
}

void palp_cli_hand_hold(palp_cli_hand *h, double seconds) {
  const int k = (int)lround(seconds / h->dt);
  for (int i = 0; i < k && !h->failed; ++i) palp_cli_hand_step(h, h->device);
}

palp_vec3 palp_cli_hand_device_at(const palp_cli_hand *h, palp_vec3 n, double depth) {
  const double q = h->R + h->r - depth;
  palp_vec3 d = {q * n.x, q * n.y, q * n.z};
  if (d.z < h->r) d.z = h->r;
  return d;
}

/* ---- the expert ---------------------------------------------------------------------- */
/* The deep press: device 14.5 mm, about 11.5 mm of indentation, inside the shipped parameters'
 * validated depth everywhere (12 mm at the pole, 45 and 70 deg, 14 mm at 60 deg:
 * config/params/breast_tissue.json) with 0.5 mm to spare, and well inside the deep band (9-18 mm).
 * The expert shows the technique; her session is not where the model should be seen leaving
 * its valid range. At 16 mm (until 2026-12-05) she pressed to 12.46 mm and the teaching
 * session spent 6.3 s beyond the table, by up to 0.46 mm (tests/assess/phantom_figures expert). */
palp_cli_expert_cfg palp_cli_expert_default(void) {
  return (palp_cli_expert_cfg){.spacing = 0.008, .d_light = 0.003, .d_medium = 0.009, .d_deep = 0.0145,
                               .press_speed = 0.05, .glide_speed = 0.05, .hold = 0.12, .min_nz = 0.06,
                               .keep_force = 0.05, .patience = 0.3, .threshold = 0.12, .cluster = 0.015};
}

/* Moves the hand to depth `d` [m] at spot normal `to`, gliding over the surface at
 * `speed` and pressing at `vz` [m/s]. Rising is allowed only while the finger still
 * feels at least `keep` [N]: an examiner keeps a light touch, so the finger follows the
 * dent as it recovers (the gel recovers in about a second, docs/model.md) instead of
 * leaving the surface. Gives up rising after `patience` [s]. */
typedef struct spot_hand {
  palp_vec3 n; /* current spot normal */
  double d;    /* current depth [m] */
} spot_hand;

static void travel(palp_cli_hand *h, spot_hand *sh, palp_vec3 to, double d, double speed, double vz, double keep,
                   double patience) {
  const double dt = h->dt;
  const palp_vec3 from = sh->n;
  const double arc = h->R * acos(fmax(-1.0, fmin(1.0, from.x * to.x + from.y * to.y + from.z * to.z)));
  const int k = arc > 0 ? (int)ceil(arc / (speed * dt)) : 0;
  const int limit = k + (int)ceil((fabs(d - sh->d) / vz + patience) / dt);
  for (int i = 1; i <= limit && !h->failed; ++i) {
    if (i <= k) {
      const double u = (double)i / k;
      palp_vec3 n = {from.x + u * (to.x - from.x), from.y + u * (to.y - from.y), from.z + u * (to.z - from.z)};
      const double l = sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
      sh->n = (palp_vec3){n.x / l, n.y / l, n.z / l};
    }
    if (sh->d < d) sh->d = fmin(d, sh->d + vz * dt);
    else if (sh->d > d && (h->steps == 0 || force_now(h) >= keep)) sh->d = fmax(d, sh->d - vz * dt);
    palp_cli_hand_step(h, palp_cli_hand_device_at(h, sh->n, sh->d));
    if (i >= k && fabs(sh->d - d) < 1e-12) break;
  }
}

/* Holds for `seconds` and returns the median force felt over the hold's last third: what
 * a settled press feels, robust to a glitch (over DDS on a loaded machine a late haptic
 * tick makes the device jump and the force spike for a step or two). In-process it moves
 * the expert's largest rise from +19.0 % (the hold's last sample) to +19.7 %. */
#define HOLD_TAIL_MAX 256
static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}
static double held_force(palp_cli_hand *h, double seconds) {
  const int k = (int)lround(seconds / h->dt);
  const int tail0 = k - k / 3;
  double f[HOLD_TAIL_MAX];
  int n = 0;
  if (h->felt_valid) {
    /* Forces from a server: hold until the server has stepped `seconds` with the
     * finger at this point, and take the median of that hold's last third. At most
     * 10x the hold plus 1 s of hand steps (a server that never catches up). */
    const palp_vec3 x = h->device;
    const long kmax = 10L * k + (long)lround(1.0 / h->dt);
    double t0 = NAN, last = NAN;
    for (long i = 0; i < kmax && !h->failed; ++i) {
      palp_cli_hand_step(h, x);
      const double dx = h->felt_device.x - x.x, dy = h->felt_device.y - x.y, dz = h->felt_device.z - x.z;
      if (dx * dx + dy * dy + dz * dz > 1e-12) { /* the server has not reached the point (1 um) */
        t0 = NAN, n = 0;
        continue;
      }
      if (isnan(t0)) t0 = h->felt_time;
      const double held = h->felt_time - t0;
      if (h->felt_time != last && held >= (double)tail0 * h->dt - 1e-9 && n < HOLD_TAIL_MAX) f[n++] = force_now(h);
      last = h->felt_time;
      if (held >= (double)(k - 1) * h->dt - 1e-9) break;
    }
  } else {
    for (int i = 0; i < k && !h->failed; ++i) {
      palp_cli_hand_step(h, h->device);
      if (i >= tail0 && n < HOLD_TAIL_MAX) f[n++] = force_now(h);
    }
  }
  if (n == 0) return force_now(h);
  qsort(f, (size_t)n, sizeof *f, cmp_double);
  return f[n / 2];
}

palp_cli_expert_spot *palp_cli_expert_exam(palp_cli_hand *h, const palp_cli_expert_cfg *cfg, int *count) {
  const double R = h->R;
  const double da = cfg->spacing / R;
  const int na = (int)floor((TR_PI / 2.0) / da);
  palp_cli_expert_spot *sp = NULL;
  int n = 0, cap = 0, strip = 0;
  spot_hand sh = {{0, 0, 1}, 0.0};
  *count = 0;
  /* MammaCare's vertical strip: parallel strips (planes x = const, straight lines seen
   * from above), spots 8 mm apart on the surface, boustrophedon; at every spot light ->
   * medium -> deep and back, gliding to the next spot at the light depth. */
  for (int ia = -na; ia <= na && !h->failed; ++ia, ++strip) {
    const double a = ia * da, ca = cos(a);
    if (ca < cfg->min_nz) continue;
    const double bmax = acos(fmin(1.0, cfg->min_nz / ca)); /* cos a cos b >= min_nz */
    const double db = cfg->spacing / (R * ca);
    const int nb = (int)floor(bmax / db);
    for (int k = -nb; k <= nb && !h->failed; ++k) {
      const int kb = (strip % 2) ? -k : k; /* boustrophedon */
      const double b = kb * db;
      const palp_vec3 nrm = {sin(a), ca * sin(b), ca * cos(b)};
      if (n == cap) {
        cap = cap ? 2 * cap : 256;
        palp_cli_expert_spot *ns = realloc(sp, sizeof *sp * (size_t)cap);
        if (!ns) {
          free(sp);
          return NULL;
        }
        sp = ns;
      }
      palp_cli_expert_spot *s = &sp[n++];
      s->n = nrm;
      if (n == 1) { /* first spot: come down onto it from where the hand is */
        palp_cli_hand_move_to(h, palp_cli_hand_device_at(h, nrm, 0.0), cfg->glide_speed);
        sh.n = nrm, sh.d = 0.0;
      }
      travel(h, &sh, nrm, cfg->d_light, cfg->glide_speed, cfg->press_speed, cfg->keep_force, cfg->patience);
      s->t = h->t;
      travel(h, &sh, nrm, cfg->d_medium, cfg->glide_speed, cfg->press_speed, cfg->keep_force, 0.0);
      s->f_medium = held_force(h, cfg->hold);
      travel(h, &sh, nrm, cfg->d_deep, cfg->glide_speed, cfg->press_speed, cfg->keep_force, 0.0);
      s->f_deep = held_force(h, cfg->hold);
      s->free = (R + h->r - cfg->d_deep) * nrm.z >= h->r;
    }
  }
  *count = n;
  return sp;
}

/* The rise of a free spot's force at the medium depth over its surroundings at the same
 * depth: a quadratic surface c0 + g . u + u^T H u (u: tangent-plane offset) plus a term
 * c6 ((z_i / z_j)^2 - 1) in the heights above the base, fitted by least squares, so that
 * the dome's own change of stiffness across the surface is not taken for a lump. The
 * last term is the rise towards the base: the breast-tissue phantom's support stiffens as
 * the gel under the skin thins (docs/model.md), as its FE does, and over the 12-28 mm of
 * surroundings (17-40 deg of arc) a quadratic alone left lesion-free spots up to +8.6%
 * above their fit (+11.6% with the cubic law first tried, a false lump in the demo); with
 * it, +4.3% at most (docs/assessment.md, "The lump rule"). It vanishes at the spot itself,
 * so c0 is still the fit there. */
static double rise_skipping(const palp_cli_hand *h, const palp_cli_expert_spot *sp, int n, int i, double r_in,
                            double r_out, const unsigned char *skip) {
  enum { P = 7 };
  double A[P][P + 1] = {{0}};
  int m = 0, side[4] = {0}; /* neighbours beyond half the outer radius at +x, -x, +y, -y */
  const palp_vec3 pi = sp[i].n;
  palp_vec3 e1 = fabs(pi.z) < 0.9 ? (palp_vec3){-pi.y, pi.x, 0} : (palp_vec3){1, 0, 0};
  const double ndote = pi.x * e1.x + pi.y * e1.y + pi.z * e1.z;
  e1 = (palp_vec3){e1.x - ndote * pi.x, e1.y - ndote * pi.y, e1.z - ndote * pi.z};
  const double l = sqrt(e1.x * e1.x + e1.y * e1.y + e1.z * e1.z);
  e1 = (palp_vec3){e1.x / l, e1.y / l, e1.z / l};
  const palp_vec3 e2 = {pi.y * e1.z - pi.z * e1.y, pi.z * e1.x - pi.x * e1.z, pi.x * e1.y - pi.y * e1.x};
  for (int j = 0; j < n; ++j) {
    if (j == i || !sp[j].free || (skip && skip[j])) continue;
    const palp_vec3 d = {h->R * (sp[j].n.x - pi.x), h->R * (sp[j].n.y - pi.y), h->R * (sp[j].n.z - pi.z)};
    const double dist = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if (dist < r_in || dist > r_out) continue;
    const double x = (d.x * e1.x + d.y * e1.y + d.z * e1.z) / r_out, y = (d.x * e2.x + d.y * e2.y + d.z * e2.z) / r_out;
    const double zr = pi.z / fmax(sp[j].n.z, 0.05); /* z_i / z_j; free spots sit well above the base */
    const double u[P] = {1.0, x, y, x * x, x * y, y * y, zr * zr - 1.0};
    for (int p = 0; p < P; ++p) {
      A[p][P] += u[p] * sp[j].f_medium;
      for (int q = 0; q < P; ++q) A[p][q] += u[p] * u[q];
    }
    m++;
    side[0] += x > 0.25, side[1] += x < -0.25, side[2] += y > 0.25, side[3] += y < -0.25;
  }
  /* Surrounded on every side, or the fit at the spot is an extrapolation: at the edge of
   * the examined area (the last strip clear of the table) a quadratic fitted to one side
   * only put a lesion-free spot +9 % above it on the breast-tissue phantom. */
  if (m < 10 || side[0] < 2 || side[1] < 2 || side[2] < 2 || side[3] < 2) return NAN;
  for (int c = 0; c < P; ++c) { /* Gauss-Jordan with partial pivoting on the normal equations */
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

double palp_cli_expert_rise(const palp_cli_hand *h, const palp_cli_expert_spot *sp, int n, int i, double r_in,
                            double r_out) {
  return rise_skipping(h, sp, n, i, r_in, r_out, NULL);
}

int palp_cli_expert_rises(const palp_cli_hand *h, const palp_cli_expert_spot *sp, int n, const palp_cli_expert_cfg *cfg,
                          double *rise) {
  for (int i = 0; i < n; ++i) rise[i] = sp[i].free ? palp_cli_expert_rise(h, sp, n, i, RISE_R_IN, RISE_R_OUT) : NAN;
  /* Second pass: the surroundings without the spots that stood out in the first (what an
   * examiner compares a lump with is the normal tissue around it). A lump 20-28 mm from a
   * spot near the edge of the examined area otherwise tilts the fit there, which is then
   * an extrapolation, and the spot rises by as much as a lump does. A spot left with too
   * few surroundings keeps its first rise. */
  unsigned char *skip = calloc((size_t)(n > 0 ? n : 1), 1);
  if (!skip) return PALP_ENOMEM;
  for (int i = 0; i < n; ++i) skip[i] = rise[i] > SUSPECT * cfg->threshold;
  for (int i = 0; i < n; ++i) {
    if (!sp[i].free) continue;
    const double r2 = rise_skipping(h, sp, n, i, RISE_R_IN, RISE_R_OUT, skip);
    if (isfinite(r2)) rise[i] = r2;
  }
  free(skip);
  return 0;
}

/* The strongest spot of each cluster rising above the threshold, strongest first:
 * writes up to cap spot indexes, returns their count (or PALP_ENOMEM). */
static int lump_spots(const palp_cli_hand *h, const palp_cli_expert_spot *sp, int n, const palp_cli_expert_cfg *cfg,
                      int *idx, int cap, double *max_rise) {
  double *rise = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
  int *used = calloc((size_t)(n > 0 ? n : 1), sizeof(int));
  if (!rise || !used || palp_cli_expert_rises(h, sp, n, cfg, rise) < 0) {
    free(rise), free(used);
    return PALP_ENOMEM;
  }
  int nf = 0;
  double maxr = -INFINITY;
  for (int i = 0; i < n; ++i)
    if (rise[i] > maxr) maxr = rise[i];
  if (max_rise) *max_rise = maxr;
  for (;;) {
    int best = -1;
    for (int i = 0; i < n; ++i)
      if (!used[i] && rise[i] > cfg->threshold && (best < 0 || rise[i] > rise[best])) best = i;
    if (best < 0 || nf >= cap) break;
    for (int i = 0; i < n; ++i) {
      const double dx = sp[i].n.x - sp[best].n.x, dy = sp[i].n.y - sp[best].n.y, dz = sp[i].n.z - sp[best].n.z;
      if (h->R * sqrt(dx * dx + dy * dy + dz * dz) <= cfg->cluster) used[i] = 1;
    }
    idx[nf++] = best;
  }
  free(rise), free(used);
  return nf;
}

int palp_cli_expert_lumps(const palp_cli_hand *h, const palp_cli_expert_spot *sp, int n, const palp_cli_expert_cfg *cfg,
                          palp_vec3 *points, double *times, int cap, double *max_rise) {
  int idx[64];
  const int nf = lump_spots(h, sp, n, cfg, idx, cap < 64 ? cap : 64, max_rise);
  for (int k = 0; k < nf; ++k) {
    points[k] = (palp_vec3){h->R * sp[idx[k]].n.x, h->R * sp[idx[k]].n.y, h->R * sp[idx[k]].n.z};
    if (times) times[k] = sp[idx[k]].t;
  }
  return nf;
}

/* Moves the device along the great circle from normal `a` to normal `b` at radius rho
 * [m] from the dome's centre (clear of the surface when rho > R + r): a straight chord
 * between two far spots would cut through the dome. */
static void hover(palp_cli_hand *h, palp_vec3 a, palp_vec3 b, double rho, double speed) {
  const double c = fmax(-1.0, fmin(1.0, a.x * b.x + a.y * b.y + a.z * b.z));
  const int segs = 1 + (int)ceil(acos(c) / (TR_PI / 18.0)); /* 10-degree chords dip < 0.4 % of rho */
  for (int k = 1; k <= segs && !h->failed; ++k) {
    const double u = (double)k / segs;
    palp_vec3 n = {a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), a.z + u * (b.z - a.z)};
    const double l = sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    if (!(l > 1e-9)) n = (palp_vec3){0, 0, 1};
    else n = (palp_vec3){n.x / l, n.y / l, n.z / l};
    palp_cli_hand_move_to(h, (palp_vec3){rho * n.x, rho * n.y, fmax(h->r, rho * n.z)}, speed);
  }
}

/* Re-palpates spot i the way the exam first reached it: onto the spot before it in the
 * exam (light, medium, deep there), a glide at the light depth to spot i, a press to the
 * medium depth and the same hold. The medium-depth force held is returned; the surface
 * history the force depends on (the gel recovers over about a second) is the exam's. */
static double repalpate(palp_cli_hand *h, const palp_cli_expert_spot *sp, int i, const palp_cli_expert_cfg *cfg) {
  const int j = i > 0 ? i - 1 : i;
  const double rho = h->R + h->r + 0.005;
  palp_vec3 up = h->device;
  const double lu = sqrt(up.x * up.x + up.y * up.y + up.z * up.z);
  up = lu > 1e-9 ? (palp_vec3){up.x / lu, up.y / lu, up.z / lu} : (palp_vec3){0, 0, 1};
  palp_cli_hand_move_to(h, (palp_vec3){rho * up.x, rho * up.y, fmax(h->r, rho * up.z)}, cfg->glide_speed);
  hover(h, up, sp[j].n, rho, 2.0 * cfg->glide_speed);
  palp_cli_hand_move_to(h, palp_cli_hand_device_at(h, sp[j].n, 0.0), cfg->glide_speed);
  spot_hand sh = {sp[j].n, 0.0};
  travel(h, &sh, sp[j].n, cfg->d_light, cfg->glide_speed, cfg->press_speed, cfg->keep_force, cfg->patience);
  travel(h, &sh, sp[j].n, cfg->d_medium, cfg->glide_speed, cfg->press_speed, cfg->keep_force, 0.0);
  (void)held_force(h, cfg->hold);
  travel(h, &sh, sp[j].n, cfg->d_deep, cfg->glide_speed, cfg->press_speed, cfg->keep_force, 0.0);
  (void)held_force(h, cfg->hold);
  travel(h, &sh, sp[i].n, cfg->d_light, cfg->glide_speed, cfg->press_speed, cfg->keep_force, cfg->patience);
  travel(h, &sh, sp[i].n, cfg->d_medium, cfg->glide_speed, cfg->press_speed, cfg->keep_force, 0.0);
  const double f = held_force(h, cfg->hold);
  travel(h, &sh, sp[i].n, cfg->d_light, cfg->glide_speed, cfg->press_speed, cfg->keep_force, cfg->patience);
  return f;
}

int palp_cli_expert_lumps_confirmed(palp_cli_hand *h, palp_cli_expert_spot *sp, int n, const palp_cli_expert_cfg *cfg,
                                    palp_vec3 *points, double *times, int cap, double *max_rise, int *rechecked) {
  int idx[64], nf = 0, checks = 0;
  if (cap > 64) cap = 64;
  unsigned char *done = calloc((size_t)(n > 0 ? n : 1), 1);
  if (!done) return PALP_ENOMEM;
  /* Each round re-palpates the candidates not yet re-checked and keeps, for each, the
   * smaller of its two forces: a spike from a late tick is not felt twice, a lump is.
   * Bounded: every round re-checks at least one new spot or ends. */
  for (int round = 0; round <= 2 * MAX_RECHECKS && !h->failed; ++round) {
    nf = lump_spots(h, sp, n, cfg, idx, cap, round == 0 ? max_rise : NULL);
    if (nf < 0) break;
    int fresh = 0;
    for (int k = 0; k < nf && checks < MAX_RECHECKS && !h->failed; ++k) {
      if (done[idx[k]]) continue;
      const double f = repalpate(h, sp, idx[k], cfg);
      sp[idx[k]].f_medium = fmin(sp[idx[k]].f_medium, f);
      done[idx[k]] = 1, fresh = 1, checks++;
    }
    if (!fresh) break;
  }
  free(done);
  if (rechecked) *rechecked = checks;
  if (nf < 0) return nf;
  for (int k = 0; k < nf; ++k) {
    points[k] = (palp_vec3){h->R * sp[idx[k]].n.x, h->R * sp[idx[k]].n.y, h->R * sp[idx[k]].n.z};
    if (times) times[k] = sp[idx[k]].t;
  }
  return nf;
}

/* ---- the novice -------------------------------------------------------------------------- */
static unsigned tr_rand(unsigned *state) {
  *state = *state * 1664525u + 1013904223u;
  return *state >> 8;
}

void palp_cli_novice_exam(palp_cli_hand *h, int presses, double depth, unsigned seed, palp_vec3 *last_press,
                          void (*on_last_hold)(void *arg), void *arg) {
  unsigned st = seed;
  for (int k = 0; k < presses && !h->failed; ++k) {
    const double polar = (tr_rand(&st) % 1000) / 1000.0 * 60.0 * TR_PI / 180.0;
    const double az = (tr_rand(&st) % 1000) / 1000.0 * 2.0 * TR_PI;
    const palp_vec3 n = {sin(polar) * cos(az), sin(polar) * sin(az), cos(polar)};
    /* travel in the air, 5 mm above the dome (not along the chord, which cuts through it) */
    const palp_vec3 from = h->device;
    const double lf = sqrt(from.x * from.x + from.y * from.y + from.z * from.z);
    for (int i = 1; i <= 20; ++i) {
      const double u = i / 20.0;
      palp_vec3 m = {(1 - u) * from.x / lf + u * n.x, (1 - u) * from.y / lf + u * n.y, (1 - u) * from.z / lf + u * n.z};
      const double lm = sqrt(m.x * m.x + m.y * m.y + m.z * m.z);
      palp_cli_hand_move_to(h, palp_cli_hand_device_at(h, (palp_vec3){m.x / lm, m.y / lm, m.z / lm}, -0.005), 0.1);
    }
    palp_cli_hand_move_to(h, palp_cli_hand_device_at(h, n, depth), 0.03);
    /* The mark once the press has been felt for 0.1 s, as a hand settles before it marks:
     * with a server's models, 0.1 s of its physics time with the finger at this point
     * (held_force), however late they come. Pressed on arrival, the station's latest model
     * could still be of the finger in the air (models come ~4 ms after the device point,
     * seconds under AddressSanitizer beside other tests), and the station refused the mark
     * as not touching (2026-12-05). In process it is a 0.1 s hold, as before. */
    (void)held_force(h, 0.1);
    if (k == presses - 1 && on_last_hold) on_last_hold(arg);
    palp_cli_hand_hold(h, 0.2);
    palp_cli_hand_move_to(h, palp_cli_hand_device_at(h, n, -0.005), 0.03);
    if (last_press) *last_press = (palp_vec3){h->R * n.x, h->R * n.y, h->R * n.z};
  }
}
