/* Tiling and blending (kinds tb, cs-tb): one work-item per output pixel evaluates stex_tb_eval (shared/tb.h),
 * which is also the C++ reference (runtime/tb.h): this kernel equals it bit for bit.
 * Output: `channels` interleaved floats per pixel, out[(j * pitch + i) * channels + c].
 */
#include "shared/tb.h"

__kernel void tb(const stex_tb_params p, __global const float* g, __global const float* lut, __global const float* pca,
                 __global const float* mean, const stex_cs_hist_params h, __global const float* hist, const long kg0, const long lg0, const long kc0, const long lc0,
                 const long x0, const long y0, const int width, const int height, const int pitch,
                 __global float* out) {
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  float v[STEX_TB_MAX_CHANNELS];
  /* (kg0, lg0), (kc0, lc0): the base nodes of the chunk's first pixel, computed on the host. */
  stex_tb_eval(p, g, lut, pca, mean, h, hist, stex_cs_pixel_fix(x0 + i), stex_cs_pixel_fix(y0 + j), kg0, lg0, kc0, lc0, v);
  const size_t o = ((size_t)j * (size_t)pitch + (size_t)i) * (size_t)p.channels;
  for (int c = 0; c < p.channels; ++c) out[o + (size_t)c] = v[c];
}
