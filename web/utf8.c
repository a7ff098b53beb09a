/* utf8.c - the pages' text made valid UTF-8 (utf8.h). */
#include "utf8.h"

#include "palp_utf8.h"

/* Each byte that begins no well-formed character (palp_utf8_len, src/utf8.c: RFC 3629) becomes '?'. */
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
