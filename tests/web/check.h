/* Minimal assertions for the web tests written in C: print what failed and where, count checks and
 * failures (main prints "N checks, M failures" and returns 1 on any failure). */
#ifndef PALP_TEST_WEB_CHECK_H
#define PALP_TEST_WEB_CHECK_H
#include <stdio.h>

static int failures, checks;
#define CHECK(cond, ...)                                   \
  do {                                                     \
    checks++;                                              \
    if (!(cond)) {                                         \
      failures++;                                          \
      fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__); \
      fprintf(stderr, __VA_ARGS__);                        \
      fputc('\n', stderr);                                 \
    }                                                      \
  } while (0)
#endif
