/* palp_dds_refusals.c - the peers DDS Security refused, counted and said once (palp_dds_refusals.h). */
#include "palp_dds_refusals.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h"

const char *palp_dds_refusal_kind_words(palp_dds_refusal_kind k) {
  return k == PALP_DDS_REFUSED_PERMISSIONS     ? "for its permissions"
         : k == PALP_DDS_REFUSED_UNAUTHENTICATED ? "without an identity"
                                                 : "at the handshake";
}

const char *palp_dds_refusal_kind_name(palp_dds_refusal_kind k) {
  return k == PALP_DDS_REFUSED_PERMISSIONS     ? "permissions"
         : k == PALP_DDS_REFUSED_UNAUTHENTICATED ? "unauthenticated"
                                                 : "handshake";
}

/* Lines and records made under t->mu and said after it is released: the owner's log and
 * session log take locks of their own, which another thread may hold while it asks this
 * table for its counts (palp-server's summary into its log file did: a lock-order
 * inversion ThreadSanitizer found, a deadlock if a refusal came as the server stopped). */
typedef struct pending_line {
  char line[512];
  palp_dds_refusal r;
  uint64_t count; /* for the record callback */
} pending_line;

typedef struct pending {
  int n;
  pending_line e[PALP_DDS_REFUSAL_SLOTS + 2]; /* one per slot, the overflow entry, one new peer */
} pending;

/* t->mu held. */
static void say(palp_dds_refusals *t, pending *p, const palp_dds_refusal *r, uint64_t count, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static void say(palp_dds_refusals *t, pending *p, const palp_dds_refusal *r, uint64_t count, const char *fmt, ...) {
  if (p->n >= (int)(sizeof p->e / sizeof p->e[0])) return; /* cannot happen: see pending */
  pending_line *e = &p->e[p->n++];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(e->line, sizeof e->line, fmt, ap);
  va_end(ap);
  e->r = *r;
  e->count = count;
  t->lines++;
}

/* t->mu released: the lines to the log, the records to the owner, in the order made. */
static void say_all(palp_dds_refusals *t, const pending *p) {
  for (int i = 0; i < p->n; i++) {
    if (t->me[0] && t->aside && !palp_dds_refusal_concerns_trainee(&p->e[i].r, t->me))
      t->aside(t->aside_ctx, p->e[i].line);
    else if (t->emit) t->emit(t->emit_ctx, p->e[i].line);
    else fprintf(stderr, "%s\n", p->e[i].line);
    if (t->record) t->record(t->record_ctx, &p->e[i].r, p->e[i].count);
  }
}

void palp_dds_refusals_init(palp_dds_refusals *t, palp_dds_refusals_emit emit, void *ctx, double window_s) {
  memset(t, 0, sizeof *t);
  pthread_mutex_init(&t->mu, NULL);
  t->emit = emit;
  t->emit_ctx = ctx;
  t->window_ns = (int64_t)((window_s > 0 ? window_s : 60.0) * 1e9);
}

void palp_dds_refusals_destroy(palp_dds_refusals *t) {
  pthread_mutex_destroy(&t->mu);
  free(t->names);
  t->names = NULL;
  t->n_names = 0;
}

int palp_dds_refusals_set_names(palp_dds_refusals *t, const palp_dds_peer_name *names, int n) {
  if (n > PALP_DDS_PEER_NAMES_MAX) n = PALP_DDS_PEER_NAMES_MAX;
  palp_dds_peer_name *copy = n > 0 ? malloc((size_t)n * sizeof *copy) : NULL;
  if (n > 0 && !copy) return PALP_ENOMEM;
  for (int i = 0; i < n; i++) {
    copy[i] = names[i];
    copy[i].who[sizeof copy[i].who - 1] = '\0';
  }
  pthread_mutex_lock(&t->mu);
  palp_dds_peer_name *old = t->names;
  t->names = copy;
  t->n_names = n > 0 ? n : 0;
  pthread_mutex_unlock(&t->mu);
  free(old);
  return 0;
}

/* Cyclone writes a GUID as four 32-bit words in hex, most significant byte first, without leading
 * zeros ("f49f7aa2:789ee759:7810bd81:1c1"): the prefix's bytes 0-3, 4-7, 8-11, then the entity. */
int palp_dds_refusal_guid_prefix(const char *who, unsigned char prefix[6]) {
  static const char head[] = "participant ";
  if (!who || strncmp(who, head, sizeof head - 1)) return 0;
  const char *p = who + sizeof head - 1;
  uint32_t w[2] = {0, 0};
  for (int k = 0; k < 2; k++) {
    int digits = 0;
    for (; *p && *p != ':'; p++, digits++) {
      const char c = *p;
      const int v = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
      if (v < 0 || digits >= 8) return 0;
      w[k] = w[k] << 4 | (uint32_t)v;
    }
    if (!digits || *p != ':') return 0;
    p++;
  }
  for (int i = 0; i < 4; i++) prefix[i] = (unsigned char)(w[0] >> (24 - 8 * i));
  prefix[4] = (unsigned char)(w[1] >> 24);
  prefix[5] = (unsigned char)(w[1] >> 16);
  return 1;
}

/* A peer refused for its permissions has authenticated, so its GUID prefix is its certificate's
 * (palp_pem_guid_prefix): named by the one identity that has it, else left as Cyclone gave it.
 * t->mu held. */
static void name_peer(const palp_dds_refusals *t, palp_dds_refusal *r) {
  unsigned char pre[6];
  if (r->kind != PALP_DDS_REFUSED_PERMISSIONS || !t->n_names || !palp_dds_refusal_guid_prefix(r->who, pre)) return;
  const palp_dds_peer_name *hit = NULL;
  for (int i = 0; i < t->n_names; i++)
    if (!memcmp(t->names[i].prefix, pre, 6)) {
      if (hit) return; /* two identities, one prefix (47 bits: not in any classroom): nobody */
      hit = &t->names[i];
    }
  if (hit) snprintf(r->who, sizeof r->who, "%s", hit->who);
}

int palp_dds_refusal_concerns_trainee(const palp_dds_refusal *r, const char *me) {
  if (me && *me && !strcmp(r->who, me)) return 1;
  /* A certificate that did not verify claiming a trainee or an instructor (alice's name from a rogue
   * CA) is not her station refused, nor a classmate: nothing the trainee can act on. One claiming the
   * server stays her concern: a station given another classroom's CA sees the real server so. */
  static const char claim[] = PALP_DDS_UNVERIFIED_CLAIM;
  const char *who = r->who;
  if (!strncmp(who, claim, sizeof claim - 1)) who += sizeof claim - 1;
  return strncmp(who, "trainee/", 8) && strncmp(who, "instructor/", 11);
}

void palp_dds_refusals_focus(palp_dds_refusals *t, const char *me, palp_dds_refusals_emit aside, void *ctx) {
  snprintf(t->me, sizeof t->me, "%s", me ? me : "");
  t->aside = aside;
  t->aside_ctx = ctx;
}

void palp_dds_refusals_on_record(palp_dds_refusals *t, palp_dds_refusals_record fn, void *ctx) {
  t->record = fn;
  t->record_ctx = ctx;
}

/* The repeats of one slot since its last line; t->mu held. "over N s" is the span from that line
 * to the last repeat, not to now: a station that retried for 9 s and stopped was said to have been
 * refused "over 60 s" when the window's tick wrote the line (until 2026-12-05). */
static void report_repeats(palp_dds_refusals *t, pending *p, palp_dds_refusal_slot *s, int64_t now_ns) {
  if (!s->unreported) return;
  say(t, p, &s->r, s->unreported, "DDS Security refused %s %s %llu more time(s) over %.0f s: %s (%llu in all)",
      s->r.who, palp_dds_refusal_kind_words(s->r.kind), (unsigned long long)s->unreported,
      (double)(s->seen_ns - s->reported_ns) * 1e-9, s->r.why, (unsigned long long)s->count);
  s->unreported = 0;
  s->reported_ns = now_ns;
}

/* FNV-1a over the peer and reason: how the overflow entry tells its peers apart without keeping them. */
static uint64_t peer_hash(const palp_dds_refusal *r) {
  uint64_t h = 1469598103934665603ull ^ (uint64_t)r->kind;
  for (const char *p = r->who; *p; p++) h = (h ^ (unsigned char)*p) * 1099511628211ull;
  h = (h ^ 0xffu) * 1099511628211ull;
  for (const char *p = r->why; *p; p++) h = (h ^ (unsigned char)*p) * 1099511628211ull;
  return h ? h : 1; /* 0 marks an empty cell */
}

/* Adds h to the set of cap cells (open addressing); 1 when it was not there, 0 when it was or the set
 * is full (then the peer may be new: the count says "at least"). */
static int set_add(uint64_t *set, int cap, uint64_t h) {
  for (int i = 0, k = (int)(h % (uint64_t)cap); i < cap; i++, k = (k + 1) % cap) {
    if (set[k] == h) return 0;
    if (!set[k]) {
      set[k] = h;
      return 1;
    }
  }
  return 0;
}

/* The overflow entry's repeats since its last line, as one line; t->mu held. */
static void report_others(palp_dds_refusals *t, pending *p, int64_t now_ns) {
  palp_dds_refusal_slot *o = &t->others;
  if (!o->unreported) return;
  const int many = t->o_since >= PALP_DDS_REFUSAL_OTHERS_SEEN;
  palp_dds_refusal agg = {.kind = o->r.kind};
  snprintf(agg.who, sizeof agg.who, "%s%llu other peer(s)", many ? "at least " : "", (unsigned long long)t->o_since);
  /* cut to fit, as every field here (its return read: GCC then knows the cut is meant) */
  if (snprintf(agg.why, sizeof agg.why, "the table of %d named peers is full; the last: %.60s %s, %.60s",
               PALP_DDS_REFUSAL_SLOTS, o->r.who, palp_dds_refusal_kind_words(o->r.kind), o->r.why) < 0)
    agg.why[0] = '\0';
  say(t, p, &agg, o->unreported, "DDS Security refused %s %llu more time(s) over %.0f s (%s) (%llu in all)", agg.who,
      (unsigned long long)o->unreported, (double)(o->seen_ns - o->reported_ns) * 1e-9, agg.why,
      (unsigned long long)o->count);
  o->unreported = 0;
  o->reported_ns = now_ns;
  t->o_since = 0;
  memset(t->o_hash, 0, sizeof t->o_hash);
}

/* A peer refused while every slot is busy; t->mu held. Its first such refusal is said at once
 * (naming the peer: most often the only one); the rest are summed, a line per window. */
static void note_other(palp_dds_refusals *t, pending *p, const palp_dds_refusal *r, int64_t now_ns) {
  palp_dds_refusal_slot *o = &t->others;
  const uint64_t h = peer_hash(r);
  t->o_peers += (uint64_t)set_add(t->o_all_hash, PALP_DDS_REFUSAL_OTHERS_SEEN, h);
  o->r = *r;
  o->count++;
  o->seen_ns = now_ns;
  if (!o->used) {
    o->used = 1;
    o->reported_ns = now_ns;
    say(t, p, r, 1,
        "DDS Security refused %s %s: %s; it gets no answer (the %d peers named here are all still refused: it and any "
        "other new peer are counted together, logged at most every %.0f s)",
        r->who, palp_dds_refusal_kind_words(r->kind), r->why, PALP_DDS_REFUSAL_SLOTS, (double)t->window_ns * 1e-9);
    return;
  }
  o->unreported++;
  t->o_since += (uint64_t)set_add(t->o_hash, PALP_DDS_REFUSAL_OTHERS_SEEN, h);
  if (now_ns - o->reported_ns >= t->window_ns) report_others(t, p, now_ns);
}

void palp_dds_refusals_note(palp_dds_refusals *t, const palp_dds_refusal *seen, int64_t now_ns) {
  pending p = {.n = 0};
  palp_dds_refusal named = *seen;
  const palp_dds_refusal *r = &named;
  pthread_mutex_lock(&t->mu);
  name_peer(t, &named);
  t->total++;
  palp_dds_refusal_slot *s = NULL, *oldest = NULL, *free_slot = NULL;
  for (int i = 0; i < PALP_DDS_REFUSAL_SLOTS; i++) {
    palp_dds_refusal_slot *c = &t->slot[i];
    if (!c->used) {
      if (!free_slot) free_slot = c;
      continue;
    }
    if (c->r.kind == r->kind && !strcmp(c->r.who, r->who) && !strcmp(c->r.why, r->why)) {
      s = c;
      break;
    }
    if (!oldest || c->seen_ns < oldest->seen_ns) oldest = c;
  }
  if (s) {
    s->count++;
    s->unreported++;
    s->seen_ns = now_ns;
    if (now_ns - s->reported_ns >= t->window_ns) report_repeats(t, &p, s, now_ns);
    pthread_mutex_unlock(&t->mu);
    say_all(t, &p);
    return;
  }
  if (!free_slot) {
    /* Full. A slot whose peer stopped being refused long ago makes room (its repeats said first);
     * while all are busy, the new peer goes to the overflow entry: evicting one that still retries
     * made each of its retries "new", a line and a record each (until session 81). */
    if (now_ns - oldest->seen_ns < (int64_t)PALP_DDS_REFUSAL_IDLE_WINDOWS * t->window_ns) {
      note_other(t, &p, r, now_ns);
      pthread_mutex_unlock(&t->mu);
      say_all(t, &p);
      return;
    }
    report_repeats(t, &p, oldest, now_ns);
    free_slot = oldest;
  }
  s = free_slot;
  memset(s, 0, sizeof *s);
  s->r = *r;
  s->used = 1;
  s->count = 1;
  s->seen_ns = s->reported_ns = now_ns;
  /* A station retries once a second for as long as it runs: say it once, plainly. */
  say(t, &p, r, 1, "DDS Security refused %s %s: %s; it gets no answer (repeats counted, logged at most every %.0f s)",
      r->who, palp_dds_refusal_kind_words(r->kind), r->why, (double)t->window_ns * 1e-9);
  pthread_mutex_unlock(&t->mu);
  say_all(t, &p);
}

void palp_dds_refusals_tick(palp_dds_refusals *t, int64_t now_ns) {
  pending p = {.n = 0};
  pthread_mutex_lock(&t->mu);
  for (int i = 0; i < PALP_DDS_REFUSAL_SLOTS; i++) {
    palp_dds_refusal_slot *s = &t->slot[i];
    if (s->used && s->unreported && now_ns - s->reported_ns >= t->window_ns) report_repeats(t, &p, s, now_ns);
  }
  if (t->others.unreported && now_ns - t->others.reported_ns >= t->window_ns) report_others(t, &p, now_ns);
  pthread_mutex_unlock(&t->mu);
  say_all(t, &p);
}

void palp_dds_refusals_flush(palp_dds_refusals *t) {
  pending p = {.n = 0};
  pthread_mutex_lock(&t->mu);
  for (int i = 0; i < PALP_DDS_REFUSAL_SLOTS; i++)
    if (t->slot[i].used) report_repeats(t, &p, &t->slot[i], t->slot[i].seen_ns);
  report_others(t, &p, t->others.seen_ns);
  pthread_mutex_unlock(&t->mu);
  say_all(t, &p);
}

void palp_dds_refusals_counts(palp_dds_refusals *t, uint64_t *total, uint64_t *lines) {
  pthread_mutex_lock(&t->mu);
  if (total) *total = t->total;
  if (lines) *lines = t->lines;
  pthread_mutex_unlock(&t->mu);
}

void palp_dds_refusals_others(palp_dds_refusals *t, uint64_t *peers, uint64_t *refusals) {
  pthread_mutex_lock(&t->mu);
  if (peers) *peers = t->o_peers;
  if (refusals) *refusals = t->others.count;
  pthread_mutex_unlock(&t->mu);
}

int palp_dds_refusals_list(palp_dds_refusals *t, palp_dds_refusal_entry *out, int max) {
  int n = 0;
  pthread_mutex_lock(&t->mu);
  for (int i = 0; i < PALP_DDS_REFUSAL_SLOTS; i++) { /* insertion, most refused first */
    const palp_dds_refusal_slot *s = &t->slot[i];
    if (!s->used) continue;
    int j = n < max ? n++ : max;
    while (j > 0 && out[j - 1].count < s->count) {
      if (j < max) out[j] = out[j - 1];
      j--;
    }
    if (j < max) out[j] = (palp_dds_refusal_entry){.r = s->r, .count = s->count};
  }
  pthread_mutex_unlock(&t->mu);
  return n;
}

int palp_dds_refusals_describe(palp_dds_refusals *t, char *buf, size_t len) {
  if (!buf || !len) return 0;
  buf[0] = '\0';
  palp_dds_refusal_entry e[PALP_DDS_REFUSAL_SLOTS];
  const int n = palp_dds_refusals_list(t, e, PALP_DDS_REFUSAL_SLOTS);
  size_t at = 0;
  for (int k = 0; k < n; k++) {
    const int w = snprintf(buf + at, len - at, "%s%s: %s (%llux)", k ? "; " : "", e[k].r.who, e[k].r.why,
                           (unsigned long long)e[k].count);
    if (w < 0 || (size_t)w >= len - at) { /* cut at the last whole entry */
      buf[at] = '\0';
      return k;
    }
    at += (size_t)w;
  }
  uint64_t op = 0, oc = 0;
  palp_dds_refusals_others(t, &op, &oc);
  if (oc) { /* said only when it fits whole */
    const int w = snprintf(buf + at, len - at, "%s%s%llu other peer(s): %llux", n ? "; " : "",
                           op >= PALP_DDS_REFUSAL_OTHERS_SEEN ? "at least " : "", (unsigned long long)op,
                           (unsigned long long)oc);
    if (w < 0 || (size_t)w >= len - at) buf[at] = '\0';
  }
  return n;
}

static void hook(void *arg, const palp_dds_refusal *r) { palp_dds_refusals_note(arg, r, palp_dds_now_ns()); }

int palp_dds_refusals_install(palp_dds_log_limit *sink, palp_dds_refusals *t, int lines, double window_s) {
  const int rc = palp_dds_log_limit_install(sink, stderr, lines, window_s);
  if (rc == 0) palp_dds_log_limit_on_refusal(sink, hook, t);
  return rc;
}
