#include "analysis/noise_kinds.h"

#include "analysis/cs_rpn_model.h"
#include "analysis/cs_spot_model.h"
#include "analysis/gabor_model.h"
#include "analysis/lrp.h"
#include "analysis/mix.h"
#include "analysis/tb_model.h"
#include "core/error.h"
#include "runtime/cs_rpn.h"
#include "runtime/cs_spot.h"
#include "runtime/gabor_renderer.h"
#include "runtime/lrp_renderer.h"
#include "runtime/mix_renderer.h"
#include "runtime/tb.h"
#include "runtime/texton_renderer.h"

namespace stex {

std::vector<std::string> noise_kinds() { return {"texton", "lrp", "gabor", "mix", "cs-spot", "tb", "cs-tb", "cs-rpn"}; }

namespace {
[[noreturn]] void unknown_kind(const ModelContainer& model, const std::string& what) {
  std::string known;
  for (const std::string& k : noise_kinds()) known += (known.empty() ? "" : ", ") + k;
  throw Error(ErrorKind::Input, "model '" + what + "' is of kind '" + model.kind +
                                    "', which this stex cannot render (known kinds: " + known + ")");
}
}  // namespace

void check_model(const ModelContainer& model, const std::string& what) { (void)describe_noise_model(model, what); }

std::unique_ptr<NoiseRenderer> make_noise_renderer(Context& ctx, const ModelContainer& model,
                                                   const NoiseRendererOptions& options, const std::string& what) {
  // One line per kind.
  if (model.kind == "texton") return std::make_unique<TextonNoise>(ctx, texton_from_container(model, what), options);
  if (model.kind == "lrp") return std::make_unique<LrpRenderer>(ctx, lrp_from_container(model, what), options);
  if (model.kind == "gabor") return std::make_unique<GaborNoise>(ctx, gabor_from_container(model, what), options);
  if (model.kind == "cs-spot") return std::make_unique<CsSpotNoise>(ctx, cs_spot_from_container(model, what), options);
  if (model.kind == "tb" || model.kind == "cs-tb") return std::make_unique<TbNoise>(ctx, tb_from_container(model, what), options);
  if (model.kind == "mix") return std::make_unique<MixNoise>(ctx, mix_from_container(model, what), options);
  if (model.kind == "cs-rpn") return std::make_unique<CsRpnNoise>(ctx, cs_rpn_from_container(model, what), options);
  unknown_kind(model, what);
}

NoiseModelSummary describe_noise_model(const ModelContainer& model, const std::string& what) {
  NoiseModelSummary s;
  s.linear = model_is_linear(model);
  // One line per kind (as make_noise_renderer).
  if (model.kind == "texton") {
    const TextonModel m = texton_from_container(model, what);
    s.channels = m.channels;
    s.mean.assign(m.mean.begin(), m.mean.begin() + m.channels);
    s.linear = m.linear;
  } else if (model.kind == "lrp") {
    const LrpModel m = lrp_from_container(model, what);
    s.channels = m.channels;
    s.mean.assign(m.mean.begin(), m.mean.begin() + m.channels);
    s.linear = m.linear;
  } else if (model.kind == "gabor") {
    const GaborModel m = gabor_from_container(model, what);
    s.channels = 1;
    s.mean = {float(m.mean)};
  } else if (model.kind == "mix") {
    const MixModel m = mix_from_container(model, what);
    s.channels = m.channels;
    // The mean varies with the map (mean0 -> mean1): the summary gives its midpoint, rho = 1/2.
    for (int c = 0; c < m.channels; ++c) s.mean.push_back(0.5f * (m.mean0[std::size_t(c)] + m.mean1[std::size_t(c)]));
    s.linear = m.linear;
  } else if (model.kind == "cs-spot") {
    const CsSpotModel m = cs_spot_from_container(model, what);
    s.channels = m.channels;
    // The render's mean is the cyclic mean M(x): its average over a period is the average of the grid.
    s.mean.assign(std::size_t(m.channels), 0.0f);
    const std::size_t cells = std::size_t(m.n0) * std::size_t(m.n1);
    for (std::size_t i = 0; i < cells; ++i)
      for (int c = 0; c < m.channels; ++c) s.mean[std::size_t(c)] += m.mean[i * std::size_t(m.channels) + c] / float(cells);
    if (m.hist.enabled()) {
      // With a histogram transfer M is that of the Gaussianised exemplar: the mean is the average of the
      // bins' quantiles (each bin's mean, over the bins: the mean over a period).
      const std::size_t bins = std::size_t(m.hist.m0) * std::size_t(m.hist.m1), q = std::size_t(m.hist.q);
      std::vector<double> avg(std::size_t(m.channels), 0.0);
      for (int c = 0; c < m.channels; ++c) {
        for (std::size_t b = 0; b < bins; ++b)
          for (std::size_t k = 0; k < q; ++k) avg[std::size_t(c)] += m.hist.quantiles[(b * std::size_t(m.channels) + std::size_t(c)) * q + k];
        avg[std::size_t(c)] /= double(bins * q);
      }
      const std::size_t ch = std::size_t(m.channels);
      for (std::size_t c = 0; c < ch; ++c) {
        double v = avg[c];
        if (!m.hist.basis.empty()) {  // back from the PCA basis (linear: the mean maps through)
          v = m.hist.basis[c];
          for (std::size_t d = 0; d < ch; ++d) v += m.hist.basis[ch + d * ch + c] * avg[d];
        }
        s.mean[c] = float(v);
      }
    }
  } else if (model.kind == "tb" || model.kind == "cs-tb") {
    const TbModel m = tb_from_container(model, what);
    s.channels = m.channels;
    // The exemplar's mean, the first entries of the PCA block (the render's mean up to the LUT's rounding).
    s.mean.assign(m.pca.begin(), m.pca.begin() + m.channels);
  } else if (model.kind == "cs-rpn") {
    const CsRpnModel m = cs_rpn_from_container(model, what);
    s.channels = 1;
    s.mean = {float(m.mean)};
  } else {
    unknown_kind(model, what);
  }
  return s;
}

bool model_is_linear(const ModelContainer& model) {
  const auto it = model.metadata.find("linear");
  return it != model.metadata.end() && it->is_boolean() && it->get<bool>();
}

std::string model_exemplar_name(const ModelContainer& model) {
  const auto ex = model.metadata.find("exemplar");
  if (ex == model.metadata.end() || !ex->is_object()) return "";
  const auto name = ex->find("name");
  return name != ex->end() && name->is_string() ? name->get<std::string>() : "";
}

}  // namespace stex
