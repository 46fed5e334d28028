// Device FFT: clFFT (float) with an FFTW fallback, reference-counted clFFT setup (see device_fft.h).
#include "analysis/device_fft.h"

#include <clFFT.h>

#include <string>

#include "core/error.h"
#include "runtime/buffer.h"
#include "runtime/cl_error.h"
#include "runtime/context.h"

namespace stex {
namespace {

// Process-wide clFFT state: setup reference count, and a lock serialising every clFFT call (its plan
// repository is global).
std::mutex& clfft_mutex() {
  static std::mutex m;
  return m;
}
int g_clfft_refs = 0;

void clfft_check(clfftStatus status, const char* call) {
  if (status == CLFFT_SUCCESS) return;
  if (int(status) < 0) throw OpenCLError(call, cl_int(status));
  throw Error(ErrorKind::Device, std::string(call) + " failed: clFFT status " + std::to_string(int(status)));
}

bool radices_only(int n) {
  if (n <= 0) return false;
  for (int r : {2, 3, 5, 7, 11, 13}) {
    while (n % r == 0) n /= r;
  }
  return n == 1;
}

}  // namespace

struct DeviceFft::Plan {
  clfftPlanHandle handle = 0;
};

DeviceFft::DeviceFft(Context& ctx) : ctx_(ctx) {
  std::lock_guard<std::mutex> lock(clfft_mutex());
  if (g_clfft_refs == 0) {
    clfftSetupData setup;
    clfft_check(clfftInitSetupData(&setup), "clfftInitSetupData");
    clfft_check(clfftSetup(&setup), "clfftSetup");
  }
  ++g_clfft_refs;
}

DeviceFft::~DeviceFft() {
  std::lock_guard<std::mutex> lock(clfft_mutex());
  for (auto& kv : plans_) {
    if (kv.second) {
      clfftDestroyPlan(&kv.second->handle);
      delete kv.second;
    }
  }
  if (--g_clfft_refs == 0) clfftTeardown();
}

bool DeviceFft::clfft_radices_only(int width, int height) {
  return radices_only(width) && radices_only(height);
}

int DeviceFft::live_count() {
  std::lock_guard<std::mutex> lock(clfft_mutex());
  return g_clfft_refs;
}

DeviceFft::Plan* DeviceFft::plan_for(int width, int height) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto key = std::make_pair(width, height);
  auto it = plans_.find(key);
  if (it != plans_.end()) return it->second;
  Plan* plan = nullptr;
  if (clfft_radices_only(width, height)) {
    std::lock_guard<std::mutex> global(clfft_mutex());
    clfftPlanHandle h = 0;
    const size_t lengths[2] = {size_t(width), size_t(height)};  // lengths[0]: the contiguous dimension
    clfftStatus st = clfftCreateDefaultPlan(&h, ctx_.context(), CLFFT_2D, lengths);
    if (st == CLFFT_SUCCESS) {
      cl_command_queue q = ctx_.queue();
      // Defaults: forward scale 1, backward scale 1/N (the convention of fft.h).
      st = clfftSetPlanPrecision(h, CLFFT_SINGLE);
      if (st == CLFFT_SUCCESS) st = clfftSetLayout(h, CLFFT_COMPLEX_INTERLEAVED, CLFFT_COMPLEX_INTERLEAVED);
      if (st == CLFFT_SUCCESS) st = clfftSetResultLocation(h, CLFFT_INPLACE);
      if (st == CLFFT_SUCCESS) st = clfftBakePlan(h, 1, &q, nullptr, nullptr);
      if (st == CLFFT_SUCCESS) {
        plan = new Plan{h};
      } else {
        clfftDestroyPlan(&h);
      }
    }
    // A size clFFT rejects (CLFFT_NOTIMPLEMENTED and the like) falls back to FFTW; device failures while
    // baking surface at the first transform through the fallback's own OpenCL calls.
  }
  plans_[key] = plan;
  return plan;
}

DeviceFft::Backend DeviceFft::transform(int width, int height, cl_mem buffer, bool inverse) {
  if (width <= 0 || height <= 0) {
    throw Error(ErrorKind::Usage, "device FFT of an empty array (" + std::to_string(width) + "x" +
                                      std::to_string(height) + ")");
  }
  if (Plan* plan = plan_for(width, height)) {
    cl_command_queue q = ctx_.queue();
    {
      std::lock_guard<std::mutex> global(clfft_mutex());
      clfft_check(clfftEnqueueTransform(plan->handle, inverse ? CLFFT_BACKWARD : CLFFT_FORWARD, 1, &q, 0,
                                        nullptr, nullptr, &buffer, nullptr, nullptr),
                  "clfftEnqueueTransform");
    }
    cl_check(clFinish(q), "clFinish");
    return Backend::ClFft;
  }
  const std::size_t n = std::size_t(width) * height;
  std::vector<ComplexF> host(n);
  cl_check(clEnqueueReadBuffer(ctx_.queue(), buffer, CL_TRUE, 0, n * sizeof(ComplexF), host.data(), 0,
                               nullptr, nullptr),
           "clEnqueueReadBuffer");
  std::vector<Complex> d(host.begin(), host.end());
  if (inverse) {
    fft2d_inverse(width, height, d);
  } else {
    fft2d_forward(width, height, d);
  }
  for (std::size_t i = 0; i < n; ++i) host[i] = ComplexF(float(d[i].real()), float(d[i].imag()));
  cl_check(clEnqueueWriteBuffer(ctx_.queue(), buffer, CL_TRUE, 0, n * sizeof(ComplexF), host.data(), 0,
                                nullptr, nullptr),
           "clEnqueueWriteBuffer");
  return Backend::Fftw;
}

DeviceFft::Backend DeviceFft::transform(int width, int height, std::vector<ComplexF>& data, bool inverse) {
  if (data.size() != std::size_t(width) * height) {
    throw Error(ErrorKind::Usage, "device FFT: data size does not match " + std::to_string(width) + "x" +
                                      std::to_string(height));
  }
  static_assert(sizeof(ComplexF) == 2 * sizeof(float), "interleaved complex float");
  Buffer<ComplexF> buf(ctx_, data, CL_MEM_READ_WRITE, "FFT buffer");
  Backend b = transform(width, height, buf.get(), inverse);
  buf.read(data.data(), data.size());
  return b;
}

}  // namespace stex
