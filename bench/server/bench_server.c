/*
 * bench_server.c - palp-server figures over real DDS on loopback.
 *
 * 1. Contact -> feedback latency: this process is a trainee station; palp-server
 *    runs as a separate process. Contacts are sent at jittered times (uniform in
 *    [0.5, 1.5] tick periods, so their phase against the server's tick is
 *    random); the latency of a contact is the time from its send to the first
 *    feedback sample echoing its sequence number: wait for the next tick + step
 *    + two DDS hops. Measured at 100 Hz and 1 kHz.
 * 2. Baseline: a plain DDS round trip of the same samples (palp_Contact out,
 *    palp_Feedback back) through an echo process on the same QoS, same run.
 * 3. Capacity: sessions at 1 kHz added step by step (each pressing with a
 *    time-varying force so its world never sleeps) until more than 1 % of ticks
 *    overrun over a 2 s window, read from palp_server_status.
 *
 * 4. --secure: latency and capacity (or, with `haptic`, the haptic capacity) with DDS Security
 *    off, then on, in the same run
 *    (docs/security.md): a classroom PKI is made in the bench's work directory by
 *    scripts/make-classroom-pki.sh; the server runs with its identity, every bench
 *    station with the trainee identity "bench" (Cyclone 0.10.2 gives all secured
 *    participants of one process the permissions of the first, so one identity).
 *
 * 5. Haptic capacity (issue 11, `bench_server haptic`): position-driven sessions
 *    added step by step, each with a station rendering at 1 kHz: one haptic
 *    thread in this process reads every session's simulated device (press
 *    cycles), renders its force from the newest local model (palp_haptic) and
 *    sends the device point at the physics rate; the server steps at 250 Hz,
 *    then at 1 kHz. Held: more sessions until more than 1 % of physics steps are
 *    late (overrun), read from palp_server_status. Same-run baseline: the
 *    model's own step with a pressed finger, timed in this process.
 *    --motion strip: the devices search in vertical strips at three depths, as the
 *    exercises' scripted expert does (palp_bench_strip_device, bench/bench_motion.h),
 *    instead of press cycles; --rate HZ: that physics rate only. With --scene config/phantoms/dome.json, the exercises' dome.
 *    Each window also prints the server process's own CPU (cores busy, from /proc): the
 *    stations share this machine's two cores here, a lab's would not, so the server's
 *    cores per session at the largest count held give a projection (not a hold) of what
 *    two cores of its own would take.
 *
 * usage: bench_server [latency|rtt|capacity|haptic|all] [--seconds S] [--threads N] [--max N]
 *        [--contact-rate HZ] [--rt-priority N] [--no-db] [--scene FILE] [--secure] [--overrun-limit PCT]
 *        [--haptic-domain ID] [--domain-base B] [--motion press|strip] [--rate HZ]
 * DDS domains 150-152 (secured 142-144), or B..B+5 with --domain-base; always the loopback config
 * (a CYCLONEDDS_URI in the environment is ignored, said on stderr).
 * --overrun-limit: keep adding sessions until this share of ticks overruns (default 1; in `haptic`, of
 * the sessions' physics steps late), e.g. 100 to compare tick time and load at equal session counts.
 * --scene: the phantoms' scene (any path; default config/paper_step.json with the
 * shipped calibrated parameters), e.g. one with params/handset.json as a baseline.
 */
#define _DEFAULT_SOURCE /* realpath */
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <pthread.h>

#include "../bench_motion.h"
#include "../bench_tmp.h"
#include "haptic_loop.h"
#include "input.h"
#include "palp_dds.h"
#include "palp_dds_security.h"
#include "palp_timer_floor.h"
#include "station.h"

extern char **environ;

/* DDS domains: latency, capacity and the round trip 150-152, secured runs 142-144 (the security
 * work's own range, 130-149); --domain-base B moves them to B..B+2 and B+3..B+5 (session 82), so
 * that two runs, or a run beside the tests, need not share one. */
static unsigned domain_base = 0; /* 0: the defaults above */
static unsigned dom(unsigned offset, unsigned fixed) { return domain_base ? domain_base + offset : fixed; }
/* The server's config, log, database and the PKI live in the run's scratch directory
 * (bench_tmp.h; fixed names in /tmp until 2026-12-05). */
static char bench_pki[600];
static unsigned haptic_domain = 120; /* --haptic-domain: parallel runs need their own */

static double seconds = 5.0;
static int threads = 2, max_sessions = 48;
static const char *scene_path = PALP_CONFIG_DIR "/paper_step.json"; /* --scene: the phantoms' scene */
static double contact_rate = 100.0;
static int rt_priority = 0;
static int no_db = 0;
static double overrun_limit = 0.01; /* --overrun-limit PCT: stop adding sessions above this */
static int secure = 0;             /* this pass runs with DDS Security */
static palp_dds_security bench_sec; /* trainee/bench in bench_pki */

static unsigned lat_domain(void) { return secure ? dom(3, 142) : dom(0, 150); }
static unsigned cap_domain(void) { return secure ? dom(4, 143) : dom(1, 151); }
static unsigned rtt_domain(void) { return dom(2, 152); }
static unsigned hap_domain(void) { return secure ? dom(5, 144) : haptic_domain; }
static int max_given = 0;
static int strip_motion = 0;     /* --motion strip: the exercises' search instead of press cycles */
static double only_rate = 0.0;   /* --rate HZ: one physics rate instead of 250 Hz then 1 kHz */

static void nap(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
  while (nanosleep(&ts, &ts) != 0) {
  }
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

typedef struct stats {
  double p50, p99, max, mean;
  size_t n;
} stats;

static stats summarize(double *v, size_t n) {
  stats s = {NAN, NAN, NAN, NAN, n};
  if (!n) return s;
  qsort(v, n, sizeof *v, cmp_double);
  double sum = 0;
  for (size_t i = 0; i < n; i++) sum += v[i];
  s.p50 = v[(n - 1) / 2];
  s.p99 = v[(size_t)((double)(n - 1) * 0.99)];
  s.max = v[n - 1];
  s.mean = sum / (double)n;
  return s;
}

static pid_t spawn_server(unsigned domain, double rate);
/* Starts path with argv, its output to log (NULL: the bench's own), tied to the bench: the child
 * gets SIGINT (a clean stop) when the bench dies, so a bench that crashes leaves no server
 * running (one did, and the next run's server met its session database: "disk I/O error").
 * Only async-signal-safe calls between fork and exec. */
static pid_t spawn_tied(const char *path, char *const argv[], const char *log) {
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid != 0) return pid; /* the child's pid, or -1 */
  if (prctl(PR_SET_PDEATHSIG, SIGINT) != 0 || getppid() != parent) _exit(126);
  if (log) {
    const int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0 || dup2(fd, 1) < 0 || dup2(fd, 2) < 0) _exit(126);
    close(fd);
  }
  execve(path, argv, environ);
  _exit(127);
}

static pid_t spawn_server_cfg(unsigned domain, double rate, const char *extra_phantom_keys);
static pid_t spawn_server(unsigned domain, double rate) { return spawn_server_cfg(domain, rate, ""); }
static pid_t spawn_server_cfg(unsigned domain, double rate, const char *extra_phantom_keys) {
  char d[16], r[32], t[16], m[16], pr[16];
  snprintf(pr, sizeof pr, "%d", rt_priority);
  snprintf(d, sizeof d, "%u", domain);
  snprintf(r, sizeof r, "%g", rate);
  snprintf(t, sizeof t, "%d", threads);
  snprintf(m, sizeof m, "%d", max_sessions);
  /* The shipped phantoms, logging to a scratch database (the real server's cost,
   * without touching the class's session log). */
  char cfg_path[600], db_path[600], log_path[600];
  if (!bench_tmp_path("palp-bench-server", "server.json", cfg_path, sizeof cfg_path)) exit(1);
  bench_tmp_path("palp-bench-server", "sessions.db", db_path, sizeof db_path);
  bench_tmp_path("palp-bench-server", "server.log", log_path, sizeof log_path);
  remove(db_path);
  FILE *cf = fopen(cfg_path, "w");
  if (!cf) {
    fprintf(stderr, "bench: cannot write %s\n", cfg_path);
    exit(1);
  }
  fprintf(cf,
          "{\"database\": \"%s\", \"dds_config\": \"%s\",\n"
          " \"phantoms\": [{\"id\": 1, \"name\": \"bench A\", \"scene\": \"%s\"%s},\n"
          "              {\"id\": 2, \"name\": \"bench B\", \"scene\": \"%s\"%s}]}\n",
          db_path, PALP_DDS_DEFAULT_CONFIG, scene_path, extra_phantom_keys, scene_path, extra_phantom_keys);
  fclose(cf);
  char *argv[20] = {PALP_SERVER_PATH, "--config", (char *)cfg_path, "--domain", d, "--tick-rate", r,
                    "--threads", t, "--max-sessions", m, "--rt-priority", pr};
  int argc = 13;
  if (secure) {
    argv[argc++] = "--pki";
    argv[argc++] = bench_pki;
  }
  if (no_db) argv[argc++] = "--no-db";
  argv[argc] = NULL;
  /* The server's own log goes to a file; the bench prints its figures. */
  const pid_t pid = spawn_tied(PALP_SERVER_PATH, argv, log_path);
  if (pid < 0) {
    fprintf(stderr, "bench: cannot start %s\n", PALP_SERVER_PATH);
    exit(1);
  }
  return pid;
}

static void stop_child(pid_t pid) {
  kill(pid, SIGINT);
  int st;
  waitpid(pid, &st, 0);
}

/* The server ended, or sent no status with new ticks in ten tries: say so with the end of its
 * log (its scratch directory is removed at exit, so the log is printed here) and exit 1. A loop
 * that waited for a dead server's status never ended (until session 82). */
static void server_failed(pid_t srv, int ended, int st, const char *why) {
  if (ended)
    fprintf(stderr, "bench: palp-server ended (%s %d) %s; the end of its log:\n",
            WIFEXITED(st) ? "exit" : "signal", WIFEXITED(st) ? WEXITSTATUS(st) : WTERMSIG(st), why);
  else {
    fprintf(stderr, "bench: %s; the end of palp-server's log:\n", why);
    stop_child(srv);
  }
  char log_path[600];
  FILE *lf = bench_tmp_path("palp-bench-server", "server.log", log_path, sizeof log_path) ? fopen(log_path, "r") : NULL;
  if (lf) {
    char buf[2048];
    if (fseek(lf, -(long)(sizeof buf - 1), SEEK_END) != 0) rewind(lf);
    const size_t n = fread(buf, 1, sizeof buf - 1, lf);
    buf[n] = 0;
    fprintf(stderr, "%s\n", buf);
    fclose(lf);
  }
  exit(1);
}

/* 0, or -1 with the reason in err (the station closed). */
static int join_as(palp_cli_station *st, unsigned domain, const char *label, uint32_t phantom, int local_models_only,
                   char *err, size_t errlen) {
  if (palp_cli_station_open_secure(st, domain, label, secure ? &bench_sec : NULL, err, errlen) < 0) return -1;
  palp_cli_join j = {.role = palp_ROLE_TRAINEE, .phantom_id = phantom, .user_name = secure ? NULL : label,
                     .want_feedback = 1, .local_models_only = local_models_only,
                     .timeout = 15};
  if (palp_cli_station_join(st, &j, err, errlen) < 0) {
    palp_cli_station_close(st);
    return -1;
  }
  /* Measure only once the server reads this station's contacts: secured
   * endpoints match after their crypto tokens are exchanged, which takes longer. */
  int64_t end = palp_dds_now_ns() + 10000000000LL;
  dds_instance_handle_t h[4];
  while (dds_get_matched_subscriptions(st->contact_w, h, 4) < 1 && palp_dds_now_ns() < end) nap(0.01);
  return 0;
}

static void join_or_die_as(palp_cli_station *st, unsigned domain, const char *label, uint32_t phantom,
                           int local_models_only) {
  char err[512];
  if (join_as(st, domain, label, phantom, local_models_only, err, sizeof err) < 0) {
    fprintf(stderr, "bench: %s: %s\n", label, err);
    exit(1);
  }
}

static void join_or_die(palp_cli_station *st, unsigned domain, const char *label, uint32_t phantom) {
  join_or_die_as(st, domain, label, phantom, 0);
}

static void fill_contact(palp_Contact *c, uint32_t session, uint64_t seq, double force) {
  palp_vec3 n;
  palp_vec3 p = palp_cli_dome_point(0.04, 25, 60, &n);
  memset(c, 0, sizeof *c);
  c->session_id = session;
  c->seq = seq;
  c->mode = palp_CONTACT_FORCE;
  c->distribution = 3;
  c->vertex = -1;
  c->center = (palp_Vec3){p.x, p.y, p.z};
  c->force = (palp_Vec3){-force * n.x, -force * n.y, -force * n.z};
  c->source_time_ns = palp_dds_now_ns();
}

/* ---- 1. contact -> feedback latency ------------------------------------------------------ */

static stats latency_run(double rate) {
  pid_t srv = spawn_server(lat_domain(), rate);
  palp_cli_station st;
  join_or_die(&st, lat_domain(), "bench-latency", 1);
  dds_entity_t ws = dds_create_waitset(st.pp);
  dds_entity_t rc = dds_create_readcondition(st.feedback_r, DDS_ANY_STATE);
  dds_waitset_attach(ws, rc, 0);
  size_t cap = (size_t)(seconds * rate * 2) + 16, n = 0;
  double *lat = malloc(cap * sizeof *lat);
  int64_t *sent_at = calloc(cap + 1, sizeof *sent_at);
  const double period = 1.0 / rate;
  uint64_t seq = 0, echoed = 0;
  int64_t t0 = palp_dds_now_ns(), warm = t0 + 1000000000, end = warm + (int64_t)(seconds * 1e9);
  int64_t next = t0;
  unsigned rng = 12345;
  while (palp_dds_now_ns() < end && seq < cap) {
    int64_t now = palp_dds_now_ns();
    if (now >= next) {
      palp_Contact c;
      /* 2 N +- 0.5 N so every sample is a new command */
      seq++;
      fill_contact(&c, st.session_id, seq, 2.0 + 0.5 * sin((double)seq * 0.1));
      sent_at[seq] = c.source_time_ns;
      dds_write(st.contact_w, &c);
      rng = rng * 1103515245u + 12345u;
      double jitter = 0.5 + (double)((rng >> 8) & 0xffff) / 65535.0; /* [0.5, 1.5] */
      next = now + (int64_t)(jitter * period * 1e9);
    }
    int64_t wait = next - palp_dds_now_ns();
    dds_waitset_wait(ws, NULL, 0, wait > 0 ? wait : 0);
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(st.feedback_r, ptr, &info, 1, 1) > 0) {
      int64_t rx = palp_dds_now_ns();
      const palp_Feedback *fb = ptr[0];
      if (info.valid_data)
        for (uint32_t k = 0; k < fb->fingers._length; k++) {
          const palp_FingerFeedback *ff = &fb->fingers._buffer[k];
          if (ff->finger != 0 || ff->contact_seq <= echoed || ff->contact_seq > seq) continue;
          /* every sequence superseded before a tick took it is skipped, not counted */
          echoed = ff->contact_seq;
          if (sent_at[echoed] >= warm && n < cap) lat[n++] = (double)(rx - sent_at[echoed]) * 1e-3;
        }
      dds_return_loan(st.feedback_r, ptr, 1);
    }
  }
  dds_delete(rc);
  dds_delete(ws);
  palp_cli_station_leave(&st);
  nap(0.1);
  palp_cli_station_close(&st);
  stop_child(srv);
  stats s = summarize(lat, n);
  free(lat);
  free(sent_at);
  return s;
}

/* ---- 2. plain DDS round trip ------------------------------------------------------------------- */

/* Child: takes palp_Contact on "palp_bench_ping", answers a palp_Feedback echoing it on "palp_bench_pong". */
static int echo_main(void) {
  dds_entity_t pp = dds_create_participant(rtt_domain(), NULL, NULL);
  dds_qos_t *qc = palp_dds_qos(PALP_TOPIC_CONTACT), *qf = palp_dds_qos(PALP_TOPIC_FEEDBACK);
  dds_entity_t tping = dds_create_topic(pp, &palp_Contact_desc, "palp_bench_ping", qc, NULL);
  dds_entity_t tpong = dds_create_topic(pp, &palp_Feedback_desc, "palp_bench_pong", qf, NULL);
  dds_entity_t r = dds_create_reader(pp, tping, qc, NULL);
  dds_entity_t w = dds_create_writer(pp, tpong, qf, NULL);
  dds_entity_t ws = dds_create_waitset(pp);
  dds_entity_t rc = dds_create_readcondition(r, DDS_ANY_STATE);
  dds_waitset_attach(ws, rc, 0);
  palp_FingerFeedback ff[1];
  palp_Feedback fb;
  memset(&fb, 0, sizeof fb);
  memset(ff, 0, sizeof ff);
  fb.fingers._buffer = ff;
  fb.fingers._maximum = fb.fingers._length = 1;
  int64_t idle_until = palp_dds_now_ns() + 30000000000LL;
  while (palp_dds_now_ns() < idle_until) {
    dds_waitset_wait(ws, NULL, 0, DDS_MSECS(100));
    palp_Contact c;
    void *ptr[1] = {&c};
    dds_sample_info_t info;
    while (dds_take(r, ptr, &info, 1, 1) > 0) {
      if (!info.valid_data) continue;
      if (c.seq == UINT64_MAX) idle_until = 0; /* done */
      fb.session_id = c.session_id;
      ff[0].contact_seq = c.seq;
      ff[0].contact_source_time_ns = c.source_time_ns;
      ff[0].force = c.force;
      dds_write(w, &fb);
    }
  }
  dds_delete_qos(qc);
  dds_delete_qos(qf);
  dds_delete(pp);
  return 0;
}

static stats rtt_run(double rate, const char *self) {
  char base[16]; /* the echo child answers on this run's round-trip domain */
  snprintf(base, sizeof base, "%u", domain_base);
  char *argv[] = {(char *)self, "echo", "--domain-base", base, NULL};
  const pid_t pid = spawn_tied(self, argv, NULL);
  if (pid < 0) exit(1);
  dds_entity_t pp = dds_create_participant(rtt_domain(), NULL, NULL);
  dds_qos_t *qc = palp_dds_qos(PALP_TOPIC_CONTACT), *qf = palp_dds_qos(PALP_TOPIC_FEEDBACK);
  dds_entity_t tping = dds_create_topic(pp, &palp_Contact_desc, "palp_bench_ping", qc, NULL);
  dds_entity_t tpong = dds_create_topic(pp, &palp_Feedback_desc, "palp_bench_pong", qf, NULL);
  dds_entity_t w = dds_create_writer(pp, tping, qc, NULL);
  dds_entity_t r = dds_create_reader(pp, tpong, qf, NULL);
  dds_entity_t ws = dds_create_waitset(pp);
  dds_entity_t rc = dds_create_readcondition(r, DDS_ANY_STATE);
  dds_waitset_attach(ws, rc, 0);
  /* wait for the echo to match both ways */
  dds_publication_matched_status_t pm = {0};
  dds_subscription_matched_status_t sm = {0};
  for (int i = 0; i < 500 && (pm.current_count == 0 || sm.current_count == 0); i++) {
    dds_get_publication_matched_status(w, &pm);
    dds_get_subscription_matched_status(r, &sm);
    nap(0.01);
  }
  size_t cap = (size_t)(seconds * rate) + 16, n = 0;
  double *lat = malloc(cap * sizeof *lat);
  uint64_t seq = 0;
  int64_t t0 = palp_dds_now_ns(), warm = t0 + 500000000, end = warm + (int64_t)(seconds * 1e9);
  while (palp_dds_now_ns() < end && n < cap) {
    int64_t next = palp_dds_now_ns() + (int64_t)(1e9 / rate);
    palp_Contact c;
    fill_contact(&c, 1, ++seq, 2.0);
    dds_write(w, &c);
    for (;;) {
      int64_t left = next - palp_dds_now_ns();
      if (left <= 0) break;
      dds_waitset_wait(ws, NULL, 0, left);
      void *ptr[1] = {NULL};
      dds_sample_info_t info;
      while (dds_take(r, ptr, &info, 1, 1) > 0) {
        const palp_Feedback *f = ptr[0];
        int64_t rx = palp_dds_now_ns();
        if (info.valid_data && f->fingers._length == 1 && f->fingers._buffer[0].contact_seq == seq &&
            f->fingers._buffer[0].contact_source_time_ns >= warm)
          lat[n++] = (double)(rx - f->fingers._buffer[0].contact_source_time_ns) * 1e-3;
        dds_return_loan(r, ptr, 1);
      }
    }
  }
  palp_Contact done;
  fill_contact(&done, 1, UINT64_MAX, 0);
  for (int i = 0; i < 3; i++) {
    dds_write(w, &done);
    nap(0.01);
  }
  dds_delete_qos(qc);
  dds_delete_qos(qf);
  dds_delete(pp);
  int st;
  waitpid(pid, &st, 0);
  stats s = summarize(lat, n);
  free(lat);
  return s;
}

/* ---- 3. capacity -------------------------------------------------------------------------------- */

typedef struct status_window {
  uint64_t ticks, overruns;
  uint64_t steps, late; /* summed over the sessions (SessionLoad): their steps, and those late or missed */
  double p99, max, load;
  uint32_t open;
  int ok;
} status_window;

static status_window read_status(dds_entity_t r, double wait) {
  status_window w = {0};
  int64_t end = palp_dds_now_ns() + (int64_t)(wait * 1e9);
  while (palp_dds_now_ns() < end && !w.ok) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(r, ptr, &info, 1, 1) > 0) {
      const palp_ServerStatus *s = ptr[0];
      if (info.valid_data) {
        w = (status_window){s->ticks, s->overruns, 0, 0, s->tick_us_p99, s->tick_us_max, s->load, s->sessions_open, 1};
        for (uint32_t k = 0; k < s->sessions._length; k++) {
          w.steps += s->sessions._buffer[k].ticks;
          w.late += s->sessions._buffer[k].overruns;
        }
      }
      dds_return_loan(r, ptr, 1);
    }
    nap(0.02);
  }
  return w;
}

static void press_all(palp_cli_station *st, int n, uint64_t *seq, double t) {
  for (int i = 0; i < n; i++) {
    palp_Contact c;
    /* 1.5 N +- 1 N at 0.7 Hz: the world keeps moving, never sleeps */
    fill_contact(&c, st[i].session_id, ++seq[i], 1.5 + sin(2 * 3.14159265 * 0.7 * t + i));
    dds_write(st[i].contact_w, &c);
  }
}

static void drain_all(palp_cli_station *st, int n) {
  for (int i = 0; i < n; i++) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(st[i].feedback_r, ptr, &info, 1, 1) > 0) dds_return_loan(st[i].feedback_r, ptr, 1);
  }
}

static void capacity_run(void) {
  pid_t srv = spawn_server(cap_domain(), 1000);
  palp_cli_station *st = calloc((size_t)max_sessions, sizeof *st);
  uint64_t *seq = calloc((size_t)max_sessions, sizeof *seq);
  char err[256];
  palp_cli_station mon;
  if (palp_cli_station_open_secure(&mon, cap_domain(), "bench-monitor", secure ? &bench_sec : NULL, err, sizeof err) < 0) {
    fprintf(stderr, "bench: %s\n", err);
    exit(1);
  }
  dds_entity_t status_r = palp_dds_create_reader(mon.pp, mon.topic[PALP_TOPIC_SERVER_STATUS], PALP_TOPIC_SERVER_STATUS);
  static const int steps[] = {1, 2, 4, 8, 10, 12, 14, 16, 20, 24, 28, 32, 36, 40, 44, 48, 56, 64};
  int n = 0, held = 0;
  printf("capacity: 1 kHz sessions on %d tick thread(s); stations press at %.0f Hz; window 2 s per step\n", threads,
         contact_rate);
  printf("  sessions  overrun%%  tick p99 [us]  tick max [us]  load\n");
  int64_t t0 = palp_dds_now_ns();
  for (size_t k = 0; k < sizeof steps / sizeof steps[0] && steps[k] <= max_sessions; k++) {
    while (n < steps[k]) {
      char label[32];
      snprintf(label, sizeof label, "bench-%02d", n);
      join_or_die(&st[n], cap_domain(), label, (uint32_t)(1 + n % 2));
      n++;
    }
    /* settle 1 s, then a 2 s window between two status samples */
    int64_t settle = palp_dds_now_ns() + 1000000000, next = palp_dds_now_ns();
    status_window a = {0}, b = {0};
    int64_t window_end = 0;
    int reads = 0; /* status reads for this window: at most 10 (1.5 s each) */
    for (;;) {
      int wst;
      if (waitpid(srv, &wst, WNOHANG) == srv) server_failed(srv, 1, wst, "during a capacity window");
      if (reads > 10) server_failed(srv, 0, 0, "no status with new ticks from palp-server in 10 tries");
      int64_t now = palp_dds_now_ns();
      if (now >= next) {
        press_all(st, n, seq, (double)(now - t0) * 1e-9);
        next += (int64_t)(1e9 / contact_rate);
      }
      drain_all(st, n);
      if (now >= settle && !a.ok) {
        a = read_status(status_r, 1.5), ++reads;
        window_end = palp_dds_now_ns() + 2000000000;
      }
      if (a.ok && now >= window_end) {
        /* first status published after the window ends */
        b = read_status(status_r, 1.5), ++reads;
        if (b.ok && b.ticks > a.ticks) break;
        window_end = palp_dds_now_ns() + 200000000;
      }
      nap(0.001);
    }
    double frac = (double)(b.overruns - a.overruns) / (double)(b.ticks - a.ticks);
    printf("  %8d  %7.2f%%  %13.0f  %13.0f  %4.0f%%\n", n, 100 * frac, b.p99, b.max, 100 * b.load);
    fflush(stdout);
    if (frac > overrun_limit) break;
    held = n;
  }
  printf("capacity%s: %d concurrent 1 kHz sessions held with <= %g%% overrun ticks (target 32 at 1%%)\n",
         secure ? " (DDS Security on)" : "", held, 100 * overrun_limit);
  for (int i = 0; i < n; i++) palp_cli_station_leave(&st[i]);
  nap(0.2);
  for (int i = 0; i < n; i++) palp_cli_station_close(&st[i]);
  palp_cli_station_close(&mon);
  stop_child(srv);
  free(st);
  free(seq);
}

/* ---- 4. haptic capacity ------------------------------------------------------------------------- */

/* CPU seconds the process pid has used (user + system, its threads together), from
 * /proc/PID/stat; -1 when unreadable. The server's own share of the two cores, apart
 * from this process's stations, which share them here and would not on a lab's server. */
static double proc_cpu_s(pid_t pid) {
  char path[64], buf[1024];
  snprintf(path, sizeof path, "/proc/%d/stat", (int)pid);
  FILE *fp = fopen(path, "r");
  if (!fp) return -1;
  const size_t n = fread(buf, 1, sizeof buf - 1, fp);
  fclose(fp);
  buf[n] = 0;
  const char *p = strrchr(buf, ')'); /* the command name may hold spaces */
  unsigned long long ut = 0, st = 0;
  if (!p || sscanf(p + 2, "%*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %llu %llu", &ut, &st) != 2) return -1;
  return (double)(ut + st) / (double)sysconf(_SC_CLK_TCK);
}

typedef struct farm {
  palp_cli_station *st;
  palp_haptic *h;
  int n;              /* sessions the thread serves (grows under the lock) */
  double physics_hz;
  pthread_mutex_t lock;
  volatile int stop;
  uint64_t ticks, late, models;
  uint64_t *seq;
} farm;

/* Device of session i at t: press cycles 0..10 mm at the pole region, phase-shifted
 * (--motion strip: palp_bench_strip_device). */
static palp_vec3 farm_device(int i, double t) {
  if (strip_motion) return palp_bench_strip_device(i, t);
  const double R = 0.04, r = 0.008;
  const double depth = 0.005 * (1 - cos(2 * 3.14159265 * 0.7 * t + i)); /* 0..10 mm */
  const double a = 0.3 * i;
  const palp_vec3 n = {0.2 * cos(a), 0.2 * sin(a), sqrt(1 - 0.04)};
  const double h = R + r - depth + 0.001;
  return (palp_vec3){n.x * h, n.y * h, n.z * h};
}

static void *farm_main(void *arg) {
  farm *f = arg;
  const int64_t period = 1000000; /* 1 kHz */
  const int every = (int)lround(1000.0 / f->physics_hz) > 0 ? (int)lround(1000.0 / f->physics_hz) : 1;
  int64_t next = palp_dds_now_ns();
  const int64_t t0 = next;
  for (uint64_t tick = 0; !f->stop; tick++) {
    next += period;
    struct timespec ts = {.tv_sec = (time_t)(next / 1000000000), .tv_nsec = (long)(next % 1000000000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) != 0) {
    }
    const int64_t now = palp_dds_now_ns();
    f->ticks++;
    if (now - next > 500000) f->late++;
    if (now - next > period) next = now;
    const double t = (double)(now - t0) * 1e-9;
    pthread_mutex_lock(&f->lock);
    for (int i = 0; i < f->n; i++) {
      /* models in (the DDS side, done here: one thread serves every station) */
      void *ptr[1] = {NULL};
      dds_sample_info_t info;
      while (dds_take(f->st[i].local_model_r, ptr, &info, 1, 1) > 0) {
        palp_local_model m;
        if (info.valid_data && palp_cli_local_model_from_wire(ptr[0], &m) == 0 && palp_haptic_update(&f->h[i], &m, t) > 0)
          f->models++;
        dds_return_loan(f->st[i].local_model_r, ptr, 1);
      }
      while (f->st[i].feedback_r > 0 && dds_take(f->st[i].feedback_r, ptr, &info, 1, 1) > 0)
        dds_return_loan(f->st[i].feedback_r, ptr, 1);
      const palp_vec3 x = farm_device(i, t);
      palp_haptic_out o;
      palp_haptic_render(&f->h[i], x, t, &o);
      if ((tick + (uint64_t)i) % (uint64_t)every == 0) {
        palp_Contact c;
        memset(&c, 0, sizeof c);
        c.session_id = f->st[i].session_id;
        c.mode = palp_CONTACT_FINGER;
        c.vertex = -1;
        c.center = (palp_Vec3){x.x, x.y, x.z};
        c.radius = 0.008;
        c.seq = ++f->seq[i];
        c.source_time_ns = now;
        dds_write(f->st[i].contact_w, &c);
      }
    }
    pthread_mutex_unlock(&f->lock);
  }
  return NULL;
}

/* The model's own step with a pressed finger at dt, timed here (same-run baseline). */
static double baseline_rebuilds_per_s; /* the baseline world's tangent rebuilds per simulated second */
static stats step_baseline(double rate) {
  palp_scene sc;
  char err[256];
  /* every return code checked: a world that refuses to step "steps" in under a microsecond and
   * would be printed as the baseline (until session 82 a failed create was dereferenced) */
  if (palp_scene_load(scene_path, &sc, err, sizeof err) < 0) {
    fprintf(stderr, "bench: the baseline's scene %s: %s\n", scene_path, err);
    exit(1);
  }
  sc.world.dt = 1.0 / rate;
  int rc;
  palp_world *w = palp_scene_create_world(&sc, &rc);
  if (!w) {
    fprintf(stderr, "bench: the baseline's world: %s\n", palp_strerror(rc));
    exit(1);
  }
  for (int i = 0; i < sc.contact_count; i++) palp_world_remove_contact(w, i);
  const int f = palp_world_add_finger(w, farm_device(0, 0), 0.008);
  if (f < 0) {
    fprintf(stderr, "bench: the baseline's finger: %s\n", palp_strerror(f));
    exit(1);
  }
  enum { N = 2000 };
  static double us[N];
  for (int k = 0; k < N; k++) {
    rc = palp_world_set_finger(w, f, farm_device(0, k / rate), 0.008);
    const int64_t a = palp_dds_now_ns();
    if (rc >= 0) rc = palp_world_step(w);
    us[k] = (double)(palp_dds_now_ns() - a) * 1e-3;
    if (rc < 0) {
      fprintf(stderr, "bench: the baseline's step %d: %s\n", k, palp_strerror(rc));
      exit(1);
    }
  }
  palp_stage_timings tm;
  palp_world_timings(w, &tm);
  baseline_rebuilds_per_s = (double)tm.refactors * rate / N;
  palp_world_destroy(w);
  return summarize(us, N);
}

static void haptic_run(double rate) {
  char extra[64];
  snprintf(extra, sizeof extra, ", \"physics_rate_hz\": %g", rate);
  pid_t srv = spawn_server_cfg(hap_domain(), 100, extra);
  farm f = {.physics_hz = rate};
  f.st = calloc((size_t)max_sessions, sizeof *f.st);
  f.h = calloc((size_t)max_sessions, sizeof *f.h);
  f.seq = calloc((size_t)max_sessions, sizeof *f.seq);
  pthread_mutex_init(&f.lock, NULL);
  char err[256];
  palp_cli_station mon;
  if (palp_cli_station_open_secure(&mon, hap_domain(), "bench-monitor", secure ? &bench_sec : NULL, err, sizeof err) < 0)
    exit(1);
  dds_entity_t status_r = palp_dds_create_reader(mon.pp, mon.topic[PALP_TOPIC_SERVER_STATUS], PALP_TOPIC_SERVER_STATUS);
  pthread_t th;
  pthread_create(&th, NULL, farm_main, &f);
  /* The machine's own floor for the late-step criterion (app/palp_timer_floor.h): a thread
   * at the ticks' priority sleeping to the physics deadlines. The server counts a step late
   * when its tick's work ends after the next tick should start; for a thread with no work
   * that is a wake-up more than a period late, which only the machine can cause. */
  const int64_t period_ns = (int64_t)(1e9 / rate + 0.5);
  palp_timer_floor fl;
  palp_timer_floor_start(&fl, period_ns, period_ns, palp_dds_now_ns(), rt_priority);
  const int fl_rt = fl.rt_ok;
  static const int steps[] = {1, 2, 4, 8, 16, 24, 32, 40, 48, 56, 64, 72, 80, 96};
  const stats base = step_baseline(rate);
  printf("haptic capacity: physics at %.0f Hz on %d tick thread(s), stations rendering at 1 kHz (one haptic thread "
         "here serves them all); devices %s; scene %s; window 2 s per step\n", rate, threads,
         strip_motion ? "searching in vertical strips at 3 / 9 / 16 mm (--motion strip)" : "pressing 0-10 mm at 0.7 Hz",
         scene_path);
  printf("  baseline, same run: the model's step with a pressed finger: p50 %.0f us, p99 %.0f us (its tangent rebuilt "
         "%.1f times a simulated second, at once: the server defers them to helpers)\n", base.p50, base.p99,
         baseline_rebuilds_per_s);
  printf("  (timer floor: a thread at the ticks' priority%s that only sleeps to the physics rate's deadlines; its wake-ups "
         "more than a period late, and the deadlines they dropped, are what the machine alone makes of the late-step "
         "criterion)\n",
         rt_priority <= 0 ? " (normal scheduling)" : fl_rt ? " (SCHED_FIFO)" : " (SCHED_FIFO refused: normal)");
  printf("  (late steps: the sessions' physics steps that ended after the next tick's start, or were missed behind "
         "schedule, over their steps; group ticks: the tick threads' passes whose work ended late)\n");
  printf("  (server cores: the server process's CPU seconds per second over the window, all its threads: ticks, "
         "helpers, DDS, the session log)\n");
  printf("  sessions  late steps  group ticks  tick p99 [us]  tick max [us]  load  station late ticks  models/s  timer floor"
         "  server cores\n");
  double cores_per_session = 0; /* at the largest count of 4 or more sessions held */
  int n = 0, held = 0, held_passes = 0, n_prev = 0, join_failed = 0;
  for (size_t k = 0; k < sizeof steps / sizeof steps[0] && steps[k] <= max_sessions && !join_failed; k++) {
    while (n < steps[k]) {
      char label[32], jerr[512];
      snprintf(label, sizeof label, "haptic-%02d", n);
      /* as palp-client's position-driven trainee joins: local models, no Feedback reader. A join that
       * fails ends the run where it stands (with every station closed in order: exiting with DDS
       * Security's threads still encrypting crashed in OpenSSL). */
      if (join_as(&f.st[n], hap_domain(), label, (uint32_t)(1 + n % 2), 1, jerr, sizeof jerr) < 0) {
        printf("  (session %d could not join: %s; the run stops at %d)\n", n + 1, jerr, n);
        join_failed = 1;
        break;
      }
      palp_haptic_init(&f.h[n], NULL);
      pthread_mutex_lock(&f.lock);
      f.n = ++n;
      pthread_mutex_unlock(&f.lock);
    }
    if (join_failed) break;
    nap(1.0);
    status_window a = read_status(status_r, 1.5);
    const uint64_t t_a = f.ticks, l_a = f.late, m_a = f.models, ft_a = atomic_load(&fl.ticks), fl_a = atomic_load(&fl.late_ticks),
                   fm_a = atomic_load(&fl.missed);
    const int64_t w0 = palp_dds_now_ns();
    const double cpu0 = proc_cpu_s(srv);
    nap(2.0);
    status_window b = a;
    for (int tries = 0; tries < 10; tries++) {
      b = read_status(status_r, 1.5);
      if (b.ok && b.ticks > a.ticks) break;
    }
    const double span = (double)(palp_dds_now_ns() - w0) * 1e-9;
    const double cpu1 = proc_cpu_s(srv), srv_cores = cpu0 >= 0 && cpu1 >= 0 ? (cpu1 - cpu0) / span : NAN;
    const double gfrac = b.ticks > a.ticks ? (double)(b.overruns - a.overruns) / (double)(b.ticks - a.ticks) : 1;
    const double frac = b.steps > a.steps ? (double)(b.late - a.late) / (double)(b.steps - a.steps) : 1;
    const double late = f.ticks > t_a ? (double)(f.late - l_a) / (double)(f.ticks - t_a) : 1;
    const uint64_t ft_b = atomic_load(&fl.ticks), fl_b = atomic_load(&fl.late_ticks), fm_b = atomic_load(&fl.missed);
    /* counted as the sessions' late steps are: a dropped deadline is a late one */
    const double floor_late =
        ft_b > ft_a ? (double)(fl_b - fl_a + fm_b - fm_a) / (double)(ft_b - ft_a + fm_b - fm_a) : 0;
    printf("  %8d  %9.2f%%  %10.2f%%  %13.0f  %13.0f  %3.0f%%  %16.2f%%  %8.0f  %10.2f%%  %10.2f\n", n, 100 * frac,
           100 * gfrac, b.p99, b.max, 100 * b.load, 100 * late, (double)(f.models - m_a) / span, 100 * floor_late,
           srv_cores);
    if (n >= 4 && srv_cores > 0 && frac <= overrun_limit) cores_per_session = srv_cores / n;
    fflush(stdout);
    if (gfrac <= overrun_limit && held_passes == n_prev) held_passes = n;
    n_prev = n;
    if (frac > overrun_limit) break;
    held = n;
  }
  printf("haptic capacity: %d sessions held at %.0f Hz physics with <= %g%% late physics steps (target %d)\n", held, rate,
         100 * overrun_limit, rate <= 250 ? 64 : 32);
  if (cores_per_session > 0)
    printf("  (the server alone used %.3f of a core per session at the largest count held: two cores of its own, "
           "stations elsewhere, would give it room for ~%.0f sessions at 100%% of both, a projection, not a hold)\n",
           cores_per_session, 2.0 / cores_per_session);
  if (cores_per_session > 0 && base.mean > 0) /* the same-run baseline as a ratio (session 82) */
    printf("  (the server's core per session over the baseline model step's own, mean %.0f us x %.0f Hz = %.3f of a core: "
           "x%.2f)\n", base.mean, rate, base.mean * 1e-6 * rate, cores_per_session / (base.mean * 1e-6 * rate));
  printf("  (by the tick passes' share alone, this benchmark's criterion until 2026-12-02, which neither counts the slots "
         "a pass that fell behind dropped nor tells one session's late step from its group's: %d, up to where this run "
         "stopped)\n", held_passes);
  f.stop = 1;
  pthread_join(th, NULL);
  palp_timer_floor_stop(&fl);
  for (int i = 0; i < n; i++) palp_cli_station_leave(&f.st[i]);
  nap(0.2);
  for (int i = 0; i < n; i++) palp_cli_station_close(&f.st[i]);
  palp_cli_station_close(&mon);
  stop_child(srv);
  free(f.st);
  free(f.h);
  free(f.seq);
}

int main(int argc, char **argv) {
  const char *what = "all";
  int compare_secure = 0;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--seconds") && i + 1 < argc) seconds = atof(argv[++i]);
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--max") && i + 1 < argc) max_sessions = atoi(argv[++i]), max_given = 1;
    else if (!strcmp(argv[i], "--contact-rate") && i + 1 < argc) contact_rate = atof(argv[++i]);
    else if (!strcmp(argv[i], "--rt-priority") && i + 1 < argc) rt_priority = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--no-db")) no_db = 1;
    else if (!strcmp(argv[i], "--secure")) compare_secure = 1;
    else if (!strcmp(argv[i], "--overrun-limit") && i + 1 < argc) overrun_limit = atof(argv[++i]) / 100.0;
    else if (!strcmp(argv[i], "--scene") && i + 1 < argc) {
      /* The server resolves a relative scene against its config file's folder (the work
       * directory here), so hand it the absolute path of the file the user named. */
      static char abs_scene[4096];
      scene_path = realpath(argv[++i], abs_scene) ? abs_scene : argv[i];
    }
    else if (!strcmp(argv[i], "--haptic-domain") && i + 1 < argc) haptic_domain = (unsigned)atoi(argv[++i]);
    else if (!strcmp(argv[i], "--domain-base") && i + 1 < argc) {
      char *end;
      const long v = strtol(argv[++i], &end, 10);
      if (*end || end == argv[i] || v < 0 || v > 227) { /* B+5 within Cyclone's 0-232; 0: the defaults */
        fprintf(stderr, "bench_server: --domain-base must be a whole number from 1 to 227, or 0 for the defaults (got \"%s\")\n", argv[i]);
        return 2;
      }
      domain_base = (unsigned)v;
    }
    else if (!strcmp(argv[i], "--motion") && i + 1 < argc && (!strcmp(argv[i + 1], "strip") || !strcmp(argv[i + 1], "press")))
      strip_motion = !strcmp(argv[++i], "strip");
    else if (!strcmp(argv[i], "--rate") && i + 1 < argc && atof(argv[i + 1]) > 0) only_rate = atof(argv[++i]);
    else if (argv[i][0] != '-') what = argv[i];
    else {
      fprintf(stderr, "usage: bench_server [latency|rtt|capacity|haptic|all] [--seconds S] [--threads N] [--max N] "
                      "[--contact-rate HZ] [--rt-priority N] [--no-db] [--scene FILE] [--secure] [--overrun-limit PCT] "
                      "[--haptic-domain ID] [--domain-base B] [--motion press|strip] [--rate HZ]\n");
      return 2;
    }
  }
  /* The loopback config for this process's participants too, whatever the caller exported: the
   * server it starts always runs on it, and a lab's CYCLONEDDS_URI put the bench's own
   * participants on the lab network, where the server is not (kept until session 82). */
  const char *lab = getenv("CYCLONEDDS_URI");
  if (lab && *lab && strcmp(what, "echo")) fprintf(stderr, "bench_server: CYCLONEDDS_URI ignored: the benchmark runs on loopback\n");
  unsetenv("CYCLONEDDS_URI");
  if (palp_dds_use_config(PALP_DDS_DEFAULT_CONFIG) < 0) {
    fprintf(stderr, "bench: cannot read %s\n", PALP_DDS_DEFAULT_CONFIG);
    return 1;
  }
  if (!strcmp(what, "echo")) return echo_main();
  if (!bench_tmp_path("palp-bench-server", "pki", bench_pki, sizeof bench_pki)) return 1;
  if (compare_secure) {
    char cmd[1024], err[512];
    snprintf(cmd, sizeof cmd, "bash '%s/../scripts/make-classroom-pki.sh' %s classroom --trainees bench >/dev/null",
             PALP_CONFIG_DIR, bench_pki);
    if (system(cmd) != 0 || palp_dds_security_init(&bench_sec, bench_pki, "trainee/bench", err, sizeof err) < 0) {
      fprintf(stderr, "bench: cannot make the classroom PKI in %s\n", bench_pki);
      return 1;
    }
  }
  int all = !strcmp(what, "all");
  for (secure = 0; secure <= compare_secure; secure++) {
  if (compare_secure) printf("\n==== DDS Security %s ====\n", secure ? "ON (authenticated, signed RTPS, encrypted data)" : "off");
  if (all || !strcmp(what, "latency") || (!strcmp(what, "rtt") && !secure)) {
    printf("contact -> feedback latency over DDS (palp-server in its own process), %.0f s per rate\n", seconds);
    printf("  %-34s %9s %9s %9s %9s %7s\n", "", "p50[us]", "p99[us]", "max[us]", "mean[us]", "n");
    for (int k = 0; k < 2; k++) {
      double rate = k ? 1000.0 : 100.0;
      stats s = {NAN, NAN, NAN, NAN, 0};
      if (all || !strcmp(what, "latency")) {
        s = latency_run(rate);
        printf("  contact->feedback at %4.0f Hz ticks   %9.0f %9.0f %9.0f %9.0f %7zu\n", rate, s.p50, s.p99, s.max,
               s.mean, s.n);
      }
      if (secure) continue; /* the round trip's bench topics are in no permissions document */
      stats b = rtt_run(rate, argv[0]);
      printf("  plain DDS round trip, %4.0f Hz sends %9.0f %9.0f %9.0f %9.0f %7zu\n", rate, b.p50, b.p99, b.max, b.mean,
             b.n);
      /* the same-run baseline as a ratio (session 82): what the server's tick and step add to two DDS hops */
      if (s.n && b.n)
        printf("  contact->feedback / round trip       %9.2f %9.2f\n", s.p50 / b.p50, s.p99 / b.p99);
      fflush(stdout);
    }
    printf("  (target: p99 < 3000 us at 1 kHz; the tick adds up to one period of waiting, mean half a period)\n");
  }
  if (all || !strcmp(what, "capacity")) capacity_run();
  if ((!secure || !all) && (all || !strcmp(what, "haptic"))) { /* haptic --secure: off, then on */
    if (!max_given) max_sessions = 96;
    if (only_rate > 0) haptic_run(only_rate);
    else {
      haptic_run(250);
      haptic_run(1000);
    }
  }
  }
  return 0;
}
