// The kind-neutral render parameters and region of every model kind: what a render of any kind is a pure
// function of, besides the model and the pixel coordinates. Each kind documents which fields it reads (seed
// and scale: every kind; mni and cell_factor: the kinds driven by a Poisson process).
#pragma once
#include <cstdint>

namespace stex {

// Parameters of one render. Documented once here; `stex render --help` and the README draw on it.
struct RenderParams {
  // Mean number of impacts per point (S1 §3.3): for texton noise lambda = mni / r^2 with r = support + order
  // (the width of the texton's support for every order). In (0, 10000].
  double mni = 30.0;
  // Cell side of the grid Poisson process as a fraction c of the kernel's size (S1 §8: 0.6). In [0.1, 2].
  // Changing it changes the realisation, not the statistics.
  double cell_factor = 0.6;
  // 64-bit seed of the counter-based RNG: the impulses of a cell are a pure function of (seed, cell).
  std::uint64_t seed = 0;
  // Output pixels per exemplar pixel, in [1/1024, 1024]. Below 1 point-sampled renders alias; the filtered
  // texton renderer (runtime/texton_filter.h, S1 §5) does not.
  double scale = 1.0;
  // Footprint filtering of a minified view (scale < 1), for the kinds whose renderer filters in closed form
  // (gabor: each kernel convolved with the pixel's footprint, runtime/gabor_params.h; lrp: each cosine faded
  // by the footprint's transfer, runtime/lrp_model.h). No effect at scale >= 1 and on the other kinds;
  // texton models filter through their own renderer (model/render_request.h).
  bool filter = false;

  // Field by field, exactly (a renderer rebuilds its parameter-dependent tables when they differ).
  bool operator==(const RenderParams& o) const {
    return mni == o.mni && cell_factor == o.cell_factor && seed == o.seed && scale == o.scale && filter == o.filter;
  }
  bool operator!=(const RenderParams& o) const { return !(*this == o); }
};

// Limits checked by validate_render_params (exposed for tests and the CLI's messages).
inline constexpr double k_max_mni = 10000.0;
inline constexpr double k_min_cell_factor = 0.1, k_max_cell_factor = 2.0;
inline constexpr double k_min_scale = 1.0 / 1024.0, k_max_scale = 1024.0;
// |origin| + size must stay below 2^46 pixels so that fixed-point centres (2P + 1) 2^15 and the reach
// around them fit an int64 with room to spare.
inline constexpr std::int64_t k_max_pixel_coordinate = std::int64_t(1) << 46;

// Checks the render parameters against the limits above; throws stex::Error(Usage) naming the parameter.
void validate_render_params(const RenderParams& params);

// Checks a region [x, x + width) x [y, y + height) of output pixels: width, height >= 1 and
// |x| + width, |y| + height < 2^46. Throws stex::Error(Usage).
void validate_region(std::int64_t x, std::int64_t y, std::int64_t width, std::int64_t height);

}  // namespace stex
