/*
 * access.h - who may talk to palp-web and which files it serves (palp_web_).
 *
 * Pure string checks, kept apart from libwebsockets so that they are unit-tested alone
 * (tests/web/test_web_unit.c). docs/web.md explains the rules.
 */
#ifndef PALP_WEB_ACCESS_H
#define PALP_WEB_ACCESS_H

#include <stddef.h>

/* Shortest token accepted [characters]: a guessable token is no access control. */
#define PALP_WEB_TOKEN_MIN 16
#define PALP_WEB_TOKEN_MAX 128

/* 1 when addr is a loopback address (127.0.0.0/8, ::1, "localhost"), else 0. */
int palp_web_addr_is_loopback(const char *addr);
/* 1 when an HTTP Host header names a loopback address ("127.0.0.1:8090", "[::1]:8090", "localhost",
 * with or without a port), else 0: without a token palp-web answers only requests sent to such a
 * name, so a page of another site made to resolve to 127.0.0.1 (DNS rebinding) gets nothing. */
int palp_web_host_is_loopback(const char *host);

/* 0 when the token may be used: PALP_WEB_TOKEN_MIN..MAX characters of [A-Za-z0-9._~-] (it travels
 * in URLs and a cookie unescaped); else PALP_EINVAL. */
int palp_web_token_check(const char *token);

/* How long an access token opens pages [s] after it was issued, unless --token-lifetime-h says
 * otherwise: a class day, so that a token printed for Monday's class does not open Friday's. A token is
 * issued when its file was last written (--token-file, --trainee-tokens), or at palp-web's start for a
 * --token given on the command line (docs/web.md). */
#define PALP_WEB_TOKEN_LIFETIME_DEFAULT_S (12.0 * 3600.0)
/* What a page with an expired token is told (the HTTP answer's body, the WebSocket's "expired" message). */
#define PALP_WEB_TOKEN_EXPIRED_TEXT "This access token has expired: ask your instructor for a new one."

/* 1 when a token issued at issued_s [s, Unix time] is past its lifetime at now_s [s, Unix time]:
 * now_s >= issued_s + lifetime_s; 0 while it is valid, and always for lifetime_s 0 (no expiry). The
 * clock is the caller's (palp-web's wall clock; tests give theirs). A NaN anywhere reads as expired. */
int palp_web_token_expired(double issued_s, double lifetime_s, double now_s);

/* A Unix time [s] as UTC, "2026-12-07T05:00:00Z", into out (>= 21 bytes); "?" for one not representable. */
void palp_web_utc_text(double unix_s, char *out, size_t len);

/* 1 when `given` (len bytes, not necessarily NUL-terminated) equals the NUL-terminated `want`;
 * the time taken does not depend on where they differ. */
int palp_web_token_equal(const char *want, const char *given, size_t len);

/* The value of cookie `name` in a Cookie header ("a=1; palp_token=xyz"), copied into out (NUL-
 * terminated); 0 when found, -1 when absent or longer than outlen - 1. */
int palp_web_cookie_get(const char *header, const char *name, char *out, size_t outlen);

/* 0 when an URL path may name a served file: starts with '/', only [A-Za-z0-9._/-], no "..",
 * no "//", no path component starting with '.', shorter than 200 characters. Else PALP_EINVAL. */
int palp_web_path_check(const char *path);

/* A trainee's own access token (--trainee-tokens FILE): a page that gives it is that trainee's and
 * is sent that trainee's sessions only, as the trainee's DDS permissions would read them. */
#define PALP_WEB_TRAINEES_MAX 256
typedef struct palp_web_trainee_token {
  char name[32];                       /* the trainee name of the sessions (an identity's NAME) */
  char token[PALP_WEB_TOKEN_MAX + 1];
  double issued_s;                     /* when it was issued [s, Unix time]: its file's last write; 0 from
                                        * palp_web_trainee_tokens_parse, which does not know it */
} palp_web_trainee_token;

/* Parses "NAME TOKEN" lines (blank lines and lines starting with '#' skipped): NAME 1-31 of
 * [a-z0-9_-], TOKEN as palp_web_token_check; no NAME or TOKEN twice, none equal to `instructor`
 * (the bridge's own token, may be NULL). Returns the count (0..max) or PALP_EINVAL with the line
 * and reason in err. */
int palp_web_trainee_tokens_parse(const char *text, const char *instructor, palp_web_trainee_token *out, int max,
                                  char *err, size_t errlen);

/* Content type by file extension; NULL for a type palp-web does not serve. */
const char *palp_web_mime(const char *path);

#endif
