/* Histogram transfer for cyclostationary textures (S4 §5.3): the inverse transfer T_b^-1 of polyphase bin b,
 * shared by the kernels of cs-spot and cs-tb (kernels/cs_spot.cl, kernels/tb.cl) and their C++ references.
 * The tables are built on the host (analysis/cs_hist.h); runtime/cs_hist.h documents the fields.
 *
 * Bins: the phase (u, v) in [0, 1)^2 of a point (its lattice coordinates modulo 1, eq. 2's P in the basis)
 * falls in bin (floor(u m0) mod m0, floor(v m1) mod m1). The analysis puts every exemplar texel (its centre)
 * in the bin of its phase; a render pixel (its centre, in model coordinates) reads the bin of its phase: a
 * deterministic P(x) for any period, integer or not. m0 = m1 = 1 is the stationary transfer (one bin).
 *
 * Inverse transfer of a Gaussian value g (T maps each bin's samples by rank to N(0.5, 1/6^2)):
 *   p = Phi((g - 0.5) * 6)   (a phi_size-entry table of the standard normal CDF on [phi_lo, phi_hi] in g,
 *                             linear interpolation, clamped: shared by all bins)
 *   T_b^-1(g) = Q_b(p)       (q quantiles of the bin's samples at p_k = (k + 1/2) / q, linear between them,
 *                             clamped to the first and last)
 * Only IEEE add, multiply, floor and conversions: kernel and reference agree bit for bit.
 *
 * Table layout (one float buffer): phi_size CDF values, then the quantiles ((j * m0 + i) * channels + c) * q + k,
 * then (basis == 1) the PCA basis: channels means, then channels x channels rows of B (y = B (x - mean)); the
 * transferred values are then PCA coordinates and stex_cs_hist_apply returns mean + B^T y.
 */
#ifndef STEX_CS_HIST_H
#define STEX_CS_HIST_H
#include "stex_platform.h"

/* 32 bytes; static_assert on the host. q == 0: no transfer (the tables are not read). */
typedef struct {
  stex_i32 m0, m1, q, channels;
  stex_i32 phi_size;
  float phi_lo, phi_scale; /* phi_scale = (phi_size - 1) / (phi_hi - phi_lo) */
  stex_i32 basis;          /* 1: the transfer is in a PCA basis stored after the quantiles (cs-spot) */
} stex_cs_hist_params;

/* The bin of phase (u, v) (any real: the bins are periodic). */
STEX_FN stex_i32 stex_cs_hist_bin(const stex_cs_hist_params h, float u, float v) {
  stex_i32 a = (stex_i32)STEX_FLOORF(u * (float)h.m0), b = (stex_i32)STEX_FLOORF(v * (float)h.m1);
  a = (a % h.m0 + h.m0) % h.m0;
  b = (b % h.m1 + h.m1) % h.m1;
  return b * h.m0 + a;
}

/* T_bin^-1(g) for channel c. */
STEX_FN float stex_cs_hist_inv(const stex_cs_hist_params h, const STEX_GLOBAL float* tab, stex_i32 bin, stex_i32 c,
                               float g) {
  float t = (g - h.phi_lo) * h.phi_scale;
  float mx = (float)(h.phi_size - 1);
  t = t < 0.0f ? 0.0f : (t > mx ? mx : t);
  float f0 = STEX_FLOORF(t);
  stex_i32 i = (stex_i32)f0;
  if (i > h.phi_size - 2) i = h.phi_size - 2;
  float f = t - (float)i;
  float p = tab[i] + f * (tab[i + 1] - tab[i]);
  float s = p * (float)h.q - 0.5f;
  float qm = (float)(h.q - 1);
  s = s < 0.0f ? 0.0f : (s > qm ? qm : s);
  float s0 = STEX_FLOORF(s);
  stex_i32 k = (stex_i32)s0;
  if (k > h.q - 2) k = h.q - 2;
  float fs = s - (float)k;
  const STEX_GLOBAL float* qv = tab + h.phi_size + (bin * h.channels + c) * h.q;
  return qv[k] + fs * (qv[k + 1] - qv[k]);
}

/* In place: v[c] <- T_bin^-1(v[c]) for every channel, then (basis) back to the colour basis. */
STEX_FN void stex_cs_hist_apply(const stex_cs_hist_params h, const STEX_GLOBAL float* tab, stex_i32 bin, float* v) {
  float t[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  stex_i32 ch = h.channels;
  for (stex_i32 c = 0; c < ch; ++c) t[c] = stex_cs_hist_inv(h, tab, bin, c, v[c]);
  if (h.basis) {
    const STEX_GLOBAL float* pca = tab + h.phi_size + h.m0 * h.m1 * ch * h.q;
    for (stex_i32 c = 0; c < ch; ++c) {
      float s = pca[c];
      for (stex_i32 d = 0; d < ch; ++d) s += pca[ch + d * ch + c] * t[d];
      v[c] = s;
    }
  } else {
    for (stex_i32 c = 0; c < ch; ++c) v[c] = t[c];
  }
}

#endif /* STEX_CS_HIST_H */
