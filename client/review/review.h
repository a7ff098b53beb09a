/* palp-review: the instructor's tool over a session log. One module per command. */
#ifndef PALP_REVIEW_H
#define PALP_REVIEW_H

#include <stdio.h>

#include "palp_db.h"
#include "palp_log.h"
#include "review_util.h"
#include "out_file.h"

/* Exit codes: 0 ok, 1 the check failed (replay mismatch), 2 bad input or an error. */
enum { REVIEW_OK = 0, REVIEW_MISMATCH = 1, REVIEW_ERROR = 2 };

int review_export(palp_log *log, palp_db *db, const palp_db_session_info *s, const char *format, const char *table,
                  const char *out_path);
int review_replay(palp_log *log, palp_db *db, const palp_db_session_info *s, int verbose);
int review_report(palp_log *log, palp_db *db, const palp_db_session_info *s, const char *out_path);

/* palp-review class --exercise NAME [--since DATE] --out FILE.html [--csv FILE] (class.c). */
int review_class(palp_log *log, palp_db *db, int argc, char **argv);
/* palp-review trainee NAME [--since DATE] [--until DATE] [--csv FILE] [--out FILE.html] (trainee.c). */
int review_trainee(palp_log *log, palp_db *db, int argc, char **argv);

#endif
