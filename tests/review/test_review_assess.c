/* Metrics from the log equal the in-process assessment (issue 13).
 * usage: test_review_assess TMPDIR TESTDIR CLASSDIR
 * An expert, a novice and a free-practice session are logged through the writer into a real
 * SQLite file (gen.h: review_gen, the fixture review_class_log, writes CLASSDIR/class.db and the
 * in-process assessments CLASSDIR/class.refs once for this test and review_cli; this test works on a
 * copy); palp-review's review_assess reads them back (exercise JSON, scene ->
 * rest mesh, finger samples, findings) and must give exactly what palp_assess gave on the
 * samples in memory: tolerance 0 (SQLite stores IEEE doubles bit for bit and the same pure
 * code runs on the same numbers). Then the properties on the logged expert and novice. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <sqlite3.h>

#include "assess_log.h"
#include "check.h"
#include "station.h"
#include "gen.h"

static void same(const char *who, const palp_assess_result *a, const palp_assess_result *b, int with_score) {
  CHECK(a->lesion_count == b->lesion_count && a->found == b->found, "%s: found %d/%d vs %d/%d", who, a->found,
        a->lesion_count, b->found, b->lesion_count);
  CHECK(a->findings == b->findings && a->withdrawn == b->withdrawn && a->false_positives == b->false_positives,
        "%s: findings %d/%d/%d vs %d/%d/%d", who, a->findings, a->withdrawn, a->false_positives, b->findings,
        b->withdrawn, b->false_positives);
  for (int k = 0; k < PALP_BAND_COUNT; k++)
    CHECK(a->coverage[k] == b->coverage[k], "%s: coverage[%d] %.17g vs %.17g", who, k, a->coverage[k], b->coverage[k]);
  CHECK(a->coverage_any == b->coverage_any, "%s: coverage_any", who);
  CHECK(a->pattern == b->pattern, "%s: pattern %s vs %s", who, palp_pattern_name(a->pattern), palp_pattern_name(b->pattern));
  CHECK(memcmp(&a->evidence, &b->evidence, sizeof a->evidence) == 0, "%s: pattern evidence differs (path %.17g vs %.17g)",
        who, a->evidence.path_length, b->evidence.path_length);
  CHECK(a->duration == b->duration && a->peak_force == b->peak_force && a->out_of_range == b->out_of_range &&
            a->out_of_range_time == b->out_of_range_time,
        "%s: time/force %.17g %.17g %d vs %.17g %.17g %d", who, a->duration, a->peak_force, a->out_of_range, b->duration,
        b->peak_force, b->out_of_range);
  if (with_score)
    CHECK(a->score == b->score && a->pass == b->pass, "%s: score %.17g/%d vs %.17g/%d", who, a->score, a->pass, b->score,
          b->pass);
}


/* The score and pass marks as printed (session 81 review): a figure never reads as reaching a mark it
 * missed, pass marks with their digits, and a session failed on its score alone says so. Expected
 * lines written out by hand. */
static int line_has(const char *text, const char *want) { return strstr(text, want) != NULL; }
static void metrics_text(double score, double pass_score, int pass, double cov_light, double pass_light, char *out,
                         size_t len) {
  static review_assessment a;
  memset(&a, 0, sizeof a);
  a.has_exercise = 1;
  snprintf(a.exercise_name, sizeof a.exercise_name, "t");
  a.ex.rubric.pass_score = pass_score;
  a.ex.rubric.pass_coverage[0] = pass_light, a.ex.rubric.pass_coverage[1] = 0.9, a.ex.rubric.pass_coverage[2] = 0.8;
  a.ex.lesion_count = 1;
  a.r.lesion_count = 1, a.r.found = 1, a.r.sensitivity = 1.0;
  a.r.coverage[0] = cov_light, a.r.coverage[1] = 0.95, a.r.coverage[2] = 0.85;
  a.r.score = score, a.r.pass = pass;
  char *buf = NULL;
  size_t n = 0;
  FILE *f = open_memstream(&buf, &n);
  review_metrics_print(f, &a);
  fclose(f);
  snprintf(out, len, "%s", buf ? buf : "");
  free(buf);
}
static void verdict_text_cases(void) {
  char t[4096];
  /* pass mark 70.4, score 70.2: before "70.2 / 100 (pass at 70): FAIL" */
  metrics_text(70.2, 70.4, 0, 0.95, 0.9, t, sizeof t);
  CHECK(line_has(t, "score            70.2 / 100 (pass at 70.4): FAIL"), "pass mark 70.4 printed as such:\n%s", t);
  /* 69.96 against 70: before "70.0 / 100 (pass at 70): FAIL"; floored, 69.9 */
  metrics_text(69.96, 70, 0, 0.95, 0.9, t, sizeof t);
  CHECK(line_has(t, "score            69.9 / 100 (pass at 70): FAIL"), "69.96 failing prints 69.9:\n%s", t);
  /* a pass: 99.625 rounds as before, 99.6 */
  metrics_text(99.625, 70, 1, 0.95, 0.9, t, sizeof t);
  CHECK(line_has(t, "score            99.6 / 100 (pass at 70): PASS"), "99.625 passing prints 99.6:\n%s", t);
  /* coverage 89.96% short of 90: 89.9, not 90.0; a pass mark of 90.5% printed 90.5, not 90 (%.0f gave "90") */
  metrics_text(80, 70, 0, 0.8996, 0.9, t, sizeof t);
  CHECK(line_has(t, "light 89.9%") && line_has(t, "(pass at 90/90/80%)"), "light 89.96%% short of 90:\n%s", t);
  metrics_text(80, 70, 0, 0.95, 0.905, t, sizeof t);
  CHECK(line_has(t, "(pass at 90.5/90/80%)"), "pass mark 90.5%%:\n%s", t);
  /* her station: every metric passed, score 69.96 not passed: 69.9, and what to work on */
  palp_SessionScore m;
  memset(&m, 0, sizeof m);
  m.status = palp_SCORE_GRADED, m.score = 69.96, m.pass = false, m.log_complete = true;
  for (int i = 0; i < 6; i++) m.passed[i] = true;
  char st[512];
  palp_cli_score_text(&m, st, sizeof st);
  printf("station: %s\n", st);
  CHECK(line_has(st, "score: 69.9 of 100, not passed") && line_has(st, "To work on: raising the score (below the pass mark)."),
        "station, the score alone failed: \"%s\"", st);
  m.passed[0] = false; /* sensitivity failed too: listed, the score not named */
  palp_cli_score_text(&m, st, sizeof st);
  CHECK(line_has(st, "To work on: finding the lumps.") && !line_has(st, "raising the score"), "station, lumps missed: \"%s\"", st);
}

int main(int argc, char **argv) {
  verdict_text_cases();
  REQUIRE(argc == 4, "usage: test_review_assess TMPDIR TESTDIR CLASSDIR");
  char path[1024], src[1024];
  snprintf(path, sizeof path, "%s/review_assess.sqlite", argv[1]);
  unlink(path);
  char err[512] = "";
  /* the class review_gen logged (the fixture), copied through SQLite's backup API (its WAL, if any, with it) */
  {
    snprintf(src, sizeof src, "%s/class.db", argv[3]);
    sqlite3 *from = NULL, *to = NULL;
    REQUIRE(sqlite3_open_v2(src, &from, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
                sqlite3_open(path, &to) == SQLITE_OK,
            "open %s and %s", src, path);
    sqlite3_backup *b = sqlite3_backup_init(to, "main", from, "main");
    REQUIRE(b && sqlite3_backup_step(b, -1) == SQLITE_DONE && sqlite3_backup_finish(b) == SQLITE_OK,
            "copy %s: %s", src, sqlite3_errmsg(to));
    sqlite3_close(from);
    sqlite3_close(to);
  }
  /* review_gen's in-process assessments: class-bob-1 (novice, seed 7), class-alice-1 (expert), class-bob-2,
   * class-carol-1 (free practice) */
  palp_assess_result gen_ref[4], ref[3];
  {
    snprintf(src, sizeof src, "%s/class.refs", argv[3]);
    FILE *f = fopen(src, "rb");
    REQUIRE(f && fread(gen_ref, sizeof gen_ref, 1, f) == 1, "read %s", src);
    fclose(f);
    ref[0] = gen_ref[1], ref[1] = gen_ref[0], ref[2] = gen_ref[3];
  }
  palp_db_writer *w;
  REQUIRE(palp_db_writer_open(path, NULL, &w, err, sizeof err) == 0, "writer: %s", err);
  /* dora's attempts at the same exercise, each logged as a server would (no samples: the "not
   * blind" rule reads only the sessions' ends, exercises and debriefs): 1 its debrief not sent,
   * 2 told the count, 3 a log from before debriefs were logged, 4 a server that logs them and
   * logged none though the session closed (the row lost), 5 a debrief row that does not parse, 6 a
   * session whose close was never logged (its server killed: no debrief went out). */
  static const struct { const char *uid, *params, *debrief; } dora[] = {
      {"dora-1", "{\"debrief_events\": true}", "not sent (level lesions): DDS refused the write: Error"},
      {"dora-2", "{\"debrief_events\": true}",
       "told at level count: found 1 of 2 lesions; marks standing 1, near no lesion 0, duplicates 0"},
      {"dora-3", "{}", NULL},
      {"dora-4", "{\"debrief_events\": true}", NULL},
      {"dora-5", "{\"debrief_events\": true}", "told at level count: found 3 of 2 lesions"},
      {"dora-6", "{\"debrief_events\": true}", NULL}};
  {
    char ex_path[1024];
    snprintf(ex_path, sizeof ex_path, "%s/exercise_expert.json", argv[2]);
    char *ex_json = gen_slurp(ex_path);
    REQUIRE(ex_json, "read %s", ex_path);
    for (int k = 0; k < 6; k++) {
      const double t = 1.7e9 + 3000 + 1000 * k;
      palp_db_session_def d = {.uid = dora[k].uid, .trainee = "dora", .station = "gen", .phantom_id = "stiff",
                               .phantom_name = "dome_breast_test", .scene_json = "{}", .params_json = dora[k].params,
                               .tick_hz = 250, .dt_s = 0.004, .start_unix_s = t};
      palp_db_session h;
      int rc = palp_db_log_session_begin(w, &d, &h);
      if (!rc) rc = palp_db_log_exercise(w, h, "test-two-lumps", ex_json);
      if (!rc && dora[k].debrief) rc = palp_db_log_event(w, h, PALP_DB_EVENT_DEBRIEF, 10, dora[k].debrief, 1);
      if (!rc && k < 5) rc = palp_db_log_session_end(w, h, PALP_DB_END_NORMAL, NULL, t + 10);
      REQUIRE(rc == 0, "%s logged: %s", dora[k].uid, palp_strerror(rc));
    }
    free(ex_json);
    REQUIRE(palp_db_writer_flush(w, 30.0) == 0, "flushed");
  }
  palp_db_writer_stats st;
  palp_db_writer_stats_get(w, &st);
  CHECK(st.shed == 0 && st.failed == 0, "nothing shed (%lld) or failed (%lld)", (long long)st.shed, (long long)st.failed);
  palp_db_writer_close(w);

  palp_db *db;
  REQUIRE(palp_db_open(path, 0, &db, err, sizeof err) == 0, "open: %s", err);
  const char *uid[3] = {"class-alice-1", "class-bob-1", "class-carol-1"};
  review_assessment a[3];
  for (int i = 0; i < 3; i++) {
    palp_db_session_info s;
    REQUIRE(palp_db_find_session(db, uid[i], &s) == 0, "%s found", uid[i]);
    REQUIRE(review_assess(db, &s, &a[i], err, sizeof err) == 0, "%s assessed: %s", uid[i], err);
    same(uid[i], &a[i].r, &ref[i], i < 2);
  }
  const palp_assess_result *e = &a[0].r, *n = &a[1].r;
  printf("expert: found %d/%d, false %d, coverage %.3f/%.3f/%.3f, %s, score %.1f\n", e->found, e->lesion_count,
         e->false_positives, e->coverage[0], e->coverage[1], e->coverage[2], palp_pattern_name(e->pattern), e->score);
  printf("novice: found %d/%d, false %d, coverage %.3f/%.3f/%.3f, %s, score %.1f\n", n->found, n->lesion_count,
         n->false_positives, n->coverage[0], n->coverage[1], n->coverage[2], palp_pattern_name(n->pattern), n->score);
  CHECK(a[0].has_exercise && !strcmp(a[0].exercise_name, "test-two-lumps"), "expert's exercise named (%s)", a[0].exercise_name);
  CHECK(e->lesion_count == 2 && e->found == 2, "the logged expert finds every 10 mm lesion (%d of %d)", e->found,
        e->lesion_count);
  CHECK(e->false_positives == 0, "no false positive (%d)", e->false_positives);
  CHECK(e->coverage[PALP_BAND_MEDIUM] >= 0.95, "medium coverage %.3f >= 0.95", e->coverage[PALP_BAND_MEDIUM]);
  CHECK(e->pattern == PALP_PATTERN_VERTICAL_STRIP, "pattern vertical strip (%s)", palp_pattern_name(e->pattern));
  CHECK(n->coverage[PALP_BAND_LIGHT] < 0.25 && n->coverage[PALP_BAND_MEDIUM] < 0.05, "novice thoroughness low (%.3f, %.3f)",
        n->coverage[0], n->coverage[1]);
  CHECK(!n->pass && n->score < e->score - 40.0, "novice scores low (%.1f vs expert %.1f) and fails", n->score, e->score);
  CHECK(a[1].mark_n == 2 && a[1].marks[0].match == PALP_FINDING_WITHDRAWN, "the novice's withdrawn mark reads back (%d marks, first %d)",
        a[1].mark_n, a[1].mark_n ? a[1].marks[0].match : 0);
  CHECK(!a[2].has_exercise && a[2].r.lesion_count == 0, "free practice: no exercise, no lesions");
  /* Where the review shows the strips: the logged expert's, not the novice's; not a circle search's
   * axial runs (test_metrics' concentric circles make 5 such "strips"), not two strips, not a
   * pruned session's (strips -1: unknown). */
  palp_assess_result circles = *e, two = *e, pruned = *e;
  circles.pattern = PALP_PATTERN_CIRCLES, circles.evidence.strips = 5;
  two.evidence.strips = 2;
  pruned.evidence.strips = -1;
  CHECK(review_strips_shown(e) && e->evidence.strips >= 13 && !review_strips_shown(n) &&
            !review_strips_shown(&circles) && !review_strips_shown(&two) && !review_strips_shown(&pruned),
        "strips shown for the expert's strip search (%d, order %.2f) only", e->evidence.strips,
        e->evidence.sweep_monotony);
  /* The touches palp-review show and the report list, read back from the log: as many as the
   * metrics' presses, in time order, their paths summing to the path length; the novice's script
   * presses 5 times 3 mm deep at the device (about 2.6 mm into the surface behind the coupling). */
  for (int i = 0; i < 3; i++) {
    const review_assessment *x = &a[i];
    double sum = 0.0;
    int ordered = 1, contact = 0;
    for (int k = 0; k < x->touch_n; k++) {
      sum += x->touches[k].path_length;
      contact += x->touches[k].contact_samples;
      if (x->touches[k].t_off < x->touches[k].t_on ||
          (k > 0 && x->touches[k].t_on - x->touches[k - 1].t_off <= PALP_ASSESS_LIFT_GAP_S))
        ordered = 0;
    }
    CHECK(x->touch_n == x->r.evidence.presses && x->touch_n > 0 && ordered, "%s: %d touches in time order, %d presses",
          uid[i], x->touch_n, x->r.evidence.presses);
    CHECK(contact == x->path_n, "%s: the touches split the %d contact samples the report draws (%d)", uid[i], x->path_n,
          contact);
    CHECK(fabs(sum - x->r.evidence.path_length) < 1e-9, "%s: the touches' paths sum to the path length (%.6f vs %.6f m)",
          uid[i], sum, x->r.evidence.path_length);
  }
  int light = a[1].touch_n == 5;
  for (int k = 0; k < a[1].touch_n; k++)
    light = light && a[1].touches[k].peak_indentation > 0.0015 && a[1].touches[k].peak_indentation < 0.0035;
  CHECK(light, "the novice's 5 light presses read back as 5 touches 1.5-3.5 mm deep (%d; first %.2f mm)", a[1].touch_n,
        a[1].touch_n ? a[1].touches[0].peak_indentation * 1e3 : 0.0);
  /* What dora was told, read back from each log (docs/assessment.md, "Debrief") */
  {
    static const int want[6] = {REVIEW_DEBRIEF_LOGGED, REVIEW_DEBRIEF_LOGGED, REVIEW_DEBRIEF_UNKNOWN, REVIEW_DEBRIEF_LOST,
                                REVIEW_DEBRIEF_UNREADABLE, REVIEW_DEBRIEF_NONE};
    for (int k = 0; k < 6; k++) {
      palp_db_session_info s;
      palp_db_debrief d;
      REQUIRE(palp_db_find_session(db, dora[k].uid, &s) == 0, "%s found", dora[k].uid);
      const int st_ = review_debrief(db, &s, &d);
      CHECK(st_ == want[k], "%s: its debrief reads as status %d (got %d)", dora[k].uid, want[k], st_);
    }
    palp_db_session_info s1;
    palp_db_debrief d;
    REQUIRE(palp_db_find_session(db, "dora-1", &s1) == 0, "dora-1");
    char text[1024];
    review_debrief_text(review_debrief(db, &s1, &d), &d, NULL, text, sizeof text);
    CHECK(!strcmp(text, "NOT SENT (the exercise's debrief: lesions): DDS refused the write: Error; its trainee was told "
                        "nothing"),
          "dora-1's line: %s", text);
    /* Her attempt after each: the latest earlier session whose debrief told her something. */
    static const struct { double after; int told; const char *uid; palp_debrief_level level; int inferred; } q[] = {
        {3500, 0, "", PALP_DEBRIEF_NONE, 0},       /* dora-1's debrief was not sent: blind */
        {4500, 1, "dora-2", PALP_DEBRIEF_COUNT, 0}, /* told the count, as logged */
        {5500, 1, "dora-3", PALP_DEBRIEF_LESIONS, 1}, /* a log without debriefs: the file's level */
        {6500, 1, "dora-4", PALP_DEBRIEF_LESIONS, 1}, /* lost: the file's level, said inferred */
        {7500, 1, "dora-5", PALP_DEBRIEF_LESIONS, 1}, /* unreadable: the same */
        {9500, 1, "dora-5", PALP_DEBRIEF_LESIONS, 1}}; /* dora-6 never closed: it told nothing */
    for (size_t k = 0; k < sizeof q / sizeof q[0]; k++) {
      palp_db_session_info later = {.id = -1, .start_unix_s = 1.7e9 + q[k].after};
      snprintf(later.trainee, sizeof later.trainee, "dora");
      review_told t;
      const int rc = review_told_before(db, &later, &a[1], &t);
      CHECK(rc == q[k].told && (!q[k].told || (!strcmp(t.uid, q[k].uid) && t.level == q[k].level &&
                                               t.inferred == q[k].inferred)),
            "an attempt %.0f s in: told %d by '%s' at level %d, inferred %d (got %d by '%s' at %d, %d)", q[k].after,
            q[k].told, q[k].uid, (int)q[k].level, q[k].inferred, rc, t.uid, (int)t.level, t.inferred);
    }
    /* A debrief that agrees with the review's count reads plainly; one that does not says so. */
    palp_db_debrief agree = {.sent = 1, .level = PALP_DB_DEBRIEF_COUNT, .lesions = a[1].r.lesion_count,
                             .found = a[1].r.found, .marks = 1};
    review_debrief_text(REVIEW_DEBRIEF_LOGGED, &agree, &a[1], text, sizeof text);
    CHECK(!strstr(text, "DIFFERS"), "a debrief agreeing with the review: %s", text);
    palp_db_debrief other = agree;
    other.found = agree.found == 0 ? 1 : 0;
    review_debrief_text(REVIEW_DEBRIEF_LOGGED, &other, &a[1], text, sizeof text);
    CHECK(strstr(text, "DIFFERS from this review"), "one that does not: %s", text);
  }
  for (int i = 0; i < 3; i++) review_assessment_free(&a[i]);
  palp_db_close(db);
  CHECK_DONE();
}
