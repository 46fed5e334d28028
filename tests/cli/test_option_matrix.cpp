// Every `stex render` option against every model kind: an option is accepted and changes the output, or it
// exits 2 naming itself; never accepted and ignored. The options that by design never change the bits (how a
// render is made, not what: --strategy, --tile-size, a pixel budget that is not reached) are checked the other
// way: accepted, and the same bits.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "analysis/image_io.h"
#include "cli_run.h"
#include "kind_models.h"

namespace fs = std::filesystem;

namespace {

std::vector<float> pixels(const fs::path& p) {
  auto in = OIIO::ImageInput::open(p.string());
  if (!in) return {};
  const OIIO::ImageSpec s = in->spec();
  std::vector<float> v(std::size_t(s.width) * s.height * s.nchannels + 2);
  v[0] = float(s.width);
  v[1] = float(s.height);
  in->read_image(0, 0, 0, s.nchannels, OIIO::TypeDesc::FLOAT, v.data() + 2);
  return v;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

struct OptionCase {
  std::string option;  // added to the render
  std::string base;    // the render it is compared with (its options besides the region)
  std::string name;    // the option under test
};

// A refusal names one of the options given.
bool names_an_option(const std::string& err, const std::string& opts) {
  for (std::size_t at = opts.find("--"); at != std::string::npos; at = opts.find("--", at + 2)) {
    const std::string name = opts.substr(at, opts.find(' ', at) - at);
    if (err.find(name) != std::string::npos) return true;
  }
  return false;
}

// A run of an option case that failed must be a refusal: exit 2 naming one of the options given. Counts it.
bool refused(const stex::test::CliRun& r, const std::string& opts, int* count) {
  if (r.code == 0) return false;
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(names_an_option(r.err, opts)) << r.err;
  ++*count;
  return true;
}

TEST(RenderOptionMatrix, EveryOptionChangesTheOutputOrIsRefused) {
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / "option_matrix";
  fs::create_directories(dir);
  const fs::path uv = dir / "uv.exr";
  {
    // a UV map of 24 x 24 pixels: a sheared plane
    stex::Image m;
    m.width = m.height = 24;
    m.channels = 2;
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 24; ++x) {
        m.pixels.push_back(100.5f + 1.5f * float(x) + 0.3f * float(y));
        m.pixels.push_back(-20.25f + 2.0f * float(y));
      }
    stex::write_image_atomic(uv.string(), m);
  }
  const fs::path map = dir / "map.png";
  {
    // a grey mixing map of 16 x 16 pixels: a diagonal ramp
    stex::Image m;
    m.width = m.height = 16;
    m.channels = 1;
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) m.pixels.push_back(float(x + y) / 30.0f);
    stex::write_image_atomic(map.string(), m);
  }
  const std::vector<OptionCase> changing = {
      {"--origin 5,7", "", "--origin"},
      {"--scale 1.5", "", "--scale"},
      {"--scale 0.5 --no-filter", "--scale 0.5", "--no-filter"},  // texton order 1 is filtered by default there
      {"--camera 2,30,60", "", "--camera"},
      {"--camera 2,30,60 --no-filter", "--camera 2,30,60", "--no-filter"},
      {"--uv-map '" + uv.string() + "'", "", "--uv-map"},
      {"--mni 7", "", "--mni"},
      {"--cell 0.8", "", "--cell"},
      {"--seed 4", "", "--seed"},
      {"--mode adsn --kernel texton", "", "--mode"},
      {"--mode adsn --kernel texton", "--mode adsn", "--kernel"},
      {"--exemplar '" + (dir / ".." / "kind_models" / "gravel.png").string() + "' --mode rpn", "--mode rpn --kernel texton",
       "--exemplar"},
      {"--bits 16", "", "--bits"},
      {"--mix-map ramp:0:64", "", "--mix-map"},
      {"--mix-scale 2", "--mix-map '" + map.string() + "'", "--mix-scale"},
      {"--mix-origin 3,4", "--mix-map '" + map.string() + "'", "--mix-origin"},
      {"--mix-wrap clamp", "--mix-map '" + map.string() + "' --mix-origin 30,0", "--mix-wrap"},
      {"--mix-scale 2", "", "--mix-scale"},  // without an image map: refused for every kind
  };
  const std::vector<OptionCase> same = {
      {"--strategy gather", "", "--strategy"},
      {"--tile-size 16 --force", "", "--tile-size"},
      {"--pixel-budget 100000", "", "--pixel-budget"},
      // --filter is the default below scale 1 for texton models of order 1 (kept as the explicit form; at
      // scale 1 the filtered evaluation gives the unfiltered bits); the other kinds refuse it.
      {"--scale 0.5 --filter", "--scale 0.5", "--filter"},
  };
  int accepted = 0, n_refused = 0;
  for (const auto& entry : stex::test::kind_models()) {
    const std::string& kind = entry.first;
    const fs::path model = entry.second;  // not a structured binding: lambdas cannot capture those in C++17
    std::map<std::string, std::vector<float>> bases;  // the kind's base renders, by their options
    auto render = [&](const std::string& opts, const std::string& out, stex::test::CliRun* r) {
      *r = stex::test::run_stex_cli("-q render '" + model.string() + "' -o '" + (dir / out).string() +
                                        "' --size 24x24 " + opts,
                                    "option_matrix");
      return dir / out;
    };
    for (const bool by_design_same : {false, true})
      for (const OptionCase& c : by_design_same ? same : changing) {
        SCOPED_TRACE(kind + ": " + c.option);
        stex::test::CliRun r;
        fs::remove(dir / "o.exr");
        const fs::path got = render(c.base + " " + c.option, "o.exr", &r);
        if (refused(r, c.base + " " + c.option, &n_refused)) continue;
        ++accepted;
        auto it = bases.find(c.base);
        if (it == bases.end()) {
          stex::test::CliRun rb;
          const fs::path base = render(c.base, "base.exr", &rb);
          ASSERT_EQ(rb.code, 0) << rb.err;
          it = bases.emplace(c.base, pixels(base)).first;
        }
        const std::vector<float> a = pixels(got);
        if (by_design_same)
          EXPECT_TRUE(same_bits(a, it->second)) << c.name << " changed the bits";
        else
          EXPECT_FALSE(same_bits(a, it->second)) << c.name << " was accepted and changed nothing";
      }
  }
  // Both outcomes occur (the matrix is not vacuous): every kind accepts --seed, only mix --mix-map, ...
  EXPECT_GT(accepted, 40);
  EXPECT_GT(n_refused, 60);
}

// Every `stex analyze` option against every method (--method texton, lrp, gabor, cs-spot, tb, cs-tb): accepted
// and the model renders differently from the same analysis without it, or exit 2 naming it. The exemplar is a
// 64 x 64 colour crop of gravel (channels from shifted copies, so the colour options have something to act
// on); the cyclostationary methods get one that repeats every 16 pixels (4 x 4 copies), so they find a lattice
// (an exactly periodic exemplar would make texton's alternating projections converge in two iterations). Options of
// the report (--json: the model unchanged, a JSON report on stdout) and a pixel budget that is not reached are
// checked the other way. A case's base holds what the option needs (--tolerance: SOT with a mask); an option
// whose default differs per method has one case per group of methods (`only`), so that every (option, method)
// pair is run once with a value that is not that method's default.
struct AnalyzeCase {
  AnalyzeCase(std::string o, std::string b, std::string n, std::vector<std::string> methods = {}, int exemplar = 2)
      : option(std::move(o)), base(std::move(b)), name(std::move(n)), only(std::move(methods)), with(exemplar) {}
  std::string option, base, name;
  std::vector<std::string> only;  // the methods of this case (empty: every method)
  int with;  // 2: both runs read the exemplar; 1: only the base (lrp's --psd mode has none); 0: neither
};

TEST(AnalyzeOptionMatrix, EveryOptionChangesTheModelOrIsRefused) {
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / "analyze_option_matrix";
  fs::create_directories(dir);
  const fs::path ex = dir / "ex.png", periodic = dir / "periodic.png";
  for (const int period : {64, 16}) {
    auto in = OIIO::ImageInput::open((fs::path(STEX_SOURCE_DIR) / "data" / "gravel.png").string());
    ASSERT_TRUE(in);
    const OIIO::ImageSpec spec = in->spec();
    std::vector<float> g(std::size_t(spec.width) * spec.height * spec.nchannels);
    in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, g.data());
    stex::Image m;
    m.width = m.height = 64;
    m.channels = 3;
    auto at = [&](int x, int y) { return g[(std::size_t(y) * spec.width + x) * spec.nchannels]; };
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        const int u = x % period + 100, v = y % period + 100;
        m.pixels.push_back(at(u, v));
        m.pixels.push_back(0.5f * at(u, v) + 0.5f * at(u + 40, v + 7));
        m.pixels.push_back(at(u + 3, v + 60));
      }
    stex::write_image_atomic((period == 16 ? periodic : ex).string(), m);
  }
  const std::vector<AnalyzeCase> changing = {
      {"--support 12", "", "--support"},
      {"--iterations 2", "--support 32", "--iterations"},  // support 64 = the exemplar: converged at once
      {"--order 3", "", "--order"},
      {"--no-colour-correction", "", "--no-colour-correction"},
      {"--mask disc:3", "--order 0", "--mask"},
      {"--tolerance 0.5", "--order 0 --mask disc:3", "--tolerance"},
      {"--max-iterations 1", "--order 0 --mask disc:3", "--max-iterations"},
      {"--seed 7", "", "--seed"},
      {"--cosines 6", "", "--cosines"},
      {"--strata 2", "", "--strata"},
      {"--structure 0.3", "", "--structure"},
      {"--turbulence 3", "--structure 0.3", "--turbulence"},
      {"--placement", "--structure 0.3", "--placement"},
      {"--psd ring:0.1,0.02", "", "--psd", {}, 1},
      {"--psd-size 32", "--psd ring:0.1,0.02", "--psd-size", {}, 0},
      {"--amplitudes paper", "", "--amplitudes"},
      {"--psd-image", "", "--psd-image"},
      {"--periods 16,0,0,32", "", "--periods"},
      {"--estimate-periods", "--periods 15.5,0.5,0,16.5", "--estimate-periods"},
      {"--border 2", "", "--border"},
      {"--histogram stationary", "", "--histogram", {"texton", "lrp", "gabor", "cs-spot"}},
      {"--histogram none", "", "--histogram", {"tb", "cs-tb"}},
      {"--delta 0", "--histogram cs", "--delta"},
      {"--tile 9", "", "--tile"},
      {"--linear", "", "--linear"},
  };
  const std::vector<AnalyzeCase> same = {
      {"--json", "", "--json"},
      {"--pixel-budget 100000", "", "--pixel-budget"},
  };
  const std::vector<std::string> methods = {"texton", "lrp", "gabor", "cs-spot", "tb", "cs-tb"};
  int accepted = 0, n_refused = 0;
  for (const std::string& method : methods) {
    std::map<std::string, std::pair<std::vector<float>, std::string>> bases;  // render and stdout, by base
    const fs::path& exemplar = method == "cs-spot" || method == "cs-tb" ? periodic : ex;
    // Analyses `opts`, renders 24 x 24 of the model; returns the exit code and fills pixels and stdout.
    auto analyse = [&](const std::string& opts, bool no_exemplar, std::vector<float>* px, stex::test::CliRun* r) {
      const fs::path model = dir / "m.stex", img = dir / "m.exr";
      fs::remove(model);
      *r = stex::test::run_stex_cli("-q analyze " + (no_exemplar ? std::string() : "'" + exemplar.string() + "' ") +
                                        "-o '" + model.string() + "' --method " + method + " " + opts,
                                    "analyze_option_matrix");
      if (r->code != 0) return;
      const stex::test::CliRun rr = stex::test::run_stex_cli(
          "-q render '" + model.string() + "' -o '" + img.string() + "' --size 24x24", "analyze_option_matrix");
      ASSERT_EQ(rr.code, 0) << rr.err;
      *px = pixels(img);
    };
    for (const bool by_design_same : {false, true})
      for (const AnalyzeCase& c : by_design_same ? same : changing) {
        if (!c.only.empty() && std::find(c.only.begin(), c.only.end(), method) == c.only.end()) continue;
        SCOPED_TRACE(method + ": " + c.option + " (base '" + c.base + "')");
        stex::test::CliRun r;
        std::vector<float> got;
        analyse(c.base + " " + c.option, c.with < 2, &got, &r);
        if (refused(r, c.base + " " + c.option, &n_refused)) continue;
        ++accepted;
        const std::string key = c.base + (c.with == 0 ? " (no exemplar)" : "");
        auto it = bases.find(key);
        if (it == bases.end()) {
          stex::test::CliRun rb;
          std::vector<float> base;
          analyse(c.base, c.with == 0, &base, &rb);
          ASSERT_EQ(rb.code, 0) << rb.err;
          it = bases.emplace(key, std::make_pair(base, rb.out)).first;
        }
        if (by_design_same) {
          EXPECT_TRUE(same_bits(got, it->second.first)) << c.name << " changed the model";
          if (c.name == "--json") {
            EXPECT_NE(r.out, it->second.second) << "--json printed nothing more";
            EXPECT_NE(r.out.find('{'), std::string::npos) << r.out;
          }
        } else {
          EXPECT_FALSE(same_bits(got, it->second.first)) << c.name << " was accepted and changed nothing";
        }
      }
  }
  EXPECT_GT(accepted, 30);
  EXPECT_GT(n_refused, 80);
  std::printf("analyze option matrix: %d accepted and changing (or same by design), %d refused\n", accepted,
              n_refused);
}

}  // namespace
