/* app.c - version, data directory, DDS config choice and common options (palp_app.h). */
#define _DEFAULT_SOURCE /* realpath */
#include "palp_app.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <arpa/inet.h>
#include <sys/stat.h>
#include <unistd.h>

#include "palp.h"

void palp_app_print_version(FILE *f, const char *prog) {
  fprintf(f, "%s %s\n", prog, palp_app_version());
}

int palp_app_handle_version(int argc, char **argv, const char *prog) {
  if (argc > 1 && !strcmp(argv[1], "--version")) {
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
  /* a directory (an empty "dds_config" resolves to the configuration's own) or a FIFO is no XML file:
   * said here, not by Cyclone at the participant's creation (session 81) */
  if (!is_file(abs)) {
    snprintf(err, errlen, "DDS config %s: not a regular file (a Cyclone DDS XML configuration)", path);
    return PALP_EINVAL;
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
          "  --log-file FILE      append log lines to FILE instead of stderr (palp-server, palp-recorder\n"
          "                       and palp-web re-open it on SIGHUP)\n",
          f);
  if (which & PALP_APP_OPT_VERBOSE) fputs("  --verbose, --quiet   aliases of --log-level debug / warn\n", f);
  if (which & PALP_APP_OPT_VERSION) fputs("  --version            print the version and exit\n", f);
  fputs("  data directory: $PALP_DATA_DIR, else <program dir>/../share/palp\n", f);
}

/* ---- is a DDS configuration loopback-only? ------------------------------------------------ */
/* The XML is read as Cyclone DDS 0.10 reads it (ddsrt xmlparser, ddsi_config), since a difference
 * is a way past the check: element and attribute names are [A-Za-z][A-Za-z0-9_:-]* compared
 * case-insensitively, and in XML given inline in CYCLONEDDS_URI an unambiguous prefix of a name
 * stands for it; attribute values are quoted with ", ' or typographic quotes and may hold '<' and
 * '>'; comments may sit between any two tokens and inside text; CDATA is text. */

static int loopback_value(const char *v, size_t n) {
  if (n == 9 && !strncmp(v, "localhost", 9)) return 1;
  if (n == 2 && !strncmp(v, "lo", 2)) return 1;
  if (n == 3 && !strncmp(v, "::1", 3)) return 1;
  /* a whole dotted address in 127.0.0.0/8: "127.0.0.256" or "127..1" is no address, and Cyclone
   * takes such a string for a host name to look up, which a resolver's search list may send
   * anywhere (session 77's review; it passed as "127." and digits) */
  char a[INET_ADDRSTRLEN];
  struct in_addr in;
  if (n < sizeof a) {
    memcpy(a, v, n);
    a[n] = '\0';
    if (inet_pton(AF_INET, a, &in) == 1) return (ntohl(in.s_addr) >> 24) == 127;
  }
  return 0;
}

/* A <Peer Address>: Cyclone sends discovery there, so it must be loopback too; it may end in
 * ":PORT" ("[::1]:PORT" for IPv6). */
static int loopback_peer(const char *v, size_t n) {
  size_t host = n, k;
  if (n > 2 && v[0] == '[') {
    const char *e = memchr(v, ']', n);
    if (!e) return 0;
    host = (size_t)(e - v) + 1;
  } else if (!loopback_value(v, n)) {
    const char *c = memchr(v, ':', n);
    host = c ? (size_t)(c - v) : n;
  }
  if (host < n) { /* ":PORT": digits only */
    if (v[host] != ':' || host + 1 == n) return 0;
    for (k = host + 1; k < n; k++)
      if (!isdigit((unsigned char)v[k])) return 0;
  }
  if (host == 2 && !strncmp(v, "lo", 2)) return 0; /* an interface's name, not a host's */
  return v[0] == '[' ? loopback_value(v + 1, host - 2) : loopback_value(v, host);
}

/* <MulticastRecvNetworkInterfaceAddresses>: "preferred" (the interface chosen, loopback here), "none",
 * empty, or a comma-separated list of loopback addresses; "any" and "all" are not. */
static int mc_recv_loopback(const char *v, size_t n) {
  if (!n || (n == 9 && !strncasecmp(v, "preferred", 9)) || (n == 4 && !strncasecmp(v, "none", 4))) return 1;
  for (size_t s = 0; s <= n;) {
    size_t e = s;
    while (e < n && v[e] != ',') e++;
    size_t a = s, b = e;
    while (a < b && (v[a] == ' ' || v[a] == '\t')) a++;
    while (b > a && (v[b - 1] == ' ' || v[b - 1] == '\t')) b--;
    if (!loopback_value(v + a, b - a) || (b - a == 2 && !strncmp(v + a, "lo", 2))) return 0;
    s = e + 1;
  }
  return 1;
}

static int xml_space(int c) {
  return c == ' ' || c == '\t' || c == '\v' || c == '\r' || c == '\n';
}

static int xml_namec(int c) {
  return isalnum((unsigned char)c) || c == '_' || c == '-' || c == ':';
}

/* Past marker after p, or the end of the text when it never comes (Cyclone stops there too). */
static const char *xml_past(const char *p, const char *marker) {
  const char *e = strstr(p, marker);
  return e ? e + strlen(marker) : p + strlen(p);
}

static const char *xml_blank(const char *p) {
  for (;;) {
    while (xml_space(*p)) p++;
    if (strncmp(p, "<!--", 4) != 0) return p;
    p = xml_past(p + 4, "-->");
  }
}

/* name[0, n) is word (1), a shorter prefix of it (-1: Cyclone takes it for word in inline XML), or neither (0). */
static int xml_name_is(const char *name, size_t n, const char *word) {
  const size_t w = strlen(word);
  if (!n || n > w || strncasecmp(name, word, n) != 0) return 0;
  return n == w ? 1 : -1;
}

/* The quoted value at p into [*v, *v + *n); past it, or NULL when p holds no quoted value. */
static const char *xml_quoted(const char *p, const char **v, size_t *n) {
  char q[4] = {0};
  if (*p == '"' || *p == '\'') q[0] = *p++;
  else if (!strncmp(p, "\xe2\x80\x9c", 3) || !strncmp(p, "\xe2\x80\x98", 3)) { /* closed by U+201D, U+2019 */
    memcpy(q, p, 3);
    q[2]++;
    p += 3;
  } else return NULL;
  const char *e = strstr(p, q);
  if (!e) return NULL;
  *v = p;
  *n = (size_t)(e - p);
  return e + strlen(q);
}

static int scope_why(char *why, size_t len, int rc, const char *fmt, const char *v, size_t n) {
  if (why && len) snprintf(why, len, fmt, (int)(n > 80 ? 80 : n), v);
  return rc;
}

/* The elements that decide where Cyclone sends: their attributes that do, or (none) their text. */
enum { EL_DOMAIN, EL_ID, EL_IFACE, EL_IFACE_ADDR, EL_PEER, EL_EXTERNAL, EL_MC_RECV, EL_OTHER };
static const struct {
  const char *name;
  int el;
  const char *attr[3];
} scope_el[] = {
    {"Domain", EL_DOMAIN, {"Id"}},
    {"DDSI2", EL_DOMAIN, {"Id"}}, /* the old names of <Domain> */
    {"DDSI2E", EL_DOMAIN, {"Id"}},
    {"Id", EL_ID, {NULL}}, /* <Domain><Id>, the old form of <Domain Id> */
    {"NetworkInterface", EL_IFACE, {"address", "name", "autodetermine"}},
    {"NetworkInterfaceAddress", EL_IFACE_ADDR, {NULL}},
    {"Peer", EL_PEER, {"Address"}},
    {"ExternalNetworkAddress", EL_EXTERNAL, {NULL}},
    /* where multicast is received: "any" or "all" join the groups on other interfaces than the one
     * chosen, so that other hosts' traffic reaches the process (session 77's review) */
    {"MulticastRecvNetworkInterfaceAddresses", EL_MC_RECV, {NULL}},
};

/* Attribute a[0, an) = v[0, n) of element s: 1 if it keeps Cyclone on loopback or does not decide. */
static int scope_attr(size_t s, const char *a, size_t an, const char *v, size_t n, char *why, size_t whylen) {
  const int el = scope_el[s].el;
  for (int k = 0; k < 3 && scope_el[s].attr[k]; k++) {
    const int is = xml_name_is(a, an, scope_el[s].attr[k]);
    if (is < 0) return scope_why(why, whylen, 0, "the attribute %.*s, which Cyclone DDS may read as a network setting", a, an);
    if (!is) continue;
    if (el == EL_DOMAIN && !(n == 3 && !strncasecmp(v, "any", 3))) /* Cyclone ignores it on other domains */
      return scope_why(why, whylen, 0, "<Domain Id=\"%.*s\">: palp cannot tell it is the domain it runs on", v, n);
    if (el == EL_IFACE && k == 2 && !(n == 5 && !strncasecmp(v, "false", 5)))
      return scope_why(why, whylen, 0, "<NetworkInterface autodetermine=\"%.*s\">", v, n);
    if (el == EL_IFACE && k < 2 && !loopback_value(v, n))
      return scope_why(why, whylen, 0, "<NetworkInterface %.*s> is not loopback", v, n);
    if (el == EL_PEER && !loopback_peer(v, n))
      return scope_why(why, whylen, 0, "<Peer Address=\"%.*s\"> is not loopback: discovery is sent there", v, n);
    return 1;
  }
  return 1;
}

/* The text of the element whose content starts at p, as Cyclone gathers it (comments out, CDATA in,
 * blanks trimmed) into v[0, *n); 0 if it does not fit. */
static int xml_text(const char *p, char *v, size_t len, size_t *n) {
  int fits = 1;
  *n = 0;
  while (*p) {
    const char *s = p, *e;
    if (!strncmp(p, "<!--", 4)) {
      p = xml_past(p + 4, "-->");
      continue;
    }
    if (!strncmp(p, "<![CDATA[", 9)) {
      s = p + 9;
      e = strstr(s, "]]>");
      if (!e) e = s + strlen(s);
      p = *e ? e + 3 : e;
    } else if (*p == '<') break;
    else {
      e = strchr(p, '<');
      if (!e) e = p + strlen(p);
      p = e;
    }
    for (; s < e; s++)
      if (*n + 1 < len) v[(*n)++] = *s;
      else fits = 0;
  }
  size_t b = 0;
  while (b < *n && xml_space(v[b])) b++;
  while (*n > b && xml_space(v[*n - 1])) (*n)--;
  memmove(v, v + b, *n - b);
  *n -= b;
  return fits;
}

int palp_app_dds_xml_loopback_only(const char *xml, char *why, size_t whylen) {
  if (why && whylen) why[0] = '\0';
  if (!xml) return 0;
  int named = 0, depth = 0, tops = 0;
  for (const char *p = xml; *p;) {
    const char *q = strchr(p, '<');
    if (!q) q = p + strlen(p);
    /* Outside the top element, Cyclone takes text in CYCLONEDDS_URI for a file's name and
     * ignores what follows a file's top element: neither is told by this reading. */
    for (const char *t = p; !depth && t < q; t++)
      if (!xml_space(*t) && *t != ',') return scope_why(why, whylen, 0, "%.*s outside the XML's element", t, (size_t)(q - t));
    if (!*(p = q)) break;
    const char *past = !strncmp(p, "<!--", 4)        ? xml_past(p + 4, "-->")
                       : !strncmp(p, "<![CDATA[", 9) ? xml_past(p + 9, "]]>")
                       : !strncmp(p, "<?", 2)        ? xml_past(p + 2, "?>")
                       : p[1] == '!' || p[1] == '/'  ? xml_past(p + 2, ">")
                                                     : NULL;
    if (past) {
      depth -= p[1] == '/' && depth > 0;
      p = past;
      continue;
    }
    const char *name = ++p;
    while (xml_namec(*p)) p++;
    const size_t nn = (size_t)(p - name);
    if (!nn || !isalpha((unsigned char)*name))
      return scope_why(why, whylen, 0, "<%.*s: not XML palp can read", name, strlen(name));
    if (!depth && tops++)
      return scope_why(why, whylen, 0, "<%.*s> after the top element: Cyclone DDS ignores it in a file", name, nn);
    size_t s = sizeof scope_el / sizeof scope_el[0];
    int abbrev = 0;
    for (size_t k = 0; k < sizeof scope_el / sizeof scope_el[0]; k++) {
      const int is = xml_name_is(name, nn, scope_el[k].name);
      if (is > 0) s = k;
      abbrev |= is < 0;
    }
    if (s == sizeof scope_el / sizeof scope_el[0] && abbrev) /* <Peers><P Address=...>, <Interfaces><N name=...> */
      return scope_why(why, whylen, 0, "<%.*s>, which Cyclone DDS may read as a network setting", name, nn);
    const int el = s < sizeof scope_el / sizeof scope_el[0] ? scope_el[s].el : EL_OTHER;
    int where = 0;
    for (;;) { /* the attributes */
      p = xml_blank(p);
      const char *a = p, *v = NULL;
      while (xml_namec(*p)) p++;
      const size_t an = (size_t)(p - a);
      size_t n = 0;
      if (!an) break;
      p = xml_blank(p);
      if (*p != '=' || !(p = xml_quoted(xml_blank(p + 1), &v, &n)))
        return scope_why(why, whylen, 0, "the attribute %.*s: not XML palp can read", a, an);
      if (el != EL_OTHER && !scope_attr(s, a, an, v, n, why, whylen)) return 0;
      if (el == EL_IFACE && (xml_name_is(a, an, "address") > 0 || xml_name_is(a, an, "name") > 0)) where = 1;
    }
    const int empty = !strncmp(p, "/>", 2);
    if (!empty && *p != '>') return scope_why(why, whylen, 0, "<%.*s ...: not XML palp can read", name, nn);
    p += empty ? 2 : 1;
    depth += !empty;
    if (el == EL_IFACE && !where)
      return scope_why(why, whylen, 0, "a <NetworkInterface>%.*s without address or name", "", 0);
    named |= el == EL_IFACE || el == EL_IFACE_ADDR;
    if (el == EL_ID || el == EL_IFACE_ADDR || el == EL_EXTERNAL || el == EL_MC_RECV) {
      char v[128] = "";
      size_t n = 0;
      const int fits = empty || xml_text(p, v, sizeof v, &n);
      if (el == EL_ID && (!fits || !(n == 3 && !strncasecmp(v, "any", 3))))
        return scope_why(why, whylen, 0, "<Id>%.*s: palp cannot tell it is the domain it runs on", v, n);
      if (el == EL_IFACE_ADDR && (!fits || !loopback_value(v, n)))
        return scope_why(why, whylen, 0, "<NetworkInterfaceAddress>%.*s", v, n);
      if (el == EL_EXTERNAL && (!fits || !(!n || loopback_value(v, n) || (n == 4 && !strncasecmp(v, "auto", 4)))))
        return scope_why(why, whylen, 0, "<ExternalNetworkAddress>%.*s: other participants are told to send there", v,
                         n);
      if (el == EL_MC_RECV && (!fits || !mc_recv_loopback(v, n)))
        return scope_why(why, whylen, 0, "<MulticastRecvNetworkInterfaceAddresses>%.*s: multicast received on other "
                         "interfaces", v, n);
    }
  }
  if (!named) return scope_why(why, whylen, 0, "no <NetworkInterface>: Cyclone DDS picks one%.*s", "", 0);
  return scope_why(why, whylen, 1, "every <NetworkInterface> and <Peer> is loopback%.*s", "", 0);
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

FILE *palp_app_fopen_private_except(const char *path, const char *const *keep, size_t nkeep) {
  /* Not O_TRUNC: what was opened is checked first, on the descriptor (no race with a rename). */
  const int fd = open(path, O_WRONLY | O_CREAT | O_CLOEXEC, 0600);
  if (fd < 0) return NULL;
  struct stat st;
  int e = 0;
  if (fstat(fd, &st) != 0) e = errno;
  for (size_t k = 0; !e && k < nkeep; k++) {
    struct stat ks;
    if (keep[k] && stat(keep[k], &ks) == 0 && ks.st_dev == st.st_dev && ks.st_ino == st.st_ino) e = EEXIST;
  }
  if (!e && S_ISREG(st.st_mode)) {
    if ((st.st_mode & 07777) != 0600 && fchmod(fd, 0600) != 0) e = errno;
    else if (st.st_size > 0 && ftruncate(fd, 0) != 0) e = errno;
  }
  FILE *f = e ? NULL : fdopen(fd, "w");
  if (!f) {
    if (!e) e = errno;
    close(fd);
    errno = e;
  }
  return f;
}

FILE *palp_app_fopen_private(const char *path) { return palp_app_fopen_private_except(path, NULL, 0); }

int palp_app_on_signals(void (*handler)(int)) {
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = handler;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  static const int sigs[] = {SIGINT, SIGTERM, SIGHUP};
  for (size_t i = 0; i < sizeof sigs / sizeof sigs[0]; i++)
    if (sigaction(sigs[i], &sa, NULL) != 0) return -1;
  return 0;
}
