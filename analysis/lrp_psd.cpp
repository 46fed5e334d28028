// The expected spectrum of an LRP model and the radial / polar comparison of spectra. See lrp_psd.h.
#include "analysis/lrp_psd.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "analysis/expected_psd.h"
#include "analysis/fft.h"
#include "core/error.h"
#include "core/math.h"

namespace stex {

namespace {

int wrap_index(int k, int t) { return ((k % t) + t) % t; }

double sinc(double u) { return u == 0.0 ? 1.0 : std::sin(k_pi * u) / (k_pi * u); }

// The lag weights of stratum s folded mod T: sum over the lags d = m (mod T) in (-T, T)^2 of the jitter's
// sinc(dx / T) sinc(dy / T), the window autocorrelation g(|d| / Delta_S) and the Hann autocorrelation R_h(d).
std::vector<double> stratum_lag_weights(const LrpModel& m, std::size_t s, const WelchHann& h) {
  const int t = m.period;
  // the rounded lattice the kernel uses (cells of round(Delta_S 2^16) fixed units)
  const double delta = double(std::llround(m.strata[s].delta * 65536.0)) / 65536.0;
  std::vector<double> out(std::size_t(t) * t, 0.0);
  for (int my = 0; my < t; ++my)
    for (int mx = 0; mx < t; ++mx) {
      double acc = 0.0;
      for (int dy : {my, my - t}) {
        if (dy <= -t || (my == 0 && dy != 0)) continue;
        for (int dx : {mx, mx - t}) {
          if (mx == 0 && dx != 0) continue;
          const double rh = h.r1[std::size_t(dx + t - 1)] * h.r1[std::size_t(dy + t - 1)];
          acc += sinc(double(dx) / t) * sinc(double(dy) / t) * lrp_window_autocorrelation(std::hypot(dx, dy) / delta) * rh;
        }
      }
      out[std::size_t(my) * t + mx] = acc;
    }
  return out;
}

// Adds to `folded` (lags mod T) the Hann-weighted autocovariance of a stratum with lag weights `lags` whose
// cosines' frequency distribution, weighted by A_j^2 / 2 and symmetrised, is `dist` (transformed in place).
void add_stratum_lags(int t, const std::vector<double>& lags, std::vector<Complex>& dist, std::vector<Complex>& folded) {
  fft2d_forward(t, t, dist);
  for (std::size_t i = 0; i < folded.size(); ++i) folded[i] += dist[i].real() * lags[i];
}

// Adds weight / count to both signs of each of the `count` table entries from `first` (half to each).
void add_table(const LrpModel& m, std::size_t first, int count, double weight, std::vector<Complex>& dist) {
  const int t = m.period;
  for (int q = 0; q < count; ++q) {
    const int fx = m.freqs[2 * (first + q)], fy = m.freqs[2 * (first + q) + 1];
    dist[std::size_t(wrap_index(fy, t)) * t + wrap_index(fx, t)] += 0.5 * weight / count;
    dist[std::size_t(wrap_index(-fy, t)) * t + wrap_index(-fx, t)] += 0.5 * weight / count;
  }
}

std::vector<double> finish(std::vector<Complex>& folded, int t, const WelchHann& h) {
  fft2d_forward(t, t, folded);
  std::vector<double> out(folded.size());
  for (std::size_t i = 0; i < folded.size(); ++i) out[i] = folded[i].real() / (double(t) * t * h.h2);
  out[0] = 0.0;  // lrp_welch zeroes the DC
  return out;
}

// The gain |v_j|^2 of output sub-stratum j (its colour weights' squared norm; 1 for S3's uniform A_S).
double sub_gain2(const LrpModel& m, std::size_t j) {
  double g2 = 0.0;
  for (int c = 0; c < 2 * m.channels; ++c) {
    const double v = m.colours[j * std::size_t(2 * m.channels) + std::size_t(c)];
    g2 += v * v;
  }
  return g2;
}

}  // namespace

std::vector<double> lrp_expected_welch_psd(const LrpModel& m, const std::vector<std::size_t>& which) {
  const int t = m.period;
  const std::size_t n = std::size_t(t) * t;
  const WelchHann h = welch_hann(t);
  std::vector<Complex> folded(n, Complex(0.0, 0.0));
  std::size_t first = 0, sub = 0;
  for (std::size_t s = 0; s < m.strata.size(); ++s) {
    const LrpStratum& st = m.strata[s];
    const bool use = which.empty() || std::find(which.begin(), which.end(), s) != which.end();
    std::vector<Complex> dist(use ? n : 0, Complex(0.0, 0.0));
    for (int c : st.sub_counts) {
      if (use) add_table(m, first, c, st.amplitude * st.amplitude / 2.0 * sub_gain2(m, sub), dist);
      first += std::size_t(c);
      ++sub;
    }
    if (use) add_stratum_lags(t, stratum_lag_weights(m, s, h), dist, folded);
  }
  return finish(folded, t, h);
}

std::vector<double> lrp_sub_stratum_psd(const LrpModel& m, std::size_t s, std::size_t first, int count) {
  const int t = m.period;
  const std::size_t n = std::size_t(t) * t;
  const WelchHann h = welch_hann(t);
  std::vector<Complex> folded(n, Complex(0.0, 0.0)), dist(n, Complex(0.0, 0.0));
  add_table(m, first, count, 0.5, dist);
  add_stratum_lags(t, stratum_lag_weights(m, s, h), dist, folded);
  return finish(folded, t, h);
}

namespace {

// The fit's bins: 32 radial bins over [0, 1/2) cycles per pixel (and the corners beyond, 14 more of the
// same width) x 16 angles over [0, pi); -1 for the DC.
std::vector<int> fit_bins(int t, int* count) {
  constexpr int rr = 32, nr = 46, na = 16;  // 46 radial bins reach the corner, |f| = 0.707
  std::vector<int> bin(std::size_t(t) * t, -1);
  for (std::size_t i = 1; i < bin.size(); ++i) {
    const int kx = int(i % t) >= t / 2 ? int(i % t) - t : int(i % t);
    const int ky = int(i / t) >= t / 2 ? int(i / t) - t : int(i / t);
    const double r = std::hypot(double(kx), double(ky)) / t;
    double th = std::atan2(double(ky), double(kx));
    if (th < 0) th += k_pi;
    if (th >= k_pi) th -= k_pi;
    const int ir = std::min(nr - 1, int(r / 0.5 * rr));
    bin[i] = ir * na + std::min(na - 1, int(th / k_pi * na));
  }
  *count = nr * na;
  return bin;
}

}  // namespace

void lrp_fit_gains(LrpModel& m, const std::vector<double>& target, int iterations) {
  const int t = m.period;
  const std::size_t n = std::size_t(t) * t;
  if (target.size() != n) throw Error(ErrorKind::Internal, "lrp_fit_gains: target of another size");
  int nb = 0;
  const std::vector<int> bin = fit_bins(t, &nb);
  const WelchHann h = welch_hann(t);
  // a[j][b]: sub-stratum j's expected power in bin b at unit amplitude; x_j = A_j^2 (initial: the model's)
  std::vector<std::vector<double>> a;
  std::vector<double> x;
  std::vector<std::size_t> stratum_of;
  std::size_t first = 0, sub = 0;
  for (std::size_t s = 0; s < m.strata.size(); ++s) {
    const std::vector<double> lags = stratum_lag_weights(m, s, h);
    for (int c : m.strata[s].sub_counts) {
      std::vector<Complex> folded(n, Complex(0.0, 0.0)), dist(n, Complex(0.0, 0.0));
      add_table(m, first, c, 0.5, dist);
      add_stratum_lags(t, lags, dist, folded);
      const std::vector<double> p = finish(folded, t, h);
      std::vector<double> row(nb, 0.0);
      for (std::size_t i = 1; i < n; ++i) row[bin[i]] += p[i];
      a.push_back(std::move(row));
      x.push_back(m.strata[s].amplitude * m.strata[s].amplitude * sub_gain2(m, sub));
      stratum_of.push_back(s);
      first += std::size_t(c);
      ++sub;
    }
  }
  std::vector<double> b(nb, 0.0);
  for (std::size_t i = 1; i < n; ++i) b[bin[i]] += target[i];
  // Itakura-Saito divergence sum_b (b_b / m_b - log(b_b / m_b) - 1), m = the model's power in bin b: the
  // spectral distance that weighs relative errors alike at any power. Multiplicative updates (x >= 0 kept)
  // x_j <- x_j (sum_b a_jb b_b / m_b^2 / sum_b a_jb / m_b)^(1/2).
  std::vector<double> model(nb);
  for (int it = 0; it < iterations; ++it) {
    std::fill(model.begin(), model.end(), 0.0);
    for (std::size_t j = 0; j < x.size(); ++j)
      for (int k = 0; k < nb; ++k) model[k] += a[j][k] * x[j];
    for (std::size_t j = 0; j < x.size(); ++j) {
      double num = 0.0, den = 0.0;
      for (int k = 0; k < nb; ++k) {
        if (!(b[k] > 0.0) || !(model[k] > 0.0)) continue;
        num += a[j][k] * b[k] / (model[k] * model[k]);
        den += a[j][k] / model[k];
      }
      if (den > 0.0) x[j] *= std::sqrt(num / den);
    }
  }
  // back into the model: each stratum's amplitude is its largest A_j, the colour weights carry A_j / that
  std::vector<double> amax(m.strata.size(), 0.0);
  for (std::size_t j = 0; j < x.size(); ++j) amax[stratum_of[j]] = std::max(amax[stratum_of[j]], std::sqrt(x[j]));
  for (std::size_t j = 0; j < x.size(); ++j) {
    const double g_old = std::sqrt(sub_gain2(m, j));
    const double g_new = amax[stratum_of[j]] > 0.0 ? std::sqrt(x[j]) / amax[stratum_of[j]] : 0.0;
    for (int c = 0; c < 2 * m.channels; ++c) {
      float& v = m.colours[j * std::size_t(2 * m.channels) + std::size_t(c)];
      v = g_old > 0.0 ? float(double(v) / g_old * g_new) : (c == 0 ? float(g_new) : 0.0f);
    }
  }
  for (std::size_t s = 0; s < m.strata.size(); ++s) m.strata[s].amplitude = amax[s];
}

PsdComparison compare_psd(const std::vector<double>& psd, const std::vector<double>& ref, int t) {
  const std::size_t n = std::size_t(t) * t;
  if (psd.size() != n || ref.size() != n) throw Error(ErrorKind::Internal, "compare_psd: spectra of different sizes");
  constexpr int nr = 24, sr = 6, sa = 8;
  PsdComparison c;
  c.period = t;
  std::vector<double> a(nr, 0.0), b(nr, 0.0), sa_sum(sr * sa, 0.0), sb_sum(sr * sa, 0.0);
  c.radial_count.assign(nr, 0);
  c.sector_count.assign(sr * sa, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const int kx = int(i % t) >= t / 2 ? int(i % t) - t : int(i % t);
    const int ky = int(i / t) >= t / 2 ? int(i / t) - t : int(i / t);
    const double fx = double(kx) / t, fy = double(ky) / t, r = std::hypot(fx, fy);
    const int ir = int(std::floor(r / 0.5 * nr));
    if (ir < nr) {
      a[ir] += psd[i];
      b[ir] += ref[i];
      ++c.radial_count[ir];
    }
    const int is = int(std::floor((r - 0.02) / 0.48 * sr));
    if (r >= 0.02 && is < sr) {
      double th = std::atan2(fy, fx);
      if (th < 0) th += k_pi;
      if (th >= k_pi) th -= k_pi;  // angles mod pi: (-f, 0) is the direction of (f, 0)
      const int ia = std::min(sa - 1, int(th / k_pi * sa));
      sa_sum[is * sa + ia] += psd[i];
      sb_sum[is * sa + ia] += ref[i];
      ++c.sector_count[is * sa + ia];
    }
  }
  auto median = [](std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t k = v.size() / 2;
    return v.size() % 2 ? v[k] : 0.5 * (v[k - 1] + v[k]);
  };
  std::vector<double> err;
  for (int k = 0; k < nr; ++k) {
    c.radial_ratio.push_back(b[k] > 0 ? a[k] / b[k] : 0.0);
    if (b[k] <= 0) continue;
    err.push_back(std::fabs(c.radial_ratio.back() - 1.0));
    if (c.radial_count[k] >= 200) {
      c.radial_max = std::max(c.radial_max, err.back());
      ++c.radial_max_bins;
    }
  }
  c.radial_median = median(err);
  err.clear();
  for (int k = 0; k < sr * sa; ++k) {
    c.sector_ratio.push_back(sb_sum[k] > 0 ? sa_sum[k] / sb_sum[k] : 0.0);
    if (sb_sum[k] > 0) err.push_back(std::fabs(c.sector_ratio.back() - 1.0));
  }
  c.sector_median = median(err);
  double sp = 0.0, sr_total = 0.0;
  for (std::size_t i = 1; i < n; ++i) {
    sp += psd[i];
    sr_total += ref[i];
  }
  if (sp > 0.0 && sr_total > 0.0) {
    double tv = 0.0;
    for (std::size_t i = 1; i < n; ++i) tv += std::fabs(psd[i] / sp - ref[i] / sr_total);
    c.displaced = 0.5 * tv;
  } else {
    c.displaced = sp == sr_total ? 0.0 : 1.0;
  }
  return c;
}

std::string psd_comparison_summary(const PsdComparison& c) {
  char max[32] = "n/a";
  if (c.radial_max_bins > 0) std::snprintf(max, sizeof max, "%.3f", c.radial_max);
  char buf[192];
  std::snprintf(buf, sizeof buf,
                "median |error| %.3f, max %s (bins >= 200 frequencies); polar sectors: median %.3f; displaced %.3f",
                c.radial_median, max, c.sector_median, c.displaced);
  return buf;
}

nlohmann::ordered_json psd_comparison_json(const PsdComparison& c) {
  nlohmann::ordered_json j;
  j["radial_median"] = c.radial_median;
  j["radial_max"] = c.radial_max_bins > 0 ? nlohmann::ordered_json(c.radial_max) : nlohmann::ordered_json();
  j["sector_median"] = c.sector_median;
  j["displaced"] = c.displaced;
  j["radial_bins"] = "24 bins of |f| in [0, 0.5) cycles/pixel; ratio = expected model power / reference power";
  j["radial_ratio"] = c.radial_ratio;
  j["radial_count"] = c.radial_count;
  j["sector_bins"] = "6 radial bins of |f| in [0.02, 0.5) x 8 angles in [0, pi), radial-major";
  j["sector_ratio"] = c.sector_ratio;
  return j;
}

}  // namespace stex
