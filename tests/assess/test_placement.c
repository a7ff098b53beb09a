/*
 * test_placement.c - lesions drawn for each session (src/placement.c, the exercise's "placement";
 * docs/assessment.md, "Lesions drawn for each session"). A random exercise of three 15 mm lesions
 * 10 mm deep in the band 20-55 deg from the pole of a 40 mm dome, at least 10 mm apart along the
 * skin. Every property is checked with the test's own geometry, not the module's:
 *  - each draw keeps the file's sizes, depths and stiffnesses, places every lesion in the band,
 *    inside the dome above its base and >= 10 mm from the others' edges along the skin;
 *  - the same seed gives the same places, bit for bit; 200 seeds give 200 different first places;
 *  - uniform over the band's skin: over 4000 one-lesion draws the share below the polar angle that
 *    halves the band's area is 0.5 +- 0.03 (4 sigma of a binomial at n = 4000: 0.032), and each
 *    azimuth quadrant holds 0.25 +- 0.03;
 *  - a file that asks too much (three 15 mm lesions 60 mm apart in a 5 deg band) is refused at
 *    load, with a message naming the placement;
 *  - the file's text with a draw written in parses back to the same places (within 1e-12 rad) as
 *    kind "drawn" with its seed; a random file with places, or a seed, is refused;
 *  - "count": how many of the file's lesions a session hides, uniform in [min, max], which ones
 *    uniform and in the file's order; a draw of fewer, or of none, reads back from its logged text;
 *  - a pool (session 83 review): 8 lesions listed that cannot be placed all at once, "count" [1, 1]:
 *    every session's draw places one, and the exercise's load (palp_exercise_scene) accepts it, its
 *    scene holding one lesion, the first listed, in the band; a pool of which some set a session may
 *    hide cannot be placed is refused, the message naming that set; without a count the scene holds
 *    the seed-0 draw of all the lesions, as before.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "palp_assess.h"

/* a check the rest depends on: stop here when it fails */
#define REQUIRE(cond, ...)   \
  do {                       \
    CHECK(cond, __VA_ARGS__); \
    if (!(cond)) return 1;   \
  } while (0)

#define PI 3.14159265358979323846
#define R 0.040

static const char *random3 =
    "{\"name\": \"r\", \"title\": \"R\", \"phantom\": \"p.json\", \"instructions\": \"go\", \"time_limit_s\": 60,"
    " \"placement\": {\"kind\": \"random\", \"polar_deg\": [20, 55], \"min_gap_mm\": 10},"
    " \"lesions\": [{\"depth_mm\": 10, \"diameter_mm\": 15, \"stiffness_ratio\": 5},"
    "               {\"depth_mm\": 10, \"diameter_mm\": 15, \"stiffness_ratio\": 5},"
    "               {\"depth_mm\": 12, \"diameter_mm\": 10, \"stiffness_ratio\": 8}],"
    " \"pressure_bands\": {\"light\": {\"depth_mm\": [1, 4]}, \"medium\": {\"depth_mm\": [4, 9]}, \"deep\": {\"depth_mm\": [9, 18]}},"
    " \"max_force_N\": 15, \"debrief\": \"lesions\", \"rubric\": {\"weights\": {\"sensitivity\": 1},"
    " \"pass\": {\"sensitivity\": 1, \"coverage\": {\"light\": 0.5, \"medium\": 0.5, \"deep\": 0.5}, \"score\": 50}}}";

static char *replaced(const char *text, const char *from, const char *to) {
  const char *at = strstr(text, from);
  if (!at) return NULL;
  const size_t n = strlen(text) - strlen(from) + strlen(to) + 1;
  char *out = malloc(n);
  snprintf(out, n, "%.*s%s%s", (int)(at - text), text, to, at + strlen(from));
  return out;
}

/* the test's own geometry: the unit direction of (polar, azimuth) */
static void dir(double polar, double az, double d[3]) {
  d[0] = sin(polar) * cos(az), d[1] = sin(polar) * sin(az), d[2] = cos(polar);
}

/* The same lesions and placement, field by field (a struct's padding is not compared: memcmp
 * would see whatever the copy left there, and did under AddressSanitizer). */
static int same_draw(const palp_exercise *a, const palp_exercise *b) {
  const palp_exercise_placement *p = &a->placement, *q = &b->placement;
  if (a->lesion_count != b->lesion_count || p->kind != q->kind || p->seed != q->seed || p->polar_min != q->polar_min ||
      p->polar_max != q->polar_max || p->min_gap != q->min_gap || p->count_min != q->count_min ||
      p->count_max != q->count_max)
    return 0;
  for (int i = 0; i < a->lesion_count; i++) {
    const palp_exercise_lesion *x = &a->lesion[i], *y = &b->lesion[i];
    if (x->polar != y->polar || x->azimuth != y->azimuth || x->depth != y->depth || x->diameter != y->diameter ||
        x->stiffness_ratio != y->stiffness_ratio || p->source[i] != q->source[i])
      return 0;
  }
  return 1;
}

static int valid_draw(const palp_exercise *src, const palp_exercise *d, char *why, size_t len) {
  if (d->lesion_count != src->lesion_count) return snprintf(why, len, "count"), 0;
  for (int i = 0; i < d->lesion_count; i++) {
    const palp_exercise_lesion *L = &d->lesion[i], *S = &src->lesion[i];
    if (L->depth != S->depth || L->diameter != S->diameter || L->stiffness_ratio != S->stiffness_ratio)
      return snprintf(why, len, "lesion %d's size, depth or stiffness changed", i), 0;
    const double deg = L->polar * 180 / PI;
    if (!(deg >= 20 - 1e-9 && deg <= 55 + 1e-9)) return snprintf(why, len, "lesion %d at polar %.3f deg", i, deg), 0;
    /* centre (R - depth) n; its lowest point above the base z = 0, its top below the skin */
    if (!((R - L->depth) * cos(L->polar) - L->diameter / 2 > 0) || !(L->depth > L->diameter / 2))
      return snprintf(why, len, "lesion %d not inside the dome above its base", i), 0;
    for (int j = 0; j < i; j++) {
      double a[3], b[3];
      dir(L->polar, L->azimuth, a);
      dir(d->lesion[j].polar, d->lesion[j].azimuth, b);
      const double arc = R * acos(fmin(1.0, a[0] * b[0] + a[1] * b[1] + a[2] * b[2]));
      const double g = arc - (L->diameter + d->lesion[j].diameter) / 2;
      if (g < 0.010 - 1e-12) return snprintf(why, len, "lesions %d and %d %.2f mm apart", j, i, g * 1e3), 0;
    }
  }
  return 1;
}

int main(void) {
  char err[512] = "";
  palp_exercise ex;
  REQUIRE(palp_exercise_parse(random3, "", &ex, err, sizeof err) == 0, "the random exercise parses: %s", err);
  CHECK(ex.placement.kind == PALP_PLACEMENT_RANDOM && fabs(ex.placement.polar_min - 20 * PI / 180) < 1e-15 &&
            fabs(ex.placement.polar_max - 55 * PI / 180) < 1e-15 && fabs(ex.placement.min_gap - 0.010) < 1e-15,
        "  placement random, band 20-55 deg, gap 10 mm");

  /* 1000 draws: every one valid */
  int bad = 0;
  char why[160] = "";
  for (uint32_t seed = 0; seed < 1000; seed++) {
    palp_exercise d;
    if (palp_exercise_draw(&ex, R, seed, &d, err, sizeof err) != 0 || d.placement.kind != PALP_PLACEMENT_DRAWN ||
        d.placement.seed != seed || !valid_draw(&ex, &d, why, sizeof why)) {
      if (!bad) printf("seed %u: %s %s\n", seed, err, why);
      bad++;
    }
  }
  CHECK(bad == 0, "1000 draws: each in the band, inside the dome, 10 mm apart, sizes kept (%d bad)", bad);

  /* the same seed, the same places; different seeds, different places */
  palp_exercise d1, d2;
  CHECK(palp_exercise_draw(&ex, R, 12345u, &d1, err, sizeof err) == 0 &&
            palp_exercise_draw(&ex, R, 12345u, &d2, err, sizeof err) == 0 && same_draw(&d1, &d2),
        "seed 12345 twice: the same lesions and placement, bit for bit");
  int same = 0;
  double first[200];
  for (uint32_t k = 0; k < 200; k++) {
    palp_exercise d;
    palp_exercise_draw(&ex, R, 777u + k, &d, err, sizeof err);
    first[k] = d.lesion[0].polar * 1000 + d.lesion[0].azimuth;
    for (uint32_t j = 0; j < k; j++) same += first[j] == first[k];
  }
  CHECK(same == 0, "200 seeds: 200 different first places (%d repeats)", same);

  /* uniform over the band's skin: one lesion, 4000 draws */
  char *one = replaced(random3,
                       ",               {\"depth_mm\": 10, \"diameter_mm\": 15, \"stiffness_ratio\": 5},"
                       "               {\"depth_mm\": 12, \"diameter_mm\": 10, \"stiffness_ratio\": 8}]",
                       "]");
  palp_exercise ex1;
  REQUIRE(one && palp_exercise_parse(one, "", &ex1, err, sizeof err) == 0 && ex1.lesion_count == 1, "one lesion: %s", err);
  /* the band's area splits in half at cos(p) = (cos 20 + cos 55) / 2 */
  const double half = acos((cos(20 * PI / 180) + cos(55 * PI / 180)) / 2);
  int below = 0, quad[4] = {0};
  for (uint32_t seed = 0; seed < 4000; seed++) {
    palp_exercise d;
    palp_exercise_draw(&ex1, R, seed, &d, err, sizeof err);
    below += d.lesion[0].polar < half;
    double az = fmod(d.lesion[0].azimuth, 2 * PI);
    if (az < 0) az += 2 * PI;
    quad[(int)(az / (PI / 2)) & 3]++;
  }
  CHECK(fabs(below / 4000.0 - 0.5) <= 0.03, "uniform over the skin: %.3f below the band's half-area angle %.1f deg (0.5 +- 0.03)",
        below / 4000.0, half * 180 / PI);
  for (int q = 0; q < 4; q++)
    CHECK(fabs(quad[q] / 4000.0 - 0.25) <= 0.03, "  azimuth quadrant %d: %.3f (0.25 +- 0.03)", q, quad[q] / 4000.0);

  /* asking too much: refused when drawn, and so at the exercise's load (palp_exercise_scene) */
  char *tight = replaced(random3, "\"polar_deg\": [20, 55], \"min_gap_mm\": 10", "\"polar_deg\": [30, 35], \"min_gap_mm\": 60");
  palp_exercise ext;
  REQUIRE(tight && palp_exercise_parse(tight, "", &ext, err, sizeof err) == 0, "the tight file parses: %s", err);
  palp_exercise dt;
  const int rc = palp_exercise_draw(&ext, R, 1u, &dt, err, sizeof err);
  printf("tight: %s\n", err);
  CHECK(rc == PALP_EINVAL && strstr(err, "placement: cannot place 3 lesions in the band 30-35 deg"),
        "three lesions 60 mm apart in a 5 deg band: refused (%d: %s)", rc, err);

  /* the text the log keeps: parsed back, the same places, kind drawn with its seed */
  char *logged = palp_exercise_drawn_json(random3, &d1);
  palp_exercise back;
  REQUIRE(logged && palp_exercise_parse(logged, "", &back, err, sizeof err) == 0, "the drawn text parses: %s", err);
  double worst = 0;
  for (int i = 0; i < 3; i++)
    worst = fmax(worst, fmax(fabs(back.lesion[i].polar - d1.lesion[i].polar), fabs(back.lesion[i].azimuth - d1.lesion[i].azimuth)));
  CHECK(back.placement.kind == PALP_PLACEMENT_DRAWN && back.placement.seed == 12345u && worst < 1e-12 &&
            back.lesion_count == 3 && back.lesion[2].stiffness_ratio == 8,
        "  kind drawn, seed 12345, places within %.1e rad (1e-12)", worst);
  palp_exercise again;
  CHECK(palp_exercise_draw(&back, R, 99u, &again, err, sizeof err) == 0 && same_draw(&again, &back),
        "  a drawn exercise is not drawn again (its places stay)");

  /* refused: places in a random file, a seed in a random file, an unknown kind, no band */
  static const struct { const char *from, *to, *field; } refuse[] = {
      {"{\"depth_mm\": 10, \"diameter_mm\": 15", "{\"polar_deg\": 30, \"depth_mm\": 10, \"diameter_mm\": 15", "drawn for each session"},
      {"\"min_gap_mm\": 10}", "\"min_gap_mm\": 10, \"seed\": 4}", "placement.seed"},
      {"\"kind\": \"random\"", "\"kind\": \"shuffled\"", "placement.kind"},
      {"\"polar_deg\": [20, 55], ", "", "placement.polar_deg: missing"},
      {"\"polar_deg\": [20, 55]", "\"polar_deg\": [20, 85]", "placement.polar_deg[1]"},
      {"\"kind\": \"random\", \"polar_deg\": [20, 55], \"min_gap_mm\": 10", "\"kind\": \"fixed\", \"min_gap_mm\": 10",
       "belong to kind random or drawn"}};
  for (size_t k = 0; k < sizeof refuse / sizeof refuse[0]; k++) {
    char *j = replaced(random3, refuse[k].from, refuse[k].to);
    palp_exercise x;
    err[0] = 0;
    const int e = j ? palp_exercise_parse(j, "", &x, err, sizeof err) : 0;
    printf("%-60.60s -> %s\n", refuse[k].to, err);
    CHECK(e == PALP_EPARSE && strstr(err, refuse[k].field), "refused, naming %s: %s", refuse[k].field, err);
    free(j);
  }
  /* How many and which (the file's "count"): [0, 3] of the three, 4000 draws. Each k in 0..3 a
   * quarter of them (+- 0.03, 4 sigma of a binomial at n = 4000: 0.027); each lesion hidden one of the
   * file's, in its order, with the file's size, depth and stiffness, in the band and 10 mm apart;
   * with [1, 1] each of the three hidden a third of the time (+- 0.03). */
  char *counted = replaced(random3, "\"min_gap_mm\": 10}", "\"min_gap_mm\": 10, \"count\": [0, 3]}");
  palp_exercise exc;
  REQUIRE(counted && palp_exercise_parse(counted, "", &exc, err, sizeof err) == 0, "count [0, 3] parses: %s", err);
  CHECK(exc.placement.count_min == 0 && exc.placement.count_max == 3, "  count 0..3 (%d..%d)", exc.placement.count_min,
        exc.placement.count_max);
  CHECK(ex.placement.count_min == 3 && ex.placement.count_max == 3, "without count, all three (%d..%d)",
        ex.placement.count_min, ex.placement.count_max);
  int kcount[4] = {0}, badk = 0;
  for (uint32_t seed = 0; seed < 4000; seed++) {
    palp_exercise d;
    if (palp_exercise_draw(&exc, R, seed, &d, err, sizeof err) != 0 || d.lesion_count < 0 || d.lesion_count > 3) {
      badk++;
      continue;
    }
    kcount[d.lesion_count]++;
    palp_exercise t = ex; /* the templates the draw took, in order, to check the draw against */
    int order = 1;
    for (int i = 0; i < d.lesion_count; i++) {
      const int src = d.placement.source[i];
      order = order && src >= 0 && src < 3 && (i == 0 || src > d.placement.source[i - 1]);
      if (order) t.lesion[i] = ex.lesion[src];
    }
    t.lesion_count = d.lesion_count;
    if (!order || !valid_draw(&t, &d, why, sizeof why)) {
      if (!badk) printf("count seed %u: %s\n", seed, order ? why : "sources out of order");
      badk++;
    }
  }
  CHECK(badk == 0, "4000 draws of [0, 3]: each a subset of the file's lesions in order, placed as above (%d bad)", badk);
  for (int k = 0; k < 4; k++)
    CHECK(fabs(kcount[k] / 4000.0 - 0.25) <= 0.03, "  %d lesions hidden in %.3f of them (0.25 +- 0.03)", k, kcount[k] / 4000.0);
  char *one_of = replaced(random3, "\"min_gap_mm\": 10}", "\"min_gap_mm\": 10, \"count\": [1, 1]}");
  palp_exercise ex11;
  REQUIRE(one_of && palp_exercise_parse(one_of, "", &ex11, err, sizeof err) == 0, "count [1, 1]: %s", err);
  int which[3] = {0};
  for (uint32_t seed = 0; seed < 3000; seed++) {
    palp_exercise d;
    if (palp_exercise_draw(&ex11, R, seed, &d, err, sizeof err) == 0 && d.lesion_count == 1) which[d.placement.source[0]]++;
  }
  for (int i = 0; i < 3; i++)
    CHECK(fabs(which[i] / 3000.0 - 1.0 / 3) <= 0.03, "  count [1, 1]: the file's lesion %d hidden in %.3f (1/3 +- 0.03)", i,
          which[i] / 3000.0);
  /* a draw of fewer, and of none, written for the log and read back */
  for (uint32_t seed = 0, seen = 0; seed < 200 && seen != 3; seed++) {
    palp_exercise d, b;
    palp_exercise_draw(&exc, R, seed, &d, err, sizeof err);
    if (d.lesion_count != 0 && d.lesion_count != 2) continue;
    seen |= d.lesion_count == 0 ? 1u : 2u;
    char *txt = palp_exercise_drawn_json(counted, &d);
    const int prc = txt ? palp_exercise_parse(txt, "", &b, err, sizeof err) : -99;
    int same_ = prc == 0 && b.lesion_count == d.lesion_count && b.placement.kind == PALP_PLACEMENT_DRAWN &&
                b.placement.count_min == 0 && b.placement.count_max == 3;
    for (int i = 0; same_ && i < d.lesion_count; i++)
      same_ = fabs(b.lesion[i].polar - d.lesion[i].polar) < 1e-12 && b.lesion[i].diameter == d.lesion[i].diameter &&
              b.lesion[i].stiffness_ratio == d.lesion[i].stiffness_ratio;
    CHECK(same_, "a draw of %d of 3 (seed %u) read back from its logged text: %d lesions, count [0, 3] (%d %s)",
          d.lesion_count, seed, b.lesion_count, prc, err);
    free(txt);
  }
  static const struct { const char *to, *field; } refuse_count[] = {
      {"\"min_gap_mm\": 10, \"count\": [2, 5]}", "placement.count: at most the 3 lesions"},
      {"\"min_gap_mm\": 10, \"count\": [2, 1]}", "placement.count: expected"},
      {"\"min_gap_mm\": 10, \"count\": [0.5, 1]}", "placement.count: expected"},
      {"\"min_gap_mm\": 10, \"count\": 2}", "placement.count: expected"},
      {"\"min_gap_mm\": 10, \"per\": \"class\"}", "placement.per: unknown \"class\" (session, run)"}};
  for (size_t k = 0; k < sizeof refuse_count / sizeof refuse_count[0]; k++) {
    char *j = replaced(random3, "\"min_gap_mm\": 10}", refuse_count[k].to);
    palp_exercise x;
    err[0] = 0;
    const int e = j ? palp_exercise_parse(j, "", &x, err, sizeof err) : 0;
    CHECK(e == PALP_EPARSE && strstr(err, refuse_count[k].field), "refused, naming %s: %s", refuse_count[k].field, err);
    free(j);
  }
  /* "per": "run" kept through the log's text (the server draws once per run: server_exercise_random) */
  char *per_run = replaced(random3, "\"min_gap_mm\": 10}", "\"min_gap_mm\": 10, \"per\": \"run\"}");
  palp_exercise exr, dr, br;
  REQUIRE(per_run && palp_exercise_parse(per_run, "", &exr, err, sizeof err) == 0 && exr.placement.per_run == 1 &&
              ex.placement.per_run == 0,
          "per run parses (and per session is the default): %s", err);
  char *rtxt = palp_exercise_draw(&exr, R, 5u, &dr, err, sizeof err) == 0 ? palp_exercise_drawn_json(per_run, &dr) : NULL;
  CHECK(rtxt && palp_exercise_parse(rtxt, "", &br, err, sizeof err) == 0 && br.placement.per_run == 1 &&
            br.placement.kind == PALP_PLACEMENT_DRAWN,
        "  and reads back from the drawn text as per run (%s)", err);
  free(rtxt), free(per_run);
  /* A pool (session 83 review): 8 lesions of 15 mm, 10 mm deep, stiffness 2-9, in the band 20-40
   * deg at least 10 mm apart, a session hiding one ("count": [1, 1]), on the shipped 40 mm dome. */
  {
    char pool[4096], ls[1200] = "";
    for (int i = 0, k = 0; i < 8; i++)
      k += snprintf(ls + k, sizeof ls - (size_t)k, "%s{\"depth_mm\": 10, \"diameter_mm\": 15, \"stiffness_ratio\": %d}",
                    i ? ", " : "", 2 + i);
    snprintf(pool, sizeof pool,
             "{\"name\": \"pool\", \"title\": \"P\", \"phantom\": \"dome.json\", \"instructions\": \"go\", "
             "\"time_limit_s\": 60, \"placement\": {\"kind\": \"random\", \"polar_deg\": [20, 40], \"min_gap_mm\": 10, "
             "\"count\": [1, 1]}, \"lesions\": [%s], \"pressure_bands\": {\"light\": {\"depth_mm\": [1, 4]}, "
             "\"medium\": {\"depth_mm\": [4, 9]}, \"deep\": {\"depth_mm\": [9, 18]}}, \"max_force_N\": 15, "
             "\"debrief\": \"lesions\", \"rubric\": {\"weights\": {\"sensitivity\": 1}, \"pass\": {\"sensitivity\": 1, "
             "\"coverage\": {\"light\": 0.5, \"medium\": 0.5, \"deep\": 0.5}, \"score\": 50}}}",
             ls);
    static palp_exercise ep, all8;
    static palp_scene sc;
    REQUIRE(palp_exercise_parse(pool, PALP_CONFIG_DIR "/phantoms", &ep, err, sizeof err) == 0 && ep.lesion_count == 8 &&
                ep.placement.count_min == 1 && ep.placement.count_max == 1,
            "the pool parses: 8 listed, count [1, 1] (%s)", err);
    /* the premise: the 8 do not fit in the band together */
    all8 = ep;
    all8.placement.count_min = all8.placement.count_max = 8;
    palp_exercise d8;
    CHECK(palp_exercise_draw(&all8, R, 0u, &d8, err, sizeof err) == PALP_EINVAL,
          "premise: all 8 at once cannot be placed (%s)", err);
    int placed = 0;
    for (uint32_t seed = 0; seed < 200; seed++) {
      palp_exercise d, t = ep; /* t: the lesion the draw took, to check the draw against */
      if (palp_exercise_draw(&ep, R, seed, &d, err, sizeof err) != 0 || d.lesion_count != 1) continue;
      t.lesion[0] = ep.lesion[d.placement.source[0]];
      t.lesion_count = 1;
      placed += valid_draw(&t, &d, why, sizeof why);
    }
    CHECK(placed == 200, "the pool: 200 sessions' draws each place one lesion, valid (%d)", placed);
    err[0] = 0;
    const int rc_pool = palp_exercise_scene(&ep, &sc, err, sizeof err);
    printf("pool of 8, count [1, 1]: palp_exercise_scene %d %s\n", rc_pool, err);
    const palp_vec3 c = sc.world.lesion[0].center;
    const double r = sqrt(c.x * c.x + c.y * c.y + c.z * c.z), polar = acos(c.z / r) * 180 / PI;
    CHECK(rc_pool == 0 && sc.world.lesion_count == 1 && fabs(r - 0.030) < 1e-12 && polar >= 20 - 1e-9 &&
              polar <= 40 + 1e-9 && fabs(sc.world.lesion[0].radius - 0.0075) < 1e-12 &&
              sc.world.lesion[0].stiffness_ratio == 2,
          "  its load accepts it: one lesion in the scene, the first listed (ratio 2: %g), 10 mm deep (centre %.3f mm "
          "from the dome's), at polar %.1f deg in the band", rc_pool == 0 ? sc.world.lesion[0].stiffness_ratio : 0.0,
          r * 1e3, polar);
  }
  /* A pool of which not every set a session may hide fits: two 6 mm lesions and two 20 mm ones in a
   * ring 30-30.5 deg, 30 mm apart, two hidden a session. Two points of the ring are at most
   * 2 x 30.5 deg = 42.6 mm apart along the skin: the small pair needs 30 + 6 = 36 mm, a small and a
   * large one 30 + 13 = 43 mm. The first set that cannot be placed, lesions 0 and 2, is named. */
  {
    static const char *ring =
        "{\"name\": \"ring\", \"title\": \"R\", \"phantom\": \"dome.json\", \"instructions\": \"go\", \"time_limit_s\": 60,"
        " \"placement\": {\"kind\": \"random\", \"polar_deg\": [30, 30.5], \"min_gap_mm\": 30, \"count\": [2, 2]},"
        " \"lesions\": [{\"depth_mm\": 10, \"diameter_mm\": 6, \"stiffness_ratio\": 5},"
        "               {\"depth_mm\": 10, \"diameter_mm\": 6, \"stiffness_ratio\": 5},"
        "               {\"depth_mm\": 12, \"diameter_mm\": 20, \"stiffness_ratio\": 5},"
        "               {\"depth_mm\": 12, \"diameter_mm\": 20, \"stiffness_ratio\": 5}],"
        " \"pressure_bands\": {\"light\": {\"depth_mm\": [1, 4]}, \"medium\": {\"depth_mm\": [4, 9]}, \"deep\": {\"depth_mm\": [9, 18]}},"
        " \"max_force_N\": 15, \"debrief\": \"lesions\", \"rubric\": {\"weights\": {\"sensitivity\": 1},"
        " \"pass\": {\"sensitivity\": 1, \"coverage\": {\"light\": 0.5, \"medium\": 0.5, \"deep\": 0.5}, \"score\": 50}}}";
    static palp_exercise er;
    static palp_scene sr;
    REQUIRE(palp_exercise_parse(ring, PALP_CONFIG_DIR "/phantoms", &er, err, sizeof err) == 0, "the ring parses: %s", err);
    err[0] = 0;
    const int rc_ring = palp_exercise_scene(&er, &sr, err, sizeof err);
    printf("ring: %s\n", err);
    CHECK(rc_ring == PALP_EINVAL && strstr(err, "placement: cannot place 2 lesions in the band 30-30.5 deg") &&
              strstr(err, "lesions[0, 2] of the 4 listed (a session hides up to 2 of them, any 2)"),
          "  refused at load, naming the set lesions[0, 2] (%d: %s)", rc_ring, err);
  }
  /* Without a count (all of them), the scene holds the seed-0 draw of all the lesions, as before. */
  {
    char *dome3 = replaced(random3, "\"phantom\": \"p.json\"", "\"phantom\": \"dome.json\"");
    static palp_exercise e3;
    static palp_scene s3;
    palp_exercise d0;
    palp_lesion want[PALP_MAX_LESIONS];
    REQUIRE(dome3 && palp_exercise_parse(dome3, PALP_CONFIG_DIR "/phantoms", &e3, err, sizeof err) == 0, "dome3: %s", err);
    const int nw = palp_exercise_draw(&e3, R, 0u, &d0, err, sizeof err) == 0
                       ? palp_exercise_lesions(&d0, R, want, PALP_MAX_LESIONS, err, sizeof err)
                       : -1;
    int same3 = nw == 3 && palp_exercise_scene(&e3, &s3, err, sizeof err) == 0 && s3.world.lesion_count == 3;
    for (int i = 0; same3 && i < 3; i++)
      same3 = want[i].center.x == s3.world.lesion[i].center.x && want[i].center.y == s3.world.lesion[i].center.y &&
              want[i].center.z == s3.world.lesion[i].center.z && want[i].radius == s3.world.lesion[i].radius &&
              want[i].stiffness_ratio == s3.world.lesion[i].stiffness_ratio;
    CHECK(same3, "without a count the scene holds the seed-0 draw of all three, bit for bit (%s)", err);
    free(dome3);
  }
  free(counted), free(one_of);
  free(one), free(tight), free(logged);
  CHECK_DONE();
}
