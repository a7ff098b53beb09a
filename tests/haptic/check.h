/* check.h - the counted check the haptic-station tests share. */
#ifndef PALP_TEST_HAPTIC_CHECK_H
#define PALP_TEST_HAPTIC_CHECK_H
#include <stdio.h>
#include <stdlib.h>

static int check_failures;
#define CHECK(cond, ...)                                                                                     \
  do {                                                                                                       \
    const int ok_ = (cond) ? 1 : 0;                                                                          \
    if (!ok_) check_failures++;                                                                              \
    fprintf(stderr, ok_ ? "ok   " : "FAIL %s:%d: ", __FILE__, __LINE__);                                     \
    fprintf(stderr, __VA_ARGS__);                                                                            \
    fputc('\n', stderr);                                                                                     \
  } while (0)

static inline int check_exit(void) {
  fprintf(stderr, check_failures ? "%d check(s) FAILED\n" : "all checks passed\n", check_failures);
  return check_failures ? 1 : 0;
}
#endif
