// The provenance attributes of rendered images (render_metadata.h).
#include "analysis/render_metadata.h"

#include <cinttypes>
#include <cstdio>

namespace stex {

std::vector<std::pair<std::string, std::string>> render_metadata(const RenderProvenance& p) {
  char origin[64], scale[64], mni[64], cell[64];
  std::snprintf(origin, sizeof origin, "%" PRId64 ",%" PRId64, p.x, p.y);
  std::snprintf(scale, sizeof scale, "%.17g", p.params.scale);
  std::snprintf(mni, sizeof mni, "%.17g", p.params.mni);
  std::snprintf(cell, sizeof cell, "%.17g", p.params.cell_factor);
  return {{"Software", std::string("stex ") + STEX_VERSION_STRING},
          {"stex:version", STEX_VERSION_STRING},
          {"stex:model_sha256", p.model_sha256},
          {"stex:mode", p.mode},
          {"stex:seed", std::to_string(p.params.seed)},
          {"stex:mni", mni},
          {"stex:origin", origin},
          {"stex:scale", scale},
          {"stex:cell", cell},
          {"stex:strategy", p.strategy},
          {"stex:kind", p.kind},
          {"stex:filter", p.filter},
          {"stex:camera", p.camera},
          {"stex:uv_map", p.uv_map},
          {"stex:mix_map", p.mix_map},
          {"ImageDescription", "stex " + p.mode + " render of " + p.exemplar_name}};
}

}  // namespace stex
