// Renders regions of an LRP noise model on an OpenCL device (S3 eq. 1, 2, 4; kernels/lrp.cl): uploads the
// model's tables once, builds the kernel, splits a region into row chunks that fit the device's allocation
// limit, and returns interleaved floats. One work-item per pixel (S3's per-pixel evaluation: 9 (J + L)
// special-function calls, §6.2); every pixel is independent, so the output is bit-identical to
// runtime/lrp_reference.h for any tiling, chunking and work-group size (tests/kernels/test_lrp.cpp).
//
// Render parameters: `seed` and `scale` apply; `mni` and `cell_factor` are ignored (they belong to the
// Poisson-driven kinds; LRP's lattice is part of the model). Two shapes of the same per-pixel gather, with the
// same bits: "gather" and "gather-padded" (see the constructor).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/lrp_model.h"
#include "runtime/noise_renderer.h"
#include "runtime/program.h"

namespace stex {

struct LrpRenderOptions {
  std::array<std::size_t, 2> local_size{0, 0};  // {0, 0}: the runtime chooses. Outputs never depend on it.
  std::size_t max_chunk_pixels = 0;             // 0: the allocation limit and 16 Mi pixels
};

class LrpNoise final : public NoiseRenderer {
 public:
  // Validates the model (Error(Input)), uploads its tables, builds kernels/lrp.cl. `options.strategy` is
  // "gather" (chunks of 16 cosines, each as long as the stratum needs: GPUs), "gather-padded" (chunks of 8,
  // every chunk computed whole, the lanes past J_S unused: what a CPU compiler vectorises; about 1.7x faster
  // than "gather" on the PoCL CPU device, docs/lrp.md) or "auto" (gather-padded on CPU devices, gather
  // otherwise); anything else is Error(Usage). Both give the same bits.
  LrpNoise(Context& ctx, const LrpModel& model, const NoiseRendererOptions& options = {});

  std::string kind() const override { return "lrp"; }
  int channels() const override { return model_.channels; }
  NoiseRenderStats render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                          float* out) override;
  NoiseRenderStats render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                          float* out, const LrpRenderOptions& options);
  std::vector<float> render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                            const LrpRenderOptions& options = {});
  const LrpModel& model() const { return model_; }

 private:
  Context& ctx_;
  LrpModel model_;
  Buffer<float> fdata_;
  std::vector<float> fdata_host_;  // what fdata_ holds (a filtered render uploads faded tables)
  Buffer<std::uint32_t> udata_;
  std::string strategy_;  // "gather" or "gather-padded"
  Kernel* kernel_ = nullptr;
  std::unique_ptr<Kernel> kernel_owned_;
};

}  // namespace stex
