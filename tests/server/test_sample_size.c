/*
 * test_sample_size.c - the loopback config bounds what a peer can make a palp reader hold (session 83
 * review "wire" #1). palp's unbounded sequences (a catalogue entry's rest positions and triangles,
 * among others) took samples up to Cyclone's default MaxSampleSize of 2 GB, held in the reader's
 * cache before palp could check them: 8 made-up catalogue entries of 1,000,000 vertices grew a
 * station from 12 MB to 229 MB. config/cyclonedds-loopback.xml now sets MaxSampleSize 16 MiB.
 *
 * Over real DDS on loopback (domain 201, in two processes: Cyclone delivers within a process
 * without the wire). The child is the peer: the loopback config with the bound lifted to 64 MiB (a
 * peer chooses its own config), writing on palp_catalogue with palp's QoS
 *  - entry 900001: 700,000 vertices, no triangles: 16,800,000 bytes of positions, just past
 *    16 MiB = 16,777,216 bytes;
 *  - entry 900002: the largest entry a palp-server publishes, the 200,000-vertex mesh with its
 *    2V - 4 = 399,996 triangles: 4,800,000 + 4,799,952 bytes, ~9.6 MB.
 * The parent reads with the config CTest gives it (the loopback config). Asserted: entry 900002
 * arrives whole within 10 s (the bound does not refuse what a server sends), and 900001 is never in
 * the reader (no instance: dds_lookup_instance finds none) 0.5 s after it (both come from one reliable
 * writer, in order: 900001 was written first). Without MaxSampleSize in the config, 900001 arrives
 * (checked by running the test with it removed). ~1 s.
 */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <dds/dds.h>

#include "check.h"
#include "palp_dds.h"

#define DOMAIN 201
#define BIG_ID 900001u
#define BIG_VERTICES 700000u /* 24 bytes each: 16,800,000 > 16 MiB */
#define MAX_ID 900002u
#define MAX_VERTICES 200000u
#define MAX_TRIANGLES (2u * MAX_VERTICES - 4u)

static void nap(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
  nanosleep(&ts, NULL);
}

static int entry(palp_Phantom *ph, uint32_t id, uint32_t nv, uint32_t nt) {
  memset(ph, 0, sizeof *ph);
  ph->phantom_id = id;
  ph->radius = 0.04;
  ph->rest._buffer = calloc(nv, sizeof *ph->rest._buffer);
  ph->rest._length = ph->rest._maximum = nv;
  if (nt) {
    ph->triangles._buffer = calloc((size_t)nt * 3, sizeof *ph->triangles._buffer);
    ph->triangles._length = ph->triangles._maximum = 3 * nt;
    for (uint32_t i = 0; ph->triangles._buffer && i < 3 * nt; i++) ph->triangles._buffer[i] = (int32_t)(i % nv);
  }
  return ph->rest._buffer && (!nt || ph->triangles._buffer) ? 0 : -1;
}

/* The peer: writes both entries, then holds them (transient-local) until killed. */
static int peer(const char *config) {
  char uri[2048];
  snprintf(uri, sizeof uri,
           "file://%s,<CycloneDDS><Domain Id=\"any\"><Internal><MaxSampleSize>64MiB</MaxSampleSize></Internal>"
           "</Domain></CycloneDDS>",
           config);
  setenv("CYCLONEDDS_URI", uri, 1);
  const dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  const dds_entity_t tp = pp > 0 ? palp_dds_create_topic(pp, PALP_TOPIC_CATALOGUE) : -1;
  const dds_entity_t w = tp > 0 ? palp_dds_create_writer(pp, tp, PALP_TOPIC_CATALOGUE) : -1;
  palp_Phantom big, max;
  if (w <= 0 || entry(&big, BIG_ID, BIG_VERTICES, 0) || entry(&max, MAX_ID, MAX_VERTICES, MAX_TRIANGLES)) {
    fprintf(stderr, "FAIL the peer: participant %d, writer %d, or memory\n", (int)pp, (int)w);
    return 1;
  }
  const dds_return_t a = dds_write(w, &big), b = dds_write(w, &max);
  if (a != 0 || b != 0) fprintf(stderr, "FAIL the peer's writes: %d, %d\n", (int)a, (int)b);
  for (int i = 0; i < 300; i++) nap(0.1); /* the parent kills it */
  return 1;
}

int main(void) {
  const char *uri = getenv("CYCLONEDDS_URI");
  if (!uri || strncmp(uri, "file://", 7) != 0) {
    fprintf(stderr, "FAIL CYCLONEDDS_URI must name the loopback config (file://...)\n");
    return 1;
  }
  const pid_t child = fork();
  if (child < 0) return 1;
  if (child == 0) _exit(peer(uri + 7)); /* before any DDS entity of the parent */
  const dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  const dds_entity_t tp = pp > 0 ? palp_dds_create_topic(pp, PALP_TOPIC_CATALOGUE) : -1;
  const dds_entity_t r = tp > 0 ? palp_dds_create_reader(pp, tp, PALP_TOPIC_CATALOGUE) : -1;
  CHECK(r > 0, "a catalogue reader on domain %d (%d)", DOMAIN, (int)r);
  uint32_t got_max = 0, got_triangles = 0, got_big = 0;
  const int64_t t0 = palp_dds_now_ns();
  double max_s = -1;
  /* until 10 s, or 0.5 s past the largest entry's arrival */
  for (;;) {
    const double t = (double)(palp_dds_now_ns() - t0) * 1e-9;
    if (r <= 0 || t > 10 || (max_s >= 0 && t > max_s + 0.5)) break;
    void *ptr[2] = {NULL, NULL};
    dds_sample_info_t info[2];
    const int n = dds_read(r, ptr, info, 2, 2);
    for (int i = 0; i < n; i++) {
      const palp_Phantom *ph = ptr[i];
      if (!info[i].valid_data) continue;
      if (ph->phantom_id == MAX_ID && max_s < 0) {
        got_max = ph->rest._length, got_triangles = ph->triangles._length / 3;
        max_s = (double)(palp_dds_now_ns() - t0) * 1e-9;
      }
      if (ph->phantom_id == BIG_ID) got_big = ph->rest._length;
    }
    if (n > 0) dds_return_loan(r, ptr, n);
    nap(0.02);
  }
  palp_Phantom key;
  memset(&key, 0, sizeof key);
  key.phantom_id = BIG_ID;
  const dds_instance_handle_t big_ih = r > 0 ? dds_lookup_instance(r, &key) : 0;
  CHECK(got_max == MAX_VERTICES && got_triangles == MAX_TRIANGLES,
        "the largest entry a server publishes (%u vertices, %u triangles, ~9.6 MB) read %.2f s after start: %u vertices, "
        "%u triangles", MAX_VERTICES, MAX_TRIANGLES, max_s, got_max, got_triangles);
  CHECK(got_big == 0 && big_ih == 0,
        "an entry of %u vertices (16,800,000 bytes > MaxSampleSize 16 MiB) never in the reader: %u vertices read, "
        "instance %s", BIG_VERTICES, got_big, big_ih ? "held" : "none");
  kill(child, SIGKILL);
  int st = 0;
  waitpid(child, &st, 0);
  if (pp > 0) dds_delete(pp);
  return failures != 0;
}
