// `stex analyze --method auto` (analysis/kind_choice.h): the measures on textures whose answer is known, and the
// pick on a labelled set of 16 exemplars: micro-textures (Gaussian by construction: the ADSN of a photograph),
// structured stochastic textures (photographs of stones, blades, dead leaves; a thresholded Gaussian field),
// near-regular textures whose cells differ in structure (tile photographs) and cyclostationary textures that
// are a periodic motif plus a small variation (generated tilings; the ADSN of an exactly periodic image).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "analysis/gaussian_synthesis.h"
#include "analysis/image_io.h"
#include "analysis/kind_choice.h"
#include "analysis/near_regular.h"
#include "core/error.h"

namespace {

using stex::Image;

Image data(const std::string& name) { return stex::load_exemplar(std::string(STEX_SOURCE_DIR) + "/data/" + name); }

Image adsn(const Image& ex, std::uint64_t seed) { return stex::synthesize_adsn(ex, 0, 0, ex.width, ex.height, seed); }

// An exactly periodic image: the top-left `cell` x `cell` pixels of `ex`, repeated over `n` x `n` cells.
Image periodic(const Image& ex, int cell, int n) {
  Image out;
  out.width = out.height = cell * n;
  out.channels = ex.channels;
  out.pixels.resize(std::size_t(out.width) * out.height * ex.channels);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < ex.channels; ++c) out.at(x, y, c) = ex.at(x % cell, y % cell, c);
  return out;
}

// A binary texture: the ADSN of `ex` thresholded at its median (a level set of a Gaussian field).
Image threshold(const Image& g) {
  std::vector<float> v = g.pixels;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  const float median = v[v.size() / 2];
  Image out = g;
  for (float& p : out.pixels) p = p > median ? 0.8f : 0.2f;
  return out;
}

stex::NearRegularSpec tiling(double period, double angle_deg, int channels, std::uint64_t seed) {
  stex::NearRegularSpec s;
  s.width = s.height = 256;
  s.channels = channels;
  const double a = angle_deg * 3.14159265358979323846 / 180.0;
  s.lattice = {period * std::cos(a), period * std::sin(a), -period * std::sin(a), period * std::cos(a)};
  s.seed = seed;
  s.kind = "rect";
  return s;
}

const std::vector<std::string> k_all = {"texton", "tb", "cs-spot", "cs-tb"};

// The measures are 1 and 0 for Gaussian textures, whatever their spectrum. ADSN realisations of 512^2 pixels:
// the gradient ratio of one is a mean of 2 x 262144 correlated |g| over their rms, so its standard deviation is a
// few 1e-3 (measured: 0.999-1.001 over the four photographs' ADSN), and the marginal W1 distance of 262144
// samples of a Gaussian field with correlation lengths of a few pixels is about 0.01 (measured 0.002-0.004).
// The bounds 0.97 and 0.05 leave a margin of 10 standard deviations and are far inside the thresholds.
TEST(KindChoice, GaussianTexturesMeasureAsGaussian) {
  for (const char* name : {"gravel.png", "grass.png", "leaves.png", "brick.png"}) {
    const Image g = adsn(data(name), 7);
    EXPECT_NEAR(stex::gradient_ratio(g), 1.0, 0.03) << name;
    EXPECT_LT(stex::marginal_distance(g), 0.05) << name;
  }
}

// A hand-computed case: the two-level stripes (x + 1) mod 4 < 2 (64 x 64; the first and last columns are equal,
// so the periodic component is the image itself) have |gx| = 1 on half the
// pixels (mean 0.5, rms 1 / sqrt 2) and gy = 0: ratio 0.5 / (sqrt(2 / pi) / sqrt 2) = sqrt(pi) / 2. Their
// standardised marginal is +-1 with probability 1/2; the quantile coupling with N(0, 1) sends Z to sign(Z), so
// W1 = E| |Z| - 1 | = 2 (2 Phi(1) - 3/2 - phi(0) + 2 phi(1)) = 0.53539. The estimator sums over the 4096
// empirical quantiles; its error against the integral is below 1e-3 (the tails beyond the outermost quantile,
// |z| > 3.5, carry 5e-4 of the integrand).
TEST(KindChoice, StripesHaveTheClosedFormMeasures) {
  Image img;
  img.width = img.height = 64;
  img.channels = 1;
  img.pixels.resize(64 * 64);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) img.at(x, y, 0) = ((x + 1) % 4 < 2) ? 1.0f : 0.0f;
  EXPECT_NEAR(stex::gradient_ratio(img), std::sqrt(3.14159265358979323846) / 2.0, 1e-6);
  const double phi0 = 1.0 / std::sqrt(2.0 * 3.14159265358979323846), phi1 = phi0 * std::exp(-0.5);
  const double Phi1 = 0.5 * std::erfc(-1.0 / std::sqrt(2.0));
  EXPECT_NEAR(stex::marginal_distance(img), 2.0 * (2.0 * Phi1 - 1.5 - phi0 + 2.0 * phi1), 1e-3);
}

struct Labelled {
  std::string name, expected;
  Image image;
};

// The labelled set: each exemplar's kind is what its construction or content makes it, not what the
// classifier said. Thresholds and measured values: docs/auto.md.
TEST(KindChoice, PicksTheExpectedKindOnALabelledSet) {
  std::vector<Labelled> set;
  // Micro-textures: Gaussian by construction.
  for (const char* name : {"gravel.png", "grass.png", "leaves.png", "brick.png"})
    set.push_back({std::string("ADSN of ") + name, "texton", adsn(data(name), 3)});
  // Structured stochastic textures: no lattice, structure in the phases.
  for (const char* name : {"gravel.png", "grass.png", "leaves.png"}) set.push_back({name, "tb", data(name)});
  set.push_back({"thresholded ADSN of grass.png", "tb", threshold(adsn(data("grass.png"), 5))});
  // Near-regular textures whose cells differ in structure (stones, marble veins, glaze, holes): a lattice, and
  // far from Gaussian once the cyclic mean is removed.
  for (const char* name : {"tiles_marble.png", "tiles_stone.png", "tiles_green.png", "perforated_metal.png"})
    set.push_back({name, "cs-tb", data(name)});
  // Cyclostationary textures that are a periodic motif plus a small Gaussian-like variation: S4's CS model
  // (the cyclic mean and a CS Gaussian around it). The generated tilings (analysis/near_regular.h: one motif,
  // per-cell colour offsets of 0.05, contrast 0.15, shifts below 0.1 px, white noise 0.02) and the ADSN of an
  // exactly periodic image (periodic with it, Gaussian).
  set.push_back({"generated tiling 32 px, 10 deg, grey", "cs-spot", stex::make_near_regular(tiling(32.0, 10.0, 1, 4))});
  set.push_back({"generated tiling 21 px, 0 deg, colour", "cs-spot", stex::make_near_regular(tiling(21.0, 0.0, 3, 5))});
  set.push_back({"ADSN of a 64 px cell of gravel.png, 4x4", "cs-spot", adsn(periodic(data("gravel.png"), 64, 4), 11)});
  set.push_back({"ADSN of a 64 px cell of grass.png, 4x4", "cs-spot", adsn(periodic(data("grass.png"), 64, 4), 13)});
  ASSERT_GE(set.size(), 12u);
  int right = 0;
  for (const Labelled& l : set) {
    const auto t0 = std::chrono::steady_clock::now();
    const stex::KindChoice ch = stex::choose_kind(l.image, k_all);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(ch.kind, l.expected) << l.name << ": " << ch.why;
    right += ch.kind == l.expected;
    std::printf("%-48s %-8s %6.0f ms  %s\n", l.name.c_str(), ch.kind.c_str(), ms, ch.why.c_str());
  }
  std::printf("%d of %zu picked as labelled\n", right, set.size());
}

// `allowed` restricts the pick to the next best kind of the case.
TEST(KindChoice, AllowedKindsRestrictThePick) {
  const Image stone = data("tiles_stone.png");
  EXPECT_EQ(stex::choose_kind(stone, {"texton", "tb"}).kind, "tb");  // near-regular, but no cs kind allowed
  EXPECT_FALSE(stex::choose_kind(stone, {"texton", "tb"}).lattice_searched);
  EXPECT_EQ(stex::choose_kind(stone, {"cs-spot", "texton"}).kind, "cs-spot");
  EXPECT_EQ(stex::choose_kind(stone, {"texton"}).kind, "texton");
  EXPECT_NE(stex::choose_kind(stone, {"texton"}).why.find("tb would suit it best"), std::string::npos);
  EXPECT_THROW(stex::choose_kind(stone, {}), stex::Error);
}

TEST(KindChoice, TinyExemplarIsAnInputError) {
  Image img;
  img.width = 1;
  img.height = 5;
  img.channels = 1;
  img.pixels.assign(5, 0.5f);
  try {
    stex::gradient_ratio(img);
    FAIL() << "no error";
  } catch (const stex::Error& e) {
    EXPECT_EQ(e.kind(), stex::ErrorKind::Input);
  }
}

}  // namespace
