/* main.c - palp-netem: relays every palp topic between two DDS domains on loopback
 * with delay, jitter and loss (netem.h; docs/station.md). */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "netem.h"
#include "palp_app.h"
#include "palp.h"
#include "palp_dds.h"

static atomic_int g_stop; /* atomic: a signal may land on any thread (client/main.c) */
static void on_signal(int sig) {
  (void)sig;
  g_stop = 1;
}

static int num(const char *opt, const char *v, double lo, double hi, double *out) {
  char *end = NULL;
  errno = 0;
  const double x = v ? strtod(v, &end) : 0;
  if (!v || errno || end == v || *end || !(x >= lo && x <= hi)) {
    fprintf(stderr, "palp-netem: %s: expected a number in [%g, %g], got \"%s\"\n", opt, lo, hi, v ? v : "");
    return -1;
  }
  *out = x;
  return 0;
}

/* num() for a whole number (a domain, a seed): 201.9 was taken as 201 without a word. */
static int whole(const char *opt, const char *v, double lo, double hi, double *out) {
  if (num(opt, v, lo, hi, out) < 0) return -1;
  if (*out != floor(*out)) {
    fprintf(stderr, "palp-netem: %s: expected a whole number from %.0f to %.0f, got \"%s\"\n", opt, lo, hi, v);
    return -1;
  }
  return 0;
}

/* The default jitter [s], when --jitter-ms is not given: 5 ms, or the delay when that is smaller (the
 * jitter may not exceed the delay; a 2 ms or 0 ms link asked for without a jitter was refused with a
 * message that named neither the 5 ms default nor which constraint failed). */
#define NETEM_JITTER_DEFAULT 0.005

#define NETEM_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_LOG | PALP_APP_OPT_VERBOSE | PALP_APP_OPT_DDS)

int main(int argc, char **argv) {
  palp_app_opts ao;
  palp_app_opts_init(&ao, "palp-netem");
  palp_netem_def d = {.domain_a = 0, .domain_b = 1, .delay = 0.020, .jitter = -1, .loss = 0.05, .seed = 1};
  double duration = 0, x;
  int delay_given = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      printf("usage: palp-netem --stations DOMAIN --server DOMAIN [--delay-ms 20] [--jitter-ms 5] [--loss 0.05]\n"
             "                  [--seed N] [--duration S] [--queue-mb 256]\n"
             "Relays every palp topic between the stations' and the server's DDS domains on loopback,\n"
             "each sample delayed by delay +- jitter (uniform, kept in order per instance; the jitter at most\n"
             "the delay, by default 5 ms or the delay if smaller), a fraction `loss` lost (best-effort topics:\n"
             "the sample dropped, an instance's end still crossing; reliable ones: delivered a round trip later).\n"
             "At most --queue-mb MB of samples in flight; past it samples are dropped and counted.\n"
             "Loopback only: a DDS config that may reach a network is refused (exit 2).\n");
      palp_app_common_usage(stdout, NETEM_OPTS);
      return 0;
    }
    int rc = 0, common = palp_app_common_opt(&ao, NETEM_OPTS, argc, argv, &i);
    if (common < 0) return 2;
    if (common) continue;
    if (!strcmp(a, "--stations")) rc = whole(a, v, 0, 232, &x), d.domain_a = (uint32_t)x;
    else if (!strcmp(a, "--server")) rc = whole(a, v, 0, 232, &x), d.domain_b = (uint32_t)x;
    else if (!strcmp(a, "--delay-ms")) rc = num(a, v, 0, 10000, &x), d.delay = x * 1e-3, delay_given = 1;
    else if (!strcmp(a, "--jitter-ms")) rc = num(a, v, 0, 10000, &x), d.jitter = x * 1e-3;
    else if (!strcmp(a, "--loss")) rc = num(a, v, 0, 0.5, &x), d.loss = x;
    else if (!strcmp(a, "--seed")) rc = whole(a, v, 0, 1e15, &x), d.seed = (uint64_t)x;
    else if (!strcmp(a, "--queue-mb")) rc = num(a, v, 1, 65536, &x), d.queue_bytes = (size_t)(x * 1048576.0);
    else if (!strcmp(a, "--duration")) rc = num(a, v, 0, 1e6, &duration);
    else {
      fprintf(stderr, "palp-netem: unknown option %s\n", a);
      return 2;
    }
    if (rc) return 2;
    i++;
  }
  if (ao.version) {
    palp_app_print_version(stdout, "palp-netem");
    return 0;
  }
  /* Each constraint of palp_netem_start said with the values used, before any DDS entity. */
  const int jitter_given = d.jitter >= 0;
  if (!jitter_given) d.jitter = fmin(NETEM_JITTER_DEFAULT, d.delay);
  if (d.domain_a == d.domain_b) {
    fprintf(stderr, "palp-netem: --stations %u and --server %u: the two domains must differ (the relay joins them)\n",
            d.domain_a, d.domain_b);
    return 2;
  }
  if (d.jitter > d.delay) {
    fprintf(stderr, "palp-netem: --jitter-ms %g exceeds --delay-ms %g%s: give --jitter-ms <= %g (the delay is drawn "
            "from delay +- jitter and may not go below 0)\n", d.jitter * 1e3, d.delay * 1e3,
            delay_given ? "" : " (the default)", d.delay * 1e3);
    return 2;
  }
  palp_log log;
  if (palp_log_init(&log, "palp-netem", ao.log_level, ao.log_file) < 0) {
    /* 2 and this wording, as every program's (docs/deploy.md): a refused setting, not a failure */
    fprintf(stderr, "palp-netem: --log-file %s: cannot open it: %s\n", ao.log_file, strerror(errno));
    return 2;
  }
  char derr[256], chosen[1100];
  if (palp_app_use_dds_config(ao.dds_config, NULL, chosen, sizeof chosen, derr, sizeof derr) < 0) {
    palp_log_error(&log, "DDS config: %s", derr);
    palp_log_close(&log);
    return 1;
  }
  /* The relay has no DDS Security and republishes every server topic and station request: on a
   * config that may reach a network it would bridge a loopback-only, unsecured palp-server onto
   * that network, what palp-server's own refusal (server/main.c) is there to prevent. Decided
   * before any participant exists, as the server decides. */
  char scope[200];
  if (!palp_app_dds_loopback_only(scope, sizeof scope)) {
    palp_log_error(&log, "refusing: the DDS config %s may reach a network (%s): the relay is for loopback tests", chosen,
                   scope);
    palp_log_close(&log);
    return 2;
  }
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
  char err[256];
  palp_netem *n = palp_netem_start(&d, err, sizeof err);
  if (!n) {
    palp_log_error(&log, "%s", err);
    palp_log_close(&log);
    return 1;
  }
  palp_log_info(&log, "%s: stations on domain %u <-> server on domain %u: %.1f +- %.1f ms, %.1f%% loss, seed %llu, "
                "DDS config %s", palp_app_version(),
                d.domain_a, d.domain_b, d.delay * 1e3, d.jitter * 1e3, d.loss * 100, (unsigned long long)d.seed, chosen);
  const int64_t end = duration > 0 ? palp_dds_now_ns() + (int64_t)(duration * 1e9) : INT64_MAX;
  while (!g_stop && palp_dds_now_ns() < end) {
    struct timespec ts = {0, 100000000};
    nanosleep(&ts, NULL);
  }
  palp_netem_stats st;
  palp_netem_get_stats(n, &st);
  palp_netem_stop(n);
  printf("palp-netem: %llu samples forwarded, %llu dropped (%llu of them past the queue's %.0f MB), %llu retransmitted "
         "late, %llu disposals (%llu best-effort ends a loss draw hit, sent anyway); one-way delay %.1f..%.1f ms; %llu "
         "session slots reclaimed\n",
         (unsigned long long)st.forwarded, (unsigned long long)st.dropped, (unsigned long long)st.over_budget,
         (double)(d.queue_bytes ? d.queue_bytes : PALP_NETEM_QUEUE_BYTES) / 1048576.0, (unsigned long long)st.retransmitted,
         (unsigned long long)st.disposals, (unsigned long long)st.ends_kept, st.delay_min * 1e3, st.delay_max * 1e3,
         (unsigned long long)st.sessions_reclaimed);
  palp_log_close(&log);
  return 0;
}
