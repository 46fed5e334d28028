// `stex bench` as a real subprocess on a tiny configuration: the JSON, CSV, SVG and Markdown reports are
// written, agree with each other, carry every requested point and baseline with internally consistent
// figures (fps = 1000 / ms, Mpixel/s = pixels / ms / 1000, the default's own ratio 1, the goals computed
// from the measured ratios; cs-spot's row on its smaller frame with a per-pixel ratio, reported as a note, no
// goal), and bad options are usage errors. Speed itself is never asserted here
// (benchmarks report it, docs/benchmarks.md).
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include "cli_run.h"

namespace fs = std::filesystem;

namespace {

std::string dir() {
  static const std::string d = [] {
    std::string p = std::string(STEX_TEST_TMP_DIR) + "/bench_cli";
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
  }();
  return d;
}

std::string slurp(const std::string& path) { return stex::test::slurp_file(path); }

using BenchRun = stex::test::CliRun;

// prefix: a command the CLI runs under (env, taskset), empty for none.
BenchRun run_cli(const std::string& args, const std::string& prefix = "") {
  return stex::test::run_stex_cli(args, "bench_cli/run", "", prefix);
}

}  // namespace

TEST(BenchCli, TinyRunWritesConsistentReports) {
  const std::string d = dir();
  const BenchRun r = run_cli("bench --exemplar '" + std::string(STEX_SOURCE_DIR) +
                     "/data/gravel.png' --size 512x512 --support 16 --mni 4,30 --compare splat,s1,omp,tb,cs-tb,cs-spot "
                     "--repeat 1 --budget-ms 50 --no-table1 --json '" + d + "/b.json' --csv '" + d +
                     "/b.csv' --svg '" + d + "/b.svg' --markdown '" + d + "/b.md'");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(slurp(d + "/b.json"));
  EXPECT_GT(j["peak"]["gflops_fma"].get<double>(), 0.0);
  ASSERT_EQ(j["textons"].size(), 1u);
  EXPECT_EQ(j["textons"][0]["support"], 16);
  EXPECT_GT(j["textons"][0]["rme"].get<double>(), 0.0);
  ASSERT_EQ(j["points"].size(), 2u);
  int rows = 0;
  double tb_vs_texton = -1.0, cs_spot_vs_texton = -1.0;
  for (const auto& p : j["points"]) {
    EXPECT_EQ(p["width"], 512);
    EXPECT_EQ(p["height"], 512);
    const double mni = p["mni"].get<double>();
    std::vector<std::string> strategies;
    for (const auto& m : p["results"]) {
      ++rows;
      strategies.push_back(m["strategy"].get<std::string>());
      ASSERT_TRUE(m["ok"].get<bool>()) << m.dump();
      const double ms = m["ms"].get<double>();
      ASSERT_GT(ms, 0.0);
      EXPECT_NEAR(m["fps"].get<double>(), 1000.0 / ms, 1e-6 * 1000.0 / ms);
      // Mpixel/s of the frame the row measured: the point's, except cs-spot's (at most 256 a side).
      const double fw = m["frame_width"].get<double>(), fh = m["frame_height"].get<double>();
      if (m["strategy"] == "cs-spot") {
        EXPECT_EQ(fw, 256.0);
        EXPECT_EQ(fh, 256.0);
      } else {
        EXPECT_EQ(fw, 512.0);
        EXPECT_EQ(fh, 512.0);
      }
      EXPECT_NEAR(m["mpixel_per_s"].get<double>(), fw * fh / (ms * 1000.0), 1e-6 * fw * fh / ms);
      if (m["strategy"] == "stex") {
        EXPECT_DOUBLE_EQ(m["time_vs_default"].get<double>(), 1.0);
        // Excess kurtosis of a texton noise render is positive (shot noise, S1 Prop. 1) and finite.
        EXPECT_TRUE(m["excess_kurtosis"].is_number());
        EXPECT_TRUE(m["spectrum_error"].is_number());
      }
    }
    EXPECT_EQ(strategies.front(), "stex");
    // Baselines run at MNI 30 only (the default --compare-mni).
    const bool baselines = std::find(strategies.begin(), strategies.end(), "s1") != strategies.end();
    EXPECT_EQ(baselines, std::fabs(mni - 30.0) < 1e-9) << "MNI " << mni;
    if (baselines) {
      EXPECT_NE(std::find(strategies.begin(), strategies.end(), "omp"), strategies.end());
      EXPECT_NE(std::find(strategies.begin(), strategies.end(), "splat"), strategies.end());
      EXPECT_NE(std::find(strategies.begin(), strategies.end(), "cs-tb"), strategies.end());
      EXPECT_NE(std::find(strategies.begin(), strategies.end(), "cs-spot"), strategies.end());
      for (const auto& m : p["results"]) {
        if (m["strategy"] == "tb") tb_vs_texton = m["time_vs_default"].get<double>();
        if (m["strategy"] == "cs-spot") {
          // Paired with the default's runs on the full 512^2 frame: the ratio is per pixel,
          // (ms / 256^2) / (paired default ms / 512^2), and the note says so.
          ASSERT_TRUE(m["default_ms_paired"].is_number()) << m.dump();
          // The minima of the same runs: positive and never above the medians.
          ASSERT_TRUE(m["ms_min"].is_number() && m["default_ms_paired_min"].is_number()) << m.dump();
          EXPECT_GT(m["ms_min"].get<double>(), 0.0);
          EXPECT_LE(m["ms_min"].get<double>(), m["ms"].get<double>());
          EXPECT_LE(m["default_ms_paired_min"].get<double>(), m["default_ms_paired"].get<double>());
          const double per_pixel = (m["ms"].get<double>() / (256.0 * 256.0)) /
                                   (m["default_ms_paired"].get<double>() / (512.0 * 512.0));
          cs_spot_vs_texton = m["time_vs_default"].get<double>();
          EXPECT_NEAR(cs_spot_vs_texton, per_pixel, 1e-9 * per_pixel);
          EXPECT_NE(m["note"].get<std::string>().find("256x256 frame"), std::string::npos) << m.dump();
        }
      }
    }
  }
  // The four goals, each computed from this run's ratios; the tiling-and-blending one (issue #8) is the tb
  // row's ratio to the texton default of its point (the only point with baselines here).
  ASSERT_EQ(j["goals"].size(), 4u);  // cs-spot has no goal (issue #8 states none): a note reports its ratio
  ASSERT_GT(cs_spot_vs_texton, 0.0);
  bool cs_note = false;
  for (const auto& n : j["notes"])
    if (n.get<std::string>().find("cs spot noise") != std::string::npos) {
      cs_note = true;
      char ratio[32];
      std::snprintf(ratio, sizeof ratio, "%.3g", cs_spot_vs_texton);
      EXPECT_NE(n.get<std::string>().find(std::string(ratio) + "x per pixel (256x256 frame)"), std::string::npos)
          << n << " vs " << ratio;
    }
  EXPECT_TRUE(cs_note) << j["notes"].dump();
  ASSERT_GT(tb_vs_texton, 0.0);
  EXPECT_NEAR(j["goals"][3]["value"].get<double>(), tb_vs_texton, 1e-9 * tb_vs_texton);
  EXPECT_EQ(j["goals"][3]["met"].get<bool>(), tb_vs_texton <= 0.3);
  for (const auto& g : j["goals"]) {
    EXPECT_FALSE(g["name"].get<std::string>().empty());
    EXPECT_GT(g["value"].get<double>(), 0.0) << g.dump();
    EXPECT_NE(g["detail"].get<std::string>().find("512^2"), std::string::npos) << g.dump();
  }
  // CSV: a header and one row per (point, strategy).
  std::istringstream csv(slurp(d + "/b.csv"));
  std::string line;
  int lines = 0;
  std::getline(csv, line);
  EXPECT_EQ(line.rfind("width,height,support,mni,strategy,ok,ms", 0), 0u) << line;
  EXPECT_NE(line.find(",frame_width,frame_height"), std::string::npos) << line;
  int cs_rows = 0;
  while (std::getline(csv, line))
    if (!line.empty()) {
      ++lines;
      if (line.find(",cs-spot,") != std::string::npos) {
        ++cs_rows;
        EXPECT_EQ(line.substr(line.size() - 8), ",256,256") << line;
      }
    }
  EXPECT_EQ(cs_rows, 1);
  EXPECT_EQ(lines, rows);
  const std::string svg = slurp(d + "/b.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_NE(slurp(d + "/b.md").find("Goals"), std::string::npos);
  EXPECT_NE(r.out.find("Goals (issue #5; issue #8"), std::string::npos) << r.out;
}

// `--compare cs-rpn` measures the four cs-rpn variants (issue #8) on a frame of at most 256 a side (here
// 256 x 200 of a 320 x 200 point): per-pixel ratios against the default's paired runs, a note each, no goal.
TEST(BenchCli, CsRpnVariantsAreMeasuredOnTheirFrame) {
  const std::string d = dir();
  const BenchRun r = run_cli("bench --exemplar '" + std::string(STEX_SOURCE_DIR) +
                          "/data/gravel.png' --size 320x200 --support 16 --mni 4 --compare-mni 4 --compare cs-rpn "
                          "--repeat 1 --budget-ms 50 --no-table1 --no-quality --json '" + d + "/r.json'");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(slurp(d + "/r.json"));
  ASSERT_EQ(j["points"].size(), 1u);
  const auto& results = j["points"][0]["results"];
  ASSERT_EQ(results.size(), 5u) << results.dump();
  const char* keys[] = {"cs-rpn-random-phase", "cs-rpn-gabor", "cs-rpn-phasor", "cs-rpn-fourier"};
  for (int v = 0; v < 4; ++v) {
    const auto& m = results[std::size_t(v) + 1];
    EXPECT_EQ(m["strategy"], keys[v]);
    ASSERT_TRUE(m["ok"].get<bool>()) << m.dump();
    EXPECT_EQ(m["frame_width"], 256);
    EXPECT_EQ(m["frame_height"], 200);
    ASSERT_TRUE(m["default_ms_paired"].is_number()) << m.dump();
    const double per_pixel = (m["ms"].get<double>() / (256.0 * 200.0)) /
                             (m["default_ms_paired"].get<double>() / (320.0 * 200.0));
    EXPECT_NEAR(m["time_vs_default"].get<double>(), per_pixel, 1e-9 * per_pixel);
    const std::string note = m["note"].get<std::string>();
    EXPECT_NE(note.find("256x200 frame"), std::string::npos) << note;
    EXPECT_EQ(note.rfind(std::string("variant ") + (keys[v] + 7) + ",", 0), 0u) << note;  // the model's variant
    EXPECT_NE(note.find(v == 1 || v == 2 ? "depends on MNI" : "does not depend on MNI"), std::string::npos) << note;
  }
  int notes = 0;
  for (const auto& n : j["notes"])
    if (n.get<std::string>().find("cs-rpn ") != std::string::npos) {
      ++notes;
      EXPECT_NE(n.get<std::string>().find("x per pixel (256x200 frame)"), std::string::npos) << n;
    }
  EXPECT_EQ(notes, 4) << j["notes"].dump();
  ASSERT_EQ(j["goals"].size(), 4u);  // no goal of their own
}

TEST(BenchCli, BadOptionsAreUsageErrors) {
  BenchRun r = run_cli("bench --mni 0 --size 64 --support 16 --no-table1");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("mni"), std::string::npos) << r.err;
  r = run_cli("bench --repeat 0 --size 64 --support 16");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--repeat"), std::string::npos) << r.err;
  r = run_cli("bench --compare nonsense --size 64 --support 16");
  EXPECT_EQ(r.code, 2) << r.err;
  r = run_cli("bench --compare cs-rpn-nonsense --size 64 --support 16");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("cs-rpn-gabor"), std::string::npos) << r.err;
}

// Worker pinning (benchmarks/lib/worker_affinity.h): by default `stex bench` sets POCL_AFFINITY=1, so that PoCL's
// workers (one per compute unit) and the OpenMP baseline's pool threads each run on one CPU, and reports it;
// the environment's POCL_AFFINITY wins; --no-pin leaves every thread free; a process that may not use CPUs
// 0..N-1 is left unpinned (PoCL would abort pinning a worker outside its CPU set) and the report says why.
TEST(BenchCli, PinsWorkerThreadsUnlessToldNot) {
  const long online = sysconf(_SC_NPROCESSORS_ONLN);
  cpu_set_t mine;
  CPU_ZERO(&mine);
  ASSERT_EQ(sched_getaffinity(0, sizeof(mine), &mine), 0);
  bool full = online >= 2;
  for (long c = 0; c < online && full; ++c) full = CPU_ISSET(int(c), &mine);
  if (!full) GTEST_SKIP() << "this test process may not use every CPU (or there is one): the default cannot pin";
  const std::string d = dir();
  const std::string args = "bench --exemplar '" + std::string(STEX_SOURCE_DIR) +
                           "/data/gravel.png' --size 64x64 --support 16 --mni 30 --compare omp --repeat 1 "
                           "--budget-ms 10 --no-table1 --no-quality --json '" + d + "/pin.json'";
  auto affinity = [&](const BenchRun& r) {
    EXPECT_EQ(r.code, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(slurp(d + "/pin.json"));
    return std::make_pair(j["machine"], j["machine"]["worker_affinity"]);
  };
  {  // default: pinned by stex bench
    BenchRun r = run_cli(args, "env -u POCL_AFFINITY");
    const auto [m, w] = affinity(r);
    EXPECT_EQ(w["source"], "stex bench") << w.dump();
    EXPECT_EQ(w["pocl_affinity"], "1") << w.dump();
    EXPECT_TRUE(w["openmp_pinned"].get<bool>()) << w.dump();
    // PoCL's workers (one per compute unit) plus the OpenMP pool's threads t > 0 are bound to one CPU each.
    int expect = int(online) - 1;
    if (m["platform"].get<std::string>().find("Portable Computing Language") != std::string::npos &&
        m["device_type"] == "CPU")
      expect += m["compute_units"].get<int>();
    EXPECT_GE(w["pinned_threads"].get<int>(), expect) << w.dump();
    EXPECT_NE(r.out.find("Worker threads: POCL_AFFINITY=1 (set by stex bench"), std::string::npos) << r.out;
  }
  {  // --no-pin: no thread of the process is bound to one CPU
    const auto [m, w] = affinity(run_cli(args + " --no-pin", "env -u POCL_AFFINITY"));
    EXPECT_EQ(w["source"], "not set") << w.dump();
    EXPECT_TRUE(w["pocl_affinity"].is_null()) << w.dump();
    EXPECT_EQ(w["note"], "--no-pin") << w.dump();
    EXPECT_FALSE(w["openmp_pinned"].get<bool>()) << w.dump();
    EXPECT_EQ(w["pinned_threads"].get<int>(), 0) << w.dump();
  }
  {  // the user's value wins
    const auto [m, w] = affinity(run_cli(args, "env POCL_AFFINITY=0"));
    EXPECT_EQ(w["source"], "environment") << w.dump();
    EXPECT_EQ(w["pocl_affinity"], "0") << w.dump();
    EXPECT_FALSE(w["openmp_pinned"].get<bool>()) << w.dump();
    EXPECT_EQ(w["pinned_threads"].get<int>(), 0) << w.dump();
  }
  {  // a CPU set without CPU 0: left unpinned, said why, and the run still completes
    const auto [m, w] = affinity(run_cli(args, "env -u POCL_AFFINITY taskset -c " + std::to_string(online - 1)));
    EXPECT_EQ(w["source"], "not set") << w.dump();
    EXPECT_NE(w["note"].get<std::string>().find("CPU set"), std::string::npos) << w.dump();
    EXPECT_EQ(w["pinned_threads"].get<int>(), -1) << w.dump();
  }
}
