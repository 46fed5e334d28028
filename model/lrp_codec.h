// The lrp codec (model/codecs.h says what every codec does; docs/model-format.md has the layout).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "model/container.h"
#include "runtime/lrp_model.h"

namespace stex {

ModelContainer to_container(const LrpModel& model);
LrpModel lrp_from_container(const ModelContainer& container, const std::string& what = "model");

}  // namespace stex
