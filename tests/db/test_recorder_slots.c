/* palp-recorder with more sessions open than its 1,024 slots (session 90's review), over real DDS on
 * loopback (domain 226, of its own).
 * usage: test_db_recorder_slots TMPDIR PALP_RECORDER DDS_CONFIG
 *
 * The test plays a server: one catalogue entry, then 1,030 sessions opened on it, none closed. Each
 * session the recorder cannot record (no free slot, or the session log refused its start: the writer's
 * queue, bounded in records and bytes, takes 1,030 scenes only as fast as the disk) is now said in its
 * log and counted in its stop line; until session 90 such a session was dropped without a word.
 * Checked: every one of the 1,030 is either a session row in the file or counted in the stop line's
 * "N sessions not recorded" (exactly: recorded + said = 1,030), at least 6 are said (1,030 - 1,024
 * slots), and the log names why at least once ("not recorded: ..."). And 20 contacts naming session 1 written
 * from session 2's partition (a forger's) are counted in session 1's log when the recorder's stop ends
 * it: one reject event "... someone forged its session id" with count 20 (until session 90 only a
 * CLOSED state wrote it; a session the recorder's stop ended kept no sign). ~6 s. */
#include <signal.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "dds_util.h"
#include "sqlite_util.h"
#include "palp.h"
#include "palp_dds.h"

#define DOMAIN 226
#define PHANTOM 3u
#define SESSIONS 1030

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: %s TMPDIR PALP_RECORDER DDS_CONFIG\n", argv[0]);
    return 2;
  }
  char db[600], logf[640];
  db_fresh_path(db, sizeof db, argv[1], "recorder-slots.db");
  snprintf(logf, sizeof logf, "%s.log", db);
  remove(logf);
  REQUIRE(palp_dds_use_config(argv[3]) == 0, "DDS config %s", argv[3]);
  const pid_t pid = start_recorder(argv[2], db, DOMAIN, logf, NULL);
  REQUIRE(pid >= 0, "fork");
  const dds_entity_t pp = dds_create_participant(DOMAIN, NULL, NULL);
  REQUIRE(pp > 0, "participant");
  const dds_entity_t w_cat = palp_dds_create_writer(pp, palp_dds_create_topic(pp, PALP_TOPIC_CATALOGUE),
                                                    PALP_TOPIC_CATALOGUE);
  const dds_entity_t w_state = palp_dds_create_writer(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_STATE),
                                                      PALP_TOPIC_SESSION_STATE);
  REQUIRE(wait_matched(w_cat, 1, 20) == 0 && wait_matched(w_state, 1, 20) == 0, "the recorder's readers matched");
  palp_mesh_def md = palp_mesh_default_def();
  palp_mesh mesh;
  REQUIRE(palp_mesh_create(&md, &mesh) == 0, "mesh");
  palp_Vec3 *rest = calloc((size_t)mesh.vertex_count, sizeof *rest);
  palp_Phantom ph = test_phantom(PHANTOM, "slot dome", &md, &mesh, rest, 250);
  REQUIRE(dds_write(w_cat, &ph) == 0, "catalogue");
  sleep_ms(300); /* the entry first: each session opens on a known phantom */
  for (uint32_t k = 1; k <= SESSIONS; k++) {
    palp_SessionState ss;
    memset(&ss, 0, sizeof ss);
    ss.session_id = k;
    ss.phantom_id = PHANTOM;
    ss.phase = palp_PHASE_OPEN;
    palp_dds_session_partition(k, ss.partition, sizeof ss.partition);
    snprintf(ss.trainee_station, sizeof ss.trainee_station, "host/1/t%u", k);
    snprintf(ss.trainee_name, sizeof ss.trainee_name, "t%u", k);
    ss.tick_rate_hz = 250;
    dds_write(w_state, &ss);
    if (k % 50 == 0) sleep_ms(20);
  }
  /* a forger writes contacts naming session 1 from session 2's partition */
  char part2[64];
  palp_dds_session_partition(2, part2, sizeof part2);
  const dds_entity_t w_forged = palp_dds_create_writer(palp_dds_session_publisher(pp, part2),
                                                       palp_dds_create_topic(pp, PALP_TOPIC_CONTACT), PALP_TOPIC_CONTACT);
  CHECK(w_forged > 0 && wait_matched(w_forged, 1, 20) == 0, "the forger's contact writer matched the recorder");
  sleep_ms(500);
  for (int k = 0; k < 20; k++) {
    palp_Contact c;
    memset(&c, 0, sizeof c);
    c.session_id = 1;
    c.seq = (uint64_t)k + 1;
    c.mode = palp_CONTACT_FINGER;
    c.center = (palp_Vec3){0, 0, 0.047};
    c.radius = 0.008;
    dds_write(w_forged, &c);
    sleep_ms(5);
  }
  sleep_ms(3000); /* taken, and written as fast as the disk goes */
  int status = 0;
  CHECK(stop_recorder(pid, &status), "the recorder stopped cleanly");
  sqlite3 *h = NULL;
  REQUIRE(sqlite3_open_v2(db, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK, "open %s", db);
  const int64_t rows = db_scalar(h, "SELECT count(*) FROM session");
  const int64_t forged = db_scalar(h, "SELECT sum(count) FROM event WHERE kind = 'reject' AND detail LIKE "
                                      "'%someone forged its session id%' AND session_id = (SELECT id FROM session "
                                      "WHERE trainee = 't1')");
  sqlite3_close(h);
  FILE *f = fopen(logf, "r");
  char line[8192];
  long said_lines = 0;
  long long not_recorded = -1;
  while (f && fgets(line, sizeof line, f)) {
    if (strstr(line, ": not recorded: ")) said_lines++;
    const char *at = strstr(line, " catalogue entries refused, ");
    if (at) sscanf(at, " catalogue entries refused, %lld sessions not recorded", &not_recorded);
  }
  if (f) fclose(f);
  printf("recorded %lld sessions, %lld said not recorded (%ld lines saying why); %lld forged contacts logged in "
         "session 1\n", (long long)rows, not_recorded, said_lines, (long long)forged);
  CHECK(not_recorded >= SESSIONS - 1024 && rows + not_recorded == SESSIONS,
        "every one of the %d sessions recorded (%lld) or counted as not recorded (%lld): none lost without a word",
        SESSIONS, (long long)rows, not_recorded);
  CHECK(said_lines >= 1, "the log says why at least once (%ld lines)", said_lines);
  CHECK(forged >= 1 && forged <= 20, "session 1, ended by the recorder's stop, logs the contacts forged into it: %lld "
        "(of 20 written best effort; before: no event)", (long long)forged);
  free(rest);
  palp_mesh_destroy(&mesh);
  dds_delete(pp);
  CHECK_DONE();
}
