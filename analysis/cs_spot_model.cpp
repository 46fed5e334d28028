// Cyclostationary spot noise by example and the "cs-spot" codec. See cs_spot_model.h.
#include "analysis/cs_spot_model.h"

#include <cmath>

#include "core/error.h"
#include "core/math.h"

namespace stex {

namespace {

using json = nlohmann::json;

[[noreturn]] void bad(const std::string& what, const std::string& msg) { bad_model_field(what, msg); }

double number(const json& j, const char* key, const std::string& what) { return model_number(j, key, what); }

int integer(const json& j, const char* key, long lo, long hi, const std::string& what) {
  return int(model_integer(j, key, lo, hi, what));
}

// The 1-D window: a sin^2 ramp over `b` texels at each end, 1 inside.
std::vector<double> taper(int n, int b) {
  std::vector<double> w(n, 1.0);
  for (int i = 0; i < b && i < n; ++i) {
    const double s = std::sin(0.5 * k_pi * (i + 0.5) / b);
    w[i] = std::min(w[i], s * s);
    w[n - 1 - i] = std::min(w[n - 1 - i], s * s);
  }
  return w;
}

}  // namespace

CsSpotModel cs_spot_from_exemplar(const Image& exemplar, const Lattice& t, const CsSpotParams& params, CsSpotReport* report) {
  validate_lattice(t, exemplar.width, exemplar.height);
  // With a histogram transfer the noise is made of the Gaussianised exemplar E_G (S4 §5.3.2).
  Image gaussianised;
  CsHistTable hist;
  if (params.histogram != 0) {
    // In the PCA basis of the colours, as tiling and blending: channels transferred independently in the
    // colour basis would recombine into false colours (a binary orange / teal motif gives pink and green).
    std::vector<float> basis;
    Image coords;
    pca_coordinates(exemplar, &basis, &coords);
    hist = build_cs_hist(coords, &t, params.histogram, params.delta, &gaussianised);
    hist.basis = std::move(basis);
  }
  const Image& e = params.histogram != 0 ? gaussianised : exemplar;
  if (e.channels < 1 || e.channels > STEX_CS_MAX_CHANNELS)
    throw Error(ErrorKind::Input, "cs-spot needs an exemplar of 1..4 channels, got " + std::to_string(e.channels));
  if (e.width > k_cs_max_spot || e.height > k_cs_max_spot)
    throw Error(ErrorKind::Limit, "cs-spot exemplars are at most 4096 pixels on each side (the spot is the exemplar)");
  const int b = params.border < 0 ? std::min(e.width, e.height) / 8 : params.border;
  if (b > std::min(e.width, e.height) / 2)
    throw Error(ErrorKind::Usage, "--border must be at most half the exemplar's smaller side (" +
                                      std::to_string(std::min(e.width, e.height) / 2) + "), got " + std::to_string(b));
  const CyclicMean m = cyclic_mean(e, t);
  CsSpotModel s;
  s.t0x = t.t0x;
  s.t0y = t.t0y;
  s.t1x = t.t1x;
  s.t1y = t.t1y;
  s.width = e.width;
  s.height = e.height;
  s.channels = e.channels;
  s.n0 = m.n0;
  s.n1 = m.n1;
  s.mean = m.values;
  s.spot.resize(e.pixels.size());
  const std::vector<double> wx = taper(e.width, b), wy = taper(e.height, b);
  double ex = 0.0, ey = 0.0;
  for (double v : wx) ex += v * v;
  for (double v : wy) ey += v * v;
  for (int j = 0; j < e.height; ++j)
    for (int i = 0; i < e.width; ++i) {
      double u, v;
      lattice_phase(t, i + 0.5, j + 0.5, &u, &v);
      for (int c = 0; c < e.channels; ++c)
        s.spot[(std::size_t(j) * e.width + i) * e.channels + c] = float(wx[i] * wy[j] * (e.at(i, j, c) - m.at(u, v, c)));
    }
  s.amplitude = std::sqrt(lattice_area(t) / (ex * ey));
  s.hist = std::move(hist);
  validate_cs_spot_model(s);
  if (report) {
    report->periods = t;
    report->border = b;
    report->window_energy = ex * ey;
    report->mean_samples = m.min_samples;
  }
  return s;
}

ModelContainer to_container(const CsSpotModel& m, const CsModelInfo& info) {
  try {
    validate_cs_spot_model(m);
  } catch (const Error& e) {
    throw Error(ErrorKind::Usage, e.what());
  }
  ModelContainer c;
  c.kind = "cs-spot";
  c.metadata["format"] = "stex-model";
  c.metadata["kind"] = "cs-spot";
  c.metadata["channels"] = m.channels;
  c.metadata["periods"] = json::array({json::array({m.t0x, m.t0y}), json::array({m.t1x, m.t1y})});
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
  if (model.kind != "cs-spot") bad(what, "model kind '" + model.kind + "' is not a cs-spot model (this needs kind 'cs-spot')");
  ModelContainer c = model;
  const int channels = integer(c.metadata, "channels", 1, STEX_CS_MAX_CHANNELS, what);
  const CsHistTable hist = cs_hist_from_container(c, channels, what);  // takes its floats off the payload's end
  if (c.kind != "cs-spot") bad(what, "model kind '" + c.kind + "' is not a cs-spot model (this needs kind 'cs-spot')");
  const json& meta = c.metadata;
  CsSpotModel m;
  m.channels = integer(meta, "channels", 1, STEX_CS_MAX_CHANNELS, what);
  const auto per = meta.find("periods");
  if (per == meta.end() || !per->is_array() || per->size() != 2 || !(*per)[0].is_array() || !(*per)[1].is_array() ||
      (*per)[0].size() != 2 || (*per)[1].size() != 2)
    bad(what, "metadata field 'periods' must be [[t0x, t0y], [t1x, t1y]]");
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      if (!(*per)[i][j].is_number() || !std::isfinite((*per)[i][j].get<double>()))
        bad(what, "metadata field 'periods' has a non-numeric or non-finite entry");
  m.t0x = (*per)[0][0].get<double>();
  m.t0y = (*per)[0][1].get<double>();
  m.t1x = (*per)[1][0].get<double>();
  m.t1y = (*per)[1][1].get<double>();
  const auto spot = meta.find("spot");
  if (spot == meta.end() || !spot->is_object()) bad(what, "metadata field 'spot' is missing");
  m.width = integer(*spot, "width", 2, k_cs_max_spot, what);
  m.height = integer(*spot, "height", 2, k_cs_max_spot, what);
  const auto grid = meta.find("mean_grid");
  if (grid == meta.end() || !grid->is_object()) bad(what, "metadata field 'mean_grid' is missing");
  m.n0 = integer(*grid, "n0", 1, k_cs_max_spot, what);
  m.n1 = integer(*grid, "n1", 1, k_cs_max_spot, what);
  m.amplitude = number(meta, "amplitude", what);
  const std::size_t ns = std::size_t(m.width) * m.height * m.channels, nm = std::size_t(m.n0) * m.n1 * m.channels;
  if (c.payload.size() != ns + nm)
    bad(what, "payload has " + std::to_string(c.payload.size()) + " floats, but the spot and the mean grid need " +
                  std::to_string(ns + nm));
  m.spot.assign(c.payload.begin(), c.payload.begin() + std::ptrdiff_t(ns));
  m.mean.assign(c.payload.begin() + std::ptrdiff_t(ns), c.payload.end());
  m.hist = hist;
  try {
    validate_cs_spot_model(m);
  } catch (const Error& e) {
    bad(what, e.what());
  }
  return m;
}

}  // namespace stex
