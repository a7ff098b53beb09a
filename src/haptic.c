/*
 * haptic.c - the station's 1 kHz haptic renderer over the server's local contact
 * models (palp_haptic.h, docs/haptics.md).
 *
 * Why an offset crossfade: a new model is the server's better answer for a state
 * the hand has already moved on from, so its force at the device differs from
 * what the hand feels now by a prediction error delta. Rendering
 *   F(t) = F_new(x(t)) + delta (1 - s(t)),  s = (t - t_arrival) / blend in [0, 1],
 * keeps the force continuous at the arrival and lets it reach the new model within
 * one physics period; a model arriving in the middle of a blend restarts it from
 * the force actually rendered, so the force stays continuous however models come.
 *
 * Why an onset is a gain, not an offset: the first model (after none, a forget or a stale
 * fade-out) must reach the hand over fade_time, and the models keep coming every period
 * meanwhile. As a long offset, each of them restarted the blend from the ~4% then
 * rendered over one period, so the onset was over in 4 ticks (0 -> 2 N at 0.48 N a tick;
 * session 82's review); and the offset, -F_new at the arrival, pulled the finger into the
 * surface once it withdrew (F_new -> 0, the offset left alone: -0.56 N on a quick tap).
 * Rendered as g(t) F(x), g rising from the share the hand felt to 1 over fade_time on the
 * station's clock, the onset keeps its length whatever arrives, and a gain on a unilateral
 * force stays unilateral. The offsets left (corrections) are cut where they would pull.
 */
#include <math.h>
#include <string.h>

#include "finger.h"
#include "palp_haptic.h"
#include "vec3.h"

palp_haptic_def palp_haptic_default_def(void) {
  return (palp_haptic_def){.max_force = 10.0,
                           .damping = 2.0,
                           .blend_time = 0.0,
                           .max_extrapolation = 0.010,
                           .stale_time = 0.25,
                           .fade_time = 0.1,
                           .max_stiffness = 4000.0};
}

palp_vec3 palp_local_model_force(const palp_local_model *m, palp_vec3 x, double age) {
  if (!m || !m->contact || !v3_isfinite(x)) return v3(0, 0, 0);
  if (!(age > 0.0)) age = 0.0; /* NaN and negative ages evaluate at the model's time */
  /* d = x - (device + drift age): the device's motion relative to the surface [m] */
  const palp_vec3 d = v3_sub(x, v3_add(m->device, v3_scale(m->drift, age)));
  const double(*K)[3] = m->stiffness;
  const palp_vec3 Kd = v3(K[0][0] * d.x + K[0][1] * d.y + K[0][2] * d.z, K[1][0] * d.x + K[1][1] * d.y + K[1][2] * d.z,
                          K[2][0] * d.x + K[2][1] * d.y + K[2][2] * d.z);
  const palp_vec3 f = v3_sub(m->force, Kd); /* [N] */
  /* Unilateral: the surface pushes, never pulls; past the release point the finger is free. */
  if (!(v3_dot(f, m->normal) > 0.0)) return v3(0, 0, 0);
  return f;
}

int palp_haptic_limit_stiffness(double K[3][3], double max_stiffness) {
  double l[3], V[3][3];
  palp_sym3_eig((const double(*)[3])K, l, V);
  const double big = fmax(fmax(fabs(l[0]), fabs(l[1])), fabs(l[2]));
  int change = 0, limited = 0;
  for (int e = 0; e < 3; ++e) {
    /* K = -dF/dx of a surface is positive semi-definite: a negative eigenvalue pushes the hand
     * on along its motion (the review's K: +1 N along 1 mm of motion). Round-off is not
     * flagged; it is projected all the same. */
    if (l[e] < 0.0) {
      if (l[e] < -1e-6 * big) limited = 1;
      l[e] = 0.0, change = 1;
    }
    /* A device is never asked to render more than the coupling allows (docs/haptics.md); a K of
     * 1e6 N/m against the hand's damping is a limit cycle of several newtons. */
    if (l[e] > max_stiffness) l[e] = max_stiffness, change = limited = 1;
  }
  if (!change) return 0; /* K stays bit for bit */
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) K[i][j] = V[i][0] * l[0] * V[j][0] + V[i][1] * l[1] * V[j][1] + V[i][2] * l[2] * V[j][2];
  for (int i = 0; i < 3; ++i) /* exactly symmetric */
    for (int j = 0; j < i; ++j) K[i][j] = K[j][i] = 0.5 * (K[i][j] + K[j][i]);
  return limited;
}

static int model_ok(const palp_local_model *m) {
  if (!(isfinite(m->time) && isfinite(m->period) && m->period >= 0.0)) return 0;
  if (!v3_isfinite(m->device) || !v3_isfinite(m->force) || !v3_isfinite(m->drift) || !v3_isfinite(m->normal))
    return 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (!isfinite(m->stiffness[i][j])) return 0;
  return 1;
}

int palp_haptic_init(palp_haptic *h, const palp_haptic_def *def) {
  if (!h) return PALP_EINVAL;
  const palp_haptic_def d = def ? *def : palp_haptic_default_def();
  if (!(d.max_force > 0.0) || !(d.damping >= 0.0) || !(d.blend_time >= 0.0) || !(d.max_extrapolation >= 0.0) ||
      !(d.stale_time > 0.0) || !(d.fade_time > 0.0) || !isfinite(d.max_force) || !isfinite(d.damping) ||
      !(d.max_stiffness > 0.0) || !isfinite(d.stale_time) || !isfinite(d.fade_time) || !isfinite(d.blend_time))
    return PALP_EINVAL; /* an infinite stale or fade time: a silent server's force would never fade */
  memset(h, 0, sizeof *h);
  h->def = d;
  h->onset_from = 1.0; /* no onset running */
  return PALP_OK;
}

void palp_haptic_forget(palp_haptic *h) {
  if (h) h->have = 0; /* rendered and last_x stay: the hand's force is what the next model blends from */
}

#define PALP_HAPTIC_DAMPER_DT_MIN 0.5e-3 /* [s] the damper's shortest velocity interval */

static double clamp01(double s) { return s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s); }

palp_vec3 palp_haptic_clamp(palp_vec3 f, double max_force, unsigned *flags) {
  const double mag = v3_len(f);
  if (mag <= max_force) return f; /* NaN fails this test and is handled below */
  if (flags) *flags |= PALP_HAPTIC_LIMITED;
  /* A non-finite force (an infinite K d, inf - inf) scaled by max / inf would be NaN on the
   * device: nothing is rendered instead. */
  if (!isfinite(mag) || !(max_force > 0.0)) return v3(0, 0, 0);
  return v3_scale(f, max_force / mag);
}

/* The share of the blend offset still left at now: 1 at the arrival, 0 after blend_len. */
static double offset_share(const palp_haptic *h, double now) {
  return 1.0 - (h->blend_len > 0.0 ? clamp01((now - h->cur_at) / h->blend_len) : 1.0);
}

/* The onset gain at now: from onset_from up to 1 over fade_time since onset_at, on the
 * station's clock alone (models arriving meanwhile do not shorten it). */
static double onset_gain(const palp_haptic *h, double now) {
  if (!(h->onset_from < 1.0)) return 1.0;
  return h->onset_from + (1.0 - h->onset_from) * clamp01((now - h->onset_at) / h->def.fade_time);
}

/* The unit normal the rendered force never pulls against: the current model's contact
 * normal, or else the last model in contact's (an offset may still decay). 0 if none. */
static int push_normal(const palp_haptic *h, palp_vec3 *n) {
  if (!h) return 0;
  palp_vec3 u = h->last_normal; /* unit, or 0 before any model in contact */
  if (h->have && h->cur.contact) {
    const double l = v3_len(h->cur.normal);
    if (l > 0.0 && isfinite(l)) u = v3_scale(h->cur.normal, 1.0 / l);
  }
  if (!(v3_len(u) > 0.0)) return 0;
  if (n) *n = u;
  return 1;
}

int palp_haptic_push_normal(const palp_haptic *h, palp_vec3 *n) { return push_normal(h, n); }

/* f without its component into the surface (along -n): a surface pushes, never pulls. */
static palp_vec3 no_pull(palp_vec3 f, palp_vec3 n) {
  const double fn = v3_dot(f, n);
  return fn < 0.0 ? v3_sub(f, v3_scale(n, fn)) : f; /* NaN passes through to the clamp, which zeroes it */
}

palp_vec3 palp_haptic_no_pull(const palp_haptic *h, palp_vec3 f) {
  palp_vec3 n;
  return push_normal(h, &n) ? no_pull(f, n) : f;
}

/* The models' force before damping and fade: the newest model, limited to max_force before
 * it is scaled by the onset gain (a 40 N model against a 10 N limit contributes 10 N, so an
 * onset or a fade of it moves the rendered force over its whole length rather than holding
 * the limit until the scale falls below 10/40), plus the decaying offset of the last
 * arrival; the sum's component into the surface cut (push_normal), then
 * limited again. *raw (if not NULL) gets the same sum without any limit (what the models
 * ask for) and *flags PALP_HAPTIC_LIMITED when a limit acted. */
static palp_vec3 model_part(const palp_haptic *h, palp_vec3 x, double now, palp_vec3 *raw, unsigned *flags) {
  const double age = fmin(now - h->cur_at, h->def.max_extrapolation);
  const double g = onset_gain(h, now);
  const palp_vec3 f = palp_local_model_force(&h->cur, x, age);
  const palp_vec3 off = v3_scale(h->prev.force, offset_share(h, now)); /* prev.force holds the offset delta */
  palp_vec3 n = {0, 0, 0};
  const int hn = push_normal(h, &n);
  palp_vec3 sum = v3_add(v3_scale(palp_haptic_clamp(f, h->def.max_force, flags), g), off);
  if (raw) *raw = hn ? no_pull(v3_add(v3_scale(f, g), off), n) : v3_add(v3_scale(f, g), off);
  if (hn) sum = no_pull(sum, n);
  return palp_haptic_clamp(sum, h->def.max_force, flags);
}

/* The share of the model force a silent server still leaves on the hand: 1 while models
 * are fresh, down to 0 over fade_time once the newest is older than stale_time. */
double palp_haptic_fade(const palp_haptic_def *d, double age) {
  return age > d->stale_time ? clamp01(1.0 - (age - d->stale_time) / d->fade_time) : 1.0;
}

static double stale_scale(const palp_haptic *h, double now) { return palp_haptic_fade(&h->def, now - h->cur_at); }

double palp_haptic_stale_scale(const palp_haptic *h, double now) {
  if (!h || !h->have) return 0.0;
  return isfinite(now) ? stale_scale(h, now) : 0.0;
}

int palp_haptic_accepts(const palp_haptic *h, const palp_local_model *m, double now) {
  if (!h || !m || !isfinite(now) || !model_ok(m)) return 0;
  if (!h->have) return 1;
  if (!(m->time > h->cur.time)) return 0; /* late or repeated: the newer one stands */
  /* A model's time may run ahead of the current one's by the station time since that one
   * came, plus stale_time: world time does not run faster than the server's clock (its
   * ticker drops lost slots rather than burst), and stale_time covers the current one's
   * delivery delay. Without this bound one model stamped 1e300 s made every later model
   * "older" and the force faded out for good. Once the current model is stale any newer
   * one is taken: should a real jump exceed the bound, the models resume after stale_time
   * rather than never. */
  return m->time - h->cur.time <= (now - h->cur_at) + h->def.stale_time || now - h->cur_at > h->def.stale_time;
}

int palp_haptic_update(palp_haptic *h, const palp_local_model *m_in, double now) {
  if (!h || !m_in || !isfinite(now)) return PALP_EINVAL;
  if (!model_ok(m_in)) return PALP_EINVAL;
  if (!palp_haptic_accepts(h, m_in, now)) return 0;
  /* The model as the station will render it: K positive semi-definite and within max_stiffness. */
  palp_local_model mk = *m_in;
  const palp_local_model *m = &mk;
  /* The contact normal as a unit vector: the damper and its floor read it as one, and a normal of
   * length 3 let the damper pull the withdrawing hand into the surface (-4 N; session 90's review;
   * the station refuses such a model from the wire, this is the library's own guard). */
  if (mk.contact) {
    const double l = v3_len(mk.normal);
    if (!(l > 1e-9)) return PALP_EINVAL; /* in contact along no direction */
    mk.normal = v3_scale(mk.normal, 1.0 / l);
  }
  const int klim = palp_haptic_limit_stiffness(mk.stiffness, h->def.max_stiffness);
  palp_vec3 delta = v3(0, 0, 0);
  double blend = h->def.blend_time > 0.0 ? h->def.blend_time : m->period;
  if (h->rendered) {
    /* What the hand feels now (before damping; limited, gained and faded as rendered) minus
     * the new model's answer as it will be rendered: the blend then starts from the force
     * the hand actually feels. Before the first model the hand felt nothing, and a
     * faded-out stale model left only its faded share: a device already pressed in when
     * the models (re)start must not get the whole force in one tick (it did: 0 -> 2.1 N
     * when the demo's first model came 0.8 s after the press), so those start an onset,
     * the gain rising from the share felt to 1 over fade_time (onset_gain); a model that
     * arrives while one runs leaves it running. */
    const double keep = h->have ? stale_scale(h, now) : 0.0;
    const double g_now = h->have ? onset_gain(h, now) : 0.0;
    const palp_vec3 was = h->have ? v3_scale(model_part(h, h->last_x, now, NULL, NULL), keep) : v3(0, 0, 0);
    if (keep < 1.0) {
      h->onset_from = keep * g_now; /* the share the hand felt */
      h->onset_at = now;
    }
    const double g_new = keep < 1.0 ? h->onset_from : g_now;
    delta = v3_sub(was, v3_scale(palp_haptic_clamp(palp_local_model_force(m, h->last_x, 0.0), h->def.max_force, NULL),
                                 g_new));

    /* delta is a correction like any other (0 for a first model; the faded models' disagreement,
     * scaled by the share felt, after a silence): one period. Blends of fade_time for it, kept to
     * their end by later models, made every correction of an onset's first 0.1 s that long, and
     * the late-model press cycles of haptic_multirate_stiff gave back 1.5% in a cycle (bound 1%). */
  }
  if (m->contact) h->last_normal = m->normal; /* made unit above */
  h->prev = h->cur;
  h->prev.force = delta;
  h->cur = *m;
  h->cur_stiffness_limited = klim;
  if (klim) h->stiffness_limited++;
  h->cur_at = now;
  h->blend_len = blend;
  h->have = h->have ? 2 : 1;
  h->models++;
  return 1;
}

void palp_haptic_render(palp_haptic *h, palp_vec3 x, double now, palp_haptic_out *out) {
  palp_haptic_out o = {.force = v3(0, 0, 0), .proxy = x, .requested = 0.0, .flags = 0};
  if (!h->have || !v3_isfinite(x) || !isfinite(now)) {
    o.flags |= PALP_HAPTIC_NO_MODEL;
    /* the hand felt 0 N here: the first model blends in from it (palp_haptic_update) */
    if (!h->have && v3_isfinite(x) && isfinite(now)) h->last_x = x, h->last_t = now, h->rendered = 1;
    *out = o;
    return;
  }
  unsigned lim = 0;
  palp_vec3 raw;
  palp_vec3 f = model_part(h, x, now, &raw, &lim);
  /* A silent server must not leave a force on the hand: the limited model force fades
   * linearly over fade_time, max_force / (fade_time / tick) per tick at most (0.1 N per
   * 1 ms tick at 10 N, 0.1 s); the damper fades with it. */
  const double keep = stale_scale(h, now);
  if (now - h->cur_at > h->def.stale_time) o.flags |= PALP_HAPTIC_STALE;
  f = v3_scale(f, keep);
  raw = v3_scale(raw, keep);
  const palp_vec3 n = h->cur.normal;
  /* In contact only while the (faded) force pushes: a faded-out model is no contact, so the
   * station's passivity observer resets and its view stops saying "touching". */
  const int contact = h->cur.contact && keep > 0.0 && v3_dot(f, n) > 0.0;
  if (contact) {
    o.flags |= PALP_HAPTIC_CONTACT;
    /* Shown proxy: the model's, carried along the surface by the device's tangential motion. */
    const palp_vec3 dx = v3_sub(x, h->cur.device);
    o.proxy = v3_add(h->cur.proxy, v3_sub(dx, v3_scale(n, v3_dot(dx, n))));
    const double fn0 = v3_dot(f, n);
    /* Damper along the normal on the device's velocity, never pulling into the surface,
     * scaled with the fade and the onset gain (it has no step at an onset either). */
    if (h->rendered && now > h->last_t && h->def.damping > 0.0) {
      /* over at least half a tick of 1 kHz: a tick just after a late one (10 us) made encoder noise of
       * 10 um a velocity of 1 m/s and the damper 2 N in one tick (session 90's review) */
      const double dt = fmax(now - h->last_t, PALP_HAPTIC_DAMPER_DT_MIN);
      const double vn = v3_dot(v3_sub(x, h->last_x), n) / dt; /* [m/s], < 0 going in */
      const palp_vec3 fd = v3_scale(n, fmax(-keep * onset_gain(h, now) * h->def.damping * vn, -fn0));
      f = v3_add(f, fd);
      raw = v3_add(raw, fd);
    }
  }
  /* requested: the force without any limit (the models' raw sum, faded, plus the damper);
   * when no limit acted it is the rendered force, so requested > max_force implies LIMITED. */
  o.requested = v3_len(raw);
  f = palp_haptic_clamp(f, h->def.max_force, &lim);
  if (contact && h->cur_stiffness_limited) lim |= PALP_HAPTIC_LIMITED; /* rendered from a limited K */
  if (!v3_isfinite(raw)) o.requested = INFINITY;
  o.flags |= lim;
  if (lim) h->limited_ticks++;
  o.force = f;
  h->last_x = x;
  h->last_t = now;
  h->rendered = 1;
  *out = o;
}
