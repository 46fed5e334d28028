/* Tiling and blending (kinds tb, cs-tb) in two passes per chunk (shared/tb.h; the C++ reference, runtime/tb.h,
 * evaluates the same functions per pixel: every kernel here equals it bit for bit):
 *  - tb_vertices: one work-item per triangle-grid vertex of the chunk's window computes its tile centre once
 *    (the vertex hash; for cs-tb the lattice node search);
 *  - tb: one work-item per output pixel finds its triangle exactly from the chunk's canonical residual
 *    (stex_cs_canon_near, 32-bit), reads its 3 vertices' centres and blends 3 fetches (any device, any scale);
 *  - tb_run (aligned tb or cs-tb; tile >= STEX_TB_LANES output pixels): one work-item per 128 pixels of a
 *    row, in runs of STEX_TB_LANES (8 or 16) consecutive pixels, explicit floatN / intN lanes (below); for cs-tb
 *    each lane's canonical CS residual, cyclic mean and (CS histogram transfer) polyphase bin as well.
 * Built with -DSTEX_TB_CH=<channels> -DSTEX_TB_CS=<0|1> -DSTEX_TB_ALIGNED=<0|1> -DSTEX_TB_UNIT=<0|1>
 * -DSTEX_TB_LANES=<8|16> (scale 1:
 * p.unit_scale as a constant, shared/tb.h) (the host's). ALIGNED (scale 1,
 * and for cs-tb integer periods: every fetch lands on a texel centre, stex_tb_local): the vertex pass stores one
 * texel offset per vertex (stex_tb_texel_base) instead of two centre coordinates and a fetch reads one texel.
 * Output: `channels` interleaved floats per pixel, out[(j * pitch + i) * channels + c].
 */
#include "shared/tb.h"

#ifndef STEX_TB_CH
#define STEX_TB_CH 1
#endif
#ifndef STEX_TB_CS
#define STEX_TB_CS 0
#endif
#ifndef STEX_TB_ALIGNED
#define STEX_TB_ALIGNED 0
#endif
#ifndef STEX_TB_LANES
#define STEX_TB_LANES 8 /* lanes of tb_run: 8, or 16 (the host's choice for devices with 16-wide float vectors) */
#endif
#define STEX_TB_RUN STEX_TB_LANES
#define STEX_TB_BLOCKS (128 / STEX_TB_LANES) /* runs per work-item of tb_run: 128 pixels of a row */
#define STEX_TB_PAD 16 /* floats before and after the planar exemplar of tb_run (>= lanes) */

/* Vertex (k0 + a, l0 + b) for a < nk, b < nl: its model fixed tile centre into centres[2 (b nk + a) + {0, 1}],
 * or (ALIGNED) its texel offset for the chunk whose first pixel is (x0, y0) into centres[b nk + a].
 * (kc0, lc0): the CS-lattice canonical node of the chunk's first pixel (cs-tb). */
__kernel void tb_vertices(const stex_tb_params p_arg, const long k0, const long l0, const long kc0, const long lc0,
                          const int nk, const int nl, const long x0, const long y0, __global int* centres,
                          STEX_WATCHDOG_ARGS) {
  const stex_tb_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int a = (int)get_global_id(0);
  const int b = (int)get_global_id(1);
  if (a >= nk || b >= nl) return;
  int cx, cy;
  stex_tb_vertex_centre(p, k0 + a, l0 + b, kc0, lc0, &cx, &cy);
#if STEX_TB_ALIGNED
  centres[b * nk + a] = stex_tb_texel_base(p, k0 + a, l0 + b, cx, cy, x0, y0);
#else
  centres[2 * (b * nk + a)] = cx;
  centres[2 * (b * nk + a) + 1] = cy;
#endif
  STEX_WATCHDOG_CHECK();
}

/* (r0gx, r0gy), (r0cx, r0cy): the canonical residuals of the chunk's first pixel in the grid and the CS
 * lattice; the grid node of a pixel is the chunk's + (dk, dl), its vertices' centres are at window index
 * (dk - dk_min + .., dl - dl_min + ..) of `centres` (nk x nl, from tb_vertices). */
__kernel void tb(const stex_tb_params p_arg, __global const float* g, __global const float* lut, __global const float* pca,
                 __global const float* mean, const stex_cs_hist_params h_arg, __global const float* hist,
                 __global const int* centres, const int nk, const int nl,
                 const int dk_min, const int dl_min, const int r0gx, const int r0gy, const int r0cx, const int r0cy,
                 const long x0, const long y0, const int width, const int height, const int pitch,
                 __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_tb_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const stex_cs_hist_params h = h_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  const int g0x = (int)p.g0x_lo, g1x = (int)p.g1x_lo, g1y = (int)p.g1y_lo; /* g0y = 0 */
  const long gdet = stex_join64(p.gdet_lo, p.gdet_hi);
  int dk, dl, rx, ry;
  stex_cs_canon_near(g0x, 0, g1x, g1y, gdet, p.gi00, p.gi01, p.gi10, p.gi11, r0gx + i * 65536, r0gy + j * 65536, &dk,
                     &dl, &rx, &ry);
  float wa, wb, wc;
  const int upper = stex_tb_triangle(p, rx, ry, &wa, &wb, &wc);
  int cx = 0, cy = 0;
#if STEX_TB_CS
  {
    const long tdet = stex_join64(p.tdet_lo, p.tdet_hi);
    int ek, el;
    stex_cs_canon_near((int)p.t0x_lo, (int)p.t0y_lo, (int)p.t1x_lo, (int)p.t1y_lo, tdet, p.ti00, p.ti01, p.ti10,
                       p.ti11, r0cx + i * 65536, r0cy + j * 65536, &ek, &el, &cx, &cy);
  }
#endif
  /* The window holds every vertex of the chunk (margins of 2 cells); the clamp only guards memory. Slot
   * vertices a = (upper, 0), b = (1 - upper, upper), c = (upper, 1) of the base node (stex_tb_triangle). */
  const int a = clamp(dk - dk_min, 0, nk - 2), b = clamp(dl - dl_min, 0, nl - 2);
  const int va = b * nk + a + upper, vb = (b + upper) * nk + a + 1 - upper, vc = (b + 1) * nk + a + upper;
  float v[STEX_TB_MAX_CHANNELS];
#if STEX_TB_ALIGNED
  /* One texel per fetch (its bilinear fractions are exactly 0; stex_tb_texel_base). */
  const int pix = j * p.ex_w + i;
  const int t_a = (centres[va] + pix) * STEX_TB_CH, t_b = (centres[vb] + pix) * STEX_TB_CH;
  const int t_c = (centres[vc] + pix) * STEX_TB_CH;
  float ga[STEX_TB_MAX_CHANNELS], gb[STEX_TB_MAX_CHANNELS], gc[STEX_TB_MAX_CHANNELS], gv[STEX_TB_MAX_CHANNELS];
  for (int c = 0; c < STEX_TB_CH; ++c) {
    ga[c] = g[t_a + c];
    gb[c] = g[t_b + c];
    gc[c] = g[t_c + c];
  }
  stex_tb_mix(p, mean, STEX_TB_CH, STEX_TB_CS, wa, wb, wc, ga, gb, gc, cx, cy, gv);
  stex_tb_finish(p, lut, pca, h, hist, cx, cy, STEX_TB_CH, gv, v);
#else
  stex_tb_blend(p, g, lut, pca, mean, h, hist, STEX_TB_CH, STEX_TB_CS, rx, ry, upper, wa, wb, wc, centres[2 * va],
                centres[2 * va + 1], centres[2 * vb], centres[2 * vb + 1], centres[2 * vc], centres[2 * vc + 1], cx, cy,
                v);
#endif
  const size_t o = ((size_t)j * (size_t)pitch + (size_t)i) * (size_t)STEX_TB_CH;
  for (int c = 0; c < STEX_TB_CH; ++c) out[o + (size_t)c] = v[c];
  STEX_WATCHDOG_CHECK();
}

#define STEX_TB_CAT2(a, b) a##b
#define STEX_TB_CAT(a, b) STEX_TB_CAT2(a, b)
#define TBF STEX_TB_CAT(float, STEX_TB_LANES)
#define TBI STEX_TB_CAT(int, STEX_TB_LANES)
#define TBL STEX_TB_CAT(long, STEX_TB_LANES)
#define TBU STEX_TB_CAT(uint, STEX_TB_LANES)
#define TB_AS_U STEX_TB_CAT(as_uint, STEX_TB_LANES)
#define TB_AS_I STEX_TB_CAT(as_int, STEX_TB_LANES)
#define TB_CVT_F STEX_TB_CAT(convert_float, STEX_TB_LANES)
#define TB_CVT_I STEX_TB_CAT(convert_int, STEX_TB_LANES)
#define TB_CVT_L STEX_TB_CAT(convert_long, STEX_TB_LANES)
#define TB_VLOAD STEX_TB_CAT(vload, STEX_TB_LANES)
#define TB_VSTORE STEX_TB_CAT(vstore, STEX_TB_LANES)

/* T^-1 on 8 lanes, a + f d with (a, d) the pair at idx (stex_tb_lut's a + f (b - a)): the pairs stay
 * interleaved, (a, d) x (1, f) is (a, f d) exactly, and one horizontal add gives a + f d per lane (x86: 8
 * 64-bit loads, 2 inserts, 2 unpacks, 2 products, 1 hadd, no de-interleaving). u holds pairs 0 1 | 4 5 and w
 * pairs 2 3 | 6 7, so that the adds of adjacent floats of (u, w) half by half give lanes 0..7 in order. */
static inline float8 stex_tb_lerp8(__global const float* lut2, const int8 idx, const float8 f) {
  const float8 u = (float8)(vload2(idx.s0, lut2), vload2(idx.s1, lut2), vload2(idx.s4, lut2), vload2(idx.s5, lut2));
  const float8 w = (float8)(vload2(idx.s2, lut2), vload2(idx.s3, lut2), vload2(idx.s6, lut2), vload2(idx.s7, lut2));
  const float8 fu = (float8)(1.0f, f.s0, 1.0f, f.s1, 1.0f, f.s4, 1.0f, f.s5);
  const float8 fw = (float8)(1.0f, f.s2, 1.0f, f.s3, 1.0f, f.s6, 1.0f, f.s7);
  const float8 x = u * fu, y = w * fw;
  return (float8)(x.s0 + x.s1, x.s2 + x.s3, y.s0 + y.s1, y.s2 + y.s3, x.s4 + x.s5, x.s6 + x.s7, y.s4 + y.s5,
                  y.s6 + y.s7);
}

/* 8 pixels' STEX_TB_CH interleaved floats (v0..v3: channels 0..3, the unused ones ignored) as vector stores
 * (scalar stores of 24 floats cost a fifth of the kernel's time for RGB). */
static inline void stex_tb_store8(const float8 v0, const float8 v1, const float8 v2, const float8 v3,
                                  __global float* o) {
#if STEX_TB_CH == 1
  vstore8(v0, 0, o);
#elif STEX_TB_CH == 2
  vstore8((float8)(v0.s0, v1.s0, v0.s1, v1.s1, v0.s2, v1.s2, v0.s3, v1.s3), 0, o);
  vstore8((float8)(v0.s4, v1.s4, v0.s5, v1.s5, v0.s6, v1.s6, v0.s7, v1.s7), 0, o + 8);
#elif STEX_TB_CH == 3
  vstore8((float8)(v0.s0, v1.s0, v2.s0, v0.s1, v1.s1, v2.s1, v0.s2, v1.s2), 0, o);
  vstore8((float8)(v2.s2, v0.s3, v1.s3, v2.s3, v0.s4, v1.s4, v2.s4, v0.s5), 0, o + 8);
  vstore8((float8)(v1.s5, v2.s5, v0.s6, v1.s6, v2.s6, v0.s7, v1.s7, v2.s7), 0, o + 16);
#else
  vstore8((float8)(v0.s0, v1.s0, v2.s0, v3.s0, v0.s1, v1.s1, v2.s1, v3.s1), 0, o);
  vstore8((float8)(v0.s2, v1.s2, v2.s2, v3.s2, v0.s3, v1.s3, v2.s3, v3.s3), 0, o + 8);
  vstore8((float8)(v0.s4, v1.s4, v2.s4, v3.s4, v0.s5, v1.s5, v2.s5, v3.s5), 0, o + 16);
  vstore8((float8)(v0.s6, v1.s6, v2.s6, v3.s6, v0.s7, v1.s7, v2.s7, v3.s7), 0, o + 24);
#endif
}

/* 8 floats of t at the lanes' indices (cs-tb's cyclic mean: a table of n0 x n1 x channels floats). */
static inline float8 stex_tb_gather8(__global const float* t, const int8 i) {
  return (float8)(t[i.s0], t[i.s1], t[i.s2], t[i.s3], t[i.s4], t[i.s5], t[i.s6], t[i.s7]);
}

#if STEX_TB_LANES == 16
#define TB_LANE_IDS ((int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15))
#define TB_GATHER(t, i) ((float16)(stex_tb_gather8((t), (i).lo), stex_tb_gather8((t), (i).hi)))
#define TB_LAST(x) ((x).sf)
static inline float16 stex_tb_lerp(__global const float* lut2, const int16 idx, const float16 f) {
  return (float16)(stex_tb_lerp8(lut2, idx.lo, f.lo), stex_tb_lerp8(lut2, idx.hi, f.hi));
}
#elif STEX_TB_LANES == 8
#define TB_LANE_IDS ((int8)(0, 1, 2, 3, 4, 5, 6, 7))
#define TB_GATHER(t, i) stex_tb_gather8((t), (i))
#define TB_LAST(x) ((x).s7)
#define stex_tb_lerp stex_tb_lerp8
#else
#error "STEX_TB_LANES must be 8 or 16"
#endif

/* A whole run: its STEX_TB_LANES x STEX_TB_CH interleaved floats (channel c of the run in v[c]). */
static inline void stex_tb_store_run(const TBF* v, __global float* o) {
#if STEX_TB_CH == 1
  TB_VSTORE(v[0], 0, o);
#else
  const TBF z = (TBF)0.0f;
  const TBF v2 = STEX_TB_CH > 2 ? v[STEX_TB_CH > 2 ? 2 : 0] : z, v3 = STEX_TB_CH > 3 ? v[STEX_TB_CH > 3 ? 3 : 0] : z;
#if STEX_TB_LANES == 16
  stex_tb_store8(v[0].lo, v[1].lo, v2.lo, v3.lo, o);
  stex_tb_store8(v[0].hi, v[1].hi, v2.hi, v3.hi, o + 8 * STEX_TB_CH);
#else
  stex_tb_store8(v[0], v[1], v2, v3, o);
#endif
#endif
}

#if !STEX_TB_ALIGNED
/* stex_tb_fetch on each lane (the general path: any scale, bilinear reads): the N lanes' displacements
 * dx = x_q - v (output fixed units; one row, so dy is the run's) from vertex v with model fixed centre
 * (cvx, cvy), every channel of the interleaved exemplar g into v[0 .. STEX_TB_CH). stex_tb_local's float
 * operations per lane; the row coordinate is the run's (scalar); the 4 texels of each lane are gathered. */
static inline void stex_tb_fetch_lanes(const stex_tb_params p, __global const float* g, const TBI dx, const int dy,
                                       const int cvx, const int cvy, TBF* v) {
  const int cfx = (cvx & 0xffff) - 32768, cfy = (cvy & 0xffff) - 32768;
  TBF tx;
  float ty;
  if (STEX_TB_UNIT_SCALE(p)) {
    tx = TB_CVT_F(dx + cfx) * (1.0f / 65536.0f);
    ty = (float)(dy + cfy) * (1.0f / 65536.0f);
  } else {
    tx = TB_CVT_F(dx) * p.inv_fix_scale + (float)cfx * (1.0f / 65536.0f);
    ty = (float)dy * p.inv_fix_scale + (float)cfy * (1.0f / 65536.0f);
  }
  const TBF fx0 = floor(tx);
  const float fy0 = floor(ty);
  const TBF fx = tx - fx0;
  const float fy = ty - fy0;
  TBI i0 = (TBI)(cvx >> 16) + TB_CVT_I(fx0);
  int j0 = (cvy >> 16) + (int)fy0;
  i0 = select(select(i0, (TBI)(p.ex_w - 2), i0 > (TBI)(p.ex_w - 2)), (TBI)0, i0 < (TBI)0);
  j0 = j0 < 0 ? 0 : (j0 > p.ex_h - 2 ? p.ex_h - 2 : j0);
  const TBI t00 = (j0 * p.ex_w + i0) * STEX_TB_CH, t01 = t00 + p.ex_w * STEX_TB_CH;
  for (int c = 0; c < STEX_TB_CH; ++c) {
    const TBF v00 = TB_GATHER(g, t00 + c), v10 = TB_GATHER(g, t00 + (STEX_TB_CH + c));
    const TBF v01 = TB_GATHER(g, t01 + c), v11 = TB_GATHER(g, t01 + (STEX_TB_CH + c));
    const TBF a = v00 + fx * (v10 - v00);
    const TBF b = v01 + fx * (v11 - v01);
    v[c] = a + fy * (b - a);
  }
}
#endif

#if STEX_TB_CS
/* cs-tb: the canonical CS residuals (cx, cy) of the run's lanes, stex_cs_canon_near's operations on each lane
 * (lane q at (ax + q 65536, ay), a run's pixels share their row): its float solve, the floors, the wrapping
 * 32-bit residual, the exact 64-bit numerators and the -1/0/+1 correction. */
static inline void stex_tb_cs_lanes(const stex_tb_params p, const int ax, const int ay, TBI* cx, TBI* cy) {
  const int t0x = (int)p.t0x_lo, t0y = (int)p.t0y_lo, t1x = (int)p.t1x_lo, t1y = (int)p.t1y_lo;
  long det = stex_join64(p.tdet_lo, p.tdet_hi);
  const TBI axl = (TBI)ax + TB_LANE_IDS * 65536;
  const TBF fx = TB_CVT_F(axl);
  const float fy = (float)ay;
  const TBF fa = fx * p.ti00 + fy * p.ti01, fb = fx * p.ti10 + fy * p.ti11;
  const TBI ka = TB_CVT_I(floor(fa)), lb = TB_CVT_I(floor(fb)); /* integral: truncation is the cast */
  const TBI x1 = TB_AS_I(TB_AS_U(axl) - TB_AS_U(ka) * (uint)t0x - TB_AS_U(lb) * (uint)t1x);
  const TBI y1 = TB_AS_I((TBU)(uint)ay - TB_AS_U(ka) * (uint)t0y - TB_AS_U(lb) * (uint)t1y);
  const TBL lx = TB_CVT_L(x1), ly = TB_CVT_L(y1);
  TBL na = lx * (long)t1y - ly * (long)t1x, nb = ly * (long)t0x - lx * (long)t0y;
  if (det < 0) {
    na = -na;
    nb = -nb;
    det = -det;
  }
  /* (na >= det) - (na < 0) as 1 / 0 / -1: vector comparisons are -1 where true */
  const TBI ea = TB_CVT_I(na < (TBL)0) - TB_CVT_I(na >= (TBL)det), eb = TB_CVT_I(nb < (TBL)0) - TB_CVT_I(nb >= (TBL)det);
  *cx = TB_AS_I(TB_AS_U(x1) - TB_AS_U(ea) * (uint)t0x - TB_AS_U(eb) * (uint)t1x);
  *cy = TB_AS_I(TB_AS_U(y1) - TB_AS_U(ea) * (uint)t0y - TB_AS_U(eb) * (uint)t1y);
}

/* stex_tb_mean on each lane: channel c of the cyclic mean at the lanes' phases (u, v) (stex_tb_mean's, from
 * the canonical CS residuals: u = cx ti00 + cy ti01, v = cx ti10 + cy ti11). */
static inline TBF stex_tb_mean_lanes(const stex_tb_params p, __global const float* mean, const TBF u, const TBF v,
                                     const int c) {
  const TBF gx = u * (float)p.n0, gy = v * (float)p.n1;
  const TBF gx0 = floor(gx), gy0 = floor(gy);
  const TBF fx = gx - gx0, fy = gy - gy0;
  TBI i0 = TB_CVT_I(gx0), j0 = TB_CVT_I(gy0);
  i0 = select(select(i0, i0 - p.n0, i0 >= (TBI)p.n0), i0 + p.n0, i0 < (TBI)0);
  j0 = select(select(j0, j0 - p.n1, j0 >= (TBI)p.n1), j0 + p.n1, j0 < (TBI)0);
  const TBI i1 = select(i0 + 1, (TBI)0, i0 + 1 == (TBI)p.n0), j1 = select(j0 + 1, (TBI)0, j0 + 1 == (TBI)p.n1);
  const int ch = p.channels;
  const TBF v00 = TB_GATHER(mean, (j0 * p.n0 + i0) * ch + c), v10 = TB_GATHER(mean, (j0 * p.n0 + i1) * ch + c);
  const TBF v01 = TB_GATHER(mean, (j1 * p.n0 + i0) * ch + c), v11 = TB_GATHER(mean, (j1 * p.n0 + i1) * ch + c);
  const TBF a = v00 + fx * (v10 - v00);
  const TBF b = v01 + fx * (v11 - v01);
  return a + fy * (b - a);
}

/* stex_cs_hist_bin on each lane. */
static inline TBI stex_tb_hist_bin_lanes(const stex_cs_hist_params h, const TBF u, const TBF v) {
  TBI a = TB_CVT_I(floor(u * (float)h.m0)), b = TB_CVT_I(floor(v * (float)h.m1));
  a = (a % h.m0 + h.m0) % h.m0;
  b = (b % h.m1 + h.m1) % h.m1;
  return b * h.m0 + a;
}

/* stex_cs_hist_inv on each lane: T_bin^-1(g) of channel c, its 4 table reads gathered lane by lane. */
static inline TBF stex_tb_hist_inv_lanes(const stex_cs_hist_params h, __global const float* tab, const TBI bin,
                                         const int c, const TBF g) {
  TBF t = (g - h.phi_lo) * h.phi_scale;
  const float mx = (float)(h.phi_size - 1);
  t = select(select(t, (TBF)mx, t > mx), (TBF)0.0f, t < 0.0f);
  TBI i = TB_CVT_I(floor(t));
  i = select(i, (TBI)(h.phi_size - 2), i > (TBI)(h.phi_size - 2));
  const TBF f = t - TB_CVT_F(i);
  const TBF t0 = TB_GATHER(tab, i), t1 = TB_GATHER(tab, i + 1);
  const TBF pr = t0 + f * (t1 - t0);
  TBF sq = pr * (float)h.q - 0.5f;
  const float qm = (float)(h.q - 1);
  sq = select(select(sq, (TBF)qm, sq > qm), (TBF)0.0f, sq < 0.0f);
  TBI k = TB_CVT_I(floor(sq));
  k = select(k, (TBI)(h.q - 2), k > (TBI)(h.q - 2));
  const TBF fs = sq - TB_CVT_F(k);
  const TBI qi = h.phi_size + (bin * h.channels + c) * h.q + k;
  const TBF q0 = TB_GATHER(tab, qi), q1 = TB_GATHER(tab, qi + 1);
  return q0 + fs * (q1 - q0);
}
#endif

/* tb (stationary) or cs-tb (STEX_TB_CS: the blend about each lane's cyclic mean, stex_tb_cs_lanes and
 * stex_tb_mean_lanes; T^-1 the stationary LUT, or with h.q > 0 the CS histogram transfer of each lane's
 * polyphase bin), aligned, g0x >= N = STEX_TB_LANES output pixels: one work-item per 128
 * pixels of a row, in runs of N consecutive pixels (chunk pixels i0 .. i0 + N - 1 of row j). On a CPU device
 * (PoCL vectorises the per-pixel kernel across work-items, so its per-pixel loads become gathers) a run reads
 * consecutive texels with one vloadN. The host picks N = 16 (float16) on tiles of >= 16 pixels: a run's scalar
 * work is then shared by twice the pixels (0.70-0.77 x N = 8's time on AVX2, 0.83-0.93 x on AVX-512; BM_Tb16
 * against BM_Tb8, docs/cyclostationary.md).
 * Bit-exactness with the reference, lane by lane:
 *  - the row's pixels share the canonical grid row l and residual ry (g0y = 0: l = floor(y / g1y)); lane q's
 *    column is the run's first pixel's dk + e_q, e_q = [na + q 65536 g1y >= det] in {0, 1} (na the first
 *    pixel's exact a-numerator in [0, det); g0x >= N pixels), its residual rx + q 65536 - e_q g0x: exactly the
 *    canonical (dk, rx, ry) of stex_cs_canon_near;
 *  - weights: stex_tb_triangle's float operations on each lane, fb taken as the row's fry gi11 (exact:
 *    gi10 = -0, so frx gi10 is +-0);
 *  - the blend visits the vertices of the run's triangles in canonical order (bottom row by column, then the
 *    top row: the order of stex_tb_triangle's slots), each with its hat weight on each lane: the lane's slot
 *    weight if the vertex is one of its triangle's, else exactly 0 (0 * a finite texel adds +-0: no change to
 *    the sums). One triangle: its 3 vertices; two: their 4; more (a short triangle inside the run): the
 *    strip's 6. Every lane's fetch of one vertex is in one texel row (within N - 1 texels of a valid fetch: the
 *    planar exemplar is padded by STEX_TB_PAD >= N floats);
 *  - stex_tb_mix, stex_tb_lut and stex_tb_finish's float operations on each lane; the LUT is read as pairs
 *    (lut[i], lut[i + 1] - lut[i]), the difference computed by the host in float: the same value as
 *    stex_tb_lut's b - a (stex_tb_lerp8: a + f d as the sum of a x 1 and f x d).
 * gp: the exemplar as STEX_TB_CH planes of ex_w x ex_h floats between STEX_TB_PAD floats of padding; lut2: the
 * pair table, lut_size pairs per channel (the last pair's difference unused). */
/* The N lanes' values of window vertex vi, column dk + K and row dl + OL of the run's base node, every
 * channel into v: aligned, one vloadN per channel of consecutive texels of the padded planar exemplar gp; else
 * stex_tb_fetch_lanes' bilinear reads of the interleaved exemplar gp (the vertex pass's two centre
 * coordinates per vertex). */
#if STEX_TB_ALIGNED
#define TB_FETCH(vi, K, OL, v)                                                                                   \
  do {                                                                                                           \
    const int t_ = centres[(vi)] + pix;                                                                          \
    for (int c_ = 0; c_ < STEX_TB_CH; ++c_) (v)[c_] = TB_VLOAD(0, gp + t_ + c_ * plane);                         \
  } while (0)
#else
#define TB_FETCH(vi, K, OL, v)                                                                                   \
  stex_tb_fetch_lanes(p, gp, rq - ((K) * g0x + (OL) * g1x), ry - (OL) * g1y, centres[2 * (vi)],                 \
                      centres[2 * (vi) + 1], (v))
#endif

__kernel void tb_run(const stex_tb_params p_arg, __global const float* gp, __global const float* lut2,
                     __global const float* pca, __global const float* mean, const stex_cs_hist_params h_arg,
                     __global const float* hist, __global const int* centres, const int nk,
                     const int nl, const int dk_min, const int dl_min, const int r0gx, const int r0gy, const int r0cx,
                     const int r0cy, const long x0, const long y0, const int width, const int height, const int pitch,
                     __global float* out, STEX_WATCHDOG_ARGS) {
  const stex_tb_params p = p_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const stex_cs_hist_params h = h_arg; /* private copy: docs/portability.md (kernel-argument structs) */
  const int i00 = (int)get_global_id(0) * (STEX_TB_RUN * STEX_TB_BLOCKS);
  const int j = (int)get_global_id(1);
  if (i00 >= width || j >= height) return;
  const int g0x = (int)p.g0x_lo, g1x = (int)p.g1x_lo, g1y = (int)p.g1y_lo; /* g0y = 0 */
  const long gdet = stex_join64(p.gdet_lo, p.gdet_hi);                       /* > 0 */
  int dk, dl, rx, ry;
  stex_cs_canon_near(g0x, 0, g1x, g1y, gdet, p.gi00, p.gi01, p.gi10, p.gi11, r0gx + i00 * 65536, r0gy + j * 65536,
                     &dk, &dl, &rx, &ry);
  const long step = 65536L * (long)g1y;
  long na = (long)g1y * (long)rx - (long)g1x * (long)ry; /* the a-numerator of (rx, ry): in [0, gdet) */
  const TBI lane = TB_LANE_IDS;
  const TBL lane_step = TB_CVT_L(lane) * step;
  for (int blk = 0; blk < STEX_TB_BLOCKS; ++blk) {
  const int i0 = i00 + blk * STEX_TB_RUN;
  if (i0 >= width) break;
  if (blk > 0) {
    /* The canonical base of pixel i0 from the previous block's (exact: N pixels are under one column). */
    rx += STEX_TB_RUN * 65536;
    na += STEX_TB_RUN * step;
    if (na >= gdet) {
      na -= gdet;
      rx -= g0x;
      dk += 1;
    }
  }
  /* lanes of column dk + 1; none when the last lane's numerator is below gdet (most runs: one scalar test) */
  const TBI e = na + (long)(STEX_TB_RUN - 1) * step < gdet ? (TBI)0 : -TB_CVT_I(lane_step >= (TBL)(gdet - na));
  const TBI rxl = (TBI)rx + lane * 65536 - ((-e) & (TBI)g0x);
  /* stex_tb_triangle */
  const TBF frx = TB_CVT_F(rxl);
  const float fry = (float)ry;
  /* fb is the row's constant fry gi11: gi10 = -0 (g0y = 0; the host checks it), so frx gi10 is +-0, which
   * leaves fry gi11 unchanged (+0 when it is +0) */
  const TBF fa = frx * p.gi00 + fry * p.gi01;
  const float fb = fry * p.gi11;
  const TBF sab = fa + fb;
  const TBI lower = sab < (TBF)1.0f; /* -1: upper = 0 */
  TBF wa = select((TBF)(1.0f - fb), 1.0f - fa - fb, lower);
  TBF wb = select(1.0f - fa, fa, lower);
  TBF wc = select(sab - 1.0f, (TBF)fb, lower);
  wa = select(wa, (TBF)0.0f, wa < 0.0f);
  wb = select(wb, (TBF)0.0f, wb < 0.0f);
  wc = select(wc, (TBF)0.0f, wc < 0.0f);
  const TBI ka = e + 1 + lower; /* column (from dk) of slots a and c: dk + e + upper */
  /* stex_tb_mix over the strip's vertices in canonical order */
  const int plane = p.ex_w * p.ex_h;
  const int row = clamp(dl - dl_min, 0, nl - 2), col = dk - dk_min;
  const int pix = STEX_TB_PAD + j * p.ex_w + i0;
#if !STEX_TB_ALIGNED
  /* x_q - v = the lanes' residuals from the run's base node (dk, dl) minus vertex (dk + K, dl + OL)'s offset */
  const TBI rq = (TBI)rx + lane * 65536;
#endif
  TBF ss = (TBF)0.0f;
  TBF acc[STEX_TB_CH], m[STEX_TB_CH]; /* m: the mean the blend is about (stex_tb_mix) */
#if STEX_TB_CS
  TBF pu, pv; /* the lanes' phases in the CS lattice */
  {
    TBI cx, cy;
    stex_tb_cs_lanes(p, r0cx + i0 * 65536, r0cy + j * 65536, &cx, &cy);
    const TBF fcx = TB_CVT_F(cx), fcy = TB_CVT_F(cy);
    pu = fcx * p.ti00 + fcy * p.ti01;
    pv = fcx * p.ti10 + fcy * p.ti11;
    for (int c = 0; c < STEX_TB_CH; ++c) m[c] = stex_tb_mean_lanes(p, mean, pu, pv, c);
  }
#else
  for (int c = 0; c < STEX_TB_CH; ++c) m[c] = (TBF)0.5f;
#endif
  for (int c = 0; c < STEX_TB_CH; ++c) acc[c] = (TBF)0.0f;
  /* The lanes' triangles follow the row's order lower(k), upper(k), lower(k + 1), ...: e is a prefix of
   * 0s, and at constant e `lower` is a prefix of -1s (fb is the row's constant and fa is non-decreasing in
   * the lane, since frx is and gi00 > 0, which the host checks). So lanes 0 and N - 1 tell how many triangles
   * the run meets: 2 e_N + u_N - u_0 + 1. */
  const int e_last = TB_LAST(e), l_first = lower.s0 != 0, l_last = TB_LAST(lower) != 0;
  if (e_last == 0 && l_first == l_last) {
    /* One triangle (most runs: tile >> N pixels): its 3 slot vertices with the slot weights, as stex_tb_mix. */
    const int u = l_first ? 0 : 1, cb = clamp(col, 0, nk - 2);
    const int va = row * nk + cb + u, vc = (row + 1) * nk + cb + u, vb = u ? (row + 1) * nk + cb : row * nk + cb + 1;
    ss = wa * wa;
    ss += wb * wb;
    ss += wc * wc;
    TBF fa_[STEX_TB_CH], fb_[STEX_TB_CH], fc_[STEX_TB_CH];
    TB_FETCH(va, u, 0, fa_);
    TB_FETCH(vb, 1 - u, u, fb_);
    TB_FETCH(vc, u, 1, fc_);
    for (int c = 0; c < STEX_TB_CH; ++c) {
      acc[c] += wa * (fa_[c] - m[c]);
      acc[c] += wb * (fb_[c] - m[c]);
      acc[c] += wc * (fc_[c] - m[c]);
    }
  } else if (e_last == 0 || (!l_first && l_last)) {
    /* Two triangles, 4 vertices: lower(dk) | upper(dk) (e_N = 0; bottom and top columns dk, dk + 1) or
     * upper(dk) | lower(dk + 1) (e_N = 1; bottom dk + 1, dk + 2, top dk, dk + 1). Each lane's hat weight at
     * each, in canonical order (bottom by column, then top): its slot weights where the vertex is its
     * triangle's, else 0 (adds exact zeros, as the general path below). */
    TBF h0, h1, h2, h3;
    if (e_last == 0) {
      h0 = select((TBF)0.0f, wa, lower);
      h1 = select(wa, wb, lower);
      h2 = select(wb, wc, lower);
      h3 = select(wc, (TBF)0.0f, lower);
    } else {
      h0 = wa;
      h1 = select((TBF)0.0f, wb, lower);
      h2 = select(wb, (TBF)0.0f, lower);
      h3 = wc;
    }
    const int cb = clamp(col + e_last, 0, nk - 2), ct = clamp(col, 0, nk - 2);
    ss += h0 * h0;
    ss += h1 * h1;
    ss += h2 * h2;
    ss += h3 * h3;
    TBF f0_[STEX_TB_CH], f1_[STEX_TB_CH], f2_[STEX_TB_CH], f3_[STEX_TB_CH];
    TB_FETCH(row * nk + cb, e_last, 0, f0_);
    TB_FETCH(row * nk + cb + 1, e_last + 1, 0, f1_);
    TB_FETCH((row + 1) * nk + ct, 0, 1, f2_);
    TB_FETCH((row + 1) * nk + ct + 1, 1, 1, f3_);
    for (int c = 0; c < STEX_TB_CH; ++c) {
      acc[c] += h0 * (f0_[c] - m[c]);
      acc[c] += h1 * (f1_[c] - m[c]);
      acc[c] += h2 * (f2_[c] - m[c]);
      acc[c] += h3 * (f3_[c] - m[c]);
    }
  } else
  for (int top = 0; top < 2; ++top)
    for (int kk = 0; kk < 3; ++kk) {
      const TBI at = (TBI)kk == ka;
      /* bottom: slot a at column e + upper, slot b (lower triangles) at e + 1; top: slot c at e + upper,
       * slot b (upper triangles) at e */
      const TBI atb = top ? (~lower & ((TBI)kk == e)) : (lower & ((TBI)kk == e + 1));
      const TBF hw = select(select((TBF)0.0f, wb, atb), top ? wc : wa, at);
      /* No branch on whether any lane uses the vertex (unpredictable): a vertex no lane uses adds exact
       * zeros, its read clamped into the buffer (a no-op for a used vertex: its reads are within the padding). */
      const int vi = (row + top) * nk + clamp(col + kk, 0, nk - 1);
      ss += hw * hw;
      TBF f_[STEX_TB_CH];
#if STEX_TB_ALIGNED
      const int t = clamp(centres[vi] + pix, 0, plane + STEX_TB_PAD);
      for (int c = 0; c < STEX_TB_CH; ++c) f_[c] = TB_VLOAD(0, gp + t + c * plane);
#else
      TB_FETCH(vi, kk, top, f_);
#endif
      for (int c = 0; c < STEX_TB_CH; ++c) acc[c] += hw * (f_[c] - m[c]);
    }
  const TBF norm = 1.0f / sqrt(ss);
  TBF gv[STEX_TB_CH];
  for (int c = 0; c < STEX_TB_CH; ++c) gv[c] = m[c] + acc[c] * norm;
#if STEX_TB_CS
  if (h.q > 0) {
    /* stex_tb_finish's CS histogram transfer: T_P(x)^-1 of each lane's polyphase bin */
    const TBI bin = stex_tb_hist_bin_lanes(h, pu, pv);
    for (int c = 0; c < STEX_TB_CH; ++c) gv[c] = stex_tb_hist_inv_lanes(h, hist, bin, c, gv[c]);
  } else
#endif
  {
  /* stex_tb_lut */
  const float lscale = (float)(p.lut_size - 1) / (p.lut_hi - p.lut_lo), lmx = (float)(p.lut_size - 1);
  for (int c = 0; c < STEX_TB_CH; ++c) {
    TBF tl = (gv[c] - p.lut_lo) * lscale;
    tl = select(select(tl, (TBF)lmx, tl > lmx), (TBF)0.0f, tl < 0.0f);
    TBI li = TB_CVT_I(tl); /* tl >= 0: truncation is stex_tb_lut's floor */
    li = select(li, (TBI)(p.lut_size - 2), li > (TBI)(p.lut_size - 2));
    const TBF lf = tl - TB_CVT_F(li);
    gv[c] = stex_tb_lerp(lut2 + 2 * c * p.lut_size, li, lf);
  }
  }
  /* stex_tb_finish: the inverse PCA */
  TBF v[STEX_TB_CH];
  for (int c = 0; c < STEX_TB_CH; ++c) {
    TBF s = (TBF)pca[c];
    for (int d = 0; d < STEX_TB_CH; ++d) s += pca[STEX_TB_CH + d * STEX_TB_CH + c] * gv[d];
    v[c] = s;
  }
  const size_t o = ((size_t)j * (size_t)pitch + (size_t)i0) * (size_t)STEX_TB_CH;
  if (i0 + STEX_TB_RUN <= width) {
    stex_tb_store_run(v, out + o); /* a whole run */
    continue;
  }
  const int n = min(STEX_TB_RUN, width - i0);
  for (int c = 0; c < STEX_TB_CH; ++c) {
    float tmp[STEX_TB_RUN];
    TB_VSTORE(v[c], 0, tmp);
    for (int q = 0; q < n; ++q) out[o + (size_t)(q * STEX_TB_CH + c)] = tmp[q];
  }
  }
  STEX_WATCHDOG_CHECK();
}
