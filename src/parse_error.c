/* parse_error.c - the JSON readers' error message (parse_error.h). */
#include "parse_error.h"

#include <stdarg.h>
#include <stdio.h>

int palp_parse_fail(palp_parse_ctx *c, int code, const char *fmt, ...) {
  if (c->err && c->errlen) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->err, c->errlen, fmt, ap);
    va_end(ap);
  }
  return code;
}
