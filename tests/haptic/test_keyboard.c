/*
 * test_keyboard.c - the finger keyboard (client/input_keyboard.c) in process, its standard input a
 * pseudo-terminal of the test's own (the keyboard needs a terminal). No server, no DDS: the test
 * hands it models and forces as the haptic thread would and reads the status line it writes.
 *
 * Built with the address sanitizer (tests/haptic/CMakeLists.txt): the status line is formatted in
 * a 64-byte stack buffer, and a write past it is the failure looked for, reported by the sanitizer
 * whether or not it shows in the text.
 */
#define _XOPEN_SOURCE 600 /* posix_openpt, grantpt, unlockpt, ptsname */
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "input.h"
#include "palp_assess.h"

/* The sanitizer's report goes to stdout: stderr is the capture file while the line is written. */
const char *__asan_default_options(void);
const char *__asan_default_options(void) { return "log_path=stdout"; }

#define DOME_R 0.058 /* [m] */
#define TIP_R 0.008  /* [m]: the finger keyboard's fingertip */

/* A pty's slave as standard input; returns the master's fd, or -1. */
static int pty_stdin(void) {
  const int m = posix_openpt(O_RDWR | O_NOCTTY);
  if (m < 0 || grantpt(m) != 0 || unlockpt(m) != 0) return -1;
  const char *name = ptsname(m);
  const int s = name ? open(name, O_RDWR | O_NOCTTY) : -1;
  if (s < 0 || dup2(s, STDIN_FILENO) < 0) return -1;
  close(s);
  return m;
}

/* One status line: the model (in contact, proxy on the z axis at |proxy| = proxy_len), then a tick
 * at t [s] (the line is written every 0.5 s), with what the keyboard wrote to stderr in out. */
static void status_line(palp_cli_input *in, double t, double proxy_len, char *out, size_t outlen) {
  palp_local_model m;
  memset(&m, 0, sizeof m);
  m.contact = 1, m.proxy = (palp_vec3){0, 0, proxy_len}, m.force = (palp_vec3){0, 0, 1.0};
  in->model(in->ctx, &m);
  palp_vec3 x;
  in->read_position(in->ctx, t, &x);
  FILE *cap = tmpfile();
  fflush(stderr);
  const int saved = dup(STDERR_FILENO);
  if (!cap || saved < 0) {
    snprintf(out, outlen, "(no capture)");
    return;
  }
  dup2(fileno(cap), STDERR_FILENO);
  in->write_force(in->ctx, (palp_vec3){0, 0, 1.0}, PALP_CLI_FORCE_CONTACT);
  fflush(stderr);
  dup2(saved, STDERR_FILENO);
  close(saved);
  rewind(cap);
  const size_t n = fread(out, 1, outlen - 1, cap);
  out[n] = '\0';
  fclose(cap);
}

/* 1. A fingertip depth of many digits (a proxy of 1e40 m, which the wire check now refuses, but
 * the line must not rely on that) in an exercise: the band's words went to tip + n with n the
 * length snprintf wanted (67), past the 64-byte buffer, with a size of 64 - 67 wrapped to 2^64 - 3.
 * Now the line is cut at 63 characters; a 5 mm press still names its band. */
static void test_status_depth(void) {
  palp_cli_input in;
  char err[256] = "";
  if (palp_cli_keyboard_finger_input(&in, err, sizeof err) != 0) {
    CHECK(0, "the finger keyboard on a pty: %s", err);
    return;
  }
  if (in.open(in.ctx, DOME_R) != 0) {
    CHECK(0, "the finger keyboard opens on a pty");
    in.close(in.ctx);
    return;
  }
  palp_band band[PALP_BAND_COUNT];
  memset(band, 0, sizeof band);
  for (int b = 0; b < PALP_BAND_COUNT; b++)
    band[b] = (palp_band){.has_depth = 1, .depth_min = 0.004 * b, .depth_max = 0.004 * (b + 1)};
  in.bands(in.ctx, band);

  char line[1024];
  status_line(&in, 1.0, DOME_R + TIP_R - 0.005, line, sizeof line); /* 5 mm deep: band 1 (4-8 mm) */
  char want[64];
  snprintf(want, sizeof want, ", fingertip 5.0 mm deep (%s): force 1.00 N", palp_band_name(1));
  CHECK(strstr(line, want) != NULL, "5 mm deep: the status line says \"%s\" (%s)", want, line + (line[0] == '\r'));

  status_line(&in, 2.0, 1e40, line, sizeof line);
  const char *a = strstr(line, ", fingertip "), *b = strstr(line, ": force 1.00 N");
  CHECK(a && b && b > a && b - a <= 63 && !strstr(line, "band"),
        "a fingertip 1e43 mm above the skin: its part of the line is cut to at most 63 characters (%d), "
        "without the band's words",
        a && b ? (int)(b - a) : -1);
  in.close(in.ctx);
}

/* Keys typed at the terminal: written to the pty's master, then given a moment to reach the slave. */
static void type(int master, const char *keys) {
  if (write(master, keys, strlen(keys)) != (ssize_t)strlen(keys)) CHECK(0, "typing \"%s\"", keys);
  nanosleep(&(struct timespec){0, 20000000}, NULL);
}

/* What the finger keyboard's status line says after a tick at t (position and step), or "". */
static void finger_status(palp_cli_input *in, double t, char *out, size_t outlen) {
  status_line(in, t, DOME_R + TIP_R - 0.005, out, outlen);
}

/* 2. (session 82) Escape sequences: ESC O A..D (a terminal's application cursor mode) moves the
 * fingertip as ESC [ A..D does; a byte after ESC that starts no sequence is a key of its own (ESC
 * then ']' doubled no step: the ']' was dropped); an ESC with nothing after it for 50 ms is over,
 * so a '[' typed later halves the step instead of starting an arrow; ESC then q ends the input. */
static void test_escape(int master) {
  palp_cli_input in;
  char err[256] = "", line[1024];
  if (palp_cli_keyboard_finger_input(&in, err, sizeof err) != 0 || in.open(in.ctx, DOME_R) != 0) {
    CHECK(0, "the finger keyboard opens on a pty: %s", err);
    return;
  }
  type(master, "\033OB\033OC\033[B"); /* down (polar +2) twice, right (azimuth +5) once */
  finger_status(&in, 1.0, line, sizeof line);
  /* polar 4 deg, azimuth 5 deg (from +x) on the 58 mm dome, in the words every tool prints (session 83):
   * 90 - 5 = 85 deg clockwise from +y = 2.83 h, "2.8 o'clock"; arc 58 mm x 4 pi / 180 = 4.05 mm, "4 mm" */
  CHECK(strstr(line, "finger at 2.8 o'clock, 4 mm from the pole, device") != NULL,
        "ESC O B, ESC O C, ESC [ B: polar 4 deg, azimuth 5 deg, at 2.8 o'clock, 4 mm from the pole (%s)",
        line + (line[0] == '\r'));
  type(master, "\033]"); /* Esc, then ]: the step doubles, 1 -> 2 mm */
  finger_status(&in, 2.0, line, sizeof line);
  CHECK(strstr(line, "(step 2 mm)") != NULL, "ESC then ]: the ] is taken, step 2 mm (%s)", line + (line[0] == '\r'));
  type(master, "\033"); /* Esc alone ... */
  palp_vec3 x;
  in.read_position(in.ctx, 2.5, &x);
  type(master, "[B"); /* ... and 100 ms later [ (halve the step) and B (no key) */
  finger_status(&in, 2.6, line, sizeof line);
  CHECK(strstr(line, "(step 1 mm)") != NULL && strstr(line, "at 2.8 o'clock, 4 mm from the pole"),
        "a lone ESC, then [ B 100 ms later: the step halves to 1 mm, the fingertip stays at 2.8 o'clock, 4 mm (%s)",
        line + (line[0] == '\r'));
  type(master, "\033q");
  CHECK(in.read_position(in.ctx, 3.0, &x) == PALP_CLI_INPUT_END, "ESC then q: the input ends");
  in.close(in.ctx);
}

/* 3. (session 82) The force keyboard's + stops at the station's safe force (2 N here), and the status
 * line says MAX; it went on by 0.25 N a press without bound (40 presses: 11 N). */
static void test_force_bound(int master) {
  palp_cli_input in;
  char err[256] = "";
  if (palp_cli_keyboard_input(&in, 2.0, err, sizeof err) != 0 || in.open(in.ctx, DOME_R) != 0) {
    CHECK(0, "the force keyboard opens on a pty: %s", err);
    return;
  }
  type(master, "++++++++++++++++++++++++++++++++++++++++ "); /* 40 presses, then space: press */
  palp_cli_cmd c[4];
  FILE *cap = tmpfile();
  fflush(stderr);
  const int saved = dup(STDERR_FILENO);
  dup2(fileno(cap), STDERR_FILENO);
  const int n = in.poll(in.ctx, 1.0, c, 4);
  fflush(stderr);
  dup2(saved, STDERR_FILENO);
  close(saved);
  char line[512];
  rewind(cap);
  line[fread(line, 1, sizeof line - 1, cap)] = '\0';
  fclose(cap);
  const double f = n == 1 ? sqrt(c[0].force.x * c[0].force.x + c[0].force.y * c[0].force.y + c[0].force.z * c[0].force.z) : -1;
  CHECK(n == 1 && c[0].mode == 1 && fabs(f - 2.0) < 1e-12 && strstr(line, "2.00 N MAX"),
        "40 presses of + with a safe force of 2 N: a press of %.3f N (2 N within 1e-12), the line says \"2.00 N MAX\" (%s)",
        f, line + (line[0] == '\r'));
  /* the place and the distribution as every tool names them (session 83: "dist 3 at polar 0 deg azimuth 0
   * deg" before): the keyboard starts at the pole with distribution 3 */
  CHECK(strstr(line, "keyboard: PRESS at the pole, distribution III gaussian, 2.00 N") != NULL,
        "the force keyboard's line names the place and distribution: \"PRESS at the pole, distribution III gaussian\" (%s)",
        line + (line[0] == '\r'));
  in.close(in.ctx);
  CHECK(palp_cli_keyboard_input(&in, 0.0, err, sizeof err) == PALP_EINVAL, "a safe force of 0 N is refused: %s", err);
}

int main(void) {
  const int master = pty_stdin();
  if (master < 0) {
    CHECK(0, "a pseudo-terminal for standard input");
    return check_exit();
  }
  test_status_depth();
  test_escape(master);
  test_force_bound(master);
  close(master);
  return check_exit();
}
