// The spectrum a model is expected to produce, as the Welch estimator of analysis/lrp.h (lrp_welch: Hann-
// windowed periodograms of T x T crops, DC zeroed, normalised so that the sum is the variance) would measure
// it on a render: the common part (an autocovariance through the estimator), and the autocovariances of the
// spectral kinds other than LRP (whose strata have their own, analysis/lrp_psd.h). `stex gabor`, `stex
// analyze --method gabor` and `stex cs-rpn` report these against the spectrum they were made from, as `stex
// analyze --method lrp` does (compare_psd, analysis/lrp_psd.h).
//
// Why the autocovariance: a periodogram of a crop of a stationary field has the expectation
//   E |FFT(h u)(k)|^2 = sum_{d in (-T, T)^2} C(d) R_h(d) e^{-2 pi i k.d / T},
// C the field's autocovariance, R_h the Hann window's autocorrelation: it holds the kernels' spectral blur and
// the estimator's own leakage exactly, with no sampling of a continuous spectrum.
#pragma once
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "analysis/image_io.h"
#include "analysis/lrp_psd.h"
#include "runtime/cs_rpn.h"
#include "runtime/gabor_params.h"

namespace stex {

// The Welch estimator's Hann window h(i) = sin^2(pi (i + 1/2) / T): its autocorrelation per axis on lags
// (-T, T) (r1[d + T - 1]) and (sum h^2)^2 over the T x T crop.
struct WelchHann {
  int period = 0;
  std::vector<double> r1;
  double h2 = 0.0;
};
WelchHann welch_hann(int period);

// The expected Welch PSD (T x T, FFT order, DC zeroed) of a stationary field with autocovariance
// cov(dx, dy), called once for every lag |dx|, |dy| < T.
std::vector<double> expected_welch_psd(int period, const std::function<double(int dx, int dy)>& cov);

// The LRP window's autocorrelation g(rho) = int w(|y|) w(|y + (rho, 0)|) d^2y (runtime/lrp_model.h's w,
// radius 1.5; rho in lattice spacings; g(0) = 2 pi int r w^2 dr to 2e-3), tabulated on steps of 0.01.
double lrp_window_autocorrelation(double rho);

// Gabor noise (runtime/gabor_params.h, kernels/shared/gabor.h) at scale 1: impulses of random sign, each
// kernel exp(-pi a^2 |d|^2) cos(2 pi f.d) with its component drawn by weight and its orientation uniform in
// omega +- spread / 2, so
//   C(d) = std^2 e^{-pi a^2 |d|^2 / 2} sum_k p_k (mean_theta cos(2 pi f_k,theta . d) + e^{-2 pi F_k^2 / a^2})
//          / sum_k p_k (1 + e^{-2 pi F_k^2 / a^2})
// (the envelope's 2^-12 truncation left out: below 1e-7 of the variance). The orientation mean is a
// midpoint rule fine enough that neighbouring orientations differ by < 0.2 radian of phase at any lag the
// envelope leaves above 1e-12.
std::vector<double> gabor_expected_welch_psd(const GaborModel& model, int period);

// One spectrum g of a cs-rpn model (runtime/cs_rpn.h) rendered alone (a stationary field: the model's other
// spectra, and so its cyclostationarity, left out), at scale 1, with Welch crops of period T = 1 / bin (its
// spectra's own grid; Error(Usage) if that is not an integer in [4, 4096]). With Phi(d) = sum_b p_b
// e^{2 pi i f_b . d} the table's characteristic function and s(d) = sinc(bin dx) sinc(bin dy) the in-bin
// jitter (1 for fourier):
//  - random phase: C(d) = E_g g(|d| / Delta) / g(0) Re Phi(d) s(d) (the lattice windows, as LRP);
//  - gabor:        C(d) = E_g e^{-pi a^2 |d|^2 / 2} Re Phi(d) s(d) (random-phase impulses: no cross term);
//  - phasor:       the output is sqrt(2 E_g) sin(arg phi), phi a complex field of normalised autocorrelation
//                  rho(d) = e^{-pi a^2 |d|^2 / 2} Phi(d) s(d); for a circular Gaussian phi,
//                  E sin(arg phi(x)) sin(arg phi(x + d)) = 1/2 Re[(pi / 4) rho 2F1(1/2, 1/2; 2; |rho|^2)]
//                  (the phase-only correlation), so C(d) = E_g Re[(pi / 4) rho 2F1(.)]: the sine profile's
//                  harmonics included, the Poisson impulses taken as Gaussian (the limit of high mni);
//  - fourier:      C(d) = E_g Re Phi(d) (the series itself).
std::vector<double> cs_rpn_expected_welch_psd(const CsRpnModel& model, std::size_t spectrum);
// What spectrum g asks for on the same grid (T = 1 / bin, FFT order): E_g p_b split between f_b and -f_b.
std::vector<double> cs_rpn_spectrum_psd(const CsRpnModel& model, std::size_t spectrum);
// T = 1 / bin as an integer; Error(Usage) when it is not one in [4, 4096].
int cs_rpn_spectrum_period(const CsRpnModel& model);

// The checks `stex gabor` and `stex analyze --method gabor` print (compare_psd of the model's expected Welch PSD
// against a reference):
//  - against an exemplar: its Welch PSD (lrp_welch, T by its rule: the largest power of two below the smaller
//    side, at most 1024) of the channel mean, the grey image gabor's analysis takes (analysis/gabor_model.h);
//  - against a PSD image (centred, gabor_model_from_psd's convention): square power-of-two images of side 16..1024
//    only, symmetrised, normalised to the model's variance (lrp_psd_from_image); nullopt for other images.
PsdComparison gabor_check_against_exemplar(const GaborModel& model, const Image& exemplar);
std::optional<PsdComparison> gabor_check_against_psd_image(const GaborModel& model, const Image& psd);
// Every spectrum of a cs-rpn model: cs_rpn_expected_welch_psd against cs_rpn_spectrum_psd. Spectra of energy 0
// are skipped (an empty comparison, period 0).
std::vector<PsdComparison> cs_rpn_check_spectra(const CsRpnModel& model);

}  // namespace stex
