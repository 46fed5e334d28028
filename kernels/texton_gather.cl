/* Texton noise, gather strategy (S1 §8): one work-item per output pixel evaluates stex_texton_eval, i.e.
 * walks the cells within reach of its pixel in the global order (ky, kx, j ascending) and sums the taps.
 * The same function is the C++ reference and the point query, so this kernel equals both bit for bit.
 *
 * Chosen by "auto" on devices that are neither CPUs nor GPUs, and the fallback of the local-memory gather
 * (runtime/texton_renderer.h explains why). No local memory: each work-item regenerates the impulses of its
 * ~7 cells (cell side 0.6 r); kernels/texton_gather_local.cl is the GPU variant sharing a work-group tile's
 * impulses in local memory, with the same bits.
 *
 * Output: planar float, channel c of pixel (i, j) at out[c * pitch * height + j * pitch + i], i < width.
 * Global size: at least (width, height); extra work-items return.
 */
#include "shared/texton.h"

__kernel void texton_gather(const stex_texton_params p_arg, __global const float* alpha,
                            __global const uint* poisson_table, const long x0, const long y0, const int width,
                            const int height, const int pitch, __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_texton_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  float v[STEX_MAX_CHANNELS];
  stex_texton_eval(p, alpha, poisson_table, stex_pixel_fix(x0 + i), stex_pixel_fix(y0 + j), v);
  const size_t plane = (size_t)pitch * (size_t)height;
  const size_t at = (size_t)j * (size_t)pitch + (size_t)i;
  for (int c = 0; c < p.channels; ++c) out[(size_t)c * plane + at] = v[c];
  STEX_WATCHDOG_CHECK();
}
