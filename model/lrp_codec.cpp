// The codec of kind "lrp" (docs/model-format.md).
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "model/lrp_codec.h"
#include "model/fields.h"
#include "model/kinds.h"

namespace stex {

using nlohmann::json;

ModelContainer to_container(const LrpModel& m) {
  validate_for_save([&] { validate_lrp_model(m); });
  ModelContainer c;
  c.kind = kinds::lrp;
  json& meta = c.metadata;
  meta["format"] = "stex-model";
  meta["kind"] = kinds::lrp;
  meta["channels"] = m.channels;
  meta["period"] = m.period;
  json mean = json::array();
  for (int i = 0; i < m.channels; ++i) mean.push_back(double(m.mean[i]));
  meta["mean"] = mean;
  meta["linear"] = m.linear;
  auto strata_json = [](const std::vector<LrpStratum>& list) {
    json strata = json::array();
    for (const auto& s : list)
      strata.push_back({{"delta", s.delta},
                        {"amplitude", s.amplitude},
                        {"energy", s.energy},
                        {"psd_lo", s.psd_lo},
                        {"psd_hi", s.psd_hi},
                        {"size", s.size},
                        {"erosion", s.erosion},
                        {"sub_counts", s.sub_counts}});
    return strata;
  };
  meta["strata"] = strata_json(m.strata);
  if (!m.turbulence.empty()) meta["turbulence_strata"] = strata_json(m.turbulence);
  meta["structure"] = {{"ratio", m.ratio}, {"block", m.block},         {"jr", m.jr},
                       {"error", m.structure_error}, {"sigma", m.sigma}, {"placement", m.placement},
                       {"blend", m.blend}};
  meta["payload"] = {{"type", "float32le"},
                     {"layout", "frequencies (kx, ky) per table entry, colours (p, q) per channel per sub-stratum, "
                                "structure terms (kx, ky, a, b per channel) per block, turbulence frequencies (kx, ky)"},
                     {"frequencies", m.freqs.size() / 2},
                     {"turbulence_frequencies", m.turb_freqs.size() / 2},
                     {"colours", m.colours.size()},
                     {"terms", m.terms.size()}};
  meta["exemplar"] = {{"name", m.exemplar_name},
                      {"sha256", m.exemplar_hash},
                      {"width", m.exemplar_width},
                      {"height", m.exemplar_height}};
  meta["analysis"] = {{"cosines", m.cosines}, {"seed", m.analysis_seed}, {"source", m.source}};
  // absent in files before per-cosine amplitudes (and still for "paper"): those files stay byte-identical
  if (m.amplitudes != "paper") meta["analysis"]["amplitudes"] = m.amplitudes;
  meta["stex_version"] = m.stex_version;
  c.payload.reserve(m.freqs.size() + m.colours.size() + m.terms.size());
  for (std::int32_t k : m.freqs) c.payload.push_back(float(k));
  c.payload.insert(c.payload.end(), m.colours.begin(), m.colours.end());
  c.payload.insert(c.payload.end(), m.terms.begin(), m.terms.end());
  for (std::int32_t k : m.turb_freqs) c.payload.push_back(float(k));
  return c;
}

LrpModel lrp_from_container(const ModelContainer& c, const std::string& what) {
  model_expect_kind(c, kinds::lrp, what);
  const json& meta = c.metadata;
  LrpModel m;
  m.channels = model_int(meta, "channels", 1, STEX_LRP_MAX_CHANNELS, what);
  m.period = model_int(meta, "period", 2, 4096, what);
  if (m.period & (m.period - 1)) bad_model_field(what, "metadata 'period' must be a power of two");
  const json& mean = model_field(meta, "mean", what);
  if (!mean.is_array() || mean.size() != std::size_t(m.channels))
    bad_model_field(what, "metadata 'mean' is not an array of " + std::to_string(m.channels) + " numbers");
  for (int i = 0; i < m.channels; ++i) {
    if (!mean[i].is_number() || !std::isfinite(mean[i].get<double>()) || std::fabs(mean[i].get<double>()) > 3.4e38)
      bad_model_field(what, "metadata 'mean' has a non-finite value");
    m.mean[i] = float(mean[i].get<double>());
  }
  const json& lin = model_field(meta, "linear", what);
  if (!lin.is_boolean()) bad_model_field(what, "metadata field 'linear' is not a boolean");
  m.linear = lin.get<bool>();
  const json& strata = model_field(meta, "strata", what);
  if (!strata.is_array() || strata.size() > STEX_LRP_MAX_STRATA)
    bad_model_field(what, "metadata 'strata' is not an array of at most " + std::to_string(STEX_LRP_MAX_STRATA) + " strata");
  auto read_strata = [&](const json& list, std::vector<LrpStratum>* out, std::size_t* entries, std::size_t* subs) {
    for (const json& s : list) {
      LrpStratum st;
      st.delta = model_number(s, "delta", what);
      st.amplitude = model_number(s, "amplitude", what);
      st.energy = model_number(s, "energy", what);
      st.psd_lo = model_number(s, "psd_lo", what);
      st.psd_hi = model_number(s, "psd_hi", what);
      st.size = model_int(s, "size", 0, 4096 * 4096, what);
      st.erosion = model_number(s, "erosion", what);
      const json& sc = model_field(s, "sub_counts", what);
      if (!sc.is_array() || sc.empty() || sc.size() > 4096)
        bad_model_field(what, "metadata 'sub_counts' must hold 1..4096 counts");
      for (const json& v : sc) {
        if (!v.is_number_integer() || v.get<long long>() < 1 || v.get<long long>() > (long long)m.period * m.period)
          bad_model_field(what, "metadata 'sub_counts' has a count outside [1, T^2]");
        st.sub_counts.push_back(int(v.get<long long>()));
        *entries += std::size_t(st.sub_counts.back());
      }
      *subs += st.sub_counts.size();
      out->push_back(std::move(st));
    }
  };
  std::size_t entries = 0, subs = 0, turb_entries = 0, turb_subs = 0;
  read_strata(strata, &m.strata, &entries, &subs);
  if (meta.contains("turbulence_strata")) {  // absent: no turbulence (sigma must then be 0)
    const json& ts = meta.at("turbulence_strata");
    if (!ts.is_array() || ts.size() > STEX_LRP_MAX_STRATA)
      bad_model_field(what, "metadata 'turbulence_strata' is not an array of at most " +
                                std::to_string(STEX_LRP_MAX_STRATA) + " strata");
    read_strata(ts, &m.turbulence, &turb_entries, &turb_subs);
  }
  const json& str = model_field(meta, "structure", what);
  m.ratio = model_number(str, "ratio", what);
  m.block = model_int(str, "block", 0, m.period, what);
  if (m.block > 0 && m.period % m.block != 0) bad_model_field(what, "metadata 'structure.block' must divide the period");
  m.jr = model_int(str, "jr", 0, 1 << 24, what);
  m.structure_error = model_number(str, "error", what);
  m.sigma = model_number(str, "sigma", what);
  const json& pl = model_field(str, "placement", what);
  if (!pl.is_boolean()) bad_model_field(what, "metadata field 'placement' is not a boolean");
  m.placement = pl.get<bool>();
  m.blend = model_number(str, "blend", what);
  const std::size_t nb = m.block > 0 ? std::size_t(m.period / m.block) : 0;
  const std::size_t n_terms = nb * nb * std::size_t(m.jr) * std::size_t(2 + 2 * m.channels);
  const std::size_t n_col = subs * std::size_t(2 * m.channels);
  const std::size_t n_all = 2 * entries + n_col + n_terms + 2 * turb_entries;
  if (c.payload.size() != n_all)
    bad_model_field(what, "payload holds " + std::to_string(c.payload.size()) + " floats, the metadata describes " +
                        std::to_string(n_all));
  for (std::size_t i = 0; i < 2 * entries; ++i) {
    const float v = c.payload[i];
    if (v != std::floor(v) || std::fabs(v) > float(m.period / 2)) bad_model_field(what, "a frequency is not an integer in [-T/2, T/2]");
    m.freqs.push_back(std::int32_t(v));
  }
  m.colours.assign(c.payload.begin() + std::ptrdiff_t(2 * entries), c.payload.begin() + std::ptrdiff_t(2 * entries + n_col));
  m.terms.assign(c.payload.begin() + std::ptrdiff_t(2 * entries + n_col),
                 c.payload.begin() + std::ptrdiff_t(2 * entries + n_col + n_terms));
  for (std::size_t i = 2 * entries + n_col + n_terms; i < n_all; ++i) {
    const float v = c.payload[i];
    if (v != std::floor(v) || std::fabs(v) > float(m.period / 2))
      bad_model_field(what, "a turbulence frequency is not an integer in [-T/2, T/2]");
    m.turb_freqs.push_back(std::int32_t(v));
  }
  const json& ex = model_field(meta, "exemplar", what);
  if (!ex.is_object() || !model_field(ex, "name", what).is_string() || !model_field(ex, "sha256", what).is_string())
    bad_model_field(what, "metadata 'exemplar' must have string 'name' and 'sha256'");
  m.exemplar_name = ex.at("name").get<std::string>();
  m.exemplar_hash = ex.at("sha256").get<std::string>();
  m.exemplar_width = model_int(ex, "width", 0, 1 << 30, what);
  m.exemplar_height = model_int(ex, "height", 0, 1 << 30, what);
  const json& an = model_field(meta, "analysis", what);
  m.cosines = model_int(an, "cosines", 0, 1 << 20, what);
  const json& seed = model_field(an, "seed", what);
  if (!seed.is_number_unsigned() && !(seed.is_number_integer() && seed.get<long long>() >= 0))
    bad_model_field(what, "metadata 'analysis.seed' is not an unsigned integer");
  m.analysis_seed = seed.get<std::uint64_t>();
  if (an.contains("source") && an.at("source").is_string()) m.source = an.at("source").get<std::string>();
  if (an.contains("amplitudes")) {  // provenance only: the gains are in the colour weights
    const json& a = an.at("amplitudes");
    if (!a.is_string() || (a != "paper" && a != "psd" && a != "psd-energy" && a != "fit"))
      bad_model_field(what, "metadata 'analysis.amplitudes' must be \"paper\", \"psd\", \"psd-energy\" or \"fit\"");
    m.amplitudes = a.get<std::string>();
  }
  if (meta.contains("stex_version") && meta.at("stex_version").is_string())
    m.stex_version = meta.at("stex_version").get<std::string>();
  validate_loaded([&] { validate_lrp_model(m); }, what);
  return m;
}

}  // namespace stex
