/* palp_dds.c - topic names, QoS and helpers shared by every palp DDS process. */
/* realpath() is XSI. */
#define _XOPEN_SOURCE 700
#include "palp_dds.h"

#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <string.h>

#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#include "palp.h" /* PALP_E* codes only; the model is not linked */
#include "palp_assess.h" /* palp_band, a plain struct */
#include "palp_finding_answers.h" /* palp_finding_sent, a plain struct */

static const char *const topic_names[PALP_TOPIC_COUNT] = {
    "palp_catalogue",     "palp_session_request", "palp_session_reply", "palp_session_state",
    "palp_contact",       "palp_feedback",        "palp_deformation",   "palp_server_status",
    "palp_local_model",   "palp_server_guard",
    "palp_server_identity", "palp_station_request",
    "palp_exercise",      "palp_finding",         "palp_finding_status",
    "palp_debrief",       "palp_session_exercise", "palp_session_score",
    "palp_debrief_score", "palp_session_log", "palp_session_closed", "palp_finger_sample"};

const char *palp_dds_topic_name(palp_dds_topic_kind kind) {
  return (unsigned)kind < PALP_TOPIC_COUNT ? topic_names[kind] : NULL;
}

int palp_dds_topic_in_session(palp_dds_topic_kind kind) {
  switch (kind) {
  case PALP_TOPIC_CONTACT:
  case PALP_TOPIC_FEEDBACK:
  case PALP_TOPIC_DEFORMATION:
  case PALP_TOPIC_LOCAL_MODEL:
  case PALP_TOPIC_FINDING:
  case PALP_TOPIC_FINDING_STATUS:
  case PALP_TOPIC_DEBRIEF:
  case PALP_TOPIC_DEBRIEF_SCORE:
  case PALP_TOPIC_SESSION_LOG:
  case PALP_TOPIC_FINGER_SAMPLE: return 1;
  default: return 0;
  }
}

const dds_topic_descriptor_t *palp_dds_topic_descriptor(palp_dds_topic_kind kind) {
  switch (kind) {
  case PALP_TOPIC_CATALOGUE: return &palp_Phantom_desc;
  case PALP_TOPIC_SESSION_REQUEST: return &palp_SessionRequest_desc;
  case PALP_TOPIC_SESSION_REPLY: return &palp_SessionReply_desc;
  case PALP_TOPIC_SESSION_STATE: return &palp_SessionState_desc;
  case PALP_TOPIC_CONTACT: return &palp_Contact_desc;
  case PALP_TOPIC_FEEDBACK: return &palp_Feedback_desc;
  case PALP_TOPIC_DEFORMATION: return &palp_Deformation_desc;
  case PALP_TOPIC_SERVER_STATUS: return &palp_ServerStatus_desc;
  case PALP_TOPIC_LOCAL_MODEL: return &palp_LocalModel_desc;
  case PALP_TOPIC_SERVER_GUARD: return &palp_ServerGuard_desc;
  case PALP_TOPIC_SERVER_IDENTITY: return &palp_ServerIdentity_desc;
  case PALP_TOPIC_STATION_REQUEST: return &palp_StationRequest_desc;
  case PALP_TOPIC_EXERCISE: return &palp_Exercise_desc;
  case PALP_TOPIC_FINDING: return &palp_Finding_desc;
  case PALP_TOPIC_FINDING_STATUS: return &palp_FindingStatus_desc;
  case PALP_TOPIC_DEBRIEF: return &palp_Debrief_desc;
  case PALP_TOPIC_SESSION_EXERCISE: return &palp_SessionExercise_desc;
  case PALP_TOPIC_SESSION_SCORE: return &palp_SessionScore_desc;
  case PALP_TOPIC_DEBRIEF_SCORE: return &palp_SessionScore_desc; /* the same score, in the session's partition */
  case PALP_TOPIC_SESSION_LOG: return &palp_SessionLog_desc;
  case PALP_TOPIC_SESSION_CLOSED: return &palp_SessionClosed_desc;
  case PALP_TOPIC_FINGER_SAMPLE: return &palp_FingerSample_desc;
  default: return NULL;
  }
}

dds_qos_t *palp_dds_qos(palp_dds_topic_kind kind) {
  dds_qos_t *q = dds_create_qos();
  const dds_duration_t lease = (dds_duration_t)(PALP_DDS_STATION_LEASE_S * 1e9);
  switch (kind) {
  case PALP_TOPIC_CATALOGUE:
  case PALP_TOPIC_SESSION_REPLY:
  case PALP_TOPIC_SESSION_STATE:
  case PALP_TOPIC_EXERCISE:
  case PALP_TOPIC_FINDING_STATUS:
  case PALP_TOPIC_DEBRIEF:
  case PALP_TOPIC_SESSION_EXERCISE:
  case PALP_TOPIC_SESSION_SCORE:
  case PALP_TOPIC_DEBRIEF_SCORE:
  case PALP_TOPIC_SESSION_LOG:
  case PALP_TOPIC_SESSION_CLOSED:
    /* State that a late joiner must see: the last value per key, kept by the writer. */
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
    break;
  case PALP_TOPIC_SERVER_IDENTITY:
    /* A late server or station sees every live server; a dead one's instance
     * turns not-alive when its participant's lease expires. */
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
    break;
  case PALP_TOPIC_SESSION_REQUEST:
  case PALP_TOPIC_STATION_REQUEST:
    /* Transient-local so a request written before the server's reader matched
     * is still delivered; automatic liveliness tells the server when the station
     * is gone. */
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
    dds_qset_liveliness(q, DDS_LIVELINESS_AUTOMATIC, lease);
    break;
  case PALP_TOPIC_FINDING:
    /* Every mark and withdrawal counts, in order: reliable keep-all on one instance
     * per session. The reader bounds what it holds (docs/assessment.md): a flood
     * blocks or drops at the writer, never grows the server. */
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
    dds_qset_resource_limits(q, 256, 64, 256);
    break;
  case PALP_TOPIC_CONTACT:
    /* Only the newest finger state matters; a lost sample is superseded within
     * a millisecond, a retransmitted old one would be harmful. */
    dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
    dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
    dds_qset_liveliness(q, DDS_LIVELINESS_AUTOMATIC, lease);
    break;
  case PALP_TOPIC_FEEDBACK:
  case PALP_TOPIC_SERVER_STATUS:
  case PALP_TOPIC_LOCAL_MODEL:
    /* Only the newest state matters: a lost local model is superseded by the next
     * physics step, and the station's renderer extrapolates across the gap. */
  case PALP_TOPIC_FINGER_SAMPLE:
    /* A lost finger sample leaves a place unmarked in a live coverage map, which the review
     * (from the log) still counts: never worth blocking the physics thread's writer for.
     * Readers that count them keep a deeper history (keep-last per finger). */
  case PALP_TOPIC_SERVER_GUARD:
    dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
    dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
    break;
  case PALP_TOPIC_DEFORMATION:
    /* Reliable keep-last 1: a display always ends on the newest frame (e.g. the
     * rest shape after release) without the writer ever blocking on it. */
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_MSECS(10));
    dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
    break;
  default: break;
  }
  return q;
}

dds_entity_t palp_dds_create_topic(dds_entity_t pp, palp_dds_topic_kind kind) {
  const dds_topic_descriptor_t *desc = palp_dds_topic_descriptor(kind);
  if (!desc) return DDS_RETCODE_BAD_PARAMETER;
  dds_qos_t *q = palp_dds_qos(kind);
  dds_entity_t t = dds_create_topic(pp, desc, palp_dds_topic_name(kind), q, NULL);
  dds_delete_qos(q);
  return t;
}

dds_qos_t *palp_dds_reader_qos(palp_dds_topic_kind kind) {
  dds_qos_t *q = palp_dds_qos(kind);
  /* Every mark counts, in order (keep-all), at most PALP_DDS_FINDING_READER_DEPTH unread per session;
   * no bound on the sessions: a 65th instance refused stalled delivery until its writer went, a
   * 257th unread sample of one only until the reader takes (the server: every pass of its loop). */
  if (q && kind == PALP_TOPIC_FINDING)
    dds_qset_resource_limits(q, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED, PALP_DDS_FINDING_READER_DEPTH);
  return q;
}

dds_entity_t palp_dds_create_reader(dds_entity_t parent, dds_entity_t topic, palp_dds_topic_kind kind) {
  dds_qos_t *q = palp_dds_reader_qos(kind);
  dds_entity_t r = dds_create_reader(parent, topic, q, NULL);
  dds_delete_qos(q);
  return r;
}

dds_entity_t palp_dds_create_display_reader(dds_entity_t parent, dds_entity_t topic) {
  dds_qos_t *q = palp_dds_qos(PALP_TOPIC_DEFORMATION);
  /* best-effort requested from a reliable writer: matched, and never waits for a retransmit */
  dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_entity_t r = dds_create_reader(parent, topic, q, NULL);
  dds_delete_qos(q);
  return r;
}

dds_entity_t palp_dds_create_writer(dds_entity_t parent, dds_entity_t topic, palp_dds_topic_kind kind) {
  dds_qos_t *q = palp_dds_qos(kind);
  dds_entity_t w = dds_create_writer(parent, topic, q, NULL);
  dds_delete_qos(q);
  return w;
}

static dds_qos_t *partition_qos(const char *partition) {
  dds_qos_t *q = dds_create_qos();
  dds_qset_partition1(q, partition);
  return q;
}

dds_entity_t palp_dds_session_publisher(dds_entity_t pp, const char *partition) {
  dds_qos_t *q = partition_qos(partition);
  dds_entity_t p = dds_create_publisher(pp, q, NULL);
  dds_delete_qos(q);
  return p;
}

dds_entity_t palp_dds_session_subscriber(dds_entity_t pp, const char *partition) {
  dds_qos_t *q = partition_qos(partition);
  dds_entity_t s = dds_create_subscriber(pp, q, NULL);
  dds_delete_qos(q);
  return s;
}

void palp_dds_session_partition(uint32_t session_id, char *buf, size_t len) {
  snprintf(buf, len, PALP_DDS_SESSION_PARTITION_FMT, session_id);
}

int palp_dds_use_config(const char *path) {
  const char *cur = getenv("CYCLONEDDS_URI");
  if (cur && *cur) return 0;
  /* No compiled-in default: an installed program must not name the source tree
   * (palp_app_use_dds_config finds the installed loopback config). */
  if (!path) return PALP_EINVAL;
  char abs[PATH_MAX];
  if (access(path, R_OK) != 0 || !realpath(path, abs)) return PALP_EIO;
  char uri[PATH_MAX + 16];
  int n = snprintf(uri, sizeof uri, "file://%s", abs);
  if (n < 0 || (size_t)n >= sizeof uri) return PALP_EINVAL;
  return setenv("CYCLONEDDS_URI", uri, 1) == 0 ? PALP_OK : PALP_EINVAL;
}

int64_t palp_dds_now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

/* ---- refusals by DDS Security, read off Cyclone's warnings ------------------- */

/* Copies src[0..n) into dst (size cap), each unprintable byte as '?': the text
 * came from a peer's certificate, and a log line must stay one line. */
void palp_dds_copy_printable(char *dst, size_t cap, const char *src, size_t n) {
  size_t j = 0;
  for (size_t i = 0; i < n && j + 1 < cap; i++) {
    const unsigned char c = (unsigned char)src[i];
    dst[j++] = (c >= 0x20 && c < 0x7f) ? (char)c : '?';
  }
  dst[j] = '\0';
}

static const char *find_n(const char *s, size_t n, const char *needle) {
  const size_t k = strlen(needle);
  for (size_t i = 0; i + k <= n; i++)
    if (!memcmp(s + i, needle, k)) return s + i;
  return NULL;
}

void palp_dds_subject_name(char *who, size_t cap, const char *s, size_t n) {
  const char *o = find_n(s, n, "/O=palp/OU="), *cn = find_n(s, n, "/CN=");
  if (o == s && cn && cn > o + 11) {
    const char *kind = o + 11, *name = cn + 4;
    const size_t kn = (size_t)(cn - kind), nn = (size_t)(s + n - name);
    const int ours = (kn == 7 && !memcmp(kind, "trainee", 7)) || (kn == 10 && !memcmp(kind, "instructor", 10)) ||
                     (kn == 6 && !memcmp(kind, "server", 6));
    if (ours && nn > 0 && !memchr(name, '/', nn) && kn + nn + 2 <= cap) {
      char tmp[PALP_DDS_REFUSAL_WHO * 2];
      snprintf(tmp, sizeof tmp, "%.*s/%.*s", (int)kn, kind, (int)nn, name);
      palp_dds_copy_printable(who, cap, tmp, strlen(tmp));
      return;
    }
  }
  palp_dds_copy_printable(who, cap, s, n);
}

int palp_dds_refusal_parse(const char *msg, size_t len, palp_dds_refusal *out) {
  static const char *const handshake[] = {"Validate remote identity failed: ", "Begin handshake request failed: ",
                                          "Begin handshake reply failed: ", "Process handshake failed: "};
  static const char perm_head[] = "Could not get remote participant ", perm_tail[] = " permissions from plugin: ";
  static const char digest[] = "Failed to finalize digest context";
  if (!msg || !out) return 0;
  while (len && (*msg == ' ' || *msg == '\t')) msg++, len--;
  const char *body = NULL, *guid = NULL;
  size_t guid_n = 0;
  palp_dds_refusal_kind kind = PALP_DDS_REFUSED_HANDSHAKE;
  /* Anywhere in the line, not only at its start: Cyclone ends some of its lines without a newline
   * ("fsm: Send handshake: failed to send message (lguid=...)", a handshake message it could not
   * send), and the next message, the refusal, reaches the sink on the same line (session 72: such a
   * line went raw into palp-recorder's log in install_demo). */
  /* The earliest of the four phrases in the line: what follows one is the exception's text, whose
   * subject is the peer's certificate's, printed as written. Until session 90 the first phrase of the
   * list found anywhere won: a rogue CA's certificate whose subject held "Validate remote identity
   * failed: Certificate not valid: error: certificate revoked; subject: /O=palp/OU=trainee/CN=alice"
   * was read as trainee/alice refused, revoked and verified (found by review). */
  const char *first = NULL;
  size_t first_n = 0;
  for (size_t i = 0; i < sizeof handshake / sizeof handshake[0]; i++) {
    const char *at = find_n(msg, len, handshake[i]);
    if (at && (!first || at < first)) first = at, first_n = strlen(handshake[i]);
  }
  if (first) {
    body = first + first_n;
    len -= (size_t)(first - msg);
    msg = first;
  }
  if (!body && len > sizeof perm_head && !memcmp(msg, perm_head, sizeof perm_head - 1)) {
    const char *t = find_n(msg, len, perm_tail);
    if (!t) return 0;
    guid = msg + sizeof perm_head - 1;
    guid_n = (size_t)(t - guid);
    body = t + sizeof perm_tail - 1;
    kind = PALP_DDS_REFUSED_PERMISSIONS;
  }
  if (!body) return 0;
  /* A stale handshake message: the challenges of an attempt that was since restarted (a peer slow to
   * answer, or a handshake failed for another reason and begun again). It is no verdict on the peer,
   * which may authenticate at the next attempt, so it is left to the rate-limited log, not counted as a
   * refusal (seen for security_classroom's thief under ThreadSanitizer, 2026-12-04). */
  if (find_n(body, (size_t)(msg + len - body), "does not match future_challenge") ||
      find_n(body, (size_t)(msg + len - body), "No future challenge exists"))
    return 0;
  /* The exception's own text, without Cyclone's "(code: N)" and the trailing
   * newline OpenSSL's error string may carry. */
  size_t bn = (size_t)(msg + len - body);
  const char *code = NULL;
  for (const char *c = body; (c = find_n(c, (size_t)(msg + len - c), "(code: ")); c++) code = c;
  if (code) bn = (size_t)(code - body);
  while (bn && (body[bn - 1] == '\n' || body[bn - 1] == ' ')) bn--;

  memset(out, 0, sizeof *out);
  out->kind = kind;
  /* the first error and the first subject after it: a subject's own text comes after both */
  const char *err = find_n(body, bn, "Certificate not valid: error: ");
  const char *subj = err ? find_n(err, (size_t)(body + bn - err), "; subject: ") : NULL;
  const char *verify = find_n(body, bn, "Verify error: ");
  if (err && subj && subj > err) {
    const char *why = err + 30, *who = subj + 11;
    palp_dds_copy_printable(out->why, sizeof out->why, why, (size_t)(subj - why));
    palp_dds_subject_name(out->who, sizeof out->who, who, (size_t)(body + bn - who));
    /* The subject is the peer's word until its certificate's chain to the classroom CA verified.
     * OpenSSL (x509_vfy.c, verify_chain) builds the chain, checks revocation, then each signature and
     * after it each certificate's dates: "certificate has expired" and "is not yet valid" come after
     * the signature passed; "certificate revoked" means the classroom's CRL (its signature checked)
     * lists the serial under the CA's name. Any other error ("unable to get local issuer certificate":
     * another CA; "certificate signature failure") vouches for nothing: a rogue CA's certificate
     * claiming /O=palp/OU=trainee/CN=alice was named trainee/alice, and alice's own station said it
     * was refused (until session 81). */
    static const char *const verified[] = {"certificate revoked", "certificate has expired",
                                           "certificate is not yet valid"};
    int chain_ok = 0;
    for (size_t i = 0; i < sizeof verified / sizeof verified[0]; i++)
      chain_ok |= !strcmp(out->why, verified[i]);
    const int ours = !strncmp(out->who, "trainee/", 8) || !strncmp(out->who, "instructor/", 11) ||
                     !strncmp(out->who, "server/", 7); /* palp_dds_subject_name read a classroom identity */
    if (!chain_ok && ours) {
      char tmp[PALP_DDS_REFUSAL_WHO];
      snprintf(tmp, sizeof tmp, "%s", out->who);
      if (snprintf(out->who, sizeof out->who, "%s%s", PALP_DDS_UNVERIFIED_CLAIM, tmp) < 0) out->who[0] = '\0';
    }
  } else if (kind == PALP_DDS_REFUSED_PERMISSIONS && verify) {
    char tmp[PALP_DDS_REFUSAL_WHY];
    const char *v = verify + 14;
    snprintf(tmp, sizeof tmp, "permissions not signed by the classroom (%.*s)", (int)(body + bn - v), v);
    palp_dds_copy_printable(out->why, sizeof out->why, tmp, strlen(tmp));
  } else if (kind == PALP_DDS_REFUSED_HANDSHAKE && bn >= sizeof digest - 1 && !memcmp(body, digest, sizeof digest - 1)) {
    /* The plugin's signature check of the peer's handshake (EVP_DigestVerifyFinal) failed: the
     * certificate has passed the CA and the CRL, but the peer cannot sign with its key. palp's own
     * programs check their key against their certificate before they start, so what is left is
     * someone else's certificate (certificates are public) or a foreign program's wrong key. */
    snprintf(out->why, sizeof out->why, "its handshake is not signed by its certificate's key (someone else's "
                                        "certificate, or a private key that is not its own)");
  } else {
    palp_dds_copy_printable(out->why, sizeof out->why, body, bn);
  }
  if (kind == PALP_DDS_REFUSED_PERMISSIONS) {
    char tmp[PALP_DDS_REFUSAL_WHO];
    snprintf(tmp, sizeof tmp, "participant %.*s", (int)guid_n, guid);
    palp_dds_copy_printable(out->who, sizeof out->who, tmp, strlen(tmp));
  } else if (!out->who[0]) {
    snprintf(out->who, sizeof out->who, "a participant");
  }
  return 1;
}

int palp_dds_startup_race(const char *msg, size_t len) {
  static const char head[] = "Remote secure participant ", tail[] = " not allowed";
  if (!msg) return 0;
  while (len && (msg[len - 1] == '\n' || msg[len - 1] == ' ')) len--;
  const size_t h = sizeof head - 1, t = sizeof tail - 1;
  if (len <= h + t || memcmp(msg, head, h) || memcmp(msg + len - t, tail, t)) return 0;
  /* a GUID between them: hex digits and ':' only */
  for (size_t i = h; i < len - t; i++)
    if (!(msg[i] == ':' || (msg[i] >= '0' && msg[i] <= '9') || (msg[i] >= 'a' && msg[i] <= 'f'))) return 0;
  return 1;
}

/* ---- rate-limited Cyclone log sink ------------------------------------------ */

static void limited_sink(void *arg, const dds_log_data_t *d) {
  palp_dds_log_limit *l = arg;
  palp_dds_refusal r;
  const int refused = palp_dds_refusal_parse(d->message, d->size, &r); /* pure: outside the lock */
  pthread_mutex_lock(l->lock);
  void (*fn)(void *, const palp_dds_refusal *) = l->on_refusal;
  void *fn_arg = l->refusal_arg;
  if (refused && fn) { /* called outside our lock, so its own lock never nests in ours */
    pthread_mutex_unlock(l->lock);
    fn(fn_arg, &r);
    return;
  }
  /* Seen in every station of the secured demo, 1-7 lines at its start: noise that reads like an alarm. */
  if (palp_dds_startup_race(d->message, d->size)) {
    l->races++;
    pthread_mutex_unlock(l->lock);
    return;
  }
  int64_t now = palp_dds_now_ns();
  if (now - l->window_start_ns >= l->window_ns) {
    if (l->suppressed_in_window)
      fprintf(l->out, "palp: %llu more DDS warning line(s) suppressed in the last %.0f s\n",
              (unsigned long long)l->suppressed_in_window, (double)l->window_ns * 1e-9);
    l->window_start_ns = now;
    l->printed_in_window = 0;
    l->suppressed_in_window = 0;
  }
  if (l->printed_in_window < l->lines) {
    /* As Cyclone's default sink: its header in front, the newline at message[size]. */
    fwrite(d->message - d->hdrsize, 1, d->hdrsize + d->size + 1, l->out);
    fflush(l->out);
    l->printed_in_window++;
    l->printed++;
  } else {
    l->suppressed_in_window++;
    l->suppressed++;
  }
  pthread_mutex_unlock(l->lock);
}

int palp_dds_log_limit_install(palp_dds_log_limit *l, FILE *out, int lines, double window_s) {
  memset(l, 0, sizeof *l);
  pthread_mutex_t *m = malloc(sizeof *m);
  if (!m) return PALP_ENOMEM;
  pthread_mutex_init(m, NULL);
  l->lock = m;
  l->out = out ? out : stderr;
  l->lines = lines < 0 ? 0 : lines;
  l->window_ns = (int64_t)(window_s * 1e9);
  l->window_start_ns = palp_dds_now_ns();
  dds_set_log_sink(limited_sink, l);
  return 0;
}

void palp_dds_log_limit_on_refusal(palp_dds_log_limit *l,
                                   void (*fn)(void *arg, const palp_dds_refusal *r), void *arg) {
  if (!l->lock) return;
  pthread_mutex_lock(l->lock);
  l->on_refusal = fn;
  l->refusal_arg = arg;
  pthread_mutex_unlock(l->lock);
}

void palp_dds_log_limit_remove(palp_dds_log_limit *l) {
  if (!l->lock) return;
  /* Cyclone swaps the sink under its write lock: no thread uses ours after this. */
  dds_set_log_sink(NULL, NULL);
  pthread_mutex_destroy(l->lock);
  free(l->lock);
  l->lock = NULL;
}

void palp_dds_log_limit_counts(palp_dds_log_limit *l, uint64_t *printed, uint64_t *suppressed) {
  if (!l->lock) {
    *printed = *suppressed = 0;
    return;
  }
  pthread_mutex_lock(l->lock);
  *printed = l->printed;
  *suppressed = l->suppressed;
  pthread_mutex_unlock(l->lock);
}

int palp_dds_debrief_ok(const palp_Debrief *d) {
  const uint32_t n = d->lesion._length;
  const int listed = d->level == palp_DEBRIEF_LESIONS;
  if (d->level > palp_DEBRIEF_LESIONS || d->lesions > PALP_MAX_LESIONS || d->found > d->lesions ||
      n > PALP_MAX_LESIONS || (n && !d->lesion._buffer) || (listed ? n != d->lesions : n != 0))
    return 0;
  uint32_t found_by = 0;
  for (uint32_t i = 0; i < n; i++) {
    const palp_DebriefLesion *l = &d->lesion._buffer[i];
    if (!isfinite(l->point.x) || !isfinite(l->point.y) || !isfinite(l->point.z) || !(l->depth >= 0) ||
        !(l->diameter >= 0) || !isfinite(l->depth) || !isfinite(l->diameter))
      return 0;
    found_by += l->found_by != 0;
  }
  return !listed || found_by == d->found;
}

static int vec_ok(palp_Vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

int palp_dds_finger_sample_ok(const palp_FingerSample *m, int mesh_triangles) {
  if (m->finger >= 4 || !isfinite(m->time) || !(m->radius > 0) || !isfinite(m->radius) || !(m->area >= 0) ||
      !isfinite(m->area) || !vec_ok(m->device) || !vec_ok(m->proxy) || !vec_ok(m->force) || !vec_ok(m->point) ||
      m->triangles._length > PALP_FINGER_SAMPLE_TRIANGLES_MAX || (m->triangles._length && !m->triangles._buffer))
    return 0;
  for (uint32_t k = 0; mesh_triangles >= 0 && k < m->triangles._length; k++)
    if (m->triangles._buffer[k] < 0 || m->triangles._buffer[k] >= mesh_triangles) return 0;
  return 1;
}

static int unit(double x) { return x >= 0 && x <= 1; } /* NaN fails */

int palp_dds_session_score_ok(const palp_SessionScore *m) {
  if (m->status == palp_SCORE_NOT_GRADED) return 1;
  if (m->status != palp_SCORE_GRADED || !(m->score >= 0 && m->score <= 100) || m->found > m->lesions ||
      m->lesions > PALP_MAX_LESIONS || !(m->duration >= 0) || !isfinite(m->duration) || !(m->peak_force >= 0) ||
      !isfinite(m->peak_force))
    return 0;
  for (int i = 0; i < 6; i++)
    if (!unit(m->credit[i])) return 0;
  for (int b = 0; b < 3; b++)
    if (!unit(m->coverage[b])) return 0;
  static const char *const patterns[] = {"unsystematic", "vertical_strip", "circles", "radial"};
  for (size_t i = 0; i < sizeof patterns / sizeof *patterns; i++)
    if (!strcmp(m->pattern, patterns[i])) return 1;
  return 0;
}

void palp_dds_finding_sent(const palp_Finding *m, struct palp_finding_sent *out) {
  *out = (palp_finding_sent){.mark_id = m->mark_id,
                             .withdraw = m->op == palp_FINDING_WITHDRAW,
                             .point = {m->point.x, m->point.y, m->point.z},
                             .t = m->time};
}

int palp_dds_exercise_bands(const palp_Exercise *ex, struct palp_band *out) {
  int ok = 1;
  for (int b = 0; b < PALP_BAND_COUNT; b++) {
    const palp_PressureBand *in = &ex->bands[b];
    palp_band *B = &out[b];
    *B = (palp_band){.has_depth = in->has_depth != 0, .has_force = in->has_force != 0, .depth_min = in->depth_min,
                     .depth_max = in->depth_max, .force_min = in->force_min, .force_max = in->force_max};
    const int depth_ok = !B->has_depth || (isfinite(B->depth_min) && isfinite(B->depth_max) && B->depth_min >= 0 &&
                                           B->depth_min < B->depth_max);
    const int force_ok = !B->has_force || (isfinite(B->force_min) && isfinite(B->force_max) && B->force_min >= 0 &&
                                           B->force_min < B->force_max);
    if (!(B->has_depth || B->has_force) || !depth_ok || !force_ok) ok = 0;
  }
  return ok;
}

/* The largest mesh a palp-server publishes (palp.h, a scene's mesh.vertex_count; the shipped
 * phantoms have 338 and 1300 vertices), and the triangles of a closed surface of that many (2V - 4).
 * Until 2026-12-06 this bound was 1,000,000 vertices of its own: five times any server's, a mesh a
 * station or palp-recorder kept (~100 MB with its triangles) from any peer on an unsecured domain. */
#define PHANTOM_MAX_VERTICES PALP_MESH_MAX_VERTICES

int palp_dds_writer_participant(dds_entity_t reader, dds_instance_handle_t pub, dds_guid_t *out) {
  dds_builtintopic_endpoint_t *ep = pub ? dds_get_matched_publication_data(reader, pub) : NULL;
  if (!ep) return PALP_EINVAL;
  *out = ep->participant_key;
  dds_builtintopic_free_endpoint(ep);
  return 0;
}

char *palp_dds_participant_text(const dds_guid_t *guid, char *out, size_t len) {
  const unsigned char *g = guid->v;
  snprintf(out, len, "participant %02x%02x%02x%02x:%02x%02x%02x%02x:%02x%02x%02x%02x", g[0], g[1], g[2], g[3], g[4],
           g[5], g[6], g[7], g[8], g[9], g[10], g[11]);
  return out;
}

char *palp_dds_writer_participant_text(dds_entity_t reader, dds_instance_handle_t pub, char *out, size_t len) {
  dds_guid_t g;
  if (palp_dds_writer_participant(reader, pub, &g) < 0) {
    snprintf(out, len, "a writer already gone");
    return out;
  }
  return palp_dds_participant_text(&g, out, len);
}

int palp_dds_phantom_check(const palp_Phantom *ph, int triangles_optional, char *err, size_t errlen) {
  const uint32_t nv = ph->rest._length, ni = ph->triangles._length;
  if (nv < 4 || nv > PHANTOM_MAX_VERTICES || !ph->rest._buffer) {
    snprintf(err, errlen, "phantom %u: %u rest vertices (want 4..%d, the largest mesh a palp-server publishes)",
             ph->phantom_id, nv, PHANTOM_MAX_VERTICES);
    return PALP_EINVAL;
  }
  if ((ni == 0 && !triangles_optional) || ni % 3 != 0) {
    snprintf(err, errlen, "phantom %u: %u triangle indices (want a positive multiple of 3)", ph->phantom_id, ni);
    return PALP_EINVAL;
  }
  /* (its own reason: 1,200,003 indices are a positive multiple of 3, and were refused as not one) */
  if (ni / 3 > 2u * PHANTOM_MAX_VERTICES) {
    snprintf(err, errlen, "phantom %u: %u triangles (at most %u, twice the largest mesh a palp-server publishes)",
             ph->phantom_id, ni / 3, 2u * PHANTOM_MAX_VERTICES);
    return PALP_EINVAL;
  }
  if (ni && !ph->triangles._buffer) {
    snprintf(err, errlen, "phantom %u: %u triangle indices and no buffer", ph->phantom_id, ni);
    return PALP_EINVAL;
  }
  for (uint32_t i = 0; i < ni; i++)
    if (ph->triangles._buffer[i] < 0 || (uint32_t)ph->triangles._buffer[i] >= nv) {
      snprintf(err, errlen, "phantom %u: triangle %u has vertex index %d (want 0..%u)", ph->phantom_id, i / 3,
               (int)ph->triangles._buffer[i], nv - 1);
      return PALP_EINVAL;
    }
  /* (without triangles, their dome count names none: it is not used) */
  if (ni && (ph->dome_triangle_count < 0 || (uint32_t)ph->dome_triangle_count > ni / 3)) {
    snprintf(err, errlen, "phantom %u: dome_triangle_count %d of %u triangles", ph->phantom_id,
             (int)ph->dome_triangle_count, ni / 3);
    return PALP_EINVAL;
  }
  if (ph->top_vertex < 0 || (uint32_t)ph->top_vertex >= nv) {
    snprintf(err, errlen, "phantom %u: top_vertex %d of %u", ph->phantom_id, (int)ph->top_vertex, nv);
    return PALP_EINVAL;
  }
  if (!(ph->radius > 0 && ph->radius < 10)) {
    snprintf(err, errlen, "phantom %u: radius %g m (want 0 < R < 10 m)", ph->phantom_id, ph->radius);
    return PALP_EINVAL;
  }
  for (uint32_t i = 0; i < nv; i++) {
    palp_Vec3 p = ph->rest._buffer[i];
    if (!isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z)) {
      snprintf(err, errlen, "phantom %u: rest vertex %u is not finite", ph->phantom_id, i);
      return PALP_EINVAL;
    }
  }
  return 0;
}
