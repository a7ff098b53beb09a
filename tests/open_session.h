/* open_session.h - a test peer's wait for a trainee's session to open, read from the public session
 * state (default partition) as any participant may: for the tools that then write into it
 * (tests/server/finding_writer.c, tests/security/forger.c). */
#ifndef PALP_TESTS_OPEN_SESSION_H
#define PALP_TESTS_OPEN_SESSION_H

#include <string.h>

#include "palp_dds.h"

/* Up to `seconds` for an OPEN session of trainee `name` on participant pp: 1 and *out, or 0. */
static inline int palp_test_open_session(dds_entity_t pp, const char *name, double seconds, palp_SessionState *out) {
  const dds_entity_t rd =
      palp_dds_create_reader(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_STATE), PALP_TOPIC_SESSION_STATE);
  int found = 0;
  for (int i = 0; i < (int)(seconds * 20) && !found && rd > 0; i++) {
    void *ptr[16] = {NULL};
    dds_sample_info_t info[16];
    const int n = dds_read(rd, ptr, info, 16, 16);
    for (int k = 0; k < n && !found; k++) {
      const palp_SessionState *m = ptr[k];
      if (info[k].valid_data && m->phase == palp_PHASE_OPEN && !strcmp(m->trainee_name, name)) *out = *m, found = 1;
    }
    if (n > 0) dds_return_loan(rd, ptr, n);
    if (!found) dds_sleepfor(DDS_MSECS(50));
  }
  return found;
}

#endif
