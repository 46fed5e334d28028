// Cyclostationary random-phase noise from user spectra (kind "cs-rpn", S4 §4.2, Fig. 1 left and 4): kernel ==
// C++ reference bit for bit (three variants, two scales, far from the origin); tile, chunk and work-group
// invariance; the local spectrum at two phases of the lattice matches the interpolated spectra there (a
// bi-lobe at 0 degrees at phase 0, at 90 degrees at phase 1/2); the variance is the spectra's energy; phasor
// output has the constant sine profile (arcsine law, bound) and concentrates at the local frequency; spectra
// files, the codec and its validation.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <vector>

#include "analysis/cs_rpn_model.h"
#include "analysis/expected_psd.h"
#include "analysis/lrp.h"
#include "analysis/fft.h"
#include "analysis/image_io.h"
#include "model/kinds.h"
#include "cli_run.h"
#include "core/error.h"
#include "core/math.h"
#include "runtime/context.h"
#include "runtime/cs_rpn.h"
#include "runtime/lrp_model.h"
#include "filter_quality.h"
#include "test_device.h"
#include "welch_se.h"

namespace stex {
namespace {


Context& ctx() {
  static std::unique_ptr<Context> c = Context::create(stex::test::test_device_spec());
  return *c;
}

RenderParams params(std::uint64_t seed, double scale = 1.0) {
  RenderParams rp;
  rp.seed = seed;
  rp.scale = scale;
  rp.mni = 16.0;
  return rp;
}

std::vector<float> device_render(CsRpnNoise& n, const RenderParams& rp, std::int64_t x, std::int64_t y, int w, int h) {
  std::vector<float> out(std::size_t(w) * h);
  n.render(rp, x, y, w, h, out.data());
  return out;
}

// Fig. 1 left: a bi-lobe rotating along t0 (3 spectra), skewed lattice.
CsRpnModel rotating(CsRpnVariant v) {
  CsRpnModel m;
  m.variant = v;
  m.t0x = 71.3;
  m.t0y = 9.2;
  m.t1x = -6.4;
  m.t1y = 58.7;
  const nlohmann::json j = {{"grid", {3, 1}}, {"size", 64},
                            {"spectra", {"bilobe:0.1,0,0.01", {{"psd", "bilobe:0.1,60,0.01"}, {"variance", 0.01}}, "bilobe:0.12,120,0.01"}}};
  cs_rpn_load_spectra(m, j);
  return cs_rpn_from_container(to_container(m));
}

// Two spectra along t0 = (96, 0): bi-lobe at 0 degrees at phase 0, at 90 degrees at phase 1/2.
CsRpnModel two_phase(CsRpnVariant v) {
  CsRpnModel m;
  m.variant = v;
  m.t0x = 96.0;
  m.t0y = 0.0;
  m.t1x = 0.0;
  m.t1y = 96.0;
  m.bandwidth = 0.05;
  m.spacing = 16.0;
  m.cosines = 16;
  const nlohmann::json j = {{"grid", {2, 1}}, {"size", 64}, {"spectra", {"bilobe:0.1,0,0.01", "bilobe:0.1,90,0.01"}}};
  cs_rpn_load_spectra(m, j);
  return m;
}

const CsRpnVariant k_all[] = {CsRpnVariant::RandomPhase, CsRpnVariant::Gabor, CsRpnVariant::Phasor, CsRpnVariant::Fourier};

TEST(CsRpn, KernelEqualsReference) {
  for (CsRpnVariant v : k_all) {
    const CsRpnModel m = rotating(v);
    CsRpnNoise noise(ctx(), m);
    for (double scale : {1.0, 0.6}) {
      const RenderParams rp = params(5, scale);
      const std::vector<float> ref = CsRpnReference(m, rp).render(-31, 12, 40, 24);
      EXPECT_EQ(device_render(noise, rp, -31, 12, 40, 24), ref) << cs_rpn_variant_name(v) << " " << scale;
    }
    const std::int64_t far = 1000000000000LL;
    const std::vector<float> a = CsRpnReference(m, params(5)).render(-far, far, 24, 16);
    EXPECT_EQ(device_render(noise, params(5), -far, far, 24, 16), a) << cs_rpn_variant_name(v);
    for (float x : a) ASSERT_TRUE(std::isfinite(x));
    // Not a copy of the origin.
    EXPECT_NE(a, CsRpnReference(m, params(5)).render(0, 0, 24, 16));
  }
}

TEST(CsRpn, TilesChunksAndWorkGroupsGiveTheSameBits) {
  for (CsRpnVariant v : k_all) {
    const CsRpnModel m = rotating(v);
    CsRpnNoise whole(ctx(), m);
    const int w = 50, h = 38;
    const std::vector<float> ref = device_render(whole, params(3), 7, -40, w, h);
    CsRpnNoise tiled(ctx(), m);
    tiled.local_size = {8, 2};
    tiled.max_chunk_pixels = 97;
    std::vector<float> assembled(ref.size());
    for (int ty = 0; ty < h; ty += 16)
      for (int tx = 0; tx < w; tx += 20) {
        const int tw = std::min(20, w - tx), th = std::min(16, h - ty);
        const std::vector<float> tile = device_render(tiled, params(3), 7 + tx, -40 + ty, tw, th);
        for (int j = 0; j < th; ++j)
          std::copy(tile.begin() + std::ptrdiff_t(j) * tw, tile.begin() + std::ptrdiff_t(j + 1) * tw,
                    assembled.begin() + std::ptrdiff_t(ty + j) * w + tx);
      }
    EXPECT_EQ(assembled, ref) << cs_rpn_variant_name(v);
    EXPECT_NE(device_render(whole, params(4), 7, -40, w, h), ref) << cs_rpn_variant_name(v);
  }
}

// ---- local spectra ----

constexpr int N = 64;  // patch side = the spectra's grid: bin k is k / 64 cycles per pixel

double hann(int i) { return std::pow(std::sin(k_pi * (i + 0.5) / N), 2); }

// Hann-windowed periodogram of a patch (mean removed), FFT order.
std::vector<double> periodogram(const std::vector<float>& patch) {
  double mean = 0.0;
  for (float v : patch) mean += v;
  mean /= double(patch.size());
  std::vector<std::complex<double>> a(std::size_t(N) * N), b(a.size());
  for (int j = 0; j < N; ++j)
    for (int i = 0; i < N; ++i) a[std::size_t(j) * N + i] = (patch[std::size_t(j) * N + i] - mean) * hann(i) * hann(j);
  std::vector<std::complex<double>> tw(N);
  for (int k = 0; k < N; ++k) tw[k] = std::polar(1.0, -2.0 * k_pi * k / N);
  for (int j = 0; j < N; ++j)  // rows
    for (int k = 0; k < N; ++k) {
      std::complex<double> s = 0.0;
      for (int i = 0; i < N; ++i) s += a[std::size_t(j) * N + i] * tw[(std::size_t(i) * k) % N];
      b[std::size_t(j) * N + k] = s;
    }
  std::vector<double> p(a.size());
  for (int k = 0; k < N; ++k)  // columns
    for (int l = 0; l < N; ++l) {
      std::complex<double> s = 0.0;
      for (int j = 0; j < N; ++j) s += b[std::size_t(j) * N + k] * tw[(std::size_t(j) * l) % N];
      p[std::size_t(l) * N + k] = std::norm(s);
    }
  return p;
}

int sgn_idx(int k) { return k < N / 2 ? k : k - N; }

// Energies of the annulus 0.05 <= |f| <= 0.15 cycles/pixel in the sector |fx| >= |fy| (the 0-degree lobes)
// and in all of it.
void x_energy(const std::vector<double>& p, double* ex, double* all) {
  *ex = *all = 0.0;
  for (int l = 0; l < N; ++l)
    for (int k = 0; k < N; ++k) {
      const double fx = double(sgn_idx(k)) / N, fy = double(sgn_idx(l)) / N, r = std::hypot(fx, fy);
      if (r < 0.05 || r > 0.15) continue;
      *all += p[std::size_t(l) * N + k];
      if (std::fabs(fx) >= std::fabs(fy)) *ex += p[std::size_t(l) * N + k];
    }
}

// The ratio estimator q = sum ex / sum all over M patches (it estimates E ex / E all, bias O(1 / M); the
// mean of per-patch ratios would estimate E[ex / all], which differs at order 1 for a single periodogram),
// and its standard error by the delta method: sqrt(var(ex - q all) / M) / mean(all).
void ratio_stats(const std::vector<double>& ex, const std::vector<double>& all, double* q, double* se) {
  double se_ = 0.0, sa = 0.0;
  for (std::size_t i = 0; i < ex.size(); ++i) {
    se_ += ex[i];
    sa += all[i];
  }
  *q = se_ / sa;
  const double M = double(ex.size()), ma = sa / M;
  double v = 0.0;
  for (std::size_t i = 0; i < ex.size(); ++i) v += std::pow(ex[i] - *q * all[i], 2);
  v /= (M - 1.0);
  *se = std::sqrt(v / M) / ma;
}

// Energy share within 0.03 cycles/pixel of the lobes +-(0.1 cos a, 0.1 sin a).
double lobe_share(const std::vector<double>& p, double angle_deg) {
  const double cx = 0.1 * std::cos(angle_deg * k_pi / 180), cy = 0.1 * std::sin(angle_deg * k_pi / 180);
  double in = 0.0, all = 0.0;
  for (int l = 0; l < N; ++l)
    for (int k = 0; k < N; ++k) {
      const double fx = double(sgn_idx(k)) / N, fy = double(sgn_idx(l)) / N;
      const double v = p[std::size_t(l) * N + k];
      all += v;
      if (std::hypot(fx - cx, fy - cy) <= 0.03 || std::hypot(fx + cx, fy + cy) <= 0.03) in += v;
    }
  return in / all;
}

// ---- the exact expected periodogram of a patch ----
// Both variants are sums of independent kernels c_i(x) = A_i e(x - x_i) cos(2 pi f.(x - x_i) + phi) with a
// uniform phase phi, so the Hann-windowed periodogram's expectation is exactly
//   E P(k) = sum_i A_i^2 / 4 E_f [ |G_i(k - f)|^2 + |G_i(k + f)|^2 ],   G_i(nu) = sum_x h(x) e(x - x_i) e^{-2 pi i nu.x},
// with f drawn from the mixture at x_i's phase (node w_c E_c / E, bin p_b, jitter uniform in the bin). The
// patch mean removed before windowing touches only bins |k| <= 1 (the Hann window's DFT is 3 bins wide), not
// the annulus. Numerics: the jitter integral by an s x s midpoint rule (G_i on a 1/(8 N) grid by zero-padded
// FFT, or 1-D DFTs for the separable Gabor envelope), Gabor's Poisson positions by a 1-px midpoint grid; the
// difference between s = 4 and s = 2 is reported and added to the tolerance as the quadrature error. The
// Gabor envelope's truncation at 2^-12 is ignored (2^-24 of the energy).
constexpr int k_fine = 8 * N;  // frequency grid: 1/8 bin

struct MixBin {
  int mx, my;
  double p;
};
std::vector<MixBin> mixture(const CsRpnModel& m, double u, double v, double* energy) {
  const double gx = (u - std::floor(u)) * m.k0, gy = (v - std::floor(v)) * m.k1;
  const int i0 = int(std::floor(gx)) % m.k0, j0 = int(std::floor(gy)) % m.k1;
  const double wx = gx - std::floor(gx), wy = gy - std::floor(gy);
  const int g[4] = {j0 * m.k0 + i0, j0 * m.k0 + (i0 + 1) % m.k0, ((j0 + 1) % m.k1) * m.k0 + i0,
                    ((j0 + 1) % m.k1) * m.k0 + (i0 + 1) % m.k0};
  const double w[4] = {(1 - wx) * (1 - wy), wx * (1 - wy), (1 - wx) * wy, wx * wy};
  double e = 0.0;
  for (int c = 0; c < 4; ++c) e += w[c] * m.spectra[std::size_t(g[c])].energy;
  *energy = e;
  std::vector<MixBin> out;
  for (int c = 0; c < 4; ++c) {
    const CsRpnSpectrum& sp = m.spectra[std::size_t(g[c])];
    const double wc = w[c] * sp.energy / e;
    if (wc == 0.0) continue;
    double total = 0.0;
    for (std::size_t b = 2; b < sp.bins.size(); b += 3) total += sp.bins[b];
    for (std::size_t b = 0; b < sp.bins.size(); b += 3)
      out.push_back({int(std::lround(sp.bins[b] * N)), int(std::lround(sp.bins[b + 1] * N)), wc * sp.bins[b + 2] / total});
  }
  return out;
}

struct AnnulusBin {
  int kx, ky;
  bool xsector;
};
std::vector<AnnulusBin> annulus() {
  std::vector<AnnulusBin> out;
  for (int l = 0; l < N; ++l)
    for (int k = 0; k < N; ++k) {
      const double fx = double(sgn_idx(k)) / N, fy = double(sgn_idx(l)) / N, r = std::hypot(fx, fy);
      if (r < 0.05 || r > 0.15) continue;
      out.push_back({sgn_idx(k), sgn_idx(l), std::fabs(fx) >= std::fabs(fy)});
    }
  return out;
}

int wrap(int q) { return ((q % k_fine) + k_fine) % k_fine; }

// Adds A^2 / 4 E_f[...] of one kernel to P over the annulus; g2(qx, qy) is |G|^2 at (qx, qy) / (8 N) cycles.
template <class G2>
void add_kernel(std::vector<double>& P, const std::vector<AnnulusBin>& ann, const std::vector<MixBin>& mix, double a2, int s,
                const G2& g2) {
  std::vector<int> d;  // jitter midpoints in 1/8-bin units
  for (int t = 0; t < s; ++t) d.push_back(int(std::lround(8.0 * ((t + 0.5) / s - 0.5))));
  const double ws = a2 / 4.0 / double(s * s);
  for (std::size_t q = 0; q < ann.size(); ++q) {
    double acc = 0.0;
    for (const MixBin& b : mix)
      for (int dx : d)
        for (int dy : d)
          acc += b.p * (g2(wrap(8 * (ann[q].kx - b.mx) - dx), wrap(8 * (ann[q].ky - b.my) - dy)) +
                        g2(wrap(8 * (ann[q].kx + b.mx) + dx), wrap(8 * (ann[q].ky + b.my) + dy)));
    P[q] += ws * acc;
  }
}

// Predicted x-sector share of the patch [x0, x0 + N) x [y0, y0 + N) for jitter quadrature s.
double predicted_share(const CsRpnModel& m, int x0, int y0, int s) {
  const std::vector<AnnulusBin> ann = annulus();
  std::vector<double> P(ann.size(), 0.0);
  if (m.variant == CsRpnVariant::RandomPhase) {
    const double delta = m.spacing, reach = 1.5 * delta;
    std::vector<Complex> buf(std::size_t(k_fine) * k_fine);
    std::vector<double> g2(buf.size());
    for (int ny = int(std::floor((y0 - reach) / delta)); ny <= int(std::ceil((y0 + N + reach) / delta)); ++ny)
      for (int nx = int(std::floor((x0 - reach) / delta)); nx <= int(std::ceil((x0 + N + reach) / delta)); ++nx) {
        const double xi = (nx + 0.5) * delta, yi = (ny + 0.5) * delta;
        std::fill(buf.begin(), buf.end(), Complex(0.0));
        bool any = false;
        for (int j = 0; j < N; ++j)
          for (int i = 0; i < N; ++i) {
            const double r = std::hypot(x0 + i + 0.5 - xi, y0 + j + 0.5 - yi) / delta;
            if (r >= 1.5) continue;
            buf[std::size_t(j) * k_fine + i] = hann(i) * hann(j) * lrp_window(r);
            any = true;
          }
        if (!any) continue;
        fft2d_forward(k_fine, k_fine, buf);
        for (std::size_t q = 0; q < buf.size(); ++q) g2[q] = std::norm(buf[q]);
        double e = 0.0;
        const std::vector<MixBin> mix = mixture(m, xi / m.t0x, yi / m.t1y, &e);
        add_kernel(P, ann, mix, e, s, [&](int qx, int qy) { return g2[std::size_t(qy) * k_fine + qx]; });
      }
  } else {
    // Separable envelope: G = Gx(nu_x; x_i) Gy(nu_y; y_i); Poisson positions on a 1-px midpoint grid.
    const double a2pi = k_pi * m.bandwidth * m.bandwidth;
    const int reach = 40;
    auto profile = [&](double c, std::vector<double>& out) {  // |sum_j h(j) e(j + 0.5 - c) e^{-2 pi i nu j}|^2
      out.assign(k_fine, 0.0);
      for (int q = 0; q < k_fine; ++q) {
        Complex acc = 0.0;
        for (int j = 0; j < N; ++j) {
          const double d = j + 0.5 - c;
          acc += hann(j) * std::exp(-a2pi * d * d) * std::polar(1.0, -2.0 * k_pi * double(q) * j / k_fine);
        }
        out[std::size_t(q)] = std::norm(acc);
      }
    };
    std::vector<double> Y(k_fine, 0.0), col;
    for (int t = -reach; t < N + reach; ++t) {
      profile(t + 0.5, col);
      for (int q = 0; q < k_fine; ++q) Y[std::size_t(q)] += col[std::size_t(q)];
    }
    // The phase depends on x only here (t0 along x, t1 = (0, T), k1 = 1: checked by the caller).
    for (int t = -reach; t < N + reach; ++t) {
      profile(t + 0.5, col);
      double e = 0.0;
      const std::vector<MixBin> mix = mixture(m, (x0 + t + 0.5) / m.t0x, 0.0, &e);
      add_kernel(P, ann, mix, e, s, [&](int qx, int qy) { return col[std::size_t(qx)] * Y[std::size_t(qy)]; });
    }
  }
  double ex = 0.0, all = 0.0;
  for (std::size_t q = 0; q < ann.size(); ++q) {
    all += P[q];
    if (ann[q].xsector) ex += P[q];
  }
  return ex / all;
}

struct PatchStats {
  double share_mean = 0.0, share_se = 0.0, var_mean = 0.0, var_se = 0.0, lobe_mean = 0.0, lobe_se = 0.0;
};

double mean_of(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s / double(v.size());
}
double se_of(const std::vector<double>& v) {
  const double m = mean_of(v);
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / double(v.size() - 1) / double(v.size()));
}

// 64 patches at phase u (centres x = 192 k + 96 u, y = 160 l): 128 px apart (>= 64 + 2 x 33 px of kernel reach),
// so their statistics are independent and the standard errors come from their spread.
PatchStats measure(CsRpnNoise& noise, const CsRpnModel& m, double u, double lobe_angle) {
  std::vector<double> exs, alls, vars, lobes;
  for (int l = 0; l < 8; ++l)
    for (int k = 0; k < 8; ++k) {
      const std::int64_t cx = 192 * k + std::int64_t(std::lround(96 * u)), cy = 160 * l;
      const std::vector<float> patch = device_render(noise, params(11), cx - N / 2, cy - N / 2, N, N);
      const std::vector<double> p = periodogram(patch);
      double ex = 0.0, all = 0.0;
      x_energy(p, &ex, &all);
      exs.push_back(ex);
      alls.push_back(all);
      lobes.push_back(lobe_share(p, lobe_angle));
      double v = 0.0;
      for (float x : patch) v += (x - m.mean) * (x - m.mean);
      vars.push_back(v / double(patch.size()));
    }
  PatchStats st{0.0, 0.0, mean_of(vars), se_of(vars), mean_of(lobes), se_of(lobes)};
  ratio_stats(exs, alls, &st.share_mean, &st.share_se);
  return st;
}

// Gabor and random-phase: at phase 0 the local PSD is the 0-degree bi-lobe, at phase 1/2 the 90-degree one
// (two spectra along t0 = (96, 0)). The statistic is the share q of the annulus 0.05..0.15 cycles/pixel in the
// sector |fx| >= |fy| of the Hann-windowed periodogram, averaged over 64 independent patches (SE from their
// spread, ratio estimator sum ex / sum all with the delta-method SE); its expectation is the ratio of the exact
// expected periodograms above, to O(1 / 64). Tolerance: 4 SE + the
// quadrature error |q(s = 4) - q(s = 2)|. The variance over the patches is the spectra's energy E = 0.0225
// within 4 SE (random phase: the lattice-averaged variance, a 64-px patch holds 4 x 4 lattice cells).
TEST(CsRpnSpectrum, LocalSpectrumFollowsTheInterpolatedSpectra) {
  for (CsRpnVariant v : {CsRpnVariant::Gabor, CsRpnVariant::RandomPhase}) {
    const CsRpnModel m = two_phase(v);
    ASSERT_EQ(m.k1, 1);
    CsRpnNoise noise(ctx(), m);
    for (double u : {0.0, 0.5}) {
      const int x0 = int(std::lround(96 * u)) - N / 2, y0 = -N / 2;  // every patch has this alignment mod 16 and 96
      const double q4 = predicted_share(m, x0, y0, 4), q2 = predicted_share(m, x0, y0, 2);
      const PatchStats s = measure(noise, m, u, u == 0.0 ? 0.0 : 90.0);
      const double tol = 4.0 * s.share_se + std::fabs(q4 - q2);
      std::printf("%s phase %.1f: x-sector share %.4f +- %.4f (SE), expected %.4f (s = 2: %.4f), |z| %.2f, tol %.4f; "
                  "variance %.5f +- %.5f (E 0.0225); lobe share %.4f +- %.4f\n",
                  cs_rpn_variant_name(v).c_str(), u, s.share_mean, s.share_se, q4, q2,
                  std::fabs(s.share_mean - q4) / s.share_se, tol, s.var_mean, s.var_se, s.lobe_mean, s.lobe_se);
      EXPECT_NEAR(s.share_mean, q4, tol) << cs_rpn_variant_name(v) << " u " << u;
      // The model itself orients the two phases apart.
      if (u == 0.0) {
        EXPECT_GT(q4, 0.75);
      } else {
        EXPECT_LT(q4, 0.25);
      }
      EXPECT_NEAR(s.var_mean, 0.0225, 4.0 * s.var_se) << cs_rpn_variant_name(v) << " u " << u;
    }
  }
}

// Fourier (S4 Fig. 4): one realisation repeats every T = 64 px, so the 64 patches per phase come from 64
// seeds (independent phases); statistic and SE as above (ratio estimator). The series' terms are independent with uniform phases, so the expected
// periodogram is exact: E P(k) = sum_f 1/4 (|D_f(k - f)|^2 + |D_f(k + f)|^2), D_f the DFT of h(x) h(y)
// sqrt(2 S^{u(x)}(f)) (separable here: the phase depends on x only); frequencies on the grid, no quadrature.
// Tolerance 4 SE; the variance is E(u) averaged over the patch's columns with weight 1 (unwindowed), 4 SE.
TEST(CsRpnSpectrum, FourierSeriesLocalSpectrumIsExact) {
  const CsRpnModel m = two_phase(CsRpnVariant::Fourier);
  CsRpnNoise noise(ctx(), m);
  const std::vector<AnnulusBin> ann = annulus();
  std::vector<Complex> hy(N);
  for (int l = 0; l < N; ++l)
    for (int j = 0; j < N; ++j) hy[std::size_t(l)] += hann(j) * std::polar(1.0, -2.0 * k_pi * double(j) * l / N);
  for (double u : {0.0, 0.5}) {
    const int x0 = int(std::lround(96 * u)) - N / 2, y0 = -N / 2;
    // S_f(x) per canonical frequency, per column.
    std::map<std::pair<int, int>, std::vector<double>> amp;
    double evar = 0.0;
    for (int i = 0; i < N; ++i) {
      double e = 0.0;
      const std::vector<MixBin> mix = mixture(m, (x0 + i + 0.5) / m.t0x, 0.0, &e);
      evar += e / N;
      for (const MixBin& b : mix) {
        std::pair<int, int> key{b.mx, b.my};
        if (b.my < 0 || (b.my == 0 && b.mx < 0)) key = {-b.mx, -b.my};
        std::vector<double>& a = amp[key];
        a.resize(N, 0.0);
        a[std::size_t(i)] += e * b.p;
      }
    }
    std::vector<double> P(ann.size(), 0.0);
    for (auto& [f, sv] : amp) {
      std::vector<Complex> dx(N);
      for (int k = 0; k < N; ++k)
        for (int i = 0; i < N; ++i)
          dx[std::size_t(k)] += hann(i) * std::sqrt(2.0 * sv[std::size_t(i)]) * std::polar(1.0, -2.0 * k_pi * double(i) * k / N);
      auto d2 = [&](int kx, int ky) { return std::norm(dx[std::size_t(((kx % N) + N) % N)] * hy[std::size_t(((ky % N) + N) % N)]); };
      for (std::size_t q = 0; q < ann.size(); ++q)
        P[q] += 0.25 * (d2(ann[q].kx - f.first, ann[q].ky - f.second) + d2(ann[q].kx + f.first, ann[q].ky + f.second));
    }
    double ex = 0.0, all = 0.0;
    for (std::size_t q = 0; q < ann.size(); ++q) {
      all += P[q];
      if (ann[q].xsector) ex += P[q];
    }
    const double expected = ex / all;
    std::vector<double> exs, alls, vars;
    for (std::uint64_t seed = 0; seed < 64; ++seed) {
      const std::vector<float> patch = device_render(noise, params(100 + seed), x0, y0, N, N);
      double e1 = 0.0, a1 = 0.0;
      x_energy(periodogram(patch), &e1, &a1);
      exs.push_back(e1);
      alls.push_back(a1);
      double v = 0.0;
      for (float x : patch) v += (x - m.mean) * (x - m.mean);
      vars.push_back(v / double(patch.size()));
    }
    double q = 0.0, se = 0.0;
    ratio_stats(exs, alls, &q, &se);
    const double var = mean_of(vars), vse = se_of(vars);
    std::printf("fourier phase %.1f: x-sector share %.4f +- %.4f, expected %.4f, |z| %.2f; variance %.5f +- %.5f (expected %.5f)\n", u, q,
                se, expected, std::fabs(q - expected) / se, var, vse, evar);
    EXPECT_NEAR(q, expected, 4.0 * se) << u;
    EXPECT_NEAR(var, evar, 4.0 * vse) << u;
    if (u == 0.0) {
      EXPECT_GT(expected, 0.75);
    } else {
      EXPECT_LT(expected, 0.25);
    }
  }
  // The series repeats every T = 64 model pixels and its amplitude every 96: the render every 192.
  EXPECT_EQ(device_render(noise, params(3), 5, 7, 16, 8), device_render(noise, params(3), 5 + 192 * 3, 7 - 192 * 5, 16, 8));
  EXPECT_NE(device_render(noise, params(3), 5, 7, 16, 8), device_render(noise, params(3), 5 + 64, 7, 16, 8));
}

// The amplitude A(x, .)^2 = S^{P(x)} varies over the whole parallelogram (a 2 x 2 grid of spectra of energies
// 0.01, 0.04, 0.03, 0.0025, skewed lattice t0 = (128, 0), t1 = (32, 128): bilinear in both lattice
// coordinates). The pixel variance at a phase is exact for both variants:
//   gabor:        Var(x) = 2 a^2 int E(u(x - d)) exp(-2 pi a^2 |d|^2) dd    (impulses' energies under env^2)
//   random phase: Var(x) = sum_i w(|x - x_i| / Delta)^2 E(u_i) / (2 pi W)  (the 9 lattice points)
// (gabor's integral by a 0.25-px midpoint grid; the truncation at 2^-12 ignored). Estimated from 2025 pixels
// congruent to x (x + k t0 + l t1, >= 128 px apart: independent; the lattice spacing 16 divides the periods, so
// the random-phase lattice is aligned alike), known mean; tolerance 4 SE with SE = sqrt((m4 - var^2) / n).
TEST(CsRpnSpectrum, VarianceFollowsTheInterpolatedEnergyOverTheParallelogram) {
  for (CsRpnVariant v : {CsRpnVariant::Gabor, CsRpnVariant::RandomPhase}) {
    CsRpnModel m;
    m.variant = v;
    m.t0x = 128.0;
    m.t0y = 0.0;
    m.t1x = 32.0;
    m.t1y = 128.0;
    m.spacing = 16.0;
    m.cosines = 8;
    const nlohmann::json j = {{"grid", {2, 2}}, {"size", 64},
                              {"spectra", {{{"psd", "bilobe:0.1,0,0.01"}, {"variance", 0.01}},
                                           {{"psd", "bilobe:0.1,45,0.01"}, {"variance", 0.04}},
                                           {{"psd", "ring:0.1,0.01"}, {"variance", 0.03}},
                                           {{"psd", "gauss:0.05,0.05,0.01"}, {"variance", 0.0025}}}}};
    cs_rpn_load_spectra(m, j);
    const CsRpnReference ref(m, params(7));
    const double det = m.t0x * m.t1y - m.t0y * m.t1x;
    auto phase_u = [&](double x, double y) { return (m.t1y * x - m.t1x * y) / det; };
    auto phase_v = [&](double x, double y) { return (-m.t0y * x + m.t0x * y) / det; };
    for (const auto& uv : std::vector<std::array<double, 2>>{{0.1, 0.2}, {0.5, 0.5}, {0.8, 0.3}, {0.35, 0.9}}) {
      const std::int64_t px = std::int64_t(std::floor(uv[0] * m.t0x + uv[1] * m.t1x)), py = std::int64_t(std::floor(uv[1] * m.t1y));
      const double cx = px + 0.5, cy = py + 0.5;
      double expected = 0.0;
      if (v == CsRpnVariant::Gabor) {
        const double a2 = m.bandwidth * m.bandwidth;
        for (double dy = -40.0 + 0.125; dy < 40.0; dy += 0.25)
          for (double dx = -40.0 + 0.125; dx < 40.0; dx += 0.25)
            expected += cs_rpn_energy(m, phase_u(cx - dx, cy - dy), phase_v(cx - dx, cy - dy)) *
                        std::exp(-2.0 * k_pi * a2 * (dx * dx + dy * dy)) * 0.0625;
        expected *= 2.0 * a2;
      } else {
        for (int ny = int(std::floor(cy / 16.0)) - 2; ny <= int(std::floor(cy / 16.0)) + 2; ++ny)
          for (int nx = int(std::floor(cx / 16.0)) - 2; nx <= int(std::floor(cx / 16.0)) + 2; ++nx) {
            const double xi = 16.0 * nx + 8.0, yi = 16.0 * ny + 8.0, r = std::hypot(cx - xi, cy - yi) / 16.0;
            if (r >= 1.5) continue;
            expected += std::pow(lrp_window(r), 2) * cs_rpn_energy(m, phase_u(xi, yi), phase_v(xi, yi));
          }
        expected /= 2.0 * k_pi * lrp_window_integral();
      }
      double m2 = 0.0, m4 = 0.0;
      int n = 0;
      for (int l = 0; l < 45; ++l)
        for (int k = 0; k < 45; ++k) {
          const double d = ref.render(px + 128 * k + 32 * l, py + 128 * l, 1, 1)[0] - m.mean;
          m2 += d * d;
          m4 += d * d * d * d;
          ++n;
        }
      m2 /= n;
      m4 /= n;
      const double se = std::sqrt((m4 - m2 * m2) / n);
      std::printf("%s phase (%.2f, %.2f): variance %.5f +- %.5f, expected %.5f (E(u) %.5f), |z| %.2f\n",
                  cs_rpn_variant_name(v).c_str(), uv[0], uv[1], m2, se, expected,
                  cs_rpn_energy(m, phase_u(cx, cy), phase_v(cx, cy)), std::fabs(m2 - expected) / se);
      EXPECT_NEAR(m2, expected, 4.0 * se) << cs_rpn_variant_name(v) << " " << uv[0] << "," << uv[1];
    }
  }
}

// Phasor: I = mean + sqrt(2 E(P(x))) sin(arg phi): |I - mean| <= sqrt(2 E) everywhere (float rounding: 1e-5
// relative), and since the impulses' phases are uniform and independent, phi's law is rotation invariant and
// arg phi is uniform: s = (I - mean) / sqrt(2 E) follows the arcsine law F(s) = 1/2 + asin(s) / pi. Samples on
// a grid 24 px apart (3 envelope standard deviations, 1 / (a sqrt(2 pi)) = 8 px), 1280 samples: KS's 99.9 %
// quantile 1.95 / sqrt(n) = 0.055 (the residual correlation makes n slightly smaller; measured is printed).
// Spectrum: the share of the periodogram within 0.03 cycles/pixel of the local lobes is at least Gabor's
// (phasor noise concentrates at the local frequency, Tricard et al. 2019), both over the same 64 patches.
TEST(CsRpnSpectrum, PhasorHasAConstantProfileAndConcentratesAtTheLocalFrequency) {
  const CsRpnModel m = two_phase(CsRpnVariant::Phasor);
  CsRpnNoise noise(ctx(), m);
  const std::vector<float> img = device_render(noise, params(21), 0, 0, 960, 768);
  double worst = 0.0;
  std::vector<double> s;
  for (int y = 0; y < 768; ++y)
    for (int x = 0; x < 960; ++x) {
      const double e = cs_rpn_energy(m, (x + 0.5) / m.t0x, (y + 0.5) / m.t1y);
      const double r = (img[std::size_t(y) * 960 + x] - m.mean) / std::sqrt(2.0 * e);
      worst = std::max(worst, std::fabs(r));
      if (x % 24 == 0 && y % 24 == 0) s.push_back(r);
    }
  std::sort(s.begin(), s.end());
  double ks = 0.0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double f = 0.5 + std::asin(std::clamp(s[i], -1.0, 1.0)) / k_pi;
    ks = std::max({ks, std::fabs(f - double(i) / s.size()), std::fabs(f - double(i + 1) / s.size())});
  }
  const double bound = 1.95 / std::sqrt(double(s.size()));
  std::printf("phasor: max |I - mean| / sqrt(2E) = %.7f; KS vs arcsine %.4f (bound %.4f, n %zu)\n", worst, ks, bound, s.size());
  EXPECT_LE(worst, 1.0 + 1e-5);
  EXPECT_GT(worst, 0.999);
  EXPECT_LT(ks, bound);

  const CsRpnModel g = two_phase(CsRpnVariant::Gabor);
  CsRpnNoise gabor(ctx(), g);
  for (double u : {0.0, 0.5}) {
    const double angle = u == 0.0 ? 0.0 : 90.0;
    const PatchStats ps = measure(noise, m, u, angle), gs = measure(gabor, g, u, angle);
    std::printf("phase %.1f: lobe share phasor %.4f +- %.4f, gabor %.4f +- %.4f; x-sector share phasor %.4f, gabor %.4f\n", u,
                ps.lobe_mean, ps.lobe_se, gs.lobe_mean, gs.lobe_se, ps.share_mean, gs.share_mean);
    EXPECT_GT(ps.lobe_mean, gs.lobe_mean - 4.0 * std::hypot(ps.lobe_se, gs.lobe_se));
    if (u == 0.0) {
      EXPECT_GT(ps.share_mean, 0.75);
    }
    if (u == 0.5) {
      EXPECT_LT(ps.share_mean, 0.25);
    }
  }
}

// ---- spectra, codec, validation ----

TEST(CsRpnSpectrum, RenderMatchesTheExpectedWelchSpectrumOfEachVariant) {
  // The spectrum check `stex cs-rpn` prints (analysis/expected_psd.h) predicts the render: one bi-lobe rendered
  // alone (a 1 x 1 grid: stationary), 512^2 at seed 5, Welch at T = 64 (15 x 15 crops), against
  // cs_rpn_expected_welch_psd in radial bins of width 2 frequency bins holding >= 1 % of the variance, and the
  // variance: each within 4 SE: the Gaussian estimator's (tests/welch_se.h) and, for the linear variants, the
  // shot-noise term (each impulse or cosine carries one frequency of the table: a ring's power also follows how
  // many fell in it; random phase's lattice makes that count binomial, which the Poisson bound covers).
  // Phasor's prediction takes phi as Gaussian (the limit of many impulses), hence mni 64 for it. The Fourier series repeats every T = 64 pixels, so its crops
  // are one realisation: tests/analysis/test_expected_psd.cpp checks it exactly instead.
  const nlohmann::json j = {{"grid", {1, 1}}, {"size", 64}, {"spectra", {"bilobe:0.12,30,0.015"}}};
  for (CsRpnVariant v : {CsRpnVariant::RandomPhase, CsRpnVariant::Gabor, CsRpnVariant::Phasor}) {
    CsRpnModel m;
    m.variant = v;
    m.bandwidth = 0.05;
    m.spacing = 16.0;
    m.cosines = 16;
    cs_rpn_load_spectra(m, j);
    m = cs_rpn_from_container(to_container(m));
    const int t = cs_rpn_spectrum_period(m);
    ASSERT_EQ(t, 64);
    const std::vector<double> want = cs_rpn_expected_welch_psd(m, 0);
    RenderParams rp = params(5);
    if (v == CsRpnVariant::Phasor) rp.mni = 64.0;
    // impulses (cosines) per pixel^2, and max / mean power per impulse (1 + exp(-2 pi |f|^2 / a^2) for Gabor)
    const double lambda = v == CsRpnVariant::RandomPhase ? m.cosines / (m.spacing * m.spacing)
                          : v == CsRpnVariant::Gabor     ? make_cs_rpn_setup(m, rp).lambda
                                                         : 0.0;
    double qmax = 0.0, qsum = 0.0, wsum = 0.0;
    for (std::size_t b = 0; b < m.spectra[0].bins.size(); b += 3) {
      const double f2 = double(m.spectra[0].bins[b]) * m.spectra[0].bins[b] + double(m.spectra[0].bins[b + 1]) * m.spectra[0].bins[b + 1];
      const double q = v == CsRpnVariant::Gabor ? 1.0 + std::exp(-2.0 * k_pi * f2 / (m.bandwidth * m.bandwidth)) : 1.0;
      qmax = std::max(qmax, q);
      qsum += m.spectra[0].bins[b + 2] * q;
      wsum += m.spectra[0].bins[b + 2];
    }
    auto shot = [&](double share) {
      return lambda > 0.0 ? test::welch_shot_rel_var(lambda, 512, t, share, qmax / (qsum / wsum)) : 0.0;
    };
    CsRpnNoise dev(ctx(), m);
    Image img;
    img.width = img.height = 512;
    img.channels = 1;
    img.pixels = device_render(dev, rp, 0, 0, 512, 512);
    const LrpSpectrum got = lrp_welch(img, t);
    ASSERT_EQ(got.crops, 225);
    const double var = std::accumulate(want.begin(), want.end(), 0.0);
    const std::vector<std::vector<std::size_t>> bins = test::welch_rings(64, 2.0, 17);
    const std::vector<std::size_t> all = test::welch_rings(64, 1e9, 1)[0];
    double worst = 0.0;
    for (const auto& bin : bins) {
      double g = 0.0, w = 0.0;
      for (std::size_t i : bin) {
        g += got.psd[i];
        w += want[i];
      }
      if (w < 0.01 * var) continue;
      const double se = std::sqrt(std::pow(test::welch_rel_se(want, bin, 15), 2.0) + shot(w / var));
      worst = std::max(worst, std::fabs(g / w - 1.0) / se);
      EXPECT_LT(std::fabs(g / w - 1.0), 4.0 * se) << cs_rpn_variant_name(v) << " radial bin at " << bin.size();
    }
    const double gv = std::accumulate(got.psd.begin(), got.psd.end(), 0.0);
    const double vse = std::sqrt(std::pow(test::welch_rel_se(want, all, 15), 2.0) + shot(1.0));
    EXPECT_NEAR(gv / var, 1.0, 4.0 * vse) << cs_rpn_variant_name(v);
    std::printf("%s: worst radial |z| %.2f, variance render / expected %.4f +- %.4f\n", cs_rpn_variant_name(v).c_str(),
                worst, gv / var, vse);
  }
}

TEST(CsRpnModel, SpectrumTablesFoldOntoThePrincipalHalfPlane) {
  const CsRpnSpectrum s = cs_rpn_spectrum(lrp_analytic_psd("bilobe:0.1,60,0.01", 64, 1.0), 0.02, "b");
  EXPECT_EQ(s.energy, 0.02);
  double total = 0.0, near = 0.0;
  const double cx = 0.1 * std::cos(k_pi / 3), cy = 0.1 * std::sin(k_pi / 3);
  for (std::size_t b = 0; b < s.bins.size(); b += 3) {
    total += s.bins[b + 2];
    if (std::hypot(s.bins[b] - cx, s.bins[b + 1] - cy) < 0.04) near += s.bins[b + 2];
    EXPECT_GE(s.bins[b] * 0.5 + s.bins[b + 1] * 0.866, 0.0);  // the half plane of direction 60 degrees
  }
  EXPECT_GT(near / total, 0.999);  // one lobe, not its mirror
  // The expected local PSD sums to E and, between two spectra, interpolates.
  CsRpnModel m = two_phase(CsRpnVariant::Gabor);
  m.spectra[1].energy = 0.01;
  for (double u : {0.0, 0.25, 0.5, 0.9}) {
    const std::vector<double> p = cs_rpn_local_psd(m, u, 0.3, 64);
    double sum = 0.0;
    for (double v : p) sum += v;
    const double w = u <= 0.5 ? 2 * u : 2 * (1 - u);
    EXPECT_NEAR(sum, (1 - w) * 0.0225 + w * 0.01, 1e-12);
    EXPECT_NEAR(cs_rpn_energy(m, u, 0.3), sum, 1e-12);
  }
}

TEST(CsRpnModel, CodecRoundTripAndValidation) {
  const CsRpnModel m = rotating(CsRpnVariant::Phasor);
  const ModelContainer c = to_container(m);
  EXPECT_EQ(c.kind, "cs-rpn");
  const std::vector<std::uint8_t> bytes = encode_container(c);
  const CsRpnModel back = cs_rpn_from_container(decode_container(bytes.data(), bytes.size()));
  EXPECT_EQ(back.variant, m.variant);
  EXPECT_EQ(back.k0, 3);
  ASSERT_EQ(back.spectra.size(), 3u);
  EXPECT_EQ(back.spectra[1].bins, m.spectra[1].bins);
  EXPECT_EQ(back.spectra[1].energy, 0.01);
  EXPECT_EQ(back.spectra[2].source, "bilobe:0.12,120,0.01");
  EXPECT_NO_THROW(check_model(c));
  const NoiseModelSummary s = describe_noise_model(c);
  EXPECT_EQ(s.channels, 1);
  EXPECT_FLOAT_EQ(s.mean[0], 0.5f);

  auto rejects = [&](const std::function<void(ModelContainer&)>& damage, const std::string& word) {
    ModelContainer d = c;
    damage(d);
    try {
      check_model(d, "m");
      ADD_FAILURE() << "accepted: " << word;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << word;
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  rejects([](ModelContainer& d) { d.metadata["variant"] = "perlin"; }, "variant");
  rejects([](ModelContainer& d) { d.metadata["grid"]["k0"] = 2; }, "spectra");
  rejects([](ModelContainer& d) { d.metadata["grid"]["k1"] = 17; }, "k1");
  rejects([](ModelContainer& d) { d.metadata["periods"] = {{1.0, 0.0}, {2.0, 0.0}}; }, "parallelogram");
  rejects([](ModelContainer& d) { d.payload.pop_back(); }, "payload");
  rejects([](ModelContainer& d) { d.payload[2] = -1.0f; }, "weights");
  rejects([](ModelContainer& d) { d.payload[0] = 0.7f; }, "0.5 cycles");
  rejects([](ModelContainer& d) { d.metadata["bin"] = 0.0; }, "bin");
  rejects([](ModelContainer& d) { d.metadata["bandwidth"] = 2.0; }, "bandwidth");
  rejects([](ModelContainer& d) { d.metadata["cosines"] = 0; }, "cosines");
  {
    ModelContainer f = c;
    f.metadata["variant"] = "fourier";
    EXPECT_NO_THROW(check_model(f));
    f.metadata["bin"] = 0.01;
    rejects([&](ModelContainer& d) { d = f; }, "fourier needs bin");
    f.metadata["bin"] = 1.0 / 64.0;
    f.payload[0] += 0.003f;
    rejects([&](ModelContainer& d) { d = f; }, "on the grid");
  }
  rejects([](ModelContainer& d) { d.metadata["spectra"][1]["energy"] = -1.0; }, "energy");
  rejects([](ModelContainer& d) {
    for (auto& e : d.metadata["spectra"]) e["energy"] = 0.0;
  }, "energy 0");
  rejects([](ModelContainer& d) { d.kind = "gabor"; d.metadata["kind"] = "gabor"; }, "gabor");
}

TEST(CsRpnModel, SpectraFileErrorsAreUsageErrors) {
  auto usage = [](const nlohmann::json& j, const std::string& word) {
    CsRpnModel m;
    try {
      cs_rpn_load_spectra(m, j);
      ADD_FAILURE() << "accepted: " << j.dump();
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Usage) << e.what();
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  usage(nlohmann::json::array(), "JSON object");
  usage({{"spectra", {"ring:0.1,0.01"}}}, "grid");
  usage({{"grid", {2, 1}}, {"spectra", {"ring:0.1,0.01"}}}, "needs 2 spectra");
  usage({{"grid", {1, 1}}, {"size", 48}, {"spectra", {"ring:0.1,0.01"}}}, "power of two");
  usage({{"grid", {1, 1}}, {"spectra", {"donut:1"}}}, "entry 0");
  usage({{"grid", {1, 1}}, {"spectra", {{{"psd", "ring:0.1,0.01"}, {"variance", -2}}}}}, "variance");
  usage({{"grid", {1, 1}}, {"spectra", {{{"psd", "ring:0.1,0.01"}, {"image", "x.png"}}}}}, "exactly one");
  CsRpnModel m;
  EXPECT_THROW(cs_rpn_load_spectra_file(m, "/nonexistent/spectra.json"), Error);
}

TEST(CsRpn, RegistryRendersTheKind) {
  const CsRpnModel m = rotating(CsRpnVariant::Gabor);
  const std::unique_ptr<NoiseRenderer> r = make_noise_renderer(ctx(), to_container(m));
  EXPECT_EQ(r->kind(), "cs-rpn");
  EXPECT_EQ(r->channels(), 1);
  std::vector<float> out(20 * 10);
  r->render(params(2), 4, 4, 20, 10, out.data());
  EXPECT_EQ(out, CsRpnReference(m, params(2)).render(4, 4, 20, 10));
  EXPECT_THROW(make_noise_renderer(ctx(), to_container(m), NoiseRendererOptions{"splat"}), Error);
}

TEST(CsRpn, RenderParameterErrorsAreUsageErrors) {
  auto usage = [](const CsRpnModel& m, const RenderParams& rp, const std::string& word) {
    try {
      make_cs_rpn_setup(m, rp);
      ADD_FAILURE() << "accepted: " << word;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Usage) << e.what();
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  RenderParams rp = params(1, 0.01);
  usage(rotating(CsRpnVariant::Gabor), rp, "shorter than 1 output pixel");
  rp = params(1);
  rp.mni = 0.0;
  usage(rotating(CsRpnVariant::Phasor), rp, "mni");
  EXPECT_NO_THROW(make_cs_rpn_setup(rotating(CsRpnVariant::RandomPhase), params(1)));  // lattice: mni unused
  CsRpnModel m = rotating(CsRpnVariant::RandomPhase);
  m.spacing = 1.0;
  usage(m, params(1, 0.2), "spacing");
}

// ---- CLI end to end: `stex cs-rpn` then `stex render` (single image and tiles) equal the reference ----
TEST(CsRpnCli, MakeThenRender) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(STEX_TEST_TMP_DIR) / "cs_rpn_cli";
  fs::remove_all(dir);
  fs::create_directories(dir);
  auto stex = [](const std::string& args) { return test::run_stex_cli(args, "cs_rpn_cli_run"); };
  const std::string spectra = (dir / "s.json").string(), model = (dir / "m.stex").string();
  {
    std::ofstream f(spectra);
    f << R"({"grid": [3, 1], "size": 64, "spectra": ["bilobe:0.1,0,0.01", {"psd": "bilobe:0.1,60,0.01", "variance": 0.01}, "bilobe:0.12,120,0.01"]})";
  }
  for (const char* variant : {"random-phase", "gabor", "phasor", "fourier"}) {
    test::CliRun r = stex("cs-rpn -o '" + model + "' --periods 71.3,9.2,-6.4,58.7 --spectra '" + spectra + "' --variant " + variant);
    ASSERT_EQ(r.code, 0) << r.err;
    const CsRpnModel m = cs_rpn_from_container(load_container(model));
    const CsRpnModel want = rotating(CsRpnVariant(parse_cs_rpn_variant(variant)));
    EXPECT_EQ(m.spectra[1].bins, want.spectra[1].bins);
    RenderParams rp = params(9);
    const std::vector<float> ref = CsRpnReference(m, rp).render(100, -5, 48, 32);
    // --mni: the impulse variants read it; random-phase and fourier refuse it (exit 2)
    const bool impulses = std::string(variant) == "gabor" || std::string(variant) == "phasor";
    const std::string mni = impulses ? " --mni 16" : "";
    if (!impulses) {
      r = stex("render '" + model + "' -o '" + (dir / "r.exr").string() + "' --size 48x32 --seed 9 --mni 16");
      EXPECT_EQ(r.code, 2) << variant;
      EXPECT_NE(r.err.find("--mni does not apply"), std::string::npos) << r.err;
    }
    r = stex("render '" + model + "' -o '" + (dir / "r.exr").string() + "' --size 48x32 --origin 100,-5 --seed 9" + mni);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(load_exemplar((dir / "r.exr").string()).pixels, ref) << variant;
    r = stex("render '" + model + "' -o '" + (dir / "t_{tx}_{ty}.exr").string() +
             "' --size 48x32 --origin 100,-5 --seed 9" + mni + " --tile-size 32 --force");
    ASSERT_EQ(r.code, 0) << r.err;
    const Image t00 = load_exemplar((dir / "t_0_0.exr").string()), t10 = load_exemplar((dir / "t_1_0.exr").string());
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 48; ++x)
        ASSERT_EQ(x < 32 ? t00.at(x, y, 0) : t10.at(x - 32, y, 0), ref[std::size_t(y) * 48 + x]) << variant << " " << x << "," << y;
  }
  // Bad input: exit 2 (usage) or 3 (input) with the problem named.
  test::CliRun r = stex("cs-rpn -o '" + model + "' --periods 10,0,20,0.1 --spectra '" + spectra + "'");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("parallel"), std::string::npos) << r.err;
  r = stex("cs-rpn -o '" + model + "' --periods 64,0,0,64 --spectra '" + spectra + "' --variant perlin");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("random-phase, gabor, phasor or fourier"), std::string::npos) << r.err;
  r = stex("cs-rpn -o '" + model + "' --periods 64,0,0,64 --spectra '" + (dir / "missing.json").string() + "'");
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("spectra file"), std::string::npos) << r.err;
  {
    std::ofstream f(spectra);
    f << R"({"grid": [2, 2], "spectra": ["ring:0.1,0.01"]})";
  }
  r = stex("cs-rpn -o '" + model + "' --periods 64,0,0,64 --spectra '" + spectra + "'");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("needs 4 spectra"), std::string::npos) << r.err;
  r = stex("cs-rpn -o '" + model + "' --periods 64,0,0,64 --spectra '" + spectra + "' --variant gabor --bandwidth 3");
  EXPECT_EQ(r.code, 2);
}

// ---- Filtered cs-rpn noise (runtime/cs_rpn.cpp set_filter): a minified view fades each random-phase cosine and
// each Fourier frequency by the footprint's transfer and convolves each Gabor kernel with the footprint. The
// device equals the C++ reference bit for bit across tilings and chunkings, the filter changes nothing at
// scale >= 1 nor for phasor noise, and the quality of issue 31 item 4 against a 16 x 16 supersampled box
// reference of the same realisation (docs/filtering.md). The model is rotating() above.

RenderParams filtered(double scale) { return test::minified(scale, 31, true, 16.0); }
RenderParams point_sampled(double scale) { return test::minified(scale, 31, false, 16.0); }

const CsRpnVariant k_filtered[] = {CsRpnVariant::RandomPhase, CsRpnVariant::Gabor, CsRpnVariant::Fourier};

TEST(CsRpnFilter, DeviceEqualsReferenceBitForBitAcrossTilings) {
  for (CsRpnVariant v : k_filtered) {
    const CsRpnModel m = rotating(v);
    CsRpnNoise noise(ctx(), m);
    for (double scale : {0.5, 1.0 / 16.0}) {
      SCOPED_TRACE(cs_rpn_variant_name(v) + " scale " + std::to_string(scale));
      const RenderParams rp = filtered(scale);
      const std::vector<float> r = CsRpnReference(m, rp).render(-13, 7, 24, 20);
      EXPECT_EQ(device_render(noise, rp, -13, 7, 24, 20), r);
      EXPECT_NE(device_render(noise, point_sampled(scale), -13, 7, 24, 20), r);
      const std::vector<float> tile = device_render(noise, rp, -5, 12, 9, 6);
      for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 9; ++i) ASSERT_EQ(tile[j * 9 + i], r[(j + 5) * 24 + (i + 8)]);
      CsRpnNoise chunked(ctx(), m);
      chunked.max_chunk_pixels = 100;
      EXPECT_EQ(device_render(chunked, rp, -13, 7, 24, 20), r);
    }
  }
}

TEST(CsRpnFilter, FilterChangesNothingAtUnitScaleNorForPhasorNoise) {
  for (CsRpnVariant v : k_filtered) {
    const CsRpnModel m = rotating(v);
    CsRpnNoise noise(ctx(), m);
    for (double scale : {1.0, 2.0})
      EXPECT_EQ(device_render(noise, filtered(scale), 3, -4, 16, 16), device_render(noise, point_sampled(scale), 3, -4, 16, 16))
          << cs_rpn_variant_name(v);
  }
  const CsRpnModel phasor = rotating(CsRpnVariant::Phasor);
  EXPECT_FALSE(cs_rpn_filters(phasor));
  CsRpnNoise noise(ctx(), phasor);
  EXPECT_EQ(device_render(noise, filtered(0.25), 3, -4, 16, 16), device_render(noise, point_sampled(0.25), 3, -4, 16, 16));
}

// The 16 x 16 supersampled box reference of the unfiltered noise at the same scale.
std::vector<float> supersampled(const CsRpnModel& m, double scale, std::int64_t x, std::int64_t y, int w, int h) {
  const CsRpnReference ref(m, point_sampled(scale));
  const CsRpnSetup& s = ref.setup();
  return test::box_supersampled(
      [&](std::int64_t fx, std::int64_t fy, float* v) {
        v[0] = stex_csr_eval(s.params, s.fdata.data(), s.udata.data(), s.reduce.data(), s.poisson.data(), fx, fy);
      },
      1, x, y, w, h);
}

using test::rms_diff;
using test::stddev;

// Issue 31 item 4 against the 16 x 16 supersampled box reference of the same realisation, scales 1/2 .. 1/64:
//  - 1/2 and 1/4: within 0.25 of the reference's standard deviation (RMS), and at least 0.9 of it kept;
//  - every scale: the point-sampled render at least twice as far off.
// Measured: 0.010-0.025 sd at 1/2, 0.025-0.088 at 1/4 (docs/filtering.md). Deeper, the Gaussian footprint and the box part ways on these band-pass spectra (as for gabor and lrp: the
// box's side lobes); the figures are printed and recorded in docs/filtering.md.
TEST(CsRpnFilter, QualityAgainstTheSupersampledBoxReference) {
  const int w = 16, h = 16;
  for (CsRpnVariant v : k_filtered) {
    const CsRpnModel m = rotating(v);
    CsRpnNoise noise(ctx(), m);
    const double sd1 = stddev(device_render(noise, point_sampled(1.0), 0, 0, 64, 64));
    for (int k = 1; k <= 5; ++k) {  // 1/64 would make t1 (59 model pixels) shorter than an output pixel
      const double scale = 1.0 / double(1 << k);
      const std::vector<float> s = supersampled(m, scale, 11, -5, w, h);
      const std::vector<float> f = device_render(noise, filtered(scale), 11, -5, w, h);
      const std::vector<float> u = device_render(noise, point_sampled(scale), 11, -5, w, h);
      const double sd = stddev(s), ef = rms_diff(f, s), eu = rms_diff(u, s);
      std::printf("%s, scale 1/%d: box sd %.4g (%.3f of scale 1); filtered rms %.3f sd, keeps %.3f sd; "
                  "point-sampled rms %.3f sd\n",
                  cs_rpn_variant_name(v).c_str(), 1 << k, sd, sd / sd1, ef / sd, stddev(f) / sd, eu / sd);
      if (k <= 2) {
        EXPECT_LE(ef, 0.25 * sd) << "scale 1/" << (1 << k);
        EXPECT_GE(stddev(f), 0.9 * sd) << "scale 1/" << (1 << k);
      }
      EXPECT_GE(eu, 2.0 * ef) << "scale 1/" << (1 << k);
    }
  }
}

}  // namespace
}  // namespace stex
