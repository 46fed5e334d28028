// Lattice statistics of cyclostationary textures (S4 §3.2, §6). See cs_lattice.h.
#include "analysis/cs_lattice.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "analysis/fft.h"
#include "core/error.h"
#include "core/math.h"

namespace stex {

namespace {


std::string num(double v) {
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}

double cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// Lattice-coordinate bounds of the rectangle [x0, x1] x [y0, y1] (its 4 corners).
void coord_bounds(const Lattice& t, double x0, double y0, double x1, double y1, double* amin, double* amax,
                  double* bmin, double* bmax) {
  *amin = *bmin = 1e300;
  *amax = *bmax = -1e300;
  const double xs[2] = {x0, x1}, ys[2] = {y0, y1};
  for (double x : xs)
    for (double y : ys) {
      double a, b;
      lattice_coords(t, x, y, &a, &b);
      *amin = std::min(*amin, a);
      *amax = std::max(*amax, a);
      *bmin = std::min(*bmin, b);
      *bmax = std::max(*bmax, b);
    }
}

bool lattice_usable(const Lattice& t) {
  const double l0 = std::hypot(t.t0x, t.t0y), l1 = std::hypot(t.t1x, t.t1y);
  const double area = lattice_area(t);
  return std::isfinite(area) && l0 >= 1.0 && l1 >= 1.0 && area >= 2.0 && area >= std::sin(5.0 * k_pi / 180.0) * l0 * l1;
}

// The sample set of the distance: per phase, the lattice coordinates (a, b) of its samples relative to the
// exemplar's centre. Fixed while the candidates of one step size are compared.
struct SampleSet {
  double cx = 0.0, cy = 0.0;
  std::vector<std::vector<std::pair<double, double>>> phases;
};

SampleSet build_samples(const Image& img, const Lattice& t, const DistanceOptions& o, double step) {
  SampleSet s;
  s.cx = 0.5 * img.width;
  s.cy = 0.5 * img.height;
  double amin, amax, bmin, bmax;
  coord_bounds(t, 0.5 - s.cx, 0.5 - s.cy, img.width - 0.5 - s.cx, img.height - 0.5 - s.cy, &amin, &amax, &bmin, &bmax);
  const int p = o.phases;
  s.phases.resize(std::size_t(p) * p);
  for (int j = 0; j < p; ++j)
    for (int i = 0; i < p; ++i) {
      const double u = (i + 0.5) / p, v = (j + 0.5) / p;
      std::vector<std::pair<double, double>> all;
      for (long l = long(std::floor(bmin - v)); l <= long(std::ceil(bmax - v)); ++l)
        for (long k = long(std::floor(amin - u)); k <= long(std::ceil(amax - u)); ++k) {
          const double a = u + double(k), b = v + double(l);
          const double x = s.cx + a * t.t0x + b * t.t1x, y = s.cy + a * t.t0y + b * t.t1y;
          // Samples that stay inside while the search moves the periods by about a step.
          const double m = 0.5 + std::min(2.0 * step * (std::fabs(a) + std::fabs(b)), 3.0);
          if (x >= m && y >= m && x <= img.width - m && y <= img.height - m) all.push_back({a, b});
        }
      auto& dst = s.phases[std::size_t(j) * p + i];
      if (int(all.size()) <= o.max_samples) {
        dst = std::move(all);
      } else {
        // Evenly spread over the list (ordered by (l, k)): samples from all over the exemplar.
        for (int q = 0; q < o.max_samples; ++q) dst.push_back(all[std::size_t(q) * all.size() / o.max_samples]);
      }
    }
  return s;
}

// The texels and weights of a bilinear read at texel-centre coordinates (x, y) (pixel centres at +0.5),
// clamped to the exemplar: sample_bilinear's, and eval_distance's for every channel at once.
struct BilinearTap {
  std::size_t p00, p10, p01, p11;  // float offsets of channel 0
  double fx, fy;
  double at(const float* px, int c) const {
    const double a = px[p00 + c] + fx * (px[p10 + c] - px[p00 + c]);
    const double b = px[p01 + c] + fx * (px[p11 + c] - px[p01 + c]);
    return a + fy * (b - a);
  }
};

BilinearTap bilinear_tap(const Image& img, double x, double y) {
  double fx = std::clamp(x - 0.5, 0.0, double(img.width - 1));
  double fy = std::clamp(y - 0.5, 0.0, double(img.height - 1));
  const int i0 = std::min(int(fx), std::max(img.width - 2, 0)), j0 = std::min(int(fy), std::max(img.height - 2, 0));
  const int i1 = std::min(i0 + 1, img.width - 1), j1 = std::min(j0 + 1, img.height - 1);
  const std::size_t ch = std::size_t(img.channels), w = std::size_t(img.width);
  return {(std::size_t(j0) * w + std::size_t(i0)) * ch, (std::size_t(j0) * w + std::size_t(i1)) * ch,
          (std::size_t(j1) * w + std::size_t(i0)) * ch, (std::size_t(j1) * w + std::size_t(i1)) * ch, fx - i0, fy - j0};
}

double eval_distance(const Image& img, const Lattice& t, const SampleSet& s) {
  const int ch = img.channels;
  std::vector<double> vals;
  double total = 0.0;
  int used = 0;
  for (const auto& ph : s.phases) {
    const std::size_t n = ph.size();
    if (n < 2) continue;
    vals.resize(n * ch);
    for (std::size_t q = 0; q < n; ++q) {
      const double x = s.cx + ph[q].first * t.t0x + ph[q].second * t.t1x;
      const double y = s.cy + ph[q].first * t.t0y + ph[q].second * t.t1y;
      const BilinearTap b = bilinear_tap(img, x, y);
      for (int c = 0; c < ch; ++c) vals[q * ch + c] = b.at(img.pixels.data(), c);
    }
    double acc = 0.0;
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = a + 1; b < n; ++b) {
        double d2 = 0.0;
        for (int c = 0; c < ch; ++c) {
          const double d = vals[a * ch + c] - vals[b * ch + c];
          d2 += d * d;
        }
        acc += std::sqrt(d2);
      }
    total += acc / (0.5 * double(n) * double(n - 1));
    ++used;
  }
  if (used == 0) throw Error(ErrorKind::Input, "no polyphase component has 2 samples in the exemplar for these periods");
  return total / used;
}

void check_options(const DistanceOptions& o) {
  if (o.phases < 1 || o.phases > 256) throw Error(ErrorKind::Usage, "distance phases must be 1..256");
  if (o.max_samples < 2 || o.max_samples > 4096) throw Error(ErrorKind::Usage, "distance max_samples must be 2..4096");
}

}  // namespace

double lattice_area(const Lattice& t) { return std::fabs(cross(t.t0x, t.t0y, t.t1x, t.t1y)); }

void lattice_coords(const Lattice& t, double x, double y, double* a, double* b) {
  const double det = cross(t.t0x, t.t0y, t.t1x, t.t1y);
  *a = cross(x, y, t.t1x, t.t1y) / det;
  *b = cross(t.t0x, t.t0y, x, y) / det;
}

void lattice_phase(const Lattice& t, double x, double y, double* u, double* v) {
  double a, b;
  lattice_coords(t, x, y, &a, &b);
  *u = a - std::floor(a);
  *v = b - std::floor(b);
  if (*u >= 1.0) *u = 0.0;  // a = -tiny rounds to 1
  if (*v >= 1.0) *v = 0.0;
}

Lattice reduce_lattice(const Lattice& in) {
  double ax = in.t0x, ay = in.t0y, bx = in.t1x, by = in.t1y;
  auto n2 = [](double x, double y) { return x * x + y * y; };
  if (n2(ax, ay) > n2(bx, by)) {
    std::swap(ax, bx);
    std::swap(ay, by);
  }
  for (int it = 0; it < 64; ++it) {
    const double m = std::round((ax * bx + ay * by) / n2(ax, ay));
    bx -= m * ax;
    by -= m * ay;
    if (n2(bx, by) < n2(ax, ay) * (1.0 - 1e-12)) {
      std::swap(ax, bx);
      std::swap(ay, by);
    } else {
      break;
    }
  }
  if (ax < 0.0 || (ax == 0.0 && ay < 0.0)) {
    ax = -ax;
    ay = -ay;
  }
  if (cross(ax, ay, bx, by) < 0.0) {
    bx = -bx;
    by = -by;
  }
  return Lattice{ax, ay, bx, by};
}

bool lattices_match(const Lattice& a, const Lattice& b, double tol, double* error) {
  double worst = 0.0;
  bool ok = true;
  auto one_way = [&](const Lattice& from, const Lattice& to) {
    if (!(lattice_area(from) > 0.0)) {
      ok = false;
      worst = 1e300;
      return;
    }
    long n[4];
    const double v[2][2] = {{to.t0x, to.t0y}, {to.t1x, to.t1y}};
    for (int q = 0; q < 2; ++q) {
      double ca, cb;
      lattice_coords(from, v[q][0], v[q][1], &ca, &cb);
      if (!std::isfinite(ca) || !std::isfinite(cb) || std::fabs(ca) > 1e6 || std::fabs(cb) > 1e6) {
        ok = false;
        worst = 1e300;
        return;
      }
      n[2 * q] = std::lround(ca);
      n[2 * q + 1] = std::lround(cb);
      const double ex = v[q][0] - (double(n[2 * q]) * from.t0x + double(n[2 * q + 1]) * from.t1x);
      const double ey = v[q][1] - (double(n[2 * q]) * from.t0y + double(n[2 * q + 1]) * from.t1y);
      worst = std::max(worst, std::hypot(ex, ey));
    }
    if (std::labs(n[0] * n[3] - n[1] * n[2]) != 1) ok = false;
  };
  one_way(a, b);
  one_way(b, a);
  if (error) *error = worst;
  return ok && worst <= tol;
}

void validate_lattice(const Lattice& t, int width, int height) {
  auto bad = [](const std::string& m) { throw Error(ErrorKind::Usage, "invalid periods: " + m); };
  if (!std::isfinite(t.t0x) || !std::isfinite(t.t0y) || !std::isfinite(t.t1x) || !std::isfinite(t.t1y))
    bad("the period vectors must be finite");
  const double l0 = std::hypot(t.t0x, t.t0y), l1 = std::hypot(t.t1x, t.t1y);
  if (l0 < 1.0 || l1 < 1.0) bad("each period vector must be at least 1 pixel long (got " + num(l0) + ", " + num(l1) + ")");
  const double area = lattice_area(t);
  if (area < 2.0) bad("the parallelogram of t0, t1 must cover at least 2 pixels^2 (got " + num(area) + ")");
  if (area < std::sin(5.0 * k_pi / 180.0) * l0 * l1) bad("t0 and t1 are (nearly) parallel: the angle between them must be at least 5 degrees");
  // A quarter (two repetitions per axis), plus 2 % for the sub-pixel error of an estimate of exactly two.
  if (area > 0.255 * double(width) * double(height))
    bad("the parallelogram of t0, t1 (" + num(area) + " pixels^2) must be at most a quarter of the exemplar (" +
        std::to_string(width) + "x" + std::to_string(height) + "): each polyphase component needs samples");
}

Lattice parse_lattice(const std::string& text) {
  double v[4];
  const char* p = text.c_str();
  for (int i = 0; i < 4; ++i) {
    char* end = nullptr;
    errno = 0;
    v[i] = std::strtod(p, &end);
    if (end == p || errno != 0 || !std::isfinite(v[i]))
      throw Error(ErrorKind::Usage, "--periods must be x0,y0,x1,y1 (four numbers, pixels), got '" + text + "'");
    p = end;
    if (i < 3) {
      if (*p != ',') throw Error(ErrorKind::Usage, "--periods must be x0,y0,x1,y1 (four numbers, pixels), got '" + text + "'");
      ++p;
    }
  }
  if (*p != '\0') throw Error(ErrorKind::Usage, "--periods must be x0,y0,x1,y1 (four numbers, pixels), got '" + text + "'");
  return Lattice{v[0], v[1], v[2], v[3]};
}

double sample_bilinear(const Image& img, double x, double y, int c) {
  const BilinearTap b = bilinear_tap(img, x, y);
  return b.at(img.pixels.data(), c);
}

std::vector<std::pair<double, double>> polyphase_positions(const Lattice& t, int width, int height, double u, double v) {
  double amin, amax, bmin, bmax;
  const double lo = 0.5, hx = width - 0.5, hy = height - 0.5;
  coord_bounds(t, lo, lo, hx, hy, &amin, &amax, &bmin, &bmax);
  std::vector<std::pair<double, double>> out;
  const double eps = 1e-9;
  for (long l = long(std::floor(bmin - v)); l <= long(std::ceil(bmax - v)); ++l)
    for (long k = long(std::floor(amin - u)); k <= long(std::ceil(amax - u)); ++k) {
      const double a = u + double(k), b = v + double(l);
      const double x = a * t.t0x + b * t.t1x, y = a * t.t0y + b * t.t1y;
      if (x >= lo - eps && y >= lo - eps && x <= hx + eps && y <= hy + eps) out.push_back({x, y});
    }
  return out;
}

std::vector<float> polyphase_component(const Image& img, const Lattice& t, double u, double v) {
  const auto pos = polyphase_positions(t, img.width, img.height, u, v);
  std::vector<float> out(pos.size() * img.channels);
  for (std::size_t q = 0; q < pos.size(); ++q)
    for (int c = 0; c < img.channels; ++c) out[q * img.channels + c] = float(sample_bilinear(img, pos[q].first, pos[q].second, c));
  return out;
}

double CyclicMean::at(double u, double v, int c) const {
  const double x = u * n0, y = v * n1;
  const double fi = std::floor(x), fj = std::floor(y);
  const double fx = x - fi, fy = y - fj;
  const int i0 = int(((long(fi) % n0) + n0) % n0), j0 = int(((long(fj) % n1) + n1) % n1);
  const int i1 = (i0 + 1) % n0, j1 = (j0 + 1) % n1;
  auto m = [&](int i, int j) { return double(values[(std::size_t(j) * n0 + i) * channels + c]); };
  const double a = m(i0, j0) + fx * (m(i1, j0) - m(i0, j0));
  const double b = m(i0, j1) + fx * (m(i1, j1) - m(i0, j1));
  return a + fy * (b - a);
}

double CyclicMean::at_point(double x, double y, int c) const {
  double u, v;
  lattice_phase(periods, x, y, &u, &v);
  return at(u, v, c);
}

CyclicMean cyclic_mean(const Image& img, const Lattice& t) {
  validate_lattice(t, img.width, img.height);
  CyclicMean m;
  m.periods = t;
  m.n0 = std::max(1, int(std::ceil(2.0 * std::hypot(t.t0x, t.t0y) - 1e-9)));
  m.n1 = std::max(1, int(std::ceil(2.0 * std::hypot(t.t1x, t.t1y) - 1e-9)));
  m.channels = img.channels;
  m.values.assign(std::size_t(m.n0) * m.n1 * img.channels, 0.0f);
  m.min_samples = 1 << 30;
  for (int j = 0; j < m.n1; ++j)
    for (int i = 0; i < m.n0; ++i) {
      const auto pos = polyphase_positions(t, img.width, img.height, double(i) / m.n0, double(j) / m.n1);
      m.min_samples = std::min(m.min_samples, int(pos.size()));
      if (pos.size() < 2)
        throw Error(ErrorKind::Input, "the exemplar (" + std::to_string(img.width) + "x" + std::to_string(img.height) +
                                          ") is too small for these periods: a polyphase component has " +
                                          std::to_string(pos.size()) + " sample(s)");
      for (int c = 0; c < img.channels; ++c) {
        double s = 0.0;
        for (const auto& p : pos) s += sample_bilinear(img, p.first, p.second, c);
        m.values[(std::size_t(j) * m.n0 + i) * img.channels + c] = float(s / double(pos.size()));
      }
    }
  return m;
}

double lattice_distance(const Image& img, const Lattice& t, const DistanceOptions& o) {
  check_options(o);
  return eval_distance(img, t, build_samples(img, t, o, 0.0));
}

double stationary_distance(const Image& img) {
  const std::size_t n = std::size_t(img.width) * img.height;
  std::uint64_t s = 0x9e3779b97f4a7c15ull;
  auto next = [&]() {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return std::size_t((s >> 33) % n);
  };
  double acc = 0.0;
  constexpr int k_pairs = 20000;
  for (int q = 0; q < k_pairs; ++q) {
    const std::size_t a = next(), b = next();
    double d2 = 0.0;
    for (int c = 0; c < img.channels; ++c) {
      const double d = double(img.pixels[a * img.channels + c]) - img.pixels[b * img.channels + c];
      d2 += d * d;
    }
    acc += std::sqrt(d2);
  }
  return acc / k_pairs;
}

namespace {

// The linear autocorrelation of the exemplar (the sum over its channels of each centred channel's), through
// a 2w x 2h zero-padded FFT.
struct Autocorrelation {
  int w = 0, h = 0, pw = 0, ph = 0;
  std::vector<double> f;  // unnormalised, on the padded grid (negative lags wrap around)
  double a0 = 0.0;         // the lag-0 value per overlapping pixel

  // The unnormalised value at lag (tx, ty).
  double raw(int tx, int ty) const {
    return f[std::size_t((ty + ph) % ph) * pw + std::size_t((tx + pw) % pw)];
  }
  // The value at lag (tx, ty), normalised by the overlap and by a0 (1 at lag 0).
  double at(int tx, int ty) const {
    return raw(tx, ty) / (double(w - std::abs(tx)) * double(h - std::abs(ty))) / a0;
  }
};

// Computes the autocorrelation; throws Input for a constant exemplar.
Autocorrelation exemplar_autocorrelation(const Image& img) {
  const int w = img.width, h = img.height;
  Autocorrelation ac;
  ac.w = w;
  ac.h = h;
  ac.pw = 2 * w;
  ac.ph = 2 * h;
  const int pw = ac.pw, ph = ac.ph;
  // Real transforms (half spectra): the power spectra summed over the channels, back to the lags.
  const std::size_t half = std::size_t(half_width(pw)) * ph;
  std::vector<double> g(std::size_t(pw) * ph);
  std::vector<Complex> spec(half), power(half, Complex(0.0, 0.0));
  for (int c = 0; c < img.channels; ++c) {
    double mean = 0.0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) mean += img.at(x, y, c);
    mean /= double(w) * h;
    std::fill(g.begin(), g.end(), 0.0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) g[std::size_t(y) * pw + x] = img.at(x, y, c) - mean;
    fft2d_r2c(pw, ph, g.data(), spec.data());
    for (std::size_t q = 0; q < half; ++q) power[q] += Complex(std::norm(spec[q]), 0.0);
  }
  ac.f.resize(std::size_t(pw) * ph);
  fft2d_c2r(pw, ph, power.data(), ac.f.data());
  ac.a0 = ac.raw(0, 0) / (double(w) * h);
  if (!(ac.a0 > 1e-12))
    throw Error(ErrorKind::Input, "the exemplar is constant: it has no periods to estimate");
  return ac;
}

// An off-centre peak of the autocorrelation at sub-pixel lag (x, y).
struct AcPeak {
  double x, y, value, len;
};

// Whether lag (tx, ty), of value c, beats its 8 neighbours (ties: the first in scan order wins).
bool is_local_max(const Autocorrelation& ac, int tx, int ty, double c) {
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      if (!dx && !dy) continue;
      const double n = ac.at(tx + dx, ty + dy);
      const bool before = dy < 0 || (dy == 0 && dx < 0);
      if (n > c || (before && n == c)) return false;
    }
  return true;
}

// The local maxima of the half plane of lags up to half the exemplar along each axis (two repetitions), off
// the central lobe, with sub-pixel positions, in scan order.
std::vector<AcPeak> autocorrelation_peaks(const Autocorrelation& ac) {
  const int rx = ac.w / 2, ry = ac.h / 2;
  std::vector<AcPeak> peaks;
  for (int ty = 0; ty <= ry; ++ty)
    for (int tx = -rx; tx <= rx; ++tx) {
      if (ty == 0 && tx <= 0) continue;
      if (tx * tx + ty * ty < 4) continue;
      const double c = ac.at(tx, ty);
      if (!(c > 0.0) || !is_local_max(ac, tx, ty, c)) continue;
      // Not on the central lobe: the autocorrelation dips by a fifth of c, and by 0.02, between 0 and t.
      const double len = std::hypot(double(tx), double(ty));
      double dip = c;
      const int steps = int(std::ceil(len));
      for (int q = 1; q < steps; ++q) {
        const int sx = int(std::lround(tx * double(q) / steps)), sy = int(std::lround(ty * double(q) / steps));
        dip = std::min(dip, ac.at(sx, sy));
      }
      if (c - dip < std::max(0.02, 0.2 * c)) continue;
      // Sub-pixel position: a parabola along each axis.
      auto vertex = [](double m, double z, double p) {
        const double den = m - 2.0 * z + p;
        return den < 0.0 ? std::clamp(0.5 * (m - p) / den, -0.5, 0.5) : 0.0;
      };
      const double ox = vertex(ac.at(tx - 1, ty), c, ac.at(tx + 1, ty));
      const double oy = vertex(ac.at(tx, ty - 1), c, ac.at(tx, ty + 1));
      peaks.push_back({tx + ox, ty + oy, c, std::hypot(tx + ox, ty + oy)});
    }
  return peaks;
}

// Whether a lattice can be a candidate on a width x height exemplar: usable, each vector at least 3 pixels,
// the cell at most a quarter of the exemplar (plus 2 %, as validate_lattice).
bool candidate_usable(const Lattice& t, int width, int height) {
  return lattice_usable(t) && std::hypot(t.t0x, t.t0y) >= 3.0 && std::hypot(t.t1x, t.t1y) >= 3.0 && lattice_area(t) >= 12.0 &&
         lattice_area(t) <= 0.255 * double(width) * double(height);
}

// The distance options of the candidate search: coarser than the refinement's.
DistanceOptions coarse_options() {
  DistanceOptions o;
  o.phases = 12;
  o.max_samples = 32;
  return o;
}

// Appends t (reduced) with its d unless unusable or already there (within a pixel).
void add_candidate(std::vector<PeriodCandidate>& cands, const Image& img, const Lattice& in, const std::string& source,
                   const DistanceOptions& o) {
  const Lattice t = reduce_lattice(in);
  if (!candidate_usable(t, img.width, img.height)) return;
  for (const PeriodCandidate& c : cands)
    if (lattices_match(c.periods, t, 1.0)) return;
  cands.push_back({t, lattice_distance(img, t, o), source});
}

// The lattices one step finer than t: those that contain t with index 2 or 3 (for a prime p, the p + 1
// lattices spanned by t and one of t0 / p, (k t0 + t1) / p, k = 0 .. p - 1).
std::vector<Lattice> finer_lattices(const Lattice& t) {
  std::vector<Lattice> out;
  for (int p : {2, 3}) {
    out.push_back(Lattice{t.t0x / p, t.t0y / p, t.t1x, t.t1y});
    for (int k = 0; k < p; ++k)
      out.push_back(Lattice{t.t0x, t.t0y, (k * t.t0x + t.t1x) / p, (k * t.t0y + t.t1y) / p});
  }
  return out;
}

// The lattices one step coarser than t: those that t contains with index 2 or 3 (for a prime p, the p + 1
// lattices spanned by p t0, t1 and by t0 + k t1, p t1, k = 0 .. p - 1).
std::vector<Lattice> coarser_lattices(const Lattice& t) {
  std::vector<Lattice> out;
  for (int p : {2, 3}) {
    out.push_back(Lattice{p * t.t0x, p * t.t0y, t.t1x, t.t1y});
    for (int k = 0; k < p; ++k)
      out.push_back(Lattice{t.t0x + k * t.t1x, t.t0y + k * t.t1y, p * t.t1x, p * t.t1y});
  }
  return out;
}

// The pattern search on d (module comment of cs_lattice.h): steps from max_step down to min_step.
Lattice pattern_search(const Image& img, const Lattice& start, const DistanceOptions& o, double max_step,
                       double min_step, int* evaluations) {
  Lattice best = start;
  for (double step = max_step; step >= min_step * (1.0 - 1e-9); step *= 0.5) {
    const SampleSet set = build_samples(img, best, o, step);
    double dbest = eval_distance(img, best, set);
    ++*evaluations;
    for (int it = 0; it < 32; ++it) {
      Lattice cand_best = best;
      double cand_d = dbest;
      for (int coord = 0; coord < 4; ++coord)
        for (int sign = -1; sign <= 1; sign += 2) {
          Lattice c = best;
          double* v = coord == 0 ? &c.t0x : coord == 1 ? &c.t0y : coord == 2 ? &c.t1x : &c.t1y;
          *v += sign * step;
          if (!lattice_usable(c)) continue;
          const double d = eval_distance(img, c, set);
          ++*evaluations;
          if (d < cand_d) {
            cand_d = d;
            cand_best = c;
          }
        }
      if (!(cand_d < dbest)) break;
      best = cand_best;
      dbest = cand_d;
    }
  }
  return best;
}

// Sub-pixel registration of one lattice vector v: the mean over the exemplar of the squared colour
// difference between the points p + v / 2 and p - v / 2 (p on a grid of texel centres, both points read
// bilinearly: their fractional offsets are opposite, so both are blurred alike and the minimum is not pulled
// towards whole pixels). The grid and the region of p are fixed for one registration (the margin covers the
// moves), so the criterion is a smooth function of v.
struct ShiftRegion {
  double x0, y0, x1, y1;
  int stride;
  bool usable;
};

ShiftRegion shift_region(const Image& img, double vx, double vy, double margin) {
  ShiftRegion r;
  r.x0 = 0.5 + 0.5 * std::fabs(vx) + margin;
  r.y0 = 0.5 + 0.5 * std::fabs(vy) + margin;
  r.x1 = img.width - 0.5 - 0.5 * std::fabs(vx) - margin;
  r.y1 = img.height - 0.5 - 0.5 * std::fabs(vy) - margin;
  const double n = std::max(0.0, r.x1 - r.x0) * std::max(0.0, r.y1 - r.y0);
  // At most about 2^14 points per evaluation (the registered image is smooth: on the corpus a stride of up to 4
  // pixels gave the same matches as 2^16 points, in about 0.8 of the estimation time); a region of under an
  // eighth of the exemplar is not used.
  r.stride = std::max(1, int(std::ceil(std::sqrt(n / 16384.0))));
  r.usable = n >= double(img.width) * img.height / 8.0;
  return r;
}

double shift_ssd(const Image& img, const ShiftRegion& r, double vx, double vy) {
  // p = (i + 0.5, j + 0.5): the texel coordinates of p +- v / 2 are (i, j) + the offsets +-v / 2, so the
  // bilinear weights are the same for every p and the reads need no clamping (the region's margin).
  const int ch = img.channels, w = img.width;
  const double ax = 0.5 * vx, ay = 0.5 * vy;
  const int pxa = int(std::floor(ax)), pya = int(std::floor(ay)), pxb = int(std::floor(-ax)), pyb = int(std::floor(-ay));
  const double fxa = ax - pxa, fya = ay - pya, fxb = -ax - pxb, fyb = -ay - pyb;
  const double wa[4] = {(1 - fxa) * (1 - fya), fxa * (1 - fya), (1 - fxa) * fya, fxa * fya};
  const double wb[4] = {(1 - fxb) * (1 - fyb), fxb * (1 - fyb), (1 - fxb) * fyb, fxb * fyb};
  const std::ptrdiff_t row = std::ptrdiff_t(w) * ch;
  const float* px = img.pixels.data();
  double acc = 0.0;
  long count = 0;
  const int i0 = int(std::ceil(r.x0 - 0.5)), i1 = int(std::floor(r.x1 - 0.5));
  const int j0 = int(std::ceil(r.y0 - 0.5)), j1 = int(std::floor(r.y1 - 0.5));
  for (int j = j0; j <= j1; j += r.stride)
    for (int i = i0; i <= i1; i += r.stride) {
      const float* a = px + (std::ptrdiff_t(j + pya) * w + (i + pxa)) * ch;
      const float* b = px + (std::ptrdiff_t(j + pyb) * w + (i + pxb)) * ch;
      for (int c = 0; c < ch; ++c) {
        const double va = wa[0] * a[c] + wa[1] * a[c + ch] + wa[2] * a[c + row] + wa[3] * a[c + row + ch];
        const double vb = wb[0] * b[c] + wb[1] * b[c + ch] + wb[2] * b[c + row] + wb[3] * b[c + row + ch];
        acc += (va - vb) * (va - vb);
      }
      ++count;
    }
  return count ? acc / double(count) : 0.0;
}

// Minimises shift_ssd around (vx, vy): a 3 x 3 grid of step h (h0 at first); while its best point is off-centre the grid
// moves there, else the quadratic through the 9 values gives the vertex (within the grid) and h halves,
// down to 1/32 pixel. Returns false when the region is too small to register.
bool register_vector(const Image& img, double* vx, double* vy, double h0) {
  const ShiftRegion r = shift_region(img, *vx, *vy, 3.0);
  if (!r.usable) return false;
  double cx = *vx, cy = *vy, h = h0;
  // The values already computed (a move keeps 6 of the 9 grid points, a halving the centre).
  std::vector<std::array<double, 3>> seen;
  auto ssd = [&](double x, double y) {
    for (const auto& q : seen)
      if (q[0] == x && q[1] == y) return q[2];
    const double e = shift_ssd(img, r, x, y);
    seen.push_back({x, y, e});
    return e;
  };
  for (int it = 0; it < 24 && h >= 1.0 / 32.0; ++it) {
    double e[3][3];
    int bi = 1, bj = 1;
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        e[j][i] = ssd(cx + (i - 1) * h, cy + (j - 1) * h);
        if (e[j][i] < e[bj][bi]) {
          bi = i;
          bj = j;
        }
      }
    if (bi != 1 || bj != 1) {
      if (std::fabs(cx + (bi - 1) * h - *vx) > 2.5 || std::fabs(cy + (bj - 1) * h - *vy) > 2.5) break;  // left the region
      cx += (bi - 1) * h;
      cy += (bj - 1) * h;
      continue;
    }
    // Quadratic e = a + b x + c y + d x^2 + f x y + g y^2 on the grid (x, y in {-1, 0, 1}): closed-form fit.
    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0, s = 0;
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        const double x = i - 1, y = j - 1, v = e[j][i];
        s += v;
        sx += x * v;
        sy += y * v;
        sxx += x * x * v;
        syy += y * y * v;
        sxy += x * y * v;
      }
    const double b = sx / 6.0, c = sy / 6.0, f = sxy / 4.0;
    const double d = 0.5 * sxx - s / 3.0, g = 0.5 * syy - s / 3.0;
    const double det = 4.0 * d * g - f * f;
    if (d > 0.0 && det > 0.0) {
      const double ox = std::clamp((-2.0 * g * b + f * c) / det, -1.0, 1.0);
      const double oy = std::clamp((-2.0 * d * c + f * b) / det, -1.0, 1.0);
      cx += ox * h;
      cy += oy * h;
    }
    h *= 0.5;
  }
  *vx = cx;
  *vy = cy;
  return true;
}

// The exemplar blurred by a Gaussian of standard deviation 1 pixel (separable, radius 3, borders clamped):
// bilinear reads of it are close to the band-limited image between texels, so the registration's minimum is
// not pulled towards whole or half pixels by the interpolation's own smoothing of detail and noise.
// Separable convolution by the symmetric kernel k (2 r + 1 taps), borders clamped.
Image convolve_separable(const Image& img, const std::vector<double>& k) {
  const int r = int(k.size() / 2);
  Image tmp = img, out = img;
  const int w = img.width, h = img.height, ch = img.channels;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < ch; ++c) {
        double s = 0.0;
        for (int q = -r; q <= r; ++q) s += k[std::size_t(q + r)] * img.at(std::clamp(x + q, 0, w - 1), y, c);
        tmp.at(x, y, c) = float(s);
      }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < ch; ++c) {
        double s = 0.0;
        for (int q = -r; q <= r; ++q) s += k[std::size_t(q + r)] * tmp.at(x, std::clamp(y + q, 0, h - 1), c);
        out.at(x, y, c) = float(s);
      }
  return out;
}

Image gaussian_blur_1px(const Image& img) {
  return convolve_separable(img, {0.004433, 0.054006, 0.242036, 0.399050, 0.242036, 0.054006, 0.004433});
}

// A separable Gaussian blur of standard deviation sigma pixels (radius 3 sigma, borders clamped).
Image gaussian_blur(const Image& img, double sigma) {
  const int r = int(std::ceil(3.0 * sigma));
  std::vector<double> k(2 * std::size_t(r) + 1);
  double sum = 0.0;
  for (int q = -r; q <= r; ++q) sum += k[std::size_t(q + r)] = std::exp(-0.5 * q * q / (sigma * sigma));
  for (double& v : k) v /= sum;
  return convolve_separable(img, k);
}

// The image that register_lattice works on: the central differences along x and y, per channel, of the
// (already 1 px blurred) exemplar blurred by 1.5 px more.
//  - A filter without a DC response: registering the exemplar itself is biased by a constant offset per cell
//    (a tile a little lighter than its neighbour): at the cells' edges the squared difference changes to first
//    order with the shift. With the shift right the edges coincide in both images, and after a zero-DC filter
//    each edge is a profile f with sum f f' = 0, so the bias is gone (measured on the corpus: errors of
//    0.1-0.3 px on large cells with per-cell colour fell to 0.02-0.04 px).
//  - The extra blur: the derivative amplifies noise, and bilinear reads of noise at a half-pixel offset have
//    less variance than at a whole one, which pulls the minimum towards half pixels; 1.5 px more makes the
//    image smooth at the scale of a texel (0.7 px: 6 of 6 large-cell misses within 0.1 px, worst 0.09 px;
//    1.5 px: worst 0.054 px).
Image gradient_image(const Image& img_in) {
  const Image img = gaussian_blur(img_in, 1.5);
  const int w = img.width, h = img.height, ch = img.channels;
  Image out;
  out.width = w;
  out.height = h;
  out.channels = 2 * ch;
  out.pixels.assign(std::size_t(w) * h * out.channels, 0.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < ch; ++c) {
        out.at(x, y, 2 * c) = 0.5f * (img.at(std::min(x + 1, w - 1), y, c) - img.at(std::max(x - 1, 0), y, c));
        out.at(x, y, 2 * c + 1) = 0.5f * (img.at(x, std::min(y + 1, h - 1), c) - img.at(x, std::max(y - 1, 0), c));
      }
  return out;
}

// Registers t0, t1, t0 + t1 and t0 - t1 (those whose region is large enough) on the blurred exemplar and fits
// the lattice to them by least squares: the final sub-pixel refinement.
Lattice register_lattice(const Image& img, const Lattice& in) {
  const Lattice t = reduce_lattice(in);
  double v[4][2] = {{t.t0x, t.t0y}, {t.t1x, t.t1y}, {t.t0x + t.t1x, t.t0y + t.t1y}, {t.t0x - t.t1x, t.t0y - t.t1y}};
  bool ok[4];
  double wgt[4];
  for (int q = 0; q < 4; ++q) {
    ok[q] = register_vector(img, &v[q][0], &v[q][1], 0.5);
    wgt[q] = 1.0;
    // A multiple m v of a short vector is registered as precisely as v and gives v to 1/m of that: double m
    // while the shifted exemplar still overlaps itself on a quarter of its area, each time from twice the last
    // estimate (whose error is then within the registration's reach).
    // A move of more than a quarter of the shortest period (or of 1 px) means the search slid towards another
    // lattice vector (small periods: m v and m v + t are both minima): the last estimate stands.
    const double reach = 0.25 * std::min(std::hypot(t.t0x, t.t0y), std::hypot(t.t1x, t.t1y));
    for (int m = 2; ok[q] && m <= 64; m *= 2) {
      const double sx = m * v[q][0], sy = m * v[q][1];
      if ((img.width - std::fabs(sx)) * (img.height - std::fabs(sy)) < 0.25 * double(img.width) * img.height) break;
      double mx = sx, my = sy;
      // From twice an estimate good to a few hundredths of a pixel: the search starts at a quarter pixel.
      if (!register_vector(img, &mx, &my, 0.25) || std::hypot(mx - sx, my - sy) > std::min(reach, 1.0)) break;
      v[q][0] = mx / m;
      v[q][1] = my / m;
      wgt[q] = double(m) * m;
    }
  }
  // Normal equations of sum |t0 - v0|^2 + |t1 - v1|^2 + |t0 + t1 - v2|^2 + |t0 - t1 - v3|^2 over the used ones.
  Lattice out = t;
  for (int axis = 0; axis < 2; ++axis) {
    double a00 = 0, a01 = 0, a11 = 0, r0 = 0, r1 = 0;
    const double w[4] = {ok[0] ? wgt[0] : 0.0, ok[1] ? wgt[1] : 0.0, ok[2] ? wgt[2] : 0.0, ok[3] ? wgt[3] : 0.0};
    a00 = w[0] + w[2] + w[3];
    a11 = w[1] + w[2] + w[3];
    a01 = w[2] - w[3];
    r0 = w[0] * v[0][axis] + w[2] * v[2][axis] + w[3] * v[3][axis];
    r1 = w[1] * v[1][axis] + w[2] * v[2][axis] - w[3] * v[3][axis];
    const double det = a00 * a11 - a01 * a01;
    if (!(det > 1e-9)) return t;
    const double x0 = (a11 * r0 - a01 * r1) / det, x1 = (a00 * r1 - a01 * r0) / det;
    (axis == 0 ? out.t0x : out.t0y) = x0;
    (axis == 0 ? out.t1x : out.t1y) = x1;
  }
  return out;
}

// The best of the lattices one step finer than t (d at the options o); d = +inf when none is usable.
PeriodCandidate best_finer(const Image& img, const Lattice& t, const DistanceOptions& o) {
  PeriodCandidate best{t, std::numeric_limits<double>::infinity(), ""};
  for (const Lattice& f : finer_lattices(t)) {
    const Lattice r = reduce_lattice(f);
    if (!candidate_usable(r, img.width, img.height)) continue;
    const double d = lattice_distance(img, r, o);
    if (d < best.d) best = {r, d, "finer (index " + std::to_string(int(std::lround(lattice_area(t) / lattice_area(r)))) + ")"};
  }
  return best;
}

// The most promising lattice one step coarser than t (coarser_lattices): the one with the lowest d at the
// candidates' options, refined briefly (its vectors carry t's error times 2 or 3) and its d at the options o.
// Cells over an eighth of the exemplar are not tried: with so few cells d is noisy, and the lowest of seven
// noisy values picked a super-lattice on the corpus. d = +inf when none is usable.
PeriodCandidate best_coarser(const Image& img, const Lattice& t, const DistanceOptions& o, int* evaluations) {
  PeriodCandidate best{t, std::numeric_limits<double>::infinity(), ""};
  double best_coarse = std::numeric_limits<double>::infinity();
  Lattice pick;
  for (const Lattice& c : coarser_lattices(t)) {
    const Lattice rc = reduce_lattice(c);
    if (!candidate_usable(rc, img.width, img.height) || lattice_area(rc) > double(img.width) * img.height / 8.0) continue;
    const double dc = lattice_distance(img, rc, coarse_options());
    if (dc < best_coarse) {
      best_coarse = dc;
      pick = rc;
    }
  }
  if (!std::isfinite(best_coarse)) return best;
  const Lattice q = reduce_lattice(pattern_search(img, pick, o, 0.5, 0.125, evaluations));
  best = {q, lattice_distance(img, q, o), "coarser (index " + std::to_string(int(std::lround(lattice_area(pick) / lattice_area(t)))) + ")"};
  return best;
}

// d, d_stationary, d_finer and the confidence of r.periods, with the warnings they call for.
void assess(const Image& img, const EstimateOptions& o, PeriodEstimate& r, bool given) {
  r.d = lattice_distance(img, r.periods, o.distance);
  r.d_stationary = stationary_distance(img);
  const PeriodCandidate finer = best_finer(img, r.periods, o.distance);
  r.d_finer = finer.d;
  const double gap = r.d_stationary - r.d;
  // The share of the random pairs' distance that the lattice explains, times how clearly the next finer
  // lattice is worse (its excess over d, in units of k_fit of the gap: 1 or more is a clear rejection).
  const double explained = r.d_stationary > 0.0 ? std::clamp(1.0 - r.d / r.d_stationary, 0.0, 1.0) : 0.0;
  const double separation = gap > 0.0 && std::isfinite(r.d_finer)
                                ? std::clamp((r.d_finer - r.d) / (k_separation * gap), 0.0, 1.0)
                                : (std::isfinite(r.d_finer) ? 0.0 : 1.0);
  r.confidence = explained * separation;
  if (std::isfinite(finer.d) && separation < 0.5)
    r.warnings.push_back(std::string("a finer lattice, (") + num(finer.periods.t0x) + ", " + num(finer.periods.t0y) +
                         ") (" + num(finer.periods.t1x) + ", " + num(finer.periods.t1y) + "), fits almost as well (d " +
                         num(finer.d) + " against " + num(r.d) + ")" +
                         (given ? ": the periods given may be a multiple of the texture's; check with `stex periods --plot`"
                                : ": the periods are ambiguous; check them with `stex periods --plot`, or give --periods"));
  if (r.confidence < k_low_confidence)
    r.warnings.push_back("low confidence " + num(r.confidence) + " in the periods (d = " + num(r.d) + ", random pairs " +
                         num(r.d_stationary) + ", finer lattice " + num(r.d_finer) +
                         "): the exemplar may be stationary, or the periods wrong; check them with `stex periods --plot` "
                         "or give --periods");
}

void check_steps(const EstimateOptions& o) {
  check_options(o.distance);
  if (!(o.min_step > 0.0) || !(o.max_step >= o.min_step) || o.max_step > 8.0)
    throw Error(ErrorKind::Usage, "refinement steps must satisfy 0 < min_step <= max_step <= 8");
}

}  // namespace

Image flatten_lighting(const Image& img) {
  // Least-squares plane a + b x + c y per channel (x, y centred and scaled to [-1/2, 1/2]: the normal
  // equations are diagonal up to rounding on the full grid).
  Image out = img;
  const int w = img.width, h = img.height;
  for (int c = 0; c < img.channels; ++c) {
    double s = 0.0, sx = 0.0, sy = 0.0, xx = 0.0, yy = 0.0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double v = img.at(x, y, c), u = (x + 0.5) / w - 0.5, t = (y + 0.5) / h - 0.5;
        s += v;
        sx += v * u;
        sy += v * t;
        xx += u * u;
        yy += t * t;
      }
    const double n = double(w) * h, a = s / n, b = xx > 0.0 ? sx / xx : 0.0, cc = yy > 0.0 ? sy / yy : 0.0;
    // The plane's lowest value over the exemplar: divide (lighting multiplies) when it stays clearly positive.
    const double lowest = a - 0.5 * std::fabs(b) - 0.5 * std::fabs(cc);
    const bool divide = a > 0.0 && lowest > 0.1 * a;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double u = (x + 0.5) / w - 0.5, t = (y + 0.5) / h - 0.5, plane = a + b * u + cc * t;
        const double v = img.at(x, y, c);
        out.at(x, y, c) = float(divide ? v * (a / plane) : v - plane + a);
      }
  }
  return out;
}

Lattice autocorrelation_periods(const Image& img, double* peak0, double* peak1) {
  std::vector<PeriodCandidate> cands = autocorrelation_candidates(img, peak0, peak1);
  return cands.front().periods;
}

namespace {

// Best first: the smallest cell among those whose d is within k_fit of the gap (to the random pairs'
// distance) of the lowest d; a finer lattice mixes distinct polyphase components and raises d, a coarser
// one (a super-lattice) keeps it. Then by d.
std::vector<std::size_t> candidate_order(const std::vector<PeriodCandidate>& cands, double d_stat) {
  double dmin = std::numeric_limits<double>::infinity();
  for (const PeriodCandidate& c : cands) dmin = std::min(dmin, c.d);
  const double limit = dmin + k_fit * std::max(d_stat - dmin, 0.0);
  std::vector<std::size_t> order(cands.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const bool fa = cands[a].d <= limit, fb = cands[b].d <= limit;
    if (fa != fb) return fa;
    if (fa) return lattice_area(cands[a].periods) < lattice_area(cands[b].periods);
    return cands[a].d < cands[b].d;
  });
  return order;
}

}  // namespace

std::vector<PeriodCandidate> autocorrelation_candidates(const Image& img, double* peak0, double* peak1) {
  const int w = img.width, h = img.height;
  if (w < 16 || h < 16) throw Error(ErrorKind::Input, "period estimation needs an exemplar of at least 16x16 pixels");
  const Autocorrelation ac = exemplar_autocorrelation(img);
  std::vector<AcPeak> peaks = autocorrelation_peaks(ac);
  if (peaks.empty()) throw Error(ErrorKind::Input, "the autocorrelation of the exemplar has no off-centre peak: give --periods");
  double top = 0.0;
  for (const AcPeak& p : peaks) top = std::max(top, p.value);
  // The shortest peaks of at least a third of the highest: every independent pair spans a candidate.
  std::vector<AcPeak> strong;
  for (const AcPeak& p : peaks)
    if (p.value >= top / 3.0) strong.push_back(p);
  std::stable_sort(strong.begin(), strong.end(), [](const AcPeak& a, const AcPeak& b) { return a.len < b.len; });
  if (strong.size() > 10) strong.resize(10);
  const DistanceOptions o = coarse_options();
  std::vector<PeriodCandidate> cands;
  std::vector<std::pair<double, double>> values;
  for (std::size_t i = 0; i < strong.size(); ++i)
    for (std::size_t j = i + 1; j < strong.size(); ++j) {
      const AcPeak &a = strong[i], &b = strong[j];
      if (std::fabs(cross(a.x, a.y, b.x, b.y)) < 0.25 * a.len * b.len) continue;
      const std::size_t before = cands.size();
      add_candidate(cands, img, Lattice{a.x, a.y, b.x, b.y}, "autocorrelation peaks", o);
      if (cands.size() > before) values.push_back({a.value, b.value});
    }
  if (cands.empty())
    throw Error(ErrorKind::Input, "the autocorrelation of the exemplar has no two independent peaks (one period only?): give --periods");
  std::vector<std::size_t> order = candidate_order(cands, stationary_distance(img));
  std::vector<PeriodCandidate> sorted;
  for (std::size_t i : order) sorted.push_back(cands[i]);
  if (peak0) *peak0 = values[order[0]].first;
  if (peak1) *peak1 = values[order[0]].second;
  return sorted;
}


PeriodEstimate refine_periods(const Image& img_in, const Lattice& initial, const EstimateOptions& o) {
  check_steps(o);
  validate_lattice(initial, img_in.width, img_in.height);
  const Image img = gaussian_blur_1px(flatten_lighting(img_in));
  PeriodEstimate r;
  r.initial = reduce_lattice(initial);
  r.d_initial = lattice_distance(img, r.initial, o.distance);
  r.periods = reduce_lattice(register_lattice(
      gradient_image(img), pattern_search(img, r.initial, o.distance, o.max_step, std::max(1.0 / 16.0, o.min_step), &r.evaluations)));
  assess(img, o, r, true);
  r.candidates.push_back({r.initial, r.d_initial, "given"});
  r.candidates.insert(r.candidates.begin(), {r.periods, r.d, "refined"});
  return r;
}

PeriodEstimate given_periods(const Image& img, const Lattice& periods) {
  validate_lattice(periods, img.width, img.height);
  PeriodEstimate est;
  est.periods = est.initial = periods;
  est.d = est.d_initial = lattice_distance(img, periods);
  est.d_stationary = stationary_distance(img);
  est.confidence = est.d_stationary > 0.0 ? std::clamp(1.0 - est.d / est.d_stationary, 0.0, 1.0) : 0.0;
  if (est.confidence < k_low_confidence)
    est.warnings.push_back("low confidence " + std::to_string(est.confidence) +
                           " in the given periods: check them, or try --estimate-periods");
  return est;
}

PeriodEstimate estimate_periods(const Image& img_in, const EstimateOptions& o) {
  check_steps(o);
  if (img_in.width < 16 || img_in.height < 16)
    throw Error(ErrorKind::Input, "period estimation needs an exemplar of at least 16x16 pixels");
  const Image img = gaussian_blur_1px(flatten_lighting(img_in));
  PeriodEstimate r;
  std::vector<PeriodCandidate> cands = autocorrelation_candidates(img, &r.peak0, &r.peak1);
  r.initial = cands.front().periods;
  r.d_initial = lattice_distance(img, r.initial, o.distance);
  const double d_stat = stationary_distance(img);
  if (std::min(r.peak0, r.peak1) < k_repeat_peaks) {
    // The exemplar does not repeat: the autocorrelation's lattice is reported unrefined with confidence 0.
    // Refining it is slow and misleading there (on a smooth stationary texture the finer-lattice steps shrink a
    // period to a few pixels, where neighbouring pixels agree: d falls and the confidence rises with no lattice
    // at all; docs/cyclostationary.md).
    r.periods = reduce_lattice(r.initial);
    r.d = r.d_initial;
    r.d_stationary = d_stat;
    r.d_finer = std::numeric_limits<double>::quiet_NaN();
    r.confidence = 0.0;
    r.warnings.push_back("the exemplar does not repeat: its autocorrelation's two peaks (" + num(r.peak0) + ", " +
                         num(r.peak1) + ") are below " + num(k_repeat_peaks) +
                         "; these periods are the autocorrelation's guess, unrefined (confidence 0): give --periods "
                         "for a near-regular texture");
    r.candidates = cands;
    try {
      validate_lattice(r.periods, img.width, img.height);
    } catch (const Error& e) {
      throw Error(ErrorKind::Input, std::string("the exemplar does not repeat (autocorrelation peaks ") + num(r.peak0) +
                                        ", " + num(r.peak1) + " below " + num(k_repeat_peaks) +
                                        ") and the autocorrelation's periods are unusable (" + e.what() + "): give --periods");
    }
    return r;
  }
  // The first candidate, refined coarsely; then, while a lattice one step finer fits about as well (within
  // k_fit of the gap), that one: the primitive lattice is the smallest cell that keeps d.
  Lattice t = pattern_search(img, r.initial, o.distance, std::max(o.max_step, o.min_step), std::max(1.0 / 16.0, o.min_step),
                             &r.evaluations);
  double d = lattice_distance(img, t, o.distance);
  // Then, while the best lattice one step coarser has a clearly lower d (by more than k_fit of the gap), that
  // one: t was finer than the texture's and mixed distinct polyphase components (the autocorrelation's peaks
  // can miss a long period, for example along grout lines, where every shift along the line correlates).
  for (int round = 0; round < 4; ++round) {
    const PeriodCandidate c = best_coarser(img, t, o.distance, &r.evaluations);
    if (!(c.d < d - k_fit * std::max(d_stat - d, 0.0))) break;
    cands.push_back(c);
    t = pattern_search(img, c.periods, o.distance, 0.25, std::max(1.0 / 16.0, o.min_step), &r.evaluations);
    d = lattice_distance(img, t, o.distance);
  }
  for (int round = 0; round < 8; ++round) {
    const PeriodCandidate f = best_finer(img, t, o.distance);
    if (!(f.d <= d + k_fit * std::max(d_stat - d, 0.0))) break;
    cands.push_back(f);
    t = pattern_search(img, f.periods, o.distance, 0.25, std::max(1.0 / 16.0, o.min_step), &r.evaluations);
    d = lattice_distance(img, t, o.distance);
  }
  r.periods = reduce_lattice(register_lattice(gradient_image(img), t));
  assess(img, o, r, false);
  r.candidates.push_back({r.periods, r.d, "refined"});
  for (const PeriodCandidate& c : cands)
    if (r.candidates.size() < 12) r.candidates.push_back(c);
  try {
    validate_lattice(r.periods, img.width, img.height);
  } catch (const Error& e) {
    throw Error(ErrorKind::Input, std::string("the estimated periods are unusable (") + e.what() + "): give --periods");
  }
  return r;
}

}  // namespace stex
