// The codec of kind "mix" (docs/model-format.md).
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "model/mix_codec.h"
#include "model/fields.h"
#include "model/kinds.h"

namespace stex {

using nlohmann::json;

ModelContainer to_container(const MixModel& m) {
  validate_for_save([&] { validate_mix_model(m); });
  ModelContainer c;
  c.kind = kinds::mix;
  json& meta = c.metadata;
  meta["format"] = "stex-model";
  meta["kind"] = kinds::mix;
  meta["channels"] = m.channels;
  meta["support"] = m.support;
  meta["order"] = m.order;
  meta["levels"] = m.levels;
  json m0 = json::array(), m1 = json::array();
  for (int ch = 0; ch < m.channels; ++ch) {
    m0.push_back(double(m.mean0[ch]));
    m1.push_back(double(m.mean1[ch]));
  }
  meta["mean0"] = m0;
  meta["mean1"] = m1;
  meta["linear"] = m.linear;
  meta["alpha"] = {{"type", "float32le"},
                   {"layout", "level k (rho = k / (levels - 1)), channel, row, column"},
                   {"count", std::uint64_t(m.alpha.size())}};
  json map;
  switch (m.map.type) {
    case MixMap::Type::Const: map = {{"type", "const"}, {"rho", m.map.rho}}; break;
    case MixMap::Type::Ramp: map = {{"type", "ramp"}, {"x0", m.map.x0}, {"x1", m.map.x1}}; break;
    case MixMap::Type::Strips: map = {{"type", "strips"}, {"period", m.map.period}, {"width", m.map.width}}; break;
    case MixMap::Type::Image:
      map = {{"type", "image"},         {"width", m.map.map_width},   {"height", m.map.map_height},
             {"scale", m.map.scale},    {"origin_x", m.map.origin_x}, {"origin_y", m.map.origin_y},
             {"wrap", m.map.clamp ? "clamp" : "repeat"}, {"name", m.map.name},
             {"count", std::uint64_t(m.map.grey.size())}};
      break;
  }
  meta["map"] = map;
  json ex = json::array();
  for (int i = 0; i < 2; ++i) ex.push_back({{"name", m.exemplar_name[i]}, {"sha256", m.exemplar_hash[i]}});
  meta["exemplars"] = ex;
  meta["exemplar"] = {{"name", m.exemplar_name[0]}, {"width", m.exemplar_width}, {"height", m.exemplar_height}};
  meta["analysis"] = {{"iterations", m.iterations},
                      {"seed", m.analysis_seed},
                      {"colour_correction", m.colour_correction}};
  meta["report"] = {{"ot_distance", m.ot_distance}, {"rme", m.rme}};
  meta["stex_version"] = m.stex_version.empty() ? std::string(STEX_VERSION_STRING) : m.stex_version;
  c.payload = m.alpha;
  if (m.map.type == MixMap::Type::Image) c.payload.insert(c.payload.end(), m.map.grey.begin(), m.map.grey.end());
  return c;
}

MixModel mix_from_container(const ModelContainer& c, const std::string& what) {
  model_expect_kind(c, kinds::mix, what);
  const json& meta = c.metadata;
  MixModel m;
  m.channels = int(model_integer(meta, "channels", 1, 4, what));
  m.support = int(model_integer(meta, "support", 1, kModelMaxSupport, what));
  m.order = int(model_integer(meta, "order", 0, 5, what));
  m.levels = int(model_integer(meta, "levels", 2, STEX_MIX_MAX_LEVELS, what));
  m.mean0 = model_means(meta, "mean0", m.channels, what);
  m.mean1 = model_means(meta, "mean1", m.channels, what);
  const auto lin = meta.find("linear");
  if (lin == meta.end() || !lin->is_boolean()) bad_model_field(what, "metadata field 'linear' is missing or not a boolean");
  m.linear = lin->get<bool>();
  const std::uint64_t n_alpha =
      std::uint64_t(m.levels) * std::uint64_t(m.channels) * std::uint64_t(m.support) * std::uint64_t(m.support);
  const auto mp = meta.find("map");
  if (mp == meta.end() || !mp->is_object()) bad_model_field(what, "metadata field 'map' is missing or not an object");
  const std::string type = model_string(*mp, "type", what);
  std::uint64_t n_map = 0;
  if (type == "const") {
    m.map.type = MixMap::Type::Const;
    m.map.rho = model_number(*mp, "rho", what);
  } else if (type == "ramp") {
    m.map.type = MixMap::Type::Ramp;
    m.map.x0 = model_number(*mp, "x0", what);
    m.map.x1 = model_number(*mp, "x1", what);
  } else if (type == "strips") {
    m.map.type = MixMap::Type::Strips;
    m.map.period = model_number(*mp, "period", what);
    m.map.width = model_number(*mp, "width", what);
  } else if (type == "image") {
    m.map.type = MixMap::Type::Image;
    m.map.map_width = int(model_integer(*mp, "width", 1, k_mix_max_map_side, what));
    m.map.map_height = int(model_integer(*mp, "height", 1, k_mix_max_map_side, what));
    m.map.scale = model_number(*mp, "scale", what);
    m.map.origin_x = model_integer(*mp, "origin_x", -(1ll << 40) + 1, (1ll << 40) - 1, what);
    m.map.origin_y = model_integer(*mp, "origin_y", -(1ll << 40) + 1, (1ll << 40) - 1, what);
    const std::string wrap = model_string(*mp, "wrap", what);
    if (wrap != "repeat" && wrap != "clamp") bad_model_field(what, "metadata 'map.wrap' must be repeat or clamp");
    m.map.clamp = wrap == "clamp";
    m.map.name = model_string(*mp, "name", what);
    n_map = std::uint64_t(m.map.map_width) * std::uint64_t(m.map.map_height);
  } else {
    bad_model_field(what, "metadata 'map.type' must be const, ramp, strips or image, got '" + type + "'");
  }
  if (c.payload.size() != n_alpha + n_map)
    bad_model_field(what, "payload has " + std::to_string(c.payload.size()) + " floats, expected levels x channels x support^2" +
                  (n_map ? " + map width x height = " : " = ") + std::to_string(n_alpha + n_map));
  m.alpha.assign(c.payload.begin(), c.payload.begin() + std::ptrdiff_t(n_alpha));
  m.map.grey.assign(c.payload.begin() + std::ptrdiff_t(n_alpha), c.payload.end());
  // Provenance (optional fields keep their defaults when absent).
  if (const auto ex = meta.find("exemplars"); ex != meta.end() && ex->is_array() && ex->size() == 2)
    for (int i = 0; i < 2; ++i) {
      const json& e = (*ex)[i];
      if (e.is_object() && e.contains("name") && e["name"].is_string()) m.exemplar_name[i] = e["name"].get<std::string>();
      if (e.is_object() && e.contains("sha256") && e["sha256"].is_string()) m.exemplar_hash[i] = e["sha256"].get<std::string>();
    }
  if (const auto ex = meta.find("exemplar"); ex != meta.end() && ex->is_object()) {
    m.exemplar_width = int(model_integer(*ex, "width", 0, 1 << 30, what));
    m.exemplar_height = int(model_integer(*ex, "height", 0, 1 << 30, what));
  }
  if (const auto an = meta.find("analysis"); an != meta.end() && an->is_object()) {
    m.iterations = int(model_integer(*an, "iterations", 0, 1 << 30, what));
    if (an->contains("seed") && (*an)["seed"].is_number_unsigned()) m.analysis_seed = (*an)["seed"].get<std::uint64_t>();
    if (an->contains("colour_correction") && (*an)["colour_correction"].is_boolean())
      m.colour_correction = (*an)["colour_correction"].get<bool>();
  }
  if (const auto r = meta.find("report"); r != meta.end() && r->is_object()) {
    if (r->contains("ot_distance") && (*r)["ot_distance"].is_number()) m.ot_distance = (*r)["ot_distance"].get<double>();
    if (r->contains("rme") && (*r)["rme"].is_array())
      for (const json& v : (*r)["rme"])
        if (v.is_number()) m.rme.push_back(v.get<double>());
  }
  if (const auto v = meta.find("stex_version"); v != meta.end() && v->is_string()) m.stex_version = v->get<std::string>();
  validate_loaded([&] { validate_mix_model(m); }, what);
  return m;
}

}  // namespace stex
