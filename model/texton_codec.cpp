// The codec of kind "texton" (docs/model-format.md).
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "model/texton_codec.h"
#include "model/fields.h"
#include "model/kinds.h"
#include "runtime/texton_params.h"

namespace stex {

using nlohmann::json;

namespace {

void validate_model(const TextonModel& m) {
  auto fail = [](const std::string& msg) { throw Error(ErrorKind::Usage, "cannot save texton model: " + msg); };
  if (m.channels < 1 || m.channels > 4) fail("channels must be 1..4");
  if (m.support < 1 || m.support > kModelMaxSupport) fail("support must be 1..4096");
  if (!valid_texton_order(m.order)) fail("order must be 0, 1, 3 or 5");
  if (m.alpha.size() != std::size_t(m.channels) * m.support * m.support) fail("alpha size mismatch");
  for (float v : m.alpha) {
    if (!std::isfinite(v)) fail("alpha has non-finite values");
  }
  for (int c = 0; c < m.channels; ++c) {
    if (!std::isfinite(m.mean[c])) fail("mean has non-finite values");
  }
  if (!std::isfinite(m.rme) || !std::isfinite(m.variance_kept)) fail("report values are not finite");
}

double non_negative(const json& j, const char* key, const std::string& what) {
  const double v = model_number(j, key, what);
  if (v < 0.0) bad_model_field(what, std::string("metadata field '") + key + "' is not a finite value >= 0");
  return v;
}

}  // namespace

ModelContainer to_container(const TextonModel& m) {
  validate_model(m);
  ModelContainer c;
  c.kind = kinds::texton;
  json& meta = c.metadata;
  meta["format"] = "stex-model";
  meta["kind"] = kinds::texton;
  meta["channels"] = m.channels;
  meta["support"] = m.support;
  meta["order"] = m.order;
  json mean = json::array();
  for (int ch = 0; ch < m.channels; ++ch) mean.push_back(double(m.mean[ch]));
  meta["mean"] = mean;
  meta["linear"] = m.linear;
  meta["alpha"] = {{"type", "float32le"},
                   {"layout", "planar: channel, row, column"},
                   {"count", std::uint64_t(m.alpha.size())}};
  meta["exemplar"] = {{"name", m.exemplar_name},
                      {"sha256", m.exemplar_hash},
                      {"width", m.exemplar_width},
                      {"height", m.exemplar_height}};
  meta["analysis"] = {{"iterations", m.iterations}, {"seed", m.analysis_seed}};
  meta["report"] = {{"rme", m.rme}, {"variance_kept", m.variance_kept}};
  meta["stex_version"] = m.stex_version;
  c.payload = m.alpha;
  return c;
}

std::vector<std::uint8_t> encode_model(const TextonModel& m) { return encode_container(to_container(m)); }

TextonModel decode_model(const std::uint8_t* data, std::size_t size, const std::string& what) {
  return texton_from_container(decode_container(data, size, what), what);
}

TextonModel texton_from_container(const ModelContainer& c, const std::string& what) {
  model_expect_kind(c, kinds::texton, what);
  const json& meta = c.metadata;
  TextonModel m;
  m.channels = model_int(meta, "channels", 1, 4, what);
  m.support = model_int(meta, "support", 1, kModelMaxSupport, what);
  m.order = model_int(meta, "order", 0, 5, what);
  if (!valid_texton_order(m.order)) bad_model_field(what, "metadata 'order' must be 0, 1, 3 or 5, got " + std::to_string(m.order));
  const std::uint64_t count = std::uint64_t(m.channels) * m.support * m.support;
  if (c.payload.size() * sizeof(float) != count * sizeof(float)) {
    bad_model_field(what, "payload is " + std::to_string(c.payload.size() * sizeof(float)) +
                  " bytes, but channels x support^2 x 4 = " + std::to_string(count * sizeof(float)));
  }
  const json& alpha_meta = meta.contains("alpha") ? meta.at("alpha") : json();
  if (!alpha_meta.is_object() || model_string(alpha_meta, "type", what) != "float32le" ||
      !alpha_meta.contains("count") || !alpha_meta.at("count").is_number_unsigned() ||
      alpha_meta.at("count").get<std::uint64_t>() != count) {
    bad_model_field(what, "metadata 'alpha' does not describe " + std::to_string(count) + " float32le values");
  }
  const json& mean = meta.contains("mean") ? meta.at("mean") : json();
  if (!mean.is_array() || mean.size() != std::size_t(m.channels)) {
    bad_model_field(what, "metadata 'mean' is not an array of " + std::to_string(m.channels) + " numbers");
  }
  for (int c = 0; c < m.channels; ++c) {
    if (!mean[c].is_number()) bad_model_field(what, "metadata 'mean' has a non-number");
    double v = mean[c].get<double>();
    if (!std::isfinite(v) || std::fabs(v) > 3.4e38) bad_model_field(what, "metadata 'mean' has a non-finite value");
    m.mean[c] = float(v);
  }
  m.linear = model_bool(meta, "linear", what);

  const json& ex = meta.contains("exemplar") ? meta.at("exemplar") : json();
  if (!ex.is_object()) bad_model_field(what, "metadata field 'exemplar' is missing or not an object");
  m.exemplar_name = model_string(ex, "name", what);
  m.exemplar_hash = model_string(ex, "sha256", what);
  if (!m.exemplar_hash.empty()) {
    bool hex = m.exemplar_hash.size() == 64;
    for (char ch : m.exemplar_hash) hex = hex && ((ch >= '0' && ch <= '9') || (ch >= 'a' && ch <= 'f'));
    if (!hex) bad_model_field(what, "metadata 'exemplar.sha256' is not 64 lowercase hex digits");
  }
  m.exemplar_width = model_int(ex, "width", 0, 1 << 30, what);
  m.exemplar_height = model_int(ex, "height", 0, 1 << 30, what);

  const json& an = meta.contains("analysis") ? meta.at("analysis") : json();
  if (!an.is_object()) bad_model_field(what, "metadata field 'analysis' is missing or not an object");
  m.iterations = model_int(an, "iterations", 0, 1 << 30, what);
  if (!an.contains("seed") || !an.at("seed").is_number_unsigned()) {
    bad_model_field(what, "metadata 'analysis.seed' is not an unsigned integer");
  }
  m.analysis_seed = an.at("seed").get<std::uint64_t>();

  const json& rep = meta.contains("report") ? meta.at("report") : json();
  if (!rep.is_object()) bad_model_field(what, "metadata field 'report' is missing or not an object");
  m.rme = non_negative(rep, "rme", what);
  m.variance_kept = non_negative(rep, "variance_kept", what);
  m.stex_version = model_string(meta, "stex_version", what);

  m.alpha = c.payload;
  return m;
}

void save_model(const TextonModel& model, const std::string& path) {
  std::vector<std::uint8_t> bytes = encode_model(model);
  write_file_atomic(path, bytes.data(), bytes.size());
}

TextonModel load_model(const std::string& path) { return texton_from_container(load_container(path), path); }

}  // namespace stex
