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
  /* The bucket first: a flood costs one comparison per sample, whatever it holds. */
  if (f->last_ns) {
    f->tokens += (double)(now_ns - f->last_ns) * 1e-9 * f->lim.rate;
    if (f->tokens > f->lim.burst) f->tokens = f->lim.burst;
  }
  f->last_ns = now_ns;
  if (f->tokens < 1.0)
    return refuse(f, "too many findings: at most %g per second (burst %d)", f->lim.rate, f->lim.burst);
  f->tokens -= 1.0;
  if (in->session_id != f->lim.session_id)
    return refuse(f, "finding names session %u, not this partition's session %u", in->session_id,
                  f->lim.session_id);
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
  if (p.x < f->lim.box_min.x || p.x > f->lim.box_max.x || p.y < f->lim.box_min.y || p.y > f->lim.box_max.y ||
      p.z < f->lim.box_min.z || p.z > f->lim.box_max.z)
    return refuse(f, "mark %u: point (%.3f, %.3f, %.3f) m is not on the phantom", in->mark_id, p.x, p.y, p.z);
  if (at >= 0) return refuse(f, "mark %u was already made (ids are not reused)", in->mark_id);
  if (f->made >= PALP_SRV_MAX_MARKS)
    return refuse(f, "mark %u: %d marks made, at most %d per session", in->mark_id, f->made, PALP_SRV_MAX_MARKS);
  f->mark[f->made] = in->mark_id;
  f->standing[f->made] = 1;
  f->made++;
  f->marks++;
  f->last_accepted = 1;
  f->accepted++;
  return 1;
}
