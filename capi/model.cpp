// C API models (include/stex/stex.h "Models"): parameter defaults, load and save (model/container.h),
// analysis of a file or of caller pixels (S1 Algorithm 1, in libstex_analysis.so: capi/analysis_bridge.h),
// properties.
#include <dlfcn.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <string>

#include "capi/analysis_bridge.h"
#include "capi/api_internal.h"
#include "model/codecs.h"
#include "model/kinds.h"

namespace stex::capi {
namespace {

static_assert(sizeof(std::size_t) != 8 || sizeof(stex_analysis_params) == k_analysis_params_v0_size,
              "stex_analysis_params changed size: append fields and keep k_analysis_params_v0_size");
static_assert(sizeof(std::size_t) != 8 || sizeof(stex_model_info) == k_model_info_v0_size,
              "stex_model_info changed size: append fields and keep k_model_info_v0_size");

std::uint64_t next_serial() {
  static std::atomic<std::uint64_t> serial{0};
  return ++serial;
}

// A model of any registered kind, decoded and validated once by its kind's codec (model/loaded_model.h).
stex_model* new_model(LoadedModel loaded) {
  auto handle = std::make_unique<stex_model>();
  handle->loaded = std::move(loaded);
  handle->texton = handle->loaded.as<TextonModel>();
  handle->serial = next_serial();
  return handle.release();
}

stex_analysis_params default_analysis_params() {
  stex_analysis_params p{};
  p.struct_size = sizeof p;
  p.seed = 0;
  p.pixel_budget = STEX_ANALYSIS_DEFAULT_PIXEL_BUDGET;
  p.support = STEX_ANALYSIS_DEFAULT_SUPPORT;
  p.iterations = STEX_ANALYSIS_DEFAULT_ITERATIONS;
  p.order = STEX_ANALYSIS_DEFAULT_ORDER;
  p.colour_correction = STEX_ANALYSIS_DEFAULT_COLOUR_CORRECTION;
  p.linear = 0;
  p.reserved = 0;
  return p;
}

// The caller's parameters (NULL: defaults), checked for API misuse; value ranges are checked by the analysis.
stex_analysis_params read_analysis_params(const stex_analysis_params* user) {
  stex_analysis_params p =
      read_sized(user, default_analysis_params(), k_analysis_params_v0_size, "stex_analysis_params");
  if (p.reserved != 0) invalid_argument("stex_analysis_params.reserved must be 0");
  if (p.colour_correction != 0 && p.colour_correction != 1)
    invalid_argument("stex_analysis_params.colour_correction must be 0 or 1, got " +
                     std::to_string(p.colour_correction));
  if (p.linear != 0 && p.linear != 1)
    invalid_argument("stex_analysis_params.linear must be 0 or 1, got " + std::to_string(p.linear));
  if (p.pixel_budget == 0) invalid_argument("stex_analysis_params.pixel_budget must be at least 1");
  return p;
}

// The analysis library's entry point, loaded on first use: $STEX_ANALYSIS_LIBRARY when set, else
// STEX_ANALYSIS_LIBRARY_NAME next to libstex.so, else by the library search path. STEX_UNAVAILABLE (naming
// what was tried) when it cannot be loaded; every later call gets the same answer.
stex_analysis_bridge_fn analysis_bridge() {
  static std::once_flag once;
  static stex_analysis_bridge_fn bridge = nullptr;
  static std::string failure;
  std::call_once(once, [] {
    std::vector<std::string> tried;
    if (const char* env = std::getenv("STEX_ANALYSIS_LIBRARY"); env && *env) {
      tried.push_back(env);
    } else {
      Dl_info self{};
      if (dladdr(reinterpret_cast<void*>(&stex_model_analyse_file), &self) && self.dli_fname) {
        std::string dir = self.dli_fname;
        const std::size_t slash = dir.rfind('/');
        if (slash != std::string::npos) tried.push_back(dir.substr(0, slash + 1) + STEX_ANALYSIS_LIBRARY_NAME);
      }
      tried.push_back(STEX_ANALYSIS_LIBRARY_NAME);
    }
    std::string errors;
    for (const std::string& name : tried) {
      void* handle = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!handle) {
        const char* e = dlerror();
        errors += std::string(errors.empty() ? "" : "; ") + (e ? e : name + ": not loadable");
        continue;
      }
      bridge = reinterpret_cast<stex_analysis_bridge_fn>(dlsym(handle, STEX_ANALYSIS_BRIDGE_SYMBOL));
      if (bridge) return;
      errors += std::string(errors.empty() ? "" : "; ") + name + " has no " + STEX_ANALYSIS_BRIDGE_SYMBOL +
                " (a library from another stex build)";
      dlclose(handle);
    }
    const char* env = std::getenv("STEX_ANALYSIS_LIBRARY");
    failure = env && *env ? std::string("the analysis library $STEX_ANALYSIS_LIBRARY cannot be loaded: ") + errors
                          : std::string("the analysis library ") + STEX_ANALYSIS_LIBRARY_NAME +
                                " is not installed beside libstex.so (set STEX_ANALYSIS_LIBRARY to its path): " +
                                errors;
  });
  if (!bridge) throw ApiError(STEX_UNAVAILABLE, failure);
  return bridge;
}

// Runs the analysis in libstex_analysis.so and decodes the model file it returns.
stex_model* analyse(const stex_analysis_request& request) {
  stex_analysis_result result{};
  analysis_bridge()(&request, &result);
  struct Release {
    stex_analysis_result& r;
    ~Release() {
      std::free(r.message);
      std::free(r.model);
    }
  } release{result};
  if (result.status != STEX_OK)
    throw Error(ErrorKind(result.status), result.message ? result.message : "the analysis failed");
  return new_model(make_loaded_model(decode_container(result.model, result.model_size, "(analysis)"), "(analysis)"));
}

const stex_model& checked(const stex_model* model) {
  if (!model) invalid_argument("model is NULL");
  return *model;
}

}  // namespace
}  // namespace stex::capi

using stex::capi::guard;
using stex::capi::invalid_argument;

extern "C" {

STEX_API stex_status stex_analysis_params_init(stex_analysis_params* params, size_t struct_size) {
  return guard("stex_analysis_params_init", [&] {
    if (!params) invalid_argument("params is NULL");
    stex::capi::write_sized(params, struct_size, stex::capi::default_analysis_params(),
                            stex::capi::k_analysis_params_v0_size, "stex_analysis_params");
  });
}

STEX_API stex_status stex_model_load(const char* path, stex_model** out) {
  if (out) *out = nullptr;
  return guard("stex_model_load", [&] {
    if (!out || !path) invalid_argument("path or out is NULL");
    *out = stex::capi::new_model(stex::load_model_file(path));
  });
}

STEX_API stex_status stex_model_save(const stex_model* model, const char* path) {
  return guard("stex_model_save", [&] {
    const stex_model& m = stex::capi::checked(model);
    if (!path) invalid_argument("path is NULL");
    stex::save_container(m.loaded.container, path);
  });
}

STEX_API stex_status stex_model_analyse_file(const char* path, const stex_analysis_params* params,
                                             stex_model** out) {
  if (out) *out = nullptr;
  return guard("stex_model_analyse_file", [&] {
    if (!out || !path) invalid_argument("path or out is NULL");
    stex_analysis_request request{};
    request.path = path;
    request.params = stex::capi::read_analysis_params(params);
    *out = stex::capi::analyse(request);
  });
}

STEX_API stex_status stex_model_analyse_pixels(const float* pixels, int32_t width, int32_t height,
                                               int32_t channels, size_t row_stride_bytes,
                                               const stex_analysis_params* params, stex_model** out) {
  if (out) *out = nullptr;
  return guard("stex_model_analyse_pixels", [&] {
    if (!out || !pixels) invalid_argument("pixels or out is NULL");
    if (width < 1 || height < 1)
      invalid_argument("the exemplar size must be at least 1x1, got " + std::to_string(width) + "x" +
                       std::to_string(height));
    if (channels < 1 || channels > 4)
      invalid_argument("channels must be 1..4, got " + std::to_string(channels));
    const std::size_t packed = std::size_t(width) * std::size_t(channels) * sizeof(float);
    const std::size_t stride = row_stride_bytes ? row_stride_bytes : packed;
    if (stride < packed || stride % sizeof(float) != 0)
      invalid_argument("row_stride_bytes " + std::to_string(row_stride_bytes) +
                       " must be 0 or a multiple of 4 of at least " + std::to_string(packed));
    const stex_analysis_params p = stex::capi::read_analysis_params(params);
    if (std::uint64_t(width) * std::uint64_t(height) > p.pixel_budget)
      throw stex::Error(stex::ErrorKind::Limit,
                        "the exemplar has " + std::to_string(width) + "x" + std::to_string(height) +
                            " pixels, more than the pixel budget " + std::to_string(p.pixel_budget));
    // Finite values, checked here (the analysis library gets packed rows).
    std::vector<float> packed_pixels(std::size_t(width) * std::size_t(height) * std::size_t(channels));
    const std::size_t row_floats = std::size_t(width) * std::size_t(channels);
    const unsigned char* base = reinterpret_cast<const unsigned char*>(pixels);
    for (std::size_t y = 0; y < std::size_t(height); ++y) {
      // memcpy: the caller's rows need not be float-aligned beyond what the stride check guarantees.
      std::memcpy(&packed_pixels[y * row_floats], base + y * stride, packed);
    }
    for (std::size_t i = 0; i < packed_pixels.size(); ++i) {
      if (!std::isfinite(packed_pixels[i])) {
        const std::size_t px = i / std::size_t(channels);
        throw stex::Error(stex::ErrorKind::Input, "pixel (" + std::to_string(px % std::size_t(width)) + ", " +
                                                      std::to_string(px / std::size_t(width)) + ") channel " +
                                                      std::to_string(i % std::size_t(channels)) +
                                                      " is not finite (NaN or Inf)");
      }
    }
    stex_analysis_request request{};
    request.pixels = packed_pixels.data();
    request.width = width;
    request.height = height;
    request.channels = channels;
    request.exemplar_name = "(memory)";
    request.params = p;
    *out = stex::capi::analyse(request);
  });
}

STEX_API void stex_model_destroy(stex_model* model) {
  guard("stex_model_destroy", [&] { delete model; });
}

STEX_API stex_status stex_model_get_info(const stex_model* model, stex_model_info* info) {
  return guard("stex_model_get_info", [&] {
    const stex_model& m = stex::capi::checked(model);
    if (!info) invalid_argument("info is NULL");
    stex_model_info full{};
    // Every kind: channels, linear, mean. The texton fields stay 0 for other kinds.
    const stex::NoiseModelSummary& summary = m.loaded.summary;
    full.channels = summary.channels;
    full.linear = summary.linear ? 1 : 0;
    for (int c = 0; c < 4; ++c) full.mean[c] = c < summary.channels ? summary.mean[std::size_t(c)] : 0.0f;
    if (m.texton) {
      const stex::TextonModel& t = *m.texton;
      full.support = t.support;
      full.order = t.order;
      full.exemplar_width = t.exemplar_width;
      full.exemplar_height = t.exemplar_height;
      full.iterations = t.iterations;
      full.analysis_seed = t.analysis_seed;
      full.rme = t.rme;
      full.variance_kept = t.variance_kept;
    }
    stex::capi::write_sized(info, info->struct_size, full, stex::capi::k_model_info_v0_size,
                            "stex_model_info");
  });
}

STEX_API stex_status stex_model_kind(const stex_model* model, const char** kind) {
  if (kind) *kind = nullptr;
  return guard("stex_model_kind", [&] {
    const stex_model& m = stex::capi::checked(model);
    if (!kind) invalid_argument("kind is NULL");
    *kind = m.loaded.container.kind.c_str();
  });
}

}  // extern "C"
