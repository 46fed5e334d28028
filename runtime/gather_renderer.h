// The skeleton of the per-pixel ("gather") renderers: the parameter cache (the kind's setup is rebuilt only
// when the RenderParams change), the kernel built on the first render, the chunked launch and read-back of
// runtime/chunked_gather.h with one default chunk size, and the test hooks (work-group size, chunk cap). A
// kind implements its setup and its kernel's leading arguments only (gabor, mix, cs-rpn).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "runtime/chunked_gather.h"
#include "runtime/context.h"
#include "runtime/noise_renderer.h"
#include "runtime/program.h"

namespace stex {

class GatherRenderer : public NoiseRenderer {
 public:
  NoiseRenderStats render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                          float* out) final;

  // Tests: work-group size {x, y} ({0, 0}: default) and the largest chunk in pixels (0: default_chunk_pixels).
  std::array<std::size_t, 2> local_size{0, 0};
  std::size_t max_chunk_pixels = 0;

 protected:
  // The kernel is entry point `entry` of `program` (kernels/). options.strategy must be "auto" or "gather"
  // (Error(Usage) naming `kind_name`). The subclass builds its setup for RenderParams{} in its constructor.
  GatherRenderer(Context& ctx, const char* kind_name, const char* program, const char* entry,
                 const NoiseRendererOptions& options);
  // Rebuilds the kind's setup for `params` (and re-uploads the tables that changed).
  virtual void set_params(const RenderParams& params) = 0;
  // Sets the kernel's leading (model) arguments from index `first`; returns the next index.
  virtual cl_uint set_model_args(Kernel& kernel, cl_uint first) = 0;

  Context& ctx_;

 private:
  const char* program_;
  const char* entry_;
  RenderParams params_;  // those of the current setup
  std::unique_ptr<Kernel> kernel_;
};

}  // namespace stex
