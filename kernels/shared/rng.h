/* Counter-based integer hash RNG shared by host and device.
 *
 * Choice: pcg4d, the 4x32-bit invertible hash of Jarzynski & Olano, "Hash Functions for GPU Rendering",
 * JCGT 9(3), 2020, which they report passing TestU01 BigCrush as a hash of structured inputs. It uses only
 * 32-bit wrap-around multiplies/adds/xor-shifts (no mul_hi, vectorises on PoCL, identical on every device).
 *
 * Keying (a sponge over the invertible permutation pcg4d):
 *   cell key   K = pcg4d(lo(cx), hi(cx), lo(cy), hi(cy))           (64-bit cell coordinates; injective)
 *   draw       v = pcg4d(pcg4d(K ^ (lo(seed), hi(seed), index, domain)))
 * Two rounds after absorbing the key give full avalanche (every output bit depends on every input bit;
 * tested in tests/kernels). Distinct domains separate the independent uses of one cell (count, impulses,
 * marks, tests). The statistical checks (chi-square uniformity, neighbour-cell and neighbour-index
 * independence) are in tests/kernels/test_rng.cpp.
 *
 * Uniform floats use the top 24 bits: exact multiples of 2^-24 in [0, 1).
 */
#ifndef STEX_RNG_H
#define STEX_RNG_H
#include "stex_platform.h"

#define STEX_DOMAIN_COUNT 0x436f756eu   /* Poisson count of a cell */
#define STEX_DOMAIN_IMPULSE 0x496d7075u /* impulse j of a cell: x, y, mark, spare */
#define STEX_DOMAIN_TEST 0x54657374u    /* free stream for tests and images of the RNG */

STEX_FN stex_uvec4 stex_pcg4d(const stex_uvec4 in) {
  stex_uvec4 v = in; /* a copy: see the note on by-value structs in stex_platform.h */
  v.x = v.x * 1664525u + 1013904223u;
  v.y = v.y * 1664525u + 1013904223u;
  v.z = v.z * 1664525u + 1013904223u;
  v.w = v.w * 1664525u + 1013904223u;
  v.x += v.y * v.w;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v.w += v.y * v.z;
  v.x ^= v.x >> 16;
  v.y ^= v.y >> 16;
  v.z ^= v.z >> 16;
  v.w ^= v.w >> 16;
  v.x += v.y * v.w;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v.w += v.y * v.z;
  return v;
}

/* Key of a 2-D cell with 64-bit signed coordinates. */
STEX_FN stex_uvec4 stex_cell_key(stex_i64 cx, stex_i64 cy) {
  stex_uvec4 v;
  v.x = stex_lo32(cx);
  v.y = stex_hi32(cx);
  v.z = stex_lo32(cy);
  v.w = stex_hi32(cy);
  return stex_pcg4d(v);
}

/* Draw number `index` of stream `domain` of a cell, for a 64-bit seed given as two words. */
STEX_FN stex_uvec4 stex_draw(const stex_uvec4 key, stex_u32 seed_lo, stex_u32 seed_hi, stex_u32 index,
                             stex_u32 domain) {
  stex_uvec4 v = key;
  v.x ^= seed_lo;
  v.y ^= seed_hi;
  v.z ^= index;
  v.w ^= domain;
  v = stex_pcg4d(stex_pcg4d(v));
#if defined(STEX_FAULT_FLIP_RNG_BIT) && defined(__OPENCL_C_VERSION__)
  /* Test builds only (runtime/selftest.h): a deliberately broken device RNG, one bit flipped, so that the
   * known-answer self-test must refuse the device. The host (the C++ reference) never sees this define. */
  v.x ^= 0x40000000u;
#endif
  return v;
}

/* Uniform float in [0, 1) from the top 24 bits of u: exact, identical on every device. */
STEX_FN float stex_uniform24(stex_u32 u) { return (float)(u >> 8) * 5.9604644775390625e-8f; /* 2^-24 */ }

#endif /* STEX_RNG_H */
