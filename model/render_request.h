// One render of a loaded model on a device: the request (region, parameters, renderer options, filter,
// camera, UV map) and the renderers that serve it. `stex render` (a single image) and `stex serve` (tiles and
// regions) both render through ModelRenderers, so a tile and the CLI's image of the same request are made by
// the same code: the kind's NoiseRenderer (model/kinds.h) or, for texton models of order 1, the filtered
// evaluation of S1 §5 (runtime/texton_filter.h), each after the known-answer self-test of its path
// (runtime/selftest.h). Clients translate their options (CLI flags, URL query) into a RenderRequest and check
// them with their own wording first; validate_render_request is the shared last line.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "model/loaded_model.h"
#include "runtime/context.h"
#include "runtime/noise_renderer.h"
#include "runtime/selftest.h"
#include "runtime/texton_filter.h"
#include "runtime/texton_params.h"

namespace stex {

// Auto: filtered when the model is filterable and the view minifies (scale < 1) or is mapped (camera, UV map).
enum class FilterMode { Auto, On, Off };

struct RenderRequest {
  std::int64_t x = 0, y = 0;  // top-left output pixel (a camera view's pixel origin)
  int width = 0, height = 0;  // with a UV map: the map's size
  RenderParams params;        // seed, MNI, cell factor, scale (output pixels per exemplar pixel)
  NoiseRendererOptions options;             // texton: the strategy
  FilterMode filter = FilterMode::Auto;
  std::optional<PerspectiveCamera> camera;  // texton models of order 1: a perspective view of the plane
  const UvMap* uv_map = nullptr;            // texton models of order 1: every pixel's plane point (not owned)

  bool mapped() const { return camera.has_value() || uv_map != nullptr; }

  // The region [x, x + width) x [y, y + height) with these parameters, strategy and filter mode.
  static RenderRequest region(std::int64_t x, std::int64_t y, int width, int height, const RenderParams& params,
                              const std::string& strategy, FilterMode filter) {
    RenderRequest r;
    r.x = x;
    r.y = y;
    r.width = width;
    r.height = height;
    r.params = params;
    r.options.strategy = strategy;
    r.filter = filter;
    return r;
  }
};

// Error(Usage): the region (at least 1x1, validate_region) and the parameters (validate_render_params).
void validate_render_region(const RenderRequest& r);
// validate_render_region, and Error(Usage) for a filter on a model that does not filter, a camera or UV map
// on a model that is not a texton model of order 1, a camera with a UV map, a UV map whose size is not the
// region's.
void validate_render_request(const LoadedModel& model, const RenderRequest& r);

// Whether the request is filtered: S1 §5's renderer (texton) or the kind's closed form (gabor, lrp,
// cs-rpn).
bool uses_filter(const LoadedModel& model, const RenderRequest& r);

struct RenderedPixels {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;  // width * height * channels, row-major, channels interleaved
  std::string strategy;       // "splat", "gather", ..., "filtered", "camera-unfiltered", "uv-map-unfiltered"
  double device_ms = 0.0;
  bool filtered = false;
  std::vector<SelftestResult> selftest_ran;  // the self-test rows checked by this render (not cached before)
};

// The renderers of one loaded model on one context, built on first use and kept (a service renders many
// tiles of a model; a new model file gets a new ModelRenderers). Not thread-safe: one per device thread.
class ModelRenderers {
 public:
  explicit ModelRenderers(Context& ctx) : ctx_(ctx) {}
  // Validates, passes the self-test gate of the path (Error(Device) if its bits differ on this device), renders.
  RenderedPixels render(const LoadedModel& model, const RenderRequest& r);

 private:
  Context& ctx_;
  std::map<std::string, std::unique_ptr<NoiseRenderer>> plain_;  // by the options' strategy
  std::unique_ptr<FilteredTextonRenderer> filtered_;
  // The self-test rows of plain renders: tb's and cs-spot's paths depend on the scale, gabor's on the filter.
  std::map<std::tuple<double, bool, std::string>, std::vector<SelftestRow>> rows_;  // by (scale, filter, strategy)
};

}  // namespace stex
