/* utf8.h - text for the pages is valid UTF-8 (RFC 3629), whatever came in.
 *
 * A WebSocket text frame must be valid UTF-8 (RFC 6455, 8.1), and a browser closes the connection on
 * one that is not. Strings from DDS and from files (an exercise saved as Latin-1, a station's name)
 * were sent as they came: cJSON escapes quotes and control characters, not bytes that are no UTF-8.
 * One such byte in the exercises message, which every page is sent after hello, closed every page,
 * the dashboard too, on every reconnect (session 80's review, 2026-12-07). */
#ifndef PALP_WEB_UTF8_H
#define PALP_WEB_UTF8_H
#include <stddef.h>

/* Replaces every byte of s[0..n) that does not begin or continue a well-formed UTF-8 sequence (an
 * overlong form, a surrogate, a code point past U+10FFFF, a stray or missing continuation byte) with
 * '?', in place; the length stays. Returns the number of bytes replaced. JSON's structural characters
 * are ASCII, so a JSON text stays JSON. */
size_t palp_web_utf8_clean(unsigned char *s, size_t n);

#endif
