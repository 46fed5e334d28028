// FFTs behind one small interface: the host transform is FFTW in double for any
// size (the analysis path, S1 Algorithm 1 and the periodic component); the device transform is clFFT in
// float on a stex::Context (analysis/device_fft.h), falling back to FFTW for sizes clFFT cannot plan (prime
// factors other than 2, 3, 5, 7, 11, 13). Convention for both, on a width x height
// row-major array:
//   forward  X(kx, ky) = sum_{x,y} x(x, y) exp(-2 i pi (kx x / width + ky y / height))
//   inverse  x(x, y)   = 1/(width height) sum_{kx,ky} X(kx, ky) exp(+2 i pi (...))   (normalised)
#pragma once
#include <complex>
#include <cstddef>
#include <memory>
#include <vector>

namespace stex {

using Complex = std::complex<double>;
using ComplexF = std::complex<float>;

// 2-D complex FFT on the host (FFTW, double). Plans are created once per (size, direction) and cached for
// the life of the process; planning is serialised by a mutex (FFTW's planner is not thread-safe), execution
// is not (new-array execution on caller buffers is thread-safe in FFTW). In place.
void fft2d_forward(int width, int height, Complex* data);
void fft2d_inverse(int width, int height, Complex* data);
inline void fft2d_forward(int width, int height, std::vector<Complex>& data) {
  fft2d_forward(width, height, data.data());
}
inline void fft2d_inverse(int width, int height, std::vector<Complex>& data) {
  fft2d_inverse(width, height, data.data());
}

// Real-input 2-D transforms (FFTW r2c / c2r, double): the non-redundant half spectrum, (width/2 + 1) x height
// row-major, X(kx, ky) for kx in [0, width/2]. fft2d_c2r is normalised like fft2d_inverse and destroys its
// input (FFTW's c2r contract). Same caching and thread-safety as above.
inline int half_width(int width) { return width / 2 + 1; }
void fft2d_r2c(int width, int height, const double* in, Complex* out);
void fft2d_c2r(int width, int height, Complex* in, double* out);

// Real 2-D transforms of signals supported on the first `rows` rows of a width x height grid (S1 Algorithm
// 1's support projection): forward skips the zero rows (row r2c on `rows` rows, then every column); inverse
// computes only those rows (every column, then row c2r on `rows` rows). Same values as fft2d_r2c /
// fft2d_c2r restricted accordingly, for about half the work when rows << height. Owns `channels` pairs of
// FFTW-aligned buffers: real(c) is rows x width, spectrum(c) the half spectrum (half_width x height,
// row-major like fft2d_r2c). Plans are made at construction (under the planner mutex).
class SupportFft {
 public:
  SupportFft(int width, int height, int rows, int channels);
  ~SupportFft();
  SupportFft(const SupportFft&) = delete;
  SupportFft& operator=(const SupportFft&) = delete;
  double* real(int c) { return real_[c]; }
  Complex* spectrum(int c) { return spectrum_[c]; }
  void forward(int c);  // real(c) -> spectrum(c)
  void inverse(int c);  // spectrum(c) -> real(c), normalised; destroys spectrum(c)

 private:
  struct Plans;
  int width_, height_, rows_;
  std::vector<double*> real_;
  std::vector<Complex*> spectrum_;
  std::unique_ptr<Plans> plans_;
};

// Direct O(N^2) DFT with the same convention, for tests on small sizes.
std::vector<Complex> naive_dft2d(int width, int height, const std::vector<Complex>& data, bool inverse);

}  // namespace stex
