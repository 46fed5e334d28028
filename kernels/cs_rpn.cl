/* Cyclostationary random-phase noise from user spectra (kind "cs-rpn"): one work-item per output pixel
 * evaluates stex_csr_eval (shared/cs_rpn.h), which is also the C++ reference (runtime/cs_rpn.h): this kernel
 * equals it bit for bit.
 *
 * Output: 1 float per pixel, out[j * pitch + i], i < width. Global size: at least (width, height); extra
 * work-items return.
 */
#include "shared/cs_rpn.h"

__kernel void cs_rpn(const stex_csr_params p_arg, __global const float* fdata, __global const uint* udata,
                     __global const uint* reduce, __global const uint* poisson, const long x0, const long y0,
                     const int width, const int height, const int pitch, __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_csr_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  out[(size_t)j * (size_t)pitch + (size_t)i] =
      stex_csr_eval(p, fdata, udata, reduce, poisson, stex_cs_pixel_fix(x0 + i), stex_cs_pixel_fix(y0 + j));
  STEX_WATCHDOG_CHECK();
}
