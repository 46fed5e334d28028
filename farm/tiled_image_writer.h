// One large image written tile by tile, never held in memory whole (issue #4: 16384^2 and larger with
// bounded memory). EXR and TIFF are written as tiled files through OIIO's ImageOutput::write_tile, one
// file tile per grid tile; formats without tiles (PNG, JPEG, HDR) are written as scanlines, buffering one
// row of tiles (width x tile_size pixels) at a time.
//
// Order: tiles must arrive in increasing index order (row by row). OpenEXR stores tiles of an
// INCREASING_Y file in that order and would otherwise buffer early tiles in memory, and the scanline
// path flushes a strip once its last tile is in. TIFF tiles must be multiples of 16 pixels (TIFF 6.0).
//
// Atomic like every farm output: the image is written to a temp file beside the target and renamed over
// it by finish(); a writer destroyed before finish() (error, SIGINT/SIGTERM) removes its temp file.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "farm/output_file.h"
#include "farm/tile_grid.h"

namespace stex::farm {

class TiledImageWriter {
 public:
  // Opens the temp file. `id` describes the full image (id.full_* and id.tile_size must match `grid`).
  // Error(Usage) for an unsupported extension/bit depth or a TIFF tile size not a multiple of 16;
  // Error(Output) when the file cannot be created.
  TiledImageWriter(const std::string& path, const TileGrid& grid, const RenderIdentity& id,
                   const OutputSettings& settings);
  ~TiledImageWriter();
  TiledImageWriter(const TiledImageWriter&) = delete;
  TiledImageWriter& operator=(const TiledImageWriter&) = delete;

  // Writes tile `tile` (interleaved floats, tile.width x tile.height x channels). Tiles must come in
  // increasing index order without gaps (Error(Internal) otherwise). Error(Output) on write failure.
  void write_tile(const TileRect& tile, const std::vector<float>& pixels);

  // Closes, fsyncs and renames the file into place. Error(Output) on failure or if tiles are missing.
  void finish();

  bool tiled_file() const { return tiled_; }
  const std::string& temp_path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  bool tiled_ = false;
};

}  // namespace stex::farm
