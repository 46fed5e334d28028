// Gabor noise model, setup and reference (Lagae et al. 2009). See gabor_params.h and kernels/shared/gabor.h.
#include "runtime/gabor_params.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/math.h"
#include "runtime/poisson_table.h"

namespace stex {

static_assert(sizeof(stex_gabor_params) == 64, "stex_gabor_params must match the OpenCL layout (64 bytes)");

namespace {

constexpr double k_fix_one = double(std::int64_t(1) << STEX_GABOR_FIX_BITS);
constexpr double k_log2e = 1.44269504088896340736;
constexpr double k_two_pi = 2.0 * k_gabor_pi;

std::string num(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

[[noreturn]] void usage(const std::string& message) { throw Error(ErrorKind::Usage, message); }

// Inverse-CDF thresholds of the weights (like runtime/poisson_table.h): T[k] = floor(P(<= k) 2^32), the
// last entry 2^32 - 1; stex_poisson_count(T, K, u) returns the smallest k with u < T[k].
std::vector<std::uint32_t> component_thresholds(const GaborModel& m) {
  double total = 0.0;
  for (const GaborComponent& c : m.components) total += c.weight;
  std::vector<std::uint32_t> t(m.components.size());
  double acc = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    acc += m.components[k].weight;
    const double v = std::floor(acc / total * 4294967296.0);
    t[k] = v >= 4294967295.0 ? 0xffffffffu : static_cast<std::uint32_t>(v);
  }
  t.back() = 0xffffffffu;
  return t;
}

}  // namespace

double gabor_radius(double bandwidth) { return std::sqrt(12.0 / (k_gabor_pi * bandwidth * bandwidth * k_log2e)); }

void validate_gabor_model(const GaborModel& m) {
  auto bad = [](const std::string& what) { throw Error(ErrorKind::Input, "invalid gabor model: " + what); };
  if (!std::isfinite(m.bandwidth) || m.bandwidth < k_gabor_min_bandwidth || m.bandwidth > k_gabor_max_bandwidth)
    bad("bandwidth must be in [1/1024, 1], got " + num(m.bandwidth));
  if (m.components.empty() || m.components.size() > STEX_GABOR_MAX_COMPONENTS)
    bad("components must number 1.." + std::to_string(STEX_GABOR_MAX_COMPONENTS) + ", got " +
        std::to_string(m.components.size()));
  double total = 0.0;
  for (std::size_t k = 0; k < m.components.size(); ++k) {
    const GaborComponent& c = m.components[k];
    const std::string at = "component " + std::to_string(k) + ": ";
    if (!std::isfinite(c.frequency) || c.frequency < 0.0 || c.frequency > k_gabor_max_frequency)
      bad(at + "frequency must be in [0, 0.5] cycles per pixel, got " + num(c.frequency));
    if (!std::isfinite(c.orientation) || std::fabs(c.orientation) > 64.0 * k_two_pi)
      bad(at + "orientation must be finite and within +-128 pi radians, got " + num(c.orientation));
    if (!std::isfinite(c.spread) || c.spread < 0.0 || c.spread > k_two_pi * (1.0 + 1e-6))
      bad(at + "spread must be in [0, 2 pi] radians, got " + num(c.spread));  // 2 pi as float32 is 2 pi (1 + 2.8e-8)
    if (!std::isfinite(c.weight) || c.weight < 0.0 || c.weight > 1e30)
      bad(at + "weight must be finite and >= 0, got " + num(c.weight));
    total += c.weight;
  }
  if (!(total > 0.0)) bad("the component weights sum to 0");
  if (!std::isfinite(m.mean) || std::fabs(m.mean) > 1e30) bad("mean must be finite, got " + num(m.mean));
  if (!std::isfinite(m.stddev) || m.stddev < 0.0 || m.stddev > 1e30)
    bad("std must be finite and >= 0, got " + num(m.stddev));
}

double gabor_noise_sigma(const GaborModel& m, double lambda) {
  const double a2 = m.bandwidth * m.bandwidth;
  double total = 0.0, acc = 0.0;
  for (const GaborComponent& c : m.components) {
    total += c.weight;
    acc += c.weight * (1.0 + std::exp(-k_two_pi * c.frequency * c.frequency / a2));
  }
  return std::sqrt(lambda / (4.0 * a2) * acc / total);
}

double gabor_psd(const GaborModel& m, double u, double v) {
  const double a2 = m.bandwidth * m.bandwidth;
  double total = 0.0, acc = 0.0, norm = 0.0;
  for (const GaborComponent& c : m.components) {
    if (c.weight <= 0.0) continue;
    total += c.weight;
    // Average of |g^|^2 over the component's orientations (64 samples across the spread).
    const int n = c.spread > 0.0 ? 64 : 1;
    double s = 0.0;
    for (int i = 0; i < n; ++i) {
      const double th = c.orientation + (n > 1 ? c.spread * ((i + 0.5) / n - 0.5) : 0.0);
      const double fx = c.frequency * std::cos(th), fy = c.frequency * std::sin(th);
      const double em = std::exp(-k_gabor_pi * ((u - fx) * (u - fx) + (v - fy) * (v - fy)) / a2);
      const double ep = std::exp(-k_gabor_pi * ((u + fx) * (u + fx) + (v + fy) * (v + fy)) / a2);
      s += (em + ep) * (em + ep) / (4.0 * a2 * a2);
    }
    acc += c.weight * s / n;
    norm += c.weight * (1.0 + std::exp(-k_two_pi * c.frequency * c.frequency / a2)) / (4.0 * a2);
  }
  (void)total;
  return m.stddev * m.stddev * acc / norm;
}

GaborFilter gabor_filter(const GaborModel& model, const RenderParams& rp) {
  GaborFilter f;
  f.bandwidth = model.bandwidth;
  f.gain.assign(model.components.size(), 1.0);
  if (!rp.filter || !(rp.scale < 1.0)) return f;
  // Footprint: the output pixel is a square of side w = 1 / scale model pixels; its box filter has variance
  // w^2 / 12 per axis, and the Gaussian footprint G_sigma of that variance replaces it. The Gabor kernel
  // exp(-pi a^2 |d|^2) cos(2 pi F.d) is s^2-Gaussian times a carrier (s^2 = 1 / (2 pi a^2)); convolved with
  // G_sigma it is exactly (per lobe, in the Fourier domain: a product of Gaussians)
  //   rho exp(-pi a'^2 |d|^2) cos(2 pi rho F.d) exp(-2 pi^2 sigma^2 rho |F|^2),
  //   rho = s^2 / (s^2 + sigma^2) = 1 / (1 + 2 pi a^2 sigma^2),  a'^2 = rho a^2.
  f.sigma2 = footprint_variance(rp.scale);
  const double a2 = model.bandwidth * model.bandwidth;
  f.rho = 1.0 / (1.0 + k_two_pi * a2 * f.sigma2);
  f.bandwidth = std::sqrt(a2 * f.rho);
  double peak = 0.0;
  for (std::size_t k = 0; k < model.components.size(); ++k) {
    const double fk = model.components[k].frequency;
    f.gain[k] = std::exp(-2.0 * k_gabor_pi * k_gabor_pi * f.sigma2 * f.rho * fk * fk);
    if (model.components[k].weight > 0.0) peak = std::max(peak, f.rho * f.gain[k]);
  }
  // Truncation at the unfiltered kernel's absolute threshold, 2^-12 of its peak 1: the filtered kernel's
  // peak is rho * gain, so its envelope is cut at 2^-12 / peak (exponent 12 + log2 peak), and a kernel whose
  // peak is below 2^-12 adds nothing (a deeply minified band-pass noise renders its mean). The error bound of
  // a filtered render is that of the unfiltered one; the cost no longer grows with the footprint there.
  f.exponent_max = peak > 0.0 ? std::max(0.0, std::min(12.0, 12.0 + std::log2(peak))) : 0.0;
  return f;
}

GaborSetup make_gabor_setup(const GaborModel& model, const RenderParams& rp) {
  validate_gabor_model(model);
  if (!std::isfinite(rp.mni) || rp.mni <= 0.0 || rp.mni > k_max_mni)
    usage("--mni must be in (0, " + num(k_max_mni) + "], got " + num(rp.mni));
  if (!std::isfinite(rp.cell_factor) || rp.cell_factor < k_min_cell_factor || rp.cell_factor > k_max_cell_factor)
    usage("--cell (cell side as a fraction of the kernel radius) must be in [" + num(k_min_cell_factor) + ", " +
          num(k_max_cell_factor) + "], got " + num(rp.cell_factor));
  if (!std::isfinite(rp.scale) || rp.scale < k_min_scale || rp.scale > k_max_scale)
    usage("--scale must be in [1/1024, 1024], got " + num(rp.scale));

  GaborSetup out;
  const double r = gabor_radius(model.bandwidth);
  out.radius = r;
  out.lambda = rp.mni / (k_gabor_pi * r * r);
  const double a_real = rp.cell_factor * r * rp.scale * k_fix_one;
  if (a_real < 256.0)
    usage("cell side c*r*scale = " + num(a_real / k_fix_one) + " output pixels is below 1/256 pixel: raise --scale");
  if (a_real >= std::ldexp(1.0, 38))
    usage("cell side c*r*scale = " + num(a_real / k_fix_one) + " output pixels is too large (>= 2^22)");
  const std::int64_t a = std::llround(a_real);
  const double cell_side = double(a) / (k_fix_one * rp.scale);
  out.cell_mean = out.lambda * cell_side * cell_side;
  out.poisson_table = poisson_threshold_table(out.cell_mean);
  // The footprint: a minified view (scale < 1, rp.filter) filters each kernel with the pixel's footprint,
  // a Gaussian of the box's variance (1 / scale)^2 / 12 per axis (gabor_filter). The impulses (cell side,
  // intensity, draws) stay those of the unfiltered noise: the same realisation, filtered.
  const GaborFilter f = gabor_filter(model, rp);
  // Conservative reach: the float test r2 < r2_max may accept a displacement a few ulp beyond r.
  const double r_eval = std::sqrt(f.exponent_max / (k_gabor_pi * f.bandwidth * f.bandwidth * k_log2e));
  const std::int64_t reach =
      static_cast<std::int64_t>(std::ceil(r_eval * k_fix_one * rp.scale * (1.0 + 1.0 / 1048576.0))) + 2;

  stex_gabor_params& p = out.params;
  p.seed_lo = stex_lo32(static_cast<stex_i64>(rp.seed));
  p.seed_hi = stex_hi32(static_cast<stex_i64>(rp.seed));
  p.cell_lo = stex_lo32(a);
  p.cell_hi = stex_hi32(a);
  p.reach_lo = stex_lo32(reach);
  p.reach_hi = stex_hi32(reach);
  p.inv_fix_scale = static_cast<float>(1.0 / (k_fix_one * rp.scale));
  p.exp2_factor = static_cast<float>(k_gabor_pi * f.bandwidth * f.bandwidth * k_log2e);
  // exponent_max / exp2_factor (12 unfiltered), computed from the float factor so that the envelope exponent
  // stays >= -exponent_max >= -12 (stex_gabor_exp2's domain).
  p.r2_max = static_cast<float>(f.exponent_max / double(p.exp2_factor));
  while (double(p.exp2_factor) * double(p.r2_max) > f.exponent_max) p.r2_max = std::nextafter(p.r2_max, 0.0f);
  p.mean = static_cast<float>(model.mean);
  p.amplitude = static_cast<float>(model.stddev / gabor_noise_sigma(model, out.lambda) * f.rho);
  p.poisson_len = static_cast<stex_u32>(out.poisson_table.size());
  p.components = static_cast<stex_u32>(model.components.size());
  p.pad0 = p.pad1 = p.pad2 = 0;

  out.components.assign(model.components.size() * STEX_GABOR_COMPONENT_FLOATS, 0.0f);
  for (std::size_t k = 0; k < model.components.size(); ++k) {
    const GaborComponent& c = model.components[k];
    float* d = &out.components[k * STEX_GABOR_COMPONENT_FLOATS];
    const double fr = c.frequency * f.rho;  // the filtered carrier (f.rho = 1 unfiltered)
    d[0] = static_cast<float>(fr * std::cos(c.orientation));
    d[1] = static_cast<float>(fr * std::sin(c.orientation));
    d[2] = static_cast<float>(fr);
    d[3] = static_cast<float>(std::remainder(c.orientation / k_two_pi, 1.0));  // turns, in [-1/2, 1/2]
    d[4] = static_cast<float>(c.spread / k_two_pi);
    d[5] = static_cast<float>(f.gain[k]);
  }
  out.component_table = component_thresholds(model);
  return out;
}

std::vector<float> GaborReference::render(std::int64_t x, std::int64_t y, int width, int height) const {
  validate_region(x, y, width, height);
  std::vector<float> out(std::size_t(width) * std::size_t(height));
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
      out[std::size_t(j) * width + i] =
          stex_gabor_eval(setup_.params, setup_.components.data(), setup_.component_table.data(),
                          setup_.poisson_table.data(), stex_gabor_pixel_fix(x + i), stex_gabor_pixel_fix(y + j));
  return out;
}

}  // namespace stex
