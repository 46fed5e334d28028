// Validation of the kind-neutral render parameters and regions. See render_params.h.
#include "core/render_params.h"

#include <cmath>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/format.h"

namespace stex {

namespace {

[[noreturn]] void usage(const std::string& message) { throw Error(ErrorKind::Usage, message); }

std::string num(double v) { return exact_number(v); }

}  // namespace

void validate_render_params(const RenderParams& p) {
  if (!std::isfinite(p.mni) || p.mni <= 0.0 || p.mni > k_max_mni)
    usage("--mni must be in (0, " + num(k_max_mni) + "], got " + num(p.mni));
  if (!std::isfinite(p.cell_factor) || p.cell_factor < k_min_cell_factor || p.cell_factor > k_max_cell_factor)
    usage("--cell (cell side as a fraction of the texton support) must be in [" + num(k_min_cell_factor) + ", " +
          num(k_max_cell_factor) + "], got " + num(p.cell_factor));
  if (!std::isfinite(p.scale) || p.scale < k_min_scale || p.scale > k_max_scale)
    usage("--scale must be in [1/1024, 1024], got " + num(p.scale));
}

void validate_region(std::int64_t x, std::int64_t y, std::int64_t width, std::int64_t height) {
  if (width < 1 || height < 1)
    usage("region size must be at least 1x1, got " + std::to_string(width) + "x" + std::to_string(height));
  auto check = [](std::int64_t o, std::int64_t n, const char* axis) {
    const std::int64_t lim = k_max_pixel_coordinate;
    if (o <= -lim || o >= lim || n >= lim || (o < 0 ? -o : o) >= lim - n)
      usage(std::string("region ") + axis + " origin " + std::to_string(o) + " with size " + std::to_string(n) +
            " exceeds the coordinate range: |origin| + size must be below 2^46");
  };
  check(x, width, "x");
  check(y, height, "y");
}

}  // namespace stex
