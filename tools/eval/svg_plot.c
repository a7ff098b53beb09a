/*
 * svg_plot.c - SVG 1.1 line charts and Bland-Altman plots (see svg_plot.h).
 *
 * Layout, in pixels: a plot frame inside fixed margins (title above, x label
 * below, rotated y label left); data map linearly onto the frame, y upwards.
 */
/* mkstemp, fchmod, fdopen: POSIX. */
#define _POSIX_C_SOURCE 200809L
#include "svg_plot.h"

#include "palp_utf8.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Okabe-Ito palette: distinguishable with the common colour-vision deficiencies. */
static const char *const palette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                      "#E69F00", "#56B4E9", "#000000", "#F0E442"};
#define PALETTE_N (sizeof palette / sizeof palette[0])

enum { MARGIN_L = 86, MARGIN_R = 24, MARGIN_T = 48, MARGIN_B = 64 };

static void msg(char *err, size_t errlen, const char *fmt, ...) {
  if (!err || !errlen) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err, errlen, fmt, ap);
  va_end(ap);
}

void palp_svg_write_text(FILE *out, const char *s) {
  if (!s) return;
  const unsigned char *p = (const unsigned char *)s;
  while (*p) {
    switch (*p) {
    case '&': fputs("&amp;", out); ++p; continue;
    case '<': fputs("&lt;", out); ++p; continue;
    case '>': fputs("&gt;", out); ++p; continue;
    case '"': fputs("&quot;", out); ++p; continue;
    case '\'': fputs("&apos;", out); ++p; continue;
    default: break;
    }
    if (*p < 0x20) { /* XML 1.0 forbids most control characters, even escaped */
      fputc(*p == '\t' ? ' ' : '?', out);
      ++p;
      continue;
    }
    size_t n = palp_utf8_xml_len(p, 4); /* a C string: its NUL ends a cut sequence */
    if (n == 0) {
      fputc('?', out);
      ++p;
      continue;
    }
    fwrite(p, 1, n, out);
    p += n;
  }
}

/* ---- axes --------------------------------------------------------------------- */

typedef struct axis {
  double lo, hi;   /* data range shown */
  double step;     /* tick spacing */
} axis;

/* Tick spacing of 1, 2 or 5 x 10^k giving about `target` intervals over range. */
static double nice_step(double range, int target) {
  double raw = range / target;
  double mag = pow(10.0, floor(log10(raw)));
  double f = raw / mag;
  double nf = f < 1.5 ? 1.0 : f < 3.0 ? 2.0 : f < 7.0 ? 5.0 : 10.0;
  return nf * mag;
}

static axis make_axis(double lo, double hi, int target) {
  axis a;
  if (!(hi > lo)) { /* a constant series still gets a visible, centred range */
    double pad = lo != 0.0 ? fabs(lo) * 0.1 : 1.0;
    lo -= pad;
    hi += pad;
  }
  a.step = nice_step(hi - lo, target);
  a.lo = floor(lo / a.step) * a.step;
  a.hi = ceil(hi / a.step) * a.step;
  return a;
}

static void format_tick(char *buf, size_t len, double v, double step) {
  if (fabs(v) < step * 1e-9) v = 0.0; /* no "-0" or "1e-17" at the origin */
  double as = fabs(step);
  if (as >= 1e-4 && as < 1e6) {
    int dec = as >= 1.0 ? 0 : (int)ceil(-log10(as) - 1e-9);
    snprintf(buf, len, "%.*f", dec, v);
  } else {
    snprintf(buf, len, "%.3g", v);
  }
}

typedef struct frame {
  double x0, y0, w, h; /* plot area [px], y0 = top */
  axis ax, ay;
} frame;

static double px(const frame *f, double x) { return f->x0 + (x - f->ax.lo) / (f->ax.hi - f->ax.lo) * f->w; }
static double py(const frame *f, double y) { return f->y0 + f->h - (y - f->ay.lo) / (f->ay.hi - f->ay.lo) * f->h; }

static void write_label_with_unit(FILE *out, const char *label, const char *unit) {
  palp_svg_write_text(out, label ? label : "");
  if (unit && *unit) {
    fputs(" [", out);
    palp_svg_write_text(out, unit);
    fputs("]", out);
  }
}

static void write_header(FILE *out, int w, int h, const char *title) {
  fprintf(out, "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n");
  fprintf(out,
          "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"%d\" height=\"%d\" "
          "viewBox=\"0 0 %d %d\" font-family=\"sans-serif\" font-size=\"13\">\n",
          w, h, w, h);
  fputs("<title>", out);
  palp_svg_write_text(out, title ? title : "plot");
  fputs("</title>\n", out);
  fprintf(out, "<rect x=\"0\" y=\"0\" width=\"%d\" height=\"%d\" fill=\"#ffffff\"/>\n", w, h);
  if (title) {
    fprintf(out, "<text class=\"title\" x=\"%.1f\" y=\"22\" text-anchor=\"middle\" font-size=\"16\" "
                 "font-weight=\"bold\">",
            w / 2.0);
    palp_svg_write_text(out, title);
    fputs("</text>\n", out);
  }
}

static void write_axes(FILE *out, const frame *f, const char *xl, const char *xu, const char *yl,
                       const char *yu) {
  fputs("<g class=\"axes\" stroke=\"#000000\" stroke-width=\"1\" fill=\"none\">\n", out);
  fprintf(out, "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\"/>\n", f->x0, f->y0,
          f->w, f->h);
  fputs("</g>\n<g class=\"grid\" stroke=\"#dddddd\" stroke-width=\"1\">\n", out);
  for (double v = f->ax.lo; v <= f->ax.hi + f->ax.step * 1e-6; v += f->ax.step)
    fprintf(out, "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\"/>\n", px(f, v), f->y0,
            px(f, v), f->y0 + f->h);
  for (double v = f->ay.lo; v <= f->ay.hi + f->ay.step * 1e-6; v += f->ay.step)
    fprintf(out, "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\"/>\n", f->x0, py(f, v),
            f->x0 + f->w, py(f, v));
  fputs("</g>\n<g class=\"ticks\" fill=\"#000000\">\n", out);
  char buf[64];
  for (double v = f->ax.lo; v <= f->ax.hi + f->ax.step * 1e-6; v += f->ax.step) {
    format_tick(buf, sizeof buf, v, f->ax.step);
    fprintf(out,
            "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" stroke=\"#000000\"/>"
            "<text class=\"xtick\" x=\"%.2f\" y=\"%.2f\" text-anchor=\"middle\">%s</text>\n",
            px(f, v), f->y0 + f->h, px(f, v), f->y0 + f->h + 5, px(f, v), f->y0 + f->h + 19, buf);
  }
  for (double v = f->ay.lo; v <= f->ay.hi + f->ay.step * 1e-6; v += f->ay.step) {
    format_tick(buf, sizeof buf, v, f->ay.step);
    fprintf(out,
            "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" stroke=\"#000000\"/>"
            "<text class=\"ytick\" x=\"%.2f\" y=\"%.2f\" text-anchor=\"end\">%s</text>\n",
            f->x0 - 5, py(f, v), f->x0, py(f, v), f->x0 - 8, py(f, v) + 4, buf);
  }
  fputs("</g>\n", out);
  fprintf(out, "<text class=\"xlabel\" x=\"%.2f\" y=\"%.2f\" text-anchor=\"middle\">",
          f->x0 + f->w / 2, f->y0 + f->h + 44);
  write_label_with_unit(out, xl, xu);
  fputs("</text>\n", out);
  double yc = f->y0 + f->h / 2;
  fprintf(out,
          "<text class=\"ylabel\" x=\"20\" y=\"%.2f\" text-anchor=\"middle\" "
          "transform=\"rotate(-90 20 %.2f)\">",
          yc, yc);
  write_label_with_unit(out, yl, yu);
  fputs("</text>\n", out);
}

static int finish(FILE *out) { return ferror(out) ? PALP_EIO : PALP_OK; }

/* ---- line chart --------------------------------------------------------------------- */

palp_svg_line_chart_def palp_svg_line_chart_default_def(void) {
  palp_svg_line_chart_def d;
  memset(&d, 0, sizeof d);
  d.width = 800;
  d.height = 480;
  return d;
}

int palp_svg_line_chart(FILE *out, const palp_svg_line_chart_def *def) {
  if (!out || !def || !def->series || def->series_count < 1) return PALP_EINVAL;
  if (def->width < 200 || def->height < 150) return PALP_EINVAL;
  double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
  for (int s = 0; s < def->series_count; ++s) {
    const palp_svg_series *se = &def->series[s];
    if (se->n > 0 && (!se->x || !se->y)) return PALP_EINVAL;
    for (size_t i = 0; i < se->n; ++i) {
      if (!isfinite(se->x[i]) || !isfinite(se->y[i])) continue;
      xlo = fmin(xlo, se->x[i]);
      xhi = fmax(xhi, se->x[i]);
      ylo = fmin(ylo, se->y[i]);
      yhi = fmax(yhi, se->y[i]);
    }
  }
  if (!(xlo <= xhi)) return PALP_EINVAL; /* no finite sample at all */

  frame f;
  f.x0 = MARGIN_L;
  f.y0 = MARGIN_T;
  f.w = def->width - MARGIN_L - MARGIN_R;
  f.h = def->height - MARGIN_T - MARGIN_B;
  f.ax = make_axis(xlo, xhi, 8);
  f.ay = make_axis(ylo, yhi, 6);

  write_header(out, def->width, def->height, def->title);
  write_axes(out, &f, def->x_label, def->x_unit, def->y_label, def->y_unit);

  fputs("<g class=\"series\" fill=\"none\" stroke-width=\"1.8\" stroke-linejoin=\"round\">\n", out);
  for (int s = 0; s < def->series_count; ++s) {
    const palp_svg_series *se = &def->series[s];
    const char *color = se->color ? se->color : palette[(size_t)s % PALETTE_N];
    fputs("<polyline stroke=\"", out);
    palp_svg_write_text(out, color);
    fputs("\"", out);
    if (se->dashed) fputs(" stroke-dasharray=\"6 4\"", out);
    fputs(" points=\"", out);
    int first = 1;
    for (size_t i = 0; i < se->n; ++i) {
      if (!isfinite(se->x[i]) || !isfinite(se->y[i])) continue;
      fprintf(out, "%s%.2f,%.2f", first ? "" : " ", px(&f, se->x[i]), py(&f, se->y[i]));
      first = 0;
    }
    fputs("\"><title>", out);
    palp_svg_write_text(out, se->label ? se->label : "");
    fputs("</title></polyline>\n", out);
  }
  fputs("</g>\n", out);

  /* Legend: top-right inside the frame, on a translucent box. */
  double lw = 0;
  for (int s = 0; s < def->series_count; ++s) {
    size_t len = def->series[s].label ? strlen(def->series[s].label) : 0;
    if (len * 7.2 > lw) lw = len * 7.2;
  }
  lw += 48;
  double lh = 20.0 * def->series_count + 8;
  double lx = f.x0 + f.w - lw - 8, ly = f.y0 + 8;
  fprintf(out,
          "<g class=\"legend\">\n<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" "
          "fill=\"#ffffff\" fill-opacity=\"0.85\" stroke=\"#888888\"/>\n",
          lx, ly, lw, lh);
  for (int s = 0; s < def->series_count; ++s) {
    const palp_svg_series *se = &def->series[s];
    const char *color = se->color ? se->color : palette[(size_t)s % PALETTE_N];
    double yy = ly + 18 + 20.0 * s;
    fprintf(out, "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" stroke-width=\"2\" stroke=\"",
            lx + 8, yy - 4, lx + 34, yy - 4);
    palp_svg_write_text(out, color);
    fputs("\"", out);
    if (se->dashed) fputs(" stroke-dasharray=\"6 4\"", out);
    fprintf(out, "/><text x=\"%.2f\" y=\"%.2f\">", lx + 40, yy);
    palp_svg_write_text(out, se->label ? se->label : "");
    fputs("</text>\n", out);
  }
  fputs("</g>\n</svg>\n", out);
  return finish(out);
}

/* ---- Bland-Altman ---------------------------------------------------------------------- */

palp_svg_bland_altman_def palp_svg_bland_altman_default_def(void) {
  palp_svg_bland_altman_def d;
  memset(&d, 0, sizeof d);
  d.width = 800;
  d.height = 480;
  d.max_points = 4000; /* as the header documents */
  return d;
}

/* A labelled horizontal line; LoA labels go left and band labels right so the
 * nearly coincident 1.96 SD and 2 SD lines stay readable. */
static void hline(FILE *out, const frame *f, double y, const char *cls, const char *dash,
                  const char *label, double value, int left) {
  fprintf(out,
          "<line class=\"%s\" x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" stroke=\"#444444\" "
          "stroke-width=\"1.4\"%s%s%s/>\n",
          cls, f->x0, py(f, y), f->x0 + f->w, py(f, y), dash ? " stroke-dasharray=\"" : "",
          dash ? dash : "", dash ? "\"" : "");
  fprintf(out, "<text class=\"%s-label\" x=\"%.2f\" y=\"%.2f\" text-anchor=\"%s\" font-size=\"11\">",
          cls, left ? f->x0 + 4 : f->x0 + f->w - 4, py(f, y) - 3, left ? "start" : "end");
  palp_svg_write_text(out, label);
  fprintf(out, " %.4g</text>\n", value);
}

int palp_svg_bland_altman(FILE *out, const palp_svg_bland_altman_def *def) {
  if (!out || !def || !def->a || !def->b || def->n < 1) return PALP_EINVAL;
  if (!isfinite(def->bias) || !isfinite(def->sd) || def->sd < 0) return PALP_EINVAL;
  if (def->width < 200 || def->height < 150) return PALP_EINVAL;
  double xlo = INFINITY, xhi = -INFINITY;
  double ylo = def->bias - 2.0 * def->sd, yhi = def->bias + 2.0 * def->sd;
  for (size_t i = 0; i < def->n; ++i) {
    double m = 0.5 * (def->a[i] + def->b[i]), d = def->a[i] - def->b[i];
    if (!isfinite(m) || !isfinite(d)) return PALP_EINVAL;
    xlo = fmin(xlo, m);
    xhi = fmax(xhi, m);
    ylo = fmin(ylo, d);
    yhi = fmax(yhi, d);
  }
  /* Headroom so the line labels above the +2 SD line stay inside the frame. */
  double pad = 0.08 * (yhi - ylo);
  frame f;
  f.x0 = MARGIN_L;
  f.y0 = MARGIN_T;
  f.w = def->width - MARGIN_L - MARGIN_R;
  f.h = def->height - MARGIN_T - MARGIN_B;
  double xpad = 0.03 * (xhi - xlo); /* keep points off the frame */
  f.ax = make_axis(xlo - xpad, xhi + xpad, 8);
  f.ay = make_axis(ylo - pad, yhi + pad, 6);

  char xl[256], yl[256];
  snprintf(xl, sizeof xl, "mean of %s and %s", def->label_a ? def->label_a : "a",
           def->label_b ? def->label_b : "b");
  snprintf(yl, sizeof yl, "%s - %s", def->label_a ? def->label_a : "a",
           def->label_b ? def->label_b : "b");
  write_header(out, def->width, def->height, def->title ? def->title : "Bland-Altman plot");
  write_axes(out, &f, xl, def->unit, yl, def->unit);

  hline(out, &f, def->bias + 2.0 * def->sd, "band", "2 3", "+2 SD", def->bias + 2.0 * def->sd, 0);
  hline(out, &f, def->bias - 2.0 * def->sd, "band", "2 3", "-2 SD", def->bias - 2.0 * def->sd, 0);
  hline(out, &f, def->bias + 1.96 * def->sd, "loa", "7 4", "+1.96 SD", def->bias + 1.96 * def->sd, 1);
  hline(out, &f, def->bias - 1.96 * def->sd, "loa", "7 4", "-1.96 SD", def->bias - 1.96 * def->sd, 1);
  hline(out, &f, def->bias, "bias", NULL, "bias", def->bias, 0);

  /* Thinning keeps every k-th pair and every pair outside the band, so the
   * picture of the spread and all the disagreeing points survive. */
  size_t stride = 1;
  if (def->max_points > 0 && def->n > def->max_points)
    stride = (def->n + def->max_points - 1) / def->max_points;
  size_t outside = 0, drawn = 0;
  fputs("<g class=\"points\" fill-opacity=\"0.75\">\n", out);
  for (size_t i = 0; i < def->n; ++i) {
    double m = 0.5 * (def->a[i] + def->b[i]), d = def->a[i] - def->b[i];
    int out_band = fabs(d - def->bias) > 2.0 * def->sd;
    outside += (size_t)out_band;
    if (!out_band && i % stride != 0) continue;
    drawn++;
    fprintf(out, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"2.6\" fill=\"%s\"/>\n", px(&f, m), py(&f, d),
            out_band ? "#D55E00" : "#0072B2");
  }
  fputs("</g>\n", out);
  double within = 100.0 * (double)(def->n - outside) / (double)def->n;
  fprintf(out,
          "<text class=\"summary\" x=\"%.2f\" y=\"%.2f\" font-size=\"12\">n = %zu, %.1f %% within "
          "bias &#177; 2 SD (orange: outside)",
          f.x0, f.y0 - 6, def->n, within);
  if (drawn < def->n)
    fprintf(out, "; %zu pairs drawn: every %zu-th and all outside", drawn, stride);
  fputs("</text>\n", out);
  fputs("</svg>\n", out);
  return finish(out);
}

/* ---- files ----------------------------------------------------------------------------- */

/* A plot goes to a temporary file next to path and is renamed over it only when whole, so a
 * failed plot leaves whatever was at path untouched and removes only the file it created.
 * A path that exists and is not a regular file (a device such as /dev/null, a FIFO) is
 * written in place: renaming over it would replace the device node. */
static int to_file(const char *path, int (*fn)(FILE *, const void *), const void *def, char *err,
                   size_t errlen) {
  struct stat sb;
  const int special = stat(path, &sb) == 0 && !S_ISREG(sb.st_mode);
  char tmp[4096];
  FILE *f = NULL;
  if (special) {
    f = fopen(path, "w");
  } else if (snprintf(tmp, sizeof tmp, "%s.XXXXXX", path) < (int)sizeof tmp) {
    int fd = mkstemp(tmp);
    if (fd >= 0) {
      fchmod(fd, 0644); /* mkstemp makes it 0600; a plot is for reading */
      f = fdopen(fd, "w");
      if (!f) {
        close(fd);
        remove(tmp);
      }
    }
  } else {
    errno = ENAMETOOLONG;
  }
  if (!f) {
    msg(err, errlen, "%s: cannot write the plot: %s", path, strerror(errno));
    return PALP_EIO;
  }
  int rc = fn(f, def);
  if (fclose(f) != 0 && rc == 0) rc = PALP_EIO;
  if (!special) {
    if (rc < 0) remove(tmp); /* ours: no half-written plot left behind */
    else if (rename(tmp, path) != 0) {
      msg(err, errlen, "%s: cannot write the plot: %s", path, strerror(errno));
      remove(tmp);
      return PALP_EIO;
    }
  }
  if (rc == PALP_EINVAL) msg(err, errlen, "%s: nothing to plot (no finite data or invalid plot settings)", path);
  else if (rc < 0) msg(err, errlen, "%s: write error while writing the plot", path);
  return rc;
}

static int line_thunk(FILE *f, const void *d) { return palp_svg_line_chart(f, d); }
static int ba_thunk(FILE *f, const void *d) { return palp_svg_bland_altman(f, d); }

int palp_svg_line_chart_file(const char *path, const palp_svg_line_chart_def *def, char *err,
                             size_t errlen) {
  return to_file(path, line_thunk, def, err, errlen);
}

int palp_svg_bland_altman_file(const char *path, const palp_svg_bland_altman_def *def, char *err,
                               size_t errlen) {
  return to_file(path, ba_thunk, def, err, errlen);
}
