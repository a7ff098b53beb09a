/*
 * grader.h - a closed exercise session's automatic score, from the server's own log (session 63).
 *
 * The instructor's review (palp-review show) assesses a session from its log: the exercise as the
 * server ran it, the fingertip's samples and the marks. The grader runs that same code
 * (client/review/assess_log.c) on a thread of its own once the session's end is in the log, so the
 * class dashboard can show, seconds after the session closes, the score the review will show. The
 * main thread only submits and takes (both O(1), never blocking on the disk); the grader waits for
 * the log's writer, reads through its own read connection and hands the result back. Bounded: 32
 * sessions waiting, 32 scores not yet taken; beyond that a session is not graded live, and the log
 * says so (the review still grades it).
 */
#ifndef PALP_SRV_GRADER_H
#define PALP_SRV_GRADER_H

#include <stddef.h>
#include <stdint.h>

#include "events.h"
#include "palp_db.h"
#include "palp_log.h"

typedef struct palp_srv_grader palp_srv_grader;

/* db_path: the log the writer w writes (the grader waits on w before it reads). */
int palp_srv_grader_open(const char *db_path, palp_db_writer *w, palp_log *log, palp_srv_grader **out);
/* [main thread] grade the session logged as uid once the log holds its end. 0, or
 * PALP_EFULL when 32 are already waiting (logged; answered at once as not graded, with why, when
 * fewer than 32 answers wait to be taken). */
int palp_srv_grader_submit(palp_srv_grader *g, uint32_t session_id, const char *uid, const char *exercise);
/* [main thread] 1 and *out when a score is ready, else 0. */
int palp_srv_grader_take(palp_srv_grader *g, palp_srv_score *out);
/* Grades the sessions still waiting (the writer given 2 s from now, even when the grader was already
 * waiting on it; else the rest are left, logged), then stops the thread; scores not taken are not
 * sent (logged). Test: server_grader. */
void palp_srv_grader_close(palp_srv_grader *g);

/* The score of an assessment as the wire carries it (pure; the tests check it against the review's
 * own numbers). a may be NULL with reason set: not graded. */
struct review_assessment;
void palp_srv_score_of(const struct review_assessment *a, uint32_t session_id, const char *uid, const char *exercise,
                       const char *reason, palp_srv_score *out);
/* The review's log-health line (palp_db_log_health_describe) into the wire's len (128) bytes: whole;
 * or, too long, without its parenthesised explanations; or, still too long, cut after its last whole
 * phrase that fits, ending " ..." (palp-review show prints all of it). */
void palp_srv_health_fit(const char *line, char *out, size_t len);

#endif
