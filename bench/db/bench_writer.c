/* Session-log writer benchmark: can one writer keep 32 sessions at 1 kHz without dropping?
 *
 * usage: bench_db_writer [DB_PATH] [SECONDS=10] [SESSIONS=32] [PRODUCERS=2]
 *
 * PRODUCERS threads (the server's tick pool) each own SESSIONS / PRODUCERS sessions and tick at
 * 1 kHz with absolute sleeps. Per session and tick: one frame summary, one feedback sample and
 * one contact input (a haptic station's 1 kHz finger); every 33 ticks (~30 Hz) a 338-vertex mesh.
 * Prints the sustained records/s, records dropped (shed + failed; target 0), the queue high-water
 * mark, enqueue latency (median, p99, max) and, as a baseline measured in the same run, what a bare
 * SQLite connection inserts per second with the same statements in large transactions (the disk
 * ceiling the worker thread works under). Values are synthetic; sizes are the real ones. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <sqlite3.h>

#include "../bench_tmp.h"
#include "palp_db.h"

#define MESH_VERTICES 338
#define MAX_SAMPLES (1 << 22)

typedef struct producer {
  palp_db_writer *w;
  palp_db_session *s;
  int nsess;
  double seconds;
  int64_t calls, refused, overruns;
  float *lat_us; /* sampled enqueue latencies [us] */
  int nlat;
} producer;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void timed(producer *p, int rc, double t0) {
  double us = (now() - t0) * 1e6;
  p->calls++;
  if (rc == PALP_EFULL) p->refused++;
  if (p->nlat < MAX_SAMPLES) p->lat_us[p->nlat++] = (float)us;
}

static void *run_producer(void *arg) {
  producer *p = arg;
  palp_vec3 *mesh = malloc(sizeof(palp_vec3) * MESH_VERTICES);
  for (int i = 0; i < MESH_VERTICES; i++) mesh[i] = (palp_vec3){0.04 * i / MESH_VERTICES, 0.01, 0.03};
  struct timespec next;
  clock_gettime(CLOCK_MONOTONIC, &next);
  const int64_t ticks = (int64_t)(p->seconds * 1000);
  for (int64_t f = 0; f < ticks; f++) {
    for (int k = 0; k < p->nsess; k++) {
      palp_db_contact c = {.frame = f, .sim_time_s = f * 1e-3, .slot = 0, .op = f ? PALP_DB_OP_UPDATE : PALP_DB_OP_ADD,
                           .kind = PALP_DB_KIND_FINGER, .center_m = {0.01, 0.002 * k, 0.045}, .radius_m = 0.008};
      double t0 = now();
      if (!getenv("BENCH_NO_CONTACT")) timed(p, palp_db_log_contact(p->w, p->s[k], &c), t0);
      palp_db_frame fr = {.frame = f + 1, .sim_time_s = (f + 1) * 1e-3, .top_disp_m = 1e-3, .max_disp_m = 2e-3,
                          .volume_m3 = 1.3e-4, .pressure_pa = 12.0, .contact_force_n = 2.5,
                          .state_hash = (uint64_t)f * 0x9E3779B97F4A7C15ull};
      t0 = now();
      timed(p, palp_db_log_frame(p->w, p->s[k], &fr), t0);
      t0 = now();
      timed(p, palp_db_log_feedback(p->w, p->s[k], f + 1, 0, (palp_vec3){0, 0, 2.5}), t0);
      if ((f + 1) % 33 == 0 && !getenv("BENCH_NO_MESH")) {
        t0 = now();
        timed(p, palp_db_log_mesh(p->w, p->s[k], f + 1, mesh, MESH_VERTICES), t0);
      }
    }
    next.tv_nsec += 1000000;
    if (next.tv_nsec >= 1000000000L) next.tv_nsec -= 1000000000L, next.tv_sec++;
    struct timespec cur;
    clock_gettime(CLOCK_MONOTONIC, &cur);
    if (cur.tv_sec > next.tv_sec || (cur.tv_sec == next.tv_sec && cur.tv_nsec > next.tv_nsec)) p->overruns++;
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
  }
  free(mesh);
  return NULL;
}

static int cmp_float(const void *a, const void *b) {
  float x = *(const float *)a, y = *(const float *)b;
  return (x > y) - (x < y);
}

/* Baseline: one connection, the frame insert, 20000 rows per transaction, as fast as it goes. */
static double sqlite_ceiling(const char *path) {
  unlink(path);
  sqlite3 *h;
  sqlite3_open(path, &h);
  sqlite3_exec(h,
               "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL; CREATE TABLE frame(session_id INTEGER, frame "
               "INTEGER, sim_time_s REAL, top_disp_m REAL, max_disp_m REAL, volume_m3 REAL, pressure_pa REAL, "
               "contact_force_n REAL, state_hash INTEGER, PRIMARY KEY(session_id, frame)) WITHOUT ROWID",
               NULL, NULL, NULL);
  sqlite3_stmt *st;
  sqlite3_prepare_v2(h, "INSERT INTO frame VALUES(?1,?2,?3,?4,?5,?6,?7,?8,?9)", -1, &st, NULL);
  const int n = 400000;
  double t0 = now();
  for (int i = 0; i < n; i++) {
    if (i % 20000 == 0) sqlite3_exec(h, "BEGIN", NULL, NULL, NULL);
    sqlite3_bind_int64(st, 1, i % 32);
    sqlite3_bind_int64(st, 2, i / 32);
    for (int k = 3; k <= 8; k++) sqlite3_bind_double(st, k, 1e-3 * k);
    sqlite3_bind_int64(st, 9, i);
    sqlite3_step(st);
    sqlite3_reset(st);
    if (i % 20000 == 19999) sqlite3_exec(h, "COMMIT", NULL, NULL, NULL);
  }
  double rate = n / (now() - t0);
  sqlite3_finalize(st);
  sqlite3_close(h);
  unlink(path);
  return rate;
}

/* Baseline 2: what the tick would wait for if it wrote to SQLite itself: one transaction per tick
 * holding every session's frame, feedback and contact rows, committed before the tick ends. */
static void sync_per_tick(const char *path, int nsess, int ticks, double *p50_us, double *p99_us) {
  unlink(path);
  char err[256];
  palp_db *db;
  if (palp_db_open(path, 1, &db, err, sizeof err)) {
    *p50_us = *p99_us = -1;
    return;
  }
  sqlite3 *h = palp_db_handle(db);
  sqlite3_exec(h, "INSERT INTO session(uid, trainee, station, phantom_id, phantom_name, scene_json, params_json, "
                  "tick_hz, dt_s, start_unix_s) VALUES('sync', '', '', '', '', '{}', '{}', 1000, 0.001, 0)",
               NULL, NULL, NULL);
  sqlite3_stmt *fr, *fb, *ci;
  sqlite3_prepare_v2(h, "INSERT INTO frame VALUES(1, ?1, ?2, 1e-3, 2e-3, 1.3e-4, 12, 2.5, ?3)", -1, &fr, NULL);
  sqlite3_prepare_v2(h, "INSERT INTO feedback VALUES(1, ?1, ?2, 0, 0, 2.5)", -1, &fb, NULL);
  sqlite3_prepare_v2(h, "INSERT INTO contact_input(session_id, frame, sim_time_s, slot, op, kind, center_x_m, "
                        "center_y_m, center_z_m, radius_m) VALUES(1, ?1, ?2, 0, 'update', 'finger', 0.01, 0, 0.045, 0.008)",
                     -1, &ci, NULL);
  double *t = malloc(sizeof(double) * (size_t)ticks);
  for (int k = 0; k < ticks; k++) {
    double t0 = now();
    sqlite3_exec(h, "BEGIN", NULL, NULL, NULL);
    for (int j = 0; j < nsess; j++) {
      int64_t f = (int64_t)k * nsess + j; /* one row per (session, tick); keys kept unique */
      sqlite3_bind_int64(fr, 1, f);
      sqlite3_bind_double(fr, 2, k * 1e-3);
      sqlite3_bind_int64(fr, 3, f);
      sqlite3_step(fr);
      sqlite3_reset(fr);
      sqlite3_bind_int64(fb, 1, f);
      sqlite3_bind_int(fb, 2, 0);
      sqlite3_step(fb);
      sqlite3_reset(fb);
      sqlite3_bind_int64(ci, 1, f);
      sqlite3_bind_double(ci, 2, k * 1e-3);
      sqlite3_step(ci);
      sqlite3_reset(ci);
    }
    sqlite3_exec(h, "COMMIT", NULL, NULL, NULL);
    t[k] = (now() - t0) * 1e6;
  }
  sqlite3_finalize(fr);
  sqlite3_finalize(fb);
  sqlite3_finalize(ci);
  palp_db_close(db);
  unlink(path);
  for (int i = 1; i < ticks; i++) /* insertion sort: 2000 values */
    for (int j = i; j > 0 && t[j] < t[j - 1]; j--) {
      double x = t[j];
      t[j] = t[j - 1];
      t[j - 1] = x;
    }
  *p50_us = t[ticks / 2];
  *p99_us = t[(int)(0.99 * (ticks - 1))];
  free(t);
}

int main(int argc, char **argv) {
  /* Options first: "--help" must never become a database path (it was created, 141 MB). */
  for (int i = 1; i < argc; i++) {
    if (argv[i][0] != '-') continue;
    const int help = !strcmp(argv[i], "--help") || !strcmp(argv[i], "-h");
    fprintf(help ? stdout : stderr,
            "usage: %s [DB_PATH] [SECONDS>0] [SESSIONS>0] [PRODUCERS 1..SESSIONS]\n"
            "Writes a synthetic 1 kHz load into DB_PATH (the file is replaced; default: bench.db in a scratch\n"
            "directory under TMPDIR, removed at exit).\n",
            argv[0]);
    return help ? 0 : 2;
  }
  char scratch[600];
  const char *path = argc > 1 ? argv[1] : bench_tmp_path("palp-bench-db", "bench.db", scratch, sizeof scratch);
  if (!path) return 1;
  const double seconds = argc > 2 ? atof(argv[2]) : 10.0;
  const int nsess = argc > 3 ? atoi(argv[3]) : 32;
  const int nprod = argc > 4 ? atoi(argv[4]) : 2;
  if (!(seconds > 0) || nsess <= 0 || nprod <= 0 || nprod > nsess) {
    fprintf(stderr, "usage: %s [DB_PATH] [SECONDS>0] [SESSIONS>0] [PRODUCERS 1..SESSIONS]\n", argv[0]);
    return 2;
  }
  char aux[1100];
  unlink(path);
  snprintf(aux, sizeof aux, "%s-wal", path);
  unlink(aux);

  char ceil_path[1100];
  snprintf(ceil_path, sizeof ceil_path, "%s.ceiling", path);
  const double ceiling = sqlite_ceiling(ceil_path);
  double sync_p50, sync_p99;
  sync_per_tick(ceil_path, nsess, 2000, &sync_p50, &sync_p99);

  char err[512];
  palp_db_writer *w;
  palp_db_writer_opts o = palp_db_writer_default_opts();
  if (palp_db_writer_open(path, &o, &w, err, sizeof err)) {
    fprintf(stderr, "bench: %s\n", err);
    return 1;
  }
  palp_db_session *s = calloc((size_t)nsess, sizeof *s);
  for (int k = 0; k < nsess; k++) {
    char uid[64], tr[32];
    snprintf(uid, sizeof uid, "bench-%d-%d", (int)getpid(), k);
    snprintf(tr, sizeof tr, "trainee-%02d", k);
    palp_db_session_def d = {.uid = uid, .trainee = tr, .station = "bench", .phantom_id = "p", .phantom_name = "p",
                             .scene_json = "{}", .params_json = "{}", .tick_hz = 1000, .dt_s = 0.001};
    palp_db_log_session_begin(w, &d, &s[k]);
  }
  producer *p = calloc((size_t)nprod, sizeof *p);
  pthread_t *th = calloc((size_t)nprod, sizeof *th);
  const double t0 = now();
  for (int i = 0, first = 0; i < nprod; i++) {
    int cnt = nsess / nprod + (i < nsess % nprod);
    p[i] = (producer){.w = w, .s = s + first, .nsess = cnt, .seconds = seconds,
                      .lat_us = malloc(sizeof(float) * MAX_SAMPLES)};
    first += cnt;
    pthread_create(&th[i], NULL, run_producer, &p[i]);
  }
  for (int i = 0; i < nprod; i++) pthread_join(th[i], NULL);
  const double t_run = now() - t0;
  for (int k = 0; k < nsess; k++) palp_db_log_session_end(w, s[k], PALP_DB_END_NORMAL, NULL, 0);
  palp_db_writer_flush(w, 60);
  const double t_all = now() - t0;
  palp_db_writer_stats st;
  palp_db_writer_stats_get(w, &st);
  palp_db_writer_close(w);

  int64_t calls = 0, refused = 0, overruns = 0;
  size_t nlat = 0;
  for (int i = 0; i < nprod; i++) calls += p[i].calls, refused += p[i].refused, overruns += p[i].overruns, nlat += (size_t)p[i].nlat;
  float *lat = malloc(sizeof(float) * (nlat ? nlat : 1));
  size_t off = 0;
  for (int i = 0; i < nprod; i++) {
    memcpy(lat + off, p[i].lat_us, sizeof(float) * (size_t)p[i].nlat);
    off += (size_t)p[i].nlat;
    free(p[i].lat_us);
  }
  qsort(lat, nlat, sizeof *lat, cmp_float);
  printf("session-log writer: %d sessions x 1 kHz on %d producer threads for %.1f s (%s)\n", nsess, nprod, seconds, path);
  printf("  offered            %.0f records/s (%lld records; frame + feedback + contact per tick, mesh at 30 Hz)\n",
         (double)calls / t_run, (long long)calls);
  printf("  written            %lld records in %.2f s incl. drain = %.0f records/s sustained, %lld commits\n",
         (long long)st.written, t_all, (double)st.written / t_all, (long long)st.commits);
  printf("  dropped            %lld (shed %lld, failed %lld); refused calls %lld\n", (long long)(st.shed + st.failed),
         (long long)st.shed, (long long)st.failed, (long long)refused);
  printf("  writer thread      %.2f s CPU = %.2f us per record, %.0f%% of one core over the run\n", st.worker_cpu_s,
         1e6 * st.worker_cpu_s / (double)(st.written ? st.written : 1), 100.0 * st.worker_cpu_s / t_all);
  printf("  queue high-water   %d of %d records (%.1f%%)\n", st.queue_high_water, st.queue_capacity,
         100.0 * st.queue_high_water / st.queue_capacity);
  if (nlat)
    printf("  enqueue latency    median %.2f us, p99 %.2f us, p99.9 %.2f us, max %.1f us (%zu calls)\n",
           lat[nlat / 2], lat[(size_t)(0.99 * (double)(nlat - 1))], lat[(size_t)(0.999 * (double)(nlat - 1))],
           lat[nlat - 1], nlat);
  printf("  tick overruns      %lld of %lld ticks\n", (long long)overruns, (long long)(seconds * 1000) * nprod);
  printf("  baseline           bare SQLite frame inserts: %.0f rows/s -> the log needs %.1f%% of that ceiling\n",
         ceiling, 100.0 * ((double)calls / t_run) / ceiling);
  if (nlat) {
    /* The tick's logging cost with the writer: the enqueue calls one tick makes (3 per session). */
    const double per_tick_p99 = 3.0 * nsess * lat[(size_t)(0.99 * (double)(nlat - 1))];
    printf("  baseline           writing on the tick thread (one transaction per tick, %d x 3 rows): "
           "p50 %.0f us, p99 %.0f us per tick; with the writer thread a tick spends ~%.1f us median "
           "(%.0fx less) of its 1000 us\n",
           nsess, sync_p50, sync_p99, 3.0 * nsess * lat[nlat / 2], sync_p50 / (3.0 * nsess * lat[nlat / 2]));
    (void)per_tick_p99;
  }
  free(lat);
  free(p);
  free(th);
  free(s);
  return st.shed + st.failed ? 1 : 0;
}
