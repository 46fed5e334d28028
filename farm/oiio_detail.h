// Private to stex_farm: the OIIO side of farm outputs (spec construction with the stex metadata, pixel
// types by extension). Kept out of the public headers so that users of farm/ do not need OIIO's.
#pragma once
#include <OpenImageIO/imageio.h>

#include <string>

#include "farm/output_file.h"

namespace stex::farm::detail {

// Pixel type for `path` (by extension) and `bits` (OutputSettings); Error(Usage) when unsupported.
OIIO::TypeDesc pixel_typedesc(const std::string& path, int bits);

// A spec for a file holding the window (x, y, width, height) of the full image described by `id`, with
// full_* set to the full image and all stex attributes. tile_index -1 = the whole image.
OIIO::ImageSpec make_output_spec(const std::string& path, const RenderIdentity& id,
                                 const OutputSettings& settings, std::int64_t tile_index, int x, int y,
                                 int width, int height);

// Lower-case extension without the dot ("exr"), "" when none.
std::string lower_extension(const std::string& path);

}  // namespace stex::farm::detail
