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

#ifdef __OPENCL_C_VERSION__
/* The loop watchdog canary (docs/portability.md, "loop watchdog"). Mesa's llvmpipe (rusticl, lavapipe) caps
 * the loop iterations of one shader invocation - a SIMD batch of work-items - at 65535, shared by every loop
 * of the kernel; past the cap each loop exits after one pass and the kernel silently computes something
 * else. Every kernel with data-dependent loops takes (STEX_WATCHDOG_ARGS) last and ends with
 * STEX_WATCHDOG_CHECK(): a loop of `watchdog_n` passes (the host passes 2; a run-time bound, so no compiler
 * unrolls it, and a multiplicative recurrence, so none replaces it by its closed form). Once the cap is
 * spent that loop runs once, the recurrence misses its two-pass value and the work-item sets *watchdog; the
 * host (runtime/loop_watchdog.h) then retries with less work per invocation or refuses. On devices without
 * such a cap the loop costs two multiply-adds per work-item. */
#define STEX_WATCHDOG_ARGS const int watchdog_n, __global uint* watchdog
STEX_FN void stex_watchdog_check(const int n, __global uint* flag) {
  uint h = 1u;
  for (int i = 0; i < n; ++i) h = h * 1664525u + 1013904223u;
  if (h != (1664525u + 1013904223u) * 1664525u + 1013904223u) flag[0] = 1u;
}
#define STEX_WATCHDOG_CHECK() stex_watchdog_check(watchdog_n, watchdog)
#endif

#endif /* STEX_PLATFORM_H */
