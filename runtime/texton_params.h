// Texton noise: the render parameters (core/render_params.h) translated into the kernel struct stex_texton_params
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

#include "core/render_params.h"
#include "kernels/shared/texton.h"
#include "runtime/model.h"

namespace stex {

// Largest texton support s checked by validate_texton_model.
inline constexpr int k_max_texton_support = 4096;

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
  // Output pixel P is evaluated at P + pixel_shift on both axes (the box prefilter's table starts that many
  // pixels before the filtered texton: runtime/texton_filter.h); 0 otherwise.
  std::int64_t pixel_shift = 0;
};

// Interpolation orders texton noise evaluates (S1 §10): 0 nearest, 1 bilinear, 3 cubic, 5 quintic B-spline.
inline bool valid_texton_order(int order) { return order == 0 || order == 1 || order == 3 || order == 5; }

// Checks a model's fields (channels 1..4, support 1..k_max_texton_support, order 0|1|3|5, alpha size, finite
// values). Throws stex::Error(Input) naming the field: a model that fails this is corrupt.
void validate_texton_model(const TextonModel& model);

// Builds the kernel struct, the padded alpha and the Poisson table. Validates model and parameters first.
TextonSetup make_texton_setup(const TextonModel& model, const RenderParams& params);

}  // namespace stex
