/*
 * palp_haptic.h - the station's haptic renderer: a 1 kHz loop's force from the
 * server's local contact models (multi-rate rendering, docs/haptics.md).
 *
 * The server steps the phantom at its own physics rate and publishes, per finger,
 * a palp_local_model (palp.h). Between models the station evaluates the newest one
 * at the device's current position every haptic tick; when a new model arrives the
 * force crossfades from the old model's prediction to the new one's over one
 * physics period, so a correction never reaches the hand as a step; the first model, and
 * the first after a stale fade-out, fade in as a gain on the model force that rises from the
 * share the hand felt to 1 over fade_time, however many models arrive meanwhile (a gain on a
 * unilateral force stays unilateral). The sum never pulls: its component into the surface
 * (against the current contact normal, or the last one while an offset decays) is cut. A model that
 * is late is extrapolated for at most max_extrapolation, then held; a model older
 * than stale_time fades the force out over fade_time (a vanished server must not
 * leave a force on the hand). Each model's force is limited to max_force before it is
 * blended or faded, so a fade or crossfade of a model asking for more than the limit
 * still ramps the rendered force over its whole length; the sum (damper included) is
 * limited again, and the caller is told when a limit acted (the station shows it). A damper on the device velocity along
 * the contact normal, active only in contact, keeps the loop passive on a real
 * device.
 *
 * Pure and allocation-free: no threads, clocks or I/O here; the caller passes its
 * station time. Units SI.
 */
#ifndef PALP_HAPTIC_H
#define PALP_HAPTIC_H

#include "palp.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct palp_haptic_def {
  double max_force;         /* safe force limit [N], default 10 */
  double damping;           /* contact damping at the device [N s/m], default 2 */
  double blend_time;        /* crossfade between models [s]; 0 = the model's period */
  double max_extrapolation; /* drift extrapolation limit [s], default 0.010 */
  double stale_time;        /* no model for this long: fade out [s], default 0.25 */
  double fade_time;         /* [s], default 0.1 */
  double max_stiffness;     /* largest eigenvalue of K rendered [N/m], default 4000: twice the coupling
                               k_c (2000 N/m) that bounds the server's K (docs/haptics.md); a model's K
                               is also projected to positive semi-definite (palp_haptic_limit_stiffness) */
} palp_haptic_def;

palp_haptic_def palp_haptic_default_def(void);
/* The share of a force still given age [s] after its newest model (or sample): 1 up to stale_time,
 * down to 0 over fade_time. The renderer's stale fade, and the force-mode driver path's (client/main.c). */
double palp_haptic_fade(const palp_haptic_def *d, double age);

enum {
  PALP_HAPTIC_LIMITED = 1u << 0, /* the force was limited to max_force, or is rendered from a model whose
                                    K was limited (max_stiffness, or indefinite) */
  PALP_HAPTIC_STALE = 1u << 1,   /* no recent model: fading out */
  PALP_HAPTIC_CONTACT = 1u << 2, /* the finger touches the surface */
  PALP_HAPTIC_NO_MODEL = 1u << 3 /* no model yet: zero force */
};

typedef struct palp_haptic_out {
  palp_vec3 force;     /* force to render on the device [N] */
  palp_vec3 proxy;     /* fingertip on the surface, for display [m] */
  double requested;    /* |force| before the limit [N] */
  unsigned flags;      /* PALP_HAPTIC_* */
} palp_haptic_out;

typedef struct palp_haptic {
  palp_haptic_def def;
  palp_local_model cur, prev;
  double cur_at;          /* station time the current model arrived [s] */
  double blend_len;       /* the current arrival's crossfade [s]: blend_time or the model's period */
  double onset_at;        /* station time the running onset began [s] */
  double onset_from;      /* the onset gain's start, the share the hand felt [0, 1]; 1
                             before any onset (the gain is 1 too once fade_time has passed
                             since onset_at) */
  palp_vec3 last_normal;  /* unit contact normal of the last model in contact (0 before any) */
  int have;               /* models received: 0, 1 or 2 (= both valid) */
  palp_vec3 last_x;       /* device point of the last render [m] */
  double last_t;          /* [s] */
  int rendered;
  int cur_stiffness_limited; /* the current model's K was limited (palp_haptic_limit_stiffness) */
  unsigned long long models, limited_ticks;
  unsigned long long stiffness_limited; /* models taken whose K was limited */
} palp_haptic;

int palp_haptic_init(palp_haptic *h, const palp_haptic_def *def);
/* Forgets the models (as before the first): the next one taken blends in over fade_time
 * from the force last rendered. The parameters and counts stay. */
void palp_haptic_forget(palp_haptic *h);
/* A new model arrived at station time now [s]. Models older than the current one
 * (by their time), or ahead of it by more than the station time since it came plus
 * stale_time, are ignored; returns 1 if taken, 0 if ignored, < 0 on error. Every model
 * is limited to max_force before it is blended or faded. */
int palp_haptic_update(palp_haptic *h, const palp_local_model *m, double now);
/* 1 if palp_haptic_update(h, m, now) would take m, else 0 (nothing changes). */
int palp_haptic_accepts(const palp_haptic *h, const palp_local_model *m, double now);
/* The share of the model force left at now [0, 1]: 1 while models are fresh, down to 0
 * over fade_time once the newest is older than stale_time; 0 before any model. */
double palp_haptic_stale_scale(const palp_haptic *h, double now);
/* The unit normal the rendered force never pulls against (*n): the current model's contact
 * normal, or else the last in-contact model's while an offset of it may still decay.
 * Returns 0 (n untouched) if there is none: before any model in contact. */
int palp_haptic_push_normal(const palp_haptic *h, palp_vec3 *n);
/* f without its component into the surface along that normal (unchanged if there is none): a
 * surface pushes, never pulls. */
palp_vec3 palp_haptic_no_pull(const palp_haptic *h, palp_vec3 f);
/* f limited to a magnitude of max_force [N] (sets PALP_HAPTIC_LIMITED in *flags, if not
 * NULL, when it acted); a non-finite f gives 0 N, flagged. */
palp_vec3 palp_haptic_clamp(palp_vec3 f, double max_force, unsigned *flags);
/* K (symmetric 3x3 [N/m]) made renderable, in place: projected to positive semi-definite
 * (negative eigenvalues to 0) and each eigenvalue capped at max_stiffness. Returns 1 if that
 * changed K beyond round-off (an eigenvalue above the cap, or one below -1e-6 of the largest:
 * a surface that would push the hand on along its motion), else 0. palp_haptic_update applies
 * it to every model it takes and flags its force PALP_HAPTIC_LIMITED when it returned 1. */
int palp_haptic_limit_stiffness(double K[3][3], double max_stiffness);
/* The force for device point x [m] at station time now [s]. */
void palp_haptic_render(palp_haptic *h, palp_vec3 x, double now, palp_haptic_out *out);

#ifdef __cplusplus
}
#endif
#endif
