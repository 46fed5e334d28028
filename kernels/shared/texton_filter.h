/* On-the-fly filtering of texton noise (S1 §5), shared by kernels/texton_filtered.cl and the C++ reference.
 *
 * By linearity, filtering the noise with a pixel's footprint filter is filtering the texton: each impulse
 * contributes the filtered texton (h * g)(x - x_j) instead of h(x - x_j). As S1 §5 does with the GPU's
 * texture units, h * g is approximated by MIP-mapping plus anisotropic probes of the texton texture:
 *  - MIP pyramid: level 0 is alpha (s x s); level l + 1 is level l box-averaged 2 x 2 (zero outside, size
 *    ceil(s_l / 2)), down to 1 x 1. Level l's texel k sits at texton position c_l + k 2^l with
 *    c_l = (2^l - 1) / 2 (the centre of the 2^l x 2^l block it averages) and is interpolated bilinearly on
 *    that 2^l grid: h_l(t) = sum_k alpha_l(k) psi((t - c_l) / 2^l - k). Integral of h_l = 4^l sum alpha_l =
 *    sum alpha for every l: the mean of the noise is preserved at every level (no renormalisation).
 *  - Footprint: the pixel's Jacobian J (texton texels per output pixel) maps the pixel square to a
 *    parallelogram with axes a = J e_x, b = J e_y. The longer axis is the major one; the number of probes is
 *    n = min(ceil(|major| / |minor|), max_aniso); the level of detail is log2(|major| / n) clamped to the
 *    pyramid, split into an integer level and a blend (trilinear); the n probes sit at
 *    ((i + 1/2) / n - 1/2) major, i = 0..n-1, and are averaged.
 * The host computes the footprint (runtime/texton_filter.cpp: level, blend, probe step, probe count, the
 * extra reach of the filtered texton) in double and passes it as floats and integers, so the device does no
 * division, log or square root: kernel and reference are bit-identical (same terms, same order as
 * stex_texton_eval: cells by (ky, kx), impulses by j, probes by i, level l before l + 1).
 *
 * A footprint of level 0, blend 0, one probe is the unfiltered bilinear tap of stex_texton_tap/fetch: the
 * filtered render of a magnified or unit-scale view equals the unfiltered render bit for bit.
 * Filtering applies to bilinear textons (order 1, S1 §5); the host rejects other orders.
 */
#ifndef STEX_TEXTON_FILTER_H
#define STEX_TEXTON_FILTER_H
#include "texton.h"

#define STEX_MIP_MAX_LEVELS 14 /* supports up to 4096 = 2^12 need 13 levels */

/* The pyramid's layout: level l is size[l] x size[l] per channel, stored padded with a zero frame of 1
 * (stride size[l] + 2), channel c of level l at offset[l] + c (size[l] + 2)^2 floats. */
typedef struct {
  stex_i32 levels;
  stex_i32 pad0;
  stex_i32 size[STEX_MIP_MAX_LEVELS];
  stex_i32 offset[STEX_MIP_MAX_LEVELS];
} stex_mip_params;

/* A pixel's footprint, computed on the host (runtime/texton_filter.h). */
typedef struct {
  stex_i32 level;     /* integer level of detail l (0 <= l < levels); blend towards l + 1 */
  stex_i32 probes;    /* n >= 1 */
  float blend;        /* weight of level l + 1 in [0, 1); 0 when l is the last level */
  float inv_probes;   /* 1 / n */
  float step_x;       /* probe step along the major axis, texton texels: major / n */
  float step_y;
  float start;        /* (1 - n) / 2: probe i sits at (start + i) * step */
  float gain;         /* fluctuation gain: 1, below 1 only for footprints beyond the pyramid's top */
  stex_u32 reach_lo;  /* extra reach of the filtered texton beyond h's support, fixed units (int64) */
  stex_u32 reach_hi;
  stex_u32 pad0, pad1;
} stex_footprint;

/* Bilinear lookup of level l at texton coordinates (tx, ty); one value per channel added to v[c] * w. */
STEX_FN void stex_mip_tap(const stex_texton_params p, const stex_mip_params m, const STEX_GLOBAL float* pyr, int l,
                          float tx, float ty, float w, float* v) {
  const stex_i32 s = m.size[l];
  const stex_i32 stride = s + 2;
  float u, t;
  if (l == 0) {
    u = tx;
    t = ty;
  } else {
    const float scale = 1.0f / (float)(1 << l);            /* exact */
    const float centre = 0.5f * (float)((1 << l) - 1);     /* exact */
    u = (tx - centre) * scale;
    t = (ty - centre) * scale;
  }
  if (!((u >= -1.0f) && (u < (float)s) && (t >= -1.0f) && (t < (float)s))) return;
  const float fx0 = STEX_FLOORF(u), fy0 = STEX_FLOORF(t);
  const float fx = u - fx0, fy = t - fy0;
  const float w00 = (1.0f - fx) * (1.0f - fy), w10 = fx * (1.0f - fy), w01 = (1.0f - fx) * fy, w11 = fx * fy;
  const stex_i32 idx = ((stex_i32)fy0 + 1) * stride + ((stex_i32)fx0 + 1);
  for (int c = 0; c < STEX_MAX_CHANNELS; ++c) { /* a literal bound: see the note at stex_texton_filtered_accum */
    if (c >= p.channels) break;
    const STEX_GLOBAL float* plane = pyr + m.offset[l] + c * stride * stride;
    v[c] += w * stex_texton_fetch(plane, idx, stride, w00, w10, w01, w11);
  }
}

/* The filtered texton's contribution at displacement (dx, dy) (fixed units), added to acc[c]. The channel
 * loops here run to the literal STEX_MAX_CHANNELS (and stop at p.channels): compilers unroll them, so they
 * spend none of the loop iterations a driver may cap per kernel invocation (Mesa's llvmpipe: 65535; the
 * loop watchdog, docs/portability.md). A footprint's many impulses times probes stay within it. */
STEX_FN void stex_texton_filtered_accum(const stex_texton_params p, const stex_mip_params m,
                                        const STEX_GLOBAL float* pyr, const stex_footprint f, stex_i64 dx,
                                        stex_i64 dy, float* acc) {
  const float tx = (float)dx * p.inv_fix_scale;
  const float ty = (float)dy * p.inv_fix_scale;
  for (int i = 0; i < f.probes; ++i) {
    const float k = f.start + (float)i;
    const float px = tx + k * f.step_x;
    const float py = ty + k * f.step_y;
    float v[STEX_MAX_CHANNELS] = {0.0f, 0.0f, 0.0f, 0.0f};
    if (f.blend > 0.0f) {
      stex_mip_tap(p, m, pyr, f.level, px, py, 1.0f - f.blend, v);
      stex_mip_tap(p, m, pyr, f.level + 1, px, py, f.blend, v);
    } else {
      stex_mip_tap(p, m, pyr, f.level, px, py, 1.0f, v);
    }
    for (int c = 0; c < STEX_MAX_CHANNELS; ++c) {
      if (c >= p.channels) break;
      acc[c] += v[c] * f.inv_probes;
    }
  }
}

/* Number of cells the filtered evaluation at (x, y) with footprint f visits: the cells of its reach in
 * (ky, kx) order. The host uses it to split a pixel's cells over several launches (below). */
STEX_FN stex_i64 stex_texton_filtered_cells(const stex_texton_params p, const stex_footprint f, stex_i64 x,
                                            stex_i64 y) {
  const stex_i64 extra = stex_join64(f.reach_lo, f.reach_hi);
  stex_i64 kx0, kx1, ky0, ky1;
  stex_texton_cell_range(p, x - extra, x + extra, &kx0, &kx1);
  stex_texton_cell_range(p, y - extra, y + extra, &ky0, &ky1);
  return (kx1 - kx0 + 1) * (ky1 - ky0 + 1);
}

/* Adds the impulses of cells [first, end) of the pixel's cells (numbered in (ky, kx) order, end clamped to
 * their number) to acc[c]. One call over all cells is the whole sum; consecutive windows in order add the same
 * terms in the same order, so a pixel whose cells are split over several launches (acc kept in a float
 * buffer between them: the same 32 bits) gets the same bits. The split exists for drivers that cap a kernel
 * invocation's loop iterations (docs/portability.md, loop watchdog): a grazing footprint reaches thousands
 * of cells. */
STEX_FN void stex_texton_filtered_window(const stex_texton_params p, const stex_mip_params m,
                                         const STEX_GLOBAL float* pyr, const STEX_GLOBAL stex_u32* poisson_table,
                                         const stex_footprint f, stex_i64 x, stex_i64 y, stex_i64 first,
                                         stex_i64 end, float* acc) {
  const stex_i64 extra = stex_join64(f.reach_lo, f.reach_hi);
  stex_i64 kx0, kx1, ky0, ky1;
  stex_texton_cell_range(p, x - extra, x + extra, &kx0, &kx1);
  stex_texton_cell_range(p, y - extra, y + extra, &ky0, &ky1);
  const stex_i64 nx = kx1 - kx0 + 1;
  const stex_i64 total = nx * (ky1 - ky0 + 1);
  if (end > total) end = total;
  if (first >= end) return;
  stex_i64 ky = ky0 + first / nx;
  stex_i64 kx = kx0 + first % nx;
  for (stex_i64 t = first; t < end; ++t) {
    stex_uvec4 key = stex_cell_key(kx, ky);
    stex_u32 n = stex_texton_count(p, key, poisson_table);
    for (stex_u32 j = 0; j < n; ++j) {
      stex_i64 xj, yj;
      stex_u32 mark;
      stex_texton_impulse(p, key, kx, ky, j, &xj, &yj, &mark);
      stex_texton_filtered_accum(p, m, pyr, f, x - xj, y - yj, acc);
    }
    if (++kx > kx1) {
      kx = kx0;
      ++ky;
    }
  }
}

/* What a launch of kernels/texton_filtered.cl does with its cell window [cell_first, cell_end): LOAD starts
 * from the sums a previous window left in `out` (else from 0), FINISH turns the sums into noise values (else
 * `out` receives the sums). One launch over all cells: FINISH only. */
#define STEX_FILTER_PASS_LOAD 1
#define STEX_FILTER_PASS_FINISH 2

/* The filtered noise value from the sum of all cells' contributions. */
STEX_FN void stex_texton_filtered_finish(const stex_texton_params p, const stex_footprint f, const float* acc,
                                         float* out) {
  for (int c = 0; c < p.channels; ++c)
    out[c] = p.mean[c] + ((acc[c] - p.lambda_sum_alpha[c]) * p.inv_sqrt_lambda) * f.gain;
}

/* Filtered gather evaluation at one fixed-point position with footprint f. out[c] for c < channels. */
STEX_FN void stex_texton_eval_filtered(const stex_texton_params p, const stex_mip_params m,
                                       const STEX_GLOBAL float* pyr, const STEX_GLOBAL stex_u32* poisson_table,
                                       const stex_footprint f, stex_i64 x, stex_i64 y, float* out) {
  float acc[STEX_MAX_CHANNELS] = {0.0f, 0.0f, 0.0f, 0.0f};
  stex_texton_filtered_window(p, m, pyr, poisson_table, f, x, y, 0, stex_texton_filtered_cells(p, f, x, y), acc);
  stex_texton_filtered_finish(p, f, acc, out);
}

#endif /* STEX_TEXTON_FILTER_H */
