// The standard error of a Welch PSD estimate (analysis/lrp.h lrp_welch: Hann-windowed periodograms of T x T
// crops at step T/2) summed over a set of frequencies, relative to its expectation; shared by the spectrum
// tests of every kind.
//  - Each periodogram ordinate is exponential (relative variance 1); f and -f are one ordinate (a real
//    field), so a set of expected powers P_i holds N_eff = (sum P)^2 / sum P^2 / 2 independent ones...
//  - ... correlated with their neighbours by the Hann window: the window's spectrum (1/4, 1/2, 1/4) makes
//    neighbouring ordinates correlate by 2/3 and next-neighbours by 1/6, so the variance of a sum is
//    (1 + 2 (2/3)^2 + 2 (1/6)^2)^2 = 3.78 times that of independent ordinates (the square: two axes).
//  - Crops overlapping by half correlate by 1/9 (the squared overlap integral of two shifted Hann windows,
//    normalised), so an n x n grid of crops is worth (n^2 / (n + 2 (n - 1) / 9))^2 independent ones.
//  - Shot noise (sparse convolution: Gabor, texton, spot noise) is not Gaussian: the sum also varies with the
//    number of impulses whose kernels put power in it, a fourth-cumulant term added to the Gaussian variance
//    above: var_shot = lambda int E[q(x)^2] dx / (lambda int E[q(x)] dx)^2, q(x) the sum's share of one impulse
//    at x. For q(x) = Q_c f_c u(x) (kernel c's power Q_c, its fraction f_c <= 1 in the set of frequencies, u the
//    crops' summed squared windows at x), var_shot <= (max Q / mean Q) / (lambda A_eff p), where
//    A_eff = (int u)^2 / int u^2 and p = E[Q f] / E[Q] is the set's share of the variance. A kernel's extent
//    smooths u (a larger A_eff), so this bounds the term from above.
#pragma once
#include <cmath>
#include <cstddef>
#include <vector>

namespace stex::test {

// Independent crops' worth of an n x n grid of half-overlapping crops.
inline double welch_effective_crops(int per_axis) {
  const double n = per_axis;
  return std::pow(n * n / (n + 2.0 * (n - 1.0) / 9.0), 2.0);  // 3 x 3: 6.83
}

// Relative SE of sum_{i in bins} of a Welch PSD whose expectation is `expected`, from `crops_per_axis`^2
// crops (times `seeds` independent renders).
inline double welch_rel_se(const std::vector<double>& expected, const std::vector<std::size_t>& bins, int crops_per_axis,
                           int seeds = 1) {
  double s = 0.0, s2 = 0.0;
  for (std::size_t i : bins) {
    s += expected[i];
    s2 += expected[i] * expected[i];
  }
  if (!(s2 > 0.0)) return 0.0;
  const double n_eff = s * s / s2;
  const double hann = std::pow(1.0 + 2.0 * 4.0 / 9.0 + 2.0 / 36.0, 2.0);
  return std::sqrt(hann * 2.0 / (n_eff * welch_effective_crops(crops_per_axis) * seeds));
}

// The frequencies of a T x T spectrum (FFT order, DC left out) in `count` rings of `width` frequency bins
// each, by radius |k| (in bins).
inline std::vector<std::vector<std::size_t>> welch_rings(int t, double width, int count) {
  std::vector<std::vector<std::size_t>> rings(static_cast<std::size_t>(count));
  for (std::size_t i = 1; i < std::size_t(t) * std::size_t(t); ++i) {
    const int kx = int(i % std::size_t(t)) >= t / 2 ? int(i % std::size_t(t)) - t : int(i % std::size_t(t));
    const int ky = int(i / std::size_t(t)) >= t / 2 ? int(i / std::size_t(t)) - t : int(i / std::size_t(t));
    const std::size_t r = std::size_t(std::hypot(kx, ky) / width);
    if (r < rings.size()) rings[r].push_back(i);
  }
  return rings;
}

// The shot-noise bound above, relative variance: impulses of intensity lambda (per pixel^2), a side x side
// render cut into T x T crops at step T / 2, a set of frequencies holding the share `share` of the variance,
// and q_ratio = max Q / mean Q of the kernels' powers.
inline double welch_shot_rel_var(double lambda, int side, int t, double share, double q_ratio = 1.0) {
  std::vector<double> u(static_cast<std::size_t>(side), 0.0);
  const double pi = 3.14159265358979323846;
  for (int a = 0; a + t <= side; a += t / 2)
    for (int i = 0; i < t; ++i) u[std::size_t(a + i)] += std::pow(std::sin(pi * (i + 0.5) / t), 4.0);
  double s1 = 0.0, s2 = 0.0;
  for (double v : u) {
    s1 += v;
    s2 += v * v;
  }
  const double a_eff = std::pow(s1 * s1 / s2, 2.0);  // separable: u(x, y) = u(x) u(y)
  return q_ratio / (lambda * a_eff * share);
}

}  // namespace stex::test
