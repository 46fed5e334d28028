/* Gabor noise by sparse convolution (Lagae, Lefebvre, Drettakis, Dutré, "Procedural noise using sparse Gabor
 * convolution", SIGGRAPH 2009; the noise of the spectrum-of-variance paper, S5 Fig. 1-4, 9), shared by the
 * OpenCL kernel (kernels/gabor_gather.cl) and the C++ reference (runtime/gabor_params.h).
 *
 *   n(x) = sum_i w_i g(x - x_i; F_i, theta_i),   g(d; F, theta) = exp(-pi a^2 |d|^2) cos(2 pi F (d . (cos theta, sin theta)))
 *   f(x) = mean + std * n(x) / sigma_n,          sigma_n^2 = lambda / (4 a^2) sum_k p_k (1 + exp(-2 pi F_k^2 / a^2))
 *
 * The impulses x_i are a Poisson process of intensity lambda (impulses per model pixel^2), on the same
 * fixed-point cell grid as texton noise (kernels/shared/texton.h): integer Poisson counts per cell
 * (poisson.h), positions from the counter RNG keyed by (seed, cell, j) (rng.h). Each impulse also draws,
 * from the same 4 words, its spectral component k (an integer inverse-CDF search of the component weights
 * p_k: arbitrary PSDs are sums of components), its orientation theta = omega_k + spread_k (u - 1/2)
 * (spread 0: anisotropic; spread 1 turn: isotropic) and its weight w_i = +-1 (Lagae et al.'s random weights).
 * Orientations are stored in turns (1 turn = 2 pi).
 *
 * The Gaussian envelope is truncated where it falls below 2^-12 (|d|^2 >= r2_max = 12 / (pi a^2 log2 e)).
 * exp and cos are evaluated by polynomials here (stex_gabor_exp2, stex_gabor_cos2pi) with IEEE add, multiply
 * and floor only, so that the kernel and the C++ reference agree bit for bit (OpenCL's exp/cos differ from
 * glibc by up to 3 ulp, measured on PoCL 3.1). Their absolute error against the true functions is below 1e-7.
 *
 * Filtering (a minified view; runtime/gabor_params.h): the host passes the kernel convolved with the pixel's
 * Gaussian footprint, which is again a Gabor kernel (a wider envelope, a lower carrier, a gain per component:
 * c[5]), so the same code evaluates both. Unfiltered, every gain is 1 and the bits are those of the plain
 * kernel.
 *
 * Summation order is global (cells by (ky, kx), impulses by j): every tiling, chunking and work-group size
 * gives the same bits.
 */
#ifndef STEX_GABOR_H
#define STEX_GABOR_H
#include "poisson.h"
#include "rng.h"
#include "stex_platform.h"

#define STEX_GABOR_FIX_BITS 16
#define STEX_GABOR_COMPONENT_FLOATS 8 /* fx, fy, frequency, omega (turns), spread (turns), gain, 0, 0 */
#define STEX_GABOR_MAX_COMPONENTS 4096

/* 64 bytes; static_assert on the host. */
typedef struct {
  stex_u32 seed_lo, seed_hi;
  stex_u32 cell_lo, cell_hi;   /* A: cell side in fixed units (int64) */
  stex_u32 reach_lo, reach_hi; /* impulses within reach (fixed units) of a point may cover it (int64) */
  float inv_fix_scale;         /* 1 / (2^F scale): fixed units -> model pixels */
  float exp2_factor;           /* pi a^2 log2(e): envelope = 2^(-exp2_factor |d|^2) */
  float r2_max;                /* squared truncation radius (model pixels^2) */
  float mean;                  /* output mean */
  float amplitude;             /* std / sigma_n */
  stex_u32 poisson_len;        /* entries of the per-cell Poisson threshold table */
  stex_u32 components;         /* entries of the component table (1..STEX_GABOR_MAX_COMPONENTS) */
  stex_u32 pad0, pad1, pad2;
} stex_gabor_params;

STEX_FN stex_i64 stex_gabor_pixel_fix(stex_i64 p) { return (2 * p + 1) * ((stex_i64)1 << (STEX_GABOR_FIX_BITS - 1)); }

#ifdef __OPENCL_C_VERSION__
#define STEX_GABOR_FABSF(x) fabs(x)
#else
#define STEX_GABOR_FABSF(x) std::fabs(x)
#endif

/* cos(2 pi t) for |t| < 2^22: reduction to s = |t - round(t)| in [0, 1/2] (exact), then to [0, 1/4] by
 * cos(2 pi s) = -cos(2 pi (1/2 - s)) (exact by Sterbenz), then the Taylor series in z = s^2 to degree 12 in
 * s (truncation error (pi/2)^14 / 14! < 7e-9). */
STEX_FN float stex_gabor_cos2pi(float t) {
  float s = STEX_GABOR_FABSF(t - STEX_FLOORF(t + 0.5f));
  float sign = 1.0f;
  if (s > 0.25f) {
    s = 0.5f - s;
    sign = -1.0f;
  }
  float z = s * s;
  /* c_n = (-1)^n (2 pi)^(2n) / (2n)! */
  float p = 7.9035363713e0f;     /* n = 6 */
  p = p * z + -2.6426256783e1f; /* n = 5 */
  p = p * z + 6.0244641372e1f;  /* n = 4 */
  p = p * z + -8.5456817207e1f; /* n = 3 */
  p = p * z + 6.4939394023e1f;  /* n = 2 */
  p = p * z + -1.9739208802e1f; /* n = 1 */
  p = p * z + 1.0f;
  return sign * p;
}

/* 2^x for x in [-12, 0]: x = k + f with k = floor(x), f in [0, 1) (exact); 2^f by its Taylor series to
 * degree 9 (error (ln 2)^10 / 10! < 7e-9), then k exact halvings (no subnormals: the result is >= 2^-12). */
STEX_FN float stex_gabor_exp2(float x) {
  float k = STEX_FLOORF(x);
  float f = x - k;
  /* (ln 2)^n / n! */
  float p = 1.0178086e-07f;
  p = p * f + 1.3215487e-06f;
  p = p * f + 1.5252734e-05f;
  p = p * f + 1.5403530e-04f;
  p = p * f + 1.3333558e-03f;
  p = p * f + 9.6181291e-03f;
  p = p * f + 5.5504109e-02f;
  p = p * f + 2.4022651e-01f;
  p = p * f + 6.9314718e-01f;
  p = p * f + 1.0f;
  for (stex_i32 i = (stex_i32)k; i < 0; ++i) p *= 0.5f;
  return p;
}

/* Cells [k0, k1] whose impulses may reach a point with fixed coordinate in [xmin, xmax]. */
STEX_FN void stex_gabor_cell_range(const stex_gabor_params p, stex_i64 xmin, stex_i64 xmax, stex_i64* k0,
                                   stex_i64* k1) {
  stex_i64 a = stex_join64(p.cell_lo, p.cell_hi);
  stex_i64 reach = stex_join64(p.reach_lo, p.reach_hi);
  *k0 = stex_floordiv(xmin - reach, a);
  *k1 = stex_floordiv(xmax + reach, a);
}

/* Contribution of impulse j of cell (kx, ky) (key = stex_cell_key(kx, ky)) at fixed point (x, y). */
STEX_FN float stex_gabor_impulse(const stex_gabor_params p, const STEX_GLOBAL float* comp,
                                 const STEX_GLOBAL stex_u32* comp_table, const stex_uvec4 key, stex_i64 kx, stex_i64 ky,
                                 stex_u32 j, stex_i64 x, stex_i64 y) {
  stex_uvec4 v = stex_draw(key, p.seed_lo, p.seed_hi, j, STEX_DOMAIN_IMPULSE);
  stex_i64 a = stex_join64(p.cell_lo, p.cell_hi);
  stex_i64 xj = kx * a + (stex_i64)(((stex_u64)(v.x >> 8) * (stex_u64)a) >> 24);
  stex_i64 yj = ky * a + (stex_i64)(((stex_u64)(v.y >> 8) * (stex_u64)a) >> 24);
  float dx = (float)(x - xj) * p.inv_fix_scale;
  float dy = (float)(y - yj) * p.inv_fix_scale;
  float r2 = dx * dx + dy * dy;
  if (r2 >= p.r2_max) return 0.0f;
  float env = stex_gabor_exp2(-(p.exp2_factor * r2));
  stex_u32 k = stex_poisson_count(comp_table, p.components, v.z);
  const STEX_GLOBAL float* c = comp + k * STEX_GABOR_COMPONENT_FLOATS;
  float fx = c[0], fy = c[1];
  if (c[4] != 0.0f) {
    float theta = c[3] + c[4] * (stex_uniform24(v.w) - 0.5f);
    fx = c[2] * stex_gabor_cos2pi(theta);
    fy = c[2] * stex_gabor_cos2pi(theta - 0.25f);
  }
  float g = (env * c[5]) * stex_gabor_cos2pi(fx * dx + fy * dy); /* gain c[5] = 1 unfiltered: env * 1 = env */
  return (v.w & 1u) ? -g : g;
}

/* Gather evaluation at one fixed-point position: the kernel and the C++ reference both call it. */
STEX_FN float stex_gabor_eval(const stex_gabor_params p, const STEX_GLOBAL float* comp,
                              const STEX_GLOBAL stex_u32* comp_table, const STEX_GLOBAL stex_u32* poisson_table,
                              stex_i64 x, stex_i64 y) {
  float acc = 0.0f;
  stex_i64 kx0, kx1, ky0, ky1;
  stex_gabor_cell_range(p, x, x, &kx0, &kx1);
  stex_gabor_cell_range(p, y, y, &ky0, &ky1);
  for (stex_i64 ky = ky0; ky <= ky1; ++ky) {
    for (stex_i64 kx = kx0; kx <= kx1; ++kx) {
      stex_uvec4 key = stex_cell_key(kx, ky);
      stex_uvec4 cv = stex_draw(key, p.seed_lo, p.seed_hi, 0u, STEX_DOMAIN_COUNT);
      stex_u32 n = stex_poisson_count(poisson_table, p.poisson_len, cv.x);
      for (stex_u32 j = 0; j < n; ++j) acc += stex_gabor_impulse(p, comp, comp_table, key, kx, ky, j, x, y);
    }
  }
  return p.mean + p.amplitude * acc;
}

#endif /* STEX_GABOR_H */
