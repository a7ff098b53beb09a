/*
 * catalogue_forger.c - another participant on DOMAIN, not the server, that writes a catalogue entry and an
 * exercise for each PHANTOM every 5 ms for SECONDS (review s83 #1), as any peer of an unsecured classroom
 * may: the entry valid (4 vertices, named "FORGED", a 0.1 N max_force, a 5 mm radius), the exercise
 * "forged" ("FORGED EXERCISE") with a 5 s time limit and its own pressure bands. A station joined to
 * PHANTOM's server must take neither. Says its participant first; exit 0, 1 on a DDS failure.
 * usage: test_catalogue_forger DOMAIN SECONDS PHANTOM...
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp_dds.h"

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: %s DOMAIN SECONDS PHANTOM...\n", argv[0]);
    return 2;
  }
  const dds_entity_t pp = dds_create_participant((dds_domainid_t)atoi(argv[1]), NULL, NULL);
  if (pp < 0) return 1;
  const dds_entity_t cat_w = palp_dds_create_writer(pp, palp_dds_create_topic(pp, PALP_TOPIC_CATALOGUE), PALP_TOPIC_CATALOGUE);
  const dds_entity_t ex_w = palp_dds_create_writer(pp, palp_dds_create_topic(pp, PALP_TOPIC_EXERCISE), PALP_TOPIC_EXERCISE);
  if (cat_w < 0 || ex_w < 0) {
    fprintf(stderr, "catalogue_forger: DDS writers refused\n");
    return 1;
  }
  /* a tetrahedron under a 5 mm dome: palp_dds_phantom_check's smallest valid mesh */
  palp_Vec3 rest[4] = {{0, 0, 0.005}, {0.005, 0, 0}, {-0.0025, 0.0043, 0}, {-0.0025, -0.0043, 0}};
  int32_t tri[12] = {0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2};
  palp_Phantom ph;
  memset(&ph, 0, sizeof ph);
  snprintf(ph.name, sizeof ph.name, "FORGED");
  snprintf(ph.scene_name, sizeof ph.scene_name, "forged");
  ph.radius = 0.005;
  ph.tick_rate_hz = 100;
  ph.max_force = 0.1;
  ph.top_vertex = 0;
  ph.dome_triangle_count = 3;
  ph.rest._buffer = rest;
  ph.rest._length = ph.rest._maximum = 4;
  ph.triangles._buffer = tri;
  ph.triangles._length = ph.triangles._maximum = 12;
  palp_Exercise ex;
  memset(&ex, 0, sizeof ex);
  snprintf(ex.name, sizeof ex.name, "forged");
  snprintf(ex.title, sizeof ex.title, "FORGED EXERCISE");
  snprintf(ex.instructions, sizeof ex.instructions, "These instructions were written by another participant.");
  ex.time_limit = 5;
  ex.max_force = 3;
  for (int b = 0; b < 3; b++) {
    ex.bands[b].has_force = 1;
    ex.bands[b].force_min = b;
    ex.bands[b].force_max = b + 1;
  }
  /* said first: the test stops it with a signal once its stations are done */
  dds_guid_t g;
  char who[64] = "participant ?";
  if (dds_get_guid(pp, &g) == 0) palp_dds_participant_text(&g, who, sizeof who);
  printf("catalogue_forger: a catalogue entry and an exercise for %d phantom(s) every 5 ms, written by %s\n",
         argc - 3, who);
  fflush(stdout);
  const int64_t end = palp_dds_now_ns() + (int64_t)(atof(argv[2]) * 1e9);
  int entries = 0, exercises = 0;
  while (palp_dds_now_ns() < end) {
    for (int k = 3; k < argc; k++) {
      ph.phantom_id = ex.phantom_id = (uint32_t)strtoul(argv[k], NULL, 10);
      entries += dds_write(cat_w, &ph) == 0;
      exercises += dds_write(ex_w, &ex) == 0;
    }
    dds_sleepfor(DDS_MSECS(5));
  }
  printf("catalogue_forger: %d catalogue entries and %d exercises written\n", entries, exercises);
  dds_delete(pp);
  return 0;
}
