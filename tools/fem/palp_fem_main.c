/*
 * palp-fem - the FE reference ("golden standard") from the command line.
 *
 *   palp-fem run --scene SCENE.json [--level N] [--dt S] [--config FEM.json]
 *                [--inp MESH.inp] [--material PROFILE] [--reading long_term|instantaneous] [--frames N]
 *                [--distribution single|uniform|gaussian|gaussian_offset]
 *                [--out FILE.csv] [--cache-dir DIR | --no-cache] [--quiet]
 *   palp-fem export-inp [--level N] [--config FEM.json] OUT.inp
 *   palp-fem info [--level N] [--config FEM.json] [--inp MESH.inp]
 *   palp-fem finger --scene SCENE.json [--level N] [--config FEM.json]
 *                [--reading long_term|instantaneous] [--out FILE.csv]
 *                [--site all|pole,45deg,60deg,70deg,pole_lesion] [--lesion-depth MM] [--lesion-ratio S]
 *                [--fe-from FINGER.csv] [--depths N | --no-force-table] [--max-force N]
 *
 * finger prints fingertip force-depth curves of the real-time model (the scene's
 * world) against the FE reference (rigid sphere, relaxed) at matched positions:
 * pole, 45 deg, 70 deg, and over a 10 mm lesion (finger_compare.c), by default 5x the
 * gel with its centre 10 mm deep (--lesion-depth in mm, --lesion-ratio: 0.2 is a cyst).
 *
 * run writes one CSV row per output frame: time, top-vertex displacement, total
 * feedback force, every real-time vertex's displacement and every contact
 * vertex's feedback (units in the column names), and prints a summary. On a
 * terminal a progress bar with an ETA goes to stderr.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "fem_internal.h"
#include "finger_compare.h"
#include "palp_app.h"

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* --quiet already means "no progress bar or summary" here, so only --log-level/--log-file. */
#define FEM_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_LOG)

static void usage(void) {
  fprintf(stderr,
          "usage: palp-fem run --scene SCENE.json [--level N] [--dt S] [--config FEM.json] [--inp MESH.inp]\n"
          "                    [--material paper_long_term|paper_instantaneous|breast_tissue]\n"
          "                    [--reading long_term|instantaneous] [--frames N]\n"
          "                    [--distribution single|uniform|gaussian|gaussian_offset]\n"
          "                    [--out FILE.csv] [--cache-dir DIR | --no-cache] [--quiet]\n"
          "       palp-fem export-inp [--level N] [--config FEM.json] OUT.inp\n"
          "       palp-fem info [--level N] [--config FEM.json] [--inp MESH.inp]\n"
          "       palp-fem finger --scene SCENE.json [--level N] [--config FEM.json]\n"
          "                       [--reading long_term|instantaneous] [--out FILE.csv]\n"
          "                       [--site all|pole,45deg,60deg,70deg,pole_lesion] [--lesion-depth MM] [--lesion-ratio S]\n"
          "                       [--fe-from FINGER.csv] [--depths N] [--no-force-table] [--max-force N]\n"
          "  finger --fe-from: the FE curves from a CSV an earlier finger run wrote (only the real-time side\n"
          "  is computed); --depths N: each curve's first N depths only; --no-force-table: no depth-for-force\n"
          "  table (its real-time curve to 30 mm is most of the real-time cost); --max-force N: each FE curve\n"
          "  ends at the first depth whose force passes N newtons (default 5)\n");
  palp_app_common_usage(stderr, FEM_OPTS);
}

typedef struct progress {
  double t0;
  int tty;
  int last_pct;
} progress;

static int on_progress(void *ud, int frame, int frames, double sim_time) {
  progress *p = ud;
  if (!p->tty) return 0;
  const int pct = (int)(1000.0 * frame / frames);
  if (pct == p->last_pct && frame != frames) return 0;
  p->last_pct = pct;
  const double el = now_s() - p->t0, eta = frame > 0 ? el * (frames - frame) / frame : 0.0;
  char bar[41];
  const int fill = (int)(40.0 * frame / frames);
  for (int i = 0; i < 40; ++i) bar[i] = i < fill ? '#' : '.';
  bar[40] = 0;
  fprintf(stderr, "\r[%s] %5.1f%% frame %d/%d t=%.2fs elapsed %.0fs ETA %.0fs ", bar, 100.0 * frame / frames, frame,
          frames, sim_time, el, eta);
  if (frame == frames) fprintf(stderr, "\n");
  fflush(stderr);
  return 0;
}

static int parse_dist(const char *s, palp_distribution *d) {
  static const char *names[] = {"single", "uniform", "gaussian", "gaussian_offset"};
  for (int i = 0; i < 4; ++i)
    if (strcmp(s, names[i]) == 0) {
      *d = (palp_distribution)(i + 1);
      return 0;
    }
  return -1;
}

static double vlen(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

static int write_csv(const char *path, const palp_fem_result *r) {
  char tmp[1100];
  snprintf(tmp, sizeof tmp, "%s.tmp", path);
  FILE *f = fopen(tmp, "w");
  if (!f) return -1;
  fprintf(f, "time_s,top_dx_m,top_dy_m,top_dz_m,top_disp_m,feedback_x_N,feedback_y_N,feedback_z_N,feedback_N");
  for (int v = 0; v < r->vertex_count; ++v) fprintf(f, ",dx%d_m,dy%d_m,dz%d_m", v, v, v);
  for (int k = 0; k < r->contact_vertex_count; ++k) {
    const int v = r->contact_vertex[k], c = r->contact_of[k];
    fprintf(f, ",fb_c%d_v%d_x_N,fb_c%d_v%d_y_N,fb_c%d_v%d_z_N", c, v, c, v, c, v);
  }
  fprintf(f, "\n");
  for (int fr = 0; fr < r->frames; ++fr) {
    const palp_vec3 t = r->top_disp[fr];
    palp_vec3 fb = {0, 0, 0};
    const palp_vec3 *row = r->feedback + (size_t)fr * (size_t)r->contact_vertex_count;
    for (int k = 0; k < r->contact_vertex_count; ++k) fb.x += row[k].x, fb.y += row[k].y, fb.z += row[k].z;
    fprintf(f, "%.6f,%.9e,%.9e,%.9e,%.9e,%.6e,%.6e,%.6e,%.6e", r->time[fr], t.x, t.y, t.z, vlen(t), fb.x, fb.y, fb.z,
            vlen(fb));
    const palp_vec3 *d = r->disp + (size_t)fr * (size_t)r->vertex_count;
    for (int v = 0; v < r->vertex_count; ++v) fprintf(f, ",%.6e,%.6e,%.6e", d[v].x, d[v].y, d[v].z);
    for (int k = 0; k < r->contact_vertex_count; ++k) fprintf(f, ",%.6e,%.6e,%.6e", row[k].x, row[k].y, row[k].z);
    fprintf(f, "\n");
  }
  const int bad = ferror(f);
  if (fclose(f) != 0 || bad || rename(tmp, path) != 0) {
    remove(tmp);
    return -1;
  }
  return 0;
}

static void summary(const palp_fem_config *cfg, const palp_scene *s, const palp_fem_result *r, double wall) {
  printf("material         %s: %s\n", cfg->material[0] ? cfg->material : "custom",
         cfg->material[0] ? palp_fem_material_label(cfg->material) : "materials set field by field");
  /* the map belongs to the run's identity: the same material under the two maps differs */
  printf("load map         %s\n", cfg->load_map == PALP_FEM_LOAD_POINT ? "point (nodal, the paper's literal load)"
                                                                         : "patch (each vertex's one-ring)");
  double peak = 0.0, t_peak = 0.0, at_release = NAN, residual = NAN, recovery = NAN, t_release = -1.0;
  palp_vec3 fb_release = {NAN, NAN, NAN};
  for (int c = 0; c < s->contact_count; ++c)
    if (s->contact[c].profile.kind == PALP_PROFILE_STEP) t_release = s->contact[c].profile.t_off;
  for (int f = 0; f < r->frames; ++f) {
    const double d = vlen(r->top_disp[f]), t = r->time[f];
    if (d > peak) peak = d, t_peak = t;
    if (t_release > 0 && fabs(t - t_release) < 0.5 * s->frame_period) {
      at_release = d;
      palp_vec3 fb = {0, 0, 0};
      for (int k = 0; k < r->contact_vertex_count; ++k) {
        const palp_vec3 q = r->feedback[(size_t)f * (size_t)r->contact_vertex_count + (size_t)k];
        fb.x += q.x, fb.y += q.y, fb.z += q.z;
      }
      fb_release = fb;
    }
    if (t_release > 0 && fabs(t - (t_release + 1.0)) < 0.5 * s->frame_period) residual = d;
    if (t_release > 0 && t > t_release && isnan(recovery) && d <= 0.05 * peak) recovery = t - t_release;
  }
  printf("scene            %s: %d contact(s), %d frames of %.3f s\n", s->name, s->contact_count, r->frames,
         s->frame_period);
  printf("mesh             %d nodes, %d hexahedra, %d free DOFs\n", r->node_count, r->element_count, r->dof_count);
  printf("top vertex       peak %.3f mm at %.2f s", 1e3 * peak, t_peak);
  if (!isnan(at_release)) printf("; at release %.3f mm", 1e3 * at_release);
  if (!isnan(residual)) printf("; 1 s after release %.3f mm", 1e3 * residual);
  printf("\n");
  if (!isnan(recovery)) printf("recovery         %.2f s after release (to 5%% of the peak)\n", recovery);
  else printf("recovery         not within the run\n");
  if (!isnan(at_release))
    printf("feedback         (%.3f, %.3f, %.3f) N at release, |f| = %.3f N over %d contact vertices\n", fb_release.x,
           fb_release.y, fb_release.z, vlen(fb_release), r->contact_vertex_count);
  else
    printf("feedback         %d contact vertices (the run ends before the release)\n", r->contact_vertex_count);
  printf("solver           %ld steps, %ld Newton iterations, %ld CG iterations, %ld factorisations (%ld on the "
         "background thread), %ld cut-backs\n",
         r->steps, r->newton_iterations, r->pcg_iterations, r->factorizations, r->background_factorizations,
         r->cutbacks);
  if (r->from_cache)
    printf("time             %.1f s computed (%.3f s per frame; the paper: 22.5 s per step); this run read it from the "
           "cache\n", r->wall_seconds, r->wall_seconds / r->frames);
  else
    printf("time             %.1f s computed: setup %.2f s (mesh, map, symbolic analysis, first factorisation), then "
           "%.3f s per frame (the paper: 22.5 s per step)\n",
           r->wall_seconds, r->sec_setup, (r->wall_seconds - r->sec_setup) / r->frames);
  printf("wall             %.2f s\n", wall);
}

typedef struct opts {
  const char *scene, *config, *inp, *out, *cache_dir, *reading, *material, *dist, *site, *fe_from, *positional;
  int level, frames, depths, no_cache, quiet, no_force_table;
  double dt;
  double lesion_depth_mm, lesion_ratio; /* finger: the pole_lesion site's lesion */
  double max_force; /* finger: [N] each FE curve ends at the first depth past it */
  palp_app_opts app;
  palp_log *log; /* main's, once the options are read */
} opts;

static int parse(int argc, char **argv, opts *o) {
  memset(o, 0, sizeof *o);
  o->level = -1;
  o->frames = -1;
  o->dt = -1.0;
  o->lesion_depth_mm = 10.0;
  o->lesion_ratio = 5.0;
  o->max_force = 5.0;
  palp_app_opts_init(&o->app, "palp-fem");
  for (int i = 2; i < argc; ++i) {
    const char *a = argv[i];
    const int has = i + 1 < argc;
    const int common = palp_app_common_opt(&o->app, FEM_OPTS, argc, argv, &i);
    if (common < 0) return -1;
    if (common) continue;
#define ARG(name, dst)                                                                                             \
  if (strcmp(a, name) == 0) {                                                                                      \
    if (!has) {                                                                                                    \
      fprintf(stderr, "palp-fem: %s needs a value\n", name);                                                       \
      return -1;                                                                                                   \
    }                                                                                                              \
    dst = argv[++i];                                                                                               \
    continue;                                                                                                      \
  }
    ARG("--scene", o->scene)
    ARG("--config", o->config)
    ARG("--inp", o->inp)
    ARG("--out", o->out)
    ARG("--cache-dir", o->cache_dir)
    ARG("--reading", o->reading)
    ARG("--material", o->material)
    ARG("--distribution", o->dist)
    ARG("--site", o->site)
    ARG("--fe-from", o->fe_from)
#undef ARG
    /* the options that take a positive real */
    const int positive_opt = strcmp(a, "--lesion-depth") == 0 || strcmp(a, "--lesion-ratio") == 0 ||
                             strcmp(a, "--max-force") == 0;
    if ((strcmp(a, "--level") == 0 || strcmp(a, "--frames") == 0 || strcmp(a, "--depths") == 0 ||
         strcmp(a, "--dt") == 0 || positive_opt) && has) {
      char *end;
      const double v = strtod(argv[++i], &end);
      if (*end || !isfinite(v)) {
        fprintf(stderr, "palp-fem: %s: not a number: %s\n", a, argv[i]);
        return -1;
      }
      if (strcmp(a, "--dt") == 0) {
      if (!(v >= 0.0)) { /* -1 is the "unset" sentinel: a negative --dt was silently ignored */
        fprintf(stderr, "palp-fem: --dt: expected 0 (one step per frame) or a step in seconds: %s\n", argv[i]);
        return -1;
      }
      o->dt = v;
    }
      else if (positive_opt && !(v > 0.0)) {
        fprintf(stderr, "palp-fem: %s: expected a positive number: %s\n", a, argv[i]);
        return -1;
      } else if (strcmp(a, "--lesion-depth") == 0) o->lesion_depth_mm = v;
      else if (strcmp(a, "--max-force") == 0) o->max_force = v;
      else if (strcmp(a, "--lesion-ratio") == 0) o->lesion_ratio = v;
      else if (v != floor(v) || v < 1 || v > 1e7) {
        fprintf(stderr, "palp-fem: %s: expected a positive integer\n", a);
        return -1;
      } else if (strcmp(a, "--level") == 0) o->level = (int)v;
      else if (strcmp(a, "--depths") == 0) o->depths = (int)v;
      else o->frames = (int)v;
      continue;
    }
    if (strcmp(a, "--no-force-table") == 0) { /* independent of --depths (it once overrode it) */
      o->no_force_table = 1;
      continue;
    }
    if (strcmp(a, "--no-cache") == 0) {
      o->no_cache = 1;
      continue;
    }
    if (strcmp(a, "--quiet") == 0) {
      o->quiet = 1;
      continue;
    }
    if (a[0] == '-' || o->positional) {
      fprintf(stderr, "palp-fem: unexpected argument %s\n", a);
      return -1;
    }
    o->positional = a;
  }
  return 0;
}

/* The FEM's material: the default profile (paper_long_term), then the one the scene's
 * real-time parameters were calibrated against (scene may be NULL), then the FEM config
 * file, then --material: a scene is compared with its own reference unless the user
 * says otherwise. */
static int build_config(const opts *o, const palp_scene *scene, palp_fem_config *cfg) {
  char err[256];
  if (palp_fem_config_for_scene(scene, cfg, err, sizeof err) != 0) {
    palp_log_error(o->log, "%s: %s", o->scene ? o->scene : "scene", err);
    return -1;
  }
  if (o->config && palp_fem_config_load(o->config, cfg, err, sizeof err) != 0) {
    palp_log_error(o->log, "%s", err);
    return -1;
  }
  if (o->material && palp_fem_config_set_material(cfg, o->material, err, sizeof err) != 0) {
    palp_log_error(o->log, "--material: %s", err);
    return -1;
  }
  if (o->level > 0) cfg->mesh.level = o->level;
  if (o->dt >= 0.0) cfg->dt = o->dt;
  if (o->inp) snprintf(cfg->inp_path, sizeof cfg->inp_path, "%s", o->inp);
  if (o->cache_dir) snprintf(cfg->cache_dir, sizeof cfg->cache_dir, "%s", o->cache_dir);
  if (o->no_cache) cfg->cache_dir[0] = 0;
  if (o->reading) {
    if (strcmp(o->reading, "long_term") == 0) cfg->c10_reading = PALP_FEM_C10_LONG_TERM;
    else if (strcmp(o->reading, "instantaneous") == 0) cfg->c10_reading = PALP_FEM_C10_INSTANTANEOUS;
    else {
      palp_log_error(o->log, "--reading: expected long_term or instantaneous");
      return -1;
    }
    /* the alias of the two paper profiles, as the config file's c10_reading: the name and
     * the profile's load map switch together (since session 82; the map used to stay, so
     * "paper_instantaneous" named two different runs) */
    if (strncmp(cfg->material, "paper_", 6) == 0) {
      snprintf(cfg->material, sizeof cfg->material, "%s",
               cfg->c10_reading == PALP_FEM_C10_LONG_TERM ? "paper_long_term" : "paper_instantaneous");
      cfg->load_map = cfg->c10_reading == PALP_FEM_C10_LONG_TERM ? PALP_FEM_LOAD_PATCH : PALP_FEM_LOAD_POINT;
    } else if (cfg->material[0])
      cfg->material[0] = 0;
  }
  if (palp_fem_config_validate(cfg, err, sizeof err) != 0) {
    palp_log_error(o->log, "%s", err);
    return -1;
  }
  return 0;
}

static int cmd_run(const opts *o) {
  if (!o->scene) {
    fprintf(stderr, "palp-fem run: --scene is required\n");
    usage();
    return 2;
  }
  palp_scene scene;
  char err[512];
  if (palp_scene_load(o->scene, &scene, err, sizeof err) != 0) {
    palp_log_error(o->log, "%s: %s", o->scene, err);
    return 2;
  }
  palp_fem_config cfg;
  if (build_config(o, &scene, &cfg)) return 2;
  if (o->frames > 0) scene.frames = o->frames;
  if (o->dist) {
    palp_distribution d;
    if (parse_dist(o->dist, &d)) {
      palp_log_error(o->log, "--distribution: expected single, uniform, gaussian or gaussian_offset");
      return 2;
    }
    for (int c = 0; c < scene.contact_count; ++c) scene.contact[c].def.distribution = d;
  }
  progress p = {.t0 = now_s(), .tty = !o->quiet && isatty(2), .last_pct = -1};
  palp_fem_result r;
  const double t0 = now_s();
  const int rc = palp_fem_run(&cfg, &scene, &r, on_progress, &p, err, sizeof err);
  if (rc) {
    if (p.tty) fprintf(stderr, "\n");
    palp_log_error(o->log, "run failed: %s (%s)", err, palp_strerror(rc));
    return 1;
  }
  if (err[0]) palp_log_warn(o->log, "%s", err);
  if (o->out && write_csv(o->out, &r) != 0) {
    palp_log_error(o->log, "cannot write %s", o->out);
    palp_fem_result_destroy(&r);
    return 1;
  }
  if (!o->quiet) summary(&cfg, &scene, &r, now_s() - t0);
  palp_fem_result_destroy(&r);
  return 0;
}

static int load_mesh(palp_log *log, const palp_fem_config *cfg, palp_fem_mesh *m) {
  char err[256];
  if (cfg->inp_path[0]) {
    if (palp_fem_inp_read(cfg->inp_path, m, err, sizeof err) != 0) {
      palp_log_error(log, "%s", err);
      return -1;
    }
  } else if (palp_fem_mesh_create(&cfg->mesh, m) != 0) {
    palp_log_error(log, "invalid mesh definition (level %d)", cfg->mesh.level);
    return -1;
  }
  return 0;
}

static int cmd_export(const opts *o) {
  if (!o->positional) {
    fprintf(stderr, "palp-fem export-inp: the output file is required\n");
    usage();
    return 2;
  }
  palp_fem_config cfg;
  if (build_config(o, NULL, &cfg)) return 2;
  palp_fem_mesh m;
  if (load_mesh(o->log, &cfg, &m)) return 2;
  char heading[128];
  snprintf(heading, sizeof heading, "palp hemisphere R = %.4g m, membrane %.4g m, level %d", cfg.mesh.radius,
           cfg.mesh.membrane_thickness, cfg.mesh.level);
  const int rc = palp_fem_inp_write(&m, o->positional, heading);
  if (rc) palp_log_error(o->log, "cannot write %s: %s", o->positional, palp_strerror(rc));
  else if (!o->quiet) printf("wrote %s: %d nodes, %d C3D8 elements, %d sets\n", o->positional, m.node_count, m.element_count, m.set_count);
  palp_fem_mesh_destroy(&m);
  return rc ? 1 : 0;
}

static int cmd_info(const opts *o) {
  palp_fem_config cfg;
  if (build_config(o, NULL, &cfg)) return 2;
  palp_fem_mesh m;
  if (load_mesh(o->log, &cfg, &m)) return 2;
  int nm = 0, nf = 0;
  double vol = 0.0;
  for (int e = 0; e < m.element_count; ++e) {
    nm += m.region[e] == PALP_FEM_MEMBRANE;
    vol += palp_fem_element_volume(&m, e);
  }
  for (int n = 0; n < m.node_count; ++n) nf += m.fixed[n];
  printf("mesh      %d nodes (%d clamped), %d hexahedra (%d membrane, %d gel), volume %.4g m^3\n", m.node_count, nf,
         m.element_count, nm, m.element_count - nm, vol);
  printf("material  %s (%s)\n", cfg.material[0] ? cfg.material : "custom",
         cfg.material[0] ? palp_fem_material_label(cfg.material) : "materials set field by field");
  for (int r = 0; r < 2; ++r) {
    const palp_fem_material *mat = r ? &cfg.membrane : &cfg.gel;
    const double ginf = palp_fem_ginf(mat), c0 = palp_fem_c10_instant(mat, cfg.c10_reading);
    printf("%-9s C10 %.4g Pa (instantaneous %.4g, relaxed %.4g), K = 2/D1 = %.3g Pa, rho %.0f kg/m^3\n",
           r ? "membrane" : "gel", mat->c10, c0, c0 * ginf, 2.0 / mat->d1, mat->density);
  }
  palp_fem_mesh_destroy(&m);
  return 0;
}

static int cmd_finger(const opts *o) {
  if (!o->scene) {
    fprintf(stderr, "palp-fem finger: --scene is required\n");
    usage();
    return 2;
  }
  palp_scene scene;
  char err[512];
  if (palp_scene_load(o->scene, &scene, err, sizeof err) != 0) {
    palp_log_error(o->log, "%s: %s", o->scene, err);
    return 2;
  }
  palp_fem_config cfg;
  if (build_config(o, &scene, &cfg)) return 2;
  if (cfg.inp_path[0]) {
    palp_log_error(o->log, "finger: --inp is not supported (the lesions need the generated mesh's regions)");
    return 2;
  }
  err[0] = 0;
  if (palp_fem_finger_compare(&cfg, &scene, o->out, o->site, 1e-3 * o->lesion_depth_mm, o->lesion_ratio, o->fe_from,
                              o->depths, !o->no_force_table, o->max_force, err, sizeof err) != 0) {
    palp_log_error(o->log, "finger: %s", err[0] ? err : "failed");
    return 1;
  }
  return 0;
}

int main(int argc, char **argv) {
  if (palp_app_handle_version(argc, argv, "palp-fem")) return 0;
  if (argc < 2 || strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0) {
    usage();
    return argc < 2 ? 2 : 0;
  }
  opts o;
  if (parse(argc, argv, &o)) {
    usage();
    return 2;
  }
  if (o.app.version) { /* after the command word: read by parse(), never as another option's value */
    palp_app_print_version(stdout, "palp-fem");
    return 0;
  }
  palp_log log;
  if (palp_log_init(&log, "palp-fem", o.app.log_level, o.app.log_file) < 0) {
    fprintf(stderr, "palp-fem: --log-file %s: cannot open it: %s\n", o.app.log_file, strerror(errno));
    return 2;
  }
  o.log = &log; /* every line is flushed as written: returning without a close loses nothing */
  if (strcmp(argv[1], "run") == 0) return cmd_run(&o);
  if (strcmp(argv[1], "export-inp") == 0) return cmd_export(&o);
  if (strcmp(argv[1], "info") == 0) return cmd_info(&o);
  if (strcmp(argv[1], "finger") == 0) return cmd_finger(&o);
  fprintf(stderr, "palp-fem: unknown command %s\n", argv[1]);
  usage();
  return 2;
}
