/*
 * palp-eval - the paper's evaluation (Tables V and VI) and the calibration of the
 * real-time parameters against the FEM reference.
 *
 *   palp-eval evaluate  [--scene FILE] [--level N] [--out DIR] [--fem-config FILE]
 *   palp-eval calibrate [--scene FILE] [--level N] [--out FILE] [--fem-config FILE]
 *
 * See docs/evaluation.md. Exit status: 0 done (also when the paper's criteria are
 * not met: that is a result), 1 the inputs cannot be used or a run failed, 2 the
 * command line is wrong.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include <cjson/cJSON.h>
#include <gsl/gsl_errno.h>
#include <limits.h>
#include <unistd.h>

#include "eval.h"
#include "eval_fem.h"
#include "svg_plot.h"
#include "palp_app.h"


typedef struct options {
  const char *cmd;
  const char *scene;
  const char *out;
  const char *fem_config;
  const char *material;
  const char *params;
  const char *cache_dir;
  const char *fit;
  const char *distributions;
  int level; /* 0: the FEM config's */
  int frames;
  int quiet;
  int plots;
  int frame_stride, vertex_stride, max_iter;
  double max_minutes;
  double force_weight, prior_weight, recovery_weight, bias_weight, bound;
  int recovery_auto;
  palp_app_opts app;
  palp_log *log; /* main's, once the options are read */
} options;

/* --quiet already means "no progress lines" here, so only --log-level/--log-file. */
#define EVAL_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_LOG)

static void usage(FILE *f) {
  fprintf(f,
          "usage: palp-eval evaluate  [--scene FILE] [--params FILE] [--level N] [--out DIR] [--fem-config FILE]\n"
          "                           [--material paper_long_term|paper_instantaneous|breast_tissue]\n"
          "                           [--frames N] [--distributions 1,2,3,4] [--cache-dir DIR] [--no-plots] [--quiet]\n"
          "       palp-eval calibrate [--scene FILE] [--params FILE] [--level N] [--out FILE] [--fem-config FILE]\n"
          "                           [--material paper_long_term|paper_instantaneous|breast_tissue]\n"
          "                           [--fit all|E1,eta1,E2,eta2,a1,a2,support_modulus,support_viscosity,added_mass,support_bulk_fraction]\n"
          "                           [--frame-stride K] [--vertex-stride K] [--force-weight W]\n"
          "                           [--prior-weight CM] [--bias-weight W] [--recovery auto|off|CM]\n"
          "                           [--bound B] [--max-iter N] [--max-minutes M]\n"
          "                           [--frames N] [--cache-dir DIR] [--quiet]\n"
          "defaults: --scene config/paper_step.json, --out out/eval (evaluate) or\n"
          "          config/params/calibrated.json (calibrate), --level from the FEM config (2)\n");
  palp_app_common_usage(f, EVAL_OPTS);
}

static int parse_int(const char *opt, const char *v, int lo, int hi, int *out) {
  char *end = NULL;
  errno = 0;
  long x = v ? strtol(v, &end, 10) : 0;
  if (!v || !*v || *end || errno || x < lo || x > hi) {
    fprintf(stderr, "palp-eval: %s expects an integer from %d to %d, got \"%s\"\n", opt, lo, hi, v ? v : "");
    return -1;
  }
  *out = (int)x;
  return 0;
}

static int parse_double(const char *opt, const char *v, double lo, double *out) {
  char *end = NULL;
  double x = v ? strtod(v, &end) : NAN;
  if (!v || !*v || *end || !isfinite(x) || x < lo) {
    fprintf(stderr, "palp-eval: %s expects a number >= %g, got \"%s\"\n", opt, lo, v ? v : "");
    return -1;
  }
  *out = x;
  return 0;
}

static int parse_args(int argc, char **argv, options *o) {
  memset(o, 0, sizeof *o);
  o->plots = 1;
  o->frame_stride = 2;
  o->vertex_stride = 1;
  o->max_iter = 40;
  o->prior_weight = 1e-3;
  o->bias_weight = 0.0;
  o->bound = 100.0;
  o->recovery_auto = 1;
  palp_app_opts_init(&o->app, "palp-eval");
  if (argc < 2) return -1;
  o->cmd = argv[1];
  if (!strcmp(o->cmd, "-h") || !strcmp(o->cmd, "--help")) {
    usage(stdout);
    exit(0);
  }
  if (strcmp(o->cmd, "evaluate") && strcmp(o->cmd, "calibrate")) {
    fprintf(stderr, "palp-eval: unknown command \"%s\" (evaluate, calibrate)\n", o->cmd);
    return -1;
  }
  for (int i = 2; i < argc; ++i) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    int takes = 1, bad = 0;
    const int common = palp_app_common_opt(&o->app, EVAL_OPTS, argc, argv, &i);
    if (common < 0) return -1;
    if (common) continue;
    if (!strcmp(a, "--scene")) o->scene = v;
    else if (!strcmp(a, "--out")) o->out = v;
    else if (!strcmp(a, "--fem-config")) o->fem_config = v;
    else if (!strcmp(a, "--material")) o->material = v;
    else if (!strcmp(a, "--params")) o->params = v;
    else if (!strcmp(a, "--cache-dir")) o->cache_dir = v;
    else if (!strcmp(a, "--fit")) o->fit = v;
    else if (!strcmp(a, "--distributions")) o->distributions = v;
    else if (!strcmp(a, "--level")) bad = parse_int(a, v, 1, 64, &o->level);
    else if (!strcmp(a, "--frames")) bad = parse_int(a, v, 2, 1000000, &o->frames);
    else if (!strcmp(a, "--frame-stride")) bad = parse_int(a, v, 1, 1000, &o->frame_stride);
    else if (!strcmp(a, "--vertex-stride")) bad = parse_int(a, v, 1, 1000, &o->vertex_stride);
    else if (!strcmp(a, "--max-iter")) bad = parse_int(a, v, 1, 10000, &o->max_iter);
    else if (!strcmp(a, "--force-weight")) bad = parse_double(a, v, 0.0, &o->force_weight);
    else if (!strcmp(a, "--bound")) bad = parse_double(a, v, 0.0, &o->bound);
    else if (!strcmp(a, "--bias-weight")) bad = parse_double(a, v, 0.0, &o->bias_weight);
    else if (!strcmp(a, "--max-minutes")) bad = parse_double(a, v, 0.0, &o->max_minutes);
    else if (!strcmp(a, "--prior-weight")) bad = parse_double(a, v, 0.0, &o->prior_weight);
    else if (!strcmp(a, "--recovery")) {
      if (v && !strcmp(v, "auto")) o->recovery_auto = 1, o->recovery_weight = 0;
      else if (v && !strcmp(v, "off")) o->recovery_auto = 0, o->recovery_weight = 0;
      else {
        o->recovery_auto = 0;
        bad = parse_double(a, v, 0.0, &o->recovery_weight);
      }
    } else if (!strcmp(a, "--quiet")) o->quiet = 1, takes = 0;
    else if (!strcmp(a, "--no-plots")) o->plots = 0, takes = 0;
    else if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
      usage(stdout);
      exit(0);
    } else {
      fprintf(stderr, "palp-eval: unknown option \"%s\"\n", a);
      return -1;
    }
    if (bad) return -1;
    if (takes) {
      if (!v) {
        fprintf(stderr, "palp-eval: %s needs a value\n", a);
        return -1;
      }
      ++i;
    }
  }
  return 0;
}

static int file_exists(const char *p) {
  struct stat st;
  return stat(p, &st) == 0 && S_ISREG(st.st_mode);
}

/* mkdir -p */
static int make_dirs(const char *path) {
  char buf[1024];
  snprintf(buf, sizeof buf, "%s", path);
  for (char *p = buf + 1; *p; ++p)
    if (*p == '/') {
      *p = 0;
      if (mkdir(buf, 0777) && errno != EEXIST) return -1;
      *p = '/';
    }
  if (mkdir(buf, 0777) && errno != EEXIST) return -1;
  struct stat st;
  return (stat(buf, &st) == 0 && S_ISDIR(st.st_mode)) ? 0 : -1;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The scene with its "parameters" entry pointing at another parameter file
 * (--params): the scene's JSON with that one key replaced, loaded through
 * palp_scene_load so the file is read and checked exactly as scenes read it.
 * Returns -100 when the parameter file itself is missing. */
static int load_with_params(const char *scene_path, const char *params, palp_scene *out, char *err, size_t errlen) {
  if (!file_exists(params)) {
    snprintf(err, errlen, "parameter file not found");
    return -100;
  }
  /* absolute, because the scene resolves "parameters" relative to itself */
  char abs_params[PATH_MAX], cwd[PATH_MAX];
  size_t lp = strlen(params), lc = 0;
  if (params[0] != '/') {
    if (!getcwd(cwd, sizeof cwd)) cwd[0] = 0;
    lc = strlen(cwd);
  }
  if ((params[0] != '/' && lc == 0) || lc + lp + 2 > sizeof abs_params) {
    snprintf(err, errlen, "cannot resolve the parameter file's path");
    return -100;
  }
  if (lc) {
    memcpy(abs_params, cwd, lc);
    abs_params[lc] = '/';
    memcpy(abs_params + lc + 1, params, lp + 1);
  } else
    memcpy(abs_params, params, lp + 1);
  FILE *f = fopen(scene_path, "rb");
  if (!f) {
    snprintf(err, errlen, "cannot read the scene");
    return PALP_EIO;
  }
  fseek(f, 0, SEEK_END);
  long len = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *txt = len >= 0 ? malloc((size_t)len + 1) : NULL;
  size_t got = txt ? fread(txt, 1, (size_t)len, f) : 0;
  fclose(f);
  if (!txt || got != (size_t)len) {
    free(txt);
    snprintf(err, errlen, "cannot read the scene");
    return PALP_EIO;
  }
  txt[len] = 0;
  cJSON *root = cJSON_Parse(txt);
  free(txt);
  if (!root || !cJSON_IsObject(root)) {
    cJSON_Delete(root);
    /* let the scene loader say what is wrong with it */
    return palp_scene_load(scene_path, out, err, errlen);
  }
  cJSON_DeleteItemFromObjectCaseSensitive(root, "parameters");
  cJSON_AddStringToObject(root, "parameters", abs_params);
  char *json = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  char tmp[] = "/tmp/palp_eval_scene_XXXXXX";
  int fd = json ? mkstemp(tmp) : -1;
  FILE *t = fd >= 0 ? fdopen(fd, "w") : NULL;
  int rc = PALP_EIO;
  if (t) {
    fputs(json, t);
    rc = fclose(t) == 0 ? palp_scene_load(tmp, out, err, errlen) : PALP_EIO;
    remove(tmp);
  } else if (fd >= 0)
    close(fd);
  if (rc == PALP_EIO && !err[0]) snprintf(err, errlen, "cannot write a temporary scene");
  free(json);
  return rc;
}

/* ---- shared set-up: scene, FEM configuration, references -------------------------------- */

typedef struct setup {
  char scene_path[512];
  palp_scene scene;
  palp_fem_config fem;
  int dist[4];
  int dist_count;
  palp_log *log;
} setup;

static int load_setup(const options *o, setup *s) {
  memset(s, 0, sizeof *s);
  s->log = o->log;
  if (o->scene) snprintf(s->scene_path, sizeof s->scene_path, "%s", o->scene);
  else if (file_exists("config/paper_step.json")) snprintf(s->scene_path, sizeof s->scene_path, "config/paper_step.json");
  else {
    /* The installed scene (app/palp_app.h): no source path is compiled in. */
    char err[256];
    if (palp_app_data_path("config/paper_step.json", s->scene_path, sizeof s->scene_path, err, sizeof err) < 0)
      snprintf(s->scene_path, sizeof s->scene_path, "config/paper_step.json");
  }
  char err[512] = "";
  if (!file_exists(s->scene_path)) {
    palp_log_error(o->log, "scene file \"%s\" not found", s->scene_path);
    return 1;
  }
  int rc = o->params ? load_with_params(s->scene_path, o->params, &s->scene, err, sizeof err)
                     : palp_scene_load(s->scene_path, &s->scene, err, sizeof err);
  if (rc) {
    palp_log_error(o->log, "%s: %s", rc == -100 ? o->params : s->scene_path, err);
    return 1;
  }
  if (s->scene.contact_count < 1) {
    palp_log_error(o->log, "%s: the scene has no contact; the evaluation loads contacts[0] under the four "
                           "distributions",
            s->scene_path);
    return 1;
  }
  if (o->frames) s->scene.frames = o->frames;
  s->fem = palp_fem_default_config();
  if (o->fem_config) {
    if (!file_exists(o->fem_config)) {
      palp_log_error(o->log, "FEM config \"%s\" not found", o->fem_config);
      return 1;
    }
    rc = palp_fem_config_load(o->fem_config, &s->fem, err, sizeof err);
    if (rc) {
      palp_log_error(o->log, "%s: %s", o->fem_config, err);
      return 1;
    }
  }
  if (o->material && palp_fem_config_set_material(&s->fem, o->material, err, sizeof err)) {
    palp_log_error(o->log, "--material: %s", err);
    return 1;
  }
  if (o->level) s->fem.mesh.level = o->level;
  if (o->cache_dir) snprintf(s->fem.cache_dir, sizeof s->fem.cache_dir, "%s", o->cache_dir);
  rc = palp_fem_config_validate(&s->fem, err, sizeof err);
  if (rc) {
    palp_log_error(o->log, "FEM configuration: %s", err);
    return 1;
  }
  if (o->distributions && strcmp(o->distributions, "all")) {
    for (const char *p = o->distributions; *p; ++p) {
      if (*p == ',') continue;
      if (*p < '1' || *p > '4' || (p[1] && p[1] != ',') || s->dist_count == 4) {
        palp_log_error(o->log, "--distributions expects a list of 1..4 (e.g. 1,3) or all, got \"%s\"",
                o->distributions);
        return 2;
      }
      s->dist[s->dist_count++] = *p - '0';
    }
  } else
    for (int d = 1; d <= 4; ++d) s->dist[s->dist_count++] = d;
  return 0;
}

typedef struct progress {
  int quiet, distribution;
  double t0;
  int last_pct;
  palp_log *log;
} progress;

static int fem_progress(void *ud, int frame, int frames, double sim_time) {
  progress *p = ud;
  if (p->quiet || frames <= 0) return 0;
  const int pct = (int)(100.0 * frame / frames);
  if (pct / 10 != p->last_pct / 10 || frame == frames) {
    p->last_pct = pct;
    palp_log_info(p->log, "FEM distribution %s: frame %d/%d (t = %.2f s), %.0f s elapsed",
            palp_eval_roman(p->distribution), frame, frames, sim_time, now_s() - p->t0);
  }
  return 0;
}

/* The FEM reference of one distribution as a record (from the cache when unchanged). */
static int reference(const setup *s, const palp_scene *sd, int quiet, palp_eval_record *out, palp_fem_result *info) {
  char err[512] = "";
  progress pr = {.quiet = quiet, .distribution = (int)sd->contact[0].def.distribution, .t0 = now_s(), .last_pct = -10,
                 .log = s->log};
  palp_fem_result fr;
  memset(&fr, 0, sizeof fr);
  int rc = palp_fem_run(&s->fem, sd, &fr, fem_progress, &pr, err, sizeof err);
  if (rc) {
    palp_log_error(s->log, "FEM reference, distribution %s: %s", palp_eval_roman(pr.distribution),
                   err[0] ? err : palp_strerror(rc));
    return 1;
  }
  rc = palp_eval_record_from_fem(&fr, sd, out, err, sizeof err);
  if (rc) palp_log_error(s->log, "FEM reference, distribution %s: %s", palp_eval_roman(pr.distribution), err);
  if (info) {
    *info = fr;
    /* keep the statistics only */
    info->time = NULL, info->disp = NULL, info->top_disp = NULL, info->contact_vertex = NULL;
    info->contact_of = NULL, info->feedback = NULL;
  }
  palp_fem_result_destroy(&fr);
  return rc ? 1 : 0;
}

/* ---- evaluate ----------------------------------------------------------------------------- */

static int write_pairs_csv(const char *path, const palp_eval_pairs *p, const palp_eval_record *rt, int force) {
  FILE *f = fopen(path, "w");
  if (!f) return -1;
  const size_t n = force ? p->n_force : p->n_disp;
  const double *a = force ? p->force_rt : p->disp_rt, *b = force ? p->force_ref : p->disp_ref;
  const int *fr = force ? p->force_frame : p->disp_frame, *vx = force ? p->force_vertex : p->disp_vertex;
  fprintf(f, force ? "frame,time_s,vertex,rt_N,fem_N\n" : "frame,time_s,vertex,rt_cm,fem_cm\n");
  for (size_t i = 0; i < n; ++i) fprintf(f, "%d,%.6f,%d,%.17g,%.17g\n", fr[i], rt->time[fr[i]], vx[i], a[i], b[i]);
  int bad = ferror(f);
  bad |= fclose(f) != 0;
  return bad ? -1 : 0;
}

static double vnorm(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

static int write_plots(palp_log *log, const char *dir, int d, const palp_eval_record *rt, const palp_eval_record *ref,
                       const palp_eval_pairs *p, const palp_eval_dist *row) {
  char path[1100], title[160], err[256];
  const int nf = rt->frames, nv = rt->vertex_count;
  double *t = malloc(sizeof(double) * (size_t)nf), *ya = malloc(sizeof(double) * (size_t)nf),
         *yb = malloc(sizeof(double) * (size_t)nf);
  if (!t || !ya || !yb) {
    free(t), free(ya), free(yb);
    return -1;
  }
  int rc = 0;
  /* the top vertex (the paper's Sec. II-C trace) and the most displaced vertex of the reference */
  int peak_v = rt->top_vertex;
  double peak = -1;
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < nv; ++i) {
      const double u = vnorm(ref->disp[(size_t)f * (size_t)nv + (size_t)i]);
      if (u > peak) peak = u, peak_v = i;
    }
  for (int which = 0; which < 2 && !rc; ++which) {
    const int v = which == 0 ? rt->top_vertex : peak_v;
    for (int f = 0; f < nf; ++f) {
      t[f] = rt->time[f];
      ya[f] = 100.0 * vnorm(rt->disp[(size_t)f * (size_t)nv + (size_t)v]);
      yb[f] = 100.0 * vnorm(ref->disp[(size_t)f * (size_t)nv + (size_t)v]);
    }
    palp_svg_series s[2] = {{.label = "real-time model", .x = t, .y = ya, .n = (size_t)nf},
                            {.label = "FEM reference", .x = t, .y = yb, .n = (size_t)nf, .dashed = 1}};
    palp_svg_line_chart_def def = palp_svg_line_chart_default_def();
    if (which == 0) snprintf(title, sizeof title, "Distribution %s: top vertex", palp_eval_roman(d));
    else snprintf(title, sizeof title, "Distribution %s: most displaced vertex (%d)", palp_eval_roman(d), v);
    def.title = title;
    def.x_label = "time";
    def.x_unit = "s";
    def.y_label = "displacement magnitude";
    def.y_unit = "cm";
    def.series = s;
    def.series_count = 2;
    snprintf(path, sizeof path, "%s/%s_d%d.svg", dir, which == 0 ? "top_vertex" : "peak_vertex", d);
    rc = palp_svg_line_chart_file(path, &def, err, sizeof err);
  }
  for (int k = 0; k < 2 && !rc; ++k) {
    if (k == 1 && !row->has_force) break;
    palp_svg_bland_altman_def def = palp_svg_bland_altman_default_def();
    snprintf(title, sizeof title, "Distribution %s: %s, real-time - FEM", palp_eval_roman(d),
             k == 0 ? "vertex displacement" : "force feedback at contact vertices");
    def.title = title;
    def.unit = k == 0 ? "cm" : "N";
    def.label_a = "real-time";
    def.label_b = "FEM";
    def.a = k == 0 ? p->disp_rt : p->force_rt;
    def.b = k == 0 ? p->disp_ref : p->force_ref;
    def.n = k == 0 ? p->n_disp : p->n_force;
    def.bias = k == 0 ? row->disp.ba.bias : row->force.ba.bias;
    def.sd = k == 0 ? row->disp.ba.sd : row->force.ba.sd;
    /* svg_plot.h documents 4000 as the default, but the default def leaves 0
     * (draw all: 118,400 circles, 6.7 MB per plot); ask for it explicitly */
    def.max_points = 4000;
    snprintf(path, sizeof path, "%s/bland_altman_%s_d%d.svg", dir, k == 0 ? "displacement" : "force", d);
    rc = palp_svg_bland_altman_file(path, &def, err, sizeof err);
  }
  if (rc) palp_log_error(log, "plot %s: %s", path, err);
  free(t), free(ya), free(yb);
  return rc;
}

/* Differences a - b of every run, back to back, for the pooled statistics. */
typedef struct run_pool {
  double *diff;
  size_t n, cap;
  size_t start[5];
  int runs;
  double margin; /* the strictest of the runs' equivalence margins */
} run_pool;

static int pool_add(run_pool *p, const double *a, const double *b, size_t n, double margin) {
  if (p->runs >= 4) return PALP_EINVAL;
  if (p->n + n > p->cap) {
    size_t cap = 2 * (p->n + n);
    double *d = realloc(p->diff, sizeof(double) * cap);
    if (!d) return PALP_ENOMEM;
    p->diff = d, p->cap = cap;
  }
  for (size_t i = 0; i < n; ++i) p->diff[p->n + i] = a[i] - b[i];
  p->start[p->runs] = p->n;
  p->n += n;
  p->start[++p->runs] = p->n;
  p->margin = p->runs == 1 ? margin : fmin(p->margin, margin);
  return PALP_OK;
}

static int cmd_evaluate(const options *o) {
  setup s;
  int rc = load_setup(o, &s);
  if (rc) return rc;
  const char *dir = o->out ? o->out : "out/eval";
  if (make_dirs(dir)) {
    palp_log_error(o->log, "cannot create the output directory \"%s\": %s", dir, strerror(errno));
    return 1;
  }
  palp_eval_report rep;
  memset(&rep, 0, sizeof rep);
  snprintf(rep.scene, sizeof rep.scene, "%s", s.scene_path);
  snprintf(rep.scene_name, sizeof rep.scene_name, "%s", s.scene.name);
  snprintf(rep.parameters, sizeof rep.parameters, "%s%sE1 %.4g Pa, eta1 %.4g Pa s, E2 %.4g Pa, eta2 %.4g Pa s, a1 %.4g, "
                                                  "a2 %.4g Pa s/m^3, support %.4g Pa/m, %.4g Pa s/m, bulk fraction %.4g, added gel mass %.4g",
           o->params ? o->params : "", o->params ? ": " : "", s.scene.world.membrane.E1, s.scene.world.membrane.eta1, s.scene.world.membrane.E2,
           s.scene.world.membrane.eta2, s.scene.world.gel.a1, s.scene.world.gel.a2, s.scene.world.gel.support_modulus,
           s.scene.world.gel.support_viscosity, s.scene.world.gel.support_bulk_fraction, s.scene.world.gel.added_mass_fraction);
  rep.frames = s.scene.frames;
  rep.frame_period = s.scene.frame_period;
  rep.vertex_count = s.scene.world.mesh.vertex_count;
  rep.ref_level = s.fem.mesh.level;
  double t_stats = 0, t_rt = 0, t_ref = 0;
  run_pool pool[2];
  memset(pool, 0, sizeof pool);
  for (int k = 0; k < s.dist_count; ++k) {
    const int d = s.dist[k];
    palp_scene sd = s.scene;
    sd.contact[0].def.distribution = (palp_distribution)d;
    char err[512] = "";
    palp_eval_record rt, ref;
    double t0 = now_s();
    rc = palp_eval_run_rt(&sd, &rt, err, sizeof err);
    t_rt += now_s() - t0;
    if (rc) {
      palp_log_error(o->log, "distribution %s: %s", palp_eval_roman(d), err);
      return 1;
    }
    palp_fem_result info;
    t0 = now_s();
    rc = reference(&s, &sd, o->quiet, &ref, &info);
    t_ref += now_s() - t0;
    if (rc) {
      palp_eval_record_destroy(&rt);
      return 1;
    }
    rep.ref_elements = info.element_count;
    rep.ref_nodes = info.node_count;
    t0 = now_s();
    palp_eval_pairs pr;
    rc = palp_eval_pairs_build(&rt, &ref, &pr, err, sizeof err);
    if (rc) {
      palp_log_error(o->log, "distribution %s: %s", palp_eval_roman(d), err);
      palp_eval_record_destroy(&rt), palp_eval_record_destroy(&ref);
      return 1;
    }
    /* The paper's units: cm for displacement; force stays in N. */
    for (size_t i = 0; i < pr.n_disp; ++i) pr.disp_rt[i] *= 100.0, pr.disp_ref[i] *= 100.0;
    palp_eval_dist *row = &rep.dist[rep.dist_count++];
    row->distribution = d;
    row->rt_seconds = rt.wall_seconds;
    row->ref_seconds = info.wall_seconds;
    row->ref_from_cache = info.from_cache;
    row->disp_vertices = pr.n_disp / (size_t)rt.frames > 0 ? (int)(pr.n_disp / (size_t)rt.frames) : 0;
    row->force_vertices = pr.force_vertices;
    rc = palp_eval_row_compute(pr.disp_rt, pr.disp_ref, pr.n_disp, &row->disp);
    if (!rc && pr.n_force >= 2) {
      rc = palp_eval_row_compute(pr.force_rt, pr.force_ref, pr.n_force, &row->force);
      row->has_force = !rc;
    }
    /* The second table: the run as the unit of analysis (eval_sound.c); it needs
     * 3 frames for an autocorrelation. */
    const int sound = rt.frames >= 3;
    if (!rc && sound)
      rc = palp_eval_sound_compute(pr.disp_rt, pr.disp_ref, pr.n_disp, rt.frames,
                                   fmax(PALP_EVAL_MARGIN_DISP_ABS, PALP_EVAL_MARGIN_DISP_REL * row->disp.ref_peak),
                                   PALP_EVAL_BOOT_SEED + (unsigned long long)d, &row->disp_sound);
    if (!rc && sound && row->has_force)
      rc = palp_eval_sound_compute(pr.force_rt, pr.force_ref, pr.n_force, rt.frames,
                                   PALP_EVAL_MARGIN_FORCE_REL * row->force.ref_peak,
                                   PALP_EVAL_BOOT_SEED + 16ull + (unsigned long long)d, &row->force_sound);
    if (!rc && sound) rc = pool_add(&pool[0], pr.disp_rt, pr.disp_ref, pr.n_disp, row->disp_sound.margin);
    if (!rc && sound && row->has_force)
      rc = pool_add(&pool[1], pr.force_rt, pr.force_ref, pr.n_force, row->force_sound.margin);
    t_stats += now_s() - t0;
    if (rc) {
      palp_log_error(o->log, "distribution %s: statistics: %s", palp_eval_roman(d), palp_strerror(rc));
    } else {
      char path[1100];
      snprintf(path, sizeof path, "%s/displacement_d%d.csv", dir, d);
      if (write_pairs_csv(path, &pr, &rt, 0)) rc = 1;
      snprintf(path, sizeof path, "%s/force_d%d.csv", dir, d);
      if (!rc && write_pairs_csv(path, &pr, &rt, 1)) rc = 1;
      if (rc) palp_log_error(o->log, "cannot write %s", path);
      if (!rc && o->plots && write_plots(o->log, dir, d, &rt, &ref, &pr, row)) rc = 1;
    }
    palp_eval_pairs_destroy(&pr);
    palp_eval_record_destroy(&rt);
    palp_eval_record_destroy(&ref);
    if (rc) return 1;
    if (!o->quiet)
      palp_log_info(o->log,
                    "distribution %s done (real-time %.2f s; FEM %s%.1f s: %d elements, %ld steps, %ld Newton "
                    "iterations, %ld cutbacks, %ld factorisations)",
              palp_eval_roman(d), row->rt_seconds, row->ref_from_cache ? "from cache, computed in " : "",
              row->ref_seconds, info.element_count, info.steps, info.newton_iterations, info.cutbacks,
              info.factorizations);
  }
  /* Pool the runs: repeated-measures Bland-Altman and TOST over the run biases. */
  for (int t = 0; t < 2; ++t) {
    if (pool[t].runs >= 2) {
      rep.pooled[t] = palp_eval_sound_pool_compute(pool[t].diff, pool[t].start, pool[t].runs, pool[t].margin,
                                                   &rep.pool[t]) ==
                      PALP_OK;
    }
    free(pool[t].diff);
  }
  palp_eval_report_print(stdout, &rep);
  char err[512] = "";
  if (palp_eval_report_write(dir, &rep, err, sizeof err)) {
    palp_log_error(o->log, "%s", err);
    return 1;
  }
  printf("\nwritten to %s/: tables.csv, tables.json, tables.md, displacement_dN.csv, force_dN.csv%s\n", dir,
         o->plots ? ", top_vertex_dN.svg, peak_vertex_dN.svg, bland_altman_{displacement,force}_dN.svg" : "");
  printf("time: real-time model %.2f s, FEM reference %.2f s, statistics %.3f s\n", t_rt, t_ref, t_stats);
  return 0;
}

/* ---- calibrate ------------------------------------------------------------------------------ */

static void print_recovery(const char *label, const palp_eval_recovery *r) {
  printf("  %-7s peak %.3f mm, back within 5%% of the peak %.3f s after release%s, %.1f%% left after 1 s\n", label,
         1e3 * r->peak, r->t_recover, r->reached ? "" : " (extrapolated)", 100.0 * r->residual_1s);
}

static int cmd_calibrate(const options *o) {
  setup s;
  int rc = load_setup(o, &s);
  if (rc) return rc;
  const char *out = o->out ? o->out : "config/params/calibrated.json";
  palp_eval_calib_def def = palp_eval_calib_default_def();
  char err[512] = "";
  const double band = def.recovery_band;
  if (o->fit && palp_eval_params_parse_mask(o->fit, &def.mask, err, sizeof err)) {
    palp_log_error(o->log, "%s", err);
    return 2;
  }
  def.frame_stride = o->frame_stride;
  def.vertex_stride = o->vertex_stride;
  def.force_weight = o->force_weight;
  def.prior_weight = o->prior_weight;
  def.bias_weight = o->bias_weight;
  def.bound_factor = o->bound;
  def.recovery_weight = o->recovery_weight;
  def.max_iter = o->max_iter;
  def.max_seconds = 60.0 * o->max_minutes;
  def.verbose = !o->quiet;
  palp_scene scenes[4];
  palp_eval_record refs[4];
  palp_fem_result info;
  memset(&info, 0, sizeof info);
  const double t0 = now_s();
  for (int k = 0; k < s.dist_count; ++k) {
    scenes[k] = s.scene;
    scenes[k].contact[0].def.distribution = (palp_distribution)s.dist[k];
    if (reference(&s, &scenes[k], o->quiet, &refs[k], &info)) {
      for (int j = 0; j < k; ++j) palp_eval_record_destroy(&refs[j]);
      return 1;
    }
  }
  const double t_ref = now_s() - t0;
  palp_eval_calib_result res, res2;
  rc = palp_eval_calibrate(scenes, refs, s.dist_count, &def, &res, err, sizeof err);
  if (rc) {
    palp_log_error(o->log, "%s", err);
    for (int k = 0; k < s.dist_count; ++k) palp_eval_record_destroy(&refs[k]);
    return 1;
  }
  /* The paper's ~1 s recovery must survive; if the free fit lost it, refit with
   * it as a penalty residual, starting from the free fit. */
  const double target = def.recovery_target;
  const int broke = !(fabs(res.recovery_after.t_recover - target) <= band);
  int refit = 0;
  if (o->recovery_auto && broke) {
    if (!o->quiet)
      palp_log_warn(o->log, "the fit moved the recovery to %.3f s (outside %.1f +- %.1f s); refitting with it "
                            "as a penalty",
              res.recovery_after.t_recover, target, band);
    def.recovery_weight = 0.1;
    /* aim inside the checked band, so the hinge's balance point does not land
     * just outside it */
    def.recovery_band = 0.75 * band;
    for (int k = 0; k < s.dist_count; ++k) palp_eval_params_set(&scenes[k].world, res.fitted);
    rc = palp_eval_calibrate(scenes, refs, s.dist_count, &def, &res2, err, sizeof err);
    if (rc) {
      palp_log_error(o->log, "%s", err);
      for (int k = 0; k < s.dist_count; ++k) palp_eval_record_destroy(&refs[k]);
      return 1;
    }
    refit = 1;
  }
  for (int k = 0; k < s.dist_count; ++k) palp_eval_record_destroy(&refs[k]);
  const palp_eval_calib_result *fin = refit ? &res2 : &res;

  printf("calibration of %s against the FEM reference (level %d, %d elements), %d distributions, %d frames\n",
         s.scene_path, s.fem.mesh.level, info.element_count, s.dist_count, s.scene.frames);
  printf("  references %.1f s; fit %d iterations, %d model evaluations, %.1f s%s; GSL: %s\n", t_ref,
         res.iterations + (refit ? res2.iterations : 0), res.evaluations + (refit ? res2.evaluations : 0),
         res.seconds + (refit ? res2.seconds : 0), refit ? " (free fit + refit with the recovery penalty)" : "",
         palp_eval_fit_status_text(fin->status));
  printf("\n  %-18s %14s %14s  %s\n", "parameter", "start", "fitted", "unit");
  for (int j = 0; j < PALP_EVAL_P_COUNT; ++j)
    printf("  %-18s %14.6g %14.6g  %s%s\n", palp_eval_param_name[j], res.start[j], fin->fitted[j],
           palp_eval_param_unit[j], (def.mask & (1u << j)) ? "" : "  (held)");
  printf("\n  displacement RMSE [cm] (Table V data: |u| of every free vertex, every frame)\n");
  printf("  %-10s %10s %10s %10s\n", "", "before", "after", "paper");
  for (int k = 0; k < s.dist_count; ++k)
    printf("  Distr. %-3s %10.4f %10.4f %10.2f\n", palp_eval_roman(s.dist[k]), 100.0 * res.rmse_before[k],
           100.0 * fin->rmse_after[k], palp_eval_paper[0][s.dist[k] - 1].rmse);
  printf("\n  recovery (top contact, uniform patch, the scene's step)\n");
  print_recovery("before", &res.recovery_before);
  if (refit) print_recovery("free", &res.recovery_after);
  print_recovery("after", &fin->recovery_after);
  const int kept = fabs(fin->recovery_after.t_recover - target) <= band;
  printf("  the paper's ~%.1f s recovery %s (band +- %.1f s)%s\n", target, kept ? "survives" : "is NOT kept", band,
         refit ? "; held by the penalty residual" : "");

  palp_world_def w = s.scene.world;
  palp_eval_params_set(&w, fin->fitted);
  char comment[1600];
  int len = snprintf(comment, sizeof comment,
                     "Real-time model parameters, SI units, fitted by `palp-eval calibrate` to the FEM reference "
                     "(level %d, %d elements) of %s under distributions",
                     s.fem.mesh.level, info.element_count, s.scene_path);
  for (int k = 0; k < s.dist_count && len < (int)sizeof comment; ++k)
    len += snprintf(comment + len, sizeof comment - (size_t)len, " %s", palp_eval_roman(s.dist[k]));
  if (len < (int)sizeof comment) len += snprintf(comment + len, sizeof comment - (size_t)len, "; displacement RMSE [cm]");
  for (int k = 0; k < s.dist_count && len < (int)sizeof comment; ++k)
    len += snprintf(comment + len, sizeof comment - (size_t)len, " %s %.4f -> %.4f", palp_eval_roman(s.dist[k]),
                    100.0 * res.rmse_before[k], 100.0 * fin->rmse_after[k]);
  if (len < (int)sizeof comment)
    snprintf(comment + len, sizeof comment - (size_t)len, "; recovery to 5%% %.2f s after release. See docs/evaluation.md.",
             fin->recovery_after.t_recover);
  if (palp_eval_params_write(out, &w, comment, err, sizeof err)) {
    palp_log_error(o->log, "%s", err);
    return 1;
  }
  printf("\nparameters written to %s\n", out);
  return 0;
}

int main(int argc, char **argv) {
  if (palp_app_handle_version(argc, argv, "palp-eval")) return 0;
  gsl_set_error_handler_off();
  options o;
  if (parse_args(argc, argv, &o)) {
    usage(stderr);
    return 2;
  }
  palp_log log;
  if (palp_log_init(&log, "palp-eval", o.app.log_level, o.app.log_file) < 0) {
    fprintf(stderr, "palp-eval: --log-file %s: cannot open it\n", o.app.log_file);
    return 2;
  }
  o.log = &log; /* every line is flushed as written */
  return !strcmp(o.cmd, "evaluate") ? cmd_evaluate(&o) : cmd_calibrate(&o);
}
