/* check.h - the assertion of the server's unit tests that need no DDS (test_inputs, test_playout,
 * test_refusals): each check says "ok" or "FAIL" and what it measured, one line on stderr; the
 * test's main returns failures != 0. The DDS tests have theirs in harness.h. */
#ifndef PALP_SERVER_CHECK_H
#define PALP_SERVER_CHECK_H
#include <stdio.h>

static int failures;
#define CHECK(cond, ...)                           \
  do {                                             \
    const int ok_ = (cond);                        \
    fprintf(stderr, "%s ", ok_ ? "ok  " : "FAIL"); \
    fprintf(stderr, __VA_ARGS__);                  \
    fprintf(stderr, "\n");                         \
    if (!ok_) failures++;                          \
  } while (0)

#endif
