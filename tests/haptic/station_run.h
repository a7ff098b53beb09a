/* station_run.h - one simulated-device trainee over real DDS, for the haptic
 * station tests: joins a phantom, runs the 1 kHz haptic loop along a trajectory,
 * pumps local models into it, and returns the loop's stats and trace. It joins as
 * palp-client joins a position-driven trainee (local_models_only: no Feedback
 * reader), so the tests' local models arrive without the summary beside them. */
#ifndef PALP_TEST_HAPTIC_STATION_RUN_H
#define PALP_TEST_HAPTIC_STATION_RUN_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "haptic_loop.h"
#include "harness.h"
#include "input.h"

typedef struct station_run {
  palp_cli_haptic_stats hs;
  palp_cli_haptic_sample *trace;
  double reply_rate_hz;      /* physics rate the server said */
  uint64_t models_seen;      /* samples fed to the loop */
  uint64_t bad;              /* dropped as invalid */
  double lat_p50_us;
  /* The models' steps: the server publishes one every physics step while the finger is down,
   * so a step between two taken models that none came for was lost on the way or overwritten in
   * the reader's history before the main thread took it. */
  uint64_t frame_first, frame_last, frames_missing;
  /* As palp-client: the session's state looked at every 100 ms (palp_cli_station_session_closed) and
   * what other participants wrote into the session said (palp_cli_station_foreign_news). */
  int closed;           /* the station took its session for closed, and stopped */
  char reason[128];
  uint64_t ignored;     /* samples dropped as not its server's (st.bind.ignored) */
  int news;             /* times the news said so (palp-client tells the trainee each time) */
  char news_line[400];  /* ... its line */
} station_run;

/* Called with the joined station before the haptic loop starts (phase 0) and after it ended, before
 * the station leaves (phase 1): a test's forger starts there and its checks run. */
typedef void (*station_run_hook)(palp_cli_station *st, int phase, void *ctx);

/* Each model the loop takes (the haptic loop's on_model, the main thread). */
static void sr_on_model(void *ctx, const palp_local_model *m, uint64_t frame) {
  station_run *o = ctx;
  (void)m;
  if (o->frame_last && frame > o->frame_last + 1) o->frames_missing += frame - o->frame_last - 1;
  if (!o->frame_first) o->frame_first = frame;
  if (frame > o->frame_last) o->frame_last = frame;
}

static int sr_cmp(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Runs one trainee on `domain`, phantom `phantom`, along traj; trace_cap ticks kept. The main
 * thread sleeps feed_pause [s] after each take of the models (0: none), as a busy machine's
 * scheduler may hold palp-client's. */
static void station_run_hooked(unsigned domain, uint32_t phantom, const char *label, const palp_cli_simdevice_def *traj,
                               double station_max_force, int rt_priority, size_t trace_cap, double feed_pause,
                               station_run_hook hook, void *hook_ctx, station_run *out) {
  memset(out, 0, sizeof *out);
  palp_cli_station st;
  /* joined as palp-client joins a position-driven trainee: local models, no Feedback reader */
  const palp_cli_join j = {.role = palp_ROLE_TRAINEE, .phantom_id = phantom, .user_name = label, .want_feedback = 1,
                           .local_models_only = 1, .timeout = 10};
  test_station_join_as(&st, domain, label, &j);
  CHECK(st.local_model_r > 0 && st.feedback_r == 0, "%s: a local-model reader and no Feedback reader", label);
  out->reply_rate_hz = st.tick_rate_hz;
  palp_cli_input in;
  if (palp_cli_simdevice_input(traj, &in) < 0 || in.open(in.ctx, 0.04) < 0) {
    fprintf(stderr, "cannot make the simulated device\n");
    exit(1);
  }
  palp_cli_haptic_def d = palp_cli_haptic_default_def();
  d.physics_rate_hz = st.tick_rate_hz;
  { /* the phantom's limit from the catalogue, as palp-client takes it */
    palp_Phantom ph;
    char perr[256];
    if (palp_cli_station_catalogue(&st, st.phantom_id, 10, &ph, perr, sizeof perr) == 0) {
      d.phantom_max_force = ph.max_force;
      palp_cli_phantom_free(&ph);
    }
  }
  d.rt_priority = rt_priority;
  if (hook) hook(&st, 0, hook_ctx);
  if (station_max_force > 0) d.render.max_force = station_max_force;
  d.in = &in;
  d.contact_w = st.contact_w;
  d.session_id = st.session_id;
  d.trace = calloc(trace_cap, sizeof *d.trace);
  d.trace_cap = trace_cap;
  d.timer_floor = 1; /* as palp-client runs it */
  d.on_model = sr_on_model;
  d.on_model_ctx = out;
  palp_cli_haptic_loop *hl = calloc(1, sizeof *hl);
  char err[256];
  if (!d.trace || !hl || palp_cli_haptic_start(hl, &d, err, sizeof err) < 0) {
    fprintf(stderr, "haptic loop: %s\n", err);
    exit(1);
  }
  dds_entity_t ws = dds_create_waitset(st.pp);
  dds_entity_t rc = dds_create_readcondition(st.local_model_r, DDS_ANY_STATE);
  dds_waitset_attach(ws, rc, 0);
  size_t nl = 0, cap = 100000;
  double *lat = calloc(cap, sizeof *lat);
  int64_t next_check = palp_dds_now_ns();
  while (!palp_cli_haptic_done(hl)) {
    dds_waitset_wait(ws, NULL, 0, DDS_MSECS(20));
    double l_us;
    const int n = palp_cli_haptic_feed(hl, &st, &out->bad, &l_us);
    if (n > 0) out->models_seen += (uint64_t)n;
    if (n > 0 && isfinite(l_us) && nl < cap) lat[nl++] = l_us;
    if (feed_pause > 0) test_sleep(feed_pause);
    if (palp_dds_now_ns() >= next_check) {
      next_check = palp_dds_now_ns() + 100000000;
      if (palp_cli_station_session_closed(&st, out->reason, sizeof out->reason)) {
        out->closed = 1;
        break;
      }
      char said[400], who[64];
      if (palp_cli_station_foreign_news(&st, said, sizeof said, who, sizeof who)) {
        out->news++;
        snprintf(out->news_line, sizeof out->news_line, "%s", said);
      }
    }
  }
  palp_cli_haptic_join(hl, &out->hs);
  if (hook) hook(&st, 1, hook_ctx);
  char said[400], who[64];
  if (palp_cli_station_foreign_news(&st, said, sizeof said, who, sizeof who)) {
    out->news++;
    snprintf(out->news_line, sizeof out->news_line, "%s", said);
  }
  out->ignored = st.bind.ignored;
  out->trace = d.trace;
  /* The timer floor ran beside the loop, at its rate, over the same seconds: its span in
   * periods (the wake-ups plus the deadlines skipped after a wake-up more than a period
   * late) is the loop's, within 1% + 5 (the floor starts half a period after the loop and
   * stops just after it). The wake-ups alone are not: on an oversubscribed machine the
   * loop, preempted in its work, skips deadlines the idle floor does not (a fresh clone's
   * test run, 2026-12-03: 1974 against 2040 over 2.1 s, 7.6% of the loop's ticks late). */
  const palp_cli_haptic_stats *h = &out->hs;
  printf("%s: timer floor beside the loop: %llu of %llu ticks late by > 0.5 ms (%.3f%%, worst %.2f ms); the loop "
         "%llu of %llu (%.3f%%, worst %.2f ms)\n", label, (unsigned long long)h->floor_late_ticks,
         (unsigned long long)h->floor_ticks, h->floor_ticks ? 100.0 * (double)h->floor_late_ticks / (double)h->floor_ticks : 0.0,
         h->floor_late_max * 1e3, (unsigned long long)h->late_ticks, (unsigned long long)h->ticks,
         h->ticks ? 100.0 * (double)h->late_ticks / (double)h->ticks : 0.0, h->late_max * 1e3);
  const double loop_span = (double)(h->ticks + h->missed), floor_span = (double)(h->floor_ticks + h->floor_missed);
  CHECK(h->floor_ticks > 0 && fabs(floor_span - loop_span) <= 0.01 * loop_span + 5 &&
            h->floor_late_ticks <= h->floor_ticks && isfinite(h->floor_late_max) && h->floor_late_max >= 0,
        "%s: the timer floor ran beside the loop: %llu + %llu skipped periods against the loop's %llu + %llu "
        "(tolerance 1%% + 5)", label, (unsigned long long)h->floor_ticks, (unsigned long long)h->floor_missed,
        (unsigned long long)h->ticks, (unsigned long long)h->missed);
  if (nl) {
    qsort(lat, nl, sizeof *lat, sr_cmp);
    out->lat_p50_us = lat[(nl - 1) / 2];
  }
  free(lat);
  dds_delete(rc);
  dds_delete(ws);
  in.close(in.ctx);
  free(hl);
  palp_cli_station_leave(&st);
  test_sleep(0.1);
  palp_cli_station_close(&st);
}

static void station_run_once(unsigned domain, uint32_t phantom, const char *label, const palp_cli_simdevice_def *traj,
                             double station_max_force, int rt_priority, size_t trace_cap, double feed_pause,
                             station_run *out) {
  station_run_hooked(domain, phantom, label, traj, station_max_force, rt_priority, trace_cap, feed_pause, NULL, NULL, out);
}

#endif
