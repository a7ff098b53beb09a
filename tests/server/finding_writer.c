/*
 * finding_writer.c - a peer in a session's partition of an unsecured classroom, for
 * server_exercise_client: waits (up to 10 s) for TRAINEE's open session, then writes withdrawals of
 * mark MARK into its partition, BURST every 100 ms for SECONDS, naming made-up sessions (the
 * session's id + 1000 + k) or, with "own", the session itself (withdrawals: they never add a mark);
 * "own-visual" first joins the session as a visual station, as palp-web does before it writes a
 * trainee page's marks (since 2026-12-06 the server takes a session's findings only from the
 * participant that joined it or, unsecured, one with a visual station in it); "own-visual-mark" then
 * marks MARK at the pole instead of withdrawing it.
 * Prints what it wrote; exit 0, or 1 when no such session opened (or the visual join was refused).
 * usage: test_finding_writer DOMAIN TRAINEE MARK BURST SECONDS [own|own-visual|own-visual-mark|dispose]
 * With "frames" (DOMAIN TRAINEE frames): once the session's first finger sample in contact and its
 * first local model are there, writes each back into the partition with frame 2^64 - 1 (a forged
 * far-future step, otherwise the server's own), then exits; 1 when none came within 10 s.
 * With "contacts" (DOMAIN TRAINEE contacts SECONDS READERS, session 83): once the session is open and
 * READERS readers of its partition's contacts are matched (the server's, and the viewers the test
 * started; at most 5 s), writes 15 N force contacts of finger 0 into its partition, distribution II at
 * polar 30 deg, azimuth 0 (3 o'clock, 21 mm from the pole of the 40 mm dome), every 50 ms for SECONDS:
 * what a peer of an unsecured classroom may write, which the server refuses (foreign_participant) and a
 * viewer must not show as the trainee's. Every 50 ms, not faster: the server's contact reader keeps the
 * newest sample of a finger, and a peer writing faster takes the place of most of the trainee's own
 * (her lift among them: the server then holds her finger down).
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../open_session.h"
#include "palp_dds.h"

/* The session's first sample on topic k (of finger 0; a finger sample in contact), rewritten with frame
 * 2^64 - 1: 1 written, 0 none within 10 s. */
static int forge_frame(dds_entity_t pp, dds_entity_t pub, dds_entity_t sub, const palp_SessionState *st,
                       palp_dds_topic_kind k) {
  const dds_entity_t tp = palp_dds_create_topic(pp, k);
  const dds_entity_t r = palp_dds_create_reader(sub, tp, k), w = palp_dds_create_writer(pub, tp, k);
  int done = 0;
  for (int i = 0; i < 200 && w > 0; i++) { /* matched with the station's reader (best-effort): up to 2 s */
    dds_publication_matched_status_t m;
    if (dds_get_publication_matched_status(w, &m) == 0 && m.current_count > 0) break;
    dds_sleepfor(DDS_MSECS(10));
  }
  for (int i = 0; i < 1000 && !done && r > 0 && w > 0; i++) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (!done && dds_take(r, ptr, &info, 1, 1) > 0) {
      if (info.valid_data && k == PALP_TOPIC_FINGER_SAMPLE) {
        palp_FingerSample m = *(const palp_FingerSample *)ptr[0]; /* its sequence the loan's until returned */
        if (m.session_id == st->session_id && m.finger == 0 && m.in_contact) {
          m.frame = UINT64_MAX;
          done = dds_write(w, &m) == 0;
        }
      } else if (info.valid_data) {
        palp_LocalModel m = *(const palp_LocalModel *)ptr[0];
        if (m.session_id == st->session_id && m.finger == 0) {
          m.frame = UINT64_MAX;
          done = dds_write(w, &m) == 0;
        }
      }
      dds_return_loan(r, ptr, 1);
      ptr[0] = NULL;
    }
    if (!done) dds_sleepfor(DDS_MSECS(10));
  }
  return done;
}

/* Joins session sid as a visual station from pp: 1 when accepted within 3 s. */
static int join_visual(dds_entity_t pp, uint32_t sid) {
  const dds_entity_t rq_w = palp_dds_create_writer(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REQUEST),
                                                   PALP_TOPIC_SESSION_REQUEST);
  const dds_entity_t rp_r = palp_dds_create_reader(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REPLY),
                                                   PALP_TOPIC_SESSION_REPLY);
  for (int i = 0; i < 200 && rq_w > 0; i++) { /* matched with the server's reader: up to 2 s */
    dds_publication_matched_status_t m;
    if (dds_get_publication_matched_status(rq_w, &m) == 0 && m.current_count > 0) break;
    dds_sleepfor(DDS_MSECS(10));
  }
  palp_SessionRequest rq;
  memset(&rq, 0, sizeof rq);
  /* an id of its own per process: a peer's station is still open on the server (its participant's
   * going not yet noticed) when the next peer joins, and a JOIN under a live station's id from another
   * participant is refused (session 80) */
  snprintf(rq.station_id, sizeof rq.station_id, "finding_writer/visual/%ld", (long)getpid());
  snprintf(rq.user_name, sizeof rq.user_name, "finding_writer");
  rq.request_seq = 1;
  rq.op = palp_OP_JOIN;
  rq.role = palp_ROLE_VISUAL;
  rq.session_id = sid;
  if (rq_w <= 0 || rp_r <= 0 || dds_write(rq_w, &rq) != 0) return 0;
  for (int i = 0; i < 300; i++) {
    palp_SessionReply b;
    void *ptr[1] = {&b};
    dds_sample_info_t info;
    while (dds_take(rp_r, ptr, &info, 1, 1) > 0)
      if (info.valid_data && !strcmp(b.station_id, rq.station_id)) return b.status == palp_REPLY_ACCEPTED;
    dds_sleepfor(DDS_MSECS(10));
  }
  return 0;
}

/* "contacts": 15 N presses of finger 0 into st's partition every 50 ms for `seconds`; the count written. */
static int forge_contacts(dds_entity_t pp, const palp_SessionState *st, double seconds, int readers) {
  const dds_entity_t pub = palp_dds_session_publisher(pp, st->partition);
  const dds_entity_t w = palp_dds_create_writer(pub, palp_dds_create_topic(pp, PALP_TOPIC_CONTACT), PALP_TOPIC_CONTACT);
  for (int i = 0; i < 500 && w > 0; i++) { /* matched (best-effort): up to 5 s */
    dds_publication_matched_status_t m;
    if (dds_get_publication_matched_status(w, &m) == 0 && (int)m.current_count >= readers) break;
    dds_sleepfor(DDS_MSECS(10));
  }
  const double R = 0.040, s30 = 0.5, c30 = 0.86602540378443864676; /* polar 30 deg, azimuth 0: along +x */
  palp_Contact c;
  memset(&c, 0, sizeof c);
  c.session_id = st->session_id;
  c.finger = 0;
  c.mode = palp_CONTACT_FORCE;
  c.distribution = 2;
  c.vertex = -1;
  c.center = (palp_Vec3){R * s30, 0, R * c30};
  c.force = (palp_Vec3){-15 * s30, 0, -15 * c30}; /* 15 N along the inward normal */
  int written = 0;
  for (int k = 0; k < (int)(seconds * 20) && w > 0; k++) {
    c.seq = (uint64_t)k + 1;
    c.source_time_ns = dds_time();
    written += dds_write(w, &c) == 0;
    dds_sleepfor(DDS_MSECS(50));
  }
  return written;
}

int main(int argc, char **argv) {
  if (argc == 6 && !strcmp(argv[3], "contacts")) {
    const dds_entity_t pp = dds_create_participant((dds_domainid_t)atoi(argv[1]), NULL, NULL);
    palp_SessionState st;
    if (!palp_test_open_session(pp, argv[2], 10.0, &st)) {
      fprintf(stderr, "finding_writer: no open session of %s within 10 s\n", argv[2]);
      return 1;
    }
    const int n = forge_contacts(pp, &st, atof(argv[4]), atoi(argv[5]));
    printf("finding_writer: %d contact samples of 15 N written into session %u's partition\n", n, st.session_id);
    dds_delete(pp);
    return n > 0 ? 0 : 1;
  }
  if (argc == 4 && !strcmp(argv[3], "frames")) {
    const dds_entity_t pp = dds_create_participant((dds_domainid_t)atoi(argv[1]), NULL, NULL);
    palp_SessionState st;
    if (!palp_test_open_session(pp, argv[2], 10.0, &st)) {
      fprintf(stderr, "finding_writer: no open session of %s within 10 s\n", argv[2]);
      return 1;
    }
    const dds_entity_t pub = palp_dds_session_publisher(pp, st.partition);
    const dds_entity_t sub = palp_dds_session_subscriber(pp, st.partition);
    const int fs = forge_frame(pp, pub, sub, &st, PALP_TOPIC_FINGER_SAMPLE);
    const int lm = forge_frame(pp, pub, sub, &st, PALP_TOPIC_LOCAL_MODEL);
    dds_sleepfor(DDS_MSECS(200)); /* delivered before the participant goes */
    printf("finding_writer: %d finger sample(s) and %d local model(s) of session %u written again with frame "
           "2^64 - 1\n", fs, lm, st.session_id);
    dds_delete(pp);
    return fs && lm ? 0 : 1;
  }
  if (argc < 6) {
    fprintf(stderr, "usage: %s DOMAIN TRAINEE MARK BURST SECONDS\n", argv[0]);
    return 2;
  }
  const dds_entity_t pp = dds_create_participant((dds_domainid_t)atoi(argv[1]), NULL, NULL);
  palp_SessionState st;
  const int found = palp_test_open_session(pp, argv[2], 10.0, &st);
  if (!found) {
    fprintf(stderr, "finding_writer: no open session of %s within 10 s\n", argv[2]);
    return 1;
  }
  /* "own-visual-mark": as own-visual, but MARK is marked (at the pole), not withdrawn: what a palp-web
   * trainee page writes beside the trainee's own station */
  const int marks = argc > 6 && !strcmp(argv[6], "own-visual-mark");
  const int visual = argc > 6 && (!strcmp(argv[6], "own-visual") || marks);
  if (visual && !join_visual(pp, st.session_id)) {
    fprintf(stderr, "finding_writer: session %u refused (or did not answer) its join as a visual station\n",
            st.session_id);
    return 1;
  }
  if (visual) printf("finding_writer: joined session %u as a visual station\n", st.session_id);
  const dds_entity_t pub = palp_dds_session_publisher(pp, st.partition);
  const dds_entity_t w = palp_dds_create_writer(pub, palp_dds_create_topic(pp, PALP_TOPIC_FINDING), PALP_TOPIC_FINDING);
  for (int i = 0; i < 200 && w > 0; i++) { /* matched with the server's reader: up to 2 s */
    dds_publication_matched_status_t m;
    if (dds_get_publication_matched_status(w, &m) == 0 && m.current_count > 0) break;
    dds_sleepfor(DDS_MSECS(10));
  }
  palp_Finding f;
  memset(&f, 0, sizeof f);
  f.op = marks ? palp_FINDING_MARK : palp_FINDING_WITHDRAW;
  if (marks) f.point = (palp_Vec3){0, 0, 0.04}, f.time = 0.5; /* the dome's pole, R = 40 mm */
  const int own = argc > 6 && (!strcmp(argv[6], "own") || visual);
  const int dispose = argc > 6 && !strcmp(argv[6], "dispose"); /* disposes of the made-up keys: no sample */
  f.mark_id = (uint32_t)atoi(argv[3]);
  const int burst = atoi(argv[4]), rounds = (int)(atof(argv[5]) * 10);
  int written = 0;
  for (int r = 0; r < rounds; r++) {
    for (int k = 0; k < burst; k++) {
      f.session_id = own ? st.session_id : st.session_id + 1000 + (uint32_t)(r * burst + k);
      written += (dispose ? dds_dispose(w, &f) : dds_write(w, &f)) == 0;
    }
    dds_sleepfor(DDS_MSECS(100));
  }
  /* The server looks a finding's writer up in Cyclone's discovery data when its tick takes it; a peer
   * gone by then is "a writer already gone", refused whatever it was (a loaded run's server took the
   * findings after this peer's 0.1 s: refused, unanswered, 1 run in ~6). Writing into the session itself,
   * linger 1 s more. */
  if (own) dds_sleepfor(DDS_SECS(1));
  printf("finding_writer: %d findings naming %s written into %s (session %u)\n", written,
         own ? "the session itself" : "other sessions", st.partition, st.session_id);
  dds_delete(pp);
  return 0;
}
