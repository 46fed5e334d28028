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
#include "runtime/gather_renderer.h"

namespace stex {

class GaborNoise final : public GatherRenderer {
 public:
  // Validates the model (Error(Input)); options.strategy must be "auto" or "gather" (Error(Usage)).
  GaborNoise(Context& ctx, const GaborModel& model, const NoiseRendererOptions& options = {});
  std::string kind() const override { return "gabor"; }
  int channels() const override { return 1; }
  // render reads every field of RenderParams (mni: impulses per kernel disc; cell_factor: cell side / kernel
  // radius).
  const GaborModel& model() const { return model_; }

 private:
  void set_params(const RenderParams& params) override;
  cl_uint set_model_args(Kernel& kernel, cl_uint first) override;

  GaborModel model_;
  GaborSetup setup_;
  Buffer<float> comp_;
  Buffer<std::uint32_t> comp_table_, poisson_;
};

}  // namespace stex
