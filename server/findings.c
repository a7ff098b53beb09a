/* findings.c - checking and holding a session's "lump here" marks. */
#include "findings.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

void palp_srv_findings_init(palp_srv_findings *f, const palp_srv_findings_limits *lim) {
  memset(f, 0, sizeof *f);
  f->lim = *lim;
  f->tokens = lim->burst;
}

double palp_srv_findings_depth_max(const palp_exercise *ex) {
  double d = 0.0;
  for (int b = 0; ex && b < PALP_BAND_COUNT; b++)
    if (ex->band[b].has_depth && ex->band[b].depth_max > d) d = ex->band[b].depth_max;
  return d > 0.0 ? d + PALP_SRV_MARK_DEPTH_SLACK : PALP_SRV_MARK_DEPTH_DEFAULT;
}

int palp_srv_findings_check_exercise(const palp_exercise *ex, double R, double max_force, char *msg, size_t len) {
  /* session 90's review: neither was checked, the parser knowing neither the dome nor the server */
  const double dmax = palp_srv_findings_depth_max(ex);
  int by_depth = 0;
  for (int b = 0; b < PALP_BAND_COUNT; b++) by_depth |= ex->band[b].has_depth;
  if (by_depth && dmax >= R) {
    snprintf(msg, len, "its pressure bands reach %.1f mm under the skin (with the marks' %.0f mm of slack), at or "
             "past the dome's %.1f mm radius: make the deep band shallower", dmax * 1e3, PALP_SRV_MARK_DEPTH_SLACK * 1e3,
             R * 1e3);
    return PALP_EINVAL;
  }
  for (int b = 0; b < PALP_BAND_COUNT; b++)
    if (ex->band[b].has_force && ex->band[b].force_min >= max_force) {
      snprintf(msg, len, "its %s band starts at %.1f N, at or above this server's force limit of %.1f N (max_force): "
               "no press can reach it", palp_band_name(b), ex->band[b].force_min, max_force);
      return PALP_EINVAL;
    }
  return 0;
}

static int refuse(palp_srv_findings *f, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(f->reason, sizeof f->reason, fmt, ap);
  va_end(ap);
  f->last_accepted = 0;
  f->refused++;
  return 0;
}

static int find_mark(const palp_srv_findings *f, uint32_t id) {
  for (int i = 0; i < f->made; i++)
    if (f->mark[i] == id) return i;
  return -1;
}

int palp_srv_findings_offer(palp_srv_findings *f, const palp_Finding *in, int64_t now_ns) {
  f->last_mark_id = in->mark_id;
  f->reason[0] = 0;
  /* Another session's id first, and not charged to this session's bucket: findings naming made-up
   * sessions spent the session's tokens, and its trainee's mark right after was refused "too many
   * findings" (test server_debrief). Over DDS the reader's filter drops them before they come here
   * (server/session.c, session 72); this is the second line. One comparison, as the bucket's. */
  if (in->session_id != f->lim.session_id)
    return refuse(f, "finding names session %u, not this partition's session %u", in->session_id,
                  f->lim.session_id);
  /* The bucket next: a flood costs one comparison per sample, whatever it holds. */
  if (f->last_ns) {
    f->tokens += (double)(now_ns - f->last_ns) * 1e-9 * f->lim.rate;
    if (f->tokens > f->lim.burst) f->tokens = f->lim.burst;
  }
  f->last_ns = now_ns;
  if (f->tokens < 1.0)
    return refuse(f, "too many findings: at most %g per second (burst %d)", f->lim.rate, f->lim.burst);
  f->tokens -= 1.0;
  if (in->op != palp_FINDING_MARK && in->op != palp_FINDING_WITHDRAW)
    return refuse(f, "unknown finding op %d", (int)in->op);
  if (in->mark_id == 0) return refuse(f, "mark_id 0: marks are numbered from 1");
  const int at = find_mark(f, in->mark_id);
  if (in->op == palp_FINDING_WITHDRAW) {
    if (at < 0 || !f->standing[at]) return refuse(f, "withdrawal of mark %u, which is not standing", in->mark_id);
    f->standing[at] = 0;
    f->marks--;
    f->last_accepted = 1;
    f->accepted++;
    return 1;
  }
  const palp_Vec3 p = in->point;
  if (!isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z)) return refuse(f, "mark %u: point is not finite", in->mark_id);
  /* On the skin, as a contact point is (findings.h): not below the base, and its distance from the
   * base's centre within the shell the skin can be pressed into. */
  const double R = f->lim.dome_radius, r = sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
  if (p.z < 0.0)
    return refuse(f, "mark %u: point (%.3f, %.3f, %.3f) m is not on the phantom: below its base", in->mark_id, p.x,
                  p.y, p.z);
  if (r < R - f->lim.depth_max)
    return refuse(f, "mark %u: point (%.3f, %.3f, %.3f) m is not on the phantom: %.1f mm under its skin (at most %.1f)",
                  in->mark_id, p.x, p.y, p.z, (R - r) * 1e3, f->lim.depth_max * 1e3);
  if (r > R + f->lim.height_max)
    return refuse(f, "mark %u: point (%.3f, %.3f, %.3f) m is not on the phantom: %.1f mm above its skin (at most %.1f)",
                  in->mark_id, p.x, p.y, p.z, (r - R) * 1e3, f->lim.height_max * 1e3);
  /* Made within the exercise's time: its model's world time, which runs no faster than the session's
   * clock (a late server skips steps), so a mark made in time is never refused for its network delay.
   * Until session 90 one made after the limit but taken before the session closed (up to a main-loop
   * pass later, and at the close's last look) counted in the debrief and the grade (found by review). */
  if (f->lim.time_limit > 0.0 && !(in->time <= f->lim.time_limit))
    return refuse(f, "mark %u: made at %.2f s of the session, after its %.0f s time limit", in->mark_id, in->time,
                  f->lim.time_limit);
  if (at >= 0) return refuse(f, "mark %u was already made (ids are not reused)", in->mark_id);
  if (f->made >= PALP_SRV_MAX_MARKS)
    return refuse(f, "mark %u: %d marks made, at most %d per session", in->mark_id, f->made, PALP_SRV_MAX_MARKS);
  f->mark[f->made] = in->mark_id;
  f->standing[f->made] = 1;
  f->point[f->made] = (palp_vec3){p.x, p.y, p.z};
  f->made++;
  f->marks++;
  f->last_accepted = 1;
  f->accepted++;
  return 1;
}

int palp_srv_findings_debrief(const palp_srv_findings *f, const palp_exercise *ex, double dome_radius,
                              uint32_t session_id, const char *reason, palp_Debrief *out,
                              palp_DebriefLesion *lesion_buf) {
  memset(out, 0, sizeof *out);
  out->session_id = session_id;
  out->level = palp_DEBRIEF_NONE;
  out->marks = (uint32_t)f->marks;
  out->lesion._buffer = lesion_buf;
  out->lesion._release = false;
  snprintf(out->reason, sizeof out->reason, "%s", reason ? reason : "");
  /* Only the standing marks count: a withdrawn one is the trainee's own correction. The review
   * counts the same (its log holds both, palp_assess drops the withdrawn). */
  palp_finding marks[PALP_SRV_MAX_MARKS];
  uint32_t ids[PALP_SRV_MAX_MARKS];
  int n = 0;
  for (int i = 0; i < f->made && i < PALP_SRV_MAX_MARKS; i++)
    if (f->standing[i]) {
      marks[n] = (palp_finding){.t = 0.0, .point = f->point[i], .withdrawn = 0};
      ids[n++] = f->mark[i];
    }
  palp_assess_result r;
  int match[PALP_SRV_MAX_MARKS];
  const int rc = palp_assess_findings(ex, dome_radius, marks, n, &r, match);
  if (rc < 0) return rc;
  if (ex->debrief == PALP_DEBRIEF_NONE) return 0;
  out->level = ex->debrief == PALP_DEBRIEF_LESIONS ? palp_DEBRIEF_LESIONS : palp_DEBRIEF_COUNT;
  out->lesions = (uint32_t)r.lesion_count;
  out->found = (uint32_t)r.found;
  out->false_marks = (uint32_t)r.false_positives;
  out->duplicates = (uint32_t)r.duplicates;
  if (out->level != palp_DEBRIEF_LESIONS) return 0;
  for (int l = 0; l < ex->lesion_count && l < PALP_MAX_LESIONS; l++) {
    const palp_vec3 c = palp_exercise_lesion_surface(&ex->lesion[l], dome_radius);
    lesion_buf[l] = (palp_DebriefLesion){.point = {c.x, c.y, c.z},
                                         .depth = ex->lesion[l].depth,
                                         .diameter = ex->lesion[l].diameter,
                                         .found_by = r.lesion_found[l] >= 0 ? ids[r.lesion_found[l]] : 0};
  }
  out->lesion._length = out->lesion._maximum = (uint32_t)ex->lesion_count;
  return 0;
}
