// Gaussian model statistics: t_u, the sampled B-spline, texton noise covariance, RME (see gaussian_model.h;
// S1 §3.1, §4.1, §4.3; S2 eq. 1, eq. 3 and §3.2).
#include "analysis/gaussian_model.h"

#include <algorithm>
#include <cmath>
#include <complex>

#include "analysis/periodic.h"
#include "core/error.h"

namespace stex {

NormalisedKernel normalised_kernel(const Image& u, bool periodic) {
  if (u.width <= 0 || u.height <= 0 || u.channels < 1 || u.channels > 4 ||
      u.pixels.size() != std::size_t(u.width) * u.height * u.channels) {
    throw Error(ErrorKind::Usage, "normalised_kernel: malformed image");
  }
  NormalisedKernel k;
  k.width = u.width;
  k.height = u.height;
  k.channels = u.channels;
  const std::size_t n = std::size_t(u.width) * u.height;
  k.t.resize(n * u.channels);
  const double norm = 1.0 / std::sqrt(double(n));
  std::vector<double> plane(n);
  for (int c = 0; c < u.channels; ++c) {
    for (std::size_t i = 0; i < n; ++i) plane[i] = u.pixels[i * u.channels + c];
    if (periodic) plane = periodic_component(u.width, u.height, plane);
    double sum = 0.0;
    for (double v : plane) sum += v;
    double mean = sum / double(n);
    k.mean[c] = mean;
    double* t = k.t.data() + n * c;
    for (std::size_t i = 0; i < n; ++i) t[i] = (plane[i] - mean) * norm;
  }
  return k;
}

namespace {
// b_1(d) = beta^(2 order + 1)(d), the centred B-spline of degree 2 order + 1 at the integers (psi * psi for
// psi = beta^order), |d| <= order; exact rationals. Order 1: 2/3, 1/6; order 3: beta^7; order 5: beta^11.
double bspline_1d(int order, int d) {
  d = d < 0 ? -d : d;
  if (order == 0) return d == 0 ? 1.0 : 0.0;
  if (order == 1) {
    static const double b[] = {2.0 / 3.0, 1.0 / 6.0};
    return d <= 1 ? b[d] : 0.0;
  }
  if (order == 3) {
    static const double b[] = {151.0 / 315.0, 397.0 / 1680.0, 1.0 / 42.0, 1.0 / 5040.0};
    return d <= 3 ? b[d] : 0.0;
  }
  if (order == 5) {
    static const double b[] = {655177.0 / 1663200.0, 1623019.0 / 6652800.0, 1093.0 / 19800.0,
                               50879.0 / 13305600.0, 509.0 / 9979200.0,    1.0 / 39916800.0};
    return d <= 5 ? b[d] : 0.0;
  }
  throw Error(ErrorKind::Usage, "B-spline order must be 0, 1, 3 or 5, got " + std::to_string(order));
}
}  // namespace

int bspline_reach(int order) { return order; }

std::vector<double> bspline_spectral_factor(int order) {
  bspline_1d(order, 0);  // validates the order
  if (order == 0) return {1.0};
  // B(z) = sum_{|d| <= k} b(d) z^d is positive on the unit circle (b^ > 0: the Euler-Frobenius polynomial of
  // an odd-degree B-spline has only negative real roots, in pairs r, 1/r). z^k B(z) has degree 2k; the k
  // roots inside the unit circle give the minimum-phase factor Q(z) = c prod (z - r_i), real, with
  // Q(z) Q(1/z) = B(z). The roots are real and simple, so Durand-Kerner on the monic polynomial converges.
  const int k = order, n = 2 * k;
  std::vector<double> p(std::size_t(n) + 1);  // p[i]: coefficient of z^i in z^k B(z)
  for (int i = 0; i <= n; ++i) p[i] = bspline_1d(order, i - k);
  std::vector<std::complex<double>> roots(n);
  for (int i = 0; i < n; ++i) roots[i] = std::pow(std::complex<double>(0.4, 0.9), i);
  auto eval = [&](std::complex<double> z) {
    std::complex<double> v(0.0);
    for (int i = n; i >= 0; --i) v = v * z + p[i] / p[n];
    return v;
  };
  for (int it = 0; it < 500; ++it) {
    double change = 0.0;
    for (int i = 0; i < n; ++i) {
      std::complex<double> den(1.0);
      for (int j = 0; j < n; ++j)
        if (j != i) den *= roots[i] - roots[j];
      const std::complex<double> step = eval(roots[i]) / den;
      roots[i] -= step;
      change = std::max(change, std::abs(step));
    }
    if (change < 1e-15) break;
  }
  std::vector<double> q{1.0};  // coefficients of prod (z - r_i) over |r_i| < 1, lowest power first
  int inside = 0;
  for (const std::complex<double>& r : roots) {
    if (std::abs(r) >= 1.0) continue;
    ++inside;
    std::vector<double> next(q.size() + 1, 0.0);
    for (std::size_t i = 0; i < q.size(); ++i) {
      next[i + 1] += q[i];
      next[i] -= q[i] * r.real();
    }
    q.swap(next);
  }
  if (inside != k) throw Error(ErrorKind::Internal, "bspline_spectral_factor: root finding failed");
  double ac0 = 0.0;
  for (double v : q) ac0 += v * v;
  const double c = std::sqrt(bspline_1d(order, 0) / ac0);
  for (double& v : q) v *= c;
  std::reverse(q.begin(), q.end());  // largest tap first (order 1: the beta of S1's bilinear kernel)
  // Check every lag: sum_x q(x + d) q(x) = b(d).
  for (int d = 0; d <= k; ++d) {
    double ac = 0.0;
    for (int x = 0; x + d <= k; ++x) ac += q[std::size_t(x + d)] * q[std::size_t(x)];
    if (std::abs(ac - bspline_1d(order, d)) > 1e-12)
      throw Error(ErrorKind::Internal, "bspline_spectral_factor: factor does not reproduce b");
  }
  return q;
}

double bspline_sample(int order, int dx, int dy) { return bspline_1d(order, dx) * bspline_1d(order, dy); }

std::vector<double> bspline_hat(int width, int height, int order) {
  std::vector<double> out(std::size_t(width) * height, 1.0);
  bspline_1d(order, 0);  // validates the order
  if (order == 0) return out;
  // b^(q) = b(0) + 2 sum_{d=1..order} b(d) cos(2 pi d q / W) per axis. For sizes below 2 order + 1 the DFT
  // of b wrapped onto the grid equals this closed form (e^{-2 i pi d q / W} is W-periodic in d), so no
  // special case is needed.
  auto axis = [order](int n) {
    std::vector<double> f(n);
    for (int q = 0; q < n; ++q) {
      double v = bspline_1d(order, 0);
      for (int d = 1; d <= order; ++d) v += 2.0 * bspline_1d(order, d) * std::cos(2.0 * M_PI * double(d) * q / n);
      f[q] = v;
    }
    return f;
  };
  const std::vector<double> fx = axis(width), fy = axis(height);
  for (int r = 0; r < height; ++r) {
    for (int q = 0; q < width; ++q) out[std::size_t(r) * width + q] = fx[q] * fy[r];
  }
  return out;
}

namespace {

// R_ij(l) = sum_x alpha_i(x + l) alpha_j(x) over the s x s support (zero outside).
template <class T>
double cross_correlation(const std::vector<T>& alpha, int support, int i, int j, int lx, int ly) {
  const int s = support;
  const T* ai = alpha.data() + std::size_t(i) * s * s;
  const T* aj = alpha.data() + std::size_t(j) * s * s;
  double acc = 0.0;
  for (int y = std::max(0, -ly); y < std::min(s, s - ly); ++y) {
    for (int x = std::max(0, -lx); x < std::min(s, s - lx); ++x) {
      acc += double(ai[std::size_t(y + ly) * s + (x + lx)]) * double(aj[std::size_t(y) * s + x]);
    }
  }
  return acc;
}

template <class T>
void check_alpha(const std::vector<T>& alpha, int channels, int support) {
  if (support <= 0 || channels <= 0 || alpha.size() != std::size_t(channels) * support * support) {
    throw Error(ErrorKind::Usage, "texton coefficients do not match channels x support x support");
  }
}

template <class T>
double model_covariance_t(const std::vector<T>& alpha, int channels, int support, int order, int i, int j,
                          int dx, int dy) {
  check_alpha(alpha, channels, support);
  const int reach = bspline_reach(order);
  double acc = 0.0;
  for (int ky = -reach; ky <= reach; ++ky) {
    for (int kx = -reach; kx <= reach; ++kx) {
      // C_ij(tau) = sum_k b(k) R_ij(tau - k)
      acc += bspline_sample(order, kx, ky) * cross_correlation(alpha, support, i, j, dx - kx, dy - ky);
    }
  }
  return acc;
}

template <class T>
std::vector<double> model_colour_covariance_t(const std::vector<T>& alpha, int channels, int support,
                                              int order) {
  std::vector<double> m(std::size_t(channels) * channels);
  for (int i = 0; i < channels; ++i) {
    for (int j = i; j < channels; ++j) {
      double v = model_covariance_t(alpha, channels, support, order, i, j, 0, 0);
      m[std::size_t(i) * channels + j] = v;
      m[std::size_t(j) * channels + i] = v;
    }
  }
  return m;
}

}  // namespace

double model_covariance(const std::vector<double>& alpha, int channels, int support, int order, int i, int j,
                        int dx, int dy) {
  return model_covariance_t(alpha, channels, support, order, i, j, dx, dy);
}
double model_covariance(const std::vector<float>& alpha, int channels, int support, int order, int i, int j,
                        int dx, int dy) {
  return model_covariance_t(alpha, channels, support, order, i, j, dx, dy);
}
std::vector<double> model_colour_covariance(const std::vector<double>& alpha, int channels, int support,
                                            int order) {
  return model_colour_covariance_t(alpha, channels, support, order);
}
std::vector<double> model_colour_covariance(const std::vector<float>& alpha, int channels, int support,
                                            int order) {
  return model_colour_covariance_t(alpha, channels, support, order);
}

std::vector<double> exemplar_colour_covariance(const NormalisedKernel& tu) {
  const int ch = tu.channels;
  const std::size_t n = std::size_t(tu.width) * tu.height;
  std::vector<double> m(std::size_t(ch) * ch, 0.0);
  for (int i = 0; i < ch; ++i) {
    for (int j = i; j < ch; ++j) {
      const double* a = tu.t.data() + n * i;
      const double* b = tu.t.data() + n * j;
      double acc = 0.0;
      for (std::size_t k = 0; k < n; ++k) acc += a[k] * b[k];
      m[std::size_t(i) * ch + j] = acc;
      m[std::size_t(j) * ch + i] = acc;
    }
  }
  return m;
}

std::vector<Complex> kernel_spectrum(const NormalisedKernel& tu) {
  const std::size_t n = std::size_t(tu.width) * tu.height;
  std::vector<Complex> out(tu.t.begin(), tu.t.end());
  for (int c = 0; c < tu.channels; ++c) fft2d_forward(tu.width, tu.height, out.data() + n * c);
  return out;
}

double texton_rme(const NormalisedKernel& tu, const std::vector<Complex>& tu_hat,
                  const std::vector<double>& alpha, int support, int order) {
  check_alpha(alpha, tu.channels, support);
  const int w = tu.width, h = tu.height, ch = tu.channels, s = support;
  if (s > w || s > h) throw Error(ErrorKind::Usage, "texton_rme: support larger than the exemplar");
  const std::size_t n = std::size_t(w) * h;
  std::vector<Complex> a_hat(n * ch, Complex(0.0));
  for (int c = 0; c < ch; ++c) {
    for (int y = 0; y < s; ++y) {
      for (int x = 0; x < s; ++x)
        a_hat[n * c + std::size_t(y) * w + x] = alpha[(std::size_t(c) * s + y) * s + x];
    }
    fft2d_forward(w, h, a_hat.data() + n * c);
  }
  const std::vector<double> b_hat = bspline_hat(w, h, order);
  double num = 0.0, den = 0.0;
  for (std::size_t k = 1; k < n; ++k) {  // xi != 0
    double uu = 0.0, aa = 0.0;
    Complex ua = 0.0;
    for (int c = 0; c < ch; ++c) {
      const Complex u = tu_hat[n * c + k], a = a_hat[n * c + k];
      uu += std::norm(u);
      aa += std::norm(a);
      ua += std::conj(u) * a;
    }
    num += uu + aa * b_hat[k] - 2.0 * std::sqrt(b_hat[k]) * std::abs(ua);
    den += uu;
  }
  if (den <= 0.0) return 0.0;
  return std::sqrt(std::max(0.0, num) / den);
}

double texton_rme(const NormalisedKernel& tu, const std::vector<double>& alpha, int support, int order) {
  return texton_rme(tu, kernel_spectrum(tu), alpha, support, order);
}

}  // namespace stex
