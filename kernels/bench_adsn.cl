/* ADSN by FFT on the device, the comparison baseline of `stex bench` (issue #5; S1 §3.1-3.2, S2 §2.1/§2.4):
 * mean + t_u (*) W, the circular convolution of the exemplar's normalised periodic component t_u with a
 * standard Gaussian white noise W, computed as IFFT(FFT(W) . FFT(t_u)) with the device FFT of
 * analysis/device_fft.h (clFFT). These kernels are the steps around the transforms; FFT(t_u) is computed once
 * on the host (setup, not timed). benchmarks/lib/adsn_baseline.h drives them. Not a product path: the host
 * ADSN of `stex render --mode adsn` is analysis/gaussian_synthesis.h.
 *
 * Complex arrays are interleaved float2, row-major on the FFT domain (dw x dh).
 */
#include "shared/rng.h"

#define BENCH_ADSN_DOMAIN 0x41444e42u /* "ADNB": the benchmark's own noise stream */

/* W(i, j) for domain pixel (i, j) = output pixel (x0 + i, y0 + j): Box-Muller on two 24-bit uniforms of the
 * counter RNG keyed by the pixel (native_* transcendentals: speed, not bit-identity, is the point here). */
__kernel void bench_adsn_noise(const uint seed_lo, const uint seed_hi, const int x0, const int y0, const int dw,
                               const int dh, __global float2* out) {
  const int i = (int)get_global_id(0), j = (int)get_global_id(1);
  if (i >= dw || j >= dh) return;
  const stex_uvec4 v = stex_draw(stex_cell_key((long)(x0 + i), (long)(y0 + j)), seed_lo, seed_hi, 0u,
                                 BENCH_ADSN_DOMAIN);
  const float u1 = ((float)(v.x >> 8) + 0.5f) * 5.9604644775390625e-8f;
  const float u2 = (float)(v.y >> 8) * 5.9604644775390625e-8f;
  out[(size_t)j * (size_t)dw + (size_t)i] =
      (float2)(native_sqrt(-2.0f * native_log(u1)) * native_cos(6.28318530718f * u2), 0.0f);
}

/* out = a . b[b_offset ..] (complex products), n elements. */
__kernel void bench_adsn_multiply(__global const float2* a, __global const float2* b, const int b_offset,
                                  __global float2* out, const int n) {
  const int k = (int)get_global_id(0);
  if (k >= n) return;
  const float2 x = a[k], y = b[(size_t)b_offset + (size_t)k];
  out[k] = (float2)(x.x * y.x - x.y * y.y, x.x * y.y + x.y * y.x);
}

/* One channel's plane of the output (starting at out[out_offset]): mean + Re(in) on the width x height
 * corner of the domain. */
__kernel void bench_adsn_finish(__global const float2* in, const int dw, const int width, const int height,
                                const float mean, __global float* out, const int out_offset) {
  const int i = (int)get_global_id(0), j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  out[(size_t)out_offset + (size_t)j * (size_t)width + (size_t)i] = mean + in[(size_t)j * (size_t)dw + (size_t)i].x;
}
