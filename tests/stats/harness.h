/* harness.h - counted checks and whole-file reads shared by the stats tool tests. */
#ifndef PALP_TEST_STATS_HARNESS_H
#define PALP_TEST_STATS_HARNESS_H
#include <stdio.h>
#include <stdlib.h>

static int failures = 0, checks = 0;

static void check(const char *what, int cond) {
  ++checks;
  if (!cond) {
    ++failures;
    fprintf(stderr, "FAIL %s\n", what);
  }
}

/* The whole file as a NUL-terminated string (empty when it cannot be read); free it. */
static char *slurp(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return calloc(1, 1);
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *s = malloc((size_t)n + 1);
  size_t got = fread(s, 1, (size_t)n, f);
  s[got] = '\0';
  fclose(f);
  return s;
}
#endif
