// Spectrum error against the ADSN model and excess kurtosis of renders. See quality.h.
#include "benchmarks/lib/quality.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "analysis/fft.h"
#include "analysis/periodic.h"
#include "core/error.h"

namespace stex::bench {
namespace {

// Adds |FFT(periodic component of one channel - its mean)|^2 / N to `half_power` ((w/2 + 1) x h).
void add_periodogram(int w, int h, std::vector<double>& channel, std::vector<double>& half_power) {
  std::vector<double> p = periodic_component(w, h, channel);
  double mean = 0;
  for (double v : p) mean += v;
  mean /= double(p.size());
  for (double& v : p) v -= mean;
  std::vector<Complex> hat(std::size_t(half_width(w)) * std::size_t(h));
  fft2d_r2c(w, h, p.data(), hat.data());
  const double inv_n = 1.0 / (double(w) * double(h));
  for (std::size_t k = 0; k < hat.size(); ++k) half_power[k] += std::norm(hat[k]) * inv_n;
}

}  // namespace

SpectrumReference::SpectrumReference(const Image& exemplar)
    : bw_(exemplar.width), bh_(exemplar.height), channels_(exemplar.channels) {
  if (bw_ < 4 || bh_ < 4) throw Error(ErrorKind::Input, "spectrum reference: the exemplar is smaller than 4x4");
  const int hw = half_width(bw_);
  const int m = std::min(bw_, bh_);
  rings_ = m / 2;
  ring_.assign(std::size_t(hw) * std::size_t(bh_), -1);
  weight_.assign(ring_.size(), 0.0);
  ring_weight_.assign(std::size_t(rings_) + 1, 0.0);
  for (int ky = 0; ky < bh_; ++ky) {
    const double fy = double(ky <= bh_ / 2 ? ky : ky - bh_) / double(bh_);
    for (int kx = 0; kx < hw; ++kx) {
      const double fx = double(kx) / double(bw_);
      const int rho = int(std::lround(double(m) * std::sqrt(fx * fx + fy * fy)));
      if (rho < 1 || rho > rings_) continue;
      const bool self_conjugate = kx == 0 || (bw_ % 2 == 0 && kx == bw_ / 2);
      const std::size_t at = std::size_t(ky) * std::size_t(hw) + std::size_t(kx);
      ring_[at] = rho;
      weight_[at] = self_conjugate ? 1.0 : 2.0;
      ring_weight_[std::size_t(rho)] += weight_[at];
    }
  }
  std::vector<double> power(ring_.size(), 0.0), channel(std::size_t(bw_) * std::size_t(bh_));
  for (int c = 0; c < channels_; ++c) {
    for (std::size_t i = 0; i < channel.size(); ++i) channel[i] = exemplar.pixels[i * channels_ + std::size_t(c)];
    add_periodogram(bw_, bh_, channel, power);
  }
  ref_rings_ = rings_of(power);
}

std::vector<double> SpectrumReference::rings_of(const std::vector<double>& half_power) const {
  std::vector<double> out(std::size_t(rings_) + 1, 0.0);
  for (std::size_t k = 0; k < half_power.size(); ++k)
    if (ring_[k] > 0) out[std::size_t(ring_[k])] += weight_[k] * half_power[k];
  for (int r = 1; r <= rings_; ++r)
    if (ring_weight_[std::size_t(r)] > 0) out[std::size_t(r)] /= ring_weight_[std::size_t(r)];
  return out;
}

std::vector<double> SpectrumReference::render_rings(const float* pixels, int width, int height, int channels) const {
  if (channels != channels_)
    throw Error(ErrorKind::Usage, "spectrum error: the render has " + std::to_string(channels) +
                                      " channels, the exemplar " + std::to_string(channels_));
  const int step_x = std::max(1, bw_ / 2), step_y = std::max(1, bh_ / 2);
  const int nbx = width < bw_ ? 0 : (width - bw_) / step_x + 1, nby = height < bh_ ? 0 : (height - bh_) / step_y + 1;
  if (nbx < 1 || nby < 1)
    throw Error(ErrorKind::Usage, "spectrum error: the render (" + std::to_string(width) + "x" + std::to_string(height) +
                                      ") is smaller than one exemplar-sized block (" + std::to_string(bw_) + "x" +
                                      std::to_string(bh_) + ")");
  std::vector<double> power(ring_.size(), 0.0), channel(std::size_t(bw_) * std::size_t(bh_));
  for (int by = 0; by < nby; ++by)
    for (int bx = 0; bx < nbx; ++bx)
      for (int c = 0; c < channels; ++c) {
        for (int j = 0; j < bh_; ++j)
          for (int i = 0; i < bw_; ++i)
            channel[std::size_t(j) * std::size_t(bw_) + std::size_t(i)] =
                pixels[((std::size_t(by) * step_y + std::size_t(j)) * std::size_t(width) + std::size_t(bx) * step_x +
                        std::size_t(i)) * std::size_t(channels) + std::size_t(c)];
        add_periodogram(bw_, bh_, channel, power);
      }
  for (double& p : power) p /= double(nbx) * double(nby);
  return rings_of(power);
}

double SpectrumReference::error(const float* pixels, int width, int height, int channels) const {
  const std::vector<double> got = render_rings(pixels, width, height, channels);
  std::vector<double> rel;
  for (int r = 1; r <= rings_; ++r) {
    const double want = ref_rings_[std::size_t(r)];
    if (want > 0) rel.push_back(std::fabs(got[std::size_t(r)] - want) / want);
  }
  if (rel.empty()) return 0.0;  // a constant exemplar: nothing to compare
  const std::size_t mid = rel.size() / 2;
  std::nth_element(rel.begin(), rel.begin() + std::ptrdiff_t(mid), rel.end());
  if (rel.size() % 2 == 1) return rel[mid];
  const double upper = rel[mid];
  return 0.5 * (upper + *std::max_element(rel.begin(), rel.begin() + std::ptrdiff_t(mid)));
}

double excess_kurtosis(const float* pixels, std::size_t pixel_count, int channels) {
  if (pixel_count == 0 || channels < 1) return 0.0;
  double total = 0;
  for (int c = 0; c < channels; ++c) {
    double mean = 0;
    for (std::size_t i = 0; i < pixel_count; ++i) mean += pixels[i * std::size_t(channels) + std::size_t(c)];
    mean /= double(pixel_count);
    double m2 = 0, m4 = 0;
    for (std::size_t i = 0; i < pixel_count; ++i) {
      const double d = pixels[i * std::size_t(channels) + std::size_t(c)] - mean;
      const double d2 = d * d;
      m2 += d2;
      m4 += d2 * d2;
    }
    m2 /= double(pixel_count);
    m4 /= double(pixel_count);
    total += m2 > 0 ? m4 / (m2 * m2) - 3.0 : 0.0;
  }
  return total / double(channels);
}

}  // namespace stex::bench
