// The texton codec (model/codecs.h says what every codec does; docs/model-format.md has the layout).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "model/container.h"
#include "runtime/model.h"

namespace stex {

ModelContainer to_container(const TextonModel& model);
TextonModel texton_from_container(const ModelContainer& model, const std::string& what = "model");
// Texton files: serialised (validating first) and parsed (every field checked; Error(Input) naming it).
std::vector<std::uint8_t> encode_model(const TextonModel& model);
TextonModel decode_model(const std::uint8_t* data, std::size_t size, const std::string& what = "model");
// Atomic (temp file beside the target + fsync + rename); Error(Output) on failure.
void save_model(const TextonModel& model, const std::string& path);
// The header's sizes are checked against the file length before the rest is read (Error(Input)).
TextonModel load_model(const std::string& path);

}  // namespace stex
