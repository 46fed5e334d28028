/* Surface texton noise (S1 §6), shared by the OpenCL kernel (kernels/surface_points.cl) and the C++
 * reference (runtime/surface.h).
 *
 *   f^s(y) = sum_{x_i in Pi^3} (1 - 2|<y - x_i, u3>|/r)^+ h(<y - x_i, u1>, <y - x_i, u2>)       (S1 §6)
 *   g^s(y) = mean + (f^s(y) - lambda r/2 sum(alpha)) / sqrt(lambda r/3)                      (Proposition 3)
 *
 * Pi^3 is a 3-D Poisson process of intensity lambda = MNI / r^3 (Proposition 3: MNI = lambda r^3), (u1, u2,
 * u3) an orthonormal frame at y with u3 the normal, h the texton of S1 eq. 3 centred on its support: the
 * tap coordinate of z is z + (s - 1)/2, so h is non-zero on [-r/2, r/2)^2 with r = s + order (bilinear: the
 * alpha grid [0, s) widened by the kernel's 1-texel reach, the same r as the plane; nearest: r = s).
 *
 * Units: positions are world units; `inv_texel` maps them to texton units (exemplar pixels), where
 * everything below happens. The Poisson process lives on a grid of cubic cells of side a = c r (c = 0.6,
 * S1 §8, "also valid for the 3D Poisson point process"); cell k covers [k a, (k + 1) a)^3 and holds an
 * integer Poisson(lambda a^3) number of impulses (kernels/shared/poisson.h) drawn from the counter RNG keyed
 * by (seed, 3-D cell): impulse j sits at (k + u24) a per axis. A point sees every impulse within r sqrt(3)/2
 * (the cube of side r about y, Proposition 3's proof); the cells intersecting the axis-aligned box of that
 * radius, plus a margin for float rounding, are walked. Impulses outside the cube add nothing.
 *
 * Determinism: only IEEE add, multiply, floor, fabs-free compares and int->float conversions on positions,
 * no FMA contraction (stex_platform.h), and one global summation order (cells by (kz, ky, kx), impulses by j
 * ascending, dot products x + y + z left to right). Kernel and reference agree bit for bit.
 */
#ifndef STEX_SURFACE_H
#define STEX_SURFACE_H
#include "poisson.h"
#include "rng.h"
#include "stex_platform.h"
#include "texton.h"

#define STEX_DOMAIN_COUNT3 0x436e7433u   /* Poisson count of a 3-D cell ("Cnt3") */
#define STEX_DOMAIN_IMPULSE3 0x496d7033u /* impulse j of a 3-D cell: x, y, z, spare ("Imp3") */

/* Everything the surface evaluation needs besides the buffers; 32-bit fields only (96 bytes, static_assert
 * on the host). */
typedef struct {
  stex_i32 support;  /* s */
  stex_i32 channels; /* 1..4 */
  stex_i32 order;    /* 0 nearest, 1 bilinear */
  stex_i32 stride;   /* s + 2: padded planar alpha, as stex_texton_params */
  stex_u32 seed_lo, seed_hi;
  stex_u32 poisson_len; /* entries in the threshold table of the per-cell mean lambda a^3 */
  float inv_texel;      /* world units -> texton units */
  float cell;           /* a, cell side in texton units */
  float inv_cell;       /* 1 / a */
  float reach;          /* half side of the axis-aligned box about y that holds every contributing impulse */
  float two_over_r;     /* 2 / r: the weight (1 - 2|t|/r)^+ */
  float centre;         /* (s - 1)/2: tap coordinate of z = 0 */
  float t_lo, t_hi;     /* tap support [t_lo, t_hi) (texton.h) */
  float inv_norm;       /* 1 / sqrt(lambda r / 3) (Proposition 3) */
  float mean[STEX_MAX_CHANNELS];
  float lambda_half_r_sum_alpha[STEX_MAX_CHANNELS]; /* lambda r/2 sum(alpha): E f^s (Proposition 3) */
} stex_surface_params;

/* Key of a 3-D cell: the 2-D key of (cx, cy) with cz absorbed by one more round. A hash (not injective
 * over all int64 triples), with the avalanche of pcg4d; its streams are separated from the plane's by the
 * 3-D domains above. */
STEX_FN stex_uvec4 stex_cell_key3(stex_i64 cx, stex_i64 cy, stex_i64 cz) {
  stex_uvec4 v = stex_cell_key(cx, cy);
  v.x ^= stex_lo32(cz);
  v.y ^= stex_hi32(cz);
  v.z ^= 0x33443344u;
  return stex_pcg4d(v);
}

STEX_FN stex_u32 stex_surface_count(const stex_surface_params p, const stex_uvec4 key,
                                    const STEX_GLOBAL stex_u32* poisson_table) {
  stex_uvec4 v = stex_draw(key, p.seed_lo, p.seed_hi, 0u, STEX_DOMAIN_COUNT3);
  return stex_poisson_count(poisson_table, p.poisson_len, v.x);
}

/* Position (texton units) of impulse j of cell (kx, ky, kz). */
STEX_FN void stex_surface_impulse(const stex_surface_params p, const stex_uvec4 key, stex_i64 kx, stex_i64 ky,
                                  stex_i64 kz, stex_u32 j, float* x, float* y, float* z) {
  stex_uvec4 v = stex_draw(key, p.seed_lo, p.seed_hi, j, STEX_DOMAIN_IMPULSE3);
  *x = ((float)kx + stex_uniform24(v.x)) * p.cell;
  *y = ((float)ky + stex_uniform24(v.y)) * p.cell;
  *z = ((float)kz + stex_uniform24(v.z)) * p.cell;
}

/* Unnormalised f^s at position q (texton units) with frame u1, u2, u3 (9 floats: u1x u1y u1z u2x ...):
 * acc[c] for c < channels. */
STEX_FN void stex_surface_sum(const stex_surface_params p, const STEX_GLOBAL float* alpha,
                              const STEX_GLOBAL stex_u32* poisson_table, float qx, float qy, float qz,
                              const float* u, float* acc) {
  for (int c = 0; c < STEX_MAX_CHANNELS; ++c) acc[c] = 0.0f;
  const stex_i64 kx0 = (stex_i64)STEX_FLOORF((qx - p.reach) * p.inv_cell);
  const stex_i64 kx1 = (stex_i64)STEX_FLOORF((qx + p.reach) * p.inv_cell);
  const stex_i64 ky0 = (stex_i64)STEX_FLOORF((qy - p.reach) * p.inv_cell);
  const stex_i64 ky1 = (stex_i64)STEX_FLOORF((qy + p.reach) * p.inv_cell);
  const stex_i64 kz0 = (stex_i64)STEX_FLOORF((qz - p.reach) * p.inv_cell);
  const stex_i64 kz1 = (stex_i64)STEX_FLOORF((qz + p.reach) * p.inv_cell);
  const stex_i32 plane = p.stride * p.stride;
  for (stex_i64 kz = kz0; kz <= kz1; ++kz) {
    for (stex_i64 ky = ky0; ky <= ky1; ++ky) {
      for (stex_i64 kx = kx0; kx <= kx1; ++kx) {
        stex_uvec4 key = stex_cell_key3(kx, ky, kz);
        stex_u32 n = stex_surface_count(p, key, poisson_table);
        for (stex_u32 j = 0; j < n; ++j) {
          float xi, yi, zi;
          stex_surface_impulse(p, key, kx, ky, kz, j, &xi, &yi, &zi);
          const float dx = qx - xi, dy = qy - yi, dz = qz - zi; /* y - x_i */
          const float t = dx * u[6] + dy * u[7] + dz * u[8];
          const float at = t < 0.0f ? -t : t;
          const float w = 1.0f - p.two_over_r * at;
          if (!(w > 0.0f)) continue;
          const float tx = (dx * u[0] + dy * u[1] + dz * u[2]) + p.centre;
          const float ty = (dx * u[3] + dy * u[4] + dz * u[5]) + p.centre;
          if (!((tx >= p.t_lo) && (tx < p.t_hi) && (ty >= p.t_lo) && (ty < p.t_hi))) continue;
          float fx0, fy0, fx, fy;
          if (p.order == 0) {
            fx0 = STEX_FLOORF(tx + 0.5f);
            fy0 = STEX_FLOORF(ty + 0.5f);
            fx = 0.0f;
            fy = 0.0f;
          } else {
            fx0 = STEX_FLOORF(tx);
            fy0 = STEX_FLOORF(ty);
            fx = tx - fx0;
            fy = ty - fy0;
          }
          const float w00 = w * ((1.0f - fx) * (1.0f - fy));
          const float w10 = w * (fx * (1.0f - fy));
          const float w01 = w * ((1.0f - fx) * fy);
          const float w11 = w * (fx * fy);
          const stex_i32 idx = ((stex_i32)fy0 + 1) * p.stride + ((stex_i32)fx0 + 1);
          for (int c = 0; c < p.channels; ++c)
            acc[c] += stex_texton_fetch(alpha + c * plane, idx, p.stride, w00, w10, w01, w11);
        }
      }
    }
  }
}

/* Normalised surface noise g^s at world position (wx, wy, wz) with orthonormal frame u (9 floats, see
 * stex_surface_sum): out[c] for c < channels (Proposition 3). */
STEX_FN void stex_surface_eval(const stex_surface_params p, const STEX_GLOBAL float* alpha,
                               const STEX_GLOBAL stex_u32* poisson_table, float wx, float wy, float wz,
                               const float* u, float* out) {
  float acc[STEX_MAX_CHANNELS];
  stex_surface_sum(p, alpha, poisson_table, wx * p.inv_texel, wy * p.inv_texel, wz * p.inv_texel, u, acc);
  for (int c = 0; c < p.channels; ++c) out[c] = p.mean[c] + (acc[c] - p.lambda_half_r_sum_alpha[c]) * p.inv_norm;
}

#endif /* STEX_SURFACE_H */
