/* Cyclostationary random-phase noise from user spectra (S4 §3.3 eq. 6, §4.2, Fig. 1 left and Fig. 4), kind
 * "cs-rpn", shared by the OpenCL kernel (kernels/cs_rpn.cl) and the C++ reference (runtime/cs_rpn.h):
 *
 *   I(x) = mean + sum_xi A(x, xi) cos(2 pi xi.x + Phi(xi)),   A(x, .)^2 = S^x,   S^x = S^{P(x)} periodic
 *
 * The local PSD S^x is the bilinear interpolation, on a periodic K0 x K1 grid of phases (i / K0, j / K1) of
 * the parallelogram (t0, t1), of K0 K1 user spectra S_g = E_g p_g (E_g the spectrum's variance, p_g its
 * normalised shape: a table of frequency bins with inverse-CDF thresholds, on a half plane):
 *
 *   S^u(f) = sum_{g in the 4 grid nodes around u} w_g(u) E_g p_g(f),   E(u) = sum_g w_g(u) E_g.
 *
 * Drawing a frequency "from the local PSD at u" is drawing from this mixture: a grid node g with probability
 * w_g E_g / E(u), then a bin of p_g by its inverse CDF (poisson.h's integer search), plus a uniform jitter
 * inside the bin (width `bin` cycles per model pixel). Each kernel (impulse or lattice point) takes the
 * phase u of its own position, found exactly from its fixed-point position (the node table of cs.h: bits of
 * the pixel coordinates select nodes, one float solve of the small exact residual), so a kernel's frequency
 * is one value whichever pixel evaluates it. The three variants (S4 §4.2, Fig. 1 left):
 *
 *  - random phase (STEX_CSR_RANDOM_PHASE), the local random-phase form of eq. 6 (S3 eq. 1): a square lattice
 *    of spacing Delta (cell centres), 3 x 3 neighbours, Kaiser-Bessel window w (lrp.h, radius 1.5 Delta),
 *    J cosines per lattice point with frequencies drawn from S^{u_i} and uniform phases:
 *      I(x) = mean + sum_i w(|x - x_i| / Delta) sqrt(E(u_i) / (pi J W)) sum_j cos(2 pi f_ij.(x - x_i) + phi_ij),
 *    W = int_0^inf r w(r)^2 dr, so that the variance averaged over positions is E(u).
 *  - Gabor (STEX_CSR_GABOR), sparse Gabor convolution (gabor.h's envelope, cos and Poisson grid): impulses
 *    x_i of intensity lambda, each with a frequency drawn from S^{u_i} and a uniform phase:
 *      I(x) = mean + (2 a / sqrt(lambda)) sum_i sqrt(E(u_i)) exp(-pi a^2 |x - x_i|^2) cos(2 pi f_i.(x - x_i) + phi_i)
 *    (variance E: lambda E / (4 a^2) before the factor). The local PSD is S^x blurred by the envelope's
 *    spectrum (a Gaussian of std a / (2 sqrt(pi)) cycles per pixel).
 *  - phasor (STEX_CSR_PHASOR), Tricard et al. 2019: the same impulses as complex kernels
 *      phi(x) = sum_i sqrt(E(u_i)) exp(-pi a^2 |x - x_i|^2) exp(i (2 pi f_i.(x - x_i) + phi_i)),
 *      I(x) = mean + sqrt(2 E(P(x))) sin(arg phi(x)) = mean + sqrt(2 E(P(x))) Im phi / |phi|
 *    (a sine profile of constant amplitude; variance E(P(x)) since arg phi is uniform: the phases are). The
 *    tables are on a half plane oriented by each spectrum's principal direction (runtime/cs_rpn.cpp), so a
 *    bi-lobe's impulses share one lobe, which phasor noise needs.
 *
 *  - Fourier (STEX_CSR_FOURIER), S4 Fig. 4's direct synthesis, eq. 6 itself: a Fourier series over the union
 *    of the spectra's bins (integer frequencies (kx, ky) / T on the half plane ky > 0 or (ky = 0, kx > 0)),
 *    one uniform phase per frequency keyed by (seed, kx, ky), amplitude sqrt(2 S^{P(x)}(f)):
 *      I(x) = mean + sum_f sqrt(2 sum_g w_g(P(x)) E_g p_g(f)) cos(2 pi f.x + Phi_f)
 *    (variance E(P(x)) at every x). x is reduced modulo the series' period T (int64, exact), so the output
 *    repeats every T model pixels along both axes, as a Fourier series does. Union table in fdata at
 *    union_off: (kx, ky) per frequency (integers as floats), then p_g(f) for every spectrum (K0 K1 x union_n).
 *
 * Filtering a minified view (runtime/cs_rpn.cpp, docs/filtering.md): random phase fades each cosine by the
 * mean of the footprint's transfer over its bin (a gain per bin at gain_off); Gabor convolves each kernel with
 * the footprint (a wider envelope, the carrier times `carrier`, a gain per bin); Fourier fades each frequency
 * in the union table. Unfiltered, gain_off = 0 and carrier = 1: the plain bits. Phasor noise is not filtered.
 *
 * Random draws (rng.h), keyed by (seed, cell, j): domain CSRA gives the impulse position (x, y words) and the
 * node and bin choices; CSRB the jitter (x, y) and the phase. Poisson counts: domain COUNT, as gabor.h.
 * Determinism: IEEE add/mul/floor, gabor.h's polynomials, and sqrt (correctly rounded on PoCL and in C++,
 * as tb.h); summation order global (cells by (ky, kx), then j): tiles, chunks and work-groups give the same bits.
 */
#ifndef STEX_CS_RPN_H
#define STEX_CS_RPN_H
#include "cs.h"
#include "gabor.h"
#include "lrp.h"

#define STEX_CSR_RANDOM_PHASE 0
#define STEX_CSR_GABOR 1
#define STEX_CSR_PHASOR 2
#define STEX_CSR_FOURIER 3
#define STEX_CSR_MAX_GRID 16                 /* K0, K1 <= 16 */
#define STEX_DOMAIN_CSR_A 0x43535241u        /* "CSRA": position, node, bin */
#define STEX_DOMAIN_CSR_B 0x43535242u        /* "CSRB": jitter, phase */
#define STEX_DOMAIN_CSR_F 0x43535246u        /* "CSRF": the phase of a Fourier-series frequency */

/* 144 bytes; static_assert on the host. fdata: E_g (K0 K1 floats), then (fx, fy) per bin (cycles per model
 * pixel); udata: (offset, count) per spectrum (2 K0 K1), then the bins' inverse-CDF thresholds. */
typedef struct {
  stex_u32 seed_lo, seed_hi;
  stex_u32 t0x_lo, t0x_hi, t0y_lo, t0y_hi; /* T0 in fixed output units (int64) */
  stex_u32 t1x_lo, t1x_hi, t1y_lo, t1y_hi; /* T1 */
  stex_u32 cell_lo, cell_hi;               /* A: impulse-grid cell / lattice spacing in fixed units (int64) */
  stex_u32 reach_lo, reach_hi;             /* Gabor, phasor: impulses within reach (fixed units) may cover x */
  float inv_fix_scale;                     /* fixed output units -> model pixels */
  float i00, i01, i10, i11;                /* inverse of [T0 T1] per fixed unit */
  stex_i32 variant;                        /* STEX_CSR_* */
  stex_i32 k0, k1;                         /* spectrum grid */
  stex_i32 cosines;                        /* random phase: J per lattice point */
  stex_u32 poisson_len;                    /* Gabor, phasor: Poisson threshold entries */
  float bin;                               /* jitter width, cycles per model pixel */
  float exp2_factor;                       /* pi a^2 log2(e) */
  float r2_max;                            /* squared envelope truncation radius (model pixels^2) */
  float inv_delta2;                        /* random phase: 1 / Delta^2 (model pixels^-2) */
  float mean;
  float amplitude;                         /* 1 / sqrt(pi J W) (random phase), 2 a / sqrt(lambda) (Gabor) */
  stex_u32 union_off;                      /* Fourier: fdata index of the union table */
  stex_u32 union_n;                        /* Fourier: frequencies in it */
  stex_u32 gain_off;                       /* filtered: fdata index of the per-bin gains (0: every gain 1) */
  float carrier;                           /* filtered Gabor: the carrier factor rho (1 unfiltered) */
  stex_u32 pad0, pad1;
} stex_csr_params;

/* The exact residual r = X - (k T0 + l T1) of a fixed-point position in (about) its base cell: node table,
 * then one float solve (as stex_cs_spot_eval). A pure function of (X, Y). */
STEX_FN void stex_csr_residual(const stex_csr_params p, const STEX_GLOBAL stex_u32* reduce, stex_i64 x, stex_i64 y,
                               stex_i64* rx, stex_i64* ry) {
  stex_i64 t0x = stex_join64(p.t0x_lo, p.t0x_hi), t0y = stex_join64(p.t0y_lo, p.t0y_hi);
  stex_i64 t1x = stex_join64(p.t1x_lo, p.t1x_hi), t1y = stex_join64(p.t1y_lo, p.t1y_hi);
  stex_i64 k = 0, l = 0;
  stex_cs_reduce_axis(reduce, 0, x >> STEX_CS_FIX_BITS, &k, &l);
  stex_cs_reduce_axis(reduce, 1, y >> STEX_CS_FIX_BITS, &k, &l);
  stex_i64 ax = stex_cs_sub_node(x, k, t0x, l, t1x), ay = stex_cs_sub_node(y, k, t0y, l, t1y);
  float fa = (float)ax * p.i00 + (float)ay * p.i01, fb = (float)ax * p.i10 + (float)ay * p.i11;
  stex_i64 ka = (stex_i64)STEX_FLOORF(fa), lb = (stex_i64)STEX_FLOORF(fb);
  *rx = stex_cs_sub_node(ax, ka, t0x, lb, t1x);
  *ry = stex_cs_sub_node(ay, ka, t0y, lb, t1y);
}

/* Phase (u, v) in [0, 1] of a small exact residual (periodic: 1 is the phase 0). */
STEX_FN void stex_csr_phase(const stex_csr_params p, stex_i64 rx, stex_i64 ry, float* u, float* v) {
  float fu = (float)rx * p.i00 + (float)ry * p.i01, fv = (float)rx * p.i10 + (float)ry * p.i11;
  *u = fu - STEX_FLOORF(fu);
  *v = fv - STEX_FLOORF(fv);
}

/* The 4 grid nodes around phase (u, v) and their weights w_g E_g; returns E(u) = their sum. */
STEX_FN float stex_csr_nodes(const stex_csr_params p, const STEX_GLOBAL float* fdata, float u, float v, stex_i32* g,
                             float* w) {
  float gx = u * (float)p.k0, gy = v * (float)p.k1;
  float ax = STEX_FLOORF(gx), ay = STEX_FLOORF(gy);
  float wx = gx - ax, wy = gy - ay;
  stex_i32 i0 = ((stex_i32)ax % p.k0 + p.k0) % p.k0, j0 = ((stex_i32)ay % p.k1 + p.k1) % p.k1;
  stex_i32 i1 = (i0 + 1) % p.k0, j1 = (j0 + 1) % p.k1;
  g[0] = j0 * p.k0 + i0;
  g[1] = j0 * p.k0 + i1;
  g[2] = j1 * p.k0 + i0;
  g[3] = j1 * p.k0 + i1;
  w[0] = (1.0f - wx) * (1.0f - wy) * fdata[g[0]];
  w[1] = wx * (1.0f - wy) * fdata[g[1]];
  w[2] = (1.0f - wx) * wy * fdata[g[2]];
  w[3] = wx * wy * fdata[g[3]];
  return ((w[0] + w[1]) + w[2]) + w[3];
}

/* Interpolated energy E(u) at phase (u, v). */
STEX_FN float stex_csr_energy(const stex_csr_params p, const STEX_GLOBAL float* fdata, float u, float v) {
  stex_i32 g[4];
  float w[4];
  return stex_csr_nodes(p, fdata, u, v, g, w);
}

/* A frequency (fx, fy) drawn from the local PSD at phase (u, v) (random words: node, bin, jitter x, jitter y)
 * and its bin's filter gain (1 unfiltered); returns E(u). */
STEX_FN float stex_csr_sample(const stex_csr_params p, const STEX_GLOBAL float* fdata, const STEX_GLOBAL stex_u32* udata,
                              float u, float v, stex_u32 r_node, stex_u32 r_bin, stex_u32 r_jx, stex_u32 r_jy, float* fx,
                              float* fy, float* gain) {
  stex_i32 g[4];
  float w[4];
  float total = stex_csr_nodes(p, fdata, u, v, g, w);
  float t = stex_uniform24(r_node) * total;
  stex_i32 c = 0, last = 0;
  float acc = 0.0f;
  for (stex_i32 q = 0; q < 4; ++q) {
    if (w[q] > 0.0f) last = q;
  }
  c = last; /* t >= the sum up to the last node can only be a rounding: the last non-zero node */
  for (stex_i32 q = 0; q < 4; ++q) {
    acc += w[q];
    if (w[q] > 0.0f && t < acc) {
      c = q;
      break;
    }
  }
  stex_i32 n = p.k0 * p.k1;
  stex_i32 sel = g[c];
  stex_u32 off = udata[2 * sel], cnt = udata[2 * sel + 1];
  stex_u32 b = off + stex_poisson_count(udata + 2 * n + off, cnt, r_bin);
  *fx = fdata[n + 2 * b] + p.bin * (stex_uniform24(r_jx) - 0.5f);
  *fy = fdata[n + 2 * b + 1] + p.bin * (stex_uniform24(r_jy) - 0.5f);
  *gain = p.gain_off != 0u ? fdata[p.gain_off + b] : 1.0f;
  return total;
}

/* Random phase: the local random-phase sum at fixed point (x, y). */
STEX_FN float stex_csr_random_phase(const stex_csr_params p, const STEX_GLOBAL float* fdata,
                                    const STEX_GLOBAL stex_u32* udata, const STEX_GLOBAL stex_u32* reduce, stex_i64 x,
                                    stex_i64 y) {
  stex_i64 a = stex_join64(p.cell_lo, p.cell_hi);
  stex_i64 cx = stex_floordiv(x, a), cy = stex_floordiv(y, a);
  stex_i64 hc = a / 2;
  float acc = 0.0f;
  for (stex_i64 ky = cy - 1; ky <= cy + 1; ++ky) {
    for (stex_i64 kx = cx - 1; kx <= cx + 1; ++kx) {
      stex_i64 px = kx * a + hc, py = ky * a + hc;
      float dx = (float)(x - px) * p.inv_fix_scale, dy = (float)(y - py) * p.inv_fix_scale;
      float win = stex_lrp_window_sq((dx * dx + dy * dy) * p.inv_delta2);
      if (win == 0.0f) continue;
      stex_i64 rx, ry;
      float u, v;
      stex_csr_residual(p, reduce, px, py, &rx, &ry);
      stex_csr_phase(p, rx, ry, &u, &v);
      stex_uvec4 key = stex_cell_key(kx, ky);
      float sum = 0.0f, e = 0.0f;
      for (stex_i32 j = 0; j < p.cosines; ++j) {
        stex_uvec4 va = stex_draw(key, p.seed_lo, p.seed_hi, (stex_u32)j, STEX_DOMAIN_CSR_A);
        stex_uvec4 vb = stex_draw(key, p.seed_lo, p.seed_hi, (stex_u32)j, STEX_DOMAIN_CSR_B);
        float fx, fy, gain;
        e = stex_csr_sample(p, fdata, udata, u, v, va.z, va.w, vb.x, vb.y, &fx, &fy, &gain);
        sum += gain * stex_gabor_cos2pi(fx * dx + fy * dy + stex_uniform24(vb.z)); /* gain 1: the same bits */
      }
      acc += win * STEX_SQRTF(e) * sum;
    }
  }
  return acc;
}

/* Gabor and phasor: the (complex) sum of the impulses' kernels at fixed point (x, y); im only for phasor. */
STEX_FN void stex_csr_impulses(const stex_csr_params p, const STEX_GLOBAL float* fdata, const STEX_GLOBAL stex_u32* udata,
                               const STEX_GLOBAL stex_u32* reduce, const STEX_GLOBAL stex_u32* poisson, stex_i64 x,
                               stex_i64 y, float* re, float* im) {
  stex_i64 a = stex_join64(p.cell_lo, p.cell_hi);
  stex_i64 reach = stex_join64(p.reach_lo, p.reach_hi);
  stex_i64 kx0 = stex_floordiv(x - reach, a), kx1 = stex_floordiv(x + reach, a);
  stex_i64 ky0 = stex_floordiv(y - reach, a), ky1 = stex_floordiv(y + reach, a);
  float sr = 0.0f, si = 0.0f;
  for (stex_i64 ky = ky0; ky <= ky1; ++ky) {
    for (stex_i64 kx = kx0; kx <= kx1; ++kx) {
      stex_uvec4 key = stex_cell_key(kx, ky);
      stex_uvec4 cv = stex_draw(key, p.seed_lo, p.seed_hi, 0u, STEX_DOMAIN_COUNT);
      stex_u32 n = stex_poisson_count(poisson, p.poisson_len, cv.x);
      if (n == 0u) continue;
      stex_i64 crx, cry;
      stex_csr_residual(p, reduce, kx * a, ky * a, &crx, &cry); /* the cell corner's residual */
      for (stex_u32 j = 0; j < n; ++j) {
        stex_uvec4 va = stex_draw(key, p.seed_lo, p.seed_hi, j, STEX_DOMAIN_CSR_A);
        stex_i64 ox = (stex_i64)(((stex_u64)(va.x >> 8) * (stex_u64)a) >> 24);
        stex_i64 oy = (stex_i64)(((stex_u64)(va.y >> 8) * (stex_u64)a) >> 24);
        float dx = (float)(x - (kx * a + ox)) * p.inv_fix_scale;
        float dy = (float)(y - (ky * a + oy)) * p.inv_fix_scale;
        float r2 = dx * dx + dy * dy;
        if (r2 >= p.r2_max) continue;
        stex_uvec4 vb = stex_draw(key, p.seed_lo, p.seed_hi, j, STEX_DOMAIN_CSR_B);
        float u, v, fx, fy, gain;
        stex_csr_phase(p, crx + ox, cry + oy, &u, &v);
        float e = stex_csr_sample(p, fdata, udata, u, v, va.z, va.w, vb.x, vb.y, &fx, &fy, &gain);
        /* Filtered (Gabor): gain and carrier of the kernel convolved with the footprint; 1 unfiltered, where
         * x * 1 = x keeps the bits. */
        float s = (STEX_SQRTF(e) * gain) * stex_gabor_exp2(-(p.exp2_factor * r2));
        float theta = (fx * p.carrier) * dx + (fy * p.carrier) * dy + stex_uniform24(vb.z);
        sr += s * stex_gabor_cos2pi(theta);
        if (p.variant == STEX_CSR_PHASOR) si += s * stex_gabor_cos2pi(theta - 0.25f);
      }
    }
  }
  *re = sr;
  *im = si;
}

/* Fourier: the series at fixed point (x, y); cell = the period T in fixed units, bin = 1 / T. */
STEX_FN float stex_csr_fourier(const stex_csr_params p, const STEX_GLOBAL float* fdata, const STEX_GLOBAL stex_u32* reduce,
                               stex_i64 x, stex_i64 y) {
  stex_i64 rx, ry;
  float u, v;
  stex_csr_residual(p, reduce, x, y, &rx, &ry);
  stex_csr_phase(p, rx, ry, &u, &v);
  stex_i32 g[4];
  float w[4];
  stex_csr_nodes(p, fdata, u, v, g, w);
  stex_i64 per = stex_join64(p.cell_lo, p.cell_hi);
  float xm = (float)(x - stex_floordiv(x, per) * per) * p.inv_fix_scale; /* [0, T) model pixels */
  float ym = (float)(y - stex_floordiv(y, per) * per) * p.inv_fix_scale;
  const STEX_GLOBAL float* uf = fdata + p.union_off;
  const STEX_GLOBAL float* pw = uf + 2u * p.union_n;
  stex_u32 n = p.union_n;
  float acc = 0.0f;
  for (stex_u32 b = 0; b < n; ++b) {
    float s = ((w[0] * pw[(stex_u32)g[0] * n + b] + w[1] * pw[(stex_u32)g[1] * n + b]) + w[2] * pw[(stex_u32)g[2] * n + b]) +
              w[3] * pw[(stex_u32)g[3] * n + b];
    if (!(s > 0.0f)) continue;
    float kx = uf[2u * b], ky = uf[2u * b + 1u];
    stex_uvec4 r = stex_draw(stex_cell_key((stex_i64)kx, (stex_i64)ky), p.seed_lo, p.seed_hi, 0u, STEX_DOMAIN_CSR_F);
    acc += STEX_SQRTF(2.0f * s) * stex_gabor_cos2pi((kx * xm + ky * ym) * p.bin + stex_uniform24(r.x));
  }
  return acc;
}

/* The noise at fixed-point position (x, y) (2^16 units per output pixel). */
STEX_FN float stex_csr_eval(const stex_csr_params p, const STEX_GLOBAL float* fdata, const STEX_GLOBAL stex_u32* udata,
                            const STEX_GLOBAL stex_u32* reduce, const STEX_GLOBAL stex_u32* poisson, stex_i64 x,
                            stex_i64 y) {
  if (p.variant == STEX_CSR_RANDOM_PHASE) return p.mean + p.amplitude * stex_csr_random_phase(p, fdata, udata, reduce, x, y);
  if (p.variant == STEX_CSR_FOURIER) return p.mean + stex_csr_fourier(p, fdata, reduce, x, y);
  float re, im;
  stex_csr_impulses(p, fdata, udata, reduce, poisson, x, y, &re, &im);
  if (p.variant == STEX_CSR_GABOR) return p.mean + p.amplitude * re;
  float m2 = re * re + im * im;
  if (!(m2 > 0.0f)) return p.mean;
  stex_i64 rx, ry;
  float u, v;
  stex_csr_residual(p, reduce, x, y, &rx, &ry);
  stex_csr_phase(p, rx, ry, &u, &v);
  float e = stex_csr_energy(p, fdata, u, v);
  return p.mean + STEX_SQRTF(2.0f * e) * (im / STEX_SQRTF(m2));
}

#endif /* STEX_CS_RPN_H */
