// `stex analyze --method lrp` and `stex render` of an lrp model, as real subprocesses: the model file is of
// kind "lrp" and renders through the registry; bad LRP options exit 2 naming the option.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "analysis/lrp.h"
#include "model/codecs.h"
#include <nlohmann/json.hpp>
#include "cli_run.h"

namespace fs = std::filesystem;

namespace {

using CliResult = stex::test::CliRun;

std::string dir() {
  static const std::string d = [] {
    std::string p = std::string(STEX_TEST_TMP_DIR) + "/lrp_cli";
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
  }();
  return d;
}

std::string slurp(const std::string& p) { return stex::test::slurp_file(p); }

CliResult run_cli(const std::string& args) { return stex::test::run_stex_cli(args, "lrp_cli/run"); }

const std::string kGravel = std::string(STEX_SOURCE_DIR) + "/data/gravel.png";

TEST(LrpCli, AnalyzeAndRender) {
  const std::string model = dir() + "/g.stex", img = dir() + "/g.png";
  CliResult a = run_cli("analyze '" + kGravel + "' --method lrp --cosines 20 --structure 0.2 --turbulence 2 --placement -o '" + model + "'");
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_NE(a.out.find("stratum 0"), std::string::npos) << a.out;
  const stex::ModelContainer c = stex::load_container(model);
  EXPECT_EQ(c.kind, "lrp");
  const stex::LrpModel m = stex::lrp_from_container(c);
  EXPECT_EQ(m.cosines, 20);
  EXPECT_TRUE(m.placement);
  CliResult r = run_cli("render '" + model + "' -o '" + img + "' --size 48x32 --seed 3");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(img));
  EXPECT_EQ(m.turbulence.size(), 2u);
  EXPECT_NE(a.out.find("turbulence 0"), std::string::npos) << a.out;
  // r = 1 with turbulence (S3 §6.3: "applying turbulence and random placement"): no random-phase strata,
  // the turbulence's own strata are written, and the render differs from the sigma = 0 model's
  const std::string m1 = dir() + "/g1.stex", m0 = dir() + "/g0.stex";
  ASSERT_EQ(run_cli("analyze '" + kGravel + "' --method lrp --structure 1 --turbulence 4 -o '" + m1 + "'").code, 0);
  ASSERT_EQ(run_cli("analyze '" + kGravel + "' --method lrp --structure 1 -o '" + m0 + "'").code, 0);
  const stex::LrpModel t1 = stex::lrp_from_container(stex::load_container(m1));
  EXPECT_TRUE(t1.strata.empty());
  EXPECT_EQ(t1.turbulence.size(), 2u);
  ASSERT_EQ(run_cli("render '" + m1 + "' -o '" + dir() + "/t1.exr' --size 32x32 --seed 3").code, 0);
  ASSERT_EQ(run_cli("render '" + m0 + "' -o '" + dir() + "/t0.exr' --size 32x32 --seed 3").code, 0);
  EXPECT_NE(slurp(dir() + "/t1.exr"), slurp(dir() + "/t0.exr"));
  // continuous-spectrum mode: no exemplar
  CliResult p = run_cli("analyze --method lrp --psd ring:0.1,0.01 --psd-size 64 --cosines 5 --strata 1 -o '" + dir() + "/ring.stex'");
  ASSERT_EQ(p.code, 0) << p.err;
}

TEST(LrpCli, BadOptions) {
  const std::string o = "-o '" + dir() + "/bad.stex'";
  for (auto [args, needle] : std::vector<std::pair<std::string, std::string>>{
           {"analyze '" + kGravel + "' --method lrp --turbulence 3 " + o, "--structure"},
           {"analyze '" + kGravel + "' --method texton --cosines 10 " + o, "--method lrp"},
           {"analyze --method lrp --psd blob:1 " + o, "blob"},
           {"analyze '" + kGravel + "' --method lrp --psd ring:0.1,0.01 " + o, "--psd"},
           {"analyze '" + kGravel + "' --method lrp --structure 1.5 " + o, "structure"},
           {"analyze " + o, "exemplar"},
           {"analyze '" + kGravel + "' --method lrp --amplitudes flat " + o, "--amplitudes"},
           {"analyze '" + kGravel + "' --method texton --amplitudes paper " + o, "--method lrp"},
           {"analyze '" + kGravel + "' --method lrp --strata 17 " + o, "--strata"}}) {
    CliResult r = run_cli(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(dir() + "/bad.stex")) << args;
  }
}

TEST(LrpCli, SpectrumReportAndAmplitudes) {
  // `stex analyze --method lrp` prints the model's expected radial PSD error against the exemplar's Welch PSD;
  // --json writes the per-bin ratios (24 radial bins, 48 sectors) with the same summary figures; the default
  // is the fitted amplitudes (within the figures on gravel), --amplitudes paper is S3's (and leaves
  // the model file without the field, as files written before it), --strata 16 is accepted.
  const std::string fit = dir() + "/fit.stex", paper = dir() + "/paper.stex";
  CliResult a = run_cli("analyze '" + kGravel + "' --method lrp -o '" + fit + "'");
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_NE(a.out.find("amplitudes fit; expected radial PSD / exemplar's Welch PSD"), std::string::npos) << a.out;
  CliResult j = run_cli("analyze '" + kGravel + "' --method lrp --json -o '" + fit + "'");
  ASSERT_EQ(j.code, 0) << j.err;
  const nlohmann::json report = nlohmann::json::parse(j.out);
  EXPECT_EQ(report.at("amplitudes"), "fit");
  const nlohmann::json& psd = report.at("psd");
  ASSERT_EQ(psd.at("radial_ratio").size(), 24u);
  ASSERT_EQ(psd.at("radial_count").size(), 24u);
  ASSERT_EQ(psd.at("sector_ratio").size(), 48u);
  std::vector<double> err;
  double worst = 0.0;
  for (std::size_t k = 0; k < 24; ++k) {
    const double e = std::fabs(psd.at("radial_ratio")[k].get<double>() - 1.0);
    err.push_back(e);
    if (psd.at("radial_count")[k].get<int>() >= 200) worst = std::max(worst, e);
  }
  std::sort(err.begin(), err.end());
  EXPECT_NEAR(psd.at("radial_median").get<double>(), 0.5 * (err[11] + err[12]), 1e-12);
  EXPECT_NEAR(psd.at("radial_max").get<double>(), worst, 1e-12);
  EXPECT_LE(psd.at("radial_median").get<double>(), 0.10);
  EXPECT_LE(psd.at("radial_max").get<double>(), 0.35);
  EXPECT_LE(psd.at("sector_median").get<double>(), 0.10);
  // the text report prints the same figures
  char line[64];
  std::snprintf(line, sizeof line, "median |error| %.3f", psd.at("radial_median").get<double>());
  EXPECT_NE(a.out.find(line), std::string::npos) << a.out;
  const stex::LrpModel m = stex::lrp_from_container(stex::load_container(fit));
  EXPECT_EQ(m.amplitudes, "fit");
  EXPECT_EQ(stex::load_container(fit).metadata.at("analysis").at("amplitudes"), "fit");
  ASSERT_EQ(run_cli("analyze '" + kGravel + "' --method lrp --amplitudes paper --strata 4 -o '" + paper + "'").code, 0);
  EXPECT_FALSE(stex::load_container(paper).metadata.at("analysis").contains("amplitudes"));
  EXPECT_EQ(stex::lrp_from_container(stex::load_container(paper)).amplitudes, "paper");
  CliResult s16 = run_cli("analyze '" + kGravel + "' --method lrp --strata 16 --cosines 400 -o '" + dir() + "/s16.stex'");
  ASSERT_EQ(s16.code, 0) << s16.err;
  EXPECT_EQ(stex::lrp_from_container(stex::load_container(dir() + "/s16.stex")).strata.size(), 16u);
  ASSERT_EQ(run_cli("render '" + dir() + "/s16.stex' -o '" + dir() + "/s16.exr' --size 32x32 --seed 1").code, 0);
}

}  // namespace
