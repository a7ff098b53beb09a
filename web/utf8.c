/* utf8.c - the pages' text made valid UTF-8 (utf8.h). */
#include "utf8.h"

#include "palp_utf8.h"

/* The length of the well-formed sequence at s[0..n) (1..4), or 0 if it is not one (RFC 3629,
 * section 4: the second byte's range depends on the first, which rules out overlong forms,
 * surrogates U+D800..DFFF and code points past U+10FFFF). */
size_t palp_web_utf8_clean(unsigned char *s, size_t n) {
  size_t replaced = 0;
  for (size_t i = 0; i < n;) {
    const size_t len = palp_utf8_len(s + i, n - i);
    if (len) {
      i += len;
    } else {
      s[i++] = '?'; /* the byte alone: what follows it is judged on its own */
      replaced++;
    }
  }
  return replaced;
}
