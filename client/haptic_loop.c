/* haptic_loop.c - the station's 1 kHz haptic thread (haptic_loop.h). */
#include "haptic_loop.h"

#include <errno.h>
#include <math.h>
#include <sched.h>
#include <semaphore.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "palp_dds.h"
#include "palp_rt_thread.h"

/* ---- mailbox ------------------------------------------------------------------------- */

int palp_cli_mailbox_init(palp_cli_mailbox *mb) {
  memset(mb, 0, sizeof *mb);
  return pthread_mutex_init(&mb->lock, NULL) == 0 ? 0 : PALP_ENOMEM;
}

void palp_cli_mailbox_destroy(palp_cli_mailbox *mb) { pthread_mutex_destroy(&mb->lock); }

void palp_cli_mailbox_put(palp_cli_mailbox *mb, const palp_local_model *m, uint32_t server_flags, double max_force,
                          double age) {
  pthread_mutex_lock(&mb->lock);
  /* A model not yet taken that is newer than m stays: best-effort delivery (or a relay) may
   * hand two models over out of order in one batch, and the older one put last replaced the
   * newer, which the haptic thread then never saw (a model a period behind until the next).
   * Once taken, m goes in whatever its time: the renderer refuses it if it is older, and a
   * server whose clock started again is not shut out of the box. */
  if (mb->seq != mb->taken && m->time < mb->model.time) {
    mb->superseded++;
    pthread_mutex_unlock(&mb->lock);
    return;
  }
  mb->age = age;
  mb->model = *m;
  mb->server_flags = server_flags;
  mb->max_force = max_force;
  mb->seq++;
  pthread_mutex_unlock(&mb->lock);
}

int palp_cli_mailbox_take(palp_cli_mailbox *mb, uint64_t *seq, palp_local_model *m, uint32_t *server_flags,
                          double *max_force, double *age) {
  if (pthread_mutex_trylock(&mb->lock) != 0) return 0; /* busy: next tick */
  int got = 0;
  if (mb->seq != *seq) {
    *m = mb->model;
    *server_flags = mb->server_flags;
    *max_force = mb->max_force;
    *age = mb->age;
    *seq = mb->seq;
    mb->taken = mb->seq;
    got = 1;
  }
  pthread_mutex_unlock(&mb->lock);
  return got;
}

static int fin3(palp_Vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }
static palp_vec3 vec(palp_Vec3 v) { return (palp_vec3){v.x, v.y, v.z}; }
static palp_vec3 v3add(palp_vec3 a, palp_vec3 b) { return (palp_vec3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static palp_vec3 v3sub(palp_vec3 a, palp_vec3 b) { return (palp_vec3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static palp_vec3 v3scale(palp_vec3 a, double s) { return (palp_vec3){a.x * s, a.y * s, a.z * s}; }
static double len3(palp_vec3 v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

int palp_cli_local_model_from_wire(const palp_LocalModel *in, palp_local_model *out) {
  if (!in || !out) return PALP_EINVAL;
  /* The period is the server's step, 1 / physics rate, and the server steps at 10..10000 Hz
   * (server/config.c), a step retried in halves down to 1/16 of it (src/world.c): a period
   * outside [1/(16 x 10000 Hz), 1 s] is no step. A period of 0 passed, and its crossfade of
   * length 0 put the model's correction on the hand as a step. palp_cli_local_model_fits_rate
   * holds it to the session's own rate. */
  if (!isfinite(in->time) || !(in->period >= PALP_CLI_MODEL_PERIOD_MIN && in->period <= PALP_CLI_MODEL_PERIOD_MAX))
    return PALP_EINVAL;
  if (!fin3(in->device) || !fin3(in->proxy) || !fin3(in->normal) || !fin3(in->force) || !fin3(in->drift) ||
      !fin3(in->point) || !isfinite(in->area) || !isfinite(in->depth))
    return PALP_EINVAL;
  double kmax = 0; /* [N/m] */
  for (int i = 0; i < 9; i++) {
    if (!isfinite(in->stiffness[i]) || fabs(in->stiffness[i]) > 1e6) return PALP_EINVAL;
    kmax = fmax(kmax, fabs(in->stiffness[i]));
  }
  /* K = -dF/dx is symmetric and positive semi-definite (palp.h; palp_contact_stiffness
   * symmetrises it exactly), so its diagonal is >= 0: an asymmetric K (beyond 1e-6 of its
   * largest entry, for any rounding on the way) or a negative diagonal entry (a surface
   * pulling the hand on as it goes in) is no phantom's. A non-negative diagonal does not make
   * K positive semi-definite, and nothing here bounds its size below 1e6 N/m: the renderer
   * projects every K it takes to positive semi-definite and caps it at render.max_stiffness
   * (palp_haptic_limit_stiffness), flagged, rather than refusing a model for round-off. */
  const double ktol = 1e-6 * kmax;
  for (int i = 0; i < 3; i++) {
    if (in->stiffness[4 * i] < -ktol) return PALP_EINVAL;
    for (int j = 0; j < i; j++)
      if (fabs(in->stiffness[3 * i + j] - in->stiffness[3 * j + i]) > ktol) return PALP_EINVAL;
  }
  const palp_vec3 f = vec(in->force), n = vec(in->normal);
  /* Every position the station reads is held to the 10 m the device is: the proxy and the
   * contact point feed the fingertip's depth (R + r - |proxy|) and the coverage, and a forged
   * proxy of 1e40 m, finite, made the finger keyboard's status line 40-odd digits long. The
   * device's depth beneath the proxy is then within 20 m. */
  if (len3(f) > 1e4 || len3(vec(in->device)) > 10.0 || len3(vec(in->proxy)) > 10.0 || len3(vec(in->point)) > 10.0 ||
      fabs(in->depth) > 20.0 || len3(vec(in->drift)) > 100.0)
    return PALP_EINVAL;
  /* The normal is read out of contact too (the passivity controller's n . K n), so it is a
   * unit vector or, out of contact, 0. */
  const double nl = len3(n);
  if (fabs(nl - 1.0) > 1e-3 && (in->in_contact || nl > 1e-12)) return PALP_EINVAL;
  memset(out, 0, sizeof *out);
  out->time = in->time;
  out->period = in->period;
  out->contact = in->in_contact ? 1 : 0;
  out->triangles = in->triangles;
  out->device = vec(in->device);
  out->proxy = vec(in->proxy);
  out->normal = n;
  out->force = f;
  for (int r = 0; r < 3; r++)
    for (int c = 0; c < 3; c++) out->stiffness[r][c] = in->stiffness[3 * r + c];
  out->drift = vec(in->drift);
  out->area = in->area;
  out->depth = in->depth;
  out->point = vec(in->point);
  return 0;
}

int palp_cli_local_model_fits_rate(const palp_local_model *m, double physics_rate_hz) {
  if (!m || !(physics_rate_hz >= PALP_CLI_PHYSICS_RATE_MIN && physics_rate_hz <= PALP_CLI_PHYSICS_RATE_MAX)) return 0;
  /* one step, 1/f, or a retried step's half down to 1/16 of it; 1% for rounding */
  const double step = 1.0 / physics_rate_hz;
  return m->period >= step / 16.0 * 0.99 && m->period <= step * 1.01;
}

long palp_cli_contact_every(double rate_hz, double physics_rate_hz) {
  /* rate / physics rate ticks per contact sample, in long and bounded: a physics rate of
   * 1e-300 Hz made lround overflow, `every` 0 and `tick % every` a SIGFPE in the haptic
   * thread, which died without writing its zero force. */
  const double r = rate_hz / physics_rate_hz;
  if (!(r > 1.0)) return 1; /* NaN, a physics rate at or above the haptic rate */
  if (!(r <= 1e6)) return 1000000;
  const long k = lround(r);
  return k >= 1 ? k : 1;
}

/* ---- the thread ------------------------------------------------------------------------ */

palp_cli_haptic_def palp_cli_haptic_default_def(void) {
  return (palp_cli_haptic_def){.rate_hz = 1000,
                               .physics_rate_hz = 250,
                               .late_threshold = 0.5e-3,
                               .latency_compensation = 1,
                               .max_latency = 0.2,
                               .render = palp_haptic_default_def()};
}

static struct timespec ts_of(int64_t ns) {
  return (struct timespec){.tv_sec = (time_t)(ns / 1000000000), .tv_nsec = (long)(ns % 1000000000)};
}

int palp_cli_haptic_can_mark(unsigned flags) {
  return (flags & PALP_HAPTIC_CONTACT) && !(flags & PALP_HAPTIC_STALE);
}

int palp_cli_outbox_admits(unsigned queued, int release) {
  /* The last PALP_CLI_RELEASE_SAMPLES slots are the lift's: position samples stop short of them.
   * Until 2026-12-07 nothing kept them, and a sender thread stalled for 64 samples' worth (256 ms
   * at 250 Hz, 64 ms at 1 kHz) dropped all three releases: the server kept the finger down, the
   * phantom dented, until the next press. */
  return release ? queued < PALP_CLI_OUTBOX : queued + PALP_CLI_RELEASE_SAMPLES < PALP_CLI_OUTBOX;
}

/* Whether the ring takes a sample now (palp_cli_outbox_admits); the haptic thread alone writes the head. */
static int outbox_room(palp_cli_haptic_loop *l, int release) {
  const unsigned h = atomic_load_explicit(&l->out_head, memory_order_relaxed);
  const unsigned t = atomic_load_explicit(&l->out_tail, memory_order_acquire);
  return palp_cli_outbox_admits(h - t, release);
}

/* The haptic thread never calls DDS: a dds_write takes locks that Cyclone's own
 * (normal-priority) threads hold, and measured in this loop it made 1% of ticks
 * late by more than 0.5 ms (worst 6.8 ms) against 0.18% for the same loop without
 * it. Samples go through a single-producer single-consumer ring to a sender
 * thread; a full ring drops the newest position sample (the next one supersedes
 * it), and keeps room for a lift (palp_cli_outbox_admits). Returns whether the sample
 * was queued (1; also with no writer, nothing to send) or dropped (0). */
static int send_contact(palp_cli_haptic_loop *l, int on, palp_vec3 x, int64_t now_ns) {
  if (l->def.contact_w <= 0) return 1;
  const unsigned h = atomic_load_explicit(&l->out_head, memory_order_relaxed);
  if (!outbox_room(l, !on)) {
    l->stats.contacts_dropped++;
    return 0;
  }
  palp_Contact *m = &l->outbox[h % PALP_CLI_OUTBOX];
  memset(m, 0, sizeof *m);
  m->session_id = l->def.session_id;
  m->finger = (uint8_t)l->def.finger;
  m->mode = on ? palp_CONTACT_FINGER : palp_CONTACT_RELEASE;
  m->vertex = -1;
  m->center = (palp_Vec3){x.x, x.y, x.z};
  m->radius = l->def.radius;
  m->seq = ++l->seq;
  m->source_time_ns = now_ns;
  atomic_store_explicit(&l->out_head, h + 1, memory_order_release);
  sem_post(&l->out_sem);
  return 1;
}

static void *sender_main(void *arg) {
  palp_cli_haptic_loop *l = arg;
  for (;;) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    ts.tv_nsec += 100000000;
    if (ts.tv_nsec >= 1000000000) {
      ts.tv_sec++;
      ts.tv_nsec -= 1000000000;
    }
    sem_timedwait(&l->out_sem, &ts);
    unsigned t = atomic_load_explicit(&l->out_tail, memory_order_relaxed);
    const unsigned h = atomic_load_explicit(&l->out_head, memory_order_acquire);
    for (; t != h; t++) {
      if (dds_write(l->def.contact_w, &l->outbox[t % PALP_CLI_OUTBOX]) == 0) l->sent++;
      else l->write_failed++;
      atomic_store_explicit(&l->out_tail, t + 1, memory_order_release);
    }
    /* Stop only once the haptic thread has finished and everything it queued is out. */
    if (atomic_load(&l->done) && t == atomic_load_explicit(&l->out_head, memory_order_acquire)) break;
  }
  return NULL;
}

/* ---- the per-tick logic, pure (haptic_loop.h) -------------------------------------- */

int palp_cli_haptic_core_init(palp_cli_haptic_core *c, const palp_haptic_def *render, double physics_rate_hz,
                              int latency_compensation, double hold_after, double max_latency) {
  memset(c, 0, sizeof *c);
  if (!(physics_rate_hz > 0) || !(max_latency >= 0)) return PALP_EINVAL;
  const int rc = palp_haptic_init(&c->renderer, render);
  if (rc < 0) return rc;
  /* Crossfades last the session's step, not each model's period: a retried step's model says
   * the last half-step it took (down to 1/16 of the step, src/world.c), and a correction
   * blended over 0.25 ms reached the hand as a step inside one 1 ms tick (2.0 N in one tick
   * for a 1 -> 3 N correction at 250 Hz; 0.5 N a tick over the step). */
  if (!(render->blend_time > 0)) c->renderer.def.blend_time = 1.0 / physics_rate_hz;
  c->compensate = latency_compensation != 0;
  c->hold_after = hold_after > 0 ? hold_after : fmax(2.0 / physics_rate_hz, 0.008);
  c->max_latency = max_latency;
  c->passivity = 1;
  c->max_damping = 20.0;
  return 0;
}

int palp_cli_haptic_core_tick(palp_cli_haptic_core *c, int on, palp_vec3 x, double t, palp_local_model *m,
                              double age, palp_haptic_out *out, palp_vec3 *xr_out) {
  /* A device reading that is not finite (a driver returning NaN once) must not reach the
   * offset, the renderer or the passivity observer: it summed into the offset and the
   * rendered force was 0 until the finger lifted, and the observer's energy went NaN, which
   * switched the controller off. The last good reading stands in for it; before any, the
   * finger counts as lifted (no force). */
  if (!(isfinite(x.x) && isfinite(x.y) && isfinite(x.z))) {
    c->bad_x_ticks++;
    if (c->have_x)
      x = c->x_prev;
    else
      on = 0, x = (palp_vec3){0, 0, 0};
  } else {
    c->have_x = 1;
  }
  const int age_ok = m && age >= 0 && age <= c->max_latency;
  /* Only a model the renderer takes starts a new horizon: a refused one (older, or not
   * valid) restarted it, so the held force was released to follow the device again. */
  const int take = m && palp_haptic_accepts(&c->renderer, m, t);
  if (take) {
    c->x_arrival_t = t;
    /* An age not trusted (unknown, negative, beyond max_latency) is not 0: a model of unknown
     * age had its stiffness followed for the whole horizon, longer than a known-late one. It
     * is held at once. */
    c->model_age = age_ok ? age : c->hold_after;
  }
  /* A model is not extrapolated beyond its horizon: its stiffness is the
   * phantom's response within one physics step, and the device's motion read
   * through it for tens of milliseconds (a 40 ms round trip, a DDS thread
   * starved on a loaded machine) renders a force the phantom never makes
   * (measured: +0.3 N over 30 ms at 20 mm/s, and over a 40 ms round trip a
   * K v dt sawtooth at every model). Once the model's age (on arrival, plus
   * since) passes hold_after the renderer's device point stops (the force is
   * held) and the motion the device makes meanwhile goes into an offset.
   * Models are anchored at the renderer's device point when they arrive, so
   * the offset never reaches the hand: the next model continues from the held
   * force through the renderer's crossfade. The renderer's stale fade-out still
   * ends the force if the server falls silent. Only with latency compensation
   * on (anchoring is what makes the offset harmless). */
  c->holding = on && c->was_on && c->compensate && c->renderer.have &&
               c->model_age + (t - c->x_arrival_t) > c->hold_after;
  if (c->holding) c->offset = v3add(c->offset, v3sub(x, c->x_prev));
  if (!on) c->offset = (palp_vec3){0, 0, 0};
  c->x_prev = x;
  const palp_vec3 xr = v3sub(x, c->offset);
  /* A press after a lift starts from no model: the models taken while lifted (the server's
   * last in-contact ones, a round trip of them) describe the surface where the finger was,
   * unanchored, and the first tick of a new press rendered one at once, with no fade-in
   * (measured: 0 -> 3.0 N in one tick pressing the same spot again 50 ms later, 0 -> 3.6 N
   * with 2 N sideways 10 mm away). The next model then blends in over fade_time, as the
   * first one does. */
  if (on && !c->was_on) palp_haptic_forget(&c->renderer);
  int taken = 0;
  if (m) {
    /* Latency compensation: the model describes the surface when the device was
     * at m->device, which this station sent `age` ago on its own clock. Its
     * stiffness K (the phantom's response within one physics step) read over a
     * 40 ms round trip at 20 mm/s turns 0.8 mm of the hand's motion into force
     * the phantom never pushes with (measured: +70% at the end of a press). The
     * model is therefore re-anchored at the renderer's device point now: its
     * force is rendered as it is (late by the round trip, which no station can
     * avoid) and K only shapes the motion that follows within the horizon.
     * Rejected: extrapolating by drift x age (with jittered arrivals the
     * server's device point moves in bursts, the drift jumps, and drift x 45 ms
     * made a 0.5 N sawtooth). Every model is anchored, whatever its age: one
     * with an age outside [0, max_latency] (or none: no source time) was taken as
     * is, at the server's device point, while the renderer read it at x minus
     * the held motion, so its force was off by K x offset (6 N at 10 mm on
     * 600 N/m) until the next model. Its drift is not extrapolated either: with
     * the age unknown, so is how far the surface has moved. */
    if (c->compensate && on) {
      m->device = xr;
      /* Past its horizon the model is held, and a held device point with the
       * surface drifting on would read as the finger coming off (measured:
       * -0.05 N per 4 ms at 20 mm/s): its drift is not extrapolated either. */
      if (!age_ok || age > c->hold_after) m->drift = (palp_vec3){0, 0, 0};
    }
    taken = palp_haptic_update(&c->renderer, m, t);
  }
  palp_haptic_out o = {.force = {0, 0, 0}, .proxy = x, .requested = 0, .flags = 0};
  if (on) {
    palp_haptic_render(&c->renderer, xr, t, &o);
  }
  /* Passivity observer and controller. A model that arrives a round trip late
   * renders the force of where the hand was, so pressing in feels softer and
   * coming out harder than the phantom is: over press-release cycles the device
   * receives energy the phantom never stored (measured, 40 ms late models, 100
   * cycles at 50 mm/s: 68.5 mJ given back for 29.5 mJ put in). The observer sums
   * the work the rendered force did on the device since the finger touched
   * (E = sum F_{k-1} . (x_k - x_{k-1}), negative while the hand pushes in); while
   * E > 0 the rendering has generated energy, and the controller adds a damper
   * -a v that takes exactly that excess out over the next tick (a = E / (|v|^2
   * dt)), limited to max_damping. Inactive when the rendering is passive (the
   * undelayed test: E stays < 0 in every cycle). */
  if (c->passivity) {
    const double dt = t - c->t_prev;
    if (c->was_on && on && dt > 0) c->energy += c->f_prev.x * (x.x - c->x_prev_pc.x) + c->f_prev.y * (x.y - c->x_prev_pc.y) +
                                                 c->f_prev.z * (x.z - c->x_prev_pc.z);
    const int pushing = (o.flags & PALP_HAPTIC_CONTACT) || len3(o.force) > 0;
    const palp_vec3 v = dt > 0 ? v3scale(v3sub(x, c->x_prev_pc), 1.0 / dt) : (palp_vec3){0, 0, 0}; /* [m/s] */
    if (!pushing) c->energy = 0; /* free: nothing stored */
    /* The damper acts only on a force there is: in free space -a v would be a drag (or a pull)
     * the phantom never makes. */
    int damped = 0;
    if (on && c->was_on && dt > 0 && c->energy > 0 && pushing) {
      const double v2 = v.x * v.x + v.y * v.y + v.z * v.z;
      if (v2 > 1e-12) {
        double a = c->energy / (v2 * dt);
        /* The limit grows with what a late model can generate: a force lagging the
         * hand by tau on a surface of normal stiffness K_n acts like a negative
         * damper -K_n tau, so the controller may need up to that; twice it, with
         * tau the model's age plus one physics period. max_damping alone (fitted to
         * the soft default phantom, K_n ~ 20 N/m) let a ~100x stiffer one give back
         * 2.2x the energy put in with 40 ms late models (test haptic_multirate_stiff). */
        double amax = c->max_damping;
        if (c->renderer.have) {
          const palp_local_model *m = &c->renderer.cur;
          const double n[3] = {m->normal.x, m->normal.y, m->normal.z};
          double kn = 0; /* n . K n [N/m] */
          for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) kn += n[i] * m->stiffness[i][j] * n[j];
          /* The lag of a force that follows the hand through K ends at the horizon: past
           * hold_after the force is held and lags nothing. Uncapped, the time since the
           * last model grew without bound after the server fell silent, and so did
           * the damper's limit. */
          const double since = fmin(fmax(t - c->x_arrival_t, 0.0), c->hold_after);
          const double tau = c->model_age + since + m->period; /* [s] */
          if (kn > 0 && tau > 0 && 2.0 * kn * tau > amax) amax = 2.0 * kn * tau;
        }
        if (a > amax) a = amax;
        /* The controller fades with the models it corrects: a silent server leaves
         * no damper on the hand either (palp_haptic_stale_scale: 1 while fresh). */
        a *= palp_haptic_stale_scale(&c->renderer, t);
        const palp_vec3 f0 = o.force;
        o.force = v3sub(o.force, v3scale(v, a));
        /* A surface pushes; it never pulls. The damper takes energy out along the hand's
         * velocity, and while the hand came out of a stiff phantom that was into the surface,
         * past the contact force: down to -3.1 N on a 2000 N/m plane with 40 ms late models
         * (session 80's review; docs/haptics.md). Its normal part stops at a force of 0 along
         * the renderer's push normal (the contact normal, or the last one while an offset
         * decays after contact is lost), as the renderer's own damper does (src/haptic.c).
         * Cut only in contact (sessions 80-88), the hand leaving the surface was pulled in:
         * -1.11 N on a 2000 N/m plane with models 4 ms late (session 82's review #3). What
         * it cannot take out coming off, the cut below does: it lessens the push itself. */
        o.force = palp_haptic_no_pull(&c->renderer, o.force);
        /* The safe force bounds what reaches the hand, the damper included: pressing
         * in, -a v adds to the force, and with energy left by late or jittered models
         * it took a 0.15 N limit to 0.52 N (test haptic_session on a loaded machine;
         * 2.1 N in haptic_multirate's case). What the limit leaves of the damper is
         * what it dissipated; the observer reads the force as rendered next tick.
         * palp_haptic_clamp also zeroes a force that is not finite (a NaN passed
         * the former `mag > limit`). */
        const double mag = len3(o.force);
        unsigned lim = 0;
        o.force = palp_haptic_clamp(o.force, c->renderer.def.max_force, &lim);
        if (lim) {
          o.flags |= PALP_HAPTIC_LIMITED;
          o.requested = isfinite(mag) ? fmax(o.requested, mag) : INFINITY;
        }
        const palp_vec3 df = v3sub(o.force, f0);
        c->dissipated += -(df.x * v.x + df.y * v.y + df.z * v.z) * dt;
        c->pc_ticks++;
        damped = 1;
      }
    }
    /* Coming off, the push gives back no more than the press put in. While the hand leaves
     * the surface (v . n > 0) the force about to act over the next tick does work F . v dt
     * on the device; if that would take the observer above 0 the push along the normal is
     * lessened, down to 0 N, so that it does not: dF_n = (E + F . v dt) / (v_n dt) [N]. The
     * damper above cannot do it: it takes out the excess of the tick gone, and a late model's
     * force still rises as the hand comes out (it renders where the hand was), so one tick's
     * rise stayed on the hand every tick (the pull above removed, this cut not yet there:
     * ~0.08 N over the last 1.2 mm of each release on the stiff phantom with 20 ms late
     * models, 0.13 mJ, 30% of the cycle's input). Sessions 80-88 took that out by pulling the
     * hand as it left (-1.11 N on a 2000 N/m plane); now nothing pulls, and this only takes
     * a push away: the force stays between 0 and the model's, so the damping limit (which
     * guards a damper that adds force) does not apply. */
    if (on && c->was_on && dt > 0 && pushing) {
      palp_vec3 nc;
      if (palp_haptic_push_normal(&c->renderer, &nc)) {
        const double vn = v.x * nc.x + v.y * nc.y + v.z * nc.z;                /* [m/s] */
        const double fn = o.force.x * nc.x + o.force.y * nc.y + o.force.z * nc.z; /* [N] */
        const double next = c->energy + (o.force.x * v.x + o.force.y * v.y + o.force.z * v.z) * dt; /* [J] */
        if (vn > 0 && fn > 0 && next > 0) {
          const double cut = fmin(next / (vn * dt), fn);
          o.force = v3sub(o.force, v3scale(nc, cut));
          c->dissipated += cut * vn * dt;
          if (!damped) c->pc_ticks++;
        }
      }
    }
    c->f_prev = on ? o.force : (palp_vec3){0, 0, 0};
    c->x_prev_pc = x;
    c->t_prev = t;
  }
  c->was_on = on;
  *out = o;
  if (xr_out) *xr_out = xr;
  return taken;
}

static void *haptic_main(void *arg) {
  palp_cli_haptic_loop *l = arg;
  const palp_cli_haptic_def *d = &l->def;
  palp_cli_haptic_stats *st = &l->stats;
  const int64_t period = (int64_t)(1e9 / d->rate_hz + 0.5);
  /* Every k-th tick goes to the server: the physics step uses one sample per step. */
  const uint64_t every = (uint64_t)palp_cli_contact_every(d->rate_hz, d->physics_rate_hz);
  const int64_t late_ns = (int64_t)(d->late_threshold * 1e9);
  const int64_t t0 = l->t0_ns;
  int64_t next = t0;
  uint64_t mb_seq = 0;
  int was_on = 0, release_left = 0;
  uint32_t model_flags = 0; /* LocalModel.flags of the model being rendered */
  palp_local_model m;
  unsigned counted = 0; /* which of the summary's counts the last tick's force went to (bits as below) */
  for (uint64_t tick = 0; !atomic_load_explicit(&l->stop, memory_order_relaxed); tick++) {
    next += period;
    struct timespec ts = ts_of(next);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
    const int64_t now = palp_dds_now_ns();
    const int64_t late = now - next;
    st->ticks++;
    if (late > PALP_TIMER_FLOOR_STALL_NS) { /* the process was not run: a stall, told apart */
      st->stalls++;
      st->stall_total += (double)late * 1e-9;
      if ((double)late * 1e-9 > st->stall_max) st->stall_max = (double)late * 1e-9;
    } else {
      if (late > late_ns) st->late_ticks++;
      if ((double)late * 1e-9 > st->late_max) st->late_max = (double)late * 1e-9;
    }
    /* A tick more than a period late is not made up in a burst: the device wants
     * the newest force, not a queue of old ones. The missed deadlines are skipped on
     * their grid, as the timer floor skips them (app/timer_floor.c): the next one comes
     * within a period, the loop keeps its half-period offset from the floor's wake-ups,
     * and both cover the same periods, ticks + missed (re-phasing to now lost ~half a
     * tick per late wake-up against the floor: 19-21 of ~2,050 ticks in a loaded test
     * run). Their wake-ups alone differ under load: the loop, preempted in its work,
     * skips deadlines the idle floor does not. */
    int64_t held_over = 0; /* deadlines skipped before this tick (a stall's are not: the process was not run) */
    if (late > period) {
      next += (late / period) * period;
      st->missed += (uint64_t)(late / period);
      if (late <= PALP_TIMER_FLOOR_STALL_NS) held_over = late / period;
    }
    /* Through those skipped deadlines the device held the last tick's force, and its flags: the
     * seconds the summary tells (force limited, outside the valid range, by limit) are periods the
     * device rendered, not ticks run. Counted in ticks alone, a loaded station under-told them
     * against the instructor's review, which counts the server's steps (0.43 s against 0.84 s in a
     * full test run, 2026-12-07). */
    if (held_over) {
      const uint64_t k = (uint64_t)held_over;
      if (counted & 1) st->out_of_range_ticks += k;
      if (counted & 2) st->beyond_validated_ticks += k;
      if (counted & 4) st->strained_ticks += k;
      if (counted & 8) st->limit_ticks += k;
      if (counted & 16) st->gel_ticks += k;
      if (counted & 32) st->limited_ticks += k;
    }
    const double t = (double)(now - t0) * 1e-9;
    if (d->duration > 0 && t >= d->duration) break;
    palp_vec3 x = {0, 0, 0};
    int on = d->in->read_position(d->in->ctx, t, &x);
    if (on == PALP_CLI_INPUT_END) {
      st->ended = 1;
      break;
    }
    if (on < 0) {
      const char *why = d->in->error ? d->in->error(d->in->ctx) : NULL;
      snprintf(st->error, sizeof st->error, "device %s: %s", d->in->name ? d->in->name : "?",
               why ? why : palp_strerror(on));
      st->failed = 1;
      break;
    }
    uint32_t sflags = 0;
    double smax = 0, age = -1;
    const int got = palp_cli_mailbox_take(&l->mailbox, &mb_seq, &m, &sflags, &smax, &age);
    palp_local_model wire; /* as the server sent it: the core re-anchors m at the device point */
    if (got) wire = m;
    palp_haptic_out o;
    palp_vec3 xr;
    const int taken = palp_cli_haptic_core_tick(&l->core, on, x, t, got ? &m : NULL, age, &o, &xr);
    /* A model's flags and the driver's word of it count once the renderer took it, and only then: one
     * refused (older than the one rendered, a relay's reordering, or too far ahead) flagged the force of
     * the model still rendered, counted, and handed the driver an older model (until session 90, found
     * by review). The safe force is the station's and the phantom's (palp_cli_haptic_start), not each
     * model's max_force: lowered to any model's, one sample of 1e-9 N left the device without force for
     * the rest of the session. */
    if (got && taken > 0) {
      model_flags = sflags;
      if (d->in->model) d->in->model(d->in->ctx, &wire);
      if (sflags & palp_LM_FORCE_LIMIT) st->server_limited_models++;
      if (sflags & PALP_DDS_LM_OUTSIDE) st->out_of_range_models++;
    }
    if (!fin3((palp_Vec3){x.x, x.y, x.z})) { /* the core rendered from the last good reading, or as lifted */
      x = l->core.x_prev;
      if (!l->core.have_x) on = 0;
    }
    /* Nothing but a finite force within the limit reaches the device (the core limits
     * it: this is the last word before the hardware). */
    if (!fin3((palp_Vec3){o.force.x, o.force.y, o.force.z})) o.force = (palp_vec3){0, 0, 0};
    /* The server's word on the model's validity travels with the force it gave, and
     * only while it is rendered: a lifted finger or a fading model says nothing. */
    if (on && (model_flags & PALP_DDS_LM_OUTSIDE) &&
        !(o.flags & (PALP_HAPTIC_STALE | PALP_HAPTIC_NO_MODEL)))
      o.flags |= PALP_CLI_FORCE_OUT_OF_RANGE;
    counted = 0;
    if (o.flags & PALP_CLI_FORCE_OUT_OF_RANGE) {
      counted |= 1;
      if (model_flags & palp_LM_BEYOND_VALIDATED) counted |= 2;
      if (model_flags & palp_LM_LARGE_STRAIN) counted |= 4;
      if (model_flags & (palp_LM_OUT_OF_RANGE & ~palp_LM_LARGE_STRAIN)) counted |= 8;
      if (model_flags & palp_LM_GEL_LAW_RANGE) counted |= 16;
    }
    if (o.flags & PALP_HAPTIC_LIMITED) counted |= 32;
    st->out_of_range_ticks += counted & 1;
    st->beyond_validated_ticks += (counted >> 1) & 1;
    st->strained_ticks += (counted >> 2) & 1;
    st->limit_ticks += (counted >> 3) & 1;
    st->gel_ticks += (counted >> 4) & 1;
    if (taken > 0) st->models++;
    if (l->core.holding) st->held_ticks++;
    d->in->write_force(d->in->ctx, o.force, o.flags);
    const double fm = len3(o.force);
    if (fm > st->peak_force) st->peak_force = fm;
    if (o.requested > st->peak_requested) st->peak_requested = o.requested;
    st->limited_ticks += (counted >> 5) & 1;
    if (o.flags & PALP_HAPTIC_STALE) st->stale_ticks++;
    if (o.flags & PALP_HAPTIC_CONTACT) st->contact_ticks++;
    /* To the server at the physics rate; a lift is sent at once and repeated on
     * the next ticks (best-effort: one lost sample must not leave the finger down). */
    if (on && (tick % every == 0 || !was_on)) send_contact(l, 1, x, now);
    if (!on && was_on) release_left = PALP_CLI_RELEASE_SAMPLES;
    if (on) release_left = 0; /* pressed again: the position samples say so */
    /* a release the ring could not take is tried again next tick, not counted as sent */
    if (!on && release_left > 0 && send_contact(l, 0, x, now)) release_left--;
    was_on = on;
    if (d->trace && st->trace_len < d->trace_cap)
      d->trace[st->trace_len++] = (palp_cli_haptic_sample){
          .t = t, .late = (double)late * 1e-9, .x = x, .f = o.force, .requested = o.requested, .flags = o.flags,
          .on = on};
    /* Try-lock: a reader preempted while holding the lock must not stall the tick
     * (priority inversion); the view is then one tick older. */
    if (pthread_mutex_trylock(&l->view_lock) == 0) {
    l->view = (palp_cli_haptic_view){.t = t, .x = x, .xr = xr, .proxy = o.proxy, .force = o.force, .requested = o.requested,
                                     /* the server's: device beneath the proxy along the normal */
                                     .depth = (o.flags & PALP_HAPTIC_CONTACT) ? l->core.renderer.cur.depth : 0,
                                     .flags = o.flags, .on = on,
                                     .point = l->core.renderer.cur.point,
                                     .model_contact = palp_cli_haptic_can_mark(o.flags),
                                     .model_time = l->core.renderer.cur.time,
                                     .out_of_range_ticks = st->out_of_range_ticks,
                                     .beyond_validated_ticks = st->beyond_validated_ticks,
                                     .strained_ticks = st->strained_ticks,
                                     .limit_ticks = st->limit_ticks,
                                     .gel_ticks = st->gel_ticks};
    pthread_mutex_unlock(&l->view_lock);
    }
  }
  /* The finger leaves with the loop: lifted now, or lifted lately with releases the ring has not yet
   * taken (until session 90 only a finger still down was released here: a lift in the last ticks whose
   * releases a full ring refused left the finger down at the server until the LEAVE; found by review).
   * A full ring is given up to 50 ms to drain. */
  if (was_on || release_left > 0) {
    int queued = 0;
    for (int tries = 0; queued < PALP_CLI_RELEASE_SAMPLES && tries < 50; tries++) {
      /* waiting for room is not a drop: only a release given up on is counted (send_contact) */
      if (l->def.contact_w > 0 && !outbox_room(l, 1) && tries < 49) nanosleep(&(struct timespec){0, 1000000}, NULL);
      else queued += send_contact(l, 0, (palp_vec3){0, 0, 0}, palp_dds_now_ns());
    }
  }
  d->in->write_force(d->in->ctx, (palp_vec3){0, 0, 0}, 0); /* leave the hand free */
  st->max_force = l->core.renderer.def.max_force;
  st->stiffness_limited_models = l->core.renderer.stiffness_limited;
  st->passivity_ticks = l->core.pc_ticks;
  st->passivity_dissipated = l->core.dissipated;
  palp_timer_floor_request_stop(&l->floor); /* it measures beside the loop, not after it */
  atomic_store(&l->done, 1);
  return NULL;
}

int palp_cli_haptic_start(palp_cli_haptic_loop *l, const palp_cli_haptic_def *def, char *err, size_t errlen) {
  memset(l, 0, sizeof *l);
  if (!def || !def->in || !def->in->read_position || !def->in->write_force) {
    snprintf(err, errlen, "haptic loop: the input is not a position-driven device (no read_position/write_force)");
    return PALP_EINVAL;
  }
  if (!(def->rate_hz >= 10 && def->rate_hz <= 10000) ||
      !(def->physics_rate_hz >= PALP_CLI_PHYSICS_RATE_MIN && def->physics_rate_hz <= PALP_CLI_PHYSICS_RATE_MAX) ||
      def->finger < 0 || def->finger >= PALP_CLI_MAX_FINGERS || !(def->late_threshold > 0)) {
    snprintf(err, errlen, "haptic loop: rate %g Hz (10..10000), the server's physics rate %g Hz (%g..%g) or finger %d "
             "invalid", def->rate_hz, def->physics_rate_hz, PALP_CLI_PHYSICS_RATE_MIN, PALP_CLI_PHYSICS_RATE_MAX,
             def->finger);
    return PALP_EINVAL;
  }
  l->def = *def;
  /* The safe force is the smaller of the station's and the phantom's limits (the
   * catalogue's max_force, which the server also reports in every model). */
  if (def->phantom_max_force > 0 && isfinite(def->phantom_max_force) &&
      def->phantom_max_force < l->def.render.max_force)
    l->def.render.max_force = def->phantom_max_force;
  if (!(l->def.radius > 0)) l->def.radius = def->in->finger_radius > 0 ? def->in->finger_radius : 0.008;
  int rc = palp_cli_haptic_core_init(&l->core, &l->def.render, def->physics_rate_hz, def->latency_compensation,
                                     def->hold_after, def->max_latency);
  if (rc < 0) {
    snprintf(err, errlen, "haptic loop: renderer parameters invalid: %s", palp_strerror(rc));
    return rc;
  }
  l->stats.max_force = l->core.renderer.def.max_force;
  /* each made thing undone if a later one cannot be made (2026-12-07: they were left) */
  const int mb_ok = palp_cli_mailbox_init(&l->mailbox) == 0;
  const int view_ok = mb_ok && pthread_mutex_init(&l->view_lock, NULL) == 0;
  const int sem_ok = view_ok && sem_init(&l->out_sem, 0, 0) == 0;
  if (!sem_ok) {
    if (view_ok) pthread_mutex_destroy(&l->view_lock);
    if (mb_ok) palp_cli_mailbox_destroy(&l->mailbox);
    snprintf(err, errlen, "haptic loop: cannot create its locks");
    return PALP_ENOMEM;
  }
  /* A tick preempted by a compiler is a force the hand feels late: a real-time class
   * keeps the haptic thread ahead of ordinary work when allowed. */
  l->t0_ns = palp_dds_now_ns();
  if (palp_rt_thread_start(&l->thread, def->rt_priority, haptic_main, l, &l->stats.rt_ok) < 0) {
    snprintf(err, errlen, "haptic loop: cannot start the thread");
    sem_destroy(&l->out_sem);
    palp_cli_mailbox_destroy(&l->mailbox);
    pthread_mutex_destroy(&l->view_lock);
    return PALP_ENOMEM;
  }
  l->started = 1;
  /* The floor is a measurement: without it the loop runs the same, so a floor thread
   * that cannot start leaves floor_ticks at 0 and the station says nothing of it. */
  if (def->timer_floor) { /* the haptic thread's deadlines half a period later: the two never wake together */
    const int64_t period = (int64_t)(1e9 / def->rate_hz + 0.5);
    palp_timer_floor_start(&l->floor, period, (int64_t)(def->late_threshold * 1e9), l->t0_ns + period / 2,
                           l->stats.rt_ok ? def->rt_priority : 0);
  }
  if (def->contact_w > 0) {
    if (pthread_create(&l->sender, NULL, sender_main, l) != 0) {
      atomic_store(&l->stop, 1);
      pthread_join(l->thread, NULL);
      palp_timer_floor_stop(&l->floor);
      l->started = 0;
      sem_destroy(&l->out_sem);
      palp_cli_mailbox_destroy(&l->mailbox);
      pthread_mutex_destroy(&l->view_lock);
      snprintf(err, errlen, "haptic loop: cannot start the sender thread");
      return PALP_ENOMEM;
    }
    l->sender_started = 1;
  }
  return 0;
}

void palp_cli_haptic_request_stop(palp_cli_haptic_loop *l) { atomic_store(&l->stop, 1); }
int palp_cli_haptic_done(palp_cli_haptic_loop *l) { return atomic_load(&l->done); }

void palp_cli_haptic_join(palp_cli_haptic_loop *l, palp_cli_haptic_stats *out) {
  if (l->started) {
    atomic_store(&l->stop, 1);
    pthread_join(l->thread, NULL);
    palp_timer_floor_stop(&l->floor);
    l->stats.floor_ticks = l->floor.ticks, l->stats.floor_late_ticks = l->floor.late_ticks;
    l->stats.floor_missed = l->floor.missed;
    l->stats.floor_late_max = l->floor.late_max;
    if (l->sender_started) {
      sem_post(&l->out_sem);
      pthread_join(l->sender, NULL);
      l->sender_started = 0;
    }
    l->stats.contacts_sent = l->sent;
    l->stats.contacts_failed = l->write_failed;
    l->stats.bad_x_ticks = l->core.bad_x_ticks;
    sem_destroy(&l->out_sem);
    l->started = 0;
    palp_cli_mailbox_destroy(&l->mailbox);
    pthread_mutex_destroy(&l->view_lock);
  }
  if (out) *out = l->stats;
}

void palp_cli_haptic_get_view(palp_cli_haptic_loop *l, palp_cli_haptic_view *out) {
  pthread_mutex_lock(&l->view_lock);
  *out = l->view;
  pthread_mutex_unlock(&l->view_lock);
}

int palp_cli_haptic_feed(palp_cli_haptic_loop *l, palp_cli_station *st, uint64_t *bad, double *latency_us) {
  const dds_entity_t reader = st->local_model_r;
  int taken = 0;
  if (latency_us) *latency_us = NAN;
  for (;;) {
    void *ptr[1] = {NULL};
    dds_sample_info_t info;
    if (dds_take(reader, ptr, &info, 1, 1) <= 0) break;
    const palp_LocalModel *w = ptr[0];
    /* what the hand feels comes from the session's server alone (station.h, palp_cli_server_bind) */
    if (info.valid_data && w->finger == (uint8_t)l->def.finger && w->session_id == l->def.session_id &&
        palp_cli_station_from_server(st, reader, &info)) {
      palp_local_model m;
      if (palp_cli_local_model_from_wire(w, &m) == 0 && palp_cli_local_model_fits_rate(&m, l->def.physics_rate_hz) &&
          isfinite(w->max_force) && w->max_force >= 0) {
        /* The model's age: it describes the surface when the device was at
         * m.device, which this station sent at contact_source_time_ns on its own
         * clock. The haptic thread re-anchors it with that (core_tick). */
        const int64_t now = palp_dds_now_ns();
        const double age = w->contact_source_time_ns > 0 ? (double)(now - w->contact_source_time_ns) * 1e-9 : -1;
        palp_cli_mailbox_put(&l->mailbox, &m, w->flags, w->max_force, age);
        if (l->def.on_model) l->def.on_model(l->def.on_model_ctx, &m, w->frame);
        if (latency_us && age > 0) *latency_us = age * 1e6;
        taken++;
      } else if (bad) {
        ++*bad;
      }
    }
    dds_return_loan(reader, ptr, 1);
  }
  return taken;
}
