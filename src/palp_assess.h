/*
 * palp_assess.h - exercises with hidden lesions and the metrics of a palpation
 * session (docs/assessment.md).
 *
 * An exercise (JSON, config/exercises/) names a phantom scene, hides lesions in it,
 * defines the three pressure bands (light / medium / deep, MammaCare's three levels
 * as fingertip indentation and/or force bands), a time limit, the trainee's
 * instructions and a rubric. palp_assess() turns a session (the fingertip's samples
 * and the trainee's findings) into the MammaCare competencies: sensitivity, false
 * positives, thoroughness per pressure band, search pattern, plus time, forces and a
 * 0-100 score.
 *
 * Pure: no DDS, no SQLite; the only I/O is reading exercise and scene files. SI units
 * inside (m, N, s); the JSON keys carry their unit (depth_mm, ...). Functions return 0
 * or a negative PALP_E* code.
 */
#ifndef PALP_ASSESS_H
#define PALP_ASSESS_H

#include <stddef.h>
#include <stdint.h>

#include "palp.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- exercises ------------------------------------------------------------ */
enum { PALP_BAND_LIGHT = 0, PALP_BAND_MEDIUM = 1, PALP_BAND_DEEP = 2, PALP_BAND_COUNT = 3 };
const char *palp_band_name(int band); /* "light", "medium", "deep" */

/* A pressure band: a sample is in it when every bound given holds, min <= x < max. */
typedef struct palp_band {
  int has_depth, has_force;
  double depth_min, depth_max; /* fingertip indentation [m] */
  double force_min, force_max; /* |force| [N] */
} palp_band;

/* A hidden lesion, placed the way an instructor thinks of it: where on the dome, how
 * deep (its centre below the surface, along the normal), how big, how hard. */
typedef struct palp_exercise_lesion {
  double polar;           /* angle from the pole [rad] */
  double azimuth;         /* [rad] */
  double depth;           /* centre below the surface [m] */
  double diameter;        /* [m] */
  double stiffness_ratio; /* E_lesion / E_gel [-] */
} palp_exercise_lesion;

typedef enum palp_pattern {
  PALP_PATTERN_UNSYSTEMATIC = 0,
  PALP_PATTERN_VERTICAL_STRIP = 1,
  PALP_PATTERN_CIRCLES = 2,
  PALP_PATTERN_RADIAL = 3
} palp_pattern;
const char *palp_pattern_name(palp_pattern p); /* "unsystematic", "vertical_strip", "circles", "radial" */

/* The score's components, in this order everywhere (rubric weights, passes, results). */
enum {
  PALP_METRIC_SENSITIVITY = 0,
  PALP_METRIC_FALSE_POSITIVES,
  PALP_METRIC_THOROUGHNESS,
  PALP_METRIC_PATTERN,
  PALP_METRIC_TIME,
  PALP_METRIC_FORCE,
  PALP_METRIC_COUNT
};
const char *palp_metric_name(int metric);
/* What a trainee who did not pass the metric works on, in her words ("finding the lumps"): her
 * station and her web page say the same (session 64). */
const char *palp_metric_to_work_on(int metric);
/* A figure judged against a mark (a score against the rubric's pass mark, a coverage in % against
 * its band's), as printed to one decimal: rounded to 0.1, except that one that missed the mark never
 * reads as reaching it (floored to 0.1: 69.96 against 70 prints 69.9, not 70.0) and one that reached
 * it never reads as below it (ceiled to 0.1). mark NAN (not known): a figure that missed is floored
 * (so it never rounds up to a mark on a whole tenth), one that reached is rounded. A session's score
 * is printed so by the review, her station and her page alike: mark NAN and reached = the session
 * passed, so a score not passed is floored everywhere and the three agree. Session 81 review:
 * "score 70.0 / 100 (pass at 70): FAIL". */
double palp_shown_tenths(double value, double mark, int reached);
/* What to work on when a session failed on its score alone (every metric passed, the weighted score
 * under the pass mark): without it her station listed nothing under "To work on" (session 81 review). */
#define PALP_SCORE_TO_WORK_ON "raising the score (below the pass mark)"

typedef struct palp_rubric {
  double weight[PALP_METRIC_COUNT]; /* >= 0, at least one > 0; the score is their weighted mean x 100 */
  double pass_sensitivity;          /* share of lesions found [0, 1] */
  int pass_max_false_positives;
  double pass_coverage[PALP_BAND_COUNT]; /* share of the surface palpated per band [0, 1] */
  palp_pattern pass_pattern;        /* UNSYSTEMATIC = any pattern passes; otherwise this one or (if
                                       pass_any_systematic) any systematic one */
  int pass_any_systematic;
  int pass_max_out_of_range;        /* force episodes above max_force */
  double pass_score;                /* [0, 100] */
  /* The strips' order (palp_pattern_evidence.sweep_monotony) in a vertical-strip search, for
   * rubrics that ask for it (docs/assessment.md, "Score"); both 0 by default, which gives a
   * vertical-strip search the pattern's full credit and pass in any order. */
  double strip_order_share;         /* [0, 1]: share of a vertical-strip search's pattern credit that
                                       rests on the order: credit = 1 - share (1 - order) */
  double pass_strip_order;          /* [0, 1]: a vertical-strip search passes the pattern only with its
                                       strips in order at least this */
} palp_rubric;

/* What a trainee is told of the lesions when her session ends (the exercise's "debrief"). */
typedef enum palp_debrief_level {
  PALP_DEBRIEF_NONE = 0,   /* nothing: the instructor's review tells */
  PALP_DEBRIEF_COUNT = 1,  /* how many she found, and how many marks found nothing */
  PALP_DEBRIEF_LESIONS = 2 /* and where each lesion is, found or missed */
} palp_debrief_level;

/* Where the lesions are (the exercise's "placement"; docs/assessment.md, "Lesions drawn for each
 * session"). A practice exercise whose lesions stay put is learnt, not examined: after one debrief
 * the trainee knows where to press. RANDOM draws them anew for each session, on the server. */
typedef enum palp_placement_kind {
  PALP_PLACEMENT_FIXED = 0,  /* where the file says (the default) */
  PALP_PLACEMENT_RANDOM = 1, /* each lesion's polar and azimuth drawn for each session
                                (palp_exercise_draw); the file gives their size, depth, stiffness */
  PALP_PLACEMENT_DRAWN = 2   /* drawn: the places the file carries are one draw's (the session
                                log's copy of a random exercise), seed says which */
} palp_placement_kind;
typedef struct palp_exercise_placement {
  palp_placement_kind kind;
  double polar_min, polar_max; /* [rad] from the pole: the band the lesions are drawn in */
  double min_gap;              /* [m] along the skin between two lesions' edges (their surface
                                  discs, a diameter across), so that each is felt apart */
  uint32_t seed;               /* DRAWN: the draw's seed */
  int per_run;                 /* RANDOM ("per": "run"): one draw for a whole server run, every
                                  session of it the same lesions (an examination: fair within a
                                  class, new for the next); 0 ("session", the default): each its own */
  int count_min, count_max;    /* RANDOM: how many of the file's lesions a session hides, drawn
                                  uniformly in [min, max] (the file's "count"; default all of them,
                                  0 allowed: a breast with no lump teaches not to mark one);
                                  DRAWN: as the file said */
  int source[PALP_MAX_LESIONS];/* DRAWN by palp_exercise_draw: the file's lesion (its index) each of
                                  these is, in the file's order */
} palp_exercise_placement;

#define PALP_EXERCISE_TEXT 1024
#define PALP_EXERCISE_TITLE_MAX 63 /* bytes: the catalogue's name of its phantom (palp_Phantom.name) */
typedef struct palp_exercise {
  char name[64];
  char title[128];
  char phantom[512];      /* the scene file as written in the exercise */
  char phantom_path[1024]; /* resolved against the exercise file's folder */
  char instructions[PALP_EXERCISE_TEXT];
  double time_limit;      /* [s] */
  int lesion_count;
  palp_exercise_lesion lesion[PALP_MAX_LESIONS];
  palp_band band[PALP_BAND_COUNT];
  double max_force;       /* [N]: above it a press is out of range */
  double match_margin;    /* [m]: a finding within lesion radius + margin of a lesion's surface
                             projection finds it */
  palp_rubric rubric;
  palp_debrief_level debrief; /* "debrief": none (default), count, lesions */
  palp_exercise_placement placement; /* "placement": fixed (default), random, drawn */
} palp_exercise;

/* Loads or parses an exercise. base_dir resolves a relative "phantom" (NULL or "" = as
 * written). On error returns a negative code and writes a message naming the field,
 * e.g. "lesions[1].depth_mm: must be > 0", into err. Geometry against the dome is
 * checked by palp_exercise_lesions (it needs the phantom's radius). */
int palp_exercise_load(const char *path, palp_exercise *out, char *err, size_t errlen);
int palp_exercise_parse(const char *json, const char *base_dir, palp_exercise *out, char *err, size_t errlen);

/* The exercise's lesions as model lesions (centres in metres) on a dome of the given
 * radius: centre = (R - depth) n(polar, azimuth). Fills up to cap and returns the
 * count, or PALP_EINVAL (message in err) when a lesion does not fit inside the dome
 * above its base, or (a fixed or drawn exercise) when two lesions' discs on the skin
 * overlap (palp_exercise_lesion_gap < 0). */
int palp_exercise_lesions(const palp_exercise *ex, double dome_radius, palp_lesion *out, int cap, char *err,
                          size_t errlen);
/* A lesion's surface projection: the point of the rest dome above its centre [m]. */
palp_vec3 palp_exercise_lesion_surface(const palp_exercise_lesion *l, double dome_radius);
/* The gap along the skin between two lesions' surface discs [m]: the great-circle arc between the
 * points above their centres less their two radii (negative: the discs overlap). The random draw's
 * min_gap_mm is measured so. */
double palp_exercise_lesion_gap(const palp_exercise_lesion *a, const palp_exercise_lesion *b, double dome_radius);

/* Loads the exercise's phantom and hides its lesions in it. A phantom that declares lesions of
 * its own is refused (PALP_EINVAL, the message naming its file): they would be felt and never
 * graded. A RANDOM exercise hides at most count_max of its lesions in a session, any of them: each
 * set of count_max (all of them by default) is drawn once (seed 0), and the first, the first
 * count_max listed, is the scene's. So a file of which some session's lesions could not be placed
 * in its band is refused at load, not at a trainee's session, and a pool (more listed than a
 * session hides) need not fit all at once. */
int palp_exercise_scene(const palp_exercise *ex, palp_scene *out, char *err, size_t errlen);

/* One session's lesions of a RANDOM exercise (src/placement.c): out is ex with how many of its
 * lesions drawn (uniformly in [count_min, count_max]; which ones, uniformly, kept in the file's
 * order, placement.source naming each), and each one's polar and azimuth drawn, uniformly over the skin of the band [polar_min, polar_max] (cos(polar)
 * uniform), each inside the dome above its base and at least min_gap from every other along the
 * skin; kind DRAWN, seed kept. The same seed gives the same places on every machine. A FIXED or
 * DRAWN exercise is copied unchanged. PALP_EINVAL (message in err) when the lesions cannot be
 * placed (10,000 tries at each of 100 fresh starts). */
int palp_exercise_draw(const palp_exercise *ex, double dome_radius, uint32_t seed, palp_exercise *out, char *err,
                       size_t errlen);
/* The exercise file's text with a draw written in: the lesions drawn (each the file's object it
 * came from, placement.source) with their polar_deg and azimuth_deg, and "placement" {"kind":
 * "drawn", "seed", "polar_deg", "min_gap_mm", "count"}; parsed back it gives drawn's lesions (places
 * within 1e-12 rad). For the session log, so that the review assesses the
 * lesions the trainee searched. malloc'd; NULL when file_json does not parse or memory runs out. */
char *palp_exercise_drawn_json(const char *file_json, const palp_exercise *drawn);

/* ---- a session ------------------------------------------------------------- */
/* One sample of the fingertip, as the server steps it (palp_local_model and
 * palp_world_finger_contacts). triangles may be NULL: the footprint is then the disc
 * of `area` around `point`. */
typedef struct palp_assess_sample {
  double t;           /* [s] */
  palp_vec3 device;   /* [m] */
  palp_vec3 proxy;    /* fingertip centre [m] */
  palp_vec3 force;    /* of the phantom on the finger [N] */
  int contact;        /* 1 when touching */
  palp_vec3 point;    /* contact point [m] */
  double area;        /* footprint [m^2] */
  int triangle_count;
  const int *triangles; /* touched triangles (mesh indices) */
} palp_assess_sample;

/* A "lump here" mark; a withdrawn mark does not count. */
typedef struct palp_finding {
  double t;        /* [s] */
  palp_vec3 point; /* [m], on or near the surface */
  int withdrawn;
} palp_finding;

enum { PALP_FINDING_FALSE = -1, PALP_FINDING_WITHDRAWN = -2, PALP_FINDING_DUPLICATE = -3 };

/* The search pattern's evidence (docs/assessment.md, "Search pattern"). */
typedef struct palp_pattern_evidence {
  double path_length;      /* contact point's path while touching [m] */
  double plan_length;      /* seen from above the pole, between stations 8 mm apart while touching: what
                              the shares weigh [m] */
  int presses;             /* touch-downs */
  double contact_time;     /* [s] */
  double share_axial;      /* plan path within 20 deg of its dominant axis [-] */
  double axis_deg;         /* that axis [deg] from +x */
  double share_tangential; /* within 20 deg of the circle about the pole [-] */
  double share_radial;     /* within 20 deg of the radius from the pole [-] */
  double sweep_monotony;   /* strips: share of the steps between successive strips (across the axis) that
                              keep the direction of the step before: 1 when the strips follow each other
                              across the breast in order; 0 with fewer than two steps (three strips) [-] */
  double overlap;          /* covered area's mean number of separate visits [-] */
  double gap_share;        /* dome area never palpated [-] */
  double largest_gap;      /* largest connected unpalpated area [m^2] */
  int strips;              /* strips: runs along the axis at least 16 mm long (docs/assessment.md) */
} palp_pattern_evidence;

typedef struct palp_assess_result {
  /* sensitivity and false positives */
  int lesion_count, found;
  int lesion_found[PALP_MAX_LESIONS]; /* index of the finding that found it, or -1 */
  int findings, withdrawn, false_positives, duplicates;
  double sensitivity; /* found / lesion_count (1 when there are none) */
  /* thoroughness */
  double coverage[PALP_BAND_COUNT]; /* share of the dome's area palpated in each band */
  double coverage_any;
  /* search pattern */
  palp_pattern pattern;
  palp_pattern_evidence evidence;
  /* time and force */
  double duration;       /* first to last sample [s] */
  double peak_force;     /* [N] */
  int out_of_range;      /* episodes with |force| > max_force */
  double out_of_range_time; /* [s] */
  /* rubric */
  double component[PALP_METRIC_COUNT]; /* each in [0, 1] */
  int pass_metric[PALP_METRIC_COUNT];
  int pass; /* every metric and the score */
  double score; /* [0, 100] */
} palp_assess_result;

/* Assesses a session on `mesh` (the phantom's rest mesh). finger_radius [m] turns the
 * proxy into an indentation: R + r - |proxy|. finding_match (optional, [finding_count])
 * receives each finding's lesion index or a PALP_FINDING_* code; coverage (optional,
 * [vertex_count]) receives each vertex's bands as bits 1 << band. Time and memory are
 * O(samples x footprint + vertices). */
int palp_assess(const palp_exercise *ex, const palp_mesh *mesh, double finger_radius, const palp_assess_sample *samples,
                int sample_count, const palp_finding *findings, int finding_count, palp_assess_result *out,
                int *finding_match, uint8_t *coverage);

/* Matches findings to the exercise's lesions exactly as palp_assess does, without a session: a
 * standing finding reaches a lesion whose surface projection on the dome of dome_radius [m] (|rest
 * pole|) lies within its radius + match_margin of the finding projected onto the dome; the lesions
 * found are a maximum matching of findings to the lesions they reach (findings in order each taking
 * the nearest that keeps it maximum), an unmatched finding that reaches one a duplicate, one that
 * reaches none false (docs/assessment.md, "Sensitivity"). PALP_ENOMEM when the matching's table
 * cannot be allocated. Fills out's lesion_count, found, lesion_found, findings, withdrawn, false_positives,
 * duplicates and sensitivity, the rest zeroed; match as palp_assess's finding_match. The server
 * debriefs a trainee with it (docs/assessment.md, "Debrief"). */
int palp_assess_findings(const palp_exercise *ex, double dome_radius, const palp_finding *findings, int finding_count,
                         palp_assess_result *out, int *finding_match);

/* A session's fingertip is sampled for the assessment every this many physics steps (the steps whose
 * world frame it divides): round(physics_hz / sample_hz), 1 when the physics is slower; sample_hz is
 * the server's `assess_sample_hz`, PALP_ASSESS_SAMPLE_HZ by default. The server logs by it, and a
 * station that shows its trainee's coverage takes the same steps' local models. */
#define PALP_ASSESS_SAMPLE_HZ 100.0 /* [Hz]: a 10 ms path resolution, 0.5 mm at a 5 cm/s glide */
int palp_assess_sample_every(double physics_hz, double sample_hz);

/* Out of touch for longer than this [s] is a lift; shorter losses of contact (the surface
 * recovering more slowly than the finger rises) keep the stroke going. palp_assess counts its
 * presses (touch-downs) by it, and palp_assess_touches splits a session by it. */
#define PALP_ASSESS_LIFT_GAP_S 0.25

/* One touch: the fingertip on the phantom from a touch-down to its lift, as palp_assess counts
 * presses. Places are contact points on the phantom's surface, not the fingertip's centre. */
typedef struct palp_touch {
  double t_on, t_off;      /* first and last sample in contact [s] */
  palp_vec3 first_point;   /* contact point at the touch-down [m] */
  palp_vec3 last_point;    /* at the lift [m] */
  double path_length;      /* the fingertip's path over the dome while touching, as palp_assess's [m] */
  double peak_force;       /* max |force| [N] */
  double peak_indentation; /* max R + r - |proxy| below the rest surface [m] */
  int contact_samples;     /* samples in contact: the touches split the session's contact samples in order */
} palp_touch;

/* Splits a session's samples into touches (the same samples palp_assess takes, in time order).
 * Writes the first cap of them into out (out may be NULL with cap 0) and returns how many there
 * are: palp_assess's evidence.presses, and their path lengths sum to its path_length. */
int palp_assess_touches(const palp_assess_sample *samples, int sample_count, double dome_radius,
                        double finger_radius, palp_touch *out, int cap);

/* A fingertip's depth [m] (its indentation, docs/naming.md "fingertip depth"): how far its centre,
 * the proxy, lies below where it would touch the undeformed dome, R + r - |proxy|, for a dome of
 * radius R centred at the origin and a fingertip of radius r. What the bands grade, in the
 * assessment, palp-web and the station alike. */
double palp_fingertip_depth(double dome_radius, double tip_radius, palp_vec3 proxy);
/* The band of an indentation [m] and force magnitude [N], or -1 outside every band. */
int palp_exercise_band(const palp_exercise *ex, double indentation, double force);
/* The same rule on three bands alone (light, medium, deep): the first whose every given bound
 * holds, or -1. palp-web classifies a live fingertip with it, as the assessment does. */
int palp_band_of(const palp_band band[PALP_BAND_COUNT], double indentation, double force);

#ifdef __cplusplus
}
#endif
#endif
