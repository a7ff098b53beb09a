/*
 * csv.h - a small RFC 4180 reader for palp-stats.
 *
 * Accepts: a header row (required), one record per line (LF, CRLF or CR), fields
 * separated by a single delimiter (',' unless told otherwise), fields optionally
 * enclosed in double quotes with "" for a literal quote and line breaks allowed
 * inside quotes, a UTF-8 byte-order mark, blank lines and rows of empty fields
 * (",,," as spreadsheets export them) skipped. Unquoted fields
 * are trimmed of spaces and tabs. Every record remembers the line it starts on so
 * error messages can point at it.
 */
#ifndef PALP_TOOLS_CSV_H
#define PALP_TOOLS_CSV_H

#include <stddef.h>
#include <stdint.h>

/* The largest file palp-stats reads: 16 MiB. Why: the reader keeps the whole text
 * plus a 4-byte offset per cell and an 8-byte line number per row (about 5 bytes of
 * memory per byte of "1,2" rows, at most ~9 for a row of bare delimiters), but the
 * commands then hold two exact decimals (~90 bytes each) per row: 2.5 million rows of
 * "1,2" (10 MB) peak at 540 MB, so 16 MiB stays under ~1 GB. The paper's largest
 * comparison (118,400 vertex pairs, a few MB as CSV) fits several times over. */
#define PALP_CSV_MAX_BYTES ((size_t)16 << 20)

typedef struct palp_csv {
  int ncols;            /* fields in the header */
  size_t nrows;         /* data records (header excluded) */
  char **header;        /* [ncols], pointing into arena */
  uint32_t *cells;      /* [nrows * ncols], row-major: offsets into arena */
  size_t *line;         /* [nrows] 1-based line each data record starts on */
  size_t header_line;   /* line of the header (after leading blank lines) */
  char *arena;          /* every cell's text, NUL-terminated (header's too) */
} palp_csv;

/* Reads and parses path. On failure returns a negative PALP_E* code and writes a
 * message that names the file and line into err. */
int palp_csv_read(const char *path, char delimiter, palp_csv *out, char *err, size_t errlen);
/* Same, from a NUL-terminated buffer; name is used in messages. */
int palp_csv_parse(const char *text, size_t len, const char *name, char delimiter, palp_csv *out,
                   char *err, size_t errlen);
void palp_csv_free(palp_csv *csv);

static inline const char *palp_csv_cell(const palp_csv *c, size_t row, int col) {
  return c->arena + c->cells[row * (size_t)c->ncols + (size_t)col];
}

#endif
