// Renders regions of a texton noise model on an OpenCL device (S1 eq. 1-3 evaluated per S1 §8): uploads the
// model once, builds the strip-splat and gather kernels (kernels/texton_splat.cl, kernels/texton_gather.cl,
// kernels/texton_gather_local.cl), splits a region into chunks that fit the device's allocation limit, and
// returns interleaved floats.
//
// Strategies (all bit-identical to each other and to runtime/reference.h, for any tiling, chunking and
// work-group size; the tests check it):
//  - splat: each work-item owns a block of pixels (a strip of a band of rows) and adds the impulses that
//    reach it in the global order. Default on CPU devices: the impulse generation is shared by the block's
//    pixels and the innermost loop (the pixels of a row an impulse covers) is vectorised by LLVM; measured on
//    PoCL 3.1 it is 100-300x faster than gather (1024^2, support 64: about 11 ms grey, 30 ms RGB). Where a
//    driver caps a kernel invocation's loop iterations (the loop watchdog, runtime/loop_watchdog.h; Mesa's
//    llvmpipe), a launch that trips it is re-run with half the block (strip first), down to 1 x 1 pixel and
//    one work-item per work-group, and later renders start from the block that passed.
//  - gather: one work-item per pixel regenerates the impulses of the ~7 cells within reach (S1 §8). Default
//    on devices that are neither CPUs nor GPUs (accelerators, custom devices): one independent work-item per
//    pixel and no local memory, the most portable form.
//  - gather-local: the gather with a work-group (16 x 16 pixels by default) sharing its tile's impulses in
//    local memory (S1 §8): the work-items generate the counts and positions of the tile's cells once, then
//    each sums its own cells' impulses in the gather's order with the gather's arithmetic. Default on GPUs
//    (CL_DEVICE_TYPE_GPU): it keeps one work-item per pixel, which is what SIMT hardware needs, and cuts the
//    hashing per pixel by the number of pixels sharing a cell. Local memory per work-group: 4 bytes per
//    cell plus 8 per impulse slot, cells = the tile's cells within reach (bounded by
//    stex_texton_tile_cells_max), slots per cell = the Poisson table's largest count. When that exceeds the
//    device's local memory (high MNI), a smaller tile (down to 4 x 4) is tried, then the plain gather
//    (TextonRenderStats::strategy says which ran). On PoCL's CPU device it costs about as much as gather
//    (~14 % less CPU time per frame, still ~100x the splat: local memory is ordinary RAM, barriers cost;
//    docs/benchmarks.md).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/loop_watchdog.h"
#include "runtime/model.h"
#include "runtime/noise_renderer.h"
#include "runtime/program.h"
#include "runtime/texton_params.h"

namespace stex {

enum class TextonStrategy { Auto, Splat, Gather, GatherLocal };

// "auto", "splat", "gather", "gather-local" <-> enum; parse throws stex::Error(Usage) naming the valid values.
TextonStrategy parse_texton_strategy(const std::string& name);
const char* texton_strategy_name(TextonStrategy strategy);

// What `Auto` resolves to on a device of type `type` (CL_DEVICE_TYPE_* bits): splat on CPUs, gather-local on
// GPUs, gather otherwise. Any other strategy is returned unchanged.
TextonStrategy resolve_texton_strategy(TextonStrategy strategy, cl_device_type type);

struct TextonRenderOptions {
  TextonStrategy strategy = TextonStrategy::Auto;
  // Work-group size override {x, y}; {0, 0} lets the renderer choose. For splat the x dimension counts
  // strips, for the gathers pixels (gather-local: the tile sharing local memory; if its impulses do not fit
  // in local memory the plain gather runs). Outputs never depend on it (tests compare sizes bit for bit).
  std::array<std::size_t, 2> local_size{0, 0};
  // gather-local: local memory available to a work-group in bytes (0: the device's CL_DEVICE_LOCAL_MEM_SIZE).
  // Smaller values force the smaller-tile and plain-gather fallbacks (tests).
  std::size_t local_mem_limit = 0;
  // A splat work-item's block: `splat_strip` pixels of `splat_band` rows (>= 1 each). Outputs never depend on
  // them; 256 x 16 measured fastest on PoCL 3.1 (impulse generation shared by 4096 pixels, spans rarely cut).
  int splat_strip = 256;
  int splat_band = 16;
  // Largest chunk in pixels per launch (0: the device's allocation limit and 16 Mi pixels). Outputs never
  // depend on it (tests force small chunks).
  std::size_t max_chunk_pixels = 0;
};

struct TextonRenderStats {
  TextonStrategy strategy = TextonStrategy::Auto;  // the strategy actually used (never Auto)
  std::array<std::size_t, 2> local_size{0, 0};      // the work-group size of the launches
  double device_ms = 0.0;                          // sum of the kernel launches' device times
  int launches = 0;
  int chunks = 0;
  // Launches re-run because the driver cut their loops short (the loop watchdog, runtime/loop_watchdog.h;
  // Mesa's llvmpipe), and the splat block the last launch used (smaller than the options' after such re-runs).
  int watchdog_retries = 0;
  std::array<int, 2> splat_block{0, 0};
};

class TextonRenderer {
 public:
  // Validates the model (stex::Error(Input)) and uploads the padded alpha planes.
  TextonRenderer(Context& ctx, const TextonModel& model);
  TextonRenderer(const TextonRenderer&) = delete;
  TextonRenderer& operator=(const TextonRenderer&) = delete;

  // Renders output pixels [x, x + width) x [y, y + height) into `out`, interleaved (width * height *
  // channels() floats; pixel (i, j) channel c at ((j * width) + i) * channels + c). Validates the
  // parameters and the region (stex::Error(Usage)).
  TextonRenderStats render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                           float* out, const TextonRenderOptions& options = {});
  std::vector<float> render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                            const TextonRenderOptions& options = {}, TextonRenderStats* stats = nullptr);

  // The strategy `Auto` resolves to on this renderer's device.
  TextonStrategy resolve(TextonStrategy strategy) const;
  int channels() const { return model_.channels; }
  const TextonModel& model() const { return model_; }
  Context& context() { return ctx_; }

 private:
  const TextonSetup& setup_for(const RenderParams& params);

  Context& ctx_;
  TextonModel model_;
  Buffer<float> alpha_;
  // Cached per RenderParams (the Poisson table depends on mni, cell factor and scale).
  std::unique_ptr<TextonSetup> setup_;
  RenderParams setup_params_;
  Buffer<std::uint32_t> table_;
  std::unique_ptr<Kernel> splat_, gather_, gather_local_;
  std::unique_ptr<LoopWatchdog> watchdog_;
  // The splat block after loop-watchdog re-runs on this device: later renders start from it ({0, 0}: none).
  std::array<int, 2> splat_block_{0, 0};
  Buffer<float> out_;  // the output chunk, kept across renders (grown when needed; every kernel writes all of it)
};

// Texton noise as a NoiseRenderer (kind "texton"): strategy "auto", "splat", "gather" or "gather-local"; reads
// every field of RenderParams.
class TextonNoise final : public NoiseRenderer {
 public:
  TextonNoise(Context& ctx, const TextonModel& model, const NoiseRendererOptions& options = {});
  std::string kind() const override { return "texton"; }
  int channels() const override { return renderer_.channels(); }
  NoiseRenderStats render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                          float* out) override;
  TextonRenderer& renderer() { return renderer_; }

 private:
  TextonRenderer renderer_;
  TextonRenderOptions options_;
};

}  // namespace stex
