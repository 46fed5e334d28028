// The baselines S2 §4 / Fig. 4 compares the SOT with, on the same support mask S:
//  - the luminance texton of Desolneux-Moisan-Ronsin (S2 ref. [1], "DMR's canonical texton"): every channel
//  of
//    t_u^ with the phase of the luminance combination removed,
//      t_lum,c^(xi) = t_u,c^(xi) conj(l^(xi)) / |l^(xi)|,   l^ = sum_c w_c t_u,c^   (:= t_u,c^ where l^ = 0),
//    with w = (1/3, 1/2, 1/6) for RGB (S2 §4), w = 1 for grey (t_lum^ = |t_u^|) and equal weights 1/C for
//    other channel counts. Its luminance has zero phase, so it is concentrated around the origin of Omega;
//    the cropped version t_lum^c keeps the pixels of S with the mask's centre on that origin (wrap-around);
//  - the cropped random-phase texton t_rpn: the random-phase image t^ = t_u^ e^{i psi} that initialises
//    Algorithm 2 (analysis/sot.h, same seed, same psi), cropped to S at [0, s)^2. It equals one iteration of
//    Algorithm 2 (SotSolver::run(seed, 1)).
// Both have the exact modulus |t_u^| before the crop (the luminance texton is a model-preserving choice of
// phase), so their RME comes from the crop alone; S2 §4 reports the SOT's RME below both.
#pragma once
#include <cstdint>
#include <vector>

#include "analysis/fft.h"
#include "analysis/gaussian_model.h"
#include "analysis/support_mask.h"

namespace stex {

// (1/3, 1/2, 1/6) for 3 channels, 1 for 1 channel, 1/C otherwise.
std::vector<double> luminance_weights(int channels);

// The full (Omega-sized, planar) luminance texton; tu_hat = kernel_spectrum(tu).
std::vector<double> luminance_texton(const NormalisedKernel& tu, const std::vector<Complex>& tu_hat);

// alpha(c, y, x) = full(c, (y - cy) mod H, (x - cx) mod W) 1_S(x, y) for (x, y) in [0, s)^2, (cx, cy) the
// mask centre: a crop of an Omega-sized planar kernel around its origin. Error(Usage) on size mismatch.
std::vector<double> crop_centred(const std::vector<double>& full, int width, int height, int channels,
                                 const SupportMask& mask);

// t_lum^c: crop_centred(luminance_texton(tu)).
std::vector<double> cropped_luminance_texton(const NormalisedKernel& tu, const std::vector<Complex>& tu_hat,
                                             const SupportMask& mask);

// The random-phase image IDFT(t_u^ e^{i psi}) of Algorithm 2's initialisation for `seed` (Omega-sized,
// planar), and its crop to S at [0, s)^2 (t_rpn of S2 Fig. 4).
std::vector<double> random_phase_texton(const NormalisedKernel& tu, const std::vector<Complex>& tu_hat,
                                        std::uint64_t seed);
std::vector<double> cropped_random_phase_texton(const NormalisedKernel& tu,
                                                const std::vector<Complex>& tu_hat, const SupportMask& mask,
                                                std::uint64_t seed);

}  // namespace stex
