// S2 Algorithm 2 (SOT) on a support mask, with the RME history, the tolerance stop and the Fig. 2 statistics.
// Conventions in sot.h; the projection is the real-arithmetic form of analysis/texton.cpp's loop with b^ = 1.
#include "analysis/sot.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <thread>

#include "analysis/texton.h"
#include "core/error.h"

namespace stex {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

void check_exemplar(const Image& u) {
  if (u.width <= 0 || u.height <= 0 || u.channels < 1 || u.channels > 4 ||
      u.pixels.size() != std::size_t(u.width) * u.height * u.channels)
    throw Error(ErrorKind::Input, "exemplar image is empty or malformed");
}

}  // namespace

SotSolver::SotSolver(const Image& exemplar, const SupportMask& mask) : mask_(mask) {
  check_exemplar(exemplar);
  if (mask.size < 1 || mask.in.size() != std::size_t(mask.size) * mask.size)
    throw Error(ErrorKind::Usage, "SOT: malformed support mask");
  if (exemplar.width < mask.size || exemplar.height < mask.size)
    throw Error(ErrorKind::Input, "exemplar is " + std::to_string(exemplar.width) + "x" +
                                      std::to_string(exemplar.height) + ", smaller than the support " +
                                      mask.description + " (" + std::to_string(mask.size) + "x" +
                                      std::to_string(mask.size) + ")");
  tu_ = normalised_kernel(exemplar, true);
  init();
}

SotSolver::SotSolver(NormalisedKernel tu, const SupportMask& mask) : tu_(std::move(tu)), mask_(mask) {
  if (tu_.width <= 0 || tu_.height <= 0 || tu_.channels < 1 || tu_.channels > 4 ||
      tu_.t.size() != std::size_t(tu_.width) * tu_.height * tu_.channels)
    throw Error(ErrorKind::Usage, "SOT: malformed kernel t_u");
  if (mask.size < 1 || mask.in.size() != std::size_t(mask.size) * mask.size)
    throw Error(ErrorKind::Usage, "SOT: malformed support mask");
  if (tu_.width < mask.size || tu_.height < mask.size)
    throw Error(ErrorKind::Input, "kernel t_u is smaller than the support " + mask.description);
  init();
}

void SotSolver::init() {
  const int w = tu_.width, h = tu_.height, ch = tu_.channels, wh = half_width(w);
  const std::size_t n = std::size_t(w) * h, nh = std::size_t(wh) * h;
  u_hat_ = stex::kernel_spectrum(tu_);
  u_half_.assign(nh * ch, Complex(0.0));
  den_ = 0.0;
  for (int c = 0; c < ch; ++c) {
    for (int ky = 0; ky < h; ++ky)
      for (int kx = 0; kx < wh; ++kx)
        u_half_[nh * c + std::size_t(ky) * wh + kx] = u_hat_[n * c + std::size_t(ky) * w + kx];
    for (std::size_t k = 1; k < n; ++k) den_ += std::norm(u_hat_[n * c + k]);
  }
}

double SotSolver::rme(const std::vector<double>& alpha) const {
  return texton_rme(tu_, u_hat_, alpha, mask_.size, 0);
}

SotRun SotSolver::run(std::uint64_t seed, int max_iterations, double tolerance,
                      const std::vector<double>* alpha0) const {
  if (max_iterations < 1)
    throw Error(ErrorKind::Usage, "SOT iterations must be at least 1, got " + std::to_string(max_iterations));
  if (!std::isfinite(tolerance) || tolerance < 0.0)
    throw Error(ErrorKind::Usage, "SOT tolerance must be finite and >= 0, got " + std::to_string(tolerance));
  const int w = tu_.width, h = tu_.height, ch = tu_.channels, s = mask_.size, wh = half_width(w);
  const std::size_t n = std::size_t(w) * h, nh = std::size_t(wh) * h;
  if (alpha0 && alpha0->size() != n * ch)
    throw Error(ErrorKind::Usage,
                "injected alpha0 has " + std::to_string(alpha0->size()) +
                    " values, expected channels x height x width = " + std::to_string(n * ch));

  SotRun out;
  SupportFft sfft(w, h, s, ch);
  {
    const std::vector<double> init = alpha0 ? *alpha0 : texton_initial_noise(w, h, ch, seed);
    for (int c = 0; c < ch; ++c) fft2d_r2c(w, h, init.data() + n * c, sfft.spectrum(c));
  }
  // The half spectrum holds every frequency once except kx = 0 and kx = W/2 (W even), which are their own
  // mirror: the others count twice in sums over all xi.
  const bool even = (w % 2) == 0;
  double prev = 0.0;
  for (int it = 0;; ++it) {
    // The spectrum is the DFT of t_it (it iterations done; t_0 = alpha_0).
    if (it > 0) {
      for (int c = 0; c < ch; ++c) sfft.forward(c);
    }
    double num = 0.0;
    for (int ky = 0; ky < h; ++ky) {
      for (int kx = 0; kx < wh; ++kx) {
        const std::size_t k = std::size_t(ky) * wh + kx;
        double zr = 0.0, zi = 0.0, aa = 0.0, uu = 0.0;
        for (int c = 0; c < ch; ++c) {
          const Complex u = u_half_[nh * c + k], a = sfft.spectrum(c)[k];
          zr += u.real() * a.real() + u.imag() * a.imag();
          zi += u.real() * a.imag() - u.imag() * a.real();
          aa += a.real() * a.real() + a.imag() * a.imag();
          uu += u.real() * u.real() + u.imag() * u.imag();
        }
        const double mag = std::sqrt(zr * zr + zi * zi);
        if (k != 0) {
          const double weight = (kx == 0 || (even && 2 * kx == w)) ? 1.0 : 2.0;
          num += weight * (uu + aa - 2.0 * mag);
        }
        // p_{t_u} (eq. 2): t_u^ z/|z|, z = t_u^* t^; z/|z| := 1 where z = 0.
        double pr = 1.0, pi = 0.0;
        if (mag > 0.0) {
          pr = zr / mag;
          pi = zi / mag;
        }
        for (int c = 0; c < ch; ++c) {
          const Complex u = u_half_[nh * c + k];
          sfft.spectrum(c)[k] = Complex(pr * u.real() - pi * u.imag(), pr * u.imag() + pi * u.real());
        }
      }
    }
    if (it > 0) {
      const double rme = den_ > 0.0 ? std::sqrt(std::max(0.0, num) / den_) : 0.0;
      out.rme_history.push_back(rme);
      out.iterations = it;
      if (tolerance > 0.0 && it >= 2 && std::fabs(rme - prev) < tolerance) {
        out.converged = true;
        break;
      }
      prev = rme;
      if (it == max_iterations) break;
    }
    // t <- q_S(IDFT(p_{t_u}(t)^)): real(c) holds rows [0, s); S is inside [0, s)^2.
    for (int c = 0; c < ch; ++c) {
      sfft.inverse(c);
      double* re = sfft.real(c);
      for (int y = 0; y < s; ++y) {
        double* row = re + std::size_t(y) * w;
        for (int x = 0; x < s; ++x)
          if (!mask_.contains(x, y)) row[x] = 0.0;
        std::fill(row + s, row + w, 0.0);
      }
    }
  }
  // real(c) still holds t_iterations (the forward transforms do not modify their input).
  out.alpha.assign(std::size_t(ch) * s * s, 0.0);
  for (int c = 0; c < ch; ++c)
    for (int y = 0; y < s; ++y)
      for (int x = 0; x < s; ++x)
        out.alpha[(std::size_t(c) * s + y) * s + x] = sfft.real(c)[std::size_t(y) * w + x];
  return out;
}

TextonModel analyse_sot(const Image& exemplar, const SotParams& params, SotReport* report) {
  const auto t_start = Clock::now();
  SotReport local;
  SotReport& rep = report ? *report : local;
  rep = SotReport{};
  const SotSolver solver(exemplar, params.mask);
  SotRun run = solver.run(params.seed, params.max_iterations, params.tolerance, params.alpha0);
  const int ch = solver.channels(), s = params.mask.size;
  rep.iterations = run.iterations;
  rep.converged = run.converged;
  rep.rme_history = run.rme_history;
  rep.rme = run.rme_history.back();
  rep.support_pixels = params.mask.count();

  const std::vector<double> a_cov = model_colour_covariance(run.alpha, ch, s, 0);
  const std::vector<double> b_cov = exemplar_colour_covariance(solver.kernel());
  double tr_a = 0.0, tr_b = 0.0;
  for (int c = 0; c < ch; ++c) {
    tr_a += a_cov[std::size_t(c) * ch + c];
    tr_b += b_cov[std::size_t(c) * ch + c];
  }
  rep.variance_kept = tr_b > 0.0 ? tr_a / tr_b : 1.0;
  if (tr_b <= 0.0)
    rep.warnings.push_back("the exemplar is constant: the texton is zero and renders are the mean colour");
  rep.colour_matrix.assign(std::size_t(ch) * ch, 0.0);
  for (int c = 0; c < ch; ++c) rep.colour_matrix[std::size_t(c) * ch + c] = 1.0;
  rep.rme_corrected = rep.rme;
  if (params.colour_correction && tr_b > 0.0) {
    int dropped = 0;
    rep.colour_matrix = apply_colour_correction(run.alpha, ch, s, a_cov, b_cov, &dropped);
    if (dropped > 0)
      rep.warnings.push_back("the texton's colour covariance is singular in " + std::to_string(dropped) +
                             " direction(s): the colour correction cannot restore the variance there");
    rep.rme_corrected = solver.rme(run.alpha);
  }

  TextonModel model;
  model.channels = ch;
  model.support = s;
  model.order = 0;
  model.alpha.assign(run.alpha.begin(), run.alpha.end());
  for (int c = 0; c < ch; ++c) model.mean[c] = float(solver.kernel().mean[c]);
  model.linear = params.linear;
  model.exemplar_width = solver.width();
  model.exemplar_height = solver.height();
  model.iterations = run.iterations;
  model.analysis_seed = params.seed;
  model.rme = rep.rme;
  model.variance_kept = rep.variance_kept;
  model.stex_version = STEX_VERSION_STRING;
  rep.ms_total = ms_since(t_start);
  return model;
}

TextonModel analyse_sot_file(const std::string& path, const LoadOptions& opts, SotParams params,
                             SotReport* report, std::vector<std::string>* warnings) {
  Image img = load_exemplar(path, opts, warnings);
  const std::string hash = sha256_file_hex(path);
  params.linear = opts.linear;
  TextonModel model = analyse_sot(img, params, report);
  const auto slash = path.find_last_of('/');
  model.exemplar_name = slash == std::string::npos ? path : path.substr(slash + 1);
  model.exemplar_hash = hash;
  return model;
}

SotConvergence sot_convergence(const SotSolver& solver, int inits, int iterations, std::uint64_t first_seed,
                               int threads) {
  if (inits < 2) throw Error(ErrorKind::Usage, "the RME statistics need at least 2 initialisations");
  if (iterations < 1) throw Error(ErrorKind::Usage, "iterations must be at least 1");
  if (threads < 1) throw Error(ErrorKind::Usage, "threads must be at least 1");
  const auto t0 = Clock::now();
  std::vector<std::vector<double>> hist(static_cast<std::size_t>(inits));
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(threads));
  auto work = [&](int first, int step) {
    try {
      for (int i = first; i < inits; i += step)
        hist[std::size_t(i)] = solver.run(first_seed + std::uint64_t(i), iterations).rme_history;
    } catch (...) {
      errors[std::size_t(first)] = std::current_exception();
    }
  };
  if (threads == 1) {
    work(0, 1);
  } else {
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) pool.emplace_back(work, t, threads);
    for (auto& th : pool) th.join();
  }
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
  SotConvergence out;
  out.inits = inits;
  out.iterations = iterations;
  out.mean.assign(std::size_t(iterations), 0.0);
  out.stddev.assign(std::size_t(iterations), 0.0);
  for (int k = 0; k < iterations; ++k) {
    double sum = 0.0;
    for (int i = 0; i < inits; ++i) sum += hist[std::size_t(i)][std::size_t(k)];
    const double m = sum / inits;
    double q = 0.0;
    for (int i = 0; i < inits; ++i) {
      const double d = hist[std::size_t(i)][std::size_t(k)] - m;
      q += d * d;
    }
    out.mean[std::size_t(k)] = m;
    out.stddev[std::size_t(k)] = std::sqrt(q / (inits - 1));
  }
  for (int i = 0; i < inits; ++i) out.final_rme.push_back(hist[std::size_t(i)].back());
  out.ms_total = ms_since(t0);
  return out;
}

}  // namespace stex
