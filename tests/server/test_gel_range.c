/*
 * test_gel_range.c - a session whose literal gel law leaves its stable range says so (session 76,
 * 2026-12-06), over real DDS into a real SQLite log (domain 157).
 *
 * The phantom is the paper's dome (config/paper_step.json's parameters) with the literal gel law
 * (PALP_GEL_PAPER_LITERAL) and a3 = 0.9 dt^2 at the server's 100 Hz (dt 10 ms): every whole step
 * keeps the momentum term (a3 / dt^2 = 0.9 < 1), but a halved step (a3 / (h h_prev) = 1.8 or 3.6)
 * and the step after one (1.8) leave it out and count it (palp_world_health.gel_momentum_dropped;
 * docs/model.md, "Steps of other lengths, and where a3 is stable"). A load on one vertex halves
 * steps (tests/model/test_gel_literal.c); ann presses 3 N on the pole's vertex five times:
 *  - the server's log says it for her session at the first such frame, then at most once per
 *    log_interval (0.5 s here) with the frames since, and says the total K as her session closes,
 *    K > 0. How many steps halve depends on when her samples reach the ticks (18 frames in the
 *    runs of 2026-12-06), so K is not fixed: it is checked against the session log and the replay;
 *  - the session log's valid_range events sum to K frames over gel_steps steps (1 <= gel_steps <=
 *    K), the review's valid-range line names it and counts those steps as time outside;
 *  - `palp-review replay` rebuilds her world from the log, reproduces it bit for bit and counts K
 *    frames itself: the count the server said is the world's, not the sum of what was said;
 *  - bob presses 0.5 N over a patch on the same phantom: no halved step, so nothing is said for
 *    his session (no line, no gel part in his events, his review line names no gel), and his
 *    replay counts 0 frames: the silence is the model's, not a missed report;
 *  - cat's position-driven fingertip goes 12 mm deep and 2 mm clear at the pole, five times: it
 *    halves steps too, and her station's local models carry LM_GEL_LAW_RANGE at some of those
 *    steps (at least one; never more than the steps her valid_range events count, the models
 *    being best-effort), which her station renders and names (tests/haptic/gel_law_range.sh).
 * Before: none of it (the server's log, the session log and the review said nothing of the
 * counter; replay did not count it); before the second fix of 2026-12-06 no wire bit carried it,
 * and her station's models said nothing (0 of ~200 flagged).
 */
#define _GNU_SOURCE
#include <inttypes.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "../tmpdir.h"
#include "db_log.h"
#include "harness.h"
#include "palp_db.h"
#include "review_util.h"

#define DOMAIN 157
#define LOG_INTERVAL 0.5 /* [s] */
#define GEL_SAID "the literal gel law's momentum term left out at "

/* Seconds of the day of a log line's timestamp ("2026-12-06T10:00:00.123Z ..."); -1 if none. */
static double line_time(const char *line) {
  int hh, mm;
  double ss;
  if (sscanf(line, "%*4d-%*2d-%*2dT%2d:%2d:%lfZ", &hh, &mm, &ss) != 3) return -1;
  return 3600.0 * hh + 60.0 * mm + ss;
}

typedef struct said {
  int lines;            /* lines saying the session's frames without the term, at the tick */
  long long said;       /* the frames those lines said */
  double min_gap;       /* [s] the least time between two of them */
  long long total;      /* the close line's total, -1 if none */
  int first_ok;         /* the first one is the warning that names the range */
} said;

static said read_log(const char *path, uint32_t session) {
  said r = {0, 0, 1e9, -1, 0};
  char head[64], line[2048];
  snprintf(head, sizeof head, "session %u: " GEL_SAID, session);
  FILE *f = fopen(path, "r");
  if (!f) return r;
  double last = -1;
  while (fgets(line, sizeof line, f)) {
    const char *p = strstr(line, head);
    if (!p) continue;
    p += strlen(head);
    long long n = 0;
    if (strstr(p, "frames in all (")) {
      if (sscanf(p, "%lld frames in all", &n) == 1) r.total = n;
      continue;
    }
    if (sscanf(p, "%lld", &n) != 1) continue;
    if (r.lines == 0) r.first_ok = strstr(p, "outside (-1/2, 1) (a3 9e-05 s^2)") != NULL && strstr(line, " WARN ");
    r.lines++;
    r.said += n;
    const double t = line_time(line);
    if (last >= 0 && t >= 0 && t - last < r.min_gap) r.min_gap = t - last;
    last = t;
  }
  fclose(f);
  return r;
}

/* `palp-review replay UID`: its exit status; *frames the frames it counted without the term (-1: not said). */
static int replay(const char *review, const char *db_path, const char *uid, long long *frames, char *out, size_t len) {
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "'%s' --db '%s' replay '%s' 2>&1", review, db_path, uid);
  FILE *p = popen(cmd, "r");
  *frames = -1;
  if (out && len) out[0] = 0;
  if (!p) return -1;
  char line[1024];
  size_t n = 0;
  while (fgets(line, sizeof line, p)) {
    const char *q = strstr(line, GEL_SAID);
    if (q) sscanf(q + strlen(GEL_SAID), "%lld", frames);
    if (out && n < len) n += (size_t)snprintf(out + n, len - n, "%s", line);
  }
  const int st = pclose(p);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* Takes the station's local models for `seconds`: *models counted, *gel those flagged
 * LM_GEL_LAW_RANGE, *outside those any PALP_DDS_LM_OUTSIDE bit. */
static void take_models(palp_cli_station *st, double seconds, long long *models, long long *gel, long long *outside) {
  const int64_t end = palp_dds_now_ns() + (int64_t)(seconds * 1e9);
  while (palp_dds_now_ns() < end) {
    void *ptr[16] = {NULL};
    dds_sample_info_t info[16];
    const int n = dds_take(st->local_model_r, ptr, info, 16, 16);
    for (int k = 0; k < n; k++) {
      if (!info[k].valid_data) continue;
      const palp_LocalModel *m = ptr[k];
      (*models)++;
      if (m->flags & palp_LM_GEL_LAW_RANGE) (*gel)++;
      if (m->flags & PALP_DDS_LM_OUTSIDE) (*outside)++;
    }
    if (n > 0) dds_return_loan(st->local_model_r, ptr, n);
    test_sleep(0.002);
  }
}

/* The session of trainee `name` in the log: its info (uid, id, dt). */
static int find_session(palp_db *db, const char *name, palp_db_session_info *out) {
  palp_db_filter flt = {.trainee = name};
  palp_db_session_info *list = NULL;
  int n = 0;
  if (palp_db_list_sessions(db, &flt, &list, &n) != 0 || n != 1) {
    free(list);
    return -1;
  }
  *out = list[0];
  free(list);
  return 0;
}

int main(int argc, char **argv) {
  /* SCENE: tests/data/literal_a3_scene.json, the paper dome's scene (config/paper_step.json with
   * config/params/calibrated.json inline), its gel law literal and a3 = 0.9 (10 ms)^2 */
  REQUIRE(argc > 2, "usage: test_server_gel_range PALP_REVIEW SCENE");
  test_init();
  char err[512], dir[512], db_path[600], log_path[600];
  const char *scene_path = argv[2];
  palp_test_tmp(dir, sizeof dir, "palp-gel-range-XXXXXX");
  REQUIRE(mkdtemp(dir) != NULL, "temporary directory");
  snprintf(db_path, sizeof db_path, "%s/sessions.db", dir);
  snprintf(log_path, sizeof log_path, "%s/server.log", dir);

  char json[1024];
  snprintf(json, sizeof json,
           "{\"domain_id\": %d, \"tick_rate_hz\": 100, \"tick_threads\": 1, \"max_force\": 20, \"log_interval\": %g,"
           " \"phantoms\": [{\"id\": 1, \"name\": \"literal a3\", \"scene\": \"%s\"}]}",
           DOMAIN, LOG_INTERVAL, scene_path);
  palp_srv_config cfg;
  REQUIRE(palp_srv_config_parse(json, PALP_CONFIG_DIR, &cfg, err, sizeof err) == 0, "config: %s", err);
  palp_log plog;
  REQUIRE(palp_log_init(&plog, "palp-server", PALP_LOG_INFO, log_path) == 0, "server log file");
  palp_srv_db_log *dbl = NULL;
  REQUIRE(palp_srv_db_log_open(db_path, 0, &plog, &dbl, err, sizeof err) == 0, "session log: %s", err);
  const palp_srv_def def = {.cfg = cfg, .events = palp_srv_db_log_events(dbl), .verbose = 0, .log = &plog};
  test_server ts;
  test_server_start_def(&ts, &def);

  /* ann: 3 N on the pole's vertex, on for 0.2 s and off for 0.2 s, five times: each onset halves a
   * step or two (a load on one vertex, as tests/model/test_gel_literal.c halves them with) */
  palp_cli_station a;
  test_station_join(&a, DOMAIN, "ann", palp_ROLE_TRAINEE, 1, 0, 1, 0);
  const uint32_t ann = a.session_id;
  for (int k = 0; k < 20; k++) {
    test_send_force(&a, 0, PALP_DIST_SINGLE, 0, 0, (k / 2) % 2 ? 0.0 : 3.0, (uint64_t)k + 1);
    test_sleep(0.1);
  }
  palp_cli_station_leave(&a);
  palp_cli_station_close(&a);
  /* bob: 0.5 N over a patch at 30 deg for 2 s */
  palp_cli_station b;
  test_station_join(&b, DOMAIN, "bob", palp_ROLE_TRAINEE, 1, 0, 1, 0);
  const uint32_t bob = b.session_id;
  for (int k = 0; k < 20; k++) {
    test_send_force(&b, 0, PALP_DIST_UNIFORM, 30, 40, 0.5, (uint64_t)k + 1);
    test_sleep(0.1);
  }
  palp_cli_station_leave(&b);
  palp_cli_station_close(&b);
  /* cat: a position-driven fingertip at the pole, 12 mm deep for 0.2 s then lifted 2 mm clear for
   * 0.2 s, five times: her station's local models say when the gel law left its range */
  palp_cli_station c;
  test_station_join(&c, DOMAIN, "cat", palp_ROLE_TRAINEE, 1, 0, 1, 0);
  const uint32_t cat = c.session_id;
  long long cat_models = 0, cat_gel = 0, cat_outside = 0;
  for (int k = 0; k < 20; k++) {
    test_send_finger(&c, 0, 0, (k / 2) % 2 ? -0.002 : 0.012, (uint64_t)k + 1);
    take_models(&c, 0.1, &cat_models, &cat_gel, &cat_outside);
  }
  palp_cli_station_leave(&c);
  palp_cli_station_close(&c);
  test_sleep(0.5);
  test_server_stop(&ts);
  palp_srv_db_log_close(dbl);
  palp_log_close(&plog);

  /* the server's log */
  const said sa = read_log(log_path, ann), sb = read_log(log_path, bob);
  printf("ann (session %u): %d lines at the ticks said %lld frames (least gap %.3f s); %lld in all at close\n", ann,
         sa.lines, sa.said, sa.lines > 1 ? sa.min_gap : 0.0, sa.total);
  CHECK(sa.total > 0, "ann's session: the server's log says at close the frames the literal law left its momentum "
        "term out (%lld)", sa.total);
  CHECK(sa.lines >= 1 && sa.first_ok, "ann's session: the first such frame said at once, as a warning naming the "
        "range and a3 (%d lines)", sa.lines);
  /* A line is stamped as it is written, after its tick's step, and the limit runs on the ticks'
   * clock: two stamps may be closer than their ticks by a step's compute time (a halved step's
   * few ms, more where ticks overrun). 50 ms covers that; said every tick, they were 10 ms apart. */
  CHECK(sa.lines < 2 || sa.min_gap >= LOG_INTERVAL - 0.05,
        "then at most once per log_interval %.1f s (least gap %.3f s, tolerance 50 ms)", LOG_INTERVAL, sa.min_gap);
  CHECK(sa.said <= sa.total && sa.lines <= 2.0 / LOG_INTERVAL + 2,
        "the lines said %lld of the %lld frames (the rest in the close's total), in %d lines over ~2 s of presses",
        sa.said, sa.total, sa.lines);
  CHECK(sb.lines == 0 && sb.total == -1, "bob's session: nothing said (%d lines, total %lld)", sb.lines, sb.total);
  const said sc = read_log(log_path, cat);
  printf("cat (session %u): %lld local models, %lld flagged LM_GEL_LAW_RANGE, %lld outside; %lld frames in all at close\n",
         cat, cat_models, cat_gel, cat_outside, sc.total);
  CHECK(sc.total > 0, "cat's fingertip made the literal law leave its range too (%lld frames)", sc.total);
  CHECK(cat_gel >= 1 && cat_gel <= cat_outside && cat_outside < cat_models,
        "her station was told: %lld of her %lld local models flagged LM_GEL_LAW_RANGE (%lld outside the valid range)",
        cat_gel, cat_models, cat_outside);

  /* the session log and the review */
  palp_db *db = NULL;
  REQUIRE(palp_db_open(db_path, 0, &db, err, sizeof err) == 0, "read the session log: %s", err);
  palp_db_session_info ia, ib, ic;
  REQUIRE(find_session(db, "ann", &ia) == 0 && find_session(db, "bob", &ib) == 0 && find_session(db, "cat", &ic) == 0,
          "one session each logged");
  palp_db_valid_range ra, rb;
  int64_t ea = 0, ua = 0, eb = 0, ub = 0;
  REQUIRE(palp_db_session_valid_range(db, ia.id, &ra, &ea, &ua) == 0 &&
              palp_db_session_valid_range(db, ib.id, &rb, &eb, &ub) == 0,
          "valid_range events read");
  CHECK(ua == 0 && ub == 0, "every valid_range event parses (%lld, %lld unreadable)", (long long)ua, (long long)ub);
  CHECK(ra.gel_frames == sa.total && ra.gel_steps >= 1 && ra.gel_steps <= ra.gel_frames && ra.gel_steps <= ra.steps,
        "ann's valid_range events: %lld frames without the momentum term (the close line's %lld) over %lld steps of "
        "%lld outside",
        (long long)ra.gel_frames, sa.total, (long long)ra.gel_steps, (long long)ra.steps);
  CHECK(rb.gel_steps == 0 && rb.gel_frames == 0, "bob's: no gel part (%lld steps, %lld frames; %lld events)",
        (long long)rb.gel_steps, (long long)rb.gel_frames, (long long)eb);
  /* each flagged step sent her one model (finger 0), best-effort: none more than the steps */
  palp_db_valid_range rc;
  int64_t ec = 0, uc = 0;
  REQUIRE(palp_db_session_valid_range(db, ic.id, &rc, &ec, &uc) == 0, "cat's valid_range events read");
  CHECK(rc.gel_frames == sc.total && rc.gel_steps >= 1 && cat_gel <= rc.gel_steps,
        "cat's valid_range events: %lld frames (the close line's %lld) over %lld steps, her station told of %lld",
        (long long)rc.gel_frames, sc.total, (long long)rc.gel_steps, cat_gel);
  char text[640], want[128];
  review_valid_range_text(db, &ia, text, sizeof text);
  snprintf(want, sizeof want, "%.2f s the gel's literal pressure law stepped outside its stable range (its momentum "
           "term left out at %lld frames)", (double)ra.gel_steps * ia.dt_s, (long long)ra.gel_frames);
  CHECK(!strncmp(text, "OUTSIDE for ", 12) && strstr(text, want), "ann's review: \"%s\"", text);
  review_valid_range_text(db, &ib, text, sizeof text);
  CHECK(!strstr(text, "gel"), "bob's review names no gel: \"%s\"", text);
  char ua_uid[128], ub_uid[128];
  snprintf(ua_uid, sizeof ua_uid, "%s", ia.uid);
  snprintf(ub_uid, sizeof ub_uid, "%s", ib.uid);
  palp_db_close(db);

  /* the replay's own count */
  long long fa = -1, fb = -1;
  char out[4096];
  const int rca = replay(argv[1], db_path, ua_uid, &fa, out, sizeof out);
  CHECK(rca == 0 && fa > 0 && fa == sa.total,
        "ann's replay reproduces her session (exit %d) and counts %lld frames without the term, the %lld the server "
        "said:\n%s", rca, fa, sa.total, out);
  const int rcb = replay(argv[1], db_path, ub_uid, &fb, out, sizeof out);
  CHECK(rcb == 0 && fb == 0, "bob's replay (exit %d) counts %lld frames: he never left the range", rcb, fb);

  unlink(db_path);
  char side[700];
  snprintf(side, sizeof side, "%s-wal", db_path);
  unlink(side);
  snprintf(side, sizeof side, "%s-shm", db_path);
  unlink(side);
  unlink(log_path);
  rmdir(dir);
  return palp_test_failures ? 1 : 0;
}
