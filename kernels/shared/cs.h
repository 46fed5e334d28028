/* Cyclostationary spot noise (S4 §4.3 eq. 9, §5.1: the CS-ADSN of a spot shot on the lattice), shared by the
 * OpenCL kernel (kernels/cs_spot.cl) and the C++ reference (runtime/cs_spot.h):
 *
 *   I(x) = M(P(x)) + amplitude * sum_{u in L} W_u S(x - u),   L = {k t0 + l t1},  amplitude = sqrt(|Ω⁻| / sum w^2)
 *
 * S is the spot: the exemplar minus its cyclic mean M, times a window w that smooths its borders to zero
 * (GGM11's enhancement, S4 §7), read by bilinear interpolation between texel centres with zeros outside; the
 * weights W_u are N(0, 1) (unit variance: Appendix A's sqrt(|Ω⁻|) is folded into `amplitude`), one per
 * lattice node, from the counter RNG keyed by (seed, node (k, l)). M is stored on an n0 x n1 grid of phases
 * and interpolated bilinearly on that periodic grid. Appendix A: the process has mean M and covariance
 * amplitude^2 sum_u S(x - u) S(x + t - u).
 *
 * Exactness on the unbounded plane: positions are int64 fixed point (2^-16 output pixel, like texton noise)
 * and so are the period vectors T0, T1 (t * 2^16 * scale, rounded once on the host). A pixel first finds a
 * nearby node exactly in integers: the bits of its pixel coordinates select precomputed nodes (the table
 * `reduce`: for bit j, the node nearest (2^j, 0) and (0, 2^j) pixels), whose sum leaves a residual of at most
 * ~47 cell diameters, which one float solve with the inverse basis brings into the base cell; the residual
 * r = x - node is then an exact small int64 (node products wrap modulo 2^64, the residual is exact). Every
 * node of the window [dk0, dk1] x [dl0, dl1] around the base node whose spot may cover x is visited in
 * (dl, dk) order; the float work per node is the small displacement's conversion, the bilinear taps and the
 * weight. Only IEEE add, multiply, floor and conversions: kernel and reference agree bit for bit, and x = 10^12
 * is as precise as x = 0.
 *
 * Gaussian weights: a piecewise-linear inverse CDF of N(0, 1) on STEX_CS_GAUSS_SEGMENTS equal-probability
 * segments (top 10 bits pick the segment, the next 14 the position in it), scaled on the host so that its
 * variance is exactly 1 (symmetric: mean exactly 0); tails beyond ~3.5 sigma are cut.
 */
#ifndef STEX_CS_H
#define STEX_CS_H
#include "cs_hist.h"
#include "rng.h"
#include "stex_platform.h"

#define STEX_CS_FIX_BITS 16
#define STEX_CS_GAUSS_SEGMENTS 1024 /* the table has SEGMENTS + 1 entries */
#define STEX_CS_REDUCE_BITS 47      /* pixel coordinates below 2^46 in magnitude */
#define STEX_CS_MAX_CHANNELS 4
#define STEX_DOMAIN_CS_WEIGHT 0x43535774u /* "CSWt": the weight W_u of a lattice node */

/* 112 bytes; static_assert on the host. */
typedef struct {
  stex_u32 seed_lo, seed_hi;
  stex_u32 t0x_lo, t0x_hi, t0y_lo, t0y_hi; /* T0 in fixed output units (int64) */
  stex_u32 t1x_lo, t1x_hi, t1y_lo, t1y_hi; /* T1 */
  float inv_fix_scale;                     /* fixed output units -> model pixels */
  float i00, i01, i10, i11;                /* inverse of [T0 T1] (per fixed unit): (a, b) = inv (x, y) */
  stex_i32 dk0, dk1, dl0, dl1;             /* node offsets around the base node whose spot may reach x */
  stex_i32 spot_w, spot_h;                 /* spot texels */
  stex_i32 n0, n1;                         /* cyclic-mean grid */
  stex_i32 channels;                       /* 1..4 */
  float amplitude;
  stex_u32 pad0, pad1, pad2;
} stex_cs_params;

STEX_FN stex_i64 stex_cs_pixel_fix(stex_i64 p) { return (2 * p + 1) * ((stex_i64)1 << (STEX_CS_FIX_BITS - 1)); }

/* a - k b0 - l b1 modulo 2^64 (exact when the true value is small; no signed overflow). */
STEX_FN stex_i64 stex_cs_sub_node(stex_i64 a, stex_i64 k, stex_i64 b0, stex_i64 l, stex_i64 b1) {
  return (stex_i64)((stex_u64)a - (stex_u64)k * (stex_u64)b0 - (stex_u64)l * (stex_u64)b1);
}

/* N(0, 1) weight from 32 random bits. */
STEX_FN float stex_cs_gauss(const STEX_GLOBAL float* table, stex_u32 u) {
  stex_u32 seg = u >> 22;
  float f = ((float)((u >> 8) & 0x3fffu) + 0.5f) * 6.103515625e-5f; /* cell midpoints, times 2^-14: E[f] = 1/2 */
  float a = table[seg], b = table[seg + 1];
  return a + f * (b - a);
}

/* Bilinear read of the zero-padded spot (texel centres at i + 0.5) at model position (dx, dy), channel c. */
STEX_FN float stex_cs_spot_at(const stex_cs_params p, const STEX_GLOBAL float* spot, float dx, float dy, stex_i32 c) {
  float sx = dx - 0.5f, sy = dy - 0.5f;
  float fx0 = STEX_FLOORF(sx), fy0 = STEX_FLOORF(sy);
  stex_i32 i0 = (stex_i32)fx0, j0 = (stex_i32)fy0;
  float fx = sx - fx0, fy = sy - fy0;
  float v00 = 0.0f, v10 = 0.0f, v01 = 0.0f, v11 = 0.0f;
  stex_i32 ch = p.channels;
  if (j0 >= 0 && j0 < p.spot_h) {
    if (i0 >= 0 && i0 < p.spot_w) v00 = spot[(j0 * p.spot_w + i0) * ch + c];
    if (i0 + 1 >= 0 && i0 + 1 < p.spot_w) v10 = spot[(j0 * p.spot_w + i0 + 1) * ch + c];
  }
  if (j0 + 1 >= 0 && j0 + 1 < p.spot_h) {
    if (i0 >= 0 && i0 < p.spot_w) v01 = spot[((j0 + 1) * p.spot_w + i0) * ch + c];
    if (i0 + 1 >= 0 && i0 + 1 < p.spot_w) v11 = spot[((j0 + 1) * p.spot_w + i0 + 1) * ch + c];
  }
  float a = v00 + fx * (v10 - v00);
  float b = v01 + fx * (v11 - v01);
  return a + fy * (b - a);
}

/* Cyclic mean at phase (u, v) (any real: the grid is periodic), channel c. */
STEX_FN float stex_cs_mean_at(const stex_cs_params p, const STEX_GLOBAL float* mean, float u, float v, stex_i32 c) {
  float x = u * (float)p.n0, y = v * (float)p.n1;
  float fx0 = STEX_FLOORF(x), fy0 = STEX_FLOORF(y);
  float fx = x - fx0, fy = y - fy0;
  stex_i32 i0 = ((stex_i32)fx0 % p.n0 + p.n0) % p.n0, j0 = ((stex_i32)fy0 % p.n1 + p.n1) % p.n1;
  stex_i32 i1 = (i0 + 1) % p.n0, j1 = (j0 + 1) % p.n1;
  stex_i32 ch = p.channels;
  float v00 = mean[(j0 * p.n0 + i0) * ch + c], v10 = mean[(j0 * p.n0 + i1) * ch + c];
  float v01 = mean[(j1 * p.n0 + i0) * ch + c], v11 = mean[(j1 * p.n0 + i1) * ch + c];
  float a = v00 + fx * (v10 - v00);
  float b = v01 + fx * (v11 - v01);
  return a + fy * (b - a);
}

/* Adds the reduction-table nodes of the set bits of |q| (pixels) for axis `axis`, with q's sign. */
STEX_FN void stex_cs_reduce_axis(const STEX_GLOBAL stex_u32* reduce, stex_i32 axis, stex_i64 q, stex_i64* k, stex_i64* l) {
  stex_i64 s = q < 0 ? -1 : 1;
  stex_u64 m = (stex_u64)(q < 0 ? -q : q);
  for (stex_i32 j = 0; j < STEX_CS_REDUCE_BITS && (m >> j) != 0u; ++j) { /* stops at the highest set bit */
    if ((m >> j) & 1u) {
      const STEX_GLOBAL stex_u32* e = reduce + (axis * STEX_CS_REDUCE_BITS + j) * 4;
      *k += s * stex_join64(e[0], e[1]);
      *l += s * stex_join64(e[2], e[3]);
    }
  }
}

/* The noise at fixed-point position (x, y): `channels` values into out[0 .. channels). h, hist: the optional
 * histogram transfer (cs_hist.h; h.q == 0: none): the Gaussian values (PCA coordinates) go through
 * T_P(x)^-1, the inverse transfer of x's polyphase bin, and back to the colour basis. */
STEX_FN void stex_cs_spot_eval(const stex_cs_params p, const STEX_GLOBAL float* spot, const STEX_GLOBAL float* mean,
                               const STEX_GLOBAL float* gauss, const STEX_GLOBAL stex_u32* reduce,
                               const stex_cs_hist_params h, const STEX_GLOBAL float* hist, stex_i64 x, stex_i64 y,
                               float* out) {
  stex_i64 t0x = stex_join64(p.t0x_lo, p.t0x_hi), t0y = stex_join64(p.t0y_lo, p.t0y_hi);
  stex_i64 t1x = stex_join64(p.t1x_lo, p.t1x_hi), t1y = stex_join64(p.t1y_lo, p.t1y_hi);
  /* Base node: table nodes for the bits of the pixel coordinates, then one float solve of the residual. */
  stex_i64 k = 0, l = 0;
  stex_cs_reduce_axis(reduce, 0, x >> STEX_CS_FIX_BITS, &k, &l);
  stex_cs_reduce_axis(reduce, 1, y >> STEX_CS_FIX_BITS, &k, &l);
  stex_i64 rx = stex_cs_sub_node(x, k, t0x, l, t1x), ry = stex_cs_sub_node(y, k, t0y, l, t1y);
  float fa = (float)rx * p.i00 + (float)ry * p.i01, fb = (float)rx * p.i10 + (float)ry * p.i11;
  stex_i64 ka = (stex_i64)STEX_FLOORF(fa), lb = (stex_i64)STEX_FLOORF(fb);
  k += ka;
  l += lb;
  rx = stex_cs_sub_node(rx, ka, t0x, lb, t1x);
  ry = stex_cs_sub_node(ry, ka, t0y, lb, t1y);
  /* Phase of x in the base cell, for M (periodic: a value slightly outside [0, 1) is the same phase). */
  float u = (float)rx * p.i00 + (float)ry * p.i01, v = (float)rx * p.i10 + (float)ry * p.i11;
  float acc[STEX_CS_MAX_CHANNELS] = {0.0f, 0.0f, 0.0f, 0.0f};
  /* Displacements x - u outside (-1, size + 1) model pixels read only zeros. */
  float lim_x = (float)(p.spot_w + 1), lim_y = (float)(p.spot_h + 1);
  for (stex_i32 dl = p.dl0; dl <= p.dl1; ++dl) {
    for (stex_i32 dk = p.dk0; dk <= p.dk1; ++dk) {
      stex_i64 dxf = stex_cs_sub_node(rx, (stex_i64)dk, t0x, (stex_i64)dl, t1x);
      stex_i64 dyf = stex_cs_sub_node(ry, (stex_i64)dk, t0y, (stex_i64)dl, t1y);
      float dx = (float)dxf * p.inv_fix_scale, dy = (float)dyf * p.inv_fix_scale;
      if (!(dx > -1.0f && dy > -1.0f && dx < lim_x && dy < lim_y)) continue;
      stex_uvec4 key = stex_cell_key(k + dk, l + dl);
      stex_uvec4 r = stex_draw(key, p.seed_lo, p.seed_hi, 0u, STEX_DOMAIN_CS_WEIGHT);
      float w = stex_cs_gauss(gauss, r.x);
      for (stex_i32 c = 0; c < p.channels; ++c) acc[c] += w * stex_cs_spot_at(p, spot, dx, dy, c);
    }
  }
  for (stex_i32 c = 0; c < p.channels; ++c) out[c] = stex_cs_mean_at(p, mean, u, v, c) + p.amplitude * acc[c];
  if (h.q > 0) stex_cs_hist_apply(h, hist, stex_cs_hist_bin(h, u, v), out);
}

#endif /* STEX_CS_H */
