/* fuzz_web_access.c - palp-web's access control on what a browser sends and what an instructor's
 * file says (web/access.c): the Cookie header (palp_web_cookie_get), the URL path of a file
 * request (palp_web_path_check, palp_web_mime), a token against the bridge's (palp_web_token_equal)
 * and the trainees' token file (palp_web_trainee_tokens_parse).
 *
 * Properties: a cookie's value is found only as `name=value` at the start of one of the header's
 * parts, copied whole and terminated inside the buffer; an accepted path is a file under the served
 * directory (starts with '/', no empty, "." or ".." component, only the served characters) and
 * nothing that is not one is accepted by accident of the checks' order; a token equals the bridge's
 * only byte for byte and length for length; an accepted token file names each trainee and token
 * once, every token valid and none the bridge's own.
 *
 * Input: three parts split at the first two NUL bytes: the Cookie header, the path, the token file
 * (the path also stands as a token). */
#include "access.h"
#include "fuzz_util.h"

static const char instructor[] = "instructor-0123456789abcdef";

/* An independent reading of the path rule (access.h), component by component. */
static int path_ok(const char *p) {
  const size_t n = strlen(p);
  if (p[0] != '/' || n >= 200) return 0;
  for (const char *c = p; *c; c++)
    if (!((*c >= 'A' && *c <= 'Z') || (*c >= 'a' && *c <= 'z') || (*c >= '0' && *c <= '9') || *c == '.' ||
          *c == '_' || *c == '/' || *c == '-'))
      return 0;
  if (strstr(p, "..")) return 0;
  for (const char *c = p; *c; c++) /* each component: not empty (but a final '/'), not starting with '.' */
    if (*c == '/' && (c[1] == '/' || c[1] == '.')) return 0;
  return 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *all = fuzz_cstr(data, size);
  const char *cookie = all, *path = "", *file = "";
  size_t a = strlen(all);
  if (a < size) {
    path = all + a + 1;
    const size_t b = strlen(path);
    if (a + 1 + b < size) file = path + b + 1;
  }

  /* the cookie */
  char v[64];
  memset(v, 'x', sizeof v);
  if (palp_web_cookie_get(cookie, "palp_token", v, sizeof v) == 0) {
    const size_t vl = strnlen(v, sizeof v);
    if (vl >= sizeof v) abort(); /* terminated inside the buffer */
    /* "palp_token=" + v at the header's start or after "; " or ";" */
    char want[80];
    snprintf(want, sizeof want, "palp_token=%s", v);
    int found = 0;
    for (const char *p = cookie; (p = strstr(p, want)) != NULL; p++) {
      const char *q = p;
      while (q > cookie && q[-1] == ' ') q--;
      if (q == cookie || q[-1] == ';') found = 1;
    }
    if (!found) {
      fprintf(stderr, "cookie value \"%s\" is not a palp_token part of \"%s\"\n", v, cookie);
      abort();
    }
    if (strchr(v, ';')) abort(); /* one part's value, never across parts */
  }

  /* the path */
  const int pc = palp_web_path_check(path);
  if ((pc == 0) != path_ok(path)) {
    fprintf(stderr, "path \"%s\": check %d, the rule says %d\n", path, pc, path_ok(path));
    abort();
  }
  const char *mime = palp_web_mime(path);
  if (mime && !strchr(path, '.')) abort();

  /* a token as the bridge compares it */
  const size_t pl = strlen(path);
  const int eq = palp_web_token_equal(instructor, path, pl);
  if (eq != (pl == strlen(instructor) && !memcmp(path, instructor, pl))) abort();

  /* the trainees' token file */
  static palp_web_trainee_token tt[PALP_WEB_TRAINEES_MAX];
  char err[256] = "";
  const int n = palp_web_trainee_tokens_parse(file, data[0] & 1 ? instructor : NULL, tt, 8, err, sizeof err);
  if (n < 0 && !err[0]) abort(); /* a refusal says why */
  if (n > 8) abort();
  for (int i = 0; i < n; i++) {
    if (palp_web_token_check(tt[i].token) != 0 || !tt[i].name[0] || strnlen(tt[i].name, sizeof tt[i].name) > 31) abort();
    if ((data[0] & 1) && !strcmp(tt[i].token, instructor)) abort();
    for (int k = 0; k < i; k++)
      if (!strcmp(tt[i].name, tt[k].name) || !strcmp(tt[i].token, tt[k].token)) abort();
  }
  free(all);
  return 0;
}
