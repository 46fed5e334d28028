// `stex assemble`: stitches the per-tile files of one farm render into one image, written tile by tile
// through the out-of-core writer (farm/tiled_image_writer.h), so memory stays at one tile (or one row of
// tiles for formats without tiles) however large the image.
//
// Before any pixel is written it checks, from the files' stex metadata (farm/output_file.h), that every
// input is a tile of the same render (model hash, parameter hash, full size, tile size, channels, pixel
// type) and that every tile of the grid is present exactly once; each violation is Error(Input) naming
// the files or the missing tile indices.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "farm/output_file.h"
#include "farm/tile_grid.h"

namespace stex::farm {

struct AssembleResult {
  std::int64_t tiles = 0;
  int width = 0, height = 0, channels = 0;
  RenderIdentity identity;
  double seconds = 0.0;
};

// The input files of a render from its name template: reads the first tile's metadata for the grid
// and lists one name per tile (existing or not; assemble() reports the missing ones).
std::vector<std::string> template_inputs(const std::string& name_template);

// Checks and stitches `inputs` into `output` (atomically). `settings` chooses the output pixel type
// (bits 0 = by extension) and compression.
AssembleResult assemble(const std::vector<std::string>& inputs, const std::string& output,
                        const OutputSettings& settings);

}  // namespace stex::farm
