// Expected Welch spectra of Gabor and cs-rpn models, and the estimator part shared with LRP's. See
// expected_psd.h.
#include "analysis/expected_psd.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <string>

#include <Eigen/Dense>

#include "analysis/fft.h"
#include "analysis/lrp.h"
#include "core/error.h"
#include "core/math.h"
#include "runtime/lrp_model.h"

namespace stex {

WelchHann welch_hann(int t) {
  WelchHann h;
  h.period = t;
  std::vector<double> hann(static_cast<std::size_t>(t));
  h.r1.assign(std::size_t(2 * t - 1), 0.0);
  for (int i = 0; i < t; ++i) hann[std::size_t(i)] = std::pow(std::sin(k_pi * (i + 0.5) / t), 2.0);
  for (int d = -(t - 1); d <= t - 1; ++d)
    for (int i = 0; i < t; ++i)
      if (i + d >= 0 && i + d < t) h.r1[std::size_t(d + t - 1)] += hann[std::size_t(i)] * hann[std::size_t(i + d)];
  h.h2 = h.r1[std::size_t(t - 1)] * h.r1[std::size_t(t - 1)];
  return h;
}

std::vector<double> expected_welch_psd(int t, const std::function<double(int, int)>& cov) {
  const WelchHann h = welch_hann(t);
  std::vector<Complex> folded(std::size_t(t) * t, Complex(0.0, 0.0));
  for (int dy = -(t - 1); dy <= t - 1; ++dy)
    for (int dx = -(t - 1); dx <= t - 1; ++dx) {
      const double rh = h.r1[std::size_t(dx + t - 1)] * h.r1[std::size_t(dy + t - 1)];
      folded[std::size_t((dy + t) % t) * t + std::size_t((dx + t) % t)] += cov(dx, dy) * rh;
    }
  fft2d_forward(t, t, folded);
  std::vector<double> out(folded.size());
  for (std::size_t i = 0; i < folded.size(); ++i) out[i] = folded[i].real() / (double(t) * t * h.h2);
  out[0] = 0.0;  // lrp_welch zeroes the DC
  return out;
}

double lrp_window_autocorrelation(double rho) {
  // midpoint rule on a 300 x 300 grid over [-1.5, 1.5]^2, rho = k 0.01, linear in between
  static const std::vector<double> g = [] {
    const int ng = 300;
    const double hg = 3.0 / ng;
    std::vector<double> wgrid(std::size_t(ng) * ng);
    for (int j = 0; j < ng; ++j)
      for (int i = 0; i < ng; ++i)
        wgrid[std::size_t(j) * ng + i] = lrp_window(std::hypot(-1.5 + (i + 0.5) * hg, -1.5 + (j + 0.5) * hg));
    std::vector<double> out(ng + 1, 0.0);
    for (int k = 0; k < ng; ++k) {
      double s = 0.0;
      for (int j = 0; j < ng; ++j)
        for (int i = 0; i + k < ng; ++i) s += wgrid[std::size_t(j) * ng + i] * wgrid[std::size_t(j) * ng + i + k];
      out[std::size_t(k)] = s * hg * hg;
    }
    return out;
  }();
  const double u = rho / 0.01;
  const int k = int(u);
  if (k >= int(g.size()) - 1) return 0.0;
  return g[std::size_t(k)] + (u - k) * (g[std::size_t(k) + 1] - g[std::size_t(k)]);
}

namespace {

double sinc(double u) { return u == 0.0 ? 1.0 : std::sin(k_pi * u) / (k_pi * u); }

// 2F1(1/2, 1/2; 2; z) for z in [0, 1]: (4 / (pi z)) (E(k) - (1 - z) K(k)), k^2 = z; its series near 0 (where
// the closed form cancels) and 4 / pi at 1 (where (1 - z) K(k) -> 0).
double hyp2f1_half_half_two(double z) {
  if (z < 1e-3) return 1.0 + z * (1.0 / 8.0 + z * (3.0 / 64.0 + z * 25.0 / 1024.0));
  if (z >= 1.0 - 1e-12) return 4.0 / k_pi;
  const double k = std::sqrt(z);
  return 4.0 / (k_pi * z) * (std::comp_ellint_2(k) - (1.0 - z) * std::comp_ellint_1(k));
}

}  // namespace

std::vector<double> gabor_expected_welch_psd(const GaborModel& m, int t) {
  validate_gabor_model(m);
  const double a2 = m.bandwidth * m.bandwidth;
  // lags where the envelope e^{-pi a^2 |d|^2 / 2} exceeds 1e-12
  const int reach = std::min(t - 1, int(std::ceil(std::sqrt(2.0 * 12.0 * std::log(10.0) / (k_pi * a2)))));
  const int nl = 2 * reach + 1;
  // (fx, fy, weight) of every orientation sample
  std::vector<std::array<double, 3>> waves;
  double norm = 0.0, cross = 0.0;
  for (const GaborComponent& c : m.components) {
    if (c.weight <= 0.0) continue;
    const double e = std::exp(-2.0 * k_pi * c.frequency * c.frequency / a2);
    norm += c.weight * (1.0 + e);
    cross += c.weight * e;
    const int n = c.spread > 0.0
                      ? std::max(1, int(std::ceil(2.0 * k_pi * c.frequency * std::sqrt(2.0) * reach * c.spread / 0.2)))
                      : 1;
    for (int i = 0; i < n; ++i) {
      const double th = c.orientation + (n > 1 ? c.spread * ((i + 0.5) / n - 0.5) : 0.0);
      waves.push_back({c.frequency * std::cos(th), c.frequency * std::sin(th), c.weight / n});
    }
  }
  // D(dx, dy) = sum_w weight cos(2 pi (fx dx + fy dy)) = Re sum_w (weight e^{2 pi i fx dx}) e^{2 pi i fy dy}
  Eigen::MatrixXcd x(nl, Eigen::Index(waves.size())), y(nl, Eigen::Index(waves.size()));
  for (int l = 0; l < nl; ++l)
    for (std::size_t w = 0; w < waves.size(); ++w) {
      const double d = l - reach;
      x(l, Eigen::Index(w)) = std::polar(waves[w][2], 2.0 * k_pi * waves[w][0] * d);
      y(l, Eigen::Index(w)) = std::polar(1.0, 2.0 * k_pi * waves[w][1] * d);
    }
  const Eigen::MatrixXd dsum = (x * y.transpose()).real();  // (dx, dy)
  const double var = m.stddev * m.stddev;
  return expected_welch_psd(t, [&](int dx, int dy) {
    if (std::abs(dx) > reach || std::abs(dy) > reach) return 0.0;
    const double env = std::exp(-k_pi * a2 * (double(dx) * dx + double(dy) * dy) / 2.0);
    return var * env * (dsum(dx + reach, dy + reach) + cross) / norm;
  });
}

int cs_rpn_spectrum_period(const CsRpnModel& m) {
  const double t = 1.0 / m.bin;
  const long r = std::lround(t);
  if (!(std::fabs(t - double(r)) < 1e-6 * t) || r < 4 || r > 4096)
    throw Error(ErrorKind::Usage, "cs-rpn spectrum check: 1 / bin = " + std::to_string(t) +
                                      " is not a whole number of pixels in [4, 4096]");
  return int(r);
}

namespace {

// The table of spectrum g on the T grid: p_b at (round(fx T), round(fy T)) mod T, one side only (the half
// plane the table is on). Sums to 1.
std::vector<Complex> table_on_grid(const CsRpnModel& m, std::size_t g, int t) {
  if (g >= m.spectra.size()) throw Error(ErrorKind::Internal, "cs-rpn spectrum index out of range");
  const std::vector<float>& bins = m.spectra[g].bins;
  double total = 0.0;
  for (std::size_t b = 2; b < bins.size(); b += 3) total += bins[b];
  std::vector<Complex> p(std::size_t(t) * t, Complex(0.0, 0.0));
  for (std::size_t b = 0; b + 2 < bins.size(); b += 3) {
    const long kx = std::lround(double(bins[b]) * t), ky = std::lround(double(bins[b + 1]) * t);
    p[std::size_t(((ky % t) + t) % t) * t + std::size_t(((kx % t) + t) % t)] += bins[b + 2] / total;
  }
  return p;
}

}  // namespace

std::vector<double> cs_rpn_spectrum_psd(const CsRpnModel& m, std::size_t g) {
  const int t = cs_rpn_spectrum_period(m);
  const std::vector<Complex> p = table_on_grid(m, g, t);
  const double e = m.spectra[g].energy;
  std::vector<double> out(p.size(), 0.0);
  for (int ky = 0; ky < t; ++ky)
    for (int kx = 0; kx < t; ++kx) {
      const double w = p[std::size_t(ky) * t + kx].real();
      if (w == 0.0) continue;
      out[std::size_t(ky) * t + kx] += 0.5 * e * w;
      out[std::size_t((t - ky) % t) * t + std::size_t((t - kx) % t)] += 0.5 * e * w;
    }
  out[0] = 0.0;
  return out;
}

std::vector<double> cs_rpn_expected_welch_psd(const CsRpnModel& m, std::size_t g) {
  validate_cs_rpn_model(m);
  const int t = cs_rpn_spectrum_period(m);
  // Phi(m) for lags m mod T (the table is on the k / T grid, so Phi is T-periodic): sum_b p_b e^{2 pi i k.m / T},
  // the conjugate of the forward transform of the real table
  std::vector<Complex> phi = table_on_grid(m, g, t);
  fft2d_forward(t, t, phi);
  const double e = m.spectra[g].energy;
  const double a2 = m.bandwidth * m.bandwidth;
  const bool jitter = m.variant != CsRpnVariant::Fourier;
  const double g0 = lrp_window_autocorrelation(0.0);
  return expected_welch_psd(t, [&](int dx, int dy) {
    const Complex ph = std::conj(phi[std::size_t((dy + t) % t) * t + std::size_t((dx + t) % t)]) *
                       (jitter ? sinc(m.bin * dx) * sinc(m.bin * dy) : 1.0);
    const double r2 = double(dx) * dx + double(dy) * dy;
    switch (m.variant) {
      case CsRpnVariant::RandomPhase:
        return e * lrp_window_autocorrelation(std::sqrt(r2) / m.spacing) / g0 * ph.real();
      case CsRpnVariant::Gabor:
        return e * std::exp(-k_pi * a2 * r2 / 2.0) * ph.real();
      case CsRpnVariant::Phasor: {
        const Complex rho = std::exp(-k_pi * a2 * r2 / 2.0) * ph;
        return e * k_pi / 4.0 * rho.real() * hyp2f1_half_half_two(std::min(1.0, std::norm(rho)));
      }
      case CsRpnVariant::Fourier:
        return e * ph.real();
    }
    return 0.0;
  });
}

PsdComparison gabor_check_against_exemplar(const GaborModel& model, const Image& exemplar) {
  Image grey;
  grey.width = exemplar.width;
  grey.height = exemplar.height;
  grey.channels = 1;
  grey.pixels.assign(std::size_t(exemplar.width) * exemplar.height, 0.0f);
  for (std::size_t i = 0; i < grey.pixels.size(); ++i) {
    double s = 0.0;
    for (int c = 0; c < exemplar.channels; ++c) s += exemplar.pixels[i * std::size_t(exemplar.channels) + std::size_t(c)];
    grey.pixels[i] = float(s / exemplar.channels);
  }
  const LrpSpectrum target = lrp_welch(grey);
  return compare_psd(gabor_expected_welch_psd(model, target.period), target.psd, target.period);
}

std::optional<PsdComparison> gabor_check_against_psd_image(const GaborModel& model, const Image& psd) {
  const int t = psd.width;
  if (psd.height != t || t < 16 || t > 1024 || (t & (t - 1)) != 0) return std::nullopt;
  const LrpSpectrum target = lrp_psd_from_image(psd, model.stddev * model.stddev);
  return compare_psd(gabor_expected_welch_psd(model, t), target.psd, t);
}

std::vector<PsdComparison> cs_rpn_check_spectra(const CsRpnModel& model) {
  std::vector<PsdComparison> out;
  const int t = cs_rpn_spectrum_period(model);
  for (std::size_t g = 0; g < model.spectra.size(); ++g) {
    if (!(model.spectra[g].energy > 0.0)) {
      out.emplace_back();
      continue;
    }
    out.push_back(compare_psd(cs_rpn_expected_welch_psd(model, g), cs_rpn_spectrum_psd(model, g), t));
  }
  return out;
}

}  // namespace stex
