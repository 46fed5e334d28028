// Gaussian model statistics: t_u, the sampled B-spline, texton noise covariance, RME (see gaussian_model.h;
// S1 §3.1, §4.1, §4.3; S2 eq. 1, eq. 3 and §3.2).
#include "analysis/gaussian_model.h"

#include <algorithm>
#include <cmath>

#include "analysis/periodic.h"
#include "runtime/error.h"

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

double bspline_sample(int order, int dx, int dy) {
  if (order == 0) return (dx == 0 && dy == 0) ? 1.0 : 0.0;
  auto one = [](int d) { return d == 0 ? 2.0 / 3.0 : (d == 1 || d == -1) ? 1.0 / 6.0 : 0.0; };
  return one(dx) * one(dy);
}

std::vector<double> bspline_hat(int width, int height, int order) {
  std::vector<double> out(std::size_t(width) * height, 1.0);
  if (order == 0) return out;
  std::vector<double> fx(width), fy(height);
  for (int q = 0; q < width; ++q) fx[q] = 2.0 / 3.0 + std::cos(2.0 * M_PI * q / width) / 3.0;
  for (int r = 0; r < height; ++r) fy[r] = 2.0 / 3.0 + std::cos(2.0 * M_PI * r / height) / 3.0;
  // Degenerate sizes (1 or 2 pixels): the DFT of b wrapped onto the grid (1/6 + 2/3 + 1/6 = 1 for size 1;
  // 2/3 +- 1/3 for size 2) equals the closed form above, so no special case is needed.
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
  const int reach = order == 0 ? 0 : 1;
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
