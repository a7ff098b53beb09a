/* valid_range.c - the detail of a valid_range event (PALP_DB_EVENT_VALID_RANGE): written by the
 * server (server/db_log.c) once a second while a session's model is outside its valid range,
 * read back by palp-review. One format, written and parsed here, so the two cannot drift. */
#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "palp_db.h"

/* "outside at N steps: depth N, skin N, limit N; deepest X mm beyond the validated depth so far";
 * with the literal gel law's frames outside its stable range (2026-12-06) ", gel N" after limit and
 * "; gel momentum left out at N frames" at the end. Without them the old detail, word for word: a
 * palp-review from before reads every session that never met them as it did. */
#define VR_FMT_HEAD "outside at %" PRId64 " steps: depth %" PRId64 ", skin %" PRId64 ", limit %" PRId64
#define VR_FMT_GEL ", gel %" PRId64
#define VR_FMT_TAIL "; deepest %.2f mm beyond the validated depth so far"
#define VR_FMT_GEL_TAIL "; gel momentum left out at %" PRId64 " frames"
#define VR_SCN_HEAD "outside at %" SCNd64 " steps: depth %" SCNd64 ", skin %" SCNd64 ", limit %" SCNd64
#define VR_SCN_TAIL "; deepest %lf mm beyond the validated depth so far"
/* A bound no real row reaches: 10^12 steps is 31 years at 1 kHz. A forged row cannot then make the
 * sums overflow before ~10^7 such rows, and the sums saturate beyond. */
#define VR_MAX_STEPS 1000000000000LL
#define VR_SUM_MAX (INT64_MAX / 2)

int palp_db_valid_range_format(const palp_db_valid_range *r, char *buf, size_t len) {
  if (r->gel_steps > 0)
    return snprintf(buf, len, VR_FMT_HEAD VR_FMT_GEL VR_FMT_TAIL VR_FMT_GEL_TAIL, r->steps, r->depth_steps,
                    r->skin_steps, r->limit_steps, r->gel_steps, r->deepest_m * 1e3, r->gel_frames);
  return snprintf(buf, len, VR_FMT_HEAD VR_FMT_TAIL, r->steps, r->depth_steps, r->skin_steps, r->limit_steps,
                  r->deepest_m * 1e3);
}

int palp_db_valid_range_parse(const char *detail, int64_t count, palp_db_valid_range *out) {
  if (!detail || !out) return PALP_EINVAL;
  palp_db_valid_range r;
  memset(&r, 0, sizeof r);
  double mm = 0;
  int used = 0;
  /* The one with gel first: the old one's "limit N;" cannot match its "limit N, gel N" */
  const int gel = sscanf(detail, VR_SCN_HEAD ", gel %" SCNd64 VR_SCN_TAIL "; gel momentum left out at %" SCNd64
                                 " frames%n",
                         &r.steps, &r.depth_steps, &r.skin_steps, &r.limit_steps, &r.gel_steps, &mm, &r.gel_frames,
                         &used) == 7 &&
                  detail[used] == '\0';
  if (!gel) {
    memset(&r, 0, sizeof r);
    used = 0;
    if (sscanf(detail, VR_SCN_HEAD VR_SCN_TAIL "%n", &r.steps, &r.depth_steps, &r.skin_steps, &r.limit_steps, &mm,
               &used) != 5 ||
        detail[used] != '\0')
      return PALP_EINVAL;
  }
  /* a step counts once in steps and at most once in each part; the depth excess is a few
   * millimetres, never a metre (the dome is 40 mm high); a gel step has at least one frame
   * without the term (and "gel 0" is written the old way, so refused here) */
  if (r.steps < 1 || r.steps > VR_MAX_STEPS || r.steps != count || r.depth_steps < 0 || r.skin_steps < 0 ||
      r.limit_steps < 0 || r.depth_steps > r.steps || r.skin_steps > r.steps || r.limit_steps > r.steps ||
      r.gel_steps > r.steps || r.depth_steps + r.skin_steps + r.limit_steps + r.gel_steps < r.steps || !isfinite(mm) ||
      mm < 0 || mm > 1000)
    return PALP_EINVAL;
  if (gel && !(r.gel_steps >= 1 && r.gel_frames >= r.gel_steps && r.gel_frames <= VR_MAX_STEPS)) return PALP_EINVAL;
  r.deepest_m = mm * 1e-3;
  *out = r;
  return 0;
}

typedef struct sum_ctx {
  palp_db_valid_range sum;
  int64_t events, unreadable;
} sum_ctx;

static int64_t sat_add(int64_t a, int64_t b) { return a > VR_SUM_MAX - b ? VR_SUM_MAX : a + b; }

static int add_event(void *user, double wall, int64_t frame, const char *kind, const char *detail, int64_t count) {
  (void)wall, (void)frame;
  sum_ctx *c = user;
  if (!kind || strcmp(kind, palp_db_event_kind_name(PALP_DB_EVENT_VALID_RANGE))) return 0;
  c->events++;
  palp_db_valid_range r;
  if (palp_db_valid_range_parse(detail, count, &r) < 0) {
    c->unreadable++;
    if (count > 0 && count <= VR_MAX_STEPS) c->sum.steps = sat_add(c->sum.steps, count);
    return 0;
  }
  c->sum.steps = sat_add(c->sum.steps, r.steps);
  c->sum.depth_steps = sat_add(c->sum.depth_steps, r.depth_steps);
  c->sum.skin_steps = sat_add(c->sum.skin_steps, r.skin_steps);
  c->sum.limit_steps = sat_add(c->sum.limit_steps, r.limit_steps);
  c->sum.gel_steps = sat_add(c->sum.gel_steps, r.gel_steps);
  c->sum.gel_frames = sat_add(c->sum.gel_frames, r.gel_frames);
  if (r.deepest_m > c->sum.deepest_m) c->sum.deepest_m = r.deepest_m;
  return 0;
}

int palp_db_session_valid_range(palp_db *db, int64_t session_id, palp_db_valid_range *sum, int64_t *events,
                                int64_t *unreadable) {
  sum_ctx c;
  memset(&c, 0, sizeof c);
  const int rc = palp_db_each_event(db, session_id, add_event, &c);
  if (rc < 0) return rc;
  *sum = c.sum;
  if (events) *events = c.events;
  if (unreadable) *unreadable = c.unreadable;
  return 0;
}
