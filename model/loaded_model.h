// A model file loaded once for rendering: the file is read once, its bytes hashed (the SHA-256 that renders
// record as stex:model_sha256 and that keys the service's caches), the container decoded and validated by
// its kind's codec once, and the decoded model kept for every renderer built from it. `stex render`, the
// farm path, `stex serve` and the C API all hold models as LoadedModel.
#pragma once
#include <any>
#include <memory>
#include <string>
#include <vector>

#include "model/container.h"
#include "model/kinds.h"
#include "runtime/context.h"
#include "runtime/noise_renderer.h"

namespace stex {

struct LoadedModel {
  std::string what;           // the file's path, or a label for a model built in memory (names it in messages)
  ModelContainer container;   // as stored
  std::string sha256;         // of the file's bytes; "" for a model built in memory
  const KindEntry* kind = nullptr;  // null only for an unknown kind loaded with defer_unknown_kind
  std::any decoded;           // the kind's model struct M, as std::shared_ptr<const M> (model/kinds.h)
  NoiseModelSummary summary;  // channels, mean, linear
  bool linear = false;        // renders are in linear light (model_is_linear): integer outputs encode sRGB

  // The decoded model when the kind's struct is M (texton-only features: filtering, point and surface
  // queries, the host comparison modes), else nullptr.
  template <class M>
  const M* as() const {
    const auto* p = std::any_cast<std::shared_ptr<const M>>(&decoded);
    return p ? p->get() : nullptr;
  }
  // Minified views can be filtered: the kind's renderer reads RenderParams::filter (NoiseModelSummary::filters:
  // texton and mix by the box prefilter, gabor, lrp, cs-rpn but phasor).
  bool filterable() const;
  // The models whose minified views filter, for messages and help texts (docs/filtering.md).
  static constexpr const char* filtering_kinds = "texton, gabor, lrp, mix and cs-rpn (not phasor) models";
  // Camera views and UV maps (filtered per pixel, S1 §5) apply: a texton model of order 1.
  bool mappable() const;
  // How a filtered render filters (the stex:filter attribute): "box-prefilter" (a texton's or a mix's
  // minified flat view: the texton convolved with the pixel's box), "mip-aniso" (S1 §5's MIP pyramid and anisotropic probes: a
  // texton's camera view or UV map) or "gaussian-footprint" (the pixel's Gaussian footprint in closed form:
  // each kernel convolved with it, gabor; each cosine faded by its transfer, lrp and cs-rpn).
  const char* filter_name(bool mapped = false) const {
    if (as<TextonModel>()) return mapped ? "mip-aniso" : "box-prefilter";
    return container.kind == kinds::mix ? "box-prefilter" : "gaussian-footprint";
  }
  // The kind's renderer on `ctx`, from the decoded model.
  std::unique_ptr<NoiseRenderer> make_renderer(Context& ctx, const NoiseRendererOptions& options = {}) const;
  // The self-test rows of a render with these parameters and options on `device` (KindEntry::selftest_rows).
  std::vector<SelftestRow> selftest_rows(const RenderParams& params, const NoiseRendererOptions& options,
                                         const DeviceInfo& device) const;
};

// Reads, hashes and decodes a model file of any kind (Error(Input) for a missing, corrupt, foreign or
// invalid file, naming the problem). With `defer_unknown_kind`, a well-formed file of a kind this stex does
// not know loads with `kind` null and make_renderer raises that error (`stex render` checks its options
// before it, as it did before the kind table decoded at load).
LoadedModel load_model_file(const std::string& path, bool defer_unknown_kind = false);

// A model built in memory (or changed after loading: `sha256` keeps the file's), decoded once.
LoadedModel make_loaded_model(ModelContainer container, const std::string& what, std::string sha256 = "",
                              bool defer_unknown_kind = false);

}  // namespace stex
