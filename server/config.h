/*
 * config.h - palp-server configuration (config/server.json).
 *
 * Parsing is a pure function of the JSON text and the directory relative paths
 * are resolved against, so tests can feed it strings. Every error names the
 * offending field, e.g. "phantoms[1].scene: expected a string".
 */
#ifndef PALP_SRV_CONFIG_H
#define PALP_SRV_CONFIG_H

#include <stddef.h>
#include <stdint.h>

#define PALP_SRV_MAX_PHANTOMS 16
#define PALP_SRV_PATH_MAX 1024
/* Several servers on one domain: ids are server_number * 2^20 + local id (idl/palp_dds.h). */
#define PALP_SRV_MAX_SERVER_NUMBER 4095
#define PALP_SRV_MAX_LOCAL_ID 1048575u
/* The widest contact limits a config may set (config.c refuses wider): a reader that cannot know a
 * server's config (palp-recorder) checks contacts against these, so that it never drops a contact
 * some server could have applied, and never keeps one no server applies. */
#define PALP_SRV_CFG_FINGER_RADIUS_MIN 1e-4 /* [m] */
#define PALP_SRV_CFG_FINGER_RADIUS_MAX 0.1  /* [m] */
#define PALP_SRV_CFG_MAX_FORCE_MAX 1000.0   /* [N] max_force's bound */
#define PALP_SRV_CFG_ABSURD_FORCE_MAX 1e6   /* [N] absurd_force's bound */

typedef enum palp_srv_force_policy {
  PALP_SRV_FORCE_CLAMP = 0, /* scale the force down to the limit, apply it, count it */
  PALP_SRV_FORCE_REJECT = 1 /* drop the sample, count it */
} palp_srv_force_policy;

typedef struct palp_srv_phantom_cfg {
  uint32_t id;                        /* > 0, unique */
  char name[64];
  char scene_path[PALP_SRV_PATH_MAX]; /* resolved against the config's directory */
  double physics_rate_hz;             /* this phantom's sessions step at this rate [Hz];
                                         0 = the server's tick_rate_hz (issue 11: the physics
                                         rate is decoupled from the stations' 1 kHz haptic rate) */
  char exercise_path[PALP_SRV_PATH_MAX]; /* issue 13: "" for a plain phantom; else the exercise file
                                            (resolved) whose phantom, with its lesions hidden in it,
                                            this entry hosts; name and scene_path are then filled by
                                            the server from the exercise (its title, its phantom) */
} palp_srv_phantom_cfg;

typedef enum palp_srv_session_exercise_policy {
  PALP_SRV_SESSION_EXERCISE_SECURED = 0,
  PALP_SRV_SESSION_EXERCISE_ALWAYS,
  PALP_SRV_SESSION_EXERCISE_OFF
} palp_srv_session_exercise_policy;

typedef struct palp_srv_config {
  uint32_t domain_id;          /* DDS domain, 0..232 */
  double tick_rate_hz;         /* session step rate [Hz]: 100 (paper) or 1000 (haptics) */
  int tick_threads;            /* tick thread pool size; 0 = number of online cores */
  int tick_priority;           /* 0: normal scheduling; 1..99: SCHED_FIFO priority of the tick threads */
  double deformation_rate_hz;  /* full-mesh rate to visual stations [Hz] */
  double status_rate_hz;       /* palp_server_status rate [Hz] */
  int max_sessions;            /* open trainee sessions at once */
  double max_force;            /* contact force limit [N] */
  palp_srv_force_policy force_policy;
  double finger_radius_min;    /* [m] */
  double finger_radius_max;    /* [m] */
  double log_interval;         /* minimum seconds between two log lines of one reject reason */
  /* Limits against a misbehaving peer (docs/robustness.md). */
  double absurd_force;         /* [N] a contact above this is rejected (absurd_force), never clamped */
  int max_viewers;             /* visual stations + observers per session */
  int stations_per_writer;     /* station ids one request writer (one station process) may hold */
  double join_rate;            /* admitted joins per second, all stations (token bucket) */
  int join_burst;              /* joins admitted at once before join_rate applies */
  double station_grace;        /* [s] a lost trainee station's session waits this long for it
                                * to come back from a stall (0: closed at once) */
  double closed_retention;     /* [s] a closed session's state and a refused station's reply stay
                                * published this long, then their DDS instances are released */
  int dds_log_lines;           /* Cyclone warnings printed per dds_log_window, the rest counted */
  double dds_log_window;       /* [s] */
  char dds_config[PALP_SRV_PATH_MAX]; /* Cyclone XML, resolved against the config's directory */
  char database[PALP_SRV_PATH_MAX];   /* SQLite session log; "" disables logging */
  double session_log_max_mb;   /* [MB, 10^6 bytes] cap on the session log's file (0: none); at the cap
                                * the log behaves as on a full disk (docs/server.md, "A full session
                                * log"): sessions go on, lost records are counted and said, and their
                                * scores say the log is incomplete */
  /* DDS Security ("security": {"pki": DIR, "identity": "server"}; docs/security.md):
   * pki "" runs plain DDS (the quick local demo). */
  char security_pki[PALP_SRV_PATH_MAX]; /* resolved against the config's directory */
  char security_identity[64];           /* default "server" */
  char log_level[16];          /* "error", "warn", "info", "debug"; "" = not set (info); re-read on SIGHUP */
  char server_name[64];        /* identity on the domain; "" = the host name */
  uint32_t server_number;      /* 0..4095: high bits of every phantom and session id it hands out */
  double assess_sample_hz;     /* issue 13: finger samples logged per second per position-driven
                                  finger, at most every physics step (default 100) */
  /* palp_session_exercise (an exercise session's lesions, for instructors' recorders; session
   * 60): written when the server runs with DDS Security, whose permissions keep it from
   * trainees (SECURED, the default), always (ALWAYS: a trusted bench without DDS Security,
   * where any participant can read it), or never (OFF). */
  palp_srv_session_exercise_policy session_exercise;
  int phantom_count;           /* phantoms and exercises: exercises come after the phantoms */
  int exercise_count;          /* of phantom[]: the last exercise_count entries */
  palp_srv_phantom_cfg phantom[PALP_SRV_MAX_PHANTOMS];
} palp_srv_config;

/* Defaults for every optional field; no phantoms. */
void palp_srv_config_defaults(palp_srv_config *cfg);

/* Parses JSON text; base_dir resolves relative paths ("" or NULL: as given).
 * Returns 0 or a negative PALP_E* code with a message naming the field in err. */
int palp_srv_config_parse(const char *json, const char *base_dir, palp_srv_config *cfg, char *err,
                          size_t errlen);
/* With server_number > 0, every phantom id must be at most PALP_SRV_MAX_LOCAL_ID
 * (also checked after command-line overrides). 0 or PALP_EINVAL. */
int palp_srv_config_check_ids(const palp_srv_config *cfg, char *err, size_t errlen);
/* One name for one phantom (session 82): a station picks a phantom by its name (--phantom-name,
 * --rejoin), so every hosted phantom's name must be non-empty and its own. names[0..count): the
 * hosted phantoms' names as served, the first `plain` of them config phantoms, the rest exercises
 * (named by their titles once loaded). PALP_EINVAL naming both entries, else 0. Run by the parse on
 * the phantoms, and by the start and --check once the exercises' titles are known. */
int palp_srv_config_check_names(const char *const *names, int count, int plain, char *err, size_t errlen);
/* Reads and parses a file; relative paths resolve against the file's directory. */
int palp_srv_config_load(const char *path, palp_srv_config *cfg, char *err, size_t errlen);

#endif
