/* palp-web: the classroom seen live in a browser. Joins the DDS domain as a viewer, serves the
 * trainee page and the instructor's dashboard, and streams deformation, forces, session states and
 * server status to them over WebSocket (docs/web.md).
 *
 *   palp-web [--domain N] [--listen ADDR] [--port P] [--token T | --token-file F]
 *            [--tls-cert F --tls-key F] [options]
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "access.h"
#include "hub.h"
#include "palp.h"
#include "palp_app.h"
#include "palp_input_file.h"
#include "palp_dds.h"
#include "palp_dds_refusals.h"
#include "serve.h"
#include "tls.h"

static atomic_int g_stop; /* atomic: a signal may land on any thread (client/main.c) */
static atomic_int g_hup;  /* SIGHUP: re-open --log-file (log rotation) and re-read the token files, done on the
                          * hub thread */
static void on_signal(int sig) {
  if (sig == SIGHUP) g_hup = 1;
  else g_stop = 1;
}

#define WEB_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_LOG | PALP_APP_OPT_VERBOSE | PALP_APP_OPT_DDS)

static void usage(FILE *f) {
  fprintf(f,
          "usage: palp-web [options]\n"
          "  --domain N          DDS domain of the classroom server (default 0)\n"
          "  --listen ADDR       address to serve on (default 127.0.0.1; anything but loopback needs a token\n"
          "                      and TLS, or --insecure-http)\n"
          "  --port P            TCP port (default 8090; 0 = any free port, printed)\n"
          "  --token T           access token (%d-%d characters of A-Z a-z 0-9 . _ ~ -); pages need ?token=T\n"
          "  --token-file F      read the token from F (keeps it out of the process list; SIGHUP re-reads it)\n"
          "  --token-lifetime-h H   every token opens pages for H hours after it was issued: when its file\n"
          "                      (--token-file, --trainee-tokens) was last written, or at start for --token\n"
          "                      (default %g: a class day; 0 = never expire)\n"
          "  --tls-cert F --tls-key F   serve HTTPS and WSS with this PEM certificate and key (made from the\n"
          "                      classroom CA by scripts/make-classroom-pki.sh DIR web HOST)\n"
          "  --insecure-http     serve plain HTTP beyond loopback: the token crosses the network in clear\n"
          "  --trainee-tokens F  trainees' own tokens, \"NAME TOKEN\" per line: a page given one sees only\n"
          "                      that trainee's sessions (no dashboard); needs --token (the instructors')\n"
          "                      New tokens without a restart: write the files, then SIGHUP: both are re-read\n"
          "                      with the checks of start (all or nothing: one bad file keeps the old tokens);\n"
          "                      pages of a removed or changed token are closed, the others stay open\n"
          "  --scale-mm MM       largest colour scale of the pages: 0..MM of displacement (default 30)\n"
          "  --scale-min-mm MM   smallest (default 0.5): a page's scale grows from it, in steps of 1-2-5,\n"
          "                      with its session's deepest displacement; equal to --scale-mm: fixed\n"
          "  --bands L,M         force gauge bands [N]: light < L <= medium <= M < deep (default 1,3)\n"
          "  --dashboard-hz HZ   frames per second and session to a dashboard (default 10)\n"
          "  --max-clients N     WebSocket connections at once (default 32)\n"
          "  --no-join           never join a session: show only what the server already streams\n"
          "  --no-feedback       never read feedback (a position-driven finger's force then shows 0 N)\n"
          "  --no-answers        never read or show where exercise sessions' lumps are (by default the\n"
          "                      dashboard shows them, and which the marks found: for a dashboard the\n"
          "                      trainees can see, e.g. projected in the room)\n"
          "  --www DIR           the pages (default <data>/www: share/palp/www installed, web/www in a build)\n"
          "  --three DIR         three.js from libjs-three (default %s)\n"
          "  --duration S        stop after S seconds (tests, benchmarks)\n"
          "  --stats             print the bridge's counters every 5 s (SIGHUP re-opens --log-file and\n"
          "                      re-reads the token files)\n"
          "  --pki DIR --identity instructor/NAME   DDS Security in a secured classroom (or PALP_PKI,\n"
          "                      PALP_IDENTITY; scripts/make-classroom-pki.sh): the bridge is that instructor\n",
          PALP_WEB_TOKEN_MIN, PALP_WEB_TOKEN_MAX, PALP_WEB_TOKEN_LIFETIME_DEFAULT_S / 3600.0, PALP_WEB_THREE_DIR);
  palp_app_common_usage(f, WEB_OPTS);
}

static int number(const char *opt, const char *v, double lo, double hi, double *out) {
  char *end = NULL;
  errno = 0;
  const double x = v ? strtod(v, &end) : 0;
  if (!v || errno || end == v || *end || !(x >= lo && x <= hi)) {
    fprintf(stderr, "palp-web: %s: expected a number in [%g, %g], got \"%s\"\n", opt, lo, hi, v ? v : "");
    return -1;
  }
  *out = x;
  return 0;
}

/* The token files' checks write their reason into e (the same words at start, on stderr, and at SIGHUP,
 * in the log) and return -1; 0 when the file passes. */
typedef struct why {
  char text[512];
} why;
static int say_why(why *e, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int say_why(why *e, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(e->text, sizeof e->text, fmt, ap);
  va_end(ap);
  return -1;
}

/* A secret (token, key) every user of the machine can read is no secret on a shared lab machine. */
static int secret_private(const char *what, const char *path, why *e) {
  struct stat st;
  if (stat(path, &st) != 0 || !(st.st_mode & (S_IROTH | S_IWOTH))) return 0;
  return say_why(e, "%s %s is readable by every user of this machine (mode %04o): chmod o-rwx it", what, path,
                 (unsigned)(st.st_mode & 07777));
}

/* The instructors' token: the first line of --token-file, checked (out: PALP_WEB_TOKEN_MAX + 1 bytes). */
static int read_token_file(const char *path, char *out, why *e) {
  if (secret_private("--token-file", path, e)) return -1;
  FILE *f = fopen(path, "r");
  if (!f) return say_why(e, "--token-file: cannot open %s: %s", path, strerror(errno));
  char line[PALP_WEB_TOKEN_MAX + 2]; /* one longer than a token may be: a longer one is refused, not cut */
  if (!fgets(line, (int)sizeof line, f)) line[0] = 0;
  fclose(f);
  line[strcspn(line, "\r\n")] = 0;
  if (palp_web_token_check(line) != 0)
    return say_why(e, "--token-file %s: the token must be %d-%d characters of A-Z a-z 0-9 . _ ~ -", path,
                   PALP_WEB_TOKEN_MIN, PALP_WEB_TOKEN_MAX);
  memcpy(out, line, strlen(line) + 1);
  return 0;
}

/* The whole of a small text file (<= 64 kB) into *out (malloc'ed, NUL-terminated); 0 or -1 said. A
 * directory, a FIFO or a file with a NUL byte is refused (palp_input_file_read): until session 81 a
 * directory read as an empty list and a NUL ended it, each trainee after it locked out without a word. */
static int read_small_file(const char *what, const char *path, char **out, why *e) {
  char reason[200];
  if (palp_input_file_read(path, 65536, out, NULL, reason, sizeof reason) != 0)
    return say_why(e, "%s %s: %s", what, path, reason);
  return 0;
}

/* The wall clock [s, Unix time]: tokens age from their files' last write, a wall-clock time. Read at start
 * only: serve.c fixes each token's expiry then and counts it down on the steady clock. */
static double wall_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* When the tokens in a file were issued [s, Unix time]: its last write, or now (start) if that is later
 * (a clock set back, a file from the future: never a lifetime beyond the one configured). */
static double issued_at(const char *path, double start) {
  struct stat st;
  if (!path || stat(path, &st) != 0) return start;
  const double m = (double)st.st_mtim.tv_sec + 1e-9 * (double)st.st_mtim.tv_nsec;
  return m < start ? m : start;
}

/* The trainees' tokens of --trainee-tokens, checked against the instructors' token, each issued at the
 * file's last write (or now, if later): their count, or -1 with the reason in e. */
static int read_trainee_tokens(const char *path, const char *instructor, double now, palp_web_trainee_token *out,
                               why *e) {
  char *text = NULL, terr[256];
  if (secret_private("--trainee-tokens", path, e) || read_small_file("--trainee-tokens", path, &text, e) != 0)
    return -1;
  const int n = palp_web_trainee_tokens_parse(text, instructor, out, PALP_WEB_TRAINEES_MAX, terr, sizeof terr);
  free(text);
  if (n < 0) return say_why(e, "--trainee-tokens %s: %s", path, terr);
  const double issued = issued_at(path, now);
  for (int k = 0; k < n; k++) out[k].issued_s = issued;
  return n;
}

/* When the tokens expire, and a warning for one already expired (a stale file): at start (printed), and
 * after a SIGHUP re-read them (logged). */
static void say_token_lifetime(palp_log *log, double token_issued_s, int trainee_count, double trainees_issued_s,
                               double lifetime_s, const char *token_file, const char *trainee_file, double now,
                               int at_start) {
  if (lifetime_s == 0) {
    if (at_start) printf("palp-web: tokens never expire (--token-lifetime-h 0)\n");
    return;
  }
  char at[32];
  for (int k = 0; k < 2; k++) {
    if (k && !trainee_count) break;
    const double issued = k ? trainees_issued_s : token_issued_s, end = issued + lifetime_s;
    const char *whose = k ? "the trainees' tokens" : "the instructors' token";
    palp_web_utc_text(end, at, sizeof at);
    if (palp_web_token_expired(issued, lifetime_s, now))
      palp_log_warn(log, "%s%s expired at %s, %.1f h ago (%s was last written %.1f h ago, --token-lifetime-h %g): "
                         "their pages are told to ask for a new one; write new tokens and send SIGHUP (or restart "
                         "palp-web)",
                    at_start ? "" : "SIGHUP: ", whose, at, (now - end) / 3600.0,
                    k ? trainee_file : token_file ? token_file : "--token", (now - issued) / 3600.0, lifetime_s / 3600.0);
    else if (at_start)
      printf("palp-web: %s expire%s at %s (%.1f h from now, --token-lifetime-h %g)\n", whose, k ? "" : "s", at,
             (end - now) / 3600.0, lifetime_s / 3600.0);
    else
      palp_log_info(log, "SIGHUP: %s expire%s at %s (%.1f h from now, --token-lifetime-h %g)", whose, k ? "" : "s", at,
                    (end - now) / 3600.0, lifetime_s / 3600.0);
  }
}

static double mono_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* --duration and --stats without a thread of their own: a small watcher on the hub's wake-ups. */
typedef struct watch {
  palp_web_server *srv;
  palp_web_hub *hub;
  double end, next_stats;
  int stats;
  palp_log *log;
  /* what SIGHUP re-reads (reload_tokens) */
  const char *token_arg, *token_file, *trainee_file; /* --token (fixed), --token-file, --trainee-tokens */
  double start, token_lifetime_s;
  int said_fixed; /* "--token cannot change" logged (once) */
} watch;

static void print_stats(palp_log *log, palp_web_hub *hub, palp_web_server *srv) {
  palp_web_hub_stats h;
  palp_web_serve_stats w;
  palp_web_hub_stats_get(hub, &h);
  palp_web_serve_stats_get(srv, &w);
  palp_log_info(log,
          "%d sessions, %d pages; DDS taken: %llu deformations, %llu contacts, %llu feedbacks, %llu states, "
          "%llu dropped, %llu of no known session, %llu of new keys past the readers' bound, %llu from outside their "
          "session's partition, %llu of a session's server topics not from its server; joins %llu, leaves %llu; sent %llu messages (%.1f MB); "
          "http %llu ok, %llu denied, %llu missing; ws %llu opened, %llu closed, %llu denied",
          h.sessions_open, h.clients, (unsigned long long)h.deformations, (unsigned long long)h.contacts,
          (unsigned long long)h.feedbacks, (unsigned long long)h.states, (unsigned long long)h.dropped,
          (unsigned long long)h.no_session, (unsigned long long)h.rejected, (unsigned long long)h.foreign,
          (unsigned long long)h.not_server, (unsigned long long)h.joins, (unsigned long long)h.leaves, (unsigned long long)w.msgs, (double)w.bytes / 1e6,
          (unsigned long long)w.http_ok, (unsigned long long)w.http_denied, (unsigned long long)w.http_missing,
          (unsigned long long)w.ws_opened,
          (unsigned long long)w.ws_closed, (unsigned long long)w.ws_denied);
  /* What letting go of the closed sessions cost: the DDS thread, and the reaper beside it (whose delete of a
   * writer waits for the readers' acknowledgements; idl/palp_dds_reaper.h). */
  if (h.rejoins) /* rejoin_if_dropped: the server had dropped this bridge from a session it follows, or may have */
    palp_log_info(log, "JOINs sent again to sessions whose server had dropped this bridge or may have (palp-web not run "
                       "for a while: %llu stall(s) of 0.3 s or more): %llu", (unsigned long long)h.stalls,
                  (unsigned long long)h.rejoins);
  if (h.leaves || h.reaped)
    palp_log_info(log, "closed sessions let go of in at most %.3f s each on the DDS thread; %llu of their writers and "
                       "readers deleted beside it, the longest in %.3f s, %d still to delete",
                  h.free_longest_s, (unsigned long long)h.reaped, h.reap_longest_s, h.reap_pending);
  if (w.http_expired || w.ws_expired) /* each token's first refusal is named in the log (serve.c) */
    palp_log_warn(log, "pages told their token expired: %llu HTTP requests, %llu WebSockets (refused, or closed at "
                       "the expiry)",
                  (unsigned long long)w.http_expired, (unsigned long long)w.ws_expired);
  if (w.ws_withdrawn) /* SIGHUP's line said each re-read's */
    palp_log_info(log, "pages closed because a SIGHUP withdrew their token: %llu", (unsigned long long)w.ws_withdrawn);
  if (h.exercises || h.findings_written || h.findings_refused || h.local_models)
    palp_log_info(log, "exercises %llu (sessions' %llu, scores %llu), trainees' scores %llu, finding statuses %llu, "
                       "findings read %llu (%llu unanswered); findings written %llu, refused %llu; local models %llu "
                       "(late %llu, lost %llu), finger samples %llu",
                  (unsigned long long)h.exercises, (unsigned long long)h.session_exercises, (unsigned long long)h.scores,
                  (unsigned long long)h.told_scores,
                  (unsigned long long)h.finding_statuses, (unsigned long long)h.findings_read,
                  (unsigned long long)h.findings_unanswered,
                  (unsigned long long)h.findings_written, (unsigned long long)h.findings_refused,
                  (unsigned long long)h.local_models, (unsigned long long)h.late_haptic,
                  (unsigned long long)h.lost_haptic, (unsigned long long)h.finger_samples);
  if (h.catalogue_refused) /* each publisher's first named in the log (hub.c, refuse_phantom) */
    palp_log_warn(log, "%llu catalogue entries refused (a mesh beyond %d vertices, no palp-server's, or malformed)",
                  (unsigned long long)h.catalogue_refused, PALP_WEB_PHANTOM_MAX_VERTICES);
  if (h.finding_renewals) /* a flood (docs/robustness.md): said apart, as a warning */
    palp_log_warn(log, "%llu disposes of finding keys of sessions this bridge does not follow (a flood: each kept "
                       "while its writer lives); the findings reader was made anew %llu times to drop them",
                  (unsigned long long)h.finding_strays, (unsigned long long)h.finding_renewals);
  if (h.stream_renewals || h.stream_renewals_failed) /* a flood of disposes of stream keys (hub.c, renew_stream) */
    palp_log_warn(log, "%llu disposes of stream keys this bridge's gate would not pass (a flood: each kept while its "
                       "writer lives), %llu stream samples refused at the readers' bound; stream readers made anew %llu "
                       "times to drop them (%llu failed, tried again)",
                  (unsigned long long)h.stream_strays, (unsigned long long)h.rejected,
                  (unsigned long long)h.stream_renewals, (unsigned long long)h.stream_renewals_failed);
}

/* SIGHUP, on the hub's thread: the token files read again with every check of start, all or nothing, and the
 * new tokens handed to the web server, which puts them in place between two of its passes and says what
 * changed (palp_web_serve_tokens_replace): tokens rotated for the next class, or one that leaked, without the
 * restart that dropped every open page. */
static void reload_tokens(watch *w) {
  if (w->token_arg && !w->said_fixed) {
    palp_log_info(w->log, "SIGHUP: --token was given on the command line: the instructors' token cannot change "
                          "while palp-web runs (--token-file F can: SIGHUP re-reads it)%s",
                  w->trainee_file ? "; --trainee-tokens is re-read" : "");
    w->said_fixed = 1;
  }
  if (!w->token_file && !w->trainee_file) return;
  palp_web_tokens *t = calloc(1, sizeof *t);
  if (!t) {
    palp_log_error(w->log, "SIGHUP: out of memory: tokens not re-read, the old ones still served");
    return;
  }
  const double now = wall_s();
  why e = {{0}};
  int ok = 1;
  if (w->token_file) {
    ok = read_token_file(w->token_file, t->token, &e) == 0;
    t->token_issued_s = issued_at(w->token_file, now);
  } else {
    snprintf(t->token, sizeof t->token, "%s", w->token_arg);
    t->token_issued_s = w->start; /* as at start: --token was issued then */
  }
  if (ok && w->trainee_file) {
    t->trainee_count = read_trainee_tokens(w->trainee_file, t->token, now, t->trainees, &e);
    ok = t->trainee_count >= 0;
  }
  if (!ok) {
    palp_log_error(w->log, "SIGHUP: tokens not re-read, the old ones still served: %s", e.text);
  } else {
    /* said before the web server's line of what changed (it logs that when it has put them in place) */
    say_token_lifetime(w->log, t->token_issued_s, t->trainee_count, t->trainee_count ? t->trainees[0].issued_s : 0,
                       w->token_lifetime_s, w->token_file, w->trainee_file, now, 0);
    if (palp_web_serve_tokens_replace(w->srv, t) != 0)
      palp_log_error(w->log, "SIGHUP: out of memory: tokens not re-read, the old ones still served");
  }
  free(t);
}

static void on_wake(void *ctx) {
  watch *w = ctx;
  const double now = mono_s();
  if (w->end > 0 && now >= w->end) g_stop = 1;
  if (atomic_exchange(&g_hup, 0)) {
    if (palp_log_reopen(w->log) < 0) palp_log_error(w->log, "SIGHUP: cannot re-open %s", w->log->path);
    else palp_log_info(w->log, "SIGHUP: log re-opened; serving goes on");
    reload_tokens(w);
  }
  palp_web_serve_wake(w->srv);
  if (w->stats && now >= w->next_stats) {
    w->next_stats = now + 5;
    print_stats(w->log, w->hub, w->srv);
  }
}

int main(int argc, char **argv) {
  palp_web_hub_def hd = palp_web_hub_default_def();
  int scale_min_given = 0;
  palp_web_serve_def sd = {.listen = "127.0.0.1", .port = 8090, .www_dir = NULL,
                           .three_dir = PALP_WEB_THREE_DIR, .max_clients = 32};
  const char *token = NULL, *token_file = NULL, *pki = NULL, *identity = NULL, *trainee_file = NULL;
  int insecure_http = 0;
  palp_app_opts ao;
  palp_app_opts_init(&ao, "palp-web");
  double duration = 0, x = 0;
  double token_lifetime_h = PALP_WEB_TOKEN_LIFETIME_DEFAULT_S / 3600.0;
  int stats = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
      usage(stdout);
      return 0;
    }
    const int common = palp_app_common_opt(&ao, WEB_OPTS, argc, argv, &i);
    if (common < 0) return 2;
    if (common) continue;
    if (!strcmp(a, "--no-join")) { hd.join = 0; continue; }
    if (!strcmp(a, "--no-feedback")) { hd.read_feedback = 0; continue; }
    if (!strcmp(a, "--no-answers")) { hd.answers = 0; continue; }
    if (!strcmp(a, "--stats")) { stats = 1; continue; }
    if (!strcmp(a, "--insecure-http")) { insecure_http = 1; continue; }
    if (!v) {
      fprintf(stderr, "palp-web: %s: missing value (or unknown option)\n", a);
      return 2;
    }
    i++;
    if (!strcmp(a, "--domain")) {
      if (number(a, v, 0, 232, &x) || x != floor(x)) return 2;
      hd.domain = (uint32_t)x;
    } else if (!strcmp(a, "--listen")) sd.listen = v;
    else if (!strcmp(a, "--port")) {
      if (number(a, v, 0, 65535, &x) || x != floor(x)) return 2;
      sd.port = (int)x;
    } else if (!strcmp(a, "--token")) token = v;
    else if (!strcmp(a, "--token-file")) token_file = v;
    else if (!strcmp(a, "--token-lifetime-h")) {
      if (number(a, v, 0, 8760, &token_lifetime_h)) return 2;
    }
    else if (!strcmp(a, "--trainee-tokens")) trainee_file = v;
    else if (!strcmp(a, "--tls-cert")) sd.tls_cert = v;
    else if (!strcmp(a, "--tls-key")) sd.tls_key = v;
    else if (!strcmp(a, "--pki")) pki = v;
    else if (!strcmp(a, "--identity")) identity = v;
    else if (!strcmp(a, "--www")) sd.www_dir = v;
    else if (!strcmp(a, "--three")) sd.three_dir = v;
    else if (!strcmp(a, "--scale-mm")) {
      if (number(a, v, 0.1, 1000, &hd.scale_mm)) return 2;
    } else if (!strcmp(a, "--scale-min-mm")) {
      if (number(a, v, 0.01, 1000, &hd.scale_min_mm)) return 2;
      scale_min_given = 1;
    } else if (!strcmp(a, "--dashboard-hz")) {
      if (number(a, v, 0.5, 60, &hd.dashboard_hz)) return 2;
    } else if (!strcmp(a, "--max-clients")) {
      if (number(a, v, 1, 256, &x) || x != floor(x)) return 2;
      sd.max_clients = (int)x;
    } else if (!strcmp(a, "--duration")) {
      if (number(a, v, 0.1, 1e7, &duration)) return 2;
    } else if (!strcmp(a, "--bands")) {
      char *end = NULL;
      errno = 0;
      hd.bands.light_max = strtod(v, &end);
      if (errno || end == v || *end != ',') {
        fprintf(stderr, "palp-web: --bands: expected L,M in newtons, got \"%s\"\n", v);
        return 2;
      }
      const char *m = end + 1;
      hd.bands.medium_max = strtod(m, &end);
      if (errno || end == m || *end || palp_web_bands_check(&hd.bands) != 0) {
        fprintf(stderr, "palp-web: --bands: expected %g < L < M (newtons), got \"%s\"\n", hd.bands.touch_min, v);
        return 2;
      }
    } else {
      fprintf(stderr, "palp-web: unknown option %s\n", a);
      usage(stderr);
      return 2;
    }
  }
  if (ao.version) {
    palp_app_print_version(stdout, "palp-web");
    return 0;
  }
  /* DDS Security before anything touches the network: a bad identity is refused up front. */
  {
    char serr[256];
    const int src = pki || identity ? palp_dds_security_init(&hd.sec, pki, identity, serr, sizeof serr)
                                    : palp_dds_security_from_env(&hd.sec, serr, sizeof serr);
    if (src < 0) {
      fprintf(stderr, "palp-web: %s\n", serr);
      return 2;
    }
    if ((pki || identity) && hd.sec.kind == PALP_DDS_ID_NONE) {
      fprintf(stderr, "palp-web: --pki and --identity go together\n");
      return 2;
    }
    if (hd.sec.warning[0]) fprintf(stderr, "palp-web: warning: DDS Security: %s\n", hd.sec.warning);
    if (hd.sec.kind != PALP_DDS_ID_NONE && hd.sec.kind != PALP_DDS_ID_INSTRUCTOR) {
      fprintf(stderr, "palp-web: --identity %s/%s: the bridge shows every session, which only an instructor "
                      "identity may read (instructor/NAME)\n",
              palp_dds_id_kind_name(hd.sec.kind), hd.sec.name);
      return 2;
    }
  }
  char tokbuf[PALP_WEB_TOKEN_MAX + 1];
  const char *token_arg = token; /* --token T: what SIGHUP cannot change */
  why e = {{0}};
  if (token_file) {
    if (token) {
      fprintf(stderr, "palp-web: give --token or --token-file, not both\n");
      return 2;
    }
    if (read_token_file(token_file, tokbuf, &e)) {
      fprintf(stderr, "palp-web: %s\n", e.text);
      return 2;
    }
    token = tokbuf;
  }
  if (token && palp_web_token_check(token) != 0) {
    fprintf(stderr, "palp-web: the token must be %d-%d characters of A-Z a-z 0-9 . _ ~ -\n", PALP_WEB_TOKEN_MIN,
            PALP_WEB_TOKEN_MAX);
    return 2;
  }
  /* The security rule of issue 14: beyond loopback only with a token. */
  if (!palp_web_addr_is_loopback(sd.listen) && !token) {
    fprintf(stderr,
            "palp-web: refusing to serve on %s without an access token: anyone on that network could watch the "
            "class. Give --token T (or --token-file F), or listen on 127.0.0.1.\n",
            sd.listen);
    return 2;
  }
  /* And with TLS (2026-12-04): a token sent in clear over the class network is anyone's who listens. */
  if (!sd.tls_cert != !sd.tls_key) {
    fprintf(stderr, "palp-web: --tls-cert and --tls-key go together\n");
    return 2;
  }
  for (int k = 0; k < 2; k++) {
    const char *f = k ? sd.tls_key : sd.tls_cert;
    if (f && access(f, R_OK) != 0) {
      fprintf(stderr, "palp-web: %s %s: %s\n", k ? "--tls-key" : "--tls-cert", f, strerror(errno));
      return 2;
    }
    if (k && f && secret_private("--tls-key", f, &e)) {
      fprintf(stderr, "palp-web: %s\n", e.text);
      return 2;
    }
  }
  if (!palp_web_addr_is_loopback(sd.listen) && !sd.tls_cert && !insecure_http) {
    fprintf(stderr,
            "palp-web: refusing to serve on %s without TLS: the access token and the class's sessions would cross "
            "the network in clear. Give --tls-cert F --tls-key F (scripts/make-classroom-pki.sh DIR web HOST makes "
            "them from the classroom CA), or --insecure-http on a network only the class can reach.\n",
            sd.listen);
    return 2;
  }
  sd.token = token;
  /* Tokens expire (a token printed for Monday's class must not open Friday's): their age counts from
   * when they were written, so a restart does not make an old file's tokens new again. */
  const double start = wall_s();
  sd.token_lifetime_s = token_lifetime_h * 3600.0;
  sd.token_issued_s = token_file ? issued_at(token_file, start) : start;
  /* Trainees' own tokens: each page scoped to its trainee, as the trainee's DDS permissions are. */
  static palp_web_trainee_token trainees[PALP_WEB_TRAINEES_MAX];
  if (trainee_file) {
    if (!token) {
      fprintf(stderr, "palp-web: --trainee-tokens needs --token (or --token-file): the instructors' own token\n");
      return 2;
    }
    const int n = read_trainee_tokens(trainee_file, token, start, trainees, &e);
    if (n < 0) {
      fprintf(stderr, "palp-web: %s\n", e.text);
      return 2;
    }
    sd.trainees = trainees;
    sd.trainee_count = n;
  }
  static palp_log log; /* static: Cyclone's threads may log through it until the process ends */
  if (palp_log_init(&log, "palp-web", ao.log_level, ao.log_file) < 0) {
    fprintf(stderr, "palp-web: --log-file %s: cannot open it: %s\n", ao.log_file, strerror(errno));
    return 2;
  }
  hd.log = &log;
  sd.log = &log;
  /* The pages live in the data directory (app/palp_app.h): never a source-tree path. */
  char www[1024], derr[256];
  if (!sd.www_dir) {
    if (palp_app_data_path("www", www, sizeof www, derr, sizeof derr) < 0) {
      palp_log_error(&log, "the pages: %s (give --www DIR)", derr);
      return 2;
    }
    sd.www_dir = www;
  }
  if (access(sd.www_dir, R_OK) != 0) {
    palp_log_error(&log, "--www %s: not readable", sd.www_dir);
    return 2;
  }
  /* The certificate and key read and checked here, before libwebsockets (web/tls.h): one reason per
   * refusal, and the day the certificate must be renewed said at every start in its last month. */
  if (sd.tls_cert) {
    char terr[512], twarn[512];
    if (palp_web_tls_check(sd.tls_cert, sd.tls_key, terr, sizeof terr, twarn, sizeof twarn) != 0) {
      palp_log_error(&log, "%s", terr);
      return 2;
    }
    if (twarn[0]) palp_log_warn(&log, "%s", twarn);
  }
  if (palp_app_use_dds_config(ao.dds_config, NULL, NULL, 0, derr, sizeof derr) != 0) {
    palp_log_error(&log, "DDS config: %s", derr);
    return 2;
  }
  /* --scale-mm alone below the default smallest scale: that one scale, fixed. */
  if (!scale_min_given && hd.scale_min_mm > hd.scale_mm) hd.scale_min_mm = hd.scale_mm;
  if (hd.scale_min_mm > hd.scale_mm) {
    palp_log_error(&log, "--scale-min-mm %g is above --scale-mm %g", hd.scale_min_mm, hd.scale_mm);
    return 2;
  }
  /* Cyclone's warnings bounded, a refused peer said once (client/main.c does the same). */
  static palp_dds_log_limit dds_sink;
  static palp_dds_refusals refusals;
  palp_dds_refusals_init(&refusals, palp_log_warn_line, &log, PALP_DDS_REFUSAL_WINDOW_S);
  palp_dds_refusals_install(&dds_sink, &refusals, 10, 10.0);
  /* a peer refused for its permissions named by its identity, not its GUID */
  if (palp_dds_security_name_peers(&hd.sec, &refusals) < 0) palp_log_warn(&log, "out of memory naming the classroom's identities");
  hd.refusals = &refusals; /* the dashboard lists them */
  char err[PALP_DDS_HINT_MAX + 256]; /* a refused reader's message ends with palp_dds_refused_hint's */
  palp_web_hub *hub = palp_web_hub_create(&hd, err, sizeof err);
  if (!hub) {
    palp_log_error(&log, "%s", err);
    return 1;
  }
  palp_web_server *srv = palp_web_serve_create(&sd, hub, err, sizeof err);
  if (!srv) {
    palp_log_error(&log, "%s", err);
    palp_web_hub_destroy(hub);
    return 1;
  }
  palp_app_on_signals(on_signal); /* by sigaction: signal()'s handler lasted one SIGHUP (palp_app.h) */
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sigemptyset(&sa.sa_mask);
  sa.sa_handler = SIG_IGN;
  sigaction(SIGPIPE, &sa, NULL);
  watch w = {.srv = srv, .hub = hub, .end = duration > 0 ? mono_s() + duration : 0, .stats = stats, .log = &log,
             .token_arg = token_arg, .token_file = token_file, .trainee_file = trainee_file, .start = start,
             .token_lifetime_s = sd.token_lifetime_s};
  if (palp_web_hub_start(hub, on_wake, &w) != 0) {
    palp_log_error(&log, "cannot start the DDS thread");
    palp_web_serve_destroy(srv);
    palp_web_hub_destroy(hub);
    return 1;
  }
  const int port = palp_web_serve_port(srv);
  const char *host = strchr(sd.listen, ':') ? "[::1]" : sd.listen;
  char q[PALP_WEB_TOKEN_MAX + 16] = "";
  /* A token given on the command line is already visible to this user; one read from a file is
   * not repeated into logs. */
  if (token) snprintf(q, sizeof q, "?token=%s", token_file ? "<the token>" : token);
  char scoped[64] = "";
  if (sd.trainee_count) snprintf(scoped, sizeof scoped, "; %d trainee token(s), each page scoped", sd.trainee_count);
  char security[96];
  printf("palp-web: DDS domain %u, DDS Security %s, serving%s on %s port %d%s%s%s\n", hd.domain,
         palp_dds_security_state(&hd.sec, security, sizeof security), sd.tls_cert ? " HTTPS" : "", sd.listen,
         port, token ? " (token required" : "", scoped, token ? ")" : "");
  const char *scheme = sd.tls_cert ? "https" : "http";
  if (!palp_web_addr_is_loopback(sd.listen) && !sd.tls_cert)
    palp_log_warn(&log, "serving plain HTTP on %s (--insecure-http): the token crosses the network in clear",
                  sd.listen);
  if (token)
    say_token_lifetime(&log, sd.token_issued_s, sd.trainee_count, sd.trainee_count ? sd.trainees[0].issued_s : 0,
                       sd.token_lifetime_s, token_file, trainee_file, start, 1);
  printf("palp-web: trainee page  %s://%s:%d/trainee.html%s\n", scheme, host, port, q);
  printf("palp-web: dashboard     %s://%s:%d/dashboard.html%s\n", scheme, host, port, q);
  /* Who sees the answers: the dashboard's viewers (docs/web.md, "The hidden lumps"). */
  if (!hd.answers)
    printf("palp-web: hidden lumps: not shown (--no-answers)\n");
  else
    printf("palp-web: hidden lumps: on the dashboard, for %s; never on a trainee page%s\n",
           token ? "holders of the instructors' token" : "anyone who opens it on this host (no --token)",
           hd.sec.kind == PALP_DDS_ID_NONE ? " (a server without DDS Security sends them only if its config "
                                             "says \"session_exercise\": \"always\")"
                                           : "");
  fflush(stdout);
  palp_web_serve_run(srv, &g_stop);
  palp_web_hub_stop(hub);
  print_stats(&log, hub, srv);
  palp_web_serve_destroy(srv);
  palp_web_hub_destroy(hub);
  palp_dds_log_limit_remove(&dds_sink); /* before the log closes; then the repeats not yet said */
  palp_dds_refusals_flush(&refusals);
  palp_log_close(&log);
  return 0;
}
