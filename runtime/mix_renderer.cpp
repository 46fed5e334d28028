// Noise-mixing renderer: setup, chunking, launches. See mix_renderer.h.
#include "runtime/mix_renderer.h"

#include <algorithm>
#include <vector>

#include "runtime/error.h"

namespace stex {

namespace {
constexpr std::size_t k_default_chunk_pixels = std::size_t(1) << 22;
constexpr std::array<std::size_t, 2> k_local{16, 4};
std::size_t round_up(std::size_t v, std::size_t m) { return (v + m - 1) / m * m; }
bool same(const RenderParams& a, const RenderParams& b) {
  return a.mni == b.mni && a.cell_factor == b.cell_factor && a.seed == b.seed && a.scale == b.scale;
}
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
  if (!same(params, setup_params_)) {
    // The textons' padding and the map do not depend on the parameters: only the grid and the table change.
    MixSetup s = make_mix_setup(model_, params);
    if (s.texton.poisson_table != setup_.texton.poisson_table)
      poisson_ = Buffer<std::uint32_t>(ctx_, s.texton.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
    setup_ = std::move(s);
    setup_params_ = params;
  }
  if (!kernel_) kernel_ = std::make_unique<Kernel>(ctx_.program("mix_gather.cl"), "mix_gather");

  const int nc = model_.channels;
  std::size_t max_pixels = max_chunk_pixels ? max_chunk_pixels : k_default_chunk_pixels;
  max_pixels = std::size_t(std::min<std::uint64_t>(max_pixels, ctx_.info().max_alloc / (sizeof(float) * nc)));
  if (max_pixels == 0) throw Error(ErrorKind::Limit, "device '" + ctx_.info().name + "' cannot allocate one pixel");
  const int chunk_w = int(std::min<std::size_t>(std::size_t(width), max_pixels));
  const int chunk_h = int(std::min<std::size_t>(std::size_t(height), std::max<std::size_t>(1, max_pixels / chunk_w)));
  Buffer<float> device_out(ctx_, std::size_t(chunk_w) * std::size_t(chunk_h) * nc, CL_MEM_READ_WRITE, "render chunk");
  std::vector<float> host(device_out.size());
  const std::array<std::size_t, 2> local = (local_size[0] && local_size[1]) ? local_size : k_local;

  NoiseRenderStats stats;
  stats.strategy = "gather";
  for (int cy = 0; cy < height; cy += chunk_h) {
    const int h = std::min(chunk_h, height - cy);
    for (int cx = 0; cx < width; cx += chunk_w) {
      const int w = std::min(chunk_w, width - cx);
      cl_uint a = 0;
      kernel_->set_arg(a++, setup_.texton.params);
      kernel_->set_arg(a++, setup_.mix);
      kernel_->set_arg(a++, alpha_);
      kernel_->set_arg(a++, map_);
      kernel_->set_arg(a++, poisson_);
      kernel_->set_arg(a++, cl_long(x + cx));
      kernel_->set_arg(a++, cl_long(y + cy));
      kernel_->set_arg(a++, cl_int(w));
      kernel_->set_arg(a++, cl_int(h));
      kernel_->set_arg(a++, cl_int(w));
      kernel_->set_arg(a++, device_out);
      stats.device_ms += kernel_->launch(ctx_, NDRange(round_up(std::size_t(w), local[0]), round_up(std::size_t(h), local[1])),
                                         NDRange(local[0], local[1]));
      ++stats.launches;
      const std::size_t row = std::size_t(w) * nc;
      device_out.read(host.data(), row * std::size_t(h));
      for (int j = 0; j < h; ++j)
        std::copy(host.begin() + std::ptrdiff_t(j * row), host.begin() + std::ptrdiff_t((j + 1) * row),
                  out + ((std::size_t(cy) + std::size_t(j)) * std::size_t(width) + std::size_t(cx)) * nc);
    }
  }
  return stats;
}

}  // namespace stex
