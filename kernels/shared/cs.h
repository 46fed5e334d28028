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
 * Canonical base (p.canon, set by the host when periods x scale <= 4096 output pixels and the window's
 * displacements fit 32 bits): the base node is the exact floor of x's lattice coordinates (stex_cs_canon_fix,
 * one int64 floor division), so it does not depend on how it was found. The kernel's fast path
 * (stex_cs_spot_run, kernels/cs_spot.cl) starts from its chunk's first pixel's canonical node (found on the
 * host as here), derives each pixel's in 32 bits (stex_cs_canon_near: a float solve and an exact -1/0/+1
 * correction, no division, no bit tables), reads the node weights from a per-chunk table computed once per
 * node, visits per row dl only the dk range that can reach the base cell, and shares each node's weight and
 * y taps between a run of pixels; the nodes it adds beyond the reference's non-zero ones add exactly 0. Kernel == reference bit for bit is the check that both exact
 * methods agree. Otherwise (canon == 0) kernel and reference both run stex_cs_spot_eval as before.
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
  stex_i32 canon;                          /* 1: canonical base nodes (|T| <= 2^28; the kernel's fast path) */
  stex_u32 det_lo, det_hi;                 /* det [T0 T1] in fixed units (int64, either sign), canon only */
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

/* Bilinear read of channel c of a cyclic grid (n0 columns, ch channels interleaved) between cells (i0, j0) and
 * (i1, j1) at fractions (fx, fy): the cyclic mean of cs-spot and of cs-tb. */
STEX_FN float stex_cs_grid_bilinear(const STEX_GLOBAL float* grid, stex_i32 n0, stex_i32 ch, stex_i32 i0, stex_i32 j0,
                                    stex_i32 i1, stex_i32 j1, float fx, float fy, stex_i32 c) {
  float v00 = grid[(j0 * n0 + i0) * ch + c], v10 = grid[(j0 * n0 + i1) * ch + c];
  float v01 = grid[(j1 * n0 + i0) * ch + c], v11 = grid[(j1 * n0 + i1) * ch + c];
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
  return stex_cs_grid_bilinear(mean, p.n0, p.channels, i0, j0, i1, j1, fx, fy, c);
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

/* The weight W_u of lattice node (k, l): N(0, 1), keyed by (seed, node). */
STEX_FN float stex_cs_weight(const stex_cs_params p, const STEX_GLOBAL float* gauss, stex_i64 k, stex_i64 l) {
  stex_uvec4 r = stex_draw(stex_cell_key(k, l), p.seed_lo, p.seed_hi, 0u, STEX_DOMAIN_CS_WEIGHT);
  return stex_cs_gauss(gauss, r.x);
}

/* Makes node (k, l) and residual (rx, ry) canonical: the exact floor of the lattice coordinates of the point,
 * from a node within a few cells of it (one int64 floor division per coordinate; |T| <= 2^28 fixed units and a
 * residual below 2^33 keep the products below 2^62). det: det [T0 T1], either sign. */
STEX_FN void stex_cs_canon_fix(stex_i64 t0x, stex_i64 t0y, stex_i64 t1x, stex_i64 t1y, stex_i64 det, stex_i64* k,
                               stex_i64* l, stex_i64* rx, stex_i64* ry) {
  stex_i64 na = t1y * *rx - t1x * *ry, nb = t0x * *ry - t0y * *rx;
  if (det < 0) {
    na = -na;
    nb = -nb;
    det = -det;
  }
  stex_i64 ea = stex_floordiv(na, det), eb = stex_floordiv(nb, det);
  *k += ea;
  *l += eb;
  *rx = stex_cs_sub_node(*rx, ea, t0x, eb, t1x);
  *ry = stex_cs_sub_node(*ry, ea, t0y, eb, t1y);
}

/* The canonical base of a point from its residual (ax, ay) relative to a canonical node nearby (the kernel's
 * chunk's first pixel: |ax|, |ay| < 2^30 fixed units), in 32-bit integers: one float solve (error below 0.1
 * cell: 2^30 fixed units are at most 2^14 / sin 5 deg cells of >= 1 pixel, relative error ~2^-22), then the
 * exact correction -1, 0 or +1 per coordinate from the signs of the int64 numerators (no division). (dk, dl):
 * the node offset, (rx, ry): the exact residual, the same as stex_cs_canon_fix's (and tb.h's stex_tb_canon's,
 * whatever its start). Shared by cs-spot's and tiling and blending's kernels (any lattice: the CS periods, the
 * triangle grid). */
STEX_FN void stex_cs_canon_near(stex_i32 t0x, stex_i32 t0y, stex_i32 t1x, stex_i32 t1y, stex_i64 det, float i00,
                                float i01, float i10, float i11, stex_i32 ax, stex_i32 ay, stex_i32* dk, stex_i32* dl,
                                stex_i32* rx, stex_i32* ry) {
  float fa = (float)ax * i00 + (float)ay * i01, fb = (float)ax * i10 + (float)ay * i11;
  stex_i32 ka = (stex_i32)STEX_FLOORF(fa), lb = (stex_i32)STEX_FLOORF(fb);
  /* Wrapping 32-bit arithmetic: the true residual is below 2^31 in magnitude. */
  stex_i32 x1 = (stex_i32)((stex_u32)ax - (stex_u32)ka * (stex_u32)t0x - (stex_u32)lb * (stex_u32)t1x);
  stex_i32 y1 = (stex_i32)((stex_u32)ay - (stex_u32)ka * (stex_u32)t0y - (stex_u32)lb * (stex_u32)t1y);
  stex_i64 na = (stex_i64)t1y * (stex_i64)x1 - (stex_i64)t1x * (stex_i64)y1;
  stex_i64 nb = (stex_i64)t0x * (stex_i64)y1 - (stex_i64)t0y * (stex_i64)x1;
  if (det < 0) {
    na = -na;
    nb = -nb;
    det = -det;
  }
  stex_i32 ea = (stex_i32)(na >= det) - (stex_i32)(na < 0), eb = (stex_i32)(nb >= det) - (stex_i32)(nb < 0);
  *dk = ka + ea;
  *dl = lb + eb;
  *rx = (stex_i32)((stex_u32)x1 - (stex_u32)ea * (stex_u32)t0x - (stex_u32)eb * (stex_u32)t1x);
  *ry = (stex_i32)((stex_u32)y1 - (stex_u32)ea * (stex_u32)t0y - (stex_u32)eb * (stex_u32)t1y);
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
  /* canon: the exact floor of the lattice coordinates (the kernel's fast path starts from the same node). */
  if (p.canon) stex_cs_canon_fix(t0x, t0y, t1x, t1y, stex_join64(p.det_lo, p.det_hi), &k, &l, &rx, &ry);
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
      float w = stex_cs_weight(p, gauss, k + dk, l + dl);
      for (stex_i32 c = 0; c < p.channels; ++c) acc[c] += w * stex_cs_spot_at(p, spot, dx, dy, c);
    }
  }
  for (stex_i32 c = 0; c < p.channels; ++c) out[c] = stex_cs_mean_at(p, mean, u, v, c) + p.amplitude * acc[c];
  if (h.q > 0) stex_cs_hist_apply(h, hist, stex_cs_hist_bin(h, u, v), out);
}

#define STEX_CS_RUN 8 /* the fast path's pixels per work-item (consecutive pixels of a row) */

/* The kernel's fast path (p.canon == 1): the noise of STEX_CS_RUN consecutive pixels of a row, equal bit for
 * bit to stex_cs_spot_eval at each of them. (ax, ay): the first pixel's residual from the chunk's canonical
 * node (32-bit, |.| < 2^30); out: STEX_CS_RUN x ch values, interleaved.
 *  - Each pixel's canonical node offset and residual (stex_cs_canon_near) give its phase (M, histogram bin)
 *    and its node range: for each row dl of [dl0, dl1] the dk range rows[2 (dl - dl0)] .. rows[2 (dl - dl0) + 1]
 *    (from the host: the nodes whose spot can add a non-zero term at a point of the base cell).
 *  - The run visits, row by row (L ascending) and node by node (K ascending), the union of its pixels' ranges
 *    (node offsets from the chunk's node); a node's weight is weights[(L - wl0) nk + K - wk0] (the chunk's
 *    window of stex_cs_weight, nk x nl), read once for the run; its y displacement, shared by the run, is
 *    tested first (a node outside adds only zeros).
 *  - x - u is the exact 32-bit integer (first pixel's residual - K T0 - L T1 + q 2^16, wrapping: the values
 *    used are small, the host checked their bound); a tap of a node whose displacement is inside (-1, size + 1)
 *    reads the padded spot spot_pad (2 zero texels on every side, (spot_w + 4) x (spot_h + 4) x ch) without
 *    bounds checks (floor(d - 0.5) >= -2), other nodes' terms are replaced by 0.
 * A pixel's non-zero terms are then those of stex_cs_spot_eval, in the same (dl, dk) order, with the same
 * arithmetic; the extra nodes add exact zeros, which leave a sum unchanged (acc is never -0). ch: the channels
 * (a compile-time constant in the kernel). */
STEX_FN void stex_cs_spot_run(const stex_cs_params p, const STEX_GLOBAL float* spot_pad, const STEX_GLOBAL float* mean,
                              const STEX_GLOBAL float* weights, const STEX_GLOBAL stex_i32* rows, stex_i32 nk,
                              stex_i32 nl, stex_i32 wk0, stex_i32 wl0, const stex_cs_hist_params h,
                              const STEX_GLOBAL float* hist, stex_i32 ch, stex_i32 ax, stex_i32 ay, float* out) {
  stex_u32 t0x = p.t0x_lo, t0y = p.t0y_lo, t1x = p.t1x_lo, t1y = p.t1y_lo; /* |T| < 2^28: the low words */
  stex_i64 det = stex_join64(p.det_lo, p.det_hi);
  stex_i32 dkq[STEX_CS_RUN], dlq[STEX_CS_RUN], rxq[STEX_CS_RUN], ryq[STEX_CS_RUN];
  stex_i32 lmin = 0x7fffffff, lmax = -0x7fffffff;
  for (stex_i32 q = 0; q < STEX_CS_RUN; ++q) {
    stex_cs_canon_near((stex_i32)t0x, (stex_i32)t0y, (stex_i32)t1x, (stex_i32)t1y, det, p.i00, p.i01, p.i10, p.i11,
                       ax + q * 65536, ay, &dkq[q], &dlq[q], &rxq[q], &ryq[q]);
    lmin = dlq[q] < lmin ? dlq[q] : lmin;
    lmax = dlq[q] > lmax ? dlq[q] : lmax;
  }
  lmin += p.dl0;
  lmax += p.dl1;
  /* Memory guard only: the host's window holds every node of the chunk's runs. */
  lmin = lmin < wl0 ? wl0 : lmin;
  lmax = lmax > wl0 + nl - 1 ? wl0 + nl - 1 : lmax;
  float acc[STEX_CS_RUN * STEX_CS_MAX_CHANNELS];
  for (stex_i32 q = 0; q < STEX_CS_RUN * STEX_CS_MAX_CHANNELS; ++q) acc[q] = 0.0f;
  float lim_x = (float)(p.spot_w + 1), lim_y = (float)(p.spot_h + 1);
  stex_i32 pw = p.spot_w + 4, imax = p.spot_w, jmax = p.spot_h;
  float inv = p.inv_fix_scale;
  for (stex_i32 L = lmin; L <= lmax; ++L) {
    /* The union of the run's pixels' dk ranges in row L. */
    stex_i32 kmin = 0x7fffffff, kmax = -0x7fffffff;
    for (stex_i32 q = 0; q < STEX_CS_RUN; ++q) {
      stex_i32 r = L - dlq[q];
      if (r >= p.dl0 && r <= p.dl1) {
        stex_i32 lo = rows[2 * (r - p.dl0)], hi = rows[2 * (r - p.dl0) + 1];
        if (lo <= hi) {
          kmin = dkq[q] + lo < kmin ? dkq[q] + lo : kmin;
          kmax = dkq[q] + hi > kmax ? dkq[q] + hi : kmax;
        }
      }
    }
    kmin = kmin < wk0 ? wk0 : kmin;
    kmax = kmax > wk0 + nk - 1 ? wk0 + nk - 1 : kmax;
    if (kmin > kmax) continue;
    stex_i32 wbase = (L - wl0) * nk - wk0; /* weights[wbase + K]: node (K, L) */
    stex_u32 ex = (stex_u32)ax - (stex_u32)L * t1x - (stex_u32)kmin * t0x;
    stex_u32 ey = (stex_u32)ay - (stex_u32)L * t1y - (stex_u32)kmin * t0y;
    for (stex_i32 K = kmin; K <= kmax; ++K, ex -= t0x, ey -= t0y) {
      float dy = (float)(stex_i32)ey * inv;
      if (!(dy > -1.0f && dy < lim_y)) continue; /* only zero terms for the whole run */
      float sy = dy - 0.5f;
      float fy0 = STEX_FLOORF(sy);
      float fy = sy - fy0;
      stex_i32 j0 = (stex_i32)fy0;
      j0 = j0 < -2 ? -2 : (j0 > jmax ? jmax : j0); /* no-op for dy inside */
      const STEX_GLOBAL float* srow = spot_pad + (j0 + 2) * pw * ch;
      float w = weights[wbase + K];
      for (stex_i32 q = 0; q < STEX_CS_RUN; ++q) {
        float dx = (float)(stex_i32)(ex + (stex_u32)q * 65536u) * inv;
        stex_i32 inside = dx > -1.0f && dx < lim_x;
        float sx = dx - 0.5f;
        float fx0 = STEX_FLOORF(sx);
        float fx = sx - fx0;
        stex_i32 i0 = (stex_i32)fx0;
        i0 = i0 < -2 ? -2 : (i0 > imax ? imax : i0); /* memory only: inside keeps i0 in [-2, imax] */
        stex_i32 o = (i0 + 2) * ch;
        for (stex_i32 c = 0; c < ch; ++c) {
          float v00 = srow[o + c], v10 = srow[o + ch + c];
          float v01 = srow[o + pw * ch + c], v11 = srow[o + (pw + 1) * ch + c];
          float s0 = v00 + fx * (v10 - v00);
          float s1 = v01 + fx * (v11 - v01);
          float sv = s0 + fy * (s1 - s0);
          acc[q * ch + c] += inside ? w * sv : 0.0f;
        }
      }
    }
  }
  for (stex_i32 q = 0; q < STEX_CS_RUN; ++q) {
    float u = (float)rxq[q] * p.i00 + (float)ryq[q] * p.i01, v = (float)rxq[q] * p.i10 + (float)ryq[q] * p.i11;
    for (stex_i32 c = 0; c < ch; ++c) out[q * ch + c] = stex_cs_mean_at(p, mean, u, v, c) + p.amplitude * acc[q * ch + c];
    if (h.q > 0) stex_cs_hist_apply(h, hist, stex_cs_hist_bin(h, u, v), out + q * ch);
  }
}

#endif /* STEX_CS_H */
