/* main.c - palp-client: a trainee, visual or observer station. */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "episode.h"
#include "haptic_loop.h"
#include "input_trainee.h"
#include "input.h"
#include "palp.h"
#include "palp_app.h"
#include "palp_assess.h"
#include "palp_dds.h"
#include "palp_coverage.h"
#include "palp_dds_refusals.h"
#include "palp_place.h"
#include "palp_utf8.h"
#include "station.h"
#include "view.h"

/* Set by SIGINT/SIGTERM/SIGHUP, polled by the loops and the station's waits (palp_cli_station.stop).
 * Atomic, not volatile sig_atomic_t: the signal may land on any thread of the process (Cyclone's,
 * OpenBLAS's), and only a lock-free atomic may be shared between a handler and other threads (C17
 * 7.14.1.1; ThreadSanitizer saw the race). */
static atomic_int g_stop;
static void on_signal(int sig) {
  (void)sig;
  g_stop = 1;
}

/* The terminal as it was before a keyboard input made it raw (no echo, no line editing). The
 * input's close() puts it back, and SIGINT/SIGTERM/SIGHUP end the station through close(); SIGQUIT
 * (Ctrl-\ works in the raw terminal), a crash or an exit() elsewhere did not, and left the shell
 * without echo. Those put it back here, then end the station as they did (the default
 * action, re-raised). tcsetattr and raise are async-signal-safe. */
static struct termios g_tty;
static atomic_int g_tty_saved;
static void restore_tty(void) {
  if (atomic_load(&g_tty_saved)) tcsetattr(STDIN_FILENO, TCSANOW, &g_tty);
}
static void on_fatal_signal(int sig) {
  restore_tty();
  raise(sig); /* SA_RESETHAND: now the default action */
}
static void guard_tty(void) {
  if (tcgetattr(STDIN_FILENO, &g_tty) != 0) return;
  atomic_store(&g_tty_saved, 1);
  atexit(restore_tty);
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_fatal_signal;
  sa.sa_flags = SA_RESETHAND;
  sigemptyset(&sa.sa_mask);
  const int sigs[] = {SIGQUIT, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
  for (size_t i = 0; i < sizeof sigs / sizeof sigs[0]; i++) {
    struct sigaction old;
    /* an ignored signal stays ignored (a background job's SIGQUIT): it ends nothing */
    if (sigaction(sigs[i], NULL, &old) == 0 && old.sa_handler != SIG_IGN) sigaction(sigs[i], &sa, NULL);
  }
}

typedef struct opts {
  const char *role;
  uint32_t domain, phantom, session;
  const char *name;
  const char *input;
  const char *profile;
  int distribution;
  double magnitude, t_on, t_off, frequency, offset, polar, azimuth;
  double finger_radius_mm, patch_area_cm2;
  double rate, duration, timeout, print_period;
  /* A keyboard input keeps a status line on the terminal (stderr, rewritten with \r): each of
   * the station's own lines then starts by clearing it, and the status line comes back at its
   * next refresh (<= 0.5 s), instead of the line being appended to it. */
  int status_line;
  const char *feedback_csv, *contact_csv, *svg, *trainee;
  const char *pki, *identity; /* DDS Security (docs/security.md); env PALP_PKI / PALP_IDENTITY */
  double svg_every, map_every;
  double max_force, haptic_rate;
  int rt_priority, rt_priority_given; /* the haptic thread's SCHED_FIFO priority (0: normal), and whether asked for */
  const char *trace_csv;
  int color, quiet, map, no_map, plot;
  int have_magnitude, have_t_off;
  palp_app_opts app; /* --version, --dds-config, --log-level, --log-file */
  const char *phantom_name, *server; /* several servers on one domain */
  int rejoin;
  palp_log *log; /* main's, once the options are read: diagnostics, not the station's output */
  /* main's table of peers DDS Security refused: each run loop ticks it, so that a refused peer's
   * repeats are said a window after its last line, not only when the station stops */
  palp_dds_refusals *refusals;
} opts;

/* The refusal table's tick, once a turn of a run loop (cheap: a lock and a time compare). */
static void tick_refusals(const opts *o) {
  if (o->refusals) palp_dds_refusals_tick(o->refusals, palp_dds_now_ns());
}

/* The station's own output lines (stdout): after the keyboard's status line, from its start. */
static void tprintf(const opts *o, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void tprintf(const opts *o, const char *fmt, ...) {
  if (o->status_line) fputs("\r\033[K", stdout);
  /* The lines carry text from the server and the classroom (an exercise's title and instructions,
   * refusal and close reasons, phantom names): written terminal-safe, so no sample can move the
   * cursor, rewrite a line the trainee reads or retitle her terminal (session 75, found by review). */
  char small[1024], *buf = small;
  va_list ap;
  va_start(ap, fmt);
  const int n = vsnprintf(small, sizeof small, fmt, ap);
  va_end(ap);
  if (n < 0) return;
  if ((size_t)n >= sizeof small && (buf = malloc((size_t)n + 1)) != NULL) {
    va_start(ap, fmt);
    vsnprintf(buf, (size_t)n + 1, fmt, ap);
    va_end(ap);
  }
  if (!buf) buf = small; /* no memory: the line cut at 1 kB */
  palp_cli_terminal_safe(buf);
  fputs(buf, stdout);
  if (buf != small) free(buf);
}

/* --quiet already means "less station output" here: no --verbose/--quiet aliases. */
#define CLIENT_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_DDS | PALP_APP_OPT_LOG)

static void usage(FILE *f) {
  fprintf(f,
          "usage: palp-client --role trainee|visual|observer [options]\n"
          "common:   --domain N  --phantom ID  --session ID  --name NAME  --duration S  --timeout S  --quiet\n"
          "secured:  --pki DIR --identity trainee/NAME|instructor/NAME (or PALP_PKI, PALP_IDENTITY):\n"
          "          DDS Security with that identity (scripts/make-classroom-pki.sh); --name defaults to NAME\n"
          "trainee:  --input script|replay:FILE|keyboard|keyboard-finger|sim:TRAJ|device:LIB.so[:ARG]\n"
          "          (default script; keyboard: force by keys, keyboard-finger: a fingertip by position)\n"
          "          --profile paper|step|ramp|sine  --distribution 1-4  --magnitude N  --t-on S --t-off S\n"
          "          --frequency HZ --offset N  --polar DEG --azimuth DEG  --patch-area CM2\n"
          "          --finger-radius MM  (position-driven finger: magnitude is the depth in mm)\n"
          "          --rate HZ  --feedback-csv FILE  --contact-csv FILE  --print-period S\n"
          "          --plot (chart of the feedback force at the end)\n"
          "          position-driven devices (--input sim:TRAJ | keyboard-finger | device:LIB.so with\n"
          "          read_position): a 1 kHz haptic thread renders the server's local contact models\n"
          "          --haptic-rate HZ (1000)  --max-force N (safe force, default 10)\n"
          "          --rt-priority 0-99 (SCHED_FIFO priority of the haptic thread, default 20 where allowed; 0: normal)\n"
          "          --trace-csv FILE (every haptic tick: t, device point, force, flags)\n"
          "          TRAJ: press|slide|circles|cycles|strips[,depth_mm=10,speed_mm_s=20,hold_s=0.5,\n"
          "          slide_mm_s=50,slide_mm=20,circle_mm=5,circle_hz=1,circles=2,cycles=5,strips=4,\n"
          "          polar=0,azimuth=0,radius_mm=8]\n"
          "visual:   --map (observer too)  --no-map  --map-every S  --no-color  --svg FILE  --svg-every S\n"
          "viewers:  follow --session ID, --trainee NAME (an open session of that trainee), or the newest\n"
          "          session on --phantom ID\n"
          "servers:  --server NAME (--phantom ID is that server's local id)  --phantom-name NAME (the least\n"
          "          busy phantom of that name, on --server if given)  --rejoin (a force-driven trainee: when\n"
          "          the server is lost, join a phantom of the same name on another server and go on)\n");
  palp_app_common_usage(f, CLIENT_OPTS);
}

static int num(const char *opt, const char *v, double lo, double hi, double *out) {
  char *end = NULL;
  errno = 0;
  double x = v ? strtod(v, &end) : 0;
  if (!v || errno || end == v || *end || !(x >= lo && x <= hi)) {
    fprintf(stderr, "palp-client: %s: expected a number in [%g, %g], got \"%s\"\n", opt, lo, hi, v ? v : "");
    return -1;
  }
  *out = x;
  return 0;
}

/* The longest name the wire carries whole: SessionRequest.user_name and SessionState.trainee_name are
 * string<63>. A longer --name was cut at byte 63 (inside a UTF-8 character, it could be), so the server's
 * log, the review and a viewer's --trainee knew another name than the one the station printed. */
#define NAME_MAX_BYTES 63
/* A viewer's snapshot names: the --svg prefix, "-NNNN.svg" (svg_no: up to 10 digits), the NUL. */
#define SVG_PATH_MAX 1100
/* --input device:LIB.so[:ARG]'s copy, split at the first ':' after the path. */
#define DEVICE_SPEC_MAX 1024

/* A name for the wire (--name, --trainee): at most NAME_MAX_BYTES bytes of UTF-8 text. 0 ok; -1 said. */
static int name_option(const char *opt, const char *v) {
  const size_t n = strlen(v);
  if (n > NAME_MAX_BYTES) {
    fprintf(stderr, "palp-client: %s: at most %d bytes (the session's records carry that many), got %zu\n", opt,
            NAME_MAX_BYTES, n);
    return -1;
  }
  for (size_t i = 0, k; i < n; i += k)
    if ((k = palp_utf8_len((const unsigned char *)v + i, n - i)) == 0) {
      fprintf(stderr, "palp-client: %s: not UTF-8 text (byte %zu)\n", opt, i + 1);
      return -1;
    }
  return 0;
}

/* A trainee's --profile and --input as given (docs/deploy.md: a bad option value is a command-line mistake,
 * exit 2; session 83 review: --profile square and --input sim:circles,circles=2.5 exited 1, as a failure).
 * What only opening the input can tell (a replay file, a driver, a terminal) stays a failure, exit 1.
 * 0 ok; -1 with why in err. */
static int check_input_option(const opts *o, char *err, size_t errlen) {
  if (strcmp(o->profile, "paper") && strcmp(o->profile, "step") && strcmp(o->profile, "ramp") &&
      strcmp(o->profile, "sine")) {
    snprintf(err, errlen, "--profile: expected paper, step, ramp or sine, got \"%s\"", o->profile);
    return -1;
  }
  const char *in = o->input;
  if (!strcmp(in, "script") || !strncmp(in, "replay:", 7) || !strcmp(in, "keyboard") || !strcmp(in, "keyboard-finger"))
    return 0;
  if (!strncmp(in, "sim:expert", 10) || !strncmp(in, "sim:novice", 10)) {
    palp_cli_trainee_def d;
    return palp_cli_trainee_parse(in + 4, &d, err, errlen) < 0 ? -1 : 0;
  }
  if (!strncmp(in, "sim:", 4)) {
    palp_cli_simdevice_def d;
    return palp_cli_simdevice_parse(in + 4, &d, err, errlen) < 0 ? -1 : 0;
  }
  if (!strncmp(in, "device:", 7)) {
    /* a longer path was cut and the cut one dlopen()ed: possibly another file (session 83 review) */
    if (strlen(in + 7) >= DEVICE_SPEC_MAX) {
      snprintf(err, errlen, "--input device:...: at most %d bytes of path and argument, got %zu", DEVICE_SPEC_MAX - 1,
               strlen(in + 7));
      return -1;
    }
    return 0;
  }
  snprintf(err, errlen,
           "--input: expected script, replay:FILE, keyboard, keyboard-finger, sim:TRAJ or device:LIB.so[:ARG], got \"%s\"",
           in);
  return -1;
}

static int parse(int argc, char **argv, opts *o) {
  *o = (opts){.role = NULL, .name = "", .input = "script", .profile = "paper", .distribution = 2, .polar = 30,
              .azimuth = 40, .timeout = 10, .print_period = 0.5, .color = isatty(STDOUT_FILENO), .map_every = 0.5,
              /* A haptic thread at normal priority was late on 0.2-0.9% of its 1 kHz ticks in the
               * demo (a 2-core machine with the server on it), at SCHED_FIFO 20 on 0-0.04%
               * (docs/station.md): real-time by default where allowed, as a haptics library does. */
              .rt_priority = 20};
  palp_app_opts_init(&o->app, "palp-client");
  int print_period_given = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    double x = 0;
#define NUM(flag, lo, hi, dst)                                                                                 \
  if (!strcmp(a, flag)) {                                                                                      \
    if (num(a, v, lo, hi, &x)) return -1;                                                                      \
    dst = x;                                                                                                   \
    i++;                                                                                                       \
    continue;                                                                                                  \
  }
#define INT(flag, lo, hi, dst)                                                                                 \
  if (!strcmp(a, flag)) {                                                                                      \
    if (num(a, v, lo, hi, &x)) return -1;                                                                      \
    if (x != floor(x)) {                                                                                       \
      fprintf(stderr, "palp-client: %s: expected a whole number, got \"%s\"\n", a, v);                         \
      return -1;                                                                                               \
    }                                                                                                          \
    dst = x;                                                                                                   \
    i++;                                                                                                       \
    continue;                                                                                                  \
  }
#define STR(flag, dst)                                                                                         \
  if (!strcmp(a, flag)) {                                                                                      \
    if (!v) {                                                                                                  \
      fprintf(stderr, "palp-client: %s: missing value\n", a);                                                \
      return -1;                                                                                               \
    }                                                                                                          \
    dst = v;                                                                                                   \
    i++;                                                                                                       \
    continue;                                                                                                  \
  }
    STR("--role", o->role)
    INT("--domain", 0, 232, o->domain)
    INT("--phantom", 0, 4294967295.0, o->phantom)
    INT("--session", 0, 4294967295.0, o->session)
    STR("--name", o->name)
    STR("--trainee", o->trainee)
    STR("--pki", o->pki)
    STR("--identity", o->identity)
    STR("--phantom-name", o->phantom_name)
    STR("--server", o->server)
    if (!strcmp(a, "--rejoin")) { o->rejoin = 1; continue; }
    STR("--input", o->input)
    STR("--profile", o->profile)
    INT("--distribution", 1, 4, o->distribution)
    if (!strcmp(a, "--magnitude")) o->have_magnitude = 1;
    NUM("--magnitude", -1000, 1000, o->magnitude)
    NUM("--t-on", 0, 1e6, o->t_on)
    if (!strcmp(a, "--t-off")) o->have_t_off = 1;
    NUM("--t-off", 0, 1e6, o->t_off)
    NUM("--frequency", 0, 1000, o->frequency)
    NUM("--offset", -1000, 1000, o->offset)
    NUM("--polar", 0, 90, o->polar)
    NUM("--azimuth", -360, 360, o->azimuth)
    NUM("--finger-radius", 0.1, 100, o->finger_radius_mm)
    NUM("--patch-area", 0.01, 100, o->patch_area_cm2)
    NUM("--rate", 1, 10000, o->rate)
    NUM("--max-force", 0.01, 1000, o->max_force)
    NUM("--haptic-rate", 10, 10000, o->haptic_rate)
    if (!strcmp(a, "--rt-priority")) o->rt_priority_given = 1;
    INT("--rt-priority", 0, 99, o->rt_priority)
    STR("--trace-csv", o->trace_csv)
    NUM("--duration", 0, 1e6, o->duration)
    NUM("--timeout", 0.1, 3600, o->timeout)
    if (!strcmp(a, "--print-period")) print_period_given = 1;
    NUM("--print-period", 0, 3600, o->print_period)
    STR("--feedback-csv", o->feedback_csv)
    STR("--contact-csv", o->contact_csv)
    STR("--svg", o->svg)
    NUM("--svg-every", 0.01, 3600, o->svg_every)
    NUM("--map-every", 0.01, 3600, o->map_every)
    if (!strcmp(a, "--map")) { o->map = 1; continue; }
    if (!strcmp(a, "--no-map")) { o->no_map = 1; continue; }
    if (!strcmp(a, "--plot")) { o->plot = 1; continue; }
    if (!strcmp(a, "--no-color")) { o->color = 0; continue; }
    if (!strcmp(a, "--quiet")) { o->quiet = 1; continue; }
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) { usage(stdout); exit(0); }
    int common = palp_app_common_opt(&o->app, CLIENT_OPTS, argc, argv, &i);
    if (common < 0) return -1;
    if (common) continue;
    fprintf(stderr, "palp-client: unknown option: %s\n", a);
    return -1;
#undef NUM
#undef INT
#undef STR
  }
  if (o->app.version) return 0;
  if (!strcmp(o->input, "keyboard") || !strcmp(o->input, "keyboard-finger")) {
    /* The finger keyboard's status line shows what its periodic line would (depth, rendered
     * force), twice a second: that line only on request. The force keyboard's status line shows
     * the command, not the phantom's answer (the pole's displacement): its periodic line stays. */
    if (!strcmp(o->input, "keyboard-finger") && !print_period_given) o->print_period = 0;
    o->status_line = isatty(STDOUT_FILENO) && isatty(STDERR_FILENO);
  }
  if (!o->role || (strcmp(o->role, "trainee") && strcmp(o->role, "visual") && strcmp(o->role, "observer"))) {
    fprintf(stderr, "palp-client: --role: expected trainee, visual or observer\n");
    return -1;
  }
  if (!strcmp(o->role, "trainee") && o->phantom == 0 && !o->phantom_name) {
    fprintf(stderr, "palp-client: --phantom: a trainee needs the id (or --phantom-name) of the phantom to palpate\n");
    return -1;
  }
  char why[320];
  if (!strcmp(o->role, "trainee") && check_input_option(o, why, sizeof why) < 0) {
    fprintf(stderr, "palp-client: %s\n", why);
    return -1;
  }
  if (name_option("--name", o->name) < 0 || (o->trainee && name_option("--trainee", o->trainee) < 0)) return -1;
  /* a longer prefix's snapshots were written under a cut name (session 83 review) */
  if (o->svg && strlen(o->svg) + sizeof "-2147483647.svg" > SVG_PATH_MAX) {
    fprintf(stderr, "palp-client: --svg: at most %zu bytes, got %zu\n", SVG_PATH_MAX - sizeof "-2147483647.svg",
            strlen(o->svg));
    return -1;
  }
  /* With --server the ids are that server's local ones (PALP_DDS_ID_LOCAL_BITS): a larger one's high
   * bits went into the server number, and --server roomA --phantom 1048577 joined roomB's phantom 1
   * without a word (session 80's review, 2026-12-07). */
  const uint32_t local_max = (1u << PALP_DDS_ID_LOCAL_BITS) - 1u;
  if (o->server && (o->phantom > local_max || o->session > local_max)) {
    fprintf(stderr, "palp-client: --server %s: --phantom and --session are that server's own ids, 1..%u (got %s %u)\n",
            o->server, local_max, o->phantom > local_max ? "--phantom" : "--session",
            o->phantom > local_max ? o->phantom : o->session);
    return -1;
  }
  return 0;
}

static double norm3(palp_Vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

/* Closes an output file the user asked for (NULL: none), saying if it could not all be written: a full
 * disk left a cut CSV that looked whole, and the station exited 0 (until 2026-12-07). 0, or -1 said. */
static int close_output(const opts *o, FILE *f, const char *path) {
  if (!f) return 0;
  const int bad = ferror(f);
  if (fclose(f) != 0 || bad) {
    palp_log_error(o->log, "cannot write %s: %s (the file is incomplete)", path, strerror(errno ? errno : EIO));
    return -1;
  }
  return 0;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* ---- input selection --------------------------------------------------------------- */

static int make_input(const opts *o, palp_cli_input *in, char *err, size_t errlen) {
  if (!strcmp(o->input, "script")) {
    palp_cli_script_def d = {.finger_mode = o->finger_radius_mm > 0, .distribution = o->distribution,
                             .polar_deg = o->polar, .azimuth_deg = o->azimuth,
                             .radius = o->finger_radius_mm * 1e-3, .patch_area = o->patch_area_cm2 * 1e-4};
    palp_profile p = palp_profile_paper_step();
    double mag = o->have_magnitude ? o->magnitude : (d.finger_mode ? 5.0 : p.magnitude); /* 3 N, or 5 mm */
    if (!strcmp(o->profile, "paper")) {
      /* the paper's 3 N step held 2 s (or a 5 mm indentation for a finger) */
    } else if (!strcmp(o->profile, "step")) {
      p.kind = PALP_PROFILE_STEP;
    } else if (!strcmp(o->profile, "ramp")) {
      p.kind = PALP_PROFILE_RAMP;
    } else if (!strcmp(o->profile, "sine")) {
      p.kind = PALP_PROFILE_SINE;
      p.frequency = o->frequency > 0 ? o->frequency : 1.0;
      p.offset = o->offset != 0 ? o->offset : mag;
    } else {
      snprintf(err, errlen, "--profile: expected paper, step, ramp or sine, got \"%s\"", o->profile);
      return PALP_EINVAL;
    }
    p.magnitude = d.finger_mode ? mag * 1e-3 : mag;
    if (d.finger_mode) p.offset *= 1e-3;
    if (strcmp(o->profile, "paper")) {
      p.t_on = o->t_on;
      p.t_off = o->have_t_off ? o->t_off : o->t_on + 2.0;
    }
    d.profile = p;
    /* Run to the end of the profile plus 1 s of recovery unless told otherwise. */
    d.end_time = o->duration > 0 ? o->duration : p.t_off + 1.0;
    return palp_cli_script_input(&d, in);
  }
  if (!strncmp(o->input, "replay:", 7)) return palp_cli_replay_input(o->input + 7, in, err, errlen);
  if (!strcmp(o->input, "keyboard"))
    return palp_cli_keyboard_input(in, o->max_force > 0 ? o->max_force : palp_cli_haptic_default_def().render.max_force,
                                   err, errlen);
  if (!strcmp(o->input, "keyboard-finger")) return palp_cli_keyboard_finger_input(in, err, errlen);
  if (!strncmp(o->input, "sim:expert", 10) || !strncmp(o->input, "sim:novice", 10)) {
    palp_cli_trainee_def d;
    int rc = palp_cli_trainee_parse(o->input + 4, &d, err, errlen);
    if (rc < 0) return rc;
    if (o->finger_radius_mm > 0) d.radius = o->finger_radius_mm * 1e-3;
    return palp_cli_trainee_input(&d, in);
  }
  if (!strncmp(o->input, "sim:", 4)) {
    palp_cli_simdevice_def d;
    int rc = palp_cli_simdevice_parse(o->input + 4, &d, err, errlen);
    if (rc < 0) return rc;
    if (o->finger_radius_mm > 0) d.radius = o->finger_radius_mm * 1e-3;
    rc = palp_cli_simdevice_input(&d, in);
    if (rc < 0) snprintf(err, errlen, "--input %s: invalid trajectory", o->input);
    return rc;
  }
  if (!strncmp(o->input, "device:", 7)) {
    char path[DEVICE_SPEC_MAX]; /* parse() refused a longer one */
    snprintf(path, sizeof path, "%s", o->input + 7);
    char *arg = strchr(path, ':');
    if (arg) *arg++ = 0;
    return palp_cli_device_input(path, arg, in, err, errlen);
  }
  snprintf(err, errlen,
           "--input: expected script, replay:FILE, keyboard, keyboard-finger, sim:TRAJ or device:LIB.so[:ARG], got \"%s\"",
           o->input);
  return PALP_EINVAL;
}

/* ---- trainee ------------------------------------------------------------------------- */

typedef struct latency {
  double *us;
  size_t n, cap;
} latency;

static void lat_add(latency *l, double us) {
  /* Enough for hours of samples at 1 kHz (8 MB); a peer writing feedback with ever higher sequence
   * numbers must not grow a station's memory for good. */
  if (l->n >= (size_t)1 << 20 || !isfinite(us)) return;
  if (l->n == l->cap) {
    size_t cap = l->cap ? 2 * l->cap : 4096;
    double *p = realloc(l->us, cap * sizeof *p);
    if (!p) return;
    l->us = p;
    l->cap = cap;
  }
  l->us[l->n++] = us;
}

#define PLOT_BINS 4096
#define PLOT_BIN_S 0.02

/* A trainee station's lines carry t = the session's world time (docs/naming.md, "time"), as the observer's
 * do: the newest the server sent, Feedback.sim_time (force-driven: every 0.1 s at least) or the rendered
 * LocalModel.time (position-driven: while the finger is down), what palp-review show prints for the same
 * moment. Until session 83 a trainee printed its own clock since its loop started, which a stalled or
 * late server, a held session or a rejoin set apart from the log's: "t= 12.30 s OUTSIDE THE MODEL'S
 * VALID RANGE" could not be found at 12.30 s in the review. A periodic line waits for the first world
 * time (no line before the server has said one). */

typedef struct feedback_ctx {
  palp_cli_station *st;
  palp_cli_input *in;
  FILE *csv;
  int64_t t0;
  uint64_t echoed[PALP_CLI_MAX_FINGERS];
  uint64_t samples;
  double peak, last, last_top;
  latency lat;
  /* finger-0 force magnitude [N] per 20 ms bin since t0, for --plot */
  double plot[PLOT_BINS];
  int plot_bins;
  double max_force; /* [N] the station's safe force, for a driver's feedback() */
  /* A driver's feedback() is called as samples come; without one for stale_time [s] its force fades
   * to 0 N over fade_time [s], the haptic thread's rule for its models (a server gone or stopped must
   * not leave its last force on the hand: it stayed there until the station closed, or for good while
   * a stopped server's lease held). given: each finger's force from the newest sample [N]; scale: the
   * share of it the driver has now (1, fading, 0). */
  palp_vec3 given[PALP_CLI_MAX_FINGERS];
  double scale;
  palp_haptic_def fade; /* its stale_time and fade_time: the renderer's (palp_haptic_fade) */
  int64_t last_rx_ns;
  double world_t; /* the newest feedback's sim_time [s]; < 0: none yet */
} feedback_ctx;

/* Takes every feedback sample; latency from the echoed contact stamp. */
static void drain_feedback(feedback_ctx *c) {
  for (;;) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    if (dds_take(c->st->feedback_r, ptr, &info, 1, 1) <= 0) break;
    const palp_Feedback *fb = ptr[0];
    int64_t rx = palp_dds_now_ns();
    if (info.valid_data && palp_cli_station_from_server(c->st, c->st->feedback_r, &info)) {
      c->samples++;
      c->last_top = fb->top_displacement;
      if (isfinite(fb->sim_time)) c->world_t = fb->sim_time;
      for (uint32_t k = 0; k < fb->fingers._length; k++) {
        const palp_FingerFeedback *ff = &fb->fingers._buffer[k];
        double lat_us = NAN;
        if (ff->finger < PALP_CLI_MAX_FINGERS && ff->contact_seq > c->echoed[ff->finger]) {
          c->echoed[ff->finger] = ff->contact_seq;
          lat_us = (double)(rx - ff->contact_source_time_ns) * 1e-3;
          lat_add(&c->lat, lat_us);
        }
        double m = norm3(ff->force);
        if (ff->finger == 0) {
          c->last = m;
          int bin = (int)((double)(rx - c->t0) * 1e-9 / PLOT_BIN_S);
          if (bin >= 0 && bin < PLOT_BINS) {
            if (m > c->plot[bin]) c->plot[bin] = m;
            if (bin + 1 > c->plot_bins) c->plot_bins = bin + 1;
          }
        }
        if (m > c->peak) c->peak = m;
        if (c->in->feedback && ff->finger < PALP_CLI_MAX_FINGERS) {
          palp_vec3 safe;
          palp_cli_device_force((palp_vec3){ff->force.x, ff->force.y, ff->force.z}, c->max_force, &safe);
          c->in->feedback(c->in->ctx, ff->finger, safe);
          c->given[ff->finger] = safe;
          c->scale = 1;
          c->last_rx_ns = rx;
        }
        if (c->csv)
          fprintf(c->csv, "%.6f,%llu,%.6f,%u,%d,%.6g,%.6g,%.6g,%.6g,%.1f\n", (double)(rx - c->t0) * 1e-9,
                  (unsigned long long)fb->frame, fb->sim_time, ff->finger, ff->active, ff->force.x, ff->force.y,
                  ff->force.z, fb->top_displacement, lat_us);
      }
    }
    dds_return_loan(c->st->feedback_r, ptr, 1);
  }
}

/* The driver's force faded after stale_time without a sample, 0 N after fade_time more (feedback_ctx);
 * now_ns < 0: 0 N at once (the station stops: the driver is not left holding a force). */
static void fade_feedback(feedback_ctx *c, int64_t now_ns) {
  if (!c->in->feedback || c->scale <= 0) return;
  const double s = now_ns < 0 ? 0 : palp_haptic_fade(&c->fade, (double)(now_ns - c->last_rx_ns) * 1e-9);
  if (s >= c->scale) return;
  c->scale = s;
  for (int f = 0; f < PALP_CLI_MAX_FINGERS; f++) {
    const palp_vec3 g = c->given[f];
    if (g.x != 0 || g.y != 0 || g.z != 0) c->in->feedback(c->in->ctx, f, (palp_vec3){g.x * s, g.y * s, g.z * s});
  }
}

/* Feedback force over time as a terminal chart: 16 rows, one column per group of bins. */
static void plot_feedback_titled(const feedback_ctx *c, FILE *out, const char *title) {
  enum { W = 64, H = 16 };
  if (c->plot_bins < 2) return;
  int per = (c->plot_bins + W - 1) / W;
  int cols = (c->plot_bins + per - 1) / per;
  double col[W] = {0}, top = 0;
  for (int k = 0; k < cols; k++) {
    for (int b = k * per; b < (k + 1) * per && b < c->plot_bins; b++)
      if (c->plot[b] > col[k]) col[k] = c->plot[b];
    if (col[k] > top) top = col[k];
  }
  if (top <= 0) top = 1;
  fprintf(out, "%s [N] over %.1f s\n", title, c->plot_bins * PLOT_BIN_S);
  for (int r = H; r >= 1; r--) {
    fprintf(out, r == H ? "%6.2f |" : (r == 1 ? "%6.2f |" : "       |"), r == H ? top : 0.0);
    for (int k = 0; k < cols; k++) fputc(col[k] >= top * (r - 0.5) / H ? '#' : ' ', out);
    fputc('\n', out);
  }
  fprintf(out, "       +");
  for (int k = 0; k < cols; k++) fputc('-', out);
  fprintf(out, "\n        0 s%*s%.1f s\n", cols > 10 ? cols - 8 : 1, "", c->plot_bins * PLOT_BIN_S);
}

static void plot_feedback(const feedback_ctx *c, FILE *out) { plot_feedback_titled(c, out, "feedback |F| on finger 0"); }

/* One release sample for finger f (best-effort topic: callers repeat it). */
static void send_release(palp_cli_station *st, int f, uint64_t *seq) {
  palp_Contact m;
  memset(&m, 0, sizeof m);
  m.session_id = st->session_id;
  m.finger = (uint8_t)f;
  m.mode = palp_CONTACT_RELEASE;
  m.vertex = -1;
  m.seq = ++*seq;
  m.source_time_ns = palp_dds_now_ns();
  dds_write(st->contact_w, &m);
}

/* ---- position-driven trainee: the 1 kHz haptic thread (issue 11) ---------------------------- */

/* ---- issue 13: exercises and "lump here" findings on a position-driven station ---------
 * On join the exercise's title and instructions (if the phantom runs one); the
 * device's button (or the keyboard's m / u) marks a lump at the fingertip's contact
 * point, the server's newest LocalModel.point, or withdraws the last mark; the
 * server's answers (marks standing, refusal reasons, time left) are printed. */
#define UI_MARKS 64
typedef struct findings_ui {
  int exercise;
  double time_limit;
  uint32_t sent[UI_MARKS]; /* marks sent and not withdrawn or refused, newest last */
  int nsent;
  int64_t next_time_print;
  uint32_t shown_id;       /* the answer last printed */
  int shown_ok;
  uint32_t shown_marks;
  int said_stranger; /* an answer to a finding this station never sent was said (once a session) */
  int64_t next_exercise_look_ns; /* after EXERCISE_WAIT_S, when the exercise is looked for again */
  /* The exercise's coverage as this station's local models show it, by the rule palp-web's pages
   * mark by (palp_coverage_press_contact) and at the band the exercise grades (palp_band_of): what
   * the review's thoroughness will say, within a point where measured (docs/station.md). */
  palp_coverage *cov;
  palp_band band[PALP_BAND_COUNT];
  double dome_radius, tip_radius; /* [m] */
  int sample_every;               /* the models of the steps the server's log samples for the review */
  double physics_hz;              /* the server's physics rate for this exercise [Hz] */
  uint64_t last_frame;            /* the newest model's step; 0: none yet */
  int last_contact;               /* ... and whether the fingertip touched the phantom in it */
  uint64_t sampled_lost;          /* sampled steps in contact whose models never reached the coverage */
  /* From a server that sends them (palp_finger_sample, session 71): the same coverage from the
   * assessment's own samples, touched triangles named: the review's, not an approximation. Told
   * once one has come; the local models' above otherwise. */
  palp_coverage *touched;
  uint64_t samples, samples_bad, samples_lost, last_sample_frame;
  uint64_t sample_step; /* the steps between two samples, the least seen (the server's assess_sample_hz) */
  int last_sample_contact;
  int64_t join_asked_ns; /* the session opened after this [ns]: its frames are bounded by it (findings_ui_frame_max) */
} findings_ui;

/* The newest frame the session's server can have stepped by now: its physics rate since the JOIN was
 * sent (the session opened after it; its ticker drops the slots it is late for rather than burst), a
 * second and 1% over for the clocks. A local model or finger sample past it was written by another
 * writer in the session's partition (an unsecured classroom), and is refused without moving the
 * marks: one sample of frame 2^64 - 1 made every later genuine one "older", and the coverage stopped
 * for the rest of the session; a model's jump inflated the steps counted lost (session 77). */
static uint64_t findings_ui_frame_max(const findings_ui *u) {
  const double s = (double)(palp_dds_now_ns() - u->join_asked_ns) * 1e-9 + 1.0;
  return (uint64_t)(s * u->physics_hz * 1.01) + 1;
}

/* One local model (the haptic loop's on_model, the main thread): its contact into the coverage,
 * if its step is one the assessment samples: the station, palp-web and the review then count the
 * same steps, and what is left between them is the footprint (the triangles under the fingertip for
 * the touched ones: 0-1.1 points of the dome in the tests, docs/web.md). */
static void findings_ui_model(void *ctx, const palp_local_model *m, uint64_t frame) {
  findings_ui *u = ctx;
  if (!u->cov || frame > findings_ui_frame_max(u)) return;
  /* The server publishes a model every step while the finger is down: a gap between two models
   * in contact is models lost on the way (best-effort) or overwritten in the reader's history
   * (PALP_CLI_MODEL_DEPTH) before this thread took them; a gap with a lifted finger at either
   * end may be the finger up, and is not counted. Counted are the sampled steps in the gap,
   * (last, frame) exclusive: what the review may count and this station could not. */
  const uint64_t se = (uint64_t)u->sample_every;
  if (u->last_frame && u->last_contact && m->contact && frame > u->last_frame + 1)
    u->sampled_lost += (frame - 1) / se - u->last_frame / se;
  if (frame > u->last_frame) u->last_frame = frame, u->last_contact = m->contact != 0;
  if (!m->contact || frame % se) return;
  const double force = sqrt(m->force.x * m->force.x + m->force.y * m->force.y + m->force.z * m->force.z);
  const int b = palp_band_of(u->band, palp_fingertip_depth(u->dome_radius, u->tip_radius, m->proxy), force);
  const double point[3] = {m->point.x, m->point.y, m->point.z}, proxy[3] = {m->proxy.x, m->proxy.y, m->proxy.z};
  if (b >= 0) palp_coverage_press_contact(u->cov, point, proxy, m->triangles, m->area, u->tip_radius, b);
}

/* The server's finger samples of this station's finger (palp_finger_sample), each checked: its
 * session and finger, finite numbers, a frame after the last one's and not past the server's clock
 * (findings_ui_frame_max); each in contact marked at the band the exercise grades, from the
 * fingertip's depth as the review measures it (the sample's own radius), on the triangles it names
 * (src/assess.c's footprint). */
static void findings_ui_samples(findings_ui *u, palp_cli_station *st, int finger) {
  if (!u->touched || st->finger_sample_r <= 0) return;
  const uint64_t frame_max = findings_ui_frame_max(u);
  for (;;) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    if (dds_take(st->finger_sample_r, ptr, &info, 1, 1) <= 0) break;
    const palp_FingerSample *w = ptr[0];
    if (info.valid_data && w->session_id == st->session_id && w->finger == (uint8_t)finger &&
        palp_cli_station_from_server(st, st->finger_sample_r, &info)) {
      if (!palp_dds_finger_sample_ok(w, -1) || w->frame <= u->last_sample_frame || w->frame > frame_max) {
        u->samples_bad++;
      } else {
        /* consecutive samples are the server's sampling step apart (the least seen: its config's
         * assess_sample_hz may not be the default): a larger gap between two in contact is samples
         * lost on the way (best-effort) or overwritten before this thread took them */
        const uint64_t gap = u->last_sample_frame ? w->frame - u->last_sample_frame : 0;
        if (gap && (!u->sample_step || gap < u->sample_step)) u->sample_step = gap;
        if (gap > u->sample_step && u->last_sample_contact && w->in_contact)
          u->samples_lost += gap / u->sample_step - 1;
        u->last_sample_frame = w->frame, u->last_sample_contact = w->in_contact;
        u->samples++;
        if (w->in_contact) {
          const double force = sqrt(w->force.x * w->force.x + w->force.y * w->force.y + w->force.z * w->force.z);
          const palp_vec3 proxy = {w->proxy.x, w->proxy.y, w->proxy.z};
          const int b = palp_band_of(u->band, palp_fingertip_depth(u->dome_radius, w->radius, proxy), force);
          if (b >= 0 && w->triangles._length > 0) {
            palp_coverage_press_touched(u->touched, w->triangles._buffer, (int)w->triangles._length, b);
          } else if (b >= 0) { /* none named: the disc of the footprint's area, as the review */
            const double point[3] = {w->point.x, w->point.y, w->point.z};
            const double centre[3] = {proxy.x, proxy.y, proxy.z};
            palp_coverage_press_contact(u->touched, point, centre, 0, w->area, w->radius, b);
          }
        }
      }
    }
    dds_return_loan(st->finger_sample_r, ptr, 1);
  }
}

/* "light 6.3%, medium 0.0%, deep 0.0%" of the dome, in each band as the review's thoroughness. */
static const char *findings_ui_coverage(const findings_ui *u, char *buf, size_t len) {
  double f[3];
  palp_coverage_band_fractions(u->samples ? u->touched : u->cov, f);
  snprintf(buf, len, "light %.1f%%, medium %.1f%%, deep %.1f%%", 100 * f[0], 100 * f[1], 100 * f[2]);
  return buf;
}

/* How long the station looks for the joined phantom's exercise (transient-local, one per phantom) at
 * every turn of its loop; after that, every EXERCISE_LOOK_S for the rest of the session. Until
 * 2026-12-08 a station found none in the first second decided the phantom ran none: on a loaded
 * machine (install_demo, session 87) a trainee's station missed her exercise's sample that long and
 * showed her no exercise, coverage or debrief while the server graded her session. An exercise is
 * hosted as a phantom of its own for the server's whole run, so a sample found late is still this
 * session's exercise (test haptic_station_late_exercise). */
#define EXERCISE_WAIT_S 1.0
#define EXERCISE_LOOK_S 0.25

static void findings_ui_start(findings_ui *u) {
  memset(u, 0, sizeof *u);
  u->next_time_print = palp_dds_now_ns() + (int64_t)30e9;
  u->shown_ok = -1;
}

/* The joined phantom's exercise, looked for by the haptic loop's main thread once a turn until it is
 * found, every EXERCISE_LOOK_S after EXERCISE_WAIT_S since t0 [ns]: 1 found and told, 0 none yet. Looked for in the loop, not before it: the haptic thread reads the device and sends its
 * contact samples from its start, and only this loop feeds it the server's local models. Waiting
 * here first (up to 1 s on every phantom without an exercise) let the server deform the phantom
 * under the finger while the device rendered 0 N, the force fading in a second late (session 77). */
static int findings_ui_exercise(findings_ui *u, const opts *o, palp_cli_station *st, const palp_cli_input *in,
                                const palp_Phantom *ph, double tip_radius, double physics_hz, int64_t t0) {
  const int64_t now = palp_dds_now_ns();
  const int late = now - t0 >= (int64_t)(EXERCISE_WAIT_S * 1e9);
  if (late && now < u->next_exercise_look_ns) return 0;
  u->next_exercise_look_ns = now + (int64_t)(EXERCISE_LOOK_S * 1e9);
  palp_Exercise ex;
  if (palp_cli_station_exercise(st, st->phantom_id, 0, &ex) != 1) return 0;
  u->exercise = 1;
  u->time_limit = ex.time_limit;
  /* the device's display names the band a press is in, as the assessment grades it */
  palp_band band[PALP_BAND_COUNT];
  const int banded = palp_dds_exercise_bands(&ex, band);
  if (in->bands && banded) in->bands(in->ctx, band);
  /* ... and the trainee is told how much of the dome was covered in each band */
  const uint32_t nv = ph->rest._length;
  double *rest = banded && nv ? malloc(sizeof *rest * 3 * nv) : NULL;
  if (rest) {
    for (uint32_t i = 0; i < nv; i++)
      rest[3 * i] = ph->rest._buffer[i].x, rest[3 * i + 1] = ph->rest._buffer[i].y, rest[3 * i + 2] = ph->rest._buffer[i].z;
    int rc;
    u->cov = palp_coverage_create(rest, (int)nv, ph->triangles._buffer, (int)(ph->triangles._length / 3),
                                  ph->dome_triangle_count, &rc);
    if (u->cov && st->finger_sample_r > 0)
      u->touched = palp_coverage_create(rest, (int)nv, ph->triangles._buffer, (int)(ph->triangles._length / 3),
                                        ph->dome_triangle_count, &rc);
    free(rest);
    memcpy(u->band, band, sizeof u->band);
    u->dome_radius = ph->radius;
    u->tip_radius = tip_radius;
    u->sample_every = palp_assess_sample_every(physics_hz, PALP_ASSESS_SAMPLE_HZ);
    u->physics_hz = physics_hz;
    u->join_asked_ns = st->join_asked_ns;
  }
  if (!o->quiet) {
    tprintf(o, "[trainee %s] exercise \"%s\": %s\n[trainee %s] %s\n[trainee %s] time limit %.0f s; mark a lump with the "
               "device's button (keyboard: m), withdraw the last mark with u\n",
               o->name, ex.name, ex.title, o->name, ex.instructions, o->name, ex.time_limit);
    /* The pressure levels the exercise grades by, in its own terms: the fingertip's depth below
     * the undeformed skin (the finger keyboard's status line shows it) and/or the force. */
    char lv[256] = "";
    size_t n = 0;
    for (int b = 0; b < 3 && n < sizeof lv; b++) {
      const palp_PressureBand *B = &ex.bands[b];
      n += (size_t)snprintf(lv + n, sizeof lv - n, "%s%s", b ? ", " : "", palp_band_name(b));
      if (B->has_depth && n < sizeof lv)
        n += (size_t)snprintf(lv + n, sizeof lv - n, " %g-%g mm deep", B->depth_min * 1e3, B->depth_max * 1e3);
      if (B->has_force && n < sizeof lv)
        n += (size_t)snprintf(lv + n, sizeof lv - n, " %g-%g N", B->force_min, B->force_max);
    }
    tprintf(o, "[trainee %s] pressure levels graded (the fingertip below the undeformed skin): %s\n", o->name, lv);
    if (late) /* what the station shows of it (coverage) counts from here; the server's grading from the join */
      tprintf(o, "[trainee %s] (the exercise reached this station %.1f s into the session; the coverage shown "
                 "here counts from now; the server grades the whole session)\n", o->name, (double)(now - t0) * 1e-9);
  }
  fflush(stdout);
  return 1;
}

static void findings_ui_tick(findings_ui *u, const opts *o, palp_cli_station *st, int button,
                             const palp_cli_haptic_view *v) {
  if (button == PALP_CLI_BUTTON_MARK) {
    /* Refused here, not sent: a mark needs a contact point, which exists only while
     * the fingertip touches the phantom. */
    if (v->on && (v->flags & PALP_HAPTIC_CONTACT) && !v->model_contact)
      tprintf(o, "[trainee %s] mark refused here: the server has sent no contact model for over %.2f s, so where "
                 "the fingertip touches is not known (its force fades out); mark again once the force is back\n",
              o->name, palp_haptic_default_def().stale_time);
    else if (!v->on || !v->model_contact)
      tprintf(o, "[trainee %s] mark refused here: the fingertip is not touching the phantom\n", o->name);
    else if (u->nsent >= UI_MARKS)
      tprintf(o, "[trainee %s] mark refused here: %d marks standing\n", o->name, u->nsent);
    else {
      const int id = palp_cli_station_mark(st, v->point, v->model_time);
      if (id > 0) {
        u->sent[u->nsent++] = (uint32_t)id;
        if (!o->quiet)
          tprintf(o, "[trainee %s] mark %d sent at (%.1f, %.1f, %.1f) mm\n", o->name, id, v->point.x * 1e3,
                     v->point.y * 1e3, v->point.z * 1e3);
      }
    }
  } else if (button == PALP_CLI_BUTTON_WITHDRAW) {
    if (u->nsent == 0)
      tprintf(o, "[trainee %s] no mark to withdraw\n", o->name);
    else if (palp_cli_station_withdraw(st, u->sent[u->nsent - 1]) == 0) {
      if (!o->quiet) tprintf(o, "[trainee %s] withdrawing mark %u\n", o->name, u->sent[u->nsent - 1]);
      u->nsent--;
    }
  }
  palp_FindingStatus fs;
  const int have_status = palp_cli_station_finding_status(st, &fs) == 1;
  if (have_status && fs.last_mark_id) {
    /* Each answer once (the server refreshes the status every half second). */
    if (fs.last_mark_id != u->shown_id || (int)fs.last_accepted != u->shown_ok || fs.marks != u->shown_marks) {
      u->shown_id = fs.last_mark_id, u->shown_ok = fs.last_accepted, u->shown_marks = fs.marks;
      /* The station numbers its marks 1, 2, ...: an answer to a higher id answers another writer's
       * finding in this session's partition (an unsecured classroom), not hers; said once, and none
       * of her marks is taken back for it. */
      if (fs.last_mark_id >= st->next_mark_id) {
        if (!u->said_stranger)
          tprintf(o, "[trainee %s] the server answered finding %u, which this station did not send: someone else "
                     "writes findings into this session (your trainee page in palp-web, or another program: is the "
                     "classroom unsecured?); its answer: %s; your next mark takes a higher number\n",
                  o->name, fs.last_mark_id, fs.last_accepted ? "accepted" : fs.reason);
        u->said_stranger = 1;
        /* The server refuses an id already made in the session: her next mark takes a higher one (until
         * 2026-12-07 her station's next mark after her palp-web page's mark 2 was mark 2, refused). */
        if (fs.last_mark_id < PALP_DDS_MARK_ID_FOLLOW_MAX) st->next_mark_id = fs.last_mark_id + 1;
      } else if (!fs.last_accepted) {
        tprintf(o, "[trainee %s] the server refused finding %u: %s\n", o->name, fs.last_mark_id, fs.reason);
        if (u->nsent && u->sent[u->nsent - 1] == fs.last_mark_id) u->nsent--;
      } else if (!o->quiet)
        tprintf(o, "[trainee %s] finding %u accepted: %u mark%s standing\n", o->name, fs.last_mark_id, fs.marks,
                   fs.marks == 1 ? "" : "s");
    }
  }
  /* The time left every 30 s from the server's status, which it publishes from the session's
   * start: until 2026-12-05 this waited for a first mark's answer, and a trainee searching for
   * two minutes before marking was told nothing. */
  if (have_status && u->exercise && !o->quiet && palp_dds_now_ns() >= u->next_time_print) {
    char cov[96];
    if (u->cov) tprintf(o, "[trainee %s] %.0f s left; covered so far: %s\n", o->name, fs.time_left,
                        findings_ui_coverage(u, cov, sizeof cov));
    else tprintf(o, "[trainee %s] %.0f s left\n", o->name, fs.time_left);
    u->next_time_print = palp_dds_now_ns() + (int64_t)30e9;
  }
  fflush(stdout);
}

static void findings_ui_end(findings_ui *u, const opts *o, palp_cli_station *st) {
  (void)st;
  if (!o->quiet && (u->exercise || u->nsent))
    tprintf(o, "[trainee %s] %d mark%s standing at the end\n", o->name, u->nsent, u->nsent == 1 ? "" : "s");
  if (!o->quiet && u->cov) {
    char cov[96];
    if (u->samples)
      tprintf(o, "[trainee %s] you covered %s of the dome (counted as the instructor's review counts it, from the "
                 "triangles you touched; the review also shows which lumps you found)\n", o->name,
                 findings_ui_coverage(u, cov, sizeof cov));
    else
      tprintf(o, "[trainee %s] you covered %s of the dome (the instructor's review counts it from the triangles "
                 "you touched, a few points either way, and shows which lumps you found)\n", o->name,
                 findings_ui_coverage(u, cov, sizeof cov));
    if (u->samples && (u->samples_lost || u->samples_bad))
      tprintf(o, "[trainee %s] %llu of the server's samples of your touches were lost on the way (%.1f s of the "
                 "exercise) and %llu refused as malformed: the review, which has them all, may count more than told "
                 "here\n", o->name, (unsigned long long)u->samples_lost,
                 (double)u->samples_lost * (double)u->sample_step / u->physics_hz, (unsigned long long)u->samples_bad);
    else if (!u->samples && u->sampled_lost)
      tprintf(o, "[trainee %s] %llu of the steps the review samples reached this station too late to be counted "
                 "(%.1f s of the exercise; its machine was busy): the review may count more than told here\n",
                 o->name, (unsigned long long)u->sampled_lost,
                 (double)u->sampled_lost * (double)u->sample_every / u->physics_hz);
  }
  palp_coverage_destroy(u->cov);
  palp_coverage_destroy(u->touched);
  u->cov = u->touched = NULL;
}

/* What the trainee's marks found, as the server told it at the session's end (palp_debrief,
 * docs/assessment.md "Debrief"): as much as the exercise lets her know. The server writes it as
 * the session closes: at once after its time limit, or as this station's LEAVE reaches it. */
#define DEBRIEF_WAIT_S 3.0
/* Returns the level told (palp_DebriefLevel), -1 when none was. */
static int print_debrief(const opts *o, palp_cli_station *st) {
  if (st->debrief_topic_refused) {
    tprintf(o, "[trainee %s] no debrief: this identity's permissions predate it (the instructor re-issues them with "
               "make-classroom-pki.sh DIR init); the instructor's review shows which lumps you found\n", o->name);
    return -1;
  }
  palp_Debrief d;
  palp_DebriefLesion les[PALP_DEBRIEF_MAX_LESIONS];
  char err[160];
  const int rc = palp_cli_station_debrief(st, DEBRIEF_WAIT_S, &d, les, err, sizeof err);
  if (rc == PALP_CLI_ESTOPPED) return -1; /* stopped again while it waited: the user is going */
  if (rc < 0) {
    palp_log_warn(o->log, "%s", err);
    return -1;
  }
  if (rc == 0) {
    tprintf(o, "[trainee %s] no debrief came from the server within %.0f s; the instructor's review shows which "
               "lumps you found\n", o->name, DEBRIEF_WAIT_S);
    return -1;
  }
  if (d.level == palp_DEBRIEF_NONE) {
    tprintf(o, "[trainee %s] debrief: this exercise keeps its lumps for the instructor's review (%u mark%s standing)\n",
               o->name, d.marks, d.marks == 1 ? "" : "s");
    return (int)d.level;
  }
  char extra[64] = "";
  if (d.duplicates) snprintf(extra, sizeof extra, ", %u on a lump already found", d.duplicates);
  /* an exercise whose lumps are drawn for each session may hide none (docs/assessment.md) */
  char found[64];
  if (d.lesions) snprintf(found, sizeof found, "found %u of %u lump%s", d.found, d.lesions, d.lesions == 1 ? "" : "s");
  else snprintf(found, sizeof found, "had no lump to find this time");
  tprintf(o, "[trainee %s] debrief: you %s with %u mark%s standing; %u mark%s near no lump%s%s\n",
             o->name, found, d.marks, d.marks == 1 ? "" : "s", d.false_marks,
             d.false_marks == 1 ? " was" : "s were", extra,
             d.level == palp_DEBRIEF_COUNT ? " (this exercise does not say where its lumps are: the instructor's "
                                             "review does)" : "");
  for (uint32_t i = 0; i < d.lesion._length; i++) {
    const palp_DebriefLesion *l = &les[i];
    const palp_vec3 p = {l->point.x, l->point.y, l->point.z};
    char by[32] = "MISSED";
    if (l->found_by) snprintf(by, sizeof by, "found by mark %u", l->found_by);
    /* where, in the one phrase every palp tool uses (palp_place_words: no clock at the pole; "along the
     * skin" after the arc until session 83, which the review's debrief line did not say) */
    char at[64];
    palp_place_words(p, at, sizeof at);
    tprintf(o, "[trainee %s]   lump %u %s: %s; %.0f mm across, its centre %.0f mm deep\n", o->name, i + 1, by, at,
            l->diameter * 1e3, l->depth * 1e3);
  }
  return (int)d.level;
}

/* A practice exercise's score (palp_debrief_score, session 64): after a debrief that told the
 * lesions, the server grades the session from its log as the review does and tells her the score,
 * and what to work on in her words (palp_metric_to_work_on, which her web page is sent too). The
 * grader has it milliseconds after the close is logged; a slow disk may take seconds. */
#define SCORE_WAIT_S 5.0
static void print_debrief_score(const opts *o, palp_cli_station *st) {
  if (st->debrief_score_topic_refused) {
    tprintf(o, "[trainee %s] no score: this identity's permissions predate it (the instructor re-issues them with "
               "make-classroom-pki.sh DIR init); the instructor's review scores the session\n", o->name);
    return;
  }
  palp_SessionScore m;
  char err[160];
  const int rc = palp_cli_station_debrief_score(st, SCORE_WAIT_S, &m, err, sizeof err);
  if (rc == PALP_CLI_ESTOPPED) return;
  if (rc < 0) {
    palp_log_warn(o->log, "%s", err);
    return;
  }
  if (rc == 0) {
    tprintf(o, "[trainee %s] no score came from the server within %.0f s; the instructor's review scores the session\n",
            o->name, SCORE_WAIT_S);
    return;
  }
  char text[640];
  tprintf(o, "[trainee %s] %s\n", o->name, palp_cli_score_text(&m, text, sizeof text));
}

/* The valid range's four limits in the words every tool uses (docs/naming.md): the announcement,
 * the summary, and the instructor's review of the session's log (client/review/review_util.c). */
static const char *const valid_range_text[4] = {
    "pressed deeper than this place of the phantom was checked against the reference model",
    "the skin is stretched or bent beyond what the model describes well",
    "the phantom is pressed onto its base or harder than the model can follow",
    "the gel's literal pressure law stepped outside its stable range"};

/* What the server's validity flags said, in the trainee's words, into buf (why: bit 1 the
 * fingertip deeper than the phantom's forces were checked against the FE there,
 * LM_BEYOND_VALIDATED; bit 2 a link or the skin's bending beyond the model's own linear
 * range, LM_LARGE_STRAIN; bit 4 pressed onto the base, or a step the model could not follow,
 * LM_BASE_CONTACT / LM_CLAMPED_STEP / LM_UNSOLVED; bit 8 the scene's literal gel law outside its
 * stable range, LM_GEL_LAW_RANGE). */
static const char *valid_range_why(int why, char *buf, size_t len) {
  size_t n = 0;
  buf[0] = 0;
  for (int b = 0; b < 4; b++)
    if (why & (1 << b))
      n += (size_t)snprintf(buf + n, n < len ? len - n : 0, "%s%s", n ? "; " : "", valid_range_text[b]);
  if (!buf[0]) snprintf(buf, len, "the phantom is deformed beyond where its forces were validated");
  return buf;
}

/* A stall of this process (palp_cli_station_session_closed saw one): the trainee is told, since the hand
 * felt nothing for that long and the server may have held the session; and that the station asked the
 * server to go on only when it did (the server's state said it held the session: the JOIN sent again).
 * Until session 83 every stall said "asked the server to go on", whether anything was sent or not. */
static void report_stall(const opts *o, const palp_cli_station *st, unsigned seen[4], const char *role, int named) {
  const char *sep = named && o->name ? " " : "", *name = named && o->name ? o->name : "";
  if (st->stalls != seen[0] && !o->quiet)
    printf("[%s%s%s] this station did not run for %.2f s (its machine was busy)\n", role, sep, name, st->stall_s);
  if (st->held_asks != seen[2] && !o->quiet)
    printf("[%s%s%s] the server held session %u, not having heard from this station; asked it to go on\n", role, sep,
           name, st->session_id);
  /* the server's lease lapsed and it came back (it did not run for a while) */
  if (st->server_returns != seen[1] && !o->quiet)
    printf("[%s%s%s] the server was silent past its lease (its machine was busy) and is back; session %u goes on\n",
           role, sep, name, st->session_id);
  /* a viewer: its JOIN again, in case the server dropped it (station.h, next_viewer_ask_ns) */
  if (st->viewer_asks != seen[3] && !o->quiet)
    printf("[%s%s%s] asked the server again to stream session %u to this station (it may have dropped it: %s)\n", role,
           sep, name, st->session_id, st->stalls != seen[0] ? "this station did not run" : "its state counted no viewer like it");
  seen[0] = st->stalls, seen[1] = st->server_returns, seen[2] = st->held_asks, seen[3] = st->viewer_asks;
  fflush(stdout);
}

/* The server's session log lost records while this session runs, or writes again (session 68): the
 * trainee is told at her station, since her session will be incomplete in the instructor's review.
 * Said even with --quiet, as the lost goodbye is: it is not progress but the record of her work. */
static void report_log(const opts *o, palp_cli_station *st, const char *role, int named) {
  char line[320];
  if (!palp_cli_station_log_news(st, line, sizeof line)) return;
  const char *sep = named && o->name ? " " : "", *name = named && o->name ? o->name : "";
  printf("[%s%s%s] %s\n", role, sep, name, line);
  fflush(stdout);
}

/* Samples another participant wrote into the session, dropped (palp_cli_station_from_server): the user
 * is told once, in the station's words, and the log names the participant. Said even with --quiet: what
 * she felt and was told may have been meant to mislead her, and her instructor should know. */
static void report_foreign(const opts *o, palp_cli_station *st, const char *role, int named) {
  char line[400], who[64];
  if (!palp_cli_station_foreign_news(st, line, sizeof line, who, sizeof who)) return;
  const char *sep = named && o->name ? " " : "", *name = named && o->name ? o->name : "";
  tprintf(o, "[%s%s%s] %s\n", role, sep, name, line);
  fflush(stdout);
  palp_log_warn(o->log, "session %u: samples of its server's topics from %s, not its server (the participant that "
                        "accepted the join), ignored; further ones are counted", st->session_id, who);
}

/* Samples of this session the server refused (SessionState.rejected_samples rose): the trainee is
 * told at once and then at most every 10 s while it rises, even with --quiet (her presses may be
 * reaching nothing: a --finger-radius outside the server's range was refused sample by sample while
 * the station said nothing, session 81). The server's log names each refusal's reason. */
#define REJECTED_SAY_INTERVAL_NS 10000000000LL
/* sent: the contact samples this station sent in the session so far. The server's count is of every
 * writer's samples in the session: more than she sent are another writer's (a peer of an unsecured
 * classroom, or a station whose server restarted under her session's id: hana was told of 9 refused
 * while she had sent none, session 83 review). */
static void report_rejected(const opts *o, palp_cli_station *st, const char *role, int named, uint64_t sent) {
  const int64_t now = palp_dds_now_ns();
  if (st->rejected_samples <= st->rejected_said ||
      (st->rejected_said_ns && now - st->rejected_said_ns < REJECTED_SAY_INTERVAL_NS))
    return;
  const char *sep = named && o->name ? " " : "", *name = named && o->name ? o->name : "";
  char radius[64] = "";
  if (o->finger_radius_mm > 0) snprintf(radius, sizeof radius, " (this station's is %g mm)", o->finger_radius_mm);
  char whose[96] = "";
  if (sent == 0)
    snprintf(whose, sizeof whose, " (this station sent none: another writer's)");
  else if (st->rejected_samples > sent)
    snprintf(whose, sizeof whose, " (more than the %llu this station sent: some are another writer's)", (unsigned long long)sent);
  tprintf(o, "[%s%s%s] the server refused %llu contact sample%s of session %u so far%s: they reach nothing. Its log "
             "says why: a finger radius outside its range%s, a force above its limit, or a writer not of this "
             "session\n",
          role, sep, name, (unsigned long long)st->rejected_samples, st->rejected_samples == 1 ? "" : "s",
          st->session_id, whose, radius);
  fflush(stdout);
  palp_log_warn(o->log, "session %u: the server refused %llu contact samples so far", st->session_id,
                (unsigned long long)st->rejected_samples);
  st->rejected_said = st->rejected_samples;
  st->rejected_said_ns = now;
}

/* The words before a closed session's reason in a summary line: the server's close (closed_words), or
 * "; session ended: " for the station's own verdict that the server was lost (palp_cli_station_session_closed
 * composes those reasons, "server lost (...)"): the server did not close that session, its station gave
 * it up (the trainee's said "session closed by the server: server lost" until session 83). */
static int server_lost(const char *reason) { return !strncmp(reason, "server lost", 11); }
static const char *close_words(const char *reason, const char *closed_words) {
  return server_lost(reason) ? "; session ended: " : closed_words;
}

/* The summary lines' count of those: "" when none. */
static const char *foreign_summary(const palp_cli_station *st, char *buf, size_t len) {
  buf[0] = 0;
  if (st->bind.ignored)
    snprintf(buf, len, "; %llu sample%s from participants other than its server ignored",
             (unsigned long long)st->bind.ignored, st->bind.ignored == 1 ? "" : "s");
  return buf;
}

static int run_haptic_trainee(const opts *o, palp_cli_station *st, const palp_Phantom *ph, palp_cli_input in) {
  int rc;
  /* A position-driven trainee does not rejoin: its haptic thread renders one session's local models
   * (review s83 #12: it ended with exit 3 on a lost server without a word about --rejoin). */
  if (o->rejoin)
    palp_log_warn(o->log, "--rejoin is for force-driven trainees: input %s does not rejoin; a lost server ends "
                          "this session (exit 3)", in.name);
  if (in.open && (rc = in.open(in.ctx, ph->radius)) < 0) {
    const char *why = in.error ? in.error(in.ctx) : NULL;
    palp_log_error(o->log, "input %s: cannot open: %s", in.name, why ? why : palp_strerror(rc));
    if (in.close) in.close(in.ctx);
    return 1;
  }
  if (!st->local_model_r) {
    palp_log_error(o->log, "no palp_local_model reader: the session was joined without feedback");
    if (in.close) in.close(in.ctx);
    return 1;
  }
  palp_cli_haptic_def d = palp_cli_haptic_default_def();
  if (o->haptic_rate > 0) d.rate_hz = o->haptic_rate;
  d.physics_rate_hz = st->tick_rate_hz > 0 ? st->tick_rate_hz : ph->tick_rate_hz;
  d.rt_priority = o->rt_priority;
  if (o->max_force > 0) d.render.max_force = o->max_force;
  d.phantom_max_force = ph->max_force;
  d.in = &in;
  d.contact_w = st->contact_w;
  d.session_id = st->session_id;
  d.duration = o->duration;
  d.timer_floor = 1; /* the late ticks are printed beside this machine's own floor */
  findings_ui fu;
  findings_ui_start(&fu);
  d.on_model = findings_ui_model; /* fu's coverage: NULL until findings_ui_exercise makes it */
  d.on_model_ctx = &fu;
  FILE *trace = NULL;
  if (o->trace_csv) {
    trace = fopen(o->trace_csv, "w");
    /* Bounded: at most 120 s of ticks are kept for the file. */
    d.trace_cap = (size_t)(d.rate_hz * 120);
    d.trace = trace ? calloc(d.trace_cap, sizeof *d.trace) : NULL;
    if (!trace || !d.trace) {
      palp_log_error(o->log, "cannot write %s", o->trace_csv);
      if (trace) fclose(trace);
      if (in.close) in.close(in.ctx);
      return 1;
    }
  }
  palp_cli_haptic_loop *hl = calloc(1, sizeof *hl);
  char err[256];
  if (!hl || palp_cli_haptic_start(hl, &d, err, sizeof err) < 0) {
    palp_log_error(o->log, "%s", hl ? err : "out of memory");
    free(hl);
    free(d.trace);
    if (trace) fclose(trace);
    if (in.close) in.close(in.ctx);
    return 1;
  }
  if (o->rt_priority > 0 && !hl->stats.rt_ok) {
    if (o->rt_priority_given)
      palp_log_warn(o->log, "--rt-priority %d: SCHED_FIFO refused; the haptic thread runs at normal priority",
                    o->rt_priority);
    else /* the default: said once, with what to do about it */
      palp_log_info(o->log, "the haptic thread runs at normal priority (SCHED_FIFO %d refused: allow it with an "
                            "rtprio limit, e.g. LimitRTPRIO=50 or limits.conf, or pass --rt-priority 0); its ticks "
                            "are likelier to be late", o->rt_priority);
  }
  /* The contact samples go every `every` ticks: the physics rate when it divides the haptic rate, else
   * the nearest such rate, said (until session 90 the summary gave the physics rate: a 600 Hz phantom was
   * "sent at 600 Hz" at 500; found by review) */
  const long every = palp_cli_contact_every(d.rate_hz, d.physics_rate_hz);
  const double sent_hz = d.rate_hz / (double)every;
  char sent_note[96] = "";
  if (fabs(sent_hz - d.physics_rate_hz) > 0.01 * d.physics_rate_hz)
    snprintf(sent_note, sizeof sent_note, ": %.0f a second, the nearest the %.0f Hz haptic rate divides into", sent_hz,
             d.rate_hz);
  if (!o->quiet)
    tprintf(o, "[trainee %s] haptic thread at %.0f Hz; the server steps the phantom at %.0f Hz (a contact sample every "
               "%ld ticks%s); safe force %.1f N\n", o->name, d.rate_hz, d.physics_rate_hz, every, sent_note,
               hl->core.renderer.def.max_force);
  fflush(stdout);
  feedback_ctx plot = {.st = st, .in = &in, .t0 = palp_dds_now_ns(), .max_force = hl->core.renderer.def.max_force};
  latency lat = {0};
  uint64_t bad = 0, models = 0;
  dds_entity_t ws = dds_create_waitset(st->pp);
  dds_entity_t lm_cond = dds_create_readcondition(st->local_model_r, DDS_ANY_STATE);
  dds_waitset_attach(ws, lm_cond, 0);
  const int64_t t0 = palp_dds_now_ns();
  int64_t next_print = t0, next_check = t0;
  unsigned stalls_seen[4] = {0, 0, 0, 0};
  int closed = 0;
  palp_cli_episode lim_ep = palp_cli_episode_make(PALP_CLI_LIMIT_HOLD_S);
  palp_cli_episode oor_ep = palp_cli_episode_make(PALP_CLI_RANGE_HOLD_S);
  double episode_peak = 0;
  uint64_t oor_ticks = 0, bv_ticks = 0, strain_ticks = 0, lim_ticks = 0, gel_ticks = 0;
  int oor_why = 0; /* the limits met in this episode (valid_range_why) */
  char why_text[320];
  char reason[128] = "";
  int exercise_found = 0;
  while (!g_stop && !palp_cli_haptic_done(hl)) {
    dds_waitset_wait(ws, NULL, 0, DDS_MSECS(20));
    tick_refusals(o);
    /* before the models are fed: those of the turn the exercise is found count in its coverage */
    if (!exercise_found)
      exercise_found = findings_ui_exercise(&fu, o, st, &in, ph, hl->def.radius, d.physics_rate_hz, t0) != 0;
    double lat_us;
    int n = palp_cli_haptic_feed(hl, st, &bad, &lat_us);
    findings_ui_samples(&fu, st, hl->def.finger);
    models += (uint64_t)(n > 0 ? n : 0);
    if (n > 0 && isfinite(lat_us)) lat_add(&lat, lat_us);
    if (st->feedback_r > 0) { /* the summary topic is not needed here: keep its queue empty */
      void *ptr[8] = {NULL};
      dds_sample_info_t info[8];
      int k = dds_take(st->feedback_r, ptr, info, 8, 8);
      if (k > 0) dds_return_loan(st->feedback_r, ptr, k);
    }
    palp_cli_haptic_view v;
    palp_cli_haptic_get_view(hl, &v);
    /* the lines' t: the world time of the model the haptic thread renders (v.t is its own clock) */
    const int have_world = v.model_time > 0;
    const double fm = sqrt(v.force.x * v.force.x + v.force.y * v.force.y + v.force.z * v.force.z);
    const int64_t now = palp_dds_now_ns();
    int bin = (int)((double)(now - plot.t0) * 1e-9 / PLOT_BIN_S);
    if (bin >= 0 && bin < PLOT_BINS) {
      if (fm > plot.plot[bin]) plot.plot[bin] = fm;
      if (bin + 1 > plot.plot_bins) plot.plot_bins = bin + 1;
    }
    if (fm > plot.peak) plot.peak = fm;
    /* The trainee is told at once when the force on her hand was limited, and that it is back
     * under the limit once it has stayed there 0.25 s: a press held at the limit dips under it
     * for a tick now and then, which made the two lines alternate 20 ms apart (episode.h). */
    const int limited = (v.flags & PALP_CLI_FORCE_LIMITED) != 0;
    if (limited && v.requested > episode_peak) episode_peak = v.requested;
    const int lim = palp_cli_episode_update(&lim_ep, v.t, limited);
    if (lim == PALP_CLI_EPISODE_BEGAN && !o->quiet) {
      /* which limit acted: the safe force, or (asking no more than it) the stiffness this station renders
       * (palp_haptic.h). Until session 90 both figures were the rendered force: a stiffness-limited press
       * at 0.4 N read "harder than the safe 0.4 N" with a safe force of 10 N (found by review). */
      const palp_haptic_def *rd = &hl->core.renderer.def;
      if (v.requested > rd->max_force)
        tprintf(o, "[trainee %s] t=%6.2f s  FORCE LIMITED: the phantom pushes back harder than the safe %.1f N (it "
                   "asks %.2f N); your device gets %.1f N\n", o->name, v.model_time, rd->max_force, v.requested, fm);
      else
        tprintf(o, "[trainee %s] t=%6.2f s  FORCE LIMITED: the phantom is stiffer here than this station's safe "
                   "%.0f N/m (or would push the hand on); your device gets %.2f N, rendered softer\n", o->name,
                   v.model_time, rd->max_stiffness, fm);
      fflush(stdout);
    }
    if (lim == PALP_CLI_EPISODE_OVER && !o->quiet) {
      /* it cleared PALP_CLI_LIMIT_HOLD_S ago on the haptic clock: the world then, a model's step before or after */
      tprintf(o, "[trainee %s] t=%6.2f s  force back under the limit (the phantom asked up to %.2f N)\n", o->name,
                 fmax(0.0, v.model_time - (v.t - lim_ep.clear_since)), episode_peak);
      fflush(stdout);
    }
    if (!lim_ep.shown) episode_peak = 0;
    /* And when the phantom is pressed beyond the model's valid range (the server's flag on
     * the models rendered since the last look), and when it is back: after 0.5 s clear, so
     * that the skin's check, which revisits each hinge every 0.2 s, does not make it flicker. */
    const int oor = v.out_of_range_ticks != oor_ticks;
    /* which limit: the trainee can act on "too deep here", not on "out of range" */
    const int why = (v.beyond_validated_ticks != bv_ticks ? 1 : 0) | (v.strained_ticks != strain_ticks ? 2 : 0) |
                    (v.limit_ticks != lim_ticks ? 4 : 0) | (v.gel_ticks != gel_ticks ? 8 : 0);
    oor_ticks = v.out_of_range_ticks, bv_ticks = v.beyond_validated_ticks;
    strain_ticks = v.strained_ticks, lim_ticks = v.limit_ticks, gel_ticks = v.gel_ticks;
    const int out = palp_cli_episode_update(&oor_ep, v.t, oor);
    if (out == PALP_CLI_EPISODE_BEGAN) {
      oor_why = 0;
      if (!o->quiet) {
        tprintf(o, "[trainee %s] t=%6.2f s  OUTSIDE THE MODEL'S VALID RANGE: %s; what you feel here is less certain\n",
                   o->name, v.model_time, valid_range_why(why, why_text, sizeof why_text));
        fflush(stdout);
      }
    }
    if (oor) oor_why |= why;
    if (out == PALP_CLI_EPISODE_OVER && !o->quiet) {
      tprintf(o, "[trainee %s] t=%6.2f s  back inside the model's valid range (outside for %.2f s: %s)\n", o->name,
                 v.model_time,
                 oor_ep.last_on - oor_ep.began, valid_range_why(oor_why, why_text, sizeof why_text));
      fflush(stdout);
    }
    if (o->print_period > 0 && !o->quiet && now >= next_print && have_world) {
      const int touching = v.on && (v.flags & PALP_CLI_FORCE_CONTACT);
      tprintf(o, "[trainee %s] t=%6.2f s  finger %s  device %5.1f mm below the proxy  rendered |F| = %5.2f N%s%s%s\n",
                 o->name, v.model_time, !v.on ? "lifted  " : touching ? "touching" : "free    ", touching ? v.depth * 1e3 : 0.0, fm,
                 limited ? "  LIMITED" : "", (v.flags & PALP_CLI_FORCE_OUT_OF_RANGE) ? "  OUTSIDE VALID RANGE" : "",
                 (v.flags & PALP_CLI_FORCE_STALE) ? "  (server silent: fading out)" : "");
      fflush(stdout);
      next_print += (int64_t)(o->print_period * 1e9);
      if (next_print <= now) next_print = now + (int64_t)(o->print_period * 1e9); /* after a wait for the world's time */
    }
    findings_ui_tick(&fu, o, st, in.button ? in.button(in.ctx) : 0, &v);
    if (now >= next_check) {
      if (palp_cli_station_session_closed(st, reason, sizeof reason)) {
        closed = 1;
        break;
      }
      report_stall(o, st, stalls_seen, "trainee", 1);
      report_log(o, st, "trainee", 1);
      report_foreign(o, st, "trainee", 1);
      report_rejected(o, st, "trainee", 1, atomic_load_explicit(&hl->sent, memory_order_relaxed));
      next_check = now + 100000000;
    }
  }
  findings_ui_end(&fu, o, st);
  dds_delete(lm_cond);
  dds_delete(ws);
  palp_cli_haptic_stats hs;
  /* The loop's last look is a check: what follows (the join, a trace of up to 120 s of ticks, the
   * summary) is this station's own work, marked as such below, so that the leave does not take a slow
   * shutdown for a stall (its careful path: the JOIN again, the LEAVE repeated for 1 s, and "did not
   * answer ... after this station's stall" from a busy server; until session 90, found by review). */
  palp_cli_station_alive(st);
  palp_cli_haptic_join(hl, &hs);
  int out_failed = 0;
  if (trace) {
    fprintf(trace, "t_s,late_s,on,x_m,y_m,z_m,fx_N,fy_N,fz_N,requested_N,flags\n");
    for (size_t i = 0; i < hs.trace_len; i++) {
      const palp_cli_haptic_sample *q = &d.trace[i];
      fprintf(trace, "%.6f,%.6f,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%u\n", q->t, q->late, q->on, q->x.x, q->x.y,
              q->x.z, q->f.x, q->f.y, q->f.z, q->requested, q->flags);
    }
    out_failed = close_output(o, trace, o->trace_csv) < 0;
    palp_cli_station_alive(st);
    if (hs.ticks > hs.trace_len) /* its buffer holds d.trace_cap ticks (until session 90 cut without a word) */
      tprintf(o, "[trainee %s] %s holds the first %.1f s of the %.1f s the haptic loop ran (%zu of %llu ticks)\n",
              o->name, o->trace_csv, (double)hs.trace_len / d.rate_hz, (double)hs.ticks / d.rate_hz, hs.trace_len,
              (unsigned long long)hs.ticks);
  }
  if (hs.failed) palp_log_error(o->log, "%s", hs.error);
  if (in.close) in.close(in.ctx);
  double p50 = NAN, p99 = NAN;
  if (lat.n) {
    qsort(lat.us, lat.n, sizeof *lat.us, cmp_double);
    p50 = lat.us[(lat.n - 1) / 2];
    p99 = lat.us[(size_t)((double)(lat.n - 1) * 0.99)];
  }
  /* Deadlines a late wake-up skipped got no force update at all (the device held its last
   * force): said beside the late ticks, which count wake-ups, not the time they lost. */
  report_foreign(o, st, "trainee", 1); /* samples that came after the loop's last look */
  char skipped[96] = "", foreign[96];
  if (hs.missed)
    snprintf(skipped, sizeof skipped, ", %llu deadline(s) skipped (the device held its last force)",
             (unsigned long long)hs.missed);
  tprintf(o, "[trainee %s] session %u: haptic loop %llu ticks at %.0f Hz, %llu late by > %.1f ms (%.3f%%, worst %.2f ms)%s; "
             "%llu local models (%llu dropped as invalid), %llu contact samples sent at %.0f Hz; contact->model latency "
             "p50 %.0f us p99 %.0f us; peak rendered force %.2f N%s%s%s\n",
             o->name, st->session_id, (unsigned long long)hs.ticks, d.rate_hz, (unsigned long long)hs.late_ticks,
             d.late_threshold * 1e3, hs.ticks ? 100.0 * (double)hs.late_ticks / (double)hs.ticks : 0.0, hs.late_max * 1e3,
             skipped,
             (unsigned long long)hs.models, (unsigned long long)bad, (unsigned long long)hs.contacts_sent,
             sent_hz, p50, p99, hs.peak_force, foreign_summary(st, foreign, sizeof foreign),
             closed ? close_words(reason, "; session closed by the server: ") : "", closed ? reason : "");
  /* what was counted and never said until session 90 (found by review) */
  if (hs.contacts_dropped || hs.contacts_failed)
    tprintf(o, "[trainee %s] %llu contact sample(s) not sent: %llu found the sender's queue full (its thread starved), "
               "%llu refused by DDS; the server held the last position it had\n", o->name,
               (unsigned long long)(hs.contacts_dropped + hs.contacts_failed), (unsigned long long)hs.contacts_dropped,
               (unsigned long long)hs.contacts_failed);
  if (hs.bad_x_ticks)
    tprintf(o, "[trainee %s] the device gave %llu reading(s) that were not numbers (NaN or infinite); the last good one "
               "stood in for each\n", o->name, (unsigned long long)hs.bad_x_ticks);
  if (hs.stalls)
    tprintf(o, "[trainee %s] this station was not run %llu time(s) for %.2f s in all (longest %.2f s: its machine was "
               "busy or it was stopped); the device's force was not updated meanwhile; not counted among the late ticks "
               "above\n", o->name, (unsigned long long)hs.stalls, hs.stall_total, hs.stall_max);
  if (hs.floor_ticks)
    tprintf(o, "[trainee %s] this machine's timer floor over the same %.1f s: a thread doing nothing at the haptic "
               "thread's priority woke > %.1f ms late on %llu of %llu ticks (%.3f%%, worst %.2f ms)\n", o->name,
               (double)(hs.floor_ticks + hs.floor_missed) / d.rate_hz, d.late_threshold * 1e3, (unsigned long long)hs.floor_late_ticks,
               (unsigned long long)hs.floor_ticks, 100.0 * (double)hs.floor_late_ticks / (double)hs.floor_ticks,
               hs.floor_late_max * 1e3);
  if (hs.limited_ticks && hs.peak_requested > hs.max_force)
    tprintf(o, "[trainee %s] FORCE LIMITED for %.3f s: the phantom asked up to %.2f N, the device got at most %.2f N\n",
               o->name, (double)hs.limited_ticks / d.rate_hz, hs.peak_requested, hs.max_force);
  else if (hs.limited_ticks) /* the stiffness alone (below): never more than the safe force asked */
    tprintf(o, "[trainee %s] FORCE LIMITED for %.3f s by the stiffness alone: the phantom asked up to %.2f N, under "
               "the safe %.2f N, rendered softer\n", o->name, (double)hs.limited_ticks / d.rate_hz, hs.peak_requested,
               hs.max_force);
  if (hs.stiffness_limited_models)
    tprintf(o, "[trainee %s] STIFFNESS LIMITED: %llu model(s) asked a stiffness above this station's %.0f N/m or one "
               "that would push the hand on; rendered limited (their seconds in contact are among the limited ones)\n",
               o->name, (unsigned long long)hs.stiffness_limited_models, d.render.max_stiffness);
  if (hs.passivity_ticks)
    tprintf(o, "[trainee %s] passivity controller: acted on %llu ticks, took out %.2f mJ the late models would have "
               "generated\n", o->name, (unsigned long long)hs.passivity_ticks, hs.passivity_dissipated * 1e3);
  /* the gel law's part only where a scene's literal law met it (most never do) */
  char gel_text[160] = "";
  if (hs.gel_ticks)
    snprintf(gel_text, sizeof gel_text, "; %.2f s %s", (double)hs.gel_ticks / d.rate_hz, valid_range_text[3]);
  if (hs.server_limited_models || hs.out_of_range_models)
    tprintf(o, "[trainee %s] the server flagged %llu models above its max_force and %llu outside the model's valid range "
               "(the device rendered those for %.2f s: %.2f s %s; %.2f s %s; %.2f s %s%s)\n", o->name,
               (unsigned long long)hs.server_limited_models, (unsigned long long)hs.out_of_range_models,
               (double)hs.out_of_range_ticks / d.rate_hz, (double)hs.beyond_validated_ticks / d.rate_hz,
               valid_range_text[0], (double)hs.strained_ticks / d.rate_hz, valid_range_text[1],
               (double)hs.limit_ticks / d.rate_hz, valid_range_text[2], gel_text);
  if (o->plot) plot_feedback_titled(&plot, stdout, "rendered |F| on the device (1 kHz haptic loop)");
  free(lat.us);
  free(d.trace);
  free(hl);
  palp_cli_station_alive(st);
  return hs.failed || out_failed ? 1 : (closed ? 3 : 0);
}

static int run_trainee(const opts *o, palp_cli_station *st, const palp_Phantom *ph, palp_cli_input in) {
  if (in.read_position && in.write_force) return run_haptic_trainee(o, st, ph, in);
  int rc;
  if (in.open && (rc = in.open(in.ctx, ph->radius)) < 0) {
    const char *why = in.error ? in.error(in.ctx) : NULL; /* the driver's own words, as the haptic path says them */
    palp_log_error(o->log, "input %s: cannot open: %s", in.name, why ? why : palp_strerror(rc));
    if (in.close) in.close(in.ctx);
    return 1;
  }
  FILE *fb_csv = o->feedback_csv ? fopen(o->feedback_csv, "w") : NULL;
  FILE *ct_csv = o->contact_csv ? fopen(o->contact_csv, "w") : NULL;
  if ((o->feedback_csv && !fb_csv) || (o->contact_csv && !ct_csv)) {
    palp_log_error(o->log, "cannot write %s", o->feedback_csv && !fb_csv ? o->feedback_csv : o->contact_csv);
    if (in.close) in.close(in.ctx);
    if (fb_csv) fclose(fb_csv);
    if (ct_csv) fclose(ct_csv);
    return 1;
  }
  if (fb_csv) fprintf(fb_csv, "t_s,frame,sim_time_s,finger,active,fx_N,fy_N,fz_N,top_displacement_m,latency_us\n");
  if (ct_csv) palp_cli_contact_csv_header(ct_csv);

  double rate = o->rate > 0 ? o->rate : (st->tick_rate_hz > 0 ? st->tick_rate_hz : 100);
  const int64_t period = (int64_t)(1e9 / rate);
  const int64_t t0 = palp_dds_now_ns();
  int64_t next = t0, next_print = t0, next_state_check = t0;
  unsigned stalls_seen[4] = {0, 0, 0, 0};
  uint64_t seq[PALP_CLI_MAX_FINGERS] = {0};
  int down[PALP_CLI_MAX_FINGERS] = {0}, release_left[PALP_CLI_MAX_FINGERS] = {0};
  uint64_t sent = 0;
  const palp_haptic_def render = palp_cli_haptic_default_def().render;
  feedback_ctx fx = {.st = st, .in = &in, .csv = fb_csv, .t0 = t0,
                     .max_force = o->max_force > 0 ? o->max_force : render.max_force,
                     .fade = render, .world_t = -1};
  /* The safe force is the smaller of the station's and the phantom's (the catalogue's max_force), as
   * on the haptic path: the server reports a finger's force above its limit as it is (session 77). */
  if (ph->max_force > 0 && isfinite(ph->max_force) && ph->max_force < fx.max_force) fx.max_force = ph->max_force;
  /* Feedback is taken as it arrives (waitset) so its receive time is exact. */
  dds_entity_t ws = dds_create_waitset(st->pp);
  dds_entity_t fb_cond = dds_create_readcondition(st->feedback_r, DDS_ANY_STATE);
  dds_waitset_attach(ws, fb_cond, 0);
  char reason[128] = "";
  int closed = 0, ended = 0, rejoins = 0, failed = 0;
  uint32_t gone_session = 0; /* a session a failed --rejoin ended (st->session_id is then 0) */
  while (!g_stop) {
    tick_refusals(o);
    int64_t now = palp_dds_now_ns();
    double t = (double)(now - t0) * 1e-9;
    if (o->duration > 0 && t >= o->duration) break;
    palp_cli_cmd cmd[PALP_CLI_MAX_FINGERS];
    /* The contacts go at --rate; the loop also wakes for the state's 100 ms checks (review s83 #6: at
     * --rate 1 every check came a second late, each taken for a stall of this station). */
    const int due = now >= next;
    int n = due ? in.poll(in.ctx, t, cmd, PALP_CLI_MAX_FINGERS) : 0;
    if (n == PALP_CLI_INPUT_END) {
      ended = 1;
      break;
    }
    if (n < 0) {
      /* the driver's own words when it has them, and a failed run's exit status (1), as on the haptic
       * path: this exited 0, saying only the error code's name (session 77) */
      const char *why = in.error ? in.error(in.ctx) : NULL;
      palp_log_error(o->log, "input %s failed: %s", in.name, why ? why : palp_strerror(n));
      failed = 1;
      break;
    }
    int want[PALP_CLI_MAX_FINGERS] = {0};
    for (int k = 0; k < n; k++) {
      const palp_cli_cmd *c = &cmd[k];
      if (c->finger < 0 || c->finger >= PALP_CLI_MAX_FINGERS) continue;
      palp_Contact m;
      memset(&m, 0, sizeof m);
      m.session_id = st->session_id;
      m.finger = (uint8_t)c->finger;
      m.mode = (palp_ContactMode)c->mode;
      /* A byte on the wire: a source's 257 went out as 1; out of a byte it goes as 0, which the
       * server refuses by name (bad_distribution) as it refuses 0 and 5. */
      m.distribution = c->distribution >= 0 && c->distribution <= 255 ? (uint8_t)c->distribution : 0;
      m.vertex = -1;
      m.center = (palp_Vec3){c->center.x, c->center.y, c->center.z};
      m.force = (palp_Vec3){c->force.x, c->force.y, c->force.z};
      m.radius = c->radius;
      m.patch_area = c->patch_area;
      if (c->mode == 0) {
        if (!down[c->finger] && release_left[c->finger] == 0) continue;
      } else {
        want[c->finger] = 1;
      }
      m.seq = ++seq[c->finger];
      m.source_time_ns = palp_dds_now_ns();
      dds_write(st->contact_w, &m);
      sent++;
      if (ct_csv) palp_cli_contact_csv_row(ct_csv, t, c);
      if (c->mode == 0) {
        down[c->finger] = 0;
        if (release_left[c->finger] > 0) release_left[c->finger]--;
      }
    }
    for (int f = 0; due && f < PALP_CLI_MAX_FINGERS; f++) {
      if (want[f]) {
        down[f] = 1;
        /* Best-effort: a lift is repeated on the next ticks so one lost sample
         * cannot leave the finger pressing. */
        release_left[f] = 3;
      } else if (down[f] || release_left[f] > 0) {
        send_release(st, f, &seq[f]);
        sent++;
        if (ct_csv && down[f]) {
          palp_cli_cmd rel = {.finger = f, .mode = 0};
          palp_cli_contact_csv_row(ct_csv, t, &rel);
        }
        down[f] = 0;
        if (release_left[f] > 0) release_left[f]--;
      }
    }
    drain_feedback(&fx);
    fade_feedback(&fx, palp_dds_now_ns());
    if (o->print_period > 0 && !o->quiet && now >= next_print && fx.world_t >= 0) {
      tprintf(o, "[trainee %s] t=%6.2f s  finger 0: %s  feedback |F| = %5.2f N  pole z %+5.2f mm\n", o->name, fx.world_t,
                 down[0] ? "pressing" : "lifted  ", fx.last, -fx.last_top * 1e3);
      fflush(stdout);
      next_print += (int64_t)(o->print_period * 1e9);
      if (next_print <= now) next_print = now + (int64_t)(o->print_period * 1e9); /* after a wait for the world's time */
    }
    if (now >= next_state_check) {
      const int was_closed = palp_cli_station_session_closed(st, reason, sizeof reason);
      report_stall(o, st, stalls_seen, "trainee", 1);
      report_log(o, st, "trainee", 1);
      report_foreign(o, st, "trainee", 1);
      report_rejected(o, st, "trainee", 1, sent);
      if (was_closed) {
        if (o->rejoin && !strncmp(reason, "server lost", 11) && rejoins < 8) {
          /* Its server is gone: the same phantom (by name) on another server, same input, same clock. */
          const uint32_t lost_session = st->session_id, lost_server = PALP_DDS_ID_SERVER(st->phantom_id);
          dds_delete(fb_cond);
          palp_cli_station_end_session(st);
          uint32_t id = 0;
          char err[PALP_DDS_HINT_MAX + 256];
          palp_cli_join j = {.role = palp_ROLE_TRAINEE, .user_name = o->name, .want_feedback = 1, .timeout = o->timeout};
          if (palp_cli_station_find_phantom(st, ph->name, -1, lost_server, o->timeout, &id, err, sizeof err) == 0 &&
              (j.phantom_id = id, palp_cli_station_join(st, &j, err, sizeof err)) == 0) {
            rejoins++;
            tprintf(o, "[trainee %s] server of session %u lost after t=%.2f s of its world; rejoined as session %u on "
                       "phantom %u \"%s\"\n", o->name, lost_session, fx.world_t > 0 ? fx.world_t : 0.0, st->session_id, id,
                       ph->name);
            fx.world_t = -1; /* the new session's world: its own time */
            fflush(stdout);
            fb_cond = dds_create_readcondition(st->feedback_r, DDS_ANY_STATE);
            dds_waitset_attach(ws, fb_cond, 0);
            memset(release_left, 0, sizeof release_left);
            memset(down, 0, sizeof down);
            reason[0] = 0;
            next_state_check = now + 100000000;
            continue;
          }
          if (!g_stop) palp_log_error(o->log, "server lost and no other server to rejoin: %s", err);
          fb_cond = 0;
          gone_session = lost_session; /* ended above: the summary names the lost one, not "session 0" */
        }
        closed = 1;
        break;
      }
      next_state_check = now + 100000000;
    }
    if (due) next += period;
    if (due && next < palp_dds_now_ns()) next = palp_dds_now_ns();
    const int64_t wake = next < next_state_check ? next : next_state_check;
    for (int64_t w; !g_stop && (w = wake - palp_dds_now_ns()) > 0;) {
      dds_waitset_wait(ws, NULL, 0, w);
      drain_feedback(&fx);
      fade_feedback(&fx, palp_dds_now_ns());
    }
  }
  if (fb_cond > 0) dds_delete(fb_cond);
  dds_delete(ws);
  /* Lift every finger (three times: best-effort), then leave. */
  for (int rep = 0; rep < 3 && !closed; rep++)
    for (int f = 0; f < PALP_CLI_MAX_FINGERS; f++)
      if (seq[f]) send_release(st, f, &seq[f]);
  fade_feedback(&fx, -1); /* the device let go before it is closed */
  if (in.close) in.close(in.ctx);
  if (close_output(o, fb_csv, o->feedback_csv) < 0) failed = 1;
  if (close_output(o, ct_csv, o->contact_csv) < 0) failed = 1;
  latency lat = fx.lat;
  report_foreign(o, st, "trainee", 1);
  char foreign[96];
  double p50 = NAN, p99 = NAN;
  if (lat.n) {
    qsort(lat.us, lat.n, sizeof *lat.us, cmp_double);
    p50 = lat.us[(lat.n - 1) / 2];
    p99 = lat.us[(size_t)((double)(lat.n - 1) * 0.99)];
  }
  tprintf(o, "[trainee %s] session %u: %llu contact samples sent at %.0f Hz, %llu feedback samples, peak feedback %.2f N, "
             "contact->feedback latency p50 %.0f us p99 %.0f us (%zu samples)%s%s%s%s\n",
             o->name, gone_session ? gone_session : st->session_id, (unsigned long long)sent, rate,
             (unsigned long long)fx.samples, fx.peak, p50, p99,
             lat.n, foreign_summary(st, foreign, sizeof foreign),
             closed ? close_words(reason, "; session closed by the server: ") : "", closed ? reason : "",
             rejoins ? "; rejoined after its server was lost" : "");
  if (o->plot) plot_feedback(&fx, stdout);
  free(lat.us);
  (void)ended;
  return failed ? 1 : (closed ? 3 : 0);
}

/* ---- visual station and observer ------------------------------------------------------------ */

typedef struct deform_copy {
  palp_Deformation d;
  palp_Vec3 *pos;
  uint32_t cap;
  int valid;
} deform_copy;

static void deform_store(deform_copy *c, const palp_Deformation *d) {
  if (d->positions._length > c->cap) {
    palp_Vec3 *p = realloc(c->pos, d->positions._length * sizeof *p);
    if (!p) return;
    c->pos = p;
    c->cap = d->positions._length;
  }
  c->d = *d;
  memcpy(c->pos, d->positions._buffer, d->positions._length * sizeof *c->pos);
  c->d.positions._buffer = c->pos;
  c->d.positions._release = false;
  c->valid = 1;
}

/* The trainee's contact samples a viewer keeps until it knows her station's writer (run_viewer): the
 * newest of finger 0, enough to hold the one the server's feedback echoes as applied (its contact_seq)
 * a few hundred milliseconds at her station's rate. */
#define VIEW_CONTACTS 32
/* A press the server's feedback shows is told with the trainee's own sample (where, how hard) when one
 * comes within this long [ns], else without them. */
#define VIEW_PRESS_WAIT_NS 300000000LL

typedef struct seen_contact {
  palp_Contact c;
  dds_instance_handle_t writer;
} seen_contact;


static int run_viewer(const opts *o, palp_cli_station *st, const palp_Phantom *ph, int observer) {
  palp_cli_view view;
  int show_map = o->map || (!observer && !o->no_map);
  if (show_map && palp_cli_view_init(&view, ph, 2 * 21, 21, 0) < 0) return 1;
  deform_copy last = {0}, peak = {0};
  double peak_disp = 0;
  const int64_t t0 = palp_dds_now_ns();
  int64_t next_map = t0, next_svg = t0 + (int64_t)(o->svg_every * 1e9), next_print = t0, next_check = t0;
  unsigned stalls_seen[4] = {0, 0, 0, 0};
  int svg_no = 0, svg_failed = 0, snapshot_written = 0;
  uint64_t frames = 0, frames_misfit = 0, contacts = 0, contacts_foreign = 0, feedbacks = 0;
  /* Presses and lifts as the server applied them (session 83 review): its feedback, which only it writes
   * (palp_cli_station_from_server), says whether the trainee's finger 0 is down. The contact stream is
   * any participant's in an unsecured classroom (the server refuses other writers' samples, the viewer
   * was not told): a peer's 15 N showed as the trainee's press. Her samples say where and how hard once
   * one of them matched the feedback's echo of the sample the server applied (contact_seq and its
   * source_time_ns): that sample's writer is her station's, and only its samples count from then on. */
  seen_contact ring[VIEW_CONTACTS];
  int ring_n = 0, ring_head = 0;
  dds_instance_handle_t trainee_writer = 0;
  palp_Contact applied; /* her station's newest sample of finger 0 (valid when have_applied) */
  memset(&applied, 0, sizeof applied);
  int have_applied = 0, server_down = 0, pressing = 0;
  uint64_t echo_seq = 0;
  int64_t echo_time = 0, press_seen_ns = 0;
  double last_fb = 0, last_top = 0;
  char reason[128] = "";
  int closed = 0;
  dds_entity_t ws = dds_create_waitset(st->pp);
  dds_entity_t conds[3];
  int nc = 0;
  if (st->deformation_r > 0) conds[nc++] = dds_create_readcondition(st->deformation_r, DDS_ANY_STATE);
  if (st->contact_r > 0) conds[nc++] = dds_create_readcondition(st->contact_r, DDS_ANY_STATE);
  if (st->feedback_r > 0) conds[nc++] = dds_create_readcondition(st->feedback_r, DDS_ANY_STATE);
  for (int i = 0; i < nc; i++) dds_waitset_attach(ws, conds[i], 0);
  /* Times printed are the session's world time (the frames' sim_time, the clock the review
   * and the log use: docs/naming.md), not this station's own clock since it joined. */
  double world_t = -1.0;
  while (!g_stop) {
    tick_refusals(o);
    int64_t now = palp_dds_now_ns();
    double t = (double)(now - t0) * 1e-9;
    if (o->duration > 0 && t >= o->duration) break;
    dds_waitset_wait(ws, NULL, 0, DDS_MSECS(50));
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (st->deformation_r > 0 && dds_take(st->deformation_r, ptr, &info, 1, 1) > 0) {
      /* A frame that does not fit the phantom's mesh is dropped, never indexed; counted for the summary
       * (a mismatch read "0 deformation frames" and nothing more, session 83 review). */
      const int ours = info.valid_data && palp_cli_station_from_server(st, st->deformation_r, &info);
      const int fits = ours && palp_cli_deformation_check(ph, ptr[0]) == 0;
      if (ours && !fits) frames_misfit++;
      if (fits) {
        const palp_Deformation *d = ptr[0];
        frames++;
        if (d->sim_time > world_t) world_t = d->sim_time;
        deform_store(&last, d);
        double m = palp_cli_max_displacement(ph, d, NULL);
        if (m >= peak_disp) {
          peak_disp = m;
          deform_store(&peak, d);
        }
      }
      dds_return_loan(st->deformation_r, ptr, 1);
    }
    while (st->contact_r > 0 && dds_take(st->contact_r, ptr, &info, 1, 1) > 0) {
      if (info.valid_data) {
        const palp_Contact *c = ptr[0];
        contacts++;
        if (c->finger == 0 && trainee_writer && info.publication_handle != trainee_writer) {
          contacts_foreign++;
        } else if (c->finger == 0 && trainee_writer) {
          applied = *c, have_applied = 1;
        } else if (c->finger == 0) {
          ring[ring_head] = (seen_contact){*c, info.publication_handle};
          ring_head = (ring_head + 1) % VIEW_CONTACTS;
          if (ring_n < VIEW_CONTACTS) ring_n++;
        }
      }
      dds_return_loan(st->contact_r, ptr, 1);
    }
    while (st->feedback_r > 0 && dds_take(st->feedback_r, ptr, &info, 1, 1) > 0) {
      if (info.valid_data && palp_cli_station_from_server(st, st->feedback_r, &info)) {
        const palp_Feedback *fb = ptr[0];
        feedbacks++;
        if (fb->sim_time > world_t) world_t = fb->sim_time;
        last_top = fb->top_displacement;
        /* finger 0's entry (a finger never used has none): down as the server applies it, its force,
         * and which of the trainee's samples it applied last */
        server_down = 0, last_fb = 0;
        for (uint32_t k = 0; k < fb->fingers._length; k++) {
          const palp_FingerFeedback *ff = &fb->fingers._buffer[k];
          if (ff->finger != 0) continue;
          server_down = ff->active != 0;
          last_fb = norm3(ff->force);
          echo_seq = ff->contact_seq, echo_time = ff->contact_source_time_ns;
        }
      }
      dds_return_loan(st->feedback_r, ptr, 1);
    }
    /* Her station's writer: the one that wrote the sample the server applied (newest first). The others
     * kept meanwhile are counted as another writer's; from now on her samples are taken as they come. */
    for (int k = 0; !trainee_writer && echo_seq && k < ring_n; k++) {
      const seen_contact *e = &ring[(ring_head - 1 - k + VIEW_CONTACTS) % VIEW_CONTACTS];
      if (e->c.seq != echo_seq || e->c.source_time_ns != echo_time) continue;
      trainee_writer = e->writer;
      for (int q = ring_n - 1; q >= 0; q--) { /* oldest first: the newest of hers is left in applied */
        const seen_contact *x = &ring[(ring_head - 1 - q + VIEW_CONTACTS) % VIEW_CONTACTS];
        if (x->writer == trainee_writer) applied = x->c, have_applied = 1;
        else contacts_foreign++;
      }
      ring_n = 0;
    }
    now = palp_dds_now_ns();
    /* A press told once the server shows the finger down, with her sample if it came (within
     * VIEW_PRESS_WAIT_NS: her station writes to the viewer directly, the server's feedback comes after
     * it applied the sample); a lift once it shows the finger up. */
    const double shown_t = world_t >= 0 ? world_t : t;
    const int hers = have_applied && applied.mode != palp_CONTACT_RELEASE;
    if (!server_down) press_seen_ns = 0;
    else if (!press_seen_ns) press_seen_ns = now;
    if (server_down && !pressing && (hers || now - press_seen_ns >= VIEW_PRESS_WAIT_NS)) {
      pressing = 1;
      if (observer && !o->quiet) {
        /* where, in the one phrase every palp tool uses (palp_place_words); the force is the one her
         * station commanded: the server may have clamped it at the phantom's max_force */
        const palp_vec3 at = {applied.center.x, applied.center.y, applied.center.z};
        char where[64];
        palp_place_words(at, where, sizeof where);
        if (!hers)
          printf("[observer] t=%6.2f s  trainee presses (her station's samples not seen here: where and how hard "
                 "unknown)\n", shown_t);
        else if (applied.mode == palp_CONTACT_FORCE)
          printf("[observer] t=%6.2f s  trainee presses: force-driven, distribution %s, %s, |F| commanded %.2f N\n",
                 shown_t, palp_cli_dist_name(applied.distribution), where, norm3(applied.force));
        else
          printf("[observer] t=%6.2f s  trainee presses: finger of radius %.1f mm %s\n", shown_t,
                 applied.radius * 1e3, where);
        fflush(stdout);
      }
    } else if (!server_down && pressing) {
      pressing = 0;
      if (observer && !o->quiet) {
        printf("[observer] t=%6.2f s  trainee lifts the finger\n", shown_t);
        fflush(stdout);
      }
    }
    if (observer && !o->quiet && o->print_period > 0 && now >= next_print) {
      /* "commanded": her station's force command, not what the server applied (it clamps at max_force);
       * "|F| applied" until session 83 */
      printf("[observer] t=%6.2f s  session %u: %s  |F| commanded %.2f N, feedback %.2f N, pole z %+.2f mm, "
             "max displacement %.2f mm\n", shown_t, st->session_id, pressing ? "pressing" : "lifted  ",
             pressing && hers && applied.mode == palp_CONTACT_FORCE ? norm3(applied.force) : 0.0, last_fb,
             -last_top * 1e3, last.valid ? palp_cli_max_displacement(ph, &last.d, NULL) * 1e3 : 0.0);
      fflush(stdout);
      next_print += (int64_t)(o->print_period * 1e9);
    }
    if (show_map && last.valid && now >= next_map) {
      if (o->color && isatty(STDOUT_FILENO)) fputs("\033[H\033[2J", stdout);
      tprintf(o, "session %u, phantom %u \"%s\"\n", st->session_id, ph->phantom_id, ph->name);
      palp_cli_view_render(&view, &last.d, stdout, o->color);
      fflush(stdout);
      next_map = now + (int64_t)(o->map_every * 1e9);
    }
    if (o->svg && o->svg_every > 0 && last.valid && now >= next_svg) {
      char path[SVG_PATH_MAX], title[160];
      const int n = snprintf(path, sizeof path, "%s-%04d.svg", o->svg, ++svg_no);
      snprintf(title, sizeof title, "palp session %u, phantom \"%s\"", st->session_id, ph->name);
      /* said at the first failure, counted after (until session 83 none was looked at) */
      if (n < 0 || (size_t)n >= sizeof path || palp_cli_view_svg(ph, &last.d, title, path) < 0) {
        if (!svg_failed++)
          palp_log_error(o->log, "cannot write %s (the station's later snapshots are counted in its summary)", path);
      }
      next_svg = now + (int64_t)(o->svg_every * 1e9);
    }
    if (now >= next_check) {
      if (palp_cli_station_session_closed(st, reason, sizeof reason)) {
        closed = 1;
        break;
      }
      report_stall(o, st, stalls_seen, observer ? "observer" : "visual", 0);
      report_log(o, st, observer ? "observer" : "visual", 0);
      report_foreign(o, st, observer ? "observer" : "visual", 0);
      next_check = now + 100000000;
    }
  }
  for (int i = 0; i < nc; i++) dds_delete(conds[i]);
  dds_delete(ws);
  if (o->svg && peak.valid) {
    char title[160];
    snprintf(title, sizeof title, "palp session %u, \"%s\", peak frame", st->session_id, ph->name);
    if (palp_cli_view_svg(ph, &peak.d, title, o->svg) < 0) {
      palp_log_error(o->log, "cannot write %s", o->svg);
      svg_failed++;
    } else {
      snapshot_written = 1;
    }
  }
  report_foreign(o, st, observer ? "observer" : "visual", 0);
  char foreign[96], misfit[96] = "", others[96] = "", unwritten[96] = "";
  if (frames_misfit)
    snprintf(misfit, sizeof misfit, " (%llu more dropped: they do not fit phantom %u's mesh)",
             (unsigned long long)frames_misfit, ph->phantom_id);
  if (contacts_foreign)
    snprintf(others, sizeof others, " (%llu of them from a writer not the trainee's station, ignored)",
             (unsigned long long)contacts_foreign);
  if (svg_failed)
    snprintf(unwritten, sizeof unwritten, ", %d snapshot%s not written", svg_failed, svg_failed == 1 ? "" : "s");
  tprintf(o, "[%s] session %u: %llu deformation frames%s, %llu contact samples seen%s, %llu feedback samples, peak "
             "displacement %.2f mm%s%s%s%s%s%s\n", observer ? "observer" : "visual", st->session_id,
          (unsigned long long)frames, misfit, (unsigned long long)contacts, others, (unsigned long long)feedbacks,
          peak_disp * 1e3, snapshot_written ? ", snapshot " : "", snapshot_written ? o->svg : "", unwritten,
          foreign_summary(st, foreign, sizeof foreign), closed ? close_words(reason, "; session closed: ") : "",
          closed ? reason : "");
  if (show_map) palp_cli_view_free(&view);
  free(last.pos);
  free(peak.pos);
  /* docs/station.md's exit statuses: 1 a snapshot asked for and not written (as the trainee's output
   * files, session 80), 3 the server lost; a session its trainee ended, or one the server closed, is
   * a viewer's normal end (it exited 0 on every close until session 83) */
  return svg_failed ? 1 : closed && server_lost(reason) ? 3 : 0;
}

int main(int argc, char **argv) {
  opts o;
  if (parse(argc, argv, &o) < 0) {
    usage(stderr);
    return 2;
  }
  if (o.app.version) {
    palp_app_print_version(stdout, "palp-client");
    return 0;
  }
  static palp_log log; /* static: Cyclone's threads may log through it until the process ends */
  if (palp_log_init(&log, "palp-client", o.app.log_level, o.app.log_file) < 0) {
    fprintf(stderr, "palp-client: --log-file %s: cannot open it: %s\n", o.app.log_file, strerror(errno));
    return 2;
  }
  o.log = &log; /* every line is flushed as written */
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
  /* A closed terminal window (SIGHUP) ends the station as SIGTERM does: the haptic thread's last
   * 0 N, the LEAVE, the terminal put back by the keyboard's close(). Its default action killed the
   * station outright, and the server took the trainee for lost and held her session for
   * station_grace. Started ignoring it (nohup), it stays ignored. */
  struct sigaction old;
  if (sigaction(SIGHUP, NULL, &old) == 0 && old.sa_handler != SIG_IGN) sigaction(SIGHUP, &sa, NULL);
  /* Output piped into a reader that went (| head) fails with EPIPE instead of killing the station
   * mid-press, the device's force left where it was: the station goes on to its end. */
  sa.sa_handler = SIG_IGN;
  sigaction(SIGPIPE, &sa, NULL);
  char err[PALP_DDS_HINT_MAX + 256]; /* a join's "no answer" ends with palp_dds_unanswered_hint's */
  if (palp_app_use_dds_config(o.app.dds_config, NULL, NULL, 0, err, sizeof err) < 0) {
    palp_log_error(o.log, "%s (give --dds-config FILE or set CYCLONEDDS_URI)", err);
    return 1;
  }
  int trainee = !strcmp(o.role, "trainee"), observer = !strcmp(o.role, "observer");
  /* The input source is checked before anything goes on the network. */
  palp_cli_input in;
  memset(&in, 0, sizeof in);
  if (trainee && make_input(&o, &in, err, sizeof err) < 0) {
    palp_log_error(o.log, "%s", err);
    return 1;
  }
  if (trainee && (!strcmp(o.input, "keyboard") || !strcmp(o.input, "keyboard-finger"))) guard_tty();
  palp_dds_security sec;
  int src = o.pki || o.identity ? palp_dds_security_init(&sec, o.pki, o.identity, err, sizeof err)
                                : palp_dds_security_from_env(&sec, err, sizeof err);
  if (src == 0 && (o.pki || o.identity) && sec.kind == PALP_DDS_ID_NONE) {
    snprintf(err, sizeof err, "--pki and --identity go together");
    src = -1;
  }
  if (src == 0 && sec.kind == PALP_DDS_ID_SERVER) {
    snprintf(err, sizeof err, "--identity: a station is a trainee or an instructor, not the server");
    src = -1;
  }
  if (src == 0 && sec.warning[0]) palp_log_warn(o.log, "DDS Security: %s", sec.warning);
  if (src < 0) {
    palp_log_error(o.log, "%s", err);
    if (in.close) in.close(in.ctx);
    return 1;
  }
  /* A secured station is its identity: the server refuses another name. */
  if (sec.kind != PALP_DDS_ID_NONE && !o.name[0]) o.name = sec.name;
  char label[64];
  snprintf(label, sizeof label, "%s%s%s", o.role, o.name[0] ? ":" : "", o.name);
  /* Cyclone's warnings: at most 10 per 10 s, and a peer DDS Security refuses (a revoked
   * laptop retries every second, for hours) said once, its repeats once a minute. Kept
   * until the process ends (static), as Cyclone's threads may log until then. */
  static palp_dds_log_limit dds_sink;
  static palp_dds_refusals refusals;
  palp_dds_refusals_init(&refusals, palp_log_warn_line, &log, PALP_DDS_REFUSAL_WINDOW_S);
  /* A trainee's terminal says what stands between it and the server (its own identity refused,
   * the server's); a classmate's revoked laptop is for the server's log and the instructor
   * (which name it), and goes to this station's debug log (until 2026-12-05 every trainee's
   * terminal named her). */
  char me[PALP_DDS_REFUSAL_WHO] = "";
  if (sec.kind == PALP_DDS_ID_TRAINEE) snprintf(me, sizeof me, "trainee/%s", sec.name);
  palp_dds_refusals_focus(&refusals, me, palp_log_debug_line, &log);
  palp_dds_refusals_install(&dds_sink, &refusals, 10, 10.0);
  /* a peer refused for its permissions named by its identity, not its GUID */
  if (palp_dds_security_name_peers(&sec, &refusals) < 0) palp_log_warn(&log, "out of memory naming the classroom's identities");
  o.refusals = &refusals;
  palp_cli_station st;
  if (palp_cli_station_open_secure(&st, o.domain, label, &sec, err, sizeof err) < 0) {
    palp_log_error(o.log, "%s", err);
    if (in.close) in.close(in.ctx);
    return 1;
  }
  /* Its waits give up when the user stops the station: exit 0 and nothing said, as a stop during
   * the session ends it (until 2026-12-06 a Ctrl-C with no server waited out --timeout twice, then
   * said "no answer" and exited 1). */
  st.stop = &g_stop;
  int64_t server_number = -1;
  if (o.server) { /* --phantom/--session are that server's local ids */
    uint32_t number = 0;
    const int got = palp_cli_station_server_number(&st, o.server, o.timeout, &number, err, sizeof err);
    if (got < 0) {
      if (got != PALP_CLI_ESTOPPED) palp_log_error(o.log, "--server: %s", err);
      if (in.close) in.close(in.ctx);
      palp_cli_station_close(&st);
      return got == PALP_CLI_ESTOPPED ? 0 : 1;
    }
    server_number = number;
    if (o.phantom) o.phantom = PALP_DDS_ID(number, o.phantom);
    if (o.session) o.session = PALP_DDS_ID(number, o.session);
  }
  if (o.phantom_name) {
    const int got =
        palp_cli_station_find_phantom(&st, o.phantom_name, server_number, -1, o.timeout, &o.phantom, err, sizeof err);
    if (got < 0) {
      if (got != PALP_CLI_ESTOPPED) palp_log_error(o.log, "--phantom-name: %s", err);
      if (in.close) in.close(in.ctx);
      palp_cli_station_close(&st);
      return got == PALP_CLI_ESTOPPED ? 0 : 1;
    }
  }
  palp_cli_join j = {.role = trainee ? palp_ROLE_TRAINEE : observer ? palp_ROLE_OBSERVER : palp_ROLE_VISUAL,
                     .phantom_id = o.phantom,
                     .session_id = o.session,
                     .user_name = o.name,
                     .want_feedback = 1,
                     /* a position-driven trainee renders from the local models (run_haptic_trainee) */
                     .local_models_only = trainee && in.read_position && in.write_force,
                     .want_deformation = !trainee,
                     .timeout = o.timeout};
  int rc = 1;
  if (!trainee && o.trainee && !o.session) {
    /* Find the trainee's open session in the (transient-local) session states: each state once, as it
     * comes (the samples not read yet, 8 at a time, until none is left). A plain read of 8 returned
     * the same first 8 states on every pass: a trainee past the 8th session on the domain was never
     * found (session 77; a server holds up to max_sessions open, its closed ones for a while). */
    int64_t end = palp_dds_now_ns() + (int64_t)(o.timeout * 1e9);
    while (!j.session_id && palp_dds_now_ns() < end && !g_stop) {
      palp_SessionState buf[8];
      void *ptr[8];
      dds_sample_info_t info[8];
      for (int i = 0; i < 8; i++) ptr[i] = &buf[i];
      int n;
      while (!j.session_id && (n = dds_read_mask(st.state_r, ptr, info, 8, 8, DDS_NOT_READ_SAMPLE_STATE)) > 0)
        for (int i = 0; i < n; i++)
          if (info[i].valid_data && buf[i].phase == palp_PHASE_OPEN && !strcmp(buf[i].trainee_name, o.trainee) &&
              (!o.phantom || buf[i].phantom_id == o.phantom))
            j.session_id = buf[i].session_id;
      if (!j.session_id) {
        struct timespec ts = {0, 100000000};
        nanosleep(&ts, NULL);
      }
    }
    if (!j.session_id) {
      if (!g_stop)
        palp_log_error(o.log, "--trainee %s: no open session of that trainee within %.0f s", o.trainee, o.timeout);
      palp_cli_station_close(&st);
      return g_stop ? 0 : 1; /* stopped: as a stop during the session */
    }
  }
  const int joined = palp_cli_station_join(&st, &j, err, sizeof err);
  if (joined < 0) {
    if (joined != PALP_CLI_ESTOPPED) palp_log_error(o.log, "%s", err);
    if (in.close) in.close(in.ctx);
    palp_cli_station_close(&st);
    return joined == PALP_CLI_ESTOPPED ? 0 : 1;
  }
  palp_Phantom ph;
  const int listed = palp_cli_station_catalogue(&st, st.phantom_id, o.timeout, &ph, err, sizeof err);
  if (listed < 0) {
    if (listed != PALP_CLI_ESTOPPED) palp_log_error(o.log, "%s", err);
    if (in.close) in.close(in.ctx);
    palp_cli_station_leave(&st);
    palp_cli_station_close(&st);
    return listed == PALP_CLI_ESTOPPED ? 0 : 1;
  }
  if (!o.quiet)
    tprintf(&o, "[%s %s] joined session %u on phantom %u \"%s\" (%u vertices, %.0f Hz), partition %s\n", o.role,
            o.name, st.session_id, ph.phantom_id, ph.name, ph.rest._length, st.tick_rate_hz, st.partition);
  fflush(stdout);
  rc = trainee ? run_trainee(&o, &st, &ph, in) : run_viewer(&o, &st, &ph, observer);
  /* The stop that ended the session is spent: the debrief and score are still awaited after it (the
   * server writes them as the LEAVE closes the session), and a second stop cuts those waits short. */
  atomic_store(&g_stop, 0);
  palp_cli_station_leave(&st);
  if (trainee && st.in_exercise && !o.quiet && print_debrief(&o, &st) == (int)palp_DEBRIEF_LESIONS)
    print_debrief_score(&o, &st);
  report_foreign(&o, &st, o.role, 1); /* a debrief or score another participant wrote, if not said yet */
  if (st.goodbye_unanswered) {
    /* Said even with --quiet: the instructor may otherwise read "not back" in the log as a crash. */
    printf("[%s %s] the server did not answer within %.0f s after this station's stall, so its goodbye may be lost: "
           "session %u may be logged as closed \"not back\" (after the server's station_grace) rather than as left\n",
           o.role, o.name, PALP_CLI_LEAVE_WAIT_S, st.session_id);
    fflush(stdout);
  }
  /* The session log's loss while the session ran, in all: said as it happened (report_log), this is the
   * count to pass on. Said even with --quiet. */
  char lost_line[320];
  if (palp_dds_log_view_summary(&st.log, lost_line, sizeof lost_line)) {
    printf("[%s %s] %s\n", o.role, o.name, lost_line);
    fflush(stdout);
  }
  /* Give the disposal a moment to reach the server before the participant goes. */
  struct timespec ts = {0, 100000000};
  nanosleep(&ts, NULL);
  palp_cli_phantom_free(&ph);
  palp_cli_station_close(&st);
  palp_dds_log_limit_remove(&dds_sink); /* the participant is gone: then the repeats not yet said */
  palp_dds_refusals_flush(&refusals);
  return rc;
}
