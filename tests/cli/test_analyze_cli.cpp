// `stex analyze` and `stex export-texton` run as real subprocesses (STEX_CLI_PATH) on the bundled exemplar
// and on bad inputs: exit codes (core/error.h), messages, and that no output file (nor a temp file) is
// left behind on failure.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "model/codecs.h"
#include "cli/bad_exemplars.h"
#include "cli_run.h"

namespace fs = std::filesystem;

namespace {

using stex::test::CliRun;

std::string tmp_dir() {
  static const std::string dir = [] {
    std::string d = std::string(STEX_TEST_TMP_DIR) + "/analyze_cli";
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

std::string slurp(const std::string& path) { return stex::test::slurp_file(path); }

// stdout and stderr in tmp_dir() (tests/cli_run.h).
CliRun stex_run(const std::string& args) { return stex::test::run_stex_cli(args, "analyze_cli"); }

std::string quote(const std::string& s) { return "'" + s + "'"; }
const std::string kGravel = std::string(STEX_SOURCE_DIR) + "/data/gravel.png";

void write_image(const std::string& path, int w, int h, int ch) {
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out);
  OIIO::ImageSpec spec(w, h, ch, OIIO::TypeDesc::UINT8);
  if (ch == 4) spec.alpha_channel = 3;
  ASSERT_TRUE(out->open(path, spec));
  std::vector<float> v(std::size_t(w) * h * ch);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = float((i * 37) % 251) / 255.0f;
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, v.data()));
  ASSERT_TRUE(out->close());
}

bool dir_has_temp_files() {
  for (const auto& e : fs::directory_iterator(tmp_dir()))
    if (e.path().filename().string().find(".stex-tmp-") != std::string::npos) return true;
  return false;
}

TEST(AnalyzeCli, AnalyzesGravelAndExportsTheTexton) {
  const std::string model = tmp_dir() + "/gravel.stex";
  CliRun r = stex_run("analyze " + quote(kGravel) + " -o " + quote(model) +
                      " --support 32 --iterations 20 --seed 3");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("RME"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("variance kept"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ms total"), std::string::npos) << r.out;
  const stex::TextonModel m = stex::load_model(model);
  EXPECT_EQ(m.support, 32);
  EXPECT_EQ(m.iterations, 20);
  EXPECT_EQ(m.analysis_seed, 3u);
  EXPECT_EQ(m.channels, 1);
  EXPECT_EQ(m.exemplar_name, "gravel.png");
  EXPECT_EQ(m.exemplar_hash.size(), 64u);
  EXPECT_GT(m.rme, 0.0);
  EXPECT_LT(m.rme, 1.0);

  CliRun png = stex_run("export-texton " + quote(model) + " -o " + quote(tmp_dir() + "/texton.png"));
  ASSERT_EQ(png.code, 0) << png.err;
  EXPECT_NE(png.out.find("normalised for display"), std::string::npos) << png.out;
  CliRun exr = stex_run("export-texton " + quote(model) + " -o " + quote(tmp_dir() + "/texton.exr"));
  ASSERT_EQ(exr.code, 0) << exr.err;
  // The EXR holds the raw coefficients.
  auto in = OIIO::ImageInput::open(tmp_dir() + "/texton.exr");
  ASSERT_TRUE(in);
  ASSERT_EQ(in->spec().width, 32);
  std::vector<float> px(32 * 32);
  ASSERT_TRUE(in->read_image(0, 0, 0, 1, OIIO::TypeDesc::FLOAT, px.data()));
  EXPECT_EQ(px[5 * 32 + 7], m.alpha_at(0, 5, 7));
  EXPECT_FALSE(dir_has_temp_files());
}

TEST(AnalyzeCli, SameSeedSameModelBytes) {
  const std::string a = tmp_dir() + "/a.stex", b = tmp_dir() + "/b.stex";
  ASSERT_EQ(stex_run("analyze " + quote(kGravel) + " -o " + quote(a) + " --support 16 --iterations 5").code, 0);
  ASSERT_EQ(stex_run("analyze " + quote(kGravel) + " -o " + quote(b) + " --support 16 --iterations 5").code, 0);
  EXPECT_EQ(slurp(a), slurp(b));
}

TEST(AnalyzeCli, LinearDecodesSrgb) {
  const std::string enc = tmp_dir() + "/enc.stex", lin = tmp_dir() + "/lin.stex";
  ASSERT_EQ(stex_run("analyze " + quote(kGravel) + " -o " + quote(enc) + " --support 16 --iterations 2").code,
            0);
  CliRun r =
      stex_run("analyze " + quote(kGravel) + " -o " + quote(lin) + " --support 16 --iterations 2 --linear");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("linear light"), std::string::npos) << r.out;
  const stex::TextonModel me = stex::load_model(enc), ml = stex::load_model(lin);
  EXPECT_FALSE(me.linear);
  EXPECT_TRUE(ml.linear);
  // Decoding is convex on [0,1] and below the identity: the linear mean is below the encoded one (gravel's
  // encoded mean is 0.496; its linear mean is about 0.2-0.25).
  EXPECT_LT(ml.mean[0], me.mean[0] - 0.1f);
}

TEST(AnalyzeCli, AlphaIsDroppedWithAWarning) {
  const std::string rgba = tmp_dir() + "/rgba.png", model = tmp_dir() + "/rgba.stex";
  write_image(rgba, 40, 40, 4);
  CliRun r = stex_run("analyze " + quote(rgba) + " -o " + quote(model) + " --support 16 --iterations 5");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("alpha"), std::string::npos) << r.err;
  EXPECT_EQ(stex::load_model(model).channels, 3);
}

struct BadCase {
  std::string name, args;
  int rc;
  std::string needle;
};

// Options that the chosen method, the model's kind or the cs-rpn variant does not read exit 2 naming the option
// and what it belongs to, and nothing is written (they used to be ignored silently).
TEST(AnalyzeCli, OptionsOfAnotherKindFailNamingTheOptionAndTheKind) {
  const std::string d = tmp_dir();
  const std::string out = d + "/kinds.stex";
  const std::string g = quote(kGravel);
  struct Case {
    std::string args, what;
  };
  const std::vector<Case> cases = {
      {"analyze " + g + " --method lrp --iterations 7 -o " + quote(out),
       "--iterations does not apply to --method lrp (it is an option of --method texton)"},
      {"analyze " + g + " --method lrp --support 16 -o " + quote(out), "--support does not apply to --method lrp"},
      {"analyze " + g + " --method lrp --order 3 -o " + quote(out), "--order does not apply to --method lrp"},
      {"analyze " + g + " --method gabor --mask disc:5 -o " + quote(out), "--mask does not apply to --method gabor"},
      {"analyze " + g + " --method gabor --tolerance 0.1 -o " + quote(out),
       "--tolerance does not apply to --method gabor"},
      {"analyze " + g + " --method gabor --seed 3 -o " + quote(out),
       "--seed does not apply to --method gabor (it is an option of --method texton or lrp)"},
      {"analyze " + g + " --method cs-spot --periods 24,0,12,10 --order 0 -o " + quote(out),
       "--order does not apply to --method cs-spot"},
      {"analyze " + g + " --method cs-spot --periods 24,0,12,10 --mask disc:3 -o " + quote(out),
       "--mask does not apply to --method cs-spot"},
      {"analyze " + g + " --method texton --cosines 8 -o " + quote(out),
       "--cosines does not apply to --method texton (it is an option of --method lrp)"},
      {"analyze " + g + " --method tb --periods 21,3,-4,17 -o " + quote(out),
       "--periods does not apply to --method tb (it is an option of --method cs-spot or cs-tb)"},
      {"analyze " + g + " --method texton --json -o " + quote(out), "--json does not apply to --method texton"},
      {"analyze " + g + " --method voronoi -o " + quote(out), "unknown --method 'voronoi'"},
      {"cs-rpn -o " + quote(out) + " --periods 64,0,0,64 --spectra nothere.json --variant gabor --spacing 10",
       "--spacing does not apply to --variant gabor (it is an option of random-phase)"},
      {"cs-rpn -o " + quote(out) + " --periods 64,0,0,64 --spectra nothere.json --variant fourier --bandwidth 0.1",
       "--bandwidth does not apply to --variant fourier (it is an option of gabor and phasor)"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args);
    const CliRun r = stex_run(c.args);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find(c.what), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
  // --help groups the method-specific options by the methods that read them.
  const CliRun h = stex_run("analyze --help");
  EXPECT_EQ(h.code, 0);
  EXPECT_NE(h.out.find("Options of --method lrp:"), std::string::npos) << h.out;
  EXPECT_NE(h.out.find("Options of --method cs-spot or cs-tb:"), std::string::npos) << h.out;

  // stex render: --mni and --cell only for the kinds driven by a Poisson process; --scale < 1 warns that a
  // kind without filtering aliases.
  const std::string lrp = d + "/kinds_lrp.stex";
  ASSERT_EQ(stex_run("analyze " + g + " --method lrp --cosines 8 --strata 2 -o " + quote(lrp)).code, 0);
  const std::string img = d + "/kinds.exr";
  CliRun r = stex_run("render " + quote(lrp) + " -o " + quote(img) + " --size 64x64 --mni 5");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--mni does not apply to '" + lrp + "', a lrp model"), std::string::npos) << r.err;
  r = stex_run("render " + quote(lrp) + " -o " + quote(img) + " --size 64x64 --cell 0.8");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--cell does not apply"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(img));
  // lrp filters minified views (docs/filtering.md): no warning; tb does not yet: it warns.
  r = stex_run("render " + quote(lrp) + " -o " + quote(img) + " --size 64x64 --scale 0.5");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("aliases"), std::string::npos) << r.err;
  const std::string tb = d + "/kinds_tb.stex";
  ASSERT_EQ(stex_run("analyze " + g + " --method tb -o " + quote(tb)).code, 0);
  r = stex_run("render " + quote(tb) + " -o " + quote(img) + " --size 64x64 --scale 0.5");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("point-samples this tb model: the render aliases"), std::string::npos) << r.err;
}

// Errors name what failed: a mistyped mask shape is not "cannot open exemplar", a missing input of another
// subcommand is named by its role, and s2-report's default exemplar does not depend on the working directory.
TEST(AnalyzeCli, ErrorsNameWhatFailed) {
  const std::string d = tmp_dir();
  const std::string out = d + "/named.stex";
  struct Case {
    std::string args;
    int code;
    std::string what;
  };
  const std::vector<Case> cases = {
      {"analyze " + quote(kGravel) + " --order 0 --mask circle:3 -o " + quote(out), 2,
       "--mask 'circle:3': unknown shape 'circle' (expected square:S, disc:R or a mask image path)"},
      {"analyze " + quote(kGravel) + " --order 0 --mask " + quote(d + "/nomask.png") + " -o " + quote(out), 3,
       "cannot open mask image '" + d + "/nomask.png'"},
      {"contrast " + quote(d + "/nothere.exr"), 3, "cannot open image '" + d + "/nothere.exr'"},
      {"analyze " + quote(d + "/nothere.png") + " -o " + quote(out), 3, "cannot open exemplar '" + d + "/nothere.png'"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args);
    const CliRun r = stex_run(c.args);
    EXPECT_EQ(r.code, c.code) << r.err;
    EXPECT_NE(r.err.find(c.what), std::string::npos) << r.err;
  }
  // s2-report from a directory without data/: the default exemplar is found by absolute path (a tiny run).
  const CliRun r = stex::test::run_stex_cli("s2-report --out " + quote(d + "/s2") +
                                                " --inits 2 --iterations 2 --radius 3 --radii 3 --fig5-iterations 2",
                                            "analyze_cli_s2", "/");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(d + "/s2"));
}

TEST(AnalyzeCli, BadInputsFailCleanlyWithoutOutput) {
  const std::string d = tmp_dir();
  write_image(d + "/one.png", 1, 1, 1);
  write_image(d + "/small.png", 20, 30, 3);
  write_image(d + "/trunc.png", 64, 64, 3);
  fs::resize_file(d + "/trunc.png", fs::file_size(d + "/trunc.png") / 2);
  { std::ofstream(d + "/garbage.stex") << "not a model"; }
  const std::string out = d + "/out.stex";
  const std::vector<BadCase> cases = {
      {"missing exemplar", "analyze " + quote(d + "/nope.png") + " -o " + quote(out), 3, "No such file"},
      {"1x1 exemplar", "analyze " + quote(d + "/one.png") + " -o " + quote(out) + " --method texton", 3,
       "smaller than the texton support"},
      {"1x1 exemplar, --method auto", "analyze " + quote(d + "/one.png") + " -o " + quote(out), 3,
       "(1x1) is too small to choose a kind"},
      {"exemplar smaller than support",
       "analyze " + quote(d + "/small.png") + " -o " + quote(out) + " --support 24", 3,
       "20x30, smaller than the texton support 24x24"},
      {"truncated png", "analyze " + quote(d + "/trunc.png") + " -o " + quote(out), 3, "trunc.png"},
      {"pixel budget", "analyze " + quote(kGravel) + " -o " + quote(out) + " --pixel-budget 1000", 5,
       "pixel budget"},
      {"support 0", "analyze " + quote(kGravel) + " -o " + quote(out) + " --support 0", 2, "support"},
      {"order 2", "analyze " + quote(kGravel) + " -o " + quote(out) + " --order 2", 2, "order"},
      {"missing -o", "analyze " + quote(kGravel), 2, "output"},
      {"unwritable output",
       "analyze " + quote(kGravel) + " -o " + quote(d + "/no_dir/x.stex") + " --support 8 --iterations 1", 6,
       "no_dir/x.stex"},
      {"corrupt model", "export-texton " + quote(d + "/garbage.stex") + " -o " + quote(d + "/t.png"), 3,
       "not a stex model file"},
      {"missing model", "export-texton " + quote(d + "/nope.stex") + " -o " + quote(d + "/t.png"), 3,
       "nope.stex"},
  };
  for (const BadCase& c : cases) {
    CliRun r = stex_run(c.args);
    EXPECT_EQ(r.code, c.rc) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.needle), std::string::npos) << c.name << ": stderr was: " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
    EXPECT_FALSE(fs::exists(d + "/t.png")) << c.name;
    EXPECT_FALSE(dir_has_temp_files()) << c.name;
  }
}

// Damaged exemplars (tests/cli/bad_exemplars.h): truncated JPEG and TIFF (3), a PNG declaring 10^5 x 10^5
// pixels (5, refused before allocation), NaN and Inf pixels in an EXR (3): stderr names the file and the
// problem, and no model (nor temp file) is written.
TEST(AnalyzeCli, DamagedExemplarsFailCleanlyWithoutOutput) {
  const std::string d = tmp_dir() + "/damaged";
  fs::create_directories(d);
  const std::string out = d + "/out.stex";
  const auto bad = stex::test::make_bad_exemplars(d);
  ASSERT_EQ(bad.size(), 5u);
  for (const auto& b : bad) {
    SCOPED_TRACE(b.name);
    CliRun r = stex_run("analyze " + quote(b.path) + " -o " + quote(out) + " --support 16 --iterations 2");
    EXPECT_EQ(r.code, b.code) << r.err;
    for (const std::string& n : b.needles) EXPECT_NE(r.err.find(n), std::string::npos) << n << " in: " << r.err;
    EXPECT_FALSE(fs::exists(out));
    for (const auto& e : fs::directory_iterator(d))
      EXPECT_EQ(e.path().filename().string().find(".stex-tmp-"), std::string::npos) << e.path();
  }
}

}  // namespace

namespace {

// --method auto, the default (analysis/kind_choice.h; the labelled set is tests/analysis/test_kind_choice.cpp):
// it says what it picked and why on stderr, picks among the methods that read the options given, and the
// method it picks runs as if named.
TEST(AnalyzeCli, MethodAutoPicksTheKindAndSaysWhy) {
  const std::string d = tmp_dir();
  const std::string out = d + "/auto.stex";
  const std::string stone = std::string(STEX_SOURCE_DIR) + "/data/tiles_stone.png";
  CliRun r = stex_run("analyze " + quote(kGravel) + " -o " + quote(out));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("stex: --method auto: tb (gradient ratio 0.86"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("tb model: "), std::string::npos) << r.out;
  // The options given narrow the choice: texton's options give texton, as before auto was the default.
  r = stex_run("analyze " + quote(kGravel) + " -o " + quote(out) + " --support 8 --iterations 2");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("--method auto: texton (the only method that reads --support, --iterations)"), std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("RME"), std::string::npos) << r.out;
  // A tile photograph: cs-tb on the estimated lattice, reported once (the method reuses auto's estimate).
  r = stex_run("analyze " + quote(stone) + " -o " + quote(out) + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("--method auto: cs-tb (gradient ratio"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("lattice (36.60, -0.10), (-0.14, 36.70)"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("\"method\": \"cs-tb\""), std::string::npos) << r.out;  // stdout is still the JSON
  // -q: nothing but errors.
  r = stex_run("-q analyze " + quote(kGravel) + " -o " + quote(out) + " --support 8 --iterations 2");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  // Options no one method reads together.
  const std::string bad = d + "/bad.stex";
  r = stex_run("analyze " + quote(kGravel) + " -o " + quote(bad) + " --support 8 --periods 30,0,0,30");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--method auto: no method reads all of --support, --periods: give --method"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(bad));
}

}  // namespace
