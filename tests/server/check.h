/* check.h - the assertion of the server's unit tests that need no DDS (test_inputs, test_playout,
 * test_refusals): each check says "ok" or "FAIL" and what it measured, one line on stderr; the
 * test's main returns failures != 0. The DDS tests have theirs in harness.h. */
#ifndef PALP_SERVER_CHECK_H
#define PALP_SERVER_CHECK_H
#include <stdio.h>
#include <string.h>

static int failures;
#define CHECK(cond, ...)                           \
  do {                                             \
    const int ok_ = (cond);                        \
    fprintf(stderr, "%s ", ok_ ? "ok  " : "FAIL"); \
    fprintf(stderr, __VA_ARGS__);                  \
    fprintf(stderr, "\n");                         \
    if (!ok_) failures++;                          \
  } while (0)

/* How many lines of the file at path hold needle (-1: no file): what a test reads of a log. */
static inline long count_lines(const char *path, const char *needle) {
  FILE *f = fopen(path, "r");
  if (!f) return -1;
  char line[2048];
  long n = 0;
  while (fgets(line, sizeof line, f))
    if (strstr(line, needle)) n++;
  fclose(f);
  return n;
}

#endif
