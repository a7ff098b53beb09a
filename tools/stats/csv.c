/*
 * csv.c - RFC 4180 reader (see csv.h). The whole file is read at once (at most
 * PALP_CSV_MAX_BYTES): phantom measurement files are kilobytes to a few megabytes.
 * Every cell's text goes, unquoted and trimmed, into one arena of len + 2 bytes (a
 * cell is never longer than its source span, and its NUL takes the place of the
 * delimiter or line break after it), addressed by 32-bit offsets: about 5 bytes of
 * memory per byte of "1,2" rows, at most ~9 for a row of bare delimiters (one malloc
 * per cell took 40-70 times the file size; session 81 review).
 */
#include "csv.h"

#include <errno.h>
#include <limits.h>
#include <stdint.h>
#include <sys/stat.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "palp.h"

typedef struct offvec {
  uint32_t *p;
  size_t n, cap;
} offvec;

static int ov_push(offvec *v, uint32_t off) {
  if (v->n + 1 > v->cap) {
    size_t cap = v->cap ? 2 * v->cap : 64;
    uint32_t *p = realloc(v->p, cap * sizeof *p);
    if (!p) return PALP_ENOMEM;
    v->p = p;
    v->cap = cap;
  }
  v->p[v->n++] = off;
  return 0;
}

static void msg(char *err, size_t errlen, const char *fmt, ...) {
  if (!err || !errlen) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err, errlen, fmt, ap);
  va_end(ap);
}

/* Appends s[0..n) trimmed of spaces and tabs, and a NUL, at arena + *w; returns the
 * cell's offset. */
static uint32_t put_trimmed(char *arena, size_t *w, const char *s, size_t n) {
  while (n && (*s == ' ' || *s == '\t')) ++s, --n;
  while (n && (s[n - 1] == ' ' || s[n - 1] == '\t')) --n;
  const uint32_t off = (uint32_t)*w;
  memcpy(arena + *w, s, n);
  arena[*w + n] = '\0';
  *w += n + 1;
  return off;
}

void palp_csv_free(palp_csv *csv) {
  if (!csv) return;
  free(csv->header); /* its strings live in the arena */
  free(csv->cells);
  free(csv->line);
  free(csv->arena);
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
  if (len > PALP_CSV_MAX_BYTES) {
    msg(err, errlen, "%s: %zu bytes, more than the %zu MiB palp-stats reads", name, len,
        (size_t)(PALP_CSV_MAX_BYTES >> 20));
    return PALP_EINVAL;
  }
  size_t i = 0;
  if (len >= 3 && (unsigned char)text[0] == 0xEF && (unsigned char)text[1] == 0xBB &&
      (unsigned char)text[2] == 0xBF)
    i = 3; /* UTF-8 byte-order mark written by spreadsheet exports */

  /* Cells: text in arena (never more than len + 1 bytes, see the top of the file),
   * offsets in all; the record being read is all[rec0 ..). */
  char *arena = malloc(len + 2);
  size_t w = 0;
  offvec all = {0};
  size_t *lines = NULL, nlines = 0, cap_lines = 0;
  size_t line = 1;
  int ncols = -1;
  size_t header_line = 0;
  int rc = 0;
  if (!arena) {
    rc = PALP_ENOMEM;
    goto fail;
  }

  while (i < len) {
    /* One record. */
    size_t rec_line = line;
    const size_t rec0 = all.n;
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
        const uint32_t off = (uint32_t)w;
        j++;
        for (;;) {
          if (j >= len) {
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
              arena[w++] = '"';
              j += 2;
              continue;
            }
            j++;
            break;
          }
          if (c == '\n' || (c == '\r' && !(j + 1 < len && text[j + 1] == '\n'))) line++;
          arena[w++] = c;
          j++;
        }
        arena[w++] = '\0';
        while (j < len && (text[j] == ' ' || text[j] == '\t') && text[j] != delim) ++j;
        if (j < len && text[j] != delim && text[j] != '\n' && text[j] != '\r') {
          msg(err, errlen,
              "%s:%zu: field %zu: unexpected text after a closing quote; quote the whole "
              "field, writing a literal quote as \"\"",
              name, line, all.n - rec0 + 1);
          rc = PALP_EPARSE;
          goto fail;
        }
        if ((rc = ov_push(&all, off)) < 0) goto fail;
        i = j;
      } else {
        size_t k = i;
        while (k < len && text[k] != delim && text[k] != '\n' && text[k] != '\r') {
          if (text[k] != ' ' && text[k] != '\t') blank = 0;
          ++k;
        }
        if ((rc = ov_push(&all, put_trimmed(arena, &w, text + i, k - i))) < 0) goto fail;
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

    const size_t nrec = all.n - rec0;
    if (blank && nrec == 1) { /* empty line */
      all.n = rec0;
      continue;
    }
    if (!quoted && ncols >= 0) {
      /* ",,," rows: spreadsheets export them below the data; they hold nothing. */
      size_t k = 0;
      while (k < nrec && arena[all.p[rec0 + k]] == '\0') ++k;
      if (k == nrec) {
        all.n = rec0;
        continue;
      }
    }
    if (ncols < 0) {
      if (nrec > (size_t)INT_MAX) {
        msg(err, errlen, "%s:%zu: the header has more than %d fields", name, rec_line, INT_MAX);
        rc = PALP_EPARSE;
        goto fail;
      }
      ncols = (int)nrec;
      header_line = rec_line;
      out->header = malloc(nrec * sizeof *out->header);
      if (!out->header) {
        rc = PALP_ENOMEM;
        goto fail;
      }
      for (size_t k = 0; k < nrec; ++k) out->header[k] = arena + all.p[rec0 + k];
      out->ncols = ncols;
      all.n = rec0;
      continue;
    }
    if (nrec != (size_t)ncols) {
      msg(err, errlen,
          "%s:%zu: this row has %zu %s-separated fields but the header (line %zu) has %d; "
          "a field containing a %s must be enclosed in double quotes",
          name, rec_line, nrec, delim_name(delim), header_line, ncols, delim_name(delim));
      rc = PALP_EPARSE;
      goto fail;
    }
    if (nlines + 1 > cap_lines) {
      size_t cap = cap_lines ? 2 * cap_lines : 64;
      size_t *p = realloc(lines, cap * sizeof *p);
      if (!p) { rc = PALP_ENOMEM; goto fail; }
      lines = p;
      cap_lines = cap;
    }
    lines[nlines++] = rec_line;
  }
  if (ncols < 0) {
    msg(err, errlen, "%s: the file is empty; expected a header row naming the columns, "
                     "then one row per measurement",
        name);
    free(lines);
    free(all.p);
    free(arena);
    return PALP_EPARSE;
  }
  out->cells = all.p;
  out->arena = arena;
  out->nrows = nlines;
  out->line = lines;
  out->header_line = header_line;
  return 0;

fail:
  free(all.p);
  free(lines);
  free(arena);
  free(out->header);
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
  struct stat st;
  if (fstat(fileno(f), &st) == 0 && S_ISREG(st.st_mode) && (uint64_t)st.st_size > PALP_CSV_MAX_BYTES) {
    fclose(f);
    msg(err, errlen, "%s: %.1f MiB, more than the %zu MiB palp-stats reads (its memory grows ~50-fold with "
                     "short rows); split the file, or drop the columns not analysed",
        path, (double)st.st_size / 1048576.0, (size_t)(PALP_CSV_MAX_BYTES >> 20));
    return PALP_EINVAL;
  }
  char *buf = NULL;
  size_t n = 0, cap = 0;
  errno = 0;
  for (;;) {
    if (n > PALP_CSV_MAX_BYTES) { /* a pipe or a file grown since fstat */
      free(buf);
      fclose(f);
      msg(err, errlen, "%s: more than the %zu MiB palp-stats reads (its memory grows ~50-fold "
                       "with short rows); split the file, or drop the columns not analysed",
          path, (size_t)(PALP_CSV_MAX_BYTES >> 20));
      return PALP_EINVAL;
    }
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
