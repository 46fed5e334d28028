// Fuzz target bodies (see entry_points.h). Invariant violations call std::abort so that libFuzzer and the
// replay test's forked children both see them as crashes.
#include "fuzz/entry_points.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>

#include "analysis/image_io.h"
#include "model/codecs.h"
#include "model/kinds.h"
#include "core/error.h"
#include "farm/name_template.h"
#include "farm/tile_grid.h"

namespace stex::fuzz {
namespace {

void require(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz invariant broken: %s\n", what);
    std::abort();
  }
}

// A temp file that lives as long as the process (load_exemplar reads files by path).
class TempFile {
 public:
  TempFile() {
    const char* dir = std::getenv("TMPDIR");
    std::string templ = std::string(dir && *dir ? dir : "/tmp") + "/stex_fuzz_XXXXXX";
    fd_ = ::mkstemp(templ.data());
    require(fd_ >= 0, "mkstemp");
    path_ = templ;
  }
  ~TempFile() {
    ::close(fd_);
    ::unlink(path_.c_str());
  }
  const std::string& write(const std::uint8_t* data, std::size_t size) {
    require(::ftruncate(fd_, 0) == 0, "ftruncate");
    std::size_t done = 0;
    while (done < size) {
      ssize_t n = ::pwrite(fd_, data + done, size - done, off_t(done));
      require(n > 0, "pwrite");
      done += std::size_t(n);
    }
    return path_;
  }

 private:
  int fd_ = -1;
  std::string path_;
};

}  // namespace

void model_file_one(const std::uint8_t* data, std::size_t size) {
  // Every registered kind's codec, through the registry.
  try {
    const ModelContainer c = decode_container(data, size, "fuzz input");
    require(valid_model_kind(c.kind), "model kind");
    check_model(c, "fuzz input");
  } catch (const Error& e) {
    require(*e.what() != '\0', "error message");
  }
  // The texton codec's own entry point (decode_model) and the decoded model's invariants.
  try {
    TextonModel m = decode_model(data, size, "fuzz input");
    require(m.channels >= 1 && m.channels <= 4, "model channels");
    require(m.support >= 1 && m.support <= kModelMaxSupport, "model support");
    require(m.alpha.size() == std::size_t(m.channels) * m.support * m.support, "model alpha size");
    for (float v : m.alpha) require(std::isfinite(v), "model alpha finite");
    for (float v : m.mean) require(std::isfinite(v), "model mean finite");
  } catch (const Error& e) {
    require(*e.what() != '\0', "error message");
  }
}

void exemplar_one(const std::uint8_t* data, std::size_t size) {
  static TempFile file;
  const std::string& path = file.write(data, size);
  LoadOptions opts;
  opts.pixel_budget = std::uint64_t(1) << 20;
  try {
    Image img = load_exemplar(path, opts);
    require(img.width > 0 && img.height > 0, "image size");
    require(std::uint64_t(img.width) * std::uint64_t(img.height) <= opts.pixel_budget, "pixel budget");
    require(img.channels >= 1 && img.channels <= 4, "image channels");
    require(img.pixels.size() == std::size_t(img.width) * img.height * img.channels, "pixel count");
    for (float v : img.pixels) require(std::isfinite(v), "pixel finite");
  } catch (const Error& e) {
    require(*e.what() != '\0', "error message");
  }
}

void tile_spec_one(const std::uint8_t* data, std::size_t size) {
  if (size < 5) return;
  // Grids up to 256 x 256 tiles: selecting all of a larger grid spends libFuzzer's time bound on sorting
  // millions of indices under instrumentation, not on parsing (fuzz/regressions/tile_spec/timeout-*:
  // "all" of 3841 x 2816 and of 1024 x 1024 one-pixel tiles; harness timeouts, not stex bugs).
  const int width = 1 + ((data[0] | data[1] << 8) % 256);
  const int height = 1 + ((data[2] | data[3] << 8) % 256);
  const int tile = 1 + data[4];
  const farm::TileGrid grid(width, height, tile);
  const std::string spec(reinterpret_cast<const char*>(data + 5), size - 5);
  std::vector<std::int64_t> tiles;
  try {
    tiles = farm::parse_tile_spec(spec, grid);
  } catch (const Error& e) {
    require(*e.what() != '\0', "error message");
    return;
  }
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    require(tiles[i] >= 0 && tiles[i] < grid.count(), "tile inside the grid");
    require(i == 0 || tiles[i - 1] < tiles[i], "tiles sorted and unique");
  }
  if (!tiles.empty()) {
    require(farm::parse_tile_spec(farm::format_index_list(tiles), grid) == tiles, "format/parse round trip");
  }
}

void name_template_one(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    farm::NameTemplate name(text);
    require(name.text() == text, "template text kept");
    const farm::TileGrid grid(300, 200, 64);  // 5 x 4 tiles
    name.check_grid(grid);
    std::set<std::string> names;
    for (std::int64_t i = 0; i < grid.count(); ++i) names.insert(name.format(grid.tile(i)));
    require(!name.has_placeholders() || names.size() == std::size_t(grid.count()), "distinct tile names");
  } catch (const Error& e) {
    require(*e.what() != '\0', "error message");
  }
}

}  // namespace stex::fuzz
