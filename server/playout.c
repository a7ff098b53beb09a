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
/* A clock reading is |t| < LIM = 2^62 ns: 146 years either side of the clock's zero, so a
 * monotonic clock, or Unix time until 2116 (at 2^61, the bound session 75 set, Unix-time
 * stamps would have been refused from 2043). What that bound guarantees, and what it does not:
 *  - two stamps (or two arrivals) differ by at most 2 (LIM - 1) = 2^63 - 2: exact in int64;
 *  - so does an offset, arrival - stamp: |off| <= 2^63 - 2;
 *  - two offsets, or a time and an offset, may differ by up to ~2^64 or 3 * 2^62: NOT int64. Those
 *    differences go through sub_held, exact up to LIM in magnitude and held at +-LIM beyond it,
 *    for any int64 operands. Every quantity the playout acts on is milliseconds (D <= 30 ms, a
 *    snap at 50 ms, a restart at 1 s), so a held difference acts as what it is: too far;
 *  - the playout time T is held to [-LIM, LIM]: a T beyond every stamp (|stamp| < LIM) plays the
 *    newest or the oldest sample as a larger one would, and T - stamp stays within 2^63 - 1. */
#define LIM (1LL << 62)
#define RESTART_NS 1000000000LL /* a stamp this much older than the newest: a new clock */
/* Jitter under 2.5 ms: no buffer [s]. A loaded loopback's own scheduling spread (the
 * demo beside an FE run: 0.8-2.3 ms) stays as the server was without it; a network's
 * (20 +- 5 ms: 6.6-9.4 ms) is played out. */
#define DEADBAND 0.0025
#define EXTRAPOLATE_NS 10000000LL /* a late sample's turn is bridged this long at most */
#define MAX_GAP_NS 20000000LL     /* ... from two samples at most this far apart */
#define MIN_GAP_NS 1000000LL      /* ... and at least this far */

void palp_srv_playout_init(palp_srv_playout *p, double reach, double step) {
  memset(p, 0, sizeof *p);
  p->reach = reach > 0 ? reach : 0;
  /* a step of a day or more is no world's (and CATCHUP steps of it stay far inside int64) */
  p->step_ns = step > 0 && step < 86400.0 ? (int64_t)(step * 1e9) : 0;
}

void palp_srv_playout_clear(palp_srv_playout *p) {
  p->head = p->n = 0;
  p->playing = p->have_played = p->catching = p->told = 0;
}

int palp_srv_playout_start(palp_srv_playout *p, int64_t src_ns, palp_vec3 x, uint64_t seq) {
  if (src_ns >= LIM || src_ns <= -LIM) return PALP_EINVAL; /* not a clock reading (LIM) */
  palp_srv_playout_clear(p);
  p->s[0] = (palp_srv_playout_sample){.src_ns = src_ns, .x = x, .seq = seq};
  p->n = 1;
  p->played_ns = src_ns;
  p->have_played = 1;
  p->catching = p->told = 1; /* a placement brought in, not a gap: not counted as one */
  return PALP_OK;
}

static const palp_srv_playout_sample *at(const palp_srv_playout *p, int i) {
  return &p->s[(p->head + i) % PALP_SRV_PLAYOUT_SAMPLES];
}

/* a - b [ns] for any int64 a, b, held to [-LIM, LIM] (exact when |a - b| <= LIM). The held end
 * is tested before subtracting: for b >= 0, b - LIM is in [-LIM, LIM) and a - b cannot exceed a;
 * for b < 0, b + LIM is in [-LIM, LIM) and a - b cannot fall below a + 1; so a - b is computed
 * only where it lies in [-LIM, a] or [a + 1, LIM], within int64. */
static int64_t sub_held(int64_t a, int64_t b) {
  if (b >= 0 ? a < b - LIM : a > b + LIM) return b >= 0 ? -LIM : LIM;
  const int64_t d = a - b;
  return d > LIM ? LIM : d < -LIM ? -LIM : d;
}

int palp_srv_playout_push(palp_srv_playout *p, int64_t src_ns, int64_t recv_ns, palp_vec3 x, uint64_t seq) {
  /* A stamp at or beyond +-2^62 ns (146 years) is not a clock reading (LIM). */
  if (src_ns >= LIM || src_ns <= -LIM || recv_ns >= LIM || recv_ns <= -LIM) return PALP_EINVAL;
  if (p->n > 0 && src_ns <= at(p, p->n - 1)->src_ns) {
    /* two stamps: exact (LIM) */
    if (at(p, p->n - 1)->src_ns - src_ns < RESTART_NS) return 0; /* repeated or overtaken: the newer stands */
    /* the station's clock went back (a restart): start over */
    palp_srv_playout_init(p, p->reach, 1e-9 * (double)p->step_ns);
  }
  const int64_t off = recv_ns - src_ns; /* |off| <= 2^63 - 2 (LIM) */
  /* Windowed minimum in two 1 s buckets: the fastest path lately, without a
   * sorted window; a path that became slower is adopted within 2 s. */
  if (p->samples == 0 || recv_ns - p->bucket_ns >= BUCKET_NS) { /* two arrivals: exact */
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
    /* Full. While a gap is caught up, the oldest two samples may be the ones around the point
     * played (the last before the gap, the first after it): the second of them goes instead,
     * so that the point keeps a sample on either side and moves on from where it is (a
     * straight path across the gap to a later sample) rather than jumping to the oldest kept. */
    if (p->have_played && at(p, 1)->src_ns > p->played_ns)
      p->s[(p->head + 1) % PALP_SRV_PLAYOUT_SAMPLES] = p->s[p->head];
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
  /* Two offsets may be ~2^64 apart (a station clock that leapt forward): held, which keeps the
   * order the percentile needs, and any held lateness is far beyond the cap. */
  for (int i = 0; i < p->off_n; i++) v[i] = sub_held(p->off[(p->off_head + i) % PALP_SRV_PLAYOUT_OFFSETS], base);
  qsort(v, (size_t)p->off_n, sizeof v[0], cmp64);
  double d = 1e-9 * (double)v[(p->off_n - 1) * 9 / 10];
  if (!(d >= DEADBAND)) d = 0;
  if (d > PALP_SRV_PLAYOUT_MAX_DELAY) d = PALP_SRV_PLAYOUT_MAX_DELAY;
  p->delay = d;
  p->off_dirty = 0;
  return d;
}

int palp_srv_playout_at(palp_srv_playout *p, int64_t now_ns, palp_vec3 *x, int64_t *src_ns, uint64_t *seq) {
  if (now_ns >= LIM || now_ns <= -LIM) return PALP_EINVAL; /* not a clock reading (LIM) */
  if (p->n == 0) return 0;
  const int64_t base = p->min_cur < p->min_prev ? p->min_cur : p->min_prev;
  const double d = target_delay(p, base);
  /* now - base: a time less an offset, up to 3 * 2^62 (LIM): held, then D (<= 30 ms) off it. */
  const int64_t target = sub_held(sub_held(now_ns, base), (int64_t)(d * 1e9));
  if (!p->playing || now_ns <= p->last_now_ns) {
    p->play_ns = p->playing ? p->play_ns : target;
  } else {
    /* err = target - (T + dt), the free-running T's distance from its target. dt is two
     * server times apart (exact, < 2^63). target and T are in [-LIM, LIM], so target - T may reach
     * 2^63: held, and a held gap (146 years) snaps; otherwise err is exact wherever it matters
     * (held beyond LIM, it snaps too). */
    const int64_t dt = now_ns - p->last_now_ns;
    const int64_t gap = sub_held(target, p->play_ns);
    const int64_t err = sub_held(gap, dt);
    if (gap == LIM || gap == -LIM || err > SNAP_NS || err < -SNAP_NS) {
      p->play_ns = target;
    } else {
      /* T + dt + step, written as target - (err - step) (T + dt = target - err, |err| <= 50 ms)
       * so that T + dt, which a huge dt would overflow, is never formed. */
      const int64_t lim = (int64_t)(SLEW * (double)dt);
      const int64_t step = err > lim ? lim : err < -lim ? -lim : err;
      p->play_ns = target - (err - step);
    }
  }
  /* No buffer wanted: never behind the freshest sample (the world sees the newest point). */
  if (d == 0 && p->play_ns < target) p->play_ns = target;
  /* Held to [-LIM, LIM] (a slewed T may lie 50 ms outside): beyond every stamp either way. */
  if (p->play_ns > LIM) p->play_ns = LIM;
  if (p->play_ns < -LIM) p->play_ns = -LIM;
  p->playing = 1;
  p->last_now_ns = now_ns;
  if (d > p->delay_max) p->delay_max = d;

  /* S: the station time played at this step. T, unless a gap is being caught up: then the
   * last one played plus what the catch-up allows (playout.h, "A gap is caught up"). Both are
   * in [-LIM, LIM], so their difference is held (exact where it matters, up to LIM). */
  int64_t S = p->play_ns;
  const palp_srv_playout_sample *newest = at(p, p->n - 1);
  if (p->have_played && p->step_ns > 0) {
    /* lag: how far the station time played trails the latest there is to play (the newest
     * sample, or T if that is earlier). most: the advance allowed, CATCHUP steps, or lag
     * step / CATCHUP_TIME when more (a long gap then shrinks by e^-1 every CATCHUP_TIME).
     * A lag beyond CATCHUP_MAX is jumped. */
    const int64_t due = S < newest->src_ns ? S : newest->src_ns, lag = sub_held(due, p->played_ns);
    int64_t most = PALP_SRV_PLAYOUT_CATCHUP * p->step_ns;
    const double prop = (double)lag * ((double)p->step_ns / (PALP_SRV_PLAYOUT_CATCHUP_TIME * 1e9));
    /* held at lag before the conversion: a day-long step times a 146-year lag is no int64 */
    if (prop > (double)most) most = prop >= (double)lag ? lag : (int64_t)prop;
    const int catching = lag > most && lag <= (int64_t)(PALP_SRV_PLAYOUT_CATCHUP_MAX * 1e9);
    if (catching) { /* played + most < due: no overflow */
      S = p->played_ns + most;
      p->behind_steps++;
      if (1e-9 * (double)(lag - most) > p->behind_max) p->behind_max = 1e-9 * (double)(lag - most);
      /* Told once per catch-up, as its lag first reaches GAP_NOTED: not only as it begins, since a
       * stall may come while a loaded link's small lag is caught up (session 87's CI: a 0.3 s stop
       * of the server then went untold). */
      if (!p->told && 1e-9 * (double)lag >= PALP_SRV_PLAYOUT_GAP_NOTED)
        p->gaps++, p->gap_last = 1e-9 * (double)lag, p->told = 1;
    } else p->told = 0;
    p->catching = catching;
  }

  if (S >= newest->src_ns) {
    *x = newest->x;
    *src_ns = newest->src_ns;
    *seq = newest->seq;
    /* A sample late for its turn: continue the last motion for a little while
     * rather than stop and then jump to catch up (a palpating hand moves smoothly:
     * at 20 mm/s a reversal within EXTRAPOLATE_NS overshoots by at most 0.2 mm). */
    const int64_t ahead = S - newest->src_ns;
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
    p->played_ns = *src_ns;
    p->have_played = 1;
    return 1;
  }
  int k = p->n - 2; /* the last sample at or before S */
  while (k >= 0 && at(p, k)->src_ns > S) k--;
  if (k < 0) { /* before the oldest kept: the oldest */
    *x = at(p, 0)->x;
    *src_ns = at(p, 0)->src_ns;
    *seq = at(p, 0)->seq;
    p->played_ns = *src_ns;
    p->have_played = 1;
    return 1;
  }
  const palp_srv_playout_sample *a = at(p, k), *b = at(p, k + 1);
  /* a <= S < b (k is the last at or before S; b is after it), so w is in [0, 1); held there
   * against rounding, since a weight outside it would move the device beyond both samples. */
  double w = (double)(S - a->src_ns) / (double)(b->src_ns - a->src_ns);
  if (!(w >= 0)) w = 0;
  if (w > 1) w = 1;
  *x = (palp_vec3){a->x.x + w * (b->x.x - a->x.x), a->x.y + w * (b->x.y - a->x.y), a->x.z + w * (b->x.z - a->x.z)};
  *src_ns = S;
  *seq = a->seq;
  p->played_ns = S;
  p->have_played = 1;
  return 1;
}
