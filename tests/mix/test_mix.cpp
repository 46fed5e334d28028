// Noise mixing (S1 §7, kind "mix"): the OT barycentre tau_rho (endpoints, geodesic distances), the textons
// from one shared initial noise (level K-1 is exactly v's texton), the device kernel against the C++
// reference bit for bit for every map, tile/chunk/work-group invariance, the render statistics at rho = 0 and
// 1 against the end models, gradient statistics across region boundaries against inside (no discontinuity,
// with a control that has one), the codec, the map parser, and `stex analyze-mix` + `stex render --mix-map`.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/gaussian_model.h"
#include "analysis/image_io.h"
#include "analysis/mix.h"
#include "model/codecs.h"
#include "model/kinds.h"
#include "analysis/ot_distance.h"
#include "analysis/texton.h"
#include "cli_run.h"
#include "filter_quality.h"
#include "sanitizer.h"
#include "core/error.h"
#include "kernels/shared/rng.h"
#include "runtime/context.h"
#include "runtime/mix_renderer.h"
#include "test_device.h"

namespace stex {
namespace {

namespace fs = std::filesystem;

Context& ctx() {
  static std::unique_ptr<Context> c = Context::create(stex::test::test_device_spec());
  return *c;
}

// Uniform in [0, 1) from the counter RNG (test domain), so that the exemplars are the same everywhere.
double uni(int x, int y, int k) {
  return stex_uniform24(stex_draw(stex_cell_key(x, y), 7u, 0u, stex_u32(k), STEX_DOMAIN_TEST).x);
}

// Two procedural W x W exemplars of different character and mean: u isotropic blobs (white noise through a
// 5x5 circular box), v horizontal streaks (white noise through a 15x1 box plus a vertical cosine).
Image exemplar(int which, int w, int channels) {
  Image im{w, w, channels, std::vector<float>(std::size_t(w) * w * channels)};
  for (int c = 0; c < channels; ++c)
    for (int y = 0; y < w; ++y)
      for (int x = 0; x < w; ++x) {
        double s = 0.0;
        if (which == 0) {
          for (int dy = -2; dy <= 2; ++dy)
            for (int dx = -2; dx <= 2; ++dx) s += uni((x + dx + w) % w, (y + dy + w) % w, c) - 0.5;
          s = 0.4 + 0.1 * s / 5.0 + 0.02 * c;
        } else {
          for (int dx = -7; dx <= 7; ++dx) s += uni((x + dx + w) % w, y, 8 + c) - 0.5;
          s = 0.6 + 0.08 * s / std::sqrt(15.0) + 0.05 * std::cos(2.0 * M_PI * 4.0 * y / w + c);
        }
        im.pixels[(std::size_t(y) * w + x) * channels + c] = float(s);
      }
  return im;
}

MixParams small_params(int levels = 5) {
  MixParams p;
  p.levels = levels;
  p.support = 12;
  p.iterations = 20;
  p.seed = 3;
  return p;
}

const MixModel& grey_model() {
  static const MixModel m = analyse_mix(exemplar(0, 64, 1), exemplar(1, 64, 1), small_params());
  return m;
}

MixModel with_map(MixModel m, const std::string& spec) {
  if (!parse_analytic_mix_map(spec, &m.map)) ADD_FAILURE() << spec;
  return m;
}

MixMap small_image_map(bool clamp) {
  MixMap m;
  m.type = MixMap::Type::Image;
  m.map_width = 5;
  m.map_height = 4;
  for (int i = 0; i < 20; ++i) m.grey.push_back(float(uni(i, 99, 0)));
  m.scale = 7.5;
  m.origin_x = -3;
  m.origin_y = 5;
  m.clamp = clamp;
  m.name = "test";
  return m;
}

std::vector<float> device_render(const MixModel& m, const RenderParams& rp, std::int64_t x, std::int64_t y, int w,
                                 int h, std::array<std::size_t, 2> local = {0, 0}, std::size_t chunk = 0) {
  MixNoise n(ctx(), m);
  n.local_size = local;
  n.max_chunk_pixels = chunk;
  std::vector<float> out(std::size_t(w) * h * m.channels);
  n.render(rp, x, y, w, h, out.data());
  return out;
}

GaussianSpectrum spectrum(const NormalisedKernel& k) { return gaussian_spectrum(k, k.width, k.height); }

// --- barycentre -----------------------------------------------------------------------------------------

void check_barycentre(int channels) {
  const NormalisedKernel tu = normalised_kernel(exemplar(0, 48, channels)), tv = normalised_kernel(exemplar(1, 48, channels));
  const MixBarycentre b = mix_barycentre(tu, tv);
  // Endpoints exact: tau_rho at rho = 1 is t_v, at rho = 0 tau_0, bit for bit; tau_0 is t_u's model.
  EXPECT_EQ(b.at(1.0).t, tv.t);
  EXPECT_EQ(b.at(0.0).t, b.tau0.t);
  for (int c = 0; c < channels; ++c) {
    EXPECT_EQ(b.at(0.0).mean[c], tu.mean[c]);
    EXPECT_EQ(b.at(1.0).mean[c], tv.mean[c]);
    EXPECT_DOUBLE_EQ(b.at(0.25).mean[c], 0.75 * tu.mean[c] + 0.25 * tv.mean[c]);
  }
  const OtDistance self = ot_distance(spectrum(b.tau0), spectrum(tu));
  EXPECT_LE(self.d2, 1e-12 * self.variance0) << "tau_0 must have t_u's covariance";
  const double d = ot_distance(spectrum(b.tau0), spectrum(b.tau1)).distance();
  EXPECT_NEAR(d, ot_distance(spectrum(tu), spectrum(tv)).distance(), 1e-9 * d);
  ASSERT_GT(d, 0.0);
  // The displacement interpolation: d(tau_0, tau_rho) = rho d, d(tau_rho, tau_1) = (1 - rho) d (mix.h derives
  // it; rounding only: 1e-7 relative).
  double naive_worst = 0.0;
  for (double rho : {0.125, 0.25, 0.5, 0.75, 0.9}) {
    const GaussianSpectrum g = spectrum(b.at(rho));
    EXPECT_NEAR(ot_distance(spectrum(b.tau0), g).distance(), rho * d, 1e-7 * d) << rho;
    EXPECT_NEAR(ot_distance(g, spectrum(b.tau1)).distance(), (1.0 - rho) * d, 1e-7 * d) << rho;
    // Control: interpolating t_u and t_v without the phase alignment is not on the geodesic.
    NormalisedKernel naive = tu;
    for (std::size_t i = 0; i < naive.t.size(); ++i) naive.t[i] = (1.0 - rho) * tu.t[i] + rho * tv.t[i];
    naive_worst = std::max(naive_worst, std::fabs(ot_distance(spectrum(tu), spectrum(naive)).distance() - rho * d) / d);
  }
  EXPECT_GT(naive_worst, 0.01);  // measured 0.033 (colour) and above: 5 orders above the tolerance
  EXPECT_THROW(b.at(1.5), Error);
}

TEST(MixBarycentre, EndpointsExactAndOnTheOtGeodesicGrey) { check_barycentre(1); }
TEST(MixBarycentre, EndpointsExactAndOnTheOtGeodesicColour) { check_barycentre(3); }

TEST(MixBarycentre, DifferentGridsAreRefused) {
  EXPECT_THROW(mix_barycentre(normalised_kernel(exemplar(0, 32, 1)), normalised_kernel(exemplar(1, 48, 1))), Error);
}

// --- analysis -----------------------------------------------------------------------------------------------

double correlation(const std::vector<float>& a, const std::vector<float>& b) {
  double ab = 0.0, aa = 0.0, bb = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ab += double(a[i]) * b[i];
    aa += double(a[i]) * a[i];
    bb += double(b[i]) * b[i];
  }
  return ab / std::sqrt(aa * bb);
}

TEST(MixAnalysis, SharedInitialNoiseAndExactLastLevel) {
  const MixModel& m = grey_model();
  ASSERT_EQ(m.levels, 5);
  ASSERT_EQ(m.alpha.size(), std::size_t(5 * 12 * 12));
  EXPECT_EQ(m.mean0[0], float(normalised_kernel(exemplar(0, 64, 1)).mean[0]));
  EXPECT_EQ(m.mean1[0], float(normalised_kernel(exemplar(1, 64, 1)).mean[0]));
  // tau_1 = t_v and the same initial noise: level K-1 is v's own texton, bit for bit.
  TextonParams tp;
  tp.support = 12;
  tp.iterations = 20;
  tp.seed = 3;
  const TextonModel tv = analyse_texton(exemplar(1, 64, 1), tp);
  EXPECT_EQ(m.level_model(4).alpha, tv.alpha);
  // Level 0: Algorithm 1 on tau_0 from the same noise.
  const MixBarycentre b = mix_barycentre(normalised_kernel(exemplar(0, 64, 1)), normalised_kernel(exemplar(1, 64, 1)));
  const std::vector<double> noise = texton_initial_noise(64, 64, 1, 3);
  tp.alpha0 = &noise;
  EXPECT_EQ(m.level_model(0).alpha, analyse_texton_kernel(b.tau0, tp).alpha);
  // The shared noise makes neighbouring levels comparable textures (S1 §7): their textons correlate (measured
  // 0.29 for rho 0 -> 0.25, where v's cosine peak enters, then 0.88..0.91), while level k + 1 against the
  // same barycentre's texton from another seed's noise does not (|corr| <= 0.16): each shared correlation
  // exceeds every other-seed one, and on average by far.
  tp.alpha0 = nullptr;
  tp.seed = 4;
  std::vector<double> shared, other;
  for (int k = 0; k + 1 < m.levels; ++k) {
    shared.push_back(correlation(m.level_model(k).alpha, m.level_model(k + 1).alpha));
    other.push_back(std::fabs(
        correlation(m.level_model(k + 1).alpha, analyse_texton_kernel(b.at(m.level_rho(k + 1)), tp).alpha)));
  }
  const double max_other = *std::max_element(other.begin(), other.end());
  double mean_shared = 0.0, mean_other = 0.0;
  for (std::size_t k = 0; k < shared.size(); ++k) {
    EXPECT_GT(shared[k], max_other) << k;
    mean_shared += shared[k] / shared.size();
    mean_other += other[k] / other.size();
  }
  EXPECT_GT(mean_shared, 0.6);
  EXPECT_LT(mean_other, 0.2);
  // The colour correction gives each level its barycentre's variance: level 0's is u's.
  const NormalisedKernel tu = normalised_kernel(exemplar(0, 64, 1));
  EXPECT_NEAR(model_colour_covariance(m.level_model(0).alpha, 1, 12, 1)[0], exemplar_colour_covariance(tu)[0],
              1e-6 * exemplar_colour_covariance(tu)[0]);
  EXPECT_EQ(m.rme.size(), 5u);
  EXPECT_GT(m.ot_distance, 0.0);
}

TEST(MixAnalysis, GreyWithColourAndDifferentSizes) {
  MixReport rep;
  const MixModel m = analyse_mix(exemplar(0, 40, 1), exemplar(1, 48, 3), small_params(3), &rep);
  EXPECT_EQ(m.channels, 3);
  EXPECT_EQ(m.exemplar_width, 40);
  // Replication, cropping, then (rho = 0 is a grey texture in 3 channels) the singular colour correction.
  ASSERT_GE(rep.warnings.size(), 2u);
  EXPECT_NE(rep.warnings[0].find("replicated"), std::string::npos);
  EXPECT_NE(rep.warnings[1].find("cropped"), std::string::npos);
  MixParams p = small_params(1);
  EXPECT_THROW(analyse_mix(exemplar(0, 32, 1), exemplar(1, 32, 1), p), Error);
  p = small_params();
  p.support = 40;
  EXPECT_THROW(analyse_mix(exemplar(0, 32, 1), exemplar(1, 32, 1), p), Error);
}

// --- kernel vs reference, invariance -----------------------------------------------------------------------

// A colour mix of cubic textons (4 levels), analysed once.
const MixModel& colour_cubic_model() {
  static const MixModel m = [] {
    MixParams cp = small_params(4);
    cp.order = 3;
    return analyse_mix(exemplar(0, 48, 3), exemplar(1, 48, 3), cp);
  }();
  return m;
}

TEST(MixKernel, EqualsReferenceBitForBitForEveryMap) {
  const MixModel grey = grey_model();
  const MixModel& colour = colour_cubic_model();
  RenderParams rp;
  rp.seed = 11;
  rp.mni = 20;
  for (const char* spec : {"const:0.3", "ramp:-10:40", "ramp:30:5", "strips:24", "strips:32:10"}) {
    for (const MixModel* base : {&grey, &colour}) {
      const MixModel m = with_map(*base, spec);
      EXPECT_EQ(device_render(m, rp, -7, 3, 48, 24), MixReference(m, rp).render(-7, 3, 48, 24))
          << spec << " channels " << m.channels;
    }
  }
  for (bool clamp : {false, true}) {
    MixModel m = grey;
    m.map = small_image_map(clamp);
    EXPECT_EQ(device_render(m, rp, -20, -4, 64, 40), MixReference(m, rp).render(-20, -4, 64, 40)) << clamp;
  }
  // Far from the origin (10^12 pixels): the same bits, the map still periodic.
  MixModel far = with_map(grey, "strips:24:6");
  const std::int64_t x0 = 1000000000000ll;
  EXPECT_EQ(device_render(far, rp, x0, -x0, 32, 16), MixReference(far, rp).render(x0, -x0, 32, 16));
  const MixReference ref(far, rp);
  EXPECT_EQ(ref.rho_pixel(x0 + 5, 0), ref.rho_pixel(x0 + 5 - 24 * 1000, 0));
}

TEST(MixKernel, TilesChunksAndWorkGroupsGiveTheSameBits) {
  const MixModel m = with_map(grey_model(), "strips:40:12");
  RenderParams rp;
  rp.seed = 5;
  const int w = 72, h = 40;
  const std::vector<float> whole = device_render(m, rp, 10, -20, w, h);
  EXPECT_EQ(device_render(m, rp, 10, -20, w, h, {8, 2}), whole);
  EXPECT_EQ(device_render(m, rp, 10, -20, w, h, {0, 0}, 100), whole);
  std::vector<float> tiled(whole.size());
  for (int ty = 0; ty < h; ty += 17)
    for (int tx = 0; tx < w; tx += 23) {
      const int tw = std::min(23, w - tx), th = std::min(17, h - ty);
      const std::vector<float> t = device_render(m, rp, 10 + tx, -20 + ty, tw, th);
      for (int j = 0; j < th; ++j)
        for (int i = 0; i < tw; ++i) tiled[std::size_t(ty + j) * w + tx + i] = t[std::size_t(j) * tw + i];
    }
  EXPECT_EQ(tiled, whole);
  rp.seed = 6;
  EXPECT_NE(device_render(m, rp, 10, -20, w, h), whole);
  // The renderer behind `stex render` and the farm (model/kinds.h) is this one.
  std::unique_ptr<NoiseRenderer> r = make_noise_renderer(ctx(), to_container(m));
  EXPECT_EQ(r->kind(), "mix");
  std::vector<float> via(whole.size());
  rp.seed = 5;
  r->render(rp, 10, -20, w, h, via.data());
  EXPECT_EQ(via, whole);
}

// --- filtering of minified views (docs/filtering.md) -----------------------------------------------------

// A filtered minified view reads each level's texton convolved with the pixel's box (kernel mix_filtered): the
// device equals the reference bit for bit for every map, order 1 and 3, across tiles, chunks and work-group
// sizes; unfiltered parameters (filter off, or scale >= 1) keep the unfiltered kernel's bits.
TEST(MixFilter, DeviceEqualsReferenceBitForBitAcrossTilings) {
  const MixModel& colour = colour_cubic_model();
  RenderParams rp;
  rp.seed = 13;
  rp.mni = 20;
  rp.filter = true;
  for (double scale : {0.5, 0.125, 0.03}) {
    rp.scale = scale;
    for (const char* spec : {"ramp:-10:40", "strips:24:6"}) {
      for (const MixModel* base : {&grey_model(), &colour}) {
        const MixModel m = with_map(*base, spec);
        const std::vector<float> ref = MixReference(m, rp).render(-7, 3, 40, 24);
        EXPECT_EQ(device_render(m, rp, -7, 3, 40, 24), ref) << spec << " scale " << scale << " order " << m.order;
        EXPECT_EQ(device_render(m, rp, -7, 3, 40, 24, {8, 2}, 90), ref) << "work groups, chunks";
      }
    }
  }
  MixModel img = grey_model();
  img.map = small_image_map(false);
  rp.scale = 0.25;
  const std::vector<float> whole = device_render(img, rp, -20, -4, 48, 30);
  EXPECT_EQ(whole, MixReference(img, rp).render(-20, -4, 48, 30));
  std::vector<float> tiled(whole.size());
  for (int ty = 0; ty < 30; ty += 13)
    for (int tx = 0; tx < 48; tx += 19) {
      const int tw = std::min(19, 48 - tx), th = std::min(13, 30 - ty);
      const std::vector<float> t = device_render(img, rp, -20 + tx, -4 + ty, tw, th);
      for (int j = 0; j < th; ++j)
        for (int i = 0; i < tw; ++i) tiled[std::size_t(ty + j) * 48 + tx + i] = t[std::size_t(j) * tw + i];
    }
  EXPECT_EQ(tiled, whole);
  // Unfiltered parameters: the plain kernel's bits.
  const MixModel m = with_map(grey_model(), "ramp:0:30");
  RenderParams plain = rp;
  plain.filter = false;
  RenderParams magnified = rp;
  magnified.scale = 1.5;
  EXPECT_EQ(MixReference(m, magnified).render(0, 0, 24, 16), [&] {
    RenderParams q = magnified;
    q.filter = false;
    return MixReference(m, q).render(0, 0, 24, 16);
  }());
  EXPECT_NE(MixReference(m, rp).render(0, 0, 24, 16), MixReference(m, plain).render(0, 0, 24, 16));
}

// Against the box reference of the same realisation (16 x 16 point samples per pixel, tests/filter_quality.h),
// a constant map (one level, a texton noise with random signs) at 1/2 .. 1/16: within 0.25 of the reference's
// sd (issue 31's bound; measured 0.017 - 0.027) and keeping at least 0.9 of it, while the point-sampled render
// is at least twice as far. Within 0.05 sd of a reference with at least one sample per texel at every scale to
// 1/64 (32 x 32 at 1/32, 64 x 64 at 1/64: measured 0.013 - 0.016; the box prefilter's table interpolation, as
// for texton noise), which also takes the bounds from 1/32 on. A ramp map (levels and mean changing across the view,
// so the sd includes the mean's ramp) is held to the same bounds at 1/2 and 1/4.
TEST(MixFilter, QualityAgainstTheSupersampledBoxReference) {
  if (test::k_under_asan) GTEST_SKIP() << "host statistics only (16 x 16 samples per pixel)";
  for (const char* spec : {"const:0.5", "ramp:0:16"}) {
    const MixModel m = with_map(grey_model(), spec);
    for (int k = 1; k <= (spec[0] == 'c' ? 6 : 2); ++k) {
      RenderParams rp;
      rp.seed = 31;
      rp.mni = 30;
      rp.scale = std::ldexp(1.0, -k);
      const MixReference point(m, rp);
      auto eval = [&](std::int64_t fx, std::int64_t fy, float* v) {
        stex_mix_eval(point.setup().texton.params, point.setup().mix, point.setup().alpha_levels.data(),
                      point.setup().map.data(), point.setup().texton.poisson_table.data(), fx, fy, v);
      };
      const std::vector<float> box = test::box_supersampled(eval, m.channels, -5, 7, 16, 16);
      // From 1/32 on, 16 samples per axis are 2 and 4 texels apart: a reference with one per texel as well.
      const std::vector<float> fine = k <= 4 ? box : test::box_supersampled(eval, m.channels, -5, 7, 16, 16, 1 << k);
      RenderParams frp = rp;
      frp.filter = true;
      const std::vector<float> f = MixReference(m, frp).render(-5, 7, 16, 16);
      const std::vector<float> u = point.render(-5, 7, 16, 16);
      const double sd = test::stddev(box), ef = test::rms_diff(f, box), eu = test::rms_diff(u, box);
      const double ef_fine = test::rms_diff(f, fine) / test::stddev(fine);
      std::printf("mix %s, scale 1/%d: box sd %.4g; filtered %.3f sd (sd kept %.3f; per-texel reference %.3f sd); "
                  "point-sampled %.3f sd\n", spec, 1 << k, sd, ef / sd, test::stddev(f) / sd, ef_fine, eu / sd);
      // From 1/32 on the 16 x 16 reference is no box filter (it aliases: 0.36 and 0.63 sd off the per-texel one
      // at 1/32 and 1/64 for this 12-texel texton): the bounds there hold against the per-texel reference.
      const std::vector<float>& ref = k <= 4 ? box : fine;
      EXPECT_LT(test::rms_diff(f, ref), 0.25 * test::stddev(ref)) << spec << " scale 1/" << (1 << k);
      EXPECT_LT(ef_fine, 0.05) << spec << " scale 1/" << (1 << k);
      EXPECT_GT(test::stddev(f), 0.9 * test::stddev(ref)) << spec << " scale 1/" << (1 << k);
      EXPECT_GT(eu, 2.0 * ef) << spec << " scale 1/" << (1 << k);
    }
  }
}

// --- statistics --------------------------------------------------------------------------------------------

// At rho = 0 (1) the render is texton noise of level 0 (K-1) with random signs: mean m0 (m1) and covariance
// C(t) = sum_l R(l) b(t - l) of that level's texton (analysis/gaussian_model.h). Estimator per seed: the mean
// of the pixels, and the mean of (f(x) - m)(f(x + t) - m) with the theoretical m (unbiased). Over 8 seeds
// (independent realisations) each statistic's tolerance is t_{7, 0.9995} = 5.41 standard errors of the mean
// over seeds, the standard error estimated from the 8 values: a test of the estimator's own variance, valid
// without assuming the field Gaussian (MNI 30 shot noise is not quite).
TEST(MixStats, ConstantMapsHaveTheEndModelsStatistics) {
  const MixModel& base = grey_model();
  const int n = 192, seeds = 8;
  const std::array<std::array<int, 2>, 5> lags{{{0, 0}, {1, 0}, {0, 1}, {2, 0}, {1, 1}}};
  for (int end = 0; end < 2; ++end) {
    const MixModel m = with_map(base, end == 0 ? "const:0" : "const:1");
    const TextonModel level = m.level_model(end == 0 ? 0 : m.levels - 1);
    const double mean = end == 0 ? m.mean0[0] : m.mean1[0];
    std::vector<std::vector<double>> stats(lags.size() + 1);
    MixNoise noise(ctx(), m);
    for (int s = 0; s < seeds; ++s) {
      RenderParams rp;
      rp.seed = 100 + s;
      std::vector<float> f(std::size_t(n) * n);
      noise.render(rp, 0, 0, n, n, f.data());
      double sum = 0.0;
      for (float v : f) sum += v;
      stats[0].push_back(sum / f.size() - mean);
      for (std::size_t l = 0; l < lags.size(); ++l) {
        const int dx = lags[l][0], dy = lags[l][1];
        double c = 0.0;
        for (int y = 0; y + dy < n; ++y)
          for (int x = 0; x + dx < n; ++x)
            c += (f[std::size_t(y) * n + x] - mean) * (f[std::size_t(y + dy) * n + x + dx] - mean);
        stats[l + 1].push_back(c / double((n - dx) * (n - dy)) -
                               model_covariance(level.alpha, 1, level.support, level.order, 0, 0, dx, dy));
      }
    }
    for (std::size_t k = 0; k < stats.size(); ++k) {
      double mu = 0.0, var = 0.0;
      for (double v : stats[k]) mu += v / seeds;
      for (double v : stats[k]) var += (v - mu) * (v - mu) / (seeds - 1);
      const double se = std::sqrt(var / seeds);
      EXPECT_LE(std::fabs(mu), 5.41 * se) << "end " << end << " statistic " << k << " (0: mean, then lags)";
      EXPECT_GT(se, 0.0);
    }
  }
  // The end models are the exemplars' models: level 0's variance is u's (colour correction), level K-1 is
  // v's texton (MixAnalysis.SharedInitialNoiseAndExactLastLevel).
  const NormalisedKernel tu = normalised_kernel(exemplar(0, 64, 1));
  EXPECT_NEAR(model_covariance(base.level_model(0).alpha, 1, 12, 1, 0, 0, 0, 0), exemplar_colour_covariance(tu)[0],
              1e-6 * exemplar_colour_covariance(tu)[0]);
}

// Mean squared horizontal difference per column, D(x) = mean_y (f(x + 1, y) - f(x, y) - (m(x + 1) - m(x)))^2.
std::vector<double> column_msd(const std::vector<float>& f, const std::vector<double>& mean, int w, int h) {
  std::vector<double> d(std::size_t(w - 1), 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x + 1 < w; ++x) {
      const double g = double(f[std::size_t(y) * w + x + 1]) - f[std::size_t(y) * w + x] - (mean[x + 1] - mean[x]);
      d[x] += g * g / h;
    }
  return d;
}

// S1 Fig. 5's setting: a ramp over 640 pixels quantised to K = 5 levels gives regions [0, 80), [80, 240),
// [240, 400), [400, 560), [560, 640) (boundaries where rho(x_j) crosses (r + 1/2) / 4). The textons switch at
// the impulses, so the field is continuous: D(x) for the pixel pairs at a boundary lies between the two
// regions' D (S1: "no undesirable discontinuity ... because the kernel functions are locally blended").
// Each boundary is rendered as a window of 96 columns x 2048 rows around it; its columns farther than the
// texton width r from the boundary are the two regions' interiors. Tolerance: the standard deviation of one
// column's D, estimated by the spread of D over those interior columns (identically distributed), times
// 4.5, plus half the difference of the two regions' means. Control: the same impulses with the texton
// switched per pixel (left of the boundary the rho = level r render, right of it level r + 1: a seam) must
// fail that bound.
TEST(MixStats, NoDiscontinuityAtRegionBoundaries) {
  const MixModel m = with_map(grey_model(), "ramp:0:640");
  const int h = 2048, half_w = 48, w = 2 * half_w;
  RenderParams rp;
  rp.seed = 21;
  const MixReference ref(m, rp);
  const int r = m.support + m.order;  // texton width: columns farther than r from a boundary are interior
  auto stats = [&](const std::vector<double>& d, int lo, int hi, double* mu, double* sd) {
    double s = 0.0, s2 = 0.0;
    for (int x = lo; x < hi; ++x) {
      s += d[x];
      s2 += d[x] * d[x];
    }
    *mu = s / (hi - lo);
    *sd = std::sqrt(std::max(0.0, s2 / (hi - lo) - *mu * *mu));
  };
  for (int k = 1; k <= 3; ++k) {
    const int xb = 80 + 160 * (k - 1), x0 = xb - half_w;  // boundary between levels k - 1 and k
    const std::vector<float> f = device_render(m, rp, x0, 0, w, h);
    std::vector<double> mean(w);
    for (int i = 0; i < w; ++i) {
      const float rho = ref.rho_pixel(x0 + i, 0);
      mean[i] = double((1.0f - rho) * m.mean0[0] + rho * m.mean1[0]);
    }
    const std::vector<double> d = column_msd(f, mean, w, h);  // d[i]: pair (x0 + i, x0 + i + 1)
    double mu0, sd0, mu1, sd1;
    stats(d, 0, half_w - r, &mu0, &sd0);
    stats(d, half_w + r, w - 1, &mu1, &sd1);
    const double centre = 0.5 * (mu0 + mu1), band = 0.5 * std::fabs(mu0 - mu1) + 4.5 * std::max(sd0, sd1);
    for (int i = half_w - 3; i <= half_w + 2; ++i)
      EXPECT_LE(std::fabs(d[i] - centre), band) << "boundary " << xb << " column " << x0 + i << ": D " << d[i]
                                                << ", inside " << mu0 << " and " << mu1;
    // Control with a seam: the same impulses and signs, level k - 1 left of the boundary, level k right.
    const MixModel left = with_map(m, "const:" + std::to_string(double(k - 1) / 4.0));
    const MixModel right = with_map(m, "const:" + std::to_string(double(k) / 4.0));
    const int sx = xb - 8;
    const std::vector<float> fl = device_render(left, rp, sx, 0, 16, h), fr = device_render(right, rp, sx, 0, 16, h);
    std::vector<float> seam(fl.size());
    for (int y = 0; y < h; ++y)
      for (int i = 0; i < 16; ++i) seam[std::size_t(y) * 16 + i] = (i < 8 ? fl : fr)[std::size_t(y) * 16 + i];
    // Each side's own (constant) mean, so that D measures the texture seam, not the mean step.
    std::vector<double> side_mean(16);
    for (int i = 0; i < 16; ++i) {
      const float rho = float(i < 8 ? k - 1 : k) / 4.0f;
      side_mean[i] = double((1.0f - rho) * m.mean0[0] + rho * m.mean1[0]);
    }
    const double seam_d = column_msd(seam, side_mean, 16, h)[7];
    std::printf("boundary %d: inside %.4g (sd %.3g) and %.4g (sd %.3g); at the boundary", xb, mu0, sd0, mu1, sd1);
    for (int i = half_w - 3; i <= half_w + 2; ++i) std::printf(" %.4g", d[i]);
    std::printf("; band %.3g; control seam %.4g\n", band, seam_d);
    EXPECT_GT(std::fabs(seam_d - centre), band) << "the control seam at " << xb << " should be detected: D "
                                                << seam_d << " vs " << centre << " +- " << band;
  }
}

// --- model file, maps, CLI ---------------------------------------------------------------------------------

TEST(MixModelFile, RoundTripAndValidation) {
  MixModel m = grey_model();
  const MixModel back = mix_from_container(decode_container(encode_container(to_container(m)).data(),
                                                            encode_container(to_container(m)).size()));
  EXPECT_EQ(back.alpha, m.alpha);
  EXPECT_EQ(back.levels, m.levels);
  EXPECT_EQ(back.mean0, m.mean0);
  EXPECT_EQ(back.mean1, m.mean1);
  EXPECT_EQ(mix_map_spec(back.map), mix_map_spec(m.map));
  EXPECT_EQ(back.rme, m.rme);
  m.map = small_image_map(true);
  const MixModel img = mix_from_container(to_container(m));
  EXPECT_EQ(img.map.grey, m.map.grey);
  EXPECT_TRUE(img.map.clamp);
  EXPECT_EQ(img.map.origin_y, 5);
  // Bad fields: Error(Input) naming them.
  auto expect_bad = [](ModelContainer c, const std::string& word) {
    try {
      mix_from_container(c, "t");
      ADD_FAILURE() << "accepted: " << word;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  ModelContainer c = to_container(grey_model());
  ModelContainer b = c;
  b.metadata["levels"] = 1;
  expect_bad(b, "levels");
  b = c;
  b.payload.pop_back();
  expect_bad(b, "payload");
  b = c;
  b.metadata["map"]["type"] = "spiral";
  expect_bad(b, "map.type");
  b = c;
  b.metadata["map"] = {{"type", "const"}, {"rho", 2.0}};
  expect_bad(b, "rho");
  b = c;
  b.kind = "texton";
  expect_bad(b, "kind");
  EXPECT_THROW(texton_from_container(c), Error);
}

TEST(MixMapSpec, ParsesAndRefuses) {
  MixMap m;
  ASSERT_TRUE(parse_analytic_mix_map("strips:64:16", &m));
  EXPECT_EQ(m.type, MixMap::Type::Strips);
  EXPECT_EQ(m.width, 16.0);
  ASSERT_TRUE(parse_analytic_mix_map("ramp:-5:100.5", &m));
  EXPECT_EQ(m.x1, 100.5);
  EXPECT_FALSE(parse_analytic_mix_map("some/file.png", &m));
  for (const char* bad : {"const:1.5", "const:", "ramp:5:5", "ramp:1", "strips:100:60", "strips:0", "strips:x"}) {
    try {
      parse_analytic_mix_map(bad, &m);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Usage) << bad;
    }
  }
  try {
    parse_mix_map((fs::path(STEX_TEST_TMP_DIR) / "missing.png").string(), 1.0, "0,0", "repeat", false);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
  }
  EXPECT_THROW(parse_mix_map("const:0.5", 2.0, "0,0", "repeat", true), Error);
  EXPECT_THROW(parse_mix_map("x.png", 1.0, "0,0", "mirror", true), Error);
  EXPECT_THROW(parse_mix_map("x.png", 1.0, "0;0", "repeat", true), Error);
  // Strips map values: 0 inside the first half period, 1 inside the second, ramps of width W at the edges.
  MixModel mm = with_map(grey_model(), "strips:40:8");
  const MixReference ref(mm, RenderParams{});
  EXPECT_EQ(ref.rho_pixel(10, 0), 0.0f);
  EXPECT_EQ(ref.rho_pixel(30, 0), 1.0f);
  EXPECT_FLOAT_EQ(ref.rho_pixel(20, 0), 0.5f + 0.5f / 8.0f);  // pixel centre 20.5, edge at 20
  EXPECT_FLOAT_EQ(ref.rho_pixel(-1, 0), 0.5f + 0.5f / 8.0f);  // centre -0.5, the falling edge at 0
}

using stex::test::CliRun;
CliRun stex(const std::string& args) { return stex::test::run_stex_cli(args, "mix_cli_io"); }

TEST(MixCli, AnalyzeMixAndRenderEqualTheLibrary) {
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / "mix_cli";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string a = (dir / "a.exr").string(), b = (dir / "b.exr").string(), model = (dir / "m.stex").string();
  write_image_atomic(a, exemplar(0, 48, 1));
  write_image_atomic(b, exemplar(1, 48, 1));
  CliRun r = stex("analyze-mix '" + a + "' '" + b + "' -o '" + model +
                  "' --levels 4 --support 10 --iterations 15 --seed 2 --mix-map strips:32:8");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("levels          4"), std::string::npos) << r.out;
  MixParams p = small_params(4);
  p.support = 10;
  p.iterations = 15;
  p.seed = 2;
  parse_analytic_mix_map("strips:32:8", &p.map);
  const MixModel lib = analyse_mix(load_exemplar(a), load_exemplar(b), p);
  const MixModel file = mix_from_container(load_container(model));
  EXPECT_EQ(file.alpha, lib.alpha);
  EXPECT_EQ(file.exemplar_name[1], "b.exr");
  RenderParams rp;
  rp.seed = 9;
  // The model's map, then a replaced one; tiles through the farm layer give the same image.
  const std::string out = (dir / "r.exr").string();
  r = stex("render '" + model + "' -o '" + out + "' --size 40x24 --origin -8,3 --seed 9");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(load_exemplar(out).pixels, MixReference(file, rp).render(-8, 3, 40, 24));
  r = stex("render '" + model + "' -o '" + out + "' --size 40x24 --origin -8,3 --seed 9 --mix-map ramp:0:40");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<float> ramp = MixReference(with_map(file, "ramp:0:40"), rp).render(-8, 3, 40, 24);
  EXPECT_EQ(load_exemplar(out).pixels, ramp);
  const std::string tiled = (dir / "t.exr").string();
  r = stex("render '" + model + "' -o '" + tiled + "' --size 40x24 --origin -8,3 --seed 9 --mix-map ramp:0:40 "
           "--tile-size 16");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(load_exemplar(tiled).pixels, ramp);
  // An image map: grey PNG, scale and origin.
  Image map{3, 2, 1, {0.0f, 0.5f, 1.0f, 1.0f, 0.25f, 0.0f}};
  const std::string map_path = (dir / "map.png").string();
  write_image_atomic(map_path, map);
  r = stex("render '" + model + "' -o '" + out + "' --size 40x24 --seed 9 --mix-map '" + map_path +
           "' --mix-scale 12 --mix-origin 2,1 --mix-wrap clamp");
  ASSERT_EQ(r.code, 0) << r.err;
  MixModel im = file;
  im.map = mix_map_from_image(map_path, 12.0, 2, 1, true);
  EXPECT_EQ(load_exemplar(out).pixels, MixReference(im, rp).render(0, 0, 40, 24));
  // Bad input: the documented exit codes, a message naming the problem, no output.
  const std::string none = (dir / "none.exr").string();
  r = stex("render '" + model + "' -o '" + none + "' --size 8x8 --mix-map strips:10:9");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("width"), std::string::npos) << r.err;
  r = stex("render '" + model + "' -o '" + none + "' --size 8x8 --mix-map '" + (dir / "missing.png").string() + "'");
  EXPECT_EQ(r.code, 3);
  r = stex("render '" + model + "' -o '" + none + "' --size 8x8 --mix-map const:0 --mix-scale 2");
  EXPECT_EQ(r.code, 2);
  r = stex("render '" + model + "' -o '" + none + "' --size 8x8 --strategy splat");
  EXPECT_EQ(r.code, 2);
  EXPECT_FALSE(fs::exists(none));
  r = stex("analyze-mix '" + a + "' '" + (dir / "missing.png").string() + "' -o '" + (dir / "bad.stex").string() + "'");
  EXPECT_EQ(r.code, 3);
  r = stex("analyze-mix '" + a + "' '" + b + "' -o '" + (dir / "bad.stex").string() + "' --levels 1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("levels"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "bad.stex"));
  // --mix-map on a texton model is a usage error.
  const std::string texton = (dir / "t.stex").string();
  r = stex("analyze '" + a + "' -o '" + texton + "' --support 10 --iterations 5");
  ASSERT_EQ(r.code, 0) << r.err;
  r = stex("render '" + texton + "' -o '" + none + "' --size 8x8 --mix-map const:0");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("mix models"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace stex
