/*
 * test_relay.c - the station's haptic loop over an emulated network (issue 11):
 * the server on DDS domain 112, the station on 113, palp-netem's relay between
 * them with 20 ms +- 5 ms one-way delay and 5% loss (seeded). The same
 * simulated-device trajectory (press 12 mm at 10 mm/s, hold 0.5 s, slide 20 mm
 * at 20 mm/s, hold, release: a palpation's pace) runs once directly on 112 (the
 * undelayed run) and once through the relay. A 40 ms round trip delays what the
 * station learns of the phantom; the test prints that floor (the undelayed force
 * against itself shifted by the measured latency). Asserted:
 *  - the haptic loop holds 1 kHz: late ticks (> 0.5 ms after their deadline) and
 *    missing ticks (time without a fresh force: a tick more than a period late is
 *    not made up) each at most max(25%, 2 x floor + 1%), where the floor is this
 *    machine's own: the same haptic loop with the simulated device and no DDS,
 *    no server, no relay, measured for 2 s at the start of the same run. The 25%
 *    is a regression guard, not the target: a loop that waited on DDS or
 *    on the 20 ms network would lose ~95% of its ticks, while fresh-clone runs on
 *    this shared 2-core VM lose 1-10% with SCHED_FIFO granted (the floor alone is
 *    0.2-1.2%, worst wake-up 5-7 ms), so the 0.1% cannot be asserted here;
 *    the test prints the figures against it;
 *  - the relayed station receives more than half of the physics steps' local
 *    models (250 Hz over the press; 5% are lost and the server's ticks overrun on
 *    a loaded machine);
 *  - the rendered force stays within 10% of the undelayed run's peak (RMS of the
 *    difference over the trajectory, on a common 1 ms grid; max and p99 printed);
 *  - no oscillation: the force's content above ~25 Hz (|F| minus its centred
 *    40 ms moving average, RMS) is at most twice the undelayed run's plus 1% of
 *    its peak;
 *  - the relayed station's server is the relay (2026-12-06): it answers the JOIN and writes the
 *    session's samples from its one participant, so the station, which reads only the participant
 *    that accepted its JOIN, takes its local models and ignores none;
 *  - each session's peak force in the server's own steps (what its log keeps as the trainee's) is
 *    at most twice the undelayed station's rendered peak (session 86): in 14 of ~100 runs of this
 *    test on a starved machine it was 0.44-13.5 N in this 0.4 N press, the phantom's answer to a
 *    device point that jumped millimetres within a step after a gap (server/playout.h).
 */
#define _DEFAULT_SOURCE /* getloadavg */
#include <stdlib.h>
#include <unistd.h>

#include <pthread.h>
#include <string.h>

#include "events.h"
#include "netem.h"
#include "station_run.h"

/* Each session's peak force in the server's steps, as it closes (the main thread's event). */
static pthread_mutex_t peaks_mu = PTHREAD_MUTEX_INITIALIZER;
static double peak_direct = -1, peak_relayed = -1;
static void on_closed(void *ctx, const palp_srv_session_summary *s) {
  (void)ctx;
  pthread_mutex_lock(&peaks_mu);
  if (s->info.trainee_name && !strcmp(s->info.trainee_name, "direct")) peak_direct = s->peak_force;
  if (s->info.trainee_name && !strcmp(s->info.trainee_name, "relayed")) peak_relayed = s->peak_force;
  pthread_mutex_unlock(&peaks_mu);
}

#define GRID 6000 /* 1 ms grid, 6 s */

static void config(palp_srv_config *cfg, unsigned domain) {
  char json[1024], err[512];
  snprintf(json, sizeof json,
           "{\"domain_id\": %u, \"tick_rate_hz\": 100, \"tick_threads\": 1, \"max_force\": 20, \"database\": \"\","
           " \"tick_priority\": 10, \"phantoms\": [{\"id\": 1, \"name\": \"haptic dome\", \"scene\": \"paper_step.json\", \"physics_rate_hz\": 250}]}",
           domain);
  if (palp_srv_config_parse(json, PALP_CONFIG_DIR, cfg, err, sizeof err) < 0) {
    fprintf(stderr, "test config: %s\n", err);
    exit(1);
  }
}

/* |F| on a 1 ms grid: the newest tick at or before each grid time. */
static int grid(const station_run *r, double *g) {
  size_t j = 0;
  int n = 0;
  for (int k = 0; k < GRID; k++) {
    const double t = k * 1e-3;
    while (j + 1 < r->hs.trace_len && r->trace[j + 1].t <= t) j++;
    if (r->hs.trace_len == 0 || r->trace[j].t > t + 2e-3) {
      g[k] = 0;
      continue;
    }
    const palp_vec3 f = r->trace[j].f;
    g[k] = sqrt(f.x * f.x + f.y * f.y + f.z * f.z);
    if (r->trace[j].t <= t) n = k + 1;
  }
  return n;
}

/* The 13 ticks around a run's largest rendered force: time, wake-up lateness, device point, force,
 * force asked before the limit, flags (PALP_CLI_FORCE_* / PALP_HAPTIC_*), finger on. */
static void print_peak(const char *name, const station_run *r) {
  size_t at = 0;
  double best = -1;
  for (size_t j = 0; j < r->hs.trace_len; j++) {
    const palp_vec3 f = r->trace[j].f;
    const double m = sqrt(f.x * f.x + f.y * f.y + f.z * f.z);
    if (m > best) best = m, at = j;
  }
  fprintf(stderr, "%s run's peak %.3f N at tick %zu of %zu:\n", name, best, at, r->hs.trace_len);
  for (size_t j = at > 6 ? at - 6 : 0; j < r->hs.trace_len && j <= at + 6; j++) {
    const palp_cli_haptic_sample *k = &r->trace[j];
    fprintf(stderr, "  t %.4f s late %.2f ms x (%.2f, %.2f, %.2f) mm |F| %.4f N asked %.4f N flags 0x%x on %d\n", k->t,
            k->late * 1e3, k->x.x * 1e3, k->x.y * 1e3, k->x.z * 1e3, sqrt(k->f.x * k->f.x + k->f.y * k->f.y + k->f.z * k->f.z),
            k->requested, k->flags, k->on);
  }
}

static double hf_rms(const double *g, int n) {
  double s = 0;
  int c = 0;
  for (int k = 20; k + 20 < n; k++) {
    double m = 0;
    for (int i = -20; i <= 20; i++) m += g[k + i];
    m /= 41;
    s += (g[k] - m) * (g[k] - m);
    c++;
  }
  return c ? sqrt(s / c) : 0;
}

/* The ripple while pressed: the same content above ~25 Hz, RMS over each 100 ms
 * window in which both forces stay above a quarter of the undelayed peak (the
 * press, hold and slide, not the touch), and the median over those windows. The
 * median, because a single transient of the phantom itself (a factor past its
 * margin on the paper's phantom at 250 Hz, docs/haptics.md: one 10-20 ms spike at
 * ~0.15 N in some runs, in both runs) would otherwise decide it. */
static int cmp(const void *a, const void *b);
static double hf_pressed_median(const double *gu, const double *gd, int n, double peak, int which, int *windows) {
  static double w[GRID / 100 + 1];
  const double *g = which ? gd : gu;
  int nw = 0;
  for (int w0 = 20; w0 + 100 + 20 < n; w0 += 100) {
    int pressed = 1;
    for (int k = w0 - 20; k < w0 + 100 + 20 && pressed; k++) pressed = gu[k] > 0.25 * peak && gd[k] > 0.25 * peak;
    if (!pressed) continue;
    double s = 0;
    for (int k = w0; k < w0 + 100; k++) {
      double m = 0;
      for (int i = -20; i <= 20; i++) m += g[k + i];
      m /= 41;
      s += (g[k] - m) * (g[k] - m);
    }
    w[nw++] = sqrt(s / 100);
  }
  *windows = nw;
  if (!nw) return INFINITY;
  qsort(w, (size_t)nw, sizeof w[0], cmp);
  return w[nw / 2];
}

static int cmp(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int main(void) {
  test_init();
  palp_cli_simdevice_def traj = palp_cli_simdevice_default_def(PALP_CLI_SIM_SLIDE);
  traj.polar_deg = 15;
  traj.azimuth_deg = 30;
  traj.depth = 0.012;
  traj.speed = 0.01;
  traj.hold = 0.5;
  traj.slide_speed = 0.02;
  traj.slide_distance = 0.02;
  const double dur = palp_cli_simdevice_duration(&traj, 0.04);
  /* The machine's floor: the haptic loop alone (no DDS), same priority. */
  palp_cli_haptic_stats fl;
  {
    palp_cli_simdevice_def cyc = palp_cli_simdevice_default_def(PALP_CLI_SIM_CYCLES);
    cyc.cycle_count = 10;
    palp_cli_input in;
    if (palp_cli_simdevice_input(&cyc, &in) < 0 || in.open(in.ctx, 0.04) < 0) return 1;
    palp_cli_haptic_def d = palp_cli_haptic_default_def();
    d.in = &in;
    d.rt_priority = 20;
    d.duration = 2.0;
    static palp_cli_haptic_loop bare;
    char e[128];
    if (palp_cli_haptic_start(&bare, &d, e, sizeof e) < 0) return 1;
    while (!palp_cli_haptic_done(&bare)) test_sleep(0.05);
    palp_cli_haptic_join(&bare, &fl);
    in.close(in.ctx);
  }
  const double floor_late = (double)fl.late_ticks / (double)(fl.ticks ? fl.ticks : 1);
  /* The floor is measured with the loop alone; the runs add a server, the relay and
   * DDS threads on the same two cores, which on this VM cost 1-10% of ticks (seen in
   * repeated fresh-clone runs, SCHED_FIFO granted: the VM itself stalls the loop). The
   * bounds therefore guard against a loop that waits on DDS or on the network (which
   * would lose most of its ticks at 20 ms of delay), not the 0.1% target,
   * which is printed beside them and reported, not asserted. */
  const double bound = fmax(0.25, 2 * floor_late + 0.01);
  /* A tick more than a period late is not made up, so missing ticks measure the
   * time without a fresh force: its own floor, from the same bare run. */
  const double floor_missing = fmax(0, 1 - (double)fl.ticks / 2000.0);
  const double bound_missing = fmax(0.25, 2 * floor_missing + 0.01);

  palp_srv_config cfg;
  config(&cfg, 112);
  test_server t;
  static const palp_srv_events events = {.session_closed = on_closed};
  const palp_srv_def def = {.cfg = cfg, .verbose = 1, .events = &events};
  test_server_start_def(&t, &def);

  station_run direct, relayed;
  /* SCHED_FIFO for the haptic thread (priority 20) and the server's tick threads
   * (10) when the kernel grants it, as a deployed station would run; the output
   * says whether it was granted. */
  station_run_once(112, 1, "direct", &traj, 0, 20, GRID + 500, 0, &direct);
  palp_netem_def nd = {.domain_a = 113, .domain_b = 112, .delay = 0.020, .jitter = 0.005, .loss = 0.05, .seed = 11};
  char err[256];
  palp_netem *n = palp_netem_start(&nd, err, sizeof err);
  if (!n) {
    fprintf(stderr, "%s\n", err);
    return 1;
  }
  station_run_once(113, 1, "relayed", &traj, 0, 20, GRID + 500, 0, &relayed);
  palp_netem_stats ns;
  palp_netem_get_stats(n, &ns);
  palp_netem_stop(n);
  test_server_stop(&t);

  static double gu[GRID], gd[GRID], diff[GRID];
  const int nu = grid(&direct, gu), ndl = grid(&relayed, gd);
  int ng = nu < ndl ? nu : ndl;
  if (ng > (int)(dur * 1000)) ng = (int)(dur * 1000);
  if (getenv("PALP_TEST_TRACE")) {
    FILE *f = fopen(getenv("PALP_TEST_TRACE"), "w");
    for (int k = 0; f && k < ng; k++) fprintf(f, "%.3f,%.5f,%.5f\n", k * 1e-3, gu[k], gd[k]);
    if (f) fclose(f);
  }
  double peak = 0, e2 = 0, emax = 0;
  for (int k = 0; k < ng; k++) {
    if (gu[k] > peak) peak = gu[k];
    diff[k] = fabs(gd[k] - gu[k]);
    e2 += diff[k] * diff[k];
    if (diff[k] > emax) emax = diff[k];
  }
  const double rms = ng ? sqrt(e2 / ng) : INFINITY;
  qsort(diff, (size_t)ng, sizeof *diff, cmp);
  const double p99 = ng ? diff[(int)((ng - 1) * 0.99)] : INFINITY;
  const double hfu = hf_rms(gu, ng), hfd = hf_rms(gd, ng);
  int nwin = 0;
  const double hpu = hf_pressed_median(gu, gd, ng, peak, 0, &nwin), hpd = hf_pressed_median(gu, gd, ng, peak, 1, &nwin);
  /* The delay floor: the undelayed force against itself, late by the measured latency. */
  const int lag = (int)lround(relayed.lat_p50_us * 1e-3);
  double f2 = 0;
  for (int k = 0; k < ng; k++) {
    const double e = gu[k] - (k >= lag ? gu[k - lag] : 0);
    f2 += e * e;
  }
  const double floor_rms = ng ? sqrt(f2 / ng) : 0;
  printf("relay: %.1f +- %.1f ms, %.0f%% loss: %llu samples forwarded, %llu dropped, %llu retransmitted late, one-way "
         "%.1f..%.1f ms\n", nd.delay * 1e3, nd.jitter * 1e3, nd.loss * 100, (unsigned long long)ns.forwarded,
         (unsigned long long)ns.dropped, (unsigned long long)ns.retransmitted, ns.delay_min * 1e3, ns.delay_max * 1e3);
  for (int i = 0; i < 2; i++) {
    const station_run *r = i ? &relayed : &direct;
    printf("%s: %llu ticks in %.2f s trajectory, %llu late > 0.5 ms (%.3f%%, worst %.2f ms), %llu models, "
           "contact->model p50 %.1f ms, force held (model late) %llu ticks, passivity controller %llu ticks %.3f mJ, "
           "SCHED_FIFO %s\n", i ? "relayed" : "direct ", (unsigned long long)r->hs.ticks, dur,
           (unsigned long long)r->hs.late_ticks, 100.0 * (double)r->hs.late_ticks / (double)(r->hs.ticks ? r->hs.ticks : 1),
           r->hs.late_max * 1e3, (unsigned long long)r->models_seen, r->lat_p50_us * 1e-3, (unsigned long long)r->hs.held_ticks, (unsigned long long)r->hs.passivity_ticks,
           r->hs.passivity_dissipated * 1e3, r->hs.rt_ok ? "granted" : "refused");
  }
  printf("force: peak (undelayed) %.3f N; relayed - undelayed on a 1 ms grid over %d ms: RMS %.4f N (%.2f%% of peak), "
         "p99 %.4f N (%.1f%%), max %.4f N (%.1f%%); above ~25 Hz: RMS %.4f N relayed vs %.4f N undelayed; delay floor "
         "(undelayed vs itself %d ms late) RMS %.4f N (%.2f%%); while pressed, above ~25 Hz (median of 100 ms windows): %.4f N relayed vs %.4f N\n",
         peak, ng, rms, 100 * rms / peak, p99, 100 * p99 / peak, emax, 100 * emax / peak, hfd, hfu, lag, floor_rms,
         100 * floor_rms / peak, hpd, hpu);
  double load = -1;
  getloadavg(&load, 1);
  printf("machine: 1-minute load average %.2f; floor (the haptic loop alone, no DDS, 2 s): %llu ticks (%.2f%% "
         "missing), %.3f%% late (worst %.2f ms), SCHED_FIFO %s; bounds asserted: %.2f%% late, %.2f%% missing (the "
         "issue's target: 0.1%%)\n", load, (unsigned long long)fl.ticks, 100 * floor_missing, 100 * floor_late,
         fl.late_max * 1e3, fl.rt_ok ? "granted" : "refused", 100 * bound, 100 * bound_missing);
  for (int i = 0; i < 2; i++) {
    const station_run *r = i ? &relayed : &direct;
    const char *name = i ? "relayed" : "undelayed";
    CHECK(r->hs.ended && !r->hs.failed, "%s run: trajectory completed", name);
    const double late = (double)r->hs.late_ticks / (double)(r->hs.ticks ? r->hs.ticks : 1);
    /* A tick more than a period late is not made up: ticks missing = time lost. */
    CHECK((double)r->hs.ticks >= (1 - bound_missing) * dur * 1000, "%s run: the loop held 1 kHz: %llu ticks in %.2f s "
          "(at most %.2f%% missing)", name, (unsigned long long)r->hs.ticks, dur, 100 * bound_missing);
    CHECK(late <= bound, "%s run: %.3f%% of ticks late by > 0.5 ms (bound %.2f%%)", name, 100 * late, 100 * bound);
  }
  /* The relay did what it was asked: one-way delays within 20 +- 5 ms (a reliable
   * sample "lost" comes one round trip, 40 ms, later), and about 5% of the samples
   * lost (best-effort dropped + reliable retransmitted + best-effort disposes and unregisters a loss draw
   * hit, which cross anyway: each draw that hits counted once; binomial 3 sigma). */
  const double n_all = (double)(ns.forwarded + ns.dropped);
  const double lost = n_all > 0 ? (double)(ns.dropped + ns.retransmitted + ns.ends_kept) / n_all : 0;
  CHECK(ns.delay_min >= 0.015 - 1e-6 && ns.delay_max <= 0.025 + 0.040 + 1e-3 &&
            (ns.retransmitted > 0 || ns.delay_max <= 0.025 + 1e-3),
        "relay delays %.2f..%.2f ms (20 +- 5 ms, + 40 ms for a retransmission)", ns.delay_min * 1e3, ns.delay_max * 1e3);
  CHECK(fabs(lost - nd.loss) <= 3 * sqrt(nd.loss * (1 - nd.loss) / (n_all > 0 ? n_all : 1)),
        "relay lost %.2f%% of %.0f samples (5%% +- 3 sigma)", 100 * lost, n_all);
  CHECK(relayed.models_seen > 0.5 * 250 * (dur - traj.start - traj.tail),
        "the relayed station received %llu local models (>= half of the physics steps: 5%% are lost, and the "
        "server's ticks overrun on a loaded machine)", (unsigned long long)relayed.models_seen);
  CHECK(relayed.ignored == 0 && direct.ignored == 0 && !relayed.closed,
        "behind the relay the station's server is the relay's participant: %llu samples ignored (%llu direct), "
        "session %s", (unsigned long long)relayed.ignored, (unsigned long long)direct.ignored,
        relayed.closed ? relayed.reason : "open");
  CHECK(peak > 0.3, "the undelayed press reaches %.3f N", peak);
  CHECK(rms <= 0.10 * peak, "relayed force within 10%% of the undelayed run's peak (RMS %.4f N <= %.4f N)", rms,
        0.10 * peak);
  CHECK(hfd <= 2 * hfu + 0.01 * peak, "no oscillation: content above ~25 Hz %.4f N <= 2 x %.4f + 1%% of peak", hfd,
        hfu);
  /* While pressed: a jittery network brought the station's device to the server in
   * bunches, which the phantom's stiffness turned into a ripple: 0.0055-0.0058 N
   * (5-8x the undelayed run's) before the server played the samples out at a steady
   * delay (server/playout.h); 0.0007-0.0010 N since, as the undelayed run's
   * 0.0007-0.0014 N (16 runs). */
  CHECK(nwin >= 15 && hpd <= 2 * hpu + 0.001 * peak, "no ripple while pressed (median of %d windows of 100 ms): "
        "content above ~25 Hz %.4f N relayed <= 2 x %.4f N undelayed + 0.1%% of peak", nwin, hpd, hpu);
  double pd = -1, pr = -1;
  for (int i = 0; i < 100 && (pd < 0 || pr < 0); i++) { /* each session closes as its station leaves */
    pthread_mutex_lock(&peaks_mu);
    pd = peak_direct, pr = peak_relayed;
    pthread_mutex_unlock(&peaks_mu);
    if (pd < 0 || pr < 0) test_sleep(0.05);
  }
  CHECK(pd >= 0 && pr >= 0 && pd <= 2 * peak && pr <= 2 * peak, "the server's own steps peaked at %.3f N "
        "(undelayed) and %.3f N (relayed), within twice the undelayed station's rendered %.3f N", pd, pr, peak);
  /* On a failure, the ticks around each run's peak force, as rendered: what the next look at a failure
   * starts from (session 84's one failure, a 4.19 N peak in a 0.4 N press while the server's own steps
   * never passed 0.36 N, left only the figures above; not reproduced in ~90 loaded runs since). */
  for (int i = 0; palp_test_failures && i < 2; i++)
    print_peak(i ? "relayed" : "undelayed", i ? &relayed : &direct);
  free(direct.trace);
  free(relayed.trace);
  fprintf(stderr, palp_test_failures ? "%d check(s) FAILED\n" : "all checks passed\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
