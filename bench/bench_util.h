/*
 * bench_util.h - the small statistics the benchmarks share (header-only; bench/ only):
 * a clock in seconds and the median of a sample (sorted in place).
 */
#ifndef PALP_BENCH_UTIL_H
#define PALP_BENCH_UTIL_H

#include <stdlib.h>
#include <time.h>

/* [s] of the given clock (CLOCK_MONOTONIC for wall time, CLOCK_PROCESS_CPUTIME_ID for CPU) */
static inline double palp_bench_clock_s(clockid_t id) {
  struct timespec ts;
  clock_gettime(id, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static inline int palp_bench_cmp(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* the median of v[0..n-1], n >= 1; sorts v */
static inline double palp_bench_median(double *v, int n) {
  qsort(v, (size_t)n, sizeof *v, palp_bench_cmp);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

#endif
