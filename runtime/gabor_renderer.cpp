// Gabor noise renderer: setup and kernel arguments over the GatherRenderer skeleton. See gabor_renderer.h.
#include "runtime/gabor_renderer.h"

namespace stex {

GaborNoise::GaborNoise(Context& ctx, const GaborModel& model, const NoiseRendererOptions& options)
    : GatherRenderer(ctx, "gabor", "gabor_gather.cl", "gabor_gather", options),
      model_(model),
      setup_(make_gabor_setup(model, RenderParams{})) {
  comp_ = Buffer<float>(ctx_, setup_.components, CL_MEM_READ_ONLY, "gabor components");
  comp_table_ = Buffer<std::uint32_t>(ctx_, setup_.component_table, CL_MEM_READ_ONLY, "gabor component table");
  poisson_ = Buffer<std::uint32_t>(ctx_, setup_.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
}

void GaborNoise::set_params(const RenderParams& params) {
  GaborSetup s = make_gabor_setup(model_, params);
  if (s.poisson_table != setup_.poisson_table)
    poisson_ = Buffer<std::uint32_t>(ctx_, s.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
  if (s.components != setup_.components)  // a filtered render's carriers and gains (gabor_filter)
    comp_ = Buffer<float>(ctx_, s.components, CL_MEM_READ_ONLY, "gabor components");
  setup_ = std::move(s);
}

cl_uint GaborNoise::set_model_args(Kernel& k, cl_uint a) {
  k.set_arg(a++, setup_.params);
  k.set_arg(a++, comp_);
  k.set_arg(a++, comp_table_);
  k.set_arg(a++, poisson_);
  return a;
}

}  // namespace stex
