/* SVG drawings of an assessment. Plan view (x right, y up: 12 o'clock = +y, as in show and the
 * report's top view); pure vector, no script, so the report stays one self-contained file. */
#include <math.h>
#include <string.h>

#include "assess_svg.h"
#include "review_util.h"

const char *const review_band_colour[3] = {"#56b4e9", "#e69f00", "#009e73"}; /* sky blue, orange, green */

typedef struct plan {
  double R, scale, c;
} plan;
static plan plan_of(const review_assessment *a, int size) {
  const double R = a->dome_radius_m > 0 ? a->dome_radius_m : 0.04;
  return (plan){R, (size / 2.0 - 4.0) / R, size / 2.0};
}
static double px(const plan *p, double x) { return p->c + x * p->scale; }
static double py(const plan *p, double y) { return p->c - y * p->scale; }

void review_svg_coverage(FILE *f, const review_assessment *a, int band, int size, const char *id) {
  const plan p = plan_of(a, size);
  fprintf(f, "<svg id=\"%s\" class=\"coverage\" data-band=\"%s\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" "
          "xmlns=\"http://www.w3.org/2000/svg\">\n", id, palp_band_name(band), size, size, size, size);
  const palp_mesh *m = &a->mesh;
  const uint8_t bit = (uint8_t)(1u << band);
  for (int t = 0; t < m->dome_triangle_count; t++) {
    const int *v = m->tri[t];
    int n = 0;
    for (int k = 0; k < 3; k++) n += a->coverage && (a->coverage[v[k]] & bit) ? 1 : 0;
    /* stroke in the fill colour hides the hairline seams of antialiasing */
    const char *col = n >= 2 ? review_band_colour[band] : REVIEW_UNCOVERED_COLOUR;
    fprintf(f, "<polygon points=\"%.1f,%.1f %.1f,%.1f %.1f,%.1f\" fill=\"%s\" stroke=\"%s\" stroke-width=\"0.6\"/>\n",
            px(&p, m->rest[v[0]].x), py(&p, m->rest[v[0]].y), px(&p, m->rest[v[1]].x), py(&p, m->rest[v[1]].y),
            px(&p, m->rest[v[2]].x), py(&p, m->rest[v[2]].y), col, col);
  }
  fputs("</svg>\n", f);
}

const char *review_finding_class(int match) {
  if (match >= 0) return "found";
  if (match == PALP_FINDING_WITHDRAWN) return "withdrawn";
  if (match == PALP_FINDING_DUPLICATE) return "duplicate";
  return "false";
}

void review_svg_path(FILE *f, const review_assessment *a, int size, const char *id) {
  const plan p = plan_of(a, size);
  fprintf(f, "<svg id=\"%s\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" xmlns=\"http://www.w3.org/2000/svg\">\n"
          "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"#fafafa\" stroke=\"#999\"/>\n",
          id, size, size, size, size, p.c, p.c, p.R * p.scale);
  /* At most ~3000 points: the path's shape, not every 4 ms sample. */
  const int step = a->path_n > 3000 ? (a->path_n + 2999) / 3000 : 1;
  fputs("<polyline class=\"finger-path\" fill=\"none\" stroke=\"#555\" stroke-width=\"0.7\" points=\"", f);
  for (int i = 0; i < a->path_n; i += step) fprintf(f, "%.1f,%.1f ", px(&p, a->path[i].x), py(&p, a->path[i].y));
  fputs("\"/>\n", f);
  for (int i = 0; i < a->ex.lesion_count; i++) {
    const palp_vec3 c = a->lesion_surface[i];
    fprintf(f, "<circle class=\"lesion\" data-lesion=\"%d\" cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"none\" "
            "stroke=\"#d55e00\" stroke-width=\"2\" stroke-dasharray=\"4 3\"/>\n",
            i + 1, px(&p, c.x), py(&p, c.y), 0.5 * a->ex.lesion[i].diameter * p.scale);
  }
  for (int i = 0; i < a->mark_n; i++) {
    const review_mark *k = &a->marks[i];
    const double x = px(&p, k->f.point.x), y = py(&p, k->f.point.y);
    const char *cl = review_finding_class(k->match);
    /* shape, not only colour: a cross for found, a square for false, a hollow circle when withdrawn */
    if (k->match >= 0)
      fprintf(f, "<path class=\"finding found\" d=\"M%.1f %.1fl10 10m0 -10l-10 10\" stroke=\"#0072b2\" stroke-width=\"3\"/>\n",
              x - 5, y - 5);
    else if (k->match == PALP_FINDING_WITHDRAWN)
      fprintf(f, "<circle class=\"finding withdrawn\" cx=\"%.1f\" cy=\"%.1f\" r=\"5\" fill=\"none\" stroke=\"#777\" "
              "stroke-width=\"2\"/>\n", x, y);
    else
      fprintf(f, "<rect class=\"finding %s\" x=\"%.1f\" y=\"%.1f\" width=\"10\" height=\"10\" fill=\"#cc79a7\"/>\n", cl,
              x - 5, y - 5);
    fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"10\">%d</text>\n", x + 7, y - 6, i + 1);
  }
  fputs("</svg>\n", f);
}

void review_svg_scores(FILE *f, const double *score, int n, int w, int h, const char *id) {
  fprintf(f, "<svg id=\"%s\" class=\"progress\" width=\"%d\" height=\"%d\" xmlns=\"http://www.w3.org/2000/svg\">\n"
          "<rect x=\"0.5\" y=\"0.5\" width=\"%d\" height=\"%d\" fill=\"none\" stroke=\"#ccc\"/>\n", id, w, h, w - 1, h - 1);
  const double x0 = 8, x1 = w - 8, y0 = h - 6, y1 = 6;
  fputs("<polyline fill=\"none\" stroke=\"#0072b2\" stroke-width=\"1.5\" points=\"", f);
  for (int i = 0; i < n; i++) {
    const double x = n > 1 ? x0 + (x1 - x0) * i / (n - 1) : (x0 + x1) / 2;
    fprintf(f, "%.1f,%.1f ", x, y0 + (y1 - y0) * score[i] / 100.0);
  }
  fputs("\"/>\n", f);
  for (int i = 0; i < n; i++) {
    const double x = n > 1 ? x0 + (x1 - x0) * i / (n - 1) : (x0 + x1) / 2;
    fprintf(f, "<circle class=\"point\" cx=\"%.1f\" cy=\"%.1f\" r=\"2.5\" fill=\"#0072b2\"><title>session %d: %.1f</title></circle>\n", x,
            y0 + (y1 - y0) * score[i] / 100.0, i + 1, score[i]);
  }
  fputs("</svg>\n", f);
}
