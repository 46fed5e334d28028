/* stex shared math dialect: the macro block that lets one header compile as OpenCL C (1.2+) and as C++17.
 *
 * Rules for every header under kernels/shared/:
 *  - pure functions of integers and floats; no I/O, no state, no recursion;
 *  - only the types below (32-bit scalars in structs, explicit padding; 64-bit integers only as locals or
 *    split into lo/hi words inside structs) so that host and device agree on layout;
 *  - no contraction of a*b+c into FMA on either side: the pragma below for OpenCL, -ffp-contract=off for the
 *    host (set in the top-level CMakeLists.txt). Kernel and C++ reference then agree bit for bit.
 */
#ifndef STEX_PLATFORM_H
#define STEX_PLATFORM_H

#ifdef __OPENCL_C_VERSION__
#pragma OPENCL FP_CONTRACT OFF
#define STEX_FN static inline
#define STEX_GLOBAL __global
#define STEX_CONSTANT __constant
typedef uint stex_u32;
typedef int stex_i32;
typedef ulong stex_u64;
typedef long stex_i64;
#define STEX_FLOORF(x) floor(x)
#define STEX_SQRTF(x) sqrt(x)
#else
#include <cmath>
#include <cstdint>
#define STEX_FN static inline
#define STEX_GLOBAL
#define STEX_CONSTANT
typedef std::uint32_t stex_u32;
typedef std::int32_t stex_i32;
typedef std::uint64_t stex_u64;
typedef std::int64_t stex_i64;
#define STEX_FLOORF(x) std::floor(x)
#define STEX_SQRTF(x) std::sqrt(x)
#endif

/* Four 32-bit words; a struct (not uint4) so that the same code compiles on both sides. */
typedef struct {
  stex_u32 x, y, z, w;
} stex_uvec4;

/* Floor division for int64 with a positive divisor (C and OpenCL truncate toward zero). */
STEX_FN stex_i64 stex_floordiv(stex_i64 a, stex_i64 b) {
  stex_i64 q = a / b;
  if ((a % b) != 0 && a < 0) q -= 1;
  return q;
}

STEX_FN stex_u32 stex_lo32(stex_i64 v) { return (stex_u32)((stex_u64)v & 0xffffffffu); }
STEX_FN stex_u32 stex_hi32(stex_i64 v) { return (stex_u32)((stex_u64)v >> 32); }
STEX_FN stex_i64 stex_join64(stex_u32 lo, stex_u32 hi) {
  return (stex_i64)(((stex_u64)hi << 32) | (stex_u64)lo);
}

#endif /* STEX_PLATFORM_H */
