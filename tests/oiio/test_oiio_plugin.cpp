// stex.imageio.so (oiio/, docs/oiio-plugin.md): models of every kind read as images by OpenImageIO, against
// `stex render` bit for bit. In-process tests load the plugin from STEX_IMAGEIO_DIR through OIIO's plugin
// search path; OiioTools.* run oiiotool and maketx (Debian's openimageio-tools) as a user would (normal tree
// only: those host programs are not built with the sanitizer runtime the sanitizer tree's plugin needs).
#include <OpenImageIO/imagecache.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "analysis/image_io.h"
#include "cli_run.h"
#include "kind_models.h"
#include "core/error.h"
#include "oiio/region_options.h"

namespace fs = std::filesystem;
using stex::oiio::parse_region_options;
using stex::oiio::RegionOptions;

namespace {

// The plugin directory, set before OIIO catalogues its plugins (the first ImageInput of the process).
const bool k_plugin_path_set = [] {
  OIIO::attribute("plugin_searchpath", std::string(STEX_IMAGEIO_DIR));
  return true;
}();

fs::path tmp(const std::string& name) {
  const fs::path p = fs::path(STEX_TEST_TMP_DIR) / name;
  fs::create_directories(p);
  return p;
}

void run_ok(const std::string& args, const fs::path& dir) {
  const auto r = stex::test::run_stex_cli(args, "cli_" + dir.filename().string(), dir.string());
  ASSERT_EQ(r.code, 0) << "stex " << args << "\n" << r.err;
}

const std::map<std::string, fs::path>& models() { return stex::test::kind_models(); }

struct Pixels {
  int width = 0, height = 0, channels = 0;
  std::vector<float> v;
};

// A file's pixels as float, read by OIIO (EXR from `stex render`, or anything the plugin serves).
Pixels read_image(const std::string& name, int miplevel = 0) {
  auto in = OIIO::ImageInput::open(name);
  if (!in) throw std::runtime_error("cannot open " + name + ": " + OIIO::geterror());
  Pixels p;
  if (miplevel > 0 && !in->seek_subimage(0, miplevel)) throw std::runtime_error("no MIP level in " + name);
  const OIIO::ImageSpec& s = in->spec();
  p.width = s.width;
  p.height = s.height;
  p.channels = s.nchannels;
  p.v.resize(std::size_t(s.width) * s.height * s.nchannels);
  if (!in->read_image(0, miplevel, 0, s.nchannels, OIIO::TypeDesc::FLOAT, p.v.data()))
    throw std::runtime_error("cannot read " + name + ": " + in->geterror());
  return p;
}

// Bit-for-bit equality of two float images, with the first differing value in the message.
::testing::AssertionResult same_bits(const Pixels& a, const Pixels& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels)
    return ::testing::AssertionFailure() << "shapes differ: " << a.width << "x" << a.height << "x" << a.channels
                                         << " vs " << b.width << "x" << b.height << "x" << b.channels;
  for (std::size_t i = 0; i < a.v.size(); ++i)
    if (std::memcmp(&a.v[i], &b.v[i], sizeof(float)) != 0)
      return ::testing::AssertionFailure() << "value " << i << " (pixel " << i / a.channels % a.width << ", "
                                           << i / a.channels / a.width << ") differs: " << a.v[i] << " vs " << b.v[i];
  return ::testing::AssertionSuccess();
}

std::string shell_quote(const std::string& s) { return "'" + s + "'"; }

int run_shell(const std::string& cmd) {
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128;
}

// ---------------------------------------------------------------------------------------------------------
// The options in the name.

TEST(RegionOptions, DefaultsAreA4096RegionAtTheOriginIn256Tiles) {
  const RegionOptions o = parse_region_options("dir/m.stex");
  EXPECT_EQ(o.path, "dir/m.stex");
  EXPECT_EQ(o.width, 4096);
  EXPECT_EQ(o.height, 4096);
  EXPECT_EQ(o.x, 0);
  EXPECT_EQ(o.y, 0);
  EXPECT_EQ(o.tile, 256);
  EXPECT_FALSE(o.mip);
  EXPECT_TRUE(o.filter);
  EXPECT_EQ(o.params, stex::RenderParams{});
}

TEST(RegionOptions, EveryKeyIsRead) {
  const RegionOptions o = parse_region_options(
      "m.stex?RES=640x480&origin=1000000000000,-77&SEED=18446744073709551615&MNI=12.5&CELL=0.8&SCALE=0.25&TILE=64&"
      "MIP=1&FILTER=0&STRATEGY=gather");
  EXPECT_EQ(o.path, "m.stex");
  EXPECT_EQ(o.width, 640);
  EXPECT_EQ(o.height, 480);
  EXPECT_EQ(o.x, 1000000000000);
  EXPECT_EQ(o.y, -77);
  EXPECT_EQ(o.params.seed, 18446744073709551615ull);
  EXPECT_EQ(o.params.mni, 12.5);
  EXPECT_EQ(o.params.cell_factor, 0.8);
  EXPECT_EQ(o.params.scale, 0.25);
  EXPECT_EQ(o.tile, 64);
  EXPECT_TRUE(o.mip);
  EXPECT_FALSE(o.filter);
  EXPECT_EQ(o.strategy, "gather");
}

TEST(RegionOptions, BadOptionsNameTheOption) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"m.stex?RES=0x10", "RES"},           {"m.stex?RES=10", "RES"},
      {"m.stex?RES=2000000x10", "RES"},     {"m.stex?ORIGIN=1,2,3", "ORIGIN"},
      {"m.stex?ORIGIN=x,2", "ORIGIN"},      {"m.stex?SEED=-1", "SEED"},
      {"m.stex?MNI=0", "MNI"},              {"m.stex?MNI=nan", "MNI"},
      {"m.stex?CELL=5", "CELL"},            {"m.stex?SCALE=0", "SCALE"},
      {"m.stex?TILE=4", "TILE"},            {"m.stex?TILE=64.5", "TILE"},
      {"m.stex?MIP=yes", "MIP"},            {"m.stex?FILTER=2", "FILTER"},
      {"m.stex?SEDE=3", "SEDE"},            {"m.stex?SEED=1&SEED=2", "SEED"},
      {"m.stex?RES", "RES"},                {"?RES=1x1", "no model file"},
      {"m.stex?ORIGIN=70368744177000,0&RES=1000x1", "ORIGIN"},
  };
  for (const auto& [name, what] : bad) {
    try {
      parse_region_options(name);
      ADD_FAILURE() << name << " was accepted";
    } catch (const stex::Error& e) {
      EXPECT_EQ(e.kind(), stex::ErrorKind::Usage) << name;
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << name << ": " << e.what();
    }
  }
}

// ---------------------------------------------------------------------------------------------------------
// Every kind through OIIO, in process.

// The region of the every-kind tests; MNI 16 for the kinds that read it (the others refuse it).
bool poisson_kind(const std::string& kind) { return stex::test::kind_model_reads_mni(kind); }
std::string region_of(const std::string& kind) {
  return std::string("RES=96x80&ORIGIN=1000000000000,-77&SEED=5&TILE=32") + (poisson_kind(kind) ? "&MNI=16" : "");
}
std::string render_of(const std::string& kind) {
  return std::string("--size 96x80 --origin 1000000000000,-77 --seed 5") + (poisson_kind(kind) ? " --mni 16" : "");
}

TEST(OiioPlugin, EveryKindReadsTheBitsOfStexRender) {
  const fs::path dir = tmp("every_kind");
  for (const auto& [kind, model] : models()) {
    SCOPED_TRACE(kind);
    run_ok("render " + shell_quote(model.string()) + " -o " + kind + ".exr " + render_of(kind), dir);
    const Pixels cli = read_image((dir / (kind + ".exr")).string());
    const Pixels plugin = read_image(model.string() + "?" + region_of(kind));
    EXPECT_TRUE(same_bits(plugin, cli));
    auto in = OIIO::ImageInput::open(model.string() + "?" + region_of(kind));
    ASSERT_TRUE(in);
    EXPECT_STREQ(in->format_name(), "stex");
    EXPECT_EQ(in->spec().tile_width, 32);
    EXPECT_EQ(in->spec().get_string_attribute("stex:kind"), kind);
    EXPECT_EQ(in->spec().get_string_attribute("stex:origin"), "1000000000000,-77");
    EXPECT_EQ(in->spec().get_string_attribute("stex:seed"), "5");
    EXPECT_EQ(in->spec().get_string_attribute("stex:model_sha256").size(), 64u);
  }
}

// MIP levels: texton models of order 1 are S1 §5's filtered renders (`stex render --scale 2^-k --filter`) of
// the same realisation, gabor and lrp their own filtered renders, other kinds the box mean of level 0's pixels.
TEST(OiioPlugin, MipLevelsAreFilteredRendersOfTheSameRealisation) {
  const fs::path dir = tmp("mip");
  const std::string name = models().at("texton").string() + "?RES=200x136&ORIGIN=4096,-8192&SEED=9&TILE=32&MIP=1";
  auto in = OIIO::ImageInput::open(name);
  ASSERT_TRUE(in) << OIIO::geterror();
  int levels = 0;
  while (in->seek_subimage(0, levels)) ++levels;
  EXPECT_EQ(levels, 8);  // 200 -> 100, 50, 25, 12, 6, 3, 1
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(k);
    const int w = std::max(1, 200 >> k), h = std::max(1, 136 >> k);
    const std::string scale = k == 0 ? "" : " --filter --scale " + std::to_string(1.0 / double(1 << k));
    run_ok("render " + shell_quote(models().at("texton").string()) + " -o l" + std::to_string(k) + ".exr --size " +
               std::to_string(w) + "x" + std::to_string(h) + " --origin " + std::to_string(4096 >> k) + "," +
               std::to_string(-(8192 >> k)) + " --seed 9" + scale,
           dir);
    const Pixels cli = read_image((dir / ("l" + std::to_string(k) + ".exr")).string());
    EXPECT_TRUE(same_bits(read_image(name, k), cli));
    ASSERT_TRUE(in->seek_subimage(0, k));
    EXPECT_EQ(in->spec().get_string_attribute("stex:filter"), k == 0 ? "none" : "box-prefilter");
  }

  // lrp (filtered in closed form, docs/filtering.md): level k is `stex render --scale 2^-k`, filtered.
  const std::string fname = models().at("lrp").string() + "?RES=64x48&ORIGIN=-96,32&SEED=4&TILE=16&MIP=1";
  for (int k = 1; k <= 2; ++k) {
    SCOPED_TRACE(k);
    run_ok("render " + shell_quote(models().at("lrp").string()) + " -o lrpf.exr --size " + std::to_string(64 >> k) +
               "x" + std::to_string(48 >> k) + " --origin " + std::to_string(-96 >> k) + "," +
               std::to_string(32 >> k) + " --seed 4 --scale " + std::to_string(1.0 / double(1 << k)),
           dir);
    EXPECT_TRUE(same_bits(read_image(fname, k), read_image((dir / "lrpf.exr").string())));
    auto fin = OIIO::ImageInput::open(fname);
    ASSERT_TRUE(fin && fin->seek_subimage(0, k));
    EXPECT_EQ(fin->spec().get_string_attribute("stex:filter"), "gaussian-footprint");
  }

  // tb (no filter yet): level k is the mean of the 2^k x 2^k level-0 pixels under each pixel, summed in double.
  const std::string lname = models().at("tb").string() + "?RES=64x48&ORIGIN=-96,32&SEED=4&TILE=16&MIP=1";
  const Pixels l0 = read_image(lname, 0);
  run_ok("render " + shell_quote(models().at("tb").string()) + " -o lrp0.exr --size 64x48 --origin -96,32 --seed 4",
         dir);
  EXPECT_TRUE(same_bits(l0, read_image((dir / "lrp0.exr").string())));
  for (int k = 1; k <= 3; ++k) {
    SCOPED_TRACE(k);
    const Pixels lk = read_image(lname, k);
    Pixels box;
    box.width = 64 >> k;
    box.height = 48 >> k;
    box.channels = l0.channels;
    for (int y = 0; y < box.height; ++y)
      for (int x = 0; x < box.width; ++x)
        for (int c = 0; c < l0.channels; ++c) {
          double sum = 0.0;
          for (int j = 0; j < (1 << k); ++j)
            for (int i = 0; i < (1 << k); ++i)
              sum += l0.v[(std::size_t((y << k) + j) * 64 + std::size_t((x << k) + i)) * l0.channels + c];
          box.v.push_back(float(sum / double(1 << (2 * k))));
        }
    EXPECT_TRUE(same_bits(lk, box));
  }
}

// A missing, damaged or foreign model, bad options and oversized regions: ImageInput errors with stex's
// message, never an exception or a crash in the host.
TEST(OiioPlugin, ErrorsComeThroughOiio) {
  const fs::path dir = tmp("errors");
  const std::string model = models().at("texton").string();
  std::string bytes;
  {
    std::ifstream f(model, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(f), {});
  }
  std::ofstream(dir / "truncated.stex", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  std::string flipped = bytes;
  flipped[flipped.size() - 9] = char(flipped[flipped.size() - 9] ^ 0x40);
  std::ofstream(dir / "flipped.stex", std::ios::binary) << flipped;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {(dir / "missing.stex").string() + "?RES=64x64", "missing.stex"},
      {(dir / "truncated.stex").string() + "?RES=64x64", "truncated.stex"},
      {(dir / "flipped.stex").string() + "?RES=64x64", "flipped.stex"},
      {model + "?RES=64x64&TILE=3", "TILE"},
      {model + "?RES=64x64&COLOUR=1", "COLOUR"},
      {model + "?RES=1048577x16", "RES"},
      {models().at("tb").string() + "?RES=65536x65536&TILE=4096&MIP=1", "MIP level"},
      {models().at("lrp").string() + "?RES=64x64&MNI=5", "MNI does not apply to a lrp model"},
  };
  for (const auto& [name, what] : cases) {
    SCOPED_TRACE(name);
    auto in = OIIO::ImageInput::open(name);
    EXPECT_FALSE(in);
    const std::string err = OIIO::geterror();
    EXPECT_NE(err.find("stex: "), std::string::npos) << err;
    EXPECT_NE(err.find(what), std::string::npos) << err;
  }
  // Through the image cache too (a texture system's path).
  auto* cache = OIIO::ImageCache::create(/*shared=*/false);
  float px[4] = {};
  EXPECT_FALSE(cache->get_pixels(OIIO::ustring((dir / "truncated.stex").string() + "?RES=64x64"), 0, 0, 0, 1, 0, 1, 0,
                                 1, OIIO::TypeDesc::FLOAT, px));
  EXPECT_NE(cache->geterror().find("truncated.stex"), std::string::npos);
  OIIO::ImageCache::destroy(cache);
}

// OIIO's image cache reads tiles from many threads: 8 threads read 10^4 random tiles of levels 0..2 through a
// small cache (tiles are evicted and rendered again) and compare each with `stex render`'s region.
TEST(OiioPlugin, TenThousandRandomTilesFromEightThreads) {
  const fs::path dir = tmp("threads");
  const std::string model = models().at("texton").string();
  const int side = 1024, tile = 64;
  const std::string name = model + "?RES=1024x1024&ORIGIN=-512,2048&SEED=11&TILE=64&MIP=1";
  std::vector<Pixels> ref;
  for (int k = 0; k < 3; ++k) {
    const std::string scale = k == 0 ? "" : " --filter --scale " + std::to_string(1.0 / double(1 << k));
    const int s = side >> k;
    run_ok("render " + shell_quote(model) + " -o r" + std::to_string(k) + ".exr --size " + std::to_string(s) + "x" +
               std::to_string(s) + " --origin " + std::to_string(-512 >> k) + "," + std::to_string(2048 >> k) +
               " --seed 11" + scale,
           dir);
    ref.push_back(read_image((dir / ("r" + std::to_string(k) + ".exr")).string()));
  }
  auto* cache = OIIO::ImageCache::create(/*shared=*/false);
  cache->attribute("max_memory_MB", 2.0f);  // levels 0..2 hold 5.3 MB of float tiles
  std::atomic<int> failures{0}, reads{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&, t] {
      std::mt19937 rng(1234u + unsigned(t));
      std::vector<float> buf(std::size_t(tile) * tile);
      for (int n = 0; n < 1250; ++n) {
        const int k = int(rng() % 3u), tiles = (side >> k) / tile;
        const int tx = int(rng() % unsigned(tiles)) * tile, ty = int(rng() % unsigned(tiles)) * tile;
        if (!cache->get_pixels(OIIO::ustring(name), 0, k, tx, tx + tile, ty, ty + tile, 0, 1, OIIO::TypeDesc::FLOAT,
                               buf.data())) {
          ++failures;
          continue;
        }
        ++reads;
        const Pixels& r = ref[std::size_t(k)];
        for (int j = 0; j < tile; ++j)
          if (std::memcmp(buf.data() + std::size_t(j) * tile, r.v.data() + std::size_t(ty + j) * r.width + tx,
                          sizeof(float) * tile) != 0) {
            ++failures;
            break;
          }
      }
    });
  for (auto& th : threads) th.join();
  EXPECT_EQ(failures.load(), 0) << cache->geterror();
  EXPECT_EQ(reads.load(), 10000);
  OIIO::ImageCache::destroy(cache);
}

// ---------------------------------------------------------------------------------------------------------
// The OIIO tools, as a user runs them (OIIO_LIBRARY_PATH names the plugin's directory).

std::string oiio_env() { return "OIIO_LIBRARY_PATH=" + shell_quote(STEX_IMAGEIO_DIR) + " "; }

TEST(OiioTools, OiiotoolReadsEveryKindAndCutsAFarRegion) {
  const fs::path dir = tmp("oiiotool");
  for (const auto& [kind, model] : models()) {
    SCOPED_TRACE(kind);
    const std::string in = shell_quote(model.string() + "?" + region_of(kind));
    ASSERT_EQ(run_shell(oiio_env() + "oiiotool " + in + " -d float -o " + shell_quote((dir / (kind + ".exr")).string())),
              0);
    ASSERT_EQ(run_shell(oiio_env() + "oiiotool " + in + " --cut 40x24+50+30 -d float -o " +
                        shell_quote((dir / (kind + "_cut.exr")).string())),
              0);
    run_ok("render " + shell_quote(model.string()) + " -o " + kind + "_cli.exr " + render_of(kind), dir);
    run_ok("render " + shell_quote(model.string()) + " -o " + kind +
               "_cli_cut.exr --size 40x24 --origin 1000000000050,-47 --seed 5" + (poisson_kind(kind) ? " --mni 16" : ""),
           dir);
    EXPECT_TRUE(same_bits(read_image((dir / (kind + ".exr")).string()), read_image((dir / (kind + "_cli.exr")).string())));
    EXPECT_TRUE(same_bits(read_image((dir / (kind + "_cut.exr")).string()),
                          read_image((dir / (kind + "_cli_cut.exr")).string())));
  }
  // A bad option: oiiotool fails (it reports the name as not found); iinfo shows stex's message.
  const std::string bad = shell_quote(models().at("lrp").string() + "?RES=8x8&SEDE=1");
  EXPECT_NE(run_shell(oiio_env() + "oiiotool " + bad + " -o " + shell_quote((dir / "x.exr").string()) +
                      " > /dev/null 2>&1"),
            0);
  EXPECT_FALSE(fs::exists(dir / "x.exr"));
  const std::string err = (dir / "err.txt").string();
  EXPECT_NE(run_shell(oiio_env() + "iinfo " + bad + " > " + shell_quote(err) + " 2>&1"), 0);
  EXPECT_NE(stex::test::slurp_file(err).find("stex: unknown option 'SEDE'"), std::string::npos)
      << stex::test::slurp_file(err);
}

TEST(OiioTools, MaketxMakesAMipMappedTextureOfARegion) {
  const fs::path dir = tmp("maketx");
  const std::string model = models().at("gabor").string();
  // maketx insists on an existing file name: the options come from STEX_IMAGEIO_OPTIONS.
  ASSERT_EQ(run_shell(oiio_env() + "STEX_IMAGEIO_OPTIONS='RES=256x128&ORIGIN=1000000000000,0&SEED=2' maketx " +
                      shell_quote(model) + " -d float -o " + shell_quote((dir / "g.tx").string()) + " > /dev/null"),
            0);
  auto in = OIIO::ImageInput::open((dir / "g.tx").string());
  ASSERT_TRUE(in);
  int levels = 0;
  while (in->seek_subimage(0, levels)) ++levels;
  EXPECT_EQ(levels, 9);  // 256x128 .. 1x1
  run_ok("render " + shell_quote(model) + " -o g.exr --size 256x128 --origin 1000000000000,0 --seed 2", dir);
  EXPECT_TRUE(same_bits(read_image((dir / "g.tx").string()), read_image((dir / "g.exr").string())));
}

}  // namespace
