// analysis/expected_psd.h: the expected Welch spectra of Gabor and cs-rpn models checked against independent
// derivations (no device; the renders are checked against them in tests/gabor and tests/cs).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <vector>

#include "analysis/cs_rpn_model.h"
#include "analysis/expected_psd.h"
#include "core/math.h"
#include "runtime/gabor_params.h"

namespace stex {
namespace {

double sum(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

// Radial bins of width 4 frequency bins (FFT order index -> bin; -1 beyond Nyquist and for the DC).
std::vector<std::vector<std::size_t>> radial_bins(int t) {
  std::vector<std::vector<std::size_t>> bins(std::size_t(t / 8));
  for (std::size_t i = 1; i < std::size_t(t) * t; ++i) {
    const int kx = int(i % t) >= t / 2 ? int(i % t) - t : int(i % t);
    const int ky = int(i / t) >= t / 2 ? int(i / t) - t : int(i / t);
    const std::size_t b = std::size_t(std::hypot(kx, ky) / 4.0);
    if (b < bins.size()) bins[b].push_back(i);
  }
  return bins;
}

TEST(ExpectedPsd, GaborAgreesWithTheTheoreticalSpectrum) {
  // Two derivations of one spectrum: the autocovariance route (gabor_expected_welch_psd: lags, orientation
  // mean by the midpoint rule, the cross term of the cos kernel, the Hann estimator) against gabor_psd, the
  // closed-form PSD in the frequency domain (|g^|^2 averaged over 64 orientations), sampled at k / T and
  // divided by T^2 (a Riemann sum of a spectrum whose integral is std^2). At T = 512 a lobe's std a / (2
  // sqrt(pi)) is 7.2 frequency bins, so the Hann window's blur (3 bins wide) moves < 1 % of a radial bin of
  // width 4 bins; bound 2 % per bin holding >= 0.5 % of the variance, and the variance to 1e-3 (the DC and
  // the frequencies beyond Nyquist are all that the Riemann sum leaves out: < 1e-6 here).
  GaborModel m;
  m.bandwidth = 0.05;
  m.stddev = 0.15;
  m.components.clear();
  for (const auto& r : {std::array<double, 4>{0.1, 0.5, 0.0, 1.0}, std::array<double, 4>{0.2, 0.0, 2.0 * k_pi, 0.5},
                        std::array<double, 4>{0.02, 1.0, 0.0, 0.3}}) {  // F = 0.02: the cos kernel's cross term
    GaborComponent c;
    c.frequency = r[0];
    c.orientation = r[1];
    c.spread = r[2];
    c.weight = r[3];
    m.components.push_back(c);
  }
  const int t = 512;
  const std::vector<double> got = gabor_expected_welch_psd(m, t);
  std::vector<double> want(got.size(), 0.0);
  for (std::size_t i = 1; i < want.size(); ++i) {
    const double u = double(int(i % t) >= t / 2 ? int(i % t) - t : int(i % t)) / t;
    const double v = double(int(i / t) >= t / 2 ? int(i / t) - t : int(i / t)) / t;
    want[i] = gabor_psd(m, u, v) / (double(t) * t);
  }
  EXPECT_NEAR(sum(got) / (m.stddev * m.stddev), 1.0, 1e-3);
  EXPECT_NEAR(sum(want) / (m.stddev * m.stddev), 1.0, 1e-3);
  double worst = 0.0;
  for (const auto& bin : radial_bins(t)) {
    double g = 0.0, w = 0.0;
    for (std::size_t i : bin) {
      g += got[i];
      w += want[i];
    }
    if (w < 0.005 * m.stddev * m.stddev) continue;
    worst = std::max(worst, std::fabs(g / w - 1.0));
    EXPECT_NEAR(g / w, 1.0, 0.02);
  }
  std::printf("gabor: autocovariance route / closed form, worst radial bin %.4f\n", worst);
  // the cross term matters: without it (F = 0.02 at a = 0.05: e^{-2 pi F^2 / a^2} = 0.37) the low bins differ
  EXPECT_GT(std::exp(-2.0 * k_pi * 0.02 * 0.02 / (0.05 * 0.05)), 0.3);
}

TEST(ExpectedPsd, CsRpnFourierIsTheSpectrumThroughTheHannWindow) {
  // The Fourier series (S4 Fig. 4) at the Welch period T = 1 / bin has its frequencies on the DFT grid, so
  // its expected Hann periodogram is the spectrum convolved with |H|^2: H = (-1/4, 1/2, -1/4) in magnitude
  // per axis, i.e. weights (1/6, 2/3, 1/6) after normalisation. An independent derivation of the lag route
  // (table -> Phi -> C(d) -> R_h -> FFT); to 1e-12 of the variance per frequency.
  CsRpnModel m;
  m.variant = CsRpnVariant::Fourier;
  const nlohmann::json j = {{"grid", {1, 1}}, {"size", 64}, {"spectra", {"bilobe:0.15,30,0.02"}}};
  cs_rpn_load_spectra(m, j);
  const int t = cs_rpn_spectrum_period(m);
  ASSERT_EQ(t, 64);
  const std::vector<double> target = cs_rpn_spectrum_psd(m, 0);
  const std::vector<double> got = cs_rpn_expected_welch_psd(m, 0);
  EXPECT_NEAR(sum(target), m.spectra[0].energy, 1e-9);
  const double w[3] = {1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0};
  double worst = 0.0;
  for (int ky = 0; ky < t; ++ky)
    for (int kx = 0; kx < t; ++kx) {
      if (kx == 0 && ky == 0) continue;
      double want = 0.0;
      for (int a = -1; a <= 1; ++a)
        for (int b = -1; b <= 1; ++b)
          want += w[a + 1] * w[b + 1] * target[std::size_t((ky + a + t) % t) * t + std::size_t((kx + b + t) % t)];
      worst = std::max(worst, std::fabs(got[std::size_t(ky) * t + kx] - want));
    }
  EXPECT_LT(worst, 1e-12 * m.spectra[0].energy);
}

TEST(ExpectedPsd, CsRpnBlursTheSpectrumByEachVariantsKernel) {
  // What each variant does to one bi-lobe (rendered alone). Each expected covariance is the Fourier variant's
  // times a positive-definite function equal to 1 at lag 0, so the expected spectrum is the Fourier variant's
  // convolved with a probability kernel: the energy E is kept (the DC aside) and the peak drops as the kernel
  // widens: fourier (no kernel) > random phase (the window of radius 1.5 Delta = 96 pixels: about 1 / 96 cycles
  // per pixel, 0.7 bins at T = 64) > gabor (a = 0.1: a lobe std of a / (2 sqrt(pi)) = 0.028 cycles per pixel,
  // 1.8 bins) > phasor. Phasor: C = E (pi / 4) sum_n c_n |rho|^{2n} Re rho with c_n >= 0 and sum_n c_n = 4 / pi;
  // |rho|^{2n} is positive definite and 1 at lag 0, so phasor's spectrum is a mixture of gabor's convolved with
  // probability kernels (for a bi-lobe, |rho|^2 carries 2f: the mixture has odd harmonics, 3f, 5f, ...).
  // Up to the sampling of the (smooth) spectra on the k / T grid, the peaks are ordered; the margins printed
  // below are wide.
  const nlohmann::json j = {{"grid", {1, 1}}, {"size", 64}, {"spectra", {"bilobe:0.1,0,0.01"}}};
  auto model = [&](CsRpnVariant v) {
    CsRpnModel m;
    m.variant = v;
    m.bandwidth = 0.1;
    m.spacing = 64.0;
    cs_rpn_load_spectra(m, j);
    return m;
  };
  const std::vector<CsRpnVariant> order = {CsRpnVariant::Fourier, CsRpnVariant::RandomPhase, CsRpnVariant::Gabor,
                                           CsRpnVariant::Phasor};
  std::vector<double> peaks, displaced;
  for (CsRpnVariant v : order) {
    const CsRpnModel m = model(v);
    const std::vector<double> psd = cs_rpn_expected_welch_psd(m, 0);
    EXPECT_NEAR(sum(psd) / m.spectra[0].energy, 1.0, 2e-3);
    peaks.push_back(*std::max_element(psd.begin(), psd.end()) / m.spectra[0].energy);
    displaced.push_back(cs_rpn_check_spectra(m)[0].displaced);
  }
  for (std::size_t i = 1; i < peaks.size(); ++i) {
    EXPECT_LT(peaks[i], peaks[i - 1]) << i;
    EXPECT_GT(displaced[i], displaced[i - 1]) << i;  // the wider the kernel, the more power leaves the lobes
  }
  EXPECT_GT(displaced[0], 0.0);  // the Hann window's own blur (1/6, 2/3, 1/6 per axis: 1 - (2/3)^2 at most)
  EXPECT_LT(displaced[0], 1.0 - 4.0 / 9.0);
  // and the check's error grows with the blur for the three linear variants
  std::vector<double> errors;
  for (std::size_t i = 0; i < 3; ++i) {
    const PsdComparison c = cs_rpn_check_spectra(model(order[i]))[0];
    errors.push_back(c.radial_median + c.radial_max);
  }
  EXPECT_LT(errors[0], errors[1]);
  EXPECT_LT(errors[1], errors[2]);
  std::printf("peak / E: fourier %.4f, random phase %.4f, gabor %.4f, phasor %.4f; displaced %.3f %.3f %.3f %.3f; "
              "median + max radial error: fourier %.3f, random phase %.3f, gabor %.3f\n",
              peaks[0], peaks[1], peaks[2], peaks[3], displaced[0], displaced[1], displaced[2], displaced[3], errors[0],
              errors[1], errors[2]);
}

}  // namespace
}  // namespace stex
