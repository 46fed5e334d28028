/* Texton noise with on-the-fly filtering (S1 §5), gather: one work-item per output pixel evaluates
 * stex_texton_eval_filtered (kernels/shared/texton_filter.h) - the C++ reference calls the same function, so
 * the two are equal bit for bit.
 *
 * Two ways to give a pixel its position and footprint:
 *  - texton_filtered_scaled: the flat plane at `scale` (RenderParams::scale): pixel P at stex_pixel_fix(P)
 *    (output-pixel fixed units) and one footprint for every pixel;
 *  - texton_filtered_mapped: per-pixel positions (int64 fixed units of the plane at scale 1, i.e. 2^16 per
 *    texton texel; x at pos[2 i], y at pos[2 i + 1]) and footprints, e.g. a perspective plane
 *    (runtime/texton_filter.h). Pixels without a plane point (above the horizon) have probes = 0 and get the
 *    model mean.
 * Output: planar float, channel c of pixel (i, j) at out[c * pitch * height + j * pitch + i].
 * Global size: at least (width, height); extra work-items return.
 */
#include "shared/texton_filter.h"

__kernel void texton_filtered_scaled(const stex_texton_params p_arg, const stex_mip_params m_arg, const stex_footprint f_arg,
                                     __global const float* pyr, __global const uint* poisson_table, const long x0,
                                     const long y0, const int width, const int height, const int pitch,
                                     __global float* out) {
  const stex_texton_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const stex_mip_params m = m_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const stex_footprint f = f_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  float v[STEX_MAX_CHANNELS];
  stex_texton_eval_filtered(p, m, pyr, poisson_table, f, stex_pixel_fix(x0 + i), stex_pixel_fix(y0 + j), v);
  const size_t plane = (size_t)pitch * (size_t)height;
  const size_t at = (size_t)j * (size_t)pitch + (size_t)i;
  for (int c = 0; c < p.channels; ++c) out[(size_t)c * plane + at] = v[c];
}

__kernel void texton_filtered_mapped(const stex_texton_params p_arg, const stex_mip_params m_arg, __global const float* pyr,
                                     __global const uint* poisson_table, __global const long* pos,
                                     __global const stex_footprint* fp, const int width, const int height,
                                     const int pitch, __global float* out) {
  const stex_texton_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const stex_mip_params m = m_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  const size_t k = (size_t)j * (size_t)width + (size_t)i;
  const stex_footprint f = fp[k];
  float v[STEX_MAX_CHANNELS];
  if (f.probes > 0) {
    stex_texton_eval_filtered(p, m, pyr, poisson_table, f, pos[2 * k], pos[2 * k + 1], v);
  } else {
    for (int c = 0; c < STEX_MAX_CHANNELS; ++c) v[c] = p.mean[c];
  }
  const size_t plane = (size_t)pitch * (size_t)height;
  const size_t at = (size_t)j * (size_t)pitch + (size_t)i;
  for (int c = 0; c < p.channels; ++c) out[(size_t)c * plane + at] = v[c];
}
