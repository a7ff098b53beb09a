/* harness.c - in-process server and station helpers for the server tests. */
#include "harness.h"

#include <math.h>
#include <string.h>
#include <time.h>

#include "input.h"
#include "../proc_rss.h"

int palp_test_failures;
int palp_test_last;

void test_sleep(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
  while (nanosleep(&ts, &ts) != 0) {
  }
}

void test_init(void) {
  if (palp_dds_use_config(PALP_DDS_DEFAULT_CONFIG) < 0) {
    fprintf(stderr, "cannot read %s\n", PALP_DDS_DEFAULT_CONFIG);
    exit(1);
  }
}

void test_config(palp_srv_config *cfg, unsigned domain, double tick_rate_hz) {
  char json[1024], err[512];
  snprintf(json, sizeof json,
           "{\"domain_id\": %u, \"tick_rate_hz\": %g, \"tick_threads\": 2, \"max_force\": 20,"
           " \"phantoms\": [{\"id\": 1, \"name\": \"test dome A\", \"scene\": \"paper_step.json\"},"
           "                {\"id\": 2, \"name\": \"test dome B\", \"scene\": \"paper_step.json\"}]}",
           domain, tick_rate_hz);
  if (palp_srv_config_parse(json, PALP_CONFIG_DIR, cfg, err, sizeof err) < 0) {
    fprintf(stderr, "test config: %s\n", err);
    exit(1);
  }
}

static void *server_main(void *arg) {
  test_server *ts = arg;
  palp_srv_run(ts->srv, 0);
  return NULL;
}

void test_server_start(test_server *ts, const palp_srv_config *cfg) {
  const palp_srv_def def = {.cfg = *cfg, .verbose = 1};
  test_server_start_def(ts, &def);
}

void test_server_start_def(test_server *ts, const palp_srv_def *def) {
  char err[512];
  int rc = 0;
  *ts = (test_server){0};
  ts->srv = palp_srv_create(def, &rc, err, sizeof err);
  if (!ts->srv) {
    fprintf(stderr, "server: %s\n", err);
    exit(1);
  }
  if (pthread_create(&ts->thread, NULL, server_main, ts) != 0) exit(1);
  ts->running = 1;
}

void test_server_stop(test_server *ts) {
  if (!ts->running) return;
  palp_srv_request_stop(ts->srv);
  pthread_join(ts->thread, NULL);
  palp_srv_print_summary(ts->srv, stderr);
  palp_srv_destroy(ts->srv);
  ts->running = 0;
}

void test_station_join_as(palp_cli_station *st, unsigned domain, const char *label, const palp_cli_join *j) {
  char err[512];
  if (palp_cli_station_open(st, domain, label, err, sizeof err) < 0 || palp_cli_station_join(st, j, err, sizeof err) < 0) {
    fprintf(stderr, "station %s: %s\n", label, err);
    exit(1);
  }
}

void test_station_join(palp_cli_station *st, unsigned domain, const char *label, int role, uint32_t phantom,
                       uint32_t session, int want_feedback, int want_deformation) {
  const palp_cli_join j = {.role = role, .phantom_id = phantom, .session_id = session, .user_name = label,
                           .want_feedback = want_feedback, .want_deformation = want_deformation, .timeout = 10};
  test_station_join_as(st, domain, label, &j);
}

void test_send_raw(palp_cli_station *st, const palp_Contact *c) { dds_write(st->contact_w, c); }

void test_send_force(palp_cli_station *st, int finger, int d, double polar, double azimuth, double force,
                     uint64_t seq) {
  palp_vec3 n;
  palp_vec3 p = palp_cli_dome_point(0.04, polar, azimuth, &n);
  palp_Contact c;
  memset(&c, 0, sizeof c);
  c.session_id = st->session_id;
  c.finger = (uint8_t)finger;
  c.seq = seq;
  c.source_time_ns = palp_dds_now_ns();
  c.mode = force > 0 ? palp_CONTACT_FORCE : palp_CONTACT_RELEASE;
  c.distribution = (uint8_t)d;
  c.vertex = -1;
  c.center = (palp_Vec3){p.x, p.y, p.z};
  c.force = (palp_Vec3){-force * n.x, -force * n.y, -force * n.z};
  dds_write(st->contact_w, &c);
}

void test_send_finger(palp_cli_station *st, double polar, double azimuth, double depth, uint64_t seq) {
  test_send_finger_r(st, polar, azimuth, depth, 0.008, seq);
}

void test_send_finger_r(palp_cli_station *st, double polar, double azimuth, double depth, double r, uint64_t seq) {
  const palp_vec3 c = palp_cli_dome_point(0.04 + r - depth, polar, azimuth, NULL);
  palp_Contact m;
  memset(&m, 0, sizeof m);
  m.session_id = st->session_id;
  m.finger = 0;
  m.seq = seq;
  m.source_time_ns = palp_dds_now_ns();
  m.mode = palp_CONTACT_FINGER;
  m.distribution = 1;
  m.vertex = -1;
  m.center = (palp_Vec3){c.x, c.y, c.z};
  m.radius = r;
  dds_write(st->contact_w, &m);
}

double test_last_feedback(palp_cli_station *st, double seconds, int *samples) {
  int64_t end = palp_dds_now_ns() + (int64_t)(seconds * 1e9);
  double last = 0;
  int n = 0;
  while (palp_dds_now_ns() < end) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(st->feedback_r, ptr, &info, 1, 1) > 0) {
      const palp_Feedback *fb = ptr[0];
      if (info.valid_data) {
        n++;
        for (uint32_t k = 0; k < fb->fingers._length; k++)
          if (fb->fingers._buffer[k].finger == 0) {
            palp_Vec3 f = fb->fingers._buffer[k].force;
            last = sqrt(f.x * f.x + f.y * f.y + f.z * f.z);
          }
      }
      dds_return_loan(st->feedback_r, ptr, 1);
    }
    test_sleep(0.002);
  }
  if (samples) *samples = n;
  return last;
}

int test_latest_guard(dds_entity_t r, double wait, palp_ServerGuard *out) {
  int64_t end = palp_dds_now_ns() + (int64_t)(wait * 1e9);
  int got = 0;
  while (palp_dds_now_ns() < end) {
    palp_ServerGuard g;
    void *ptr[1] = {&g};
    dds_sample_info_t info;
    while (dds_take(r, ptr, &info, 1, 1) > 0)
      if (info.valid_data) *out = g, got = 1;
    if (got) return 1;
    test_sleep(0.05);
  }
  return 0;
}

long test_rss_kb(void) { return palp_test_rss_kb(0); }
