/* palp_utf8.h - the one rule for well-formed UTF-8 (RFC 3629) that every tool applies to text from
 * the network or a file before a terminal, a JSON export, an SVG or a WebSocket frame gets it. */
#ifndef PALP_UTF8_H
#define PALP_UTF8_H
#include <stddef.h>

/* The length (1-4) of the well-formed UTF-8 character that begins at s, of the n bytes there; 0 if
 * none does: a continuation byte, an overlong form (C0, C1, E0 80..9F, F0 80..8F), a surrogate
 * (ED A0..BF), a code point past U+10FFFF (F4 90.., F5..FF), or a sequence cut short by n. A NUL
 * is a character of length 1 (a C string's end is the caller's). */
size_t palp_utf8_len(const unsigned char *s, size_t n);
/* The same for XML 1.0 text (an SVG): 0 also for U+FFFE and U+FFFF (EF BF BE, EF BF BF), well-formed
 * UTF-8 that XML's Char production excludes. Control characters are the caller's rule. */
size_t palp_utf8_xml_len(const unsigned char *s, size_t n);

#endif
