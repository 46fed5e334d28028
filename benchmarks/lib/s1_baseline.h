// Host side of kernels/bench_s1_baseline.cl: the S1 texton noise evaluation as published (S1 §8: cells of
// r/1.6, impulses regenerated per pixel, Xorshift per cell, Gaussian-approximated counts), a performance
// baseline for `stex bench` only. Its output has the texton noise's mean and (up to the count approximation)
// variance but is not bit-identical to stex's kernels; see the kernel's header for what it does and why stex
// does not.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/model.h"
#include "runtime/program.h"

namespace stex::bench {

// The constants S1 §8 derives from (model, MNI).
struct S1Constants {
  double r = 0;          // texton reach s + order (the bilinear texton is non-zero on [-1, s)^2)
  double lambda = 0;     // MNI / r^2
  double cell = 0;       // grid cell side a = r / 1.6
  double cell_mean = 0;  // lambda a^2 = MNI / 1.6^2
};
S1Constants s1_constants(const TextonModel& model, double mni);

class S1BaselineRenderer {
 public:
  // Validates the model (stex::Error(Input)), uploads its padded alpha, builds the kernel for its channels.
  S1BaselineRenderer(Context& ctx, const TextonModel& model);

  // Renders output pixels [x0, x0 + width) x [y0, y0 + height) (float coordinates: keep |x0|, |y0| small) into
  // `planar` (channels planes of width * height floats) if not null. Returns the kernel's device time in ms.
  double render(double mni, std::uint32_t seed, int x0, int y0, int width, int height, float* planar);
  // Interleaved output (pixel (i, j) channel c at (j * width + i) * channels + c).
  std::vector<float> render_interleaved(double mni, std::uint32_t seed, int x0, int y0, int width, int height,
                                        double* device_ms = nullptr);

  int channels() const { return model_.channels; }

 private:
  Context& ctx_;
  TextonModel model_;
  Buffer<float> alpha_;
  Buffer<float> out_;
  std::array<double, 4> sum_alpha_{};
  std::unique_ptr<Kernel> kernel_;
};

}  // namespace stex::bench
