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

typedef struct palp_srv_findings_limits {
  uint32_t session_id;     /* the partition's session: a finding naming another is refused */
  palp_vec3 box_min, box_max; /* the dome's bounding box grown by the largest finger radius [m] */
  double rate;             /* findings per second once the burst is spent */
  int burst;               /* findings accepted at once */
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
