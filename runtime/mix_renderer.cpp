// Noise-mixing renderer: setup, chunking, launches. See mix_renderer.h.
#include "runtime/mix_renderer.h"

#include <algorithm>
#include <vector>

#include "core/error.h"
#include "runtime/chunked_gather.h"

namespace stex {

namespace {
constexpr std::size_t k_default_chunk_pixels = std::size_t(1) << 22;
}  // namespace

MixNoise::MixNoise(Context& ctx, const MixModel& model, const NoiseRendererOptions& options)
    : ctx_(ctx), model_(model), setup_(make_mix_setup(model, RenderParams{})) {
  if (options.strategy != "auto" && options.strategy != "gather")
    throw Error(ErrorKind::Usage, "unknown strategy '" + options.strategy + "' for mix noise (expected auto or gather)");
  alpha_ = Buffer<float>(ctx_, setup_.alpha_levels, CL_MEM_READ_ONLY, "mix textons");
  map_ = Buffer<float>(ctx_, setup_.map, CL_MEM_READ_ONLY, "mixing map");
  poisson_ = Buffer<std::uint32_t>(ctx_, setup_.texton.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
}

NoiseRenderStats MixNoise::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                                  float* out) {
  validate_region(x, y, width, height);
  if (params != setup_params_) {
    // The textons' padding and the map do not depend on the parameters: only the grid and the table change.
    MixSetup s = make_mix_setup(model_, params);
    if (s.texton.poisson_table != setup_.texton.poisson_table)
      poisson_ = Buffer<std::uint32_t>(ctx_, s.texton.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
    setup_ = std::move(s);
    setup_params_ = params;
  }
  if (!kernel_) kernel_ = std::make_unique<Kernel>(ctx_.program("mix_gather.cl"), "mix_gather");

  GatherChunking chunking;
  chunking.max_chunk_pixels = max_chunk_pixels ? max_chunk_pixels : k_default_chunk_pixels;
  if (local_size[0] && local_size[1]) chunking.local = local_size;
  return render_gather_chunks(ctx_, *kernel_, channels(), x, y, width, height, out, chunking,
                              [&](Kernel& k, cl_uint a, std::int64_t x0, std::int64_t y0) {
                                (void)x0;
                                (void)y0;
                                k.set_arg(a++, setup_.texton.params);
                                k.set_arg(a++, setup_.mix);
                                k.set_arg(a++, alpha_);
                                k.set_arg(a++, map_);
                                k.set_arg(a++, poisson_);
                                return a;
                              });
}

}  // namespace stex
