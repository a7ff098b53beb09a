/*
 * test_metrics.c - the session metrics on synthetic sessions whose answers are known
 * by construction (src/assess.c, docs/assessment.md): finding matching, coverage per
 * band, the pattern classifier on strips / circles / spokes / a random walk, force
 * episodes and the rubric score.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "palp_assess.h"

#define PI 3.14159265358979323846
static const double R = 0.04, r = 0.008;

static palp_exercise exercise(void) {
  palp_exercise ex;
  memset(&ex, 0, sizeof ex);
  ex.time_limit = 100;
  ex.lesion_count = 1;
  ex.lesion[0] = (palp_exercise_lesion){.polar = 30 * PI / 180, .azimuth = 0, .depth = 0.01, .diameter = 0.01,
                                        .stiffness_ratio = 5};
  for (int b = 0; b < 3; ++b) ex.band[b].has_depth = 1;
  ex.band[0].depth_min = 0.001, ex.band[0].depth_max = 0.005;
  ex.band[1].depth_min = 0.005, ex.band[1].depth_max = 0.012;
  ex.band[2].depth_min = 0.012, ex.band[2].depth_max = 0.025;
  ex.max_force = 3.0;
  ex.match_margin = 0.010;
  for (int m = 0; m < PALP_METRIC_COUNT; ++m) ex.rubric.weight[m] = 1.0;
  return ex;
}

/* A touching sample at unit direction n, indentation d [m], force f [N]. */
static palp_assess_sample at(double t, palp_vec3 n, double d, double f) {
  const double q = R + r - d;
  const palp_vec3 p = {q * n.x, q * n.y, q * n.z};
  return (palp_assess_sample){.t = t, .device = p, .proxy = p, .force = {0, 0, f}, .contact = 1,
                              .point = {R * n.x, R * n.y, R * n.z}, .area = 1e-4};
}
static palp_vec3 unit(double x, double y) { /* the dome point above plan position (x, y) */
  const double z = sqrt(fmax(R * R - x * x - y * y, 0.0));
  return (palp_vec3){x / R, y / R, z / R};
}

static double v3_dist_mm(palp_vec3 a, palp_vec3 b) { return 1e3 * sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z)); }

/* Plan-view trajectories, 1 mm per sample at 50 mm/s. */
typedef struct traj {
  palp_assess_sample *s;
  int n, cap;
} traj;
static void add(traj *T, double x, double y) {
  if (T->n == T->cap) T->s = realloc(T->s, sizeof *T->s * (size_t)(T->cap = T->cap ? 2 * T->cap : 1024));
  T->s[T->n] = at(T->n * 0.02, unit(x, y), 0.008, 0.5);
  T->n++;
}
static void line(traj *T, double x0, double y0, double x1, double y1) {
  const int k = (int)ceil(hypot(x1 - x0, y1 - y0) / 0.001);
  for (int i = 0; i <= k; ++i) add(T, x0 + (x1 - x0) * i / k, y0 + (y1 - y0) * i / k);
}

/* Classifies under a rubric that asks for a systematic pattern, rests half a strip search's
 * pattern credit on its strips' order and passes it from order 0.7 (the shipped exercises');
 * the result goes to *out when given. */
static palp_pattern classify_res(const palp_mesh *mesh, traj *T, const char *what, palp_pattern_evidence *ev,
                                 palp_assess_result *out) {
  palp_exercise ex = exercise();
  ex.rubric.pass_any_systematic = 1;
  ex.rubric.strip_order_share = 0.5;
  ex.rubric.pass_strip_order = 0.7;
  palp_assess_result res;
  CHECK(palp_assess(&ex, mesh, r, T->s, T->n, NULL, 0, &res, NULL, NULL) == 0, "%s assessed", what);
  if (out) *out = res;
  printf("%-8s plan %.3f m  axial %.2f (axis %.0f deg) tangential %.2f radial %.2f, %d strips in order %.2f -> %s\n",
         what, res.evidence.plan_length, res.evidence.share_axial, res.evidence.axis_deg, res.evidence.share_tangential,
         res.evidence.share_radial, res.evidence.strips, res.evidence.sweep_monotony, palp_pattern_name(res.pattern));
  if (ev) *ev = res.evidence;
  free(T->s);
  memset(T, 0, sizeof *T);
  return res.pattern;
}
static palp_pattern classify(const palp_mesh *mesh, traj *T, const char *what, palp_pattern_evidence *ev) {
  return classify_res(mesh, T, what, ev, NULL);
}

int main(void) {
  palp_mesh mesh;
  palp_mesh_def md = palp_mesh_default_def();
  CHECK(palp_mesh_create(&md, &mesh) == 0, "mesh");
  palp_exercise ex = exercise();
  palp_assess_result res;

  /* 1. Findings: lesion at polar 30 deg, azimuth 0, radius 5 mm: found within 5 + 10 mm
   * of its surface projection (R sin 30, 0, R cos 30) = (20, 0, 34.64) mm. */
  const palp_vec3 s0 = {0.020, 0.0, 0.034641016};
  palp_finding f[5] = {
      {1.0, {s0.x + 0.030, s0.y, s0.z}, 0},  /* 30 mm off: false */
      {2.0, {s0.x, s0.y + 0.012, s0.z}, 0},  /* 12 mm off: finds it */
      {3.0, {s0.x, s0.y - 0.010, s0.z}, 0},  /* second mark on the same lesion: duplicate */
      {4.0, {-0.02, 0.0, 0.0346}, 1},        /* withdrawn: ignored */
      {5.0, {s0.x, s0.y + 0.016, s0.z}, 0},  /* 16 mm off (> 15): false */
  };
  palp_assess_sample one = at(0, unit(0, 0), 0.003, 0.1);
  int match[5];
  CHECK(palp_assess(&ex, &mesh, r, &one, 1, f, 5, &res, match, NULL) == 0, "assess");
  CHECK(res.found == 1 && res.lesion_found[0] == 1, "the 12 mm mark finds the lesion (found %d by %d)", res.found,
        res.lesion_found[0]);
  CHECK(match[0] == PALP_FINDING_FALSE && match[1] == 0 && match[2] == PALP_FINDING_DUPLICATE &&
            match[3] == PALP_FINDING_WITHDRAWN && match[4] == PALP_FINDING_FALSE,
        "matches %d %d %d %d %d", match[0], match[1], match[2], match[3], match[4]);
  CHECK(res.false_positives == 2 && res.duplicates == 1 && res.withdrawn == 1 && res.findings == 4,
        "fp %d dup %d withdrawn %d findings %d", res.false_positives, res.duplicates, res.withdrawn, res.findings);
  CHECK_NEAR(res.sensitivity, 1.0, 0.0, "sensitivity");
  { /* session 90's review: a lesion count past PALP_MAX_LESIONS (a caller's own exercise) is refused, as
     * palp_assess_findings refuses it; it overran the matcher's arrays (d[PALP_MAX_LESIONS]) */
    palp_exercise many = ex;
    many.lesion_count = PALP_MAX_LESIONS + 1;
    palp_exercise none = ex;
    none.lesion_count = -1;
    CHECK(palp_assess(&many, &mesh, r, &one, 1, f, 5, &res, match, NULL) == PALP_EINVAL &&
              palp_assess(&none, &mesh, r, &one, 1, f, 5, &res, match, NULL) == PALP_EINVAL,
          "lesion counts %d and -1 refused (PALP_EINVAL)", PALP_MAX_LESIONS + 1);
  }
  /* The same findings without a session (the server's debrief): the same verdicts, on the dome of
   * the mesh's pole radius (40 mm, the default mesh). */
  {
    palp_assess_result d;
    int dm[5];
    CHECK(palp_assess_findings(&ex, 0.04, f, 5, &d, dm) == 0, "palp_assess_findings");
    CHECK(d.found == 1 && d.lesion_found[0] == 1 && d.false_positives == 2 && d.duplicates == 1 && d.withdrawn == 1 &&
              d.findings == 4 && dm[0] == PALP_FINDING_FALSE && dm[1] == 0 && dm[2] == PALP_FINDING_DUPLICATE &&
              dm[3] == PALP_FINDING_WITHDRAWN && dm[4] == PALP_FINDING_FALSE,
          "  as palp_assess: found %d by %d, fp %d, dup %d, withdrawn %d", d.found, d.lesion_found[0],
          d.false_positives, d.duplicates, d.withdrawn);
    const palp_finding bad = {0.0, {NAN, 0, 0.04}, 0};
    CHECK(palp_assess_findings(&ex, 0.04, &bad, 1, &d, NULL) == PALP_EINVAL, "  a NaN point refused");
    CHECK(palp_assess_findings(&ex, 0.0, f, 5, &d, NULL) == PALP_EINVAL, "  a zero radius refused");
  }

  /* 1b. The order of the marks does not decide what is found (session 81 review). Two 10 mm lesions
   * at polar 30 deg, azimuth 0 (A) and 40 deg (B), margin 10 mm: reach 15 mm. On the 40 mm dome the
   * ring at polar 30 has radius 20 mm, so a chord between azimuths a and b is 40 sin(|a - b| / 2) mm:
   * A-B 13.68. Mark P at azimuth 18 deg: 6.26 mm from A, 7.63 from B (reaches both); mark Q at -20
   * deg: 6.95 from A, 20.0 from B (reaches A only). Either order: both lesions found, P finding B and
   * Q finding A (the only maximum matching). The greedy rule before gave P the nearer A and left Q a
   * duplicate in the order (P, Q): 1 of 2. */
  {
    palp_exercise two = exercise();
    two.lesion_count = 2;
    two.lesion[1] = two.lesion[0];
    two.lesion[1].azimuth = 40 * PI / 180;
    const double p30 = 30 * PI / 180;
#define ON_RING(az_deg) {R * sin(p30) * cos((az_deg) * PI / 180), R * sin(p30) * sin((az_deg) * PI / 180), R * cos(p30)}
    const palp_finding P = {1.0, ON_RING(18.0), 0}, Q = {2.0, ON_RING(-20.0), 0};
    const palp_finding pq[2] = {P, Q}, qp[2] = {Q, P};
    palp_assess_result d;
    int dm[2];
    CHECK(palp_assess_findings(&two, R, pq, 2, &d, dm) == 0 && d.found == 2 && d.duplicates == 0 &&
              d.false_positives == 0 && dm[0] == 1 && dm[1] == 0 && d.lesion_found[0] == 1 && d.lesion_found[1] == 0,
          "marks (P at 18 deg, Q at -20 deg): found %d of 2, dup %d, false %d, P -> %d, Q -> %d (want 2, 0, 0, B=1, A=0)",
          d.found, d.duplicates, d.false_positives, dm[0], dm[1]);
    CHECK(palp_assess_findings(&two, R, qp, 2, &d, dm) == 0 && d.found == 2 && d.duplicates == 0 &&
              d.false_positives == 0 && dm[0] == 0 && dm[1] == 1 && d.lesion_found[0] == 0 && d.lesion_found[1] == 1,
          "marks (Q, P): found %d of 2, dup %d, false %d, Q -> %d, P -> %d (want 2, 0, 0, A=0, B=1)", d.found,
          d.duplicates, d.false_positives, dm[0], dm[1]);
    /* palp_assess matches the same way */
    CHECK(palp_assess(&two, &mesh, r, &one, 1, pq, 2, &res, match, NULL) == 0 && res.found == 2 &&
              res.duplicates == 0 && fabs(res.sensitivity - 1.0) < 1e-12,
          "palp_assess on (P, Q): found %d of 2, dup %d", res.found, res.duplicates);
    /* A true duplicate stays one: Q and a mark at -10 deg (3.49 mm from A, 40 sin 25 = 16.9 mm from
     * B: out of reach) both reach A alone, whatever their order; a mark at azimuth 180 deg (40 mm
     * from A, 40 sin 70 = 37.6 from B) reaches neither. The first of the two in log order is
     * credited (the nearer one coming later does not take it). B is missed. */
    const palp_finding Q2 = {3.0, ON_RING(-10.0), 0}, far = {4.0, ON_RING(180.0), 0};
    const palp_finding dup[3] = {Q, Q2, far};
    int dm3[3];
    CHECK(palp_assess_findings(&two, R, dup, 3, &d, dm3) == 0 && d.found == 1 && d.duplicates == 1 &&
              d.false_positives == 1 && d.lesion_found[0] == 0 && d.lesion_found[1] == -1 && dm3[0] == 0 &&
              dm3[1] == PALP_FINDING_DUPLICATE && dm3[2] == PALP_FINDING_FALSE,
          "two marks on A alone, one far: found %d, dup %d, false %d, A by %d, B by %d (want 1, 1, 1, 0, -1)", d.found,
          d.duplicates, d.false_positives, d.lesion_found[0], d.lesion_found[1]);
    const palp_finding dup2[3] = {far, Q2, Q};
    CHECK(palp_assess_findings(&two, R, dup2, 3, &d, dm3) == 0 && d.found == 1 && d.duplicates == 1 &&
              d.false_positives == 1 && d.lesion_found[0] == 1 && dm3[0] == PALP_FINDING_FALSE && dm3[1] == 0 &&
              dm3[2] == PALP_FINDING_DUPLICATE,
          "reversed: found %d, dup %d, false %d, A by %d (want 1, 1, 1, 1)", d.found, d.duplicates, d.false_positives,
          d.lesion_found[0]);
#undef ON_RING
  }

  /* 1c. A figure as printed against its mark (palp_shown_tenths, session 81 review), by hand: 69.96
   * missing 70 is floored to 69.9 (rounding gave 70.0); 70.04 reaching a mark of 70.04 is ceiled to
   * 70.1 (rounding gave 70.0, under it); 99.625 passing rounds to 99.6; with no mark known a figure
   * that missed is floored (18.05 -> 18.0), one that reached rounds (85.07 -> 85.1). */
  CHECK_NEAR(palp_shown_tenths(69.96, 70, 0), 69.9, 1e-9, "69.96 short of 70");
  CHECK_NEAR(palp_shown_tenths(70.04, 70.04, 1), 70.1, 1e-9, "70.04 at a mark of 70.04");
  CHECK_NEAR(palp_shown_tenths(99.625, 70, 1), 99.6, 1e-9, "99.625 passing");
  CHECK_NEAR(palp_shown_tenths(18.05, NAN, 0), 18.0, 1e-9, "18.05 not passed, mark unknown");
  CHECK_NEAR(palp_shown_tenths(85.07, NAN, 1), 85.1, 1e-9, "85.07 passed, mark unknown");
  CHECK_NEAR(palp_shown_tenths(65.07, 70, 0), 65.1, 1e-9, "65.07 well short of 70: rounded");

  /* 2. Coverage: one sample touching every dome triangle at 8 mm covers the whole
   * surface in the medium band and nothing in the others. */
  int *all = malloc(sizeof(int) * (size_t)mesh.dome_triangle_count);
  for (int t = 0; t < mesh.dome_triangle_count; ++t) all[t] = t;
  palp_assess_sample full = at(0, unit(0, 0), 0.008, 0.5);
  full.triangles = all, full.triangle_count = mesh.dome_triangle_count;
  uint8_t *cov = malloc((size_t)mesh.vertex_count);
  CHECK(palp_assess(&ex, &mesh, r, &full, 1, NULL, 0, &res, NULL, cov) == 0, "assess");
  CHECK_NEAR(res.coverage[PALP_BAND_MEDIUM], 1.0, 1e-12, "all triangles: medium coverage");
  CHECK(res.coverage[PALP_BAND_LIGHT] == 0.0 && res.coverage[PALP_BAND_DEEP] == 0.0, "other bands untouched");
  CHECK(cov[mesh.top_vertex] == (1u << PALP_BAND_MEDIUM), "pole's map entry is the medium bit (%u)",
        (unsigned)cov[mesh.top_vertex]);
  CHECK(res.evidence.gap_share < 1e-12 && res.evidence.largest_gap == 0.0, "no gap");
  /* one triangle: its three vertices' areas over the dome's */
  full.triangle_count = 1;
  CHECK(palp_assess(&ex, &mesh, r, &full, 1, NULL, 0, &res, NULL, NULL) == 0, "assess");
  double tot = 0.0;
  for (int v = 0; v < mesh.vertex_count; ++v) tot += mesh.vertex_area[v];
  const double tri = mesh.vertex_area[mesh.tri[0][0]] + mesh.vertex_area[mesh.tri[0][1]] + mesh.vertex_area[mesh.tri[0][2]];
  CHECK_NEAR(res.coverage[PALP_BAND_MEDIUM], tri / tot, 1e-12, "one triangle's coverage");
  /* outside every band (0.5 mm): touched, counted in coverage_any, in no band */
  full.proxy = (palp_vec3){0, 0, R + r - 0.0005};
  CHECK(palp_assess(&ex, &mesh, r, &full, 1, NULL, 0, &res, NULL, NULL) == 0, "assess");
  CHECK(res.coverage[0] == 0 && res.coverage[1] == 0 && res.coverage[2] == 0 && res.coverage_any > 0,
        "0.5 mm: in no band, yet touched");
  /* no triangles: the disc of the area around the point; a disc wider than the dome covers it all */
  palp_assess_sample disc = at(0, unit(0, 0), 0.003, 0.1);
  disc.area = PI * 0.2 * 0.2;
  CHECK(palp_assess(&ex, &mesh, r, &disc, 1, NULL, 0, &res, NULL, NULL) == 0, "assess");
  CHECK_NEAR(res.coverage[PALP_BAND_LIGHT], 1.0, 1e-12, "a 20 cm disc covers the dome");
  disc.area = 1e-12; /* a point: just the nearest vertex, the pole */
  CHECK(palp_assess(&ex, &mesh, r, &disc, 1, NULL, 0, &res, NULL, NULL) == 0, "assess");
  CHECK_NEAR(res.coverage[PALP_BAND_LIGHT], mesh.vertex_area[mesh.top_vertex] / tot, 1e-12, "a point: the pole only");

  /* 3. Forces and time: two excursions above 3 N, peak 4.5 N, 100 samples at 0.01 s. */
  palp_assess_sample fs[100];
  for (int i = 0; i < 100; ++i) {
    const double F = (i >= 10 && i < 20) ? 3.5 : (i >= 50 && i < 55) ? 4.5 : 1.0;
    fs[i] = at(i * 0.01, unit(0, 0), 0.008, F);
  }
  CHECK(palp_assess(&ex, &mesh, r, fs, 100, NULL, 0, &res, NULL, NULL) == 0, "assess");
  CHECK(res.out_of_range == 2, "two episodes (%d)", res.out_of_range);
  CHECK_NEAR(res.out_of_range_time, 0.15, 1e-9, "0.10 s + 0.05 s above");
  CHECK_NEAR(res.peak_force, 4.5, 1e-12, "peak");
  CHECK_NEAR(res.duration, 0.99, 1e-12, "duration");
  CHECK(res.evidence.presses == 1, "one press (%d)", res.evidence.presses);
  /* score: sensitivity 0, fp 0 -> 1, thoroughness (0 + cov + 0)/3, pattern 0, time 1, force 1/3 */
  const double want = 100.0 * (0 + 1 + res.coverage[1] / 3.0 + 0 + 1 + 1.0 / 3.0) / 6.0;
  CHECK_NEAR(res.score, want, 1e-9, "equal-weight score");
  CHECK(!res.pass_metric[PALP_METRIC_SENSITIVITY] || ex.rubric.pass_sensitivity == 0, "pass flags");
  /* bad input is refused */
  fs[5].t = NAN;
  CHECK(palp_assess(&ex, &mesh, r, fs, 100, NULL, 0, &res, NULL, NULL) == PALP_EINVAL, "NaN time refused");
  fs[5].t = 0.05;
  fs[6].t = 0.0;
  CHECK(palp_assess(&ex, &mesh, r, fs, 100, NULL, 0, &res, NULL, NULL) == PALP_EINVAL, "time going back refused");

  /* 4. The classifier. Vertical strips 8 mm apart, boustrophedon, across the dome. */
  traj T = {0};
  palp_pattern_evidence ev;
  for (int k = -4; k <= 4; ++k) {
    const double x = k * 0.008, h = sqrt(0.037 * 0.037 - x * x), y = (k % 2) ? h : -h;
    if (T.n) line(&T, T.s[T.n - 1].point.x, T.s[T.n - 1].point.y, x, y);
    line(&T, x, y, x, -y);
  }
  palp_assess_result cr;
  CHECK(classify_res(&mesh, &T, "strips", &ev, &cr) == PALP_PATTERN_VERTICAL_STRIP, "strips");
  /* in order: the pattern's full credit and its pass under a rubric that asks for the order */
  CHECK(cr.component[PALP_METRIC_PATTERN] == 1.0 && cr.pass_metric[PALP_METRIC_PATTERN],
        "strips in order: credit %.3f (want 1), pass %d", cr.component[PALP_METRIC_PATTERN],
        cr.pass_metric[PALP_METRIC_PATTERN]);
  CHECK(fabs(fabs(ev.axis_deg) - 90.0) < 5.0, "strip axis along y (%.1f deg)", ev.axis_deg);
  /* nine strips, each a step the same way across: every step keeps the one before's direction */
  CHECK(ev.strips == 9, "nine strips (%d)", ev.strips);
  CHECK(ev.sweep_monotony == 1.0, "strips in order across the dome (%.3f)", ev.sweep_monotony);
  /* The same strips in a scattered order (places -4..4 visited 0, 3, -2, 4, -4, 1, -1, 2, -3: every
   * step reverses the one before) are still strips, but not in order; and a search of the left half
   * in order and then the right half in order (0..-4, 4..1) reverses twice in its 7 pairs of steps:
   * at the jump to the right edge, and where it goes on leftwards from there. */
  static const int scattered[9] = {0, 3, -2, 4, -4, 1, -1, 2, -3}, halves[9] = {0, -1, -2, -3, -4, 4, 3, 2, 1};
  const int *order[2] = {scattered, halves};
  const double want_order[2] = {0.0, 5.0 / 7.0};
  for (int o = 0; o < 2; ++o) {
    for (int j = 0; j < 9; ++j) {
      const int k = order[o][j];
      const double x = k * 0.008, h = sqrt(0.037 * 0.037 - x * x), y = (j % 2) ? h : -h;
      if (T.n) line(&T, T.s[T.n - 1].point.x, T.s[T.n - 1].point.y, x, y);
      line(&T, x, y, x, -y);
    }
    CHECK(classify_res(&mesh, &T, o ? "halves" : "scatter", &ev, &cr) == PALP_PATTERN_VERTICAL_STRIP,
          "strips in any order");
    CHECK(ev.strips == 9, "nine strips (%d)", ev.strips);
    CHECK(fabs(ev.sweep_monotony - want_order[o]) < 1e-12, "%s: strips in order %.3f (want %.3f)",
          o ? "two halves" : "scattered", ev.sweep_monotony, want_order[o]);
    /* credit 1 - 0.5 (1 - order): scattered 0.5 (what circles earn), two halves 1 - 0.5 x 2/7 = 6/7;
     * the pass at 0.7: the halves (5/7 = 0.714) pass, the scattered strips do not */
    const double want_credit[2] = {0.5, 6.0 / 7.0};
    CHECK(fabs(cr.component[PALP_METRIC_PATTERN] - want_credit[o]) < 1e-12, "%s: pattern credit %.4f (want %.4f)",
          o ? "two halves" : "scattered", cr.component[PALP_METRIC_PATTERN], want_credit[o]);
    CHECK(cr.pass_metric[PALP_METRIC_PATTERN] == o, "%s: pattern %s under pass 0.7", o ? "two halves" : "scattered",
          cr.pass_metric[PALP_METRIC_PATTERN] ? "passes" : "fails");
  }
  /* strips all stroked the same way, each followed by a lift and a return in the air: lifts end strips */
  for (int k = -4; k <= 4; ++k) {
    const double x = k * 0.008, h = sqrt(0.037 * 0.037 - x * x);
    const double t0 = T.n ? T.s[T.n - 1].t + 1.0 : 0.0; /* a 1 s lift */
    const int first = T.n;
    line(&T, x, -h, x, h);
    for (int i = first; i < T.n; ++i) T.s[i].t += t0;
  }
  {
    /* The same strips as touches (palp_assess_touches): one per strip, each from (x, -h) to (x, h) on the
     * dome, 8 mm deep at 0.5 N (at() above); as many as palp_assess's presses, their paths summing to
     * its path length. */
    palp_touch tv[12];
    const int nt = palp_assess_touches(T.s, T.n, R, r, tv, 12);
    palp_exercise tex = exercise();
    palp_assess_result tres;
    CHECK(palp_assess(&tex, &mesh, r, T.s, T.n, NULL, 0, &tres, NULL, NULL) == 0, "lifted strips assessed");
    CHECK(nt == 9 && nt == tres.evidence.presses, "touches: %d, palp_assess's presses %d (want 9)", nt,
          tres.evidence.presses);
    double sum = 0.0, worst = 0.0;
    for (int k = 0; k < nt && k < 12; ++k) {
      const double x = (k - 4) * 0.008, h = sqrt(0.037 * 0.037 - x * x);
      const palp_vec3 a = unit(x, -h), b = unit(x, h);
      worst = fmax(worst, fmax(v3_dist_mm(tv[k].first_point, (palp_vec3){R * a.x, R * a.y, R * a.z}),
                               v3_dist_mm(tv[k].last_point, (palp_vec3){R * b.x, R * b.y, R * b.z})));
      CHECK(k == 0 || tv[k].t_on - tv[k - 1].t_off > PALP_ASSESS_LIFT_GAP_S, "touch %d starts after a lift", k + 1);
      CHECK(fabs(tv[k].peak_force - 0.5) < 1e-12 && fabs(tv[k].peak_indentation - 0.008) < 1e-12,
            "touch %d: peak %.3f N, deepest %.4f m (want 0.5 N, 0.008 m)", k + 1, tv[k].peak_force,
            tv[k].peak_indentation);
      sum += tv[k].path_length;
    }
    CHECK(worst < 1e-9, "each touch comes down and lifts where its strip begins and ends (worst %.2g mm)", worst);
    CHECK(fabs(sum - tres.evidence.path_length) < 1e-12, "the touches' paths sum to the path length (%.6f vs %.6f m)",
          sum, tres.evidence.path_length);
    CHECK(palp_assess_touches(T.s, T.n, R, r, tv, 3) == 9, "a short buffer still gets the count");
    CHECK(palp_assess_touches(T.s, T.n, R, r, NULL, 0) == 9 && palp_assess_touches(T.s, 0, R, r, NULL, 0) == 0,
          "counting only; no samples, no touches");
  }
  CHECK(classify(&mesh, &T, "lifted", &ev) == PALP_PATTERN_VERTICAL_STRIP, "lifted strips");
  CHECK(ev.strips == 9 && ev.sweep_monotony == 1.0, "lifted strips: %d in order %.3f", ev.strips, ev.sweep_monotony);
  /* the same, rotated by 30 deg: any strip direction counts */
  for (int k = -4; k <= 4; ++k) {
    const double x = k * 0.008, h = sqrt(0.037 * 0.037 - x * x), y = (k % 2) ? h : -h;
    const double c = cos(PI / 6), s = sin(PI / 6);
    double px = x * c - y * s, py = x * s + y * c;
    if (T.n) line(&T, T.s[T.n - 1].point.x, T.s[T.n - 1].point.y, px, py);
    line(&T, px, py, x * c + y * s, x * s - y * c);
  }
  CHECK(classify(&mesh, &T, "strips30", NULL) == PALP_PATTERN_VERTICAL_STRIP, "rotated strips");
  /* concentric circles, 8 mm apart */
  for (int k = 1; k <= 4; ++k) {
    const double rho = k * 0.008;
    if (T.n) line(&T, T.s[T.n - 1].point.x, T.s[T.n - 1].point.y, rho, 0);
    for (int i = 0; i <= (int)(2 * PI * rho / 0.001); ++i) {
      const double a = i * 0.001 / rho;
      add(&T, rho * cos(a), rho * sin(a));
    }
  }
  CHECK(classify_res(&mesh, &T, "circles", &ev, &cr) == PALP_PATTERN_CIRCLES, "circles");
  /* the strips' order is asked of a strip search only: circles keep their half credit and pass */
  CHECK(cr.component[PALP_METRIC_PATTERN] == 0.5 && cr.pass_metric[PALP_METRIC_PATTERN],
        "circles: credit %.3f (want 0.5), pass %d whatever their axial runs' order (%.2f)",
        cr.component[PALP_METRIC_PATTERN], cr.pass_metric[PALP_METRIC_PATTERN], ev.sweep_monotony);
  /* radial spokes (wedges): out and back along 12 directions */
  for (int k = 0; k < 12; ++k) {
    const double a = k * PI / 6;
    line(&T, 0, 0, 0.036 * cos(a), 0.036 * sin(a));
    line(&T, 0.036 * cos(a), 0.036 * sin(a), 0, 0);
  }
  CHECK(classify(&mesh, &T, "spokes", NULL) == PALP_PATTERN_RADIAL, "spokes");
  /* a random walk: 10 mm legs in random directions, kept on the dome */
  unsigned st = 12345u;
  double x = 0, y = 0;
  for (int k = 0; k < 80; ++k) {
    st = st * 1664525u + 1013904223u;
    const double a = (st >> 8) / 16777216.0 * 2 * PI;
    double nx = x + 0.010 * cos(a), ny = y + 0.010 * sin(a);
    if (hypot(nx, ny) > 0.034) nx = x - 0.010 * cos(a), ny = y - 0.010 * sin(a);
    line(&T, x, y, nx, ny);
    x = nx, y = ny;
  }
  CHECK(classify(&mesh, &T, "random", NULL) == PALP_PATTERN_UNSYSTEMATIC, "random walk");
  /* too little search to have a pattern: one 5 cm stroke */
  line(&T, -0.025, 0, 0.025, 0);
  CHECK(classify(&mesh, &T, "stroke", NULL) == PALP_PATTERN_UNSYSTEMATIC, "a single 5 cm stroke");

  free(all), free(cov);
  palp_mesh_destroy(&mesh);
  CHECK_DONE();
}
