// The picture of `stex periods --plot`. See period_plot.h.
#include "analysis/period_plot.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace stex {

DistanceMap distance_map(const Image& img, const Lattice& t, int n, double step, const DistanceOptions& o) {
  DistanceMap m;
  m.center = t;
  m.n = n;
  m.step = step;
  m.d.assign(std::size_t(n) * n, std::numeric_limits<double>::quiet_NaN());
  const double l0 = std::hypot(t.t0x, t.t0y), l1 = std::hypot(t.t1x, t.t1y);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double s0 = 1.0 + (i - 0.5 * (n - 1)) * step / l0, s1 = 1.0 + (j - 0.5 * (n - 1)) * step / l1;
      const Lattice c{t.t0x * s0, t.t0y * s0, t.t1x * s1, t.t1y * s1};
      try {
        validate_lattice(c, img.width, img.height);
        m.d[std::size_t(j) * n + i] = lattice_distance(img, c, o);
      } catch (const Error&) {
        // left NaN: drawn grey
      }
    }
  return m;
}

namespace {

// A dark-to-bright colour ramp (dark blue, purple, orange, pale yellow) for t in [0, 1].
void ramp(double t, float* rgb) {
  static const double stops[5][3] = {{0.05, 0.03, 0.25}, {0.35, 0.07, 0.5}, {0.75, 0.2, 0.35}, {0.98, 0.55, 0.1}, {0.99, 0.95, 0.6}};
  t = std::clamp(t, 0.0, 1.0) * 4.0;
  const int k = std::min(3, int(t));
  const double f = t - k;
  for (int c = 0; c < 3; ++c) rgb[c] = float(stops[k][c] + f * (stops[k + 1][c] - stops[k][c]));
}

void put(Image& out, int x, int y, float r, float g, float b) {
  if (x < 0 || y < 0 || x >= out.width || y >= out.height) return;
  out.at(x, y, 0) = r;
  out.at(x, y, 1) = g;
  out.at(x, y, 2) = b;
}

// A cross of half-size s at (x, y), drawn over a dark outline so it shows on any exemplar.
void cross(Image& out, double x, double y, int s, float r, float g, float b) {
  const int cx = int(std::floor(x)), cy = int(std::floor(y));
  for (int q = -s - 1; q <= s + 1; ++q)
    for (int o = -1; o <= 1; ++o) {
      put(out, cx + q, cy + o, 0, 0, 0);
      put(out, cx + o, cy + q, 0, 0, 0);
    }
  for (int q = -s; q <= s; ++q) {
    put(out, cx + q, cy, r, g, b);
    put(out, cx, cy + q, r, g, b);
  }
}

void segment(Image& out, double x0, double y0, double x1, double y1, float r, float g, float b) {
  const int steps = int(std::ceil(std::hypot(x1 - x0, y1 - y0))) + 1;
  for (int q = 0; q <= steps; ++q) {
    const double f = double(q) / steps;
    put(out, int(std::floor(x0 + f * (x1 - x0))), int(std::floor(y0 + f * (y1 - y0))), r, g, b);
  }
}

}  // namespace

void write_period_plot(const std::string& path, const Image& ex, const PeriodEstimate& e) {
  const int w = ex.width, h = ex.height, gap = 8;
  const int panel = std::max(h, 128);  // the map's side
  Image out;
  out.width = w + gap + panel;
  out.height = std::max(h, panel);
  out.channels = 3;
  out.pixels.assign(std::size_t(out.width) * out.height * 3, 1.0f);
  // Left: the exemplar (grey as grey), the lattice's nodes anchored at its centre, the basis from there.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = ex.at(x, y, ex.channels >= 3 ? c : 0);
  const Lattice& t = e.periods;
  const double cx = 0.5 * w, cy = 0.5 * h;
  double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
  for (double x : {0.0, double(w)})
    for (double y : {0.0, double(h)}) {
      double a, b;
      lattice_coords(t, x - cx, y - cy, &a, &b);
      amin = std::min(amin, a);
      amax = std::max(amax, a);
      bmin = std::min(bmin, b);
      bmax = std::max(bmax, b);
    }
  const int size = std::clamp(int(std::min(std::hypot(t.t0x, t.t0y), std::hypot(t.t1x, t.t1y)) / 6.0), 2, 6);
  for (long l = long(std::floor(bmin)); l <= long(std::ceil(bmax)); ++l)
    for (long k = long(std::floor(amin)); k <= long(std::ceil(amax)); ++k) {
      const double x = cx + k * t.t0x + l * t.t1x, y = cy + k * t.t0y + l * t.t1y;
      if (x >= 0 && y >= 0 && x < w && y < h) cross(out, x, y, size, 1.0f, 0.15f, 0.1f);
    }
  segment(out, cx, cy, cx + t.t0x, cy + t.t0y, 1.0f, 0.9f, 0.1f);
  segment(out, cx, cy, cx + t.t1x, cy + t.t1y, 0.2f, 0.9f, 1.0f);
  segment(out, cx + t.t0x, cy + t.t0y, cx + t.t0x + t.t1x, cy + t.t0y + t.t1y, 0.2f, 0.9f, 1.0f);
  segment(out, cx + t.t1x, cy + t.t1y, cx + t.t0x + t.t1x, cy + t.t0y + t.t1y, 1.0f, 0.9f, 1.0f);
  // Right: d around the periods, +-range pixels along each vector (S4 Fig. 10), normalised to its own range.
  const int n = 41;
  const double range = std::clamp(0.1 * std::min(std::hypot(t.t0x, t.t0y), std::hypot(t.t1x, t.t1y)), 1.0, 8.0);
  DistanceOptions o;
  o.phases = 10;
  o.max_samples = 24;
  const DistanceMap m = distance_map(ex, t, n, 2.0 * range / (n - 1), o);
  double lo = 1e300, hi = -1e300;
  for (double v : m.d)
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  for (int y = 0; y < panel; ++y)
    for (int x = 0; x < panel; ++x) {
      const int i = std::min(n - 1, x * n / panel), j = std::min(n - 1, y * n / panel);
      const double v = m.d[std::size_t(j) * n + i];
      float rgb[3] = {0.5f, 0.5f, 0.5f};
      if (std::isfinite(v)) ramp(hi > lo ? (v - lo) / (hi - lo) : 0.0, rgb);
      put(out, w + gap + x, y, rgb[0], rgb[1], rgb[2]);
    }
  cross(out, w + gap + 0.5 * panel, 0.5 * panel, 4, 1.0f, 1.0f, 1.0f);
  write_image_atomic(path, out);
}

}  // namespace stex
