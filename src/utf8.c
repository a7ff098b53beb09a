/* The one UTF-8 rule (palp_utf8.h). Until session 82 palp-review, the visual station's SVG,
 * palp-eval's SVG and palp-web each had a copy of it. */
#include "palp_utf8.h"

size_t palp_utf8_len(const unsigned char *s, size_t n) {
  if (n == 0) return 0;
  const unsigned char b = s[0];
  if (b < 0x80) return 1;
  size_t len;
  unsigned char lo = 0x80, hi = 0xBF; /* the second byte's range */
  if (b >= 0xC2 && b <= 0xDF) len = 2;
  else if (b == 0xE0) len = 3, lo = 0xA0; /* no overlong 3-byte form */
  else if (b == 0xED) len = 3, hi = 0x9F; /* no surrogate */
  else if (b >= 0xE1 && b <= 0xEF) len = 3;
  else if (b == 0xF0) len = 4, lo = 0x90; /* no overlong 4-byte form */
  else if (b == 0xF4) len = 4, hi = 0x8F; /* nothing past U+10FFFF */
  else if (b >= 0xF1 && b <= 0xF3) len = 4;
  else return 0; /* 0x80..0xC1 (a continuation or an overlong lead), 0xF5..0xFF */
  if (n < len || s[1] < lo || s[1] > hi) return 0;
  for (size_t k = 2; k < len; k++)
    if (s[k] < 0x80 || s[k] > 0xBF) return 0;
  return len;
}

size_t palp_utf8_xml_len(const unsigned char *s, size_t n) {
  const size_t len = palp_utf8_len(s, n);
  /* U+FFFE, U+FFFF: not XML characters (a parser refuses the document) */
  if (len == 3 && s[0] == 0xEF && s[1] == 0xBF && s[2] >= 0xBE) return 0;
  return len;
}
