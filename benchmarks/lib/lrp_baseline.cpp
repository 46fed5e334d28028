// Plain C++ -ffast-math LRP baseline. See lrp_baseline.h.
#include "benchmarks/lib/lrp_baseline.h"

#include <omp.h>

#include <algorithm>
#include <cmath>

#include "kernels/shared/rng.h"

namespace stex::bench {

namespace {

constexpr float k_two_pi = 6.28318530717958647692f;

inline float window(float y) {  // Kaiser-Bessel alpha 3, radius 1.5, I0 by its series
  if (y >= 1.5f) return 0.0f;
  const float z = 3.0f * 3.14159265358979f * std::sqrt(1.0f - (y / 1.5f) * (y / 1.5f));
  const float u = z * z * 0.25f;
  float term = 1.0f, sum = 1.0f;
  for (int m = 1; m <= 17; ++m) {
    term *= u / float(m * m);
    sum += term;
  }
  return sum * 6.12335928e-4f;
}

inline float uniform(std::uint32_t v) { return float(v >> 8) * 5.9604644775390625e-8f; }

template <bool PolyCos>
void eval(const LrpSetup& s, std::int64_t x, std::int64_t y, float* out) {
  const stex_lrp_params& p = s.params;
  const float* fd = s.fdata.data();
  const std::uint32_t* ud = s.udata.data();
  float acc[4] = {0, 0, 0, 0};
  float turb = 0.0f;
  for (int st = 0; st < p.strata; ++st) {
    const std::int64_t a = stex_join64(p.cell_lo[st], p.cell_hi[st]);
    const std::int64_t cx = stex_floordiv(x, a), cy = stex_floordiv(y, a);
    float carrier = 0.0f;
    for (std::int64_t ky = cy - 1; ky <= cy + 1; ++ky)
      for (std::int64_t kx = cx - 1; kx <= cx + 1; ++kx) {
        const float dx = float(x - (kx * a + a / 2)) * p.inv_fix_scale;
        const float dy = float(y - (ky * a + a / 2)) * p.inv_fix_scale;
        const float wa = window(std::sqrt(dx * dx + dy * dy) * p.inv_delta[st]) * p.amp[st];
        if (wa == 0.0f) continue;
        const stex_uvec4 key = stex_cell_key(kx, ky);
        for (std::uint32_t j = 0; j < p.js[st]; ++j) {
          const stex_uvec4 v = stex_draw(key, p.seed_lo, p.seed_hi, j, STEX_DOMAIN_LRP + std::uint32_t(st));
          const std::uint32_t sub = p.sub_off[st] + j, off = ud[2 * sub], n = ud[2 * sub + 1];
          const std::uint32_t idx = std::uint32_t((std::uint64_t(v.x >> 8) * n) >> 24);
          const float fx = (fd[2 * (off + idx)] + uniform(v.y) - 0.5f) * p.bin;
          const float fy = (fd[2 * (off + idx) + 1] + uniform(v.z) - 0.5f) * p.bin;
          float c, sn;
          if constexpr (PolyCos) {
            stex_lrp_cossin(fx * dx + fy * dy + uniform(v.w), &c, &sn);
          } else {
            const float th = k_two_pi * (fx * dx + fy * dy + uniform(v.w));
            c = std::cos(th);
            sn = std::sin(th);
          }
          carrier += wa * c;
          const float* col = fd + p.col_off + 2 * p.channels * sub;
          for (int ch = 0; ch < p.channels; ++ch) acc[ch] += wa * (col[2 * ch] * c + col[2 * ch + 1] * sn);
        }
      }
    turb += std::fabs(carrier);
  }
  if (p.flags & STEX_LRP_FLAG_STRUCTURE) {
    // the structure without placement/turbulence blending (the benchmark's J = 50, r = 0 model has none;
    // kept for completeness with the same block lookup)
    const std::int64_t period = stex_join64(p.period_lo, p.period_hi);
    const float disp = (p.flags & STEX_LRP_FLAG_TURBULENCE) ? p.sigma * turb * p.turb_norm : 0.0f;
    float ux = float(x - stex_floordiv(x, period) * period) * p.inv_fix_scale + disp;
    float uy = float(y - stex_floordiv(y, period) * period) * p.inv_fix_scale + disp;
    ux -= p.period * std::floor(ux * p.inv_period);
    uy -= p.period * std::floor(uy * p.inv_period);
    const int bx = std::min(p.blocks - 1, int(ux * p.inv_block)), by = std::min(p.blocks - 1, int(uy * p.inv_block));
    const float ddx = (ux - bx * p.block) * p.inv_block, ddy = (uy - by * p.block) * p.inv_block;
    const int stride = 2 + 2 * p.channels;
    const float* t = fd + p.r_off + std::size_t(by * p.blocks + bx) * p.jr * stride;
    for (int k = 0; k < p.jr; ++k, t += stride) {
      float c, sn;
      if constexpr (PolyCos) {
        stex_lrp_cossin(t[0] * ddx + t[1] * ddy, &c, &sn);
      } else {
        const float th = k_two_pi * (t[0] * ddx + t[1] * ddy);
        c = std::cos(th);
        sn = std::sin(th);
      }
      for (int ch = 0; ch < p.channels; ++ch) acc[ch] += t[2 + 2 * ch] * c + t[3 + 2 * ch] * sn;
    }
  }
  for (int ch = 0; ch < p.channels; ++ch) out[ch] = p.mean[ch] + acc[ch];
}

template <bool PolyCos>
void render(const LrpSetup& setup, std::int64_t x, std::int64_t y, int width, int height, float* out, int threads) {
  const int nc = setup.channels;
  if (threads > 0) omp_set_num_threads(threads);
#pragma omp parallel for schedule(dynamic, 4)
  for (int j = 0; j < height; ++j) {
    const std::int64_t fy = stex_lrp_pixel_fix(y + j);
    for (int i = 0; i < width; ++i)
      eval<PolyCos>(setup, stex_lrp_pixel_fix(x + i), fy, out + (std::size_t(j) * width + i) * nc);
  }
}

}  // namespace

void lrp_fastmath_render(const LrpSetup& setup, std::int64_t x, std::int64_t y, int width, int height, float* out,
                         int threads) {
  render<false>(setup, x, y, width, height, out, threads);
}

void lrp_fastmath_polycos_render(const LrpSetup& setup, std::int64_t x, std::int64_t y, int width, int height,
                                 float* out, int threads) {
  render<true>(setup, x, y, width, height, out, threads);
}

}  // namespace stex::bench
