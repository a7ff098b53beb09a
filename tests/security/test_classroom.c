/* test_classroom.c - a secured classroom over the real DDS Security plugins: who may
 * join, write, read and close what (docs/security.md).
 *
 * Cyclone DDS 0.10.2's access control plugin is built with
 * ACCESS_CONTROL_USE_ONE_PERMISSION: every secured participant of one process on
 * one domain shares the first one's permissions. So each identity runs in a
 * process of its own: this program is the server (in-process, domain 130) and
 * re-executes itself once per identity ("child ROLE"). Alice presses 3 N for
 * 9 s while the others try their attacks; each process asserts what it sees.
 *
 * usage: test_security_classroom PKI_DIR   (made by make_pki.sh) */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <spawn.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../open_session.h"
#include "harness.h"
#include "palp_dds_refusals.h"
#include "palp_pem.h"
#include "../tmpdir.h"

#define DOMAIN 130
#define ALICE_SECONDS 12.0

extern char **environ;

static const char *pki;

static void open_secure(palp_cli_station *st, const char *dir, const char *identity, const char *label) {
  palp_dds_security sec;
  char err[512];
  if (palp_dds_security_init(&sec, dir, identity, err, sizeof err) < 0) {
    fprintf(stderr, "%s: %s\n", identity, err);
    exit(1);
  }
  if (palp_cli_station_open_secure(st, DOMAIN, label, &sec, err, sizeof err) < 0) {
    fprintf(stderr, "%s: %s\n", identity, err);
    exit(1);
  }
}

static int join(palp_cli_station *st, int role, uint32_t phantom, uint32_t session, double timeout, char *err,
                size_t errlen) {
  palp_cli_join j = {.role = role, .phantom_id = phantom, .session_id = session, .want_feedback = 1,
                     .want_deformation = role != palp_ROLE_TRAINEE, .timeout = timeout};
  return palp_cli_station_join(st, &j, err, errlen);
}

/* Counts valid samples on a reader for `seconds` (take). */
static int count_samples(dds_entity_t rd, double seconds) {
  int64_t end = palp_dds_now_ns() + (int64_t)(seconds * 1e9);
  int n = 0;
  do {
    void *ptr[8] = {NULL};
    dds_sample_info_t info[8];
    int k;
    while ((k = dds_take(rd, ptr, info, 8, 8)) > 0) {
      for (int i = 0; i < k; i++) n += info[i].valid_data;
      dds_return_loan(rd, ptr, k);
    }
    test_sleep(0.01);
  } while (palp_dds_now_ns() < end);
  return n;
}

static int matched_pubs(dds_entity_t rd) {
  dds_instance_handle_t h[8];
  return (int)dds_get_matched_publications(rd, h, 8);
}

static int matched_subs(dds_entity_t wr) {
  dds_instance_handle_t h[8];
  return (int)dds_get_matched_subscriptions(wr, h, 8);
}

/* Waits for the open session of trainee `name` in the public session states (0, or -1). */
static int find_session(palp_cli_station *st, const char *name, double timeout, palp_SessionState *out) {
  return palp_test_open_session(st->pp, name, timeout, out) ? 0 : -1;
}

/* A request written through st's own request writer (its identity's partition)
 * with any station id: what a modified station could send. */
static void send_request(palp_cli_station *st, const char *station_id, int op, int role, uint32_t phantom,
                         uint32_t session, const char *user, uint32_t seq) {
  palp_SessionRequest rq;
  memset(&rq, 0, sizeof rq);
  snprintf(rq.station_id, sizeof rq.station_id, "%s", station_id);
  rq.request_seq = seq;
  rq.op = op;
  rq.role = role;
  rq.phantom_id = phantom;
  rq.session_id = session;
  snprintf(rq.user_name, sizeof rq.user_name, "%s", user);
  rq.want_feedback = 1;
  dds_write(st->request_w, &rq);
}

static double force_of(const palp_Feedback *fb) {
  for (uint32_t k = 0; k < fb->fingers._length; k++)
    if (fb->fingers._buffer[k].finger == 0) {
      palp_Vec3 f = fb->fingers._buffer[k].force;
      return sqrt(f.x * f.x + f.y * f.y + f.z * f.z);
    }
  return 0;
}

/* ---- alice: presses 3 N for ALICE_SECONDS; nothing anyone else does may change that ---- */
static void child_alice(void) {
  palp_cli_station alice;
  char err[512];
  open_secure(&alice, pki, "trainee/alice", "t");
  REQUIRE(join(&alice, palp_ROLE_TRAINEE, 1, 0, 15, err, sizeof err) == 0, "alice joins phantom 1 (%s)", err);
  char want[64];
  snprintf(want, sizeof want, "palp/s/alice/%u", alice.session_id);
  CHECK(strcmp(alice.partition, want) == 0, "alice's session partition is %s (expected %s)", alice.partition, want);
  int64_t t0 = palp_dds_now_ns(), end = t0 + (int64_t)(ALICE_SECONDS * 1e9);
  double fmin = 1e9, fmax = 0;
  int samples = 0, forged_replies = 0, closed = 0;
  uint64_t seq = 0;
  while (palp_dds_now_ns() < end && !closed) {
    test_send_force(&alice, 0, 2, 30, 40, 3.0, ++seq);
    test_sleep(0.01);
    void *ptr[4] = {NULL};
    dds_sample_info_t info[4];
    int k;
    while ((k = dds_take(alice.feedback_r, ptr, info, 4, 4)) > 0) {
      for (int i = 0; i < k; i++)
        if (info[i].valid_data && palp_dds_now_ns() - t0 > 1500000000LL) {
          double f = force_of(ptr[i]);
          fmin = f < fmin ? f : fmin;
          fmax = f > fmax ? f : fmax;
          samples++;
        }
      dds_return_loan(alice.feedback_r, ptr, k);
    }
    while ((k = dds_take(alice.reply_r, ptr, info, 4, 4)) > 0) {
      for (int i = 0; i < k; i++)
        forged_replies += info[i].valid_data && strcmp(((palp_SessionReply *)ptr[i])->reason, "forged") == 0;
      dds_return_loan(alice.reply_r, ptr, k);
    }
    closed = palp_cli_station_session_closed(&alice, NULL, 0);
  }
  CHECK(!closed, "alice's session %u stayed open for %.0f s (bob's forged LEAVE, JOIN and disposal did nothing)",
        alice.session_id, ALICE_SECONDS);
  CHECK(samples > 300 && fmin > 2.7 && fmax < 3.3,
        "she felt her own 3 N throughout: %d feedback samples in [%.3f, %.3f] N (tolerance 0.3 N; the intruders' 5 N "
        "never applied)", samples, fmin, fmax);
  CHECK(forged_replies == 0, "no forged reply reached her (%d)", forged_replies);
  palp_cli_station_leave(&alice);
  test_sleep(0.2);
  palp_cli_station_close(&alice);
}

/* ---- bob: another trainee tries to write into, read, close, take over and rename ---- */
static void child_bob(void) {
  palp_cli_station bob;
  char err[512];
  open_secure(&bob, pki, "trainee/bob", "t");
  /* nor join under another name */
  send_request(&bob, bob.station_id, palp_OP_JOIN, palp_ROLE_TRAINEE, 2, 0, "alice", 902);
  palp_SessionReply rep;
  memset(&rep, 0, sizeof rep);
  int64_t end = palp_dds_now_ns() + 3000000000LL;
  int got = 0;
  while (!got && palp_dds_now_ns() < end) {
    void *ptr[1] = {&rep};
    dds_sample_info_t info;
    while (!got && dds_take(bob.reply_r, ptr, &info, 1, 1) > 0)
      got = info.valid_data && rep.request_seq == 902 && !strcmp(rep.station_id, bob.station_id);
    test_sleep(0.01);
  }
  CHECK(got && rep.status == palp_REPLY_REJECTED && strstr(rep.reason, "not the authenticated identity"),
        "bob joining under the name \"alice\" is rejected: %s", got ? rep.reason : "(no reply)");
  REQUIRE(join(&bob, palp_ROLE_TRAINEE, 2, 0, 15, err, sizeof err) == 0, "bob joins phantom 2 (%s)", err);
  palp_SessionState a;
  REQUIRE(find_session(&bob, "alice", 10, &a) == 0, "bob sees alice's session %u in the public session states",
          a.session_id);
  dds_entity_t pub = palp_dds_session_publisher(bob.pp, a.partition);
  dds_entity_t sub = palp_dds_session_subscriber(bob.pp, a.partition);
  dds_entity_t w = palp_dds_create_writer(pub, bob.topic[PALP_TOPIC_CONTACT], PALP_TOPIC_CONTACT);
  CHECK(w == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY, "bob's contact writer in %s is refused: %s", a.partition,
        dds_strretcode(w));
  dds_entity_t r = palp_dds_create_reader(sub, bob.topic[PALP_TOPIC_FEEDBACK], PALP_TOPIC_FEEDBACK);
  dds_entity_t rd = palp_dds_create_reader(sub, bob.topic[PALP_TOPIC_DEFORMATION], PALP_TOPIC_DEFORMATION);
  CHECK(r == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY && rd == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY,
        "bob's feedback and deformation readers in %s are refused: %s, %s", a.partition, dds_strretcode(r),
        dds_strretcode(rd));
  /* issue 13: nor mark lumps in alice's session, nor read her findings' answers */
  dds_entity_t fw = palp_dds_create_writer(pub, bob.topic[PALP_TOPIC_FINDING], PALP_TOPIC_FINDING);
  dds_entity_t fr = palp_dds_create_reader(sub, bob.topic[PALP_TOPIC_FINDING_STATUS], PALP_TOPIC_FINDING_STATUS);
  CHECK(fw == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY && fr == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY,
        "bob's finding writer and finding-status reader in %s are refused: %s, %s", a.partition, dds_strretcode(fw),
        dds_strretcode(fr));
  CHECK(bob.finding_w > 0 && bob.finding_status_r > 0, "bob's own session has his finding writer and status reader");
  /* 2026-12-05: nor read her debrief (what she found, and where the lesions are), nor write one as
   * the server in his own session; his own session has his debrief reader */
  dds_entity_t dr = palp_dds_create_reader(sub, bob.topic[PALP_TOPIC_DEBRIEF], PALP_TOPIC_DEBRIEF);
  dds_entity_t dw_own = palp_dds_create_writer(palp_dds_session_publisher(bob.pp, bob.partition),
                                               bob.topic[PALP_TOPIC_DEBRIEF], PALP_TOPIC_DEBRIEF);
  CHECK(dr == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY && dw_own == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY && bob.debrief_r > 0,
        "bob's debrief reader in %s is refused (%s), and a debrief writer in his own (%s); he reads his own", a.partition,
        dds_strretcode(dr), dds_strretcode(dw_own));
  /* session 64: likewise her score (palp_debrief_score): not read in her session, not forged in his;
   * he reads his own */
  dds_entity_t sr = palp_dds_create_reader(sub, bob.topic[PALP_TOPIC_DEBRIEF_SCORE], PALP_TOPIC_DEBRIEF_SCORE);
  dds_entity_t sw_own = palp_dds_create_writer(palp_dds_session_publisher(bob.pp, bob.partition),
                                               bob.topic[PALP_TOPIC_DEBRIEF_SCORE], PALP_TOPIC_DEBRIEF_SCORE);
  CHECK(sr == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY && sw_own == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY &&
            bob.debrief_score_r > 0,
        "bob's score reader in %s is refused (%s), and a score writer in his own (%s); he reads his own", a.partition,
        dds_strretcode(sr), dds_strretcode(sw_own));
  /* session 69: nor read her session's own log losses (palp_session_log), nor write them into his; he
   * reads his own */
  dds_entity_t lr = palp_dds_create_reader(sub, bob.topic[PALP_TOPIC_SESSION_LOG], PALP_TOPIC_SESSION_LOG);
  dds_entity_t lw_own = palp_dds_create_writer(palp_dds_session_publisher(bob.pp, bob.partition),
                                               bob.topic[PALP_TOPIC_SESSION_LOG], PALP_TOPIC_SESSION_LOG);
  CHECK(lr == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY && lw_own == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY &&
            bob.session_log_r > 0,
        "bob's session-log reader in %s is refused (%s), and a session-log writer in his own (%s); he reads his own",
        a.partition, dds_strretcode(lr), dds_strretcode(lw_own));
  /* nor answer findings as the server, nor publish an exercise */
  dds_entity_t own_pub = palp_dds_session_publisher(bob.pp, bob.partition);
  dds_entity_t fsw = palp_dds_create_writer(own_pub, bob.topic[PALP_TOPIC_FINDING_STATUS], PALP_TOPIC_FINDING_STATUS);
  dds_entity_t exw = palp_dds_create_writer(bob.pp, bob.topic[PALP_TOPIC_EXERCISE], PALP_TOPIC_EXERCISE);
  CHECK(fsw == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY && exw == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY,
        "bob may not write finding status (even in his own session) nor exercises: %s, %s", dds_strretcode(fsw),
        dds_strretcode(exw));
  /* session 60: nor read any session's exercise with its lesions (the answers), the server's to
   * instructors: a trainee's permissions do not even create the topic (its station does not try) */
  const dds_entity_t sx = palp_dds_create_topic(bob.pp, PALP_TOPIC_SESSION_EXERCISE);
  CHECK(sx == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY && bob.topic[PALP_TOPIC_SESSION_EXERCISE] == 0,
        "bob may not create topic palp_session_exercise (%s), and his station does not try", dds_strretcode(sx));
  /* session 63: nor the closed exercise sessions' scores (what every trainee's marks found) */
  const dds_entity_t ss = palp_dds_create_topic(bob.pp, PALP_TOPIC_SESSION_SCORE);
  CHECK(ss == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY && bob.topic[PALP_TOPIC_SESSION_SCORE] == 0,
        "bob may not create topic palp_session_score (%s), and his station does not try", dds_strretcode(ss));
  /* session 69: nor the instructors' list of who the closed sessions were (nor forge one) */
  const dds_entity_t sc = palp_dds_create_topic(bob.pp, PALP_TOPIC_SESSION_CLOSED);
  CHECK(sc == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY && bob.topic[PALP_TOPIC_SESSION_CLOSED] == 0,
        "bob may not create topic palp_session_closed (%s), and his station does not try", dds_strretcode(sc));
  /* nor publish as the server */
  const palp_dds_topic_kind server_topics[] = {PALP_TOPIC_CATALOGUE, PALP_TOPIC_SESSION_REPLY,
                                                PALP_TOPIC_SESSION_STATE, PALP_TOPIC_SERVER_STATUS};
  int refused = 0;
  for (int k = 0; k < 4; k++)
    refused += palp_dds_create_writer(bob.pp, bob.topic[server_topics[k]], server_topics[k]) ==
               DDS_RETCODE_NOT_ALLOWED_BY_SECURITY;
  dds_entity_t own = palp_dds_session_publisher(bob.pp, bob.partition);
  refused += palp_dds_create_writer(own, bob.topic[PALP_TOPIC_FEEDBACK], PALP_TOPIC_FEEDBACK) ==
             DDS_RETCODE_NOT_ALLOWED_BY_SECURITY;
  refused += palp_dds_create_writer(own, bob.topic[PALP_TOPIC_DEFORMATION], PALP_TOPIC_DEFORMATION) ==
             DDS_RETCODE_NOT_ALLOWED_BY_SECURITY;
  CHECK(refused == 6, "bob may not write catalogue, reply, state, status, nor feedback or deformation even in his "
        "own session: %d of 6 refused", refused);
  /* nor close or take over alice's station (through his own, permitted writer).
   * Requests are keep-last 1 per station: spaced out, so that the server sees
   * (and counts) each one rather than only the newest. */
  send_request(&bob, a.trainee_station, palp_OP_LEAVE, palp_ROLE_TRAINEE, 0, 0, "bob", 900);
  test_sleep(0.5);
  send_request(&bob, a.trainee_station, palp_OP_JOIN, palp_ROLE_TRAINEE, 1, 0, "alice", 901);
  test_sleep(0.5);
  palp_SessionRequest key;
  memset(&key, 0, sizeof key);
  snprintf(key.station_id, sizeof key.station_id, "%s", a.trainee_station);
  dds_dispose(bob.request_w, &key);
  test_sleep(0.5);
  /* Once the instructor follows his session, try to follow alice's (which, as any
   * new join, would end his own). */
  int64_t until = palp_dds_now_ns() + 20000000000LL;
  int followed = 0;
  while (!followed && palp_dds_now_ns() < until) {
    palp_SessionState buf[8];
    void *ptr[8];
    dds_sample_info_t info[8];
    for (int i = 0; i < 8; i++) ptr[i] = &buf[i];
    int n = dds_read(bob.state_r, ptr, info, 8, 8);
    for (int i = 0; i < n; i++)
      followed |= info[i].valid_data && buf[i].session_id == bob.session_id && buf[i].observer_count >= 1;
    test_sleep(0.05);
  }
  CHECK(followed, "bob's session state shows the instructor following it");
  CHECK(join(&bob, palp_ROLE_OBSERVER, 0, a.session_id, 3, err, sizeof err) < 0 && strstr(err, "another trainee"),
        "bob cannot observe alice's session: %s", err);
  palp_cli_station_leave(&bob);
  test_sleep(0.2);
  palp_cli_station_close(&bob);
}

/* ---- ines: an instructor follows any session, but cannot palpate ---- */
static void child_ines(void) {
  palp_cli_station ines;
  char err[512];
  open_secure(&ines, pki, "instructor/ines", "obs");
  CHECK(join(&ines, palp_ROLE_TRAINEE, 1, 0, 10, err, sizeof err) < 0 && strstr(err, "instructor"),
        "an instructor identity cannot open a trainee session: %s", err);
  palp_SessionState a;
  REQUIRE(find_session(&ines, "alice", 10, &a) == 0, "ines finds alice's session %u", a.session_id);
  REQUIRE(join(&ines, palp_ROLE_OBSERVER, 0, a.session_id, 10, err, sizeof err) == 0,
          "ines joins alice's session %u as observer (%s)", a.session_id, err);
  /* Secured endpoints match only after their crypto tokens are exchanged. */
  int64_t until = palp_dds_now_ns() + 5000000000LL;
  while ((matched_pubs(ines.contact_r) < 1 || matched_pubs(ines.deformation_r) < 1) && palp_dds_now_ns() < until)
    test_sleep(0.05);
  count_samples(ines.contact_r, 0);
  int contacts = count_samples(ines.contact_r, 1.0);
  int frames = count_samples(ines.deformation_r, 0.3);
  CHECK(contacts > 20 && frames > 3, "ines reads alice's contacts (%d in 1 s) and deformation (%d frames)", contacts,
        frames);
  palp_SessionState b;
  REQUIRE(find_session(&ines, "bob", 10, &b) == 0, "ines finds bob's session %u", b.session_id);
  err[0] = 0;
  CHECK(join(&ines, palp_ROLE_OBSERVER, 0, b.session_id, 10, err, sizeof err) == 0,
        "ines follows bob's session %u too (%s)", b.session_id, err);
  /* Stay until bob's session ends (he waits to see her in it). */
  int64_t until2 = palp_dds_now_ns() + 20000000000LL;
  while (!palp_cli_station_session_closed(&ines, NULL, 0) && palp_dds_now_ns() < until2) test_sleep(0.05);
  palp_cli_station_leave(&ines);
  palp_cli_station_close(&ines);
}

/* ---- anon: no credentials at all ---- */
static void child_anon(void) {
  palp_cli_station anon;
  char err[512];
  REQUIRE(palp_cli_station_open(&anon, DOMAIN, "anon", err, sizeof err) == 0, "plain participant: %s", err);
  palp_cli_join j = {.role = palp_ROLE_TRAINEE, .phantom_id = 1, .user_name = "alice", .timeout = 2.5};
  CHECK(palp_cli_station_join(&anon, &j, err, sizeof err) < 0, "an unauthenticated join gets no answer: %s", err);
  int seen = count_samples(anon.catalogue_r, 0.1) + count_samples(anon.state_r, 0.1);
  CHECK(seen == 0 && matched_pubs(anon.catalogue_r) == 0 && matched_pubs(anon.state_r) == 0 &&
            matched_subs(anon.request_w) == 0,
        "it discovers nothing: %d catalogue/state samples, %d + %d matched writers, %d matched readers", seen,
        matched_pubs(anon.catalogue_r), matched_pubs(anon.state_r), matched_subs(anon.request_w));
  /* 5 N into alice's session 1 (the naming rule is public): alice's own check sees if it lands */
  dds_entity_t pub = palp_dds_session_publisher(anon.pp, "palp/s/alice/1");
  palp_cli_station fake = anon;
  fake.contact_w = palp_dds_create_writer(pub, anon.topic[PALP_TOPIC_CONTACT], PALP_TOPIC_CONTACT);
  fake.session_id = 1;
  for (int i = 0; i < 200; i++) {
    test_send_force(&fake, 0, 2, 30, 40, 5.0, 1000000 + (uint64_t)i);
    test_sleep(0.01);
  }
  CHECK(fake.contact_w > 0 && matched_subs(fake.contact_w) == 0,
        "its 200 contacts of 5 N into palp/s/alice/1 reach no reader (%d matched)", matched_subs(fake.contact_w));
  palp_cli_station_close(&anon);
}

/* ---- forged: bob's genuine identity with server rights signed by his own CA ---- */
static void child_forged(void) {
  char forged[1024], err[512];
  snprintf(forged, sizeof forged, "%s-forged", pki);
  palp_dds_security sec;
  REQUIRE(palp_dds_security_init(&sec, forged, "trainee/bob", err, sizeof err) == 0, "forged: %s", err);
  dds_qos_t *q = dds_create_qos();
  palp_dds_security_qos(&sec, q);
  char ca[1100];
  snprintf(ca, sizeof ca, "file:%s/rogue-ca.cert.pem", sec.pki);
  dds_qset_prop(q, "dds.sec.access.permissions_ca", ca);
  dds_entity_t pp = dds_create_participant(DOMAIN, q, NULL);
  dds_delete_qos(q);
  REQUIRE(pp > 0, "the forged participant is created (its own CA vouches for its permissions locally): %s",
          pp < 0 ? dds_strretcode(pp) : "ok");
  /* Cyclone gave it a GUID prefix from bob's certificate (DDS Security 9.3.3); the server names the
   * refused peer by it, so palp's computation must be Cyclone's. */
  char cert[1100], subject[256];
  snprintf(cert, sizeof cert, "%s/trainee/bob.cert.pem", sec.pki);
  dds_guid_t g;
  unsigned char want[6];
  const int got = dds_get_guid(pp, &g) == DDS_RETCODE_OK && palp_pem_guid_prefix(cert, want, subject, sizeof subject) == 0;
  CHECK(got && !memcmp(g.v, want, 6) && !strcmp(subject, "/O=palp/OU=trainee/CN=bob"),
        "its GUID prefix begins %02x%02x%02x%02x:%02x%02x, bob's certificate's subject %s hashes to %02x%02x%02x%02x:%02x%02x",
        g.v[0], g.v[1], g.v[2], g.v[3], g.v[4], g.v[5], subject, want[0], want[1], want[2], want[3], want[4], want[5]);
  dds_entity_t rt = palp_dds_create_topic(pp, PALP_TOPIC_SESSION_REPLY);
  dds_entity_t fw = palp_dds_create_writer(pp, rt, PALP_TOPIC_SESSION_REPLY);
  dds_entity_t ct = palp_dds_create_topic(pp, PALP_TOPIC_SERVER_STATUS);
  dds_entity_t fr = palp_dds_create_reader(pp, ct, PALP_TOPIC_SERVER_STATUS);
  REQUIRE(fw > 0 && fr > 0, "locally it may write replies and read the server status (%d, %d)", fw, fr);
  palp_SessionReply m;
  memset(&m, 0, sizeof m);
  snprintf(m.station_id, sizeof m.station_id, "trainee/alice");
  m.status = palp_REPLY_REJECTED;
  snprintf(m.reason, sizeof m.reason, "forged");
  for (int i = 0; i < 40; i++) {
    m.request_seq = (uint32_t)i;
    dds_write(fw, &m);
    test_sleep(0.05);
  }
  int cat = count_samples(fr, 0.1);
  CHECK(matched_subs(fw) == 0 && cat == 0 && matched_pubs(fr) == 0,
        "the classroom does not accept its permissions: %d readers matched its replies; it read %d status "
        "samples from %d writers", matched_subs(fw), cat, matched_pubs(fr));
  dds_delete(pp);
}

/* ---- thief: bob's certificate and permissions (public files) with a key of the thief's own ---- */
static void child_thief(void) {
  char err[512], key[1100];
  palp_dds_security sec; /* bob's genuine files, for everything but the key */
  REQUIRE(palp_dds_security_init(&sec, pki, "trainee/bob", err, sizeof err) == 0, "thief: %s", err);
  dds_qos_t *q = dds_create_qos();
  palp_dds_security_qos(&sec, q);
  snprintf(key, sizeof key, "file:%s-thief/trainee/bob.key.pem", pki);
  dds_qset_prop(q, "dds.sec.auth.private_key", key);
  dds_entity_t pp = dds_create_participant(DOMAIN, q, NULL);
  dds_delete_qos(q);
  /* Cyclone 0.10.2 does not match the key to the certificate at creation (palp's programs do,
   * idl/palp_dds_security.c): the thief gets as far as the handshake, whose signature exposes it. */
  REQUIRE(pp > 0, "the thief's participant is created: %s", pp < 0 ? dds_strretcode(pp) : "ok");
  dds_entity_t ct = palp_dds_create_topic(pp, PALP_TOPIC_SERVER_STATUS);
  dds_entity_t fr = palp_dds_create_reader(pp, ct, PALP_TOPIC_SERVER_STATUS);
  REQUIRE(fr > 0, "locally it may read the server status (%d)", fr);
  /* Until the server has said why it refused it (the parent makes DIR-thief/done), at most 30 s: which
   * side fails the signature first depends on timing, and a slow run (ThreadSanitizer) restarts
   * attempts whose stale messages fail on their challenges before any signature is checked. */
  char done[1100];
  snprintf(done, sizeof done, "%s-thief/done", pki);
  const int64_t t0 = palp_dds_now_ns();
  int cat = 0;
  while (access(done, F_OK) != 0 && palp_dds_now_ns() - t0 < 30000000000LL) cat += count_samples(fr, 0.2);
  CHECK(cat == 0 && matched_pubs(fr) == 0,
        "the thief, with bob's certificate but not his key, hears nothing from the server in %.1f s: %d status "
        "samples from %d writers", (double)(palp_dds_now_ns() - t0) * 1e-9, cat, matched_pubs(fr));
  dds_delete(pp);
}

/* ---- dave: revoked (in the classroom's CRL) ---- */
static void child_dave(void) {
  char dir[1024], err[512];
  snprintf(dir, sizeof dir, "%s-dave", pki);
  palp_dds_security sec;
  REQUIRE(palp_dds_security_init(&sec, dir, "trainee/dave", err, sizeof err) == 0, "dave: %s", err);
  /* With the classroom's CRL, his participant is not even created... */
  dds_qos_t *q = dds_create_qos();
  palp_dds_security_qos(&sec, q);
  char crl[1100];
  snprintf(crl, sizeof crl, "file:%s/crl.pem", pki);
  dds_qset_prop(q, "org.eclipse.cyclonedds.sec.auth.crl", crl);
  dds_entity_t pp = dds_create_participant(DOMAIN, q, NULL);
  dds_delete_qos(q);
  CHECK(pp < 0, "with the classroom CRL, dave's own participant is refused: %s", pp < 0 ? dds_strretcode(pp) : "created");
  if (pp > 0) dds_delete(pp);
  /* ...and keeping the CRL from before his revocation does not help him: the server checks its own. */
  palp_cli_station dave;
  REQUIRE(palp_cli_station_open_secure(&dave, DOMAIN, "t", &sec, err, sizeof err) == 0,
          "dave's station starts with his own files (the CRL from before his revocation): %s", err);
  CHECK(join(&dave, palp_ROLE_TRAINEE, 1, 0, 3, err, sizeof err) < 0 && count_samples(dave.catalogue_r, 0.1) == 0 &&
            matched_pubs(dave.catalogue_r) == 0,
        "the revoked trainee dave gets no answer and no catalogue: %s", err);
  palp_cli_station_close(&dave);
}

static pid_t spawn(const char *self, const char *role) {
  char *argv[] = {(char *)self, (char *)pki, "child", (char *)role, NULL};
  pid_t pid = 0;
  if (posix_spawn(&pid, self, NULL, NULL, argv, environ) != 0) {
    fprintf(stderr, "cannot start %s %s\n", self, role);
    exit(1);
  }
  return pid;
}

static int wait_child(pid_t pid, const char *role) {
  int status = 0;
  waitpid(pid, &status, 0);
  int ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  CHECK(ok, "process %s passed its checks (exit status %d)", role, WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  return ok;
}

/* The identities a program reads from its PKI directory to name peers refused for their permissions
 * (palp_dds_security_name_peers): a certificate names its subject; a FIFO (which would block a read), a
 * file that is no certificate and a directory are passed over, without blocking the start. */
static void test_name_peers_dir(void) {
  char dir[160], path[256], cmd[1200];
  palp_test_tmp(dir, sizeof dir, "palp-names-XXXXXX");
  REQUIRE(mkdtemp(dir), "temporary directory");
  snprintf(path, sizeof path, "%s/trainee", dir);
  REQUIRE(mkdir(path, 0700) == 0, "%s", path);
  snprintf(cmd, sizeof cmd, "cp '%s/trainee/bob.cert.pem' '%s/trainee/bob.cert.pem' && printf 'junk' > '%s/trainee/junk.cert.pem' "
                            "&& mkfifo '%s/trainee/fifo.cert.pem' && mkdir '%s/trainee/dir.cert.pem'",
           pki, dir, dir, dir, dir);
  REQUIRE(system(cmd) == 0, "%s", cmd);
  palp_dds_security sec = {.kind = PALP_DDS_ID_TRAINEE};
  snprintf(sec.pki, sizeof sec.pki, "%s", dir);
  palp_dds_refusals t;
  palp_dds_refusals_init(&t, NULL, NULL, 60.0);
  const int64_t t0 = palp_dds_now_ns();
  const int n = palp_dds_security_name_peers(&sec, &t);
  unsigned char want[6] = {0};
  snprintf(path, sizeof path, "%s/trainee/bob.cert.pem", dir);
  CHECK(n == 1 && t.n_names == 1 && !strcmp(t.names[0].who, "trainee/bob") &&
            palp_pem_guid_prefix(path, want, NULL, 0) == 0 && !memcmp(t.names[0].prefix, want, 6),
        "one identity named from a directory with a certificate, junk, a FIFO and a directory: %d (%s), %.3f s", n,
        n > 0 ? t.names[0].who : "", (double)(palp_dds_now_ns() - t0) * 1e-9);
  const palp_dds_security plain = {.kind = PALP_DDS_ID_NONE};
  CHECK(palp_dds_security_name_peers(&plain, &t) == 0 && t.n_names == 1, "a plain program reads nothing");
  CHECK(palp_pem_guid_prefix("/nonexistent/x.cert.pem", want, NULL, 0) == -1, "no certificate, no prefix");
  palp_dds_refusals_destroy(&t);
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  CHECK(system(cmd) == 0, "removed %s", dir);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s PKI_DIR\n", argv[0]);
    return 2;
  }
  pki = argv[1];
  test_init();
  if (argc >= 4 && !strcmp(argv[2], "child")) {
    const char *role = argv[3];
    if (!strcmp(role, "alice")) child_alice();
    else if (!strcmp(role, "bob")) child_bob();
    else if (!strcmp(role, "ines")) child_ines();
    else if (!strcmp(role, "anon")) child_anon();
    else if (!strcmp(role, "forged")) child_forged();
    else if (!strcmp(role, "dave")) child_dave();
    else if (!strcmp(role, "thief")) child_thief();
    return palp_test_failures ? 1 : 0;
  }
  test_name_peers_dir();
  palp_srv_config cfg;
  test_config(&cfg, DOMAIN, 100);
  snprintf(cfg.security_pki, sizeof cfg.security_pki, "%s", pki);
  cfg.log_interval = 0.0; /* every refusal on its own line: the count below is explained */
  int64_t t0 = palp_dds_now_ns();
  test_server ts = {0};
  test_server_start(&ts, &cfg);
  pid_t alice = spawn(argv[0], "alice");
  int64_t end = palp_dds_now_ns() + 15000000000LL;
  while (palp_srv_open_sessions(ts.srv) < 1 && palp_dds_now_ns() < end) test_sleep(0.05);
  REQUIRE(palp_srv_open_sessions(ts.srv) == 1, "alice's session is open after %.2f s (server start, handshake, join)",
          (double)(palp_dds_now_ns() - t0) * 1e-9);
  char done[1100];
  snprintf(done, sizeof done, "%s-thief/done", pki);
  unlink(done);
  const char *roles[] = {"bob", "ines", "anon", "forged", "dave", "thief"};
  pid_t pids[6];
  for (int i = 0; i < 6; i++) pids[i] = spawn(argv[0], roles[i]);
  for (int i = 0; i < 5; i++) wait_child(pids[i], roles[i]);
  /* The thief stays until the server has given its reason (or 20 s more), then is told to go. */
  char seen[600];
  for (const int64_t until = palp_dds_now_ns() + 20000000000LL;;) {
    palp_srv_security_refusals(ts.srv, seen, sizeof seen);
    if (strstr(seen, "its handshake is not signed") || palp_dds_now_ns() >= until) break;
    test_sleep(0.1);
  }
  FILE *f = fopen(done, "w");
  REQUIRE(f && fclose(f) == 0, "%s", done);
  wait_child(pids[5], roles[5]);
  wait_child(alice, "alice");
  uint64_t refused = palp_srv_refused_requests(ts.srv);
  /* bob's LEAVE, JOIN and disposal of alice's station, and his JOIN as "alice" */
  CHECK(refused == 4, "the server refused exactly bob's 4 requests that were not his own: %llu",
        (unsigned long long)refused);
  /* A refused participant gets no answer and makes no event: the server names it
   * from Cyclone's warning (idl/palp_dds_refusals.c). dave retried for ~3 s, so at least
   * one refusal each; the forged participant's identity is the classroom's, its
   * permissions are signed by its own CA. The anonymous one leaves no trace (no
   * handshake is attempted with it). */
  char who[600];
  const uint64_t nref = palp_srv_security_refusals(ts.srv, who, sizeof who);
  CHECK(nref >= 1 && strstr(who, "trainee/dave: certificate revoked ("),
        "the server names the revoked trainee dave and why: %llu refusal(s): %s", (unsigned long long)nref, who);
  /* Cyclone names it only by its GUID; the server names it by the identity whose certificate gives
   * that GUID (idl/palp_dds_refusals.c): bob's, whose permissions the forger replaced. */
  const char *forged = strstr(who, "trainee/bob: permissions not signed by the classroom (");
  CHECK(forged && !strstr(who, "participant "),
        "and the forged participant, refused for its permissions, named by the identity it authenticated with: %s", who);
  /* The thief's certificate passes the CA and the CRL; the signature of its handshake does not. Cyclone
   * says "Failed to finalize digest context" and names nobody; the server says what it means. */
  CHECK(strstr(who, "a participant: its handshake is not signed by its certificate's key (someone else's certificate"),
        "and the thief, with bob's certificate and a key of its own, refused for its handshake's signature: %s", who);
  CHECK(!strstr(who, "alice") && !strstr(who, "ines") && forged && !strstr(forged + 11, "bob") &&
            strstr(who, "bob") == forged + 8,
        "nobody else of the classroom is among them: %s", who);
  test_server_stop(&ts);
  fprintf(stderr, "%s (%.1f s)\n", palp_test_failures ? "FAILED" : "passed", (double)(palp_dds_now_ns() - t0) * 1e-9);
  return palp_test_failures ? 1 : 0;
}
