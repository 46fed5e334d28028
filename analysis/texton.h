// Texton analysis: S1 Algorithm 1 (texton interpolation coefficients alpha on an s x s support for the
// bilinear texton noise of S1 §4), the joint colour-phase projection of S1 §4.3, and the colour covariance
// correction of S1 §4.3 / S2 §4 ("Colour correction" below). Order 0 (b^ = 1) is S2's
// synthesis-oriented texton (SOT, S2 Algorithm 2).
//
// Conventions (documented here once, used by --help and docs/model-format.md):
//  - Omega is the exemplar grid (W x H); the support S is the square [0,s)^2 at the top-left corner of
//    Omega (any placement is equivalent up to a circular shift of the phases; the top-left keeps the crop a
//    plain copy). The exemplar must be at least s x s.
//  - Preprocess: u is replaced by its periodic component (Moisan), t_u = (p - mean)/sqrt(|Omega|) per
//  channel.
//  - Initialisation: alpha_0 is standard white Gaussian noise on Omega, one independent field per channel,
//    drawn from the project's counter RNG (kernels/shared/rng.h): value (x, y, channel c) from
//    stex_draw(stex_cell_key(x, y), seed, index = c, domain = kAnalysisDomain) by Box-Muller on 53-bit
//    uniforms (host only; deterministic for (exemplar, parameters, seed)). Tests may inject alpha_0.
//  - Each of the n iterations: alpha^ <- DFT(alpha); per frequency z = u^* alpha^ (u^ = t_u^ as a
//    C^channels vector), alpha^ <- (1/sqrt(b^)) (z/|z|) u^ with z/|z| := 1 where z = 0; alpha <- real part of
//    the inverse DFT; alpha <- 1_S alpha. For one channel this is exactly Algorithm 1's step 1.b
//    alpha^ <- |t_u^|/sqrt(b^) alpha^/|alpha^|. b^ is the DFT of the sampled psi * psi of the order
//    (analysis/gaussian_model.h): orders 3 and 5 (S1 §10) divide by the spectrum of beta^7 / beta^11, which
//    is small near Nyquist (min ~2.9e-3, ~7.9e-5): high frequencies of alpha are amplified (ringing, S1 Fig. 9).
//  - Colour correction (optional, on by default): A = model colour covariance of alpha (B-spline weighted
//    autocorrelation at lags |t| <= order, i.e. within the support of b), B = sum_x t_u t_u^T,
//    alpha <- sqrtm(B) sqrtm(A)^-1 alpha, so that the model covariance equals B. For one channel: a
//    variance rescale. Directions where A's eigenvalue is below 1e-12 of its largest are left at zero.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/gaussian_model.h"
#include "analysis/image_io.h"
#include "runtime/model.h"

namespace stex {

// Counter-RNG domain of the analysis' random initialisation ("Anls"); distinct from the render domains.
constexpr std::uint32_t kAnalysisDomain = 0x416e6c73u;

struct TextonParams {
  int support = 64;     // s
  int iterations = 50;  // n >= 1
  std::uint64_t seed = 0;
  int order = 1;                  // 1: bilinear texton (S1); 0: nearest, S2's SOT; 3, 5: B-splines (S1 §10)
  bool colour_correction = true;  // S1 §4.3 colour covariance correction
  bool linear = false;            // recorded in the model: the exemplar was decoded to linear light
  // Injected alpha_0 (tests): planar channels x H x W on Omega; replaces the random initialisation.
  const std::vector<double>* alpha0 = nullptr;
};

struct TextonReport {
  double rme = 0.0;                   // texton_rme before the colour correction (analysis/gaussian_model.h)
  double rme_corrected = 0.0;         // the same after the colour correction
  double variance_kept = 0.0;         // trace A / trace B before the correction (1 for a constant exemplar)
  std::vector<double> colour_matrix;  // the C x C correction sqrtm(B) sqrtm(A)^-1 (identity if disabled)
  double ms_periodic = 0.0, ms_iterations = 0.0, ms_correction = 0.0, ms_report = 0.0, ms_total = 0.0;
  std::vector<std::string> warnings;
};

// The white Gaussian initialisation described above (planar channels x height x width).
std::vector<double> texton_initial_noise(int width, int height, int channels, std::uint64_t seed);

// S1 Algorithm 1 (+ §4.3) on an exemplar. Errors: Usage for bad parameters (support < 1 or > 4096,
// iterations < 1, order not 0/1/3/5, wrong alpha0 size), Input when the exemplar is smaller than the support.
// Fills the model's analysis fields (not the exemplar name and hash: see analyse_texton_file).
TextonModel analyse_texton(const Image& exemplar, const TextonParams& params, TextonReport* report = nullptr);

// The same on a given normalised kernel t (the spectral constraint t^ of Algorithm 1 and the colour
// covariance B = sum_x t t^T of the correction): analyse_texton(u) is analyse_texton_kernel(normalised_kernel(u))
// bit for bit. Used for kernels that are not an exemplar's t_u, e.g. the OT barycentres tau_rho of S1 §7
// (analysis/mix.h). The model's mean is the kernel's `mean`; Omega is the kernel's grid.
TextonModel analyse_texton_kernel(const NormalisedKernel& t, const TextonParams& params,
                                  TextonReport* report = nullptr);

// The colour covariance correction described above, applied in place to planar alpha (channels x support^2):
// alpha <- sqrtm(b_cov) sqrtm(a_cov)^-1 alpha with a_cov = model_colour_covariance(alpha, ...) and b_cov the
// exemplar's (both C x C row-major). Returns the matrix (row-major); `dropped` (optional) receives the number
// of directions where a_cov is singular (left at zero). Used by analyse_texton and analysis/sot (S2 §4).
std::vector<double> apply_colour_correction(std::vector<double>& alpha, int channels, int support,
                                            const std::vector<double>& a_cov,
                                            const std::vector<double>& b_cov, int* dropped = nullptr);

// Loads `path` (load_exemplar with opts; params.linear is taken from opts.linear), analyses it, and
// records the exemplar's file name (without directories) and SHA-256 in the model.
TextonModel analyse_texton_file(const std::string& path, const LoadOptions& opts, TextonParams params,
                                TextonReport* report = nullptr, std::vector<std::string>* warnings = nullptr);

}  // namespace stex
