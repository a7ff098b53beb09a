/* bench_tmp.h - a benchmark's scratch directory: made with mkdtemp under TMPDIR (else /tmp) and
 * removed at exit. A fixed name in /tmp (the benchmarks' defaults until 2026-12-05) lets two runs
 * overwrite each other and another user of the machine plant a symlink where root writes
 * (SQLite adds -wal and -shm files beside a database, at names anyone can predict). */
#ifndef PALP_BENCH_TMP_H
#define PALP_BENCH_TMP_H

#include <stdio.h>
#include <stdlib.h>

static char bench_tmp_dir[512];

static inline void bench_tmp_remove(void) {
  if (!bench_tmp_dir[0]) return;
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", bench_tmp_dir);
  if (system(cmd) != 0) fprintf(stderr, "bench: could not remove %s\n", bench_tmp_dir);
}

/* "DIR/name" in the scratch directory (made on the first call), or NULL when it cannot be made. */
static inline const char *bench_tmp_path(const char *prefix, const char *name, char *out, size_t len) {
  if (!bench_tmp_dir[0]) {
    const char *t = getenv("TMPDIR");
    snprintf(bench_tmp_dir, sizeof bench_tmp_dir, "%s/%s.XXXXXX", t && t[0] ? t : "/tmp", prefix);
    if (!mkdtemp(bench_tmp_dir)) {
      fprintf(stderr, "bench: cannot make a scratch directory %s\n", bench_tmp_dir);
      bench_tmp_dir[0] = '\0';
      return NULL;
    }
    atexit(bench_tmp_remove);
  }
  snprintf(out, len, "%s/%s", bench_tmp_dir, name);
  return out;
}

#endif
