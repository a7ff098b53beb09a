/* open_session.h - a test peer's wait for a trainee's session to open, read from the public session
 * state (default partition) as any participant may: for the tools that then write into it
 * (tests/server/finding_writer.c, tests/security/forger.c), and for the security tests' stations
 * (tests/security/test_classroom.c, test_disposed.c), whose own state reader holds only their session. */
#ifndef PALP_TESTS_OPEN_SESSION_H
#define PALP_TESTS_OPEN_SESSION_H

#include <string.h>

#include "palp_dds.h"

/* Up to `seconds` for an OPEN session of trainee `name` on participant pp: 1 and *out, or 0. Through a
 * reader of its own (transient-local: every state sent anew), each state read once as it comes, so
 * more sessions than one read holds are all seen; the reader deleted after. */
static inline int palp_test_open_session(dds_entity_t pp, const char *name, double seconds, palp_SessionState *out) {
  const dds_entity_t rd =
      palp_dds_create_reader(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_STATE), PALP_TOPIC_SESSION_STATE);
  int found = 0;
  for (int i = 0; i < (int)(seconds * 20) && !found && rd > 0; i++) {
    int n;
    do {
      void *ptr[16] = {NULL};
      dds_sample_info_t info[16];
      n = dds_read_mask(rd, ptr, info, 16, 16, DDS_NOT_READ_SAMPLE_STATE);
      for (int k = 0; k < n && !found; k++) {
        const palp_SessionState *m = ptr[k];
        if (info[k].valid_data && m->phase == palp_PHASE_OPEN && !strcmp(m->trainee_name, name)) *out = *m, found = 1;
      }
      if (n > 0) dds_return_loan(rd, ptr, n);
    } while (n > 0 && !found);
    if (!found) dds_sleepfor(DDS_MSECS(50));
  }
  if (rd > 0) dds_delete(rd);
  return found;
}

#endif
