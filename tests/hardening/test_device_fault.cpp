// A device error mid-run gives the retryable exit code 75 and no partial output (issue #12). The fault is
// injected with STEX_FAULT_DEVICE_LAUNCH=N (runtime/texton_renderer.cpp: the N-th kernel launch fails with
// CL_OUT_OF_RESOURCES, as a lost device does). Runs the real `stex render` binary: a single image, a farm
// render into one large image, and a farm render into one file per tile (tiles finished before the fault
// stay, whole; the rest are rendered by the retry).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include "analysis/image_io.h"
#include "model/codecs.h"
#include "test_device.h"
#include "hardening/isolate.h"
#include "runtime/model.h"
#include "cli_run.h"

namespace fs = std::filesystem;

namespace {

fs::path tmp_dir(const std::string& name) {
  fs::path d = fs::path(STEX_TEST_TMP_DIR) / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

struct CliRun {
  int exit_code = -1;
  std::string err;
};

CliRun run_stex(const fs::path& dir, const std::string& env, const std::string& args) {
  const stex::test::CliRun c = stex::test::run_stex_cli(args, "device_fault_run", dir.string(), env);
  return {c.code, c.err};
}

void write_model(const fs::path& path) {
  stex::TextonModel m;
  m.channels = 3;
  m.support = 8;
  m.alpha.resize(3 * 64);
  for (std::size_t i = 0; i < m.alpha.size(); ++i) m.alpha[i] = 0.01f * float((i * 29) % 13) - 0.06f;
  m.mean = {0.5f, 0.4f, 0.3f, 0.0f};
  m.exemplar_name = "synthetic.png";
  m.stex_version = "test";
  stex::save_model(m, path.string());
}

// The known-answer self-test (runtime/selftest.h) renders before the first render on a device unless its
// cached pass is there, and its launches count towards STEX_FAULT_DEVICE_LAUNCH: one render without the
// fault first, so that the N-th launch is the render's whatever the cache held before.
void warm_selftest(const fs::path& dir) {
  const CliRun r = run_stex(dir, "", "render m.stex -o warm.exr --size 8x8");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  fs::remove(dir / "warm.exr");
}

}  // namespace

TEST(DeviceFault, SingleImageExitsRetryableWithoutOutput) {
  const fs::path dir = tmp_dir("fault_single");
  write_model(dir / "m.stex");
  warm_selftest(dir);
  CliRun r = run_stex(dir, "STEX_FAULT_DEVICE_LAUNCH=1", "render m.stex -o out.exr --size 256x256");
  EXPECT_EQ(r.exit_code, 75) << r.err;
  EXPECT_NE(r.err.find("CL_OUT_OF_RESOURCES"), std::string::npos) << r.err;
  EXPECT_EQ(listing(dir), std::set<std::string>{"m.stex"});
  // Without the fault the same command succeeds: the failure came from the injected device error alone.
  r = run_stex(dir, "", "render m.stex -o out.exr --size 256x256");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(listing(dir), (std::set<std::string>{"m.stex", "out.exr"}));
}

TEST(DeviceFault, FarmLargeImageExitsRetryableWithoutOutput) {
  const fs::path dir = tmp_dir("fault_large");
  write_model(dir / "m.stex");
  warm_selftest(dir);
  CliRun r = run_stex(dir, "STEX_FAULT_DEVICE_LAUNCH=3", "render m.stex -o out.exr --size 256x256 --tile-size 64");
  EXPECT_EQ(r.exit_code, 75) << r.err;
  EXPECT_EQ(listing(dir), std::set<std::string>{"m.stex"});
}

TEST(DeviceFault, FarmTilesKeepFinishedTilesAndRetryCompletes) {
  const fs::path dir = tmp_dir("fault_tiles");
  write_model(dir / "m.stex");
  warm_selftest(dir);
  const std::string args = "render m.stex -o 'out_{tx}_{ty}.exr' --size 256x256 --tile-size 64";
  CliRun r = run_stex(dir, "STEX_FAULT_DEVICE_LAUNCH=3", args);
  EXPECT_EQ(r.exit_code, 75) << r.err;
  // The third launch failed: the tiles finished before it are kept, the failed one left nothing (no temp
  // file). How many tiles finished depends on the launches a tile takes on the test device (PoCL: one, so
  // tiles 0 and 1; rusticl's llvmpipe renders a 64^2 tile in more launches, so none may have finished).
  const std::set<std::string> kept = listing(dir);
  EXPECT_EQ(kept.count("m.stex"), 1u);
  EXPECT_LE(kept.size(), 3u);
  const std::vector<std::string> order = {"m.stex", "out_0_0.exr", "out_1_0.exr"};
  EXPECT_EQ(kept, std::set<std::string>(order.begin(), order.begin() + std::ptrdiff_t(kept.size())));
  if (stex::test::test_device_is_pocl()) {
    EXPECT_EQ(kept.size(), 3u);
  }
  r = run_stex(dir, "", args + " --skip-existing");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(listing(dir).size(), 17u);
}

// A driver that cuts a kernel's loops short (the loop watchdog, runtime/loop_watchdog.h; injected with
// STEX_FAULT_WATCHDOG=N: the next N canary reads report a trip). One trip: the launch is re-run with a
// smaller splat block and the render succeeds with the bits of an untripped render. A trip that persists
// down to a one-pixel splat block moves to the plain gather (the same bits), and down to one work-item per
// work-group there: exit 4 (device refused), a message naming the kernel and the cause, and no output file.
TEST(DeviceFault, LoopWatchdogRetriesThenRefusesWithoutOutput) {
  const fs::path dir = tmp_dir("fault_watchdog");
  write_model(dir / "m.stex");
  warm_selftest(dir);
  const std::string args = " --size 96x64 --origin 1000003,-77 --strategy splat";
  CliRun r = run_stex(dir, "", "render m.stex -o clean.exr" + args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_stex(dir, "STEX_FAULT_WATCHDOG=1", "render m.stex -o retried.exr" + args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The pixels, bit for bit (the files differ in their creation time). Read in a forked child: reading an
  // EXR here would start OpenEXR's global thread pool in this process, and the fuzz-regression children
  // forked later in this binary (isolate.h) would inherit the pool without its threads and hang.
  const stex::test::BatchResult cmp = stex::test::run_isolated_batch(
      {0}, [&](std::uint64_t, const std::function<void(const std::string&)>& fail) {
        const stex::Image a = stex::load_float_image((dir / "clean.exr").string(), "clean render", 1u << 20);
        const stex::Image b = stex::load_float_image((dir / "retried.exr").string(), "retried render", 1u << 20);
        if (a.pixels.size() != 96u * 64u * 3u || b.pixels.size() != a.pixels.size())
          fail("pixel counts " + std::to_string(a.pixels.size()) + " and " + std::to_string(b.pixels.size()));
        else if (std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) != 0)
          fail("the re-run launch gave different pixels");
      });
  EXPECT_TRUE(cmp.failures.empty()) << cmp.failures.front();
  EXPECT_EQ(cmp.inputs_done, 1);
  fs::remove(dir / "clean.exr");
  fs::remove(dir / "retried.exr");

  r = run_stex(dir, "STEX_FAULT_WATCHDOG=1000", "render m.stex -o out.exr" + args);
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("texton_gather"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("cut the loops"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("docs/portability.md"), std::string::npos) << r.err;
  EXPECT_EQ(listing(dir), std::set<std::string>{"m.stex"});
}
