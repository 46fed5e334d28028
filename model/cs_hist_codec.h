// The histogram-transfer (cs-spot and cs-tb files) codec (model/codecs.h says what every codec does; docs/model-format.md has the layout).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "model/container.h"
#include "runtime/cs_hist.h"

namespace stex {

// The histogram-transfer table that cs-spot and cs-tb files may carry: metadata "histogram": {"mode", "delta",
// "bins": [m0, m1], "q", "pca"} (absent for mode none: files written before the transfer existed load as mode
// none), the quantiles (then the basis if "pca") appended to the payload. The reader takes them off the end
// of `c`'s payload, which it shortens; Error(Input) for a malformed field or a payload too short.
void cs_hist_to_container(const CsHistTable& t, ModelContainer& c);
CsHistTable cs_hist_from_container(ModelContainer& c, int channels, const std::string& what);

}  // namespace stex
