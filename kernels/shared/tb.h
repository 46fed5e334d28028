/* Tiling and blending (Heitz & Neyret, "High-performance by-example noise using a histogram-preserving
 * blending operator", HPG 2018; Deliot & Heitz, GPU Zen 2) and its cyclostationary variant (S4 §5.2), shared by
 * the OpenCL kernel (kernels/tb.cl) and the C++ reference (runtime/tb.h). Kinds "tb" and "cs-tb".
 *
 * The output plane is covered by a triangle grid of side L (basis e0 = (L, 0), e1 = (L/2, L sqrt(3)/2)); each
 * grid vertex v carries a hexagonal tile of the (Gaussianised, PCA-decorrelated) exemplar G read at an
 * offset of its own, and a point x in triangle (v1, v2, v3) with barycentric weights w_i blends 3 fetches:
 *
 *   g(x) = m(x) + sum_i w_i (G(f_i(x)) - m(x)) / sqrt(sum_i w_i^2)        (variance-preserving blend)
 *   out  = PCA^-1 (T^-1(g))                                             (per-channel inverse LUT, colour basis)
 *          (cs-tb with a histogram table: T_P(x)^-1 of x's polyphase bin instead of the LUT, cs_hist.h)
 *
 *  - tb:    f_i(x) = (x - v_i) + o_i, o_i in a box that keeps the hexagon inside the exemplar (its integer
 *           part uniform, its 2^-16 fraction v_i's own: fetches are texel-aligned at scale 1, stex_tb_local);
 *           m = the mean of G (0.5: T maps every channel to N(0.5, 1/6^2)).
 *  - cs-tb: f_i(x) = x - U_i with U_i a random node of the exemplar's lattice (t0, t1) such that v_i - U_i lies
 *           in that box: the fetch is congruent to x, P(f_i(x)) = P(x) (S4 §5.2), so the three fetches belong
 *           to x's polyphase component; m(x) = M_G(P(x)), the cyclic mean of G, which the blend preserves.
 *
 * Exactness on the unbounded plane: the triangle-grid vertices and the CS-lattice nodes are int64 fixed point
 * (2^-16 output pixel). Each pixel's base node is *canonical* (the exact floor of its lattice coordinates,
 * stex_tb_canon) whatever start node it is given: the kernel gets its chunk's (found on the host with the bit
 * tables of cs.h), the reference each pixel's own; only small displacements become floats. Kernel and
 * reference agree bit for bit, for any chunking.
 */
#ifndef STEX_TB_H
#define STEX_TB_H
#include "cs.h"
#include "cs_hist.h"
#include "rng.h"
#include "stex_platform.h"

#define STEX_TB_MAX_CHANNELS 4
#define STEX_DOMAIN_TB_VERTEX 0x54427678u /* "TBvx": the offset of a grid vertex */
#define STEX_TB_TRIES 8                   /* cs-tb: random draws of a node before the deterministic scan */

/* 216 bytes; static_assert on the host. */
typedef struct {
  stex_u32 seed_lo, seed_hi;
  stex_u32 g0x_lo, g0x_hi, g0y_lo, g0y_hi, g1x_lo, g1x_hi, g1y_lo, g1y_hi; /* triangle grid basis, fixed units */
  float gi00, gi01, gi10, gi11;                                           /* its inverse per fixed unit */
  stex_u32 t0x_lo, t0x_hi, t0y_lo, t0y_hi, t1x_lo, t1x_hi, t1y_lo, t1y_hi; /* cs-tb: the lattice, fixed units */
  float ti00, ti01, ti10, ti11;                                           /* its inverse per fixed unit */
  float inv_fix_scale;                                                    /* fixed output units -> model pixels */
  float box_x0, box_y0, box_x1, box_y1;  /* allowed tile centres in the exemplar (model pixels) */
  stex_i32 dk0, dk1, dl0, dl1;            /* cs-tb: node window around a vertex's base node */
  stex_i32 ex_w, ex_h, channels, lut_size;
  stex_i32 cs, n0, n1;                    /* cs: 1 for cs-tb; n0 x n1: the cyclic-mean grid of G */
  float lut_lo, lut_hi;                   /* the LUT covers g in [lut_lo, lut_hi] */
  stex_u32 gdet_lo, gdet_hi, tdet_lo, tdet_hi; /* det of each basis (int64, either sign) */
  stex_i32 unit_scale;                    /* 1 when scale == 1 exactly: output fixed units are model fixed units */
  float inv_scale;                        /* 1 / scale (cs-tb: a tile centre to model fixed units) */
  stex_i32 bfx0, bfy0, bfx1, bfy1;        /* tb: the box of tile centres in model fixed units, inclusive */
} stex_tb_params;

/* Tile centres are model fixed-point integers (2^-16 model pixel; STEX_CS_FIX_BITS = 16), one per axis:
 * c = 65536 ci + cf, ci the integer part, cf the fraction. A fetch of vertex v at output point x reads G at
 * model point (x - v) / scale + c; its bilinear coordinate (minus the texel-centre offset 1/2) is
 * ci + t, t = (x - v) / scale + (cf - 32768) / 65536, computed from d = x - v (output fixed units, exact and
 * small). At scale 1 t is computed from the exact integer d + cf - 32768, and every centre is *aligned*
 * (cf = v mod 65536: stex_tb_vertex_centre for tb, and for cs-tb with integer periods): t is then an integer,
 * the bilinear fractions are exactly 0 and a fetch reads one texel (the kernels' aligned paths use this;
 * the reference keeps the bilinear formula, whose zero fractions give the same bits). */
/* The kernels get p.unit_scale as the compile-time constant STEX_TB_UNIT too (the host sets both from the
 * same scale), so that the choice costs nothing per fetch; the C++ reference reads the field. */
#ifdef STEX_TB_UNIT
#define STEX_TB_UNIT_SCALE(p) STEX_TB_UNIT
#else
#define STEX_TB_UNIT_SCALE(p) ((p).unit_scale)
#endif
STEX_FN float stex_tb_local(const stex_tb_params p, stex_i32 d, stex_i32 c) {
  stex_i32 cf = (c & 0xffff) - 32768;
  return STEX_TB_UNIT_SCALE(p) ? (float)(d + cf) * (1.0f / 65536.0f)
                      : (float)d * p.inv_fix_scale + (float)cf * (1.0f / 65536.0f);
}

/* Bilinear read of G (texel centres at i + 0.5), channel c, for tile displacement (dx, dy) = x - v (output
 * fixed units) and model fixed tile centre (cx, cy). The box of centres keeps every fetch of a valid model
 * inside the texel-centre hull; the clamp only guards memory. */
STEX_FN float stex_tb_fetch(const stex_tb_params p, const STEX_GLOBAL float* g, stex_i32 dx, stex_i32 dy, stex_i32 cx,
                            stex_i32 cy, stex_i32 c) {
  float tx = stex_tb_local(p, dx, cx), ty = stex_tb_local(p, dy, cy);
  float fx0 = STEX_FLOORF(tx), fy0 = STEX_FLOORF(ty);
  float fx = tx - fx0, fy = ty - fy0;
  stex_i32 i0 = (cx >> 16) + (stex_i32)fx0, j0 = (cy >> 16) + (stex_i32)fy0;
  i0 = i0 < 0 ? 0 : (i0 > p.ex_w - 2 ? p.ex_w - 2 : i0);
  j0 = j0 < 0 ? 0 : (j0 > p.ex_h - 2 ? p.ex_h - 2 : j0);
  stex_i32 ch = p.channels;
  float v00 = g[(j0 * p.ex_w + i0) * ch + c], v10 = g[(j0 * p.ex_w + i0 + 1) * ch + c];
  float v01 = g[((j0 + 1) * p.ex_w + i0) * ch + c], v11 = g[((j0 + 1) * p.ex_w + i0 + 1) * ch + c];
  float a = v00 + fx * (v10 - v00);
  float b = v01 + fx * (v11 - v01);
  return a + fy * (b - a);
}

/* Inverse LUT of channel c at Gaussian value v (linear interpolation, clamped to the table). */
STEX_FN float stex_tb_lut(const stex_tb_params p, const STEX_GLOBAL float* lut, float v, stex_i32 c) {
  float t = (v - p.lut_lo) * ((float)(p.lut_size - 1) / (p.lut_hi - p.lut_lo));
  float mx = (float)(p.lut_size - 1);
  t = t < 0.0f ? 0.0f : (t > mx ? mx : t);
  float f0 = STEX_FLOORF(t);
  stex_i32 i = (stex_i32)f0;
  if (i > p.lut_size - 2) i = p.lut_size - 2;
  float f = t - (float)i;
  float a = lut[c * p.lut_size + i], b = lut[c * p.lut_size + i + 1];
  return a + f * (b - a);
}

/* Base node and exact residual of fixed position (x, y) in a lattice (basis b0, b1; inverse i..; table). */
STEX_FN void stex_tb_base(const STEX_GLOBAL stex_u32* reduce, stex_i64 b0x, stex_i64 b0y, stex_i64 b1x, stex_i64 b1y,
                          float i00, float i01, float i10, float i11, stex_i64 x, stex_i64 y, stex_i64* k, stex_i64* l,
                          stex_i64* rx, stex_i64* ry) {
  *k = 0;
  *l = 0;
  stex_cs_reduce_axis(reduce, 0, x >> STEX_CS_FIX_BITS, k, l);
  stex_cs_reduce_axis(reduce, 1, y >> STEX_CS_FIX_BITS, k, l);
  stex_i64 ax = stex_cs_sub_node(x, *k, b0x, *l, b1x), ay = stex_cs_sub_node(y, *k, b0y, *l, b1y);
  float fa = (float)ax * i00 + (float)ay * i01, fb = (float)ax * i10 + (float)ay * i11;
  stex_i64 ka = (stex_i64)STEX_FLOORF(fa), lb = (stex_i64)STEX_FLOORF(fb);
  *k += ka;
  *l += lb;
  *rx = stex_cs_sub_node(ax, ka, b0x, lb, b1x);
  *ry = stex_cs_sub_node(ay, ka, b0y, lb, b1y);
}

/* The canonical base node of (x, y) in a lattice: floor of its exact lattice coordinates, from any start
 * node (k0, l0) near it (a chunk's base node: within ~2^12 pixels). A float solve brings the residual within
 * a cell or two, then one exact int64 floor division per coordinate (|T| <= 2^28 fixed units keeps the
 * products below 2^60) gives the same (k, l) and residual whatever the start: renders do not depend on
 * the chunking. */
STEX_FN void stex_tb_canon(stex_i64 b0x, stex_i64 b0y, stex_i64 b1x, stex_i64 b1y, stex_i64 det, float i00, float i01,
                           float i10, float i11, stex_i64 x, stex_i64 y, stex_i64 k0, stex_i64 l0, stex_i64* k,
                           stex_i64* l, stex_i64* rx, stex_i64* ry) {
  stex_i64 ax = stex_cs_sub_node(x, k0, b0x, l0, b1x), ay = stex_cs_sub_node(y, k0, b0y, l0, b1y);
  float fa = (float)ax * i00 + (float)ay * i01, fb = (float)ax * i10 + (float)ay * i11;
  stex_i64 ka = (stex_i64)STEX_FLOORF(fa), lb = (stex_i64)STEX_FLOORF(fb);
  ax = stex_cs_sub_node(ax, ka, b0x, lb, b1x);
  ay = stex_cs_sub_node(ay, ka, b0y, lb, b1y);
  stex_i64 na = b1y * ax - b1x * ay, nb = b0x * ay - b0y * ax;
  if (det < 0) {
    na = -na;
    nb = -nb;
    det = -det;
  }
  stex_i64 ea = stex_floordiv(na, det), eb = stex_floordiv(nb, det);
  *k = k0 + ka + ea;
  *l = l0 + lb + eb;
  *rx = stex_cs_sub_node(ax, ea, b0x, eb, b1x);
  *ry = stex_cs_sub_node(ay, ea, b0y, eb, b1y);
}

/* tb: a centre coordinate with fraction cf = v mod 65536 (aligned, see stex_tb_local) and integer part
 * uniform (draw u) among those keeping the centre in [lo, hi] (model fixed units; the box is at least 2
 * pixels wide, so there is at least one). */
STEX_FN stex_i32 stex_tb_pick(stex_i64 v, stex_i32 lo, stex_i32 hi, stex_u32 u) {
  stex_i32 cf = (stex_i32)((stex_u64)v & 0xffffu);
  stex_i32 nmin = (lo - cf + 65535) >> 16, nmax = (hi - cf) >> 16; /* lo, hi > 65536 > cf */
  stex_u32 range = (stex_u32)(nmax - nmin + 1);
  stex_i32 n = nmin + (stex_i32)(((stex_u64)u * (stex_u64)range) >> 32);
  return cf + n * 65536;
}

/* cs-tb: a centre v - U (output fixed units, exact) in model fixed units: itself at scale 1 (aligned when
 * the periods are integers: U's coordinates are then multiples of 65536), else rounded from ex / scale. */
STEX_FN stex_i32 stex_tb_cs_fix(const stex_tb_params p, stex_i64 e) {
  return STEX_TB_UNIT_SCALE(p) ? (stex_i32)e : (stex_i32)STEX_FLOORF((float)e * p.inv_scale + 0.5f);
}

/* The grid vertex (kv, lv) in fixed output units (modulo 2^64, exact on the plane). */
STEX_FN void stex_tb_vertex_fix(const stex_tb_params p, stex_i64 kv, stex_i64 lv, stex_i64* vx, stex_i64* vy) {
  stex_i64 g0x = stex_join64(p.g0x_lo, p.g0x_hi), g0y = stex_join64(p.g0y_lo, p.g0y_hi);
  stex_i64 g1x = stex_join64(p.g1x_lo, p.g1x_hi), g1y = stex_join64(p.g1y_lo, p.g1y_hi);
  *vx = (stex_i64)((stex_u64)kv * (stex_u64)g0x + (stex_u64)lv * (stex_u64)g1x);
  *vy = (stex_i64)((stex_u64)kv * (stex_u64)g0y + (stex_u64)lv * (stex_u64)g1y);
}

/* Whether node offset (a, b) puts v - U = nr - (a t0 + b t1) inside the box (model pixels); if so, (*ex, *ey)
 * receive it (fixed units). */
STEX_FN stex_i32 stex_tb_node_in_box(const stex_tb_params p, stex_i64 nrx, stex_i64 nry, stex_i64 t0x, stex_i64 t0y,
                                     stex_i64 t1x, stex_i64 t1y, stex_i32 a, stex_i32 b, stex_i64* ex, stex_i64* ey) {
  stex_i64 x = stex_cs_sub_node(nrx, (stex_i64)a, t0x, (stex_i64)b, t1x);
  stex_i64 y = stex_cs_sub_node(nry, (stex_i64)a, t0y, (stex_i64)b, t1y);
  float fx = (float)x * p.inv_fix_scale, fy = (float)y * p.inv_fix_scale;
  if (!(fx >= p.box_x0 && fx <= p.box_x1 && fy >= p.box_y0 && fy <= p.box_y1)) return 0;
  *ex = x;
  *ey = y;
  return 1;
}

/* The tile centre (cx, cy) of grid vertex (kv, lv) in the exemplar, model fixed units (stex_tb_local).
 * (kc0, lc0): cs-tb, any CS-lattice start node near the vertex. */
STEX_FN void stex_tb_vertex_centre(const stex_tb_params p, stex_i64 kv, stex_i64 lv, stex_i64 kc0, stex_i64 lc0,
                                   stex_i32* cx, stex_i32* cy) {
  stex_uvec4 key = stex_cell_key(kv, lv);
  stex_i64 vx, vy;
  stex_tb_vertex_fix(p, kv, lv, &vx, &vy);
  if (!p.cs) {
    stex_uvec4 r = stex_draw(key, p.seed_lo, p.seed_hi, 0u, STEX_DOMAIN_TB_VERTEX);
    *cx = stex_tb_pick(vx, p.bfx0, p.bfx1, r.x);
    *cy = stex_tb_pick(vy, p.bfy0, p.bfy1, r.y);
    return;
  }
  stex_i64 t0x = stex_join64(p.t0x_lo, p.t0x_hi), t0y = stex_join64(p.t0y_lo, p.t0y_hi);
  stex_i64 t1x = stex_join64(p.t1x_lo, p.t1x_hi), t1y = stex_join64(p.t1y_lo, p.t1y_hi);
  stex_i64 tdet = stex_join64(p.tdet_lo, p.tdet_hi);
  /* The vertex's canonical residual in the lattice. */
  stex_i64 nk, nl, nrx, nry;
  stex_tb_canon(t0x, t0y, t1x, t1y, tdet, p.ti00, p.ti01, p.ti10, p.ti11, vx, vy, kc0, lc0, &nk, &nl, &nrx, &nry);
  /* A node offset (a, b) with v - U = nr - (a t0 + b t1) inside the box (model pixels). */
  stex_i32 wk = p.dk1 - p.dk0 + 1, wl = p.dl1 - p.dl0 + 1;
  stex_i32 found = 0;
  stex_i64 fex = 0, fey = 0;
  for (stex_u32 t = 0; t < STEX_TB_TRIES && !found; ++t) {
    stex_uvec4 r = stex_draw(key, p.seed_lo, p.seed_hi, t, STEX_DOMAIN_TB_VERTEX);
    stex_i32 a = p.dk0 + (stex_i32)(r.x % (stex_u32)wk), b = p.dl0 + (stex_i32)(r.y % (stex_u32)wl);
    found = stex_tb_node_in_box(p, nrx, nry, t0x, t0y, t1x, t1y, a, b, &fex, &fey);
  }
  for (stex_i32 b = p.dl0; b <= p.dl1 && !found; ++b)
    for (stex_i32 a = p.dk0; a <= p.dk1 && !found; ++a) found = stex_tb_node_in_box(p, nrx, nry, t0x, t0y, t1x, t1y, a, b, &fex, &fey);
  /* The host guarantees the box holds a whole cell, so a node is always found. */
  *cx = stex_tb_cs_fix(p, fex);
  *cy = stex_tb_cs_fix(p, fey);
}

/* The texel offset of an aligned vertex (kv, lv) with centre (cx, cy) for a chunk whose first pixel is
 * (x0, y0) (ex_w texels a row): at scale 1 its fetch for chunk pixel (i, j) reads texel base + j ex_w + i
 * (exactly the texel stex_tb_fetch reads with zero fractions: ci + t = x0 + i + ci - floor(v / 65536)). */
STEX_FN stex_i32 stex_tb_texel_base(const stex_tb_params p, stex_i64 kv, stex_i64 lv, stex_i32 cx, stex_i32 cy,
                                    stex_i64 x0, stex_i64 y0) {
  stex_i64 vx, vy;
  stex_tb_vertex_fix(p, kv, lv, &vx, &vy);
  stex_i32 ox = (stex_i32)(x0 + (stex_i64)(cx >> 16) - (vx >> 16));
  stex_i32 oy = (stex_i32)(y0 + (stex_i64)(cy >> 16) - (vy >> 16));
  return oy * p.ex_w + ox;
}

/* The triangle of canonical grid residual (rx, ry) and its barycentric weights in *canonical vertex order*:
 * by grid row (the base node's row l, then l + 1), then column. upper = 0: the triangle (0,0), (1,0), (0,1)
 * of the base node, weights wa, wb, wc in that order; upper = 1: (1,0), (0,1), (1,1). Slot vertices relative
 * to the base node: a = (upper, 0), b = (1 - upper, upper), c = (upper, 1). The blend sums in this order;
 * the run kernel (kernels/tb.cl, tb_run) sums every vertex of a strip in the same order with hat weights that
 * are exactly 0 off a pixel's triangle, so both add the same nonzero terms in the same order. */
STEX_FN stex_i32 stex_tb_triangle(const stex_tb_params p, stex_i32 rx, stex_i32 ry, float* wa, float* wb, float* wc) {
  float fa = (float)rx * p.gi00 + (float)ry * p.gi01, fb = (float)rx * p.gi10 + (float)ry * p.gi11;
  stex_i32 upper = fa + fb < 1.0f ? 0 : 1;
  float a = upper ? 1.0f - fb : 1.0f - fa - fb;
  float b = upper ? 1.0f - fa : fa;
  float c = upper ? fa + fb - 1.0f : fb;
  *wa = a < 0.0f ? 0.0f : a;
  *wb = b < 0.0f ? 0.0f : b;
  *wc = c < 0.0f ? 0.0f : c;
  return upper;
}

/* Cyclic mean M_G at the phase of canonical CS residual (cx, cy), channel c (u, v in [0, 1) up to rounding:
 * the grid index is wrapped once). */
STEX_FN float stex_tb_mean(const stex_tb_params p, const STEX_GLOBAL float* mean, stex_i32 cx, stex_i32 cy, stex_i32 c) {
  float u = (float)cx * p.ti00 + (float)cy * p.ti01, v = (float)cx * p.ti10 + (float)cy * p.ti11;
  float gx = u * (float)p.n0, gy = v * (float)p.n1;
  float gx0 = STEX_FLOORF(gx), gy0 = STEX_FLOORF(gy);
  float fx = gx - gx0, fy = gy - gy0;
  stex_i32 i0 = (stex_i32)gx0, j0 = (stex_i32)gy0;
  i0 = i0 < 0 ? i0 + p.n0 : (i0 >= p.n0 ? i0 - p.n0 : i0);
  j0 = j0 < 0 ? j0 + p.n1 : (j0 >= p.n1 ? j0 - p.n1 : j0);
  stex_i32 i1 = i0 + 1 == p.n0 ? 0 : i0 + 1, j1 = j0 + 1 == p.n1 ? 0 : j0 + 1;
  return stex_cs_grid_bilinear(mean, p.n0, p.channels, i0, j0, i1, j1, fx, fy, c);
}

/* The output colour of blended Gaussian values gv[0 .. ch): T^-1 per PCA channel (the LUT step or the CS
 * histogram transfer), then the
 * inverse PCA (out = mean + B^T T^-1(gv); pca: ch means, then ch x ch rows of B). */
STEX_FN void stex_tb_finish(const stex_tb_params p, const STEX_GLOBAL float* lut, const STEX_GLOBAL float* pca,
                            const stex_cs_hist_params h, const STEX_GLOBAL float* hist, stex_i32 cx, stex_i32 cy,
                            stex_i32 ch, float* gv, float* out) {
  /* T^-1: the stationary LUT, or (h.q > 0, cs-tb) T_P(x)^-1 of the polyphase bin of x's phase (u, v) in the CS
   * lattice, from its canonical residual (cx, cy) (cs_hist.h, S4 5.3.2). */
  if (h.q > 0) {
    float u = (float)cx * p.ti00 + (float)cy * p.ti01, v = (float)cx * p.ti10 + (float)cy * p.ti11;
    stex_i32 bin = stex_cs_hist_bin(h, u, v);
    for (stex_i32 c = 0; c < ch; ++c) gv[c] = stex_cs_hist_inv(h, hist, bin, c, gv[c]);
  } else {
    for (stex_i32 c = 0; c < ch; ++c) gv[c] = stex_tb_lut(p, lut, gv[c], c);
  }
  for (stex_i32 c = 0; c < ch; ++c) {
    float s = pca[c];
    for (stex_i32 d = 0; d < ch; ++d) s += pca[ch + d * ch + c] * gv[d];
    out[c] = s;
  }
}

/* The blended Gaussian values gv[0 .. ch) of a pixel: canonical weights wa..wc (stex_tb_triangle) and its
 * 3 fetches' values ga, gb, gc (per channel), m the mean (0.5, or for cs-tb the cyclic mean at canonical CS
 * residual (cx, cy)): g = m + sum_s w_s (G_s - m) / sqrt(sum_s w_s^2), both sums in slot order from 0. */
STEX_FN void stex_tb_mix(const stex_tb_params p, const STEX_GLOBAL float* mean, stex_i32 ch, stex_i32 cs, float wa,
                         float wb, float wc, const float* ga, const float* gb, const float* gc, stex_i32 cx, stex_i32 cy,
                         float* gv) {
  float ss = wa * wa;
  ss += wb * wb;
  ss += wc * wc;
  float norm = 1.0f / STEX_SQRTF(ss);
  for (stex_i32 c = 0; c < ch; ++c) {
    float m = cs ? stex_tb_mean(p, mean, cx, cy, c) : 0.5f;
    float acc = 0.0f;
    acc += wa * (ga[c] - m);
    acc += wb * (gb[c] - m);
    acc += wc * (gc[c] - m);
    gv[c] = m + acc * norm;
  }
}

/* x - v (output fixed units) of slot vertex (ok, ol) of the base node, from the canonical residual (rx, ry). */
STEX_FN void stex_tb_disp(const stex_tb_params p, stex_i32 rx, stex_i32 ry, stex_i32 ok, stex_i32 ol, stex_i32* dx,
                          stex_i32* dy) {
  stex_i32 g0x = (stex_i32)p.g0x_lo, g1x = (stex_i32)p.g1x_lo, g1y = (stex_i32)p.g1y_lo; /* g0y = 0 */
  *dx = rx - ok * g0x - ol * g1x;
  *dy = ry - ol * g1y;
}

/* The noise of a pixel (general path: any scale, bilinear fetches): canonical grid residual (rx, ry),
 * triangle `upper` and canonical weights (stex_tb_triangle), model fixed tile centres (cax, cay) .. (ccx, ccy)
 * of its slot vertices a, b, c (stex_tb_vertex_centre) and, for cs-tb, canonical CS residual (cx, cy): `ch`
 * (= p.channels) values into out; cs = p.cs (both may be compile-time constants in the kernel). */
STEX_FN void stex_tb_blend(const stex_tb_params p, const STEX_GLOBAL float* g, const STEX_GLOBAL float* lut,
                           const STEX_GLOBAL float* pca, const STEX_GLOBAL float* mean, const stex_cs_hist_params h,
                           const STEX_GLOBAL float* hist, stex_i32 ch, stex_i32 cs, stex_i32 rx, stex_i32 ry,
                           stex_i32 upper, float wa, float wb, float wc, stex_i32 cax, stex_i32 cay, stex_i32 cbx,
                           stex_i32 cby, stex_i32 ccx, stex_i32 ccy, stex_i32 cx, stex_i32 cy, float* out) {
  stex_i32 dax, day, dbx, dby, dcx, dcy;
  stex_tb_disp(p, rx, ry, upper, 0, &dax, &day);
  stex_tb_disp(p, rx, ry, 1 - upper, upper, &dbx, &dby);
  stex_tb_disp(p, rx, ry, upper, 1, &dcx, &dcy);
  float ga[STEX_TB_MAX_CHANNELS], gb[STEX_TB_MAX_CHANNELS], gc[STEX_TB_MAX_CHANNELS], gv[STEX_TB_MAX_CHANNELS];
  for (stex_i32 c = 0; c < ch; ++c) {
    ga[c] = stex_tb_fetch(p, g, dax, day, cax, cay, c);
    gb[c] = stex_tb_fetch(p, g, dbx, dby, cbx, cby, c);
    gc[c] = stex_tb_fetch(p, g, dcx, dcy, ccx, ccy, c);
  }
  stex_tb_mix(p, mean, ch, cs, wa, wb, wc, ga, gb, gc, cx, cy, gv);
  stex_tb_finish(p, lut, pca, h, hist, cx, cy, ch, gv, out);
}

/* The noise at fixed position (x, y) (the C++ reference's per-pixel path): `channels` values into out.
 * (kg0, lg0), (kc0, lc0): start nodes near (x, y) in the triangle grid and the CS lattice (stex_tb_base with
 * the bit tables of cs.h gives them for any point); mean: the cyclic mean of G (cs-tb) on n0 x n1. */
STEX_FN void stex_tb_eval(const stex_tb_params p, const STEX_GLOBAL float* g, const STEX_GLOBAL float* lut,
                          const STEX_GLOBAL float* pca, const STEX_GLOBAL float* mean, const stex_cs_hist_params h,
                          const STEX_GLOBAL float* hist, stex_i64 x, stex_i64 y, stex_i64 kg0, stex_i64 lg0,
                          stex_i64 kc0, stex_i64 lc0, float* out) {
  stex_i64 gdet = stex_join64(p.gdet_lo, p.gdet_hi), tdet = stex_join64(p.tdet_lo, p.tdet_hi);
  stex_i64 g0x = stex_join64(p.g0x_lo, p.g0x_hi), g0y = stex_join64(p.g0y_lo, p.g0y_hi);
  stex_i64 g1x = stex_join64(p.g1x_lo, p.g1x_hi), g1y = stex_join64(p.g1y_lo, p.g1y_hi);
  stex_i64 k, l, rx, ry;
  stex_tb_canon(g0x, g0y, g1x, g1y, gdet, p.gi00, p.gi01, p.gi10, p.gi11, x, y, kg0, lg0, &k, &l, &rx, &ry);
  float wa, wb, wc;
  stex_i32 upper = stex_tb_triangle(p, (stex_i32)rx, (stex_i32)ry, &wa, &wb, &wc);
  stex_i64 ck = kc0, cl = lc0, cx = 0, cy = 0;
  if (p.cs) {
    stex_i64 t0x = stex_join64(p.t0x_lo, p.t0x_hi), t0y = stex_join64(p.t0y_lo, p.t0y_hi);
    stex_i64 t1x = stex_join64(p.t1x_lo, p.t1x_hi), t1y = stex_join64(p.t1y_lo, p.t1y_hi);
    stex_tb_canon(t0x, t0y, t1x, t1y, tdet, p.ti00, p.ti01, p.ti10, p.ti11, x, y, kc0, lc0, &ck, &cl, &cx, &cy);
  }
  stex_i32 cax, cay, cbx, cby, ccx, ccy;
  stex_tb_vertex_centre(p, k + upper, l, ck, cl, &cax, &cay);
  stex_tb_vertex_centre(p, k + 1 - upper, l + upper, ck, cl, &cbx, &cby);
  stex_tb_vertex_centre(p, k + upper, l + 1, ck, cl, &ccx, &ccy);
  stex_tb_blend(p, g, lut, pca, mean, h, hist, p.channels, p.cs, (stex_i32)rx, (stex_i32)ry, upper, wa, wb, wc, cax,
                cay, cbx, cby, ccx, ccy, (stex_i32)cx, (stex_i32)cy, out);
}

#endif /* STEX_TB_H */
