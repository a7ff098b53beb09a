/*
 * decimal.h - exact decimal numbers for palp-stats input.
 *
 * Why: a measurement written as 1000000000000.4 has no binary64 twin; converting
 * it first and subtracting afterwards keeps only 3-4 of its 13+1 digits of spread.
 * ANOVA, Bland-Altman and RMSE are invariant under a common shift of the data, so
 * palp-stats subtracts one data value (the origin) from every cell *in decimal*,
 * exactly, and converts only the small remainder. NIST StRD SmLs07-09 then give
 * their certified results.
 */
#ifndef PALP_TOOLS_DECIMAL_H
#define PALP_TOOLS_DECIMAL_H

#define PALP_DEC_MAX_DIGITS 64

typedef struct palp_dec {
  int neg;    /* sign */
  int exp;    /* value = digits * 10^exp */
  int nd;     /* significant digits held, 0 for zero */
  char d[PALP_DEC_MAX_DIGITS]; /* digits '0'..'9', most significant first, no leading zeros */
  int inexact; /* more than PALP_DEC_MAX_DIGITS digits given: the tail was dropped */
  double value; /* the correctly rounded binary64 value (strtod) */
} palp_dec;

/* Parses a plain decimal number: optional sign, digits with an optional point,
 * optional exponent (1.5, -.25, 3e-4, +7.). Surrounding spaces are allowed.
 * Returns 0, or -1 when the text is not such a number, -2 when it is a number
 * whose magnitude overflows binary64. NaN, inf and hexadecimal are rejected. */
int palp_dec_parse(const char *s, palp_dec *out);

/* x - origin, computed exactly in decimal and rounded once to binary64. Falls
 * back to x.value - origin.value when the aligned operands would exceed the
 * internal width (exponents hundreds of orders apart). */
double palp_dec_sub(const palp_dec *x, const palp_dec *origin);

#endif
