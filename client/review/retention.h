/* Retention (retention.c): delete and prune sessions, reclaiming the space. */
#ifndef PALP_REVIEW_RETENTION_H
#define PALP_REVIEW_RETENTION_H
#include "review.h"
int review_delete(palp_log *log, palp_db *db, const char *path, int argc, char **argv);
/* The session a SESSION argument names (session_name.c): its exact uid, else a station's "session N" (1-9
 * digits) when one session has it, else, with allow_prefix, the one uid that starts with it. Anything
 * else is said (the candidates listed on stderr): REVIEW_ERROR. 0 with *s filled. */
int review_find_session(palp_log *log, palp_db *db, const char *cmd, const char *arg, int allow_prefix,
                        palp_db_session_info *s);
int review_prune(palp_log *log, palp_db *db, const char *path, int argc, char **argv);
#endif
