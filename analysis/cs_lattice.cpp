// Lattice statistics of cyclostationary textures (S4 §3.2, §6). See cs_lattice.h.
#include "analysis/cs_lattice.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
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

// Luminance (channel mean) of the exemplar.
std::vector<double> luminance(const Image& img) {
  std::vector<double> u(std::size_t(img.width) * img.height);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      double s = 0.0;
      for (int c = 0; c < img.channels; ++c) s += img.at(x, y, c);
      u[std::size_t(y) * img.width + x] = s / img.channels;
    }
  return u;
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
      for (int c = 0; c < ch; ++c) vals[q * ch + c] = sample_bilinear(img, x, y, c);
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

void validate_lattice(const Lattice& t, int width, int height) {
  auto bad = [](const std::string& m) { throw Error(ErrorKind::Usage, "invalid periods: " + m); };
  if (!std::isfinite(t.t0x) || !std::isfinite(t.t0y) || !std::isfinite(t.t1x) || !std::isfinite(t.t1y))
    bad("the period vectors must be finite");
  const double l0 = std::hypot(t.t0x, t.t0y), l1 = std::hypot(t.t1x, t.t1y);
  if (l0 < 1.0 || l1 < 1.0) bad("each period vector must be at least 1 pixel long (got " + num(l0) + ", " + num(l1) + ")");
  const double area = lattice_area(t);
  if (area < 2.0) bad("the parallelogram of t0, t1 must cover at least 2 pixels^2 (got " + num(area) + ")");
  if (area < std::sin(5.0 * k_pi / 180.0) * l0 * l1) bad("t0 and t1 are (nearly) parallel: the angle between them must be at least 5 degrees");
  if (area > 0.25 * double(width) * double(height))
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
  double fx = std::clamp(x - 0.5, 0.0, double(img.width - 1));
  double fy = std::clamp(y - 0.5, 0.0, double(img.height - 1));
  const int i0 = std::min(int(fx), std::max(img.width - 2, 0)), j0 = std::min(int(fy), std::max(img.height - 2, 0));
  const int i1 = std::min(i0 + 1, img.width - 1), j1 = std::min(j0 + 1, img.height - 1);
  fx -= i0;
  fy -= j0;
  const double a = img.at(i0, j0, c) + fx * (img.at(i1, j0, c) - img.at(i0, j0, c));
  const double b = img.at(i0, j1, c) + fx * (img.at(i1, j1, c) - img.at(i0, j1, c));
  return a + fy * (b - a);
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

// The linear autocorrelation of the exemplar's centred luminance (2w x 2h zero-padded FFT).
struct Autocorrelation {
  int w = 0, h = 0, pw = 0, ph = 0;
  std::vector<Complex> f;  // unnormalised, on the padded grid (negative lags wrap around)
  double a0 = 0.0;         // the lag-0 value per overlapping pixel

  // The unnormalised value at lag (tx, ty).
  double raw(int tx, int ty) const {
    return f[std::size_t((ty + ph) % ph) * pw + std::size_t((tx + pw) % pw)].real();
  }
  // The value at lag (tx, ty), normalised by the overlap and by a0 (1 at lag 0).
  double at(int tx, int ty) const {
    return raw(tx, ty) / (double(w - std::abs(tx)) * double(h - std::abs(ty))) / a0;
  }
};

// Computes the autocorrelation; throws Input for a constant exemplar.
Autocorrelation luminance_autocorrelation(const Image& img) {
  const int w = img.width, h = img.height;
  std::vector<double> lum = luminance(img);
  double mean = 0.0;
  for (double v : lum) mean += v;
  mean /= double(lum.size());
  // Linear (not circular) autocorrelation through a 2w x 2h zero-padded FFT, normalised by the overlap.
  Autocorrelation ac;
  ac.w = w;
  ac.h = h;
  ac.pw = 2 * w;
  ac.ph = 2 * h;
  const int pw = ac.pw, ph = ac.ph;
  std::vector<Complex>& f = ac.f;
  f.assign(std::size_t(pw) * ph, Complex(0.0, 0.0));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) f[std::size_t(y) * pw + x] = Complex(lum[std::size_t(y) * w + x] - mean, 0.0);
  fft2d_forward(pw, ph, f);
  for (Complex& z : f) z = Complex(std::norm(z), 0.0);
  fft2d_inverse(pw, ph, f);
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
  bool is_max = true;
  for (int dy = -1; dy <= 1 && is_max; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      if (!dx && !dy) continue;
      const double n = ac.at(tx + dx, ty + dy);
      // Ties: the first in scan order wins.
      const bool before = dy < 0 || (dy == 0 && dx < 0);
      if (n > c || (before && n == c)) {
        is_max = false;
        break;
      }
    }
  return is_max;
}

// The local maxima of the half plane of lags off the central lobe, with sub-pixel positions, in scan order.
std::vector<AcPeak> autocorrelation_peaks(const Autocorrelation& ac) {
  const int rx = ac.w / 2, ry = ac.h / 2;
  std::vector<AcPeak> peaks;
  for (int ty = 0; ty < ry; ++ty)
    for (int tx = -rx + 1; tx < rx; ++tx) {
      if (ty == 0 && tx <= 0) continue;
      if (tx * tx + ty * ty < 4) continue;
      const double c = ac.at(tx, ty);
      if (!is_local_max(ac, tx, ty, c)) continue;
      // Not on the central lobe: the autocorrelation dips by 0.1 somewhere between 0 and t.
      const double len = std::hypot(double(tx), double(ty));
      double dip = c;
      const int steps = int(std::ceil(len));
      for (int q = 1; q < steps; ++q) {
        const int sx = int(std::lround(tx * double(q) / steps)), sy = int(std::lround(ty * double(q) / steps));
        dip = std::min(dip, ac.at(sx, sy));
      }
      if (c - dip < 0.1) continue;
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

// The shortest peak of value >= threshold and independent of `other` (if given); nullptr if none.
const AcPeak* shortest_peak(const std::vector<AcPeak>& peaks, double threshold, const AcPeak* other) {
  const AcPeak* best = nullptr;
  for (const AcPeak& p : peaks) {
    if (p.value < threshold) continue;
    if (other && std::fabs(cross(other->x, other->y, p.x, p.y)) < 0.25 * other->len * p.len) continue;
    if (!best || p.len < best->len) best = &p;
  }
  return best;
}

// A lattice spanned by two peaks, with its area, its distance d and the two peaks' values.
struct LatticeCandidate {
  Lattice t;
  double area, d, v0, v1;
};

// Appends the lattice spanned by peaks a and b unless it is degenerate, too coarse or a duplicate.
void add_candidate(std::vector<LatticeCandidate>& cands, const Image& img, const AcPeak* a, const AcPeak* b) {
  const int w = img.width, h = img.height;
  if (std::fabs(cross(a->x, a->y, b->x, b->y)) < 0.25 * a->len * b->len) return;
  const Lattice t = reduce_lattice(Lattice{a->x, a->y, b->x, b->y});
  if (!lattice_usable(t) || lattice_area(t) > 0.25 * double(w) * h) return;
  for (const LatticeCandidate& c : cands) {
    const double moved = std::fabs(c.t.t0x - t.t0x) + std::fabs(c.t.t0y - t.t0y) +
                         std::fabs(c.t.t1x - t.t1x) + std::fabs(c.t.t1y - t.t1y);
    if (std::fabs(lattice_area(c.t) - lattice_area(t)) < 0.5 && moved < 2.0) return;
  }
  DistanceOptions o;
  o.phases = 12;
  o.max_samples = 32;
  cands.push_back({t, lattice_area(t), lattice_distance(img, t, o), a->value, b->value});
}

// The candidates of (p0, p1) and of every pair of the 8 shortest strong peaks (value >= top / 2).
std::vector<LatticeCandidate> candidate_lattices(const Image& img, const std::vector<AcPeak>& peaks,
                                                 double top, const AcPeak* p0, const AcPeak* p1) {
  std::vector<const AcPeak*> strong;
  for (const AcPeak& p : peaks)
    if (p.value >= 0.5 * top) strong.push_back(&p);
  std::stable_sort(strong.begin(), strong.end(),
                   [](const AcPeak* a, const AcPeak* b) { return a->len < b->len; });
  if (strong.size() > 8) strong.resize(8);
  std::vector<LatticeCandidate> cands;
  add_candidate(cands, img, p0, p1);
  for (std::size_t i = 0; i < strong.size(); ++i)
    for (std::size_t j = i + 1; j < strong.size(); ++j) add_candidate(cands, img, strong[i], strong[j]);
  return cands;
}

}  // namespace

Lattice autocorrelation_periods(const Image& img, double* peak0, double* peak1) {
  const int w = img.width, h = img.height;
  if (w < 16 || h < 16) throw Error(ErrorKind::Input, "period estimation needs an exemplar of at least 16x16 pixels");
  const Autocorrelation ac = luminance_autocorrelation(img);
  const std::vector<AcPeak> peaks = autocorrelation_peaks(ac);
  if (peaks.empty()) throw Error(ErrorKind::Input, "the autocorrelation of the exemplar has no off-centre peak: give --periods");
  double top = 0.0;
  for (const AcPeak& p : peaks) top = std::max(top, p.value);
  const AcPeak* p0 = shortest_peak(peaks, 0.5 * top, nullptr);
  const AcPeak* p1 = shortest_peak(peaks, 0.5 * top, p0);
  if (!p1) p1 = shortest_peak(peaks, -1e300, p0);
  if (!p1)
    throw Error(ErrorKind::Input, "the autocorrelation of the exemplar has no two independent peaks (one period only?): give --periods");
  // Sub-harmonics: a pattern that repeats at t / 2 in part of the cell (a line, a motif) gives a strong
  // peak at t / 2 too, and the shortest peaks then span a lattice finer than the texture's. Every pair of
  // the shortest strong peaks spans a candidate lattice; a finer lattice mixes distinct polyphase
  // components and raises d, a coarser one (a super-lattice of the true one) keeps d. The answer is the
  // smallest candidate whose d is within 10 % of the lowest.
  const std::vector<LatticeCandidate> cands = candidate_lattices(img, peaks, top, p0, p1);
  if (cands.empty()) {
    if (peak0) *peak0 = p0->value;
    if (peak1) *peak1 = p1->value;
    return reduce_lattice(Lattice{p0->x, p0->y, p1->x, p1->y});
  }
  double dmin = 1e300;
  for (const LatticeCandidate& c : cands) dmin = std::min(dmin, c.d);
  const LatticeCandidate* best = nullptr;
  for (const LatticeCandidate& c : cands)
    if (c.d <= 1.1 * dmin && (!best || c.area < best->area)) best = &c;
  if (peak0) *peak0 = best->v0;
  if (peak1) *peak1 = best->v1;
  return best->t;
}

PeriodEstimate refine_periods(const Image& img, const Lattice& initial, const EstimateOptions& o) {
  check_options(o.distance);
  if (!(o.min_step > 0.0) || !(o.max_step >= o.min_step) || o.max_step > 8.0)
    throw Error(ErrorKind::Usage, "refinement steps must satisfy 0 < min_step <= max_step <= 8");
  validate_lattice(initial, img.width, img.height);
  PeriodEstimate r;
  r.initial = reduce_lattice(initial);
  Lattice best = r.initial;
  r.d_initial = lattice_distance(img, best, o.distance);
  for (double step = o.max_step; step >= o.min_step * (1.0 - 1e-9); step *= 0.5) {
    const SampleSet set = build_samples(img, best, o.distance, step);
    double dbest = eval_distance(img, best, set);
    ++r.evaluations;
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
          ++r.evaluations;
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
  r.periods = reduce_lattice(best);
  r.d = lattice_distance(img, r.periods, o.distance);
  r.d_stationary = stationary_distance(img);
  r.confidence = r.d_stationary > 0.0 ? std::clamp(1.0 - r.d / r.d_stationary, 0.0, 1.0) : 0.0;
  if (r.confidence < k_low_confidence)
    r.warnings.push_back("low confidence " + num(r.confidence) + " in the periods (d = " + num(r.d) +
                         ", random pairs " + num(r.d_stationary) +
                         "): the exemplar may be stationary, or the estimate wrong; check them or give --periods");
  return r;
}

PeriodEstimate estimate_periods(const Image& img, const EstimateOptions& o) {
  double p0 = 0.0, p1 = 0.0;
  const Lattice init = autocorrelation_periods(img, &p0, &p1);
  try {
    validate_lattice(init, img.width, img.height);
  } catch (const Error& e) {
    throw Error(ErrorKind::Input, std::string("the autocorrelation's periods are unusable (") + e.what() + "): give --periods");
  }
  PeriodEstimate r = refine_periods(img, init, o);
  r.peak0 = p0;
  r.peak1 = p1;
  return r;
}

}  // namespace stex
