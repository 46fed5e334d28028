// Optimal-transport distances between circular Gaussian texture models (S2 §2.3): the L2 OT distance of eq.
// 1, the projection of eq. 2, and the relative model error (RME) of S2 §3.2.
//
// A circular Gaussian model on a W x H domain Theta with d channels is mean + CADSN^Theta(h) (S2 §2.2): the
// field m + h (.) W, W a standard white noise on Theta, with covariance h (.) h~; it is given here by the DFT
// h^ of the square root kernel h (GaussianSpectrum). Sources:
//  - an exemplar or any image u (a render): h = t_u of its periodic component (S2 eq. 3), m = its mean;
//  - a kernel (NormalisedKernel) zero-padded at the origin of a larger Theta (S2 §2.4's embedding);
//  - a texton model (runtime/model.h): h^ = sqrt(b^) alpha^ (alpha at [0, s)^2, b^ the DFT of the sampled
//    B-spline of its order; b^ = 1 for order 0), the spectral square root of the texton noise covariance
//    (S1 Prop. 1, as texton_rme in analysis/gaussian_model.h), m = the model's mean.
//
// Distance (eq. 1, per pixel: the 1/|Theta| makes it the L2 distance between kernels, see ot_projection):
//   d_OT^2 = 1/|Theta| sum_{xi != 0} ( |h0^|^2 + |h1^|^2 - 2 |h0^* h1^| )(xi)
// with |.| the C^d norm and h0^* h1^ the Hermitian product over channels. It is the squared Wasserstein-2
// distance between the two centred Gaussian fields on Theta with the constant (xi = 0) component removed,
// divided by |Theta|: the general formula tr S0 + tr S1 - 2 tr (S0^1/2 S1 S0^1/2)^1/2 on the |Theta| d x
// |Theta| d block-circulant covariances, diagonalised by the DFT (checked against Eigen in
// tests/analysis/test_ot_distance). It is a pseudo-metric on kernels (zero between kernels with the same
// covariance) and a metric on models. With the means (different Gaussians): d_OT,m^2 = d_OT^2 + |m0 - m1|^2,
// the per-pixel W2 distance of the full fields when the xi = 0 term is dropped. include_dc = true adds the xi
// = 0 term (for comparisons with the general matrix formula; S2 drops it because t_u has zero mean).
//
// RME (S2 §3.2, with eq. 1's factor 2): RME(model; reference)^2 = d_OT^2 / (1/|Theta| sum_{xi != 0}
// |href^|^2), the OT distance relative to the reference's marginal variance. Not symmetric.
#pragma once
#include <array>
#include <vector>

#include "analysis/fft.h"
#include "analysis/gaussian_model.h"
#include "analysis/image_io.h"
#include "runtime/model.h"

namespace stex {

struct GaussianSpectrum {
  int width = 0, height = 0, channels = 0;
  std::array<double, 4> mean{};
  std::vector<Complex> hat;  // planar channels x height x width, the DFT of h on Theta
};

// h = the kernel zero-padded at the origin of a width x height domain (at least the kernel's size).
GaussianSpectrum gaussian_spectrum(const NormalisedKernel& kernel, int width, int height);
// h = t_u of u's periodic component, zero-padded to width x height (0: u's own size).
GaussianSpectrum gaussian_spectrum_of_image(const Image& u, int width = 0, int height = 0);
// h^ = sqrt(b^) alpha^ on a width x height domain (at least s x s).
GaussianSpectrum gaussian_spectrum_of_model(const TextonModel& model, int width, int height);

struct OtDistance {
  double d2 = 0.0;                          // eq. 1 (xi != 0 unless include_dc)
  double mean2 = 0.0;                       // |m0 - m1|^2
  double variance0 = 0.0, variance1 = 0.0;  // 1/|Theta| sum_{xi != 0} |h^|^2: each model's marginal variance
  double distance() const;                  // sqrt(d2)
  double distance_with_mean() const;        // sqrt(d2 + mean2)
  double rme_1_vs_0() const;                // sqrt(d2 / variance0): model 1 against reference 0 (S2 §3.2)
  double rme_0_vs_1() const;                // sqrt(d2 / variance1)
};

// Error(Usage) when the domains or channel counts differ.
OtDistance ot_distance(const GaussianSpectrum& a, const GaussianSpectrum& b, bool include_dc = false);
// RME of `model` against `reference` (S2 §3.2). 0 when the reference is constant.
double relative_model_error(const GaussianSpectrum& reference, const GaussianSpectrum& model);

// Eq. 2: the spectrum of p_{h0}(h1), per frequency the orthogonal projection of h1^(xi) onto the C^d-circle
// {e^{i phi} h0^(xi)}: h0^ z/|z| with z = h0^* h1^ (z/|z| := 1 where z = 0, which stays on the circle; eq.
// 2's indicator gives 0 there). Every kernel k with k (.) k~ = h0 (.) h0~ is at the same OT distance from h1
// (the distance only sees |h0^* h1^|); p_{h0}(h1) is the one closest to h1 in L2, and that L2 distance is
// d_OT:
//   1/|Theta| sum_xi |p^ - h1^|^2 = d_OT^2(h0, h1) (with the xi = 0 term).
std::vector<Complex> ot_projection(const GaussianSpectrum& h0, const GaussianSpectrum& h1);

// C x C row-major colour covariance of the model: 1/|Theta| sum_xi Re(h_i^ conj(h_j^)) = sum_x h_i(x) h_j(x)
// (all frequencies: the marginal covariance of mean + h (.) W).
std::vector<double> spectrum_colour_covariance(const GaussianSpectrum& g);

}  // namespace stex
