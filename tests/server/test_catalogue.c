/* test_catalogue.c - a station that starts after the server still receives the
 * phantom catalogue (reliable, transient-local), with the rest mesh; the tenth server
 * identity is found by name; and (2026-12-07) a phantom behind 300 made-up catalogue
 * entries is still found, by id and by name. Domain 101, ~2.6 s. */
#include <math.h>
#include <string.h>

#include "harness.h"

#define DOMAIN 101

int main(void) {
  test_init();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  /* Twelve phantoms, more than one read of 8 held: the station must see every one (it read 8
   * at a time and never found the ninth phantom of config/server-exercises.json). */
  for (int k = 2; k < 12; ++k) {
    cfg.phantom[k] = cfg.phantom[1];
    cfg.phantom[k].id = (uint32_t)k + 1;
    snprintf(cfg.phantom[k].name, sizeof cfg.phantom[k].name, "test dome %c", 'A' + k);
  }
  cfg.phantom_count = 12;
  test_server ts = {0};
  test_server_start(&ts, &cfg);
  /* The server has published (and its writer holds) the catalogue well before
   * this station exists: a late joiner by 1.5 s. */
  test_sleep(1.5);
  palp_cli_station st;
  char err[512];
  REQUIRE(palp_cli_station_open(&st, DOMAIN, "late", err, sizeof err) == 0, "late station opens (%s)", err);
  int64_t t0 = palp_dds_now_ns();
  for (uint32_t id = 1; id <= 2; id++) {
    palp_Phantom ph;
    int rc = palp_cli_station_catalogue(&st, id, 5.0, &ph, err, sizeof err);
    REQUIRE(rc == 0, "phantom %u in the catalogue after %.0f ms (within 5 s) %s", id,
            (double)(palp_dds_now_ns() - t0) * 1e-6, rc ? err : "");
    /* From config/paper_step.json: 338 vertices on a 4 cm dome; a closed
     * triangulated surface of sphere topology has F = 2V - 4 faces (Euler). */
    CHECK(ph.rest._length == 338, "phantom %u: %u rest vertices, want 338 (paper_step.json)", id, ph.rest._length);
    CHECK(ph.triangles._length == 3 * (2 * 338 - 4), "phantom %u: %u triangle indices, want 3 (2V - 4) = %d", id,
          ph.triangles._length, 3 * (2 * 338 - 4));
    CHECK(fabs(ph.radius - 0.04) < 1e-12, "phantom %u: radius %g m, want 0.04", id, ph.radius);
    CHECK(ph.tick_rate_hz == 100 && ph.max_force == 20, "phantom %u: %g Hz, limit %g N (config: 100 Hz, 20 N)", id,
          ph.tick_rate_hz, ph.max_force);
    CHECK(strcmp(ph.name, id == 1 ? "test dome A" : "test dome B") == 0, "phantom %u is named \"%s\"", id, ph.name);
    double rmax = 0;
    int bad = 0;
    for (uint32_t i = 0; i < ph.rest._length; i++) {
      palp_Vec3 p = ph.rest._buffer[i];
      double r = sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
      if (r > rmax) rmax = r;
      bad += p.z < -1e-12;
    }
    CHECK(fabs(rmax - 0.04) < 1e-9 && bad == 0, "rest vertices on a hemisphere of radius 0.04 m (max |x| %.6f m, %d below z=0)",
          rmax, bad);
    int range = 1;
    for (uint32_t i = 0; i < ph.triangles._length; i++)
      range &= ph.triangles._buffer[i] >= 0 && ph.triangles._buffer[i] < (int32_t)ph.rest._length;
    CHECK(range, "every triangle index is a vertex");
    palp_cli_phantom_free(&ph);
  }
  for (uint32_t id = 9; id <= 12; id++) {
    palp_Phantom ph;
    int rc = palp_cli_station_catalogue(&st, id, 5.0, &ph, err, sizeof err);
    CHECK(rc == 0 && ph.phantom_id == id && ph.name[10] == (char)('A' + id - 1),
          "phantom %u of 12 in the catalogue: %s", id, rc ? err : ph.name);
    if (rc == 0) palp_cli_phantom_free(&ph);
  }
  palp_Phantom none;
  CHECK(palp_cli_station_catalogue(&st, 99, 0.5, &none, err, sizeof err) < 0, "phantom 99 is not hosted: %s", err);
  /* Nine more servers' identities on the domain besides the harness server's, written in order: --server NAME
   * must find the last, past any first 8 (the station read 8 at a time, the same first 8 on every pass, and
   * never found a ninth server: session 77). Numbers no real server here has. */
  const dds_entity_t fp = dds_create_participant(DOMAIN, NULL, NULL);
  const dds_entity_t fw = palp_dds_create_writer(fp, palp_dds_create_topic(fp, PALP_TOPIC_SERVER_IDENTITY),
                                                 PALP_TOPIC_SERVER_IDENTITY);
  REQUIRE(fp > 0 && fw > 0, "a peer writes server identities");
  for (int k = 1; k <= 9; k++) {
    palp_ServerIdentity id;
    memset(&id, 0, sizeof id);
    snprintf(id.server_name, sizeof id.server_name, "room-%d", k);
    id.server_number = 4000 + (uint32_t)k;
    snprintf(id.instance, sizeof id.instance, "test/%d", k);
    id.started_unix_ns = k;
    dds_write(fw, &id);
  }
  uint32_t number = 0;
  int rc = palp_cli_station_server_number(&st, "room-9", 5.0, &number, err, sizeof err);
  CHECK(rc == 0 && number == 4009, "--server room-9, the tenth identity on the domain, is server %u (want 4009) %s",
        number, rc ? err : "");
  rc = palp_cli_station_server_number(&st, "room-1", 5.0, &number, err, sizeof err);
  CHECK(rc == 0 && number == 4001, "--server room-1 is server %u (want 4001) %s", number, rc ? err : "");
  /* (2026-12-07) 300 made-up, valid catalogue entries (phantoms 1001..1300, named "decoy") that a peer
   * wrote before the server's: a station that read the catalogue 256 samples at a time with a plain read
   * saw the same first 256 on every pass, all decoys, and, already joined, exited 1 "no catalogue entry
   * for phantom 1". It looks its phantom up by its key, and searches every entry for a name. The server
   * is started again after a fresh station has received the decoys: its entries come after them. */
  palp_Phantom real;
  err[0] = 0;
  REQUIRE(palp_cli_station_catalogue(&st, 1, 5.0, &real, err, sizeof err) == 0, "phantom 1, the decoys' mesh: %s", err);
  test_server_stop(&ts);
  const dds_entity_t dw = palp_dds_create_writer(fp, palp_dds_create_topic(fp, PALP_TOPIC_CATALOGUE), PALP_TOPIC_CATALOGUE);
  REQUIRE(dw > 0, "a peer writes catalogue entries");
  enum { DECOYS = 300 };
  for (uint32_t k = 1; k <= DECOYS; k++) {
    palp_Phantom d = real;
    d.phantom_id = 1000 + k;
    snprintf(d.name, sizeof d.name, "decoy %u", k);
    dds_write(dw, &d);
  }
  palp_cli_station fresh;
  err[0] = 0;
  REQUIRE(palp_cli_station_open(&fresh, DOMAIN, "fresh", err, sizeof err) == 0, "a fresh station opens (%s)", err);
  int held = 0;
  for (int64_t until = palp_dds_now_ns() + 5000000000LL; held < DECOYS && palp_dds_now_ns() < until; test_sleep(0.02)) {
    void *ptr[DECOYS + 20] = {NULL};
    dds_sample_info_t info[DECOYS + 20];
    held = dds_read(fresh.catalogue_r, ptr, info, DECOYS + 20, DECOYS + 20);
    if (held > 0) dds_return_loan(fresh.catalogue_r, ptr, held);
  }
  REQUIRE(held == DECOYS, "the fresh station holds the %d decoys (%d) before the server starts again", DECOYS, held);
  test_server_start(&ts, &cfg);
  palp_Phantom ph1;
  rc = palp_cli_station_catalogue(&fresh, 1, 5.0, &ph1, err, sizeof err);
  CHECK(rc == 0 && ph1.phantom_id == 1 && strcmp(ph1.name, "test dome A") == 0,
        "phantom 1 found behind %d decoy entries: %s", DECOYS, rc ? err : ph1.name);
  if (rc == 0) palp_cli_phantom_free(&ph1);
  uint32_t found = 0;
  rc = palp_cli_station_find_phantom(&fresh, "test dome L", -1, -1, 5.0, &found, err, sizeof err);
  CHECK(rc == 0 && found == 12, "\"test dome L\" found by name behind %d decoy entries: phantom %u %s", DECOYS, found,
        rc ? err : "");
  palp_cli_phantom_free(&real);
  palp_cli_station_close(&fresh);
  dds_delete(fp);
  palp_cli_station_close(&st);
  test_server_stop(&ts);
  fprintf(stderr, "%d failure(s)\n", palp_test_failures);
  return palp_test_failures ? 1 : 0;
}
