/* fuzz_util.h - small helpers shared by the fuzz entry points (tests/fuzz/). */
#ifndef PALP_FUZZ_UTIL_H
#define PALP_FUZZ_UTIL_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The input as a NUL-terminated string (parsers of text take one). */
static inline char *fuzz_cstr(const uint8_t *data, size_t size) {
  char *s = malloc(size + 1);
  if (!s) abort();
  if (size) memcpy(s, data, size);
  s[size] = '\0';
  return s;
}

static char fuzz_file_path[256];
static inline void fuzz_file_remove(void) {
  if (fuzz_file_path[0]) unlink(fuzz_file_path);
}

/* The input as a file, for readers that take a path: one per process (under TMPDIR, else /tmp),
 * rewritten each run and removed when the process exits. */
static inline const char *fuzz_file(const uint8_t *data, size_t size, const char *ext) {
  char *path = fuzz_file_path;
  const char *tmp = getenv("TMPDIR");
  if (!path[0]) atexit(fuzz_file_remove);
  snprintf(path, sizeof fuzz_file_path, "%s/palp-fuzz-%ld%s", tmp && tmp[0] ? tmp : "/tmp", (long)getpid(), ext);
  FILE *f = fopen(path, "wb");
  if (!f) abort();
  if (size && fwrite(data, 1, size, f) != size) abort();
  fclose(f);
  return path;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#endif
