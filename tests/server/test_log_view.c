/*
 * test_log_view.c - the server's session log as one session sees it (session 68): the counts a
 * station (and palp-web, for a trainee's page) reads off its server's status turned into what the
 * session's user is told (idl/palp_dds_log_view.c), and the station's news of them, said at once and
 * not again for a minute while the losses go on (palp_cli_station_log_news, client/station.c). The
 * statuses are written out by hand (the counts a server's status carries, one a second); every
 * expected line is written out too. No DDS.
 */
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "palp_dds_log_view.h"
#include "station.h"

#define S 1000000000LL /* [ns] */

static const char *words(const palp_dds_log_view *v, int trainee, int *level) {
  static char buf[400];
  *level = palp_dds_log_view_words(v, trainee, buf, sizeof buf);
  return buf;
}

static void test_view(void) {
  palp_dds_log_view v = {0};
  int lvl;
  /* The session first listed: 7 shed and 500 failed before it, which are not hers. */
  palp_dds_log_view_status(&v, 100, 7, 500, 0);
  palp_dds_log_view_status(&v, 150, 7, 500, 1 * S);
  CHECK(!strcmp(words(&v, 1, &lvl), "") && lvl == 0, "losses from before the session are not said: \"%s\" (%d)",
        words(&v, 1, &lvl), lvl);
  /* Then 49 fail: said while they go on, why in the words a trainee can pass on. */
  palp_dds_log_view_status(&v, 150, 7, 549, 2 * S);
  CHECK(!strcmp(words(&v, 1, &lvl),
                "the server's session log is losing records: 49 so far while this session runs (the log's disk or "
                "its cap is full); this session will be incomplete in the review: tell your instructor") &&
            lvl == 1,
        "49 failed: \"%s\" (%d)", words(&v, 1, &lvl), lvl);
  CHECK(!strcmp(words(&v, 0, &lvl),
                "the server's session log is losing records: 49 so far while this session runs (the log's disk or "
                "its cap is full); this session will be incomplete in the review; the server's log says what to do") &&
            lvl == 1,
        "  an instructor following the session is told what to do, not to tell one: \"%s\"", words(&v, 0, &lvl));
  palp_dds_log_view_status(&v, 150, 7, 560, 3 * S);
  CHECK(v.failed == 60 && v.shed == 0 && v.losing == 1, "11 more: 60 failed, 0 shed, losing (%llu, %llu, %d)",
        (unsigned long long)v.failed, (unsigned long long)v.shed, v.losing);
  /* A small batch written 1 s after the last loss is not yet "writing again" (no flip each second). */
  palp_dds_log_view_status(&v, 200, 7, 560, 4 * S);
  CHECK(words(&v, 1, &lvl)[0] && lvl == 1, "written 1 s after the last loss: still losing (%d)", lvl);
  palp_dds_log_view_status(&v, 260, 7, 560, 9 * S);
  CHECK(!strcmp(words(&v, 1, &lvl),
                "the server's session log is writing again; 60 records were lost while this session ran: it will be "
                "incomplete in the review") &&
            lvl == 2,
        "written, and 6 s since the last loss (>= 5 s): \"%s\" (%d)", words(&v, 1, &lvl), lvl);
  /* Sheds then (the writer behind): both causes named. */
  palp_dds_log_view_status(&v, 300, 12, 560, 11 * S);
  CHECK(!strcmp(words(&v, 1, &lvl),
                "the server's session log is losing records: 65 so far while this session runs (the server was too "
                "busy to write some, and the log's disk or its cap is full); this session will be incomplete in the "
                "review: tell your instructor") &&
            lvl == 1,
        "5 shed after 60 failed: \"%s\"", words(&v, 1, &lvl));
  /* The server begun again (its counts from 0): what was lost stays lost, and counting goes on. */
  palp_dds_log_view_status(&v, 10, 0, 0, 12 * S);
  CHECK(v.shed + v.failed == 65, "a server begun again: the 65 lost stay (%llu)", (unsigned long long)(v.shed + v.failed));
  palp_dds_log_view_status(&v, 20, 0, 3, 13 * S);
  CHECK(v.shed == 5 && v.failed == 63 && v.losing, "  and 3 more failed after it: 5 shed, 63 failed (%llu, %llu)",
        (unsigned long long)v.shed, (unsigned long long)v.failed);

  palp_dds_log_view o = {0};
  palp_dds_log_view_status(&o, 0, 0, 0, 0);
  palp_dds_log_view_status(&o, 10, 4, 0, 1 * S);
  CHECK(!strcmp(words(&o, 1, &lvl),
                "the server's session log is losing records: 4 so far while this session runs (the server was too "
                "busy to write them); this session will be incomplete in the review: tell your instructor"),
        "sheds alone: \"%s\"", words(&o, 1, &lvl));
  /* No loss for 6 s, but nothing written either: a full file that takes nothing is not writing again. */
  palp_dds_log_view z = {0};
  palp_dds_log_view_status(&z, 100, 0, 0, 0);
  palp_dds_log_view_status(&z, 100, 0, 5, 1 * S);
  palp_dds_log_view_status(&z, 100, 0, 5, 7 * S);
  CHECK(words(&z, 1, &lvl)[0] && lvl == 1, "no loss for 6 s and nothing written: still losing (%d)", lvl);
  char sum[300];
  CHECK(palp_dds_log_view_summary(&v, sum, sizeof sum) == 1 &&
            !strcmp(sum, "the server's session log lost 68 records while this session ran (the server was too busy to "
                         "write some, and the log's disk or its cap is full): it will be incomplete in the review"),
        "the loss in all as the session ends: \"%s\"", sum);
  palp_dds_log_view n = {0};
  for (int k = 0; k < 5; k++) palp_dds_log_view_status(&n, 100 * (uint64_t)k, 0, 0, k * S);
  CHECK(!strcmp(words(&n, 1, &lvl), "") && lvl == 0 && palp_dds_log_view_summary(&n, sum, sizeof sum) == 0 && !sum[0],
        "a log that loses nothing says nothing, during the session or at its end (%d)", lvl);
}

/* A server that says each session's own losses (palp_session_log, session 69): her own counts replace
 * the server's, which then say only whether the log writes again; another session's losses are not
 * hers. */
static void test_own(void) {
  palp_dds_log_view v = {0};
  int lvl;
  palp_dds_log_view_status(&v, 100, 0, 0, 0);
  palp_dds_log_view_session(&v, 0, 0, 0); /* her session opened: nothing of hers lost */
  palp_dds_log_view_status(&v, 150, 0, 400, 1 * S); /* another session loses 400 */
  palp_dds_log_view_session(&v, 0, 0, 1 * S);
  CHECK(!strcmp(words(&v, 1, &lvl), "") && lvl == 0 && v.own,
        "the server loses 400 records of another session, none of hers: nothing said (\"%s\", %d)", words(&v, 1, &lvl),
        lvl);
  palp_dds_log_view_session(&v, 0, 37, 2 * S);
  palp_dds_log_view_status(&v, 150, 0, 900, 2 * S);
  CHECK(!strcmp(words(&v, 1, &lvl),
                "the server's session log is losing this session's records: 37 so far (the log's disk or its cap is "
                "full); this session will be incomplete in the review: tell your instructor") &&
            lvl == 1,
        "37 of hers among the server's 900: her 37 said: \"%s\" (%d)", words(&v, 1, &lvl), lvl);
  CHECK(!strcmp(words(&v, 0, &lvl),
                "the server's session log is losing this session's records: 37 so far (the log's disk or its cap is "
                "full); this session will be incomplete in the review; the server's log says what to do"),
        "  to an observer: \"%s\"", words(&v, 0, &lvl));
  palp_dds_log_view_session(&v, 0, 37, 3 * S); /* the same count again (a repeat): no rise */
  palp_dds_log_view_status(&v, 300, 0, 950, 8 * S); /* written, the others still losing, hers not for 6 s */
  CHECK(!strcmp(words(&v, 1, &lvl),
                "the server's session log is writing again; 37 of this session's records were lost: it will be "
                "incomplete in the review") &&
            lvl == 2,
        "hers quiet 6 s and records written, while the server loses others': writing again: \"%s\" (%d)",
        words(&v, 1, &lvl), lvl);
  palp_dds_log_view_session(&v, 3, 37, 9 * S);
  lvl = palp_dds_log_view_words(&v, 1, NULL, 0);
  CHECK(lvl == 1 && v.shed == 3 && v.failed == 37,
        "3 of hers shed after: losing again (%d; %llu shed, %llu failed)", lvl, (unsigned long long)v.shed,
        (unsigned long long)v.failed);
  palp_dds_log_view_session(&v, 0, 5, 10 * S); /* counts that fall cannot be her server's */
  CHECK(v.shed == 3 && v.failed == 37, "a sample whose counts fall is ignored: what was lost stays (%llu, %llu)",
        (unsigned long long)v.shed, (unsigned long long)v.failed);
  char sum[300];
  CHECK(palp_dds_log_view_summary(&v, sum, sizeof sum) == 1 &&
            !strcmp(sum, "the server's session log lost 40 of this session's records (the server was too busy to write "
                         "some, and the log's disk or its cap is full): it will be incomplete in the review"),
        "the loss in all, hers: \"%s\"", sum);
  /* Her counts heard after the server's had said "losing" (a status read first): hers replace them. */
  palp_dds_log_view w = {0};
  palp_dds_log_view_status(&w, 100, 0, 0, 0);
  palp_dds_log_view_status(&w, 100, 0, 25, 1 * S);
  CHECK(palp_dds_log_view_words(&w, 1, NULL, 0) == 1, "the server's counts first: losing");
  palp_dds_log_view_session(&w, 0, 0, 1 * S);
  CHECK(palp_dds_log_view_words(&w, 1, NULL, 0) == 0 && w.shed + w.failed == 0,
        "  then her own, none lost: nothing to say (%llu)", (unsigned long long)(w.shed + w.failed));
}

/* The station's news: said at once, not again within PALP_CLI_LOG_SAY_S while losing, "writing again"
 * once after it; an observer is not told to tell an instructor. */
static void test_news(void) {
  palp_cli_station st;
  memset(&st, 0, sizeof st);
  st.has_last_join = 1;
  st.last_join.role = palp_ROLE_TRAINEE;
  char line[400];
  palp_dds_log_view_status(&st.log, 100, 0, 0, 0);
  CHECK(palp_cli_station_log_news(&st, line, sizeof line) == 0 && !line[0], "nothing lost: no news");
  palp_dds_log_view_status(&st.log, 100, 0, 12, 1 * S);
  CHECK(palp_cli_station_log_news(&st, line, sizeof line) == 1 &&
            !strcmp(line, "the server's session log is losing records: 12 so far while this session runs (the log's "
                          "disk or its cap is full); this session will be incomplete in the review: tell your instructor"),
        "12 lost: said at once: \"%s\"", line);
  palp_dds_log_view_status(&st.log, 100, 0, 30, 2 * S);
  CHECK(palp_cli_station_log_news(&st, line, sizeof line) == 0, "30 lost a second later: not said again within %.0f s",
        PALP_CLI_LOG_SAY_S);
  palp_dds_log_view_status(&st.log, 180, 0, 30, 8 * S);
  CHECK(palp_cli_station_log_news(&st, line, sizeof line) == 1 &&
            !strcmp(line, "the server's session log is writing again; 30 records were lost while this session ran: it "
                          "will be incomplete in the review"),
        "written 6 s after the last loss: \"%s\"", line);
  CHECK(palp_cli_station_log_news(&st, line, sizeof line) == 0, "  said once");
  palp_dds_log_view_status(&st.log, 180, 0, 31, 9 * S);
  CHECK(palp_cli_station_log_news(&st, line, sizeof line) == 1 && strstr(line, "losing records: 31 so far"),
        "a loss after it is said at once: \"%s\"", line);
  st.last_join.role = palp_ROLE_OBSERVER;
  memset(&st.log_said, 0, sizeof st.log_said);
  CHECK(palp_cli_station_log_news(&st, line, sizeof line) == 1 && strstr(line, "; the server's log says what to do") &&
            !strstr(line, "tell your instructor"),
        "an observer's station: \"%s\"", line);
}

int main(void) {
  test_view();
  test_own();
  test_news();
  return failures ? 1 : 0;
}
