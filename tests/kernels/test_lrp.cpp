// LRP noise (S3): the shared device math against double precision, the kernel against the C++ reference
// (bit for bit), tile/chunk/work-group invariance, determinism, and the render's spectrum against the
// model's target (energy per stratum, leakage outside the strata, variance).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <cmath>
#include <memory>
#include <numeric>
#include <vector>

#include "analysis/fft.h"
#include "analysis/image_io.h"
#include "analysis/lrp.h"
#include "analysis/lrp_psd.h"
#include "model/kinds.h"
#include "core/error.h"
#include "runtime/buffer.h"
#include "runtime/context.h"
#include "runtime/lrp_reference.h"
#include "runtime/program.h"
#ifdef STEX_HAVE_BENCH
#include "benchmarks/lib/lrp_baseline.h"
#endif
#include "runtime/lrp_renderer.h"
#include "filter_quality.h"
#include "test_device.h"

namespace stex {
namespace {

Context& lrp_context() {
  static std::unique_ptr<Context> ctx = Context::create(stex::test::test_device_spec());
  return *ctx;
}

const Image& gravel() {
  static const Image img = load_exemplar(std::string(STEX_SOURCE_DIR) + "/data/gravel.png");
  return img;
}

const LrpSpectrum& gravel_spectrum() {
  static const LrpSpectrum sp = lrp_welch(gravel());
  return sp;
}

// S3 as written (uniform A_S, J / L cosines per stratum, L = 4): the model the checks below and their numbers
// in docs/lrp.md were written for; gravel_fit_model() is the default analysis (LrpAmplitudes::Fit, L = 5).
LrpModel gravel_model(double r = 0.0, double sigma = 0.0, bool placement = false, int cosines = 50) {
  LrpParams p;
  p.amplitudes = LrpAmplitudes::Paper;
  p.strata = 4;
  p.cosines = cosines;
  p.ratio = r;
  p.sigma = sigma;
  p.placement = placement;
  return lrp_from_spectrum(gravel_spectrum(), p);
}

const LrpModel& gravel_fit_model() {
  static const LrpModel m = lrp_from_spectrum(gravel_spectrum(), LrpParams{});
  return m;
}

// A small colour exemplar: a grey gravel crop mixed into three correlated channels plus a shifted copy, so
// that the channels have frequency-dependent relative phases.
Image colour_exemplar() {
  const Image& g = gravel();
  Image c;
  c.width = c.height = 128;
  c.channels = 3;
  c.pixels.resize(128 * 128 * 3);
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) {
      const float a = g.at(x, y, 0), b = g.at(x + 3, y + 1, 0);
      c.at(x, y, 0) = 0.8f * a + 0.1f;
      c.at(x, y, 1) = 0.5f * a + 0.3f * b + 0.1f;
      c.at(x, y, 2) = 0.6f * b + 0.2f;
    }
  return c;
}

std::size_t bit_differences(const std::vector<float>& a, const std::vector<float>& b) {
  EXPECT_EQ(a.size(), b.size());
  std::size_t d = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(float)) != 0) ++d;
  return d;
}

TEST(LrpMath, CosSinAgainstDouble) {
  // The polynomial cos/sin of kernels/shared/lrp.h: error against double cos(2 pi t) over a dense grid of
  // turns, including far from [0, 1). Bound: the float rounding of t (2^-24 relative) times 2 pi plus a few
  // ulp of the result; measured max is printed.
  double worst = 0.0;
  for (int i = -200000; i <= 200000; ++i) {
    const float t = float(i) * 1.3e-5f;
    float c, s;
    stex_lrp_cossin(t, &c, &s);
    const double tt = double(t);
    worst = std::max({worst, std::fabs(c - std::cos(2 * M_PI * tt)), std::fabs(s - std::sin(2 * M_PI * tt))});
  }
  std::printf("max |cos/sin error| vs double: %.3g\n", worst);
  EXPECT_LT(worst, 4e-7);
}

TEST(LrpMath, WindowAgainstDouble) {
  double worst = 0.0;
  for (int i = 0; i <= 30000; ++i) {
    const double y = i * 1.6 / 30000;
    const float y2 = float(y) * float(y);
    worst = std::max(worst, std::fabs(stex_lrp_window_sq(y2) - lrp_window(std::sqrt(double(y2)))));
  }
  std::printf("max |window error| vs double: %.3g\n", worst);
  EXPECT_LT(worst, 5e-7);  // a few float ulp of values <= 1
  EXPECT_FLOAT_EQ(stex_lrp_window_sq(0.0f), 1.0f);
  EXPECT_EQ(stex_lrp_window_sq(2.25f), 0.0f);
}

TEST(LrpMath, WindowIntegralAndErosionConstant) {
  // int_0^1.5 r w^2 dr by a midpoint rule independent of the library's Simpson rule; the paper's 0.1126 is
  // for its 5-term b_3 variant of the window (S3 §4.3), ours uses I0 (0.1196).
  double s = 0.0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double r = (i + 0.5) * 1.5 / n;
    s += r * lrp_window(r) * lrp_window(r) * 1.5 / n;
  }
  EXPECT_NEAR(lrp_window_integral(), s, 1e-7);
  EXPECT_NEAR(lrp_window_integral(), 0.119583, 1e-5);
  const double d1 = lrp_erosion_delta1(0.75);
  std::printf("window integral %.6f, erosion delta_1 (75 %%) %.5f\n", lrp_window_integral(), d1);
  EXPECT_GT(d1, 0.05);
  EXPECT_LT(d1, 0.6);
  EXPECT_LT(lrp_erosion_delta1(0.5), d1);
}

TEST(LrpMath, DeviceCosChoices) {
  // The choice of cos on the device (issue #7): OpenCL's cos (precise, not vectorised on PoCL), native_cos
  // (fast, implementation-defined accuracy, differs across devices) and stex_lrp_cossin (polynomial, IEEE
  // add/mul only). Each is evaluated on the device at 2^16 phases t in [0, 4) turns against double; the
  // polynomial must equal the host's bits and stay within the float bound of CosSinAgainstDouble.
  Context& ctx = lrp_context();
  const std::string src = resolve_kernel_source("lrp.cl") + R"(
__kernel void cos_choices(__global const float* t, __global float* out) {
  const int i = get_global_id(0);
  const float a = 6.28318530717958647692f * t[i];
  float c, s;
  stex_lrp_cossin(t[i], &c, &s);
  out[3 * i] = cos(a);
  out[3 * i + 1] = native_cos(a);
  out[3 * i + 2] = c;
})";
  Program prog(ctx, src, "", "cos choices");
  Kernel k(prog, "cos_choices");
  const int n = 1 << 16;
  std::vector<float> t(n);
  for (int i = 0; i < n; ++i) t[i] = float(i) * (4.0f / n) + 1.7e-6f * float(i % 7);
  Buffer<float> bt(ctx, t), bo(ctx, std::size_t(3) * n, CL_MEM_WRITE_ONLY);
  k.set_arg(0, bt);
  k.set_arg(1, bo);
  k.launch(ctx, NDRange(n));
  const std::vector<float> o = bo.read();
  double err[3] = {0, 0, 0};
  std::size_t host_diff = 0;
  for (int i = 0; i < n; ++i) {
    const double want = std::cos(2 * M_PI * double(t[i]));
    // errors of the function given its float argument (for cos/native_cos the argument 2 pi t is itself
    // rounded: that part is charged to them, as it is what a kernel computes)
    for (int j = 0; j < 3; ++j) err[j] = std::max(err[j], std::fabs(o[3 * i + j] - want));
    float c, s;
    stex_lrp_cossin(t[i], &c, &s);
    if (std::memcmp(&c, &o[3 * i + 2], sizeof(float)) != 0) ++host_diff;
  }
  std::printf("max |error| vs double on %s: cos %.3g, native_cos %.3g, stex_lrp_cossin %.3g\n",
              ctx.info().name.c_str(), err[0], err[1], err[2]);
  EXPECT_EQ(host_diff, 0u);
  EXPECT_LT(err[2], 4e-7);
}

#ifdef STEX_HAVE_BENCH
TEST(LrpMath, FastMathBaselineComputesTheSameNoise) {
  // The benchmark's plain C++ -ffast-math baseline is the same algorithm: same draws, lattice and tables;
  // only libm cos/sin, sqrt and contraction differ. Bound: 450 cosines of amplitude <= 0.04 per pixel
  // with per-term errors ~1e-6 (the phase 2 pi t in float) gives < 1e-3.
  const LrpModel m = gravel_model();
  RenderParams rp;
  rp.seed = 4;
  const LrpSetup s = make_lrp_setup(m, rp);
  std::vector<float> a(64 * 64);
  bench::lrp_fastmath_render(s, 10, 20, 64, 64, a.data(), 2);
  const std::vector<float> b = LrpReference(s).render(10, 20, 64, 64);
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, double(std::fabs(a[i] - b[i])));
  std::printf("fast-math baseline vs reference: max |diff| %.3g\n", worst);
  EXPECT_LT(worst, 1e-3);
  // the variant with the kernel's cos/sin polynomial: only sqrt, the window's series and contraction differ
  // (no 2 pi t rounding), so the same bound holds
  bench::lrp_fastmath_polycos_render(s, 10, 20, 64, 64, a.data(), 2);
  double worst_poly = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) worst_poly = std::max(worst_poly, double(std::fabs(a[i] - b[i])));
  std::printf("fast-math baseline with stex_lrp_cossin vs reference: max |diff| %.3g\n", worst_poly);
  EXPECT_LT(worst_poly, 1e-3);
}
#endif

TEST(LrpColour, NoFalseColours) {
  // colour_exemplar() has RGB = M (a, b) + offset with two grey sources a, b: its colours span a plane of
  // RGB. With one shared phase per cosine and a per-sub-stratum colour vector v in the span of M's columns
  // (the leading eigenvector of M C_ab(f) M^T), every render deviation lies in that plane too, where
  // independent per-channel phases would fill RGB. Check: the rms of the deviation along the plane's normal
  // is below 1e-3 of the rms deviation (float rounding of the colour weights, ~1e-7, times the sum of
  // ~450 terms).
  LrpParams p;
  p.cosines = 30;
  const LrpModel m = analyse_lrp(colour_exemplar(), p);
  ASSERT_EQ(m.channels, 3);
  RenderParams rp;
  rp.seed = 21;
  const std::vector<float> img = LrpReference(m, rp).render(0, 0, 48, 48);
  const double c1[3] = {0.8, 0.5, 0.0}, c2[3] = {0.0, 0.3, 0.6};
  double n[3] = {c1[1] * c2[2] - c1[2] * c2[1], c1[2] * c2[0] - c1[0] * c2[2], c1[0] * c2[1] - c1[1] * c2[0]};
  const double nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (double& v : n) v /= nn;
  double off = 0.0, all = 0.0;
  for (std::size_t i = 0; i < img.size(); i += 3) {
    double d[3];
    for (int c = 0; c < 3; ++c) d[c] = img[i + c] - m.mean[c];
    const double dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
    off += dn * dn;
    all += d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  }
  std::printf("colour: rms off the exemplar's colour plane / rms deviation = %.3g\n", std::sqrt(off / all));
  EXPECT_LT(std::sqrt(off / all), 1e-3);
  EXPECT_GT(all, 0.0);
}

struct Case {
  const char* name;
  LrpModel model;
};

std::vector<Case> cases() {
  std::vector<Case> c;
  c.push_back({"gravel r=0", gravel_model()});
  c.push_back({"gravel r=0 fitted amplitudes", gravel_fit_model()});  // per-sub-stratum gains in the colours
  c.push_back({"gravel r=0.2 placement turbulence", gravel_model(0.2, 4.0, true)});
  LrpParams p;
  p.cosines = 20;
  p.ratio = 0.1;
  p.placement = true;
  c.push_back({"colour r=0.1 placement", analyse_lrp(colour_exemplar(), p)});
  c.push_back({"ring", lrp_from_spectrum(lrp_analytic_psd("ring:0.1,0.01", 128), LrpParams{5, 1})});
  return c;
}

TEST(LrpKernel, MatchesReferenceBitForBit) {
  for (const Case& c : cases()) {
    for (double scale : {1.0, 0.7}) {
      RenderParams rp;
      rp.seed = 0x123456789abcULL;
      rp.scale = scale;
      LrpNoise dev(lrp_context(), c.model);
      const LrpReference ref(c.model, rp);
      for (std::int64_t x0 : {std::int64_t(-37), std::int64_t(1000000000000LL)}) {
        const auto a = dev.render(rp, x0, 11, 61, 23);
        const auto b = ref.render(x0, 11, 61, 23);
        EXPECT_EQ(bit_differences(a, b), 0u) << c.name << " scale " << scale << " x0 " << x0;
        bool finite = true;
        for (float v : a) finite = finite && std::isfinite(v);
        EXPECT_TRUE(finite) << c.name;
      }
    }
  }
}

// The two shapes of the kernel (runtime/lrp_renderer.h): chunks of 16 as long as each stratum needs, and chunks of
// 8 always computed whole (the lanes past J_S drawn and dropped). Both are checked against the reference on
// models whose J_S are not multiples of 8 (the fitted model's 3, 3, 5, 7, 32; the ring's 5; the colour model's
// remainders), so a padded lane that leaked into a sum, or a clamped table read that went wrong, shows as bits.
TEST(LrpKernel, PaddedAndExactChunksGiveTheReferenceBits) {
  LrpParams colour;
  colour.cosines = 21;  // J_S of 1 to 9 over 5 strata: remainders in every stratum
  const std::vector<Case> cs = {{"gravel r=0 fitted amplitudes", gravel_fit_model()},
                                {"colour fitted amplitudes", analyse_lrp(colour_exemplar(), colour)},
                                {"ring", lrp_from_spectrum(lrp_analytic_psd("ring:0.1,0.01", 128), LrpParams{5, 1})}};
  for (const Case& c : cs) {
    RenderParams rp;
    rp.seed = 77;
    const LrpReference ref(c.model, rp);
    const auto want = ref.render(-1000003, 29, 37, 19);
    for (const char* strategy : {"gather", "gather-padded"}) {
      NoiseRendererOptions o;
      o.strategy = strategy;
      LrpNoise dev(lrp_context(), c.model, o);
      std::vector<float> got(want.size());
      const NoiseRenderStats st = dev.render(rp, -1000003, 29, 37, 19, got.data());
      EXPECT_EQ(st.strategy, strategy);
      EXPECT_EQ(bit_differences(got, want), 0u) << c.name << " " << strategy;
    }
  }
  // auto: the padded chunks on CPU devices, the exact ones elsewhere
  LrpNoise dev(lrp_context(), cs[2].model);
  std::vector<float> out(8 * 8);
  const bool cpu = (lrp_context().info().type & CL_DEVICE_TYPE_CPU) != 0;
  EXPECT_EQ(dev.render(RenderParams{}, 0, 0, 8, 8, out.data()).strategy, cpu ? "gather-padded" : "gather");
  NoiseRendererOptions bad;
  bad.strategy = "gather-local";
  EXPECT_THROW(LrpNoise(lrp_context(), cs[2].model, bad), Error);
}

TEST(LrpKernel, RegisteredKindRendersThroughTheRegistry) {
  const LrpModel m = gravel_model(0.2, 2.0, true, 20);
  const auto bytes = encode_container(to_container(m));
  const ModelContainer c = decode_container(bytes.data(), bytes.size());
  auto r = make_noise_renderer(lrp_context(), c);
  EXPECT_EQ(r->kind(), "lrp");
  EXPECT_EQ(r->channels(), 1);
  RenderParams rp;
  rp.seed = 3;
  std::vector<float> a(32 * 16);
  r->render(rp, 5, -9, 32, 16, a.data());
  EXPECT_EQ(bit_differences(a, LrpReference(lrp_from_container(c), rp).render(5, -9, 32, 16)), 0u);
  NoiseRendererOptions bad;
  bad.strategy = "splat";
  EXPECT_THROW(make_noise_renderer(lrp_context(), c, bad), Error);
}

TEST(LrpKernel, TileChunkAndWorkGroupInvariant) {
  const LrpModel m = gravel_model(0.2, 4.0, true);
  LrpNoise dev(lrp_context(), m);
  RenderParams rp;
  rp.seed = 5;
  const int w = 96, h = 70;
  const auto whole = dev.render(rp, -20, 300, w, h);
  // 4 uneven tiles
  std::vector<float> tiled(whole.size());
  for (auto [tx, ty, tw, th] : std::vector<std::array<int, 4>>{{0, 0, 33, 41}, {33, 0, 63, 41}, {0, 41, 33, 29}, {33, 41, 63, 29}}) {
    const auto t = dev.render(rp, -20 + tx, 300 + ty, tw, th);
    for (int j = 0; j < th; ++j)
      for (int i = 0; i < tw; ++i) tiled[std::size_t(ty + j) * w + tx + i] = t[std::size_t(j) * tw + i];
  }
  EXPECT_EQ(bit_differences(whole, tiled), 0u);
  LrpRenderOptions o;
  o.local_size = {8, 2};
  o.max_chunk_pixels = 500;  // 5 rows per launch
  EXPECT_EQ(bit_differences(whole, dev.render(rp, -20, 300, w, h, o)), 0u);
}

TEST(LrpKernel, DeterministicAndSeeded) {
  const LrpModel m = gravel_model();
  LrpNoise dev(lrp_context(), m);
  RenderParams rp;
  rp.seed = 9;
  const auto a = dev.render(rp, 0, 0, 64, 64);
  EXPECT_EQ(bit_differences(a, dev.render(rp, 0, 0, 64, 64)), 0u);
  LrpNoise dev2(lrp_context(), m);  // a fresh renderer, same bits
  EXPECT_EQ(bit_differences(a, dev2.render(rp, 0, 0, 64, 64)), 0u);
  rp.seed = 10;
  EXPECT_GT(bit_differences(a, dev.render(rp, 0, 0, 64, 64)), 64u * 64u * 9 / 10);
}

// Welch PSD of a grey render with the analysis' own estimator (same T, window and normalisation).
LrpSpectrum render_psd(const LrpModel& m, std::uint64_t seed, int size) {
  LrpNoise dev(lrp_context(), m);
  RenderParams rp;
  rp.seed = seed;
  Image img;
  img.width = img.height = size;
  img.channels = 1;
  img.pixels = dev.render(rp, 0, 0, size, size);
  return lrp_welch(img, m.period);
}

// Predicted spectrum of n_S alone (S3 §4): each cosine's energy is spread by the window's spectrum
// |W^(Delta_S nu)|^2 around +-f, f drawn uniformly in a uniformly chosen sub-stratum table. The window is
// sampled on the T x T pixel grid (as the render is) and transformed; returns the fraction of n_S's energy
// predicted outside the stratum mask.
double predicted_leakage(const LrpModel& m, std::size_t s, const std::vector<int>& which) {
  const int t = m.period;
  const std::size_t n = std::size_t(t) * t;
  const double delta = m.strata[s].delta;
  std::vector<Complex> w(n);
  for (int y = 0; y < t; ++y)
    for (int x = 0; x < t; ++x) {
      const double dx = x >= t / 2 ? x - t : x, dy = y >= t / 2 ? y - t : y;
      w[std::size_t(y) * t + x] = lrp_window(std::hypot(dx, dy) / delta);
    }
  fft2d_forward(t, t, w);
  std::vector<double> k(n);
  double ksum = 0.0;
  for (std::size_t i = 0; i < n; ++i) ksum += (k[i] = std::norm(w[i]));
  std::size_t first = 0;
  for (std::size_t q = 0; q < s; ++q)
    for (int c : m.strata[q].sub_counts) first += std::size_t(c);
  // distribution of the drawn frequency (both signs), convolved with the window's spectrum by FFT
  std::vector<Complex> d(n, Complex(0.0, 0.0));
  const double per_sub = 1.0 / double(m.strata[s].sub_counts.size());
  std::size_t e = first;
  for (int c : m.strata[s].sub_counts) {
    for (int q = 0; q < c; ++q, ++e) {
      const int fx = m.freqs[2 * e], fy = m.freqs[2 * e + 1];
      d[std::size_t((fy % t + t) % t) * t + (fx % t + t) % t] += 0.5 * per_sub / c;
      d[std::size_t((-fy % t + t) % t) * t + (-fx % t + t) % t] += 0.5 * per_sub / c;
    }
  }
  std::vector<Complex> kc(k.begin(), k.end());
  fft2d_forward(t, t, d);
  fft2d_forward(t, t, kc);
  for (std::size_t i = 0; i < n; ++i) d[i] *= kc[i];
  fft2d_inverse(t, t, d);
  double outside = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    if (which[i] != int(s)) outside += d[i].real() / ksum;
  return outside;
}

// The exact expected Welch PSD of a render's strata: lrp_expected_welch_psd (analysis/lrp_psd.h).
std::vector<double> expected_welch_psd(const LrpModel& m, const std::vector<std::size_t>& which_strata = {}) {
  return lrp_expected_welch_psd(m, which_strata);
}

// Relative standard error of the Welch estimate of sum_{k in bin} P(k) for a near-Gaussian field
// (tolerance derivation of LrpSpectrum.RenderPsdMatchesTheModel): one Hann periodogram ordinate has
// SD = mean; the ordinates k and -k are equal (real field); neighbouring ordinates correlate through the
// Hann spectral window (amplitude weights 1/2, -1/4 at 1 bin: correlation (2/3)^2 at 1 bin, (1/6)^2 at 2,
// per axis), so a bin's variance is 3.78 times that of independent ordinates ((1 + 2 (2/3)^2 + 2 (1/6)^2)^2);
// the 3 x 3 crops of a 512^2 render overlap by half (correlation (1/3)^2 per overlapping axis), worth
// 81 / (9 + 24 / 9 + 16 / 81) = 6.83 independent crops; N_eff = (sum P)^2 / sum P^2 over the bin's
// ordinates for an uneven PSD. rel SE = sqrt(3.78 * 2 / (N_eff * 6.83 * seeds)).
double welch_bin_rel_se(const std::vector<double>& expected, const std::vector<std::size_t>& bin, int seeds) {
  double s = 0.0, s2 = 0.0;
  for (std::size_t i : bin) {
    s += expected[i];
    s2 += expected[i] * expected[i];
  }
  const double n_eff = s2 > 0 ? s * s / s2 : 0.0;
  const double hann = std::pow(1.0 + 2.0 * 4.0 / 9.0 + 2.0 / 36.0, 2.0);
  const double crops = 81.0 / (9.0 + 24.0 / 9.0 + 16.0 / 81.0);
  return std::sqrt(hann * 2.0 / (n_eff * crops * seeds));
}

// The render PSDs shared by the spectrum tests: r = 0, J = 50, L = 4 on gravel, 512^2 renders of seeds
// 100..102 analysed with the analysis' own Welch estimator (T = 256, 3 x 3 crops each).
const std::vector<LrpSpectrum>& gravel_render_psds() {
  static const std::vector<LrpSpectrum> v = [] {
    std::vector<LrpSpectrum> r;
    for (int k = 0; k < 3; ++k) r.push_back(render_psd(gravel_model(), 100 + k, 512));
    return r;
  }();
  return v;
}

// Stratum index of each frequency of the target (by the strata's PSD intervals), -1 for the DC.
std::vector<int> stratum_of_bins(const LrpModel& m, const LrpSpectrum& target) {
  std::vector<int> which(target.psd.size(), -1);
  for (std::size_t i = 1; i < which.size(); ++i)
    for (std::size_t s = 0; s < m.strata.size(); ++s)
      if (target.psd[i] > 0 && target.psd[i] <= m.strata[s].psd_hi && target.psd[i] >= m.strata[s].psd_lo)
        which[i] = int(s);
  return which;
}

TEST(LrpSpectrum, RenderPsdMatchesTheModel) {
  // S3 §4: the render's Welch PSD (mean of 3 seeds) against the model's expected PSD (expected_welch_psd:
  // each stratum's energy spread by the window's spectrum around its sub-strata frequencies, plus the
  // estimator's Hann leakage), summed over (a) radial bins of width 4 bins and (b) the bins of each stratum
  // of the target. Tolerance per bin: 4 relative standard errors of the Welch estimate (welch_bin_rel_se:
  // about 1 / sqrt(crops x seeds x independent ordinates in the bin)). Also: the target PSD itself (the
  // exemplar's) against the model's prediction, per stratum: what the model gives up (spectral leakage
  // into neighbouring strata), recorded, not bounded.
  const LrpModel m = gravel_model();
  const LrpSpectrum& target = gravel_spectrum();
  const int t = m.period;
  const std::size_t n = std::size_t(t) * t;
  const std::vector<double> want = expected_welch_psd(m);
  const auto& renders = gravel_render_psds();
  const int seeds = int(renders.size());
  std::vector<double> got(n, 0.0);
  for (const auto& r : renders)
    for (std::size_t i = 0; i < n; ++i) got[i] += r.psd[i] / seeds;
  const double want_var = std::accumulate(want.begin(), want.end(), 0.0);
  const double target_var = std::accumulate(target.psd.begin(), target.psd.end(), 0.0);
  std::printf("expected render variance %.6f (model strata: sum C_S(0) minus the DC), exemplar %.6f\n", want_var,
              target_var);
  auto check = [&](const char* what, const std::vector<std::vector<std::size_t>>& bins, double* worst_z,
                   double* worst_rel) {
    double z2 = 0.0;
    int used = 0;
    for (std::size_t b = 0; b < bins.size(); ++b) {
      if (bins[b].size() < 8) continue;
      double g = 0.0, w = 0.0;
      for (std::size_t i : bins[b]) {
        g += got[i];
        w += want[i];
      }
      if (w < 1e-4 * want_var) continue;  // below the accuracy of the g table (see RingRenderRadialEnergy)
      const double se = welch_bin_rel_se(want, bins[b], seeds);
      const double rel = g / w - 1.0;
      *worst_z = std::max(*worst_z, std::fabs(rel) / se);
      *worst_rel = std::max(*worst_rel, std::fabs(rel));
      z2 += rel * rel / (se * se);
      ++used;
      EXPECT_LT(std::fabs(rel), 4.0 * se) << what << " bin " << b << ": render " << g << ", model " << w;
    }
    std::printf("%s: %d bins, max |render / model - 1| %.4f, max |z| %.2f, mean z^2 %.2f\n", what, used, *worst_rel,
                *worst_z, z2 / used);
  };
  std::vector<std::vector<std::size_t>> radial(t / 8 + 24);
  for (std::size_t i = 1; i < n; ++i) {
    const int kx = int(i % t) >= t / 2 ? int(i % t) - t : int(i % t), ky = int(i / t) >= t / 2 ? int(i / t) - t : int(i / t);
    radial[std::size_t(std::hypot(kx, ky) / 4.0)].push_back(i);
  }
  const std::vector<int> which = stratum_of_bins(m, target);
  std::vector<std::vector<std::size_t>> per_stratum(m.strata.size());
  for (std::size_t i = 1; i < n; ++i)
    if (which[i] >= 0) per_stratum[std::size_t(which[i])].push_back(i);
  double zr = 0.0, rr = 0.0, zs = 0.0, rs = 0.0;
  check("radial bins (width 4)", radial, &zr, &rr);
  check("per-stratum bins", per_stratum, &zs, &rs);
  for (std::size_t s = 0; s < m.strata.size(); ++s) {
    double g = 0.0, w = 0.0, e = 0.0;
    for (std::size_t i : per_stratum[s]) {
      g += got[i];
      w += want[i];
      e += target.psd[i];
    }
    std::printf("stratum %zu: energy on its bins: exemplar %.6f, model %.6f, render %.6f (render / model %.4f)\n", s,
                e, w, g, g / w);
  }
}

// The leakage check of RenderEnergyAndLeakageMatchTheModel for any grey r = 0 model of gravel (see there).
void check_leakage(const LrpModel& m, const LrpSpectrum& target) {
  const std::vector<int> which = stratum_of_bins(m, target);
  auto mean_se = [](const std::vector<double>& v) {
    const double mu = std::accumulate(v.begin(), v.end(), 0.0) / v.size();
    double ss = 0.0;
    for (double x : v) ss += (x - mu) * (x - mu);
    return std::pair<double, double>(mu, std::sqrt(ss / (v.size() - 1) / v.size()));
  };
  std::size_t first = 0, subs = 0;
  for (std::size_t s = 0; s < m.strata.size(); ++s) {
    LrpModel one = m;
    one.strata = {m.strata[s]};
    std::size_t entries = 0;
    for (int c : m.strata[s].sub_counts) entries += std::size_t(c);
    one.freqs.assign(m.freqs.begin() + std::ptrdiff_t(2 * first), m.freqs.begin() + std::ptrdiff_t(2 * (first + entries)));
    one.colours.assign(m.colours.begin() + std::ptrdiff_t(2 * subs),
                       m.colours.begin() + std::ptrdiff_t(2 * (subs + m.strata[s].sub_counts.size())));
    first += entries;
    subs += m.strata[s].sub_counts.size();
    const std::vector<double> want = expected_welch_psd(m, {s});
    std::vector<std::size_t> in_bins, out_bins;
    double w_in = 0.0, w_out = 0.0;
    for (std::size_t i = 1; i < want.size(); ++i) {
      (which[i] == int(s) ? in_bins : out_bins).push_back(i);
      (which[i] == int(s) ? w_in : w_out) += want[i];
    }
    const double pred = w_out / (w_in + w_out);
    const int seeds = 2;
    const double se = pred * (1 - pred) *
                      std::hypot(welch_bin_rel_se(want, in_bins, seeds), welch_bin_rel_se(want, out_bins, seeds));
    std::vector<double> leak;
    for (int k = 0; k < seeds; ++k) {
      const LrpSpectrum rs = render_psd(one, 200 + k, 512);
      double in = 0.0, all = 0.0;
      for (std::size_t i = 1; i < rs.psd.size(); ++i) {
        all += rs.psd[i];
        if (which[i] == int(s)) in += rs.psd[i];
      }
      leak.push_back(1.0 - in / all);
    }
    const auto [lk, lk_se] = mean_se(leak);
    std::printf("stratum %zu: |S| %d, Delta %.2f px, J_S %zu: leakage of n_S outside S %.4f (seed spread %.4f), "
                "predicted %.4f +- %.4f (old window-only prediction %.4f)\n",
                s, m.strata[s].size, m.strata[s].delta, m.strata[s].sub_counts.size(), lk, lk_se, pred, se,
                predicted_leakage(m, s, which));
    EXPECT_NEAR(lk, pred, 4 * se) << "stratum " << s;
  }
}

TEST(LrpSpectrum, RenderEnergyAndLeakageMatchTheModel) {
  // r = 0, J = 50, L = 4 on gravel, 512^2 renders analysed with the analysis' own Welch estimator.
  //  - Variance (eq. 3): render / exemplar over 3 seeds; tolerance 4 standard errors of the mean, the SE
  //    estimated from the seeds.
  //  - Leakage: rendering n_S alone, the fraction of its energy outside S, against the prediction of the
  //    exact expected Welch PSD of n_S (expected_welch_psd: window spread, in-bin jitter, Hann leakage).
  //    The strata of a noisy exemplar PSD are fragmented (scattered high-PSD bins), so their leakage is
  //    large; the check is that the evaluator spreads energy exactly as the model predicts. Tolerance: 4
  //    SE of the measured fraction out / (in + out), by the delta method from the relative SEs of the two
  //    sums (welch_bin_rel_se, 2 seeds; in and out are sums over disjoint frequencies, independent):
  //    SE = leak (1 - leak) sqrt(se_in^2 + se_out^2).
  const LrpModel m = gravel_model();
  const LrpSpectrum& target = gravel_spectrum();
  const int t = m.period;
  ASSERT_EQ(t, 256);
  auto mean_se = [](const std::vector<double>& v) {
    const double mu = std::accumulate(v.begin(), v.end(), 0.0) / v.size();
    double ss = 0.0;
    for (double x : v) ss += (x - mu) * (x - mu);
    return std::pair<double, double>(mu, std::sqrt(ss / (v.size() - 1) / v.size()));
  };
  const double target_var = std::accumulate(target.psd.begin(), target.psd.end(), 0.0);
  std::vector<double> var_ratio;
  for (const auto& r : gravel_render_psds())
    var_ratio.push_back(std::accumulate(r.psd.begin(), r.psd.end(), 0.0) / target_var);
  const auto [vr, vr_se] = mean_se(var_ratio);
  std::printf("render variance / exemplar variance: %.4f +- %.4f\n", vr, vr_se);
  EXPECT_NEAR(vr, 1.0, 4 * vr_se);
  check_leakage(m, target);
}

TEST(LrpSpectrum, FittedModelLeakageMatchesTheModel) {
  // The default analysis (fitted amplitudes, L = 5, J_S by sqrt|S|) on gravel: each stratum rendered alone
  // spreads its energy outside S as the exact expected PSD predicts (same check and tolerance as
  // RenderEnergyAndLeakageMatchTheModel: 4 SE by the delta method, 2 seeds of 512^2).
  check_leakage(gravel_fit_model(), gravel_spectrum());
}

TEST(LrpSpectrum, RenderMatchesTheExemplarSpectrum) {
  // Issue 33's acceptance on grass (the issue's example) and leaves (synthetic dead leaves: sharp edges, a
  // steep anisotropic spectrum; gravel is checked on its model in tests/analysis, and brick does not meet the
  // figures at J = 50: docs/lrp.md): the default analysis (J = 50), a 2048^2 render
  // (seed 7) and the exemplar, each by the same estimator (Hann-windowed periodograms of 256^2 crops at step
  // 128: lrp_welch at T = 256; 225 crops of the render, 9 of the exemplar), compared in 24 radial bins and 6 x 8
  // polar sectors (compare_psd): median |ratio - 1| <= 0.10, max over the bins of >= 200 frequencies <= 0.35,
  // sector median <= 0.10 (the issue's figures). These are bounds on the model, not on the estimator: the
  // render's own relative SE per radial bin is about 1 % (welch_bin_rel_se with 225 crops), so it matches
  // the model's expected spectrum (checked below against lrp_expected_welch_psd, 4 SE per bin) and the
  // figures are those `stex analyze` predicts. The render's variance matches the model's to 4 SE.
  // Not in the sanitized run (tests/CMakeLists.txt, _sanitize_skip_kernels).
  for (const char* name : {"grass", "leaves"}) {
    SCOPED_TRACE(name);
    const Image ex = load_exemplar(std::string(STEX_SOURCE_DIR) + "/data/" + name + ".png");
    const LrpSpectrum target = lrp_welch(ex, 256);
    const LrpModel m = lrp_from_spectrum(target, LrpParams{});
    ASSERT_EQ(m.period, 256);
    ASSERT_EQ(m.amplitudes, "fit");
    const LrpSpectrum got = render_psd(m, 7, 2048);
    ASSERT_EQ(got.period, 256);
    ASSERT_EQ(got.crops, 225);
    const PsdComparison c = compare_psd(got.psd, target.psd, 256);
    std::printf("%s 2048^2 render / exemplar: radial median %.4f, max %.4f, sector median %.4f\n", name, c.radial_median,
                c.radial_max, c.sector_median);
    for (double r : c.radial_ratio) std::printf(" %.3f", r);
    std::printf("\n");
    EXPECT_LE(c.radial_median, 0.10);
    EXPECT_LE(c.radial_max, 0.35);
    EXPECT_LE(c.sector_median, 0.10);
    // the render against the model's expectation, per radial bin: 4 relative SE (225 crops: 25.3 independent
    // crops' worth, as welch_bin_rel_se's 6.83 for 9; rel SE = sqrt(3.78 * 2 / (N_eff * crops_eff)))
    const std::vector<double> want = lrp_expected_welch_psd(m);
    const double crops_eff = 6.83 * 225.0 / 9.0;
    std::vector<std::vector<std::size_t>> bins(24);
    for (std::size_t i = 1; i < want.size(); ++i) {
      const int kx = int(i % 256) >= 128 ? int(i % 256) - 256 : int(i % 256);
      const int ky = int(i / 256) >= 128 ? int(i / 256) - 256 : int(i / 256);
      const int b = int(std::hypot(kx, ky) / 256.0 / 0.5 * 24);
      if (b < 24) bins[std::size_t(b)].push_back(i);
    }
    double worst = 0.0;
    for (const auto& bin : bins) {
      double g = 0.0, w = 0.0, w2 = 0.0;
      for (std::size_t i : bin) {
        g += got.psd[i];
        w += want[i];
        w2 += want[i] * want[i];
      }
      const double se = std::sqrt(3.78 * 2.0 / (w * w / w2 * crops_eff));
      worst = std::max(worst, std::fabs(g / w - 1.0) / se);
      EXPECT_LT(std::fabs(g / w - 1.0), 4.0 * se);
    }
    double vg = 0.0, vw = 0.0, vw2 = 0.0;
    for (std::size_t i = 1; i < want.size(); ++i) {
      vg += got.psd[i];
      vw += want[i];
      vw2 += want[i] * want[i];
    }
    const double vse = std::sqrt(3.78 * 2.0 / (vw * vw / vw2 * crops_eff));
    std::printf("render vs model: max |z| over radial bins %.2f; variance render / model %.4f +- %.4f, model / "
                "exemplar %.4f\n", worst, vg / vw, vse, vw / std::accumulate(target.psd.begin(), target.psd.end(), 0.0));
    EXPECT_NEAR(vg / vw, 1.0, 4.0 * vse);
  }
}

TEST(LrpSpectrum, RingRenderRadialEnergy) {
  // Continuous-spectrum mode (S3 Fig. 10): ring:0.1,0.01 (radius 12.8 bins of T = 128), J = 5, one
  // stratum. The render's Welch PSD (3 seeds of 256^2, T = 128) against the model's expected PSD
  // (expected_welch_psd) in radial bins of width 2 bins; tolerance 4 relative SE per bin
  // (welch_bin_rel_se). Bins where the model expects < 1e-4 of the variance are not compared one by one:
  // there the expected PSD is below the accuracy of its window-autocorrelation table (linear interpolation
  // of g on a 0.01 grid: ~1e-6 of the variance per bin); the render's energy there must be below 1e-4 of
  // the variance per such bin.
  // Also where the energy is: the radial bin of the render's peak is the ring's, and the energy share
  // within 3 ring widths of the radius matches the model's (4 relative SE of that sum): with J = 5 the
  // windows' spread (1 / Delta_S) widens the ring, so the share is below the target's.
  const LrpSpectrum target = lrp_analytic_psd("ring:0.1,0.01", 128);
  const LrpModel m = lrp_from_spectrum(target, LrpParams{5, 1});
  ASSERT_EQ(m.strata.size(), 1u);
  const int t = m.period, seeds = 3;
  const std::size_t n = std::size_t(t) * t;
  std::vector<double> got(n, 0.0);
  for (int k = 0; k < seeds; ++k) {
    const LrpSpectrum r = render_psd(m, 300 + k, 2 * t);
    for (std::size_t i = 0; i < n; ++i) got[i] += r.psd[i] / seeds;
  }
  const std::vector<double> want = expected_welch_psd(m);
  std::vector<std::vector<std::size_t>> radial(t / 2 + 2);
  std::vector<double> radius(n);
  for (std::size_t i = 1; i < n; ++i) {
    const int kx = int(i % t) >= t / 2 ? int(i % t) - t : int(i % t), ky = int(i / t) >= t / 2 ? int(i / t) - t : int(i / t);
    radius[i] = std::hypot(kx, ky);
    if (radius[i] < t / 2) radial[std::size_t(radius[i] / 2.0)].push_back(i);
  }
  const double want_var = std::accumulate(want.begin(), want.end(), 0.0);
  double worst_z = 0.0, z2 = 0.0, faint_got = 0.0;
  int used = 0, faint = 0;
  std::size_t peak_got = 0, peak_want = 0;
  std::vector<double> g_bin(radial.size(), 0.0), w_bin(radial.size(), 0.0);
  for (std::size_t b = 0; b < radial.size(); ++b) {
    for (std::size_t i : radial[b]) {
      g_bin[b] += got[i];
      w_bin[b] += want[i];
    }
    if (g_bin[b] > g_bin[peak_got]) peak_got = b;
    if (w_bin[b] > w_bin[peak_want]) peak_want = b;
    if (radial[b].size() < 8) continue;
    if (w_bin[b] < 1e-4 * want_var) {
      faint_got += g_bin[b];
      ++faint;
      continue;
    }
    const double se = welch_bin_rel_se(want, radial[b], seeds);
    const double rel = g_bin[b] / w_bin[b] - 1.0;
    worst_z = std::max(worst_z, std::fabs(rel) / se);
    z2 += rel * rel / (se * se);
    ++used;
    EXPECT_LT(std::fabs(rel), 4 * se) << "radial bin " << b << ": render " << g_bin[b] << ", model " << w_bin[b];
  }
  double near_got = 0.0, near_want = 0.0, near_target = 0.0, all_got = 0.0, all_target = 0.0;
  std::vector<std::size_t> near_bins;
  for (std::size_t i = 1; i < n; ++i) {
    const bool near = std::fabs(radius[i] - 12.8) < 3 * 1.28;
    all_got += got[i];
    all_target += target.psd[i];
    if (near) {
      near_got += got[i];
      near_want += want[i];
      near_target += target.psd[i];
      near_bins.push_back(i);
    }
  }
  const double near_se = welch_bin_rel_se(want, near_bins, seeds) * near_want / want_var;
  std::printf("ring: Delta %.2f px, |S| %d; %d radial bins, max |z| %.2f, mean z^2 %.2f, render energy in the faint "
              "bins %.2g; peak bin radius [%zu, %zu) bins (model [%zu, %zu)); energy within 3 W of the radius: render "
              "%.3f, model %.3f +- %.3f, target %.3f\n",
              m.strata[0].delta, m.strata[0].size, used, worst_z, z2 / used, faint_got / all_got, 2 * peak_got,
              2 * peak_got + 2, 2 * peak_want, 2 * peak_want + 2, near_got / all_got, near_want / want_var, near_se,
              near_target / all_target);
  EXPECT_LT(faint_got / all_got, faint * 1e-4);  // as if each faint bin were at the threshold
  EXPECT_EQ(peak_got, peak_want);
  EXPECT_EQ(peak_got, std::size_t(12.8 / 2));  // the ring's radius bin [12, 14)
  EXPECT_GT(near_target / all_target, 0.99);
  EXPECT_NEAR(near_got / all_got, near_want / want_var, 4 * near_se);
  EXPECT_GT(near_got / all_got, 0.5);  // most of the render's energy is on the ring
}

double correlation(const std::vector<float>& a, const std::vector<float>& b) {
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ma += a[i];
    mb += b[i];
  }
  ma /= a.size();
  mb /= b.size();
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

TEST(LrpStructure, RatioOneReproducesTheExemplarUpToTheBlockError) {
  // r = 1, no turbulence, no placement: n = mean + n_R, and n_R on [0, T)^2 is the first Welch crop (the
  // exemplar's top-left T x T) up to the block approximation error the analysis measured (S3 §5.3), which
  // the 1/256 stop rule bounds. The device evaluates in float: allow 1e-5 on top.
  const LrpModel m = gravel_model(1.0);
  ASSERT_TRUE(m.strata.empty());
  ASSERT_GT(m.block, 0);
  LrpNoise dev(lrp_context(), m);
  const int t = m.period;
  const auto img = dev.render(RenderParams{}, 0, 0, t, t);
  double err = 0.0;
  for (int y = 0; y < t; ++y)
    for (int x = 0; x < t; ++x) err += std::fabs(img[std::size_t(y) * t + x] - gravel().at(x, y, 0));
  err /= double(t) * t;
  std::printf("r = 1: block %d, J_R %d, analysis error %.5f, render vs exemplar mean |error| %.5f\n", m.block, m.jr,
              m.structure_error, err);
  EXPECT_LE(m.structure_error, 1.0 / 256.0);
  EXPECT_LE(err, m.structure_error + 1e-5);
  // periodic with period T without placement, any seed
  RenderParams rp;
  rp.seed = 77;
  const auto shifted = dev.render(rp, t, -3 * t, t, t);
  EXPECT_LT(std::fabs(correlation(img, shifted) - 1.0), 1e-6);
}

TEST(LrpStructure, BlockEdgeSeamsMeasured) {
  // S3 §5.3 sets Delta_R to the block size "so as to handle transitions"; here each pixel uses its own
  // block's series (docs/lrp.md: window-blending neighbours' periodic series mixes their contents). The
  // seams at block edges are measured on n_R alone (gravel, r = 0.2: the strata removed) against the
  // structure image s (lrp_structure_image):
  //  - at pixel centres (scale 1) the render is s + e, e the block approximation error (mean |e| < 1/256 by
  //    the stop rule); a step across an edge exceeds s's own step by at most |e_left| + |e_right|, so the
  //    largest excess is bounded by 2 max |e| (checked), and the mean excess by 2 mean |e| on edge pixels;
  //  - between pixel centres (scale 8: samples 1/8 px apart) a block's series is a trigonometric
  //    interpolant of its own block, periodic with period B, so at the exact edge it jumps: the jump is
  //    |f_left(B) - f_right(0)| <= 2 max |n_R - mean| (checked), measured against the steps between
  //    neighbouring samples inside blocks.
  LrpModel m = gravel_model(0.2);
  m.strata.clear();
  m.freqs.clear();
  m.colours.clear();
  const int t = m.period, b = m.block;
  ASSERT_GT(b, 1);
  ASSERT_LT(b, t);
  const std::vector<float> img = lrp_structure_image(gravel_spectrum(), 0.2);
  LrpNoise dev(lrp_context(), m);
  const auto r1 = dev.render(RenderParams{}, 0, 0, t, t);
  double emax = 0.0, esum = 0.0, dev_max = 0.0;
  for (std::size_t i = 0; i < r1.size(); ++i) {
    emax = std::max(emax, double(std::fabs(r1[i] - img[i])));
    esum += std::fabs(r1[i] - img[i]);
    dev_max = std::max(dev_max, double(std::fabs(r1[i] - m.mean[0])));
  }
  double excess_max = 0.0, excess_sum = 0.0, step_edge = 0.0, step_in = 0.0;
  int edges = 0, inside = 0;
  for (int y = 0; y < t; ++y)
    for (int x = 1; x < t; ++x) {
      const std::size_t i = std::size_t(y) * t + x;
      const double sr = std::fabs(r1[i] - r1[i - 1]), si = std::fabs(img[i] - img[i - 1]);
      if (x % b == 0) {
        excess_max = std::max(excess_max, sr - si);
        excess_sum += sr - si;
        step_edge += sr;
        ++edges;
      } else {
        step_in += sr;
        ++inside;
      }
    }
  std::printf("block seams, B = %d, scale 1: max |e| %.4f, mean |e| %.5f; step across edges: mean %.4f (inside %.4f), "
              "excess over the exemplar's step: max %.4f (bound 2 max|e| = %.4f), mean %.5f\n",
              b, emax, esum / r1.size(), step_edge / edges, step_in / inside, excess_max, 2 * emax,
              excess_sum / edges);
  EXPECT_LE(esum / r1.size(), 1.0 / 256.0 + 1e-5);
  EXPECT_LE(excess_max, 2 * emax + 1e-5);
  // scale 8: a strip of 2 exemplar rows across the first row of blocks
  RenderParams rp;
  rp.scale = 8.0;
  const int w = 8 * t, h = 16;
  const auto r8 = dev.render(rp, 0, 0, w, h);
  double jump_max = 0.0, jump_sum = 0.0, in_max = 0.0, in_sum = 0.0;
  int nj = 0, ni = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 1; x < w; ++x) {
      const double st = std::fabs(r8[std::size_t(y) * w + x] - r8[std::size_t(y) * w + x - 1]);
      if (x % (8 * b) == 0) {
        jump_max = std::max(jump_max, st);
        jump_sum += st;
        ++nj;
      } else {
        in_max = std::max(in_max, st);
        in_sum += st;
        ++ni;
      }
    }
  std::printf("block seams, scale 8 (1/8 px samples): jump at the edge max %.4f mean %.4f; steps inside max %.4f mean "
              "%.5f; bound 2 max |n_R - mean| = %.4f\n",
              jump_max, jump_sum / nj, in_max, in_sum / ni, 2 * dev_max);
  EXPECT_LE(jump_max, 2 * dev_max + 1e-5);
}

TEST(LrpStructure, RatioZeroIsFullyRandomPhase) {
  // r = 0: no fixed-phase region at all, and two seeds give uncorrelated renders. Bound on |rho| for
  // independent fields: 4 / sqrt(N_eff) with N_eff = pixels / correlation area; the correlation area of
  // gravel's noise is below 8^2 pixels (its PSD is spread over most of the band), so N_eff >= 256^2 / 64.
  const LrpModel m = gravel_model(0.0);
  EXPECT_EQ(m.block, 0);
  EXPECT_TRUE(m.terms.empty());
  LrpNoise dev(lrp_context(), m);
  RenderParams a, b;
  a.seed = 1;
  b.seed = 2;
  const double rho = correlation(dev.render(a, 0, 0, 256, 256), dev.render(b, 0, 0, 256, 256));
  std::printf("r = 0: correlation of two seeds %.4f\n", rho);
  EXPECT_LT(std::fabs(rho), 4.0 / std::sqrt(256.0 * 256.0 / 64.0));
  // r = 0.2: the structure is shared by every seed (fixed phases), so two seeds correlate about as much as
  // the structure's share of the variance.
  const LrpModel s = gravel_model(0.2);
  LrpNoise ds(lrp_context(), s);
  const double rho_s = correlation(ds.render(a, 0, 0, 256, 256), ds.render(b, 0, 0, 256, 256));
  std::printf("r = 0.2: correlation of two seeds %.4f\n", rho_s);
  EXPECT_GT(rho_s, 0.1);
}

// A two-channel exemplar whose structure is one travelling wave along x, period 16 px: channel 0 =
// 0.5 + 0.2 cos(2 pi x / 16), channel 1 = 0.5 + 0.2 sin(2 pi x / 16). At r = 1 the model is the structure
// alone (no random-phase strata), so a render's phase atan2(ch1 - mean, ch0 - mean) reads the x position
// at which the structure was evaluated: the turbulent displacement d(x) is the phase difference to the
// sigma = 0 render times 16 / (2 pi).
LrpModel wave_model(double sigma, bool placement, int turbulence_strata = 2) {
  Image ex;
  ex.width = ex.height = 160;  // T = 128 (largest power of two strictly below 160), 8 wave periods
  ex.channels = 2;
  ex.pixels.resize(std::size_t(160) * 160 * 2);
  for (int y = 0; y < 160; ++y)
    for (int x = 0; x < 160; ++x) {
      ex.at(x, y, 0) = float(0.5 + 0.2 * std::cos(2 * M_PI * x / 16.0));
      ex.at(x, y, 1) = float(0.5 + 0.2 * std::sin(2 * M_PI * x / 16.0));
    }
  LrpParams p;
  p.cosines = 4;
  p.ratio = 1.0;
  p.sigma = sigma;
  p.placement = placement;
  p.turbulence_strata = turbulence_strata;
  p.turbulence_cosines = 4 * turbulence_strata;
  return analyse_lrp(ex, p);
}

// Displacement (px along x, wrapped to (-8, 8]) of a wave render against the sigma = 0 render.
std::vector<double> wave_displacement(const LrpModel& m, const std::vector<float>& img,
                                      const std::vector<float>& ref) {
  std::vector<double> d(img.size() / 2);
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double a = std::atan2(img[2 * i + 1] - m.mean[1], img[2 * i] - m.mean[0]);
    const double b = std::atan2(ref[2 * i + 1] - m.mean[1], ref[2 * i] - m.mean[0]);
    double dp = a - b;
    while (dp <= -M_PI) dp += 2 * M_PI;
    while (dp > M_PI) dp -= 2 * M_PI;
    d[i] = dp * 16.0 / (2 * M_PI);
  }
  return d;
}

TEST(LrpTurbulence, RatioOneTurbulenceChangesTheRender) {
  // S3 §6.3: at r = 1 the model "reduces to applying turbulence and random placement"; there are no
  // random-phase strata, and the turbulence has strata of its own over the whole spectrum (§5.2). So
  // sigma > 0 must change the render, more for larger sigma: the correlation with the sigma = 0 render
  // falls strictly with sigma (same seed, so the displacement field is the same field scaled), and at
  // sigma = 0 the render is the exemplar crop (LrpStructure.RatioOneReproducesTheExemplarUpToTheBlockError).
  // One analysis: the turbulence strata do not depend on sigma, which only scales the displacement.
  LrpParams p;
  p.ratio = 1.0;
  p.sigma = 1.0;
  const LrpModel m1 = lrp_from_spectrum(gravel_spectrum(), p);
  ASSERT_TRUE(m1.strata.empty());
  ASSERT_EQ(m1.turbulence.size(), 2u);
  LrpModel m0 = m1;
  m0.sigma = 0.0;
  m0.turbulence.clear();
  m0.turb_freqs.clear();
  RenderParams rp;
  rp.seed = 12;
  const auto base = LrpNoise(lrp_context(), m0).render(rp, 0, 0, 128, 128);
  double last = 1.0;
  for (double sigma : {0.5, 2.0, 8.0}) {
    LrpModel m = m1;
    m.sigma = sigma;
    const auto img = LrpNoise(lrp_context(), m).render(rp, 0, 0, 128, 128);
    const double rho = correlation(img, base);
    std::printf("r = 1, sigma %.1f px: correlation with the sigma = 0 render %.4f\n", sigma, rho);
    EXPECT_LT(rho, last) << sigma;
    EXPECT_LT(rho, 0.999) << sigma;
    last = rho;
  }
  // a model file that asks for turbulence without turbulence strata is refused by name
  LrpModel broken = m1;
  broken.turbulence.clear();
  broken.turb_freqs.clear();
  try {
    validate_lrp_model(broken);
    ADD_FAILURE() << "accepted sigma > 0 without turbulence strata";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("turbulence"), std::string::npos) << e.what();
  }
}

TEST(LrpTurbulence, DisplacementIsSigmaTimesTheNormalisedTurbulence) {
  // S3 §5.2: the structure is read at x + sigma n_T(x), n_T = sum_T |n_T| (here normalised by
  // sqrt(sum_T Var n_T)). On the wave exemplar (r = 1) the displacement d(x) is read from the phase.
  //  - Linear in sigma, pointwise: d_sigma / sigma is the same field for sigma = 0.5, 1, 2 (same seed); the
  //    bound 2e-3 px is float rounding of positions ~ 256 px (3e-5 px) and of the phase (1e-6 turn of a
  //    16 px wave) with margin.
  //  - Scale: with one turbulence stratum, n_T = |carrier| / sd, so E[d^2] = sigma^2 exactly (the
  //    carrier's variance is the one eq. 3 gives; the lattice envelope's < 5 % ripple averages out over
  //    the region). Measured over 8 seeds of 256^2 at sigma = 1: the mean of d^2 within 4 standard errors
  //    (the SE from the seeds' spread: the turbulence is narrow-band, its envelope correlates over ~Delta).
  //    Also d >= 0 (|n_S| >= 0).
  const LrpModel m0 = wave_model(0.0, false);
  ASSERT_TRUE(m0.strata.empty());
  ASSERT_EQ(m0.block, 128);  // one block reproduces the wave exactly
  RenderParams rp;
  const auto ref = LrpNoise(lrp_context(), m0).render(rp, 0, 0, 256, 256);
  const double sigmas[3] = {0.5, 1.0, 2.0};
  std::vector<std::vector<double>> per_sigma;
  for (double sigma : sigmas) {
    const LrpModel m = wave_model(sigma, false);
    rp.seed = 31;
    per_sigma.push_back(wave_displacement(m, LrpNoise(lrp_context(), m).render(rp, 0, 0, 256, 256), ref));
  }
  // d_sigma - sigma d_1, wrapped to the wave's period (d_2 may exceed half a period, 8 px), over sigma
  auto wrapped = [](double v) { return v - 16.0 * std::round(v / 16.0); };
  double worst = 0.0, dmin = 1e9;
  for (std::size_t i = 0; i < per_sigma[0].size(); ++i) {
    for (int k : {0, 2})
      worst = std::max(worst, std::fabs(wrapped(per_sigma[k][i] - sigmas[k] * per_sigma[1][i])) / sigmas[k]);
    dmin = std::min(dmin, per_sigma[1][i]);
  }
  std::printf("turbulence: max |d_sigma / sigma - d_1| over sigma = 0.5, 2: %.3g px; min d %.3g px\n", worst, dmin);
  EXPECT_LT(worst, 2e-3);
  EXPECT_GT(dmin, -2e-3);
  const LrpModel m1 = wave_model(1.0, false, 1);
  ASSERT_EQ(m1.turbulence.size(), 1u);
  LrpNoise dev(lrp_context(), m1);
  std::vector<double> ms;
  for (int k = 0; k < 8; ++k) {
    rp.seed = 400 + k;
    const std::vector<double> d = wave_displacement(m1, dev.render(rp, 0, 0, 256, 256), ref);
    double s2 = 0.0;
    for (double v : d) s2 += v * v;
    ms.push_back(s2 / d.size());
  }
  const double mu = std::accumulate(ms.begin(), ms.end(), 0.0) / ms.size();
  double ss = 0.0;
  for (double v : ms) ss += (v - mu) * (v - mu);
  const double se = std::sqrt(ss / (ms.size() - 1) / ms.size());
  std::printf("turbulence, one stratum, sigma = 1 px: mean d^2 = %.4f +- %.4f px^2 (expected 1)\n", mu, se);
  EXPECT_NEAR(mu, 1.0, 4 * se);
}

TEST(LrpTurbulence, PlacementIsAppliedBeforeTurbulence) {
  // S3 §5.2: "random placement must be applied first in order to ensure continuity of the spatial
  // distortion": x' = place(x) + sigma n_T(x). Outside the placement blend bands place(x) = x + s_b (one
  // block's shift), so the displacement read from the wave's phase with placement on equals the field
  // without placement at every pixel (same seed); with the reverse order, place(x + d) would pick the
  // neighbouring block (or blend) wherever x + d crosses into a band, within ~4 sigma px of it.
  const double sigma = 2.0;
  RenderParams rp;
  rp.seed = 44;
  const LrpModel p0 = wave_model(0.0, true), p1 = wave_model(sigma, true);
  const LrpModel n0 = wave_model(0.0, false), n1 = wave_model(sigma, false);
  const int w = 256;
  const auto d_place = wave_displacement(p1, LrpNoise(lrp_context(), p1).render(rp, 0, 0, w, w),
                                         LrpNoise(lrp_context(), p0).render(rp, 0, 0, w, w));
  const auto d_plain = wave_displacement(n1, LrpNoise(lrp_context(), n1).render(rp, 0, 0, w, w),
                                         LrpNoise(lrp_context(), n0).render(rp, 0, 0, w, w));
  const double pb = p1.period / 2.0, band = 0.5 * p1.blend * pb;  // placement block, half blend band (px)
  auto in_band = [&](int i) {
    const double f = std::fmod(i + 0.5, pb);
    return f < band + 0.5 || f > pb - band - 0.5;
  };
  double worst = 0.0;
  std::size_t used = 0, crossing = 0;
  for (int y = 0; y < w; ++y)
    for (int x = 0; x < w; ++x) {
      if (in_band(x) || in_band(y)) continue;
      const double d = d_plain[std::size_t(y) * w + x];
      worst = std::max(worst, std::fabs(d_place[std::size_t(y) * w + x] - d));
      // x + d lands in a band (or beyond): there the reverse order would read another block or a blend
      if (std::fmod(x + 0.5, pb) + d > pb - band) ++crossing;
      ++used;
    }
  std::printf("placement then turbulence: %zu pixels outside the blend bands (%zu of them displaced into a band), "
              "max |d_placed - d| %.3g px\n",
              used, crossing, worst);
  EXPECT_GT(used, std::size_t(w) * w / 2);
  EXPECT_GT(crossing, std::size_t(100));  // the reverse order would show at these pixels
  EXPECT_LT(worst, 2e-3);
}

TEST(LrpStructure, PlacementBreaksPeriodicityAndIsContinuous) {
  const LrpModel m = gravel_model(0.3, 0.0, true);
  LrpNoise dev(lrp_context(), m);
  const int t = m.period;
  RenderParams rp;
  const auto a = dev.render(rp, 0, 0, t, t);
  const auto b = dev.render(rp, 4 * t, 0, t, t);
  // without placement these are identical in the structure; with it, the shifted half-period blocks differ
  EXPECT_LT(correlation(a, b), 0.9);
  // continuity: across a placement-block edge (x = T/2) the step between neighbours is no larger than
  // the typical step inside blocks (the blend band is a smoothstep over T/8 pixels)
  double edge = 0.0, inside = 0.0;
  for (int y = 0; y < t; ++y) {
    edge += std::fabs(a[std::size_t(y) * t + t / 2] - a[std::size_t(y) * t + t / 2 - 1]);
    inside += std::fabs(a[std::size_t(y) * t + t / 4] - a[std::size_t(y) * t + t / 4 - 1]);
  }
  std::printf("placement: mean step across a block edge %.4f, inside %.4f\n", edge / t, inside / t);
  EXPECT_LT(edge, 2.0 * inside);
}

TEST(LrpStructure, PlacementWithTurbulenceIsContinuous) {
  // With turbulence too (placement first, then x' = place(x) + sigma n_T(x), S3 §5.2), the render stays
  // continuous across the placement-block edges x = k T/2: the mean step between neighbouring pixels
  // across an edge is no larger than twice the mean step inside blocks, at r = 0.3 and r = 1 (structure
  // only: the strongest case), sigma = 4 px.
  for (double r : {0.3, 1.0}) {
    const LrpModel m = gravel_model(r, 4.0, true);
    ASSERT_FALSE(m.turbulence.empty());
    LrpNoise dev(lrp_context(), m);
    const int t = m.period;
    RenderParams rp;
    rp.seed = 8;
    const int rows = t / 2;  // one placement block's height
    const auto a = dev.render(rp, 0, 0, t, rows);
    double edge = 0.0, inside = 0.0;
    for (int y = 0; y < rows; ++y) {
      edge += std::fabs(a[std::size_t(y) * t + t / 2] - a[std::size_t(y) * t + t / 2 - 1]);
      inside += std::fabs(a[std::size_t(y) * t + t / 4] - a[std::size_t(y) * t + t / 4 - 1]);
    }
    std::printf("placement + turbulence, r = %.1f: mean step across a block edge %.4f, inside %.4f\n", r,
                edge / rows, inside / rows);
    EXPECT_LT(edge, 2.0 * inside) << r;
  }
}

// ---- Filtered LRP noise (runtime/lrp_model.cpp, frequency clamping of S3 §6.4 by the footprint's Gaussian
// transfer): the device equals the C++ reference bit for bit across tilings and chunkings, the filter changes
// nothing at scale >= 1, and the quality of issue 31 item 4 against a 16 x 16 supersampled box reference of
// the same realisation (docs/filtering.md).

// The default analysis of gravel (fitted amplitudes), and with structure by fixed phases (r = 0.3).
const LrpModel& plain_model() { return gravel_fit_model(); }
const LrpModel& structured_model() {
  static const LrpModel m = [] {
    LrpParams p;
    p.ratio = 0.3;
    return lrp_from_spectrum(gravel_spectrum(), p);
  }();
  return m;
}

RenderParams filtered(double scale) { return test::minified(scale, 99, true); }
RenderParams point_sampled(double scale) { return test::minified(scale, 99, false); }

std::vector<float> filter_render(const LrpModel& m, const RenderParams& rp, std::int64_t x, std::int64_t y, int w,
                                 int h, std::size_t chunk = 0) {
  LrpNoise n(lrp_context(), m);
  LrpRenderOptions o;
  o.max_chunk_pixels = chunk;
  return n.render(rp, x, y, w, h, o);
}

TEST(LrpFilter, DeviceEqualsReferenceBitForBitAcrossTilings) {
  for (const LrpModel* m : {&plain_model(), &structured_model()}) {
    for (double scale : {0.5, 1.0 / 16.0}) {
      const RenderParams rp = filtered(scale);
      const std::vector<float> r = LrpReference(*m, rp).render(-13, 7, 24, 20);
      EXPECT_EQ(filter_render(*m, rp, -13, 7, 24, 20), r) << "scale " << scale;
      EXPECT_EQ(filter_render(*m, rp, -13, 7, 24, 20, 100), r) << "scale " << scale << ", chunks of 100";
      const std::vector<float> tile = filter_render(*m, rp, -5, 12, 9, 6);
      for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 9; ++i) ASSERT_EQ(tile[j * 9 + i], r[(j + 5) * 24 + (i + 8)]);
      // One renderer for both: the tables follow the parameters.
      LrpNoise n(lrp_context(), *m);
      EXPECT_NE(n.render(point_sampled(scale), -13, 7, 24, 20, LrpRenderOptions{}), r);
      EXPECT_EQ(n.render(rp, -13, 7, 24, 20, LrpRenderOptions{}), r);
    }
  }
}

TEST(LrpFilter, FilterChangesNothingAtUnitScaleAndAbove) {
  for (double scale : {1.0, 3.0})
    EXPECT_EQ(filter_render(structured_model(), filtered(scale), 3, -4, 16, 16),
              filter_render(structured_model(), point_sampled(scale), 3, -4, 16, 16));
}

// The 16 x 16 supersampled box reference of the unfiltered noise at the same scale: the same cosines.
std::vector<float> supersampled(const LrpModel& m, double scale, std::int64_t x, std::int64_t y, int w, int h) {
  const LrpReference ref(m, point_sampled(scale));
  const LrpSetup& s = ref.setup();
  return test::box_supersampled(
      [&](std::int64_t fx, std::int64_t fy, float* v) { stex_lrp_eval(s.params, s.fdata.data(), s.udata.data(), fx, fy, v); },
      m.channels, x, y, w, h);
}

using test::rms_diff;
using test::stddev;

// Issue 31 item 4 against the 16 x 16 supersampled box reference of the same realisation, scales 1/2 .. 1/64:
//  - 1/2 and 1/4: within 0.25 of the reference's standard deviation (RMS), and at least 0.9 of it kept;
//  - the point-sampled render at least twice as far off: every scale without structure, to 1/16 with it.
// Measured (docs/filtering.md): 0.09 / 0.19 sd at 1/2 / 1/4, 0.34 at 1/8, then the Gaussian footprint and the
// box part ways (the box's side lobes, the windows' own spectra). With structure, each block's mean (the
// 0-frequency terms S3 §6.4 leaves to a MIP map) is not faded: from 1/32 the filtered render keeps 2-5x the
// box's contrast. The figures are printed and recorded in docs/filtering.md.
TEST(LrpFilter, QualityAgainstTheSupersampledBoxReference) {
  const int w = 16, h = 16;
  const double sd1 = stddev(filter_render(plain_model(), point_sampled(1.0), 0, 0, 64, 64));
  for (const LrpModel* m : {&plain_model(), &structured_model()}) {
    for (int k = 1; k <= 6; ++k) {
      const double scale = 1.0 / double(1 << k);
      const std::vector<float> s = supersampled(*m, scale, 11, -5, w, h);
      const std::vector<float> f = filter_render(*m, filtered(scale), 11, -5, w, h);
      const std::vector<float> u = filter_render(*m, point_sampled(scale), 11, -5, w, h);
      const double sd = stddev(s), ef = rms_diff(f, s), eu = rms_diff(u, s);
      std::printf("%s, scale 1/%d: box sd %.4g (%.3f of scale 1); filtered rms %.3f sd, keeps %.3f sd; "
                  "point-sampled rms %.3f sd\n",
                  m->block ? "structured" : "plain", 1 << k, sd, sd / sd1, ef / sd, stddev(f) / sd, eu / sd);
      if (k <= 2) {
        EXPECT_LE(ef, 0.25 * sd) << "scale 1/" << (1 << k);
        EXPECT_GE(stddev(f), 0.9 * sd) << "scale 1/" << (1 << k);
      }
      if (m->block == 0 || k <= 4) {
        EXPECT_GE(eu, 2.0 * ef) << "scale 1/" << (1 << k);
      }
    }
  }
}

}  // namespace
}  // namespace stex
