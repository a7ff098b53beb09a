/*
 * test_place.c - a place on the phantom in the words every tool prints (src/place.c, docs/naming.md,
 * "position on the phantom"): the clock seen from above, the arc from the pole, and "the pole" where
 * a clock is noise. Expected values are worked by hand on the 40 mm dome:
 *  - the clock: +x is 3 o'clock, -y 6, -x 9, +y 12 (never 0); polar 30 deg at azimuth 40 deg (from
 *    +x towards +y) is 90 - 40 = 50 deg clockwise from +y = 1.667 h, and its arc 40 mm x pi/6 =
 *    20.944 mm; tolerance 1e-9 (rounding only);
 *  - "at the pole" below 1 mm of arc: polar 0, and polar 0.9 / 40 rad (0.9 mm) are; 1.1 / 40 rad
 *    (1.1 mm) is not, whatever the azimuth; the apex dented 5 mm, (0, 0, 35) mm, still is;
 *  - an exercise file's lesion at polar 0 has its surface point at the pole (the debrief then says "at
 *    the pole"), one at polar 30 deg does not;
 *  - (session 83) the phrase every tool prints, palp_place_words: "at the pole" or "at H.H o'clock, N mm
 *    from the pole".
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "palp_assess.h"
#include "palp_place.h"

#define PI 3.14159265358979323846
#define R 0.040

static palp_vec3 on_dome(double polar, double az) {
  return (palp_vec3){R * sin(polar) * cos(az), R * sin(polar) * sin(az), R * cos(polar)};
}

int main(void) {
  CHECK_NEAR(palp_place_clock_hours((palp_vec3){0.01, 0, 0.03}), 3.0, 1e-9, "+x: 3 o'clock");
  CHECK_NEAR(palp_place_clock_hours((palp_vec3){0, -0.01, 0.03}), 6.0, 1e-9, "-y: 6 o'clock");
  CHECK_NEAR(palp_place_clock_hours((palp_vec3){-0.01, 0, 0.03}), 9.0, 1e-9, "-x: 9 o'clock");
  CHECK_NEAR(palp_place_clock_hours((palp_vec3){0, 0.01, 0.03}), 12.0, 1e-9, "+y: 12 o'clock, not 0");
  const palp_vec3 p = on_dome(PI / 6, 40 * PI / 180);
  CHECK_NEAR(palp_place_clock_hours(p), 50.0 / 30.0, 1e-9, "polar 30 deg, azimuth 40 deg");
  CHECK_NEAR(palp_place_arc(p), R * PI / 6, 1e-12, "its arc from the pole [m]");
  CHECK(!palp_place_at_pole(p), "polar 30 deg is not at the pole");

  CHECK(palp_place_at_pole((palp_vec3){0, 0, R}), "the apex is at the pole");
  CHECK(palp_place_at_pole((palp_vec3){0, 0, 0.035}), "the apex dented 5 mm is at the pole");
  for (int k = 0; k < 12; k++) {
    const double az = k * PI / 6;
    CHECK(palp_place_at_pole(on_dome(0.9e-3 / R, az)), "0.9 mm of arc at azimuth %d deg is at the pole", k * 30);
    CHECK(!palp_place_at_pole(on_dome(1.1e-3 / R, az)), "1.1 mm of arc at azimuth %d deg is not", k * 30);
  }

  /* an exercise's lesions: one at polar 0 (its azimuth meaningless), one at polar 30 */
  static const char *file =
      "{\"name\": \"pole\", \"title\": \"P\", \"phantom\": \"p.json\", \"instructions\": \"go\", \"time_limit_s\": 60,"
      " \"lesions\": [{\"polar_deg\": 0, \"azimuth_deg\": 75, \"depth_mm\": 10, \"diameter_mm\": 15, \"stiffness_ratio\": 5},"
      "               {\"polar_deg\": 30, \"azimuth_deg\": 40, \"depth_mm\": 10, \"diameter_mm\": 15, \"stiffness_ratio\": 5}],"
      " \"pressure_bands\": {\"light\": {\"depth_mm\": [1, 4]}, \"medium\": {\"depth_mm\": [4, 9]}, \"deep\": {\"depth_mm\": [9, 18]}},"
      " \"max_force_N\": 15, \"debrief\": \"lesions\", \"rubric\": {\"weights\": {\"sensitivity\": 1},"
      " \"pass\": {\"sensitivity\": 1, \"coverage\": {\"light\": 0.5, \"medium\": 0.5, \"deep\": 0.5}, \"score\": 50}}}";
  palp_exercise ex;
  char err[256];
  const int e = palp_exercise_parse(file, ".", &ex, err, sizeof err);
  CHECK(e == 0, "the exercise parses: %s", err);
  if (e == 0) {
    const palp_vec3 a = palp_exercise_lesion_surface(&ex.lesion[0], R), b = palp_exercise_lesion_surface(&ex.lesion[1], R);
    CHECK(palp_place_at_pole(a), "the lesion at polar 0 is at the pole (arc %.3g mm)", palp_place_arc(a) * 1e3);
    CHECK(!palp_place_at_pole(b), "the lesion at polar 30 deg is not");
    CHECK_NEAR(palp_place_clock_hours(b), 50.0 / 30.0, 1e-9, "the lesion at polar 30 deg, azimuth 40 deg: 1.667 h");
    CHECK_NEAR(palp_place_clock_shown(b), 1.7, 1e-12, "  shown 1.7 h");
  }

  /* 12 o'clock as every tool prints it (session 81 review): a lesion at azimuth 90 deg (+y) is 12
   * o'clock, one at 88.6 deg is 1.4 deg = 0.047 h clockwise of it, which rounds to 0.0 h at one
   * decimal: both read 12.0. The raw hours at 90 deg were 6e-17 (cos 90 deg in floating point), not
   * mapped to 12, and "%.1f" printed "0.0". Likewise 91.4 deg is 11.953 h: 12.0; 87 deg is 0.1 h;
   * 180 deg (-x) 9.0; azimuth 0 (+x) 3.0. */
  static const struct {
    double az_deg, shown;
  } twelve[] = {{90, 12.0}, {88.6, 12.0}, {91.4, 12.0}, {87, 0.1}, {180, 9.0}, {0, 3.0}};
  for (size_t k = 0; k < sizeof twelve / sizeof *twelve; k++) {
    const palp_exercise_lesion l = {.polar = 30 * PI / 180, .azimuth = twelve[k].az_deg * PI / 180, .depth = 0.01,
                                    .diameter = 0.015, .stiffness_ratio = 5};
    const palp_vec3 s = palp_exercise_lesion_surface(&l, R);
    char text[16];
    snprintf(text, sizeof text, "%.1f", palp_place_clock_shown(s));
    char want[16];
    snprintf(want, sizeof want, "%.1f", twelve[k].shown);
    printf("azimuth %5.1f deg: raw %.3g h, shown %s o'clock\n", twelve[k].az_deg, palp_place_clock_hours(s), text);
    CHECK(strcmp(text, want) == 0, "azimuth %.1f deg reads %s o'clock (want %s)", twelve[k].az_deg, text, want);
    CHECK(palp_place_clock_shown(s) > 0.05 && palp_place_clock_shown(s) <= 12.0, "  in (0, 12]");
  }

  /* The one phrase for a place (palp_place_words, session 83): worked by hand as above. Polar 30 deg,
   * azimuth 40 deg: 1.667 h shown 1.7, arc 20.944 mm shown 21; the pole's apex, and 0.9 mm of arc, "at
   * the pole"; 12 o'clock at azimuth 90 deg, arc 20.944 mm; the rim of the 40 mm dome at +x (polar 90
   * deg): 3 o'clock, 40 x pi/2 = 62.83 mm shown 63. A buffer too short is cut, never overrun. */
  static const struct {
    double polar_deg, az_deg;
    const char *want;
  } words[] = {{30, 40, "at 1.7 o'clock, 21 mm from the pole"},
               {0, 0, "at the pole"},
               {0.9e-3 / R * 180 / PI, 200, "at the pole"},
               {30, 90, "at 12.0 o'clock, 21 mm from the pole"},
               {90, 0, "at 3.0 o'clock, 63 mm from the pole"}};
  for (size_t k = 0; k < sizeof words / sizeof *words; k++) {
    char text[64];
    const char *got = palp_place_words(on_dome(words[k].polar_deg * PI / 180, words[k].az_deg * PI / 180), text, sizeof text);
    CHECK(got == text && strcmp(text, words[k].want) == 0, "polar %.3g deg, azimuth %g deg: \"%s\" (want \"%s\")",
          words[k].polar_deg, words[k].az_deg, text, words[k].want);
  }
  char small[8];
  memset(small, 'x', sizeof small);
  palp_place_words(p, small, 6);
  CHECK(strcmp(small, "at 1.") == 0 && small[6] == 'x', "a 6-byte buffer gets \"at 1.\" and nothing past it (%.5s)", small);
  CHECK_DONE();
}
