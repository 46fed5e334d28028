// OT distance between circular Gaussian models (analysis/ot_distance.h, S2 eq. 1), the projection of eq. 2,
// the RME (S2 §3.2) and the spectra of images and models:
//  - eq. 1 equals the general Gaussian W2 formula tr S0 + tr S1 - 2 tr (S0^1/2 S1 S0^1/2)^1/2 (+ |Theta| |m0
//  -
//    m1|^2) computed with Eigen on the explicit |Theta| d x |Theta| d covariance matrices S = H H^T of the
//    circular fields m + H W (the last trace as the nuclear norm of H0^T H1, see w2_squared), on 1-D and 2-D
//    tiny domains with 1, 2 and 3 channels; without the xi = 0 term it equals the same formula on the fields
//    with each channel's spatial mean removed;
//  - it is a metric on models: zero on itself and between kernels of one covariance (phase-shifted), positive
//    otherwise, symmetric, and the triangle inequality holds on 200 random triples;
//  - eq. 2: p_{h0}(h1) has h0's covariance, its L2 distance to h1 is d_OT, no kernel with h0's covariance is
//    closer, it is idempotent and real;
//  - the RME of a model against its exemplar equals the analysis' own RME (texton_rme) for order 0 and 1; the
//    spectra's colour covariances equal the direct ones; errors on mismatched inputs.
// Exact identities: tolerances are rounding (relative 1e-9 for eigen-decompositions, 1e-12 for sums).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "analysis/fft.h"
#include "analysis/gaussian_model.h"
#include "analysis/image_io.h"
#include "analysis/ot_distance.h"
#include "analysis/sot.h"
#include "analysis/texton.h"
#include "core/error.h"

namespace stex {
namespace {

// A random kernel of the given size (counter RNG via texton_initial_noise), optionally zero-sum per channel.
NormalisedKernel random_kernel(int w, int h, int ch, std::uint64_t seed, bool zero_sum = false) {
  NormalisedKernel k;
  k.width = w;
  k.height = h;
  k.channels = ch;
  k.t = texton_initial_noise(w, h, ch, seed);
  const std::size_t n = std::size_t(w) * h;
  for (int c = 0; c < ch; ++c) {
    k.mean[c] = 0.1 * double(seed % 7) + 0.05 * c;
    if (!zero_sum) continue;
    double s = 0.0;
    for (std::size_t i = 0; i < n; ++i) s += k.t[n * c + i];
    for (std::size_t i = 0; i < n; ++i) k.t[n * c + i] -= s / double(n);
  }
  return k;
}

// The fields F_c(x) = sum_z h_c(x - z) W(z) on the w x h torus as F = H W: H[(c,x), z] = h_c(x - z), so the
// covariance is S = H H^T (|Theta| d x |Theta| d). `centre` removes each channel's spatial mean from F (the
// projection onto xi != 0).
Eigen::MatrixXd field_matrix(const NormalisedKernel& k, bool centre) {
  const int w = k.width, h = k.height, ch = k.channels, n = w * h;
  Eigen::MatrixXd H(n * ch, n);
  for (int c = 0; c < ch; ++c)
    for (int x = 0; x < n; ++x)
      for (int z = 0; z < n; ++z) {
        const int dx = ((x % w - z % w) % w + w) % w, dy = ((x / w - z / w) % h + h) % h;
        H(c * n + x, z) = k.t[std::size_t(c) * n + std::size_t(dy) * w + dx];
      }
  if (centre) {
    for (int c = 0; c < ch; ++c) {
      Eigen::MatrixXd block = H.block(c * n, 0, n, n);
      const Eigen::RowVectorXd colmean = block.colwise().mean();
      H.block(c * n, 0, n, n) = block.rowwise() - colmean;
    }
  }
  return H;
}

// The general formula W2^2 = tr S0 + tr S1 - 2 tr (S0^1/2 S1 S0^1/2)^1/2 with S = H H^T. The last trace is
// evaluated as the nuclear norm of H0^T H1 (the non-zero eigenvalues of S0^1/2 S1 S0^1/2 are those of
// (H0^T H1)(H0^T H1)^T): the same number, but stable when S is rank-deficient (d > 1 channels share one W, so
// rank S <= |Theta|), where an eigen-decomposition square root turns rounding-level eigenvalues eps into
// sqrt(eps) errors. For one channel (full rank) the eigen-decomposition route is checked too.
double w2_squared(const Eigen::MatrixXd& h0, const Eigen::MatrixXd& h1) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(h0.transpose() * h1);
  return h0.squaredNorm() + h1.squaredNorm() - 2.0 * svd.singularValues().sum();
}

Eigen::MatrixXd psd_sqrt(const Eigen::MatrixXd& m) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(m);
  Eigen::VectorXd ev = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
}

double w2_squared_eigen(const Eigen::MatrixXd& s0, const Eigen::MatrixXd& s1) {
  const Eigen::MatrixXd r0 = psd_sqrt(s0);
  const Eigen::MatrixXd mid = r0 * s1 * r0;
  return s0.trace() + s1.trace() - 2.0 * psd_sqrt(0.5 * (mid + mid.transpose())).trace();
}

TEST(OtDistance, MatchesTheGeneralGaussianFormula) {
  struct Size {
    int w, h, ch;
  };
  for (const Size& sz : {Size{8, 1, 1}, Size{4, 3, 1}, Size{4, 3, 2}, Size{3, 3, 3}, Size{5, 4, 3}}) {
    for (std::uint64_t seed : {1u, 2u}) {
      const NormalisedKernel a = random_kernel(sz.w, sz.h, sz.ch, seed),
                             b = random_kernel(sz.w, sz.h, sz.ch, seed + 10);
      const GaussianSpectrum ga = gaussian_spectrum(a, sz.w, sz.h), gb = gaussian_spectrum(b, sz.w, sz.h);
      const double n = double(sz.w) * sz.h;
      SCOPED_TRACE(std::to_string(sz.w) + "x" + std::to_string(sz.h) + "x" + std::to_string(sz.ch));
      // With the xi = 0 term: the full circular fields.
      const OtDistance full = ot_distance(ga, gb, true);
      const Eigen::MatrixXd ha = field_matrix(a, false), hb = field_matrix(b, false);
      const double w2 = w2_squared(ha, hb);
      EXPECT_NEAR(full.d2 * n, w2, 1e-9 * std::max(1.0, w2));
      if (sz.ch == 1) {
        const double w2e = w2_squared_eigen(ha * ha.transpose(), hb * hb.transpose());
        EXPECT_NEAR(w2e, w2, 1e-8 * std::max(1.0, w2));
      }
      double m2 = 0.0;
      for (int c = 0; c < sz.ch; ++c) m2 += (a.mean[c] - b.mean[c]) * (a.mean[c] - b.mean[c]);
      EXPECT_NEAR((full.d2 + full.mean2) * n, w2 + n * m2, 1e-9 * std::max(1.0, w2 + n * m2));
      // Without it (S2 eq. 1): the fields with their spatial means removed.
      const OtDistance centred = ot_distance(ga, gb, false);
      const double w2c = w2_squared(field_matrix(a, true), field_matrix(b, true));
      EXPECT_NEAR(centred.d2 * n, w2c, 1e-9 * std::max(1.0, w2c));
      EXPECT_GT(full.d2, centred.d2 * 1.0001);  // random kernels have non-zero sums: the xi = 0 term counts
      // Zero-sum kernels: the two agree.
      const NormalisedKernel az = random_kernel(sz.w, sz.h, sz.ch, seed + 20, true),
                             bz = random_kernel(sz.w, sz.h, sz.ch, seed + 30, true);
      const GaussianSpectrum gaz = gaussian_spectrum(az, sz.w, sz.h), gbz = gaussian_spectrum(bz, sz.w, sz.h);
      EXPECT_NEAR(ot_distance(gaz, gbz, false).d2, ot_distance(gaz, gbz, true).d2, 1e-12);
      // Variances: 1/|Theta| sum_{xi != 0} |h^|^2 = trace of the centred covariance / |Theta|.
      EXPECT_NEAR(centred.variance0 * n, field_matrix(a, true).squaredNorm(), 1e-9 * n);
    }
  }
}

TEST(OtDistance, IsAMetricOnModels) {
  const int w = 16, h = 12, ch = 3;
  std::vector<GaussianSpectrum> pool;
  for (std::uint64_t s = 0; s < 8; ++s)
    pool.push_back(gaussian_spectrum(random_kernel(w, h, ch, 100 + s), w, h));
  // Smoothed and sharpened variants and mixtures, so that some models are close to each other.
  const std::size_t n = std::size_t(w) * h;
  for (int v = 0; v < 4; ++v) {
    GaussianSpectrum g = pool[std::size_t(v)];
    for (int c = 0; c < ch; ++c)
      for (std::size_t k = 0; k < n; ++k)
        g.hat[n * c + k] =
            0.7 * g.hat[n * c + k] + 0.3 * pool[std::size_t(v + 1)].hat[n * c + k] * (v % 2 ? 1.0 : 0.5);
    pool.push_back(g);
  }
  // A model equal to pool[0] with every frequency's phase rotated (the same covariance: distance 0).
  GaussianSpectrum rotated = pool[0];
  for (std::size_t k = 0; k < n; ++k) {
    const Complex ph = std::polar(1.0, 0.37 * double(k % 11));
    for (int c = 0; c < ch; ++c) rotated.hat[n * c + k] *= ph;
  }
  EXPECT_NEAR(ot_distance(pool[0], rotated).d2, 0.0, 1e-12 * pool[0].hat.size());
  for (std::size_t i = 0; i < pool.size(); ++i) {
    EXPECT_NEAR(ot_distance(pool[i], pool[i]).d2, 0.0, 1e-12);
    for (std::size_t j = 0; j < pool.size(); ++j) {
      const double dij = ot_distance(pool[i], pool[j]).distance(),
                   dji = ot_distance(pool[j], pool[i]).distance();
      EXPECT_NEAR(dij, dji, 1e-12 * std::max(1.0, dij));
      if (i != j) {
        EXPECT_GT(dij, 1e-3);
      }
    }
  }
  // Triangle inequality on 200 random triples (indices from the counter RNG).
  const std::vector<double> pick = texton_initial_noise(200, 3, 1, 42);
  int checked = 0;
  for (int t = 0; t < 200; ++t) {
    auto idx = [&](int r) {
      const double u = 0.5 * (1.0 + std::erf(pick[std::size_t(r) * 200 + t] / std::sqrt(2.0)));  // uniform
      return std::min(pool.size() - 1, std::size_t(u * double(pool.size())));
    };
    const GaussianSpectrum &a = pool[idx(0)], &b = pool[idx(1)], &c = pool[idx(2)];
    const double ab = ot_distance(a, b).distance(), bc = ot_distance(b, c).distance(),
                 ac = ot_distance(a, c).distance();
    EXPECT_LE(ac, ab + bc + 1e-12);
    ++checked;
  }
  EXPECT_EQ(checked, 200);
  EXPECT_NEAR(ot_distance(pool[0], rotated).distance() + ot_distance(rotated, pool[3]).distance(),
              ot_distance(pool[0], pool[3]).distance(), 1e-6);
}

TEST(OtProjection, Eq2IsTheClosestKernelWithTheReferenceCovariance) {
  for (int ch : {1, 3}) {
    const int w = 10, h = 9;
    const std::size_t n = std::size_t(w) * h;
    const GaussianSpectrum g0 = gaussian_spectrum(random_kernel(w, h, ch, 7), w, h),
                           g1 = gaussian_spectrum(random_kernel(w, h, ch, 8), w, h);
    const std::vector<Complex> p = ot_projection(g0, g1);
    double peak = 0.0;
    for (const Complex& v : g0.hat) peak = std::max(peak, std::abs(v));
    // Same covariance as h0: p^ p^* = h0^ h0^* per frequency (moduli and cross-spectra).
    for (std::size_t k = 0; k < n; ++k)
      for (int i = 0; i < ch; ++i)
        for (int j = 0; j < ch; ++j) {
          const Complex pp = p[n * i + k] * std::conj(p[n * j + k]),
                        hh = g0.hat[n * i + k] * std::conj(g0.hat[n * j + k]);
          EXPECT_NEAR(std::abs(pp - hh), 0.0, 1e-12 * peak * peak);
        }
    // L2 distance to h1 = d_OT (all frequencies).
    auto l2 = [&](const std::vector<Complex>& a) {
      double s = 0.0;
      for (std::size_t i = 0; i < a.size(); ++i) s += std::norm(a[i] - g1.hat[i]);
      return s / double(n);
    };
    const double dp = l2(p), dot = ot_distance(g0, g1, true).d2;
    EXPECT_NEAR(dp, dot, 1e-12 * std::max(1.0, dot));
    // No kernel with h0's covariance (h0^ e^{i phi(xi)}) is closer.
    for (std::uint64_t s = 0; s < 20; ++s) {
      const std::vector<double> phases = texton_initial_noise(w, h, 1, 500 + s);
      std::vector<Complex> k(g0.hat);
      for (std::size_t q = 0; q < n; ++q)
        for (int c = 0; c < ch; ++c) k[n * c + q] *= std::polar(1.0, 3.0 * phases[q]);
      EXPECT_GE(l2(k), dp - 1e-12);
    }
    // Idempotent, and a real kernel (Hermitian spectrum).
    GaussianSpectrum gp = g1;
    gp.hat = p;
    const std::vector<Complex> pp = ot_projection(g0, gp);
    for (std::size_t i = 0; i < p.size(); ++i) EXPECT_NEAR(std::abs(pp[i] - p[i]), 0.0, 1e-12 * peak);
    for (int c = 0; c < ch; ++c) {
      std::vector<Complex> sp(p.begin() + n * c, p.begin() + n * (c + 1));
      fft2d_inverse(w, h, sp);
      for (const Complex& v : sp) EXPECT_NEAR(v.imag(), 0.0, 1e-12 * peak);
    }
  }
}

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

TEST(OtDistance, RmeOfAModelAgainstItsExemplarIsTheAnalysisRme) {
  const Image u = gravel_crop(64);
  const GaussianSpectrum gu = gaussian_spectrum_of_image(u);
  EXPECT_EQ(relative_model_error(gu, gu), 0.0);
  GaussianSpectrum zero = gu;
  for (Complex& v : zero.hat) v = 0.0;
  EXPECT_NEAR(relative_model_error(gu, zero), 1.0, 1e-12);
  // Order 1 (S1) and order 0 (SOT) without colour correction: the model stores alpha as float, so the RMEs
  // agree to float rounding (relative ~1e-7 on alpha).
  TextonParams tp;
  tp.support = 16;
  tp.iterations = 10;
  tp.colour_correction = false;
  for (int order : {0, 1}) {
    tp.order = order;
    const TextonModel m = analyse_texton(u, tp);
    const GaussianSpectrum gm = gaussian_spectrum_of_model(m, 64, 64);
    EXPECT_NEAR(relative_model_error(gu, gm), m.rme, 1e-5) << "order " << order;
    // Colour covariance of the model's spectrum = model_colour_covariance (B-spline weighted for order 1).
    const double direct = model_colour_covariance(m.alpha, 1, 16, order)[0];
    EXPECT_NEAR(spectrum_colour_covariance(gm)[0], direct, 1e-12 * std::max(1e-12, direct));
  }
  SotParams sp;
  sp.mask = disc_mask(7);
  sp.max_iterations = 10;
  sp.colour_correction = false;
  SotReport rep;
  const TextonModel sot = analyse_sot(u, sp, &rep);
  EXPECT_NEAR(relative_model_error(gu, gaussian_spectrum_of_model(sot, 64, 64)), rep.rme, 1e-5);
  // The image's colour covariance = the exemplar covariance of its t_u.
  EXPECT_NEAR(spectrum_colour_covariance(gu)[0], exemplar_colour_covariance(normalised_kernel(u, true))[0],
              1e-15);
}

TEST(OtDistance, ErrorsOnMismatchedModels) {
  const GaussianSpectrum a = gaussian_spectrum(random_kernel(4, 4, 1, 1), 4, 4),
                         b = gaussian_spectrum(random_kernel(4, 4, 1, 2), 5, 4),
                         c = gaussian_spectrum(random_kernel(4, 4, 3, 3), 4, 4);
  EXPECT_THROW(ot_distance(a, b), Error);
  EXPECT_THROW(ot_distance(a, c), Error);
  EXPECT_THROW(ot_projection(a, c), Error);
  EXPECT_THROW(gaussian_spectrum(random_kernel(4, 4, 1, 1), 3, 4), Error);
}

}  // namespace
}  // namespace stex
