/*
 * eval.h - the evaluation of the real-time model against the FEM reference
 * (Widmer & Hu 2011, Sec. II-D, Tables V and VI) and the calibration of its
 * parameters. Prefix palp_eval_.
 *
 * A run of either model becomes a palp_eval_record: the displacement of every
 * real-time vertex and the feedback at every contact vertex, per output frame.
 * Two records of the same scene are compared pair by pair (same vertex, same
 * frame) with the statistics of src/stats.h.
 *
 * Units: SI inside (m, N, s); the tables convert to the paper's cm and N at the
 * edge. Functions return PALP_OK or a negative PALP_E* code and write a message
 * into err when one is given.
 */
#ifndef PALP_EVAL_H
#define PALP_EVAL_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "palp.h"
#include "stats.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- records ------------------------------------------------------------- */
typedef struct palp_eval_record {
  int frames;
  int vertex_count;
  int top_vertex;
  double *time;          /* [frames] end of each output frame [s] */
  palp_vec3 *disp;       /* [frames * vertex_count] displacement from rest [m] */
  uint8_t *fixed;        /* [vertex_count] 1 for the clamped rim (equal in both models) */
  int contact_vertex_count;
  int *contact_vertex;   /* [contact_vertex_count] real-time vertex index */
  int *contact_of;       /* [contact_vertex_count] scene contact index */
  palp_vec3 *feedback;   /* [frames * contact_vertex_count] force on the finger [N] */
  double wall_seconds;   /* time taken to produce it */
} palp_eval_record;

void palp_eval_record_destroy(palp_eval_record *r);

/* Runs the real-time model through a scene exactly as palp-run does (apply the
 * profiles at palp_scene_step_time, step, read back per output frame). Fails with
 * PALP_EUNSTABLE when the model blows up (e.g. during a calibration trial). */
int palp_eval_run_rt(const palp_scene *s, palp_eval_record *out, char *err, size_t errlen);

/* ---- comparison ---------------------------------------------------------- */
/* One row of Table V or VI: the statistics of the paired data set. */
typedef struct palp_eval_row {
  size_t n;               /* pairs */
  double rmse;            /* [m] or [N] */
  palp_stats_anova anova; /* real-time values vs reference values, two groups */
  palp_stats_ba ba;       /* a = real-time, b = reference */
  int meets;              /* the paper's verdict: p > 0.05 and agreement > 95% */
  double max_abs_diff;    /* largest |a - b| */
  double ref_peak;        /* largest reference value (scale for the reader) */
  double rt_peak;         /* largest real-time value */
} palp_eval_row;

/* The paired data sets of one distribution, in SI units:
 *   displacement: |u| of every free (non-rim) vertex at every frame, a = real-time,
 *                 b = reference, ordered frame-major (frame 0 vertices ..., frame 1 ...);
 *   force: |f| of the feedback at every contact vertex present in both records at
 *          every frame, paired by (contact, vertex).
 * Arrays are malloc'd; palp_eval_pairs_destroy frees them. */
typedef struct palp_eval_pairs {
  size_t n_disp;
  double *disp_rt, *disp_ref;
  int *disp_frame, *disp_vertex;   /* [n_disp] where each pair comes from */
  size_t n_force;
  double *force_rt, *force_ref;
  int *force_frame, *force_vertex; /* [n_force] */
  int force_vertices; /* contact vertices paired */
} palp_eval_pairs;

int palp_eval_pairs_build(const palp_eval_record *rt, const palp_eval_record *ref, palp_eval_pairs *out,
                          char *err, size_t errlen);
void palp_eval_pairs_destroy(palp_eval_pairs *p);

/* Fills one row from paired values (RMSE, ANOVA of the two groups, Bland-Altman,
 * verdict). Needs n >= 2. */
int palp_eval_row_compute(const double *a, const double *b, size_t n, palp_eval_row *out);

/* ---- the paper's Tables V and VI ------------------------------------------- */
typedef struct palp_eval_paper_row {
  double rmse, f, p, sd, agree_percent; /* cm or N, -, -, cm or N, % */
} palp_eval_paper_row;
/* [0] Table V (displacement, cm), [1] Table VI (force, N); rows I..IV. */
extern const palp_eval_paper_row palp_eval_paper[2][4];

/* ---- calibration ------------------------------------------------------------ */
enum {
  PALP_EVAL_P_E1 = 0,
  PALP_EVAL_P_ETA1,
  PALP_EVAL_P_E2,
  PALP_EVAL_P_ETA2,
  PALP_EVAL_P_A1,
  PALP_EVAL_P_A2,
  PALP_EVAL_P_SUPPORT_K,
  PALP_EVAL_P_SUPPORT_C,
  PALP_EVAL_P_ADDED_MASS,
  PALP_EVAL_P_BULK_FRACTION,
  PALP_EVAL_P_BENDING, /* membrane.bending_stiffness [N m]; fitted only from a start > 0 */
  PALP_EVAL_P_RELAX_K, /* gel.support_relax_modulus [Pa/m]; fitted only from a start > 0 */
  PALP_EVAL_P_RELAX_TAU, /* gel.support_relax_time [s]; fitted only with the modulus */
  PALP_EVAL_P_COUNT
};
/* "E1", "eta1", "E2", "eta2", "a1", "a2", "support_modulus", "support_viscosity", "added_mass",
 * "support_bulk_fraction" */
extern const char *const palp_eval_param_name[PALP_EVAL_P_COUNT];
/* Units for reports: "Pa", "Pa s", ... */
extern const char *const palp_eval_param_unit[PALP_EVAL_P_COUNT];

void palp_eval_params_get(const palp_world_def *w, double p[PALP_EVAL_P_COUNT]);
void palp_eval_params_set(palp_world_def *w, const double p[PALP_EVAL_P_COUNT]);
/* Parses "E1,eta2,..." (or "all") into a mask of 1u << PALP_EVAL_P_*. */
int palp_eval_params_parse_mask(const char *list, unsigned *mask, char *err, size_t errlen);

/* Recovery of the paper's top-contact experiment with the scene's parameters:
 * uniform patch at the pole, the scene's first profile if it is a step (else the
 * paper's 3 N for 2 s), top-vertex displacement magnitude. t_recover is the time
 * after release at which it falls to 5% of its peak, interpolated linearly
 * between frames so that it varies smoothly with the parameters; if it never
 * does within the 2.5 s simulated after release, it is extrapolated from the
 * last frames (and flagged). */
typedef struct palp_eval_recovery {
  double peak;        /* [m] */
  double t_recover;   /* [s] after release */
  double residual_1s; /* displacement 1 s after release / peak [-] */
  int reached;        /* 1 when the 5% level was crossed inside the run */
} palp_eval_recovery;
int palp_eval_recovery_measure(const palp_scene *s, palp_eval_recovery *out, char *err, size_t errlen);

/* A fingertip force-depth reference for calibrate (e.g. the FEM's, palp-eval
 * calibrate --finger): a rigid sphere pressed along -n at the site, the reference
 * force along n at each depth. */
#define PALP_EVAL_FINGER_MAX_DEPTHS 8
typedef struct palp_eval_finger_ref {
  const char *name;   /* the site, for reports */
  palp_vec3 n;        /* outward unit normal at the site */
  double radius;      /* [m] */
  int lesion_count;
  palp_lesion lesion[PALP_MAX_LESIONS];
  int count;          /* depths, 1..PALP_EVAL_FINGER_MAX_DEPTHS */
  double depth[PALP_EVAL_FINGER_MAX_DEPTHS]; /* [m] of the fingertip centre below the undeformed surface */
  double force[PALP_EVAL_FINGER_MAX_DEPTHS]; /* [N] reference, > 0 */
} palp_eval_finger_ref;

/* The real-time model's fingertip force-depth curve (world def wd with the lesions
 * added, stepped at palp_eval_finger_rt_step(wd)): a finger of `radius` whose device is
 * ramped at 5 mm/s to each depth in turn along -n and held (hold_s, hold_s, hold_s / 2
 * with two corrections) so that the proxy, the fingertip centre, sits at depth[k].
 * force[k]: the force along n [N]; depth_real[k]: where the proxy ended [m]. Returns
 * count or -1. palp_eval_finger_rt_at: the same at a step dt [s] of the caller's. */
int palp_eval_finger_rt(const palp_world_def *wd, const palp_lesion *lesions, int lesion_count, palp_vec3 n,
                        double radius, const double *depth, int count, double hold_s, double *force,
                        double *depth_real, char *err, size_t errlen);
int palp_eval_finger_rt_at(const palp_world_def *wd, double dt, const palp_lesion *lesions, int lesion_count,
                           palp_vec3 n, double radius, const double *depth, int count, double hold_s, double *force,
                           double *depth_real, char *err, size_t errlen);

/* The step [s] the fingertip curve drives wd at. 4 ms, the exercises' 250 Hz, where the
 * fingertip's contact is linearised at the current positions (finger_linearise "current"):
 * its held force does not depend on the step (test model_finger_step: within 0.1% at 4, 1
 * and 0.25 ms; the 1,300-vertex long-term set's curve to 4 mm within 0.01% at 4 and 1 ms),
 * and a quarter of the steps makes the fingertip tests 4.5-5x faster. 1 ms otherwise: the
 * "free" linearisation's held force falls with a longer step (the long-term dome 45 deg
 * off the pole at 3 mm: 5.45 / 5.30 / 5.19 / 5.12 N at 0.5 / 1 / 2 / 4 ms) and its sets
 * were fitted and validated at 1 ms (docs/haptics.md, "The held force depends on the physics
 * step"). */
double palp_eval_finger_rt_step(const palp_world_def *wd);

/* A deep press, the check a fitted set must pass before it ships (docs/evaluation.md,
 * docs/materials.md "The refit withdrawn"): the default fingertip (8 mm, 2000 N/m) on the
 * world def wd at 250 Hz (the rate position-driven phantoms run at), its device pressed
 * along -n from 1 mm above the surface in 2 mm levels of travel (10 mm/s, 0.5 s a level)
 * to max_depth [m]. Returns the device depth [m] of the level where the fingertip lost
 * the surface (out of contact after touching it), 0 when it kept it all the way, or -1
 * (err says why). *force: the force along n at the end [N]; *strain: the largest link
 * strain the world saw [-]; either may be NULL. */
double palp_eval_deep_press(const palp_world_def *wd, palp_vec3 n, double max_depth, double *force, double *strain,
                            char *err, size_t errlen);

/* The FE curve of one site (pole, 45deg, 70deg, pole_lesion) from a CSV written by
 * `palp-fem finger` (header site,depth_m,fem_N,..., fem_min_gap_m; '#' provenance lines
 * before it): its rows in file order, at most max, into depth [m], force [N] and gap [m]
 * (gap may be NULL). Returns the count, 0 when the site has no rows, -1 on an
 * unreadable file (err says why). Lets a fine FE level's fingertip be computed once. */
int palp_eval_finger_csv_read(const char *path, const char *site, int max, double *depth, double *force, double *gap,
                              char *err, size_t errlen);

/* The reference force at depth d [m]: piecewise linear through (0, 0) and the
 * reference points, the last segment continued beyond them. */
double palp_eval_finger_ref_at(const palp_eval_finger_ref *f, double d);

/* RMS over every site and depth of F_rt / F_ref(d_rt) - 1 (the reference at the depth
 * the model's proxy reached, palp_eval_finger_ref_at) for the world def wd; NAN when a
 * run fails (err says why). forces (may be NULL) gets the model's forces, site by
 * site, PALP_EVAL_FINGER_MAX_DEPTHS apart. */
double palp_eval_finger_rms(const palp_world_def *wd, const palp_eval_finger_ref *refs, int count, double hold_s,
                            double *forces, char *err, size_t errlen);

typedef struct palp_eval_calib_def {
  unsigned mask;          /* parameters fitted (1u << PALP_EVAL_P_*); default all but a1 */
  int frame_stride;       /* residual every k-th frame, >= 1 */
  int vertex_stride;      /* residual every k-th free vertex, >= 1 */
  double force_weight;    /* force residuals [N] are multiplied by this and compared to
                             displacement residuals [cm]; 0 leaves force out */
  double bias_weight;     /* [-] per reference, lambda_b (mean |u_rt| - mean |u_ref|) [cm] with
                             lambda_b = bias_weight sqrt(N_data): the mean displacement the
                             paper's ANOVA compares; 0 leaves it to the data residuals */
  double peak_weight;     /* [-] per reference, lambda_k 100 (peak_rt - peak_ref) [cm] with
                             lambda_k = peak_weight sqrt(N_data), peak the largest |u| over every
                             vertex and frame: a peak error of x cm costs as much as an RMS error
                             of peak_weight x cm over all data residuals; 0 leaves it out */
  double prior_weight;    /* [cm] Tikhonov weight on ln(p / p_start): a factor e costs
                             as much as this RMS displacement error over all residuals */
  double recovery_weight; /* [cm] penalty: (|t_recover - target| - band)+ / recovery_tol costs
                             as much as this RMS error; 0 = no penalty */
  double recovery_target; /* [s], 1.0 (the paper) */
  double recovery_tol;    /* [s], 0.1 */
  double recovery_band;   /* [s], 0.2: the penalty is a hinge, zero while |t_recover - target|
                             <= band ("about 1 s"), growing linearly outside it */
  double bound_factor;    /* each parameter stays within [p_start / b, p_start b]: the solver's
                             unknown x maps to ln(p / p_start) = ln(b) tanh(x / ln(b)); 0 = no
                             bound. Default 100: directions the data barely see (eta1, a2)
                             otherwise drift by ten decades chasing the last 1% of cost */
  int max_iter;           /* trust-region iterations, 40 */
  double max_seconds;     /* wall-clock budget of the fit [s]; 0 = none. The best point so
                             far is returned when it runs out (status PALP_EVAL_FIT_TIMEOUT) */
  double h_df;            /* finite-difference step in ln p, 3e-3 (0.3%) */
  int verbose;            /* progress to stderr */
  /* Fingertip force-depth references fitted together with the displacement fields
   * (issue 12): residual lambda_f (F_rt / F_ref(d_rt) - 1) per site and depth (the
 * reference interpolated to where the model's proxy got, palp_eval_finger_ref_at), lambda_f =
   * finger_weight sqrt(N_data / N_finger), so that a relative force error e at every
   * point costs as much as an RMS displacement error of finger_weight e [cm]. */
  const palp_eval_finger_ref *finger;
  int finger_count;
  double finger_weight;   /* [cm] per unit relative force error; 0 leaves the finger out */
  double finger_hold_s;   /* holds of palp_eval_finger_rt, 0.3 s in a fit */
} palp_eval_calib_def;

palp_eval_calib_def palp_eval_calib_default_def(void);

/* Fit status beyond GSL's codes (which are positive). */
#define PALP_EVAL_FIT_TIMEOUT 1000
const char *palp_eval_fit_status_text(int status);

typedef struct palp_eval_calib_result {
  double start[PALP_EVAL_P_COUNT];
  double fitted[PALP_EVAL_P_COUNT];
  double rmse_before[4], rmse_after[4]; /* displacement magnitude RMSE per reference [m] */
  double peak_ref[4], peak_before[4], peak_after[4]; /* largest |u| over vertices and frames [m] */
  double cost_before, cost_after;       /* 0.5 sum r^2 of the fit residuals */
  int iterations;
  int evaluations;
  int status;         /* GSL status: 0 converged, GSL_EMAXITER, GSL_ENOPROG (no step lowers
                         the cost), PALP_EVAL_FIT_TIMEOUT (max_seconds ran out) */
  int reason;         /* 1 small step, 2 small gradient */
  double seconds;
  palp_eval_recovery recovery_before, recovery_after;
  int recovery_penalised; /* 1 when the penalty residual was active in the final fit */
  double finger_rms_before, finger_rms_after; /* palp_eval_finger_rms; NAN without references */
} palp_eval_calib_result;

/* Fits the real-time parameters of `base` (its world def is the start) so that
 * running the scenes scenes[0..count) reproduces refs[0..count) (the reference
 * records, e.g. the FEM under the four distributions). Residuals: the real-time
 * minus reference displacement components [cm] of every vertex_stride-th free
 * vertex at every frame_stride-th frame, optionally feedback, plus the prior and
 * recovery terms. Parameters are fitted as x = ln(p / p_start) (positive, and equal
 * finite-difference steps in relative terms). GSL trust region (Levenberg-
 * Marquardt), QR solver, forward-difference Jacobian. */
int palp_eval_calibrate(const palp_scene *scenes, const palp_eval_record *refs, int count,
                        const palp_eval_calib_def *def, palp_eval_calib_result *out, char *err,
                        size_t errlen);

/* Writes a parameter file in the format of config/params/calibrated.json; material names
 * the FEM profile the parameters were fitted against (written as "material" so that a
 * scene using the file is evaluated against it; NULL or "" writes none). */
int palp_eval_params_write(const char *path, const palp_world_def *w, const char *material, const char *comment,
                           char *err, size_t errlen);


/* ---- sound statistics beside the paper's (docs/statistics.md) ------------------ */
/* Equivalence margins, from perception (docs/statistics.md cites the sources):
 * displacement: 1 mm (finger-span discrimination), but no more than 15% of the
 * reference's peak (the compliance discrimination threshold: under a given force a
 * dent 15% deeper is a 15% softer phantom) and no less than 5% of it (the RMSE
 * criterion): max(5% peak, min(1 mm, 15% peak)). On the soft reproduction (peaks
 * 15-35 mm) that is the old max(1 mm, 5%); on the long-term domes (peaks 0.5-0.8 mm)
 * it is 15% of the peak, where 1 mm was larger than the whole signal.
 * force: 15% of the reference's peak force (compliance discrimination ~15-22%). */
#define PALP_EVAL_MARGIN_DISP_ABS 0.1   /* [cm] */
#define PALP_EVAL_MARGIN_DISP_REL 0.05  /* [-] of the reference peak */
#define PALP_EVAL_MARGIN_DISP_JND 0.15  /* [-] of the reference peak */
#define PALP_EVAL_MARGIN_FORCE_REL 0.15 /* [-] of the reference peak */
/* The displacement margin [cm] for a reference peak [cm]. */
static inline double palp_eval_disp_margin(double ref_peak_cm) {
  const double jnd = PALP_EVAL_MARGIN_DISP_JND * ref_peak_cm;
  const double floor_rel = PALP_EVAL_MARGIN_DISP_REL * ref_peak_cm;
  const double capped = PALP_EVAL_MARGIN_DISP_ABS < jnd ? PALP_EVAL_MARGIN_DISP_ABS : jnd;
  return capped > floor_rel ? capped : floor_rel;
}
#define PALP_EVAL_TOST_ALPHA 0.05
#define PALP_EVAL_BOOT_RESAMPLES 4000
#define PALP_EVAL_BOOT_SEED 20110817ull
#define PALP_EVAL_BOOT_MIN_BLOCKS 4 /* fixed: the tables are reproducible */

/* One run's paired data set, with the run as the unit of analysis: its vertex-frames
 * are repeated measures. The per-frame mean difference dbar_f (frames values) is the
 * series whose autocorrelation decides how much the run knows about its bias. */
typedef struct palp_eval_sound {
  int frames;
  double bias;          /* mean of all differences = mean of dbar_f [cm or N] */
  double frame_sd;      /* SD of dbar_f */
  double r1;            /* lag-1 autocorrelation of dbar_f (0 when dbar_f is constant) */
  double n_eff;         /* AR(1) effective number of frames, n (1 - r1) / (1 + r1) in [1, n] */
  double margin;        /* equivalence margin, -+ [cm or N] */
  int tost_valid;       /* n_eff >= 2: a t reference with n_eff - 1 df exists */
  palp_stats_tost tost; /* SE = frame_sd / sqrt(n_eff), df = n_eff - 1 */
  palp_stats_boot boot; /* moving blocks of frames, b from the AR(1) rule */
  int boot_reliable;    /* at least PALP_EVAL_BOOT_MIN_BLOCKS blocks per resample: with fewer, the
                           resamples are near copies of the record and the SE is far too small */
  int boot_equivalent;  /* boot_reliable and the bootstrap's 90% interval inside -+ margin */
  int equivalent;       /* tost_valid && tost.equivalent && boot_equivalent: both SEs must agree */
} palp_eval_sound;

/* a, b: n pairs ordered frame-major with n / frames pairs per frame (as
 * palp_eval_pairs_build makes them); margin > 0; seed for the bootstrap. */
int palp_eval_sound_compute(const double *a, const double *b, size_t n, int frames, double margin,
                            unsigned long long seed, palp_eval_sound *out);

/* Several runs pooled: repeated-measures Bland-Altman (runs as subjects, their
 * vertex-frames as repeated measures) and TOST with the run biases as the
 * observations (SE = SD of the run biases / sqrt(runs), runs - 1 df). */
typedef struct palp_eval_sound_pool {
  int runs;
  double margin;
  palp_stats_ba_rm ba;
  int tost_valid; /* runs >= 2 */
  palp_stats_tost tost;
} palp_eval_sound_pool;

/* diff holds the differences a - b of run g in diff[start[g] .. start[g+1]); margin:
 * the smallest of the runs' margins (the strictest). */
int palp_eval_sound_pool_compute(const double *diff, const size_t *start, int runs, double margin,
                                 palp_eval_sound_pool *out);


/* ---- runs over random contact sites and force levels (docs/statistics.md) ----------- */
/* The unit of analysis is a run: one load distribution at one contact site and one
 * force level, FEM vs real-time over the step protocol. A distribution's runs are
 * the independent observations its equivalence test counts. */
#define PALP_EVAL_SITES_MAX_RUNS 64 /* per distribution (the pooled statistics' bound) */
#define PALP_EVAL_RECOVERY_LEVEL 0.05 /* "recovered": back within 5% of the peak */

typedef struct palp_eval_site {
  double polar_deg, azimuth_deg; /* on the dome, polar 0 = the pole */
} palp_eval_site;

/* `count` sites uniform over the dome's area between the polar angles polar_min_deg and
 * polar_max_deg (cos(polar) uniform, azimuth uniform on [0, 360)), from a SplitMix64
 * stream started at `seed`: the same seed gives the same sites on every platform.
 * Errors (PALP_EINVAL): count < 1, NULL, 0 <= min < max <= 90 violated. */
int palp_eval_sites_draw(unsigned long long seed, int count, double polar_min_deg, double polar_max_deg,
                         palp_eval_site *out);

/* Time after t_off [s] at which |u| of `vertex` falls to PALP_EVAL_RECOVERY_LEVEL of its
 * peak (over the whole record), interpolated linearly between frames; *reached = 0 and
 * *t = NAN when it never does inside the record. */
int palp_eval_record_recovery(const palp_eval_record *r, int vertex, double t_off, double *t, int *reached);

/* One run's figures (displacement in cm, force in N). */
typedef struct palp_eval_run {
  int distribution;      /* 1..4 */
  int site;              /* index into the drawn sites */
  double polar_deg, azimuth_deg;
  double force;          /* step magnitude [N] */
  int ok;                /* 0: a model failed (message in `error`); the figures are unset */
  char error[160];
  int frames;
  double disp_bias, disp_rmse, disp_max_abs; /* over all free vertex-frames */
  double disp_peak_rt, disp_peak_ref;        /* largest |u| of each model in the run */
  double peak_error;                         /* (peak_rt - peak_ref) / peak_ref [-] */
  double disp_margin;                        /* max(5% of peak_ref, min(1 mm, 15% of it)): palp_eval_disp_margin */
  double disp_r1, disp_n_eff;                /* of the per-frame mean difference */
  int has_force;
  double force_bias, force_rmse, force_peak_ref, force_margin; /* 15% of force_peak_ref */
  int peak_vertex;                           /* the FEM's most displaced vertex */
  double recovery_rt, recovery_ref;          /* [s] after release, at peak_vertex */
  int recovered_rt, recovered_ref;
  double rt_seconds, ref_seconds;
  int ref_from_cache;
} palp_eval_run;

/* Fills the run's displacement/force figures from its paired data (pairs in cm and N,
 * frame-major) and records; t_off is the step's release time [s]. */
int palp_eval_run_compute(const palp_eval_pairs *p, const palp_eval_record *rt, const palp_eval_record *ref,
                          double t_off, palp_eval_run *out);

/* One quantity (displacement or force) of one distribution over its runs. */
typedef struct palp_eval_sites_summary {
  int runs;
  size_t n;              /* vertex-frame pairs pooled */
  double margin;         /* the strictest of the runs' margins */
  palp_eval_row paper;   /* paper-literal: RMSE, ANOVA, Bland-Altman over the pooled pairs */
  palp_eval_sound_pool pool; /* runs as units: TOST (t over run biases, runs - 1 df) and
                                repeated-measures Bland-Altman (runs as subjects) */
  double frames_r1;      /* lag-1 autocorrelation of the runs' per-frame mean differences,
                            joined run after run */
  palp_stats_boot boot;  /* moving-block bootstrap of the mean of that joined series */
  int boot_reliable;     /* at least PALP_EVAL_BOOT_MIN_BLOCKS blocks per resample */
  int boot_equivalent;   /* boot_reliable and its 90% interval inside -+ margin */
} palp_eval_sites_summary;

/* a, b: the pooled pairs; run g holds [start[g], start[g+1]) with frames frames each
 * (frame-major, the same count of pairs in every frame of a run); margin[g] the run's
 * equivalence margin; runs in 2..PALP_EVAL_SITES_MAX_RUNS. */
int palp_eval_sites_summarise(const double *a, const double *b, const size_t *start, int runs, int frames,
                              const double *margin, unsigned long long seed, palp_eval_sites_summary *out);


/* The lag-1 autocorrelation of the per-frame mean difference above which the caveats say
 * the paper-literal ANOVA's p measures the number of pairs: at r1 = 0.5 the AR(1) effective
 * number of frames n (1 - r1) / (1 + r1) is a third of n, and it falls to 0 as r1 -> 1.
 * Below it (force: r1 near -0.24 in a 400-frame run) the caveat names the repeated
 * measures only, since the frames are then close to independent. */
#define PALP_EVAL_CAVEAT_R1 0.5

/* ---- the evaluation report ---------------------------------------------------- */
typedef struct palp_eval_dist {
  int distribution;   /* 1..4 (I..IV) */
  palp_eval_row disp; /* Table V row, data in cm */
  palp_eval_row force; /* Table VI row, data in N; valid when has_force */
  int has_force;
  palp_eval_sound disp_sound, force_sound; /* the second table (force when has_force) */
  int disp_vertices;  /* free vertices per frame */
  int force_vertices; /* paired contact vertices per frame */
  double rt_seconds, ref_seconds;
  int ref_from_cache;
} palp_eval_dist;

typedef struct palp_eval_report {
  char scene[512];       /* scene file */
  char scene_name[64];
  char parameters[512];  /* what the real-time parameters were (file or "scene") */
  int frames;
  double frame_period;   /* [s] */
  int vertex_count;
  int ref_level;         /* FEM mesh level */
  int ref_elements, ref_nodes;
  /* the FEM's material profile (palp_fem_config.material, or "custom, ... C10 reading" for
   * materials a FEM config set by hand) and load map ("patch" / "point"): the profile decides
   * the whole reference, so the tables name it (session 82) */
  char ref_material[64];
  char ref_load_map[8];
  int dist_count;
  palp_eval_dist dist[4];
  palp_eval_sound_pool pool[2]; /* displacement, force over the runs (valid when pooled[t]) */
  int pooled[2];
} palp_eval_report;

/* "I", "II", "III", "IV" */
const char *palp_eval_roman(int distribution);
/* Both tables beside the paper's, readable. */
void palp_eval_report_print(FILE *out, const palp_eval_report *r);
/* tables.csv (one row per table and distribution), tables.json, tables.md. */
int palp_eval_report_write(const char *dir, const palp_eval_report *r, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
