// Cyclostationary spot noise (kind "cs-spot", S4 §5.1): the device kernel against the C++ reference bit for
// bit (sub-pixel skewed periods, colour, far from the origin, scale); tile, chunk and work-group invariance,
// with chunk origins far from the origin; the fast path's 32-bit canonical step against the exact floor; the
// canonical and the general base computing the same noise (and the general path's kernel at a huge scale);
// the Gaussian weight table; the cyclic mean of renders against M and the covariance against Appendix A; the
// codec and the registry; `stex analyze --method cs-spot` (--periods, --estimate-periods, --json) and
// `stex render` (single image and tiles) end to end, with bad input.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

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
using test::make_bricks;

Context& ctx() {
  static std::unique_ptr<Context> c = Context::create(stex::test::test_device_spec());
  return *c;
}

const Lattice k_skew{13.71, -5.23, 6.14, 15.92};

CsSpotModel colour_model() {
  static const CsSpotModel m = [] {
    const Image ex = make_bricks(72, 64, k_skew, 3, 0.15, 0.03, 21);
    return cs_spot_from_container(to_container(cs_spot_from_exemplar(ex, k_skew)));
  }();
  return m;
}

RenderParams params(std::uint64_t seed, double scale = 1.0) {
  RenderParams rp;
  rp.seed = seed;
  rp.scale = scale;
  return rp;
}

std::vector<float> device_render(CsSpotNoise& n, const RenderParams& rp, std::int64_t x, std::int64_t y, int w, int h) {
  std::vector<float> out(std::size_t(w) * h * n.channels());
  n.render(rp, x, y, w, h, out.data());
  return out;
}

TEST(CsSpot, GaussianTableHasUnitVarianceAndZeroMean) {
  const std::vector<float> t = cs_gaussian_table();
  ASSERT_EQ(t.size(), std::size_t(STEX_CS_GAUSS_SEGMENTS + 1));
  // Exact moments of the lookup over all 2^24 inputs that matter (segment x 2^14 positions), in double.
  double m1 = 0.0, m2 = 0.0, m4 = 0.0;
  for (std::uint32_t seg = 0; seg < STEX_CS_GAUSS_SEGMENTS; ++seg)
    for (std::uint32_t f = 0; f < 16384; f += 1) {
      const double w = stex_cs_gauss(t.data(), (seg << 22) | (f << 8));
      m1 += w;
      m2 += w * w;
      m4 += w * w * w * w;
    }
  const double n = double(STEX_CS_GAUSS_SEGMENTS) * 16384.0;
  EXPECT_NEAR(m1 / n, 0.0, 1e-7);
  EXPECT_NEAR(m2 / n, 1.0, 1e-6);
  EXPECT_NEAR(m4 / n, 3.0, 0.03);  // Gaussian kurtosis, tails beyond 3.5 sigma cut
}

TEST(CsSpot, KernelEqualsReference) {
  const CsSpotModel m = colour_model();
  CsSpotNoise noise(ctx(), m);
  for (double scale : {1.0, 0.37, 2.5}) {
    const RenderParams rp = params(7, scale);
    const CsSpotReference ref(m, rp);
    EXPECT_EQ(device_render(noise, rp, -17, 9, 40, 24), ref.render(-17, 9, 40, 24)) << "scale " << scale;
  }
  // Far from the origin: same bits, finite values, and not a copy of the origin's.
  const std::int64_t far = 1000000000000LL;
  const RenderParams rp = params(7);
  const CsSpotReference ref(m, rp);
  const std::vector<float> a = ref.render(far, -far, 24, 16);
  EXPECT_EQ(device_render(noise, rp, far, -far, 24, 16), a);
  for (float v : a) ASSERT_TRUE(std::isfinite(v));
  EXPECT_NE(a, ref.render(0, 0, 24, 16));
}

TEST(CsSpot, TilesChunksAndWorkGroupsGiveTheSameBits) {
  const CsSpotModel m = colour_model();
  const RenderParams rp = params(3);
  CsSpotNoise whole(ctx(), m);
  const int w = 50, h = 38;
  const std::vector<float> ref = device_render(whole, rp, -25, 40, w, h);
  CsSpotNoise tiled(ctx(), m);
  tiled.local_size = {8, 2};
  tiled.max_chunk_pixels = 97;
  std::vector<float> assembled(ref.size());
  const int ch = m.channels;
  for (int ty = 0; ty < h; ty += 16)
    for (int tx = 0; tx < w; tx += 20) {
      const int tw = std::min(20, w - tx), th = std::min(16, h - ty);
      const std::vector<float> tile = device_render(tiled, rp, -25 + tx, 40 + ty, tw, th);
      for (int j = 0; j < th; ++j)
        std::copy(tile.begin() + std::ptrdiff_t(j) * tw * ch, tile.begin() + std::ptrdiff_t(j + 1) * tw * ch,
                  assembled.begin() + (std::ptrdiff_t(ty + j) * w + tx) * ch);
    }
  EXPECT_EQ(assembled, ref);
  // Determinism across renderers and runs; another seed is another texture.
  CsSpotNoise again(ctx(), m);
  EXPECT_EQ(device_render(again, rp, -25, 40, w, h), ref);
  EXPECT_NE(device_render(again, params(4), -25, 40, w, h), ref);
}

// stex_cs_canon_near (the kernels' 32-bit canonical step, shared with tiling and blending) is checked against
// both exact floors (stex_cs_canon_fix and stex_tb_canon) by Tb.CanonNearEqualsTheExactFloor (test_tb.cpp).

// The fast path's chunks start from their first pixel's canonical node: chunk origins far from the origin
// (10^12, both signs, and just below 2^46 pixels, the bit tables' limit), non-integer residual steps (scale
// 0.37), one channel and colour, rows cut into chunks of 37 pixels (not whole rows) and work-groups of 8 x 2
// give the bits of one launch and of the reference.
TEST(CsSpot, FarChunkOriginsGiveTheSameBits) {
  const CsSpotModel colour = colour_model();
  const CsSpotModel grey = cs_spot_from_exemplar(make_bricks(64, 56, k_skew, 1, 0.15, 0.03, 5), k_skew);
  const std::int64_t far = 1000000000000LL, edge = (std::int64_t(1) << 45) - 100;
  struct Case {
    const CsSpotModel* m;
    std::int64_t x, y;
    double scale;
  };
  const Case cases[] = {{&colour, far, -far, 1.0}, {&colour, -far - 13, far + 7, 0.37}, {&grey, far, far, 1.0},
                        {&grey, -edge, edge, 2.5}};
  for (const Case& c : cases) {
    const RenderParams rp = params(11, c.scale);
    ASSERT_EQ(CsSpotReference(*c.m, rp).setup().params.canon, 1);
    CsSpotNoise whole(ctx(), *c.m);
    const int w = 41, h = 9;
    const std::vector<float> ref = CsSpotReference(*c.m, rp).render(c.x, c.y, w, h);
    EXPECT_EQ(device_render(whole, rp, c.x, c.y, w, h), ref) << c.x << " " << c.y << " scale " << c.scale;
    CsSpotNoise chunked(ctx(), *c.m);
    chunked.max_chunk_pixels = 37;
    chunked.local_size = {8, 2};
    EXPECT_EQ(device_render(chunked, rp, c.x, c.y, w, h), ref) << c.x << " " << c.y << " scale " << c.scale;
    for (float v : ref) ASSERT_TRUE(std::isfinite(v));
  }
}

// The canonical base (params.canon, the fast path's) and the general per-point base (canon 0, used above 4096
// output pixels per period) compute the same noise: the spot sums visit the same nodes with the same exact
// displacements (identical bits), and the mean M differs only where the general base is a neighbour of the
// canonical one (its phase then differs by a whole period: the periodic grid gives M up to the rounding of the
// grid coordinate u n0, a few ulps of n0 <= 64, i.e. < 1e-5 times the step of M between grid values, <= 1).
// Far from the origin too. A huge scale selects the general path, whose kernel
// equals the reference.
TEST(CsSpot, CanonicalAndGeneralBasesComputeTheSameNoise) {
  const CsSpotModel m = colour_model();
  for (std::int64_t x0 : {std::int64_t(-30), std::int64_t(1000000000000LL)}) {
    const CsSpotReference ref(m, params(5));
    const CsSpotSetup& s = ref.setup();
    ASSERT_EQ(s.params.canon, 1);
    stex_cs_params general = s.params;
    general.canon = 0;
    double worst = 0.0;
    int differ = 0;
    const int w = 48, h = 40;
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i) {
        float a[4], b[4];
        const std::int64_t x = stex_cs_pixel_fix(x0 + i), y = stex_cs_pixel_fix(-x0 + j);
        stex_cs_spot_eval(s.params, m.spot.data(), m.mean.data(), s.gauss.data(), s.reduce.data(), s.hist_params,
                          s.hist.data(), x, y, a);
        stex_cs_spot_eval(general, m.spot.data(), m.mean.data(), s.gauss.data(), s.reduce.data(), s.hist_params,
                          s.hist.data(), x, y, b);
        for (int c = 0; c < m.channels; ++c) {
          worst = std::max(worst, double(std::fabs(a[c] - b[c])));
          differ += a[c] != b[c];
        }
      }
    EXPECT_LT(worst, 1e-5) << x0;
    EXPECT_LT(differ, w * h * m.channels / 10) << x0;
  }
  const RenderParams huge = params(5, 400.0);  // periods ~6000 output pixels
  const CsSpotReference ref(m, huge);
  ASSERT_EQ(ref.setup().params.canon, 0);
  CsSpotNoise noise(ctx(), m);
  EXPECT_EQ(device_render(noise, huge, 123456, -654321, 12, 6), ref.render(123456, -654321, 12, 6));
  // The fast path's row ranges lie in the reference's window and leave out nodes of the skewed lattice.
  const CsSpotReference fast(m, params(5));
  const CsSpotSetup& s = fast.setup();
  const stex_cs_params& p = s.params;
  ASSERT_EQ(s.rows.size(), std::size_t(2 * (p.dl1 - p.dl0 + 1)));
  long visited = 0;
  for (std::size_t r = 0; r < s.rows.size(); r += 2) {
    if (s.rows[r] > s.rows[r + 1]) continue;
    EXPECT_GE(s.rows[r], p.dk0);
    EXPECT_LE(s.rows[r + 1], p.dk1);
    visited += s.rows[r + 1] - s.rows[r] + 1;
  }
  EXPECT_LT(visited, long(p.dk1 - p.dk0 + 1) * long(p.dl1 - p.dl0 + 1));
}

// The render's mean at each pixel is M (eq. 9 adds M to a centred process): over N seeds the pixel mean is
// within 5 standard errors sqrt(R(x, 0) / N) of M, R from Appendix A (the weights are exactly centred with
// unit variance, so this is the estimator's own spread; 5 sigma over 3 x 256 pixels fails by chance with
// probability ~4e-4).
TEST(CsSpot, MeanOfRendersIsTheCyclicMean) {
  const CsSpotModel m = colour_model();
  const int w = 16, h = 16, n = 48, ch = m.channels;
  std::vector<double> acc(std::size_t(w) * h * ch, 0.0);
  for (int s = 0; s < n; ++s) {
    const std::vector<float> r = CsSpotReference(m, params(1000 + s)).render(5, -3, w, h);
    for (std::size_t i = 0; i < r.size(); ++i) acc[i] += r[i];
  }
  double worst = 0.0;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
      for (int c = 0; c < ch; ++c) {
        const double mean = acc[(std::size_t(j) * w + i) * ch + c] / n;
        const double var = cs_spot_covariance(m, 5 + i, -3 + j, 0, 0, c, c);
        ASSERT_GT(var, 0.0);
        worst = std::max(worst, std::fabs(mean - cs_spot_mean(m, 5 + i, -3 + j, c)) / std::sqrt(var / n));
      }
  EXPECT_LT(worst, 5.0);
}

// Appendix A: the covariance of the render between pixels p and p + t (same and cross channels) equals
// amplitude^2 sum_u S(p - u) S(p + t - u). Estimated over N seeds; the estimator's standard error is
// sqrt((R(p,0) R(p+t,0) + R(p,t)^2) / N) (Gaussian fourth moments), and each check allows 4.5 of them.
TEST(CsSpot, CovarianceIsTheSpotsAppendixA) {
  const CsSpotModel m = colour_model();
  const int n = 600;
  struct Pair {
    int px, py, tx, ty, c1, c2;
  };
  const Pair pairs[] = {{3, 4, 0, 0, 0, 0}, {3, 4, 1, 0, 0, 0}, {3, 4, 2, 3, 1, 1}, {8, 3, 5, -2, 2, 2},
                        {3, 4, 0, 0, 0, 2}, {8, 3, 1, 1, 1, 0}, {6, 7, -4, 1, 2, 2}};
  std::vector<std::vector<float>> renders;
  for (int s = 0; s < n; ++s) renders.push_back(CsSpotReference(m, params(500 + s)).render(0, 0, 16, 12));
  const int ch = m.channels;
  for (const Pair& q : pairs) {
    const double mu1 = cs_spot_mean(m, q.px, q.py, q.c1), mu2 = cs_spot_mean(m, q.px + q.tx, q.py + q.ty, q.c2);
    double acc = 0.0;
    for (const auto& r : renders)
      acc += (r[(std::size_t(q.py) * 16 + q.px) * ch + q.c1] - mu1) *
             (r[(std::size_t(q.py + q.ty) * 16 + q.px + q.tx) * ch + q.c2] - mu2);
    const double emp = acc / n;
    const double theory = cs_spot_covariance(m, q.px, q.py, q.tx, q.ty, q.c1, q.c2);
    const double v1 = cs_spot_covariance(m, q.px, q.py, 0, 0, q.c1, q.c1);
    const double v2 = cs_spot_covariance(m, q.px + q.tx, q.py + q.ty, 0, 0, q.c2, q.c2);
    const double se = std::sqrt((v1 * v2 + theory * theory) / n);
    EXPECT_LT(std::fabs(emp - theory), 4.5 * se)
        << "p (" << q.px << ", " << q.py << ") t (" << q.tx << ", " << q.ty << ") c " << q.c1 << q.c2 << ": empirical "
        << emp << " theory " << theory;
  }
}

// The spot noise reproduces the exemplar's polyphase statistics: M is the exemplar's cyclic mean, and the
// variance over a period of the render is the windowed variance of the exemplar around M.
TEST(CsSpot, ModelVarianceMatchesTheExemplarsAroundM) {
  const Image ex = make_bricks(96, 96, k_skew, 1, 0.15, 0.03, 4);
  const CsSpotModel m = cs_spot_from_exemplar(ex, k_skew);
  const CyclicMean cm = cyclic_mean(ex, k_skew);
  // Mean over a block of pixels of R(x, 0) vs the exemplar's variance around M (same block of phases).
  double model = 0.0, exemplar = 0.0;
  int cnt = 0;
  for (int j = 30; j < 60; ++j)
    for (int i = 30; i < 60; ++i) {
      model += cs_spot_covariance(m, i, j, 0, 0, 0, 0);
      const double d = ex.at(i, j, 0) - cm.at_point(i + 0.5, j + 0.5, 0);
      exemplar += d * d;
      ++cnt;
    }
  // Both estimate the same per-phase variances; the window and the finite exemplar make them differ by a
  // few per cent, not more (measured: see docs/cyclostationary.md).
  EXPECT_NEAR(model / cnt, exemplar / cnt, 0.15 * exemplar / cnt);
}

TEST(CsSpot, CodecRoundTripAndValidation) {
  const CsSpotModel m = colour_model();
  CsModelInfo info;
  info.d = 0.1;
  info.confidence = 0.9;
  const ModelContainer c = to_container(m, info);
  const std::vector<std::uint8_t> bytes = encode_container(c);
  const CsSpotModel back = cs_spot_from_container(decode_container(bytes.data(), bytes.size()));
  EXPECT_EQ(back.spot, m.spot);
  EXPECT_EQ(back.mean, m.mean);
  EXPECT_EQ(back.t0x, m.t0x);
  EXPECT_EQ(back.t1y, m.t1y);
  EXPECT_EQ(back.amplitude, m.amplitude);
  auto input_error = [](const ModelContainer& bad) {
    try {
      cs_spot_from_container(bad, "bad.stex");
    } catch (const Error& e) {
      return e.kind() == ErrorKind::Input && std::string(e.what()).find("bad.stex") != std::string::npos;
    }
    return false;
  };
  ModelContainer b = c;
  b.metadata["periods"] = nlohmann::json::array({1, 2, 3, 4});
  EXPECT_TRUE(input_error(b));
  b = c;
  b.metadata["periods"] = {{10.0, 0.0}, {20.0, 0.1}};  // parallel
  EXPECT_TRUE(input_error(b));
  b = c;
  b.payload.pop_back();
  EXPECT_TRUE(input_error(b));
  b = c;
  b.metadata["mean_grid"]["n0"] = 0;
  EXPECT_TRUE(input_error(b));
  b = c;
  b.kind = "gabor";
  EXPECT_TRUE(input_error(b));
  b = c;
  b.metadata["channels"] = 5;
  EXPECT_TRUE(input_error(b));
}

TEST(CsSpot, RegistryRendersTheKind) {
  const CsSpotModel m = colour_model();
  const std::unique_ptr<NoiseRenderer> r = make_noise_renderer(ctx(), to_container(m));
  EXPECT_EQ(r->kind(), "cs-spot");
  EXPECT_EQ(r->channels(), 3);
  std::vector<float> out(20 * 10 * 3);
  r->render(params(2), 4, 4, 20, 10, out.data());
  EXPECT_EQ(out, CsSpotReference(m, params(2)).render(4, 4, 20, 10));
  EXPECT_THROW(make_noise_renderer(ctx(), to_container(m), NoiseRendererOptions{"splat"}), Error);
}

// ---- CLI end to end ----
using stex::test::CliRun;
CliRun stex(const std::string& args) { return stex::test::run_stex_cli(args, "cs_cli"); }

TEST(CsSpotCli, AnalyzeWithPeriodsAndEstimateThenRender) {
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / "cs_cli_render";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const Lattice t{21.37, 3.62, -4.81, 17.26};
  // A float exemplar (EXR): the periods in the file are the generator's exactly.
  const std::string ex = (dir / "bricks.exr").string(), model = (dir / "m.stex").string();
  write_image_atomic(ex, make_bricks(192, 176, t, 3, 0.15, 0.03, 11));
  CliRun r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-spot --estimate-periods --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const Lattice got{j["periods"][0][0], j["periods"][0][1], j["periods"][1][0], j["periods"][1][1]};
  const Lattice a = reduce_lattice(got), b = reduce_lattice(t);
  EXPECT_LT(std::max({std::fabs(a.t0x - b.t0x), std::fabs(a.t0y - b.t0y), std::fabs(a.t1x - b.t1x), std::fabs(a.t1y - b.t1y)}), 0.1)
      << r.out;
  // 0.4 when k_separation was 0.4; at 0.5 the separation term, here below its cap, is 0.8 of what it was.
  EXPECT_GT(j["confidence"].get<double>(), 0.32);
  EXPECT_TRUE(j.contains("d"));
  // The model renders through `stex render`, single image and tiles, with the same bits as the reference.
  const CsSpotModel m = cs_spot_from_container(load_container(model));
  const std::vector<float> ref = CsSpotReference(m, params(9)).render(100, -5, 48, 32);
  ASSERT_EQ(stex("render '" + model + "' -o '" + (dir / "r.exr").string() + "' --size 48x32 --origin 100,-5 --seed 9").code, 0);
  EXPECT_EQ(load_exemplar((dir / "r.exr").string()).pixels, ref);
  r = stex("render '" + model + "' -o '" + (dir / "t_{tx}_{ty}.exr").string() + "' --size 48x32 --origin 100,-5 --seed 9 --tile-size 32");
  ASSERT_EQ(r.code, 0) << r.err;
  const Image t00 = load_exemplar((dir / "t_0_0.exr").string()), t10 = load_exemplar((dir / "t_1_0.exr").string());
  ASSERT_EQ(t00.width, 32);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 48; ++x)
      for (int c = 0; c < 3; ++c) {
        const float v = x < 32 ? t00.at(x, y, c) : t10.at(x - 32, y, c);
        ASSERT_EQ(v, ref[(std::size_t(y) * 48 + x) * 3 + c]) << x << "," << y;
      }
  // Given periods are used as given and reported.
  r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-spot --periods 21.37,3.62,-4.81,17.26 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json g = nlohmann::json::parse(r.out);
  EXPECT_EQ(g["periods"][0][0].get<double>(), 21.37);
  EXPECT_EQ(g["periods"][1][1].get<double>(), 17.26);
  EXPECT_FALSE(g["estimated"].get<bool>());
  // Bad input: exit 2 with the problem named.
  r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-spot --periods 10,0,20,0.1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("parallel"), std::string::npos) << r.err;
  r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-spot --periods 1,2,3");
  EXPECT_EQ(r.code, 2);
  r = stex("analyze '" + ex + "' -o '" + model + "' --method texton --periods 21,3,-4,17");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--method cs-spot"), std::string::npos) << r.err;
  // Both: the rough periods given are refined (S4 §6) to the exemplar's, 21.37,3.62,-4.81,17.26.
  r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-spot --periods 21,3,-4,17 --estimate-periods --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json rj = nlohmann::json::parse(r.out);
  EXPECT_TRUE(rj["estimated"].get<bool>());
  EXPECT_TRUE(lattices_match(Lattice{21.37, 3.62, -4.81, 17.26},
                             Lattice{rj["periods"][0][0], rj["periods"][0][1], rj["periods"][1][0], rj["periods"][1][1]}, 0.1))
      << r.out;
}

// `stex analyze --method cs-tb|tb` then `stex render` (tiles): the JSON reports the periods; renders equal
// the reference; tb refuses periods.
TEST(CsSpotCli, TilingAndBlendingAnalyzeAndRender) {
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / "cs_cli_tb";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const Lattice t{21.37, 3.62, -4.81, 17.26};
  const std::string ex = (dir / "bricks.exr").string(), model = (dir / "m.stex").string();
  write_image_atomic(ex, make_bricks(192, 176, t, 3, 0.15, 0.03, 11));
  CliRun r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-tb --periods 21.37,3.62,-4.81,17.26 --tile 24 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["periods"][0][0].get<double>(), 21.37);
  EXPECT_EQ(j["tile"].get<double>(), 24.0);
  const TbModel m = tb_from_container(load_container(model));
  EXPECT_TRUE(m.cs);
  const std::vector<float> ref = TbReference(m, params(4)).render(-7, 3, 40, 20);
  r = stex("render '" + model + "' -o '" + (dir / "t_{tx}_{ty}.exr").string() + "' --size 40x20 --origin -7,3 --seed 4 --tile-size 20");
  ASSERT_EQ(r.code, 0) << r.err;
  const Image t00 = load_exemplar((dir / "t_0_0.exr").string()), t10 = load_exemplar((dir / "t_1_0.exr").string());
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 40; ++x)
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(x < 20 ? t00.at(x, y, c) : t10.at(x - 20, y, c), ref[(std::size_t(y) * 40 + x) * 3 + c]) << x << "," << y;
  r = stex("analyze '" + ex + "' -o '" + model + "' --method tb --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(tb_from_container(load_container(model)).cs);
  r = stex("analyze '" + ex + "' -o '" + model + "' --method tb --periods 21,3,-4,17");
  EXPECT_EQ(r.code, 2);
  r = stex("analyze '" + ex + "' -o '" + model + "' --method cs-tb --tile 500");
  EXPECT_EQ(r.code, 2);
  r = stex("analyze '" + ex + "' -o '" + model + "' --method tb --border 4");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--border does not apply to --method tb (it is an option of --method cs-spot)"), std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace stex
