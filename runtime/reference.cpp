// C++ reference evaluator: stex_texton_eval per pixel (S1 §8 gather). See reference.h.
#include "runtime/reference.h"

#include "core/error.h"

namespace stex {

TextonReference::TextonReference(const TextonModel& model, const RenderParams& params)
    : setup_(make_texton_setup(model, params)) {}

TextonReference::TextonReference(TextonSetup setup) : setup_(std::move(setup)) {}

void TextonReference::eval_fixed(std::int64_t fx, std::int64_t fy, float* out) const {
  float v[STEX_MAX_CHANNELS];
  stex_texton_eval(setup_.params, setup_.alpha_padded.data(), setup_.poisson_table.data(), fx, fy, v);
  for (int c = 0; c < setup_.channels; ++c) out[c] = v[c];
}

void TextonReference::eval_pixel(std::int64_t px, std::int64_t py, float* out) const {
  validate_region(px, py, 1, 1);
  eval_fixed(stex_pixel_fix(px), stex_pixel_fix(py), out);
}

std::uint32_t TextonReference::cell_count(std::int64_t kx, std::int64_t ky) const {
  return stex_texton_count(setup_.params, stex_cell_key(kx, ky), setup_.poisson_table.data());
}

std::vector<float> TextonReference::render(std::int64_t x, std::int64_t y, int width, int height) const {
  validate_region(x, y, width, height);
  x += setup_.pixel_shift;  // the box prefilter's setup (runtime/texton_filter.h)
  y += setup_.pixel_shift;
  validate_region(x, y, width, height);
  const int nc = setup_.channels;
  std::vector<float> out(std::size_t(width) * std::size_t(height) * std::size_t(nc));
  for (int j = 0; j < height; ++j) {
    const std::int64_t fy = stex_pixel_fix(y + j);
    for (int i = 0; i < width; ++i)
      eval_fixed(stex_pixel_fix(x + i), fy, &out[(std::size_t(j) * std::size_t(width) + std::size_t(i)) * nc]);
  }
  return out;
}

}  // namespace stex
