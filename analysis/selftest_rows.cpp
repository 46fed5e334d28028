// The self-test rows of a render (selftest_rows.h).
#include "analysis/selftest_rows.h"

#include "analysis/cs_rpn_model.h"
#include "analysis/cs_spot_model.h"
#include "analysis/mix.h"
#include "analysis/tb_model.h"
#include "runtime/cs_rpn.h"
#include "runtime/cs_spot.h"
#include "runtime/tb.h"
#include "runtime/texton_renderer.h"

namespace stex {

std::vector<SelftestRow> selftest_rows_for(const ModelContainer& model, const RenderParams& params,
                                           const NoiseRendererOptions& options, const DeviceInfo& device,
                                           const std::string& what) {
  const std::string& kind = model.kind;
  if (kind == "texton") {
    return {texton_selftest_row(texton_selftest_strategy(options.strategy, device), texton_from_container(model, what).order)};
  }
  if (kind == "mix") {
    const int order = mix_from_container(model, what).order;
    return {{kind, order == 1 ? "gather" : "gather order " + std::to_string(order)}};
  }
  if (kind == "tb" || kind == "cs-tb") {
    const TbModel m = tb_from_container(model, what);
    const TbSetup setup = make_tb_setup(m, params);
    if (setup.aligned) return {{kind, "aligned"}};
    return {{kind, setup.params.unit_scale ? "sub-pixel" : "scaled"}};
  }
  if (kind == "cs-spot")
    return {{kind, make_cs_spot_setup(cs_spot_from_container(model, what), params).params.canon ? "lattice" : "general"}};
  if (kind == "cs-rpn") return {{kind, cs_rpn_variant_name(cs_rpn_from_container(model, what).variant)}};
  if (kind == "lrp" || kind == "gabor") return {{kind, "gather"}};
  return {};  // a kind make_noise_renderer refuses (by name, Error(Input))
}

SelftestRow filtered_selftest_row(bool mapped) { return {"texton", mapped ? "mapped" : "filtered"}; }

}  // namespace stex
