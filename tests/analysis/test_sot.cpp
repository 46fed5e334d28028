// The synthesis-oriented texton (analysis/sot.h, S2 Algorithm 2), its support masks
// (analysis/support_mask.h) and the baselines of S2 §4 (analysis/luminance_texton.h):
//  - masks: the digital disc, the square, a mask image (bounding box), the spec parser and its errors;
//  - Algorithm 2 on a square mask is S1 Algorithm 1 of order 0 (analysis/texton.h) value for value;
//  - a disc SOT is exactly zero outside the disc; the model is order 0, support 2R + 1, valid;
//  - the in-loop RME history equals the RME recomputed independently (texton_rme) of the n-iteration texton,
//    and is non-increasing (error reduction, see sot.h);
//  - the tolerance stop is the first n >= 2 with |RME_n - RME_{n-1}| < T, and returns that iterate;
//  - iteration 1 is the cropped random-phase texton; with S = Omega the joint colour projection reproduces
//    the model exactly (RME_1 = 0; a per-channel phase would not);
//  - the luminance texton's luminance has zero phase and each channel keeps |t_u^|;
//  - S2's claim: the SOT's RME is below the cropped luminance texton's (and the cropped random phase's) on
//  the
//    same support, on gravel (grey) and two synthesised colour Gaussian textures of different spectra;
//  - the Fig. 2 statistics do not depend on the thread count; parameter errors.
// Every computation is deterministic (counter RNG, fixed seeds): the comparisons are exact or to rounding.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/fft.h"
#include "analysis/gaussian_model.h"
#include "analysis/gaussian_synthesis.h"
#include "analysis/image_io.h"
#include "analysis/luminance_texton.h"
#include "analysis/sot.h"
#include "analysis/support_mask.h"
#include "analysis/texton.h"
#include "core/error.h"
#include "runtime/texton_params.h"

namespace stex {
namespace {

Image gravel_crop(int size) {
  const Image full = load_exemplar(std::string(STEX_SOURCE_DIR) + "/data/gravel.png");
  Image out;
  out.width = out.height = size;
  out.channels = full.channels;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      for (int c = 0; c < full.channels; ++c) out.pixels.push_back(full.at(x, y, c));
  return out;
}

// A colour Gaussian texture with a known spectrum: CADSN of a 3-channel kernel on an n x n torus.
//  'A': oriented band-pass Gabor kernels whose carrier phase differs per channel (colour phase structure);
//  'B': isotropic low-pass blobs of widths 1, 3, 6 px mixed differently per channel.
Image colour_gaussian(char which, int n, std::uint64_t seed) {
  const int ks = 21, r = ks / 2;
  NormalisedKernel k;
  k.width = k.height = ks;
  k.channels = 3;
  k.mean = {0.5, 0.4, 0.3, 0.0};
  k.t.assign(std::size_t(3) * ks * ks, 0.0);
  const double sig[3] = {1.0, 3.0, 6.0};
  const double mix[3][3] = {{1.0, 0.4, 0.1}, {0.2, 1.0, 0.5}, {0.1, 0.2, 1.0}};
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < ks; ++y)
      for (int x = 0; x < ks; ++x) {
        const double dx = x - r, dy = y - r, d2 = dx * dx + dy * dy;
        double v = 0.0;
        if (which == 'A') {
          v = 0.01 * std::exp(-d2 / 18.0) * std::cos(0.9 * dx + 0.35 * dy + 1.1 * c);
        } else {
          for (int j = 0; j < 3; ++j) v += 0.02 * mix[c][j] * std::exp(-d2 / (2 * sig[j] * sig[j])) / sig[j];
        }
        k.t[(std::size_t(c) * ks + y) * ks + x] = v;
      }
  return synthesize_cadsn(k, 0, 0, n, n, seed);
}

Image white_noise_image(int w, int h, int channels, std::uint64_t seed) {
  const std::vector<double> g = texton_initial_noise(w, h, channels, seed + 777);
  Image img;
  img.width = w;
  img.height = h;
  img.channels = channels;
  img.pixels.resize(std::size_t(w) * h * channels);
  const std::size_t n = std::size_t(w) * h;
  for (int c = 0; c < channels; ++c)
    for (std::size_t i = 0; i < n; ++i)
      img.pixels[i * channels + c] = float(0.5 + 0.1 * g[n * c + i] + 0.002 * double((i % w) * (c + 1)));
  return img;
}

double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
  EXPECT_EQ(a.size(), b.size());
  double m = 0.0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) m = std::max(m, std::fabs(a[i] - b[i]));
  return m;
}

double max_abs(const std::vector<double>& a) {
  double m = 0.0;
  for (double v : a) m = std::max(m, std::fabs(v));
  return m;
}

TEST(SupportMask, DiscSquareImageAndParser) {
  const SupportMask d0 = disc_mask(0);
  EXPECT_EQ(d0.size, 1);
  EXPECT_EQ(d0.count(), 1u);
  // r = 2: the 13 lattice points with dx^2 + dy^2 <= 4.
  const SupportMask d2 = disc_mask(2);
  EXPECT_EQ(d2.size, 5);
  EXPECT_EQ(d2.count(), 13u);
  EXPECT_TRUE(d2.contains(2, 0));
  EXPECT_FALSE(d2.contains(1, 0));
  EXPECT_FALSE(d2.contains(0, 0));
  const SupportMask d15 = disc_mask(15);
  std::size_t expected = 0;
  for (int y = -15; y <= 15; ++y)
    for (int x = -15; x <= 15; ++x) expected += (x * x + y * y <= 225) ? 1 : 0;
  EXPECT_EQ(d15.count(), expected);
  EXPECT_EQ(d15.centre_x, 15);
  for (int y = 0; y < 31; ++y)
    for (int x = 0; x < 31; ++x) {
      EXPECT_EQ(d15.contains(x, y), d15.contains(30 - x, y));
      EXPECT_EQ(d15.contains(x, y), d15.contains(y, x));
    }
  EXPECT_EQ(square_mask(7).count(), 49u);

  // Mask image: two non-zero pixels at (3, 2) and (5, 6): bounding box 3 x 5, padded to 5 x 5.
  Image m;
  m.width = 10;
  m.height = 9;
  m.channels = 1;
  m.pixels.assign(90, 0.0f);
  m.at(3, 2, 0) = 1.0f;
  m.at(5, 6, 0) = 0.2f;
  const SupportMask im = mask_from_image(m, "m.png");
  EXPECT_EQ(im.size, 5);
  EXPECT_EQ(im.count(), 2u);
  EXPECT_TRUE(im.contains(0, 0));
  EXPECT_TRUE(im.contains(2, 4));

  EXPECT_EQ(parse_support_mask("disc:5").size, 11);
  EXPECT_EQ(parse_support_mask("square:9").count(), 81u);
  for (const char* bad : {"disc:", "disc:x", "disc:-1", "square:0", "square:5000", "disc:3000", ""}) {
    try {
      parse_support_mask(bad);
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Usage) << bad;
    }
  }
  const std::string dir = std::string(STEX_TEST_TMP_DIR) + "/sot_masks";
  std::filesystem::create_directories(dir);
  write_image_atomic(dir + "/mask.png", m);
  const SupportMask from_file = parse_support_mask(dir + "/mask.png");
  EXPECT_EQ(from_file.size, 5);
  EXPECT_EQ(from_file.count(), 2u);
  m.pixels.assign(90, 0.0f);
  write_image_atomic(dir + "/empty.png", m);
  for (const std::string& bad : {dir + "/empty.png", dir + "/missing.png"}) {
    try {
      parse_support_mask(bad);
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << bad;
    }
  }
}

TEST(Sot, SquareMaskIsAlgorithm1OfOrderZero) {
  for (int ch : {1, 3}) {
    const Image u = white_noise_image(48, 40, ch, 3);
    TextonParams tp;
    tp.support = 12;
    tp.iterations = 15;
    tp.seed = 9;
    tp.order = 0;
    tp.colour_correction = false;
    const TextonModel a1 = analyse_texton(u, tp);
    const SotRun run = SotSolver(u, square_mask(12)).run(9, 15);
    ASSERT_EQ(run.alpha.size(), a1.alpha.size());
    ASSERT_EQ(run.iterations, 15);
    double worst = 0.0;
    for (std::size_t i = 0; i < run.alpha.size(); ++i)
      worst = std::max(worst, std::fabs(double(float(run.alpha[i])) - double(a1.alpha[i])));
    EXPECT_EQ(worst, 0.0) << "channels " << ch;  // same arithmetic, same FFTs: identical after float rounding
    EXPECT_NEAR(run.rme_history.back(), a1.rme, 1e-12);
  }
}

TEST(Sot, DiscSupportIsZeroOutsideTheDiscAndRenderable) {
  const Image u = gravel_crop(64);
  SotParams p;
  p.mask = disc_mask(6);
  p.max_iterations = 30;
  p.seed = 4;
  SotReport rep;
  const TextonModel m = analyse_sot(u, p, &rep);
  EXPECT_EQ(m.order, 0);
  EXPECT_EQ(m.support, 13);
  EXPECT_EQ(rep.support_pixels, p.mask.count());
  EXPECT_NO_THROW(validate_texton_model(m));
  double inside = 0.0;
  for (int y = 0; y < 13; ++y)
    for (int x = 0; x < 13; ++x) {
      if (p.mask.contains(x, y))
        inside = std::max(inside, double(std::fabs(m.alpha_at(0, y, x))));
      else
        EXPECT_EQ(m.alpha_at(0, y, x), 0.0f) << x << "," << y;
    }
  EXPECT_GT(inside, 1e-4);
  EXPECT_DOUBLE_EQ(m.rme, rep.rme);
  // Grey colour correction = variance rescale to the exemplar's variance: the model's covariance matches it.
  std::vector<double> alpha(m.alpha.begin(), m.alpha.end());
  const double var_model = model_colour_covariance(alpha, 1, 13, 0)[0];
  const double var_ex = exemplar_colour_covariance(normalised_kernel(u, true))[0];
  EXPECT_NEAR(var_model / var_ex, 1.0, 1e-5);  // float storage of alpha
  EXPECT_LT(rep.variance_kept, 1.0);
}

TEST(Sot, RmeHistoryIsTheRmeAndNeverIncreases) {
  for (int ch : {1, 3}) {
    const Image u = ch == 1 ? gravel_crop(64) : colour_gaussian('A', 64, 5);
    const SotSolver solver(u, disc_mask(7));
    const SotRun run = solver.run(2, 60);
    ASSERT_EQ(run.rme_history.size(), 60u);
    EXPECT_NEAR(run.rme_history.back(), solver.rme(run.alpha), 1e-12);
    for (int n : {1, 2, 7}) {
      const SotRun short_run = solver.run(2, n);
      EXPECT_EQ(max_abs_diff(short_run.alpha, SotSolver(u, disc_mask(7)).run(2, n).alpha), 0.0);
      EXPECT_NEAR(run.rme_history[std::size_t(n - 1)], solver.rme(short_run.alpha), 1e-12) << "n " << n;
    }
    // Error reduction: ||t_n - p(t_n)|| is non-increasing (rounding slack 1e-12).
    for (std::size_t k = 1; k < run.rme_history.size(); ++k)
      EXPECT_LE(run.rme_history[k], run.rme_history[k - 1] + 1e-12) << "channels " << ch << " n " << k + 1;
    EXPECT_LT(run.rme_history.back(), run.rme_history.front() - 0.1);
  }
}

TEST(Sot, ToleranceStopsAtTheFirstSmallChange) {
  const Image u = gravel_crop(64);
  const SotSolver solver(u, disc_mask(5));
  const SotRun full = solver.run(1, 150);
  EXPECT_FALSE(full.converged);
  EXPECT_EQ(full.iterations, 150);
  for (double tol : {1e-2, 1e-3, 1e-4}) {
    int expected = 150;
    for (int n = 2; n <= 150; ++n)
      if (std::fabs(full.rme_history[std::size_t(n - 1)] - full.rme_history[std::size_t(n - 2)]) < tol) {
        expected = n;
        break;
      }
    ASSERT_LT(expected, 150) << "the test needs a stop before the cap at tolerance " << tol;
    const SotRun stopped = solver.run(1, 150, tol);
    EXPECT_TRUE(stopped.converged);
    EXPECT_EQ(stopped.iterations, expected) << "tolerance " << tol;
    ASSERT_EQ(stopped.rme_history.size(), std::size_t(expected));
    EXPECT_EQ(max_abs_diff(stopped.alpha, solver.run(1, expected).alpha), 0.0);
  }
  const SotRun capped = solver.run(1, 3, 1e-12);
  EXPECT_EQ(capped.iterations, 3);
  EXPECT_FALSE(capped.converged);
  EXPECT_EQ(solver.run(1, 50, 1.0).iterations, 2);  // any change is below 1
}

TEST(Sot, FirstIterationIsTheCroppedRandomPhaseTexton) {
  for (int ch : {1, 3}) {
    const Image u = ch == 1 ? gravel_crop(48) : colour_gaussian('B', 48, 6);
    const SotSolver solver(u, disc_mask(8));
    const std::vector<double> rpn =
        cropped_random_phase_texton(solver.kernel(), solver.kernel_spectrum(), solver.mask(), 11);
    EXPECT_LT(max_abs_diff(rpn, solver.run(11, 1).alpha), 1e-12 * std::max(1.0, max_abs(rpn)) + 1e-15);
    // The uncropped random-phase image has exactly the modulus of t_u^ per channel.
    const std::vector<double> full = random_phase_texton(solver.kernel(), solver.kernel_spectrum(), 11);
    const std::size_t n = std::size_t(48) * 48;
    for (int c = 0; c < ch; ++c) {
      std::vector<Complex> f(full.begin() + n * c, full.begin() + n * (c + 1));
      fft2d_forward(48, 48, f);
      double worst = 0.0, peak = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        worst = std::max(worst, std::fabs(std::abs(f[k]) - std::abs(solver.kernel_spectrum()[n * c + k])));
        peak = std::max(peak, std::abs(f[k]));
      }
      EXPECT_LT(worst, 1e-12 * peak);
    }
  }
}

TEST(Sot, FullSupportJointColourProjectionIsExact) {
  // S = Omega: q_S is the identity and the first projection t_u^ e^{i psi} (one phase for all channels) has
  // the exemplar's covariance, cross-spectra included: RME_1 = 0 to rounding (sqrt of ~1e-16 relative).
  const Image u = colour_gaussian('A', 32, 8);
  const SotSolver solver(u, square_mask(32));
  const SotRun run = solver.run(3, 2);
  EXPECT_LT(run.rme_history[0], 1e-7);
  EXPECT_LT(run.rme_history[1], 1e-7);
}

TEST(LuminanceTexton, LuminanceHasZeroPhaseAndChannelsKeepTheirModulus) {
  const Image u = colour_gaussian('A', 40, 9);
  const NormalisedKernel tu = normalised_kernel(u, true);
  const std::vector<Complex> th = kernel_spectrum(tu);
  const std::vector<double> lum = luminance_texton(tu, th);
  const std::size_t n = std::size_t(40) * 40;
  std::vector<Complex> lh(lum.begin(), lum.end());
  for (int c = 0; c < 3; ++c) fft2d_forward(40, 40, lh.data() + n * c);
  const std::vector<double> w = luminance_weights(3);
  EXPECT_DOUBLE_EQ(w[0], 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(w[1], 0.5);
  double peak = 0.0;
  for (const Complex& v : th) peak = std::max(peak, std::abs(v));
  for (std::size_t k = 0; k < n; ++k) {
    Complex l = 0.0;
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(std::abs(lh[n * c + k]), std::abs(th[n * c + k]), 1e-12 * peak);
      l += w[std::size_t(c)] * lh[n * c + k];
    }
    EXPECT_NEAR(l.imag(), 0.0, 1e-12 * peak);
    EXPECT_GE(l.real(), -1e-12 * peak);
  }
  // Grey: zero phase, so the texton is even, t(x) = t(-x), and its crop is centred on the origin.
  const Image g = gravel_crop(32);
  const NormalisedKernel tg = normalised_kernel(g, true);
  const std::vector<double> lg = luminance_texton(tg, kernel_spectrum(tg));
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x)
      EXPECT_NEAR(lg[std::size_t(y) * 32 + x], lg[std::size_t((32 - y) % 32) * 32 + (32 - x) % 32], 1e-14);
  const SupportMask d = disc_mask(3);
  const std::vector<double> crop = cropped_luminance_texton(tg, kernel_spectrum(tg), d);
  EXPECT_DOUBLE_EQ(crop[3 * 7 + 3], lg[0]);        // centre = origin
  EXPECT_DOUBLE_EQ(crop[3 * 7 + 4], lg[1]);        // one to the right
  EXPECT_DOUBLE_EQ(crop[2 * 7 + 3], lg[31 * 32]);  // one up (wrap-around)
  EXPECT_EQ(crop[0], 0.0);                         // outside the disc
  EXPECT_GT(lg[0], 0.0);  // the zero-phase texton peaks at the origin: sum |t_u^| / |Omega| > 0
}

// S2 §4: "the SOT leads to lower RME value than the luminance texton cropped with the same support", with
// 1000 iterations as in S2 Fig. 4. The gaps are printed; they are deterministic (fixed seeds), so the
// comparison is exact, not statistical. The gap is small on the smooth low-pass texture B (about 0.004 at
// radius 15): there the luminance texton is nearly optimal, and after only 200 iterations the SOT of seed 0
// is still above it at radius 12 (0.4185 vs 0.4179; docs/s2.md).
TEST(Sot, BelowTheCroppedLuminanceTextonOnThreeExemplars) {
  struct Case {
    const char* name;
    Image u;
  };
  const std::vector<Case> cases = {{"gravel 96^2 (grey)", gravel_crop(96)},
                                   {"colour A (oriented band-pass)", colour_gaussian('A', 96, 21)},
                                   {"colour B (multi-scale low-pass)", colour_gaussian('B', 96, 22)}};
  for (const Case& c : cases) {
    for (int r : {5, 15}) {
      const SotSolver solver(c.u, disc_mask(r));
      const double sot = solver.run(0, 1000).rme_history.back();
      const double lum =
          solver.rme(cropped_luminance_texton(solver.kernel(), solver.kernel_spectrum(), solver.mask()));
      const double rpn = solver.rme(
          cropped_random_phase_texton(solver.kernel(), solver.kernel_spectrum(), solver.mask(), 0));
      std::printf("[ info ] %s, disc:%d: RME SOT %.4f, luminance texton %.4f, random phase %.4f\n", c.name, r,
                  sot, lum, rpn);
      EXPECT_LT(sot, lum) << c.name << " r " << r;
      EXPECT_LT(sot, rpn) << c.name << " r " << r;
      EXPECT_GT(sot, 0.0);
    }
  }
}

TEST(Sot, DeterministicSeededAndThreadIndependentStatistics) {
  const Image u = gravel_crop(48);
  const SotSolver solver(u, disc_mask(6));
  EXPECT_EQ(max_abs_diff(solver.run(5, 10).alpha, solver.run(5, 10).alpha), 0.0);
  EXPECT_GT(max_abs_diff(solver.run(5, 10).alpha, solver.run(6, 10).alpha), 1e-4);
  const SotConvergence one = sot_convergence(solver, 5, 12, 100, 1),
                       two = sot_convergence(solver, 5, 12, 100, 2);
  EXPECT_EQ(one.mean, two.mean);
  EXPECT_EQ(one.stddev, two.stddev);
  // Against the definition: mean and (n - 1)-normalised standard deviation of the per-seed histories.
  std::vector<std::vector<double>> h;
  for (int i = 0; i < 5; ++i) h.push_back(solver.run(100 + std::uint64_t(i), 12).rme_history);
  for (int k : {0, 5, 11}) {
    double m = 0.0;
    for (const auto& v : h) m += v[std::size_t(k)] / 5.0;
    double q = 0.0;
    for (const auto& v : h) q += (v[std::size_t(k)] - m) * (v[std::size_t(k)] - m);
    EXPECT_NEAR(one.mean[std::size_t(k)], m, 1e-14);
    EXPECT_NEAR(one.stddev[std::size_t(k)], std::sqrt(q / 4.0), 1e-14);
  }
  EXPECT_GT(one.stddev[0], 0.0);
}

TEST(Sot, ParameterErrors) {
  const Image u = gravel_crop(32);
  auto kind_of = [](auto&& f) {
    try {
      f();
    } catch (const Error& e) {
      return e.kind();
    }
    return ErrorKind::Internal;
  };
  EXPECT_EQ(kind_of([&] { SotSolver(u, disc_mask(16)); }), ErrorKind::Input);  // 33 > 32
  const SotSolver solver(u, disc_mask(4));
  EXPECT_EQ(kind_of([&] { solver.run(0, 0); }), ErrorKind::Usage);
  EXPECT_EQ(kind_of([&] { solver.run(0, 5, -1.0); }), ErrorKind::Usage);
  EXPECT_EQ(kind_of([&] { solver.run(0, 5, std::nan("")); }), ErrorKind::Usage);
  const std::vector<double> wrong(10, 0.0);
  EXPECT_EQ(kind_of([&] { solver.run(0, 5, 0.0, &wrong); }), ErrorKind::Usage);
  EXPECT_EQ(kind_of([&] { sot_convergence(solver, 1, 5); }), ErrorKind::Usage);
  Image empty;
  EXPECT_EQ(kind_of([&] { SotSolver(empty, disc_mask(1)); }), ErrorKind::Input);
}

}  // namespace
}  // namespace stex
