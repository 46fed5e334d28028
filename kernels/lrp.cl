/* Local random-phase noise (S3 eq. 1, 2, 4), one work-item per output pixel: evaluates stex_lrp_eval
 * (kernels/shared/lrp.h), the same function the C++ reference (runtime/lrp_reference.h) calls, so kernel and
 * reference agree bit for bit. Each pixel is independent of every other: outputs do not depend on the
 * region's tiling, chunking or the work-group size.
 *
 * Output: interleaved float, channel c of pixel (i, j) at out[(j * width + i) * channels + c].
 * Global size: at least (width, height); extra work-items return.
 */
#include "shared/lrp.h"

__kernel void lrp_eval(const stex_lrp_params p_arg, __global const float* fdata, __global const uint* udata,
                       const long x0, const long y0, const int width, const int height, __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_lrp_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  float v[STEX_LRP_MAX_CHANNELS];
  stex_lrp_eval(p, fdata, udata, stex_lrp_pixel_fix(x0 + i), stex_lrp_pixel_fix(y0 + j), v);
  const size_t at = ((size_t)j * (size_t)width + (size_t)i) * (size_t)p.channels;
  for (int c = 0; c < p.channels; ++c) out[at + (size_t)c] = v[c];
  STEX_WATCHDOG_CHECK();
}
