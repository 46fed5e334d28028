// Noise-mixing renderer: setup and kernel arguments over the GatherRenderer skeleton. See mix_renderer.h.
#include "runtime/mix_renderer.h"

namespace stex {

MixNoise::MixNoise(Context& ctx, const MixModel& model, const NoiseRendererOptions& options)
    : GatherRenderer(ctx, "mix", "mix_gather.cl", "mix_gather", options),
      model_(model),
      setup_(make_mix_setup(model, RenderParams{})) {
  alpha_ = Buffer<float>(ctx_, setup_.alpha_levels, CL_MEM_READ_ONLY, "mix textons");
  map_ = Buffer<float>(ctx_, setup_.map, CL_MEM_READ_ONLY, "mixing map");
  poisson_ = Buffer<std::uint32_t>(ctx_, setup_.texton.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
}

void MixNoise::set_params(const RenderParams& params) {
  // The textons' padding and the map do not depend on the parameters: only the grid and the table change.
  // A filtered minified view (RenderParams::filter, scale < 1) also changes the textons: the box-prefiltered
  // ones (runtime/mix_model.h), uploaded while the parameters ask for them.
  MixSetup s = make_mix_setup(model_, params);
  if (s.texton.poisson_table != setup_.texton.poisson_table)
    poisson_ = Buffer<std::uint32_t>(ctx_, s.texton.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
  if (s.alpha_levels != setup_.alpha_levels)
    alpha_ = Buffer<float>(ctx_, s.alpha_levels, CL_MEM_READ_ONLY, "mix textons");
  setup_ = std::move(s);
}

cl_uint MixNoise::set_model_args(Kernel& k, cl_uint a) {
  k.set_arg(a++, setup_.texton.params);
  k.set_arg(a++, setup_.mix);
  k.set_arg(a++, alpha_);
  k.set_arg(a++, map_);
  k.set_arg(a++, poisson_);
  return a;
}

}  // namespace stex
