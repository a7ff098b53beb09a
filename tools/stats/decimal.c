/*
 * decimal.c - exact decimal parsing and subtraction (see decimal.h).
 */
#include "decimal.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int palp_dec_parse(const char *s, palp_dec *out) {
  memset(out, 0, sizeof *out);
  const char *p = s;
  while (*p == ' ' || *p == '\t') ++p;
  const char *start = p;
  if (*p == '+' || *p == '-') out->neg = (*p++ == '-');
  int seen_digit = 0, point = 0;
  long exp = 0;
  for (;; ++p) {
    if (*p >= '0' && *p <= '9') {
      seen_digit = 1;
      if (out->nd == 0 && *p == '0') {
        if (point) exp--; /* leading zero after the point: 0.00x */
        continue;
      }
      if (out->nd < PALP_DEC_MAX_DIGITS) {
        out->d[out->nd++] = *p;
        if (point) exp--;
      } else {
        out->inexact |= (*p != '0');
        if (!point) exp++;
      }
    } else if (*p == '.' && !point) {
      point = 1;
    } else {
      break;
    }
  }
  if (!seen_digit) return -1;
  if (*p == 'e' || *p == 'E') {
    ++p;
    int eneg = 0;
    if (*p == '+' || *p == '-') eneg = (*p++ == '-');
    if (!(*p >= '0' && *p <= '9')) return -1;
    long e = 0;
    for (; *p >= '0' && *p <= '9'; ++p)
      if (e < 100000) e = e * 10 + (*p - '0');
    exp += eneg ? -e : e;
  }
  while (*p == ' ' || *p == '\t') ++p;
  if (*p != '\0') return -1;
  /* Drop trailing zeros of the significand into the exponent. */
  while (out->nd > 0 && out->d[out->nd - 1] == '0') {
    out->nd--;
    exp++;
  }
  if (out->nd == 0) {
    out->neg = 0;
    exp = 0;
  }
  if (exp > 1000000 || exp < -1000000) exp = exp > 0 ? 1000000 : -1000000;
  out->exp = (int)exp;
  out->value = strtod(start, NULL);
  if (!isfinite(out->value)) return -2;
  return 0;
}

/* Magnitude compare of two aligned digit arrays of equal length. */
static int cmp_digits(const char *a, const char *b, int n) {
  for (int i = 0; i < n; ++i)
    if (a[i] != b[i]) return a[i] < b[i] ? -1 : 1;
  return 0;
}

#define WIDTH (3 * PALP_DEC_MAX_DIGITS)

double palp_dec_sub(const palp_dec *x, const palp_dec *o) {
  if (o->nd == 0) return x->value;
  if (x->nd == 0) return -o->value;
  int e = x->exp < o->exp ? x->exp : o->exp;
  /* Integer length of each operand once aligned to exponent e. */
  long lx = (long)x->nd + (x->exp - e), lo = (long)o->nd + (o->exp - e);
  long n = lx > lo ? lx : lo;
  if (n > WIDTH) return x->value - o->value;

  /* Right-aligned digit values 0..9 in arrays of length n. */
  char a[WIDTH], b[WIDTH];
  memset(a, 0, sizeof a);
  memset(b, 0, sizeof b);
  for (int i = 0; i < x->nd; ++i) a[n - lx + i] = (char)(x->d[i] - '0');
  for (int i = 0; i < o->nd; ++i) b[n - lo + i] = (char)(o->d[i] - '0');

  /* x - o with signs: same signs subtract magnitudes, different signs add. */
  char r[WIDTH + 1];
  int neg;
  if (x->neg == o->neg) {
    int c = cmp_digits(a, b, (int)n);
    if (c == 0) return 0.0;
    const char *big = c > 0 ? a : b, *small = c > 0 ? b : a;
    neg = c > 0 ? x->neg : !x->neg;
    int borrow = 0;
    for (long i = n - 1; i >= 0; --i) {
      int v = big[i] - small[i] - borrow;
      borrow = v < 0;
      r[i + 1] = (char)(v + (borrow ? 10 : 0));
    }
    r[0] = 0;
  } else {
    neg = x->neg;
    int carry = 0;
    for (long i = n - 1; i >= 0; --i) {
      int v = a[i] + b[i] + carry;
      carry = v >= 10;
      r[i + 1] = (char)(v - (carry ? 10 : 0));
    }
    r[0] = (char)carry;
  }
  /* Render "[-]digits e<e>" and let strtod round it once, correctly. */
  char buf[WIDTH + 32];
  int k = 0;
  if (neg) buf[k++] = '-';
  long i = 0;
  while (i < n && r[i] == 0) ++i;
  for (; i <= n; ++i) buf[k++] = (char)('0' + r[i]);
  snprintf(buf + k, sizeof buf - (size_t)k, "e%d", e);
  return strtod(buf, NULL);
}
