/*
 * tls.h - palp-web's certificate and key, checked before libwebsockets is given them (palp_web_).
 *
 * Why here and not left to libwebsockets: its refusal of a pair that does not belong together is
 * one message for several causes ("the certificate and key must be PEM and belong together, or the
 * port is in use ..."), it leaks on that path (72 bytes, libwebsockets 4.1, under ASan), and it says
 * nothing of a certificate that has expired or soon will: browsers then refuse the class's pages
 * with a warning the instructor has to interpret. palp-web does not renew its certificate
 * (docs/web.md), so it says when it must be renewed.
 */
#ifndef PALP_WEB_TLS_H
#define PALP_WEB_TLS_H

#include <stddef.h>

/* Days before the certificate's end palp-web warns of it at start (as the DDS identities do). */
#define PALP_WEB_TLS_WARN_DAYS 30

/* Reads the PEM certificate and private key and checks that the key is the certificate's and that
 * the certificate is valid now. 0 when it is, with warn set ("" or, within PALP_WEB_TLS_WARN_DAYS of
 * the end, when it expires); PALP_EINVAL with the reason in err otherwise: not a PEM certificate,
 * not a PEM private key (a key with a passphrase is refused, never prompted for), another key than
 * the certificate's, not valid yet, expired. */
int palp_web_tls_check(const char *cert, const char *key, char *err, size_t errlen, char *warn, size_t warnlen);

#endif
