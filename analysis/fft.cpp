// Host 2-D FFT with FFTW (double): cached in-place plans, one plan per alignment class serves any
// caller buffer through the new-array execute functions (thread-safe, unlike the planner). See fft.h.
#include "analysis/fft.h"

#include <fftw3.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <tuple>

#include "runtime/error.h"

namespace stex {
namespace {

struct PlanCache {
  std::mutex mutex;
  std::map<std::tuple<int, int, int, bool>, fftw_plan> plans;  // (width, height, kind, aligned) -> plan
  ~PlanCache() {
    for (auto& kv : plans) fftw_destroy_plan(kv.second);
  }
};

PlanCache& plan_cache() {
  static PlanCache cache;
  return cache;
}

// Plan kinds besides FFTW_FORWARD / FFTW_BACKWARD (complex, in place).
constexpr int kR2c = 2, kC2r = 3;

// Plans for SIMD-aligned buffers (the common case: large std::vector allocations are 16-byte aligned) and
// FFTW_UNALIGNED fallbacks for anything else; FFTW requires the alignment of the planned arrays to match
// at execution (fftw_alignment_of).
fftw_plan get_plan(int width, int height, int sign, bool aligned) {
  if (width <= 0 || height <= 0) {
    throw Error(ErrorKind::Usage,
                "FFT of an empty array (" + std::to_string(width) + "x" + std::to_string(height) + ")");
  }
  PlanCache& cache = plan_cache();
  std::lock_guard<std::mutex> lock(cache.mutex);
  auto key = std::make_tuple(width, height, sign, aligned);
  auto it = cache.plans.find(key);
  if (it != cache.plans.end()) return it->second;
  // Plan on scratch buffers (FFTW_ESTIMATE does not touch them, but they must exist). Complex: in place;
  // r2c / c2r: out of place (the execute calls must match).
  const std::size_t n = std::size_t(width) * height;
  auto* scratch = fftw_alloc_complex(n);
  auto* scratch_real = fftw_alloc_real(n);
  if (!scratch || !scratch_real) {
    fftw_free(scratch);
    fftw_free(scratch_real);
    throw Error(ErrorKind::Limit, "cannot allocate an FFT scratch buffer");
  }
  const unsigned flags = aligned ? FFTW_ESTIMATE : (FFTW_ESTIMATE | FFTW_UNALIGNED);
  fftw_plan plan = sign == kR2c   ? fftw_plan_dft_r2c_2d(height, width, scratch_real, scratch, flags)
                   : sign == kC2r ? fftw_plan_dft_c2r_2d(height, width, scratch, scratch_real, flags)
                                  : fftw_plan_dft_2d(height, width, scratch, scratch, sign, flags);
  fftw_free(scratch);
  fftw_free(scratch_real);
  if (!plan) {
    throw Error(ErrorKind::Internal, "FFTW could not plan a " + std::to_string(width) + "x" +
                                         std::to_string(height) + " transform");
  }
  cache.plans.emplace(key, plan);
  return plan;
}

bool is_aligned(const void* a, const void* b) {
  return fftw_alignment_of(reinterpret_cast<double*>(const_cast<void*>(a))) == 0 &&
         fftw_alignment_of(reinterpret_cast<double*>(const_cast<void*>(b))) == 0;
}

}  // namespace

void fft2d_forward(int width, int height, Complex* data) {
  fftw_plan plan = get_plan(width, height, FFTW_FORWARD, is_aligned(data, data));
  auto* p = reinterpret_cast<fftw_complex*>(data);
  fftw_execute_dft(plan, p, p);
}

void fft2d_inverse(int width, int height, Complex* data) {
  fftw_plan plan = get_plan(width, height, FFTW_BACKWARD, is_aligned(data, data));
  auto* p = reinterpret_cast<fftw_complex*>(data);
  fftw_execute_dft(plan, p, p);
  const double scale = 1.0 / (double(width) * double(height));
  const std::size_t n = std::size_t(width) * height;
  for (std::size_t i = 0; i < n; ++i) data[i] *= scale;
}

void fft2d_r2c(int width, int height, const double* in, Complex* out) {
  fftw_plan plan = get_plan(width, height, kR2c, is_aligned(in, out));
  // FFTW's r2c does not modify its input when out of place; the const_cast only meets its C signature.
  fftw_execute_dft_r2c(plan, const_cast<double*>(in), reinterpret_cast<fftw_complex*>(out));
}

void fft2d_c2r(int width, int height, Complex* in, double* out) {
  fftw_plan plan = get_plan(width, height, kC2r, is_aligned(in, out));
  fftw_execute_dft_c2r(plan, reinterpret_cast<fftw_complex*>(in), out);
  const double scale = 1.0 / (double(width) * double(height));
  const std::size_t n = std::size_t(width) * height;
  for (std::size_t i = 0; i < n; ++i) out[i] *= scale;
}

std::vector<Complex> naive_dft2d(int width, int height, const std::vector<Complex>& data, bool inverse) {
  const double sign = inverse ? 1.0 : -1.0;
  const double two_pi = 2.0 * M_PI;
  std::vector<Complex> out(std::size_t(width) * height);
  for (int ky = 0; ky < height; ++ky) {
    for (int kx = 0; kx < width; ++kx) {
      Complex acc = 0.0;
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          // Reduce the phase index modulo the size first: exact integer arithmetic keeps the angle small.
          double phase = sign * two_pi *
                         (double((std::int64_t(kx) * x) % width) / width +
                          double((std::int64_t(ky) * y) % height) / height);
          acc += data[std::size_t(y) * width + x] * Complex(std::cos(phase), std::sin(phase));
        }
      }
      out[std::size_t(ky) * width + kx] = inverse ? acc / (double(width) * height) : acc;
    }
  }
  return out;
}

}  // namespace stex
