/*
 * assess.c - the metrics of a palpation session (palp_assess.h; every definition and
 * its source is in docs/assessment.md). Pure: samples and findings in, numbers out.
 *
 * Positions are read on the rest dome (centre at the origin, radius R): a point is
 * projected radially onto it, p^ = R p / |p|. That way a press along the normal does
 * not move the finger on the map, and the path is what the trainee's hand travelled
 * over the breast, not the dent's own motion.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "palp_assess.h"
#include "vec3.h"

#define DEG (PALP_PI / 180.0)
/* A direction within 20 deg of a reference counts as along it (axial, tangential, radial). */
#define ALIGN_DEG 20.0
/* Near the pole the radial and tangential directions are undefined. */
#define POLE_EXCLUSION 0.003 /* [m] */
/* A pattern needs this much plan path and this share of it along one direction. */
#define PATTERN_MIN_PATH 0.10 /* [m] */
#define PATTERN_MIN_SHARE 0.60
/* A vertex re-entering the footprint after this long away starts a new visit. */
#define VISIT_GAP 0.5 /* [s] */
/* Out of touch for longer than this is a lift (palp_assess.h). */
#define LIFT_GAP PALP_ASSESS_LIFT_GAP_S /* [s] */

static palp_vec3 on_dome(palp_vec3 p, double R) {
  const double n = v3_len(p);
  return n > 1e-12 ? v3_scale(p, R / n) : v3(0, 0, R);
}

static double fnorm(palp_vec3 f) { return v3_len(f); }

/* ---- findings ------------------------------------------------------------ */
/* Which standing marks find which lesions: a maximum matching between the marks and the lesions
 * each is within reach of (radius + match_margin of the lesion's surface projection), so the number
 * found never depends on the order of the marks (docs/assessment.md, "Sensitivity"). The greedy rule
 * before (each mark in order took the nearest lesion not yet found) let a mark between two lumps take
 * the one a later mark alone could reach, the other then reported missed (session 81 review).
 *
 * Among the maximum matchings the one kept is the old rule's wherever it already found the most:
 * marks in log order each take the nearest lesion (the file's order on a tie) that still leaves a
 * maximum matching possible. So a mark keeps the lump it found when a later mark lands nearer (the
 * live debrief on palp-web does not move a lump's credit to a later mark), and only a lump the
 * greedy rule would have lost changes hands. The counts (found, duplicates, false positives) are the
 * same for every maximum matching; only which mark is credited follows the order.
 *
 * The feasibility test is a table over the in-reach marks and the subsets of lesions used:
 * most[i][used] = the most lesions marks i.. can still find with `used` taken (<= 8 lesions: 256
 * subsets; O(marks x 256 x lesions)). */
static int reach_of(const palp_exercise *ex, double R, palp_vec3 point, double *dist) {
  const palp_vec3 p = on_dome(point, R);
  int mask = 0;
  for (int l = 0; l < ex->lesion_count; ++l) {
    const palp_vec3 s = palp_exercise_lesion_surface(&ex->lesion[l], R);
    dist[l] = v3_len(v3_sub(p, s));
    if (dist[l] <= ex->lesion[l].diameter / 2.0 + ex->match_margin) mask |= 1 << l;
  }
  return mask;
}

static int match_findings(const palp_exercise *ex, double R, const palp_finding *f, int nf, palp_assess_result *r,
                          int *match) {
  const int L = ex->lesion_count, S = 1 << L;
  r->lesion_count = L;
  for (int l = 0; l < PALP_MAX_LESIONS; ++l) r->lesion_found[l] = -1;
  /* the marks within reach of some lesion, in log order */
  int nc = 0;
  for (int i = 0; i < nf; ++i) {
    double d[PALP_MAX_LESIONS];
    if (!f[i].withdrawn && reach_of(ex, R, f[i].point, d)) nc++;
  }
  int *cand = malloc(sizeof(int) * (size_t)(nc ? nc : 1));
  unsigned char *most = calloc((size_t)(nc + 1) * (size_t)S, 1);
  if (!cand || !most) {
    free(cand), free(most);
    return PALP_ENOMEM;
  }
  nc = 0;
  for (int i = 0; i < nf; ++i) {
    double d[PALP_MAX_LESIONS];
    if (!f[i].withdrawn && reach_of(ex, R, f[i].point, d)) cand[nc++] = i;
  }
  for (int k = nc - 1; k >= 0; --k) {
    double d[PALP_MAX_LESIONS];
    const int reach = reach_of(ex, R, f[cand[k]].point, d);
    for (int used = 0; used < S; ++used) {
      int best = most[(size_t)(k + 1) * S + used]; /* this mark finds nothing */
      for (int l = 0; l < L; ++l)
        if ((reach & ~used) >> l & 1 && 1 + most[(size_t)(k + 1) * S + (used | 1 << l)] > best)
          best = 1 + most[(size_t)(k + 1) * S + (used | 1 << l)];
      most[(size_t)k * S + used] = (unsigned char)best;
    }
  }
  int used = 0, k = 0;
  for (int i = 0; i < nf; ++i) {
    int m;
    if (f[i].withdrawn) {
      m = PALP_FINDING_WITHDRAWN;
      r->withdrawn++;
    } else {
      r->findings++;
      double d[PALP_MAX_LESIONS];
      const int reach = reach_of(ex, R, f[i].point, d);
      int best = -1;
      if (reach) {
        const int need = most[(size_t)k * S + used]; /* what the marks from this one on must still find */
        for (int l = 0; l < L; ++l)
          if ((reach & ~used) >> l & 1 && 1 + most[(size_t)(k + 1) * S + (used | 1 << l)] == need &&
              (best < 0 || d[l] < d[best]))
            best = l;
        k++;
      }
      if (best >= 0) {
        used |= 1 << best;
        r->lesion_found[best] = i;
        r->found++;
        m = best;
      } else if (reach) { /* within reach of a lesion another mark found */
        m = PALP_FINDING_DUPLICATE;
        r->duplicates++;
      } else {
        m = PALP_FINDING_FALSE;
        r->false_positives++;
      }
    }
    if (match) match[i] = m;
  }
  free(cand), free(most);
  r->sensitivity = L ? (double)r->found / L : 1.0;
  return PALP_OK;
}

/* ---- coverage ------------------------------------------------------------- */
static int uf_find(int *p, int i) {
  while (p[i] != i) i = p[i] = p[p[i]];
  return i;
}

/* Marks sample s's footprint into mark[] (stamp) and calls back per vertex via the list. */
static int footprint(const palp_mesh *mesh, const palp_assess_sample *s, double R, int *list, int *stamp, int tag) {
  int n = 0;
  if (s->triangles && s->triangle_count > 0) {
    for (int k = 0; k < s->triangle_count; ++k) {
      const int t = s->triangles[k];
      if (t < 0 || t >= mesh->dome_triangle_count) continue; /* base triangles are not palpable */
      for (int j = 0; j < 3; ++j) {
        const int v = mesh->tri[t][j];
        if (stamp[v] != tag) stamp[v] = tag, list[n++] = v;
      }
    }
    return n;
  }
  /* No triangles logged: the disc of the footprint's area around the contact point. */
  const palp_vec3 c = on_dome(s->point, R);
  const double rho = sqrt(fmax(s->area, 0.0) / PALP_PI);
  int nearest = -1;
  double dn = INFINITY;
  for (int v = 0; v < mesh->vertex_count; ++v) {
    if (!(mesh->vertex_area[v] > 0.0)) continue;
    const double d = v3_len(v3_sub(mesh->rest[v], c));
    if (d < dn) dn = d, nearest = v;
    if (d <= rho && stamp[v] != tag) stamp[v] = tag, list[n++] = v;
  }
  if (nearest >= 0 && stamp[nearest] != tag) stamp[nearest] = tag, list[n++] = nearest;
  return n;
}

/* ---- search pattern ------------------------------------------------------- */
/* The search path seen from above the pole: the proxy's position on the rest dome,
 * decimated to points at least STATION apart along the touching path (a new point
 * once the finger is that far from the last one). Motions smaller than a fingertip
 * are palpation in place (MammaCare's dime-sized circles, a press), not search. */
#define STATION 0.008 /* [m] */
/* Strips (MammaCare's vertical strip: parallel strokes a fingertip apart, each next to
 * the one before, across the breast). A strip is a run of axial segments in one direction
 * while touching, at least two stations long; it ends where the finger turns along the
 * axis, lifts, or strokes half a station off the strip's line. Its place is the
 * length-weighted mean of its segments' across-axis coordinate. A step between strips
 * shorter than STRIP_STEP (retracing a strip, the proxy's sideways give) is no step. */
#define STRIP_MIN (2.0 * STATION)   /* [m] */
#define STRIP_WIDTH (0.5 * STATION) /* [m] */
#define STRIP_STEP 0.002            /* [m] */

typedef struct strip_track {
  int open, dir, stretch;
  double len, csum; /* axial length [m] and its across-weighted sum [m^2] */
  int kept;         /* strips kept */
  double last;      /* the last counted strip's place [m] */
  int last_sign;    /* the direction of the last step between strips (0: none yet) */
  int pairs, turns; /* successive steps between strips; those that reverse the one before */
} strip_track;

static void strip_close(strip_track *st) {
  if (st->open && st->len >= STRIP_MIN) {
    const double p = st->csum / st->len;
    if (!st->kept) st->last = p;
    else if (fabs(p - st->last) >= STRIP_STEP) {
      const int sg = p > st->last ? 1 : -1;
      if (st->last_sign) st->pairs++, st->turns += sg != st->last_sign;
      st->last_sign = sg;
      st->last = p;
    }
    st->kept++;
  }
  st->open = 0;
}

/* An axial segment of length w [m], direction dir (+1/-1 along the axis), its midpoint
 * c [m] across the axis, in touching stretch `stretch`. */
static void strip_add(strip_track *st, int dir, int stretch, double w, double c) {
  if (st->open && (dir != st->dir || stretch != st->stretch || fabs(c - st->csum / st->len) > STRIP_WIDTH))
    strip_close(st);
  if (!st->open) *st = (strip_track){.open = 1, .dir = dir, .stretch = stretch, .kept = st->kept, .last = st->last,
                                     .last_sign = st->last_sign, .pairs = st->pairs, .turns = st->turns};
  st->len += w;
  st->csum += w * c;
}

static void pattern(const palp_assess_sample *s, int n, double R, palp_pattern_evidence *ev, palp_pattern *out) {
  const double ca = cos(ALIGN_DEG * DEG), sa = sin(ALIGN_DEG * DEG);
  double c2 = 0.0, s2 = 0.0;
  for (int i = 1; i < n; ++i)
    if (s[i].contact && s[i - 1].contact)
      ev->path_length += v3_len(v3_sub(on_dome(s[i].proxy, R), on_dome(s[i - 1].proxy, R)));
  for (int pass = 0; pass < 2; ++pass) {
    const double ax = 0.5 * atan2(s2, c2), ux = cos(ax), uy = sin(ax);
    double along = 0.0, tang = 0.0, rad = 0.0;
    strip_track st = {0};
    int have = 0, stretch = 0;
    double t_last = 0.0;
    palp_vec3 a = {0, 0, 0};
    for (int i = 0; i < n; ++i) {
      if (!s[i].contact) continue;
      /* the search is the path while touching: a lift ends a stretch */
      if (have && s[i].t - t_last > LIFT_GAP) have = 0;
      t_last = s[i].t;
      const palp_vec3 b = on_dome(s[i].proxy, R);
      if (!have) {
        a = b, have = 1, stretch++;
        continue;
      }
      if (v3_len(v3_sub(b, a)) < STATION) continue;
      const double dx = b.x - a.x, dy = b.y - a.y, w = hypot(dx, dy);
      const palp_vec3 prev = a;
      a = b;
      if (pass == 0) {
        ev->plan_length += w;
        if (w > 0.0) {
          const double phi = atan2(dy, dx);
          c2 += w * cos(2.0 * phi), s2 += w * sin(2.0 * phi);
        }
        continue;
      }
      if (!(w > 0.0)) continue;
      const double ua = dx * ux + dy * uy, cu = fabs(ua) / w;
      const double mx = 0.5 * (prev.x + b.x), my = 0.5 * (prev.y + b.y), rm = hypot(mx, my);
      if (cu >= ca) {
        along += w;
        strip_add(&st, ua > 0 ? 1 : -1, stretch, w, -mx * uy + my * ux);
      }
      if (rm < POLE_EXCLUSION) continue;
      const double cr = fabs(dx * mx + dy * my) / (w * rm);
      if (cr >= ca) rad += w;
      else if (cr <= sa) tang += w;
    }
    if (pass == 1) {
      const double L = ev->plan_length;
      ev->axis_deg = ax / DEG;
      ev->share_axial = L > 0 ? along / L : 0.0;
      ev->share_tangential = L > 0 ? tang / L : 0.0;
      ev->share_radial = L > 0 ? rad / L : 0.0;
      strip_close(&st);
      ev->strips = st.kept;
      ev->sweep_monotony = st.pairs > 0 ? (double)(st.pairs - st.turns) / st.pairs : 0.0;
    }
  }
  *out = PALP_PATTERN_UNSYSTEMATIC;
  if (!(ev->plan_length >= PATTERN_MIN_PATH)) return;
  double best = ev->share_axial;
  palp_pattern p = PALP_PATTERN_VERTICAL_STRIP;
  if (ev->share_tangential > best) best = ev->share_tangential, p = PALP_PATTERN_CIRCLES;
  if (ev->share_radial > best) best = ev->share_radial, p = PALP_PATTERN_RADIAL;
  if (best >= PATTERN_MIN_SHARE) *out = p;
}

int palp_assess_findings(const palp_exercise *ex, double dome_radius, const palp_finding *f, int nf,
                         palp_assess_result *out, int *match) {
  if (!ex || !out || nf < 0 || (nf && !f) || !(dome_radius > 0.0) || ex->lesion_count < 0 ||
      ex->lesion_count > PALP_MAX_LESIONS)
    return PALP_EINVAL;
  for (int i = 0; i < nf; ++i)
    if (!v3_isfinite(f[i].point)) return PALP_EINVAL;
  memset(out, 0, sizeof *out);
  return match_findings(ex, dome_radius, f, nf, out, match);
}

int palp_assess_sample_every(double physics_hz, double sample_hz) {
  const long k = physics_hz > sample_hz && sample_hz > 0 ? lround(physics_hz / sample_hz) : 1;
  return k > 0 && k < 1000000 ? (int)k : 1;
}

int palp_assess_touches(const palp_assess_sample *s, int n, double R, double r, palp_touch *out, int cap) {
  int count = 0;
  double t_touch = -INFINITY;
  palp_touch cur = {0};
  for (int i = 0; i < n; ++i) {
    if (!s[i].contact) continue;
    if (s[i].t - t_touch > LIFT_GAP) { /* a touch-down: the touch before (if any) is complete */
      if (count > 0 && count <= cap) out[count - 1] = cur;
      count++;
      cur = (palp_touch){.t_on = s[i].t, .first_point = s[i].point};
    }
    t_touch = s[i].t;
    cur.contact_samples++;
    cur.t_off = s[i].t;
    cur.last_point = s[i].point;
    /* the same segments as palp_assess's path: consecutive samples both in contact */
    if (i > 0 && s[i - 1].contact) cur.path_length += v3_len(v3_sub(on_dome(s[i].proxy, R), on_dome(s[i - 1].proxy, R)));
    const double F = fnorm(s[i].force), indent = palp_fingertip_depth(R, r, s[i].proxy);
    if (F > cur.peak_force) cur.peak_force = F;
    if (indent > cur.peak_indentation) cur.peak_indentation = indent;
  }
  if (count > 0 && count <= cap) out[count - 1] = cur;
  return count;
}

int palp_assess(const palp_exercise *ex, const palp_mesh *mesh, double r, const palp_assess_sample *s, int n,
                const palp_finding *f, int nf, palp_assess_result *out, int *match, uint8_t *coverage) {
  /* the lesion count as palp_assess_findings checks it: more than PALP_MAX_LESIONS overran the matcher's
   * arrays (an exercise built by a caller, not the parser, which bounds it; session 90's review) */
  if (!ex || !mesh || !out || n < 0 || nf < 0 || (n && !s) || (nf && !f) || !(r > 0.0) || !mesh->vertex_area ||
      ex->lesion_count < 0 || ex->lesion_count > PALP_MAX_LESIONS)
    return PALP_EINVAL;
  memset(out, 0, sizeof *out);
  const double R = v3_len(mesh->rest[mesh->top_vertex]); /* the pole lies on the dome's radius */
  for (int i = 0; i < n; ++i)
    if (!isfinite(s[i].t) || !v3_isfinite(s[i].proxy) || !v3_isfinite(s[i].force) || !v3_isfinite(s[i].point) ||
        !isfinite(s[i].area) || (i > 0 && s[i].t < s[i - 1].t) || s[i].triangle_count < 0)
      return PALP_EINVAL;
  for (int i = 0; i < nf; ++i)
    if (!v3_isfinite(f[i].point) || !isfinite(f[i].t)) return PALP_EINVAL;

  const int mrc = match_findings(ex, R, f, nf, out, match);
  if (mrc != PALP_OK) return mrc;

  const int V = mesh->vertex_count;
  uint8_t *bands = calloc((size_t)V, 1);
  int *list = malloc(sizeof(int) * (size_t)V), *stamp = malloc(sizeof(int) * (size_t)V);
  int *visits = calloc((size_t)V, sizeof(int)), *parent = malloc(sizeof(int) * (size_t)V);
  double *last = malloc(sizeof(double) * (size_t)V);
  if (!bands || !list || !stamp || !visits || !parent || !last) {
    free(bands), free(list), free(stamp), free(visits), free(parent), free(last);
    return PALP_ENOMEM;
  }
  for (int v = 0; v < V; ++v) stamp[v] = -1, last[v] = -INFINITY;

  int above = 0;
  double t_touch = -INFINITY;
  for (int i = 0; i < n; ++i) {
    const double F = fnorm(s[i].force);
    if (F > out->peak_force) out->peak_force = F;
    const int hi = F > ex->max_force;
    if (hi && !above) out->out_of_range++;
    if (hi && i > 0) out->out_of_range_time += s[i].t - s[i - 1].t;
    above = hi;
    if (!s[i].contact) continue;
    if (s[i].t - t_touch > LIFT_GAP) out->evidence.presses++;
    t_touch = s[i].t;
    if (i > 0 && s[i - 1].contact) out->evidence.contact_time += s[i].t - s[i - 1].t;
    const double indent = palp_fingertip_depth(R, r, s[i].proxy);
    const int b = palp_exercise_band(ex, indent, F);
    const int k = footprint(mesh, &s[i], R, list, stamp, i);
    for (int j = 0; j < k; ++j) {
      const int v = list[j];
      if (b >= 0) bands[v] |= (uint8_t)(1u << b);
      if (s[i].t - last[v] > VISIT_GAP) visits[v]++;
      last[v] = s[i].t;
    }
  }
  if (n > 0) out->duration = s[n - 1].t - s[0].t;

  double total = 0.0, any = 0.0, cov[PALP_BAND_COUNT] = {0}, visit_area = 0.0;
  for (int v = 0; v < V; ++v) {
    const double A = mesh->vertex_area[v];
    total += A;
    for (int b = 0; b < PALP_BAND_COUNT; ++b)
      if (bands[v] & (1u << b)) cov[b] += A;
    if (visits[v]) any += A, visit_area += A * visits[v];
  }
  for (int b = 0; b < PALP_BAND_COUNT; ++b) out->coverage[b] = total > 0 ? cov[b] / total : 0.0;
  out->coverage_any = total > 0 ? any / total : 0.0;
  out->evidence.overlap = any > 0 ? visit_area / any : 0.0;
  out->evidence.gap_share = total > 0 ? 1.0 - out->coverage_any : 0.0;

  /* Gaps: connected regions of never-touched vertices over the dome's edges. */
  for (int v = 0; v < V; ++v) parent[v] = v;
  for (int t = 0; t < mesh->dome_triangle_count; ++t)
    for (int j = 0; j < 3; ++j) {
      const int a = mesh->tri[t][j], b = mesh->tri[t][(j + 1) % 3];
      if (!visits[a] && !visits[b]) parent[uf_find(parent, a)] = uf_find(parent, b);
    }
  for (int v = 0; v < V; ++v) last[v] = 0.0;
  for (int v = 0; v < V; ++v)
    if (!visits[v] && mesh->vertex_area[v] > 0.0) last[uf_find(parent, v)] += mesh->vertex_area[v];
  for (int v = 0; v < V; ++v)
    if (last[v] > out->evidence.largest_gap) out->evidence.largest_gap = last[v];

  if (coverage) memcpy(coverage, bands, (size_t)V);
  free(bands), free(list), free(stamp), free(visits), free(parent), free(last);

  pattern(s, n, R, &out->evidence, &out->pattern);

  /* Rubric: each component in [0, 1], the score their weighted mean (docs/assessment.md). */
  const palp_rubric *rb = &ex->rubric;
  double *c = out->component;
  c[PALP_METRIC_SENSITIVITY] = out->sensitivity;
  c[PALP_METRIC_FALSE_POSITIVES] = 1.0 / (1.0 + out->false_positives);
  c[PALP_METRIC_THOROUGHNESS] = (out->coverage[0] + out->coverage[1] + out->coverage[2]) / 3.0;
  /* A vertical-strip search earns full credit in any order unless the rubric rests a share of it
   * on the strips' order: at share 0.5 strips in a scattered order earn what circles earn. */
  const double order = out->evidence.sweep_monotony;
  c[PALP_METRIC_PATTERN] = out->pattern == PALP_PATTERN_VERTICAL_STRIP ? 1.0 - rb->strip_order_share * (1.0 - order)
                           : out->pattern == PALP_PATTERN_UNSYSTEMATIC ? 0.0
                                                                       : 0.5;
  c[PALP_METRIC_TIME] = out->duration <= ex->time_limit ? 1.0 : fmax(0.0, 2.0 - out->duration / ex->time_limit);
  c[PALP_METRIC_FORCE] = 1.0 / (1.0 + out->out_of_range);
  double ws = 0.0, sc = 0.0;
  for (int m = 0; m < PALP_METRIC_COUNT; ++m) ws += rb->weight[m], sc += rb->weight[m] * c[m];
  out->score = ws > 0 ? 100.0 * sc / ws : 0.0;

  int *p = out->pass_metric;
  p[PALP_METRIC_SENSITIVITY] = out->sensitivity >= rb->pass_sensitivity;
  p[PALP_METRIC_FALSE_POSITIVES] = out->false_positives <= rb->pass_max_false_positives;
  p[PALP_METRIC_THOROUGHNESS] = 1;
  for (int b = 0; b < PALP_BAND_COUNT; ++b)
    if (!(out->coverage[b] >= rb->pass_coverage[b])) p[PALP_METRIC_THOROUGHNESS] = 0;
  p[PALP_METRIC_PATTERN] = rb->pass_any_systematic ? out->pattern != PALP_PATTERN_UNSYSTEMATIC
                           : rb->pass_pattern == PALP_PATTERN_UNSYSTEMATIC ? 1
                                                                           : out->pattern == rb->pass_pattern;
  if (out->pattern == PALP_PATTERN_VERTICAL_STRIP && !(order >= rb->pass_strip_order)) p[PALP_METRIC_PATTERN] = 0;
  p[PALP_METRIC_TIME] = out->duration <= ex->time_limit;
  p[PALP_METRIC_FORCE] = out->out_of_range <= rb->pass_max_out_of_range;
  out->pass = out->score >= rb->pass_score;
  for (int m = 0; m < PALP_METRIC_COUNT; ++m) out->pass = out->pass && p[m];
  return PALP_OK;
}
