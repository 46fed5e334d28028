/* Local random-phase (LRP) noise evaluation, shared by the OpenCL kernel (kernels/lrp.cl) and the C++
 * reference (runtime/lrp_reference.h). S3 = Gilet, Sauvage, Vanhoey, Dischler, Ghazanfarpour, "Local
 * Random-Phase Noise for Procedural Texturing", ACM TOG 33(6), 2014.
 *
 *   n(x)   = mean + n_R(x') + sum_S n_S(x)                                           (S3 eq. 2 and §5.1)
 *   n_S(x) = sum_{i in 3x3 lattice cells} w(|x - x_i| / Delta_S) sum_{j < J_S} A_S cos(2 pi f_ij.(x - x_i) + phi_ij)
 *                                                                                     (S3 eq. 1, one per stratum)
 *   n_R    = the fixed-phase structure (S3 eq. 4), block-wise (S3 §5.3), evaluated at the randomly placed
 *            (§5.2, half-period blocks) and turbulent position x' = place(x) + sigma n_T(x) (placement
 *            first, then turbulence, S3 §5.2), n_T = sum_T |n_T|: the turbulence strata's carriers (their
 *            own coarse stratification of the whole spectrum, not added to the output), normalised by
 *            sqrt(sum_T Var n_T).
 *
 * Window (S3 §3.6): Kaiser-Bessel, alpha = 3, radius 1.5: w(y) = I0(3 pi sqrt(1 - (y/1.5)^2)) / I0(3 pi).
 * I0(z) = sum_m (z^2/4)^m / (m!)^2 depends on z^2 only, so w is a polynomial in y^2 (no sqrt): 18 terms
 * (m <= 17) give float accuracy at the largest argument z = 3 pi (the last term is 4e-10 of the sum).
 *
 * Spatial lattice: stratum S has square cells of side A_S fixed units (A_S = round(Delta_S scale 2^16));
 * x_i is the centre of cell i; a point in cell c is within 1.5 Delta_S of the centres of cells c-1..c+1 only,
 * so the outer sum has I = 9 terms (S3 §3.4). The cosine uses the local displacement x - x_i (exact int64,
 * converted to float once): a random phase shifted by a constant is still a random phase, and positions far
 * from the origin keep full precision.
 *
 * Random draws (kernels/shared/rng.h), keyed by (seed, stratum, lattice cell, j): draw j of domain
 * STEX_DOMAIN_LRP + stratum of cell i gives the frequency (a table entry of sub-stratum j, uniform, plus a
 * uniform jitter inside its frequency bin) and the phase (uniform in [0, 1) turns); turbulence stratum t
 * draws in domain STEX_DOMAIN_LRP_TURB + t. Placement shifts are keyed by (seed, placement cell) in
 * STEX_DOMAIN_LRP_PLACE.
 *
 * Determinism: cos/sin are the polynomial stex_lrp_cossin (IEEE add/mul/floor only) and the window is a
 * polynomial; with FP_CONTRACT off, kernel and reference agree bit for bit on every IEEE device. Its error
 * against double precision is measured in tests/kernels/test_lrp.cpp (about 1e-7, float rounding). OpenCL's
 * precise cos is slow on PoCL (not vectorised) and native_cos differs across devices (docs/lrp.md), so
 * neither is used.
 */
#ifndef STEX_LRP_H
#define STEX_LRP_H
#include "rng.h"
#include "stex_platform.h"

#define STEX_LRP_FIX_BITS 16
#define STEX_LRP_MAX_STRATA 16
#define STEX_LRP_MAX_CHANNELS 4
/* Cosines per chunk (stex_lrp_strata). The host may set it and STEX_LRP_PAD_CHUNKS when it builds the kernel
 * (runtime/lrp_renderer.cpp: 16 unpadded for GPUs, 8 padded for CPU devices); neither changes a bit: the sums
 * run over j = 0 .. J_S - 1 in order whatever the chunking. */
#ifndef STEX_LRP_CHUNK
#define STEX_LRP_CHUNK 16u
#endif
#define STEX_DOMAIN_LRP 0x4c525000u       /* + stratum index: frequency/phase draws of a lattice cell */
#define STEX_DOMAIN_LRP_PLACE 0x4c52506cu /* random placement shift of a half-period block */
#define STEX_DOMAIN_LRP_TURB 0x4c525400u  /* + turbulence stratum index: draws of a turbulence lattice cell */

#define STEX_LRP_FLAG_STRUCTURE 1u
#define STEX_LRP_FLAG_PLACEMENT 2u
#define STEX_LRP_FLAG_TURBULENCE 4u

/* Everything a kernel needs besides the two tables; 32-bit fields only (static_assert on the host).
 * fdata holds floats: frequencies (kx, ky) of every sub-stratum table, the colour of every sub-stratum
 * (p_c, q_c), and the structure blocks' terms; udata holds (offset, count) of each sub-stratum's table. */
typedef struct {
  stex_i32 channels; /* 1..4 */
  stex_i32 strata;   /* output strata, 0..STEX_LRP_MAX_STRATA */
  stex_i32 tstrata;  /* turbulence strata after them (S3 §5.2; 0 unless STEX_LRP_FLAG_TURBULENCE); sum <= max */
  stex_u32 flags;    /* STEX_LRP_FLAG_* */
  stex_u32 seed_lo, seed_hi;
  float inv_fix_scale; /* 1 / (2^16 scale): fixed units -> exemplar pixels */
  float bin;           /* 1 / T: frequency bin width (cycles per exemplar pixel) */
  stex_u32 col_off;    /* fdata offset of the sub-strata colours: 2 * channels floats each */
  float mean[STEX_LRP_MAX_CHANNELS];
  stex_u32 cell_lo[STEX_LRP_MAX_STRATA], cell_hi[STEX_LRP_MAX_STRATA]; /* A_S in fixed units (int64) */
  float inv_delta[STEX_LRP_MAX_STRATA];                                /* 1 / Delta_S (exemplar pixels) */
  float amp[STEX_LRP_MAX_STRATA];                                      /* the stratum's largest cosine amplitude */
  stex_u32 js[STEX_LRP_MAX_STRATA];                                    /* J_S */
  stex_u32 sub_off[STEX_LRP_MAX_STRATA];                               /* first sub-stratum of S */
  /* structure (S3 §5) */
  stex_u32 period_lo, period_hi; /* T in fixed units (int64) */
  stex_u32 place_lo, place_hi;   /* placement block T/2 in fixed units (int64) */
  float period;                  /* T in exemplar pixels */
  float inv_period;              /* 1 / T */
  float block;                   /* B in exemplar pixels */
  float inv_block;               /* 1 / B */
  stex_i32 blocks;               /* T / B blocks per side */
  stex_i32 jr;                   /* terms per block */
  stex_u32 r_off;                /* fdata offset of the blocks' terms: (2 + 2 channels) floats each */
  float sigma;                   /* turbulence scale, exemplar pixels */
  float turb_norm;               /* 1 / sqrt(sum_S Var n_S): n_T in units of the carrier's deviation */
  float inv_place;               /* 1 / (placement block in fixed units) */
  float blend;                   /* width of the placement blend band, fraction of a placement block */
  float inv_blend;               /* 1 / blend */
} stex_lrp_params;

/* Fixed-point centre of output pixel P (2^16 units per output pixel). */
STEX_FN stex_i64 stex_lrp_pixel_fix(stex_i64 p) { return (2 * p + 1) * ((stex_i64)1 << (STEX_LRP_FIX_BITS - 1)); }

/* Kaiser-Bessel window (alpha = 3, radius 1.5, w(0) = 1) as a function of y^2, y = |x - x_i| / Delta.
 * I0(3 pi sqrt(1 - y^2 / 2.25)) by Horner on u = z^2 / 4 = (9 pi^2 / 4)(1 - y^2 / 2.25), coefficients
 * 1 / m^2; divided by I0(3 pi) = 1633.0905... (exact to float in the constant). 0 outside [0, 1.5). */
STEX_FN float stex_lrp_window_sq(float y2) {
  if (!(y2 < 2.25f)) return 0.0f;
  float u = 22.2066099025f * (1.0f - y2 * 0.444444444444f);
  float s = 1.0f;
  s = 1.0f + u * 0.00346020761246f * s; /* 1/17^2 */
  s = 1.0f + u * 0.00390625f * s;       /* 1/16^2 */
  s = 1.0f + u * 0.00444444444444f * s; /* 1/15^2 */
  s = 1.0f + u * 0.00510204081633f * s; /* 1/14^2 */
  s = 1.0f + u * 0.00591715976331f * s; /* 1/13^2 */
  s = 1.0f + u * 0.00694444444444f * s; /* 1/12^2 */
  s = 1.0f + u * 0.00826446280992f * s; /* 1/11^2 */
  s = 1.0f + u * 0.01f * s;             /* 1/10^2 */
  s = 1.0f + u * 0.0123456790123f * s;  /* 1/9^2 */
  s = 1.0f + u * 0.015625f * s;         /* 1/8^2 */
  s = 1.0f + u * 0.0204081632653f * s;  /* 1/7^2 */
  s = 1.0f + u * 0.0277777777778f * s;  /* 1/6^2 */
  s = 1.0f + u * 0.04f * s;             /* 1/5^2 */
  s = 1.0f + u * 0.0625f * s;           /* 1/4^2 */
  s = 1.0f + u * 0.111111111111f * s;   /* 1/3^2 */
  s = 1.0f + u * 0.25f * s;             /* 1/2^2 */
  s = 1.0f + u * s;                     /* 1/1^2 */
  return s * 6.12335928e-4f;            /* 1 / I0(3 pi) */
}

/* cos(2 pi t) and sin(2 pi t) for any t (turns), by reduction to [-1/8, 1/8] turn and Taylor polynomials
 * (degree 10 / 11 at |a| <= pi/4: truncation < 2e-10). IEEE add/mul/floor only: bit-identical everywhere. */
STEX_FN void stex_lrp_cossin(float t, float* c, float* s) {
  float t4 = (t - STEX_FLOORF(t)) * 4.0f;
  float q = STEX_FLOORF(t4 + 0.5f);
  float a = (t4 - q) * 1.57079632679f; /* [-pi/4, pi/4] */
  float a2 = a * a;
  float cp = 1.0f + a2 * (-0.5f + a2 * (0.0416666666667f + a2 * (-0.00138888888889f +
                     a2 * (2.48015873016e-5f + a2 * -2.7557319224e-7f))));
  float sp = a * (1.0f + a2 * (-0.166666666667f + a2 * (0.00833333333333f + a2 * (-1.98412698413e-4f +
                     a2 * (2.7557319224e-6f + a2 * -2.50521083854e-8f)))));
  stex_i32 qi = ((stex_i32)q) & 3;
  /* rotate by q quarter turns: (c, s) = (cp, sp), (-sp, cp), (-cp, -sp), (sp, -cp) for q = 0..3; written as
   * selects (no branches) so that loops calling it vectorise; negation is exact, so the bits are those of
   * the four cases */
  float c0 = (qi & 1) ? sp : cp;
  float s0 = (qi & 1) ? cp : sp;
  *c = ((qi + 1) & 2) ? -c0 : c0;
  *s = (qi & 2) ? -s0 : s0;
}

/* a mod b in [0, b) for b > 0. */
STEX_FN stex_i64 stex_floormod_i64(stex_i64 a, stex_i64 b) { return a - stex_floordiv(a, b) * b; }

STEX_FN stex_i64 stex_lrp_cell(const stex_lrp_params p, int s) { return stex_join64(p.cell_lo[s], p.cell_hi[s]); }

/* Random-phase strata at fixed-point position (x, y): adds sum_S n_S over the output strata to acc[c] and
 * returns sum_T |carrier_T| over the turbulence strata (the turbulence, un-normalised); the carrier of a
 * stratum is its noise before the colour weights (summed for the turbulence strata only). */
STEX_FN float stex_lrp_strata(const stex_lrp_params p, const STEX_GLOBAL float* fdata,
                              const STEX_GLOBAL stex_u32* udata, stex_i64 x, stex_i64 y, float* acc) {
  float turb = 0.0f;
  for (int s = 0; s < p.strata + p.tstrata; ++s) {
    int out = s < p.strata;
    stex_u32 domain = out ? STEX_DOMAIN_LRP + (stex_u32)s : STEX_DOMAIN_LRP_TURB + (stex_u32)(s - p.strata);
    stex_i64 a = stex_lrp_cell(p, s);
    stex_i64 cx = stex_floordiv(x, a), cy = stex_floordiv(y, a);
    float carrier = 0.0f;
    float inv_d = p.inv_delta[s];
    float amp = p.amp[s];
    stex_u32 js = p.js[s];
    stex_u32 sub0 = p.sub_off[s];
    float bin = p.bin;
    for (stex_i64 ky = cy - 1; ky <= cy + 1; ++ky) {
      for (stex_i64 kx = cx - 1; kx <= cx + 1; ++kx) {
        float dx = (float)(x - (kx * a + a / 2)) * p.inv_fix_scale;
        float dy = (float)(y - (ky * a + a / 2)) * p.inv_fix_scale;
        float rx = dx * inv_d, ry = dy * inv_d;
        float wa = stex_lrp_window_sq(rx * rx + ry * ry) * amp;
        if (wa == 0.0f) continue;
        stex_uvec4 key = stex_cell_key(kx, ky);
        /* The cosines of the cell in chunks of STEX_LRP_CHUNK: first the draws, table look-ups and cos/sin of
         * the chunk, independent per j (a loop without reductions, which the device compiler vectorises),
         * then the sums in the order of j (float addition is not associative: this order is the one both
         * sides use, so kernel and reference agree bit for bit). With STEX_LRP_PAD_CHUNKS the first loop
         * always runs STEX_LRP_CHUNK lanes: the lanes past J_S draw j >= J_S and read the stratum's last
         * sub-stratum, and are never summed. A constant trip count is what a CPU compiler vectorises whole;
         * without it a chunk of J_S mod (vector width) cosines runs scalar, one lane at a time (J_S of 3, 5
         * and 7 are common: docs/lrp.md "Speed"). */
        for (stex_u32 j0 = 0; j0 < js; j0 += STEX_LRP_CHUNK) {
          stex_u32 nj = js - j0 < STEX_LRP_CHUNK ? js - j0 : STEX_LRP_CHUNK;
          float wc[STEX_LRP_CHUNK], ws[STEX_LRP_CHUNK];
#ifdef STEX_LRP_PAD_CHUNKS
          for (stex_u32 jj = 0; jj < STEX_LRP_CHUNK; ++jj) {
            stex_u32 j = j0 + jj;
            stex_uvec4 v = stex_draw(key, p.seed_lo, p.seed_hi, j, domain);
            stex_u32 sub = sub0 + (jj < nj ? j : js - 1u);
#else
          for (stex_u32 jj = 0; jj < nj; ++jj) {
            stex_u32 j = j0 + jj;
            stex_uvec4 v = stex_draw(key, p.seed_lo, p.seed_hi, j, domain);
            stex_u32 sub = sub0 + j;
#endif
            stex_u32 off = udata[2 * sub], n = udata[2 * sub + 1];
            stex_u32 idx = (stex_u32)(((stex_u64)(v.x >> 8) * (stex_u64)n) >> 24);
            float fx = (fdata[2 * (off + idx)] + (stex_uniform24(v.y) - 0.5f)) * bin;
            float fy = (fdata[2 * (off + idx) + 1] + (stex_uniform24(v.z) - 0.5f)) * bin;
            float t = fx * dx + fy * dy + stex_uniform24(v.w);
            float cs, sn;
            stex_lrp_cossin(t, &cs, &sn);
            wc[jj] = wa * cs;
            ws[jj] = wa * sn;
          }
          const STEX_GLOBAL float* col = fdata + p.col_off + 2 * (stex_u32)p.channels * (sub0 + j0);
          if (!out) {
            for (stex_u32 jj = 0; jj < nj; ++jj) carrier += wc[jj];
          } else if (p.channels == 1) { /* grey: the same sums as below without the channel loop */
            float a0 = acc[0];
            for (stex_u32 jj = 0; jj < nj; ++jj) {
              a0 += col[2 * jj] * wc[jj] + col[2 * jj + 1] * ws[jj];
            }
            acc[0] = a0;
          } else {
            for (stex_u32 jj = 0; jj < nj; ++jj) {
              for (int c = 0; c < p.channels; ++c) acc[c] += col[2 * c] * wc[jj] + col[2 * c + 1] * ws[jj];
              col += 2 * p.channels;
            }
          }
        }
      }
    }
    if (!out) turb += carrier < 0.0f ? -carrier : carrier;
  }
  return turb;
}

/* The structure n_R at a position u (exemplar pixels, any value: the structure is T-periodic): the
 * Fourier series of u's block (S3 §5.3; each block holds its jr highest-amplitude terms, coefficients per
 * channel: value += re cos(2 pi k.d / B) + im sin(...), d = u - block origin). Adds to acc[c]. */
STEX_FN void stex_lrp_structure_at(const stex_lrp_params p, const STEX_GLOBAL float* fdata, float ux, float uy,
                                   float weight, float* acc) {
  ux -= p.period * STEX_FLOORF(ux * p.inv_period);
  uy -= p.period * STEX_FLOORF(uy * p.inv_period);
  stex_i32 bx = (stex_i32)STEX_FLOORF(ux * p.inv_block), by = (stex_i32)STEX_FLOORF(uy * p.inv_block);
  bx = bx < 0 ? 0 : (bx >= p.blocks ? p.blocks - 1 : bx);
  by = by < 0 ? 0 : (by >= p.blocks ? p.blocks - 1 : by);
  float dx = (ux - (float)bx * p.block) * p.inv_block, dy = (uy - (float)by * p.block) * p.inv_block;
  stex_i32 stride = 2 + 2 * p.channels;
  const STEX_GLOBAL float* term = fdata + p.r_off + (stex_u32)((by * p.blocks + bx) * p.jr * stride);
  for (stex_i32 k = 0; k < p.jr; ++k) {
    float cs, sn;
    stex_lrp_cossin(term[0] * dx + term[1] * dy, &cs, &sn);
    for (int c = 0; c < p.channels; ++c) acc[c] += weight * (term[2 + 2 * c] * cs + term[3 + 2 * c] * sn);
    term += stride;
  }
}

/* Placement shift of half-period block (bx, by): uniform in [0, T) fixed units per axis. */
STEX_FN void stex_lrp_shift(const stex_lrp_params p, stex_i64 bx, stex_i64 by, stex_i64* sx, stex_i64* sy) {
  stex_uvec4 v = stex_draw(stex_cell_key(bx, by), p.seed_lo, p.seed_hi, 0u, STEX_DOMAIN_LRP_PLACE);
  stex_u64 period = (stex_u64)stex_join64(p.period_lo, p.period_hi);
  *sx = (stex_i64)(((stex_u64)(v.x >> 8) * period) >> 24);
  *sy = (stex_i64)(((stex_u64)(v.y >> 8) * period) >> 24);
}

/* Weights of a placement block and its neighbour along one axis: f is the position inside the block in
 * [0, 1); within blend/2 of an edge the block shares the point with its neighbour by a smoothstep
 * (0.5/0.5 on the edge, so the blend is continuous). Returns the neighbour's direction (-1, 0, +1). */
STEX_FN int stex_lrp_blend_axis(float f, float blend, float inv_blend, float* w_self) {
  float h = 0.5f * blend;
  float e;
  int dir = 0;
  if (f < h) {
    e = 0.5f + f * inv_blend;
    dir = -1;
  } else if (f > 1.0f - h) {
    e = 0.5f + (1.0f - f) * inv_blend;
    dir = 1;
  } else {
    *w_self = 1.0f;
    return 0;
  }
  *w_self = e * e * (3.0f - 2.0f * e);
  return dir;
}

/* Full evaluation at fixed-point position (x, y): out[c] for c < channels. */
STEX_FN void stex_lrp_eval(const stex_lrp_params p, const STEX_GLOBAL float* fdata, const STEX_GLOBAL stex_u32* udata,
                           stex_i64 x, stex_i64 y, float* out) {
  float acc[STEX_LRP_MAX_CHANNELS] = {0.0f, 0.0f, 0.0f, 0.0f};
  float turb = stex_lrp_strata(p, fdata, udata, x, y, acc);
  if (p.flags & STEX_LRP_FLAG_STRUCTURE) {
    float disp = 0.0f;
    if (p.flags & STEX_LRP_FLAG_TURBULENCE) disp = p.sigma * turb * p.turb_norm;
    stex_i64 period = stex_join64(p.period_lo, p.period_hi);
    if (p.flags & STEX_LRP_FLAG_PLACEMENT) {
      stex_i64 pb = stex_join64(p.place_lo, p.place_hi);
      stex_i64 bx = stex_floordiv(x, pb), by = stex_floordiv(y, pb);
      float fx = (float)(x - bx * pb) * p.inv_place, fy = (float)(y - by * pb) * p.inv_place;
      float wx, wy;
      int nx = stex_lrp_blend_axis(fx, p.blend, p.inv_blend, &wx);
      int ny = stex_lrp_blend_axis(fy, p.blend, p.inv_blend, &wy);
      for (int iy = 0; iy < 2; ++iy) {
        if (iy == 1 && ny == 0) break;
        float wyy = iy == 0 ? wy : 1.0f - wy;
        for (int ix = 0; ix < 2; ++ix) {
          if (ix == 1 && nx == 0) break;
          float wxx = ix == 0 ? wx : 1.0f - wx;
          stex_i64 sx, sy;
          stex_lrp_shift(p, bx + (ix ? nx : 0), by + (iy ? ny : 0), &sx, &sy);
          float ux = (float)stex_floormod_i64(x + sx, period) * p.inv_fix_scale + disp;
          float uy = (float)stex_floormod_i64(y + sy, period) * p.inv_fix_scale + disp;
          stex_lrp_structure_at(p, fdata, ux, uy, wxx * wyy, acc);
        }
      }
    } else {
      float ux = (float)stex_floormod_i64(x, period) * p.inv_fix_scale + disp;
      float uy = (float)stex_floormod_i64(y, period) * p.inv_fix_scale + disp;
      stex_lrp_structure_at(p, fdata, ux, uy, 1.0f, acc);
    }
  }
  for (int c = 0; c < p.channels; ++c) out[c] = p.mean[c] + acc[c];
}

#endif /* STEX_LRP_H */
