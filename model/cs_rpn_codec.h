// The cs-rpn codec (model/codecs.h says what every codec does; docs/model-format.md has the layout).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "model/container.h"
#include "runtime/cs_rpn.h"

namespace stex {

ModelContainer to_container(const CsRpnModel& model);
CsRpnModel cs_rpn_from_container(const ModelContainer& model, const std::string& what = "model");

}  // namespace stex
