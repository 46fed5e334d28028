// OpenCL C entry points of the C API, appended at build time to the resolved kernels/shared/texton.h
// (capi/context.cpp ensure_kernels). Like the gather kernel (kernels/texton_gather.cl) each is a thin loop
// over stex_texton_eval, so their values equal the splat/gather renders and the C++ reference bit for bit.
//  - stex_capi_points: point queries at fixed-point positions (stex_eval_points).
//  - stex_capi_region: a region written interleaved, with an offset and a row stride, into a caller's
//    cl_mem (stex_render_cl with the gather strategy): no planar staging buffer, no host round trip.
#include "capi/api_internal.h"

namespace stex::capi {

const char* device_kernel_source() {
  return R"stex_capi(
#line 1 "capi/device_kernels.cpp"
/* xy: 2n fixed-point coordinates (x0, y0, x1, y1, ...); out: n * channels floats, interleaved. */
__kernel void stex_capi_points(const stex_texton_params p_arg, __global const float* alpha,
                               __global const uint* poisson_table, __global const long* xy, const uint n,
                               __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_texton_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const size_t k = get_global_id(0);
  if (k >= n) return;
  float v[STEX_MAX_CHANNELS];
  stex_texton_eval(p, alpha, poisson_table, xy[2 * k], xy[2 * k + 1], v);
  for (int c = 0; c < p.channels; ++c) out[k * (size_t)p.channels + (size_t)c] = v[c];
  STEX_WATCHDOG_CHECK();
}

/* Pixel (i, j) of the region at (x0, y0), channel c -> dst[offset + j * row_stride + i * channels + c]
 * (offset and row_stride in floats). */
__kernel void stex_capi_region(const stex_texton_params p_arg, __global const float* alpha,
                               __global const uint* poisson_table, const long x0, const long y0, const int width,
                               const int height, __global float* dst, const ulong offset, const ulong row_stride,
                               STEX_WATCHDOG_ARGS) {
  const stex_texton_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  float v[STEX_MAX_CHANNELS];
  stex_texton_eval(p, alpha, poisson_table, stex_pixel_fix(x0 + i), stex_pixel_fix(y0 + j), v);
  const ulong at = offset + (ulong)j * row_stride + (ulong)i * (ulong)p.channels;
  for (int c = 0; c < p.channels; ++c) dst[at + (ulong)c] = v[c];
  STEX_WATCHDOG_CHECK();
}
)stex_capi";
}

}  // namespace stex::capi
