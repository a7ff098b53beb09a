/* palp_dds_security.c - DDS Security properties and identity naming for palp processes. */
/* realpath() is XSI. */
#define _XOPEN_SOURCE 700
#include "palp_dds_security.h"

#include <dirent.h>
#include <errno.h>
#include <fnmatch.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "palp.h" /* PALP_E* codes only */
#include "palp_dds_refusals.h"
#include "palp_pem.h"

/* Where Debian's libddsc0debian keeps the plugins (not on the loader path);
 * PALP_DDS_SECURITY_LIBDIR in the environment overrides the build's choice. */
#ifndef PALP_DDS_SECURITY_LIBDIR
#define PALP_DDS_SECURITY_LIBDIR ""
#endif

static int fail(char *err, size_t errlen, int code, const char *fmt, ...) {
  if (err && errlen) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
  }
  return code;
}

const char *palp_dds_id_kind_name(palp_dds_id_kind kind) {
  switch (kind) {
  case PALP_DDS_ID_SERVER: return "server";
  case PALP_DDS_ID_TRAINEE: return "trainee";
  case PALP_DDS_ID_INSTRUCTOR: return "instructor";
  default: return NULL;
  }
}

/* Names go into partition names and permission patterns, whose matching
 * (fnmatch) and subject-name parsing (',', '/', '=') would give other
 * characters a meaning. */
static int valid_name(const char *s, size_t n) {
  if (n == 0 || n >= PALP_DDS_NAME_MAX) return 0;
  for (size_t i = 0; i < n; i++) {
    char c = s[i];
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_')) return 0;
  }
  return 1;
}

static palp_dds_id_kind kind_of(const char *s, size_t n) {
  if (n == 6 && !strncmp(s, "server", n)) return PALP_DDS_ID_SERVER;
  if (n == 7 && !strncmp(s, "trainee", n)) return PALP_DDS_ID_TRAINEE;
  if (n == 10 && !strncmp(s, "instructor", n)) return PALP_DDS_ID_INSTRUCTOR;
  return PALP_DDS_ID_NONE;
}

int palp_dds_identity_parse(const char *identity, palp_dds_id_kind *kind, char *name, size_t namelen, char *err,
                            size_t errlen) {
  if (!identity) return fail(err, errlen, PALP_EINVAL, "no identity");
  if (!strcmp(identity, "server")) identity = "server/server";
  const char *slash = strchr(identity, '/');
  palp_dds_id_kind k = slash ? kind_of(identity, (size_t)(slash - identity)) : PALP_DDS_ID_NONE;
  if (k == PALP_DDS_ID_NONE || !valid_name(slash + 1, strlen(slash + 1)) || strlen(slash + 1) >= namelen)
    return fail(err, errlen, PALP_EINVAL,
                "identity \"%s\": expected trainee/NAME, instructor/NAME or server, NAME 1-%d characters of a-z 0-9 - _",
                identity, PALP_DDS_NAME_MAX - 1);
  *kind = k;
  snprintf(name, namelen, "%s", slash + 1);
  return 0;
}

static int file_of(const palp_dds_security *sec, const char *suffix, char *buf, size_t len) {
  int n;
  if (suffix[0] == '.')
    n = snprintf(buf, len, "%s/%s/%s%s", sec->pki, palp_dds_id_kind_name(sec->kind), sec->name, suffix);
  else
    n = snprintf(buf, len, "%s/%s", sec->pki, suffix);
  return n < 0 || (size_t)n >= len ? -1 : 0;
}

static const char *const identity_files[] = {".cert.pem", ".key.pem", ".permissions.p7s", "ca.cert.pem",
                                             "governance.p7s"};

/* The length of STEM when a directory entry is named STEM.cert.pem with STEM not empty, else 0. */
static size_t cert_stem(const char *name) {
  static const char suffix[] = ".cert.pem";
  const size_t n = strlen(name), k = sizeof suffix - 1;
  return n > k && !strcmp(name + n - k, suffix) ? n - k : 0;
}

/* Whether s[0..n) is the script's STAMP, %Y%m%dT%H%M%S: after "trainee_bob-" only a stamp, so that
 * trainee/bob-x's revoked files are not bob's (until session 90 bob, his files missing, was told he
 * was revoked and pointed at bob-x's; found by review). */
static int is_stamp(const char *s, size_t n) {
  if (n != 15) return 0;
  for (size_t i = 0; i < n; i++)
    if (i == 8 ? s[i] != 'T' : (s[i] < '0' || s[i] > '9')) return 0;
  return 1;
}

/* The newest DIR/revoked/KIND_NAME-STAMP of a revoked identity (make-classroom-pki.sh
 * revoke moves its files there, STAMP a UTC time that sorts): 1 and its path prefix
 * in buf, or 0 when the identity was never revoked here. */
static int revoked_copy(const palp_dds_security *sec, char *buf, size_t len) {
  char dir[PALP_DDS_PKI_PATH_MAX + 16], head[96];
  snprintf(dir, sizeof dir, "%s/revoked", sec->pki);
  const int hn = snprintf(head, sizeof head, "%s_%s-", palp_dds_id_kind_name(sec->kind), sec->name);
  DIR *d = opendir(dir);
  if (!d || hn < 0 || (size_t)hn >= sizeof head) {
    if (d) closedir(d);
    return 0;
  }
  char best[256] = "";
  for (struct dirent *e; (e = readdir(d));) {
    const size_t stem = cert_stem(e->d_name);
    if (strncmp(e->d_name, head, (size_t)hn) || !stem || !is_stamp(e->d_name + hn, stem - (size_t)hn)) continue;
    if (stem < sizeof best && strncmp(e->d_name, best, sizeof best) > 0) {
      memcpy(best, e->d_name, stem);
      best[stem] = '\0';
    }
  }
  closedir(d);
  if (!best[0]) return 0;
  const int n = snprintf(buf, len, "%s/%s", dir, best);
  return n > 0 && (size_t)n < len;
}

/* The identity's key against its certificate, and the certificate against the classroom's CA, before
 * any participant exists (palp_pem_check). Measured (2026-12-04): a station given bob's key for alice's
 * certificate created its participant and then heard only "no answer from palp-server", while the
 * server logged an unnamed participant refused with "Failed to finalize digest context"; another CA's
 * certificate and a key under a passphrase were refused at creation, in OpenSSL's words ("unable to
 * get local issuer certificate", a page of "bad decrypt"), under palp's guess "is the certificate
 * revoked or expired". 0, or PALP_EINVAL with the reason; *cert_days the certificate's notAfter from
 * now [d] (NAN when it or its date cannot be read: the plugins then say so themselves, at creation). */
static int identity_pair_check(const palp_dds_security *s, const char *identity, double *cert_days, char *err,
                               size_t errlen) {
  char cf[PALP_DDS_PKI_PATH_MAX + 96], kf[PALP_DDS_PKI_PATH_MAX + 96], caf[PALP_DDS_PKI_PATH_MAX + 96];
  *cert_days = NAN;
  if (file_of(s, ".cert.pem", cf, sizeof cf) < 0 || file_of(s, ".key.pem", kf, sizeof kf) < 0 ||
      file_of(s, "ca.cert.pem", caf, sizeof caf) < 0)
    return 0;
  palp_pem_info in;
  const palp_pem_status st = palp_pem_check(cf, kf, caf, &in);
  if (st != PALP_PEM_NO_CERT && st != PALP_PEM_BAD_DATES) *cert_days = in.end_days;
  switch (st) {
  case PALP_PEM_NO_KEY:
    return fail(err, errlen, PALP_EINVAL,
                "identity %s: its private key %s is not a PEM private key, or has a passphrase (palp gives none)",
                identity, kf);
  case PALP_PEM_NOT_ITS_KEY:
    return fail(err, errlen, PALP_EINVAL,
                "identity %s: its private key %s is not the key of its certificate %s (a key copied from another "
                "identity, or kept from before the certificate was re-issued?): every handshake would fail",
                identity, kf, cf);
  case PALP_PEM_NOT_FROM_CA:
    return fail(err, errlen, PALP_EINVAL,
                "identity %s: its certificate %s was not issued by this classroom's CA (%s): it is another "
                "classroom's, or the CA was made anew; every handshake would fail (make-classroom-pki.sh DIR add %s %s "
                "issues one from this CA)",
                identity, cf, caf, palp_dds_id_kind_name(s->kind), s->name);
  default: /* read, or left to the plugins (NO_CERT, BAD_DATES) */
    return 0;
  }
}

static void expiry_phrase(char *buf, size_t len, const char *what, double days) {
  char date[16];
  const time_t when = time(NULL) + (time_t)(days * 86400.0);
  struct tm tm;
  strftime(date, sizeof date, "%Y-%m-%d", gmtime_r(&when, &tm));
  if (days < 0)
    snprintf(buf, len, "%s EXPIRED %.1f day(s) ago (%s)", what, -days, date);
  else
    snprintf(buf, len, "%s expires in %.1f day(s) (%s)", what, days, date);
}

/* The classroom's CRL, which every role must have: DDS Security checks revocation only when a
 * participant is given a CRL, and each participant decides alone whom it admits (mutual
 * authentication: the server's CRL keeps a revoked station out of the server, a station's own keeps a
 * revoked peer, a stolen server identity included, out of that station). Until session 81 a missing or
 * unreadable crl.pem left the property out, and revocation off without a word: a server on a copy of
 * the PKI without it admitted the revoked trainee/dave. make-classroom-pki.sh always writes one, so its
 * absence is a setup error. 0 and *days its nextUpdate from now [d] (NAN: none), or PALP_EIO /
 * PALP_EINVAL naming the file. */
static int crl_check(const palp_dds_security *s, double *days, char *err, size_t errlen) {
  char f[PALP_DDS_PKI_PATH_MAX + 16];
  *days = NAN;
  if (file_of(s, "crl.pem", f, sizeof f) != 0)
    return fail(err, errlen, PALP_EINVAL, "classroom CRL %s/crl.pem: path too long", s->pki);
  const int rc = palp_pem_crl_days(f, days);
  if (rc == -1)
    return fail(err, errlen, PALP_EIO,
                "classroom CRL %s: %s: without it revoked identities would be admitted (copy it from the classroom's "
                "PKI; make-classroom-pki.sh DIR crl re-issues it)",
                f, errno == ENOENT ? "missing" : strerror(errno));
  if (rc < 0)
    return fail(err, errlen, PALP_EINVAL,
                "classroom CRL %s: not a PEM CRL: without it revoked identities would be admitted (copy it from the "
                "classroom's PKI; make-classroom-pki.sh DIR crl re-issues it)",
                f);
  return 0;
}

/* cert_days: the identity certificate's notAfter from now [d] (identity_pair_check); crl_days: the
 * CRL's nextUpdate (crl_check; NAN when it has none). */
static void expiry_warning(palp_dds_security *s, double cert_days, double crl_days) {
  char a[200] = "", b[200] = "";
  const char *kind = palp_dds_id_kind_name(s->kind);
  if (cert_days < PALP_DDS_EXPIRY_WARN_DAYS) {
    char what[96];
    snprintf(what, sizeof what, "the certificate of %s/%s", kind, s->name);
    expiry_phrase(a, sizeof a, what, cert_days);
  }
  if (crl_days < PALP_DDS_EXPIRY_WARN_DAYS) expiry_phrase(b, sizeof b, "the classroom CRL (crl.pem)", crl_days);
  if (!a[0] && !b[0]) return;
  snprintf(s->warning, sizeof s->warning, "%s%s%s%s%s", a,
           a[0] ? ": issue a new one (make-classroom-pki.sh DIR revoke, then add)" : "", a[0] && b[0] ? "; " : "", b,
           b[0] ? ": re-issue it (make-classroom-pki.sh DIR crl) and copy it to every participant, since an expired "
                  "CRL fails every handshake"
                : "");
}

/* The version make-classroom-pki.sh wrote into the identity's signed permissions (their text is in
 * the S/MIME file's clear part, near its start): 1 when they carry none (made before versions were),
 * 0 when the file cannot be read (the plugins then say why at creation). */
static int permissions_version(const palp_dds_security *s) {
  char f[PALP_DDS_PKI_PATH_MAX + 96], buf[4096];
  if (file_of(s, ".permissions.p7s", f, sizeof f) < 0) return 0;
  FILE *fp = fopen(f, "r");
  if (!fp) return 0;
  const size_t n = fread(buf, 1, sizeof buf - 1, fp);
  fclose(fp);
  buf[n] = '\0';
  static const char mark[] = "palp permissions, version ";
  const char *m = strstr(buf, mark);
  return m ? atoi(m + sizeof mark - 1) : 1;
}

/* Whether the identity's signed permissions name a rule for `topic` (a <topic> pattern matching it, as
 * DDS Security matches them, fnmatch): 1 yes, 0 no, -1 unreadable. Read from the S/MIME file's clear
 * part (at most 64 KiB: the script's are ~2 KiB), so it is what the plugins enforce. Partitions and the
 * rule's kind (publish or subscribe) are not told apart: enough to say that no rule names a topic. */
static int permissions_name(const palp_dds_security *s, const char *topic) {
  char f[PALP_DDS_PKI_PATH_MAX + 96];
  if (file_of(s, ".permissions.p7s", f, sizeof f) < 0) return -1;
  FILE *fp = fopen(f, "r");
  if (!fp) return -1;
  enum { CAP = 65536 };
  char *buf = malloc(CAP);
  if (!buf) {
    fclose(fp);
    return -1;
  }
  const size_t n = fread(buf, 1, CAP - 1, fp);
  fclose(fp);
  buf[n] = '\0';
  int named = 0;
  static const char open_tag[] = "<topic>", close_tag[] = "</topic>";
  for (const char *p = strstr(buf, open_tag); p && !named; p = strstr(p, open_tag)) {
    p += sizeof open_tag - 1;
    const char *e = strstr(p, close_tag);
    if (!e) break;
    char pat[256];
    const size_t k = (size_t)(e - p);
    if (k < sizeof pat) {
      memcpy(pat, p, k);
      pat[k] = '\0';
      named = fnmatch(pat, topic, 0) == 0;
    }
    p = e;
  }
  free(buf);
  return named;
}

/* Appends to the start-up warning that the identity's permissions are damaged or predate this
 * build's topics, and what to do. */
static void permissions_warning(palp_dds_security *s) {
  char what[200];
  /* Every palp program of every identity reads palp_catalogue: permissions with no rule naming it
   * are damaged, whatever their version (until 2026-12-06 the PKI script could write an instructor's
   * "*" as file names), and every topic will be refused. Said at start, --check too. */
  if (permissions_name(s, "palp_catalogue") == 0) {
    snprintf(what, sizeof what, "name no rule for palp_catalogue, which every palp program reads: they are damaged, "
                                "and every topic will be refused");
  } else {
    const int v = permissions_version(s);
    if (v <= 0 || v >= PALP_DDS_PERMISSIONS_VERSION) return;
    snprintf(what, sizeof what, "are version %d, older than this palp's %d: the topics added since are refused to it "
                                "(they go without them, and say what is lost)", v, PALP_DDS_PERMISSIONS_VERSION);
  }
  const char *kind = palp_dds_id_kind_name(s->kind);
  const size_t used = strlen(s->warning);
  snprintf(s->warning + used, sizeof s->warning - used,
           "%sthe permissions of %s/%s %s; re-issue them with scripts/make-classroom-pki.sh %s init and copy "
           "%s/%s/%s.permissions.p7s to this machine",
           used ? "; " : "", kind, s->name, what, s->pki, s->pki, kind, s->name);
}

int palp_dds_security_init(palp_dds_security *sec, const char *pki, const char *identity, char *err, size_t errlen) {
  memset(sec, 0, sizeof *sec);
  if (!pki || !identity || !pki[0] || !identity[0]) return 0;
  palp_dds_security s;
  memset(&s, 0, sizeof s);
  int rc = palp_dds_identity_parse(identity, &s.kind, s.name, sizeof s.name, err, errlen);
  if (rc < 0) return rc;
  char abs[PATH_MAX];
  if (!realpath(pki, abs)) return fail(err, errlen, PALP_EIO, "PKI directory %s: not found", pki);
  size_t n = strlen(abs);
  if (n >= sizeof s.pki) return fail(err, errlen, PALP_EINVAL, "PKI directory %s: path too long", pki);
  memcpy(s.pki, abs, n + 1);
  for (size_t i = 0; i < sizeof identity_files / sizeof identity_files[0]; i++) {
    char f[PALP_DDS_PKI_PATH_MAX + 96];
    if (file_of(&s, identity_files[i], f, sizeof f) < 0 || access(f, R_OK) != 0) {
      char revoked[PALP_DDS_PKI_PATH_MAX + 96];
      if (i == 0 && revoked_copy(&s, revoked, sizeof revoked))
        return fail(err, errlen, PALP_EIO,
                    "identity %s was revoked in this classroom (its files were moved to %s.*): ask the instructor "
                    "for a new one (make-classroom-pki.sh DIR add %s %s)",
                    identity, revoked, palp_dds_id_kind_name(s.kind), s.name);
      return fail(err, errlen, PALP_EIO, "identity %s: cannot read %s (make it with scripts/make-classroom-pki.sh)",
                  identity, f);
    }
  }
  /* A private key every user of the machine can read is anyone's identity on a shared lab
   * machine: refused, as ssh refuses such keys (group-readable stays allowed, for a service group). */
  char key[PALP_DDS_PKI_PATH_MAX + 96];
  struct stat st;
  if (file_of(&s, ".key.pem", key, sizeof key) == 0 && stat(key, &st) == 0 && (st.st_mode & (S_IROTH | S_IWOTH)))
    return fail(err, errlen, PALP_EINVAL,
                "identity %s: its private key %s is readable by every user of this machine (mode %04o): "
                "chmod o-rwx it (make-classroom-pki.sh makes keys 0600)",
                identity, key, (unsigned)(st.st_mode & 07777));
  double cert_days, crl_days;
  if ((rc = identity_pair_check(&s, identity, &cert_days, err, errlen)) < 0) return rc;
  if ((rc = crl_check(&s, &crl_days, err, errlen)) < 0) return rc;
  expiry_warning(&s, cert_days, crl_days);
  permissions_warning(&s);
  *sec = s;
  return 0;
}

int palp_dds_security_from_env(palp_dds_security *sec, char *err, size_t errlen) {
  const char *pki = getenv("PALP_PKI"), *id = getenv("PALP_IDENTITY");
  int have_pki = pki && *pki, have_id = id && *id;
  memset(sec, 0, sizeof *sec);
  if (have_pki != have_id)
    return fail(err, errlen, PALP_EINVAL, "PALP_PKI and PALP_IDENTITY must be set together (%s is missing)",
                have_pki ? "PALP_IDENTITY" : "PALP_PKI");
  return have_pki ? palp_dds_security_init(sec, pki, id, err, errlen) : 0;
}

static void set_file_prop(dds_qos_t *qos, const char *prop, const palp_dds_security *sec, const char *suffix) {
  char f[PALP_DDS_PKI_PATH_MAX + 96], uri[PALP_DDS_PKI_PATH_MAX + 128];
  if (file_of(sec, suffix, f, sizeof f) < 0) return;
  snprintf(uri, sizeof uri, "file:%s", f);
  dds_qset_prop(qos, prop, uri);
}

static void set_plugin(dds_qos_t *qos, const char *what, const char *lib, const char *init, const char *fini) {
  const char *dir = getenv("PALP_DDS_SECURITY_LIBDIR");
  if (!dir || !*dir) dir = PALP_DDS_SECURITY_LIBDIR;
  char path[PATH_MAX], prop[64];
  /* An empty directory leaves the name to the dynamic loader's search path. */
  if (dir[0])
    snprintf(path, sizeof path, "%s/lib%s.so", dir, lib);
  else
    snprintf(path, sizeof path, "%s", lib);
  snprintf(prop, sizeof prop, "dds.sec.%s.library.path", what);
  dds_qset_prop(qos, prop, path);
  snprintf(prop, sizeof prop, "dds.sec.%s.library.init", what);
  dds_qset_prop(qos, prop, init);
  snprintf(prop, sizeof prop, "dds.sec.%s.library.finalize", what);
  dds_qset_prop(qos, prop, fini);
}

void palp_dds_security_qos(const palp_dds_security *sec, dds_qos_t *qos) {
  if (!sec || sec->kind == PALP_DDS_ID_NONE) return;
  set_plugin(qos, "auth", "dds_security_auth", "init_authentication", "finalize_authentication");
  set_plugin(qos, "crypto", "dds_security_crypto", "init_crypto", "finalize_crypto");
  set_plugin(qos, "access", "dds_security_ac", "init_access_control", "finalize_access_control");
  set_file_prop(qos, "dds.sec.auth.identity_ca", sec, "ca.cert.pem");
  set_file_prop(qos, "dds.sec.auth.identity_certificate", sec, ".cert.pem");
  set_file_prop(qos, "dds.sec.auth.private_key", sec, ".key.pem");
  set_file_prop(qos, "dds.sec.access.permissions_ca", sec, "ca.cert.pem");
  set_file_prop(qos, "dds.sec.access.governance", sec, "governance.p7s");
  set_file_prop(qos, "dds.sec.access.permissions", sec, ".permissions.p7s");
  /* Revocation: every certificate a participant validates, its own and each remote one, is checked
   * against the classroom's CRL. Always set (palp_dds_security_init refused a PKI without a readable
   * one): a CRL gone since makes the participant's creation fail, never revocation silently off. */
  set_file_prop(qos, "org.eclipse.cyclonedds.sec.auth.crl", sec, "crl.pem");
}

dds_entity_t palp_dds_create_participant(dds_domainid_t domain, const palp_dds_security *sec) {
  if (!sec || sec->kind == PALP_DDS_ID_NONE) return dds_create_participant(domain, NULL, NULL);
  dds_qos_t *qos = dds_create_qos();
  palp_dds_security_qos(sec, qos);
  dds_entity_t pp = dds_create_participant(domain, qos, NULL);
  dds_delete_qos(qos);
  return pp;
}

void palp_dds_request_partition(const palp_dds_security *sec, char *buf, size_t len) {
  if (!sec || sec->kind == PALP_DDS_ID_NONE)
    snprintf(buf, len, "%s", "");
  else
    snprintf(buf, len, "palp/%s/%s", palp_dds_id_kind_name(sec->kind), sec->name);
}

int palp_dds_identity_from_partition(const char *partition, palp_dds_id_kind *kind, char *name, size_t namelen) {
  if (!partition || strncmp(partition, "palp/", 5) != 0) return PALP_EINVAL;
  const char *k = partition + 5, *slash = strchr(k, '/');
  if (!slash) return PALP_EINVAL;
  palp_dds_id_kind kd = kind_of(k, (size_t)(slash - k));
  /* Only stations publish requests; a server identity never does. */
  if (kd != PALP_DDS_ID_TRAINEE && kd != PALP_DDS_ID_INSTRUCTOR) return PALP_EINVAL;
  size_t n = strlen(slash + 1);
  if (!valid_name(slash + 1, n) || n >= namelen) return PALP_EINVAL;
  *kind = kd;
  memcpy(name, slash + 1, n + 1);
  return 0;
}

void palp_dds_secure_session_partition(const char *name, uint32_t session_id, char *buf, size_t len) {
  snprintf(buf, len, "palp/s/%s/%u", name, session_id);
}

/* Participant announcements (SPDP) are not protected by DDS Security, so a plain and a secured
 * participant see each other's on the built-in topic even when nothing else of theirs matches;
 * Cyclone's built-in reader, created late, still holds every participant already discovered. */
int palp_dds_peer_participants(dds_entity_t pp) {
  dds_guid_t me;
  if (dds_get_guid(pp, &me) < 0) return PALP_EIO;
  const dds_entity_t rd = dds_create_reader(pp, DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, NULL, NULL);
  if (rd < 0) return PALP_EIO;
  enum { MAXP = 64 };
  void *ptr[MAXP] = {NULL};
  dds_sample_info_t info[MAXP];
  int peers = 0;
  const int n = dds_read(rd, ptr, info, MAXP, MAXP);
  for (int i = 0; i < n; i++) {
    const dds_builtintopic_participant_t *p = ptr[i];
    if (info[i].valid_data && info[i].instance_state == DDS_IST_ALIVE && memcmp(&p->key, &me, sizeof me) != 0)
      peers++;
  }
  if (n > 0) dds_return_loan(rd, ptr, n);
  dds_delete(rd);
  return n < 0 ? PALP_EIO : peers;
}

void palp_dds_unanswered_hint(dds_entity_t pp, const palp_dds_security *sec, char *buf, size_t len) {
  if (len) buf[0] = '\0';
  const int peers = palp_dds_peer_participants(pp);
  if (peers <= 0) return;
  if (!sec || sec->kind == PALP_DDS_ID_NONE)
    snprintf(buf, len,
             "; %d other DDS participant%s on this domain, none of which answered: if the classroom runs with DDS "
             "Security, give --pki DIR --identity KIND/NAME (or PALP_PKI and PALP_IDENTITY)",
             peers, peers == 1 ? " is" : "s are");
  else
    snprintf(buf, len,
             "; %d other DDS participant%s on this domain, none of which answered %s/%s: is the server secured with "
             "the same classroom PKI (a plain server, one of another CA, or one whose governance.p7s differs from "
             "this station's cannot talk to this identity: make-classroom-pki.sh re-issues an old governance, which "
             "every station then needs), and is this certificate valid and not revoked? (the server's log names each "
             "identity it refuses, and why)",
             peers, peers == 1 ? " is" : "s are", palp_dds_id_kind_name(sec->kind), sec->name);
}

const char *palp_dds_security_state(const palp_dds_security *sec, char *buf, size_t len) {
  if (!sec || sec->kind == PALP_DDS_ID_NONE)
    snprintf(buf, len, "off");
  else
    snprintf(buf, len, "on (identity %s/%s)", palp_dds_id_kind_name(sec->kind), sec->name);
  return buf;
}

const char *palp_dds_refused_hint(const palp_dds_security *sec, const char *topic, char *buf, size_t len) {
  if (!buf || len == 0) return buf;
  buf[0] = '\0';
  if (!sec || sec->kind == PALP_DDS_ID_NONE) return buf;
  /* Secured, a topic or reader the process needs is refused when its permissions have no rule for it:
   * permissions older than the program (a topic added since), or damaged ones (the PKI script wrote an
   * instructor's "*" as file names until 2026-12-06). Both are mended by the script's init. */
  const char *kind = palp_dds_id_kind_name(sec->kind);
  /* Said for sure where the file tells (session 71): no rule names the topic, or one does and the
   * refusal is for something else (a partition, a signature). */
  const int named = topic ? permissions_name(sec, topic) : -1;
  if (named == 1) {
    snprintf(buf, len,
             "; DDS Security: the permissions of %s/%s (%s/%s/%s.permissions.p7s) name topic %s, but not for "
             "this use (publish or subscribe, partition), or they are not signed by this classroom's CA: "
             "re-issue them with scripts/make-classroom-pki.sh %s init, copy them to this machine and restart "
             "(docs/security.md)",
             kind, sec->name, sec->pki, kind, sec->name, topic, sec->pki);
    return buf;
  }
  snprintf(buf, len,
           "; DDS Security: the permissions of %s/%s (%s/%s/%s.permissions.p7s) %s %s%s: "
           "re-issue them with scripts/make-classroom-pki.sh %s init, copy them to this machine and restart "
           "(docs/security.md, \"Permissions version\")",
           kind, sec->name, sec->pki, kind, sec->name, named == 0 ? "have no rule for" : "may not allow",
           topic ? "topic " : "its topics", topic ? topic : "", sec->pki);
  return buf;
}

int palp_dds_security_name_peers(const palp_dds_security *sec, struct palp_dds_refusals *t) {
  if (!sec || sec->kind == PALP_DDS_ID_NONE || !t) return 0;
  static const char *const kinds[] = {"trainee", "instructor", "server"};
  palp_dds_peer_name *names = NULL;
  int n = 0, cap = 0;
  for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; k++) {
    char dir[PALP_DDS_PKI_PATH_MAX + 16];
    snprintf(dir, sizeof dir, "%s/%s", sec->pki, kinds[k]);
    DIR *d = opendir(dir);
    if (!d) continue;
    for (struct dirent *e; (e = readdir(d)) && n < PALP_DDS_PEER_NAMES_MAX;) {
      if (!cert_stem(e->d_name)) continue;
      char path[PALP_DDS_PKI_PATH_MAX + 16 + 260], subject[512];
      unsigned char pre[6];
      struct stat st;
      if (snprintf(path, sizeof path, "%s/%s", dir, e->d_name) >= (int)sizeof path || stat(path, &st) != 0 ||
          !S_ISREG(st.st_mode) || st.st_size > 65536 || palp_pem_guid_prefix(path, pre, subject, sizeof subject) < 0)
        continue; /* not a certificate (a FIFO or a device would block the start): nobody to name by it */
      if (n == cap) {
        const int ncap = cap ? 2 * cap : 32;
        palp_dds_peer_name *g = realloc(names, (size_t)ncap * sizeof *g);
        if (!g) {
          closedir(d);
          free(names);
          return PALP_ENOMEM;
        }
        names = g, cap = ncap;
      }
      memcpy(names[n].prefix, pre, sizeof pre);
      palp_dds_subject_name(names[n].who, sizeof names[n].who, subject, strlen(subject));
      n++;
    }
    closedir(d);
  }
  const int rc = palp_dds_refusals_set_names(t, names, n);
  free(names);
  return rc < 0 ? rc : n;
}
