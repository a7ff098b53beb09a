/*
 * csv.c - RFC 4180 reader (see csv.h). The whole file is read at once: phantom
 * measurement files are kilobytes to a few megabytes.
 */
#include "csv.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h"

typedef struct strbuf {
  char *p;
  size_t n, cap;
} strbuf;

static int sb_put(strbuf *b, char c) {
  if (b->n + 2 > b->cap) {
    size_t cap = b->cap ? 2 * b->cap : 32;
    char *p = realloc(b->p, cap);
    if (!p) return PALP_ENOMEM;
    b->p = p;
    b->cap = cap;
  }
  b->p[b->n++] = c;
  b->p[b->n] = '\0';
  return 0;
}

typedef struct ptrvec {
  char **p;
  size_t n, cap;
} ptrvec;

static int pv_push(ptrvec *v, char *s) {
  if (v->n + 1 > v->cap) {
    size_t cap = v->cap ? 2 * v->cap : 16;
    char **p = realloc(v->p, cap * sizeof *p);
    if (!p) return PALP_ENOMEM;
    v->p = p;
    v->cap = cap;
  }
  v->p[v->n++] = s;
  return 0;
}

static void pv_free(ptrvec *v) {
  for (size_t i = 0; i < v->n; ++i) free(v->p[i]);
  free(v->p);
  v->p = NULL;
  v->n = v->cap = 0;
}

static void msg(char *err, size_t errlen, const char *fmt, ...) {
  if (!err || !errlen) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err, errlen, fmt, ap);
  va_end(ap);
}

static char *trimmed_copy(const char *s, size_t n) {
  while (n && (*s == ' ' || *s == '\t')) ++s, --n;
  while (n && (s[n - 1] == ' ' || s[n - 1] == '\t')) --n;
  char *r = malloc(n + 1);
  if (!r) return NULL;
  memcpy(r, s, n);
  r[n] = '\0';
  return r;
}

void palp_csv_free(palp_csv *csv) {
  if (!csv) return;
  if (csv->header)
    for (int i = 0; i < csv->ncols; ++i) free(csv->header[i]);
  if (csv->cells)
    for (size_t i = 0; i < csv->nrows * (size_t)csv->ncols; ++i) free(csv->cells[i]);
  free(csv->header);
  free(csv->cells);
  free(csv->line);
  memset(csv, 0, sizeof *csv);
}

static const char *delim_name(char d) {
  switch (d) {
  case ',': return "comma";
  case ';': return "semicolon";
  case '\t': return "tab";
  default: return "delimiter";
  }
}

int palp_csv_parse(const char *text, size_t len, const char *name, char delim, palp_csv *out,
                   char *err, size_t errlen) {
  memset(out, 0, sizeof *out);
  size_t i = 0;
  if (len >= 3 && (unsigned char)text[0] == 0xEF && (unsigned char)text[1] == 0xBB &&
      (unsigned char)text[2] == 0xBF)
    i = 3; /* UTF-8 byte-order mark written by spreadsheet exports */

  ptrvec all = {0}, rec = {0};
  size_t *lines = NULL, nlines = 0, cap_lines = 0;
  size_t line = 1;
  int ncols = -1;
  size_t header_line = 0;
  int rc = 0;

  while (i < len) {
    /* One record. */
    size_t rec_line = line;
    int blank = 1;  /* nothing but whitespace so far */
    int quoted = 0; /* a quoted field was seen (even "" is content) */
    for (;;) {
      /* One field. */
      size_t j = i;
      while (j < len && (text[j] == ' ' || text[j] == '\t') && text[j] != delim) ++j;
      if (j < len && text[j] == '"') {
        blank = 0;
        quoted = 1;
        size_t quote_line = line;
        strbuf b = {0};
        if ((rc = sb_put(&b, '\0')) < 0) goto fail;
        b.n = 0;
        j++;
        for (;;) {
          if (j >= len) {
            free(b.p);
            msg(err, errlen,
                "%s:%zu: a quoted field opened here is never closed (missing '\"'); "
                "inside quotes a literal quote is written as \"\"",
                name, quote_line);
            rc = PALP_EPARSE;
            goto fail;
          }
          char c = text[j];
          if (c == '"') {
            if (j + 1 < len && text[j + 1] == '"') {
              if ((rc = sb_put(&b, '"')) < 0) { free(b.p); goto fail; }
              j += 2;
              continue;
            }
            j++;
            break;
          }
          if (c == '\n' || (c == '\r' && !(j + 1 < len && text[j + 1] == '\n'))) line++;
          if ((rc = sb_put(&b, c)) < 0) { free(b.p); goto fail; }
          j++;
        }
        while (j < len && (text[j] == ' ' || text[j] == '\t') && text[j] != delim) ++j;
        if (j < len && text[j] != delim && text[j] != '\n' && text[j] != '\r') {
          free(b.p);
          msg(err, errlen,
              "%s:%zu: field %zu: unexpected text after a closing quote; quote the whole "
              "field, writing a literal quote as \"\"",
              name, line, rec.n + 1);
          rc = PALP_EPARSE;
          goto fail;
        }
        if ((rc = pv_push(&rec, b.p)) < 0) { free(b.p); goto fail; }
        i = j;
      } else {
        size_t k = i;
        while (k < len && text[k] != delim && text[k] != '\n' && text[k] != '\r') {
          if (text[k] != ' ' && text[k] != '\t') blank = 0;
          ++k;
        }
        char *f = trimmed_copy(text + i, k - i);
        if (!f) { rc = PALP_ENOMEM; goto fail; }
        if ((rc = pv_push(&rec, f)) < 0) { free(f); goto fail; }
        i = k;
      }
      if (i < len && text[i] == delim) {
        blank = 0;
        i++;
        continue;
      }
      /* End of record: newline or end of text. */
      if (i < len && text[i] == '\r') {
        i++;
        if (i < len && text[i] == '\n') i++;
      } else if (i < len && text[i] == '\n') {
        i++;
      }
      line++;
      break;
    }

    if (blank && rec.n == 1) { /* empty line */
      pv_free(&rec);
      continue;
    }
    if (!quoted && ncols >= 0) {
      /* ",,," rows: spreadsheets export them below the data; they hold nothing. */
      size_t k = 0;
      while (k < rec.n && rec.p[k][0] == '\0') ++k;
      if (k == rec.n) {
        pv_free(&rec);
        continue;
      }
    }
    if (ncols < 0) {
      ncols = (int)rec.n;
      header_line = rec_line;
      out->header = rec.p;
      out->ncols = ncols;
      rec.p = NULL;
      rec.n = rec.cap = 0;
      continue;
    }
    if ((int)rec.n != ncols) {
      msg(err, errlen,
          "%s:%zu: this row has %zu %s-separated fields but the header (line %zu) has %d; "
          "a field containing a %s must be enclosed in double quotes",
          name, rec_line, rec.n, delim_name(delim), header_line, ncols, delim_name(delim));
      rc = PALP_EPARSE;
      goto fail;
    }
    for (size_t k = 0; k < rec.n; ++k) {
      if ((rc = pv_push(&all, rec.p[k])) < 0) goto fail;
      rec.p[k] = NULL;
    }
    rec.n = 0;
    if (nlines + 1 > cap_lines) {
      size_t cap = cap_lines ? 2 * cap_lines : 64;
      size_t *p = realloc(lines, cap * sizeof *p);
      if (!p) { rc = PALP_ENOMEM; goto fail; }
      lines = p;
      cap_lines = cap;
    }
    lines[nlines++] = rec_line;
  }
  pv_free(&rec);
  if (ncols < 0) {
    msg(err, errlen, "%s: the file is empty; expected a header row naming the columns, "
                     "then one row per measurement",
        name);
    free(lines);
    pv_free(&all);
    return PALP_EPARSE;
  }
  out->cells = all.p;
  out->nrows = nlines;
  out->line = lines;
  out->header_line = header_line;
  return 0;

fail:
  pv_free(&rec);
  pv_free(&all);
  free(lines);
  if (out->header) {
    for (int k = 0; k < out->ncols; ++k) free(out->header[k]);
    free(out->header);
  }
  memset(out, 0, sizeof *out);
  if (rc == PALP_ENOMEM) msg(err, errlen, "%s: out of memory while reading", name);
  return rc;
}

int palp_csv_read(const char *path, char delim, palp_csv *out, char *err, size_t errlen) {
  memset(out, 0, sizeof *out);
  FILE *f = fopen(path, "rb");
  if (!f) {
    msg(err, errlen, "%s: cannot open: %s", path, strerror(errno));
    return PALP_EIO;
  }
  char *buf = NULL;
  size_t n = 0, cap = 0;
  errno = 0;
  for (;;) {
    if (n + 65536 + 1 > cap) {
      size_t nc = cap ? 2 * cap : 65536 + 1;
      char *p = realloc(buf, nc);
      if (!p) {
        free(buf);
        fclose(f);
        msg(err, errlen, "%s: out of memory while reading", path);
        return PALP_ENOMEM;
      }
      buf = p;
      cap = nc;
    }
    size_t got = fread(buf + n, 1, 65536, f);
    n += got;
    if (got < 65536) break;
  }
  const int bad = ferror(f), why = errno; /* fread's reason (EISDIR for a directory), before fclose */
  fclose(f);
  if (bad) {
    free(buf);
    msg(err, errlen, "%s: cannot read it: %s", path, strerror(why ? why : EIO));
    return PALP_EIO;
  }
  buf[n] = '\0';
  if (memchr(buf, '\0', n)) {
    free(buf);
    msg(err, errlen, "%s: contains NUL bytes; this is not a text CSV file (a spreadsheet "
                     "saved as .xlsx or .ods? export it as CSV)",
        path);
    return PALP_EPARSE;
  }
  int rc = palp_csv_parse(buf, n, path, delim, out, err, errlen);
  free(buf);
  return rc;
}
