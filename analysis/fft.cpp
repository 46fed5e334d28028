// Host 2-D FFT with FFTW (double): cached in-place plans, one plan per alignment class serves any
// caller buffer through the new-array execute functions (thread-safe, unlike the planner). See fft.h.
#include "analysis/fft.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>

#include "core/error.h"

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

struct SupportFft::Plans {
  fftw_plan row_r2c = nullptr, col_forward = nullptr, col_inverse = nullptr, row_c2r = nullptr;
};

SupportFft::SupportFft(int width, int height, int rows, int channels)
    : width_(width), height_(height), rows_(rows), plans_(std::make_unique<Plans>()) {
  if (width <= 0 || height <= 0 || rows <= 0 || rows > height || channels <= 0) {
    throw Error(ErrorKind::Usage, "SupportFft: invalid sizes");
  }
  const int wh = half_width(width);
  for (int c = 0; c < channels; ++c) {
    real_.push_back(fftw_alloc_real(std::size_t(rows) * width));
    spectrum_.push_back(reinterpret_cast<Complex*>(fftw_alloc_complex(std::size_t(wh) * height)));
    if (!real_.back() || !spectrum_.back()) throw Error(ErrorKind::Limit, "cannot allocate FFT buffers");
  }
  auto* spec = reinterpret_cast<fftw_complex*>(spectrum_[0]);
  double* re = real_[0];
  const int n_row[1] = {width}, n_col[1] = {height};
  std::lock_guard<std::mutex> lock(plan_cache().mutex);
  // Rows: `rows` transforms of length width, contiguous, one row apart (real) / one half row apart.
  plans_->row_r2c =
      fftw_plan_many_dft_r2c(1, n_row, rows, re, nullptr, 1, width, spec, nullptr, 1, wh, FFTW_ESTIMATE);
  plans_->row_c2r =
      fftw_plan_many_dft_c2r(1, n_row, rows, spec, nullptr, 1, wh, re, nullptr, 1, width, FFTW_ESTIMATE);
  // Columns: wh transforms of length height, stride wh, adjacent; in place.
  plans_->col_forward = fftw_plan_many_dft(1, n_col, wh, spec, nullptr, wh, 1, spec, nullptr, wh, 1,
                                           FFTW_FORWARD, FFTW_ESTIMATE);
  plans_->col_inverse = fftw_plan_many_dft(1, n_col, wh, spec, nullptr, wh, 1, spec, nullptr, wh, 1,
                                           FFTW_BACKWARD, FFTW_ESTIMATE);
  if (!plans_->row_r2c || !plans_->row_c2r || !plans_->col_forward || !plans_->col_inverse) {
    throw Error(ErrorKind::Internal, "FFTW could not plan the support transforms");
  }
}

SupportFft::~SupportFft() {
  {
    std::lock_guard<std::mutex> lock(plan_cache().mutex);
    for (fftw_plan p : {plans_->row_r2c, plans_->row_c2r, plans_->col_forward, plans_->col_inverse}) {
      if (p) fftw_destroy_plan(p);
    }
  }
  for (double* p : real_) fftw_free(p);
  for (Complex* p : spectrum_) fftw_free(p);
}

void SupportFft::forward(int c) {
  const int wh = half_width(width_);
  auto* spec = reinterpret_cast<fftw_complex*>(spectrum_[c]);
  // Rows >= rows_ of the signal are zero, so are their row transforms.
  std::fill(spectrum_[c] + std::size_t(rows_) * wh, spectrum_[c] + std::size_t(height_) * wh, Complex(0.0));
  fftw_execute_dft_r2c(plans_->row_r2c, real_[c], spec);
  fftw_execute_dft(plans_->col_forward, spec, spec);
}

void SupportFft::inverse(int c) {
  auto* spec = reinterpret_cast<fftw_complex*>(spectrum_[c]);
  fftw_execute_dft(plans_->col_inverse, spec, spec);
  fftw_execute_dft_c2r(plans_->row_c2r, spec, real_[c]);
  const double scale = 1.0 / (double(width_) * double(height_));
  const std::size_t n = std::size_t(rows_) * width_;
  for (std::size_t i = 0; i < n; ++i) real_[c][i] *= scale;
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
