// Higher-order textons (S1 §10): B-spline interpolation of orders 3 and 5 in evaluation.
//  - The kernels' B-spline weights (stex_bspline_weights, Horner forms in float) equal the centred B-spline's
//    defining sum at the tap offsets. Tolerance 2e-6 absolute: the weights are <= 1 and each is at most ~12
//    float operations, each rounding by <= 2^-24 relative (6e-8), so the error stays below 1e-6.
//  - Rendered noise of orders 3 and 5 has the model mean and the model covariance
//    C(tau) = sum_l R(l) b(tau - l) with b = psi * psi sampled (beta^7, beta^11), computed in
//    test_texton_common.h by quadrature of the defining B-spline (independent of the library's tables).
//    Standard errors as in test_texton_stats.cpp: batch means over 128 x 128 blocks (a 16 x 16 texton's
//    correlation length is <= 21 pixels, so blocks are nearly independent), bound 4.5 standard errors per
//    lag (41 lags: a correct implementation fails with probability ~3e-4 in the Gaussian approximation);
//    mean: 5 standard errors of Var(mean) = (sum alpha)^2 / N. Power: the covariance of the same alpha under
//    bilinear interpolation (what a kernel ignoring the order would produce) is rejected by far.
// Bit-identity of splat, gather and the reference for these orders is in test_texton_eval.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "kernels/shared/texton.h"
#include "kernels/test_texton_common.h"
#include "runtime/texton_renderer.h"

namespace stex {
namespace {

using test::bspline_def;
using test::model_lag_covariance;
using test::synthetic_model;
using test::texton_context;

TEST(TextonOrders, BsplineWeightsMatchTheDefinition) {
  for (int order : {3, 5}) {
    const int back = (order - 1) / 2;
    double worst = 0.0;
    for (int i = 0; i <= 1000; ++i) {
      const float f = i == 1000 ? 0.99999994f : float(i) / 1000.0f;
      float w[6];
      stex_bspline_weights(order, f, w);
      double sum = 0.0;
      for (int m = 0; m <= order; ++m) {
        const double expect = bspline_def(order, double(f) + back - m);
        worst = std::max(worst, std::fabs(double(w[m]) - expect));
        sum += w[m];
      }
      EXPECT_NEAR(sum, 1.0, 2e-6) << "partition of unity, order " << order << " f " << f;
    }
    EXPECT_LT(worst, 2e-6) << "order " << order;
  }
}

TEST(TextonOrders, RenderedCovarianceMatchesTheModel) {
  const int n = 1024, L = 4, block = 128;
  for (int order : {3, 5}) {
    const TextonModel model = synthetic_model(1, 16, order, 40 + order);  // anisotropic (oriented wave)
    TextonModel bilinear = model;
    bilinear.order = 1;
    RenderParams params;
    params.seed = 9000 + order;
    TextonRenderer renderer(texton_context(), model);
    TextonRenderOptions opt;
    opt.strategy = TextonStrategy::Splat;
    const std::vector<float> img = renderer.render(params, -300, 77, n, n, opt);
    double mean = 0;
    for (float v : img) mean += v;
    mean /= double(img.size());
    double sum_alpha = 0;
    for (float a : model.alpha) sum_alpha += a;
    const double se_mean = std::fabs(sum_alpha) / double(n);
    EXPECT_NEAR(mean, model.mean[0], 5 * se_mean) << "order " << order;

    const int nb = n / block, blocks = nb * nb;
    double worst = 0, bilinear_max = 0;
    int tested = 0;
    for (int dy = 0; dy <= L; ++dy)
      for (int dx = -L; dx <= L; ++dx) {
        if (dy == 0 && dx < 0) continue;
        std::vector<double> est(blocks);
        for (int by = 0; by < nb; ++by)
          for (int bx = 0; bx < nb; ++bx) {
            double s = 0;
            long cnt = 0;
            const int x0 = bx * block + std::max(0, -dx), x1 = (bx + 1) * block - std::max(0, dx);
            for (int y = by * block; y < (by + 1) * block - dy; ++y) {
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
        EXPECT_LT(z, 4.5) << "order " << order << " lag (" << dx << ", " << dy << "): empirical " << m
                          << " theory " << theory << " se " << se;
        worst = std::max(worst, z);
        bilinear_max = std::max(bilinear_max, std::fabs(m - model_lag_covariance(bilinear, 0, 0, dx, dy)) / se);
        ++tested;
      }
    EXPECT_EQ(tested, 41);
    EXPECT_GT(bilinear_max, 20.0) << "order " << order;
    std::printf("order %d: mean %.6f (model %.6f, se %.2e); 41 lags, worst |z| %.2f; bilinear model max |z| %.1f\n",
                order, mean, double(model.mean[0]), se_mean, worst, bilinear_max);
  }
}

}  // namespace
}  // namespace stex
