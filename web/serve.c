/* serve.c - palp-web's HTTP + WebSocket server on libwebsockets. */
#include "serve.h"

#include <fcntl.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <libwebsockets.h>
#include <pthread.h>

#include "access.h"
#include "palp.h"

#define COOKIE "palp_token"
#define WS_PATH "/ws"
#define CONTROL_MAX 256
/* WebSocket pages a trainee's token may hold open at once (a page and a spare tab or two), and the
 * connections of max_clients only an instructor's page (or a page without tokens) may take: one
 * trainee, or a few, opening pages in a loop must not lock the class and its instructor out
 * (session 75, found by review: max_clients was one pool for every token). */
#define PAGES_PER_TRAINEE 3
#define INSTRUCTOR_RESERVE 2
/* ... at most half of max_clients (a --max-clients of 2 left trainees none) */
static int instructor_reserve(int max_clients) {
  return max_clients / 2 < INSTRUCTOR_RESERVE ? max_clients / 2 : INSTRUCTOR_RESERVE;
}

struct conn;

struct palp_web_server {
  palp_web_serve_def def; /* its token and trainees are start's: the served ones are tok's */
  char listen[64];
  char www[512], three[512];
  int have_token;
  /* The tokens served (the service thread alone reads them), and a set re-read at SIGHUP waiting to take
   * their place (palp_web_serve_tokens_replace, from the hub's thread): handed over under tok_mu, put in place
   * by the service thread between two passes (apply_tokens), so no request ever sees half of each. */
  palp_web_tokens *tok, *pending;
  pthread_mutex_t tok_mu;
  /* The attached WebSocket pages (the service thread alone): a SIGHUP's new tokens are checked against every
   * open page at once (apply_tokens). gen counts the token sets put in place. */
  struct conn *conns;
  unsigned gen;
  palp_web_hub *hub;
  struct lws_context *ctx;
  struct lws_vhost *vh;
  struct lws_protocols protocols[2];
  lws_retry_bo_t retry;
  /* Counted by the lws service thread alone, without a lock; stats_pub is its copy under stats_mu, made
   * after every lws_service pass (at least every 100 ms: the hub wakes the loop), which
   * palp_web_serve_stats_get reads. main's --stats line is printed from the hub's thread (on_wake),
   * which read the counters themselves while this thread wrote them (a data race). */
  palp_web_serve_stats stats, stats_pub;
  pthread_mutex_t stats_mu;
  /* Pages open per trainee token, and in all for trainee tokens (the lws service thread alone
   * counts them: no lock). */
  int trainee_pages[PALP_WEB_TRAINEES_MAX + 1], trainee_pages_all;
  /* Whose expired token the log has named (say_expired): 0 the instructors', k + 1 trainee k's (the
   * service thread alone). */
  unsigned char expired_said[PALP_WEB_TRAINEES_MAX + 1];
  /* Each token's expiry, fixed at palp_web_serve_create from the wall clock and compared on the steady
   * clock after (palp_web_token_deadline_at_start): 0 the instructors', k + 1 trainee k's. Fixed anew for
   * a token a SIGHUP brought or re-issued (apply_tokens), from the wall clock then. */
  palp_web_token_deadline deadline[PALP_WEB_TRAINEES_MAX + 1];
};

/* Per connection (HTTP or WebSocket): libwebsockets allocates and zeroes it. */
typedef struct conn {
  palp_web_cursor cursor;
  int who; /* authorised()'s answer at the handshake: 0 an instructor's page, k + 1 trainee k's (renumbered
            * when a SIGHUP's tokens keep its token: apply_tokens) */
  int expired; /* its token is past its lifetime: told so, then closed (tell_expired) */
  int withdrawn; /* its token was removed or changed at a SIGHUP: told so, then closed (tell_expired) */
  int told;    /* tell_expired has written to it (lws may offer a closing connection a write again) */
  int attached;
  unsigned gen; /* the token set it was let in by (palp_web_server.gen) */
  struct lws *wsi;               /* attached: its connection, and its place in palp_web_server.conns */
  struct conn *prev, *next;
  size_t rx_len;
  int rx_overflow;
  char rx[CONTROL_MAX];
} conn;

static int fail(char *err, size_t errlen, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err, errlen, fmt, ap);
  va_end(ap);
  return -1;
}

static palp_web_server *server_of(struct lws *wsi) {
  return (palp_web_server *)lws_context_user(lws_get_context(wsi));
}

/* Whose token a value is: 0 the instructors' (--token), k + 1 trainee k's, -1 nobody's. Every token
 * is compared, each in constant time, so the time does not tell which one nearly matched. */
static int token_owner(const palp_web_server *s, const char *v) {
  const size_t n = strlen(v);
  const palp_web_tokens *t = s->tok;
  int who = palp_web_token_equal(t->token, v, n) ? 0 : -1;
  for (int k = 0; k < t->trainee_count; k++)
    if (palp_web_token_equal(t->trainees[k].token, v, n) && who < 0) who = k + 1;
  return who;
}

static double issued_of(const palp_web_server *s, int who) {
  return who > 0 ? s->tok->trainees[who - 1].issued_s : s->tok->token_issued_s;
}

/* 1 when who's token (token_owner's answer) is past its lifetime now: its deadline, fixed at start (or at the
 * SIGHUP that brought it), on the steady clock (a wall clock set by NTP mid-class moves no token's expiry). */
static int token_expired(const palp_web_server *s, int who) {
  return s->have_token && who >= 0 && who <= PALP_WEB_TRAINEES_MAX &&
         palp_web_token_past(&s->deadline[who], palp_web_clock_system());
}

/* The first refusal of each expired token in the log (a page left open retries every second: the
 * stats line counts the rest). */
static void say_expired(palp_web_server *s, int who) {
  if (who < 0 || who > PALP_WEB_TRAINEES_MAX || s->expired_said[who]) return;
  s->expired_said[who] = 1;
  char at[32], issued[32], whose[64];
  palp_web_utc_text(s->deadline[who].wall_s, at, sizeof at); /* by the wall clock as it read at start */
  palp_web_utc_text(issued_of(s, who), issued, sizeof issued);
  if (who > 0) snprintf(whose, sizeof whose, "trainee %s's token", s->tok->trainees[who - 1].name);
  else snprintf(whose, sizeof whose, "the instructors' token");
  palp_log_warn(s->def.log,
                "%s expired at %s (issued %s, lifetime %g h, --token-lifetime-h): its pages are refused and told to "
                "ask for a new one; further refusals counted, not logged (--stats)",
                whose, at, issued, s->def.token_lifetime_s / 3600.0);
}

/* Who the request is (token_owner: 0 an instructor, k + 1 trainee k, -1 refused) by the token in
 * its URL or its cookie; 0 when no token is required. *from_url says it came in the URL (the answer
 * then sets the cookie for the page's own requests); *stale that the token is past its lifetime
 * (checked at every request: the caller refuses it, saying why). */
static int authorised(palp_web_server *s, struct lws *wsi, int allow_cookie, int *from_url, int *stale) {
  *from_url = 0;
  *stale = 0;
  if (!s->have_token) return 0;
  char v[PALP_WEB_TOKEN_MAX + 16];
  /* lws copies "token=VALUE" into v and returns where VALUE starts */
  const char *arg = lws_get_urlarg_by_name(wsi, "token=", v, (int)sizeof v);
  const int by_url = arg ? token_owner(s, arg) : -1;
  if (by_url >= 0) {
    *from_url = 1;
    *stale = token_expired(s, by_url);
    return by_url;
  }
  if (!allow_cookie) return -1;
  const int n = lws_hdr_total_length(wsi, WSI_TOKEN_HTTP_COOKIE);
  if (n <= 0 || n > 4096) return -1;
  char *h = malloc((size_t)n + 1);
  int who = -1;
  if (h && lws_hdr_copy(wsi, h, n + 1, WSI_TOKEN_HTTP_COOKIE) > 0 &&
      palp_web_cookie_get(h, COOKIE, v, sizeof v) == 0)
    who = token_owner(s, v);
  free(h);
  *stale = token_expired(s, who);
  return who;
}

/* A browser page from another origin must not drive the WebSocket with this page's cookie or
 * token: the Origin's host:port must be the Host the request was sent to. */
static int same_origin(struct lws *wsi) {
  char origin[256], host[256];
  /* absent: not a browser. Too long to copy is not absent (lws_hdr_copy says -1 for both; a page
   * served from a 249-character host name went through as "no Origin" until session 75): refused. */
  const int on = lws_hdr_total_length(wsi, WSI_TOKEN_ORIGIN);
  if (on <= 0) return 1;
  if (on >= (int)sizeof origin || lws_hdr_copy(wsi, origin, sizeof origin, WSI_TOKEN_ORIGIN) <= 0) return 0;
  if (lws_hdr_copy(wsi, host, sizeof host, WSI_TOKEN_HOST) <= 0) return 0;
  const char *o = strstr(origin, "://");
  return o && !strcmp(o + 3, host);
}

/* Without a token palp-web listens on loopback only, and answers only a request sent to a loopback
 * name: a page of another site whose name was made to resolve to 127.0.0.1 (DNS rebinding) is
 * same-origin with itself (Origin = Host = evil.example:8090) and would read every session. With a
 * token, such a page has none. */
static int host_allowed(palp_web_server *s, struct lws *wsi) {
  if (s->have_token) return 1;
  char host[256];
  const int n = lws_hdr_total_length(wsi, WSI_TOKEN_HOST);
  return n > 0 && n < (int)sizeof host && lws_hdr_copy(wsi, host, sizeof host, WSI_TOKEN_HOST) > 0 &&
         palp_web_host_is_loopback(host);
}

/* Every HTTP answer's headers (docs/web.md), a file's and a refusal's alike: libwebsockets adds the
 * vhost's own to each status line it writes, which lws_return_http_status's answers (401, 404) lacked
 * when they were passed to lws_serve_http_file only. */
static const struct lws_protocol_vhost_options answer_headers[] = {
    {&answer_headers[1], NULL, "Cache-Control:", "no-store"},
    {&answer_headers[2], NULL, "X-Content-Type-Options:", "nosniff"},
    {&answer_headers[3], NULL, "Referrer-Policy:", "no-referrer"},
    {NULL, NULL, "Content-Security-Policy:",
     "default-src 'self'; connect-src 'self'; img-src 'self' data:; frame-ancestors 'none'"},
};

/* An HTTP answer without a page; body (plain words, lws puts them in a minimal HTML page) may be NULL. */
static int http_status(struct lws *wsi, unsigned code, const char *body, uint64_t *counter) {
  (*counter)++;
  if (lws_return_http_status(wsi, code, body)) return -1;
  return lws_http_transaction_completed(wsi) ? -1 : 0;
}

static int serve_file(struct lws *wsi, palp_web_server *s, const char *uri) {
  int from_url = 0, stale = 0;
  const int who = authorised(s, wsi, 1, &from_url, &stale);
  if (who < 0 || !host_allowed(s, wsi)) return http_status(wsi, HTTP_STATUS_UNAUTHORIZED, NULL, &s->stats.http_denied);
  if (stale) { /* a token this bridge gave, too old: the page says why, not a bare 401 */
    s->stats.http_expired++;
    say_expired(s, who);
    return http_status(wsi, HTTP_STATUS_UNAUTHORIZED, PALP_WEB_TOKEN_EXPIRED_TEXT, &s->stats.http_denied);
  }
  const char *path = !strcmp(uri, "/") ? "/index.html" : uri;
  const char *mime = palp_web_mime(path);
  if (palp_web_path_check(path) != 0 || !mime) return http_status(wsi, HTTP_STATUS_NOT_FOUND, NULL, &s->stats.http_missing);
  char file[1024];
  static const char lib[] = "/lib/three/";
  if (!strncmp(path, lib, sizeof lib - 1))
    snprintf(file, sizeof file, "%s/%s", s->three, path + sizeof lib - 1);
  else
    snprintf(file, sizeof file, "%s%s", s->www, path);
  /* a file that is not there, or that this user cannot open (mode 000), is answered here:
   * lws_serve_http_file sends its own 404 for it and returns 1, as for a file it served, which counted it
   * in http_ok. Opened, not only stat()ed, so a file stat() sees but open() refuses is missing too. */
  struct stat sb;
  const int fd = open(file, O_RDONLY | O_CLOEXEC);
  const int regular = fd >= 0 && fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode);
  if (fd >= 0) close(fd);
  if (!regular) return http_status(wsi, HTTP_STATUS_NOT_FOUND, NULL, &s->stats.http_missing);
  char headers[512] = ""; /* answer_headers come with the status line */
  int n = 0;
  if (from_url && s->have_token)
    n = snprintf(headers, sizeof headers, "Set-Cookie: " COOKIE "=%s; Path=/; HttpOnly; SameSite=Strict%s\x0d\x0a",
                 who ? s->tok->trainees[who - 1].token : s->tok->token, s->def.tls_cert ? "; Secure" : "");
  const int rc = lws_serve_http_file(wsi, file, mime, headers, n);
  /* < 0: lws failed (it may have answered already, lws-http.h): no second answer; the connection closes */
  if (rc < 0) {
    s->stats.http_missing++;
    return -1;
  }
  s->stats.http_ok++;
  if (rc > 0 && lws_http_transaction_completed(wsi)) return -1;
  return 0;
}

/* Tells a WebSocket page that its token expired, or was withdrawn at a SIGHUP ({"type": "expired",
 * "message": ...}, which the pages show and stop reconnecting on) and closes it (1008, policy violation,
 * "token expired" or "token withdrawn"): a refused handshake tells a page nothing it can show. Returns -1,
 * the callback's "close". */
static int tell_expired(struct lws *wsi, palp_web_server *s, conn *c) {
  if (c->told) return -1;
  c->told = 1;
  if (c->withdrawn) {
    s->stats.ws_withdrawn++;
  } else if (c->attached) { /* open when its token expired (checked at each of its wake-ups, <= 100 ms) */
    s->stats.ws_expired++;
    say_expired(s, c->who);
  }
  static const char expired[] = "{\"type\":\"expired\",\"message\":\"" PALP_WEB_TOKEN_EXPIRED_TEXT "\"}";
  static const char withdrawn[] = "{\"type\":\"expired\",\"message\":\"" PALP_WEB_TOKEN_WITHDRAWN_TEXT "\"}";
  const char *msg = c->withdrawn ? withdrawn : expired;
  const size_t n = strlen(msg);
  unsigned char buf[LWS_PRE + (sizeof expired > sizeof withdrawn ? sizeof expired : sizeof withdrawn)];
  memcpy(buf + LWS_PRE, msg, n);
  lws_write(wsi, buf + LWS_PRE, n, LWS_WRITE_TEXT);
  const char *why = c->withdrawn ? "token withdrawn" : "token expired";
  lws_close_reason(wsi, LWS_CLOSE_STATUS_POLICY_VIOLATION, (unsigned char *)why, strlen(why));
  return -1;
}

/* Closes a page the bridge has no room for (1008) with the reason, which the page shows: a bare close
 * told it nothing, and it retried every second without saying why. Returns -1, the callback's "close". */
static int refuse_full(struct lws *wsi, palp_web_server *s, const char *why) {
  s->stats.ws_full++;
  lws_close_reason(wsi, LWS_CLOSE_STATUS_POLICY_VIOLATION, (unsigned char *)why, strlen(why));
  return -1;
}

static int callback(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in, size_t len) {
  palp_web_server *s = server_of(wsi);
  conn *c = user;
  switch (reason) {
  case LWS_CALLBACK_HTTP:
    return serve_file(wsi, s, (const char *)in);

  case LWS_CALLBACK_HTTP_FILE_COMPLETION:
    return lws_http_transaction_completed(wsi) ? -1 : 0;

  case LWS_CALLBACK_FILTER_PROTOCOL_CONNECTION: {
    char uri[64];
    int from_url = 0, stale = 0;
    /* The WebSocket carries the token in its URL (a page reads it from its own address); the
     * cookie alone is not enough, so a cross-site page cannot ride on it. */
    const int who = lws_hdr_copy(wsi, uri, sizeof uri, WSI_TOKEN_GET_URI) > 0 && !strcmp(uri, WS_PATH)
                        ? authorised(s, wsi, 0, &from_url, &stale)
                        : -1;
    if (who < 0 || !same_origin(wsi) || !host_allowed(s, wsi) || !c) {
      s->stats.ws_denied++;
      return 1;
    }
    c->who = who; /* the connection's data exists from here on, zeroed */
    c->gen = s->gen;
    /* An expired token's page is let in only to be told so (tell_expired): never attached to the hub. */
    c->expired = stale;
    return 0;
  }

  case LWS_CALLBACK_ESTABLISHED: {
    const int who = c->who;
    if (c->gen != s->gen) { /* let in by tokens a SIGHUP has replaced since (who counts in the old ones) */
      c->withdrawn = 1;
      lws_callback_on_writable(wsi);
      return 0;
    }
    if (c->expired) {
      s->stats.ws_denied++;
      s->stats.ws_expired++;
      say_expired(s, who);
      lws_callback_on_writable(wsi);
      return 0;
    }
    /* (each reason at most 123 bytes, a close frame's) */
    if (who > 0 && who <= PALP_WEB_TRAINEES_MAX && s->trainee_pages[who] >= PAGES_PER_TRAINEE) {
      char why[96];
      snprintf(why, sizeof why, "this trainee's token has %d pages open already: close one of them", PAGES_PER_TRAINEE);
      return refuse_full(wsi, s, why);
    }
    if (who > 0 && (who > PALP_WEB_TRAINEES_MAX ||
                    s->trainee_pages_all >= s->def.max_clients - instructor_reserve(s->def.max_clients)))
      return refuse_full(wsi, s, "palp-web has no room for more trainees' pages (--max-clients)");
    if (palp_web_hub_attach(s->hub, &c->cursor, s->def.max_clients) != 0)
      return refuse_full(wsi, s, "palp-web has no room for more pages (--max-clients)");
    if (who > 0) s->trainee_pages[who]++, s->trainee_pages_all++;
    if (who > 0) /* a trainee's page: that trainee's sessions only (palp_web_hub_attach zeroed the cursor) */
      palp_web_hub_scope(s->hub, &c->cursor, s->tok->trainees[who - 1].name);
    c->attached = 1;
    c->wsi = wsi;
    c->prev = NULL;
    c->next = s->conns;
    if (s->conns) s->conns->prev = c;
    s->conns = c;
    s->stats.ws_opened++;
    lws_callback_on_writable(wsi);
    return 0;
  }

  case LWS_CALLBACK_CLOSED:
    if (c && c->attached) {
      palp_web_hub_detach(s->hub, &c->cursor);
      c->attached = 0;
      if (c->prev) c->prev->next = c->next;
      else s->conns = c->next;
      if (c->next) c->next->prev = c->prev;
      /* a withdrawn page no longer counts among its token's (apply_tokens) */
      if (!c->withdrawn && c->who > 0 && c->who <= PALP_WEB_TRAINEES_MAX)
        s->trainee_pages[c->who]--, s->trainee_pages_all--;
      s->stats.ws_closed++;
    }
    return 0;

  case LWS_CALLBACK_RECEIVE: {
    /* Only control messages ({"follow": ...}, {"trainee": ...}, {"finding": ...}): the first two
     * change what this page is sent; a finding reaches DDS only from a bound trainee page, after
     * the hub's checks. Anything longer than CONTROL_MAX is dropped whole. Nothing from a page
     * whose token has expired (its next write tells it and closes). */
    if (!c->attached || c->expired || c->withdrawn || token_expired(s, c->who)) {
      lws_callback_on_writable(wsi);
      return 0;
    }
    if (lws_frame_is_binary(wsi)) c->rx_overflow = 1;
    if (!c->rx_overflow && c->rx_len + len <= CONTROL_MAX) {
      memcpy(c->rx + c->rx_len, in, len);
      c->rx_len += len;
    } else {
      c->rx_overflow = 1;
    }
    if (lws_is_final_fragment(wsi) && !lws_remaining_packet_payload(wsi)) {
      const int rc = c->rx_overflow ? PALP_EINVAL : palp_web_hub_control(s->hub, &c->cursor, c->rx, c->rx_len);
      /* done, a finding refused, or a control refused with why (a trainee's token asking for the
       * dashboard): every one gets an answer */
      if (rc >= 0) s->stats.control_ok++;
      else s->stats.control_bad++;
      lws_callback_on_writable(wsi);
      c->rx_len = 0;
      c->rx_overflow = 0;
    }
    return 0;
  }

  case LWS_CALLBACK_SERVER_WRITEABLE: {
    /* every page is offered a write at each of the hub's wake-ups (<= 100 ms): its token's lifetime
     * is checked there too, so a page left open is closed at its token's expiry */
    if (c->expired || c->withdrawn || (c->attached && token_expired(s, c->who))) return tell_expired(wsi, s, c);
    if (!c->attached) return 0;
    unsigned char *buf = NULL;
    size_t n = 0;
    int binary = 0;
    const int got = palp_web_hub_next(s->hub, &c->cursor, LWS_PRE, &buf, &n, &binary);
    if (got <= 0) return 0;
    const int w = lws_write(wsi, buf + LWS_PRE, n, binary ? LWS_WRITE_BINARY : LWS_WRITE_TEXT);
    free(buf);
    if (w < (int)n) return -1; /* the connection is gone */
    s->stats.msgs++;
    s->stats.bytes += n;
    lws_callback_on_writable(wsi); /* more may be waiting; the next call says */
    return 0;
  }

  case LWS_CALLBACK_EVENT_WAIT_CANCELLED:
    /* palp_web_serve_wake from the hub's thread: offer every page its new messages. */
    if (lws_get_vhost(wsi) && lws_get_protocol(wsi))
      lws_callback_on_writable_all_protocol_vhost(lws_get_vhost(wsi), lws_get_protocol(wsi));
    return 0;

  default:
    break;
  }
  return lws_callback_http_dummy(wsi, reason, user, in, len);
}

static void lws_log_to_stderr(int level, const char *line) {
  (void)level;
  fprintf(stderr, "palp-web: lws: %s", line);
}

palp_web_server *palp_web_serve_create(const palp_web_serve_def *def, palp_web_hub *hub, char *err, size_t errlen) {
  palp_web_server *s = calloc(1, sizeof *s);
  if (!s) {
    fail(err, errlen, "out of memory");
    return NULL;
  }
  s->def = *def;
  s->hub = hub;
  snprintf(s->listen, sizeof s->listen, "%s", def->listen ? def->listen : "127.0.0.1");
  snprintf(s->www, sizeof s->www, "%s", def->www_dir);
  snprintf(s->three, sizeof s->three, "%s", def->three_dir);
  s->tok = calloc(1, sizeof *s->tok);
  if (!s->tok) {
    fail(err, errlen, "out of memory");
    free(s);
    return NULL;
  }
  if (def->token) {
    snprintf(s->tok->token, sizeof s->tok->token, "%s", def->token);
    s->have_token = 1;
  }
  s->tok->token_issued_s = def->token_issued_s;
  /* the per-token arrays hold PALP_WEB_TRAINEES_MAX (main's parse reads no more) */
  s->tok->trainee_count = def->trainee_count > PALP_WEB_TRAINEES_MAX ? PALP_WEB_TRAINEES_MAX : def->trainee_count;
  if (s->tok->trainee_count > 0)
    memcpy(s->tok->trainees, def->trainees, (size_t)s->tok->trainee_count * sizeof *def->trainees);
  s->def.listen = s->listen;
  s->def.token = NULL, s->def.trainees = NULL, s->def.trainee_count = 0; /* tok's from here on */
  for (int who = 0; who <= s->tok->trainee_count; who++)
    s->deadline[who] = palp_web_token_deadline_at_start(issued_of(s, who), def->token_lifetime_s, palp_web_clock_system());
  lws_set_log_level(LLL_ERR | LLL_WARN, lws_log_to_stderr);
  s->protocols[0] = (struct lws_protocols){.name = "palp", .callback = callback, .per_session_data_size = sizeof(conn),
                                           .rx_buffer_size = 4096};
  /* A page whose machine vanished without closing (no FIN) is pinged after 10 s idle and dropped
   * after 20 s; an abrupt close on a live machine is seen at once. */
  s->retry = (lws_retry_bo_t){.secs_since_valid_ping = 10, .secs_since_valid_hangup = 20};
  struct lws_context_creation_info info;
  memset(&info, 0, sizeof info);
  info.port = def->port;
  info.iface = s->listen;
  info.protocols = s->protocols;
  info.user = s;
  info.uid = -1;
  info.gid = -1;
  info.retry_and_idle_policy = &s->retry;
  info.headers = answer_headers;
  if (!strchr(s->listen, ':')) info.options |= LWS_SERVER_OPTION_DISABLE_IPV6;
  if (def->tls_cert) {
    info.options |= LWS_SERVER_OPTION_DO_SSL_GLOBAL_INIT;
    info.ssl_cert_filepath = def->tls_cert;
    info.ssl_private_key_filepath = def->tls_key;
    /* HTTP/1.1 only: the pages are a handful of files, and the WebSocket (RFC 6455) upgrades from
     * HTTP/1.1. Offered h2, curl 7.88 took it and the file serving here, written for HTTP/1.1
     * transactions, answered nothing ("empty reply"). */
    info.alpn = "http/1.1";
  }
  s->ctx = lws_create_context(&info);
  if (!s->ctx) {
    if (def->tls_cert)
      fail(err, errlen,
           "cannot serve HTTPS on %s port %d: the certificate %s and key %s must be PEM and belong together "
           "(the port may also be in use, or not an address of this machine)",
           s->listen, def->port, def->tls_cert, def->tls_key);
    else
      fail(err, errlen, "cannot listen on %s port %d (in use, or not an address of this machine?)", s->listen,
           def->port);
    free(s->tok);
    free(s);
    return NULL;
  }
  s->vh = lws_get_vhost_by_name(s->ctx, "default");
  if (!s->vh || lws_get_vhost_listen_port(s->vh) <= 0) {
    fail(err, errlen, "cannot listen on %s port %d", s->listen, def->port);
    lws_context_destroy(s->ctx);
    free(s->tok);
    free(s);
    return NULL;
  }
  pthread_mutex_init(&s->stats_mu, NULL);
  pthread_mutex_init(&s->tok_mu, NULL);
  return s;
}

int palp_web_serve_port(const palp_web_server *s) { return lws_get_vhost_listen_port(s->vh); }

/* The service thread's counters, copied under the lock for palp_web_serve_stats_get (stats_pub). */
static void publish_stats(palp_web_server *s) {
  pthread_mutex_lock(&s->stats_mu);
  s->stats_pub = s->stats;
  pthread_mutex_unlock(&s->stats_mu);
}

/* Puts a SIGHUP's tokens in place (palp_web_serve_tokens_replace), on the service thread between two passes:
 * every later request and handshake is checked against them, and each open page once, now. Logs what
 * changed. */
static void apply_tokens(palp_web_server *s) {
  pthread_mutex_lock(&s->tok_mu);
  palp_web_tokens *next = s->pending;
  s->pending = NULL;
  pthread_mutex_unlock(&s->tok_mu);
  if (!next) return;
  palp_web_tokens *old = s->tok;
  const palp_web_clock *clk = palp_web_clock_system();
  const double life = s->def.token_lifetime_s;
  /* map: an old `who` to the new one, -1 for a token withdrawn (removed, or changed: a trainee's name with
   * another token). A token kept with the same issued time keeps its expiry, and whether the log named it
   * expired; any other is given one as at start (its file rewritten: issued anew). */
  int map[PALP_WEB_TRAINEES_MAX + 1];
  palp_web_token_deadline deadline[PALP_WEB_TRAINEES_MAX + 1];
  unsigned char said[PALP_WEB_TRAINEES_MAX + 1];
  const int same_instructor = !strcmp(old->token, next->token);
  map[0] = same_instructor ? 0 : -1;
  const int keep0 = same_instructor && old->token_issued_s == next->token_issued_s;
  deadline[0] = keep0 ? s->deadline[0] : palp_web_token_deadline_at_start(next->token_issued_s, life, clk);
  said[0] = keep0 ? s->expired_said[0] : 0;
  for (int j = 1; j <= next->trainee_count; j++) {
    deadline[j] = palp_web_token_deadline_at_start(next->trainees[j - 1].issued_s, life, clk);
    said[j] = 0;
  }
  int added = next->trainee_count, removed = 0, changed = 0;
  for (int k = 0; k < old->trainee_count; k++) {
    const palp_web_trainee_token *o = &old->trainees[k];
    map[k + 1] = -1;
    int j = 0;
    while (j < next->trainee_count && strcmp(next->trainees[j].name, o->name)) j++;
    if (j == next->trainee_count) {
      removed++;
      continue;
    }
    added--;
    if (strcmp(next->trainees[j].token, o->token)) {
      changed++;
      continue;
    }
    map[k + 1] = j + 1;
    if (next->trainees[j].issued_s == o->issued_s) deadline[j + 1] = s->deadline[k + 1], said[j + 1] = s->expired_said[k + 1];
  }
  s->tok = next;
  memcpy(s->deadline, deadline, (size_t)(next->trainee_count + 1) * sizeof deadline[0]);
  memcpy(s->expired_said, said, (size_t)(next->trainee_count + 1));
  s->gen++;
  /* every open page at once: renumbered, or told and closed; the trainees' counts made anew */
  memset(s->trainee_pages, 0, sizeof s->trainee_pages);
  s->trainee_pages_all = 0;
  int closing = 0;
  for (conn *c = s->conns; c; c = c->next) {
    if (c->withdrawn) continue; /* by an earlier SIGHUP, closing already */
    const int who = c->who >= 0 && c->who <= old->trainee_count ? map[c->who] : -1;
    if (who < 0) {
      c->withdrawn = 1;
      closing++;
      lws_callback_on_writable(c->wsi);
      continue;
    }
    c->who = who;
    if (who > 0) s->trainee_pages[who]++, s->trainee_pages_all++;
  }
  free(old);
  palp_log_info(s->def.log,
                "SIGHUP: tokens re-read: instructors' token %s, trainees' tokens %d (added %d, removed %d, changed %d); "
                "closed %d pages whose token was withdrawn",
                same_instructor ? "unchanged" : "replaced", next->trainee_count, added, removed, changed, closing);
}

void palp_web_serve_run(palp_web_server *s, atomic_int *stop) {
  /* The hub wakes the loop at least every 100 ms, so a stop request is seen that soon. */
  while (!*stop) {
    const int rc = lws_service(s->ctx, 0);
    apply_tokens(s);
    publish_stats(s);
    if (rc < 0) break;
  }
}

int palp_web_serve_tokens_replace(palp_web_server *s, const palp_web_tokens *t) {
  if (!s->have_token || !t || palp_web_token_check(t->token) != 0 || t->trainee_count < 0 ||
      t->trainee_count > PALP_WEB_TRAINEES_MAX)
    return PALP_EINVAL;
  palp_web_tokens *copy = malloc(sizeof *copy);
  if (!copy) return PALP_ENOMEM;
  *copy = *t;
  pthread_mutex_lock(&s->tok_mu);
  palp_web_tokens *older = s->pending; /* not yet in place: the newer read wins */
  s->pending = copy;
  pthread_mutex_unlock(&s->tok_mu);
  free(older);
  palp_web_serve_wake(s);
  return 0;
}

void palp_web_serve_wake(void *server) {
  palp_web_server *s = server;
  if (s && s->ctx) lws_cancel_service(s->ctx);
}

void palp_web_serve_stats_get(palp_web_server *s, palp_web_serve_stats *out) {
  pthread_mutex_lock(&s->stats_mu);
  *out = s->stats_pub;
  pthread_mutex_unlock(&s->stats_mu);
}

void palp_web_serve_destroy(palp_web_server *s) {
  if (!s) return;
  if (s->ctx) lws_context_destroy(s->ctx);
  pthread_mutex_destroy(&s->stats_mu);
  pthread_mutex_destroy(&s->tok_mu);
  free(s->pending);
  free(s->tok);
  free(s);
}
