/* Tiling and blending (kinds tb, cs-tb) in two passes per chunk (shared/tb.h; the C++ reference, runtime/tb.h,
 * evaluates the same functions per pixel: every kernel here equals it bit for bit):
 *  - tb_vertices: one work-item per triangle-grid vertex of the chunk's window computes its tile centre once
 *    (the vertex hash; for cs-tb the lattice node search);
 *  - tb: one work-item per output pixel finds its triangle exactly from the chunk's canonical residual
 *    (stex_cs_canon_near, 32-bit), reads its 3 vertices' centres and blends 3 fetches (any device, any scale);
 *  - tb_run (tb only, aligned, tile >= 8 output pixels): one work-item per run of 8 consecutive pixels of a row,
 *    explicit float8 / int8 lanes (below).
 * Built with -DSTEX_TB_CH=<channels> -DSTEX_TB_CS=<0|1> -DSTEX_TB_ALIGNED=<0|1> -DSTEX_TB_UNIT=<0|1> (scale 1:
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
#define STEX_TB_RUN 8    /* lanes of tb_run */
#define STEX_TB_BLOCKS 8 /* runs of 8 pixels per work-item of tb_run (64 pixels of a row) */
#define STEX_TB_PAD 8 /* floats before and after the planar exemplar of tb_run */

/* Vertex (k0 + a, l0 + b) for a < nk, b < nl: its model fixed tile centre into centres[2 (b nk + a) + {0, 1}],
 * or (ALIGNED) its texel offset for the chunk whose first pixel is (x0, y0) into centres[b nk + a].
 * (kc0, lc0): the CS-lattice canonical node of the chunk's first pixel (cs-tb). */
__kernel void tb_vertices(const stex_tb_params p, const long k0, const long l0, const long kc0, const long lc0,
                          const int nk, const int nl, const long x0, const long y0, __global int* centres) {
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
}

/* (r0gx, r0gy), (r0cx, r0cy): the canonical residuals of the chunk's first pixel in the grid and the CS
 * lattice; the grid node of a pixel is the chunk's + (dk, dl), its vertices' centres are at window index
 * (dk - dk_min + .., dl - dl_min + ..) of `centres` (nk x nl, from tb_vertices). */
__kernel void tb(const stex_tb_params p, __global const float* g, __global const float* lut, __global const float* pca,
                 __global const float* mean, const stex_cs_hist_params h, __global const float* hist,
                 __global const int* centres, const int nk, const int nl,
                 const int dk_min, const int dl_min, const int r0gx, const int r0gy, const int r0cx, const int r0cy,
                 const long x0, const long y0, const int width, const int height, const int pitch,
                 __global float* out) {
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
}

/* 8 lanes of the pair table (lut[i], lut[i + 1] - lut[i]) at i = idx.sq: one 64-bit read a lane. */
static inline void stex_tb_gather8_pairs(__global const float* lut2, const int8 idx, float8* a, float8* d) {
  const float2 p0 = vload2(idx.s0, lut2), p1 = vload2(idx.s1, lut2), p2 = vload2(idx.s2, lut2);
  const float2 p3 = vload2(idx.s3, lut2), p4 = vload2(idx.s4, lut2), p5 = vload2(idx.s5, lut2);
  const float2 p6 = vload2(idx.s6, lut2), p7 = vload2(idx.s7, lut2);
  *a = (float8)(p0.x, p1.x, p2.x, p3.x, p4.x, p5.x, p6.x, p7.x);
  *d = (float8)(p0.y, p1.y, p2.y, p3.y, p4.y, p5.y, p6.y, p7.y);
}

/* tb (stationary, no histogram table), aligned, g0x >= 8 output pixels: one work-item per run of 8 consecutive
 * pixels (chunk pixels i0 .. i0 + 7 of row j). On a CPU device (PoCL vectorises the per-pixel kernel across
 * work-items, so its per-pixel loads become AVX2 gathers) a run reads consecutive texels with vload8.
 * Bit-exactness with the reference, lane by lane:
 *  - the row's pixels share the canonical grid row l and residual ry (g0y = 0: l = floor(y / g1y)); lane q's
 *    column is the run's first pixel's dk + e_q, e_q = [na + q 65536 g1y >= det] in {0, 1} (na the first
 *    pixel's exact a-numerator in [0, det); g0x > 7 pixels), its residual rx + q 65536 - e_q g0x: exactly the
 *    canonical (dk, rx, ry) of stex_cs_canon_near;
 *  - weights: stex_tb_triangle's float operations on each lane;
 *  - the blend visits the strip's vertices in canonical order (bottom row by column, then the top row: the
 *    order of stex_tb_triangle's slots), each with its hat weight on each lane: the lane's slot weight if the
 *    vertex is one of its triangle's, else exactly 0 (0 * a finite texel adds +-0: no change to the sums);
 *    a vertex that is on no lane's triangle is skipped. Every lane's fetch of one vertex is in one texel row
 *    (within 7 texels of a valid fetch: the planar exemplar is padded by STEX_TB_PAD floats);
 *  - stex_tb_mix, stex_tb_lut and stex_tb_finish's float operations on each lane; the LUT is read as pairs
 *    (lut[i], lut[i + 1] - lut[i]), the difference computed by the host in float: the same value as
 *    stex_tb_lut's b - a.
 * gp: the exemplar as STEX_TB_CH planes of ex_w x ex_h floats between STEX_TB_PAD floats of padding; lut2: the
 * pair table, lut_size pairs per channel (the last pair's difference unused). */
__kernel void tb_run(const stex_tb_params p, __global const float* gp, __global const float* lut2,
                     __global const float* pca, __global const int* centres, const int nk, const int nl,
                     const int dk_min, const int dl_min, const int r0gx, const int r0gy, const long x0, const long y0,
                     const int width, const int height, const int pitch, __global float* out) {
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
  const int8 lane = (int8)(0, 1, 2, 3, 4, 5, 6, 7);
  const long8 lane_step = convert_long8(lane) * step;
  for (int blk = 0; blk < STEX_TB_BLOCKS; ++blk) {
  const int i0 = i00 + blk * STEX_TB_RUN;
  if (i0 >= width) break;
  if (blk > 0) {
    /* The canonical base of pixel i0 from the previous block's (exact: 8 pixels are under one column). */
    rx += STEX_TB_RUN * 65536;
    na += STEX_TB_RUN * step;
    if (na >= gdet) {
      na -= gdet;
      rx -= g0x;
      dk += 1;
    }
  }
  const int8 e = -convert_int8(lane_step >= (long8)(gdet - na)); /* lanes of column dk + 1 */
  const int8 rxl = (int8)rx + lane * 65536 - e * g0x;
  /* stex_tb_triangle */
  const float8 frx = convert_float8(rxl);
  const float fry = (float)ry;
  const float8 fa = frx * p.gi00 + fry * p.gi01, fb = frx * p.gi10 + fry * p.gi11;
  const float8 sab = fa + fb;
  const int8 lower = sab < (float8)1.0f; /* -1: upper = 0 */
  float8 wa = select(1.0f - fb, 1.0f - fa - fb, lower);
  float8 wb = select(1.0f - fa, fa, lower);
  float8 wc = select(sab - 1.0f, fb, lower);
  wa = select(wa, (float8)0.0f, wa < 0.0f);
  wb = select(wb, (float8)0.0f, wb < 0.0f);
  wc = select(wc, (float8)0.0f, wc < 0.0f);
  const int8 ka = e + 1 + lower; /* column (from dk) of slots a and c: dk + e + upper */
  /* stex_tb_mix over the strip's vertices in canonical order */
  const int plane = p.ex_w * p.ex_h;
  const int row = clamp(dl - dl_min, 0, nl - 2), col = dk - dk_min;
  const int pix = STEX_TB_PAD + j * p.ex_w + i0;
  float8 ss = (float8)0.0f;
  float8 acc[STEX_TB_CH];
  for (int c = 0; c < STEX_TB_CH; ++c) acc[c] = (float8)0.0f;
  const int one_triangle = e.s7 == 0 && (all(lower) || !any(lower)); /* most runs (tile >> 8 pixels) */
  if (one_triangle) {
    /* Every lane in the same triangle: its 3 slot vertices with the slot weights, as stex_tb_mix. */
    const int u = lower.s0 ? 0 : 1, cb = clamp(col, 0, nk - 2);
    const int ta = centres[row * nk + cb + u] + pix, tc = centres[(row + 1) * nk + cb + u] + pix;
    const int tbv = centres[u ? (row + 1) * nk + cb : row * nk + cb + 1] + pix;
    ss = wa * wa;
    ss += wb * wb;
    ss += wc * wc;
    for (int c = 0; c < STEX_TB_CH; ++c) {
      acc[c] += wa * (vload8(0, gp + ta + c * plane) - 0.5f);
      acc[c] += wb * (vload8(0, gp + tbv + c * plane) - 0.5f);
      acc[c] += wc * (vload8(0, gp + tc + c * plane) - 0.5f);
    }
  } else
  for (int top = 0; top < 2; ++top)
    for (int kk = 0; kk < 3; ++kk) {
      const int8 at = (int8)kk == ka;
      /* bottom: slot a at column e + upper, slot b (lower triangles) at e + 1; top: slot c at e + upper,
       * slot b (upper triangles) at e */
      const int8 atb = top ? (~lower & ((int8)kk == e)) : (lower & ((int8)kk == e + 1));
      const float8 hw = select(select((float8)0.0f, wb, atb), top ? wc : wa, at);
      /* No branch on whether any lane uses the vertex (unpredictable): a vertex no lane uses adds exact
       * zeros, its read clamped into the buffer (a no-op for a used vertex: its reads are within the padding). */
      const int vi = (row + top) * nk + clamp(col + kk, 0, nk - 1);
      const int t = clamp(centres[vi] + pix, 0, plane + STEX_TB_PAD);
      ss += hw * hw;
      for (int c = 0; c < STEX_TB_CH; ++c) acc[c] += hw * (vload8(0, gp + t + c * plane) - 0.5f);
    }
  const float8 norm = 1.0f / sqrt(ss);
  float8 gv[STEX_TB_CH];
  for (int c = 0; c < STEX_TB_CH; ++c) gv[c] = 0.5f + acc[c] * norm;
  /* stex_tb_lut */
  const float lscale = (float)(p.lut_size - 1) / (p.lut_hi - p.lut_lo), lmx = (float)(p.lut_size - 1);
  for (int c = 0; c < STEX_TB_CH; ++c) {
    float8 tl = (gv[c] - p.lut_lo) * lscale;
    tl = select(select(tl, (float8)lmx, tl > lmx), (float8)0.0f, tl < 0.0f);
    int8 li = convert_int8(tl); /* tl >= 0: truncation is stex_tb_lut's floor */
    li = select(li, (int8)(p.lut_size - 2), li > (int8)(p.lut_size - 2));
    const float8 lf = tl - convert_float8(li);
    float8 la, ld;
    stex_tb_gather8_pairs(lut2 + 2 * c * p.lut_size, li, &la, &ld);
    gv[c] = la + lf * ld;
  }
  /* stex_tb_finish: the inverse PCA */
  float8 v[STEX_TB_CH];
  for (int c = 0; c < STEX_TB_CH; ++c) {
    float8 s = (float8)pca[c];
    for (int d = 0; d < STEX_TB_CH; ++d) s += pca[STEX_TB_CH + d * STEX_TB_CH + c] * gv[d];
    v[c] = s;
  }
  const size_t o = ((size_t)j * (size_t)pitch + (size_t)i0) * (size_t)STEX_TB_CH;
  if (i0 + STEX_TB_RUN <= width) {
    /* A whole run: its 8 x STEX_TB_CH interleaved floats as vector stores (scalar stores of 24 floats cost
     * a fifth of the kernel's time for RGB). */
#if STEX_TB_CH == 1
    vstore8(v[0], 0, out + o);
#elif STEX_TB_CH == 2
    vstore8((float8)(v[0].s0, v[1].s0, v[0].s1, v[1].s1, v[0].s2, v[1].s2, v[0].s3, v[1].s3), 0, out + o);
    vstore8((float8)(v[0].s4, v[1].s4, v[0].s5, v[1].s5, v[0].s6, v[1].s6, v[0].s7, v[1].s7), 0, out + o + 8);
#elif STEX_TB_CH == 3
    vstore8((float8)(v[0].s0, v[1].s0, v[2].s0, v[0].s1, v[1].s1, v[2].s1, v[0].s2, v[1].s2), 0, out + o);
    vstore8((float8)(v[2].s2, v[0].s3, v[1].s3, v[2].s3, v[0].s4, v[1].s4, v[2].s4, v[0].s5), 0, out + o + 8);
    vstore8((float8)(v[1].s5, v[2].s5, v[0].s6, v[1].s6, v[2].s6, v[0].s7, v[1].s7, v[2].s7), 0, out + o + 16);
#else
    vstore8((float8)(v[0].s0, v[1].s0, v[2].s0, v[3].s0, v[0].s1, v[1].s1, v[2].s1, v[3].s1), 0, out + o);
    vstore8((float8)(v[0].s2, v[1].s2, v[2].s2, v[3].s2, v[0].s3, v[1].s3, v[2].s3, v[3].s3), 0, out + o + 8);
    vstore8((float8)(v[0].s4, v[1].s4, v[2].s4, v[3].s4, v[0].s5, v[1].s5, v[2].s5, v[3].s5), 0, out + o + 16);
    vstore8((float8)(v[0].s6, v[1].s6, v[2].s6, v[3].s6, v[0].s7, v[1].s7, v[2].s7, v[3].s7), 0, out + o + 24);
#endif
    continue;
  }
  const int n = min(STEX_TB_RUN, width - i0);
  for (int c = 0; c < STEX_TB_CH; ++c) {
    float tmp[STEX_TB_RUN];
    vstore8(v[c], 0, tmp);
    for (int q = 0; q < n; ++q) out[o + (size_t)(q * STEX_TB_CH + c)] = tmp[q];
  }
  }
}
