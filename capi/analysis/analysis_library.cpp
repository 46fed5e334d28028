// libstex_analysis.so: the texton analysis behind stex_model_analyse_file and stex_model_analyse_pixels
// (capi/analysis_bridge.h), loaded by libstex.so on first use. Exports only STEX_ANALYSIS_BRIDGE_SYMBOL.
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>

#include "analysis/image_io.h"
#include "analysis/texton.h"
#include "capi/analysis_bridge.h"
#include "core/error.h"
#include "core/sha256.h"
#include "model/codecs.h"
#include "model/container.h"

namespace {

// The C API's defaults (capi/analysis_bridge.h) are the analysis's.
constexpr stex::TextonParams k_defaults{};
static_assert(STEX_ANALYSIS_DEFAULT_PIXEL_BUDGET == stex::LoadOptions{}.pixel_budget, "pixel budget");
static_assert(STEX_ANALYSIS_DEFAULT_SUPPORT == k_defaults.support, "support");
static_assert(STEX_ANALYSIS_DEFAULT_ITERATIONS == k_defaults.iterations, "iterations");
static_assert(STEX_ANALYSIS_DEFAULT_ORDER == k_defaults.order, "order");
static_assert((STEX_ANALYSIS_DEFAULT_COLOUR_CORRECTION != 0) == k_defaults.colour_correction, "colour correction");
static_assert(k_defaults.seed == 0 && !k_defaults.linear, "seed, linear");

stex::TextonParams texton_params(const stex_analysis_params& p) {
  stex::TextonParams t;
  t.support = p.support;
  t.iterations = p.iterations;
  t.seed = p.seed;
  t.order = p.order;
  t.colour_correction = p.colour_correction != 0;
  t.linear = p.linear != 0;
  return t;
}

stex::TextonModel analyse(const stex_analysis_request& r) {
  const stex::TextonParams params = texton_params(r.params);
  if (r.path) {
    stex::LoadOptions load;
    load.pixel_budget = r.params.pixel_budget;
    load.linear = r.params.linear != 0;
    return stex::analyse_texton_file(r.path, load, params);
  }
  stex::Image image;
  image.width = r.width;
  image.height = r.height;
  image.channels = r.channels;
  const std::size_t n = std::size_t(r.width) * std::size_t(r.height) * std::size_t(r.channels);
  image.pixels.assign(r.pixels, r.pixels + n);
  stex::TextonModel model = stex::analyse_texton(image, params);
  model.exemplar_name = r.exemplar_name ? r.exemplar_name : "(memory)";
  model.exemplar_hash = stex::sha256_hex(image.pixels.data(), image.pixels.size() * sizeof(float));
  return model;
}

char* copy_message(const char* text) {
  const std::size_t n = std::strlen(text);
  char* out = static_cast<char*>(std::malloc(n + 1));
  if (out) std::memcpy(out, text, n + 1);
  return out;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) void stex_analysis_bridge_v1(const stex_analysis_request* request,
                                                                                stex_analysis_result* result) {
  *result = stex_analysis_result{};
  try {
    const std::vector<std::uint8_t> bytes = stex::encode_container(stex::to_container(analyse(*request)));
    result->model = static_cast<unsigned char*>(std::malloc(bytes.size()));
    if (!result->model) throw std::bad_alloc();
    std::memcpy(result->model, bytes.data(), bytes.size());
    result->model_size = bytes.size();
    result->status = STEX_OK;
  } catch (const stex::Error& e) {
    result->status = int32_t(e.kind());
    result->message = copy_message(e.what());
  } catch (const std::bad_alloc&) {
    result->status = STEX_LIMIT;
    result->message = copy_message("out of host memory");
  } catch (const std::exception& e) {
    result->status = STEX_INTERNAL;
    result->message = copy_message(e.what());
  } catch (...) {
    result->status = STEX_INTERNAL;
    result->message = copy_message("unknown exception");
  }
}
