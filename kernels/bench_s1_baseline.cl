/* The S1 texton noise evaluation AS PUBLISHED (S1 §8), kept as a PERFORMANCE BASELINE for `stex bench`
 * (issue #5): the algorithm stex's own kernels improve on, measured on the same device in the same run.
 * It is not a product path and is not bit-identical to anything; tests only check its mean and variance
 * (tests/kernels/test_bench_baselines.cpp). Written from the paper's description and what is known of
 * the authors' shader's behaviour (below), not from the authors' code.
 *
 * What S1 §8 (and the authors' shader) does, and this kernel repeats:
 *  - one work-item per pixel regenerates, for every pixel, the impulses of every grid cell that may reach
 *    it (gather; nothing is shared between pixels);
 *  - grid cells of side a = r / 1.6 (r = s + 1, the bilinear texton's reach), so the per-cell Poisson mean
 *    is lambda a^2 = MNI / 1.6^2 (11.7 at MNI 30);
 *  - a per-cell Xorshift PRNG (Marsaglia) seeded by an integer hash of the cell coordinates;
 *  - the impulse count drawn from the Gaussian approximation of the Poisson law, Box-Muller:
 *    n = floor(lambda a^2 + 1/2 + sqrt(lambda a^2) g), g ~ N(0, 1);
 *  - impulse positions uniform in the cell from the same Xorshift stream, float coordinates;
 *  - a bilinear fetch of the texton per impulse that covers the pixel (manual bilinear from a buffer: on
 *    PoCL's CPU device read_imagef with linear filtering is 5-12x slower (PoCL 3.1); on a GPU the
 *    shader's texture unit would do it), then S1 eq. 2's normalisation.
 * Where the authors' shader has undefined behaviour or a defect, this baseline takes the defined choice that
 * costs the same: a negative Gaussian count (probability ~1.8e-4 per cell at MNI 30; the shader casts it to
 * unsigned, undefined behaviour) is clamped to 0; the Xorshift state is forced non-zero (the shader's hash can
 * return the stuck state 0); cell seeds are not periodic. Transcendentals are native_* (GLSL's log/cos/sqrt
 * carry no accuracy guarantee either; on PoCL 3.1 the precise ones are not vectorised): the
 * baseline is not handicapped by precision stex does not need here.
 *
 * stex's own kernels NEVER do any of this: their counts are exact Poisson variates from an integer threshold
 * table (kernels/shared/poisson.h), their impulses come from a counter-based hash keyed by (seed, cell, index)
 * (kernels/shared/rng.h), their positions are int64 fixed point, and every strategy is bit-identical to the
 * C++ reference (kernels/shared/texton.h).
 *
 * Build option -DS1_CHANNELS=<1..4>. Alpha: the padded planar planes of stex (runtime/texton_params.h: one
 * (s+2)^2 plane per channel, zero frame of 1). Output: planar float, channel c of pixel (i, j) at
 * out[c * pitch * height + j * pitch + i]. Global size >= (width, height); extra work-items return.
 */
#ifndef S1_CHANNELS
#error "bench_s1_baseline.cl needs -DS1_CHANNELS=<channels>"
#endif

/* Seed of a cell's Xorshift stream: the cell coordinates and the seed mixed into one word, then the
 * murmur3 32-bit finaliser for avalanche. Xorshift's state must never be 0 (it would stay 0). */
static inline uint s1_cell_seed(int cx, int cy, uint seed) {
  uint h = ((uint)cx * 0x9e3779b1u) ^ ((uint)cy * 0x85ebca77u) ^ seed;
  h ^= h >> 16;
  h *= 0x85ebca6bu;
  h ^= h >> 13;
  h *= 0xc2b2ae35u;
  h ^= h >> 16;
  return h != 0u ? h : 0x6d2b79f5u;
}

/* Marsaglia's xorshift32 (shifts 13, 17, 5); uniform float in [0, 1) from its top 24 bits. */
static inline float s1_uniform(uint* state) {
  uint x = *state;
  x ^= x << 13;
  x ^= x >> 17;
  x ^= x << 5;
  *state = x;
  return (float)(x >> 8) * (1.0f / 16777216.0f);
}

__kernel void bench_s1_baseline(__global const float* alpha, const int stride, const float t_lo, const float t_hi,
                                const float cell, const float inv_cell, const float cell_mean, const float cell_sd,
                                const uint seed, const float inv_sqrt_lambda, const float4 mean,
                                const float4 lambda_sum_alpha, const int x0, const int y0, const int width,
                                const int height, const int pitch, __global float* out) {
  const int i = (int)get_global_id(0);
  const int j = (int)get_global_id(1);
  if (i >= width || j >= height) return;
  const int aplane = stride * stride;
  const float px = (float)(x0 + i) + 0.5f;
  const float py = (float)(y0 + j) + 0.5f;
  /* Impulses at x_j with px - x_j in [t_lo, t_hi) reach the pixel: cells from (px - t_hi)/a to (px - t_lo)/a. */
  const int kx0 = (int)floor((px - t_hi) * inv_cell), kx1 = (int)floor((px - t_lo) * inv_cell);
  const int ky0 = (int)floor((py - t_hi) * inv_cell), ky1 = (int)floor((py - t_lo) * inv_cell);
  float acc[S1_CHANNELS];
  for (int c = 0; c < S1_CHANNELS; ++c) acc[c] = 0.0f;

  for (int ky = ky0; ky <= ky1; ++ky) {
    for (int kx = kx0; kx <= kx1; ++kx) {
      uint state = s1_cell_seed(kx, ky, seed);
      /* Gaussian-approximated Poisson count (Box-Muller), clamped at 0 (see the header). */
      const float u1 = 1.0f - s1_uniform(&state); /* (0, 1] */
      const float u2 = s1_uniform(&state);
      const float g = native_sqrt(-2.0f * native_log(u1)) * native_cos(6.28318530718f * u2);
      const int n = max((int)floor(cell_mean + 0.5f + cell_sd * g), 0);
      for (int k = 0; k < n; ++k) {
        const float xj = ((float)kx + s1_uniform(&state)) * cell;
        const float yj = ((float)ky + s1_uniform(&state)) * cell;
        const float tx = px - xj, ty = py - yj;
        if (tx >= t_lo && tx < t_hi && ty >= t_lo && ty < t_hi) {
          const float fx0 = floor(tx), fy0 = floor(ty);
          const float fx = tx - fx0, fy = ty - fy0;
          const float w00 = (1.0f - fx) * (1.0f - fy), w10 = fx * (1.0f - fy);
          const float w01 = (1.0f - fx) * fy, w11 = fx * fy;
          const int idx = ((int)fy0 + 1) * stride + (int)fx0 + 1;
          for (int c = 0; c < S1_CHANNELS; ++c) {
            __global const float* a = alpha + c * aplane + idx;
            acc[c] += w00 * a[0] + w10 * a[1] + w01 * a[stride] + w11 * a[stride + 1];
          }
        }
      }
    }
  }

  const size_t plane = (size_t)pitch * (size_t)height;
  const size_t at = (size_t)j * (size_t)pitch + (size_t)i;
  const float m[4] = {mean.x, mean.y, mean.z, mean.w};
  const float l[4] = {lambda_sum_alpha.x, lambda_sum_alpha.y, lambda_sum_alpha.z, lambda_sum_alpha.w};
  for (int c = 0; c < S1_CHANNELS; ++c) out[(size_t)c * plane + at] = m[c] + (acc[c] - l[c]) * inv_sqrt_lambda;
}
