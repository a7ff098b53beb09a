/* report: one self-contained HTML page per session (inline CSS and SVG, no script, no external
 * resource), readable in any browser from a USB stick: force over time, displacement over time,
 * and where the trainee pressed, drawn on a top view of the phantom's rest mesh shaded by the
 * largest deformation logged. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "assess_log.h"
#include "assess_svg.h"
#include "grades.h"
#include "palp_app.h"
#include "review.h"

#define PLOT_POINTS 1500 /* time-series points per plot; buckets keep their maxima so peaks survive */

typedef struct series {
  const char *name, *color;
  const double *x, *y;
  int n;
} series;

/* A "nice" tick step (1, 2 or 5 times a power of ten) giving about `target` intervals. */
static double nice_step(double range, int target) {
  if (!(range > 0)) return 1.0;
  double raw = range / target, p = pow(10.0, floor(log10(raw))), m = raw / p;
  return p * (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10);
}

/* Axis ticks from `first` in steps of `step` up to `last`: at most MAX_TICKS, and none when the step
 * does not move a value of that size (first + step == first: frame times of 1e17 s from a damaged log,
 * where "v += step" never passed the end and the report wrote <line> elements until the disk filled). */
#define MAX_TICKS 100
static int tick_count(double first, double last, double step) {
  if (!isfinite(first) || !isfinite(last) || !(step > 0) || !isfinite(step) || !(first + step > first)) return 0;
  const double n = floor((last - first) / step + 1e-9) + 1;
  return !(n >= 1) ? 0 : n > MAX_TICKS ? MAX_TICKS : (int)n;
}

/* The plot's bounds and points are of the finite values only: a log edited or damaged elsewhere may
 * hold an infinite or NaN time or value (SQLite stores 9e999 as +Inf), which has no place on an axis;
 * such points are left out of the line and counted under the plot. */
static void svg_plot(FILE *f, const char *id, const char *title, const char *xlabel, const char *ylabel,
                     const series *s, int ns) {
  const double W = 760, H = 300, L = 70, R = 20, T = 36, B = 46;
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  int any = 0;
  long long nonfinite = 0;
  for (int k = 0; k < ns; k++)
    for (int i = 0; i < s[k].n; i++) {
      if (!isfinite(s[k].x[i]) || !isfinite(s[k].y[i])) {
        nonfinite++;
        continue;
      }
      if (!any) x0 = x1 = s[k].x[i], any = 1;
      if (s[k].x[i] < x0) x0 = s[k].x[i];
      if (s[k].x[i] > x1) x1 = s[k].x[i];
      if (s[k].y[i] > y1) y1 = s[k].y[i];
      if (s[k].y[i] < y0) y0 = s[k].y[i];
    }
  /* A span that a value of this size can hold: x0 + 1 == x0 beyond 2^53, which divided by zero below. */
  if (!(x1 > x0)) x1 = x0 + fmax(1.0, fabs(x0) * 1e-9);
  if (!(y1 > y0)) y1 = y0 + fmax(1.0, fabs(y0) * 1e-9);
  const double ys = nice_step(y1 - y0, 5), xs = nice_step(x1 - x0, 8);
  if (isfinite(ceil(y1 / ys) * ys) && isfinite(floor(y0 / ys) * ys) && ceil(y1 / ys) * ys > floor(y0 / ys) * ys) {
    y1 = ceil(y1 / ys) * ys;
    y0 = floor(y0 / ys) * ys;
  }
#define PX(v) (L + ((v) - x0) / (x1 - x0) * (W - L - R))
#define PY(v) (H - B - ((v) - y0) / (y1 - y0) * (H - T - B))
  fprintf(f, "<svg id=\"%s\" class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
             "viewBox=\"0 0 %.0f %.0f\" role=\"img\" aria-label=\"%s\">\n",
          id, W, H, W, H, title);
  fprintf(f, "<rect x=\"0\" y=\"0\" width=\"%.0f\" height=\"%.0f\" fill=\"#ffffff\"/>\n", W, H);
  fprintf(f, "<text x=\"%.0f\" y=\"20\" font-size=\"15\" font-weight=\"bold\">%s</text>\n", L, title);
  const int nyt = tick_count(y0, y1, ys);
  for (int k = 0; k < nyt; k++) {
    const double v = y0 + k * ys;
    fprintf(f, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#e2e2e2\"/>", L, PY(v), W - R, PY(v));
    fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" text-anchor=\"end\">%g</text>\n", L - 6, PY(v) + 4,
            fabs(v) < 1e-12 ? 0.0 : v);
  }
  const double xfirst = ceil(x0 / xs) * xs;
  const int nxt = tick_count(xfirst, x1, xs);
  for (int k = 0; k < nxt; k++) {
    const double v = xfirst + k * xs;
    fprintf(f, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#f0f0f0\"/>", PX(v), T, PX(v), H - B);
    fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" text-anchor=\"middle\">%g</text>\n", PX(v), H - B + 16,
            fabs(v) < 1e-12 ? 0.0 : v);
  }
  fprintf(f, "<rect x=\"%.0f\" y=\"%.0f\" width=\"%.0f\" height=\"%.0f\" fill=\"none\" stroke=\"#444\"/>\n", L, T,
          W - L - R, H - T - B);
  fprintf(f, "<text x=\"%.0f\" y=\"%.0f\" font-size=\"12\" text-anchor=\"middle\">%s</text>\n", (L + W - R) / 2,
          H - 8, xlabel);
  fprintf(f, "<text x=\"14\" y=\"%.0f\" font-size=\"12\" text-anchor=\"middle\" transform=\"rotate(-90 14 %.0f)\">%s</text>\n",
          (T + H - B) / 2, (T + H - B) / 2, ylabel);
  for (int k = 0; k < ns; k++) {
    fprintf(f, "<polyline class=\"series\" fill=\"none\" stroke=\"%s\" stroke-width=\"1.6\" points=\"", s[k].color);
    for (int i = 0; i < s[k].n; i++)
      if (isfinite(s[k].x[i]) && isfinite(s[k].y[i])) fprintf(f, "%.1f,%.1f ", PX(s[k].x[i]), PY(s[k].y[i]));
    fputs("\"/>\n", f);
    fprintf(f, "<rect x=\"%.0f\" y=\"%.0f\" width=\"14\" height=\"3\" fill=\"%s\"/>", W - R - 190, T + 10 + 16.0 * k,
            s[k].color);
    fprintf(f, "<text x=\"%.0f\" y=\"%.0f\" font-size=\"12\">%s</text>\n", W - R - 170, T + 15 + 16.0 * k, s[k].name);
  }
#undef PX
#undef PY
  fputs("</svg>\n", f);
  if (nonfinite)
    fprintf(f, "<p class=\"warn nonfinite\">%lld point%s of this plot not drawn: the log holds a time or value there "
               "that is not a finite number (a damaged or edited log).</p>\n",
            nonfinite, nonfinite == 1 ? "" : "s");
}

/* ---- time series, bucketed -------------------------------------------------------------- */
typedef struct ts_ctx {
  int64_t per_bucket, in_bucket;
  int n, cap;
  double *t, *force, *top, *max;
} ts_ctx;

static int ts_cb(void *u, const palp_db_frame *fr) {
  ts_ctx *c = u;
  if (c->in_bucket == 0) {
    if (c->n == c->cap) return 1;
    c->t[c->n] = fr->sim_time_s;
    c->force[c->n] = fr->contact_force_n;
    c->top[c->n] = fr->top_disp_m * 1e3;
    c->max[c->n] = fr->max_disp_m * 1e3;
    c->n++;
  } else {
    int i = c->n - 1;
    if (fr->contact_force_n > c->force[i]) c->force[i] = fr->contact_force_n;
    if (fr->top_disp_m * 1e3 > c->top[i]) c->top[i] = fr->top_disp_m * 1e3;
    if (fr->max_disp_m * 1e3 > c->max[i]) c->max[i] = fr->max_disp_m * 1e3;
  }
  if (++c->in_bucket == c->per_bucket) c->in_bucket = 0;
  return 0;
}

/* ---- the deformed mesh with the largest displacement ------------------------------------- */
typedef struct mesh_ctx {
  const palp_mesh *rest;
  palp_vec3 *best;
  double best_max;
  int64_t best_frame;
} mesh_ctx;

static int mesh_cb(void *u, int64_t frame, const palp_vec3 *pos, int n) {
  mesh_ctx *c = u;
  if (!c->rest || n != c->rest->vertex_count) return 0;
  double m = 0;
  for (int i = 0; i < n; i++) {
    double dx = pos[i].x - c->rest->rest[i].x, dy = pos[i].y - c->rest->rest[i].y, dz = pos[i].z - c->rest->rest[i].z;
    double d = sqrt(dx * dx + dy * dy + dz * dz);
    if (d > m) m = d;
  }
  if (m > c->best_max) {
    c->best_max = m;
    c->best_frame = frame;
    memcpy(c->best, pos, (size_t)n * sizeof *pos);
  }
  return 0;
}

static const char *const press_colors[] = {"#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b"};

/* a: the assessment (NULL or no touches: none); its finger's touches replace the finger slot's
 * device points with the contact points on the surface, one line per touch. */
static void svg_topview(FILE *f, const palp_mesh *m, const mesh_ctx *mc, const review_contacts *in,
                        const review_press *pr, int np, const review_assessment *a) {
  const int touches = a && a->touch_n > 0;
  const double S = 440, C = S / 2, R = m ? sqrt(m->rest[0].x * m->rest[0].x + m->rest[0].y * m->rest[0].y +
                                                m->rest[0].z * m->rest[0].z) : 0.04;
  const double k = (S / 2 - 30) / R; /* px per m */
#define TX(p) (C + (p).x * k)
#define TY(p) (C - (p).y * k)
  fprintf(f, "<svg id=\"plot-topview\" class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" "
             "height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\" role=\"img\" aria-label=\"where the trainee pressed\">\n",
          S, S + 30, S, S + 30);
  fprintf(f, "<rect width=\"%.0f\" height=\"%.0f\" fill=\"#ffffff\"/>\n", S, S + 30);
  if (m) {
    fputs("<g class=\"mesh\" stroke=\"#b9a89e\" stroke-width=\"0.4\">\n", f);
    for (int t = 0; t < m->dome_triangle_count; t++) {
      const int *v = m->tri[t];
      double shade = 0;
      if (mc->best_max > 0) {
        for (int j = 0; j < 3; j++) {
          const palp_vec3 a = mc->best[v[j]], b = m->rest[v[j]];
          shade += sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
        }
        shade /= 3 * mc->best_max;
      }
      /* Skin tone at rest towards deep red at the largest displacement. */
      int r = (int)(246 - shade * (246 - 178)), g = (int)(226 - shade * (226 - 24)), b = (int)(212 - shade * (212 - 43));
      fprintf(f, "<polygon fill=\"rgb(%d,%d,%d)\" points=\"%.1f,%.1f %.1f,%.1f %.1f,%.1f\"/>\n", r, g, b,
              TX(m->rest[v[0]]), TY(m->rest[v[0]]), TX(m->rest[v[1]]), TY(m->rest[v[1]]), TX(m->rest[v[2]]),
              TY(m->rest[v[2]]));
    }
    fputs("</g>\n", f);
  }
  fprintf(f, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"none\" stroke=\"#555\"/>\n", C, C, R * k);
  fprintf(f, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"2\" fill=\"#555\"/>\n", C, C);
  const char *lab[4] = {"12", "3", "6", "9"};
  const double lx[4] = {C, C + R * k + 14, C, C - R * k - 14}, ly[4] = {C - R * k - 8, C + 4, C + R * k + 18, C + 4};
  for (int i = 0; i < 4; i++)
    fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"12\" text-anchor=\"middle\">%s</text>\n", lx[i], ly[i], lab[i]);
  /* Finger paths: every logged centre of the slot while it lived. */
  for (int p = 0; p < np; p++) {
    const char *col = press_colors[p % 6];
    if (pr[p].kind == PALP_DB_KIND_FINGER && touches) continue; /* drawn by its touches below */
    if (pr[p].kind == PALP_DB_KIND_FINGER) {
      fprintf(f, "<polyline class=\"finger-path\" fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" stroke-opacity=\"0.8\" points=\"", col);
      int live = 0;
      for (int i = 0; i < in->n; i++) {
        const palp_db_contact *c = &in->v[i];
        if (c->slot != pr[p].slot || c->kind != PALP_DB_KIND_FINGER) continue;
        if (c->op == PALP_DB_OP_ADD) live = c->sim_time_s == pr[p].t_on_s;
        if (!live || c->op == PALP_DB_OP_REMOVE) {
          if (c->op == PALP_DB_OP_REMOVE) live = 0;
          continue;
        }
        fprintf(f, "%.1f,%.1f ", TX(c->center_m), TY(c->center_m));
      }
      fputs("\"/>\n", f);
    }
    const double rad = 5 + 3 * sqrt(pr[p].peak_force_n);
    fprintf(f, "<circle class=\"press\" cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"%s\" fill-opacity=\"0.45\" "
               "stroke=\"%s\" stroke-width=\"1.5\"><title>slot %d, %s, peak %.2f N</title></circle>\n",
            TX(pr[p].first_center_m), TY(pr[p].first_center_m), rad, col, col, pr[p].slot,
            pr[p].kind == PALP_DB_KIND_FORCE ? "force contact" : "finger", pr[p].peak_force_n);
    fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" text-anchor=\"middle\">%d</text>\n",
            TX(pr[p].first_center_m), TY(pr[p].first_center_m) + 4, p + 1);
  }
  /* (n, not k: k is the scale the TX/TY macros use.) The finger's touches: each one's contact points as a line (at most ~1500 points in all), and
   * a circle where it came down, sized by its peak force, numbered as the touches table. */
  const int stride = touches && a->path_n > 1500 ? (a->path_n + 1499) / 1500 : 1;
  for (int n = 0, at = 0; touches && n < a->touch_n; at += a->touches[n].contact_samples, n++) {
    const palp_touch *t = &a->touches[n];
    fputs("<polyline class=\"touch-path\" fill=\"none\" stroke=\"#1f4e8c\" stroke-width=\"1.2\" stroke-opacity=\"0.7\" "
          "points=\"", f);
    const int end = at + t->contact_samples < a->path_n ? at + t->contact_samples : a->path_n;
    for (int i = at; i < end; i += stride) fprintf(f, "%.1f,%.1f ", TX(a->path[i]), TY(a->path[i]));
    if (end > at && (end - 1 - at) % stride) fprintf(f, "%.1f,%.1f", TX(a->path[end - 1]), TY(a->path[end - 1])); /* its lift */
    fputs("\"/>\n", f);
  }
  for (int n = 0; touches && n < a->touch_n; n++) {
    const palp_touch *t = &a->touches[n];
    fprintf(f, "<circle class=\"touch\" cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"#1f4e8c\" fill-opacity=\"0.35\" "
               "stroke=\"#1f4e8c\"><title>touch %d: %.2f .. %.2f s, deepest %.1f mm, peak %.2f N</title></circle>\n",
            TX(t->first_point), TY(t->first_point), 3 + 2 * sqrt(t->peak_force), n + 1, t->t_on, t->t_off,
            t->peak_indentation * 1e3, t->peak_force);
    if (a->touch_n <= 30)
      fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"10\" text-anchor=\"middle\">%d</text>\n", TX(t->first_point),
              TY(t->first_point) - 6, n + 1);
  }
  if (mc->best_max > 0)
    fprintf(f, "<text x=\"8\" y=\"%.0f\" font-size=\"12\">shading: displacement at frame %lld, max %.2f mm</text>\n",
            S + 20, (long long)mc->best_frame, mc->best_max * 1e3);
  else fprintf(f, "<text x=\"8\" y=\"%.0f\" font-size=\"12\">rest shape (no deformed mesh logged)</text>\n", S + 20);
#undef TX
#undef TY
  fputs("</svg>\n", f);
}

static int ev_row(void *u, double wall, int64_t frame, const char *kind, const char *detail, int64_t count) {
  FILE *f = u;
  char ts[64];
  review_fmt_time(wall, ts, sizeof ts);
  fprintf(f, "<tr><td>%s</td><td>%lld</td><td>", ts, (long long)frame);
  html_str(f, kind);
  fprintf(f, "</td><td>%lld</td><td>", (long long)count);
  html_str(f, detail);
  fputs("</td></tr>\n", f);
  return 0;
}

static int note_row(void *u, double wall, const char *author, const char *text, const char *grade) {
  FILE *f = u;
  char ts[64];
  review_fmt_time(wall, ts, sizeof ts);
  fprintf(f, "<tr><td>%s</td><td>", ts);
  html_str(f, author);
  fputs("</td><td>", f);
  html_str(f, grade ? grade : "");
  fputs("</td><td>", f);
  html_str(f, text);
  fputs("</td></tr>\n", f);
  return 0;
}

/* A table of the log the page could not read to its end (a damaged page): said on the page where it
 * stops, and the first such kept in why for the exit status (2026-12-06: the tables ended silently). */
static void unreadable(FILE *f, palp_db *db, const char *table, char *why, size_t len) {
  char msg[320];
  snprintf(msg, sizeof msg, "the %s table could not be read: %s", table, palp_db_errmsg(db));
  fputs("<p class=\"warn db-error\">Incomplete: ", f);
  html_str(f, msg);
  fputs(".</p>\n", f);
  if (!why[0]) snprintf(why, len, "%s", msg);
}

static void info_row(FILE *f, const char *k, const char *v) {
  fprintf(f, "<tr><th>%s</th><td>", k);
  html_str(f, v);
  fputs("</td></tr>\n", f);
}


/* One metric row: its name, value, the rubric's pass mark and the verdict, with data-
 * attributes so that a reader (or a test) finds a metric by name, not by position. */
static void metric_row(FILE *f, const char *key, const char *name, const char *value, const char *mark, int verdict) {
  fprintf(f, "<tr data-metric=\"%s\"><th>%s</th><td class=\"value\">", key, name);
  html_str(f, value);
  fputs("</td><td>", f);
  html_str(f, mark);
  fprintf(f, "</td><td class=\"%s\">%s</td></tr>\n", verdict < 0 ? "na" : verdict ? "pass" : "fail",
          verdict < 0 ? "-" : verdict ? "pass" : "FAIL");
}

/* Where the phantom's model answered outside its valid range (docs/model.md, "Valid range"),
 * next to the assessment whose pressure levels rest on its forces. */
static void valid_range_section(palp_db *db, const palp_db_session_info *s, FILE *f) {
  char range[640];
  const int in_range = review_valid_range_text(db, s, range, sizeof range);
  fprintf(f, "<h2>The model's valid range</h2>\n<p id=\"valid-range\"%s>",
          in_range == REVIEW_RANGE_OUTSIDE ? " class=\"warn\"" : "");
  html_str(f, range);
  if (in_range == REVIEW_RANGE_OUTSIDE)
    fputs(". The forces there are the model's extrapolation, not what it was validated to give: weigh the "
          "pressure levels the assessment credits there accordingly.", f);
  fputs("</p>\n", f);
}

/* The assessment (issue 13): metrics and score against the rubric, the coverage map per
 * pressure band, the finger's path with the findings against the now revealed lesions. */
/* Leaves the assessment in *keep (the caller frees it; zeroed when there is none) for the
 * touches table further down. */
static void assessment_section(palp_log *log, palp_db *db, const palp_db_session_info *s, FILE *f,
                               review_assessment *keep, char *why, size_t whylen) {
  review_assessment a;
  char err[256] = "";
  memset(keep, 0, sizeof *keep);
  fputs("<h2>Assessment</h2>\n", f);
  const int rc = review_assess(db, s, &a, err, sizeof err);
  if (rc == PALP_DB_ENOTFOUND) {
    review_assessment st;
    const int stored = review_stored_metrics(db, s->id, &st);
    if (stored == 0 && st.has_exercise) {
      fprintf(f, "<p id=\"assessment-pruned\">The finger samples of this session were pruned; its stored metrics: "
              "%d of %d lesions found, %d false positives, coverage light/medium/deep %.1f%% / %.1f%% / %.1f%%, "
              "pattern %s, score %.1f (%s).</p>\n", st.r.found, st.r.lesion_count, st.r.false_positives,
              100 * st.r.coverage[0], 100 * st.r.coverage[1], 100 * st.r.coverage[2], palp_pattern_name(st.r.pattern),
              palp_shown_tenths(st.r.score, NAN, st.r.pass), st.r.pass ? "pass" : "fail");
    } else if (stored == 0) {
      /* free practice: no lesions to find and no score (stored as NULL), as show and the CSVs say */
      fprintf(f, "<p id=\"assessment-pruned\">The finger samples of this session were pruned; its stored metrics "
              "(free practice: no hidden lesions, no score): %d mark%s (%d withdrawn), coverage light/medium/deep "
              "%.1f%% / %.1f%% / %.1f%%, pattern %s.</p>\n", st.r.findings, st.r.findings == 1 ? "" : "s",
              st.r.withdrawn, 100 * st.r.coverage[0], 100 * st.r.coverage[1], 100 * st.r.coverage[2],
              palp_pattern_name(st.r.pattern));
    } else if (stored != PALP_DB_ENOTFOUND) {
      unreadable(f, db, "session_metrics", why, whylen);
    } else {
      fputs("<p id=\"assessment-none\">No finger samples were logged for this session (a force-driven session, or a "
            "log from before the assessment): nothing to assess.</p>\n", f);
    }
    return;
  }
  if (rc) {
    palp_log_warn(log, "report: assessment: %s", err);
    /* the log could not be read: the page says it, and the exit status (since session 81: exit 0), as
     * export, trainee and class do; a scene or exercise that does not parse stays said on the page alone */
    if ((rc == PALP_DB_ESQL || rc == PALP_ENOMEM) && !why[0])
      snprintf(why, whylen, "the assessment could not be computed: %s", err);
    fputs("<p class=\"warn\" id=\"assessment-error\">The assessment could not be computed: ", f);
    html_str(f, err);
    fputs("</p>\n", f);
    return;
  }
  const palp_assess_result *r = &a.r;
  const palp_rubric *rb = &a.ex.rubric;
  char v[256], m[128];
  if (a.has_exercise) {
    fputs("<p>Exercise <b id=\"exercise-name\">", f);
    html_str(f, a.exercise_name);
    fputs("</b>: ", f);
    html_str(f, a.ex.title);
    fprintf(f, " (time limit %.0f s). Metrics from %d finger samples; definitions in docs/assessment.md.</p>\n",
            a.ex.time_limit, a.samples);
    char drawn[160];
    if (review_drawn_text(&a.ex, drawn, sizeof drawn))
      fprintf(f, "<p id=\"drawn\">Its lesions were %s: the places below are this attempt's own.</p>\n", drawn);
    /* an attempt after a debrief on the same lesions (docs/assessment.md, "Debrief") */
    review_told told;
    if (review_told_before(db, s, &a, &told) == 1) {
      char t[512];
      review_told_text(s, &told, t, sizeof t);
      fputs("<p class=\"warn\" id=\"told-before\">", f);
      html_str(f, t);
      fputs(".</p>\n", f);
    }
    /* and what this session's debrief told as it closed */
    palp_db_debrief d;
    const int st = review_debrief(db, s, &d);
    char t[1024];
    review_debrief_text(st, &d, &a, t, sizeof t);
    fprintf(f, "<p id=\"debrief\"%s>Debrief as the session ended: ",
            (st == REVIEW_DEBRIEF_LOGGED && d.sent) || st == REVIEW_DEBRIEF_UNKNOWN ? "" : " class=\"warn\"");
    html_str(f, t);
    fputs(".</p>\n", f);
  } else {
    fprintf(f, "<p id=\"exercise-name\">Free practice: no exercise, no hidden lesions, so no sensitivity and no score. "
            "Metrics from %d finger samples.</p>\n", a.samples);
  }
  fputs("<table id=\"metrics\"><tr><th>metric</th><th>value</th><th>pass mark</th><th>verdict</th></tr>\n", f);
  const int ex = a.has_exercise;
  if (ex) {
    snprintf(v, sizeof v, "%d of %d lesions found (%.0f%%)", r->found, r->lesion_count, 100 * r->sensitivity);
    snprintf(m, sizeof m, ">= %.0f%%", 100 * rb->pass_sensitivity);
    metric_row(f, "sensitivity", "Sensitivity", v, m, r->pass_metric[PALP_METRIC_SENSITIVITY]);
    snprintf(v, sizeof v, "%d (of %d marks, %d withdrawn)", r->false_positives, r->findings, r->withdrawn);
    snprintf(m, sizeof m, "<= %d", rb->pass_max_false_positives);
    metric_row(f, "false_positives", "False positives", v, m, r->pass_metric[PALP_METRIC_FALSE_POSITIVES]);
  }
  for (int b = 0; b < PALP_BAND_COUNT; b++) {
    char key[32], name[64];
    snprintf(key, sizeof key, "coverage_%s", palp_band_name(b));
    snprintf(name, sizeof name, "Thoroughness, %s pressure", palp_band_name(b));
    snprintf(v, sizeof v, "%.1f%% of the dome", 100 * r->coverage[b]);
    snprintf(m, sizeof m, ">= %.0f%%", 100 * rb->pass_coverage[b]);
    metric_row(f, key, name, v, ex ? m : "-", ex ? r->pass_metric[PALP_METRIC_THOROUGHNESS] : -1);
  }
  snprintf(v, sizeof v, "%s (path %.2f m, %d presses, overlap %.2f, never palpated %.1f%%, largest gap %.1f cm2)",
           palp_pattern_name(r->pattern), r->evidence.path_length, r->evidence.presses, r->evidence.overlap,
           100 * r->evidence.gap_share, r->evidence.largest_gap * 1e4);
  review_pattern_mark(rb, m, sizeof m);
  metric_row(f, "pattern", "Search pattern", v, ex ? m : "-", ex ? r->pass_metric[PALP_METRIC_PATTERN] : -1);
  if (review_strips_shown(r)) {
    snprintf(v, sizeof v, "%d strips, in order %.2f (steps between strips that keep the direction of the one before)",
             r->evidence.strips, r->evidence.sweep_monotony);
    /* the order's verdict is part of the pattern's row; this row says what the rubric asks of it */
    if (ex && (rb->pass_strip_order > 0.0 || rb->strip_order_share > 0.0))
      snprintf(m, sizeof m, ">= %.2f; %.0f%% of the pattern's credit (%.2f of 1)", rb->pass_strip_order,
               100 * rb->strip_order_share, r->component[PALP_METRIC_PATTERN]);
    else snprintf(m, sizeof m, "-");
    /* its own verdict where the rubric sets a pass mark (it is also part of the pattern's) */
    metric_row(f, "strips", "Strips and their order", v, m,
               ex && rb->pass_strip_order > 0.0 ? r->evidence.sweep_monotony >= rb->pass_strip_order : -1);
  }
  snprintf(v, sizeof v, "%.2f s", r->duration);
  snprintf(m, sizeof m, "<= %.0f s", a.ex.time_limit);
  metric_row(f, "time", "Time", v, ex ? m : "-", ex ? r->pass_metric[PALP_METRIC_TIME] : -1);
  snprintf(v, sizeof v, "peak %.2f N, %d episode%s above %.2f N (%.2f s)", r->peak_force, r->out_of_range,
           r->out_of_range == 1 ? "" : "s", a.ex.max_force, r->out_of_range_time);
  snprintf(m, sizeof m, "<= %d episodes", rb->pass_max_out_of_range);
  metric_row(f, "force", "Force", v, ex ? m : "-", ex ? r->pass_metric[PALP_METRIC_FORCE] : -1);
  if (ex) {
    snprintf(v, sizeof v, "%.1f / 100", palp_shown_tenths(r->score, r->pass ? rb->pass_score : NAN, r->pass));
    snprintf(m, sizeof m, ">= %g and every metric", rb->pass_score);
    metric_row(f, "score", "Score", v, m, r->pass);
  }
  fputs("</table>\n", f);

  fputs("<h3>Coverage per pressure level</h3>\n<p>Seen from above (12 o'clock = +y). A triangle is coloured when the "
        "finger's contact footprint covered it in that band:", f);
  for (int b = 0; b < PALP_BAND_COUNT; b++)
    fprintf(f, " <span style=\"display:inline-block;width:10px;height:10px;background:%s\"></span> %s", review_band_colour[b],
            palp_band_name(b));
  fprintf(f, "; <span style=\"display:inline-block;width:10px;height:10px;background:%s\"></span> never.</p>\n<div "
          "id=\"coverage-maps\" style=\"display:flex;gap:16px;flex-wrap:wrap\">\n", REVIEW_UNCOVERED_COLOUR);
  for (int b = 0; b < PALP_BAND_COUNT; b++) {
    char id[32];
    snprintf(id, sizeof id, "coverage-%s", palp_band_name(b));
    fprintf(f, "<figure style=\"margin:0\"><figcaption>%s: %.1f%%</figcaption>\n", palp_band_name(b), 100 * r->coverage[b]);
    review_svg_coverage(f, &a, b, 220, id);
    fputs("</figure>\n", f);
  }
  fputs("</div>\n<h3>Path and findings</h3>\n<p>The finger's contact point while touching (grey line); the lesions, "
        "revealed (dashed orange circles, their size); the trainee's marks: a blue cross found a lesion, a pink square "
        "is a false positive, a grey ring was withdrawn.</p>\n", f);
  review_svg_path(f, &a, 360, "finger-path");
  fputs("<table id=\"findings\"><tr><th>#</th><th>mark</th><th>time [s]</th><th>x, y, z [mm]</th><th>clock</th>"
        "<th>verdict</th></tr>\n", f);
  for (int i = 0; i < a.mark_n; i++) {
    const review_mark *k = &a.marks[i];
    const palp_vec3 p = k->f.point;
    char clk[24];
    fprintf(f, "<tr class=\"finding %s\"><td>%d</td><td>%lld</td><td>%.2f</td><td>%.1f, %.1f, %.1f</td><td>%s</td><td>",
            review_finding_class(k->match), i + 1, (long long)k->mark_id, k->f.t, p.x * 1e3, p.y * 1e3, p.z * 1e3,
            review_clock_cell(p, 0, clk, sizeof clk));
    if (k->match >= 0) fprintf(f, "found lesion %d", k->match + 1);
    else fputs(review_finding_class(k->match), f);
    fputs("</td></tr>\n", f);
  }
  fputs("</table>\n", f);
  if (a.ex.lesion_count) {
    fputs("<table id=\"lesions\"><tr><th>lesion</th><th>diameter [mm]</th><th>depth [mm]</th><th>stiffness x gel</th>"
          "<th>surface x, y, z [mm]</th><th>found by</th></tr>\n", f);
    for (int i = 0; i < a.ex.lesion_count; i++) {
      const palp_exercise_lesion *l = &a.ex.lesion[i];
      const palp_vec3 c = a.lesion_surface[i];
      fprintf(f, "<tr class=\"lesion %s\"><td>%d</td><td>%.1f</td><td>%.1f</td><td>%.1f</td><td>%.1f, %.1f, %.1f</td><td>",
              r->lesion_found[i] >= 0 ? "found" : "missed", i + 1, l->diameter * 1e3, l->depth * 1e3, l->stiffness_ratio,
              c.x * 1e3, c.y * 1e3, c.z * 1e3);
      if (r->lesion_found[i] >= 0) fprintf(f, "mark #%d", r->lesion_found[i] + 1);
      else fputs("missed", f);
      fputs("</td></tr>\n", f);
    }
    fputs("</table>\n", f);
  }
  *keep = a; /* ownership moves to the caller */
}

/* Every touch of the finger (palp_assess_touches): where it came down and lifted on the
 * phantom's surface, its path, deepest indentation and peak force. */
static void touches_table(FILE *f, const review_assessment *a) {
  fprintf(f, "<p>The finger's %d touch%s (a lift is more than %.2f s off the surface), at its contact points on the "
             "phantom's surface:</p>\n<table id=\"touches\"><tr><th>#</th><th>on [s]</th><th>off [s]</th>"
             "<th>down at x, y, z [mm]</th><th>clock</th><th>arc from the pole [mm]</th><th>lifted at clock</th>"
             "<th>arc [mm]</th><th>path [mm]</th><th>deepest [mm]</th><th>peak force [N]</th></tr>\n",
          a->touch_n, a->touch_n == 1 ? "" : "es", PALP_ASSESS_LIFT_GAP_S);
  for (int i = 0; i < a->touch_n; i++) {
    const palp_touch *t = &a->touches[i];
    char down[24], lift[24];
    fprintf(f, "<tr><td>%d</td><td>%.2f</td><td>%.2f</td><td>%.1f, %.1f, %.1f</td><td>%s</td><td>%.1f</td>"
               "<td>%s</td><td>%.1f</td><td>%.1f</td><td>%.1f</td><td>%.2f</td></tr>\n",
            i + 1, t->t_on, t->t_off, t->first_point.x * 1e3, t->first_point.y * 1e3, t->first_point.z * 1e3,
            review_clock_cell(t->first_point, 0, down, sizeof down), review_arc_m(t->first_point) * 1e3,
            review_clock_cell(t->last_point, 0, lift, sizeof lift),
            review_arc_m(t->last_point) * 1e3, t->path_length * 1e3, t->peak_indentation * 1e3, t->peak_force);
  }
  fputs("</table>\n", f);
}

int review_report(palp_log *log, palp_db *db, const palp_db_session_info *s, const char *out_path) {
  /* The phantom's rest mesh from the logged scene. */
  char *scene_json = NULL;
  palp_db_session_json(db, s->id, &scene_json, NULL);
  palp_scene sc;
  char perr[256] = "no scene logged";
  palp_mesh mesh;
  int have_mesh = 0;
  if (scene_json && palp_scene_parse(scene_json, &sc, perr, sizeof perr) == 0)
    have_mesh = palp_mesh_create(&sc.world.mesh, &mesh) == 0;
  else palp_log_warn(log, "report: the logged scene does not parse (%s); drawing without the phantom", perr);
  free(scene_json);

  ts_ctx ts = {0};
  ts.per_bucket = s->frames > PLOT_POINTS ? (s->frames + PLOT_POINTS - 1) / PLOT_POINTS : 1;
  ts.cap = PLOT_POINTS + 1;
  ts.t = malloc(sizeof(double) * (size_t)ts.cap);
  ts.force = malloc(sizeof(double) * (size_t)ts.cap);
  ts.top = malloc(sizeof(double) * (size_t)ts.cap);
  ts.max = malloc(sizeof(double) * (size_t)ts.cap);
  mesh_ctx mc = {have_mesh ? &mesh : NULL, have_mesh ? malloc((size_t)mesh.vertex_count * sizeof(palp_vec3)) : NULL, 0, 0};
  review_contacts in = {0};
  review_press *pr = NULL;
  int np = 0;
  int rc = 0;
  char why[400] = ""; /* the first table of the log the page could not read to its end */
  if (!ts.t || !ts.force || !ts.top || !ts.max || (have_mesh && !mc.best)) rc = PALP_ENOMEM;
  if (!rc) rc = palp_db_each_frame(db, s->id, ts_cb, &ts);
  if (rc == 1) rc = 0; /* the bucket array filled: the last frames share the final point */
  if (!rc && have_mesh) rc = palp_db_each_mesh(db, s->id, mesh_cb, &mc);
  if (!rc) rc = review_load_contacts(db, s->id, &in);
  if (!rc) rc = review_presses(db, s->id, &in, &pr, &np);
  FILE *f = NULL;
  int werr = 0; /* errno of a write that failed: nothing renamed over out_path */
  int open_said = 0; /* the file could not be opened, and that was said: once */
  if (!rc && !(f = review_fopen_out(log, out_path))) {
    if (errno != EINVAL) palp_log_error(log, "report: %s: %s", out_path, strerror(errno)); /* EINVAL: it said why */
    rc = PALP_EIO, open_said = 1;
  }
  if (!rc) {
    fputs("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>palp session ", f);
    html_str(f, s->uid);
    fputs("</title>\n<style>body{font-family:sans-serif;margin:24px;color:#222;max-width:1000px}"
          "table{border-collapse:collapse;margin:8px 0 20px}td,th{border:1px solid #ccc;padding:3px 8px;"
          "text-align:left;font-size:13px}th{background:#f4f4f4}.warn{color:#a00;font-weight:bold}"
          "svg.plot{display:block;margin:8px 0 20px;border:1px solid #ddd}td.fail{color:#a00;font-weight:bold}"
          "td.pass{color:#060}</style>\n</head><body>\n", f);
    fputs("<h1>Palpation session <span id=\"session-uid\">", f);
    html_str(f, s->uid);
    fputs("</span></h1>\n<table id=\"session-info\">\n", f);
    char buf[512], t0[64], t1[64];
    info_row(f, "Trainee", s->trainee);
    info_row(f, "Station", s->station);
    snprintf(buf, sizeof buf, "%s (%s)", s->phantom_id, s->phantom_name);
    info_row(f, "Phantom", buf);
    review_fmt_time(s->start_unix_s, t0, sizeof t0);
    info_row(f, "Started", t0);
    review_fmt_time(s->end_unix_s, t1, sizeof t1);
    snprintf(buf, sizeof buf, "%s (%s%s%s)", s->end_reason[0] ? t1 : "-", s->end_reason[0] ? s->end_reason : "not ended",
             s->end_detail[0] ? ": " : "", s->end_detail);
    info_row(f, "Ended", buf);
    palp_db_log_health health;
    char logging[200];
    review_fmt_logging(s, palp_db_log_health_get(db, s, &health) == 0 ? &health : NULL, logging, sizeof logging);
    char tp[64];
    review_fmt_time(s->pruned_unix_s, tp, sizeof tp);
    if (s->pruned_unix_s > 0) snprintf(buf, sizeof buf, "not known: its frames were pruned on %s", tp);
    else snprintf(buf, sizeof buf, "%.3f s simulated, %s", s->sim_duration_s, logging);
    info_row(f, "Duration", buf);
    fputs("</table>\n", f);
    if (s->pruned_unix_s > 0) {
      fputs("<p class=\"warn\" id=\"pruned\">PRUNED on ", f);
      html_str(f, tp);
      fputs(": this session's frames, feedback, contact inputs, meshes and finger samples were deleted "
            "(palp-review prune). Its plots are empty and it cannot be replayed; its metrics below are the ones "
            "stored when it was pruned.</p>\n", f);
    }
    if (s->records_shed || s->records_failed)
      fprintf(f, "<p class=\"warn\">This log is incomplete: %lld records were shed and %lld lost to disk errors.</p>\n",
              (long long)s->records_shed, (long long)s->records_failed);

    review_assessment a;
    assessment_section(log, db, s, f, &a, why, sizeof why);
    valid_range_section(db, s, f);
    fputs("<h2>Force</h2>\n", f);
    series fs = {"contact force", "#c0392b", ts.t, ts.force, ts.n};
    svg_plot(f, "plot-force", "Contact force over time", "simulated time [s]", "force [N]", &fs, 1);
    fputs("<h2>Displacement</h2>\n", f);
    series ds[2] = {{"top vertex", "#1f77b4", ts.t, ts.top, ts.n}, {"largest, any vertex", "#ff7f0e", ts.t, ts.max, ts.n}};
    svg_plot(f, "plot-displacement", "Displacement over time", "simulated time [s]", "displacement [mm]", ds, 2);

    fputs("<h2>Where the trainee pressed</h2>\n<p>Top view of the phantom (12 o'clock = +y). Circles mark where each "
          "contact started, sized by its peak force; lines follow a finger's path (with its touches logged, blue: a "
          "circle where each touch came down, numbered as the touches table, and its contact points while "
          "touching).</p>\n", f);
    svg_topview(f, have_mesh ? &mesh : NULL, &mc, &in, pr, np, &a);
    fputs("<table id=\"presses\"><tr><th>#</th><th>slot</th><th>kind</th><th>centre x, y, z [mm] (a finger: its device point at the start)</th>"
          "<th>clock</th><th>on [s]</th><th>off [s]</th><th>peak force [N]</th></tr>\n", f);
    for (int p = 0; p < np; p++) {
      const palp_vec3 c = pr[p].first_center_m;
      char clk[24];
      fprintf(f, "<tr><td>%d</td><td>%d</td><td>%s</td><td>%.1f, %.1f, %.1f</td><td>%s</td><td>%.3f</td><td>",
              p + 1, pr[p].slot, pr[p].kind == PALP_DB_KIND_FORCE ? "force" : "finger", c.x * 1e3, c.y * 1e3,
              c.z * 1e3, review_clock_cell(c, 0, clk, sizeof clk), pr[p].t_on_s);
      if (pr[p].t_off_s >= 0) fprintf(f, "%.3f", pr[p].t_off_s);
      else fputs("end", f);
      fprintf(f, "</td><td>%.3f</td></tr>\n", pr[p].peak_force_n);
    }
    fputs("</table>\n", f);
    if (a.touch_n > 0) touches_table(f, &a);
    review_assessment_free(&a);
    fputs("<h2>Events</h2>\n<table id=\"events\"><tr><th>time</th><th>frame</th><th>kind</th>"
          "<th>count</th><th>detail</th></tr>\n", f);
    const int evrc = palp_db_each_event(db, s->id, ev_row, f);
    fputs("</table>\n", f);
    if (evrc) unreadable(f, db, "event", why, sizeof why);
    fputs("<h2>Instructor notes</h2>\n<table id=\"notes\"><tr><th>time</th><th>author</th><th>grade</th>"
          "<th>note</th></tr>\n", f);
    const int nrc = review_each_note(db, s->id, note_row, f); /* each note's grade with its score and level */
    fputs("</table>\n", f);
    if (nrc) unreadable(f, db, "note", why, sizeof why);
    fputs("<p style=\"font-size:11px;color:#777\">Generated by palp-review from the session log.</p>\n"
          "</body></html>\n", f);
    if (review_close_out(f) != 0) werr = errno;
  }
  free(ts.t);
  free(ts.force);
  free(ts.top);
  free(ts.max);
  free(mc.best);
  free(in.v);
  free(pr);
  if (have_mesh) palp_mesh_destroy(&mesh);
  if (werr) {
    palp_log_error(log, "report: %s: %s (not written; a file already there is kept)", out_path, strerror(werr));
    return REVIEW_ERROR;
  }
  if (rc) {
    if (!open_said)
      palp_log_error(log, "report: %s: %s", out_path, rc == PALP_DB_ESQL ? palp_db_errmsg(db) : palp_db_strerror(rc));
    return REVIEW_ERROR;
  }
  if (why[0]) {
    palp_log_error(log, "report: %s written, but %s (the report is incomplete)", out_path, why);
    return REVIEW_ERROR;
  }
  printf("report: wrote %s\n", out_path);
  return REVIEW_OK;
}
