/* test_ticker.c - the tick pool's own bookkeeping (server/ticker.c), with the session's tick, readiness and
 * settle replaced by stubs that the test times (no world, no DDS; ~6 s):
 *
 * - a session closed while its rebuild is in flight (session 82): its settle, stubbed as a helper's job
 *   that takes 300 ms, runs after the group's lock is released, so the other session of its group steps
 *   on meanwhile: at least 15 of the 60 slots at 200 Hz (until session 82 the settle ran under the
 *   lock: 0), and the closed one is not stepped once palp_srv_ticker_remove has returned;
 * - a pass stalled 60 ms (12 slots at 200 Hz): each session's skipped slots counted apart from its late
 *   steps (>= 8 skipped; late <= ticks: until session 82 the slots were added to its overruns, which then
 *   outnumbered its ticks after a stall), and told to the session's log in one overrun event for the
 *   stall's skipped slots, not one per slot (until session 89: 12 calls here; 60,000 per session, under
 *   the group's lock, after a 60 s stop at 1 kHz);
 * - a stall 4.6 s into a 5 s status period (0.2 Hz) is in that period's tick_us_max (>= 50 ms): until
 *   session 82 the pass times were kept for the first 4 s only;
 * - with two groups, one session's snapshot (palp_srv_ticker_with, the server's session_stats since
 *   session 89) is taken while the other group's pass is stalled 300 ms, not after it: it locks its own
 *   group alone (palp_srv_ticker_each waits for every group); none once the session is removed. */
#include <stdatomic.h>
#include <stdlib.h>
#include <time.h>

#include "check.h"
#include "palp_dds.h"
#include "ticker.h"

#define RATE_HZ 200.0

/* What the stubs do to each session: counted steps, a one-off stall of its next step, a job in flight. */
typedef struct stub {
  palp_srv_session *s;
  atomic_int steps;
  atomic_llong stall_ns;  /* the next step takes this long, once */
  atomic_int settling;    /* its settle is in progress */
  atomic_int other_steps; /* the other session's steps during the settle */
  atomic_int stalling;    /* its stalled step is in progress */
} stub;
static stub stubs[2];

static stub *stub_of(const palp_srv_session *s) { return &stubs[s == stubs[0].s ? 0 : 1]; }

static void nap_ns(int64_t ns) {
  struct timespec ts = {.tv_sec = (time_t)(ns / 1000000000), .tv_nsec = (long)(ns % 1000000000)};
  while (nanosleep(&ts, &ts) != 0) {
  }
}

int64_t palp_srv_session_tick(palp_srv_session *s, int64_t now_ns) {
  (void)now_ns;
  stub *st = stub_of(s);
  s->stats.ticks++;
  atomic_fetch_add(&st->steps, 1);
  const long long stall = atomic_exchange(&st->stall_ns, 0);
  if (stall > 0) {
    atomic_store(&st->stalling, 1);
    nap_ns(stall);
    atomic_store(&st->stalling, 0);
  }
  return 0;
}

int palp_srv_session_tick_ready(palp_srv_session *s) {
  (void)s;
  return 1;
}

/* A helper's job still running for 300 ms: what the real settle waits for (2-19 ms; long here so
 * that the other session's steps meanwhile are many). */
void palp_srv_session_factor_settle(palp_srv_session *s) {
  if (!s->factor.job) return;
  stub *st = stub_of(s), *other = &stubs[st == &stubs[0] ? 1 : 0];
  atomic_store(&st->settling, 1);
  const int before = atomic_load(&other->steps);
  nap_ns(300000000);
  atomic_store(&st->other_steps, atomic_load(&other->steps) - before);
  atomic_store(&st->settling, 0);
  s->factor.job = NULL;
}

/* The session log's overrun events: calls and the late steps they carry, per session. */
static atomic_int overrun_calls[2];
static atomic_llong overrun_steps[2];
static void on_overrun(void *ctx, uint32_t session_id, uint64_t n, int64_t late_ns) {
  (void)ctx, (void)late_ns;
  const int k = session_id == 1 ? 0 : 1;
  atomic_fetch_add(&overrun_calls[k], 1);
  atomic_fetch_add(&overrun_steps[k], (long long)n);
}

typedef struct counts {
  uint64_t ticks[2], overruns[2], skipped[2];
  int calls[2];       /* overrun events so far */
  long long told[2];  /* the late steps they carried */
} counts;

static void read_one(void *ctx, palp_srv_session *s) {
  counts *c = ctx;
  const int k = (int)(stub_of(s) - stubs);
  c->ticks[k] = s->stats.ticks, c->overruns[k] = s->stats.overruns, c->skipped[k] = s->stats.skipped;
  /* under the group's lock, as the events are told: the same moment as the counters */
  c->calls[k] = atomic_load(&overrun_calls[k]), c->told[k] = atomic_load(&overrun_steps[k]);
}

int main(void) {
  palp_srv_session *a = calloc(1, sizeof *a), *b = calloc(1, sizeof *b);
  if (!a || !b) return 2;
  a->id = 1, b->id = 2;
  const palp_srv_events ev = {.overrun = on_overrun};
  a->events = &ev, b->events = &ev;
  stubs[0].s = a, stubs[1].s = b;
  int rt = 0, err = 0;
  const double rate = RATE_HZ;
  palp_srv_ticker *t = palp_srv_ticker_create_rates(1, &rate, 1, 4, 0, 0.2, &rt, &err);
  if (!t) {
    fprintf(stderr, "FAIL ticker not created (%d)\n", err);
    return 1;
  }
  palp_srv_tick_stats ts;
  palp_srv_ticker_stats(t, &ts); /* the status period starts now */
  CHECK(palp_srv_ticker_add(t, a) == 0 && palp_srv_ticker_add(t, b) == 0, "two sessions in the one group");
  nap_ns(300000000);

  /* A pass stalled 60 ms: 12 slots at 200 Hz, each a slot skipped by both sessions. */
  int calls0[2];
  for (int k = 0; k < 2; k++) calls0[k] = atomic_load(&overrun_calls[k]);
  atomic_store(&stubs[0].stall_ns, 60000000);
  nap_ns(300000000);
  counts c = {0};
  palp_srv_ticker_each(t, read_one, &c);
  for (int k = 0; k < 2; k++) {
    const int calls = c.calls[k] - calls0[k];
    const long long steps = c.told[k];
    /* the stalled tick itself (session 1), the skipped slots once; a loaded machine may add a late tick or two */
    CHECK(calls >= 1 && calls <= 4 && steps == (long long)c.overruns[k],
          "session %d's log told of its %llu late steps in %d overrun event(s) over the stall (want 1..4, carrying "
          "%lld steps: all of them)", k + 1, (unsigned long long)c.overruns[k], calls, steps);
  }
  for (int k = 0; k < 2; k++)
    CHECK(c.skipped[k] >= 8 && c.overruns[k] >= c.skipped[k] && c.overruns[k] <= c.ticks[k] + c.skipped[k],
          "session %d after a 60 ms stall: %llu of %llu steps taken and slots skipped late, %llu slots skipped (want "
          ">= 8 skipped, each counted late, late <= steps + skipped)", k + 1, (unsigned long long)c.overruns[k],
          (unsigned long long)(c.ticks[k] + c.skipped[k]), (unsigned long long)c.skipped[k]);

  /* Session 1 closes with a job in flight: session 2 steps on during its settle. */
  a->factor.job = (palp_factor_job *)(void *)&stubs[0]; /* never run: the stub settle only times it */
  const int64_t r0 = palp_dds_now_ns();
  palp_srv_ticker_remove(t, a);
  const double took = (double)(palp_dds_now_ns() - r0) * 1e-9;
  const int other = atomic_load(&stubs[0].other_steps);
  CHECK(took >= 0.29 && other >= 15,
        "session 2 stepped %d times during session 1's 300 ms settle at %.0f Hz (remove took %.2f s; want >= 15 of "
        "%.0f)", other, RATE_HZ, took, 0.3 * RATE_HZ);
  CHECK(a->factor.job == NULL && a->factor_pool == NULL, "session 1's job settled and its pool let go");
  const int a_steps = atomic_load(&stubs[0].steps);
  nap_ns(100000000);
  CHECK(atomic_load(&stubs[0].steps) == a_steps, "session 1 not stepped after its remove (%d then %d)", a_steps,
        atomic_load(&stubs[0].steps));

  /* A 60 ms pass 4.6 s into a 5 s status period begun after the stall above: in the period's max. */
  palp_srv_ticker_stats(t, &ts);
  const int64_t p0 = palp_dds_now_ns();
  const int64_t at = p0 + 4600000000LL - palp_dds_now_ns();
  if (at > 0) nap_ns(at);
  atomic_store(&stubs[1].stall_ns, 60000000);
  nap_ns(300000000);
  palp_srv_ticker_stats(t, &ts);
  CHECK(ts.tick_us_max >= 50000, "a 60 ms pass %.1f s into the status period: tick_us_max %.0f us (want >= 50000)",
        (double)(palp_dds_now_ns() - p0) * 1e-9 - 0.3, ts.tick_us_max);
  CHECK(ts.late_steps <= ts.steps + ts.skipped_steps && ts.late_steps >= ts.skipped_steps && ts.skipped_steps >= 16,
        "the pool: %llu of %llu steps late, %llu slots dropped, %llu steps skipped", (unsigned long long)ts.late_steps,
        (unsigned long long)ts.steps, (unsigned long long)ts.lost_slots, (unsigned long long)ts.skipped_steps);
  palp_srv_ticker_remove(t, b);
  palp_srv_ticker_destroy(t);

  /* Two groups at 200 Hz, a in the first and b in the second (each to the group with fewer). */
  palp_srv_ticker *t2 = palp_srv_ticker_create_rates(2, &rate, 1, 4, 0, 0.2, &rt, &err);
  if (!t2) {
    fprintf(stderr, "FAIL ticker of two groups not created (%d)\n", err);
    return 1;
  }
  CHECK(palp_srv_ticker_add(t2, a) == 0 && palp_srv_ticker_add(t2, b) == 0 && a->tick_group != b->tick_group,
        "a and b in groups %d and %d", a->tick_group, b->tick_group);
  nap_ns(50000000);
  atomic_store(&stubs[1].stall_ns, 300000000);
  for (int i = 0; i < 200 && !atomic_load(&stubs[1].stalling); i++) nap_ns(5000000);
  const int b_stalled = atomic_load(&stubs[1].stalling);
  counts c2 = {0};
  const int with = palp_srv_ticker_with(t2, a, read_one, &c2);
  const int still = atomic_load(&stubs[1].stalling);
  CHECK(b_stalled && with == 1 && still && c2.ticks[0] > 0,
        "a's snapshot taken while b's group is in a 300 ms pass (b stalling %d then %d, taken %d, a's steps %llu)",
        b_stalled, still, with, (unsigned long long)c2.ticks[0]);
  palp_srv_ticker_remove(t2, a);
  CHECK(palp_srv_ticker_with(t2, a, read_one, &c2) == 0 && a->tick_group == 0, "none of a once removed");
  palp_srv_ticker_remove(t2, b);
  palp_srv_ticker_destroy(t2);
  free(a);
  free(b);
  fprintf(stderr, "%s\n", failures ? "FAILED" : "passed");
  return failures != 0;
}
