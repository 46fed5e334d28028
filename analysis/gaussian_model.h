// Statistics of Gaussian texture models shared by the analyses:
//  - the normalised kernel t_u = (p - mean)/sqrt(|Omega|) of an exemplar's periodic component, per channel
//    (S1 §3.1, S2 eq. 3), whose autocorrelation is the exemplar's (circular) covariance;
//  - the sampled B-spline b of S1 §4.1 (order 1: the 3x3 (1/6, 2/3, 1/6) outer product; order 0: a delta)
//    and its DFT b^ on Omega;
//  - the covariance of a texton noise with interpolation coefficients alpha (S1 §4.1, Proposition 1):
//    C_ij(tau) = sum_l R_ij(l) b(tau - l), R_ij(l) = sum_x alpha_i(x + l) alpha_j(x);
//  - S2's relative model error (RME), extended to the interpolated model (see texton_rme).
// Planar layouts throughout: channel c, row y, column x at (c * height + y) * width + x.
#pragma once
#include <array>
#include <vector>

#include "analysis/fft.h"
#include "analysis/image_io.h"

namespace stex {

struct NormalisedKernel {
  int width = 0, height = 0, channels = 0;
  std::array<double, 4> mean{};  // mean of u (= mean of its periodic component)
  std::vector<double> t;         // planar t_u
};

// t_u of `u`; `periodic` replaces u by its periodic component first (S1 §4.2), as the analysis does.
NormalisedKernel normalised_kernel(const Image& u, bool periodic = true);

// b(dx, dy) of the given interpolation order k (0, 1, 3 or 5; S1 §4.1 and §10): the sampled
// psi * psi = beta^(2k+1) (order 1: the 3x3 (1/6, 2/3, 1/6) outer product; order 0: a delta), zero outside
// {-k..k}^2 (bspline_reach). Other orders: Error(Usage).
double bspline_sample(int order, int dx, int dy);
int bspline_reach(int order);
// A real 1-D filter q of length order + 1 with sum_x q(x + d) q(x) = b_1(d) (the minimum-phase spectral
// factor of the sampled B-spline: q * q~ = beta^(2 order + 1) at the integers), so that alpha * (q x q) has
// the texton noise covariance on Z^2. Order 0: {1}; order 1: ((1 + 1/sqrt 3)/2, (1 - 1/sqrt 3)/2).
std::vector<double> bspline_spectral_factor(int order);
// b^ on a width x height DFT grid (real, positive: >= 1/9 for order 1, ~2.9e-3 for 3, ~7.9e-5 for 5), in
// closed form: per axis b(0) + 2 sum_d b(d) cos(2 pi d q / W); order 1: (2/3 + cos(2 pi kx / W)/3)(...).
std::vector<double> bspline_hat(int width, int height, int order);

// Texton noise covariance C_ij(dx, dy) (above) for s x s planar alpha with `channels` channels.
double model_covariance(const std::vector<double>& alpha, int channels, int support, int order, int i, int j,
                        int dx, int dy);
double model_covariance(const std::vector<float>& alpha, int channels, int support, int order, int i, int j,
                        int dx, int dy);
// C x C row-major matrix C_ij(0): the model's colour covariance (A of S1 §4.3's colour correction).
std::vector<double> model_colour_covariance(const std::vector<double>& alpha, int channels, int support,
                                            int order);
std::vector<double> model_colour_covariance(const std::vector<float>& alpha, int channels, int support,
                                            int order);
// C x C row-major sum_x t_u(x) t_u(x)^T: the exemplar's colour covariance (B of the colour correction).
std::vector<double> exemplar_colour_covariance(const NormalisedKernel& tu);

// Per-channel DFTs of t_u on Omega (planar, complex).
std::vector<Complex> kernel_spectrum(const NormalisedKernel& tu);

// RME of an interpolated texton against t_u, S2 §3.2 extended to S1's model:
//   RME^2 = sum_{xi != 0} ( |u^|^2 + |m^|^2 - 2 |u^* m^| ) / sum_{xi != 0} |u^|^2,
// with u^ = t_u^ (a C^channels vector per frequency), m^ = sqrt(b^) alpha^ the spectral square root of the
// model's sampled covariance (|m^|^2 = |alpha^|^2 b^, S1 eq. 4), alpha^ the DFT on Omega of alpha placed at
// [0,s)^2 and zero elsewhere. The numerator is the squared OT distance between the circular Gaussian models
// (S2 eq. 1; the factor 2 of eq. 1 makes it zero when the spectra agree). For order 0 (b^ = 1) this is
// exactly S2's RME of the SOT. Returns 0 for a constant exemplar.
double texton_rme(const NormalisedKernel& tu, const std::vector<Complex>& tu_hat,
                  const std::vector<double>& alpha, int support, int order);
double texton_rme(const NormalisedKernel& tu, const std::vector<double>& alpha, int support, int order);

}  // namespace stex
