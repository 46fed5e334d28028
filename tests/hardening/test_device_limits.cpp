// Device limits (issue #12): a render whose output is larger than the device's largest allocation is split
// into chunks automatically and does not fail for size alone. PoCL's device shrinks to 1 GiB with
// POCL_MEMORY_LIMIT=1 (docs/hardening.md; CL_DEVICE_MAX_MEM_ALLOC_SIZE is then 256 MiB): the test renders a
// one-channel region of more than max_alloc bytes with no chunk cap of its own (so the device limit is
// what splits it) and compares it bit for bit with the same region rendered as separate row strips.
// It runs in a forked child: the environment variable must be set before PoCL initialises, and the test
// binary's other children (the damage sweep) must not inherit an OpenCL runtime.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <limits>

#include "hardening/isolate.h"
#include "runtime/context.h"
#include "runtime/model.h"
#include "runtime/texton_renderer.h"
#include "test_device.h"

namespace {

stex::TextonModel small_model() {
  stex::TextonModel m;
  m.channels = 1;
  m.support = 8;
  m.alpha.resize(64);
  for (int i = 0; i < 64; ++i) m.alpha[std::size_t(i)] = 0.01f * float((i * 37) % 17) - 0.08f;
  m.mean = {0.5f, 0, 0, 0};
  m.exemplar_name = "synthetic";
  return m;
}

}  // namespace

TEST(DeviceLimits, RenderLargerThanMaxAllocationIsChunkedAndExact) {
  STEX_SKIP_UNLESS_POCL("POCL_MEMORY_LIMIT shrinks PoCL's device only");
  stex::test::IsolatedLimits limits;
  limits.seconds = 600;
  limits.per_input_seconds = 600;  // one input: the whole render
  limits.address_space = 0;  // the child holds two ~260 MiB images; PoCL maps more than it touches
  auto r = stex::test::run_isolated_batch({0}, [](std::uint64_t, const std::function<void(const std::string&)>& fail) {
    ::setenv("POCL_MEMORY_LIMIT", "1", 1);
    auto ctx = stex::Context::create(stex::test::test_device_spec());
    const std::uint64_t max_alloc = ctx->info().max_alloc;
    if (max_alloc == 0 || max_alloc > (std::uint64_t(1) << 30))
      return fail("POCL_MEMORY_LIMIT=1 did not shrink the device: max_alloc " + std::to_string(max_alloc));
    const int width = 4096;
    // One chunk's worth of rows plus a ragged remainder: the output exceeds max_alloc.
    const int height = int(max_alloc / (std::uint64_t(width) * sizeof(float))) + 300;
    const std::uint64_t bytes = std::uint64_t(width) * std::uint64_t(height) * sizeof(float);
    if (bytes <= max_alloc) return fail("region not larger than max_alloc");

    stex::TextonRenderer renderer(*ctx, small_model());
    stex::RenderParams params;
    params.seed = 0x5eed1234;
    stex::TextonRenderOptions unbounded;
    unbounded.max_chunk_pixels = std::numeric_limits<std::size_t>::max();  // only the device limits chunks
    stex::TextonRenderStats stats;
    const std::int64_t x0 = -123456789, y0 = 987654;
    const std::vector<float> whole = renderer.render(params, x0, y0, width, height, unbounded, &stats);
    if (stats.chunks < 2) return fail("rendered in " + std::to_string(stats.chunks) + " chunk(s)");

    std::vector<float> strips(whole.size());
    const int strip = 4099;  // not a divisor of the chunk height: strip and chunk edges differ
    for (int y = 0; y < height; y += strip) {
      const int h = std::min(strip, height - y);
      renderer.render(params, x0, y0 + y, width, h, strips.data() + std::size_t(y) * width);
    }
    std::size_t diff = 0;
    for (std::size_t i = 0; i < whole.size(); ++i) diff += std::memcmp(&whole[i], &strips[i], sizeof(float)) != 0;
    if (diff != 0) fail(std::to_string(diff) + " values differ between the chunked render and the strips");
    std::printf("max_alloc %llu B, region %dx%d = %llu B, %d chunks\n", (unsigned long long)max_alloc, width,
                height, (unsigned long long)bytes, stats.chunks);
  }, limits);
  for (const auto& f : r.failures) ADD_FAILURE() << f;
  EXPECT_EQ(r.inputs_done, 1);
}
