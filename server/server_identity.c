/* server_identity.c - a server's identity on its DDS domain (server_identity.h). */
#include "server_identity.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "palp.h"
#include "palp_dds.h"
#include "palp_log.h"

#define MAX_PEERS 64
/* Identity samples taken per call: a peer writing thousands of names cannot hold the main
 * thread (the rest wait in the reader for the next poll). */
#define SAMPLES_PER_PASS 64
/* A server gives way to an older one with its name or number only within this long of its
 * announcement (server_identity.h, "start-up window"): time for discovery to bring it the
 * identity of a server started at the same moment (on loopback well under a second). */
#define STARTUP_WINDOW_NS (5 * 1000000000LL)
#define REWRITE_PERIOD_NS 1000000000LL /* its own announcement again at most once a second */

typedef struct peer {
  int alive;
  char name[64], instance[64];
  uint32_t number;
  dds_instance_handle_t ih;
} peer;

struct palp_srv_identity {
  dds_entity_t reader, writer, rc, ws;
  palp_ServerIdentity me;
  palp_HostedPhantom *hosted;
  palp_log *log;
  peer peers[MAX_PEERS];
  char conflict[256]; /* sticky: once this server must give way, every poll says so */
  int64_t announced_ns; /* palp_dds_now_ns of its announcement; the start-up window runs from it */
  double log_interval_s;
  /* Claims of its name or number by an older server after the start-up window: anomalous
   * (a forged sample, or a network that split and healed), warned about, never obeyed. */
  uint64_t late_unsaid; /* claims not logged since the last line */
  int64_t late_said_ns;
  int rewrite_pending;
  int64_t rewritten_ns;
  char sec_hint[200]; /* what the warning advises, secured or not */
};

static int64_t unix_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static peer *find_peer(palp_srv_identity *id, dds_instance_handle_t ih, int create) {
  peer *free_slot = NULL;
  for (int i = 0; i < MAX_PEERS; i++) {
    if (id->peers[i].ih == ih && ih) return &id->peers[i];
    if (!id->peers[i].ih && !free_slot) free_slot = &id->peers[i];
  }
  if (create && free_slot) {
    memset(free_slot, 0, sizeof *free_slot);
    free_slot->ih = ih;
  }
  return create ? free_slot : NULL;
}

/* The older of two servers keeps a name or number; equal start times (unlikely:
 * ns) fall back to the instance string so both sides agree. */
static int other_is_older(const palp_srv_identity *id, const palp_ServerIdentity *o) {
  if (o->started_unix_ns != id->me.started_unix_ns) return o->started_unix_ns < id->me.started_unix_ns;
  return strcmp(o->instance, id->me.instance) < 0;
}

/* A claim of this server's name or number by an older server after its start-up window: giving way would close every session on the word of one sample,
 * which on plain DDS anyone may write. Warned about at most once per log interval (with how
 * many came meanwhile); this server keeps serving and says again that it holds them. */
static void late_claim(palp_srv_identity *id, const palp_ServerIdentity *o, dds_instance_handle_t pub, int same_name) {
  id->rewrite_pending = 1;
  const int64_t now = palp_dds_now_ns();
  if (id->late_said_ns && now - id->late_said_ns < (int64_t)(id->log_interval_s * 1e9)) {
    id->late_unsaid++;
    return;
  }
  char who[96], more[96] = "";
  /* who wrote the claim: its participant's GUID (plain DDS: any peer could have; secured: only a
   * participant holding one of the classroom's server certificates may publish this topic) */
  palp_dds_writer_participant_text(id->reader, pub, who, sizeof who);
  if (id->late_unsaid)
    snprintf(more, sizeof more, " (and %llu more such claims since the last line)", (unsigned long long)id->late_unsaid);
  palp_log_warn(id->log, "server %s \"%s\" (number %u) claimed by an older server \"%s\" (number %u, instance \"%s\", "
                         "started at %lld ns), written by %s, after its start-up window: ignored, this server keeps "
                         "serving and announces itself again; %s%s",
                same_name ? "name" : "number", id->me.server_name, id->me.server_number, PALP_PRINTABLE(o->server_name),
                o->server_number, PALP_PRINTABLE(o->instance),
                (long long)o->started_unix_ns, who, id->sec_hint, more);
  id->late_said_ns = now;
  id->late_unsaid = 0;
}

/* Takes new samples, at most SAMPLES_PER_PASS. Returns 0, or PALP_EINVAL (message in err) when
 * this server must give way. announced: whether this server has written its identity. */
static int take_all(palp_srv_identity *id, int announced, char *err, size_t errlen) {
  void *ptr[8] = {NULL};
  dds_sample_info_t info[8];
  int n, rc = 0, rewrite = 0, taken = 0;
  /* Before its announcement a server always gives way (another holds the name); after it, only
   * within its start-up window: two servers started at once both announce, and the younger stops. */
  const int may_give_way = !announced || palp_dds_now_ns() - id->announced_ns < STARTUP_WINDOW_NS;
  while (taken < SAMPLES_PER_PASS && (n = dds_take(id->reader, ptr, info, 8, 8)) > 0) {
    taken += n;
    for (int i = 0; i < n; i++) {
      const palp_ServerIdentity *o = ptr[i];
      if (!info[i].valid_data) {
        if (info[i].instance_state == DDS_IST_ALIVE) continue;
        peer *p = find_peer(id, info[i].instance_handle, 0);
        if (p && p->alive) {
          p->alive = 0;
          palp_log_warn(id->log, "server \"%s\" (number %u, %s) is gone from the domain; its stations are told by "
                                 "their session state", PALP_PRINTABLE(p->name), p->number, PALP_PRINTABLE(p->instance));
        }
        continue;
      }
      if (strcmp(o->instance, id->me.instance) == 0) continue; /* our own announcement */
      const int same_name = strcmp(o->server_name, id->me.server_name) == 0;
      const int same_number = o->server_number == id->me.server_number;
      if ((same_name || same_number) && info[i].instance_state == DDS_IST_ALIVE) {
        if (announced && other_is_older(id, o) && !may_give_way) {
          late_claim(id, o, info[i].publication_handle, same_name);
        } else if (!announced || other_is_older(id, o)) {
          snprintf(err, errlen,
                   "server %s \"%s\" (number %u) is already running on this domain as %s: give this server "
                   "another server_name and server_number, or stop that one",
                   same_name ? "name" : "number", PALP_PRINTABLE(o->server_name), o->server_number, PALP_PRINTABLE(o->instance));
          rc = PALP_EINVAL;
        } else {
          /* A younger server gives way only within its own start-up window: one started long after
           * (a network that split and healed) keeps serving too, and is told so in its log. */
          palp_log_warn(id->log, "a second server (%s) claims %s \"%s\" / number %u, started after this one: it "
                                 "gives way if it is within its start-up window (5 s), else both keep serving: stop "
                                 "one of them; this server keeps them",
                        PALP_PRINTABLE(o->instance), same_name ? "name" : "number", PALP_PRINTABLE(o->server_name), o->server_number);
          rewrite = 1;
        }
        continue;
      }
      peer *p = find_peer(id, info[i].instance_handle, 1);
      if (!p) continue;
      if (!p->alive)
        palp_log_info(id->log, "server \"%s\" (number %u, %s) is on this domain with %u phantom(s)",
                      PALP_PRINTABLE(o->server_name), o->server_number, PALP_PRINTABLE(o->instance), o->phantoms._length);
      p->alive = 1;
      p->number = o->server_number;
      snprintf(p->name, sizeof p->name, "%s", o->server_name);
      snprintf(p->instance, sizeof p->instance, "%s", o->instance);
    }
    dds_return_loan(id->reader, ptr, n);
    if (n < 8) break;
  }
  /* Both wrote the same key (same name): the reader's last value may be the
   * other's; say again who holds it (at most once a second: a flood of claims must not
   * become a flood of announcements; a pending one goes out at a later poll). */
  if (rewrite) id->rewrite_pending = 1;
  const int64_t now = palp_dds_now_ns();
  if (id->rewrite_pending && announced && rc == 0 && now - id->rewritten_ns >= REWRITE_PERIOD_NS) {
    dds_write(id->writer, &id->me);
    id->rewritten_ns = now;
    id->rewrite_pending = 0;
  }
  return rc;
}

palp_srv_identity *palp_srv_identity_create(const palp_srv_identity_def *def, int *rc, char *err, size_t errlen) {
  palp_srv_identity *id = calloc(1, sizeof *id);
  if (!id) {
    *rc = PALP_ENOMEM;
    snprintf(err, errlen, "out of memory");
    return NULL;
  }
  id->log = def->log;
  id->log_interval_s = def->log_interval_s > 0 ? def->log_interval_s : 1.0;
  snprintf(id->sec_hint, sizeof id->sec_hint, "%s",
           def->secured ? "only the classroom's server certificates may write this topic: find the server started "
                          "with this name, or revoke the certificate (make-classroom-pki.sh DIR revoke)"
                        : "DDS Security is off, so any participant may write this: a forged sample, or a second "
                          "server with this name on a network that split and healed; run the classroom secured");
  snprintf(id->me.server_name, sizeof id->me.server_name, "%s", def->name);
  id->me.server_number = def->number;
  snprintf(id->me.instance, sizeof id->me.instance, "%s", def->instance);
  id->me.started_unix_ns = unix_ns();
  id->hosted = calloc((size_t)(def->phantom_count > 0 ? def->phantom_count : 1), sizeof *id->hosted);
  if (!id->hosted) {
    *rc = PALP_ENOMEM;
    snprintf(err, errlen, "out of memory");
    goto fail;
  }
  for (int i = 0; i < def->phantom_count; i++) {
    id->hosted[i].phantom_id = def->phantom_id[i];
    snprintf(id->hosted[i].name, sizeof id->hosted[i].name, "%s", def->phantom_name[i]);
  }
  id->me.phantoms = (dds_sequence_palp_HostedPhantom){(uint32_t)def->phantom_count, (uint32_t)def->phantom_count,
                                                       id->hosted, false};
  id->reader = palp_dds_create_reader(def->participant, def->topic, PALP_TOPIC_SERVER_IDENTITY);
  id->writer = palp_dds_create_writer(def->participant, def->topic, PALP_TOPIC_SERVER_IDENTITY);
  id->ws = dds_create_waitset(def->participant);
  id->rc = dds_create_readcondition(id->reader, DDS_ANY_STATE);
  if (id->reader < 0 || id->writer < 0 || id->ws < 0 || id->rc < 0 || dds_waitset_attach(id->ws, id->rc, 0) < 0) {
    *rc = PALP_EIO;
    snprintf(err, errlen, "cannot create the server identity's reader and writer");
    goto fail;
  }
  /* Listen before announcing: a server already holding the name or number
   * delivers its (transient-local) identity once discovery has matched us. */
  const int64_t end = palp_dds_now_ns() + (int64_t)(def->wait_s * 1e9);
  for (;;) {
    if ((*rc = take_all(id, 0, err, errlen)) < 0) goto fail;
    int64_t left = end - palp_dds_now_ns();
    if (left <= 0) break;
    dds_waitset_wait(id->ws, NULL, 0, left);
  }
  if (dds_write(id->writer, &id->me) < 0) {
    *rc = PALP_EIO;
    snprintf(err, errlen, "cannot announce the server identity");
    goto fail;
  }
  id->announced_ns = palp_dds_now_ns();
  *rc = 0;
  return id;
fail:
  palp_srv_identity_destroy(id);
  return NULL;
}

int palp_srv_identity_poll(palp_srv_identity *id, char *err, size_t errlen) {
  if (!id) return 0;
  if (!id->conflict[0] && take_all(id, 1, id->conflict, sizeof id->conflict) == 0) return 0;
  snprintf(err, errlen, "%s", id->conflict);
  return PALP_EINVAL;
}

int palp_srv_identity_peers(const palp_srv_identity *id) {
  int n = 0;
  for (int i = 0; id && i < MAX_PEERS; i++) n += id->peers[i].ih && id->peers[i].alive;
  return n;
}

void palp_srv_identity_destroy(palp_srv_identity *id) {
  if (!id) return;
  /* The participant's deletion deletes the entities; only the memory is ours. */
  free(id->hosted);
  free(id);
}
