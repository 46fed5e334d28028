// Render parameters of texton noise and their translation into the kernel struct stex_texton_params
// (kernels/shared/texton.h): intensity lambda = MNI / r^2 (S1 §3.3, "Shot noise evaluation cost"), the cell
// grid of side c r (S1 §8, c = 0.6), the per-cell Poisson mean and its integer threshold table, the reach of
// an impulse in fixed-point units, and the padded planar alpha planes the kernels fetch from (S1 eq. 3).
//
// Every strategy (tile splat, gather, the C++ reference, point queries) starts from the TextonSetup built
// here, so they all see the same integers and the same float constants: that is what makes their outputs
// bit-identical.
#pragma once
#include <cstdint>
#include <vector>

#include "kernels/shared/texton.h"
#include "runtime/model.h"

namespace stex {

// Parameters of one render of a texton noise model. Documented once here; `stex render --help` and the
// README draw on it.
struct RenderParams {
  // Mean number of impacts per point (S1 §3.3): lambda = mni / r^2 with r = support + order (the width of
  // the texton's support for every order). In (0, 10000].
  double mni = 30.0;
  // Cell side of the grid Poisson process as a fraction c of r (S1 §8: 0.6). In [0.1, 2]. Changing it
  // changes the realisation, not the statistics.
  double cell_factor = 0.6;
  // 64-bit seed of the counter-based RNG: the impulses of a cell are a pure function of (seed, cell).
  std::uint64_t seed = 0;
  // Output pixels per exemplar pixel, in [1/1024, 1024]. Below 1 point-sampled renders alias; the filtered
  // renderer (runtime/texton_filter.h, S1 §5) does not.
  double scale = 1.0;
};

// Limits checked by make_texton_setup (exposed for tests and the CLI's messages).
inline constexpr double k_max_mni = 10000.0;
inline constexpr double k_min_cell_factor = 0.1, k_max_cell_factor = 2.0;
inline constexpr double k_min_scale = 1.0 / 1024.0, k_max_scale = 1024.0;
inline constexpr int k_max_texton_support = 4096;
// |origin| + size must stay below 2^46 pixels so that fixed-point centres (2P + 1) 2^15 and the reach
// around them fit an int64 with room to spare.
inline constexpr std::int64_t k_max_pixel_coordinate = std::int64_t(1) << 46;

// Everything the kernels and the reference need for one (model, parameters) pair.
struct TextonSetup {
  stex_texton_params params{};               // the kernel struct (104 bytes)
  std::vector<float> alpha_padded;           // channels planes of stride^2 floats, zero frame of 1
  std::vector<std::uint32_t> poisson_table;  // threshold table of the per-cell Poisson mean
  double lambda = 0.0;                       // intensity (impulses per exemplar pixel^2)
  double cell_mean = 0.0;                    // expected impulses per cell: lambda (A / (2^16 scale))^2
  std::int64_t cell_fix = 0;                 // A, the cell side in fixed units
  std::int64_t reach_back = 0, reach_fwd = 0;
  int channels = 0;
};

// Interpolation orders texton noise evaluates (S1 §10): 0 nearest, 1 bilinear, 3 cubic, 5 quintic B-spline.
inline bool valid_texton_order(int order) { return order == 0 || order == 1 || order == 3 || order == 5; }

// Checks a model's fields (channels 1..4, support 1..k_max_texton_support, order 0|1|3|5, alpha size, finite
// values). Throws stex::Error(Input) naming the field: a model that fails this is corrupt.
void validate_texton_model(const TextonModel& model);

// Checks the render parameters; throws stex::Error(Usage) naming the parameter.
void validate_render_params(const RenderParams& params);

// Builds the kernel struct, the padded alpha and the Poisson table. Validates model and parameters first.
TextonSetup make_texton_setup(const TextonModel& model, const RenderParams& params);

// Checks a region [x, x + width) x [y, y + height) of output pixels: width, height >= 1 and
// |x| + width, |y| + height < 2^46. Throws stex::Error(Usage).
void validate_region(std::int64_t x, std::int64_t y, std::int64_t width, std::int64_t height);

}  // namespace stex
