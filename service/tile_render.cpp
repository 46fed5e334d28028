// Tile and region rendering and encoding with the CLI's bits (service/tile_render.h).
#include "service/tile_render.h"

#include <unistd.h>

#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "analysis/mix.h"
#include "analysis/render_metadata.h"
#include "core/error.h"

namespace stex::service {

void validate_request(const ServedModel& model, const TileRequest& r) {
  validate_render_region(r);
  if (r.format != "png" && r.format != "exr")
    throw Error(ErrorKind::Usage, "format must be png or exr, got '" + r.format + "'");
  if (r.format == "png" && r.bits != 0 && r.bits != 8 && r.bits != 16)
    throw Error(ErrorKind::Usage, "bits must be 8 or 16 for png, got " + std::to_string(r.bits));
  if (r.format == "exr" && r.bits != 0 && r.bits != 16 && r.bits != 32)
    throw Error(ErrorKind::Usage, "bits must be 16 (half) or 32 for exr, got " + std::to_string(r.bits));
  if (r.filter == FilterMode::On && !model.filterable()) {
    const TextonModel* t = model.as<TextonModel>();
    throw Error(ErrorKind::Usage, "filter=on applies to " + std::string(LoadedModel::filtering_kinds) + " ('" + model.name +
                                      "' is " +
                                      (t ? "a texton model of order " + std::to_string(t->order)
                                         : "a " + model.container.kind + " model") +
                                      ")");
  }
}

DeviceRenderers::Entry& DeviceRenderers::entry(const ServedModel& model) {
  Entry& e = by_name_[model.name];
  if (e.sha256 != model.sha256 || !e.renderers) {  // first use or the model file changed: rebuild
    e.sha256 = model.sha256;
    e.renderers = std::make_unique<ModelRenderers>(ctx_);
  }
  return e;
}

int DeviceRenderers::channels(const ServedModel& model) {
  return model.summary.channels;
}

RenderedImage DeviceRenderers::render(const ServedModel& model, const TileRequest& r) {
  // The known-answer self-test of the path (runtime/selftest.h) runs in ModelRenderers::render, as for
  // `stex render`: a device whose bits differ gets Error(Device) (500 with the message) instead of a wrong tile.
  RenderedPixels px = entry(model).renderers->render(model, r);
  RenderedImage out;
  out.image = Image{px.width, px.height, px.channels, std::move(px.pixels)};
  out.strategy = std::move(px.strategy);
  out.device_ms = px.device_ms;
  out.filtered = px.filtered;
  return out;
}

Encoder::Encoder() {
  // The writer fsyncs every file: in memory (/dev/shm) that costs nothing; $TMPDIR overrides.
  const char* tmp = std::getenv("TMPDIR");
  std::string base = tmp && *tmp ? tmp : "/tmp";
  if (!(tmp && *tmp) && ::access("/dev/shm", W_OK) == 0) base = "/dev/shm";
  std::string tmpl = base + "/stex-serve-XXXXXX";
  if (!::mkdtemp(tmpl.data()))
    throw Error(ErrorKind::Output, "cannot create the scratch directory '" + tmpl + "' for encoding tiles");
  dir_ = tmpl;
}

Encoder::~Encoder() {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

std::string Encoder::encode(const ServedModel& model, const TileRequest& r, const RenderedImage& img) {
  // The CLI's WriteOptions and metadata (cli/render.cpp, "3. Write atomically, with provenance"), for its
  // texton/own-kind mode without a camera.
  const bool float_out = r.format == "exr";
  WriteOptions wo;
  wo.bits = r.bits;
  wo.encode_srgb = model.linear && !float_out;
  RenderProvenance prov;
  prov.model_sha256 = model.sha256;
  prov.mode = model.container.kind;
  prov.kind = model.container.kind;
  prov.strategy = img.strategy;
  prov.exemplar_name = model_exemplar_name(model.container);
  prov.params = r.params;
  prov.x = r.x;
  prov.y = r.y;
  prov.filter = img.filtered ? model.filter_name() : "none";
  // A mix model renders with its own map (the service has no --mix-map): the CLI records that map's spec.
  if (const MixModel* mix = model.as<MixModel>()) prov.mix_map = mix_map_spec(mix->map);
  wo.metadata = render_metadata(prov);
  const std::string path = dir_ + "/t" + std::to_string(next_.fetch_add(1)) + "." + r.format;
  write_image_atomic(path, img.image, wo);
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  const bool ok = bool(in) || in.eof();
  ::unlink(path.c_str());
  if (!ok) throw Error(ErrorKind::Output, "cannot read back the encoded tile '" + path + "'");
  return bytes.str();
}

std::string content_type(const std::string& format) { return format == "exr" ? "image/x-exr" : "image/png"; }

}  // namespace stex::service
