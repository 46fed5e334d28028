// The codec of kind cs-spot and cs-tb: the histogram table (docs/model-format.md).
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "model/cs_hist_codec.h"
#include "model/fields.h"
#include "model/kinds.h"

namespace stex {

using nlohmann::json;

void cs_hist_to_container(const CsHistTable& t, ModelContainer& c) {
  if (!t.enabled()) return;
  c.metadata["histogram"] = {{"mode", cs_hist_mode_name(t.mode)}, {"delta", t.delta}, {"bins", {t.m0, t.m1}}, {"q", t.q},
                             {"pca", !t.basis.empty()}};
  c.payload.insert(c.payload.end(), t.quantiles.begin(), t.quantiles.end());
  c.payload.insert(c.payload.end(), t.basis.begin(), t.basis.end());
}

CsHistTable cs_hist_from_container(ModelContainer& c, int channels, const std::string& what) {
  CsHistTable t;
  const auto it = c.metadata.find("histogram");
  if (it == c.metadata.end()) return t;
  const json& hj = *it;
  if (!hj.is_object()) bad_model_field(what, "metadata field 'histogram' must be an object");
  const auto mode = hj.find("mode");
  if (mode == hj.end() || !mode->is_string() || (*mode != "stationary" && *mode != "cs"))
    bad_model_field(what, "metadata field 'histogram.mode' must be \"stationary\" or \"cs\"");
  t.mode = *mode == "cs" ? 2 : 1;
  auto integer = [&](const json& j, const char* key, long lo, long hi) {
    if (!j.is_number_integer() || j.get<long long>() < lo || j.get<long long>() > hi)
      bad_model_field(what, std::string("metadata field 'histogram.") + key + "' must be an integer " + std::to_string(lo) + ".." +
                    std::to_string(hi));
    return int(j.get<long long>());
  };
  const auto delta = hj.find("delta"), q = hj.find("q"), bins = hj.find("bins");
  if (delta == hj.end() || q == hj.end() || bins == hj.end()) bad_model_field(what, "metadata field 'histogram' needs delta, bins and q");
  t.delta = integer(*delta, "delta", 0, k_cs_hist_max_delta);
  t.q = integer(*q, "q", 2, 65536);
  if (!bins->is_array() || bins->size() != 2) bad_model_field(what, "metadata field 'histogram.bins' must be [m0, m1]");
  t.m0 = integer((*bins)[0], "bins", 1, 4096);
  t.m1 = integer((*bins)[1], "bins", 1, 4096);
  t.channels = channels;
  const auto pca = hj.find("pca");
  if (pca != hj.end() && !pca->is_boolean()) bad_model_field(what, "metadata field 'histogram.pca' must be true or false");
  const std::size_t nb = pca != hj.end() && pca->get<bool>() ? std::size_t(channels) * (channels + 1) : 0;
  const std::size_t nq = std::size_t(t.m0) * t.m1 * std::size_t(channels) * t.q;
  if (c.payload.size() < nq + nb)
    bad_model_field(what, "payload has " + std::to_string(c.payload.size()) + " floats, the histogram table alone needs " + std::to_string(nq + nb));
  t.basis.assign(c.payload.end() - std::ptrdiff_t(nb), c.payload.end());
  t.quantiles.assign(c.payload.end() - std::ptrdiff_t(nq + nb), c.payload.end() - std::ptrdiff_t(nb));
  c.payload.resize(c.payload.size() - nq - nb);
  return t;
}

}  // namespace stex
