// Chi-square statistics for the statistical kernel tests: the chi-square survival function through the
// regularised incomplete gamma function (series for x < a + 1, Lentz continued fraction beyond, evaluated in
// long double), its quantiles by bisection, and Pearson's statistic. Thresholds in tests are quantiles
// computed here for the exact degrees of freedom, so no table values or normal approximations are needed.
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace stex::test {

// Regularised lower incomplete gamma P(a, x) (series) or upper Q(a, x) (continued fraction); a > 0, x >= 0.
inline long double gamma_p_series(long double a, long double x) {
  long double term = 1.0L / a, sum = term;
  for (int n = 1; n < 100000; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::fabs(term) < std::fabs(sum) * 1e-19L) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

inline long double gamma_q_fraction(long double a, long double x) {
  const long double tiny =
      std::numeric_limits<long double>::min() / std::numeric_limits<long double>::epsilon();
  long double b = x + 1.0L - a, c = 1.0L / tiny, d = 1.0L / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const long double an = -i * (i - a);
    b += 2.0L;
    d = an * d + b;
    if (std::fabs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1.0L / d;
    const long double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1.0L) < 1e-19L) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

// P(X > x) for X ~ chi2(dof).
inline double chi2_sf(double x, double dof) {
  if (x <= 0.0) return 1.0;
  const long double a = dof / 2.0L, xx = x / 2.0L;
  if (xx < a + 1.0L) return double(1.0L - gamma_p_series(a, xx));
  return double(gamma_q_fraction(a, xx));
}

// P(X <= x) for X ~ chi2(dof), accurate in the lower tail too.
inline double chi2_cdf(double x, double dof) {
  if (x <= 0.0) return 0.0;
  const long double a = dof / 2.0L, xx = x / 2.0L;
  if (xx < a + 1.0L) return double(gamma_p_series(a, xx));
  return double(1.0L - gamma_q_fraction(a, xx));
}

// x with P(X > x) = p (upper quantile), by bisection.
inline double chi2_upper_quantile(double p, double dof) {
  double lo = 0.0, hi = dof + 20.0 * std::sqrt(2.0 * dof) + 100.0;
  while (chi2_sf(hi, dof) > p) hi *= 2.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chi2_sf(mid, dof) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// x with P(X <= x) = p (lower quantile), by bisection.
inline double chi2_lower_quantile(double p, double dof) {
  double lo = 0.0, hi = dof;
  while (chi2_cdf(hi, dof) < p) hi *= 2.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chi2_cdf(mid, dof) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Pearson's statistic sum (observed - expected)^2 / expected.
inline double pearson(const std::vector<std::uint64_t>& observed, const std::vector<double>& expected) {
  double chi2 = 0.0;
  for (std::size_t i = 0; i < observed.size(); ++i) {
    const double d = double(observed[i]) - expected[i];
    chi2 += d * d / expected[i];
  }
  return chi2;
}

// Pearson's statistic against a uniform distribution over the bins.
inline double pearson_uniform(const std::vector<std::uint64_t>& observed) {
  std::uint64_t n = 0;
  for (std::uint64_t o : observed) n += o;
  return pearson(observed, std::vector<double>(observed.size(), double(n) / double(observed.size())));
}

}  // namespace stex::test
