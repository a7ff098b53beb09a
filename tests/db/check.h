/* Minimal assertions for the db tests: print what failed and where, count failures. */
#ifndef PALP_TEST_DB_CHECK_H
#define PALP_TEST_DB_CHECK_H
#include <stdio.h>
#include <stdlib.h>

static int check_failures;
#define CHECK(cond, ...)                                                                            \
  do {                                                                                              \
    if (!(cond)) {                                                                                  \
      fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, __LINE__, #cond);                      \
      fprintf(stderr, __VA_ARGS__);                                                                 \
      fputc('\n', stderr);                                                                          \
      check_failures++;                                                                             \
    }                                                                                               \
  } while (0)
#define REQUIRE(cond, ...)                                                                          \
  do {                                                                                              \
    int require_ok_ = (cond) ? 1 : 0; /* evaluated once: cond often has side effects */                     \
    CHECK(require_ok_, __VA_ARGS__);                                                                \
    if (!require_ok_) exit(1);                                                                      \
  } while (0)
#define CHECK_DONE()                                                                                \
  do {                                                                                              \
    if (check_failures) {                                                                           \
      fprintf(stderr, "%d check(s) failed\n", check_failures);                                      \
      return 1;                                                                                     \
    }                                                                                               \
    printf("all checks passed\n");                                                                  \
    return 0;                                                                                       \
  } while (0)
#endif
