// The spectrum an LRP model (runtime/lrp_model.h) is expected to produce, and the comparison of two power
// spectra by radial and polar bins: what `stex analyze --method lrp` reports and what the LRP tests assert.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/lrp_model.h"

namespace stex {

// The exact expected Welch PSD (analysis/lrp.h's estimator on crops of the model's T, DC zeroed) of a render
// of the model's random-phase strata `which_strata` (all when empty); r = 0 models, or the strata part of
// any model (the fixed-phase structure is left out). Channels: the trace (sum over channels).
//  - strata are independent (their own RNG domains); within a stratum, lattice points and cosines have
//    independent uniform phases, so averaged over positions the autocovariance of n_S is
//      C_S(d) = sum_j A_j^2 / 2 * E cos(2 pi f_j . d) * g(|d| / Delta_S),
//    A_j = A_S |v_j| (v_j the sub-stratum's colour weights, their norm the sub-stratum's gain),
//    g(rho) = int w(|y|) w(|y + (rho, 0)|) d^2y (the window's autocorrelation over one lattice cell's area
//    Delta_S^2), and f_j = (k + u) / T with k uniform in sub-stratum j's table and u uniform in [-1/2, 1/2)^2
//    (the in-bin jitter): E cos = mean_k cos(2 pi k.d / T) * sinc(dx / T) sinc(dy / T);
//  - a Hann-windowed periodogram has expectation E|FFT(h u)(k)|^2 = sum_d C(d) R_h(d) e^{-2 pi i k.d / T},
//    R_h the window's autocorrelation, lags d in (-T, T)^2 folded mod T; lrp_welch divides by T^2 sum h^2.
// So it includes the window's spectral spread, the jitter and the estimator's own (Hann) leakage; only the
// lattice's non-stationarity (an envelope varying < 5 %, S3 §3.4, averaged over each crop) is left out.
std::vector<double> lrp_expected_welch_psd(const LrpModel& model, const std::vector<std::size_t>& which_strata = {});

// One sub-stratum's expected Welch PSD at unit amplitude A_j = 1 (same derivation); `first` is the index of
// its first table entry in model.freqs / 2. The building block of lrp_expected_welch_psd.
std::vector<double> lrp_sub_stratum_psd(const LrpModel& model, std::size_t stratum, std::size_t first, int count);

// Fits the amplitudes of every sub-stratum's cosines to `target` (T x T, FFT order): weighted least squares
// on the relative error of the expected Welch PSD over polar bins (32 radial over [0, 1/2) cycles per pixel,
// the corners beyond, x 16 angles), x >= 0, by multiplicative updates from the model's amplitudes. Each
// stratum's amplitude becomes its largest cosine amplitude, the colour weights carry the ratios (norm <= 1).
void lrp_fit_gains(LrpModel& model, const std::vector<double>& target, int iterations = 500);

// Two T x T power spectra (FFT order) compared as the ratio `psd / reference` of their sums over
//  - 24 radial bins of |f| in [0, 1/2) cycles per pixel (corners beyond 1/2 left out), and
//  - 6 radial x 8 angular polar sectors (|f| in [0.02, 1/2), angle in [0, pi)).
// radial_median: median over the radial bins of |ratio - 1|; radial_max: the largest over the bins holding at
// least 200 frequencies and some reference power (radial_max_bins of them); sector_median: the median of |ratio - 1|
// over the sectors. displaced: the share of the power that sits elsewhere, (1/2) sum_f |p(f) - r(f)| over
// every frequency but DC, each spectrum normalised to sum 1 (the total-variation distance: 0 equal, 1
// disjoint). The ratios judge broad spectra bin by bin; for a narrow one (a bi-lobe, lines) most bins hold
// almost nothing and their ratios say little, while `displaced` measures what a blur moves off the lines.
struct PsdComparison {
  int period = 0;
  std::vector<double> radial_ratio, sector_ratio;
  std::vector<int> radial_count, sector_count;
  double radial_median = 0.0, radial_max = 0.0, sector_median = 0.0;
  int radial_max_bins = 0;
  double displaced = 0.0;
};
PsdComparison compare_psd(const std::vector<double>& psd, const std::vector<double>& reference, int period);
// "median |error| 0.072, max 0.168 (bins >= 200 frequencies); polar sectors: median 0.038; displaced 0.021":
// what the CLIs print ("max n/a" when no radial bin holds 200 frequencies).
std::string psd_comparison_summary(const PsdComparison& c);
// The figures and the per-bin ratios as JSON (radial_median, radial_max (null without a bin of 200
// frequencies), sector_median, displaced, radial_bins,
// radial_ratio, radial_count, sector_bins, sector_ratio).
nlohmann::ordered_json psd_comparison_json(const PsdComparison& c);

}  // namespace stex
