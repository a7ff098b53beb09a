/* palp-review's output files (--out, --csv): written whole or not at all.
 *
 * A report, export or CSV named by a path that is a regular file (or none yet) is written to a
 * temporary file beside it and renamed over the name only once every byte is written (Redis
 * rdb.c's way, without its fsync): a full disk, a quota or a crash half way leaves the report that was there,
 * never half of the new one (before session 82 the old file was truncated first, then lost). A device,
 * pipe or symlink (/dev/stdout, /dev/null, a FIFO) is written in place, as before. */
#ifndef PALP_REVIEW_OUT_FILE_H
#define PALP_REVIEW_OUT_FILE_H

#include <stdio.h>

#include "palp_log.h"

/* The session log the command reads: no output file may be it, or its -wal or -shm. */
void review_out_protect(const char *db_path);
/* Opens PATH for writing, the file its owner's alone (0600). Refuses the session log itself and its
 * -wal and -shm (said, naming the file; errno EEXIST): "report S --out sessions.db" once truncated the
 * log it read. NULL and errno on failure. */
FILE *review_fopen_out(palp_log *log, const char *path);
/* Finishes what review_fopen_out opened (or stdout): flushed, its error flag read and renamed
 * into place. 0, or -1 with errno (EIO where an earlier write failed and its own errno is gone): then
 * nothing was renamed, the temporary file is removed and what PATH held before is kept. Not
 * fsynced (out_file.c says why). */
int review_close_out(FILE *f);
/* Gives up a file review_fopen_out opened: closed, its temporary file removed, PATH as it was. */
void review_abandon_out(FILE *f);

#endif
