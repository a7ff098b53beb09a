/*
 * test_netem_relay.c - palp-netem carries an instance's end across the relay (session 81 review).
 *
 * Until session 81 the relay looked an invalid sample's key up with dds_instance_get_key after
 * taking it; an instance with no sample left and no writer is freed by that take, the lookup failed
 * and the relay dropped the unregister without counting it. Behind the relay a stalled station
 * (SIGSTOP, its contact writer's lease lost) kept its finger pressed on the server 4.5 s after the
 * stall was lifted; directly the server lifted it at once.
 *
 * A real relay (palp_netem_start) between DDS domains 203 (stations' side) and 204 (server's side),
 * 2 ms one way, no jitter, no loss, on the loopback config. A contact writer of session 7 on domain
 * 203 writes fingers 0..3; a reader on 204 must see each instance's end within 1 s (the relay adds
 * 2 ms; the bound is for a loaded machine):
 *   finger 0: written, then unregistered by its live writer (no autodispose, as a lost lease)
 *                                                              -> NOT_ALIVE_NO_WRITERS
 *   finger 1: written, then disposed                           -> NOT_ALIVE_DISPOSED
 *   finger 2: written by a writer that is then deleted         -> NOT_ALIVE_DISPOSED (autodispose)
 *   finger 3: written by a writer deleted at once, before the relay can take the sample alone
 *             (the state may then ride on the valid sample)    -> NOT_ALIVE (either)
 * Fingers 0 and 2 failed before the fix (never seen not alive); finger 1 passed (its writer still
 * holds the instance, so the lookup worked). Domains 203/204 are this test's own.
 */
#include <stdio.h>
#include <string.h>
#include <time.h>

#include <dds/dds.h>

#include "netem.h"
#include "palp_dds.h"

#define SESSION 7u
#define BOUND_NS 1000000000LL

static dds_entity_t rd_b; /* the server side's contact reader */
static int64_t not_alive_ns[4];
static int not_alive_state[4];
static int seen[4];

static void sleep_ms(int ms) {
  struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
  nanosleep(&ts, NULL);
}

/* Takes everything the server side has and notes, per finger, the first valid sample and the first
 * not-alive state. */
static void poll_b(void) {
  palp_Contact buf[16];
  void *ptr[16];
  dds_sample_info_t info[16];
  for (int i = 0; i < 16; i++) ptr[i] = &buf[i];
  int n;
  while ((n = dds_take(rd_b, ptr, info, 16, 16)) > 0)
    for (int i = 0; i < n; i++) {
      const unsigned f = buf[i].finger;
      if (f >= 4 || buf[i].session_id != SESSION) continue;
      if (info[i].valid_data) seen[f] = 1;
      if (info[i].instance_state != DDS_IST_ALIVE && !not_alive_ns[f]) {
        not_alive_ns[f] = palp_dds_now_ns();
        not_alive_state[f] = (int)info[i].instance_state;
      }
    }
}

/* Writes finger f every 20 ms until the server side has it (best-effort: the relay's session
 * writer is made with the session's first sample, before the reader matched it). */
static int write_until_seen(dds_entity_t w, unsigned f) {
  palp_Contact c;
  memset(&c, 0, sizeof c);
  c.session_id = SESSION, c.finger = (uint8_t)f;
  for (int i = 0; i < 150 && !seen[f]; i++) {
    dds_write(w, &c);
    sleep_ms(20);
    poll_b();
  }
  return seen[f];
}

static int wait_matched(dds_entity_t w) {
  for (int i = 0; i < 300; i++) {
    dds_publication_matched_status_t st;
    if (dds_get_publication_matched_status(w, &st) == 0 && st.current_count > 0) return 1;
    sleep_ms(10);
  }
  return 0;
}

/* Polls until finger f is seen not alive or BOUND_NS after t0 has passed. */
static void wait_not_alive(unsigned f, int64_t t0) {
  while (!not_alive_ns[f] && palp_dds_now_ns() - t0 < BOUND_NS) {
    poll_b();
    sleep_ms(2);
  }
}

static const char *state_name(int s) {
  return s == DDS_IST_NOT_ALIVE_DISPOSED ? "NOT_ALIVE_DISPOSED"
         : s == DDS_IST_NOT_ALIVE_NO_WRITERS ? "NOT_ALIVE_NO_WRITERS"
         : s == DDS_IST_ALIVE ? "ALIVE" : "none";
}

int main(void) {
  if (palp_dds_use_config(PALP_DDS_DEFAULT_CONFIG) < 0) {
    fprintf(stderr, "FAIL no DDS config %s\n", PALP_DDS_DEFAULT_CONFIG);
    return 1;
  }
  char err[256];
  const palp_netem_def def = {.domain_a = 203, .domain_b = 204, .delay = 0.002, .jitter = 0, .loss = 0, .seed = 1};
  palp_netem *relay = palp_netem_start(&def, err, sizeof err);
  if (!relay) {
    fprintf(stderr, "FAIL %s\n", err);
    return 1;
  }
  char part[64];
  palp_dds_session_partition(SESSION, part, sizeof part);
  const dds_entity_t pa = dds_create_participant(203, NULL, NULL), pb = dds_create_participant(204, NULL, NULL);
  const dds_entity_t ta = palp_dds_create_topic(pa, PALP_TOPIC_CONTACT), tb = palp_dds_create_topic(pb, PALP_TOPIC_CONTACT);
  const dds_entity_t pub = palp_dds_session_publisher(pa, part), sub = palp_dds_session_subscriber(pb, part);
  rd_b = palp_dds_create_reader(sub, tb, PALP_TOPIC_CONTACT);
  /* w does not dispose what it unregisters, as a writer whose lease ran out (the stalled station):
   * finger 0's instance ends with no writer, not disposed */
  dds_qos_t *q = palp_dds_qos(PALP_TOPIC_CONTACT);
  dds_qset_writer_data_lifecycle(q, false);
  const dds_entity_t w = dds_create_writer(pub, ta, q, NULL);
  dds_delete_qos(q);
  const dds_entity_t w2 = palp_dds_create_writer(pub, ta, PALP_TOPIC_CONTACT);
  const dds_entity_t w3 = palp_dds_create_writer(pub, ta, PALP_TOPIC_CONTACT);
  if (pa < 0 || pb < 0 || rd_b < 0 || w < 0 || w2 < 0 || w3 < 0) {
    fprintf(stderr, "FAIL cannot create the test's DDS entities\n");
    return 1;
  }
  int failures = 0;
  palp_Contact key;
  memset(&key, 0, sizeof key);
  key.session_id = SESSION;
  int64_t t0[4] = {0};

  /* finger 0: unregistered by its live writer */
  if (!write_until_seen(w, 0)) fprintf(stderr, "FAIL finger 0 never crossed the relay\n"), ++failures;
  key.finger = 0;
  sleep_ms(50); /* the relay has taken every copy by now: the instance holds no sample */
  t0[0] = palp_dds_now_ns();
  dds_unregister_instance(w, &key);
  wait_not_alive(0, t0[0]);

  /* finger 1: disposed */
  if (!write_until_seen(w, 1)) fprintf(stderr, "FAIL finger 1 never crossed the relay\n"), ++failures;
  key.finger = 1;
  sleep_ms(50);
  t0[1] = palp_dds_now_ns();
  dds_dispose(w, &key);
  wait_not_alive(1, t0[1]);

  /* finger 2: its writer deleted */
  if (!write_until_seen(w2, 2)) fprintf(stderr, "FAIL finger 2 never crossed the relay\n"), ++failures;
  sleep_ms(50);
  t0[2] = palp_dds_now_ns();
  dds_delete(w2);
  wait_not_alive(2, t0[2]);

  /* finger 3: one sample, its writer deleted at once (the relay's writers of the session are
   * matched by now: finger 0 crossed) */
  if (!wait_matched(w3)) fprintf(stderr, "FAIL the relay never matched a writer\n"), ++failures;
  palp_Contact c;
  memset(&c, 0, sizeof c);
  c.session_id = SESSION, c.finger = 3;
  dds_write(w3, &c);
  t0[3] = palp_dds_now_ns();
  dds_delete(w3);
  wait_not_alive(3, t0[3]);

  const int want[4] = {DDS_IST_NOT_ALIVE_NO_WRITERS, DDS_IST_NOT_ALIVE_DISPOSED, DDS_IST_NOT_ALIVE_DISPOSED, 0};
  const char *what[4] = {"unregistered", "disposed", "writer deleted", "written and writer deleted at once"};
  for (int f = 0; f < 4; f++) {
    const int ok = not_alive_ns[f] && (want[f] == 0 || not_alive_state[f] == want[f]);
    printf("%s finger %d (%s): %s after %.1f ms (want %s within %.0f ms)\n", ok ? "ok  " : "FAIL", f, what[f],
           state_name(not_alive_state[f]), not_alive_ns[f] ? (double)(not_alive_ns[f] - t0[f]) * 1e-6 : -1.0,
           want[f] ? state_name(want[f]) : "NOT_ALIVE_*", (double)BOUND_NS * 1e-6);
    failures += !ok;
  }
  palp_netem_stats st;
  palp_netem_get_stats(relay, &st);
  printf("relay: %llu forwarded, %llu dropped, %llu disposals/unregistrations\n", (unsigned long long)st.forwarded,
         (unsigned long long)st.dropped, (unsigned long long)st.disposals);
  if (st.disposals < 4) fprintf(stderr, "FAIL %llu state changes counted, want >= 4\n", (unsigned long long)st.disposals), ++failures;
  dds_delete(pa);
  dds_delete(pb);
  palp_netem_stop(relay);
  return failures ? 1 : 0;
}
