/*
 * phantom_figures.c - measures an exercise phantom on the real-time model, in process, the
 * way the scripted trainees feel it (tests/assess/recorder.h, client/trainee.c): a fingertip
 * (8 mm sphere, the default coupling) pressed along the normal at 50 mm/s, held 0.12 s, the
 * force read as the median of the hold's last third. Not a test: the figures behind the
 * exercises' bands, lesions and the expert's settings (docs/assessment.md).
 *
 *   phantom_figures curve SCENE_OR_EXERCISE            force vs indentation 1-25 mm, pole / 45 / 70 deg
 *   phantom_figures gain EXERCISE                      each lesion: force over it / mirrored site / no lesion
 *   phantom_figures surface SCENE_OR_EXERCISE DEPTH_MM isolated presses on the expert's grid, no lesions
 *   phantom_figures expert EXERCISE [key=value ...]    the expert's exam: rises at and away from the lesions,
 *                                                      the assessment (keys: spacing_mm, light_mm, medium_mm,
 *                                                      deep_mm, threshold, hold_s, nolesions=1)
 *
 * Indentation is the assessment's: R + r - |proxy|. A target indentation is reached by
 * commanding the device deeper by the coupling's stretch (fixed-point, 6 passes).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp_assess.h"
#include "recorder.h"

#define R_FINGER 0.008
#define PRESS_SPEED 0.05
#define HOLD 0.12

static double deg(double d) { return d * TR_PI / 180.0; }
static palp_vec3 normal_at(double polar_deg, double az_deg) {
  const double p = deg(polar_deg), a = deg(az_deg);
  return (palp_vec3){sin(p) * cos(a), sin(p) * sin(a), cos(p)};
}
static double norm3(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

/* Loads a scene, or an exercise's scene (with its lesions when `lesions`). */
static int load(const char *path, int lesions, palp_scene *sc, palp_exercise *ex, int *is_ex) {
  char err[512] = "";
  *is_ex = 0;
  if (palp_exercise_load(path, ex, err, sizeof err) == 0) {
    *is_ex = 1;
    if (!lesions) {
      if (palp_scene_load(ex->phantom_path, sc, err, sizeof err)) goto fail;
      return 0;
    }
    if (palp_exercise_scene(ex, sc, err, sizeof err)) goto fail;
    return 0;
  }
  if (palp_scene_load(path, sc, err, sizeof err) == 0) return 0;
fail:
  fprintf(stderr, "%s: %s\n", path, err);
  return -1;
}

typedef struct press {
  double device_depth, indentation, force, force_settled;
} press;

/* One press in a fresh world: down to device depth d along n, hold, read; then hold to 1 s. */
static press press_once(const palp_scene *sc, palp_vec3 n, double d) {
  int e = 0;
  palp_world *w = palp_scene_create_world(sc, &e);
  press out = {d, NAN, NAN, NAN};
  if (!w) {
    fprintf(stderr, "world: %s\n", palp_strerror(e));
    return out;
  }
  const double R = sc->world.mesh.radius;
  recorder rc;
  rec_init(&rc, w, R, R_FINGER, (palp_vec3){0, 0, R + R_FINGER + 0.005});
  palp_cli_hand h;
  rec_hand(&rc, &h);
  palp_cli_hand_move_to(&h, palp_cli_hand_device_at(&h, n, -0.002), 0.1);
  palp_cli_hand_move_to(&h, palp_cli_hand_device_at(&h, n, d), PRESS_SPEED);
  const int k = (int)lround(HOLD / h.dt), tail0 = k - k / 3;
  double f[64];
  int m = 0;
  for (int i = 0; i < k; ++i) {
    palp_cli_hand_step(&h, h.device);
    if (i >= tail0) f[m++] = norm3(h.force);
  }
  for (int i = 0; i < m; ++i)
    for (int j = i + 1; j < m; ++j)
      if (f[j] < f[i]) {
        const double t = f[i];
        f[i] = f[j], f[j] = t;
      }
  out.force = f[m / 2];
  out.indentation = R + R_FINGER - norm3(rc.s[rc.n - 1].proxy);
  palp_cli_hand_hold(&h, 1.0 - HOLD);
  out.force_settled = norm3(h.force);
  rec_free(&rc);
  palp_world_destroy(w);
  return out;
}

/* A press reaching `ind` [m] of indentation (the device deeper by the coupling's stretch). */
static press press_to(const palp_scene *sc, palp_vec3 n, double ind) {
  double d = ind;
  press p = press_once(sc, n, d);
  for (int it = 0; it < 6 && isfinite(p.indentation) && fabs(p.indentation - ind) > 2e-5; ++it) {
    d += ind - p.indentation;
    p = press_once(sc, n, d);
  }
  return p;
}

static int cmd_curve(const char *path) {
  palp_scene sc;
  palp_exercise ex;
  int is_ex;
  if (load(path, 0, &sc, &ex, &is_ex)) return 1;
  const double sites[3] = {0, 45, 70};
  const double depths[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 14, 16, 18, 20, 22, 25};
  printf("# %s: force [N] at indentation [mm] (held 0.12 s; settled 1 s in brackets; device depth [mm])\n", path);
  printf("%6s", "mm");
  for (int s = 0; s < 3; ++s) printf(" | polar %2.0f: F  (1 s)  device", sites[s]);
  printf("\n");
  for (size_t k = 0; k < sizeof depths / sizeof *depths; ++k) {
    printf("%6.1f", depths[k]);
    for (int s = 0; s < 3; ++s) {
      const press p = press_to(&sc, normal_at(sites[s], 0), depths[k] * 1e-3);
      printf(" | %6.3f (%6.3f) %5.1f%s", p.force, p.force_settled, p.device_depth * 1e3,
             fabs(p.indentation - depths[k] * 1e-3) > 1e-4 ? "*" : " ");
    }
    printf("\n");
    fflush(stdout);
  }
  printf("# * indentation not reached within 0.1 mm (the table stops the hand near the rim)\n");
  return 0;
}

static int cmd_gain(const char *path, int argc, char **argv) {
  palp_scene with, without;
  palp_exercise ex;
  int is_ex;
  if (load(path, 1, &with, &ex, &is_ex) || !is_ex || load(path, 0, &without, &ex, &is_ex)) return 1;
  double depths[16] = {2, 4, 6, 8, 10, 12, 15};
  size_t nd = 7;
  if (argc > 0) /* the depths [mm] given */
    for (nd = 0; nd < (size_t)argc && nd < 16; ++nd) depths[nd] = atof(argv[nd]);
  for (int l = 0; l < ex.lesion_count; ++l) {
    const palp_exercise_lesion *L = &ex.lesion[l];
    const double pd = L->polar * 180 / TR_PI, ad = L->azimuth * 180 / TR_PI;
    printf("# %s lesion %d: polar %.0f az %.0f, %.1f mm, %.1f mm deep, ratio %.1f\n", path, l, pd, ad,
           L->diameter * 1e3, L->depth * 1e3, L->stiffness_ratio);
    printf("%6s %9s %9s %9s %8s %8s\n", "mm", "F_lesion", "F_mirror", "F_none", "/mirror", "/none");
    for (size_t k = 0; k < nd; ++k) {
      const double ind = depths[k] * 1e-3;
      const press a = press_to(&with, normal_at(pd, ad), ind);
      const press b = press_to(&with, normal_at(pd, ad + 180), ind);
      const press c = press_to(&without, normal_at(pd, ad), ind);
      printf("%6.1f %9.3f %9.3f %9.3f %+7.1f%% %+7.1f%%\n", depths[k], a.force, b.force, c.force,
             100 * (a.force / b.force - 1), 100 * (a.force / c.force - 1));
      fflush(stdout);
    }
  }
  return 0;
}

/* The expert's grid (client/trainee.c: strips x = const, spots `spacing` apart). */
static int grid(double R, double spacing, double min_nz, palp_vec3 *out, int cap) {
  const double da = spacing / R;
  const int na = (int)floor((TR_PI / 2.0) / da);
  int n = 0;
  for (int ia = -na; ia <= na; ++ia) {
    const double a = ia * da, ca = cos(a);
    if (ca < min_nz) continue;
    const double bmax = acos(fmin(1.0, min_nz / ca)), db = spacing / (R * ca);
    const int nb = (int)floor(bmax / db);
    for (int k = -nb; k <= nb && n < cap; ++k) out[n++] = (palp_vec3){sin(a), ca * sin(k * db), ca * cos(k * db)};
  }
  return n;
}

static int cmd_surface(const char *path, double depth_mm) {
  palp_scene sc;
  palp_exercise ex;
  int is_ex;
  if (load(path, 0, &sc, &ex, &is_ex)) return 1;
  const double R = sc.world.mesh.radius;
  static palp_vec3 g[512];
  const int n = grid(R, 0.008, 0.06, g, 512);
  /* polar rings of 10 deg: mean, min, max; only spots where the press stays clear of the table */
  enum { RINGS = 9 };
  double sum[RINGS] = {0}, mn[RINGS], mx[RINGS];
  int cnt[RINGS] = {0};
  for (int r = 0; r < RINGS; ++r) mn[r] = INFINITY, mx[r] = -INFINITY;
  printf("# %s: isolated presses to %.1f mm indentation on the expert's 8 mm grid (%d spots), no lesions\n", path,
         depth_mm, n);
  for (int i = 0; i < n; ++i) {
    const double polar = acos(g[i].z) * 180 / TR_PI;
    const press p = press_to(&sc, g[i], depth_mm * 1e-3);
    if (fabs(p.indentation - depth_mm * 1e-3) > 1e-4) continue; /* the table */
    const int r = (int)(polar / 10);
    if (r >= RINGS) continue;
    sum[r] += p.force, cnt[r]++;
    mn[r] = fmin(mn[r], p.force), mx[r] = fmax(mx[r], p.force);
    printf("spot %3d polar %5.1f az %6.1f F %.4f\n", i, polar, atan2(g[i].y, g[i].x) * 180 / TR_PI, p.force);
    fflush(stdout);
  }
  printf("# ring: spots, mean, min, max, (max - min) / mean\n");
  for (int r = 0; r < RINGS; ++r)
    if (cnt[r])
      printf("polar %2d-%2d: %3d  %.3f  %.3f  %.3f  %.1f%%\n", 10 * r, 10 * r + 10, cnt[r], sum[r] / cnt[r], mn[r],
             mx[r], 100 * (mx[r] - mn[r]) / (sum[r] / cnt[r]));
  return 0;
}

static int cmd_expert(const char *path, int argc, char **argv) {
  palp_scene sc;
  palp_exercise ex;
  int is_ex, nolesions = 0, use_deep = 0;
  palp_cli_expert_cfg cfg = palp_cli_expert_default();
  for (int i = 0; i < argc; ++i) {
    double v;
    char key[64];
    if (sscanf(argv[i], "%63[^=]=%lf", key, &v) != 2) return fprintf(stderr, "bad %s\n", argv[i]), 2;
    if (!strcmp(key, "spacing_mm")) cfg.spacing = v * 1e-3;
    else if (!strcmp(key, "light_mm")) cfg.d_light = v * 1e-3;
    else if (!strcmp(key, "medium_mm")) cfg.d_medium = v * 1e-3;
    else if (!strcmp(key, "deep_mm")) cfg.d_deep = v * 1e-3;
    else if (!strcmp(key, "threshold")) cfg.threshold = v;
    else if (!strcmp(key, "hold_s")) cfg.hold = v;
    else if (!strcmp(key, "keep_N")) cfg.keep_force = v;
    else if (!strcmp(key, "nolesions")) nolesions = v != 0;
    else if (!strcmp(key, "use_deep")) use_deep = v != 0;
    else return fprintf(stderr, "unknown key %s\n", key), 2;
  }
  if (load(path, 1, &sc, &ex, &is_ex) || !is_ex) return 1;
  if (nolesions) sc.world.lesion_count = 0;
  int e = 0;
  palp_world *w = palp_scene_create_world(&sc, &e);
  if (!w) return fprintf(stderr, "world: %s\n", palp_strerror(e)), 1;
  const double R = sc.world.mesh.radius;
  recorder rc;
  rec_init(&rc, w, R, R_FINGER, (palp_vec3){0, 0, R + R_FINGER + 0.005});
  palp_cli_hand h;
  rec_hand(&rc, &h);
  int n = 0;
  palp_cli_expert_spot *sp = palp_cli_expert_exam(&h, &cfg, &n);
  rec_finish(&rc);
  if (!sp || rc.failed) return fprintf(stderr, "exam failed\n"), 1;
  if (use_deep) /* the lump rule on the deep press's force instead of the medium one's */
    for (int i = 0; i < n; ++i) sp[i].f_medium = sp[i].f_deep;
  /* rises: the largest near each lesion (within its radius + 10 mm of its surface point) and away */
  double near_max[PALP_MAX_LESIONS], far_max = -INFINITY, far_sum = 0, far_sq = 0;
  int far_n = 0, far_at = -1;
  double judged_polar = 0;
  for (int l = 0; l < PALP_MAX_LESIONS; ++l) near_max[l] = -INFINITY;
  double *rises = malloc(sizeof(double) * (size_t)n);
  if (!rises || palp_cli_expert_rises(&h, sp, n, &cfg, rises) < 0) return 1;
  for (int i = 0; i < n; ++i) {
    if (!sp[i].free) continue;
    const double r = rises[i];
    if (!isfinite(r)) continue;
    int near = 0;
    for (int l = 0; l < ex.lesion_count && !nolesions; ++l) {
      const palp_vec3 s = palp_exercise_lesion_surface(&ex.lesion[l], R);
      const palp_vec3 d = {R * sp[i].n.x - s.x, R * sp[i].n.y - s.y, R * sp[i].n.z - s.z};
      if (norm3(d) <= ex.lesion[l].diameter / 2 + 0.010) near = 1, near_max[l] = fmax(near_max[l], r);
    }
    judged_polar = fmax(judged_polar, acos(sp[i].n.z) * 180 / TR_PI);
    if (!near) {
      far_sum += r, far_sq += r * r, far_n++;
      if (r > far_max) far_max = r, far_at = i;
    }
  }
  const double sd = far_n > 1 ? sqrt((far_sq - far_sum * far_sum / far_n) / (far_n - 1)) : NAN;
  printf("expert on %s%s: spacing %.1f mm, device depths %.1f / %.1f / %.1f mm, hold %.2f s, threshold %.3f%s\n", path,
         nolesions ? " (lesions removed)" : "", cfg.spacing * 1e3, cfg.d_light * 1e3, cfg.d_medium * 1e3,
         cfg.d_deep * 1e3, cfg.hold, cfg.threshold,
         use_deep ? ", rule on the deep force" : "");
  printf("  %d spots, %d samples; rise away from lesions: %d spots, mean %+.4f sd %.4f, max %+.4f", n, rc.n, far_n,
         far_n ? far_sum / far_n : NAN, sd, far_max);
  if (far_at >= 0)
    printf(" (polar %.1f az %.1f)", acos(sp[far_at].n.z) * 180 / TR_PI,
           atan2(sp[far_at].n.y, sp[far_at].n.x) * 180 / TR_PI);
  printf("; spots judged up to polar %.1f deg\n", judged_polar);
  for (int l = 0; l < ex.lesion_count && !nolesions; ++l) printf("  lesion %d: largest rise %+.4f\n", l, near_max[l]);
  /* medium and deep forces: range over the free spots */
  double fm0 = INFINITY, fm1 = 0, fd0 = INFINITY, fd1 = 0;
  for (int i = 0; i < n; ++i)
    if (sp[i].free) {
      fm0 = fmin(fm0, sp[i].f_medium), fm1 = fmax(fm1, sp[i].f_medium);
      fd0 = fmin(fd0, sp[i].f_deep), fd1 = fmax(fd1, sp[i].f_deep);
    }
  printf("  held force: medium %.2f-%.2f N, deep %.2f-%.2f N\n", fm0, fm1, fd0, fd1);
  palp_finding f[16];
  palp_vec3 p[16];
  double t[16], max_rise = 0;
  const int nf = palp_cli_expert_lumps(&h, sp, n, &cfg, p, t, 16, &max_rise);
  for (int i = 0; i < nf; ++i) f[i] = (palp_finding){.t = t[i], .point = p[i], .withdrawn = 0};
  if (nolesions) ex.lesion_count = 0;
  palp_assess_result r;
  int match[16];
  if (palp_assess(&ex, palp_world_mesh(w), R_FINGER, rc.s, rc.n, f, nf, &r, match, NULL) == 0) {
    /* where the samples fall: indentation range per band */
    printf("  found %d/%d, false %d, coverage %.3f / %.3f / %.3f, %s (axial %.2f), time %.1f s, peak %.2f N, "
           "out of range %d, score %.1f, pass %d\n",
           r.found, r.lesion_count, r.false_positives, r.coverage[0], r.coverage[1], r.coverage[2],
           palp_pattern_name(r.pattern), r.evidence.share_axial, r.duration, r.peak_force, r.out_of_range, r.score,
           r.pass);
    for (int i = 0; i < nf; ++i)
      printf("  mark %d at polar %.1f az %.1f: %s\n", i, acos(p[i].z / R) * 180 / TR_PI,
             atan2(p[i].y, p[i].x) * 180 / TR_PI, match[i] >= 0 ? "lesion" : "false");
  }
  /* indentation the held presses reached: max over samples */
  double ind_max = 0;
  for (int i = 0; i < rc.n; ++i) ind_max = fmax(ind_max, R + R_FINGER - norm3(rc.s[i].proxy));
  printf("  deepest indentation %.2f mm\n", ind_max * 1e3);
  palp_world_health hl;
  palp_world_get_health(w, &hl);
  printf("  deeper than validated: %lld steps of %.0f ms (by up to %.2f mm)\n", (long long)hl.beyond_validated_steps,
         sc.world.dt * 1e3, hl.max_beyond_validated * 1e3);
  free(sp), free(rises);
  rec_free(&rc);
  palp_world_destroy(w);
  return 0;
}

int main(int argc, char **argv) {
  if (argc >= 3 && !strcmp(argv[1], "curve")) return cmd_curve(argv[2]);
  if (argc >= 3 && !strcmp(argv[1], "gain")) return cmd_gain(argv[2], argc - 3, argv + 3);
  if (argc >= 4 && !strcmp(argv[1], "surface")) return cmd_surface(argv[2], atof(argv[3]));
  if (argc >= 3 && !strcmp(argv[1], "expert")) return cmd_expert(argv[2], argc - 3, argv + 3);
  fprintf(stderr, "usage: %s curve|gain|surface|expert FILE [...] (see the source)\n", argv[0]);
  return 2;
}
