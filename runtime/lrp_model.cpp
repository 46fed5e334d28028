// LRP model validation and the kernel setup (S3 §4-5). See lrp_model.h.
#include "runtime/lrp_model.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/math.h"

namespace stex {

static_assert(sizeof(stex_lrp_params) == 4 * (9 + 4 + 6 * STEX_LRP_MAX_STRATA + 16),
              "stex_lrp_params must be 32-bit fields without hidden padding");

namespace {

[[noreturn]] void bad(const std::string& what) { throw Error(ErrorKind::Input, "LRP model: " + what); }

bool finite(double v) { return std::isfinite(v); }

// Frequency clamping (S3 §6.4) by the footprint of a minified view: every cosine is faded by the transfer of
// the pixel's footprint, a Gaussian of the box's variance (1 / scale)^2 / 12 per axis, at its frequency,
// T(f) = exp(-2 pi^2 sigma^2 |f|^2) (a smooth clamp: the paper fades out the cosines above the sampling
// limit). A cosine's frequency is drawn at render time (a table entry of its sub-stratum plus a uniform jitter
// inside the bin), so each sub-stratum's colour weights are scaled by the mean of T over its entries and
// their bins (closed form: T is separable). The structure's terms are scaled by T at their frequency k / B;
// each block's mean (k = 0) stays (S3 §6.4: it needs a MIP map; docs/filtering.md). The turbulence strata
// displace the structure and are not filtered. Changes the tables only: the kernel is the unfiltered one.
void filter_tables(const LrpModel& m, const RenderParams& rp, LrpSetup& s) {
  const double c = 2.0 * k_pi * k_pi * footprint_variance(rp.scale);
  const double period = double(m.period);
  std::size_t entry = 0, sub = 0;
  const std::size_t stride = 2 * std::size_t(m.channels);
  for (const LrpStratum& st : m.strata) {
    for (int count : st.sub_counts) {
      double g = 0.0;
      for (int e = 0; e < count; ++e, ++entry) {
        const double kx = m.freqs[2 * entry], ky = m.freqs[2 * entry + 1];
        g += mean_of_gaussian(c, (kx - 0.5) / period, (kx + 0.5) / period) *
             mean_of_gaussian(c, (ky - 0.5) / period, (ky + 0.5) / period);
      }
      g /= double(count);
      float* col = &s.fdata[s.params.col_off + sub * stride];
      for (std::size_t k = 0; k < stride; ++k) col[k] = float(double(col[k]) * g);
      ++sub;
    }
  }
  if (m.block > 0) {
    const std::size_t tstride = 2 + stride;
    for (std::size_t t = 0; t < m.terms.size() / tstride; ++t) {
      float* term = &s.fdata[s.params.r_off + t * tstride];
      const double fx = term[0] / double(m.block), fy = term[1] / double(m.block);
      const double g = std::exp(-c * (fx * fx + fy * fy));
      for (std::size_t k = 2; k < tstride; ++k) term[k] = float(double(term[k]) * g);
    }
  }
}

}  // namespace

int LrpModel::total_sub_strata() const {
  int n = 0;
  for (const auto& s : strata) n += int(s.sub_counts.size());
  return n;
}

double lrp_window(double y) {
  if (!(std::fabs(y) < 1.5)) return 0.0;
  auto i0 = [](double z) {
    const double u = z * z / 4.0;
    double term = 1.0, sum = 1.0;
    for (int m = 1; m < 60; ++m) {
      term *= u / (double(m) * m);
      sum += term;
    }
    return sum;
  };
  const double pi = 3.14159265358979323846;
  return i0(3.0 * pi * std::sqrt(1.0 - (y / 1.5) * (y / 1.5))) / i0(3.0 * pi);
}

double lrp_window_integral() {
  static const double value = [] {
    const int n = 6000;  // Simpson on [0, 1.5]; w is smooth inside and w(1.5) = 1/I0(3 pi)
    const double h = 1.5 / n;
    double s = 0.0;
    for (int i = 0; i <= n; ++i) {
      const double r = i * h;
      const double f = r * lrp_window(std::min(r, 1.5 - 1e-15)) * lrp_window(std::min(r, 1.5 - 1e-15));
      s += f * (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0));
    }
    return s * h / 3.0;
  }();
  return value;
}

void validate_lrp_model(const LrpModel& m) {
  if (m.channels < 1 || m.channels > STEX_LRP_MAX_CHANNELS)
    bad("channels must be 1..4, got " + std::to_string(m.channels));
  if (m.period < 2 || m.period > 4096 || (m.period & (m.period - 1)) != 0)
    bad("period T must be a power of two in [2, 4096], got " + std::to_string(m.period));
  for (int c = 0; c < m.channels; ++c)
    if (!finite(m.mean[c])) bad("mean[" + std::to_string(c) + "] is not finite");
  if (m.strata.size() > STEX_LRP_MAX_STRATA)
    bad("at most " + std::to_string(STEX_LRP_MAX_STRATA) + " strata, got " + std::to_string(m.strata.size()));
  if (m.strata.size() + m.turbulence.size() > STEX_LRP_MAX_STRATA)
    bad("at most " + std::to_string(STEX_LRP_MAX_STRATA) + " strata and turbulence strata together, got " +
        std::to_string(m.strata.size() + m.turbulence.size()));
  auto check_strata = [&](const std::vector<LrpStratum>& list, const char* kind) {
    std::size_t entries = 0;
    for (std::size_t s = 0; s < list.size(); ++s) {
      const LrpStratum& st = list[s];
      const std::string name = std::string(kind) + " " + std::to_string(s) + ": ";
      if (!finite(st.delta) || st.delta <= 0.0 || st.delta > 1e6) bad(name + "delta must be in (0, 1e6]");
      if (!finite(st.amplitude) || st.amplitude < 0.0) bad(name + "amplitude must be finite and >= 0");
      if (!finite(st.energy) || !finite(st.psd_lo) || !finite(st.psd_hi) || !finite(st.erosion))
        bad(name + "energy, psd interval and erosion must be finite");
      if (st.sub_counts.empty() || st.sub_counts.size() > 4096)
        bad(name + "J_S (sub-strata) must be 1..4096, got " + std::to_string(st.sub_counts.size()));
      for (int c : st.sub_counts) {
        if (c < 1 || c > m.period * m.period) bad(name + "a sub-stratum table must hold 1..T^2 frequencies");
        entries += std::size_t(c);
      }
    }
    return entries;
  };
  const std::size_t entries = check_strata(m.strata, "stratum");
  const std::size_t turb_entries = check_strata(m.turbulence, "turbulence stratum");
  if (m.turb_freqs.size() != 2 * turb_entries)
    bad("turbulence frequency table holds " + std::to_string(m.turb_freqs.size() / 2) +
        " entries, the turbulence strata declare " + std::to_string(turb_entries));
  for (std::int32_t k : m.turb_freqs)
    if (k < -m.period / 2 || k > m.period / 2)
      bad("turbulence frequency " + std::to_string(k) + " outside [-T/2, T/2]");
  if (m.freqs.size() != 2 * entries)
    bad("frequency table holds " + std::to_string(m.freqs.size() / 2) + " entries, the sub-strata declare " +
        std::to_string(entries));
  for (std::int32_t k : m.freqs)
    if (k < -m.period / 2 || k > m.period / 2) bad("frequency " + std::to_string(k) + " outside [-T/2, T/2]");
  if (m.colours.size() != std::size_t(2 * m.channels * m.total_sub_strata()))
    bad("colour table must hold 2 * channels floats per sub-stratum");
  for (float v : m.colours)
    if (!finite(v) || std::fabs(v) > 1.0f + 1e-5f) bad("colour weights must be finite and in [-1, 1]");
  if (!finite(m.ratio) || m.ratio < 0.0 || m.ratio > 1.0) bad("structure ratio r must be in [0, 1]");
  if (m.block == 0) {
    if (m.jr != 0 || !m.terms.empty()) bad("structure terms without a block size");
  } else {
    if (m.block < 1 || m.block > m.period || m.period % m.block != 0)
      bad("block size must divide the period, got " + std::to_string(m.block));
    if (m.jr < 1 || m.jr > m.block * m.block) bad("J_R must be 1..B^2, got " + std::to_string(m.jr));
    const std::size_t nb = std::size_t(m.blocks());
    if (m.terms.size() != nb * nb * std::size_t(m.jr) * std::size_t(2 + 2 * m.channels))
      bad("structure table must hold blocks^2 * J_R * (2 + 2 channels) floats");
    for (float v : m.terms)
      if (!finite(v)) bad("structure terms must be finite");
  }
  if (!finite(m.structure_error) || m.structure_error < 0.0) bad("structure error must be finite and >= 0");
  if (!finite(m.sigma) || m.sigma < 0.0 || m.sigma > 1e6) bad("turbulence sigma must be in [0, 1e6]");
  if (!finite(m.blend) || m.blend <= 0.0 || m.blend > 1.0) bad("placement blend must be in (0, 1]");
  if ((m.sigma > 0.0 || m.placement) && m.block == 0)
    bad("turbulence and placement act on the structure: they need r > 0");
  if (m.sigma > 0.0 && m.turbulence.empty())
    bad("turbulence sigma > 0 needs turbulence strata (re-run stex analyze to rebuild the model)");
  if (m.sigma == 0.0 && !m.turbulence.empty()) bad("turbulence strata without a turbulence sigma");
}

LrpSetup make_lrp_setup(const LrpModel& m, const RenderParams& rp) {
  validate_lrp_model(m);
  if (!(rp.scale >= k_min_scale && rp.scale <= k_max_scale))
    throw Error(ErrorKind::Usage, "scale must be in [1/1024, 1024], got " + std::to_string(rp.scale));
  LrpSetup s;
  s.channels = m.channels;
  stex_lrp_params& p = s.params;
  p.channels = m.channels;
  p.strata = int(m.strata.size());
  p.seed_lo = std::uint32_t(rp.seed & 0xffffffffu);
  p.seed_hi = std::uint32_t(rp.seed >> 32);
  const double fix_scale = rp.scale * double(1 << STEX_LRP_FIX_BITS);
  p.inv_fix_scale = float(1.0 / fix_scale);
  p.bin = float(1.0 / m.period);
  for (int c = 0; c < m.channels; ++c) p.mean[c] = m.mean[c];

  // Tables: frequencies, then colours, then structure terms (floats); sub-strata (offset, count) (u32).
  for (std::int32_t k : m.freqs) s.fdata.push_back(float(k));
  for (std::int32_t k : m.turb_freqs) s.fdata.push_back(float(k));
  p.col_off = std::uint32_t(s.fdata.size());
  s.fdata.insert(s.fdata.end(), m.colours.begin(), m.colours.end());
  p.r_off = std::uint32_t(s.fdata.size());
  s.fdata.insert(s.fdata.end(), m.terms.begin(), m.terms.end());
  if (s.fdata.empty()) s.fdata.push_back(0.0f);
  std::uint32_t entry = 0, sub = 0;
  const double wint = lrp_window_integral();
  double turb_var = 0.0;
  // Output strata at indices 0..strata-1, then the turbulence strata (S3 §5.2) at strata..strata+tstrata-1.
  const std::size_t ns = m.strata.size();
  for (std::size_t i = 0; i < ns + m.turbulence.size(); ++i) {
    const bool turb = i >= ns;
    const LrpStratum& st = turb ? m.turbulence[i - ns] : m.strata[i];
    const double cell = std::llround(st.delta * fix_scale);
    if (cell < 1.0 || cell > double(std::int64_t(1) << 40))
      throw Error(ErrorKind::Usage, "scale " + std::to_string(rp.scale) + " makes the lattice of " +
                                        (turb ? "turbulence stratum " + std::to_string(i - ns)
                                              : "stratum " + std::to_string(i)) +
                                        " degenerate");
    const std::int64_t a = std::int64_t(cell);
    p.cell_lo[i] = stex_lo32(a);
    p.cell_hi[i] = stex_hi32(a);
    // 1/Delta_S in exemplar pixels of the rounded lattice, so that the window reaches exactly 1.5 cells.
    p.inv_delta[i] = float(fix_scale / double(a));
    p.amp[i] = float(st.amplitude);
    p.js[i] = std::uint32_t(st.sub_counts.size());
    p.sub_off[i] = sub;
    for (int c : st.sub_counts) {
      s.udata.push_back(entry);
      s.udata.push_back(std::uint32_t(c));
      entry += std::uint32_t(c);
      ++sub;
    }
    // Variance of the carrier of a turbulence stratum: J_S cosines of amplitude A_S under a lattice of
    // windows: A_S^2 / 2 * J_S * mean_x sum_i w^2 = A_S^2 J_S pi int r w^2 dr.
    if (turb)
      turb_var += st.amplitude * st.amplitude * double(st.sub_counts.size()) * 3.14159265358979323846 * wint;
  }
  if (s.udata.empty()) s.udata.push_back(0u);
  if (m.block > 0) {
    p.flags |= STEX_LRP_FLAG_STRUCTURE;
    const std::int64_t period = std::llround(double(m.period) * fix_scale);
    if (period < 2)
      throw Error(ErrorKind::Usage, "scale " + std::to_string(rp.scale) + " is too small for the structure");
    p.period_lo = stex_lo32(period);
    p.period_hi = stex_hi32(period);
    const std::int64_t place = period / 2;
    p.place_lo = stex_lo32(place);
    p.place_hi = stex_hi32(place);
    p.inv_place = float(1.0 / double(place));
    p.period = float(m.period);
    p.inv_period = float(1.0 / m.period);
    p.block = float(m.block);
    p.inv_block = float(1.0 / m.block);
    p.blocks = m.blocks();
    p.jr = m.jr;
    p.blend = float(m.blend);
    p.inv_blend = float(1.0 / m.blend);
    if (m.placement) p.flags |= STEX_LRP_FLAG_PLACEMENT;
    if (m.sigma > 0.0) {
      if (!(turb_var > 0.0)) throw Error(ErrorKind::Input, "LRP model: the turbulence strata have no energy");
      p.flags |= STEX_LRP_FLAG_TURBULENCE;
      p.tstrata = int(m.turbulence.size());
      p.sigma = float(m.sigma);
      p.turb_norm = float(1.0 / std::sqrt(turb_var));
    }
  }
  if (rp.filter && rp.scale < 1.0) filter_tables(m, rp, s);
  return s;
}

}  // namespace stex
