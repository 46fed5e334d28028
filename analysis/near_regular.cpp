// Synthetic near-regular textures with a known primitive lattice. See near_regular.h.
#include "analysis/near_regular.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>

#include <Eigen/Dense>

#include "analysis/fft.h"
#include "core/error.h"
#include "core/math.h"

namespace stex {

namespace {

// splitmix64: the integer generator every draw comes from.
struct Rng {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double uniform() { return double(next() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  int integer(int lo, int hi) { return lo + int(next() % std::uint64_t(hi - lo + 1)); }  // [lo, hi]
  double gauss() {  // Box-Muller on two integer-drawn uniforms (values only, never counts)
    const double u1 = (double(next() >> 11) + 1.0) * (1.0 / 9007199254740993.0), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * k_pi * u2);
  }
};

// A hash of a cell's indices to uniforms in [0, 1): per-cell variations.
double cell_uniform(std::int64_t k, std::int64_t l, std::uint64_t seed, int what) {
  Rng r{seed ^ (std::uint64_t(k) * 0xd6e8feb86659fd93ull) ^ (std::uint64_t(l) * 0xa0761d6478bd642full) ^
        (std::uint64_t(what + 1) * 0xe7037ed1a0b428dbull)};
  r.next();
  return r.uniform();
}

// The motif: a random periodic field of the cell coordinates (an N x N tile in (u, v), 1/f amplitude
// spectrum up to order N / 4 with random phases: detail at every scale, like the grain of stone or
// ceramic; its order-1 terms make the lattice primitive), a disc, grout lines.
struct Motif {
  int n = 0;
  std::vector<double> tile;  // n x n, standard deviation 1
  double disc_u, disc_v, disc_r, disc_amp;
  double at(double u, double v) const {  // bilinear, periodic
    const double x = u * n, y = v * n;
    const int i0 = int(std::floor(x)), j0 = int(std::floor(y));
    const double fx = x - i0, fy = y - j0;
    auto t = [&](int i, int j) { return tile[std::size_t(((j % n) + n) % n) * n + std::size_t(((i % n) + n) % n)]; };
    const double a = t(i0, j0) + fx * (t(i0 + 1, j0) - t(i0, j0)), b = t(i0, j0 + 1) + fx * (t(i0 + 1, j0 + 1) - t(i0, j0 + 1));
    return a + fy * (b - a);
  }
};

Motif draw_motif(Rng& rng, double longest_period) {
  Motif m;
  m.n = 16;
  while (m.n < longest_period && m.n < 512) m.n *= 2;
  const int n = m.n, kmax = n / 4;
  std::vector<Complex> f(std::size_t(n) * n, Complex(0.0, 0.0));
  for (int ky = -kmax; ky <= kmax; ++ky)
    for (int kx = -kmax; kx <= kmax; ++kx) {
      if (!kx && !ky) continue;
      if (ky < 0 || (ky == 0 && kx < 0)) continue;  // the other half by symmetry
      const double amp = 1.0 / std::hypot(double(kx), double(ky)), phase = rng.uniform(0.0, 2.0 * k_pi);
      const Complex z = std::polar(amp, phase);
      f[std::size_t((ky + n) % n) * n + std::size_t((kx + n) % n)] = z;
      f[std::size_t((n - ky) % n) * n + std::size_t((n - kx) % n)] = std::conj(z);
    }
  fft2d_inverse(n, n, f);
  m.tile.resize(f.size());
  double s2 = 0.0;
  for (std::size_t q = 0; q < f.size(); ++q) {
    m.tile[q] = f[q].real();
    s2 += m.tile[q] * m.tile[q];
  }
  const double sd = std::sqrt(s2 / double(f.size()));
  for (double& v : m.tile) v /= sd;
  m.disc_u = rng.uniform();
  m.disc_v = rng.uniform();
  m.disc_r = rng.uniform(0.12, 0.3);
  m.disc_amp = rng.uniform(-1.5, 1.5);
  return m;
}

// The seed of the per-cell draws (its own stream, so that the realised lattice needs no motif).
std::uint64_t cell_seed_of(const NearRegularSpec& s) {
  Rng r{s.seed ^ 0x3c6ef372fe94f82bull};
  return r.next();
}

// The shift of cell (k, l), pixels, uniform in +-cell_jitter per axis.
void cell_shift(const NearRegularSpec& s, std::uint64_t cell_seed, std::int64_t k, std::int64_t l, double* jx,
                double* jy) {
  *jx = s.cell_jitter * (2.0 * cell_uniform(k, l, cell_seed, 0) - 1.0);
  *jy = s.cell_jitter * (2.0 * cell_uniform(k, l, cell_seed, 1) - 1.0);
}

double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

std::string tmp_directory(const std::string& dir) {
  if (!dir.empty()) return dir;
  const char* t = std::getenv("TMPDIR");
  return t && *t ? t : "/tmp";
}

}  // namespace

Image make_near_regular(const NearRegularSpec& s, const std::string& tmp_dir) {
  if (s.width < 16 || s.height < 16 || s.width > 4096 || s.height > 4096)
    throw Error(ErrorKind::Usage, "near-regular exemplar sizes must be 16..4096");
  if (s.channels != 1 && s.channels != 3) throw Error(ErrorKind::Usage, "near-regular exemplars have 1 or 3 channels");
  const Lattice& t = s.lattice;
  const double area = lattice_area(t);
  if (!(area > 1.0)) throw Error(ErrorKind::Usage, "near-regular lattice is degenerate");
  const double l0 = std::hypot(t.t0x, t.t0y), l1 = std::hypot(t.t1x, t.t1y);

  Rng rng{s.seed * 0x9e3779b97f4a7c15ull + 0x632be59bd9b4e019ull};
  const Motif motif = draw_motif(rng, std::max(l0, l1));
  double gain[3], base[3], disc_gain[3];
  for (int c = 0; c < 3; ++c) {
    gain[c] = rng.uniform(0.6, 1.2);
    base[c] = rng.uniform(0.35, 0.6);
    disc_gain[c] = rng.uniform(0.5, 1.2);
  }
  const double grout_level = rng.uniform(0.05, 0.25);
  const double scale = 0.1;  // the motif's standard deviation
  const double grout_px = std::max(0.8, s.grout_width * std::sqrt(area));
  const double disc_px = motif.disc_r * std::sqrt(area);
  const double ramp_den = s.width * std::fabs(std::cos(s.gradient_angle)) + s.height * std::fabs(std::sin(s.gradient_angle));
  const std::uint64_t cell_seed = cell_seed_of(s);

  Image img;
  img.width = s.width;
  img.height = s.height;
  img.channels = s.channels;
  img.pixels.resize(std::size_t(s.width) * s.height * s.channels);
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) {
      const double px = x + 0.5 - s.origin_x, py = y + 0.5 - s.origin_y;
      double a, b;
      lattice_coords(t, px, py, &a, &b);
      const std::int64_t k = std::int64_t(std::floor(a)), l = std::int64_t(std::floor(b));
      // The cell's own shift (pixels: the tile laid slightly off, grout included), contrast and colour.
      double jx, jy;
      cell_shift(s, cell_seed, k, l, &jx, &jy);
      const double contrast = 1.0 + s.cell_contrast * (2.0 * cell_uniform(k, l, cell_seed, 2) - 1.0);
      double ma, mb;
      lattice_coords(t, px - jx, py - jy, &ma, &mb);
      const double fu = ma - std::floor(ma), fv = mb - std::floor(mb);
      const double v = scale * motif.at(fu, fv);
      // The disc: its distance in pixels, on the periodic cell.
      double du = fu - motif.disc_u, dv = fv - motif.disc_v;
      du -= std::round(du);
      dv -= std::round(dv);
      const double dist = std::hypot(du * t.t0x + dv * t.t1x, du * t.t0y + dv * t.t1y);
      const double disc = 1.0 - smoothstep(disc_px - 0.7, disc_px + 0.7, dist);
      // Grout: the distance (pixels) to the nearest side of the shifted cell.
      const double side = std::min(std::min(fu, 1.0 - fu) * area / l1, std::min(fv, 1.0 - fv) * area / l0);
      const double grout = s.grout_width > 0.0 ? std::exp(-(side / grout_px) * (side / grout_px)) : 0.0;
      const double ramp = ramp_den > 0.0 ? ((x + 0.5 - 0.5 * s.width) * std::cos(s.gradient_angle) +
                                            (y + 0.5 - 0.5 * s.height) * std::sin(s.gradient_angle)) / ramp_den
                                         : 0.0;
      const double light = 1.0 + s.gradient * ramp;
      for (int c = 0; c < s.channels; ++c) {
        const int cc = s.channels == 1 ? 1 : c;
        const double cell = s.cell_colour * (2.0 * cell_uniform(k, l, cell_seed, 3 + cc) - 1.0);
        const double tile = base[cc] + cell + contrast * (gain[cc] * v + 0.1 * motif.disc_amp * disc_gain[cc] * disc);
        const double val = light * ((1.0 - grout) * tile + grout * grout_level) + s.noise * rng.gauss();
        img.at(x, y, c) = float(std::round(std::clamp(val, 0.0, 1.0) * 255.0) / 255.0);
      }
    }
  if (s.jpeg_quality > 0) {
    const std::string path = tmp_directory(tmp_dir) + "/stex_near_regular_" + std::to_string(::getpid()) + "_" +
                             std::to_string(s.seed) + ".jpg";
    WriteOptions wo;
    wo.metadata.push_back({"Compression", "jpeg:" + std::to_string(std::clamp(s.jpeg_quality, 1, 100))});
    write_image_atomic(path, img, wo);
    try {
      img = load_exemplar(path);
    } catch (...) {
      std::remove(path.c_str());
      throw;
    }
    std::remove(path.c_str());
  }
  return img;
}

Lattice realised_lattice(const NearRegularSpec& s) {
  const Lattice& t = s.lattice;
  if (!(lattice_area(t) > 1.0)) throw Error(ErrorKind::Usage, "near-regular lattice is degenerate");
  const std::uint64_t cell_seed = cell_seed_of(s);
  // Pixels per cell: each cell weighs what the image shows of it.
  std::map<std::pair<std::int64_t, std::int64_t>, double> count;
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) {
      double a, b;
      lattice_coords(t, x + 0.5 - s.origin_x, y + 0.5 - s.origin_y, &a, &b);
      count[{std::int64_t(std::floor(a)), std::int64_t(std::floor(b))}] += 1.0;
    }
  // Weighted least squares of each shift component on (1, k, l): the lattice's correction.
  double m[3][3] = {}, rx[3] = {}, ry[3] = {};
  for (const auto& [kl, w] : count) {
    const double f[3] = {1.0, double(kl.first), double(kl.second)};
    double jx, jy;
    cell_shift(s, cell_seed, kl.first, kl.second, &jx, &jy);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) m[i][j] += w * f[i] * f[j];
      rx[i] += w * f[i] * jx;
      ry[i] += w * f[i] * jy;
    }
  }
  const Eigen::Matrix3d mm = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(&m[0][0]);
  const Eigen::Vector3d bx = mm.ldlt().solve(Eigen::Vector3d(rx[0], rx[1], rx[2]));
  const Eigen::Vector3d by = mm.ldlt().solve(Eigen::Vector3d(ry[0], ry[1], ry[2]));
  if (!bx.allFinite() || !by.allFinite()) return t;  // one row or column of cells: the nominal lattice
  return Lattice{t.t0x + bx[1], t.t0y + by[1], t.t1x + bx[2], t.t1y + by[2]};
}

std::vector<NearRegularSpec> near_regular_corpus(int count, std::uint64_t seed) {
  if (count < 0 || count > 100000) throw Error(ErrorKind::Usage, "corpus size must be 0..100000");
  std::vector<NearRegularSpec> out;
  Rng rng{seed ^ 0x5851f42d4c957f2dull};
  static const int sizes[] = {128, 256, 256, 384, 512, 512, 512, 512};
  for (int i = 0; i < count; ++i) {
    NearRegularSpec s;
    s.seed = rng.next() >> 1;
    s.width = sizes[rng.integer(0, 7)];
    s.height = rng.uniform() < 0.25 ? sizes[rng.integer(1, 7)] : s.width;
    const double side = std::min(s.width, s.height);
    const double lmin = 4.0, lmax = side / 2.0;
    // Repetitions per axis log-uniform in [2, 30], periods clamped to [4, side / 2].
    auto length = [&]() { return std::clamp(side / std::exp(rng.uniform(std::log(2.0), std::log(30.0))), lmin, lmax); };
    const double l0 = length();
    const int which = rng.integer(0, 5);  // 0-2 rect (0: axis-aligned), 3-4 sheared, 5 hex
    const double theta = which == 0 ? 0.0 : rng.uniform(0.0, k_pi);
    double l1 = std::clamp(l0 * std::exp(rng.uniform(std::log(0.6), std::log(1.6))), lmin, lmax);
    double phi = 0.5 * k_pi;  // angle from t0 to t1
    if (which <= 2) {
      s.kind = "rect";
    } else if (which <= 4) {
      s.kind = "sheared";
      phi = rng.uniform() < 0.5 ? rng.uniform(55.0, 80.0) * k_pi / 180.0 : rng.uniform(100.0, 125.0) * k_pi / 180.0;
    } else {
      s.kind = "hex";
      l1 = l0;
      phi = k_pi / 3.0;
    }
    s.lattice = Lattice{l0 * std::cos(theta), l0 * std::sin(theta), l1 * std::cos(theta + phi), l1 * std::sin(theta + phi)};
    s.origin_x = rng.uniform(0.0, s.width);
    s.origin_y = rng.uniform(0.0, s.height);
    s.channels = rng.uniform() < 0.5 ? 3 : 1;
    s.grout_width = rng.uniform() < 0.6 ? rng.uniform(0.02, 0.08) : 0.0;
    s.cell_colour = rng.uniform(0.0, 0.12);
    s.cell_contrast = rng.uniform(0.0, 0.3);
    s.cell_jitter = rng.uniform(0.0, 0.1);
    s.noise = rng.uniform(0.0, 0.06);
    s.gradient = rng.uniform() < 1.0 / 3.0 ? rng.uniform(0.2, 0.6) : 0.0;
    s.gradient_angle = rng.uniform(0.0, 2.0 * k_pi);
    s.jpeg_quality = rng.uniform() < 0.5 ? rng.integer(60, 95) : 0;
    out.push_back(s);
  }
  return out;
}

std::string describe(const NearRegularSpec& s) {
  const Lattice& t = s.lattice;
  const double side0 = std::min(s.width, s.height);
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "%s %dx%dx%d periods (%.3f, %.3f) (%.3f, %.3f) reps %.1f/%.1f grout %.3f cell %.3f/%.3f/%.2fpx "
                "noise %.3f gradient %.2f jpeg %d seed %llu",
                s.kind.c_str(), s.width, s.height, s.channels, t.t0x, t.t0y, t.t1x, t.t1y,
                side0 / std::hypot(t.t0x, t.t0y), side0 / std::hypot(t.t1x, t.t1y), s.grout_width, s.cell_colour,
                s.cell_contrast, s.cell_jitter, s.noise, s.gradient, s.jpeg_quality, (unsigned long long)s.seed);
  return buf;
}

}  // namespace stex
