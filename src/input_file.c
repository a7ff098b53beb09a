/*
 * input_file.c - a file a user hands the product, read whole and bounded; its JSON read strictly
 * (palp_input_file.h).
 */
#include "palp_input_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "palp.h"

/* "1 MiB", "64 kB", "1000 bytes": the bound as a user wrote it down */
static void size_text(size_t b, char *out, size_t n) {
  if (b >= ((size_t)1 << 20) && b % ((size_t)1 << 20) == 0) snprintf(out, n, "%zu MiB", b >> 20);
  else if (b >= 1024 && b % 1024 == 0) snprintf(out, n, "%zu kB", b >> 10);
  else snprintf(out, n, "%zu bytes", b);
}

static int say(char *why, size_t whylen, int code, const char *text) {
  if (why && whylen) snprintf(why, whylen, "%s", text);
  return code;
}

int palp_input_file_read(const char *path, size_t max_bytes, char **out, size_t *len, char *why, size_t whylen) {
  char msg[160], bound[32];
  size_text(max_bytes, bound, sizeof bound);
  *out = NULL;
  if (len) *len = 0;
  if (!path || !*path) return say(why, whylen, PALP_EINVAL, "no file named");
  /* O_NONBLOCK: opening a FIFO for reading blocks until a writer comes; a device may block too. Only
   * a regular file is read, so the flag never changes how its bytes come. */
  const int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    snprintf(msg, sizeof msg, "cannot open: %s", strerror(errno));
    return say(why, whylen, PALP_EIO, msg);
  }
  struct stat st;
  if (fstat(fd, &st) != 0) {
    snprintf(msg, sizeof msg, "cannot read: %s", strerror(errno));
    close(fd);
    return say(why, whylen, PALP_EIO, msg);
  }
  if (!S_ISREG(st.st_mode)) {
    close(fd);
    return say(why, whylen, PALP_EINVAL, S_ISDIR(st.st_mode) ? "a directory, not a file" : "not a regular file");
  }
  if ((unsigned long long)st.st_size > max_bytes) {
    close(fd);
    snprintf(msg, sizeof msg, "larger than %s (%lld bytes)", bound, (long long)st.st_size);
    return say(why, whylen, PALP_EINVAL, msg);
  }
  /* room for what fstat said and 4 kB of growth, within the bound, and the terminating NUL */
  const size_t want = (size_t)st.st_size + 4096, cap = (want < max_bytes ? want : max_bytes) + 1;
  char *buf = malloc(cap);
  if (!buf) {
    close(fd);
    return say(why, whylen, PALP_ENOMEM, "out of memory");
  }
  size_t n = 0;
  while (n < cap - 1) {
    const ssize_t r = read(fd, buf + n, cap - 1 - n);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      snprintf(msg, sizeof msg, "read error: %s", strerror(errno));
      close(fd);
      free(buf);
      return say(why, whylen, PALP_EIO, msg);
    }
    if (r == 0) break;
    n += (size_t)r;
  }
  char extra;
  const int more = n == cap - 1 && read(fd, &extra, 1) == 1; /* the buffer full and still bytes */
  close(fd);
  if (more) {
    free(buf);
    if (n >= max_bytes) snprintf(msg, sizeof msg, "larger than %s", bound);
    else snprintf(msg, sizeof msg, "grew while it was read");
    return say(why, whylen, PALP_EINVAL, msg);
  }
  const char *nul = memchr(buf, 0, n);
  if (nul) {
    snprintf(msg, sizeof msg, "a NUL byte at byte %zu: not a text file", (size_t)(nul - buf));
    free(buf);
    return say(why, whylen, PALP_EINVAL, msg);
  }
  buf[n] = 0;
  *out = buf;
  if (len) *len = n;
  return PALP_OK;
}

/* ---- strict JSON --------------------------------------------------------------------------------- */

static int by_name(const void *a, const void *b) {
  return strcmp((*(const cJSON *const *)a)->string, (*(const cJSON *const *)b)->string);
}

/* The first object under item (depth first) with a key twice: 1 and its path and key in why. cJSON
 * bounds the nesting (CJSON_NESTING_LIMIT, 1000), so the recursion is bounded; each object's names
 * are sorted (n log n), so a file of 100,000 keys costs no quadratic pass. */
static int duplicate_key(const cJSON *item, char *path, size_t pathlen, size_t at, char *why, size_t whylen) {
  if (cJSON_IsObject(item)) {
    size_t n = 0;
    for (const cJSON *c = item->child; c; c = c->next) n++;
    if (n > 1) {
      const cJSON **v = malloc(n * sizeof *v);
      if (!v) return say(why, whylen, 1, "out of memory");
      size_t i = 0;
      for (const cJSON *c = item->child; c; c = c->next) v[i++] = c;
      qsort(v, n, sizeof *v, by_name);
      for (i = 1; i < n; i++)
        if (!strcmp(v[i - 1]->string, v[i]->string)) {
          if (why && whylen)
            snprintf(why, whylen, "key \"%.60s\" given twice (in %s): which one was meant cannot be told",
                     v[i]->string, at ? path : "the top-level object");
          free(v);
          return 1;
        }
      free(v);
    }
  }
  int index = 0;
  for (const cJSON *c = item->child; c; c = c->next, index++) {
    size_t m;
    if (c->string) m = (size_t)snprintf(path + at, pathlen - at, "%s%s", at ? "." : "", c->string);
    else m = (size_t)snprintf(path + at, pathlen - at, "[%d]", index);
    const size_t next = at + m < pathlen ? at + m : pathlen - 1;
    if (duplicate_key(c, path, pathlen, next, why, whylen)) return 1;
    path[at] = 0;
  }
  return 0;
}

cJSON *palp_json_parse_strict(const char *text, char *why, size_t whylen) {
  if (!text) {
    say(why, whylen, PALP_EINVAL, "no text");
    return NULL;
  }
  const char *end = NULL;
  cJSON *root = cJSON_ParseWithOpts(text, &end, 0);
  if (!root) {
    /* where, as an editor counts it (session 90's review: "near \"},\"" alone named no place in a
     * 200-line classroom config); from the parse's own end, which cJSON sets to the error on failure
     * (its global cJSON_GetErrorPtr is shared by every thread that parses) */
    const char *at = end ? end : cJSON_GetErrorPtr();
    long line = 1, col = 1;
    for (const char *p = text; at && p < at && *p; p++) {
      if (*p == '\n') line++, col = 1;
      else col++;
    }
    if (why && whylen) snprintf(why, whylen, "not valid JSON at line %ld, column %ld, near \"%.24s\"", line, col, at ? at : "");
    return NULL;
  }
  while (end && (*end == ' ' || *end == '\t' || *end == '\n' || *end == '\r')) end++;
  if (end && *end) {
    if (why && whylen) snprintf(why, whylen, "text after the JSON value, near \"%.24s\"", end);
    cJSON_Delete(root);
    return NULL;
  }
  char path[256] = "";
  if (duplicate_key(root, path, sizeof path, 0, why, whylen)) {
    cJSON_Delete(root);
    return NULL;
  }
  return root;
}
