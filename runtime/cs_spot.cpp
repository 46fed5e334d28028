// Cyclostationary spot noise: validation, setup, reference, Appendix A, renderer. See cs_spot.h and
// kernels/shared/cs.h.
#include "runtime/cs_spot.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/math.h"
#include "runtime/chunked_gather.h"

namespace stex {

static_assert(sizeof(stex_cs_params) == 112, "stex_cs_params must match the OpenCL layout (112 bytes)");

namespace {

constexpr double k_fix_one = double(std::int64_t(1) << STEX_CS_FIX_BITS);

std::string num(double v) {
  std::ostringstream os;
  os.precision(9);
  os << v;
  return os.str();
}


double phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }
double phi_inv(double p) {
  double lo = -40.0, hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (phi(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Bilinear read of the zero-padded spot in double (the theory of Appendix A).
double spot_at(const CsSpotModel& m, double dx, double dy, int c) {
  const double sx = dx - 0.5, sy = dy - 0.5;
  const double fx0 = std::floor(sx), fy0 = std::floor(sy);
  const long i0 = long(fx0), j0 = long(fy0);
  const double fx = sx - fx0, fy = sy - fy0;
  auto tex = [&](long i, long j) -> double {
    if (i < 0 || j < 0 || i >= m.width || j >= m.height) return 0.0;
    return m.spot[(std::size_t(j) * m.width + std::size_t(i)) * m.channels + c];
  };
  const double a = tex(i0, j0) + fx * (tex(i0 + 1, j0) - tex(i0, j0));
  const double b = tex(i0, j0 + 1) + fx * (tex(i0 + 1, j0 + 1) - tex(i0, j0 + 1));
  return a + fy * (b - a);
}

}  // namespace

void validate_model_periods(const std::string& kind, double t0x, double t0y, double t1x, double t1y) {
  auto bad = [&](const std::string& what) { throw Error(ErrorKind::Input, "invalid " + kind + " model: " + what); };
  for (double v : {t0x, t0y, t1x, t1y})
    if (!std::isfinite(v) || std::fabs(v) > 8192.0) bad("period coordinates must be finite and within 8192 pixels");
  const double l0 = std::hypot(t0x, t0y), l1 = std::hypot(t1x, t1y);
  const double area = std::fabs(t0x * t1y - t0y * t1x);
  if (l0 < 1.0 || l1 < 1.0) bad("each period vector must be at least 1 pixel long");
  if (area < 2.0 || area < std::sin(5.0 * k_pi / 180.0) * l0 * l1)
    bad("the period vectors must span a parallelogram of at least 2 pixels^2, at least 5 degrees apart");
}

void validate_cs_spot_model(const CsSpotModel& m) {
  auto bad = [](const std::string& what) { throw Error(ErrorKind::Input, "invalid cs-spot model: " + what); };
  if (m.channels < 1 || m.channels > STEX_CS_MAX_CHANNELS) bad("channels must be 1..4, got " + std::to_string(m.channels));
  if (m.width < 2 || m.height < 2 || m.width > k_cs_max_spot || m.height > k_cs_max_spot)
    bad("the spot must be 2..4096 texels on each side, got " + std::to_string(m.width) + "x" + std::to_string(m.height));
  validate_model_periods("cs-spot", m.t0x, m.t0y, m.t1x, m.t1y);
  const double area = std::fabs(m.t0x * m.t1y - m.t0y * m.t1x);
  if (double(m.width) * m.height / area > k_cs_max_nodes_per_spot)
    bad("the spot covers more than 65536 lattice cells (" + num(double(m.width) * m.height / area) + ")");
  if (m.spot.size() != std::size_t(m.width) * m.height * m.channels) bad("spot size does not match width x height x channels");
  if (m.n0 < 1 || m.n1 < 1 || m.n0 > k_cs_max_spot || m.n1 > k_cs_max_spot)
    bad("the mean grid must be 1..4096 on each side, got " + std::to_string(m.n0) + "x" + std::to_string(m.n1));
  if (m.mean.size() != std::size_t(m.n0) * m.n1 * m.channels) bad("mean grid size does not match n0 x n1 x channels");
  for (float v : m.spot)
    if (!std::isfinite(v) || std::fabs(v) > 1e30f) bad("the spot has a non-finite value");
  for (float v : m.mean)
    if (!std::isfinite(v) || std::fabs(v) > 1e30f) bad("the mean has a non-finite value");
  if (!std::isfinite(m.amplitude) || m.amplitude < 0.0 || m.amplitude > 1e6)
    bad("amplitude must be finite, in [0, 1e6], got " + num(m.amplitude));
  validate_cs_hist(m.hist, m.channels, m.width, m.height, "invalid cs-spot model");
}

namespace {
std::vector<float> make_gaussian_table() {
  constexpr int n = STEX_CS_GAUSS_SEGMENTS;
  std::vector<double> q(n + 1);
  for (int i = 1; i < n; ++i) q[i] = phi_inv(double(i) / n);
  q[0] = phi_inv(0.25 / n);
  q[n] = -q[0];
  for (int i = 1; i < n / 2; ++i) q[n - i] = -q[i];  // exact symmetry: mean 0
  q[n / 2] = 0.0;
  // Variance of the lookup: a segment is uniform over its 2^14 midpoints f, E[f] = 1/2, E[f^2] = 1/3 - 1/(12 M^2).
  const double m2 = 1.0 / 3.0 - 1.0 / (12.0 * 16384.0 * 16384.0);
  auto variance = [&](const std::vector<float>& t) {
    double v = 0.0;
    for (int i = 0; i < n; ++i) {
      const double a = t[i], d = double(t[i + 1]) - t[i];
      v += a * a + a * d + m2 * d * d;
    }
    return v / n;
  };
  std::vector<float> t(n + 1);
  for (int i = 0; i <= n; ++i) t[i] = float(q[i]);
  const double s = 1.0 / std::sqrt(variance(t));
  for (int i = 0; i <= n; ++i) t[i] = float(q[i] * s);
  return t;
}
}  // namespace

std::vector<float> cs_gaussian_table() {
  static const std::vector<float> table = make_gaussian_table();  // ~10 ms of bisections: once per process
  return table;
}

std::vector<std::uint32_t> cs_reduce_table(std::int64_t T0x, std::int64_t T0y, std::int64_t T1x, std::int64_t T1y) {
  const double det = double(T0x) * double(T1y) - double(T0y) * double(T1x);
  const double i00 = double(T1y) / det, i01 = -double(T1x) / det;
  const double i10 = -double(T0y) / det, i11 = double(T0x) / det;
  std::vector<std::uint32_t> t(2 * STEX_CS_REDUCE_BITS * 4, 0u);
  for (int axis = 0; axis < 2; ++axis)
    for (int j = 0; j < STEX_CS_REDUCE_BITS; ++j) {
      const double v = std::ldexp(k_fix_one, j);
      const double a = axis == 0 ? i00 * v : i01 * v, b = axis == 0 ? i10 * v : i11 * v;
      const std::int64_t k = std::llround(a), l = std::llround(b);
      std::uint32_t* e = &t[(std::size_t(axis) * STEX_CS_REDUCE_BITS + j) * 4];
      e[0] = stex_lo32(k);
      e[1] = stex_hi32(k);
      e[2] = stex_lo32(l);
      e[3] = stex_hi32(l);
    }
  return t;
}

namespace {

// The output scale and the inverse of the fixed-point period matrix, shared by the setup's phases.
struct SpotFrame {
  double fs = 0.0;  // fixed units per model pixel
  double i00 = 0.0, i01 = 0.0, i10 = 0.0, i11 = 0.0;
};

// Inverts the fixed-point period matrix of out (T0, T1 as columns).
SpotFrame spot_frame(const CsSpotSetup& out, double fs) {
  SpotFrame f;
  f.fs = fs;
  const double det = double(out.T0x) * double(out.T1y) - double(out.T0y) * double(out.T1x);
  f.i00 = double(out.T1y) / det;
  f.i01 = -double(out.T1x) / det;
  f.i10 = -double(out.T0y) / det;
  f.i11 = double(out.T0x) / det;
  return f;
}

// Fills the seed, the periods and the inverse matrix of the kernel parameters.
void set_lattice_params(stex_cs_params& p, const CsSpotSetup& out, const RenderParams& rp,
                        const SpotFrame& f) {
  set_cs_lattice_words(p, rp.seed, out.T0x, out.T0y, out.T1x, out.T1y, f.fs, float(f.i00), float(f.i01),
                       float(f.i10), float(f.i11));
}

// Sets the node window [dk0, dk1] x [dl0, dl1] of the kernel parameters.
void set_spot_node_window(stex_cs_params& p, const CsSpotModel& m, const SpotFrame& f) {
  const double fs = f.fs;
  // Node window: x lies in the base cell (lattice coordinates in [0, 1), up to float rounding), and the spot's
  // non-zero reads lie in (-1, size + 1) model pixels.
  set_node_window(p, -1.0 * fs, -1.0 * fs, (m.width + 1.0) * fs, (m.height + 1.0) * fs,
                  [&f](double x, double y, double* a, double* b) {
                    *a = f.i00 * x + f.i01 * y;
                    *b = f.i10 * x + f.i11 * y;
                  });
}

// Enables the kernel's fast path (params.canon, the determinant) when the fixed-point bounds below allow it.
void enable_fast_path(CsSpotSetup& out, const SpotFrame& f) {
  stex_cs_params& p = out.params;
  // The fast path: |T| <= 2^28 fixed units (the canonical step's int64 products, the 32-bit residuals of a
  // chunk of <= 4096 pixels a side), and x - u within 32 bits for every node of the window and any x of the
  // base cell; the window widened by the nodes a run of STEX_CS_RUN pixels adds (its extent in cells, plus
  // one) and one node (the last step of the kernel's loop).
  constexpr double k_max_fix = double(std::int64_t(1) << 28);
  const double tmax = std::max({std::fabs(double(out.T0x)), std::fabs(double(out.T0y)), std::fabs(double(out.T1x)),
                                std::fabs(double(out.T1y))});
  const double run_k = std::ceil(STEX_CS_RUN * k_fix_one * std::fabs(f.i00)) + 2.0;
  const double run_l = std::ceil(STEX_CS_RUN * k_fix_one * std::fabs(f.i10)) + 2.0;
  double dmax = 0.0;
  for (double a : {0.0, 1.0})
    for (double b : {0.0, 1.0})
      for (double dk : {double(p.dk0) - run_k, double(p.dk1) + run_k})
        for (double dl : {double(p.dl0) - run_l, double(p.dl1) + run_l})
          dmax = std::max({dmax, std::fabs((a - dk) * double(out.T0x) + (b - dl) * double(out.T1x)),
                           std::fabs((a - dk) * double(out.T0y) + (b - dl) * double(out.T1y))});
  if (tmax <= k_max_fix && dmax < 2147483648.0 - 16777216.0) {
    p.canon = 1;
    const std::int64_t idet = out.T0x * out.T1y - out.T0y * out.T1x;  // |T| <= 2^28: exact
    p.det_lo = stex_lo32(idet);
    p.det_hi = stex_hi32(idet);
  }
}

// Fills out.rows (fast path only): per row dl of the node window, the dk range that can reach the base cell.
void set_row_ranges(CsSpotSetup& out, const CsSpotModel& m, const SpotFrame& f) {
  const stex_cs_params& p = out.params;
  const double fs = f.fs;
  // Per row dl of the window, the dk range of the nodes whose spot can add a non-zero term at a point x of the
  // base cell (exact lattice coordinates in [0, 1)^2: the canonical base). A term is non-zero only if the
  // float displacement d = x - u has a tap of non-zero weight on a texel: d in (-0.5, size + 0.5) on both
  // axes; the float d is within 1e-3 pixel of the exact one (three roundings of relative 2^-24, |d| < 4100), so the
  // box B = [-0.51, w + 0.51] x [-0.51, h + 0.51] holds every such exact d. In lattice coordinates B is the
  // quadrilateral q; row dl needs the a-range [lo, hi] of q over the strip b in [-dl, 1 - dl], and then
  // dk in [ceil(-hi), floor(1 - lo)] (margins 1e-6 cell for the double arithmetic). Nodes outside the rows
  // add exact zeros in stex_cs_spot_eval too, so the sums agree bit for bit.
  const double ex0 = -0.51 * fs, ey0 = -0.51 * fs, ex1 = (m.width + 0.51) * fs, ey1 = (m.height + 0.51) * fs;
  const double qx[4] = {ex0, ex1, ex1, ex0}, qy[4] = {ey0, ey0, ey1, ey1};
  double qa[4], qb[4];
  for (int c = 0; c < 4; ++c) {
    qa[c] = f.i00 * qx[c] + f.i01 * qy[c];
    qb[c] = f.i10 * qx[c] + f.i11 * qy[c];
  }
  for (int dl = p.dl0; dl <= p.dl1; ++dl) {
    const double s0 = -dl - 1e-6, s1 = 1.0 - dl + 1e-6;
    double lo = 1e300, hi = -1e300;
    for (int c = 0; c < 4; ++c) {
      if (qb[c] >= s0 && qb[c] <= s1) {
        lo = std::min(lo, qa[c]);
        hi = std::max(hi, qa[c]);
      }
      const int d = (c + 1) % 4;
      for (double s : {s0, s1})
        if (qb[c] != qb[d] && std::min(qb[c], qb[d]) <= s && s <= std::max(qb[c], qb[d])) {
          const double a = qa[c] + (s - qb[c]) / (qb[d] - qb[c]) * (qa[d] - qa[c]);
          lo = std::min(lo, a);
          hi = std::max(hi, a);
        }
    }
    std::int32_t k0 = 0, k1 = -1;  // empty row
    if (lo <= hi) {
      k0 = std::max(p.dk0, stex_i32(std::ceil(-hi - 1e-6)));
      k1 = std::min(p.dk1, stex_i32(std::floor(1.0 - lo + 1e-6)));
      if (k0 > k1) {
        k0 = 0;
        k1 = -1;
      }
    }
    out.rows.push_back(k0);
    out.rows.push_back(k1);
  }
}

// Halves out.max_chunk_side until the fast path's weight window of a chunk fits k_cs_max_window_nodes.
void limit_chunk_side(CsSpotSetup& out, const SpotFrame& f) {
  const stex_cs_params& p = out.params;
  // Chunk side: the weight window of an S x S chunk spans S (|i00| + |i01|) cells in k (and the same in l)
  // plus the node window and margins.
  const double ka = k_fix_one * (std::fabs(f.i00) + std::fabs(f.i01)),
               la = k_fix_one * (std::fabs(f.i10) + std::fabs(f.i11));
  auto nodes = [&](double side) {
    return (side * ka + (p.dk1 - p.dk0) + 8.0) * (side * la + (p.dl1 - p.dl0) + 8.0);
  };
  while (out.max_chunk_side > 16 && nodes(out.max_chunk_side) > double(k_cs_max_window_nodes))
    out.max_chunk_side /= 2;
}

}  // namespace

CsSpotSetup make_cs_spot_setup(const CsSpotModel& m, const RenderParams& rp) {
  validate_cs_spot_model(m);
  validate_render_params(rp);
  CsSpotSetup out;
  const double fs = k_fix_one * rp.scale;
  out.T0x = std::llround(m.t0x * fs);
  out.T0y = std::llround(m.t0y * fs);
  out.T1x = std::llround(m.t1x * fs);
  out.T1y = std::llround(m.t1y * fs);
  const SpotFrame f = spot_frame(out, fs);

  stex_cs_params& p = out.params;
  set_lattice_params(p, out, rp, f);
  set_spot_node_window(p, m, f);
  p.spot_w = m.width;
  p.spot_h = m.height;
  p.n0 = m.n0;
  p.n1 = m.n1;
  p.channels = m.channels;
  p.amplitude = float(m.amplitude);
  p.det_lo = p.det_hi = 0;
  p.canon = 0;
  enable_fast_path(out, f);
  if (p.canon) {
    set_row_ranges(out, m, f);
    limit_chunk_side(out, f);
  }
  out.gauss = cs_gaussian_table();
  out.reduce = cs_reduce_table(out.T0x, out.T0y, out.T1x, out.T1y);
  out.hist_params = cs_hist_params(m.hist);
  out.hist = cs_hist_device_table(m.hist);
  return out;
}

void cs_spot_canonical(const CsSpotSetup& s, std::int64_t px, std::int64_t py, std::int64_t* k, std::int64_t* l,
                       std::int64_t* rx, std::int64_t* ry) {
  const stex_cs_params& p = s.params;
  const std::int64_t x = stex_cs_pixel_fix(px), y = stex_cs_pixel_fix(py);
  // As stex_cs_spot_eval: the table nodes of the bits, one float solve, the exact floor.
  *k = 0;
  *l = 0;
  stex_cs_reduce_axis(s.reduce.data(), 0, x >> STEX_CS_FIX_BITS, k, l);
  stex_cs_reduce_axis(s.reduce.data(), 1, y >> STEX_CS_FIX_BITS, k, l);
  std::int64_t ax = stex_cs_sub_node(x, *k, s.T0x, *l, s.T1x), ay = stex_cs_sub_node(y, *k, s.T0y, *l, s.T1y);
  const float fa = float(ax) * p.i00 + float(ay) * p.i01, fb = float(ax) * p.i10 + float(ay) * p.i11;
  const std::int64_t ka = std::int64_t(std::floor(fa)), lb = std::int64_t(std::floor(fb));
  *k += ka;
  *l += lb;
  *rx = stex_cs_sub_node(ax, ka, s.T0x, lb, s.T1x);
  *ry = stex_cs_sub_node(ay, ka, s.T0y, lb, s.T1y);
  stex_cs_canon_fix(s.T0x, s.T0y, s.T1x, s.T1y, stex_join64(p.det_lo, p.det_hi), k, l, rx, ry);
}

std::vector<float> cs_padded_spot(const CsSpotModel& m) {
  const std::size_t pw = std::size_t(m.width) + 4, ch = std::size_t(m.channels);
  std::vector<float> out(pw * (std::size_t(m.height) + 4) * ch, 0.0f);
  for (int j = 0; j < m.height; ++j)
    std::copy(m.spot.begin() + std::ptrdiff_t(std::size_t(j) * m.width * ch),
              m.spot.begin() + std::ptrdiff_t(std::size_t(j + 1) * m.width * ch),
              out.begin() + std::ptrdiff_t(((std::size_t(j) + 2) * pw + 2) * ch));
  return out;
}

std::vector<float> CsSpotReference::render(std::int64_t x, std::int64_t y, int width, int height) const {
  validate_region(x, y, width, height);
  const int ch = model_.channels;
  std::vector<float> out(std::size_t(width) * height * ch);
  float v[STEX_CS_MAX_CHANNELS];
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      stex_cs_spot_eval(setup_.params, model_.spot.data(), model_.mean.data(), setup_.gauss.data(), setup_.reduce.data(),
                        setup_.hist_params, setup_.hist.data(), stex_cs_pixel_fix(x + i), stex_cs_pixel_fix(y + j), v);
      for (int c = 0; c < ch; ++c) out[(std::size_t(j) * width + i) * ch + c] = v[c];
    }
  return out;
}

double cs_spot_covariance(const CsSpotModel& m, std::int64_t px, std::int64_t py, int tx, int ty, int c1, int c2) {
  const CsSpotSetup s = make_cs_spot_setup(m, RenderParams{});
  const double inv = 1.0 / k_fix_one;
  const std::int64_t x = stex_cs_pixel_fix(px), y = stex_cs_pixel_fix(py);
  const std::int64_t x2 = stex_cs_pixel_fix(px + tx), y2 = stex_cs_pixel_fix(py + ty);
  const double det = double(s.T0x) * double(s.T1y) - double(s.T0y) * double(s.T1x);
  const double a = (double(s.T1y) * x - double(s.T1x) * y) / det, b = (-double(s.T0y) * x + double(s.T0x) * y) / det;
  const long reach = long(std::ceil((m.width + m.height + 4.0) * k_fix_one / std::min(std::fabs(det) / std::hypot(double(s.T0x), double(s.T0y)),
                                                                              std::fabs(det) / std::hypot(double(s.T1x), double(s.T1y)))));
  double acc = 0.0;
  for (long l = long(std::floor(b)) - reach; l <= long(std::floor(b)) + reach; ++l)
    for (long k = long(std::floor(a)) - reach; k <= long(std::floor(a)) + reach; ++k) {
      const std::int64_t ux = k * s.T0x + l * s.T1x, uy = k * s.T0y + l * s.T1y;
      const double s1 = spot_at(m, double(x - ux) * inv, double(y - uy) * inv, c1);
      if (s1 == 0.0) continue;
      acc += s1 * spot_at(m, double(x2 - ux) * inv, double(y2 - uy) * inv, c2);
    }
  return m.amplitude * m.amplitude * acc;
}

double cs_spot_mean(const CsSpotModel& m, std::int64_t px, std::int64_t py, int c) {
  const double x = px + 0.5, y = py + 0.5;
  const double det = m.t0x * m.t1y - m.t0y * m.t1x;
  double a = (m.t1y * x - m.t1x * y) / det, b = (-m.t0y * x + m.t0x * y) / det;
  a -= std::floor(a);
  b -= std::floor(b);
  const double gx = a * m.n0, gy = b * m.n1;
  const double fx0 = std::floor(gx), fy0 = std::floor(gy);
  const int i0 = int(long(fx0) % m.n0), j0 = int(long(fy0) % m.n1);
  const int i1 = (i0 + 1) % m.n0, j1 = (j0 + 1) % m.n1;
  const double fx = gx - fx0, fy = gy - fy0;
  auto g = [&](int i, int j) { return double(m.mean[(std::size_t(j) * m.n0 + i) * m.channels + c]); };
  const double top = g(i0, j0) + fx * (g(i1, j0) - g(i0, j0));
  const double bot = g(i0, j1) + fx * (g(i1, j1) - g(i0, j1));
  return top + fy * (bot - top);
}

CsSpotNoise::CsSpotNoise(Context& ctx, const CsSpotModel& model, const NoiseRendererOptions& options)
    : ctx_(ctx), model_(model), setup_(make_cs_spot_setup(model, RenderParams{})) {
  if (options.strategy != "auto" && options.strategy != "gather")
    throw Error(ErrorKind::Usage, "unknown strategy '" + options.strategy + "' for cs-spot noise (expected auto or gather)");
  spot_ = Buffer<float>(ctx_, model_.spot, CL_MEM_READ_ONLY, "cs-spot spot");
  spot_pad_ = Buffer<float>(ctx_, cs_padded_spot(model_), CL_MEM_READ_ONLY, "cs-spot padded spot");
  mean_ = Buffer<float>(ctx_, model_.mean, CL_MEM_READ_ONLY, "cs-spot mean");
  gauss_ = Buffer<float>(ctx_, setup_.gauss, CL_MEM_READ_ONLY, "cs-spot gaussian table");
  reduce_ = Buffer<std::uint32_t>(ctx_, setup_.reduce, CL_MEM_READ_ONLY, "cs-spot node table");
  hist_ = Buffer<float>(ctx_, setup_.hist, CL_MEM_READ_ONLY, "cs-spot histogram table");
  if (!setup_.rows.empty()) rows_ = Buffer<std::int32_t>(ctx_, setup_.rows, CL_MEM_READ_ONLY, "cs-spot node rows");
}

NoiseRenderStats CsSpotNoise::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                                     float* out) {
  validate_region(x, y, width, height);
  if (params != setup_params_) {
    CsSpotSetup s = make_cs_spot_setup(model_, params);
    if (s.reduce != setup_.reduce)
      reduce_ = Buffer<std::uint32_t>(ctx_, s.reduce, CL_MEM_READ_ONLY, "cs-spot node table");
    if (!s.rows.empty() && s.rows != setup_.rows)
      rows_ = Buffer<std::int32_t>(ctx_, s.rows, CL_MEM_READ_ONLY, "cs-spot node rows");
    setup_ = std::move(s);
    setup_params_ = params;
  }
  if (!kernel_) {
    // Channels are a compile-time constant of the fast pixel kernel (its loops unroll).
    Program& program = ctx_.program("cs_spot.cl", "-DSTEX_CS_CH=" + std::to_string(model_.channels));
    kernel_ = std::make_unique<Kernel>(program, "cs_spot");
    weights_kernel_ = std::make_unique<Kernel>(program, "cs_spot_weights");
    general_kernel_ = std::make_unique<Kernel>(program, "cs_spot_general");
  }
  GatherChunking chunking;
  chunking.max_chunk_pixels = max_chunk_pixels ? max_chunk_pixels : default_chunk_pixels(channels());
  if (local_size[0] && local_size[1]) chunking.local = local_size;
  if (!setup_.params.canon) {
    return render_gather_chunks(ctx_, *general_kernel_, channels(), x, y, width, height, out, chunking,
                                [&](Kernel& k, cl_uint a, std::int64_t, std::int64_t) {
                                  k.set_arg(a++, setup_.params);
                                  k.set_arg(a++, spot_);
                                  k.set_arg(a++, mean_);
                                  k.set_arg(a++, gauss_);
                                  k.set_arg(a++, reduce_);
                                  k.set_arg(a++, setup_.hist_params);
                                  k.set_arg(a++, hist_);
                                  return a;
                                });
  }
  // Fast path. Chunks at most 4096 pixels a side (the 32-bit residuals from the chunk's first pixel's
  // canonical node stay below 2^30 fixed units), smaller when the weight window would pass its bound.
  chunking.max_side = setup_.max_chunk_side;
  chunking.pixels_per_item_x = STEX_CS_RUN;
  const stex_cs_params& p = setup_.params;
  std::int64_t nk_node = 0, nl_node = 0, res[2] = {0, 0};
  int wk0 = 0, wl0 = 0, nk = 0, nl = 0;
  chunking.before_chunk = [&](std::int64_t x0, std::int64_t y0, int w, int h) -> double {
    cs_spot_canonical(setup_, x0, y0, &nk_node, &nl_node, &res[0], &res[1]);
    // The node offsets of the chunk's pixels: the lattice coordinates of its corners' residuals (a row's last
    // run may reach STEX_CS_RUN - 1 pixels past the chunk).
    const double det = double(setup_.T0x) * double(setup_.T1y) - double(setup_.T0y) * double(setup_.T1x);
    double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
    for (int cj : {0, h - 1})
      for (int ci : {0, w - 1 + STEX_CS_RUN - 1}) {
        const double ax = double(res[0]) + double(ci) * k_fix_one, ay = double(res[1]) + double(cj) * k_fix_one;
        const double a = (double(setup_.T1y) * ax - double(setup_.T1x) * ay) / det;
        const double b = (double(setup_.T0x) * ay - double(setup_.T0y) * ax) / det;
        amin = std::min(amin, a);
        amax = std::max(amax, a);
        bmin = std::min(bmin, b);
        bmax = std::max(bmax, b);
      }
    // Margins of 2 cells (rounding), then the node window of a pixel.
    wk0 = int(std::floor(amin)) - 2 + p.dk0;
    wl0 = int(std::floor(bmin)) - 2 + p.dl0;
    nk = int(std::floor(amax)) + 2 + p.dk1 - wk0 + 1;
    nl = int(std::floor(bmax)) + 2 + p.dl1 - wl0 + 1;
    const std::size_t need = std::size_t(nk) * std::size_t(nl);
    weights_.reserve(ctx_, need, CL_MEM_READ_WRITE, "cs-spot node weights");
    Kernel& wk = *weights_kernel_;
    cl_uint a = 0;
    wk.set_arg(a++, setup_.params);
    wk.set_arg(a++, gauss_);
    wk.set_arg(a++, cl_long(nk_node + wk0));
    wk.set_arg(a++, cl_long(nl_node + wl0));
    wk.set_arg(a++, cl_int(nk));
    wk.set_arg(a++, cl_int(nl));
    wk.set_arg(a++, weights_);
    return wk.launch(ctx_, NDRange(std::size_t(nk), std::size_t(nl)));
  };
  return render_gather_chunks(ctx_, *kernel_, channels(), x, y, width, height, out, chunking,
                              [&](Kernel& k, cl_uint a, std::int64_t, std::int64_t) {
                                k.set_arg(a++, setup_.params);
                                k.set_arg(a++, spot_pad_);
                                k.set_arg(a++, mean_);
                                k.set_arg(a++, weights_);
                                k.set_arg(a++, rows_);
                                k.set_arg(a++, cl_int(nk));
                                k.set_arg(a++, cl_int(nl));
                                k.set_arg(a++, cl_int(wk0));
                                k.set_arg(a++, cl_int(wl0));
                                k.set_arg(a++, cl_int(res[0]));
                                k.set_arg(a++, cl_int(res[1]));
                                k.set_arg(a++, setup_.hist_params);
                                k.set_arg(a++, hist_);
                                return a;
                              });
}

}  // namespace stex
