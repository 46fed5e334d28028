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
 * Cells: a launch adds the impulses of cells [cell_first, cell_end) of each pixel's cells and `pass`
 * (STEX_FILTER_PASS_*) says whether it continues the sums left in `out` and whether it finishes them; the host
 * splits the cells over several launches only where the driver caps the loop iterations of an invocation
 * (runtime/texton_filter.cpp). Bits do not depend on the split.
 * Global size: at least (width, height); extra work-items return.
 */
#include "shared/texton_filter.h"

/* One pixel's share of a launch: its cells [cell_first, cell_end), continuing and/or finishing as `pass`
 * says; px[c * plane] is the pixel's channel c in the output. */
void texton_filtered_pass(const stex_texton_params p, const stex_mip_params m, __global const float* pyr,
                          __global const uint* poisson_table, const stex_footprint f, const long x, const long y,
                          const long cell_first, const long cell_end, const int pass, __global float* px,
                          const size_t plane) {
  float acc[STEX_MAX_CHANNELS] = {0.0f, 0.0f, 0.0f, 0.0f};
  if (pass & STEX_FILTER_PASS_LOAD) {
    for (int c = 0; c < STEX_MAX_CHANNELS; ++c) { /* literal bounds: no capped loop iterations spent */
      if (c >= p.channels) break;
      acc[c] = px[(size_t)c * plane];
    }
  }
  stex_texton_filtered_window(p, m, pyr, poisson_table, f, x, y, cell_first, cell_end, acc);
  float v[STEX_MAX_CHANNELS];
  if (pass & STEX_FILTER_PASS_FINISH) {
    stex_texton_filtered_finish(p, f, acc, v);
  } else {
    for (int c = 0; c < STEX_MAX_CHANNELS; ++c) v[c] = acc[c];
  }
  for (int c = 0; c < STEX_MAX_CHANNELS; ++c) {
    if (c >= p.channels) break;
    px[(size_t)c * plane] = v[c];
  }
}

__kernel void texton_filtered_scaled(const stex_texton_params p_arg, const stex_mip_params m_arg, const stex_footprint f_arg,
                                     __global const float* pyr, __global const uint* poisson_table, const long x0,
                                     const long y0, const int width, const int height, const int pitch,
                                     __global float* out, const long cell_first, const long cell_end,
                                     const int pass, STEX_WATCHDOG_ARGS) {
  const stex_texton_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const stex_mip_params m = m_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const stex_footprint f = f_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  const size_t plane = (size_t)pitch * (size_t)height;
  const size_t at = (size_t)j * (size_t)pitch + (size_t)i;
  texton_filtered_pass(p, m, pyr, poisson_table, f, stex_pixel_fix(x0 + i), stex_pixel_fix(y0 + j), cell_first,
                       cell_end, pass, out + at, plane);
  STEX_WATCHDOG_CHECK();
}

__kernel void texton_filtered_mapped(const stex_texton_params p_arg, const stex_mip_params m_arg, __global const float* pyr,
                                     __global const uint* poisson_table, __global const long* pos,
                                     __global const stex_footprint* fp, const int width, const int height,
                                     const int pitch, __global float* out, const long cell_first,
                                     const long cell_end, const int pass, STEX_WATCHDOG_ARGS) {
  const stex_texton_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const stex_mip_params m = m_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  const size_t k = (size_t)j * (size_t)width + (size_t)i;
  const stex_footprint f = fp[k];
  const size_t plane = (size_t)pitch * (size_t)height;
  const size_t at = (size_t)j * (size_t)pitch + (size_t)i;
  if (f.probes > 0) {
    texton_filtered_pass(p, m, pyr, poisson_table, f, pos[2 * k], pos[2 * k + 1], cell_first, cell_end, pass,
                         out + at, plane);
  } else if (pass & STEX_FILTER_PASS_FINISH) {
    for (int c = 0; c < p.channels; ++c) out[(size_t)c * plane + at] = p.mean[c];
  }
  STEX_WATCHDOG_CHECK();
}
