// ADSN on Z^2 and circular, RPN, DSN on Z^2 and circular (S1 §3.1-3.2, S2 §2.1-2.2, Algorithm 1, §2.4; GGM's
// random phase noise). See gaussian_synthesis.h.
#include "analysis/gaussian_synthesis.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "analysis/fft.h"
#include "analysis/gaussian_model.h"
#include "core/error.h"
#include "kernels/shared/poisson.h"
#include "kernels/shared/rng.h"
#include "runtime/poisson_table.h"
#include "runtime/texton_params.h"

namespace stex {

namespace {

void check_region(std::int64_t x, std::int64_t y, int width, int height) { validate_region(x, y, width, height); }

// Standard normal from one counter-RNG draw (Box-Muller on two 24-bit uniforms in (0, 1)).
double gaussian_at(std::int64_t px, std::int64_t py, std::uint64_t seed) {
  const stex_uvec4 v = stex_draw(stex_cell_key(px, py), stex_lo32(std::int64_t(seed)), stex_hi32(std::int64_t(seed)),
                                 0u, k_domain_adsn_noise);
  const double u1 = (double(v.x >> 8) + 0.5) * (1.0 / 16777216.0);
  const double u2 = double(v.y >> 8) * (1.0 / 16777216.0);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

}  // namespace

Image synthesize_adsn(const Image& exemplar, std::int64_t x, std::int64_t y, int width, int height,
                      std::uint64_t seed, std::uint64_t pixel_budget) {
  check_region(x, y, width, height);
  return synthesize_cadsn(normalised_kernel(exemplar, true), x, y, width, height, seed, pixel_budget);
}

namespace {

void check_kernel(const NormalisedKernel& k) {
  if (k.width <= 0 || k.height <= 0 || k.channels < 1 || k.channels > 4 ||
      k.t.size() != std::size_t(k.width) * std::size_t(k.height) * std::size_t(k.channels))
    throw Error(ErrorKind::Usage, "synthesis kernel is empty or malformed");
}

void check_budget(const char* what, int dw, int dh, std::uint64_t pixel_budget) {
  const std::uint64_t domain = std::uint64_t(dw) * std::uint64_t(dh);
  if (domain > pixel_budget)
    throw Error(ErrorKind::Limit, std::string(what) + " FFT domain " + std::to_string(dw) + "x" +
                                      std::to_string(dh) + " (" + std::to_string(domain) +
                                      " pixels) exceeds the pixel budget of " + std::to_string(pixel_budget));
}

// out(i, j) = mean + sum_q k(q) N(i + ox - q, j + oy - q) for the output pixels, with N the white noise of
// the dw x dh FFT domain whose pixel (i, j) is the absolute pixel (nx + i, ny + j) for i < nw, j < nh (zero
// beyond). Circular on the domain; (ox, oy) is the domain index of output pixel (0, 0). `phase_only`
// replaces N^ by sqrt(dw dh) N^/|N^| (RPN). t_u-style kernels are zero-padded at the domain origin.
Image circular_filter(const NormalisedKernel& k, std::int64_t nx, std::int64_t ny, int nw, int nh, int dw,
                      int dh, int ox, int oy, int width, int height, std::uint64_t seed, bool phase_only) {
  const std::size_t n = std::size_t(dw) * std::size_t(dh);
  const int hw = half_width(dw);
  const std::size_t nhalf = std::size_t(hw) * std::size_t(dh);
  std::vector<double> real(n, 0.0);
  for (int j = 0; j < nh; ++j)
    for (int i = 0; i < nw; ++i) real[std::size_t(j) * dw + i] = gaussian_at(nx + i, ny + j, seed);
  std::vector<Complex> noise_hat(nhalf), t_hat(nhalf);
  fft2d_r2c(dw, dh, real.data(), noise_hat.data());
  if (phase_only) {
    const double root = std::sqrt(double(n));
    for (Complex& v : noise_hat) {
      const double mag = std::abs(v);
      v = mag > 0.0 ? v * (root / mag) : Complex(root);
    }
  }
  Image out;
  out.width = width;
  out.height = height;
  out.channels = k.channels;
  out.pixels.resize(std::size_t(width) * std::size_t(height) * std::size_t(k.channels));
  const std::size_t plane = std::size_t(k.width) * std::size_t(k.height);
  for (int c = 0; c < k.channels; ++c) {
    // Kernel of channel c embedded zero-padded at the origin of the domain (S2 §2.4).
    std::fill(real.begin(), real.end(), 0.0);
    const double* t = k.t.data() + plane * std::size_t(c);
    for (int j = 0; j < k.height; ++j)
      for (int i = 0; i < k.width; ++i) real[std::size_t(j) * dw + i] = t[std::size_t(j) * k.width + i];
    fft2d_r2c(dw, dh, real.data(), t_hat.data());
    for (std::size_t q = 0; q < nhalf; ++q) t_hat[q] *= noise_hat[q];
    fft2d_c2r(dw, dh, t_hat.data(), real.data());
    for (int j = 0; j < height; ++j)
      for (int i = 0; i < width; ++i)
        out.pixels[(std::size_t(j) * width + i) * k.channels + c] =
            float(k.mean[c] + real[std::size_t(j + oy) * dw + (i + ox)]);
  }
  return out;
}

}  // namespace

double white_noise_at(std::int64_t px, std::int64_t py, std::uint64_t seed) {
  return gaussian_at(px, py, seed);
}

int fft_friendly_size(int n) {
  if (n < 1) return 1;
  for (std::int64_t m = n;; ++m) {
    std::int64_t r = m;
    for (int p : {2, 3, 5, 7})
      while (r % p == 0) r /= p;
    if (r == 1) return int(m);
  }
}

NormalisedKernel texton_kernel(const TextonModel& model) {
  validate_texton_model(model);
  const int s = model.support, ch = model.channels;
  NormalisedKernel k;
  k.channels = ch;
  for (int c = 0; c < ch; ++c) k.mean[c] = model.mean[c];
  if (model.order == 0) {
    k.width = k.height = s;
    k.t.assign(model.alpha.begin(), model.alpha.end());
    return k;
  }
  // alpha * (q x q), q the spectral factor of the sampled B-spline (q * q~ = beta^(2 order + 1) at the
  // integers; order 1: q = ((1 + 1/sqrt 3)/2, (1 - 1/sqrt 3)/2), q * q~ = (1/6, 2/3, 1/6)).
  const std::vector<double> q = bspline_spectral_factor(model.order);
  const int taps = int(q.size());
  const int r = s + taps - 1;
  k.width = k.height = r;
  k.t.assign(std::size_t(ch) * r * r, 0.0);
  for (int c = 0; c < ch; ++c)
    for (int y = 0; y < s; ++y)
      for (int x = 0; x < s; ++x) {
        const double a = model.alpha_at(c, y, x);
        for (int dy = 0; dy < taps; ++dy)
          for (int dx = 0; dx < taps; ++dx)
            k.t[(std::size_t(c) * r + y + dy) * r + x + dx] += a * q[std::size_t(dy)] * q[std::size_t(dx)];
      }
  return k;
}

Image synthesize_cadsn(const NormalisedKernel& kernel, std::int64_t x, std::int64_t y, int width, int height,
                       std::uint64_t seed, std::uint64_t pixel_budget) {
  check_region(x, y, width, height);
  check_kernel(kernel);
  const int dw = std::max(width, kernel.width), dh = std::max(height, kernel.height);
  check_budget("CADSN", dw, dh, pixel_budget);
  // White noise keyed by absolute output coordinates: domain pixel (i, j) is output pixel (x + i, y + j).
  return circular_filter(kernel, x, y, dw, dh, dw, dh, 0, 0, width, height, seed, false);
}

Image synthesize_rpn(const NormalisedKernel& kernel, std::int64_t x, std::int64_t y, int width, int height,
                     std::uint64_t seed, std::uint64_t pixel_budget) {
  check_region(x, y, width, height);
  check_kernel(kernel);
  const int dw = std::max(width, kernel.width), dh = std::max(height, kernel.height);
  check_budget("RPN", dw, dh, pixel_budget);
  return circular_filter(kernel, x, y, dw, dh, dw, dh, 0, 0, width, height, seed, true);
}

Image synthesize_adsn_z2(const NormalisedKernel& kernel, std::int64_t x, std::int64_t y, int width,
                         int height, std::uint64_t seed, std::uint64_t pixel_budget) {
  check_region(x, y, width, height);
  check_kernel(kernel);
  // Noise on [x - kw + 1, x + width) x [y - kh + 1, y + height); output pixel (i, j) needs the noise at
  // domain indices (i + kw - 1 - qx, j + kh - 1 - qy) for q in the kernel's support: inside [0, nw) x [0,
  // nh).
  const std::int64_t nw64 = std::int64_t(width) + kernel.width - 1,
                     nh64 = std::int64_t(height) + kernel.height - 1;
  if (nw64 > (std::int64_t(1) << 30) || nh64 > (std::int64_t(1) << 30))
    throw Error(ErrorKind::Limit, "ADSN region plus kernel margin is too large");
  const int nw = int(nw64), nh = int(nh64);
  const int dw = fft_friendly_size(nw), dh = fft_friendly_size(nh);
  check_budget("ADSN (region + kernel margin)", dw, dh, pixel_budget);
  return circular_filter(kernel, x - kernel.width + 1, y - kernel.height + 1, nw, nh, dw, dh,
                         kernel.width - 1, kernel.height - 1, width, height, seed, false);
}

Image synthesize_cdsn(const TextonModel& model, std::int64_t x, std::int64_t y, int width, int height,
                      double mni, std::uint64_t seed, std::uint64_t pixel_budget) {
  validate_texton_model(model);
  check_region(x, y, width, height);
  if (!std::isfinite(mni) || mni <= 0.0 || mni > k_max_mni)
    throw Error(ErrorKind::Usage, "--mni must be in (0, 10000], got " + std::to_string(mni));
  const int s = model.support, nc = model.channels;
  const int dw = std::max(width, s), dh = std::max(height, s);
  check_budget("CDSN", dw, dh, pixel_budget);
  const double lambda = mni / (double(s) * double(s));
  const std::vector<std::uint32_t> table = poisson_threshold_table(lambda);
  const std::uint32_t seed_lo = stex_lo32(std::int64_t(seed)), seed_hi = stex_hi32(std::int64_t(seed));
  const std::size_t n = std::size_t(dw) * std::size_t(dh);
  const int hw = half_width(dw);
  const std::size_t nhalf = std::size_t(hw) * std::size_t(dh);
  // Poisson counts P(q) on Theta, q = (x + i, y + j) in absolute coordinates.
  std::vector<double> real(n);
  for (int j = 0; j < dh; ++j)
    for (int i = 0; i < dw; ++i) {
      const stex_uvec4 v = stex_draw(stex_cell_key(x + i, y + j), seed_lo, seed_hi, 0u, k_domain_cdsn_count);
      real[std::size_t(j) * dw + i] =
          double(stex_poisson_count(table.data(), std::uint32_t(table.size()), v.x));
    }
  std::vector<Complex> count_hat(nhalf), a_hat(nhalf);
  fft2d_r2c(dw, dh, real.data(), count_hat.data());
  Image out;
  out.width = width;
  out.height = height;
  out.channels = nc;
  out.pixels.resize(std::size_t(width) * std::size_t(height) * std::size_t(nc));
  const double inv_sqrt_lambda = 1.0 / std::sqrt(lambda);
  for (int c = 0; c < nc; ++c) {
    std::fill(real.begin(), real.end(), 0.0);
    double sum = 0.0;
    for (int j = 0; j < s; ++j)
      for (int i = 0; i < s; ++i) {
        const double a = model.alpha_at(c, j, i);
        real[std::size_t(j) * dw + i] = a;
        sum += a;
      }
    fft2d_r2c(dw, dh, real.data(), a_hat.data());
    for (std::size_t q = 0; q < nhalf; ++q) a_hat[q] *= count_hat[q];
    fft2d_c2r(dw, dh, a_hat.data(), real.data());
    const double offset = lambda * sum;
    for (int j = 0; j < height; ++j)
      for (int i = 0; i < width; ++i)
        out.pixels[(std::size_t(j) * width + i) * nc + c] =
            float(double(model.mean[c]) + (real[std::size_t(j) * dw + i] - offset) * inv_sqrt_lambda);
  }
  return out;
}

Image synthesize_dsn(const TextonModel& model, std::int64_t x, std::int64_t y, int width, int height, double mni,
                     std::uint64_t seed) {
  validate_texton_model(model);
  check_region(x, y, width, height);
  if (!std::isfinite(mni) || mni <= 0.0 || mni > k_max_mni)
    throw Error(ErrorKind::Usage, "--mni must be in (0, 10000], got " + std::to_string(mni));
  const int s = model.support, nc = model.channels;
  const double lambda = mni / (double(s) * double(s));
  const std::vector<std::uint32_t> table = poisson_threshold_table(lambda);
  const std::uint32_t seed_lo = stex_lo32(std::int64_t(seed)), seed_hi = stex_hi32(std::int64_t(seed));

  std::vector<double> acc(std::size_t(width) * std::size_t(height) * std::size_t(nc), 0.0);
  // Impulses q in [x - s + 1, x + width) x [y - s + 1, y + height) reach the region (alpha on [0, s)^2).
  // Every pixel receives its terms in the order of q (row-major), whatever the region: tile-invariant.
  for (std::int64_t qy = y - s + 1; qy < y + height; ++qy)
    for (std::int64_t qx = x - s + 1; qx < x + width; ++qx) {
      const stex_uvec4 v = stex_draw(stex_cell_key(qx, qy), seed_lo, seed_hi, 0u, k_domain_dsn_count);
      const std::uint32_t count = stex_poisson_count(table.data(), std::uint32_t(table.size()), v.x);
      if (count == 0) continue;
      const int ky0 = int(std::max<std::int64_t>(0, y - qy)), ky1 = int(std::min<std::int64_t>(s, y + height - qy));
      const int kx0 = int(std::max<std::int64_t>(0, x - qx)), kx1 = int(std::min<std::int64_t>(s, x + width - qx));
      for (int ky = ky0; ky < ky1; ++ky)
        for (int kx = kx0; kx < kx1; ++kx) {
          const std::size_t p = std::size_t(qy + ky - y) * std::size_t(width) + std::size_t(qx + kx - x);
          for (int c = 0; c < nc; ++c) acc[p * nc + c] += double(count) * double(model.alpha_at(c, ky, kx));
        }
    }

  Image out;
  out.width = width;
  out.height = height;
  out.channels = nc;
  out.pixels.resize(acc.size());
  const double inv_sqrt_lambda = 1.0 / std::sqrt(lambda);
  for (int c = 0; c < nc; ++c) {
    double sum = 0.0;
    for (int i = 0; i < s * s; ++i) sum += double(model.alpha[std::size_t(c) * s * s + i]);
    const double offset = lambda * sum;
    for (std::size_t p = 0; p < std::size_t(width) * std::size_t(height); ++p)
      out.pixels[p * nc + c] = float(double(model.mean[c]) + (acc[p * nc + c] - offset) * inv_sqrt_lambda);
  }
  return out;
}

}  // namespace stex
