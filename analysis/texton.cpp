// Texton analysis: S1 Algorithm 1 with the colour phase projection and colour covariance correction of
// S1 §4.3 (order 0: S2 Algorithm 2). The conventions are documented in texton.h.
#include "analysis/texton.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "analysis/fft.h"
#include "analysis/gaussian_model.h"
#include "core/error.h"
#include "kernels/shared/rng.h"
#include "runtime/texton_params.h"

namespace stex {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Uniform in (0, 1) from 53 bits of two 32-bit words: never 0, so log() below is finite.
double uniform_open(std::uint32_t hi, std::uint32_t lo) {
  std::uint64_t bits = (std::uint64_t(hi) << 21) | (std::uint64_t(lo) >> 11);  // 53 bits
  return (double(bits) + 0.5) * (1.0 / 9007199254740992.0);                    // 2^-53
}

// Symmetric PSD square root and (pseudo-)inverse square root through the eigen-decomposition.
struct SqrtPair {
  Eigen::MatrixXd root, inv_root;
  int dropped = 0;
};
SqrtPair sym_sqrt(const Eigen::MatrixXd& m) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(m);
  Eigen::VectorXd ev = es.eigenvalues();
  const double top = std::max(ev.maxCoeff(), 0.0);
  Eigen::VectorXd r(ev.size()), ir(ev.size());
  SqrtPair out;
  for (int k = 0; k < ev.size(); ++k) {
    double v = std::max(ev[k], 0.0);
    r[k] = std::sqrt(v);
    if (top > 0.0 && v > 1e-12 * top) {
      ir[k] = 1.0 / std::sqrt(v);
    } else {
      ir[k] = 0.0;
      ++out.dropped;
    }
  }
  out.root = es.eigenvectors() * r.asDiagonal() * es.eigenvectors().transpose();
  out.inv_root = es.eigenvectors() * ir.asDiagonal() * es.eigenvectors().transpose();
  return out;
}

}  // namespace

std::vector<double> texton_initial_noise(int width, int height, int channels, std::uint64_t seed) {
  const std::size_t n = std::size_t(width) * height;
  std::vector<double> out(n * channels);
  const stex_u32 seed_lo = stex_u32(seed & 0xffffffffu), seed_hi = stex_u32(seed >> 32);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const stex_uvec4 key = stex_cell_key(x, y);
      for (int c = 0; c < channels; ++c) {
        const stex_uvec4 d = stex_draw(key, seed_lo, seed_hi, stex_u32(c), kAnalysisDomain);
        // Box-Muller (cos branch): a standard normal from two independent uniforms.
        const double u1 = uniform_open(d.x, d.y), u2 = uniform_open(d.z, d.w);
        out[n * c + std::size_t(y) * width + x] = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
      }
    }
  }
  return out;
}

TextonModel analyse_texton(const Image& exemplar, const TextonParams& params, TextonReport* report) {
  const int w = exemplar.width, h = exemplar.height, ch = exemplar.channels;
  if (w <= 0 || h <= 0 || ch < 1 || ch > 4 || exemplar.pixels.size() != std::size_t(w) * h * ch) {
    throw Error(ErrorKind::Input, "exemplar image is empty or malformed");
  }
  const int s = params.support;
  if (s >= 1 && s <= 4096 && (w < s || h < s)) {
    throw Error(ErrorKind::Input, "exemplar is " + std::to_string(w) + "x" + std::to_string(h) +
                                      ", smaller than the texton support " + std::to_string(s) + "x" +
                                      std::to_string(s) + " (use a smaller --support or a larger exemplar)");
  }
  const auto t0 = Clock::now();
  const NormalisedKernel tu = normalised_kernel(exemplar, true);
  const double ms_periodic = ms_since(t0);
  TextonModel model = analyse_texton_kernel(tu, params, report);
  if (report) {
    report->ms_periodic += ms_periodic;
    report->ms_total += ms_periodic;
  }
  return model;
}

TextonModel analyse_texton_kernel(const NormalisedKernel& tu, const TextonParams& params, TextonReport* report) {
  const auto t_start = Clock::now();
  TextonReport local;
  TextonReport& rep = report ? *report : local;
  rep = TextonReport{};

  const int s = params.support;
  if (s < 1 || s > 4096) {
    throw Error(ErrorKind::Usage,
                "texton support must be between 1 and 4096 pixels, got " + std::to_string(s));
  }
  if (params.iterations < 1) {
    throw Error(ErrorKind::Usage,
                "texton iterations must be at least 1, got " + std::to_string(params.iterations));
  }
  if (!valid_texton_order(params.order)) {
    throw Error(ErrorKind::Usage,
                "interpolation order must be 0 (nearest, SOT), 1 (bilinear), 3 (cubic) or 5 (quintic B-spline), got " +
                    std::to_string(params.order));
  }
  const int w = tu.width, h = tu.height, ch = tu.channels;
  if (w <= 0 || h <= 0 || ch < 1 || ch > 4 || tu.t.size() != std::size_t(w) * h * ch) {
    throw Error(ErrorKind::Input, "exemplar kernel is empty or malformed");
  }
  if (w < s || h < s) {
    throw Error(ErrorKind::Input, "exemplar is " + std::to_string(w) + "x" + std::to_string(h) +
                                      ", smaller than the texton support " + std::to_string(s) + "x" +
                                      std::to_string(s) + " (use a smaller --support or a larger exemplar)");
  }
  const std::size_t n = std::size_t(w) * h;
  if (params.alpha0 && params.alpha0->size() != n * ch) {
    throw Error(ErrorKind::Usage,
                "injected alpha0 has " + std::to_string(params.alpha0->size()) +
                    " values, expected channels x height x width = " + std::to_string(n * ch));
  }

  // Spectral constraint: t_u^ and b^.
  auto t0 = Clock::now();
  const std::vector<Complex> u_hat = kernel_spectrum(tu);
  const std::vector<double> b_hat = bspline_hat(w, h, params.order);
  std::vector<double> inv_sqrt_b(n);
  for (std::size_t k = 0; k < n; ++k) inv_sqrt_b[k] = 1.0 / std::sqrt(b_hat[k]);
  rep.ms_periodic = ms_since(t0);

  // Algorithm 1.
  t0 = Clock::now();
  std::vector<double> init = params.alpha0 ? *params.alpha0 : texton_initial_noise(w, h, ch, params.seed);
  // Real transforms: alpha is real, so the half spectrum (kx <= W/2) carries everything and the
  // projection, a pointwise map that preserves Hermitian symmetry, is applied on it alone.
  const int wh = half_width(w);
  const std::size_t nh = std::size_t(wh) * h;
  std::vector<Complex> u_half(nh * ch);
  std::vector<double> proj(nh);  // 1/sqrt(b^) on the half grid
  for (int ky = 0; ky < h; ++ky) {
    for (int kx = 0; kx < wh; ++kx) {
      const std::size_t full = std::size_t(ky) * w + kx, half = std::size_t(ky) * wh + kx;
      for (int c = 0; c < ch; ++c) u_half[nh * c + half] = u_hat[n * c + full];
      proj[half] = inv_sqrt_b[full];
    }
  }
  // The first transform sees alpha_0 on all of Omega; afterwards alpha lives on the rows [0,s) (columns
  // >= s zeroed) and the support transforms skip the rest.
  SupportFft sfft(w, h, s, ch);
  for (int c = 0; c < ch; ++c) fft2d_r2c(w, h, init.data() + n * c, sfft.spectrum(c));
  init = {};
  for (int it = 0; it < params.iterations; ++it) {
    if (it > 0) {
      for (int c = 0; c < ch; ++c) sfft.forward(c);
    }
    // Joint phase z/|z| with z = u^* alpha^ (S1 §4.3); for one channel the phase of alpha^ relative to u^.
    // Written in real arithmetic: std::complex's abs (hypot) and division dominated the profile.
    for (std::size_t k = 0; k < nh; ++k) {
      double zr = 0.0, zi = 0.0;
      for (int c = 0; c < ch; ++c) {
        const Complex u = u_half[nh * c + k], a = sfft.spectrum(c)[k];
        zr += u.real() * a.real() + u.imag() * a.imag();
        zi += u.real() * a.imag() - u.imag() * a.real();
      }
      const double mag = std::sqrt(zr * zr + zi * zi);  // |z| is far from over/underflow here
      double pr = proj[k], pi = 0.0;                    // z/|z| := 1 where z = 0
      if (mag > 0.0) {
        pr = zr / mag * proj[k];
        pi = zi / mag * proj[k];
      }
      for (int c = 0; c < ch; ++c) {
        const Complex u = u_half[nh * c + k];
        sfft.spectrum(c)[k] = Complex(pr * u.real() - pi * u.imag(), pr * u.imag() + pi * u.real());
      }
    }
    for (int c = 0; c < ch; ++c) {
      sfft.inverse(c);
      // Support projection alpha <- 1_S alpha, S = [0,s)^2 (the rows >= s were never computed).
      double* re = sfft.real(c);
      for (int y = 0; y < s; ++y) std::fill(re + std::size_t(y) * w + s, re + std::size_t(y + 1) * w, 0.0);
    }
  }
  std::vector<double> alpha(std::size_t(ch) * s * s);
  for (int c = 0; c < ch; ++c) {
    for (int y = 0; y < s; ++y) {
      for (int x = 0; x < s; ++x)
        alpha[(std::size_t(c) * s + y) * s + x] = sfft.real(c)[std::size_t(y) * w + x];
    }
  }
  rep.ms_iterations = ms_since(t0);

  // Report before correction.
  t0 = Clock::now();
  rep.rme = texton_rme(tu, u_hat, alpha, s, params.order);
  const std::vector<double> a_cov = model_colour_covariance(alpha, ch, s, params.order);
  const std::vector<double> b_cov = exemplar_colour_covariance(tu);
  double tr_a = 0.0, tr_b = 0.0;
  for (int c = 0; c < ch; ++c) {
    tr_a += a_cov[std::size_t(c) * ch + c];
    tr_b += b_cov[std::size_t(c) * ch + c];
  }
  if (tr_b > 0.0) {
    rep.variance_kept = tr_a / tr_b;
  } else {
    rep.variance_kept = 1.0;
    rep.warnings.push_back("the exemplar is constant: the texton is zero and renders are the mean colour");
  }
  rep.ms_report = ms_since(t0);

  // Colour covariance correction C = sqrtm(B) sqrtm(A)^-1 (S1 §4.3).
  t0 = Clock::now();
  std::vector<double> cmat(std::size_t(ch) * ch, 0.0);
  for (int c = 0; c < ch; ++c) cmat[std::size_t(c) * ch + c] = 1.0;
  if (params.colour_correction && tr_b > 0.0) {
    int dropped = 0;
    cmat = apply_colour_correction(alpha, ch, s, a_cov, b_cov, &dropped);
    if (dropped > 0) {
      rep.warnings.push_back("the texton's colour covariance is singular in " + std::to_string(dropped) +
                             " direction(s): the colour correction cannot restore the variance there");
    }
  }
  rep.colour_matrix = cmat;
  rep.ms_correction = ms_since(t0);
  t0 = Clock::now();
  rep.rme_corrected = params.colour_correction ? texton_rme(tu, u_hat, alpha, s, params.order) : rep.rme;
  rep.ms_report += ms_since(t0);

  TextonModel model;
  model.channels = ch;
  model.support = s;
  model.order = params.order;
  model.alpha.assign(alpha.begin(), alpha.end());
  for (int c = 0; c < ch; ++c) model.mean[c] = float(tu.mean[c]);
  model.linear = params.linear;
  model.exemplar_width = w;
  model.exemplar_height = h;
  model.iterations = params.iterations;
  model.analysis_seed = params.seed;
  model.rme = rep.rme;
  model.variance_kept = rep.variance_kept;
  model.stex_version = STEX_VERSION_STRING;
  rep.ms_total = ms_since(t_start);
  return model;
}

std::vector<double> apply_colour_correction(std::vector<double>& alpha, int channels, int support,
                                            const std::vector<double>& a_cov,
                                            const std::vector<double>& b_cov, int* dropped) {
  const int ch = channels;
  const std::size_t ss = std::size_t(support) * support;
  if (ch < 1 || alpha.size() != ss * ch || a_cov.size() != std::size_t(ch) * ch ||
      b_cov.size() != a_cov.size())
    throw Error(ErrorKind::Usage, "apply_colour_correction: sizes do not match channels x support^2");
  Eigen::MatrixXd am(ch, ch), bm(ch, ch);
  for (int i = 0; i < ch; ++i) {
    for (int j = 0; j < ch; ++j) {
      am(i, j) = a_cov[std::size_t(i) * ch + j];
      bm(i, j) = b_cov[std::size_t(i) * ch + j];
    }
  }
  SqrtPair sa = sym_sqrt(am), sb = sym_sqrt(bm);
  if (dropped) *dropped = sa.dropped;
  const Eigen::MatrixXd cmat = sb.root * sa.inv_root;
  std::vector<double> mixed(alpha.size(), 0.0);
  for (int i = 0; i < ch; ++i) {
    for (int j = 0; j < ch; ++j) {
      const double cij = cmat(i, j);
      for (std::size_t k = 0; k < ss; ++k) mixed[ss * i + k] += cij * alpha[ss * j + k];
    }
  }
  alpha.swap(mixed);
  std::vector<double> out(std::size_t(ch) * ch);
  for (int i = 0; i < ch; ++i) {
    for (int j = 0; j < ch; ++j) out[std::size_t(i) * ch + j] = cmat(i, j);
  }
  return out;
}

TextonModel analyse_texton_file(const std::string& path, const LoadOptions& opts, TextonParams params,
                                TextonReport* report, std::vector<std::string>* warnings) {
  Image img = load_exemplar(path, opts, warnings);
  const std::string hash = sha256_file_hex(path);
  params.linear = opts.linear;
  TextonModel model = analyse_texton(img, params, report);
  auto slash = path.find_last_of('/');
  model.exemplar_name = slash == std::string::npos ? path : path.substr(slash + 1);
  model.exemplar_hash = hash;
  return model;
}

}  // namespace stex
