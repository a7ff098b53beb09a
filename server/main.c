/* main.c - palp-server: the classroom server's command line. */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "config.h"
#include "db_log.h"
#include "findings.h" /* palp_srv_findings_check_exercise: as the start checks an exercise */
#include "palp.h"
#include "palp_app.h"
#include "palp_dds.h"
#include "palp_dds_security.h"
#include "palp_assess.h"
#include "server.h"

#define SERVER_OPTS (PALP_APP_OPT_VERSION | PALP_APP_OPT_LOG | PALP_APP_OPT_VERBOSE | PALP_APP_OPT_DDS)

static void usage(FILE *f) {
  fprintf(f,
          "usage: palp-server [options]\n"
          "  --config PATH        server configuration (default <data>/config/server.json)\n"
          "  --database PATH      override the config's \"database\" (the SQLite session log); also --db,\n"
          "                       as palp-recorder and palp-review name it\n"
          "  --domain N           override domain_id\n"
          "  --server-name NAME   override server_name (identity on the domain; default the host name)\n"
          "  --server-number N    override server_number (0..4095; the high bits of every phantom/session id)\n"
          "  --identity-wait S    listen S seconds for servers already on the domain before announcing\n"
          "                       (default 0.5 with a server name or number, else 0; a lab network may need 2)\n"
          "  --tick-rate HZ       override tick_rate_hz (100 as in the paper, 1000 for haptics)\n"
          "  --threads N          override tick_threads (0 = one per core)\n"
          "  --rt-priority N      override tick_priority (1..99: SCHED_FIFO tick threads; 0: normal)\n"
          "  --max-sessions N     override max_sessions\n"
          "  --duration S         stop after S seconds (default: until SIGINT/SIGTERM)\n"
          "  --check              validate the configuration and the scenes, then exit\n"
          "  --no-db              do not write the session log (config \"database\")\n"
          "  --pki DIR            DDS Security with the classroom PKI in DIR (config \"security\"; docs/security.md)\n"
          "  --identity ID        the server's identity in the PKI (default server)\n"
          "  --insecure           serve a DDS network beyond loopback without DDS Security (refused\n"
          "                       otherwise: anyone on that network could join, press and close sessions)\n"
          "signals: SIGINT/SIGTERM stop cleanly (every session closed and summarised); SIGHUP re-opens\n"
          "         the --log-file (log rotation) and re-reads the config's log_level; sessions go on\n");
  palp_app_common_usage(f, SERVER_OPTS);
}

/* A signal may land on any thread, including ones that libraries start before
 * main (OpenBLAS's pool, under CHOLMOD), which no mask set here can reach; so the
 * handler only writes the signal number into a pipe (async-signal-safe), and this
 * thread reads it and makes the stop request, where DDS calls are allowed. */
typedef struct sig_ctx {
  int fd[2]; /* [0] read by signal_main, [1] written by the handler and by main */
  palp_srv *srv;
  palp_log *log;
  const char *config_path;
  palp_srv_config *file_cfg; /* the config file as the run started with it (before command-line overrides), its
                              * log_level as last re-read: what a SIGHUP's file is compared with */
  int level_fixed;           /* --log-level/--verbose/--quiet given: the file's log_level is ignored */
  /* The SIGINT/SIGTERM that stopped the run (0: none): written by the signal thread, read by main
   * while that thread runs, so atomic (a plain int until session 82). */
  atomic_int signo;
} sig_ctx;

/* SIGHUP: what can change without touching a session is re-read (log_level); any
 * other change is reported and waits for a restart, which closes sessions cleanly. */
static void reload_config(sig_ctx *c) {
  static palp_srv_config nc; /* one signal thread; too large for comfort on its stack */
  char e[512];
  if (palp_srv_config_load(c->config_path, &nc, e, sizeof e) < 0) {
    /* e names the file already (palp_srv_config_load: "<path>: ...") */
    palp_log_error(c->log, "SIGHUP: %s; the running configuration stays", e);
    return;
  }
  palp_log_level lv;
  if (!c->level_fixed && nc.log_level[0] && palp_log_parse_level(nc.log_level, &lv) == 0 &&
      lv != palp_log_get_level(c->log)) {
    /* At WARN, so the change shows whichever way it goes. */
    palp_log_warn(c->log, "SIGHUP: log level %s -> %s", palp_log_level_name(palp_log_get_level(c->log)),
                  palp_log_level_name(lv));
    palp_log_set_level(c->log, lv);
  }
  snprintf(c->file_cfg->log_level, sizeof c->file_cfg->log_level, "%s", nc.log_level);
  /* Against the file the run started with, kept: until session 90 each SIGHUP made the file it read the
   * baseline, so a change still waiting for a restart was said once and then never (the next rotation's
   * SIGHUP said nothing), and a file put back as the run has it was said "changed" (found by review). */
  if (memcmp(c->file_cfg, &nc, sizeof nc) != 0)
    palp_log_warn(c->log, "SIGHUP: %s differs from the configuration this run started with beyond log_level; a "
                  "restart applies it (sessions close cleanly)", c->config_path);
}

static int sig_pipe_w = -1; /* the handler's only state: a process-wide fd is unavoidable */

static void on_signal(int sig) {
  const int saved = errno;
  const unsigned char b = (unsigned char)sig;
  if (sig_pipe_w >= 0 && write(sig_pipe_w, &b, 1) < 0) { /* nothing safe to do */
  }
  errno = saved;
}

static void *signal_main(void *arg) {
  sig_ctx *c = arg;
  for (;;) {
    unsigned char b = 0;
    ssize_t n;
    while ((n = read(c->fd[0], &b, 1)) < 0 && errno == EINTR) {
    }
    if (n != 1 || b == 0) return NULL; /* 0 is main's own wake-up when the run ends by itself */
    if (b == SIGHUP) {
      /* Rotation: logrotate moved the file; keep serving, write to a new one. */
      int rc = palp_log_reopen(c->log);
      if (rc < 0) palp_log_error(c->log, "SIGHUP: cannot re-open the log file %s; still writing to the old one",
                                 c->log->path);
      else palp_log_info(c->log, "SIGHUP: log re-opened%s%s; sessions continue", c->log->path[0] ? " " : "",
                         c->log->path);
      reload_config(c);
      continue;
    }
    atomic_store(&c->signo, b);
    palp_log_info(c->log, "%s: shutting down", b == SIGINT ? "SIGINT" : "SIGTERM");
    palp_srv_request_stop(c->srv);
    return NULL;
  }
}

static int parse_num(const char *opt, const char *arg, double lo, double hi, double *out) {
  char *end = NULL;
  errno = 0;
  double v = arg ? strtod(arg, &end) : 0;
  if (!arg || errno || end == arg || *end || !(v >= lo && v <= hi)) {
    fprintf(stderr, "palp-server: %s: expected a number in [%g, %g], got \"%s\"\n", opt, lo, hi, arg ? arg : "");
    return -1;
  }
  *out = v;
  return 0;
}

/* An option that counts (a domain, a number, threads, sessions, a priority): a fraction was
 * cut silently (--domain 42.5 ran on domain 42), so it is refused. */
static int parse_whole(const char *opt, const char *arg, double lo, double hi, double *out) {
  double v = 0;
  if (parse_num(opt, arg, lo, hi, &v)) return -1;
  if (v != floor(v)) {
    fprintf(stderr, "palp-server: %s: expected a whole number in [%g, %g], got \"%s\"\n", opt, lo, hi, arg);
    return -1;
  }
  *out = v;
  return 0;
}

int main(int argc, char **argv) {
  const char *config_path = NULL, *database = NULL;
  char default_config[PALP_SRV_PATH_MAX];
  palp_app_opts ao;
  palp_app_opts_init(&ao, "palp-server");
  const char *server_name = NULL;
  double server_number = -1, identity_wait = -1;
  double domain = -1, rate = -1, threads = -1, max_sessions = -1, duration = 0, prio = -1;
  int check = 0, verbose = 0, no_db = 0;
  const char *pki = NULL, *identity = NULL;
  int insecure = 0;
  char err[PALP_DDS_HINT_MAX + 512]; /* palp_dds_refused_hint's ends a refused topic's message */
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    int bad = 0, common = palp_app_common_opt(&ao, SERVER_OPTS, argc, argv, &i);
    if (common < 0) return 2;
    if (common) continue;
    if (!strcmp(a, "--config") && v) config_path = argv[++i];
    /* --db: palp-recorder's and palp-review's name for the same file (docs/naming.md) */
    else if ((!strcmp(a, "--database") || !strcmp(a, "--db")) && v) database = argv[++i];
    else if (!strcmp(a, "--server-name") && v) {
      if (!v[0] || strlen(v) >= 64) {
        fprintf(stderr, "palp-server: --server-name: 1 to 63 characters (got %zu)\n", strlen(v));
        return 2;
      }
      server_name = argv[++i];
    }
    else if (!strcmp(a, "--server-number")) bad = parse_whole(a, v, 0, 4095, &server_number), i++;
    else if (!strcmp(a, "--identity-wait")) bad = parse_num(a, v, 0, 60, &identity_wait), i++;
    else if (!strcmp(a, "--domain")) bad = parse_whole(a, v, 0, 232, &domain), i++;
    /* at least 1 / PALP_WORLD_MAX_DT: a slower rate's step is longer than a world steps */
    else if (!strcmp(a, "--tick-rate")) bad = parse_num(a, v, 1.0 / PALP_WORLD_MAX_DT, 10000, &rate), i++;
    else if (!strcmp(a, "--threads")) bad = parse_whole(a, v, 0, 64, &threads), i++;
    else if (!strcmp(a, "--rt-priority")) bad = parse_whole(a, v, 0, 99, &prio), i++;
    else if (!strcmp(a, "--max-sessions")) bad = parse_whole(a, v, 1, 1024, &max_sessions), i++;
    else if (!strcmp(a, "--duration")) bad = parse_num(a, v, 0, 1e7, &duration), i++;
    else if (!strcmp(a, "--check")) check = 1;
    else if (!strcmp(a, "--no-db")) no_db = 1;
    else if (!strcmp(a, "--insecure")) insecure = 1;
    else if (!strcmp(a, "--pki") && v) pki = argv[++i];
    else if (!strcmp(a, "--identity") && v) identity = argv[++i];
    else if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      usage(stdout);
      return 0;
    } else {
      fprintf(stderr, "palp-server: unknown option or missing value: %s\n", a);
      usage(stderr);
      return 2;
    }
    if (bad) return 2;
  }
  if (ao.version) {
    palp_app_print_version(stdout, "palp-server");
    return 0;
  }
  verbose = ao.log_level >= PALP_LOG_DEBUG;
  palp_log plog;
  if (palp_log_init(&plog, "palp-server", ao.log_level, ao.log_file) < 0) {
    /* 2, as every program's: a log file that cannot be opened is a setting a restart cannot mend
     * (the unit's RestartPreventExitStatus=2, docs/deploy.md); it was 1, and systemd restarted a
     * server whose /var/log/palp it could not write every 2 s until the start limit. */
    fprintf(stderr, "palp-server: --log-file %s: cannot open it: %s\n", ao.log_file, strerror(errno));
    return 2;
  }
  if (!config_path) {
    if (palp_app_data_path("config/server.json", default_config, sizeof default_config, err, sizeof err) < 0) {
      fprintf(stderr, "palp-server: %s (or give --config)\n", err);
      return 1;
    }
    config_path = default_config;
  }

  palp_srv_def def;
  memset(&def, 0, sizeof def);
  int rc = palp_srv_config_load(config_path, &def.cfg, err, sizeof err);
  if (rc < 0) {
    fprintf(stderr, "palp-server: bad configuration: %s\n", err);
    return 1;
  }
  static palp_srv_config file_cfg; /* for SIGHUP's comparison */
  file_cfg = def.cfg;
  palp_log_level file_level;
  if (!ao.log_level_set && def.cfg.log_level[0] && palp_log_parse_level(def.cfg.log_level, &file_level) == 0) {
    palp_log_set_level(&plog, file_level);
  }
  if (domain >= 0) def.cfg.domain_id = (uint32_t)domain;
  if (rate > 0) def.cfg.tick_rate_hz = rate;
  if (threads >= 0) def.cfg.tick_threads = (int)threads;
  if (max_sessions > 0) def.cfg.max_sessions = (int)max_sessions;
  if (prio >= 0) def.cfg.tick_priority = (int)prio;
  if (database) snprintf(def.cfg.database, sizeof def.cfg.database, "%s", database);
  if (server_name) snprintf(def.cfg.server_name, sizeof def.cfg.server_name, "%s", server_name);
  if (server_number >= 0) def.cfg.server_number = (uint32_t)server_number;
  /* A server given an identity is meant to share its domain: it listens before it
   * serves. A default one (number 0, host name) starts at once, as it always did; a
   * clash is still found by its first identity poll (<= 1 status period), and the
   * younger server stops. */
  def.identity_wait_s = identity_wait >= 0                                   ? identity_wait
                        : def.cfg.server_number > 0 || def.cfg.server_name[0] ? 0.5
                                                                              : 0.0;
  if (palp_srv_config_check_ids(&def.cfg, err, sizeof err) < 0) {
    fprintf(stderr, "palp-server: bad configuration: %s: %s\n", config_path, err);
    return 1;
  }
  def.verbose = verbose;
  if (pki) snprintf(def.cfg.security_pki, sizeof def.cfg.security_pki, "%s", pki);
  if (identity) snprintf(def.cfg.security_identity, sizeof def.cfg.security_identity, "%s", identity);
  def.log = &plog;
  char dds_chosen[PALP_SRV_PATH_MAX + 32];
  if (palp_app_use_dds_config(ao.dds_config, def.cfg.dds_config, dds_chosen, sizeof dds_chosen, err, sizeof err) < 0) {
    if (ao.dds_config) fprintf(stderr, "palp-server: --dds-config: %s\n", err);
    else fprintf(stderr, "palp-server: bad configuration: %s: dds_config: %s\n", config_path, err);
    return 1;
  }
  /* Nobody is trusted by default: beyond loopback a classroom runs secured, unless whoever
   * starts the server says, with --insecure, that the network is the class's alone. Decided
   * from the DDS config before any participant exists, so a refused server sends nothing. */
  char scope[200];
  const int loopback = palp_app_dds_loopback_only(scope, sizeof scope);
  const int secured = def.cfg.security_pki[0] != '\0';
  if (!loopback && !secured && !insecure) {
    fprintf(stderr,
            "palp-server: refusing to serve beyond loopback without DDS Security: the DDS config %s may reach a "
            "network (%s), where anyone could join, press on a trainee's phantom or close sessions. Give --pki DIR "
            "(config \"security\"; docs/security.md), a loopback DDS config, or --insecure if this network is the "
            "class's alone.\n",
            dds_chosen, scope);
    return 2;
  }
  if (check) {
    /* Build every phantom's world once, without DDS, as the start does (palp_srv_prepare_phantom:
     * the physics rate's step, force feedback, a station's fingers, the world itself). */
    for (int i = 0; i < def.cfg.phantom_count; i++) {
      static palp_scene sc;
      char msg[512] = "";
      palp_srv_phantom_cfg pc = def.cfg.phantom[i];
      const int plain = def.cfg.phantom_count - def.cfg.exercise_count;
      if (i >= plain) { /* an exercise: its file, its phantom and its lesions in it */
        palp_exercise *ex = calloc(1, sizeof *ex);
        rc = ex ? palp_exercise_load(def.cfg.phantom[i].exercise_path, ex, msg, sizeof msg) : PALP_ENOMEM;
        if (rc == 0) rc = palp_exercise_scene(ex, &sc, msg, sizeof msg);
        if (rc == 0) rc = palp_srv_findings_check_exercise(ex, sc.world.mesh.radius, def.cfg.max_force, msg, sizeof msg);
        if (rc == 0) snprintf(pc.scene_path, sizeof pc.scene_path, "%s", ex->phantom_path);
        /* its title is its name, as the start makes it (load_exercise), for the names' check below */
        if (rc == 0) snprintf(def.cfg.phantom[i].name, sizeof def.cfg.phantom[i].name, "%.63s", ex->title);
        free(ex);
        if (rc < 0) {
          fprintf(stderr, "palp-server: bad configuration: exercises[%d].file: %s: %s\n", i - plain,
                  def.cfg.phantom[i].exercise_path, msg[0] ? msg : palp_strerror(rc));
          return 1;
        }
      } else {
        rc = palp_scene_load(def.cfg.phantom[i].scene_path, &sc, msg, sizeof msg);
        if (rc < 0) {
          fprintf(stderr, "palp-server: bad configuration: phantoms[%d].scene: %s: %s\n", i,
                  def.cfg.phantom[i].scene_path, msg[0] ? msg : palp_strerror(rc));
          return 1;
        }
      }
      palp_world *w = NULL;
      rc = palp_srv_prepare_phantom(&def.cfg, i, &pc, &sc, &w, msg, sizeof msg);
      palp_world_destroy(w);
      if (rc < 0) {
        fprintf(stderr, "palp-server: bad configuration: %s: %s\n", config_path, msg);
        return 1;
      }
    }
    {
      /* one name for one phantom (session 82), the exercises by their titles, as the start checks */
      const char *names[PALP_SRV_MAX_PHANTOMS];
      char msg[320] = "";
      for (int i = 0; i < def.cfg.phantom_count; i++) names[i] = def.cfg.phantom[i].name;
      if (palp_srv_config_check_names(names, def.cfg.phantom_count, def.cfg.phantom_count - def.cfg.exercise_count, msg,
                                      sizeof msg) < 0) {
        fprintf(stderr, "palp-server: bad configuration: %s: %s\n", config_path, msg);
        return 1;
      }
    }
    /* Secured: the identity's files are there and its key is private (what the start would
     * refuse, said before it). */
    if (def.cfg.security_pki[0]) {
      palp_dds_security sec;
      char msg[400] = "";
      if (palp_srv_security_prepare(&def.cfg, &sec, msg, sizeof msg) < 0) {
        fprintf(stderr, "palp-server: bad configuration: security: %s\n", msg);
        return 1;
      }
      if (sec.warning[0]) fprintf(stderr, "palp-server: warning: DDS Security: %s\n", sec.warning);
    }
    printf("palp-server: %s: ok (%d phantoms, %.0f Hz, domain %u%s)\n", config_path, def.cfg.phantom_count,
           def.cfg.tick_rate_hz, def.cfg.domain_id, def.cfg.security_pki[0] ? ", DDS Security identity readable" : "");
    return 0;
  }

  sig_ctx sc;
  memset(&sc, 0, sizeof sc);
  atomic_init(&sc.signo, 0);
  if (pipe(sc.fd) != 0) {
    fprintf(stderr, "palp-server: cannot create the signal pipe: %s\n", strerror(errno));
    return 1;
  }
  sig_pipe_w = sc.fd[1];
  /* SIGHUP too: its default action would kill us with every session open */
  palp_app_on_signals(on_signal);
  sc.log = &plog;
  sc.config_path = config_path;
  sc.file_cfg = &file_cfg;
  sc.level_fixed = ao.log_level_set;
  palp_log_info(&plog, "%s starting: config %s, DDS config %s", palp_app_version(), config_path, dds_chosen);
  if (!loopback && !secured)
    palp_log_warn(&plog, "--insecure: serving a DDS network beyond loopback (%s) WITHOUT DDS Security: anyone on it "
                         "is trusted",
                  scope);

  palp_srv_db_log *log = NULL;
  if (def.cfg.database[0] && !no_db) {
    /* what palp_srv_create would refuse for DDS Security, refused before the log's file is made */
    palp_dds_security sec;
    char msg[400] = "";
    if (palp_srv_security_prepare(&def.cfg, &sec, msg, sizeof msg) < 0) {
      palp_log_error(&plog, "%s: security: %s", config_path, msg);
      return 1;
    }
    /* The log's directory (e.g. out/) is created on first use; one level only. */
    char dir[PALP_SRV_PATH_MAX];
    snprintf(dir, sizeof dir, "%s", def.cfg.database);
    char *slash = strrchr(dir, '/');
    if (slash && slash != dir) {
      *slash = 0;
      mkdir(dir, 0777);
    }
    rc = palp_srv_db_log_open(def.cfg.database, (int64_t)(def.cfg.session_log_max_mb * 1e6), &plog, &log, err,
                              sizeof err);
    if (rc < 0) {
      fprintf(stderr, "palp-server: bad configuration: %s: database: %s: %s\n", config_path, def.cfg.database, err);
      return 1;
    }
    def.events = palp_srv_db_log_events(log);
    palp_log_info(&plog, "logging sessions to %s", def.cfg.database);
  }
  palp_srv *srv = palp_srv_create(&def, &rc, err, sizeof err);
  if (!srv) {
    palp_log_error(&plog, "%s: %s", config_path, err);
    palp_srv_db_log_close(log);
    return 1;
  }
  sc.srv = srv;
  pthread_t sig_thread;
  if (pthread_create(&sig_thread, NULL, signal_main, &sc) != 0) {
    fprintf(stderr, "palp-server: cannot start the signal thread\n");
    palp_srv_destroy(srv);
    return 1;
  }
  rc = palp_srv_run(srv, duration);
  /* What ended the run, read once as it ended: a signal stores it before it asks the stop, and one
   * coming after the run ended by itself is not named as its end. */
  const int stopped_by = atomic_load(&sc.signo);
  /* Wake the signal thread if no signal came. */
  const unsigned char zero = 0;
  if (!stopped_by && write(sc.fd[1], &zero, 1) < 0) pthread_cancel(sig_thread);
  pthread_join(sig_thread, NULL);
  printf("\npalp-server session summary\n");
  palp_srv_print_summary(srv, stdout);
  fflush(stdout);
  if (plog.path[0]) { /* a service's stdout may go nowhere: the table goes to its log too */
    palp_log_info(&plog, "stopped; session summary:");
    pthread_mutex_lock(&plog.mu);
    palp_srv_print_summary(srv, plog.f);
    fflush(plog.f);
    pthread_mutex_unlock(&plog.mu);
  }
  palp_srv_destroy(srv);
  palp_srv_db_log_close(log);
  palp_log_info(&plog, "stopped (%s)",
                stopped_by == SIGINT    ? "SIGINT"
                : stopped_by == SIGTERM ? "SIGTERM"
                : rc < 0              ? "server identity conflict"
                                      : "end of run");
  palp_log_close(&plog);
  return rc < 0 ? 1 : 0;
}
