/*
 * palp_input_file.h - a file a user or a colleague hands the product (a server configuration, a
 * scene, its parameters, an exercise, an FE configuration, an access list): read whole and bounded,
 * and its JSON read strictly.
 *
 * Why one reader: each reader had its own fopen, and none looked at what it opened. A FIFO named as
 * a scene or an exercise hung palp-server's start (and --check) for ever without a word; a NUL byte
 * ended the text early without a word. And cJSON_Parse stops after the first value and keeps the
 * first of two equal keys: an override appended to a file ("max_force": 5000 after 100) or text after
 * the object were silently ignored (session 81's review).
 */
#ifndef PALP_INPUT_FILE_H
#define PALP_INPUT_FILE_H

#include <stddef.h>

#include <cjson/cJSON.h>

/* Reads the regular file at path whole into *out (NUL-terminated, the caller frees), *len its bytes
 * (len may be NULL). Refused, with why ("cannot open: <errno text>", "not a regular file", "larger
 * than N bytes", "a NUL byte at byte N", "read error: ..."): PALP_EIO when it cannot be opened or
 * read, PALP_EINVAL when it is not a regular file, too large or holds a NUL, PALP_ENOMEM. Opened
 * without blocking, so a FIFO or a device is refused at once. */
int palp_input_file_read(const char *path, size_t max_bytes, char **out, size_t *len, char *why, size_t whylen);

/* Parses text as one JSON value with only white space after it, in which no object has a key twice.
 * NULL with why ("not valid JSON at line L, column C, near \"...\"", "text after the JSON value, near \"...\"",
 * "key \"k\" given twice (in <path>)"). */
cJSON *palp_json_parse_strict(const char *text, char *why, size_t whylen);

#endif
