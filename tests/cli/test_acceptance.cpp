// Issue #3's acceptance, end to end through the CLI: `stex analyze` with every default (support 64, 50
// iterations, order 1, colour correction) on an exemplar nobody tuned on, then `stex render` of a 2048^2
// image at MNI 30, must give
//   - mean:  per channel |mean(render) - mean(exemplar)| / sd(exemplar) <= 5 % (worst channel),
//   - colour covariance: ||C_render - C_exemplar||_F / ||C_exemplar||_F <= 3 % (C_exemplar of the periodic
//     component, which is what the analysis models),
//   - power spectrum: the radially averaged periodogram in 24 bins of |f| in [0, 1/2), of the render averaged
//     over exemplar-sized blocks (periodic component of each block), against the exemplar's periodic
//     component: median relative bin error <= 5 %, every bin with >= 200 frequencies <= 20 % (bins with
//     fewer frequencies, the lowest on small exemplars, are dominated by the bias of the periodic
//     component's periodogram on finite blocks and count in the median only).
// These are the measures by which issue #3's acceptance is judged (mean, colour covariance, radially averaged
// power spectrum), implemented here independently on stex's own FFT and periodic decomposition.
//
// The thresholds are the issue's, not tuned: the estimators' own noise is far below them. The render's
// periodogram averaged over B = (2048/W)^2 blocks has a relative standard deviation of about
// 1/sqrt(B * n_bin) per bin (periodogram ordinates are ~exponential): <= 1/sqrt(16 * 200) = 1.8 % for the
// bins that count in the max. The render's mean and covariance average ~4 * 10^6 correlated pixels (texton
// support 64: correlation area ~ 64^2), so their relative errors are ~ sqrt(64^2 / 2048^2) = 3 % of sd for
// the mean (worst case) and less for the covariance; the measured values are printed.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/fft.h"
#include "analysis/image_io.h"
#include "analysis/periodic.h"
#include "cli_run.h"

namespace fs = std::filesystem;
using namespace stex;

namespace {

std::string tmp_dir() {
  static const std::string d = [] {
    std::string p = std::string(STEX_TEST_TMP_DIR) + "/acceptance";
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
  }();
  return d;
}

int run(const std::string& args, std::string* err_text = nullptr) {
  const stex::test::CliRun r = stex::test::run_stex_cli(args, "acceptance/run");
  if (err_text) *err_text = r.err;
  return r.code;
}

// Planar double channels of an interleaved image region.
std::vector<std::vector<double>> planes(const Image& img, int x0, int y0, int w, int h, int channels) {
  std::vector<std::vector<double>> p(std::size_t(channels), std::vector<double>(std::size_t(w) * h));
  for (int c = 0; c < channels; ++c)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) p[c][std::size_t(y) * w + x] = img.at(x0 + x, y0 + y, c);
  return p;
}

std::vector<double> means(const std::vector<std::vector<double>>& p) {
  std::vector<double> m;
  for (const auto& v : p) {
    double s = 0.0;
    for (double x : v) s += x;
    m.push_back(s / double(v.size()));
  }
  return m;
}

std::vector<double> covariance(const std::vector<std::vector<double>>& p) {
  const std::size_t C = p.size(), n = p[0].size();
  const std::vector<double> m = means(p);
  std::vector<double> cov(C * C, 0.0);
  for (std::size_t i = 0; i < C; ++i)
    for (std::size_t j = 0; j < C; ++j) {
      double s = 0.0;
      for (std::size_t k = 0; k < n; ++k) s += (p[i][k] - m[i]) * (p[j][k] - m[j]);
      cov[i * C + j] = s / double(n);
    }
  return cov;
}

constexpr int kBins = 24;

int radial_bin(int qx, int qy, int w, int h) {
  const double fx = (qx <= w / 2 ? qx : qx - w) / double(w), fy = (qy <= h / 2 ? qy : qy - h) / double(h);
  const double r = std::sqrt(fx * fx + fy * fy);
  const int b = int(std::floor(r / 0.5 * kBins));
  return b >= 0 && b < kBins ? b : -1;
}

// Radially averaged periodogram (sum over channels of |DFT of the centred channel|^2 / (w h)).
std::vector<double> radial_psd(const std::vector<std::vector<double>>& p, int w, int h) {
  std::vector<double> sum(kBins, 0.0), count(kBins, 0.0);
  std::vector<Complex> f(std::size_t(w) * h);
  std::vector<double> power(std::size_t(w) * h, 0.0);
  for (const auto& ch : p) {
    double m = 0.0;
    for (double v : ch) m += v;
    m /= double(ch.size());
    for (std::size_t k = 0; k < ch.size(); ++k) f[k] = Complex(ch[k] - m, 0.0);
    fft2d_forward(w, h, f);
    for (std::size_t k = 0; k < f.size(); ++k) power[k] += std::norm(f[k]) / (double(w) * h);
  }
  for (int qy = 0; qy < h; ++qy)
    for (int qx = 0; qx < w; ++qx) {
      const int b = radial_bin(qx, qy, w, h);
      if (b < 0) continue;
      sum[b] += power[std::size_t(qy) * w + qx];
      count[b] += 1.0;
    }
  for (int b = 0; b < kBins; ++b) sum[b] /= std::max(count[b], 1.0);
  return sum;
}

std::vector<int> radial_counts(int w, int h) {
  std::vector<int> n(kBins, 0);
  for (int qy = 0; qy < h; ++qy)
    for (int qx = 0; qx < w; ++qx) {
      const int b = radial_bin(qx, qy, w, h);
      if (b >= 0) ++n[b];
    }
  return n;
}

std::vector<std::vector<double>> periodic(const std::vector<std::vector<double>>& p, int w, int h) {
  std::vector<std::vector<double>> out;
  for (const auto& ch : p) out.push_back(periodic_component(w, h, ch));
  return out;
}

struct Acceptance {
  double mean_err = 0, cov_err = 0, psd_median = 0, psd_max = 0;
};

Acceptance measure(const Image& ex, const Image& rd) {
  const int C = std::min(ex.channels, 3);
  const int W = ex.width, H = ex.height;
  const auto ex_p = periodic(planes(ex, 0, 0, W, H, C), W, H);
  const auto rd_all = planes(rd, 0, 0, rd.width, rd.height, C);
  const std::vector<double> m_ex = means(planes(ex, 0, 0, W, H, C)), m_rd = means(rd_all);
  const std::vector<double> c_ex = covariance(ex_p), c_rd = covariance(rd_all);
  Acceptance a;
  double num = 0.0, den = 0.0;
  for (int i = 0; i < C; ++i) {
    a.mean_err = std::max(a.mean_err, std::abs(m_rd[i] - m_ex[i]) / std::sqrt(c_ex[std::size_t(i) * C + i]));
    for (int j = 0; j < C; ++j) {
      const double d = c_rd[std::size_t(i) * C + j] - c_ex[std::size_t(i) * C + j];
      num += d * d;
      den += c_ex[std::size_t(i) * C + j] * c_ex[std::size_t(i) * C + j];
    }
  }
  a.cov_err = std::sqrt(num / den);
  std::vector<double> r_rd(kBins, 0.0);
  int blocks = 0;
  for (int y = 0; y + H <= rd.height; y += H)
    for (int x = 0; x + W <= rd.width; x += W) {
      const std::vector<double> r = radial_psd(periodic(planes(rd, x, y, W, H, C), W, H), W, H);
      for (int b = 0; b < kBins; ++b) r_rd[b] += r[b];
      ++blocks;
    }
  EXPECT_GE(blocks, 4);
  const std::vector<double> r_ex = radial_psd(ex_p, W, H);
  const std::vector<int> n = radial_counts(W, H);
  std::vector<double> rel;
  for (int b = 0; b < kBins; ++b) {
    const double e = std::abs(r_rd[b] / blocks - r_ex[b]) / r_ex[b];
    rel.push_back(e);
    if (n[b] >= 200) a.psd_max = std::max(a.psd_max, e);
  }
  std::vector<double> sorted = rel;
  std::sort(sorted.begin(), sorted.end());
  a.psd_median = kBins % 2 ? sorted[kBins / 2] : 0.5 * (sorted[kBins / 2 - 1] + sorted[kBins / 2]);
  return a;
}

void check_exemplar(const std::string& exemplar, const std::string& name) {
  const std::string model = tmp_dir() + "/" + name + ".stex", render = tmp_dir() + "/" + name + ".exr";
  std::string err;
  ASSERT_EQ(run("analyze '" + exemplar + "' -o '" + model + "' --method texton", &err), 0) << err;
  ASSERT_EQ(run("render '" + model + "' -o '" + render + "' --size 2048x2048 --mni 30 --seed 11", &err), 0)
      << err;
  const Image ex = load_exemplar(exemplar);
  const Image rd = load_exemplar(render, LoadOptions{std::uint64_t(1) << 23, false});
  ASSERT_EQ(rd.width, 2048);
  const Acceptance a = measure(ex, rd);
  std::printf("[ acceptance ] %s (%dx%d, %d channel(s)), 2048^2 render at MNI 30: mean_err=%.4f cov_err=%.4f "
              "psd_median=%.4f psd_max=%.4f (limits 0.05, 0.03, 0.05, 0.20)\n",
              name.c_str(), ex.width, ex.height, ex.channels, a.mean_err, a.cov_err, a.psd_median, a.psd_max);
  EXPECT_LE(a.mean_err, 0.05);
  EXPECT_LE(a.cov_err, 0.03);
  EXPECT_LE(a.psd_median, 0.05);
  EXPECT_LE(a.psd_max, 0.20);
}

// A colour exemplar with correlated channels and an anisotropic spectrum, made from white noise: two
// independent Gaussian fields (an oriented band-pass lobe pair and a power-law field) mixed into RGB by a
// 3x2 matrix, plus independent grain per channel and a mean, written as 16-bit PNG. Nobody tuned stex on
// it.
std::string make_colour_exemplar() {
  const int W = 384, H = 384;
  std::mt19937_64 rng(20261201);
  std::normal_distribution<double> gauss(0.0, 1.0);
  auto field = [&](auto amplitude) {
    std::vector<Complex> f(std::size_t(W) * H);
    for (auto& v : f) v = Complex(gauss(rng), 0.0);
    fft2d_forward(W, H, f);
    for (int qy = 0; qy < H; ++qy)
      for (int qx = 0; qx < W; ++qx) {
        const double fx = (qx <= W / 2 ? qx : qx - W) / double(W), fy = (qy <= H / 2 ? qy : qy - H) / double(H);
        f[std::size_t(qy) * W + qx] *= amplitude(fx, fy);
      }
    fft2d_inverse(W, H, f);
    std::vector<double> out(f.size());
    double s2 = 0.0;
    for (std::size_t k = 0; k < f.size(); ++k) s2 += f[k].real() * f[k].real();
    const double norm = 1.0 / std::sqrt(s2 / double(f.size()));
    for (std::size_t k = 0; k < f.size(); ++k) out[k] = f[k].real() * norm;
    return out;
  };
  const double c = std::cos(0.5), s = std::sin(0.5);
  const std::vector<double> g1 = field([&](double fx, double fy) {
    const double u = c * fx + s * fy, v = -s * fx + c * fy;
    auto lobe = [&](double u0) { return std::exp(-((u - u0) * (u - u0) / (2 * 0.01 * 0.01) + v * v / (2 * 0.03 * 0.03))); };
    return lobe(0.08) + lobe(-0.08);
  });
  // Natural-image-like power law (power ~ 1/(f0 + |f|)^2): power at every frequency, as in photographs.
  const std::vector<double> g2 = field([](double fx, double fy) { return 1.0 / (0.02 + std::sqrt(fx * fx + fy * fy)); });
  // And a little independent noise per channel (sensor noise): the colour structure differs per frequency.
  std::vector<std::vector<double>> grain;
  for (int ch = 0; ch < 3; ++ch) grain.push_back(field([](double, double) { return 1.0; }));
  const double mix[3][2] = {{0.10, 0.04}, {0.07, -0.05}, {0.02, 0.08}}, mean[3] = {0.5, 0.45, 0.4};
  std::vector<std::uint16_t> px(std::size_t(W) * H * 3);
  for (std::size_t k = 0; k < g1.size(); ++k)
    for (int ch = 0; ch < 3; ++ch) {
      const double v = mean[ch] + mix[ch][0] * g1[k] + mix[ch][1] * g2[k] + 0.01 * grain[std::size_t(ch)][k];
      px[k * 3 + ch] = std::uint16_t(std::lround(std::clamp(v, 0.0, 1.0) * 65535.0));
    }
  const std::string path = tmp_dir() + "/colour.png";
  auto out = OIIO::ImageOutput::create(path);
  EXPECT_TRUE(out);
  OIIO::ImageSpec spec(W, H, 3, OIIO::TypeDesc::UINT16);
  EXPECT_TRUE(out->open(path, spec));
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::UINT16, px.data()));
  EXPECT_TRUE(out->close());
  return path;
}

}  // namespace

TEST(Acceptance, GravelAtTheDefaultsMatchesMeanCovarianceAndSpectrum) {
  check_exemplar(std::string(STEX_SOURCE_DIR) + "/data/gravel.png", "gravel");
}

TEST(Acceptance, SyntheticColourExemplarAtTheDefaultsMatchesMeanCovarianceAndSpectrum) {
  check_exemplar(make_colour_exemplar(), "colour");
}
