// Noise mixing (S1 §7): the optimal-transport barycentre tau_rho between the Gaussian (ADSN) models of two
// exemplars u and v, the textons alpha_rho of K barycentres computed by S1 Algorithm 1 from one shared
// initial noise, the stored model of kind "mix" (docs/model-format.md) and mixing maps from images. The
// runtime model and the maps are runtime/mix_model.h; the evaluation is kernels/shared/mix.h.
//
// S1 §7 (following Xia, Ferradans, Peyré, Aujol 2014): "for a mixing parameter rho in [0, 1], the barycenter
// of the ADSN models associated with the kernels t_u = (u - mean(u)) / sqrt|Omega| and t_v = ... is the ADSN
// model associated with the kernel tau_rho defined by
//
//   tau_rho = (1 - rho) tau_0 + rho tau_1   with   tau_0 = (t_u^* t_v / |t_u^* t_v|) t_u,   tau_1 = t_v."
//
// The product and the ratio are per frequency on the DFTs (t_u^* t_v = sum_c conj(t_u,c^) t_v,c^, the
// Hermitian product over channels: the colour case of XFPA14), z/|z| := 1 where z = 0 (as the projection of
// S2 eq. 2, analysis/ot_distance.h). tau_0 has the covariance of t_u (one unit phase per frequency on all
// channels) and the phase of t_v, so that tau_0^* tau_1 = |t_u^* t_v| >= 0 at every frequency; then per
// frequency |tau_0^* tau_rho| = (1 - rho)|tau_0|^2 + rho |t_u^* t_v| and S2's eq. 1 gives
//   d_OT(tau_0, tau_rho) = rho d_OT(tau_0, tau_1),   d_OT(tau_rho, tau_1) = (1 - rho) d_OT(tau_0, tau_1):
// the displacement interpolation (a geodesic) between the two models (tests/mix checks both). tau_0, tau_1
// are real (conjugate-symmetric spectra); the mean of model rho is (1 - rho) mean(u) + rho mean(v).
//
// "Using the same white noise initialization in Algorithm 1 allows to compare the different textures": the
// K textons alpha_{rho_k}, rho_k = k / (K - 1), all start from texton_initial_noise(Omega, seed) (so level
// K - 1 is exactly analyse_texton(v, seed)), each with the colour correction towards its own barycentre's
// covariance sum_x tau_rho tau_rho^T.
//
// The two exemplars must share a grid Omega: a larger one is cropped to the common size (top-left, with a
// warning), and a grey exemplar mixed with a colour one is replicated to the colour one's channels.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/gaussian_model.h"
#include "analysis/image_io.h"
#include "model/codecs.h"
#include "analysis/texton.h"
#include "runtime/mix_model.h"

namespace stex {

// tau_0 and tau_1 of S1 §7 on Omega (planar, like NormalisedKernel::t), with the exemplars' means.
struct MixBarycentre {
  NormalisedKernel tau0, tau1;
  // tau_rho = (1 - rho) tau_0 + rho tau_1, mean (1 - rho) m0 + rho m1. rho in [0, 1] (Error(Usage)).
  NormalisedKernel at(double rho) const;
};

// Error(Usage) when the kernels' grids or channel counts differ.
MixBarycentre mix_barycentre(const NormalisedKernel& tu, const NormalisedKernel& tv);

struct MixParams {
  int levels = 17;  // K in [2, 257]
  int support = 64, iterations = 50, order = 1;
  std::uint64_t seed = 0;
  bool colour_correction = true;
  bool linear = false;  // recorded: the exemplars were decoded to linear light
  MixMap map;           // stored in the model as its default map (runtime/mix_model.h)
};

struct MixReport {
  double ot_distance = 0.0;           // d_OT(tau_0, tau_1) (S2 eq. 1, per pixel)
  std::vector<TextonReport> levels;   // Algorithm 1's report per level
  std::vector<std::string> warnings;  // cropping, channel promotion, constant exemplars
  double ms_total = 0.0;
};

// Brings two exemplars to one grid and channel count (above); appends what it did to `warnings`.
void match_exemplars(Image& u, Image& v, std::vector<std::string>* warnings);
// The K textons (above). Errors as analyse_texton (Usage for bad parameters, Input for small exemplars),
// Usage for levels outside [2, 257].
MixModel analyse_mix(const Image& u, const Image& v, const MixParams& params, MixReport* report = nullptr);
// Loads both (load_exemplar with opts), analyses, records names (without directories) and SHA-256s.
MixModel analyse_mix_files(const std::string& path_u, const std::string& path_v, const LoadOptions& opts,
                           MixParams params, MixReport* report = nullptr);

// A mixing map from a grey image file (channel mean; load_exemplar's decoding, no linearisation), each map
// pixel covering `scale` output pixels, its top-left corner at output pixel (origin_x, origin_y), repeated or
// clamped outside. Error(Input) for an unreadable image, Error(Usage) for bad parameters.
MixMap mix_map_from_image(const std::string& path, double scale, std::int64_t origin_x, std::int64_t origin_y,
                          bool clamp);
// --mix-map SPEC with its image options: an analytic spec (const:, ramp:, strips:) or an image path; wrap is
// "repeat" or "clamp", origin "X,Y". The image options apply only to images (Error(Usage) otherwise when
// `image_options_given`).
MixMap parse_mix_map(const std::string& spec, double scale, const std::string& origin, const std::string& wrap,
                     bool image_options_given);


}  // namespace stex
