// The kind table (model/kinds.h): one entry per kind, each a decode, describe, make-renderer and self-test-rows
// function over the kind's codec (model/codecs.h) and renderer (runtime/).
#include "model/kinds.h"

#include "core/error.h"
#include "model/cs_rpn_codec.h"
#include "model/cs_spot_codec.h"
#include "model/gabor_codec.h"
#include "model/lrp_codec.h"
#include "model/mix_codec.h"
#include "model/tb_codec.h"
#include "model/texton_codec.h"
#include "runtime/cs_rpn.h"
#include "runtime/cs_spot.h"
#include "runtime/gabor_renderer.h"
#include "runtime/lrp_renderer.h"
#include "runtime/mix_renderer.h"
#include "runtime/tb.h"
#include "runtime/texton_params.h"
#include "runtime/texton_renderer.h"

namespace stex {

namespace {

// The decoded model of kind entry K: the struct its codec returns.
template <class M>
const M& decoded_as(const std::any& decoded) {
  return *std::any_cast<const std::shared_ptr<const M>&>(decoded);
}

// decode of a kind whose codec is `codec`.
template <auto codec>
std::any decode(const ModelContainer& model, const std::string& what) {
  using M = decltype(codec(model, what));
  return std::shared_ptr<const M>(std::make_shared<M>(codec(model, what)));
}

// Texton models are also checked for rendering (support, order, finite values) when decoded.
std::any decode_texton(const ModelContainer& model, const std::string& what) {
  auto m = std::make_shared<TextonModel>(texton_from_container(model, what));
  validate_texton_model(*m);
  return std::shared_ptr<const TextonModel>(std::move(m));
}

// make_renderer of a kind whose model struct is M and whose renderer is R.
template <class M, class R>
std::unique_ptr<NoiseRenderer> make(Context& ctx, const std::any& decoded, const NoiseRendererOptions& options) {
  return std::make_unique<R>(ctx, decoded_as<M>(decoded), options);
}

// The render's mean and channels for the kinds that store them as such.
template <class M, bool Poisson, bool Filters = false>
NoiseModelSummary summary_of(const std::any& decoded, const ModelContainer&) {
  const M& m = decoded_as<M>(decoded);
  NoiseModelSummary s;
  s.channels = m.channels;
  s.mean.assign(m.mean.begin(), m.mean.begin() + m.channels);
  s.linear = m.linear;
  s.poisson = Poisson;
  s.filters = Filters;
  return s;
}

NoiseModelSummary describe_gabor(const std::any& decoded, const ModelContainer& c) {
  const GaborModel& m = decoded_as<GaborModel>(decoded);
  return {1, {float(m.mean)}, model_is_linear(c), true, true};
}

NoiseModelSummary describe_mix(const std::any& decoded, const ModelContainer&) {
  const MixModel& m = decoded_as<MixModel>(decoded);
  NoiseModelSummary s;
  s.channels = m.channels;
  // The mean varies with the map (mean0 -> mean1): the summary gives its midpoint, rho = 1/2.
  for (int k = 0; k < m.channels; ++k) s.mean.push_back(0.5f * (m.mean0[std::size_t(k)] + m.mean1[std::size_t(k)]));
  s.linear = m.linear;
  s.poisson = true;  // the texton grid's impulses
  s.filters = true;  // minified views: the box prefilter per level (runtime/mix_model.h)
  return s;
}

// cs-spot: the render's mean is the cyclic mean M(x), whose average over a period is the average of the grid.
// With a histogram transfer, M is that of the Gaussianised exemplar and the mean is the average of the bins'
// quantiles (each bin's mean, over the bins: the mean over a period), back from the PCA basis if any.
NoiseModelSummary describe_cs_spot(const std::any& decoded, const ModelContainer& c) {
  const CsSpotModel& m = decoded_as<CsSpotModel>(decoded);
  NoiseModelSummary s;
  s.channels = m.channels;
  s.linear = model_is_linear(c);
  const std::size_t ch = std::size_t(m.channels);
  s.mean.assign(ch, 0.0f);
  const std::size_t cells = std::size_t(m.n0) * std::size_t(m.n1);
  for (std::size_t i = 0; i < cells; ++i)
    for (std::size_t k = 0; k < ch; ++k) s.mean[k] += m.mean[i * ch + k] / float(cells);
  if (!m.hist.enabled()) return s;
  const std::size_t bins = std::size_t(m.hist.m0) * std::size_t(m.hist.m1), q = std::size_t(m.hist.q);
  std::vector<double> avg(ch, 0.0);
  for (std::size_t k = 0; k < ch; ++k) {
    for (std::size_t b = 0; b < bins; ++b)
      for (std::size_t j = 0; j < q; ++j) avg[k] += m.hist.quantiles[(b * ch + k) * q + j];
    avg[k] /= double(bins * q);
  }
  for (std::size_t k = 0; k < ch; ++k) {
    double v = avg[k];
    if (!m.hist.basis.empty()) {  // linear: the mean maps through the basis
      v = m.hist.basis[k];
      for (std::size_t d = 0; d < ch; ++d) v += m.hist.basis[ch + d * ch + k] * avg[d];
    }
    s.mean[k] = float(v);
  }
  return s;
}

// tb, cs-tb: the exemplar's mean, the first entries of the PCA block (the render's mean up to the LUT's rounding).
NoiseModelSummary describe_tb(const std::any& decoded, const ModelContainer& c) {
  const TbModel& m = decoded_as<TbModel>(decoded);
  NoiseModelSummary s;
  s.channels = m.channels;
  s.mean.assign(m.pca.begin(), m.pca.begin() + m.channels);
  s.linear = model_is_linear(c);
  return s;
}

// The self-test rows of each kind's renderer (KindEntry::selftest_rows).
std::vector<SelftestRow> rows_texton(const std::any& decoded, const RenderParams& params, const NoiseRendererOptions& options,
                                     const DeviceInfo& device) {
  if (params.filter && params.scale < 1.0) return {filtered_selftest_row(false)};  // the box prefilter
  return {texton_selftest_row(texton_selftest_strategy(options.strategy, device), decoded_as<TextonModel>(decoded).order)};
}

std::vector<SelftestRow> rows_mix(const std::any& decoded, const RenderParams& params, const NoiseRendererOptions&,
                                  const DeviceInfo&) {
  if (params.filter && params.scale < 1.0) return {{kinds::mix, "filtered"}};  // the box prefilter
  const int order = decoded_as<MixModel>(decoded).order;
  return {{kinds::mix, order == 1 ? "gather" : "gather order " + std::to_string(order)}};
}

template <const char* kind>
std::vector<SelftestRow> rows_tb(const std::any& decoded, const RenderParams& params, const NoiseRendererOptions&,
                                 const DeviceInfo&) {
  const TbSetup setup = make_tb_setup(decoded_as<TbModel>(decoded), params);
  if (setup.aligned) return {{kind, "aligned"}};
  return {{kind, setup.params.unit_scale ? "sub-pixel" : "scaled"}};
}

std::vector<SelftestRow> rows_cs_spot(const std::any& decoded, const RenderParams& params, const NoiseRendererOptions&,
                                      const DeviceInfo&) {
  return {{kinds::cs_spot, make_cs_spot_setup(decoded_as<CsSpotModel>(decoded), params).params.canon ? "lattice"
                                                                                                      : "general"}};
}

std::vector<SelftestRow> rows_cs_rpn(const std::any& decoded, const RenderParams&, const NoiseRendererOptions&,
                                     const DeviceInfo&) {
  return {{kinds::cs_rpn, cs_rpn_variant_name(decoded_as<CsRpnModel>(decoded).variant)}};
}

// lrp and gabor: one gather path.
template <const char* kind>
std::vector<SelftestRow> rows_gather(const std::any&, const RenderParams&, const NoiseRendererOptions&,
                                     const DeviceInfo&) {
  return {{kind, "gather"}};
}

// gabor: the gather, plain or with filtered kernels (a minified view with RenderParams::filter).
std::vector<SelftestRow> rows_gabor(const std::any&, const RenderParams& params, const NoiseRendererOptions&,
                                    const DeviceInfo&) {
  return {{kinds::gabor, params.filter && params.scale < 1.0 ? "filtered" : "gather"}};
}

NoiseModelSummary describe_cs_rpn(const std::any& decoded, const ModelContainer& c) {
  const CsRpnModel& m = decoded_as<CsRpnModel>(decoded);
  const bool impulses = m.variant == CsRpnVariant::Gabor || m.variant == CsRpnVariant::Phasor;
  return {1, {float(m.mean)}, model_is_linear(c), impulses, cs_rpn_filters(m)};
}

}  // namespace

const std::vector<KindEntry>& kind_table() {
  // One entry per kind.
  static const std::vector<KindEntry> table = {
      {kinds::texton, decode_texton, summary_of<TextonModel, true, true>, make<TextonModel, TextonNoise>, rows_texton},
      {kinds::lrp, decode<lrp_from_container>, summary_of<LrpModel, false, true>, make<LrpModel, LrpNoise>,
       rows_gather<kinds::lrp>},
      {kinds::gabor, decode<gabor_from_container>, describe_gabor, make<GaborModel, GaborNoise>, rows_gabor},
      {kinds::mix, decode<mix_from_container>, describe_mix, make<MixModel, MixNoise>, rows_mix},
      {kinds::cs_spot, decode<cs_spot_from_container>, describe_cs_spot, make<CsSpotModel, CsSpotNoise>,
       rows_cs_spot},
      {kinds::tb, decode<tb_from_container>, describe_tb, make<TbModel, TbNoise>, rows_tb<kinds::tb>},
      {kinds::cs_tb, decode<tb_from_container>, describe_tb, make<TbModel, TbNoise>, rows_tb<kinds::cs_tb>},
      {kinds::cs_rpn, decode<cs_rpn_from_container>, describe_cs_rpn, make<CsRpnModel, CsRpnNoise>, rows_cs_rpn},
  };
  return table;
}

const KindEntry* find_kind(const std::string& name) {
  for (const KindEntry& e : kind_table())
    if (name == e.name) return &e;
  return nullptr;
}

std::vector<std::string> noise_kinds() {
  std::vector<std::string> names;
  for (const KindEntry& e : kind_table()) names.emplace_back(e.name);
  return names;
}

const KindEntry& kind_of(const ModelContainer& model, const std::string& what) {
  if (const KindEntry* e = find_kind(model.kind)) return *e;
  std::string known;
  for (const std::string& k : noise_kinds()) known += (known.empty() ? "" : ", ") + k;
  throw Error(ErrorKind::Input, "model '" + what + "' is of kind '" + model.kind +
                                    "', which this stex cannot render (known kinds: " + known + ")");
}

std::unique_ptr<NoiseRenderer> make_noise_renderer(Context& ctx, const ModelContainer& model,
                                                   const NoiseRendererOptions& options, const std::string& what) {
  const KindEntry& kind = kind_of(model, what);
  return kind.make_renderer(ctx, kind.decode(model, what), options);
}

std::vector<SelftestRow> selftest_rows_for(const ModelContainer& model, const RenderParams& params,
                                           const NoiseRendererOptions& options, const DeviceInfo& device,
                                           const std::string& what) {
  const KindEntry& kind = kind_of(model, what);
  return kind.selftest_rows(kind.decode(model, what), params, options, device);
}

NoiseModelSummary describe_noise_model(const ModelContainer& model, const std::string& what) {
  const KindEntry& kind = kind_of(model, what);
  return kind.describe(kind.decode(model, what), model);
}

void check_model(const ModelContainer& model, const std::string& what) { (void)describe_noise_model(model, what); }

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
