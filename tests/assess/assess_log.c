/*
 * assess_log.c - the assessment of a session from palp-server's log (issue 13) through the
 * review's own code path (client/review/assess_log.c, review_assess: what `palp-review show`,
 * the report and the class report print), so the DDS test checks what the instructor sees.
 * Used by exercise_trainees.sh on sessions played by palp-client's scripted trainees.
 *
 * usage: assess_log DB TRAINEE expert|novice [STATION_LOG]
 * Asserts for an expert: every lesion found, no false positive, medium coverage >= 0.95,
 * pattern vertical strip; for a novice: medium coverage < 0.30 and not every lesion found. With
 * the trainee's station log: the coverage the station told her at its end ("you covered light
 * X%, medium Y%, deep Z% of the dome", palp_coverage) is this coverage within 1.5 points per band.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "assess_log.h"
#include "palp_db.h"

static int failures;
#define CHECK(c, ...)                            \
  do {                                           \
    printf("%s ", (c) ? "ok  " : "FAIL");        \
    printf(__VA_ARGS__);                         \
    printf("\n");                                \
    if (!(c)) failures++;                        \
  } while (0)

/* The station's last "you covered light X%, medium Y%, deep Z% of the dome" as fractions: 1, or 0. */
static int station_coverage(const char *path, const char *trainee, double out[3]) {
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  char line[1024], head[96];
  snprintf(head, sizeof head, "[trainee %s] you covered light %%lf%%%%, medium %%lf%%%%, deep %%lf%%%%", trainee);
  int found = 0;
  while (fgets(line, sizeof line, f)) {
    double l, m, d;
    if (sscanf(line, head, &l, &m, &d) == 3) out[0] = l / 100, out[1] = m / 100, out[2] = d / 100, found = 1;
  }
  fclose(f);
  return found;
}

int main(int argc, char **argv) {
  if ((argc != 4 && argc != 5) || (strcmp(argv[3], "expert") && strcmp(argv[3], "novice"))) {
    fprintf(stderr, "usage: %s DB TRAINEE expert|novice [STATION_LOG]\n", argv[0]);
    return 2;
  }
  const int expert = !strcmp(argv[3], "expert");
  char err[512] = "";
  palp_db *db = NULL;
  if (palp_db_open(argv[1], 0, &db, err, sizeof err) < 0) {
    fprintf(stderr, "FAIL %s: %s\n", argv[1], err);
    return 1;
  }
  palp_db_filter flt = {.trainee = argv[2]};
  palp_db_session_info *ss = NULL;
  int ns = 0;
  if (palp_db_list_sessions(db, &flt, &ss, &ns) < 0 || ns < 1) {
    fprintf(stderr, "FAIL no session of %s in %s\n", argv[2], argv[1]);
    return 1;
  }
  const palp_db_session_info *si = &ss[ns - 1];
  review_assessment a;
  if (review_assess(db, si, &a, err, sizeof err) != 0 || !a.has_exercise) {
    fprintf(stderr, "FAIL session %s: %s\n", si->uid, a.has_exercise ? err : "no exercise in the log");
    return 1;
  }
  const palp_assess_result r = a.r;
  printf("%s (session %s, exercise %s): %d samples, %d findings: found %d/%d, false %d, coverage light %.3f "
         "medium %.3f deep %.3f, pattern %s (axial %.2f, %d strips in order %.2f), time %.1f s, peak %.2f N, score %.1f, "
         "pass %d\n",
         argv[2], si->uid, a.exercise_name, a.samples, r.findings, r.found, r.lesion_count, r.false_positives,
         r.coverage[0], r.coverage[1], r.coverage[2], palp_pattern_name(r.pattern), r.evidence.share_axial, r.evidence.strips,
         r.evidence.sweep_monotony, r.duration,
         r.peak_force, r.score, r.pass);
  if (expert) {
    CHECK(r.found == r.lesion_count && r.lesion_count > 0, "the expert finds every lesion (%d of %d)", r.found,
          r.lesion_count);
    CHECK(r.false_positives == 0, "no false positive (%d)", r.false_positives);
    CHECK(r.coverage[PALP_BAND_MEDIUM] >= 0.95, "medium coverage %.3f >= 0.95", r.coverage[PALP_BAND_MEDIUM]);
    CHECK(r.pattern == PALP_PATTERN_VERTICAL_STRIP, "pattern vertical strip (%s)", palp_pattern_name(r.pattern));
    /* one pass of 15 strips, each next to the one before (in process: 15, order 1.00); the
     * tolerance is for edge strips a late tick shortens below 16 mm, and a strip the proxy's
     * sideways give breaks into pieces more than 2 mm apart */
    CHECK(r.evidence.strips >= 12 && r.evidence.sweep_monotony >= 0.8, "the strips in order: %d strips, order %.2f",
          r.evidence.strips, r.evidence.sweep_monotony);
  } else {
    CHECK(r.coverage[PALP_BAND_MEDIUM] < 0.30, "novice medium coverage %.3f < 0.30", r.coverage[PALP_BAND_MEDIUM]);
    CHECK(r.found < r.lesion_count, "the novice misses a lesion (%d of %d found)", r.found, r.lesion_count);
  }
  if (argc == 5) { /* what the station told the trainee, against the review's thoroughness */
    double said[3];
    const int got = station_coverage(argv[4], argv[2], said);
    double worst = 0;
    for (int b = 0; got && b < 3; b++) {
      const double d = said[b] > r.coverage[b] ? said[b] - r.coverage[b] : r.coverage[b] - said[b];
      if (d > worst) worst = d;
    }
    CHECK(got && worst <= 0.015, "the station told %s light %.3f, medium %.3f, deep %.3f: the review's within 0.015 "
          "(worst %.4f)", argv[2], got ? said[0] : -1, got ? said[1] : -1, got ? said[2] : -1, worst);
  }
  review_assessment_free(&a);
  free(ss);
  palp_db_close(db);
  return failures ? 1 : 0;
}
