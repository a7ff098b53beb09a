/* test_db_slots.c - the session log's slots (server/db_log.c, session 75): sessions whose ids are
 * 1,024 apart (the log's slot count) open at the same time are all logged, each with its own
 * events and end. Until session 75 a session whose slot an older open session held was not logged
 * at all ("slot ... busy"). The server's events are called directly, as palp_srv calls them; no DDS. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "../tmpdir.h"
#include "check.h"
#include "db_log.h"
#include "palp.h"
#include "palp_db.h"

/* The count of the session's rejection event(s). */
static int rejected_count(void *user, double wall_unix_s, int64_t frame, const char *kind, const char *detail,
                          int64_t count) {
  (void)wall_unix_s, (void)frame, (void)detail;
  if (strstr(kind, "reject")) *(int64_t *)user += count;
  return 0;
}

int main(void) {
  char err[512] = "", dir[512], db_path[600], scene_path[600];
  palp_test_tmp(dir, sizeof dir, "palp-db-slots-XXXXXX");
  if (!mkdtemp(dir)) return 2;
  snprintf(db_path, sizeof db_path, "%s/log.db", dir);
  snprintf(scene_path, sizeof scene_path, "%s/paper_step.json", PALP_CONFIG_DIR);
  palp_scene scene;
  if (palp_scene_load(scene_path, &scene, err, sizeof err) < 0) {
    fprintf(stderr, "scene: %s\n", err);
    return 2;
  }
  palp_srv_db_log *dbl = NULL;
  if (palp_srv_db_log_open(db_path, 0, NULL, &dbl, err, sizeof err) < 0) {
    fprintf(stderr, "log: %s\n", err);
    return 2;
  }
  const palp_srv_events *ev = palp_srv_db_log_events(dbl);
  /* 5, 1029 and 2053 share slot 5; 6 is 1029's next slot, taken first. */
  const uint32_t ids[4] = {5, 6, 5 + 1024, 5 + 2048};
  const char *names[4] = {"ann", "bob", "cid", "dee"};
  palp_srv_session_info info[4];
  for (int k = 0; k < 4; k++) {
    info[k] = (palp_srv_session_info){.session_id = ids[k],
                                      .phantom_id = 1,
                                      .phantom_name = "dome",
                                      .trainee_station = names[k],
                                      .trainee_name = names[k],
                                      .partition = "p",
                                      .tick_rate_hz = 1.0 / scene.world.dt,
                                      .dt = scene.world.dt,
                                      .scene_path = scene_path,
                                      .scene = &scene,
                                      .max_force = 10};
    ev->session_opened(ev->ctx, &info[k]);
  }
  /* Each session's own counts reach its own row: k + 1 rejections each, flushed at its close. */
  for (int k = 0; k < 4; k++)
    for (int r = 0; r <= k; r++) ev->contact_rejected(ev->ctx, ids[k], PALP_SRV_REJ_NONFINITE, 0, 1);
  for (int k = 3; k >= 0; k--) {
    palp_srv_session_summary sum;
    memset(&sum, 0, sizeof sum);
    sum.info = info[k];
    sum.close_reason = "trainee station left";
    ev->session_closed(ev->ctx, &sum);
  }
  /* session 90's review: an exercise session the log could not take (every slot open here; a refused
   * start is the same path) is still handed to the grader at its close, which answers why it is not
   * scored: her station and the dashboard are told, where before no answer ever came. 1,024 plain
   * sessions fill the slots; the 1,025th, an exercise's, is not logged. */
  for (uint32_t k = 0; k < 1024; k++) {
    palp_srv_session_info fill = info[0];
    fill.session_id = 10000 + k;
    fill.trainee_name = fill.trainee_station = "fill";
    ev->session_opened(ev->ctx, &fill);
  }
  palp_srv_session_info exi = info[0];
  exi.session_id = 20000;
  exi.trainee_name = exi.trainee_station = "eve";
  exi.exercise_name = "slot-ex";
  exi.exercise_json = "{}";
  ev->session_opened(ev->ctx, &exi);
  {
    palp_srv_session_summary sum;
    memset(&sum, 0, sizeof sum);
    sum.info = exi;
    sum.close_reason = "trainee station left";
    ev->session_closed(ev->ctx, &sum);
  }
  palp_srv_score sc;
  int told = 0;
  for (int t = 0; t < 500 && !told; t++) {
    memset(&sc, 0, sizeof sc);
    if (ev->take_score(ev->ctx, &sc) == 1 && sc.session_id == 20000) told = 1;
    else nanosleep(&(struct timespec){0, 10000000}, NULL);
  }
  CHECK(told && !sc.graded && strcmp(sc.exercise, "slot-ex") == 0 && strstr(sc.reason, "not in the log") != NULL,
        "an exercise session the log could not take is answered at its close: told %d, graded %d, exercise \"%s\", "
        "\"%s\" (before: no answer)", told, told ? sc.graded : -1, told ? sc.exercise : "", told ? sc.reason : "");
  palp_srv_db_log_close(dbl);

  palp_db *db = NULL;
  if (palp_db_open(db_path, 0, &db, err, sizeof err) < 0) {
    fprintf(stderr, "read the log: %s\n", err);
    return 2;
  }
  int logged = 0, ended = 0, events_ok = 0;
  for (int k = 0; k < 4; k++) {
    palp_db_filter flt = {.trainee = names[k]};
    palp_db_session_info *list = NULL;
    int n = 0;
    if (palp_db_list_sessions(db, &flt, &list, &n) == 0 && n == 1) {
      logged++;
      ended += list[0].end_unix_s > 0;
      int64_t rejected = 0; /* its own k + 1, not another's */
      palp_db_each_event(db, list[0].id, rejected_count, &rejected);
      events_ok += rejected == k + 1;
      fprintf(stderr, "     session %u (%s): logged, %lld rejections (want %d), end \"%s\"\n", ids[k], names[k],
              (long long)rejected, k + 1, list[0].end_reason);
    }
    free(list);
  }
  palp_db_close(db);
  CHECK(logged == 4 && ended == 4 && events_ok == 4,
        "4 sessions open at once, 3 of them sharing slot 5 (ids 5, 1029, 2053; 6 beside them): %d logged, %d ended, "
        "%d with their own rejection counts (want 4, 4, 4)", logged, ended, events_ok);
  unlink(db_path);
  char side[700];
  snprintf(side, sizeof side, "%s-wal", db_path);
  unlink(side);
  snprintf(side, sizeof side, "%s-shm", db_path);
  unlink(side);
  rmdir(dir);
  fprintf(stderr, failures ? "%d check(s) FAILED\n" : "all checks passed\n", failures);
  return failures ? 1 : 0;
}
