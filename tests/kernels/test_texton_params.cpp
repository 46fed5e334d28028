// runtime/texton_params: render parameters -> stex_texton_params (S1 §3.3 lambda = MNI / r^2, §8 cells of
// side c r). Checks the derived values against their definitions, the validation messages, and the one
// property the bit-identity of the strategies rests on: the reach is conservative, i.e. every displacement
// whose float tap lies inside the texton support (kernels/shared/texton.h) lies within [-reach_fwd,
// reach_back], for unit and non-unit scales (including the float rounding at the support edges).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "kernels/test_texton_common.h"
#include "runtime/poisson_table.h"
#include "runtime/texton_params.h"

namespace stex {
namespace {

using test::synthetic_model;

TEST(TextonParams, DerivedValues) {
  const TextonModel model = synthetic_model(3, 64, 1, 41);
  RenderParams rp;
  rp.mni = 30;
  rp.cell_factor = 0.6;
  rp.scale = 2.37;
  rp.seed = 0x1122334455667788ull;
  const TextonSetup s = make_texton_setup(model, rp);
  const stex_texton_params& p = s.params;
  EXPECT_EQ(p.support, 64);
  EXPECT_EQ(p.stride, 66);
  EXPECT_EQ(p.channels, 3);
  EXPECT_EQ(p.seed_lo, 0x55667788u);
  EXPECT_EQ(p.seed_hi, 0x11223344u);
  EXPECT_DOUBLE_EQ(s.lambda, 30.0 / (65.0 * 65.0));
  const std::int64_t a = std::llround(0.6 * 65 * 2.37 * 65536.0);
  EXPECT_EQ(s.cell_fix, a);
  EXPECT_EQ(stex_cell_size(p), a);
  // The per-cell mean uses the rounded A: the intensity is exact.
  const double side = double(a) / (65536.0 * 2.37);
  EXPECT_DOUBLE_EQ(s.cell_mean, s.lambda * side * side);
  EXPECT_EQ(s.poisson_table, poisson_threshold_table(s.cell_mean));
  EXPECT_EQ(p.poisson_len, s.poisson_table.size());
  EXPECT_EQ(p.t_lo, -1.0f);
  EXPECT_EQ(p.t_hi, 64.0f);
  EXPECT_EQ(p.inv_fix_scale, float(1.0 / (65536.0 * 2.37)));
  EXPECT_EQ(p.inv_sqrt_lambda, float(1.0 / std::sqrt(s.lambda)));
  for (int c = 0; c < 3; ++c) {
    double sum = 0;
    for (int i = 0; i < 64 * 64; ++i) sum += model.alpha[std::size_t(c) * 4096 + i];
    EXPECT_EQ(p.lambda_sum_alpha[c], float(s.lambda * sum));
    EXPECT_EQ(p.mean[c], model.mean[c]);
  }
  EXPECT_EQ(p.mean[3], 0.0f);
  // Padded planes: zero frame of 1, alpha(k) at (k + 1); stride + 2 zeros of slack after the last plane.
  ASSERT_EQ(s.alpha_padded.size(), 3u * 66 * 66 + 68);
  EXPECT_EQ(s.alpha_padded[0], 0.0f);
  EXPECT_EQ(s.alpha_padded[66 * 66 - 1], 0.0f);
  EXPECT_EQ(s.alpha_padded[2 * 66 * 66 + 5 * 66 + 8], model.alpha_at(2, 4, 7));
  // Reach covers the support [-1, 64) texels = [-1, 64) * 2^16 * 2.37 fixed units.
  EXPECT_GE(s.reach_back, std::int64_t(std::ceil(64 * 65536.0 * 2.37)));
  EXPECT_GE(s.reach_fwd, std::int64_t(std::ceil(1 * 65536.0 * 2.37)));

  TextonModel m0 = synthetic_model(1, 20, 0, 42);
  const TextonSetup s0 = make_texton_setup(m0, RenderParams{});
  EXPECT_DOUBLE_EQ(s0.lambda, 30.0 / 400.0);  // order 0: r = s
  EXPECT_EQ(s0.params.t_lo, -0.5f);
  EXPECT_EQ(s0.params.t_hi, 19.5f);
}

// Every displacement with an inside tap lies within the reach (brute force around both edges).
TEST(TextonParams, ReachIsConservative) {
  for (int order : {0, 1})
    for (double scale : {1.0, 0.5, 2.37, 1.0 / 1024.0 * 3.1, 1000.3, 0.77777})
      for (int support : {1, 16, 64, 255}) {
        const TextonModel model = synthetic_model(1, support, order, 43, 0.0f, false);
        RenderParams rp;
        rp.scale = scale;
        rp.cell_factor = 2.0;  // keeps A >= 256 fixed units at the smallest scale
        TextonSetup s;
        try {
          s = make_texton_setup(model, rp);
        } catch (const Error&) {
          continue;  // A out of range for this combination (tested in Validation)
        }
        auto inside = [&](std::int64_t dx) {
          float w00, w10, w01, w11;
          stex_texton_tap(s.params, dx, 0, &w00, &w10, &w01, &w11);
          return w00 != 0.0f || w10 != 0.0f || w01 != 0.0f || w11 != 0.0f ||
                 (float(dx) * s.params.inv_fix_scale >= s.params.t_lo &&
                  float(dx) * s.params.inv_fix_scale < s.params.t_hi);
        };
        const double f = 65536.0 * scale;
        const std::int64_t hi_edge = std::int64_t(double(s.params.t_hi) * f);
        const std::int64_t lo_edge = std::int64_t(double(s.params.t_lo) * f);
        for (std::int64_t d = -3000; d <= 3000; ++d) {
          if (inside(hi_edge + d)) {
            EXPECT_LE(hi_edge + d, s.reach_back) << "order " << order << " scale " << scale;
          }
          if (inside(lo_edge + d)) {
            EXPECT_GE(lo_edge + d, -s.reach_fwd) << "order " << order << " scale " << scale;
          }
        }
        // And it is tight to within the documented margin (2^-20 relative + 2 units).
        EXPECT_LE(s.reach_back, std::int64_t(double(s.params.t_hi) * f * (1 + 1.0 / 1048576.0)) + 3);
      }
}

TEST(TextonParams, Validation) {
  const TextonModel model = synthetic_model(1, 16, 1, 44);
  auto usage_message = [&](RenderParams rp) {
    try {
      make_texton_setup(model, rp);
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Usage) << e.what();
      return std::string(e.what());
    }
    return std::string("no error");
  };
  RenderParams rp;
  rp.mni = 0;
  EXPECT_NE(usage_message(rp).find("--mni"), std::string::npos);
  rp.mni = -1;
  EXPECT_NE(usage_message(rp).find("--mni"), std::string::npos);
  rp.mni = 10001;
  EXPECT_NE(usage_message(rp).find("--mni"), std::string::npos);
  rp.mni = NAN;
  EXPECT_NE(usage_message(rp).find("--mni"), std::string::npos);
  rp = RenderParams{};
  rp.cell_factor = 0.05;
  EXPECT_NE(usage_message(rp).find("--cell"), std::string::npos);
  rp.cell_factor = 2.5;
  EXPECT_NE(usage_message(rp).find("--cell"), std::string::npos);
  rp = RenderParams{};
  rp.scale = 2000;
  EXPECT_NE(usage_message(rp).find("--scale"), std::string::npos);
  rp.scale = 1.0 / 2048;
  EXPECT_NE(usage_message(rp).find("--scale"), std::string::npos);
  rp.scale = INFINITY;
  EXPECT_NE(usage_message(rp).find("--scale"), std::string::npos);
  // Cell side below 1/256 pixel: s = 1 (r = 2), c = 0.1, scale 1/1024 -> 0.0002 pixels.
  TextonModel tiny = synthetic_model(1, 1, 1, 45);
  rp = RenderParams{};
  rp.cell_factor = 0.1;
  rp.scale = 1.0 / 1024;
  try {
    make_texton_setup(tiny, rp);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("cell side"), std::string::npos) << e.what();
  }
  // A per-cell mean too large for the Poisson table (MNI 10000, c = 2 -> 40000 per cell).
  rp = RenderParams{};
  rp.mni = 10000;
  rp.cell_factor = 2.0;
  EXPECT_THROW(make_texton_setup(model, rp), Error);

  // Model validation: Input errors naming the field.
  TextonModel bad = model;
  bad.alpha.pop_back();
  EXPECT_THROW(validate_texton_model(bad), Error);
  bad = model;
  bad.alpha[7] = NAN;
  try {
    validate_texton_model(bad);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("alpha[7]"), std::string::npos);
  }
  bad = model;
  bad.channels = 5;
  EXPECT_THROW(validate_texton_model(bad), Error);
  bad = model;
  bad.order = 2;
  EXPECT_THROW(validate_texton_model(bad), Error);

  // Regions: |origin| + size < 2^46.
  const std::int64_t lim = std::int64_t(1) << 46;
  EXPECT_NO_THROW(validate_region(lim - 11, -(lim - 11), 10, 10));
  EXPECT_THROW(validate_region(lim - 10, 0, 10, 10), Error);
  EXPECT_THROW(validate_region(0, -(lim - 10), 10, 10), Error);
  EXPECT_THROW(validate_region(INT64_MIN, 0, 10, 10), Error);
  EXPECT_THROW(validate_region(0, 0, 0, 10), Error);
  EXPECT_THROW(validate_region(0, 0, 10, -1), Error);
}

}  // namespace
}  // namespace stex
