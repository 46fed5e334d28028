// Texton noise evaluation on the device against the C++ reference (S1 eq. 1-3, §8): the strip-splat, gather
// and local-memory gather kernels (kernels/texton_*.cl through runtime/texton_renderer) must equal
// runtime/reference's
// stex_texton_eval bit for bit - the design adds the same float terms in the same global order with the
// same expressions (kernels/shared/texton.h), so no tolerance is needed and none is used. Covered: order 0
// and 1, 1 and 3 channels, scale 1 (the splat's exact unit-scale span), 0.5, 2.37, origins 0, negative and
// +-10^12; invariance under tiling (regular and ragged), chunking, work-group size, strip width and
// repetition; a different seed changes the output.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "core/error.h"
#include "kernels/test_texton_common.h"
#include "runtime/program.h"
#include "runtime/reference.h"
#include "runtime/texton_params.h"
#include "runtime/texton_renderer.h"

namespace stex {
namespace {

using test::count_bit_differences;
using test::synthetic_model;
using test::texton_context;

struct Case {
  int channels, support, order;
  double scale;
  std::int64_t x, y;
  int width, height;
};

std::string describe(const Case& c) {
  return std::to_string(c.channels) + "ch s" + std::to_string(c.support) + " order " + std::to_string(c.order) +
         " scale " + std::to_string(c.scale) + " origin (" + std::to_string(c.x) + ", " + std::to_string(c.y) + ") " +
         std::to_string(c.width) + "x" + std::to_string(c.height);
}

void PrintTo(const Case& c, std::ostream* os) { *os << describe(c); }

class TextonVsReference : public ::testing::TestWithParam<Case> {};

TEST_P(TextonVsReference, SplatAndGatherEqualReferenceBitForBit) {
  const Case& c = GetParam();
  const TextonModel model = synthetic_model(c.channels, c.support, c.order, 11);
  RenderParams params;
  params.seed = 0x5eed0001;
  params.scale = c.scale;
  const TextonReference reference(model, params);
  const std::vector<float> expected = reference.render(c.x, c.y, c.width, c.height);

  TextonRenderer renderer(texton_context(), model);
  TextonRenderOptions splat;
  splat.strategy = TextonStrategy::Splat;
  TextonRenderOptions gather;
  gather.strategy = TextonStrategy::Gather;
  TextonRenderOptions local;
  local.strategy = TextonStrategy::GatherLocal;
  const std::vector<float> s = renderer.render(params, c.x, c.y, c.width, c.height, splat);
  const std::vector<float> g = renderer.render(params, c.x, c.y, c.width, c.height, gather);
  TextonRenderStats stats;
  const std::vector<float> l = renderer.render(params, c.x, c.y, c.width, c.height, local, &stats);
  EXPECT_EQ(stats.strategy, TextonStrategy::GatherLocal) << describe(c);
  EXPECT_EQ(count_bit_differences(s, expected), 0u) << "splat vs reference, " << describe(c);
  EXPECT_EQ(count_bit_differences(g, expected), 0u) << "gather vs reference, " << describe(c);
  EXPECT_EQ(count_bit_differences(l, expected), 0u) << "gather-local vs reference, " << describe(c);
  EXPECT_EQ(count_bit_differences(s, g), 0u) << "splat vs gather, " << describe(c);
  EXPECT_EQ(count_bit_differences(s, l), 0u) << "splat vs gather-local, " << describe(c);

  // The image is not degenerate: values vary and stay finite.
  double lo = 1e30, hi = -1e30;
  for (float v : expected) {
    ASSERT_TRUE(std::isfinite(v));
    lo = std::min(lo, double(v));
    hi = std::max(hi, double(v));
  }
  EXPECT_GT(hi - lo, 1e-3) << describe(c);
}

constexpr std::int64_t k_tera = 1000000000000ll;

INSTANTIATE_TEST_SUITE_P(
    Cases, TextonVsReference,
    ::testing::Values(Case{1, 64, 1, 1.0, 0, 0, 97, 83},            // default support, unit scale
                      Case{3, 16, 1, 1.0, -517, -33, 130, 41},      // colour, negative origin
                      Case{1, 16, 0, 1.0, 5, -7, 131, 40},          // order 0 (SOT)
                      Case{3, 16, 0, 2.37, -3, 9, 90, 37},          // order 0, magnified
                      Case{1, 16, 1, 0.5, 0, 0, 150, 50},           // minified
                      Case{3, 12, 1, 2.37, 40, -1000, 100, 45},     // magnified, colour
                      Case{1, 16, 1, 1.0, k_tera, -k_tera, 120, 40},       // far out, unit scale
                      Case{3, 16, 1, 2.37, -k_tera, k_tera + 17, 77, 30},  // far out, magnified
                      Case{1, 20, 0, 0.5, k_tera, k_tera, 96, 33},         // far out, order 0, minified
                      Case{1, 5, 1, 1.0, -2, -2, 70, 20},                  // tiny support
                      Case{4, 16, 1, 1.0, 0, 0, 66, 20},                   // 4 channels
                      Case{1, 255, 1, 1.0, -100, 3, 60, 12},               // support 255: unit scale, per-pixel taps
                      Case{1, 16, 3, 1.0, -5, 7, 90, 31},                  // cubic B-spline (S1 §10)
                      Case{3, 12, 3, 0.61, k_tera, -3, 70, 25},            // cubic, colour, minified, far out
                      Case{1, 16, 5, 1.0, 3, 3, 80, 27},                   // quintic B-spline
                      Case{3, 10, 5, 2.37, -40, -k_tera, 64, 22}));        // quintic, colour, magnified

// The local-memory gather (kernels/texton_gather_local.cl) at MNI 1 and 30 (per-cell means 0.36 and 10.8,
// so very different impulse slots per cell), grey and colour, orders 0, 1 and 3, unit and
// non-unit scales, origins near 10^12 and near the 2^46 limit, for work-group sizes that are square, wide,
// odd (ragged tiles at the image edge) and 1 x 1: equal to the C++ reference and to the splat bit for bit.
struct LocalCase {
  int channels, support, order;
  double mni, scale;
  std::int64_t x, y;
};

TEST(TextonEval, GatherLocalEqualsReferenceAndSplatForMniAndWorkGroups) {
  const std::int64_t edge = (std::int64_t(1) << 46) - 200;  // |x| + width < 2^46
  const LocalCase cases[] = {
      {1, 16, 1, 1.0, 1.0, 0, 0},               {3, 16, 1, 30.0, 1.0, -517, 33},
      {1, 12, 0, 30.0, 2.37, k_tera, -k_tera},  {3, 12, 0, 1.0, 0.5, -k_tera, 5},
      {1, 10, 3, 30.0, 1.3, 7, k_tera + 3},     {3, 10, 3, 1.0, 1.0, -40, -40},
      {3, 16, 1, 30.0, 1.0, edge, -edge},
  };
  const std::array<std::size_t, 2> sizes[] = {{16, 16}, {32, 4}, {5, 3}, {1, 1}};
  const int w = 61, h = 37;
  // A device without local memory builds no local-memory kernel: gather-local
  // runs the plain gather there, with the same bits. The capability comes from the query, never assumed.
  const std::uint64_t device_local = texton_context().info().local_mem;
  for (const LocalCase& c : cases) {
    const TextonModel model = synthetic_model(c.channels, c.support, c.order, 31);
    RenderParams params;
    params.seed = 0xfeed;
    params.mni = c.mni;
    params.scale = c.scale;
    const std::string what = std::to_string(c.channels) + "ch order " + std::to_string(c.order) + " mni " +
                             std::to_string(c.mni) + " scale " + std::to_string(c.scale) + " origin " +
                             std::to_string(c.x) + "," + std::to_string(c.y);
    const std::vector<float> expected = TextonReference(model, params).render(c.x, c.y, w, h);
    TextonRenderer renderer(texton_context(), model);
    TextonRenderOptions splat;
    splat.strategy = TextonStrategy::Splat;
    EXPECT_EQ(count_bit_differences(renderer.render(params, c.x, c.y, w, h, splat), expected), 0u) << what;
    for (const auto& size : sizes) {
      TextonRenderOptions opt;
      opt.strategy = TextonStrategy::GatherLocal;
      opt.local_size = size;
      TextonRenderStats stats;
      const std::vector<float> l = renderer.render(params, c.x, c.y, w, h, opt, &stats);
      if (device_local == 0) {
        ASSERT_EQ(stats.strategy, TextonStrategy::Gather) << what;
      } else if (stats.strategy == TextonStrategy::GatherLocal) {
        EXPECT_EQ(stats.local_size, size) << what;  // else: the tile does not fit this device's local memory
      }
      EXPECT_EQ(count_bit_differences(l, expected), 0u) << what << " local " << size[0] << "x" << size[1];
    }
  }
}

// Local memory too small for the default 16 x 16 tile: the renderer shrinks the tile; too small for a 4 x 4
// tile: it runs the plain gather. Same bits every time. Chunking (tiles cut by chunk edges) changes none.
TEST(TextonEval, GatherLocalFallbacksAndChunks) {
  const TextonModel model = synthetic_model(3, 16, 1, 32);
  RenderParams params;
  params.seed = 5;
  const TextonReference reference(model, params);
  const std::vector<float> expected = reference.render(-30, 20, 90, 50);
  TextonRenderer renderer(texton_context(), model);
  TextonRenderOptions opt;
  opt.strategy = TextonStrategy::GatherLocal;
  TextonRenderStats stats;
  const TextonSetup setup = make_texton_setup(model, params);
  const std::uint64_t slots = stex_texton_cell_slots(setup.params);
  const std::uint64_t cells16 = std::uint64_t(stex_texton_tile_cells_max(setup.params, 16));
  const std::uint64_t cells8 = std::uint64_t(stex_texton_tile_cells_max(setup.params, 8));
  ASSERT_LT(cells8, cells16);  // support 16 + order 1: r = 17, cells of 10.2 pixels
  const std::uint64_t bytes16x16 = cells16 * cells16 * (4 + 8 * slots);
  const std::uint64_t bytes16x8 = cells16 * cells8 * (4 + 8 * slots);
  // The tile sizes below are the renderer's choice where the device has the local memory for them (the
  // query, CL_DEVICE_LOCAL_MEM_SIZE; with none every case runs the plain gather, same bits)
  // and where the kernel's work-group limit (CL_KERNEL_WORK_GROUP_SIZE; 32 on llvmpipe) takes a 16 x 16 tile.
  const std::uint64_t device_local = texton_context().info().local_mem;
  Kernel local_kernel(texton_context().program("texton_gather_local.cl"), "texton_gather_local");
  const bool fits16x16 = local_kernel.fit_local(texton_context(), {16, 16}) == std::array<std::size_t, 2>{16, 16};
  EXPECT_EQ(count_bit_differences(renderer.render(params, -30, 20, 90, 50, opt, &stats), expected), 0u);
  if (device_local >= bytes16x16 && fits16x16) {
    EXPECT_EQ(stats.strategy, TextonStrategy::GatherLocal);
    EXPECT_EQ(stats.local_size, (std::array<std::size_t, 2>{16, 16}));
  } else if (device_local == 0) {
    EXPECT_EQ(stats.strategy, TextonStrategy::Gather);
  }

  // Room for a 16 x 8 tile but not for 16 x 16.
  opt.local_mem_limit = std::size_t(bytes16x8);
  EXPECT_EQ(count_bit_differences(renderer.render(params, -30, 20, 90, 50, opt, &stats), expected), 0u);
  if (device_local >= bytes16x8 && fits16x16) {
    EXPECT_EQ(stats.strategy, TextonStrategy::GatherLocal);
    EXPECT_EQ(stats.local_size, (std::array<std::size_t, 2>{16, 8}));
  } else if (device_local == 0) {
    EXPECT_EQ(stats.strategy, TextonStrategy::Gather);
  }
  // Not even a 4 x 4 tile: the plain gather.
  opt.local_mem_limit = 64;
  EXPECT_EQ(count_bit_differences(renderer.render(params, -30, 20, 90, 50, opt, &stats), expected), 0u);
  EXPECT_EQ(stats.strategy, TextonStrategy::Gather);
  // A caller's work-group that does not fit: the plain gather too.
  opt.local_size = {16, 16};
  opt.local_mem_limit = std::size_t(cells16 * cells16 * (4 + 8 * slots)) - 1;
  EXPECT_EQ(count_bit_differences(renderer.render(params, -30, 20, 90, 50, opt, &stats), expected), 0u);
  EXPECT_EQ(stats.strategy, TextonStrategy::Gather);

  TextonRenderOptions chunked;
  chunked.strategy = TextonStrategy::GatherLocal;
  chunked.max_chunk_pixels = 1000;  // chunks of 90 x 11 rows: tiles cut at every chunk edge
  EXPECT_EQ(count_bit_differences(renderer.render(params, -30, 20, 90, 50, chunked, &stats), expected), 0u);
  EXPECT_GT(stats.chunks, 4);
}

TEST(TextonEval, PointQueryEqualsRegionPixels) {
  const TextonModel model = synthetic_model(3, 16, 1, 5);
  RenderParams params;
  params.seed = 99;
  params.scale = 1.7;
  const TextonReference reference(model, params);
  const std::vector<float> img = reference.render(-20, 30, 40, 8);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 40; i += 7) {
      float v[4];
      reference.eval_pixel(-20 + i, 30 + j, v);
      for (int c = 0; c < 3; ++c) EXPECT_EQ(v[c], img[(std::size_t(j) * 40 + i) * 3 + c]);
    }
}

// A 1024^2 render equals its four 512^2 tiles rendered separately at the right origins, and a ragged
// tiling into 300 x 700 pieces (and the remainders), bit for bit.
TEST(TextonEval, TilingInvarianceSplat) {
  const TextonModel model = synthetic_model(3, 64, 1, 21);
  RenderParams params;
  params.seed = 1234;
  TextonRenderer renderer(texton_context(), model);
  TextonRenderOptions opt;
  opt.strategy = TextonStrategy::Splat;
  const int n = 1024, nc = 3;
  const std::int64_t ox = -300, oy = 77;
  const std::vector<float> whole = renderer.render(params, ox, oy, n, n, opt);

  std::vector<float> quads(whole.size(), -1.0f);
  for (int ty = 0; ty < 2; ++ty)
    for (int tx = 0; tx < 2; ++tx)
      test::paste(quads, n, nc, tx * 512, ty * 512, 512, 512,
                  renderer.render(params, ox + tx * 512, oy + ty * 512, 512, 512, opt));
  EXPECT_EQ(count_bit_differences(whole, quads), 0u);

  std::vector<float> ragged(whole.size(), -1.0f);
  for (int y = 0; y < n; y += 700)
    for (int x = 0; x < n; x += 300) {
      const int w = std::min(300, n - x), h = std::min(700, n - y);
      test::paste(ragged, n, nc, x, y, w, h, renderer.render(params, ox + x, oy + y, w, h, opt));
    }
  EXPECT_EQ(count_bit_differences(whole, ragged), 0u);
}

TEST(TextonEval, TilingInvarianceGather) {
  const TextonModel model = synthetic_model(1, 32, 1, 22);
  RenderParams params;
  params.seed = 77;
  params.scale = 1.3;
  TextonRenderer renderer(texton_context(), model);
  TextonRenderOptions opt;
  opt.strategy = TextonStrategy::Gather;
  const int n = 256;
  const std::vector<float> whole = renderer.render(params, 0, -128, n, n, opt);
  std::vector<float> tiled(whole.size(), -1.0f);
  for (int y = 0; y < n; y += 100)
    for (int x = 0; x < n; x += 70) {
      const int w = std::min(70, n - x), h = std::min(100, n - y);
      test::paste(tiled, n, 1, x, y, w, h, renderer.render(params, x, -128 + y, w, h, opt));
    }
  EXPECT_EQ(count_bit_differences(whole, tiled), 0u);
}

// Chunking (forced by a small chunk cap), work-group size, strip width and repetition change no bit.
TEST(TextonEval, ChunkWorkGroupStripAndRunInvariance) {
  const TextonModel model = synthetic_model(3, 24, 1, 23);
  RenderParams params;
  params.seed = 4242;
  params.scale = 1.0;
  TextonRenderer renderer(texton_context(), model);
  const int w = 300, h = 170;
  const std::int64_t x = 1000, y = -5000;

  for (TextonStrategy st : {TextonStrategy::Splat, TextonStrategy::Gather}) {
    TextonRenderOptions base;
    base.strategy = st;
    TextonRenderStats stats;
    const std::vector<float> ref = renderer.render(params, x, y, w, h, base, &stats);
    EXPECT_EQ(stats.chunks, 1);
    EXPECT_EQ(stats.strategy, st);

    TextonRenderOptions chunked = base;
    chunked.max_chunk_pixels = 7000;  // 7000 / 300 -> chunks of 23 rows
    const std::vector<float> c = renderer.render(params, x, y, w, h, chunked, &stats);
    EXPECT_GT(stats.chunks, 5);
    EXPECT_EQ(count_bit_differences(ref, c), 0u) << texton_strategy_name(st) << " chunked";

    chunked.max_chunk_pixels = 100;  // narrower than a row: 2-D chunks of 100 x 1
    const std::vector<float> c2 = renderer.render(params, x, y, w, 20, chunked, &stats);
    EXPECT_EQ(stats.chunks, 3 * 20);
    EXPECT_EQ(count_bit_differences(test::crop(ref, w, 3, 0, 0, w, 20), c2), 0u)
        << texton_strategy_name(st) << " 2-D chunks";

    TextonRenderOptions wg = base;
    wg.local_size = {st == TextonStrategy::Splat ? std::size_t(2) : std::size_t(8), 3};
    EXPECT_EQ(count_bit_differences(ref, renderer.render(params, x, y, w, h, wg)), 0u)
        << texton_strategy_name(st) << " local size 2/8 x 3";
    wg.local_size = {1, 1};
    EXPECT_EQ(count_bit_differences(ref, renderer.render(params, x, y, w, h, wg)), 0u)
        << texton_strategy_name(st) << " local size 1 x 1";

    EXPECT_EQ(count_bit_differences(ref, renderer.render(params, x, y, w, h, base)), 0u)
        << texton_strategy_name(st) << " repeated";
  }

  TextonRenderOptions strip;
  strip.strategy = TextonStrategy::Splat;
  const std::vector<float> a = renderer.render(params, x, y, w, h, strip);
  for (int sw : {1, 17, 64, 300, 1000})
    for (int band : {1, 5, 16, 200}) {
      strip.splat_strip = sw;
      strip.splat_band = band;
      EXPECT_EQ(count_bit_differences(a, renderer.render(params, x, y, w, h, strip)), 0u)
          << "strip " << sw << " band " << band;
    }
}

TEST(TextonEval, SeedChangesOutput) {
  const TextonModel model = synthetic_model(1, 16, 1, 24);
  TextonRenderer renderer(texton_context(), model);
  RenderParams p1, p2;
  p1.seed = 1;
  p2.seed = 2;
  const std::vector<float> a = renderer.render(p1, 0, 0, 128, 128);
  const std::vector<float> b = renderer.render(p2, 0, 0, 128, 128);
  // Independent realisations: essentially every pixel differs.
  EXPECT_GT(count_bit_differences(a, b), a.size() * 99 / 100);
  // A 64-bit seed: only the high word differs.
  RenderParams p3 = p1;
  p3.seed = p1.seed | (std::uint64_t(1) << 40);
  EXPECT_GT(count_bit_differences(a, renderer.render(p3, 0, 0, 128, 128)), a.size() * 99 / 100);
}

TEST(TextonEval, AutoStrategyAndValidation) {
  const TextonModel model = synthetic_model(1, 8, 1, 25);
  TextonRenderer renderer(texton_context(), model);
  const bool cpu = (texton_context().info().type & CL_DEVICE_TYPE_CPU) != 0;
  EXPECT_EQ(renderer.resolve(TextonStrategy::Auto), cpu ? TextonStrategy::Splat : TextonStrategy::Gather);
  EXPECT_EQ(parse_texton_strategy("gather"), TextonStrategy::Gather);
  EXPECT_EQ(parse_texton_strategy("gather-local"), TextonStrategy::GatherLocal);
  EXPECT_STREQ(texton_strategy_name(TextonStrategy::GatherLocal), "gather-local");
  // Auto: splat on CPUs, the local-memory gather on GPUs, the plain gather on other devices.
  EXPECT_EQ(resolve_texton_strategy(TextonStrategy::Auto, CL_DEVICE_TYPE_CPU), TextonStrategy::Splat);
  EXPECT_EQ(resolve_texton_strategy(TextonStrategy::Auto, CL_DEVICE_TYPE_GPU), TextonStrategy::GatherLocal);
  EXPECT_EQ(resolve_texton_strategy(TextonStrategy::Auto, CL_DEVICE_TYPE_ACCELERATOR), TextonStrategy::Gather);
  EXPECT_EQ(resolve_texton_strategy(TextonStrategy::Gather, CL_DEVICE_TYPE_GPU), TextonStrategy::Gather);
  try {
    parse_texton_strategy("fast");
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("fast"), std::string::npos);
  }
  RenderParams p;
  EXPECT_THROW(renderer.render(p, 0, 0, 0, 10), Error);
  EXPECT_THROW(renderer.render(p, std::int64_t(1) << 46, 0, 10, 10), Error);
  p.mni = -1;
  EXPECT_THROW(renderer.render(p, 0, 0, 10, 10), Error);
}

}  // namespace
}  // namespace stex
