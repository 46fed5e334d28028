// Synthetic cyclostationary exemplars with known periods for the tests of the cs area: bricks (per-cell
// random colour between smooth mortar lines, a smooth periodic pattern inside each cell) on any
// parallelogram lattice, plus white noise. Evaluated at texel centres (i + 0.5, j + 0.5) in the model
// coordinates of analysis/cs_lattice.h, so the true periods are exactly the lattice given.
#pragma once
#include <cmath>
#include <cstdint>
#include <random>

#include "analysis/cs_lattice.h"
#include "analysis/image_io.h"

namespace stex::test {

inline double cs_hash01(std::int64_t k, std::int64_t l, std::uint64_t seed, int c) {
  std::uint64_t h = seed * 0x9e3779b97f4a7c15ull ^ (std::uint64_t(k) * 0xbf58476d1ce4e5b9ull) ^
                    (std::uint64_t(l) * 0x94d049bb133111ebull) ^ (std::uint64_t(c + 1) * 0x2545f4914f6cdd1dull);
  h ^= h >> 31;
  h *= 0x9e3779b97f4a7c15ull;
  h ^= h >> 29;
  return double(h >> 11) * (1.0 / 9007199254740992.0);
}

// cell_contrast: amplitude of the per-cell random colour; noise: std of the white noise added per texel.
// mortar: the width (pixels) of the mortar's Gaussian profile.
inline Image make_bricks(int w, int h, const Lattice& t, int channels, double cell_contrast, double noise,
                         std::uint64_t seed, double mortar_width = 1.2) {
  constexpr double pi = 3.14159265358979323846;
  Image img;
  img.width = w;
  img.height = h;
  img.channels = channels;
  img.pixels.resize(std::size_t(w) * h * channels);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const double area = lattice_area(t), l0 = std::hypot(t.t0x, t.t0y), l1 = std::hypot(t.t1x, t.t1y);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      double a, b;
      lattice_coords(t, i + 0.5, j + 0.5, &a, &b);
      const double k = std::floor(a), l = std::floor(b), fu = a - k, fv = b - l;
      // Distances (pixels) to the cell's sides: the lines a = k (parallel to t1) and b = l (parallel to t0).
      const double du = std::min(fu, 1.0 - fu) * area / l1, dv = std::min(fv, 1.0 - fv) * area / l0;
      const double dm = std::min(du, dv);
      const double mortar = std::exp(-(dm / mortar_width) * (dm / mortar_width));
      const double intra = 0.08 * std::sin(2.0 * pi * fu) + 0.06 * std::cos(2.0 * pi * (fu + 2.0 * fv));
      for (int c = 0; c < channels; ++c) {
        const double cell = cell_contrast * (2.0 * cs_hash01(std::int64_t(k), std::int64_t(l), seed, c) - 1.0);
        const double brick = 0.55 + 0.1 * c + cell + intra * (1.0 - 0.3 * c);
        img.at(i, j, c) = float((1.0 - mortar) * brick + mortar * 0.15 + noise * gauss(rng));
      }
    }
  return img;
}

// A smooth stationary texture: white noise blurred by a (2r + 1)^2 box.
inline Image make_stationary(int w, int h, int channels, int r, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<double> white(std::size_t(w) * h * channels);
  for (double& v : white) v = gauss(rng);
  Image img;
  img.width = w;
  img.height = h;
  img.channels = channels;
  img.pixels.resize(white.size());
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
      for (int c = 0; c < channels; ++c) {
        double s = 0.0;
        for (int dy = -r; dy <= r; ++dy)
          for (int dx = -r; dx <= r; ++dx)
            s += white[(std::size_t((j + dy + h) % h) * w + std::size_t((i + dx + w) % w)) * channels + c];
        img.at(i, j, c) = float(0.5 + 0.1 * s / (2 * r + 1));
      }
  return img;
}

}  // namespace stex::test
