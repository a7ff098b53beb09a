/* access.c - address, token and path checks of palp-web. */
#include "access.h"

#include <arpa/inet.h>
#include <string.h>

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

int palp_web_token_equal(const char *want, const char *given, size_t len) {
  if (!want || !given) return 0;
  const size_t n = strlen(want);
  /* Compare every byte of `want` whatever the input, so the time says nothing about the prefix. */
  unsigned diff = (unsigned)(n ^ len);
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
