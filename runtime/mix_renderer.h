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
#include "runtime/gather_renderer.h"

namespace stex {

class MixNoise final : public GatherRenderer {
 public:
  // Validates the model (Error(Input)); options.strategy must be "auto" or "gather" (Error(Usage)).
  MixNoise(Context& ctx, const MixModel& model, const NoiseRendererOptions& options = {});
  std::string kind() const override { return "mix"; }
  int channels() const override { return model_.channels; }
  // render reads every field of RenderParams (as texton noise: lambda = mni / r^2, cell side c r, seed, scale).
  const MixModel& model() const { return model_; }

 private:
  void set_params(const RenderParams& params) override;
  cl_uint set_model_args(Kernel& kernel, cl_uint first) override;

  MixModel model_;
  MixSetup setup_;
  Buffer<float> alpha_, map_;
  Buffer<std::uint32_t> poisson_;
};

}  // namespace stex
