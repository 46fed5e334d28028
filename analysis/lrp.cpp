// LRP noise and texture by example (S3 §4-5): Welch PSD, strata, erosion, k-means, eq. 3, region R and the
// block subdivision, analytic spectra, and the "lrp" container codec. See lrp.h.
#include "analysis/lrp.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>

#include "analysis/fft.h"
#include "analysis/lrp_psd.h"
#include "core/error.h"
#include "core/math.h"
#include "kernels/shared/rng.h"

namespace stex {

namespace {

constexpr std::uint32_t k_domain_kmeans = 0x4b6d6e73u;  // k-means seeding draws (host only)

[[noreturn]] void usage(const std::string& m) { throw Error(ErrorKind::Usage, m); }

int wrap(int k, int t) { return ((k % t) + t) % t; }
// Centred frequency of FFT index i: [-T/2, T/2).
int centred(int i, int t) { return i >= t / 2 ? i - t : i; }

std::uint64_t draw64(std::uint64_t seed, std::uint32_t stream, std::uint32_t index) {
  stex_uvec4 v = stex_draw(stex_cell_key(std::int64_t(stream), 0), std::uint32_t(seed), std::uint32_t(seed >> 32),
                           index, k_domain_kmeans);
  return (std::uint64_t(v.x) << 32) | v.y;
}

// Squared Euclidean distance (in bins) from each point of `mask` (T x T, FFT order, periodic) to the nearest
// point outside it, capped at (cap + 1)^2: brute force over the offsets of a disc, nearest first.
std::vector<double> distance_to_complement(const std::vector<char>& mask, int t, double cap) {
  const int r = int(std::ceil(cap)) + 1;
  std::vector<std::pair<int, int>> offs;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx)
      if ((dx || dy) && dx * dx + dy * dy <= r * r) offs.push_back({dx, dy});
  std::sort(offs.begin(), offs.end(), [](auto a, auto b) {
    return a.first * a.first + a.second * a.second < b.first * b.first + b.second * b.second;
  });
  std::vector<double> d2(mask.size(), 0.0);
  for (int y = 0; y < t; ++y) {
    for (int x = 0; x < t; ++x) {
      const std::size_t i = std::size_t(y) * t + x;
      if (!mask[i]) continue;
      double best = double(r) * r + 1.0;
      for (auto [dx, dy] : offs) {
        if (!mask[std::size_t(wrap(y + dy, t)) * t + wrap(x + dx, t)]) {
          best = double(dx * dx + dy * dy);
          break;
        }
      }
      d2[i] = best;
    }
  }
  return d2;
}

// Connected components (8-neighbours, periodic) of `mask`; label -1 outside.
std::vector<int> components(const std::vector<char>& mask, int t, int* count) {
  std::vector<int> label(mask.size(), -1);
  int n = 0;
  std::vector<int> stack;
  for (std::size_t s = 0; s < mask.size(); ++s) {
    if (!mask[s] || label[s] >= 0) continue;
    label[s] = n;
    stack.push_back(int(s));
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      const int x = i % t, y = i / t;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const std::size_t j = std::size_t(wrap(y + dy, t)) * t + wrap(x + dx, t);
          if (mask[j] && label[j] < 0) {
            label[j] = n;
            stack.push_back(int(j));
          }
        }
    }
    ++n;
  }
  *count = n;
  return label;
}

// k-means of 2-D integer points into k clusters (k <= points), seeded by k distinct random points.
// Optional weights (one per point, > 0) weight the centroids (Lloyd on the weighted sum of squares).
std::vector<int> kmeans(const std::vector<std::array<int, 2>>& pts, int k, std::uint64_t seed, std::uint32_t stream,
                        const std::vector<double>& weights = {}) {
  const int n = int(pts.size());
  std::vector<int> idx(n);
  std::iota(idx.begin(), idx.end(), 0);
  for (int i = 0; i < k; ++i) {  // partial Fisher-Yates with the counter RNG
    const int j = i + int(draw64(seed, stream, std::uint32_t(i)) % std::uint64_t(n - i));
    std::swap(idx[i], idx[j]);
  }
  std::vector<std::array<double, 2>> c(k);
  for (int i = 0; i < k; ++i) c[i] = {double(pts[idx[i]][0]), double(pts[idx[i]][1])};
  std::vector<int> assign(n, -1);
  for (int it = 0; it < 200; ++it) {
    bool changed = false;
    for (int p = 0; p < n; ++p) {
      int best = 0;
      double bd = 1e300;
      for (int q = 0; q < k; ++q) {
        const double dx = pts[p][0] - c[q][0], dy = pts[p][1] - c[q][1];
        const double d = dx * dx + dy * dy;
        if (d < bd) {
          bd = d;
          best = q;
        }
      }
      if (assign[p] != best) {
        assign[p] = best;
        changed = true;
      }
    }
    std::vector<std::array<double, 3>> sum(k, {0.0, 0.0, 0.0});
    for (int p = 0; p < n; ++p) {
      const double wp = weights.empty() ? 1.0 : weights[p];
      sum[assign[p]][0] += wp * pts[p][0];
      sum[assign[p]][1] += wp * pts[p][1];
      sum[assign[p]][2] += wp;
    }
    for (int q = 0; q < k; ++q) {
      if (sum[q][2] > 0) {
        c[q] = {sum[q][0] / sum[q][2], sum[q][1] / sum[q][2]};
      } else {  // empty cluster: move it to the point farthest from its centre
        int far = 0;
        double fd = -1.0;
        for (int p = 0; p < n; ++p) {
          const double dx = pts[p][0] - c[assign[p]][0], dy = pts[p][1] - c[assign[p]][1];
          if (dx * dx + dy * dy > fd) {
            fd = dx * dx + dy * dy;
            far = p;
          }
        }
        c[q] = {double(pts[far][0]), double(pts[far][1])};
        assign[far] = q;
        changed = true;
      }
    }
    if (!changed) break;
  }
  return assign;
}

// Leading eigenvector of a Hermitian channels x channels matrix as LRP colour weights (p_c, q_c) =
// (Re v_c, -Im v_c), global phase chosen so that the largest component is real and positive.
void colour_weights(const std::vector<std::complex<double>>& m, int ch, float* out) {
  if (ch == 1) {
    out[0] = 1.0f;
    out[1] = 0.0f;
    return;
  }
  Eigen::MatrixXcd a(ch, ch);
  for (int i = 0; i < ch; ++i)
    for (int j = 0; j < ch; ++j) a(i, j) = m[std::size_t(i) * ch + j];
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> es(a);
  Eigen::VectorXcd v = es.eigenvectors().col(ch - 1);
  int big = 0;
  for (int i = 1; i < ch; ++i)
    if (std::abs(v(i)) > std::abs(v(big))) big = i;
  if (std::abs(v(big)) > 0) v *= std::conj(v(big)) / std::abs(v(big));
  const double norm = v.norm();
  for (int i = 0; i < ch; ++i) {
    const std::complex<double> z = norm > 0 ? v(i) / norm : std::complex<double>(i == 0 ? 1.0 : 0.0, 0.0);
    out[2 * i] = float(z.real());
    out[2 * i + 1] = float(-z.imag());
  }
}

std::vector<double> split_numbers(const std::string& s, const std::string& spec) {
  std::vector<double> v;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double d = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(d)) usage("bad number '" + item + "' in PSD spec '" + spec + "'");
    v.push_back(d);
  }
  return v;
}

LrpSpectrum normalised(std::vector<double> p, int t, double variance, const std::string& what) {
  // symmetrise, zero the DC, normalise
  std::vector<double> s(p.size());
  for (int y = 0; y < t; ++y)
    for (int x = 0; x < t; ++x)
      s[std::size_t(y) * t + x] = 0.5 * (p[std::size_t(y) * t + x] + p[std::size_t(wrap(-y, t)) * t + wrap(-x, t)]);
  s[0] = 0.0;
  double sum = 0.0;
  for (double v : s) {
    if (!(v >= 0.0) || !std::isfinite(v)) throw Error(ErrorKind::Input, what + ": PSD values must be finite and >= 0");
    sum += v;
  }
  if (!(sum > 0.0)) throw Error(ErrorKind::Input, what + ": the PSD has no energy outside the zero frequency");
  // Support: drop the weakest frequencies that together hold at most 1e-4 of the energy (a Gaussian's tails
  // are positive in double down to 1e-300 over the whole grid). Otherwise they count in |S|, and
  // Delta_S = T sqrt(J_S) / sqrt(2 |S|) (S3 §4.3) shrinks until the window spreads the energy over the
  // whole band: ring:0.1,0.01 at T = 128, J = 5 counted 12032 frequencies, Delta 1.85 px, and its render
  // kept 7 % of its energy near the ring (LrpSpectrum.RingRenderRadialEnergy).
  {
    std::vector<double> sorted(s);
    std::sort(sorted.begin(), sorted.end());
    double acc = 0.0, cut = 0.0;
    for (double v : sorted) {
      if (acc + v > 1e-4 * sum) {
        cut = v;
        break;
      }
      acc += v;
    }
    sum = 0.0;
    for (double& v : s) {
      if (v < cut) v = 0.0;  // symmetric values: conjugate pairs are dropped together
      sum += v;
    }
  }
  for (double& v : s) v *= variance / sum;
  LrpSpectrum out;
  out.period = t;
  out.channels = 1;
  out.psd = std::move(s);
  out.mean = {0.5};
  return out;
}

}  // namespace

const char* lrp_amplitudes_name(LrpAmplitudes a) {
  switch (a) {
    case LrpAmplitudes::Paper: return "paper";
    case LrpAmplitudes::Psd: return "psd";
    case LrpAmplitudes::PsdEnergy: return "psd-energy";
    case LrpAmplitudes::Fit: return "fit";
  }
  return "paper";
}

LrpAmplitudes parse_lrp_amplitudes(const std::string& name) {
  for (LrpAmplitudes a : {LrpAmplitudes::Paper, LrpAmplitudes::Psd, LrpAmplitudes::PsdEnergy, LrpAmplitudes::Fit})
    if (name == lrp_amplitudes_name(a)) return a;
  usage("--amplitudes '" + name + "': expected fit, paper, psd or psd-energy");
}

double lrp_erosion_delta1(double fraction) {
  // w^(nu) = int_{-1.5}^{1.5} w(y) cos(2 pi nu y) dy (w even); Parseval: int w^2 dy = int |w^|^2 dnu.
  const int ny = 1200;
  const double hy = 3.0 / ny;
  std::vector<double> w(ny);
  double total = 0.0;
  for (int i = 0; i < ny; ++i) {
    w[i] = lrp_window(-1.5 + (i + 0.5) * hy);
    total += w[i] * w[i] * hy;
  }
  const double dnu = 0.0005;
  double acc = 0.0;
  for (int k = 0; k < 40000; ++k) {
    const double nu = (k + 0.5) * dnu;
    double f = 0.0;
    for (int i = 0; i < ny; ++i) f += w[i] * std::cos(2.0 * k_pi * nu * (-1.5 + (i + 0.5) * hy));
    f *= hy;
    const double add = 2.0 * f * f * dnu;  // both signs of nu
    if (acc + add >= fraction * total) return k * dnu + dnu * (fraction * total - acc) / add;
    acc += add;
  }
  throw Error(ErrorKind::Internal, "LRP erosion constant did not converge");
}

LrpSpectrum lrp_welch(const Image& ex, int max_period) {
  const int side = std::min(ex.width, ex.height);
  if (side < 4 || ex.channels < 1 || ex.channels > 4)
    throw Error(ErrorKind::Input, "LRP analysis needs an exemplar of at least 4x4 pixels with 1..4 channels");
  int t = 1;
  while (t * 2 < side && t * 2 <= max_period) t *= 2;  // largest power of two strictly below the size
  const int ch = ex.channels;
  LrpSpectrum sp;
  sp.period = t;
  sp.channels = ch;
  sp.mean.assign(ch, 0.0);
  for (int y = 0; y < ex.height; ++y)
    for (int x = 0; x < ex.width; ++x)
      for (int c = 0; c < ch; ++c) sp.mean[c] += ex.at(x, y, c);
  for (double& m : sp.mean) m /= double(ex.width) * ex.height;
  const std::size_t n = std::size_t(t) * t;
  std::vector<double> hann(t);
  double h2 = 0.0;
  for (int i = 0; i < t; ++i) hann[i] = std::pow(std::sin(k_pi * (i + 0.5) / t), 2.0);
  for (int y = 0; y < t; ++y)
    for (int x = 0; x < t; ++x) h2 += hann[x] * hann[x] * hann[y] * hann[y];
  sp.psd.assign(n, 0.0);
  sp.cross.assign(n * ch * ch, 0.0);
  sp.phases.assign(n * ch, 0.0);
  std::vector<std::vector<Complex>> buf(ch, std::vector<Complex>(n));
  const int step = std::max(1, t / 2);
  int crops = 0;
  for (int oy = 0; oy + t <= ex.height; oy += step) {
    for (int ox = 0; ox + t <= ex.width; ox += step) {
      for (int c = 0; c < ch; ++c) {
        for (int y = 0; y < t; ++y)
          for (int x = 0; x < t; ++x)
            buf[c][std::size_t(y) * t + x] = (ex.at(ox + x, oy + y, c) - sp.mean[c]) * hann[x] * hann[y];
        fft2d_forward(t, t, buf[c]);
      }
      for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < ch; ++a)
          for (int b = 0; b < ch; ++b) sp.cross[(i * ch + a) * ch + b] += buf[a][i] * std::conj(buf[b][i]);
      if (crops == 0) {  // the first crop, unwindowed: amplitudes and phases of the structure (S3 §5.1)
        for (int c = 0; c < ch; ++c) {
          std::vector<Complex> raw(n);
          for (int y = 0; y < t; ++y)
            for (int x = 0; x < t; ++x) raw[std::size_t(y) * t + x] = ex.at(x, y, c) - sp.mean[c];
          fft2d_forward(t, t, raw);
          std::copy(raw.begin(), raw.end(), sp.phases.begin() + std::ptrdiff_t(c * n));
        }
      }
      ++crops;
    }
  }
  sp.crops = crops;
  const double norm = 1.0 / (double(crops) * double(n) * h2);
  for (auto& v : sp.cross) v *= norm;
  for (std::size_t i = 0; i < n; ++i) {
    double tr = 0.0;
    for (int c = 0; c < ch; ++c) tr += sp.cross[(i * ch + c) * ch + c].real();
    sp.psd[i] = tr;
  }
  sp.psd[0] = 0.0;  // the mean is modelled separately
  return sp;
}

LrpSpectrum lrp_analytic_psd(const std::string& spec, int t, double variance) {
  if (t < 8 || t > 4096 || (t & (t - 1))) usage("PSD grid size must be a power of two in [8, 4096]");
  const auto colon = spec.find(':');
  if (colon == std::string::npos) usage("PSD spec '" + spec + "' must be ring:F,W, bilobe:F,A,W or gauss:FX,FY,W[;...]");
  const std::string kind = spec.substr(0, colon), args = spec.substr(colon + 1);
  std::vector<double> p(std::size_t(t) * t, 0.0);
  auto each = [&](auto&& f) {
    for (int y = 0; y < t; ++y)
      for (int x = 0; x < t; ++x) p[std::size_t(y) * t + x] += f(double(centred(x, t)) / t, double(centred(y, t)) / t);
  };
  auto lobe = [&](double fx, double fy, double w) {
    each([=](double u, double v) {
      const double a = ((u - fx) * (u - fx) + (v - fy) * (v - fy)) / (2 * w * w);
      const double b = ((u + fx) * (u + fx) + (v + fy) * (v + fy)) / (2 * w * w);
      return std::exp(-a) + std::exp(-b);
    });
  };
  if (kind == "ring") {
    const auto a = split_numbers(args, spec);
    if (a.size() != 2 || a[0] < 0 || a[0] > 0.5 || a[1] <= 0) usage("ring:F,W needs 0 <= F <= 0.5 and W > 0");
    each([&](double u, double v) {
      const double r = std::sqrt(u * u + v * v) - a[0];
      return std::exp(-r * r / (2 * a[1] * a[1]));
    });
  } else if (kind == "bilobe") {
    const auto a = split_numbers(args, spec);
    if (a.size() != 3 || a[0] < 0 || a[0] > 0.5 || a[2] <= 0) usage("bilobe:F,A,W needs 0 <= F <= 0.5 and W > 0");
    lobe(a[0] * std::cos(a[1] * k_pi / 180), a[0] * std::sin(a[1] * k_pi / 180), a[2]);
  } else if (kind == "gauss") {
    std::stringstream ss(args);
    std::string item;
    int lobes = 0;
    while (std::getline(ss, item, ';')) {
      const auto a = split_numbers(item, spec);
      if (a.size() != 3 || std::fabs(a[0]) > 0.5 || std::fabs(a[1]) > 0.5 || a[2] <= 0)
        usage("gauss:FX,FY,W needs |FX|, |FY| <= 0.5 and W > 0");
      lobe(a[0], a[1], a[2]);
      ++lobes;
    }
    if (!lobes) usage("gauss: needs at least one lobe");
  } else {
    usage("unknown PSD kind '" + kind + "' (expected ring, bilobe or gauss)");
  }
  return normalised(std::move(p), t, variance, "PSD '" + spec + "'");
}

LrpSpectrum lrp_psd_from_image(const Image& img, double variance) {
  const int t = img.width;
  if (img.width != img.height || t < 8 || t > 4096 || (t & (t - 1)))
    throw Error(ErrorKind::Input, "a PSD image must be square with a power-of-two side in [8, 4096], got " +
                                      std::to_string(img.width) + "x" + std::to_string(img.height));
  std::vector<double> p(std::size_t(t) * t);
  for (int y = 0; y < t; ++y)
    for (int x = 0; x < t; ++x) {
      double v = 0.0;
      for (int c = 0; c < img.channels; ++c) v += img.at(wrap(x + t / 2, t), wrap(y + t / 2, t), c);
      p[std::size_t(y) * t + x] = v / img.channels;
    }
  return normalised(std::move(p), t, variance, "PSD image");
}

std::vector<float> lrp_structure_image(const LrpSpectrum& sp, double ratio) {
  const int t = sp.period, ch = sp.channels;
  const std::size_t n = std::size_t(t) * t;
  if (sp.phases.size() != n * ch) usage("this spectrum has no phases (an analytic PSD): no structure (r must be 0)");
  // R: highest-P frequencies until their energy reaches r E (conjugate pairs together).
  std::vector<std::size_t> order(n - 1);
  std::iota(order.begin(), order.end(), std::size_t(1));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return sp.psd[a] > sp.psd[b]; });
  double total = 0.0;
  for (std::size_t i = 1; i < n; ++i) total += sp.psd[i];
  std::vector<char> in(n, 0);
  double acc = 0.0;
  for (std::size_t i : order) {
    if (acc >= ratio * total && ratio < 1.0) break;
    if (in[i]) continue;
    const std::size_t j = std::size_t(wrap(-int(i / t), t)) * t + wrap(-int(i % t), t);
    in[i] = in[j] = 1;
    acc += sp.psd[i] + (j != i ? sp.psd[j] : 0.0);
  }
  if (ratio > 0.0) in[0] = 1;  // the crop's own mean offset belongs to its structure
  std::vector<float> img(n * ch);
  for (int c = 0; c < ch; ++c) {
    std::vector<Complex> x(n);
    for (std::size_t i = 0; i < n; ++i) x[i] = in[i] ? sp.phases[c * n + i] : Complex(0.0, 0.0);
    fft2d_inverse(t, t, x);
    for (std::size_t i = 0; i < n; ++i) img[i * ch + c] = float(x[i].real() + sp.mean[c]);
  }
  return img;
}

namespace {

// The region R as a mask (same rule as lrp_structure_image).
std::vector<char> region_mask(const LrpSpectrum& sp, double ratio, double* share) {
  const int t = sp.period;
  const std::size_t n = std::size_t(t) * t;
  std::vector<char> in(n, 0);
  *share = 0.0;
  if (ratio <= 0.0) return in;
  std::vector<std::size_t> order(n - 1);
  std::iota(order.begin(), order.end(), std::size_t(1));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return sp.psd[a] > sp.psd[b]; });
  double total = 0.0;
  for (std::size_t i = 1; i < n; ++i) total += sp.psd[i];
  double acc = 0.0;
  for (std::size_t i : order) {
    if (acc >= ratio * total && ratio < 1.0) break;
    if (in[i]) continue;
    const std::size_t j = std::size_t(wrap(-int(i / t), t)) * t + wrap(-int(i % t), t);
    in[i] = in[j] = 1;
    acc += sp.psd[i] + (j != i ? sp.psd[j] : 0.0);
  }
  *share = total > 0 ? acc / total : 0.0;
  return in;
}

// S3 §5.3 / Fig. 9: block subdivision of the structure image until the J_R highest-amplitude terms per block
// reproduce it within `stop` (mean |error| over pixels and channels).
void subdivide(const std::vector<float>& img, const std::vector<double>& mean, int t, int ch, int jr, double stop,
               LrpModel* m, LrpReport* rep) {
  int levels = 0;
  for (int b = t; b >= 1; b /= 2) {
    ++levels;
    const int nb = t / b;
    const std::size_t bn = std::size_t(b) * b;
    // representatives of conjugate classes on the B x B grid
    std::vector<int> reps;
    for (int i = 0; i < int(bn); ++i) {
      const int kx = i % b, ky = i / b;
      const int j = wrap(-ky, b) * b + wrap(-kx, b);
      if (i <= j) reps.push_back(i);
    }
    const int keep = std::min<int>(jr, int(reps.size()));
    std::vector<float> terms(std::size_t(nb) * nb * keep * (2 + 2 * ch), 0.0f);
    double err = 0.0;
    std::vector<std::vector<Complex>> blk(ch, std::vector<Complex>(bn));
    for (int by = 0; by < nb; ++by) {
      for (int bx = 0; bx < nb; ++bx) {
        for (int c = 0; c < ch; ++c) {
          for (int y = 0; y < b; ++y)
            for (int x = 0; x < b; ++x)
              blk[c][std::size_t(y) * b + x] =
                  double(img[((std::size_t(by) * b + y) * t + std::size_t(bx) * b + x) * ch + c]) - mean[c];
          fft2d_forward(b, b, blk[c]);
        }
        std::vector<int> sel = reps;
        auto power = [&](int i) {
          double s = 0.0;
          for (int c = 0; c < ch; ++c) s += std::norm(blk[c][i]);
          return s;
        };
        std::stable_sort(sel.begin(), sel.end(), [&](int a, int c2) { return power(a) > power(c2); });
        sel.resize(keep);
        // reconstruction with the kept terms, for the error
        std::vector<std::vector<Complex>> rec(ch, std::vector<Complex>(bn, Complex(0.0, 0.0)));
        float* out = &terms[(std::size_t(by) * nb + bx) * keep * (2 + 2 * ch)];
        for (int k = 0; k < keep; ++k) {
          const int i = sel[k];
          const int kx = i % b, ky = i / b;
          const int j = wrap(-ky, b) * b + wrap(-kx, b);
          const double factor = (i == j ? 1.0 : 2.0) / double(bn);
          // samples sit at pixel centres (d = x + 1/2): fold the half-pixel shift into the phase
          const int ckx = centred(kx, b), cky = centred(ky, b);
          const Complex shift = std::polar(1.0, -k_pi * double(ckx + cky) / b);
          out[0] = float(ckx);
          out[1] = float(cky);
          for (int c = 0; c < ch; ++c) {
            rec[c][i] = blk[c][i];
            rec[c][j] = blk[c][j];
            const Complex z = blk[c][i] * shift * factor;
            out[2 + 2 * c] = float(z.real());
            out[3 + 2 * c] = float(-z.imag());
          }
          out += 2 + 2 * ch;
        }
        for (int c = 0; c < ch; ++c) {
          fft2d_inverse(b, b, rec[c]);
          for (int y = 0; y < b; ++y)
            for (int x = 0; x < b; ++x)
              err += std::fabs(rec[c][std::size_t(y) * b + x].real() + mean[c] -
                               double(img[((std::size_t(by) * b + y) * t + std::size_t(bx) * b + x) * ch + c]));
        }
      }
    }
    err /= double(t) * t * ch;
    if (err < stop || b == 1) {
      m->block = b;
      m->jr = keep;
      m->terms = std::move(terms);
      m->structure_error = err;
      if (rep) {
        rep->block = b;
        rep->jr = keep;
        rep->levels = levels;
        rep->structure_error = err;
      }
      return;
    }
  }
}

// The strata of build_strata: the model's strata, tables and colours, and the report's rows.
struct StrataBuild {
  std::vector<LrpStratum> strata;
  std::vector<std::int32_t> freqs;
  std::vector<float> colours;
  std::vector<LrpStratumReport> reports;
};

// The cosine budget J_S of each stratum: S3's equal shares (power 0: J / L, the remainder to the strongest
// strata) or shares proportional to |S|^power, at least one each (largest remainders, ties to the earlier).
std::vector<int> allocate_cosines(const std::vector<double>& sizes, int j, double power) {
  const int ls = int(sizes.size());
  std::vector<int> out(ls, 0);
  if (ls == 0) return out;
  if (power == 0.0) {
    for (int s = 0; s < ls; ++s) out[s] = j / ls + (s < j % ls ? 1 : 0);
    return out;
  }
  double sum = 0.0;
  for (double v : sizes) sum += std::pow(v, power);
  std::vector<double> ideal(ls);
  int used = 0;
  for (int s = 0; s < ls; ++s) {
    ideal[s] = double(j - ls) * std::pow(sizes[s], power) / sum;
    out[s] = 1 + int(std::floor(ideal[s]));
    used += out[s];
  }
  std::vector<int> order(ls);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return ideal[a] - std::floor(ideal[a]) > ideal[b] - std::floor(ideal[b]); });
  for (int k = 0; used < j; k = (k + 1) % ls, ++used) ++out[order[k]];
  return out;
}

// Per-cosine gains of a stratum from the PSD over each sub-stratum: every frequency of the (uneroded) stratum
// goes to the sub-stratum of the nearest k-means centroid (conjugates to the half plane), E_r is the PSD summed
// over sub-stratum r's frequencies, and the m_r cosines drawing from table r share it: gain_q^2 =
// J_S (E_r / m_r) / sum_r E_r, r = q mod k. So sum_q gain_q^2 = J_S: the cosines' energy sum_q A_S^2 gain_q^2
// is eq. 3's J_S A_S^2 (the stratum's energy and variance kept), and the windows, Delta_S and the erosion,
// which eq. 3's leakage bound depends on, are unchanged.
std::vector<double> psd_gains(const LrpSpectrum& sp, const std::vector<std::size_t>& stratum,
                              const std::vector<std::array<int, 2>>& pts, const std::vector<int>& assign, int k, int js) {
  const int t = sp.period;
  std::vector<std::array<double, 3>> c(k, {0.0, 0.0, 0.0});
  for (std::size_t p = 0; p < pts.size(); ++p) {
    c[assign[p]][0] += pts[p][0];
    c[assign[p]][1] += pts[p][1];
    c[assign[p]][2] += 1.0;
  }
  for (auto& v : c) v = {v[0] / std::max(v[2], 1.0), v[1] / std::max(v[2], 1.0), v[2]};
  std::vector<double> e(k, 0.0);
  double total = 0.0;
  for (std::size_t i : stratum) {
    const int kx = centred(int(i % t), t), ky = centred(int(i / t), t);
    int best = 0;
    double bd = 1e300;
    for (int q = 0; q < k; ++q) {
      if (c[q][2] <= 0) continue;
      for (int sign : {1, -1}) {
        const double dx = sign * kx - c[q][0], dy = sign * ky - c[q][1];
        if (dx * dx + dy * dy < bd) {
          bd = dx * dx + dy * dy;
          best = q;
        }
      }
    }
    e[best] += sp.psd[i];
    total += sp.psd[i];
  }
  std::vector<double> gains(js, 1.0);
  if (!(total > 0.0)) return gains;
  std::vector<int> users(k, 0);
  for (int q = 0; q < js; ++q) ++users[q % k];
  for (int q = 0; q < js; ++q) gains[q] = std::sqrt(double(js) * e[q % k] / users[q % k] / total);
  return gains;
}

// k-means of a stratum's eroded points into J_S sub-strata (random seeding, S3 §4.3; LrpAmplitudes::PsdEnergy
// weights the points by P^2, which makes the sub-strata hold about equal energy), their tables, colours and
// (LrpAmplitudes::Psd*) per-cosine gains: the stratum's amplitude becomes A_S max_q gain_q and sub-stratum q's
// colour weights are scaled by gain_q / max gain (kernels/shared/lrp.h multiplies them; norms stay <= 1).
void emit_sub_strata(const LrpSpectrum& sp, const std::vector<std::size_t>& stratum,
                     const std::vector<std::array<int, 2>>& pts, int js, LrpAmplitudes amplitudes, std::uint64_t seed,
                     std::uint32_t stream, LrpStratum* st, StrataBuild* out) {
  const int t = sp.period, ch = sp.channels;
  const int k = std::min<int>(js, int(pts.size()));
  std::vector<double> weights;
  if (amplitudes == LrpAmplitudes::PsdEnergy || amplitudes == LrpAmplitudes::Fit)
    for (const auto& f : pts) weights.push_back(std::pow(sp.psd[std::size_t(wrap(f[1], t)) * t + wrap(f[0], t)], 2.0));
  const std::vector<int> assign = kmeans(pts, k, seed, stream, weights);
  std::vector<std::vector<std::array<int, 2>>> subs(k);
  for (std::size_t p = 0; p < pts.size(); ++p) subs[assign[p]].push_back(pts[p]);
  std::vector<double> gains(js, 1.0);
  if (amplitudes != LrpAmplitudes::Paper) gains = psd_gains(sp, stratum, pts, assign, k, js);
  const double gmax = *std::max_element(gains.begin(), gains.end());
  if (amplitudes != LrpAmplitudes::Paper && gmax > 0.0) st->amplitude *= gmax;
  for (int q = 0; q < js; ++q) {
    const auto& sub = subs[q % k];  // fewer points than J_S: sub-strata share tables
    st->sub_counts.push_back(int(sub.size()));
    std::vector<std::complex<double>> cross(std::size_t(ch) * ch, 0.0);
    for (const auto& f : sub) {
      out->freqs.push_back(f[0]);
      out->freqs.push_back(f[1]);
      if (!sp.cross.empty()) {
        const std::size_t i = std::size_t(wrap(f[1], t)) * t + wrap(f[0], t);
        for (std::size_t e = 0; e < cross.size(); ++e) cross[e] += sp.cross[i * ch * ch + e];
      }
    }
    float w[2 * STEX_LRP_MAX_CHANNELS];
    if (sp.cross.empty()) {
      for (int c = 0; c < ch; ++c) {
        w[2 * c] = c == 0 ? 1.0f : 0.0f;
        w[2 * c + 1] = 0.0f;
      }
    } else {
      colour_weights(cross, ch, w);
    }
    if (amplitudes != LrpAmplitudes::Paper && gmax > 0.0)
      for (int c = 0; c < 2 * ch; ++c) w[c] = float(double(w[c]) * (gains[q] / gmax));
    out->colours.insert(out->colours.end(), w, w + 2 * ch);
  }
}

// S3 §4.2-4.3: `levels` strata of equal energy over the frequencies not in `exclude` (and not the DC), sharing
// `j_rest` cosines: Delta_S, eq. 3, erosion, k-means sub-strata (streams stream_base + s), colours and gains.
StrataBuild build_strata(const LrpSpectrum& sp, const std::vector<char>& exclude, int levels, int j_rest,
                         LrpAmplitudes amplitudes, double alloc_power, std::uint64_t seed, std::uint32_t stream_base,
                         double delta1, double wint, double total) {
  const int t = sp.period;
  const std::size_t n = std::size_t(t) * t;
  StrataBuild out;
  std::vector<std::size_t> order;
  double e_rest = 0.0;
  for (std::size_t i = 1; i < n; ++i)
    if (!exclude[i] && sp.psd[i] > 0.0) {
      order.push_back(i);
      e_rest += sp.psd[i];
    }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return sp.psd[a] > sp.psd[b]; });
  const int l_max = std::min(levels, j_rest);
  std::vector<std::vector<std::size_t>> strata;
  if (l_max > 0 && !order.empty() && e_rest > 0.0) {
    // Cut the decreasing order where the cumulative energy crosses k E / L; equal values stay together.
    std::vector<std::size_t> cur;
    double acc = 0.0;
    int k = 1;
    for (std::size_t q = 0; q < order.size(); ++q) {
      const std::size_t i = order[q];
      cur.push_back(i);
      acc += sp.psd[i];
      const bool tie_next = q + 1 < order.size() && sp.psd[order[q + 1]] == sp.psd[i];
      if (k < l_max && acc >= e_rest * k / l_max && !tie_next) {
        strata.push_back(std::move(cur));
        cur.clear();
        while (k < l_max && acc >= e_rest * k / l_max) ++k;  // a peak holding several shares closes them all
      }
    }
    if (!cur.empty()) strata.push_back(std::move(cur));
  }
  const int ls = int(strata.size());
  std::vector<double> sizes;
  for (const auto& st : strata) sizes.push_back(double(st.size()));
  const std::vector<int> budget = allocate_cosines(sizes, j_rest, amplitudes == LrpAmplitudes::Paper ? 0.0 : alloc_power);
  for (int s = 0; s < ls; ++s) {
    const int js = budget[s];
    std::vector<char> mask(n, 0);
    double es = 0.0;
    for (std::size_t i : strata[s]) {
      mask[i] = 1;
      es += sp.psd[i];
    }
    LrpStratum st;
    st.size = int(strata[s].size());
    st.energy = es;
    st.psd_hi = sp.psd[strata[s].front()];
    st.psd_lo = sp.psd[strata[s].back()];
    st.delta = double(t) * std::sqrt(double(js)) / std::sqrt(2.0 * st.size);  // S3 §4.3
    st.erosion = delta1 / st.delta * t;                                      // bins
    // S3 eq. 3 with E_S taken over the area Delta_S^2 one lattice point serves (see lrp.h).
    const double e_local = st.delta * st.delta * es;
    st.amplitude = std::sqrt(e_local / (st.delta * st.delta * js * k_pi * wint));
    // Erosion (75 % rule), keeping the deepest points of parts the erosion would sweep out.
    const std::vector<double> d2 = distance_to_complement(mask, t, st.erosion);
    int ncomp = 0;
    const std::vector<int> comp = components(mask, t, &ncomp);
    std::vector<double> deepest(ncomp, 0.0);
    for (std::size_t i = 0; i < n; ++i)
      if (mask[i]) deepest[comp[i]] = std::max(deepest[comp[i]], d2[i]);
    const double e2 = st.erosion * st.erosion;
    std::vector<std::array<int, 2>> pts;  // eroded stratum on the half plane
    int eroded = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!mask[i]) continue;
      const bool keep = d2[i] > e2 || (deepest[comp[i]] <= e2 && d2[i] == deepest[comp[i]]);
      if (!keep) continue;
      ++eroded;
      const int kx = centred(int(i % t), t), ky = centred(int(i / t), t);
      if (ky == -t / 2 || kx == -t / 2) continue;  // Nyquist: its own conjugate's alias, left out
      if (ky > 0 || (ky == 0 && kx > 0)) pts.push_back({kx, ky});
    }
    if (pts.empty()) continue;  // a stratum of Nyquist frequencies only: nothing to draw
    const double eq3_amplitude = st.amplitude;
    emit_sub_strata(sp, strata[s], pts, js, amplitudes, seed, stream_base + std::uint32_t(s), &st, &out);
    LrpStratumReport sr;
    sr.energy_share = total > 0 ? es / total : 0.0;
    sr.size = st.size;
    sr.eroded_size = eroded;
    sr.js = js;
    sr.delta = st.delta;
    sr.erosion = st.erosion;
    sr.amplitude = eq3_amplitude;
    sr.max_amplitude = st.amplitude;
    out.reports.push_back(sr);
    out.strata.push_back(std::move(st));
  }
  return out;
}

}  // namespace

std::vector<char> lrp_region_mask(const LrpSpectrum& sp, double ratio) {
  double share = 0.0;
  return region_mask(sp, ratio, &share);
}

LrpModel lrp_from_spectrum(const LrpSpectrum& sp, const LrpParams& prm, LrpReport* rep) {
  const auto t0 = std::chrono::steady_clock::now();
  if (prm.cosines < 1 || prm.cosines > 4096) usage("--cosines J must be in [1, 4096]");
  if (prm.strata < 1 || prm.strata > STEX_LRP_MAX_STRATA) usage("--strata L must be in [1, " + std::to_string(STEX_LRP_MAX_STRATA) + "]");
  if (!(prm.ratio >= 0.0 && prm.ratio <= 1.0)) usage("--structure r must be in [0, 1]");
  if (!(prm.sigma >= 0.0 && prm.sigma <= 1e6)) usage("--turbulence sigma must be in [0, 1e6]");
  if ((prm.sigma > 0.0 || prm.placement) && prm.ratio <= 0.0)
    usage("--turbulence and --placement act on the fixed-phase structure: they need --structure r > 0");
  if (!(prm.erosion_energy > 0.0 && prm.erosion_energy < 1.0)) usage("erosion energy fraction must be in (0, 1)");
  const int t = sp.period, ch = sp.channels;
  const std::size_t n = std::size_t(t) * t;
  LrpModel m;
  m.channels = ch;
  m.period = t;
  for (int c = 0; c < ch; ++c) m.mean[c] = float(sp.mean[c]);
  m.cosines = prm.cosines;
  m.analysis_seed = prm.seed;
  m.amplitudes = lrp_amplitudes_name(prm.amplitudes);
  m.ratio = prm.ratio;
  m.sigma = prm.sigma;
  m.placement = prm.placement;
  LrpReport local;
  LrpReport& r = rep ? *rep : local;
  r = LrpReport{};
  r.period = t;
  r.crops = sp.crops;
  r.window_integral = lrp_window_integral();
  r.delta1 = lrp_erosion_delta1(prm.erosion_energy);
  double total = 0.0;
  for (std::size_t i = 1; i < n; ++i) total += sp.psd[i];
  r.variance = total;

  // S3 §5: region R and its budget J_R = r J.
  double share = 0.0;
  const std::vector<char> in_r = region_mask(sp, prm.ratio, &share);
  int jr = 0;
  if (prm.ratio > 0.0) {
    jr = std::max(1, int(std::lround(prm.ratio * prm.cosines)));
    const std::vector<float> img = lrp_structure_image(sp, prm.ratio);
    subdivide(img, sp.mean, t, ch, jr, prm.stop_error, &m, &r);
    r.region_size = int(std::count(in_r.begin() + 1, in_r.end(), char(1)));
    r.region_share = share;
  }
  const int j_rest = prm.cosines - jr;

  // S3 §4.2: strata of equal energy over the frequencies outside R (and outside the DC).
  {
    StrataBuild b = build_strata(sp, in_r, prm.strata, j_rest, prm.amplitudes, prm.allocation_power, prm.seed, 0u,
                                 r.delta1, r.window_integral, total);
    m.strata = std::move(b.strata);
    m.freqs = std::move(b.freqs);
    m.colours = std::move(b.colours);
    r.strata = std::move(b.reports);
  }
  if (prm.amplitudes == LrpAmplitudes::Fit && !m.strata.empty()) {
    // the strata's share of the target: every frequency outside R
    std::vector<double> target = sp.psd;
    for (std::size_t i = 0; i < n; ++i)
      if (in_r[i]) target[i] = 0.0;
    lrp_fit_gains(m, target, prm.fit_iterations);
    for (std::size_t s = 0; s < m.strata.size(); ++s) r.strata[s].max_amplitude = m.strata[s].amplitude;
  }
  // S3 §5.2: the turbulence n_T = sum_S |n_S| "computed from the (whole) spectrum itself" with "a rough
  // stratification and a low cosine budget": its own strata over every frequency but the DC (R included),
  // so it exists at any r, r = 1 too (S3 §6.3: then the model "reduces to applying turbulence and random
  // placement"). Carriers only (no colour); k-means streams 64 + s.
  if (prm.sigma > 0.0) {
    if (prm.turbulence_strata < 1 || prm.turbulence_cosines < prm.turbulence_strata)
      usage("turbulence needs at least one stratum and one cosine per stratum");
    // the turbulence's carriers keep S3's uniform A_S (no colour weights to carry gains)
    StrataBuild b = build_strata(sp, std::vector<char>(n, 0), prm.turbulence_strata, prm.turbulence_cosines,
                                 LrpAmplitudes::Paper, 0.0, prm.seed, 64u, r.delta1, r.window_integral, total);
    if (b.strata.empty()) usage("--turbulence: the spectrum has no energy to build the turbulence from");
    if (m.strata.size() + b.strata.size() > STEX_LRP_MAX_STRATA)
      usage("--turbulence: " + std::to_string(m.strata.size()) + " strata plus " + std::to_string(b.strata.size()) +
            " turbulence strata exceed the limit of " + std::to_string(STEX_LRP_MAX_STRATA) +
            " (lower --strata)");
    m.turbulence = std::move(b.strata);
    m.turb_freqs = std::move(b.freqs);
    r.turbulence = std::move(b.reports);
  }
  r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  validate_lrp_model(m);
  return m;
}

LrpModel analyse_lrp(const Image& ex, const LrpParams& prm, LrpReport* rep, LrpSpectrum* spectrum) {
  LrpSpectrum sp = lrp_welch(ex, prm.max_period);
  LrpModel m = lrp_from_spectrum(sp, prm, rep);
  if (spectrum) *spectrum = std::move(sp);
  m.source = "exemplar";
  m.stex_version = STEX_VERSION_STRING;
  m.exemplar_width = ex.width;
  m.exemplar_height = ex.height;
  return m;
}

LrpModel analyse_lrp_file(const std::string& path, const LoadOptions& opts, const LrpParams& prm, LrpReport* rep,
                          std::vector<std::string>* warnings, LrpSpectrum* spectrum) {
  const Image ex = load_exemplar(path, opts, warnings);
  LrpModel m = analyse_lrp(ex, prm, rep, spectrum);
  m.linear = opts.linear;
  const auto slash = path.find_last_of('/');
  m.exemplar_name = slash == std::string::npos ? path : path.substr(slash + 1);
  m.exemplar_hash = sha256_file_hex(path);
  return m;
}

}  // namespace stex
