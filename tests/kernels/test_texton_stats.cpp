// Statistics of rendered texton noise against S1 Proposition 1 / Theorem 2 (and the shot-noise cumulants of
// [Pap71]) on large device renders (strip splat, bit-identical to the reference by test_texton_eval):
//  - per-channel mean = model mean and variance = C(0) = integral h^2 (normalised noise, S1 eq. 2);
//  - the empirical covariance at lags |dx|, |dy| <= 8 equals C(tau) = sum_l R(l) b(tau - l) (S1 §4.1; R the
//    autocorrelation of alpha, b the sampled cubic B-spline), and NOT its transpose (power check);
//  - the excess kurtosis equals the shot-noise value integral h^4 / (lambda (integral h^2)^2) for MNI 1, 4, 30;
//  - a tile at x = 10^12 has the statistics of a tile at 0.
//
// Tolerances (fixed seeds, so every run gives the same numbers; the bounds say how unlikely a failure of a
// correct implementation would be):
//  - mean: Var(mean estimate) = sum_tau C(tau) / N = (sum alpha)^2 / N for N pixels (the sum of C over the
//    integer lags is (integral h)^2 because b sums to 1). Bound: 5 standard errors.
//  - variance: Gaussian-limit formula plus the shot-noise kurtosis term,
//    Var(v) = [2 sum_tau C(tau)^2 + (1/lambda) sum_tau K(tau)] / N, K(tau) = integral h^2(y) h^2(y + tau) dy,
//    with sum_tau K(tau) approximated by (integral h^2)^2 (a Riemann sum of h^2; the approximation only
//    scales the bound by a few percent). Bound: 5 standard errors.
//  - covariance and kurtosis: batch means over independent blocks (128 x 128 pixels, 4 to 8 times the
//    correlation length of a 16 x 16 texton, so neighbouring blocks are nearly independent): the standard
//    error is the standard deviation of the per-block estimates / sqrt(blocks). Bound: 4.5 standard errors
//    per lag (over the 145 independent lags a correct implementation fails with probability ~1e-3 in the
//    Gaussian approximation), 5 for the kurtosis.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "kernels/test_texton_common.h"
#include "runtime/reference.h"
#include "runtime/texton_renderer.h"

namespace stex {
namespace {

using test::model_lag_covariance;
using test::synthetic_model;
using test::texton_context;
using test::texton_moments;

constexpr int k_block = 128;

std::vector<float> render_splat(TextonRenderer& r, const RenderParams& p, std::int64_t x, std::int64_t y, int n) {
  TextonRenderOptions opt;
  opt.strategy = TextonStrategy::Splat;
  return r.render(p, x, y, n, n, opt);
}

// Mean and (biased) variance of channel c of an n x n interleaved image.
void mean_var(const std::vector<float>& img, int nc, int c, double* mean, double* var) {
  const std::size_t n = img.size() / nc;
  double s = 0;
  for (std::size_t i = 0; i < n; ++i) s += img[i * nc + c];
  const double m = s / double(n);
  double q = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double d = img[i * nc + c] - m;
    q += d * d;
  }
  *mean = m;
  *var = q / double(n);
}

double sum_c_squared(const TextonModel& m, int c) {
  const int reach = m.support + m.order;
  double s = 0;
  for (int dy = -reach; dy <= reach; ++dy)
    for (int dx = -reach; dx <= reach; ++dx) {
      const double v = model_lag_covariance(m, c, c, dx, dy);
      s += v * v;
    }
  return s;
}

double sum_alpha(const TextonModel& m, int c) {
  double s = 0;
  for (int i = 0; i < m.support * m.support; ++i) s += m.alpha[std::size_t(c) * m.support * m.support + i];
  return s;
}

// S1 Prop. 1 / Theorem 2: per-channel mean and variance over a 2048^2 colour render.
TEST(TextonStats, MeanAndVarianceMatchProposition1) {
  const TextonModel model = synthetic_model(3, 16, 1, 31);
  RenderParams params;
  params.seed = 2024;
  TextonRenderer renderer(texton_context(), model);
  const int n = 2048, nc = 3;
  const std::vector<float> img = render_splat(renderer, params, -1024, 333, n);
  const double N = double(n) * n;
  const double lambda = params.mni / double((model.support + 1) * (model.support + 1));
  for (int c = 0; c < nc; ++c) {
    double mean, var;
    mean_var(img, nc, c, &mean, &var);
    const test::TextonMoments mo = texton_moments(model, c);
    const double c0 = model_lag_covariance(model, c, c, 0, 0);
    ASSERT_NEAR(c0, mo.h2, 1e-9 * mo.h2) << "C(0) must equal the integral of h^2";
    const double se_mean = std::fabs(sum_alpha(model, c)) / std::sqrt(N);
    const double se_var = std::sqrt((2.0 * sum_c_squared(model, c) + mo.h2 * mo.h2 / lambda) / N);
    EXPECT_NEAR(mean, model.mean[c], 5 * se_mean) << "channel " << c;
    EXPECT_NEAR(var, c0, 5 * se_var) << "channel " << c;
    // Power: a noise normalised with r = s instead of s + 1 (variance off by (17/16)^2) would fail.
    EXPECT_GT(std::fabs(c0 * (17.0 * 17.0) / (16.0 * 16.0) - c0), 5 * se_var);
    std::printf("channel %d: mean %.6f (model %.6f, se %.2e), variance %.6e (C(0) %.6e, se %.2e)\n", c, mean,
                double(model.mean[c]), se_mean, var, c0, se_var);
  }
}

// Empirical covariance at |dx|, |dy| <= 8 against (alpha~ * alpha) * b, with batch-mean standard errors.
TEST(TextonStats, CovarianceMatchesModelAtLagsUpTo8) {
  const TextonModel model = synthetic_model(1, 16, 1, 32);  // anisotropic (oriented wave)
  RenderParams params;
  params.seed = 777;
  TextonRenderer renderer(texton_context(), model);
  const int n = 2048, L = 8;
  const std::vector<float> img = render_splat(renderer, params, 5, -9, n);
  double mean, var;
  mean_var(img, 1, 0, &mean, &var);
  const int nb = n / k_block, blocks = nb * nb;
  int worst_sigma_lag = 0;
  double worst = 0, transposed_max = 0;
  int tested = 0;
  for (int dy = 0; dy <= L; ++dy)
    for (int dx = -L; dx <= L; ++dx) {
      if (dy == 0 && dx < 0) continue;  // C(-tau) = C(tau)
      std::vector<double> est(blocks);
      for (int by = 0; by < nb; ++by)
        for (int bx = 0; bx < nb; ++bx) {
          double s = 0;
          long cnt = 0;
          const int x0 = bx * k_block + std::max(0, -dx), x1 = (bx + 1) * k_block - std::max(0, dx);
          for (int y = by * k_block; y < (by + 1) * k_block - dy; ++y) {
            const float* r0 = &img[std::size_t(y) * n];
            const float* r1 = &img[std::size_t(y + dy) * n + dx];
            for (int x = x0; x < x1; ++x) s += (r0[x] - mean) * (r1[x] - mean);
            cnt += x1 - x0;
          }
          est[by * nb + bx] = s / double(cnt);
        }
      double m = 0, q = 0;
      for (double e : est) m += e;
      m /= blocks;
      for (double e : est) q += (e - m) * (e - m);
      const double se = std::sqrt(q / (blocks - 1) / blocks);
      const double theory = model_lag_covariance(model, 0, 0, dx, dy);
      const double z = std::fabs(m - theory) / se;
      EXPECT_LT(z, 4.5) << "lag (" << dx << ", " << dy << "): empirical " << m << " theory " << theory << " se "
                        << se;
      if (z > worst) {
        worst = z;
        worst_sigma_lag = dy * 100 + dx;
      }
      transposed_max = std::max(transposed_max, std::fabs(m - model_lag_covariance(model, 0, 0, dy, dx)) / se);
      ++tested;
    }
  EXPECT_EQ(tested, 145);
  // Power: the transposed covariance (x and y swapped in the evaluation) is rejected by far.
  EXPECT_GT(transposed_max, 20.0);
  std::printf("covariance: 145 lags, worst |z| = %.2f at lag code %d; transposed model max |z| = %.1f\n", worst,
              worst_sigma_lag, transposed_max);
}

// Excess kurtosis of the normalised shot noise: kappa_4 / sigma^4 = integral h^4 / (lambda (integral h^2)^2).
TEST(TextonStats, ExcessKurtosisFollowsShotNoise) {
  const TextonModel model = synthetic_model(1, 16, 1, 33);
  const test::TextonMoments mo = texton_moments(model, 0);
  TextonRenderer renderer(texton_context(), model);
  const int n = 2048, nb = n / k_block, blocks = nb * nb;
  for (double mni : {1.0, 4.0, 30.0}) {
    RenderParams params;
    params.mni = mni;
    params.seed = 100 + std::uint64_t(mni);
    const double lambda = mni / double((model.support + 1) * (model.support + 1));
    const double theory = mo.h4 / (lambda * mo.h2 * mo.h2);
    const std::vector<float> img = render_splat(renderer, params, 0, 0, n);
    double mean, var;
    mean_var(img, 1, 0, &mean, &var);
    auto kurt_of = [&](int x0, int y0, int w, int h) {
      double m2 = 0, m4 = 0;
      for (int y = y0; y < y0 + h; ++y)
        for (int x = x0; x < x0 + w; ++x) {
          const double d = img[std::size_t(y) * n + x] - mean;
          const double d2 = d * d;
          m2 += d2;
          m4 += d2 * d2;
        }
      const double cnt = double(w) * h;
      m2 /= cnt;
      m4 /= cnt;
      return m4 / (m2 * m2) - 3.0;
    };
    const double k = kurt_of(0, 0, n, n);
    std::vector<double> est;
    for (int by = 0; by < nb; ++by)
      for (int bx = 0; bx < nb; ++bx) est.push_back(kurt_of(bx * k_block, by * k_block, k_block, k_block));
    double m = 0, q = 0;
    for (double e : est) m += e;
    m /= blocks;
    for (double e : est) q += (e - m) * (e - m);
    const double se = std::sqrt(q / (blocks - 1) / blocks);
    EXPECT_NEAR(k, theory, 5 * se) << "MNI " << mni;
    std::printf("MNI %g: excess kurtosis %.4f, shot-noise theory %.4f, batch se %.4f\n", mni, k, theory, se);
    if (mni == 1.0) {
      // Power: at MNI 1 the kurtosis is far from the Gaussian limit 0 and from a 13% error in lambda.
      EXPECT_GT(theory, 20 * se);
      EXPECT_GT(std::fabs(theory * (16.0 * 16.0) / (17.0 * 17.0) - theory), 5 * se);
    }
  }
}

// A tile at x = 10^12 has the same statistics as one at 0 (and equals the reference there).
TEST(TextonStats, FarOutTileHasTheSameStatistics) {
  const TextonModel model = synthetic_model(1, 16, 1, 34);
  RenderParams params;
  params.seed = 9;
  params.scale = 1.0;
  TextonRenderer renderer(texton_context(), model);
  const int n = 1024;
  const std::int64_t far = 1000000000000ll;
  const std::vector<float> a = render_splat(renderer, params, 0, 0, n);
  const std::vector<float> b = render_splat(renderer, params, far, -far, n);
  const double N = double(n) * n;
  const test::TextonMoments mo = texton_moments(model, 0);
  const double lambda = params.mni / 289.0;
  const double se_mean = std::fabs(sum_alpha(model, 0)) / std::sqrt(N);
  const double se_var = std::sqrt((2.0 * sum_c_squared(model, 0) + mo.h2 * mo.h2 / lambda) / N);
  double ma, va, mb, vb;
  mean_var(a, 1, 0, &ma, &va);
  mean_var(b, 1, 0, &mb, &vb);
  EXPECT_NEAR(ma, mb, 5 * std::sqrt(2.0) * se_mean);
  EXPECT_NEAR(va, vb, 5 * std::sqrt(2.0) * se_var);
  EXPECT_NEAR(vb, mo.h2, 5 * se_var);
  // Different realisations, not a copy.
  EXPECT_GT(test::count_bit_differences(a, b), a.size() * 99 / 100);
  // Reference equality far out (the precision claim: int64 cells, float only inside a cell).
  const TextonReference reference(model, params);
  EXPECT_EQ(test::count_bit_differences(test::crop(b, n, 1, 500, 600, 64, 48),
                                        reference.render(far + 500, -far + 600, 64, 48)),
            0u);
  std::printf("origin 0: mean %.6f var %.6e; origin 1e12: mean %.6f var %.6e; C(0) %.6e\n", ma, va, mb, vb, mo.h2);
}

// Poisson counts per cell: mean and variance of the count over many cells equal the per-cell mean (the
// count of a cell is an integer function of (seed, cell); every strategy reads it from the same table).
TEST(TextonStats, CellCountsArePoisson) {
  const TextonModel model = synthetic_model(1, 16, 1, 35);
  RenderParams params;
  params.seed = 31337;
  const TextonReference reference(model, params);
  const double mu = reference.setup().cell_mean;
  const int side = 300;
  double s = 0, q = 0;
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const double k = reference.cell_count(x - 150, y + 1000000000);
      s += k;
      q += k * k;
    }
  const double N = double(side) * side;
  const double m = s / N, v = q / N - m * m;
  // Poisson: Var(mean) = mu / N; Var(sample variance) ~ (mu_4 - mu^2) / N with mu_4 = mu + 3 mu^2.
  EXPECT_NEAR(m, mu, 5 * std::sqrt(mu / N));
  EXPECT_NEAR(v, mu, 5 * std::sqrt((mu + 2 * mu * mu) / N));
}

}  // namespace
}  // namespace stex
