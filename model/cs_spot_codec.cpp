// The codec of kind "cs-spot" (docs/model-format.md).
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "model/cs_spot_codec.h"
#include "model/cs_hist_codec.h"
#include "model/fields.h"
#include "model/kinds.h"

namespace stex {

using nlohmann::json;

ModelContainer to_container(const CsSpotModel& m, const CsModelInfo& info) {
  validate_for_save([&] { validate_cs_spot_model(m); });
  ModelContainer c;
  c.kind = kinds::cs_spot;
  c.metadata["format"] = "stex-model";
  c.metadata["kind"] = kinds::cs_spot;
  c.metadata["channels"] = m.channels;
  c.metadata["periods"] = periods_json(m.t0x, m.t0y, m.t1x, m.t1y);
  c.metadata["spot"] = {{"width", m.width}, {"height", m.height}, {"border", info.border}};
  c.metadata["mean_grid"] = {{"n0", m.n0}, {"n1", m.n1}};
  c.metadata["amplitude"] = m.amplitude;
  c.metadata["linear"] = info.linear;
  c.metadata["periods_estimated"] = info.estimated;
  if (info.d >= 0.0) c.metadata["d"] = info.d;
  if (info.confidence >= 0.0) c.metadata["confidence"] = info.confidence;
  if (!info.exemplar_name.empty()) c.metadata["exemplar"] = {{"name", info.exemplar_name}};
  c.metadata["payload"] = {{"type", "float32le"},
                           {"layout", "spot (height x width x channels, the exemplar minus M, windowed), then the "
                                      "cyclic mean M (n1 x n0 x channels, phases (i / n0, j / n1)), then the "
                                      "histogram quantiles if 'histogram' is present (bins m1 x m0 x channels x q)"}};
  c.metadata["stex_version"] = STEX_VERSION_STRING;
  c.payload = m.spot;
  c.payload.insert(c.payload.end(), m.mean.begin(), m.mean.end());
  cs_hist_to_container(m.hist, c);
  return c;
}

CsSpotModel cs_spot_from_container(const ModelContainer& model, const std::string& what) {
  model_expect_kind(model, kinds::cs_spot, what);
  ModelContainer c = model;
  const int channels = model_int(c.metadata, "channels", 1, STEX_CS_MAX_CHANNELS, what);
  const CsHistTable hist = cs_hist_from_container(c, channels, what);  // takes its floats off the payload's end
  const json& meta = c.metadata;
  CsSpotModel m;
  m.channels = model_int(meta, "channels", 1, STEX_CS_MAX_CHANNELS, what);
  model_periods_into(m, meta, what);
  const json& spot = model_object(meta, "spot", what);
  m.width = model_int(spot, "width", 2, k_cs_max_spot, what);
  m.height = model_int(spot, "height", 2, k_cs_max_spot, what);
  const json& grid = model_object(meta, "mean_grid", what);
  m.n0 = model_int(grid, "n0", 1, k_cs_max_spot, what);
  m.n1 = model_int(grid, "n1", 1, k_cs_max_spot, what);
  m.amplitude = model_number(meta, "amplitude", what);
  const std::size_t ns = std::size_t(m.width) * m.height * m.channels, nm = std::size_t(m.n0) * m.n1 * m.channels;
  if (c.payload.size() != ns + nm)
    bad_model_field(what, "payload has " + std::to_string(c.payload.size()) + " floats, but the spot and the mean grid need " +
                  std::to_string(ns + nm));
  m.spot.assign(c.payload.begin(), c.payload.begin() + std::ptrdiff_t(ns));
  m.mean.assign(c.payload.begin() + std::ptrdiff_t(ns), c.payload.end());
  m.hist = hist;
  validate_loaded([&] { validate_cs_spot_model(m); }, what);
  return m;
}

}  // namespace stex
