// Cyclostationary random-phase noise: validation, setup, expected local PSD, reference, renderer. See
// cs_rpn.h and kernels/shared/cs_rpn.h.
#include "runtime/cs_rpn.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.h"
#include "core/math.h"
#include "runtime/chunked_gather.h"
#include "runtime/cs_spot.h"
#include "runtime/gabor_params.h"
#include "runtime/lrp_model.h"
#include "runtime/poisson_table.h"

namespace stex {

static_assert(sizeof(stex_csr_params) == 144, "stex_csr_params must match the OpenCL layout (144 bytes)");

namespace {

constexpr double k_fix_one = double(std::int64_t(1) << STEX_CS_FIX_BITS);
constexpr double k_log2e = 1.44269504088896340736;

std::string num(double v) {
  std::ostringstream os;
  os.precision(9);
  os << v;
  return os.str();
}

[[noreturn]] void usage(const std::string& m) { throw Error(ErrorKind::Usage, m); }

}  // namespace

// The distinct frequencies of all spectra as integers (kx, ky) on the half plane ky > 0 or (ky = 0, kx > 0),
// sorted by (ky, kx); fourier only.
std::vector<int> fourier_union(const CsRpnModel& m);

namespace {


// The bilinear grid weights of phase (u, v): nodes and weights w_g (without E_g), as stex_csr_nodes in double.
void grid_weights(const CsRpnModel& m, double u, double v, int g[4], double w[4]) {
  const double gx = (u - std::floor(u)) * m.k0, gy = (v - std::floor(v)) * m.k1;
  const double ax = std::floor(gx), ay = std::floor(gy);
  const double wx = gx - ax, wy = gy - ay;
  const int i0 = int(long(ax) % m.k0), j0 = int(long(ay) % m.k1);
  const int i1 = (i0 + 1) % m.k0, j1 = (j0 + 1) % m.k1;
  g[0] = j0 * m.k0 + i0;
  g[1] = j0 * m.k0 + i1;
  g[2] = j1 * m.k0 + i0;
  g[3] = j1 * m.k0 + i1;
  w[0] = (1 - wx) * (1 - wy);
  w[1] = wx * (1 - wy);
  w[2] = (1 - wx) * wy;
  w[3] = wx * wy;
}

// Length of [a, b] ∩ [c, d].
double overlap(double a, double b, double c, double d) { return std::max(0.0, std::min(b, d) - std::max(a, c)); }

}  // namespace

std::string cs_rpn_variant_name(CsRpnVariant v) {
  switch (v) {
    case CsRpnVariant::RandomPhase: return "random-phase";
    case CsRpnVariant::Gabor: return "gabor";
    case CsRpnVariant::Phasor: return "phasor";
    case CsRpnVariant::Fourier: return "fourier";
  }
  return "?";
}

CsRpnVariant parse_cs_rpn_variant(const std::string& name) {
  if (name == "random-phase") return CsRpnVariant::RandomPhase;
  if (name == "gabor") return CsRpnVariant::Gabor;
  if (name == "phasor") return CsRpnVariant::Phasor;
  if (name == "fourier") return CsRpnVariant::Fourier;
  usage("unknown cs-rpn variant '" + name + "' (expected random-phase, gabor, phasor or fourier)");
}

void validate_cs_rpn_model(const CsRpnModel& m) {
  auto bad = [](const std::string& what) { throw Error(ErrorKind::Input, "invalid cs-rpn model: " + what); };
  const int vi = int(m.variant);
  if (vi < STEX_CSR_RANDOM_PHASE || vi > STEX_CSR_FOURIER) bad("unknown variant " + std::to_string(vi));
  validate_model_periods("cs-rpn", m.t0x, m.t0y, m.t1x, m.t1y);
  if (m.k0 < 1 || m.k1 < 1 || m.k0 > STEX_CSR_MAX_GRID || m.k1 > STEX_CSR_MAX_GRID)
    bad("the spectrum grid must be 1..16 on each side, got " + std::to_string(m.k0) + "x" + std::to_string(m.k1));
  if (m.spectra.size() != std::size_t(m.k0) * std::size_t(m.k1))
    bad("the grid " + std::to_string(m.k0) + "x" + std::to_string(m.k1) + " needs " + std::to_string(m.k0 * m.k1) +
        " spectra, got " + std::to_string(m.spectra.size()));
  std::size_t total = 0;
  bool any = false;
  for (std::size_t g = 0; g < m.spectra.size(); ++g) {
    const CsRpnSpectrum& s = m.spectra[g];
    const std::string at = "spectrum " + std::to_string(g) + ": ";
    if (!std::isfinite(s.energy) || s.energy < 0.0 || s.energy > 1e6) bad(at + "energy must be in [0, 1e6], got " + num(s.energy));
    any = any || s.energy > 0.0;
    if (s.bins.size() % 3 != 0 || s.bins.empty() || s.bins.size() / 3 > std::size_t(k_cs_rpn_max_bins))
      bad(at + "needs 1..65536 bins (fx, fy, weight), got " + std::to_string(s.bins.size()) + " floats");
    total += s.bins.size() / 3;
    for (std::size_t b = 0; b < s.bins.size(); b += 3) {
      const float fx = s.bins[b], fy = s.bins[b + 1], w = s.bins[b + 2];
      if (!std::isfinite(fx) || !std::isfinite(fy) || std::hypot(double(fx), double(fy)) > 0.5 + 1e-6)
        bad(at + "bin frequencies must be finite, at most 0.5 cycles per pixel");
      if (!std::isfinite(w) || !(w > 0.0f) || w > 1e30f) bad(at + "bin weights must be positive and finite");
    }
  }
  if (!any) bad("every spectrum has energy 0");
  if (total > k_cs_rpn_max_total_bins) bad("more than 2^20 bins in all");
  if (!std::isfinite(m.bin) || !(m.bin > 0.0) || m.bin > 0.25) bad("bin must be in (0, 0.25], got " + num(m.bin));
  if (!std::isfinite(m.mean) || std::fabs(m.mean) > 1e6) bad("mean must be finite, within 1e6");
  if (!std::isfinite(m.bandwidth) || m.bandwidth < k_gabor_min_bandwidth || m.bandwidth > k_gabor_max_bandwidth)
    bad("bandwidth must be in [1/1024, 1], got " + num(m.bandwidth));
  if (!std::isfinite(m.spacing) || m.spacing < 1.0 || m.spacing > 4096.0) bad("spacing must be in [1, 4096], got " + num(m.spacing));
  if (m.cosines < 1 || m.cosines > k_cs_rpn_max_cosines) bad("cosines must be 1..256, got " + std::to_string(m.cosines));
  if (m.variant == CsRpnVariant::Fourier) {
    const double t = 1.0 / m.bin;
    const long T = std::lround(t);
    if (std::fabs(t - double(T)) > 1e-9 || T < 16 || T > 1024 || (T & (T - 1)) != 0)
      bad("fourier needs bin = 1 / T, T a power of two in 16..1024, got bin " + num(m.bin));
    for (const CsRpnSpectrum& s : m.spectra)
      for (std::size_t b = 0; b < s.bins.size(); b += 3)
        for (int c = 0; c < 2; ++c)
          if (std::fabs(double(s.bins[b + c]) * double(T) - std::round(double(s.bins[b + c]) * double(T))) > 1e-3)
            bad("fourier needs every bin frequency on the grid k / T (T = " + std::to_string(T) + ")");
    if (fourier_union(m).size() / 2 > k_cs_rpn_max_fourier) bad("fourier: more than 16384 distinct frequencies");
  }
}

std::vector<int> fourier_union(const CsRpnModel& m) {
  const long T = std::lround(1.0 / m.bin);
  std::vector<int> out;
  std::vector<std::pair<int, int>> seen;
  for (const CsRpnSpectrum& s : m.spectra)
    for (std::size_t b = 0; b < s.bins.size(); b += 3) {
      int kx = int(std::lround(double(s.bins[b]) * double(T))), ky = int(std::lround(double(s.bins[b + 1]) * double(T)));
      if (ky < 0 || (ky == 0 && kx < 0)) {
        kx = -kx;
        ky = -ky;
      }
      seen.emplace_back(ky, kx);
    }
  std::sort(seen.begin(), seen.end());
  seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
  for (const auto& [ky, kx] : seen) {
    out.push_back(kx);
    out.push_back(ky);
  }
  return out;
}

namespace {

// The period vectors in fixed output units, as rounded for this scale.
struct FixedPeriods {
  double fs = 0.0;  // fixed units per model pixel
  std::int64_t T0x = 0, T0y = 0, T1x = 0, T1y = 0;
};

// Fills the seed, the periods, the inverse period matrix and the model's scalars of the kernel parameters.
void set_lattice_params(stex_csr_params& p, const CsRpnModel& m, const RenderParams& rp,
                        const FixedPeriods& t) {
  const double det = double(t.T0x) * double(t.T1y) - double(t.T0y) * double(t.T1x);
  p = stex_csr_params{};
  set_cs_lattice_words(p, rp.seed, t.T0x, t.T0y, t.T1x, t.T1y, t.fs, float(double(t.T1y) / det),
                       float(-double(t.T1x) / det), float(-double(t.T0y) / det), float(double(t.T0x) / det));
  p.variant = stex_i32(m.variant);
  p.k0 = m.k0;
  p.k1 = m.k1;
  p.cosines = m.cosines;
  p.bin = float(m.bin);
  p.mean = float(m.mean);
}

// Fourier: the series' period as the cell; no Poisson table.
void set_fourier_params(CsRpnSetup& out, const CsRpnModel& m, double fs) {
  stex_csr_params& p = out.params;
  const std::int64_t per = std::llround(std::round(1.0 / m.bin) * fs);  // the series' period T in fixed units
  p.cell_lo = stex_lo32(per);
  p.cell_hi = stex_hi32(per);
  out.poisson = {0xffffffffu};
  p.poisson_len = 1;
}

// Random phase: the cosine spacing as the cell; no Poisson table. Throws Usage for a sub-1/4-pixel spacing.
void set_random_phase_params(CsRpnSetup& out, const CsRpnModel& m, const RenderParams& rp, double fs) {
  stex_csr_params& p = out.params;
  const double a_real = m.spacing * fs;
  if (a_real < 65536.0 / 4.0)
    usage("spacing x scale = " + num(m.spacing * rp.scale) +
          " output pixels is below 1/4 pixel: raise --scale");
  const std::int64_t a = std::llround(a_real);
  const double delta = double(a) / fs;  // the spacing as used (model pixels)
  p.cell_lo = stex_lo32(a);
  p.cell_hi = stex_hi32(a);
  p.inv_delta2 = float(1.0 / (delta * delta));
  p.amplitude = float(1.0 / std::sqrt(k_pi * m.cosines * lrp_window_integral()));
  out.poisson = {0xffffffffu};
  p.poisson_len = 1;
}

// Gabor and phasor: the impulse density, cell, reach, Gaussian cut-off and Poisson table. Throws Usage
// for a bad --mni or --cell, or a cell side out of the fixed-point range.
void set_impulse_params(CsRpnSetup& out, const CsRpnModel& m, const RenderParams& rp, double fs) {
  stex_csr_params& p = out.params;
  if (!std::isfinite(rp.mni) || rp.mni <= 0.0 || rp.mni > k_max_mni)
    usage("--mni must be in (0, " + num(k_max_mni) + "], got " + num(rp.mni));
  if (!std::isfinite(rp.cell_factor) || rp.cell_factor < 0.1 || rp.cell_factor > 2.0)
    usage("--cell (cell side as a fraction of the kernel radius) must be in [0.1, 2], got " +
          num(rp.cell_factor));
  const double r = gabor_radius(m.bandwidth);
  out.lambda = rp.mni / (k_pi * r * r);
  const double a_real = rp.cell_factor * r * fs;
  if (a_real < 256.0) usage("cell side c*r*scale is below 1/256 pixel: raise --scale");
  if (a_real >= std::ldexp(1.0, 38)) usage("cell side c*r*scale is too large (>= 2^22 pixels)");
  const std::int64_t a = std::llround(a_real);
  const double cell_side = double(a) / fs;
  out.poisson = poisson_threshold_table(out.lambda * cell_side * cell_side);
  const std::int64_t reach = static_cast<std::int64_t>(std::ceil(r * fs * (1.0 + 1.0 / 1048576.0))) + 2;
  p.cell_lo = stex_lo32(a);
  p.cell_hi = stex_hi32(a);
  p.reach_lo = stex_lo32(reach);
  p.reach_hi = stex_hi32(reach);
  p.exp2_factor = float(k_pi * m.bandwidth * m.bandwidth * k_log2e);
  p.r2_max = float(12.0 / double(p.exp2_factor));
  while (double(p.exp2_factor) * double(p.r2_max) > 12.0) p.r2_max = std::nextafter(p.r2_max, 0.0f);
  p.amplitude = float(2.0 * m.bandwidth / std::sqrt(out.lambda));
  p.poisson_len = stex_u32(out.poisson.size());
}

// The bin tables: fdata gets E_g then (fx, fy) per bin, udata (offset, count) per spectrum then the
// cumulative weight thresholds.
void set_bin_tables(CsRpnSetup& out, const CsRpnModel& m) {
  const std::size_t G = m.spectra.size();
  out.fdata.reserve(G);
  for (const CsRpnSpectrum& s : m.spectra) out.fdata.push_back(float(s.energy));
  out.udata.assign(2 * G, 0u);
  std::vector<std::uint32_t> thresholds;
  std::uint32_t offset = 0;
  for (std::size_t g = 0; g < G; ++g) {
    const CsRpnSpectrum& s = m.spectra[g];
    const std::size_t n = s.bins.size() / 3;
    out.udata[2 * g] = offset;
    out.udata[2 * g + 1] = std::uint32_t(n);
    double total = 0.0;
    for (std::size_t b = 0; b < n; ++b) total += s.bins[3 * b + 2];
    double acc = 0.0;
    for (std::size_t b = 0; b < n; ++b) {
      out.fdata.push_back(s.bins[3 * b]);
      out.fdata.push_back(s.bins[3 * b + 1]);
      acc += s.bins[3 * b + 2];
      const double t = std::floor(acc / total * 4294967296.0);
      thresholds.push_back(b + 1 == n || t >= 4294967295.0 ? 0xffffffffu : std::uint32_t(t));
    }
    offset += std::uint32_t(n);
  }
  out.udata.insert(out.udata.end(), thresholds.begin(), thresholds.end());
}

// Index of the frequency bin (fx, fy), folded onto the half plane, in the sorted union un of the series.
std::size_t union_index(const std::vector<int>& un, long T, float fx, float fy) {
  const std::size_t U = un.size() / 2;
  int kx = int(std::lround(double(fx) * double(T))), ky = int(std::lround(double(fy) * double(T)));
  if (ky < 0 || (ky == 0 && kx < 0)) {
    kx = -kx;
    ky = -ky;
  }
  std::size_t lo = 0, hi = U;  // the union is sorted by (ky, kx)
  while (lo < hi) {
    const std::size_t mid = (lo + hi) / 2;
    if (std::make_pair(un[2 * mid + 1], un[2 * mid]) < std::make_pair(ky, kx))
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo;
}

// Fourier only: appends the frequency union and, per spectrum, the normalised weight of each union entry.
void set_fourier_tables(CsRpnSetup& out, const CsRpnModel& m) {
  stex_csr_params& p = out.params;
  const std::size_t G = m.spectra.size();
  const std::vector<int> un = fourier_union(m);
  const std::size_t U = un.size() / 2;
  const long T = std::lround(1.0 / m.bin);
  p.union_off = std::uint32_t(out.fdata.size());
  p.union_n = std::uint32_t(U);
  for (int k : un) out.fdata.push_back(float(k));
  std::vector<float> pw(G * U, 0.0f);
  for (std::size_t g = 0; g < G; ++g) {
    const CsRpnSpectrum& s = m.spectra[g];
    double total = 0.0;
    for (std::size_t b = 2; b < s.bins.size(); b += 3) total += s.bins[b];
    for (std::size_t b = 0; b < s.bins.size(); b += 3) {
      const std::size_t q = union_index(un, T, s.bins[b], s.bins[b + 1]);
      pw[g * U + q] += float(s.bins[b + 2] / total);
    }
  }
  out.fdata.insert(out.fdata.end(), pw.begin(), pw.end());
}

// Filtering a minified view (docs/filtering.md): the footprint is a Gaussian of the pixel box's variance,
// transfer T(f) = exp(-c |f|^2), c = 2 pi^2 sigma^2. The realisation (lattice, impulses, draws) is unchanged.
//  - random phase: each cosine faded by the mean of T over its bin (its frequency is the bin's centre plus a
//    uniform jitter of one bin): a gain per bin, read by stex_csr_sample;
//  - Gabor: each kernel convolved with the footprint (runtime/gabor_params.h's closed form): the envelope's
//    a'^2 = rho a^2, the carrier times rho, the amplitude times rho and a gain per bin (T at rho's rate,
//    averaged over the bin); the envelope is cut at the unfiltered kernel's absolute threshold;
//  - Fourier: each frequency's amplitude times T (its weights p_g(f) times T^2 under the square root).
// Phasor noise normalises its complex sum (a sine profile of constant amplitude) and is not filtered.
void set_filter(CsRpnSetup& out, const CsRpnModel& m, const RenderParams& rp, double fs) {
  stex_csr_params& p = out.params;
  const double c = 2.0 * k_pi * k_pi * footprint_variance(rp.scale);
  if (m.variant == CsRpnVariant::Fourier) {
    const std::size_t U = p.union_n;
    const float* uf = &out.fdata[p.union_off];
    float* pw = &out.fdata[p.union_off + 2 * U];
    for (std::size_t g = 0; g < m.spectra.size(); ++g)
      for (std::size_t q = 0; q < U; ++q) {
        const double fx = double(uf[2 * q]) * m.bin, fy = double(uf[2 * q + 1]) * m.bin;
        pw[g * U + q] = float(double(pw[g * U + q]) * std::exp(-2.0 * c * (fx * fx + fy * fy)));
      }
    return;
  }
  double rho = 1.0;
  if (m.variant == CsRpnVariant::Gabor) {
    const double a2 = m.bandwidth * m.bandwidth;
    rho = 1.0 / (1.0 + 2.0 * k_pi * a2 * footprint_variance(rp.scale));
  }
  // Gains per bin, in the bin tables' order (set_bin_tables): the mean of exp(-c rho f^2) over the bin.
  const std::size_t G = m.spectra.size();
  p.gain_off = std::uint32_t(out.fdata.size());
  double peak = 0.0;
  const double h = 0.5 * m.bin;
  for (std::size_t g = 0; g < G; ++g) {
    const CsRpnSpectrum& sp = m.spectra[g];
    for (std::size_t b = 0; b < sp.bins.size(); b += 3) {
      const double fx = sp.bins[b], fy = sp.bins[b + 1];
      const double gain = mean_of_gaussian(c * rho, fx - h, fx + h) * mean_of_gaussian(c * rho, fy - h, fy + h);
      out.fdata.push_back(float(gain));
      if (sp.bins[b + 2] > 0.0f) peak = std::max(peak, rho * gain);
    }
  }
  if (m.variant != CsRpnVariant::Gabor) return;
  const double a2f = m.bandwidth * m.bandwidth * rho;
  const double exponent = peak > 0.0 ? std::max(0.0, std::min(12.0, 12.0 + std::log2(peak))) : 0.0;
  const double r = std::sqrt(exponent / (k_pi * a2f * k_log2e));
  const std::int64_t reach = static_cast<std::int64_t>(std::ceil(r * fs * (1.0 + 1.0 / 1048576.0))) + 2;
  p.reach_lo = stex_lo32(reach);
  p.reach_hi = stex_hi32(reach);
  p.exp2_factor = float(k_pi * a2f * k_log2e);
  p.r2_max = float(exponent / double(p.exp2_factor));
  while (double(p.exp2_factor) * double(p.r2_max) > exponent) p.r2_max = std::nextafter(p.r2_max, 0.0f);
  p.amplitude = float(double(p.amplitude) * rho);
  p.carrier = float(rho);
}

}  // namespace

bool cs_rpn_filters(const CsRpnModel& m) { return m.variant != CsRpnVariant::Phasor; }

CsRpnSetup make_cs_rpn_setup(const CsRpnModel& m, const RenderParams& rp) {
  validate_cs_rpn_model(m);
  validate_render_params(rp);
  CsRpnSetup out;
  FixedPeriods t;
  t.fs = k_fix_one * rp.scale;
  t.T0x = std::llround(m.t0x * t.fs);
  t.T0y = std::llround(m.t0y * t.fs);
  t.T1x = std::llround(m.t1x * t.fs);
  t.T1y = std::llround(m.t1y * t.fs);
  if (std::hypot(m.t0x, m.t0y) * rp.scale < 1.0 || std::hypot(m.t1x, m.t1y) * rp.scale < 1.0)
    usage("--scale " + num(rp.scale) + " makes a period vector shorter than 1 output pixel");
  set_lattice_params(out.params, m, rp, t);
  if (m.variant == CsRpnVariant::Fourier) {
    set_fourier_params(out, m, t.fs);
  } else if (m.variant == CsRpnVariant::RandomPhase) {
    set_random_phase_params(out, m, rp, t.fs);
  } else {
    set_impulse_params(out, m, rp, t.fs);
  }
  set_bin_tables(out, m);
  if (m.variant == CsRpnVariant::Fourier) set_fourier_tables(out, m);
  out.params.carrier = 1.0f;
  if (rp.filter && rp.scale < 1.0 && cs_rpn_filters(m)) set_filter(out, m, rp, t.fs);
  out.reduce = cs_reduce_table(t.T0x, t.T0y, t.T1x, t.T1y);
  return out;
}

double cs_rpn_energy(const CsRpnModel& m, double u, double v) {
  int g[4];
  double w[4];
  grid_weights(m, u, v, g, w);
  double e = 0.0;
  for (int q = 0; q < 4; ++q) e += w[q] * m.spectra[std::size_t(g[q])].energy;
  return e;
}

std::vector<double> cs_rpn_local_psd(const CsRpnModel& m, double u, double v, int T) {
  std::vector<double> psd(std::size_t(T) * T, 0.0);
  int g[4];
  double w[4];
  grid_weights(m, u, v, g, w);
  const double h = m.variant == CsRpnVariant::Fourier ? 1e-9 * m.bin : 0.5 * m.bin;  // fourier: no jitter
  for (int q = 0; q < 4; ++q) {
    const CsRpnSpectrum& s = m.spectra[std::size_t(g[q])];
    const double e = w[q] * s.energy;
    if (e == 0.0) continue;
    double total = 0.0;
    for (std::size_t b = 2; b < s.bins.size(); b += 3) total += s.bins[b];
    for (std::size_t b = 0; b < s.bins.size(); b += 3) {
      const double share = e * s.bins[b + 2] / total;
      for (int sign = -1; sign <= 1; sign += 2) {
        const double fx = sign * double(s.bins[b]) * T, fy = sign * double(s.bins[b + 1]) * T;  // in bins
        const double hb = h * T;
        for (long ky = long(std::floor(fy - hb - 0.5)); ky <= long(std::ceil(fy + hb + 0.5)); ++ky) {
          const double oy = overlap(fy - hb, fy + hb, ky - 0.5, ky + 0.5) / (2 * hb);
          if (oy <= 0.0) continue;
          for (long kx = long(std::floor(fx - hb - 0.5)); kx <= long(std::ceil(fx + hb + 0.5)); ++kx) {
            const double ox = overlap(fx - hb, fx + hb, kx - 0.5, kx + 0.5) / (2 * hb);
            if (ox <= 0.0) continue;
            const long ix = ((kx % T) + T) % T, iy = ((ky % T) + T) % T;
            psd[std::size_t(iy) * T + std::size_t(ix)] += 0.5 * share * ox * oy;
          }
        }
      }
    }
  }
  return psd;
}

std::vector<float> CsRpnReference::render(std::int64_t x, std::int64_t y, int width, int height) const {
  validate_region(x, y, width, height);
  std::vector<float> out(std::size_t(width) * height);
  const CsRpnSetup& s = setup_;
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
      out[std::size_t(j) * width + i] = stex_csr_eval(s.params, s.fdata.data(), s.udata.data(), s.reduce.data(),
                                                      s.poisson.data(), stex_cs_pixel_fix(x + i), stex_cs_pixel_fix(y + j));
  return out;
}

CsRpnNoise::CsRpnNoise(Context& ctx, const CsRpnModel& model, const NoiseRendererOptions& options)
    : GatherRenderer(ctx, "cs-rpn", "cs_rpn.cl", "cs_rpn", options),
      model_(model),
      setup_(make_cs_rpn_setup(model, RenderParams{})) {
  fdata_ = Buffer<float>(ctx_, setup_.fdata, CL_MEM_READ_ONLY, "cs-rpn spectra");
  udata_ = Buffer<std::uint32_t>(ctx_, setup_.udata, CL_MEM_READ_ONLY, "cs-rpn spectrum tables");
  reduce_ = Buffer<std::uint32_t>(ctx_, setup_.reduce, CL_MEM_READ_ONLY, "cs-rpn node table");
  poisson_ = Buffer<std::uint32_t>(ctx_, setup_.poisson, CL_MEM_READ_ONLY, "cs-rpn poisson table");
}

void CsRpnNoise::set_params(const RenderParams& params) {
  CsRpnSetup s = make_cs_rpn_setup(model_, params);
  if (s.reduce != setup_.reduce) reduce_ = Buffer<std::uint32_t>(ctx_, s.reduce, CL_MEM_READ_ONLY, "cs-rpn node table");
  if (s.poisson != setup_.poisson)
    poisson_ = Buffer<std::uint32_t>(ctx_, s.poisson, CL_MEM_READ_ONLY, "cs-rpn poisson table");
  if (s.fdata != setup_.fdata)  // a filtered render's gains or faded Fourier weights
    fdata_ = Buffer<float>(ctx_, s.fdata, CL_MEM_READ_ONLY, "cs-rpn spectra");
  setup_ = std::move(s);
}

cl_uint CsRpnNoise::set_model_args(Kernel& k, cl_uint a) {
  k.set_arg(a++, setup_.params);
  k.set_arg(a++, fdata_);
  k.set_arg(a++, udata_);
  k.set_arg(a++, reduce_);
  k.set_arg(a++, poisson_);
  return a;
}

}  // namespace stex
