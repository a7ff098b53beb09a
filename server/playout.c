/*
 * playout.c - a position-driven finger's device samples played out at a steady
 * delay (playout.h; docs/station.md, latency item 5, "Jitter on the way in").
 */
#include "playout.h"

#include <stdlib.h>
#include <string.h>

#define BUCKET_NS 1000000000LL /* the minimum offset is the least over the last 1-2 s */
#define SLEW 0.1               /* T runs at most 10% fast or slow towards its target */
#define SNAP_NS 50000000LL     /* further than 50 ms off (a pause, a new path): jump */
/* |stamp| < 2^61 ns (73 years either side of the clock's zero: a monotonic clock, or Unix time
 * until 2043): every difference taken below (two stamps, an offset and the base offset, the
 * playout time and a stamp) then stays under 2^63. At 2^62, allowed until session 75, the gap
 * between stamps -2^62 and +2^62 was 2^63: a signed overflow, and a weight far outside [0, 1]. */
#define CLOCK_LIMIT (1LL << 61)
#define RESTART_NS 1000000000LL /* a stamp this much older than the newest: a new clock */
/* Jitter under 2.5 ms: no buffer [s]. A loaded loopback's own scheduling spread (the
 * demo beside an FE run: 0.8-2.3 ms) stays as the server was without it; a network's
 * (20 +- 5 ms: 6.6-9.4 ms) is played out. */
#define DEADBAND 0.0025
#define EXTRAPOLATE_NS 10000000LL /* a late sample's turn is bridged this long at most */
#define MAX_GAP_NS 20000000LL     /* ... from two samples at most this far apart */
#define MIN_GAP_NS 1000000LL      /* ... and at least this far */

void palp_srv_playout_init(palp_srv_playout *p, double reach) {
  memset(p, 0, sizeof *p);
  p->reach = reach > 0 ? reach : 0;
}

void palp_srv_playout_clear(palp_srv_playout *p) {
  p->head = p->n = 0;
  p->playing = 0;
}

static const palp_srv_playout_sample *at(const palp_srv_playout *p, int i) {
  return &p->s[(p->head + i) % PALP_SRV_PLAYOUT_SAMPLES];
}

int palp_srv_playout_push(palp_srv_playout *p, int64_t src_ns, int64_t recv_ns, palp_vec3 x, uint64_t seq) {
  /* Offsets between two clocks are relative, but must not overflow: a stamp at or beyond
   * +-2^61 ns (73 years) is not a clock reading (CLOCK_LIMIT). */
  if (src_ns >= CLOCK_LIMIT || src_ns <= -CLOCK_LIMIT || recv_ns >= CLOCK_LIMIT || recv_ns <= -CLOCK_LIMIT)
    return PALP_EINVAL;
  if (p->n > 0 && src_ns <= at(p, p->n - 1)->src_ns) {
    if (at(p, p->n - 1)->src_ns - src_ns < RESTART_NS) return 0; /* repeated or overtaken: the newer stands */
    palp_srv_playout_init(p, p->reach); /* the station's clock went back (a restart): start over */
  }
  const int64_t off = recv_ns - src_ns;
  /* Windowed minimum in two 1 s buckets: the fastest path lately, without a
   * sorted window; a path that became slower is adopted within 2 s. */
  if (p->samples == 0 || recv_ns - p->bucket_ns >= BUCKET_NS) {
    p->min_prev = p->samples == 0 ? off : p->min_cur;
    p->min_cur = off;
    p->bucket_ns = recv_ns;
  } else if (off < p->min_cur) {
    p->min_cur = off;
  }
  p->off[(p->off_head + p->off_n) % PALP_SRV_PLAYOUT_OFFSETS] = off;
  if (p->off_n < PALP_SRV_PLAYOUT_OFFSETS)
    p->off_n++;
  else
    p->off_head = (p->off_head + 1) % PALP_SRV_PLAYOUT_OFFSETS;
  p->samples++;
  if (p->samples <= 8 || p->samples % 8 == 0) p->off_dirty = 1;
  if (p->playing && src_ns < p->play_ns) p->late++; /* came after its turn: bridged (palp_srv_playout_at) */
  palp_srv_playout_sample *s;
  if (p->n < PALP_SRV_PLAYOUT_SAMPLES) {
    s = &p->s[(p->head + p->n) % PALP_SRV_PLAYOUT_SAMPLES];
    p->n++;
  } else {
    s = &p->s[p->head];
    p->head = (p->head + 1) % PALP_SRV_PLAYOUT_SAMPLES;
  }
  *s = (palp_srv_playout_sample){.src_ns = src_ns, .x = x, .seq = seq};
  return 1;
}

static int cmp64(const void *a, const void *b) {
  const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}

/* D [s]: the 90th percentile of how much later than the fastest path the recent
 * samples came; under DEADBAND none (a loopback's scheduling, a quiet LAN), at most
 * PALP_SRV_PLAYOUT_MAX_DELAY. Re-estimated every 8th sample: it moves slowly, and
 * a sort of 64 at every 1 kHz step of 32 sessions would cost 3% of a core. */
static double target_delay(palp_srv_playout *p, int64_t base) {
  if (!p->off_dirty) return p->delay;
  int64_t v[PALP_SRV_PLAYOUT_OFFSETS];
  for (int i = 0; i < p->off_n; i++) v[i] = p->off[(p->off_head + i) % PALP_SRV_PLAYOUT_OFFSETS] - base;
  qsort(v, (size_t)p->off_n, sizeof v[0], cmp64);
  double d = 1e-9 * (double)v[(p->off_n - 1) * 9 / 10];
  if (!(d >= DEADBAND)) d = 0;
  if (d > PALP_SRV_PLAYOUT_MAX_DELAY) d = PALP_SRV_PLAYOUT_MAX_DELAY;
  p->delay = d;
  p->off_dirty = 0;
  return d;
}

int palp_srv_playout_at(palp_srv_playout *p, int64_t now_ns, palp_vec3 *x, int64_t *src_ns, uint64_t *seq) {
  if (p->n == 0) return 0;
  const int64_t base = p->min_cur < p->min_prev ? p->min_cur : p->min_prev;
  const double d = target_delay(p, base);
  const int64_t target = now_ns - base - (int64_t)(d * 1e9);
  if (!p->playing || now_ns <= p->last_now_ns) {
    p->play_ns = p->playing ? p->play_ns : target;
  } else {
    const int64_t dt = now_ns - p->last_now_ns;
    const int64_t free_run = p->play_ns + dt;
    int64_t err = target - free_run;
    if (err > SNAP_NS || err < -SNAP_NS) {
      p->play_ns = target;
    } else {
      const int64_t lim = (int64_t)(SLEW * (double)dt);
      if (err > lim) err = lim;
      if (err < -lim) err = -lim;
      p->play_ns = free_run + err;
    }
  }
  /* No buffer wanted: never behind the freshest sample (the world sees the newest point). */
  if (d == 0 && p->play_ns < target) p->play_ns = target;
  p->playing = 1;
  p->last_now_ns = now_ns;
  if (d > p->delay_max) p->delay_max = d;

  const int64_t T = p->play_ns;
  const palp_srv_playout_sample *newest = at(p, p->n - 1);
  if (T >= newest->src_ns) {
    *x = newest->x;
    *src_ns = newest->src_ns;
    *seq = newest->seq;
    /* A sample late for its turn: continue the last motion for a little while
     * rather than stop and then jump to catch up (a palpating hand moves smoothly:
     * at 20 mm/s a reversal within EXTRAPOLATE_NS overshoots by at most 0.2 mm). */
    const int64_t ahead = T - newest->src_ns;
    if (p->n >= 2 && ahead > 0 && d > 0) {
      const palp_srv_playout_sample *a = at(p, p->n - 2);
      const int64_t gap = newest->src_ns - a->src_ns;
      /* Not from two stamps closer than a millisecond (no station samples that fast; a
       * forged pair 1 ns apart would make any speed), nor out of the reach the
       * validator allows (its ball is convex, so interpolated points stay in it;
       * continued ones might not). */
      if (gap >= MIN_GAP_NS && gap <= MAX_GAP_NS) {
        const int64_t by = ahead < EXTRAPOLATE_NS ? ahead : EXTRAPOLATE_NS;
        const double w = (double)by / (double)gap;
        const palp_vec3 y = {newest->x.x + w * (newest->x.x - a->x.x), newest->x.y + w * (newest->x.y - a->x.y),
                             newest->x.z + w * (newest->x.z - a->x.z)};
        if (!(p->reach > 0) || y.x * y.x + y.y * y.y + y.z * y.z <= p->reach * p->reach) {
          *x = y;
          *src_ns = newest->src_ns + by;
        }
      }
    }
    return 1;
  }
  int k = p->n - 2; /* the last sample at or before T */
  while (k >= 0 && at(p, k)->src_ns > T) k--;
  if (k < 0) { /* before the oldest kept: the oldest */
    *x = at(p, 0)->x;
    *src_ns = at(p, 0)->src_ns;
    *seq = at(p, 0)->seq;
    return 1;
  }
  const palp_srv_playout_sample *a = at(p, k), *b = at(p, k + 1);
  /* a <= T < b (k is the last at or before T; b is after it), so w is in [0, 1); held there
   * against rounding, since a weight outside it would move the device beyond both samples. */
  double w = (double)(T - a->src_ns) / (double)(b->src_ns - a->src_ns);
  if (!(w >= 0)) w = 0;
  if (w > 1) w = 1;
  *x = (palp_vec3){a->x.x + w * (b->x.x - a->x.x), a->x.y + w * (b->x.y - a->x.y), a->x.z + w * (b->x.z - a->x.z)};
  *src_ns = T;
  *seq = a->seq;
  return 1;
}
