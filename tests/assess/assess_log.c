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
 * X%, medium Y%, deep Z% of the dome", palp_coverage, from the server's finger samples) is this
 * coverage to the 0.1 point it prints,
 * and the debrief the server sent her at the end (palp_debrief, printed by the station) is the
 * review's: lesions found and marks near none, and per lesion found or missed, by which mark, its
 * clock position and arc from the pole (as printed, to its rounding), diameter and depth.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "assess_log.h"
#include "palp_db.h"
#include "review_util.h"

static int failures;
#define CHECK(c, ...)                            \
  do {                                           \
    printf("%s ", (c) ? "ok  " : "FAIL");        \
    printf(__VA_ARGS__);                         \
    printf("\n");                                \
    if (!(c)) failures++;                        \
  } while (0)

/* The station's last "you covered light X%, medium Y%, deep Z% of the dome" as fractions: 1, or 0;
 * *exact 1 when it said it counted them as the review does (from the server's finger samples). */
static int station_coverage(const char *path, const char *trainee, double out[3], int *exact, int *lossy) {
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  char line[1024], head[96];
  snprintf(head, sizeof head, "[trainee %s] you covered light %%lf%%%%, medium %%lf%%%%, deep %%lf%%%%", trainee);
  int found = 0;
  while (fgets(line, sizeof line, f)) {
    double l, m, d;
    if (sscanf(line, head, &l, &m, &d) == 3) {
      out[0] = l / 100, out[1] = m / 100, out[2] = d / 100, found = 1;
      *exact = strstr(line, "counted as the instructor's review counts it") != NULL;
    }
    if (strstr(line, "of the server's samples of your touches were lost on the way")) *lossy = 1;
  }
  fclose(f);
  return found;
}

/* The station's debrief lines (client/main.c, print_debrief). */
typedef struct said_lump {
  int found_by; /* 0: MISSED */
  double clock_h, arc_mm, across_mm, deep_mm;
} said_lump;
typedef struct said_debrief {
  int seen;
  unsigned found, lesions, marks, near_none;
  int lumps;
  said_lump lump[PALP_MAX_LESIONS];
} said_debrief;

static void station_debrief(const char *path, const char *trainee, said_debrief *d) {
  memset(d, 0, sizeof *d);
  FILE *f = fopen(path, "r");
  if (!f) return;
  char line[1024], head[160], found[160], missed[160];
  snprintf(head, sizeof head, "[trainee %s] debrief: you found ", trainee);
  snprintf(found, sizeof found, "[trainee %s]   lump %%d found by mark %%d: at %%lf o'clock, %%lf mm from the pole; "
           "%%lf mm across, its centre %%lf mm deep", trainee);
  snprintf(missed, sizeof missed, "[trainee %s]   lump %%d MISSED: at %%lf o'clock, %%lf mm from the pole; "
           "%%lf mm across, its centre %%lf mm deep", trainee);
  while (fgets(line, sizeof line, f)) {
    int i, by;
    double c, a, w, dp;
    /* "... you found 1 of 2 lumps with 1 mark standing; 0 marks were near no lump" (singular or plural) */
    const char *with = strstr(line, " with "), *semi = strstr(line, "; ");
    if (!strncmp(line, head, strlen(head)) && with && semi &&
        sscanf(line + strlen(head), "%u of %u", &d->found, &d->lesions) == 2 && sscanf(with, " with %u", &d->marks) == 1 &&
        sscanf(semi, "; %u", &d->near_none) == 1)
      d->seen = 1;
    else if (sscanf(line, found, &i, &by, &c, &a, &w, &dp) == 6 && i >= 1 && i <= PALP_MAX_LESIONS)
      d->lump[i - 1] = (said_lump){by, c, a, w, dp}, d->lumps = i > d->lumps ? i : d->lumps;
    else if (sscanf(line, missed, &i, &c, &a, &w, &dp) == 5 && i >= 1 && i <= PALP_MAX_LESIONS)
      d->lump[i - 1] = (said_lump){0, c, a, w, dp}, d->lumps = i > d->lumps ? i : d->lumps;
  }
  fclose(f);
}

/* A clock reading's difference in hours, across 12. */
static double clock_diff(double a, double b) {
  double d = a - b;
  while (d > 6) d -= 12;
  while (d < -6) d += 12;
  return d < 0 ? -d : d;
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
    int exact = 0, lossy = 0;
    const int got = station_coverage(argv[4], argv[2], said, &exact, &lossy);
    double worst = 0, over = 0;
    for (int b = 0; got && b < 3; b++) {
      const double d = said[b] > r.coverage[b] ? said[b] - r.coverage[b] : r.coverage[b] - said[b];
      if (d > worst) worst = d;
      if (said[b] - r.coverage[b] > over) over = said[b] - r.coverage[b];
    }
    /* Samples lost on the way (which the station then says) can only leave places it did not
     * mark: it may read under the review, never over it. */
    if (lossy) {
      printf("note %s's station lost some of the server's finger samples: asserted only that it reads no more "
             "than the review\n", argv[2]);
      worst = over;
    }
    /* From the server's finger samples (session 71) the station counts the review's own footprint:
     * equal to the 0.1 point it prints (half of it, and 1e-9 for the binary fractions), unless
     * samples were lost on the way, which it then says (not in these runs on loopback). Before,
     * from the local models' count of touched triangles, 1.5 points: the patch approximated the
     * footprint (0.8-1.6 points in eve's whole exam, docs/web.md). A station that lost samples says so,
 * and is held only to not reading over the review. */
    CHECK(got && exact, "%s's station counted her coverage from the server's finger samples", argv[2]);
    const double tol = exact ? 0.0005 + 1e-9 : 0.015;
    CHECK(got && worst <= tol, "the station told %s light %.3f, medium %.3f, deep %.3f: the review's within %.4f "
          "(worst %.4f)", argv[2], got ? said[0] : -1, got ? said[1] : -1, got ? said[2] : -1, tol, worst);
    /* The debrief: the server matched her standing marks itself (palp_assess_findings); the
     * review matches the logged ones (palp_assess). The places are printed to 0.1 h and 1 mm. */
    said_debrief d;
    station_debrief(argv[4], argv[2], &d);
    int standing = 0;
    for (int i = 0; i < a.mark_n; i++) standing += !a.marks[i].f.withdrawn;
    CHECK(d.seen && (int)d.found == r.found && (int)d.lesions == r.lesion_count && (int)d.near_none == r.false_positives &&
              (int)d.marks == standing,
          "the station's debrief told %s: %u of %u found, %u marks standing, %u near none (review: %d of %d, %d, %d)",
          argv[2], d.found, d.lesions, d.marks, d.near_none, r.found, r.lesion_count, standing, r.false_positives);
    CHECK(d.lumps == r.lesion_count, "  every lesion listed (%d of %d)", d.lumps, r.lesion_count);
    for (int l = 0; l < d.lumps && l < r.lesion_count; l++) {
      const said_lump *u = &d.lump[l];
      const int by = r.lesion_found[l] >= 0 ? (int)a.marks[r.lesion_found[l]].mark_id : 0;
      const palp_vec3 p = a.lesion_surface[l];
      const double clock = review_clock_hours(p), arc = review_arc_m(p) * 1e3;
      CHECK(u->found_by == by, "  lesion %d: %s (review: %s by mark %d)", l + 1, u->found_by ? "found" : "missed",
            by ? "found" : "missed", by);
      CHECK(clock_diff(u->clock_h, clock) <= 0.051 && fabs(u->arc_mm - arc) <= 0.51 &&
                fabs(u->across_mm - a.ex.lesion[l].diameter * 1e3) <= 0.51 && fabs(u->deep_mm - a.ex.lesion[l].depth * 1e3) <= 0.51,
            "  lesion %d at %.1f o'clock, %.0f mm from the pole, %.0f mm across, %.0f mm deep (review: %.2f h, %.2f mm, %.1f, "
            "%.1f; tolerance the printed rounding)", l + 1, u->clock_h, u->arc_mm, u->across_mm, u->deep_mm, clock, arc,
            a.ex.lesion[l].diameter * 1e3, a.ex.lesion[l].depth * 1e3);
    }
  }
  review_assessment_free(&a);
  free(ss);
  palp_db_close(db);
  return failures ? 1 : 0;
}
