// One small model of every kind (texton, lrp, gabor, mix, cs-spot, tb, cs-tb, cs-rpn), made through the `stex`
// binary (tests/cli_run.h) from a 128 x 128 crop of data/gravel.png, as the golden tests make theirs: fast to
// analyse and to render. For the tests that run something against every kind (tests/oiio, tests/cli's option
// matrix). Needs STEX_SOURCE_DIR, STEX_CLI_PATH and STEX_TEST_TMP_DIR (every test area defines them).
//
// The models are made once per `stex` binary and shared by the test binaries: in a directory beside the
// areas' scratch directories named by the binary's size and modification time (a rebuilt `stex` makes new
// ones), built under a temporary name and renamed into place (two binaries running at once both build, one
// rename wins, both use the result).
#pragma once
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "analysis/image_io.h"
#include "cli_run.h"

namespace stex::test {

// The kinds whose renders read --mni and --cell (NoiseModelSummary::poisson) among kind_models().
inline bool kind_model_reads_mni(const std::string& kind) {
  return kind == "texton" || kind == "gabor" || kind == "mix";
}

// kind -> model file, made once per process in STEX_TEST_TMP_DIR/kind_models (throws if a command fails).
inline const std::map<std::string, std::filesystem::path>& kind_models() {
  namespace fs = std::filesystem;
  static const std::map<std::string, fs::path> models = [] {
    const auto stamp = std::to_string(fs::file_size(STEX_CLI_PATH)) + "_" +
                       std::to_string(fs::last_write_time(STEX_CLI_PATH).time_since_epoch().count());
    const fs::path final_dir = fs::path(STEX_TEST_TMP_DIR).parent_path() / ("kind_models_" + stamp);
    const std::vector<std::string> kinds = {"texton", "lrp", "gabor", "mix", "cs-spot", "tb", "cs-tb", "cs-rpn"};
    auto listing = [&](const fs::path& d) {
      std::map<std::string, fs::path> out;
      for (const auto& k : kinds) out[k] = d / (k + ".stex");
      return out;
    };
    if (fs::exists(final_dir / "complete")) return listing(final_dir);
    const fs::path dir = final_dir.string() + ".tmp." + std::to_string(::getpid());
    fs::remove_all(dir);
    fs::create_directories(dir);
    const Image full = load_exemplar((fs::path(STEX_SOURCE_DIR) / "data" / "gravel.png").string());
    Image g;
    g.width = g.height = 128;
    g.channels = full.channels;
    for (int y = 0; y < 128; ++y)
      for (int x = 0; x < 128; ++x)
        for (int c = 0; c < full.channels; ++c) g.pixels.push_back(full.at(x, y, c));
    write_image_atomic((dir / "gravel.png").string(), g);
    // mix's second exemplar: a deterministic grey-blue pattern
    Image b;
    b.width = b.height = 48;
    b.channels = 3;
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 48; ++x)
        for (int c = 0; c < 3; ++c) b.pixels.push_back(0.3f + 0.1f * float(c) + 0.2f * float(((x / 6) ^ (y / 4)) & 1));
    write_image_atomic((dir / "b.png").string(), b);
    std::ofstream(dir / "s.json") << R"({"grid": [3, 1], "size": 64, "spectra": ["bilobe:0.1,0,0.01", )"
                                     R"("bilobe:0.1,60,0.01", "bilobe:0.12,120,0.01"]})";
    const std::vector<std::pair<std::string, std::string>> make = {
        {"texton", "analyze gravel.png -o texton.stex --support 12 --iterations 4"},
        {"lrp", "analyze gravel.png -o lrp.stex --method lrp --cosines 12 --strata 3 --amplitudes paper"},
        {"gabor", "analyze gravel.png -o gabor.stex --method gabor"},
        {"mix", "analyze-mix gravel.png b.png -o mix.stex --levels 3 --support 10 --iterations 5 --seed 2 "
                "--mix-map strips:32:8"},
        {"cs-spot", "analyze gravel.png -o cs-spot.stex --method cs-spot --periods 31.5,2.25,-3,29.75"},
        {"tb", "analyze gravel.png -o tb.stex --method tb"},
        {"cs-tb", "analyze gravel.png -o cs-tb.stex --method cs-tb --periods 32,0,0,32"},
        {"cs-rpn", "cs-rpn -o cs-rpn.stex --periods 71.3,9.2,-6.4,58.7 --spectra s.json --variant random-phase"},
    };
    for (const auto& [kind, args] : make) {
      const CliRun r = run_stex_cli(args, "kind_models_" + kind, dir.string());
      if (r.code != 0) throw std::runtime_error("stex " + args + " failed: " + r.err);
    }
    std::ofstream(dir / "complete") << "made by " << STEX_CLI_PATH << "\n";
    std::error_code ec;
    fs::rename(dir, final_dir, ec);  // fails when another binary's rename came first: use theirs
    if (ec) fs::remove_all(dir, ec);
    return listing(final_dir);
  }();
  return models;
}

}  // namespace stex::test
