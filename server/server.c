/* server.c - the classroom server's DDS front end and session bookkeeping. */
#include "server.h"
#include "identity.h"

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <dds/dds.h>

#include "palp.h"
#include "palp_dds.h"
#include "session.h"
#include "ticker.h"

#define MAX_STATIONS 256

typedef struct station {
  int in_use;
  char id[64];
  int role;            /* palp_Role */
  uint32_t session_id; /* 0: not in a session */
  int want_feedback, want_deformation;
  int keyed;           /* last request came on palp_station_request */
  dds_instance_handle_t ih; /* its instance there (keyed by station_key) */
} station;

typedef struct closed_session {
  palp_srv_session_summary sum;
  char phantom_name[64], station[64], name[64], partition[64], reason[128];
  int open; /* still open at print time (filled from a live session) */
} closed_session;

struct palp_srv {
  palp_srv_config cfg;
  const palp_srv_events *events;
  int verbose;
  palp_log *log;
  palp_srv_identity *identity;
  char server_id[64];
  int64_t start_ns;

  palp_srv_phantom phantom[PALP_SRV_MAX_PHANTOMS];
  int phantom_count;

  dds_entity_t pp;
  dds_entity_t topic[PALP_TOPIC_COUNT];
  dds_entity_t station_request_r, station_request_rc;
  /* palp_station_request writers whose liveliness lapsed (Cyclone's listener thread
   * -> main thread): tells a crash from a dispose, which Cyclone reports alike. */
  pthread_mutex_t lost_mu;
  dds_instance_handle_t lost[64];
  unsigned lost_n;
  dds_entity_t catalogue_w, request_r, reply_w, state_w, status_w, status_r;
  int warned_other_server;
  dds_entity_t request_rc, stop_gc, waitset;

  palp_srv_ticker *ticker;
  palp_srv_session **sessions; /* open sessions, [cfg.max_sessions] */
  int session_count;
  uint32_t next_session_id;
  uint64_t sessions_total;
  uint64_t rejected_closed[PALP_SRV_REJ_COUNT]; /* counters of sessions already closed */

  station stations[MAX_STATIONS];

  closed_session *closed;
  int closed_count, closed_cap;

  palp_SessionLoad *loads;
  atomic_int stop;
};

static int fail(char *err, size_t errlen, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err, errlen, fmt, ap);
  va_end(ap);
  return 0;
}

static void logf_(const palp_srv *srv, const char *fmt, ...) {
  if (!srv->verbose && !palp_log_enabled(srv->log, PALP_LOG_DEBUG)) return;
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  palp_logf(srv->log, srv->verbose ? PALP_LOG_INFO : PALP_LOG_DEBUG, "%s", msg);
}

/* ---- phantoms and catalogue ------------------------------------------------ */

static int load_phantom(palp_srv *srv, const palp_srv_phantom_cfg *pc, palp_srv_phantom *ph, char *err,
                        size_t errlen) {
  char msg[256] = "";
  ph->cfg = *pc;
  int rc = palp_scene_load(pc->scene_path, &ph->scene, msg, sizeof msg);
  if (rc < 0) {
    fail(err, errlen, "phantoms (id %u): scene %s: %s", pc->id, pc->scene_path, msg[0] ? msg : palp_strerror(rc));
    return rc;
  }
  /* Every session steps at the server's tick rate. Stations drive the contacts:
   * each session removes the scene's scripted contacts after building its world
   * (session.c). The server needs contact feedback and a slot per finger besides
   * the scene's contacts; a scene without them is refused rather than altered,
   * so a recorded scene file always rebuilds the world the session ran. */
  ph->scene.world.dt = 1.0 / srv->cfg.tick_rate_hz;
  if (!(ph->scene.world.effects & PALP_EFFECT_FORCE_FEEDBACK)) {
    fail(err, errlen, "phantoms (id %u): scene %s: effects must include \"force_feedback\" for stations", pc->id,
         pc->scene_path);
    return PALP_EINVAL;
  }
  if (ph->scene.world.max_contacts < PALP_SRV_MAX_FINGERS) {
    fail(err, errlen, "phantoms (id %u): scene %s: max_contacts %d is below the %d fingers of a station", pc->id,
         pc->scene_path, ph->scene.world.max_contacts, PALP_SRV_MAX_FINGERS);
    return PALP_EINVAL;
  }
  ph->template_world = palp_scene_create_world(&ph->scene, &rc);
  if (!ph->template_world) {
    fail(err, errlen, "phantoms (id %u): scene %s: cannot build the world: %s", pc->id, pc->scene_path,
         palp_strerror(rc));
    return rc < 0 ? rc : PALP_EINVAL;
  }
  ph->mesh = palp_world_mesh(ph->template_world);
  return 0;
}

static int phantom_sessions(const palp_srv *srv, uint32_t phantom_id) {
  int n = 0;
  for (int i = 0; i < srv->session_count; i++) n += srv->sessions[i]->phantom->cfg.id == phantom_id;
  return n;
}

static void publish_catalogue(palp_srv *srv, const palp_srv_phantom *ph) {
  const palp_mesh *m = ph->mesh;
  const palp_world_def *wd = &ph->scene.world;
  palp_Phantom msg;
  memset(&msg, 0, sizeof msg);
  msg.phantom_id = ph->cfg.id;
  snprintf(msg.name, sizeof msg.name, "%s", ph->cfg.name);
  snprintf(msg.scene_name, sizeof msg.scene_name, "%s", ph->scene.name);
  msg.radius = wd->mesh.radius;
  msg.tick_rate_hz = srv->cfg.tick_rate_hz;
  msg.max_force = srv->cfg.max_force;
  msg.effects = wd->effects;
  msg.membrane = (palp_MembraneParams){wd->membrane.thickness, wd->membrane.density, wd->membrane.E1,
                                       wd->membrane.eta1, wd->membrane.E2, wd->membrane.eta2};
  msg.gel = (palp_GelParams){(int32_t)wd->gel.law, wd->gel.pressure, wd->gel.a1, wd->gel.a2, wd->gel.a3};
  msg.top_vertex = m->top_vertex;
  msg.dome_triangle_count = m->dome_triangle_count;
  palp_Vec3 *rest = malloc((size_t)m->vertex_count * sizeof *rest);
  int32_t *tri = malloc((size_t)m->triangle_count * 3 * sizeof *tri);
  if (!rest || !tri) {
    free(rest);
    free(tri);
    return;
  }
  for (int i = 0; i < m->vertex_count; i++) rest[i] = (palp_Vec3){m->rest[i].x, m->rest[i].y, m->rest[i].z};
  for (int i = 0; i < m->triangle_count; i++)
    for (int k = 0; k < 3; k++) tri[3 * i + k] = m->tri[i][k];
  msg.rest = (dds_sequence_palp_Vec3){(uint32_t)m->vertex_count, (uint32_t)m->vertex_count, rest, false};
  msg.triangles = (dds_sequence_long){(uint32_t)m->triangle_count * 3, (uint32_t)m->triangle_count * 3, tri, false};
  msg.active_sessions = (uint32_t)phantom_sessions(srv, ph->cfg.id);
  dds_write(srv->catalogue_w, &msg);
  free(rest);
  free(tri);
}

static palp_srv_phantom *find_phantom(palp_srv *srv, uint32_t id) {
  for (int i = 0; i < srv->phantom_count; i++)
    if (srv->phantom[i].cfg.id == id) return &srv->phantom[i];
  return NULL;
}

/* ---- session state ----------------------------------------------------------- */

typedef struct stats_snapshot {
  uint32_t id;
  palp_srv_session_stats st;
  int found;
} stats_snapshot;

static void snap_one(void *ctx, palp_srv_session *s) {
  stats_snapshot *sn = ctx;
  if (s->id == sn->id) {
    sn->st = s->stats;
    sn->found = 1;
  }
}

static palp_srv_session_stats session_stats(palp_srv *srv, palp_srv_session *s) {
  stats_snapshot sn = {.id = s->id};
  palp_srv_ticker_each(srv->ticker, snap_one, &sn);
  return sn.found ? sn.st : s->stats; /* detached: the tick thread no longer writes it */
}

static void member_counts(const palp_srv *srv, uint32_t sid, uint32_t *visual, uint32_t *observer) {
  *visual = *observer = 0;
  for (int i = 0; i < MAX_STATIONS; i++) {
    const station *st = &srv->stations[i];
    if (!st->in_use || st->session_id != sid) continue;
    if (st->role == palp_ROLE_VISUAL) ++*visual;
    if (st->role == palp_ROLE_OBSERVER) ++*observer;
  }
}

static void publish_state(palp_srv *srv, palp_srv_session *s, int closed, const char *reason,
                          const palp_srv_session_stats *stp) {
  palp_srv_session_stats st = stp ? *stp : session_stats(srv, s);
  palp_SessionState m;
  memset(&m, 0, sizeof m);
  m.session_id = s->id;
  m.phantom_id = s->phantom->cfg.id;
  m.phase = closed ? palp_PHASE_CLOSED : palp_PHASE_OPEN;
  snprintf(m.partition, sizeof m.partition, "%s", s->partition);
  snprintf(m.trainee_station, sizeof m.trainee_station, "%s", s->trainee_station);
  snprintf(m.trainee_name, sizeof m.trainee_name, "%s", s->trainee_name);
  member_counts(srv, s->id, &m.visual_count, &m.observer_count);
  m.tick_rate_hz = srv->cfg.tick_rate_hz;
  m.duration = (double)(palp_dds_now_ns() - s->opened_ns) * 1e-9;
  m.ticks = st.ticks;
  m.overruns = st.overruns;
  m.contact_samples = st.contact_samples;
  for (int r = 0; r < PALP_SRV_REJ_COUNT; r++)
    if (r != PALP_SRV_REJ_FORCE_LIMIT || srv->cfg.force_policy == PALP_SRV_FORCE_REJECT)
      m.rejected_samples += st.rejected[r];
  m.peak_force = st.peak_force;
  m.peak_displacement = st.peak_displacement;
  snprintf(m.reason, sizeof m.reason, "%s", reason ? reason : "");
  dds_write(srv->state_w, &m);
}

static void reply(palp_srv *srv, const palp_SessionRequest *rq, palp_srv_session *s, const char *why) {
  palp_SessionReply r;
  memset(&r, 0, sizeof r);
  snprintf(r.station_id, sizeof r.station_id, "%s", rq->station_id);
  r.request_seq = rq->request_seq;
  r.status = s ? palp_REPLY_ACCEPTED : palp_REPLY_REJECTED;
  r.tick_rate_hz = srv->cfg.tick_rate_hz;
  if (s) {
    r.session_id = s->id;
    r.phantom_id = s->phantom->cfg.id;
    snprintf(r.partition, sizeof r.partition, "%s", s->partition);
  } else {
    r.phantom_id = rq->phantom_id;
    snprintf(r.reason, sizeof r.reason, "%s", why ? why : "rejected");
  }
  dds_write(srv->reply_w, &r);
}

static palp_srv_session *find_session(palp_srv *srv, uint32_t id) {
  for (int i = 0; i < srv->session_count; i++)
    if (srv->sessions[i]->id == id) return srv->sessions[i];
  return NULL;
}

static station *find_station(palp_srv *srv, const char *id, int create) {
  station *free_slot = NULL;
  for (int i = 0; i < MAX_STATIONS; i++) {
    station *st = &srv->stations[i];
    if (st->in_use && strcmp(st->id, id) == 0) return st;
    if (!st->in_use && !free_slot) free_slot = st;
  }
  if (!create || !free_slot) return NULL;
  memset(free_slot, 0, sizeof *free_slot);
  free_slot->in_use = 1;
  snprintf(free_slot->id, sizeof free_slot->id, "%s", id);
  return free_slot;
}

static void remember_closed(palp_srv *srv, const palp_srv_session_summary *sum, int open) {
  if (srv->closed_count == srv->closed_cap) {
    int cap = srv->closed_cap ? 2 * srv->closed_cap : 16;
    closed_session *n = realloc(srv->closed, (size_t)cap * sizeof *n);
    if (!n) return;
    srv->closed = n;
    srv->closed_cap = cap;
  }
  closed_session *c = &srv->closed[srv->closed_count++];
  c->sum = *sum;
  c->open = open;
  snprintf(c->phantom_name, sizeof c->phantom_name, "%s", sum->info.phantom_name);
  snprintf(c->station, sizeof c->station, "%s", sum->info.trainee_station);
  snprintf(c->name, sizeof c->name, "%s", sum->info.trainee_name);
  snprintf(c->partition, sizeof c->partition, "%s", sum->info.partition);
  snprintf(c->reason, sizeof c->reason, "%s", sum->close_reason ? sum->close_reason : "");
  c->sum.info.phantom_name = c->phantom_name;
  c->sum.info.trainee_station = c->station;
  c->sum.info.trainee_name = c->name;
  c->sum.info.partition = c->partition;
  c->sum.close_reason = c->reason;
}

static void close_session(palp_srv *srv, palp_srv_session *s, const char *reason) {
  palp_srv_ticker_remove(srv->ticker, s);
  /* Detached: the stats are final and owned by this thread now. */
  palp_srv_session_summary sum;
  palp_srv_session_summary_fill(s, reason, palp_dds_now_ns(), &sum);
  publish_state(srv, s, 1, reason, &s->stats);
  remember_closed(srv, &sum, 0);
  for (int r = 0; r < PALP_SRV_REJ_COUNT; r++) srv->rejected_closed[r] += s->stats.rejected[r];
  if (srv->events && srv->events->session_closed) srv->events->session_closed(srv->events->ctx, &sum);
  palp_log_info(srv->log, "session %u closed after %.1f s (%s)", s->id, sum.duration, reason);
  for (int i = 0; i < MAX_STATIONS; i++)
    if (srv->stations[i].in_use && srv->stations[i].session_id == s->id) srv->stations[i].session_id = 0;
  for (int i = 0; i < srv->session_count; i++)
    if (srv->sessions[i] == s) {
      srv->sessions[i] = srv->sessions[--srv->session_count];
      break;
    }
  palp_srv_phantom *ph = s->phantom;
  palp_srv_session_destroy(s);
  publish_catalogue(srv, ph);
}

/* The station leaves whatever it is in: a trainee's session closes, a viewer
 * only stops being counted. */
static void station_leave(palp_srv *srv, station *st, const char *reason) {
  palp_srv_session *s = st->session_id ? find_session(srv, st->session_id) : NULL;
  uint32_t sid = st->session_id;
  int role = st->role;
  st->session_id = 0;
  if (!s) return;
  if (role == palp_ROLE_TRAINEE && strcmp(s->trainee_station, st->id) == 0) {
    char why[160];
    snprintf(why, sizeof why, "trainee station %s", reason);
    close_session(srv, s, why);
    return;
  }
  if (st->want_deformation) atomic_fetch_sub(&s->deform_members, 1);
  if (st->want_feedback) atomic_fetch_sub(&s->want_feedback, 1);
  if (srv->events && srv->events->member_changed) srv->events->member_changed(srv->events->ctx, sid, st->id, role, 0);
  logf_(srv, "station %s (%s) left session %u: %s", st->id, role == palp_ROLE_VISUAL ? "visual" : "observer",
        sid, reason);
  publish_state(srv, s, 0, NULL, NULL);
}

/* With other servers on the domain, a request for a phantom or session this server
 * does not hold is theirs: no reply (two replies to one station would race). Alone,
 * the server rejects it with a reason, as it always did. */
static int not_mine(const palp_srv *srv, const palp_SessionRequest *rq) {
  char ignored[256]; /* a conflict is acted on by palp_srv_run's next poll */
  palp_srv_identity_poll(srv->identity, ignored, sizeof ignored);
  if (!palp_srv_identity_peers(srv->identity)) return 0;
  if (rq->role != palp_ROLE_TRAINEE && rq->session_id)
    return PALP_DDS_ID_SERVER(rq->session_id) != srv->cfg.server_number;
  return find_phantom((palp_srv *)srv, rq->phantom_id) == NULL;
}

static void handle_join(palp_srv *srv, const palp_SessionRequest *rq) {
  char why[128];
  if (rq->role > palp_ROLE_OBSERVER) {
    reply(srv, rq, NULL, "unknown role");
    return;
  }
  station *st = find_station(srv, rq->station_id, 1);
  if (!st) {
    reply(srv, rq, NULL, "too many stations");
    return;
  }
  if (st->session_id) station_leave(srv, st, "re-joined");
  st->role = (int)rq->role;
  st->want_feedback = rq->want_feedback;
  st->want_deformation = rq->want_deformation;
  palp_srv_session *s = NULL;
  if (rq->role == palp_ROLE_TRAINEE) {
    palp_srv_phantom *ph = find_phantom(srv, rq->phantom_id);
    if (!ph && not_mine(srv, rq)) return;
    if (!ph) {
      snprintf(why, sizeof why, "unknown phantom %u", rq->phantom_id);
      reply(srv, rq, NULL, why);
      return;
    }
    if (srv->session_count >= srv->cfg.max_sessions) {
      snprintf(why, sizeof why, "server full: %d sessions open (max_sessions)", srv->session_count);
      reply(srv, rq, NULL, why);
      return;
    }
    palp_srv_session_def d = {.id = srv->next_session_id,
                              .phantom = ph,
                              .cfg = &srv->cfg,
                              .trainee_station = rq->station_id,
                              .trainee_name = rq->user_name,
                              .participant = srv->pp,
                              .contact_topic = srv->topic[PALP_TOPIC_CONTACT],
                              .feedback_topic = srv->topic[PALP_TOPIC_FEEDBACK],
                              .deformation_topic = srv->topic[PALP_TOPIC_DEFORMATION],
                              .events = srv->events,
                              .log = srv->log};
    int rc = 0;
    s = palp_srv_session_create(&d, &rc);
    if (!s) {
      snprintf(why, sizeof why, "cannot create the session: %s", palp_strerror(rc));
      reply(srv, rq, NULL, why);
      return;
    }
    atomic_store(&s->want_feedback, rq->want_feedback ? 1 : 0);
    atomic_store(&s->deform_members, rq->want_deformation ? 1 : 0);
    /* The log learns of the session before its first tick can report on it. */
    palp_srv_session_info info;
    palp_srv_session_info_fill(s, &info);
    if (srv->events && srv->events->session_opened) srv->events->session_opened(srv->events->ctx, &info);
    if (palp_srv_ticker_add(srv->ticker, s) < 0) {
      palp_srv_session_summary sum;
      palp_srv_session_summary_fill(s, "tick pool full", palp_dds_now_ns(), &sum);
      if (srv->events && srv->events->session_closed) srv->events->session_closed(srv->events->ctx, &sum);
      palp_srv_session_destroy(s);
      reply(srv, rq, NULL, "tick pool full");
      return;
    }
    srv->next_session_id++;
    /* Local ids wrap after 2^20 - 1 sessions, keeping the server's number. */
    if (PALP_DDS_ID_LOCAL(srv->next_session_id) == 0)
      srv->next_session_id = PALP_DDS_ID(srv->cfg.server_number, 1);
  pthread_mutex_init(&srv->lost_mu, NULL);
    srv->sessions_total++;
    srv->sessions[srv->session_count++] = s;
    st->session_id = s->id;
    reply(srv, rq, s, NULL);
    publish_state(srv, s, 0, NULL, NULL);
    publish_catalogue(srv, ph);
    palp_log_info(srv->log, "session %u opened: trainee \"%s\" (%s) on phantom %u \"%s\", partition %s",
            s->id, s->trainee_name, s->trainee_station, ph->cfg.id, ph->cfg.name, s->partition);
    return;
  }
  /* Visual station or observer: a given session, else the newest on the phantom. */
  if (rq->session_id) {
    s = find_session(srv, rq->session_id);
  } else {
    for (int i = 0; i < srv->session_count; i++) {
      palp_srv_session *c = srv->sessions[i];
      if ((rq->phantom_id == 0 || c->phantom->cfg.id == rq->phantom_id) && (!s || c->id > s->id)) s = c;
    }
  }
  if (!s && not_mine(srv, rq)) return;
  if (!s) {
    if (rq->session_id)
      snprintf(why, sizeof why, "no open session %u", rq->session_id);
    else
      snprintf(why, sizeof why, "no open session on phantom %u", rq->phantom_id);
    reply(srv, rq, NULL, why);
    return;
  }
  st->session_id = s->id;
  if (st->want_deformation) atomic_fetch_add(&s->deform_members, 1);
  if (st->want_feedback) atomic_fetch_add(&s->want_feedback, 1);
  reply(srv, rq, s, NULL);
  publish_state(srv, s, 0, NULL, NULL);
  if (srv->events && srv->events->member_changed)
    srv->events->member_changed(srv->events->ctx, s->id, st->id, st->role, 1);
  palp_log_info(srv->log, "station %s joined session %u as %s", st->id, s->id,
          rq->role == palp_ROLE_VISUAL ? "visual station" : "observer");
}

/* A request instance that turned not-alive while its writer is still matched was
 * disposed on purpose: a goodbye (dispose alone is enough, as for any DDS entity).
 * A writer that is gone (lease expired) means the station vanished. */
static void on_station_liveliness(dds_entity_t reader, const dds_liveliness_changed_status_t st, void *arg) {
  (void)reader;
  palp_srv *srv = arg;
  if ((st.not_alive_count_change > 0 || st.alive_count_change < 0) && st.last_publication_handle) {
    pthread_mutex_lock(&srv->lost_mu);
    srv->lost[srv->lost_n++ % 64] = st.last_publication_handle;
    pthread_mutex_unlock(&srv->lost_mu);
  }
}

static int station_writer_lost(palp_srv *srv, dds_instance_handle_t w) {
  int lost = 0;
  pthread_mutex_lock(&srv->lost_mu);
  for (unsigned i = 0; i < 64 && i < srv->lost_n; i++) lost |= srv->lost[i] == w;
  pthread_mutex_unlock(&srv->lost_mu);
  return lost;
}

/* Cyclone 0.10 reports a dispose and a writer whose liveliness lapsed (autodispose)
 * alike, as a disposed instance, and unregisters the lapsed writer's instances just
 * before it calls the liveliness listener. So a disposed instance is a goodbye only
 * if its writer is still matched and, a moment later, has not lost its liveliness. */
static const char *station_not_alive_reason(palp_srv *srv, const dds_sample_info_t *info) {
  const char *lost = "lost (liveliness lease expired)";
  if (info->instance_state != DDS_IST_NOT_ALIVE_DISPOSED || !info->publication_handle) return lost;
  dds_builtintopic_endpoint_t *w = dds_get_matched_publication_data(srv->station_request_r, info->publication_handle);
  if (!w) return lost;
  dds_builtintopic_free_endpoint(w);
  const struct timespec grace = {0, 50000000}; /* the listener runs right after the unregister */
  nanosleep(&grace, NULL);
  return station_writer_lost(srv, info->publication_handle) ? lost : "left (request disposed)";
}

static void handle_request_sample(palp_srv *srv, palp_SessionRequest *rq, station **out_st) {
  if (rq->op == palp_OP_JOIN) {
    handle_join(srv, rq);
    if (out_st) *out_st = find_station(srv, rq->station_id, 0);
    return;
  }
  station *st = find_station(srv, rq->station_id, 0);
  if (st) {
    station_leave(srv, st, "left");
    st->in_use = 0;
  }
  if (st || !palp_srv_identity_peers(srv->identity)) reply(srv, rq, NULL, "left");
  if (out_st) *out_st = NULL;
}

/* palp_station_request: the same requests, keyed by 8 bytes (docs/interop.md). */
static void handle_station_requests(palp_srv *srv) {
  enum { N = 16 };
  palp_StationRequest buf[N];
  void *ptr[N];
  dds_sample_info_t info[N];
  for (int i = 0; i < N; i++) ptr[i] = &buf[i];
  int n;
  while ((n = dds_take(srv->station_request_r, ptr, info, N, N)) > 0) {
    for (int i = 0; i < n; i++) {
      if (info[i].valid_data) {
        const palp_StationRequest *s = &buf[i];
        palp_SessionRequest rq;
        memset(&rq, 0, sizeof rq);
        snprintf(rq.station_id, sizeof rq.station_id, "%s", s->station_id);
        rq.request_seq = s->request_seq;
        rq.op = s->op;
        rq.role = s->role;
        rq.phantom_id = s->phantom_id;
        rq.session_id = s->session_id;
        snprintf(rq.user_name, sizeof rq.user_name, "%s", s->user_name);
        rq.want_feedback = s->want_feedback;
        rq.want_deformation = s->want_deformation;
        station *st = NULL;
        handle_request_sample(srv, &rq, &st);
        if (st) {
          st->keyed = 1;
          st->ih = info[i].instance_handle;
        }
        continue;
      }
      if (info[i].instance_state == DDS_IST_ALIVE) continue;
      /* By instance handle: once its last sample is taken, a "no writers" instance
       * may be gone, and its key with it. */
      for (int k = 0; k < MAX_STATIONS; k++) {
        station *st = &srv->stations[k];
        if (!st->in_use || !st->keyed || st->ih != info[i].instance_handle) continue;
        station_leave(srv, st, station_not_alive_reason(srv, &info[i]));
        st->in_use = 0;
      }
    }
    if (n < N) break;
  }
}

static void handle_requests(palp_srv *srv) {
  enum { N = 16 };
  palp_SessionRequest buf[N];
  void *ptr[N];
  dds_sample_info_t info[N];
  for (int i = 0; i < N; i++) ptr[i] = &buf[i];
  int n;
  handle_station_requests(srv);
  while ((n = dds_take(srv->request_r, ptr, info, N, N)) > 0) {
    for (int i = 0; i < n; i++) {
      if (info[i].valid_data) {
        if (buf[i].op == palp_OP_JOIN)
          handle_join(srv, &buf[i]);
        else {
          station *st = find_station(srv, buf[i].station_id, 0);
          if (st) {
            station_leave(srv, st, "left");
            st->in_use = 0;
          }
          if (st || !palp_srv_identity_peers(srv->identity)) reply(srv, &buf[i], NULL, "left");
        }
        continue;
      }
      if (info[i].instance_state == DDS_IST_ALIVE) continue;
      palp_SessionRequest key;
      memset(&key, 0, sizeof key);
      if (dds_instance_get_key(srv->request_r, info[i].instance_handle, &key) != 0) continue;
      station *st = find_station(srv, key.station_id, 0);
      if (!st) continue;
      /* A station that says goodbye sends OP_LEAVE first (handled above, which
       * forgets it), so reaching here means it vanished: its writer's automatic
       * liveliness (0.5 s) or its participant's lease (1 s) expired, and
       * Cyclone unregistered (or, autodispose, disposed) its instance. Cyclone
       * reports a lapsed writer's instances as disposed, so a dispose alone cannot
       * be told from a crash on this topic: palp_station_request can. */
      station_leave(srv, st, "lost (liveliness lease expired)");
      st->in_use = 0;
    }
    if (n < N) break;
  }
}

/* ---- status -------------------------------------------------------------------- */

typedef struct load_ctx {
  palp_srv *srv;
  uint32_t n;
  uint64_t rejected[PALP_SRV_REJ_COUNT];
} load_ctx;

static void load_one(void *ctx, palp_srv_session *s) {
  load_ctx *lc = ctx;
  if (lc->n >= (uint32_t)lc->srv->cfg.max_sessions) return;
  palp_SessionLoad *l = &lc->srv->loads[lc->n++];
  memset(l, 0, sizeof *l);
  l->session_id = s->id;
  l->phantom_id = s->phantom->cfg.id;
  l->ticks = s->stats.ticks;
  l->overruns = s->stats.overruns;
  l->awake_ticks = s->stats.awake_ticks;
  l->contact_samples = s->stats.contact_samples;
  for (int r = 0; r < PALP_SRV_REJ_COUNT; r++) {
    l->rejected[r] = s->stats.rejected[r];
    lc->rejected[r] += s->stats.rejected[r];
  }
  l->step_us_max = s->stats.step_us_max;
  s->stats.step_us_max = 0;
}

static void check_other_servers(palp_srv *srv) {
  void *ptr[4] = {NULL};
  dds_sample_info_t info[4];
  int n;
  while ((n = dds_take(srv->status_r, ptr, info, 4, 4)) > 0) {
    for (int i = 0; i < n; i++) {
      const palp_ServerStatus *st = ptr[i];
      if (info[i].valid_data && strcmp(st->server_id, srv->server_id) != 0 && !srv->warned_other_server) {
        /* Harmless with distinct server numbers (identity.h), which refuse to start
         * otherwise; a server without identities (older palp) would answer every join. */
        palp_log_info(srv->log, "another server (%s) publishes status on domain %u", st->server_id,
                      srv->cfg.domain_id);
        srv->warned_other_server = 1;
      }
    }
    dds_return_loan(srv->status_r, ptr, n);
  }
}

static void publish_status(palp_srv *srv) {
  check_other_servers(srv);
  palp_srv_tick_stats ts;
  palp_srv_ticker_stats(srv->ticker, &ts);
  load_ctx lc = {.srv = srv};
  palp_srv_ticker_each(srv->ticker, load_one, &lc);
  palp_ServerStatus m;
  memset(&m, 0, sizeof m);
  snprintf(m.server_id, sizeof m.server_id, "%s", srv->server_id);
  m.uptime = (double)(palp_dds_now_ns() - srv->start_ns) * 1e-9;
  m.tick_rate_hz = srv->cfg.tick_rate_hz;
  m.tick_threads = (uint32_t)palp_srv_ticker_threads(srv->ticker);
  m.sessions_open = (uint32_t)srv->session_count;
  m.sessions_total = srv->sessions_total;
  m.load = ts.load;
  m.tick_us_p50 = ts.tick_us_p50;
  m.tick_us_p99 = ts.tick_us_p99;
  m.tick_us_max = ts.tick_us_max;
  m.ticks = ts.ticks;
  m.overruns = ts.overruns;
  for (int r = 0; r < PALP_SRV_REJ_COUNT; r++) m.rejected[r] = lc.rejected[r] + srv->rejected_closed[r];
  if (srv->events && srv->events->log_counts) {
    uint64_t w = 0, sh = 0, f = 0;
    srv->events->log_counts(srv->events->ctx, &w, &sh, &f);
    m.log_written = w;
    m.log_shed = sh;
    m.log_failed = f;
  }
  m.sessions = (dds_sequence_palp_SessionLoad){lc.n, lc.n, srv->loads, false};
  dds_write(srv->status_w, &m);
  for (int i = 0; i < srv->session_count; i++) publish_state(srv, srv->sessions[i], 0, NULL, NULL);
}

/* ---- lifecycle ------------------------------------------------------------------- */

palp_srv *palp_srv_create(const palp_srv_def *def, int *rc, char *err, size_t errlen) {
  palp_srv *srv = calloc(1, sizeof *srv);
  if (!srv) {
    *rc = PALP_ENOMEM;
    fail(err, errlen, "out of memory");
    return NULL;
  }
  srv->cfg = def->cfg;
  srv->events = def->events;
  srv->verbose = def->verbose;
  srv->log = def->log;
  srv->next_session_id = PALP_DDS_ID(srv->cfg.server_number, 1);
  srv->start_ns = palp_dds_now_ns();
  char host[32] = "host";
  gethostname(host, sizeof host - 1);
  snprintf(srv->server_id, sizeof srv->server_id, "palp-server/%s/%ld", host, (long)getpid());
  if (!srv->cfg.server_name[0]) snprintf(srv->cfg.server_name, sizeof srv->cfg.server_name, "%s", host);
  if (palp_srv_config_check_ids(&srv->cfg, err, errlen) < 0) {
    *rc = PALP_EINVAL;
    goto fail;
  }
  /* Every id this server hands out carries its number (idl/palp_dds.h). */
  for (int i = 0; i < srv->cfg.phantom_count; i++)
    srv->cfg.phantom[i].id = PALP_DDS_ID(srv->cfg.server_number, srv->cfg.phantom[i].id);
  srv->sessions = calloc((size_t)srv->cfg.max_sessions, sizeof *srv->sessions);
  srv->loads = calloc((size_t)srv->cfg.max_sessions, sizeof *srv->loads);
  if (!srv->sessions || !srv->loads) {
    *rc = PALP_ENOMEM;
    fail(err, errlen, "out of memory");
    goto fail;
  }
  for (int i = 0; i < srv->cfg.phantom_count; i++) {
    *rc = load_phantom(srv, &srv->cfg.phantom[i], &srv->phantom[i], err, errlen);
    srv->phantom_count = i + (srv->phantom[i].template_world != NULL);
    if (*rc < 0) goto fail;
  }
  srv->pp = dds_create_participant((dds_domainid_t)srv->cfg.domain_id, NULL, NULL);
  if (srv->pp < 0) {
    *rc = PALP_EIO;
    fail(err, errlen, "dds_config: cannot create a DDS participant on domain %u: %s (CYCLONEDDS_URI=%s)",
         srv->cfg.domain_id, dds_strretcode(srv->pp), getenv("CYCLONEDDS_URI") ? getenv("CYCLONEDDS_URI") : "");
    goto fail;
  }
  for (int k = 0; k < PALP_TOPIC_COUNT; k++) {
    srv->topic[k] = palp_dds_create_topic(srv->pp, (palp_dds_topic_kind)k);
    if (srv->topic[k] < 0) {
      *rc = PALP_EIO;
      fail(err, errlen, "cannot create topic %s: %s", palp_dds_topic_name((palp_dds_topic_kind)k),
           dds_strretcode(srv->topic[k]));
      goto fail;
    }
  }
  srv->catalogue_w = palp_dds_create_writer(srv->pp, srv->topic[PALP_TOPIC_CATALOGUE], PALP_TOPIC_CATALOGUE);
  srv->request_r = palp_dds_create_reader(srv->pp, srv->topic[PALP_TOPIC_SESSION_REQUEST], PALP_TOPIC_SESSION_REQUEST);
  srv->reply_w = palp_dds_create_writer(srv->pp, srv->topic[PALP_TOPIC_SESSION_REPLY], PALP_TOPIC_SESSION_REPLY);
  srv->state_w = palp_dds_create_writer(srv->pp, srv->topic[PALP_TOPIC_SESSION_STATE], PALP_TOPIC_SESSION_STATE);
  srv->status_w = palp_dds_create_writer(srv->pp, srv->topic[PALP_TOPIC_SERVER_STATUS], PALP_TOPIC_SERVER_STATUS);
  /* Only to notice a second server on the domain: both would answer every join. */
  srv->status_r = palp_dds_create_reader(srv->pp, srv->topic[PALP_TOPIC_SERVER_STATUS], PALP_TOPIC_SERVER_STATUS);
  srv->waitset = dds_create_waitset(srv->pp);
  srv->stop_gc = dds_create_guardcondition(srv->pp);
  srv->request_rc = dds_create_readcondition(srv->request_r, DDS_ANY_STATE);
  srv->station_request_r =
      palp_dds_create_reader(srv->pp, srv->topic[PALP_TOPIC_STATION_REQUEST], PALP_TOPIC_STATION_REQUEST);
  srv->station_request_rc = dds_create_readcondition(srv->station_request_r, DDS_ANY_STATE);
  if (srv->station_request_r > 0) {
    dds_listener_t *lv = dds_create_listener(NULL);
    dds_lset_liveliness_changed_arg(lv, on_station_liveliness, srv, true);
    dds_set_listener(srv->station_request_r, lv);
    dds_delete_listener(lv);
  }
  if (srv->station_request_r < 0 || srv->station_request_rc < 0 ||
      dds_waitset_attach(srv->waitset, srv->station_request_rc, 1) < 0) {
    *rc = PALP_EIO;
    fail(err, errlen, "cannot create the palp_station_request reader");
    goto fail;
  }
  if (srv->catalogue_w < 0 || srv->request_r < 0 || srv->reply_w < 0 || srv->state_w < 0 || srv->status_w < 0 ||
      srv->status_r < 0 ||
      srv->waitset < 0 || srv->stop_gc < 0 || srv->request_rc < 0 ||
      dds_waitset_attach(srv->waitset, srv->request_rc, 0) < 0 || dds_waitset_attach(srv->waitset, srv->stop_gc, 0) < 0) {
    *rc = PALP_EIO;
    fail(err, errlen, "cannot create the server's DDS readers and writers");
    goto fail;
  }
  int rt_ok = 0;
  srv->ticker = palp_srv_ticker_create(srv->cfg.tick_threads, srv->cfg.tick_rate_hz, srv->cfg.max_sessions,
                                       srv->cfg.tick_priority, &rt_ok, rc);
  if (!srv->ticker) {
    fail(err, errlen, "cannot start the tick threads: %s", palp_strerror(*rc));
    goto fail;
  }
  if (srv->cfg.tick_priority > 0 && !rt_ok)
    palp_log_warn(srv->log, "tick_priority %d: SCHED_FIFO refused (needs CAP_SYS_NICE or an rtprio limit); "
                    "tick threads run at normal priority\n", srv->cfg.tick_priority);
  {
    uint32_t ids[PALP_SRV_MAX_PHANTOMS];
    const char *names[PALP_SRV_MAX_PHANTOMS];
    for (int i = 0; i < srv->phantom_count; i++) {
      ids[i] = srv->phantom[i].cfg.id;
      names[i] = srv->phantom[i].cfg.name;
    }
    char instance[64];
    snprintf(instance, sizeof instance, "%.40s/%ld", host, (long)getpid());
    palp_srv_identity_def idd = {.participant = srv->pp,
                                 .topic = srv->topic[PALP_TOPIC_SERVER_IDENTITY],
                                 .name = srv->cfg.server_name,
                                 .number = srv->cfg.server_number,
                                 .instance = instance,
                                 .phantom_count = srv->phantom_count,
                                 .phantom_id = ids,
                                 .phantom_name = names,
                                 .wait_s = def->identity_wait_s,
                                 .log = srv->log};
    srv->identity = palp_srv_identity_create(&idd, rc, err, errlen);
    if (!srv->identity) goto fail;
  }
  for (int i = 0; i < srv->phantom_count; i++) publish_catalogue(srv, &srv->phantom[i]);
  *rc = 0;
  return srv;
fail:
  palp_srv_destroy(srv);
  return NULL;
}

void palp_srv_request_stop(palp_srv *srv) {
  atomic_store(&srv->stop, 1);
  dds_set_guardcondition(srv->stop_gc, true);
}

int palp_srv_run(palp_srv *srv, double duration) {
  const int64_t status_period = (int64_t)(1e9 / srv->cfg.status_rate_hz);
  int64_t next_status = palp_dds_now_ns() + status_period;
  int64_t end = duration > 0 ? palp_dds_now_ns() + (int64_t)(duration * 1e9) : INT64_MAX;
  int result = 0;
  palp_log_info(srv->log, "%s: server \"%s\" number %u, domain %u, %d phantom(s), %.0f Hz on %d tick thread(s), max %d "
                "sessions", srv->server_id, srv->cfg.server_name, srv->cfg.server_number, srv->cfg.domain_id,
                srv->phantom_count, srv->cfg.tick_rate_hz, palp_srv_ticker_threads(srv->ticker), srv->cfg.max_sessions);
  while (!atomic_load(&srv->stop)) {
    int64_t now = palp_dds_now_ns();
    if (now >= end) break;
    int64_t wake = next_status < end ? next_status : end;
    /* Wake at least every 100 ms to notice sessions whose model failed. */
    if (wake - now > 100000000) wake = now + 100000000;
    dds_waitset_wait(srv->waitset, NULL, 0, wake - now > 0 ? wake - now : 0);
    handle_requests(srv);
    for (int i = 0; i < srv->session_count; i++) {
      palp_srv_session *s = srv->sessions[i];
      int f = atomic_load(&s->failed);
      if (f) {
        char why[128];
        snprintf(why, sizeof why, "model step failed: %s", palp_strerror(f));
        close_session(srv, s, why);
        i--;
      }
    }
    if (palp_dds_now_ns() >= next_status) {
      char why[256];
      if (palp_srv_identity_poll(srv->identity, why, sizeof why) < 0) {
        palp_log_error(srv->log, "stopping: %s", why);
        result = PALP_EINVAL;
        break;
      }
      publish_status(srv);
      next_status += status_period;
      if (next_status < palp_dds_now_ns()) next_status = palp_dds_now_ns() + status_period;
    }
  }
  dds_set_guardcondition(srv->stop_gc, false);
  while (srv->session_count > 0)
    close_session(srv, srv->sessions[srv->session_count - 1], result ? "server identity conflict" : "server shutdown");
  publish_status(srv);
  return result;
}

int palp_srv_open_sessions(const palp_srv *srv) { return srv->session_count; }

static void print_row(FILE *out, const palp_srv_session_summary *s, const char *state) {
  uint64_t rej = 0;
  for (int r = 0; r < PALP_SRV_REJ_COUNT; r++) rej += s->rejected[r];
  fprintf(out, "%-7u %-16.16s %-26.26s %8.2f %9llu %8.2f %9.2f %9llu %8llu %8llu  %s\n", s->info.session_id,
          s->info.trainee_name, s->info.phantom_name, s->duration, (unsigned long long)s->contact_samples,
          s->peak_force, s->peak_displacement * 1e3, (unsigned long long)s->ticks,
          (unsigned long long)s->overruns, (unsigned long long)rej, state);
}

void palp_srv_print_summary(const palp_srv *srv, FILE *out) {
  fprintf(out, "%-7s %-16s %-26s %8s %9s %8s %9s %9s %8s %8s  %s\n", "session", "trainee", "phantom", "dur[s]",
          "contacts", "Fmax[N]", "dmax[mm]", "ticks", "overruns", "rejected", "closed because");
  for (int i = 0; i < srv->closed_count; i++) print_row(out, &srv->closed[i].sum, srv->closed[i].reason);
  for (int i = 0; i < srv->session_count; i++) {
    palp_srv_session_summary sum;
    palp_srv_session_summary_fill(srv->sessions[i], "(open)", palp_dds_now_ns(), &sum);
    print_row(out, &sum, "(open)");
  }
}

void palp_srv_destroy(palp_srv *srv) {
  if (!srv) return;
  palp_srv_ticker_destroy(srv->ticker);
  for (int i = 0; i < srv->session_count; i++) palp_srv_session_destroy(srv->sessions[i]);
  if (srv->pp > 0) dds_delete(srv->pp);
  palp_srv_identity_destroy(srv->identity);
  for (int i = 0; i < srv->phantom_count; i++) palp_world_destroy(srv->phantom[i].template_world);
  free(srv->sessions);
  free(srv->loads);
  free(srv->closed);
  pthread_mutex_destroy(&srv->lost_mu);
  free(srv);
}
