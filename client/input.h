/*
 * input.h - haptic input sources behind one small driver interface.
 *
 * A source says, at station time t, what each finger should be doing; the
 * station turns that into palp_contact samples and hands the server's feedback
 * force back through feedback() (a real device renders it). Sources: scripted
 * profiles (the paper's four distributions; step, ramp, sine), replay of a
 * contact CSV, the keyboard, and shared-object device drivers (input_device.c)
 * so a real haptic device can be plugged in without rebuilding palp-client.
 */
#ifndef PALP_CLI_INPUT_H
#define PALP_CLI_INPUT_H

#include <stdio.h>

#include "palp.h"

#define PALP_CLI_MAX_FINGERS 4
#define PALP_CLI_INPUT_END 1000 /* poll(): the source has finished */

/* The desired state of one finger. mode: 0 lifted, 1 force-driven, 2 position-driven
 * (the values of palp_ContactMode on the wire). */
typedef struct palp_cli_cmd {
  int finger;
  int mode;
  int distribution;     /* 1..4 (force-driven) */
  palp_vec3 center;     /* contact centre / finger tip centre [m] */
  palp_vec3 force;      /* force on the phantom [N] (force-driven) */
  double radius;        /* finger tip radius [m] (position-driven) */
  double patch_area;    /* [m^2], 0 = the paper's 5.2 cm^2 */
} palp_cli_cmd;

typedef struct palp_cli_input {
  const char *name;
  void *ctx;
  /* phantom dome radius [m] is known from the catalogue when open is called */
  int (*open)(void *ctx, double phantom_radius);
  /* Fills up to cap finger states for time t [s] since the start; returns how
   * many, PALP_CLI_INPUT_END when finished, or a negative PALP_E* code. */
  int (*poll)(void *ctx, double t, palp_cli_cmd *cmds, int cap);
  /* Optional: the force the phantom exerts on a finger [N], every feedback sample. */
  void (*feedback)(void *ctx, int finger, palp_vec3 force);
  void (*close)(void *ctx);
} palp_cli_input;

/* Point on the dome of radius R at polar angle from the pole and azimuth [deg],
 * and the outward unit normal there. */
palp_vec3 palp_cli_dome_point(double R, double polar_deg, double azimuth_deg, palp_vec3 *normal);

/* ---- scripted profiles ----------------------------------------------------- */
typedef struct palp_cli_script_def {
  int finger_mode;      /* 0: force-driven (profile in N); 1: position-driven (profile is depth [m]) */
  int distribution;     /* 1..4 */
  double polar_deg, azimuth_deg; /* where on the dome */
  palp_profile profile; /* force [N] or indentation depth [m] over time */
  double radius;        /* finger tip radius [m] */
  double patch_area;    /* [m^2], 0 default */
  double end_time;      /* [s]; the source ends here */
} palp_cli_script_def;
int palp_cli_script_input(const palp_cli_script_def *def, palp_cli_input *out);

/* ---- replay of a contact CSV -----------------------------------------------
 * Header "t_s,finger,mode,distribution,cx_m,cy_m,cz_m,fx_N,fy_N,fz_N,radius_m";
 * palp-client --contact-csv writes this format. */
int palp_cli_replay_input(const char *path, palp_cli_input *out, char *err, size_t errlen);
void palp_cli_contact_csv_header(FILE *f);
void palp_cli_contact_csv_row(FILE *f, double t, const palp_cli_cmd *c);

/* ---- keyboard (raw terminal) -------------------------------------------------- */
int palp_cli_keyboard_input(palp_cli_input *out, char *err, size_t errlen);

/* ---- device driver (shared object) ----------------------------------------------
 * A driver is a shared object exporting
 *   int palp_cli_device_driver(const char *arg, palp_cli_input *out);
 * which fills out (ops + its ctx) and returns 0. */
typedef int (*palp_cli_device_entry)(const char *arg, palp_cli_input *out);
int palp_cli_device_input(const char *path, const char *arg, palp_cli_input *out, char *err, size_t errlen);

#endif
