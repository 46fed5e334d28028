// OT distance (S2 eq. 1), projection (eq. 2) and RME (§3.2) between circular Gaussian models. See
// ot_distance.h.
#include "analysis/ot_distance.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "runtime/texton_params.h"

namespace stex {
namespace {

void check_pair(const GaussianSpectrum& a, const GaussianSpectrum& b) {
  for (const GaussianSpectrum* g : {&a, &b})
    if (g->width <= 0 || g->height <= 0 || g->channels < 1 || g->channels > 4 ||
        g->hat.size() != std::size_t(g->width) * g->height * g->channels)
      throw Error(ErrorKind::Usage, "malformed Gaussian model spectrum");
  if (a.width != b.width || a.height != b.height)
    throw Error(ErrorKind::Usage, "the two models live on different domains (" + std::to_string(a.width) +
                                      "x" + std::to_string(a.height) + " and " + std::to_string(b.width) +
                                      "x" + std::to_string(b.height) + ")");
  if (a.channels != b.channels)
    throw Error(ErrorKind::Usage, "the two models have different channel counts (" +
                                      std::to_string(a.channels) + " and " + std::to_string(b.channels) +
                                      ")");
}

}  // namespace

GaussianSpectrum gaussian_spectrum(const NormalisedKernel& kernel, int width, int height) {
  const int kw = kernel.width, kh = kernel.height, ch = kernel.channels;
  if (kw <= 0 || kh <= 0 || ch < 1 || ch > 4 || kernel.t.size() != std::size_t(kw) * kh * ch)
    throw Error(ErrorKind::Usage, "gaussian_spectrum: malformed kernel");
  if (width < kw || height < kh)
    throw Error(ErrorKind::Usage, "gaussian_spectrum: the domain " + std::to_string(width) + "x" +
                                      std::to_string(height) + " is smaller than the kernel " +
                                      std::to_string(kw) + "x" + std::to_string(kh));
  GaussianSpectrum g;
  g.width = width;
  g.height = height;
  g.channels = ch;
  g.mean = kernel.mean;
  const std::size_t n = std::size_t(width) * height, kn = std::size_t(kw) * kh;
  g.hat.assign(n * ch, Complex(0.0));
  for (int c = 0; c < ch; ++c) {
    for (int y = 0; y < kh; ++y)
      for (int x = 0; x < kw; ++x)
        g.hat[n * c + std::size_t(y) * width + x] = kernel.t[kn * c + std::size_t(y) * kw + x];
    fft2d_forward(width, height, g.hat.data() + n * c);
  }
  return g;
}

GaussianSpectrum gaussian_spectrum_of_image(const Image& u, int width, int height) {
  const NormalisedKernel tu = normalised_kernel(u, true);
  return gaussian_spectrum(tu, width > 0 ? width : u.width, height > 0 ? height : u.height);
}

GaussianSpectrum gaussian_spectrum_of_model(const TextonModel& model, int width, int height) {
  const int s = model.support, ch = model.channels;
  if (s < 1 || ch < 1 || ch > 4 || !valid_texton_order(model.order) ||
      model.alpha.size() != std::size_t(ch) * s * s)
    throw Error(ErrorKind::Usage, "gaussian_spectrum_of_model: malformed model");
  if (width < s || height < s)
    throw Error(ErrorKind::Usage, "gaussian_spectrum_of_model: the domain " + std::to_string(width) + "x" +
                                      std::to_string(height) + " is smaller than the texton support " +
                                      std::to_string(s));
  NormalisedKernel k;
  k.width = k.height = s;
  k.channels = ch;
  for (int c = 0; c < ch; ++c) k.mean[c] = model.mean[c];
  k.t.assign(model.alpha.begin(), model.alpha.end());
  GaussianSpectrum g = gaussian_spectrum(k, width, height);
  if (model.order != 0) {
    const std::vector<double> b_hat = bspline_hat(width, height, model.order);
    const std::size_t n = std::size_t(width) * height;
    for (int c = 0; c < ch; ++c)
      for (std::size_t i = 0; i < n; ++i) g.hat[n * c + i] *= std::sqrt(b_hat[i]);
  }
  return g;
}

double OtDistance::distance() const { return std::sqrt(std::max(0.0, d2)); }
double OtDistance::distance_with_mean() const { return std::sqrt(std::max(0.0, d2 + mean2)); }
double OtDistance::rme_1_vs_0() const {
  return variance0 > 0.0 ? std::sqrt(std::max(0.0, d2) / variance0) : 0.0;
}
double OtDistance::rme_0_vs_1() const {
  return variance1 > 0.0 ? std::sqrt(std::max(0.0, d2) / variance1) : 0.0;
}

OtDistance ot_distance(const GaussianSpectrum& a, const GaussianSpectrum& b, bool include_dc) {
  check_pair(a, b);
  const std::size_t n = std::size_t(a.width) * a.height;
  const int ch = a.channels;
  double num = 0.0, va = 0.0, vb = 0.0;
  for (std::size_t k = include_dc ? 0 : 1; k < n; ++k) {
    double aa = 0.0, bb = 0.0;
    Complex ab = 0.0;
    for (int c = 0; c < ch; ++c) {
      const Complex x = a.hat[n * c + k], y = b.hat[n * c + k];
      aa += std::norm(x);
      bb += std::norm(y);
      ab += std::conj(x) * y;
    }
    num += aa + bb - 2.0 * std::abs(ab);
    if (k != 0) {
      va += aa;
      vb += bb;
    }
  }
  OtDistance d;
  d.d2 = std::max(0.0, num) / double(n);
  d.variance0 = va / double(n);
  d.variance1 = vb / double(n);
  for (int c = 0; c < ch; ++c) d.mean2 += (a.mean[c] - b.mean[c]) * (a.mean[c] - b.mean[c]);
  return d;
}

double relative_model_error(const GaussianSpectrum& reference, const GaussianSpectrum& model) {
  return ot_distance(reference, model).rme_1_vs_0();
}

std::vector<Complex> ot_projection(const GaussianSpectrum& h0, const GaussianSpectrum& h1) {
  check_pair(h0, h1);
  const std::size_t n = std::size_t(h0.width) * h0.height;
  const int ch = h0.channels;
  std::vector<Complex> out(h0.hat.size());
  for (std::size_t k = 0; k < n; ++k) {
    Complex z = 0.0;
    for (int c = 0; c < ch; ++c) z += std::conj(h0.hat[n * c + k]) * h1.hat[n * c + k];
    const double mag = std::abs(z);
    const Complex phase = mag > 0.0 ? z / mag : Complex(1.0);
    for (int c = 0; c < ch; ++c) out[n * c + k] = h0.hat[n * c + k] * phase;
  }
  return out;
}

std::vector<double> spectrum_colour_covariance(const GaussianSpectrum& g) {
  const std::size_t n = std::size_t(g.width) * g.height;
  const int ch = g.channels;
  if (ch < 1 || g.hat.size() != n * ch) throw Error(ErrorKind::Usage, "malformed Gaussian model spectrum");
  std::vector<double> m(std::size_t(ch) * ch, 0.0);
  for (int i = 0; i < ch; ++i)
    for (int j = i; j < ch; ++j) {
      double acc = 0.0;
      for (std::size_t k = 0; k < n; ++k) acc += (g.hat[n * i + k] * std::conj(g.hat[n * j + k])).real();
      m[std::size_t(i) * ch + j] = m[std::size_t(j) * ch + i] = acc / double(n);
    }
  return m;
}

}  // namespace stex
