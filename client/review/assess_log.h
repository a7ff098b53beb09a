/* Metrics from the log (assess_log.c): a session's exercise, rest mesh, finger samples and
 * findings turned into palp_assess, the same call the tests make in process. */
#ifndef PALP_REVIEW_ASSESS_LOG_H
#define PALP_REVIEW_ASSESS_LOG_H

#include <stdint.h>
#include <stdio.h>

#include "palp_assess.h"
#include "palp_db.h"

typedef struct review_mark {
  int64_t mark_id;
  palp_finding f;  /* withdrawn set when a later withdrawal names it */
  int match;       /* lesion index, or PALP_FINDING_FALSE / _WITHDRAWN / _DUPLICATE */
} review_mark;

typedef struct review_assessment {
  int has_exercise;          /* 0: free practice (no lesions, default bands, no sensitivity/score) */
  char exercise_name[64];
  /* no exercise logged, but the recorder saw the session's phantom run this one (params_json
   * "exercise_name", palp-recorder since session 60): its lesions never reached the log */
  char exercise_unlogged[64];
  /* the finger samples' triangles are the patch under the fingertip, as many as it touched, not the
   * touched triangles themselves (params_json "footprint": "patch", palp-recorder since session 61) */
  int footprint_patch;
  palp_exercise ex;
  palp_assess_result r;
  int samples;               /* finger samples logged */
  double finger_radius_m;
  double dome_radius_m;
  palp_mesh mesh;            /* the rest mesh (owned) */
  uint8_t *coverage;         /* [mesh.vertex_count] bits 1 << band */
  palp_vec3 *path;           /* contact points while touching, in order */
  int path_n;
  review_mark *marks;
  int mark_n;
  palp_touch *touches;       /* the finger's touches in time order (palp_assess_touches) */
  int touch_n;
  palp_vec3 lesion_surface[PALP_MAX_LESIONS]; /* each lesion's surface projection [m] */
} review_assessment;

/* 0, PALP_DB_ENOTFOUND when the session logged no finger samples (nothing to assess), or
 * another negative code with a message in err. */
int review_assess(palp_db *db, const palp_db_session_info *s, review_assessment *out, char *err, size_t errlen);
void review_assessment_free(review_assessment *a);

/* What a session's trainee was told as it closed (docs/assessment.md, "Debrief"), from its logged
 * debrief event (palp_db_session_debrief): */
enum {
  REVIEW_DEBRIEF_UNKNOWN = 0,    /* its server logged no debriefs (before 2026-12-05's session 59,
                                    a palp-recorder before session 60, or one that missed it): the log does not say */
  REVIEW_DEBRIEF_LOGGED = 1,     /* *d: sent (what was told) or not sent (why) */
  REVIEW_DEBRIEF_NONE = 2,       /* its server logs debriefs and logged none (no exercise, or a
                                    session that never closed: a killed server) */
  REVIEW_DEBRIEF_UNREADABLE = 3, /* its row does not parse (a log edited by hand) */
  REVIEW_DEBRIEF_LOST = 4        /* none, though the session's close was logged: the row was lost
                                    (a full queue shed it, a disk error): the log does not say */
};
int review_debrief(palp_db *db, const palp_db_session_info *s, palp_db_debrief *d);
/* The instructor's line for it, the lesions' places named as every tool names them ("told where
 * each lump is: found 1 of 2; lump 1 found by mark 1 (at 1.7 o'clock, 21 mm from the pole), lump 2
 * MISSED (...); 2 marks standing, 1 near no lump"); a, the session's assessment, gives the places
 * (NULL, or one without the exercise: lumps by number only). */
void review_debrief_text(int status, const palp_db_debrief *d, const struct review_assessment *a, char *buf, size_t len);

/* For a drawn exercise (its lesions drawn for the session, docs/assessment.md): "drawn for this
 * session (seed N, polar A-B deg from the pole, at least G mm apart)" into buf, 1; else "" and 0.
 * One wording for show and the session report. */
int review_drawn_text(const palp_exercise *ex, char *buf, size_t len);

/* Whether the trainee had been debriefed on these very lesions before this attempt (docs/assessment.md,
 * "Debrief"): the latest earlier session of the same trainee, ended, whose logged exercise has the
 * same name and lesions and whose debrief told the lesions or their count: as its log records it
 * (review_debrief), or, for a log from before debriefs were logged, as its exercise file's level
 * says (inferred). 1 and *out when there is one, 0 when not, a negative code on a database error.
 * An attempt after a debrief that told the lesions is not blind. */
typedef struct review_told {
  char uid[128];          /* the earlier session */
  double end_unix_s;      /* when it ended: the debrief was sent then */
  palp_debrief_level level;
  int inferred;           /* 1: from the exercise file, the log not recording what was sent */
} review_told;
int review_told_before(palp_db *db, const palp_db_session_info *s, const review_assessment *a, review_told *out);
/* "bob had been told where this exercise's lesions are when session X ended (DATE): this attempt was
 * not blind" into buf, for show and the report; "" when there was no such session. */
void review_told_text(const palp_db_session_info *s, const review_told *t, char *buf, size_t len);

/* The metrics as CSV: the header line, then one row per session. */
void review_metrics_csv_header(FILE *f);
/* outside_s: seconds outside the model's valid range (review_valid_range_seconds; < 0: the log does
 * not say, an empty field); then the instructor's latest grade, read from db; the last two (since
 * session 59) what the trainee was told as the session closed and the earlier session whose
 * debrief made this attempt not blind. */
void review_metrics_csv_row(FILE *f, palp_db *db, const palp_db_session_info *s, const review_assessment *a,
                            double outside_s);
/* The metrics, score and rubric as text lines (palp-review show). */
void review_metrics_print(FILE *f, const review_assessment *a);
/* The finger's touches as text (palp-review show): where each began and ended on the phantom's
 * surface, its path, deepest indentation and peak force; the first `listed`, then how many more. */
enum { REVIEW_TOUCHES_LISTED = 20 };
void review_touches_print(FILE *f, const review_assessment *a, int listed);
/* Whether the review shows a session's strips and their order (docs/assessment.md): a search
 * classed vertical strip with three strips or more (circles and spokes have axial runs too,
 * whose order means nothing; those of a session pruned before schema 5 are unknown). The CSVs
 * carry them always. */
int review_strips_shown(const palp_assess_result *r);
/* The rubric's pass mark for the search pattern as the review writes it: "any", "systematic",
 * "vertical_strip", ..., followed by "; strips in order >= 0.70" when the rubric asks for an
 * order (palp_rubric.pass_strip_order). */
void review_pattern_mark(const palp_rubric *rb, char *buf, size_t len);

/* A pruned session's stored metrics (session_metrics, schema 4; the strips since schema 5): printed, or into *out
 * (only the fields the table holds; the pattern's overlap, gap share and largest gap, which it does not
 * hold, -1: unknown, empty in the CSV). 0, PALP_DB_ENOTFOUND when none are stored, or PALP_DB_ESQL when the
 * table could not be read (palp_db_errmsg says why). */
int review_stored_metrics_print(palp_db *db, int64_t sid, FILE *f);
int review_stored_metrics(palp_db *db, int64_t sid, review_assessment *out);

#endif
