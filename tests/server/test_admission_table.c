/* test_admission_table.c - palp_srv_admission_sweep releases exactly the instances of the writers that are gone
 * (server/admission.c; no DDS).
 *
 * - small: 30 writers x 3 instances, the even writers gone: 45 released, every odd writer's instance still
 *   held (the probe chains whole after the erases), every even one's not, and a gone writer's entry gone;
 * - large, at the largest config's table (max_sessions 1024 x 65 slots: 2 x 66560 + 64 instances): filled
 *   by writers of 1 to 4 instances with scattered handles, then swept with a third of the writers gone,
 *   then with all of them gone: the counts exact, and the time printed (not asserted). Until 2026-12-06 a
 *   gone writer's instances were each found by a scan of the whole table from slot 0: releasing a full
 *   table was ~3.5e10 probes. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "admission.h"

static int failures;
#define CHECK(cond, ...)                                                                                     \
  do {                                                                                                       \
    const int ok_ = (cond);                                                                                  \
    if (ok_) fprintf(stderr, "ok   ");                                                                       \
    else fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);                                                \
    fprintf(stderr, __VA_ARGS__);                                                                            \
    fputc('\n', stderr);                                                                                     \
    failures += !ok_;                                                                                        \
  } while (0)

static uint64_t mix(uint64_t x) { /* scattered, nonzero handles */
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return (x ^ (x >> 31)) | 1;
}

typedef struct gone_rule {
  int modulus; /* writer w is gone when (w % modulus) == 0; 1: all gone */
  long calls;
} gone_rule;

/* Writers are handles mix(w) for w = 1..; the rule sees w through a map kept by the test. */
static uint64_t *writer_handles;
static int nwriters;

static int index_of(uint64_t h) {
  for (int lo = 0, hi = nwriters - 1; lo <= hi;) { /* writer_handles sorted by the test */
    const int mid = (lo + hi) / 2;
    if (writer_handles[mid] == h) return mid;
    if (writer_handles[mid] < h) lo = mid + 1;
    else hi = mid - 1;
  }
  return -1;
}

static int matched(uint64_t writer, void *arg) {
  gone_rule *r = arg;
  r->calls++;
  const int i = index_of(writer);
  return i >= 0 && (i % r->modulus) != 0;
}

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return (x > y) - (x < y);
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void small(void) {
  palp_srv_admission *a = palp_srv_admission_create(3, 100, 10, 10);
  enum { W = 30, K = 3 };
  int admitted = 0;
  for (uint64_t w = 1; w <= W; w++)
    for (uint64_t k = 0; k < K; k++) admitted += palp_srv_admission_admit(a, w * 1000 + k, w);
  CHECK(admitted == W * K && !palp_srv_admission_admit(a, 1 * 1000 + 9, 1),
        "small: %d of %d admitted, a 4th instance of writer 1 refused (per_writer 3)", admitted, W * K);
  nwriters = W + 1; /* index i is writer i: even indices gone */
  writer_handles = calloc((size_t)nwriters, sizeof *writer_handles);
  for (int i = 0; i < nwriters; i++) writer_handles[i] = (uint64_t)i;
  gone_rule r = {.modulus = 2};
  const int released = palp_srv_admission_sweep(a, matched, &r);
  int odd_held = 0, even_held = 0;
  for (uint64_t w = 1; w <= W; w++)
    for (uint64_t k = 0; k < K; k++) {
      const int h = palp_srv_admission_holds(a, w * 1000 + k);
      if (w % 2) odd_held += h;
      else even_held += h;
    }
  CHECK(released == 45 && palp_srv_admission_count(a) == 45 && odd_held == 45 && even_held == 0 && r.calls == W,
        "small: the 15 even writers gone: %d released (want 45), %d left, odd writers' instances held %d (want 45), "
        "even %d (want 0), %ld writers asked (want %d)", released, palp_srv_admission_count(a), odd_held, even_held,
        r.calls, W);
  int again = 0;
  for (uint64_t k = 0; k < K; k++) again += palp_srv_admission_admit(a, 2 * 1000 + 100 + k, 2);
  CHECK(again == K, "small: a released writer's count is gone with it (%d of %d admitted anew)", again, K);
  free(writer_handles);
  palp_srv_admission_destroy(a);
}

/* Fills the table: writer i holds 1 + i % 4 instances; returns the instances admitted. */
static int fill(palp_srv_admission *a, int capacity, uint64_t salt, int *per_writer_n) {
  int n = 0;
  nwriters = 0;
  for (uint64_t w = 1; n < capacity; w++) {
    const int k_n = 1 + (int)(w % 4);
    const uint64_t wh = mix(salt ^ (w << 20));
    int got = 0;
    for (int k = 0; k < k_n && n < capacity; k++) {
      got += palp_srv_admission_admit(a, mix(salt + w * 8 + (uint64_t)k), wh);
      n++;
    }
    per_writer_n[nwriters] = got;
    writer_handles[nwriters++] = wh;
  }
  return n;
}

static void large(void) {
  const int slots = 1024 * (1 + 64), capacity = 2 * slots + 64;
  palp_srv_admission *a = palp_srv_admission_create(4, capacity, 10, 10);
  writer_handles = calloc((size_t)capacity, sizeof *writer_handles);
  int *per_writer_n = calloc((size_t)capacity, sizeof *per_writer_n);
  const int filled = fill(a, capacity, 0x5a17, per_writer_n);
  /* The rule indexes writers in handle order: sort handles and their counts together. */
  uint64_t *pairs = calloc((size_t)nwriters * 2, sizeof *pairs);
  for (int i = 0; i < nwriters; i++) pairs[2 * i] = writer_handles[i], pairs[2 * i + 1] = (uint64_t)per_writer_n[i];
  qsort(pairs, (size_t)nwriters, 2 * sizeof *pairs, cmp_u64);
  int want_released = 0;
  for (int i = 0; i < nwriters; i++) {
    writer_handles[i] = pairs[2 * i];
    if (i % 3 == 0) want_released += (int)pairs[2 * i + 1];
  }
  CHECK(filled == capacity && palp_srv_admission_count(a) == capacity,
        "large: %d instances from %d writers admitted (want %d)", palp_srv_admission_count(a), nwriters, capacity);

  gone_rule third = {.modulus = 3};
  double t0 = now_s();
  const int released = palp_srv_admission_sweep(a, matched, &third);
  const double t_third = now_s() - t0;
  CHECK(released == want_released && palp_srv_admission_count(a) == capacity - want_released &&
            third.calls == nwriters,
        "large: a third of the writers gone: %d released (want %d), %d left, %ld writers asked (want %d)", released,
        want_released, palp_srv_admission_count(a), third.calls, nwriters);
  /* Every instance of a live writer still found, none of a gone one. */
  int wrong = 0;
  for (uint64_t w = 1, n = 0; n < (uint64_t)capacity; w++) {
    const int k_n = 1 + (int)(w % 4);
    const int gone = index_of(mix(0x5a17 ^ (w << 20))) % 3 == 0;
    for (int k = 0; k < k_n && n < (uint64_t)capacity; k++, n++)
      wrong += palp_srv_admission_holds(a, mix(0x5a17 + w * 8 + (uint64_t)k)) == gone;
  }
  CHECK(wrong == 0, "large: every live writer's instance held, no gone writer's (%d wrong)", wrong);

  gone_rule all = {.modulus = 1};
  t0 = now_s();
  const int rest = palp_srv_admission_sweep(a, matched, &all);
  const double t_all = now_s() - t0;
  CHECK(rest == capacity - want_released && palp_srv_admission_count(a) == 0,
        "large: every writer gone: %d released (want %d), %d left", rest, capacity - want_released,
        palp_srv_admission_count(a));
  fprintf(stderr, "large table (%d instances, %d writers): a third released in %.3f s, the rest in %.3f s\n", capacity,
          nwriters, t_third, t_all);
  free(pairs);
  free(per_writer_n);
  free(writer_handles);
  palp_srv_admission_destroy(a);
}

int main(void) {
  small();
  large();
  fprintf(stderr, "%d failure(s)\n", failures);
  return failures ? 1 : 0;
}
