// One render of a loaded model on a device (model/render_request.h).
#include "model/render_request.h"

#include "core/error.h"

namespace stex {

void validate_render_region(const RenderRequest& r) {
  if (r.width < 1 || r.height < 1) throw Error(ErrorKind::Usage, "the region must be at least 1x1 pixels");
  validate_region(r.x, r.y, r.width, r.height);
  validate_render_params(r.params);
}

void validate_render_request(const LoadedModel& model, const RenderRequest& r) {
  validate_render_region(r);
  const TextonModel* t = model.as<TextonModel>();
  if (r.filter == FilterMode::On && !model.filterable())
    throw Error(ErrorKind::Usage, "filtering applies to " + std::string(LoadedModel::filtering_kinds) + "; '" +
                                      model.what + "' is a " + model.container.kind + " model");
  if (r.mapped() && !model.mappable())
    throw Error(ErrorKind::Usage, t ? "a camera or a UV map (filtered, S1 §5) needs a bilinear texton (order 1); "
                                      "this model has order " + std::to_string(t->order)
                                    : "a camera and a UV map apply to texton models of order 1; '" + model.what +
                                          "' is a " + model.container.kind + " model");
  if (r.camera && r.uv_map) throw Error(ErrorKind::Usage, "a camera and a UV map exclude each other");
  if (r.uv_map && (r.uv_map->width != r.width || r.uv_map->height != r.height))
    throw Error(ErrorKind::Usage, "the UV map's size differs from the region's");
}

bool uses_filter(const LoadedModel& model, const RenderRequest& r) {
  if (!model.filterable() || r.filter == FilterMode::Off) return false;
  // Minified views filter; so do a texton's camera views and UV maps (S1 §5), and its magnified views at
  // --filter (the unfiltered bits: level 0, one probe).
  if (!model.mappable() && !(r.params.scale < 1.0)) return false;
  return r.filter == FilterMode::On || r.mapped() || r.params.scale < 1.0;
}

RenderedPixels ModelRenderers::render(const LoadedModel& model, const RenderRequest& r) {
  validate_render_request(model, r);
  RenderedPixels out;
  out.width = r.width;
  out.height = r.height;
  out.filtered = uses_filter(model, r);
  // A texton's camera or UV-map view: S1 §5's MIP pyramid and probes (order 1). Flat views, filtered or not,
  // take the kind's renderer, which reads RenderParams::filter (texton and mix: the box prefilter).
  if (r.mapped()) {
    if (!filtered_) filtered_ = std::make_unique<FilteredTextonRenderer>(ctx_, *model.as<TextonModel>());
    out.selftest_ran = ensure_selftest(ctx_, {filtered_selftest_row(r.mapped())});
    out.channels = filtered_->channels();
    if (r.camera) {
      out.pixels = filtered_->render_camera(r.params, *r.camera, r.x, r.y, r.width, r.height, &out.device_ms, 0,
                                            out.filtered);
    } else {
      out.pixels = filtered_->render_uv_map(r.params, *r.uv_map, &out.device_ms, 0, out.filtered);
    }
    out.strategy = out.filtered ? "filtered" : (r.camera ? "camera-unfiltered" : "uv-map-unfiltered");
    return out;
  }
  // The kind's renderer; a kind that filters reads params.filter (NoiseModelSummary::filters; texton too).
  RenderParams params = r.params;
  params.filter = out.filtered;
  std::unique_ptr<NoiseRenderer>& renderer = plain_[r.options.strategy];
  if (!renderer) renderer = model.make_renderer(ctx_, r.options);
  const auto key = std::make_tuple(params.scale, params.filter, r.options.strategy);
  auto rows = rows_.find(key);
  if (rows == rows_.end()) rows = rows_.emplace(key, model.selftest_rows(params, r.options, ctx_.info())).first;
  out.selftest_ran = ensure_selftest(ctx_, rows->second);
  out.channels = renderer->channels();
  out.pixels.resize(std::size_t(r.width) * std::size_t(r.height) * std::size_t(out.channels));
  const NoiseRenderStats stats = renderer->render(params, r.x, r.y, r.width, r.height, out.pixels.data());
  out.strategy = stats.strategy;
  out.device_ms = stats.device_ms;
  return out;
}

}  // namespace stex
