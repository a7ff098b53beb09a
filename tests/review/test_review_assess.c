/* Metrics from the log equal the in-process assessment (issue 13).
 * usage: test_review_assess TMPDIR TESTDIR
 * An expert, a novice and a free-practice session are logged through the writer into a real
 * SQLite file (gen.h); palp-review's review_assess reads them back (exercise JSON, scene ->
 * rest mesh, finger samples, findings) and must give exactly what palp_assess gave on the
 * samples in memory: tolerance 0 (SQLite stores IEEE doubles bit for bit and the same pure
 * code runs on the same numbers). Then the properties on the logged expert and novice. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "assess_log.h"
#include "check.h"
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

int main(int argc, char **argv) {
  REQUIRE(argc == 3, "usage: test_review_assess TMPDIR TESTDIR");
  char path[1024];
  snprintf(path, sizeof path, "%s/review_assess.sqlite", argv[1]);
  unlink(path);
  char err[512] = "";
  palp_db_writer *w;
  REQUIRE(palp_db_writer_open(path, NULL, &w, err, sizeof err) == 0, "writer: %s", err);
  palp_assess_result ref[3];
  REQUIRE(gen_session(w, argv[2], "ra-expert", "alice", GEN_EXPERT, 0, 1.7e9, &ref[0]) == 0, "expert logged");
  REQUIRE(gen_session(w, argv[2], "ra-novice", "bob", GEN_NOVICE, 7u, 1.7e9 + 1000, &ref[1]) == 0, "novice logged");
  REQUIRE(gen_session(w, argv[2], "ra-free", "carol", GEN_FREE, 3u, 1.7e9 + 2000, &ref[2]) == 0, "free logged");
  palp_db_writer_stats st;
  palp_db_writer_stats_get(w, &st);
  CHECK(st.shed == 0 && st.failed == 0, "nothing shed (%lld) or failed (%lld)", (long long)st.shed, (long long)st.failed);
  palp_db_writer_close(w);

  palp_db *db;
  REQUIRE(palp_db_open(path, 0, &db, err, sizeof err) == 0, "open: %s", err);
  const char *uid[3] = {"ra-expert", "ra-novice", "ra-free"};
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
  for (int i = 0; i < 3; i++) review_assessment_free(&a[i]);
  palp_db_close(db);
  CHECK_DONE();
}
