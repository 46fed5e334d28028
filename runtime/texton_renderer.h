// Renders regions of a texton noise model on an OpenCL device (S1 eq. 1-3 evaluated per S1 §8): uploads the
// model once, builds the strip-splat and gather kernels (kernels/texton_splat.cl, kernels/texton_gather.cl),
// splits a region into chunks that fit the device's allocation limit, and returns interleaved floats.
//
// Strategies (all bit-identical to each other and to runtime/reference.h, for any tiling, chunking and
// work-group size; the tests check it):
//  - splat: each work-item owns a block of pixels (a strip of a band of rows) and adds the impulses that
//    reach it in the global order. Default on CPU devices: the impulse generation is shared by the block's
//    pixels and the innermost loop (the pixels of a row an impulse covers) is vectorised by LLVM; measured on
//    PoCL 3.1 it is 100-300x faster than gather (1024^2, support 64: about 11 ms grey, 30 ms RGB).
//  - gather: one work-item per pixel regenerates the impulses of the ~7 cells within reach (S1 §8). Default
//    on GPUs and other devices: it exposes one independent work-item per pixel, which is what SIMT
//    hardware needs, while the splat's serial per-strip loops expose 64x fewer work-items with divergent
//    trip counts.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/model.h"
#include "runtime/noise_renderer.h"
#include "runtime/program.h"
#include "runtime/texton_params.h"

namespace stex {

enum class TextonStrategy { Auto, Splat, Gather };

// "auto", "splat", "gather" <-> enum; parse throws stex::Error(Usage) naming the valid values.
TextonStrategy parse_texton_strategy(const std::string& name);
const char* texton_strategy_name(TextonStrategy strategy);

struct TextonRenderOptions {
  TextonStrategy strategy = TextonStrategy::Auto;
  // Work-group size override {x, y}; {0, 0} lets the renderer choose. For splat the x dimension counts
  // strips, for gather pixels. Outputs never depend on it (tests compare two sizes bit for bit).
  std::array<std::size_t, 2> local_size{0, 0};
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
  double device_ms = 0.0;                          // sum of the kernel launches' device times
  int launches = 0;
  int chunks = 0;
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
  std::unique_ptr<Kernel> splat_, gather_;
};

// Texton noise as a NoiseRenderer (kind "texton"): strategy "auto", "splat" or "gather"; reads every field of
// RenderParams.
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
