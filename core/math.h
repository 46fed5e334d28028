// Constants and small helpers of the host code's double-precision maths (the kernels' float constants live in
// kernels/shared).
#pragma once
#include <algorithm>
#include <cmath>

namespace stex {

inline constexpr double k_pi = 3.14159265358979323846;

// The mean of exp(-c x^2) over x in [x0, x1] (x0 < x1, c >= 0): closed form by erf, and 1 - c (x0^2 + x0 x1 +
// x1^2) / 3 to first order where c x^2 is tiny (the erf difference would cancel). The filters of minified
// views average a Gaussian transfer over a frequency bin with it (docs/filtering.md).
inline double mean_of_gaussian(double c, double x0, double x1) {
  const double r = std::sqrt(c);
  if (r * std::max(std::fabs(x0), std::fabs(x1)) < 1e-4) return 1.0 - c * (x0 * x0 + x0 * x1 + x1 * x1) / 3.0;
  return std::sqrt(k_pi) / (2.0 * r * (x1 - x0)) * (std::erf(r * x1) - std::erf(r * x0));
}

// The variance per axis of a minified view's footprint: the box of an output pixel, 1 / scale model pixels
// wide, has variance (1 / scale)^2 / 12; the Gaussian footprint of the filters has the same.
inline double footprint_variance(double scale) { return 1.0 / (12.0 * scale * scale); }

}  // namespace stex
