/* netem.c - the DDS-level delay/jitter/loss relay (netem.h). */
#include "netem.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <dds/dds.h>

#include "palp.h"
#include "palp_dds.h"

/* Session partitions per side at once. A slot is reclaimed for a new session when every instance
 * it relayed has ended (disposed or unregistered) and nothing crossed it for PART_CLOSED_NS, or,
 * failing that, when nothing crossed it for PART_IDLE_NS (least recently used first), so made-up
 * session ids hold a slot at most PART_IDLE_NS after their last sample. Until session 81 a slot was
 * never freed: the 65th session of the relay's lifetime was dropped even with nothing else open.
 * Reclaimed only when a new session finds no free slot: a quiet live session keeps its writers. */
#define MAX_PARTS 64
#define PART_ALIVE_MAX 32                    /* source instances tracked per slot */
#define PART_CLOSED_NS 1000000000LL          /* 1 s */
#define PART_IDLE_NS 30000000000LL           /* 30 s */

typedef struct sess_part {
  int used;
  uint32_t sid;
  dds_entity_t pub; /* 0 until its writers are made; deleting it deletes them */
  dds_entity_t writer[PALP_TOPIC_COUNT];
  dds_instance_handle_t own[PALP_TOPIC_COUNT]; /* the writers' handles, 0 for none */
  int64_t last_ns;  /* the last sample that crossed it [CLOCK_MONOTONIC ns] */
  /* the source instances it carried that are still alive (their readers' handles); lost: more
   * than the set holds, the slot then waits for PART_IDLE_NS */
  dds_instance_handle_t alive[PART_ALIVE_MAX];
  int alive_count, alive_lost;
} sess_part;

typedef struct side {
  dds_entity_t pp, sub_global, sub_session, pub_global, ws, stop_gc;
  dds_entity_t reader[PALP_TOPIC_COUNT], topic[PALP_TOPIC_COUNT];
  dds_entity_t writer_global[PALP_TOPIC_COUNT];
  /* session topics: per session's partition a publisher and a writer of every session topic,
   * all made when the first sample of the session crosses to this side (under the lock) */
  sess_part part[MAX_PARTS];
  /* the relay's own global writers on this side (and each part's own): their samples are never
   * relayed back; made before the threads start, read-only after */
  dds_instance_handle_t own[PALP_TOPIC_COUNT];
  int own_count;
} side;

typedef struct rx_arg {
  struct palp_netem *n;
  int from;
} rx_arg;

typedef struct item {
  int64_t due;   /* CLOCK_MONOTONIC [ns] */
  int to;        /* destination side 0 (A) / 1 (B) */
  int kind;      /* palp_dds_topic_kind */
  int op;        /* 0 write, 1 dispose, 2 unregister */
  dds_instance_handle_t ih; /* the source instance (its reader's handle) */
  int after;     /* after a write: 0 nothing, 1 dispose, 2 unregister (the sample's instance was
                  * no longer alive when the relay took it: Cyclone then carries the state on the
                  * valid sample and queues no invalid one) */
  void *sample;  /* deep copy; freed after delivery */
  size_t bytes;  /* what it holds in memory (item_bytes) */
  uint64_t seq;  /* queued order: equal due times leave in it */
} item;

/* FIFO per instance, not per topic (until session 81 one topic's samples of every session and
 * writer were kept in one order: at 20 +- 5 ms and one sample each 0.16 ms the mean delay was
 * 23.4 ms, 29% above 24 ms, and one late reliable sample of one session delayed every other
 * session's samples of that topic). DDS orders only per writer and instance anyway. */
#define ORDER_SLOTS 4096 /* a power of 2; streams with a sample in flight */
#define ORDER_PROBES 16
typedef struct order_ent {
  dds_instance_handle_t ih;
  int64_t last_due; /* < now: nothing of its stream in flight, the entry is free */
  int to, kind;
} order_ent;

struct palp_netem {
  palp_netem_def def;
  side s[2];
  pthread_t rx[2], tx;
  int rx_started[2], tx_started;
  atomic_int stop;
  pthread_mutex_t lock;
  pthread_cond_t cond;
  /* The samples in flight, a min-heap on (due, seq). Not a list kept sorted: with each instance
   * delayed on its own, a sample lands anywhere in the last 2 x jitter of the queue, and a walk
   * from the head costs the whole queue (a 10 s delay holds 10 s of samples) per sample. */
  item **heap;
  int queued, heap_cap;
  uint64_t seq;
  size_t queued_bytes, budget; /* held by the queue's items, and at most (writes; state changes 1/8 more) */
  /* Per (side, topic, source instance) the due time of its latest queued sample, so that an
   * instance's samples keep their order (order_keep); spill: the latest due of the samples whose
   * stream found no entry. */
  order_ent order[ORDER_SLOTS];
  int64_t spill[2][PALP_TOPIC_COUNT];
  uint64_t rng;
  palp_netem_stats st;
  /* st.delay_min holds a delay. Not "forwarded + retransmitted > 0": nothing is forwarded
   * until the first sample falls due, and until then every enqueue overwrote the minimum.
   * Like st, under lock (enqueue runs on both rx threads). */
  int have_min;
  rx_arg *rx_args;
};

/* palp_dds's one list: until 2026-12-07 this was a list of the relay's own that stopped at the
 * five streams, and a station behind the relay marked lumps nobody answered and got no debrief. */
static int is_session_topic(int k) { return palp_dds_topic_in_session((palp_dds_topic_kind)k); }

static int is_reliable(int k) {
  dds_qos_t *q = palp_dds_qos((palp_dds_topic_kind)k);
  dds_reliability_kind_t r = DDS_RELIABILITY_BEST_EFFORT;
  dds_duration_t d;
  dds_qget_reliability(q, &r, &d);
  dds_delete_qos(q);
  return r == DDS_RELIABILITY_RELIABLE;
}

/* splitmix64: small, seedable, good enough for delays and losses. */
static double uniform(palp_netem *n) {
  uint64_t z = (n->rng += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static void free_sample(int kind, void *p) {
  if (!p) return;
  dds_sample_free(p, palp_dds_topic_descriptor((palp_dds_topic_kind)kind), DDS_FREE_ALL);
}

/* Bytes a queued sample holds: the item, the sample and its sequences' buffers (palp's types have
 * no unbounded string; bounded ones are inline). By hand per type: the sequences are few and listed
 * here; a type given a new sequence must be added (the queue then undercounts it). */
#define SEQ_BYTES(seq) ((size_t)(seq)._length * sizeof *(seq)._buffer)
static size_t item_bytes(int kind, const void *sample) {
  size_t b = sizeof(item) + sizeof(item *); /* and its place in the heap */
  if (!sample) return b;
  b += palp_dds_topic_descriptor((palp_dds_topic_kind)kind)->m_size;
  switch ((palp_dds_topic_kind)kind) {
  case PALP_TOPIC_CATALOGUE: {
    const palp_Phantom *x = sample;
    return b + SEQ_BYTES(x->rest) + SEQ_BYTES(x->triangles);
  }
  case PALP_TOPIC_FEEDBACK: return b + SEQ_BYTES(((const palp_Feedback *)sample)->fingers);
  case PALP_TOPIC_DEFORMATION: return b + SEQ_BYTES(((const palp_Deformation *)sample)->positions);
  case PALP_TOPIC_SERVER_STATUS: return b + SEQ_BYTES(((const palp_ServerStatus *)sample)->sessions);
  case PALP_TOPIC_SERVER_IDENTITY: return b + SEQ_BYTES(((const palp_ServerIdentity *)sample)->phantoms);
  case PALP_TOPIC_DEBRIEF: return b + SEQ_BYTES(((const palp_Debrief *)sample)->lesion);
  case PALP_TOPIC_FINGER_SAMPLE: return b + SEQ_BYTES(((const palp_FingerSample *)sample)->triangles);
  default: return b;
  }
}

static int item_before(const item *a, const item *b) { return a->due < b->due || (a->due == b->due && a->seq < b->seq); }

static int heap_push(palp_netem *n, item *it) {
  if (n->queued == n->heap_cap) {
    const int cap = n->heap_cap ? 2 * n->heap_cap : 256;
    item **h = realloc(n->heap, (size_t)cap * sizeof *h);
    if (!h) return -1;
    n->heap = h, n->heap_cap = cap;
  }
  int i = n->queued++;
  while (i > 0 && item_before(it, n->heap[(i - 1) / 2])) {
    n->heap[i] = n->heap[(i - 1) / 2];
    i = (i - 1) / 2;
  }
  n->heap[i] = it;
  return 0;
}

static item *heap_pop(palp_netem *n) {
  item *top = n->heap[0], *last = n->heap[--n->queued];
  int i = 0;
  for (;;) {
    int c = 2 * i + 1;
    if (c >= n->queued) break;
    if (c + 1 < n->queued && item_before(n->heap[c + 1], n->heap[c])) c++;
    if (!item_before(n->heap[c], last)) break;
    n->heap[i] = n->heap[c];
    i = c;
  }
  if (n->queued > 0) n->heap[i] = last;
  return top;
}

/* The due time of a sample of instance ih of (to, kind) drawn as `due` at time now, kept in order
 * after that instance's earlier ones; under the lock. An entry whose last due has passed holds
 * nothing back (every later due is >= now), so it is free for another stream. A stream that finds
 * neither its entry nor a free one among ORDER_PROBES (4096 streams in flight) is ordered against
 * the topic's spill, as is any new stream while a spilled sample is in flight: order is kept, at
 * the cost of the old per-topic bias in that case only. */
static int64_t order_keep(palp_netem *n, int64_t now, int to, int kind, dds_instance_handle_t ih, int64_t due) {
  uint64_t h = ih ^ ((uint64_t)(to * PALP_TOPIC_COUNT + kind) << 48);
  h = (h ^ (h >> 31)) * 0x94D049BB133111EBull;
  h ^= h >> 29;
  order_ent *free_e = NULL;
  for (int p = 0; p < ORDER_PROBES; p++) {
    order_ent *e = &n->order[(h + (uint64_t)p) & (ORDER_SLOTS - 1)];
    if (e->last_due < now) {
      if (!free_e) free_e = e;
    } else if (e->ih == ih && e->to == to && e->kind == kind) {
      if (due < e->last_due) due = e->last_due;
      e->last_due = due;
      return due;
    }
  }
  int64_t *spill = &n->spill[to][kind];
  if (due < *spill) due = *spill; /* (a spill in the past is below every due) */
  if (free_e) *free_e = (order_ent){.ih = ih, .last_due = due, .to = to, .kind = kind};
  else *spill = due;
  return due;
}

/* Queues a copy for the other side, drawn at time now [CLOCK_MONOTONIC ns] (a test's own clock;
 * enqueue: the real one); called with the lock held. */
static void enqueue_at(palp_netem *n, int64_t now, int to, int kind, int op, int after, dds_instance_handle_t ih,
                       void *sample) {
  /* Bounded by memory, not by count (until session 81: 65536 samples, which at a 100k-vertex
   * deformation's 2.4 MB each is 157 GB; a 10 s delay held 231 MB after 100 of them). Past the
   * budget a sample is lost, as on a full link, and counted; a dispose or unregister may use 1/8
   * more, so that a flood of large samples does not also leave a finger pressed: alone, or carried by
   * a write (`after`: a writer deleted just after its last sample; until session 90 such a write had
   * the plain budget, and its end was lost with it; found by review). */
  const size_t bytes = item_bytes(kind, sample);
  const size_t limit = op || after ? n->budget + n->budget / 8 : n->budget;
  if (n->queued_bytes + bytes > limit) {
    n->st.dropped++;
    n->st.over_budget++;
    free_sample(kind, sample);
    return;
  }
  double d = n->def.delay + n->def.jitter * (2 * uniform(n) - 1);
  const int lost = uniform(n) < n->def.loss;
  if (lost && !is_reliable(kind)) {
    /* Best-effort: nothing is retransmitted. A write's data is lost (dropped); an instance's end (a
     * dispose or unregister, alone or carried by the lost write) still crosses, at the sample's own
     * delay: a lost end would leave a finger pressed behind the relay, which the relay does not
     * emulate. Each loss draw that hits is counted once: a write in dropped, an end alone in
     * ends_kept. Until session 83 such an end was also delayed a round trip and counted as
     * "retransmitted" (at loss 0.5, 2000 best-effort samples queued were reported as 506 dropped and
     * 1020 retransmitted). */
    if (op == 0) {
      n->st.dropped++;
      if (!after) {
        free_sample(kind, sample);
        return;
      }
      op = after, after = 0;
    } else {
      n->st.ends_kept++;
    }
  } else if (lost) {
    d += 2 * n->def.delay; /* reliable: the retransmission comes one round trip later */
    n->st.retransmitted++;
  }
  if (d < 0) d = 0;
  /* A sample never overtakes an earlier one of its instance (as DDS orders them); samples of other
   * instances, other sessions' or fingers', keep their own delays. */
  const int64_t due = order_keep(n, now, to, kind, ih, now + (int64_t)(d * 1e9));
  const double applied = (double)(due - now) * 1e-9;
  if (!n->have_min || applied < n->st.delay_min) n->st.delay_min = applied, n->have_min = 1;
  if (applied > n->st.delay_max) n->st.delay_max = applied;
  item *it = calloc(1, sizeof *it);
  if (!it) {
    free_sample(kind, sample);
    n->st.dropped++;
    return;
  }
  *it = (item){.due = due, .to = to, .kind = kind, .op = op, .after = after, .ih = ih, .sample = sample, .bytes = bytes,
               .seq = n->seq++};
  if (heap_push(n, it) < 0) {
    free_sample(kind, sample);
    free(it);
    n->st.dropped++;
    return;
  }
  n->queued_bytes += bytes;
  pthread_cond_signal(&n->cond);
}

/* Queues a copy for the other side, now; called with the lock held. */
static void enqueue(palp_netem *n, int to, int kind, int op, int after, dds_instance_handle_t ih, void *sample) {
  enqueue_at(n, palp_dds_now_ns(), to, kind, op, after, ih, sample);
}

/* The relay's writers do not dispose what they unregister (Cyclone's default does): an unregister
 * crosses as an unregister, a dispose as a dispose, and writers the relay deletes leave their
 * instances without a writer, as a link that went down would, not disposed. */
static dds_entity_t relay_writer(dds_entity_t parent, dds_entity_t topic, int kind) {
  dds_qos_t *q = palp_dds_qos((palp_dds_topic_kind)kind);
  dds_qset_writer_data_lifecycle(q, false);
  const dds_entity_t w = dds_create_writer(parent, topic, q, NULL);
  dds_delete_qos(q);
  return w;
}

static void add_own(side *s, dds_entity_t w) {
  dds_instance_handle_t h;
  if (s->own_count < PALP_TOPIC_COUNT && dds_get_instance_handle(w, &h) == 0) s->own[s->own_count++] = h;
}

/* Under the lock (the transmit thread makes and reclaims the parts). */
static int is_own(side *s, dds_instance_handle_t h) {
  for (int i = 0; i < s->own_count; i++)
    if (s->own[i] == h) return 1;
  for (int i = 0; i < MAX_PARTS; i++)
    if (s->part[i].used)
      for (int k = 0; k < PALP_TOPIC_COUNT; k++)
        if (s->part[i].own[k] == h) return 1;
  return 0;
}

static void part_release(sess_part *p) {
  if (p->pub > 0) dds_delete(p->pub); /* and its writers */
  memset(p, 0, sizeof *p);
}

/* The slot of session sid on side s at time now: its own, a free one, or a reclaimed one (a closed
 * session's, else the least recently used idle one); -1 when every slot is busy. A new or reclaimed
 * slot has pub 0: the caller makes its writers. */
static int part_slot(palp_netem *n, side *s, uint32_t sid, int64_t now) {
  int free_i = -1, closed_i = -1, idle_i = -1;
  for (int i = 0; i < MAX_PARTS; i++) {
    const sess_part *p = &s->part[i];
    if (!p->used) {
      if (free_i < 0) free_i = i;
      continue;
    }
    if (p->sid == sid) return i;
    const int64_t idle = now - p->last_ns;
    if (p->alive_count == 0 && !p->alive_lost && idle >= PART_CLOSED_NS &&
        (closed_i < 0 || p->last_ns < s->part[closed_i].last_ns))
      closed_i = i;
    if (idle >= PART_IDLE_NS && (idle_i < 0 || p->last_ns < s->part[idle_i].last_ns)) idle_i = i;
  }
  const int i = free_i >= 0 ? free_i : closed_i >= 0 ? closed_i : idle_i;
  if (i < 0) return -1;
  if (s->part[i].used) {
    part_release(&s->part[i]);
    n->st.sessions_reclaimed++;
  }
  s->part[i].used = 1, s->part[i].sid = sid, s->part[i].last_ns = now;
  return i;
}

/* Notes a sample crossing slot p: a write keeps its source instance alive, a dispose or unregister
 * (alone or after a write) ends it. */
static void part_note(sess_part *p, int64_t now, int op, int after, dds_instance_handle_t ih) {
  p->last_ns = now;
  int j = 0;
  while (j < p->alive_count && p->alive[j] != ih) j++;
  if (op == 0 && after == 0) {
    if (j < p->alive_count) return;
    if (p->alive_count < PART_ALIVE_MAX) p->alive[p->alive_count++] = ih;
    else p->alive_lost = 1;
  } else if (j < p->alive_count) {
    p->alive[j] = p->alive[--p->alive_count];
  }
}

/* The writer of a session topic on side s, its session's writers made on first use. All of them at
 * once, not each topic's at its first sample: a writer made for a sample is written before any reader
 * has matched it, and the server writes a session's debrief and unregisters it as the session closes
 * (its writer goes with the session), so a debrief writer made then lost its one sample to the
 * unregister before the station's reader matched (2026-12-07: no station behind the relay was ever
 * debriefed). Made with the session's first feedback or contact, they match as the server's own do.
 * Under the lock. */
static dds_entity_t writer_for(palp_netem *n, side *s, const item *it, int64_t now) {
  if (!is_session_topic(it->kind)) return s->writer_global[it->kind];
  const uint32_t sid = *(const uint32_t *)it->sample; /* session_id is every session type's first member */
  const int i = part_slot(n, s, sid, now);
  if (i < 0) return 0;
  sess_part *p = &s->part[i];
  if (p->pub <= 0) {
    char name[64];
    palp_dds_session_partition(sid, name, sizeof name);
    p->pub = palp_dds_session_publisher(s->pp, name);
    for (int k = 0; k < PALP_TOPIC_COUNT && p->pub > 0; k++) {
      if (!is_session_topic(k)) continue;
      p->writer[k] = relay_writer(p->pub, s->topic[k], k);
      if (p->writer[k] <= 0 || dds_get_instance_handle(p->writer[k], &p->own[k]) != 0) {
        part_release(p); /* and the writers made so far; the session's next sample tries again */
        return 0;
      }
    }
    if (p->pub <= 0) {
      part_release(p);
      return 0;
    }
  }
  part_note(p, now, it->op, it->after, it->ih);
  return p->writer[it->kind];
}

static void *tx_main(void *arg) {
  palp_netem *n = arg;
  pthread_mutex_lock(&n->lock);
  while (!atomic_load(&n->stop)) {
    if (!n->queued) {
      struct timespec ts;
      clock_gettime(CLOCK_MONOTONIC, &ts);
      ts.tv_nsec += 50000000;
      if (ts.tv_nsec >= 1000000000) {
        ts.tv_sec++;
        ts.tv_nsec -= 1000000000;
      }
      pthread_cond_timedwait(&n->cond, &n->lock, &ts);
      continue;
    }
    const int64_t now = palp_dds_now_ns();
    if (n->heap[0]->due > now) {
      const int64_t due = n->heap[0]->due;
      struct timespec ts = {.tv_sec = (time_t)(due / 1000000000), .tv_nsec = (long)(due % 1000000000)};
      pthread_cond_timedwait(&n->cond, &n->lock, &ts);
      continue;
    }
    item *it = heap_pop(n);
    n->queued_bytes -= it->bytes;
    side *s = &n->s[it->to];
    const dds_entity_t w = writer_for(n, s, it, now);
    pthread_mutex_unlock(&n->lock);
    /* Any failure is a drop, counted: a write refused, or an unregister of an instance this
     * writer never registered. */
    dds_return_t rc = w > 0 ? 0 : DDS_RETCODE_ERROR;
    if (rc == 0 && it->op == 0) rc = dds_write(w, it->sample);
    if (rc == 0 && (it->op == 1 || it->after == 1)) rc = dds_dispose(w, it->sample);
    if (rc == 0 && (it->op == 2 || it->after == 2)) rc = dds_unregister_instance(w, it->sample);
    free_sample(it->kind, it->sample);
    free(it);
    pthread_mutex_lock(&n->lock);
    if (rc == 0) n->st.forwarded++;
    else n->st.dropped++;
  }
  pthread_mutex_unlock(&n->lock);
  return NULL;
}

static void *rx_main(void *arg) {
  rx_arg *ra = arg;
  palp_netem *n = ra->n;
  side *s = &n->s[ra->from];
  const int to = 1 - ra->from;
  while (!atomic_load(&n->stop)) {
    dds_waitset_wait(s->ws, NULL, 0, DDS_MSECS(100));
    for (int k = 0; k < PALP_TOPIC_COUNT; k++) {
      const dds_topic_descriptor_t *desc = palp_dds_topic_descriptor((palp_dds_topic_kind)k);
      for (;;) {
        void *buf = calloc(1, desc->m_size);
        if (!buf) break;
        void *ptr[1] = {buf};
        dds_sample_info_t info;
        if (dds_take(s->reader[k], ptr, &info, 1, 1) <= 0) {
          free(buf);
          break;
        }
        int op = 0, after = 0;
        if (!info.valid_data) {
          /* A dispose or unregister: dds_take fills an invalid sample's key fields (session_id
           * included, which picks the partition), as server/session.c reads a finger off it. Not
           * dds_instance_get_key: once the take has emptied an instance that has no writer left,
           * Cyclone frees it and the lookup fails, and until session 81 every such unregister was
           * lost, uncounted (a stalled station's fingers stayed pressed behind the relay). */
          if (info.instance_state == DDS_IST_ALIVE) { /* no state change to carry */
            free_sample(k, buf);
            continue;
          }
          op = info.instance_state == DDS_IST_NOT_ALIVE_DISPOSED ? 1 : 2;
        } else if (info.instance_state != DDS_IST_ALIVE) {
          after = info.instance_state == DDS_IST_NOT_ALIVE_DISPOSED ? 1 : 2;
        }
        pthread_mutex_lock(&n->lock);
        /* Ignore-local QoS is not enough on every Cyclone release: a sample of one
         * of the relay's own writers is never sent back (it would loop). */
        if (is_own(s, info.publication_handle)) {
          pthread_mutex_unlock(&n->lock);
          free_sample(k, buf);
          continue;
        }
        if (op || after) n->st.disposals++;
        enqueue(n, to, k, op, after, info.instance_handle, buf);
        pthread_mutex_unlock(&n->lock);
      }
    }
  }
  return NULL;
}

static int open_side(palp_netem *n, side *s, uint32_t domain, char *err, size_t errlen) {
  /* The relay must not read back what it writes itself on the same domain. */
  dds_qos_t *q = dds_create_qos();
  dds_qset_ignorelocal(q, DDS_IGNORELOCAL_PARTICIPANT);
  s->pp = dds_create_participant((dds_domainid_t)domain, q, NULL);
  dds_delete_qos(q);
  if (s->pp < 0) {
    snprintf(err, errlen, "netem: cannot create a participant on domain %u: %s", domain, dds_strretcode(s->pp));
    return PALP_EIO;
  }
  s->sub_global = dds_create_subscriber(s->pp, NULL, NULL);
  s->sub_session = palp_dds_session_subscriber(s->pp, "palp/session/*");
  s->pub_global = dds_create_publisher(s->pp, NULL, NULL);
  s->ws = dds_create_waitset(s->pp);
  s->stop_gc = dds_create_guardcondition(s->pp);
  if (s->sub_global < 0 || s->sub_session < 0 || s->pub_global < 0 || s->ws < 0 || s->stop_gc < 0) {
    snprintf(err, errlen, "netem: cannot create publishers/subscribers on domain %u", domain);
    return PALP_EIO;
  }
  dds_waitset_attach(s->ws, s->stop_gc, 0);
  for (int k = 0; k < PALP_TOPIC_COUNT; k++) {
    s->topic[k] = palp_dds_create_topic(s->pp, (palp_dds_topic_kind)k);
    if (s->topic[k] < 0) {
      snprintf(err, errlen, "netem: cannot create topic %s", palp_dds_topic_name((palp_dds_topic_kind)k));
      return PALP_EIO;
    }
    s->reader[k] = palp_dds_create_reader(is_session_topic(k) ? s->sub_session : s->sub_global, s->topic[k],
                                          (palp_dds_topic_kind)k);
    if (!is_session_topic(k)) {
      s->writer_global[k] = relay_writer(s->pub_global, s->topic[k], k);
      if (s->writer_global[k] > 0) add_own(s, s->writer_global[k]);
    }
    dds_entity_t rc = s->reader[k] > 0 ? dds_create_readcondition(s->reader[k], DDS_ANY_STATE) : -1;
    if (s->reader[k] < 0 || s->writer_global[k] < 0 || rc < 0 || dds_waitset_attach(s->ws, rc, 0) < 0) {
      snprintf(err, errlen, "netem: cannot create the relay's endpoints for %s",
               palp_dds_topic_name((palp_dds_topic_kind)k));
      return PALP_EIO;
    }
  }
  (void)n;
  return 0;
}

palp_netem *palp_netem_start(const palp_netem_def *def, char *err, size_t errlen) {
  if (!def || def->domain_a == def->domain_b || def->domain_a > 232 || def->domain_b > 232 ||
      !(def->delay >= 0 && def->delay <= 10) || !(def->jitter >= 0 && def->jitter <= def->delay) ||
      !(def->loss >= 0 && def->loss <= 0.5)) {
    if (def)
      snprintf(err, errlen, "netem: domains %u and %u, delay %g s, jitter %g s, loss %g: want domains that differ (0..232), "
               "0 <= jitter <= delay <= 10 s, loss in [0, 0.5]", def->domain_a, def->domain_b, def->delay, def->jitter,
               def->loss);
    else snprintf(err, errlen, "netem: no definition");
    return NULL;
  }
  palp_netem *n = calloc(1, sizeof *n);
  if (!n) {
    snprintf(err, errlen, "netem: out of memory");
    return NULL;
  }
  n->def = *def;
  n->budget = def->queue_bytes ? def->queue_bytes : PALP_NETEM_QUEUE_BYTES;
  n->rng = def->seed;
  pthread_mutex_init(&n->lock, NULL);
  pthread_condattr_t ca;
  pthread_condattr_init(&ca);
  pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
  pthread_cond_init(&n->cond, &ca);
  pthread_condattr_destroy(&ca);
  if (open_side(n, &n->s[0], def->domain_a, err, errlen) < 0 || open_side(n, &n->s[1], def->domain_b, err, errlen) < 0) {
    palp_netem_stop(n);
    return NULL;
  }
  rx_arg *ra = calloc(2, sizeof *ra);
  if (!ra || pthread_create(&n->tx, NULL, tx_main, n) != 0) {
    free(ra);
    snprintf(err, errlen, "netem: cannot start its threads");
    palp_netem_stop(n);
    return NULL;
  }
  n->tx_started = 1;
  for (int i = 0; i < 2; i++) {
    ra[i] = (rx_arg){n, i};
    if (pthread_create(&n->rx[i], NULL, rx_main, &ra[i]) == 0) n->rx_started[i] = 1;
  }
  n->rx_args = ra; /* freed by palp_netem_stop after the threads are joined */
  return n;
}

void palp_netem_get_stats(palp_netem *n, palp_netem_stats *out) {
  pthread_mutex_lock(&n->lock);
  *out = n->st;
  pthread_mutex_unlock(&n->lock);
}

void palp_netem_stop(palp_netem *n) {
  if (!n) return;
  atomic_store(&n->stop, 1);
  for (int i = 0; i < 2; i++)
    if (n->s[i].stop_gc > 0) dds_set_guardcondition(n->s[i].stop_gc, true);
  pthread_mutex_lock(&n->lock);
  pthread_cond_broadcast(&n->cond);
  pthread_mutex_unlock(&n->lock);
  for (int i = 0; i < 2; i++)
    if (n->rx_started[i]) pthread_join(n->rx[i], NULL);
  if (n->tx_started) pthread_join(n->tx, NULL);
  for (int i = 0; i < n->queued; i++) {
    free_sample(n->heap[i]->kind, n->heap[i]->sample);
    free(n->heap[i]);
  }
  free(n->heap);
  for (int i = 0; i < 2; i++)
    if (n->s[i].pp > 0) dds_delete(n->s[i].pp); /* and every part's publisher */
  pthread_mutex_destroy(&n->lock);
  pthread_cond_destroy(&n->cond);
  free(n->rx_args);
  free(n);
}
