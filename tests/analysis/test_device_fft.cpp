// Device FFT (analysis/device_fft.h) on the OpenCL device (PoCL CPU here): clFFT against FFTW, the FFTW
// fallback for a size clFFT cannot plan (97 is prime), round trips, and the reference-counted clFFT setup.
// Tolerance: single precision FFT error grows like eps_f * log2(N) (eps_f = 6e-8, log2(3072) ~ 12) in the
// relative L2 norm: ~1e-6; measured 2e-7 at 1024^2 on PoCL 3.1. Bound 1e-5 relative (10x margin).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "analysis/device_fft.h"
#include "analysis/fft.h"
#include "runtime/context.h"
#include "test_device.h"

namespace {

using stex::Complex;
using stex::ComplexF;

std::vector<ComplexF> signal(int w, int h) {
  std::vector<ComplexF> v(std::size_t(w) * h);
  for (std::size_t i = 0; i < v.size(); ++i)
    v[i] =
        ComplexF(float(std::sin(0.31 * double(i)) + 0.2 * double(i % 7)), float(std::cos(0.17 * double(i))));
  return v;
}

double relative_l2(const std::vector<ComplexF>& a, const std::vector<Complex>& ref) {
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    num += std::norm(Complex(a[i].real(), a[i].imag()) - ref[i]);
    den += std::norm(ref[i]);
  }
  return std::sqrt(num / den);
}

// One context for the test binary (device discovery and clFFT kernel compilation are slow).
stex::Context& ctx() {
  static std::unique_ptr<stex::Context> c = stex::Context::create(stex::test::test_device_spec());
  return *c;
}

void check_against_fftw(stex::DeviceFft& fft, int w, int h, stex::DeviceFft::Backend expected) {
  const auto x = signal(w, h);
  for (bool inverse : {false, true}) {
    std::vector<Complex> ref(x.begin(), x.end());
    if (inverse) {
      stex::fft2d_inverse(w, h, ref);
    } else {
      stex::fft2d_forward(w, h, ref);
    }
    auto y = x;
    EXPECT_EQ(fft.transform(w, h, y, inverse), expected) << w << "x" << h;
    EXPECT_LT(relative_l2(y, ref), 1e-5) << w << "x" << h << (inverse ? " inverse" : " forward");
  }
  // Round trip.
  auto y = x;
  fft.transform(w, h, y, false);
  fft.transform(w, h, y, true);
  std::vector<Complex> xd(x.begin(), x.end());
  EXPECT_LT(relative_l2(y, xd), 1e-5);
}

TEST(DeviceFft, RadixCheck) {
  EXPECT_TRUE(stex::DeviceFft::clfft_radices_only(64, 48));
  EXPECT_TRUE(stex::DeviceFft::clfft_radices_only(26, 22));  // 2*13, 2*11
  EXPECT_FALSE(stex::DeviceFft::clfft_radices_only(97, 97));
  EXPECT_FALSE(stex::DeviceFft::clfft_radices_only(64, 17));
}

TEST(DeviceFft, ClFftAgreesWithFftw) {
  stex::DeviceFft fft(ctx());
  check_against_fftw(fft, 64, 48, stex::DeviceFft::Backend::ClFft);
}

TEST(DeviceFft, PrimeSizeFallsBackToFftw) {
  stex::DeviceFft fft(ctx());
  check_against_fftw(fft, 97, 97, stex::DeviceFft::Backend::Fftw);
}

TEST(DeviceFft, SetupIsReferenceCounted) {
  const int before = stex::DeviceFft::live_count();
  auto a = std::make_unique<stex::DeviceFft>(ctx());
  {
    stex::DeviceFft b(ctx());
    EXPECT_EQ(stex::DeviceFft::live_count(), before + 2);
    // One size throughout: every new size compiles clFFT kernels (seconds on a cold PoCL cache).
    auto y = signal(64, 48);
    EXPECT_EQ(b.transform(64, 48, y, false), stex::DeviceFft::Backend::ClFft);
  }
  // b's teardown must not have torn clFFT down under a.
  EXPECT_EQ(stex::DeviceFft::live_count(), before + 1);
  check_against_fftw(*a, 64, 48, stex::DeviceFft::Backend::ClFft);
  a.reset();
  EXPECT_EQ(stex::DeviceFft::live_count(), before);
  // A fresh setup after a full teardown works.
  stex::DeviceFft c(ctx());
  check_against_fftw(c, 64, 48, stex::DeviceFft::Backend::ClFft);
}

}  // namespace
