/* utf8.c - the pages' text made valid UTF-8 (utf8.h). */
#include "utf8.h"

/* The length of the well-formed sequence at s[0..n) (1..4), or 0 if it is not one (RFC 3629,
 * section 4: the second byte's range depends on the first, which rules out overlong forms,
 * surrogates U+D800..DFFF and code points past U+10FFFF). */
static size_t sequence_at(const unsigned char *s, size_t n) {
  const unsigned char b = s[0];
  if (b < 0x80) return 1;
  size_t len;
  unsigned char lo = 0x80, hi = 0xBF; /* the second byte's range */
  if (b >= 0xC2 && b <= 0xDF) len = 2;
  else if (b == 0xE0) len = 3, lo = 0xA0;
  else if (b == 0xED) len = 3, hi = 0x9F;
  else if (b >= 0xE1 && b <= 0xEF) len = 3;
  else if (b == 0xF0) len = 4, lo = 0x90;
  else if (b == 0xF4) len = 4, hi = 0x8F;
  else if (b >= 0xF1 && b <= 0xF3) len = 4;
  else return 0; /* 0x80..0xC1 (a continuation or an overlong lead), 0xF5..0xFF */
  if (n < len || s[1] < lo || s[1] > hi) return 0;
  for (size_t k = 2; k < len; k++)
    if (s[k] < 0x80 || s[k] > 0xBF) return 0;
  return len;
}

size_t palp_web_utf8_clean(unsigned char *s, size_t n) {
  size_t replaced = 0;
  for (size_t i = 0; i < n;) {
    const size_t len = sequence_at(s + i, n - i);
    if (len) {
      i += len;
    } else {
      s[i++] = '?'; /* the byte alone: what follows it is judged on its own */
      replaced++;
    }
  }
  return replaced;
}
