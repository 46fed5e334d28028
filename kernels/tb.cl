/* Tiling and blending (kinds tb, cs-tb) in two passes per chunk (shared/tb.h; the C++ reference, runtime/tb.h,
 * evaluates the same functions per pixel: the kernels equal it bit for bit):
 *  - tb_vertices: one work-item per triangle-grid vertex of the chunk's window computes its tile centre once
 *    (the vertex hash; for cs-tb the lattice node search);
 *  - tb: one work-item per output pixel finds its triangle exactly from the chunk's canonical residual
 *    (stex_tb_canon_near, 32-bit), reads its 3 vertices' centres and blends 3 fetches.
 * Built with -DSTEX_TB_CH=<channels> -DSTEX_TB_CS=<0|1> (the host's), so the channel loops unroll.
 * Output: `channels` interleaved floats per pixel, out[(j * pitch + i) * channels + c].
 */
#include "shared/tb.h"

#ifndef STEX_TB_CH
#define STEX_TB_CH 1
#endif
#ifndef STEX_TB_CS
#define STEX_TB_CS 0
#endif

/* Vertex (k0 + a, l0 + b) for a < nk, b < nl: its tile centre into centres[2 (b nk + a) + {0, 1}].
 * (kc0, lc0): the CS-lattice canonical node of the chunk's first pixel (cs-tb). */
__kernel void tb_vertices(const stex_tb_params p, const long k0, const long l0, const long kc0, const long lc0,
                          const int nk, const int nl, __global float* centres) {
  const int a = (int)get_global_id(0);
  const int b = (int)get_global_id(1);
  if (a >= nk || b >= nl) return;
  float cx, cy;
  stex_tb_vertex_centre(p, k0 + a, l0 + b, kc0, lc0, &cx, &cy);
  centres[2 * (b * nk + a)] = cx;
  centres[2 * (b * nk + a) + 1] = cy;
}

/* (r0gx, r0gy), (r0cx, r0cy): the canonical residuals of the chunk's first pixel in the grid and the CS
 * lattice; the grid node of a pixel is the chunk's + (dk, dl), its vertices' centres are at window index
 * (dk - dk_min + .., dl - dl_min + ..) of `centres` (nk x nl, from tb_vertices). */
__kernel void tb(const stex_tb_params p, __global const float* g, __global const float* lut, __global const float* pca,
                 __global const float* mean, const stex_cs_hist_params h, __global const float* hist,
                 __global const float* centres, const int nk, const int nl,
                 const int dk_min, const int dl_min, const int r0gx, const int r0gy, const int r0cx, const int r0cy,
                 const long x0, const long y0, const int width, const int height, const int pitch,
                 __global float* out) {
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  const int g0x = (int)p.g0x_lo, g1x = (int)p.g1x_lo, g1y = (int)p.g1y_lo; /* g0y = 0 */
  const long gdet = stex_join64(p.gdet_lo, p.gdet_hi);
  int dk, dl, rx, ry;
  stex_tb_canon_near(g0x, 0, g1x, g1y, gdet, p.gi00, p.gi01, p.gi10, p.gi11, r0gx + i * 65536, r0gy + j * 65536, &dk,
                     &dl, &rx, &ry);
  float w0, w1, w2;
  const int upper = stex_tb_triangle(p, rx, ry, &w0, &w1, &w2);
  int cx = 0, cy = 0;
#if STEX_TB_CS
  {
    const long tdet = stex_join64(p.tdet_lo, p.tdet_hi);
    int ek, el;
    stex_tb_canon_near((int)p.t0x_lo, (int)p.t0y_lo, (int)p.t1x_lo, (int)p.t1y_lo, tdet, p.ti00, p.ti01, p.ti10,
                       p.ti11, r0cx + i * 65536, r0cy + j * 65536, &ek, &el, &cx, &cy);
  }
#endif
  /* The window holds every vertex of the chunk (margins of 2 cells); the clamp only guards memory. */
  int a = clamp(dk - dk_min, 0, nk - 2), b = clamp(dl - dl_min, 0, nl - 2);
  const int v0 = 2 * ((b + upper) * nk + a + upper), v1 = 2 * (b * nk + a + 1), v2 = 2 * ((b + 1) * nk + a);
  float v[STEX_TB_MAX_CHANNELS];
  stex_tb_blend(p, g, lut, pca, mean, h, hist, STEX_TB_CH, STEX_TB_CS, rx, ry, upper, w0, w1, w2, centres[v0], centres[v0 + 1],
                centres[v1], centres[v1 + 1], centres[v2], centres[v2 + 1], cx, cy, v);
  const size_t o = ((size_t)j * (size_t)pitch + (size_t)i) * (size_t)STEX_TB_CH;
  for (int c = 0; c < STEX_TB_CH; ++c) out[o + (size_t)c] = v[c];
}
