// LoadedModel (model/loaded_model.h): one read, one hash, one decode.
#include "model/loaded_model.h"

#include "runtime/model.h"

namespace stex {

std::unique_ptr<NoiseRenderer> LoadedModel::make_renderer(Context& ctx, const NoiseRendererOptions& options) const {
  return (kind ? *kind : kind_of(container, what)).make_renderer(ctx, decoded, options);
}

std::vector<SelftestRow> LoadedModel::selftest_rows(const RenderParams& params, const NoiseRendererOptions& options,
                                                    const DeviceInfo& device) const {
  return (kind ? *kind : kind_of(container, what)).selftest_rows(decoded, params, options, device);
}

bool LoadedModel::mappable() const {
  const TextonModel* t = as<TextonModel>();
  return t && t->order == 1;
}

bool LoadedModel::filterable() const { return summary.filters; }

LoadedModel make_loaded_model(ModelContainer container, const std::string& what, std::string sha256,
                              bool defer_unknown_kind) {
  LoadedModel m;
  m.what = what;
  m.kind = defer_unknown_kind ? find_kind(container.kind) : &kind_of(container, what);
  if (m.kind) {
    m.decoded = m.kind->decode(container, what);
    m.summary = m.kind->describe(m.decoded, container);
  }
  m.linear = model_is_linear(container);
  m.sha256 = std::move(sha256);
  m.container = std::move(container);
  return m;
}

LoadedModel load_model_file(const std::string& path, bool defer_unknown_kind) {
  std::string sha256;
  ModelContainer container = load_container(path, &sha256);
  return make_loaded_model(std::move(container), path, std::move(sha256), defer_unknown_kind);
}

}  // namespace stex
