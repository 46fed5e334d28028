// The codec of kind "tb" and "cs-tb" (docs/model-format.md).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "model/tb_codec.h"
#include "model/cs_hist_codec.h"
#include "model/fields.h"
#include "model/kinds.h"

namespace stex {

using nlohmann::json;

ModelContainer to_container(const TbModel& m) {
  validate_for_save([&] { validate_tb_model(m); });
  ModelContainer c;
  c.kind = m.cs ? kinds::cs_tb : kinds::tb;
  c.metadata["format"] = "stex-model";
  c.metadata["kind"] = c.kind;
  c.metadata["channels"] = m.channels;
  c.metadata["tile"] = m.tile;
  c.metadata["exemplar_size"] = {m.width, m.height};
  c.metadata["lut"] = {{"size", m.lut_size}, {"lo", m.lut_lo}, {"hi", m.lut_hi}};
  if (m.cs) c.metadata["periods"] = periods_json(m.t0x, m.t0y, m.t1x, m.t1y);
  c.metadata["mean_grid"] = {{"n0", m.n0}, {"n1", m.n1}};
  c.metadata["linear"] = false;
  c.metadata["payload"] = {{"type", "float32le"}, {"layout", "gauss (h x w x ch), lut (ch x size), pca (ch means, ch x ch rows), mean (n1 x n0 x ch), then the histogram quantiles if 'histogram' is present (bins m1 x m0 x ch x q)"}};
  c.metadata["stex_version"] = STEX_VERSION_STRING;
  c.payload = m.gauss;
  c.payload.insert(c.payload.end(), m.lut.begin(), m.lut.end());
  c.payload.insert(c.payload.end(), m.pca.begin(), m.pca.end());
  c.payload.insert(c.payload.end(), m.mean.begin(), m.mean.end());
  cs_hist_to_container(m.hist, c);
  return c;
}

TbModel tb_from_container(const ModelContainer& model, const std::string& what) {
  if (model.kind != kinds::tb && model.kind != kinds::cs_tb)
    bad_model_field(what, "model kind '" + model.kind + "' is not a tb or cs-tb model");
  ModelContainer c = model;
  const json& meta = c.metadata;
  TbModel m;
  m.cs = c.kind == kinds::cs_tb;
  m.channels = model_int(meta, "channels", 1, STEX_TB_MAX_CHANNELS, what);
  m.tile = model_number(meta, "tile", what);
  const auto sz = meta.find("exemplar_size");
  if (sz == meta.end() || !sz->is_array() || sz->size() != 2 || !(*sz)[0].is_number_integer() || !(*sz)[1].is_number_integer())
    bad_model_field(what, "metadata field 'exemplar_size' must be [width, height]");
  m.width = int(std::clamp<long long>((*sz)[0].get<long long>(), 0, 1 << 20));
  m.height = int(std::clamp<long long>((*sz)[1].get<long long>(), 0, 1 << 20));
  if (m.width < 8 || m.height < 8 || m.width > 4096 || m.height > 4096) bad_model_field(what, "exemplar_size must be 8..4096");
  const json& lut = model_object(meta, "lut", what);
  m.lut_size = model_int(lut, "size", 2, 65536, what);
  m.lut_lo = model_number(lut, "lo", what);
  m.lut_hi = model_number(lut, "hi", what);
  const json& grid = model_object(meta, "mean_grid", what);
  m.n0 = model_int(grid, "n0", 1, 4096, what);
  m.n1 = model_int(grid, "n1", 1, 4096, what);
  if (m.cs) {
    model_periods_into(m, meta, what);
  }
  m.hist = cs_hist_from_container(c, m.channels, what);  // takes its floats off the payload's end
  const std::size_t ng = std::size_t(m.width) * m.height * m.channels, nl = std::size_t(m.lut_size) * m.channels;
  const std::size_t np = std::size_t(m.channels) * (m.channels + 1), nm = std::size_t(m.n0) * m.n1 * m.channels;
  if (c.payload.size() != ng + nl + np + nm)
    bad_model_field(what, "payload has " + std::to_string(c.payload.size()) + " floats, the fields need " + std::to_string(ng + nl + np + nm));
  auto it = c.payload.begin();
  m.gauss.assign(it, it + std::ptrdiff_t(ng));
  it += std::ptrdiff_t(ng);
  m.lut.assign(it, it + std::ptrdiff_t(nl));
  it += std::ptrdiff_t(nl);
  m.pca.assign(it, it + std::ptrdiff_t(np));
  it += std::ptrdiff_t(np);
  m.mean.assign(it, c.payload.end());
  validate_loaded([&] { validate_tb_model(m); }, what);
  return m;
}

}  // namespace stex
