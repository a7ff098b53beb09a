/*
 * test_log_full.c - a session log that fills mid-session (session 66), over real DDS into a real
 * SQLite file (domain 134). After ava's session, logged whole by an uncapped server (yesterday's
 * class), the file is capped (palp_srv_db_log_open's max_bytes, the config's session_log_max_mb:
 * PRAGMA max_page_count, which SQLite enforces as SQLITE_FULL, the very error a full disk gives) a
 * little above its size:
 *  - fia's practice exercise (tests/server/exercise_short.json, 2 s) fills it as she presses: her
 *    session goes on to its time limit, she is debriefed, and her score comes graded from what the
 *    log holds, with log_complete false and the review's health line ("CUT SHORT: ..." or
 *    "DAMAGED: ...", as the batches fell); the words her station prints (palp_cli_score_text) end
 *    with "The session's log is incomplete: the score may be low."; palp-review's reading of the
 *    log gives the score she was told, to the last bit, and the same health line;
 *  - gus's session on a plain phantom, pressing all along, keeps stepping through it (its feedback
 *    counted over 1 s after the loss); his station, reading his server's status, tells him the log is
 *    losing records while his session runs (session 68: a free-practice trainee has no score to say it;
 *    "writing again" is test_log_view's: the prune below frees too little for a session pressing on);
 *  - the server's log says the loss as it happens, with the cap and what to do, before the stop;
 *  - ida's practice session, opened while the log is full, is debriefed and told why she gets no
 *    score ("not in the session log, which is losing records (database or disk is full); ...");
 *  - the instructor's `palp-review prune --older-than 0` takes ava's session (and any other whose
 *    end got in) and frees pages: the log writes again, the server's log says so, and hal's
 *    session, opened after, is logged whole;
 *  - the file stays sound (PRAGMA integrity_check ok).
 */
#define _GNU_SOURCE
#include <math.h>
#include <pthread.h>
#include <sqlite3.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "assess_log.h"
#include "db_log.h"
#include "grader.h" /* palp_srv_health_fit */
#include "harness.h"
#include "palp_assess.h"
#include "palp_db.h"

#define DOMAIN 134
#define EX_SHORT 8
/* Above the log after ava's session: fia's session's opening rows (its scene and exercise, ~20 KB) and its
 * first second or so of samples; her 2 s of pressing at 250 Hz write several times that. */
#define MARGIN_BYTES (96 * 1024)

static long file_size(const char *path) {
  struct stat sb;
  return stat(path, &sb) == 0 ? (long)sb.st_size : -1;
}

/* 1 when the file at path holds needle, the first such line copied into line. */
static int log_has(const char *path, const char *needle, char *line, size_t len) {
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  char buf[2048];
  int found = 0;
  while (!found && fgets(buf, sizeof buf, f))
    if (strstr(buf, needle)) {
      found = 1;
      snprintf(line, len, "%s", buf);
      line[strcspn(line, "\n")] = 0;
    }
  fclose(f);
  return found;
}

static int wait_log(const char *path, const char *needle, double seconds, char *line, size_t len) {
  for (double t = 0; t < seconds; t += 0.1) {
    if (log_has(path, needle, line, len)) return 1;
    test_sleep(0.1);
  }
  return log_has(path, needle, line, len);
}

int main(int argc, char **argv) {
  REQUIRE(argc > 1, "usage: test_server_log_full PALP_REVIEW");
  test_init();
  char err[512];
  char cwd[512], db_path[700], log_path[700];
  REQUIRE(getcwd(cwd, sizeof cwd) != NULL, "cwd");
  snprintf(db_path, sizeof db_path, "%s/server_log_full.db", cwd);
  snprintf(log_path, sizeof log_path, "%s/server_log_full.log", cwd);
  unlink(db_path);
  unlink(log_path);
  char json[1024];
  snprintf(json, sizeof json,
           "{\"domain_id\": %d, \"tick_rate_hz\": 100, \"tick_threads\": 1, \"max_force\": 20,"
           " \"session_exercise\": \"always\", \"session_log_max_mb\": 1,"
           " \"phantoms\": [{\"id\": 1, \"name\": \"test dome\", \"scene\": \"paper_step.json\"}],"
           " \"exercises\": [{\"id\": %d, \"file\": \"%s/exercise_short.json\", \"physics_rate_hz\": 250}]}",
           DOMAIN, EX_SHORT, PALP_TEST_DIR);
  palp_srv_config cfg;
  REQUIRE(palp_srv_config_parse(json, PALP_CONFIG_DIR, &cfg, err, sizeof err) == 0, "config: %s", err);
  /* palp-server gives its log the config's MB (server/main.c; test server_session_log checks the line it
   * says); this test gives palp_srv_db_log_open a cap in bytes, 96 KB above the log it makes */
  CHECK(cfg.session_log_max_mb == 1.0, "config: session_log_max_mb read (%g MB)", cfg.session_log_max_mb);

  /* Yesterday's class: ava's session, logged whole by an uncapped server; the file's size then. */
  palp_srv_db_log *dbl = NULL;
  REQUIRE(palp_srv_db_log_open(db_path, 0, NULL, &dbl, err, sizeof err) == 0, "log: %s", err);
  {
    const palp_srv_def def0 = {.cfg = cfg, .events = palp_srv_db_log_events(dbl), .verbose = 0};
    test_server ts0;
    test_server_start_def(&ts0, &def0);
    palp_cli_station a;
    test_station_join(&a, DOMAIN, "ava", palp_ROLE_TRAINEE, 1, 0, 1, 0);
    test_send_force(&a, 0, 1, 0, 0, 2.0, 1);
    test_sleep(2.0);
    palp_cli_station_leave(&a);
    test_sleep(0.3);
    test_server_stop(&ts0);
    palp_cli_station_close(&a);
  }
  palp_srv_db_log_close(dbl);
  char ava_uid[128] = "";
  {
    palp_db *db0 = NULL;
    REQUIRE(palp_db_open(db_path, 0, &db0, err, sizeof err) == 0, "read the log: %s", err);
    palp_db_filter flt = {.trainee = "ava"};
    palp_db_session_info *list = NULL;
    int n = 0;
    REQUIRE(palp_db_list_sessions(db0, &flt, &list, &n) == 0 && n == 1 && list[0].end_unix_s > 0,
            "ava's session logged whole (%d)", n);
    snprintf(ava_uid, sizeof ava_uid, "%s", list[0].uid);
    free(list);
    palp_db_close(db0);
  }
  const long before = file_size(db_path);
  REQUIRE(before > 0, "the log's file after ava's session (%ld bytes)", before);
  const int64_t cap = before + MARGIN_BYTES;

  palp_log plog;
  REQUIRE(palp_log_init(&plog, "palp-server", PALP_LOG_INFO, log_path) == 0, "server log file");
  REQUIRE(palp_srv_db_log_open(db_path, cap, &plog, &dbl, err, sizeof err) == 0, "capped log: %s", err);
  char line[2048] = "", cap_text[64];
  snprintf(cap_text, sizeof cap_text, "of its cap of %.2f MB (session_log_max_mb)", (double)cap * 1e-6);
  CHECK(log_has(log_path, cap_text, line, sizeof line),
        "the server's log says the cap as it opens: \"%s\"", line);
  /* one log for the server and its session log, as palp-server has */
  const palp_srv_def def = {.cfg = cfg, .events = palp_srv_db_log_events(dbl), .verbose = 0, .log = &plog};
  test_server ts;
  test_server_start_def(&ts, &def);

  /* gus presses a plain phantom all along; fia's practice session fills the log. */
  palp_cli_station g, f;
  test_station_join(&g, DOMAIN, "gus", palp_ROLE_TRAINEE, 1, 0, 1, 0);
  test_send_force(&g, 0, 1, 0, 0, 2.0, 1);
  test_station_join(&f, DOMAIN, "fia", palp_ROLE_TRAINEE, EX_SHORT, 0, 1, 0);
  uint64_t seq = 1;
  for (int k = 0; k < 120; k++) { /* down to 12 mm over lesion 1, then slide; her 2 s limit ends it */
    test_send_finger(&f, 31 + (k > 60 ? 0.2 * (k - 60) : 0), 41, k <= 40 ? 0.012 * k / 40.0 : 0.012, seq++);
    palp_cli_station_session_closed(&g, NULL, 0); /* gus's station reads its server's status as palp-client does */
    test_sleep(0.02);
  }
  char loss[2048] = "";
  CHECK(wait_log(log_path, "records lost so far", 5.0, loss, sizeof loss) &&
            strstr(loss, "failed: writing the session log: database or disk is full") &&
            strstr(loss, "reached its cap of ") && strstr(loss, cap_text + strlen("of its cap of ")) &&
            strstr(loss, "sessions go on"),
        "the server's log says the loss as it happens, and what to do: \"%s\"", loss);
  int gus_samples = 0; /* one feedback sample per physics step */
  test_last_feedback(&g, 1.0, &gus_samples);
  CHECK(gus_samples >= 50, "gus's session steps on with the log full: %d feedback samples over 1 s (100 Hz; >= 50)",
        gus_samples);
  /* gus practises freely: no debrief, no score to say it. His station says his session is not being
   * recorded whole (session 68), from his server's status, in words he can pass on. */
  char news[400] = "";
  long long gus_lost = 0;
  for (int k = 0; k < 60 && !news[0]; k++) {
    palp_cli_station_session_closed(&g, NULL, 0);
    if (!palp_cli_station_log_news(&g, news, sizeof news)) test_sleep(0.1);
  }
  int gn = 0;
  /* his own records (palp_session_log, session 69), not the server's: fia loses hers meanwhile */
  sscanf(news, "the server's session log is losing this session's records: %lld so far (%n", &gus_lost, &gn);
  const char *gus_tail = "); this session will be incomplete in the review: tell your instructor";
  const char *rest = gn > 0 ? news + gn : "";
  CHECK(gus_lost > 0 &&
            (!strncmp(rest, "the log's disk or its cap is full", 33) ||
             !strncmp(rest, "the server was too busy to write some, and the log's disk or its cap is full", 76)) &&
            strlen(news) > strlen(gus_tail) && !strcmp(news + strlen(news) - strlen(gus_tail), gus_tail),
        "gus's station tells him the log is losing his session's records while it runs, within 6 s: \"%s\"", news);

  palp_Debrief d;
  palp_DebriefLesion dl[PALP_DEBRIEF_MAX_LESIONS];
  char derr[160] = "", serr[160] = "";
  const int got_d = palp_cli_station_debrief(&f, 6.0, &d, dl, derr, sizeof derr);
  CHECK(got_d == 1 && d.level == palp_DEBRIEF_LESIONS && d.lesions == 2,
        "fia's session ran to its limit and she is debriefed (got %d, level %d %s)", got_d, got_d == 1 ? (int)d.level : -1,
        derr);
  palp_SessionScore m, m2;
  memset(&m, 0, sizeof m);
  memset(&m2, 0, sizeof m2);
  char text2[640] = "";
  /* the writer retries each failing batch (0.35 s of back-off) before the grader may read */
  const int got = got_d == 1 ? palp_cli_station_debrief_score(&f, 15.0, &m, serr, sizeof serr) : -1;
  char text[640] = "";
  if (got == 1) palp_cli_score_text(&m, text, sizeof text);
  /* Which, depends on the batches: her end lost with the rest (CUT SHORT), or, when a small batch found
   * room on a partly filled page, logged after records were lost (DAMAGED); both seen under load. */
  CHECK(got == 1 && m.status == palp_SCORE_GRADED && !m.log_complete &&
            (strncmp(m.log_health, "CUT SHORT: ", 11) == 0 || strncmp(m.log_health, "DAMAGED: ", 9) == 0),
        "fia's score is graded from what the log holds, which it says is incomplete: \"%s\" (got %d %s)",
        got == 1 ? m.log_health : "", got, serr);
  const char *tail = " The session's log is incomplete: the score may be low.";
  CHECK(strlen(text) > strlen(tail) && strcmp(text + strlen(text) - strlen(tail), tail) == 0 &&
            strncmp(text, "score: ", 7) == 0,
        "  and her station tells her so: \"%s\"", text);

  /* palp-review's reading of the log, while the server runs (a reader beside the writer: WAL), gives
   * the score she was told (before the prune below, which may take her session if its end got in). */
  palp_db *db = NULL;
  REQUIRE(palp_db_open(db_path, 0, &db, err, sizeof err) == 0, "read the log: %s", err);
  palp_db_session_info info;
  const int found = got == 1 && palp_db_find_session(db, m.log_uid, &info) == 0 && strcmp(info.uid, m.log_uid) == 0;
  CHECK(found, "fia's session is in the log (%s)", got == 1 ? m.log_uid : "");
  if (found) {
    review_assessment *ra = calloc(1, sizeof *ra);
    REQUIRE(ra, "memory");
    const int arc = review_assess(db, &info, ra, err, sizeof err);
    CHECK(arc == 0 && ra->r.score == m.score && (int)m.pass == ra->r.pass && m.samples == (uint32_t)ra->samples &&
              m.samples > 0,
          "  palp-review reads the score she was told: %.3f / %.3f from %u / %d finger samples (%s)", m.score,
          arc == 0 ? ra->r.score : -1.0, m.samples, arc == 0 ? ra->samples : -1, arc ? err : "ok");
    palp_db_log_health hl;
    char hline[400] = "";
    if (palp_db_log_health_get(db, &info, &hl) == 0) palp_db_log_health_describe(&hl, hline, sizeof hline);
    /* the wire's string<127>: the whole line, or palp_srv_health_fit's shortening of it (test_grader
     * checks that one by its words); its heading either way */
    char fit[128];
    palp_srv_health_fit(hline, fit, sizeof fit);
    CHECK(strcmp(fit, m.log_health) == 0 && strncmp(fit, hline, 9) == 0,
          "  and her score's health line is the review's, fitted to the wire: \"%s\" from \"%s\"", m.log_health,
          hline);
    if (arc == 0) review_assessment_free(ra);
    free(ra);
  }
  palp_db_close(db);

  /* ida's practice session opens while the log is full: its opening is lost with the rest, and she is
   * told why she gets no score, not that the server forgot her. */
  palp_cli_station ia;
  test_station_join(&ia, DOMAIN, "ida", palp_ROLE_TRAINEE, EX_SHORT, 0, 1, 0);
  for (int k = 0; k < 40; k++) {
    test_send_finger(&ia, 31, 41, 0.008 * k / 40.0, seq++);
    test_sleep(0.02);
  }
  const int got_di = palp_cli_station_debrief(&ia, 6.0, &d, dl, derr, sizeof derr);
  const int got_i = got_di == 1 ? palp_cli_station_debrief_score(&ia, 15.0, &m2, serr, sizeof serr) : -1;
  if (got_i == 1) palp_cli_score_text(&m2, text2, sizeof text2);
  /* "is losing" while the writer's last batch failed, "lost" when a small one found room since; and when
   * her session's row found room but her exercise did not (seen once in 9 runs under load), the count
   * her row holds (session 67: "the log holds no exercise for the session" before). */
  long long lost_n = 0;
  int used = 0;
  sscanf(text2, "no score: the session log lost %lld of its records (database or disk is full); tell your instructor%n",
         &lost_n, &used);
  CHECK(got_di == 1 && got_i == 1 && m2.status == palp_SCORE_NOT_GRADED &&
            (strcmp(text2, "no score: not in the session log, which is losing records (database or disk is full); "
                           "tell your instructor") == 0 ||
             strcmp(text2, "no score: not in the session log, which lost records (database or disk is full); tell your "
                           "instructor") == 0 ||
             (used > 0 && (size_t)used == strlen(text2) && lost_n > 0)),
        "ida's session, opened with the log full, is debriefed and she is told why no score: \"%s\" (got %d %d %s %s)",
        text2, got_di, got_i, derr, serr);
  palp_cli_station_close(&ia);

  /* The instructor prunes the old sessions (ava's, ended and logged; the others too where their ends
   * got in, else kept as "no end logged"): the pages freed, the log writes again, says so, and hal's
   * session, opened after, is logged whole. */
  for (int k = 0; k < 15; k++) { /* his station reads on, as palp-client does every 100 ms: 1.5 s, a status or more */
    palp_cli_station_session_closed(&g, NULL, 0);
    test_sleep(0.1);
  }
  const uint32_t gus_session = g.session_id;
  palp_cli_station_leave(&g);
  test_sleep(0.5);
  /* What gus's station says as his session ends is his own loss (session 69): no more than his
   * session's row counts (records still queued as he left may fail after), where the server as a
   * whole lost more meanwhile, fia's and ida's among them. */
  char gus_sum[400] = "";
  long long gus_all = 0;
  palp_dds_log_view_summary(&g.log, gus_sum, sizeof gus_sum);
  sscanf(gus_sum, "the server's session log lost %lld of this session's records (", &gus_all);
  const long long server_lost = (long long)g.log.lost_prev; /* the server's count in his last status */
  long long gus_row = -1;
  REQUIRE(palp_db_open(db_path, 0, &db, err, sizeof err) == 0, "read the log: %s", err);
  {
    palp_db_filter flt = {.trainee = "gus"};
    palp_db_session_info *list = NULL;
    int n = 0;
    if (palp_db_list_sessions(db, &flt, &list, &n) == 0 && n == 1) gus_row = list[0].records_shed + list[0].records_failed;
    free(list);
  }
  palp_db_close(db);
  CHECK(gus_all >= gus_lost && gus_all > 0 && gus_all <= gus_row && gus_all < server_lost,
        "gus's station, his session over, says his own loss: %lld (first said %lld) <= his session's row in the log, "
        "%lld, of the server's %lld: \"%s\"",
        gus_all, gus_lost, gus_row, server_lost, gus_sum);
  /* ... and the server's log says it as his session closes, in the same count: between what his station
   * last heard and what his row holds */
  char closed_line[600] = "", needle[96];
  long long closed_lost = -1;
  snprintf(needle, sizeof needle, "session %u: the session log lost ", gus_session);
  if (log_has(log_path, needle, closed_line, sizeof closed_line)) {
    const char *at = strstr(closed_line, needle);
    if (at) sscanf(at + strlen(needle), "%lld", &closed_lost);
  }
  CHECK(closed_lost >= gus_all && closed_lost <= gus_row && strstr(closed_line, "of its records while it ran (") &&
            strstr(closed_line, "its review will be incomplete"),
        "  and the server's log, as his session closed: %lld (%lld .. %lld): \"%s\"", closed_lost, gus_all, gus_row,
        closed_line);
  char cmd[2400], out[1024] = "";
  snprintf(cmd, sizeof cmd, "'%s' --db '%s' prune --older-than 0 2>&1", argv[1], db_path);
  FILE *p = popen(cmd, "r");
  REQUIRE(p != NULL, "palp-review prune");
  const size_t nout = fread(out, 1, sizeof out - 1, p);
  out[nout] = 0;
  const int prc = pclose(p);
  char ava_line[160];
  snprintf(ava_line, sizeof ava_line, "pruned %s\n", ava_uid);
  CHECK(WIFEXITED(prc) && WEXITSTATUS(prc) == 0 && strstr(out, ava_line),
        "palp-review prune --older-than 0 takes ava's session (%s) (exit %d): %s", ava_uid,
        WIFEXITED(prc) ? WEXITSTATUS(prc) : -1, out);
  palp_cli_station hs;
  test_station_join(&hs, DOMAIN, "hal", palp_ROLE_TRAINEE, 1, 0, 1, 0);
  test_send_force(&hs, 0, 1, 0, 0, 1.0, 1);
  test_sleep(0.5);
  palp_cli_station_leave(&hs);
  char again[2048] = "";
  CHECK(wait_log(log_path, "session log: writing again", 8.0, again, sizeof again),
        "with pages free the log writes again, and says so: \"%s\"", again);
  const uint32_t hal_session = hs.session_id;

  test_server_stop(&ts);
  palp_cli_station_close(&g);
  palp_cli_station_close(&f);
  palp_cli_station_close(&hs);
  palp_srv_db_log_close(dbl);
  char closing[2048] = "";
  CHECK(log_has(log_path, "records written,", closing, sizeof closing) && !strstr(closing, " 0 failed"),
        "the closing line counts the lost records: \"%s\"", closing);
  palp_log_close(&plog);

  /* The file is sound, and hal's session whole. */
  sqlite3 *h = NULL;
  REQUIRE(sqlite3_open(db_path, &h) == SQLITE_OK, "a connection of the test's own");
  sqlite3_stmt *st = NULL;
  const char *ic = "";
  if (sqlite3_prepare_v2(h, "PRAGMA integrity_check", -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
    ic = (const char *)sqlite3_column_text(st, 0);
  CHECK(ic && strcmp(ic, "ok") == 0, "the capped file is sound: integrity_check \"%s\"", ic ? ic : "");
  sqlite3_finalize(st);
  sqlite3_close(h);
  REQUIRE(palp_db_open(db_path, 0, &db, err, sizeof err) == 0, "read the log: %s", err);
  palp_db_session_info hi;
  char hal_uid[32];
  snprintf(hal_uid, sizeof hal_uid, "-%u", hal_session);
  int hal_whole = 0;
  {
    palp_db_filter flt = {.trainee = "hal"};
    palp_db_session_info *list = NULL;
    int n = 0;
    if (palp_db_list_sessions(db, &flt, &list, &n) == 0 && n == 1) {
      hi = list[0];
      palp_db_log_health hh;
      hal_whole = strstr(hi.uid, hal_uid) != NULL && palp_db_log_health_get(db, &hi, &hh) == 0 && hh.complete;
    }
    free(list);
  }
  CHECK(hal_whole, "hal's session, opened after, is logged whole (ended, no frame missing)");
  palp_db_close(db);
  fprintf(stderr, "server_log_full: the log %ld bytes after ava's session, cap %lld bytes; %s\n", before, (long long)cap,
          closing);
  if (!palp_test_failures) unlink(db_path), unlink(log_path);
  return palp_test_failures ? 1 : 0;
}
