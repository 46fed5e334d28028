// Surface texton noise (S1 §6): Proposition 3 (mean, variance, MNI = lambda r^3) checked statistically on
// the C++ reference, the device kernel checked against the reference bit for bit, frames and validation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "core/error.h"
#include "kernels/shared/surface.h"
#include "kernels/test_texton_common.h"
#include "runtime/surface.h"

namespace stex {
namespace {

using test::synthetic_model;
using test::texton_context;

// A random unit vector from the counter RNG (uniform on the sphere: z uniform, angle uniform).
std::array<double, 3> random_unit(std::uint32_t i, std::uint32_t stream) {
  const stex_uvec4 v = stex_draw(stex_cell_key(i, stream), 11u, 0u, 0u, STEX_DOMAIN_TEST);
  const double z = 2.0 * stex_uniform24(v.x) - 1.0, phi = 6.283185307179586 * stex_uniform24(v.y);
  const double rxy = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {rxy * std::cos(phi), rxy * std::sin(phi), z};
}

struct Points {
  std::vector<float> pos, frames;
  std::size_t size() const { return pos.size() / 3; }
};

// n^3 points on a cubic lattice of spacing `spacing` world units (plus a random sub-texel jitter), each
// with a random frame (random normal and random tangent).
Points lattice_points(int n, double spacing, double jitter, double offset = 0.0) {
  Points p;
  std::uint32_t k = 0;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x, ++k) {
        const auto nrm = random_unit(k, 1), tan = random_unit(k, 2), j = random_unit(k, 3);
        p.pos.push_back(float(offset + x * spacing + jitter * j[0]));
        p.pos.push_back(float(offset + y * spacing + jitter * j[1]));
        p.pos.push_back(float(offset + z * spacing + jitter * j[2]));
        const auto f = surface_frame(nrm.data(), tan.data(), k);
        p.frames.insert(p.frames.end(), f.begin(), f.end());
      }
  return p;
}

// Proposition 3: E g^s = mean, Var g^s = integral h^2 (= the plane noise's variance), for any frames.
// Points are 2 r apart (more than the cube diagonal r sqrt(3)), so they share no impulse: independent
// samples. The tolerance is 4.5 standard errors of each estimator, from the exact moments of the shot
// noise (Campbell): Var(mean^) = sigma^2 / N; Var(var^) ~ (kappa4 + 2 sigma^4) / N with the fourth
// cumulant kappa4 = lambda integral (w h)^4 / (lambda r/3)^2 = lambda (r/5) h4 / (lambda r/3)^2, since
// integral (1 - 2|t|/r)^4 dt = r/5. Fixed seeds: the outcome is deterministic.
void check_proposition3(int order, double mni, double cell_factor, std::uint64_t seed) {
  const TextonModel m = synthetic_model(3, 8, order, 5);
  SurfaceParams sp;
  sp.mni = mni;
  sp.cell_factor = cell_factor;
  sp.seed = seed;
  sp.texel = 0.25;
  const SurfaceReference ref(m, sp);
  const double r = ref.setup().r, lambda = ref.setup().lambda;
  ASSERT_NEAR(lambda * r * r * r, mni, 1e-9 * mni);
  const Points pts = lattice_points(20, 2.0 * r * sp.texel, 3.0 * sp.texel);
  const std::size_t n = pts.size();
  std::vector<double> sum(3, 0.0), sum2(3, 0.0);
  std::vector<float> v(3);
  for (std::size_t k = 0; k < n; ++k) {
    ref.eval(&pts.pos[3 * k], &pts.frames[9 * k], v.data());
    for (int c = 0; c < 3; ++c) {
      sum[c] += v[c];
      sum2[c] += double(v[c]) * v[c];
    }
  }
  for (int c = 0; c < 3; ++c) {
    const test::TextonMoments mo = test::texton_moments(m, c);
    const double sigma2 = mo.h2;
    const double kappa4 = lambda * (r / 5.0) * mo.h4 / ((lambda * r / 3.0) * (lambda * r / 3.0));
    const double mean = sum[c] / double(n);
    const double var = sum2[c] / double(n) - mean * mean;
    const double se_mean = std::sqrt(sigma2 / double(n));
    const double se_var = std::sqrt((kappa4 + 2.0 * sigma2 * sigma2) / double(n));
    EXPECT_NEAR(mean, m.mean[c], 4.5 * se_mean) << "channel " << c << " order " << order;
    EXPECT_NEAR(var, sigma2, 4.5 * se_var) << "channel " << c << " order " << order << " (r/2 instead of r/3 "
                                           << "in the normalisation would give " << sigma2 * 1.5 << ")";
  }
}

TEST(SurfaceNoise, Proposition3MeanAndVarianceBilinear) { check_proposition3(1, 60.0, 0.6, 1); }
TEST(SurfaceNoise, Proposition3MeanAndVarianceNearestLowMni) { check_proposition3(0, 10.0, 0.35, 2); }

// Proposition 3: a point sees lambda r^3 impulses on average, those in the cube of side r about it with the
// frame's axes. Counted with the shared header's own cell walk; Poisson counts: the standard error of the
// mean over N independent points is sqrt(MNI / N); 4.5 of them.
TEST(SurfaceNoise, MeanNumberOfImpactsIsLambdaRCubed) {
  const TextonModel m = synthetic_model(1, 12, 1, 3);
  SurfaceParams sp;
  sp.mni = 60.0;
  sp.seed = 9;
  const SurfaceReference ref(m, sp);
  const stex_surface_params p = ref.setup().params;
  const double r = ref.setup().r;
  const Points pts = lattice_points(12, 2.0 * r, 2.0);
  double total = 0.0;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const float* q = &pts.pos[3 * k];
    const float* u = &pts.frames[9 * k];
    const auto k0 = [&](float x) { return std::int64_t(std::floor((x - p.reach) * p.inv_cell)); };
    const auto k1 = [&](float x) { return std::int64_t(std::floor((x + p.reach) * p.inv_cell)); };
    for (std::int64_t kz = k0(q[2]); kz <= k1(q[2]); ++kz)
      for (std::int64_t ky = k0(q[1]); ky <= k1(q[1]); ++ky)
        for (std::int64_t kx = k0(q[0]); kx <= k1(q[0]); ++kx) {
          const stex_uvec4 key = stex_cell_key3(kx, ky, kz);
          const std::uint32_t cnt = stex_surface_count(p, key, ref.setup().poisson_table.data());
          for (std::uint32_t j = 0; j < cnt; ++j) {
            float x, y, z;
            stex_surface_impulse(p, key, kx, ky, kz, j, &x, &y, &z);
            const double d[3] = {double(q[0]) - x, double(q[1]) - y, double(q[2]) - z};
            bool inside = true;
            for (int a = 0; a < 3; ++a) {
              const double t = d[0] * u[3 * a] + d[1] * u[3 * a + 1] + d[2] * u[3 * a + 2];
              inside = inside && std::fabs(t) < r / 2.0;
            }
            total += inside ? 1.0 : 0.0;
          }
        }
  }
  const double n = double(pts.size());
  EXPECT_NEAR(total / n, sp.mni, 4.5 * std::sqrt(sp.mni / n));
}

// The unnormalised sum has mean lambda r/2 sum(alpha) (Proposition 3 before normalisation); checked on a
// model with a large sum(alpha) so that the mean dominates.
TEST(SurfaceNoise, UnnormalisedMeanIsLambdaHalfRSumAlpha) {
  const TextonModel m = synthetic_model(1, 6, 1, 4, /*offset=*/0.05f);
  SurfaceParams sp;
  sp.seed = 21;
  const SurfaceReference ref(m, sp);
  const double r = ref.setup().r, lambda = ref.setup().lambda;
  const test::TextonMoments mo = test::texton_moments(m, 0);
  const Points pts = lattice_points(16, 2.0 * r, 1.0);
  double sum = 0.0;
  float acc = 0.0f;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    ref.sum(&pts.pos[3 * k], &pts.frames[9 * k], &acc);
    sum += acc;
  }
  const double n = double(pts.size());
  const double expected = lambda * r / 2.0 * mo.h1;             // integral h = sum alpha (bilinear)
  const double se = std::sqrt(lambda * r / 3.0 * mo.h2 / n);  // Var f^s = lambda r/3 integral h^2
  EXPECT_NEAR(sum / n, expected, 4.5 * se);
}

// The device kernel is the reference compiled as OpenCL C: identical bits, for any batch size, near the
// origin and far from it.
TEST(SurfaceNoise, KernelMatchesReferenceBitForBit) {
  for (int order : {0, 1}) {
    const TextonModel m = synthetic_model(3, 10, order, 7);
    SurfaceParams sp;
    sp.seed = 0x123456789abcull;
    sp.texel = 0.01;
    SurfaceReference ref(m, sp);
    SurfaceRenderer dev(texton_context(), m);
    for (double offset : {-0.37, 1000.0}) {
      const Points pts = lattice_points(9, 0.013, 0.05, offset);
      const std::size_t n = pts.size();
      std::vector<float> expected(n * 3), got(n * 3), got_small(n * 3);
      for (std::size_t k = 0; k < n; ++k) ref.eval(&pts.pos[3 * k], &pts.frames[9 * k], &expected[3 * k]);
      dev.eval(sp, n, pts.pos.data(), pts.frames.data(), got.data());
      dev.eval(sp, n, pts.pos.data(), pts.frames.data(), got_small.data(), 37);
      EXPECT_EQ(test::count_bit_differences(expected, got), 0u) << "order " << order << " offset " << offset;
      EXPECT_EQ(test::count_bit_differences(expected, got_small), 0u);
    }
  }
}

// Nearby points give nearby values (the field is continuous): the mean squared difference between points
// 0.05 texel apart is small against the variance.
TEST(SurfaceNoise, ContinuousAlongTheSurface) {
  const TextonModel m = synthetic_model(1, 8, 1, 8);
  SurfaceParams sp;
  const SurfaceReference ref(m, sp);
  const double n3[3] = {0.3, 0.4, 0.866};
  const auto f = surface_frame(n3, nullptr);
  double d2 = 0.0, v2 = 0.0;
  float a = 0, b = 0;
  for (int i = 0; i < 400; ++i) {
    const float p[3] = {float(i * 2.1), float(i * 0.7), 3.0f};
    const float q[3] = {p[0] + 0.05f * f[0], p[1] + 0.05f * f[1], p[2] + 0.05f * f[2]};
    ref.eval(p, f.data(), &a);
    ref.eval(q, f.data(), &b);
    d2 += double(a - b) * (a - b);
    v2 += double(a - m.mean[0]) * (a - m.mean[0]);
  }
  EXPECT_LT(d2, 0.05 * v2);
}

TEST(SurfaceFrame, OrthonormalWithGivenTangentAndWithout) {
  const double n[3] = {0.0, 0.0, -2.0}, t[3] = {1.0, 1.0, 5.0};
  for (const double* tan : {static_cast<const double*>(t), static_cast<const double*>(nullptr)}) {
    const auto f = surface_frame(n, tan);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const double d = double(f[3 * a]) * f[3 * b] + double(f[3 * a + 1]) * f[3 * b + 1] +
                         double(f[3 * a + 2]) * f[3 * b + 2];
        EXPECT_NEAR(d, a == b ? 1.0 : 0.0, 1e-6);
      }
    EXPECT_FLOAT_EQ(f[8], -1.0f);
  }
  const auto g = surface_frame(n, t);
  EXPECT_NEAR(g[0], std::sqrt(0.5), 1e-6);  // the tangent projected on the tangent plane
  EXPECT_NEAR(g[1], std::sqrt(0.5), 1e-6);
}

TEST(SurfaceFrame, BadInputNamesThePoint) {
  const double zero[3] = {0, 0, 0}, nan3[3] = {NAN, 0, 1};
  try {
    surface_frame(zero, nullptr, 17);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("point 17"), std::string::npos);
  }
  EXPECT_THROW(surface_frame(nan3, nullptr), Error);
  SurfaceParams sp;
  const double far[3] = {0, 1e7, 0};
  EXPECT_THROW(validate_surface_position(sp, far, 0), Error);
  sp.texel = 0;
  EXPECT_THROW(validate_surface_params(sp), Error);
  sp = SurfaceParams{};
  sp.mni = -1;
  EXPECT_THROW(validate_surface_params(sp), Error);
}

}  // namespace
}  // namespace stex
