/*
 * palp_dds_log_view.h - the server's session log as one session sees it, from palp_server_status.
 *
 * The server's status counts its log's records since it began (log_written, log_shed, log_failed):
 * the whole server's, not a session's. A station, or palp-web for a trainee's page, that reads the
 * status of the server listing its session counts from the first one it sees the records the log
 * lost while that session ran, and whether it is losing them now, so that a trainee whose practice
 * is not being recorded is told so where she palpates, as the instructor is on the dashboard
 * (session 68; docs/station.md, "The session log"). Pure: counts in, words out.
 *
 * A server that says each session's own losses (palp_session_log, session 69) is heard instead:
 * from its first such sample the view counts the records of this session the log lost, and the
 * server's counts only tell it whether the log writes again; the words then say "this session's
 * records", and a session that lost none is told nothing while others lose theirs.
 */
#ifndef PALP_DDS_LOG_VIEW_H
#define PALP_DDS_LOG_VIEW_H

#include <stddef.h>
#include <stdint.h>

/* Writing again once no record was lost for this long [s] and records were written since the last
 * loss: the status comes every second, and a full file that takes a small batch now and then must
 * not flip the words each second. */
#define PALP_DDS_LOG_QUIET_S 5.0

typedef struct palp_dds_log_view {
  int seen;                         /* a status listing the session has been read */
  int64_t base_shed, base_failed;   /* the server's counts then (moved when they fall: a server begun again) */
  uint64_t shed, failed;            /* lost since then [records] */
  uint64_t lost_prev, written_prev; /* the server's counts in the status before */
  int losing;                       /* a rise seen, and not PALP_DDS_LOG_QUIET_S of writing since */
  int64_t rose_ns;                  /* the last rise (the caller's monotonic clock) */
  uint64_t written_at_rise;
  int own;                          /* palp_session_log heard: shed and failed are this session's own */
} palp_dds_log_view;

/* One status of the server that lists the session (a zeroed view before the first), at now_ns. */
void palp_dds_log_view_status(palp_dds_log_view *v, uint64_t written, uint64_t shed, uint64_t failed, int64_t now_ns);

/* This session's own losses (palp_session_log: its records shed and failed since it opened), at now_ns:
 * from the first, they replace the counts from the status. */
void palp_dds_log_view_session(palp_dds_log_view *v, uint64_t shed, uint64_t failed, int64_t now_ns);

/* What the session's user is told, "" and 0 when nothing was lost since the view began; 1 while
 * losing: "the server's session log is losing records: 12 so far while this session runs (the log's
 * disk or its cap is full); this session will be incomplete in the review: tell your instructor"
 * (trainee 0, an instructor following it: "...; the server's log says what to do"); 2 after:
 * "the server's session log is writing again; 12 records were lost while this session ran: it will
 * be incomplete in the review". With its own counts (palp_dds_log_view_session): "the server's session
 * log is losing this session's records: 12 so far (...); ..." and "... is writing again; 12 of this
 * session's records were lost: ...". */
int palp_dds_log_view_words(const palp_dds_log_view *v, int trainee, char *buf, size_t len);
/* The loss in all, as the session ends, 0 and "" when none: "the server's session log lost 1210 records
 * while this session ran (the log's disk or its cap is full): it will be incomplete in the review"; with
 * its own counts "the server's session log lost 1210 of this session's records (...): ...". */
int palp_dds_log_view_summary(const palp_dds_log_view *v, char *buf, size_t len);

#endif
