/*
 * palp_rng.h - one small random stream for every tool that must draw the same numbers on every
 * machine from a seed: SplitMix64 (Steele, Lea & Flood 2014), a 64-bit counter through a mixing
 * finaliser. Pure and header-only: the state is the caller's, no globals. Used for the lesions an
 * exercise draws for each session (src/placement.c), the server's per-session seeds
 * (server/server.c) and the evaluation's random sites (tools/eval/eval_sites.c).
 */
#ifndef PALP_RNG_H
#define PALP_RNG_H

#include <stdint.h>

/* SplitMix64's finaliser: each bit of z reaches every bit of the result (also the world's state
 * hash's word mix, src/world.c). */
static inline uint64_t palp_rng_mix(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/* The next 64 random bits; advances *state by the golden-ratio increment. */
static inline uint64_t palp_rng_next(uint64_t *state) { return palp_rng_mix(*state += 0x9e3779b97f4a7c15ULL); }

/* Uniform on [0, 1) with 53 random bits (every double of the form k 2^-53). */
static inline double palp_rng_uniform(uint64_t *state) { return (double)(palp_rng_next(state) >> 11) * 0x1.0p-53; }

#endif
