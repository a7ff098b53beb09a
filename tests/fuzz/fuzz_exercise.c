/* fuzz_exercise.c - what an instructor's review assesses: an exercise file (the JSON the server
 * loads from config/exercises/, and that palp-review parses again out of each session's log,
 * a file anyone may hand it) and a session's finger samples and marks (the log's rows: a damaged
 * or hand-edited file gives any values) through palp_exercise_parse, palp_exercise_lesions and
 * palp_assess / palp_assess_touches.
 *
 * Properties: a refused exercise says why (a non-empty message); an accepted one holds the
 * ranges docs/assessment.md states, and its lesions lie inside the dome above its base; an
 * accepted session's metrics are finite and in their ranges (shares in [0, 1], a score in
 * [0, 100], each mark a lesion or a code), and its touches are palp_assess's presses, their
 * paths summing to its path length (the review prints both).
 *
 * Input: the exercise JSON up to the first NUL byte (a fixed valid exercise when it is refused,
 * so that the samples are fuzzed either way); after it, records of 24 bytes: a sample (clock
 * step, fingertip centre, force, contact point, footprint, contact flag, up to 3 touched
 * triangles of any index) or, when its first byte is 0xff, a mark (point, withdrawn). */
#include <math.h>
#include <string.h>

#include "fuzz_util.h"
#include "palp.h"
#include "palp_assess.h"

static const char fallback[] =
    "{\"name\": \"f\", \"title\": \"t\", \"phantom\": \"p.json\", \"instructions\": \"i\", \"time_limit_s\": 300,"
    " \"lesions\": [{\"polar_deg\": 30, \"azimuth_deg\": 40, \"depth_mm\": 10, \"diameter_mm\": 15,"
    " \"stiffness_ratio\": 5}, {\"polar_deg\": 60, \"azimuth_deg\": 200, \"depth_mm\": 12, \"diameter_mm\": 10,"
    " \"stiffness_ratio\": 0.2}],"
    " \"pressure_bands\": {\"light\": {\"depth_mm\": [1, 4]}, \"medium\": {\"depth_mm\": [4, 9]},"
    " \"deep\": {\"depth_mm\": [9, 18], \"force_N\": [2, 20]}}, \"max_force_N\": 15, \"match_margin_mm\": 10,"
    " \"rubric\": {\"weights\": {\"sensitivity\": 40, \"false_positives\": 15, \"thoroughness\": 25, \"pattern\": 10,"
    " \"time\": 5, \"force\": 5}, \"strip_order_share\": 0.5, \"pass\": {\"sensitivity\": 1, \"max_false_positives\": 0,"
    " \"coverage\": {\"light\": 0.9, \"medium\": 0.9, \"deep\": 0.8}, \"pattern\": \"systematic\","
    " \"max_out_of_range\": 0, \"strip_order\": 0.7, \"score\": 70}}}";

static int16_t i16(const uint8_t *p) { return (int16_t)(p[0] | p[1] << 8); }
static int in01(double x) { return x >= 0.0 && x <= 1.0; }
static int fin(palp_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

#define FAIL(...)                 \
  do {                            \
    fprintf(stderr, __VA_ARGS__); \
    fputc('\n', stderr);          \
    abort();                      \
  } while (0)

/* A random exercise as the server draws it for a session (src/placement.c): a draw is refused
 * with a message or gives a drawn exercise whose lesions lie in the band, fit the dome, and come
 * back the same from the text the session log keeps. */
static void check_draw(const char *json, const palp_exercise *ex) {
  const double R = 0.04;
  palp_exercise d;
  char err[512] = "";
  if (palp_exercise_draw(ex, R, 7u, &d, err, sizeof err) != 0) {
    if (!err[0]) FAIL("draw refused without a message");
    return;
  }
  if (ex->placement.kind != PALP_PLACEMENT_RANDOM) {
    int same = d.lesion_count == ex->lesion_count && d.placement.kind == ex->placement.kind;
    for (int i = 0; same && i < d.lesion_count; ++i) /* field by field: not the structs' padding */
      same = d.lesion[i].polar == ex->lesion[i].polar && d.lesion[i].azimuth == ex->lesion[i].azimuth &&
             d.lesion[i].depth == ex->lesion[i].depth && d.lesion[i].diameter == ex->lesion[i].diameter;
    if (!same) FAIL("a fixed or drawn exercise changed by a draw");
    return;
  }
  if (d.placement.kind != PALP_PLACEMENT_DRAWN || d.placement.seed != 7u) FAIL("draw: kind %d", (int)d.placement.kind);
  for (int i = 0; i < d.lesion_count; ++i)
    if (!(d.lesion[i].polar >= ex->placement.polar_min - 1e-12 && d.lesion[i].polar <= ex->placement.polar_max + 1e-12))
      FAIL("drawn lesion %d at polar %g outside the band", i, d.lesion[i].polar);
  palp_lesion les[PALP_MAX_LESIONS];
  if (palp_exercise_lesions(&d, R, les, PALP_MAX_LESIONS, err, sizeof err) != d.lesion_count) FAIL("drawn lesions: %s", err);
  char *text = palp_exercise_drawn_json(json, &d);
  palp_exercise back;
  if (!text || palp_exercise_parse(text, "/nonexistent", &back, err, sizeof err) != 0) FAIL("drawn text: %s", err);
  for (int i = 0; i < d.lesion_count; ++i)
    if (fabs(back.lesion[i].polar - d.lesion[i].polar) > 1e-12 || fabs(back.lesion[i].azimuth - d.lesion[i].azimuth) > 1e-12)
      FAIL("drawn lesion %d not read back", i);
  free(text);
}

static void check_exercise(const palp_exercise *ex) {
  if (ex->lesion_count < 0 || ex->lesion_count > PALP_MAX_LESIONS) FAIL("lesion count %d", ex->lesion_count);
  if (!(ex->time_limit >= 1.0 && ex->time_limit <= 86400.0)) FAIL("time limit %g", ex->time_limit);
  if (!(ex->max_force > 0.0) || !isfinite(ex->max_force)) FAIL("max force %g", ex->max_force);
  if (!(ex->match_margin >= 0.0) || !isfinite(ex->match_margin)) FAIL("match margin %g", ex->match_margin);
  const double R = 0.04; /* [m] the shipped dome */
  palp_lesion les[PALP_MAX_LESIONS];
  char err[512] = "";
  const int nl = palp_exercise_lesions(ex, R, les, PALP_MAX_LESIONS, err, sizeof err);
  if (nl < 0 && !err[0]) FAIL("lesions refused without a message");
  for (int i = 0; i < nl; ++i) {
    const palp_vec3 c = les[i].center;
    const double r = les[i].radius, d = sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
    if (!fin(c) || !(r > 0.0) || d + r > R * (1.0 + 1e-9) || c.z - r < -1e-12)
      FAIL("lesion %d: centre (%g, %g, %g) m, radius %g m: not inside the dome above its base", i, c.x, c.y, c.z, r);
    if (!(les[i].stiffness_ratio > 0.0) || !isfinite(les[i].stiffness_ratio)) FAIL("lesion %d stiffness", i);
  }
  static const double depth[] = {-1, 0, 0.5e-3, 1e-3, 4e-3, 9e-3, 0.018, 0.05, NAN, INFINITY};
  for (size_t i = 0; i < sizeof depth / sizeof *depth; ++i) {
    const int b = palp_exercise_band(ex, depth[i], 3.0);
    if (b < -1 || b >= PALP_BAND_COUNT) FAIL("band %d", b);
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static palp_mesh mesh;
  static int have_mesh;
  if (!have_mesh) {
    palp_mesh_def md = palp_mesh_default_def();
    if (palp_mesh_create(&md, &mesh) != 0) abort();
    have_mesh = 1;
  }
  size_t jn = 0;
  while (jn < size && data[jn]) jn++;
  char *json = fuzz_cstr(data, jn);
  palp_exercise ex;
  char err[512] = "";
  if (palp_exercise_parse(json, "/nonexistent", &ex, err, sizeof err) == 0) {
    check_exercise(&ex);
    check_draw(json, &ex);
  } else {
    if (!err[0]) FAIL("exercise refused without a message");
    if (palp_exercise_parse(fallback, NULL, &ex, err, sizeof err) != 0) FAIL("fallback: %s", err);
  }
  free(json);

  /* the session: samples and marks */
  const uint8_t *p = data + (jn < size ? jn + 1 : size);
  size_t left = size - (size_t)(p - data);
  const int cap = (int)(left / 24);
  palp_assess_sample *s = calloc((size_t)cap + 1, sizeof *s);
  palp_finding *f = calloc((size_t)cap + 1, sizeof *f);
  int(*tri)[3] = calloc((size_t)cap + 1, sizeof *tri);
  if (!s || !f || !tri) abort();
  int n = 0, nf = 0;
  double t = 0.0;
  for (; left >= 24; p += 24, left -= 24) {
    if (p[0] == 0xff) { /* a mark */
      f[nf++] = (palp_finding){.t = t, .point = {i16(p + 1) * 5e-5, i16(p + 3) * 5e-5, i16(p + 5) * 5e-5},
                               .withdrawn = p[7] & 1};
      continue;
    }
    palp_assess_sample *q = &s[n];
    t += p[0] * 1e-3; /* [s] a lift is a gap over 0.25 s */
    q->t = t;
    q->proxy = (palp_vec3){i16(p + 1) * 5e-5, i16(p + 3) * 5e-5, i16(p + 5) * 5e-5}; /* +-1.6 m */
    q->device = q->proxy;
    q->force = (palp_vec3){i16(p + 7) * 1e-3, i16(p + 9) * 1e-3, i16(p + 11) * 1e-3}; /* +-33 N */
    q->point = (palp_vec3){i16(p + 13) * 5e-5, i16(p + 15) * 5e-5, i16(p + 17) * 5e-5};
    q->area = p[19] * 1e-6;                                                           /* [m^2] */
    q->contact = p[20] & 1;
    q->triangle_count = (p[20] >> 1) % 4;
    for (int k = 0; k < 3; ++k) tri[n][k] = (int)(int8_t)p[21 + k] * 8; /* -1024..1016: some not on the dome */
    q->triangles = q->triangle_count ? tri[n] : NULL;
    n++;
  }
  palp_assess_result r;
  int *match = calloc((size_t)nf + 1, sizeof *match);
  uint8_t *cov = calloc((size_t)mesh.vertex_count, 1);
  if (!match || !cov) abort();
  const double rf = 0.008; /* [m] the fingertip */
  if (palp_assess(&ex, &mesh, rf, s, n, f, nf, &r, match, cov) == 0) {
    if (r.found < 0 || r.found > r.lesion_count || r.lesion_count != ex.lesion_count) FAIL("found %d", r.found);
    if (!in01(r.sensitivity) || !in01(r.coverage_any)) FAIL("sensitivity %g, coverage %g", r.sensitivity, r.coverage_any);
    for (int b = 0; b < PALP_BAND_COUNT; ++b)
      if (!in01(r.coverage[b])) FAIL("coverage[%d] %g", b, r.coverage[b]);
    for (int m = 0; m < PALP_METRIC_COUNT; ++m)
      if (!in01(r.component[m])) FAIL("component %d: %g", m, r.component[m]);
    if (!(r.score >= 0.0 && r.score <= 100.0)) FAIL("score %g", r.score);
    if (!strcmp(palp_pattern_name(r.pattern), "?")) FAIL("pattern %d", (int)r.pattern);
    const palp_pattern_evidence *e = &r.evidence;
    if (!(e->path_length >= 0.0) || !isfinite(e->path_length) || !(e->overlap >= 0.0) || !isfinite(e->overlap) ||
        !in01(e->gap_share) || !in01(e->sweep_monotony) || !(e->largest_gap >= 0.0) || e->strips < 0 ||
        e->presses < 0 || !(r.peak_force >= 0.0) || !isfinite(r.peak_force) || !(r.duration >= 0.0))
      FAIL("evidence: path %g, overlap %g, gap %g, monotony %g, strips %d, presses %d", e->path_length, e->overlap,
           e->gap_share, e->sweep_monotony, e->strips, e->presses);
    for (int i = 0; i < nf; ++i)
      if (!(match[i] >= 0 ? match[i] < r.lesion_count
                          : match[i] == PALP_FINDING_FALSE || match[i] == PALP_FINDING_WITHDRAWN ||
                                match[i] == PALP_FINDING_DUPLICATE))
        FAIL("mark %d matched %d", i, match[i]);
    for (int v = 0; v < mesh.vertex_count; ++v)
      if (cov[v] >> PALP_BAND_COUNT) FAIL("vertex %d bands 0x%x", v, cov[v]);

    const double R = 0.04;
    const int nt = palp_assess_touches(s, n, R, rf, NULL, 0);
    if (nt != e->presses) FAIL("touches %d, presses %d", nt, e->presses);
    palp_touch *tt = calloc((size_t)nt + 1, sizeof *tt);
    if (!tt) abort();
    if (palp_assess_touches(s, n, R, rf, tt, nt) != nt) FAIL("touches counted twice differ");
    double path = 0.0;
    int in_contact = 0, split = 0;
    for (int i = 0; i < n; ++i) in_contact += s[i].contact != 0;
    for (int i = 0; i < nt; ++i) {
      if (!(tt[i].t_off >= tt[i].t_on) || !(tt[i].path_length >= 0.0) || tt[i].contact_samples < 1)
        FAIL("touch %d: %g..%g s, path %g m, %d samples", i, tt[i].t_on, tt[i].t_off, tt[i].path_length,
             tt[i].contact_samples);
      path += tt[i].path_length;
      split += tt[i].contact_samples;
    }
    if (!(fabs(path - e->path_length) <= 1e-9 * e->path_length + 1e-12))
      FAIL("touches' paths %.17g m against the path %.17g m", path, e->path_length);
    if (split != in_contact) FAIL("touches hold %d contact samples of %d", split, in_contact);
    free(tt);
  }
  free(match);
  free(cov);
  free(s);
  free(f);
  free(tri);
  return 0;
}
