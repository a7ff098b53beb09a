/* check.h - minimal assertions for the model tests: each names its tolerance. */
#ifndef PALP_CHECK_H
#define PALP_CHECK_H
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int check_failures = 0;
#define CHECK(cond, ...)                                                  \
  do {                                                                    \
    if (!(cond)) {                                                        \
      fprintf(stderr, "FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);     \
      fprintf(stderr, __VA_ARGS__);                                       \
      fprintf(stderr, "\n");                                              \
      check_failures++;                                                   \
    }                                                                     \
  } while (0)
/* |a - b| <= tol */
#define CHECK_NEAR(a, b, tol, what)                                                              \
  CHECK(fabs((a) - (b)) <= (tol), "%s: %.9g vs %.9g (tolerance %.3g)", what, (double)(a), (double)(b), \
        (double)(tol))
#define CHECK_DONE()                                                              \
  do {                                                                            \
    if (check_failures) fprintf(stderr, "%d check(s) failed\n", check_failures);  \
    else printf("all checks passed\n");                                           \
    return check_failures ? 1 : 0;                                                \
  } while (0)
#endif
