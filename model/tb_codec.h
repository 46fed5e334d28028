// The tb and cs-tb (one codec: the kind says whether the model has periods) codec (model/codecs.h says what every codec does; docs/model-format.md has the layout).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "model/container.h"
#include "runtime/tb.h"

namespace stex {

ModelContainer to_container(const TbModel& model);
TbModel tb_from_container(const ModelContainer& model, const std::string& what = "model");

}  // namespace stex
