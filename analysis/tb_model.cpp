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

}  // namespace stex
