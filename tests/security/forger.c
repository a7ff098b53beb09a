/*
 * forger.c - an authenticated trainee forging another trainee's session id, for security_cli: waits
 * (up to 10 s) for VICTIM's open session, then writes, in its own partition "palp/s/<own name>/<id>"
 * (which its permissions allow), contacts of finger 1 pressing at the pole and marks, every 50 ms for
 * SECONDS, all naming VICTIM's session. The server reads each session in its own partition and never
 * sees them; a classroom-wide reader (palp-web, palp-recorder) must not take them for VICTIM's.
 * Prints what it wrote; exit 0, or 1 when no such session opened or the identity was refused.
 * usage: test_security_forger DOMAIN PKI IDENTITY VICTIM SECONDS
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../open_session.h"
#include "palp_dds.h"
#include "palp_dds_security.h"

int main(int argc, char **argv) {
  if (argc < 6) {
    fprintf(stderr, "usage: %s DOMAIN PKI IDENTITY VICTIM SECONDS\n", argv[0]);
    return 2;
  }
  palp_dds_security sec;
  char err[512];
  if (palp_dds_security_init(&sec, argv[2], argv[3], err, sizeof err) < 0) {
    fprintf(stderr, "forger: %s\n", err);
    return 1;
  }
  const dds_entity_t pp = palp_dds_create_participant((dds_domainid_t)atoi(argv[1]), &sec);
  if (pp < 0) {
    fprintf(stderr, "forger: no participant: %s\n", dds_strretcode(pp));
    return 1;
  }
  palp_SessionState st;
  const int found = palp_test_open_session(pp, argv[4], 10.0, &st);
  if (!found) {
    fprintf(stderr, "forger: no open session of %s within 10 s\n", argv[4]);
    return 1;
  }
  const char *self = strchr(argv[3], '/');
  char part[64];
  snprintf(part, sizeof part, "palp/s/%s/%u", self ? self + 1 : argv[3], st.session_id);
  const dds_entity_t pub = palp_dds_session_publisher(pp, part);
  const dds_entity_t wc = palp_dds_create_writer(pub, palp_dds_create_topic(pp, PALP_TOPIC_CONTACT), PALP_TOPIC_CONTACT);
  const dds_entity_t wf = palp_dds_create_writer(pub, palp_dds_create_topic(pp, PALP_TOPIC_FINDING), PALP_TOPIC_FINDING);
  if (wc < 0 || wf < 0) {
    fprintf(stderr, "forger: writers in %s refused: %s / %s\n", part, dds_strretcode(wc), dds_strretcode(wf));
    return 1;
  }
  dds_sleepfor(DDS_MSECS(500)); /* matched with the classroom-wide readers */
  palp_Contact c;
  memset(&c, 0, sizeof c);
  c.session_id = st.session_id;
  c.finger = 1;
  c.mode = palp_CONTACT_FINGER;
  c.center = (palp_Vec3){0, 0, 0.045};
  c.radius = 0.008;
  palp_Finding f;
  memset(&f, 0, sizeof f);
  f.session_id = st.session_id;
  f.op = palp_FINDING_MARK;
  f.point = (palp_Vec3){0, 0, 0.040};
  int contacts = 0, findings = 0;
  const int rounds = (int)(atof(argv[5]) * 20);
  for (int r = 0; r < rounds; r++) {
    c.seq = (uint64_t)r + 1;
    c.source_time_ns = palp_dds_now_ns();
    contacts += dds_write(wc, &c) == 0;
    if (r % 10 == 0) {
      f.mark_id = 100 + (uint32_t)r / 10;
      f.time = 0.05 * r;
      findings += dds_write(wf, &f) == 0;
    }
    dds_sleepfor(DDS_MSECS(50));
  }
  printf("forger: %d contacts and %d marks naming %s's session %u written into %s\n", contacts, findings, argv[4],
         st.session_id, part);
  dds_delete(pp);
  return 0;
}
