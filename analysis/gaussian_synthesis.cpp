// ADSN by FFT and DSN on Z^2 (S1 §3.1-3.2, S2 §2.1 Algorithm 1, §2.4). See gaussian_synthesis.h.
#include "analysis/gaussian_synthesis.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "analysis/fft.h"
#include "analysis/gaussian_model.h"
#include "kernels/shared/poisson.h"
#include "kernels/shared/rng.h"
#include "runtime/error.h"
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
  const NormalisedKernel tu = normalised_kernel(exemplar, true);
  const int dw = std::max(width, tu.width), dh = std::max(height, tu.height);
  const std::uint64_t domain = std::uint64_t(dw) * std::uint64_t(dh);
  if (domain > pixel_budget)
    throw Error(ErrorKind::Limit, "ADSN FFT domain " + std::to_string(dw) + "x" + std::to_string(dh) + " (" +
                                      std::to_string(domain) + " pixels) exceeds the pixel budget of " +
                                      std::to_string(pixel_budget));
  const std::size_t n = std::size_t(domain);
  const int hw = half_width(dw);
  const std::size_t nh = std::size_t(hw) * std::size_t(dh);

  // White noise keyed by absolute output coordinates: domain pixel (i, j) is output pixel (x + i, y + j).
  std::vector<double> real(n);
  for (int j = 0; j < dh; ++j)
    for (int i = 0; i < dw; ++i) real[std::size_t(j) * dw + i] = gaussian_at(x + i, y + j, seed);
  std::vector<Complex> noise_hat(nh), t_hat(nh);
  fft2d_r2c(dw, dh, real.data(), noise_hat.data());

  Image out;
  out.width = width;
  out.height = height;
  out.channels = tu.channels;
  out.pixels.resize(std::size_t(width) * std::size_t(height) * std::size_t(tu.channels));
  const std::size_t plane = std::size_t(tu.width) * std::size_t(tu.height);
  for (int c = 0; c < tu.channels; ++c) {
    // t_u of channel c embedded zero-padded at the origin of the domain (S2 §2.4).
    std::fill(real.begin(), real.end(), 0.0);
    const double* t = tu.t.data() + plane * std::size_t(c);
    for (int j = 0; j < tu.height; ++j)
      for (int i = 0; i < tu.width; ++i) real[std::size_t(j) * dw + i] = t[std::size_t(j) * tu.width + i];
    fft2d_r2c(dw, dh, real.data(), t_hat.data());
    for (std::size_t k = 0; k < nh; ++k) t_hat[k] *= noise_hat[k];
    fft2d_c2r(dw, dh, t_hat.data(), real.data());
    for (int j = 0; j < height; ++j)
      for (int i = 0; i < width; ++i)
        out.pixels[(std::size_t(j) * width + i) * tu.channels + c] =
            float(tu.mean[c] + real[std::size_t(j) * dw + i]);
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
