/* tls.c - palp-web's certificate and key, checked before use (tls.h), read as the DDS identities
 * are (idl/palp_pem.h). */
#include "tls.h"

#include <stdio.h>

#include "palp.h" /* PALP_E* codes */
#include "palp_pem.h"

int palp_web_tls_check(const char *cert, const char *key, char *err, size_t errlen, char *warn, size_t warnlen) {
  if (warnlen) warn[0] = '\0';
  palp_pem_info in;
  switch (palp_pem_check(cert, key, NULL, &in)) {
  case PALP_PEM_OK:
    break;
  case PALP_PEM_NO_CERT:
    snprintf(err, errlen, "--tls-cert %s: not a PEM certificate", cert);
    return PALP_EINVAL;
  case PALP_PEM_NO_KEY:
    snprintf(err, errlen, "--tls-key %s: not a PEM private key (or one with a passphrase, which a service cannot ask for)",
             key);
    return PALP_EINVAL;
  case PALP_PEM_NOT_ITS_KEY:
    snprintf(err, errlen, "--tls-key %s is not the key of --tls-cert %s (give the key made with that certificate)", key,
             cert);
    return PALP_EINVAL;
  default: /* PALP_PEM_BAD_DATES (no CA asked) */
    snprintf(err, errlen, "--tls-cert %s: its validity dates cannot be read", cert);
    return PALP_EINVAL;
  }
  if (in.start_days > 0) {
    snprintf(err, errlen, "--tls-cert %s is not valid before %s (is this machine's clock right?)", cert, in.start_date);
    return PALP_EINVAL;
  }
  if (in.end_days < 0) {
    snprintf(err, errlen,
             "--tls-cert %s EXPIRED %.1f day(s) ago (%s): browsers refuse it; make a new one "
             "(scripts/make-classroom-pki.sh DIR web HOST)",
             cert, -in.end_days, in.end_date);
    return PALP_EINVAL;
  }
  if (in.end_days < PALP_WEB_TLS_WARN_DAYS)
    snprintf(warn, warnlen,
             "--tls-cert %s expires in %.1f day(s) (%s): make a new one before then "
             "(scripts/make-classroom-pki.sh DIR web HOST) and restart palp-web",
             cert, in.end_days, in.end_date);
  return 0;
}
