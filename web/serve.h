/*
 * serve.h - palp-web's HTTP and WebSocket side on libwebsockets (palp_web_serve_).
 *
 * Serves the static pages (web/www) and three.js from Debian's libjs-three under /lib/three/,
 * and one WebSocket endpoint, /ws, that streams the hub's messages. With a token configured every
 * request must carry it (?token= or the cookie the first page load sets): without it HTTP answers
 * 401 and the WebSocket handshake is refused. A trainee's own token (if given any) serves the same
 * pages, but its WebSocket is scoped to that trainee's sessions. With a certificate and key it
 * serves HTTPS and WSS instead (libwebsockets on OpenSSL).
 */
#ifndef PALP_WEB_SERVE_H
#define PALP_WEB_SERVE_H

#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>

#include "access.h"
#include "hub.h"
#include "palp_log.h"

/* The access tokens served: read at start, and re-read from their files at SIGHUP (main.c), then handed
 * over whole (palp_web_serve_tokens_replace). */
typedef struct palp_web_tokens {
  char token[PALP_WEB_TOKEN_MAX + 1]; /* the instructors' */
  double token_issued_s;              /* when it was issued [s, Unix time]: its file's last write, or start */
  int trainee_count;
  palp_web_trainee_token trainees[PALP_WEB_TRAINEES_MAX]; /* each with its issued_s */
} palp_web_tokens;

typedef struct palp_web_serve_def {
  const char *listen;    /* address to bind, default 127.0.0.1 */
  int port;              /* 0: any free port (printed) */
  const char *token;     /* NULL: no token (loopback only; main refuses otherwise) */
  const char *www_dir;   /* the pages */
  const char *three_dir; /* /usr/share/javascript/three */
  int max_clients;       /* WebSocket connections at once */
  /* Trainees' own tokens (--trainee-tokens FILE; needs token): a page that gives one is scoped to
   * that trainee's sessions (palp_web_cursor.scope). token stays the instructors'. */
  const palp_web_trainee_token *trainees;
  int trainee_count;
  /* Every token's lifetime [s] (0: none), from when it was issued: token_issued_s [s, Unix time] for
   * the instructors', each trainee's own issued_s. What is left of each is fixed at
   * palp_web_serve_create by the wall clock and counted down on the steady clock from then
   * (palp_web_token_deadline_at_start: a wall clock corrected later moves no expiry). Checked on every
   * request and handshake, and an open WebSocket is closed at its token's expiry; a page with an
   * expired token is told so
   * (PALP_WEB_TOKEN_EXPIRED_TEXT: the HTTP 401's body, an {"type": "expired"} WebSocket message). */
  double token_lifetime_s, token_issued_s;
  palp_log *log; /* each expired token's first refusal is logged (NULL: stderr) */
  /* HTTPS and WSS on the same port (both or neither; PEM files): the token and the pages then
   * cross the network encrypted, and the cookie is marked Secure. main refuses to serve beyond
   * loopback without them unless told --insecure-http. */
  const char *tls_cert, *tls_key;
} palp_web_serve_def;

typedef struct palp_web_serve_stats {
  uint64_t http_ok, http_denied, http_missing;
  uint64_t http_expired, ws_expired; /* refused for an expired token (in http_denied, ws_denied) or, ws,
                                      * closed at its expiry */
  uint64_t ws_opened, ws_closed, ws_denied, ws_full;
  uint64_t ws_withdrawn; /* closed because their token was withdrawn (palp_web_serve_tokens_replace) */
  uint64_t msgs, bytes, control_ok, control_bad;
} palp_web_serve_stats;

typedef struct palp_web_server palp_web_server;

palp_web_server *palp_web_serve_create(const palp_web_serve_def *def, palp_web_hub *hub, char *err, size_t errlen);
/* The port actually bound (useful with port 0). */
int palp_web_serve_port(const palp_web_server *s);
/* Serves until *stop becomes non-zero. */
void palp_web_serve_run(palp_web_server *s, atomic_int *stop);
/* Thread-safe: makes the service loop push new hub messages to the browsers. */
void palp_web_serve_wake(void *server);
/* Thread-safe (main calls it from the hub's thread at SIGHUP): the tokens to serve from now on, copied; the
 * web server's thread puts them in place at its next pass (<= 100 ms), all at once, and logs what changed.
 * From then on every request and handshake is checked against them, each token's expiry recomputed from its
 * issued time as at start (one whose token and issued time are the same keeps its expiry); every open
 * WebSocket whose token is the same (the instructors' unchanged, a trainee's name with the same token) stays
 * open, one whose token was removed or changed is told (PALP_WEB_TOKEN_WITHDRAWN_TEXT) and closed (1008,
 * "token withdrawn"). A newer call before that pass replaces the older's tokens. 0, or PALP_EINVAL for a
 * server started without a token (nothing to replace), PALP_ENOMEM. */
int palp_web_serve_tokens_replace(palp_web_server *s, const palp_web_tokens *t);
/* The counters as of the service loop's last pass (a copy it makes under a lock after each): safe from
 * any thread, e.g. main's --stats line printed from the hub's. */
void palp_web_serve_stats_get(palp_web_server *s, palp_web_serve_stats *out);
void palp_web_serve_destroy(palp_web_server *s);

#endif
