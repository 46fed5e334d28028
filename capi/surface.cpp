// C API surface-noise point queries (include/stex/stex.h "Surface noise"; S1 §6, Proposition 3): world
// positions with normals (and optional tangents) -> the values of runtime/surface.h's SurfaceRenderer, which
// equal its C++ reference SurfaceReference bit for bit. Every position and frame is checked and converted
// (positions to float, frames by surface_frame) before any device work; points go to the device in batches,
// and the values do not depend on the batch size.
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "capi/api_internal.h"

namespace stex::capi {
namespace {

static_assert(sizeof(std::size_t) != 8 || sizeof(stex_surface_eval_params) == k_surface_eval_params_v0_size,
              "stex_surface_eval_params changed size: append fields and keep k_surface_eval_params_v0_size");

constexpr std::size_t k_surface_batch = std::size_t(1) << 18;  // points converted and evaluated at once

stex_surface_eval_params default_surface_params() {
  const SurfaceParams s;
  stex_surface_eval_params p{};
  p.struct_size = sizeof p;
  p.mni = s.mni;
  p.cell_factor = s.cell_factor;
  p.texel = s.texel;
  p.seed = s.seed;
  p.reserved[0] = 0;
  p.reserved[1] = 0;
  return p;
}

// API misuse is STEX_INVALID_ARGUMENT, values out of range STEX_USAGE (validate_surface_params).
SurfaceParams read_surface_params(const stex_surface_eval_params* user) {
  const stex_surface_eval_params p =
      read_sized(user, default_surface_params(), k_surface_eval_params_v0_size, "stex_surface_eval_params");
  if (p.reserved[0] != 0 || p.reserved[1] != 0) invalid_argument("stex_surface_eval_params.reserved must be 0");
  SurfaceParams s;
  s.mni = p.mni;
  s.cell_factor = p.cell_factor;
  s.texel = p.texel;
  s.seed = p.seed;
  validate_surface_params(s);
  return s;
}

}  // namespace
}  // namespace stex::capi

using stex::capi::guard;
using stex::capi::invalid_argument;

extern "C" {

STEX_API stex_status stex_surface_eval_params_init(stex_surface_eval_params* params, size_t struct_size) {
  return guard("stex_surface_eval_params_init", [&] {
    if (!params) invalid_argument("params is NULL");
    stex::capi::write_sized(params, struct_size, stex::capi::default_surface_params(),
                            stex::capi::k_surface_eval_params_v0_size, "stex_surface_eval_params");
  });
}

STEX_API stex_status stex_eval_surface_points(stex_context* context, const stex_model* model,
                                              const stex_surface_eval_params* params, size_t count,
                                              const double* positions, const double* normals,
                                              const double* tangents, float* out) {
  using namespace stex::capi;
  return guard("stex_eval_surface_points", [&] {
    if (!context) invalid_argument("context is NULL");
    if (!model) invalid_argument("model is NULL");
    if (count > 0 && (!positions || !normals || !out)) invalid_argument("positions, normals or out is NULL");
    const stex::SurfaceParams sp = read_surface_params(params);
    const stex::TextonModel& texton = texton_of(*model, "surface point queries");
    if (count == 0) return;
    const std::size_t nc = std::size_t(texton.channels);
    if (count > std::numeric_limits<std::size_t>::max() / (9 * sizeof(double)))
      invalid_argument("count " + std::to_string(count) + " is too large");
    // Every position and frame is checked before any device work (the messages name the point).
    for (std::size_t k = 0; k < count; ++k) {
      stex::validate_surface_position(sp, positions + 3 * k, k);
      stex::surface_frame(normals + 3 * k, tangents ? tangents + 3 * k : nullptr, k);
    }

    stex_context& ctx = *context;
    std::lock_guard<std::mutex> lock(ctx.mutex);
    ModelEntry& entry = model_entry(ctx, *model);
    if (!entry.surface) entry.surface = std::make_unique<stex::SurfaceRenderer>(*ctx.ctx, texton);
    const std::size_t batch = std::min(count, k_surface_batch);
    std::vector<float> pos(3 * batch), frames(9 * batch);
    for (std::size_t k0 = 0; k0 < count; k0 += batch) {
      const std::size_t n = std::min(batch, count - k0);
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t k = k0 + i;
        for (int a = 0; a < 3; ++a) pos[3 * i + std::size_t(a)] = float(positions[3 * k + std::size_t(a)]);
        const std::array<float, 9> f = stex::surface_frame(normals + 3 * k, tangents ? tangents + 3 * k : nullptr, k);
        std::copy(f.begin(), f.end(), frames.begin() + std::ptrdiff_t(9 * i));
      }
      entry.surface->eval(sp, n, pos.data(), frames.data(), out + k0 * nc);
    }
  });
}

}  // extern "C"
