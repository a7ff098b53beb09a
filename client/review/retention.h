/* Retention (retention.c): delete and prune sessions, reclaiming the space. */
#ifndef PALP_REVIEW_RETENTION_H
#define PALP_REVIEW_RETENTION_H
#include "review.h"
int review_delete(palp_log *log, palp_db *db, const char *path, int argc, char **argv);
int review_prune(palp_log *log, palp_db *db, const char *path, int argc, char **argv);
#endif
