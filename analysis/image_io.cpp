// Exemplar loading and atomic image writing through OpenImageIO (see image_io.h for the contract and
// docs/hardening.md for the failure modes each check answers).
#include "analysis/image_io.h"

#include <OpenImageIO/imageio.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>

#include "core/atomic_file.h"
#include "core/error.h"

namespace stex {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

std::string extension_of(const std::string& path) {
  auto slash = path.find_last_of('/');
  auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return lower(path.substr(dot + 1));
}

// The OIIO format an extension suggests, for the "content differs from the name" warning.
std::string format_for_extension(const std::string& ext) {
  static const std::map<std::string, std::string> table = {
      {"png", "png"},   {"jpg", "jpeg"},    {"jpeg", "jpeg"}, {"jpe", "jpeg"},  {"tif", "tiff"},
      {"tiff", "tiff"}, {"exr", "openexr"}, {"bmp", "bmp"},   {"tga", "targa"}, {"hdr", "hdr"},
      {"pgm", "pnm"},   {"ppm", "pnm"},     {"pnm", "pnm"},   {"pbm", "pnm"}};
  auto it = table.find(ext);
  return it == table.end() ? std::string() : it->second;
}

std::string quoted(const std::string& path) { return "'" + path + "'"; }

std::string oiio_message(std::string msg) {
  while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' ')) msg.pop_back();
  return msg.empty() ? std::string("unknown error") : msg;
}

// PNG files (by content: the 8-byte signature) must have a whole chunk layout: every chunk from the signature
// to IEND lies inside the file. OIIO 2.4.7's PNG reader answers a short read inside its libpng read callback
// with png_error(), which longjmps out of the callback past a live std::string (PNGInput::PngReadCallback:
// leaked per truncated file, found by LeakSanitizer; a longjmp over C++ objects is undefined in general).
// With the layout checked first, libpng never reads past the end of the file: truncations are refused
// here, with the offset, and other damage reaches libpng's own checks (CRCs, zlib), which do not unwind
// through that callback.
void check_png_layout(const std::string& path, std::uint64_t file_size, const std::string& what) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw Error(ErrorKind::Input, "cannot open " + what + " " + quoted(path) + ": " + std::strerror(errno));
  struct Closer {
    std::FILE* f;
    ~Closer() { std::fclose(f); }
  } closer{f};
  static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  unsigned char head[8];
  if (file_size < 8 || std::fread(head, 1, 8, f) != 8 || std::memcmp(head, signature, 8) != 0) return;  // not PNG
  auto corrupt = [&](const std::string& why) {
    return Error(ErrorKind::Input, "cannot decode " + what + " " + quoted(path) + " (truncated or corrupt PNG): " + why);
  };
  std::uint64_t off = 8;
  while (true) {
    if (off + 12 > file_size) {
      throw corrupt("the file ends at byte " + std::to_string(file_size) + " without an IEND chunk");
    }
    if (std::fseek(f, long(off), SEEK_SET) != 0 || std::fread(head, 1, 8, f) != 8)
      throw corrupt("read error at byte " + std::to_string(off));
    const std::uint64_t length = std::uint64_t(head[0]) << 24 | std::uint64_t(head[1]) << 16 |
                                 std::uint64_t(head[2]) << 8 | std::uint64_t(head[3]);
    std::string type(reinterpret_cast<const char*>(head + 4), 4);
    for (char& c : type)
      if (!std::isalpha(static_cast<unsigned char>(c))) c = '?';
    if (length > 0x7fffffffu) {
      throw corrupt("chunk '" + type + "' at byte " + std::to_string(off) + " declares " + std::to_string(length) +
                    " bytes (at most 2^31-1)");
    }
    if (off + 12 + length > file_size) {
      throw corrupt("chunk '" + type + "' at byte " + std::to_string(off) + " (" + std::to_string(length) +
                    " bytes) runs past the end of the file (" + std::to_string(file_size) + " bytes)");
    }
    if (type == "IEND") return;
    off += 12 + length;
  }
}

}  // namespace

const std::vector<std::string>& exemplar_format_allow_list() {
  static const std::vector<std::string> formats = {"png", "jpeg",  "tiff", "openexr",
                                                   "bmp", "targa", "hdr",  "pnm"};
  return formats;
}

float srgb_to_linear(float v) {
  float a = std::fabs(v);
  float r = a <= 0.04045f ? a / 12.92f : std::pow((a + 0.055f) / 1.055f, 2.4f);
  return std::copysign(r, v);
}

float linear_to_srgb(float v) {
  float a = std::fabs(v);
  float r = a <= 0.0031308f ? a * 12.92f : 1.055f * std::pow(a, 1.0f / 2.4f) - 0.055f;
  return std::copysign(r, v);
}

Image load_exemplar(const std::string& path, const LoadOptions& opts, std::vector<std::string>* warnings) {
  const std::string what = opts.what;
  auto warn = [&](const std::string& w) {
    if (warnings) warnings->push_back(w);
  };
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw Error(ErrorKind::Input, "cannot open " + what + " " + quoted(path) + ": " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode))
    throw Error(ErrorKind::Input, what + " " + quoted(path) + " is not a regular file");

  check_png_layout(path, std::uint64_t(st.st_size), what);
  // Colour values as stored, not multiplied by alpha: alpha is dropped, and premultiplied colours would
  // darken the texture where it is transparent.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) {
    throw Error(ErrorKind::Input,
                "cannot read " + what + " " + quoted(path) + ": " + oiio_message(OIIO::geterror()));
  }
  const std::string format = in->format_name();
  const auto& allowed = exemplar_format_allow_list();
  if (std::find(allowed.begin(), allowed.end(), format) == allowed.end()) {
    throw Error(ErrorKind::Input, what + " " + quoted(path) + " is in format '" + format +
                                      "', which is not accepted (allowed: png, jpeg, tiff, openexr, bmp, "
                                      "targa, hdr, pnm)");
  }
  std::string expected = format_for_extension(extension_of(path));
  if (!expected.empty() && expected != format) {
    warn(what + " " + quoted(path) + " is named like " + expected + " but its content is " + format +
         "; loading it as " + format);
  }

  const OIIO::ImageSpec spec = in->spec();
  if (spec.deep) throw Error(ErrorKind::Input, what + " " + quoted(path) + " is a deep image (unsupported)");
  if (spec.depth > 1)
    throw Error(ErrorKind::Input, what + " " + quoted(path) + " is a volume (unsupported)");
  if (spec.width <= 0 || spec.height <= 0) {
    throw Error(ErrorKind::Input, what + " " + quoted(path) + " declares an empty size " +
                                      std::to_string(spec.width) + "x" + std::to_string(spec.height));
  }
  if (spec.nchannels < 1 || spec.nchannels > 4) {
    throw Error(ErrorKind::Input, what + " " + quoted(path) + " has " + std::to_string(spec.nchannels) +
                                      " channels; 1 to 4 are supported");
  }
  // Declared size against the budget before anything is allocated (width, height > 0 and int: the
  // product fits in 62 bits; the byte count is checked separately against size_t).
  const std::uint64_t pixels = std::uint64_t(spec.width) * std::uint64_t(spec.height);
  if (pixels > opts.pixel_budget) {
    throw Error(ErrorKind::Limit, what + " " + quoted(path) + " declares " + std::to_string(spec.width) +
                                      "x" + std::to_string(spec.height) + " = " + std::to_string(pixels) +
                                      " pixels, over the pixel budget of " +
                                      std::to_string(opts.pixel_budget));
  }
  const std::size_t nch = std::size_t(spec.nchannels);
  if (pixels > std::numeric_limits<std::size_t>::max() / (nch * sizeof(float))) {
    throw Error(ErrorKind::Limit, what + " " + quoted(path) + " is too large to address in memory");
  }

  std::vector<float> raw(std::size_t(pixels) * nch);
  bool ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, raw.data());
  // OIIO can return true on a truncated TIFF or JPEG: has_error() is the authority (docs/hardening.md).
  if (!ok || in->has_error()) {
    throw Error(ErrorKind::Input, "cannot decode " + what + " " + quoted(path) +
                                      " (truncated or corrupt?): " + oiio_message(in->geterror()));
  }
  in->close();
  if (in->has_error()) {
    throw Error(ErrorKind::Input,
                "error while closing " + what + " " + quoted(path) + ": " + oiio_message(in->geterror()));
  }

  // Drop alpha: 2 channels -> 1, 4 -> 3. The alpha channel is the one OIIO names, else the last.
  int drop = -1;
  if (nch == 2 || nch == 4) {
    drop = (spec.alpha_channel >= 0 && spec.alpha_channel < int(nch)) ? spec.alpha_channel : int(nch) - 1;
    warn(what + " " + quoted(path) + ": alpha channel '" +
         (drop < int(spec.channelnames.size()) ? spec.channelnames[drop] : std::string("?")) +
         "' dropped (alpha is not part of the texture model)");
  }
  Image img;
  img.width = spec.width;
  img.height = spec.height;
  img.channels = int(nch) - (drop >= 0 ? 1 : 0);
  if (drop < 0) {
    img.pixels = std::move(raw);
  } else {
    img.pixels.resize(std::size_t(pixels) * img.channels);
    for (std::size_t i = 0; i < pixels; ++i) {
      int o = 0;
      for (int c = 0; c < int(nch); ++c) {
        if (c != drop) img.pixels[i * img.channels + o++] = raw[i * nch + c];
      }
    }
  }

  for (std::size_t i = 0; i < img.pixels.size(); ++i) {
    if (!std::isfinite(img.pixels[i])) {
      std::size_t p = i / img.channels;
      throw Error(ErrorKind::Input, what + " " + quoted(path) + " has a non-finite value (" +
                                        (std::isnan(img.pixels[i]) ? "NaN" : "Inf") + ") at pixel (" +
                                        std::to_string(p % img.width) + ", " + std::to_string(p / img.width) +
                                        ") channel " + std::to_string(i % img.channels));
    }
  }

  if (opts.linear) {
    std::string cs = lower(spec.get_string_attribute("oiio:ColorSpace"));
    bool already_linear = cs == "linear" || cs == "scene_linear" || cs == "lin_srgb" || cs == "linear rec709";
    if (already_linear) {
      warn(what + " " + quoted(path) + " is stored in linear light (" + cs +
           "); --linear leaves its values as they are");
    } else {
      for (float& v : img.pixels) v = srgb_to_linear(v);
    }
  }
  return img;
}

Image load_float_image(const std::string& path, const std::string& what, std::uint64_t pixel_budget) {
  const std::string name = what + " " + quoted(path);
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw Error(ErrorKind::Input, "cannot open " + name + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw Error(ErrorKind::Input, name + " is not a regular file");
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw Error(ErrorKind::Input, "cannot read " + name + ": " + oiio_message(OIIO::geterror()));
  const OIIO::ImageSpec spec = in->spec();
  if (spec.deep || spec.depth > 1) throw Error(ErrorKind::Input, name + " is a deep image or a volume (unsupported)");
  if (spec.width <= 0 || spec.height <= 0)
    throw Error(ErrorKind::Input, name + " declares an empty size " + std::to_string(spec.width) + "x" +
                                      std::to_string(spec.height));
  if (spec.nchannels < 1 || spec.nchannels > 4)
    throw Error(ErrorKind::Input, name + " has " + std::to_string(spec.nchannels) + " channels; 1 to 4 are supported");
  // Every channel of the file must be floating point: integer pixels are normalised to [0, 1] on reading,
  // which would silently turn data (coordinates) into fractions.
  const OIIO::TypeDesc::BASETYPE base = OIIO::TypeDesc::BASETYPE(spec.format.basetype);
  const bool is_float = base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::DOUBLE;
  bool channels_float = true;
  for (const OIIO::TypeDesc& t : spec.channelformats)
    channels_float = channels_float && (t.basetype == OIIO::TypeDesc::HALF || t.basetype == OIIO::TypeDesc::FLOAT ||
                                        t.basetype == OIIO::TypeDesc::DOUBLE);
  if (!is_float || !channels_float)
    throw Error(ErrorKind::Input, name + " stores " + spec.format.c_str() +
                                      " pixels; it must be a floating-point image (e.g. EXR, half or float)");
  const std::uint64_t pixels = std::uint64_t(spec.width) * std::uint64_t(spec.height);
  if (pixels > pixel_budget)
    throw Error(ErrorKind::Limit, name + " declares " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                                      " = " + std::to_string(pixels) + " pixels, over the pixel budget of " +
                                      std::to_string(pixel_budget));
  Image img;
  img.width = spec.width;
  img.height = spec.height;
  img.channels = spec.nchannels;
  img.pixels.resize(std::size_t(pixels) * std::size_t(spec.nchannels));
  const bool ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, img.pixels.data());
  if (!ok || in->has_error())
    throw Error(ErrorKind::Input, "cannot decode " + name + " (truncated or corrupt?): " + oiio_message(in->geterror()));
  in->close();
  return img;
}

std::size_t write_image_atomic(const std::string& path, const Image& img, const WriteOptions& opts) {
  if (img.width <= 0 || img.height <= 0 || img.channels < 1 || img.channels > 4 ||
      img.pixels.size() != std::size_t(img.width) * img.height * img.channels) {
    throw Error(ErrorKind::Output, "cannot write " + quoted(path) + ": malformed image (" +
                                       std::to_string(img.width) + "x" + std::to_string(img.height) + "x" +
                                       std::to_string(img.channels) + ", " +
                                       std::to_string(img.pixels.size()) + " values)");
  }
  const std::string ext = extension_of(path);
  OIIO::TypeDesc type = OIIO::TypeDesc::UINT8;
  bool is_float = false;
  if (ext == "exr") {
    type = opts.bits == 16 ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT;
    is_float = true;
  } else if (ext == "hdr") {
    type = OIIO::TypeDesc::FLOAT;
    is_float = true;
  } else if ((ext == "tif" || ext == "tiff") && opts.bits == 32) {
    type = OIIO::TypeDesc::FLOAT;
    is_float = true;
  } else if ((ext == "png" || ext == "tif" || ext == "tiff") && opts.bits == 16) {
    type = OIIO::TypeDesc::UINT16;
  } else if (opts.bits != 0 && opts.bits != 8) {
    throw Error(ErrorKind::Output, "cannot write " + quoted(path) + ": " + std::to_string(opts.bits) +
                                       "-bit output is not supported for ." + ext + " files");
  }

  std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
  if (!out) {
    throw Error(ErrorKind::Output, "cannot write " + quoted(path) + ": no image writer for extension '." +
                                       ext + "' (" + oiio_message(OIIO::geterror()) + ")");
  }

  // Values to write (float), with sRGB encoding and clamping for integer formats.
  std::vector<float> values = img.pixels;
  std::size_t clamped = 0;
  for (float& v : values) {
    if (opts.encode_srgb) v = linear_to_srgb(v);
    if (!is_float) {
      if (std::isnan(v)) {
        v = 0.0f;
        ++clamped;
      } else if (v < 0.0f) {
        v = 0.0f;
        ++clamped;
      } else if (v > 1.0f) {
        v = 1.0f;
        ++clamped;
      }
    }
  }

  // Unique temp file beside the target, keeping the extension (OIIO picks the writer by name).
  TempOutput temp(path);
  const std::string& tmp = temp.path();
  auto fail = [&](const std::string& what) {
    temp.discard();
    throw Error(ErrorKind::Output, "cannot write " + quoted(path) + ": " + what);
  };

  OIIO::ImageSpec spec(img.width, img.height, img.channels, type);
  static const char* kNames[4][4] = {{"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
  spec.channelnames.clear();
  for (int c = 0; c < img.channels; ++c) spec.channelnames.push_back(kNames[img.channels - 1][c]);
  spec.alpha_channel = (img.channels == 2 || img.channels == 4) ? img.channels - 1 : -1;
  for (const auto& kv : opts.metadata) spec.attribute(kv.first, kv.second);
  try {
    if (!out->open(tmp, spec)) fail(oiio_message(out->geterror()));
    if (!out->write_image(OIIO::TypeDesc::FLOAT, values.data()) || out->has_error()) {
      std::string msg = oiio_message(out->geterror());
      out->close();
      fail(msg);
    }
    if (!out->close()) fail(oiio_message(out->geterror()));
    out.reset();
  } catch (const Error&) {
    throw;  // fail() already removed the temp file
  } catch (const std::exception& e) {
    out.reset();
    fail(std::string("image writer failed: ") + e.what());
  }

  temp.commit();
  return clamped;
}

}  // namespace stex
