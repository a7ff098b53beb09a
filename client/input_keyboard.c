/* input_keyboard.c - the keyboard as a haptic stand-in, in a raw terminal.
 *
 * Arrow up/down move the finger towards the pole/rim, left/right around the
 * dome; + and - change the force by 0.25 N; space presses/lifts; 1-4 choose the
 * paper's distribution; q ends. The terminal is restored on close. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <termios.h>
#include <unistd.h>

#include "input.h"

typedef struct keyboard {
  struct termios saved;
  int raw;
  double R;
  double polar, azimuth; /* [deg] */
  double force;          /* [N] */
  int pressed, distribution, quit;
  int esc;               /* escape sequence progress */
  double last_status;
} keyboard;

static int k_open(void *ctx, double R) {
  keyboard *k = ctx;
  k->R = R;
  struct termios t;
  if (tcgetattr(STDIN_FILENO, &k->saved) != 0) return PALP_EIO;
  t = k->saved;
  t.c_lflag &= ~(tcflag_t)(ICANON | ECHO);
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  if (tcsetattr(STDIN_FILENO, TCSANOW, &t) != 0) return PALP_EIO;
  k->raw = 1;
  fprintf(stderr, "keyboard: arrows move, +/- force, space press/lift, 1-4 distribution, q quit\n");
  return 0;
}

static void key(keyboard *k, int c) {
  if (k->esc == 1) {
    k->esc = c == '[' ? 2 : 0;
    return;
  }
  if (k->esc == 2) {
    k->esc = 0;
    if (c == 'A') k->polar -= 2;
    if (c == 'B') k->polar += 2;
    if (c == 'C') k->azimuth += 5;
    if (c == 'D') k->azimuth -= 5;
    if (k->polar < 0) k->polar = 0;
    if (k->polar > 80) k->polar = 80; /* keep off the fixed rim */
    return;
  }
  switch (c) {
  case 27: k->esc = 1; break;
  case '+': case '=': k->force += 0.25; break;
  case '-': case '_': k->force = k->force > 0.25 ? k->force - 0.25 : 0; break;
  case ' ': k->pressed = !k->pressed; break;
  case '1': case '2': case '3': case '4': k->distribution = c - '0'; break;
  case 'q': case 'Q': k->quit = 1; break;
  default: break;
  }
}

static int k_poll(void *ctx, double t, palp_cli_cmd *cmd, int cap) {
  keyboard *k = ctx;
  fd_set fds;
  struct timeval tv = {0, 0};
  FD_ZERO(&fds);
  FD_SET(STDIN_FILENO, &fds);
  while (select(STDIN_FILENO + 1, &fds, NULL, NULL, &tv) > 0) {
    unsigned char c;
    if (read(STDIN_FILENO, &c, 1) != 1) break;
    key(k, c);
    FD_ZERO(&fds);
    FD_SET(STDIN_FILENO, &fds);
  }
  if (k->quit) return PALP_CLI_INPUT_END;
  if (t - k->last_status >= 0.5) {
    fprintf(stderr, "\rkeyboard: %s dist %d at polar %.0f deg azimuth %.0f deg, %.2f N   ",
            k->pressed ? "PRESS" : "lift ", k->distribution, k->polar, k->azimuth, k->force);
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

int palp_cli_keyboard_input(palp_cli_input *out, char *err, size_t errlen) {
  if (!isatty(STDIN_FILENO)) {
    snprintf(err, errlen, "--input keyboard needs a terminal on standard input");
    return PALP_EINVAL;
  }
  keyboard *k = calloc(1, sizeof *k);
  if (!k) return PALP_ENOMEM;
  k->polar = 0;
  k->force = 1.0;
  k->distribution = 3;
  *out = (palp_cli_input){.name = "keyboard", .ctx = k, .open = k_open, .poll = k_poll, .close = k_close};
  return 0;
}
