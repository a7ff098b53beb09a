/*
 * palp_dds_refusals.h - the peers DDS Security refused, counted and said once.
 *
 * A station refused at the handshake (revoked, expired, signed by another CA) or
 * for its permissions gets no answer, and nobody gets an event for it: the only
 * trace is a Cyclone warning, repeated about once a second by every participant
 * it tries, for as long as it runs (palp_dds_refusal_parse). Raw, a revoked laptop
 * left on filled every station's terminal and palp-web's log at ~2 lines a second.
 * Here each refusal is counted per peer and reason; the first is said at once,
 * naming the peer as palp names it (trainee/dave), and the repeats are summed into
 * one line per peer and reason per `window` (one a minute by default). The table
 * is bounded: its PALP_DDS_REFUSAL_SLOTS named peers keep their slots while they are
 * refused (a slot idle for PALP_DDS_REFUSAL_IDLE_WINDOWS windows is given to a new
 * peer, its unsaid repeats said first); when all are busy, a new peer's first refusal
 * is said once and it and every later such peer are counted together in one overflow
 * entry ("N other peer(s) refused M more time(s)"), said at most once per window.
 * Until session 81 the peer seen longest ago gave up its slot: with 17 peers retrying,
 * each retry evicted one and was "new", so every refusal became a line and a record
 * (1700 lines in 100 s, against 34 now). Lines go to the owner's `emit`
 * (the program's log, as a warning). Thread-safe: Cyclone's threads call in. Lines
 * and records are said after the table's lock is released, so `emit` and `record` may
 * take locks of their own that a caller of the table holds (palp-server prints its
 * summary, counts included, holding its log's lock).
 *
 * Every palp DDS program installs it (palp_dds_refusals_install): the server, the
 * stations, the recorder and palp-web.
 */
#ifndef PALP_DDS_REFUSALS_H
#define PALP_DDS_REFUSALS_H

#include <pthread.h>
#include <stdint.h>
#include <stdio.h>

#include "palp_dds.h"

#define PALP_DDS_REFUSAL_SLOTS 16
#define PALP_DDS_REFUSAL_WINDOW_S 60.0 /* [s] between two lines about one peer and reason */
/* A named peer not refused for this many windows gives its slot to a new one (a station turned
 * off is not retrying; one retrying once a second never idles that long). */
#define PALP_DDS_REFUSAL_IDLE_WINDOWS 2
/* The overflow entry tells apart this many peers (hashes; past it: "at least"). */
#define PALP_DDS_REFUSAL_OTHERS_SEEN 256

typedef struct palp_dds_refusal_slot {
  palp_dds_refusal r;
  uint64_t count;      /* since first seen */
  uint64_t unreported; /* since the last line about it */
  int64_t reported_ns, seen_ns;
  int used;
} palp_dds_refusal_slot;

/* One line, without a newline, for the owner's log (a warning). */
typedef void (*palp_dds_refusals_emit)(void *ctx, const char *line);

/* With each line: the peer and how many refusals the line stands for (the first: 1; a
 * repeats line: its repeats), e.g. to keep them in the session log. */
typedef void (*palp_dds_refusals_record)(void *ctx, const palp_dds_refusal *r, uint64_t count);

/* A classroom identity and the first 6 bytes of the GUID prefix DDS Security gives it
 * (palp_pem_guid_prefix): how a peer refused for its permissions, which Cyclone names only by
 * its GUID, is named as palp names it. */
#define PALP_DDS_PEER_NAMES_MAX 1024
typedef struct palp_dds_peer_name {
  unsigned char prefix[6];
  char who[PALP_DDS_REFUSAL_WHO];
} palp_dds_peer_name;
typedef struct palp_dds_refusals {
  pthread_mutex_t mu;
  palp_dds_peer_name *names; /* owned; NULL: GUIDs stay GUIDs */
  int n_names;
  palp_dds_refusals_emit emit; /* NULL: stderr */
  void *emit_ctx;
  palp_dds_refusals_record record; /* NULL: none */
  void *record_ctx;
  /* A trainee's focus (palp_dds_refusals_focus): "" none, else its identity; the lines about
   * the classmates and instructors refused go to `aside` */
  char me[PALP_DDS_REFUSAL_WHO];
  palp_dds_refusals_emit aside;
  void *aside_ctx;
  int64_t window_ns;
  uint64_t total, lines;
  palp_dds_refusal_slot slot[PALP_DDS_REFUSAL_SLOTS];
  /* The peers refused while every slot was busy, counted together: `others.r` the last of them,
   * others.count every refusal of theirs. o_peers: the distinct peers among them (o_all_hash tells
   * them apart); o_since: those since the last line (o_hash). Both at most OTHERS_SEEN. */
  palp_dds_refusal_slot others;
  uint64_t o_peers, o_since;
  uint64_t o_hash[PALP_DDS_REFUSAL_OTHERS_SEEN];
  uint64_t o_all_hash[PALP_DDS_REFUSAL_OTHERS_SEEN];
} palp_dds_refusals;

void palp_dds_refusals_init(palp_dds_refusals *t, palp_dds_refusals_emit emit, void *ctx, double window_s);
void palp_dds_refusals_destroy(palp_dds_refusals *t);
/* Before the sink is installed (not thread-safe against it). */
void palp_dds_refusals_on_record(palp_dds_refusals *t, palp_dds_refusals_record fn, void *ctx);
/* Whether refusal r is a trainee station's concern (1), `me` its identity ("trainee/alice"): its
 * own identity refused (the server's answer to it), or a peer that is neither a trainee nor an
 * instructor (the server, another CA's subject, a GUID): what may stand between it and the server.
 * A classmate or an instructor refused (a revoked laptop: the server refuses it too, and its log,
 * palp-web and the review name it to the instructor) is not (0), nor a certificate that did not
 * verify claiming a trainee or an instructor (PALP_DDS_UNVERIFIED_CLAIM: never `me`). */
int palp_dds_refusal_concerns_trainee(const palp_dds_refusal *r, const char *me);
/* Before the sink is installed: the table of trainee station `me` says the lines about refusals
 * that are not its concern (palp_dds_refusal_concerns_trainee) to `aside` (its debug log) instead
 * of `emit`. Counts, lists and records are unchanged. */
void palp_dds_refusals_focus(palp_dds_refusals *t, const char *me, palp_dds_refusals_emit aside, void *ctx);
/* The identities whose GUIDs name a peer refused for its permissions
 * ("participant f49f7aa2:789ee759:...": the first 6 bytes of its prefix) by palp's name for them
 * (trainee/bob); copied (replacing any before), at most PALP_DDS_PEER_NAMES_MAX; thread-safe. A prefix
 * two of them share names nobody.
 * 0 or PALP_ENOMEM. */
int palp_dds_refusals_set_names(palp_dds_refusals *t, const palp_dds_peer_name *names, int n);
/* "participant GUID" (palp_dds_refusal_parse) to the first 6 bytes of its prefix: 1, or 0 when who
 * is not that. */
int palp_dds_refusal_guid_prefix(const char *who, unsigned char prefix[6]);
/* One refusal seen at now_ns (monotonic): logs the first of its peer and reason,
 * or the repeats once `window` has passed since the last line about them. */
void palp_dds_refusals_note(palp_dds_refusals *t, const palp_dds_refusal *r, int64_t now_ns);
/* Logs the repeats of each peer and reason whose last line is a `window` old, though no
 * refusal came since to do it (a station that stopped retrying): call it now and then
 * from the owner's loop (the server at each status, palp-web each second). */
void palp_dds_refusals_tick(palp_dds_refusals *t, int64_t now_ns);
/* Logs every repeat not yet reported (at shutdown). */
void palp_dds_refusals_flush(palp_dds_refusals *t);
/* Totals: refusals seen, log lines written. */
void palp_dds_refusals_counts(palp_dds_refusals *t, uint64_t *total, uint64_t *lines);
/* The overflow entry: how many distinct peers were refused while the table was full (at most
 * PALP_DDS_REFUSAL_OTHERS_SEEN told apart) and how many times; the named peers' counts plus
 * `refusals` make the total (palp_dds_refusals_counts) as long as no slot was given up. */
void palp_dds_refusals_others(palp_dds_refusals *t, uint64_t *peers, uint64_t *refusals);
/* A peer in the table and how often it was refused. */
typedef struct palp_dds_refusal_entry {
  palp_dds_refusal r;
  uint64_t count;
} palp_dds_refusal_entry;
/* The peers still in the table, most refused first (at most max); returns how many. */
int palp_dds_refusals_list(palp_dds_refusals *t, palp_dds_refusal_entry *out, int max);
/* "trainee/dave: certificate revoked (31x); ..." for the peers still in the table,
 * most refused first, then "N other peer(s): Mx" for the overflow entry when it fits; returns the
 * number of named peers listed. */
int palp_dds_refusals_describe(palp_dds_refusals *t, char *buf, size_t len);

/* The process's DDS log sink (palp_dds_log_limit_install: other Cyclone warnings,
 * `lines` per `window_s` to stderr) with t noting its refusals; t must be
 * initialised and outlive the sink (palp_dds_log_limit_remove first). 0 or PALP_E*. */
int palp_dds_refusals_install(palp_dds_log_limit *sink, palp_dds_refusals *t, int lines, double window_s);

#endif
