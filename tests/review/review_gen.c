/* review_gen DB TESTDIR: logs a small class for the palp-review tests and the README demo:
 * alice (expert), bob (novice, two sessions: progress), carol (free practice, no exercise),
 * one day apart from 2026-01-05 so --since has something to cut. */
#include <stdio.h>

#include "gen.h"

int main(int argc, char **argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: review_gen DB TESTDIR\n");
    return 2;
  }
  char err[512] = "";
  palp_db_writer *w;
  if (palp_db_writer_open(argv[1], NULL, &w, err, sizeof err)) {
    fprintf(stderr, "review_gen: %s\n", err);
    return 2;
  }
  const double day = 86400.0, t0 = 1767610800.0; /* 2026-01-05 11:00 UTC */
  /* bob's logs are as a server before session 59 wrote them (no debriefs logged: his second
   * attempt's "not blind" is inferred from his first's exercise file); alice's server logged her
   * debrief: both lumps found, by her two marks (test_review_cli.sh reads it back) */
  int rc = gen_session(w, argv[2], "class-bob-1", "bob", GEN_NOVICE, 7u, t0, NULL, NULL);
  if (!rc)
    rc = gen_session(w, argv[2], "class-alice-1", "alice", GEN_EXPERT, 0, t0 + day, NULL,
                     "told at level lesions: found 2 of 2 lesions; marks standing 2, near no lesion 0, duplicates 0; "
                     "found by marks 2 1");
  if (!rc) rc = gen_session(w, argv[2], "class-bob-2", "bob", GEN_NOVICE, 11u, t0 + 2 * day, NULL, NULL);
  if (!rc) rc = gen_session(w, argv[2], "class-carol-1", "carol", GEN_FREE, 5u, t0 + 3 * day, NULL, "");
  palp_db_writer_close(w);
  return rc ? 1 : 0;
}
