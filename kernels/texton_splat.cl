/* Texton noise, tile-splat strategy (S1 §8, evaluated per strip of pixels instead of per pixel): the
 * default on CPU devices.
 *
 * Each work-item owns one strip of `seg` consecutive output pixels of one row. It walks the cells whose
 * impulses may reach its strip in the global order (ky ascending, kx ascending, impulse j ascending;
 * kernels/shared/texton.h) and adds each impulse's taps to the pixels of the strip it may cover. Every
 * pixel therefore receives its contributions in the global order, computed by the same functions as
 * stex_texton_eval (stex_texton_tap, stex_texton_fetch, stex_texton_finish): the output equals the gather
 * kernel and the C++ reference bit for bit. Cells, impulses and pixels the loops skip would add an exact
 * +0 in the gather, which changes no bit.
 *
 * Why strips (measured on PoCL 3.1, FIELD-NOTES): per-work-item loops over impulses keep PoCL's work-item
 * loop outermost, and barriers that would let it vectorise across work-items cost more than they gain
 * here; instead the innermost loop - over the pixels of the strip an impulse covers - is a plain counted
 * loop with straight-line, scalar-per-channel body and `restrict` buffers, which LLVM's loop vectoriser
 * turns into SIMD code. A strip shares the hashing of its ~12 cells among `seg` pixels.
 *
 * Build options: -DSTEX_SPLAT_CHANNELS=<1..4> (the model's channel count).
 * Output: planar float, channel c of pixel (i, j) at out[c * pitch * height + j * pitch + i], i < width.
 * Global size: (ceil(width / seg), height) (extra work-items return); any local size.
 */
#include "shared/texton.h"

#ifndef STEX_SPLAT_CHANNELS
#error "texton_splat.cl needs -DSTEX_SPLAT_CHANNELS=<channels>"
#endif

__kernel void texton_splat(const stex_texton_params p, __global const float* restrict alpha,
                           __global const uint* restrict poisson_table, const long x0, const long y0,
                           const int width, const int height, const int pitch, const int seg,
                           __global float* restrict out) {
  const int row = (int)get_global_id(1);
  const int c_begin = (int)get_global_id(0) * seg;
  if (row >= height || c_begin >= width) return;
  const int c_end = min(c_begin + seg, width) - 1;
  const size_t plane = (size_t)pitch * (size_t)height;
  const int stride = p.stride;
  const int aplane = stride * stride;
  __global float* restrict o = out + (size_t)row * (size_t)pitch;

  for (int c = 0; c < STEX_SPLAT_CHANNELS; ++c)
    for (int i = c_begin; i <= c_end; ++i) o[(size_t)c * plane + i] = 0.0f;

  const long unit = (long)1 << STEX_FIX_BITS;
  const long half_unit = unit >> 1;
  const long fy = stex_pixel_fix(y0 + row);
  const long rb = stex_join64(p.reach_back_lo, p.reach_back_hi);
  const long rf = stex_join64(p.reach_fwd_lo, p.reach_fwd_hi);
  /* Unit scale (inv_fix_scale == 2^-F) with |t| < 2^(24-F): float(D) * 2^-F is exact, so the taps of the
   * pixels of a row that an impulse covers differ only by a shift of the texel index (see the span). */
  const int unit_scale = p.inv_fix_scale == 1.0f / (float)unit && p.support + 1 < (1 << (24 - STEX_FIX_BITS));
  const long t_lo_fix = (long)(p.t_lo * (float)unit), t_hi_fix = (long)(p.t_hi * (float)unit);
  long kx0, kx1, ky0, ky1;
  stex_texton_cell_range(p, stex_pixel_fix(x0 + c_begin), stex_pixel_fix(x0 + c_end), &kx0, &kx1);
  stex_texton_cell_range(p, fy, fy, &ky0, &ky1);

  for (long ky = ky0; ky <= ky1; ++ky) {
    for (long kx = kx0; kx <= kx1; ++kx) {
      const stex_uvec4 key = stex_cell_key(kx, ky);
      const uint n = stex_texton_count(p, key, poisson_table);
      for (uint j = 0; j < n; ++j) {
        long xj, yj;
        uint mark;
        stex_texton_impulse(p, key, kx, ky, j, &xj, &yj, &mark);
        const long dy = fy - yj;
        if (dy < -rf || dy > rb) continue;
        /* Pixels whose centre X = (x0 + i) 2^F + 2^(F-1) lies in [xj - rf, xj + rb]. */
        const long i0 = -stex_floordiv(half_unit - (xj - rf), unit) - x0;
        const long i1 = stex_floordiv(xj + rb - half_unit, unit) - x0;
        const int lo = (int)max(i0, (long)c_begin);
        const int hi = (int)min(i1, (long)c_end);
        if (unit_scale) {
          /* Exact unit-scale span: the pixels whose tap is inside in x, [t_lo 2^F, t_hi 2^F) in fixed
           * units; all share the tap of the first one shifted by one texel per pixel. */
          const long s0 = -stex_floordiv(half_unit - (xj + t_lo_fix), unit) - x0;
          const long s1 = -stex_floordiv(half_unit - (xj + t_hi_fix), unit) - x0 - 1;
          const int slo = (int)max(s0, (long)c_begin);
          const int shi = (int)min(s1, (long)c_end);
          if (slo > shi || dy < t_lo_fix || dy >= t_hi_fix) continue;
          float w00, w10, w01, w11;
          const int idx0 = stex_texton_tap(p, stex_pixel_fix(x0 + slo) - xj, dy, &w00, &w10, &w01, &w11) - slo;
          for (int c = 0; c < STEX_SPLAT_CHANNELS; ++c) {
            __global float* restrict oc = o + (size_t)c * plane;
            __global const float* restrict ac = alpha + c * aplane;
            for (int i = slo; i <= shi; ++i) oc[i] += stex_texton_fetch(ac, idx0 + i, stride, w00, w10, w01, w11);
          }
          continue;
        }
        for (int i = lo; i <= hi; ++i) {
          float w00, w10, w01, w11;
          const int idx = stex_texton_tap(p, stex_pixel_fix(x0 + i) - xj, dy, &w00, &w10, &w01, &w11);
          for (int c = 0; c < STEX_SPLAT_CHANNELS; ++c)
            o[(size_t)c * plane + i] += stex_texton_fetch(alpha + c * aplane, idx, stride, w00, w10, w01, w11);
        }
      }
    }
  }

  for (int c = 0; c < STEX_SPLAT_CHANNELS; ++c)
    for (int i = c_begin; i <= c_end; ++i) o[(size_t)c * plane + i] = stex_texton_finish(p, c, o[(size_t)c * plane + i]);
}
