/*
 * test_svg.c - the SVG plot writer (tools/eval/svg_plot.c): output is well-formed
 * XML (xmllint --noout from libxml2-utils) and holds the expected elements: one
 * polyline per series with one point per finite sample, the hand-derived ticks,
 * escaped text, one circle per Bland-Altman pair and the bias / LoA / band lines.
 *
 * usage: test_svg WORKDIR
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "svg_plot.h"

#include "harness.h"

static const char *dir;

static int count(const char *hay, const char *needle) {
  int n = 0;
  for (const char *p = strstr(hay, needle); p; p = strstr(p + 1, needle)) ++n;
  return n;
}

/* xmllint must accept the file as well-formed XML. A missing xmllint is a failure
 * (libxml2-utils is in scripts/debian-packages.txt), not a skip. */
static void check_well_formed(const char *path) {
  char cmd[1200];
  snprintf(cmd, sizeof cmd, "xmllint --noout '%s'", path);
  int st = system(cmd);
  char what[1300];
  snprintf(what, sizeof what, "xmllint --noout %s exits 0 (well-formed XML)", path);
  check(what, WIFEXITED(st) && WEXITSTATUS(st) == 0);
}

/* Number of "x,y" pairs in the points attribute of the k-th polyline. */
static int polyline_points(const char *svg, int k) {
  const char *p = svg;
  for (int i = 0; i <= k; ++i) {
    p = strstr(p, "<polyline");
    if (!p) return -1;
    p += 9;
  }
  p = strstr(p, "points=\"");
  if (!p) return -1;
  p += 8;
  int n = 0;
  for (; *p && *p != '"'; ++p)
    if (*p == ',') ++n;
  return n;
}

static void test_line_chart(void) {
  /* Series 1: 401 samples over 0..4 s (the paper's 400 frames + t = 0).
   * Series 2: 37 samples, one of them NaN (must be skipped -> 36 points). */
  enum { N1 = 401, N2 = 37 };
  static double t1[N1], y1[N1], t2[N2], y2[N2];
  for (int i = 0; i < N1; ++i) {
    t1[i] = 0.01 * i;
    y1[i] = t1[i] < 2.0 ? -0.8 * (1.0 - exp(-t1[i] / 0.1)) : -0.8 * exp(-(t1[i] - 2.0) / 0.3);
  }
  for (int i = 0; i < N2; ++i) {
    t2[i] = 4.0 * i / (N2 - 1);
    y2[i] = -0.7 * sin(t2[i]);
  }
  y2[10] = NAN;
  palp_svg_series s[2] = {
      {.label = "real-time model", .x = t1, .y = y1, .n = N1},
      {.label = "FEM <reference> & \"cache\"", .x = t2, .y = y2, .n = N2, .dashed = 1},
  };
  palp_svg_line_chart_def def = palp_svg_line_chart_default_def();
  def.title = "Top vertex: I <single> & II";
  def.x_label = "time";
  def.x_unit = "s";
  def.y_label = "displacement \xB5m"; /* Latin-1 micro sign: invalid UTF-8 */
  def.y_unit = "cm";
  def.series = s;
  def.series_count = 2;
  char path[1024], err[256];
  snprintf(path, sizeof path, "%s/line.svg", dir);
  check("line chart written", palp_svg_line_chart_file(path, &def, err, sizeof err) == 0);
  check_well_formed(path);
  char *svg = slurp(path);
  check("SVG 1.1 root", strstr(svg, "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\"") != NULL);
  check("two polylines", count(svg, "<polyline") == 2);
  check("series 1: 401 points for 401 samples", polyline_points(svg, 0) == N1);
  check("series 2: 36 points for 37 samples with one NaN", polyline_points(svg, 1) == N2 - 1);
  check("dashed second series", count(svg, "stroke-dasharray=\"6 4\"") == 2); /* line + legend */
  /* x spans 0..4 s: 8 target intervals -> step 0.5 -> ticks 0.0, 0.5, ..., 4.0 (9). */
  check("9 x ticks", count(svg, "class=\"xtick\"") == 9);
  check("x tick 4.0", strstr(svg, ">4.0</text>") != NULL);
  check("x tick 0.5", strstr(svg, ">0.5</text>") != NULL);
  /* y spans -0.8..0 (series 1 reaches ~-0.8, series 2 -0.7): step 0.2 -> -0.8..0.0 (5+). */
  check("y tick -0.8", strstr(svg, ">-0.8</text>") != NULL);
  check("y tick 0.0 (not -0.0)", strstr(svg, ">0.0</text>") != NULL && !strstr(svg, ">-0.0<"));
  check("axis label with unit", strstr(svg, "time [s]") != NULL);
  check("invalid UTF-8 replaced", strstr(svg, "displacement ?m [cm]") != NULL);
  check("title escaped", strstr(svg, "Top vertex: I &lt;single&gt; &amp; II") != NULL);
  check("legend label escaped", strstr(svg, "FEM &lt;reference&gt; &amp; &quot;cache&quot;") != NULL);
  check("no raw '<single>'", strstr(svg, "<single>") == NULL);
  check("legend entries", count(svg, "class=\"legend\"") == 1);
  free(svg);

  /* Nothing finite to plot: an error, and no file left behind. */
  double nan1[1] = {NAN};
  palp_svg_series bad = {.label = "x", .x = nan1, .y = nan1, .n = 1};
  def.series = &bad;
  def.series_count = 1;
  snprintf(path, sizeof path, "%s/empty.svg", dir);
  check("all-NaN series -> EINVAL", palp_svg_line_chart_file(path, &def, err, sizeof err) == PALP_EINVAL);
  struct stat sb;
  check("no half-written file", stat(path, &sb) != 0);

  /* A failed plot leaves what was at the path untouched (it deleted it, whatever it was:
   * as root, --svg /dev/null would have removed the device node), and no temporary file. */
  snprintf(path, sizeof path, "%s/precious.svg", dir);
  FILE *pf = fopen(path, "w");
  fputs("keep me\n", pf);
  fclose(pf);
  check("failed plot over an existing file -> EINVAL", palp_svg_line_chart_file(path, &def, err, sizeof err) == PALP_EINVAL);
  char *kept = slurp(path);
  check("the existing file is untouched", kept && strcmp(kept, "keep me\n") == 0);
  free(kept);
  remove(path);
  check("failed plot to /dev/null -> EINVAL", palp_svg_line_chart_file("/dev/null", &def, err, sizeof err) == PALP_EINVAL);
  check("/dev/null is still a character device", stat("/dev/null", &sb) == 0 && S_ISCHR(sb.st_mode));
  DIR *dd = opendir(dir);
  int leftovers = 0;
  for (struct dirent *de; dd && (de = readdir(dd));) leftovers += strstr(de->d_name, ".svg.") != NULL;
  if (dd) closedir(dd);
  check("no temporary file left in the directory", leftovers == 0);
  def.series_count = 0;
  check("no series -> EINVAL", palp_svg_line_chart(stdout, &def) == PALP_EINVAL);
}

static void test_bland_altman_plot(void) {
  /* The hand example of test_stats.c: bias 0.1, SD sqrt(0.84/9); the last pair
   * (d = 0.9) is the only one outside bias +- 2 SD. */
  const double b[10] = {1.2, 1.5, 0.8, 2.0, 1.1, 0.9, 1.7, 1.3, 1.6, 1.4};
  const double d[10] = {0.1, -0.1, 0.2, 0.0, -0.2, 0.1, 0.0, -0.1, 0.1, 0.9};
  double a[10];
  for (int i = 0; i < 10; ++i) a[i] = b[i] + d[i];
  palp_svg_bland_altman_def def = palp_svg_bland_altman_default_def();
  def.title = "Distribution I: displacement";
  def.unit = "cm";
  def.label_a = "real-time";
  def.label_b = "FEM";
  def.a = a;
  def.b = b;
  def.n = 10;
  def.bias = 0.1;
  def.sd = sqrt(0.84 / 9.0);
  char path[1024], err[256];
  snprintf(path, sizeof path, "%s/ba.svg", dir);
  check("BA plot written", palp_svg_bland_altman_file(path, &def, err, sizeof err) == 0);
  check_well_formed(path);
  char *svg = slurp(path);
  check("one circle per pair", count(svg, "<circle") == 10);
  check("one point outside 2 SD marked", count(svg, "fill=\"#D55E00\"") == 1);
  check("bias line", count(svg, "<line class=\"bias\"") == 1);
  check("two 1.96 SD lines", count(svg, "<line class=\"loa\"") == 2);
  check("two 2 SD lines", count(svg, "<line class=\"band\"") == 2);
  check("bias label value", strstr(svg, "bias 0.1</text>") != NULL);
  check("axis labels", strstr(svg, "mean of real-time and FEM [cm]") != NULL &&
                           strstr(svg, "real-time - FEM [cm]") != NULL);
  check("summary 90 %", strstr(svg, "n = 10, 90.0 %") != NULL);
  free(svg);
  def.sd = -1.0;
  check("negative SD -> EINVAL", palp_svg_bland_altman(stdout, &def) == PALP_EINVAL);

  /* Thinning: 20000 pairs, d_i = +-0.01 alternating except 3 pairs at 1.0, so
   * bias ~ 1.5e-4 and SD ~ 0.016: exactly those 3 lie outside 2 SD. With
   * max_points 1000 the stride is 20: pairs 0, 20, ..., 19980 (1000) plus the 3
   * outliers (placed at odd indices, so not already drawn) = 1003 circles. */
  enum { NB = 20000 };
  static double ta[NB], tb[NB];
  double sum = 0.0, sq = 0.0;
  for (int i = 0; i < NB; ++i) {
    tb[i] = 1.0 + 1e-4 * i;
    ta[i] = tb[i] + ((i == 101 || i == 5001 || i == 15001) ? 1.0 : (i % 2 ? 0.01 : -0.01));
    sum += ta[i] - tb[i];
  }
  double bias = sum / NB;
  for (int i = 0; i < NB; ++i) sq += (ta[i] - tb[i] - bias) * (ta[i] - tb[i] - bias);
  def.a = ta;
  def.b = tb;
  def.n = NB;
  def.bias = bias;
  def.sd = sqrt(sq / (NB - 1));
  def.max_points = 1000;
  snprintf(path, sizeof path, "%s/ba_thin.svg", dir);
  check("thinned BA plot written", palp_svg_bland_altman_file(path, &def, err, sizeof err) == 0);
  check_well_formed(path);
  svg = slurp(path);
  check("thinned: 1003 circles", count(svg, "<circle") == 1003);
  check("thinned: the 3 outliers marked", count(svg, "fill=\"#D55E00\"") == 3);
  check("thinned: summary says so", strstr(svg, "1003 pairs drawn: every 20-th") != NULL);
  free(svg);
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: %s WORKDIR\n", argv[0]);
    return 2;
  }
  dir = argv[1];
  mkdir(dir, 0755);
  test_line_chart();
  test_bland_altman_plot();
  printf("%d checks, %d failures\n", checks, failures);
  return failures ? 1 : 0;
}
