/* test_session_wrap.c - local session ids wrap without handing out one still open (plain DDS, domain 219).
 *
 * A server's local session ids run 1 .. 2^20 - 1 and then start again at 1. Until session 89 the wrap
 * gave the next session id 1 even while a session with it was still open: the two then shared a
 * partition (feedback, deformation, findings crossing over) and a slot of the session log (a read-only
 * review's finding; ~14.6 h of JOINs and LEAVEs at the default join_rate). The wrap is brought close
 * here by the server's test hook, palp_srv_def.session_local_max = 3:
 * - alice joins and stays: session 1; bob joins and leaves (2), then carol (3);
 * - dave joins: the ids wrap, 1 is alice's, so he gets 2 (before: 1, alice's);
 * - erin joins with alice and dave still open: 3.
 * Expected by hand from the rule "the next id after the last handed out, past 3 back to 1, skipping
 * those open". ~3 s. */
#include <string.h>

#include "harness.h"

#define DOMAIN 219

static uint32_t join_trainee(palp_cli_station *st, const char *name) {
  palp_cli_join j = {.role = palp_ROLE_TRAINEE, .phantom_id = 1, .user_name = name, .timeout = 5.0};
  char label[32];
  snprintf(label, sizeof label, "wrap-%s", name);
  test_station_join_as(st, DOMAIN, label, &j);
  return PALP_DDS_ID_LOCAL(st->session_id);
}

int main(void) {
  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  cfg.max_sessions = 4;
  const palp_srv_def def = {.cfg = cfg, .session_local_max = 3};
  test_server ts = {0};
  test_server_start_def(&ts, &def);

  palp_cli_station alice, bob, carol, dave, erin;
  const uint32_t a = join_trainee(&alice, "alice");
  const uint32_t b = join_trainee(&bob, "bob");
  palp_cli_station_leave(&bob);
  palp_cli_station_close(&bob);
  const uint32_t c = join_trainee(&carol, "carol");
  palp_cli_station_leave(&carol);
  palp_cli_station_close(&carol);
  CHECK(a == 1 && b == 2 && c == 3, "before the wrap: alice %u, bob %u, carol %u (1, 2, 3)", a, b, c);
  test_sleep(0.3); /* bob's and carol's sessions closed */
  const uint32_t d = join_trainee(&dave, "dave");
  CHECK(d == 2, "after the wrap, with alice's session 1 open, dave gets %u (2; before session 89: 1, alice's)", d);
  const uint32_t e = join_trainee(&erin, "erin");
  CHECK(e == 3, "then erin gets %u (3: alice's 1 and dave's 2 open)", e);
  CHECK(palp_srv_open_sessions(ts.srv) == 3, "3 sessions open (%d)", palp_srv_open_sessions(ts.srv));
  palp_cli_station_leave(&alice);
  palp_cli_station_leave(&dave);
  palp_cli_station_leave(&erin);
  palp_cli_station_close(&alice);
  palp_cli_station_close(&dave);
  palp_cli_station_close(&erin);
  test_server_stop(&ts);
  fprintf(stderr, "%s\n", palp_test_failures ? "FAILED" : "passed");
  return palp_test_failures != 0;
}
