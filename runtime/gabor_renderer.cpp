// Gabor noise renderer: setup, chunking, launches. See gabor_renderer.h.
#include "runtime/gabor_renderer.h"

#include <algorithm>
#include <vector>

#include "runtime/error.h"

namespace stex {

namespace {
constexpr std::size_t k_default_chunk_pixels = std::size_t(1) << 24;
constexpr std::array<std::size_t, 2> k_local{16, 4};
std::size_t round_up(std::size_t v, std::size_t m) { return (v + m - 1) / m * m; }
bool same(const RenderParams& a, const RenderParams& b) {
  return a.mni == b.mni && a.cell_factor == b.cell_factor && a.seed == b.seed && a.scale == b.scale;
}
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
  if (!same(params, setup_params_)) {
    GaborSetup s = make_gabor_setup(model_, params);
    if (s.poisson_table != setup_.poisson_table)
      poisson_ = Buffer<std::uint32_t>(ctx_, s.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
    setup_ = std::move(s);
    setup_params_ = params;
  }
  if (!kernel_) kernel_ = std::make_unique<Kernel>(ctx_.program("gabor_gather.cl"), "gabor_gather");

  std::size_t max_pixels = max_chunk_pixels ? max_chunk_pixels : k_default_chunk_pixels;
  max_pixels = std::size_t(std::min<std::uint64_t>(max_pixels, ctx_.info().max_alloc / sizeof(float)));
  if (max_pixels == 0) throw Error(ErrorKind::Limit, "device '" + ctx_.info().name + "' cannot allocate one pixel");
  const int chunk_w = int(std::min<std::size_t>(std::size_t(width), max_pixels));
  const int chunk_h = int(std::min<std::size_t>(std::size_t(height), std::max<std::size_t>(1, max_pixels / chunk_w)));
  Buffer<float> device_out(ctx_, std::size_t(chunk_w) * std::size_t(chunk_h), CL_MEM_READ_WRITE, "render chunk");
  std::vector<float> host(device_out.size());
  const std::array<std::size_t, 2> local = (local_size[0] && local_size[1]) ? local_size : k_local;

  NoiseRenderStats stats;
  stats.strategy = "gather";
  for (int cy = 0; cy < height; cy += chunk_h) {
    const int h = std::min(chunk_h, height - cy);
    for (int cx = 0; cx < width; cx += chunk_w) {
      const int w = std::min(chunk_w, width - cx);
      cl_uint a = 0;
      kernel_->set_arg(a++, setup_.params);
      kernel_->set_arg(a++, comp_);
      kernel_->set_arg(a++, comp_table_);
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
      device_out.read(host.data(), std::size_t(w) * std::size_t(h));
      for (int j = 0; j < h; ++j)
        std::copy(host.begin() + std::ptrdiff_t(j) * w, host.begin() + std::ptrdiff_t(j + 1) * w,
                  out + (std::size_t(cy) + std::size_t(j)) * std::size_t(width) + std::size_t(cx));
    }
  }
  return stats;
}

}  // namespace stex
