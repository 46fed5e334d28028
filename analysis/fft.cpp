// Host 2-D FFT with FFTW (double): cached in-place plans, FFTW_UNALIGNED so that one plan serves any
// caller buffer through fftw_execute_dft (which is thread-safe, unlike the planner). See fft.h.
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
  std::map<std::tuple<int, int, int>, fftw_plan> plans;  // (width, height, sign) -> plan
  ~PlanCache() {
    for (auto& kv : plans) fftw_destroy_plan(kv.second);
  }
};

PlanCache& plan_cache() {
  static PlanCache cache;
  return cache;
}

fftw_plan get_plan(int width, int height, int sign) {
  if (width <= 0 || height <= 0) {
    throw Error(ErrorKind::Usage, "FFT of an empty array (" + std::to_string(width) + "x" +
                                      std::to_string(height) + ")");
  }
  PlanCache& cache = plan_cache();
  std::lock_guard<std::mutex> lock(cache.mutex);
  auto key = std::make_tuple(width, height, sign);
  auto it = cache.plans.find(key);
  if (it != cache.plans.end()) return it->second;
  // Plan on a scratch buffer (FFTW_ESTIMATE does not touch it, but it must exist); in place.
  auto* scratch = fftw_alloc_complex(std::size_t(width) * height);
  if (!scratch) throw Error(ErrorKind::Limit, "cannot allocate an FFT scratch buffer");
  fftw_plan plan = fftw_plan_dft_2d(height, width, scratch, scratch, sign, FFTW_ESTIMATE | FFTW_UNALIGNED);
  fftw_free(scratch);
  if (!plan) {
    throw Error(ErrorKind::Internal, "FFTW could not plan a " + std::to_string(width) + "x" +
                                         std::to_string(height) + " transform");
  }
  cache.plans.emplace(key, plan);
  return plan;
}

}  // namespace

void fft2d_forward(int width, int height, Complex* data) {
  fftw_plan plan = get_plan(width, height, FFTW_FORWARD);
  auto* p = reinterpret_cast<fftw_complex*>(data);
  fftw_execute_dft(plan, p, p);
}

void fft2d_inverse(int width, int height, Complex* data) {
  fftw_plan plan = get_plan(width, height, FFTW_BACKWARD);
  auto* p = reinterpret_cast<fftw_complex*>(data);
  fftw_execute_dft(plan, p, p);
  const double scale = 1.0 / (double(width) * double(height));
  const std::size_t n = std::size_t(width) * height;
  for (std::size_t i = 0; i < n; ++i) data[i] *= scale;
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
