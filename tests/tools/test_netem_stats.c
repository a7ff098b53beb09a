/*
 * test_netem_stats.c - palp-netem's applied-delay statistics (review, 2026-12-06).
 *
 * White-box: netem.c is compiled into this test so that its enqueue() runs as the relay's
 * receive threads run it (under the lock), with no DDS entity and no domain: enqueue only
 * draws the delay, queues the item and updates the statistics, and a relay between two DDS
 * domains is more than this check needs. No transmit thread runs, so nothing is ever
 * forwarded: exactly the start of a run, where delay_min used to be overwritten by every
 * enqueue (the minimum was taken only once "forwarded + retransmitted > 0").
 *
 * Expected values come from palp_rng.h's SplitMix64, not from netem.c: per sample one
 * uniform for the jitter and one for the loss draw; delay + jitter (2u - 1), truncated to
 * whole ns by the due time (tolerance 2 ns). Each sample goes to its own (side, topic) link,
 * so no order clamp applies.
 */
#include "netem.c"

#include "palp_rng.h"

int main(void) {
  static palp_netem n; /* large (the sides' writer tables): not on the stack */
  memset(&n, 0, sizeof n);
  n.def = (palp_netem_def){.domain_a = 0, .domain_b = 1, .delay = 0.020, .jitter = 0.010, .loss = 0.0, .seed = 42};
  n.rng = n.def.seed; /* as palp_netem_start */
  pthread_mutex_init(&n.lock, NULL);
  pthread_cond_init(&n.cond, NULL);
  uint64_t r = n.def.seed;
  double lo = INFINITY, hi = 0.0;
  int failures = 0, rises = 0;
  const int count = 2 * PALP_TOPIC_COUNT;
  for (int i = 0; i < count; ++i) {
    const double u = palp_rng_uniform(&r);
    (void)palp_rng_uniform(&r); /* the loss draw */
    const double d = n.def.delay + n.def.jitter * (2 * u - 1);
    rises += d > lo; /* a later sample slower than the fastest so far: the case that was wrong */
    lo = fmin(lo, d), hi = fmax(hi, d);
    pthread_mutex_lock(&n.lock);
    enqueue(&n, i % 2, i / 2, 0, 0, 0, NULL);
    palp_netem_stats st = n.st;
    pthread_mutex_unlock(&n.lock);
    if (!(fabs(st.delay_min - lo) <= 2e-9 && fabs(st.delay_max - hi) <= 2e-9 && st.forwarded == 0)) {
      fprintf(stderr, "FAIL after %d samples, none forwarded: delay_min %.9f s (want %.9f), delay_max %.9f s (want %.9f)\n",
              i + 1, st.delay_min, lo, st.delay_max, hi);
      ++failures;
    }
  }
  if (rises == 0) {
    fprintf(stderr, "FAIL test setup: no sample slower than an earlier one (seed %llu)\n", (unsigned long long)n.def.seed);
    ++failures;
  }
  printf("netem: %d samples queued, none forwarded: delay_min %.6f s, delay_max %.6f s (the drawn extremes within 2 ns); "
         "%d samples slower than an earlier one\n", count, n.st.delay_min, n.st.delay_max, rises);
  if (n.queued != count) {
    fprintf(stderr, "FAIL %d queued, want %d\n", n.queued, count);
    ++failures;
  }
  for (item *it = n.head, *next; it; it = next) next = it->next, free(it);
  pthread_cond_destroy(&n.cond);
  pthread_mutex_destroy(&n.lock);
  if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
  return failures ? 1 : 0;
}
