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

namespace {

// Throws for bad parameters or a malformed kernel, in the order analyse_texton_kernel documents.
void validate_texton_kernel_inputs(const NormalisedKernel& tu, const TextonParams& params) {
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
}

// The spectral constraint of Algorithm 1 on the full grid: t_u^ and 1/sqrt(b^).
struct SpectralConstraint {
  std::vector<Complex> u_hat;
  std::vector<double> inv_sqrt_b;
};

// Computes t_u^ and 1/sqrt(b^) (b^ the B-spline spectrum of the interpolation order).
SpectralConstraint spectral_constraint(const NormalisedKernel& tu, int order) {
  const std::size_t n = std::size_t(tu.width) * tu.height;
  SpectralConstraint sc;
  sc.u_hat = kernel_spectrum(tu);
  const std::vector<double> b_hat = bspline_hat(tu.width, tu.height, order);
  sc.inv_sqrt_b.resize(n);
  for (std::size_t k = 0; k < n; ++k) sc.inv_sqrt_b[k] = 1.0 / std::sqrt(b_hat[k]);
  return sc;
}

// The spectral constraint restricted to the half spectrum (kx <= W/2) of the real transforms.
struct HalfConstraint {
  std::size_t nh = 0;           // half-grid size per channel
  std::vector<Complex> u_half;  // planar channels x half grid
  std::vector<double> proj;     // 1/sqrt(b^) on the half grid
};

// Copies the half spectrum out of the full-grid constraint.
HalfConstraint half_constraint(const SpectralConstraint& sc, int w, int h, int ch) {
  // Real transforms: alpha is real, so the half spectrum (kx <= W/2) carries everything and the
  // projection, a pointwise map that preserves Hermitian symmetry, is applied on it alone.
  const std::size_t n = std::size_t(w) * h;
  const int wh = half_width(w);
  HalfConstraint hc;
  hc.nh = std::size_t(wh) * h;
  hc.u_half.resize(hc.nh * ch);
  hc.proj.resize(hc.nh);
  for (int ky = 0; ky < h; ++ky) {
    for (int kx = 0; kx < wh; ++kx) {
      const std::size_t full = std::size_t(ky) * w + kx, half = std::size_t(ky) * wh + kx;
      for (int c = 0; c < ch; ++c) hc.u_half[hc.nh * c + half] = sc.u_hat[n * c + full];
      hc.proj[half] = sc.inv_sqrt_b[full];
    }
  }
  return hc;
}

// The spectral projection of one iteration, in place on the half spectra of sfft.
void project_joint_phase(const HalfConstraint& hc, SupportFft& sfft, int ch) {
  const std::size_t nh = hc.nh;
  // Joint phase z/|z| with z = u^* alpha^ (S1 §4.3); for one channel the phase of alpha^ relative to u^.
  // Written in real arithmetic: std::complex's abs (hypot) and division dominated the profile.
  for (std::size_t k = 0; k < nh; ++k) {
    double zr = 0.0, zi = 0.0;
    for (int c = 0; c < ch; ++c) {
      const Complex u = hc.u_half[nh * c + k], a = sfft.spectrum(c)[k];
      zr += u.real() * a.real() + u.imag() * a.imag();
      zi += u.real() * a.imag() - u.imag() * a.real();
    }
    const double mag = std::sqrt(zr * zr + zi * zi);  // |z| is far from over/underflow here
    double pr = hc.proj[k], pi = 0.0;                 // z/|z| := 1 where z = 0
    if (mag > 0.0) {
      pr = zr / mag * hc.proj[k];
      pi = zi / mag * hc.proj[k];
    }
    for (int c = 0; c < ch; ++c) {
      const Complex u = hc.u_half[nh * c + k];
      sfft.spectrum(c)[k] = Complex(pr * u.real() - pi * u.imag(), pr * u.imag() + pi * u.real());
    }
  }
}

// Algorithm 1's alternating projections; returns alpha, planar channels x support^2.
std::vector<double> texton_iterations(const NormalisedKernel& tu, const TextonParams& params,
                                      const SpectralConstraint& sc) {
  const int w = tu.width, h = tu.height, ch = tu.channels, s = params.support;
  const std::size_t n = std::size_t(w) * h;
  std::vector<double> init = params.alpha0 ? *params.alpha0 : texton_initial_noise(w, h, ch, params.seed);
  const HalfConstraint hc = half_constraint(sc, w, h, ch);
  // The first transform sees alpha_0 on all of Omega; afterwards alpha lives on the rows [0,s) (columns
  // >= s zeroed) and the support transforms skip the rest.
  SupportFft sfft(w, h, s, ch);
  for (int c = 0; c < ch; ++c) fft2d_r2c(w, h, init.data() + n * c, sfft.spectrum(c));
  init = {};
  for (int it = 0; it < params.iterations; ++it) {
    if (it > 0) {
      for (int c = 0; c < ch; ++c) sfft.forward(c);
    }
    project_joint_phase(hc, sfft, ch);
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
  return alpha;
}

// The colour covariances A (texton) and B (exemplar) the correction maps between.
struct ColourCovariances {
  std::vector<double> a_cov, b_cov;
  double tr_b = 0.0;  // trace B: 0 for a constant exemplar
};

// Fills the report's pre-correction fields (rme, variance_kept, the constant-exemplar warning).
ColourCovariances report_before_correction(const NormalisedKernel& tu, const SpectralConstraint& sc,
                                           const std::vector<double>& alpha, const TextonParams& params,
                                           TextonReport& rep) {
  const int ch = tu.channels, s = params.support;
  rep.rme = texton_rme(tu, sc.u_hat, alpha, s, params.order);
  ColourCovariances cov;
  cov.a_cov = model_colour_covariance(alpha, ch, s, params.order);
  cov.b_cov = exemplar_colour_covariance(tu);
  double tr_a = 0.0, tr_b = 0.0;
  for (int c = 0; c < ch; ++c) {
    tr_a += cov.a_cov[std::size_t(c) * ch + c];
    tr_b += cov.b_cov[std::size_t(c) * ch + c];
  }
  cov.tr_b = tr_b;
  if (tr_b > 0.0) {
    rep.variance_kept = tr_a / tr_b;
  } else {
    rep.variance_kept = 1.0;
    rep.warnings.push_back("the exemplar is constant: the texton is zero and renders are the mean colour");
  }
  return cov;
}

// Applies the colour correction (if enabled and the exemplar is not constant) and records its matrix.
void correct_colour(std::vector<double>& alpha, int ch, const TextonParams& params,
                    const ColourCovariances& cov, TextonReport& rep) {
  const int s = params.support;
  std::vector<double> cmat(std::size_t(ch) * ch, 0.0);
  for (int c = 0; c < ch; ++c) cmat[std::size_t(c) * ch + c] = 1.0;
  if (params.colour_correction && cov.tr_b > 0.0) {
    int dropped = 0;
    cmat = apply_colour_correction(alpha, ch, s, cov.a_cov, cov.b_cov, &dropped);
    if (dropped > 0) {
      rep.warnings.push_back("the texton's colour covariance is singular in " + std::to_string(dropped) +
                             " direction(s): the colour correction cannot restore the variance there");
    }
  }
  rep.colour_matrix = cmat;
}

// Assembles the model's analysis fields from the final alpha and the report.
TextonModel make_texton_model(const NormalisedKernel& tu, const TextonParams& params,
                              const std::vector<double>& alpha, const TextonReport& rep) {
  TextonModel model;
  model.channels = tu.channels;
  model.support = params.support;
  model.order = params.order;
  model.alpha.assign(alpha.begin(), alpha.end());
  for (int c = 0; c < tu.channels; ++c) model.mean[c] = float(tu.mean[c]);
  model.linear = params.linear;
  model.exemplar_width = tu.width;
  model.exemplar_height = tu.height;
  model.iterations = params.iterations;
  model.analysis_seed = params.seed;
  model.rme = rep.rme;
  model.variance_kept = rep.variance_kept;
  model.stex_version = STEX_VERSION_STRING;
  return model;
}

}  // namespace

TextonModel analyse_texton_kernel(const NormalisedKernel& tu, const TextonParams& params, TextonReport* report) {
  const auto t_start = Clock::now();
  TextonReport local;
  TextonReport& rep = report ? *report : local;
  rep = TextonReport{};
  validate_texton_kernel_inputs(tu, params);

  // Spectral constraint: t_u^ and b^.
  auto t0 = Clock::now();
  const SpectralConstraint sc = spectral_constraint(tu, params.order);
  rep.ms_periodic = ms_since(t0);

  // Algorithm 1.
  t0 = Clock::now();
  std::vector<double> alpha = texton_iterations(tu, params, sc);
  rep.ms_iterations = ms_since(t0);

  // Report before correction.
  t0 = Clock::now();
  const ColourCovariances cov = report_before_correction(tu, sc, alpha, params, rep);
  rep.ms_report = ms_since(t0);

  // Colour covariance correction C = sqrtm(B) sqrtm(A)^-1 (S1 §4.3).
  t0 = Clock::now();
  correct_colour(alpha, tu.channels, params, cov, rep);
  rep.ms_correction = ms_since(t0);
  t0 = Clock::now();
  rep.rme_corrected =
      params.colour_correction ? texton_rme(tu, sc.u_hat, alpha, params.support, params.order) : rep.rme;
  rep.ms_report += ms_since(t0);

  TextonModel model = make_texton_model(tu, params, alpha, rep);
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
