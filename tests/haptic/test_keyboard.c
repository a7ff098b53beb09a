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

int main(void) {
  const int master = pty_stdin();
  if (master < 0) {
    CHECK(0, "a pseudo-terminal for standard input");
    return check_exit();
  }
  test_status_depth();
  close(master);
  return check_exit();
}
