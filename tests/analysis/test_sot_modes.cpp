// The Gaussian and spot-noise render modes of analysis/gaussian_synthesis.h (S2 §2.1-2.2, §2.4; RPN of
// Galerne-Gousseau-Morel):
//  - DSN converges to ADSN as lambda grows (S2 §2.1): the excess kurtosis of DSN_lambda(alpha) is
//    sum alpha^4 / (lambda (sum alpha^2)^2) (the fourth cumulant of shot noise over the squared variance),
//    measured at four intensities and checked against it (5 batch-means standard errors: 16 x 16 blocks of
//    128^2 pixels of a 2048^2 render), then the 1/lambda law itself (least-squares slope of log kurtosis on
//    log lambda = -1 within 5 propagated standard errors); the ADSN of the same kernel has kurtosis 0 and the
//    same lag covariance (alpha * alpha~) within 5 standard errors;
//  - ADSN on Z^2 is tile-invariant (to one float ulp: the FFT's rounding depends on the tile) and equals the
//    direct sum mean + sum_q k(q) W(p - q);
//  - CADSN equals the direct circular sum on Theta and is what synthesize_adsn(exemplar) computes;
//  - RPN has modulus sqrt(|Theta|) |k^| with the colour phase differences of k^, a random phase, and the
//    pixel variance sum k^2;
//  - CDSN equals the direct circular sum of the Poisson counts of its stream;
//  - the order-1 texton kernel alpha * (beta x beta) has the texton noise covariance (S1 Prop. 1).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analysis/fft.h"
#include "analysis/gaussian_model.h"
#include "analysis/gaussian_synthesis.h"
#include "analysis/texton.h"
#include "core/error.h"
#include "kernels/shared/poisson.h"
#include "kernels/shared/rng.h"
#include "runtime/poisson_table.h"

namespace stex {
namespace {

NormalisedKernel random_kernel(int w, int h, int ch, std::uint64_t seed, double scale) {
  NormalisedKernel k;
  k.width = w;
  k.height = h;
  k.channels = ch;
  k.t = texton_initial_noise(w, h, ch, seed);
  for (double& v : k.t) v *= scale;
  for (int c = 0; c < ch; ++c) k.mean[c] = 0.45 + 0.05 * c;
  return k;
}

TextonModel model_from(const NormalisedKernel& k) {
  TextonModel m;
  m.channels = k.channels;
  m.support = k.width;
  m.order = 0;
  m.alpha.assign(k.t.begin(), k.t.end());
  for (int c = 0; c < k.channels; ++c) m.mean[c] = float(k.mean[c]);
  return m;
}

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

struct Moments {
  double kurtosis = 0.0, kurtosis_se = 0.0, cov1 = 0.0, cov1_se = 0.0;
};

// Whole-image excess kurtosis and lag-(1, 0) covariance around the known mean; standard errors from batch
// means over b x b blocks.
Moments moments(const Image& img, double mean, int b) {
  const int n = img.width, nb = n / b;
  std::vector<double> kurt, cov;
  double w2 = 0, w4 = 0;
  for (int by = 0; by < nb; ++by)
    for (int bx = 0; bx < nb; ++bx) {
      double m2 = 0, m4 = 0, c1 = 0;
      for (int y = by * b; y < (by + 1) * b; ++y)
        for (int x = bx * b; x < (bx + 1) * b; ++x) {
          const double d = img.pixels[std::size_t(y) * n + x] - mean;
          m2 += d * d;
          m4 += d * d * d * d;
          if (x + 1 < (bx + 1) * b) c1 += d * (img.pixels[std::size_t(y) * n + x + 1] - mean);
        }
      const double cnt = double(b) * b;
      w2 += m2;
      w4 += m4;
      kurt.push_back((m4 / cnt) / ((m2 / cnt) * (m2 / cnt)) - 3.0);
      cov.push_back(c1 / (double(b) * (b - 1)));
    }
  const double N = double(n) * n;
  Moments m;
  m.kurtosis = (w4 / N) / ((w2 / N) * (w2 / N)) - 3.0;
  m.kurtosis_se = se_of(kurt);
  m.cov1 = mean_of(cov);
  m.cov1_se = se_of(cov);
  return m;
}

TEST(GaussianModes, DsnKurtosisFallsAsOneOverLambdaTowardsTheAdsn) {
  // A compact 3 x 3 spot (fast mixing, so that 2048^2 pixels give ~1e-3 standard errors on the kurtosis).
  NormalisedKernel k;
  k.width = k.height = 3;
  k.channels = 1;
  k.mean[0] = 0.5;
  k.t = {0.009, -0.003, 0.002, 0.004, 0.010, -0.005, 0.001, 0.003, -0.002};
  const TextonModel model = model_from(k);
  double s2 = 0, s4 = 0;
  for (double a : k.t) {
    s2 += a * a;
    s4 += a * a * a * a;
  }
  const double cov1_theory = k.t[0] * k.t[1] + k.t[1] * k.t[2] + k.t[3] * k.t[4] + k.t[4] * k.t[5] +
                             k.t[6] * k.t[7] + k.t[7] * k.t[8];  // (alpha * alpha~)(1, 0)
  const int n = 2048, b = 128;
  std::vector<double> log_lambda, log_kurt, weight;
  std::uint64_t seed = 31;  // a seed per intensity: independent estimates for the slope's standard error
  for (double mni : {1.0, 4.0, 16.0, 64.0}) {
    const double lambda = mni / 9.0;
    const Image img = synthesize_dsn(model, 0, 0, n, n, mni, seed++);
    const Moments m = moments(img, 0.5, b);
    const double theory = s4 / (lambda * s2 * s2);
    EXPECT_NEAR(m.kurtosis, theory, 5 * m.kurtosis_se) << "MNI " << mni;
    EXPECT_GT(theory, 8 * m.kurtosis_se) << "MNI " << mni << ": the kurtosis must be resolved";
    EXPECT_NEAR(m.cov1, cov1_theory, 5 * m.cov1_se) << "MNI " << mni;
    std::printf("[ info ] DSN MNI %g (lambda %.4f): excess kurtosis %.4f +- %.4f, theory %.4f\n", mni, lambda,
                m.kurtosis, m.kurtosis_se, theory);
    log_lambda.push_back(std::log(lambda));
    log_kurt.push_back(std::log(m.kurtosis));
    const double rel = m.kurtosis_se / m.kurtosis;  // standard error of log kurtosis
    weight.push_back(1.0 / (rel * rel));
  }
  // Weighted least-squares slope of log kurtosis on log lambda, and its standard error.
  double sw = 0, sx = 0, sy = 0;
  for (std::size_t i = 0; i < weight.size(); ++i) {
    sw += weight[i];
    sx += weight[i] * log_lambda[i];
    sy += weight[i] * log_kurt[i];
  }
  const double xm = sx / sw, ym = sy / sw;
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < weight.size(); ++i) {
    sxx += weight[i] * (log_lambda[i] - xm) * (log_lambda[i] - xm);
    sxy += weight[i] * (log_lambda[i] - xm) * (log_kurt[i] - ym);
  }
  const double slope = sxy / sxx, slope_se = 1.0 / std::sqrt(sxx);
  std::printf("[ info ] log-log slope of the DSN kurtosis against lambda: %.4f +- %.4f (1/lambda law: -1)\n",
              slope, slope_se);
  EXPECT_NEAR(slope, -1.0, 5 * slope_se);
  EXPECT_LT(slope_se, 0.1);
  // The limit: ADSN of the same kernel (Z^2), Gaussian: kurtosis 0, same covariance.
  const Moments g = moments(synthesize_adsn_z2(k, 0, 0, n, n, 31), 0.5, b);
  EXPECT_NEAR(g.kurtosis, 0.0, 5 * g.kurtosis_se);
  EXPECT_NEAR(g.cov1, cov1_theory, 5 * g.cov1_se);
  std::printf("[ info ] ADSN: excess kurtosis %.4f +- %.4f\n", g.kurtosis, g.kurtosis_se);
}

TEST(GaussianModes, AdsnOnZ2IsTileInvariantAndTheDirectSum) {
  const NormalisedKernel k = random_kernel(13, 9, 3, 5, 0.01);
  const std::int64_t x0 = -500, y0 = 77;
  const Image whole = synthesize_adsn_z2(k, x0, y0, 120, 90, 4);
  ASSERT_EQ(whole.channels, 3);
  double worst = 0.0;
  for (int ty = 0; ty < 90; ty += 40)
    for (int tx = 0; tx < 120; tx += 50) {
      const int w = std::min(50, 120 - tx), h = std::min(40, 90 - ty);
      const Image tile = synthesize_adsn_z2(k, x0 + tx, y0 + ty, w, h, 4);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          for (int c = 0; c < 3; ++c)
            worst = std::max(worst, double(std::fabs(tile.at(x, y, c) - whole.at(tx + x, ty + y, c))));
    }
  EXPECT_LE(worst, 1.2e-7);  // one float ulp below 2 (values are about 0.45 +- 0.5)
  // Direct sum at a few pixels.
  for (int p = 0; p < 12; ++p) {
    const int px = (p * 37) % 120, py = (p * 53) % 90;
    for (int c = 0; c < 3; ++c) {
      double v = k.mean[c];
      for (int qy = 0; qy < 9; ++qy)
        for (int qx = 0; qx < 13; ++qx)
          v += k.t[(std::size_t(c) * 9 + qy) * 13 + qx] * white_noise_at(x0 + px - qx, y0 + py - qy, 4);
      EXPECT_NEAR(whole.at(px, py, c), v, 1e-6);
    }
  }
  const Image other = synthesize_adsn_z2(k, x0, y0, 120, 90, 5);
  EXPECT_GT(std::fabs(other.at(10, 10, 0) - whole.at(10, 10, 0)), 0.0);
  EXPECT_THROW(synthesize_adsn_z2(k, 0, 0, 100000, 100000, 0), Error);
}

TEST(GaussianModes, CadsnIsTheCircularSumOnTheta) {
  const NormalisedKernel k = random_kernel(6, 5, 2, 6, 0.02);
  struct Region {
    int w, h;
  };
  for (const Region r : {Region{12, 10}, Region{4, 3}}) {
    const std::int64_t x0 = 30, y0 = -2;
    const Image img = synthesize_cadsn(k, x0, y0, r.w, r.h, 8);
    const int dw = std::max(r.w, 6), dh = std::max(r.h, 5);
    for (int y = 0; y < r.h; ++y)
      for (int x = 0; x < r.w; ++x)
        for (int c = 0; c < 2; ++c) {
          double v = k.mean[c];
          for (int qy = 0; qy < 5; ++qy)
            for (int qx = 0; qx < 6; ++qx)
              v += k.t[(std::size_t(c) * 5 + qy) * 6 + qx] *
                   white_noise_at(x0 + ((x - qx) % dw + dw) % dw, y0 + ((y - qy) % dh + dh) % dh, 8);
          EXPECT_NEAR(img.at(x, y, c), v, 1e-6);
        }
  }
  // synthesize_adsn(exemplar) = CADSN of the exemplar's t_u.
  Image u;
  u.width = 20;
  u.height = 16;
  u.channels = 1;
  const std::vector<double> g = texton_initial_noise(20, 16, 1, 3);
  for (double v : g) u.pixels.push_back(float(0.5 + 0.1 * v));
  const Image a = synthesize_adsn(u, 3, 4, 30, 10, 2),
              b = synthesize_cadsn(normalised_kernel(u, true), 3, 4, 30, 10, 2);
  EXPECT_EQ(a.pixels, b.pixels);
}

TEST(GaussianModes, RpnHasTheKernelModulusAndARandomPhase) {
  const int ch = 3;
  for (int size : {16, 24}) {  // Theta = the kernel's size, then a zero-padded kernel
    const NormalisedKernel k = random_kernel(16, 16, ch, 9, 0.01);
    const Image img = synthesize_rpn(k, 5, -3, size, size, 12);
    const std::size_t n = std::size_t(size) * size;
    std::vector<Complex> f(n * ch), kh(n * ch, 0.0);
    for (int c = 0; c < ch; ++c) {
      double var = 0.0, sk2 = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        const double d = img.pixels[i * ch + c] - k.mean[c];
        f[n * c + i] = d;
        var += d * d;
      }
      for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
          const double v = k.t[(std::size_t(c) * 16 + y) * 16 + x];
          kh[n * c + std::size_t(y) * size + x] = v;
          sk2 += v * v;
        }
      EXPECT_NEAR(var / double(n), sk2, 1e-5 * sk2);  // Parseval: pixel variance = sum k^2
      fft2d_forward(size, size, f.data() + n * c);
      fft2d_forward(size, size, kh.data() + n * c);
    }
    double peak = 0.0;
    for (const Complex& v : kh) peak = std::max(peak, std::abs(v));
    const double root = std::sqrt(double(n));
    double phase_change = 0.0;
    int strong = 0;
    for (std::size_t q = 1; q < n; ++q) {
      for (int c = 0; c < ch; ++c)
        EXPECT_NEAR(std::abs(f[n * c + q]), root * std::abs(kh[n * c + q]), 1e-5 * root * peak);
      if (std::abs(kh[q]) < 0.2 * peak || std::abs(kh[n + q]) < 0.2 * peak) continue;
      // One phase for all channels: the cross-spectrum phase of channels 1 and 0 is k^'s.
      const Complex cf = f[n + q] * std::conj(f[q]), ck = kh[n + q] * std::conj(kh[q]);
      EXPECT_NEAR(std::abs(cf / std::abs(cf) - ck / std::abs(ck)), 0.0, 1e-3);
      phase_change += std::abs(f[q] / std::abs(f[q]) - kh[q] / std::abs(kh[q]));
      ++strong;
    }
    ASSERT_GT(strong, 10);
    EXPECT_GT(phase_change / strong, 0.5);  // a uniform phase difference has E|e^{i psi} - 1| = 4/pi
  }
}

TEST(GaussianModes, CdsnIsTheCircularSumOfItsPoissonCounts) {
  const NormalisedKernel k = random_kernel(5, 5, 2, 10, 0.02);
  const TextonModel m = model_from(k);
  const double mni = 20.0, lambda = mni / 25.0;
  const std::vector<std::uint32_t> table = poisson_threshold_table(lambda);
  struct Region {
    int w, h;
  };
  for (const Region r : {Region{14, 11}, Region{3, 2}}) {
    const std::int64_t x0 = 3, y0 = -8;
    const Image img = synthesize_cdsn(m, x0, y0, r.w, r.h, mni, 17);
    const int dw = std::max(r.w, 5), dh = std::max(r.h, 5);
    auto count = [&](int i, int j) {
      const stex_uvec4 v = stex_draw(stex_cell_key(x0 + i, y0 + j), 17u, 0u, 0u, k_domain_cdsn_count);
      return double(stex_poisson_count(table.data(), std::uint32_t(table.size()), v.x));
    };
    for (int y = 0; y < r.h; ++y)
      for (int x = 0; x < r.w; ++x)
        for (int c = 0; c < 2; ++c) {
          double acc = 0.0, sum = 0.0;
          for (int qy = 0; qy < 5; ++qy)
            for (int qx = 0; qx < 5; ++qx) {
              const double a = m.alpha_at(c, qy, qx);
              sum += a;
              acc += a * count(((x - qx) % dw + dw) % dw, ((y - qy) % dh + dh) % dh);
            }
          EXPECT_NEAR(img.at(x, y, c), m.mean[c] + (acc - lambda * sum) / std::sqrt(lambda), 1e-5);
        }
  }
  EXPECT_THROW(synthesize_cdsn(m, 0, 0, 8, 8, 0.0, 1), Error);
}

// alpha * (q x q) must have the texton noise covariance (alpha~ * alpha) * b of every interpolation order:
// exact algebra, so 1e-12 (double rounding over <= 11^2 * 6^2 products).
class TextonKernelOrder : public ::testing::TestWithParam<int> {};

TEST_P(TextonKernelOrder, HasTheTextonNoiseCovariance) {
  const int order = GetParam();
  TextonModel m;
  m.channels = 2;
  m.support = 6;
  m.order = order;
  const std::vector<double> a = texton_initial_noise(6, 6, 2, 77);
  m.alpha.assign(a.begin(), a.end());
  m.mean = {0.3f, 0.6f, 0.0f, 0.0f};
  const NormalisedKernel k = texton_kernel(m);
  const int r = 6 + order;
  ASSERT_EQ(k.width, r);
  ASSERT_EQ(k.height, r);
  EXPECT_DOUBLE_EQ(k.mean[1], double(0.6f));
  const int reach = 5 + order;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int dy = -reach - 1; dy <= reach + 1; ++dy)
        for (int dx = -reach - 1; dx <= reach + 1; ++dx) {
          double acc = 0.0;  // sum_x k_i(x + d) k_j(x)
          for (int y = 0; y < r; ++y)
            for (int x = 0; x < r; ++x) {
              const int xx = x + dx, yy = y + dy;
              if (xx < 0 || yy < 0 || xx >= r || yy >= r) continue;
              acc += k.t[(std::size_t(i) * r + yy) * r + xx] * k.t[(std::size_t(j) * r + y) * r + x];
            }
          EXPECT_NEAR(acc, model_covariance(m.alpha, 2, 6, order, i, j, dx, dy), 1e-12)
              << "order " << order << " channels " << i << "," << j << " lag " << dx << "," << dy;
        }
}

INSTANTIATE_TEST_SUITE_P(Orders, TextonKernelOrder, ::testing::Values(0, 1, 3, 5));

TEST(GaussianModes, SpectralFactorReproducesTheSampledBspline) {
  for (int order : {0, 1, 3, 5}) {
    const std::vector<double> q = bspline_spectral_factor(order);
    ASSERT_EQ(int(q.size()), order + 1);
    for (int d = -order - 1; d <= order + 1; ++d) {
      double ac = 0.0;
      for (int x = 0; x <= order; ++x)
        if (x + d >= 0 && x + d <= order) ac += q[std::size_t(x + d)] * q[std::size_t(x)];
      // b_1(d) = b(d, 0) / b_1(0) with b_1(0) = sqrt(b(0, 0))
      EXPECT_NEAR(ac, bspline_sample(order, d, 0) / std::sqrt(bspline_sample(order, 0, 0)), 1e-12)
          << "order " << order << " lag " << d;
    }
  }
  const std::vector<double> q1 = bspline_spectral_factor(1);
  EXPECT_NEAR(q1[0], 0.5 * (1.0 + 1.0 / std::sqrt(3.0)), 1e-14);
  EXPECT_NEAR(q1[1], 0.5 * (1.0 - 1.0 / std::sqrt(3.0)), 1e-14);
  EXPECT_THROW(bspline_spectral_factor(2), Error);
}

}  // namespace
}  // namespace stex
