/*
 * test_exercise.c - exercise files (src/exercise.c, docs/assessment.md): the shipped
 * exercises load and hide their lesions where they say, and bad files are refused with
 * a message naming the field.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <pthread.h>

#include "check.h"
#include "palp_assess.h"

#define PI 3.14159265358979323846

static const char *good =
    "{\"name\": \"t\", \"title\": \"T\", \"phantom\": \"p.json\", \"instructions\": \"go\", \"time_limit_s\": 60,"
    " \"lesions\": [{\"polar_deg\": 90, \"azimuth_deg\": 0, \"depth_mm\": 10, \"diameter_mm\": 4, \"stiffness_ratio\": 3}],"
    " \"pressure_bands\": {\"light\": {\"depth_mm\": [1, 5]}, \"medium\": {\"depth_mm\": [5, 12]},"
    " \"deep\": {\"depth_mm\": [12, 25], \"force_N\": [0, 9]}},"
    " \"max_force_N\": 5, \"rubric\": {\"weights\": {\"sensitivity\": 1},"
    " \"pass\": {\"sensitivity\": 1, \"coverage\": {\"light\": 0.5, \"medium\": 0.5, \"deep\": 0.5}, \"score\": 50}}}";

/* Replaces the first occurrence of `from` in good by `to` and expects a parse error
 * whose message contains `field`. */
static void expect_error(const char *from, const char *to, const char *field) {
  char json[4096];
  const char *at = strstr(good, from);
  CHECK(at != NULL, "test setup: \"%s\" not in the template", from);
  if (!at) return;
  snprintf(json, sizeof json, "%.*s%s%s", (int)(at - good), good, to, at + strlen(from));
  palp_exercise ex;
  char err[256] = "";
  const int e = palp_exercise_parse(json, "", &ex, err, sizeof err);
  printf("%-40s -> %s\n", to, err);
  CHECK(e == PALP_EPARSE, "replacing %s by %s: expected PALP_EPARSE, got %d", from, to, e);
  CHECK(strstr(err, field) != NULL, "message \"%s\" should name %s", err, field);
}

/* One thread of the concurrent parse below: 200 parses of `good`, counting those that fail or
 * differ from the main thread's (no CHECK here: its counter is not for threads). */
typedef struct parse_job {
  const palp_exercise *want;
  int bad;
} parse_job;
static void *parse_many(void *arg) {
  parse_job *j = arg;
  for (int i = 0; i < 200; ++i) {
    palp_exercise ex;
    char err[256];
    if (palp_exercise_parse(good, "/x", &ex, err, sizeof err) != 0 ||
        memcmp(&ex.rubric, &j->want->rubric, sizeof ex.rubric) != 0)
      j->bad++;
  }
  return NULL;
}


/* Writes text to dir/name; returns 0 on success. */
static int write_file(const char *dir, const char *name, const char *text) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "w");
  if (!f) return -1;
  const int ok = fputs(text, f) >= 0;
  return fclose(f) == 0 && ok ? 0 : -1;
}

/* An exercise on `phantom` (an absolute path) with the lesions given (JSON array items). */
static void exercise_text(char *out, size_t n, const char *phantom, const char *lesions) {
  snprintf(out, n,
           "{\"name\": \"t\", \"title\": \"T\", \"phantom\": \"%s\", \"instructions\": \"go\", \"time_limit_s\": 60,"
           " \"lesions\": [%s],"
           " \"pressure_bands\": {\"light\": {\"depth_mm\": [1, 4]}, \"medium\": {\"depth_mm\": [4, 9]},"
           " \"deep\": {\"depth_mm\": [9, 18]}}, \"max_force_N\": 15, \"rubric\": {\"weights\": {\"sensitivity\": 1},"
           " \"pass\": {\"sensitivity\": 1, \"coverage\": {\"light\": 0.5, \"medium\": 0.5, \"deep\": 0.5}, \"score\": 50}}}",
           phantom, lesions);
}

/* Loads exercise text (as a file in dir) and builds its scene: the scene's return code, its
 * message in err. */
static int scene_of(const char *dir, const char *text, char *err, size_t errlen) {
  static palp_scene sc;
  palp_exercise ex;
  err[0] = 0;
  char path[1024];
  snprintf(path, sizeof path, "%s/ex.json", dir);
  if (write_file(dir, "ex.json", text)) return -100;
  const int e = palp_exercise_load(path, &ex, err, errlen);
  if (e) return e;
  return palp_exercise_scene(&ex, &sc, err, errlen);
}

int main(void) {
  char err[512] = "";
  palp_exercise ex;
  /* 1. The template parses; units converted to SI. */
  CHECK(palp_exercise_parse(good, "/x", &ex, err, sizeof err) == 0, "template: %s", err);
  CHECK(strcmp(ex.phantom_path, "/x/p.json") == 0, "phantom resolved against the folder: %s", ex.phantom_path);
  CHECK_NEAR(ex.lesion[0].depth, 0.010, 1e-15, "depth_mm -> m");
  CHECK_NEAR(ex.lesion[0].polar, PI / 2, 1e-15, "polar_deg -> rad");
  CHECK_NEAR(ex.match_margin, 0.010, 1e-15, "default match margin 10 mm");
  CHECK(ex.rubric.strip_order_share == 0.0 && ex.rubric.pass_strip_order == 0.0,
        "a rubric that does not ask for the strips' order gives a strip search full credit in any order");
  /* bands: depth only for light/medium; deep also needs force in [0, 9) N */
  CHECK(palp_exercise_band(&ex, 0.003, 0.1) == PALP_BAND_LIGHT, "3 mm is light");
  CHECK(palp_exercise_band(&ex, 0.005, 0.1) == PALP_BAND_MEDIUM, "5 mm is medium (min inclusive)");
  CHECK(palp_exercise_band(&ex, 0.0005, 0.1) == -1, "0.5 mm is in no band");
  CHECK(palp_exercise_band(&ex, 0.020, 9.5) == -1, "20 mm at 9.5 N: outside deep's force band");
  /* geometry: at polar 90 deg a 4 mm lesion's centre is on the base plane: refused */
  palp_lesion L[PALP_MAX_LESIONS];
  CHECK(palp_exercise_lesions(&ex, 0.04, L, PALP_MAX_LESIONS, err, sizeof err) == PALP_EINVAL,
        "a lesion cut by the base is refused");
  printf("base: %s\n", err);
  CHECK(strstr(err, "lesions[0]") != NULL, "names the lesion");

  /* The debrief: none unless the file asks (an examination's lesions never leave the server). */
  CHECK(ex.debrief == PALP_DEBRIEF_NONE, "no \"debrief\" key: none (%d)", (int)ex.debrief);
  {
    static const char *const words[] = {"none", "count", "lesions"};
    static const palp_debrief_level levels[] = {PALP_DEBRIEF_NONE, PALP_DEBRIEF_COUNT, PALP_DEBRIEF_LESIONS};
    for (int i = 0; i < 3; i++) {
      char json[2048]; /* good is ~600 characters */
      const char *at = strstr(good, "\"max_force_N\"");
      snprintf(json, sizeof json, "%.*s\"debrief\": \"%s\", %s", (int)(at - good), good, words[i], at);
      palp_exercise d;
      CHECK(palp_exercise_parse(json, "/x", &d, err, sizeof err) == 0 && d.debrief == levels[i], "\"debrief\": \"%s\" (%s)",
            words[i], err);
    }
  }
  expect_error("\"max_force_N\": 5", "\"max_force_N\": 5, \"debrief\": \"all\"", "debrief: unknown \"all\"");
  expect_error("\"max_force_N\": 5", "\"max_force_N\": 5, \"debrief\": true", "debrief: expected a string");

  /* 2. Bad files, each naming its field. */
  expect_error("\"title\": \"T\", ", "", "title");
  /* session 81: a title over the catalogue's 63 bytes (64 here) refused; 63 taken whole */
  expect_error("\"title\": \"T\"", "\"title\": \"0123456789012345678901234567890123456789012345678901234567890123\"",
               "title: longer than 63 characters");
  {
    char json[4096], err[256];
    const char *at = strstr(good, "\"title\": \"T\"");
    snprintf(json, sizeof json, "%.*s\"title\": \"%s\"%s", (int)(at - good), good,
             "012345678901234567890123456789012345678901234567890123456789012", at + strlen("\"title\": \"T\""));
    palp_exercise d;
    CHECK(palp_exercise_parse(json, "/x", &d, err, sizeof err) == 0 && strlen(d.title) == 63,
          "a 63-byte title is taken whole (%s)", err);
  }
  expect_error("\"depth_mm\": 10", "\"depth_mm\": 1", "lesions[0].depth_mm");
  expect_error("\"diameter_mm\": 4", "\"diameter_mm\": -4", "lesions[0].diameter_mm");
  expect_error("\"stiffness_ratio\": 3", "\"stiffness_ratio\": \"hard\"", "lesions[0].stiffness_ratio");
  expect_error("\"polar_deg\": 90", "\"polar_deg\": 95", "lesions[0].polar_deg");
  expect_error("\"time_limit_s\": 60", "\"time_limit_s\": 0", "time_limit_s");
  expect_error("\"medium\": {\"depth_mm\": [5, 12]}", "\"medium\": {\"depth_mm\": [4, 12]}",
               "pressure_bands.medium.depth_mm");
  expect_error("\"light\": {\"depth_mm\": [1, 5]}", "\"light\": {}", "pressure_bands.light");
  /* session 90's review: a band against every band below it, not only the one just below: medium by force
   * alone, deep by depth inside light's (taken before, light credited for deep presses) */
  expect_error("\"medium\": {\"depth_mm\": [5, 12]}, \"deep\": {\"depth_mm\": [12, 25]",
               "\"medium\": {\"force_N\": [12, 14]}, \"deep\": {\"depth_mm\": [3, 25]",
               "pressure_bands.deep.depth_mm: must start at or above light's max");
  expect_error("\"max_force_N\": 5", "\"max_force_N\": 5, \"decoys\": [{}]", "decoys");
  expect_error("\"max_force_N\": 5", "\"max_force_N\": 5, \"time_limit\": 3", "time_limit: unknown key");
  expect_error("\"sensitivity\": 1}", "\"sensitivty\": 1}", "rubric.weights.sensitivty");
  expect_error("\"sensitivity\": 1}", "\"sensitivity\": 0}", "rubric.weights");
  expect_error("\"score\": 50", "\"score\": 50, \"pattern\": \"spiral\"", "rubric.pass.pattern");
  expect_error("\"score\": 50", "\"score\": 150", "rubric.pass.score");
  expect_error("\"score\": 50", "\"score\": 50, \"strip_order\": 1.2", "rubric.pass.strip_order");
  expect_error("\"score\": 50", "\"score\": 50, \"strip_order\": \"in order\"", "rubric.pass.strip_order");
  expect_error("\"pass\": {", "\"strip_order_share\": -0.5, \"pass\": {", "rubric.strip_order_share");
  expect_error("\"name\": \"t\"", "\"name\": \"T t\"", "name");
  CHECK(palp_exercise_parse("{", "", &ex, err, sizeof err) == PALP_EPARSE, "not JSON");
  CHECK(palp_exercise_load("/nonexistent/x.json", &ex, err, sizeof err) == PALP_EIO, "missing file");

  /* 3. The shipped exercises: what they promise, and where their lesions end up. */
  const struct {
    const char *file;
    double polar_deg, az_deg, depth_mm, diameter_mm;
  } shipped[] = {{"easy", 30, 120, 12, 20}, {"hard", 35, 200, 10, 10}};
  for (int k = 0; k < 2; ++k) {
    char path[1024];
    snprintf(path, sizeof path, "%s/exercises/%s.json", PALP_CONFIG_DIR, shipped[k].file);
    CHECK(palp_exercise_load(path, &ex, err, sizeof err) == 0, "%s: %s", path, err);
    CHECK(ex.lesion_count == 1, "%s: one lesion", shipped[k].file);
    /* the shipped rubrics ask for the strips' order (docs/assessment.md, "Score") */
    CHECK(ex.rubric.strip_order_share == 0.5 && ex.rubric.pass_strip_order == 0.7,
          "%s: half the pattern's credit on the strips' order, pass at 0.7 (%.2f, %.2f)", shipped[k].file,
          ex.rubric.strip_order_share, ex.rubric.pass_strip_order);
    CHECK_NEAR(ex.lesion[0].diameter, shipped[k].diameter_mm * 1e-3, 1e-12, "diameter");
    palp_scene sc;
    CHECK(palp_exercise_scene(&ex, &sc, err, sizeof err) == 0, "%s scene: %s", shipped[k].file, err);
    CHECK(sc.world.lesion_count == 1, "the scene holds the hidden lesion");
    /* centre = (R - depth) (sin p cos a, sin p sin a, cos p), R = 40 mm, written out here */
    const double p = shipped[k].polar_deg * PI / 180, a = shipped[k].az_deg * PI / 180;
    const double q = 0.040 - shipped[k].depth_mm * 1e-3;
    const palp_vec3 c = sc.world.lesion[0].center;
    printf("%s: lesion centre (%.4f, %.4f, %.4f) m, radius %.4f m\n", shipped[k].file, c.x, c.y, c.z,
           sc.world.lesion[0].radius);
    CHECK_NEAR(c.x, q * sin(p) * cos(a), 1e-12, "centre x");
    CHECK_NEAR(c.y, q * sin(p) * sin(a), 1e-12, "centre y");
    CHECK_NEAR(c.z, q * cos(p), 1e-12, "centre z");
    CHECK_NEAR(sc.world.lesion[0].radius, shipped[k].diameter_mm * 0.5e-3, 1e-12, "radius");
    CHECK_NEAR(sc.world.dt, 0.004, 1e-15, "the phantom steps at 250 Hz");
    int e = 0;
    palp_world *w = palp_scene_create_world(&sc, &e);
    CHECK(w != NULL, "%s: the world accepts the lesion (%s)", shipped[k].file, palp_strerror(e));
    palp_world_destroy(w);
  }
  /* "medium" draws its lesion for each session (since 2026-12-05): the band 20-55 deg, 10 mm
   * gaps; loaded, its scene holds one draw, a 15 mm lesion 12 mm deep in that band. */
  {
    char path[1024];
    snprintf(path, sizeof path, "%s/exercises/medium.json", PALP_CONFIG_DIR);
    CHECK(palp_exercise_load(path, &ex, err, sizeof err) == 0, "%s: %s", path, err);
    CHECK(ex.lesion_count == 1 && ex.placement.kind == PALP_PLACEMENT_RANDOM &&
              fabs(ex.placement.polar_min - 20 * PI / 180) < 1e-15 && fabs(ex.placement.polar_max - 55 * PI / 180) < 1e-15,
          "medium: one lesion drawn for each session in the band 20-55 deg");
    palp_scene sc;
    CHECK(palp_exercise_scene(&ex, &sc, err, sizeof err) == 0 && sc.world.lesion_count == 1, "medium scene: %s", err);
    const palp_vec3 c = sc.world.lesion[0].center;
    const double r = sqrt(c.x * c.x + c.y * c.y + c.z * c.z), polar = acos(c.z / r) * 180 / PI;
    printf("medium: one draw at polar %.1f deg, centre %.1f mm from the dome's centre\n", polar, r * 1e3);
    CHECK(fabs(r - 0.028) < 1e-12 && polar >= 20 - 1e-9 && polar <= 55 + 1e-9 &&
              fabs(sc.world.lesion[0].radius - 0.0075) < 1e-12,
          "  its centre 12 mm under the skin (R - depth = 28 mm: %.6f), at polar %.1f in the band, radius 7.5 mm", r * 1e3,
          polar);
  }
  /* Exercises parsed on several threads at once (a server loads them while another reloads):
   * the same result on each. parse_rubric filled a static key table on every call, a data race
   * (review, 2026-12-06) that only ThreadSanitizer sees: scripts/sanitize.sh thread runs this test. */
  {
    palp_exercise want;
    CHECK(palp_exercise_parse(good, "/x", &want, err, sizeof err) == 0, "template: %s", err);
    parse_job jobs[4];
    pthread_t th[4];
    int started = 0;
    for (int i = 0; i < 4; ++i) {
      jobs[i] = (parse_job){&want, 0};
      started += pthread_create(&th[i], NULL, parse_many, &jobs[i]) == 0;
    }
    CHECK(started == 4, "4 threads started (%d)", started);
    int bad = 0;
    for (int i = 0; i < started; ++i) pthread_join(th[i], NULL), bad += jobs[i].bad;
    CHECK(bad == 0, "800 parses on 4 threads: %d failed or differed from one parse alone", bad);
  }

  /* 4. What an exercise is graded on is what the phantom holds (session 81 review). */
  {
    char dir[] = "/tmp/palp_test_exercise_XXXXXX";
    CHECK(mkdtemp(dir) != NULL, "temporary directory");
    char text[4096], phantom[1200], dome[1200];
    snprintf(dome, sizeof dome, "%s/phantoms/dome.json", PALP_CONFIG_DIR);
    /* (a) a phantom with a lesion of its own: felt but never graded, so refused, naming its file */
    char scene[2048];
    snprintf(scene, sizeof scene,
             "{\"name\": \"own\", \"mesh\": {\"radius_m\": 0.04, \"vertex_count\": 338},"
             " \"parameters\": \"%s/params/breast_tissue.json\","
             " \"time\": {\"dt_s\": 0.004, \"frames\": 1, \"frame_period_s\": 0.004},"
             " \"effects\": [\"membrane_elasticity\", \"gel_pressure\", \"gel_support\", \"force_feedback\"],"
             " \"lesions\": [{\"center_m\": [0.0, 0.0, 0.03], \"radius_m\": 0.005, \"stiffness_ratio\": 5}],"
             " \"contacts\": []}",
             PALP_CONFIG_DIR);
    CHECK(write_file(dir, "own.json", scene) == 0, "phantom written");
    snprintf(phantom, sizeof phantom, "%s/own.json", dir);
    const char *one = "{\"polar_deg\": 30, \"azimuth_deg\": 0, \"depth_mm\": 10, \"diameter_mm\": 10, \"stiffness_ratio\": 5}";
    exercise_text(text, sizeof text, phantom, one);
    int e = scene_of(dir, text, err, sizeof err);
    printf("phantom with a lesion of its own -> %d: %s\n", e, err);
    CHECK(e == PALP_EINVAL && strstr(err, phantom) && strstr(err, "put the lesions in the exercise"),
          "  refused, naming %s and saying where the lesions go", phantom);
    /* the same exercise on the shipped dome (no lesions of its own) is accepted */
    exercise_text(text, sizeof text, dome, one);
    e = scene_of(dir, text, err, sizeof err);
    CHECK(e == 0, "  the same exercise on dome.json: %d %s", e, err);
    /* (b) fixed lesions: one listed twice is one lump: refused. On the 40 mm dome two 10 mm lesions
     * at polar 30 deg, azimuths 0 and a, are an arc R acos(cos^2 30 + sin^2 30 cos a) apart along
     * the skin, their discs overlapping when that is under 10 mm. a = 28 deg: cos = 0.75 + 0.25 x
     * 0.88295 = 0.97074, acos 0.24252 rad, arc 9.70 mm: overlap 0.30 mm, refused. a = 40 deg:
     * cos = 0.75 + 0.25 x 0.76604 = 0.94151, acos 0.34338 rad, arc 13.74 mm: a 3.7 mm gap, accepted. */
    char two[512];
    snprintf(two, sizeof two, "%s, %s", one, one);
    exercise_text(text, sizeof text, dome, two);
    e = scene_of(dir, text, err, sizeof err);
    printf("one lesion listed twice -> %d: %s\n", e, err);
    CHECK(e == PALP_EINVAL && strstr(err, "lesions[0] and lesions[1]") && strstr(err, "overlap by 10.0 mm"),
          "  refused: the two discs overlap by their whole 10 mm");
    snprintf(two, sizeof two, "%s, {\"polar_deg\": 30, \"azimuth_deg\": 28, \"depth_mm\": 10, \"diameter_mm\": 10, "
             "\"stiffness_ratio\": 5}", one);
    exercise_text(text, sizeof text, dome, two);
    e = scene_of(dir, text, err, sizeof err);
    printf("discs 9.70 mm apart along the skin -> %d: %s\n", e, err);
    CHECK(e == PALP_EINVAL && strstr(err, "overlap by 0.3 mm") && strstr(err, "9.7 mm apart"),
          "  refused: overlap 0.3 mm, centres 9.7 mm apart");
    snprintf(two, sizeof two, "%s, {\"polar_deg\": 30, \"azimuth_deg\": 40, \"depth_mm\": 10, \"diameter_mm\": 10, "
             "\"stiffness_ratio\": 5}", one);
    exercise_text(text, sizeof text, dome, two);
    e = scene_of(dir, text, err, sizeof err);
    CHECK(e == 0, "  discs 3.7 mm apart accepted: %d %s", e, err);
    char path[1200];
    snprintf(path, sizeof path, "%s/ex.json", dir), unlink(path);
    snprintf(path, sizeof path, "%s/own.json", dir), unlink(path);
    rmdir(dir);
    /* (c) every shipped exercise (config/exercises, which config/server-exercises.json lists) and the
     * tests' own still load and build their scenes */
    const char *files[] = {"exercises/easy.json", "exercises/medium.json", "exercises/hard.json",
                           "exercises/teaching.json"};
    for (int k = 0; k < 4; ++k) {
      static palp_scene sc;
      snprintf(path, sizeof path, "%s/%s", PALP_CONFIG_DIR, files[k]);
      CHECK(palp_exercise_load(path, &ex, err, sizeof err) == 0 && palp_exercise_scene(&ex, &sc, err, sizeof err) == 0,
            "%s loads: %s", files[k], err);
    }
    const char *tfiles[] = {"exercise_expert.json", "../server/exercise_short.json", "../server/exercise_wire.json",
                            "../server/exercise_random.json"};
    for (int k = 0; k < 4; ++k) {
      static palp_scene sc;
      snprintf(path, sizeof path, "%s/%s", PALP_TEST_DIR, tfiles[k]);
      CHECK(palp_exercise_load(path, &ex, err, sizeof err) == 0 && palp_exercise_scene(&ex, &sc, err, sizeof err) == 0,
            "%s loads: %s", tfiles[k], err);
    }
  }
  CHECK_DONE();
}
