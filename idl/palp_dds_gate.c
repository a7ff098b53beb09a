/*
 * palp_dds_gate.c - the sessions a classroom-wide reader lets in (palp_dds_gate.h).
 */
#include "palp_dds_gate.h"

#include <stdbool.h>
#include <stddef.h>
#include <string.h>

#include "palp.h"
#include "palp_types.h"

#define FINGERS 4

/* Every stream's session id is its first key, the finger its second: the filters read them at
 * these offsets whatever the type. */
_Static_assert(offsetof(palp_Contact, session_id) == 0 && offsetof(palp_Feedback, session_id) == 0 &&
                   offsetof(palp_Deformation, session_id) == 0 && offsetof(palp_LocalModel, session_id) == 0 &&
                   offsetof(palp_FingerSample, session_id) == 0 && offsetof(palp_Finding, session_id) == 0 &&
                   offsetof(palp_FindingStatus, session_id) == 0 && offsetof(palp_Debrief, session_id) == 0 &&
                   offsetof(palp_SessionScore, session_id) == 0 && offsetof(palp_SessionLog, session_id) == 0,
               "the session id first");
_Static_assert(offsetof(palp_LocalModel, finger) == offsetof(palp_Contact, finger) &&
                   offsetof(palp_FingerSample, finger) == offsetof(palp_Contact, finger),
               "the finger second");

void palp_dds_gate_init(palp_dds_gate *g, int slots) {
  memset(g, 0, sizeof *g);
  g->slots = slots < 1 ? 1 : slots > PALP_DDS_GATE_SLOTS_MAX ? PALP_DDS_GATE_SLOTS_MAX : slots;
}

void palp_dds_gate_set(palp_dds_gate *g, int slot, uint32_t sid) {
  if (slot >= 0 && slot < g->slots) atomic_store_explicit(&g->slot_sid[slot], sid, memory_order_relaxed);
}

int palp_dds_gate_passes(palp_dds_gate *g, uint32_t sid) {
  if (sid == 0) return 0;
  for (int i = 0; i < g->slots; i++)
    if (atomic_load_explicit(&g->slot_sid[i], memory_order_relaxed) == sid) return 1;
  for (int i = 0; i < PALP_DDS_GATE_HEARD; i++)
    if (atomic_load_explicit(&g->heard[i], memory_order_relaxed) == sid) return 1;
  return 0;
}

/* The state topic's filter (receive thread): passes every state; notes an open session's id. A
 * forged flood of states (unsecured) cycles this ring, never the owner's slots. */
static bool state_heard(const void *sample, void *arg) {
  const palp_SessionState *m = sample;
  palp_dds_gate *g = arg;
  if (m->phase == palp_PHASE_OPEN && m->session_id != 0) {
    const unsigned k = atomic_fetch_add_explicit(&g->heard_next, 1u, memory_order_relaxed) % PALP_DDS_GATE_HEARD;
    atomic_store_explicit(&g->heard[k], m->session_id, memory_order_relaxed);
  }
  return true;
}

static bool session_passes(const void *sample, void *arg) { return palp_dds_gate_passes(arg, *(const uint32_t *)sample); }

static bool finger_passes(const void *sample, void *arg) {
  return ((const uint8_t *)sample)[offsetof(palp_Contact, finger)] < FINGERS && session_passes(sample, arg);
}

static int finger_keyed(palp_dds_topic_kind kind) {
  return kind == PALP_TOPIC_CONTACT || kind == PALP_TOPIC_LOCAL_MODEL || kind == PALP_TOPIC_FINGER_SAMPLE;
}

static int set_filter(dds_entity_t topic, bool (*fn)(const void *, void *), palp_dds_gate *g) {
  if (topic <= 0) return 0;
  struct dds_topic_filter flt = {.mode = DDS_TOPIC_FILTER_SAMPLE_ARG, .f = {.sample_arg = fn}, .arg = g};
  const dds_return_t rc = dds_set_topic_filter_extended(topic, &flt);
  return rc < 0 ? (int)rc : 0;
}

static int filter_session_topic(palp_dds_gate *g, dds_entity_t topic, palp_dds_topic_kind kind) {
  if (finger_keyed(kind)) return set_filter(topic, finger_passes, g);
  if (kind == PALP_TOPIC_FEEDBACK || kind == PALP_TOPIC_DEFORMATION || kind == PALP_TOPIC_FINDING ||
      kind == PALP_TOPIC_FINDING_STATUS || kind == PALP_TOPIC_DEBRIEF || kind == PALP_TOPIC_DEBRIEF_SCORE ||
      kind == PALP_TOPIC_SESSION_LOG)
    return set_filter(topic, session_passes, g);
  return PALP_EINVAL;
}

int palp_dds_gate_filter_topics(palp_dds_gate *g, const dds_entity_t topic[PALP_TOPIC_COUNT],
                                const palp_dds_topic_kind *more, size_t n_more) {
  static const palp_dds_topic_kind streams[] = {PALP_TOPIC_CONTACT, PALP_TOPIC_FEEDBACK, PALP_TOPIC_DEFORMATION,
                                                PALP_TOPIC_LOCAL_MODEL, PALP_TOPIC_FINGER_SAMPLE};
  const size_t n_streams = sizeof streams / sizeof streams[0];
  int rc = set_filter(topic[PALP_TOPIC_SESSION_STATE], state_heard, g);
  for (size_t k = 0; k < n_streams + n_more && rc == 0; k++) {
    const palp_dds_topic_kind kind = k < n_streams ? streams[k] : more[k - n_streams];
    rc = filter_session_topic(g, topic[kind], kind);
  }
  return rc;
}

int32_t palp_dds_gate_instances(const palp_dds_gate *g, palp_dds_topic_kind kind) {
  return (finger_keyed(kind) ? FINGERS : 1) * (g->slots + PALP_DDS_GATE_HEARD);
}

void palp_dds_gate_limit(const palp_dds_gate *g, dds_qos_t *q, palp_dds_topic_kind kind) {
  dds_qset_resource_limits(q, DDS_LENGTH_UNLIMITED, palp_dds_gate_instances(g, kind), DDS_LENGTH_UNLIMITED);
}

int palp_dds_gate_key_passes(palp_dds_gate *g, palp_dds_topic_kind kind, const void *key) {
  return finger_keyed(kind) ? finger_passes(key, g) : session_passes(key, g);
}

uint32_t palp_dds_gate_refused_since(dds_entity_t rd, uint32_t *seen) {
  dds_sample_rejected_status_t st;
  if (rd <= 0 || dds_get_sample_rejected_status(rd, &st) != 0) return 0;
  const uint32_t d = st.total_count - *seen; /* unsigned: a wrapped total still gives the increment */
  *seen = st.total_count;
  return d;
}
