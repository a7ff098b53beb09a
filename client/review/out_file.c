/* palp-review's output files, written whole or not at all (out_file.h). */
#define _GNU_SOURCE /* mkostemp's O_CLOEXEC */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "out_file.h"
#include "palp_app.h"
#include "review_util.h"

/* The files being written under a temporary name. A command has at most two open at once (a CSV, then
 * a page); the table is the tool's, not the library's. */
enum { OUT_MAX = 4 };
typedef struct out_pending {
  FILE *f;
  char tmp[PATH_MAX], path[PATH_MAX];
} out_pending;
static out_pending pending[OUT_MAX];
static const char *protected_db;

void review_out_protect(const char *db_path) { protected_db = db_path; }

/* Whether PATH, as it stands (symlinks followed), is the session log or its -wal or -shm. */
static int is_protected(const char *path) {
  if (!protected_db) return 0;
  struct stat st;
  if (stat(path, &st) != 0) return 0;
  static const char *const suffix[] = {"", "-wal", "-shm"};
  for (size_t k = 0; k < sizeof suffix / sizeof suffix[0]; k++) {
    char p[PATH_MAX];
    struct stat ks;
    if (snprintf(p, sizeof p, "%s%s", protected_db, suffix[k]) < (int)sizeof p && stat(p, &ks) == 0 &&
        ks.st_dev == st.st_dev && ks.st_ino == st.st_ino)
      return 1;
  }
  return 0;
}

static FILE *open_in_place(const char *path) {
  char wal[PATH_MAX], shm[PATH_MAX];
  const char *p = protected_db ? protected_db : "";
  snprintf(wal, sizeof wal, "%s-wal", p);
  snprintf(shm, sizeof shm, "%s-shm", p);
  const char *const keep[] = {protected_db, wal, shm};
  return palp_app_fopen_private_except(path, keep, protected_db ? 3 : 0);
}

FILE *review_fopen_out(palp_log *log, const char *path) {
  FILE *f = NULL;
  if (!strcmp(path, "-")) { /* export and the CSVs take it for standard output; a report, a page, is a file */
    palp_log_error(log, "'-' is not a file name here: give the file to write (FILE.html), or /dev/stdout for "
                   "standard output");
    errno = EINVAL;
    return NULL;
  }
  struct stat st;
  const int exists = lstat(path, &st) == 0;
  out_pending *slot = NULL;
  for (int k = 0; k < OUT_MAX && !slot; k++)
    if (!pending[k].f) slot = &pending[k];
  if (is_protected(path)) errno = EEXIST;
  else if ((exists && !S_ISREG(st.st_mode)) || !slot) f = open_in_place(path); /* a device, pipe or symlink */
  else if (snprintf(slot->tmp, sizeof slot->tmp, "%s.palp-XXXXXX", path) >= (int)sizeof slot->tmp)
    errno = ENAMETOOLONG;
  else {
    /* mkostemp creates the file 0600, beside PATH so that rename() stays in one file system */
    const int fd = mkostemp(slot->tmp, O_CLOEXEC);
    if (fd < 0) {
      /* a directory the review may not create in (a file it may write, in a directory it may not):
       * written in place, as before */
      if (errno == EACCES || errno == EPERM || errno == EROFS) f = open_in_place(path);
    } else if (!(f = fdopen(fd, "w"))) {
      const int e = errno;
      close(fd);
      unlink(slot->tmp);
      errno = e;
    } else {
      slot->f = f;
      snprintf(slot->path, sizeof slot->path, "%s", path);
    }
  }
  if (!f && errno == EEXIST)
    palp_log_error(log, "%s is the session log being read (%s, or its -wal or -shm): not overwritten; name another "
                   "file", path, protected_db ? protected_db : "");
  return f;
}

static out_pending *find(FILE *f) {
  for (int k = 0; k < OUT_MAX; k++)
    if (f && pending[k].f == f) return &pending[k];
  return NULL;
}

int review_close_out(FILE *f) {
  out_pending *p = find(f);
  if (!p) return review_finish_output(f);
  int err = 0;
  if (fflush(f)) err = errno;
  if (!err && ferror(f)) err = EIO;
  /* Not fsynced: a report can be written again, and a disk flush per file would make a class's many
   * reports wait on every other writer of the disk. What the rename guards against is a write that
   * fails half way (a full disk, a quota): the old file is kept. */
  if (fclose(f) && !err) err = errno;
  if (!err && is_protected(p->path)) err = EEXIST; /* made the log since it was opened: not replaced */
  if (!err && rename(p->tmp, p->path)) err = errno;
  if (err) unlink(p->tmp);
  p->f = NULL;
  if (!err) return 0;
  errno = err;
  return -1;
}

void review_abandon_out(FILE *f) {
  out_pending *p = find(f);
  if (f && f != stdout) fclose(f);
  if (!p) return;
  unlink(p->tmp);
  p->f = NULL;
}
