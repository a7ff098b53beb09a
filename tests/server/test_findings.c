/*
 * test_findings.c - issue 13 over real DDS and a real SQLite file (domain 60):
 *  - a server hosting an exercise (tests/server/exercise_wire.json: two lesions hidden in
 *    tests/assess/phantom_stiff.json) publishes its title, instructions and limits, and
 *    nothing a trainee can read carries a lesion: a spy participant subscribed to every
 *    topic and partition a trainee may read captures every sample's serialized bytes and
 *    finds no lesion centre coordinate, radius or depth (as the IEEE double at any byte
 *    offset), no Vec3 within 1e-6 m of a centre and no exercise JSON text, while the
 *    server's log has the lesions;
 *  - findings: mark / withdraw accepted and logged with the world's frame and time; a
 *    forged session id, a NaN point, a point off the phantom, the withdrawal of an
 *    unknown mark, a flood of 1,000 marks and the 65th mark each refused with a reason
 *    (logged as events); another session keeps stepping during the flood;
 *  - finger samples of the position-driven fingertip are logged at assess_sample_hz;
 *  - an exercise's time limit ends its session ("exercise time limit reached", end
 *    reason normal in the log, the station told in the state's reason);
 *  - debriefs: carol's ("lesions") says which of her two marks found which lesion and where
 *    each lesion is; alice's (no "debrief" key: none) carries no lesion value nor count, and the
 *    spy reads it among the rest;
 *  - scores (palp_session_score, session 63): as each exercise session closes the server grades
 *    it from its own log and writes the score for the instructors: alice's (she pressed over
 *    lesion 1 and marked it) 1 of 2 found, no false mark, the very numbers palp-review's reading
 *    of the log gives; carol's (no fingertip: marks only) not graded, and why; bob's free practice
 *    none.
 */
#define _GNU_SOURCE
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>
#include <dds/dds.h>
/* Cyclone's serdata header (for the serialized bytes: ddsi_serdata_to_ser) uses GNU
 * `asm` in its inline atomics, which strict C17 does not know by that name. */
#define asm __asm__
#include <dds/ddsi/ddsi_serdata.h>
#undef asm

#include "assess_log.h"
#include "db_log.h"
#include "findings.h"
#include "harness.h"
#include "palp_assess.h"
#include "palp_db.h"

#define DOMAIN 60
#define EX_WIRE 7
#define EX_SHORT 8
#define PI 3.14159265358979323846

/* ---- the secrets: what must never reach a trainee ------------------------------ */
static double secret[64];
static int nsecret;
static palp_vec3 centre[PALP_MAX_LESIONS];
static int ncentre;

static void add_secret(double v) {
  secret[nsecret++] = v;
}

/* ---- the spy: every topic and partition a trainee may read ---------------------- */
#define SPY_MAX 32
typedef struct spy {
  dds_entity_t pp, sub_default, sub_session;
  dds_entity_t topic[PALP_TOPIC_COUNT];
  dds_entity_t r[SPY_MAX];
  int kind[SPY_MAX];
  int n;
  pthread_mutex_t mu;
  uint64_t samples[PALP_TOPIC_COUNT];
  uint64_t bytes;
  int leaks;
  char leak[256];
  atomic_int stop;
  pthread_t thread;
} spy;

static void spy_reader(spy *s, dds_entity_t sub, palp_dds_topic_kind k) {
  pthread_mutex_lock(&s->mu);
  s->r[s->n] = palp_dds_create_reader(sub, s->topic[k], k);
  REQUIRE(s->r[s->n] > 0, "spy reader on %s", palp_dds_topic_name(k));
  s->kind[s->n++] = (int)k;
  pthread_mutex_unlock(&s->mu);
}

static void scan(spy *s, int kind, const unsigned char *b, size_t n) {
  s->bytes += n;
  for (size_t k = 0; k + 8 <= n; k++)
    for (int j = 0; j < nsecret; j++)
      if (memcmp(b + k, &secret[j], 8) == 0 && !s->leaks++)
        snprintf(s->leak, sizeof s->leak, "%s: the double %.17g at byte %zu", palp_dds_topic_name(kind), secret[j], k);
  /* Vec3 fields: XCDR1 aligns doubles to 8 after the 4-byte encapsulation header; a
   * stride of 4 covers either alignment. */
  for (size_t k = 4; k + 24 <= n; k += 4) {
    double v[3];
    memcpy(v, b + k, sizeof v);
    for (int j = 0; j < ncentre; j++)
      if (fabs(v[0] - centre[j].x) < 1e-6 && fabs(v[1] - centre[j].y) < 1e-6 && fabs(v[2] - centre[j].z) < 1e-6 &&
          !s->leaks++)
        snprintf(s->leak, sizeof s->leak, "%s: a Vec3 within 1e-6 m of lesion %d's centre at byte %zu",
                 palp_dds_topic_name(kind), j, k);
  }
  static const char *const text[] = {"lesion", "polar_deg", "stiffness_ratio", "depth_mm"};
  for (int j = 0; j < 4; j++)
    if (memmem(b, n, text[j], strlen(text[j])) && !s->leaks++)
      snprintf(s->leak, sizeof s->leak, "%s: the text \"%s\"", palp_dds_topic_name(kind), text[j]);
}

static void spy_poll(spy *s) {
  pthread_mutex_lock(&s->mu);
  for (int i = 0; i < s->n; i++) {
    struct ddsi_serdata *sd[16];
    dds_sample_info_t si[16];
    int got;
    while ((got = dds_takecdr(s->r[i], sd, 16, si, DDS_ANY_STATE)) > 0) {
      for (int k = 0; k < got; k++) {
        const uint32_t sz = ddsi_serdata_size(sd[k]);
        unsigned char *buf = malloc(sz ? sz : 1);
        if (buf) {
          ddsi_serdata_to_ser(sd[k], 0, sz, buf);
          scan(s, s->kind[i], buf, sz);
          free(buf);
        }
        if (si[k].valid_data) s->samples[s->kind[i]]++;
        ddsi_serdata_unref(sd[k]);
      }
      if (got < 16) break;
    }
  }
  pthread_mutex_unlock(&s->mu);
}

static void *spy_main(void *arg) {
  spy *s = arg;
  while (!atomic_load(&s->stop)) {
    spy_poll(s);
    test_sleep(0.003);
  }
  spy_poll(s);
  return NULL;
}

static void spy_start(spy *s) {
  memset(s, 0, sizeof *s);
  pthread_mutex_init(&s->mu, NULL);
  s->pp = dds_create_participant(DOMAIN, NULL, NULL);
  REQUIRE(s->pp > 0, "spy participant");
  for (int k = 0; k < PALP_TOPIC_COUNT; k++) s->topic[k] = palp_dds_create_topic(s->pp, (palp_dds_topic_kind)k);
  s->sub_default = dds_create_subscriber(s->pp, NULL, NULL);
  /* What a trainee's permissions let it read in the default partition (make-classroom-pki.sh). */
  const palp_dds_topic_kind global[] = {PALP_TOPIC_CATALOGUE, PALP_TOPIC_SESSION_REPLY, PALP_TOPIC_SESSION_STATE,
                                        PALP_TOPIC_SERVER_STATUS, PALP_TOPIC_SERVER_GUARD,
                                        PALP_TOPIC_SERVER_IDENTITY, PALP_TOPIC_EXERCISE};
  for (size_t i = 0; i < sizeof global / sizeof global[0]; i++) spy_reader(s, s->sub_default, global[i]);
  REQUIRE(pthread_create(&s->thread, NULL, spy_main, s) == 0, "spy thread");
}

/* ... and in its own session partition. */
static void spy_session(spy *s, const char *partition) {
  s->sub_session = palp_dds_session_subscriber(s->pp, partition);
  const palp_dds_topic_kind sess[] = {PALP_TOPIC_CONTACT,     PALP_TOPIC_FEEDBACK, PALP_TOPIC_DEFORMATION,
                                      PALP_TOPIC_LOCAL_MODEL, PALP_TOPIC_FINDING,  PALP_TOPIC_FINDING_STATUS,
                                      PALP_TOPIC_DEBRIEF,     PALP_TOPIC_DEBRIEF_SCORE};
  for (size_t i = 0; i < sizeof sess / sizeof sess[0]; i++) spy_reader(s, s->sub_session, sess[i]);
}

/* ---- findings over DDS ------------------------------------------------------------ */
typedef struct trainee_findings {
  dds_entity_t w, r;
  uint32_t session_id;
} trainee_findings;

static void send_finding(trainee_findings *t, int op, uint32_t mark, uint32_t session, palp_vec3 p) {
  palp_Finding f;
  memset(&f, 0, sizeof f);
  f.session_id = session;
  f.mark_id = mark;
  f.op = (palp_FindingOp)op;
  f.point = (palp_Vec3){p.x, p.y, p.z};
  f.time = 0;
  dds_write(t->w, &f);
}

/* The status answering `mark` (the newest one), within `wait` [s]; 1 when it came. */
static int wait_status(trainee_findings *t, uint32_t mark, double wait, palp_FindingStatus *out) {
  const int64_t end = palp_dds_now_ns() + (int64_t)(wait * 1e9);
  int got = 0;
  while (palp_dds_now_ns() < end) {
    palp_FindingStatus st;
    memset(&st, 0, sizeof st);
    void *ptr[1] = {&st};
    dds_sample_info_t info;
    while (dds_take(t->r, ptr, &info, 1, 1) > 0)
      if (info.valid_data && st.last_mark_id == mark) *out = st, got = 1;
    if (got) return 1;
    test_sleep(0.005);
  }
  return 0;
}

static palp_vec3 dome_point(double R, double polar_deg, double az_deg) {
  const double p = polar_deg * PI / 180, a = az_deg * PI / 180;
  return (palp_vec3){R * sin(p) * cos(a), R * sin(p) * sin(a), R * cos(p)};
}


/* The newest feedback frame of a station within wait [s], or -1. */
static int64_t latest_frame(palp_cli_station *st, double wait) {
  const int64_t end = palp_dds_now_ns() + (int64_t)(wait * 1e9);
  int64_t frame = -1;
  while (palp_dds_now_ns() < end) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    while (dds_take(st->feedback_r, ptr, &info, 1, 1) > 0) {
      if (info.valid_data) frame = (int64_t)((const palp_Feedback *)ptr[0])->frame;
      dds_return_loan(st->feedback_r, ptr, 1);
    }
    if (frame >= 0) return frame;
    test_sleep(0.005);
  }
  return frame;
}

/* ---- the log ------------------------------------------------------------------------- */
typedef struct log_findings {
  int marks, withdrawals, bad_order;
  int64_t last_frame;
  palp_db_finding first;
} log_findings;

static int on_log_finding(void *user, const palp_db_finding *f) {
  log_findings *l = user;
  if (l->marks + l->withdrawals == 0) l->first = *f;
  if (f->frame < l->last_frame) l->bad_order++;
  l->last_frame = f->frame;
  if (f->op == PALP_DB_FINDING_MARK) l->marks++;
  if (f->op == PALP_DB_FINDING_WITHDRAW) l->withdrawals++;
  return 0;
}

typedef struct log_samples {
  int n, touching, with_triangles, bad_radius;
  int64_t first_frame, last_frame, min_gap, max_gap, prev;
} log_samples;

static int on_log_sample(void *user, const palp_db_finger_sample *s) {
  log_samples *l = user;
  if (l->n == 0) l->first_frame = s->frame, l->min_gap = INT64_MAX;
  else {
    const int64_t g = s->frame - l->prev;
    if (g < l->min_gap) l->min_gap = g;
    if (g > l->max_gap) l->max_gap = g;
  }
  l->prev = l->last_frame = s->frame;
  l->n++;
  l->touching += s->in_contact;
  l->with_triangles += s->triangle_count > 0;
  l->bad_radius += fabs(s->radius_m - 0.008) > 1e-12;
  return 0;
}

typedef struct log_events {
  int forged, nan, unknown, off, flood, cap;
} log_events;

static int on_log_event(void *user, double wall, int64_t frame, const char *kind, const char *detail,
                        int64_t count) {
  (void)wall, (void)frame, (void)kind;
  log_events *l = user;
  if (!detail || !strstr(detail, "finding")) return 0;
  if (strstr(detail, "names session")) l->forged++;
  if (strstr(detail, "not finite")) l->nan++;
  if (strstr(detail, "not standing")) l->unknown++;
  if (strstr(detail, "not on the phantom")) l->off++;
  if (strstr(detail, "too many findings") || strstr(detail, "not logged one by one")) l->flood += (int)count;
  if (strstr(detail, "at most 64")) l->cap++;
  return 0;
}



/* Unit cases of where a mark may lie (server/findings.c, session 81 review): a mark is the fingertip's
 * contact point, on the skin or pressed into it. On the 40 mm dome with the shipped bands (deep
 * 9-18 mm) a mark may lie 18 + 1 = 19 mm under the rest skin and 5 mm above it, z >= 0. At polar 30
 * deg, azimuth 0, a point at distance q from the base's centre is q (sin 30, 0, cos 30). Before, a
 * box grown by 30 mm took q = 20 mm (20 under) and q = 64 mm (24 above: (32, 0, 55.4) mm, inside
 * +-70 mm). */
static void offer_cases(void) {
  static const char *json =
      "{\"name\": \"u\", \"title\": \"U\", \"phantom\": \"p.json\", \"instructions\": \"go\", \"time_limit_s\": 60,"
      " \"lesions\": [], \"pressure_bands\": {\"light\": {\"depth_mm\": [1, 4]}, \"medium\": {\"depth_mm\": [4, 9]},"
      " \"deep\": {\"depth_mm\": [9, 18]}}, \"max_force_N\": 15, \"rubric\": {\"weights\": {\"sensitivity\": 1},"
      " \"pass\": {\"sensitivity\": 1, \"coverage\": {\"light\": 0.5, \"medium\": 0.5, \"deep\": 0.5}, \"score\": 50}}}";
  palp_exercise ex;
  char err[256];
  REQUIRE(palp_exercise_parse(json, "", &ex, err, sizeof err) == 0, "unit exercise: %s", err);
  const double dmax = palp_srv_findings_depth_max(&ex);
  CHECK(fabs(dmax - 0.019) < 1e-12, "depth bound: the deep band's 18 mm + 1 = 19 mm (%.6f m)", dmax);
  CHECK(fabs(palp_srv_findings_depth_max(NULL) - 0.023) < 1e-12, "no exercise: 23 mm");
  palp_srv_findings f;
  const palp_srv_findings_limits lim = {.session_id = 7, .dome_radius = 0.04, .depth_max = dmax,
                                        .height_max = PALP_SRV_MARK_HEIGHT, .rate = 5, .burst = 10};
  palp_srv_findings_init(&f, &lim);
  const double s30 = 0.5, c30 = sqrt(3.0) / 2.0;
  static const struct {
    double q_mm, z_override; /* distance from the base's centre at polar 30; z_override != 0: that point instead */
    int accepted;
    const char *why;
  } cases[] = {{40, 0, 1, NULL}, {22, 0, 1, NULL}, {21.5, 0, 1, NULL}, {44.5, 0, 1, NULL},
               {20, 0, 0, "20.0 mm under its skin (at most 19.0)"}, {64, 0, 0, "24.0 mm above its skin (at most 5.0)"},
               {40, -1, 0, "below its base"}};
  int64_t t = 1000000000;
  for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
    const double q = cases[k].q_mm * 1e-3;
    palp_vec3 p = {q * s30, 0, q * c30};
    if (cases[k].z_override) p = (palp_vec3){0.0399, 0, -0.001}; /* 39.9 mm from the centre, 1 mm under the base */
    const palp_Finding in = {.session_id = 7, .mark_id = (uint32_t)(k + 1), .op = palp_FINDING_MARK, .point = {p.x, p.y, p.z}};
    const int got = palp_srv_findings_offer(&f, &in, t += 300000000);
    printf("mark at (%.1f, %.1f, %.1f) mm: %s %s\n", p.x * 1e3, p.y * 1e3, p.z * 1e3, got ? "accepted" : "refused", f.reason);
    CHECK(got == cases[k].accepted && (!cases[k].why || (strstr(f.reason, "is not on the phantom") && strstr(f.reason, cases[k].why))),
          "mark %zu (%g mm from the base's centre): %s, want %s%s%s", k + 1, cases[k].q_mm, got ? "accepted" : f.reason,
          cases[k].accepted ? "accepted" : "refused: ", cases[k].why ? cases[k].why : "", "");
  }
  /* session 90's review: a mark made after the exercise's time limit (its model's world time past it) is
   * refused, one made at the limit accepted; the session closes up to a main-loop pass after its limit
   * and drains its marks at the close, and a late one counted in the debrief and grade before */
  palp_srv_findings_limits timed = lim;
  timed.time_limit = ex.time_limit; /* 60 s */
  palp_srv_findings g;
  palp_srv_findings_init(&g, &timed);
  const palp_vec3 on = {0.040 * s30, 0, 0.040 * c30};
  const palp_Finding at_limit = {.session_id = 7, .mark_id = 1, .op = palp_FINDING_MARK, .point = {on.x, on.y, on.z},
                                 .time = 60.0};
  const palp_Finding after = {.session_id = 7, .mark_id = 2, .op = palp_FINDING_MARK, .point = {on.x, on.y, on.z},
                              .time = 60.05};
  const int in_time = palp_srv_findings_offer(&g, &at_limit, t += 300000000);
  const int late = palp_srv_findings_offer(&g, &after, t += 300000000);
  CHECK(fabs(ex.time_limit - 60.0) < 1e-12 && in_time == 1 && late == 0 &&
            strstr(g.reason, "mark 2: made at 60.05 s of the session, after its 60 s time limit") && g.marks == 1,
        "time limit 60 s: a mark made at 60.00 s accepted, one at 60.05 s refused (\"%s\"), 1 standing", g.reason);
}

int main(void) {
  test_init();
  offer_cases();
  const int64_t t_start = palp_dds_now_ns();
  /* The secrets, as the server computes them from the exercise file. */
  palp_exercise ex;
  char err[512];
  REQUIRE(palp_exercise_load(PALP_TEST_DIR "/exercise_wire.json", &ex, err, sizeof err) == 0, "exercise: %s", err);
  palp_lesion les[PALP_MAX_LESIONS];
  ncentre = palp_exercise_lesions(&ex, 0.04, les, PALP_MAX_LESIONS, err, sizeof err);
  REQUIRE(ncentre == 2, "two lesions (%s)", err);
  for (int i = 0; i < ncentre; i++) {
    centre[i] = les[i].center;
    add_secret(les[i].center.x), add_secret(les[i].center.y), add_secret(les[i].center.z);
    add_secret(les[i].radius);
    add_secret(ex.lesion[i].depth), add_secret(ex.lesion[i].diameter);
    add_secret(ex.lesion[i].polar), add_secret(ex.lesion[i].azimuth);
  }

  { /* The scan itself finds a leak when there is one: a Vec3 at the centre, and a radius. */
    spy ctl;
    memset(&ctl, 0, sizeof ctl);
    unsigned char buf[64] = {0};
    const double v[3] = {centre[1].x, centre[1].y, centre[1].z};
    memcpy(buf + 12, v, sizeof v);
    scan(&ctl, PALP_TOPIC_LOCAL_MODEL, buf, sizeof buf);
    const int vec = ctl.leaks;
    memset(buf, 0, sizeof buf);
    memcpy(buf + 21, &les[0].radius, 8);
    ctl.leaks = 0;
    scan(&ctl, PALP_TOPIC_LOCAL_MODEL, buf, sizeof buf);
    CHECK(vec > 0 && ctl.leaks > 0, "control: the scan catches a planted centre (%d hits) and radius (%d)", vec,
          ctl.leaks);
  }
  char cwd[512], db_path[700];
  REQUIRE(getcwd(cwd, sizeof cwd) != NULL, "cwd");
  snprintf(db_path, sizeof db_path, "%s/server_findings.db", cwd);
  unlink(db_path);
  char json[2048];
  snprintf(json, sizeof json,
           "{\"domain_id\": %d, \"tick_rate_hz\": 100, \"tick_threads\": 1, \"max_force\": 20,"
           " \"session_exercise\": \"always\","
           " \"phantoms\": [{\"id\": 1, \"name\": \"test dome\", \"scene\": \"paper_step.json\"}],"
           " \"exercises\": [{\"id\": %d, \"file\": \"%s/exercise_wire.json\", \"physics_rate_hz\": 250},"
           "                 {\"id\": %d, \"file\": \"%s/exercise_short.json\", \"physics_rate_hz\": 250}]}",
           DOMAIN, EX_WIRE, PALP_TEST_DIR, EX_SHORT, PALP_TEST_DIR);
  palp_srv_config cfg;
  REQUIRE(palp_srv_config_parse(json, PALP_CONFIG_DIR, &cfg, err, sizeof err) == 0, "config: %s", err);
  CHECK(cfg.phantom_count == 3 && cfg.exercise_count == 2, "config: 1 phantom + 2 exercises hosted");
  palp_srv_db_log *dbl = NULL;
  REQUIRE(palp_srv_db_log_open(db_path, 0, NULL, &dbl, err, sizeof err) == 0, "log: %s", err);
  palp_srv_def def = {.cfg = cfg, .events = palp_srv_db_log_events(dbl), .verbose = 0};
  test_server ts;
  test_server_start_def(&ts, &def);

  spy sp;
  spy_start(&sp);
  /* An instructor's reader of the scores, in the default partition (an instructor's permissions). */
  const dds_entity_t ipp = dds_create_participant(DOMAIN, NULL, NULL);
  REQUIRE(ipp > 0, "instructor participant");
  const dds_entity_t score_r = palp_dds_create_reader(
      ipp, palp_dds_create_topic(ipp, PALP_TOPIC_SESSION_SCORE), PALP_TOPIC_SESSION_SCORE);
  REQUIRE(score_r > 0, "score reader");

  /* ---- the trainee on the exercise ---- */
  palp_cli_station a;
  test_station_join(&a, DOMAIN, "alice", palp_ROLE_TRAINEE, EX_WIRE, 0, 1, 1);
  spy_session(&sp, a.partition);
  palp_Phantom ph;
  REQUIRE(palp_cli_station_catalogue(&a, EX_WIRE, 5, &ph, err, sizeof err) == 0, "catalogue: %s", err);
  CHECK(strcmp(ph.name, ex.title) == 0, "the exercise's catalogue entry is named by its title (\"%s\")", ph.name);
  CHECK(ph.rest._length == 338, "and carries the phantom's rest mesh (%u vertices)", ph.rest._length);
  palp_cli_phantom_free(&ph);
  {
    dds_entity_t er = palp_dds_create_reader(a.pp, a.topic[PALP_TOPIC_EXERCISE], PALP_TOPIC_EXERCISE);
    palp_Exercise e;
    int got = 0;
    for (int k = 0; k < 200 && !got; k++) {
      memset(&e, 0, sizeof e);
      void *ptr[1] = {&e};
      dds_sample_info_t info;
      while (!got && dds_take(er, ptr, &info, 1, 1) > 0) got = info.valid_data && e.phantom_id == EX_WIRE;
      if (!got) test_sleep(0.02);
    }
    CHECK(got, "the trainee reads palp_exercise for phantom %d", EX_WIRE);
    CHECK(got && strcmp(e.name, "test-wire") == 0 && strcmp(e.title, ex.title) == 0 &&
              strcmp(e.instructions, ex.instructions) == 0 && e.time_limit == 120 && e.max_force == 20,
          "  with its name, title, instructions, time limit 120 s and max force 20 N");
    CHECK(got && e.bands[1].has_depth && fabs(e.bands[1].depth_min - 0.005) < 1e-12 &&
              fabs(e.bands[1].depth_max - 0.012) < 1e-12,
          "  and its pressure bands (medium 5-12 mm)");
    dds_delete(er);
  }

  /* ---- a second trainee on a plain phantom, pressing all along ---- */
  palp_cli_station b;
  test_station_join(&b, DOMAIN, "bob", palp_ROLE_TRAINEE, 1, 0, 1, 0);
  test_send_force(&b, 0, 1, 0, 0, 2.0, 1);

  /* ---- alice palpates over lesion 1 (position-driven fingertip) ---- */
  uint64_t seq = 1;
  for (int k = 0; k <= 60; k++) { /* down to 12 mm over 0.6 s, then hold 0.6 s */
    test_send_finger(&a, 31, 41, k <= 30 ? 0.012 * k / 30.0 : 0.012, seq++);
    test_sleep(0.02);
  }

  trainee_findings tf = {.session_id = a.session_id};
  tf.w = palp_dds_create_writer(a.pub, a.topic[PALP_TOPIC_FINDING], PALP_TOPIC_FINDING);
  tf.r = palp_dds_create_reader(a.sub, a.topic[PALP_TOPIC_FINDING_STATUS], PALP_TOPIC_FINDING_STATUS);
  REQUIRE(tf.w > 0 && tf.r > 0, "finding writer and status reader");
  test_sleep(0.3); /* matched */
  palp_FindingStatus st;
  const palp_vec3 p1 = dome_point(0.04, 31, 41);
  send_finding(&tf, palp_FINDING_MARK, 1, a.session_id, p1);
  CHECK(wait_status(&tf, 1, 3, &st) && st.last_accepted && st.marks == 1 && st.reason[0] == 0,
        "mark 1 accepted (marks %u, reason \"%s\")", st.marks, st.reason);
  CHECK(st.time_left > 100 && st.time_left <= 120, "status: %.1f s left of the 120 s limit", st.time_left);
  send_finding(&tf, palp_FINDING_MARK, 2, a.session_id, dome_point(0.04, 0, 0));
  CHECK(wait_status(&tf, 2, 3, &st) && st.last_accepted && st.marks == 2, "mark 2 accepted (marks %u)", st.marks);
  send_finding(&tf, palp_FINDING_WITHDRAW, 2, a.session_id, (palp_vec3){0, 0, 0});
  test_sleep(0.05);
  CHECK(wait_status(&tf, 2, 3, &st) && st.last_accepted && st.marks == 1, "mark 2 withdrawn (marks %u)", st.marks);
  /* Since session 72 a finding naming another session is dropped by the reader's filter (made-up
   * session ids were instances of a reader whose limits stalled the server's delivery): not answered,
   * logged (the events below). */
  send_finding(&tf, palp_FINDING_MARK, 3, a.session_id + 1000, p1);
  CHECK(!wait_status(&tf, 3, 1, &st), "forged session id dropped at the reader: no answer within 1 s");
  send_finding(&tf, palp_FINDING_MARK, 4, a.session_id, (palp_vec3){NAN, 0, 0.04});
  CHECK(wait_status(&tf, 4, 3, &st) && !st.last_accepted && strstr(st.reason, "not finite"),
        "NaN point refused: \"%s\"", st.reason);
  send_finding(&tf, palp_FINDING_WITHDRAW, 99, a.session_id, (palp_vec3){0, 0, 0});
  CHECK(wait_status(&tf, 99, 3, &st) && !st.last_accepted && strstr(st.reason, "not standing"),
        "withdrawal of an unknown mark refused: \"%s\"", st.reason);
  send_finding(&tf, palp_FINDING_MARK, 5, a.session_id, (palp_vec3){1, 1, 1});
  CHECK(wait_status(&tf, 5, 3, &st) && !st.last_accepted && strstr(st.reason, "not on the phantom"),
        "a point 1.7 m away refused: \"%s\"", st.reason);
  CHECK(st.marks == 1, "refusals leave the marks standing (%u)", st.marks);

  /* ---- a flood of 1,000 marks; bob's session keeps stepping ---- */
  test_sleep(1.5); /* the bucket refills */
  const int64_t f0 = latest_frame(&b, 2);
  const int64_t t0 = palp_dds_now_ns();
  int written = 0;
  for (uint32_t id = 1000; id < 2000; id++) {
    palp_Finding f = {.session_id = a.session_id, .mark_id = id, .op = palp_FINDING_MARK,
                      .point = {p1.x, p1.y, p1.z}};
    written += dds_write(tf.w, &f) == DDS_RETCODE_OK;
  }
  CHECK(wait_status(&tf, 1999, 10, &st), "the flood's last mark answered");
  const double flood_s = (double)(palp_dds_now_ns() - t0) * 1e-9;
  test_sleep(1.0); /* and a second after it: a backlog would show as missing frames */
  const int64_t f1 = latest_frame(&b, 2);
  const double frames = (double)(f1 - f0), expect = 100.0 * (double)(palp_dds_now_ns() - t0) * 1e-9;
  CHECK(written == 1000, "1,000 marks written (%d) in %.2f s", written, flood_s);
  CHECK(!st.last_accepted && strstr(st.reason, "too many findings"), "the flood refused: \"%s\"", st.reason);
  const int flood_accepted = (int)st.marks - 1;
  CHECK(flood_accepted >= 1 && flood_accepted <= 10 + (int)ceil(5 * flood_s) + 1,
        "flood: %d accepted (burst 10 + 5/s over %.2f s), %d refused", flood_accepted, flood_s,
        1000 - flood_accepted);
  /* The findings are handled on the main thread, not the tick: a flood that held the tick
   * would show as ~0 frames. 50 %, not more: without SCHED_FIFO on this shared 2-core VM
   * (load average 20-40 during these runs) 77-99 % was measured, the machine at fault. */
  CHECK(frames >= 0.5 * expect, "bob's session stepped %.0f frames of %.0f (100 Hz) during the flood and 1 s after",
        frames, expect);

  /* ---- up to the 64th mark, then the 65th ---- */
  int made = 2 + flood_accepted, paced_ok = 1;
  test_sleep(1.0);
  for (uint32_t id = 3000; made < 64; id++) {
    send_finding(&tf, palp_FINDING_MARK, id, a.session_id, p1);
    if (!wait_status(&tf, id, 5, &st) || !st.last_accepted) {
      paced_ok = 0;
      fprintf(stderr, "mark %u: %s\n", id, st.reason);
      break;
    }
    made++;
    test_sleep(0.2);
  }
  CHECK(paced_ok && made == 64, "marks up to 64 accepted at 5/s (%d made, %u standing)", made, st.marks);
  test_sleep(0.25);
  send_finding(&tf, palp_FINDING_MARK, 5000, a.session_id, p1);
  CHECK(wait_status(&tf, 5000, 3, &st) && !st.last_accepted && strstr(st.reason, "at most 64"),
        "the 65th mark refused: \"%s\"", st.reason);
  CHECK(st.marks == 63, "63 standing (64 made, 1 withdrawn): %u", st.marks);

  /* ---- the time limit ---- */
  palp_cli_station c;
  test_station_join(&c, DOMAIN, "carol", palp_ROLE_TRAINEE, EX_SHORT, 0, 1, 0);
  const int64_t tj = palp_dds_now_ns(); /* the join answered: the session is open */
  /* carol marks over lesion 1 (polar 31, azimuth 41: the surface above its centre) and 20 mm
   * from the pole's other side, near neither: her debrief must say 1 of 2, mark 2 near none. */
  const int c1 = palp_cli_station_mark(&c, dome_point(0.04, 31, 41), 0.1);
  const int c2 = palp_cli_station_mark(&c, dome_point(0.04, 60, 130), 0.2);
  CHECK(c1 == 1 && c2 == 2, "carol's marks sent (ids %d, %d)", c1, c2);
  char reason[160] = "";
  int closed = 0;
  while (!closed && palp_dds_now_ns() - tj < (int64_t)6e9) {
    closed = palp_cli_station_session_closed(&c, reason, sizeof reason) == 1;
    if (!closed) test_sleep(0.02);
  }
  const double limit_s = (double)(palp_dds_now_ns() - tj) * 1e-9;
  CHECK(closed && strcmp(reason, "exercise time limit reached") == 0,
        "the 2 s exercise closed %.2f s after the join was answered: \"%s\"", limit_s, reason);
  /* Up to 1.5 s late: the main loop checks every 100 ms, and a loaded machine (load average
   * 20-40 seen here) delays the state's delivery. */
  CHECK(limit_s >= 1.8 && limit_s <= 3.5, "  within [1.8, 3.5] s of the join");
  const uint32_t carol_session = c.session_id;

  /* ---- debriefs (palp_debrief, docs/assessment.md "Debrief") ----
   * carol's exercise ("debrief": "lesions") tells her what her marks found and where each lesion
   * is: the surface above its centre, palp_exercise_lesion_surface of the file's angles, here
   * computed from the test's own copy of them (polar 31 / 52, azimuth 41 / 217 on R = 40 mm). */
  {
    palp_Debrief d;
    palp_DebriefLesion dl[PALP_DEBRIEF_MAX_LESIONS];
    char derr[160] = "";
    const int got = palp_cli_station_debrief(&c, 3.0, &d, dl, derr, sizeof derr);
    CHECK(got == 1, "carol's debrief came after her time limit (%d %s)", got, derr);
    CHECK(got == 1 && d.level == palp_DEBRIEF_LESIONS && d.lesions == 2 && d.found == 1 && d.marks == 2 &&
              d.false_marks == 1 && d.duplicates == 0,
          "  1 of 2 lesions found, 2 marks standing, 1 near no lesion (level %d, %u of %u, marks %u, false %u, dup %u)",
          got == 1 ? (int)d.level : -1, d.found, d.lesions, d.marks, d.false_marks, d.duplicates);
    CHECK(got == 1 && strcmp(d.reason, "exercise time limit reached") == 0, "  the reason: \"%s\"", d.reason);
    const double pol[2] = {31, 52}, az[2] = {41, 217};
    for (int l = 0; l < 2 && got == 1 && d.lesion._length == 2; l++) {
      const palp_vec3 e = dome_point(0.04, pol[l], az[l]);
      const double err_m = hypot(hypot(dl[l].point.x - e.x, dl[l].point.y - e.y), dl[l].point.z - e.z);
      CHECK(err_m < 1e-9, "  lesion %d at the surface above its centre (off by %.1e m, tolerance 1e-9)", l + 1, err_m);
    }
    CHECK(got == 1 && d.lesion._length == 2 && dl[0].found_by == 1 && dl[1].found_by == 0 &&
              fabs(dl[0].depth - 0.0103) < 1e-12 && fabs(dl[1].diameter - 0.0106) < 1e-12,
          "  lesion 1 found by mark 1, lesion 2 missed; depth 10.3 mm, diameter 10.6 mm as the file says");
  }

  palp_cli_station_leave(&a);
  palp_cli_station_leave(&b);
  /* alice's exercise says nothing ("debrief" absent: none): her debrief comes, with her marks
   * standing and not one lesion, nor how many (the spy below checks its bytes too). */
  {
    palp_Debrief d;
    palp_DebriefLesion dl[PALP_DEBRIEF_MAX_LESIONS];
    char derr[160] = "";
    const int got = palp_cli_station_debrief(&a, 3.0, &d, dl, derr, sizeof derr);
    CHECK(got == 1 && d.level == palp_DEBRIEF_NONE && d.marks == 63 && d.lesions == 0 && d.found == 0 &&
              d.false_marks == 0 && d.lesion._length == 0,
          "alice's debrief tells nothing of the lesions (got %d, level %d, marks %u, lesions %u, found %u, listed %u)",
          got, got == 1 ? (int)d.level : -1, d.marks, d.lesions, d.found, d.lesion._length);
  }
  /* ---- scores (palp_session_score): alice's and carol's, not bob's ---- */
  palp_SessionScore score_a, score_c;
  int got_a = 0, got_c = 0, got_other = 0;
  for (int k = 0; k < 500 && !(got_a && got_c); k++) { /* up to 10 s: the log's writer, then the grading */
    palp_SessionScore m;
    void *ptr[1] = {&m};
    dds_sample_info_t info;
    while (dds_take(score_r, ptr, &info, 1, 1) > 0) {
      if (!info.valid_data) continue;
      if (m.session_id == a.session_id) score_a = m, got_a = 1;
      else if (m.session_id == carol_session) score_c = m, got_c = 1;
      else got_other++;
    }
    if (!(got_a && got_c)) test_sleep(0.02);
  }
  CHECK(got_a && score_a.status == palp_SCORE_GRADED && strcmp(score_a.exercise_name, "test-wire") == 0 &&
            palp_dds_session_score_ok(&score_a),
        "alice's session scored for the instructors (got %d, status %d, exercise \"%s\")", got_a,
        got_a ? (int)score_a.status : -1, got_a ? score_a.exercise_name : "");
  CHECK(got_a && score_a.lesions == 2 && score_a.found == 1 && score_a.false_marks == 0 && score_a.samples > 100,
        "  1 of 2 lesions found (mark 1 over lesion 1), no false mark (mark 2 withdrawn), %u finger samples",
        got_a ? score_a.samples : 0);
  CHECK(got_c && score_c.status == palp_SCORE_NOT_GRADED && strstr(score_c.reason, "no finger samples"),
        "carol's (marks, no fingertip) not graded, and why: \"%s\"", got_c ? score_c.reason : "");
  test_sleep(0.5);
  {
    palp_SessionScore m;
    void *ptr[1] = {&m};
    dds_sample_info_t info;
    while (dds_take(score_r, ptr, &info, 1, 1) > 0) got_other += info.valid_data;
  }
  CHECK(got_other == 0, "no score for bob's free practice, nor any other (%d)", got_other);
  /* ---- the trainee's own score (palp_debrief_score, session 64): carol's exercise told her the
   * lesions (a practice exercise), so her station is told her score as well, the instructors' one
   * (here not graded, and why); alice's (debrief none: an examination) is never sent to hers, though
   * the instructors have had it for 0.5 s. */
  {
    palp_SessionScore m;
    char serr[160] = "";
    const int got = palp_cli_station_debrief_score(&c, 5.0, &m, serr, sizeof serr);
    CHECK(got == 1 && got_c && m.session_id == carol_session && m.status == palp_SCORE_NOT_GRADED &&
              strcmp(m.reason, score_c.reason) == 0 && strcmp(m.log_uid, score_c.log_uid) == 0 &&
              strcmp(m.exercise_name, score_c.exercise_name) == 0,
          "carol's station is told her score as the instructors are: not graded, \"%s\" (got %d %s)",
          got == 1 ? m.reason : "", got, serr);
    const int got_alice = palp_cli_station_debrief_score(&a, 0.5, &m, serr, sizeof serr);
    CHECK(got_alice == 0 && got_a, "alice's station is told no score (her exercise's debrief is none): got %d",
          got_alice);
  }
  dds_delete(ipp);
  atomic_store(&sp.stop, 1);
  pthread_join(sp.thread, NULL);
  const palp_dds_topic_kind must_see[] = {PALP_TOPIC_CATALOGUE, PALP_TOPIC_EXERCISE,    PALP_TOPIC_SESSION_STATE,
                                          PALP_TOPIC_SESSION_REPLY, PALP_TOPIC_LOCAL_MODEL, PALP_TOPIC_FEEDBACK,
                                          PALP_TOPIC_DEFORMATION, PALP_TOPIC_FINDING_STATUS, PALP_TOPIC_FINDING,
                                          PALP_TOPIC_DEBRIEF};
  for (size_t i = 0; i < sizeof must_see / sizeof must_see[0]; i++)
    CHECK(sp.samples[must_see[i]] > 0, "spy captured %llu samples of %s",
          (unsigned long long)sp.samples[must_see[i]], palp_dds_topic_name(must_see[i]));
  CHECK(sp.leaks == 0, "no lesion value in %llu serialized bytes a trainee could read (%d leaks%s%s)",
        (unsigned long long)sp.bytes, sp.leaks, sp.leaks ? ": " : "", sp.leak);
  dds_delete(sp.pp);

  test_server_stop(&ts);
  palp_srv_db_log_close(dbl);
  palp_cli_station_close(&a);
  palp_cli_station_close(&b);
  palp_cli_station_close(&c);

  /* ---- the instructor's log ---- */
  palp_db *db = NULL;
  REQUIRE(palp_db_open(db_path, 0, &db, err, sizeof err) == 0, "open the log: %s", err);
  palp_db_session_info *ss = NULL;
  int ns = 0;
  REQUIRE(palp_db_list_sessions(db, NULL, &ss, &ns) == 0 && ns == 3, "three sessions logged (%d)", ns);
  const palp_db_session_info *sa = NULL, *sb = NULL, *sc = NULL;
  for (int i = 0; i < ns; i++) {
    if (strcmp(ss[i].trainee, "alice") == 0) sa = &ss[i];
    if (strcmp(ss[i].trainee, "bob") == 0) sb = &ss[i];
    if (strcmp(ss[i].trainee, "carol") == 0) sc = &ss[i];
  }
  REQUIRE(sa && sb && sc, "alice's, bob's and carol's sessions");
  char name[64] = "";
  char *exj = NULL;
  CHECK(palp_db_session_exercise(db, sa->id, name, sizeof name, &exj) == 0 && strcmp(name, "test-wire") == 0,
        "alice's session logs its exercise \"%s\"", name);
  if (exj) {
    palp_exercise lx;
    palp_lesion ll[PALP_MAX_LESIONS];
    int n = palp_exercise_parse(exj, PALP_TEST_DIR, &lx, err, sizeof err) == 0
                ? palp_exercise_lesions(&lx, 0.04, ll, PALP_MAX_LESIONS, err, sizeof err)
                : -1;
    /* Independently: centre = (R - depth) n(polar, azimuth), radius = diameter / 2. */
    const double want[2][4] = {{31, 41, 10.3e-3, 9.7e-3}, {52, 217, 11.1e-3, 10.6e-3}};
    int ok = n == 2;
    for (int i = 0; ok && i < 2; i++) {
      const palp_vec3 cw = dome_point(0.04 - want[i][2], want[i][0], want[i][1]);
      ok = fabs(ll[i].center.x - cw.x) < 1e-9 && fabs(ll[i].center.y - cw.y) < 1e-9 &&
           fabs(ll[i].center.z - cw.z) < 1e-9 && fabs(ll[i].radius - want[i][3] / 2) < 1e-12;
    }
    CHECK(ok, "  the log has both lesions (centres within 1e-9 m of (R - depth) n, radii exact)");
    free(exj);
  }
  char *scene = NULL, *params = NULL;
  CHECK(palp_db_session_json(db, sa->id, &scene, &params) == 0 && scene && strstr(scene, "lesion"),
        "  its scene_json includes the lesions");
  free(scene), free(params);
  CHECK(palp_db_session_exercise(db, sb->id, name, sizeof name, &exj) == PALP_DB_ENOTFOUND,
        "bob's free practice has no exercise");
  log_findings lf = {0};
  palp_db_each_finding(db, sa->id, on_log_finding, &lf);
  CHECK(lf.marks == 64 && lf.withdrawals == 1, "the log has the 64 accepted marks and 1 withdrawal (%d, %d)",
        lf.marks, lf.withdrawals);
  CHECK(lf.first.mark_id == 1 && lf.first.point_m.x == p1.x && lf.first.point_m.y == p1.y &&
            lf.first.point_m.z == p1.z && lf.first.frame > 0 && lf.first.sim_time_s > 0,
        "  mark 1 at the point sent, frame %lld, t %.3f s", (long long)lf.first.frame, lf.first.sim_time_s);
  CHECK(lf.bad_order == 0, "  in frame order");
  log_events le = {0};
  palp_db_each_event(db, sa->id, on_log_event, &le);
  CHECK(le.forged == 1 && le.nan == 1 && le.unknown == 1 && le.off == 1 && le.cap == 1,
        "refusals logged as events: forged %d, NaN %d, unknown %d, off %d, 65th %d", le.forged, le.nan, le.unknown,
        le.off, le.cap);
  CHECK(le.flood >= 1000 - flood_accepted - 1 && le.flood <= 1000 - flood_accepted,
        "  the flood's %d refusals (one by one, then counted): %d", 1000 - flood_accepted, le.flood);
  log_samples ls = {0};
  palp_db_each_finger_sample(db, sa->id, on_log_sample, &ls);
  /* 250 Hz physics, assess_sample_hz 100: every lround(2.5) = 3rd frame. */
  CHECK(ls.n > 100 && ls.min_gap == 3 && ls.max_gap == 3, "finger samples: %d, every %lld..%lld frames", ls.n,
        (long long)ls.min_gap, (long long)ls.max_gap);
  CHECK(ls.touching > 50 && ls.with_triangles > 50 && ls.bad_radius == 0,
        "  %d touching, %d with their triangles, fingertip radius 8 mm", ls.touching, ls.with_triangles);
  CHECK(strcmp(sc->end_reason, "normal") == 0 && strcmp(sc->end_detail, "exercise time limit reached") == 0,
        "carol's session (%u) ended %s: \"%s\"", carol_session, sc->end_reason, sc->end_detail);
  /* What each trainee was told is in the log (PALP_DB_EVENT_DEBRIEF, since session 59), as her
   * station got it above: carol's 1 of 2 with lesion 1 found by mark 1, alice's nothing but her
   * 63 marks; bob's free practice had no debrief. */
  {
    palp_db_debrief d;
    CHECK(palp_db_session_debrief(db, sc->id, &d) == 1 && d.sent && d.level == PALP_DB_DEBRIEF_LESIONS &&
              d.lesions == 2 && d.found == 1 && d.marks == 2 && d.false_marks == 1 && d.duplicates == 0 &&
              d.listed == 2 && d.found_by[0] == 1 && d.found_by[1] == 0,
          "carol's log: her debrief as sent (level %d, %d of %d, marks %d, false %d, listed %d: %u %u)", (int)d.level,
          d.found, d.lesions, d.marks, d.false_marks, d.listed, d.found_by[0], d.found_by[1]);
    CHECK(palp_db_session_debrief(db, sa->id, &d) == 1 && d.sent && d.level == PALP_DB_DEBRIEF_NONE && d.marks == 63 &&
              d.lesions == 0 && d.listed == 0,
          "alice's log: told nothing of the lesions, 63 marks standing (level %d, marks %d)", (int)d.level, d.marks);
    CHECK(palp_db_session_debrief(db, sb->id, &d) == 0, "bob's free practice logged no debrief");
    char *p2 = NULL;
    cJSON *pj = palp_db_session_json(db, sa->id, NULL, &p2) == 0 && p2 ? cJSON_Parse(p2) : NULL;
    CHECK(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(pj, "debrief_events")),
          "  the sessions say their server logs debriefs (\"debrief_events\": true): %s", p2 ? p2 : "(none)");
    cJSON_Delete(pj);
    free(p2);
  }
  /* The score sent is palp-review's reading of the same log, to the last bit: the dashboard and the
   * review give the instructor one number. */
  {
    review_assessment *ra = calloc(1, sizeof *ra);
    REQUIRE(ra, "memory");
    const int arc = review_assess(db, sa, ra, err, sizeof err);
    CHECK(arc == 0 && got_a && strcmp(score_a.log_uid, sa->uid) == 0,
          "alice's score names her logged session \"%s\" (the log's uid \"%s\"; review: %s)",
          got_a ? score_a.log_uid : "", sa->uid, arc ? err : "ok");
    if (arc == 0 && got_a) {
      int same = score_a.score == ra->r.score && (int)score_a.pass == ra->r.pass && score_a.found == (uint32_t)ra->r.found &&
                 score_a.samples == (uint32_t)ra->samples && score_a.duration == ra->r.duration &&
                 score_a.peak_force == ra->r.peak_force && strcmp(score_a.pattern, palp_pattern_name(ra->r.pattern)) == 0;
      for (int m = 0; m < PALP_METRIC_COUNT; m++)
        same = same && score_a.credit[m] == ra->r.component[m] && (int)score_a.passed[m] == ra->r.pass_metric[m];
      for (int b = 0; b < PALP_BAND_COUNT; b++) same = same && score_a.coverage[b] == ra->r.coverage[b];
      CHECK(same, "  and its numbers are the review's, exactly (score %.3f / %.3f, light %.4f / %.4f)", score_a.score,
            ra->r.score, score_a.coverage[0], ra->r.coverage[0]);
      CHECK(!score_a.pass && score_a.score < 70, "  a 20 s session over one lesion does not pass (score %.1f)",
            score_a.score);
      palp_db_log_health hl;
      char line[128] = "";
      if (palp_db_log_health_get(db, sa, &hl) == 0) palp_db_log_health_describe(&hl, line, sizeof line);
      CHECK(score_a.log_complete && hl.complete && strncmp(score_a.log_health, "complete: ", 10) == 0 &&
                strcmp(score_a.log_health, line) == 0,
            "  from a complete log, in the review's words: \"%s\"", score_a.log_health);
      review_assessment_free(ra);
    }
    free(ra);
  }
  free(ss);
  palp_db_close(db);

  /* ---- a server whose grader did not start (session 65) ----
   * palp_srv_db_log_open leaves take_score NULL when palp_srv_grader_open fails (a thread or memory
   * refused): nothing will score the session, so a practice exercise's trainee is told at once why
   * (the log's `unscored` words), not left to wait her station's 5 s for a score that will not come.
   * The same log's events, take_score taken away as that failure leaves it. */
  {
    char db2[760];
    snprintf(db2, sizeof db2, "%s/server_findings_nograder.db", cwd);
    unlink(db2);
    palp_srv_db_log *dbl2 = NULL;
    REQUIRE(palp_srv_db_log_open(db2, 0, NULL, &dbl2, err, sizeof err) == 0, "second log: %s", err);
    palp_srv_events ev = *palp_srv_db_log_events(dbl2);
    ev.take_score = NULL;
    palp_srv_def def2 = {.cfg = cfg, .events = &ev, .verbose = 0};
    test_server ts2 = {0};
    test_server_start_def(&ts2, &def2);
    palp_cli_station d;
    test_station_join(&d, DOMAIN, "dora", palp_ROLE_TRAINEE, EX_SHORT, 0, 1, 0);
    palp_Debrief db_;
    palp_DebriefLesion dl[PALP_DEBRIEF_MAX_LESIONS];
    char derr[160] = "";
    const int got_d = palp_cli_station_debrief(&d, 6.0, &db_, dl, derr, sizeof derr); /* the 2 s limit, then */
    const int64_t t_debrief = palp_dds_now_ns();
    palp_SessionScore m;
    char serr[160] = "";
    const int got = got_d == 1 ? palp_cli_station_debrief_score(&d, 5.0, &m, serr, sizeof serr) : -1;
    const double after_s = (double)(palp_dds_now_ns() - t_debrief) * 1e-9;
    CHECK(got_d == 1 && db_.level == palp_DEBRIEF_LESIONS, "dora's practice session debriefed (got %d %s)", got_d, derr);
    CHECK(got == 1 && m.session_id == d.session_id && m.status == palp_SCORE_NOT_GRADED &&
              strcmp(m.reason, "this server's grader did not start (its log says why); the instructor's review "
                               "scores the session from the session log") == 0 &&
              strcmp(m.exercise_name, "test-short") == 0,
          "a server without its grader tells dora at once why she gets no score: \"%s\" (got %d %s)",
          got == 1 ? m.reason : "", got, serr);
    CHECK(got == 1 && after_s < 1.0, "  %.2f s after her debrief (tolerance 1 s; her station waits 5 s for a score)",
          after_s);
    palp_cli_station_leave(&d);
    test_server_stop(&ts2);
    palp_cli_station_close(&d);
    palp_srv_db_log_close(dbl2);
    unlink(db2);
    /* A log with its grader (a log of its own: a log's session uids are its server run's): a server
     * stopped while ema's practice session runs closes it and tells her at once that it will not be
     * scored (the grader takes no session the shutdown closed): the debrief and the answer are
     * written as the server stops, and reach her station. */
    REQUIRE(palp_srv_db_log_open(db2, 0, NULL, &dbl2, err, sizeof err) == 0, "third log: %s", err);
    palp_srv_def def3 = {.cfg = cfg, .events = palp_srv_db_log_events(dbl2), .verbose = 0};
    test_server ts3 = {0};
    test_server_start_def(&ts3, &def3);
    palp_cli_station e;
    test_station_join(&e, DOMAIN, "ema", palp_ROLE_TRAINEE, EX_SHORT, 0, 1, 0);
    test_server_stop(&ts3);
    const int got_de = palp_cli_station_debrief(&e, 3.0, &db_, dl, derr, sizeof derr);
    const int got_e = got_de == 1 ? palp_cli_station_debrief_score(&e, 3.0, &m, serr, sizeof serr) : -1;
    CHECK(got_de == 1 && db_.level == palp_DEBRIEF_LESIONS && strcmp(db_.reason, "server shutdown") == 0,
          "ema's practice session, closed by the server's stop, debriefed (got %d, \"%s\" %s)", got_de,
          got_de == 1 ? db_.reason : "", derr);
    CHECK(got_e == 1 && m.session_id == e.session_id && m.status == palp_SCORE_NOT_GRADED &&
              strncmp(m.reason, "the server stopped before it scored the session", 47) == 0,
          "  and told why she gets no score: \"%s\" (got %d %s)", got_e == 1 ? m.reason : "", got_e, serr);
    palp_cli_station_close(&e);
    palp_srv_db_log_close(dbl2);
    unlink(db2);
  }
  fprintf(stderr, "server_findings: %.1f s\n", (double)(palp_dds_now_ns() - t_start) * 1e-9);
  return palp_test_failures ? 1 : 0;
}
