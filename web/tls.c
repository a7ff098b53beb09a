/* tls.c - palp-web's certificate and key, checked before use (tls.h). */
#include "tls.h"

#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <stdio.h>
#include <time.h>

#include "palp.h" /* PALP_E* codes */

/* A key with a passphrase is refused: a service cannot stop to ask for it. */
static int no_passphrase(char *buf, int size, int rwflag, void *u) {
  (void)buf, (void)size, (void)rwflag, (void)u;
  return 0;
}

/* Days from now to t (negative: t is past); -1 return when t cannot be read. */
static int days_from_now(const ASN1_TIME *t, double *days) {
  int d = 0, s = 0;
  if (!t || !ASN1_TIME_diff(&d, &s, NULL, t)) return -1;
  *days = d + s / 86400.0;
  return 0;
}

static void date_of(const ASN1_TIME *t, char *buf, size_t len) {
  struct tm tm;
  if (len) buf[0] = '\0';
  if (t && ASN1_TIME_to_tm(t, &tm)) strftime(buf, len, "%Y-%m-%d %H:%M UTC", &tm);
}

int palp_web_tls_check(const char *cert, const char *key, char *err, size_t errlen, char *warn, size_t warnlen) {
  if (warnlen) warn[0] = '\0';
  int rc = PALP_EINVAL;
  X509 *x = NULL;
  EVP_PKEY *k = NULL;
  FILE *f = fopen(cert, "r");
  if (f) x = PEM_read_X509(f, NULL, no_passphrase, NULL), fclose(f);
  if (!x) {
    snprintf(err, errlen, "--tls-cert %s: not a PEM certificate", cert);
    goto out;
  }
  f = fopen(key, "r");
  if (f) k = PEM_read_PrivateKey(f, NULL, no_passphrase, NULL), fclose(f);
  if (!k) {
    snprintf(err, errlen, "--tls-key %s: not a PEM private key (or one with a passphrase, which a service cannot ask for)",
             key);
    goto out;
  }
  if (X509_check_private_key(x, k) != 1) {
    snprintf(err, errlen, "--tls-key %s is not the key of --tls-cert %s (give the key made with that certificate)", key,
             cert);
    goto out;
  }
  double start = 0, end = 0;
  char date[64];
  if (days_from_now(X509_get0_notBefore(x), &start) != 0 || days_from_now(X509_get0_notAfter(x), &end) != 0) {
    snprintf(err, errlen, "--tls-cert %s: its validity dates cannot be read", cert);
    goto out;
  }
  if (start > 0) {
    date_of(X509_get0_notBefore(x), date, sizeof date);
    snprintf(err, errlen, "--tls-cert %s is not valid before %s (is this machine's clock right?)", cert, date);
    goto out;
  }
  date_of(X509_get0_notAfter(x), date, sizeof date);
  if (end < 0) {
    snprintf(err, errlen,
             "--tls-cert %s EXPIRED %.1f day(s) ago (%s): browsers refuse it; make a new one "
             "(scripts/make-classroom-pki.sh DIR web HOST)",
             cert, -end, date);
    goto out;
  }
  if (end < PALP_WEB_TLS_WARN_DAYS)
    snprintf(warn, warnlen,
             "--tls-cert %s expires in %.1f day(s) (%s): make a new one before then "
             "(scripts/make-classroom-pki.sh DIR web HOST) and restart palp-web",
             cert, end, date);
  rc = 0;
out:
  X509_free(x);
  EVP_PKEY_free(k);
  ERR_clear_error(); /* nothing of these reads is left for libwebsockets' own TLS calls to misread */
  return rc;
}
