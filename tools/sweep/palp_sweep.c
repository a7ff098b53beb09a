/*
 * palp-sweep - what accuracy costs in time.
 *
 *   palp-sweep [--scene config/paper_step.json] [--distribution uniform]
 *              [--ref-level 2] [--frames N] [--out out/sweep] [--quick]
 *
 * Names never hold commas, so the CSV reads with any splitter.
 * Sweeps the fidelity knobs of the real-time model (mesh resolution, time step,
 * effects, gel law) and of the FEM reference (mesh level) and measures, for each
 * point, the cost (median step time, and wall time per simulated second) and the
 * error against the finest FEM reference run: displacement RMSE over every vertex
 * and frame, total contact-force RMSE per frame, and the Bland-Altman agreement
 * (share of |displacement| differences within bias +- 2 SD). Writes a table (CSV,
 * Markdown) and an SVG plot of error against cost with the Pareto front marked and
 * the server's default configuration circled.
 *
 * Meshes differ between points, so errors are measured on the reference's probe
 * mesh: the FEM is mapped to a 1,300-vertex real-time mesh, every point's vertex is
 * compared with the nearest probe vertex (rest positions), and forces as the total
 * force on the contact, which does not depend on the mesh.
 *
 * These are not palp-eval's quantities under the same names (docs/evaluation.md):
 * the sweep's displacement RMSE is of the vector difference u_point - u_ref over every
 * vertex, the clamped rim included, and its agreement is the Bland-Altman share of the
 * |u| differences over every vertex too; palp-eval's Table V RMSE and agreement are of
 * |u_rt| - |u_FEM| over the free vertices only (the rim's identical zero pairs pad the
 * agreement). The sweep ranks configurations against one reference; its figures are
 * not comparable with palp-eval's tables. The reference row has no error: its RMSEs
 * and agreement are written empty.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "eval_fem.h"
#include "palp.h"
#include "palp_fem.h"
#include "stats.h"
#include "palp_app.h"

#define PROBE_VERTICES 1300

typedef struct point {
  char name[64];
  int fem; /* 0 real-time, 1 FEM */
  int vertices, level;
  double dt;
  double step_median_s;  /* median step (RT) or mean frame (FEM) time [s] */
  double cost;           /* wall time per simulated second [s/s] */
  double disp_rmse;      /* [m] */
  double force_rmse;     /* [N] */
  double agreement;      /* share of |d| differences within bias +- 2 SD */
  int pareto, is_default;
  int failed;            /* the run stopped (why: reason); no cost or error, never on the front */
  char reason[160];
} point;

typedef struct reference {
  int frames, nv;
  palp_vec3 *rest;  /* probe mesh rest positions [nv] */
  palp_vec3 *disp;  /* [frames * nv] */
  double *force;    /* [frames] |total contact force| [N] */
} reference;

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
static int cmpd(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}
static double dist2(palp_vec3 a, palp_vec3 b) {
  return (a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z);
}
static double norm(palp_vec3 a) { return sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

static int progress(void *ud, int frame, int frames, double t) {
  (void)t;
  if (isatty(2)) fprintf(stderr, "\r  %s: frame %d/%d ", (const char *)ud, frame, frames);
  return 0;
}

/* Reference or FEM point: the FE run mapped to the probe mesh. */
static int run_fem(const palp_scene *probe_scene, int level, palp_fem_result *r, char *err, size_t errlen) {
  palp_fem_config cfg;
  /* the profile the scene's parameters answer to (docs/materials.md) */
  if (palp_fem_config_for_scene(probe_scene, &cfg, err, errlen)) return -1;
  cfg.mesh.level = level;
  char label[32];
  snprintf(label, sizeof label, "FEM level %d", level);
  const int e = palp_fem_run(&cfg, probe_scene, r, progress, label, err, errlen);
  if (isatty(2)) fprintf(stderr, "\n");
  return e;
}

static double total_force(const palp_fem_result *r, int f) {
  palp_vec3 s = {0, 0, 0};
  for (int k = 0; k < r->contact_vertex_count; ++k) {
    const palp_vec3 v = r->feedback[(size_t)f * r->contact_vertex_count + k];
    s.x += v.x, s.y += v.y, s.z += v.z;
  }
  return norm(s);
}

/* Errors of a displacement field sampled at `rest` positions against the reference,
 * accumulated over frames; |d| pairs go to a, b for Bland-Altman. */
typedef struct errs {
  double se_disp, se_force;
  size_t n_disp, n_force;
  double *a, *b;
  size_t n, cap;
} errs;

static void add_frame(errs *e, const reference *R, int f, const palp_vec3 *disp, int nv,
                      const int *map, double force) {
  for (int i = 0; i < nv; ++i) {
    const palp_vec3 d = disp[i], r = R->disp[(size_t)f * R->nv + map[i]];
    e->se_disp += dist2(d, r);
    e->n_disp++;
    if (e->n < e->cap) {
      e->a[e->n] = norm(d);
      e->b[e->n] = norm(r);
      e->n++;
    }
  }
  e->se_force += (force - R->force[f]) * (force - R->force[f]);
  e->n_force++;
}

static void finish(errs *e, point *pt) {
  pt->disp_rmse = sqrt(e->se_disp / (double)(e->n_disp ? e->n_disp : 1));
  pt->force_rmse = sqrt(e->se_force / (double)(e->n_force ? e->n_force : 1));
  palp_stats_ba ba;
  pt->agreement = palp_stats_bland_altman(e->a, e->b, e->n, &ba) == PALP_OK ? ba.agreement : NAN;
}

/* Nearest probe vertex of each vertex of a mesh (rest positions); NULL without memory. */
static int *nearest_map(const palp_vec3 *rest, int nv, const reference *R) {
  int *map = malloc(sizeof(int) * (size_t)nv);
  if (!map) return NULL;
  for (int i = 0; i < nv; ++i) {
    double bd = INFINITY;
    for (int j = 0; j < R->nv; ++j) {
      const double d = dist2(rest[i], R->rest[j]);
      if (d < bd) bd = d, map[i] = j;
    }
  }
  return map;
}

/* Marks the point failed (its reason logged and kept for the table): no cost, no error. */
static int fail_point(palp_log *log, point *pt, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int fail_point(palp_log *log, point *pt, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(pt->reason, sizeof pt->reason, fmt, ap);
  va_end(ap);
  pt->failed = 1;
  pt->step_median_s = pt->cost = pt->disp_rmse = pt->force_rmse = pt->agreement = NAN;
  palp_log_error(log, "point \"%s\" failed: %s", pt->name, pt->reason);
  return -1;
}

/* 0, or -1 with the point marked failed: a world that refuses a step or a force is no
 * result (it used to go on "stepping" in ~0 us and could land on the Pareto front). */
static int run_rt(palp_log *log, const palp_scene *s, const reference *R, point *pt) {
  int err;
  palp_world *w = palp_scene_create_world(s, &err);
  if (!w) return fail_point(log, pt, "cannot create the world: %s", palp_strerror(err));
  const palp_mesh *m = palp_world_mesh(w);
  const int nv = m->vertex_count;
  int *map = nearest_map(m->rest, nv, R);
  const int sub = (int)lround(s->frame_period / s->world.dt);
  const long nsteps = (long)R->frames * sub;
  double *st = malloc(sizeof(double) * (size_t)(nsteps > 0 ? nsteps : 1));
  palp_vec3 *disp = malloc(sizeof(palp_vec3) * (size_t)nv);
  errs e = {0};
  e.cap = (size_t)R->frames * (size_t)nv;
  e.a = malloc(sizeof(double) * e.cap);
  e.b = malloc(sizeof(double) * e.cap);
  int rc = 0;
  if (!map || !st || !disp || !e.a || !e.b) rc = fail_point(log, pt, "out of memory (%ld steps, %d vertices)", nsteps, nv);
  long k = 0;
  double wall = 0.0;
  for (int f = 0; !rc && f < R->frames; ++f) {
    for (int q = 0; q < sub; ++q, ++k) {
      /* the step's start on the FE reference's clock (a failed one may leave halves) */
      const double t0 = now_s(), t = palp_scene_step_time(s, f, q);
      err = palp_scene_apply(s, w, t);
      if (err) {
        rc = fail_point(log, pt, "step %ld (from t = %g s): the scene's forces: %s", k, t, palp_strerror(err));
        break;
      }
      err = palp_world_step(w);
      if (err) {
        rc = fail_point(log, pt, "step %ld (from t = %g s): %s", k, t, palp_strerror(err));
        break;
      }
      st[k] = now_s() - t0;
      wall += st[k];
    }
    if (rc) break;
    const palp_vec3 *p = palp_world_positions(w);
    for (int i = 0; i < nv; ++i)
      disp[i] = (palp_vec3){p[i].x - m->rest[i].x, p[i].y - m->rest[i].y, p[i].z - m->rest[i].z};
    palp_vec3 fb = {0, 0, 0};
    for (int c = 0; c < s->contact_count; ++c) {
      palp_vec3 one;
      if (palp_world_contact_feedback(w, c, &one) == PALP_OK) fb.x += one.x, fb.y += one.y, fb.z += one.z;
    }
    add_frame(&e, R, f, disp, nv, map, norm(fb));
  }
  if (!rc && nsteps < 1) rc = fail_point(log, pt, "no steps (%d frames of %d steps)", R->frames, sub);
  if (!rc) {
    qsort(st, (size_t)nsteps, sizeof *st, cmpd);
    pt->step_median_s = st[nsteps / 2];
    pt->cost = wall / (R->frames * s->frame_period);
    finish(&e, pt);
  }
  free(st), free(disp), free(map), free(e.a), free(e.b);
  palp_world_destroy(w);
  return rc;
}

/* Failed points are never on the front, nor keep another point off it. */
static void mark_pareto(point *p, int n) {
  for (int i = 0; i < n; ++i) {
    p[i].pareto = !p[i].failed;
    for (int j = 0; p[i].pareto && j < n; ++j) {
      if (j == i || p[j].failed) continue;
      const int no_worse = p[j].cost <= p[i].cost && p[j].disp_rmse <= p[i].disp_rmse;
      const int better = p[j].cost < p[i].cost || p[j].disp_rmse < p[i].disp_rmse;
      if (no_worse && better) {
        p[i].pareto = 0;
        break;
      }
    }
  }
}

static int cmp_cost(const void *a, const void *b) {
  const point *x = a, *y = b;
  return (x->cost > y->cost) - (x->cost < y->cost);
}

static FILE *write_svg(const char *path, const point *p, int n) {
  FILE *f = fopen(path, "w");
  if (!f) return NULL;
  const double W = 920, H = 520, L = 80, Rm = 190, T = 62, B = 60;
  double xmin = INFINITY, xmax = 0, ymin = INFINITY, ymax = 0;
  for (int i = 0; i < n; ++i) {
    if (p[i].failed) continue;
    xmin = fmin(xmin, p[i].cost), xmax = fmax(xmax, p[i].cost);
    ymin = fmin(ymin, p[i].disp_rmse), ymax = fmax(ymax, p[i].disp_rmse);
  }
  if (!(xmin <= xmax)) xmin = xmax = 1.0, ymin = ymax = 1e-3; /* nothing to plot: empty axes */
  const double lx0 = floor(log10(xmin)), lx1 = ceil(log10(xmax)), ly0 = floor(log10(ymin * 1e3)),
               ly1 = ceil(log10(ymax * 1e3));
#define SX(c) (L + (log10(c) - lx0) / (lx1 - lx0 > 0 ? lx1 - lx0 : 1) * (W - L - Rm))
#define SY(e) (H - B - (log10((e) * 1e3) - ly0) / (ly1 - ly0 > 0 ? ly1 - ly0 : 1) * (H - T - B))
  fprintf(f,
          "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%g\" "
          "height=\"%g\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" "
          "fill=\"white\"/>\n<text x=\"%g\" y=\"20\" font-size=\"15\">What accuracy costs: displacement RMSE against "
          "the finest FEM reference</text>\n<text x=\"%g\" y=\"38\" font-size=\"12\" fill=\"#555\">against "
          "wall time per simulated second, on this machine; labels on the Pareto front and the server "
          "default</text>\n",
          W, H, L, L);
  for (double e = lx0; e <= lx1 + 1e-9; e += 1) {
    const double x = SX(pow(10, e));
    fprintf(f, "<line x1=\"%.1f\" y1=\"%g\" x2=\"%.1f\" y2=\"%g\" stroke=\"#ddd\"/><text x=\"%.1f\" y=\"%g\" "
               "text-anchor=\"middle\">1e%g</text>\n",
            x, T, x, H - B, x, H - B + 18, e);
  }
  for (double e = ly0; e <= ly1 + 1e-9; e += 1) {
    const double y = SY(pow(10, e) * 1e-3);
    fprintf(f, "<line x1=\"%g\" y1=\"%.1f\" x2=\"%g\" y2=\"%.1f\" stroke=\"#ddd\"/><text x=\"%g\" y=\"%.1f\" "
               "text-anchor=\"end\">1e%g</text>\n",
            L, y, W - Rm, y, L - 6, y + 4, e);
  }
  fprintf(f, "<text x=\"%g\" y=\"%g\" text-anchor=\"middle\">cost: wall seconds per simulated second (log)</text>\n",
          (L + W - Rm) / 2, H - 18);
  fprintf(f, "<text x=\"18\" y=\"%g\" transform=\"rotate(-90 18 %g)\" text-anchor=\"middle\">displacement RMSE "
             "[mm] (log)</text>\n",
          (T + H - B) / 2, (T + H - B) / 2);
  /* Pareto front as a line through its points in order of cost. */
  point *sorted = malloc(sizeof(point) * (size_t)(n > 0 ? n : 1));
  if (sorted) {
    memcpy(sorted, p, sizeof(point) * (size_t)n);
    qsort(sorted, (size_t)n, sizeof *sorted, cmp_cost);
    fprintf(f, "<polyline fill=\"none\" stroke=\"#d62728\" stroke-width=\"1.5\" points=\"");
    for (int i = 0; i < n; ++i)
      if (sorted[i].pareto) fprintf(f, "%.1f,%.1f ", SX(sorted[i].cost), SY(sorted[i].disp_rmse));
    fprintf(f, "\"/>\n");
    free(sorted);
  }
  int labelled = 0;
  for (int i = 0; i < n; ++i) {
    if (p[i].failed) continue; /* no cost, no error: listed as failed in the table */
    const double x = SX(p[i].cost), y = SY(p[i].disp_rmse);
    fprintf(f, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"%s\"/>\n", x, y, p[i].fem ? "#1f77b4" : "#2ca02c");
    if (p[i].is_default)
      fprintf(f, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"9\" fill=\"none\" stroke=\"black\" stroke-width=\"1.5\"/>\n", x,
              y);
    if (p[i].pareto || p[i].is_default) {
      /* Stagger labels of nearby points above and below, with a leader line. */
      const double dy = (labelled++ % 2) ? 22.0 + 12.0 * (labelled % 3) : -(10.0 + 12.0 * (labelled % 3));
      fprintf(f, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\" stroke-width=\"0.6\"/>"
                 "<text x=\"%.1f\" y=\"%.1f\" font-size=\"10\">%s%s</text>\n",
              x, y, x + 4, y + dy - 3, x + 5, y + dy, p[i].name, p[i].is_default ? " (server default)" : "");
    }
  }
  const double lx = W - Rm + 14;
  fprintf(f,
          "<g font-size=\"11\"><text x=\"%g\" y=\"%g\" fill=\"#2ca02c\">&#9679; real-time model</text>"
          "<text x=\"%g\" y=\"%g\" fill=\"#1f77b4\">&#9679; FEM (coarser levels)</text>"
          "<text x=\"%g\" y=\"%g\" fill=\"#d62728\">&#8212; Pareto front</text>"
          "<text x=\"%g\" y=\"%g\">&#9711; server default</text></g>\n</svg>\n",
          lx, T + 12, lx, T + 28, lx, T + 44, lx, T + 60);
#undef SX
#undef SY
  return f; /* closed and checked by the caller */
}

static void print_point(const point *p) {
  if (p->failed) printf("  %-28s FAILED: %s\n", p->name, p->reason);
  else
    printf("  %-28s cost %.4f s/s, step %.1f us, displacement RMSE %.3f mm, force RMSE %.3f N\n", p->name, p->cost,
           1e6 * p->step_median_s, 1e3 * p->disp_rmse, p->force_rmse);
  fflush(stdout);
}

#define SWEEP_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_LOG | PALP_APP_OPT_VERBOSE)

/* The whole string an integer in [lo, hi]: atoi read "2x" as 2 and "abc" as 0 (all frames)
 * until session 82. */
static int parse_int(const char *opt, const char *v, int lo, int hi, int *out) {
  char *end = NULL;
  errno = 0;
  const long x = v ? strtol(v, &end, 10) : 0;
  if (!v || !*v || *end || errno || x < lo || x > hi) {
    fprintf(stderr, "palp-sweep: %s expects an integer from %d to %d, got \"%s\"\n", opt, lo, hi, v ? v : "");
    return -1;
  }
  *out = (int)x;
  return 0;
}

/* A written file's stream closed, its errors reported: a full disk used to leave a truncated
 * sweep.csv or sweep.md (fclose unchecked) and no sweep.svg (fopen unchecked) with exit 0. */
static int close_checked(palp_log *log, FILE *f, const char *path) {
  int bad = ferror(f);
  bad |= fclose(f) != 0;
  if (bad) palp_log_error(log, "cannot write %s", path);
  return bad ? -1 : 0;
}

static void usage(FILE *f) {
  fprintf(f, "usage: palp-sweep [--scene FILE] [--distribution single|uniform|gaussian|gaussian_offset]\n"
                  "                  [--ref-level N] [--frames N] [--out DIR] [--quick] [--version]\n"
                  "--scene defaults to config/paper_step.json if that exists here, else the installed one\n"
                  "(<data>/config/paper_step.json).\n");
  palp_app_common_usage(f, SWEEP_OPTS);
}

int main(int argc, char **argv) {
  palp_app_opts ao;
  palp_app_opts_init(&ao, "palp-sweep");
  static const char default_scene[] = "config/paper_step.json";
  const char *scene_path = default_scene, *out = "out/sweep", *dist = "uniform";
  int ref_level = 2, frames = 0, quick = 0;
  for (int i = 1; i < argc; ++i) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    const int common = palp_app_common_opt(&ao, SWEEP_OPTS, argc, argv, &i);
    if (common < 0) return 2;
    if (common) continue;
    const int valued = !strcmp(a, "--scene") || !strcmp(a, "--distribution") || !strcmp(a, "--ref-level") ||
                       !strcmp(a, "--frames") || !strcmp(a, "--out");
    if (valued && !v) {
      fprintf(stderr, "palp-sweep: %s needs a value\n", a);
      return usage(stderr), 2;
    }
    if (!strcmp(a, "--scene")) scene_path = v, ++i;
    else if (!strcmp(a, "--distribution")) dist = v, ++i;
    else if (!strcmp(a, "--ref-level")) {
      if (parse_int(a, v, 1, 6, &ref_level)) return usage(stderr), 2;
      ++i;
    } else if (!strcmp(a, "--frames")) {
      if (parse_int(a, v, 1, 100000000, &frames)) return usage(stderr), 2;
      ++i;
    } else if (!strcmp(a, "--out")) out = v, ++i;
    else if (!strcmp(a, "--quick")) quick = 1;
    else if (!strcmp(a, "--help") || !strcmp(a, "-h")) return usage(stdout), 0;
    else {
      fprintf(stderr, "palp-sweep: unknown option \"%s\"\n", a);
      return usage(stderr), 2;
    }
  }
  if (ao.version) {
    palp_app_print_version(stdout, "palp-sweep");
    return 0;
  }
  /* Every line is flushed as it is written, so the early returns below lose nothing. */
  palp_log log;
  if (palp_log_init(&log, "palp-sweep", ao.log_level, ao.log_file) < 0) {
    fprintf(stderr, "palp-sweep: --log-file %s: cannot open it: %s\n", ao.log_file, strerror(errno));
    return 2;
  }
  char installed_scene[1024], derr[512];
  if (scene_path == default_scene && access(default_scene, R_OK) != 0) {
    if (palp_app_data_path(default_scene, installed_scene, sizeof installed_scene, derr, sizeof derr) < 0) {
      palp_log_error(&log, "no %s here and %s; give --scene FILE", default_scene, derr);
      return 2;
    }
    scene_path = installed_scene;
  }
  palp_scene s;
  char err[512];
  /* an unusable input is exit 1 (a command-line error is 2), as in palp-eval; the loader's
   * message names the file already */
  if (palp_scene_load(scene_path, &s, err, sizeof err)) {
    if (strstr(err, scene_path)) palp_log_error(&log, "%s", err);
    else palp_log_error(&log, "%s: %s", scene_path, err);
    return 1;
  }
  const char *names[] = {"single", "uniform", "gaussian", "gaussian_offset"};
  int d = 0;
  for (int i = 0; i < 4; ++i)
    if (!strcmp(dist, names[i])) d = i + 1;
  if (!d || s.contact_count < 1) {
    palp_log_error(&log, "unknown distribution \"%s\" or a scene without contacts", dist);
    return 2;
  }
  s.contact[0].def.distribution = (palp_distribution)d;
  if (frames > 0) s.frames = frames;
  if (mkdir(out, 0755) && errno != EEXIST) {
    palp_log_error(&log, "cannot create %s: %s", out, strerror(errno));
    return 1;
  }

  /* The reference: the finest FEM level asked for, mapped to the probe mesh. */
  palp_scene probe = s;
  probe.world.mesh.vertex_count = PROBE_VERTICES;
  palp_fem_result ref;
  printf("palp-sweep: scene %s, distribution %s, %d frames; reference FEM level %d on a %d-vertex probe mesh\n",
         scene_path, dist, s.frames, ref_level, PROBE_VERTICES);
  fflush(stdout);
  if (run_fem(&probe, ref_level, &ref, err, sizeof err)) {
    palp_log_error(&log, "reference FEM failed: %s", err);
    return 1;
  }
  reference R = {.frames = ref.frames, .nv = ref.vertex_count};
  palp_mesh pm;
  const int mrc = palp_mesh_create(&probe.world.mesh, &pm);
  if (mrc) {
    palp_log_error(&log, "the %d-vertex probe mesh: %s", PROBE_VERTICES, palp_strerror(mrc));
    palp_fem_result_destroy(&ref);
    return 1;
  }
  R.rest = pm.rest;
  R.disp = ref.disp;
  R.force = malloc(sizeof(double) * (size_t)(R.frames > 0 ? R.frames : 1));
  if (!R.force) {
    palp_log_error(&log, "out of memory");
    palp_mesh_destroy(&pm);
    palp_fem_result_destroy(&ref);
    return 1;
  }
  for (int f = 0; f < R.frames; ++f) R.force[f] = total_force(&ref, f);

  point pts[40];
  int n = 0;
  /* Real-time model: mesh x step with every effect of the scene on. */
  const int vcounts[] = {100, 338, 1300, 5000};
  const double dts[] = {0.01, 0.005, 0.002, 0.001};
  const int nvc = quick ? 2 : 4, ndt = quick ? 2 : 4;
  for (int a = 0; a < nvc; ++a)
    for (int b = 0; b < ndt; ++b) {
      if (vcounts[a] == 5000 && dts[b] < 0.005) continue; /* minutes per point; the trend is clear without */
      palp_scene q = s;
      q.world.mesh.vertex_count = vcounts[a];
      q.world.dt = quick && b ? 0.002 : dts[b];
      point *p = &pts[n];
      memset(p, 0, sizeof *p);
      snprintf(p->name, sizeof p->name, "RT %d v %g ms", vcounts[a], 1e3 * q.world.dt);
      p->vertices = vcounts[a], p->dt = q.world.dt;
      p->is_default = vcounts[a] == 338 && fabs(q.world.dt - 0.01) < 1e-12;
      run_rt(&log, &q, &R, p);
      print_point(p);
      n++;
    }
  /* Effects and gel law at the default mesh and step. */
  struct {
    const char *name;
    uint32_t off;
    int literal;
  } fx[] = {{"RT 338 v no viscosity", PALP_EFFECT_MEMBRANE_VISCOSITY | PALP_EFFECT_GEL_DAMPING, 0},
            {"RT 338 v no gel support", PALP_EFFECT_GEL_SUPPORT, 0},
            {"RT 338 v no gel pressure", PALP_EFFECT_GEL_PRESSURE, 0},
            {"RT 338 v literal Eq. 3", 0, 1}};
  for (size_t k = 0; k < (quick ? 1 : sizeof fx / sizeof *fx); ++k) {
    palp_scene q = s;
    q.world.mesh.vertex_count = 338;
    q.world.effects &= ~fx[k].off;
    if (!(q.world.effects & (PALP_EFFECT_GEL_PRESSURE | PALP_EFFECT_GEL_SUPPORT)))
      q.world.effects &= ~(uint32_t)PALP_EFFECT_GEL_DAMPING;
    if (fx[k].literal) q.world.gel.law = PALP_GEL_PAPER_LITERAL, q.world.gel.a3 = 0.0;
    point *p = &pts[n];
    memset(p, 0, sizeof *p);
    snprintf(p->name, sizeof p->name, "%s", fx[k].name);
    p->vertices = 338, p->dt = q.world.dt;
    run_rt(&log, &q, &R, p);
    print_point(p);
    n++;
  }
  /* The FEM's own fidelity: coarser levels against the finest. */
  for (int level = 1; level < ref_level; ++level) {
    palp_fem_result r;
    point *p = &pts[n++];
    memset(p, 0, sizeof *p);
    p->fem = 1, p->level = level, p->vertices = PROBE_VERTICES;
    if (run_fem(&probe, level, &r, err, sizeof err)) {
      snprintf(p->name, sizeof p->name, "FEM level %d", level);
      fail_point(&log, p, "%s", err);
      print_point(p);
      continue;
    }
    snprintf(p->name, sizeof p->name, "FEM level %d (%d hex)", level, r.element_count);
    errs e = {0};
    e.cap = (size_t)R.frames * (size_t)R.nv;
    e.a = malloc(sizeof(double) * e.cap);
    e.b = malloc(sizeof(double) * e.cap);
    int *id = malloc(sizeof(int) * (size_t)R.nv);
    if (!e.a || !e.b || !id) fail_point(&log, p, "out of memory");
    else {
      p->step_median_s = r.wall_seconds / r.frames;
      p->cost = r.wall_seconds / (r.frames * s.frame_period);
      for (int i = 0; i < R.nv; ++i) id[i] = i;
      for (int f = 0; f < R.frames; ++f)
        add_frame(&e, &R, f, r.disp + (size_t)f * r.vertex_count, r.vertex_count, id, total_force(&r, f));
      finish(&e, p);
    }
    free(id), free(e.a), free(e.b);
    palp_fem_result_destroy(&r);
    if (p->failed) print_point(p);
    else
      printf("  %-28s cost %.4f s/s, frame %.3f s, displacement RMSE %.3f mm, force RMSE %.3f N\n", p->name, p->cost,
             p->step_median_s, 1e3 * p->disp_rmse, p->force_rmse);
  }
  /* The reference itself: zero error by construction, its cost for the plot's scale. */
  {
    point *p = &pts[n++];
    memset(p, 0, sizeof *p);
    snprintf(p->name, sizeof p->name, "FEM level %d (reference)", ref_level);
    p->fem = 1, p->level = ref_level, p->vertices = PROBE_VERTICES;
    p->step_median_s = ref.wall_seconds / ref.frames;
    p->cost = ref.wall_seconds / (ref.frames * s.frame_period);
    /* no error against itself: NaN, written empty (the memset's 0 wrote force_rmse 0 and
     * agreement 0.0000 until session 82, read as a perfect force and no agreement) */
    p->disp_rmse = p->force_rmse = p->agreement = NAN;
  }
  /* The reference has no error to plot: leave it out of the front and the plot. */
  const int nplot = n - 1;
  mark_pareto(pts, nplot);

  char path[1024], csv_path[1024], md_path[1024];
  snprintf(csv_path, sizeof csv_path, "%s/sweep.csv", out);
  FILE *csv = fopen(csv_path, "w");
  snprintf(md_path, sizeof md_path, "%s/sweep.md", out);
  FILE *md = fopen(md_path, "w");
  if (!csv || !md) {
    palp_log_error(&log, "cannot write %s: %s", !csv ? csv_path : md_path, strerror(errno));
    if (csv) fclose(csv);
    if (md) fclose(md);
    return 1;
  }
  fprintf(csv, "name,model,vertices,fem_level,dt_s,step_or_frame_s,cost_s_per_sim_s,disp_rmse_m,force_rmse_N,"
               "agreement,pareto,server_default,failed\n");
  fprintf(md, "| point | cost [s per simulated s] | step or frame | displacement RMSE [mm] | force RMSE [N] | "
              "agreement | Pareto |\n|---|---|---|---|---|---|---|\n");
  for (int i = 0; i < n; ++i) {
    const point *p = &pts[i];
    if (i < nplot || p->failed)
      fprintf(csv, "\"%s\",%s,%d,%d,%g,%.6g,%.6g,%.6g,%.6g,%.4f,%d,%d,%d\n", p->name, p->fem ? "fem" : "rt",
              p->vertices, p->level, p->dt, p->step_median_s, p->cost, p->disp_rmse, p->force_rmse, p->agreement,
              p->pareto, p->is_default, p->failed);
    else /* the reference: no error against itself, so its error columns are empty */
      fprintf(csv, "\"%s\",%s,%d,%d,%g,%.6g,%.6g,,,,%d,%d,%d\n", p->name, p->fem ? "fem" : "rt", p->vertices, p->level,
              p->dt, p->step_median_s, p->cost, p->pareto, p->is_default, p->failed);
    if (p->failed)
      fprintf(md, "| %s%s | failed: %s | | | | | |\n", p->name, p->is_default ? " **(server default)**" : "", p->reason);
    else if (i < nplot)
      fprintf(md, "| %s%s | %.4f | %s%.4g %s | %.3f | %.3f | %.1f%% | %s |\n", p->name,
              p->is_default ? " **(server default)**" : "", p->cost, "", p->fem ? p->step_median_s : 1e6 * p->step_median_s,
              p->fem ? "s/frame" : "us/step", 1e3 * p->disp_rmse, p->force_rmse, 100 * p->agreement,
              p->pareto ? "yes" : "");
    else
      fprintf(md, "| %s | %.4f | %.4g s/frame | (reference) | | | |\n", p->name, p->cost, p->step_median_s);
  }
  int wbad = close_checked(&log, csv, csv_path);
  wbad |= close_checked(&log, md, md_path);
  snprintf(path, sizeof path, "%s/sweep.svg", out);
  FILE *svg = write_svg(path, pts, nplot);
  if (!svg) {
    palp_log_error(&log, "cannot write %s: %s", path, strerror(errno));
    wbad = -1;
  } else
    wbad |= close_checked(&log, svg, path);
  if (wbad) {
    free(R.force);
    palp_mesh_destroy(&pm);
    palp_fem_result_destroy(&ref);
    return 1;
  }
  int front = 0, failed = 0;
  for (int i = 0; i < nplot; ++i) front += pts[i].pareto, failed += pts[i].failed;
  printf("wrote %s/sweep.csv, sweep.md, sweep.svg (%d points, %d on the Pareto front)\n", out, n, front);
  free(R.force);
  palp_mesh_destroy(&pm);
  palp_fem_result_destroy(&ref);
  /* The table is written either way (the failed rows say why); the exit says it is incomplete. */
  if (failed) {
    palp_log_error(&log, "%d of %d points failed (marked in the table, never on the Pareto front)", failed, nplot);
    return 1;
  }
  return 0;
}
