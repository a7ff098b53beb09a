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
/* ... and a page whose token was removed or replaced in its file while it was open (SIGHUP re-reads them). */
#define PALP_WEB_TOKEN_WITHDRAWN_TEXT "This access token was withdrawn: ask your instructor for a new one."

/* 1 when a token issued at issued_s [s, Unix time] is past its lifetime at now_s [s, Unix time]:
 * now_s >= issued_s + lifetime_s; 0 while it is valid, and always for lifetime_s 0 (no expiry). The
 * clock is the caller's: palp-web reads it at start only (what it prints then); serving, it compares
 * the deadlines below. A NaN anywhere reads as expired. */
int palp_web_token_expired(double issued_s, double lifetime_s, double now_s);

/* The clocks a token's lifetime is measured on: the wall clock [s, Unix time], which says when a token
 * was issued (its file's last write is a wall-clock time), and a steady clock [s, any origin] that no
 * setting of the wall clock moves. The wall clock is read once, at start; every later use compares the
 * steady one, so that NTP correcting a machine that booted with a wrong clock (a jump of hours, in
 * either direction) neither expires every open page at once nor lengthens a token's life (found by
 * review, 2026-12-06). Tests give their own clock. */
typedef struct palp_web_clock {
  double (*wall_s)(void *user);
  double (*steady_s)(void *user);
  void *user;
} palp_web_clock;
/* The system's: CLOCK_REALTIME, and CLOCK_BOOTTIME as the steady clock (CLOCK_MONOTONIC stops while the
 * machine is suspended: a laptop closed overnight would keep Monday's token open on Tuesday). */
const palp_web_clock *palp_web_clock_system(void);

/* A token's expiry, fixed once at start (palp_web_token_deadline_at_start). */
typedef struct palp_web_token_deadline {
  double lifetime_s; /* 0: never expires */
  double steady_s;   /* the expiry on the clock's steady_s */
  double wall_s;     /* the same instant by the wall clock as it read at start [s, Unix time] (for one
                      * expired before start, issued + lifetime): for messages */
} palp_web_token_deadline;

/* The expiry of a token issued at issued_s [s, Unix time] with lifetime_s (0: none), read from clock c
 * now (start): what is left of its life, issued_s + lifetime_s - the wall clock now, clamped to
 * [0, lifetime_s] (a file written "in the future" gets no more than its lifetime), counted from the
 * steady clock now. A NaN anywhere gives a token expired at start. */
palp_web_token_deadline palp_web_token_deadline_at_start(double issued_s, double lifetime_s, const palp_web_clock *c);
/* 1 when a token with deadline d is past it by clock c (the steady clock alone), 0 while valid, always 0
 * for lifetime 0. */
int palp_web_token_past(const palp_web_token_deadline *d, const palp_web_clock *c);

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
