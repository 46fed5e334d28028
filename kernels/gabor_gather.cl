/* Gabor noise, gather strategy: one work-item per output pixel evaluates stex_gabor_eval (shared/gabor.h),
 * i.e. walks the cells within reach of its pixel in the global order (ky, kx, j ascending). The same
 * function is the C++ reference (runtime/gabor_params.h), so this kernel equals it bit for bit.
 *
 * Output: one channel, out[j * pitch + i] for pixel (i, j), i < width. Global size: at least (width, height);
 * extra work-items return.
 */
#include "shared/gabor.h"

__kernel void gabor_gather(const stex_gabor_params p_arg, __global const float* comp, __global const uint* comp_table,
                           __global const uint* poisson_table, const long x0, const long y0, const int width,
                           const int height, const int pitch, __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_gabor_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  out[(size_t)j * (size_t)pitch + (size_t)i] = stex_gabor_eval(
      p, comp, comp_table, poisson_table, stex_gabor_pixel_fix(x0 + i), stex_gabor_pixel_fix(y0 + j));
  STEX_WATCHDOG_CHECK();
}
