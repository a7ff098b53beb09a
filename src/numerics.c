/*
 * numerics.c - a fingerprint of the math library as the model calls it (palp.h,
 * palp_numerics_fingerprint).
 *
 * Why: a replay is bit-identical only where exp, expm1, pow, atan2, sin, cos and acos give the
 * same bits as where the session ran. glibc picks their code at run time by the CPU's features
 * (FMA and AVX2 variants beside the baseline's), and the variants differ in the last bit: the
 * demo's sessions, replayed by the same binary with those variants turned off
 * (GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA), mismatched from frame 1 (session 81's review).
 * The session log keeps the fingerprint of the machine that ran it; a replay that mismatches on a
 * machine with another one says so, rather than calling the log damaged.
 */
#include <math.h>
#include <string.h>

#include "palp.h"

/* A fixed stream of arguments (a 64-bit LCG's top 53 bits), the same on every machine. */
static double arg_in(uint64_t *s, double lo, double hi) {
  *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
  return lo + (hi - lo) * (double)(*s >> 11) * 0x1p-53;
}

/* 1,024 values of each function, over the ranges the model calls it in: exp and expm1 of the
 * Burgers law's -h/tau (and the support's), pow of the polytropic gel's (V0/V)^a1 (a1 up to its
 * bound of 300), atan2 and acos of the hinges' angles, sin and cos of the mesh's and the fingers'.
 * Measured on this project's machines: every function's 1,024 values differ in some bit between
 * glibc's FMA and baseline paths, so one path's fingerprint never equals the other's. */
uint64_t palp_numerics_fingerprint(void) {
  uint64_t h = 1469598103934665603ULL, s = 1;
  for (int f = 0; f < 7; ++f)
    for (int k = 0; k < 1024; ++k) {
      double v;
      switch (f) {
      case 0: v = exp(arg_in(&s, -40.0, 5.0)); break;
      case 1: v = expm1(arg_in(&s, -5.0, 1.0)); break;
      case 2: {
        const double b = arg_in(&s, 0.5, 2.0), e = arg_in(&s, 0.5, 300.0);
        v = pow(b, e);
      } break;
      case 3: {
        const double y = arg_in(&s, -1.0, 1.0), x = arg_in(&s, -1.0, 1.0);
        v = atan2(y, x);
      } break;
      case 4: v = sin(arg_in(&s, -7.0, 7.0)); break;
      case 5: v = cos(arg_in(&s, -7.0, 7.0)); break;
      default: v = acos(arg_in(&s, -1.0, 1.0)); break;
      }
      uint64_t bits;
      memcpy(&bits, &v, sizeof bits);
      h = (h ^ bits) * 1099511628211ULL; /* FNV-1a over the results' bits */
    }
  return h;
}
