// Periodic + smooth decomposition (analysis/periodic.h, Moisan 2011): p is characterised by
// Laplacian_periodic(p) = Laplacian_free(u) and mean(p) = mean(u), so checking both (plus u = p + s and
// mean(s) = 0) verifies the decomposition completely. Tolerance 1e-10 on values of order 1: the FFT
// solve divides by eigenvalues >= min(2 - 2cos(2 pi/N)) ~ 1.5e-4 (N = 512), amplifying FFTW's ~1e-15
// relative error to ~1e-11 at most.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analysis/periodic.h"
#include "kernels/shared/rng.h"

namespace {

// A non-periodic test image: a ramp (large wrap-around jumps) plus counter-RNG noise.
std::vector<double> ramp_noise(int w, int h) {
  std::vector<double> u(std::size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      stex_uvec4 r = stex_draw(stex_cell_key(x, y), 1, 0, 0, STEX_DOMAIN_TEST);
      u[std::size_t(y) * w + x] = 0.01 * x - 0.02 * y + stex_uniform24(r.x);
    }
  return u;
}

TEST(Periodic, LaplacianAndMeanCharacterisePeriodicComponent) {
  for (auto [w, h] : {std::pair{64, 48}, std::pair{31, 17}, std::pair{512, 512}}) {
    auto u = ramp_noise(w, h);
    std::vector<double> s;
    auto p = stex::periodic_component(w, h, u, &s);
    auto lp = stex::laplacian_periodic(w, h, p);
    auto lf = stex::laplacian_free(w, h, u);
    double err = 0.0, mean_u = 0.0, mean_p = 0.0, mean_s = 0.0, sum_err = 0.0;
    for (std::size_t i = 0; i < u.size(); ++i) {
      err = std::max(err, std::abs(lp[i] - lf[i]));
      sum_err = std::max(sum_err, std::abs(p[i] + s[i] - u[i]));
      mean_u += u[i];
      mean_p += p[i];
      mean_s += s[i];
    }
    const double n = double(u.size());
    EXPECT_LT(err, 1e-10) << w << "x" << h;
    EXPECT_LT(sum_err, 1e-12);
    EXPECT_NEAR(mean_p / n, mean_u / n, 1e-12);
    EXPECT_NEAR(mean_s / n, 0.0, 1e-12);
    // s is smooth: harmonic away from the border (its periodic Laplacian is the boundary image).
    auto ls = stex::laplacian_periodic(w, h, s);
    double interior = 0.0;
    for (int y = 1; y + 1 < h; ++y)
      for (int x = 1; x + 1 < w; ++x) interior = std::max(interior, std::abs(ls[std::size_t(y) * w + x]));
    EXPECT_LT(interior, 1e-10);
  }
}

TEST(Periodic, ImageWithoutWrapJumpsIsUnchanged) {
  // Opposite borders equal: the boundary image is zero, so s = 0 and p = u.
  const int w = 40, h = 24;
  std::vector<double> u(std::size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      stex_uvec4 r = stex_draw(stex_cell_key(x, y), 2, 0, 0, STEX_DOMAIN_TEST);
      u[std::size_t(y) * w + x] = stex_uniform24(r.x);
    }
  for (int y = 0; y < h; ++y) u[std::size_t(y) * w + (w - 1)] = u[std::size_t(y) * w];
  for (int x = 0; x < w; ++x) u[std::size_t(h - 1) * w + x] = u[x];
  auto p = stex::periodic_component(w, h, u);
  for (std::size_t i = 0; i < u.size(); ++i) ASSERT_NEAR(p[i], u[i], 1e-10) << i;
}

TEST(Periodic, RampHasClosedFormPeriodicComponent) {
  // u(x, y) = x / w. In 1-D the conditions read: p'' = 0 inside, Laplacian_periodic(p)(0) = u(1) - u(0) =
  // 1/w and (w-1) = -1/w; p(x) = a x solves them with a w = 1/w, so p(x) = x / w^2 + c, with c fixed by
  // mean(p) = mean(u) = (w-1)/(2w). The wrap-around jump shrinks from (w-1)/w to (w-1)/w^2.
  const int w = 64, h = 32;
  std::vector<double> u(std::size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) u[std::size_t(y) * w + x] = double(x) / w;
  auto p = stex::periodic_component(w, h, u);
  const double c = (w - 1) / (2.0 * w) - (w - 1) / (2.0 * w * w);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      ASSERT_NEAR(p[std::size_t(y) * w + x], double(x) / (w * w) + c, 1e-12) << x << "," << y;
}

}  // namespace
