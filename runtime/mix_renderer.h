// Renders regions of a noise-mixing model (S1 §7) on an OpenCL device (kernels/mix_gather.cl over
// kernels/shared/mix.h): uploads the K textons and the mixing map once, rebuilds the Poisson table when the
// render parameters change, splits a region into chunks that fit the device's allocation limit. One
// strategy, "gather" (one work-item per pixel). Bit-identical to MixReference for any tiling, chunking and
// work-group size (tests/mix).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/mix_model.h"
#include "runtime/noise_renderer.h"
#include "runtime/program.h"

namespace stex {

class MixNoise final : public NoiseRenderer {
 public:
  // Validates the model (Error(Input)); options.strategy must be "auto" or "gather" (Error(Usage)).
  MixNoise(Context& ctx, const MixModel& model, const NoiseRendererOptions& options = {});
  std::string kind() const override { return "mix"; }
  int channels() const override { return model_.channels; }
  // Reads every field of RenderParams (as texton noise: lambda = mni / r^2, cell side c r, seed, scale).
  NoiseRenderStats render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                          float* out) override;

  // Tests: work-group size {x, y} ({0, 0}: default) and the largest chunk in pixels (0: device limit).
  std::array<std::size_t, 2> local_size{0, 0};
  std::size_t max_chunk_pixels = 0;
  const MixModel& model() const { return model_; }

 private:
  Context& ctx_;
  MixModel model_;
  RenderParams setup_params_;
  MixSetup setup_;
  Buffer<float> alpha_, map_;
  Buffer<std::uint32_t> poisson_;
  std::unique_ptr<Kernel> kernel_;
};

}  // namespace stex
