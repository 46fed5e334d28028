// Damage sweep (issue #12, in OpenEXR's style): for a PNG, a JPEG, a TIFF and an EXR written here from a
// small synthetic image, and for a model file written by save_model, 2000 seeded damaged variants each
// (bit flips, truncations, overwritten byte runs; std::mt19937 seeded by the variant number, so every
// run tries the same inputs). Each variant is loaded through load_exemplar / load_model inside a forked,
// time- and memory-bounded child (isolate.h): it either succeeds, and then the data is finite and within
// its declared size and the pixel budget, or throws stex::Error with a non-empty message. A crash, a hang
// or any other exception fails the test naming the fixture and the variant's seed.
// In the sanitizer tree (scripts/san-configure.sh) the sweep runs 400 variants per fixture, seeds 2000..2399:
// inputs the normal tree's 2000 (seeds 0..1999) do not try, each about 10x slower under ASan; the issue's 2000
// per fixture are the normal tree's (docs/hardening.md, "the sanitized run's profile").
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "analysis/cs_rpn_model.h"
#include "analysis/cs_spot_model.h"
#include "analysis/gabor_model.h"
#include "analysis/image_io.h"
#include "analysis/lrp.h"
#include "model/codecs.h"
#include "model/kinds.h"
#include "analysis/tb_model.h"
#include "core/error.h"
#include "hardening/isolate.h"
#include "sanitizer.h"

namespace fs = std::filesystem;
using stex::test::run_isolated_batch;

namespace {

constexpr int k_variants = stex::test::k_under_asan ? 400 : 2000;
constexpr int k_first_seed = stex::test::k_under_asan ? 2000 : 0;
constexpr int k_batch = 250;  // variants per forked child: one fork costs a few ms
constexpr std::uint64_t k_budget = std::uint64_t(1) << 20;  // pixels: damaged headers beyond it -> Limit

fs::path tmp_dir(const std::string& name) {
  fs::path d = fs::path(STEX_TEST_TMP_DIR) / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::vector<std::uint8_t> read_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(f), {});
}

void write_bytes(const fs::path& p, const std::vector<std::uint8_t>& b) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}

// One damaged variant of `src`, fully determined by `seed`: kind 0 flips 1-8 bits, kind 1 truncates,
// kind 2 overwrites a run of 1-64 bytes (random, 0x00 or 0xFF), kind 3 does a flip and a truncation.
std::vector<std::uint8_t> damage(const std::vector<std::uint8_t>& src, std::uint64_t seed) {
  std::mt19937 rng(std::uint32_t(seed * 2654435761u + 12345u));
  std::vector<std::uint8_t> out = src;
  auto pos = [&](std::size_t n) { return std::size_t(rng() % std::max<std::size_t>(n, 1)); };
  const int kind = int(seed % 4);
  if (kind == 0 || kind == 3) {
    int flips = 1 + int(rng() % 8);
    for (int i = 0; i < flips; ++i) out[pos(out.size())] ^= std::uint8_t(1u << (rng() % 8));
  }
  if (kind == 1 || kind == 3) {
    out.resize(pos(out.size()));
  }
  if (kind == 2) {
    std::size_t at = pos(out.size());
    std::size_t len = std::min<std::size_t>(1 + rng() % 64, out.size() - at);
    int fill = int(rng() % 3);
    for (std::size_t i = 0; i < len; ++i)
      out[at + i] = fill == 0 ? std::uint8_t(rng()) : fill == 1 ? std::uint8_t(0) : std::uint8_t(0xFF);
  }
  return out;
}

stex::Image synthetic_image(int w, int h, int c) {
  stex::Image img;
  img.width = w;
  img.height = h;
  img.channels = c;
  img.pixels.resize(std::size_t(w) * h * c);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < c; ++k)
        img.at(x, y, k) = 0.5f + 0.4f * std::sin(0.37f * x + 0.71f * y + 1.3f * k);
  return img;
}

// Writes the fixture in a forked child: the parent never initialises OIIO or OpenEXR thread pools, which
// a later fork would copy without their threads.
void write_fixture_isolated(const fs::path& path) {
  auto r = run_isolated_batch({0}, [&](std::uint64_t, const std::function<void(const std::string&)>&) {
    if (path.filename() == "fixture_lrp.stex") {
      // An LRP model (analysis/lrp.h) from an analytic ring spectrum: one stratum, 5 cosines.
      stex::LrpParams p;
      p.cosines = 5;
      p.strata = 1;
      p.amplitudes = stex::LrpAmplitudes::Paper;
      stex::save_container(stex::to_container(stex::lrp_from_spectrum(stex::lrp_analytic_psd("ring:0.1,0.01", 64), p)),
                           path.string());
    } else if (path.filename() == "fixture_cs_hist.stex" || path.filename() == "fixture_cs_spot_hist.stex") {
      // cs-tb / cs-spot models with a cyclostationary histogram table (analysis/cs_hist.h, δ = 1).
      const stex::Image ex = synthetic_image(40, 40, 2);
      const stex::Lattice t{6.0, 0.0, 0.0, 5.0};
      if (path.filename() == "fixture_cs_hist.stex") {
        stex::TbParams p;
        p.tile = 4.0;
        p.histogram = 2;
        stex::save_container(stex::to_container(stex::tb_from_exemplar(ex, p, &t)), path.string());
      } else {
        stex::CsSpotParams p;
        p.histogram = 2;
        stex::save_container(stex::to_container(stex::cs_spot_from_exemplar(ex, t, p)), path.string());
      }
    } else if (path.filename() == "fixture_gabor.stex") {
      stex::GaborModel g;
      g.bandwidth = 0.06;
      g.components.resize(2);
      g.components[1].frequency = 0.2;
      g.components[1].orientation = 1.0;
      stex::save_container(stex::to_container(g), path.string());
    } else if (path.filename() == "fixture_cs_rpn.stex") {
      // A cs-rpn model (analysis/cs_rpn_model.h): two bi-lobes along t0, phasor.
      stex::CsRpnModel m;
      m.variant = stex::CsRpnVariant::Phasor;
      m.t0x = 40.0;
      m.t1y = 40.0;
      stex::cs_rpn_load_spectra(m, nlohmann::json::parse(R"({"grid": [2, 1], "size": 16,
          "spectra": ["bilobe:0.2,0,0.03", {"psd": "bilobe:0.2,90,0.03", "variance": 0.01}]})"));
      stex::save_container(stex::to_container(m), path.string());
    } else if (path.extension() == ".stex") {
      stex::TextonModel m;
      m.channels = 3;
      m.support = 8;
      m.alpha.resize(3 * 8 * 8);
      std::mt19937 rng(7);
      for (float& a : m.alpha) a = float(rng() % 2001) / 1000.0f - 1.0f;
      m.mean = {0.5f, 0.4f, 0.3f, 0.0f};
      m.exemplar_name = "synthetic.png";
      m.exemplar_hash = std::string(64, 'a');
      m.exemplar_width = 32;
      m.exemplar_height = 24;
      m.iterations = 10;
      m.stex_version = "test";
      stex::save_model(m, path.string());
    } else {
      stex::write_image_atomic(path.string(), synthetic_image(32, 24, 3));
    }
  });
  ASSERT_TRUE(r.failures.empty()) << r.failures.front();
}

using Check = std::function<void(const std::string& path, const std::function<void(const std::string&)>& fail)>;

void check_exemplar(const std::string& path, const std::function<void(const std::string&)>& fail) {
  stex::LoadOptions opts;
  opts.pixel_budget = k_budget;
  try {
    stex::Image img = stex::load_exemplar(path, opts);
    if (img.width <= 0 || img.height <= 0 || img.channels < 1 || img.channels > 4)
      return fail("loaded with a bad shape " + std::to_string(img.width) + "x" + std::to_string(img.height));
    if (std::uint64_t(img.width) * std::uint64_t(img.height) > k_budget) return fail("loaded over the budget");
    if (img.pixels.size() != std::size_t(img.width) * img.height * img.channels)
      return fail("pixel count differs from the declared size");
    for (float v : img.pixels)
      if (!std::isfinite(v)) return fail("loaded a non-finite value");
  } catch (const stex::Error& e) {
    if (std::string(e.what()).empty()) fail("stex::Error with an empty message");
  }
}

void check_model(const std::string& path, const std::function<void(const std::string&)>& fail) {
  try {
    stex::TextonModel m = stex::load_model(path);
    if (m.channels < 1 || m.channels > 4 || m.support < 1 || m.support > stex::kModelMaxSupport)
      return fail("loaded a model with a bad shape");
    if (m.alpha.size() != std::size_t(m.channels) * m.support * m.support)
      return fail("alpha size differs from the declared shape");
    for (float v : m.alpha)
      if (!std::isfinite(v)) return fail("loaded a non-finite alpha");
    for (float v : m.mean)
      if (!std::isfinite(v)) return fail("loaded a non-finite mean");
  } catch (const stex::Error& e) {
    if (std::string(e.what()).empty()) fail("stex::Error with an empty message");
  }
}

// Any kind, through the registry's codecs (analysis/noise_kinds.h): loads and validates every field, or
// fails with a message.
void check_any_model(const std::string& path, const std::function<void(const std::string&)>& fail) {
  try {
    const stex::ModelContainer c = stex::load_container(path);
    if (!stex::valid_model_kind(c.kind)) return fail("loaded a container with an invalid kind");
    stex::check_model(c, path);
    for (float v : c.payload)
      if (!std::isfinite(v)) return fail("loaded a non-finite payload value");
  } catch (const stex::Error& e) {
    if (std::string(e.what()).empty()) fail("stex::Error with an empty message");
  }
}

// Sweeps k_variants damaged copies of the fixture `name`; returns the number of contract violations.
int sweep(const std::string& name, const Check& check) {
  const fs::path dir = tmp_dir("sweep_" + name);
  const fs::path fixture = dir / name;
  write_fixture_isolated(fixture);
  const std::vector<std::uint8_t> src = read_bytes(fixture);
  EXPECT_GT(src.size(), 16u);
  std::vector<std::string> failures;
  for (int start = 0; start < k_variants; start += k_batch) {
    std::vector<std::uint64_t> ids;
    for (int i = start; i < std::min(k_variants, start + k_batch); ++i) ids.push_back(std::uint64_t(k_first_seed + i));
    const fs::path variant = dir / ("variant" + fixture.extension().string());
    auto r = run_isolated_batch(ids, [&](std::uint64_t seed, const std::function<void(const std::string&)>& fail) {
      write_bytes(variant, damage(src, seed));
      check(variant.string(), fail);
    });
    EXPECT_EQ(r.inputs_done, int(ids.size())) << name;
    for (auto& f : r.failures) failures.push_back(name + " " + f);
  }
  for (auto& f : failures) ADD_FAILURE() << f;
  // The undamaged fixture loads (else the sweep would only ever exercise the error path).
  auto r = run_isolated_batch({0}, [&](std::uint64_t, const std::function<void(const std::string&)>& fail) {
    bool intact_fails = false;
    check(fixture.string(), [&](const std::string& m) {
      intact_fails = true;
      fail(m);
    });
    if (!intact_fails) {
      try {
        if (fixture.extension() == ".stex")
          stex::check_model(stex::load_container(fixture.string()), fixture.string());
        else
          stex::load_exemplar(fixture.string());
      } catch (const std::exception& e) {
        fail(std::string("the undamaged fixture does not load: ") + e.what());
      }
    }
  });
  for (auto& f : r.failures) ADD_FAILURE() << name << " " << f;
  return int(failures.size());
}

}  // namespace

TEST(DamageSweep, Png) { EXPECT_EQ(sweep("fixture.png", check_exemplar), 0); }
TEST(DamageSweep, Jpeg) { EXPECT_EQ(sweep("fixture.jpg", check_exemplar), 0); }
TEST(DamageSweep, Tiff) { EXPECT_EQ(sweep("fixture.tif", check_exemplar), 0); }
TEST(DamageSweep, Exr) { EXPECT_EQ(sweep("fixture.exr", check_exemplar), 0); }
TEST(DamageSweep, ModelFile) { EXPECT_EQ(sweep("fixture.stex", check_model), 0); }
TEST(DamageSweep, LrpModelFile) { EXPECT_EQ(sweep("fixture_lrp.stex", check_any_model), 0); }
TEST(DamageSweep, GaborModelFile) { EXPECT_EQ(sweep("fixture_gabor.stex", check_any_model), 0); }
TEST(DamageSweep, CsTbHistogramModelFile) { EXPECT_EQ(sweep("fixture_cs_hist.stex", check_any_model), 0); }
TEST(DamageSweep, CsSpotHistogramModelFile) { EXPECT_EQ(sweep("fixture_cs_spot_hist.stex", check_any_model), 0); }
TEST(DamageSweep, CsRpnModelFile) { EXPECT_EQ(sweep("fixture_cs_rpn.stex", check_any_model), 0); }

// The damage itself: deterministic per seed, and each kind changes the bytes it says it changes.
TEST(DamageSweep, VariantsAreDeterministicAndDamaged) {
  std::vector<std::uint8_t> src(1000);
  for (std::size_t i = 0; i < src.size(); ++i) src[i] = std::uint8_t(i * 7);
  int changed = 0;
  for (std::uint64_t s = 0; s < 400; ++s) {
    auto a = damage(src, s), b = damage(src, s);
    ASSERT_EQ(a, b) << s;
    if (s % 4 == 1) {
      EXPECT_LT(a.size(), src.size()) << s;
    }
    if (s % 4 == 0) {
      EXPECT_EQ(a.size(), src.size()) << s;
    }
    changed += a != src;
  }
  EXPECT_GE(changed, 390);
}
