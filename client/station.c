/* station.c - the DDS side of a palp station. */
#include "station.h"
#include "view.h"
#include "input.h" /* PALP_CLI_MAX_FINGERS, PALP_CLI_PHYSICS_RATE_* */

#include "palp_assess.h" /* palp_metric_to_work_on: the words her page uses too */
#include "palp_log.h"    /* PALP_PRINTABLE_LONG */

#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>
#include <unistd.h>

static int fail(char *err, size_t errlen, int code, const char *fmt, ...) {
  if (err && errlen) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
  }
  return code;
}

static void nap(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
  nanosleep(&ts, NULL);
}

/* The caller asked the station to end (palp_cli_station.stop). */
static int stopped(const palp_cli_station *st) { return st->stop && atomic_load(st->stop); }

static int fail_stopped(char *err, size_t errlen) {
  return fail(err, errlen, PALP_CLI_ESTOPPED, "interrupted");
}

/* The session topics' filter (DDS receive thread): this station's session. Each type's first key is
 * its session id. st->session_id is set before the session's readers exist and they are deleted
 * (palp_cli_station_end_session) before another session's id replaces it. */
static bool own_session(const void *sample, void *arg) {
  const palp_cli_station *st = arg;
  return *(const uint32_t *)sample == st->session_id;
}
_Static_assert(offsetof(palp_Contact, session_id) == 0 && offsetof(palp_Feedback, session_id) == 0 &&
                   offsetof(palp_Deformation, session_id) == 0 && offsetof(palp_FindingStatus, session_id) == 0 &&
                   offsetof(palp_Debrief, session_id) == 0 && offsetof(palp_SessionScore, session_id) == 0 &&
                   offsetof(palp_SessionLog, session_id) == 0 && offsetof(palp_SessionState, session_id) == 0,
               "the session id first");

/* The global topics' filters (2026-12-07). Unfiltered, every made-up key a peer wrote became an
 * instance of the station's reader, held as long as its writer lived: an observer's RSS went from
 * 12.8 MB to 138 MB after a peer wrote 200,000 OPEN states of distinct ids (~630 B a key). The
 * replies: those to this station (their key is its station id; the station writes none). */
static bool own_reply(const void *sample, void *arg) {
  const palp_SessionReply *r = sample;
  const palp_cli_station *st = arg;
  return strncmp(r->station_id, st->station_id, sizeof r->station_id) == 0;
}

/* The servers' statuses: those that list this station's session, the only ones it reads (watch_log);
 * none outside a session (a status comes every status period: none is missed for long). */
static bool own_status(const void *sample, void *arg) {
  const palp_ServerStatus *m = sample;
  palp_cli_station *st = arg;
  /* the atomic copy: this reader lives while the main thread joins and ends sessions */
  const uint32_t id = atomic_load_explicit(&st->status_session_id, memory_order_relaxed);
  for (uint32_t k = 0; id && k < m->sessions._length; k++)
    if (m->sessions._buffer[k].session_id == id) return true;
  return false;
}

/* The exercises: the joined phantom's (st->exercise_phantom, set before its reader exists). */
static bool own_exercise(const void *sample, void *arg) {
  const palp_Exercise *e = sample;
  const palp_cli_station *st = arg;
  return e->phantom_id == st->exercise_phantom;
}

/* A reader of kind on a topic entity of its own that carries filter f: *topic and the reader, or a
 * negative code (nothing made). */
static dds_entity_t filtered_reader(palp_cli_station *st, palp_dds_topic_kind kind,
                                    bool (*f)(const void *, void *), dds_entity_t *topic) {
  const dds_entity_t tp = palp_dds_create_topic(st->pp, kind);
  if (tp < 0) return tp;
  struct dds_topic_filter flt = {.mode = DDS_TOPIC_FILTER_SAMPLE_ARG, .f = {.sample_arg = f}, .arg = st};
  const dds_entity_t r = dds_set_topic_filter_extended(tp, &flt) == 0 ? palp_dds_create_reader(st->pp, tp, kind) : -1;
  if (r < 0) {
    dds_delete(tp);
    return r;
  }
  *topic = tp;
  return r;
}

/* The exercise reader for phantom_id (palp_cli_station.exercise_r), made anew unless it is that
 * phantom's already. */
static void server_only_close(palp_cli_station *st, palp_cli_server_only *so);
static int server_only_open(palp_cli_station *st, palp_cli_server_only *so, palp_dds_topic_kind kind,
                            dds_entity_t known_by, uint32_t phantom, int force);
static void server_only_count(palp_cli_station *st, palp_cli_server_only *so);

static int exercise_reader(palp_cli_station *st, uint32_t phantom_id) {
  if (st->exercise_r > 0 && st->exercise_phantom == phantom_id) return 0;
  server_only_close(st, &st->exercise_srv);
  if (st->exercise_r > 0) dds_delete(st->exercise_r);
  if (st->exercise_topic > 0) dds_delete(st->exercise_topic);
  st->exercise_r = st->exercise_topic = 0;
  st->exercise_phantom = phantom_id;
  const dds_entity_t r = filtered_reader(st, PALP_TOPIC_EXERCISE, own_exercise, &st->exercise_topic);
  if (r < 0) return PALP_EIO;
  st->exercise_r = r;
  return 0;
}

/* In a session, its own state only (state_r on st->state_topic, filtered by own_session); outside one,
 * every state (state_r on the shared topic entity: palp-client's --trainee looks for a trainee's
 * session before its join). Each replaces the other's reader, and with it what it held: the
 * states read before the join are not kept through the session. */
static int state_reader(palp_cli_station *st, int in_session) {
  dds_entity_t tp = 0;
  const dds_entity_t r =
      in_session ? filtered_reader(st, PALP_TOPIC_SESSION_STATE, own_session, &tp)
                 : palp_dds_create_reader(st->pp, st->topic[PALP_TOPIC_SESSION_STATE], PALP_TOPIC_SESSION_STATE);
  if (r < 0) return PALP_EIO;
  if (st->state_r > 0) dds_delete(st->state_r);
  if (st->state_topic > 0) dds_delete(st->state_topic);
  st->state_r = r;
  st->state_topic = tp;
  return 0;
}

/* A best-effort stream's reader of the session (contacts, feedback, deformations), holding at most
 * PALP_CLI_STREAM_INSTANCES keys: a dispose of a made-up key passes no filter. Deformations are read
 * best-effort from the server's reliable writer, as palp_dds_create_display_reader does. */
static dds_entity_t stream_reader(const palp_cli_station *st, dds_entity_t topic, palp_dds_topic_kind kind) {
  dds_qos_t *q = palp_dds_qos(kind);
  dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_resource_limits(q, DDS_LENGTH_UNLIMITED, PALP_CLI_STREAM_INSTANCES, DDS_LENGTH_UNLIMITED);
  const dds_entity_t r = dds_create_reader(st->sub, topic, q, NULL);
  dds_delete_qos(q);
  return r;
}

/* Where this process's request numbers start (2026-12-07): random, 31 bits, never 0. The server refuses
 * a JOIN whose (station id, request_seq) is the one that opened a session it closed (it remembers its
 * last 1,024 closed sessions): DDS re-delivers an old JOIN when a participant is found again. A station
 * id is "host/pid/label", and every process numbered its requests from 1: a station restarted with the
 * same host, pid and label (a container's pid 1 and fixed hostname; a pid reused) sent the closed
 * session's pair again and was refused "session 1 closed: trainee station left" (reproduced with
 * `unshare -p -f palp-client --role trainee --phantom 1 --duration 1` run twice). A number, not a nonce
 * in the id: the id's form stays "host/pid/label" (a secured one "kind/name/host/pid/label", which the
 * server checks), and nothing reads request_seq but for equality (server/server.c; web/hub.c numbers its
 * own). 2^31 requests from the start cannot wrap to 0 in a process's life. Without getrandom (a kernel
 * before 3.17) the clock and the pid: distinct for two processes started apart. */
static uint32_t first_request_seq(void) {
  uint32_t v = 0;
  if (getrandom(&v, sizeof v, GRND_NONBLOCK) != (ssize_t)sizeof v) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    v = (uint32_t)ts.tv_nsec ^ (uint32_t)ts.tv_sec * 2654435761u ^ (uint32_t)getpid() * 40503u;
  }
  v &= 0x7fffffffu;
  return v ? v : 1;
}

int palp_cli_station_open(palp_cli_station *st, uint32_t domain, const char *label, char *err, size_t errlen) {
  return palp_cli_station_open_secure(st, domain, label, NULL, err, errlen);
}

int palp_cli_station_open_secure(palp_cli_station *st, uint32_t domain, const char *label,
                                 const palp_dds_security *sec, char *err, size_t errlen) {
  memset(st, 0, sizeof *st);
  st->request_seq = first_request_seq(); /* the first request sends the next */
  if (sec) st->sec = *sec;
  const int secured = st->sec.kind != PALP_DDS_ID_NONE;
  char host[32] = "host";
  gethostname(host, sizeof host - 1);
  if (secured) /* identity <= 42 characters, so the prefix always fits the 63 */
    snprintf(st->station_id, sizeof st->station_id, "%s/%s/%.8s/%ld/%s", palp_dds_id_kind_name(st->sec.kind),
             st->sec.name, host, (long)getpid(), label ? label : "station");
  else
    snprintf(st->station_id, sizeof st->station_id, "%.24s/%ld/%.24s", host, (long)getpid(),
             label ? label : "station");
  st->pp = palp_dds_create_participant((dds_domainid_t)domain, &st->sec);
  if (st->pp < 0)
    return fail(err, errlen, PALP_EIO, "cannot create a DDS participant on domain %u: %s%s", domain,
                dds_strretcode(st->pp),
                secured ? " (DDS Security refused the identity: see the messages above; is the certificate revoked"
                          " or expired, the domain above 230?)"
                        : "");
  for (int k = 0; k < PALP_TOPIC_COUNT; k++) {
    /* palp_station_request is for other vendors' stations on plain DDS (docs/interop.md). */
    if (k == PALP_TOPIC_STATION_REQUEST) continue;
    /* palp_session_exercise and palp_session_score hold an exercise's answers: for instructors'
     * tools only. */
    if (k == PALP_TOPIC_SESSION_EXERCISE || k == PALP_TOPIC_SESSION_SCORE) continue;
    if (k == PALP_TOPIC_SESSION_CLOSED) continue; /* the instructors' dashboards' (session 69) */
    st->topic[k] = palp_dds_create_topic(st->pp, (palp_dds_topic_kind)k);
    /* palp_debrief came after the classroom PKIs of 2026-12-04 and before: an identity whose
     * permissions predate it still palpates, and is told at an exercise's end why it is not
     * debriefed (make-classroom-pki.sh init re-issues the permissions). */
    if (st->topic[k] < 0 && k == PALP_TOPIC_DEBRIEF && secured) {
      st->topic[k] = 0;
      st->debrief_topic_refused = 1;
      continue;
    }
    if (st->topic[k] < 0 && k == PALP_TOPIC_DEBRIEF_SCORE && secured) { /* likewise, session 64 */
      st->topic[k] = 0;
      st->debrief_score_topic_refused = 1;
      continue;
    }
    if (st->topic[k] < 0 && k == PALP_TOPIC_SESSION_LOG && secured) { /* session 69: the server's counts instead */
      st->topic[k] = 0;
      continue;
    }
    if (st->topic[k] < 0 && k == PALP_TOPIC_FINGER_SAMPLE && secured) { /* session 71: coverage approximated */
      st->topic[k] = 0;
      continue;
    }
    if (st->topic[k] < 0) {
      char hint[PALP_DDS_HINT_MAX];
      const char *name = palp_dds_topic_name((palp_dds_topic_kind)k);
      palp_dds_refused_hint(&st->sec, name, hint, sizeof hint);
      palp_cli_station_close(st);
      return fail(err, errlen, PALP_EIO, "cannot create topic %s%s", name, hint);
    }
  }
  /* The session's other topics take only this session's samples too (its local models and finger
   * samples are filtered in palp_cli_station_join): a flood of made-up keys in its partition of an
   * unsecured classroom never becomes an instance in its readers (server/session.c filters its
   * contacts so). A filter applies to every reader of its topic entity, and these topics' readers
   * are all of the session; and to its writers: hence not the contacts, which a trainee writes here
   * (a viewer's contact reader has a filtered topic entity of its own, palp_cli_station_join). */
  static const palp_dds_topic_kind own[] = {PALP_TOPIC_FEEDBACK, PALP_TOPIC_DEFORMATION,
                                            PALP_TOPIC_FINDING_STATUS, PALP_TOPIC_DEBRIEF, PALP_TOPIC_DEBRIEF_SCORE,
                                            PALP_TOPIC_SESSION_LOG};
  for (size_t k = 0; k < sizeof own / sizeof own[0]; k++) {
    struct dds_topic_filter flt = {.mode = DDS_TOPIC_FILTER_SAMPLE_ARG, .f = {.sample_arg = own_session}, .arg = st};
    if (st->topic[own[k]] > 0 && dds_set_topic_filter_extended(st->topic[own[k]], &flt) < 0) {
      palp_cli_station_close(st);
      return fail(err, errlen, PALP_EIO, "cannot filter topic %s", palp_dds_topic_name(own[k]));
    }
  }
  st->catalogue_r = palp_dds_create_reader(st->pp, st->topic[PALP_TOPIC_CATALOGUE], PALP_TOPIC_CATALOGUE);
  dds_entity_t request_parent = st->pp;
  if (secured) {
    char part[64];
    palp_dds_request_partition(&st->sec, part, sizeof part);
    st->request_pub = palp_dds_session_publisher(st->pp, part);
    request_parent = st->request_pub;
  }
  st->request_w = request_parent < 0 ? request_parent
                                     : palp_dds_create_writer(request_parent, st->topic[PALP_TOPIC_SESSION_REQUEST],
                                                              PALP_TOPIC_SESSION_REQUEST);
  /* Its replies and the statuses of its session's server only (own_reply, own_status), through topic
   * entities of their own: st->topic[] of the global topics stays unfiltered for other readers (a
   * benchmark's monitor reads every status through it). The states and the exercise are filtered to the
   * session at the join (state_reader, exercise_reader). The catalogue is not: a search by name needs
   * every entry (palp_cli_station_find_phantom), made-up ones among them. */
  st->reply_r = filtered_reader(st, PALP_TOPIC_SESSION_REPLY, own_reply, &st->reply_topic);
  st->state_r = palp_dds_create_reader(st->pp, st->topic[PALP_TOPIC_SESSION_STATE], PALP_TOPIC_SESSION_STATE);
  /* The server's status, for its session log's losses (palp_cli_station_log_news); a station whose
   * permissions refuse it palpates all the same and is told nothing of the log. */
  st->status_r = filtered_reader(st, PALP_TOPIC_SERVER_STATUS, own_status, &st->status_topic);
  if (st->status_r < 0) st->status_r = 0;
  /* What discovery announces of the domain's writers: which are the session's server's
   * (palp_cli_station_from_server). Without it, a writer is asked of the reader it matched. */
  st->publications_r = dds_create_reader(st->pp, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, NULL, NULL);
  if (st->publications_r < 0) st->publications_r = 0;
  if (st->catalogue_r < 0 || st->request_w < 0 || st->reply_r < 0 || st->state_r < 0) {
    palp_cli_station_close(st);
    return fail(err, errlen, PALP_EIO, "cannot create the station's DDS endpoints");
  }
  return 0;
}

void palp_cli_station_close(palp_cli_station *st) {
  if (st->pp > 0) dds_delete(st->pp);
  st->pp = 0;
}

/* The catalogue, looked through (2026-12-07). A plain dds_read of at most N samples returns the same
 * first N on every pass: 300 made-up entries a peer wrote before the server's hid the real phantom
 * (the station, already joined, exited 1 "no catalogue entry for phantom 1"; tests/server/
 * test_catalogue.c). A phantom known by its id is its instance, looked up by its key; a search (by
 * name, or any phantom) reads every entry once, as it comes, CATALOGUE_PAGE at a time, through a reader
 * of its own made for the search (the station's own has marked what earlier searches read). */
#define CATALOGUE_PAGE 64

/* One catalogue entry for palp_cli_station_catalogue: 0 copied into *out (the caller frees it with
 * palp_cli_phantom_free), PALP_ENOMEM, or 1: not this one (not alive, another id, or malformed: bad
 * says why, the first of a kind written to stderr). */
static int take_entry(const palp_Phantom *p, const dds_sample_info_t *info, uint32_t phantom_id, char *bad,
                      size_t badlen, palp_Phantom *out) {
  /* Not alive: its server is gone (several servers on one domain). */
  if (!info->valid_data || info->instance_state != DDS_IST_ALIVE || (phantom_id && p->phantom_id != phantom_id))
    return 1;
  /* From the network: checked before any index in it is used (a forged entry
   * with bad triangle indices crashed the visual station). */
  char why[200];
  if (palp_cli_phantom_check(p, why, sizeof why) < 0) {
    if (strcmp(bad, why) != 0) fprintf(stderr, "palp-client: ignoring a malformed catalogue entry: %s\n", why);
    snprintf(bad, badlen, "%s", why);
    return 1;
  }
  *out = *p;
  size_t nv = p->rest._length, nt = p->triangles._length;
  out->rest._buffer = malloc((nv ? nv : 1) * sizeof(palp_Vec3));
  out->triangles._buffer = malloc((nt ? nt : 1) * sizeof(int32_t));
  if (!out->rest._buffer || !out->triangles._buffer) {
    palp_cli_phantom_free(out);
    return PALP_ENOMEM;
  }
  memcpy(out->rest._buffer, p->rest._buffer, nv * sizeof(palp_Vec3));
  memcpy(out->triangles._buffer, p->triangles._buffer, nt * sizeof(int32_t));
  out->rest._maximum = (uint32_t)nv;
  out->triangles._maximum = (uint32_t)nt;
  out->rest._release = out->triangles._release = false;
  return 0;
}

/* A search's own catalogue reader: transient-local, so it is sent the whole catalogue anew. */
static dds_entity_t search_reader(palp_cli_station *st) {
  return palp_dds_create_reader(st->pp, st->topic[PALP_TOPIC_CATALOGUE], PALP_TOPIC_CATALOGUE);
}

int palp_cli_station_catalogue(palp_cli_station *st, uint32_t phantom_id, double timeout, palp_Phantom *out,
                               char *err, size_t errlen) {
  int64_t end = palp_dds_now_ns() + (int64_t)(timeout * 1e9);
  /* In a session, the server's entry alone (review s83 #1): through a reader of its own that drops other
   * writers' samples before they enter its history, made when the server's catalogue writer is known (the
   * station's own reader matched it long before), and sent the server's entry anew (transient-local).
   * The session's phantom is the one wanted then. */
  const int bound = st->bind.bound;
  if (bound && !phantom_id) phantom_id = st->phantom_id;
  palp_cli_server_only srv;
  memset(&srv, 0, sizeof srv);
  /* any phantom: a search through every entry */
  dds_entity_t rd = bound ? 0 : phantom_id ? st->catalogue_r : search_reader(st);
  if (rd < 0) return fail(err, errlen, PALP_EIO, "cannot read the catalogue: %s", dds_strretcode(rd));
  int result = 1;
  char bad[256] = "";
  for (int pass = 0;; pass++) {
    if (bound) {
      if (server_only_open(st, &srv, PALP_TOPIC_CATALOGUE, st->catalogue_r, phantom_id, pass == 0) < 0) {
        result = PALP_EIO;
        break;
      }
      rd = srv.reader;
    }
    if (phantom_id && rd > 0) {
      /* read, not take: the catalogue stays available to later calls */
      palp_Phantom key;
      memset(&key, 0, sizeof key);
      key.phantom_id = phantom_id;
      const dds_instance_handle_t ih = dds_lookup_instance(rd, &key);
      void *ptr[1] = {NULL};
      dds_sample_info_t info;
      if (ih != DDS_HANDLE_NIL && dds_read_instance(rd, ptr, &info, 1, 1, ih) > 0) {
        result = take_entry(ptr[0], &info, phantom_id, bad, sizeof bad, out);
        dds_return_loan(rd, ptr, 1);
      }
    } else if (!phantom_id) {
      int n;
      do {
        void *ptr[CATALOGUE_PAGE] = {NULL};
        dds_sample_info_t info[CATALOGUE_PAGE];
        n = dds_read_mask(rd, ptr, info, CATALOGUE_PAGE, CATALOGUE_PAGE, DDS_NOT_READ_SAMPLE_STATE);
        for (int i = 0; i < n && result == 1; i++) result = take_entry(ptr[i], &info[i], 0, bad, sizeof bad, out);
        if (n > 0) dds_return_loan(rd, ptr, n);
      } while (result == 1 && n > 0);
    }
    if (result != 1) break;
    if (stopped(st)) {
      result = PALP_CLI_ESTOPPED;
      break;
    }
    const int64_t now = palp_dds_now_ns();
    if (now >= end) break;
    nap(end - now < DDS_MSECS(20) ? (double)(end - now) * 1e-9 : 0.02);
  }
  /* what another participant wrote for the phantom, named before its reader goes */
  const unsigned long long forged = bound ? atomic_load(&srv.refused) : 0;
  char forger[64] = "a writer already gone";
  if (forged) palp_dds_writer_participant_text(srv.reader, (dds_instance_handle_t)atomic_load(&srv.first_refused),
                                               forger, sizeof forger);
  if (bound) server_only_close(st, &srv); /* its refusals counted (bind.ignored), said with the session's */
  else if (rd != st->catalogue_r) dds_delete(rd);
  if (result == PALP_CLI_ESTOPPED) return fail_stopped(err, errlen);
  if (result == PALP_ENOMEM) return fail(err, errlen, result, "out of memory");
  if (result == PALP_EIO) return fail(err, errlen, result, "cannot read the catalogue");
  if (result != 0 && bad[0])
    return fail(err, errlen, PALP_EINVAL, "no valid catalogue entry for phantom %u within %.1f s: %s", phantom_id,
                timeout, bad);
  if (result != 0 && forged)
    return fail(err, errlen, PALP_EIO,
                "phantom %u's catalogue entry comes from %s, not this session's server (%llu sample%s ignored); none "
                "from the server within %.1f s", phantom_id, forger, forged, forged == 1 ? "" : "s", timeout);
  if (result != 0) {
    char hint[PALP_DDS_HINT_MAX];
    palp_dds_unanswered_hint(st->pp, &st->sec, hint, sizeof hint);
    return fail(err, errlen, PALP_EIO, "no catalogue entry for phantom %u within %.1f s (is palp-server running on this domain?)%s",
                phantom_id, timeout, hint);
  }
  return 0;
}

void palp_cli_phantom_free(palp_Phantom *p) {
  free(p->rest._buffer);
  free(p->triangles._buffer);
  p->rest._buffer = NULL;
  p->triangles._buffer = NULL;
}

/* Writes a new request (the next request_seq); *sent (may be NULL) keeps a copy. */
static int send_request(palp_cli_station *st, const palp_cli_join *j, int op, palp_SessionRequest *sent) {
  palp_SessionRequest rq;
  memset(&rq, 0, sizeof rq);
  snprintf(rq.station_id, sizeof rq.station_id, "%s", st->station_id);
  rq.request_seq = ++st->request_seq;
  rq.op = op;
  rq.role = (palp_Role)j->role;
  rq.phantom_id = j->phantom_id;
  rq.session_id = j->session_id;
  /* A secured station is its identity: no name given means the identity's name. */
  const char *user = j->user_name && j->user_name[0] ? j->user_name
                     : st->sec.kind != PALP_DDS_ID_NONE ? st->sec.name
                                                         : "";
  snprintf(rq.user_name, sizeof rq.user_name, "%s", user);
  rq.want_feedback = j->want_feedback != 0;
  rq.want_deformation = j->want_deformation != 0;
  if (op == palp_OP_JOIN) st->last_join = rq, st->has_last_join = 0; /* kept once accepted */
  if (sent) *sent = rq;
  return dds_write(st->request_w, &rq) < 0 ? PALP_EIO : 0;
}

/* Waits for the reply to request seq until end_ns: 1 accepted, 0 rejected, -1 timeout, -2 the
 * caller's stop flag set (looked at only when stoppable: a leave's waits are the goodbye itself). *pub
 * (may be NULL): the replier's publication handle. In a session only its server's replies count. */
static int await_reply_to(palp_cli_station *st, uint32_t seq, int64_t end_ns, int stoppable, palp_SessionReply *out,
                          dds_instance_handle_t *pub) {
  dds_entity_t ws = dds_create_waitset(st->pp);
  dds_entity_t rc = dds_create_readcondition(st->reply_r, DDS_ANY_STATE);
  dds_waitset_attach(ws, rc, 0);
  int result = -1;
  while (result < 0) {
    palp_SessionReply buf[4];
    void *ptr[4] = {&buf[0], &buf[1], &buf[2], &buf[3]};
    dds_sample_info_t info[4];
    int n;
    while (result < 0 && (n = dds_take(st->reply_r, ptr, info, 4, 4)) > 0)
      for (int i = 0; i < n; i++)
        if (info[i].valid_data && strncmp(buf[i].station_id, st->station_id, sizeof buf[i].station_id) == 0 &&
            buf[i].request_seq == seq && (!st->session_id || palp_cli_station_from_server(st, st->reply_r, &info[i]))) {
          *out = buf[i];
          if (pub) *pub = info[i].publication_handle;
          result = buf[i].status == palp_REPLY_ACCEPTED;
        }
    int64_t now = palp_dds_now_ns();
    if (result >= 0 || now >= end_ns) break;
    if (stoppable && stopped(st)) {
      result = -2;
      break;
    }
    dds_waitset_wait(ws, NULL, 0, end_ns - now < DDS_MSECS(50) ? end_ns - now : DDS_MSECS(50));
  }
  dds_delete(rc);
  dds_delete(ws);
  return result;
}

static int await_reply(palp_cli_station *st, int64_t end_ns, palp_SessionReply *out, dds_instance_handle_t *pub) {
  return await_reply_to(st, st->request_seq, end_ns, 1, out, pub);
}

/* ---- the session's server (palp_cli_server_bind, 2026-12-06) ------------------------------------- */

enum { FROM_GONE = -1, FROM_OTHER = 0, FROM_SERVER = 1 };

/* Takes what discovery announced of the writers on the domain (palp_cli_station.publications_r) since
 * the last call and keeps the server's among them. The announcement comes before the writer's first
 * sample, and stays until taken after the writer left: the writer of a sample the server wrote just
 * before it deleted it (its score, written by a writer of its own as it shuts down, or the session's
 * last samples as its publisher goes at the close) is known for the server's when taken, where the
 * matched writers no longer have it. */
/* Whether an announced writer of the server's is one this station reads: in the session's partition, or
 * one of the global topics it reads (the state, the status, the replies). A server announces the writers
 * of all its sessions: kept, they would push this session's out of the PALP_CLI_SERVER_WRITERS kept. */
static int read_here(const palp_cli_station *st, const dds_builtintopic_endpoint_t *ep) {
  static const palp_dds_topic_kind global[] = {PALP_TOPIC_SESSION_STATE, PALP_TOPIC_SERVER_STATUS,
                                               PALP_TOPIC_SESSION_REPLY};
  for (size_t k = 0; k < sizeof global / sizeof global[0]; k++)
    if (ep->topic_name && strcmp(ep->topic_name, palp_dds_topic_name(global[k])) == 0) return 1;
  uint32_t n = 0;
  char **ps = NULL;
  int here = 0;
  if (!ep->qos || !dds_qget_partition(ep->qos, &n, &ps)) return 0;
  for (uint32_t i = 0; i < n; i++) {
    here |= ps[i] && strcmp(ps[i], st->partition) == 0;
    dds_free(ps[i]);
  }
  dds_free(ps);
  return here;
}

/* Full, the oldest goes: the server's writers get new handles each time this station finds its
 * participant again after a lapse of its lease (a stall), and the old ones write no more. */
static void keep_mine(palp_cli_server_bind *b, dds_instance_handle_t pub) {
  if (b->n_mine < PALP_CLI_SERVER_WRITERS) b->mine[b->n_mine++] = pub;
  else b->mine[b->mine_next++ % PALP_CLI_SERVER_WRITERS] = pub;
}

static int is_mine(const palp_cli_server_bind *b, dds_instance_handle_t pub) {
  for (int i = 0; i < b->n_mine; i++)
    if (b->mine[i] == pub) return 1;
  return 0;
}

static void take_announcements(palp_cli_station *st) {
  palp_cli_server_bind *b = &st->bind;
  if (st->publications_r <= 0 || !b->bound) return;
  void *ptr[16] = {NULL};
  dds_sample_info_t info[16];
  int n;
  while ((n = dds_take(st->publications_r, ptr, info, 16, 16)) > 0) {
    for (int i = 0; i < n; i++) {
      const dds_builtintopic_endpoint_t *ep = ptr[i];
      if (!info[i].valid_data || memcmp(&ep->participant_key, &b->server, sizeof b->server) != 0 || !read_here(st, ep))
        continue;
      if (!is_mine(b, info[i].instance_handle)) keep_mine(b, info[i].instance_handle);
    }
    dds_return_loan(st->publications_r, ptr, n);
  }
}

/* Whose writer pub is: the server's, another participant's (*who names it), or gone before the station
 * knew it. Found once per writer, then kept by its handle (never reused in a process): the server's
 * from discovery's announcements (take_announcements), another's asked of the reader it matched. */
static int writer_verdict(palp_cli_station *st, dds_entity_t reader, dds_instance_handle_t pub, const dds_guid_t **who) {
  palp_cli_server_bind *b = &st->bind;
  *who = NULL;
  if (!pub) return FROM_GONE;
  if (is_mine(b, pub)) return FROM_SERVER;
  for (int i = 0; i < PALP_CLI_OTHER_WRITERS; i++)
    if (b->other[i] == pub) {
      *who = &b->other_pp[i];
      return FROM_OTHER;
    }
  take_announcements(st);
  if (is_mine(b, pub)) return FROM_SERVER;
  dds_guid_t g;
  if (palp_dds_writer_participant(reader, pub, &g) < 0) return FROM_GONE;
  if (memcmp(&g, &b->server, sizeof g) == 0) { /* no announcement reader, or not taken yet */
    keep_mine(b, pub);
    return FROM_SERVER;
  }
  const unsigned k = b->other_next++ % PALP_CLI_OTHER_WRITERS;
  b->other[k] = pub;
  b->other_pp[k] = g;
  *who = &b->other_pp[k];
  return FROM_OTHER;
}

/* A sample dropped: counted, and its participant (NULL: a writer already gone) kept if the first. */
static void ignored(palp_cli_server_bind *b, const dds_guid_t *who) {
  if (!b->ignored++) b->first_ignored_ns = palp_dds_now_ns();
  if (who && !b->have_other) b->first_other = *who, b->have_other = 1;
}

int palp_cli_station_from_server(palp_cli_station *st, dds_entity_t reader, const dds_sample_info_t *info) {
  palp_cli_server_bind *b = &st->bind;
  if (!b->bound) return 1;
  const dds_guid_t *who;
  if (writer_verdict(st, reader, info->publication_handle, &who) == FROM_SERVER) {
    b->heard_ns = palp_dds_now_ns();
    return 1;
  }
  ignored(b, who);
  return 0;
}

/* ---- the server's own catalogue entry and exercise (palp_cli_server_only, review s83 #1) ----------- */

/* [receive thread] The phantom's samples from the writers in so->pub pass; the phantom's from any other
 * writer are dropped and counted; another phantom's are dropped uncounted (not this session's: other
 * servers' entries). Both types' key, phantom_id, comes first. */
static bool server_only_accepts(const void *sample, const dds_sample_info_t *si, void *arg) {
  palp_cli_server_only *so = arg;
  if (*(const uint32_t *)sample != so->phantom) return false;
  for (int i = 0; i < so->n; i++)
    if (so->pub[i] == si->publication_handle) return true;
  unsigned long long none = 0;
  atomic_compare_exchange_strong(&so->first_refused, &none, (unsigned long long)si->publication_handle);
  atomic_fetch_add_explicit(&so->refused, 1, memory_order_relaxed);
  return false;
}
_Static_assert(offsetof(palp_Phantom, phantom_id) == 0 && offsetof(palp_Exercise, phantom_id) == 0,
               "the phantom id first");

/* What so's filter dropped since the last look, added to the session's count (bind.ignored) and its first
 * participant named, as palp_cli_station_from_server does for the session's streams. */
static void server_only_count(palp_cli_station *st, palp_cli_server_only *so) {
  const uint64_t refused = atomic_load(&so->refused);
  if (refused <= so->counted) return;
  const uint64_t fresh = refused - so->counted;
  so->counted = refused;
  if (!st->bind.ignored) st->bind.first_ignored_ns = palp_dds_now_ns();
  st->bind.ignored += fresh;
  dds_guid_t g;
  const dds_instance_handle_t first = (dds_instance_handle_t)atomic_load(&so->first_refused);
  if (!st->bind.have_other && so->reader > 0 && first && palp_dds_writer_participant(so->reader, first, &g) == 0)
    st->bind.first_other = g, st->bind.have_other = 1;
}

static void server_only_close(palp_cli_station *st, palp_cli_server_only *so) {
  if (so->reader > 0) server_only_count(st, so);
  if (so->reader > 0) dds_delete(so->reader);
  if (so->topic > 0) dds_delete(so->topic);
  so->reader = so->topic = 0;
  so->n = 0;
  atomic_store(&so->refused, 0);
  atomic_store(&so->first_refused, 0);
  so->counted = 0;
}

/* so reading kind's samples of phantom from the session's server alone: its writers of the topic are those
 * known_by (a reader of the topic that has long matched every writer of it) has matched from the server's
 * participant. Made anew when that set grew (a server writer matched later than the last look: its samples
 * were dropped meanwhile, and a new transient-local reader is sent them again); looked at most every
 * 0.2 s unless asked (force). 0, or a negative code; so->reader 0 while no server writer is matched. */
static int server_only_open(palp_cli_station *st, palp_cli_server_only *so, palp_dds_topic_kind kind,
                            dds_entity_t known_by, uint32_t phantom, int force) {
  const int64_t now = palp_dds_now_ns();
  if (so->phantom != phantom) server_only_close(st, so);
  if (!force && now - so->looked_ns < 200000000) return 0;
  so->looked_ns = now;
  dds_instance_handle_t h[32], mine[PALP_CLI_SERVER_ONLY_WRITERS];
  const dds_return_t m = known_by > 0 ? dds_get_matched_publications(known_by, h, 32) : 0;
  int n = 0, fresh = so->reader <= 0;
  for (int i = 0; i < (m < 32 ? m : 32) && n < PALP_CLI_SERVER_ONLY_WRITERS; i++) {
    dds_guid_t g;
    if (palp_dds_writer_participant(known_by, h[i], &g) < 0 || memcmp(&g, &st->bind.server, sizeof g) != 0) continue;
    mine[n++] = h[i];
    int had = 0;
    for (int k = 0; k < so->n; k++) had |= so->pub[k] == h[i];
    fresh |= !had;
  }
  if (!fresh || n == 0) return 0;
  server_only_close(st, so); /* the filter's set changes only with no reader of it */
  memcpy(so->pub, mine, (size_t)n * sizeof *mine);
  so->n = n;
  so->phantom = phantom;
  so->looked_ns = now;
  const dds_entity_t tp = palp_dds_create_topic(st->pp, kind);
  if (tp < 0) return PALP_EIO;
  struct dds_topic_filter flt = {.mode = DDS_TOPIC_FILTER_SAMPLE_SAMPLEINFO_ARG,
                                 .f = {.sample_sampleinfo_arg = server_only_accepts}, .arg = so};
  const dds_entity_t r = dds_set_topic_filter_extended(tp, &flt) == 0 ? palp_dds_create_reader(st->pp, tp, kind) : -1;
  if (r < 0) {
    dds_delete(tp);
    return PALP_EIO;
  }
  so->topic = tp;
  so->reader = r;
  return 0;
}

int palp_cli_station_foreign_news(palp_cli_station *st, char *line, size_t len, char *who, size_t wholen) {
  palp_cli_server_bind *b = &st->bind;
  if (len) line[0] = 0;
  if (wholen) who[0] = 0;
  /* Held until the server is heard after the first of them, or the session is over: a restarted server's
   * reply, status or state comes before its restart shows, and a restart suspected and unresolved may be
   * one (review s83 #5: a trainee was told to report an intrusion as her server restarted). */
  if (!b->ignored || b->told) return 0;
  const int over = st->closed_seen || b->left;
  const int heard_since = b->heard_ns > b->first_ignored_ns;
  if (!over && !b->restarted && (b->suspect_ns || !heard_since)) return 0;
  b->told = 1;
  char pp[64] = "a writer already gone";
  if (b->have_other) palp_dds_participant_text(&b->first_other, pp, sizeof pp);
  snprintf(who, wholen, "%s", pp);
  const unsigned long long n = (unsigned long long)b->ignored;
  if (b->restarted)
    snprintf(line, len, "ignored %llu sample%s of session %u from %s: the restarted server's, not this session's "
                        "server's", n, n == 1 ? "" : "s", st->session_id, pp);
  else if (heard_since && !b->suspect_ns)
    snprintf(line, len, "ignored %llu sample%s of session %u from %s, which is not this session's server: another "
                        "program writes into your session (tell your instructor); what you feel and are told comes "
                        "from the server alone", n, n == 1 ? "" : "s", st->session_id, pp);
  else /* over with its server silent since: a restarted server's, perhaps, whose restart did not show */
    snprintf(line, len, "ignored %llu sample%s of session %u from %s, which is not this session's server (silent "
                        "since: perhaps it restarted); what you felt and were told came from the server alone", n,
             n == 1 ? "" : "s", st->session_id, pp);
  return 1;
}

/* The session's endpoints matched by the server's before the join returns. Contacts are
 * best-effort and volatile (idl/palp_dds.c): a press written before the server's reader
 * has matched the station's writer is lost without a trace, and feedback sent before the
 * station's reader matched never arrives. On a machine busy enough to slow discovery
 * (seen in the test suite: a keyboard trainee's whole 3 s press lost, its feedback 0 N)
 * the trainee would press into nothing. Waits until every endpoint the station made has
 * a match, or end_ns (the join's timeout); then it goes on either way, the endpoints
 * matching when discovery catches up. */
static void await_matched(palp_cli_station *st, int64_t end_ns) {
  for (;;) {
    int ready = 1;
    if (st->contact_w > 0) {
      dds_publication_matched_status_t m;
      ready &= dds_get_publication_matched_status(st->contact_w, &m) == 0 && m.current_count > 0;
    }
    const dds_entity_t rd[3] = {st->feedback_r, st->local_model_r, st->deformation_r};
    for (int k = 0; k < 3; k++)
      if (rd[k] > 0) {
        dds_subscription_matched_status_t m;
        ready &= dds_get_subscription_matched_status(rd[k], &m) == 0 && m.current_count > 0;
      }
    /* stopped: the join stands, and the caller's loop, seeing the stop, leaves the session */
    if (ready || palp_dds_now_ns() >= end_ns || stopped(st)) return;
    nap(0.005);
  }
}

/* The finger-sample reader's filter (DDS receive thread): this station's session and a finger it may
 * have. st->session_id is set before the reader exists and cleared after it is deleted. */
static bool own_finger_sample(const void *sample, void *arg) {
  const palp_FingerSample *m = sample;
  const palp_cli_station *st = arg;
  return m->session_id == st->session_id && m->finger < PALP_CLI_MAX_FINGERS;
}

static bool own_local_model(const void *sample, void *arg) {
  const palp_LocalModel *m = sample;
  const palp_cli_station *st = arg;
  return m->session_id == st->session_id && m->finger < PALP_CLI_MAX_FINGERS;
}

int palp_cli_station_join(palp_cli_station *st, const palp_cli_join *j, char *err, size_t errlen) {
  int64_t end = palp_dds_now_ns() + (int64_t)(j->timeout * 1e9);
  palp_SessionReply r;
  memset(&r, 0, sizeof r);
  int64_t asked = 0;
  dds_instance_handle_t replier = 0;
  server_only_close(st, &st->exercise_srv); /* the last session's server's */
  memset(&st->bind, 0, sizeof st->bind); /* whoever accepts this JOIN is the session's server */
  /* The phantom's exercise reader made before the JOIN goes: its exercise (transient-local) is sent
   * while the server answers, as to the reader made at the station's start before 2026-12-07. */
  if (j->phantom_id && exercise_reader(st, j->phantom_id) < 0)
    return fail(err, errlen, PALP_EIO, "cannot create the exercise reader");
  for (;;) {
    asked = palp_dds_now_ns();
    if (send_request(st, j, palp_OP_JOIN, NULL) < 0) return fail(err, errlen, PALP_EIO, "cannot send the join request");
    int got = await_reply(st, end, &r, &replier);
    if (got == 1) break;
    if (got == -2) return fail_stopped(err, errlen);
    if (got < 0) {
      char hint[PALP_DDS_HINT_MAX];
      palp_dds_unanswered_hint(st->pp, &st->sec, hint, sizeof hint);
      return fail(err, errlen, PALP_EIO, "no answer from palp-server within %.1f s (is it running on this domain?)%s",
                  j->timeout, hint);
    }
    /* A viewer may start before the trainee it follows: ask again until the timeout. */
    int retry = j->role != palp_ROLE_TRAINEE && strncmp(r.reason, "no open session", 15) == 0;
    if (!retry || palp_dds_now_ns() + DDS_MSECS(250) >= end)
      /* the server's words, escaped as the log escapes a peer's fields: a forged reply's escape
       * sequence must not reach the terminal the error is written to */
      return fail(err, errlen, PALP_EINVAL, "join rejected: %s", PALP_PRINTABLE_LONG(r.reason));
    for (int k = 0; k < 5; k++) { /* 0.25 s, the stop flag looked at every 50 ms */
      if (stopped(st)) return fail_stopped(err, errlen);
      nap(0.05);
    }
  }
  /* The server's physics rate paces the contact samples and the haptic thread's horizon:
   * a rate outside the server's own bounds (10..10000 Hz, server/config.c) is no server's,
   * and one of 1e-300 Hz crashed the haptic thread (a division by a sample interval of 0). */
  if (!(r.tick_rate_hz >= PALP_CLI_PHYSICS_RATE_MIN && r.tick_rate_hz <= PALP_CLI_PHYSICS_RATE_MAX))
    return fail(err, errlen, PALP_EINVAL, "join refused: the server's physics rate %g Hz is outside %g..%g Hz",
                r.tick_rate_hz, PALP_CLI_PHYSICS_RATE_MIN, PALP_CLI_PHYSICS_RATE_MAX);
  /* The session's server is the participant that accepted: its writers, and no other participant's,
   * are read in the session (palp_cli_station_from_server). Behind palp-netem that is the relay, which
   * writes the reply and the session's topics from its one participant (tools/netem/netem.c). */
  if (palp_dds_writer_participant(st->reply_r, replier, &st->bind.server) < 0)
    return fail(err, errlen, PALP_EIO, "the server that accepted the join left the domain at once");
  st->bind.bound = 1;
  keep_mine(&st->bind, replier);
  st->bind.heard_ns = palp_dds_now_ns();
  st->session_id = r.session_id;
  atomic_store_explicit(&st->status_session_id, r.session_id, memory_order_relaxed);
  st->phantom_id = r.phantom_id;
  st->tick_rate_hz = r.tick_rate_hz;
  /* the server's refusals are this session's: the last one's count, which --rejoin left here, kept the
   * first refusals of the new session from being told (review s83 #12) */
  st->rejected_samples = st->rejected_said = 0;
  st->rejected_said_ns = 0;
  if (state_reader(st, 1) < 0 || exercise_reader(st, r.phantom_id) < 0)
    return fail(err, errlen, PALP_EIO, "cannot create the session's state and exercise readers");
  st->join_asked_ns = asked;
  snprintf(st->session_trainee, sizeof st->session_trainee, "%s", j->role == palp_ROLE_TRAINEE ? st->station_id : "");
  st->session_ticks = 0;
  st->has_last_join = 1;
  st->last_check_ns = st->stall_end_ns = st->doubt_until_ns = 0;
  st->closed_seen = 0;
  st->next_held_ask_ns = 0;
  st->next_viewer_ask_ns = palp_dds_now_ns() + 1000000000; /* the state may not count it yet */
  st->viewer_stalls = st->stalls;
  st->viewer_stall_asks = 0;
  memset(&st->log, 0, sizeof st->log);
  memset(&st->log_said, 0, sizeof st->log_said);
  snprintf(st->partition, sizeof st->partition, "%s", r.partition);
  st->pub = palp_dds_session_publisher(st->pp, st->partition);
  st->sub = palp_dds_session_subscriber(st->pp, st->partition);
  if (st->pub < 0 || st->sub < 0) return fail(err, errlen, PALP_EIO, "cannot create the session's publisher/subscriber");
  if (j->role == palp_ROLE_TRAINEE)
    st->contact_w = palp_dds_create_writer(st->pub, st->topic[PALP_TOPIC_CONTACT], PALP_TOPIC_CONTACT);
  else { /* a viewer reads the trainee's contacts through a topic entity of its own, filtered to the session */
    st->contact_topic = palp_dds_create_topic(st->pp, PALP_TOPIC_CONTACT);
    struct dds_topic_filter flt = {.mode = DDS_TOPIC_FILTER_SAMPLE_ARG, .f = {.sample_arg = own_session}, .arg = st};
    st->contact_r = st->contact_topic > 0 && dds_set_topic_filter_extended(st->contact_topic, &flt) == 0
                        ? stream_reader(st, st->contact_topic, PALP_TOPIC_CONTACT)
                        : -1;
  }
  if (j->want_feedback && !(j->local_models_only && j->role == palp_ROLE_TRAINEE))
    st->feedback_r = stream_reader(st, st->topic[PALP_TOPIC_FEEDBACK], PALP_TOPIC_FEEDBACK);
  if (j->want_feedback && j->role == palp_ROLE_TRAINEE) {
    /* The haptic loop needs only the newest model, but the exercise's coverage counts every step
     * the review samples: a station whose main thread a busy machine delays past one physics
     * period (4 ms at 250 Hz) lost models from a keep-last-1 history (eve's light coverage read
     * 1.6 points under the review's with her machine loaded; docs/station.md). The writer keeps
     * one and sends best-effort, so a deeper reader history changes nothing on the wire. */
    dds_qos_t *q = palp_dds_qos(PALP_TOPIC_LOCAL_MODEL);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, PALP_CLI_MODEL_DEPTH);
    /* A dispose carries no sample for the filter (Cyclone 0.10 makes its instance unfiltered): a
     * flood of disposes of made-up keys is held to PALP_CLI_STREAM_INSTANCES (best-effort: a
     * rejected sample is dropped, never retried), as the server holds its contacts. */
    dds_qset_resource_limits(q, DDS_LENGTH_UNLIMITED, PALP_CLI_STREAM_INSTANCES, DDS_LENGTH_UNLIMITED);
    /* Filtered as the finger samples below: its topic entity is this reader's alone. */
    struct dds_topic_filter lflt = {.mode = DDS_TOPIC_FILTER_SAMPLE_ARG, .f = {.sample_arg = own_local_model}, .arg = st};
    st->local_model_r = dds_set_topic_filter_extended(st->topic[PALP_TOPIC_LOCAL_MODEL], &lflt) == 0
                            ? dds_create_reader(st->sub, st->topic[PALP_TOPIC_LOCAL_MODEL], q, NULL)
                            : -1;
    dds_delete_qos(q);
    /* ... and from a server that sends them (session 71), the assessment's own finger samples,
     * touched triangles named: the coverage is then the review's. The same depth: 320 ms of
     * samples at 100 Hz. Without them (a server or permissions that predate the topic) the
     * coverage is approximated from the local models. */
    if (st->topic[PALP_TOPIC_FINGER_SAMPLE] > 0) {
      /* On a topic entity of its own that carries a filter: a sample of another session or of a
       * finger past the last never becomes an instance in this reader (a flood of made-up keys in
       * an unsecured classroom costs the station nothing; server/session.c filters contacts so). */
      const dds_entity_t tp = st->finger_sample_topic = palp_dds_create_topic(st->pp, PALP_TOPIC_FINGER_SAMPLE);
      struct dds_topic_filter flt = {.mode = DDS_TOPIC_FILTER_SAMPLE_ARG, .f = {.sample_arg = own_finger_sample}, .arg = st};
      q = palp_dds_qos(PALP_TOPIC_FINGER_SAMPLE);
      dds_qset_history(q, DDS_HISTORY_KEEP_LAST, PALP_CLI_MODEL_DEPTH);
      dds_qset_resource_limits(q, DDS_LENGTH_UNLIMITED, PALP_CLI_STREAM_INSTANCES, DDS_LENGTH_UNLIMITED);
      st->finger_sample_r = tp > 0 && dds_set_topic_filter_extended(tp, &flt) == 0 ? dds_create_reader(st->sub, tp, q, NULL) : -1;
      dds_delete_qos(q);
      if (st->finger_sample_r < 0) st->finger_sample_r = 0;
    }
  }
  if (j->want_deformation)
    st->deformation_r = stream_reader(st, st->topic[PALP_TOPIC_DEFORMATION], PALP_TOPIC_DEFORMATION);
  if (j->role == palp_ROLE_TRAINEE) { /* issue 13: findings, any session (free practice too) */
    st->finding_w = palp_dds_create_writer(st->pub, st->topic[PALP_TOPIC_FINDING], PALP_TOPIC_FINDING);
    st->finding_status_r =
        palp_dds_create_reader(st->sub, st->topic[PALP_TOPIC_FINDING_STATUS], PALP_TOPIC_FINDING_STATUS);
    if (st->topic[PALP_TOPIC_DEBRIEF] > 0)
      st->debrief_r = palp_dds_create_reader(st->sub, st->topic[PALP_TOPIC_DEBRIEF], PALP_TOPIC_DEBRIEF);
    if (st->topic[PALP_TOPIC_DEBRIEF_SCORE] > 0)
      st->debrief_score_r =
          palp_dds_create_reader(st->sub, st->topic[PALP_TOPIC_DEBRIEF_SCORE], PALP_TOPIC_DEBRIEF_SCORE);
    st->next_mark_id = 1;
  }
  /* Every role: her session's own losses in the server's log (session 69); without them (a server or
   * permissions that predate the topic) the station counts the server's, from its status. */
  if (st->topic[PALP_TOPIC_SESSION_LOG] > 0) {
    st->session_log_r = palp_dds_create_reader(st->sub, st->topic[PALP_TOPIC_SESSION_LOG], PALP_TOPIC_SESSION_LOG);
    if (st->session_log_r < 0) st->session_log_r = 0;
  }
  if (st->contact_w < 0 || st->contact_r < 0 || st->feedback_r < 0 || st->deformation_r < 0 || st->local_model_r < 0 ||
      st->finding_w < 0 || st->finding_status_r < 0 || st->debrief_r < 0 || st->debrief_score_r < 0)
    return fail(err, errlen, PALP_EIO, "cannot create the session's readers/writers");
  await_matched(st, end);
  return 0;
}

/* A gap over PALP_CLI_STALL_S between since and now [ns] was a stall of this process:
 * counted and told (report_stall), and a lapse of the server's lease seen right after it
 * is waited for longer (below). The server may have lost this station meanwhile and hold
 * its session: its state then says so, and the JOIN goes again from there (the one
 * mechanism for a station's stall and a server's). */
static void note_stall(palp_cli_station *st, int64_t since, int64_t now) {
  if (!since || now - since <= (int64_t)(PALP_CLI_STALL_S * 1e9)) return;
  st->stall_s = (double)(now - since) * 1e-9;
  st->stall_end_ns = now;
  st->stalls++;
  st->next_held_ask_ns = 0; /* a held state read now is answered now */
}

/* This station ran at now [ns]: a gap since its last sign of life is a stall (note_stall). */
static void station_alive(palp_cli_station *st, int64_t now) {
  note_stall(st, st->last_check_ns, now);
  st->last_check_ns = now;
}

void palp_cli_station_alive(palp_cli_station *st) { station_alive(st, palp_dds_now_ns()); }

int palp_cli_station_exercise(palp_cli_station *st, uint32_t phantom_id, double timeout, palp_Exercise *out) {
  const int64_t end = palp_dds_now_ns() + (int64_t)(timeout * 1e9);
  for (;;) {
    /* A caller that waits here (a timeout > 0) before its loop's first
     * palp_cli_station_session_closed keeps the loop's clock: a stop meanwhile is a stall like
     * one in the loop (counted, and the server's lapsed lease after it waited for). Until
     * 2026-12-06 a trainee station spent its first second after a join here on a phantom without
     * an exercise (test haptic_station_stalled once stopped it inside this wait: it blamed the
     * server); its haptic loop now looks once a turn, timeout 0 (client/main.c). */
    const int64_t now = palp_dds_now_ns();
    station_alive(st, now);
    palp_Exercise e;
    void *ptr[1] = {&e};
    dds_sample_info_t info;
    /* read, not take: it stays for the next join (transient-local, one per phantom) */
    dds_instance_handle_t ih;
    memset(&e, 0, sizeof e);
    e.phantom_id = phantom_id;
    /* only the joined phantom's is read (exercise_reader); in a session, only its server's (review s83
     * #1): exercise_r, made before the JOIN, has matched the server's writer by now, and the reader read
     * takes that writer's samples alone (server_only_open; looked for again every 0.2 s meanwhile) */
    dds_entity_t rd = st->exercise_r;
    if (st->bind.bound && rd > 0 && phantom_id == st->exercise_phantom) {
      (void)server_only_open(st, &st->exercise_srv, PALP_TOPIC_EXERCISE, st->exercise_r, phantom_id, 0);
      rd = st->exercise_srv.reader; /* 0 (nothing read) until the server's writer is known */
      server_only_count(st, &st->exercise_srv);
    }
    ih = rd > 0 && phantom_id == st->exercise_phantom ? dds_lookup_instance(rd, &e) : DDS_HANDLE_NIL;
    if (ih != DDS_HANDLE_NIL && dds_read_instance(rd, ptr, &info, 1, 1, ih) > 0 && info.valid_data) {
      *out = e;
      out->name[sizeof out->name - 1] = 0;
      out->title[sizeof out->title - 1] = 0;
      out->instructions[sizeof out->instructions - 1] = 0;
      if (phantom_id == st->phantom_id) st->in_exercise = 1;
      return 1;
    }
    if (now >= end) return 0;
    if (stopped(st)) return PALP_CLI_ESTOPPED;
    nap(0.02);
  }
}

static int send_finding(palp_cli_station *st, palp_FindingOp op, uint32_t mark_id, palp_vec3 p, double t) {
  if (st->finding_w <= 0) return PALP_EINVAL;
  palp_Finding f;
  memset(&f, 0, sizeof f);
  f.session_id = st->session_id;
  f.mark_id = mark_id;
  f.op = op;
  f.point = (palp_Vec3){p.x, p.y, p.z};
  f.time = t;
  return dds_write(st->finding_w, &f) < 0 ? PALP_EIO : 0;
}

int palp_cli_station_mark(palp_cli_station *st, palp_vec3 point, double t) {
  const uint32_t id = st->next_mark_id;
  const int rc = send_finding(st, palp_FINDING_MARK, id, point, t);
  if (rc < 0) return rc;
  st->next_mark_id++;
  return (int)id;
}

int palp_cli_station_withdraw(palp_cli_station *st, uint32_t mark_id) {
  return send_finding(st, palp_FINDING_WITHDRAW, mark_id, (palp_vec3){0, 0, 0}, 0);
}

int palp_cli_station_finding_status(palp_cli_station *st, palp_FindingStatus *out) {
  if (st->finding_status_r <= 0) return 0;
  int got = 0;
  palp_FindingStatus s;
  void *ptr[1] = {&s};
  dds_sample_info_t info;
  while (dds_take(st->finding_status_r, ptr, &info, 1, 1) > 0)
    if (info.valid_data && palp_cli_station_from_server(st, st->finding_status_r, &info)) *out = s, got = 1;
  if (got) out->reason[sizeof out->reason - 1] = 0;
  return got;
}

int palp_cli_station_debrief(palp_cli_station *st, double timeout, palp_Debrief *out, palp_DebriefLesion *lesions,
                             char *err, size_t errlen) {
  if (st->debrief_r <= 0) return 0;
  const int64_t end = palp_dds_now_ns() + (int64_t)(timeout * 1e9);
  for (;;) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    int got = 0, rc = 0;
    /* Loaned: the sample holds a sequence, and the loan frees it. The server writes one per
     * session; anything else in this partition's instance is checked like any sample. */
    while (dds_take(st->debrief_r, ptr, &info, 1, 1) > 0) {
      const palp_Debrief *d = ptr[0];
      if (info.valid_data && d->session_id == st->session_id && palp_cli_station_from_server(st, st->debrief_r, &info)) {
        const uint32_t n = d->lesion._length;
        if (!palp_dds_debrief_ok(d)) {
          rc = fail(err, errlen, PALP_EPARSE, "a malformed debrief (level %d, %u lesions listed of %u, %u found): ignored",
                    (int)d->level, n, d->lesions, d->found);
        } else {
          *out = *d;
          out->reason[sizeof out->reason - 1] = 0;
          for (uint32_t i = 0; i < n; i++) lesions[i] = d->lesion._buffer[i];
          out->lesion._buffer = lesions;
          out->lesion._release = false;
          out->lesion._maximum = PALP_DEBRIEF_MAX_LESIONS;
          got = 1, rc = 0;
        }
      }
      dds_return_loan(st->debrief_r, ptr, 1);
      ptr[0] = NULL;
    }
    if (got) return 1;
    if (rc < 0) return rc;
    if (palp_dds_now_ns() >= end) return 0;
    if (stopped(st)) return fail_stopped(err, errlen);
    nap(0.02);
  }
}

int palp_cli_station_debrief_score(palp_cli_station *st, double timeout, palp_SessionScore *out, char *err,
                                   size_t errlen) {
  if (st->debrief_score_r <= 0) return 0;
  const int64_t end = palp_dds_now_ns() + (int64_t)(timeout * 1e9);
  for (;;) {
    palp_SessionScore m;
    void *ptr[1] = {&m};
    dds_sample_info_t info;
    int got = 0, rc = 0;
    while (dds_take(st->debrief_score_r, ptr, &info, 1, 1) > 0) {
      if (!info.valid_data || m.session_id != st->session_id) continue;
      if (!palp_cli_station_from_server(st, st->debrief_score_r, &info)) continue; /* a false grade */
      /* bounded strings, but terminated only by the sender: made so before any use */
      m.log_uid[sizeof m.log_uid - 1] = m.exercise_name[sizeof m.exercise_name - 1] = 0;
      m.pattern[sizeof m.pattern - 1] = m.reason[sizeof m.reason - 1] = m.log_health[sizeof m.log_health - 1] = 0;
      if (!palp_dds_session_score_ok(&m)) {
        rc = fail(err, errlen, PALP_EPARSE, "a malformed score (status %d, score %g, %u found of %u): ignored",
                  (int)m.status, m.score, m.found, m.lesions);
        continue;
      }
      *out = m;
      got = 1, rc = 0;
    }
    if (got) return 1;
    if (rc < 0) return rc;
    if (palp_dds_now_ns() >= end) return 0;
    if (stopped(st)) return fail_stopped(err, errlen);
    nap(0.02);
  }
}

const char *palp_cli_score_text(const palp_SessionScore *m, char *buf, size_t len) {
  if (!len) return buf;
  if (m->status != palp_SCORE_GRADED) {
    snprintf(buf, len, "no score: %s", m->reason);
    return buf;
  }
  char work[256] = "";
  size_t n = 0;
  for (int i = 0; i < PALP_METRIC_COUNT && i < 6; i++)
    if (!m->passed[i])
      n += (size_t)snprintf(work + n, n < sizeof work ? sizeof work - n : 0, "%s%s", n ? ", " : " To work on: ",
                            palp_metric_to_work_on(i));
  /* Every metric passed and still not passed: the score alone is under the pass mark (which the wire
   * does not carry). A score not passed is floored to 0.1, as the review prints it: it never reads as
   * a mark on a whole tenth it missed (69.96 printed 70.0). */
  const int only_score = !m->pass && n == 0;
  if (only_score) n += (size_t)snprintf(work, sizeof work, " To work on: %s", PALP_SCORE_TO_WORK_ON);
  if (n) snprintf(work + n, n < sizeof work ? sizeof work - n : 0, ".");
  snprintf(buf, len, "score: %.1f of 100, %s (the automatic score, as the review gives it; your instructor grades "
                     "you).%s%s", palp_shown_tenths(m->score, NAN, m->pass), m->pass ? "passed" : "not passed", work,
           m->log_complete ? "" : " The session's log is incomplete: the score may be low.");
  return buf;
}

/* Writes rq (again, unless already_sent) every 0.3 s until the server answers its
 * request_seq or end_ns passes: 1 answered, 0 not (a write that fails ends the wait). */
static int ask_until_answered(palp_cli_station *st, const palp_SessionRequest *rq, int already_sent, int64_t end_ns) {
  palp_SessionReply r;
  for (int64_t t = palp_dds_now_ns(); t < end_ns; t = palp_dds_now_ns()) {
    if (!already_sent && dds_write(st->request_w, rq) < 0) return 0;
    already_sent = 0;
    const int64_t slice = t + 300000000;
    if (await_reply_to(st, rq->request_seq, slice < end_ns ? slice : end_ns, 0, &r, NULL) >= 0) return 1;
  }
  return 0;
}

int palp_cli_station_leave(palp_cli_station *st) {
  /* Right out of a stall (the user's interrupt is often what ends it) or soon after one:
   * the server may have lost this participant with its lease and not found it again yet,
   * and a LEAVE sent now would go with the participant. The accepted JOIN once more, and
   * its answer awaited: the server then knows the station again (it resumed the held
   * session, or it never lost it and answered again); then the LEAVE, until answered. */
  const int64_t now = palp_dds_now_ns();
  const int out_of_stall = st->last_check_ns && now - st->last_check_ns > (int64_t)(PALP_CLI_STALL_S * 1e9);
  const int after_stall = st->stall_end_ns && now - st->stall_end_ns < (int64_t)(PALP_CLI_LEAVE_WAIT_S * 1e9);
  const int careful =
      st->has_last_join && !st->closed_seen && st->last_join.role == palp_ROLE_TRAINEE && (out_of_stall || after_stall);
  int answered = 0;
  const int64_t end = now + (int64_t)(PALP_CLI_LEAVE_WAIT_S * 1e9);
  if (careful) {
    palp_SessionReply old;
    void *ptr[1] = {&old};
    dds_sample_info_t info;
    while (dds_take(st->reply_r, ptr, &info, 1, 1) > 0) { /* answers from before: not evidence */
    }
    /* Sent again every 0.3 s until answered, as a held session's JOIN is (session_closed):
     * a JOIN written while the server's reader is being matched to this writer again
     * can be lost for good (a volatile reader starts after what the writer had sent). */
    answered = ask_until_answered(st, &st->last_join, 0, end);
  }
  /* An explicit leave first, so the server can tell a goodbye from a crash;
   * then the disposal, which also ends the request's transient-local history. */
  palp_cli_join none = {.role = palp_ROLE_TRAINEE};
  palp_SessionRequest lv;
  send_request(st, &none, palp_OP_LEAVE, &lv);
  if (careful && answered) {
    /* The JOIN's answer is not proof that a LEAVE sent now arrives: answers are
     * transient-local, so one the server wrote a while ago can be delivered now (one was
     * taken 0.19 s after it was written), and a LEAVE the server has not fetched yet is
     * replaced by the disposal below (keep-last 1): the session then closed as "not back"
     * (server_stalled's wes, 2 runs in 16 under load, 2026-12-03; a LEAVE answered only
     * 0.19 s after it was sent in 1 run of 25 since). The LEAVE's own answer (to its new
     * request_seq, which no earlier reply carries) is proof, so the LEAVE goes again every
     * 0.3 s until answered, for at least 1 s, before the disposal. */
    const int64_t t0 = palp_dds_now_ns();
    answered = ask_until_answered(st, &lv, 1, end > t0 + 1000000000 ? end : t0 + 1000000000);
  }
  /* Unanswered (the server is stopped, starved or gone): the goodbye still goes, but the
   * user is told it may not arrive, so a session logged as "not back" is no surprise. */
  st->goodbye_unanswered = careful && !answered;
  st->bind.left = 1; /* nothing more comes: the samples ignored are said now (palp_cli_station_foreign_news) */
  palp_SessionRequest key;
  memset(&key, 0, sizeof key);
  snprintf(key.station_id, sizeof key.station_id, "%s", st->station_id);
  return dds_dispose(st->request_w, &key) < 0 ? PALP_EIO : 0;
}

/* ---- the server's session log, as this session sees it (session 68) ------------------------------ */

/* Takes the newest statuses; only the one whose server lists this session counts (session ids carry
 * their server's number, so one server's); then the session's own losses (session 69), each read
 * without the other where only one is there. */
static void watch_log(palp_cli_station *st, int64_t now) {
  if (!st->session_id) return;
  void *ptr[4] = {NULL};
  dds_sample_info_t info[4];
  int n;
  while (st->status_r > 0 && (n = dds_take(st->status_r, ptr, info, 4, 4)) > 0) {
    for (int i = 0; i < n; i++) {
      const palp_ServerStatus *m = ptr[i];
      if (!info[i].valid_data) continue;
      int mine = 0;
      for (uint32_t k = 0; k < m->sessions._length && !mine; k++) mine = m->sessions._buffer[k].session_id == st->session_id;
      if (mine && palp_cli_station_from_server(st, st->status_r, &info[i]))
        palp_dds_log_view_status(&st->log, m->log_written, m->log_shed, m->log_failed, now);
    }
    dds_return_loan(st->status_r, ptr, n);
  }
  if (st->session_log_r <= 0) return;
  palp_SessionLog m;
  void *one[1] = {&m};
  dds_sample_info_t mi;
  while (dds_take(st->session_log_r, one, &mi, 1, 1) > 0)
    if (mi.valid_data && m.session_id == st->session_id && palp_cli_station_from_server(st, st->session_log_r, &mi))
      palp_dds_log_view_session(&st->log, m.shed, m.failed, now);
}

int palp_cli_station_log_news(palp_cli_station *st, char *line, size_t len) {
  if (len) line[0] = 0;
  const palp_dds_log_view *v = &st->log;
  palp_cli_log_news *n = &st->log_said;
  const uint64_t lost = v->shed + v->failed;
  const int64_t now = palp_dds_now_ns();
  const int say_loss = v->losing && lost > n->said_lost &&
                       (!n->said_losing || now - n->said_ns >= (int64_t)(PALP_CLI_LOG_SAY_S * 1e9));
  const int say_again = n->said_losing && !v->losing;
  if (!say_loss && !say_again) return 0;
  /* A trainee tells her instructor; an instructor following the session is the one to act. */
  const int trainee = !st->has_last_join || st->last_join.role == palp_ROLE_TRAINEE;
  palp_dds_log_view_words(v, trainee, line, len);
  n->said_lost = lost;
  n->said_losing = say_loss;
  if (say_loss) n->said_ns = now;
  return 1;
}

/* A state of this session that another participant wrote (not its server: palp_cli_server_bind) is a
 * forgery or a restarted server's. Either way it is not this session's server speaking, and it neither
 * closes the session nor says the server is back. When it claims what a restart shows (this id now
 * another trainee's session, or its ticks fallen back) it is held as a suspicion, which the session's
 * server refutes by speaking (palp_cli_station_session_closed). */
static void suspect_restart(palp_cli_station *st, const palp_SessionState *m) {
  palp_cli_server_bind *b = &st->bind;
  if (b->suspect_ns) return;
  if (st->session_trainee[0] && strcmp(m->trainee_station, st->session_trainee) != 0)
    snprintf(b->suspect_reason, sizeof b->suspect_reason,
             "server lost (it restarted: session %u is now another trainee's session)", st->session_id);
  else if (m->ticks < st->session_ticks)
    snprintf(b->suspect_reason, sizeof b->suspect_reason,
             "server lost (it restarted: session %u was opened anew, at tick %llu after %llu)", st->session_id,
             (unsigned long long)m->ticks, (unsigned long long)st->session_ticks);
  else
    return; /* claims nothing a restart would: a forgery (a close, a state ahead) */
  b->suspect_ns = palp_dds_now_ns();
}

/* The answers to this station's JOIN in its session: any of its server's is a sign of it (a restart
 * suspected is refuted by it). A trainee's accepted JOIN refused by its server means the server no longer
 * holds the session (an open or held one is answered "accepted" again): it closed it while this station
 * did not run, and the answer says why, "session N closed: REASON" from the server's memory of closed
 * requests (review s83 #3). The refusal and its reason are kept (bind.refused) for
 * palp_cli_station_session_closed. A JOIN is answered so when the station sends it again (after a stall,
 * on a held state, ask_after_stall) and when DDS re-delivers it as the two find each other again. An
 * acceptance is never taken for proof of anything: it may be the old answer, re-delivered likewise. */
static void take_replies(palp_cli_station *st) {
  palp_SessionReply r;
  void *ptr[1] = {&r};
  dds_sample_info_t info;
  palp_cli_server_bind *b = &st->bind;
  const int trainee = st->has_last_join && st->last_join.role == palp_ROLE_TRAINEE;
  while (dds_take(st->reply_r, ptr, &info, 1, 1) > 0) {
    if (!info.valid_data || strncmp(r.station_id, st->station_id, sizeof r.station_id) != 0 ||
        !palp_cli_station_from_server(st, st->reply_r, &info) || !trainee || !st->session_id || b->refused ||
        r.request_seq != st->last_join.request_seq)
      continue;
    r.reason[sizeof r.reason - 1] = 0; /* terminated by the sender only */
    char head[32];
    const int n = snprintf(head, sizeof head, "session %u closed: ", st->session_id);
    if (r.status == palp_REPLY_ACCEPTED && r.session_id != st->session_id)
      /* it forgot the close and opened another session for the JOIN: the leave that follows ends it */
      snprintf(b->refused_reason, sizeof b->refused_reason,
               "closed while this station did not run (its JOIN, sent again, opened session %u)", r.session_id);
    else if (r.status == palp_REPLY_ACCEPTED)
      continue;
    else if (n > 0 && (size_t)n < sizeof head && strncmp(r.reason, head, (size_t)n) == 0)
      snprintf(b->refused_reason, sizeof b->refused_reason, "%s", r.reason + n);
    else /* a refusal that names no close: the server is there all the same, and holds no session for it */
      snprintf(b->refused_reason, sizeof b->refused_reason, "no longer held (its JOIN, sent again, refused: %.60s)",
               r.reason);
    b->refused = 1;
  }
}

/* The replies to a JOIN sent again, taken as they come (take_replies) until done(st) or end [ns]: the one
 * wait of restart_confirmed and ask_after_stall. */
static void await_replies(palp_cli_station *st, int64_t end, int (*done)(const palp_cli_station *)) {
  const dds_entity_t ws = dds_create_waitset(st->pp), rc = dds_create_readcondition(st->reply_r, DDS_ANY_STATE);
  dds_waitset_attach(ws, rc, 0);
  for (int64_t t = palp_dds_now_ns(); t < end && !done(st); t = palp_dds_now_ns()) {
    dds_waitset_wait(ws, NULL, 0, end - t);
    take_replies(st);
  }
  dds_delete(rc);
  dds_delete(ws);
}
static int heard_since_suspicion(const palp_cli_station *st) { return st->bind.heard_ns > st->bind.suspect_ns; }
static int join_refused(const palp_cli_station *st) { return st->bind.refused; }

/* A restart suspected (suspect_restart), and the session's server quiet for PALP_CLI_SERVER_QUIET_S (any
 * sample of its since the suspicion refutes it): the server is asked, by its accepted JOIN sent again,
 * which it answers again at once (server/server.c, handle_join), and its answer awaited here for up to
 * PALP_CLI_SERVER_ASK_S: nothing of the server's is coming meanwhile anyway. Unanswered, the session is
 * lost: 1 and the reason. */
static int restart_confirmed(palp_cli_station *st, int64_t now, char *reason, size_t len) {
  palp_cli_server_bind *b = &st->bind;
  if (!b->suspect_ns) return 0;
  take_replies(st);
  if (b->heard_ns > b->suspect_ns) { /* its server spoke since: a forgery */
    b->suspect_ns = 0;
    return 0;
  }
  const int64_t quiet_from = b->heard_ns > st->stall_end_ns ? b->heard_ns : st->stall_end_ns;
  /* at most one question every 0.3 s: a flood of forged states must not become a flood of JOINs */
  if (now - quiet_from < (int64_t)(PALP_CLI_SERVER_QUIET_S * 1e9) || now - b->asked_ns < 300000000 ||
      !st->has_last_join)
    return 0;
  dds_write(st->request_w, &st->last_join);
  b->asked_ns = palp_dds_now_ns();
  await_replies(st, b->asked_ns + (int64_t)(PALP_CLI_SERVER_ASK_S * 1e9), heard_since_suspicion);
  if (b->heard_ns > b->suspect_ns) {
    b->suspect_ns = 0;
    return 0;
  }
  if (reason) snprintf(reason, len, "%s", b->suspect_reason);
  return 1;
}

/* The server's lease lapsed as this station sees it (its session state not alive, its writer gone): a
 * crash, or a server its machine did not run for a while, or this station's own view of a lease it could
 * not renew while stalled itself. The server's state may come back (found again, its transient-local state
 * re-delivered): for PALP_CLI_SERVER_WAIT_S after a stall of ours that explains the lapse,
 * PALP_CLI_SERVER_GRACE_S otherwise; then it is lost. now: the start of the check [ns]. */
static void lapse_seen(palp_cli_station *st, int64_t now) {
  /* Stopped within this call, after its start: the lapse is likely our own stall's (seen in the suite: a
   * station stopped 1 s blamed the server). */
  note_stall(st, now, palp_dds_now_ns());
  /* ... but only a stall long enough to outlast the server's lease, and just over: a shorter one, or one
   * the server's traffic has renewed the lease since, is no cause of it (review s83 #2;
   * PALP_CLI_STALL_LAPSE_FRACTION). A stall ending within this call ends after now. */
  const int after_stall = st->stall_end_ns && st->stall_s >= PALP_CLI_STALL_LAPSE_FRACTION * PALP_DDS_SERVER_LEASE_S &&
                          now - st->stall_end_ns <= (int64_t)(PALP_CLI_STALL_LAPSE_SEEN_S * 1e9);
  if (!st->doubt_until_ns) {
    st->doubt_until_ns = now + (int64_t)((after_stall ? PALP_CLI_SERVER_WAIT_S : PALP_CLI_SERVER_GRACE_S) * 1e9);
    st->doubt_after_stall = after_stall;
  }
}

/* The doubt after a stall of this station's ran out with no state of the server's (review s83 #3). A
 * server alive all along may have closed the session meanwhile and retired its state (closed_retention: a
 * station stopped past station_grace + closed_retention, >= 15 s by default, is never sent it again), so
 * a trainee asks before it says "server lost": its accepted JOIN again, whose refusal take_replies keeps
 * (an open session's state would have come: the server republishes it every status period). Waits up to
 * PALP_CLI_LOST_ASK_S for it; 1 when refused (bind.refused_reason says why), 0 unanswered or not a trainee
 * (a viewer's JOIN may name no session). */
static int ask_after_stall(palp_cli_station *st) {
  if (st->bind.refused) return 1;
  if (!st->has_last_join || st->last_join.role != palp_ROLE_TRAINEE || dds_write(st->request_w, &st->last_join) < 0)
    return 0;
  await_replies(st, palp_dds_now_ns() + (int64_t)(PALP_CLI_LOST_ASK_S * 1e9), join_refused);
  return st->bind.refused;
}

/* A viewer's JOIN again (station.h, next_viewer_ask_ns). The server drops a visual station or observer
 * whose request writer's 0.5 s liveliness lapses, as it does a crashed one, and holds nothing for it: a
 * visual station its machine did not run for 0.8 s was left out of its session, and if it was the only
 * one the server stopped streaming the deformation (it streams it only to members who want it), its view
 * standing still until the session ended (test server_viewer_rejoin, 2026-12-08; palp-web had the same,
 * mended 2026-12-07). The accepted JOIN again, its request number kept, so that a server that still counts
 * this station answers it again harmlessly; naming its session, so that one that dropped it takes it back
 * into this session and not the phantom's newest (a viewer's first JOIN may name none). */
static int viewer_ask(palp_cli_station *st, int64_t now) {
  if (!st->has_last_join || st->last_join.role == palp_ROLE_TRAINEE || now < st->next_viewer_ask_ns) return 0;
  palp_SessionRequest rq = st->last_join;
  rq.session_id = st->session_id;
  if (dds_write(st->request_w, &rq) < 0) return 0;
  st->last_join = rq;
  st->viewer_asks++;
  st->next_viewer_ask_ns = now + 1000000000;
  return 1;
}

int palp_cli_station_session_closed(palp_cli_station *st, char *reason, size_t len) {
  const int64_t now = palp_dds_now_ns();
  station_alive(st, now);
  watch_log(st, now);
  take_announcements(st); /* kept small: what came since the last look */
  take_replies(st);        /* the server's refusal of the accepted JOIN, if it came (below) */
  palp_SessionState buf[4];
  void *ptr[4] = {&buf[0], &buf[1], &buf[2], &buf[3]};
  dds_sample_info_t info[4];
  int n, closed = 0;
  while ((n = dds_take(st->state_r, ptr, info, 4, 4)) > 0)
    for (int i = 0; i < n; i++) {
      if (info[i].valid_data) {
        if (buf[i].session_id != st->session_id) continue;
        buf[i].trainee_station[sizeof buf[i].trainee_station - 1] = 0; /* terminated by the sender only */
        if (!palp_cli_station_from_server(st, st->state_r, &info[i])) {
          suspect_restart(st, &buf[i]);
          continue;
        }
        /* Its server's own state. Behind palp-netem the server is the relay's participant, whose
         * states a restarted server's may be: the same two signs of a restart are read here too. */
        if (!st->session_trainee[0])
          snprintf(st->session_trainee, sizeof st->session_trainee, "%s", buf[i].trainee_station);
        if (strcmp(buf[i].trainee_station, st->session_trainee) != 0) {
          /* This session's id names another trainee's session: its server restarted and numbers its
           * sessions from 1 again. Taken for "back" (and not even doubted when the new server's state
           * came before the old one's lease lapsed), the station pressed on into that trainee's
           * session, its contacts applied there (session 77). Its own session is gone. */
          closed = st->bind.restarted = 1;
          if (reason)
            snprintf(reason, len, "server lost (it restarted: session %u is now another trainee's session)",
                     st->session_id);
          continue;
        }
        if (buf[i].ticks < st->session_ticks) {
          /* The same id and station, but a session that has stepped less than this one had: a
           * restarted server took this station's last JOIN again (the request topic keeps it) and
           * opened a new session for it, a fresh phantom, exercise and clock, its marks forgotten.
           * Taken for "back", the station went on into it unaware (session 77). Its session is gone. */
          closed = st->bind.restarted = 1;
          if (reason)
            snprintf(reason, len, "server lost (it restarted: session %u was opened anew, at tick %llu after %llu)",
                     st->session_id, (unsigned long long)buf[i].ticks, (unsigned long long)st->session_ticks);
          continue;
        }
        st->session_ticks = buf[i].ticks;
        st->rejected_samples = buf[i].rejected_samples;
        if (buf[i].phase == palp_PHASE_CLOSED) {
          closed = 1;
          if (reason) snprintf(reason, len, "%s", buf[i].reason);
        } else {
          /* The lapse can come with the state itself: Cyclone adds no invalid sample when the
           * instance's latest sample is unread as its writer goes. A state that came while this
           * station was stopped, read as it runs again after the server's lease lapsed, said "open"
           * and nothing ever ended the session (a trainee stopped 2 s, its server killed meanwhile,
           * pressed on into nothing for her whole --duration; review s83, the "second risk" of #3).
           * Its writer still matched: a dispose by another participant, not a lapse. */
          dds_guid_t g;
          const int lapsed = info[i].instance_state != DDS_IST_ALIVE &&
                             palp_dds_writer_participant(st->state_r, info[i].publication_handle, &g) < 0;
          if (lapsed) lapse_seen(st, now);
          else {
            if (st->doubt_until_ns && !st->doubt_after_stall) st->server_returns++; /* it, not we, was silent */
            st->doubt_until_ns = 0;                                                /* its server is there */
          }
          /* Open with a reason: the server waits for its trainee station, i.e. it lost this
           * one (its view of our leases lapsed while we, or it, did not run) and holds the
           * session for the same request. Ask again, once a second while it says so:
           * neither side may have seen a stall of its own (a server stopped 0.8 s lapses
           * only our writers' 0.5 s lease, and we see nothing of it). */
          if (buf[i].reason[0] && st->has_last_join && st->last_join.role == palp_ROLE_TRAINEE &&
              now >= st->next_held_ask_ns) {
            dds_write(st->request_w, &st->last_join);
            st->held_asks++;
            st->next_held_ask_ns = now + 1000000000;
          }
          /* A viewer the state does not count: dropped (its stall, or the server's) */
          if (st->has_last_join && st->last_join.role != palp_ROLE_TRAINEE &&
              (st->last_join.role == palp_ROLE_VISUAL ? buf[i].visual_count : buf[i].observer_count) == 0)
            viewer_ask(st, now);
        }
      } else if (info[i].instance_state != DDS_IST_ALIVE) {
        /* The server never disposes a state; a not-alive one means its writer's
         * lease lapsed (its participant's expired and Cyclone unregistered, and with
         * autodispose disposed, the instance). A crash, or a server its machine did not
         * run for a while, or this station's own view of a lease it could not renew
         * while stalled itself: the server's state may come back (found again, its
         * transient-local state re-delivered), for PALP_CLI_SERVER_WAIT_S after a stall
         * of ours, PALP_CLI_SERVER_GRACE_S otherwise; then it is lost. */
        /* The key is in the invalid sample (no dds_instance_get_key scan). */
        if (buf[i].session_id != st->session_id) continue;
        /* Disposed by another participant's writer: not its server's lease (a writer gone before it
         * was known may be the server's: its lapse is taken for one, as before). */
        const dds_guid_t *who;
        if (st->bind.bound && writer_verdict(st, st->state_r, info[i].publication_handle, &who) == FROM_OTHER) {
          ignored(&st->bind, who);
          continue;
        }
        lapse_seen(st, now);
      }
    }
  /* A viewer after a stall of its own: dropped or not, the JOIN again (the state may still count the
   * session's other viewers), at once and a second later (a lapse the server had not yet acted on when
   * the first came: answered as a member's, then dropped) */
  if (!closed && st->stalls != st->viewer_stalls && st->has_last_join && st->last_join.role != palp_ROLE_TRAINEE) {
    st->viewer_stalls = st->stalls;
    st->viewer_stall_asks = 2;
    st->next_viewer_ask_ns = 0;
  }
  if (!closed && st->viewer_stall_asks > 0 && viewer_ask(st, now)) st->viewer_stall_asks--;
  if (!closed && restart_confirmed(st, now, reason, len)) closed = st->bind.restarted = 1;
  /* The server, asked again (or sent the JOIN again by DDS as the two found each other), no longer holds
   * the session: its word for why, as soon as it came, rather than a lapse waited out */
  if (!closed && st->bind.refused) {
    closed = 1;
    if (reason) snprintf(reason, len, "%s", st->bind.refused_reason);
  }
  if (!closed && st->doubt_until_ns && now >= st->doubt_until_ns) {
    closed = 1;
    if (st->doubt_after_stall && ask_after_stall(st)) {
      if (reason) snprintf(reason, len, "%s", st->bind.refused_reason); /* the server answered: its reason */
    } else if (reason && st->doubt_after_stall)
      snprintf(reason, len, "server lost (liveliness lease expired; not back within %.0f s of this station's %.1f s stall)",
               PALP_CLI_SERVER_WAIT_S, st->stall_s);
    else if (reason)
      snprintf(reason, len, "server lost (liveliness lease expired; not back within %.1f s)", PALP_CLI_SERVER_GRACE_S);
  }
  st->closed_seen |= closed;
  return closed;
}

int palp_cli_station_find_phantom(palp_cli_station *st, const char *name, int64_t server_number,
                                  int64_t exclude_server, double timeout, uint32_t *out_id, char *err, size_t errlen) {
  /* Every entry once, as it comes (a search's own reader, its samples not read yet, a page at a time
   * until none is left): a plain read of 256 saw only the first 256 entries on every pass. */
  const dds_entity_t rd = search_reader(st);
  if (rd < 0) return fail(err, errlen, PALP_EIO, "cannot read the catalogue: %s", dds_strretcode(rd));
  const int64_t start = palp_dds_now_ns(), end = start + (int64_t)(timeout * 1e9);
  int64_t settle = INT64_MAX; /* after the first match, 0.3 s for the other servers' entries */
  uint32_t best = 0, best_sessions = UINT32_MAX;
  /* The names the catalogue had where this one was looked for (the servers asked for), to tell a user
   * who mistyped it: with none matched, the hint was DDS Security's, and a catalogue that had come was
   * said not to have answered (session 83 review: "dome A (calibrated)", a name the shipped configs no
   * longer have). The first NAMES_SHOWN distinct ones; `others` counts the entries of the servers not
   * asked for. */
  enum { NAMES_SHOWN = 6 };
  char names[NAMES_SHOWN][sizeof ((palp_Phantom *)0)->name];
  int nnames = 0, more_names = 0, others = 0;
  while (palp_dds_now_ns() < end && palp_dds_now_ns() < settle) {
    int n;
    do {
      void *ptr[CATALOGUE_PAGE] = {NULL};
      dds_sample_info_t info[CATALOGUE_PAGE];
      n = dds_read_mask(rd, ptr, info, CATALOGUE_PAGE, CATALOGUE_PAGE, DDS_NOT_READ_SAMPLE_STATE);
      for (int i = 0; i < n; i++) {
        const palp_Phantom *p = ptr[i];
        if (!info[i].valid_data || info[i].instance_state != DDS_IST_ALIVE) continue;
        const uint32_t srvno = PALP_DDS_ID_SERVER(p->phantom_id);
        if ((server_number >= 0 && srvno != (uint32_t)server_number) ||
            (exclude_server >= 0 && srvno == (uint32_t)exclude_server)) {
          others++;
          continue;
        }
        if (strcmp(p->name, name) != 0) {
          int known = 0;
          for (int k = 0; k < nnames && !known; k++) known = !strcmp(names[k], p->name);
          if (!known && nnames < NAMES_SHOWN) snprintf(names[nnames++], sizeof names[0], "%s", p->name);
          else if (!known) more_names++;
          continue;
        }
        /* The least busy phantom of that name: a class spreads over the servers. */
        if (p->active_sessions < best_sessions || (p->active_sessions == best_sessions && p->phantom_id < best)) {
          best = p->phantom_id;
          best_sessions = p->active_sessions;
        }
      }
      if (n > 0) dds_return_loan(rd, ptr, n);
    } while (n > 0);
    if (best && settle == INT64_MAX) settle = palp_dds_now_ns() + DDS_MSECS(300);
    if (stopped(st)) {
      dds_delete(rd);
      return fail_stopped(err, errlen);
    }
    nap(0.05);
  }
  dds_delete(rd);
  if (!best && (nnames || others)) {
    /* the catalogue came: the name is what did not match */
    char seen[NAMES_SHOWN * 72 + 64] = "";
    size_t n = 0;
    for (int k = 0; k < nnames && n < sizeof seen; k++)
      n += (size_t)snprintf(seen + n, sizeof seen - n, "%s\"%s\"", k ? ", " : "", names[k]);
    if (more_names && n < sizeof seen) snprintf(seen + n, sizeof seen - n, " and %d more", more_names);
    return fail(err, errlen, PALP_EIO, "no phantom named \"%s\"%s within %.1f s; the catalogue %s%s%s", name,
                exclude_server >= 0 ? " on another server" : server_number >= 0 ? " on that server" : "", timeout,
                nnames ? "lists " : "lists no phantom there", seen,
                nnames ? " (names are matched exactly)" : "");
  }
  if (!best) {
    char hint[PALP_DDS_HINT_MAX];
    palp_dds_unanswered_hint(st->pp, &st->sec, hint, sizeof hint);
    return fail(err, errlen, PALP_EIO, "no phantom named \"%s\"%s within %.1f s%s", name,
                exclude_server >= 0 ? " on another server" : "", timeout, hint);
  }
  *out_id = best;
  return 0;
}

int palp_cli_station_server_number(palp_cli_station *st, const char *server_name, double timeout, uint32_t *out,
                                   char *err, size_t errlen) {
  dds_entity_t r =
      palp_dds_create_reader(st->pp, st->topic[PALP_TOPIC_SERVER_IDENTITY], PALP_TOPIC_SERVER_IDENTITY);
  if (r < 0) return fail(err, errlen, PALP_EIO, "cannot read the server identities");
  const int64_t end = palp_dds_now_ns() + (int64_t)(timeout * 1e9);
  int found = 0;
  while (!found && palp_dds_now_ns() < end) {
    /* Each identity once, as it comes (the samples not read yet, 8 at a time, until none is left): a
     * plain read of 8 returned the same first 8 on every pass, and a ninth server was never found
     * (session 77; the catalogue's reads had the same fault, fixed 2026-12-07: CATALOGUE_PAGE). */
    int n;
    do {
      void *ptr[8] = {NULL};
      dds_sample_info_t info[8];
      n = dds_read_mask(r, ptr, info, 8, 8, DDS_NOT_READ_SAMPLE_STATE);
      for (int i = 0; i < n; i++) {
        const palp_ServerIdentity *s = ptr[i];
        if (info[i].valid_data && info[i].instance_state == DDS_IST_ALIVE && strcmp(s->server_name, server_name) == 0) {
          *out = s->server_number;
          found = 1;
        }
      }
      if (n > 0) dds_return_loan(r, ptr, n);
    } while (!found && n > 0);
    if (!found && stopped(st)) {
      dds_delete(r);
      return fail_stopped(err, errlen);
    }
    if (!found) nap(0.05);
  }
  dds_delete(r);
  return found ? 0 : fail(err, errlen, PALP_EIO, "no server named \"%s\" on this domain within %.1f s", server_name, timeout);
}

void palp_cli_station_end_session(palp_cli_station *st) {
  /* Deleting the publisher/subscriber deletes the session's readers and writers. */
  if (st->pub > 0) dds_delete(st->pub);
  if (st->sub > 0) dds_delete(st->sub);
  st->pub = st->sub = st->contact_w = st->contact_r = st->feedback_r = st->deformation_r = 0;
  st->finding_w = st->finding_status_r = st->debrief_r = st->debrief_score_r = st->session_log_r = 0;
  st->local_model_r = st->finger_sample_r = 0;
  if (st->finger_sample_topic > 0) dds_delete(st->finger_sample_topic); /* its filter's, this session's */
  if (st->contact_topic > 0) dds_delete(st->contact_topic);               /* likewise */
  st->finger_sample_topic = st->contact_topic = 0;
  /* every state again, as before the first join (state_reader); the next join makes its phantom's
   * exercise reader */
  if (state_reader(st, 0) < 0) {
    if (st->state_r > 0) dds_delete(st->state_r);
    if (st->state_topic > 0) dds_delete(st->state_topic);
    st->state_r = st->state_topic = 0;
  }
  server_only_close(st, &st->exercise_srv);
  if (st->exercise_r > 0) dds_delete(st->exercise_r);
  if (st->exercise_topic > 0) dds_delete(st->exercise_topic);
  st->exercise_r = st->exercise_topic = 0;
  st->exercise_phantom = 0;
  st->session_id = 0;
  atomic_store_explicit(&st->status_session_id, 0, memory_order_relaxed);
  memset(&st->bind, 0, sizeof st->bind); /* the next session's server is whoever accepts its JOIN */
  /* the next session's server counts from its own base */
  memset(&st->log, 0, sizeof st->log);
  memset(&st->log_said, 0, sizeof st->log_said);
}
