/* log.c - levelled, timestamped log lines (palp_log.h). */
#include "palp_log.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "palp.h"

static const char *const level_names[] = {"ERROR", "WARN", "INFO", "DEBUG"};

static FILE *open_append(const char *path) {
  /* 0640: session logs name trainees; the world need not read them. */
  int fd = open(path, O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0640);
  if (fd < 0) return NULL;
  FILE *f = fdopen(fd, "a");
  if (!f) {
    const int e = errno; /* the caller prints fdopen's reason, not close's */
    close(fd);
    errno = e;
  }
  return f;
}

int palp_log_init(palp_log *l, const char *prog, palp_log_level level, const char *path) {
  memset(l, 0, sizeof *l);
  snprintf(l->prog, sizeof l->prog, "%s", prog ? prog : "palp");
  atomic_init(&l->level, (int)level);
  pthread_mutex_init(&l->mu, NULL);
  l->f = stderr;
  if (path && path[0]) {
    if (strlen(path) >= sizeof l->path) { /* callers print strerror(errno): make it this reason */
      errno = ENAMETOOLONG;
      return PALP_EINVAL;
    }
    FILE *f = open_append(path);
    if (!f) return PALP_EIO;
    snprintf(l->path, sizeof l->path, "%s", path);
    l->f = f;
  }
  return PALP_OK;
}

void palp_log_close(palp_log *l) {
  if (!l) return;
  pthread_mutex_lock(&l->mu);
  if (l->f && l->f != stderr && fclose(l->f) != 0 && !l->failing) l->write_errors++;
  if (l->write_errors)
    fprintf(stderr, "%s: log file %s: %lu line(s) could not be written to it (they went to stderr)\n", l->prog,
            l->path, l->write_errors);
  l->f = stderr;
  pthread_mutex_unlock(&l->mu);
  pthread_mutex_destroy(&l->mu);
}

int palp_log_reopen(palp_log *l) {
  if (!l || !l->path[0]) return PALP_OK;
  FILE *f = open_append(l->path);
  if (!f) return PALP_EIO;
  pthread_mutex_lock(&l->mu);
  FILE *old = l->f;
  l->f = f;
  l->failing = 0; /* a new file: its first failure is said again */
  pthread_mutex_unlock(&l->mu);
  if (old && old != stderr) fclose(old);
  return PALP_OK;
}

void palp_log_set_level(palp_log *l, palp_log_level level) {
  if (l) atomic_store(&l->level, (int)level);
}

palp_log_level palp_log_get_level(const palp_log *l) {
  return l ? (palp_log_level)atomic_load(&((palp_log *)l)->level) : PALP_LOG_DEBUG;
}

int palp_log_enabled(const palp_log *l, palp_log_level level) { return (int)level <= (int)palp_log_get_level(l); }

int palp_log_parse_level(const char *s, palp_log_level *out) {
  static const struct {
    const char *name;
    palp_log_level level;
  } names[] = {{"error", PALP_LOG_ERROR}, {"warn", PALP_LOG_WARN}, {"warning", PALP_LOG_WARN},
               {"info", PALP_LOG_INFO},   {"debug", PALP_LOG_DEBUG}};
  for (size_t i = 0; s && i < sizeof names / sizeof names[0]; i++)
    if (!strcmp(s, names[i].name)) {
      *out = names[i].level;
      return PALP_OK;
    }
  return PALP_EINVAL;
}

const char *palp_log_level_name(palp_log_level level) {
  return level >= PALP_LOG_ERROR && level <= PALP_LOG_DEBUG ? level_names[level] : "?";
}

void palp_log_timestamp(char *buf, size_t len) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  struct tm tm;
  gmtime_r(&ts.tv_sec, &tm);
  /* strftime for the fields (an int year could be 11 digits to snprintf's analysis, which then
   * warns of truncation); the milliseconds appended */
  char day[32];
  if (!strftime(day, sizeof day, "%Y-%m-%dT%H:%M:%S", &tm)) day[0] = '\0';
  snprintf(buf, len, "%s.%03dZ", day, (int)(ts.tv_nsec / 1000000));
}

void palp_logf(palp_log *l, palp_log_level level, const char *fmt, ...) {
  if (!palp_log_enabled(l, level)) return;
  /* Format the whole line first: one write per line keeps threads' lines whole. */
  char line[2048];
  char ts[40];
  palp_log_timestamp(ts, sizeof ts);
  int n = snprintf(line, sizeof line, "%s %-5s %s: ", ts, palp_log_level_name(level), l ? l->prog : "palp");
  if (n < 0) return;
  va_list ap;
  va_start(ap, fmt);
  int m = vsnprintf(line + n, sizeof line - (size_t)n, fmt, ap);
  va_end(ap);
  size_t len = m < 0 ? (size_t)n : (size_t)n + (size_t)m;
  if (len > sizeof line - 2) len = sizeof line - 2; /* truncated: still one line */
  while (len > 0 && line[len - 1] == '\n') len--;
  line[len++] = '\n';
  if (!l) {
    fwrite(line, 1, len, stderr);
    return;
  }
  pthread_mutex_lock(&l->mu);
  errno = 0;
  const int ok = fwrite(line, 1, len, l->f) == len && fflush(l->f) == 0;
  if (!ok && l->f != stderr) {
    /* A full disk hid every later line, errors included, without a word (session 82's review): the
     * line goes to stderr as well, and the failure is said there once, not once a line. */
    const int e = errno ? errno : EIO;
    clearerr(l->f);
    l->write_errors++;
    if (!l->failing)
      fprintf(stderr, "%s: log file %s: cannot write to it: %s; its lines go to stderr too\n", l->prog, l->path,
              strerror(e));
    l->failing = 1;
    fwrite(line, 1, len, stderr);
  } else if (ok)
    l->failing = 0;
  pthread_mutex_unlock(&l->mu);
}

void palp_log_warn_line(void *ctx, const char *line) { palp_logf(ctx, PALP_LOG_WARN, "%s", line); }
void palp_log_debug_line(void *ctx, const char *line) { palp_logf(ctx, PALP_LOG_DEBUG, "%s", line); }

char *palp_log_printable(const char *in, char *out, size_t len) {
  size_t o = 0;
  int c1_tail = 0; /* the second byte of a C1 control's UTF-8 form */
  for (const unsigned char *c = (const unsigned char *)(in ? in : ""); *c; c++) {
    /* The C1 controls U+0080..U+009F, in UTF-8 0xC2 0x80..0x9F, are escapes too: CSI (U+009B) and OSC
     * (U+009D) clear a terminal's screen or retitle it as ESC [ and ESC ] do (session 80's review,
     * 2026-12-07: they passed). Other bytes >= 0x80 stay: UTF-8 text is kept as it is. */
    const int c1 = c1_tail || palp_utf8_c1_at((const char *)c);
    c1_tail = !c1_tail && c1;
    const int esc = *c < 0x20 || *c == 0x7f || *c == '\\' || c1;
    const size_t need = esc ? 4 : 1;
    if (o + need >= len) break; /* cut whole: never half an escape */
    if (esc)
      snprintf(out + o, 5, "\\x%02x", *c);
    else
      out[o] = (char)*c;
    o += need;
  }
  out[o] = 0;
  return out;
}
