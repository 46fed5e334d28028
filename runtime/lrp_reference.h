// The C++ reference evaluator of LRP noise (S3 eq. 1, 2, 4): kernels/shared/lrp.h compiled as C++ and called
// once per pixel. The tests compare the kernel against it bit for bit; the benchmark's plain C++ baseline is
// a separate -ffast-math build of the same algorithm (benchmarks/lrp_baseline.cpp).
#pragma once
#include <cstdint>
#include <vector>

#include "runtime/lrp_model.h"

namespace stex {

class LrpReference {
 public:
  LrpReference(const LrpModel& model, const RenderParams& params);
  explicit LrpReference(LrpSetup setup);

  // Output pixels [x, x + width) x [y, y + height), interleaved: pixel (i, j) channel c at
  // ((j * width) + i) * channels + c. Validates the region (stex::Error(Usage)).
  std::vector<float> render(std::int64_t x, std::int64_t y, int width, int height) const;
  // Point query at the centre of output pixel (px, py).
  void eval_pixel(std::int64_t px, std::int64_t py, float* out) const;

  int channels() const { return setup_.channels; }
  const LrpSetup& setup() const { return setup_; }

 private:
  LrpSetup setup_;
};

}  // namespace stex
