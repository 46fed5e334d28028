// Output name templates of farm renders: `out/gravel_{tx}_{ty}.exr`, `{index}`, zero padding `{tx:03}`,
// Mari-style `<UDIM>` (= 1001 + u + 10 v with u = tx < 10, v = ty), and `{{`/`}}` for literal braces.
// A name without any placeholder means "one large image" (farm/tiled_image_writer.h). Unknown or
// malformed placeholders are Error(Usage) naming them, so a typo never silently writes one file per task
// over the same name.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "farm/tile_grid.h"

namespace stex::farm {

class NameTemplate {
 public:
  // Parses `text`; Error(Usage) for unknown placeholders ({x}, {tile}, <UVTILE>...), bad padding
  // ({tx:3}, {tx:0}, padding above 20), unmatched braces.
  explicit NameTemplate(std::string text);

  const std::string& text() const { return text_; }
  bool has_placeholders() const;
  bool uses_udim() const;

  // Error(Usage) when the template cannot name every tile of `grid` distinctly: <UDIM> with more than 10
  // tiles per row, or a template that does not tell apart tiles of different columns (rows) when the grid
  // has more than one column (row).
  void check_grid(const TileGrid& grid) const;

  // The name of one tile. Error(Usage) for <UDIM> with tx >= 10.
  std::string format(const TileRect& tile) const;

 private:
  enum class Kind { Literal, Tx, Ty, Index, Udim };
  struct Part {
    Kind kind;
    std::string literal;
    int pad = 0;  // minimum digits, zero padded
  };
  std::string text_;
  std::vector<Part> parts_;
};

// 1001 + u + 10 v; Error(Usage) unless 0 <= u < 10 and 0 <= v.
int udim_number(int u, int v);

}  // namespace stex::farm
