/*
 * placement.c - one session's lesions of a random exercise (palp_exercise_draw; docs/assessment.md,
 * "Lesions drawn for each session"). Pure and deterministic: SplitMix64 (src/palp_rng.h), seeded by
 * the server per session, so that the same seed gives the same lesions on every machine. A logged draw
 * can be checked by drawing it again from the exercise file with its seed; from its own logged text
 * (read back as kind random, with its seed) only when its count is fixed (lo = hi, or no count): the text keeps the k lesions drawn, not the n
 * listed, and the draw takes hi from those listed (min(hi, n)), so a draw of k < hi would be redrawn
 * with another hi and may pick another k (review session 83: with count [0, 3], 119 of 200 logged
 * draws redrew the same). Nothing redraws today: the review uses the logged places.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "palp_assess.h"
#include "palp_rng.h"
#include "parse_error.h"
#include "vec3.h"

#define TRIES_PER_LESION 10000
#define STARTS 100

static palp_vec3 dir_of(double polar, double az) {
  return v3(sin(polar) * cos(az), sin(polar) * sin(az), cos(polar));
}

/* Inside the dome and clear of its base: palp_exercise_lesions' test. */
static int fits(const palp_exercise_lesion *L, double R) {
  const double a = L->diameter / 2.0;
  const palp_vec3 c = v3_scale(dir_of(L->polar, L->azimuth), R - L->depth);
  return R - L->depth + a < R && L->depth + a < 2.0 * R && c.z - a > 0.0;
}

int palp_exercise_draw(const palp_exercise *ex, double R, uint32_t seed, palp_exercise *out, char *err, size_t errlen) {
  palp_parse_ctx c = {err, errlen};
  if (!ex || !out || !(R > 0.0)) return palp_parse_fail(&c, PALP_EINVAL, "exercise draw: bad arguments");
  *out = *ex;
  if (ex->placement.kind != PALP_PLACEMENT_RANDOM) return PALP_OK;
  const palp_exercise_placement *P = &ex->placement;
  /* cos(polar) uniform in [cos max, cos min]: every square millimetre of the band's skin as likely */
  const double c0 = cos(P->polar_max), c1 = cos(P->polar_min);
  uint64_t s = 0x5eed5eed00000000ULL ^ seed;
  /* How many, then which: k uniform in [count_min, count_max], a uniform k-subset (the first k of a
   * partial Fisher-Yates shuffle), kept in the file's order. */
  const int n = ex->lesion_count;
  const int lo = P->count_min >= 0 ? P->count_min : n, hi = P->count_max >= 0 && P->count_max <= n ? P->count_max : n;
  /* u < 1 (53 bits), so u * m < m for m <= 9: k <= hi and j <= n - 1 without a clamp */
  const int k = lo + (int)(palp_rng_uniform(&s) * (double)(hi - lo + 1));
  int idx[PALP_MAX_LESIONS];
  for (int i = 0; i < n; i++) idx[i] = i;
  for (int i = 0; i < k; i++) {
    const int j = i + (int)(palp_rng_uniform(&s) * (double)(n - i));
    const int t = idx[i];
    idx[i] = idx[j];
    idx[j] = t;
  }
  for (int i = 1; i < k; i++) /* insertion sort of the chosen: the file's order */
    for (int j = i; j > 0 && idx[j - 1] > idx[j]; j--) {
      const int t = idx[j];
      idx[j] = idx[j - 1];
      idx[j - 1] = t;
    }
  out->lesion_count = k;
  memset(out->lesion, 0, sizeof out->lesion); /* nothing of the lesions left out stays */
  for (int i = 0; i < k; i++) {
    out->lesion[i] = ex->lesion[idx[i]];
    out->placement.source[i] = idx[i];
  }
  for (int start = 0; start < STARTS; start++) {
    int placed = 0;
    for (int i = 0; i < k; i++) {
      palp_exercise_lesion *L = &out->lesion[i];
      int ok = 0;
      for (int t = 0; t < TRIES_PER_LESION && !ok; t++) {
        L->polar = acos(c0 + (c1 - c0) * palp_rng_uniform(&s));
        L->azimuth = 2.0 * PALP_PI * palp_rng_uniform(&s);
        ok = fits(L, R);
        for (int j = 0; j < i && ok; j++) ok = palp_exercise_lesion_gap(L, &out->lesion[j], R) >= P->min_gap;
      }
      if (!ok) break;
      placed++;
    }
    if (placed == k) {
      out->placement.kind = PALP_PLACEMENT_DRAWN;
      out->placement.seed = seed;
      return PALP_OK;
    }
  }
  return palp_parse_fail(&c, PALP_EINVAL,
                         "placement: cannot place %d lesions in the band %g-%g deg from the pole at least %g mm apart "
                         "(a wider band, a smaller gap or fewer lesions)",
                         k, P->polar_min * 180.0 / PALP_PI, P->polar_max * 180.0 / PALP_PI, P->min_gap * 1e3);
}
