/* review_gen DB TESTDIR [REFS]: logs a small class for the palp-review tests and the README demo:
 * alice (expert), bob (novice, two sessions: progress), carol (free practice, no exercise),
 * one day apart from 2026-01-05 so --since has something to cut. REFS: the in-process assessment of
 * each session's samples (gen.h), written as palp_assess_result structs (class-bob-1, class-alice-1, class-bob-2, class-carol-1),
 * for test_review_assess, which checks the review's metrics from the log against them. The class is
 * logged once, by the fixture review_class_log (tests/review/CMakeLists.txt), for review_cli and
 * review_assess: each had scripted the same expert in process (~6 s of CPU each, 2026-12-07). */
#include <stdio.h>

#include "gen.h"

int main(int argc, char **argv) {
  if (argc != 3 && argc != 4) {
    fprintf(stderr, "usage: review_gen DB TESTDIR [REFS]\n");
    return 2;
  }
  char err[512] = "";
  palp_db_writer *w;
  if (palp_db_writer_open(argv[1], NULL, &w, err, sizeof err)) {
    fprintf(stderr, "review_gen: %s\n", err);
    return 2;
  }
  const double day = 86400.0, t0 = 1767610800.0; /* 2026-01-05 11:00 UTC */
  palp_assess_result ref[4];
  memset(ref, 0, sizeof ref);
  /* bob's logs are as a server before session 59 wrote them (no debriefs logged: his second
   * attempt's "not blind" is inferred from his first's exercise file); alice's server logged her
   * debrief: both lumps found, by her two marks (test_review_cli.sh reads it back) */
  int rc = gen_session(w, argv[2], "class-bob-1", "bob", GEN_NOVICE, 7u, t0, &ref[0], NULL);
  if (!rc)
    rc = gen_session(w, argv[2], "class-alice-1", "alice", GEN_EXPERT, 0, t0 + day, &ref[1],
                     "told at level lesions: found 2 of 2 lesions; marks standing 2, near no lesion 0, duplicates 0; "
                     "found by marks 2 1");
  if (!rc) rc = gen_session(w, argv[2], "class-bob-2", "bob", GEN_NOVICE, 11u, t0 + 2 * day, &ref[2], NULL);
  if (!rc) rc = gen_session(w, argv[2], "class-carol-1", "carol", GEN_FREE, 5u, t0 + 3 * day, &ref[3], "");
  palp_db_writer_close(w);
  if (!rc && argc == 4) {
    FILE *f = fopen(argv[3], "wb");
    if (!f || fwrite(ref, sizeof ref, 1, f) != 1) rc = -1;
    if (f && fclose(f) != 0) rc = -1;
    if (rc) fprintf(stderr, "review_gen: cannot write %s\n", argv[3]);
  }
  return rc ? 1 : 0;
}
