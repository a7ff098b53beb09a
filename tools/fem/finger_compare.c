/*
 * finger_compare.c - `palp-fem finger`: fingertip force-depth curves, real-time
 * model vs FE reference at matched positions (docs/fem.md, "The finger").
 *
 * Sites: the pole, 45 deg off-centre, 70 deg (20 deg above the rim: an 8 mm tip
 * closer to the rim would meet the table first), and the pole over a 10 mm lesion
 * (5x the gel) whose centre is 10 mm deep (--lesion-depth, --lesion-ratio change it). The tip moves along the inward radial
 * normal; its depth is d = R + r - |c| for centre c (from the undeformed sphere).
 *
 * FE: the rigid sphere at centre c, relaxed static equilibrium (the long-term
 * response) at depths 0.25 mm ... until the force passes 5 N (--max-force).
 * Real-time: the scene's world (its parameters, mesh and material), a finger whose
 * device point is driven to each depth and held, corrected twice so that the
 * proxy (the fingertip centre, the FE sphere's counterpart) sits at the FE depth.
 * Prints, per depth, both forces and their ratio; with --out, a CSV.
 *
 * --fe-from CSV takes the FE side from a CSV this command wrote before (same
 * columns), so that the real-time side of a fine FE level can be compared again
 * in seconds, e.g. for a parameter search or a test against stored references;
 * --depths N stops each FE curve after its first N depths (a cheap check that a
 * stored curve is still what the FEM computes); --no-force-table leaves out the
 * depth-for-force table, whose real-time curve to 30 mm is ~90% of the real-time cost
 * (the two are independent: --no-force-table once meant "all depths" too, and a run
 * asked for 14 depths went on to 18 mm).
 */
/* stat: POSIX. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "eval.h"
#include "fem_finger.h"
#include "finger_compare.h"

#define MAXD 24

typedef struct site {
  const char *name;
  double polar_deg;
  int lesion;
  int in_all; /* run by --site all (60deg is asked by name: stored curves predate it) */
} site;

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Whether name is one of the comma-separated tokens of list: a substring test took
 * "pole_lesion" for "pole" too and computed the plain pole first. */
static int listed(const char *list, const char *name) {
  const size_t n = strlen(name);
  for (const char *p = list; p && *p;) {
    const char *end = strchr(p, ',');
    const size_t len = end ? (size_t)(end - p) : strlen(p);
    if (len == n && strncmp(p, name, n) == 0) return 1;
    p = end ? end + 1 : NULL;
  }
  return 0;
}

/* Each FE depth as it is computed, to stderr, in the CSV's columns (the real-time
 * ones empty): a level-4 curve takes minutes (hours with "full_newton"), and a run stopped before its end (the
 * CSV is written per site) keeps its depths in the log. */
typedef struct fe_progress {
  const char *site;
  double t0;
} fe_progress;

static void fe_row(void *ud, int k, double depth, double force, double gap, long newton) {
  const fe_progress *p = ud;
  fprintf(stderr, "FE row %d: %s,%.6e,%.6e,,,,%.3e (%.0f s, %ld Newton iterations)\n", k + 1, p->site, depth, force,
          gap, now_s() - p->t0, newton);
}

/* The FE curve of one site from a CSV written by this command (palp_eval_finger_csv_read),
 * checked to follow this command's depth sequence. */
static int read_fe_curve(const char *path, const char *name, const double *depths, int max, double *F, double *G,
                         char *err, size_t errlen) {
  double d[MAXD];
  const int n = palp_eval_finger_csv_read(path, name, max, d, F, G, err, errlen);
  for (int k = 0; k < n; ++k)
    if (fabs(d[k] - depths[k]) > 1e-9) {
      snprintf(err, errlen, "%s: %s row %d at depth %.6g m, expected %.6g m (this command's sequence)", path, name,
               k + 1, d[k], depths[k]);
      return -1;
    }
  return n;
}

int palp_fem_finger_compare(const palp_fem_config *cfg0, const palp_scene *scene, const char *csv, const char *only,
                            double lesion_depth, double lesion_ratio, const char *fe_from, int max_depths,
                            int force_table, double max_force, char *err, size_t errlen) {
  setvbuf(stdout, NULL, _IOLBF, 0); /* a long run shows each site as it finishes */
  palp_fem_config cfg = *cfg0;
  cfg.max_newton = cfg.max_newton < 25 ? 25 : cfg.max_newton;
  palp_fem_mesh mesh;
  if (palp_fem_mesh_create(&cfg.mesh, &mesh)) {
    snprintf(err, errlen, "invalid mesh definition");
    return -1;
  }
  /* the FE dome is the scene's (both are pressed at the same centres) */
  if (palp_fem_check_radius(&mesh, scene->world.mesh.radius, err, errlen)) {
    palp_fem_mesh_destroy(&mesh);
    return -1;
  }
  const double R = cfg.mesh.radius;
  const palp_lesion lump = {.center = {0, 0, R - lesion_depth}, .radius = 0.005, .stiffness_ratio = lesion_ratio};
  /* inside the dome, clear of the surface and of the base (the scene's rule) */
  if (!(lesion_depth > lump.radius && lesion_depth < R - lump.radius) || !(lesion_ratio > 0.0 && lesion_ratio <= 1e6)) {
    snprintf(err, errlen, "lesion %.4g m deep, ratio %.4g: the centre must lie %.0f-%.0f mm deep, 0 < ratio <= 1e6",
             lesion_depth, lesion_ratio, 1e3 * lump.radius, 1e3 * (R - lump.radius));
    palp_fem_mesh_destroy(&mesh);
    return -1;
  }
  /* 60 deg: between 45 and 70, where the validated depth falls fastest (docs/model.md, "Valid range") */
  const site sites[5] = {{"pole", 0, 0, 1}, {"45deg", 45, 0, 1}, {"70deg", 70, 0, 1}, {"pole_lesion", 0, 1, 1},
                         {"60deg", 60, 0, 0}};
  static const double depths[MAXD] = {0.25e-3, 0.5e-3, 0.75e-3, 1e-3, 1.5e-3, 2e-3, 2.5e-3, 3e-3,
                                      4e-3,    5e-3,   6e-3,    7e-3, 8e-3,   10e-3, 12e-3, 14e-3,
                                      16e-3,   18e-3,  20e-3,   22e-3, 24e-3, 26e-3, 28e-3, 30e-3};
  /* every --site token names a site (a typo once computed nothing and exited 0) */
  for (const char *p = only; p && *p && strcmp(only, "all") != 0;) {
    const char *end = strchr(p, ',');
    const size_t len = end ? (size_t)(end - p) : strlen(p);
    int known = 0;
    for (int s = 0; s < (int)(sizeof sites / sizeof sites[0]); ++s)
      known |= strlen(sites[s].name) == len && strncmp(p, sites[s].name, len) == 0;
    if (!known) {
      snprintf(err, errlen, "--site: \"%.*s\" names no site (all, or a list of pole, 45deg, 60deg, 70deg, "
               "pole_lesion)", (int)(len < 64 ? len : 64), p);
      palp_fem_mesh_destroy(&mesh);
      return -1;
    }
    p = end ? end + 1 : NULL;
  }
  /* --out goes to CSV.XXXXXX (mkstemp: its own name, 0600, no symlink followed, two runs
   * apart), renamed over CSV only when the run succeeded: --fe-from may
   * name the same file (re-running the real-time side in place), and a level-4 curve
   * it holds took hours. A failed run leaves its rows in CSV.partial. A path that is
   * not a regular file (/dev/null, a FIFO) is written in place. */
  FILE *out = NULL;
  char tmp[4096] = "";
  struct stat sb;
  const int special = csv && stat(csv, &sb) == 0 && !S_ISREG(sb.st_mode);
  if (csv && !special && snprintf(tmp, sizeof tmp, "%s.XXXXXX", csv) >= (int)sizeof tmp) {
    snprintf(err, errlen, "%s: path too long", csv);
    palp_fem_mesh_destroy(&mesh);
    return -1;
  }
  if (csv && !special) {
    const int fd = mkstemp(tmp);
    if (fd >= 0 && !(out = fdopen(fd, "w"))) {
      close(fd);
      remove(tmp);
    }
  } else if (csv)
    out = fopen(csv, "w");
  if (csv && !out) {
    snprintf(err, errlen, "cannot write %s", special ? csv : tmp);
    palp_fem_mesh_destroy(&mesh);
    return -1;
  }
  if (out) fprintf(out, "site,depth_m,fem_N,realtime_N,realtime_depth_m,ratio_rt_over_fem,fem_min_gap_m\n");
  printf("FE: level %d (%d hexahedra), %s reading, relaxed (long-term) static%s%s; real-time: the scene's world (%s)\n",
         cfg.mesh.level, mesh.element_count, cfg.c10_reading == PALP_FEM_C10_LONG_TERM ? "long_term" : "instantaneous",
         fe_from ? ", taken from " : "", fe_from ? fe_from : "", scene->name);
  const int maxd = max_depths > 0 && max_depths < MAXD ? max_depths : MAXD; /* <= 0: all */
  double Fplain[MAXD] = {0}, Rplain[MAXD] = {0};
  int nplain = 0, rc = 0;
  const int all = !only || strcmp(only, "all") == 0; /* no --site: all */
  for (int s = 0; s < (int)(sizeof sites / sizeof sites[0]) && !rc; ++s) {
    if (all ? !sites[s].in_all : !listed(only, sites[s].name)) continue;
    const double th = sites[s].polar_deg * PALP_FEM_PI / 180.0;
    const palp_vec3 n = {sin(th), 0, cos(th)};
    double F[MAXD], G[MAXD], Fr[MAXD], Dr[MAXD];
    long newton = 0;
    const double t0 = now_s();
    const double nv[3] = {n.x, n.y, n.z};
    fe_progress prog = {sites[s].name, t0};
    err[0] = 0;
    const int nd = fe_from ? read_fe_curve(fe_from, sites[s].name, depths, maxd, F, G, err, errlen)
                           : palp_fem_finger_curve(&cfg, &mesh, &lump, sites[s].lesion, nv, 0.008, depths, maxd, max_force, F,
                                                   G, &newton, fe_row, &prog, err, errlen);
    const double t1 = now_s();
    if (nd <= 0) {
      if (fe_from && nd == 0) snprintf(err, errlen, "%s has no rows of site %s", fe_from, sites[s].name);
      else if (!fe_from && nd == 0) {
        char why[256];
        snprintf(why, sizeof why, "%s", err[0] ? err : "no reason given");
        snprintf(err, errlen, "site %s: the FE press failed at its first depth, %.2f mm: %s", sites[s].name,
                 1e3 * depths[0], why);
      }
      rc = -1;
      break;
    }
    /* a curve that ends before its last depth without passing max_force is a failed press,
     * not a finished curve: its rows are printed and kept, then the run fails */
    char failed[384] = "";
    if (!fe_from && nd < maxd && !(F[nd - 1] > max_force))
      snprintf(failed, sizeof failed, "site %s: the FE press failed at %.2f mm after %d of %d depths (%.3g N, below "
               "--max-force %g N): %s", sites[s].name, 1e3 * depths[nd], nd, maxd, F[nd - 1], max_force,
               err[0] ? err : "no reason given");
    if (palp_eval_finger_rt(&scene->world, &lump, sites[s].lesion, n, 0.008, depths, nd, 1.0, Fr, Dr, err, errlen) <
        0) {
      rc = -1;
      break;
    }
    char what[96] = "";
    if (sites[s].lesion)
      snprintf(what, sizeof what, ", 10 mm lesion %gx %g mm deep", lesion_ratio, 1e3 * lesion_depth);
    printf("\n%s (%.0f deg%s): FE %.1f s, %ld Newton iterations; real-time %.1f s\n", sites[s].name,
           sites[s].polar_deg, what, t1 - t0, newton, now_s() - t1);
    printf("  depth mm   FE N    RT N   RT depth mm  RT/FE%s\n", sites[s].lesion ? "   FE lesion gain  RT lesion gain" : "");
    for (int k = 0; k < nd; ++k) {
      printf("  %7.2f %7.3f %7.4f %9.3f %8.3f", depths[k] * 1e3, F[k], Fr[k], Dr[k] * 1e3, Fr[k] / F[k]);
      if (sites[s].lesion && k < nplain)
        printf("   %+8.1f%%        %+8.1f%%", 100 * (F[k] / Fplain[k] - 1), 100 * (Fr[k] / Rplain[k] - 1));
      printf("\n");
      if (out)
        fprintf(out, "%s,%.6e,%.6e,%.6e,%.6e,%.6e,%.3e\n", sites[s].name, depths[k], F[k], Fr[k], Dr[k], Fr[k] / F[k],
                G[k]);
    }
    /* force-matched: the depth each model needs for 0.3, 1, 3, 5 N (the real-time
     * curve continued to 30 mm, ~90% of the real-time cost: skipped without force_table;
     * linear interpolation between held depths) */
    if (force_table && !failed[0]) {
      double Fl[MAXD], Dl[MAXD];
      const int nl =
          palp_eval_finger_rt(&scene->world, &lump, sites[s].lesion, n, 0.008, depths, MAXD, 1.0, Fl, Dl, err, errlen);
      static const double targets[4] = {0.3, 1.0, 3.0, 5.0};
      printf("  force N  FE depth mm  RT depth mm\n");
      for (int t = 0; t < 4; ++t) {
        double dfe = NAN, drt = NAN;
        for (int k = 0; k < nd; ++k)
          if (F[k] >= targets[t]) {
            const double F0 = k ? F[k - 1] : 0.0, D0 = k ? depths[k - 1] : 0.0;
            dfe = D0 + (depths[k] - D0) * (targets[t] - F0) / (F[k] - F0);
            break;
          }
        for (int k = 0; k < nl; ++k)
          if (Fl[k] >= targets[t]) {
            const double F0 = k ? Fl[k - 1] : 0.0, D0 = k ? Dl[k - 1] : 0.0;
            drt = D0 + (Dl[k] - D0) * (targets[t] - F0) / (Fl[k] - F0);
            break;
          }
        printf("  %7.1f  %10.2f  %10.2f%s\n", targets[t], dfe * 1e3, drt * 1e3,
               isnan(drt) ? "  (not reached by 30 mm)" : "");
      }
    }
    if (failed[0]) {
      snprintf(err, errlen, "%s", failed);
      rc = -1;
      break;
    }
    if (out) fflush(out);
    if (s == 0) {
      nplain = nd;
      memcpy(Fplain, F, sizeof F);
      memcpy(Rplain, Fr, sizeof Fr);
    }
  }
  if (out) {
    const int bad = ferror(out);
    if (fclose(out) != 0 || bad) {
      if (!rc) snprintf(err, errlen, "%s: write error", special ? csv : tmp);
      rc = -1;
    }
  }
  if (out && !special) {
    if (!rc && rename(tmp, csv) != 0) {
      snprintf(err, errlen, "cannot rename %s to %s", tmp, csv);
      rc = -1;
      remove(tmp);
    } else if (rc) { /* keep what was computed beside, not over, the file named */
      char part[4200];
      snprintf(part, sizeof part, "%s.partial", csv);
      if (rename(tmp, part) == 0) {
        const size_t n = strlen(err);
        if (n + 1 < errlen) snprintf(err + n, errlen - n, " (the rows written are in %s; %s is unchanged)", part, csv);
      } else
        remove(tmp);
    }
  }
  palp_fem_mesh_destroy(&mesh);
  return rc;
}
