// The counter-based RNG (kernels/shared/rng.h) on the device against the C++ reference, and its statistical
// quality: kernels/rng_test.cl evaluates stex_cell_key / stex_draw / stex_uniform24 for grids of 64-bit cells
// (around 0, at +-10^12, at the INT64 limits and across the 32-bit word boundary of the coordinates) and the
// same headers compiled as C++ must give the same bits. The statistical tests run on the device's output
// (uniformity, independence of neighbouring cells and indices) and on the reference (avalanche).
//
// Thresholds: every chi-square statistic must lie between the lower and upper 1e-6 quantiles of the
// chi-square distribution with its degrees of freedom (computed in tests/kernels/chi_square.h, not from a
// table); correlations within 5 sigma of 0 with sigma = 1/sqrt(n); avalanche frequencies within 6 sigma of
// 1/2 with sigma = 1/(2 sqrt(N)). Seeds are fixed, so the results are deterministic; the quantiles bound the
// chance that a perfect RNG would fail a check at about 2e-6 per statistic.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "kernels/chi_square.h"
#include "kernels/shared/rng.h"
#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/program.h"
#include "test_device.h"

namespace stex {
namespace {

using test::chi2_lower_quantile;
using test::chi2_upper_quantile;
using test::pearson_uniform;

constexpr double k_p = 1e-6;  // tail probability of every chi-square threshold

Context& context() {
  static std::unique_ptr<Context> ctx = Context::create(stex::test::test_device_spec());
  return *ctx;
}

// Four 32 x 32 blocks of cells; cell c = b * 1024 + y * 32 + x is (origin_b.x + x, origin_b.y + y).
constexpr int k_block = 32;
constexpr int k_blocks = 4;
constexpr std::uint32_t k_indices = 64;  // draws per cell: 4096 cells * 64 draws * 4 words = 1,048,576 words
constexpr std::uint64_t k_seed = 0x0123456789abcdefull;

struct Origin {
  std::int64_t x, y;
};
constexpr Origin k_origins[k_blocks] = {
    {-16, -16},                           // around 0
    {1000000000000ll, -1000000000000ll},  // +-10^12
    {std::numeric_limits<std::int64_t>::max() - 31,
     std::numeric_limits<std::int64_t>::min()},                     // INT64 limits
    {-(std::int64_t(1) << 32) - 16, (std::int64_t(1) << 32) - 16},  // across the lo/hi word boundary
};

std::vector<std::int64_t> grid_cells() {
  std::vector<std::int64_t> cells;
  for (const Origin& o : k_origins)
    for (int y = 0; y < k_block; ++y)
      for (int x = 0; x < k_block; ++x) {
        cells.push_back(o.x + x);
        cells.push_back(o.y + y);
      }
  return cells;
}

struct Draws {
  std::vector<std::uint32_t> words;  // words[4 (cell * n_index + j) + lane]
  std::vector<float> uniforms;
};

Draws device_draws(const std::vector<std::int64_t>& cells, std::uint32_t n_index, std::uint32_t index0,
                   std::uint64_t seed, std::uint32_t domain) {
  Context& ctx = context();
  Kernel kernel(ctx.program("rng_test.cl"), "rng_draws");
  const std::size_t items = cells.size() / 2 * n_index;
  Buffer<std::int64_t> cell_buf(ctx, cells);
  Buffer<std::uint32_t> words(ctx, items * 4);
  Buffer<float> uniforms(ctx, items * 4);
  kernel.set_arg(0, cell_buf);
  kernel.set_arg(1, n_index);
  kernel.set_arg(2, index0);
  kernel.set_arg(3, std::uint32_t(seed));
  kernel.set_arg(4, std::uint32_t(seed >> 32));
  kernel.set_arg(5, domain);
  kernel.set_arg(6, words);
  kernel.set_arg(7, uniforms);
  kernel.launch(ctx, NDRange(items));
  return {words.read(), uniforms.read()};
}

// The main data set (device output), computed once.
const Draws& main_draws() {
  static const Draws draws = device_draws(grid_cells(), k_indices, 0, k_seed, STEX_DOMAIN_TEST);
  return draws;
}

std::uint32_t float_bits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

// Compares device draws with the reference; returns the number of values compared.
std::size_t expect_draws_match(const std::vector<std::int64_t>& cells, std::uint32_t n_index,
                               std::uint32_t index0, std::uint64_t seed, std::uint32_t domain,
                               const Draws& dev) {
  const std::size_t n_cells = cells.size() / 2;
  EXPECT_EQ(dev.words.size(), n_cells * n_index * 4);
  EXPECT_EQ(dev.uniforms.size(), n_cells * n_index * 4);
  std::size_t mismatches = 0;
  for (std::size_t c = 0; c < n_cells; ++c) {
    const stex_uvec4 key = stex_cell_key(cells[2 * c], cells[2 * c + 1]);
    for (std::uint32_t j = 0; j < n_index; ++j) {
      const stex_uvec4 v = stex_draw(key, std::uint32_t(seed), std::uint32_t(seed >> 32), index0 + j, domain);
      const std::uint32_t ref[4] = {v.x, v.y, v.z, v.w};
      const std::size_t g = c * n_index + j;
      for (int lane = 0; lane < 4; ++lane) {
        const bool same = dev.words[4 * g + lane] == ref[lane] &&
                          float_bits(dev.uniforms[4 * g + lane]) == float_bits(stex_uniform24(ref[lane]));
        if (!same && ++mismatches <= 5)
          ADD_FAILURE() << "cell (" << cells[2 * c] << ", " << cells[2 * c + 1] << ") index " << index0 + j
                        << " lane " << lane << ": device " << dev.words[4 * g + lane] << " reference "
                        << ref[lane];
      }
    }
  }
  EXPECT_EQ(mismatches, 0u);
  return n_cells * n_index * 4;
}

TEST(RngKernel, CellKeysMatchReference) {
  std::vector<std::int64_t> cells = grid_cells();
  const std::int64_t extremes[] = {0,
                                   -1,
                                   1,
                                   1000000000000ll,
                                   -1000000000000ll,
                                   std::numeric_limits<std::int64_t>::max(),
                                   std::numeric_limits<std::int64_t>::min(),
                                   std::int64_t(1) << 32,
                                   -(std::int64_t(1) << 32)};
  for (std::int64_t x : extremes)
    for (std::int64_t y : extremes) {
      cells.push_back(x);
      cells.push_back(y);
    }
  Context& ctx = context();
  Kernel kernel(ctx.program("rng_test.cl"), "rng_cell_keys");
  Buffer<std::int64_t> cell_buf(ctx, cells);
  Buffer<std::uint32_t> keys(ctx, cells.size() * 2);
  kernel.set_arg(0, cell_buf);
  kernel.set_arg(1, keys);
  kernel.launch(ctx, NDRange(cells.size() / 2));
  const std::vector<std::uint32_t> dev = keys.read();
  for (std::size_t c = 0; c < cells.size() / 2; ++c) {
    const stex_uvec4 k = stex_cell_key(cells[2 * c], cells[2 * c + 1]);
    ASSERT_EQ(dev[4 * c + 0], k.x) << cells[2 * c] << ", " << cells[2 * c + 1];
    ASSERT_EQ(dev[4 * c + 1], k.y) << cells[2 * c] << ", " << cells[2 * c + 1];
    ASSERT_EQ(dev[4 * c + 2], k.z) << cells[2 * c] << ", " << cells[2 * c + 1];
    ASSERT_EQ(dev[4 * c + 3], k.w) << cells[2 * c] << ", " << cells[2 * c + 1];
  }
}

TEST(RngKernel, DrawsMatchReferenceBitForBit) {
  const std::vector<std::int64_t> cells = grid_cells();
  std::size_t compared = expect_draws_match(cells, k_indices, 0, k_seed, STEX_DOMAIN_TEST, main_draws());
  EXPECT_GE(compared, 1000000u);  // words, and as many uniform24 floats

  // Another seed (all ones), the Poisson domain, and indices wrapping around 2^32.
  const std::vector<std::int64_t> block(cells.begin() + 2 * 1024 * 2, cells.begin() + 2 * 1024 * 3);
  const Draws other = device_draws(block, 128, 0xffffffc0u, ~std::uint64_t(0), STEX_DOMAIN_COUNT);
  expect_draws_match(block, 128, 0xffffffc0u, ~std::uint64_t(0), STEX_DOMAIN_COUNT, other);
}

TEST(RngStatistics, UniformFloatsAreExactAndInUnitInterval) {
  const Draws& d = main_draws();
  double sum = 0.0;
  for (std::size_t i = 0; i < d.uniforms.size(); ++i) {
    const float u = d.uniforms[i];
    ASSERT_GE(u, 0.0f);
    ASSERT_LT(u, 1.0f);
    ASSERT_EQ(u * 16777216.0f, float(d.words[i] >> 8)) << "a multiple of 2^-24 from the top 24 bits";
    sum += u;
  }
  // Mean of n uniforms: variance 1/(12 n); within 5 sigma of 1/2.
  const double n = double(d.uniforms.size());
  EXPECT_NEAR(sum / n, 0.5, 5.0 * std::sqrt(1.0 / (12.0 * n)));
  EXPECT_EQ(stex_uniform24(0u), 0.0f);
  EXPECT_EQ(stex_uniform24(0xffffffffu), 1.0f - 5.9604644775390625e-8f);
}

void expect_chi2_within(double chi2, double dof, const std::string& what) {
  const double lo = chi2_lower_quantile(k_p, dof), hi = chi2_upper_quantile(k_p, dof);
  EXPECT_GT(chi2, lo) << what << ": chi2 " << chi2 << " (dof " << dof << ") is suspiciously uniform";
  EXPECT_LT(chi2, hi) << what << ": chi2 " << chi2 << " (dof " << dof << ") above the 1e-6 quantile " << hi;
}

TEST(RngStatistics, WordsAreUniform) {
  const std::vector<std::uint32_t>& w = main_draws().words;
  // 256 bins for each byte of each lane: 16 statistics with 255 degrees of freedom, 262144 words each.
  for (int lane = 0; lane < 4; ++lane)
    for (int byte = 0; byte < 4; ++byte) {
      std::vector<std::uint64_t> hist(256, 0);
      for (std::size_t i = lane; i < w.size(); i += 4) ++hist[(w[i] >> (8 * byte)) & 0xff];
      expect_chi2_within(pearson_uniform(hist), 255,
                         "lane " + std::to_string(lane) + " byte " + std::to_string(byte));
    }
  // 65536 bins of the top and of the bottom 16 bits of all 1,048,576 words (16 expected per bin).
  for (int shift : {16, 0}) {
    std::vector<std::uint64_t> hist(65536, 0);
    for (std::uint32_t x : w) ++hist[(x >> shift) & 0xffff];
    expect_chi2_within(pearson_uniform(hist), 65535, "16-bit bins, shift " + std::to_string(shift));
  }
}

// 2-D chi-square of the top 4 bits of paired words (256 bins, dof 255 against the uniform product of the
// known uniform marginals) and the correlation of their uniform24 values.
void expect_independent(const std::vector<std::pair<std::size_t, std::size_t>>& pairs,
                        const std::string& what) {
  const Draws& d = main_draws();
  for (int lane = 0; lane < 4; ++lane) {
    std::vector<std::uint64_t> hist(256, 0);
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
    for (const auto& [a, b] : pairs) {
      const std::uint32_t wa = d.words[4 * a + lane], wb = d.words[4 * b + lane];
      ++hist[((wa >> 28) << 4) | (wb >> 28)];
      const double ua = d.uniforms[4 * a + lane], ub = d.uniforms[4 * b + lane];
      sa += ua;
      sb += ub;
      saa += ua * ua;
      sbb += ub * ub;
      sab += ua * ub;
    }
    const double n = double(pairs.size());
    const std::string label = what + ", lane " + std::to_string(lane);
    expect_chi2_within(pearson_uniform(hist), 255, label);
    const double cov = sab / n - (sa / n) * (sb / n);
    const double r = cov / std::sqrt((saa / n - (sa / n) * (sa / n)) * (sbb / n - (sb / n) * (sb / n)));
    EXPECT_LT(std::fabs(r), 5.0 / std::sqrt(n))
        << label << ": correlation " << r << " over " << n << " pairs";
  }
}

TEST(RngStatistics, NeighbouringCellsAndIndicesAreIndependent) {
  auto item = [](int b, int x, int y, std::uint32_t j) {
    return (std::size_t(b) * k_block * k_block + std::size_t(y) * k_block + std::size_t(x)) * k_indices + j;
  };
  std::vector<std::pair<std::size_t, std::size_t>> cx_pairs, cy_pairs, index_pairs;
  for (int b = 0; b < k_blocks; ++b)
    for (int y = 0; y < k_block; ++y)
      for (int x = 0; x < k_block; ++x)
        for (std::uint32_t j = 0; j < k_indices; ++j) {
          if (x + 1 < k_block) cx_pairs.emplace_back(item(b, x, y, j), item(b, x + 1, y, j));
          if (y + 1 < k_block) cy_pairs.emplace_back(item(b, x, y, j), item(b, x, y + 1, j));
          if (j + 1 < k_indices) index_pairs.emplace_back(item(b, x, y, j), item(b, x, y, j + 1));
        }
  ASSERT_GE(cx_pairs.size(), 250000u);
  expect_independent(cx_pairs, "cells (x, y) and (x + 1, y)");
  expect_independent(cy_pairs, "cells (x, y) and (x, y + 1)");
  expect_independent(index_pairs, "indices j and j + 1");
}

// Avalanche of the whole keyed draw stex_draw(stex_cell_key(cx, cy), seed, index, domain): flipping any one
// of the 256 input bits flips each of the 128 output bits with probability 1/2.
TEST(RngStatistics, EveryInputBitAvalanchesEveryOutputBit) {
  constexpr int k_samples = 10000;
  // N Bernoulli(1/2) trials: sigma of the frequency = 1/(2 sqrt(N)) = 0.005; tolerance 6 sigma = 0.03. Under
  // a perfect hash, P(|z| > 6) = 2e-9 per (input bit, output bit) pair, 6.6e-5 over all 32768 pairs.
  const double tolerance = 6.0 * 0.5 / std::sqrt(double(k_samples));
  struct Input {
    std::uint64_t cx, cy, seed;
    std::uint32_t index, domain;
  };
  auto eval = [](const Input& in) {
    const stex_uvec4 key = stex_cell_key(std::int64_t(in.cx), std::int64_t(in.cy));
    return stex_draw(key, std::uint32_t(in.seed), std::uint32_t(in.seed >> 32), in.index, in.domain);
  };
  auto flip = [](Input in, int bit) {
    if (bit < 64)
      in.cx ^= std::uint64_t(1) << bit;
    else if (bit < 128)
      in.cy ^= std::uint64_t(1) << (bit - 64);
    else if (bit < 192)
      in.seed ^= std::uint64_t(1) << (bit - 128);
    else if (bit < 224)
      in.index ^= std::uint32_t(1) << (bit - 192);
    else
      in.domain ^= std::uint32_t(1) << (bit - 224);
    return in;
  };
  std::mt19937_64 gen(20240611);
  std::vector<std::uint32_t> flips(256 * 128, 0);  // flips[in_bit * 128 + out_bit]
  for (int s = 0; s < k_samples; ++s) {
    Input in{gen(), gen(), gen(), std::uint32_t(gen()), std::uint32_t(gen())};
    const stex_uvec4 base = eval(in);
    for (int bit = 0; bit < 256; ++bit) {
      const stex_uvec4 v = eval(flip(in, bit));
      const std::uint32_t diff[4] = {v.x ^ base.x, v.y ^ base.y, v.z ^ base.z, v.w ^ base.w};
      for (int lane = 0; lane < 4; ++lane)
        for (int ob = 0; ob < 32; ++ob) flips[bit * 128 + lane * 32 + ob] += (diff[lane] >> ob) & 1u;
    }
  }
  const char* names[] = {"cx", "cy", "seed", "index", "domain"};
  int failures = 0;
  double worst = 0.0;
  for (int bit = 0; bit < 256; ++bit)
    for (int ob = 0; ob < 128; ++ob) {
      const double p = double(flips[bit * 128 + ob]) / k_samples;
      worst = std::max(worst, std::fabs(p - 0.5));
      if (std::fabs(p - 0.5) > tolerance && ++failures <= 10) {
        const int group = bit < 192 ? bit / 64 : bit < 224 ? 3 : 4;
        const int offset = bit < 192 ? bit % 64 : bit < 224 ? bit - 192 : bit - 224;
        ADD_FAILURE() << "flipping " << names[group] << " bit " << offset << " flips output lane " << ob / 32
                      << " bit " << ob % 32 << " with frequency " << p;
      }
    }
  EXPECT_EQ(failures, 0) << "largest deviation from 1/2: " << worst;
}

// The threshold helper itself, against closed forms: chi2(2) has P(X > x) = exp(-x/2); chi2(1) has
// P(X > x) = erfc(sqrt(x/2)).
TEST(ChiSquareHelper, MatchesClosedForms) {
  EXPECT_NEAR(chi2_upper_quantile(1e-6, 2), -2.0 * std::log(1e-6), 1e-9);
  EXPECT_NEAR(chi2_lower_quantile(1e-6, 2), -2.0 * std::log1p(-1e-6), 1e-12);
  for (double x : {0.1, 1.0, 5.0, 30.0}) EXPECT_NEAR(test::chi2_sf(x, 1), std::erfc(std::sqrt(x / 2)), 1e-15);
  // Large dof: the upper 1e-6 quantile lies about 4.75 standard deviations (sqrt(2 dof)) above the mean.
  const double q = chi2_upper_quantile(1e-6, 65535);
  EXPECT_GT(q, 65535 + 4.6 * std::sqrt(2.0 * 65535));
  EXPECT_LT(q, 65535 + 4.9 * std::sqrt(2.0 * 65535));
}

}  // namespace
}  // namespace stex
