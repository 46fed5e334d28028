// LRP renderer: uploads, chunking, launches. See lrp_renderer.h.
#include "runtime/lrp_renderer.h"

#include <algorithm>

#include "core/error.h"
#include "runtime/chunked_gather.h"
#include "runtime/loop_watchdog.h"

namespace stex {

LrpNoise::LrpNoise(Context& ctx, const LrpModel& model, const NoiseRendererOptions& options)
    : ctx_(ctx), model_(model) {
  if (options.strategy != "auto" && options.strategy != "gather" && options.strategy != "gather-padded")
    throw Error(ErrorKind::Usage, "unknown strategy '" + options.strategy +
                                      "' for an lrp model (expected auto, gather or gather-padded)");
  strategy_ = options.strategy != "auto" ? options.strategy
              : (ctx_.info().type & CL_DEVICE_TYPE_CPU) != 0 ? "gather-padded"
                                                             : "gather";
  const LrpSetup setup = make_lrp_setup(model_, RenderParams{});
  fdata_ = Buffer<float>(ctx_, setup.fdata, CL_MEM_READ_ONLY, "LRP tables");
  fdata_host_ = setup.fdata;
  udata_ = Buffer<std::uint32_t>(ctx_, setup.udata, CL_MEM_READ_ONLY, "LRP sub-strata");
  const char* shape = strategy_ == "gather-padded" ? "-DSTEX_LRP_PAD_CHUNKS -DSTEX_LRP_CHUNK=8u" : "";
  kernel_owned_ = std::make_unique<Kernel>(ctx_.program("lrp.cl", shape), "lrp_eval");
  kernel_ = kernel_owned_.get();
}

NoiseRenderStats LrpNoise::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width,
                                     int height, float* out) {
  return render(params, x, y, width, height, out, LrpRenderOptions{});
}

std::vector<float> LrpNoise::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width,
                                       int height, const LrpRenderOptions& options) {
  validate_region(x, y, width, height);
  std::vector<float> out(std::size_t(width) * std::size_t(height) * std::size_t(model_.channels));
  render(params, x, y, width, height, out.data(), options);
  return out;
}

NoiseRenderStats LrpNoise::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width,
                                     int height, float* out, const LrpRenderOptions& options) {
  validate_region(x, y, width, height);
  const LrpSetup setup = make_lrp_setup(model_, params);
  if (setup.fdata != fdata_host_) {  // a filtered render's faded colours and terms (RenderParams::filter)
    fdata_ = Buffer<float>(ctx_, setup.fdata, CL_MEM_READ_ONLY, "LRP tables");
    fdata_host_ = setup.fdata;
  }
  const std::size_t ch = std::size_t(model_.channels);
  const std::size_t row_bytes = std::size_t(width) * ch * sizeof(float);
  std::size_t limit = options.max_chunk_pixels ? options.max_chunk_pixels : default_chunk_pixels(model_.channels);
  const std::size_t alloc = std::size_t(ctx_.info().max_alloc);
  if (alloc > 0) limit = std::min(limit, std::max<std::size_t>(1, alloc / (ch * sizeof(float))));
  const int rows = int(std::max<std::size_t>(1, std::min<std::size_t>(std::size_t(height), limit / std::size_t(width))));
  if (row_bytes > alloc && alloc > 0)
    throw Error(ErrorKind::Limit, "one row of " + std::to_string(width) + " pixels exceeds the device's allocation limit");
  Buffer<float> dev(ctx_, std::size_t(rows) * std::size_t(width) * ch, CL_MEM_WRITE_ONLY, "LRP output");
  NoiseRenderStats stats;
  stats.strategy = strategy_;
  const bool fixed_local = options.local_size[0] && options.local_size[1];
  const std::array<std::size_t, 2> local = fixed_local ? kernel_->fit_local(ctx_, options.local_size)
                                                       : std::array<std::size_t, 2>{0, 0};
  const std::size_t lx = local[0], ly = local[1];
  LoopWatchdog watchdog(ctx_);
  for (int r0 = 0; r0 < height; r0 += rows) {
    const int h = std::min(rows, height - r0);
    kernel_->set_arg(0, setup.params);
    kernel_->set_arg(1, fdata_);
    kernel_->set_arg(2, udata_);
    const cl_long x0 = x, y0 = y + r0;
    kernel_->set_arg(3, x0);
    kernel_->set_arg(4, y0);
    const cl_int w = width, hh = h;
    kernel_->set_arg(5, w);
    kernel_->set_arg(6, hh);
    kernel_->set_arg(7, dev);
    stats.device_ms += launch_watched(ctx_, *kernel_, watchdog, 8, std::size_t(width), std::size_t(h), {lx, ly},
                                      &stats.launches);
    dev.read(out + std::size_t(r0) * std::size_t(width) * ch, std::size_t(h) * std::size_t(width) * ch);
  }
  return stats;
}

}  // namespace stex
