/*
 * hostile_server.c - a forged palp-server for station_text: on DOMAIN it publishes phantom 1 with a name
 * carrying terminal escape sequences (the default 338-vertex dome), and answers every JOIN: "accept"
 * with session 1 in a partition whose name carries them too, its state open once a trainee joined (hers),
 * a rest-shape deformation frame every 0.1 s, and 1.5 s after the last join the session closed with a
 * reason that carries them;
 * "reject" refuses with such a reason. An unsecured classroom lets any peer write these; the stations
 * must print them terminal-safe. Runs SECONDS. Prints what it did; exit 0, 1 on a DDS failure.
 * usage: test_hostile_server DOMAIN accept|reject SECONDS
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h"
#include "palp_dds.h"
#include "server.h"

/* an OSC that retitles the terminal, a screen clear, a bell, a carriage return */
#define HOSTILE "\033]0;owned\007\033[2J\r"

int main(int argc, char **argv) {
  if (argc < 4 || (strcmp(argv[2], "accept") && strcmp(argv[2], "reject"))) {
    fprintf(stderr, "usage: %s DOMAIN accept|reject SECONDS\n", argv[0]);
    return 2;
  }
  const int accept = !strcmp(argv[2], "accept");
  int64_t end = palp_dds_now_ns() + (int64_t)(atof(argv[3]) * 1e9);
  const dds_entity_t pp = dds_create_participant((dds_domainid_t)atoi(argv[1]), NULL, NULL);
  if (pp < 0) return 1;
  const dds_entity_t cat_w = palp_dds_create_writer(pp, palp_dds_create_topic(pp, PALP_TOPIC_CATALOGUE), PALP_TOPIC_CATALOGUE);
  const dds_entity_t rq_r =
      palp_dds_create_reader(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REQUEST), PALP_TOPIC_SESSION_REQUEST);
  const dds_entity_t reply_w =
      palp_dds_create_writer(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REPLY), PALP_TOPIC_SESSION_REPLY);
  const dds_entity_t state_w =
      palp_dds_create_writer(pp, palp_dds_create_topic(pp, PALP_TOPIC_SESSION_STATE), PALP_TOPIC_SESSION_STATE);
  /* the session's endpoints, so that a station's join finds them matched */
  const char *partition = "palp/session/1" HOSTILE;
  const dds_entity_t pub = palp_dds_session_publisher(pp, partition), sub = palp_dds_session_subscriber(pp, partition);
  const dds_entity_t def_w =
      palp_dds_create_writer(pub, palp_dds_create_topic(pp, PALP_TOPIC_DEFORMATION), PALP_TOPIC_DEFORMATION);
  const dds_entity_t fb_w = palp_dds_create_writer(pub, palp_dds_create_topic(pp, PALP_TOPIC_FEEDBACK), PALP_TOPIC_FEEDBACK);
  const dds_entity_t lm_w =
      palp_dds_create_writer(pub, palp_dds_create_topic(pp, PALP_TOPIC_LOCAL_MODEL), PALP_TOPIC_LOCAL_MODEL);
  const dds_entity_t ct_r = palp_dds_create_reader(sub, palp_dds_create_topic(pp, PALP_TOPIC_CONTACT), PALP_TOPIC_CONTACT);
  if (cat_w < 0 || rq_r < 0 || reply_w < 0 || state_w < 0 || def_w < 0 || fb_w < 0 || lm_w < 0 || ct_r < 0) {
    fprintf(stderr, "hostile_server: DDS endpoints refused\n");
    return 1;
  }
  palp_mesh mesh;
  const palp_mesh_def md = palp_mesh_default_def();
  if (palp_mesh_create(&md, &mesh) < 0) return 1;
  palp_Vec3 *rest = malloc((size_t)mesh.vertex_count * sizeof *rest);
  int32_t *tri = malloc((size_t)mesh.triangle_count * 3 * sizeof *tri);
  if (!rest || !tri) return 1;
  palp_Phantom ph;
  memset(&ph, 0, sizeof ph);
  ph.phantom_id = 1;
  snprintf(ph.name, sizeof ph.name, "dome" HOSTILE "x");
  snprintf(ph.scene_name, sizeof ph.scene_name, "hostile");
  ph.radius = md.radius;
  ph.tick_rate_hz = 100;
  ph.max_force = 20;
  palp_srv_catalogue_mesh(&mesh, rest, tri, &ph);
  dds_write(cat_w, &ph);
  palp_SessionState st;
  memset(&st, 0, sizeof st);
  st.session_id = 1;
  st.phantom_id = 1;
  st.phase = palp_PHASE_OPEN;
  snprintf(st.partition, sizeof st.partition, "%s", partition);
  st.tick_rate_hz = 100;
  palp_Deformation d;
  memset(&d, 0, sizeof d);
  d.session_id = 1;
  d.positions = (dds_sequence_palp_Vec3){(uint32_t)mesh.vertex_count, (uint32_t)mesh.vertex_count, rest, false};
  int64_t close_at = 0, next_frame = 0;
  int joins = 0;
  while (palp_dds_now_ns() < end) {
    palp_SessionRequest rq;
    void *ptr[1] = {&rq};
    dds_sample_info_t info;
    while (dds_take(rq_r, ptr, &info, 1, 1) > 0) {
      if (!info.valid_data || rq.op != palp_OP_JOIN) continue;
      palp_SessionReply r;
      memset(&r, 0, sizeof r);
      snprintf(r.station_id, sizeof r.station_id, "%s", rq.station_id);
      r.request_seq = rq.request_seq;
      r.status = accept ? palp_REPLY_ACCEPTED : palp_REPLY_REJECTED;
      r.session_id = accept ? 1 : 0;
      r.phantom_id = 1;
      r.tick_rate_hz = 100;
      if (accept) snprintf(r.partition, sizeof r.partition, "%s", partition);
      else snprintf(r.reason, sizeof r.reason, "no room" HOSTILE "x");
      dds_write(reply_w, &r);
      joins++;
      if (accept && rq.role == palp_ROLE_TRAINEE && !st.trainee_station[0]) { /* the session is hers */
        snprintf(st.trainee_station, sizeof st.trainee_station, "%s", rq.station_id);
        snprintf(st.trainee_name, sizeof st.trainee_name, "%s", rq.user_name);
        dds_write(state_w, &st);
      }
      if (accept && st.phase == palp_PHASE_OPEN) close_at = palp_dds_now_ns() + 1500000000; /* 1.5 s after the last join */
    }
    const int64_t now = palp_dds_now_ns();
    if (accept && now >= next_frame) {
      d.frame++;
      d.sim_time = 0.01 * (double)d.frame;
      dds_write(def_w, &d);
      next_frame = now + 100000000;
    }
    if (close_at && now >= close_at) {
      st.phase = palp_PHASE_CLOSED;
      snprintf(st.reason, sizeof st.reason, "closed" HOSTILE "x");
      dds_write(state_w, &st);
      close_at = 0;
      /* its closing said, 1 s more for the stations to read it; the lifetime given is a bound (a
       * loaded machine's stations may join seconds late: the close waits for them, not a clock) */
      if (now + 1000000000 < end) end = now + 1000000000;
      printf("hostile_server: session 1 closed with an escape sequence in its reason\n");
    }
    dds_sleepfor(DDS_MSECS(10));
  }
  printf("hostile_server: %s %d join(s)\n", accept ? "accepted" : "rejected", joins);
  free(rest);
  free(tri);
  palp_mesh_destroy(&mesh);
  dds_delete(pp);
  return 0;
}
