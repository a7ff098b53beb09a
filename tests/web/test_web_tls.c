/* test_web_tls.c - palp_web_tls_check (web/tls.h) on certificates made here with OpenSSL: self-signed
 * P-256 pairs whose validity is set in hours from now, so that "expired", "not yet valid" and
 * "expires within 30 days" are real certificates, not mocks. Each case states what palp-web must
 * say before libwebsockets is given the pair. */
#include <openssl/ec.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "palp.h"
#include "tls.h"
#include "../tmpdir.h"

static char dir[64];

/* A self-signed certificate valid from `from_h` to `to_h` hours from now, and its key, written to
 * DIR/NAME.cert.pem and DIR/NAME.key.pem; with wrong_key, another new key is written instead of the
 * certificate's, to make a pair that does not belong together. */
static void make(const char *name, long from_h, long to_h, int wrong_key) {
  EVP_PKEY *k = EVP_EC_gen("P-256"), *other = wrong_key ? EVP_EC_gen("P-256") : NULL;
  X509 *x = X509_new();
  if (!k || !x || (wrong_key && !other)) abort();
  X509_set_version(x, 2);
  ASN1_INTEGER_set(X509_get_serialNumber(x), 1);
  X509_gmtime_adj(X509_getm_notBefore(x), from_h * 3600);
  X509_gmtime_adj(X509_getm_notAfter(x), to_h * 3600);
  X509_set_pubkey(x, k);
  X509_NAME *n = X509_get_subject_name(x);
  X509_NAME_add_entry_by_txt(n, "CN", MBSTRING_ASC, (const unsigned char *)"127.0.0.1", -1, -1, 0);
  X509_set_issuer_name(x, n);
  if (!X509_sign(x, k, EVP_sha256())) abort();
  char path[128];
  snprintf(path, sizeof path, "%s/%s.cert.pem", dir, name);
  FILE *f = fopen(path, "w");
  if (!f || !PEM_write_X509(f, x)) abort();
  fclose(f);
  snprintf(path, sizeof path, "%s/%s.key.pem", dir, name);
  f = fopen(path, "w");
  if (!f || !PEM_write_PrivateKey(f, wrong_key ? other : k, NULL, NULL, 0, NULL, NULL)) abort();
  fclose(f);
  X509_free(x);
  EVP_PKEY_free(k);
  EVP_PKEY_free(other);
}

static int check_pair(const char *name, char *err, size_t errlen, char *warn, size_t warnlen) {
  char cert[128], key[128];
  snprintf(cert, sizeof cert, "%s/%s.cert.pem", dir, name);
  snprintf(key, sizeof key, "%s/%s.key.pem", dir, name);
  err[0] = '\0';
  return palp_web_tls_check(cert, key, err, errlen, warn, warnlen);
}

int main(void) {
  palp_test_tmp(dir, sizeof dir, "palp-web-tls-XXXXXX");
  if (!mkdtemp(dir)) return 2;
  make("good", -1, 24 * 365, 0);
  make("soon", -1, 24 * 10, 0); /* 10 days left: inside the 30-day warning */
  make("expired", -48, -24, 0);
  make("future", 24, 48, 0);
  make("mismatch", -1, 24 * 365, 1);
  char err[512], warn[512];

  CHECK(check_pair("good", err, sizeof err, warn, sizeof warn) == 0 && !warn[0], "a valid pair: accepted, no warning (%s)",
        err);
  {
    const int rc = check_pair("soon", err, sizeof err, warn, sizeof warn);
    const char *at = strstr(warn, "expires in ");
    double days = -1;
    if (at) sscanf(at, "expires in %lf", &days);
    CHECK(rc == 0 && days >= 9.9 && days <= 10.0, "10 days left: accepted with a warning that says when (10 days "
          "within 0.1): \"%s\"", warn);
  }
  CHECK(check_pair("expired", err, sizeof err, warn, sizeof warn) == PALP_EINVAL && strstr(err, "EXPIRED 1.0 day(s) ago"),
        "expired a day ago: refused, and said: \"%s\"", err);
  CHECK(check_pair("future", err, sizeof err, warn, sizeof warn) == PALP_EINVAL && strstr(err, "not valid before"),
        "valid from tomorrow: refused, the clock named: \"%s\"", err);
  CHECK(check_pair("mismatch", err, sizeof err, warn, sizeof warn) == PALP_EINVAL && strstr(err, "is not the key of"),
        "another key than the certificate's: refused as such: \"%s\"", err);

  /* a key where the certificate belongs, an empty key, a missing file */
  char cert[128], key[128];
  snprintf(cert, sizeof cert, "%s/good.cert.pem", dir);
  snprintf(key, sizeof key, "%s/good.key.pem", dir);
  CHECK(palp_web_tls_check(key, key, err, sizeof err, warn, sizeof warn) == PALP_EINVAL &&
            strstr(err, "not a PEM certificate"),
        "a key as the certificate: \"%s\"", err);
  char empty[128];
  snprintf(empty, sizeof empty, "%s/empty.pem", dir);
  fclose(fopen(empty, "w"));
  CHECK(palp_web_tls_check(cert, empty, err, sizeof err, warn, sizeof warn) == PALP_EINVAL &&
            strstr(err, "not a PEM private key"),
        "an empty key: \"%s\"", err);
  CHECK(palp_web_tls_check(cert, "/nonexistent/key.pem", err, sizeof err, warn, sizeof warn) == PALP_EINVAL,
        "a missing key: refused");

  /* a key with a passphrase is refused without a prompt (stdin closed: a prompt would hang or fail) */
  {
    EVP_PKEY *k = EVP_EC_gen("P-256");
    char enc[128];
    snprintf(enc, sizeof enc, "%s/enc.key.pem", dir);
    FILE *f = fopen(enc, "w");
    if (!k || !f || !PEM_write_PrivateKey(f, k, EVP_aes_128_cbc(), NULL, 0, NULL, (void *)"secret")) return 2;
    fclose(f);
    EVP_PKEY_free(k);
    CHECK(palp_web_tls_check(cert, enc, err, sizeof err, warn, sizeof warn) == PALP_EINVAL && strstr(err, "passphrase"),
          "a key with a passphrase: refused, not prompted for: \"%s\"", err);
  }

  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
  printf("%d checks, %d failures\n", checks, failures);
  return failures ? 1 : 0;
}
