/* access.c - address, token and path checks of palp-web. */
#include "access.h"

#include <arpa/inet.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "palp.h" /* PALP_E* codes */

int palp_web_addr_is_loopback(const char *addr) {
  if (!addr) return 0;
  if (!strcmp(addr, "localhost")) return 1;
  struct in_addr a4;
  if (inet_pton(AF_INET, addr, &a4) == 1) return (ntohl(a4.s_addr) >> 24) == 127;
  struct in6_addr a6;
  if (inet_pton(AF_INET6, addr, &a6) == 1) return IN6_IS_ADDR_LOOPBACK(&a6) ? 1 : 0;
  return 0;
}

int palp_web_host_is_loopback(const char *host) {
  if (!host) return 0;
  char addr[64];
  const char *end;
  if (host[0] == '[') { /* [v6]:port */
    end = strchr(host, ']');
    if (!end || (size_t)(end - host - 1) >= sizeof addr) return 0;
    memcpy(addr, host + 1, (size_t)(end - host - 1));
    addr[end - host - 1] = '\0';
    end++;
  } else {
    end = strchr(host, ':');
    if (!end) end = host + strlen(host);
    if ((size_t)(end - host) >= sizeof addr) return 0;
    memcpy(addr, host, (size_t)(end - host));
    addr[end - host] = '\0';
  }
  if (*end == ':') { /* a port: 1-5 digits and nothing after */
    size_t d = strspn(end + 1, "0123456789");
    if (d < 1 || d > 5 || end[1 + d]) return 0;
  } else if (*end) {
    return 0;
  }
  return palp_web_addr_is_loopback(addr);
}

static int token_char(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
         c == '~' || c == '-';
}

int palp_web_token_check(const char *token) {
  if (!token) return PALP_EINVAL;
  size_t n = strlen(token);
  if (n < PALP_WEB_TOKEN_MIN || n > PALP_WEB_TOKEN_MAX) return PALP_EINVAL;
  for (size_t i = 0; i < n; i++)
    if (!token_char(token[i])) return PALP_EINVAL;
  return 0;
}

int palp_web_token_expired(double issued_s, double lifetime_s, double now_s) {
  if (lifetime_s == 0) return 0;
  /* written so that a NaN fails the comparison and so expires: a token of unknown age opens nothing */
  return !(now_s < issued_s + lifetime_s);
}

static double read_clock(clockid_t id) {
  struct timespec ts;
  if (clock_gettime(id, &ts) != 0) return NAN; /* an unknown time: every token reads as expired */
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
static double system_wall(void *user) {
  (void)user;
  return read_clock(CLOCK_REALTIME);
}
static double system_steady(void *user) {
  (void)user;
  return read_clock(CLOCK_BOOTTIME);
}

const palp_web_clock *palp_web_clock_system(void) {
  static const palp_web_clock c = {system_wall, system_steady, NULL};
  return &c;
}

palp_web_token_deadline palp_web_token_deadline_at_start(double issued_s, double lifetime_s, const palp_web_clock *c) {
  /* read together, so that the steady deadline stands for the same instant the wall clock names */
  const double wall = c->wall_s(c->user), steady = c->steady_s(c->user);
  double left = issued_s + lifetime_s - wall;
  if (!(left > 0)) left = 0; /* expired already, or a NaN: expired at start */
  else if (left > lifetime_s) left = lifetime_s;
  /* by the wall clock: when it will expire, or for one expired before start when it did */
  return (palp_web_token_deadline){
      .lifetime_s = lifetime_s, .steady_s = steady + left, .wall_s = left > 0 ? wall + left : issued_s + lifetime_s};
}

int palp_web_token_past(const palp_web_token_deadline *d, const palp_web_clock *c) {
  if (d->lifetime_s == 0) return 0;
  /* a NaN fails the comparison and so expires */
  return !(c->steady_s(c->user) < d->steady_s);
}

void palp_web_utc_text(double unix_s, char *out, size_t len) {
  struct tm tm;
  const time_t t = isfinite(unix_s) && fabs(unix_s) < 1e15 ? (time_t)floor(unix_s) : 0;
  if (!len) return;
  if (!isfinite(unix_s) || fabs(unix_s) >= 1e15 || !gmtime_r(&t, &tm) || !strftime(out, len, "%Y-%m-%dT%H:%M:%SZ", &tm))
    snprintf(out, len, "?");
}

int palp_web_token_equal(const char *want, const char *given, size_t len) {
  if (!want || !given) return 0;
  const size_t n = strlen(want);
  /* Compare every byte of `want` whatever the input, so the time says nothing about the prefix. */
  /* The lengths compared whole: folded into an unsigned, a length 2^32 longer than `want` read as
   * equal (not reachable through libwebsockets' bounded headers, but the function says "equals"). */
  unsigned diff = (n ^ len) != 0;
  for (size_t i = 0; i < n; i++) diff |= (unsigned char)want[i] ^ (unsigned char)(i < len ? given[i] : 0);
  return diff == 0;
}

int palp_web_cookie_get(const char *h, const char *name, char *out, size_t outlen) {
  if (!h || !name || !out || !outlen) return -1;
  const size_t nl = strlen(name);
  const char *p = h;
  while (*p) {
    while (*p == ' ' || *p == ';') p++;
    const char *end = strchr(p, ';');
    if (!end) end = p + strlen(p);
    if ((size_t)(end - p) > nl && !strncmp(p, name, nl) && p[nl] == '=') {
      const char *v = p + nl + 1;
      size_t vl = (size_t)(end - v);
      while (vl && v[vl - 1] == ' ') vl--;
      if (vl >= outlen) return -1;
      memcpy(out, v, vl);
      out[vl] = 0;
      return 0;
    }
    p = end;
  }
  return -1;
}

int palp_web_path_check(const char *path) {
  if (!path || path[0] != '/') return PALP_EINVAL;
  size_t n = strlen(path);
  if (n >= 200) return PALP_EINVAL;
  for (size_t i = 0; i < n; i++) {
    const char c = path[i];
    if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
          c == '/' || c == '-'))
      return PALP_EINVAL;
    if (c == '/' && (path[i + 1] == '/' || path[i + 1] == '.')) return PALP_EINVAL; /* "//", "/.", "/.." */
  }
  return strstr(path, "..") ? PALP_EINVAL : 0;
}

const char *palp_web_mime(const char *path) {
  const char *dot = path ? strrchr(path, '.') : NULL;
  if (!dot || strchr(dot, '/')) return NULL;
  if (!strcmp(dot, ".html")) return "text/html; charset=utf-8";
  if (!strcmp(dot, ".js")) return "text/javascript; charset=utf-8";
  if (!strcmp(dot, ".css")) return "text/css; charset=utf-8";
  if (!strcmp(dot, ".svg")) return "image/svg+xml";
  if (!strcmp(dot, ".png")) return "image/png";
  return NULL;
}

static int name_ok(const char *n, size_t len) {
  if (len < 1 || len > 31) return 0;
  for (size_t i = 0; i < len; i++)
    if (!((n[i] >= 'a' && n[i] <= 'z') || (n[i] >= '0' && n[i] <= '9') || n[i] == '_' || n[i] == '-')) return 0;
  return 1;
}

int palp_web_trainee_tokens_parse(const char *text, const char *instructor, palp_web_trainee_token *out, int max,
                                  char *err, size_t errlen) {
  int n = 0, line = 0;
  for (const char *p = text; p && *p;) {
    const char *eol = strchr(p, '\n');
    const size_t ll = eol ? (size_t)(eol - p) : strlen(p);
    ++line;
    char buf[256];
    if (ll >= sizeof buf) {
      snprintf(err, errlen, "line %d: longer than %zu characters", line, sizeof buf - 1);
      return PALP_EINVAL;
    }
    memcpy(buf, p, ll);
    buf[ll] = '\0';
    p = eol ? eol + 1 : NULL;
    if (ll && buf[ll - 1] == '\r') buf[ll - 1] = '\0';
    const char *a = buf + strspn(buf, " \t");
    if (!*a || *a == '#') continue;
    const size_t an = strcspn(a, " \t");
    const char *b = a + an + strspn(a + an, " \t");
    const size_t bn = strcspn(b, " \t");
    if (!name_ok(a, an) || !bn || b[bn + strspn(b + bn, " \t")] != '\0') {
      snprintf(err, errlen, "line %d: expected NAME TOKEN, NAME 1-31 of a-z 0-9 _ -", line);
      return PALP_EINVAL;
    }
    if (n >= max) {
      snprintf(err, errlen, "line %d: more than %d trainees", line, max);
      return PALP_EINVAL;
    }
    palp_web_trainee_token *t = &out[n];
    memcpy(t->name, a, an);
    t->name[an] = '\0';
    t->issued_s = 0;
    if (bn > PALP_WEB_TOKEN_MAX) {
      snprintf(err, errlen, "line %d (%s): the token must be %d-%d characters of A-Z a-z 0-9 . _ ~ -", line, t->name,
               PALP_WEB_TOKEN_MIN, PALP_WEB_TOKEN_MAX);
      return PALP_EINVAL;
    }
    memcpy(t->token, b, bn);
    t->token[bn] = '\0';
    if (palp_web_token_check(t->token) != 0) {
      snprintf(err, errlen, "line %d (%s): the token must be %d-%d characters of A-Z a-z 0-9 . _ ~ -", line, t->name,
               PALP_WEB_TOKEN_MIN, PALP_WEB_TOKEN_MAX);
      return PALP_EINVAL;
    }
    if (instructor && !strcmp(instructor, t->token)) {
      snprintf(err, errlen, "line %d (%s): the same token as the instructors' (--token or --token-file)", line, t->name);
      return PALP_EINVAL;
    }
    for (int k = 0; k < n; k++)
      if (!strcmp(out[k].name, t->name) || !strcmp(out[k].token, t->token)) {
        snprintf(err, errlen, "line %d (%s): %s given twice", line, t->name,
                 !strcmp(out[k].name, t->name) ? "the name" : "the token");
        return PALP_EINVAL;
      }
    n++;
  }
  return n;
}
