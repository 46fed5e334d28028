// The comparison modes of `stex render` (analysis/gaussian_synthesis): DSN of the texton on Z^2 (S2 §2.1,
// Algorithm 1 with a grid Poisson process) and the exemplar's ADSN by FFT (S1 §3.1-3.2, S2 §2.4).
//
// DSN: tile-invariant bit for bit; mean = model mean, covariance at integer lags = (alpha * alpha~)(tau)
// (S2 §2.1: the normalised DSN has covariance h * h~ with h = alpha), excess kurtosis = sum alpha^4 /
// (lambda (sum alpha^2)^2). Tolerances from batch means over 128 x 128 blocks (as in test_texton_stats),
// 5 standard errors.
// ADSN: each pixel is mean + sum_q t_u(q) W(p - q) with W i.i.d. N(0, 1), so its variance is exactly
// sum t_u^2 = the exemplar's (periodic component's) variance, whatever the domain; the covariance at lag tau
// is the circular autocorrelation of t_u on the domain. Checked over 48 independent seeds: per seed the
// sample statistic, across seeds the standard error (the realisations are independent), 5 standard errors.
// Also: the spatial mean over a whole periodic domain is exactly the exemplar mean (sum t_u = 0).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "analysis/gaussian_synthesis.h"
#include "analysis/periodic.h"
#include "core/error.h"
#include "kernels/test_texton_common.h"

namespace stex {
namespace {

using test::synthetic_model;

double mean_of(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / double(v.size());
}
double se_of(const std::vector<double>& v) {
  const double m = mean_of(v);
  double q = 0;
  for (double x : v) q += (x - m) * (x - m);
  return std::sqrt(q / double(v.size() - 1) / double(v.size()));
}

TEST(DsnMode, TileInvariantAndDeterministic) {
  const TextonModel model = synthetic_model(3, 16, 0, 51);
  const Image whole = synthesize_dsn(model, -40, 1000, 200, 150, 30.0, 5);
  std::vector<float> tiled(whole.pixels.size(), -1.0f);
  for (int y = 0; y < 150; y += 64)
    for (int x = 0; x < 200; x += 90) {
      const int w = std::min(90, 200 - x), h = std::min(64, 150 - y);
      test::paste(tiled, 200, 3, x, y, w, h, synthesize_dsn(model, -40 + x, 1000 + y, w, h, 30.0, 5).pixels);
    }
  EXPECT_EQ(test::count_bit_differences(whole.pixels, tiled), 0u);
  EXPECT_GT(test::count_bit_differences(whole.pixels, synthesize_dsn(model, -40, 1000, 200, 150, 30.0, 6).pixels),
            whole.pixels.size() * 9 / 10);
  EXPECT_THROW(synthesize_dsn(model, 0, 0, 10, 10, -1.0, 0), Error);
  EXPECT_THROW(synthesize_dsn(model, 0, 0, 0, 10, 30.0, 0), Error);
}

TEST(DsnMode, StatisticsMatchSpotNoise) {
  const TextonModel model = synthetic_model(1, 16, 0, 52);
  const int s = model.support, n = 1024, b = 128, nb = n / b;
  const double mni = 4.0;  // low intensity: a clearly non-Gaussian kurtosis
  const double lambda = mni / double(s * s);
  const Image img = synthesize_dsn(model, 0, 0, n, n, mni, 77);
  auto R = [&](int dx, int dy) { return test::model_lag_covariance(model, 0, 0, dx, dy); };  // order 0: alpha*alpha~
  double sa2 = 0, sa4 = 0;
  for (float a : model.alpha) {
    sa2 += double(a) * a;
    sa4 += double(a) * a * a * a;
  }
  const double m = model.mean[0];
  for (int lag = 0; lag <= 6; lag += 2) {
    std::vector<double> est;
    for (int by = 0; by < nb; ++by)
      for (int bx = 0; bx < nb; ++bx) {
        double acc = 0;
        long cnt = 0;
        for (int y = by * b; y < (by + 1) * b; ++y)
          for (int x = bx * b; x < (bx + 1) * b - lag; ++x) {
            acc += (img.pixels[std::size_t(y) * n + x] - m) * (img.pixels[std::size_t(y) * n + x + lag] - m);
            ++cnt;
          }
        est.push_back(acc / double(cnt));
      }
    EXPECT_NEAR(mean_of(est), R(lag, 0), 5 * se_of(est)) << "lag " << lag;
  }
  std::vector<double> kurt, means;
  double w2 = 0, w4 = 0;
  for (int by = 0; by < nb; ++by)
    for (int bx = 0; bx < nb; ++bx) {
      double s1 = 0, m2 = 0, m4 = 0;
      for (int y = by * b; y < (by + 1) * b; ++y)
        for (int x = bx * b; x < (bx + 1) * b; ++x) {
          const double d = img.pixels[std::size_t(y) * n + x] - m;
          s1 += d;
          m2 += d * d;
          m4 += d * d * d * d;
        }
      const double cnt = double(b) * b;
      w2 += m2;
      w4 += m4;
      means.push_back(s1 / cnt);
      kurt.push_back((m4 / cnt) / ((m2 / cnt) * (m2 / cnt)) - 3.0);
    }
  EXPECT_NEAR(mean_of(means), 0.0, 5 * se_of(means));
  // Whole-image estimate, batch-means standard error.
  const double N = double(n) * n;
  const double kurt_whole = (w4 / N) / ((w2 / N) * (w2 / N)) - 3.0;
  const double kurt_theory = sa4 / (lambda * sa2 * sa2);
  EXPECT_NEAR(kurt_whole, kurt_theory, 5 * se_of(kurt));
  EXPECT_GT(kurt_theory, 10 * se_of(kurt));
}

// A 64 x 64 periodic grey exemplar (periodic component = itself up to rounding): oriented cosines + noise.
Image periodic_exemplar() {
  Image u;
  u.width = u.height = 64;
  u.channels = 1;
  u.pixels.resize(64 * 64);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const stex_uvec4 v = stex_draw(stex_cell_key(x, y), 3, 0, 0, STEX_DOMAIN_TEST);
      u.at(x, y, 0) = float(0.5 + 0.08 * std::cos(6.283185307179586 * (3 * x + y) / 64.0) +
                            0.3 * (stex_uniform24(v.x) - 0.5));
    }
  return u;
}

TEST(AdsnMode, VarianceAndCovarianceOfTheGaussianModel) {
  const Image u = periodic_exemplar();
  std::vector<double> plane(u.pixels.begin(), u.pixels.end());
  const std::vector<double> p = periodic_component(64, 64, plane);
  double mean = 0;
  for (double v : p) mean += v;
  mean /= double(p.size());
  // t_u = (p - mean) / 8; circular autocorrelation c(tau) = sum_x t(x) t(x + tau).
  auto c = [&](int dx, int dy) {
    double s = 0;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x)
        s += (p[std::size_t(y) * 64 + x] - mean) * (p[std::size_t(((y + dy) % 64 + 64) % 64) * 64 + ((x + dx) % 64 + 64) % 64] - mean);
    return s / 4096.0;
  };
  // Domain = exemplar size: the spatial mean is exactly the exemplar mean; covariance = c.
  std::vector<double> var64, cov64, var256;
  for (std::uint64_t seed = 0; seed < 48; ++seed) {
    const Image a = synthesize_adsn(u, 0, 0, 64, 64, seed);
    double m = 0;
    for (float v : a.pixels) m += v;
    m /= 4096.0;
    EXPECT_NEAR(m, mean, 1e-6);
    double v0 = 0, v1 = 0;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        const double d = a.at(x, y, 0) - mean;
        v0 += d * d;
        v1 += d * (a.at((x + 8) % 64, y, 0) - mean);
      }
    var64.push_back(v0 / 4096.0);
    cov64.push_back(v1 / 4096.0);
    // Output larger than the exemplar: t_u zero-padded in a 256^2 domain; the pixel variance is unchanged.
    const Image big = synthesize_adsn(u, 1000, -7, 256, 256, seed);
    double vb = 0;
    for (float v : big.pixels) vb += (v - mean) * (v - mean);
    var256.push_back(vb / (256.0 * 256.0));
  }
  EXPECT_NEAR(mean_of(var64), c(0, 0), 5 * se_of(var64));
  EXPECT_NEAR(mean_of(cov64), c(8, 0), 5 * se_of(cov64));
  EXPECT_NEAR(mean_of(var256), c(0, 0), 5 * se_of(var256));
  EXPECT_GT(std::fabs(c(8, 0) - c(0, 8)), 5 * se_of(cov64));  // power: the oriented pattern is anisotropic
  // Deterministic.
  EXPECT_EQ(test::count_bit_differences(synthesize_adsn(u, 0, 0, 100, 80, 9).pixels,
                                        synthesize_adsn(u, 0, 0, 100, 80, 9).pixels),
            0u);
  EXPECT_THROW(synthesize_adsn(u, 0, 0, 100000, 100000, 0), Error);
}

}  // namespace
}  // namespace stex
