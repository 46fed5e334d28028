/* Cyclostationary spot noise: one work-item per output pixel evaluates stex_cs_spot_eval (shared/cs.h), which
 * is also the C++ reference (runtime/cs_spot.h): this kernel equals it bit for bit.
 *
 * Output: `channels` interleaved floats per pixel, out[(j * pitch + i) * channels + c], i < width. Global
 * size: at least (width, height); extra work-items return.
 */
#include "shared/cs.h"

__kernel void cs_spot(const stex_cs_params p, __global const float* spot, __global const float* mean,
                      __global const float* gauss, __global const uint* reduce, const stex_cs_hist_params h,
                      __global const float* hist, const long x0, const long y0,
                      const int width, const int height, const int pitch, __global float* out) {
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  float v[STEX_CS_MAX_CHANNELS];
  stex_cs_spot_eval(p, spot, mean, gauss, reduce, h, hist, stex_cs_pixel_fix(x0 + i), stex_cs_pixel_fix(y0 + j), v);
  const size_t o = ((size_t)j * (size_t)pitch + (size_t)i) * (size_t)p.channels;
  for (int c = 0; c < p.channels; ++c) out[o + (size_t)c] = v[c];
}
