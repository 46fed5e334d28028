// Histogram transfer (S4 §5.3): stationary, and cyclostationary per polyphase bin with the δ neighbourhood,
// in cs-spot and cs-tb. The kernels against the C++ references bit for bit (with tables), tile invariance;
// on a synthetic CS exemplar whose polyphase components are binary with per-component levels and
// probabilities, the renders' per-component histograms match the exemplar's (KS distance, bounds from the
// sample sizes below) where the stationary transfer's do not; a stationary exemplar gives the stationary
// result; the table's memory bound; the codec, damaged fields, and the CLI.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "analysis/cs_hist.h"
#include "analysis/cs_spot_model.h"
#include "analysis/image_io.h"
#include "model/codecs.h"
#include "model/kinds.h"
#include "analysis/tb_model.h"
#include "cli_run.h"
#include "core/error.h"
#include "runtime/context.h"
#include "runtime/cs_spot.h"
#include "runtime/tb.h"
#include "test_device.h"
#include "tests/cs/cs_synthetic.h"

namespace stex {
namespace {

namespace fs = std::filesystem;
using test::cs_hash01;
using test::make_stationary;

Context& ctx() {
  static std::unique_ptr<Context> c = Context::create(stex::test::test_device_spec());
  return *c;
}

RenderParams params(std::uint64_t seed, double scale = 1.0) {
  RenderParams rp;
  rp.seed = seed;
  rp.scale = scale;
  return rp;
}

template <class N>
std::vector<float> device_render(N& n, const RenderParams& rp, std::int64_t x, std::int64_t y, int w, int h) {
  std::vector<float> out(std::size_t(w) * h * n.channels());
  n.render(rp, x, y, w, h, out.data());
  return out;
}

// The test exemplar: periods (12, 0), (0, 10) (integer and axis-aligned: the bins are exactly the texel
// polyphase components (i mod 12, j mod 10), 120 of them); 144 x 120 texels, 12 x 12 = 144 cells. Texel
// (i, j) of cell (k, l) is binary: hi(i, j) if U_kl < p(i, j) else lo(i, j), with U_kl uniform per cell (so
// a cell's "on" texels form a coherent motif) and levels and probabilities that differ between components:
// the global histogram mixes 240 levels, each component has two.
constexpr int k_p0 = 12, k_p1 = 10, k_w = 144, k_h = 120;
const Lattice k_t{double(k_p0), 0.0, 0.0, double(k_p1)};
double level_lo(int i, int j) { return 0.05 + 0.5 * i / (k_p0 - 1.0) + 0.02 * j; }
double level_hi(int i, int j) { return level_lo(i, j) + 0.2 + 0.15 * ((i + j) % 3); }
double prob_on(int i, int j) { return 0.2 + 0.6 * ((i + 2 * j) % 7) / 6.0; }
Image binary_cs_exemplar() {
  Image img;
  img.width = k_w;
  img.height = k_h;
  img.channels = 1;
  img.pixels.resize(std::size_t(k_w) * k_h);
  for (int y = 0; y < k_h; ++y)
    for (int x = 0; x < k_w; ++x) {
      const int i = x % k_p0, j = y % k_p1;
      const double u = cs_hash01(x / k_p0, y / k_p1, 77, 0);
      img.at(x, y, 0) = float(u < prob_on(i, j) ? level_hi(i, j) : level_lo(i, j));
    }
  return img;
}

// Two-sample Kolmogorov-Smirnov distance sup |F_a - F_b| (exact for ties: steps compared after each value).
double ks(std::vector<double> a, std::vector<double> b) {
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  std::size_t i = 0, j = 0;
  double d = 0.0;
  while (i < a.size() && j < b.size()) {
    const double v = std::min(a[i], b[j]);
    while (i < a.size() && a[i] <= v) ++i;
    while (j < b.size() && b[j] <= v) ++j;
    d = std::max(d, std::fabs(double(i) / a.size() - double(j) / b.size()));
  }
  return d;
}

// Per-component KS between the exemplar's component samples and the render's pixels of that component
// (pixel (x, y) of a render at origin (x0, y0), scale 1, belongs to component ((x0 + x) mod 12, (y0 + y) mod 10)).
struct KsStats {
  double max = 0.0, mean = 0.0;
};
// The KS distance of each component's render samples r[b] to its exemplar samples e[b]: max and mean over b.
KsStats components_ks(std::vector<std::vector<double>>& e, std::vector<std::vector<double>>& r) {
  KsStats s;
  for (std::size_t b = 0; b < e.size(); ++b) {
    // The inverse PCA (mean + basis x value, in float) moves a level by an ulp or two: a render value within
    // 1e-5 of an exemplar level is that level (the levels are at least 0.02 apart).
    std::sort(e[b].begin(), e[b].end());
    for (double& v : r[b]) {
      const auto it = std::lower_bound(e[b].begin(), e[b].end(), v);
      if (it != e[b].end() && *it - v < 1e-5) v = *it;
      if (it != e[b].begin() && v - *(it - 1) < 1e-5) v = *(it - 1);
    }
    const double d = ks(e[b], r[b]);
    s.max = std::max(s.max, d);
    s.mean += d / double(e.size());
  }
  return s;
}

KsStats per_component_ks(const Image& ex, const std::vector<std::vector<float>>& renders, std::int64_t x0, std::int64_t y0,
                         int w, int h) {
  std::vector<std::vector<double>> e(k_p0 * k_p1), r(k_p0 * k_p1);
  for (int y = 0; y < ex.height; ++y)
    for (int x = 0; x < ex.width; ++x) e[std::size_t((y % k_p1) * k_p0 + x % k_p0)].push_back(ex.at(x, y, 0));
  for (const auto& img : renders)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const int i = int(((x0 + x) % k_p0 + k_p0) % k_p0), j = int(((y0 + y) % k_p1 + k_p1) % k_p1);
        r[std::size_t(j * k_p0 + i)].push_back(img[std::size_t(y) * w + x]);
      }
  return components_ks(e, r);
}

// Bounds for a two-sample KS distance between n_e exemplar samples (the 144 cells, independent) and m_eff
// effectively independent render samples, s = sqrt(1/n_e + 1/m_eff): the max over the 120 components at
// total level 0.001 (Bonferroni: per component 8.3e-6, Kolmogorov quantile sqrt(-ln(alpha/2)/2) = 2.49);
// the mean over components at most the Kolmogorov mean 0.87 s plus 3 of its standard deviations 0.26 s
// (no credit for averaging: the components' distances are correlated through shared tiles or weights).
// Ties (binary data) only make KS smaller.
double bound_max(double n_e, double m_eff) { return 2.49 * std::sqrt(1.0 / n_e + 1.0 / m_eff); }
double bound_mean(double n_e, double m_eff) { return (0.87 + 3.0 * 0.26) * std::sqrt(1.0 / n_e + 1.0 / m_eff); }

TEST(CsHist, TableShapeMemoryBoundAndGaussianisation) {
  const Image ex = binary_cs_exemplar();
  Image g;
  const CsHistTable t = build_cs_hist(ex, &k_t, 2, 0, &g);
  EXPECT_EQ(t.m0, 12);
  EXPECT_EQ(t.m1, 10);
  EXPECT_EQ(t.q, 144);  // floor(144 * 120 / 120): the table is exactly the exemplar's size
  EXPECT_LE(std::size_t(t.m0) * t.m1 * t.q, std::size_t(k_w) * k_h);
  // δ = 0: each component is Gaussianised alone by ranks: its 144 values are exactly the 144 rank Gaussians
  // (mean 0.5 up to float rounding, the same sorted set in every component).
  std::vector<double> first;
  for (int b = 0; b < 120; ++b) {
    std::vector<double> v;
    for (int y = b / 12; y < k_h; y += 10)
      for (int x = b % 12; x < k_w; x += 12) v.push_back(g.at(x, y, 0));
    std::sort(v.begin(), v.end());
    if (b == 0) first = v;
    ASSERT_EQ(v, first) << b;
  }
  double m = 0.0;
  for (double v : first) m += v / 144.0;
  EXPECT_NEAR(m, 0.5, 1e-6);
  // Quantiles of a binary component: lo then hi, one interpolated step between.
  const float* q0 = &t.quantiles[0];
  EXPECT_FLOAT_EQ(q0[0], float(level_lo(0, 0)));
  EXPECT_FLOAT_EQ(q0[143], float(level_hi(0, 0)));
  // Skewed and sub-pixel periods: the bins stay within |Ω⁻| and the table within the exemplar.
  const Lattice sk{13.71, -5.23, 6.14, 15.92};
  int m0, m1;
  cs_hist_bins(sk, &m0, &m1);
  EXPECT_LE(double(m0) * m1, lattice_area(sk));
  const CsHistTable ts = build_cs_hist(ex, &sk, 2, 1, nullptr);
  EXPECT_LE(double(ts.m0) * ts.m1 * ts.q, double(k_w) * k_h);
  EXPECT_NO_THROW(validate_cs_hist(ts, 1, k_w, k_h, "t"));
}

const TbModel& tb_model(int histogram, int delta) {
  static std::map<int, TbModel> cache;
  const int key = histogram * 100 + delta;
  if (!cache.count(key)) {
    TbParams p;
    p.tile = 16.0;
    p.histogram = histogram;
    p.delta = delta;
    cache[key] = tb_from_container(to_container(tb_from_exemplar(binary_cs_exemplar(), p, &k_t)));
  }
  return cache[key];
}
const CsSpotModel& spot_model(int histogram, int delta) {
  static std::map<int, CsSpotModel> cache;
  const int key = histogram * 100 + delta;
  if (!cache.count(key)) {
    CsSpotParams p;
    p.histogram = histogram;
    p.delta = delta;
    cache[key] = cs_spot_from_container(to_container(cs_spot_from_exemplar(binary_cs_exemplar(), k_t, p)));
  }
  return cache[key];
}

TEST(CsHist, KernelsEqualReferencesWithTables) {
  const std::int64_t far = 1000000000000LL;
  {
    const TbModel& m = tb_model(2, 1);
    ASSERT_TRUE(m.hist.enabled());
    TbNoise noise(ctx(), m);
    for (double scale : {1.0, 0.43}) {
      const RenderParams rp = params(5, scale);
      EXPECT_EQ(device_render(noise, rp, -31, 12, 40, 24), TbReference(m, rp).render(-31, 12, 40, 24)) << scale;
    }
    EXPECT_EQ(device_render(noise, params(5), -far, far, 24, 16), TbReference(m, params(5)).render(-far, far, 24, 16));
  }
  for (int mode : {1, 2}) {
    const CsSpotModel& m = spot_model(mode, 1);
    CsSpotNoise noise(ctx(), m);
    for (double scale : {1.0, 0.43}) {
      const RenderParams rp = params(6, scale);
      EXPECT_EQ(device_render(noise, rp, 40, -9, 24, 16), CsSpotReference(m, rp).render(40, -9, 24, 16)) << mode << scale;
    }
    EXPECT_EQ(device_render(noise, params(6), far, -far, 16, 8), CsSpotReference(m, params(6)).render(far, -far, 16, 8));
  }
}

template <class N, class M>
void expect_tile_invariance(const M& m) {
  N whole(ctx(), m);
  const int w = 50, h = 38;
  const std::vector<float> ref = device_render(whole, params(3), 7, -40, w, h);
  N tiled(ctx(), m);
  tiled.local_size = {8, 2};
  tiled.max_chunk_pixels = 101;
  std::vector<float> assembled(ref.size());
  for (int ty = 0; ty < h; ty += 16)
    for (int tx = 0; tx < w; tx += 20) {
      const int tw = std::min(20, w - tx), th = std::min(16, h - ty);
      const std::vector<float> tile = device_render(tiled, params(3), 7 + tx, -40 + ty, tw, th);
      for (int j = 0; j < th; ++j)
        std::copy(tile.begin() + std::ptrdiff_t(j) * tw, tile.begin() + std::ptrdiff_t(j + 1) * tw,
                  assembled.begin() + std::ptrdiff_t(ty + j) * w + tx);
    }
  EXPECT_EQ(assembled, ref);
  EXPECT_EQ(device_render(whole, params(3), 7, -40, w, h), ref);  // deterministic
  EXPECT_NE(device_render(whole, params(4), 7, -40, w, h), ref);
}

TEST(CsHist, TilesChunksAndWorkGroupsGiveTheSameBits) {
  expect_tile_invariance<TbNoise>(tb_model(2, 1));
  expect_tile_invariance<CsSpotNoise>(spot_model(2, 1));
}

// cs-tb on the binary CS exemplar. Renders: 4 seeds x 360 x 300 pixels at origin (1000, -700), tile 16. The
// render's effective sample size per component, conservatively, is the number of grid vertices (one
// independent tile draw each; a pixel's value depends on 3 of them, and a tile holds several independent
// cells, so this undercounts): 4 x 360 x 300 / (16^2 sqrt(3) / 2) = 1949. With n_e = 144 cells: max KS
// bound 0.225, mean bound 0.151.
TEST(CsHist, CsTbKeepsTheComponentHistogramsWhereTheStationaryTransferDoesNot) {
  const Image ex = binary_cs_exemplar();
  const int w = 360, h = 300;
  const std::int64_t x0 = 1000, y0 = -700;
  auto run = [&](const TbModel& m) {
    std::vector<std::vector<float>> r;
    TbNoise noise(ctx(), m);
    for (std::uint64_t seed = 1; seed <= 4; ++seed) r.push_back(device_render(noise, params(seed), x0, y0, w, h));
    return per_component_ks(ex, r, x0, y0, w, h);
  };
  const double m_eff = 4.0 * w * h / (16.0 * 16.0 * std::sqrt(3.0) / 2.0);
  const KsStats cs0 = run(tb_model(2, 0)), cs1 = run(tb_model(2, 1)), st = run(tb_model(1, 1));
  std::printf("cs-tb per-component KS: cs delta 0 max %.4f mean %.4f; cs delta 1 max %.4f mean %.4f; stationary max %.4f mean %.4f "
              "(bounds max %.4f mean %.4f)\n",
              cs0.max, cs0.mean, cs1.max, cs1.mean, st.max, st.mean, bound_max(144, m_eff), bound_mean(144, m_eff));
  EXPECT_LE(cs0.max, bound_max(144, m_eff));
  EXPECT_LE(cs0.mean, bound_mean(144, m_eff));
  // The stationary transfer blends other components' levels into each one: far outside the bounds.
  EXPECT_GT(st.mean, bound_max(144, m_eff));
  EXPECT_GT(st.mean, 3.0 * cs0.mean);
  // δ = 1 pools 9 components of different levels (this exemplar changes from one texel to the next): worse
  // than δ = 0 here, still better than the stationary transfer (S4 Fig. 9's compromise).
  EXPECT_LT(cs1.mean, st.mean);
}

// cs-spot on the binary CS exemplar. Renders: 2 seeds x 168 x 140 pixels at origin (-333, 250). A pixel's
// value is Gaussian (a sum of N(0, 1) weights) with mean M_G and the covariance of Appendix A; two pixels of
// one component (a lattice vector apart) are correlated by sum_u S(x - u) S(x + t - u), a sum of products of
// different cells' independent values: close to 0, so every pixel counts: m_eff = 2 x 168 x 140 / 120 = 392
// per component. Bounds (n_e = 144): max 0.240, mean 0.161. Without a transfer the render is Gaussian and
// the stationary transfer mixes levels: both far outside.
TEST(CsHist, CsSpotKeepsTheComponentHistogramsWhereTheStationaryTransferDoesNot) {
  const Image ex = binary_cs_exemplar();
  const int w = 168, h = 140;
  const std::int64_t x0 = -333, y0 = 250;
  auto run = [&](const CsSpotModel& m) {
    std::vector<std::vector<float>> r;
    CsSpotNoise noise(ctx(), m);
    for (std::uint64_t seed = 1; seed <= 2; ++seed) r.push_back(device_render(noise, params(seed), x0, y0, w, h));
    return per_component_ks(ex, r, x0, y0, w, h);
  };
  const double m_eff = 2.0 * w * h / 120.0;
  const KsStats cs0 = run(spot_model(2, 0)), st = run(spot_model(1, 0)), none = run(spot_model(0, 1));
  std::printf("cs-spot per-component KS: cs delta 0 max %.4f mean %.4f; stationary max %.4f mean %.4f; none max %.4f mean %.4f "
              "(bounds max %.4f mean %.4f)\n",
              cs0.max, cs0.mean, st.max, st.mean, none.max, none.mean, bound_max(144, m_eff), bound_mean(144, m_eff));
  EXPECT_LE(cs0.max, bound_max(144, m_eff));
  EXPECT_LE(cs0.mean, bound_mean(144, m_eff));
  EXPECT_GT(st.mean, bound_max(144, m_eff));
  EXPECT_GT(st.mean, 3.0 * cs0.mean);
  EXPECT_GT(none.mean, bound_max(144, m_eff));
}

// A skewed lattice with non-integer periods t0 = (11.5, 1.25), t1 = (-2, 9.5) (|Ω⁻| = 111.75 px²): the
// polyphase bins are then cs_hist_bins' m0 x m1 = 11 x 9 = 99 cells of the phase square, and a texel or pixel
// belongs to the bin of its centre's phase. Exemplar 144 x 120: texel of lattice cell (k, l) and bin (a, b) is
// hi(a, b) if U_kl < p(a, b) else lo(a, b), U_kl uniform per lattice cell. Per-bin KS as above; n_e: the
// ~155 lattice cells the exemplar overlaps (two texels of one cell in one bin share U_kl: cells, not texels,
// are the independent samples). The bounds use the 120-component Bonferroni constant (99 here: conservative).
const Lattice k_skew{11.5, 1.25, -2.0, 9.5};
int skew_bin(double x, double y, int m0, int m1) {
  double u, v;
  lattice_phase(k_skew, x, y, &u, &v);
  const int a = std::min(m0 - 1, int(std::floor(u * m0))), b = std::min(m1 - 1, int(std::floor(v * m1)));
  return b * m0 + a;
}
Image binary_skewed_exemplar(int m0, int m1) {
  Image img;
  img.width = k_w;
  img.height = k_h;
  img.channels = 1;
  img.pixels.resize(std::size_t(k_w) * k_h);
  for (int y = 0; y < k_h; ++y)
    for (int x = 0; x < k_w; ++x) {
      double ka, lb;
      lattice_coords(k_skew, x + 0.5, y + 0.5, &ka, &lb);
      const int bin = skew_bin(x + 0.5, y + 0.5, m0, m1), a = bin % m0, b = bin / m0;
      const double u = cs_hash01(int(std::floor(ka)), int(std::floor(lb)), 78, 0);
      img.at(x, y, 0) = float(u < prob_on(a, b) ? level_hi(a, b) : level_lo(a, b));
    }
  return img;
}
KsStats per_bin_ks(const Image& ex, const std::vector<std::vector<float>>& renders, std::int64_t x0, std::int64_t y0,
                   int w, int h, int m0, int m1) {
  std::vector<std::vector<double>> e(std::size_t(m0) * m1), r(std::size_t(m0) * m1);
  for (int y = 0; y < ex.height; ++y)
    for (int x = 0; x < ex.width; ++x) e[std::size_t(skew_bin(x + 0.5, y + 0.5, m0, m1))].push_back(ex.at(x, y, 0));
  for (const auto& img : renders)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        r[std::size_t(skew_bin(double(x0 + x) + 0.5, double(y0 + y) + 0.5, m0, m1))].push_back(img[std::size_t(y) * w + x]);
  return components_ks(e, r);
}

TEST(CsHist, SkewedNonIntegerPeriodsKeepTheBinHistograms) {
  int m0 = 0, m1 = 0;
  cs_hist_bins(k_skew, &m0, &m1);
  ASSERT_EQ(m0, 11);
  ASSERT_EQ(m1, 9);
  const Image ex = binary_skewed_exemplar(m0, m1);
  const double n_e = double(k_w) * k_h / lattice_area(k_skew);  // ~155 lattice cells
  // cs-tb (tile 16): renders 4 seeds x 360 x 300 at (1000, -700); m_eff = grid vertices, as above.
  const int w = 360, h = 300;
  const std::int64_t x0 = 1000, y0 = -700;
  auto run_tb = [&](int histogram) {
    TbParams p;
    p.tile = 16.0;
    p.histogram = histogram;
    p.delta = 0;
    const TbModel m = tb_from_container(to_container(tb_from_exemplar(ex, p, &k_skew)));
    TbNoise noise(ctx(), m);
    std::vector<std::vector<float>> r;
    for (std::uint64_t seed = 1; seed <= 4; ++seed) r.push_back(device_render(noise, params(seed), x0, y0, w, h));
    return per_bin_ks(ex, r, x0, y0, w, h, m0, m1);
  };
  const double m_tb = 4.0 * w * h / (16.0 * 16.0 * std::sqrt(3.0) / 2.0);
  const KsStats tb_cs = run_tb(2), tb_st = run_tb(1);
  // cs-spot: 2 seeds x 168 x 140 at (-333, 250); every pixel of a bin counts (as above): m_eff = pixels / bins.
  const int ws = 168, hs = 140;
  const std::int64_t xs = -333, ys = 250;
  auto run_spot = [&](int histogram) {
    CsSpotParams p;
    p.histogram = histogram;
    p.delta = 0;
    const CsSpotModel m = cs_spot_from_container(to_container(cs_spot_from_exemplar(ex, k_skew, p)));
    CsSpotNoise noise(ctx(), m);
    std::vector<std::vector<float>> r;
    for (std::uint64_t seed = 1; seed <= 2; ++seed) r.push_back(device_render(noise, params(seed), xs, ys, ws, hs));
    return per_bin_ks(ex, r, xs, ys, ws, hs, m0, m1);
  };
  const double m_spot = 2.0 * ws * hs / double(m0 * m1);
  const KsStats sp_cs = run_spot(2), sp_st = run_spot(1);
  std::printf("skewed periods, per-bin KS: cs-tb cs max %.4f mean %.4f, stationary max %.4f mean %.4f (bounds %.4f / %.4f); "
              "cs-spot cs max %.4f mean %.4f, stationary max %.4f mean %.4f (bounds %.4f / %.4f)\n",
              tb_cs.max, tb_cs.mean, tb_st.max, tb_st.mean, bound_max(n_e, m_tb), bound_mean(n_e, m_tb), sp_cs.max,
              sp_cs.mean, sp_st.max, sp_st.mean, bound_max(n_e, m_spot), bound_mean(n_e, m_spot));
  EXPECT_LE(tb_cs.max, bound_max(n_e, m_tb));
  EXPECT_LE(tb_cs.mean, bound_mean(n_e, m_tb));
  EXPECT_GT(tb_st.mean, bound_max(n_e, m_tb));
  EXPECT_LE(sp_cs.max, bound_max(n_e, m_spot));
  EXPECT_LE(sp_cs.mean, bound_mean(n_e, m_spot));
  EXPECT_GT(sp_st.mean, bound_max(n_e, m_spot));
}

// Stationary exemplar (blurred white noise): (1) with δ covering every bin, each bin pools the whole
// exemplar: the Gaussianised exemplar is bit for bit the stationary transfer's (up to the order of tied values), and every bin's T^-1 is the
// stationary one up to the quantile grids (144 vs 1024 points of the same sorted data: the difference is at
// most the largest gap between consecutive stationary quantiles in the range compared). (2) With δ = 1 the
// cs-tb render's global histogram equals the stationary transfer's render's: KS between them (same seeds)
// at most the two-sample bound at level 0.001 (c = 1.95) for m_eff = grid vertices of each render.
TEST(CsHist, StationaryExemplarGivesTheStationaryResult) {
  const Image ex = make_stationary(k_w, k_h, 1, 2, 41);
  Image gs, gc;
  const CsHistTable st = build_cs_hist(ex, nullptr, 1, 0, &gs);
  const CsHistTable cov = build_cs_hist(ex, &k_t, 2, 6, &gc);
  // Same pool (the whole exemplar) and ranks: E_G agrees bit for bit at every texel whose value is not tied
  // (tied texels are ordered by the cell hash in cs mode, the texel hash in stationary mode), and the sets
  // of values are equal.
  {
    std::vector<float> sorted = ex.pixels;
    std::sort(sorted.begin(), sorted.end());
    std::size_t differ = 0, tied = 0;
    for (std::size_t i = 0; i < ex.pixels.size(); ++i) {
      const auto r = std::equal_range(sorted.begin(), sorted.end(), ex.pixels[i]);
      const bool is_tied = r.second - r.first > 1;
      tied += is_tied;
      if (gc.pixels[i] != gs.pixels[i]) {
        ++differ;
        EXPECT_TRUE(is_tied) << i;
      }
    }
    std::vector<float> a = gc.pixels, b = gs.pixels;
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    EXPECT_EQ(a, b);
    std::printf("covering delta: E_G differs at %zu texels, all tied (%zu tied of %zu)\n", differ, tied, ex.pixels.size());
  }
  EXPECT_EQ(st.m0 * st.m1, 1);
  const stex_cs_hist_params hs = cs_hist_params(st), hc = cs_hist_params(cov);
  const std::vector<float> ts = cs_hist_device_table(st), tc = cs_hist_device_table(cov);
  double gap = 0.0;
  for (int k = 1; k < st.q; ++k) gap = std::max(gap, double(st.quantiles[k] - st.quantiles[k - 1]) * (k > 20 && k < st.q - 20));
  double worst = 0.0;
  for (int b = 0; b < cov.m0 * cov.m1; ++b)
    for (int i = 0; i <= 100; ++i) {
      const float g = 0.5f + (float(i) / 100.0f - 0.5f) * 0.5f;  // 0.5 -+ 1.5 sigma
      worst = std::max(worst, double(std::fabs(stex_cs_hist_inv(hc, tc.data(), b, 0, g) - stex_cs_hist_inv(hs, ts.data(), 0, 0, g))));
    }
  std::printf("covering delta: max |T_b^-1 - T^-1| %.3g (largest quantile gap %.3g)\n", worst, gap);
  EXPECT_LE(worst, gap);

  TbParams p;
  p.tile = 16.0;
  TbModel a = tb_from_exemplar(ex, p, &k_t);
  p.histogram = 2;
  p.delta = 1;
  TbModel b = tb_from_exemplar(ex, p, &k_t);
  const int w = 240, h = 200;
  std::vector<double> ra, rb;
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    for (float v : TbReference(a, params(seed)).render(0, 0, w, h)) ra.push_back(v);
    for (float v : TbReference(b, params(seed + 10)).render(0, 0, w, h)) rb.push_back(v);
  }
  const double m_eff = 2.0 * w * h / (16.0 * 16.0 * std::sqrt(3.0) / 2.0);
  const double d = ks(ra, rb), bound = 1.95 * std::sqrt(2.0 / m_eff);
  std::printf("stationary exemplar: KS(cs-tb delta 1 render, stationary render) %.4f (bound %.4f)\n", d, bound);
  EXPECT_LE(d, bound);
}

TEST(CsHist, CodecRoundTripOldFilesAndDamage) {
  const TbModel& m = tb_model(2, 1);
  const ModelContainer c = to_container(m);
  ASSERT_TRUE(c.metadata.contains("histogram"));
  EXPECT_EQ(c.metadata["histogram"]["mode"], "cs");
  const TbModel back = tb_from_container(c);
  EXPECT_EQ(back.hist.quantiles, m.hist.quantiles);
  EXPECT_EQ(back.gauss, m.gauss);
  EXPECT_NO_THROW(check_model(c, "m"));
  // A file without the field (written before the transfer existed) loads as the stationary LUT.
  const ModelContainer old = to_container(tb_model(1, 1));
  EXPECT_FALSE(old.metadata.contains("histogram"));
  EXPECT_FALSE(tb_from_container(old).hist.enabled());
  const ModelContainer sc = to_container(spot_model(2, 1));
  EXPECT_EQ(cs_spot_from_container(sc).hist.quantiles, spot_model(2, 1).hist.quantiles);
  EXPECT_NO_THROW(check_model(sc, "s"));
  auto expect_input = [](const ModelContainer& d, const char* what) {
    try {
      check_model(d, "damaged");
      ADD_FAILURE() << "accepted: " << what;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << what;
      EXPECT_NE(std::string(e.what()).find("histogram"), std::string::npos) << what << ": " << e.what();
    }
  };
  EXPECT_EQ(sc.metadata["histogram"]["pca"], true);  // cs-spot transfers in the PCA basis; cs-tb has its own
  EXPECT_EQ(c.metadata["histogram"]["pca"], false);
  for (const ModelContainer* base : {&c, &sc}) {
    // The last quantile (before cs-spot's 1 + 1 basis floats).
    const std::size_t last = base->payload.size() - 1 - (base == &sc ? 2 : 0);
    ModelContainer d = *base;
    d.payload[last] = d.payload[last - 1] - 1.0f;  // below its predecessor
    expect_input(d, "non-monotone");
    d = *base;
    d.payload[last] = std::nanf("");
    expect_input(d, "nan");
    d = *base;
    d.payload.back() = std::nanf("");
    expect_input(d, "nan at the end");
    d = *base;
    d.metadata["histogram"]["pca"] = !d.metadata["histogram"]["pca"].get<bool>();  // the payload no longer matches
    EXPECT_THROW(check_model(d, "damaged"), Error);
    d = *base;
    d.metadata["histogram"]["mode"] = "bogus";
    expect_input(d, "mode");
    d = *base;
    d.metadata["histogram"]["q"] = 100000;
    expect_input(d, "q range");
    d = *base;
    d.metadata["histogram"]["bins"] = {120, 120};  // more than the exemplar: payload too short
    expect_input(d, "bins");
    d = *base;
    d.metadata["histogram"]["delta"] = -1;
    expect_input(d, "delta");
  }
  // A table larger than the exemplar is refused even when the payload matches it.
  TbModel big = m;
  big.hist.q = 145;
  big.hist.quantiles.assign(std::size_t(big.hist.m0) * big.hist.m1 * 145, 0.5f);
  EXPECT_THROW(validate_tb_model(big), Error);
}

TEST(CsHistCli, AnalyzeWithDeltaAndRender) {
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / "cs_hist_cli";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string ex = (dir / "binary.exr").string(), model = (dir / "m.stex").string();
  write_image_atomic(ex, binary_cs_exemplar());
  auto stex = [&](const std::string& args) { return test::run_stex_cli(args, "cs_hist_cli"); };
  test::CliRun r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-tb --periods 12,0,0,10 --tile 16 --delta 1 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["histogram"], "cs");
  EXPECT_EQ(j["delta"], 1);
  EXPECT_EQ(j["histogram_bins"][0], 12);
  const TbModel m = tb_from_container(load_container(model));
  EXPECT_EQ(m.hist.quantiles, tb_model(2, 1).hist.quantiles);
  const std::vector<float> ref = TbReference(m, params(4)).render(-7, 3, 40, 20);
  r = stex("render '" + model + "' -o '" + (dir / "t_{tx}_{ty}.exr").string() + "' --size 40x20 --origin -7,3 --seed 4 --tile-size 20");
  ASSERT_EQ(r.code, 0) << r.err;
  const Image t00 = load_exemplar((dir / "t_0_0.exr").string()), t10 = load_exemplar((dir / "t_1_0.exr").string());
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 40; ++x)
      ASSERT_EQ(x < 20 ? t00.at(x, y, 0) : t10.at(x - 20, y, 0), ref[std::size_t(y) * 40 + x]) << x << "," << y;
  r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-spot --periods 12,0,0,10 --histogram cs --delta 0 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["histogram"], "cs");
  EXPECT_EQ(cs_spot_from_container(load_container(model)).hist.quantiles, spot_model(2, 0).hist.quantiles);
  r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-spot --periods 12,0,0,10 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["histogram"], "none");
  // Bad input: exit 2, the message naming the problem.
  r = stex("analyze '" + ex + "' -o '" + model + "' --method tb --delta 1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--delta does not apply to --method tb"), std::string::npos) << r.err;
  r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-tb --periods 12,0,0,10 --histogram stationary --delta 2");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--delta"), std::string::npos) << r.err;
  r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-tb --periods 12,0,0,10 --histogram gaussian");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--histogram must be none, stationary or cs"), std::string::npos) << r.err;
  r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-tb --periods 12,0,0,10 --histogram none");
  EXPECT_EQ(r.code, 2);
  r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-spot --periods 12,0,0,10 --delta 65");
  EXPECT_EQ(r.code, 2);
  r = stex("analyze '" + ex + "' -o '" + model + "' --method texton --delta 1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("does not apply to --method texton"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace stex
