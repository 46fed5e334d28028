// Golden bits: every model kind and evaluation path, end to end through the `stex` binary (analysis or model
// maker, model file, render), hashed and compared with tests/golden/renders.txt. The table was written before
// the kind-layer redesign (issue 28) and pins what "behaviour unchanged, bits unchanged" means: a refactor that
// changes one bit of a model file or of a render fails here, naming the case and the file.
//
// The bits are the same on every device stex accepts (docs/portability.md), so the table holds on any device.
// Hashes: model files (.stex) byte for byte with the "stex_version" value blanked (a release does not change a
// model); images by their decoded float pixels and shape (an EXR carries its creation time); other files (PLY)
// byte for byte. 16 hex digits of SHA-256 each.
//
// A change that is meant to change bits rewrites the table, and says so in its commit:
//   rm tests/golden/renders.txt && STEX_GOLDEN_WRITE=$PWD/tests/golden/renders.txt build/tests/test_golden
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/image_io.h"
#include "cli_run.h"
#include "core/sha256.h"

namespace fs = std::filesystem;

namespace {

struct GoldenCase {
  std::string name;
  std::vector<std::string> commands;  // stex arguments, run in the case's directory, in order; all must exit 0
  std::vector<std::string> files;     // outputs to hash, relative to the case's directory
};

// Region of every flat render: far from the origin on x, negative on y (both signs of the cell arithmetic).
const std::string k_region = " --size 64x48 --origin 1000003,-77 --seed 5";

const std::vector<GoldenCase>& cases() {
  static const std::vector<GoldenCase> list = {
      {"texton-order1",
       {"analyze gravel.png -o m.stex --support 16 --iterations 5 --seed 3",
        "render m.stex -o splat.exr --strategy splat" + k_region,
        "render m.stex -o gather.exr --strategy gather" + k_region,
        "render m.stex -o local.exr --strategy gather-local" + k_region,
        "render m.stex -o scaled.exr --scale 2.5 --mni 12 --cell 0.9" + k_region,
        "render m.stex -o filtered.exr --scale 0.3 --filter --strategy splat" + k_region,
        "render m.stex -o filtered-gather.exr --scale 0.3 --filter --strategy gather" + k_region,
        "render m.stex -o camera.exr --size 64x48 --camera 60,55,50 --seed 5",
        "render m.stex -o uv.exr --uv-map uv.exr --seed 5"},
       {"m.stex", "splat.exr", "gather.exr", "local.exr", "scaled.exr", "filtered.exr", "filtered-gather.exr",
        "camera.exr", "uv.exr"}},
      {"texton-linear",
       {"analyze gravel.png -o m.stex --support 12 --iterations 4 --linear", "render m.stex -o r.exr" + k_region,
        "render m.stex -o r.png" + k_region},
       {"m.stex", "r.exr", "r.png"}},
      {"texton-sot",
       {"analyze gravel.png -o m.stex --order 0 --support 12 --iterations 4 --mask disc:5",
        "render m.stex -o r.exr" + k_region, "render m.stex -o f.exr --scale 0.25" + k_region},
       {"m.stex", "r.exr", "f.exr"}},
      {"texton-order3",
       {"analyze gravel.png -o m.stex --order 3 --support 8 --iterations 3",
        "render m.stex -o splat.exr --strategy splat" + k_region,
        "render m.stex -o gather.exr --strategy gather" + k_region,
        "render m.stex -o f.exr --scale 0.125" + k_region},
       {"m.stex", "splat.exr", "gather.exr", "f.exr"}},
      {"texton-order5",
       {"analyze gravel.png -o m.stex --order 5 --support 8 --iterations 3", "render m.stex -o r.exr" + k_region},
       {"m.stex", "r.exr"}},
      {"texton-tiles",
       {"analyze gravel.png -o m.stex --support 8 --iterations 3",
        "render m.stex -o 't_{tx}_{ty}.exr' --tile-size 32" + k_region},
       {"t_0_0.exr", "t_1_0.exr", "t_0_1.exr", "t_1_1.exr"}},
      {"lrp",
       {"analyze gravel.png -o m.stex --method lrp --cosines 12 --strata 3 --amplitudes paper", "render m.stex -o r.exr" + k_region,
        "analyze -o p.stex --method lrp --psd ring:0.1,0.02 --psd-size 64 --cosines 8 --amplitudes paper --strata 4",
        "render p.stex -o p.exr --scale 1.5" + k_region},
       {"m.stex", "r.exr", "p.stex", "p.exr"}},
      {"lrp-structure",
       {"analyze gravel.png -o m.stex --method lrp --cosines 8 --structure 0.4 --turbulence 3 --placement "
        "--amplitudes paper --strata 4",
        "render m.stex -o r.exr" + k_region, "render m.stex -o f.exr --scale 0.25" + k_region},
       {"m.stex", "r.exr", "f.exr"}},
      {"gabor",
       {"analyze gravel.png -o m.stex --method gabor", "render m.stex -o r.exr --mni 20" + k_region,
        "gabor -o g.stex", "render g.stex -o g.exr --scale 0.75 --no-filter" + k_region,
        "render g.stex -o gf.exr --scale 0.25" + k_region,  // filtered (docs/filtering.md)
        "renormalize --model g.stex --size 64x48 --origin 40,-7 -o n.exr --L 8"},
       {"m.stex", "r.exr", "g.stex", "g.exr", "gf.exr", "n.exr"}},
      {"mix",
       {"analyze-mix gravel.png b.png -o m.stex --levels 3 --support 10 --iterations 5 --seed 2 "
        "--mix-map strips:32:8",
        "render m.stex -o r.exr" + k_region, "render m.stex -o ramp.exr --mix-map ramp:0:64" + k_region,
        "render m.stex -o f.exr --scale 0.125" + k_region},
       {"m.stex", "r.exr", "ramp.exr", "f.exr"}},
      {"cs-spot",
       {"analyze gravel.png -o m.stex --method cs-spot --periods 31.5,2.25,-3,29.75",
        "render m.stex -o lattice.exr" + k_region, "render m.stex -o general.exr --scale 200" + k_region},
       {"m.stex", "lattice.exr", "general.exr"}},
      {"cs-rpn",
       {"cs-rpn -o rp.stex --periods 71.3,9.2,-6.4,58.7 --spectra s.json --variant random-phase",
        "cs-rpn -o ga.stex --periods 71.3,9.2,-6.4,58.7 --spectra s.json --variant gabor",
        "cs-rpn -o ph.stex --periods 71.3,9.2,-6.4,58.7 --spectra s.json --variant phasor",
        "cs-rpn -o fo.stex --periods 71.3,9.2,-6.4,58.7 --spectra s.json --variant fourier",
        "render rp.stex -o rp.exr" + k_region, "render ga.stex -o ga.exr --mni 16" + k_region,
        "render ph.stex -o ph.exr --mni 16" + k_region, "render fo.stex -o fo.exr" + k_region,
        "render rp.stex -o rpf.exr --scale 0.5" + k_region, "render ga.stex -o gaf.exr --mni 16 --scale 0.5" + k_region,
        "render fo.stex -o fof.exr --scale 0.5" + k_region},  // filtered (docs/filtering.md)
       {"rp.stex", "ga.stex", "ph.stex", "fo.stex", "rp.exr", "ga.exr", "ph.exr", "fo.exr", "rpf.exr", "gaf.exr",
        "fof.exr"}},
      {"tb",
       {"analyze gravel.png -o m.stex --method tb", "render m.stex -o aligned.exr" + k_region,
        "render m.stex -o scaled.exr --scale 0.7" + k_region},
       {"m.stex", "aligned.exr", "scaled.exr"}},
      {"cs-tb",
       {"analyze gravel.png -o a.stex --method cs-tb --periods 32,0,0,32",
        "analyze gravel.png -o s.stex --method cs-tb --periods 31.5,2.25,-3,29.75",
        "render a.stex -o aligned.exr" + k_region, "render s.stex -o subpixel.exr" + k_region,
        "render s.stex -o scaled.exr --scale 1.3" + k_region},
       {"a.stex", "s.stex", "aligned.exr", "subpixel.exr", "scaled.exr"}},
      {"surface",
       {"analyze gravel.png -o m.stex --support 8 --iterations 3",
        "surface m.stex --mesh quad.obj -o out.ply --bake tex.exr --bake-size 32x32 --preview view.png "
        "--preview-size 48x32 --texel 0.05 --mni 20"},
       {"out.ply", "tex.exr", "view.png"}},
  };
  return list;
}

// The inputs every case may use, written into its directory.
void write_inputs(const fs::path& dir) {
  // The exemplar: the top-left 128 x 128 pixels of data/gravel.png (8-bit values survive the round trip).
  const stex::Image full = stex::load_exemplar((fs::path(STEX_SOURCE_DIR) / "data" / "gravel.png").string());
  stex::Image g;
  g.width = g.height = 128;
  g.channels = full.channels;
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x)
      for (int c = 0; c < full.channels; ++c) g.pixels.push_back(full.at(x, y, c));
  stex::write_image_atomic((dir / "gravel.png").string(), g);
  // Mix's second exemplar: a deterministic grey-blue pattern (no RNG involved). PNG, not EXR: the model
  // stores its exemplars' file hashes, and an EXR carries its creation time.
  stex::Image b;
  b.width = b.height = 48;
  b.channels = 3;
  b.pixels.resize(std::size_t(48) * 48 * 3);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 48; ++x)
      for (int c = 0; c < 3; ++c)
        b.pixels[(std::size_t(y) * 48 + x) * 3 + c] = 0.3f + 0.1f * float(c) + 0.2f * float(((x / 6) ^ (y / 4)) & 1);
  stex::write_image_atomic((dir / "b.png").string(), b);
  // A UV map: a sheared, rotating plane over 40 x 30 pixels.
  stex::Image uv;
  uv.width = 40;
  uv.height = 30;
  uv.channels = 2;
  uv.pixels.resize(std::size_t(40) * 30 * 2);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      uv.pixels[(std::size_t(y) * 40 + x) * 2 + 0] = 1000.25f + 1.7f * float(x) + 0.4f * float(y) + 0.01f * float(x * y);
      uv.pixels[(std::size_t(y) * 40 + x) * 2 + 1] = -50.5f - 0.3f * float(x) + 2.1f * float(y);
    }
  stex::write_image_atomic((dir / "uv.exr").string(), uv);
  std::ofstream(dir / "quad.obj") << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                     "f 1/1 2/2 3/3 4/4\n";
  std::ofstream(dir / "s.json") << R"({"grid": [3, 1], "size": 64, "spectra": ["bilobe:0.1,0,0.01", )"
                                   R"({"psd": "bilobe:0.1,60,0.01", "variance": 0.01}, "bilobe:0.12,120,0.01"]})";
}

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

std::string short_hash(const void* data, std::size_t size) { return stex::sha256_hex(data, size).substr(0, 16); }

std::string hash_file(const fs::path& p) {
  const std::string ext = p.extension().string();
  if (ext == ".exr" || ext == ".png" || ext == ".tif") {
    const stex::Image img = ext == ".exr" ? stex::load_float_image(p.string(), "golden output", std::uint64_t(1) << 24)
                                          : stex::load_exemplar(p.string());
    std::string bytes = std::to_string(img.width) + "x" + std::to_string(img.height) + "x" +
                        std::to_string(img.channels) + ":";
    bytes.append(reinterpret_cast<const char*>(img.pixels.data()), img.pixels.size() * sizeof(float));
    return short_hash(bytes.data(), bytes.size());
  }
  std::string bytes = read_bytes(p);
  if (ext == ".stex") {
    const std::string key = "\"stex_version\": \"";
    const std::size_t at = bytes.find(key);
    if (at != std::string::npos) {
      const std::size_t end = bytes.find('"', at + key.size());
      if (end != std::string::npos) bytes.replace(at + key.size(), end - at - key.size(), end - at - key.size(), '.');
    }
  }
  return short_hash(bytes.data(), bytes.size());
}

// "case file hash" per line.
std::map<std::string, std::string> golden_table() {
  std::map<std::string, std::string> table;
  std::ifstream in(fs::path(STEX_SOURCE_DIR) / "tests" / "golden" / "renders.txt");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string name, file, hash;
    if (words >> name >> file >> hash) table[name + " " + file] = hash;
  }
  return table;
}

// gtest prints a failing parameter with this (instead of its bytes).
void PrintTo(const GoldenCase& c, std::ostream* os) { *os << c.name; }

class Golden : public ::testing::TestWithParam<GoldenCase> {};

TEST_P(Golden, BitsMatchTheTable) {
  const GoldenCase& c = GetParam();
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / c.name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_inputs(dir);
  for (const std::string& cmd : c.commands) {
    const stex::test::CliRun r = stex::test::run_stex_cli("-q " + cmd, "run_" + c.name, dir.string());
    ASSERT_EQ(r.code, 0) << "stex " << cmd << "\n" << r.err;
  }
  const char* write = std::getenv("STEX_GOLDEN_WRITE");
  const std::map<std::string, std::string> table = golden_table();
  for (const std::string& f : c.files) {
    ASSERT_TRUE(fs::exists(dir / f)) << c.name << ": no output " << f;
    const std::string got = hash_file(dir / f);
    if (write && *write) {
      std::ofstream(write, std::ios::app) << c.name << " " << f << " " << got << "\n";
      continue;
    }
    const auto it = table.find(c.name + " " + f);
    ASSERT_NE(it, table.end()) << c.name << " " << f << ": not in tests/golden/renders.txt (got " << got << ")";
    EXPECT_EQ(got, it->second) << c.name << " " << f << ": the bits changed";
  }
}

INSTANTIATE_TEST_SUITE_P(AllKinds, Golden, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<GoldenCase>& info) {
                           std::string n = info.param.name;
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

}  // namespace
