/* Structured grades (grades.c): a score 0-100 and/or a rubric level on an instructor note
 * (note.score, note.level, schema 3); the free-text grade of older notes still displays. */
#ifndef PALP_REVIEW_GRADES_H
#define PALP_REVIEW_GRADES_H

#include <stddef.h>

#include "palp_db.h"

/* The rubric levels, lowest first. */
extern const char *const review_levels[4];

/* Parses a score: a plain decimal number within [0, 100] ("82", "82.5"). 0, or -1 with a message. */
int review_parse_score(const char *s, double *out, char *msg, size_t len);
/* Parses a level (exact, lower case). 0 and its index, or -1 with a message. */
int review_parse_level(const char *s, int *out, char *msg, size_t len);

/* Adds a note with an optional score (< 0: none) and level (NULL: none). */
int review_add_graded_note(palp_db *db, int64_t sid, const char *author, const char *text, double score,
                           const char *level);

/* The latest grade of a session as one short string: "82 competent", "82", "competent",
 * "'B+' (free text)" for a pre-schema-3 grade, "-" (none), or "unreadable" (the notes could not be
 * read). 1 graded, 0 not, -1 not known (prune --keep-graded keeps it). */
int review_latest_grade(palp_db *db, int64_t sid, char *buf, size_t len);
/* The parts of the grade review_latest_grade shows: *score (-1 when it gave none) and level (""
 * when none); 1 when it has either, 0 when the session is ungraded or its latest grade is an old
 * free-text one (which has neither). */
int review_latest_grade_parts(palp_db *db, int64_t sid, double *score, char *level, size_t len);
/* One note's grade for display, from its columns (any may be absent). */
void review_grade_text(int has_score, double score, const char *level, const char *free_text, char *buf, size_t len);

/* Every note of a session in order; grade is review_grade_text's string or NULL when ungraded. 0, fn's
 * nonzero return, or PALP_DB_ESQL when the table could not be read to its end (palp_db_errmsg says why). */
typedef int (*review_note_fn)(void *user, double wall_unix_s, const char *author, const char *text, const char *grade);
int review_each_note(palp_db *db, int64_t sid, review_note_fn fn, void *user);

#endif
