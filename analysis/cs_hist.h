// Histogram transfer by example (S4 §5.3): stationary (§5.3.1, one bin) and cyclostationary per polyphase
// bin (§5.3.2) with the robust neighbourhood δ (§5.3.3). Builds the tables of runtime/cs_hist.h and the
// Gaussianised exemplar E_G = T_P(x)(E(x)); the codec helpers put the table into model files.
//
// Bins (kernels/shared/cs_hist.h): m0 = max(1, floor(|t0| sqrt(sin θ))), m1 likewise (θ the angle between
// t0 and t1), so that m0 m1 <= |Ω⁻|: a bin is a parallelogram of at least one pixel^2 in Ω⁻ (for
// axis-aligned integer periods exactly one texel: the bins are the texel polyphase components). Every
// exemplar texel belongs to the bin of its centre's phase; bin b's samples E^b are the texels of the bins
// (i + di, j + dj), |di|, |dj| <= δ (periodic, distinct bins: δ = 1 pools 9 bins), grown by one ring at a
// time while fewer than k_cs_hist_min_samples (only bins of thin or skewed cells need it).
// T_b: the rank r of a value among E^b's n samples (ties broken by a fixed hash of the texel's lattice cell,
// then its index: a binary bin spreads over the whole Gaussian, and a flat motif's texels of one cell get
// the same rank position in their bins, so E_G stays coherent across the motif) -> 0.5 + Phi^-1((r + 1/2) / n) / 6. Each texel is
// Gaussianised with its own bin's T. T_b^-1: q quantiles of E^b at (k + 1/2) / q, q = min(1024, floor(w h /
// (m0 m1))): the table has at most w h entries per channel, the exemplar's size.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "analysis/cs_lattice.h"
#include "analysis/image_io.h"
#include "model/codecs.h"
#include "runtime/cs_hist.h"

namespace stex {

inline constexpr int k_cs_hist_min_samples = 4;
inline constexpr int k_cs_hist_max_q = 1024;

// PCA of an image's colours, in double: mean[c] and B's rows (the eigenvectors of the colour covariance,
// Eigen's ascending order) rows[d * ch + c]; project() is coordinate d of a pixel, B (px - mean).
struct ColourPca {
  int ch = 0;
  std::vector<double> mean, rows;
  double project(const float* px, int d) const {
    double s = 0.0;
    for (int c = 0; c < ch; ++c) s += rows[std::size_t(d) * ch + c] * (px[c] - mean[c]);
    return s;
  }
  // The device form: ch means, then the ch x ch rows of B, in float.
  std::vector<float> device_basis() const;
};
ColourPca colour_pca(const Image& e);
// PCA coordinates of the colours (cs-spot's transfer; tiling and blending uses colour_pca directly):
// basis = ColourPca::device_basis(), coords = B (e - mean) in float.
void pca_coordinates(const Image& e, std::vector<float>* basis, Image* coords);
// The bin grid of a lattice (see above).
void cs_hist_bins(const Lattice& t, int* m0, int* m1);
// mode 1 (stationary; periods unused, may be null) or 2 (cs; periods validated). gauss (may be null)
// receives E_G, the same size as img. Error(Usage) for a bad mode or delta.
CsHistTable build_cs_hist(const Image& img, const Lattice* periods, int mode, int delta, Image* gauss);
// "none" / "stationary" / "cs" -> 0 / 1 / 2 (Error(Usage) naming the choices otherwise).
int parse_cs_hist_mode(const std::string& name);

}  // namespace stex
