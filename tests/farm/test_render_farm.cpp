// The real `stex render` in farm mode (texton, lrp and gabor noise on the OpenCL device, DSN on the host):
// tiles rendered by separate processes in any order, stitched by `stex assemble`, and the single-image tiled
// writer all equal the ordinary whole-image render bit for bit; resume and refusals; the peak memory of a
// 16384^2 tiled EXR render; tiles per second on this device.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>

#include "model/codecs.h"
#include "farm/output_file.h"
#include "kernels/test_texton_common.h"
#include "sanitizer.h"
#include "tests/farm/farm_test_util.h"

using namespace stex;
using namespace stex::farm;
using namespace stex::farm::test;

namespace {

const std::string kStex = STEX_CLI_PATH;

std::string save_test_model(const std::string& dir) {
  TextonModel m = stex::test::synthetic_model(3, 16, 1, 61, 0.01f);
  m.exemplar_name = "none.png";
  m.stex_version = STEX_VERSION_STRING;
  std::string path = dir + "/model.stex";
  save_model(m, path);
  return path;
}

std::vector<std::string> render_args(const std::string& model, const std::string& out,
                                     const std::string& size, std::vector<std::string> extra = {}) {
  std::vector<std::string> a = {kStex,    "render", model,      "-o",           out, "--size", size,
                                "--seed", "5",      "--origin", "123456789,-42"};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

nlohmann::json json_of(const std::string& out) {
  std::size_t end = out.find_last_not_of('\n');
  std::size_t start = out.rfind('\n', end);
  start = start == std::string::npos ? 0 : start + 1;
  return nlohmann::json::parse(out.substr(start, end - start + 1));
}

}  // namespace

TEST(RenderFarm, TasksInAnyOrderAssembleToTheWholeRender) {
  std::string dir = fresh_dir();
  std::string model = save_test_model(dir);
  ProcessResult r = run_process(render_args(model, dir + "/whole.exr", "700x500"), dir + "/p");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<float> whole = read_output_pixels(dir + "/whole.exr");
  ASSERT_EQ(whole.size(), 700u * 500 * 3);

  // 6x4 = 24 tiles of 128, 5 per task: tasks 0-4 as separate processes, shuffled, indices from the env.
  std::vector<int> tasks = {0, 1, 2, 3, 4};
  std::shuffle(tasks.begin(), tasks.end(), std::mt19937(3));
  const std::string templ = dir + "/tiles/t_{tx:02}_{ty:02}.exr";
  for (int task : tasks) {
    r = run_process(
        render_args(model, templ, "700x500", {"--tile-size", "128", "--tiles-per-task", "5", "--json"}),
        dir + "/p", {"SLURM_ARRAY_TASK_ID=" + std::to_string(task)});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(json_of(r.out)["tiles_done"], task == 4 ? 4 : 5);
  }
  r = run_process({kStex, "assemble", "--template", templ, "-o", dir + "/assembled.exr"}, dir + "/p");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_output_pixels(dir + "/assembled.exr"), whole);

  // One large image through the out-of-core writer.
  r = run_process(render_args(model, dir + "/big.exr", "700x500", {"--tile-size", "128"}), dir + "/p");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_output_pixels(dir + "/big.exr"), whole);
  OutputInspection ins = inspect_output(dir + "/big.exr");
  ASSERT_EQ(ins.state, OutputState::Valid) << ins.problem;
  EXPECT_TRUE(ins.info.tiled);
  EXPECT_EQ(ins.info.id.seed, 5u);
  EXPECT_EQ(ins.info.id.origin_x, 123456789);

  // Resume: everything up to date. Another seed: refused with --skip-existing, re-rendered with --update.
  r = run_process(render_args(model, templ, "700x500", {"--tile-size", "128", "--skip-existing", "--json"}),
                  dir + "/p");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json_of(r.out)["tiles_skipped"], 24);
  std::vector<std::string> other =
      render_args(model, templ, "700x500", {"--tile-size", "128", "--skip-existing"});
  other[8] = "6";  // --seed 6
  r = run_process(other, dir + "/p");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("param hash"), std::string::npos) << r.err;
  EXPECT_EQ(count_temp_files(dir + "/tiles"), 0);
}

// Every model kind goes through the same farm path (analysis/noise_kinds registry): per-tile files from
// separate processes, assembled, and the out-of-core single image equal the whole render bit for bit.
TEST(RenderFarm, EveryKindTilesAssembleToTheWholeRender) {
  std::string dir = fresh_dir();
  struct Kind {
    std::string name;
    std::vector<std::string> make;
  };
  const std::vector<Kind> kinds = {
      {"lrp",
       {kStex, "analyze", "--method", "lrp", "--psd", "ring:0.1,0.01", "--psd-size", "64", "--cosines", "5",
        "--strata", "1", "-o", dir + "/lrp.stex"}},
      {"gabor",
       {kStex, "gabor", "-o", dir + "/gabor.stex", "--frequency", "0.1", "--orientation", "30", "--lobes", "2",
        "--bandwidth", "0.06"}},
  };
  for (const Kind& k : kinds) {
    SCOPED_TRACE(k.name);
    const std::string model = dir + "/" + k.name + ".stex";
    ProcessResult r = run_process(k.make, dir + "/p");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = run_process(render_args(model, dir + "/" + k.name + "_whole.exr", "300x200"), dir + "/p");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::vector<float> whole = read_output_pixels(dir + "/" + k.name + "_whole.exr");
    ASSERT_FALSE(whole.empty());
    const std::string templ = dir + "/" + k.name + "_tiles/t_{index}.exr";
    for (const char* tiles : {"4-5", "0-3"}) {  // 3x2 tiles of 128 in two processes, out of order
      r = run_process(render_args(model, templ, "300x200", {"--tile-size", "128", "--tiles", tiles}),
                      dir + "/p");
      ASSERT_EQ(r.exit_code, 0) << r.err;
    }
    r = run_process({kStex, "assemble", "--template", templ, "-o", dir + "/" + k.name + "_assembled.exr"},
                    dir + "/p");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(read_output_pixels(dir + "/" + k.name + "_assembled.exr"), whole);
    r = run_process(render_args(model, dir + "/" + k.name + "_big.exr", "300x200", {"--tile-size", "64"}),
                    dir + "/p");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(read_output_pixels(dir + "/" + k.name + "_big.exr"), whole);
  }
}

// Issue #4: the peak resident memory of the real renderer (PoCL runtime, device buffers in host memory,
// the out-of-core tiled EXR writer) for a 16384^2 image, printed and below 1 GiB. A grey model at MNI 4
// keeps the run short; the memory does not depend on the MNI. Three tiles are checked against renders of
// their own region.
TEST(RenderFarm, PeakRssOf16384SquaredTiledExrRenderStaysBounded) {
  std::string dir = fresh_dir();
  TextonModel m = stex::test::synthetic_model(1, 16, 1, 62, 0.01f);
  m.exemplar_name = "none.png";
  m.stex_version = STEX_VERSION_STRING;
  const std::string model = dir + "/grey.stex", out = dir + "/big.exr";
  save_model(m, model);
  ProcessResult r = run_process(
      {kStex, "render", model, "-o", out, "--size", "16384x16384", "--tile-size", "1024", "--mni", "4",
       "--seed", "9", "--compression", "none", "--json", "--progress", "none"},
      dir + "/p");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json j = json_of(r.out);
  const double rss_mib = double(r.max_rss_kb) / 1024.0;
  std::printf(
      "[ farm ] stex render 16384x16384 grey float tiled EXR (256 tiles of 1024^2, texton MNI 4, default "
      "device): peak RSS %.1f MiB, %.2f s, %.2f tiles/s, %.1f Mpx/s\n",
      rss_mib, j["seconds"].get<double>(), 256.0 / j["seconds"].get<double>(),
      j["pixels_per_second"].get<double>() / 1e6);
  if (!stex::test::k_under_asan) {  // tests/sanitizer.h: not stex's memory under ASan
    EXPECT_LT(rss_mib, 1024.0);
  }
  EXPECT_EQ(j["tiles_done"], 256);
  OutputInspection ins = inspect_output(out, false);
  ASSERT_EQ(ins.state, OutputState::Valid) << ins.problem;
  EXPECT_TRUE(ins.info.tiled);
  EXPECT_EQ(ins.info.width, 16384);
  for (const std::pair<int, int>& t : {std::pair<int, int>{0, 0}, {7, 9}, {15, 15}}) {
    const std::string one = dir + "/one.exr";
    r = run_process({kStex, "render", model, "-o", one, "--size", "1024x1024", "--origin",
                     std::to_string(t.first * 1024) + "," + std::to_string(t.second * 1024), "--mni", "4",
                     "--seed", "9"},
                    dir + "/p");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(read_output_region(out, t.first * 1024, t.second * 1024, 1024, 1024), read_output_pixels(one))
        << "tile " << t.first << "," << t.second;
  }
  std::remove(out.c_str());
}

TEST(RenderFarm, DsnTilesAndRefusals) {
  std::string dir = fresh_dir();
  std::string model = save_test_model(dir);
  ProcessResult r =
      run_process(render_args(model, dir + "/dsn.exr", "300x200", {"--mode", "dsn"}), dir + "/p");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_process(
      render_args(model, dir + "/dsn_tiled.exr", "300x200", {"--mode", "dsn", "--tile-size", "64"}),
      dir + "/p");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_output_pixels(dir + "/dsn_tiled.exr"), read_output_pixels(dir + "/dsn.exr"));
  // ADSN is not tile-invariant: refused in farm mode.
  r = run_process(
      render_args(model, dir + "/adsn_{index}.exr", "300x200", {"--mode", "adsn", "--tile-size", "64"}),
      dir + "/p");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("tile-invariant"), std::string::npos) << r.err;
  // Farm options without --tile-size, and a bad spec, are usage errors.
  r = run_process(render_args(model, dir + "/x.exr", "300x200", {"--tiles", "0-3"}), dir + "/p");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--tile-size"), std::string::npos) << r.err;
  r = run_process(
      render_args(model, dir + "/x_{index}.exr", "300x200", {"--tile-size", "64", "--tiles", "2-1"}),
      dir + "/p");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("descending"), std::string::npos) << r.err;
}

TEST(RenderFarm, TilesPerSecondOnThisDevice) {
  std::string dir = fresh_dir();
  std::string model = save_test_model(dir);
  // 4096^2 RGB texton noise (MNI 30) as 16 tiles of 1024^2, one process, per-tile float EXR files without
  // compression (zip costs more than the render: docs/farm.md "Throughput").
  ProcessResult r = run_process(
      render_args(model, dir + "/t_{index}.exr", "4096x4096",
                  {"--tile-size", "1024", "--json", "--progress", "none", "--compression", "none"}),
      dir + "/p");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json j = json_of(r.out);
  EXPECT_EQ(j["tiles_done"], 16);
  std::printf(
      "[ farm ] stex render 4096x4096 RGB in 16 tiles of 1024^2 (texton, MNI 30, default device, no "
      "compression): "
      "%.2f s, %.2f tiles/s, %.1f Mpx/s, peak RSS %.0f MiB\n",
      j["seconds"].get<double>(), 16.0 / j["seconds"].get<double>(),
      j["pixels_per_second"].get<double>() / 1e6, double(r.max_rss_kb) / 1024.0);
}
