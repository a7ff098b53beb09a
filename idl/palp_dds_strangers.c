/* palp_dds_strangers.c - plain DDS participants on a secured domain (palp_dds_strangers.h). */
#include "palp_dds_strangers.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h" /* PALP_E* codes */

/* At most `n` bytes of src appended to dst at *j (dst's size cap), unprintable bytes as '?'. */
static void put(char *dst, size_t cap, size_t *j, const char *src, size_t n) {
  palp_dds_copy_printable(dst + *j, cap - *j, src, strnlen(src, n));
  *j += strlen(dst + *j);
}

/* The vendor ids of the RTPS specification's registry that a classroom may meet. */
static const char *vendor_name(uint8_t a, uint8_t b) {
  if (a != 0x01) return NULL;
  switch (b) {
  case 0x01: return "RTI Connext DDS";
  case 0x03: return "OpenDDS";
  case 0x0f: return "Fast DDS";
  case 0x10: return "Cyclone DDS";
  default: return NULL;
  }
}

int palp_dds_guid_plain(const uint8_t prefix[12]) { return (prefix[0] & 0x80) == 0; }

void palp_dds_stranger_name(const char *process, const char *host, const uint8_t *prefix, char *out, size_t len) {
  enum { PART = 40 };
  if (!len) return;
  out[0] = '\0';
  size_t j = 0;
  if (process && *process) {
    const char *base = strrchr(process, '/');
    const char *p = base && base[1] ? base + 1 : process;
    put(out, len, &j, p, PART);
  } else if (host && *host) {
    put(out, len, &j, "a participant", PART);
  } else if (prefix) { /* it names nothing: its vendor and GUID prefix, which the server's trace also shows */
    const char *v = vendor_name(prefix[0], prefix[1]);
    char buf[96];
    if (v) snprintf(buf, sizeof buf, "a %s participant, GUID prefix ", v);
    else snprintf(buf, sizeof buf, "a participant of vendor %02x%02x, GUID prefix ", prefix[0], prefix[1]);
    put(out, len, &j, buf, sizeof buf);
    for (int i = 0; i < 6; i++) {
      snprintf(buf, sizeof buf, "%02x", prefix[i]);
      put(out, len, &j, buf, 2);
    }
    return;
  } else {
    put(out, len, &j, "a participant that names neither its process nor its host", 64);
    return;
  }
  if (host && *host) {
    put(out, len, &j, " on host ", 16);
    put(out, len, &j, host, PART);
  }
}

int palp_dds_strangers_init(palp_dds_strangers *s, dds_entity_t pp, double grace_s) {
  memset(s, 0, sizeof *s);
  s->grace_ns = (int64_t)(grace_s * 1e9);
  if (dds_get_guid(pp, &s->me) < 0) return PALP_EIO;
  s->ptr = calloc(PALP_DDS_STRANGER_READ, sizeof *s->ptr);
  s->info = calloc(PALP_DDS_STRANGER_READ, sizeof *s->info);
  if (!s->ptr || !s->info) {
    free(s->ptr), free(s->info);
    s->ptr = NULL, s->info = NULL; /* destroy and tick test s->ptr: nothing left to free or read */
    return PALP_ENOMEM;
  }
  static const dds_entity_t topic[3] = {DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, DDS_BUILTIN_TOPIC_DCPSPUBLICATION,
                                        DDS_BUILTIN_TOPIC_DCPSSUBSCRIPTION};
  for (int k = 0; k < 3; k++) {
    s->rd[k] = dds_create_reader(pp, topic[k], NULL, NULL);
    if (s->rd[k] < 0) {
      for (int i = 0; i < k; i++) dds_delete(s->rd[i]);
      free(s->ptr), free(s->info);
      s->ptr = NULL, s->info = NULL;
      return PALP_EIO;
    }
  }
  return 0;
}

void palp_dds_strangers_destroy(palp_dds_strangers *s) {
  if (!s->ptr) return;
  for (int k = 0; k < 3; k++) dds_delete(s->rd[k]);
  free(s->ptr), free(s->info);
  s->ptr = NULL, s->info = NULL;
}

/* The samples of instances gone (participants and endpoints that left) are taken out, so
 * the readers hold only what is alive: bounded over a day of stations coming and going. */
static void take_gone(palp_dds_strangers *s, dds_entity_t rd) {
  const uint32_t gone = DDS_ANY_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_NOT_ALIVE_DISPOSED_INSTANCE_STATE |
                        DDS_NOT_ALIVE_NO_WRITERS_INSTANCE_STATE;
  for (;;) {
    s->ptr[0] = NULL;
    const int n = dds_take_mask(rd, s->ptr, s->info, PALP_DDS_STRANGER_READ, PALP_DDS_STRANGER_READ, gone);
    if (n <= 0) return;
    dds_return_loan(rd, s->ptr, n);
    if (n < PALP_DDS_STRANGER_READ) return;
  }
}

static palp_dds_stranger_slot *find(palp_dds_strangers *s, const dds_guid_t *key) {
  for (int i = 0; i < PALP_DDS_STRANGER_SLOTS; i++)
    if (s->slot[i].used && !memcmp(&s->slot[i].key, key, sizeof *key)) return &s->slot[i];
  return NULL;
}

/* Whether any alive endpoint (DCPSPublication or DCPSSubscription) belongs to participant
 * `key`; -1 when a reader held more than one read can look at (cannot tell). */
static int has_endpoint(palp_dds_strangers *s, const dds_guid_t *key) {
  for (int k = 1; k < 3; k++) {
    s->ptr[0] = NULL;
    const int n = dds_read_mask(s->rd[k], s->ptr, s->info, PALP_DDS_STRANGER_READ, PALP_DDS_STRANGER_READ,
                                DDS_ANY_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_ALIVE_INSTANCE_STATE);
    if (n < 0) return -1;
    int found = 0;
    for (int i = 0; i < n && !found; i++) {
      const dds_builtintopic_endpoint_t *e = s->ptr[i];
      found = s->info[i].valid_data && !memcmp(&e->participant_key, key, sizeof *key);
    }
    if (n > 0) dds_return_loan(s->rd[k], s->ptr, n);
    if (found) return 1;
    if (n == PALP_DDS_STRANGER_READ) return -1;
  }
  return 0;
}

int palp_dds_strangers_tick(palp_dds_strangers *s, palp_dds_refusals *t, int64_t now_ns) {
  if (!s->ptr) return 0;
  for (int k = 0; k < 3; k++) take_gone(s, s->rd[k]);
  for (int i = 0; i < PALP_DDS_STRANGER_SLOTS; i++) s->slot[i].seen = 0;
  s->ptr[0] = NULL;
  const int n = dds_read_mask(s->rd[0], s->ptr, s->info, PALP_DDS_STRANGER_READ, PALP_DDS_STRANGER_READ,
                              DDS_ANY_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_ALIVE_INSTANCE_STATE);
  if (n < 0) return 0;
  /* Who is plain and not yet judged: copied out, as has_endpoint reuses the loan arrays. */
  enum { CAND = PALP_DDS_STRANGER_SLOTS };
  struct {
    dds_guid_t key;
    char name[PALP_DDS_REFUSAL_WHO];
  } cand[CAND];
  int nc = 0;
  for (int i = 0; i < n; i++) {
    const dds_builtintopic_participant_t *p = s->ptr[i];
    if (!s->info[i].valid_data || !memcmp(&p->key, &s->me, sizeof s->me)) continue;
    palp_dds_stranger_slot *sl = find(s, &p->key);
    if (sl) {
      sl->seen = 1;
      if (sl->said) continue;
    }
    /* all three asked, one by one: each one present is returned, allocated, and freed below */
    char *proc = NULL, *host = NULL, *pid = NULL;
    int props = 0;
    if (p->qos) {
      props += dds_qget_prop(p->qos, "__ProcessName", &proc);
      props += dds_qget_prop(p->qos, "__Hostname", &host);
      props += dds_qget_prop(p->qos, "__Pid", &pid);
    }
    if ((props || palp_dds_guid_plain(p->key.v)) && nc < CAND) {
      cand[nc].key = p->key;
      palp_dds_stranger_name(proc, host, p->key.v, cand[nc].name, sizeof cand[nc].name);
      nc++;
    }
    dds_free(proc), dds_free(host), dds_free(pid);
  }
  if (n > 0) dds_return_loan(s->rd[0], s->ptr, n);
  /* Slots of peers gone are freed: a station back under the same GUID is new again. */
  for (int i = 0; i < PALP_DDS_STRANGER_SLOTS; i++)
    if (s->slot[i].used && !s->slot[i].seen) s->slot[i].used = 0;
  int noted = 0;
  for (int c = 0; c < nc; c++) {
    palp_dds_stranger_slot *sl = find(s, &cand[c].key);
    if (!sl) {
      for (int i = 0; i < PALP_DDS_STRANGER_SLOTS && !sl; i++)
        if (!s->slot[i].used) sl = &s->slot[i];
      if (!sl) break; /* full: the others are looked at once slots free up */
      *sl = (palp_dds_stranger_slot){.key = cand[c].key, .first_ns = now_ns, .used = 1, .seen = 1};
    }
    if (now_ns - sl->first_ns < s->grace_ns) continue;
    const int e = has_endpoint(s, &cand[c].key);
    if (e != 0) {
      if (e > 0) sl->said = 1; /* talks to us: authenticated, nothing to say */
      continue;
    }
    palp_dds_refusal r = {.kind = PALP_DDS_REFUSED_UNAUTHENTICATED};
    snprintf(r.who, sizeof r.who, "%s", cand[c].name);
    snprintf(r.why, sizeof r.why, "a plain DDS participant, with no DDS Security identity (started without --pki and "
                                  "--identity?)");
    palp_dds_refusals_note(t, &r, now_ns);
    sl->said = 1;
    noted++;
  }
  return noted;
}
