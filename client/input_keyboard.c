/* input_keyboard.c - the keyboard as a haptic stand-in, in a raw terminal.
 *
 * Arrow up/down move the finger towards the pole/rim, left/right around the
 * dome; + and - change the force by 0.25 N, up to the station's safe force; space presses/lifts; 1-4 choose the
 * paper's distribution; q ends. Arrows come as ESC [ A..D or, in a terminal's application cursor
 * mode, ESC O A..D. The terminal is restored on close (and by palp-client on
 * SIGQUIT, SIGHUP, a crash or exit, which never reach close: client/main.c, guard_tty). */
#include <math.h>
#include <poll.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <termios.h>
#include <unistd.h>

#include "input.h"
#include "palp_assess.h" /* palp_band_of: the band a press is in, as the assessment grades it */
#include "palp_place.h"  /* palp_place_words: a place in the words every palp tool prints */

typedef struct keyboard {
  struct termios saved;
  int raw;
  double R;
  double polar, azimuth; /* [deg] */
  double force;          /* [N] */
  double max_force;      /* [N] the station's safe force: + stops there (0: the finger keyboard, no force keys) */
  int pressed, distribution, quit;
  int esc;               /* escape sequence progress: 1 after ESC, 2 after ESC [ or ESC O */
  double now, esc_t;     /* the poll's time, and when the ESC came [s] */
  double last_status;
  const char *erase;     /* after a status line: erase what a longer one before it left (a terminal's EL) */
} keyboard;

/* Where the keys put the finger, in the one phrase every palp tool prints for a place (docs/naming.md:
 * the clock seen from above and the arc from the pole, "at the pole" within 1 mm of it), on the
 * undeformed dome. The status lines said "at polar 4 deg azimuth 5 deg" until session 83 (the azimuth
 * from +x, which no other tool shows). */
static const char *key_place(const keyboard *k, char *buf, size_t len) {
  return palp_place_words(palp_cli_dome_point(k->R, k->polar, k->azimuth, NULL), buf, len);
}

/* A lone ESC (the Esc key) is over when no byte follows within this long [s]: a terminal sends an
 * arrow's bytes in one write, and a person's next key comes later. */
#define KEY_ESC_TIMEOUT 0.05

/* The status line, written from the haptic thread (the finger's) or the contact loop: only when stderr
 * can take it now, else skipped until the next (every 0.5 s). A terminal whose output is stopped, or
 * stderr piped to a slow reader, blocked fprintf, and with it the 1 kHz loop: no ticks, no contact
 * samples, the server holding her last point (session 90's review). */
static void status_line(const char *fmt, ...) {
  struct pollfd p = {.fd = STDERR_FILENO, .events = POLLOUT};
  if (poll(&p, 1, 0) != 1 || !(p.revents & POLLOUT)) return;
  va_list ap;
  va_start(ap, fmt);
  vfprintf(stderr, fmt, ap);
  va_end(ap);
}

/* The terminal in raw mode (no line buffering, no echo, no XON/XOFF: Ctrl-S stops no output) for
 * single keys; restored by close. */
static int k_raw(keyboard *k, double R) {
  k->R = R;
  k->erase = isatty(STDERR_FILENO) ? "\033[K" : "   ";
  struct termios t;
  if (tcgetattr(STDIN_FILENO, &k->saved) != 0) return PALP_EIO;
  t = k->saved;
  t.c_lflag &= ~(tcflag_t)(ICANON | ECHO);
  t.c_iflag &= ~(tcflag_t)IXON; /* Ctrl-S would stop the terminal's output, and a status write with it */
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  if (tcsetattr(STDIN_FILENO, TCSANOW, &t) != 0) return PALP_EIO;
  k->raw = 1;
  return 0;
}

static int k_open(void *ctx, double R) {
  keyboard *k = ctx;
  int rc = k_raw(k, R);
  if (rc == 0)
    fprintf(stderr, "keyboard: arrows move, +/- force (up to the station's safe force, %.2f N), space press/lift, "
                    "1-4 distribution, q quit\n", k->max_force);
  return rc;
}

/* An escape sequence's byte: 1 when c was taken as part of one (an arrow moves the finger), 0 when c
 * is a key of its own. After ESC only '[' or 'O' go on (ESC O A..D: application cursor mode, whose
 * arrows did nothing); any other byte ends the ESC and is its own key (ESC then q lost the q until
 * session 82). */
static int key_esc(keyboard *k, int c) {
  if (k->esc == 1) {
    k->esc = c == '[' || c == 'O' ? 2 : 0;
    return k->esc == 2;
  }
  if (k->esc == 2) {
    k->esc = 0;
    if (c == 'A') k->polar -= 2;
    if (c == 'B') k->polar += 2;
    if (c == 'C') k->azimuth += 5;
    if (c == 'D') k->azimuth -= 5;
    if (k->polar < 0) k->polar = 0;
    if (k->polar > 80) k->polar = 80; /* keep off the fixed rim */
    return 1;
  }
  return 0;
}

/* Before the keys of a poll at t: an ESC with nothing after it for KEY_ESC_TIMEOUT was the Esc key
 * alone, so the next key ('[' included) is a key of its own. */
static void key_time(keyboard *k, double t) {
  k->now = t;
  if (k->esc && !(t - k->esc_t <= KEY_ESC_TIMEOUT)) k->esc = 0;
}

static void key(keyboard *k, int c) {
  if (key_esc(k, c)) return;
  switch (c) {
  case 27: k->esc = 1, k->esc_t = k->now; break;
  /* bounded at the station's safe force, as the finger keyboard's depth keys are bounded: past it the
   * renderer clamped every sample while the status line showed ever larger forces (session 82) */
  case '+': case '=': k->force = k->force + 0.25 > k->max_force ? k->max_force : k->force + 0.25; break;
  case '-': case '_': k->force = k->force > 0.25 ? k->force - 0.25 : 0; break;
  case ' ': k->pressed = !k->pressed; break;
  case '1': case '2': case '3': case '4': k->distribution = c - '0'; break;
  case 'q': case 'Q': k->quit = 1; break;
  default: break;
  }
}

/* Hands every key waiting on stdin to on_key, without blocking. */
static void drain_keys(void (*on_key)(void *, unsigned char), void *arg) {
  fd_set fds;
  struct timeval tv = {0, 0};
  FD_ZERO(&fds);
  FD_SET(STDIN_FILENO, &fds);
  while (select(STDIN_FILENO + 1, &fds, NULL, NULL, &tv) > 0) {
    unsigned char c;
    if (read(STDIN_FILENO, &c, 1) != 1) break;
    on_key(arg, c);
    FD_ZERO(&fds);
    FD_SET(STDIN_FILENO, &fds);
  }
}

static void key_cb(void *arg, unsigned char c) { key(arg, c); }

static int k_poll(void *ctx, double t, palp_cli_cmd *cmd, int cap) {
  keyboard *k = ctx;
  key_time(k, t);
  drain_keys(key_cb, k);
  if (k->quit) return PALP_CLI_INPUT_END;
  if (t - k->last_status >= 0.5) {
    /* the distribution in its one name (I-IV and its keyword; "dist 3" until session 83) */
    char at[64];
    status_line("\rkeyboard: %s %s, distribution %s, %.2f N%s%s", k->pressed ? "PRESS" : "lift ",
            key_place(k, at, sizeof at), palp_cli_dist_name(k->distribution), k->force,
            k->force >= k->max_force ? " MAX" : "", k->erase);
    k->last_status = t;
  }
  if (cap < 1) return 0;
  palp_vec3 n;
  palp_vec3 p = palp_cli_dome_point(k->R, k->polar, k->azimuth, &n);
  cmd[0] = (palp_cli_cmd){.finger = 0, .mode = (k->pressed && k->force > 0) ? 1 : 0,
                          .distribution = k->distribution, .center = p,
                          .force = {-k->force * n.x, -k->force * n.y, -k->force * n.z}};
  return 1;
}

static void k_close(void *ctx) {
  keyboard *k = ctx;
  if (k->raw) tcsetattr(STDIN_FILENO, TCSANOW, &k->saved);
  fputc('\n', stderr);
  free(k);
}

int palp_cli_keyboard_input(palp_cli_input *out, double max_force, char *err, size_t errlen) {
  if (!(max_force > 0) || !isfinite(max_force)) {
    snprintf(err, errlen, "--input keyboard: the safe force %g N is not a force > 0", max_force);
    return PALP_EINVAL;
  }
  if (!isatty(STDIN_FILENO)) {
    snprintf(err, errlen, "--input keyboard needs a terminal on standard input");
    return PALP_EINVAL;
  }
  keyboard *k = calloc(1, sizeof *k);
  if (!k) return PALP_ENOMEM;
  k->polar = 0;
  k->max_force = max_force;
  k->force = max_force < 1.0 ? max_force : 1.0;
  k->distribution = 3;
  k->erase = "";
  *out = (palp_cli_input){.name = "keyboard", .ctx = k, .open = k_open, .poll = k_poll, .close = k_close};
  return 0;
}

/* ---- position-driven keyboard (issue 11) ------------------------------------------------
 * Arrow up/down move the fingertip towards the pole/rim (2 deg), left/right around
 * the dome (5 deg); + and - press deeper / come up by one depth step (depth of the tip's
 * lowest point below the undeformed surface; negative = above it); [ and ] halve and
 * double the step (0.125-4 mm, 1 mm at first: on a long-term dome 1 mm is ~2.3 N,
 * on breast tissue ~0.45 N, docs/materials.md); space lifts or
 * lowers the finger; q ends. read_position and write_force run on the haptic
 * thread: reading a key is one non-blocking select() per tick, and the status line
 * (the force the station renders) is written twice a second. */
typedef struct kfinger {
  keyboard k;            /* terminal state, position, quit */
  double depth;          /* [m] */
  double step;           /* [m] per + or - */
  int lifted;
  double last_status;
  double t;
  palp_vec3 force;
  unsigned flags;
  double radius;
  atomic_int button;     /* issue 13: m / u pressed (haptic thread -> main thread) */
  palp_vec3 device;      /* the device point handed to the station [m], moving towards the keys' point */
  double device_t;       /* when it was last moved [s]; < 0: not yet placed */
  /* The fingertip's depth below the undeformed surface in the server's newest model, R + r - |proxy|
   * [m] (what an exercise's pressure bands and the review read; the keys' depth is the device's,
   * which the coupling spring keeps deeper by F / k); NAN when not touching. Haptic thread. */
  double tip_depth;
  double model_force;    /* |F| of that model [N] (the phantom's, before the station limits it) */
  /* The exercise's pressure bands (kf_bands, main thread), published by have_bands (release;
   * the haptic thread reads them after an acquire): the status line names the band a press is
   * in, as the assessment grades it (palp_band_of: depth and the model's force). */
  palp_band band[PALP_BAND_COUNT];
  atomic_int have_bands;
} kfinger;

/* How fast the keys move the fingertip [m/s]: a brisk hand's press (the scripted trainees press and
 * glide at 50 mm/s). A key is a step of 0.125-4 mm and several may come at once; taken in one tick,
 * 7 mm put the device 7 mm under the surface before the server's next model and the station rendered
 * (and announced as limited) a 14 N spike at a depth where the phantom answers 1.2 N. */
#define KF_SPEED 0.05

static int kf_open(void *ctx, double R) {
  kfinger *f = ctx;
  int rc = k_raw(&f->k, R);
  if (rc == 0)
    fprintf(stderr, "keyboard (finger): arrows move the fingertip, +/- press deeper / come up one step (1 mm), "
                    "[/] halve / double the step, space lift, m mark a lump here, u withdraw the last mark, q quit\n");
  return rc;
}

static void fkey(kfinger *f, int c) {
  keyboard *k = &f->k;
  if (key_esc(k, c)) return; /* arrows */
  switch (c) {
  case '+': case '=': f->depth = f->depth + f->step > 0.035 ? 0.035 : f->depth + f->step; break;
  case '-': case '_': f->depth = f->depth - f->step < -0.010 ? -0.010 : f->depth - f->step; break;
  case '[': f->step = f->step / 2.0 < 0.000125 ? 0.000125 : f->step / 2.0; break;
  case ']': f->step = f->step * 2.0 > 0.004 ? 0.004 : f->step * 2.0; break;
  case ' ': f->lifted = !f->lifted; break;
  case 'm': case 'M': atomic_store(&f->button, PALP_CLI_BUTTON_MARK); break;
  case 'u': case 'U': atomic_store(&f->button, PALP_CLI_BUTTON_WITHDRAW); break;
  default: key(k, c); break;
  }
}

static void fkey_cb(void *arg, unsigned char c) { fkey(arg, c); }

static int kf_read(void *ctx, double t, palp_vec3 *x) {
  kfinger *f = ctx;
  key_time(&f->k, t);
  drain_keys(fkey_cb, f);
  if (f->k.quit) return PALP_CLI_INPUT_END;
  f->t = t;
  palp_vec3 n;
  palp_vec3 p = palp_cli_dome_point(f->k.R, f->k.polar, f->k.azimuth, &n);
  const double h = f->radius - f->depth;
  const palp_vec3 target = {p.x + n.x * h, p.y + n.y * h, p.z + n.z * h};
  if (f->device_t < 0 || t < f->device_t) {
    f->device = target;
  } else { /* towards the keys' point at KF_SPEED at most; a stall of the thread is not made up at once */
    const double dt = t - f->device_t < 0.1 ? t - f->device_t : 0.1, reach = KF_SPEED * dt;
    const palp_vec3 d = {target.x - f->device.x, target.y - f->device.y, target.z - f->device.z};
    const double dist = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    const double s = dist > reach ? reach / dist : 1.0;
    f->device = (palp_vec3){f->device.x + s * d.x, f->device.y + s * d.y, f->device.z + s * d.z};
  }
  f->device_t = t;
  *x = f->device;
  return f->lifted ? 0 : 1;
}

static void kf_write(void *ctx, palp_vec3 force, unsigned flags) {
  kfinger *f = ctx;
  f->force = force;
  f->flags = flags;
  if (f->t - f->last_status >= 0.5) {
    const double m = sqrt(force.x * force.x + force.y * force.y + force.z * force.z);
    char tip[64] = "";
    if (isfinite(f->tip_depth)) {
      /* snprintf returns the length it wanted, not what it wrote: a depth of many digits (a model
       * from the wire bounds the proxy, but this line must not rely on it) would put the band's
       * words past the end of tip, so they go after what was written, or nowhere. */
      int n = snprintf(tip, sizeof tip, ", fingertip %.1f mm deep", f->tip_depth * 1e3);
      if (n < 0) n = 0, tip[0] = '\0';
      if ((size_t)n >= sizeof tip) n = (int)sizeof tip - 1;
      if (atomic_load_explicit(&f->have_bands, memory_order_acquire)) { /* an exercise: its band, or none */
        const int b = palp_band_of(f->band, f->tip_depth, f->model_force);
        snprintf(tip + n, sizeof tip - (size_t)n, " (%s)", b >= 0 ? palp_band_name(b) : "no band");
      }
    }
    char at[64];
    status_line("\rkeyboard: %s %s, device %+.3g mm (step %g mm)%s: force %.2f N%s%s%s",
            f->lifted ? "lifted" : "finger", key_place(&f->k, at, sizeof at), f->depth * 1e3, f->step * 1e3, tip, m,
            (flags & PALP_CLI_FORCE_LIMITED) ? " LIMITED" : "",
            (flags & PALP_CLI_FORCE_OUT_OF_RANGE) ? " OUTSIDE VALID RANGE" : "", f->k.erase);
    f->last_status = f->t;
  }
}

static void kf_model(void *ctx, const palp_local_model *m) {
  kfinger *f = ctx;
  f->tip_depth = m->contact ? palp_fingertip_depth(f->k.R, f->radius, m->proxy) : NAN;
  f->model_force = sqrt(m->force.x * m->force.x + m->force.y * m->force.y + m->force.z * m->force.z);
}

static void kf_bands(void *ctx, const struct palp_band *band) {
  kfinger *f = ctx;
  if (atomic_load_explicit(&f->have_bands, memory_order_relaxed)) return; /* once: the haptic thread reads them */
  memcpy(f->band, band, sizeof f->band);
  atomic_store_explicit(&f->have_bands, 1, memory_order_release);
}

static int kf_button(void *ctx) {
  kfinger *f = ctx;
  return atomic_exchange(&f->button, 0);
}

static void kf_close(void *ctx) {
  kfinger *f = ctx;
  if (f->k.raw) tcsetattr(STDIN_FILENO, TCSANOW, &f->k.saved);
  fputc('\n', stderr);
  free(f);
}

int palp_cli_keyboard_finger_input(palp_cli_input *out, char *err, size_t errlen) {
  if (!isatty(STDIN_FILENO)) {
    snprintf(err, errlen, "--input keyboard-finger needs a terminal on standard input");
    return PALP_EINVAL;
  }
  kfinger *f = calloc(1, sizeof *f);
  if (!f) return PALP_ENOMEM;
  f->k.distribution = 3;
  f->k.erase = "";
  f->depth = -0.002; /* start 2 mm above the pole */
  f->step = 0.001;
  f->radius = 0.008;
  f->device_t = -1;
  f->tip_depth = NAN;
  *out = (palp_cli_input){.name = "keyboard (finger)", .ctx = f, .open = kf_open, .close = kf_close,
                          .read_position = kf_read, .write_force = kf_write, .finger_radius = f->radius,
                          .button = kf_button, .model = kf_model, .bands = kf_bands};
  return 0;
}
