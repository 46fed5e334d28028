// Cyclostationary spot noise: validation, setup, reference, Appendix A, renderer. See cs_spot.h and
// kernels/shared/cs.h.
#include "runtime/cs_spot.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "runtime/chunked_gather.h"
#include "runtime/error.h"

namespace stex {

static_assert(sizeof(stex_cs_params) == 112, "stex_cs_params must match the OpenCL layout (112 bytes)");

namespace {

constexpr double k_fix_one = double(std::int64_t(1) << STEX_CS_FIX_BITS);
constexpr double k_pi = 3.14159265358979323846;
constexpr std::size_t k_default_chunk_pixels = std::size_t(1) << 22;

std::string num(double v) {
  std::ostringstream os;
  os.precision(9);
  os << v;
  return os.str();
}

bool same(const RenderParams& a, const RenderParams& b) {
  return a.mni == b.mni && a.cell_factor == b.cell_factor && a.seed == b.seed && a.scale == b.scale;
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

void validate_cs_spot_model(const CsSpotModel& m) {
  auto bad = [](const std::string& what) { throw Error(ErrorKind::Input, "invalid cs-spot model: " + what); };
  if (m.channels < 1 || m.channels > STEX_CS_MAX_CHANNELS) bad("channels must be 1..4, got " + std::to_string(m.channels));
  if (m.width < 2 || m.height < 2 || m.width > k_cs_max_spot || m.height > k_cs_max_spot)
    bad("the spot must be 2..4096 texels on each side, got " + std::to_string(m.width) + "x" + std::to_string(m.height));
  const double p[4] = {m.t0x, m.t0y, m.t1x, m.t1y};
  for (double v : p)
    if (!std::isfinite(v) || std::fabs(v) > 8192.0) bad("period coordinates must be finite and within 8192 pixels");
  const double l0 = std::hypot(m.t0x, m.t0y), l1 = std::hypot(m.t1x, m.t1y);
  const double area = std::fabs(m.t0x * m.t1y - m.t0y * m.t1x);
  if (l0 < 1.0 || l1 < 1.0) bad("each period vector must be at least 1 pixel long");
  if (area < 2.0 || area < std::sin(5.0 * k_pi / 180.0) * l0 * l1)
    bad("the period vectors must span a parallelogram of at least 2 pixels^2, at least 5 degrees apart");
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

CsSpotSetup make_cs_spot_setup(const CsSpotModel& m, const RenderParams& rp) {
  validate_cs_spot_model(m);
  validate_render_params(rp);
  CsSpotSetup out;
  const double fs = k_fix_one * rp.scale;
  out.T0x = std::llround(m.t0x * fs);
  out.T0y = std::llround(m.t0y * fs);
  out.T1x = std::llround(m.t1x * fs);
  out.T1y = std::llround(m.t1y * fs);
  const double det = double(out.T0x) * double(out.T1y) - double(out.T0y) * double(out.T1x);
  const double i00 = double(out.T1y) / det, i01 = -double(out.T1x) / det;
  const double i10 = -double(out.T0y) / det, i11 = double(out.T0x) / det;

  stex_cs_params& p = out.params;
  p.seed_lo = stex_lo32(static_cast<stex_i64>(rp.seed));
  p.seed_hi = stex_hi32(static_cast<stex_i64>(rp.seed));
  p.t0x_lo = stex_lo32(out.T0x);
  p.t0x_hi = stex_hi32(out.T0x);
  p.t0y_lo = stex_lo32(out.T0y);
  p.t0y_hi = stex_hi32(out.T0y);
  p.t1x_lo = stex_lo32(out.T1x);
  p.t1x_hi = stex_hi32(out.T1x);
  p.t1y_lo = stex_lo32(out.T1y);
  p.t1y_hi = stex_hi32(out.T1y);
  p.inv_fix_scale = static_cast<float>(1.0 / fs);
  p.i00 = float(i00);
  p.i01 = float(i01);
  p.i10 = float(i10);
  p.i11 = float(i11);
  // Node window: x lies in the base cell (lattice coordinates in [0, 1), up to float rounding), and the spot's
  // non-zero reads lie in (-1, size + 1) model pixels.
  const double bx0 = -1.0 * fs, by0 = -1.0 * fs, bx1 = (m.width + 1.0) * fs, by1 = (m.height + 1.0) * fs;
  double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
  for (double x : {bx0, bx1})
    for (double y : {by0, by1}) {
      const double a = i00 * x + i01 * y, b = i10 * x + i11 * y;
      amin = std::min(amin, a);
      amax = std::max(amax, a);
      bmin = std::min(bmin, b);
      bmax = std::max(bmax, b);
    }
  p.dk0 = stex_i32(std::floor(-0.01 - amax));
  p.dk1 = stex_i32(std::ceil(1.01 - amin));
  p.dl0 = stex_i32(std::floor(-0.01 - bmax));
  p.dl1 = stex_i32(std::ceil(1.01 - bmin));
  p.spot_w = m.width;
  p.spot_h = m.height;
  p.n0 = m.n0;
  p.n1 = m.n1;
  p.channels = m.channels;
  p.amplitude = float(m.amplitude);
  p.pad0 = p.pad1 = p.pad2 = 0;
  out.gauss = cs_gaussian_table();
  out.reduce = cs_reduce_table(out.T0x, out.T0y, out.T1x, out.T1y);
  out.hist_params = cs_hist_params(m.hist);
  out.hist = cs_hist_device_table(m.hist);
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
  mean_ = Buffer<float>(ctx_, model_.mean, CL_MEM_READ_ONLY, "cs-spot mean");
  gauss_ = Buffer<float>(ctx_, setup_.gauss, CL_MEM_READ_ONLY, "cs-spot gaussian table");
  reduce_ = Buffer<std::uint32_t>(ctx_, setup_.reduce, CL_MEM_READ_ONLY, "cs-spot node table");
  hist_ = Buffer<float>(ctx_, setup_.hist, CL_MEM_READ_ONLY, "cs-spot histogram table");
}

NoiseRenderStats CsSpotNoise::render(const RenderParams& params, std::int64_t x, std::int64_t y, int width, int height,
                                     float* out) {
  validate_region(x, y, width, height);
  if (!same(params, setup_params_)) {
    CsSpotSetup s = make_cs_spot_setup(model_, params);
    if (s.reduce != setup_.reduce)
      reduce_ = Buffer<std::uint32_t>(ctx_, s.reduce, CL_MEM_READ_ONLY, "cs-spot node table");
    setup_ = std::move(s);
    setup_params_ = params;
  }
  if (!kernel_) kernel_ = std::make_unique<Kernel>(ctx_.program("cs_spot.cl"), "cs_spot");
  GatherChunking chunking;
  chunking.max_chunk_pixels = max_chunk_pixels ? max_chunk_pixels : k_default_chunk_pixels;
  if (local_size[0] && local_size[1]) chunking.local = local_size;
  return render_gather_chunks(ctx_, *kernel_, channels(), x, y, width, height, out, chunking,
                              [&](Kernel& k, cl_uint a, std::int64_t x0, std::int64_t y0) {
                                (void)x0;
                                (void)y0;
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

}  // namespace stex
