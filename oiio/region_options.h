// The options of a model opened as an image (stex.imageio.so, docs/oiio-plugin.md): the file name carries
// them after a '?', the way OpenImageIO's own `null` reader does (`gravel.stex?RES=8192x8192&SEED=3`), and
// they say which region of the unbounded texture the image is and how it is rendered. Parsed without OIIO,
// so the tests and the fuzzer-free unit tests check the grammar directly.
#pragma once
#include <cstdint>
#include <string>

#include "core/render_params.h"

namespace stex::oiio {

struct RegionOptions {
  std::string path;                // the model file (the name before '?')
  int width = 4096, height = 4096;  // RES=WxH: level 0's size in output pixels
  std::int64_t x = 0, y = 0;        // ORIGIN=X,Y: the output pixel at the image's (0, 0)
  int tile = 256;                   // TILE=T: square tiles of T x T pixels
  bool mip = false;                 // MIP=1: MIP levels 1.. (level k: scale 2^-k of the same realisation)
  bool filter = true;               // FILTER=0: every level point-sampled at its scale (aliases)
  RenderParams params;              // SEED, MNI, CELL, SCALE (level 0's scale)
  bool mni_given = false, cell_given = false;  // MNI / CELL in the name (refused for kinds that do not read them)
  std::string strategy = "auto";    // STRATEGY=name: the kind's evaluation strategy (never changes the bits)
};

// Limits of the options (checked by parse_region_options).
inline constexpr int k_max_region_side = 1 << 20;  // RES: each side at most 2^20 pixels
inline constexpr int k_min_tile = 8, k_max_tile = 4096;

// Splits `name` at its first '?' and parses the '&'-separated KEY=VALUE options (keys case-insensitive):
// RES, ORIGIN, SEED, MNI, CELL, SCALE, TILE, MIP, FILTER, STRATEGY. Error(Usage) naming the option for an
// unknown key, a repeated key, a malformed or out-of-range value; the region and parameters are checked with
// validate_region / validate_render_params.
RegionOptions parse_region_options(const std::string& name);

// The model file's path of `name` (the part before the first '?').
std::string region_model_path(const std::string& name);

}  // namespace stex::oiio
