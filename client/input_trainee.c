/* input_trainee.c - the scripted trainees (trainee.c) as a position-driven device:
 * --input sim:expert[,...] and sim:novice[,...] (issue 13, docs/assessment.md).
 *
 * The script runs on a thread of its own and moves the hand one physics step at a
 * time in real time (an absolute clock at the phantom's physics period); the station's
 * haptic thread reads the hand's point (read_position) and gives back the force it
 * renders from the server's local models (write_force): what the trainee feels. A lump
 * is marked the way a trainee does it: the fingertip goes back to the spot, touches
 * it lightly and presses the device's button (the station sends LocalModel.point). */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "input.h"
#include "input_trainee.h"

#define MAX_LUMPS 16

typedef struct tsrc {
  palp_cli_trainee_def def;
  double R;
  pthread_t thread;
  int started;
  pthread_mutex_t mu;
  palp_vec3 x;          /* [mu] the hand's device point */
  palp_vec3 force;      /* [mu] the phantom's force in the server's newest local model */
  palp_vec3 model_device; /* [mu] the device point that model's step used */
  double model_time;      /* [mu] its world time [s] */
  int have_model;         /* [mu] */
  atomic_int done, stop, button;
  struct timespec next; /* script thread: its clock */
  palp_cli_hand hand;
  char err[160];
  /* results, for the station's printout */
  int spots, lumps;
  double max_rise;
  int rechecked;      /* suspected lumps palpated a second time */
  long late_restarts; /* script steps that restarted its clock (it was held > 2 steps) */
} tsrc;

static void ts_add(struct timespec *t, double s) {
  t->tv_nsec += (long)(s * 1e9);
  while (t->tv_nsec >= 1000000000L) t->tv_nsec -= 1000000000L, t->tv_sec++;
}

/* One physics step in real time: the point is published, the clock advances by dt,
 * and what the station rendered then is what the hand felt. */
static int hand_step(void *ctx, palp_vec3 dev, palp_vec3 *force, double *t) {
  tsrc *s = ctx;
  if (atomic_load(&s->stop)) return PALP_EINVAL;
  pthread_mutex_lock(&s->mu);
  s->x = dev;
  pthread_mutex_unlock(&s->mu);
  ts_add(&s->next, s->hand.dt);
  /* Late by more than two steps (a loaded machine held this thread): start the
   * clock again from now rather than catch up. Catching up ran a burst of steps
   * with no sleep between them, so the point jumped ahead of the server's models
   * and the force read back was that of a place the hand had already left. */
  struct timespec now;
  clock_gettime(CLOCK_MONOTONIC, &now);
  const double behind = (double)(now.tv_sec - s->next.tv_sec) + 1e-9 * (double)(now.tv_nsec - s->next.tv_nsec);
  if (behind > 2.0 * s->hand.dt) {
    s->next = now;
    s->late_restarts++;
  }
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &s->next, NULL) != 0) {
  }
  pthread_mutex_lock(&s->mu);
  *force = s->force;
  s->hand.felt_valid = s->have_model;
  s->hand.felt_device = s->model_device;
  s->hand.felt_time = s->model_time;
  pthread_mutex_unlock(&s->mu);
  *t = s->hand.t + s->hand.dt;
  return 0;
}

static void press_button(void *arg) {
  tsrc *s = arg;
  atomic_store(&s->button, PALP_CLI_BUTTON_MARK);
}

static void *script(void *arg) {
  tsrc *s = arg;
  palp_cli_hand *h = &s->hand;
  clock_gettime(CLOCK_MONOTONIC, &s->next);
  if (s->def.kind == PALP_CLI_TRAINEE_EXPERT) {
    int n = 0;
    palp_cli_expert_spot *sp = palp_cli_expert_exam(h, &s->def.expert, &n);
    palp_vec3 lump[MAX_LUMPS];
    s->spots = n;
    s->lumps = sp && !h->failed ? palp_cli_expert_lumps_confirmed(h, sp, n, &s->def.expert, lump, NULL, MAX_LUMPS,
                                                                  &s->max_rise, &s->rechecked)
                                : 0;
    if (s->lumps < 0) s->lumps = 0;
    free(sp);
    /* Mark each lump: lift 5 mm, go over the spot, touch it lightly, press the button. */
    for (int i = 0; i < s->lumps && !h->failed; i++) {
      const double l = sqrt(lump[i].x * lump[i].x + lump[i].y * lump[i].y + lump[i].z * lump[i].z);
      const palp_vec3 n = {lump[i].x / l, lump[i].y / l, lump[i].z / l};
      const palp_vec3 up = h->device;
      const double lu = sqrt(up.x * up.x + up.y * up.y + up.z * up.z);
      palp_cli_hand_move_to(h, (palp_vec3){up.x / lu * (s->R + h->r + 0.005), up.y / lu * (s->R + h->r + 0.005),
                                           up.z / lu * (s->R + h->r + 0.005)}, 0.05);
      palp_cli_hand_move_to(h, palp_cli_hand_device_at(h, n, -0.005), 0.1);
      palp_cli_hand_move_to(h, palp_cli_hand_device_at(h, n, s->def.expert.d_light), 0.03);
      palp_cli_hand_hold(h, 0.3);
      press_button(s);
      palp_cli_hand_hold(h, 0.7); /* the station sends it and hears the answer */
    }
  } else {
    palp_vec3 last;
    palp_cli_novice_exam(h, s->def.presses, s->def.depth, s->def.seed, &last, press_button, s);
    s->lumps = 1;
    palp_cli_hand_hold(h, 0.7);
  }
  if (h->failed && !atomic_load(&s->stop)) snprintf(s->err, sizeof s->err, "scripted trainee: the hand failed");
  atomic_store(&s->done, 1);
  return NULL;
}

static int t_open(void *ctx, double R) {
  tsrc *s = ctx;
  if (!(R > 0)) return PALP_EINVAL;
  s->R = R;
  const palp_vec3 start = {0, 0, R + s->def.radius + 0.005};
  s->x = start;
  palp_cli_hand_init(&s->hand, s, hand_step, 1.0 / s->def.physics_rate_hz, R, s->def.radius, start);
  if (pthread_create(&s->thread, NULL, script, s) != 0) return PALP_ENOMEM;
  s->started = 1;
  return 0;
}

static int t_read(void *ctx, double t, palp_vec3 *x) {
  (void)t;
  tsrc *s = ctx;
  if (atomic_load(&s->done)) return s->err[0] ? PALP_EINVAL : PALP_CLI_INPUT_END;
  pthread_mutex_lock(&s->mu);
  *x = s->x;
  pthread_mutex_unlock(&s->mu);
  return 1;
}

static void t_write(void *ctx, palp_vec3 f, unsigned flags) {
  (void)ctx, (void)f, (void)flags; /* the script reads the server's force (t_model), not the rendered one */
}

/* What the script feels: the phantom's force after the server's step, as the in-process
 * world gives it. The station's rendered force (extrapolated between 250 Hz models,
 * limited to the safe force) spiked to 46 N under late ticks on a loaded machine, and
 * the lump rule compares forces to 12 %. */
static void t_model(void *ctx, const palp_local_model *m) {
  tsrc *s = ctx;
  pthread_mutex_lock(&s->mu);
  s->force = m->force;
  s->model_device = m->device;
  s->model_time = m->time;
  s->have_model = 1;
  pthread_mutex_unlock(&s->mu);
}

static int t_button(void *ctx) {
  tsrc *s = ctx;
  return atomic_exchange(&s->button, 0);
}

static const char *t_error(void *ctx) {
  tsrc *s = ctx;
  return s->err[0] ? s->err : NULL;
}

static void t_close(void *ctx) {
  tsrc *s = ctx;
  atomic_store(&s->stop, 1);
  if (s->started) pthread_join(s->thread, NULL);
  printf("[scripted %s] %ld steps of %.1f ms (%.1f s), clock restarted %ld times after a late step%s%s\n",
         s->def.kind == PALP_CLI_TRAINEE_EXPERT ? "expert" : "novice", s->hand.steps, s->hand.dt * 1e3,
         (double)s->hand.steps * s->hand.dt, s->late_restarts, s->err[0] ? ": " : "", s->err);
  if (s->def.kind == PALP_CLI_TRAINEE_EXPERT)
    printf("[scripted expert] %d spots, %d suspected lump%s re-palpated, %d lump%s marked (largest rise over the "
           "surroundings at first %+.1f%%)\n", s->spots, s->rechecked, s->rechecked == 1 ? "" : "s", s->lumps,
           s->lumps == 1 ? "" : "s", 100 * s->max_rise);
  pthread_mutex_destroy(&s->mu);
  free(s);
}

palp_cli_trainee_def palp_cli_trainee_default_def(palp_cli_trainee_kind kind) {
  return (palp_cli_trainee_def){.kind = kind, .expert = palp_cli_expert_default(), .presses = 5, .depth = 0.003,
                                .seed = 7u, .radius = 0.008, .physics_rate_hz = 250};
}

int palp_cli_trainee_parse(const char *spec, palp_cli_trainee_def *out, char *err, size_t errlen) {
  char buf[256];
  if (!spec || strlen(spec) >= sizeof buf) {
    snprintf(err, errlen, "scripted trainee: empty or too long");
    return PALP_EINVAL;
  }
  snprintf(buf, sizeof buf, "%s", spec);
  char *save = NULL, *tok = strtok_r(buf, ",", &save);
  palp_cli_trainee_def d;
  if (tok && !strcmp(tok, "expert")) d = palp_cli_trainee_default_def(PALP_CLI_TRAINEE_EXPERT);
  else if (tok && !strcmp(tok, "novice")) d = palp_cli_trainee_default_def(PALP_CLI_TRAINEE_NOVICE);
  else {
    snprintf(err, errlen, "scripted trainee \"%s\": expected expert or novice", tok ? tok : "");
    return PALP_EINVAL;
  }
  while ((tok = strtok_r(NULL, ",", &save))) {
    char *eq = strchr(tok, '=');
    char *end = NULL;
    double v = eq ? strtod(eq + 1, &end) : NAN;
    if (!eq || end == eq + 1 || *end || !isfinite(v) || v <= 0 || v > 1e4) {
      snprintf(err, errlen, "scripted trainee: \"%s\": expected key=value with a number in (0, 1e4]", tok);
      return PALP_EINVAL;
    }
    *eq = 0;
    if (!strcmp(tok, "spacing_mm")) d.expert.spacing = v * 1e-3;
    else if (!strcmp(tok, "hold_s")) d.expert.hold = v;
    else if (!strcmp(tok, "threshold")) d.expert.threshold = v;
    else if (!strcmp(tok, "presses") && v == floor(v) && v <= 100) d.presses = (int)v;
    else if (!strcmp(tok, "depth_mm")) d.depth = v * 1e-3;
    else if (!strcmp(tok, "seed") && v == floor(v)) d.seed = (unsigned)v;
    else if (!strcmp(tok, "rate_hz")) d.physics_rate_hz = v;
    else {
      snprintf(err, errlen, "scripted trainee: unknown key or bad value \"%s\" (spacing_mm, hold_s, threshold, "
                            "presses, depth_mm, seed, rate_hz)", tok);
      return PALP_EINVAL;
    }
  }
  if (d.expert.spacing < 0.002 || d.physics_rate_hz < 10 || d.depth > 0.03) {
    snprintf(err, errlen, "scripted trainee: spacing >= 2 mm, rate_hz >= 10, depth <= 30 mm");
    return PALP_EINVAL;
  }
  *out = d;
  return 0;
}

int palp_cli_trainee_input(const palp_cli_trainee_def *def, palp_cli_input *out) {
  tsrc *s = calloc(1, sizeof *s);
  if (!s) return PALP_ENOMEM;
  s->def = *def;
  pthread_mutex_init(&s->mu, NULL);
  *out = (palp_cli_input){.name = def->kind == PALP_CLI_TRAINEE_EXPERT ? "scripted expert" : "scripted novice",
                          .ctx = s,
                          .open = t_open,
                          .close = t_close,
                          .read_position = t_read,
                          .write_force = t_write,
                          .error = t_error,
                          .finger_radius = def->radius,
                          .button = t_button,
                          .model = t_model};
  return 0;
}
