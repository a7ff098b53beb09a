/* palp_dds_log_view.c - the server's session log as one session sees it (palp_dds_log_view.h). */
#include <stdio.h>

#include "palp_dds_log_view.h"

/* Writing again: PALP_DDS_LOG_QUIET_S since the last loss, and records written since. */
static void maybe_quiet(palp_dds_log_view *v, uint64_t written, int64_t now_ns) {
  if (v->losing && now_ns - v->rose_ns >= (int64_t)(PALP_DDS_LOG_QUIET_S * 1e9) && written > v->written_at_rise)
    v->losing = 0;
}

void palp_dds_log_view_status(palp_dds_log_view *v, uint64_t written, uint64_t shed, uint64_t failed, int64_t now_ns) {
  const uint64_t lost = shed + failed;
  if (v->own) { /* the session's own counts: the server's say only whether the log writes again */
    maybe_quiet(v, written, now_ns);
    v->seen = 1;
    v->lost_prev = lost;
    v->written_prev = written;
    return;
  }
  if (!v->seen) { /* the base from which the session's losses are counted */
    *v = (palp_dds_log_view){.seen = 1, .base_shed = (int64_t)shed, .base_failed = (int64_t)failed,
                             .lost_prev = lost, .written_prev = written};
    return;
  }
  if (lost < v->lost_prev || written < v->written_prev) {
    /* Counts that fall: a server begun again. What was lost before stays lost: the base moves so
     * that the counts go on from there. */
    v->base_shed = (int64_t)shed - (int64_t)v->shed;
    v->base_failed = (int64_t)failed - (int64_t)v->failed;
  } else if (lost > v->lost_prev) {
    v->losing = 1;
    v->rose_ns = now_ns;
    v->written_at_rise = written;
  } else {
    maybe_quiet(v, written, now_ns);
  }
  v->shed = (uint64_t)((int64_t)shed - v->base_shed);
  v->failed = (uint64_t)((int64_t)failed - v->base_failed);
  v->lost_prev = lost;
  v->written_prev = written;
}

void palp_dds_log_view_session(palp_dds_log_view *v, uint64_t shed, uint64_t failed, int64_t now_ns) {
  if (failed > UINT64_MAX - shed) return; /* a sum past 2^64 is no count (a forged sample): it would wrap */
  const uint64_t before = v->own ? v->shed + v->failed : 0;
  if (v->own && shed + failed < before) return; /* a session's losses never fall: not from its server */
  if (!v->own) /* what the server's counts said before is not hers: her own say it from now on */
    v->losing = 0;
  v->own = 1;
  if (shed + failed > before) { /* the server's counts never fall for one session; a repeat is no rise */
    v->losing = 1;
    v->rose_ns = now_ns;
    v->written_at_rise = v->written_prev;
  }
  v->shed = shed;
  v->failed = failed;
}

/* Why, as far as the session's user can do anything with it: an instructor can (the dashboard and the
 * server's log say what to do), a trainee tells one. */
static const char *why(const palp_dds_log_view *v) {
  return v->failed && v->shed ? "the server was too busy to write some, and the log's disk or its cap is full"
         : v->failed          ? "the log's disk or its cap is full"
                              : "the server was too busy to write them";
}

int palp_dds_log_view_words(const palp_dds_log_view *v, int trainee, char *buf, size_t len) {
  if (len) buf[0] = 0;
  const unsigned long long lost = v->shed + v->failed;
  if (!lost) return 0;
  const char *then = trainee ? ": tell your instructor" : "; the server's log says what to do";
  if (v->losing) {
    if (v->own)
      snprintf(buf, len,
               "the server's session log is losing this session's records: %llu so far (%s); this session will be "
               "incomplete in the review%s",
               lost, why(v), then);
    else
      snprintf(buf, len,
               "the server's session log is losing records: %llu so far while this session runs (%s); this session "
               "will be incomplete in the review%s",
               lost, why(v), then);
    return 1;
  }
  snprintf(buf, len,
           v->own ? "the server's session log is writing again; %llu of this session's records were lost: it will be "
                    "incomplete in the review"
                  : "the server's session log is writing again; %llu records were lost while this session ran: it "
                    "will be incomplete in the review",
           lost);
  return 2;
}

int palp_dds_log_view_summary(const palp_dds_log_view *v, char *buf, size_t len) {
  if (len) buf[0] = 0;
  const unsigned long long lost = v->shed + v->failed;
  if (!lost) return 0;
  snprintf(buf, len,
           v->own ? "the server's session log lost %llu of this session's records (%s): it will be incomplete in the "
                    "review"
                  : "the server's session log lost %llu records while this session ran (%s): it will be incomplete "
                    "in the review",
           lost, why(v));
  return 1;
}
