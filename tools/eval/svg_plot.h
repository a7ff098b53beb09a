/*
 * svg_plot.h - self-contained SVG 1.1 plots for the evaluation: a line chart of
 * time series (top-vertex displacement of both models) and a Bland-Altman plot
 * (mean vs difference with the bias, +-1.96 SD and +-2 SD lines).
 *
 * The output needs no fonts, scripts or external resources; every text is XML-
 * escaped and invalid UTF-8 is replaced, so any CSV header can serve as a label.
 * Functions return 0 or a negative PALP_E* code (palp.h).
 */
#ifndef PALP_SVG_PLOT_H
#define PALP_SVG_PLOT_H

#include <stddef.h>
#include <stdio.h>

#include "palp.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct palp_svg_series {
  const char *label;     /* legend text */
  const double *x, *y;   /* [n] samples, x ascending for a time series */
  size_t n;
  const char *color;     /* CSS colour, NULL picks from a colour-blind-safe palette */
  int dashed;            /* draw dashed */
} palp_svg_series;

typedef struct palp_svg_line_chart_def {
  const char *title;
  const char *x_label, *x_unit; /* axis label and unit, e.g. "time", "s" */
  const char *y_label, *y_unit; /* e.g. "top-vertex displacement", "cm" */
  int width, height;            /* [px], default 800 x 480 */
  const palp_svg_series *series;
  int series_count;
} palp_svg_line_chart_def;

palp_svg_line_chart_def palp_svg_line_chart_default_def(void);

/* One <polyline> per series with one point per finite sample (non-finite samples
 * are skipped), axes with "nice" ticks (1, 2, 5 x 10^k), axis labels with units
 * and a legend. */
int palp_svg_line_chart(FILE *out, const palp_svg_line_chart_def *def);
int palp_svg_line_chart_file(const char *path, const palp_svg_line_chart_def *def, char *err,
                             size_t errlen);

typedef struct palp_svg_bland_altman_def {
  const char *title;
  const char *unit;              /* unit of a and b, e.g. "cm" or "N"; NULL for none */
  const char *label_a, *label_b; /* names of the two methods */
  const double *a, *b;           /* [n] paired values */
  size_t n;
  double bias, sd;               /* from palp_stats_bland_altman */
  int width, height;             /* [px], default 800 x 480 */
  size_t max_points;             /* draw at most about this many circles (every k-th pair
                                    plus every pair outside bias +- 2 SD); 0 draws all.
                                    Default 4000: 400 frames x 338 vertices would
                                    otherwise make a 10 MB file no viewer enjoys */
} palp_svg_bland_altman_def;

palp_svg_bland_altman_def palp_svg_bland_altman_default_def(void);

/* One <circle> per pair at ((a+b)/2, a-b) (thinned by max_points), points outside
 * bias +- 2 SD marked;
 * horizontal lines at the bias (solid), bias +- 1.96 SD (dashed) and bias +- 2 SD
 * (dotted), each labelled with its value. */
int palp_svg_bland_altman(FILE *out, const palp_svg_bland_altman_def *def);
int palp_svg_bland_altman_file(const char *path, const palp_svg_bland_altman_def *def, char *err,
                               size_t errlen);

/* Writes s XML-escaped (& < > " ') with invalid UTF-8 and control characters
 * replaced by '?'. Exposed for tests and for other SVG writers. */
void palp_svg_write_text(FILE *out, const char *s);

#ifdef __cplusplus
}
#endif

#endif
