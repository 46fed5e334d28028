/* Noise mixing (S1 §7): texton noise with spatially varying textons, shared by the OpenCL kernel
 * (kernels/mix_gather.cl) and the C++ reference (runtime/mix_model.h).
 *
 * S1 §7 defines, for a partition D_1..D_R of the plane and textons h_1..h_R, the mixed shot noise
 *
 *   f_lambda(x) = sum_{(x_j, eps_j) in Pi^M_lambda} sum_{1 <= r <= R} eps_j h_r(x - x_j) 1_{x_j in D_r},
 *
 * "Given the marked Poisson point process Pi^M_lambda of intensity lambda/2 on R^2 x {-1, 1}": every impulse
 * carries a random weight eps_j uniform on {-1, 1}, so f has null expectation whatever the sums of the h_r,
 * and g_lambda = f_lambda / sqrt(lambda) tends to a Gaussian field. "The noise mixing is then obtained by
 * sampling f_lambda / sqrt(lambda) and adding a linear interpolation of the mean values of u and v":
 *
 *   out(x) = (1 - rho(x)) m0 + rho(x) m1 + f_lambda(x) / sqrt(lambda).
 *
 * Here the textons are h_r = the texton of alpha_{rho_r}, rho_r = r / (K - 1), r = 0..K-1 (S1: "the textures
 * (h_r) associated with (tau_{(r-1)/(R-1)})"), and the partition comes from a mixing map rho(x) in [0, 1]:
 * D_r = { x : the level nearest to rho(x) is r }, i.e. r(x_j) = floor(rho(x_j) (K - 1) + 1/2). S1 Fig. 5's
 * R vertical strips are the ramp map below quantised this way; any grey image gives any partition. The
 * texton of an impulse is chosen from rho at the impulse x_j (not at the pixel), so each texton copy is
 * whole and the field is continuous across region boundaries ("the kernel functions are locally blended").
 * S1 §8's kernel has its support [-r/2, r/2]^2 around x_j, while texton.h anchors the texton at its top-left
 * (h is non-zero on [-(k+1)/2, s - 1 + (k+1)/2)^2 of the displacement): the paper's x_j is the texton's centre,
 * x_j + (s - 1)/2 texton pixels on each axis, and that is where rho is read (so regions and the texture they
 * draw line up).
 *
 * The impulses are those of texton noise (kernels/shared/texton.h: integer Poisson counts per cell,
 * positions from the counter RNG keyed by (seed, cell, j)); eps_j is bit 0 of the draw's spare word
 * `mark`. Intensity lambda = MNI / r^2 with both signs together, as in texton noise.
 *
 * Mixing maps, in output pixels (fixed point, STEX_FIX_BITS fractional bits, like every position):
 *  - const:   rho = c;
 *  - ramp:    rho = clamp((X - X0) / (X1 - X0), 0, 1) (X1 < X0 reverses it);
 *  - strips:  period P, rho = 0 on [0, P/2), 1 on [P/2, P) (mod P), each edge a linear ramp of width W
 *             centred on it (W = 0: hard edges; W <= P/2);
 *  - image:   a grey map of w x h pixels, pixel (i, j) centred at O + (i + 1/2, j + 1/2) S (S output pixels
 *             per map pixel), bilinear between centres, outside the map repeated or clamped to its edge.
 * Every map is an integer computation on the fixed-point position up to one int64 -> float conversion of an
 * exact offset, then IEEE float add/multiply/floor: host and device agree bit for bit, at 10^12 as at 0.
 *
 * A filtered minified view (docs/filtering.md) is the same sum with each level's texton convolved with the
 * pixel's box: the host passes the box-prefiltered tables as the K textons (bilinear, their own support and
 * texel) and `shift`, the whole output pixels their sample 0 lies before the impulse, added to every
 * displacement (an exact integer; 0 unfiltered, which changes no bit).
 */
#ifndef STEX_MIX_H
#define STEX_MIX_H
#include "texton.h"

#define STEX_MIX_MAX_LEVELS 257
#define STEX_MIX_MAP_CONST 0
#define STEX_MIX_MAP_RAMP 1
#define STEX_MIX_MAP_STRIPS 2
#define STEX_MIX_MAP_IMAGE 3
#define STEX_MIX_WRAP_REPEAT 0
#define STEX_MIX_WRAP_CLAMP 1

/* 104 bytes; static_assert on the host. */
typedef struct {
  stex_i32 levels;       /* K >= 2 */
  stex_i32 level_floats; /* floats per level in the alpha buffer (a padded texton of texton.h) */
  stex_i32 map_type;     /* STEX_MIX_MAP_* */
  stex_i32 map_wrap;     /* image: STEX_MIX_WRAP_* */
  stex_u32 a_lo, a_hi;   /* ramp: X0; strips: P; image: origin x (fixed units, int64) */
  stex_u32 b_lo, b_hi;   /* strips: W; image: origin y */
  stex_u32 c_lo, c_hi;   /* image: S, the map pixel side (fixed units, even) */
  float rho_const;       /* const: rho */
  float inv_len;         /* ramp: 1 / (X1 - X0); strips: 1 / W (0 if W = 0); image: 1 / S (per fixed unit) */
  stex_i32 map_width, map_height; /* image: w, h */
  float mean0[STEX_MAX_CHANNELS], mean1[STEX_MAX_CHANNELS]; /* m0 (rho = 0, exemplar u), m1 (rho = 1, v) */
  stex_u32 centre_lo, centre_hi; /* texton centre relative to its impulse, per axis (fixed units, int64) */
  stex_u32 shift_lo, shift_hi;   /* added to every displacement (fixed units, int64): 0, or the box prefilter's
                                    whole-pixel shift (runtime/mix_model.h) */
} stex_mix_params;

STEX_FN float stex_mix_clamp01(float v) { return v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v); }

STEX_FN stex_i64 stex_mix_floormod(stex_i64 a, stex_i64 b) { return a - stex_floordiv(a, b) * b; }

/* Map index i wrapped into [0, n) (repeat) or clamped to it. */
STEX_FN stex_i64 stex_mix_wrap(stex_i64 i, stex_i64 n, stex_i32 wrap) {
  if (wrap == STEX_MIX_WRAP_CLAMP) return i < 0 ? 0 : (i >= n ? n - 1 : i);
  return stex_mix_floormod(i, n);
}

/* Strips: rho at phase q = (X mod P), edges at 0 (rho 1 -> 0) and P/2 (rho 0 -> 1). */
STEX_FN float stex_mix_strips(const stex_mix_params m, stex_i64 x) {
  const stex_i64 period = stex_join64(m.a_lo, m.a_hi);
  const stex_i64 mid = period / 2, quarter = period / 4;
  stex_i64 q = stex_mix_floormod(x, period);
  if (q >= period - quarter) q -= period; /* q in [-P/4, 3P/4) */
  if (q < quarter) {                      /* around the edge at 0 */
    if (m.inv_len == 0.0f) return q < 0 ? 1.0f : 0.0f;
    return stex_mix_clamp01(0.5f - (float)q * m.inv_len);
  }
  if (m.inv_len == 0.0f) return q >= mid ? 1.0f : 0.0f; /* around the edge at P/2 */
  return stex_mix_clamp01(0.5f + (float)(q - mid) * m.inv_len);
}

/* Image: bilinear between pixel centres. */
STEX_FN float stex_mix_image(const stex_mix_params m, const STEX_GLOBAL float* map, stex_i64 x, stex_i64 y) {
  const stex_i64 side = stex_join64(m.c_lo, m.c_hi);
  const stex_i64 dx = x - stex_join64(m.a_lo, m.a_hi) - side / 2;
  const stex_i64 dy = y - stex_join64(m.b_lo, m.b_hi) - side / 2;
  const stex_i64 ix = stex_floordiv(dx, side), iy = stex_floordiv(dy, side);
  const float fx = (float)(dx - ix * side) * m.inv_len;
  const float fy = (float)(dy - iy * side) * m.inv_len;
  const stex_i64 w = m.map_width, h = m.map_height;
  const stex_i64 x0 = stex_mix_wrap(ix, w, m.map_wrap), x1 = stex_mix_wrap(ix + 1, w, m.map_wrap);
  const stex_i64 y0 = stex_mix_wrap(iy, h, m.map_wrap), y1 = stex_mix_wrap(iy + 1, h, m.map_wrap);
  const float top = (1.0f - fx) * map[y0 * w + x0] + fx * map[y0 * w + x1];
  const float bottom = (1.0f - fx) * map[y1 * w + x0] + fx * map[y1 * w + x1];
  return stex_mix_clamp01((1.0f - fy) * top + fy * bottom);
}

/* rho(X) in [0, 1] at a fixed-point position. */
STEX_FN float stex_mix_rho(const stex_mix_params m, const STEX_GLOBAL float* map, stex_i64 x, stex_i64 y) {
  if (m.map_type == STEX_MIX_MAP_RAMP)
    return stex_mix_clamp01((float)(x - stex_join64(m.a_lo, m.a_hi)) * m.inv_len);
  if (m.map_type == STEX_MIX_MAP_STRIPS) return stex_mix_strips(m, x);
  if (m.map_type == STEX_MIX_MAP_IMAGE) return stex_mix_image(m, map, x, y);
  return m.rho_const;
}

/* The region D_r of a rho: the nearest level r = floor(rho (K - 1) + 1/2), in [0, K - 1]. */
STEX_FN stex_i32 stex_mix_level(const stex_mix_params m, float rho) {
  stex_i32 r = (stex_i32)STEX_FLOORF(rho * (float)(m.levels - 1) + 0.5f);
  return r < 0 ? 0 : (r > m.levels - 1 ? m.levels - 1 : r);
}

/* Whether a displacement (fixed units) lies in the texton's support (the test of stex_texton_tap). */
STEX_FN int stex_mix_covers(const stex_texton_params p, stex_i64 dx, stex_i64 dy) {
  const float tx = (float)dx * p.inv_fix_scale;
  const float ty = (float)dy * p.inv_fix_scale;
  return (tx >= p.t_lo) && (tx < p.t_hi) && (ty >= p.t_lo) && (ty < p.t_hi);
}

/* Gather evaluation at one fixed-point position (kernel and C++ reference). `alpha` holds the K padded
 * textons, level r at r * level_floats (each laid out as texton.h's padded planes). Sum order: cells by
 * (ky, kx), impulses by j, as texton noise; impulses that do not cover the point are skipped by every
 * strategy alike. out[c] for c < channels. */
STEX_FN void stex_mix_eval(const stex_texton_params p, const stex_mix_params m, const STEX_GLOBAL float* alpha,
                           const STEX_GLOBAL float* map, const STEX_GLOBAL stex_u32* poisson_table, stex_i64 x,
                           stex_i64 y, float* out) {
  float acc[STEX_MAX_CHANNELS] = {0.0f, 0.0f, 0.0f, 0.0f};
  stex_i64 kx0, kx1, ky0, ky1;
  stex_texton_cell_range(p, x, x, &kx0, &kx1);
  stex_texton_cell_range(p, y, y, &ky0, &ky1);
  const stex_i32 plane = p.stride * p.stride;
  const stex_i64 shift = stex_join64(m.shift_lo, m.shift_hi);
  for (stex_i64 ky = ky0; ky <= ky1; ++ky) {
    for (stex_i64 kx = kx0; kx <= kx1; ++kx) {
      const stex_uvec4 key = stex_cell_key(kx, ky);
      const stex_u32 n = stex_texton_count(p, key, poisson_table);
      for (stex_u32 j = 0; j < n; ++j) {
        stex_i64 xj, yj;
        stex_u32 mark;
        stex_texton_impulse(p, key, kx, ky, j, &xj, &yj, &mark);
        const stex_i64 dx = x - xj + shift, dy = y - yj + shift;
        if (!stex_mix_covers(p, dx, dy)) continue;
        /* 1_{x_j in D_r}: the texton of the region of the impulse. */
        const stex_i64 centre = stex_join64(m.centre_lo, m.centre_hi);
        const stex_i32 r = stex_mix_level(m, stex_mix_rho(m, map, xj + centre, yj + centre));
        const STEX_GLOBAL float* a = alpha + r * m.level_floats;
        const float eps = (mark & 1u) ? -1.0f : 1.0f; /* eps_j uniform on {-1, 1} */
        if (p.order > 1) {
          float h[STEX_MAX_CHANNELS] = {0.0f, 0.0f, 0.0f, 0.0f};
          stex_texton_hi_accum(p, a, dx, dy, h);
          for (int c = 0; c < p.channels; ++c) acc[c] += eps * h[c];
          continue;
        }
        float w00, w10, w01, w11;
        const stex_i32 idx = stex_texton_tap(p, dx, dy, &w00, &w10, &w01, &w11);
        for (int c = 0; c < p.channels; ++c)
          acc[c] += eps * stex_texton_fetch(a + c * plane, idx, p.stride, w00, w10, w01, w11);
      }
    }
  }
  /* Mean interpolated at the point: (1 - rho(x)) m0 + rho(x) m1. */
  const float rho = stex_mix_rho(m, map, x, y);
  for (int c = 0; c < p.channels; ++c)
    out[c] = ((1.0f - rho) * m.mean0[c] + rho * m.mean1[c]) + acc[c] * p.inv_sqrt_lambda;
}

#endif /* STEX_MIX_H */
