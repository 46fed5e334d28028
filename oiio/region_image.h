// A region of a model's unbounded texture seen as a tiled, optionally MIP-mapped image: what the OpenImageIO
// reader stex.imageio.so (oiio/stex_imageio.cpp) serves, kept free of OIIO so it can be tested directly.
//
// Level 0 is `stex render MODEL --size WxH --origin X,Y --scale S --seed .. --mni .. --cell ..` (with --filter
// when S < 1 and the model filters): its tiles are the same bits. Level k >= 1 (MIP=1) is the same
// realisation at scale S / 2^k over output pixels [floor(X / 2^k), ..) (exactly nested when X and Y are
// multiples of 2^k), max(1, W >> k) x max(1, H >> k) pixels:
//   - texton models of order 1: S1 §5's filtered render, `stex render --scale S/2^k --filter` bit for bit;
//   - other kinds (no filtering yet, issue 31): the box mean of the 2^k x 2^k level-0 pixels under each
//     pixel (a box-filtered pyramid, as maketx's default makes, without a base image), summed in double in
//     row-major order, so a tile's bits never depend on how it is computed;
//   - FILTER=0: `stex render --scale S/2^k` point-sampled (aliases).
// Renders go to one device per process (STEX_DEVICE, PoCL's kernel cache in stex's usual place), behind one
// lock: OIIO's ImageCache and TextureSystem read tiles from many threads.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "model/loaded_model.h"
#include "model/render_request.h"
#include "oiio/region_options.h"

namespace stex::oiio {

enum class LevelPath { Plain, Filtered, Box };

struct RegionLevel {
  int width = 0, height = 0;  // pixels of this level
  std::int64_t x = 0, y = 0;  // its output pixel at (0, 0), at its scale
  RenderParams params;        // scale = S / 2^k
  int shift = 0;              // k
  LevelPath path = LevelPath::Plain;
};

// Box levels: a tile reads at most this many level-0 pixels (checked at construction for every level).
inline constexpr std::int64_t k_max_box_footprint = std::int64_t(1) << 28;

class RegionImage {
 public:
  // Loads the model (Error(Input)), checks the options against it and builds the levels (Error(Usage),
  // Error(Limit) for a box level whose tiles would read more than k_max_box_footprint pixels).
  explicit RegionImage(RegionOptions options);

  const RegionOptions& options() const { return options_; }
  const LoadedModel& model() const { return *model_; }
  int channels() const { return channels_; }
  const std::vector<RegionLevel>& levels() const { return levels_; }

  // Renders the tile whose top-left pixel is (tx, ty) (multiples of the tile size, inside the level) into
  // `out`, tile x tile x channels floats, interleaved; pixels past the level's edge are 0. Returns the
  // strategy used. Thread-safe. Errors: stex::Error (device, limits), as `stex render` raises them.
  std::string render_tile(int level, int tx, int ty, float* out) const;

  // The provenance attributes of `stex render` for this level (render_metadata), with `strategy`.
  std::vector<std::pair<std::string, std::string>> metadata(int level, const std::string& strategy) const;

 private:
  RenderedPixels render(const RenderRequest& r) const;
  RenderRequest request(const RegionLevel& l, std::int64_t x, std::int64_t y, int w, int h) const;

  RegionOptions options_;
  std::shared_ptr<const LoadedModel> model_;
  int channels_ = 0;
  std::vector<RegionLevel> levels_;
};

}  // namespace stex::oiio
