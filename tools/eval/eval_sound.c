/*
 * eval_sound.c - the second table beside the paper's Tables V and VI: equivalence
 * of the bias (TOST at perceptual margins) with the run as the unit of analysis,
 * and repeated-measures Bland-Altman limits over several runs.
 *
 * Why: the paper's ANOVA treats every vertex-frame of one deterministic run as an
 * independent observation. They are not: the per-frame mean difference changes
 * smoothly with the load (lag-1 autocorrelation ~0.99), so the information about
 * the bias is that of a handful of frames (AR(1) effective size), and the
 * between-run variation of the bias is what a new contact would see.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "eval.h"

int palp_eval_sound_compute(const double *a, const double *b, size_t n, int frames, double margin,
                            unsigned long long seed, palp_eval_sound *out) {
  if (!a || !b || !out || frames < 3 || n % (size_t)frames != 0 || n == 0 || !(margin > 0.0)) return PALP_EINVAL;
  const size_t per = n / (size_t)frames, nf = (size_t)frames;
  double *dbar = malloc(sizeof(double) * nf);
  double *work = malloc(sizeof(double) * PALP_EVAL_BOOT_RESAMPLES);
  if (!dbar || !work) {
    free(dbar), free(work);
    return PALP_ENOMEM;
  }
  /* dbar_f = mean over the frame's pairs of a - b [cm or N] */
  for (size_t f = 0; f < nf; ++f) {
    palp_stats_sum s = {0.0, 0.0};
    for (size_t i = 0; i < per; ++i) palp_stats_sum_add(&s, a[f * per + i] - b[f * per + i]);
    dbar[f] = palp_stats_sum_value(&s) / (double)per;
  }
  palp_eval_sound o;
  memset(&o, 0, sizeof o);
  o.frames = frames;
  o.margin = margin;
  double ssd;
  palp_stats_mean_ssd(dbar, nf, &o.bias, &ssd);
  o.frame_sd = sqrt(ssd / (double)(nf - 1));
  int rc = PALP_OK;
  if (palp_stats_autocorr1(dbar, nf, &o.r1) != PALP_OK) o.r1 = 0.0; /* constant series */
  o.n_eff = palp_stats_neff_ar1(nf, o.r1);
  o.tost_valid = o.n_eff >= 2.0;
  if (o.tost_valid)
    rc = palp_stats_tost_t(o.bias, o.frame_sd / sqrt(o.n_eff), o.n_eff - 1.0, -margin, margin,
                           PALP_EVAL_TOST_ALPHA, &o.tost);
  if (!rc)
    rc = palp_stats_block_bootstrap_mean(dbar, nf, palp_stats_block_length_ar1(nf, o.r1),
                                         PALP_EVAL_BOOT_RESAMPLES, seed, 1.0 - 2.0 * PALP_EVAL_TOST_ALPHA, work,
                                         &o.boot);
  free(dbar), free(work);
  if (rc) return rc;
  o.boot_reliable = o.boot.blocks >= PALP_EVAL_BOOT_MIN_BLOCKS;
  o.boot_equivalent = o.boot_reliable && o.boot.ci_lower > -margin && o.boot.ci_upper < margin;
  o.equivalent = o.tost_valid && o.tost.equivalent && o.boot_equivalent;
  *out = o;
  return PALP_OK;
}

int palp_eval_sound_pool_compute(const double *diff, const size_t *start, int runs, double margin,
                                 palp_eval_sound_pool *out) {
  if (!diff || !start || !out || runs < 2 || !(margin > 0.0)) return PALP_EINVAL;
  palp_eval_sound_pool o;
  memset(&o, 0, sizeof o);
  o.runs = runs;
  o.margin = margin;
  int rc = palp_stats_bland_altman_rm(diff, start, runs, &o.ba);
  if (rc) return rc;
  /* the runs' biases: one observation per unit of analysis */
  double bias[64];
  if (runs > 64) return PALP_EINVAL;
  for (int g = 0; g < runs; ++g) {
    double ssd;
    palp_stats_mean_ssd(diff + start[g], start[g + 1] - start[g], &bias[g], &ssd);
  }
  double m, ssd;
  palp_stats_mean_ssd(bias, (size_t)runs, &m, &ssd);
  o.tost_valid = 1;
  rc = palp_stats_tost_t(m, sqrt(ssd / (double)(runs - 1)) / sqrt((double)runs), (double)(runs - 1), -margin, margin,
                         PALP_EVAL_TOST_ALPHA, &o.tost);
  if (rc) return rc;
  *out = o;
  return PALP_OK;
}
