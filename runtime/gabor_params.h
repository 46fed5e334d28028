// Gabor noise (Lagae et al. 2009, sparse Gabor convolution; S5's test noise): the model, its render setup
// (stex_gabor_params of kernels/shared/gabor.h, component tables, Poisson table) and the C++ reference
// evaluator on the shared header. The model kind is "gabor" (codec: analysis/gabor_model.h).
//
// Parameters, documented once here (`stex gabor --help` and the README draw on them):
//  - bandwidth a (1 / model pixel): the Gaussian envelope exp(-pi a^2 |d|^2); the kernel is truncated at
//    radius r = sqrt(12 / (pi a^2 log2 e)) ~ 1.63 / a (envelope 2^-12). A lobe of the PSD is a Gaussian of
//    standard deviation a / (2 sqrt(pi)) cycles per pixel. In [1/1024, 1].
//  - components k = 1..K (K <= 4096): frequency F_k (cycles per model pixel, [0, 0.5]), orientation omega_k
//    (radians), orientation spread_k (radians, [0, 2 pi]: 0 anisotropic, 2 pi isotropic) and weight p_k >= 0
//    (relative power; at least one > 0). A single component is Lagae's anisotropic (spread 0) or isotropic
//    (spread 2 pi) noise; several make multi-lobe spectra (S5 Fig. 3, 14-17); many approximate any PSD
//    (analysis/gabor_model.h builds them from a PSD image).
//  - mean, std: the output's mean and standard deviation (the noise is normalised by its theoretical
//    standard deviation sigma_n of kernels/shared/gabor.h).
// Render parameters (runtime/texton_params.h RenderParams): seed; mni = mean number of impulses whose kernel
// disc (radius r) covers a point, lambda = mni / (pi r^2); cell_factor = cell side / r (S1 §8's 0.6); scale =
// output pixels per model pixel; filter = filter a minified view (gabor_filter below). Output: 1 channel.
#pragma once
#include <cstdint>
#include <vector>

#include "kernels/shared/gabor.h"
#include "runtime/texton_params.h"

namespace stex {

struct GaborComponent {
  double frequency = 0.1;    // cycles per model pixel
  double orientation = 0.0;  // radians
  double spread = 0.0;       // radians: orientations uniform in orientation +- spread / 2
  double weight = 1.0;       // relative power
};

struct GaborModel {
  double bandwidth = 0.05;  // a, 1 / model pixel
  std::vector<GaborComponent> components = std::vector<GaborComponent>(1);  // one default component
  double mean = 0.5;
  double stddev = 0.15;
};

inline constexpr double k_gabor_min_bandwidth = 1.0 / 1024.0, k_gabor_max_bandwidth = 1.0;
inline constexpr double k_gabor_max_frequency = 0.5;
inline constexpr double k_gabor_pi = 3.14159265358979323846;

// Checks every field; Error(Input) naming it ("invalid gabor model: ...").
void validate_gabor_model(const GaborModel& model);
// sigma_n: the theoretical standard deviation of n(x) = sum_i w_i g(x - x_i) at intensity lambda.
double gabor_noise_sigma(const GaborModel& model, double lambda);
// Truncation radius r of the kernel in model pixels.
double gabor_radius(double bandwidth);
// The theoretical PSD of the render (before mean and std; per unit area) at frequency (u, v) in cycles per
// model pixel, normalised so that its integral over the plane is std^2.
double gabor_psd(const GaborModel& model, double u, double v);

// The footprint filter of a render (RenderParams::filter at scale < 1; identity otherwise): the filtered
// kernel's bandwidth a' = sqrt(rho) a, carrier factor and amplitude rho, and the gain of each component.
struct GaborFilter {
  double sigma2 = 0.0;     // footprint variance per axis, model pixels^2 (0: unfiltered)
  double rho = 1.0;        // 1 / (1 + 2 pi a^2 sigma^2)
  double bandwidth = 0.0;  // a'
  std::vector<double> gain;  // per component: exp(-2 pi^2 sigma^2 rho F_k^2)
  // The envelope is truncated where exp2 of minus this (12 unfiltered; 12 + log2(rho max gain) filtered,
  // 0: the kernel is below the truncation threshold everywhere and adds nothing).
  double exponent_max = 12.0;
};
GaborFilter gabor_filter(const GaborModel& model, const RenderParams& params);

struct GaborSetup {
  stex_gabor_params params{};
  std::vector<float> components;               // STEX_GABOR_COMPONENT_FLOATS per component
  std::vector<std::uint32_t> component_table;  // inverse-CDF thresholds of the weights
  std::vector<std::uint32_t> poisson_table;
  double lambda = 0.0, cell_mean = 0.0, radius = 0.0;
};

// Validates model (Error(Input)) and parameters (Error(Usage)) and builds everything the kernel needs.
GaborSetup make_gabor_setup(const GaborModel& model, const RenderParams& params);

// The C++ reference: stex_gabor_eval compiled as C++, one call per pixel (single-threaded; tests).
class GaborReference {
 public:
  GaborReference(const GaborModel& model, const RenderParams& params) : setup_(make_gabor_setup(model, params)) {}
  // Pixels [x, x + width) x [y, y + height), row-major, 1 channel. Validates the region (Error(Usage)).
  std::vector<float> render(std::int64_t x, std::int64_t y, int width, int height) const;
  const GaborSetup& setup() const { return setup_; }

 private:
  GaborSetup setup_;
};

}  // namespace stex
