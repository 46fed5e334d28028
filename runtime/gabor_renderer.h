// Renders regions of a Gabor noise model on an OpenCL device (kernels/gabor_gather.cl over
// kernels/shared/gabor.h): uploads the component tables once, rebuilds the Poisson table when the render
// parameters change, splits a region into chunks that fit the device's allocation limit. One strategy,
// "gather" (one work-item per pixel: what GPUs need; on PoCL's CPU device the ~60 kernel evaluations per
// pixel vectorise across work-items). Bit-identical to GaborReference for any tiling, chunking and
// work-group size (tests/gabor).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/gabor_params.h"
#include "runtime/noise_renderer.h"
#include "runtime/program.h"

namespace stex {

class GaborNoise final : public NoiseRenderer {
 public:
  // Validates the model (Error(Input)); options.strategy must be "auto" or "gather" (Error(Usage)).
  GaborNoise(Context& ctx, const GaborModel& model, const NoiseRendererOptions& options = {});
  std::string kind() const override { return "gabor"; }
  int channels() const override { return 1; }
  // Reads every field of RenderParams (mni: impulses per kernel disc; cell_factor: cell side / kernel radius).
  NoiseRenderStats render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                          float* out) override;

  // Tests: work-group size {x, y} ({0, 0}: default) and the largest chunk in pixels (0: device limit).
  std::array<std::size_t, 2> local_size{0, 0};
  std::size_t max_chunk_pixels = 0;
  const GaborModel& model() const { return model_; }

 private:
  Context& ctx_;
  GaborModel model_;
  RenderParams setup_params_;
  GaborSetup setup_;
  Buffer<float> comp_;
  Buffer<std::uint32_t> comp_table_, poisson_;
  std::unique_ptr<Kernel> kernel_;
};

}  // namespace stex
