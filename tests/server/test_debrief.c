/*
 * test_debrief.c - the server's debrief of a session's marks (server/findings.c,
 * palp_srv_findings_debrief; docs/assessment.md "Debrief"), without DDS: the marks go through
 * palp_srv_findings_offer as the server's main thread takes them. One exercise, two lesions
 * (polar 30 / 60 deg, azimuth 0 / 180 deg, 10 mm deep, 15 mm across, match margin 10 mm) on a
 * 40 mm dome, told at each of the three levels. Expected values come from the geometry stated
 * here (a mark on the skin above a lesion's centre finds it; one 40 mm away finds none), not from
 * the code under test. What it writes passes the readers' check (palp_dds_debrief_ok), and copies
 * altered to not add up do not.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "findings.h"
#include "palp_dds.h"

#define PI 3.14159265358979323846
#define R 0.04

static palp_vec3 skin(double polar_deg, double az_deg) { /* the dome's rest skin [m] */
  const double p = polar_deg * PI / 180, a = az_deg * PI / 180;
  return (palp_vec3){R * sin(p) * cos(a), R * sin(p) * sin(a), R * cos(p)};
}

static const char *exercise(const char *debrief, char *buf, size_t len) {
  snprintf(buf, len,
           "{\"name\": \"t\", \"title\": \"T\", \"phantom\": \"p.json\", \"instructions\": \"I\", \"time_limit_s\": 60,"
           " \"lesions\": [{\"polar_deg\": 30, \"azimuth_deg\": 0, \"depth_mm\": 10, \"diameter_mm\": 15, \"stiffness_ratio\": 5},"
           "               {\"polar_deg\": 60, \"azimuth_deg\": 180, \"depth_mm\": 10, \"diameter_mm\": 15, \"stiffness_ratio\": 5}],"
           " \"pressure_bands\": {\"light\": {\"depth_mm\": [1, 4]}, \"medium\": {\"depth_mm\": [4, 9]}, \"deep\": {\"depth_mm\": [9, 18]}},"
           " \"max_force_N\": 15, \"match_margin_mm\": 10%s%s%s,"
           " \"rubric\": {\"weights\": {\"sensitivity\": 1}, \"pass\": {\"sensitivity\": 1, \"coverage\": {\"light\": 0.5, \"medium\": 0.5,"
           " \"deep\": 0.5}, \"score\": 50}}}",
           debrief ? ", \"debrief\": \"" : "", debrief ? debrief : "", debrief ? "\"" : "");
  return buf;
}

static void mark(palp_srv_findings *f, uint32_t id, int op, palp_vec3 p, int64_t t) {
  const palp_Finding in = {.session_id = 7, .mark_id = id, .op = (palp_FindingOp)op, .point = {p.x, p.y, p.z}};
  CHECK(palp_srv_findings_offer(f, &in, t) == 1, "mark %u %s accepted (%s)", id,
        op == palp_FINDING_MARK ? "made" : "withdrawn", f->reason);
}

int main(void) {
  /* Marks: 1 on lesion 1 (withdrawn), 2 on lesion 1, 3 also on lesion 1 (a duplicate), 4 far from both
   * (the pole's other side: 40 mm from either), 5 on lesion 2. Standing: 2, 3, 4, 5. */
  palp_srv_findings f;
  const palp_srv_findings_limits lim = {.session_id = 7, .dome_radius = 0.04, .depth_max = 0.019, .height_max = 0.005,
                                        .rate = 5, .burst = 10};
  palp_srv_findings_init(&f, &lim);
  int64_t t = 1000000000;
  mark(&f, 1, palp_FINDING_MARK, skin(30, 0), t += 300000000);
  mark(&f, 1, palp_FINDING_WITHDRAW, skin(0, 0), t += 300000000);
  mark(&f, 2, palp_FINDING_MARK, skin(30, 0), t += 300000000);
  mark(&f, 3, palp_FINDING_MARK, skin(33, 5), t += 300000000);
  mark(&f, 4, palp_FINDING_MARK, skin(60, 90), t += 300000000);
  mark(&f, 5, palp_FINDING_MARK, skin(60, 180), t += 300000000);

  /* 200 findings naming other sessions at once (a peer's flood in this partition, unsecured) are
   * each refused with their reason, and spend none of the session's tokens (burst 10): the
   * trainee's next mark, 1 ms later, is accepted (it was refused "too many findings"). */
  int stray_refused = 0;
  for (uint32_t k = 0; k < 200; k++) {
    const palp_Finding in = {.session_id = 5000 + k, .mark_id = 1, .op = palp_FINDING_MARK, .point = {0, 0, R}};
    stray_refused += palp_srv_findings_offer(&f, &in, t) == 0 && strstr(f.reason, "names session") != NULL;
  }
  CHECK(stray_refused == 200, "200 findings of other sessions refused, each naming why (%d)", stray_refused);
  mark(&f, 6, palp_FINDING_MARK, skin(60, 90), t += 1000000);
  mark(&f, 6, palp_FINDING_WITHDRAW, skin(0, 0), t += 1000000);

  static const char *const level_key[] = {NULL, "none", "count", "lesions"};
  for (int k = 0; k < 4; k++) {
    char json[2048], err[256];
    palp_exercise ex;
    const int parsed = palp_exercise_parse(exercise(level_key[k], json, sizeof json), "/x", &ex, err, sizeof err);
    CHECK(parsed == 0, "exercise with debrief %s: %s", level_key[k] ? level_key[k] : "(absent)", err);
    if (parsed != 0) continue;
    palp_Debrief d;
    palp_DebriefLesion les[PALP_MAX_LESIONS];
    memset(les, 0, sizeof les);
    const int rc = palp_srv_findings_debrief(&f, &ex, R, 7, "trainee station left", &d, les);
    CHECK(rc == 0 && d.session_id == 7 && d.marks == 4 && strcmp(d.reason, "trainee station left") == 0,
          "  debrief of session 7, 4 marks standing, the reason (rc %d, marks %u, \"%s\")", rc, d.marks, d.reason);
    if (k <= 1) { /* absent or "none": nothing of the lesions, not even how many */
      CHECK(d.level == palp_DEBRIEF_NONE && d.lesions == 0 && d.found == 0 && d.false_marks == 0 && d.duplicates == 0 &&
                d.lesion._length == 0,
            "  none: no count, no lesion (level %d, %u of %u, false %u, dup %u, listed %u)", (int)d.level, d.found,
            d.lesions, d.false_marks, d.duplicates, d.lesion._length);
    } else {
      CHECK(d.level == (k == 2 ? palp_DEBRIEF_COUNT : palp_DEBRIEF_LESIONS) && d.lesions == 2 && d.found == 2 &&
                d.false_marks == 1 && d.duplicates == 1,
            "  %s: 2 of 2 found, 1 mark near none (mark 4), 1 on a lesion already found (mark 3) (%u of %u, false %u, "
            "dup %u)", level_key[k], d.found, d.lesions, d.false_marks, d.duplicates);
    }
    if (k == 2) CHECK(d.lesion._length == 0, "  count: no lesion listed (%u)", d.lesion._length);
    /* what the server writes, a reader takes (palp_dds_debrief_ok, the station's and palp-web's check) */
    CHECK(palp_dds_debrief_ok(&d) == 1, "  the readers' check takes it");
    if (k == 3) {
      /* ... and refuses what does not add up (each altered copy, then put back) */
      palp_Debrief bad = d;
      bad.found = 1;
      const int wrong_count = palp_dds_debrief_ok(&bad);
      bad = d, bad.level = palp_DEBRIEF_COUNT;
      const int listed_at_count = palp_dds_debrief_ok(&bad);
      bad = d, bad.lesion._length = 1;
      const int one_of_two = palp_dds_debrief_ok(&bad);
      const double z = les[1].point.z;
      les[1].point.z = NAN;
      const int nan_point = palp_dds_debrief_ok(&d);
      les[1].point.z = z;
      bad = d, bad.level = (palp_DebriefLevel)7;
      const int unknown_level = palp_dds_debrief_ok(&bad);
      CHECK(!wrong_count && !listed_at_count && !one_of_two && !nan_point && !unknown_level,
            "  refused: found not the count of found_by (%d), lesions listed at count (%d), 1 of 2 listed (%d), a NaN "
            "place (%d), level 7 (%d)", wrong_count, listed_at_count, one_of_two, nan_point, unknown_level);
    }
    if (k == 3) {
      const palp_vec3 s1 = skin(30, 0), s2 = skin(60, 180);
      const double e1 = hypot(hypot(les[0].point.x - s1.x, les[0].point.y - s1.y), les[0].point.z - s1.z);
      const double e2 = hypot(hypot(les[1].point.x - s2.x, les[1].point.y - s2.y), les[1].point.z - s2.z);
      CHECK(d.lesion._length == 2 && d.lesion._buffer == les && les[0].found_by == 2 && les[1].found_by == 5 &&
                e1 < 1e-12 && e2 < 1e-12 && fabs(les[0].depth - 0.010) < 1e-15 && fabs(les[1].diameter - 0.015) < 1e-15,
            "  lesions: lesion 1 found by mark 2 (the withdrawn mark 1 does not count), lesion 2 by mark 5, each at the "
            "skin above its centre (off by %.1e and %.1e m, tolerance 1e-12), 10 mm deep, 15 mm across", e1, e2);
    }
  }
  fprintf(stderr, failures ? "%d check(s) FAILED\n" : "all checks passed\n", failures);
  return failures ? 1 : 0;
}
