/*
 * findings.h - a session's "lump here" marks (issue 13, docs/assessment.md): what the
 * server accepts from palp_finding, and the state palp_finding_status reports.
 *
 * Pure bookkeeping (no DDS calls): the server's main thread takes the samples, offers
 * each here, logs the verdict and writes the status. Everything a station sends is
 * checked before use; what is held is bounded (PALP_SRV_MAX_MARKS marks, a token
 * bucket), whatever the station sends.
 */
#ifndef PALP_SRV_FINDINGS_H
#define PALP_SRV_FINDINGS_H

#include <stdint.h>

#include "palp.h"
#include "palp_assess.h"
#include "palp_types.h"

#define PALP_SRV_MAX_MARKS 64 /* marks a session may make (withdrawn ones count): the log stays bounded */
/* A trainee marks a lump after feeling it, seconds apart; a station correcting a slip
 * (mark, withdraw, mark) needs a few at once. Beyond that it is a broken or hostile peer. */
#define PALP_SRV_FINDING_RATE 5.0
#define PALP_SRV_FINDING_BURST 10

/* Where a mark may lie (palp_srv_findings_offer): its distance from the base's centre within
 * [R - depth_max, R + height_max] and z >= 0. A mark is the fingertip's contact point (LocalModel.point,
 * on the skin the fingertip presses); measured over two scripted expert exams (tests/assess
 * test_trainees, 2026-12, session 81) it lay 0.00-10.4 mm under the rest skin, never above it, and
 * at most 0.10 mm deeper than the fingertip's indentation. So: no deeper than the exercise's deepest
 * pressure band reaches plus 1 mm (PALP_SRV_MARK_DEPTH_SLACK), and no higher than
 * PALP_SRV_MARK_HEIGHT above the skin. The bounding box grown by the largest finger radius (30 mm)
 * that stood here before took a mark 20 mm inside the dome or 24 mm above the skin and matched it by
 * radial projection (session 81 review). */
#define PALP_SRV_MARK_DEPTH_SLACK 0.001 /* [m] */
/* With no depth band to go by (force bands, or no exercise): ~22 mm is the fingertip's indentation
 * at the server's 20 N force limit at the pole (docs/assessment.md's table: 19.8 N at 22 mm), + 1 mm. */
#define PALP_SRV_MARK_DEPTH_DEFAULT 0.023 /* [m] */
/* Above the rest skin: contact points were never measured there; 5 mm leaves room for the skin's
 * bulge beside a press and a station's rounding, and is far below a fingertip's radius. */
#define PALP_SRV_MARK_HEIGHT 0.005 /* [m] */

typedef struct palp_srv_findings_limits {
  uint32_t session_id;     /* the partition's session: a finding naming another is refused */
  double dome_radius;      /* R [m]: the rest pole's distance from the base's centre */
  double depth_max;        /* how far under the rest skin a mark may lie [m] (palp_srv_findings_depth_max) */
  double height_max;       /* how far above it [m] (PALP_SRV_MARK_HEIGHT) */
  double rate;             /* findings per second once the burst is spent */
  int burst;               /* findings accepted at once */
  double time_limit;       /* the exercise's [s]; a mark made later (its model's world time) is refused; 0: none */
} palp_srv_findings_limits;

typedef struct palp_srv_findings {
  palp_srv_findings_limits lim;
  uint32_t mark[PALP_SRV_MAX_MARKS]; /* ids of the marks made, in order */
  uint8_t standing[PALP_SRV_MAX_MARKS]; /* 1 until withdrawn */
  palp_vec3 point[PALP_SRV_MAX_MARKS];  /* where each was made [m] (checked finite, on the phantom) */
  int made;                /* marks made (<= PALP_SRV_MAX_MARKS) */
  int marks;               /* standing */
  double tokens;
  int64_t last_ns;         /* of the token bucket's last refill; 0: full */
  /* the answer to the latest finding, as palp_finding_status carries it */
  uint32_t last_mark_id;
  int last_accepted;
  char reason[128];
  uint64_t accepted, refused;
} palp_srv_findings;

void palp_srv_findings_init(palp_srv_findings *f, const palp_srv_findings_limits *lim);
/* How far under the rest skin a mark may lie [m]: the deepest depth bound of ex's pressure bands +
 * PALP_SRV_MARK_DEPTH_SLACK, or PALP_SRV_MARK_DEPTH_DEFAULT when ex is NULL or bands by force alone. */
double palp_srv_findings_depth_max(const palp_exercise *ex);
/* An exercise's pressure bands against the dome of radius R [m] and the server's force limit max_force [N]
 * (the start and --check): PALP_EINVAL and why in msg when a depth band reaches R (a mark anywhere inside
 * the dome would be taken for a contact point) or a force band starts at or above max_force (no press can
 * reach it: every trainee fails its coverage); else 0. */
int palp_srv_findings_check_exercise(const palp_exercise *ex, double R, double max_force, char *msg, size_t len);

/* Checks one finding at monotonic time now_ns and, when it is accepted, applies it.
 * Returns 1 (accepted) or 0 (refused; f->reason says why). In either case
 * last_mark_id, last_accepted and reason describe this finding. */
int palp_srv_findings_offer(palp_srv_findings *f, const palp_Finding *in, int64_t now_ns);

/* The session's debrief (palp_debrief, docs/assessment.md "Debrief"): its standing marks matched
 * to the exercise's lesions as the instructor's review matches them (palp_assess_findings on a dome
 * of dome_radius [m], the rest pole's distance from the base centre), told at the exercise's level.
 * reason: why the session ended. Fills every field of out, its lesion sequence pointing into
 * lesion_buf [PALP_MAX_LESIONS]. Returns 0, or a negative PALP_E* code (out then says nothing of
 * the lesions). */
int palp_srv_findings_debrief(const palp_srv_findings *f, const palp_exercise *ex, double dome_radius,
                              uint32_t session_id, const char *reason, palp_Debrief *out,
                              palp_DebriefLesion *lesion_buf);

#endif
