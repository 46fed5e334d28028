// Luminance texton (Desolneux-Moisan-Ronsin) and cropped random-phase texton: the baselines of S2 §4 /
// Fig. 4. See luminance_texton.h.
#include "analysis/luminance_texton.h"

#include <cmath>

#include "analysis/texton.h"
#include "core/error.h"

namespace stex {
namespace {

void check_kernel(const NormalisedKernel& tu, const std::vector<Complex>& tu_hat) {
  const std::size_t n = std::size_t(tu.width) * tu.height;
  if (tu.width <= 0 || tu.height <= 0 || tu.channels < 1 || tu.t.size() != n * tu.channels ||
      tu_hat.size() != tu.t.size())
    throw Error(ErrorKind::Usage, "luminance texton: t_u and its spectrum do not match");
}

// Real part of the inverse DFT of each planar channel.
std::vector<double> inverse_real(int w, int h, int ch, std::vector<Complex> spec) {
  const std::size_t n = std::size_t(w) * h;
  std::vector<double> out(n * ch);
  for (int c = 0; c < ch; ++c) {
    fft2d_inverse(w, h, spec.data() + n * c);
    for (std::size_t k = 0; k < n; ++k) out[n * c + k] = spec[n * c + k].real();
  }
  return out;
}

}  // namespace

std::vector<double> luminance_weights(int channels) {
  if (channels == 3) return {1.0 / 3.0, 1.0 / 2.0, 1.0 / 6.0};
  if (channels < 1) throw Error(ErrorKind::Usage, "luminance weights need at least one channel");
  return std::vector<double>(std::size_t(channels), 1.0 / channels);
}

std::vector<double> luminance_texton(const NormalisedKernel& tu, const std::vector<Complex>& tu_hat) {
  check_kernel(tu, tu_hat);
  const int w = tu.width, h = tu.height, ch = tu.channels;
  const std::size_t n = std::size_t(w) * h;
  const std::vector<double> wt = luminance_weights(ch);
  std::vector<Complex> spec(tu_hat);
  for (std::size_t k = 0; k < n; ++k) {
    Complex l = 0.0;
    for (int c = 0; c < ch; ++c) l += wt[std::size_t(c)] * tu_hat[n * c + k];
    const double mag = std::abs(l);
    if (mag == 0.0) continue;
    const Complex unphase = std::conj(l) / mag;  // e^{-i arg l^}
    for (int c = 0; c < ch; ++c) spec[n * c + k] *= unphase;
  }
  return inverse_real(w, h, ch, std::move(spec));
}

std::vector<double> crop_centred(const std::vector<double>& full, int width, int height, int channels,
                                 const SupportMask& mask) {
  const std::size_t n = std::size_t(width) * height;
  const int s = mask.size;
  if (width < s || height < s || full.size() != n * channels)
    throw Error(ErrorKind::Usage,
                "crop_centred: the kernel does not match its size or is smaller than the mask");
  std::vector<double> out(std::size_t(channels) * s * s, 0.0);
  for (int c = 0; c < channels; ++c)
    for (int y = 0; y < s; ++y)
      for (int x = 0; x < s; ++x) {
        if (!mask.contains(x, y)) continue;
        const int sy = ((y - mask.centre_y) % height + height) % height;
        const int sx = ((x - mask.centre_x) % width + width) % width;
        out[(std::size_t(c) * s + y) * s + x] = full[n * c + std::size_t(sy) * width + sx];
      }
  return out;
}

std::vector<double> cropped_luminance_texton(const NormalisedKernel& tu, const std::vector<Complex>& tu_hat,
                                             const SupportMask& mask) {
  return crop_centred(luminance_texton(tu, tu_hat), tu.width, tu.height, tu.channels, mask);
}

std::vector<double> random_phase_texton(const NormalisedKernel& tu, const std::vector<Complex>& tu_hat,
                                        std::uint64_t seed) {
  check_kernel(tu, tu_hat);
  const int w = tu.width, h = tu.height, ch = tu.channels;
  const std::size_t n = std::size_t(w) * h;
  // psi = arg(t_u^* alpha_0^) with alpha_0 the white noise of Algorithm 2's initialisation (sot.h).
  std::vector<double> noise = texton_initial_noise(w, h, ch, seed);
  std::vector<Complex> a_hat(noise.begin(), noise.end());
  for (int c = 0; c < ch; ++c) fft2d_forward(w, h, a_hat.data() + n * c);
  std::vector<Complex> spec(tu_hat);
  for (std::size_t k = 0; k < n; ++k) {
    Complex z = 0.0;
    for (int c = 0; c < ch; ++c) z += std::conj(tu_hat[n * c + k]) * a_hat[n * c + k];
    const double mag = std::abs(z);
    const Complex phase = mag > 0.0 ? z / mag : Complex(1.0);
    for (int c = 0; c < ch; ++c) spec[n * c + k] *= phase;
  }
  return inverse_real(w, h, ch, std::move(spec));
}

std::vector<double> cropped_random_phase_texton(const NormalisedKernel& tu,
                                                const std::vector<Complex>& tu_hat, const SupportMask& mask,
                                                std::uint64_t seed) {
  const std::vector<double> full = random_phase_texton(tu, tu_hat, seed);
  const int w = tu.width, s = mask.size;
  const std::size_t n = std::size_t(w) * tu.height;
  if (tu.width < s || tu.height < s)
    throw Error(ErrorKind::Usage, "random-phase texton smaller than the mask");
  std::vector<double> out(std::size_t(tu.channels) * s * s, 0.0);
  for (int c = 0; c < tu.channels; ++c)
    for (int y = 0; y < s; ++y)
      for (int x = 0; x < s; ++x)
        if (mask.contains(x, y)) out[(std::size_t(c) * s + y) * s + x] = full[n * c + std::size_t(y) * w + x];
  return out;
}

}  // namespace stex
