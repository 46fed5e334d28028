// Tiling and blending by example and the tb / cs-tb codec. See tb_model.h.
#include "analysis/tb_model.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"

namespace stex {

namespace {

using json = nlohmann::json;
constexpr double k_std = 1.0 / 6.0;  // T maps every channel to N(0.5, k_std^2) (Heitz & Neyret)

double phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }
double phi_inv(double p) {
  double lo = -40.0, hi = 40.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (phi(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

[[noreturn]] void bad(const std::string& what, const std::string& msg) {
  throw Error(ErrorKind::Input, "model '" + what + "': " + msg);
}

}  // namespace

TbModel tb_from_exemplar(const Image& e, const TbParams& params, const Lattice* periods) {
  if (e.channels < 1 || e.channels > STEX_TB_MAX_CHANNELS)
    throw Error(ErrorKind::Input, "tiling and blending needs an exemplar of 1..4 channels");
  if (params.lut_size < 2 || params.lut_size > 65536) throw Error(ErrorKind::Usage, "lut size must be 2..65536");
  if (params.histogram != 1 && params.histogram != 2)
    throw Error(ErrorKind::Usage, "tiling and blending needs --histogram stationary or cs");
  if (params.histogram == 2 && !periods)
    throw Error(ErrorKind::Usage, "--histogram cs and --delta need periods (--method cs-tb)");
  TbModel m;
  m.cs = periods != nullptr;
  m.width = e.width;
  m.height = e.height;
  m.channels = e.channels;
  m.tile = params.tile < 0.0 ? std::min(e.width, e.height) / 6.0 : params.tile;
  if (!(m.tile >= 2.0) || 2.0 * m.tile + 4.0 > std::min(e.width, e.height))
    throw Error(ErrorKind::Usage, "--tile must be at least 2 and at most (min(width, height) - 4) / 2 pixels");
  const int ch = e.channels;
  const std::size_t n = std::size_t(e.width) * e.height;
  // PCA: y = B (x - mean), B's rows the eigenvectors of the colour covariance.
  const ColourPca pca = colour_pca(e);
  m.pca = pca.device_basis();
  // Per PCA channel: ranks -> Gaussian (T), and the quantile function as the inverse LUT.
  m.lut_size = params.lut_size;
  m.gauss.resize(n * ch);
  m.lut.resize(std::size_t(ch) * m.lut_size);
  std::vector<double> y(n);
  std::vector<std::size_t> order(n);
  Image pc;  // the exemplar in PCA coordinates (for the cyclostationary transfer)
  pc.width = e.width;
  pc.height = e.height;
  pc.channels = ch;
  pc.pixels.resize(n * ch);
  for (int d = 0; d < ch; ++d) {
    for (std::size_t i = 0; i < n; ++i) {
      const double s = pca.project(&e.pixels[i * ch], d);
      y[i] = s;
      pc.pixels[i * ch + d] = float(s);
    }
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return y[a] < y[b]; });
    for (std::size_t r = 0; r < n; ++r)
      m.gauss[order[r] * ch + d] = float(0.5 + k_std * phi_inv((double(r) + 0.5) / double(n)));
    for (int j = 0; j < m.lut_size; ++j) {
      const double g = m.lut_lo + (m.lut_hi - m.lut_lo) * j / (m.lut_size - 1);
      const double pos = std::clamp(phi((g - 0.5) / k_std) * double(n) - 0.5, 0.0, double(n - 1));
      const std::size_t r0 = std::min(std::size_t(pos), n - 1), r1 = std::min(r0 + 1, n - 1);
      const double f = pos - double(r0);
      m.lut[std::size_t(d) * m.lut_size + j] = float(y[order[r0]] + f * (y[order[r1]] - y[order[r0]]));
    }
  }
  if (params.histogram == 2) {
    // S4 §5.3.2: each texel Gaussianised by its polyphase bin's T_b (replaces the stationary ranks above;
    // the stationary LUT stays in the model but is not used).
    Image eg;
    m.hist = build_cs_hist(pc, periods, 2, params.delta, &eg);
    m.gauss = eg.pixels;
  }
  if (m.cs) {
    validate_lattice(*periods, e.width, e.height);
    m.t0x = periods->t0x;
    m.t0y = periods->t0y;
    m.t1x = periods->t1x;
    m.t1y = periods->t1y;
    Image g;
    g.width = e.width;
    g.height = e.height;
    g.channels = ch;
    g.pixels = m.gauss;
    const CyclicMean cm = cyclic_mean(g, *periods);
    m.n0 = cm.n0;
    m.n1 = cm.n1;
    m.mean = cm.values;
  } else {
    m.mean.assign(ch, 0.5f);
  }
  try {
    validate_tb_model(m);
  } catch (const Error& err) {
    throw Error(ErrorKind::Usage, err.what());
  }
  return m;
}

ModelContainer to_container(const TbModel& m) {
  try {
    validate_tb_model(m);
  } catch (const Error& e) {
    throw Error(ErrorKind::Usage, e.what());
  }
  ModelContainer c;
  c.kind = m.cs ? "cs-tb" : "tb";
  c.metadata["format"] = "stex-model";
  c.metadata["kind"] = c.kind;
  c.metadata["channels"] = m.channels;
  c.metadata["tile"] = m.tile;
  c.metadata["exemplar_size"] = {m.width, m.height};
  c.metadata["lut"] = {{"size", m.lut_size}, {"lo", m.lut_lo}, {"hi", m.lut_hi}};
  if (m.cs) c.metadata["periods"] = json::array({json::array({m.t0x, m.t0y}), json::array({m.t1x, m.t1y})});
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
  if (model.kind != "tb" && model.kind != "cs-tb") bad(what, "model kind '" + model.kind + "' is not a tb or cs-tb model");
  ModelContainer c = model;
  const json& meta = c.metadata;
  TbModel m;
  m.cs = c.kind == "cs-tb";
  auto integer = [&](const json& j, const char* key, long lo, long hi) {
    const auto it = j.find(key);
    if (it == j.end() || !it->is_number_integer() || it->get<long long>() < lo || it->get<long long>() > hi)
      bad(what, std::string("metadata field '") + key + "' is missing or out of range");
    return int(it->get<long long>());
  };
  auto number = [&](const json& j, const char* key) {
    const auto it = j.find(key);
    if (it == j.end() || !it->is_number() || !std::isfinite(it->get<double>()))
      bad(what, std::string("metadata field '") + key + "' is missing or not a finite number");
    return it->get<double>();
  };
  m.channels = integer(meta, "channels", 1, STEX_TB_MAX_CHANNELS);
  m.tile = number(meta, "tile");
  const auto sz = meta.find("exemplar_size");
  if (sz == meta.end() || !sz->is_array() || sz->size() != 2 || !(*sz)[0].is_number_integer() || !(*sz)[1].is_number_integer())
    bad(what, "metadata field 'exemplar_size' must be [width, height]");
  m.width = int(std::clamp<long long>((*sz)[0].get<long long>(), 0, 1 << 20));
  m.height = int(std::clamp<long long>((*sz)[1].get<long long>(), 0, 1 << 20));
  if (m.width < 8 || m.height < 8 || m.width > 4096 || m.height > 4096) bad(what, "exemplar_size must be 8..4096");
  const auto lut = meta.find("lut");
  if (lut == meta.end() || !lut->is_object()) bad(what, "metadata field 'lut' is missing");
  m.lut_size = integer(*lut, "size", 2, 65536);
  m.lut_lo = number(*lut, "lo");
  m.lut_hi = number(*lut, "hi");
  const auto grid = meta.find("mean_grid");
  if (grid == meta.end() || !grid->is_object()) bad(what, "metadata field 'mean_grid' is missing");
  m.n0 = integer(*grid, "n0", 1, 4096);
  m.n1 = integer(*grid, "n1", 1, 4096);
  if (m.cs) {
    const auto per = meta.find("periods");
    if (per == meta.end() || !per->is_array() || per->size() != 2 || !(*per)[0].is_array() || !(*per)[1].is_array() ||
        (*per)[0].size() != 2 || (*per)[1].size() != 2 || !(*per)[0][0].is_number() || !(*per)[0][1].is_number() ||
        !(*per)[1][0].is_number() || !(*per)[1][1].is_number())
      bad(what, "metadata field 'periods' must be [[t0x, t0y], [t1x, t1y]]");
    m.t0x = (*per)[0][0].get<double>();
    m.t0y = (*per)[0][1].get<double>();
    m.t1x = (*per)[1][0].get<double>();
    m.t1y = (*per)[1][1].get<double>();
  }
  m.hist = cs_hist_from_container(c, m.channels, what);  // takes its floats off the payload's end
  const std::size_t ng = std::size_t(m.width) * m.height * m.channels, nl = std::size_t(m.lut_size) * m.channels;
  const std::size_t np = std::size_t(m.channels) * (m.channels + 1), nm = std::size_t(m.n0) * m.n1 * m.channels;
  if (c.payload.size() != ng + nl + np + nm)
    bad(what, "payload has " + std::to_string(c.payload.size()) + " floats, the fields need " + std::to_string(ng + nl + np + nm));
  auto it = c.payload.begin();
  m.gauss.assign(it, it + std::ptrdiff_t(ng));
  it += std::ptrdiff_t(ng);
  m.lut.assign(it, it + std::ptrdiff_t(nl));
  it += std::ptrdiff_t(nl);
  m.pca.assign(it, it + std::ptrdiff_t(np));
  it += std::ptrdiff_t(np);
  m.mean.assign(it, c.payload.end());
  try {
    validate_tb_model(m);
  } catch (const Error& e) {
    bad(what, e.what());
  }
  return m;
}

}  // namespace stex
