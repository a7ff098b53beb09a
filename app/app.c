/* app.c - version, data directory, DDS config choice and common options (palp_app.h). */
#define _DEFAULT_SOURCE /* realpath */
#include "palp_app.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "palp.h"

#ifndef PALP_VERSION_STRING
#define PALP_VERSION_STRING "unknown"
#endif

const char *palp_app_version(void) { return PALP_VERSION_STRING; }

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
