/*
 * exercise_peer.c - plays the server's part of the assessment wire contract for the web tests,
 * until palp-server hosts exercises itself (branch `findings`): publishes an Exercise for one
 * catalogue phantom, answers every open session of that phantom with a FindingStatus (marks 0,
 * time left), reads palp_finding in every session partition, keeps the marks standing per session
 * and answers each finding with a new FindingStatus. Every finding is printed on stdout, one line
 * each, for the test to assert on:
 *   FINDING session=ID op=mark|withdraw mark=N point=X,Y,Z time=T
 * usage: web_exercise_peer DOMAIN PHANTOM_ID SECONDS (CYCLONEDDS_URI set by the caller)
 * PHANTOM_ID 0: listen only (palp-server hosts the exercise and answers): it publishes nothing
 * and only prints the findings it reads, so a test can assert what reached the domain.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <dds/dds.h>

#include "palp_dds.h"

#define MAX_SESSIONS 16
#define MAX_MARKS 64
#define TIME_LIMIT_S 300.0

typedef struct peer_session {
  uint32_t id;
  dds_entity_t pub, w;
  int64_t opened_ns;
  int announced; /* the first status (marks 0, time left) was sent */
  uint32_t marks[MAX_MARKS];
  int n;
} peer_session;

static peer_session sessions[MAX_SESSIONS];

static peer_session *session_get(dds_entity_t pp, dds_entity_t topic, uint32_t id) {
  for (int i = 0; i < MAX_SESSIONS; i++)
    if (sessions[i].id == id) return &sessions[i];
  for (int i = 0; i < MAX_SESSIONS; i++)
    if (!sessions[i].id) {
      peer_session *s = &sessions[i];
      char part[64];
      palp_dds_session_partition(id, part, sizeof part);
      s->pub = palp_dds_session_publisher(pp, part);
      s->w = s->pub > 0 ? palp_dds_create_writer(s->pub, topic, PALP_TOPIC_FINDING_STATUS) : -1;
      if (s->w <= 0) return NULL;
      s->id = id;
      s->opened_ns = palp_dds_now_ns();
      return s;
    }
  return NULL;
}

static int listen_only;

static void answer(peer_session *s, uint32_t mark_id, int accepted, const char *reason) {
  if (listen_only) return;
  palp_FindingStatus st;
  memset(&st, 0, sizeof st);
  st.session_id = s->id;
  st.marks = (uint32_t)s->n;
  st.last_mark_id = mark_id;
  st.last_accepted = accepted != 0;
  snprintf(st.reason, sizeof st.reason, "%s", reason);
  st.time_left = TIME_LIMIT_S - (double)(palp_dds_now_ns() - s->opened_ns) * 1e-9;
  dds_write(s->w, &st);
}

int main(int argc, char **argv) {
  if (argc != 4) {
    fprintf(stderr, "usage: %s DOMAIN PHANTOM_ID SECONDS\n", argv[0]);
    return 2;
  }
  const uint32_t domain = (uint32_t)strtoul(argv[1], NULL, 10), phantom = (uint32_t)strtoul(argv[2], NULL, 10);
  const double seconds = atof(argv[3]);
  const dds_entity_t pp = dds_create_participant(domain, NULL, NULL);
  if (pp < 0) {
    fprintf(stderr, "exercise_peer: no participant: %s\n", dds_strretcode(pp));
    return 1;
  }
  const dds_entity_t t_ex = palp_dds_create_topic(pp, PALP_TOPIC_EXERCISE);
  const dds_entity_t t_f = palp_dds_create_topic(pp, PALP_TOPIC_FINDING);
  const dds_entity_t t_fs = palp_dds_create_topic(pp, PALP_TOPIC_FINDING_STATUS);
  const dds_entity_t t_st = palp_dds_create_topic(pp, PALP_TOPIC_SESSION_STATE);
  const dds_entity_t w_ex = palp_dds_create_writer(pp, t_ex, PALP_TOPIC_EXERCISE);
  const dds_entity_t r_st = palp_dds_create_reader(pp, t_st, PALP_TOPIC_SESSION_STATE);
  char wildcard[64];
  snprintf(wildcard, sizeof wildcard, PALP_DDS_SESSION_PARTITION_FMT, 0u);
  char *z = strrchr(wildcard, '/');
  if (z) snprintf(z + 1, sizeof wildcard - (size_t)(z + 1 - wildcard), "*");
  const dds_entity_t sub = palp_dds_session_subscriber(pp, wildcard);
  const dds_entity_t r_f = palp_dds_create_reader(sub, t_f, PALP_TOPIC_FINDING);
  if (w_ex <= 0 || r_st <= 0 || r_f <= 0) {
    fprintf(stderr, "exercise_peer: cannot create endpoints\n");
    return 1;
  }
  listen_only = phantom == 0;
  palp_Exercise ex;
  memset(&ex, 0, sizeof ex);
  ex.phantom_id = phantom;
  snprintf(ex.name, sizeof ex.name, "web-test");
  snprintf(ex.title, sizeof ex.title, "Find the lump (web test)");
  snprintf(ex.instructions, sizeof ex.instructions,
           "Palpate the dome in vertical strips at three pressures. Mark every lump you feel.");
  ex.time_limit = TIME_LIMIT_S;
  ex.max_force = 10;
  if (!listen_only) dds_write(w_ex, &ex);
  printf("READY phantom=%u\n", phantom);
  fflush(stdout);
  const int64_t end = palp_dds_now_ns() + (int64_t)(seconds * 1e9);
  while (palp_dds_now_ns() < end) {
    palp_SessionState st;
    void *sp = &st;
    dds_sample_info_t si;
    while (dds_take(r_st, &sp, &si, 1, 1) == 1) {
      if (si.valid_data && st.phase == palp_PHASE_OPEN && st.phantom_id == phantom) {
        peer_session *s = session_get(pp, t_fs, st.session_id);
        if (s && !s->announced) answer(s, 0, 1, ""), s->announced = 1;
      }
    }
    palp_Finding f;
    void *fp = &f;
    while (dds_take(r_f, &fp, &si, 1, 1) == 1) {
      if (!si.valid_data) continue;
      peer_session *s = session_get(pp, t_fs, f.session_id);
      if (!s) continue;
      int ok = 0;
      const char *why = "";
      if (f.op == palp_FINDING_MARK) {
        ok = isfinite(f.point.x) && isfinite(f.point.y) && isfinite(f.point.z) && s->n < MAX_MARKS;
        if (ok) s->marks[s->n++] = f.mark_id;
        else why = "bad point or too many marks";
      } else {
        for (int i = 0; i < s->n && !ok; i++)
          if (s->marks[i] == f.mark_id) {
            s->marks[i] = s->marks[--s->n];
            ok = 1;
          }
        if (!ok) why = "no such mark";
      }
      answer(s, f.mark_id, ok, why);
      printf("FINDING session=%u op=%s mark=%u point=%.6f,%.6f,%.6f time=%.4f\n", f.session_id,
             f.op == palp_FINDING_MARK ? "mark" : "withdraw", f.mark_id, f.point.x, f.point.y, f.point.z, f.time);
      fflush(stdout);
    }
    dds_sleepfor(DDS_MSECS(10));
  }
  dds_delete(pp);
  return 0;
}
