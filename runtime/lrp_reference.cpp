// C++ reference evaluator: stex_lrp_eval per pixel. See lrp_reference.h.
#include "runtime/lrp_reference.h"

namespace stex {

LrpReference::LrpReference(const LrpModel& model, const RenderParams& params)
    : setup_(make_lrp_setup(model, params)) {}

LrpReference::LrpReference(LrpSetup setup) : setup_(std::move(setup)) {}

void LrpReference::eval_pixel(std::int64_t px, std::int64_t py, float* out) const {
  validate_region(px, py, 1, 1);
  float v[STEX_LRP_MAX_CHANNELS];
  stex_lrp_eval(setup_.params, setup_.fdata.data(), setup_.udata.data(), stex_lrp_pixel_fix(px),
                stex_lrp_pixel_fix(py), v);
  for (int c = 0; c < setup_.channels; ++c) out[c] = v[c];
}

std::vector<float> LrpReference::render(std::int64_t x, std::int64_t y, int width, int height) const {
  validate_region(x, y, width, height);
  const int nc = setup_.channels;
  std::vector<float> out(std::size_t(width) * std::size_t(height) * std::size_t(nc));
  float v[STEX_LRP_MAX_CHANNELS];
  for (int j = 0; j < height; ++j) {
    const std::int64_t fy = stex_lrp_pixel_fix(y + j);
    for (int i = 0; i < width; ++i) {
      stex_lrp_eval(setup_.params, setup_.fdata.data(), setup_.udata.data(), stex_lrp_pixel_fix(x + i), fy, v);
      for (int c = 0; c < nc; ++c) out[(std::size_t(j) * std::size_t(width) + std::size_t(i)) * nc + c] = v[c];
    }
  }
  return out;
}

}  // namespace stex
