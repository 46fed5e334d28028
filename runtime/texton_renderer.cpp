// Texton noise renderer: strategy choice, chunking, launches (S1 §8). See texton_renderer.h.
#include "runtime/texton_renderer.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>

#include "runtime/cl_error.h"
#include "runtime/error.h"

namespace stex {

namespace {

constexpr std::size_t k_default_chunk_pixels = std::size_t(1) << 24;  // 16 Mi pixels per launch

// Fault injection for the hardening tests (docs/hardening.md): STEX_FAULT_DEVICE_LAUNCH=N makes the N-th
// kernel launch of the process (1-based) fail as a lost device does (CL_OUT_OF_RESOURCES, retryable), so
// that "a device error mid-run exits 75 and leaves no partial output" can be tested on a CPU device.
void maybe_inject_device_fault() {
  static const long k_fail_at = [] {
    const char* v = std::getenv("STEX_FAULT_DEVICE_LAUNCH");
    return v ? std::atol(v) : 0L;
  }();
  static std::atomic<long> launches{0};
  if (k_fail_at > 0 && ++launches == k_fail_at)
    throw OpenCLError("clEnqueueNDRangeKernel", -5, "injected by STEX_FAULT_DEVICE_LAUNCH");
}
constexpr std::array<std::size_t, 2> k_splat_local{1, 4};
constexpr std::array<std::size_t, 2> k_gather_local{16, 4};

std::size_t round_up(std::size_t v, std::size_t m) { return (v + m - 1) / m * m; }

bool same_params(const RenderParams& a, const RenderParams& b) {
  return a.mni == b.mni && a.cell_factor == b.cell_factor && a.seed == b.seed && a.scale == b.scale;
}

}  // namespace

TextonStrategy parse_texton_strategy(const std::string& name) {
  if (name == "auto") return TextonStrategy::Auto;
  if (name == "splat") return TextonStrategy::Splat;
  if (name == "gather") return TextonStrategy::Gather;
  throw Error(ErrorKind::Usage, "unknown strategy '" + name + "' (expected auto, splat or gather)");
}

const char* texton_strategy_name(TextonStrategy strategy) {
  switch (strategy) {
    case TextonStrategy::Auto: return "auto";
    case TextonStrategy::Splat: return "splat";
    case TextonStrategy::Gather: return "gather";
  }
  return "?";
}

TextonRenderer::TextonRenderer(Context& ctx, const TextonModel& model) : ctx_(ctx), model_(model) {
  // The padded alpha depends on the model only: build it once with default parameters.
  TextonSetup setup = make_texton_setup(model_, RenderParams{});
  alpha_ = Buffer<float>(ctx_, setup.alpha_padded, CL_MEM_READ_ONLY, "texton alpha");
  setup_params_ = RenderParams{};
  table_ = Buffer<std::uint32_t>(ctx_, setup.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
  setup_ = std::make_unique<TextonSetup>(std::move(setup));
}

TextonStrategy TextonRenderer::resolve(TextonStrategy strategy) const {
  if (strategy != TextonStrategy::Auto) return strategy;
  return (ctx_.info().type & CL_DEVICE_TYPE_CPU) ? TextonStrategy::Splat : TextonStrategy::Gather;
}

const TextonSetup& TextonRenderer::setup_for(const RenderParams& params) {
  if (!same_params(params, setup_params_)) {
    auto setup = std::make_unique<TextonSetup>(make_texton_setup(model_, params));
    if (setup->poisson_table != setup_->poisson_table)
      table_ = Buffer<std::uint32_t>(ctx_, setup->poisson_table, CL_MEM_READ_ONLY, "Poisson table");
    setup_ = std::move(setup);
    setup_params_ = params;
  }
  return *setup_;
}

TextonRenderStats TextonRenderer::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width,
                                         int height, float* out, const TextonRenderOptions& options) {
  validate_region(x, y, width, height);
  if (options.splat_strip < 1 || options.splat_band < 1)
    throw Error(ErrorKind::Usage, "splat blocks must be at least 1x1 pixel, got " + std::to_string(options.splat_strip) +
                                      "x" + std::to_string(options.splat_band));
  const TextonSetup& setup = setup_for(params);
  const int nc = setup.channels;
  TextonRenderStats stats;
  stats.strategy = resolve(options.strategy);
  const bool splat = stats.strategy == TextonStrategy::Splat;

  // Chunk size: bounded by the caller's cap, the default, and the device's largest allocation.
  std::size_t max_pixels = options.max_chunk_pixels ? options.max_chunk_pixels : k_default_chunk_pixels;
  const std::uint64_t alloc_pixels = ctx_.info().max_alloc / (std::uint64_t(nc) * sizeof(float));
  max_pixels = std::size_t(std::min<std::uint64_t>(max_pixels, alloc_pixels));
  if (max_pixels == 0) throw Error(ErrorKind::Limit, "device '" + ctx_.info().name + "' cannot allocate one pixel");
  const int chunk_w = int(std::min<std::size_t>(std::size_t(width), max_pixels));
  const int chunk_h = int(std::min<std::size_t>(std::size_t(height), std::max<std::size_t>(1, max_pixels / chunk_w)));

  Buffer<float> device_out(ctx_, std::size_t(chunk_w) * std::size_t(chunk_h) * std::size_t(nc), CL_MEM_READ_WRITE,
                           "render chunk");
  std::vector<float> planar(device_out.size());

  Kernel* kernel = nullptr;
  if (splat) {
    if (!splat_) {
      const std::string opts = "-DSTEX_SPLAT_CHANNELS=" + std::to_string(nc);
      splat_ = std::make_unique<Kernel>(ctx_.program("texton_splat.cl", opts), "texton_splat");
    }
    kernel = splat_.get();
  } else {
    if (!gather_) gather_ = std::make_unique<Kernel>(ctx_.program("texton_gather.cl"), "texton_gather");
    kernel = gather_.get();
  }
  const std::array<std::size_t, 2> local =
      (options.local_size[0] && options.local_size[1]) ? options.local_size : (splat ? k_splat_local : k_gather_local);

  for (int cy = 0; cy < height; cy += chunk_h) {
    const int h = std::min(chunk_h, height - cy);
    for (int cx = 0; cx < width; cx += chunk_w) {
      const int w = std::min(chunk_w, width - cx);
      const std::int64_t ox = x + cx, oy = y + cy;
      const int pitch = w;
      cl_uint a = 0;
      kernel->set_arg(a++, setup.params);
      kernel->set_arg(a++, alpha_);
      kernel->set_arg(a++, table_);
      kernel->set_arg(a++, cl_long(ox));
      kernel->set_arg(a++, cl_long(oy));
      kernel->set_arg(a++, cl_int(w));
      kernel->set_arg(a++, cl_int(h));
      kernel->set_arg(a++, cl_int(pitch));
      std::size_t gx = std::size_t(w), gy = std::size_t(h);
      if (splat) {
        kernel->set_arg(a++, cl_int(options.splat_strip));
        kernel->set_arg(a++, cl_int(options.splat_band));
        gx = (gx + std::size_t(options.splat_strip) - 1) / std::size_t(options.splat_strip);
        gy = (gy + std::size_t(options.splat_band) - 1) / std::size_t(options.splat_band);
      }
      kernel->set_arg(a++, device_out);
      const NDRange global(round_up(gx, local[0]), round_up(gy, local[1]));
      maybe_inject_device_fault();
      stats.device_ms += kernel->launch(ctx_, global, NDRange(local[0], local[1]));
      ++stats.launches;
      ++stats.chunks;

      // Planar (pitch x h per channel) -> the caller's interleaved image.
      const std::size_t plane = std::size_t(pitch) * std::size_t(h);
      device_out.read(planar.data(), plane * std::size_t(nc));
      for (int j = 0; j < h; ++j) {
        float* dst = out + ((std::size_t(cy) + std::size_t(j)) * std::size_t(width) + std::size_t(cx)) * std::size_t(nc);
        const std::size_t row = std::size_t(j) * std::size_t(pitch);
        for (int i = 0; i < w; ++i)
          for (int c = 0; c < nc; ++c) dst[std::size_t(i) * nc + c] = planar[std::size_t(c) * plane + row + i];
      }
    }
  }
  return stats;
}

std::vector<float> TextonRenderer::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width,
                                          int height, const TextonRenderOptions& options, TextonRenderStats* stats) {
  validate_region(x, y, width, height);
  std::vector<float> out(std::size_t(width) * std::size_t(height) * std::size_t(model_.channels));
  TextonRenderStats s = render(params, x, y, width, height, out.data(), options);
  if (stats) *stats = s;
  return out;
}

TextonNoise::TextonNoise(Context& ctx, const TextonModel& model, const NoiseRendererOptions& options)
    : renderer_(ctx, model) {
  options_.strategy = parse_texton_strategy(options.strategy);
}

NoiseRenderStats TextonNoise::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width,
                                     int height, float* out) {
  const TextonRenderStats s = renderer_.render(params, x, y, width, height, out, options_);
  NoiseRenderStats r;
  r.strategy = texton_strategy_name(s.strategy);
  r.device_ms = s.device_ms;
  r.launches = s.launches;
  return r;
}

}  // namespace stex
