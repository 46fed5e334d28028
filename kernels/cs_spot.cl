/* Cyclostationary spot noise (shared/cs.h; the C++ reference, runtime/cs_spot.h, evaluates stex_cs_spot_eval
 * per pixel: these kernels equal it bit for bit). Two paths, chosen by the host from the model and the scale
 * only (never from the chunking):
 *  - fast (p.canon == 1), two passes per chunk:
 *    cs_spot_weights: one work-item per lattice node of the chunk's window computes its weight W_u once (a
 *                     node is shared by the ~|E| / |cell| pixels its spot covers);
 *    cs_spot:         one work-item per run of STEX_CS_RUN pixels of a row: each pixel's canonical node
 *                     from the chunk's first pixel's (stex_cs_canon_near, 32-bit), then the nodes' spots
 *                     summed node by node for the run (stex_cs_spot_run: a node's weight and y taps shared).
 *    Built with -DSTEX_CS_CH=<channels> (the channel loops unroll).
 *  - general (periods x scale above 4096 output pixels, or displacements beyond 32 bits): cs_spot_general,
 *    stex_cs_spot_eval per pixel from its absolute coordinates.
 * Output: `channels` interleaved floats per pixel, out[(j * pitch + i) * channels + c], i < width. Global size:
 * at least (width, height); extra work-items return.
 */
#include "shared/cs.h"

#ifndef STEX_CS_CH
#define STEX_CS_CH 1
#endif

/* Node (k0 + a, l0 + b) for a < nk, b < nl: its weight into weights[b nk + a]. */
__kernel void cs_spot_weights(const stex_cs_params p_arg, __global const float* gauss, const long k0, const long l0,
                              const int nk, const int nl, __global float* weights) {
  const stex_cs_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int a = (int)get_global_id(0);
  const int b = (int)get_global_id(1);
  if (a >= nk || b >= nl) return;
  weights[b * nk + a] = stex_cs_weight(p, gauss, k0 + a, l0 + b);
}

/* (r0x, r0y): the canonical residual of the chunk's first pixel; the weight window (nk x nl) starts at node
 * offset (wk0, wl0) from that pixel's node and holds every node the chunk's runs reach. One work-item per
 * STEX_CS_RUN consecutive pixels of a row (global size x: width / STEX_CS_RUN, rounded up). */
__kernel void cs_spot(const stex_cs_params p_arg, __global const float* spot_pad, __global const float* mean,
                      __global const float* weights, __global const int* rows, const int nk, const int nl,
                      const int wk0, const int wl0, const int r0x, const int r0y, const stex_cs_hist_params h_arg,
                      __global const float* hist, const long x0, const long y0, const int width, const int height,
                      const int pitch, __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_cs_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const stex_cs_hist_params h = h_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0) * STEX_CS_RUN;
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  float v[STEX_CS_RUN * STEX_CS_CH];
  stex_cs_spot_run(p, spot_pad, mean, weights, rows, nk, nl, wk0, wl0, h, hist, STEX_CS_CH, r0x + i * 65536,
                   r0y + j * 65536, v);
  const int n = width - i < STEX_CS_RUN ? width - i : STEX_CS_RUN;
  const size_t o = ((size_t)j * (size_t)pitch + (size_t)i) * (size_t)STEX_CS_CH;
  for (int q = 0; q < n; ++q)
    for (int c = 0; c < STEX_CS_CH; ++c) out[o + (size_t)(q * STEX_CS_CH + c)] = v[q * STEX_CS_CH + c];
  STEX_WATCHDOG_CHECK();
}

__kernel void cs_spot_general(const stex_cs_params p_arg, __global const float* spot, __global const float* mean,
                              __global const float* gauss, __global const uint* reduce, const stex_cs_hist_params h_arg,
                              __global const float* hist, const long x0, const long y0, const int width,
                              const int height, const int pitch, __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_cs_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const stex_cs_hist_params h = h_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  float v[STEX_CS_MAX_CHANNELS];
  stex_cs_spot_eval(p, spot, mean, gauss, reduce, h, hist, stex_cs_pixel_fix(x0 + i), stex_cs_pixel_fix(y0 + j), v);
  const size_t o = ((size_t)j * (size_t)pitch + (size_t)i) * (size_t)p.channels;
  for (int c = 0; c < p.channels; ++c) out[o + (size_t)c] = v[c];
  STEX_WATCHDOG_CHECK();
}
