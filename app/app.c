/* app.c - version, data directory, DDS config choice and common options (palp_app.h). */
#define _DEFAULT_SOURCE /* realpath */
#include "palp_app.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "palp.h"

void palp_app_print_version(FILE *f, const char *prog) {
  fprintf(f, "%s %s\n", prog, palp_app_version());
}

int palp_app_handle_version(int argc, char **argv, const char *prog) {
  for (int i = 1; i < argc; i++)
    if (!strcmp(argv[i], "--version")) {
      palp_app_print_version(stdout, prog);
      return 1;
    }
  return 0;
}

static int is_dir(const char *p) {
  struct stat st;
  return stat(p, &st) == 0 && S_ISDIR(st.st_mode);
}

static int is_file(const char *p) {
  struct stat st;
  return stat(p, &st) == 0 && S_ISREG(st.st_mode);
}

int palp_app_data_dir(char *buf, size_t len, char *err, size_t errlen) {
  const char *env = getenv("PALP_DATA_DIR");
  if (env && env[0]) {
    if (!is_dir(env)) {
      snprintf(err, errlen, "PALP_DATA_DIR=%s is not a directory", env);
      return PALP_EIO;
    }
    if ((size_t)snprintf(buf, len, "%s", env) >= len) return PALP_EINVAL;
    return PALP_OK;
  }
  char exe[PATH_MAX];
  ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n <= 0) {
    snprintf(err, errlen, "cannot find the program's own path (/proc/self/exe): %s; set PALP_DATA_DIR",
             strerror(errno));
    return PALP_EIO;
  }
  exe[n] = 0;
  char *slash = strrchr(exe, '/');
  if (slash) *slash = 0;
  /* Installed layout first, then the build tree (marked, so an installed program
   * never wanders into some other tree two levels up). */
  static const char *const up[] = {"/..", "/../..", "/../../.."};
  for (int k = 0; k < 3; k++) {
    char cand[PATH_MAX + 64], marker[PATH_MAX + 96], real[PATH_MAX];
    snprintf(cand, sizeof cand, "%s%s/share/palp", exe, up[k]);
    snprintf(marker, sizeof marker, "%s/palp-build-tree", cand);
    if (!is_dir(cand) || (k > 0 && !is_file(marker))) continue;
    const char *use = realpath(cand, real) ? real : cand;
    if ((size_t)snprintf(buf, len, "%s", use) >= len) return PALP_EINVAL;
    return PALP_OK;
  }
  snprintf(err, errlen, "no data directory: %s/../share/palp does not exist; set PALP_DATA_DIR", exe);
  return PALP_EIO;
}

int palp_app_data_path(const char *rel, char *buf, size_t len, char *err, size_t errlen) {
  char dir[PATH_MAX];
  int rc = palp_app_data_dir(dir, sizeof dir, err, errlen);
  if (rc < 0) return rc;
  char joined[PATH_MAX + 256], real[PATH_MAX];
  snprintf(joined, sizeof joined, "%s/%s", dir, rel);
  /* Through the build tree's link to the sources, so paths in messages and the
   * config's relative paths read as they always did. */
  const char *use = realpath(joined, real) ? real : joined;
  if ((size_t)snprintf(buf, len, "%s", use) >= len) {
    snprintf(err, errlen, "%s: path too long", use);
    return PALP_EINVAL;
  }
  return PALP_OK;
}

static int set_uri(const char *path, char *chosen, size_t chosen_len, char *err, size_t errlen) {
  char abs[PATH_MAX];
  if (access(path, R_OK) != 0 || !realpath(path, abs)) {
    snprintf(err, errlen, "DDS config %s: %s", path, strerror(errno));
    return PALP_EIO;
  }
  char uri[PATH_MAX + 16];
  if ((size_t)snprintf(uri, sizeof uri, "file://%s", abs) >= sizeof uri || setenv("CYCLONEDDS_URI", uri, 1)) {
    snprintf(err, errlen, "DDS config %s: path too long", path);
    return PALP_EINVAL;
  }
  if (chosen) snprintf(chosen, chosen_len, "%s", abs);
  return PALP_OK;
}

int palp_app_use_dds_config(const char *flag, const char *fallback, char *chosen, size_t chosen_len, char *err,
                            size_t errlen) {
  if (flag && flag[0]) return set_uri(flag, chosen, chosen_len, err, errlen);
  const char *env = getenv("CYCLONEDDS_URI");
  if (env && env[0]) {
    if (chosen) snprintf(chosen, chosen_len, "CYCLONEDDS_URI=%s", env);
    return PALP_OK;
  }
  if (fallback && fallback[0]) return set_uri(fallback, chosen, chosen_len, err, errlen);
  char def[PATH_MAX];
  int rc = palp_app_data_path("config/cyclonedds-loopback.xml", def, sizeof def, err, errlen);
  if (rc < 0) return rc;
  return set_uri(def, chosen, chosen_len, err, errlen);
}

void palp_app_opts_init(palp_app_opts *o, const char *prog) {
  memset(o, 0, sizeof *o);
  o->prog = prog;
  o->log_level = PALP_LOG_INFO;
}

int palp_app_common_opt(palp_app_opts *o, unsigned which, int argc, char **argv, int *i) {
  const char *a = argv[*i], *v = *i + 1 < argc ? argv[*i + 1] : NULL;
  if ((which & PALP_APP_OPT_VERSION) && !strcmp(a, "--version")) {
    o->version = 1;
    return 1;
  }
  if ((which & PALP_APP_OPT_VERBOSE) && !strcmp(a, "--verbose")) {
    o->log_level = PALP_LOG_DEBUG;
    o->log_level_set = 1;
    return 1;
  }
  if ((which & PALP_APP_OPT_VERBOSE) && !strcmp(a, "--quiet")) {
    o->log_level = PALP_LOG_WARN;
    o->log_level_set = 1;
    return 1;
  }
  const char **dst = NULL;
  if ((which & PALP_APP_OPT_LOG) && !strcmp(a, "--log-file")) dst = &o->log_file;
  else if ((which & PALP_APP_OPT_DDS) && !strcmp(a, "--dds-config")) dst = &o->dds_config;
  else if ((which & PALP_APP_OPT_LOG) && !strcmp(a, "--log-level")) {
    if (!v || palp_log_parse_level(v, &o->log_level) < 0) {
      fprintf(stderr, "%s: --log-level: expected error, warn, info or debug, got \"%s\"\n", o->prog, v ? v : "");
      return -1;
    }
    o->log_level_set = 1;
    (*i)++;
    return 1;
  }
  if (!dst) return 0;
  if (!v || !v[0]) {
    fprintf(stderr, "%s: %s: missing value\n", o->prog, a);
    return -1;
  }
  *dst = v;
  (*i)++;
  return 1;
}

void palp_app_common_usage(FILE *f, unsigned which) {
  if (which & PALP_APP_OPT_DDS)
    fputs("  --dds-config FILE    Cyclone DDS XML (default: $CYCLONEDDS_URI, else the installed\n"
          "                       loopback config <data>/config/cyclonedds-loopback.xml)\n",
          f);
  if (which & PALP_APP_OPT_LOG)
    fputs("  --log-level LEVEL    error, warn, info (default) or debug\n"
          "  --log-file FILE      append log lines to FILE instead of stderr (palp-server and palp-recorder re-open it on SIGHUP)\n",
          f);
  if (which & PALP_APP_OPT_VERBOSE) fputs("  --verbose, --quiet   aliases of --log-level debug / warn\n", f);
  if (which & PALP_APP_OPT_VERSION) fputs("  --version            print the version and exit\n", f);
  fputs("  data directory: $PALP_DATA_DIR, else <program dir>/../share/palp\n", f);
}

/* ---- is a DDS configuration loopback-only? ------------------------------------------------ */

static int loopback_value(const char *v, size_t n) {
  if (n == 9 && !strncmp(v, "localhost", 9)) return 1;
  if (n == 2 && !strncmp(v, "lo", 2)) return 1;
  if (n == 3 && !strncmp(v, "::1", 3)) return 1;
  if (n > 4 && !strncmp(v, "127.", 4)) {
    for (size_t k = 4; k < n; k++)
      if (!isdigit((unsigned char)v[k]) && v[k] != '.') return 0;
    return 1;
  }
  return 0;
}

/* The value of attribute name="..." (or '...') inside the tag [t, end); NULL if absent. */
static const char *attr(const char *t, const char *end, const char *name, size_t *n) {
  const size_t ln = strlen(name);
  for (const char *p = t; p + ln + 2 < end; p++) {
    if (strncmp(p, name, ln) != 0 || !isspace((unsigned char)p[-1])) continue;
    const char *q = p + ln;
    while (q < end && isspace((unsigned char)*q)) q++;
    if (q >= end || *q != '=') continue;
    q++;
    while (q < end && isspace((unsigned char)*q)) q++;
    if (q >= end || (*q != '"' && *q != '\'')) continue;
    const char quote = *q++;
    const char *e = memchr(q, quote, (size_t)(end - q));
    if (!e) return NULL;
    *n = (size_t)(e - q);
    return q;
  }
  return NULL;
}

static int scope_why(char *why, size_t len, int rc, const char *fmt, const char *v, size_t n) {
  if (why && len) snprintf(why, len, fmt, (int)(n > 80 ? 80 : n), v);
  return rc;
}

int palp_app_dds_xml_loopback_only(const char *xml, char *why, size_t whylen) {
  if (why && whylen) why[0] = '\0';
  if (!xml) return 0;
  /* comments out: a commented-out interface must not count either way */
  char *x = strdup(xml);
  if (!x) return 0;
  for (char *c; (c = strstr(x, "<!--"));) {
    char *e = strstr(c + 4, "-->");
    if (!e) {
      *c = '\0';
      break;
    }
    memmove(c, e + 3, strlen(e + 3) + 1);
  }
  int named = 0, rc = 1;
  for (const char *p = x; rc && (p = strstr(p, "<NetworkInterface")); p++) {
    const char *tag = p + 17, *end = strchr(tag, '>');
    if (!end) break;
    size_t n = 0;
    const char *v;
    if (!strncmp(tag, "Address", 7)) { /* <NetworkInterfaceAddress>VALUE</...>, the older form */
      v = end + 1;
      const char *e = strchr(v, '<');
      n = e ? (size_t)(e - v) : 0;
      while (n && isspace((unsigned char)*v)) v++, n--;
      while (n && isspace((unsigned char)v[n - 1])) n--;
      named = 1;
      if (!loopback_value(v, n)) rc = scope_why(why, whylen, 0, "<NetworkInterfaceAddress>%.*s", v, n);
      continue;
    }
    if (!isspace((unsigned char)*tag) && *tag != '/' && *tag != '>') continue; /* NetworkInterfaces? not a tag of ours */
    named = 1;
    if ((v = attr(tag, end, "autodetermine", &n)) && n == 4 && !strncmp(v, "true", 4)) {
      rc = scope_why(why, whylen, 0, "<NetworkInterface autodetermine=\"%.*s\">", v, n);
    } else if ((v = attr(tag, end, "address", &n)) || (v = attr(tag, end, "name", &n))) {
      if (!loopback_value(v, n)) rc = scope_why(why, whylen, 0, "<NetworkInterface %.*s> is not loopback", v, n);
    } else {
      rc = scope_why(why, whylen, 0, "a <NetworkInterface>%.*s without address or name", "", 0);
    }
  }
  free(x);
  if (rc && !named) return scope_why(why, whylen, 0, "no <NetworkInterface>: Cyclone DDS picks one%.*s", "", 0);
  if (rc) scope_why(why, whylen, 1, "every <NetworkInterface> is loopback%.*s", "", 0);
  return rc;
}

int palp_app_dds_loopback_only(char *why, size_t whylen) {
  const char *uri = getenv("CYCLONEDDS_URI");
  if (why && whylen) why[0] = '\0';
  if (!uri || !uri[0]) return scope_why(why, whylen, 0, "CYCLONEDDS_URI is not set: Cyclone DDS's defaults%.*s", "", 0);
  while (isspace((unsigned char)*uri)) uri++;
  if (uri[0] == '<') return palp_app_dds_xml_loopback_only(uri, why, whylen);
  if (strncmp(uri, "file://", 7) != 0 || strchr(uri, ','))
    return scope_why(why, whylen, 0, "CYCLONEDDS_URI=%.*s is not one file", uri, strlen(uri));
  FILE *f = fopen(uri + 7, "r");
  if (!f) return scope_why(why, whylen, 0, "%.*s cannot be read", uri + 7, strlen(uri + 7));
  char *buf = NULL;
  size_t cap = 0, len = 0;
  for (;;) {
    if (len + 4097 > cap) {
      char *nb = realloc(buf, cap + 65536);
      if (!nb || cap > (1u << 22)) { /* a 4 MB DDS config is not one */
        free(nb ? nb : buf);
        fclose(f);
        return scope_why(why, whylen, 0, "%.*s is too large to read", uri + 7, strlen(uri + 7));
      }
      buf = nb;
      cap += 65536;
    }
    const size_t got = fread(buf + len, 1, 4096, f);
    len += got;
    if (got < 4096) break;
  }
  fclose(f);
  buf[len] = '\0';
  const int rc = palp_app_dds_xml_loopback_only(buf, why, whylen);
  free(buf);
  return rc;
}

FILE *palp_app_fopen_private(const char *path) {
  const int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) return NULL;
  FILE *f = fdopen(fd, "w");
  if (!f) {
    const int e = errno;
    close(fd);
    errno = e;
  }
  return f;
}
