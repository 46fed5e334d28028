// The codec of kind "cs-rpn" (docs/model-format.md).
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "model/cs_rpn_codec.h"
#include "model/fields.h"
#include "model/kinds.h"

namespace stex {

using nlohmann::json;

ModelContainer to_container(const CsRpnModel& m) {
  validate_for_save([&] { validate_cs_rpn_model(m); });
  ModelContainer c;
  c.kind = kinds::cs_rpn;
  c.metadata["format"] = "stex-model";
  c.metadata["kind"] = kinds::cs_rpn;
  c.metadata["variant"] = cs_rpn_variant_name(m.variant);
  c.metadata["periods"] = periods_json(m.t0x, m.t0y, m.t1x, m.t1y);
  c.metadata["grid"] = {{"k0", m.k0}, {"k1", m.k1}};
  c.metadata["bin"] = m.bin;
  c.metadata["mean"] = m.mean;
  c.metadata["bandwidth"] = m.bandwidth;
  c.metadata["spacing"] = m.spacing;
  c.metadata["cosines"] = m.cosines;
  json spectra = json::array();
  for (const CsRpnSpectrum& s : m.spectra) {
    json e = {{"energy", s.energy}, {"bins", s.bins.size() / 3}};
    if (!s.source.empty()) e["source"] = s.source;
    spectra.push_back(e);
  }
  c.metadata["spectra"] = spectra;
  c.metadata["linear"] = false;
  c.metadata["payload"] = {{"type", "float32le"},
                           {"layout", "per spectrum (row-major over the grid), its bins (fx, fy, weight): cycles per "
                                      "model pixel, relative power"}};
  c.metadata["stex_version"] = STEX_VERSION_STRING;
  for (const CsRpnSpectrum& s : m.spectra) c.payload.insert(c.payload.end(), s.bins.begin(), s.bins.end());
  return c;
}

CsRpnModel cs_rpn_from_container(const ModelContainer& c, const std::string& what) {
  model_expect_kind(c, kinds::cs_rpn, what);
  const json& meta = c.metadata;
  CsRpnModel m;
  const std::string variant = model_string(meta, "variant", what);
  try {
    m.variant = parse_cs_rpn_variant(variant);
  } catch (const Error& e) {
    bad_model_field(what, e.what());
  }
  model_periods_into(m, meta, what);
  const json& grid = model_object(meta, "grid", what);
  m.k0 = model_int(grid, "k0", 1, STEX_CSR_MAX_GRID, what);
  m.k1 = model_int(grid, "k1", 1, STEX_CSR_MAX_GRID, what);
  m.bin = model_number(meta, "bin", what);
  m.mean = model_number(meta, "mean", what);
  m.bandwidth = model_number(meta, "bandwidth", what);
  m.spacing = model_number(meta, "spacing", what);
  m.cosines = model_int(meta, "cosines", 1, k_cs_rpn_max_cosines, what);
  const auto spectra = meta.find("spectra");
  if (spectra == meta.end() || !spectra->is_array() || spectra->size() != std::size_t(m.k0) * std::size_t(m.k1))
    bad_model_field(what, "metadata field 'spectra' must be an array of k0 x k1 entries");
  std::size_t at = 0;
  for (const json& e : *spectra) {
    if (!e.is_object()) bad_model_field(what, "metadata field 'spectra' has an entry that is not an object");
    CsRpnSpectrum s;
    s.energy = model_number(e, "energy", what);
    const int n = model_int(e, "bins", 1, k_cs_rpn_max_bins, what);
    if (e.contains("source") && e["source"].is_string()) s.source = e["source"].get<std::string>();
    if (c.payload.size() < at + 3 * std::size_t(n))
      bad_model_field(what, "payload has " + std::to_string(c.payload.size()) + " floats, fewer than the spectra's bins need");
    s.bins.assign(c.payload.begin() + std::ptrdiff_t(at), c.payload.begin() + std::ptrdiff_t(at + 3 * std::size_t(n)));
    at += 3 * std::size_t(n);
    m.spectra.push_back(std::move(s));
  }
  if (at != c.payload.size())
    bad_model_field(what, "payload has " + std::to_string(c.payload.size()) + " floats, but the spectra's bins need " + std::to_string(at));
  validate_loaded([&] { validate_cs_rpn_model(m); }, what);
  return m;
}

}  // namespace stex
