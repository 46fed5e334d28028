// Replays every file of fuzz/corpus/<target>/ and fuzz/regressions/<target>/ through the fuzz target's body
// (fuzz/entry_points.h) in the normal build, each target's files in a forked, time- and memory-bounded
// child (isolate.h): a crash found by the fuzzer once and fixed stays fixed. The entry points abort on a
// broken invariant, so a regression shows up as a crash naming the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>

#include "fuzz/entry_points.h"
#include "hardening/isolate.h"

namespace fs = std::filesystem;

namespace {

using Entry = void (*)(const std::uint8_t*, std::size_t);

std::vector<fs::path> inputs_of(const std::string& target) {
  std::vector<fs::path> files;
  for (const char* kind : {"corpus", "regressions"}) {
    fs::path dir = fs::path(STEX_FUZZ_DIR) / kind / target;
    if (!fs::is_directory(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file() && e.path().filename().string()[0] != '.') files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// Runs all inputs of `target`; returns how many were replayed.
std::size_t replay(const std::string& target, Entry entry) {
  const std::vector<fs::path> files = inputs_of(target);
  std::vector<std::uint64_t> ids(files.size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = i;
  auto r = stex::test::run_isolated_batch(ids, [&](std::uint64_t id, const std::function<void(const std::string&)>&) {
    std::ifstream f(files[id], std::ios::binary);
    std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(f)), {});
    entry(bytes.data(), bytes.size());
  });
  for (const auto& failure : r.failures) {
    // "input <id>: ..." -> name the file.
    const std::size_t id = failure.size() > 6 && std::isdigit(static_cast<unsigned char>(failure[6]))
                               ? std::stoul(failure.substr(6))
                               : files.size();
    ADD_FAILURE() << target << ": " << (id < files.size() ? files[id].string() : "?") << " -> " << failure;
  }
  EXPECT_EQ(r.inputs_done, int(files.size()));
  return files.size();
}

}  // namespace

TEST(FuzzRegressions, ModelFile) { EXPECT_GE(replay("model_file", stex::fuzz::model_file_one), 1u); }
TEST(FuzzRegressions, Exemplar) { EXPECT_GE(replay("exemplar", stex::fuzz::exemplar_one), 8u); }
TEST(FuzzRegressions, TileSpec) { EXPECT_GE(replay("tile_spec", stex::fuzz::tile_spec_one), 5u); }
TEST(FuzzRegressions, NameTemplate) { EXPECT_GE(replay("name_template", stex::fuzz::name_template_one), 5u); }
