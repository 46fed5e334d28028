// The provenance attributes every rendered image carries (`stex render`'s single images, and the tiles and
// regions of `stex serve`, which must be the same bytes as the CLI's for the same parameters): one function,
// so the two writers cannot drift apart.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "runtime/texton_params.h"

namespace stex {

struct RenderProvenance {
  std::string model_sha256;   // of the model file
  std::string mode;           // "texton", "adsn", ... or the model's kind
  std::string kind;           // the model's kind
  std::string strategy;       // the strategy actually used
  std::string exemplar_name;  // model_exemplar_name(container)
  RenderParams params;
  std::int64_t x = 0, y = 0;  // origin
  std::string filter = "none";  // stex:filter: LoadedModel::filter_name() of a filtered render
  std::string camera, uv_map, mix_map;  // "" when not used
};

// The string attributes of WriteOptions::metadata (analysis/image_io.h), in a fixed order.
std::vector<std::pair<std::string, std::string>> render_metadata(const RenderProvenance& p);

}  // namespace stex
