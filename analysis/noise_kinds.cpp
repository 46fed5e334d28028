#include "analysis/noise_kinds.h"

#include "analysis/cs_spot_model.h"
#include "analysis/gabor_model.h"
#include "analysis/lrp.h"
#include "analysis/tb_model.h"
#include "runtime/cs_spot.h"
#include "runtime/error.h"
#include "runtime/gabor_renderer.h"
#include "runtime/lrp_renderer.h"
#include "runtime/tb.h"
#include "runtime/texton_renderer.h"

namespace stex {

std::vector<std::string> noise_kinds() { return {"texton", "lrp", "gabor", "cs-spot", "tb", "cs-tb"}; }

std::unique_ptr<NoiseRenderer> make_noise_renderer(Context& ctx, const ModelContainer& model,
                                                   const NoiseRendererOptions& options, const std::string& what) {
  // One line per kind.
  if (model.kind == "texton") return std::make_unique<TextonNoise>(ctx, texton_from_container(model, what), options);
  if (model.kind == "lrp") return std::make_unique<LrpRenderer>(ctx, lrp_from_container(model, what), options);
  if (model.kind == "gabor") return std::make_unique<GaborNoise>(ctx, gabor_from_container(model, what), options);
  if (model.kind == "cs-spot") return std::make_unique<CsSpotNoise>(ctx, cs_spot_from_container(model, what), options);
  if (model.kind == "tb" || model.kind == "cs-tb") return std::make_unique<TbNoise>(ctx, tb_from_container(model, what), options);
  std::string known;
  for (const std::string& k : noise_kinds()) known += (known.empty() ? "" : ", ") + k;
  throw Error(ErrorKind::Input, "model '" + what + "' is of kind '" + model.kind +
                                    "', which this stex cannot render (known kinds: " + known + ")");
}

bool model_is_linear(const ModelContainer& model) {
  const auto it = model.metadata.find("linear");
  return it != model.metadata.end() && it->is_boolean() && it->get<bool>();
}

std::string model_exemplar_name(const ModelContainer& model) {
  const auto ex = model.metadata.find("exemplar");
  if (ex == model.metadata.end() || !ex->is_object()) return "";
  const auto name = ex->find("name");
  return name != ex->end() && name->is_string() ? name->get<std::string>() : "";
}

}  // namespace stex
