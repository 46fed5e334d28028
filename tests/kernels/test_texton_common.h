// Shared fixtures of the texton evaluation tests (tests/kernels/test_texton_*.cpp): one OpenCL context per
// test binary, synthetic texton models drawn from the counter RNG (so that no analysis code is involved),
// bit-exact image comparison, and the exact moments of a bilinear / nearest texton (S1 eq. 3) that the
// statistical tests compare against.
#pragma once
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "kernels/shared/rng.h"
#include "runtime/context.h"
#include "runtime/model.h"
#include "test_device.h"

namespace stex::test {

inline Context& texton_context() {
  static std::unique_ptr<Context> ctx = Context::create(stex::test::test_device_spec());
  return *ctx;
}

// A synthetic model: alpha(c, y, x) = amplitude * (u - 1/2) + offset + wave, u uniform from the counter RNG
// keyed by (x, y) and (seed, c); `wave` adds an anisotropic oriented cosine (so that a transposed or
// mirrored evaluation changes the covariance).
inline TextonModel synthetic_model(int channels, int support, int order, std::uint64_t seed,
                                   float offset = 0.002f, bool wave = true) {
  TextonModel m;
  m.channels = channels;
  m.support = support;
  m.order = order;
  m.alpha.resize(std::size_t(channels) * support * support);
  const float amplitude = 0.08f / float(support);
  for (int c = 0; c < channels; ++c) {
    m.mean[c] = 0.25f + 0.2f * float(c);
    for (int y = 0; y < support; ++y)
      for (int x = 0; x < support; ++x) {
        stex_uvec4 v = stex_draw(stex_cell_key(x, y), stex_lo32(std::int64_t(seed)), stex_hi32(std::int64_t(seed)),
                                 std::uint32_t(c), STEX_DOMAIN_TEST);
        float a = amplitude * (stex_uniform24(v.x) - 0.5f) + offset;
        if (wave) a += amplitude * 0.7f * std::cos(6.2831853f * (float(x) + 0.4f * float(y)) / 5.0f + float(c));
        m.alpha[(std::size_t(c) * support + y) * support + x] = a;
      }
  }
  m.exemplar_name = "synthetic";
  return m;
}

// Number of values whose bits differ (NaN-safe, -0 != +0).
inline std::size_t count_bit_differences(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) return std::max(a.size(), b.size());
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(float)) != 0) ++n;
  return n;
}

// Copies the sub-image [x, x + w) x [y, y + h) of an interleaved image of width `width`.
inline std::vector<float> crop(const std::vector<float>& img, int width, int channels, int x, int y, int w, int h) {
  std::vector<float> out(std::size_t(w) * h * channels);
  for (int j = 0; j < h; ++j)
    std::memcpy(&out[std::size_t(j) * w * channels], &img[(std::size_t(y + j) * width + x) * channels],
                sizeof(float) * std::size_t(w) * channels);
  return out;
}

// Pastes a w x h interleaved tile into an image of width `width` at (x, y).
inline void paste(std::vector<float>& img, int width, int channels, int x, int y, int w, int h,
                  const std::vector<float>& tile) {
  for (int j = 0; j < h; ++j)
    std::memcpy(&img[(std::size_t(y + j) * width + x) * channels], &tile[std::size_t(j) * w * channels],
                sizeof(float) * std::size_t(w) * channels);
}

// Exact moments of the texton h(y) = sum_k alpha(k) psi(y - k) of channel c (S1 eq. 3): integral of h,
// h^2 and h^4 over R^2. Order 1: on each unit square h is bilinear in the local coordinates, so h^4 has
// degree 4 per axis and 3-point Gauss-Legendre quadrature per axis is exact. Order 0: h is constant
// alpha(k) on the unit square around k.
struct TextonMoments {
  double h1 = 0, h2 = 0, h4 = 0;
};
inline TextonMoments texton_moments(const TextonModel& m, int c) {
  const int s = m.support;
  auto a = [&](int x, int y) -> double {
    return (x < 0 || y < 0 || x >= s || y >= s) ? 0.0 : double(m.alpha_at(c, y, x));
  };
  TextonMoments t;
  if (m.order == 0) {
    for (int y = 0; y < s; ++y)
      for (int x = 0; x < s; ++x) {
        const double v = a(x, y);
        t.h1 += v;
        t.h2 += v * v;
        t.h4 += v * v * v * v;
      }
    return t;
  }
  const double gx[3] = {0.5 - 0.5 * std::sqrt(0.6), 0.5, 0.5 + 0.5 * std::sqrt(0.6)};
  const double gw[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
  for (int y = -1; y < s; ++y)
    for (int x = -1; x < s; ++x) {
      const double a00 = a(x, y), a10 = a(x + 1, y), a01 = a(x, y + 1), a11 = a(x + 1, y + 1);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const double u = gx[i], v = gx[j], w = gw[i] * gw[j];
          const double h = a00 * (1 - u) * (1 - v) + a10 * u * (1 - v) + a01 * (1 - u) * v + a11 * u * v;
          t.h1 += w * h;
          t.h2 += w * h * h;
          t.h4 += w * h * h * h * h;
        }
    }
  return t;
}

// The centred B-spline of degree n by its defining sum (1/n!) sum_k (-1)^k C(n+1, k) (x + (n+1)/2 - k)_+^n,
// independent of the kernels' Horner forms and of analysis/gaussian_model's tables.
inline double bspline_def(int n, double x) {
  double fact = 1.0, acc = 0.0, binom = 1.0;
  for (int i = 2; i <= n; ++i) fact *= i;
  for (int k = 0; k <= n + 1; ++k) {
    const double v = x + 0.5 * (n + 1) - k;
    if (v > 0) acc += ((k % 2) ? -binom : binom) * std::pow(v, n);
    binom = binom * double(n + 1 - k) / double(k + 1);
  }
  return acc / fact;
}

// (psi * psi)(d) = integral beta^k(y) beta^k(y + d) dy for odd k by 8-point Gauss-Legendre quadrature per
// unit interval between the integer knots (degree 2k <= 10: exact up to rounding).
inline double bspline_autocorrelation(int k, int d) {
  const double gx[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
  const double gw[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
  double integral = 0.0;
  for (int a = -k - 1; a <= k + 1; ++a)
    for (int g = 0; g < 8; ++g) {
      const double t = g < 4 ? -gx[g] : gx[g - 4], y = a + 0.5 + 0.5 * t;
      integral += 0.5 * gw[g % 4] * bspline_def(k, y) * bspline_def(k, y + d);
    }
  return integral;
}

// Covariance of the normalised texton noise at integer lag (dx, dy) between channels i and j (S1 Prop. 1
// and §4.1): C(tau) = integral h_i(y) h_j(y + tau) dy = sum_l R_ij(l) b(tau - l), R_ij(l) = sum_x
// alpha_i(x) alpha_j(x + l), b the sampled psi * psi: the cubic B-spline (1/6, 2/3, 1/6)^2 (order 1), a delta
// (order 0), beta^7 / beta^11 samples (orders 3, 5; S1 §10) computed by quadrature above.
inline double model_lag_covariance(const TextonModel& m, int i, int j, int dx, int dy) {
  const int s = m.support;
  auto R = [&](int lx, int ly) {
    double r = 0;
    for (int y = 0; y < s; ++y)
      for (int x = 0; x < s; ++x) {
        const int x2 = x + lx, y2 = y + ly;
        if (x2 < 0 || y2 < 0 || x2 >= s || y2 >= s) continue;
        r += double(m.alpha_at(i, y, x)) * double(m.alpha_at(j, y2, x2));
      }
    return r;
  };
  if (m.order == 0) return R(dx, dy);
  const int k = m.order;
  std::vector<double> b1(2 * k + 1);
  for (int d = -k; d <= k; ++d) b1[d + k] = bspline_autocorrelation(k, d);
  double c = 0;
  for (int ey = -k; ey <= k; ++ey)
    for (int ex = -k; ex <= k; ++ex) c += b1[ex + k] * b1[ey + k] * R(dx - ex, dy - ey);
  return c;
}

}  // namespace stex::test
