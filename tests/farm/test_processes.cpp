// Farm runs as real processes (tests/farm/helper/farm_synth, the `stex` binary): exit codes and messages,
// progress and JSON output, tiles rendered by separate processes in any order, two concurrent writers of
// the same 200 tiles, kill -9 at random moments then --skip-existing, SIGTERM at a tile boundary, a full
// filesystem (a small tmpfs when the test may mount one; the fsync fault hook always), and the peak RSS
// of a 16384^2 tiled EXR.
#include <gtest/gtest.h>
#include <sys/mount.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <thread>

#include "farm/output_file.h"
#include "farm/tile_grid.h"
#include "tests/farm/farm_test_util.h"
#include "tests/farm/synth_pattern.h"
#include "sanitizer.h"

using namespace stex::farm;
using namespace stex::farm::test;

namespace {

const std::string kSynth = STEX_FARM_SYNTH_PATH;
const std::string kStex = STEX_CLI_PATH;

std::vector<std::string> synth(const std::string& output, const std::string& size, int tile,
                               std::vector<std::string> extra = {}) {
  std::vector<std::string> a = {
      kSynth,   "-o", output,       "--size", size, "--tile-size", std::to_string(tile),
      "--seed", "11", "--progress", "none"};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

// Every tile file of the grid under `name` (a printf pattern over the index) exists, is a valid stex
// output and holds exactly the synthetic pixels of its window (seed 11, 3 channels, origin 0).
void expect_tile_valid(const std::string& path, const TileGrid& g, std::int64_t index) {
  OutputInspection ins = inspect_output(path);
  ASSERT_EQ(ins.state, OutputState::Valid) << path << ": " << ins.problem;
  TileRect t = g.tile(index);
  std::vector<float> want;
  synth_region(11, 3, t.x0, t.y0, t.width, t.height, want);
  EXPECT_EQ(read_output_pixels(path), want) << path;
}

std::string tile_path(const std::string& dir, std::int64_t i) {
  return dir + "/t_" + std::to_string(i) + ".exr";
}

nlohmann::json last_json_line(const std::string& out) {
  std::size_t end = out.find_last_not_of('\n');
  std::size_t start = out.rfind('\n', end);
  return nlohmann::json::parse(out.substr(start == std::string::npos ? 0 : start + 1,
                                          end - (start == std::string::npos ? 0 : start + 1) + 1));
}

}  // namespace

TEST(Processes, ExitCodesAndMessages) {
  std::string dir = fresh_dir();
  ProcessResult r =
      run_process(synth(dir + "/t_{index}.exr", "256x256", 64, {"--tiles", "3, x"}), dir + "/a");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("item 'x'"), std::string::npos) << r.err;
  r = run_process(synth(dir + "/t_{index}.exr", "256x256", 64, {"--tiles", "16"}), dir + "/a");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("4x4 tiles"), std::string::npos) << r.err;
  r = run_process(synth(dir + "/t_{index}.exr", "256x256", 64), dir + "/a", {"SLURM_ARRAY_TASK_ID=20"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("tasks 0-15"), std::string::npos) << r.err;
  r = run_process(synth(dir + "/t_{foo}.exr", "256x256", 64), dir + "/a");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("{foo}"), std::string::npos) << r.err;
  // A device failure mid-run: retryable code, earlier tiles kept, no temp file.
  r = run_process(synth(dir + "/t_{index}.exr", "256x256", 64, {"--fail-at-x", "128"}), dir + "/a");
  EXPECT_EQ(r.exit_code, 75) << r.err;
  EXPECT_NE(r.err.find("synthetic device failure"), std::string::npos) << r.err;
  EXPECT_TRUE(exists(tile_path(dir, 1)));
  EXPECT_FALSE(exists(tile_path(dir, 2)));
  EXPECT_EQ(count_temp_files(dir), 0);
  // Existing outputs without a policy flag: usage error, nothing rendered.
  r = run_process(synth(dir + "/t_{index}.exr", "256x256", 64, {"--json"}), dir + "/a");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--skip-existing"), std::string::npos) << r.err;
  // The retry resumes.
  r = run_process(synth(dir + "/t_{index}.exr", "256x256", 64, {"--skip-existing", "--json"}), dir + "/a");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json j = last_json_line(r.out);
  EXPECT_EQ(j["tiles_skipped"], 2);
  EXPECT_EQ(j["tiles_done"], 14);
  TileGrid g(256, 256, 64);
  for (std::int64_t i = 0; i < g.count(); ++i) expect_tile_valid(tile_path(dir, i), g, i);
}

TEST(Processes, ProgressDryRunAndJson) {
  std::string dir = fresh_dir();
  std::vector<std::string> base = synth(dir + "/t_{index}.exr", "128x128", 64);
  base.erase(base.end() - 2, base.end());  // drop "--progress none"
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = base;
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  ProcessResult r = run_process(with({"--dry-run", "--tiles-per-task", "2"}), dir + "/a");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(
      r.out.find("task 1 tile 3 (tx 1, ty 1) window 64,64 64x64 -> " + dir + "/t_3.exr: render (missing)"),
      std::string::npos)
      << r.out;
  EXPECT_TRUE(list_dir(dir).size() == 2u);  // only the captured output files
  r = run_process(with({"--progress", "lines"}), dir + "/a");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("stex: tile 0 done (1/4, 25.0%"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("stex: tile 3 done (4/4, 100.0%, ETA 0 s): " + dir + "/t_3.exr"), std::string::npos)
      << r.err;
  r = run_process(with({"--progress", "openjd", "--skip-existing", "--tiles", "0,1"}), dir + "/a");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("openjd_progress: 0\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("openjd_progress: 50.00\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("openjd_progress: 100.00\n"), std::string::npos) << r.out;
  r = run_process(with({"--progress", "none", "--force", "--json"}), dir + "/a");
  nlohmann::json j = last_json_line(r.out);
  EXPECT_EQ(j["tiles_selected"], 4);
  EXPECT_EQ(j["tiles_done"], 4);
  EXPECT_EQ(j["tiles_failed"], 0);
  EXPECT_EQ(j["pixels_rendered"], 128 * 128);
  EXPECT_GT(j["pixels_per_second"].get<double>(), 0.0);
  EXPECT_EQ(j["exit_code"], 0);
  // A failure still prints the summary, with the error and its exit code.
  r = run_process(with({"--progress", "none", "--force", "--json", "--fail-at-x", "64"}), dir + "/a");
  EXPECT_EQ(r.exit_code, 75);
  j = last_json_line(r.out);
  EXPECT_EQ(j["tiles_failed"], 1);
  EXPECT_EQ(j["tiles_done"], 1);
  EXPECT_EQ(j["exit_code"], 75);
}

TEST(Processes, SeparateTasksInAnyOrderAssembleToOneRender) {
  std::string dir = fresh_dir();
  const std::string templ = dir + "/tiles/t_{tx}_{ty}.exr";
  TileGrid g(700, 500, 128);  // 6x4 = 24 tiles, ragged
  const int per_task = 5;     // 5 tasks, the last one ragged
  std::vector<int> tasks = {3, 0, 4, 2, 1};
  for (int task : tasks) {  // as a scheduler would run them: each its own process, env task id
    ProcessResult r =
        run_process(synth(templ, "700x500", 128, {"--tiles-per-task", std::to_string(per_task)}),
                    dir + "/task", {"SLURM_ARRAY_TASK_ID=" + std::to_string(task)});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  ProcessResult r = run_process(synth(dir + "/single.exr", "700x500", 128), dir + "/single");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_process({kStex, "assemble", "--template", templ, "-o", dir + "/assembled.exr"}, dir + "/asm");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<float> want;
  synth_region(11, 3, 0, 0, 700, 500, want);
  EXPECT_EQ(read_output_pixels(dir + "/single.exr"), want);
  EXPECT_EQ(read_output_pixels(dir + "/assembled.exr"), want);
  // Listing files works too; a missing tile is a clear input error (exit 3) and writes nothing.
  std::vector<std::string> files = {kStex, "assemble", "-o", dir + "/partial.exr"};
  for (std::int64_t i = 0; i < g.count(); ++i) {
    TileRect t = g.tile(i);
    if (i != 13)
      files.push_back(dir + "/tiles/t_" + std::to_string(t.tx) + "_" + std::to_string(t.ty) + ".exr");
  }
  r = run_process(files, dir + "/asm");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("1 tile(s) missing: 13"), std::string::npos) << r.err;
  EXPECT_FALSE(exists(dir + "/partial.exr"));
  r = run_process({kStex, "assemble", "-o", dir + "/x.exr"}, dir + "/asm");
  EXPECT_EQ(r.exit_code, 2) << r.err;
}

TEST(Processes, TwoConcurrentWritersOfTheSame200Tiles) {
  std::string dir = fresh_dir();
  TileGrid g(640, 320, 32);  // 20 x 10 = 200 tiles
  ASSERT_EQ(g.count(), 200);
  std::vector<std::string> args = synth(dir + "/t_{index}.exr", "640x320", 32, {"--force"});
  pid_t a = spawn(args, dir + "/a.out", dir + "/a.err");
  pid_t b = spawn(args, dir + "/b.out", dir + "/b.err");
  ProcessResult ra = wait_process(a, dir + "/a.out", dir + "/a.err");
  ProcessResult rb = wait_process(b, dir + "/b.out", dir + "/b.err");
  EXPECT_EQ(ra.exit_code, 0) << ra.err;
  EXPECT_EQ(rb.exit_code, 0) << rb.err;
  int corrupt = 0;
  for (std::int64_t i = 0; i < g.count(); ++i) {
    OutputInspection ins = inspect_output(tile_path(dir, i));
    if (ins.state != OutputState::Valid) {
      ++corrupt;
      continue;
    }
    expect_tile_valid(tile_path(dir, i), g, i);
  }
  std::printf("[ farm ] two concurrent writers, 200 tiles: %d corrupt, %d temp files left\n", corrupt,
              count_temp_files(dir));
  EXPECT_EQ(corrupt, 0);
  EXPECT_EQ(count_temp_files(dir), 0);
}

TEST(Processes, KillNineAtRandomMomentsThenSkipExisting) {
  std::string dir = fresh_dir();
  TileGrid g(512, 384, 64);  // 8 x 6 = 48 tiles
  auto args = [&](const std::string& d) {
    return synth(d + "/t_{index}.exr", "512x384", 64, {"--skip-existing", "--json", "--sleep-ms", "5"});
  };
  // One undisturbed run gives the span to draw kill moments from.
  auto t0 = std::chrono::steady_clock::now();
  ProcessResult full = run_process(args(dir + "/ref"), dir + "/ref");
  double span_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(full.exit_code, 0) << full.err;
  std::mt19937 rng(20240611);
  // 24 kills; 8 in the sanitizer tree (tests/sanitizer.h), where each run of the instrumented stex costs ~8x
  // (docs/hardening.md, "the sanitized run's profile"); the bound on mid-run kills keeps its ratio (1 in 6).
  const int kKills = stex::test::k_under_asan ? 8 : 24;
  int mid_run = 0, temps_left = 0;
  for (int k = 0; k < kKills; ++k) {
    SCOPED_TRACE("kill " + std::to_string(k));
    std::string d = dir + "/k" + std::to_string(k);
    ASSERT_EQ(std::system(("mkdir -p '" + d + "'").c_str()), 0);
    // Even kills: any moment of a run (start-up included). Odd kills: a moment after the first tile is
    // in place, so that many land between tiles or inside a write.
    int delay_us = std::uniform_int_distribution<int>(0, int(span_ms * 1000))(rng);
    pid_t pid = spawn(args(d), d + "/../k.out", d + "/../k.err");
    if (k % 2 == 1) {
      for (int i = 0; i < 6000 && !exists(tile_path(d, 0)); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      delay_us /= 2;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(delay_us));
    ::kill(pid, SIGKILL);
    wait_process(pid, d + "/../k.out", d + "/../k.err");
    // Whatever is under an output name is whole and correct.
    std::int64_t valid = 0;
    for (std::int64_t i = 0; i < g.count(); ++i) {
      if (!exists(tile_path(d, i))) continue;
      expect_tile_valid(tile_path(d, i), g, i);
      ++valid;
    }
    temps_left += count_temp_files(d);
    if (valid > 0 && valid < g.count()) ++mid_run;
    // Resume: exactly the missing tiles are rendered, and then every tile is there and correct.
    ProcessResult r = run_process(args(d), d + "/../resume");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    nlohmann::json j = last_json_line(r.out);
    EXPECT_EQ(j["tiles_skipped"], valid);
    EXPECT_EQ(j["tiles_done"], g.count() - valid);
    for (std::int64_t i = 0; i < g.count(); ++i) expect_tile_valid(tile_path(d, i), g, i);
  }
  std::printf(
      "[ farm ] kill -9 at %d random moments over %.0f ms: %d mid-run, %d temp files left behind "
      "(hidden names, never outputs)\n",
      kKills, span_ms, mid_run, temps_left);
  EXPECT_GE(mid_run, kKills / 6);
}

TEST(Processes, SigtermStopsAtATileBoundary) {
  std::string dir = fresh_dir();
  TileGrid g(512, 512, 64);  // 64 tiles, 100 ms each: SIGTERM arrives long before the end
  std::vector<std::string> args = synth(dir + "/t_{index}.exr", "512x512", 64, {"--sleep-ms", "100"});
  pid_t pid = spawn(args, dir + "/../term.out", dir + "/../term.err");
  for (int i = 0; i < 6000 && !exists(tile_path(dir, 1)); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ::kill(pid, SIGTERM);
  ProcessResult r = wait_process(pid, dir + "/../term.out", dir + "/../term.err");
  EXPECT_EQ(r.exit_code, 130) << r.err;
  EXPECT_NE(r.err.find("interrupted by SIGTERM"), std::string::npos) << r.err;
  EXPECT_EQ(count_temp_files(dir), 0);
  std::int64_t present = 0;
  for (std::int64_t i = 0; i < g.count(); ++i) {
    if (exists(tile_path(dir, i))) {
      expect_tile_valid(tile_path(dir, i), g, i);
      ++present;
    }
  }
  EXPECT_LT(present, g.count());
  // The single-image mode removes its temp file too.
  pid = spawn(synth(dir + "/big.exr", "512x512", 64, {"--sleep-ms", "100"}), dir + "/../term.out",
              dir + "/../term.err");
  for (int i = 0; i < 6000 && count_temp_files(dir) == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  ::kill(pid, SIGINT);
  r = wait_process(pid, dir + "/../term.out", dir + "/../term.err");
  EXPECT_EQ(r.exit_code, 130) << r.err;
  EXPECT_FALSE(exists(dir + "/big.exr"));
  EXPECT_EQ(count_temp_files(dir), 0);
}

namespace {

// Mounts a small tmpfs for the test's lifetime; skipped() when this process may not mount.
class SmallTmpfs {
 public:
  SmallTmpfs(const std::string& dir, const std::string& size) : dir_(dir) {
    mounted_ = ::mount("tmpfs", dir.c_str(), "tmpfs", 0, ("size=" + size).c_str()) == 0;
    if (!mounted_) why_ = std::strerror(errno);
  }
  ~SmallTmpfs() {
    if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  bool mounted() const { return mounted_; }
  const std::string& why() const { return why_; }

 private:
  std::string dir_, why_;
  bool mounted_ = false;
};

}  // namespace

TEST(Processes, FullFilesystemIsARetryableCleanFailure) {
  std::string dir = fresh_dir();
  std::string mnt = dir + "/mnt";
  ASSERT_EQ(std::system(("mkdir -p '" + mnt + "'").c_str()), 0);
  SmallTmpfs fs(mnt, "300k");
  if (!fs.mounted())
    GTEST_SKIP() << "cannot mount a tmpfs here (" << fs.why() << "); the fsync fault test covers this";
  // 64x64x3 float tiles uncompressed are ~49 KB: the sixth or so does not fit.
  TileGrid g(512, 512, 64);
  ProcessResult r =
      run_process(synth(mnt + "/t_{index}.exr", "512x512", 64, {"--compression", "none"}), dir + "/a");
  std::printf("[ farm ] full tmpfs: exit %d, message: %s", r.exit_code, r.err.c_str());
  EXPECT_EQ(r.exit_code, 6) << r.err;
  EXPECT_NE(r.err.find(mnt), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("No space left on device"), std::string::npos) << r.err;
  EXPECT_EQ(count_temp_files(mnt), 0);
  std::int64_t present = 0;
  for (std::int64_t i = 0; i < g.count(); ++i) {
    if (exists(tile_path(mnt, i))) {
      expect_tile_valid(tile_path(mnt, i), g, i);
      ++present;
    }
  }
  EXPECT_GT(present, 0);
  EXPECT_LT(present, g.count());
  // One large image that does not fit: same code, no output, no temp file.
  ASSERT_EQ(std::system(("rm -f '" + mnt + "'/*").c_str()), 0);
  r = run_process(synth(mnt + "/big.exr", "1024x1024", 128, {"--compression", "none"}), dir + "/b");
  EXPECT_EQ(r.exit_code, 6) << r.err;
  EXPECT_FALSE(exists(mnt + "/big.exr"));
  EXPECT_EQ(count_temp_files(mnt), 0);
  EXPECT_TRUE(list_dir(mnt).empty());
}

TEST(Processes, FsyncFaultHookIsARetryableCleanFailure) {
  std::string dir = fresh_dir();
  ProcessResult r = run_process(synth(dir + "/t_{index}.exr", "256x256", 64), dir + "/../fault",
                                {"STEX_FARM_FAULT_FSYNC=3"});
  EXPECT_EQ(r.exit_code, 6) << r.err;
  EXPECT_NE(r.err.find("No space left on device"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(tile_path(dir, 2)), std::string::npos) << r.err;
  EXPECT_EQ(list_dir(dir).size(), 2u);  // tiles 0 and 1, nothing else
  EXPECT_EQ(count_temp_files(dir), 0);
  r = run_process(synth(dir + "/big.exr", "256x256", 64), dir + "/../fault", {"STEX_FARM_FAULT_FSYNC=1"});
  EXPECT_EQ(r.exit_code, 6) << r.err;
  EXPECT_FALSE(exists(dir + "/big.exr"));
  EXPECT_EQ(count_temp_files(dir), 0);
}

TEST(Processes, PeakRssOf16384SquaredTiledExrStaysBounded) {
  std::string dir = fresh_dir();
  const std::string out = dir + "/big.exr";
  ProcessResult r =
      run_process(synth(out, "16384x16384", 512, {"--compression", "none", "--json"}), dir + "/rss");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json j = last_json_line(r.out);
  const double rss_mib = double(r.max_rss_kb) / 1024.0;
  std::printf(
      "[ farm ] 16384x16384 RGB float tiled EXR (1024 tiles of 512^2, 3 GiB of pixels): peak RSS %.1f MiB, "
      "%.2f s, %.1f tiles/s, %.1f Mpx/s\n",
      rss_mib, j["seconds"].get<double>(), 1024.0 / j["seconds"].get<double>(),
      j["pixels_per_second"].get<double>() / 1e6);
  EXPECT_LT(rss_mib, 1024.0);
  OutputInspection ins = inspect_output(out, false);
  ASSERT_EQ(ins.state, OutputState::Valid) << ins.problem;
  EXPECT_TRUE(ins.info.tiled);
  EXPECT_EQ(ins.info.width, 16384);
  TileGrid g(16384, 16384, 512);
  for (std::int64_t i : {std::int64_t(0), std::int64_t(517), g.count() - 1}) {
    TileRect t = g.tile(i);
    std::vector<float> want;
    synth_region(11, 3, t.x0, t.y0, t.width, t.height, want);
    EXPECT_EQ(read_output_region(out, t.x0, t.y0, t.width, t.height), want) << "tile " << i;
  }
  std::remove(out.c_str());
}
