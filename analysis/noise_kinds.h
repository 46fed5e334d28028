// The registry of model kinds: builds the device evaluator (runtime/noise_renderer.h) of a stored model of
// any kind. One place lists the kinds stex renders; `stex render`, the farm layer and the service go
// through it, so a kind registered here gets single-image renders, tiles, out-of-core images and resume.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "analysis/model_file.h"
#include "runtime/context.h"
#include "runtime/noise_renderer.h"

namespace stex {

// The kinds make_noise_renderer knows, in the order they were added ("texton", ...).
std::vector<std::string> noise_kinds();

// Decodes the container with its kind's codec (Error(Input) naming a bad field, or an unknown kind) and
// builds its renderer on `ctx` (Error(Usage) for options the kind does not take; Error(Device) on device
// failure).
std::unique_ptr<NoiseRenderer> make_noise_renderer(Context& ctx, const ModelContainer& model,
                                                   const NoiseRendererOptions& options = {},
                                                   const std::string& what = "model");

// Decodes the container with its kind's codec, validating every field, without building a renderer (no
// device needed; = describe_noise_model below, result dropped): Error(Input) naming a bad field, or an
// unknown kind. The fuzz target and the damage sweep of the model loader go through it, so every registered
// kind's codec is covered.
void check_model(const ModelContainer& model, const std::string& what = "model");

// What a stored model of any kind renders, known without a device: its kind's codec decodes and validates it
// (the same checks as make_noise_renderer: Error(Input) naming a bad field, or an unknown kind). The C API
// (capi/model.cpp) loads every kind through it.
struct NoiseModelSummary {
  int channels = 0;                        // 1..4
  std::vector<float> mean;                 // per channel: the render's mean (mix: at rho = 1/2)
  bool linear = false;                     // renders are in linear light (model_is_linear)
};
NoiseModelSummary describe_noise_model(const ModelContainer& model, const std::string& what = "model");

// Whether renders of this model are in linear light (metadata "linear": true; absent means false): integer
// outputs are then encoded to sRGB.
bool model_is_linear(const ModelContainer& model);
// The exemplar's file name recorded in the metadata ("exemplar": {"name": ...}), or "".
std::string model_exemplar_name(const ModelContainer& model);

}  // namespace stex
