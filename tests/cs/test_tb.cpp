// Tiling and blending (kinds "tb" and "cs-tb", Heitz & Neyret 2018, S4 §5.2): the device kernel against the
// C++ reference bit for bit (near the origin, far from it, another scale); tile, chunk and work-group
// invariance; cs-tb's congruent fetches reproduce an exactly periodic exemplar where stationary tb cannot;
// tb keeps a stationary exemplar's histogram (Gaussianisation + variance-preserving blend); the codec.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <map>
#include <vector>

#include "model/kinds.h"
#include "analysis/tb_model.h"
#include "core/error.h"
#include "runtime/context.h"
#include "runtime/tb.h"
#include "test_device.h"
#include "tests/cs/cs_synthetic.h"

namespace stex {
namespace {

using test::make_bricks;
using test::make_stationary;

Context& ctx() {
  static std::unique_ptr<Context> c = Context::create(stex::test::test_device_spec());
  return *c;
}

const Lattice k_t{17.4, 2.3, -3.1, 14.6};

RenderParams params(std::uint64_t seed, double scale = 1.0) {
  RenderParams rp;
  rp.seed = seed;
  rp.scale = scale;
  return rp;
}

std::vector<float> device_render(TbNoise& n, const RenderParams& rp, std::int64_t x, std::int64_t y, int w, int h) {
  std::vector<float> out(std::size_t(w) * h * n.channels());
  n.render(rp, x, y, w, h, out.data());
  return out;
}

const TbModel& cs_model() {
  static const TbModel m = [] {
    TbParams p;
    p.tile = 20.0;
    return tb_from_container(to_container(tb_from_exemplar(make_bricks(128, 120, k_t, 3, 0.15, 0.03, 3), p, &k_t)));
  }();
  return m;
}
const TbModel& st_model() {
  static const TbModel m = [] {
    TbParams p;
    p.tile = 20.0;
    return tb_from_container(to_container(tb_from_exemplar(make_stationary(128, 120, 3, 2, 5), p)));
  }();
  return m;
}

TEST(Tb, KernelEqualsReference) {
  for (const TbModel* m : {&cs_model(), &st_model()}) {
    TbNoise noise(ctx(), *m);
    for (double scale : {1.0, 0.43}) {
      const RenderParams rp = params(5, scale);
      EXPECT_EQ(device_render(noise, rp, -31, 12, 40, 24), TbReference(*m, rp).render(-31, 12, 40, 24)) << m->cs << " " << scale;
    }
    const std::int64_t far = 1000000000000LL;
    const std::vector<float> a = TbReference(*m, params(5)).render(-far, far, 24, 16);
    EXPECT_EQ(device_render(noise, params(5), -far, far, 24, 16), a);
    for (float v : a) ASSERT_TRUE(std::isfinite(v));
  }
}

// The pixel kernel's 32-bit residuals (stex_cs_canon_near) at their limits: a chunk 4096 pixels wide (the
// renderer's cap) and tile x scale = 4000 output pixels (periods x scale ~3500 for cs-tb), so residuals from
// the chunk's node reach ~2^29.6 fixed units; far from the origin too.
TEST(Tb, KernelEqualsReferenceAtTheResidualLimits) {
  for (const TbModel* m : {&cs_model(), &st_model()}) {
    TbNoise noise(ctx(), *m);
    const RenderParams rp = params(8, 200.0);
    for (std::int64_t x0 : {std::int64_t(-1234567), std::int64_t(777777777777LL)}) {
      const std::vector<float> a = TbReference(*m, rp).render(x0, -3, 4096, 2);
      EXPECT_EQ(device_render(noise, rp, x0, -3, 4096, 2), a) << m->cs << " " << x0;
    }
  }
}

// stex_cs_canon_near (the pixel kernels' 32-bit canonical base, tb's and cs-spot's) against stex_tb_canon and
// stex_cs_canon_fix (int64 floor division)
// on points exactly on lattice nodes and lines and one fixed unit off them, where the float estimate's floor is
// most often wrong: the exact -1/0/+1 correction must fix every case, and must be needed in some (otherwise
// this test would not exercise it). Lattices: the triangle grid of tile 4000 output pixels (the limit) and
// a skewed CS lattice of periods ~3000 pixels; residuals up to ~2^30 fixed units.
TEST(Tb, CanonNearEqualsTheExactFloor) {
  std::uint64_t state = 12345;
  auto next = [&] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return std::int64_t(state >> 33);
  };
  const double fs = 65536.0 * 200.0;
  const std::int64_t lat[2][4] = {
      {std::llround(20.0 * fs), 0, std::llround(10.0 * fs), std::llround(10.0 * std::sqrt(3.0) * fs)},
      {std::llround(k_t.t0x * fs), std::llround(k_t.t0y * fs), std::llround(k_t.t1x * fs), std::llround(k_t.t1y * fs)}};
  int corrected = 0, cases = 0;
  for (const auto& b : lat) {
    const std::int64_t det = b[0] * b[3] - b[1] * b[2];
    const double dd = double(det);
    const float i00 = float(double(b[3]) / dd), i01 = float(-double(b[2]) / dd);
    const float i10 = float(-double(b[1]) / dd), i11 = float(double(b[0]) / dd);
    for (int n = 0; n < 20000; ++n) {
      // A node (m, k) of the lattice, a point on a line through it, plus -1, 0 or +1 fixed unit.
      const std::int64_t m = next() % 3 - 1, k = next() % 3, t = next() % 65536;
      std::int64_t x = m * b[0] + k * b[2], y = m * b[1] + k * b[3];
      if (n % 3 == 1) { x += t * b[0] / 65536; y += t * b[1] / 65536; }
      if (n % 3 == 2) { x += t * b[2] / 65536; y += t * b[3] / 65536; }
      x += next() % 3 - 1;
      y += next() % 3 - 1;
      std::int64_t ek, el, erx, ery;
      stex_tb_canon(b[0], b[1], b[2], b[3], det, i00, i01, i10, i11, x, y, 0, 0, &ek, &el, &erx, &ery);
      stex_i32 dk, dl, rx, ry;
      stex_cs_canon_near(stex_i32(b[0]), stex_i32(b[1]), stex_i32(b[2]), stex_i32(b[3]), det, i00, i01, i10, i11,
                         stex_i32(x), stex_i32(y), &dk, &dl, &rx, &ry);
      ASSERT_EQ(std::int64_t(dk), ek) << x << " " << y;
      ASSERT_EQ(std::int64_t(dl), el) << x << " " << y;
      ASSERT_EQ(std::int64_t(rx), erx);
      ASSERT_EQ(std::int64_t(ry), ery);
      // cs.h's own exact step (cs-spot's reference) agrees too.
      std::int64_t fk = 0, fl = 0, frx = x, fry = y;
      stex_cs_canon_fix(b[0], b[1], b[2], b[3], det, &fk, &fl, &frx, &fry);
      ASSERT_EQ(fk, ek);
      ASSERT_EQ(fl, el);
      ASSERT_EQ(frx, erx);
      ASSERT_EQ(fry, ery);
      const float fa = float(x) * i00 + float(y) * i01, fb = float(x) * i10 + float(y) * i11;
      if (std::int64_t(std::floor(fa)) != ek || std::int64_t(std::floor(fb)) != el) ++corrected;
      ++cases;
    }
  }
  std::printf("canon_near: %d of %d cases needed the exact correction\n", corrected, cases);
  EXPECT_GT(corrected, 0);
}

// A 1-channel stationary model (the run kernel's vstore8 path) and a cs-tb model with integer periods (aligned
// at scale 1: the per-pixel kernel's one-texel path).
const TbModel& st1_model() {
  static const TbModel m = [] {
    TbParams p;
    p.tile = 20.0;
    return tb_from_container(to_container(tb_from_exemplar(make_stationary(128, 120, 1, 2, 6), p)));
  }();
  return m;
}
// 2- and 4-channel stationary models: the run kernel's interleaved vector stores for those channel counts.
const TbModel& st_channels_model(int channels) {
  static const TbModel m2 = [] {
    TbParams p;
    p.tile = 20.0;
    return tb_from_container(to_container(tb_from_exemplar(make_stationary(128, 120, 2, 2, 7), p)));
  }();
  static const TbModel m4 = [] {
    TbParams p;
    p.tile = 20.0;
    return tb_from_container(to_container(tb_from_exemplar(make_stationary(128, 120, 4, 2, 8), p)));
  }();
  return channels == 2 ? m2 : m4;
}
const Lattice k_ti{17.0, 2.0, -3.0, 15.0};
const TbModel& csi_model() {
  static const TbModel m = [] {
    TbParams p;
    p.tile = 20.0;
    return tb_from_container(to_container(tb_from_exemplar(make_bricks(128, 120, k_ti, 3, 0.15, 0.03, 3), p, &k_ti)));
  }();
  return m;
}
// Integer periods with 1, 2 or 4 channels (the run kernel's per-lane cyclic mean for each channel count),
// and (hist) with the CS histogram transfer (the run kernel's per-lane polyphase bins and T_b^-1 reads).
const TbModel& csi_channels_model(int channels, bool hist = false) {
  static std::map<std::pair<int, bool>, TbModel> models;
  auto it = models.find({channels, hist});
  if (it == models.end()) {
    TbParams p;
    p.tile = 20.0;
    if (hist) p.histogram = 2;
    it = models.emplace(std::make_pair(channels, hist),
                        tb_from_container(to_container(tb_from_exemplar(
                            make_bricks(128, 120, k_ti, channels, 0.15, 0.03, 3 + channels), p, &k_ti))))
             .first;
  }
  return it->second;
}

// At scale 1 every tb fetch (and every cs-tb fetch with integer periods) lands on a texel centre: the
// fetch's local coordinate t (stex_tb_local) is an integer, so the bilinear fractions are exactly 0, and the
// texel is the one of the vertex's texel offset (stex_tb_texel_base) for any chunk origin. Checked on every
// slot vertex of a 40 x 30 region near the origin and far from it; at scale 0.43 most fractions are not 0.
TEST(Tb, AlignedFetchesReadOneTexel) {
  for (const TbModel* m : {&st_model(), &csi_model(), &cs_model()}) {
    for (double scale : {1.0, 0.43}) {
      const TbSetup s = make_tb_setup(*m, params(5, scale));
      const stex_tb_params& p = s.params;
      EXPECT_EQ(s.aligned, scale == 1.0 && m != &cs_model());
      int fractional = 0, n = 0;
      for (std::int64_t y0 : {std::int64_t(-17), std::int64_t(300000000001LL)})
        for (int j = 0; j < 30; ++j)
          for (int i = 0; i < 40; ++i) {
            const std::int64_t px = y0 + 3 + i, py = y0 + j;
            std::int64_t node[4], res[4];
            tb_canonical(s, px, py, node, res);
            float w[3];
            const int up = stex_tb_triangle(p, stex_i32(res[0]), stex_i32(res[1]), &w[0], &w[1], &w[2]);
            const int ok[3] = {up, 1 - up, up}, ol[3] = {0, up, 1};
            for (int v = 0; v < 3; ++v) {
              stex_i32 cx, cy, dx, dy;
              stex_tb_vertex_centre(p, node[0] + ok[v], node[1] + ol[v], node[2], node[3], &cx, &cy);
              stex_tb_disp(p, stex_i32(res[0]), stex_i32(res[1]), ok[v], ol[v], &dx, &dy);
              const float tx = stex_tb_local(p, dx, cx), ty = stex_tb_local(p, dy, cy);
              ++n;
              if (tx != std::floor(tx) || ty != std::floor(ty)) {
                ++fractional;
                continue;
              }
              // The texel of the chunk whose first pixel is (px - 5, py - 2), at chunk pixel (5, 2).
              const stex_i32 base = stex_tb_texel_base(p, node[0] + ok[v], node[1] + ol[v], cx, cy, px - 5, py - 2);
              const std::int64_t ix = (cx >> 16) + std::int64_t(tx), iy = (cy >> 16) + std::int64_t(ty);
              ASSERT_EQ(std::int64_t(base) + 2 * m->width + 5, iy * m->width + ix);
              ASSERT_TRUE(ix >= 0 && ix <= m->width - 2 && iy >= 0 && iy <= m->height - 2);
            }
          }
      if (s.aligned)
        EXPECT_EQ(fractional, 0) << m->cs;
      else
        EXPECT_GT(fractional, n / 2) << m->cs << " " << scale;
    }
  }
}

// The run kernel (128 pixels a work-item in runs of 8 or 16 lanes: float8 or float16) and the per-pixel kernel
// give the reference's bits, for 1 to 4 channels, near and far from the origin, widths and origins not
// multiples of 8; the aligned per-pixel kernel too (tb and cs-tb with integer periods). With tiles of 20
// pixels a 16-pixel run meets up to 3 triangles (the kernel's 6-vertex path).
TEST(Tb, RunAndPixelKernelsEqualTheReference) {
  for (const TbModel* m : {&st1_model(), &st_channels_model(2), &st_model(), &st_channels_model(4), &csi_model(),
                           &csi_channels_model(1), &csi_channels_model(2), &csi_channels_model(4),
                           &csi_channels_model(3, true)}) {
    if (m == &csi_channels_model(3, true)) {
      ASSERT_GT(m->hist.q, 0);  // the CS transfer's tables are in use
    }
    TbNoise pix(ctx(), *m), run8(ctx(), *m), run16(ctx(), *m);
    pix.run_mode = 0;
    run8.run_mode = run16.run_mode = 1;
    run8.run_lanes = 8;
    run16.run_lanes = 16;
    for (std::int64_t x0 : {std::int64_t(-37), std::int64_t(5), std::int64_t(-777777777779LL)}) {
      const RenderParams rp = params(11);
      const std::vector<float> ref = TbReference(*m, rp).render(x0, 3 - x0 / 3, 61, 23);
      EXPECT_EQ(device_render(pix, rp, x0, 3 - x0 / 3, 61, 23), ref) << m->cs << " " << x0;
      EXPECT_EQ(pix.last_kernel, "tb");
      EXPECT_EQ(device_render(run8, rp, x0, 3 - x0 / 3, 61, 23), ref) << m->cs << " " << x0 << " 8 lanes";
      EXPECT_EQ(run8.last_kernel, "tb_run");
      EXPECT_EQ(device_render(run16, rp, x0, 3 - x0 / 3, 61, 23), ref) << m->cs << " " << x0 << " 16 lanes";
      EXPECT_EQ(run16.last_kernel, "tb_run16");
    }
  }
}

// The run kernel's general path (bilinear fetches gathered lane by lane: any scale, and cs-tb with sub-pixel
// periods at scale 1) gives the reference's bits too: tb and cs-tb (sub-pixel skewed periods, integer
// periods off scale 1, the CS histogram transfer), 1 to 4 channels, minified (0.43: a 8.6-pixel tile, so 16
// lanes fall back to 8), at 0.999 and magnified (1.7), near and far from the origin.
TEST(Tb, RunKernelWithBilinearFetchesEqualsTheReference) {
  struct Case {
    const TbModel* m;
    double scale;
  };
  const Case cases[] = {{&st1_model(), 0.999}, {&st_model(), 0.43},          {&st_channels_model(2), 1.7},
                        {&st_channels_model(4), 0.999}, {&cs_model(), 1.0},   {&cs_model(), 0.43},
                        {&csi_model(), 1.7},   {&csi_channels_model(2, true), 0.999}, {&csi_channels_model(1), 0.43}};
  for (const Case& k : cases) {
    const TbModel& m = *k.m;
    const RenderParams rp = params(13, k.scale);
    ASSERT_FALSE(make_tb_setup(m, rp).aligned);
    TbNoise run8(ctx(), m), run16(ctx(), m);
    run8.run_mode = run16.run_mode = 1;
    run8.run_lanes = 8;
    run16.run_lanes = 16;
    for (std::int64_t x0 : {std::int64_t(-29), std::int64_t(-555555555557LL)}) {
      const std::vector<float> ref = TbReference(m, rp).render(x0, 7 - x0 / 5, 59, 17);
      EXPECT_EQ(device_render(run8, rp, x0, 7 - x0 / 5, 59, 17), ref) << m.cs << " " << k.scale << " " << x0;
      EXPECT_EQ(run8.last_kernel, "tb_run");
      EXPECT_EQ(device_render(run16, rp, x0, 7 - x0 / 5, 59, 17), ref) << m.cs << " " << k.scale << " " << x0;
      EXPECT_EQ(run16.last_kernel, m.tile * k.scale >= 16.0 ? "tb_run16" : "tb_run");
    }
  }
}

// 16 lanes need a tile of >= 16 output pixels: on a 12-pixel tile the run kernel falls back to 8 lanes, with
// the reference's bits.
TEST(Tb, NarrowTilesFallBackToEightLanes) {
  TbParams p;
  p.tile = 12.0;
  const TbModel m = tb_from_exemplar(make_stationary(64, 60, 1, 2, 5), p);
  TbNoise run(ctx(), m);
  run.run_mode = 1;
  run.run_lanes = 16;
  const RenderParams rp = params(2);
  EXPECT_EQ(device_render(run, rp, -13, 8, 45, 9), TbReference(m, rp).render(-13, 8, 45, 9));
  EXPECT_EQ(run.last_kernel, "tb_run");
}

TEST(Tb, TilesChunksAndWorkGroupsGiveTheSameBits) {
  const TbModel& m = cs_model();
  TbNoise whole(ctx(), m);
  const int w = 50, h = 38, ch = m.channels;
  const std::vector<float> ref = device_render(whole, params(3), 7, -40, w, h);
  TbNoise tiled(ctx(), m);
  tiled.local_size = {8, 2};
  tiled.max_chunk_pixels = 101;
  std::vector<float> assembled(ref.size());
  for (int ty = 0; ty < h; ty += 16)
    for (int tx = 0; tx < w; tx += 20) {
      const int tw = std::min(20, w - tx), th = std::min(16, h - ty);
      const std::vector<float> tile = device_render(tiled, params(3), 7 + tx, -40 + ty, tw, th);
      for (int j = 0; j < th; ++j)
        std::copy(tile.begin() + std::ptrdiff_t(j) * tw * ch, tile.begin() + std::ptrdiff_t(j + 1) * tw * ch,
                  assembled.begin() + (std::ptrdiff_t(ty + j) * w + tx) * ch);
    }
  EXPECT_EQ(assembled, ref);
  EXPECT_NE(device_render(whole, params(4), 7, -40, w, h), ref);
}

// The same for the run kernel: tiles whose origins and widths are not multiples of its runs, small chunks and
// another work-group size, against the per-pixel kernel's whole render; 8 and 16 lanes.
TEST(Tb, RunKernelTilesGiveTheSameBits) {
  for (int lanes : {8, 16})
  for (const TbModel* m : {&st1_model(), &st_channels_model(2), &st_model(), &st_channels_model(4), &csi_model(),
                           &csi_channels_model(1), &csi_channels_model(2, true)}) {
    TbNoise whole(ctx(), *m);
    whole.run_mode = 0;
    const int w = 67, h = 21, ch = m->channels;
    const std::vector<float> ref = device_render(whole, params(3), -9, 40, w, h);
    TbNoise tiled(ctx(), *m);
    tiled.run_mode = 1;
    tiled.run_lanes = lanes;
    tiled.local_size = {2, 3};
    tiled.max_chunk_pixels = 50;
    std::vector<float> assembled(ref.size());
    for (int ty = 0; ty < h; ty += 10)
      for (int tx = 0; tx < w; tx += 13) {
        const int tw = std::min(13, w - tx), th = std::min(10, h - ty);
        const std::vector<float> tile = device_render(tiled, params(3), -9 + tx, 40 + ty, tw, th);
        ASSERT_EQ(tiled.last_kernel, lanes == 16 ? "tb_run16" : "tb_run");
        for (int j = 0; j < th; ++j)
          std::copy(tile.begin() + std::ptrdiff_t(j) * tw * ch, tile.begin() + std::ptrdiff_t(j + 1) * tw * ch,
                    assembled.begin() + (std::ptrdiff_t(ty + j) * w + tx) * ch);
      }
    EXPECT_EQ(assembled, ref) << ch;
  }
}

// An exactly periodic exemplar (no per-cell colour, no noise; smooth mortar of width 3 px): every cs-tb fetch
// is congruent to its pixel, so the render is the pattern itself up to interpolation (bilinear reads of
// pixels at sub-pixel offsets: h^2 |f''| / 8 <= 0.011 per axis, amplified by at most sqrt(3) by the blend's
// normalisation: about 0.04 at worst), while stationary tb's fetches are not congruent and break the pattern.
TEST(Tb, CsFetchesAreCongruent) {
  TbParams p;
  p.tile = 20.0;
  const Image ex = make_bricks(128, 120, k_t, 1, 0.0, 0.0, 1, 3.0);
  const Image truth = make_bricks(400, 300, k_t, 1, 0.0, 0.0, 1, 3.0);
  const TbModel cs = tb_from_exemplar(ex, p, &k_t), st = tb_from_exemplar(ex, p);
  const std::vector<float> a = TbReference(cs, params(9)).render(300, 200, 64, 64);
  const std::vector<float> b = TbReference(st, params(9)).render(300, 200, 64, 64);
  double worst_cs = 0.0, mean_cs = 0.0, mean_st = 0.0;
  for (int j = 0; j < 64; ++j)
    for (int i = 0; i < 64; ++i) {
      const double t = truth.at(300 + i, 200 + j, 0);
      worst_cs = std::max(worst_cs, std::fabs(a[std::size_t(j) * 64 + i] - t));
      mean_cs += std::fabs(a[std::size_t(j) * 64 + i] - t);
      mean_st += std::fabs(b[std::size_t(j) * 64 + i] - t);
    }
  mean_cs /= 4096.0;
  mean_st /= 4096.0;
  std::printf("periodic exemplar: cs-tb max error %.4f, mean %.4f; tb mean %.4f\n", worst_cs, mean_cs, mean_st);
  EXPECT_LT(worst_cs, 0.05);
  EXPECT_GT(mean_st, 10.0 * mean_cs);
}

// tb keeps the histogram of a stationary exemplar: Kolmogorov-Smirnov distance per channel between a 192^2
// render and the exemplar. The render's pixels are correlated over about a tile (L = 20 px), so its effective
// sample size is about (192 / 20)^2 ~ 90 tiles x 3 fetches; KS's 99.9 % quantile 1.95 / sqrt(n_eff) gives
// ~0.12. Measured values are printed.
TEST(Tb, StationaryHistogramIsKept) {
  const TbModel& m = st_model();
  const Image ex = make_stationary(128, 120, 3, 2, 5);
  const int w = 192, ch = 3;
  const std::vector<float> r = TbReference(m, params(2)).render(1000, 1000, w, w);
  for (int c = 0; c < ch; ++c) {
    std::vector<float> a, b;
    for (std::size_t i = 0; i < r.size() / ch; ++i) a.push_back(r[i * ch + c]);
    for (std::size_t i = 0; i < ex.pixels.size() / ch; ++i) b.push_back(ex.pixels[i * ch + c]);
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    double ks = 0.0;
    std::size_t ia = 0, ib = 0;
    while (ia < a.size() && ib < b.size()) {
      if (a[ia] <= b[ib]) ++ia; else ++ib;
      ks = std::max(ks, std::fabs(double(ia) / a.size() - double(ib) / b.size()));
    }
    std::printf("channel %d: KS %.4f\n", c, ks);
    EXPECT_LT(ks, 0.12);
  }
}

TEST(Tb, CodecAndRegistry) {
  for (const TbModel* m : {&cs_model(), &st_model()}) {
    const ModelContainer c = to_container(*m);
    EXPECT_EQ(c.kind, m->cs ? "cs-tb" : "tb");
    const std::vector<std::uint8_t> bytes = encode_container(c);
    const TbModel back = tb_from_container(decode_container(bytes.data(), bytes.size()));
    EXPECT_EQ(back.gauss, m->gauss);
    EXPECT_EQ(back.lut, m->lut);
    EXPECT_EQ(back.mean, m->mean);
    const std::unique_ptr<NoiseRenderer> r = make_noise_renderer(ctx(), c);
    EXPECT_EQ(r->kind(), c.kind);
    std::vector<float> out(16 * 8 * 3);
    r->render(params(1), 0, 0, 16, 8, out.data());
    EXPECT_EQ(out, TbReference(*m, params(1)).render(0, 0, 16, 8));
    ModelContainer b = c;
    b.payload.pop_back();
    EXPECT_THROW(tb_from_container(b), Error);
    b = c;
    b.metadata["tile"] = 1000.0;
    EXPECT_THROW(tb_from_container(b), Error);
  }
}

}  // namespace
}  // namespace stex
