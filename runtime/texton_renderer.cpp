// Texton noise renderer: strategy choice, chunking, launches (S1 §8). See texton_renderer.h.
#include "runtime/texton_renderer.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>

#include "core/error.h"
#include "runtime/chunked_gather.h"
#include "runtime/cl_error.h"
#include "runtime/texton_filter.h"

namespace stex {

namespace {

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
constexpr std::array<std::size_t, 2> k_gather_tile{16, 16};  // gather-local's default tile
constexpr std::size_t k_min_tile = 4;                         // smaller tiles fall back to the plain gather

// Local memory of a gather-local work-group of `local` pixels: a count per cell within reach of the tile and
// the two position words (8 bytes) per impulse slot (kernels/texton_gather_local.cl).
struct LocalLayout {
  std::uint64_t cells = 0, slots = 0;
  std::uint64_t bytes() const { return cells * 4 + cells * slots * 8; }
};
LocalLayout local_layout(const stex_texton_params& p, const std::array<std::size_t, 2>& local) {
  LocalLayout l;
  l.cells = std::uint64_t(stex_texton_tile_cells_max(p, stex_i64(local[0]))) *
            std::uint64_t(stex_texton_tile_cells_max(p, stex_i64(local[1])));
  l.slots = stex_texton_cell_slots(p);
  return l;
}

std::size_t round_up(std::size_t v, std::size_t m) { return (v + m - 1) / m * m; }

bool same_params(const RenderParams& a, const RenderParams& b) {
  return a.mni == b.mni && a.cell_factor == b.cell_factor && a.seed == b.seed && a.scale == b.scale &&
         texton_prefilters(a) == texton_prefilters(b);
}

}  // namespace

TextonStrategy parse_texton_strategy(const std::string& name) {
  if (name == "auto") return TextonStrategy::Auto;
  if (name == "splat") return TextonStrategy::Splat;
  if (name == "gather") return TextonStrategy::Gather;
  if (name == "gather-local") return TextonStrategy::GatherLocal;
  throw Error(ErrorKind::Usage, "unknown strategy '" + name + "' (expected auto, splat, gather or gather-local)");
}

const char* texton_strategy_name(TextonStrategy strategy) {
  switch (strategy) {
    case TextonStrategy::Auto: return "auto";
    case TextonStrategy::Splat: return "splat";
    case TextonStrategy::Gather: return "gather";
    case TextonStrategy::GatherLocal: return "gather-local";
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

TextonStrategy resolve_texton_strategy(TextonStrategy strategy, cl_device_type type) {
  if (strategy != TextonStrategy::Auto) return strategy;
  if (type & CL_DEVICE_TYPE_CPU) return TextonStrategy::Splat;
  if (type & CL_DEVICE_TYPE_GPU) return TextonStrategy::GatherLocal;
  return TextonStrategy::Gather;
}

TextonStrategy TextonRenderer::resolve(TextonStrategy strategy) const {
  return resolve_texton_strategy(strategy, ctx_.info().type);
}

const TextonSetup& TextonRenderer::setup_for(const RenderParams& params) {
  if (!same_params(params, setup_params_)) {
    // A filtered minified view renders the box-prefiltered texton (runtime/texton_filter.h) with the same
    // impulses: its table replaces alpha until the parameters change back.
    auto setup = std::make_unique<TextonSetup>(make_filtered_texton_setup(model_, params));
    if (setup->poisson_table != setup_->poisson_table)
      table_ = Buffer<std::uint32_t>(ctx_, setup->poisson_table, CL_MEM_READ_ONLY, "Poisson table");
    if (setup->alpha_padded != setup_->alpha_padded)
      alpha_ = Buffer<float>(ctx_, setup->alpha_padded, CL_MEM_READ_ONLY, "texton alpha");
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
  // The box prefilter's table starts pixel_shift pixels early: pixel P is evaluated at P + pixel_shift.
  x += setup.pixel_shift;
  y += setup.pixel_shift;
  validate_region(x, y, width, height);
  const int nc = setup.channels;
  TextonRenderStats stats;
  stats.strategy = resolve(options.strategy);

  // gather-local: the tile (work-group) whose cells' impulses fit in local memory; none (down to 4 x 4, or
  // the caller's size) -> the plain gather.
  std::array<std::size_t, 2> tile{0, 0};
  LocalLayout layout;
  if (stats.strategy == TextonStrategy::GatherLocal) {
    // The device's local memory (CL_DEVICE_LOCAL_MEM_SIZE; 32 KiB on Mesa's llvmpipe): none, no local-memory
    // kernel is built at all.
    const std::uint64_t device_local = ctx_.info().local_mem;
    const std::uint64_t budget =
        options.local_mem_limit ? std::min<std::uint64_t>(options.local_mem_limit, device_local) : device_local;
    if (budget > 0 && !gather_local_)
      gather_local_ = std::make_unique<Kernel>(ctx_.program("texton_gather_local.cl"), "texton_gather_local");
    const bool fixed = options.local_size[0] && options.local_size[1];
    std::array<std::size_t, 2> t = fixed ? options.local_size : k_gather_tile;
    for (; budget > 0;) {
      const LocalLayout l = local_layout(setup.params, t);
      if (gather_local_->fit_local(ctx_, t) == t && l.bytes() <= budget) {
        tile = t;
        layout = l;
        break;
      }
      if (fixed || (t[0] <= k_min_tile && t[1] <= k_min_tile)) break;
      if (t[1] >= t[0])
        t[1] /= 2;
      else
        t[0] /= 2;
    }
    if (!tile[0]) stats.strategy = TextonStrategy::Gather;
  }
  bool splat = stats.strategy == TextonStrategy::Splat;
  bool gather_local = stats.strategy == TextonStrategy::GatherLocal;

  // Chunk size: bounded by the caller's cap, the default, and the device's largest allocation.
  std::size_t max_pixels = options.max_chunk_pixels ? options.max_chunk_pixels : default_chunk_pixels(nc);
  const std::uint64_t alloc_pixels = ctx_.info().max_alloc / (std::uint64_t(nc) * sizeof(float));
  max_pixels = std::size_t(std::min<std::uint64_t>(max_pixels, alloc_pixels));
  if (max_pixels == 0) throw Error(ErrorKind::Limit, "device '" + ctx_.info().name + "' cannot allocate one pixel");
  const int chunk_w = int(std::min<std::size_t>(std::size_t(width), max_pixels));
  const int chunk_h = int(std::min<std::size_t>(std::size_t(height), std::max<std::size_t>(1, max_pixels / chunk_w)));

  // The output chunk is kept across renders (as GatherChunking::out_buffer): no device allocation per frame.
  const std::size_t chunk_floats = std::size_t(chunk_w) * std::size_t(chunk_h) * std::size_t(nc);
  out_.reserve(ctx_, chunk_floats, CL_MEM_READ_WRITE, "render chunk");
  Buffer<float>& device_out = out_;
  std::vector<float> planar(chunk_floats);

  Kernel* kernel = nullptr;
  if (gather_local) {
    kernel = gather_local_.get();
  } else if (splat) {
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
      gather_local ? tile
                   : kernel->fit_local(ctx_, (options.local_size[0] && options.local_size[1])
                                                 ? options.local_size
                                                 : (splat ? k_splat_local : k_gather_local));
  stats.local_size = local;

  // The splat block: the caller's, or the smaller one earlier renders on this device fell back to.
  std::array<int, 2> block{options.splat_strip, options.splat_band};
  if (splat && splat_block_[0] > 0) block = {std::min(block[0], splat_block_[0]), std::min(block[1], splat_block_[1])};
  std::array<std::size_t, 2> launch_local = local;
  if (!watchdog_) watchdog_ = std::make_unique<LoopWatchdog>(ctx_);

  for (int cy = 0; cy < height; cy += chunk_h) {
    const int h = std::min(chunk_h, height - cy);
    for (int cx = 0; cx < width; cx += chunk_w) {
      const int w = std::min(chunk_w, width - cx);
      const std::int64_t ox = x + cx, oy = y + cy;
      const int pitch = w;
      for (;;) {
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
          kernel->set_arg(a++, cl_int(block[0]));
          kernel->set_arg(a++, cl_int(block[1]));
          gx = (gx + std::size_t(block[0]) - 1) / std::size_t(block[0]);
          gy = (gy + std::size_t(block[1]) - 1) / std::size_t(block[1]);
        }
        if (gather_local) {
          kernel->set_local_arg(a++, std::size_t(layout.cells) * sizeof(cl_uint));
          kernel->set_local_arg(a++, std::size_t(layout.cells * layout.slots) * sizeof(cl_uint2));
          kernel->set_arg(a++, cl_int(layout.cells));
          kernel->set_arg(a++, cl_int(layout.slots));
        }
        kernel->set_arg(a++, device_out);
        watchdog_->bind(*kernel, a);
        const NDRange global(round_up(gx, launch_local[0]), round_up(gy, launch_local[1]));
        maybe_inject_device_fault();
        stats.device_ms += kernel->launch(ctx_, global, NDRange(launch_local[0], launch_local[1]));
        ++stats.launches;
        if (!watchdog_->tripped()) break;
        // The driver cut this launch's loops short (loop_watchdog.h): its values are wrong. Re-run it with less
        // work per kernel invocation; no pixel depends on the split.
        ++stats.watchdog_retries;
        if (splat && (block[0] > 1 || block[1] > 1)) {
          if (block[0] >= block[1] * 4 || block[1] == 1)
            block[0] = (block[0] + 1) / 2;
          else
            block[1] = (block[1] + 1) / 2;
          splat_block_ = block;
        } else if (gather_local || splat) {
          // The plain gather: one work-item per pixel, no shared tile, the same bits. A splat block of one
          // pixel still sums every impulse of its cells in one invocation: the texton a few pixels wide and
          // the dense impulses of a deeply minified view (the box prefilter, runtime/texton_filter.h) can pass
          // the cap where a pixel's own impulses do not.
          if (!gather_) gather_ = std::make_unique<Kernel>(ctx_.program("texton_gather.cl"), "texton_gather");
          kernel = gather_.get();
          stats.strategy = TextonStrategy::Gather;
          launch_local = kernel->fit_local(ctx_, k_gather_local);
          gather_local = false;
          if (splat) splat_block_ = {0, 0};  // smaller blocks did not help: later renders start afresh
          splat = false;
        } else if (launch_local[0] * launch_local[1] > 1) {
          launch_local = {1, 1};
        } else {
          throw Error(ErrorKind::Device, LoopWatchdog::refusal(ctx_.info(), kernel->name()));
        }
      }
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
  stats.local_size = launch_local;
  if (splat) stats.splat_block = block;
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
