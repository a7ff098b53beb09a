/* test_first_contact.c - a trainee's first press, written the moment its join returns,
 * reaches the server. Contacts are best-effort and volatile (idl/palp_dds.c): a sample
 * written before the session's endpoints have matched is dropped without a trace, and a
 * machine busy enough to slow discovery lost a keyboard trainee's whole first press
 * (server_keyboard in the suite: feedback 0 N). palp_cli_station_join now returns only
 * once the station's session endpoints are matched (or its timeout passed). Six stations
 * in turn each write one 2 N press right after joining and nothing else: every one must
 * get the phantom's 2 N back (within 10%), and each join must return with its contact
 * writer and feedback reader matched. On an idle loopback the endpoints have already
 * matched when the reply arrives (the server makes them before it replies), so this passes
 * without the wait too: it guards the end-to-end property; the wait covers discovery that
 * lags the reply (a busy machine, a lossy network). Domain 119. */
#include <math.h>
#include <string.h>

#include "harness.h"

#define DOMAIN 119

int main(void) {
  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  test_server ts = {0};
  test_server_start(&ts, &cfg);
  enum { N = 6 };
  int pressed = 0, matched = 0;
  for (int k = 0; k < N; k++) {
    palp_cli_station st;
    char label[32];
    snprintf(label, sizeof label, "first%d", k);
    test_station_join(&st, DOMAIN, label, palp_ROLE_TRAINEE, 1 + (uint32_t)(k % 2), 0, 1, 0);
    dds_publication_matched_status_t pm;
    dds_subscription_matched_status_t sm;
    const int m = dds_get_publication_matched_status(st.contact_w, &pm) == 0 && pm.current_count > 0 &&
                  dds_get_subscription_matched_status(st.feedback_r, &sm) == 0 && sm.current_count > 0;
    test_send_force(&st, 0, 2, 20.0, 30.0 * k, 2.0, 1); /* the only contact this station sends */
    int samples = 0;
    const double f = test_last_feedback(&st, 1.0, &samples);
    fprintf(stderr, "station %d: matched at join %d, feedback %.3f N (%d samples)\n", k, m, f, samples);
    matched += m;
    pressed += fabs(f - 2.0) <= 0.2;
    palp_cli_station_leave(&st);
    test_sleep(0.1);
    palp_cli_station_close(&st);
  }
  CHECK(matched == N, "every join returned with its contact writer and feedback reader matched (%d of %d)", matched,
        N);
  CHECK(pressed == N, "every first press, written as the join returned, came back as 2 N +- 0.2 N (%d of %d)", pressed,
        N);
  test_server_stop(&ts);
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
