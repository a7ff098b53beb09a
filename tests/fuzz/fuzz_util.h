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

/* The input as a file, for readers that take a path: one per process, rewritten each run. */
static inline const char *fuzz_file(const uint8_t *data, size_t size, const char *ext) {
  static char path[256];
  snprintf(path, sizeof path, "/tmp/palp-fuzz-%ld%s", (long)getpid(), ext);
  FILE *f = fopen(path, "wb");
  if (!f) abort();
  if (size && fwrite(data, 1, size, f) != size) abort();
  fclose(f);
  return path;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#endif
