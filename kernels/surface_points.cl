/* Surface texton noise point queries (S1 §6): one work-item per surface point evaluates stex_surface_eval
 * (kernels/shared/surface.h), the function the C++ reference (runtime/surface.h) calls, so both agree bit
 * for bit. positions: 3 floats per point (world units); frames: 9 floats per point (u1, u2, u3, u3 the
 * normal); out: `channels` floats per point, interleaved. Global size: at least count; extra work-items
 * return.
 */
#include "shared/surface.h"

__kernel void surface_points(const stex_surface_params p_arg, __global const float* alpha,
                             __global const uint* poisson_table, __global const float* positions,
                             __global const float* frames, const uint count, __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_surface_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const size_t k = get_global_id(0);
  if (k >= count) return;
  float u[9];
  for (int i = 0; i < 9; ++i) u[i] = frames[9 * k + i];
  float v[STEX_MAX_CHANNELS];
  stex_surface_eval(p, alpha, poisson_table, positions[3 * k], positions[3 * k + 1], positions[3 * k + 2], u, v);
  for (int c = 0; c < p.channels; ++c) out[k * (size_t)p.channels + c] = v[c];
  STEX_WATCHDOG_CHECK();
}
