/*
 * finding_writer.c - a peer in a session's partition of an unsecured classroom, for
 * server_exercise_client: waits (up to 10 s) for TRAINEE's open session, then writes withdrawals of
 * mark MARK into its partition, BURST every 100 ms for SECONDS, naming made-up sessions (the
 * session's id + 1000 + k) or, with "own", the session itself (withdrawals: they never add a mark).
 * Prints what it wrote; exit 0, or 1 when no such session opened.
 * usage: test_finding_writer DOMAIN TRAINEE MARK BURST SECONDS [own]
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../open_session.h"
#include "palp_dds.h"

int main(int argc, char **argv) {
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
  const dds_entity_t pub = palp_dds_session_publisher(pp, st.partition);
  const dds_entity_t w = palp_dds_create_writer(pub, palp_dds_create_topic(pp, PALP_TOPIC_FINDING), PALP_TOPIC_FINDING);
  for (int i = 0; i < 200 && w > 0; i++) { /* matched with the server's reader: up to 2 s */
    dds_publication_matched_status_t m;
    if (dds_get_publication_matched_status(w, &m) == 0 && m.current_count > 0) break;
    dds_sleepfor(DDS_MSECS(10));
  }
  palp_Finding f;
  memset(&f, 0, sizeof f);
  f.op = palp_FINDING_WITHDRAW;
  const int own = argc > 6 && !strcmp(argv[6], "own");
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
  printf("finding_writer: %d findings naming %s written into %s (session %u)\n", written,
         own ? "the session itself" : "other sessions", st.partition, st.session_id);
  dds_delete(pp);
  return 0;
}
