/* Texton noise, tile-splat strategy (S1 §8, evaluated per block of pixels instead of per pixel): the
 * default on CPU devices.
 *
 * Each work-item owns a block of `seg` consecutive pixels of `band` consecutive rows. It walks the cells
 * whose impulses may reach its block in the global order (ky ascending, kx ascending, impulse j ascending;
 * kernels/shared/texton.h) and adds each impulse's taps to the pixels of the block it may cover. Every
 * pixel therefore receives its contributions in the global order, computed by the same functions as
 * stex_texton_eval (stex_texton_tap, stex_texton_fetch, stex_texton_finish): the output equals the gather
 * kernel and the C++ reference bit for bit. Cells, impulses and pixels the loops skip would add an exact
 * +0 in the gather, which changes no bit.
 *
 * Why blocks per work-item (measured on PoCL 3.1): per-work-item loops over impulses keep
 * PoCL's work-item loop outermost, and barriers that would let it vectorise across work-items cost more than
 * they gained here (a work-group-per-tile variant with a barrier per impulse was 3x slower than this one
 * before its optimisations); instead the innermost loop - over the pixels of a row an impulse covers - is a
 * plain counted loop with a straight-line, scalar-per-channel body and `restrict` buffers, which LLVM's loop
 * vectoriser turns into SIMD code. A block shares the hashing of its cells among seg x band pixels.
 *
 * Unit scale (the default) with supports up to 256: every tap of an impulse is its first tap shifted by whole
 * texels (proof at the span below), so the inner loop is contiguous loads with constant weights - no
 * gathers, one stex_texton_tap per impulse - written with explicit float16/float8 vectors (LLVM's loop
 * vectoriser would pick 256-bit vectors on AVX-512 CPUs). Other scales call stex_texton_tap per pixel (the
 * loads are gathers).
 *
 * Orders 3 and 5 (S1 §10) take the per-pixel path with the (order + 1)^2 taps of stex_texton_hi_taps/_channel.
 *
 * Build options: -DSTEX_SPLAT_CHANNELS=<1..4> (the model's channel count).
 * Output: planar float, channel c of pixel (i, j) at out[c * pitch * height + j * pitch + i], i < width.
 * Global size: (ceil(width / seg), ceil(height / band)) (extra work-items return); any local size.
 */
#include "shared/texton.h"

#ifndef STEX_SPLAT_CHANNELS
#error "texton_splat.cl needs -DSTEX_SPLAT_CHANNELS=<channels>"
#endif

/* float16 / float8 at any float alignment: stores through these are single unaligned vector stores. */
typedef struct __attribute__((packed)) {
  float16 v;
} stex_splat_f16;
typedef struct __attribute__((packed)) {
  float8 v;
} stex_splat_f8;

__kernel void texton_splat(const stex_texton_params p_arg, __global const float* restrict alpha,
                           __global const uint* restrict poisson_table, const long x0, const long y0,
                           const int width, const int height, const int pitch, const int seg, const int band,
                           __global float* restrict out, STEX_WATCHDOG_ARGS) {
  const stex_texton_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int c_begin = (int)get_global_id(0) * seg;
  const int r_begin = (int)get_global_id(1) * band;
  if (r_begin >= height || c_begin >= width) return;
  const int c_end = min(c_begin + seg, width) - 1;
  const int r_end = min(r_begin + band, height) - 1;
  const size_t plane = (size_t)pitch * (size_t)height;
  const int stride = p.stride;
  const int aplane = stride * stride;

  for (int c = 0; c < STEX_SPLAT_CHANNELS; ++c)
    for (int r = r_begin; r <= r_end; ++r) {
      __global float* restrict o = out + (size_t)c * plane + (size_t)r * (size_t)pitch;
      for (int i = c_begin; i <= c_end; ++i) o[i] = 0.0f;
    }

  const long unit = (long)1 << STEX_FIX_BITS;
  const long half_unit = unit >> 1;
  const long rb = stex_join64(p.reach_back_lo, p.reach_back_hi);
  const long rf = stex_join64(p.reach_fwd_lo, p.reach_fwd_hi);
  /* Unit scale (inv_fix_scale == 2^-F) and every displacement D inside the support, [t_lo 2^F, t_hi 2^F),
   * below 2^24 in magnitude (supports up to 256): float(D) * 2^-F is exact, so the taps of the pixels an
   * impulse covers differ only by a shift of the texel index (see the span). Displacements outside the
   * support convert to floats outside it too (rounding is monotonic and the bounds are representable), so
   * the exact integer span selects the same pixels as the float test of stex_texton_tap. */
  const long t_lo_fix = (long)(p.t_lo * (float)unit), t_hi_fix = (long)(p.t_hi * (float)unit);
  const int unit_scale = p.order <= 1 && p.inv_fix_scale == 1.0f / (float)unit && t_hi_fix <= (1L << 24) &&
                         -t_lo_fix <= (1L << 24);
  long kx0, kx1, ky0, ky1;
  stex_texton_cell_range(p, stex_pixel_fix(x0 + c_begin), stex_pixel_fix(x0 + c_end), &kx0, &kx1);
  stex_texton_cell_range(p, stex_pixel_fix(y0 + r_begin), stex_pixel_fix(y0 + r_end), &ky0, &ky1);

  for (long ky = ky0; ky <= ky1; ++ky) {
    for (long kx = kx0; kx <= kx1; ++kx) {
      const stex_uvec4 key = stex_cell_key(kx, ky);
      const uint n = stex_texton_count(p, key, poisson_table);
      for (uint j = 0; j < n; ++j) {
        long xj, yj;
        uint mark;
        stex_texton_impulse(p, key, kx, ky, j, &xj, &yj, &mark);
        /* Rows and pixels whose centre (x0 + i) 2^F + 2^(F-1) lies in [xj - rf, xj + rb] (same in y): the
         * reach, a superset of the support (runtime/texton_params.cpp). */
        const int lo = (int)max(-stex_floordiv(half_unit - (xj - rf), unit) - x0, (long)c_begin);
        const int hi = (int)min(stex_floordiv(xj + rb - half_unit, unit) - x0, (long)c_end);
        int rlo = (int)max(-stex_floordiv(half_unit - (yj - rf), unit) - y0, (long)r_begin);
        int rhi = (int)min(stex_floordiv(yj + rb - half_unit, unit) - y0, (long)r_end);
        if (lo > hi || rlo > rhi) continue;
        if (unit_scale) {
          /* Exact unit-scale spans: the pixels and rows whose tap is inside, [t_lo 2^F, t_hi 2^F) in fixed
           * units. Every tap of the impulse is the tap of the first pixel of the first row shifted by one
           * texel per pixel and one texton row per row: float(D) 2^-F is exact, so the fractional parts (and
           * the weights) are the same floats and the integer parts step by one. */
          const int slo = (int)max(-stex_floordiv(half_unit - (xj + t_lo_fix), unit) - x0, (long)c_begin);
          const int shi = (int)min(-stex_floordiv(half_unit - (xj + t_hi_fix), unit) - x0 - 1, (long)c_end);
          rlo = (int)max(-stex_floordiv(half_unit - (yj + t_lo_fix), unit) - y0, (long)r_begin);
          rhi = (int)min(-stex_floordiv(half_unit - (yj + t_hi_fix), unit) - y0 - 1, (long)r_end);
          if (slo > shi || rlo > rhi) continue;
          float w00, w10, w01, w11;
          const int idx0 = stex_texton_tap(p, stex_pixel_fix(x0 + slo) - xj, stex_pixel_fix(y0 + rlo) - yj, &w00,
                                           &w10, &w01, &w11);
          const int span = shi - slo + 1;
          for (int r = rlo; r <= rhi; ++r) {
            const int idx = idx0 + (r - rlo) * stride; /* the tap of pixel slo in row r */
            for (int c = 0; c < STEX_SPLAT_CHANNELS; ++c) {
              __global float* restrict oc = out + (size_t)c * plane + (size_t)r * (size_t)pitch + slo;
              __global const float* restrict ac = alpha + c * aplane + idx;
              /* 16 (then 8) pixels at a time in explicit vector types: LLVM keeps explicit 512-bit types in
               * zmm registers, while its loop vectoriser prefers 256-bit ones on AVX-512 CPUs (measured: PoCL's
               * auto-vectorised loop ran at half the width of a C++ AVX-512 build). Per lane it is the
               * expression of stex_texton_fetch, in its order, unfused (FP_CONTRACT OFF): the same floats. */
              int k = 0;
              for (; k + 16 <= span; k += 16) {
                const float16 t = (float16)(w00) * vload16(0, ac + k) + (float16)(w10) * vload16(0, ac + k + 1) +
                                  (float16)(w01) * vload16(0, ac + k + stride) +
                                  (float16)(w11) * vload16(0, ac + k + stride + 1);
                /* A packed wrapper: one unaligned 512-bit store (PoCL lowers vstore16 to four 128-bit ones). */
                ((__global stex_splat_f16*)(oc + k))->v = vload16(0, oc + k) + t;
              }
              if (k + 8 <= span) {
                const float8 t = (float8)(w00) * vload8(0, ac + k) + (float8)(w10) * vload8(0, ac + k + 1) +
                                 (float8)(w01) * vload8(0, ac + k + stride) +
                                 (float8)(w11) * vload8(0, ac + k + stride + 1);
                ((__global stex_splat_f8*)(oc + k))->v = vload8(0, oc + k) + t;
                k += 8;
              }
              for (; k < span; ++k) oc[k] += stex_texton_fetch(ac, k, stride, w00, w10, w01, w11);
            }
          }
          continue;
        }
        if (p.order > 1) {
          /* Orders 3 and 5 (S1 §10): the (order + 1)^2 taps of the gather's expression per pixel
           * (stex_texton_hi_taps, then stex_texton_hi_channel per channel, a literal channel bound: see
           * docs/portability.md), added to the pixel in the global order. */
          for (int r = rlo; r <= rhi; ++r) {
            const long dy = stex_pixel_fix(y0 + r) - yj;
            __global float* restrict o = out + (size_t)r * (size_t)pitch;
            for (int i = lo; i <= hi; ++i) {
              float wx[6], wy[6];
              int idx0;
              if (!stex_texton_hi_taps(p, stex_pixel_fix(x0 + i) - xj, dy, wx, wy, &idx0)) continue;
              for (int c = 0; c < STEX_SPLAT_CHANNELS; ++c)
                o[(size_t)c * plane + i] += stex_texton_hi_channel(p, alpha + c * aplane, idx0, wx, wy);
            }
          }
          continue;
        }
        for (int r = rlo; r <= rhi; ++r) {
          const long dy = stex_pixel_fix(y0 + r) - yj;
          __global float* restrict o = out + (size_t)r * (size_t)pitch;
          for (int i = lo; i <= hi; ++i) {
            float w00, w10, w01, w11;
            const int idx = stex_texton_tap(p, stex_pixel_fix(x0 + i) - xj, dy, &w00, &w10, &w01, &w11);
            for (int c = 0; c < STEX_SPLAT_CHANNELS; ++c)
              o[(size_t)c * plane + i] += stex_texton_fetch(alpha + c * aplane, idx, stride, w00, w10, w01, w11);
          }
        }
      }
    }
  }

  for (int c = 0; c < STEX_SPLAT_CHANNELS; ++c)
    for (int r = r_begin; r <= r_end; ++r) {
      __global float* restrict o = out + (size_t)c * plane + (size_t)r * (size_t)pitch;
      for (int i = c_begin; i <= c_end; ++i) o[i] = stex_texton_finish(p, c, o[i]);
    }
  STEX_WATCHDOG_CHECK();
}
