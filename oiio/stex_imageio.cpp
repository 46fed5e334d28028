// stex.imageio.so: OpenImageIO's reader of stex models. `MODEL.stex?RES=WxH&ORIGIN=X,Y&SEED=S&..` opens a
// region of the model's unbounded texture as a tiled float image (MIP-mapped with MIP=1), rendered tile by
// tile on demand (oiio/region_image.h; docs/oiio-plugin.md). Exports only OIIO's three plugin symbols
// (stex_imageio_version, stex_input_imageio_create, stex_input_extensions; the link's version script hides
// the rest); every error reaches the host through ImageInput's error path, never as an exception.
#include <OpenImageIO/imageio.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "oiio/region_image.h"

OIIO_PLUGIN_NAMESPACE_BEGIN

namespace {

// Level 0's first tile of the images opened lately, by the name with its options and the model's SHA-256:
// hosts open a file more than once (oiiotool reads the spec, then the pixels through its cache), and each
// open renders that tile to surface device errors and learn the strategy. At most 16 MB kept.
class FirstTiles {
 public:
  struct Tile {
    std::vector<float> pixels;
    std::string strategy;
  };
  static FirstTiles& instance() {
    static FirstTiles* t = new FirstTiles();  // never destroyed (see DeviceHost in region_image.cpp)
    return *t;
  }
  bool find(const std::string& key, Tile& out) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& e : tiles_)
      if (e.first == key) {
        out = e.second;
        return true;
      }
    return false;
  }
  void put(const std::string& key, const Tile& t) {
    const std::size_t bytes = t.pixels.size() * sizeof(float);
    if (bytes > k_bytes) return;
    std::lock_guard<std::mutex> lock(mutex_);
    tiles_.emplace_front(key, t);
    bytes_ += bytes;
    while (bytes_ > k_bytes) {
      bytes_ -= tiles_.back().second.pixels.size() * sizeof(float);
      tiles_.pop_back();
    }
  }

 private:
  static constexpr std::size_t k_bytes = std::size_t(16) << 20;
  std::mutex mutex_;
  std::list<std::pair<std::string, Tile>> tiles_;
  std::size_t bytes_ = 0;
};

class StexInput final : public ImageInput {
 public:
  const char* format_name() const override { return "stex"; }
  int supports(string_view feature) const override {
    return feature == "arbitrary_metadata" || feature == "procedural";
  }
  bool valid_file(const std::string& filename) const override {
    std::ifstream in(stex::oiio::region_model_path(filename), std::ios::binary);
    char magic[8] = {};
    return in.read(magic, sizeof magic) && std::memcmp(magic, "STEXMDL", 8) == 0;
  }
  bool open(const std::string& name, ImageSpec& newspec) override;
  bool open(const std::string& name, ImageSpec& newspec, const ImageSpec& /*config*/) override {
    return open(name, newspec);
  }
  bool close() override {
    image_.reset();
    specs_.clear();
    first_tile_.clear();
    return true;
  }
  int current_subimage() const override { return 0; }
  int current_miplevel() const override {
    std::lock_guard<const ImageInput> lock(*this);
    return level_;
  }
  bool seek_subimage(int subimage, int miplevel) override;
  ImageSpec spec(int subimage, int miplevel = 0) override;
  ImageSpec spec_dimensions(int subimage, int miplevel = 0) override { return spec(subimage, miplevel); }
  bool read_native_scanline(int subimage, int miplevel, int y, int z, void* data) override;
  bool read_native_tile(int subimage, int miplevel, int x, int y, int z, void* data) override;

 private:
  std::unique_ptr<stex::oiio::RegionImage> image_;
  std::vector<ImageSpec> specs_;  // one per MIP level
  std::vector<float> first_tile_;  // level 0's tile (0, 0), rendered by open()
  int level_ = 0;
};

bool StexInput::open(const std::string& name, ImageSpec& newspec) {
  try {
    close();
    // A plain file name takes its options from $STEX_IMAGEIO_OPTIONS (tools such as maketx insist on a
    // name that exists on disk).
    std::string full = name;
    const char* env = std::getenv("STEX_IMAGEIO_OPTIONS");
    if (name.find('?') == std::string::npos && env && *env) full += std::string("?") + env;
    auto image = std::make_unique<stex::oiio::RegionImage>(stex::oiio::parse_region_options(full));
    const auto& o = image->options();
    // Level 0's first tile now: a device, kernel or self-test failure is open()'s error, and the attributes
    // name the strategy actually used (as `stex render` records it).
    const std::string key = full + "\n" + image->model().sha256;
    FirstTiles::Tile first;
    if (!FirstTiles::instance().find(key, first)) {
      first.pixels.resize(std::size_t(o.tile) * o.tile * image->channels());
      first.strategy = image->render_tile(0, 0, 0, first.pixels.data());
      FirstTiles::instance().put(key, first);
    }
    const std::string strategy = first.strategy;
    first_tile_ = std::move(first.pixels);  // served to reads of that tile: it renders once per open, at most
    for (int k = 0; k < int(image->levels().size()); ++k) {
      const auto& l = image->levels()[std::size_t(k)];
      ImageSpec s(l.width, l.height, image->channels(), TypeDesc::FLOAT);
      s.tile_width = o.tile;
      s.tile_height = o.tile;
      s.tile_depth = 1;
      std::string level_strategy = strategy;
      if (l.path == stex::oiio::LevelPath::Filtered) level_strategy = "filtered";
      if (l.path == stex::oiio::LevelPath::Box) level_strategy = "box-mean of " + strategy;
      for (const auto& [key, value] : image->metadata(k, level_strategy)) s.attribute(key, value);
      s.attribute("oiio:ColorSpace", image->model().linear ? "linear" : "sRGB");
      if (o.mip) s.attribute("textureformat", "Plain Texture");
      specs_.push_back(std::move(s));
    }
    image_ = std::move(image);
    level_ = 0;
    m_spec = specs_[0];
    newspec = m_spec;
    return true;
  } catch (const std::exception& e) {
    close();
    errorfmt("stex: {}", e.what());
    return false;
  }
}

bool StexInput::seek_subimage(int subimage, int miplevel) {
  std::lock_guard<const ImageInput> lock(*this);
  if (!image_ || subimage != 0 || miplevel < 0 || miplevel >= int(specs_.size())) return false;
  level_ = miplevel;
  m_spec = specs_[std::size_t(miplevel)];
  return true;
}

ImageSpec StexInput::spec(int subimage, int miplevel) {
  std::lock_guard<const ImageInput> lock(*this);
  if (!image_ || subimage != 0 || miplevel < 0 || miplevel >= int(specs_.size())) return ImageSpec();
  return specs_[std::size_t(miplevel)];
}

bool StexInput::read_native_tile(int subimage, int miplevel, int x, int y, int z, void* data) {
  if (!image_ || subimage != 0 || miplevel < 0 || miplevel >= int(specs_.size()) || z != 0) {
    errorfmt("stex: no subimage {} MIP level {} in this image", subimage, miplevel);
    return false;
  }
  try {
    if (miplevel == 0 && x == 0 && y == 0 && !first_tile_.empty())
      std::memcpy(data, first_tile_.data(), first_tile_.size() * sizeof(float));
    else
      image_->render_tile(miplevel, x, y, static_cast<float*>(data));
    return true;
  } catch (const std::exception& e) {
    errorfmt("stex: {}", e.what());
    return false;
  }
}

// Tiled images are read by tiles; a scanline read (OIIO's generic path never asks for one of a tiled file)
// renders the row's tiles and copies the row.
bool StexInput::read_native_scanline(int subimage, int miplevel, int y, int z, void* data) {
  if (!image_ || subimage != 0 || miplevel < 0 || miplevel >= int(specs_.size()) || z != 0) {
    errorfmt("stex: no subimage {} MIP level {} in this image", subimage, miplevel);
    return false;
  }
  const ImageSpec& s = specs_[std::size_t(miplevel)];
  const int t = s.tile_width, c = s.nchannels;
  std::vector<float> tile(std::size_t(t) * t * c);
  try {
    for (int x = 0; x < s.width; x += t) {
      image_->render_tile(miplevel, x, y - y % t, tile.data());
      const int w = std::min(t, s.width - x);
      std::memcpy(static_cast<float*>(data) + std::size_t(x) * c, tile.data() + std::size_t(y % t) * t * c,
                  sizeof(float) * w * c);
    }
    return true;
  } catch (const std::exception& e) {
    errorfmt("stex: {}", e.what());
    return false;
  }
}

}  // namespace

OIIO_PLUGIN_EXPORTS_BEGIN

OIIO_EXPORT int stex_imageio_version = OIIO_PLUGIN_VERSION;
OIIO_EXPORT const char* stex_imageio_library_version() { return "stex " STEX_VERSION_STRING; }
OIIO_EXPORT ImageInput* stex_input_imageio_create() { return new StexInput; }
OIIO_EXPORT const char* stex_input_extensions[] = {"stex", nullptr};

OIIO_PLUGIN_EXPORTS_END

OIIO_PLUGIN_NAMESPACE_END
