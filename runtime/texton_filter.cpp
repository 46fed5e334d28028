// On-the-fly filtering of texton noise (S1 §5). See texton_filter.h and kernels/shared/texton_filter.h.
#include "runtime/texton_filter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "core/error.h"
#include "runtime/loop_watchdog.h"

namespace stex {

static_assert(sizeof(stex_footprint) == 48, "stex_footprint must match the OpenCL layout (48 bytes)");
static_assert(sizeof(stex_mip_params) == 8 + 8 * STEX_MIP_MAX_LEVELS, "stex_mip_params layout");

namespace {

constexpr double k_fix_one = double(std::int64_t(1) << STEX_FIX_BITS);
// Plane positions beyond this many texels from the origin are sky (fixed units stay far inside int64).
constexpr double k_max_plane = 1099511627776.0;  // 2^40

[[noreturn]] void usage(const std::string& m) { throw Error(ErrorKind::Usage, m); }

std::int64_t reach_fixed(double texels, double fix_per_texel) {
  return static_cast<std::int64_t>(std::ceil(texels * fix_per_texel * (1.0 + 1.0 / 1048576.0))) + 2;
}

}  // namespace

MipPyramid make_mip_pyramid(const TextonModel& model) {
  validate_texton_model(model);
  if (model.order != 1)
    usage("filtering (S1 §5) needs a bilinear texton (order 1); this model has order " + std::to_string(model.order));
  MipPyramid out;
  const int s = model.support, nc = model.channels;
  std::vector<int> sizes{s};
  while (sizes.back() > 1) sizes.push_back((sizes.back() + 1) / 2);
  if (int(sizes.size()) > STEX_MIP_MAX_LEVELS) usage("texton support too large for the MIP pyramid");
  stex_mip_params& m = out.params;
  m.levels = int(sizes.size());
  m.pad0 = 0;
  std::size_t total = 0;
  for (int l = 0; l < STEX_MIP_MAX_LEVELS; ++l) {
    m.size[l] = l < m.levels ? sizes[std::size_t(l)] : 0;
    m.offset[l] = l < m.levels ? int(total) : 0;
    if (l < m.levels) total += std::size_t(nc) * std::size_t(sizes[std::size_t(l)] + 2) * std::size_t(sizes[std::size_t(l)] + 2);
  }
  out.data.assign(total + 8, 0.0f);
  for (int l = 0; l < m.levels; ++l) {
    const int sl = m.size[l], stride = sl + 2, block = 1 << l;
    const double inv_area = 1.0 / (double(block) * double(block));
    for (int c = 0; c < nc; ++c) {
      float* plane = out.data.data() + m.offset[l] + std::size_t(c) * stride * stride;
      for (int ky = 0; ky < sl; ++ky)
        for (int kx = 0; kx < sl; ++kx) {
          // Mean of the 2^l x 2^l block of alpha (zeros beyond the support): the repeated 2 x 2 average.
          double sum = 0.0;
          for (int y = ky * block; y < std::min(s, (ky + 1) * block); ++y)
            for (int x = kx * block; x < std::min(s, (kx + 1) * block); ++x) sum += double(model.alpha_at(c, y, x));
          plane[std::size_t(ky + 1) * stride + std::size_t(kx + 1)] = static_cast<float>(sum * inv_area);
        }
    }
  }
  return out;
}

stex_footprint make_footprint(int levels, double jxx, double jxy, double jyx, double jyy, double fix_per_texel) {
  stex_footprint f{};
  f.level = 0;
  f.probes = 1;
  f.blend = 0.0f;
  f.inv_probes = 1.0f;
  f.step_x = f.step_y = 0.0f;
  f.start = 0.0f;
  f.gain = 1.0f;
  const double la2 = jxx * jxx + jyx * jyx, lb2 = jxy * jxy + jyy * jyy;
  const bool a_major = la2 >= lb2;
  const double lmaj = std::sqrt(a_major ? la2 : lb2), lmin = std::sqrt(a_major ? lb2 : la2);
  const double mx = a_major ? jxx : jxy, my = a_major ? jyx : jyy;
  double extra = 1.0;
  if (lmaj > 1.0) {
    // Probes: enough that each covers at most the minor axis (and at most one texel apart when the minor
    // axis is below a texel), capped by k_max_aniso.
    const int n = int(std::min<double>(k_max_aniso, std::ceil(lmaj / std::max(lmin, 1.0) - 1e-9)));
    double per_probe = lmaj / n;
    double lod = per_probe > 1.0 ? std::log2(per_probe) : 0.0;
    const int top = levels - 1;
    if (lod >= top) {
      // Beyond the pyramid (a probe wider than the whole texton): the probes read the top level 2^top apart
      // and the fluctuation is scaled by 2^top / per_probe - the standard deviation of a box average over a
      // region much wider than the correlation length falls as 1 / its side. This bounds the work per pixel
      // (the reach stays below (n + 4) 2^top texels) near a horizon.
      const double cap = std::ldexp(1.0, top);
      f.gain = static_cast<float>(std::min(1.0, cap / per_probe));
      per_probe = std::min(per_probe, cap);
      lod = top;
    }
    f.level = std::min(top, int(std::floor(lod)));
    f.blend = f.level >= top ? 0.0f : static_cast<float>(lod - f.level);
    if (f.blend >= 1.0f) f.blend = 0.99999994f;
    f.probes = n;
    f.inv_probes = static_cast<float>(1.0 / n);
    f.step_x = static_cast<float>(mx / lmaj * per_probe);
    f.step_y = static_cast<float>(my / lmaj * per_probe);
    f.start = static_cast<float>(0.5 * (1 - n));
    // The filtered texton reaches 2^(l+1) texels beyond h's support at level l (texton_filter.h), the
    // probes (n - 1)/2 steps.
    const int used = f.blend > 0.0f ? f.level + 1 : f.level;
    extra += std::ldexp(1.0, used + 1) + 0.5 * (n - 1) * per_probe;
  }
  const std::int64_t r = f.level == 0 && f.probes == 1 ? 0 : reach_fixed(extra, fix_per_texel);
  f.reach_lo = stex_lo32(r);
  f.reach_hi = stex_hi32(r);
  f.pad0 = f.pad1 = 0;
  return f;
}

namespace {

// The antiderivative of the centred B-spline of degree n (0, 1, 3, 5; S1 §10), B(x) = int_{-inf}^x beta_n:
// B(x) = 1/(n+1)! sum_{k=0}^{n+1} (-1)^k C(n+1, k) (x + (n+1)/2 - k)_+^(n+1), 0 below the support, 1 above.
double bspline_integral(int n, double x) {
  const double half = 0.5 * (n + 1);
  if (x <= -half) return 0.0;
  if (x >= half) return 1.0;
  double sum = 0.0, binom = 1.0, fact = 1.0;
  for (int k = 1; k <= n + 1; ++k) fact *= k;
  for (int k = 0; k <= n + 1; ++k) {
    const double t = x + half - k;
    if (t > 0.0) sum += (k % 2 ? -binom : binom) * std::pow(t, n + 1);
    binom = binom * (n + 1 - k) / (k + 1);
  }
  return sum / fact;
}

}  // namespace

BoxPrefilter make_box_prefilter(const TextonModel& model, double scale) {
  validate_texton_model(model);
  if (!(scale > 0.0 && scale < 1.0)) usage("the box prefilter applies to minified views (0 < scale < 1)");
  const int n = model.order, s = model.support, nc = model.channels;
  const double w = 1.0 / scale;   // the pixel's box, texels per side
  const double half = 0.5 * (n + 1);  // psi's half support
  // The table starts `shift` whole output pixels before h_w's support, so that its first sample sits at
  // texton coordinate -shift / scale (exact in the fixed-point displacement).
  const std::int64_t shift = std::int64_t(std::ceil((half + 0.5 * w) * scale - 1e-12));
  const double origin = -double(shift) * w;
  const double end = double(s - 1) + half + 0.5 * w;  // h_w vanishes beyond
  const double range = end - origin;
  // Spacing: half a texel, coarser (a power of two) where the table would pass 512 samples per axis; h_w is
  // then at least 256 texels wide and smooth on the scale of the spacing.
  const double q = std::max(0.5, std::exp2(std::ceil(std::log2(range / 512.0))));
  const int size = int(std::ceil(range / q)) + 1;
  if (size > k_max_texton_support) usage("the box-prefiltered texton would exceed the largest texton support");
  // Phi(x) = (psi * box_w)(x) = (B(x + w/2) - B(x - w/2)) / w at sample m, coefficient k: x = origin + m q - k.
  std::vector<double> phi(std::size_t(size) * s);
  for (int m = 0; m < size; ++m)
    for (int k = 0; k < s; ++k) {
      const double x = origin + m * q - k;
      phi[std::size_t(m) * s + k] = (bspline_integral(n, x + 0.5 * w) - bspline_integral(n, x - 0.5 * w)) / w;
    }
  BoxPrefilter out;
  out.texton.channels = nc;
  out.texton.support = size;
  out.texton.order = 1;
  out.texton.mean = model.mean;
  out.texton.alpha.assign(std::size_t(nc) * size * size, 0.0f);
  std::vector<double> rows(std::size_t(s) * size);  // alpha filtered along x: rows[ky][mx]
  for (int c = 0; c < nc; ++c) {
    for (int ky = 0; ky < s; ++ky)
      for (int mx = 0; mx < size; ++mx) {
        double v = 0.0;
        for (int kx = 0; kx < s; ++kx) v += double(model.alpha_at(c, ky, kx)) * phi[std::size_t(mx) * s + kx];
        rows[std::size_t(ky) * size + mx] = v;
      }
    double sum = 0.0;
    for (int my = 0; my < size; ++my)
      for (int mx = 0; mx < size; ++mx) {
        double v = 0.0;
        for (int ky = 0; ky < s; ++ky) v += phi[std::size_t(my) * s + ky] * rows[std::size_t(ky) * size + mx];
        const float f = static_cast<float>(v);
        out.texton.alpha[(std::size_t(c) * size + my) * size + mx] = f;
        sum += double(f);
      }
    out.integral[std::size_t(c)] = sum * q * q;  // the integral of the bilinear interpolant of the samples
  }
  out.spacing = q;
  out.shift = shift;
  out.origin = origin;
  return out;
}

TextonSetup prefiltered_setup(const TextonSetup& base, const BoxPrefilter& pre, double scale) {
  // The table as a bilinear texton: support `size`, its texel q exemplar pixels (inv_fix_scale / q: exact, q a
  // power of two), its first sample at displacement 0 of a pixel evaluated `shift` whole output pixels further
  // (TextonSetup::pixel_shift); base's grid, lambda, Poisson table and seed: the same impulses.
  const TextonSetup t = make_texton_setup(pre.texton, RenderParams{});
  TextonSetup out = base;
  stex_texton_params& p = out.params;
  p.support = pre.texton.support;
  p.order = 1;
  p.stride = t.params.stride;
  p.frame = t.params.frame;
  p.t_lo = t.params.t_lo;
  p.t_hi = t.params.t_hi;
  p.inv_fix_scale = static_cast<float>(double(base.params.inv_fix_scale) / pre.spacing);
  // Displacements D = X(P') - X_j of the shifted pixel P' = P + shift lie in [t_lo q, t_hi q) texels.
  const std::int64_t back = reach_fixed(double(p.t_hi) * pre.spacing, k_fix_one * scale);
  const std::int64_t fwd = reach_fixed(-double(p.t_lo) * pre.spacing, k_fix_one * scale);
  p.reach_back_lo = stex_lo32(back);
  p.reach_back_hi = stex_hi32(back);
  p.reach_fwd_lo = stex_lo32(fwd);
  p.reach_fwd_hi = stex_hi32(fwd);
  out.reach_back = back;
  out.reach_fwd = fwd;
  for (int c = 0; c < STEX_MAX_CHANNELS; ++c)
    p.lambda_sum_alpha[c] = c < base.channels ? static_cast<float>(base.lambda * pre.integral[std::size_t(c)]) : 0.0f;
  out.alpha_padded = t.alpha_padded;
  out.pixel_shift = pre.shift;
  return out;
}

TextonSetup make_filtered_texton_setup(const TextonModel& model, const RenderParams& params) {
  const TextonSetup base = make_texton_setup(model, params);
  if (!texton_prefilters(params)) return base;
  return prefiltered_setup(base, make_box_prefilter(model, params.scale), params.scale);
}

PerspectiveCamera parse_camera(const std::string& spec, std::int64_t image_width, std::int64_t image_height) {
  PerspectiveCamera cam;
  std::istringstream is(spec);
  char c1 = 0, c2 = 0;
  if (!(is >> cam.height >> c1 >> cam.tilt >> c2 >> cam.fov) || c1 != ',' || c2 != ',' || !is.eof())
    usage("--camera must be HEIGHT,TILT,FOV (e.g. 200,70,60), got '" + spec + "'");
  if (!std::isfinite(cam.height) || cam.height <= 0.0 || cam.height > 1e9)
    usage("--camera height must be in (0, 1e9] exemplar pixels, got " + std::to_string(cam.height));
  if (!std::isfinite(cam.tilt) || cam.tilt < 0.0 || cam.tilt > 89.0)
    usage("--camera tilt must be in [0, 89] degrees, got " + std::to_string(cam.tilt));
  if (!std::isfinite(cam.fov) || cam.fov <= 0.0 || cam.fov >= 170.0)
    usage("--camera field of view must be in (0, 170) degrees, got " + std::to_string(cam.fov));
  if (image_width < 1 || image_height < 1) usage("--camera needs an image size of at least 1x1");
  cam.image_width = image_width;
  cam.image_height = image_height;
  return cam;
}

bool camera_point(const PerspectiveCamera& cam, double px, double py, double* u, double* v) {
  const double tau = cam.tilt * M_PI / 180.0;
  const double ct = std::cos(tau), st = std::sin(tau);
  const double f = 0.5 * double(cam.image_height) / std::tan(0.5 * cam.fov * M_PI / 180.0);
  const double sx = (px - 0.5 * double(cam.image_width)) / f;
  const double sy = (py - 0.5 * double(cam.image_height)) / f;
  const double gx = sx, gy = st - sy * ct;
  const double q = ct + sy * st;
  if (!(q > 1e-9)) return false;
  const double t = cam.height / q;
  *u = t * gx;
  *v = t * gy;
  return std::fabs(*u) < k_max_plane && std::fabs(*v) < k_max_plane;
}

bool camera_map(const PerspectiveCamera& cam, std::int64_t i, std::int64_t j, double* u, double* v, double jac[4]) {
  const double tau = cam.tilt * M_PI / 180.0;
  const double ct = std::cos(tau), st = std::sin(tau);
  const double f = 0.5 * double(cam.image_height) / std::tan(0.5 * cam.fov * M_PI / 180.0);
  // The same arithmetic as camera_point(i + 0.5, j + 0.5).
  const double sx = (double(i) + 0.5 - 0.5 * double(cam.image_width)) / f;
  const double sy = (double(j) + 0.5 - 0.5 * double(cam.image_height)) / f;
  // Ray direction d + sx r - sy up: d = (0, sin, -cos), r = (1, 0, 0), up = (0, cos, sin).
  const double gx = sx, gy = st - sy * ct;
  const double q = ct + sy * st;  // -dz
  if (!(q > 1e-9)) return false;
  const double t = cam.height / q;
  *u = t * gx;
  *v = t * gy;
  if (!(std::fabs(*u) < k_max_plane && std::fabs(*v) < k_max_plane)) return false;
  // p = H g / q: dp/di = H (dg/di) / q (dq/di = 0); dp/dj = H (dg/dj q - g dq/dj) / q^2.
  const double dgx_di = 1.0 / f, dgy_dj = -ct / f, dq_dj = st / f;
  jac[0] = cam.height * dgx_di / q;                              // du/di
  jac[1] = cam.height * (0.0 * q - gx * dq_dj) / (q * q);        // du/dj
  jac[2] = 0.0;                                                  // dv/di
  jac[3] = cam.height * (dgy_dj * q - gy * dq_dj) / (q * q);     // dv/dj
  return true;
}

void camera_footprints(const PerspectiveCamera& cam, int levels, std::int64_t x, std::int64_t y, int w, int h,
                       std::vector<std::int64_t>* pos, std::vector<stex_footprint>* fp, bool filter) {
  validate_region(x, y, w, h);
  const std::size_t n = std::size_t(w) * std::size_t(h);
  pos->assign(2 * n, 0);
  fp->assign(n, stex_footprint{});
  for (int jj = 0; jj < h; ++jj)
    for (int ii = 0; ii < w; ++ii) {
      const std::size_t k = std::size_t(jj) * std::size_t(w) + std::size_t(ii);
      double u, v, jac[4];
      if (!camera_map(cam, x + ii, y + jj, &u, &v, jac)) continue;  // probes = 0: sky
      (*pos)[2 * k] = std::llround(u * k_fix_one);
      (*pos)[2 * k + 1] = std::llround(v * k_fix_one);
      (*fp)[k] = filter ? make_footprint(levels, jac[0], jac[1], jac[2], jac[3], k_fix_one)
                        : make_footprint(levels, 1.0, 0.0, 0.0, 1.0, k_fix_one);
    }
}

void validate_uv_map(const UvMap& map, const std::string& what) {
  if (map.width < 2 || map.height < 2)
    throw Error(ErrorKind::Input, what + " is " + std::to_string(map.width) + "x" + std::to_string(map.height) +
                                      " pixels: it needs at least 2x2 (the UV Jacobian comes from neighbouring pixels)");
  if (map.uv.size() != 2 * std::size_t(map.width) * std::size_t(map.height))
    throw Error(ErrorKind::Input, what + " holds " + std::to_string(map.uv.size()) + " values, expected 2 x " +
                                      std::to_string(map.width) + " x " + std::to_string(map.height));
  for (std::size_t k = 0; k < map.uv.size(); ++k) {
    const double v = map.uv[k];
    if (!std::isfinite(v) || std::fabs(v) >= k_max_plane) {
      const std::size_t px = k / 2;
      std::ostringstream os;
      os << what << ": pixel (" << px % std::size_t(map.width) << ", " << px / std::size_t(map.width) << ") "
         << (k % 2 ? "v" : "u") << " = " << v
         << (std::isfinite(v) ? " is beyond 2^40 exemplar pixels" : " is not finite (NaN or Inf)");
      throw Error(ErrorKind::Input, os.str());
    }
  }
}

void uv_map_jacobian(const UvMap& map, int i, int j, double jac[4]) {
  const auto at = [&](int x, int y, int c) {
    return map.uv[2 * (std::size_t(y) * std::size_t(map.width) + std::size_t(x)) + std::size_t(c)];
  };
  // Central differences inside, one-sided on the border.
  const int i0 = std::max(0, i - 1), i1 = std::min(map.width - 1, i + 1);
  const int j0 = std::max(0, j - 1), j1 = std::min(map.height - 1, j + 1);
  const double di = double(i1 - i0), dj = double(j1 - j0);
  jac[0] = (at(i1, j, 0) - at(i0, j, 0)) / di;  // du/di
  jac[1] = (at(i, j1, 0) - at(i, j0, 0)) / dj;  // du/dj
  jac[2] = (at(i1, j, 1) - at(i0, j, 1)) / di;  // dv/di
  jac[3] = (at(i, j1, 1) - at(i, j0, 1)) / dj;  // dv/dj
}

void uv_map_footprints(const UvMap& map, int levels, int y, int h, std::vector<std::int64_t>* pos,
                       std::vector<stex_footprint>* fp, bool filter) {
  if (y < 0 || h < 0 || y + h > map.height) usage("uv_map_footprints: rows outside the map");
  const std::size_t n = std::size_t(map.width) * std::size_t(h);
  pos->assign(2 * n, 0);
  fp->assign(n, stex_footprint{});
  for (int jj = 0; jj < h; ++jj)
    for (int ii = 0; ii < map.width; ++ii) {
      const std::size_t k = std::size_t(jj) * std::size_t(map.width) + std::size_t(ii);
      const std::size_t m = 2 * (std::size_t(y + jj) * std::size_t(map.width) + std::size_t(ii));
      (*pos)[2 * k] = std::llround(map.uv[m] * k_fix_one);
      (*pos)[2 * k + 1] = std::llround(map.uv[m + 1] * k_fix_one);
      double jac[4];
      uv_map_jacobian(map, ii, y + jj, jac);
      (*fp)[k] = filter ? make_footprint(levels, jac[0], jac[1], jac[2], jac[3], k_fix_one)
                        : make_footprint(levels, 1.0, 0.0, 0.0, 1.0, k_fix_one);
    }
}

// ---- reference ----

FilteredTextonReference::FilteredTextonReference(const TextonModel& model, const RenderParams& params)
    : setup_(make_texton_setup(model, params)), order_(model.order) {
  if (model.order == 1) pyramid_ = make_mip_pyramid(model);
  if (params.scale < 1.0) {  // the box prefilter, any order
    RenderParams p = params;
    p.filter = true;
    minified_ = std::make_unique<TextonReference>(make_filtered_texton_setup(model, p));
  } else {  // magnified: level 0, one probe (the unfiltered tap; order 1 only)
    need_pyramid();
    scaled_ = make_footprint(pyramid_.params.levels, 1.0 / params.scale, 0.0, 0.0, 1.0 / params.scale,
                             k_fix_one * params.scale);
  }
}

void FilteredTextonReference::need_pyramid() const {
  if (order_ != 1)
    usage("filtering (S1 §5) needs a bilinear texton (order 1); this model has order " + std::to_string(order_));
}

std::vector<float> FilteredTextonReference::render_scaled(std::int64_t x, std::int64_t y, int width,
                                                          int height) const {
  validate_region(x, y, width, height);
  if (minified_) return minified_->render(x, y, width, height);
  const int nc = setup_.channels;
  std::vector<float> out(std::size_t(width) * std::size_t(height) * std::size_t(nc));
  float v[STEX_MAX_CHANNELS];
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      stex_texton_eval_filtered(setup_.params, pyramid_.params, pyramid_.data.data(), setup_.poisson_table.data(),
                                scaled_, stex_pixel_fix(x + i), stex_pixel_fix(y + j), v);
      for (int c = 0; c < nc; ++c) out[(std::size_t(j) * std::size_t(width) + std::size_t(i)) * nc + c] = v[c];
    }
  return out;
}

std::vector<float> FilteredTextonReference::render_camera(const PerspectiveCamera& cam, std::int64_t x,
                                                          std::int64_t y, int width, int height) const {
  if (setup_.params.inv_fix_scale != static_cast<float>(1.0 / k_fix_one))
    usage("camera renders need a setup at scale 1 (plane units are texels)");
  need_pyramid();
  std::vector<std::int64_t> pos;
  std::vector<stex_footprint> fp;
  camera_footprints(cam, pyramid_.params.levels, x, y, width, height, &pos, &fp);
  const int nc = setup_.channels;
  std::vector<float> out(std::size_t(width) * std::size_t(height) * std::size_t(nc));
  float v[STEX_MAX_CHANNELS];
  for (std::size_t k = 0; k < fp.size(); ++k) {
    if (fp[k].probes > 0) {
      stex_texton_eval_filtered(setup_.params, pyramid_.params, pyramid_.data.data(), setup_.poisson_table.data(),
                                fp[k], pos[2 * k], pos[2 * k + 1], v);
    } else {
      for (int c = 0; c < nc; ++c) v[c] = setup_.params.mean[c];
    }
    for (int c = 0; c < nc; ++c) out[k * nc + c] = v[c];
  }
  return out;
}

std::vector<float> FilteredTextonReference::render_uv_map(const UvMap& map) const {
  need_pyramid();
  if (setup_.params.inv_fix_scale != static_cast<float>(1.0 / k_fix_one))
    usage("UV map renders need a setup at scale 1 (plane units are texels)");
  validate_uv_map(map);
  std::vector<std::int64_t> pos;
  std::vector<stex_footprint> fp;
  uv_map_footprints(map, pyramid_.params.levels, 0, map.height, &pos, &fp);
  const int nc = setup_.channels;
  std::vector<float> out(fp.size() * std::size_t(nc));
  float v[STEX_MAX_CHANNELS];
  for (std::size_t k = 0; k < fp.size(); ++k) {
    stex_texton_eval_filtered(setup_.params, pyramid_.params, pyramid_.data.data(), setup_.poisson_table.data(),
                              fp[k], pos[2 * k], pos[2 * k + 1], v);
    for (int c = 0; c < nc; ++c) out[k * nc + c] = v[c];
  }
  return out;
}

// ---- device ----

FilteredTextonRenderer::FilteredTextonRenderer(Context& ctx, const TextonModel& model)
    : ctx_(ctx), model_(model) {
  validate_texton_model(model);
  if (model.order == 1) {  // S1 §5's MIP pyramid: cameras, UV maps and magnified views
    pyramid_ = make_mip_pyramid(model);
    pyr_ = Buffer<float>(ctx_, pyramid_.data, CL_MEM_READ_ONLY, "texton MIP pyramid");
  }
}

namespace {

constexpr std::size_t k_default_rows_pixels = std::size_t(1) << 20;

// Planar (w x h per channel) -> interleaved rows [row0, row0 + h) of an image of width w.
void deinterleave_into(const std::vector<float>& planar, int w, int h, int nc, float* dst) {
  const std::size_t plane = std::size_t(w) * std::size_t(h);
  for (std::size_t k = 0; k < plane; ++k)
    for (int c = 0; c < nc; ++c) dst[k * nc + c] = planar[std::size_t(c) * plane + k];
}

}  // namespace

void FilteredTextonRenderer::need_pyramid() const {
  if (model_.order != 1)
    usage("filtering (S1 §5) needs a bilinear texton (order 1); this model has order " + std::to_string(model_.order));
}

double FilteredTextonRenderer::launch_cells(Kernel& kernel, cl_uint index, int width, int height,
                                            std::int64_t max_cells) {
  LoopWatchdog watchdog(ctx_);
  const std::array<std::size_t, 2> local = kernel.fit_local(ctx_, {16, 4});
  max_cells = std::max<std::int64_t>(1, max_cells);
  double ms = 0.0;
  for (std::int64_t window = max_cells;; window = (window + 1) / 2) {
    const std::int64_t passes = (max_cells + window - 1) / window;
    bool tripped = false;
    for (std::int64_t k = 0; k < passes && !tripped; ++k) {
      const bool last = k + 1 == passes;
      const int pass = (k > 0 ? STEX_FILTER_PASS_LOAD : 0) | (last ? STEX_FILTER_PASS_FINISH : 0);
      kernel.set_arg(index, cl_long(k * window));
      kernel.set_arg(index + 1, cl_long(last ? std::numeric_limits<std::int64_t>::max() : (k + 1) * window));
      kernel.set_arg(index + 2, cl_int(pass));
      ms += launch_checked(ctx_, kernel, watchdog, index + 3, std::size_t(width), std::size_t(height), local, &tripped);
      ++last_launches_;
    }
    if (!tripped) {
      last_cell_passes_ = std::max(last_cell_passes_, int(std::min<std::int64_t>(passes, 1 << 30)));
      return ms;
    }
    if (window == 1) throw Error(ErrorKind::Device, LoopWatchdog::refusal(ctx_.info(), kernel.name()));
  }
}

std::vector<float> FilteredTextonRenderer::render_scaled(const RenderParams& params, std::int64_t x, std::int64_t y,
                                                         int width, int height, double* device_ms,
                                                         std::size_t max_chunk_pixels) {
  validate_region(x, y, width, height);
  if (params.scale < 1.0) {  // the box prefilter through the texton renderer (the device's default strategy)
    if (!minified_) minified_ = std::make_unique<TextonRenderer>(ctx_, model_);
    RenderParams p = params;
    p.filter = true;
    TextonRenderStats stats;
    std::vector<float> out = minified_->render(p, x, y, width, height, TextonRenderOptions{}, &stats);
    if (device_ms) *device_ms = stats.device_ms;
    last_launches_ = stats.chunks;
    last_cell_passes_ = 1;
    return out;
  }
  need_pyramid();
  const TextonSetup setup = make_texton_setup(model_, params);
  const double j = 1.0 / params.scale;
  const stex_footprint f = make_footprint(pyramid_.params.levels, j, 0.0, 0.0, j, k_fix_one * params.scale);
  Buffer<std::uint32_t> table(ctx_, setup.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
  if (!scaled_) scaled_ = std::make_unique<Kernel>(ctx_.program("texton_filtered.cl"), "texton_filtered_scaled");
  const int nc = setup.channels;
  const std::size_t cap = max_chunk_pixels ? max_chunk_pixels : k_default_rows_pixels;
  const int rows = int(std::max<std::size_t>(1, std::min<std::size_t>(std::size_t(height), cap / std::size_t(width))));
  std::vector<float> out(std::size_t(width) * std::size_t(height) * std::size_t(nc));
  Buffer<float> dev(ctx_, std::size_t(width) * std::size_t(rows) * std::size_t(nc), CL_MEM_READ_WRITE, "render chunk");
  std::vector<float> planar;
  last_launches_ = last_cell_passes_ = 0;
  double ms = 0.0;
  for (int r0 = 0; r0 < height; r0 += rows) {
    const int h = std::min(rows, height - r0);
    std::int64_t max_cells = 0;
    for (int jj = 0; jj < h; ++jj)
      for (int ii = 0; ii < width; ++ii)
        max_cells = std::max(max_cells, stex_texton_filtered_cells(setup.params, f, stex_pixel_fix(x + ii),
                                                                   stex_pixel_fix(y + r0 + jj)));
    cl_uint a = 0;
    scaled_->set_arg(a++, setup.params);
    scaled_->set_arg(a++, pyramid_.params);
    scaled_->set_arg(a++, f);
    scaled_->set_arg(a++, pyr_);
    scaled_->set_arg(a++, table);
    scaled_->set_arg(a++, cl_long(x));
    scaled_->set_arg(a++, cl_long(y + r0));
    scaled_->set_arg(a++, cl_int(width));
    scaled_->set_arg(a++, cl_int(h));
    scaled_->set_arg(a++, cl_int(width));
    scaled_->set_arg(a++, dev);
    ms += launch_cells(*scaled_, a, width, h, max_cells);
    planar.resize(std::size_t(width) * std::size_t(h) * std::size_t(nc));
    dev.read(planar.data(), planar.size());
    deinterleave_into(planar, width, h, nc, out.data() + std::size_t(r0) * std::size_t(width) * std::size_t(nc));
  }
  if (device_ms) *device_ms = ms;
  return out;
}

std::vector<float> FilteredTextonRenderer::render_camera(const RenderParams& params, const PerspectiveCamera& cam,
                                                         std::int64_t x, std::int64_t y, int width, int height,
                                                         double* device_ms, std::size_t max_chunk_pixels,
                                                         bool filter) {
  validate_region(x, y, width, height);
  const FootprintRows rows_of = [](const void* source, int levels, std::int64_t x0, std::int64_t r0, int w, int h,
                                   bool f, std::vector<std::int64_t>* pos, std::vector<stex_footprint>* fp) {
    camera_footprints(*static_cast<const PerspectiveCamera*>(source), levels, x0, r0, w, h, pos, fp, f);
  };
  return render_mapped(params, &cam, rows_of, x, y, width, height, device_ms, max_chunk_pixels, filter);
}

std::vector<float> FilteredTextonRenderer::render_uv_map(const RenderParams& params, const UvMap& map,
                                                         double* device_ms, std::size_t max_chunk_pixels,
                                                         bool filter) {
  validate_uv_map(map);
  const FootprintRows rows_of = [](const void* source, int levels, std::int64_t, std::int64_t r0, int, int h,
                                   bool f, std::vector<std::int64_t>* pos, std::vector<stex_footprint>* fp) {
    uv_map_footprints(*static_cast<const UvMap*>(source), levels, int(r0), h, pos, fp, f);
  };
  return render_mapped(params, &map, rows_of, 0, 0, map.width, map.height, device_ms, max_chunk_pixels, filter);
}

std::vector<float> FilteredTextonRenderer::render_mapped(const RenderParams& params, const void* source,
                                                         FootprintRows rows_of, std::int64_t x, std::int64_t y,
                                                         int width, int height, double* device_ms,
                                                         std::size_t max_chunk_pixels, bool filter) {
  need_pyramid();
  RenderParams unit = params;
  unit.scale = 1.0;
  const TextonSetup setup = make_texton_setup(model_, unit);
  Buffer<std::uint32_t> table(ctx_, setup.poisson_table, CL_MEM_READ_ONLY, "Poisson table");
  if (!mapped_) mapped_ = std::make_unique<Kernel>(ctx_.program("texton_filtered.cl"), "texton_filtered_mapped");
  const int nc = setup.channels;
  const std::size_t cap = max_chunk_pixels ? max_chunk_pixels : k_default_rows_pixels;
  const int rows = int(std::max<std::size_t>(1, std::min<std::size_t>(std::size_t(height), cap / std::size_t(width))));
  std::vector<float> out(std::size_t(width) * std::size_t(height) * std::size_t(nc));
  const std::size_t chunk = std::size_t(width) * std::size_t(rows);
  Buffer<float> dev(ctx_, chunk * std::size_t(nc), CL_MEM_READ_WRITE, "render chunk");
  Buffer<std::int64_t> dpos(ctx_, 2 * chunk, CL_MEM_READ_ONLY, "plane positions");
  Buffer<stex_footprint> dfp(ctx_, chunk, CL_MEM_READ_ONLY, "footprints");
  std::vector<std::int64_t> pos;
  std::vector<stex_footprint> fp;
  std::vector<float> planar;
  last_launches_ = last_cell_passes_ = 0;
  double ms = 0.0;
  for (int r0 = 0; r0 < height; r0 += rows) {
    const int h = std::min(rows, height - r0);
    rows_of(source, pyramid_.params.levels, x, y + r0, width, h, filter, &pos, &fp);
    std::int64_t max_cells = 0;
    for (std::size_t k = 0; k < fp.size(); ++k)
      if (fp[k].probes > 0)
        max_cells = std::max(max_cells, stex_texton_filtered_cells(setup.params, fp[k], pos[2 * k], pos[2 * k + 1]));
    dpos.write(pos.data(), pos.size());
    dfp.write(fp.data(), fp.size());
    cl_uint a = 0;
    mapped_->set_arg(a++, setup.params);
    mapped_->set_arg(a++, pyramid_.params);
    mapped_->set_arg(a++, pyr_);
    mapped_->set_arg(a++, table);
    mapped_->set_arg(a++, dpos);
    mapped_->set_arg(a++, dfp);
    mapped_->set_arg(a++, cl_int(width));
    mapped_->set_arg(a++, cl_int(h));
    mapped_->set_arg(a++, cl_int(width));
    mapped_->set_arg(a++, dev);
    ms += launch_cells(*mapped_, a, width, h, max_cells);
    planar.resize(std::size_t(width) * std::size_t(h) * std::size_t(nc));
    dev.read(planar.data(), planar.size());
    deinterleave_into(planar, width, h, nc, out.data() + std::size_t(r0) * std::size_t(width) * std::size_t(nc));
  }
  if (device_ms) *device_ms = ms;
  return out;
}

}  // namespace stex
