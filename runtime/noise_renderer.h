// The interface every model kind's device evaluator implements (texton, and the kinds added beside it). A
// NoiseRenderer is built once per (context, model) — it uploads the model and builds its kernels — and then
// renders any region of the unbounded texture: the output is a pure function of (model, parameters, seed,
// pixel coordinates), never of the region's split into tiles or chunks, the work-group size or the run.
//
// Built from a stored model by make_noise_renderer (the kind table, model/kinds.h); the CLI's `stex render`, the
// farm layer (farm::RegionRenderer) and the service render every kind through it.
#pragma once
#include <cstdint>
#include <string>

#include "runtime/texton_params.h"

namespace stex {

// Options of a renderer that never change its output (how, not what).
struct NoiseRendererOptions {
  // Evaluation strategy: "auto" lets the kind choose for the device. A kind with several strategies (texton:
  // "splat", "gather") documents them; a kind with one rejects any other name with Error(Usage).
  std::string strategy = "auto";
};

struct NoiseRenderStats {
  std::string strategy;    // the strategy actually used
  double device_ms = 0.0;  // sum of the kernel launches' device times
  int launches = 0;
};

class NoiseRenderer {
 public:
  virtual ~NoiseRenderer() = default;
  // The model kind ("texton", ...), as stored in the model file.
  virtual std::string kind() const = 0;
  // Channels of the output (1..4).
  virtual int channels() const = 0;
  // Renders output pixels [x, x + width) x [y, y + height) into `out`: width * height * channels() floats,
  // interleaved (pixel (i, j) channel c at ((j * width) + i) * channels() + c). `params` are the render
  // parameters of runtime/texton_params.h: seed and scale apply to every kind; mni and cell_factor to the
  // kinds driven by a Poisson process (each kind documents which it reads). Validates the parameters and
  // the region (Error(Usage)); device failures are Error(Device) (retryable).
  virtual NoiseRenderStats render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                                  float* out) = 0;
};

}  // namespace stex
