// Histogram transfer by example and its codec. See cs_hist.h.
#include "analysis/cs_hist.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

#include "core/error.h"

namespace stex {

namespace {

using json = nlohmann::json;

double phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }
double phi_inv(double p) {
  double lo = -40.0, hi = 40.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (phi(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

std::uint64_t mix64(std::uint64_t h) {
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebull;
  h ^= h >> 31;
  return h;
}

}  // namespace

ColourPca colour_pca(const Image& e) {
  const int ch = e.channels;
  const std::size_t n = std::size_t(e.width) * e.height;
  Eigen::VectorXd mu = Eigen::VectorXd::Zero(ch);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < ch; ++c) mu[c] += e.pixels[i * ch + c];
  mu /= double(n);
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(ch, ch);
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < ch; ++a)
      for (int b = 0; b < ch; ++b) cov(a, b) += (e.pixels[i * ch + a] - mu[a]) * (e.pixels[i * ch + b] - mu[b]);
  cov /= double(n);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(cov);
  const Eigen::MatrixXd B = es.eigenvectors().transpose();
  ColourPca p;
  p.ch = ch;
  p.mean.assign(mu.data(), mu.data() + ch);
  p.rows.resize(std::size_t(ch) * ch);
  for (int d = 0; d < ch; ++d)
    for (int c = 0; c < ch; ++c) p.rows[std::size_t(d) * ch + c] = B(d, c);
  return p;
}

std::vector<float> ColourPca::device_basis() const {
  std::vector<float> b(std::size_t(ch) * (ch + 1));
  for (int c = 0; c < ch; ++c) b[std::size_t(c)] = float(mean[c]);
  for (std::size_t k = 0; k < rows.size(); ++k) b[std::size_t(ch) + k] = float(rows[k]);
  return b;
}

void pca_coordinates(const Image& e, std::vector<float>* basis, Image* coords) {
  const ColourPca p = colour_pca(e);
  const int ch = e.channels;
  const std::size_t n = std::size_t(e.width) * e.height;
  *basis = p.device_basis();
  coords->width = e.width;
  coords->height = e.height;
  coords->channels = ch;
  coords->pixels.resize(n * ch);
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < ch; ++d) coords->pixels[i * ch + d] = float(p.project(&e.pixels[i * ch], d));
}

void cs_hist_bins(const Lattice& t, int* m0, int* m1) {
  const double l0 = std::hypot(t.t0x, t.t0y), l1 = std::hypot(t.t1x, t.t1y);
  const double s = std::sqrt(lattice_area(t) / (l0 * l1));  // sqrt(sin θ)
  *m0 = std::max(1, int(std::floor(l0 * s + 1e-9)));
  *m1 = std::max(1, int(std::floor(l1 * s + 1e-9)));
}

int parse_cs_hist_mode(const std::string& name) {
  if (name == "none") return 0;
  if (name == "stationary") return 1;
  if (name == "cs") return 2;
  throw Error(ErrorKind::Usage, "--histogram must be none, stationary or cs, got '" + name + "'");
}

CsHistTable build_cs_hist(const Image& img, const Lattice* periods, int mode, int delta, Image* gauss) {
  if (mode != 1 && mode != 2) throw Error(ErrorKind::Usage, "histogram transfer mode must be stationary or cs");
  if (delta < 0 || delta > k_cs_hist_max_delta)
    throw Error(ErrorKind::Usage, "--delta must be 0.." + std::to_string(k_cs_hist_max_delta) + ", got " + std::to_string(delta));
  if (mode == 2 && !periods) throw Error(ErrorKind::Usage, "a cyclostationary histogram transfer needs periods");
  const int w = img.width, h = img.height, ch = img.channels;
  const std::size_t n = std::size_t(w) * h;
  CsHistTable t;
  t.mode = mode;
  t.delta = mode == 2 ? delta : 0;
  t.channels = ch;
  t.m0 = t.m1 = 1;
  if (mode == 2) {
    validate_lattice(*periods, w, h);
    cs_hist_bins(*periods, &t.m0, &t.m1);
  }
  const int nb = t.m0 * t.m1;
  t.q = int(std::min<std::size_t>(k_cs_hist_max_q, n / std::size_t(nb)));
  if (t.q < 2) throw Error(ErrorKind::Input, "the exemplar is too small for a histogram table of these periods");
  // Texel -> bin, and each bin's texels.
  std::vector<int> bin_of(n, 0);
  std::vector<std::vector<std::uint32_t>> members(static_cast<std::size_t>(nb));
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      int b = 0;
      if (mode == 2) {
        double u, v;
        lattice_phase(*periods, i + 0.5, j + 0.5, &u, &v);
        const int a = int(std::floor(u * t.m0)) % t.m0, c = int(std::floor(v * t.m1)) % t.m1;
        b = ((c + t.m1) % t.m1) * t.m0 + (a + t.m0) % t.m0;
      }
      const std::size_t idx = std::size_t(j) * w + i;
      bin_of[idx] = b;
      members[std::size_t(b)].push_back(std::uint32_t(idx));
    }
  // Ties (flat regions, 8-bit exemplars) are broken by a fixed hash of the texel's lattice cell (k, l) for
  // the cs transfer: within one cell, tied texels of different bins get the same rank position in their
  // bins, so a flat motif stays coherent in E_G (a hash of the texel itself would make it salt and pepper);
  // then by the texel index. The stationary transfer hashes the texel index.
  std::vector<std::uint64_t> tie(n);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const std::size_t idx = std::size_t(j) * w + i;
      std::uint64_t key = idx * 0x9e3779b97f4a7c15ull;
      if (mode == 2) {
        double a, b;
        lattice_coords(*periods, i + 0.5, j + 0.5, &a, &b);
        key = std::uint64_t(std::int64_t(std::floor(a))) * 0x9e3779b97f4a7c15ull ^
              std::uint64_t(std::int64_t(std::floor(b))) * 0xc2b2ae3d27d4eb4full;
      }
      tie[idx] = mix64(key + 0x5354455848697374ull);
    }
  t.quantiles.assign(std::size_t(nb) * ch * t.q, 0.0f);
  if (gauss) {
    gauss->width = w;
    gauss->height = h;
    gauss->channels = ch;
    gauss->pixels.assign(n * ch, 0.0f);
  }
  std::vector<std::uint32_t> pool;
  std::vector<char> used(static_cast<std::size_t>(nb), 0);
  std::vector<double> gval;  // Gaussian value of rank r for the current pool size
  for (int bj = 0; bj < t.m1; ++bj)
    for (int bi = 0; bi < t.m0; ++bi) {
      const int b = bj * t.m0 + bi;
      // The pooled samples E^b: bins within the neighbourhood, grown while too few.
      int r = t.delta;
      for (;;) {
        pool.clear();
        std::fill(used.begin(), used.end(), 0);
        const int ri = std::min(r, (t.m0 - 1) / 2 + 1), rj = std::min(r, (t.m1 - 1) / 2 + 1);
        for (int dj = -rj; dj <= rj; ++dj)
          for (int di = -ri; di <= ri; ++di) {
            const int nbn = (((bj + dj) % t.m1 + t.m1) % t.m1) * t.m0 + ((bi + di) % t.m0 + t.m0) % t.m0;
            if (used[std::size_t(nbn)]) continue;
            used[std::size_t(nbn)] = 1;
            pool.insert(pool.end(), members[std::size_t(nbn)].begin(), members[std::size_t(nbn)].end());
          }
        if (pool.size() >= std::size_t(k_cs_hist_min_samples) || (ri > (t.m0 - 1) / 2 && rj > (t.m1 - 1) / 2)) break;
        ++r;
      }
      const std::size_t np = pool.size();
      if (np == 0) throw Error(ErrorKind::Input, "a histogram bin has no samples (the exemplar is too small)");
      if (gauss) {
        gval.resize(np);
        for (std::size_t k = 0; k < np; ++k) gval[k] = 0.5 + phi_inv((double(k) + 0.5) / double(np)) / 6.0;
      }
      std::vector<std::uint32_t> order(pool);
      for (int c = 0; c < ch; ++c) {
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t bb) {
          const float va = img.pixels[std::size_t(a) * ch + c], vb = img.pixels[std::size_t(bb) * ch + c];
          if (va != vb) return va < vb;
          return tie[a] != tie[bb] ? tie[a] < tie[bb] : a < bb;
        });
        float* qv = &t.quantiles[(std::size_t(b) * ch + c) * t.q];
        for (int k = 0; k < t.q; ++k) {
          const double pos = std::clamp((double(k) + 0.5) / t.q * double(np) - 0.5, 0.0, double(np - 1));
          const std::size_t r0 = std::min(std::size_t(pos), np - 1), r1 = std::min(r0 + 1, np - 1);
          const double f = pos - double(r0);
          const double a = img.pixels[std::size_t(order[r0]) * ch + c], bv = img.pixels[std::size_t(order[r1]) * ch + c];
          qv[k] = float(a + f * (bv - a));
        }
        for (int k = 1; k < t.q; ++k) qv[k] = std::max(qv[k], qv[k - 1]);  // rounding of the interpolation
        if (gauss)
          for (std::size_t k = 0; k < np; ++k)
            if (bin_of[order[k]] == b) gauss->pixels[std::size_t(order[k]) * ch + c] = float(gval[k]);
      }
    }
  return t;
}

}  // namespace stex
