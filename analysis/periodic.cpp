// Periodic + smooth decomposition (Moisan 2011), see periodic.h. S1 §4.2 preprocess.
#include "analysis/periodic.h"

#include <cmath>

#include "analysis/fft.h"
#include "core/error.h"

namespace stex {

std::vector<double> periodic_boundary_image(int width, int height, const std::vector<double>& u) {
  const int w = width, h = height;
  std::vector<double> v(std::size_t(w) * h, 0.0);
  auto at = [&](int x, int y) { return u[std::size_t(y) * w + x]; };
  for (int y = 0; y < h; ++y) {
    double jump = at(w - 1, y) - at(0, y);
    v[std::size_t(y) * w + 0] += jump;
    v[std::size_t(y) * w + (w - 1)] -= jump;
  }
  for (int x = 0; x < w; ++x) {
    double jump = at(x, h - 1) - at(x, 0);
    v[x] += jump;
    v[std::size_t(h - 1) * w + x] -= jump;
  }
  return v;
}

std::vector<double> periodic_component(int width, int height, const std::vector<double>& u,
                                       std::vector<double>* smooth) {
  if (width <= 0 || height <= 0 || u.size() != std::size_t(width) * height) {
    throw Error(ErrorKind::Usage, "periodic_component: image size does not match its data");
  }
  std::vector<double> v = periodic_boundary_image(width, height, u);
  std::vector<Complex> s_hat(v.begin(), v.end());
  fft2d_forward(width, height, s_hat);
  const double two_pi = 2.0 * M_PI;
  std::vector<double> cx(width), cy(height);
  for (int q = 0; q < width; ++q) cx[q] = 2.0 * std::cos(two_pi * q / width);
  for (int r = 0; r < height; ++r) cy[r] = 2.0 * std::cos(two_pi * r / height);
  for (int r = 0; r < height; ++r) {
    for (int q = 0; q < width; ++q) {
      std::size_t i = std::size_t(r) * width + q;
      double denom = cx[q] + cy[r] - 4.0;  // eigenvalue of the periodic 5-point Laplacian; 0 only at (0,0)
      s_hat[i] = (q == 0 && r == 0) ? Complex(0.0) : s_hat[i] / denom;
    }
  }
  fft2d_inverse(width, height, s_hat);
  std::vector<double> p(u.size());
  if (smooth) smooth->resize(u.size());
  for (std::size_t i = 0; i < u.size(); ++i) {
    double s = s_hat[i].real();
    p[i] = u[i] - s;
    if (smooth) (*smooth)[i] = s;
  }
  return p;
}

std::vector<double> laplacian_periodic(int width, int height, const std::vector<double>& u) {
  std::vector<double> out(u.size());
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      double c = u[std::size_t(y) * width + x];
      double sum = u[std::size_t(y) * width + (x + 1) % width] +
                   u[std::size_t(y) * width + (x + width - 1) % width] +
                   u[std::size_t((y + 1) % height) * width + x] +
                   u[std::size_t((y + height - 1) % height) * width + x];
      out[std::size_t(y) * width + x] = sum - 4.0 * c;
    }
  }
  return out;
}

std::vector<double> laplacian_free(int width, int height, const std::vector<double>& u) {
  std::vector<double> out(u.size());
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      double c = u[std::size_t(y) * width + x];
      double acc = 0.0;
      if (x > 0) acc += u[std::size_t(y) * width + x - 1] - c;
      if (x + 1 < width) acc += u[std::size_t(y) * width + x + 1] - c;
      if (y > 0) acc += u[std::size_t(y - 1) * width + x] - c;
      if (y + 1 < height) acc += u[std::size_t(y + 1) * width + x] - c;
      out[std::size_t(y) * width + x] = acc;
    }
  }
  return out;
}

}  // namespace stex
