// The mix codec (model/codecs.h says what every codec does; docs/model-format.md has the layout).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "model/container.h"
#include "runtime/mix_model.h"

namespace stex {

ModelContainer to_container(const MixModel& model);
MixModel mix_from_container(const ModelContainer& model, const std::string& what = "model");

}  // namespace stex
