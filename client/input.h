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
/* The server's physics rates (server/config.c, palp-server --tick-rate: 10..10000 Hz, the floor
 * 1 / PALP_WORLD_MAX_DT: a longer step no world takes); a
 * join with another is refused (palp_cli_station_join, palp_cli_haptic_start). */
#define PALP_CLI_PHYSICS_RATE_MIN (1.0 / PALP_WORLD_MAX_DT)
#define PALP_CLI_PHYSICS_RATE_MAX 10000.0
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

struct palp_band;
typedef struct palp_cli_input {
  const char *name;
  void *ctx;
  /* phantom dome radius [m] is known from the catalogue when open is called */
  int (*open)(void *ctx, double phantom_radius);
  /* Fills up to cap finger states for time t [s] since the start; returns how
   * many, PALP_CLI_INPUT_END when finished, or a negative PALP_E* code. */
  int (*poll)(void *ctx, double t, palp_cli_cmd *cmds, int cap);
  /* Optional: the force the phantom exerts on a finger [N], every feedback sample; limited to the
   * station's safe force first (palp_cli_device_force: --max-force or 10 N, or the phantom's
   * max_force where that is smaller). With no sample for 0.25 s it fades to 0 N over
   * 0.1 s (the haptic thread's stale_time and fade_time), and it is 0 N before close(). */
  void (*feedback)(void *ctx, int finger, palp_vec3 force);
  void (*close)(void *ctx);
  /* ---- position in, force out, at 1 kHz (issue 11); all optional, added at the
   * end so drivers built against the older header (these fields zero) still load.
   * A source with read_position is a haptic device: palp-client runs its haptic
   * thread (haptic_loop.h) at 1 kHz, which calls read_position, renders the force
   * from the server's newest local contact model and calls write_force, every
   * tick; poll() and feedback() are then not used. Both are called from the
   * haptic thread only, and must not block. */
  /* Device point (the fingertip sphere's centre) [m] at time t [s] since the
   * start: 1 the finger is on (position-driven), 0 lifted (away from the
   * phantom), PALP_CLI_INPUT_END finished, or a negative PALP_E* code, with
   * error() saying why. */
  int (*read_position)(void *ctx, double t, palp_vec3 *x);
  /* The force to render [N] and PALP_CLI_FORCE_* flags (e.g. the station limited it). */
  void (*write_force)(void *ctx, palp_vec3 f, unsigned flags);
  /* A clear message for the last error, or NULL. */
  const char *(*error)(void *ctx);
  double finger_radius; /* fingertip sphere [m]; 0 = 8 mm */
  /* ---- issue 13, optional (added at the end: older drivers leave it zero) --------
   * The device's "lump here" button: PALP_CLI_BUTTON_MARK (mark a lump where the
   * fingertip touches), PALP_CLI_BUTTON_WITHDRAW (withdraw the last mark) or 0 when
   * nothing was pressed since the last call. Called from the station's main thread
   * (not the haptic thread) about 50 times a second; must not block. */
  int (*button)(void *ctx);
  /* Optional: every new local contact model from the server (its force is the
   * phantom's after the physics step, before the station limits or extrapolates it).
   * Called from the haptic thread; must not block. */
  void (*model)(void *ctx, const palp_local_model *m);
  /* Optional (2026-12-05; added at the end: older drivers leave it zero): the pressure bands the
   * session's exercise grades, PALP_BAND_COUNT of src/palp_assess.h's palp_band, checked, so that
   * a device's display can name the band a press is in as the assessment will. Called once, from
   * the station's main thread, after the haptic thread started; never outside an exercise. */
  void (*bands)(void *ctx, const struct palp_band *band);
} palp_cli_input;
enum { PALP_CLI_BUTTON_MARK = 1, PALP_CLI_BUTTON_WITHDRAW = 2 };

/* write_force flags (bits 0-3: the values of palp_haptic's PALP_HAPTIC_*). */
enum {
  PALP_CLI_FORCE_LIMITED = 1u << 0,  /* limited to the safe force: show the trainee */
  PALP_CLI_FORCE_STALE = 1u << 1,    /* no recent model from the server: fading out */
  PALP_CLI_FORCE_CONTACT = 1u << 2,  /* the fingertip touches the surface */
  PALP_CLI_FORCE_NO_MODEL = 1u << 3, /* no model yet */
  /* The model being rendered was flagged by the server outside the phantom model's valid
   * range (LocalModel.flags & PALP_DDS_LM_OUTSIDE: a link strained beyond +-50%, the skin's
   * linearised bending off by more than 0.1 rad or the set's validated miss, deeper than validated,
   * the literal gel law outside its stable range, ...): the force is less certain than
   * the model's validation says (docs/model.md, "Valid range"). Show the trainee. */
  PALP_CLI_FORCE_OUT_OF_RANGE = 1u << 4
};

/* Point on the dome of radius R at polar angle from the pole and azimuth [deg],
 * and the outward unit normal there. */
palp_vec3 palp_cli_dome_point(double R, double polar_deg, double azimuth_deg, palp_vec3 *normal);

/* A force distribution 1-4 in its one name (docs/naming.md: the paper's numeral, then the scene file's
 * keyword): "I single" .. "IV gaussian_offset", "?" for any other number. The observer and the force
 * keyboard's status line (palp-review has review_dist_name). */
const char *palp_cli_dist_name(int distribution);

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

/* ---- simulated haptic device (input_simdevice.c) -------------------------------
 * A position-driven device following a scripted trajectory, for tests and demos.
 * Depth is the fingertip's lowest point below the undeformed surface [m]
 * (0: touching), measured along the surface normal; the device point is the
 * sphere's centre. Patterns:
 *   press:   approach, press to depth at speed, hold, release at speed
 *   slide:   press, then slide along the surface (towards azimuth + 90 deg) at slide_speed
 *            over slide_distance, release
 *   circles: press, then circle_count circles of circle_radius at circle_hz, release
 *   cycles:  cycle_count press-release cycles to depth at speed (no hold)
 *   strips:  the MammaCare vertical-strip search: parallel strips (x = const) across
 *            the dome, each swept at three depths (light, medium, deep = depth/3,
 *            2 depth/3, depth) at slide_speed, lifting between strips */
typedef enum palp_cli_sim_pattern {
  PALP_CLI_SIM_PRESS = 0,
  PALP_CLI_SIM_SLIDE,
  PALP_CLI_SIM_CIRCLES,
  PALP_CLI_SIM_CYCLES,
  PALP_CLI_SIM_STRIPS
} palp_cli_sim_pattern;

typedef struct palp_cli_simdevice_def {
  palp_cli_sim_pattern pattern;
  double polar_deg, azimuth_deg; /* where the press starts */
  double depth;          /* [m], default 0.010 */
  double speed;          /* press/release speed along the normal [m/s], default 0.02 */
  double hold;           /* [s] at depth before sliding/releasing, default 0.5 */
  double approach;       /* start this far above the surface [m], default 0.003 */
  double slide_speed;    /* [m/s], default 0.05 */
  double slide_distance; /* [m], default 0.02 */
  double circle_radius;  /* [m], default 0.005 */
  double circle_hz;      /* default 1 */
  int circle_count;      /* default 2 */
  int cycle_count;       /* default 5 */
  int strip_count;       /* default 4 */
  double strip_extent;   /* strips cover |x|, |y| <= this [m]; default 0.6 R */
  double radius;         /* fingertip [m], default 0.008 */
  double start;          /* idle time before the trajectory [s], default 0.2 */
  double tail;           /* lifted time after it before the source ends [s], default 0.5 */
  double mark_at;        /* issue 13: press the "lump here" button at this time [s]; 0: never */
  double withdraw_at;    /* press "withdraw the last mark" at this time [s]; 0: never */
} palp_cli_simdevice_def;

palp_cli_simdevice_def palp_cli_simdevice_default_def(palp_cli_sim_pattern pattern);
/* Parses "press|slide|circles|cycles|strips[,key=value...]" (keys: depth_mm, speed_mm_s,
 * hold_s, slide_mm_s, slide_mm, circle_mm, circle_hz, circles, cycles, strips, polar,
 * azimuth, radius_mm); err names a bad key or value. At most 21 circles, 510 cycles and
 * 127 strips (what fits the trajectory's waypoints with its final lift; so for _input). */
int palp_cli_simdevice_parse(const char *spec, palp_cli_simdevice_def *out, char *err, size_t errlen);
int palp_cli_simdevice_input(const palp_cli_simdevice_def *def, palp_cli_input *out);
/* The trajectory itself, for tests that drive a model directly: device point at t
 * on a dome of radius R; returns 1 on, 0 lifted, PALP_CLI_INPUT_END after the end. */
int palp_cli_simdevice_at(const palp_cli_simdevice_def *def, double R, double t, palp_vec3 *x);
double palp_cli_simdevice_duration(const palp_cli_simdevice_def *def, double R);

/* ---- keyboard (raw terminal) -------------------------------------------------- */
/* max_force [N]: the station's safe force (--max-force, else the renderer's default); the force keys
 * stop there, and the status line says MAX. */
int palp_cli_keyboard_input(palp_cli_input *out, double max_force, char *err, size_t errlen);
/* Position-driven keyboard (issue 11): arrows move a virtual fingertip over the
 * surface, +/- change its depth in 1 mm steps, space lifts/lowers; the force the
 * station renders is shown. */
int palp_cli_keyboard_finger_input(palp_cli_input *out, char *err, size_t errlen);
/* ---- device driver (shared object) ----------------------------------------------
 * A driver is a shared object exporting
 *   int palp_cli_device_driver(const char *arg, palp_cli_input *out);
 * which fills out (ops + its ctx) and returns 0. */
typedef int (*palp_cli_device_entry)(const char *arg, palp_cli_input *out);
int palp_cli_device_input(const char *path, const char *arg, palp_cli_input *out, char *err, size_t errlen);

/* The server's feedback force as a device driver may be given it (feedback()): limited to max_force
 * [N] in magnitude; a force that is not finite gives 0 N. Returns 0 as it was, 1 limited, PALP_EINVAL
 * not finite. The 1 kHz haptic thread limits its own force; this is the force-driven stations' path,
 * which handed a driver whatever a sample said (NaN, 1e6 N; session 75, found by review). */
int palp_cli_device_force(palp_vec3 f, double max_force, palp_vec3 *out);

#endif
