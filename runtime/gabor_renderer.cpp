// Gabor noise renderer: setup, chunking, launches. See gabor_renderer.h.
#include "runtime/gabor_renderer.h"

#include <algorithm>
#include <vector>

#include "core/error.h"
#include "runtime/chunked_gather.h"

namespace stex {

namespace {
constexpr std::size_t k_default_chunk_pixels = std::size_t(1) << 24;
}  // namespace

GaborNoise::GaborNoise(Context& ctx, const GaborModel& model, const NoiseRendererOptions& options)
    : ctx_(ctx), model_(model), setup_(make_gabor_setup(model, RenderParams{})) {
  if (options.strategy != "auto" && options.strategy != "gather")
    throw Error(ErrorKind::Usage, "unknown strategy '" + options.strategy + "' for gabor noise (expected auto or gather)");
  comp_ = Buffer<float>(ctx_, setup_.components, CL_MEM_READ_ONLY, "gabor components");
  comp_table_ = Buffer<std::uint32_t>(ctx_, setup_.component_table, CL_MEM_READ_ONLY, "gabor component table");
  poisson_ = Buffer<std::uint32_t>(ctx_, setup_.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
}

NoiseRenderStats GaborNoise::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width,
                                    int height, float* out) {
  validate_region(x, y, width, height);
  if (params != setup_params_) {
    GaborSetup s = make_gabor_setup(model_, params);
    if (s.poisson_table != setup_.poisson_table)
      poisson_ = Buffer<std::uint32_t>(ctx_, s.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
    setup_ = std::move(s);
    setup_params_ = params;
  }
  if (!kernel_) kernel_ = std::make_unique<Kernel>(ctx_.program("gabor_gather.cl"), "gabor_gather");

  GatherChunking chunking;
  chunking.max_chunk_pixels = max_chunk_pixels ? max_chunk_pixels : k_default_chunk_pixels;
  if (local_size[0] && local_size[1]) chunking.local = local_size;
  return render_gather_chunks(ctx_, *kernel_, channels(), x, y, width, height, out, chunking,
                              [&](Kernel& k, cl_uint a, std::int64_t x0, std::int64_t y0) {
                                (void)x0;
                                (void)y0;
                                k.set_arg(a++, setup_.params);
                                k.set_arg(a++, comp_);
                                k.set_arg(a++, comp_table_);
                                k.set_arg(a++, poisson_);
                                return a;
                              });
}

}  // namespace stex
