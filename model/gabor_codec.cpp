// The codec of kind "gabor" (docs/model-format.md).
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "model/gabor_codec.h"
#include "model/fields.h"
#include "model/kinds.h"

namespace stex {

using nlohmann::json;

ModelContainer to_container(const GaborModel& m) {
  validate_for_save([&] { validate_gabor_model(m); });
  ModelContainer c;
  c.kind = kinds::gabor;
  c.metadata["format"] = "stex-model";
  c.metadata["kind"] = kinds::gabor;
  c.metadata["channels"] = 1;
  c.metadata["bandwidth"] = m.bandwidth;
  c.metadata["mean"] = m.mean;
  c.metadata["std"] = m.stddev;
  c.metadata["linear"] = false;
  c.metadata["components"] = {{"type", "float32le"},
                              {"layout", "per component: frequency (cycles/pixel), orientation (rad), spread (rad), weight"},
                              {"count", std::uint64_t(m.components.size())}};
  c.metadata["stex_version"] = STEX_VERSION_STRING;
  for (const GaborComponent& k : m.components) {
    c.payload.push_back(float(k.frequency));
    c.payload.push_back(float(k.orientation));
    c.payload.push_back(float(k.spread));
    c.payload.push_back(float(k.weight));
  }
  return c;
}

GaborModel gabor_from_container(const ModelContainer& c, const std::string& what) {
  model_expect_kind(c, kinds::gabor, what);
  const json& meta = c.metadata;
  GaborModel m;
  const auto ch = meta.find("channels");
  if (ch == meta.end() || !ch->is_number_integer() || ch->get<long long>() != 1)
    bad_model_field(what, "metadata field 'channels' must be 1 for kind gabor");
  m.bandwidth = model_number(meta, "bandwidth", what);
  m.mean = model_number(meta, "mean", what);
  m.stddev = model_number(meta, "std", what);
  const auto comp = meta.find("components");
  if (comp == meta.end() || !comp->is_object() || !comp->contains("count") || !comp->at("count").is_number_unsigned())
    bad_model_field(what, "metadata field 'components' is missing or has no unsigned 'count'");
  const std::uint64_t n = comp->at("count").get<std::uint64_t>();
  if (n < 1 || n > STEX_GABOR_MAX_COMPONENTS)
    bad_model_field(what, "metadata 'components.count' must be 1.." + std::to_string(STEX_GABOR_MAX_COMPONENTS) + ", got " +
                  std::to_string(n));
  if (c.payload.size() != n * 4)
    bad_model_field(what, "payload has " + std::to_string(c.payload.size()) + " floats, but 4 x components.count = " +
                  std::to_string(n * 4));
  m.components.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    m.components[k].frequency = c.payload[4 * k];
    m.components[k].orientation = c.payload[4 * k + 1];
    m.components[k].spread = c.payload[4 * k + 2];
    m.components[k].weight = c.payload[4 * k + 3];
  }
  validate_loaded([&] { validate_gabor_model(m); }, what);
  return m;
}

}  // namespace stex
