/*
 * test_episode.c - when the station tells the trainee that the force on her hand is limited
 * and that it is back under the limit, or that the phantom is outside the model's valid range
 * and back inside (client/episode.h). The station's main loop looks every ~20 ms; these are
 * its looks, scripted. Times are exact multiples of the look period; tolerance 1e-9 s.
 */
#include <math.h>

#include "check.h"
#include "episode.h"

#define LOOK 0.02 /* [s] the station's main loop waits up to 20 ms between looks */

typedef struct counts {
  int began, over;
  double first_began, last_over_at, last_over_clear, last_duration;
} counts;

/* Looks from t0 to t1 (inclusive, every LOOK) with the condition given by on(t). */
static void run(palp_cli_episode *e, counts *c, double t0, double t1, int (*on)(double)) {
  const int n = (int)lround((t1 - t0) / LOOK);
  for (int i = 0; i <= n; ++i) {
    const double t = t0 + i * LOOK;
    const int r = palp_cli_episode_update(e, t, on(t));
    if (r == PALP_CLI_EPISODE_BEGAN) {
      if (c->began++ == 0) c->first_began = t;
    }
    if (r == PALP_CLI_EPISODE_OVER)
      c->over++, c->last_over_at = t, c->last_over_clear = e->clear_since, c->last_duration = e->last_on - e->began;
  }
}

static int near(double t, double u) { return fabs(t - u) < 0.5 * LOOK; }

/* A press held at the limit from 1.00 to 3.00 s that dips under it for one look at 1.50 and
 * for two at 2.00-2.02 (what a press at the limit does), then released. */
static int held_with_dips(double t) {
  if (t < 1.0 - 1e-9 || t > 3.0 + 1e-9) return 0;
  return !(near(t, 1.50) || near(t, 2.00) || near(t, 2.02));
}
/* Clear for 0.20 s (under the 0.25 s hold) between two presses. */
static int short_gap(double t) { return (t > 1.0 - 1e-9 && t < 2.0 - 1e-9) || (t > 2.2 - 1e-9 && t < 3.0 + 1e-9); }
/* The valid range: flagged models at 1.00-1.40 s and, after 0.40 s clear, 1.80-2.00 s (the
 * skin's check revisits a hinge every 0.2 s, so it is clear for a while within one press). */
static int flicker(double t) { return (t > 1.0 - 1e-9 && t < 1.4 + 1e-9) || (t > 1.8 - 1e-9 && t < 2.0 + 1e-9); }

int main(void) {
  /* 1. The force limit: one announcement each way for a held press with dips. */
  palp_cli_episode e = palp_cli_episode_make(PALP_CLI_LIMIT_HOLD_S);
  counts c = {0};
  run(&e, &c, 0.0, 4.0, held_with_dips);
  CHECK(c.began == 1 && near(c.first_began, 1.0), "limit: FORCE LIMITED once, at 1.00 s (%d, first at %.2f s)", c.began,
        c.first_began);
  CHECK(c.over == 1, "limit: back under the limit once (%d)", c.over);
  CHECK(fabs(c.last_over_clear - 3.02) < 1e-9, "limit: said to be back from 3.02 s, the first look clear after the "
        "press (%.9f s)", c.last_over_clear);
  CHECK(c.last_over_at >= 3.02 + PALP_CLI_LIMIT_HOLD_S - 1e-9 && c.last_over_at < 3.02 + PALP_CLI_LIMIT_HOLD_S + LOOK,
        "limit: said once it had been clear %.2f s (at %.2f s)", PALP_CLI_LIMIT_HOLD_S, c.last_over_at);

  /* Without a hold the same press makes three episodes: what the hold is for. */
  e = palp_cli_episode_make(0.0);
  c = (counts){0};
  run(&e, &c, 0.0, 4.0, held_with_dips);
  CHECK(c.began == 3 && c.over == 3, "no hold: the dips make 3 episodes each way (%d, %d)", c.began, c.over);

  /* 2. A gap shorter than the hold is one episode; the hold counts from the first clear look. */
  e = palp_cli_episode_make(PALP_CLI_LIMIT_HOLD_S);
  c = (counts){0};
  run(&e, &c, 0.0, 4.0, short_gap);
  CHECK(c.began == 1 && c.over == 1 && fabs(c.last_over_clear - 3.02) < 1e-9,
        "limit: a 0.20 s gap stays one episode (%d began, %d over, clear from %.2f s)", c.began, c.over,
        c.last_over_clear);

  /* 3. A late look: the loop stalled 1 s after the first clear look, then the episode is over at once. */
  e = palp_cli_episode_make(PALP_CLI_LIMIT_HOLD_S);
  int r1 = palp_cli_episode_update(&e, 1.00, 1), r2 = palp_cli_episode_update(&e, 1.02, 0),
      r3 = palp_cli_episode_update(&e, 2.02, 0), r4 = palp_cli_episode_update(&e, 2.04, 0);
  CHECK(r1 == PALP_CLI_EPISODE_BEGAN && r2 == PALP_CLI_EPISODE_QUIET && r3 == PALP_CLI_EPISODE_OVER &&
            r4 == PALP_CLI_EPISODE_QUIET,
        "limit: began, quiet, over after a stalled second, then quiet (%d %d %d %d)", r1, r2, r3, r4);
  /* ... but a first clear look that comes late does not count the stall as clear */
  e = palp_cli_episode_make(PALP_CLI_LIMIT_HOLD_S);
  r1 = palp_cli_episode_update(&e, 1.00, 1), r2 = palp_cli_episode_update(&e, 2.00, 0);
  CHECK(r1 == PALP_CLI_EPISODE_BEGAN && r2 == PALP_CLI_EPISODE_QUIET,
        "limit: the first clear look after a stall is not yet over (%d %d)", r1, r2);

  /* 4. The valid range: 0.40 s clear inside a press stays one episode under the 0.5 s hold, and
   * its duration runs from the first flagged look to the last (1.00 to 2.00 s). */
  e = palp_cli_episode_make(PALP_CLI_RANGE_HOLD_S);
  c = (counts){0};
  run(&e, &c, 0.0, 3.0, flicker);
  CHECK(c.began == 1 && c.over == 1, "range: one OUTSIDE and one back inside (%d, %d)", c.began, c.over);
  CHECK(fabs(c.last_duration - 1.0) < 1e-9, "range: outside for 1.00 s (%.9f)", c.last_duration);
  CHECK(c.last_over_at >= 2.02 + PALP_CLI_RANGE_HOLD_S - 1e-9, "range: back inside said at %.2f s, after %.2f s clear",
        c.last_over_at, PALP_CLI_RANGE_HOLD_S);
  return check_exit();
}
