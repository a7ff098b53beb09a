/* palp_pem.c - a PEM certificate and its key, checked before use (palp_pem.h). */
#include "palp_pem.h"

#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/sha.h>
#include <openssl/x509.h>
#include <math.h>
#include <stdio.h>
#include <time.h>

/* A key with a passphrase is refused, never prompted for (palp_pem.h). */
static int no_passphrase(char *buf, int size, int rwflag, void *u) {
  (void)buf, (void)size, (void)rwflag, (void)u;
  return 0;
}

/* Days from now until t [d] (negative once past): 0, or -1 if t cannot be read. */
static int days_until(const ASN1_TIME *t, double *days) {
  int d = 0, s = 0;
  if (!t || !ASN1_TIME_diff(&d, &s, NULL, t)) return -1;
  *days = d + s / 86400.0;
  return 0;
}

static void date_of(const ASN1_TIME *t, char *buf, size_t len) {
  struct tm tm;
  buf[0] = '\0';
  if (t && ASN1_TIME_to_tm(t, &tm)) strftime(buf, len, "%Y-%m-%d %H:%M UTC", &tm);
}

static X509 *read_cert(const char *path) {
  FILE *f = path ? fopen(path, "r") : NULL;
  if (!f) return NULL;
  X509 *x = PEM_read_X509(f, NULL, no_passphrase, NULL);
  fclose(f);
  return x;
}

palp_pem_status palp_pem_check(const char *cert, const char *key, const char *ca, palp_pem_info *info) {
  palp_pem_status st = PALP_PEM_OK;
  /* the dates not read (no certificate, or bad dates) are not numbers, never what the stack held */
  info->start_days = info->end_days = NAN;
  info->start_date[0] = info->end_date[0] = '\0';
  X509 *x = read_cert(cert), *cx = NULL;
  EVP_PKEY *k = NULL, *cak = NULL;
  if (!x) {
    st = PALP_PEM_NO_CERT;
    goto out;
  }
  if (days_until(X509_get0_notBefore(x), &info->start_days) != 0 ||
      days_until(X509_get0_notAfter(x), &info->end_days) != 0)
    st = PALP_PEM_BAD_DATES; /* said after the key and the CA, in the statuses' order */
  date_of(X509_get0_notBefore(x), info->start_date, sizeof info->start_date);
  date_of(X509_get0_notAfter(x), info->end_date, sizeof info->end_date);
  if (key) {
    FILE *f = fopen(key, "r");
    if (f) k = PEM_read_PrivateKey(f, NULL, no_passphrase, NULL), fclose(f);
    if (!k) {
      st = PALP_PEM_NO_KEY;
      goto out;
    }
    if (X509_check_private_key(x, k) != 1) {
      st = PALP_PEM_NOT_ITS_KEY;
      goto out;
    }
  }
  if (ca && (cx = read_cert(ca)) != NULL && (cak = X509_get_pubkey(cx)) != NULL && X509_verify(x, cak) != 1)
    st = PALP_PEM_NOT_FROM_CA;
out:
  X509_free(x);
  X509_free(cx);
  EVP_PKEY_free(k);
  EVP_PKEY_free(cak);
  ERR_clear_error(); /* nothing left for the DDS plugins' or libwebsockets' own OpenSSL calls to misread */
  return st;
}

int palp_pem_crl_days(const char *crl, double *days) {
  *days = NAN;
  FILE *f = fopen(crl, "r");
  if (!f) return -1;
  X509_CRL *c = PEM_read_X509_CRL(f, NULL, no_passphrase, NULL);
  fclose(f);
  /* A CRL without a nextUpdate is still a CRL: read, with no date to warn of. */
  if (c && days_until(X509_CRL_get0_nextUpdate(c), days) != 0) *days = NAN;
  const int rc = c ? 0 : -2;
  X509_CRL_free(c);
  ERR_clear_error();
  return rc;
}

int palp_pem_guid_prefix(const char *cert, unsigned char prefix[6], char *subject, size_t cap) {
  X509 *x = read_cert(cert);
  const X509_NAME *name = x ? X509_get_subject_name(x) : NULL;
  unsigned char *der = NULL;
  const int n = name ? i2d_X509_NAME(name, &der) : -1;
  int rc = -1;
  if (n > 0) {
    unsigned char high[SHA256_DIGEST_LENGTH];
    SHA256(der, (size_t)n, high);
    /* prefix[i] = (the bit before) | high[i] >> 1, the first bit 1: 9.3.3's "bit 0 set, then
     * the hash's first 47 bits" (Cyclone's get_adjusted_participant_guid). */
    unsigned char carry = 0x80;
    for (int i = 0; i < 6; i++) {
      prefix[i] = (unsigned char)(carry | high[i] >> 1);
      carry = (unsigned char)(high[i] << 7);
    }
    if (subject && cap) {
      char *one = X509_NAME_oneline(name, NULL, 0);
      snprintf(subject, cap, "%s", one ? one : "");
      OPENSSL_free(one);
    }
    rc = 0;
  }
  OPENSSL_free(der);
  X509_free(x);
  ERR_clear_error();
  return rc;
}
