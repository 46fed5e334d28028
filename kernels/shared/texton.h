/* Texton noise evaluation, shared by the OpenCL kernels and the C++ reference (S1 eq. 1-3, §8).
 *
 *   f(x) = mean + (sum_j h(x - x_j) - lambda * sum(alpha)) / sqrt(lambda),   h(y) = sum_k alpha(k) psi(y - k)
 *
 * psi is the centred B-spline of degree `order` (S1 §10): the bilinear kernel (order 1, S1), the
 * nearest-neighbour box (order 0, S2's SOT), the cubic (order 3) or the quintic (order 5) B-spline, whose
 * support is [-(order+1)/2, (order+1)/2]^2. alpha lives on k in [0, s)^2; h is non-zero for y in
 * [-(order+1)/2, s - 1 + (order+1)/2)^2 (order 1: [-1, s)^2, order 0: [-0.5, s - 0.5)^2); so r = s + order
 * and lambda = MNI / r^2.
 *
 * Coordinates (exact for any int64 pixel index: x = 10^12 is as precise as x = 0, docs/ARCHITECTURE.md
 * "Invariants"):
 *  - Output pixel P (int64) has its centre at P + 1/2 output pixels; in fixed point with STEX_FIX_BITS
 *    fractional bits: X(P) = (2P + 1) * 2^(STEX_FIX_BITS - 1), an int64.
 *  - The Poisson process lives on a grid of square cells of side A fixed units (A = round(c r scale 2^F),
 *    an int64 chosen on the host; c = 0.6 by default, S1 §8). Cell k covers [k A, (k + 1) A).
 *  - Impulse j of cell (kx, ky) sits at k A + floor(u24 * A / 2^24) with u24 the top 24 bits of its draw.
 *  - Pixel-to-impulse displacement D = X(P) - X_j is an exact int64; the only float step is
 *    t = float(D) * inv_fix_scale (texton coordinates, exemplar pixels), computed identically everywhere.
 * The cell grid scales with `scale`, so changing scale zooms the same realisation (up to the rounding of A).
 *
 * Summation order is global: cells by (ky, kx) ascending, impulses by j ascending. Every strategy (tile
 * splat, gather, point query, C++ reference) adds each pixel's contributions in that order with the same
 * float expression, so outputs are bit-identical across strategies, tilings, work-group sizes and devices
 * that implement IEEE float add/mul/convert with round-to-nearest (all OpenCL devices for these ops).
 * Impulses that do not cover a pixel contribute an exact +0, which changes no bits.
 */
#ifndef STEX_TEXTON_H
#define STEX_TEXTON_H
#include "poisson.h"
#include "rng.h"
#include "stex_platform.h"

#define STEX_FIX_BITS 16
#define STEX_MAX_CHANNELS 4

/* Everything a kernel needs besides the buffers; 32-bit fields only (104 bytes, static_assert on host). */
typedef struct {
  stex_i32 support;  /* s: alpha is s x s */
  stex_i32 channels; /* 1..4 */
  stex_i32 order;    /* 0 nearest (SOT), 1 bilinear, 3 cubic, 5 quintic B-spline */
  stex_i32 stride;   /* s + 2 frame: alpha is stored planar, one stride^2 plane per channel, zero frame */
  stex_u32 seed_lo, seed_hi;
  stex_u32 cell_lo, cell_hi;               /* A: cell side in fixed units (int64) */
  stex_u32 reach_back_lo, reach_back_hi;   /* impulses with X_j >= X - reach_back may cover X (int64) */
  stex_u32 reach_fwd_lo, reach_fwd_hi;     /* impulses with X_j <= X + reach_fwd may cover X (int64) */
  float inv_fix_scale;                     /* 1 / (2^F * scale): fixed units -> exemplar pixels */
  float inv_sqrt_lambda;                   /* 1 / sqrt(lambda) */
  stex_u32 poisson_len;                    /* entries in the threshold table of the per-cell mean */
  float t_lo, t_hi;                        /* texton support in texton coordinates: [t_lo, t_hi) */
  stex_i32 frame;                          /* zero frame of the padded alpha: 1 (orders 0, 1), order (3, 5) */
  float mean[STEX_MAX_CHANNELS];           /* model mean per channel */
  float lambda_sum_alpha[STEX_MAX_CHANNELS]; /* lambda * sum(alpha) per channel */
} stex_texton_params;

/* Fixed-point centre of output pixel P. */
STEX_FN stex_i64 stex_pixel_fix(stex_i64 p) { return (2 * p + 1) * ((stex_i64)1 << (STEX_FIX_BITS - 1)); }

STEX_FN stex_i64 stex_cell_size(const stex_texton_params p) { return stex_join64(p.cell_lo, p.cell_hi); }

/* Range of cells [k0, k1] whose impulses may cover some point with fixed coordinate in [xmin, xmax]. */
STEX_FN void stex_texton_cell_range(const stex_texton_params p, stex_i64 xmin, stex_i64 xmax, stex_i64* k0,
                                    stex_i64* k1) {
  stex_i64 a = stex_cell_size(p);
  *k0 = stex_floordiv(xmin - stex_join64(p.reach_back_lo, p.reach_back_hi), a);
  *k1 = stex_floordiv(xmax + stex_join64(p.reach_fwd_lo, p.reach_fwd_hi), a);
}

/* Number of impulses in the cell with key `key`. */
STEX_FN stex_u32 stex_texton_count(const stex_texton_params p, const stex_uvec4 key,
                                   const STEX_GLOBAL stex_u32* poisson_table) {
  stex_uvec4 v = stex_draw(key, p.seed_lo, p.seed_hi, 0u, STEX_DOMAIN_COUNT);
  return stex_poisson_count(poisson_table, p.poisson_len, v.x);
}

/* Fixed-point coordinate of an impulse in cell k (side a) from its 32-bit draw `word`: k a + floor(u24 a / 2^24),
 * u24 the word's top 24 bits. Integer arithmetic only: the local-memory gather stores the words and
 * reconstructs the same int64 with this function. */
STEX_FN stex_i64 stex_texton_coord(stex_i64 k, stex_i64 a, stex_u32 word) {
  return k * a + (stex_i64)(((stex_u64)(word >> 8) * (stex_u64)a) >> 24);
}

/* The 128-bit draw of impulse j of the cell with key `key` (x, y: its position words), and the fixed-point
 * position of impulse j of cell (kx, ky); `mark` receives a spare 32-bit word of the draw
 * (random signs for noise mixing, S1 §7). */
STEX_FN stex_uvec4 stex_texton_impulse_draw(const stex_texton_params p, const stex_uvec4 key, stex_u32 j) {
  return stex_draw(key, p.seed_lo, p.seed_hi, j, STEX_DOMAIN_IMPULSE);
}
STEX_FN void stex_texton_impulse(const stex_texton_params p, const stex_uvec4 key, stex_i64 kx, stex_i64 ky,
                                 stex_u32 j, stex_i64* xj, stex_i64* yj, stex_u32* mark) {
  stex_uvec4 v = stex_texton_impulse_draw(p, key, j);
  stex_i64 a = stex_cell_size(p);
  *xj = stex_texton_coord(kx, a, v.x);
  *yj = stex_texton_coord(ky, a, v.y);
  *mark = v.z;
}

/* Bilinear (or nearest) tap for a displacement (dx, dy) = X(P) - X_j in fixed units: the padded index of
 * the top-left texel and four weights. Outside the support: index 0 and zero weights (an exact +0). */
STEX_FN stex_i32 stex_texton_tap(const stex_texton_params p, stex_i64 dx, stex_i64 dy, float* w00,
                                 float* w10, float* w01, float* w11) {
  float tx = (float)dx * p.inv_fix_scale;
  float ty = (float)dy * p.inv_fix_scale;
  int inside = (tx >= p.t_lo) && (tx < p.t_hi) && (ty >= p.t_lo) && (ty < p.t_hi);
  if (!inside) {
    *w00 = 0.0f;
    *w10 = 0.0f;
    *w01 = 0.0f;
    *w11 = 0.0f;
    return 0;
  }
  float fx0, fy0, fx, fy;
  if (p.order == 0) {
    fx0 = STEX_FLOORF(tx + 0.5f);
    fy0 = STEX_FLOORF(ty + 0.5f);
    fx = 0.0f;
    fy = 0.0f;
  } else {
    fx0 = STEX_FLOORF(tx);
    fy0 = STEX_FLOORF(ty);
    fx = tx - fx0;
    fy = ty - fy0;
  }
  *w00 = (1.0f - fx) * (1.0f - fy);
  *w10 = fx * (1.0f - fy);
  *w01 = (1.0f - fx) * fy;
  *w11 = fx * fy;
  return ((stex_i32)fy0 + 1) * p.stride + ((stex_i32)fx0 + 1);
}

/* One channel's contribution of a tap; `plane` is that channel's padded (s+2)^2 alpha plane. */
STEX_FN float stex_texton_fetch(const STEX_GLOBAL float* plane, stex_i32 idx, stex_i32 stride, float w00,
                                float w10, float w01, float w11) {
  return w00 * plane[idx] + w10 * plane[idx + 1] + w01 * plane[idx + stride] + w11 * plane[idx + stride + 1];
}

/* B-spline weights of degree `order` (3 or 5, S1 §10) for the taps floor(t) - (order - 1)/2 + m, m = 0..order,
 * of a coordinate with fractional part f = t - floor(t): w[m] = beta_order(f + (order - 1)/2 - m), in Horner
 * form (exact polynomials of the centred B-spline; tests/kernels compare them with the defining sum). */
STEX_FN void stex_bspline_weights(int order, float f, float* w) {
  if (order == 3) {
    const float g = 1.0f - f;
    w[0] = g * g * g * (1.0f / 6.0f);
    w[1] = (f * f * (3.0f * f - 6.0f) + 4.0f) * (1.0f / 6.0f);
    w[2] = (g * g * (3.0f * g - 6.0f) + 4.0f) * (1.0f / 6.0f);
    w[3] = f * f * f * (1.0f / 6.0f);
  } else {
    const float g = 1.0f - f;
    const float g2 = g * g, f2 = f * f;
    w[0] = g2 * g2 * g * (1.0f / 120.0f);
    w[1] = (f * (f * (f * (f * (5.0f * f - 20.0f) + 20.0f) + 20.0f) - 50.0f) + 26.0f) * (1.0f / 120.0f);
    w[2] = (f2 * (f2 * (30.0f - 10.0f * f) - 60.0f) + 66.0f) * (1.0f / 120.0f);
    w[3] = (g2 * (g2 * (30.0f - 10.0f * g) - 60.0f) + 66.0f) * (1.0f / 120.0f);
    w[4] = (g * (g * (g * (g * (5.0f * g - 20.0f) + 20.0f) + 20.0f) - 50.0f) + 26.0f) * (1.0f / 120.0f);
    w[5] = f2 * f2 * f * (1.0f / 120.0f);
  }
}

/* sum_{my, mx <= order} wy[my] (wx[mx] a[my stride + mx]): rows my ascending, within a row mx ascending, the row
 * sum then weighted. Callers pass `order` as a literal (3 or 5): stex_texton_hi_channel. */
STEX_FN float stex_texton_hi_dot(const STEX_GLOBAL float* a, stex_i32 stride, const float* wx, const float* wy,
                                 const int order) {
  float sum = 0.0f;
  for (int my = 0; my <= order; ++my) {
    float row = 0.0f;
    for (int mx = 0; mx <= order; ++mx) row += wx[mx] * a[my * stride + mx];
    sum += wy[my] * row;
  }
  return sum;
}

/* Higher-order texton (orders 3 and 5, S1 §10) at a displacement (dx, dy) in fixed units, in two steps so
 * that a caller can loop over channels with a literal bound (docs/portability.md, "run-time loop bounds around
 * private arrays"):
 *  - stex_texton_hi_taps: the B-spline weights wx, wy (order + 1 each) and the padded index of the first tap;
 *    0 outside the support (every strategy skips the same displacements, so no bit depends on it);
 *  - stex_texton_hi_channel: h_c = sum_{my, mx} wy[my] (wx[mx] alpha_c(...)) for one channel's plane, in one
 *    fixed order (rows my ascending, within a row mx ascending, the row sum then weighted), with the order as
 *    a literal at both call sites of stex_texton_hi_dot. */
STEX_FN int stex_texton_hi_taps(const stex_texton_params p, stex_i64 dx, stex_i64 dy, float* wx, float* wy,
                                stex_i32* idx0) {
  const float tx = (float)dx * p.inv_fix_scale;
  const float ty = (float)dy * p.inv_fix_scale;
  if (!((tx >= p.t_lo) && (tx < p.t_hi) && (ty >= p.t_lo) && (ty < p.t_hi))) return 0;
  const float fx0 = STEX_FLOORF(tx), fy0 = STEX_FLOORF(ty);
  stex_bspline_weights(p.order, tx - fx0, wx);
  stex_bspline_weights(p.order, ty - fy0, wy);
  const stex_i32 back = (p.order - 1) / 2;
  *idx0 = ((stex_i32)fy0 - back + p.frame) * p.stride + ((stex_i32)fx0 - back + p.frame);
  return 1;
}

STEX_FN float stex_texton_hi_channel(const stex_texton_params p, const STEX_GLOBAL float* plane, stex_i32 idx0,
                                     const float* wx, const float* wy) {
  return p.order == 3 ? stex_texton_hi_dot(plane + idx0, p.stride, wx, wy, 3)
                      : stex_texton_hi_dot(plane + idx0, p.stride, wx, wy, 5);
}

/* Adds h_c(t) to acc[c] for c < channels (the gathers' form). */
STEX_FN void stex_texton_hi_accum(const stex_texton_params p, const STEX_GLOBAL float* alpha, stex_i64 dx, stex_i64 dy,
                                  float* acc) {
  float wx[6], wy[6];
  stex_i32 idx0;
  if (!stex_texton_hi_taps(p, dx, dy, wx, wy, &idx0)) return;
  const stex_i32 plane = p.stride * p.stride;
  for (int c = 0; c < p.channels; ++c) acc[c] += stex_texton_hi_channel(p, alpha + c * plane, idx0, wx, wy);
}

/* Final normalisation of an accumulated sum (S1 eq. 2 plus the mean). */
STEX_FN float stex_texton_finish(const stex_texton_params p, int c, float acc) {
  return p.mean[c] + (acc - p.lambda_sum_alpha[c]) * p.inv_sqrt_lambda;
}

/* Adds the taps of the impulse at (xj, yj) to the sums acc[c] of the pixel at (x, y) (fixed units): the body
 * of the gathers' impulse loop, shared by stex_texton_eval and the local-memory gather
 * (kernels/texton_gather_local.cl) so that both add the same floats. */
STEX_FN void stex_texton_add_impulse(const stex_texton_params p, const STEX_GLOBAL float* alpha, stex_i64 x,
                                     stex_i64 y, stex_i64 xj, stex_i64 yj, float* acc) {
  if (p.order > 1) {
    stex_texton_hi_accum(p, alpha, x - xj, y - yj, acc);
    return;
  }
  const stex_i32 plane = p.stride * p.stride;
  float w00, w10, w01, w11;
  stex_i32 idx = stex_texton_tap(p, x - xj, y - yj, &w00, &w10, &w01, &w11);
  for (int c = 0; c < p.channels; ++c)
    acc[c] += stex_texton_fetch(alpha + c * plane, idx, p.stride, w00, w10, w01, w11);
}

/* Gather evaluation at one fixed-point position (the point-query path; the gather kernel and the C++
 * reference both call it). out[c] for c < channels. */
STEX_FN void stex_texton_eval(const stex_texton_params p, const STEX_GLOBAL float* alpha,
                              const STEX_GLOBAL stex_u32* poisson_table, stex_i64 x, stex_i64 y, float* out) {
  float acc[STEX_MAX_CHANNELS] = {0.0f, 0.0f, 0.0f, 0.0f};
  stex_i64 kx0, kx1, ky0, ky1;
  stex_texton_cell_range(p, x, x, &kx0, &kx1);
  stex_texton_cell_range(p, y, y, &ky0, &ky1);
  for (stex_i64 ky = ky0; ky <= ky1; ++ky) {
    for (stex_i64 kx = kx0; kx <= kx1; ++kx) {
      stex_uvec4 key = stex_cell_key(kx, ky);
      stex_u32 n = stex_texton_count(p, key, poisson_table);
      for (stex_u32 j = 0; j < n; ++j) {
        stex_i64 xj, yj;
        stex_u32 mark;
        stex_texton_impulse(p, key, kx, ky, j, &xj, &yj, &mark);
        stex_texton_add_impulse(p, alpha, x, y, xj, yj, acc);
      }
    }
  }
  for (int c = 0; c < p.channels; ++c) out[c] = stex_texton_finish(p, c, acc[c]);
}

/* Bounds of the local-memory gather (kernels/texton_gather_local.cl), computed on the host from the same
 * integers the kernel uses. A work-group's tile of `tile` pixels along an axis spans the fixed-point centres
 * [X, X + (tile - 1) 2^F]; its cells are stex_texton_cell_range of that interval, i.e. the cells meeting an
 * interval of length L = (tile - 1) 2^F + reach_back + reach_fwd, at most floor(L / A) + 2 of them. */
STEX_FN stex_i64 stex_texton_tile_cells_max(const stex_texton_params p, stex_i64 tile) {
  const stex_i64 len = (tile - 1) * ((stex_i64)1 << STEX_FIX_BITS) + stex_join64(p.reach_back_lo, p.reach_back_hi) +
                       stex_join64(p.reach_fwd_lo, p.reach_fwd_hi);
  return len / stex_cell_size(p) + 2;
}

/* Impulse slots per cell: the largest count the Poisson table can return (len - 1, the folded tail), at
 * least 1. */
STEX_FN stex_u32 stex_texton_cell_slots(const stex_texton_params p) {
  return p.poisson_len > 1u ? p.poisson_len - 1u : 1u;
}

#endif /* STEX_TEXTON_H */
