/*
 * palp_pem.h - a PEM certificate and its key as palp's programs check them before use (palp_pem_).
 *
 * One reading for both users: the DDS identities (palp_dds_security.c: the key against its
 * certificate, the certificate against the classroom CA, the days left before it and the CRL expire)
 * and palp-web's TLS pair (web/tls.c). OpenSSL only; no DDS. A key with a passphrase is never
 * prompted for: a service cannot stop to ask, and palp gives the DDS plugins none.
 */
#ifndef PALP_PEM_H
#define PALP_PEM_H

#include <stddef.h>

typedef enum palp_pem_status {
  PALP_PEM_OK = 0,
  PALP_PEM_NO_CERT,      /* the certificate cannot be read as PEM */
  PALP_PEM_NO_KEY,       /* the key cannot be read as PEM, or has a passphrase */
  PALP_PEM_NOT_ITS_KEY,  /* the key is not the certificate's */
  PALP_PEM_NOT_FROM_CA,  /* the CA's key did not sign the certificate */
  PALP_PEM_BAD_DATES     /* the certificate's validity dates cannot be read */
} palp_pem_status;

typedef struct palp_pem_info {
  double start_days, end_days;       /* notBefore / notAfter from now [d]; negative: past */
  char start_date[32], end_date[32]; /* the same as "YYYY-MM-DD HH:MM UTC" */
} palp_pem_info;

/* Reads `cert` and, when not NULL, `key` (must be the certificate's) and `ca` (a CA certificate
 * whose key must have signed it; a CA file that cannot be read is not checked). Fills info once the
 * certificate is read (until then its dates NaN, its texts empty). The checks run in the order of the statuses above. */
palp_pem_status palp_pem_check(const char *cert, const char *key, const char *ca, palp_pem_info *info);

/* A CRL's nextUpdate from now [d] (negative: past; NAN when the CRL has none): 0; -1 when the file
 * cannot be opened (errno says why), -2 when it is not a PEM CRL. */
int palp_pem_crl_days(const char *crl, double *days);

/* The first 6 bytes of the GUID prefix that DDS Security's builtin authentication gives a participant
 * authenticated with this certificate (DDS Security 1.1, 9.3.3): bit 0 set, bits 1-47 the first 47 bits
 * of SHA-256 over the DER encoding of the certificate's subject name. Cyclone's handshake refuses a peer
 * whose prefix does not match its certificate ("incorrect participant guid"), so an authenticated
 * participant's prefix names its subject. `subject` (when not NULL) gets the subject as OpenSSL writes
 * it on one line ("/O=palp/OU=trainee/CN=bob", as in Cyclone's messages). 0, or -1 when the
 * certificate cannot be read. */
int palp_pem_guid_prefix(const char *cert, unsigned char prefix[6], char *subject, size_t cap);

#endif
