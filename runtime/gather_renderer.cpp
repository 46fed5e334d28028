// GatherRenderer (runtime/gather_renderer.h): the render loop every per-pixel renderer shares.
#include "runtime/gather_renderer.h"

#include "core/error.h"

namespace stex {

GatherRenderer::GatherRenderer(Context& ctx, const char* kind_name, const char* program, const char* entry,
                               const NoiseRendererOptions& options)
    : ctx_(ctx), program_(program), entry_(entry) {
  if (options.strategy != "auto" && options.strategy != "gather")
    throw Error(ErrorKind::Usage, "unknown strategy '" + options.strategy + "' for " + kind_name +
                                      " noise (expected auto or gather)");
}

NoiseRenderStats GatherRenderer::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width,
                                        int height, float* out) {
  validate_region(x, y, width, height);
  if (params != params_) {
    set_params(params);
    params_ = params;
  }
  if (!kernel_) kernel_ = std::make_unique<Kernel>(ctx_.program(program_), entry_);
  GatherChunking chunking;
  chunking.max_chunk_pixels = max_chunk_pixels ? max_chunk_pixels : default_chunk_pixels(channels());
  if (local_size[0] && local_size[1]) chunking.local = local_size;
  return render_gather_chunks(ctx_, *kernel_, channels(), x, y, width, height, out, chunking,
                              [&](Kernel& k, cl_uint first, std::int64_t, std::int64_t) {
                                return set_model_args(k, first);
                              });
}

}  // namespace stex
