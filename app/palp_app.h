/*
 * palp_app.h - what every palp program shares on its command line: its version,
 * where its data (configs, scenes, parameters) lives, which DDS config it uses,
 * and the common options (--version, --log-level, --verbose/--quiet,
 * --log-file, --dds-config).
 *
 * Data directory (docs/deploy.md), first that applies:
 *   1. $PALP_DATA_DIR (an error if it is set but not a directory);
 *   2. <directory of the executable>/../share/palp, the installed layout
 *      (bin/palp-server next to share/palp/config/...);
 *   3. <exe dir>/../../share/palp or <exe dir>/../../../share/palp if it holds
 *      the marker file "palp-build-tree": the build tree (CMake makes
 *      build/share/palp with a link to the source tree's config/), so programs
 *      run from build/ behave as before without any source path compiled in.
 * No path is compiled into a program: an installed binary can be moved with its
 * prefix (a relocatable install), and it never falls back to a source tree.
 */
#ifndef PALP_APP_H
#define PALP_APP_H

#include <stddef.h>
#include <stdio.h>

#include "palp_log.h"

#define PALP_APP_PATH_MAX 1024

/* "0.1.0+<git describe>" of this build. */
const char *palp_app_version(void);
/* Prints "prog version" and the model/wire contract it speaks, to f. */
void palp_app_print_version(FILE *f, const char *prog);

/* For programs with a command word (palp-review, palp-fem, palp-eval, palp-stats): if argv[1] is
 * exactly "--version", prints the version to stdout and returns 1 (the caller exits 0). Only there:
 * further on "--version" may be the value of another option (`--note "--version"` printed the
 * version and exited 0 without storing the note, until session 82), so a later one is taken by the
 * program's own option loop (palp_app_common_opt, PALP_APP_OPT_VERSION), which knows which options
 * take a value. */
int palp_app_handle_version(int argc, char **argv, const char *prog);

/* The data directory (see above) into buf. Returns 0 or a negative PALP_E*
 * code with a message naming what was tried in err. */
int palp_app_data_dir(char *buf, size_t len, char *err, size_t errlen);
/* <data dir>/rel into buf (rel e.g. "config/server.json"). */
int palp_app_data_path(const char *rel, char *buf, size_t len, char *err, size_t errlen);

/* Opens PATH for writing (created or truncated) as fopen(path, "w") does, but the file is its owner's
 * alone (mode 0600): reports and exports carry trainees' names and grades. An existing regular file is
 * made 0600 before it is truncated (since session 81: it kept its mode, a 0644 report stayed readable
 * by all); a device or pipe (/dev/null, /dev/stdout) is written as it is. NULL and errno on failure. */
FILE *palp_app_fopen_private(const char *path);
/* The same, but the file opened is first compared (st_dev, st_ino, after symlinks) with each of the
 * nkeep files keep[] names that exist: if it is one of them, nothing is truncated or changed, NULL with
 * errno EEXIST (palp-review: --out naming the session log itself, or its -wal or -shm, destroyed it). */
FILE *palp_app_fopen_private_except(const char *path, const char *const *keep, size_t nkeep);

/* Installs handler for SIGINT, SIGTERM and SIGHUP by sigaction with SA_RESTART (a read interrupted by one
 * goes on). Never signal(): built as ISO C (-std=c17), glibc's signal() has System V semantics, the
 * handler reset to the default at its first delivery, so the second SIGHUP (the second log rotation)
 * killed palp-web and palp-recorder with their sessions open (found 2026-12-06). sigaction also replaces
 * the SIG_IGN a shell gives a script's background jobs for SIGINT, so `kill -INT` stops them cleanly.
 * Returns 0, or -1 with errno set. */
int palp_app_on_signals(void (*handler)(int));

/* The one way every program chooses its DDS config, first that applies:
 *   flag      (--dds-config FILE): used even if CYCLONEDDS_URI is set;
 *   CYCLONEDDS_URI from the environment: left as it is;
 *   fallback  (e.g. the server.json "dds_config"), if not NULL;
 *   <data dir>/config/cyclonedds-loopback.xml, the installed loopback default.
 * Sets CYCLONEDDS_URI=file://<absolute path> for the chosen file. chosen (may be
 * NULL) receives the file or "CYCLONEDDS_URI=..." for the log. Returns 0 or a
 * negative PALP_E* code with a message in err (the file cannot be read). */
int palp_app_use_dds_config(const char *flag, const char *fallback, char *chosen, size_t chosen_len, char *err,
                            size_t errlen);

/* Whether a Cyclone DDS configuration keeps a participant on loopback: 1 when every network
 * interface it names (<NetworkInterface address=|name=>, <NetworkInterfaceAddress>) is
 * loopback (127.0.0.0/8, ::1, "lo", "localhost"), it names at least one, and every address it
 * sends to or has others send to (<Peer Address>, <ExternalNetworkAddress>) is loopback too;
 * 0 otherwise, including whatever cannot be told for sure (no interface: Cyclone picks one;
 * autodetermine; a ${VARIABLE}; a <Domain Id> other than "any"; an abbreviated name; XML this
 * reading cannot follow). Names are read as Cyclone reads them, case-insensitively; comments
 * and CDATA are not elements. why (may be NULL) says which element decided.
 * Fail-safe by design: "0" may be loopback after all, "1" never reaches the network. */
int palp_app_dds_xml_loopback_only(const char *xml, char *why, size_t whylen);

/* The same for the configuration CYCLONEDDS_URI holds now (after palp_app_use_dds_config): one
 * file:// URI or inline XML; anything else (several items, another scheme) is 0. */
int palp_app_dds_loopback_only(char *why, size_t whylen);

/* The options every program takes. */
typedef struct palp_app_opts {
  const char *prog;
  palp_log_level log_level;  /* --log-level, --verbose (debug), --quiet (warn); default info */
  const char *log_file;      /* --log-file FILE; NULL = stderr */
  const char *dds_config;    /* --dds-config FILE; NULL = see palp_app_use_dds_config */
  int version;               /* --version seen */
  int log_level_set;         /* --log-level, --verbose or --quiet given */
} palp_app_opts;

void palp_app_opts_init(palp_app_opts *o, const char *prog);
/* Looks at argv[*i]: if it is a common option (and, for those with a value,
 * argv[*i + 1]), records it, advances *i past its value and returns 1; returns
 * 0 for any other argument, and -1 (message on stderr) for a bad value.
 * which: a mask of PALP_APP_OPT_* the program accepts. */
#define PALP_APP_OPT_VERSION 1u
#define PALP_APP_OPT_LOG 2u     /* --log-level, --log-file */
#define PALP_APP_OPT_VERBOSE 4u /* --verbose, --quiet as aliases of --log-level debug / warn */
#define PALP_APP_OPT_DDS 8u     /* --dds-config */
int palp_app_common_opt(palp_app_opts *o, unsigned which, int argc, char **argv, int *i);
/* Usage lines for the accepted common options. */
void palp_app_common_usage(FILE *f, unsigned which);

#endif
