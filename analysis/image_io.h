// Exemplar and output image files through OpenImageIO, with the defences docs/hardening.md lists:
// a format allow-list (OIIO picks the reader by content, not by extension), the declared size
// checked against a pixel budget before any allocation, has_error() after every read (OIIO reports success
// on truncated TIFF/JPEG), NaN/Inf rejected, and atomic writes (unique temp file in the target directory,
// fsync, rename) so that every file written appears whole or not at all (docs/ARCHITECTURE.md "Invariants").
//
// Values: by default the file's encoded values are analysed as they are (8-bit sRGB PNG -> [0,1] floats,
// no transfer function); LoadOptions::linear decodes sRGB first (IEC 61966-2-1 curve), except for files
// that OIIO reports as already linear (EXR, HDR), which are left alone with a warning.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace stex {

struct Image {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;  // interleaved, row-major: (y * width + x) * channels + c

  float at(int x, int y, int c) const { return pixels[(std::size_t(y) * width + x) * channels + c]; }
  float& at(int x, int y, int c) { return pixels[(std::size_t(y) * width + x) * channels + c]; }
};

struct LoadOptions {
  std::uint64_t pixel_budget = std::uint64_t(1) << 26;  // width * height, checked before allocating
  bool linear = false;                                  // decode sRGB to linear light
  const char* what = "exemplar";  // names the file in messages ("exemplar", "mask image", ...): a literal
};

// OIIO format names accepted by load_exemplar (ImageInput::format_name()).
const std::vector<std::string>& exemplar_format_allow_list();

// Loads an exemplar through OIIO: 1, 2, 3, 4 channels; 8/16-bit, half, float; palettes expanded by OIIO;
// alpha dropped with a warning (2 ch -> 1, 4 ch -> 3), colours read as stored (unassociated: not multiplied
// by alpha). Errors (each naming the file and the problem):
// Error(Input) for a missing/unreadable/truncated/corrupt file, a format outside the allow-list, an
// unsupported layout (deep, volume, > 4 channels) or NaN/Inf pixels; Error(Limit) when the declared size
// exceeds opts.pixel_budget. A file whose content format differs from its extension (a Targa named .png)
// is loaded as what it is when that format is allowed, with a warning.
Image load_exemplar(const std::string& path, const LoadOptions& opts = {},
                    std::vector<std::string>* warnings = nullptr);

// Loads a floating-point data image (half, float or double pixels; 1..4 channels, all kept as stored, no
// alpha handling, NaN/Inf kept for the caller to judge), e.g. a UV map. `what` names it in messages.
// Error(Input) for a missing, unreadable or corrupt file, integer pixels or an unsupported layout;
// Error(Limit) above `pixel_budget` pixels (checked before allocating).
Image load_float_image(const std::string& path, const std::string& what, std::uint64_t pixel_budget);

struct WriteOptions {
  // 0: by extension: exr/hdr -> float 32, png/tif/others -> 8 bit. 16: png/tif 16 bit, exr half.
  // 32: float (exr, tif, hdr only).
  int bits = 0;
  bool encode_srgb = false;  // apply linear_to_srgb to every channel before writing
  std::vector<std::pair<std::string, std::string>> metadata;  // string attributes (e.g. "Software")
};

// Writes by extension through OIIO. Integer formats clamp to [0,1] (NaN -> 0); returns the number of
// values clamped. Writes to a unique temp file in the target directory (mkstemps), fsyncs, renames over
// `path`. On any failure removes the temp file and throws Error(Output) naming the file and the problem.
std::size_t write_image_atomic(const std::string& path, const Image& img, const WriteOptions& opts = {});

// sRGB transfer functions (IEC 61966-2-1), applied per value. Odd extension for negative values
// (f(-v) = -f(v)) so that values outside [0,1] (float exemplars, noise overshoot) survive a round trip.
float srgb_to_linear(float v);
float linear_to_srgb(float v);

// Hex SHA-256 (FIPS 180-4) of a file's bytes; Error(Input) if it cannot be read. See core/sha256.h.
std::string sha256_file_hex(const std::string& path);

}  // namespace stex
