// The cs-spot codec (model/codecs.h says what every codec does; docs/model-format.md has the layout).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "model/container.h"
#include "runtime/cs_spot.h"

namespace stex {

// The extra metadata a cs-spot file carries (not needed to render: provenance and the estimate's quality).
struct CsModelInfo {
  std::string exemplar_name;
  bool linear = false;
  bool estimated = false;
  double d = -1.0, confidence = -1.0;  // < 0: not computed
  int border = 0;
};
ModelContainer to_container(const CsSpotModel& model, const CsModelInfo& info = {});
CsSpotModel cs_spot_from_container(const ModelContainer& model, const std::string& what = "model");

}  // namespace stex
