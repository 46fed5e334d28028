// Gabor noise models: codec of kind "gabor" and construction from a PSD. See gabor_model.h.
#include "analysis/gabor_model.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "analysis/fft.h"
#include "analysis/periodic.h"
#include "core/error.h"

namespace stex {

GaborModel gabor_roundtrip(const GaborModel& m) { return gabor_from_container(to_container(m), "in memory"); }

GaborModel gabor_model_from_psd(const Image& psd, double bandwidth, int max_components, double floor_rel,
                                int* dropped) {
  if (psd.width < 1 || psd.height < 1 || psd.channels < 1) throw Error(ErrorKind::Input, "the PSD image is empty");
  if (max_components < 1 || max_components > STEX_GABOR_MAX_COMPONENTS)
    throw Error(ErrorKind::Usage, "--max-components must be 1..4096, got " + std::to_string(max_components));
  const int w = psd.width, h = psd.height;
  auto at = [&](int i, int j) -> double {
    const float v = psd.at(((i % w) + w) % w, ((j % h) + h) % h, 0);
    if (!(v >= 0.0f)) throw Error(ErrorKind::Input, "the PSD image has a negative or NaN value");
    return v;
  };
  struct Bin {
    double fx, fy, p;
  };
  std::vector<Bin> bins;
  double peak = 0.0;
  int beyond = 0;
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      const int di = i - w / 2, dj = j - h / 2;
      // Half plane (di > 0, or di == 0 and dj >= 0) : the other half is the mirror image.
      if (di < 0 || (di == 0 && dj < 0)) continue;
      const int mi = w / 2 - di, mj = h / 2 - dj;  // the pixel of -f
      const double p = (di == 0 && dj == 0) ? 0.0 : at(i, j) + at(mi, mj);
      const double fx = double(di) / w, fy = double(dj) / h;
      if (p <= 0.0) continue;
      if (std::hypot(fx, fy) > 0.5) {
        ++beyond;
        continue;
      }
      bins.push_back({fx, fy, p});
      peak = std::max(peak, p);
    }
  }
  if (bins.empty() || !(peak > 0.0)) throw Error(ErrorKind::Input, "the PSD has no power below 0.5 cycles per pixel");
  std::stable_sort(bins.begin(), bins.end(), [](const Bin& a, const Bin& b) { return a.p > b.p; });
  GaborModel m;
  m.bandwidth = bandwidth;
  m.components.clear();
  int drop = beyond;
  for (const Bin& b : bins) {
    if (int(m.components.size()) >= max_components || b.p < floor_rel * peak) {
      ++drop;
      continue;
    }
    GaborComponent c;
    c.frequency = std::hypot(b.fx, b.fy);
    c.orientation = std::atan2(b.fy, b.fx);
    c.spread = 0.0;
    c.weight = b.p / peak;
    m.components.push_back(c);
  }
  if (dropped) *dropped = drop;
  return m;
}

Image exemplar_psd(const Image& ex, int grid, double* mean_out, double* std_out) {
  if (grid < 2 || grid > 1024) throw Error(ErrorKind::Usage, "--grid must be 2..1024, got " + std::to_string(grid));
  const int w = ex.width, h = ex.height;
  if (w < grid || h < grid)
    throw Error(ErrorKind::Input, "the exemplar (" + std::to_string(w) + "x" + std::to_string(h) +
                                      ") is smaller than the PSD grid " + std::to_string(grid));
  std::vector<double> u(std::size_t(w) * h, 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double s = 0.0;
      for (int c = 0; c < ex.channels; ++c) s += ex.at(x, y, c);
      u[std::size_t(y) * w + x] = s / ex.channels;
    }
  const double mean = std::accumulate(u.begin(), u.end(), 0.0) / double(u.size());
  std::vector<double> p = periodic_component(w, h, u);
  double var = 0.0;
  std::vector<Complex> f(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    f[i] = Complex(p[i] - mean, 0.0);
    var += (p[i] - mean) * (p[i] - mean);
  }
  var /= double(p.size());
  fft2d_forward(w, h, f);
  // Average |F|^2 over grid x grid bins of the centred spectrum: bin (bi, bj) gathers the frequencies whose
  // nearest centred bin (frequency f -> bin grid/2 + round(f grid), modulo grid).
  Image out;
  out.width = out.height = grid;
  out.channels = 1;
  out.pixels.assign(std::size_t(grid) * grid, 0.0f);
  std::vector<double> acc(std::size_t(grid) * grid, 0.0);
  std::vector<int> cnt(acc.size(), 0);
  for (int ky = 0; ky < h; ++ky)
    for (int kx = 0; kx < w; ++kx) {
      const double fx = double(kx >= (w + 1) / 2 ? kx - w : kx) / w, fy = double(ky >= (h + 1) / 2 ? ky - h : ky) / h;
      const int bi = (grid / 2 + int(std::lround(fx * grid)) + grid) % grid;
      const int bj = (grid / 2 + int(std::lround(fy * grid)) + grid) % grid;
      acc[std::size_t(bj) * grid + bi] += std::norm(f[std::size_t(ky) * w + kx]);
      ++cnt[std::size_t(bj) * grid + bi];
    }
  for (std::size_t i = 0; i < acc.size(); ++i) out.pixels[i] = cnt[i] ? float(acc[i] / cnt[i]) : 0.0f;
  if (mean_out) *mean_out = mean;
  if (std_out) *std_out = std::sqrt(var);
  return out;
}

}  // namespace stex
