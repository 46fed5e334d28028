// The C++ reference evaluator of texton noise (S1 eq. 1-3, §8 gather): kernels/shared/texton.h compiled as
// C++ and called once per pixel. Used by the tests (every kernel is compared against it bit for bit) and
// by baselines; it is not a product path (single-threaded, about 80 impulse evaluations per pixel).
#pragma once
#include <cstdint>
#include <vector>

#include "runtime/model.h"
#include "runtime/texton_params.h"

namespace stex {

class TextonReference {
 public:
  TextonReference(const TextonModel& model, const RenderParams& params);
  explicit TextonReference(TextonSetup setup);

  // Output pixels [x, x + width) x [y, y + height), interleaved: pixel (i, j) channel c at
  // ((j * width) + i) * channels + c. Validates the region (stex::Error(Usage)).
  std::vector<float> render(std::int64_t x, std::int64_t y, int width, int height) const;

  // Point query at fixed-point coordinates (STEX_FIX_BITS fractional bits, output pixel units): out[c] for
  // c < channels(). The centre of output pixel P is stex_pixel_fix(P).
  void eval_fixed(std::int64_t fx, std::int64_t fy, float* out) const;
  // Point query at the centre of output pixel (px, py).
  void eval_pixel(std::int64_t px, std::int64_t py, float* out) const;

  // Number of impulses of cell (kx, ky) (the integer every strategy agrees on).
  std::uint32_t cell_count(std::int64_t kx, std::int64_t ky) const;

  int channels() const { return setup_.channels; }
  const TextonSetup& setup() const { return setup_; }

 private:
  TextonSetup setup_;
};

}  // namespace stex
