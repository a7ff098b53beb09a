/*
 * palp_finding_answers.h - a trainee's findings paired with the server's answers to them, as a
 * reader of the wire sees both (palp-recorder logs by it, palp-web's dashboard shows by it).
 *
 * The server answers each finding (palp_finding), in the order it takes them, on
 * palp_finding_status, which is keep-last 1: an answer can be replaced before it is sent, and an
 * answer can reach a reader before the finding it answers (two topics). So a finding counts once
 * its answer is seen: accepted, or refused with the server's reason. An answer to a later finding
 * means the earlier findings' answers were replaced: those, and any finding not answered within
 * the wait, are given up as unanswered. A mark and its withdrawal carry the same mark id; an
 * answer is matched to the newest pending finding of its id (with both pending it is the
 * withdrawal's: keep-last 1 replaced the mark's; since session 81, the oldest before).
 *
 * Not every status is an answer (session 83 review). The server writes its status again at 2 Hz
 * (the time left moves) with the last answer in it, and a reader that starts mid-session is
 * handed the writer's last status (transient-local) for a finding it never saw (palp_finding is
 * volatile). Queued for the wait, such a copy was taken by the next finding of that mark id, a
 * double press of "withdraw" within 2 s: a withdrawal the server refused was logged accepted. So
 * a status equal to the one received before it (mark id, verdict, reason and marks standing;
 * the time left aside) is a repeat and answers nothing, and neither does a historical one, which
 * the caller knows by its source timestamp (written before the caller's reader was made). The
 * one answer lost so: a second refusal of the same id for the same reason right after the first
 * (its finding then counts as unanswered, never as the wrong verdict). Pure: no DDS, no clock of
 * its own.
 */
#ifndef PALP_FINDING_ANSWERS_H
#define PALP_FINDING_ANSWERS_H

#include <stdint.h>

#include "vec3.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PALP_FINDING_ANSWERS_PENDING 32 /* findings awaiting an answer; a flood gives up the oldest */
#define PALP_FINDING_ANSWERS_QUEUED 8   /* answers awaiting their finding */
#define PALP_FINDING_ANSWER_WAIT_S 2.0  /* [s]: the server answers within its loop's pass (ms) */

enum { PALP_VERDICT_REFUSED = 0, PALP_VERDICT_ACCEPTED = 1, PALP_VERDICT_UNANSWERED = 2 };

/* A finding as the trainee's station sent it. */
typedef struct palp_finding_sent {
  uint32_t mark_id;
  int withdraw;    /* 1: the withdrawal of mark mark_id */
  palp_vec3 point; /* [m], a mark's */
  double t;        /* the session's simulated time it names [s] */
} palp_finding_sent;

/* Called once per finding, in the order the findings were sent: verdict PALP_VERDICT_*, reason the
 * server's (refused) or "" . */
typedef void (*palp_finding_verdict_fn)(void *ctx, const palp_finding_sent *f, int verdict, const char *reason);

typedef struct palp_finding_answers {
  struct {
    palp_finding_sent f;
    double since; /* [s], the caller's clock */
  } finding[PALP_FINDING_ANSWERS_PENDING]; /* oldest first */
  int findings;
  struct {
    uint32_t mark_id;
    int accepted;
    char reason[128];
    double since;
  } answer[PALP_FINDING_ANSWERS_QUEUED]; /* oldest first */
  int answers;
  struct { /* the status received last, answer or not: a repeat of it answers nothing */
    int valid;
    uint32_t mark_id, marks;
    int accepted;
    char reason[128];
  } last;
} palp_finding_answers;

void palp_finding_answers_reset(palp_finding_answers *a);
/* A finding taken from the wire at `now` [s]. */
void palp_finding_answers_finding(palp_finding_answers *a, const palp_finding_sent *f, double now,
                                  palp_finding_verdict_fn fn, void *ctx);
/* A server's status (palp_finding_status: last_mark_id, last_accepted, reason, marks standing):
 * the answer to mark_id, unless it names mark 0 (none yet), repeats the status received before it,
 * or is historical (1: the caller's reader was handed it as it joined: written before the reader
 * was made, by its source timestamp). */
void palp_finding_answers_answer(palp_finding_answers *a, uint32_t mark_id, int accepted, const char *reason,
                                 uint32_t marks, int historical, double now, palp_finding_verdict_fn fn, void *ctx);
/* Gives up findings and answers older than `wait` [s] at `now`, or all of them (the session ended). */
void palp_finding_answers_settle(palp_finding_answers *a, double now, double wait, int all,
                                 palp_finding_verdict_fn fn, void *ctx);

#ifdef __cplusplus
}
#endif

#endif
