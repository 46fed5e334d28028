// The kind table: one entry per model kind stex renders, and the kinds' names. Every client (`stex render`,
// the farm layer, `stex serve`, the C API) reaches a kind through this table, never by its name string:
// adding a kind is its own files (model struct and renderer in runtime/, codec in model/, analysis in
// analysis/) plus one entry in model/kinds.cpp (docs/ARCHITECTURE.md, "Adding a kind").
#pragma once
#include <any>
#include <memory>
#include <string>
#include <vector>

#include "model/container.h"
#include "runtime/context.h"
#include "runtime/noise_renderer.h"
#include "runtime/selftest.h"
#include "runtime/texton_params.h"

namespace stex {

// The names stored in a model file's header and metadata.
namespace kinds {
inline constexpr char texton[] = "texton";
inline constexpr char lrp[] = "lrp";
inline constexpr char gabor[] = "gabor";
inline constexpr char mix[] = "mix";
inline constexpr char cs_spot[] = "cs-spot";
inline constexpr char tb[] = "tb";
inline constexpr char cs_tb[] = "cs-tb";
inline constexpr char cs_rpn[] = "cs-rpn";
}  // namespace kinds

// What a stored model of any kind renders, known without a device.
struct NoiseModelSummary {
  int channels = 0;         // 1..4
  std::vector<float> mean;  // per channel: the render's mean (mix: at rho = 1/2)
  bool linear = false;      // renders are in linear light (model_is_linear)
  // Renders read RenderParams::mni and cell_factor: the kinds driven by a Poisson impulse process (texton,
  // gabor, mix, cs-rpn's gabor and phasor variants). Clients refuse --mni / --cell for the others.
  bool poisson = false;
  // Minified views (scale < 1) are filtered by the kind's own renderer when asked (RenderParams::filter):
  // texton and mix by the box prefilter, gabor, lrp and cs-rpn in closed form (docs/filtering.md).
  bool filters = false;
};

// One kind. `decode` runs the kind's codec (model/codecs.h), which validates every field (Error(Input) naming
// a bad field), and returns the kind's model struct M as std::shared_ptr<const M> in a std::any; `describe`
// and `make_renderer` take that decoded model, so a model is decoded once however often it is rendered
// (model/loaded_model.h).
struct KindEntry {
  const char* name;
  std::any (*decode)(const ModelContainer& model, const std::string& what);
  NoiseModelSummary (*describe)(const std::any& decoded, const ModelContainer& model);
  // Error(Usage) for options the kind does not take; Error(Device) on device failure.
  std::unique_ptr<NoiseRenderer> (*make_renderer)(Context& ctx, const std::any& decoded,
                                                  const NoiseRendererOptions& options);
  // The known-answer self-test rows (runtime/selftest.h) of the path its renderer takes on `device` with
  // these parameters and options (texton: the strategy and order; tb / cs-tb: aligned, sub-pixel or scaled;
  // cs-spot: lattice or general; cs-rpn: the variant; mix: the order). Renders pass them to ensure_selftest.
  std::vector<SelftestRow> (*selftest_rows)(const std::any& decoded, const RenderParams& params,
                                            const NoiseRendererOptions& options, const DeviceInfo& device);
};

// Every kind, in the order they were added ("texton", ...).
const std::vector<KindEntry>& kind_table();
// The entry of `name`, or nullptr.
const KindEntry* find_kind(const std::string& name);
// The entry of the container's kind; Error(Input) naming the known kinds for an unknown one.
const KindEntry& kind_of(const ModelContainer& model, const std::string& what = "model");

// The kinds' names, in table order.
std::vector<std::string> noise_kinds();

// Decodes the container with its kind's codec and builds its renderer on `ctx` (a model rendered more than
// once: model/loaded_model.h, decoded once).
std::unique_ptr<NoiseRenderer> make_noise_renderer(Context& ctx, const ModelContainer& model,
                                                   const NoiseRendererOptions& options = {},
                                                   const std::string& what = "model");

// Decodes the container and returns its kind's self-test rows for a render (KindEntry::selftest_rows; a model
// rendered more than once: LoadedModel::selftest_rows, decoded once).
std::vector<SelftestRow> selftest_rows_for(const ModelContainer& model, const RenderParams& params,
                                           const NoiseRendererOptions& options, const DeviceInfo& device,
                                           const std::string& what = "model");

// Decodes the container with its kind's codec, validating every field, without building a renderer (no
// device needed; = describe_noise_model, result dropped). The fuzz target and the damage sweep of the model
// loader go through it, so every registered kind's codec is covered.
void check_model(const ModelContainer& model, const std::string& what = "model");

// What a stored model of any kind renders (the same checks as make_noise_renderer). The C API loads every
// kind through it.
NoiseModelSummary describe_noise_model(const ModelContainer& model, const std::string& what = "model");

// Whether renders of this model are in linear light (metadata "linear": true; absent means false): integer
// outputs are then encoded to sRGB.
bool model_is_linear(const ModelContainer& model);
// The exemplar's file name recorded in the metadata ("exemplar": {"name": ...}), or "".
std::string model_exemplar_name(const ModelContainer& model);

}  // namespace stex
