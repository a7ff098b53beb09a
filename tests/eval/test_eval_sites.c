/*
 * test_eval_sites.c - the pieces of evaluate --sites that need no model run:
 * the random contact sites (uniform over the dome's area) and the recovery time
 * read from a record.
 *
 *   draw      20,000 sites over polar 0-60 deg: the share below 30 deg must be the
 *             area ratio (1 - cos 30)/(1 - cos 60) = 0.26795 within 0.012 (binomial
 *             SE 0.0031, ~4 SE), the mean azimuth 180 deg within 4 deg (SE 0.73 deg),
 *             every site inside the range; the same seed gives the same sites, another
 *             seed other sites; a 20-40 deg band stays inside it; bad ranges refused.
 *   recovery  a hand-made record: the peak 1.0 held to t_off = 0.05 s, then 0.5, 0.2,
 *             0.04 at 0.06, 0.07, 0.08 s: the 5% level (0.05) is crossed between 0.07
 *             and 0.08 s at 0.07 + 0.01 (0.2 - 0.05)/(0.2 - 0.04) = 0.079375 s, i.e.
 *             0.029375 s after release (1e-12); a record that never falls that far is
 *             reported as not reached.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../tmpdir.h"
#include "eval.h"
#include "vec3.h"

static int checks, failures;
#define CHECK(c, ...)                                                                                                  \
  do {                                                                                                                 \
    ++checks;                                                                                                          \
    if (!(c)) {                                                                                                        \
      ++failures;                                                                                                      \
      fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);                                                             \
      fprintf(stderr, __VA_ARGS__);                                                                                    \
      fputc('\n', stderr);                                                                                             \
    }                                                                                                                  \
  } while (0)

static void test_draw(void) {
  enum { N = 20000 };
  palp_eval_site *s = malloc(sizeof *s * N), *t = malloc(sizeof *t * N);
  CHECK(palp_eval_sites_draw(1, N, 0.0, 60.0, s) == PALP_OK, "draw");
  int below = 0, inside = 1;
  double az = 0;
  for (int i = 0; i < N; ++i) {
    below += s[i].polar_deg < 30.0;
    az += s[i].azimuth_deg;
    inside &= s[i].polar_deg >= 0.0 && s[i].polar_deg <= 60.0 && s[i].azimuth_deg >= 0.0 && s[i].azimuth_deg < 360.0;
  }
  const double want = (1.0 - cos(PALP_PI / 6.0)) / (1.0 - cos(PALP_PI / 3.0));
  CHECK(fabs((double)below / N - want) < 0.012, "share below 30 deg %.4f vs area ratio %.4f", (double)below / N, want);
  CHECK(fabs(az / N - 180.0) < 4.0, "mean azimuth %.2f vs 180", az / N);
  CHECK(inside, "every site inside polar 0-60, azimuth 0-360");
  CHECK(palp_eval_sites_draw(1, N, 0.0, 60.0, t) == PALP_OK && !memcmp(s, t, sizeof *s * N), "same seed, same sites");
  CHECK(palp_eval_sites_draw(2, 4, 0.0, 60.0, t) == PALP_OK && memcmp(s, t, sizeof *s * 4), "another seed");
  CHECK(palp_eval_sites_draw(3, 1000, 20.0, 40.0, t) == PALP_OK, "band");
  int band = 1;
  for (int i = 0; i < 1000; ++i) band &= t[i].polar_deg >= 20.0 && t[i].polar_deg <= 40.0;
  CHECK(band, "20-40 deg band respected");
  CHECK(palp_eval_sites_draw(1, 4, 40.0, 20.0, t) == PALP_EINVAL, "min > max");
  CHECK(palp_eval_sites_draw(1, 4, 0.0, 95.0, t) == PALP_EINVAL, "max > 90");
  CHECK(palp_eval_sites_draw(1, 0, 0.0, 60.0, t) == PALP_EINVAL, "count 0");
  free(s), free(t);
}

static void test_recovery(void) {
  const double u[10] = {1.0, 1.0, 1.0, 1.0, 1.0, 0.5, 0.2, 0.04, 0.01, 0.0};
  double time[10];
  palp_vec3 disp[10];
  for (int f = 0; f < 10; ++f) time[f] = 0.01 * (f + 1), disp[f] = (palp_vec3){0.0, 0.0, -u[f]};
  palp_eval_record r;
  memset(&r, 0, sizeof r);
  r.frames = 10, r.vertex_count = 1, r.time = time, r.disp = disp;
  double t = 0;
  int reached = 0;
  CHECK(palp_eval_record_recovery(&r, 0, 0.05, &t, &reached) == PALP_OK, "recovery");
  CHECK(reached && fabs(t - 0.029375) < 1e-12, "recovery %.15g s vs 0.029375 s", t);
  for (int f = 5; f < 10; ++f) disp[f].z = -0.5;
  CHECK(palp_eval_record_recovery(&r, 0, 0.05, &t, &reached) == PALP_OK && !reached && isnan(t), "never recovered");
  CHECK(palp_eval_record_recovery(&r, 1, 0.05, &t, &reached) == PALP_EINVAL, "vertex out of range");
}

/* palp-fem finger's CSV as palp-eval --finger-from reads it (session 81's review): a good file's rows of
 * one site, by hand; "inf" (sscanf takes it: an infinite force passed the calibration's force > 0) and
 * a second row at one depth (counted twice toward "every fitted depth", the caller then said falsely
 * that a depth had no row) refused, each naming the row. */
static void test_finger_csv(void) {
  char path[512];
  palp_test_tmp(path, sizeof path, "palp_finger_csv_XXXXXX");
  const int fd = mkstemp(path);
  CHECK(fd >= 0, "mkstemp");
  if (fd < 0) return;
  close(fd);
  static const char *const body[3] = {
      "site,depth_m,fem_N,rt_N,rt_depth_m,ratio,gap_m\npole,0.0005,0.25,0.2,0.0005,0.8,0\nside,0.0005,9,9,0.0005,1,0\n"
      "pole,0.001,0.5,0.4,0.001,0.8,0\n",
      "site,depth_m,fem_N,rt_N,rt_depth_m,ratio,gap_m\npole,0.0005,inf,0.2,0.0005,0.8,0\n",
      "site,depth_m,fem_N,rt_N,rt_depth_m,ratio,gap_m\npole,0.001,0.5,0.4,0.001,0.8,0\npole,0.001,0.6,0.4,0.001,0.8,0\n"};
  static const char *const want[3] = {NULL, "row 1 (site pole): a number is not finite",
                                      "row 2: site pole at depth 0.001 m given twice"};
  for (int i = 0; i < 3; i++) {
    FILE *f = fopen(path, "w");
    fputs(body[i], f);
    fclose(f);
    double d[8], fo[8];
    char err[256] = "";
    const int n = palp_eval_finger_csv_read(path, "pole", 8, d, fo, NULL, err, sizeof err);
    if (!want[i])
      CHECK(n == 2 && d[0] == 0.0005 && fo[0] == 0.25 && d[1] == 0.001 && fo[1] == 0.5, "the pole's two rows: %d (%s)",
            n, err);
    else CHECK(n < 0 && strstr(err, want[i]), "file %d refused, \"%s\": %d, %s", i, want[i], n, err);
  }
  remove(path);
}

int main(void) {
  test_draw();
  test_recovery();
  test_finger_csv();
  printf("test_eval_sites: %d checks, %d failures\n", checks, failures);
  return failures ? 1 : 0;
}
