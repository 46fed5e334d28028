// A model region as a tiled MIP-mapped image. See region_image.h.
#include "oiio/region_image.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <list>
#include <mutex>

#include "analysis/render_metadata.h"
#include "core/error.h"
#include "runtime/context.h"
#include "runtime/device.h"
#include "runtime/mix_model.h"

namespace stex::oiio {

namespace {

// The process's device: one context (STEX_DEVICE, else the default device) and the renderers of the models
// opened, by the model file's SHA-256 (a model opened twice shares them; at most k_models kept, least recently
// used dropped). One lock serialises the renders: the context's queue and every renderer are single-threaded.
// Never destroyed: a host application may unload plugins or exit while OpenCL is being torn down.
class DeviceHost {
 public:
  static DeviceHost& instance() {
    static DeviceHost* host = new DeviceHost();
    return *host;
  }

  RenderedPixels render(const LoadedModel& model, const RenderRequest& r) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!ctx_) {
      configure_kernel_cache();  // PoCL's cache in stex's usual place (the plugin's first render)
      const char* spec = std::getenv("STEX_DEVICE");
      ctx_ = Context::create(spec ? spec : "");
    }
    auto it = std::find_if(renderers_.begin(), renderers_.end(),
                           [&](const auto& e) { return e.first == model.sha256; });
    if (it == renderers_.end()) {
      renderers_.emplace_front(model.sha256, std::make_unique<ModelRenderers>(*ctx_));
      if (renderers_.size() > k_models) renderers_.pop_back();
      it = renderers_.begin();
    } else if (it != renderers_.begin()) {
      renderers_.splice(renderers_.begin(), renderers_, it);
      it = renderers_.begin();
    }
    return it->second->render(model, r);
  }

 private:
  static constexpr std::size_t k_models = 16;
  std::mutex mutex_;
  std::unique_ptr<Context> ctx_;
  std::list<std::pair<std::string, std::unique_ptr<ModelRenderers>>> renderers_;
};

std::int64_t floor_shift(std::int64_t v, int k) {
  const std::int64_t d = std::int64_t(1) << k;
  return v >= 0 ? v / d : -((-v + d - 1) / d);
}

}  // namespace

RegionImage::RegionImage(RegionOptions options) : options_(std::move(options)) {
  model_ = std::make_shared<const LoadedModel>(load_model_file(options_.path));
  channels_ = model_->summary.channels;
  if ((options_.mni_given || options_.cell_given) && !model_->summary.poisson)
    throw Error(ErrorKind::Usage, std::string(options_.mni_given ? "MNI" : "CELL") + " does not apply to a " +
                                      model_->container.kind +
                                      " model: only the kinds driven by a Poisson impulse process read it (texton, "
                                      "gabor, mix, cs-rpn's gabor and phasor variants)");
  const bool filterable = model_->filterable();
  const RegionOptions& o = options_;

  int count = 1;
  if (o.mip) {
    const int side = std::max(o.width, o.height);
    while ((side >> count) >= 1 && o.params.scale / double(std::int64_t(1) << count) >= k_min_scale) ++count;
  }
  for (int k = 0; k < count; ++k) {
    RegionLevel l;
    l.shift = k;
    l.width = std::max(1, o.width >> k);
    l.height = std::max(1, o.height >> k);
    l.x = floor_shift(o.x, k);
    l.y = floor_shift(o.y, k);
    l.params = o.params;
    l.params.scale = o.params.scale / double(std::int64_t(1) << k);
    if (k == 0)
      l.path = o.filter && filterable && o.params.scale < 1.0 ? LevelPath::Filtered : LevelPath::Plain;
    else if (!o.filter)
      l.path = LevelPath::Plain;
    else
      l.path = filterable ? LevelPath::Filtered : LevelPath::Box;
    if (l.path == LevelPath::Box) {
      const std::int64_t fw = std::int64_t(std::min(o.tile, l.width)) << k;
      const std::int64_t fh = std::int64_t(std::min(o.tile, l.height)) << k;
      if (fw * fh > k_max_box_footprint)
        throw Error(ErrorKind::Limit,
                    "MIP level " + std::to_string(k) + " of a " + model_->container.kind +
                        " model is the box mean of level 0: each of its tiles would read " + std::to_string(fw) +
                        "x" + std::to_string(fh) + " pixels of level 0 (at most 2^28); use a smaller RES or TILE, "
                        "or FILTER=0 (point-sampled levels)");
    }
    validate_render_request(*model_, request(l, l.x, l.y, l.width, l.height));
    levels_.push_back(l);
  }
}

RenderRequest RegionImage::request(const RegionLevel& l, std::int64_t x, std::int64_t y, int w, int h) const {
  return RenderRequest::region(x, y, w, h, l.params, options_.strategy,
                               l.path == LevelPath::Filtered ? FilterMode::On : FilterMode::Off);
}

RenderedPixels RegionImage::render(const RenderRequest& r) const { return DeviceHost::instance().render(*model_, r); }

std::string RegionImage::render_tile(int level, int tx, int ty, float* out) const {
  if (level < 0 || level >= int(levels_.size())) throw Error(ErrorKind::Usage, "no MIP level " + std::to_string(level));
  const RegionLevel& l = levels_[std::size_t(level)];
  const int t = options_.tile, c = channels_;
  if (tx < 0 || ty < 0 || tx >= l.width || ty >= l.height || tx % t != 0 || ty % t != 0)
    throw Error(ErrorKind::Usage, "tile (" + std::to_string(tx) + ", " + std::to_string(ty) + ") is not a tile of level " +
                                      std::to_string(level));
  const int tw = std::min(t, l.width - tx), th = std::min(t, l.height - ty);
  std::fill(out, out + std::size_t(t) * std::size_t(t) * std::size_t(c), 0.0f);

  if (l.path != LevelPath::Box) {
    const RenderedPixels px = render(request(l, l.x + tx, l.y + ty, tw, th));
    for (int j = 0; j < th; ++j)
      std::memcpy(out + std::size_t(j) * t * c, px.pixels.data() + std::size_t(j) * tw * c, sizeof(float) * tw * c);
    return px.strategy;
  }

  // Box: level-k pixel (i, j) is the mean of level-0 pixels [(X + i) 2^k, (X + i + 1) 2^k) x [..), summed
  // row by row (rows ascending, columns ascending), whatever the strip height.
  const RegionLevel& base = levels_[0];
  const int k = l.shift, side = 1 << k;
  const std::int64_t bx = (l.x + tx) * side, by = (l.y + ty) * side;
  const int bw = tw << k, bh = th << k;
  const int strip = std::max(1, std::min(bh, int((std::int64_t(1) << 22) / bw)));
  std::vector<double> acc(std::size_t(tw) * th * c, 0.0);
  std::string strategy;
  for (int r0 = 0; r0 < bh; r0 += strip) {
    const int rows = std::min(strip, bh - r0);
    const RenderedPixels px = render(request(base, bx, by + r0, bw, rows));
    strategy = px.strategy;
    for (int r = 0; r < rows; ++r) {
      double* row = acc.data() + std::size_t((r0 + r) >> k) * tw * c;
      const float* src = px.pixels.data() + std::size_t(r) * bw * c;
      for (int i = 0; i < bw; ++i)
        for (int ch = 0; ch < c; ++ch) row[std::size_t(i >> k) * c + ch] += double(src[std::size_t(i) * c + ch]);
    }
  }
  const double inv = 1.0 / double(std::int64_t(side) * side);
  for (int j = 0; j < th; ++j)
    for (int i = 0; i < tw * c; ++i)
      out[std::size_t(j) * t * c + i] = float(acc[std::size_t(j) * tw * c + i] * inv);
  return "box-mean of " + strategy;
}

std::vector<std::pair<std::string, std::string>> RegionImage::metadata(int level, const std::string& strategy) const {
  const RegionLevel& l = levels_.at(std::size_t(level));
  RenderProvenance p;
  p.model_sha256 = model_->sha256;
  p.mode = model_->container.kind;
  p.kind = model_->container.kind;
  p.strategy = strategy;
  p.exemplar_name = model_exemplar_name(model_->container);
  p.params = l.params;
  p.x = l.x;
  p.y = l.y;
  p.filter = l.path == LevelPath::Filtered ? model_->filter_name() : "none";
  if (const auto* mix = model_->as<MixModel>()) p.mix_map = mix_map_spec(mix->map);
  auto md = render_metadata(p);
  md.emplace_back("stex:mip", l.path == LevelPath::Box ? "box" : l.path == LevelPath::Filtered ? "filtered" : "none");
  return md;
}

}  // namespace stex::oiio
