/*
 * palp-run - runs a scene offline and writes per-frame results as CSV.
 *
 *   palp-run SCENE.json [--distribution single|uniform|gaussian|gaussian_offset|all]
 *            [--dt S] [--vertices N] [--frames N] [--out PREFIX] [--quiet]
 *
 * PREFIX_frames.csv: time, top-vertex displacement, max displacement, volume,
 * pressure, applied and feedback force per frame; PREFIX_vertices.csv: the
 * displacement of every vertex per frame (PREFIX's directory is created if its parent exists; PREFIX may
 * be up to 1000 bytes, longer is refused). A summary
 * goes to stdout.
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "palp.h"
#include "palp_app.h"
#include "palp_rng.h"
#include "stats.h"

/* Step times kept for the median and p99: every one up to STEP_SAMPLES, then a uniform sample
 * of that many (reservoir sampling, Vitter's algorithm R). A scene may ask for 1e8 frames of
 * 1e5 steps, and one double per step was up to 8e13 bytes (unchecked, then written through).
 * With 2^20 samples (8 MB) the p99 of a longer run is off by ~0.01 percentile points (one
 * standard deviation, sqrt(0.99 * 0.01 / 2^20)). */
#define STEP_SAMPLES (1L << 20)

/* The longest --out PREFIX taken: every path built from it ("_d4" and "_vertices.csv" added) fits
 * the buffers below. A longer one was cut without a word (session 82's review: "_d1".."_d4" lost,
 * so four runs overwrote one file, exit 0); now it is refused, exit 2. */
#define RUN_PREFIX_MAX 1000
#define RUN_PATH_LEN (RUN_PREFIX_MAX + 32)

/* snprintf into a path buffer; 0, or -1 when the path did not fit (said, naming --out and the limit) */
static int path_fmt(char *buf, size_t len, const char *prefix, const char *suffix) {
  const int n = snprintf(buf, len, "%s%s", prefix, suffix);
  if (n < 0 || (size_t)n >= len) {
    fprintf(stderr, "palp-run: --out: PREFIX followed by \"%s\" is too long (PREFIX may be at most %d bytes)\n",
            suffix, RUN_PREFIX_MAX);
    return -1;
  }
  return 0;
}

typedef struct run_summary {
  double peak_top, t_peak, top_at_release, residual_1s, recovery_time, max_vol_err, peak_pressure;
  double peak_contact, contact_residual_1s;
  palp_world_health health;
  palp_vec3 feedback_at_release;
  double step_median_us, step_p99_us;
} run_summary;

static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Whether CSV file f (path) has taken every write: a full disk truncated PREFIX_frames.csv and
 * the run still exited 0, as if finished. closing: flush and close it too (closed either way). */
static int csv_ok(palp_log *log, FILE *f, const char *path, int closing) {
  int e = ferror(f) ? (errno ? errno : EIO) : 0; /* errno: the failed write's, checked every frame */
  if (closing) {
    if (fflush(f) != 0 && !e) e = errno ? errno : EIO;
    if (fclose(f) != 0 && !e) e = errno ? errno : EIO;
  }
  if (e) palp_log_error(log, "%s: cannot write it: %s", path, strerror(e));
  return !e;
}

static const char *dist_label[] = {"", "I single", "II uniform", "III gaussian", "IV gaussian_offset"};

/* Whether the scene releases a step (the recovery figures' reference instant), as run() finds it. */
static int has_release(const palp_scene *s) {
  for (int c = 0; c < s->contact_count; ++c)
    if (s->contact[c].profile.kind == PALP_PROFILE_STEP && s->contact[c].profile.t_off > 0) return 1;
  return 0;
}

static int run(palp_log *log, const palp_scene *s, const char *prefix, run_summary *sum) {
  int err;
  palp_world *w = palp_scene_create_world(s, &err);
  if (!w) {
    palp_log_error(log, "cannot create the world: %s", palp_strerror(err));
    return 1;
  }
  const palp_mesh *m = palp_world_mesh(w);
  const int nv = m->vertex_count, top = m->top_vertex;
  const int probe = s->contact_count ? palp_mesh_nearest_vertex(m, m->rest, s->contact[0].def.center) : top;
  const int sub = (int)lround(s->frame_period / s->world.dt);
  FILE *ff = NULL, *fv = NULL;
  char fpath[RUN_PATH_LEN], vpath[RUN_PATH_LEN];
  if (prefix) {
    if (path_fmt(fpath, sizeof fpath, prefix, "_frames.csv") || path_fmt(vpath, sizeof vpath, prefix, "_vertices.csv")) {
      palp_world_destroy(w);
      return 2;
    }
    errno = 0;
    ff = fopen(fpath, "w");
    if (!ff) palp_log_error(log, "cannot write %s: %s", fpath, strerror(errno));
    else if (!(fv = fopen(vpath, "w"))) palp_log_error(log, "cannot write %s: %s", vpath, strerror(errno));
    if (!ff || !fv) {
      if (ff) fclose(ff);
      if (fv) fclose(fv);
      palp_world_destroy(w);
      return 1;
    }
    fprintf(ff, "time_s,top_dx_m,top_dy_m,top_dz_m,top_disp_m,max_disp_m,volume_m3,volume_rel_err,pressure_Pa,"
                "applied_N,feedback_x_N,feedback_y_N,feedback_z_N,feedback_N\n");
    fprintf(fv, "time_s");
    for (int i = 0; i < nv; ++i) fprintf(fv, ",dx%d_m,dy%d_m,dz%d_m", i, i, i);
    fprintf(fv, "\n");
  }
  const long nsteps = (long)s->frames * sub;
  const long nkeep = nsteps < STEP_SAMPLES ? nsteps : STEP_SAMPLES;
  double *st = malloc(sizeof(double) * (size_t)(nkeep > 0 ? nkeep : 1));
  if (!st) {
    palp_log_error(log, "cannot allocate %ld step times", nkeep);
    if (ff) fclose(ff);
    if (fv) fclose(fv);
    palp_world_destroy(w);
    return 1;
  }
  uint64_t rng = 0x70616c702d72756eULL; /* fixed: the same scene reports the same sample's statistics */
  memset(sum, 0, sizeof *sum);
  /* not reached until the run gets there (a run shorter than release + 1 s, or no step profile): said
   * so below, not 0 (until session 90 "1 s after release 0.000 mm (0.0%)" read as full recovery; found
   * by review) */
  sum->recovery_time = sum->contact_residual_1s = sum->residual_1s = sum->top_at_release = NAN;
  sum->feedback_at_release = (palp_vec3){NAN, NAN, NAN};
  double t_release = -1.0;
  for (int c = 0; c < s->contact_count; ++c)
    if (s->contact[c].profile.kind == PALP_PROFILE_STEP) t_release = s->contact[c].profile.t_off;
  const double V0 = palp_world_rest_volume(w);
  long k = 0;
  err = 0;
  for (int f = 0; f < s->frames; ++f) {
    double applied = 0.0;
    for (int q = 0; q < sub; ++q, ++k) {
      err = palp_scene_apply(s, w, palp_scene_step_time(s, f, q)); /* the FE reference's clock */
      if (err) {
        palp_log_error(log, "step %ld: the scene's forces: %s", k, palp_strerror(err));
        break;
      }
      const double t0 = now_s();
      err = palp_world_step(w);
      const double dt_step = now_s() - t0;
      if (err) {
        palp_log_error(log, "step %ld failed: %s", k, palp_strerror(err));
        break;
      }
      if (k < nkeep) st[k] = dt_step;
      else {
        const long j = (long)(palp_rng_next(&rng) % (uint64_t)(k + 1));
        if (j < nkeep) st[j] = dt_step;
      }
    }
    if (err) {
      free(st);
      if (ff) fclose(ff);
      if (fv) fclose(fv);
      palp_world_destroy(w);
      return 1;
    }
    for (int c = 0; c < s->contact_count; ++c)
      applied += palp_profile_eval(&s->contact[c].profile, palp_scene_step_time(s, f, sub - 1));
    const palp_vec3 *p = palp_world_positions(w);
    const double t = palp_world_time(w);
    const palp_vec3 d = {p[top].x - m->rest[top].x, p[top].y - m->rest[top].y, p[top].z - m->rest[top].z};
    const double top_disp = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    double maxd = 0.0;
    for (int i = 0; i < nv; ++i) {
      const double dx = p[i].x - m->rest[i].x, dy = p[i].y - m->rest[i].y, dz = p[i].z - m->rest[i].z;
      maxd = fmax(maxd, sqrt(dx * dx + dy * dy + dz * dz));
    }
    const double V = palp_world_volume(w), verr = (V - V0) / V0;
    palp_vec3 fb = {0, 0, 0};
    for (int c = 0; c < s->contact_count; ++c) {
      palp_vec3 one;
      if (palp_world_contact_feedback(w, c, &one) == PALP_OK) fb.x += one.x, fb.y += one.y, fb.z += one.z;
    }
    const double fbn = sqrt(fb.x * fb.x + fb.y * fb.y + fb.z * fb.z);
    if (top_disp > sum->peak_top) sum->peak_top = top_disp, sum->t_peak = t;
    const double cdx = p[probe].x - m->rest[probe].x, cdy = p[probe].y - m->rest[probe].y,
                 cdz = p[probe].z - m->rest[probe].z;
    const double cdisp = sqrt(cdx * cdx + cdy * cdy + cdz * cdz);
    if (cdisp > sum->peak_contact) sum->peak_contact = cdisp;
    if (t_release > 0 && fabs(t - (t_release + 1.0)) < 0.5 * s->frame_period) sum->contact_residual_1s = cdisp;
    if (t_release > 0 && fabs(t - t_release) < 0.5 * s->frame_period) {
      sum->top_at_release = top_disp;
      sum->feedback_at_release = fb;
    }
    if (t_release > 0 && fabs(t - (t_release + 1.0)) < 0.5 * s->frame_period) sum->residual_1s = top_disp;
    if (t_release > 0 && t > t_release && isnan(sum->recovery_time) && top_disp <= 0.05 * sum->peak_top)
      sum->recovery_time = t - t_release;
    sum->max_vol_err = fmax(sum->max_vol_err, fabs(verr));
    sum->peak_pressure = fmax(sum->peak_pressure, palp_world_pressure(w));
    if (ff) {
      fprintf(ff, "%.6f,%.9e,%.9e,%.9e,%.9e,%.9e,%.9e,%.3e,%.6e,%.6f,%.6e,%.6e,%.6e,%.6e\n", t, d.x, d.y, d.z,
              top_disp, maxd, V, verr, palp_world_pressure(w), applied, fb.x, fb.y, fb.z, fbn);
      fprintf(fv, "%.6f", t);
      for (int i = 0; i < nv; ++i)
        fprintf(fv, ",%.6e,%.6e,%.6e", p[i].x - m->rest[i].x, p[i].y - m->rest[i].y, p[i].z - m->rest[i].z);
      fprintf(fv, "\n");
      if (!csv_ok(log, ff, fpath, 0) || !csv_ok(log, fv, vpath, 0)) {
        free(st);
        fclose(ff);
        fclose(fv);
        palp_world_destroy(w);
        return 1;
      }
    }
  }
  palp_world_get_health(w, &sum->health);
  if (nkeep > 0) {
    qsort(st, (size_t)nkeep, sizeof *st, cmp_double);
    /* One rule for both, type 7 as palp-stats: st[n/2] and st[floor(0.99 (n-1))] put the p99 of
     * 2 steps below their median (the faster step against the slower). */
    sum->step_median_us = 1e6 * palp_stats_quantile_sorted(st, (size_t)nkeep, 0.5);
    sum->step_p99_us = 1e6 * palp_stats_quantile_sorted(st, (size_t)nkeep, 0.99);
  }
  free(st);
  palp_world_destroy(w);
  /* both closed even when the first fails */
  return ff && !(csv_ok(log, ff, fpath, 1) & csv_ok(log, fv, vpath, 1)) ? 1 : 0;
}

/* The whole of v as a whole number in [lo, hi] (the scene file's own limits): atoi read
 * "1e3" as 1, "10k" as 10, ignored "abc", "-5" and "0", and overflowed on 99999999999. */
static int whole_opt(const char *opt, const char *v, long lo, long hi, int *out) {
  char *end;
  errno = 0;
  const long x = strtol(v, &end, 10);
  if (!isdigit((unsigned char)v[0]) || *end || errno == ERANGE || x < lo || x > hi) {
    fprintf(stderr, "palp-run: %s must be a whole number from %ld to %ld (got \"%s\")\n", opt, lo, hi, v);
    return -1;
  }
  *out = (int)x;
  return 0;
}

/* --quiet already means "no scene line on stdout" here, so only --log-level/--log-file. */
#define RUN_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_LOG)

static void usage(void) {
  fprintf(stderr, "usage: palp-run SCENE.json [--distribution single|uniform|gaussian|gaussian_offset|all]\n"
                  "                [--dt S] [--vertices N] [--frames N] [--out PREFIX] [--quiet]\n");
  palp_app_common_usage(stderr, RUN_OPTS);
}

int main(int argc, char **argv) {
  palp_app_opts ao;
  palp_app_opts_init(&ao, "palp-run");
  const char *scene_path = NULL, *prefix = NULL, *dist = NULL;
  double dt = 0.0;
  int vertices = 0, frames = 0, quiet = 0;
  for (int i = 1; i < argc; ++i) {
    const char *a = argv[i];
    const char *v = (i + 1 < argc) ? argv[i + 1] : NULL;
    const int common = palp_app_common_opt(&ao, RUN_OPTS, argc, argv, &i);
    if (common < 0) return 2;
    if (common) continue;
    if (!strcmp(a, "--distribution") && v) dist = v, ++i;
    else if (!strcmp(a, "--dt") && v) {
      char *end;
      dt = strtod(v, &end);
      if (isspace((unsigned char)v[0]) || end == v || *end || !isfinite(dt) || !(dt > 0.0)) {
        fprintf(stderr, "palp-run: --dt must be a time step in seconds > 0 (got \"%s\")\n", v);
        return 2;
      }
      ++i;
    } else if (!strcmp(a, "--vertices") && v) {
      if (whole_opt(a, v, 19, PALP_MESH_MAX_VERTICES, &vertices) < 0) return 2;
      ++i;
    } else if (!strcmp(a, "--frames") && v) {
      if (whole_opt(a, v, 1, 100000000, &frames) < 0) return 2;
      ++i;
    } else if (!strcmp(a, "--out") && v) {
      if (strlen(v) > RUN_PREFIX_MAX) {
        fprintf(stderr, "palp-run: --out: PREFIX is %zu bytes, longer than the limit of %d\n", strlen(v),
                RUN_PREFIX_MAX);
        return 2;
      }
      prefix = v, ++i;
    }
    else if (!strcmp(a, "--quiet")) quiet = 1;
    else if (!strcmp(a, "-h") || !strcmp(a, "--help")) return usage(), 0;
    else if (a[0] != '-' && !scene_path) scene_path = a;
    else return usage(), 2;
  }
  if (ao.version) {
    palp_app_print_version(stdout, "palp-run");
    return 0;
  }
  if (!scene_path) return usage(), 2;
  palp_log log;
  if (palp_log_init(&log, "palp-run", ao.log_level, ao.log_file) < 0) {
    fprintf(stderr, "palp-run: --log-file %s: cannot open it: %s\n", ao.log_file, strerror(errno));
    return 2;
  }
  int rc = 0;
  palp_scene s;
  char err[256];
  if (palp_scene_load(scene_path, &s, err, sizeof err)) {
    palp_log_error(&log, "%s: %s", scene_path, err);
    rc = 2;
    goto out;
  }
  if (dt > 0.0) { /* given (checked > 0 above) */
    /* The scene's own bound on steps per frame: a tiny --dt overflowed the int step count. */
    if (!(dt <= s.frame_period) || !(s.frame_period / dt < 100000.5)) {
      palp_log_error(&log, "--dt %g s: must be <= the frame period %g s and give at most 100000 steps per frame",
                     dt, s.frame_period);
      rc = 2;
      goto out;
    }
    s.world.dt = s.frame_period / lround(s.frame_period / dt);
  }
  if (vertices) s.world.mesh.vertex_count = vertices;
  if (frames > 0) s.frames = frames;
  int first = 1, last = 1;
  if (dist) {
    if (!strcmp(dist, "all")) first = 1, last = 4;
    else {
      int d = 0;
      const char *names[] = {"single", "uniform", "gaussian", "gaussian_offset"};
      for (int i = 0; i < 4; ++i)
        if (!strcmp(dist, names[i])) d = i + 1;
      if (!d) {
        palp_log_error(&log, "unknown distribution \"%s\"", dist);
        rc = 2;
        goto out;
      }
      first = last = d;
    }
  }
  if (!quiet)
    printf("palp-run: scene \"%s\", %d vertices, dt %.4g s, %d frames of %.4g s\n", s.name,
           s.world.mesh.vertex_count, s.world.dt, s.frames, s.frame_period);
  /* The prefix's directory (README's `--out out/run` in a fresh clone, which has no out/) is created, one
   * level only and with mode 0777 & umask, as palp-server creates its session log's; deeper missing
   * directories stay an error, said by the CSV's open (until session 81 `--out nodir/run` failed:
   * "cannot write nodir/run_frames.csv"). */
  if (prefix) {
    char dir[RUN_PATH_LEN];
    if (path_fmt(dir, sizeof dir, prefix, "")) {
      rc = 2;
      goto out;
    }
    char *slash = strrchr(dir, '/');
    if (slash && slash != dir) {
      *slash = 0;
      if (mkdir(dir, 0777) == 0) palp_log_info(&log, "created %s/", dir);
    }
  }
  for (int d = first; d <= last; ++d) {
    palp_scene sd = s;
    if (dist)
      for (int c = 0; c < sd.contact_count; ++c) sd.contact[c].def.distribution = (palp_distribution)d;
    char pre[RUN_PATH_LEN], dn[16];
    snprintf(dn, sizeof dn, "_d%d", d);
    if (prefix && path_fmt(pre, sizeof pre, prefix, first != last ? dn : "")) {
      rc = 2;
      break;
    }
    run_summary sum;
    const int r = run(&log, &sd, prefix ? pre : NULL, &sum);
    if (r) {
      if (r > rc) rc = r;
      if (r == 2) break;
      continue;
    }
    const int dd = sd.contact_count ? (int)sd.contact[0].def.distribution : 0;
    /* what the run did not reach is said, with why */
    const double t_end = (double)sd.frames * sd.frame_period;
    char why[96];
    if (!has_release(&sd)) snprintf(why, sizeof why, "no release in this scene");
    else snprintf(why, sizeof why, "not reached: the run ends at %.2f s", t_end);
    char resid[128], back[160], fbrel[160];
    if (isnan(sum.contact_residual_1s)) snprintf(resid, sizeof resid, "(%s)", why);
    else snprintf(resid, sizeof resid, "%.3f mm (%.1f%%)", 1e3 * sum.contact_residual_1s,
                  sum.peak_contact > 0 ? 100.0 * sum.contact_residual_1s / sum.peak_contact : 0.0);
    if (isnan(sum.recovery_time)) snprintf(back, sizeof back, "not back within 5%% of its peak (%s)",
                                          has_release(&sd) ? "by the run's end" : why);
    else snprintf(back, sizeof back, "back within 5%% of its peak %.2f s after release", sum.recovery_time);
    if (isnan(sum.feedback_at_release.x)) snprintf(fbrel, sizeof fbrel, "feedback at release (%s)", why);
    else snprintf(fbrel, sizeof fbrel, "feedback at release (%.3f, %.3f, %.3f) N", sum.feedback_at_release.x,
                  sum.feedback_at_release.y, sum.feedback_at_release.z);
    printf("distribution %-20s contact vertex: peak %.3f mm, 1 s after release %s; top vertex: peak "
           "%.3f mm at %.2f s, %s\n",
           dd ? dist_label[dd] : "-", 1e3 * sum.peak_contact, resid, 1e3 * sum.peak_top, sum.t_peak, back);
    printf("    max |volume error| %.4f%%, peak gauge pressure %.1f Pa, %s, step median %.1f us, p99 %.1f us\n",
           100.0 * sum.max_vol_err, sum.peak_pressure, fbrel, sum.step_median_us, sum.step_p99_us);
    printf("    health: %lld substeps, %lld refactorisations, max link strain %.3f, %lld large-strain steps\n",
           (long long)sum.health.substeps, (long long)sum.health.refactors, sum.health.max_strain,
           (long long)sum.health.large_strain_steps);
  }
out:
  /* the summary on a full disk or a closed pipe was written to nothing: not a success */
  errno = 0;
  if (fflush(stdout) != 0 || ferror(stdout)) {
    palp_log_error(&log, "cannot write the summary to stdout: %s", strerror(errno ? errno : EIO));
    if (!rc) rc = 1;
  }
  palp_log_close(&log);
  return rc;
}
