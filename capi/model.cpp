// C API models (include/stex/stex.h "Models"): parameter defaults, load and save (analysis/model_file.h),
// analysis of a file or of caller pixels (analysis/texton.h, S1 Algorithm 1), properties.
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>

#include "analysis/image_io.h"
#include "model/codecs.h"
#include "model/kinds.h"
#include "analysis/texton.h"
#include "capi/api_internal.h"
#include "core/sha256.h"

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

// A model of any registered kind: decoded and validated by its kind's codec (analysis/noise_kinds.h).
stex_model* new_model(ModelContainer container, const std::string& what) {
  auto handle = std::make_unique<stex_model>();
  handle->summary = describe_noise_model(container, what);
  if (container.kind == kinds::texton)
    handle->texton = std::make_unique<TextonModel>(texton_from_container(container, what));
  handle->container = std::move(container);
  handle->serial = next_serial();
  return handle.release();
}

stex_model* new_model(const TextonModel& model) { return new_model(to_container(model), "(analysis)"); }

stex_analysis_params default_analysis_params() {
  const TextonParams t;
  const LoadOptions l;
  stex_analysis_params p{};
  p.struct_size = sizeof p;
  p.seed = t.seed;
  p.pixel_budget = l.pixel_budget;
  p.support = t.support;
  p.iterations = t.iterations;
  p.order = t.order;
  p.colour_correction = t.colour_correction ? 1 : 0;
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

TextonParams texton_params(const stex_analysis_params& p) {
  TextonParams t;
  t.support = p.support;
  t.iterations = p.iterations;
  t.seed = p.seed;
  t.order = p.order;
  t.colour_correction = p.colour_correction != 0;
  t.linear = p.linear != 0;
  return t;
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
    *out = stex::capi::new_model(stex::load_container(path), path);
  });
}

STEX_API stex_status stex_model_save(const stex_model* model, const char* path) {
  return guard("stex_model_save", [&] {
    const stex_model& m = stex::capi::checked(model);
    if (!path) invalid_argument("path is NULL");
    stex::save_container(m.container, path);
  });
}

STEX_API stex_status stex_model_analyse_file(const char* path, const stex_analysis_params* params,
                                             stex_model** out) {
  if (out) *out = nullptr;
  return guard("stex_model_analyse_file", [&] {
    if (!out || !path) invalid_argument("path or out is NULL");
    const stex_analysis_params p = stex::capi::read_analysis_params(params);
    stex::LoadOptions load;
    load.pixel_budget = p.pixel_budget;
    load.linear = p.linear != 0;
    *out = stex::capi::new_model(stex::analyse_texton_file(path, load, stex::capi::texton_params(p)));
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
    stex::Image image;
    image.width = width;
    image.height = height;
    image.channels = channels;
    image.pixels.resize(std::size_t(width) * std::size_t(height) * std::size_t(channels));
    const std::size_t row_floats = std::size_t(width) * std::size_t(channels);
    const unsigned char* base = reinterpret_cast<const unsigned char*>(pixels);
    for (std::size_t y = 0; y < std::size_t(height); ++y) {
      // memcpy: the caller's rows need not be float-aligned beyond what the stride check guarantees.
      std::memcpy(&image.pixels[y * row_floats], base + y * stride, packed);
    }
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
      if (!std::isfinite(image.pixels[i])) {
        const std::size_t px = i / std::size_t(channels);
        throw stex::Error(stex::ErrorKind::Input, "pixel (" + std::to_string(px % std::size_t(width)) + ", " +
                                                      std::to_string(px / std::size_t(width)) + ") channel " +
                                                      std::to_string(i % std::size_t(channels)) +
                                                      " is not finite (NaN or Inf)");
      }
    }
    stex::TextonModel model = stex::analyse_texton(image, stex::capi::texton_params(p));
    model.exemplar_name = "(memory)";
    model.exemplar_hash = stex::sha256_hex(image.pixels.data(), image.pixels.size() * sizeof(float));
    *out = stex::capi::new_model(model);
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
    full.channels = m.summary.channels;
    full.linear = m.summary.linear ? 1 : 0;
    for (int c = 0; c < 4; ++c) full.mean[c] = c < m.summary.channels ? m.summary.mean[std::size_t(c)] : 0.0f;
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
    *kind = m.container.kind.c_str();
  });
}

}  // extern "C"
