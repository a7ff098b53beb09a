/* tmpdir.h - where a test makes its temporary files: TMPDIR when set (scripts/test.sh gives every
 * run one of its own and fails when a passing test leaves anything in it: docs/robustness.md,
 * "Temporary files"), else /tmp. */
#ifndef PALP_TESTS_TMPDIR_H
#define PALP_TESTS_TMPDIR_H

#include <stdio.h>
#include <stdlib.h>

/* Writes "TMPDIR/name" (name may end in XXXXXX for mkstemp/mkdtemp) into out; returns out. */
static inline char *palp_test_tmp(char *out, size_t size, const char *name) {
  const char *dir = getenv("TMPDIR");
  snprintf(out, size, "%s/%s", dir && dir[0] ? dir : "/tmp", name);
  return out;
}

#endif
