/* Noise mixing (S1 §7), gather strategy: one work-item per output pixel evaluates stex_mix_eval
 * (shared/mix.h), i.e. walks the cells within reach of its pixel in the global order (ky, kx, j ascending),
 * picks each impulse's texton from the mixing map at the impulse and adds it with its sign. The same
 * function is the C++ reference (runtime/mix_model.h), so this kernel equals it bit for bit.
 *
 * Output: interleaved float, channel c of pixel (i, j) at out[(j * pitch + i) * channels + c], i < width.
 * Global size: at least (width, height); extra work-items return.
 */
#include "shared/mix.h"

__kernel void mix_gather(const stex_texton_params p_arg, const stex_mix_params m_arg, __global const float* alpha,
                         __global const float* map, __global const uint* poisson_table, const long x0,
                         const long y0, const int width, const int height, const int pitch, __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_texton_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const stex_mix_params m = m_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  float v[STEX_MAX_CHANNELS];
  stex_mix_eval(p, m, alpha, map, poisson_table, stex_pixel_fix(x0 + i), stex_pixel_fix(y0 + j), v);
  const size_t at = ((size_t)j * (size_t)pitch + (size_t)i) * (size_t)p.channels;
  for (int c = 0; c < p.channels; ++c) out[at + (size_t)c] = v[c];
  STEX_WATCHDOG_CHECK();
}
