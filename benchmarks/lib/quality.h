// Quality of a render measured against the Gaussian model it approximates (issue #5; S1 Theorem 2: texton
// noise tends to the ADSN of the exemplar as MNI grows, and its power spectrum is fixed by the texton):
//
//  - spectrum error: the normalised power-spectrum error against the ADSN model. The ADSN of an exemplar u
//    on its own grid Omega (W x H) has the expected periodogram |FFT(p - mean p)|^2 / |Omega|, p the periodic
//    component of u (S1 §3.1, §4.2). The render is cut into W x H blocks overlapping by half (Welch: offsets
//    multiple of W/2 and H/2, every block whole inside the render; 9 blocks on a 1024^2 render of a 512^2
//    exemplar); each block, per channel, is replaced by its periodic component (so that the block's border
//    does not leak into the spectrum, exactly as for the exemplar) and its periodogram |FFT(b - mean b)|^2 /
//    |Omega| is taken; periodograms are summed over channels and averaged over blocks. Both spectra are then averaged
//    over rings of radius rho = round(M sqrt((kx/W)^2 + (ky/H)^2)), M = min(W, H), for rho = 1 .. M/2 (the
//    DC term and the corners beyond the Nyquist circle are left out). The error is the MEDIAN over rings of
//    |P_render(rho) - P_adsn(rho)| / P_adsn(rho). 0 is a perfect match; the estimate itself fluctuates by a
//    few percent (a ring of radius rho averages ~pi rho frequencies x blocks x channels exponential-like
//    periodogram values, and heavy-tailed shot noise at low MNI fluctuates more): the ADSN baseline's own score in the same run is that noise floor.
//  - excess kurtosis of the marginal: m4 / m2^2 - 3 per channel (central moments over all pixels), averaged
//    over channels. 0 for the Gaussian limit; shot noise has integral h^4 / (lambda (integral h^2)^2) > 0,
//    which falls as 1/MNI.
// Renders are interleaved (pixel (i, j) channel c at (j * width + i) * channels + c).
#pragma once
#include <cstddef>
#include <vector>

#include "analysis/image_io.h"

namespace stex::bench {

class SpectrumReference {
 public:
  explicit SpectrumReference(const Image& exemplar);

  // The median relative ring error of a render (see above). Throws stex::Error(Usage) if the render is
  // smaller than one block or has a different channel count.
  double error(const float* pixels, int width, int height, int channels) const;
  // Ring averages of the exemplar (rho = 0 .. M/2; entry 0 unused).
  const std::vector<double>& reference_rings() const { return ref_rings_; }
  // Ring averages of a render (same layout), as error() computes them.
  std::vector<double> render_rings(const float* pixels, int width, int height, int channels) const;
  int block_width() const { return bw_; }
  int block_height() const { return bh_; }

 private:
  std::vector<double> rings_of(const std::vector<double>& half_power) const;
  int bw_ = 0, bh_ = 0, channels_ = 0, rings_ = 0;
  std::vector<int> ring_;        // ring of each half-spectrum entry ((bw/2 + 1) x bh), -1 if unused
  std::vector<double> weight_;   // 2 for entries standing for a conjugate pair, else 1
  std::vector<double> ring_weight_;
  std::vector<double> ref_rings_;
};

// Mean over channels of the per-channel excess kurtosis m4 / m2^2 - 3.
double excess_kurtosis(const float* pixels, std::size_t pixel_count, int channels);

}  // namespace stex::bench
