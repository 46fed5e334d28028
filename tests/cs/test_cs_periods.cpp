// Period estimation on near-regular exemplars (analysis/cs_lattice.h, analysis/near_regular.h): the generated
// corpus, two repetitions per axis, super-lattices, real photographs with lattices measured by hand, and the
// `stex periods` command.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "analysis/cs_lattice.h"
#include "analysis/gaussian_synthesis.h"
#include "analysis/image_io.h"
#include "analysis/near_regular.h"
#include "cli_run.h"
#include "core/error.h"

using namespace stex;

namespace {

std::string str(const Lattice& t) {
  char b[160];
  std::snprintf(b, sizeof b, "(%.3f, %.3f) (%.3f, %.3f)", t.t0x, t.t0y, t.t1x, t.t1y);
  return b;
}

// Whether every vector of `got` is a lattice vector of `truth` (within 0.5 px) and its cell larger.
bool is_super_lattice(const Lattice& got, const Lattice& truth) {
  const double v[2][2] = {{got.t0x, got.t0y}, {got.t1x, got.t1y}};
  for (const auto& q : v) {
    double a, b;
    lattice_coords(truth, q[0], q[1], &a, &b);
    const double ex = q[0] - (std::round(a) * truth.t0x + std::round(b) * truth.t1x);
    const double ey = q[1] - (std::round(a) * truth.t0y + std::round(b) * truth.t1y);
    if (std::hypot(ex, ey) > 0.5) return false;
  }
  return lattice_area(got) > 1.5 * lattice_area(truth);
}

}  // namespace

TEST(PeriodsMatch, EquivalentBasesMatchAndSubLatticesDoNot) {
  const Lattice t{21.5, 3.0, -4.0, 17.25};
  EXPECT_TRUE(lattices_match(t, Lattice{t.t0x + t.t1x, t.t0y + t.t1y, -t.t1x, -t.t1y}, 1e-9));
  EXPECT_TRUE(lattices_match(t, Lattice{t.t0x + 0.05, t.t0y, t.t1x, t.t1y - 0.05}, 0.1));
  EXPECT_FALSE(lattices_match(t, Lattice{t.t0x + 0.2, t.t0y, t.t1x, t.t1y}, 0.1));
  EXPECT_FALSE(lattices_match(t, Lattice{2 * t.t0x, 2 * t.t0y, t.t1x, t.t1y}, 0.1));   // a super-lattice
  EXPECT_FALSE(lattices_match(t, Lattice{t.t0x / 2, t.t0y / 2, t.t1x, t.t1y}, 0.1));   // a finer lattice
}

// The corpus generator's exemplars are what they claim: the same spec gives the same pixels, and the lattice
// given repeats the exemplar's statistics (its d is well below the random pairs', a finer lattice's is not).
TEST(PeriodsCorpus, GeneratorIsDeterministicAndItsLatticeIsPrimitive) {
  const std::vector<NearRegularSpec> specs = near_regular_corpus(3, 7);
  ASSERT_EQ(specs.size(), 3u);
  for (NearRegularSpec s : specs) {
    s.jpeg_quality = 0;
    const Image a = make_near_regular(s), b = make_near_regular(s);
    EXPECT_EQ(a.pixels, b.pixels) << describe(s);
    const double d = lattice_distance(a, s.lattice), d_stat = stationary_distance(a);
    const double d_half = lattice_distance(a, Lattice{s.lattice.t0x / 2, s.lattice.t0y / 2, s.lattice.t1x, s.lattice.t1y});
    EXPECT_LT(d, 0.8 * d_stat) << describe(s);
    EXPECT_GT(d_half, d + 0.15 * (d_stat - d)) << describe(s);
  }
}

// The truth estimates are judged against: the least-squares lattice of the tiles as drawn. Without per-cell
// shifts it is the spec's lattice; with them it moves by a small fraction of the shift (the mean of many
// independent shifts), more with few cells than with many.
TEST(PeriodsCorpus, RealisedLatticeIsTheFitOfTheDrawnCells) {
  NearRegularSpec s;
  s.width = s.height = 256;
  s.lattice = Lattice{30.3, 4.1, -7.2, 26.9};
  s.cell_jitter = 0.0;
  Lattice r = realised_lattice(s);
  EXPECT_EQ(r.t0x, s.lattice.t0x);
  EXPECT_EQ(r.t1y, s.lattice.t1y);
  s.cell_jitter = 0.1;
  double err_many = 0.0, err_few = 0.0;
  lattices_match(s.lattice, realised_lattice(s), 1.0, &err_many);  // ~80 cells
  s.lattice = Lattice{110.0, 7.0, -9.0, 120.0};
  lattices_match(s.lattice, realised_lattice(s), 1.0, &err_few);  // ~5 cells
  // Shifts uniform in +-0.1 px: per component sd 0.058; the slope of a fit over n cells along an axis of
  // k repetitions has sd ~ 0.058 sqrt(12 / n) / k, ~0.002 px for 80 cells, ~0.03 px for 5.
  EXPECT_GT(err_many, 0.0);
  EXPECT_LT(err_many, 0.02);
  EXPECT_LT(err_few, 0.1);
  EXPECT_GT(err_few, err_many);
}

// The acceptance measured on a fixed subset of the corpus (the first 24 exemplars of seed 1: sizes
// 128..512, 2 to 30 repetitions, rectangular, sheared and hexagonal lattices, JPEG, gradients, colour).
// Deterministic input and code: the figures are exact regressions, printed for docs/cyclostationary.md.
// Asserted: no super-lattice with a confidence at or above the warning threshold (the criterion),
// and at least 22 of 24 within 0.1 px of the lattice of the cells as drawn (realised_lattice; measured 23 of 24
// at this commit, a regression floor; the whole 200-exemplar corpus, `stex periods --corpus 200`, is reported in
// docs/cyclostationary.md; the goal is 98 %).
TEST(PeriodsCorpus, FixedSubsetFindsThePrimitiveLattice) {
  const std::vector<NearRegularSpec> specs = near_regular_corpus(24, 1);
  int matched = 0;
  for (const NearRegularSpec& s : specs) {
    const Image img = make_near_regular(s);
    PeriodEstimate e;
    try {
      e = estimate_periods(img);
    } catch (const Error& err) {
      std::printf("miss: %s: %s\n", describe(s).c_str(), err.what());
      continue;
    }
    double err = 0.0;
    const Lattice truth = realised_lattice(s);
    const bool ok = lattices_match(truth, e.periods, 0.1, &err);
    matched += ok;
    if (!ok) std::printf("miss: %s\n  got %s error %.3f px confidence %.3f\n", describe(s).c_str(), str(e.periods).c_str(), err, e.confidence);
    EXPECT_FALSE(is_super_lattice(e.periods, truth) && e.confidence >= k_low_confidence)
        << describe(s) << " got " << str(e.periods) << " confidence " << e.confidence;
  }
  std::printf("corpus subset: %d of %zu within 0.1 px\n", matched, specs.size());
  EXPECT_GE(matched, 22);
}

// Two repetitions per axis (the 2 x 2 slabs, which used to fail with "no two independent peaks"): a
// 512^2 exemplar of four 256^2 cells. Found within the 0.1 px of the lattice of the cells as drawn
// (measured 0.042 px; 0.068 px from the spec's lattice, which four jittered cells do not pin down).
TEST(PeriodsCorpus, TwoRepetitionsPerAxis) {
  NearRegularSpec s;
  s.width = s.height = 512;
  s.channels = 3;
  s.lattice = Lattice{256.0, 0.0, 0.0, 256.0};
  s.origin_x = 17.0;
  s.origin_y = 40.0;
  s.seed = 22;
  s.kind = "rect";
  const PeriodEstimate e = estimate_periods(make_near_regular(s));
  double err = 0.0;
  EXPECT_TRUE(lattices_match(realised_lattice(s), e.periods, 0.1, &err)) << str(e.periods) << " error " << err;
  EXPECT_GE(e.confidence, k_low_confidence);
}

// The super-lattice case: a 192 x 160 exemplar on (24, 0), (12, 10). The estimator used to return
// (0, -20), (24, 0), a cell twice the true one, with confidence 0.835 and no warning.
TEST(PeriodsCorpus, ReturnsThePrimitiveLatticeNotASuperLattice) {
  NearRegularSpec s;
  s.width = 192;
  s.height = 160;
  s.channels = 1;
  s.lattice = Lattice{24.0, 0.0, 12.0, 10.0};
  s.grout_width = 0.05;
  s.seed = 5;
  s.kind = "sheared";
  const PeriodEstimate e = estimate_periods(make_near_regular(s));
  double err = 0.0;
  EXPECT_TRUE(lattices_match(s.lattice, e.periods, 0.1, &err)) << str(e.periods) << " error " << err;
  EXPECT_NEAR(lattice_area(e.periods), 240.0, 1.0);
}

// Refinement of a user's estimate 1.5 px off (S4 §6) on a sheared lattice with a lighting gradient and JPEG.
TEST(PeriodsCorpus, RefinesARoughEstimate) {
  NearRegularSpec s;
  s.width = s.height = 384;
  s.lattice = Lattice{61.3, 8.2, 27.9, 70.4};
  s.gradient = 0.5;
  s.gradient_angle = 0.7;
  s.jpeg_quality = 80;
  s.seed = 9;
  const Image img = make_near_regular(s);
  const PeriodEstimate e = refine_periods(img, Lattice{62.5, 7.0, 29.0, 71.5});
  double err = 0.0;
  EXPECT_TRUE(lattices_match(s.lattice, e.periods, 0.1, &err)) << str(e.periods) << " error " << err;
  EXPECT_LT(e.d, e.d_initial);
}

// Real photographs (data/README.md), their lattices measured by hand (grout crossings or hole centres picked
// by eye, refined locally, least-squares fit; residuals 0.2-1.1 px RMS: real cells differ by about a pixel),
// so the estimate is checked within 1 px. The three tile textures are seamless 256^2 images, so their exact
// mean periods are 256 / 4, 256 / 7 and 256 / 6.
TEST(PeriodsPhotographs, EachGetsItsHandMeasuredLattice) {
  struct Photo {
    const char* file;
    Lattice hand;
  };
  const Photo photos[] = {
      {"tiles_marble.png", {64.0, 0.0, 0.0, 64.0}},
      {"tiles_stone.png", {256.0 / 7.0, 0.0, 0.0, 256.0 / 7.0}},
      {"tiles_green.png", {256.0 / 6.0, 0.0, 0.0, 256.0 / 6.0}},
      {"perforated_metal.png", {51.2, 0.0, 25.6, 25.6}},
  };
  for (const Photo& p : photos) {
    const Image img = load_exemplar(std::string(STEX_SOURCE_DIR) + "/data/" + p.file);
    const PeriodEstimate e = estimate_periods(img);
    double err = 0.0;
    EXPECT_TRUE(lattices_match(p.hand, e.periods, 1.0, &err)) << p.file << " got " << str(e.periods) << " error " << err;
    std::printf("%s: %s, %.3f px from the hand lattice, confidence %.3f\n", p.file, str(e.periods).c_str(), err, e.confidence);
  }
}

// `stex periods`: JSON with the estimate and candidates, the plot written whole; --periods refines; the
// corpus mode reports; usage errors exit 2.
TEST(PeriodsCli, EstimatesPlotsRefinesAndReports) {
  auto stex = [](const std::string& args) { return stex::test::run_stex_cli(args, "periods_cli"); };
  const std::string dir = std::string(STEX_TEST_TMP_DIR) + "/periods_cli";
  const std::string photo = std::string(STEX_SOURCE_DIR) + "/data/tiles_stone.png";
  auto r = stex("periods '" + photo + "' --json --plot '" + dir + "/plot.png'");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(lattices_match(Lattice{256.0 / 7, 0, 0, 256.0 / 7},
                             Lattice{j["periods"][0][0], j["periods"][0][1], j["periods"][1][0], j["periods"][1][1]}, 1.0));
  EXPECT_GE(j["candidates"].size(), 2u);
  const Image plot = load_exemplar(dir + "/plot.png");
  EXPECT_GT(plot.width, 256);
  EXPECT_EQ(plot.height, 256);
  r = stex("periods '" + photo + "' --periods 37.5,0.5,0.5,36 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["from"], "refinement of --periods");
  r = stex("periods --corpus 2 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["corpus"], 2);
  r = stex("periods '" + photo + "' --corpus 2");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--corpus"), std::string::npos) << r.err;
  r = stex("periods");
  EXPECT_EQ(r.code, 2);
  r = stex("periods '" + photo + "' --periods 1,2,3");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--periods"), std::string::npos) << r.err;
}

// A texture that does not repeat gets no refined lattice: the autocorrelation's peaks are below k_repeat_peaks
// (measured 0.02-0.11 on these), so the periods are the autocorrelation's guess with confidence 0, a warning,
// and no refinement (0 evaluations of d). Before the gate the ADSN of gravel.png came out as the lattice
// (2.5, -2.5), (325.7, 324.2) with confidence 0.70 after 452 evaluations and up to minutes: the finer-lattice
// steps shrank a period to a few pixels, where neighbouring pixels of a smooth texture agree.
TEST(PeriodsStationary, TexturesThatDoNotRepeatGetNoRefinedLattice) {
  const Image gravel = load_exemplar(std::string(STEX_SOURCE_DIR) + "/data/gravel.png");
  const Image grass = load_exemplar(std::string(STEX_SOURCE_DIR) + "/data/grass.png");
  const std::vector<std::pair<std::string, Image>> cases = {{"gravel.png", gravel},
                                                            {"ADSN of gravel.png", synthesize_adsn(gravel, 0, 0, 512, 512, 1)},
                                                            {"grass.png", grass},
                                                            {"ADSN of grass.png", synthesize_adsn(grass, 0, 0, 512, 512, 1)}};
  for (const auto& c : cases) {
    const PeriodEstimate e = estimate_periods(c.second);
    EXPECT_LT(std::min(e.peak0, e.peak1), k_repeat_peaks) << c.first;
    EXPECT_EQ(e.confidence, 0.0) << c.first;
    EXPECT_EQ(e.evaluations, 0) << c.first;
    ASSERT_FALSE(e.warnings.empty()) << c.first;
    EXPECT_NE(e.warnings.back().find("does not repeat"), std::string::npos) << e.warnings.back();
  }
}
