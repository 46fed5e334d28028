// Poisson counts from integer threshold tables (kernels/shared/poisson.h, runtime/poisson_table.cpp): the
// table's properties and its exact mean and variance, the device sampler against the host bit for bit, and
// the distribution of per-cell counts drawn the way the renderers draw them (draw 0 of STEX_DOMAIN_COUNT of
// each cell) against Poisson(lambda).
//
// Thresholds: table moments within the bound the 2^-32 quantisation allows (derived below); the count
// distribution's chi-square below the upper 1e-6 quantile of chi-square with (bins - 1) degrees of freedom
// (tests/kernels/chi_square.h), bins pooled so that every expected count is >= 5; the sample mean within
// 5 sigma = 5 sqrt(lambda / n) of lambda. Seeds are fixed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

#include "core/error.h"
#include "kernels/chi_square.h"
#include "kernels/shared/poisson.h"
#include "kernels/shared/rng.h"
#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/poisson_table.h"
#include "runtime/program.h"
#include "test_device.h"

namespace stex {
namespace {

const double k_lambdas[] = {0.5, 3.0, 12.0, 30.0, 100.0};

Context& context() {
  static std::unique_ptr<Context> ctx = Context::create(stex::test::test_device_spec());
  return *ctx;
}

// Poisson(lambda) pmf for k = 0 .. kmax by the recurrence p(k) = p(k-1) lambda / k in long double
// (independent of the lgamma-based table code).
std::vector<long double> poisson_pmf(double lambda, std::size_t kmax) {
  std::vector<long double> p(kmax + 1);
  p[0] = std::exp(-static_cast<long double>(lambda));
  for (std::size_t k = 1; k <= kmax; ++k) p[k] = p[k - 1] * lambda / static_cast<long double>(k);
  return p;
}

TEST(PoissonTable, Properties) {
  for (double lambda : {0.5, 3.0, 12.0, 30.0, 100.0, 1000.0}) {
    SCOPED_TRACE("lambda " + std::to_string(lambda));
    const std::vector<std::uint32_t> t = poisson_threshold_table(lambda);
    const std::size_t K = t.size();
    ASSERT_GE(K, 2u);
    ASSERT_LE(K, std::size_t(STEX_POISSON_MAX_TABLE));
    EXPECT_EQ(t.back(), 0xffffffffu);
    for (std::size_t k = 0; k + 1 < K; ++k) {
      EXPECT_LT(t[k], 0xffffffffu) << "only the last entry saturates";
      EXPECT_LE(t[k], t[k + 1]) << "monotone at " << k;
    }
    // Entry k is floor(F(k) 2^32) of the true CDF: compare with the recurrence in long double. The two
    // evaluations of F differ by ~1e-18, so floor may differ by one only at an exact boundary.
    const std::vector<long double> pmf = poisson_pmf(lambda, K);
    long double cdf = 0.0L;
    for (std::size_t k = 0; k + 1 < K; ++k) {
      cdf += pmf[k];
      const long double scaled = std::floor(cdf * 4294967296.0L);
      EXPECT_LE(std::fabs(static_cast<long double>(t[k]) - scaled), 1.0L) << "entry " << k;
    }
    // K - 1 is the first k with F(k) 2^32 >= 2^32 - 1: the mass beyond K - 2 exceeds 2^-32.
    EXPECT_LT(static_cast<long double>(t[K - 2]), 4294967295.0L);

    // Exact moments of the quantised distribution: P(N > k) = (2^32 - T[k]) / 2^32 for k < K - 1, 0 beyond.
    long double mean = 0.0L, second = 0.0L;
    for (std::size_t k = 0; k + 1 < K; ++k) {
      const long double tail = (4294967296.0L - t[k]) / 4294967296.0L;
      mean += tail;                                                  // E[N] = sum_k P(N > k)
      second += (2.0L * static_cast<long double>(k) + 1.0L) * tail;  // E[N^2] = sum_k (2k + 1) P(N > k)
    }
    const long double var = second - mean * mean;
    // Quantisation bound. E[N] = sum_k P(N > k) changes by sum_{k < K-1} (F(k) - F_q(k)) in [0, (K - 1)
    // 2^-32) (each T[k] is F(k) 2^32 rounded down) minus the folded tail sum_{k >= K-1} (1 - F(k)). That tail
    // starts below 2^-32 and shrinks by at least r = lambda / (K + 1) per step (P(N > k+1) <= P(N > k)
    // lambda/(k+2)), so it is below 2^-32 / (1 - r). Likewise E[N^2] = sum_k (2k + 1) P(N > k) changes by
    // less than (K - 1)^2 2^-32 or 2^-32 ((2K - 1)/(1 - r) + 2r/(1 - r)^2). Var = E[N^2] - E[N]^2 then moves
    // by at most the E[N^2] bound plus (2 lambda + mean bound) times the mean bound.
    const long double eps = 1.0L / 4294967296.0L;
    const long double Kl = static_cast<long double>(K);
    const long double r = lambda / (Kl + 1.0L);
    ASSERT_LT(r, 1.0L);
    const long double mean_tol = (Kl + 1.0L / (1.0L - r)) * eps;
    const long double second_tol =
        (Kl * Kl + (2.0L * Kl - 1.0L) / (1.0L - r) + 2.0L * r / ((1.0L - r) * (1.0L - r))) * eps;
    const long double var_tol = second_tol + (2.0L * lambda + mean_tol) * mean_tol;
    EXPECT_LE(std::fabs(mean - lambda), mean_tol) << "mean " << double(mean);
    EXPECT_LE(std::fabs(var - lambda), var_tol) << "variance " << double(var);
    // Relative to lambda these bounds are 1e-9 or better for lambda >= 3 (3.6e-9 at lambda = 0.5).
    std::printf("lambda %7.1f: K %4zu, |mean - lambda| %.2e (bound %.2e), |var - lambda| %.2e (bound %.2e)\n",
                lambda, K, double(std::fabs(mean - lambda)), double(mean_tol),
                double(std::fabs(var - lambda)), double(var_tol));
  }
  EXPECT_THROW(poisson_threshold_table(0.0), Error);
  EXPECT_THROW(poisson_threshold_table(-1.0), Error);
  EXPECT_THROW(poisson_threshold_table(std::nan("")), Error);
  EXPECT_THROW(poisson_threshold_table(1e6), Error);  // longer than STEX_POISSON_MAX_TABLE
}

TEST(PoissonSampler, HostSearchIsTheSmallestThresholdAboveU) {
  for (double lambda : k_lambdas) {
    const std::vector<std::uint32_t> t = poisson_threshold_table(lambda);
    const std::uint32_t len = std::uint32_t(t.size());
    auto linear = [&](std::uint32_t u) {
      for (std::uint32_t k = 0; k < len; ++k)
        if (u < t[k]) return k;
      return len - 1;
    };
    for (std::uint32_t k = 0; k < len; ++k)
      for (std::uint32_t u : {t[k] - 1u, t[k], t[k] + 1u})
        ASSERT_EQ(stex_poisson_count(t.data(), len, u), linear(u));
    for (std::uint32_t u : {0u, 1u, 0x7fffffffu, 0xfffffffeu, 0xffffffffu})
      ASSERT_EQ(stex_poisson_count(t.data(), len, u), linear(u));
  }
  const std::uint32_t single[] = {0xffffffffu};
  EXPECT_EQ(stex_poisson_count(single, 1, 0u), 0u);
  EXPECT_EQ(stex_poisson_count(single, 1, 0xffffffffu), 0u);
}

TEST(PoissonSampler, DeviceEqualsHostBitForBit) {
  Context& ctx = context();
  Kernel kernel(ctx.program("rng_test.cl"), "poisson_lookup");
  for (double lambda : k_lambdas) {
    const std::vector<std::uint32_t> t = poisson_threshold_table(lambda);
    const std::uint32_t len = std::uint32_t(t.size());
    // Every threshold and its neighbours, the extremes, and 65536 words from the RNG.
    std::vector<std::uint32_t> u{0u, 1u, 0x80000000u, 0xfffffffeu, 0xffffffffu};
    for (std::uint32_t x : t) {
      u.push_back(x - 1u);
      u.push_back(x);
      u.push_back(x + 1u);
    }
    const stex_uvec4 key = stex_cell_key(12345, -678);
    for (std::uint32_t j = 0; j < 16384; ++j) {
      const stex_uvec4 v = stex_draw(key, 99u, 0u, j, STEX_DOMAIN_TEST);
      u.insert(u.end(), {v.x, v.y, v.z, v.w});
    }
    Buffer<std::uint32_t> table(ctx, t);
    Buffer<std::uint32_t> words(ctx, u);
    Buffer<std::uint32_t> counts(ctx, u.size());
    kernel.set_arg(0, table);
    kernel.set_arg(1, len);
    kernel.set_arg(2, words);
    kernel.set_arg(3, counts);
    kernel.launch(ctx, NDRange(u.size()));
    const std::vector<std::uint32_t> dev = counts.read();
    for (std::size_t i = 0; i < u.size(); ++i)
      ASSERT_EQ(dev[i], stex_poisson_count(t.data(), len, u[i])) << "lambda " << lambda << " u " << u[i];
  }
}

TEST(PoissonSampler, CellCountsFollowPoisson) {
  Context& ctx = context();
  Kernel kernel(ctx.program("rng_test.cl"), "poisson_cells");
  constexpr std::size_t k_width = 512, k_height = 512;  // 262144 cells per lambda
  const std::int64_t x0 = -256, y0 = 1000000000000ll;
  const std::uint64_t seed = 0x5eed5eed12345678ull;
  for (double lambda : k_lambdas) {
    SCOPED_TRACE("lambda " + std::to_string(lambda));
    const std::vector<std::uint32_t> t = poisson_threshold_table(lambda);
    const std::uint32_t len = std::uint32_t(t.size());
    Buffer<std::uint32_t> table(ctx, t);
    Buffer<std::uint32_t> counts(ctx, k_width * k_height);
    kernel.set_arg(0, table);
    kernel.set_arg(1, len);
    kernel.set_arg(2, cl_long(x0));
    kernel.set_arg(3, cl_long(y0));
    kernel.set_arg(4, std::uint32_t(seed));
    kernel.set_arg(5, std::uint32_t(seed >> 32));
    kernel.set_arg(6, counts);
    kernel.launch(ctx, NDRange(k_width, k_height));
    const std::vector<std::uint32_t> dev = counts.read();

    // The device counts are those of the reference (renderers rely on it), spot-checked on a stride.
    for (std::size_t i = 0; i < dev.size(); i += 97) {
      const stex_uvec4 key = stex_cell_key(x0 + std::int64_t(i % k_width), y0 + std::int64_t(i / k_width));
      const stex_uvec4 v =
          stex_draw(key, std::uint32_t(seed), std::uint32_t(seed >> 32), 0u, STEX_DOMAIN_COUNT);
      ASSERT_EQ(dev[i], stex_poisson_count(t.data(), len, v.x)) << "cell " << i;
    }

    const double n = double(dev.size());
    std::vector<std::uint64_t> hist(len, 0);
    double sum = 0.0;
    for (std::uint32_t c : dev) {
      ASSERT_LT(c, len);
      ++hist[c];
      sum += c;
    }
    EXPECT_NEAR(sum / n, lambda, 5.0 * std::sqrt(lambda / n));

    // Bins: pool the left tail until its expected count reaches 5, then single values while both the value
    // and everything to its right expect >= 5, and the rest as the right tail.
    const std::vector<long double> pmf = poisson_pmf(lambda, len);
    std::vector<double> expected;
    std::vector<std::uint64_t> observed;
    long double right_mass = 1.0L;
    std::uint64_t right_obs = std::uint64_t(n);
    long double acc_e = 0.0L;
    std::uint64_t acc_o = 0;
    for (std::uint32_t k = 0; k < len; ++k) {
      acc_e += pmf[k] * n;
      acc_o += hist[k];
      right_mass -= pmf[k];
      right_obs -= hist[k];
      if (acc_e >= 5.0L && right_mass * n >= 5.0L) {
        expected.push_back(double(acc_e));
        observed.push_back(acc_o);
        acc_e = 0.0L;
        acc_o = 0;
      } else if (right_mass * n < 5.0L) {
        // Everything from here on is the right tail (its mass computed as 1 - F, including k >= len).
        expected.push_back(double(acc_e + right_mass * n));
        observed.push_back(acc_o + right_obs);
        break;
      }
    }
    ASSERT_GE(expected.size(), 3u);
    for (double e : expected) ASSERT_GE(e, 5.0);
    std::uint64_t total = 0;
    for (std::uint64_t o : observed) total += o;
    ASSERT_EQ(total, dev.size());
    const double dof = double(expected.size() - 1);
    const double chi2 = test::pearson(observed, expected);
    const double threshold = test::chi2_upper_quantile(1e-6, dof);
    EXPECT_LT(chi2, threshold) << expected.size() << " bins";
    // Also not suspiciously close to the expectation (a sampler returning expected frequencies exactly).
    EXPECT_GT(chi2, test::chi2_lower_quantile(1e-6, dof)) << expected.size() << " bins";
  }
}

}  // namespace
}  // namespace stex
