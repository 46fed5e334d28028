// Farm output files and their metadata. Every file a farm render writes (one tile, or the whole image)
// carries who made it and which pixels it holds, as OIIO attributes (EXR header attributes, TIFF/PNG
// metadata):
//   stex:version, stex:model_hash, stex:param_hash, stex:seed, stex:mni, stex:origin ("X,Y" noise-space
//   offset of pixel (0,0)), stex:full_size ("WxH"), stex:tile_size, stex:grid ("NXxNY"), stex:tile_index
//   (int, -1 for a whole image), stex:window ("x,y,w,h" inside the full image), Software ("stex V");
// and the data window itself: the file's origin is (x, y) and OIIO's full_x/full_y/full_width/
// full_height describe the full image, so EXR tools show the tile in place.
//
// The parameter hash identifies the pixel function: two renders with the same param hash give the same
// value at the same pixel whatever the strategy, device or tiling. It is FNV-1a 64 over a canonical text
// (versioned, keys sorted) of the model hash, seed, MNI, origin and the caller's pixel-affecting
// parameters (mode, scale, cell factor, ...). The grid and the output pixel type are not part of it; they
// are compared separately (OutputInfo).
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "farm/tile_grid.h"

namespace stex::farm {

using KeyValues = std::vector<std::pair<std::string, std::string>>;

// What identifies a render: same identity (apart from window/tile index) = same pixels.
struct RenderIdentity {
  std::string stex_version;
  std::string model_hash;
  std::string param_hash;
  std::uint64_t seed = 0;
  double mni = 0.0;
  std::int64_t origin_x = 0, origin_y = 0;
  int full_width = 0, full_height = 0, tile_size = 0;
  int channels = 0;
};

// How pixels are stored. bits: 0 = by extension (exr/tif/hdr float 32, png/jpg 8 bit); 16 = exr half,
// tif/png 16 bit; 32 = float (exr, tif); 8 = tif/png/jpg 8 bit. compression: OIIO's "compression"
// attribute ("" = the format's default; e.g. "zip", "none", "piz" for EXR).
struct OutputSettings {
  int bits = 0;
  std::string compression;
  KeyValues metadata;  // extra string attributes
};

// What a file says about itself.
struct OutputInfo {
  RenderIdentity id;
  std::int64_t tile_index = -1;             // -1: the whole image
  int x = 0, y = 0, width = 0, height = 0;  // data window inside the full image
  std::string pixel_type;                   // OIIO type name: "float", "half", "uint8", "uint16"
  bool tiled = false;                       // stored as tiles (not scanlines)
};

// FNV-1a 64 of a byte string, as 16 lower-case hex digits. Stable across platforms and releases.
std::string fnv1a64_hex(const std::string& bytes);

// The parameter hash (see the file comment). Error(Usage) if a key is empty or contains '=' or a newline.
std::string compute_param_hash(const std::string& model_hash, std::uint64_t seed, double mni,
                               std::int64_t origin_x, std::int64_t origin_y, const KeyValues& params);

// OIIO type name of the pixels stored for `path` with `bits` (see OutputSettings); Error(Usage) for an
// unsupported extension or bit depth.
std::string output_pixel_type(const std::string& path, int bits);

// Writes one tile (interleaved floats, tile.width x tile.height x id.channels) to `path` atomically
// (core/atomic_file.h) with the metadata above. Error(Output) on failure (no file left behind).
void write_tile_file(const std::string& path, const std::vector<float>& pixels, const TileRect& tile,
                     const RenderIdentity& id, const OutputSettings& settings);

enum class OutputState { Missing, Invalid, Valid };

struct OutputInspection {
  OutputState state = OutputState::Missing;
  std::string problem;  // why Invalid: unreadable, truncated, not a stex output, ...
  OutputInfo info;      // when Valid
};

// Looks at an existing output: header and stex metadata, and with verify_pixels every pixel is decoded
// (tile by tile or strip by strip, bounded memory) so that a truncated or corrupt file is Invalid.
OutputInspection inspect_output(const std::string& path, bool verify_pixels = true);

// Reads all pixels of a (tile) file as interleaved floats: width x height x channels of its data window.
// Error(Input) naming the file if it cannot be read whole.
std::vector<float> read_output_pixels(const std::string& path);

// Reads the pixels of a rectangle (full-image coordinates, inside the file's data window) of an output
// file as interleaved floats. Error(Input) on failure.
std::vector<float> read_output_region(const std::string& path, int x0, int y0, int width, int height);

}  // namespace stex::farm
