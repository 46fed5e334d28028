// `stex analyze --method auto`: which model kind suits an exemplar, with the measures that decided it.
//
// Three questions, each a measure of the exemplar against a threshold (values measured on data/ and on
// stex's own renders are in docs/auto.md; tests/analysis/test_kind_choice.cpp checks the picks on a
// labelled set):
//  1. Does it repeat on a lattice? The autocorrelation's two peaks (at least k_repeat_peaks,
//     analysis/cs_lattice.h), then the period estimation of S4 §6 and its confidence: at least
//     k_auto_lattice_confidence is a lattice (the tile photographs of data/: 0.22-0.36).
//  2. Is it far from Gaussian? Texton noise and the other Gaussian kinds reproduce the exemplar's spectrum and
//     nothing else: their textures are random-phase, and any structure that lives in the phases (edges,
//     stones, blades, grout) is lost. Two measures, each 1 or 0 for a Gaussian texture whatever its spectrum:
//     - the gradient ratio TV(u) / E[TV(ADSN(u))]: the exemplar's total variation (periodic differences, summed
//       over channels) over the expected total variation of its asymptotic discrete spot noise, which is exact
//       in closed form: each derivative of ADSN(u) is Gaussian with the variance of u's periodic derivative,
//       so E|g| = sqrt(2 / pi) rms(g). Phase coherence (sharp edges, flat regions) makes gradients sparse and
//       the ratio low; this is the effect size behind Blanchet and Moisan's sharpness index (2012), without
//       their normalisation by TV's standard deviation, which grows with the image size;
//     - the marginal distance: the 1-Wasserstein distance between each channel's standardised histogram and
//       the standard normal distribution (mean over channels), which texton noise cannot change either.
//     Far from Gaussian: gradient ratio below k_auto_gradient_ratio, or marginal distance above
//     k_auto_marginal_distance.
//  3. The kind: a lattice and far from Gaussian: cs-tb (tiling and blending on the lattice keeps the cells'
//     content); a lattice and near Gaussian: cs-spot (a cyclostationary Gaussian texture); no lattice and far
//     from Gaussian: tb; otherwise texton (a micro-texture, S1's domain).
// `allowed` restricts the pick (the kinds whose options the user gave); the preference order of each case
// lists the next best kind, so the pick is always one of `allowed`.
#pragma once
#include <string>
#include <vector>

#include "analysis/cs_lattice.h"
#include "analysis/image_io.h"

namespace stex {

inline constexpr double k_auto_lattice_confidence = 0.15;
inline constexpr double k_auto_gradient_ratio = 0.92;
inline constexpr double k_auto_marginal_distance = 0.15;

struct KindChoice {
  std::string kind;             // model/kinds.h's name: texton, tb, cs-spot or cs-tb
  double gradient_ratio = 1.0;  // TV(u) / E[TV(ADSN(u))]
  double marginal_distance = 0.0;
  bool lattice_searched = false;  // only when a cyclostationary kind is allowed
  double peaks = 0.0;             // the weaker of the autocorrelation's two peaks (1: a perfect repeat)
  bool lattice = false;           // peaks >= k_repeat_peaks and confidence >= k_auto_lattice_confidence
  double residual_gradient_ratio = 1.0, residual_marginal_distance = 0.0;  // of u - M (on a lattice)
  PeriodEstimate periods;         // when searched and found (confidence may still be low)
  std::string why;                // one sentence: the measures and the thresholds that decided
};

// The exemplar minus its cyclic mean M (S4 eq. 3) at the pixel centres.
Image cyclic_residual(const Image& img, const Lattice& t);

// The gradient ratio and the marginal distance (question 2 above). Error(Input) for an exemplar smaller than
// 2 x 2.
double gradient_ratio(const Image& img);
double marginal_distance(const Image& img);

// The pick among `allowed` (a subset of texton, tb, cs-spot, cs-tb; not empty), as described above.
KindChoice choose_kind(const Image& exemplar, const std::vector<std::string>& allowed);

}  // namespace stex
