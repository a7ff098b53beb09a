/*
 * trainee.h - scripted trainees (issue 13, docs/assessment.md "Scripted trainees"): a
 * MammaCare expert (vertical strips, three pressures at every spot, marks a lump where
 * the force at equal depth rises above its surroundings) and a novice (a few light
 * presses at random places, one guessed mark).
 *
 * Trainees know where their hand is (the device point they command) and what they feel
 * (the force after each physics step), never where the lesions are. They drive a hand
 * through one callback, so the same script runs on an in-process world
 * (tests/assess/recorder.h) and on a station over DDS (input_trainee.c). Pure: no DDS.
 */
#ifndef PALP_CLI_TRAINEE_H
#define PALP_CLI_TRAINEE_H

#include "palp.h"

/* The hand: one physics step with the device at `dev` [m]; the callback returns the
 * force felt after it [N] and the world time [s], and 0, or < 0 to abort the script. */
typedef struct palp_cli_hand {
  void *ctx;
  int (*step)(void *ctx, palp_vec3 dev, palp_vec3 *force, double *t);
  double dt;         /* physics step [s] */
  double R, r;       /* dome and fingertip radii [m] */
  /* state */
  palp_vec3 device;  /* last commanded [m] */
  palp_vec3 force;   /* felt after the last step [N] */
  double t;          /* world time after the last step [s] */
  long steps;
  int failed;
  /* Set by a step callback whose force comes from elsewhere (a server's local model):
   * the device point and the server's time that force belongs to. A hold then counts
   * the server's physics time at the held point, not the hand's own steps, so a press
   * is read after the same simulated hold however late the models come. */
  int felt_valid;
  palp_vec3 felt_device; /* [m] */
  double felt_time;      /* [s] */
} palp_cli_hand;

void palp_cli_hand_init(palp_cli_hand *h, void *ctx, int (*step)(void *, palp_vec3, palp_vec3 *, double *), double dt,
                        double R, double r, palp_vec3 start);
void palp_cli_hand_step(palp_cli_hand *h, palp_vec3 dev);
/* Straight line at speed [m/s]; hold still for seconds. */
void palp_cli_hand_move_to(palp_cli_hand *h, palp_vec3 to, double speed);
void palp_cli_hand_hold(palp_cli_hand *h, double seconds);
/* The device `depth` [m] below the rest surface along the unit normal n, never below
 * the table the phantom stands on (near the rim the hand presses sideways). */
palp_vec3 palp_cli_hand_device_at(const palp_cli_hand *h, palp_vec3 n, double depth);

/* ---- the expert ----------------------------------------------------------------- */
typedef struct palp_cli_expert_spot {
  palp_vec3 n;      /* unit normal (the spot's direction from the dome's centre) */
  double t;         /* when pressed [s] */
  double f_medium;  /* force held at the medium depth [N] */
  double f_deep;    /* force held at the deep depth [N] */
  int free;         /* the deep press went along the normal, clear of the table */
} palp_cli_expert_spot;

typedef struct palp_cli_expert_cfg {
  double spacing;                   /* [m] between spots and strips */
  double d_light, d_medium, d_deep; /* device depths [m] */
  double press_speed, glide_speed;  /* [m/s] */
  double hold;                      /* [s] at each depth */
  double min_nz;                    /* spots down to this normal z (rim margin) */
  double keep_force;                /* light touch kept while rising and gliding [N] */
  double patience;                  /* longest wait for the dent to recover to the light depth [s] */
  double threshold;                 /* a rise above this over the fitted surroundings is a lump [-] */
  double cluster;                   /* spots closer than this are one lump [m] */
} palp_cli_expert_cfg;
palp_cli_expert_cfg palp_cli_expert_default(void);

/* Runs the exam; returns the spots (malloc'd, free()) and their count in *count. */
palp_cli_expert_spot *palp_cli_expert_exam(palp_cli_hand *h, const palp_cli_expert_cfg *cfg, int *count);
/* A free spot's medium-depth force over a quadratic fitted to the free spots between
 * r_in and r_out away: F / c0 - 1, or NAN with fewer than 10 neighbours or fewer than 2
 * beyond r_out / 2 on any side (+-x, +-y of the tangent plane: the spot is not surrounded). */
double palp_cli_expert_rise(const palp_cli_hand *h, const palp_cli_expert_spot *sp, int n, int i, double r_in,
                            double r_out);
/* Every spot's rise as the lump rule sees it: palp_cli_expert_rise (12-28 mm), then again
 * with the spots that rose above half the threshold left out of the others' surroundings.
 * NAN for a spot not free or without enough surroundings. Returns 0 or PALP_ENOMEM. */
int palp_cli_expert_rises(const palp_cli_hand *h, const palp_cli_expert_spot *sp, int n, const palp_cli_expert_cfg *cfg,
                          double *rise);
/* The strongest spot of each cluster rising above cfg->threshold: writes up to cap
 * surface points [m] and times, returns the count; the largest rise in *max_rise. */
int palp_cli_expert_lumps(const palp_cli_hand *h, const palp_cli_expert_spot *sp, int n, const palp_cli_expert_cfg *cfg,
                          palp_vec3 *points, double *times, int cap, double *max_rise);

/* As palp_cli_expert_lumps, but a clinician's way: every suspected lump is palpated
 * once more (from the spot before it, as in the exam) and keeps the smaller of its two
 * medium-depth forces before the lumps are chosen again; at most 12 re-checks, their
 * number in *rechecked. Updates sp[].f_medium of the spots re-checked. Moves the hand. */
int palp_cli_expert_lumps_confirmed(palp_cli_hand *h, palp_cli_expert_spot *sp, int n, const palp_cli_expert_cfg *cfg,
                                    palp_vec3 *points, double *times, int cap, double *max_rise, int *rechecked);

/* ---- the novice ------------------------------------------------------------------ */
/* `presses` presses to `depth` [m] at random places (polar < 60 deg, seeded), travelling
 * in the air 5 mm above the dome; *last_press = the surface point of the last one.
 * on_last_hold (optional) is called once while the last press is held (a station
 * presses its button there). */
void palp_cli_novice_exam(palp_cli_hand *h, int presses, double depth, unsigned seed, palp_vec3 *last_press,
                          void (*on_last_hold)(void *arg), void *arg);

#endif
