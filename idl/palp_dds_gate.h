/*
 * palp_dds_gate.h - which sessions a classroom-wide reader lets into its stream readers.
 *
 * palp-web and palp-recorder read every session's partition ("palp/session/" "*", "palp/s/" "*").
 * In an unsecured classroom anyone may write there, and every new key (session, finger) a reader
 * sees becomes an instance it keeps until the key's writer goes: a flood of made-up keys grows the
 * reader without bound. The gate is a set of session ids consulted by topic filters on the
 * streams' topics (contacts, feedback, deformations, local models, finger samples), on the DDS
 * receive thread, before an instance exists (Cyclone evaluates a filter before it stores a new
 * instance): a sample passes when its session is one the owner keeps open (palp_dds_gate_set, the
 * owner's thread, slot by slot) or one whose OPEN state arrived lately (a ring the state topic's
 * filter fills as the state arrives, so that a session's first samples are not lost to the owner
 * reading its state a little later), and its finger, where it has one, is 0-3.
 *
 * A dispose carries no sample for a filter (Cyclone 0.10 makes its instance unfiltered): a
 * best-effort stream reader also takes palp_dds_gate_limit's instance bound, as many keys as the
 * gate can pass. A reliable one cannot (Cyclone retries a reliable sample a reader refuses for
 * resource limits on the delivery path, docs/robustness.md). The bound alone let a flood of disposes
 * fill the reader for as long as the disposing writer lived, every later session's keys refused:
 * the owner also counts the strays it takes (palp_dds_gate_key_passes) and the samples refused
 * (palp_dds_gate_refused_since) and makes the reader anew when idl/palp_dds_strays.h says so.
 *
 * Lock-free: the owner writes its slots, the state filter the ring, the stream filters only read.
 */
#ifndef PALP_DDS_GATE_H
#define PALP_DDS_GATE_H

#include <stdatomic.h>
#include <stdint.h>

#include "dds/dds.h"
#include "palp_dds.h"

#define PALP_DDS_GATE_SLOTS_MAX 1024 /* palp-recorder's sessions; palp-web keeps 64 */
#define PALP_DDS_GATE_HEARD 128      /* sessions heard open, not yet (or no longer) in a slot */

typedef struct palp_dds_gate {
  int slots; /* the owner's session slots in use, <= PALP_DDS_GATE_SLOTS_MAX */
  _Atomic uint32_t slot_sid[PALP_DDS_GATE_SLOTS_MAX]; /* 0: free */
  _Atomic uint32_t heard[PALP_DDS_GATE_HEARD];
  atomic_uint heard_next;
} palp_dds_gate;

/* An empty gate for an owner with `slots` session slots (1..PALP_DDS_GATE_SLOTS_MAX). */
void palp_dds_gate_init(palp_dds_gate *g, int slots);
/* The gate's topic filters on a participant's topics (indexed by palp_dds_topic_kind): the
 * session-state topic's (every state passes; an open one is noted) and the streams' (PALP_TOPIC_CONTACT,
 * _FEEDBACK, _DEFORMATION, _LOCAL_MODEL, _FINGER_SAMPLE), and the owner's `more` of the session's
 * reliable topics it reads only while a session is open or just closed (_FINDING, _FINDING_STATUS,
 * _DEBRIEF, _DEBRIEF_SCORE, _SESSION_LOG; not one the owner writes on: a filter applies to its
 * topic's writers too). Set before the topics' readers exist; a filter applies to every reader of
 * its topic entity; a topic <= 0 (not allowed by older permissions) is left alone. 0, or a negative
 * DDS return code (PALP_EINVAL: a topic the gate cannot filter). */
int palp_dds_gate_filter_topics(palp_dds_gate *g, const dds_entity_t topic[PALP_TOPIC_COUNT],
                                const palp_dds_topic_kind *more, size_t n_more);
/* The owner's slot `slot` now holds session `sid` (0: none). */
void palp_dds_gate_set(palp_dds_gate *g, int slot, uint32_t sid);
/* Whether a sample of session `sid` passes (sid 0 never does). */
int palp_dds_gate_passes(palp_dds_gate *g, uint32_t sid);
/* The instance bound for a best-effort reader of a stream: as many keys as the gate passes (4
 * fingers each for the finger-keyed topics). Sets it on q (max_samples and per instance left to
 * the history). */
void palp_dds_gate_limit(const palp_dds_gate *g, dds_qos_t *q, palp_dds_topic_kind kind);
int32_t palp_dds_gate_instances(const palp_dds_gate *g, palp_dds_topic_kind kind);
/* Whether the filter of stream `kind` would pass a sample with key fields `key` (a taken sample's,
 * an invalid one's too: Cyclone fills its key): its session passes and, on a finger-keyed topic,
 * its finger is 0-3. A taken dispose of a key it would not pass is a stray: an instance a flood made
 * that the bound holds until the reader is made anew (idl/palp_dds_strays.h). */
int palp_dds_gate_key_passes(palp_dds_gate *g, palp_dds_topic_kind kind, const void *key);
/* The samples stream reader `rd` refused since *seen (its sample-rejected total when last asked;
 * 0 for a new reader), *seen updated: past the instance bound a dispose of a made-up key is refused
 * like any sample of a new key, and a full reader is what the renewal is there to empty. 0 when
 * the status cannot be read. */
uint32_t palp_dds_gate_refused_since(dds_entity_t rd, uint32_t *seen);

#endif
