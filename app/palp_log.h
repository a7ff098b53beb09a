/*
 * palp_log.h - levelled, timestamped log lines for every palp program.
 *
 *   2024-05-01T10:00:00.123Z INFO  palp-server: session 3 opened ...
 *
 * One palp_log per process, owned by main() and handed to the code that logs
 * (e.g. palp_srv_def.log): no global state, so tests can run several servers
 * in one process, each with its own log. Timestamps are UTC (ISO 8601, ms),
 * so lines from machines in different time zones sort together. A line is
 * written with one fwrite under a mutex: lines from threads never interleave.
 * The level is atomic, so a SIGHUP handler thread may change it while tick
 * threads log. Passing NULL as the log writes to stderr at every level, so
 * library code stays usable without one.
 */
#ifndef PALP_LOG_H
#define PALP_LOG_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>

typedef enum palp_log_level {
  PALP_LOG_ERROR = 0, /* the program or a session cannot go on */
  PALP_LOG_WARN = 1,  /* something was refused, clamped or degraded */
  PALP_LOG_INFO = 2,  /* lifecycle: start, sessions opened/closed, stop (the default) */
  PALP_LOG_DEBUG = 3  /* every join/leave, per-request detail */
} palp_log_level;

#define PALP_LOG_PATH_MAX 1024

typedef struct palp_log {
  char prog[32];
  atomic_int level;
  pthread_mutex_t mu;
  FILE *f;                       /* stderr, or the file at path */
  char path[PALP_LOG_PATH_MAX]; /* "" = stderr */
  /* Lines the file did not take (a full disk, an I/O error; under mu): each such line goes to stderr
   * too, and the failure is said there once (again after a line is written or the file re-opened). */
  unsigned long write_errors;
  int failing;
} palp_log;

/* path NULL or "" logs to stderr; otherwise appends to the file (created 0640).
 * Returns 0 or a negative PALP_E* code (the file cannot be opened), errno then saying why
 * (ENAMETOOLONG for a path of PALP_LOG_PATH_MAX or more). */
int palp_log_init(palp_log *l, const char *prog, palp_log_level level, const char *path);
void palp_log_close(palp_log *l);
/* Re-opens the log file (after logrotate moved it); a no-op on stderr.
 * On failure keeps the old stream and returns a negative code. */
int palp_log_reopen(palp_log *l);

void palp_log_set_level(palp_log *l, palp_log_level level);
palp_log_level palp_log_get_level(const palp_log *l);
int palp_log_enabled(const palp_log *l, palp_log_level level);
/* "error", "warn", "info", "debug" (also "warning"); 0 or PALP_EINVAL. */
int palp_log_parse_level(const char *s, palp_log_level *out);
const char *palp_log_level_name(palp_log_level level);

/* One line: timestamp, level, "prog: ", the message, newline. */
void palp_logf(palp_log *l, palp_log_level level, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

#define palp_log_error(l, ...) palp_logf((l), PALP_LOG_ERROR, __VA_ARGS__)
#define palp_log_warn(l, ...) palp_logf((l), PALP_LOG_WARN, __VA_ARGS__)
#define palp_log_info(l, ...) palp_logf((l), PALP_LOG_INFO, __VA_ARGS__)
#define palp_log_debug(l, ...) palp_logf((l), PALP_LOG_DEBUG, __VA_ARGS__)

/* A callback for code that reports lines without knowing palp_log (ctx is the
 * palp_log *, NULL for stderr): one warning line, e.g. palp_dds_refusals' emit. */
void palp_log_warn_line(void *ctx, const char *line);
/* The same at debug level (what a trainee station sets aside: palp_dds_refusals_focus). */
void palp_log_debug_line(void *ctx, const char *line);

/* A string from the network made safe for one log line: control bytes (a newline would forge a
 * line of its own, an ESC would drive the terminal), DEL and the backslash itself are written
 * as \xNN, so what is logged maps back to what came; cut to fit out (len >= 1), always
 * terminated. Returns out. */
char *palp_log_printable(const char *in, char *out, size_t len);
/* palp_log_printable of a network string into a buffer of the expression's own (a compound literal,
 * alive to the end of the enclosing block): 4x the field, so every byte fits escaped. For a 64-byte
 * field (a station id, a user name), and for a 128-byte one. */
typedef struct palp_log_field {
  char s[4 * 64];
} palp_log_field;
/* 1 if s begins with a C1 control U+0080..U+009F in UTF-8 (0xC2 0x80..0x9F): CSI (U+009B) and OSC
 * (U+009D) act on a terminal as ESC [ and ESC ] do. For the log's escapes and the station's
 * terminal-safe text alike. */
static inline int palp_utf8_c1_at(const char *s) {
  const unsigned char *u = (const unsigned char *)s;
  return u[0] == 0xC2 && u[1] >= 0x80 && u[1] <= 0x9F;
}
#define PALP_PRINTABLE(str) (palp_log_printable((str), (palp_log_field){{0}}.s, sizeof(palp_log_field)))
#define PALP_PRINTABLE_LONG(str) (palp_log_printable((str), (char[4 * 128]){0}, 4 * 128))

/* Formats the current UTC time as 2024-05-01T10:00:00.123Z into buf (>= 25 bytes). */
void palp_log_timestamp(char *buf, size_t len);

#endif
