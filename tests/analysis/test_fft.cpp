// Host FFT (analysis/fft.h): round trips, agreement with a direct DFT on small odd sizes, the real
// transforms against the complex one, and concurrent planning from several threads.
// Tolerances: FFTW's error is O(eps log N) relative to the L2 norm; with N <= 4096 and eps = 2.2e-16,
// 1e-12 (relative to the data's max magnitude) leaves a margin of more than 100x.
#include <gtest/gtest.h>

#include <cmath>
#include <thread>
#include <vector>

#include "analysis/fft.h"
#include "core/error.h"

namespace {

using stex::Complex;

std::vector<Complex> test_signal(int w, int h, unsigned salt) {
  std::vector<Complex> v(std::size_t(w) * h);
  for (std::size_t i = 0; i < v.size(); ++i) {
    // A deterministic, non-symmetric pattern (no RNG needed for a transform test).
    v[i] = Complex(std::sin(0.37 * double(i) + salt) + 0.25 * double((i * 7 + salt) % 5),
                   std::cos(1.13 * double(i) * double(salt + 1)));
  }
  return v;
}

double max_abs_diff(const std::vector<Complex>& a, const std::vector<Complex>& b) {
  double m = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

TEST(Fft, RoundTripIsIdentity) {
  for (auto [w, h] :
       {std::pair{64, 48}, std::pair{97, 97}, std::pair{1, 7}, std::pair{13, 1}, std::pair{512, 512}}) {
    auto x = test_signal(w, h, 3);
    auto y = x;
    stex::fft2d_forward(w, h, y);
    stex::fft2d_inverse(w, h, y);
    EXPECT_LT(max_abs_diff(x, y), 1e-12) << w << "x" << h;
  }
}

TEST(Fft, MatchesNaiveDftOnSmallOddSizes) {
  for (auto [w, h] : {std::pair{7, 5}, std::pair{9, 11}, std::pair{3, 1}}) {
    auto x = test_signal(w, h, 5);
    auto ref = stex::naive_dft2d(w, h, x, false);
    auto y = x;
    stex::fft2d_forward(w, h, y);
    EXPECT_LT(max_abs_diff(ref, y), 1e-11 * w * h) << w << "x" << h;
    auto ref_inv = stex::naive_dft2d(w, h, x, true);
    y = x;
    stex::fft2d_inverse(w, h, y);
    EXPECT_LT(max_abs_diff(ref_inv, y), 1e-12) << w << "x" << h;
  }
  // The sign convention: a unit impulse at (1, 0) has X(kx, ky) = exp(-2 i pi kx / w).
  const int w = 5, h = 3;
  std::vector<Complex> d(w * h, 0.0);
  d[1] = 1.0;
  stex::fft2d_forward(w, h, d);
  EXPECT_NEAR(d[1].real(), std::cos(-2 * M_PI / w), 1e-15);
  EXPECT_NEAR(d[1].imag(), std::sin(-2 * M_PI / w), 1e-15);
}

TEST(Fft, RealTransformsMatchComplex) {
  for (auto [w, h] : {std::pair{16, 12}, std::pair{15, 9}, std::pair{256, 256}}) {
    auto x = test_signal(w, h, 7);
    std::vector<double> re(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) re[i] = x[i].real();
    std::vector<Complex> full(re.begin(), re.end());
    stex::fft2d_forward(w, h, full);
    const int wh = stex::half_width(w);
    std::vector<Complex> half(std::size_t(wh) * h);
    stex::fft2d_r2c(w, h, re.data(), half.data());
    double err = 0.0;
    for (int ky = 0; ky < h; ++ky)
      for (int kx = 0; kx < wh; ++kx) err = std::max(err, std::abs(half[ky * wh + kx] - full[ky * w + kx]));
    EXPECT_LT(err, 1e-12 * w * h) << w << "x" << h;
    std::vector<double> back(re.size());
    stex::fft2d_c2r(w, h, half.data(), back.data());
    double err2 = 0.0;
    for (std::size_t i = 0; i < re.size(); ++i) err2 = std::max(err2, std::abs(back[i] - re[i]));
    EXPECT_LT(err2, 1e-12) << w << "x" << h;
  }
}

TEST(Fft, SupportTransformsMatchFullRealTransforms) {
  // A signal on the first `rows` rows: SupportFft's spectrum equals fft2d_r2c of the zero-padded grid, and
  // its inverse equals the first `rows` rows of fft2d_c2r.
  for (auto [w, h, rows] : {std::tuple{16, 12, 5}, std::tuple{15, 9, 9}, std::tuple{64, 64, 1}}) {
    stex::SupportFft sf(w, h, rows, 2);
    const int wh = stex::half_width(w);
    for (int c = 0; c < 2; ++c) {
      auto x = test_signal(w, h, unsigned(11 + c));
      std::vector<double> full(std::size_t(w) * h, 0.0);
      for (int i = 0; i < rows * w; ++i) full[i] = sf.real(c)[i] = x[i].real();
      std::vector<Complex> ref(std::size_t(wh) * h);
      stex::fft2d_r2c(w, h, full.data(), ref.data());
      sf.forward(c);
      double err = 0.0;
      for (std::size_t k = 0; k < ref.size(); ++k) err = std::max(err, std::abs(sf.spectrum(c)[k] - ref[k]));
      EXPECT_LT(err, 1e-12 * w * h) << w << "x" << h << " rows " << rows;
      // Inverse of an arbitrary Hermitian half spectrum (the reference's): rows [0, rows) of c2r.
      for (std::size_t k = 0; k < ref.size(); ++k) sf.spectrum(c)[k] = ref[k] * Complex(0.5, 0.25);
      std::vector<Complex> ref2(ref);
      for (auto& v : ref2) v *= Complex(0.5, 0.25);
      std::vector<double> back(full.size());
      stex::fft2d_c2r(w, h, ref2.data(), back.data());
      sf.inverse(c);
      double err2 = 0.0;
      for (int i = 0; i < rows * w; ++i) err2 = std::max(err2, std::abs(sf.real(c)[i] - back[i]));
      EXPECT_LT(err2, 1e-12) << w << "x" << h << " rows " << rows;
    }
  }
}

TEST(Fft, UnalignedBuffersUseTheirOwnPlan) {
  // An odd offset into a vector is not SIMD-aligned: the transform must still be right.
  const int w = 32, h = 8;
  auto x = test_signal(w, h, 9);
  std::vector<double> buf(w * h + 1);
  for (int i = 0; i < w * h; ++i) buf[i + 1] = x[i].real();
  std::vector<Complex> half(std::size_t(stex::half_width(w)) * h + 1);
  stex::fft2d_r2c(w, h, buf.data() + 1, half.data() + 1);
  std::vector<Complex> full(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) full[i] = x[i].real();
  stex::fft2d_forward(w, h, full);
  EXPECT_LT(std::abs(half[1 + 3] - full[3]), 1e-12 * w * h);
}

TEST(Fft, ConcurrentPlanningIsSafe) {
  // Sizes not used elsewhere, so that the threads race on the planner.
  std::vector<std::thread> threads;
  std::vector<double> errors(8, 1.0);
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([t, &errors] {
      const int w = 40 + t % 4, h = 30 + t % 3;
      auto x = test_signal(w, h, unsigned(t));
      auto y = x;
      stex::fft2d_forward(w, h, y);
      stex::fft2d_inverse(w, h, y);
      errors[t] = max_abs_diff(x, y);
    });
  }
  for (auto& th : threads) th.join();
  for (double e : errors) EXPECT_LT(e, 1e-12);
}

TEST(Fft, EmptySizeIsAnError) {
  std::vector<Complex> d(1);
  EXPECT_THROW(stex::fft2d_forward(0, 1, d.data()), stex::Error);
}

}  // namespace
