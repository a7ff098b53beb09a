/* valid_range.c - the detail of a valid_range event (PALP_DB_EVENT_VALID_RANGE): written by the
 * server (server/db_log.c) once a second while a session's model is outside its valid range,
 * read back by palp-review. One format, written and parsed here, so the two cannot drift. */
#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "palp_db.h"

/* "outside at N steps: depth N, skin N, limit N; deepest X mm beyond the validated depth so far" */
#define VR_FMT_HEAD "outside at %" PRId64 " steps: depth %" PRId64 ", skin %" PRId64 ", limit %" PRId64
#define VR_FMT_TAIL "; deepest %.2f mm beyond the validated depth so far"
/* A bound no real row reaches: 10^12 steps is 31 years at 1 kHz. A forged row cannot then make the
 * sums overflow before ~10^7 such rows, and the sums saturate beyond. */
#define VR_MAX_STEPS 1000000000000LL
#define VR_SUM_MAX (INT64_MAX / 2)

int palp_db_valid_range_format(const palp_db_valid_range *r, char *buf, size_t len) {
  return snprintf(buf, len, VR_FMT_HEAD VR_FMT_TAIL, r->steps, r->depth_steps, r->skin_steps, r->limit_steps,
                  r->deepest_m * 1e3);
}

int palp_db_valid_range_parse(const char *detail, int64_t count, palp_db_valid_range *out) {
  if (!detail || !out) return PALP_EINVAL;
  palp_db_valid_range r;
  double mm = 0;
  int used = 0;
  if (sscanf(detail, "outside at %" SCNd64 " steps: depth %" SCNd64 ", skin %" SCNd64 ", limit %" SCNd64
                     "; deepest %lf mm beyond the validated depth so far%n",
             &r.steps, &r.depth_steps, &r.skin_steps, &r.limit_steps, &mm, &used) != 5 ||
      detail[used] != '\0')
    return PALP_EINVAL;
  /* a step counts once in steps and at most once in each part; the depth excess is a few
   * millimetres, never a metre (the dome is 40 mm high) */
  if (r.steps < 1 || r.steps > VR_MAX_STEPS || r.steps != count || r.depth_steps < 0 || r.skin_steps < 0 ||
      r.limit_steps < 0 || r.depth_steps > r.steps || r.skin_steps > r.steps || r.limit_steps > r.steps ||
      r.depth_steps + r.skin_steps + r.limit_steps < r.steps || !isfinite(mm) || mm < 0 || mm > 1000)
    return PALP_EINVAL;
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
