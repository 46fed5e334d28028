// Which self-test rows (runtime/selftest.h) a render uses: the kind of a stored model and the evaluation path
// its renderer will take on a device with these parameters and options (texton: the strategy `auto` or the
// option resolves to there, and the order; tb / cs-tb: aligned, sub-pixel or scaled; cs-spot: lattice or
// general; cs-rpn: the variant; mix: the order). `stex render` and `stex serve` pass them to ensure_selftest
// before rendering.
#pragma once
#include <string>
#include <vector>

#include "model/codecs.h"
#include "runtime/device.h"
#include "runtime/noise_renderer.h"
#include "runtime/selftest.h"
#include "runtime/texton_params.h"

namespace stex {

// The rows of a render through make_noise_renderer (analysis/noise_kinds.h). Decodes the model with its
// kind's codec (the errors of make_noise_renderer: Error(Input), Error(Usage) for parameters the kind refuses).
std::vector<SelftestRow> selftest_rows_for(const ModelContainer& model, const RenderParams& params,
                                           const NoiseRendererOptions& options, const DeviceInfo& device,
                                           const std::string& what = "model");

// The row of a filtered texton render (runtime/texton_filter.h): "filtered" for the flat plane at a scale,
// "mapped" for a camera or a UV map.
SelftestRow filtered_selftest_row(bool mapped);

}  // namespace stex
