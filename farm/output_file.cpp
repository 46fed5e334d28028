// Farm output files: metadata, parameter hash, atomic per-tile writes and inspection (farm/output_file.h).
#include "farm/output_file.h"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "farm/oiio_detail.h"

namespace stex::farm {

using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

namespace detail {

std::string lower_extension(const std::string& path) {
  std::size_t slash = path.find_last_of('/');
  std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

TypeDesc pixel_typedesc(const std::string& path, int bits) {
  std::string ext = lower_extension(path);
  auto unsupported = [&] {
    throw Error(ErrorKind::Usage, "output '" + path + "': " + std::to_string(bits) +
                                      "-bit pixels are not supported for ." + ext +
                                      " (exr: 16/32, tif: 8/16/32, png: 8/16, jpg: 8)");
  };
  if (bits != 0 && bits != 8 && bits != 16 && bits != 32) unsupported();
  if (ext == "exr") {
    if (bits == 8) unsupported();
    return bits == 16 ? TypeDesc::HALF : TypeDesc::FLOAT;
  }
  if (ext == "tif" || ext == "tiff") {
    return bits == 8 ? TypeDesc::UINT8 : bits == 16 ? TypeDesc::UINT16 : TypeDesc::FLOAT;
  }
  if (ext == "hdr") {
    if (bits != 0 && bits != 32) unsupported();
    return TypeDesc::FLOAT;
  }
  if (ext == "png") {
    if (bits == 32) unsupported();
    return bits == 16 ? TypeDesc::UINT16 : TypeDesc::UINT8;
  }
  if (ext == "jpg" || ext == "jpeg") {
    if (bits != 0 && bits != 8) unsupported();
    return TypeDesc::UINT8;
  }
  throw Error(ErrorKind::Usage, "output '" + path + "': unsupported extension '." + ext +
                                    "' (farm outputs: exr, tif, tiff, png, jpg, hdr)");
}

ImageSpec make_output_spec(const std::string& path, const RenderIdentity& id, const OutputSettings& settings,
                           std::int64_t tile_index, int x, int y, int width, int height) {
  ImageSpec spec(width, height, id.channels, pixel_typedesc(path, settings.bits));
  spec.channelnames.clear();
  static const char* kNames[4] = {"R", "G", "B", "A"};
  for (int c = 0; c < id.channels; ++c) spec.channelnames.push_back(id.channels == 1 ? "Y" : kNames[c & 3]);
  spec.alpha_channel = -1;
  spec.x = x;
  spec.y = y;
  spec.full_x = 0;
  spec.full_y = 0;
  spec.full_width = id.full_width;
  spec.full_height = id.full_height;
  if (!settings.compression.empty()) spec.attribute("compression", settings.compression);
  // OIIO 2.4 with libtiff 4.5 reports "failed TIFFWriteCustomDirectory() of the Exif data" for every TIFF
  // (the write succeeds otherwise); stex writes no Exif tags, so skip the Exif directory.
  spec.attribute("tiff:write_exif", 0);
  for (const auto& kv : settings.metadata) spec.attribute(kv.first, kv.second);
  // Every field as a "stex:KEY" attribute (EXR keeps any attribute; PNG keeps strings as text chunks),
  // and all of them once more in ImageDescription, the one text field TIFF (and PNG) always keep.
  char buf[128];
  TileGrid grid(id.full_width, id.full_height, id.tile_size);
  KeyValues meta;
  meta.emplace_back("version", id.stex_version);
  meta.emplace_back("model_hash", id.model_hash);
  meta.emplace_back("param_hash", id.param_hash);
  meta.emplace_back("seed", std::to_string(id.seed));
  std::snprintf(buf, sizeof buf, "%.17g", id.mni);
  meta.emplace_back("mni", buf);
  std::snprintf(buf, sizeof buf, "%" PRId64 ",%" PRId64, id.origin_x, id.origin_y);
  meta.emplace_back("origin", buf);
  std::snprintf(buf, sizeof buf, "%dx%d", id.full_width, id.full_height);
  meta.emplace_back("full_size", buf);
  meta.emplace_back("tile_size", std::to_string(id.tile_size));
  std::snprintf(buf, sizeof buf, "%dx%d", grid.nx(), grid.ny());
  meta.emplace_back("grid", buf);
  meta.emplace_back("tile_index", std::to_string(tile_index));
  std::snprintf(buf, sizeof buf, "%d,%d,%d,%d", x, y, width, height);
  meta.emplace_back("window", buf);
  const bool exr = lower_extension(path) == "exr";
  std::string description = "stex farm output;";
  for (const auto& [key, value] : meta) {
    if (exr && key == "tile_index")
      spec.attribute("stex:tile_index", int(tile_index));
    else if (exr && key == "tile_size")
      spec.attribute("stex:tile_size", id.tile_size);
    else
      spec.attribute("stex:" + key, value);
    description += " " + key + "=" + value + ";";
  }
  spec.attribute("Software", "stex " + id.stex_version);
  spec.attribute("ImageDescription", description);
  return spec;
}

}  // namespace detail

namespace {

// A stex metadata field: the "stex:KEY" attribute, else the "KEY=VALUE;" item of ImageDescription.
std::string stex_field(const ImageSpec& spec, const std::string& key) {
  if (const OIIO::ParamValue* p = spec.find_attribute("stex:" + key)) return p->get_string();
  std::string desc = spec.get_string_attribute("ImageDescription");
  if (desc.rfind("stex farm output;", 0) != 0) return "";
  std::string needle = " " + key + "=";
  std::size_t at = desc.find(needle);
  if (at == std::string::npos) return "";
  at += needle.size();
  std::size_t end = desc.find(';', at);
  return desc.substr(at, end == std::string::npos ? std::string::npos : end - at);
}

bool parse_ints(const std::string& s, char sep, int n, long long* out) {
  const char* c = s.c_str();
  for (int i = 0; i < n; ++i) {
    char* end = nullptr;
    errno = 0;
    out[i] = std::strtoll(c, &end, 10);
    if (end == c || errno) return false;
    c = end;
    if (i + 1 < n) {
      if (*c != sep) return false;
      ++c;
    }
  }
  return *c == '\0';
}

// Decodes every pixel, one tile row (tiled files) or 64 scanlines at a time: bounded memory.
bool verify_all_pixels(ImageInput& in, std::string& problem) {
  const ImageSpec& spec = in.spec();
  const int nch = spec.nchannels;
  if (spec.tile_width > 0) {
    int th = std::max(1, spec.tile_height);
    std::vector<float> buf(std::size_t(spec.width) * th * nch);
    for (int y = spec.y; y < spec.y + spec.height; y += th) {
      int y1 = std::min(y + th, spec.y + spec.height);
      if (!in.read_tiles(0, 0, spec.x, spec.x + spec.width, y, y1, 0, 1, 0, nch, TypeDesc::FLOAT,
                         buf.data()) ||
          in.has_error()) {
        problem = "cannot decode pixels: " + in.geterror();
        return false;
      }
    }
  } else {
    const int rows = 64;
    std::vector<float> buf(std::size_t(spec.width) * rows * nch);
    for (int y = spec.y; y < spec.y + spec.height; y += rows) {
      int y1 = std::min(y + rows, spec.y + spec.height);
      if (!in.read_scanlines(0, 0, y, y1, 0, 0, nch, TypeDesc::FLOAT, buf.data()) || in.has_error()) {
        problem = "cannot decode pixels: " + in.geterror();
        return false;
      }
    }
  }
  return true;
}

std::unique_ptr<ImageInput> open_input(const std::string& path) {
  auto in = ImageInput::open(path);
  if (!in) {
    std::string err = OIIO::geterror();
    throw Error(ErrorKind::Input, "cannot open '" + path + "': " + (err.empty() ? "unknown error" : err));
  }
  return in;
}

}  // namespace

std::string fnv1a64_hex(const std::string& bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016" PRIx64, h);
  return buf;
}

std::string compute_param_hash(const std::string& model_hash, std::uint64_t seed, double mni,
                               std::int64_t origin_x, std::int64_t origin_y, const KeyValues& params) {
  KeyValues sorted = params;
  std::sort(sorted.begin(), sorted.end());
  std::ostringstream os;
  char buf[64];
  os << "stex-param-hash-v1\n";
  os << "model_hash=" << model_hash << "\n";
  os << "seed=" << seed << "\n";
  std::snprintf(buf, sizeof buf, "%.17g", mni);
  os << "mni=" << buf << "\n";
  os << "origin=" << origin_x << "," << origin_y << "\n";
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    const auto& [k, v] = sorted[i];
    if (k.empty() || k.find_first_of("=\n") != std::string::npos || v.find('\n') != std::string::npos)
      throw Error(ErrorKind::Usage,
                  "render parameter '" + k + "' cannot be hashed (empty key, '=' or newline)");
    if (i > 0 && sorted[i - 1].first == k)
      throw Error(ErrorKind::Usage, "render parameter '" + k + "' given twice");
    os << k << "=" << v << "\n";
  }
  return fnv1a64_hex(os.str());
}

std::string output_pixel_type(const std::string& path, int bits) {
  return detail::pixel_typedesc(path, bits).c_str();
}

void write_tile_file(const std::string& path, const std::vector<float>& pixels, const TileRect& tile,
                     const RenderIdentity& id, const OutputSettings& settings) {
  if (pixels.size() != std::size_t(tile.width) * tile.height * id.channels) {
    throw Error(ErrorKind::Internal, "tile " + std::to_string(tile.index) + ": " +
                                         std::to_string(pixels.size()) + " values for a " +
                                         std::to_string(tile.width) + "x" + std::to_string(tile.height) +
                                         "x" + std::to_string(id.channels) + " tile");
  }
  ImageSpec spec =
      detail::make_output_spec(path, id, settings, tile.index, tile.x0, tile.y0, tile.width, tile.height);
  make_parent_dirs(path);
  TempOutput tmp(path, /*fault_hook=*/true);
  auto out = ImageOutput::create(tmp.path());
  if (!out) throw Error(ErrorKind::Output, "cannot write '" + path + "': " + OIIO::geterror());
  if (!out->supports("origin")) {  // PNG/JPEG have no data window: the stex:window attribute still says it
    spec.x = spec.y = 0;
  }
  errno = 0;
  bool ok = out->open(tmp.path(), spec) && out->write_image(TypeDesc::FLOAT, pixels.data());
  int saved_errno = errno;
  ok = out->close() && ok;
  if (!ok && saved_errno == 0) saved_errno = errno;
  if (!ok || out->has_error()) {
    std::string err = out->geterror();
    std::string cause = write_failure_cause(path, saved_errno);
    throw Error(ErrorKind::Output, "cannot write '" + path + "': " + (cause.empty() ? "" : cause + ": ") +
                                       (err.empty() ? "write failed" : err));
  }
  out.reset();
  tmp.commit();
}

OutputInspection inspect_output(const std::string& path, bool verify_pixels) {
  OutputInspection r;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) return r;
    r.state = OutputState::Invalid;
    r.problem = std::strerror(errno);
    return r;
  }
  r.state = OutputState::Invalid;
  auto in = ImageInput::open(path);
  if (!in) {
    r.problem = "unreadable: " + OIIO::geterror();
    return r;
  }
  const ImageSpec& spec = in->spec();
  OutputInfo& info = r.info;
  info.id.param_hash = stex_field(spec, "param_hash");
  info.id.model_hash = stex_field(spec, "model_hash");
  info.id.stex_version = stex_field(spec, "version");
  if (info.id.param_hash.empty() || info.id.model_hash.empty()) {
    r.problem = "not a stex farm output (no stex:param_hash/stex:model_hash metadata)";
    return r;
  }
  long long window[4], full[2], origin[2];
  std::string seed = stex_field(spec, "seed");
  std::string mni = stex_field(spec, "mni");
  char* end = nullptr;
  errno = 0;
  info.id.seed = std::strtoull(seed.c_str(), &end, 10);
  bool ok = !seed.empty() && *end == '\0' && errno == 0;
  info.id.mni = std::strtod(mni.c_str(), &end);
  ok = ok && !mni.empty() && *end == '\0';
  ok = ok && parse_ints(stex_field(spec, "window"), ',', 4, window);
  ok = ok && parse_ints(stex_field(spec, "full_size"), 'x', 2, full);
  ok = ok && parse_ints(stex_field(spec, "origin"), ',', 2, origin);
  long long tile_index = 0, tile_size = 0;
  ok = ok && parse_ints(stex_field(spec, "tile_index"), ',', 1, &tile_index);
  ok = ok && parse_ints(stex_field(spec, "tile_size"), ',', 1, &tile_size);
  if (!ok) {
    r.problem = "incomplete stex metadata";
    return r;
  }
  info.id.origin_x = origin[0];
  info.id.origin_y = origin[1];
  info.id.full_width = int(full[0]);
  info.id.full_height = int(full[1]);
  info.id.tile_size = int(tile_size);
  info.id.channels = spec.nchannels;
  info.tile_index = tile_index;
  info.x = int(window[0]);
  info.y = int(window[1]);
  info.width = int(window[2]);
  info.height = int(window[3]);
  info.pixel_type = spec.format.c_str();
  info.tiled = spec.tile_width > 0;
  if (info.width != spec.width || info.height != spec.height) {
    r.problem = "stex:window " + stex_field(spec, "window") + " does not match the file's size " +
                std::to_string(spec.width) + "x" + std::to_string(spec.height);
    return r;
  }
  if (verify_pixels && !verify_all_pixels(*in, r.problem)) return r;
  r.state = OutputState::Valid;
  return r;
}

std::vector<float> read_output_pixels(const std::string& path) {
  auto in = open_input(path);
  const ImageSpec& spec = in->spec();
  std::vector<float> px(std::size_t(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, TypeDesc::FLOAT, px.data()) || in->has_error())
    throw Error(ErrorKind::Input, "cannot read the pixels of '" + path + "': " + in->geterror());
  return px;
}

std::vector<float> read_output_region(const std::string& path, int x0, int y0, int width, int height) {
  auto in = open_input(path);
  const ImageSpec& spec = in->spec();
  // Files without a data window (PNG) hold their window at (0,0); stex:window says where it is.
  int fx = spec.x, fy = spec.y;
  long long window[4];
  if (fx == 0 && fy == 0 && parse_ints(stex_field(spec, "window"), ',', 4, window)) {
    fx = int(window[0]);
    fy = int(window[1]);
  }
  if (x0 < fx || y0 < fy || width < 1 || height < 1 ||
      x0 + std::int64_t(width) > fx + std::int64_t(spec.width) ||
      y0 + std::int64_t(height) > fy + std::int64_t(spec.height)) {
    throw Error(ErrorKind::Input, "region outside the data window of '" + path + "'");
  }
  const int nch = spec.nchannels;
  std::vector<float> out(std::size_t(width) * height * nch);
  const int lx = x0 - fx + spec.x, ly = y0 - fy + spec.y;  // in the file's own coordinates
  // Read whole tiles (tiled files) or whole scanlines covering the region, then crop. (OIIO 2.4's
  // read_scanlines on a tiled EXR crashes with SIGFPE, so tiled files are only read through read_tiles.)
  int bx0 = spec.x, bx1 = spec.x + spec.width, by0 = ly, by1 = ly + height;
  if (spec.tile_width > 0) {
    const int tw = spec.tile_width, th = std::max(1, spec.tile_height);
    bx0 = spec.x + (lx - spec.x) / tw * tw;
    bx1 = std::min(spec.x + spec.width, spec.x + (lx + width - spec.x + tw - 1) / tw * tw);
    by0 = spec.y + (ly - spec.y) / th * th;
    by1 = std::min(spec.y + spec.height, spec.y + (ly + height - spec.y + th - 1) / th * th);
  }
  const int bw = bx1 - bx0;
  std::vector<float> block(std::size_t(bw) * (by1 - by0) * nch);
  bool ok = spec.tile_width > 0
                ? in->read_tiles(0, 0, bx0, bx1, by0, by1, 0, 1, 0, nch, TypeDesc::FLOAT, block.data())
                : in->read_scanlines(0, 0, by0, by1, 0, 0, nch, TypeDesc::FLOAT, block.data());
  for (int r = 0; ok && r < height; ++r) {
    std::copy_n(block.begin() + (std::size_t(ly - by0 + r) * bw + (lx - bx0)) * nch, std::size_t(width) * nch,
                out.begin() + std::size_t(r) * width * nch);
  }
  if (!ok || in->has_error())
    throw Error(ErrorKind::Input, "cannot read a region of '" + path + "': " + in->geterror());
  return out;
}

}  // namespace stex::farm
