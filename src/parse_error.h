/*
 * parse_error.h - where the JSON readers (scene.c, exercise.c) put the message
 * that names the offending field (internal).
 */
#ifndef PALP_PARSE_ERROR_H
#define PALP_PARSE_ERROR_H

#include <stddef.h>

typedef struct palp_parse_ctx {
  char *err; /* caller's buffer, may be NULL */
  size_t errlen;
} palp_parse_ctx;

/* Formats the message into c->err (if any) and returns code. */
int palp_parse_fail(palp_parse_ctx *c, int code, const char *fmt, ...);

#endif
