// Correctness of the benchmark baselines (issue #5; benchmarks/lib/): their speed is measured by `stex bench`
// and benchmarks/stex_bench, never here.
//  - The plain C++ OpenMP tile splat (benchmarks/lib/omp_splat.h) equals the C++ reference
//    (runtime/reference.h) bit for bit: it calls the same shared header functions in the same global order
//    (S1 §8 evaluation order of kernels/shared/texton.h), for any tile size and thread count, at unit scale
//    (the shifted-tap fast path, up to support 256) and at other scales (one tap per pixel), for both orders.
//  - The S1-as-published baseline kernel (kernels/bench_s1_baseline.cl) has the texton noise's mean and
//    variance (S1 Prop. 1). Tolerances: the mean's standard error is |sum alpha| / sqrt(N) (the sum of the
//    covariance over all lags is (integral h)^2 = (sum alpha)^2); the variance's is
//    sqrt((2 sum_tau C(tau)^2 + (integral h^2)^2 / lambda) / N) (Gaussian term plus the shot-noise kurtosis
//    term, as tests/kernels/test_texton_stats.cpp). Bound: 5 standard errors, plus for the variance the bias
//    of the Gaussian count approximation: the rounded count has variance lambda a^2 + 1/12 instead of
//    lambda a^2, which adds (1/12) sum_cells (integral_cell h)^2 / (lambda a^4) <= integral h^2 / (12 lambda a^2)
//    (Cauchy-Schwarz per cell): a relative bias of at most 1 / (12 x cell mean) (0.7 % at MNI 30). Its mean
//    count is unbiased up to the clamp at 0 (probability ~1e-4 per cell, each clamp moving the count by
//    about 1): negligible against the standard error.
//  - The quality measures of `stex bench` (benchmarks/lib/quality.h) follow their definitions: a render made
//    of exact copies of the exemplar has spectrum error 0, one with twice the exemplar's contrast has 3 (the
//    power of every ring is 4x); the excess kurtosis of a uniform marginal is -1.2.
//  - The FMA micro-kernel (kernels/bench_fma_peak.cl) computes, bit for bit, the recurrence the host
//    computes with std::fma (fused) or separate mul and add (contraction off on both sides).
#include <gtest/gtest.h>

#ifdef STEX_HAVE_BENCH

#include <cmath>
#include <cstdint>
#include <vector>

#include "benchmarks/lib/fma_peak.h"
#include "benchmarks/lib/omp_splat.h"
#include "benchmarks/lib/quality.h"
#include "benchmarks/lib/s1_baseline.h"
#include "kernels/test_texton_common.h"
#include "runtime/reference.h"
#include "runtime/texton_renderer.h"

namespace stex {
namespace {

using test::count_bit_differences;
using test::model_lag_covariance;
using test::synthetic_model;
using test::texton_context;
using test::texton_moments;

struct OmpCase {
  int channels, support, order;
  double scale, mni;
  std::int64_t x, y;
  int width, height;
};

void expect_omp_equals_reference(const OmpCase& k) {
  const TextonModel model = synthetic_model(k.channels, k.support, k.order, 7 + std::uint64_t(k.support));
  RenderParams params;
  params.mni = k.mni;
  params.scale = k.scale;
  params.seed = 0x5eed0000u + std::uint64_t(k.support);
  const TextonReference reference(model, params);
  const std::vector<float> want = reference.render(k.x, k.y, k.width, k.height);
  const TextonSetup setup = make_texton_setup(model, params);
  for (int tile : {5, 37, 128}) {
    for (int threads : {1, 2}) {
      bench::OmpSplatOptions opt;
      opt.tile = tile;
      opt.threads = threads;
      const std::vector<float> got = bench::omp_splat_render_interleaved(setup, k.x, k.y, k.width, k.height, opt);
      EXPECT_EQ(count_bit_differences(got, want), 0u)
          << "channels " << k.channels << " support " << k.support << " order " << k.order << " scale " << k.scale
          << " tile " << tile << " threads " << threads;
    }
  }
}

TEST(BenchBaselines, OmpSplatEqualsReferenceUnitScale) {
  expect_omp_equals_reference({3, 16, 1, 1.0, 30.0, -45, 17, 90, 70});
  expect_omp_equals_reference({1, 64, 1, 1.0, 30.0, 1000003, -77, 150, 40});
  expect_omp_equals_reference({1, 9, 0, 1.0, 8.0, -3, -3, 64, 64});
}

// Support 256 at unit scale: displacements reach 2^24 fixed units, the edge of the exact fast path.
TEST(BenchBaselines, OmpSplatEqualsReferenceSupport256) {
  expect_omp_equals_reference({1, 256, 1, 1.0, 4.0, -300, 11, 48, 20});
}

// The stex splat kernel at the supports `stex bench` measures (up to 256, where the displacements reach
// 2^24 fixed units): bit-identical to the reference like the OpenMP splat, whichever path it takes.
TEST(BenchBaselines, SplatKernelEqualsReferenceAtBenchSupports) {
  for (int support : {32, 256}) {
    const TextonModel model = synthetic_model(1, support, 1, 5 + std::uint64_t(support));
    RenderParams params;
    params.mni = 8.0;
    params.seed = 77;
    const TextonReference reference(model, params);
    TextonRenderer renderer(texton_context(), model);
    TextonRenderOptions opt;
    opt.strategy = TextonStrategy::Splat;
    const std::vector<float> got = renderer.render(params, -300, 11, 48, 20, opt);
    EXPECT_EQ(count_bit_differences(got, reference.render(-300, 11, 48, 20)), 0u) << "support " << support;
  }
}

TEST(BenchBaselines, OmpSplatEqualsReferenceOtherScales) {
  expect_omp_equals_reference({3, 12, 1, 1.7, 30.0, -20, 5, 60, 45});
  expect_omp_equals_reference({2, 10, 0, 0.6, 16.0, 7, -9, 50, 50});
}

TEST(BenchBaselines, S1BaselineHasTheModelMeanAndVariance) {
  const TextonModel model = synthetic_model(3, 16, 1, 41);
  const int n = 1024, nc = 3;
  const double mni = 30.0;
  bench::S1BaselineRenderer s1(texton_context(), model);
  const bench::S1Constants k = bench::s1_constants(model, mni);
  EXPECT_NEAR(k.cell, 17.0 / 1.6, 1e-12);
  EXPECT_NEAR(k.cell_mean, mni / (1.6 * 1.6), 1e-9);
  const std::vector<float> img = s1.render_interleaved(mni, 12345u, -300, 41, n, n);
  const double N = double(n) * n;
  for (int c = 0; c < nc; ++c) {
    double s = 0;
    for (std::size_t i = 0; i < img.size() / nc; ++i) s += img[i * nc + c];
    const double mean = s / N;
    double q = 0;
    for (std::size_t i = 0; i < img.size() / nc; ++i) q += (img[i * nc + c] - mean) * (img[i * nc + c] - mean);
    const double var = q / N;
    const test::TextonMoments mo = texton_moments(model, c);
    double sum_alpha = 0, sum_c2 = 0;
    for (int i = 0; i < model.support * model.support; ++i) sum_alpha += model.alpha[(std::size_t(c) * model.support * model.support) + std::size_t(i)];
    const int reach = model.support + 1;
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        const double v = model_lag_covariance(model, c, c, dx, dy);
        sum_c2 += v * v;
      }
    const double se_mean = std::fabs(sum_alpha) / std::sqrt(N);
    const double se_var = std::sqrt((2.0 * sum_c2 + mo.h2 * mo.h2 / k.lambda) / N);
    const double count_bias = mo.h2 / (12.0 * k.cell_mean);
    EXPECT_NEAR(mean, model.mean[c], 5 * se_mean) << "channel " << c;
    EXPECT_NEAR(var, mo.h2, 5 * se_var + count_bias) << "channel " << c;
    // Power: a normalisation with r = s instead of s + 1 would be rejected.
    EXPECT_GT(std::fabs(mo.h2 * (17.0 * 17.0) / (16.0 * 16.0) - mo.h2), 5 * se_var + count_bias);
    std::printf("S1 baseline channel %d: mean %.6f (model %.6f, se %.1e), variance %.6e (model %.6e, se %.1e, "
                "count bias <= %.1e)\n",
                c, mean, double(model.mean[c]), se_mean, var, mo.h2, se_var, count_bias);
  }
}

TEST(BenchBaselines, QualityMeasuresFollowTheirDefinitions) {
  Image ex;
  ex.width = 48;
  ex.height = 40;
  ex.channels = 2;
  ex.pixels.resize(std::size_t(ex.width) * ex.height * 2);
  for (int y = 0; y < ex.height; ++y)
    for (int x = 0; x < ex.width; ++x)
      for (int c = 0; c < 2; ++c) {
        const stex_uvec4 v = stex_draw(stex_cell_key(x, y), 3, 0, std::uint32_t(c), STEX_DOMAIN_TEST);
        ex.at(x, y, c) = 0.3f + 0.2f * stex_uniform24(v.x) + 0.1f * std::sin(0.7f * float(x) + float(c));
      }
  const bench::SpectrumReference ref(ex);
  // The exemplar plus less than half a block more on each side (blocks overlap by half: only the block at
  // the origin fits, an exact copy), and the same with the contrast doubled around 0.5.
  const int w = ex.width + ex.width / 2 - 1, h = ex.height + 3;
  std::vector<float> copies(std::size_t(w) * h * 2), doubled(copies.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 2; ++c) {
        const float v = ex.at(x % ex.width, y % ex.height, c);
        copies[(std::size_t(y) * w + x) * 2 + c] = v;
        doubled[(std::size_t(y) * w + x) * 2 + c] = 0.5f + 2.0f * (v - 0.5f);
      }
  EXPECT_LT(ref.error(copies.data(), w, h, 2), 1e-9);
  EXPECT_NEAR(ref.error(doubled.data(), w, h, 2), 3.0, 1e-5);
  EXPECT_THROW(ref.error(copies.data(), ex.width - 1, ex.height, 2), Error);  // smaller than one block
  EXPECT_THROW(ref.error(copies.data(), w, h, 1), Error);                      // channel mismatch

  std::vector<float> uniform(2 * 200000);
  for (std::size_t i = 0; i < uniform.size(); ++i)
    uniform[i] = stex_uniform24(stex_draw(stex_cell_key(std::int64_t(i), 0), 9, 0, 0, STEX_DOMAIN_TEST).x);
  EXPECT_NEAR(bench::excess_kurtosis(uniform.data(), uniform.size() / 2, 2), -1.2, 0.02);
}

TEST(BenchBaselines, PeakKernelComputesTheRecurrence) {
  const std::size_t items = 200;
  const int iterations = 37;
  for (bool fused : {true, false}) {
    // m, c chosen so that fused and unfused results differ (a check that each variant is what it says).
    const float m = 0.9990001f, c = 0.0013f;
    const std::vector<float> out = bench::run_peak_kernel(texton_context(), fused, items, iterations, m, c);
    ASSERT_EQ(out.size(), items);
    std::size_t bad = 0;
    for (std::size_t g = 0; g < items; ++g)
      if (out[g] != bench::peak_expected(fused, std::uint32_t(g), iterations, m, c)) ++bad;
    EXPECT_EQ(bad, 0u) << (fused ? "fma" : "mul+add") << ": out[0] = " << out[0]
                       << ", expected " << bench::peak_expected(fused, 0, iterations, m, c);
  }
  EXPECT_NE(bench::peak_expected(true, 3, iterations, 0.9990001f, 0.0013f),
            bench::peak_expected(false, 3, iterations, 0.9990001f, 0.0013f));
  EXPECT_DOUBLE_EQ(bench::peak_flops(10, 3), 10.0 * 3 * 12 * 16 * 2);
}

}  // namespace
}  // namespace stex

#else

TEST(BenchBaselines, SkippedWithoutBenchmarks) { GTEST_SKIP() << "built with STEX_BUILD_BENCHMARKS=OFF"; }

#endif
